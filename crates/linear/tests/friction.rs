//! LuGre friction in the linear models (docs/control.md, "Friction with a stuck phase"). At
//! rest and unloaded (`z = 0`) the bristles are a presliding spring: `z' = omega` and the
//! friction torque is `sigma0 z + (sigma1 + sigma2) omega`, so each slider sees a spring
//! `g^2 eta sigma0` and a damper `g^2 eta (sigma1 + sigma2)` on its travel since rest. The
//! linear model of the machine under PD (`kp`, `kd`) with LuGre motors therefore has the
//! modes of the same machine under PD with `kp + g^2 eta sigma0` and `kd + g^2 eta sigma1`
//! on motors with the viscous friction alone (a second model built without any friction
//! state), and each bristle's row of `A` is `z' = g rho'`.

use std::sync::Arc;

use flexprr_control::{Actuator, LuGre, MotorBallScrew, MotorRatings, Pid};
use flexprr_dynamics::{Actuation, CoupledOptions, CoupledSystem, ModalDamping, paper};
use flexprr_kinematics::{Line, Pose, Trajectory};
use flexprr_linear::{Output, linearize, modes};
use nalgebra::Vector3;

const STIFFNESS: f64 = 30.0;
const DAMPING: f64 = 0.01;
const ROTOR: f64 = 1.6e-5;

fn motor(lugre: bool) -> MotorBallScrew {
    MotorBallScrew {
        rotor_inertia: ROTOR,
        lead: 0.01,
        efficiency: 0.9,
        ratings: MotorRatings {
            peak_torque: 3.5,
            continuous_torque: 1.2,
            max_speed: 100.0,
        },
        viscous_friction: 1e-4,
        coulomb_friction: if lugre { 0.02 } else { 0.0 },
        coulomb_smoothing: 0.01,
        drive: None,
        screw: None,
        friction_feedforward: false,
        lugre: lugre.then_some(LuGre {
            static_friction: 0.03,
            stribeck_speed: 0.05,
            bristle_stiffness: STIFFNESS,
            bristle_damping: DAMPING,
        }),
    }
    .validated()
    .unwrap()
}

fn at_rest(actuator: MotorBallScrew, kp: f64, kd: f64) -> CoupledSystem {
    let actuator: Arc<dyn Actuator> = Arc::new(actuator);
    let actuation = Actuation {
        controller: Arc::new(Pid::pd(kp, kd, true, 0.0).unwrap()),
        actuators: [actuator.clone(), actuator.clone(), actuator],
    };
    let rest: Arc<dyn Trajectory + Send + Sync> = Arc::new(
        Line::new(
            Pose::new(-0.05, 0.0, 45f64.to_radians()),
            Vector3::zeros(),
            0.0,
        )
        .unwrap(),
    );
    let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
    CoupledSystem::new(machine, rest, ModalDamping::none(), CoupledOptions::full())
        .unwrap()
        .with_actuation(actuation, 0.0)
        .unwrap()
}

#[test]
fn stuck_the_bristles_are_a_presliding_spring_in_the_linear_model() {
    let (kp, kd) = (2.0e5, 2000.0);
    let m = motor(true);
    let (g, eta) = (m.ratio(), m.efficiency);
    let mut lugre = at_rest(m, kp, kd);
    let y0 = lugre.initial_state();
    let lin = linearize(&mut lugre, 0.0, &y0, &[], &[Output::SliderPosition(0)]).unwrap();
    // The bristles' rows: z' = g rho', nothing else.
    let index = |signal: &str| {
        lin.states
            .iter()
            .position(|s| s.signal == signal)
            .unwrap_or_else(|| panic!("no state {signal}"))
    };
    for i in 1..=3 {
        let row = index(&format!("bristle_deflection_{i}"));
        let rate = index(&format!("rho_{i}_rate"));
        for col in 0..lin.a.ncols() {
            let want = if col == rate { g } else { 0.0 };
            let got = lin.a[(row, col)];
            assert!(
                (got - want).abs() <= 1e-6 * g,
                "A[z_{i}, {col}] = {got}, want {want}"
            );
        }
    }
    // The same machine with the presliding spring and damper in the PD gains.
    let spring = g * g * eta * STIFFNESS;
    let mut equivalent = at_rest(motor(false), kp + spring, kd + g * g * eta * DAMPING);
    let y0 = equivalent.initial_state();
    let reference =
        linearize(&mut equivalent, 0.0, &y0, &[], &[Output::SliderPosition(0)]).unwrap();
    let (with, without) = (modes(&lin).unwrap(), modes(&reference).unwrap());
    let largest = without
        .iter()
        .map(|m| m.eigenvalue.re.hypot(m.eigenvalue.im))
        .fold(0.0, f64::max);
    for mode in &without {
        let nearest = with
            .iter()
            .map(|w| {
                (w.eigenvalue.re - mode.eigenvalue.re).hypot(w.eigenvalue.im - mode.eigenvalue.im)
            })
            .fold(f64::INFINITY, f64::min);
        assert!(
            nearest <= 1e-6 * largest,
            "mode at {} Hz (damping {}): nearest LuGre eigenvalue {nearest} away",
            mode.frequency_hz,
            mode.damping_ratio
        );
    }
    // The presliding modes: each slider with its rotor on the bristle spring, near
    // sqrt(g^2 eta sigma0 / (m_s + J g^2)) (the links add their share of mass; the rotor
    // alone would ring at sqrt(eta sigma0 / J)).
    let slider = paper::machine(3, paper::YOUNGS_MODULUS)
        .unwrap()
        .slider_mass[0];
    let predicted = (spring / (slider + ROTOR * g * g)).sqrt() / std::f64::consts::TAU;
    let rotor = (eta * STIFFNESS / ROTOR).sqrt() / std::f64::consts::TAU;
    let nearest = with
        .iter()
        .map(|m| m.frequency_hz)
        .min_by(|a, b| (a - predicted).abs().total_cmp(&(b - predicted).abs()))
        .unwrap();
    println!(
        "presliding spring {spring:.4e} N/m at the slider; nearest mode {nearest:.2} Hz, slider and rotor on it {predicted:.2} Hz, the rotor alone {rotor:.2} Hz"
    );
    assert!(
        (nearest / predicted - 1.0).abs() < 0.01,
        "{nearest} vs {predicted}"
    );
}

#[test]
fn sliding_the_bristles_add_a_fast_pole_and_the_stribeck_slope() {
    // Sliders at about the Stribeck speed (0.05 rev/s = 0.5 mm/s on a 10 mm lead), where
    // the curve's slope is steepest.
    let m = motor(true);
    let lugre = m.lugre.unwrap();
    let g = m.ratio();
    let actuator: Arc<dyn Actuator> = Arc::new(m);
    let actuation = Actuation {
        controller: Arc::new(Pid::pd(2.0e5, 2000.0, true, 0.0).unwrap()),
        actuators: [actuator.clone(), actuator.clone(), actuator],
    };
    let line: Arc<dyn Trajectory + Send + Sync> = Arc::new(
        Line::new(
            Pose::new(-0.05, 0.0, 45f64.to_radians()),
            Vector3::new(6e-4, 3e-4, 0.0),
            0.0,
        )
        .unwrap(),
    );
    let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
    let rigid = machine
        .geometry
        .inverse_kinematics(&line.motion(0.0))
        .unwrap();
    let mut model = CoupledSystem::new(machine, line, ModalDamping::none(), CoupledOptions::full())
        .unwrap()
        .with_actuation(actuation, 0.0)
        .unwrap();
    let y0 = model.initial_state();
    let lin = linearize(&mut model, 0.0, &y0, &[], &[Output::SliderPosition(0)]).unwrap();
    let index = |signal: &str| {
        lin.states
            .iter()
            .position(|s| s.signal == signal)
            .unwrap_or_else(|| panic!("no state {signal}"))
    };
    let ws = lugre.stribeck_rate();
    for i in 1..=3 {
        let omega = g * rigid.legs[i - 1].rho_dot;
        let curve = lugre.stribeck(0.02, omega);
        let slope = -(0.03 - 0.02) * 2.0 * omega / (ws * ws) * (-(omega / ws).powi(2)).exp();
        let (row, rate) = (
            index(&format!("bristle_deflection_{i}")),
            index(&format!("rho_{i}_rate")),
        );
        // z' = omega - sigma0 |omega| z / g(omega) about z = sign(omega) g / sigma0:
        // d z'/d z = -sigma0 |omega| / g, d z'/d rho' = g omega g'(omega) / g(omega).
        let pole = -STIFFNESS * omega.abs() / curve;
        let coupling = g * omega * slope / curve;
        println!(
            "slider {i}: {:.3} rev/s, pole {:.4e} 1/s (A: {:.4e}), d z'/d rho' {coupling:.4e} (A: {:.4e})",
            omega / std::f64::consts::TAU,
            pole,
            lin.a[(row, row)],
            lin.a[(row, rate)]
        );
        assert!(
            (omega / ws).abs() > 0.3,
            "slider {i} far from the Stribeck speed"
        );
        assert!((lin.a[(row, row)] / pole - 1.0).abs() < 1e-5, "slider {i}");
        assert!(
            (lin.a[(row, rate)] - coupling).abs() < 1e-4 * g,
            "slider {i}"
        );
    }
}
