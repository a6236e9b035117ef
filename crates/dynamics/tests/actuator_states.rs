//! Actuators with states of their own (`Actuator::states`): the models carry them in the ODE
//! after the continuous law's states, and the wiring is checked against closed forms with a
//! first-order lag `F' = (F_c - F) / T` (an amplifier's bandwidth):
//!
//! * the layout: the state grows by one entry per slider after the PI law's three, started
//!   at the actuator's initial states, and the rates of the lag's states are `(F_c - F) / T`
//!   with the command the law computes there (so law and actuator states are not swapped);
//! * the limit: as `T -> 0` the run converges to the ideal force's at first order in `T`;
//! * the right-hand sides allocate nothing with such states (the lag, and a motor with its
//!   winding, current loop and compliant screw).

use std::sync::Arc;

use flexprr_control::{
    Actuator, ActuatorOutput, ActuatorSignal, Drive, IdealForce, MotorBallScrew, MotorRatings, Pid,
    Screw, Winding,
};
use flexprr_dynamics::{
    Actuation, CoupledOptions, CoupledSystem, ModalDamping, NonlinearOptions, NonlinearSystem,
    SceneModel, paper,
};
use flexprr_integrators::{Integrator, Options, Rk45};
use flexprr_kinematics::Trajectory;

#[global_allocator]
static GLOBAL: flexprr_testkit::CountingAllocator = flexprr_testkit::CountingAllocator;

const LAGGED: [ActuatorSignal; 1] = [ActuatorSignal {
    name: "lagged_force",
    header_unit: "N",
    symbol: "F",
    unit: "N",
}];

/// A force following its command with a first-order lag of time constant `T` (s).
#[derive(Debug)]
struct Lagged(f64);

impl Actuator for Lagged {
    fn apply(&self, command: f64, _velocity: f64) -> ActuatorOutput {
        ActuatorOutput {
            force: command,
            ..ActuatorOutput::default()
        }
    }
    fn name(&self) -> &'static str {
        "lagged"
    }
    fn states(&self) -> usize {
        1
    }
    fn state_names(&self) -> &'static [ActuatorSignal] {
        &LAGGED
    }
    /// Starts at a force no run reaches, so that the check below sees where it lands.
    fn initial_states(&self, velocity: f64, states: &mut [f64]) {
        states[0] = 7.0 + velocity;
    }
    fn apply_with_states(
        &self,
        command: f64,
        _velocity: f64,
        _friction_velocity: Option<f64>,
        states: &[f64],
        rates: &mut [f64],
    ) -> ActuatorOutput {
        rates[0] = (command - states[0]) / self.0;
        ActuatorOutput {
            force: states[0],
            ..ActuatorOutput::default()
        }
    }
}

fn actuation(lag: Option<f64>, ki: f64) -> Actuation {
    let actuator: Arc<dyn Actuator> = match lag {
        Some(t) => Arc::new(Lagged(t)),
        None => Arc::new(IdealForce),
    };
    Actuation {
        controller: Arc::new(Pid::new(2.0e5, 400.0, ki, true, 0.0).unwrap()),
        actuators: [actuator.clone(), actuator.clone(), actuator],
    }
}

fn trajectory() -> Arc<dyn Trajectory + Send + Sync> {
    Arc::new(paper::trajectory(20.0).unwrap())
}

fn coupled(actuation: Actuation) -> CoupledSystem {
    let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
    CoupledSystem::new(
        machine,
        trajectory(),
        ModalDamping::none(),
        CoupledOptions::full(),
    )
    .unwrap()
    .with_actuation(actuation, 0.0)
    .unwrap()
}

fn nonlinear(actuation: Actuation) -> NonlinearSystem {
    let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
    let options = NonlinearOptions {
        elements: 4,
        ..NonlinearOptions::paper(paper::YOUNGS_MODULUS)
    };
    NonlinearSystem::new(machine, trajectory(), options)
        .unwrap()
        .with_actuation(actuation, 0.0)
        .unwrap()
}

#[test]
fn the_actuators_states_follow_the_laws_in_the_state_with_their_own_rates() {
    let lag = 1e-3;
    let pairs: [(Box<dyn SceneModel>, Box<dyn SceneModel>); 2] = [
        (
            Box::new(coupled(actuation(None, 1.0e6))),
            Box::new(coupled(actuation(Some(lag), 1.0e6))),
        ),
        (
            Box::new(nonlinear(actuation(None, 1.0e6))),
            Box::new(nonlinear(actuation(Some(lag), 1.0e6))),
        ),
    ];
    for (mut ideal, mut lagged) in pairs {
        let (n, n_lagged) = (ideal.modes(), lagged.modes());
        assert_eq!(n, n_lagged);
        // Three law states (the PI's integrals), then one per actuator.
        assert_eq!(ideal.dim(), 2 * n + 3, "{}", ideal.kind());
        assert_eq!(lagged.dim(), 2 * n + 6, "{}", lagged.kind());
        let mut y = lagged.initial_state();
        let tail = 2 * n;
        assert_eq!(&y[tail..tail + 3], &[0.0; 3]);
        // Started at the actuator's initial states for the commanded slider velocities.
        let velocity: Vec<f64> = (0..3).map(|i| y[2 * n - 3 + i]).collect();
        for i in 0..3 {
            assert!((y[tail + 3 + i] - (7.0 + velocity[i])).abs() <= 1e-15);
        }
        // Away from the start: law states and forces of their own.
        for (k, v) in y[tail..].iter_mut().enumerate() {
            *v = 10.0 * k as f64 - 25.0;
        }
        let t = 0.013;
        let mut dy = vec![0.0; y.len()];
        lagged.rhs(t, &y, &mut dy);
        let snapshot = lagged.snapshot(t, &y).unwrap();
        let actuators = snapshot.actuators.unwrap();
        for i in 0..3 {
            let force = y[tail + 3 + i];
            assert!((actuators[i].output.force - force).abs() <= 1e-12);
            let expected = (actuators[i].command - force) / lag;
            assert!(
                (dy[tail + 3 + i] - expected).abs() <= 1e-9 * expected.abs(),
                "{}: {} vs {expected}",
                lagged.kind(),
                dy[tail + 3 + i]
            );
        }
        // The law's integral states see the same slider errors with or without the lag.
        let y_ideal = y[..tail + 3].to_vec();
        let mut dy_ideal = vec![0.0; y_ideal.len()];
        ideal.rhs(t, &y_ideal, &mut dy_ideal);
        for k in 0..3 {
            assert!(
                (dy[tail + k] - dy_ideal[tail + k]).abs()
                    <= 1e-12 * dy_ideal[tail + k].abs().max(1e-9)
            );
        }
    }
}

#[test]
fn a_vanishing_lag_converges_to_the_ideal_force_at_first_order() {
    let t: Vec<f64> = (0..=40).map(|k| 5e-4 * f64::from(k)).collect();
    let sliders = |lag: Option<f64>| -> Vec<f64> {
        let mut model = coupled(actuation(lag, 0.0));
        // The sliders are the last three coordinates (the trait's count, with them).
        let n = SceneModel::modes(&model);
        let y0 = SceneModel::initial_state(&model);
        let solution = Rk45::new(Options::default().rtol(1e-10).atol(1e-13))
            .solve(&mut model, 0.0, &y0, &t)
            .unwrap();
        (0..t.len())
            .flat_map(|k| (0..3).map(move |i| (k, n - 3 + i)))
            .map(|(k, j)| solution.y(k)[j])
            .collect()
    };
    let ideal = sliders(None);
    let difference = |lag: f64| {
        // The lag starts at 7 N + v (a start no ideal force has): set off by it.
        sliders(Some(lag))
            .iter()
            .zip(&ideal)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    };
    let (d1, d2, d3) = (difference(4e-5), difference(2e-5), difference(1e-5));
    println!("lagged minus ideal slider positions: {d1:.3e}, {d2:.3e}, {d3:.3e}");
    assert!(d2 < 0.6 * d1 && d3 < 0.6 * d2, "{d1} {d2} {d3}");
    assert!(d2 > 0.4 * d1 && d3 > 0.4 * d2, "{d1} {d2} {d3}");
}

/// A motor with its winding under a current loop and a compliant screw (four states).
fn drive_motor() -> Arc<dyn Actuator> {
    Arc::new(
        MotorBallScrew {
            viscous_friction: 1e-4,
            coulomb_friction: 0.02,
            drive: Some(Drive {
                torque_constant: 0.22,
                resistance: 1.6,
                bus_voltage: 320.0,
                current_limit: 16.0,
                winding: Some(Winding {
                    inductance: 2.8e-3,
                    current_bandwidth: Some(1000.0),
                }),
            }),
            friction_feedforward: false,
            lugre: None,
            screw: Some(Screw {
                stiffness: 1e8,
                damping: 300.0,
            }),
            ..*drive_motor_spec()
        }
        .validated()
        .unwrap(),
    )
}

#[test]
fn the_right_hand_sides_with_actuator_states_allocate_nothing() {
    let motor = drive_motor();
    assert_eq!(motor.states(), 4);
    let driven = || Actuation {
        controller: Arc::new(Pid::new(2.0e5, 400.0, 1.0e6, true, 0.0).unwrap()),
        actuators: [motor.clone(), motor.clone(), motor.clone()],
    };
    let mut models: Vec<Box<dyn SceneModel>> = vec![
        Box::new(coupled(actuation(Some(1e-3), 1.0e6))),
        Box::new(nonlinear(actuation(Some(1e-3), 1.0e6))),
        Box::new(coupled(driven())),
        Box::new(nonlinear(driven())),
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

/// A motor with friction (viscous and Coulomb) on a rigid screw, with or without the
/// friction in the feedforward.
fn rubbing_motor(viscous: f64, coulomb: f64, feedforward: bool) -> MotorBallScrew {
    MotorBallScrew {
        viscous_friction: viscous,
        coulomb_friction: coulomb,
        friction_feedforward: feedforward,
        drive: None,
        screw: None,
        ..*drive_motor_spec()
    }
    .validated()
    .unwrap()
}

/// The motor of [`drive_motor`] without friction, drive or screw, for struct updates.
fn drive_motor_spec() -> Box<MotorBallScrew> {
    Box::new(MotorBallScrew {
        rotor_inertia: 1.6e-5,
        lead: 0.01,
        efficiency: 0.9,
        ratings: MotorRatings {
            peak_torque: 3.5,
            continuous_torque: 1.2,
            max_speed: 100.0,
        },
        viscous_friction: 0.0,
        coulomb_friction: 0.0,
        coulomb_smoothing: 0.01,
        drive: None,
        friction_feedforward: false,
        lugre: None,
        screw: None,
    })
}

/// The friction in the feedforward: on a constant-velocity move a PD law carries the
/// motor's friction with the steady error `e = F_f / kp`, `F_f = g eta tau_f(g rho')` (its
/// closed form); with the friction in the feedforward the error shrinks to the law's own
/// (the same move without friction).
#[test]
fn the_friction_feedforward_leaves_the_laws_own_error() {
    use flexprr_kinematics::{Line, Pose};
    let (kp, kd) = (2.0e5, 2000.0);
    let line: Arc<dyn Trajectory + Send + Sync> = Arc::new(
        Line::new(
            Pose::new(-0.02, 0.0, 45f64.to_radians()),
            nalgebra::Vector3::new(0.1, 0.0, 0.0),
            0.0,
        )
        .unwrap(),
    );
    let run = |motor: MotorBallScrew| -> ([f64; 3], [f64; 3]) {
        let motor: Arc<dyn Actuator> = Arc::new(motor);
        let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
        let mut model = CoupledSystem::new(
            machine,
            line.clone(),
            ModalDamping::none(),
            CoupledOptions::full(),
        )
        .unwrap()
        .with_actuation(
            Actuation {
                controller: Arc::new(Pid::pd(kp, kd, true, 0.0).unwrap()),
                actuators: [motor.clone(), motor.clone(), motor],
            },
            0.0,
        )
        .unwrap();
        let end = 0.2;
        let y0 = SceneModel::initial_state(&model);
        let solution = Rk45::new(Options::default().rtol(1e-10).atol(1e-14))
            .solve(&mut model, 0.0, &y0, &[0.0, end])
            .unwrap();
        let snapshot = model.snapshot(end, solution.y(1)).unwrap();
        let rigid = line.motion(end);
        let commanded = paper::machine(3, paper::YOUNGS_MODULUS)
            .unwrap()
            .geometry
            .inverse_kinematics_unchecked(&rigid)
            .unwrap();
        let error = std::array::from_fn(|i| commanded.legs[i].rho - snapshot.sliders[i].position);
        let velocity = std::array::from_fn(|i| commanded.legs[i].rho_dot);
        (error, velocity)
    };
    let (viscous, coulomb) = (1e-4, 0.02);
    let (without, velocity) = run(rubbing_motor(viscous, coulomb, false));
    let (with, _) = run(rubbing_motor(viscous, coulomb, true));
    let (frictionless, _) = run(rubbing_motor(0.0, 0.0, false));
    let motor = rubbing_motor(viscous, coulomb, false);
    let g = motor.ratio();
    for i in 0..3 {
        let closed = g * motor.efficiency * motor.friction_torque(g * velocity[i]) / kp;
        println!(
            "slider {}: error {:.3} um (friction / kp = {:.3} um), with the friction fed forward {:.4} um, without friction {:.4} um",
            i + 1,
            1e6 * without[i],
            1e6 * (closed + frictionless[i]),
            1e6 * with[i],
            1e6 * frictionless[i]
        );
        assert!(
            (without[i] - frictionless[i] - closed).abs() <= 0.02 * closed.abs(),
            "{i}: {} vs {closed}",
            without[i] - frictionless[i]
        );
        assert!(
            (with[i] - frictionless[i]).abs() <= 1e-3 * closed.abs(),
            "{i}: {} vs {}",
            with[i],
            frictionless[i]
        );
    }
}
