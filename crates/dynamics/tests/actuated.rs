//! The machine under control (docs/control.md): the coupled and nonlinear models with the
//! sliders as degrees of freedom, checked against independent references:
//!
//! * **energy**: the actuators' work equals the change of kinetic and strain energy (exactly
//!   for the nonlinear model's lumped masses; to the coupled model's own order, which leaves
//!   out terms of relative size `delta / l`);
//! * **closed-loop poles**: with stiff links, a slider offset at rest decays as the linear
//!   system `M_rho e'' + kd e' + kp e = 0`, `M_rho` the rigid machine's mass matrix in slider
//!   coordinates built from the rigid inverse dynamics (a separate code, model.md section 4);
//! * **rigid limit**: with the rigid feedforward, the tracking error vanishes as the links
//!   stiffen (the feedforward is exact for rigid links);
//! * **stiff servo**: a very stiff PD makes the actuated model the prescribed one;
//! * **sampled control**: the zero-order hold converges to the continuous law as the period
//!   shrinks, at first order;
//! * the right-hand sides allocate nothing.

use std::sync::Arc;

use flexprr_control::{Actuator, IdealForce, Pid};
use flexprr_dynamics::{
    Actuation, CoupledOptions, CoupledSystem, Machine, ModalDamping, NonlinearOptions,
    NonlinearSystem, SceneModel, inverse_dynamics, paper,
};
use flexprr_integrators::{Integrator, OdeSystem, Options, Rk45, Solution};
use flexprr_kinematics::{Line, PlatformMotion, Pose, Trajectory};
use nalgebra::{Matrix3, Vector3};

#[global_allocator]
static GLOBAL: flexprr_testkit::CountingAllocator = flexprr_testkit::CountingAllocator;

fn machine(youngs_modulus: f64) -> Arc<Machine> {
    Arc::new(paper::machine(3, youngs_modulus).unwrap())
}

fn actuation(kp: f64, kd: f64, ki: f64, period: f64) -> Actuation {
    let force: Arc<dyn Actuator> = Arc::new(IdealForce);
    Actuation {
        controller: Arc::new(Pid::new(kp, kd, ki, true, period).unwrap()),
        actuators: [force.clone(), force.clone(), force],
    }
}

fn coupled(
    machine: Arc<Machine>,
    trajectory: Arc<dyn Trajectory + Send + Sync>,
    actuation: Actuation,
) -> CoupledSystem {
    CoupledSystem::new(
        machine,
        trajectory,
        ModalDamping::none(),
        CoupledOptions::full(),
    )
    .unwrap()
    .with_actuation(actuation, 0.0)
    .unwrap()
}

fn nonlinear(
    machine: Arc<Machine>,
    trajectory: Arc<dyn Trajectory + Send + Sync>,
    actuation: Actuation,
    elements: usize,
) -> NonlinearSystem {
    let options = NonlinearOptions {
        elements,
        ..NonlinearOptions::paper(paper::YOUNGS_MODULUS)
    };
    NonlinearSystem::new(machine, trajectory, options)
        .unwrap()
        .with_actuation(actuation, 0.0)
        .unwrap()
}

fn solve(model: &mut dyn SceneModel, t: &[f64], rtol: f64) -> Solution {
    let y0 = model.initial_state();
    Rk45::new(Options::default().rtol(rtol).atol(1e-3 * rtol))
        .solve(model, 0.0, &y0, t)
        .expect("integrates")
}

fn times(end: f64, step: f64) -> Vec<f64> {
    let n = (end / step).round() as usize;
    (0..=n).map(|k| k as f64 * step).collect()
}

/// The work of the actuators `int sum_i F_i rho_i' dt` (Simpson's rule) against the change
/// of the total energy, relative to the largest work or energy change along the run.
fn energy_balance(model: &mut dyn SceneModel, t: &[f64], solution: &Solution) -> f64 {
    let (mut power, mut energy) = (Vec::new(), Vec::new());
    for (k, &tk) in t.iter().enumerate() {
        let y = solution.y(k);
        let snapshot = model.snapshot(tk, y).expect("snapshot");
        let actuators = snapshot.actuators.expect("actuated");
        power.push(
            (0..3)
                .map(|i| actuators[i].output.force * snapshot.sliders[i].velocity)
                .sum::<f64>(),
        );
        let e = model.energies(tk, y).expect("energies");
        energy.push(e.kinetic.expect("kinetic energy") + e.strain.iter().sum::<f64>());
    }
    let h = t[1] - t[0];
    let (mut work, mut worst, mut scale) = (0.0, 0.0_f64, 0.0_f64);
    for k in (2..t.len()).step_by(2) {
        work += h / 3.0 * (power[k - 2] + 4.0 * power[k - 1] + power[k]);
        let change = energy[k] - energy[0];
        worst = worst.max((work - change).abs());
        scale = scale.max(work.abs()).max(change.abs());
    }
    worst / scale
}

#[test]
fn the_actuators_work_is_the_energy_of_the_nonlinear_machine() {
    let trajectory: Arc<dyn Trajectory + Send + Sync> = Arc::new(paper::trajectory(20.0).unwrap());
    let mut model = nonlinear(
        machine(paper::YOUNGS_MODULUS),
        trajectory,
        actuation(2.0e5, 400.0, 0.0, 0.0),
        8,
    );
    let t = times(0.02, 2.0e-6);
    let solution = solve(&mut model, &t, 1e-10);
    let error = energy_balance(&mut model, &t, &solution);
    println!("nonlinear: energy balance {error:.2e}");
    assert!(error < 1e-6, "{error}");
}

#[test]
fn the_actuators_work_is_the_energy_of_the_coupled_machine_to_its_order() {
    let trajectory: Arc<dyn Trajectory + Send + Sync> = Arc::new(paper::trajectory(20.0).unwrap());
    let mut model = coupled(
        machine(paper::YOUNGS_MODULUS),
        trajectory,
        actuation(2.0e5, 400.0, 0.0, 0.0),
    );
    let t = times(0.05, 1.0e-5);
    let solution = solve(&mut model, &t, 1e-10);
    let error = energy_balance(&mut model, &t, &solution);
    println!("coupled: energy balance {error:.2e}");
    // The coupled model leaves out terms of relative size delta / l (about 5e-4 at 20 Hz,
    // docs/coupled.md): its energy closes to that order, not to the tolerance.
    assert!(error < 2e-3, "{error}");
}

/// The rigid machine's mass matrix in slider coordinates at `pose` at rest, from the rigid
/// inverse dynamics: the driving forces `F = M_rho rho''` of three platform accelerations.
fn slider_mass_matrix(machine: &Machine, pose: Pose) -> Matrix3<f64> {
    let (mut forces, mut accelerations) = (Matrix3::zeros(), Matrix3::zeros());
    for k in 0..3 {
        let mut acceleration = Vector3::zeros();
        acceleration[k] = 1.0;
        let motion = PlatformMotion {
            pose,
            velocity: Vector3::zeros(),
            acceleration,
        };
        let state = machine
            .geometry
            .inverse_kinematics_unchecked(&motion)
            .unwrap();
        let reactions = inverse_dynamics(machine, &state, None, 0.0).unwrap();
        forces.set_column(k, &Vector3::from(reactions.driving_force));
        accelerations.set_column(
            k,
            &Vector3::from(std::array::from_fn::<f64, 3, _>(|i| state.legs[i].rho_ddot)),
        );
    }
    forces * accelerations.try_inverse().unwrap()
}

/// The linear closed loop `M e'' + kd e' + kp e = 0` from `e(0) = e0`, `e'(0) = 0`,
/// integrated at a tight tolerance.
fn linear_closed_loop(mass: Matrix3<f64>, kp: f64, kd: f64, e0: [f64; 3], t: &[f64]) -> Solution {
    struct Loop {
        inverse: Matrix3<f64>,
        kp: f64,
        kd: f64,
    }
    impl OdeSystem for Loop {
        fn dim(&self) -> usize {
            6
        }
        fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
            let e = Vector3::new(y[0], y[1], y[2]);
            let v = Vector3::new(y[3], y[4], y[5]);
            let a = -(self.inverse * (self.kp * e + self.kd * v));
            dy[..3].copy_from_slice(&y[3..]);
            dy[3..].copy_from_slice(a.as_slice());
        }
    }
    let mut system = Loop {
        inverse: mass.try_inverse().unwrap(),
        kp,
        kd,
    };
    let y0 = [e0[0], e0[1], e0[2], 0.0, 0.0, 0.0];
    Rk45::new(Options::default().rtol(1e-12).atol(1e-18))
        .solve(&mut system, 0.0, &y0, t)
        .unwrap()
}

#[test]
fn a_slider_offset_decays_with_the_closed_loop_poles_of_the_rigid_machine() {
    let pose = Pose::new(-0.05, 0.02, 45f64.to_radians());
    let stiff = machine(1.0e4 * paper::YOUNGS_MODULUS);
    let trajectory: Arc<dyn Trajectory + Send + Sync> =
        Arc::new(Line::new(pose, Vector3::zeros(), 0.0).unwrap());
    let (kp, kd) = (2.0e5, 400.0);
    let mut model = coupled(stiff.clone(), trajectory, actuation(kp, kd, 0.0, 0.0));
    let e0 = [1.0e-5, -5.0e-6, 2.0e-6];
    let mut y0 = SceneModel::initial_state(&model);
    let n = CoupledSystem::modes(&model);
    for i in 0..3 {
        y0[n + i] -= e0[i]; // e = rho_ref - rho
    }
    let t = times(0.05, 1.0e-4);
    let solution = Rk45::new(Options::default().rtol(1e-10).atol(1e-14))
        .solve(&mut model, 0.0, &y0, &t)
        .unwrap();
    let mass = slider_mass_matrix(&stiff, pose);
    assert!(
        (mass - mass.transpose()).norm() <= 1e-12 * mass.norm(),
        "the rigid mass matrix is symmetric: {mass}"
    );
    let linear = linear_closed_loop(mass, kp, kd, e0, &t);
    let rigid = stiff
        .geometry
        .inverse_kinematics_unchecked(&PlatformMotion::at_rest(pose))
        .unwrap();
    let scale = e0.iter().fold(0.0_f64, |m, e| m.max(e.abs()));
    let mut worst = 0.0_f64;
    for k in 0..t.len() {
        for i in 0..3 {
            let e = rigid.legs[i].rho - solution.y(k)[n + i];
            worst = worst.max((e - linear.y(k)[i]).abs());
        }
    }
    // The poles: the slowest decay rate of the linear loop, and the error has decayed by it.
    let a = {
        let inverse = mass.try_inverse().unwrap();
        let mut a = faer::Mat::<f64>::zeros(6, 6);
        for i in 0..3 {
            a[(i, 3 + i)] = 1.0;
            for j in 0..3 {
                a[(3 + i, j)] = -kp * inverse[(i, j)];
                a[(3 + i, 3 + j)] = -kd * inverse[(i, j)];
            }
        }
        a
    };
    let poles = a.eigenvalues().unwrap();
    let slowest = poles.iter().map(|p| -p.re).fold(f64::INFINITY, f64::min);
    println!(
        "closed loop: worst difference {:.2e} of {scale:.1e} m; poles {poles:?}; slowest decay {slowest:.1} 1/s",
        worst
    );
    assert!(slowest > 0.0);
    assert!(worst <= 2e-3 * scale, "{worst}");
}

/// Largest slider error `|rho_ref - rho|` over a run of `model` at `t`.
fn peak_tracking_error(model: &mut dyn SceneModel, t: &[f64]) -> f64 {
    let solution = solve(model, t, 1e-9);
    let mut peak = 0.0_f64;
    for (k, &tk) in t.iter().enumerate() {
        let snapshot = model.snapshot(tk, solution.y(k)).unwrap();
        let rigid = model
            .machine()
            .geometry
            .inverse_kinematics_unchecked(&snapshot.nominal)
            .unwrap();
        for i in 0..3 {
            peak = peak.max((rigid.legs[i].rho - snapshot.sliders[i].position).abs());
        }
    }
    peak
}

#[test]
fn with_the_rigid_feedforward_the_tracking_error_vanishes_as_the_links_stiffen() {
    let t = times(0.05, 1e-4);
    let errors: Vec<f64> = [1.0, 10.0, 100.0]
        .iter()
        .map(|scale| {
            let trajectory: Arc<dyn Trajectory + Send + Sync> =
                Arc::new(paper::trajectory(20.0).unwrap());
            let mut model = coupled(
                machine(scale * paper::YOUNGS_MODULUS),
                trajectory,
                actuation(2.0e5, 400.0, 0.0, 0.0),
            );
            peak_tracking_error(&mut model, &t)
        })
        .collect();
    println!("peak slider errors at E x 1, 10, 100: {errors:?}");
    // The links' elastic reactions scale as 1 / EI: the error drops at least 5x a decade.
    assert!(
        errors[1] < errors[0] / 5.0 && errors[2] < errors[1] / 5.0,
        "{errors:?}"
    );
}

#[test]
fn a_very_stiff_servo_is_the_prescribed_coupled_model() {
    let trajectory: Arc<dyn Trajectory + Send + Sync> = Arc::new(paper::trajectory(20.0).unwrap());
    let t = times(0.05, 2.5e-4);
    let mut stiff = coupled(
        machine(paper::YOUNGS_MODULUS),
        trajectory.clone(),
        actuation(1.0e9, 1.0e5, 0.0, 0.0),
    );
    let mut prescribed = CoupledSystem::new(
        machine(paper::YOUNGS_MODULUS),
        trajectory,
        ModalDamping::none(),
        CoupledOptions::full(),
    )
    .unwrap();
    let (a, b) = (
        solve(&mut stiff, &t, 1e-9),
        solve(&mut prescribed, &t, 1e-9),
    );
    let (mut num, mut den) = (0.0, 0.0);
    for (k, &tk) in t.iter().enumerate() {
        for i in 0..3 {
            let wa = stiff.deflection(tk, i, 0.5, a.y(k)).unwrap();
            let wb = SceneModel::deflection(&prescribed, tk, i, 0.5, b.y(k)).unwrap();
            num += (wa - wb) * (wa - wb);
            den += wb * wb;
        }
    }
    let error = (num / den).sqrt();
    println!(
        "stiff servo against prescribed sliders: {:.3} %",
        100.0 * error
    );
    assert!(error < 2e-3, "{error}");
}

#[test]
fn the_zero_order_hold_converges_to_the_continuous_law_at_first_order() {
    let t = times(0.02, 1e-4);
    let deflections = |period: f64| -> Vec<f64> {
        let trajectory: Arc<dyn Trajectory + Send + Sync> =
            Arc::new(paper::trajectory(20.0).unwrap());
        let mut model = coupled(
            machine(paper::YOUNGS_MODULUS),
            trajectory,
            actuation(2.0e5, 400.0, 0.0, period),
        );
        // The sample times come from the model as the run goes (`OdeSystem::next_stop`).
        let y0 = SceneModel::initial_state(&model);
        let solution = Rk45::new(Options::default().rtol(1e-9).atol(1e-12))
            .solve_observed(&mut model, 0.0, &y0, &t, &[], &mut ())
            .unwrap();
        (0..t.len())
            .flat_map(|k| {
                let y = solution.y(k).to_vec();
                let n = CoupledSystem::modes(&model);
                (0..3).map(move |i| y[n + i])
            })
            .collect()
    };
    let continuous = deflections(0.0);
    let difference = |period: f64| {
        let sampled = deflections(period);
        sampled
            .iter()
            .zip(&continuous)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    };
    let (d1, d2, d3) = (difference(4e-4), difference(2e-4), difference(1e-4));
    println!("sampled minus continuous slider positions: {d1:.2e}, {d2:.2e}, {d3:.2e}");
    // First order in the period: halving it about halves the difference.
    assert!(d2 < 0.7 * d1 && d3 < 0.7 * d2, "{d1} {d2} {d3}");
    assert!(d2 > 0.3 * d1 && d3 > 0.3 * d2, "{d1} {d2} {d3}");
}

#[test]
fn the_actuated_right_hand_sides_allocate_nothing() {
    let trajectory: Arc<dyn Trajectory + Send + Sync> = Arc::new(paper::trajectory(20.0).unwrap());
    let mut models: Vec<Box<dyn SceneModel>> = vec![
        Box::new(coupled(
            machine(paper::YOUNGS_MODULUS),
            trajectory.clone(),
            actuation(2.0e5, 400.0, 1.0e6, 0.0),
        )),
        Box::new(nonlinear(
            machine(paper::YOUNGS_MODULUS),
            trajectory,
            actuation(2.0e5, 400.0, 1.0e6, 0.0),
            8,
        )),
    ];
    for model in &mut models {
        let y = model.initial_state();
        let mut dy = vec![0.0; y.len()];
        model.rhs(0.01, &y, &mut dy);
        let ((), allocations) = flexprr_testkit::count_allocations(|| {
            for k in 0..100 {
                model.rhs(0.01 + 1e-4 * f64::from(k), &y, &mut dy);
            }
        });
        assert_eq!(allocations, 0, "{}", model.kind());
        assert!(dy.iter().all(|v| v.is_finite()), "{}", model.kind());
    }
}
