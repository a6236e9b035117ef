//! Piezoelectric patches under strain-rate feedback (docs/piezo.md) against the closed form
//! of the added modal damping, `zeta_j = G k_a k_s d_j^2 / (2 m_j omega_j)` with
//! `d_j = psi_j'(x2) - psi_j'(x1)` (eq. P3), checked two ways:
//!
//! * the decay of a free vibration of the locked machine at rest (each link a pinned-pinned
//!   beam: the KED model with no axial load), link 1 started in its first mode;
//! * the eigenvalues of the linearised model (crates/linear);
//!
//! and the energy law: the work of the actuators equals the change of the links' energy.

use std::sync::Arc;

use flexprr_control::StrainRate;
use flexprr_dynamics::{
    Formulation, Machine, ModalDamping, ModalSystem, Patch, PatchControl, SceneModel, paper,
};
use flexprr_integrators::{Integrator, Options, Rk45};
use flexprr_kinematics::{Line, Pose, Trajectory};
use flexprr_linear::{linearize, modes};
use nalgebra::Vector3;

const K_A: f64 = 0.02; // N m / V
const K_S: f64 = 50.0; // V / rad
const GAIN: f64 = 2e-3; // s

fn machine() -> Arc<Machine> {
    Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap())
}

/// The locked machine at rest with one patch on link 1 from 0.4 to 0.6 under strain-rate
/// feedback of gain `gain`.
fn locked_with_patch(gain: f64, limit: f64) -> ModalSystem {
    let pose = Pose::new(-0.05, 0.02, 45f64.to_radians());
    let rest: Arc<dyn Trajectory + Send + Sync> =
        Arc::new(Line::new(pose, Vector3::zeros(), 0.0).unwrap());
    let control = PatchControl {
        patches: vec![Patch {
            link: 0,
            xi_start: 0.4,
            xi_end: 0.6,
            actuator_constant: K_A,
            sensor_constant: K_S,
            voltage_limit: limit,
        }],
        controller: Arc::new(StrainRate::new(gain, 0.0).unwrap()),
    };
    ModalSystem::new(
        machine(),
        rest,
        Formulation::consistent(),
        ModalDamping::none(),
    )
    .unwrap()
    .with_patch_control(control, 0.0)
    .unwrap()
}

/// The closed form of eq. P3 for mode `j` (0-based) of link 1.
fn closed_form(gain: f64, j: usize) -> (f64, f64) {
    let m = machine();
    let link = &m.links[0];
    let ints = &link.integrals;
    let l = link.length();
    let d = (link.basis.eval(j, 0.6)[1] - link.basis.eval(j, 0.4)[1]) / l;
    let (mass, stiffness) = (ints.mass[(j, j)], ints.stiffness[(j, j)]);
    let omega = (stiffness / mass).sqrt();
    (gain * K_A * K_S * d * d / (2.0 * mass * omega), omega)
}

#[test]
fn the_added_damping_of_the_linear_model_is_the_closed_form() {
    let mut model = locked_with_patch(GAIN, 1e9);
    let y0 = SceneModel::initial_state(&model);
    let lin = linearize(&mut model, 0.0, &y0, &[], &[]).unwrap();
    let found = modes(&lin).unwrap();
    for j in [0, 2] {
        let (zeta, omega) = closed_form(GAIN, j);
        // Link 1's mode j: of the three links' modes at this frequency (the other two are
        // undamped), the damped one.
        let f = omega / std::f64::consts::TAU;
        let mode = found
            .iter()
            .filter(|m| (m.frequency_hz / f - 1.0).abs() < 0.01)
            .max_by(|a, b| a.damping_ratio.total_cmp(&b.damping_ratio))
            .unwrap();
        println!(
            "mode {}: zeta {:.4e} (closed form {zeta:.4e}), {:.2} Hz",
            j + 1,
            mode.damping_ratio,
            mode.frequency_hz
        );
        // First order in the gain, and the other modes' coupling through the patch: 2 %.
        assert!(
            (mode.damping_ratio / zeta - 1.0).abs() < 0.02,
            "{} {zeta}",
            mode.damping_ratio
        );
    }
}

#[test]
fn a_free_vibration_decays_at_the_closed_form_rate() {
    let mut model = locked_with_patch(GAIN, 1e9);
    let mut y0 = SceneModel::initial_state(&model);
    let amplitude = 1e-4;
    y0[0] = amplitude; // link 1, mode 1
    let (zeta, omega) = closed_form(GAIN, 0);
    let period = std::f64::consts::TAU / omega;
    let cycles = 20.0;
    let t: Vec<f64> = (0..=4000)
        .map(|k| k as f64 * cycles * period / 4000.0)
        .collect();
    let solution = Rk45::new(Options::default().rtol(1e-10).atol(1e-16))
        .solve(&mut model, 0.0, &y0, &t)
        .unwrap();
    // Envelope of the first mode: the largest |eta_1| over the first and the last cycle.
    let peak = |from: f64, to: f64| {
        (0..t.len())
            .filter(|&k| t[k] >= from && t[k] <= to)
            .map(|k| solution.y(k)[0].abs())
            .fold(0.0, f64::max)
    };
    let (first, last) = (
        peak(0.0, period),
        peak((cycles - 1.0) * period, cycles * period),
    );
    let measured = (first / last).ln() / ((cycles - 1.0) * std::f64::consts::TAU);
    println!("free decay: zeta {measured:.4e} (closed form {zeta:.4e})");
    assert!((measured / zeta - 1.0).abs() < 0.03, "{measured} {zeta}");
}

#[test]
fn the_actuator_work_is_the_energy_removed_from_the_links() {
    let mut model = locked_with_patch(GAIN, 1e9);
    let mut y0 = SceneModel::initial_state(&model);
    y0[0] = 1e-4;
    y0[1] = -3e-5;
    let t: Vec<f64> = (0..=20000).map(|k| k as f64 * 1e-6).collect();
    let solution = Rk45::new(Options::default().rtol(1e-11).atol(1e-17))
        .solve(&mut model, 0.0, &y0, &t)
        .unwrap();
    let (mut power, mut energy) = (Vec::new(), Vec::new());
    for (k, &tk) in t.iter().enumerate() {
        let y = solution.y(k);
        power.push(
            model
                .patch_states(tk, y)
                .iter()
                .map(|p| p.power)
                .sum::<f64>(),
        );
        let e = SceneModel::energies(&mut model, tk, y).unwrap();
        energy.push(e.strain.iter().sum::<f64>() + e.elastic_kinetic.unwrap().iter().sum::<f64>());
    }
    let h = t[1] - t[0];
    let mut work = 0.0;
    let mut worst = 0.0_f64;
    for k in (2..t.len()).step_by(2) {
        work += h / 3.0 * (power[k - 2] + 4.0 * power[k - 1] + power[k]);
        worst = worst.max((work - (energy[k] - energy[0])).abs());
    }
    let removed = energy[0] - energy[t.len() - 1];
    println!(
        "energy removed {removed:.3e} J, balance {:.2e} of it",
        worst / removed
    );
    assert!(removed > 0.0);
    assert!(worst < 1e-6 * energy[0], "{worst}");
}

#[test]
fn zero_gain_is_the_uncontrolled_link_and_the_limit_clips() {
    let mut controlled = locked_with_patch(0.0, 1e9);
    let mut plain = ModalSystem::new(
        machine(),
        Arc::new(
            Line::new(
                Pose::new(-0.05, 0.02, 45f64.to_radians()),
                Vector3::zeros(),
                0.0,
            )
            .unwrap(),
        ),
        Formulation::consistent(),
        ModalDamping::none(),
    )
    .unwrap();
    let mut y0 = SceneModel::initial_state(&plain);
    y0[0] = 1e-4;
    let t = [0.0, 0.01];
    let rk = Rk45::new(Options::default().rtol(1e-10).atol(1e-16));
    let (a, b) = (
        rk.solve(&mut controlled, 0.0, &y0, &t).unwrap(),
        rk.solve(&mut plain, 0.0, &y0, &t).unwrap(),
    );
    for (x, y) in a.y(1).iter().zip(b.y(1)) {
        assert!((x - y).abs() <= 1e-12 * 1e-4, "{x} {y}");
    }
    // A tight limit: the command is clipped and said so.
    let mut clipped = locked_with_patch(GAIN, 1.0);
    let mut y = y0.clone();
    let n = y.len() / 2;
    y[n] = 10.0; // a fast first mode: a large sensor rate
    let states = clipped.patch_states(0.0, &y);
    assert!(states[0].saturated && (states[0].voltage.abs() - 1.0).abs() < 1e-12);
}

/// The same patch on the coupled and the nonlinear (32 elements) models at rest: their
/// linear models' added damping of link 1's first mode against the closed form (the
/// nonlinear links' first mode is the sine to the mesh's accuracy).
#[test]
fn the_coupled_and_nonlinear_patches_add_the_closed_form_damping() {
    use flexprr_dynamics::{CoupledOptions, CoupledSystem, NonlinearOptions, NonlinearSystem};
    let pose = Pose::new(-0.05, 0.02, 45f64.to_radians());
    let rest: Arc<dyn Trajectory + Send + Sync> =
        Arc::new(Line::new(pose, Vector3::zeros(), 0.0).unwrap());
    let control = || PatchControl {
        patches: vec![Patch {
            link: 0,
            xi_start: 0.4,
            xi_end: 0.6,
            actuator_constant: K_A,
            sensor_constant: K_S,
            voltage_limit: 1e9,
        }],
        controller: Arc::new(StrainRate::new(GAIN, 0.0).unwrap()),
    };
    let coupled = CoupledSystem::new(
        machine(),
        rest.clone(),
        ModalDamping::none(),
        CoupledOptions::full(),
    )
    .unwrap()
    .with_patch_control(control(), 0.0)
    .unwrap();
    let options = NonlinearOptions {
        elements: 32,
        ..NonlinearOptions::paper(paper::YOUNGS_MODULUS)
    };
    let mut nonlinear = NonlinearSystem::new(machine(), rest, options).unwrap();
    nonlinear.start_at(0.0).unwrap();
    let nonlinear = nonlinear.with_patch_control(control(), 0.0).unwrap();
    let (zeta, omega) = closed_form(GAIN, 0);
    let f = omega / std::f64::consts::TAU;
    let models: Vec<(Box<dyn SceneModel>, f64)> =
        vec![(Box::new(coupled), 0.02), (Box::new(nonlinear), 0.03)];
    for (mut model, tolerance) in models {
        let y0 = model.initial_state();
        let lin = linearize(model.as_mut(), 0.0, &y0, &[], &[]).unwrap();
        let mode = modes(&lin)
            .unwrap()
            .into_iter()
            .filter(|m| (m.frequency_hz / f - 1.0).abs() < 0.01)
            .max_by(|a, b| a.damping_ratio.total_cmp(&b.damping_ratio))
            .unwrap();
        println!(
            "{}: zeta {:.4e} (closed form {zeta:.4e})",
            model.kind(),
            mode.damping_ratio
        );
        assert!(
            (mode.damping_ratio / zeta - 1.0).abs() < tolerance,
            "{}: {} {zeta}",
            model.kind(),
            mode.damping_ratio
        );
    }
}

/// The nonlinear model's patch: the actuator's work equals the change of the whole
/// machine's energy (its lumped masses make the balance exact).
#[test]
fn the_nonlinear_patch_work_is_the_energy_change() {
    use flexprr_dynamics::{NonlinearOptions, NonlinearSystem};
    let rest: Arc<dyn Trajectory + Send + Sync> = Arc::new(
        Line::new(
            Pose::new(-0.05, 0.02, 45f64.to_radians()),
            Vector3::zeros(),
            0.0,
        )
        .unwrap(),
    );
    let options = NonlinearOptions {
        elements: 8,
        ..NonlinearOptions::paper(paper::YOUNGS_MODULUS)
    };
    let mut model = NonlinearSystem::new(machine(), rest, options).unwrap();
    model.start_at(0.0).unwrap();
    let mut model = model
        .with_patch_control(
            PatchControl {
                patches: vec![Patch {
                    link: 0,
                    xi_start: 0.3,
                    xi_end: 0.6,
                    actuator_constant: K_A,
                    sensor_constant: K_S,
                    voltage_limit: 1e9,
                }],
                controller: Arc::new(StrainRate::new(GAIN, 0.0).unwrap()),
            },
            0.0,
        )
        .unwrap();
    let mut y0 = SceneModel::initial_state(&model);
    // Bend link 1 by a transverse velocity of its middle nodes.
    let n = y0.len() / 2;
    let range = SceneModel::link_range(&model, 0);
    for j in range.clone().skip(1).step_by(3).take(7) {
        y0[n + j] = 0.05;
    }
    let t: Vec<f64> = (0..=10000).map(|k| k as f64 * 1e-6).collect();
    let solution = Rk45::new(Options::default().rtol(1e-11).atol(1e-15))
        .solve(&mut model, 0.0, &y0, &t)
        .unwrap();
    let (mut power, mut energy) = (Vec::new(), Vec::new());
    for (k, &tk) in t.iter().enumerate() {
        let y = solution.y(k);
        power.push(
            model
                .patch_states(tk, y)
                .unwrap()
                .iter()
                .map(|p| p.power)
                .sum::<f64>(),
        );
        let e = SceneModel::energies(&mut model, tk, y).unwrap();
        energy.push(e.kinetic.unwrap() + e.strain.iter().sum::<f64>());
    }
    let h = t[1] - t[0];
    let (mut work, mut worst) = (0.0, 0.0_f64);
    for k in (2..t.len()).step_by(2) {
        work += h / 3.0 * (power[k - 2] + 4.0 * power[k - 1] + power[k]);
        worst = worst.max((work - (energy[k] - energy[0])).abs());
    }
    let removed = energy[0] - energy[t.len() - 1];
    println!(
        "nonlinear: energy removed {removed:.3e} J, balance {:.2e} of it",
        worst / removed
    );
    assert!(removed > 0.0);
    assert!(worst < 1e-4 * removed, "{worst} of {removed}");
}

/// Modal velocity feedback with one patch per link, targeting the first mode at a damping
/// ratio of 0.02: the linear model's first modes of all three links get 0.02 (the patches
/// also damp the third modes they see, by spillover, not targeted).
#[test]
fn modal_velocity_control_gives_the_targeted_damping_ratio() {
    let pose = Pose::new(-0.05, 0.02, 45f64.to_radians());
    let rest: Arc<dyn Trajectory + Send + Sync> =
        Arc::new(Line::new(pose, Vector3::zeros(), 0.0).unwrap());
    let patches: Vec<Patch> = (0..3)
        .map(|link| Patch {
            link,
            xi_start: 0.4,
            xi_end: 0.6,
            actuator_constant: K_A,
            sensor_constant: K_S,
            voltage_limit: 1e9,
        })
        .collect();
    let law =
        flexprr_dynamics::modal_velocity_law(&machine(), &patches, &[0], &[0.02], 0.0).unwrap();
    let mut model = ModalSystem::new(
        machine(),
        rest,
        Formulation::consistent(),
        ModalDamping::none(),
    )
    .unwrap()
    .with_patch_control(
        PatchControl {
            patches,
            controller: Arc::new(law),
        },
        0.0,
    )
    .unwrap();
    let y0 = SceneModel::initial_state(&model);
    let lin = linearize(&mut model, 0.0, &y0, &[], &[]).unwrap();
    let found = modes(&lin).unwrap();
    let first: Vec<f64> = found
        .iter()
        .filter(|m| m.frequency_hz < 200.0)
        .map(|m| m.damping_ratio)
        .collect();
    println!("first modes' damping ratios: {first:?}");
    assert_eq!(first.len(), 3);
    // The third mode's coupling through the patch (spillover) moves it by a per cent.
    assert!(
        first.iter().all(|z| (z / 0.02 - 1.0).abs() < 0.02),
        "{first:?}"
    );
}
