//! Friction with a stuck phase (LuGre, `flexprr_control::friction`) and the feedforward that
//! includes friction, checked against closed forms:
//!
//! * a motor on its ball screw (one degree of freedom: the slider with the reflected rotor,
//!   driven through `MotorBallScrew::apply_with_states`): a constant torque below the
//!   static torque leaves it stuck with the bristles at `tau / sigma0`, turned by the
//!   closed-form presliding `-z_S ln(1 - tau / tau_S)`, at rest; a slowly rising torque
//!   breaks it away at the static torque; sliding at a constant speed the bristles relax
//!   exponentially onto the Stribeck curve `g(omega) + sigma2 omega`;
//! * the machine under PD on a constant-velocity line with Coulomb friction: the slider
//!   error is the closed form `g eta tau_C / kp` without the friction in the feedforward and
//!   nearly zero with it.

use std::sync::Arc;

use flexprr_control::{Actuator, LuGre, MotorBallScrew, MotorRatings, Pid};
use flexprr_dynamics::{Actuation, CoupledOptions, CoupledSystem, ModalDamping, SceneModel, paper};
use flexprr_integrators::{Bdf, Integrator, OdeSystem, Options};
use flexprr_kinematics::{Line, Pose, Trajectory};
use nalgebra::Vector3;

const COULOMB: f64 = 0.02;
const STATIC: f64 = 0.03;
const STIFFNESS: f64 = 30.0;
const ROTOR: f64 = 1.6e-5;
const SLIDER: f64 = 0.5;

/// The BM200-like motor of `configs/servo_motor_f2.toml` with LuGre friction: a 30 N m/rad
/// presliding spring (1 mrad of presliding at the static torque, 1.6 um at the nut).
fn motor(damping: f64) -> MotorBallScrew {
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
        coulomb_friction: COULOMB,
        coulomb_smoothing: 0.01,
        drive: None,
        screw: None,
        friction_feedforward: false,
        lugre: Some(LuGre {
            static_friction: STATIC,
            stribeck_speed: 0.05,
            bristle_stiffness: STIFFNESS,
            bristle_damping: damping,
        }),
    }
    .validated()
    .unwrap()
}

/// The slider (`SLIDER` kg) on the motor's screw, driven by the motor torque `torque(t)`:
/// state `(x, x', z)`.
struct Screw<F: Fn(f64) -> f64> {
    motor: MotorBallScrew,
    torque: F,
}

impl<F: Fn(f64) -> f64> Screw<F> {
    fn mass(&self) -> f64 {
        SLIDER + self.motor.mass_on_slider()
    }
    /// The force command that asks the motor for the torque `tau`.
    fn command(&self, tau: f64) -> f64 {
        tau * self.motor.ratio() * self.motor.efficiency
    }
}

impl<F: Fn(f64) -> f64> OdeSystem for Screw<F> {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        let command = self.command((self.torque)(t));
        let out = self
            .motor
            .apply_with_states(command, y[1], None, &y[2..], &mut dy[2..]);
        dy[0] = y[1];
        dy[1] = out.force / self.mass();
    }
}

fn solve<S: OdeSystem>(system: &mut S, y0: &[f64], t: &[f64]) -> flexprr_integrators::Solution {
    Bdf::new(Options::default().rtol(1e-9).atol(1e-14))
        .solve(system, 0.0, y0, t)
        .unwrap()
}

#[test]
fn below_the_static_torque_the_motor_stays_stuck_on_its_presliding_spring() {
    // Overdamped on the bristles (damping ratio 3 with the rotor and slider): the approach
    // is monotone, so the presliding displacement has its closed form. The closed form
    // takes g = tau_S (presliding speeds far below the Stribeck speed): with a Stribeck
    // speed of 1 rev/s. (At 0.05 rev/s a step of 0.7 tau_S turns the shaft 1.9 % further,
    // and a step of 0.9 tau_S breaks it away: the presliding speed reaches the Stribeck
    // speed and the friction falls, the model's rate dependence.)
    let inertia = ROTOR + SLIDER / (std::f64::consts::TAU / 0.01_f64).powi(2);
    let damping = 6.0 * (STIFFNESS * inertia).sqrt();
    for fraction in [0.1, 0.5, 0.9] {
        let tau = fraction * STATIC;
        let mut m = motor(damping);
        if let Some(lugre) = m.lugre.as_mut() {
            lugre.stribeck_speed = 1.0;
        }
        let mut screw = Screw {
            motor: m,
            torque: move |_| tau,
        };
        let g = screw.motor.ratio();
        let t: Vec<f64> = (0..=50).map(|k| 0.002 * f64::from(k)).collect();
        let solution = solve(&mut screw, &[0.0; 3], &t);
        let end = solution.y(t.len() - 1);
        let (phi, speed, z) = (g * end[0], g * end[1], end[2]);
        // Stuck: the bristles carry the torque, the shaft is at rest.
        assert!(
            (z / (tau / STIFFNESS) - 1.0).abs() < 1e-3,
            "{fraction}: z = {z}"
        );
        assert!(speed.abs() < 1e-6, "{fraction}: {speed} rad/s");
        // Turned by the closed-form presliding displacement.
        let z_s = STATIC / STIFFNESS;
        let expected = -z_s * (1.0 - fraction).ln();
        println!(
            "tau = {fraction} tau_S: phi = {phi:.6e} rad, closed form {expected:.6e}, tau / sigma0 = {:.6e}",
            tau / STIFFNESS
        );
        assert!(
            (phi / expected - 1.0).abs() < 1e-3,
            "{fraction}: {phi} vs {expected}"
        );
        // Held for good: no creep over the last half.
        let mid = solution.y(t.len() / 2);
        assert!((g * mid[0] - phi).abs() < 1e-3 * phi, "{fraction}: creeps");
    }
}

#[test]
fn a_slowly_rising_torque_breaks_away_at_the_static_torque() {
    let rate = STATIC; // N m/s: the static torque at t = 1 s
    let mut screw = Screw {
        motor: motor(2.0 * (STIFFNESS * ROTOR).sqrt()),
        torque: move |t| rate * t,
    };
    let g = screw.motor.ratio();
    let t: Vec<f64> = (0..=1100).map(|k| 1e-3 * f64::from(k)).collect();
    let solution = solve(&mut screw, &[0.0; 3], &t);
    // Breakaway: the speed reaches the Stribeck speed (0.05 rev/s).
    let k = (0..t.len())
        .find(|&k| (solution.y(k)[1] / 0.01).abs() >= 0.05)
        .expect("no breakaway");
    let breakaway = rate * t[k];
    println!("breakaway at {breakaway:.5} N m, static torque {STATIC} N m");
    assert!((breakaway / STATIC - 1.0).abs() < 0.01, "{breakaway}");
    // Before it, stuck: at 0.9 tau_S the shaft has turned no more than the presliding.
    let k90 = 900;
    let phi = g * solution.y(k90)[0];
    let expected = -(STATIC / STIFFNESS) * 0.1f64.ln();
    assert!((phi / expected - 1.0).abs() < 0.02, "{phi} vs {expected}");
}

/// The bristles at a shaft driven at a constant speed: the state `z` alone.
struct Bristles {
    motor: MotorBallScrew,
    velocity: f64,
}

impl OdeSystem for Bristles {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
        self.motor
            .apply_with_states(0.0, self.velocity, None, y, dy);
    }
}

#[test]
fn sliding_at_a_constant_speed_gives_the_stribeck_curve() {
    let m = motor(0.01);
    let lugre = m.lugre.unwrap();
    let (g, eta) = (m.ratio(), m.efficiency);
    for revs in [-3.0, -0.05, 0.01, 0.03, 0.1, 1.0, 20.0] {
        let velocity = revs * m.lead;
        let omega = g * velocity;
        let curve = omega.signum() * lugre.stribeck(COULOMB, omega);
        let relaxation = STIFFNESS * omega.abs() / lugre.stribeck(COULOMB, omega);
        let t: Vec<f64> = (0..=80).map(|k| f64::from(k) * 0.5 / relaxation).collect();
        let mut bristles = Bristles { motor: m, velocity };
        let solution = solve(&mut bristles, &[0.0], &t);
        for (k, &tk) in t.iter().enumerate() {
            // z(t) = z_ss (1 - exp(-sigma0 |omega| t / g(omega))) at a constant speed.
            let z = curve / STIFFNESS * (1.0 - (-relaxation * tk).exp());
            let got = solution.y(k)[0];
            assert!(
                (got - z).abs() <= 1e-6 * curve.abs() / STIFFNESS,
                "{revs}: {got} vs {z}"
            );
        }
        // Settled: the force on the slider is the curve plus the viscous term.
        let z = solution.y(t.len() - 1)[0];
        let out = m.apply_with_states(0.0, velocity, None, &[z], &mut [0.0]);
        let expected = -g * eta * (curve + 1e-4 * omega);
        assert!(
            (out.force - expected).abs() <= 1e-6 * expected.abs(),
            "{revs}: {out:?}"
        );
        // The feedforward's friction is the same steady force.
        let with_feedforward = MotorBallScrew {
            friction_feedforward: true,
            ..m
        };
        let feedforward = with_feedforward.friction_feedforward(velocity);
        assert!((feedforward + expected).abs() <= 1e-12 * expected.abs());
    }
}

/// The coupled machine under PD (`kp`, `kd`) on a slow line (platform at 20 mm/s), its
/// motors with Coulomb friction only, the friction in the feedforward or not: the slider
/// errors from 0.1 s to 0.2 s.
fn line_errors(friction_feedforward: bool) -> (Vec<[f64; 3]>, f64) {
    let (kp, kd) = (2.0e5, 2000.0);
    let m = MotorBallScrew {
        viscous_friction: 0.0,
        lugre: None,
        friction_feedforward,
        ..motor(0.0)
    };
    let actuator: Arc<dyn Actuator> = Arc::new(m);
    let law = Pid::pd(kp, kd, true, 0.0).unwrap();
    let actuation = Actuation {
        controller: Arc::new(law),
        actuators: [actuator.clone(), actuator.clone(), actuator],
    };
    let line: Arc<dyn Trajectory + Send + Sync> = Arc::new(
        Line::new(
            Pose::new(-0.05, 0.0, 45f64.to_radians()),
            Vector3::new(0.02, 0.01, 0.0),
            0.0,
        )
        .unwrap(),
    );
    let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
    let mut model = CoupledSystem::new(
        machine,
        line.clone(),
        ModalDamping::none(),
        CoupledOptions::full(),
    )
    .unwrap()
    .with_actuation(actuation, 0.0)
    .unwrap();
    // The sliders follow the links' modal coordinates.
    let n = model.modes();
    let y0 = SceneModel::initial_state(&model);
    let t: Vec<f64> = (0..=20).map(|k| 0.1 + 0.005 * f64::from(k)).collect();
    let mut all = vec![0.0];
    all.extend(&t);
    let solution = flexprr_integrators::Rk45::new(Options::default().rtol(1e-9).atol(1e-12))
        .solve(&mut model, 0.0, &y0, &all)
        .unwrap();
    let geometry = paper::machine(3, paper::YOUNGS_MODULUS).unwrap().geometry;
    let errors = t
        .iter()
        .enumerate()
        .map(|(k, &tk)| {
            let rigid = geometry.inverse_kinematics(&line.motion(tk)).unwrap();
            let y = solution.y(k + 1);
            std::array::from_fn(|i| rigid.legs[i].rho - y[n + i])
        })
        .collect();
    // The closed form: kp e = g eta tau_C at a constant speed (all sliders move).
    let expected = m.ratio() * m.efficiency * COULOMB / kp;
    (errors, expected)
}

#[test]
fn the_friction_feedforward_removes_the_coulomb_error_of_a_pd_law() {
    let (without, expected) = line_errors(false);
    let (with, _) = line_errors(true);
    let worst = |errors: &[[f64; 3]], target: &dyn Fn(f64) -> f64| {
        errors
            .iter()
            .flat_map(|e| e.iter().map(|&e| (e.abs() - target(e)).abs()))
            .fold(0.0, f64::max)
    };
    let off_without = worst(&without, &|_| expected);
    let off_with = worst(&with, &|_| 0.0);
    println!(
        "closed form g eta tau_C / kp = {expected:.4e} m; without: largest deviation {off_without:.3e} m; with: largest error {off_with:.3e} m"
    );
    assert!(off_without < 0.01 * expected, "{off_without} of {expected}");
    assert!(off_with < 0.01 * expected, "{off_with} of {expected}");
}
