//! The channels of a linear model (docs/linear.md, "Channels") against the laws and closed
//! forms that define them, on the coupled machine at rest:
//!
//! * under a PD law `F = kp (r - rho) + kd (r' - rho')` (feedforward off): the setpoint
//!   `reference:I` passes to `slider_command:I` with gain `kp`, `reference_rate:I` with
//!   `kd`; `slider_error:I` is `r - rho`; the command is `-kp rho - kd rho'` in the state;
//!   at zero frequency slider `i` follows its setpoint (gain 1) and yields `1 / kp` to its
//!   own force;
//! * the velocities are the rates of the positions: `C_velocity = C_position A` (a
//!   position output has no feedthrough and `C B = 0`);
//! * a motor on a ball screw: `motor_torque:I = slider_command:I / (g eta)` below its peak;
//! * a piezoelectric patch: its sensor reads `k_s sum_j d_j eta_j` (eq. P2 of docs/piezo.md,
//!   `d_j = psi_j'(x2) - psi_j'(x1)`), and a voltage on its actuator deflects the locked
//!   link statically by `sum_j psi_j(xi) k_a d_j V / K_jj` (the modal static solution; the
//!   patch's moments leave the joint reactions alone);
//! * every channel's identifier is one python-control and MATLAB accept.

use std::f64::consts::PI;
use std::sync::Arc;

use flexprr_control::{Actuator, IdealForce, MotorBallScrew, MotorRatings, Pid, StrainRate};
use flexprr_dynamics::{
    Actuation, CoupledOptions, CoupledSystem, Machine, ModalDamping, Patch, PatchControl,
    SceneModel, paper,
};
use flexprr_kinematics::{Line, Pose, Trajectory};
use flexprr_linear::{Axis, Input, Linearization, Output, linearize};
use nalgebra::{DMatrix, Vector3};

fn rest(at: Pose) -> Arc<dyn Trajectory + Send + Sync> {
    Arc::new(Line::new(at, Vector3::zeros(), 0.0).unwrap())
}

fn machine() -> Arc<Machine> {
    Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap())
}

fn at() -> Pose {
    Pose::new(-0.05, 0.02, 40f64.to_radians())
}

fn servo(actuators: [Arc<dyn Actuator>; 3], kp: f64, kd: f64) -> Box<dyn SceneModel> {
    let actuation = Actuation {
        controller: Arc::new(Pid::pd(kp, kd, false, 0.0).unwrap()),
        actuators,
    };
    Box::new(
        CoupledSystem::new(
            machine(),
            rest(at()),
            ModalDamping::none(),
            CoupledOptions::full(),
        )
        .unwrap()
        .with_actuation(actuation, 0.0)
        .unwrap(),
    )
}

fn dense(m: &faer::Mat<f64>) -> DMatrix<f64> {
    DMatrix::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)])
}

/// `-C A^-1 B + D`, the static gain.
fn static_gain(lin: &Linearization) -> DMatrix<f64> {
    let (a, b, c, d) = (dense(&lin.a), dense(&lin.b), dense(&lin.c), dense(&lin.d));
    -(&c * a.lu().solve(&b).unwrap()) + d
}

/// The largest entry's size of a row, for relative comparisons.
fn scale(row: &[f64]) -> f64 {
    row.iter().fold(0.0f64, |m, v| m.max(v.abs()))
}

#[test]
fn the_slider_loop_channels_follow_the_pd_law() {
    let (kp, kd) = (2.0e5, 400.0);
    let force: Arc<dyn Actuator> = Arc::new(IdealForce);
    let mut model = servo([force.clone(), force.clone(), force], kp, kd);
    let y0 = model.initial_state();
    let inputs = [
        Input::SliderForce(0),
        Input::Reference(0),
        Input::ReferenceRate(0),
    ];
    let outputs = [
        Output::SliderPosition(0),
        Output::SliderVelocity(0),
        Output::SliderError(0),
        Output::SliderErrorRate(0),
        Output::SliderCommand(0),
        Output::Platform(Axis::X),
        Output::PlatformVelocity(Axis::X),
        Output::Platform(Axis::Phi),
        Output::PlatformVelocity(Axis::Phi),
    ];
    let lin = linearize(model.as_mut(), 0.0, &y0, &inputs, &outputs).unwrap();
    assert!(!lin.is_discrete());
    let (a, c, d) = (dense(&lin.a), dense(&lin.c), dense(&lin.d));
    // Feedthrough: the law's command sees the setpoint and its rate; the errors are the
    // setpoint less the slider.
    let expect_d = [(4, 1, kp), (4, 2, kd), (2, 1, 1.0), (3, 2, 1.0)];
    for (o, i, want) in expect_d {
        assert!(
            (d[(o, i)] - want).abs() < 1e-6 * want,
            "D[{o},{i}] = {}",
            d[(o, i)]
        );
    }
    for o in [0, 1, 5, 6, 7, 8] {
        for i in 0..3 {
            assert!(
                d[(o, i)].abs() < 1e-9,
                "no feedthrough to {}: {}",
                outputs[o],
                d[(o, i)]
            );
        }
    }
    // The state rows: error = -rho, error rate = -rho', command = -kp rho - kd rho'.
    let n = a.nrows();
    let row = |o: usize| (0..n).map(|j| c[(o, j)]).collect::<Vec<_>>();
    let (rho, rate) = (row(0), row(1));
    let mut worst = 0.0f64;
    for j in 0..n {
        worst = worst.max((c[(2, j)] + rho[j]).abs() / scale(&rho));
        worst = worst.max((c[(3, j)] + rate[j]).abs() / scale(&rate));
        let law = -kp * rho[j] - kd * rate[j];
        worst = worst.max((c[(4, j)] - law).abs() / (kp * scale(&rho)));
    }
    // The velocities are the positions' rates.
    for (position, velocity) in [(0, 1), (5, 6), (7, 8)] {
        let p = DMatrix::from_fn(1, n, |_, j| c[(position, j)]);
        let derivative = &p * &a;
        let v = row(velocity);
        for j in 0..n {
            worst = worst.max((derivative[(0, j)] - v[j]).abs() / scale(&v));
        }
    }
    println!("largest relative difference of the channel rows from the law: {worst:.2e}");
    assert!(worst < 1e-7, "{worst}");
    // Static: slider 1 follows its setpoint and yields 1/kp to its own force.
    let g = static_gain(&lin);
    assert!((g[(0, 0)] - 1.0 / kp).abs() < 1e-8 / kp, "{}", g[(0, 0)]);
    assert!((g[(0, 1)] - 1.0).abs() < 1e-8, "{}", g[(0, 1)]);
    assert!((g[(2, 0)] + 1.0 / kp).abs() < 1e-8 / kp, "{}", g[(2, 0)]);
    assert!(g[(2, 1)].abs() < 1e-8, "{}", g[(2, 1)]);
}

#[test]
fn the_motor_torque_is_the_command_through_the_screw() {
    let motor = MotorBallScrew {
        rotor_inertia: 1.6e-5,
        lead: 0.01,
        efficiency: 0.9,
        ratings: MotorRatings {
            peak_torque: 3.5,
            continuous_torque: 1.2,
            max_speed: 100.0,
        },
        viscous_friction: 1e-4,
        coulomb_friction: 0.02,
        coulomb_smoothing: 0.01,
        drive: None,
        friction_feedforward: false,
        screw: None,
        lugre: None,
    }
    .validated()
    .unwrap();
    let g = 2.0 * PI / motor.lead;
    let motor: Arc<dyn Actuator> = Arc::new(motor);
    let mut model = servo([motor.clone(), motor.clone(), motor], 2e5, 2000.0);
    let y0 = model.initial_state();
    let outputs = [
        Output::SliderCommand(1),
        Output::MotorTorque(1),
        Output::SliderPosition(1),
    ];
    let lin = linearize(model.as_mut(), 0.0, &y0, &[Input::Reference(1)], &outputs).unwrap();
    assert!(
        lin.notes
            .iter()
            .any(|n| n.contains("Coulomb friction left out")),
        "{:?}",
        lin.notes
    );
    let (c, d) = (dense(&lin.c), dense(&lin.d));
    let command = (0..c.ncols()).map(|j| c[(0, j)]).collect::<Vec<_>>();
    for j in 0..c.ncols() {
        assert!((c[(1, j)] - c[(0, j)] / (g * 0.9)).abs() <= 1e-9 * scale(&command) / g);
    }
    assert!(
        (d[(1, 0)] - 2e5 / (g * 0.9)).abs() < 1e-6 * 2e5 / g,
        "{}",
        d[(1, 0)]
    );
    // An ideal force has no motor: the output is refused by name.
    let force: Arc<dyn Actuator> = Arc::new(IdealForce);
    let mut ideal = servo([force.clone(), force.clone(), force], 2e5, 400.0);
    let y0 = ideal.initial_state();
    let e = linearize(ideal.as_mut(), 0.0, &y0, &[], &[Output::MotorTorque(0)]).unwrap_err();
    assert!(e.to_string().starts_with("motor_torque:1:"), "{e}");
}

#[test]
fn a_patch_senses_its_slope_difference_and_bends_its_link() {
    let (k_a, k_s) = (3.7e-4, 8.0e3);
    let patch = Patch {
        link: 0,
        xi_start: 0.4,
        xi_end: 0.6,
        actuator_constant: k_a,
        sensor_constant: k_s,
        voltage_limit: 200.0,
    };
    let control = PatchControl {
        patches: vec![patch],
        controller: Arc::new(StrainRate::new(0.0, 0.0).unwrap()),
    };
    let m = machine();
    let mut model: Box<dyn SceneModel> = Box::new(
        CoupledSystem::new(
            m.clone(),
            rest(at()),
            ModalDamping::none(),
            CoupledOptions::full(),
        )
        .unwrap()
        .with_patch_control(control, 0.0)
        .unwrap(),
    );
    let y0 = model.initial_state();
    let outputs = [
        Output::PatchSensor(0),
        Output::Deflection { link: 0, xi: 0.5 },
    ];
    let lin = linearize(
        model.as_mut(),
        0.0,
        &y0,
        &[Input::PatchVoltage(0)],
        &outputs,
    )
    .unwrap();
    let link = &m.links[0];
    let l = link.length();
    let r = link.modes();
    let d: Vec<f64> = (0..r)
        .map(|j| (link.basis.eval(j, 0.6)[1] - link.basis.eval(j, 0.4)[1]) / l)
        .collect();
    // The sensor row: k_s d_j on link 1's modal coordinates, nothing else.
    let c = dense(&lin.c);
    for j in 0..c.ncols() {
        let want = if j < r { k_s * d[j] } else { 0.0 };
        assert!(
            (c[(0, j)] - want).abs() < 1e-7 * k_s * scale(&d),
            "C[0,{j}] = {}",
            c[(0, j)]
        );
    }
    // The static response to a volt: eta = K^-1 k_a d (K diagonal for the sine modes).
    let g = static_gain(&lin);
    let stiffness = &link.integrals.stiffness;
    let eta: Vec<f64> = (0..r).map(|j| k_a * d[j] / stiffness[(j, j)]).collect();
    let sensor: f64 = (0..r).map(|j| k_s * d[j] * eta[j]).sum();
    let mid: f64 = (0..r).map(|j| link.basis.eval(j, 0.5)[0] * eta[j]).sum();
    println!(
        "per volt: sensor {:.6e} V (closed form {sensor:.6e}), mid-span {:.6e} m ({mid:.6e})",
        g[(0, 0)],
        g[(1, 0)]
    );
    assert!((g[(0, 0)] - sensor).abs() < 1e-8 * sensor.abs());
    assert!((g[(1, 0)] - mid).abs() < 1e-8 * mid.abs());
    // A patch the scene does not have is refused by name.
    let e = linearize(model.as_mut(), 0.0, &y0, &[Input::PatchVoltage(1)], &[]).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("patch_voltage:2: the scene has 1 patch"),
        "{e}"
    );
}

#[test]
fn every_name_is_a_signal_name() {
    let names = [
        "slider_force:1",
        "point_force:2@0.125",
        "reference:3",
        "reference_rate:1",
        "patch_voltage:2",
        "actuator_command:1",
    ]
    .iter()
    .map(|s| s.parse::<Input>().unwrap().signal_name())
    .chain(
        [
            "slider:1",
            "slider_velocity:2",
            "slider_error:3",
            "slider_error_rate:1",
            "motor_torque:2",
            "slider_command:3",
            "platform:phi",
            "platform_velocity:y",
            "deflection:1@0.5",
            "slope:2@1",
            "acceleration:3@0.75",
            "patch_sensor:4",
        ]
        .iter()
        .map(|s| s.parse::<Output>().unwrap().signal_name()),
    )
    .collect::<Vec<_>>();
    for name in &names {
        assert!(
            name.starts_with(|c: char| c.is_ascii_alphabetic())
                && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
                && !name.contains("__")
                && !name.ends_with('_'),
            "{name}"
        );
    }
    let mut unique = names.clone();
    unique.sort();
    unique.dedup();
    assert_eq!(unique.len(), names.len());
}

/// The loop broken at slider 1's actuator (`actuator_command:1` in, `slider_command:1` out)
/// and closed again by `u = y` has the closed loop's poles: continuous and sampled PID.
#[test]
fn a_loop_broken_at_its_actuator_closes_back_to_the_machine() {
    use faer::linalg::solvers::Eigen;
    for period in [0.0, 5e-4] {
        let force: Arc<dyn Actuator> = Arc::new(IdealForce);
        let actuation = Actuation {
            controller: Arc::new(Pid::new(2e5, 400.0, 4e6, true, period).unwrap()),
            actuators: [force.clone(), force.clone(), force],
        };
        let mut model: Box<dyn SceneModel> = Box::new(
            CoupledSystem::new(
                machine(),
                rest(at()),
                ModalDamping::none(),
                CoupledOptions::full(),
            )
            .unwrap()
            .with_actuation(actuation, 0.0)
            .unwrap(),
        );
        let y0 = model.initial_state();
        let closed = linearize(model.as_mut(), 0.0, &y0, &[], &[]).unwrap();
        let open = linearize(
            model.as_mut(),
            0.0,
            &y0,
            &[Input::ActuatorCommand(0)],
            &[Output::SliderCommand(0)],
        )
        .unwrap();
        assert_eq!(open.dt.to_bits(), period.to_bits());
        let (a, b, c, d) = (
            dense(&open.a),
            dense(&open.b),
            dense(&open.c),
            dense(&open.d),
        );
        let again = &a + &b * (&c / (1.0 - d[(0, 0)]));
        let eigen = |m: &DMatrix<f64>| {
            let f = faer::Mat::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)]);
            let e = Eigen::new_from_real(f.as_ref()).unwrap();
            let mut v: Vec<(f64, f64)> =
                (0..m.nrows()).map(|k| (e.S()[k].re, e.S()[k].im)).collect();
            v.sort_by(|p, q| p.0.total_cmp(&q.0).then(p.1.total_cmp(&q.1)));
            v
        };
        let (want, got) = (eigen(&dense(&closed.a)), eigen(&again));
        assert_eq!(want.len(), got.len());
        let size = want.iter().fold(0.0f64, |m, p| m.max(p.0.hypot(p.1)));
        let worst = want
            .iter()
            .map(|w| {
                got.iter()
                    .map(|g| (w.0 - g.0).hypot(w.1 - g.1))
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0f64, f64::max);
        println!(
            "period {period}: poles of the loop closed again within {:.1e} of {size:.1e}",
            worst
        );
        assert!(worst < 1e-7 * size, "{worst}");
    }
}
