//! Rigid inverse dynamics against independent checks: the full 12-equation system, the power
//! balance `sum F_ai rho_i' = dT/dt`, the link's own equilibrium, and the type-II error.

use flexprr_dynamics::{
    DynamicsError, Formulation, Machine, ModalDamping, ModalSystem, end_forces, inverse_dynamics,
    inverse_dynamics_full, paper, rigid_kinetic_energy,
};
use flexprr_kinematics::{PlatformMotion, Pose, Trajectory};
use nalgebra::Vector3;
use proptest::prelude::*;
use std::sync::Arc;

fn machine() -> Machine {
    paper::machine(3, paper::YOUNGS_MODULUS).unwrap()
}

/// A smooth, non-periodic test motion around the paper's workspace with rotation, so that
/// every inertia term (including I_p phi'') is exercised.
#[derive(Debug, Clone, Copy)]
struct Wobble {
    amp: [f64; 3],
    freq: [f64; 3],
    phase: [f64; 3],
}

impl Trajectory for Wobble {
    fn motion(&self, t: f64) -> PlatformMotion {
        let centre = [-0.05, 0.0, std::f64::consts::FRAC_PI_4];
        let mut q = [0.0; 3];
        let mut v = [0.0; 3];
        let mut a = [0.0; 3];
        for k in 0..3 {
            let w = std::f64::consts::TAU * self.freq[k];
            let s = (w * t + self.phase[k]).sin();
            let c = (w * t + self.phase[k]).cos();
            q[k] = centre[k] + self.amp[k] * s;
            v[k] = self.amp[k] * w * c;
            a[k] = -self.amp[k] * w * w * s;
        }
        PlatformMotion {
            pose: Pose::new(q[0], q[1], q[2]),
            velocity: Vector3::from(v),
            acceleration: Vector3::from(a),
        }
    }
}

fn wobble() -> impl Strategy<Value = Wobble> {
    (
        prop::array::uniform3(0.0..0.03f64),
        prop::array::uniform3(1.0..25.0f64),
        prop::array::uniform3(0.0..std::f64::consts::TAU),
    )
        .prop_map(|(amp, freq, phase)| Wobble {
            amp: [amp[0], amp[1], amp[2] * 3.0],
            freq,
            phase,
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// The hand-reduced 3x3 solve equals the full 12-equation system.
    #[test]
    fn reduced_equals_full_system(traj in wobble(), t in 0.0..0.5f64) {
        let m = machine();
        let state = m.geometry.inverse_kinematics(&traj.motion(t)).unwrap();
        let fast = inverse_dynamics(&m, &state, None, t).unwrap();
        let full = inverse_dynamics_full(&m, &state, t).unwrap();
        let scale = fast.slider_on_link.iter().map(|f| f.norm()).fold(1.0, f64::max);
        for i in 0..3 {
            prop_assert!((fast.slider_on_link[i] - full.slider_on_link[i]).norm() < 1e-10 * scale);
            prop_assert!((fast.platform_on_link[i] - full.platform_on_link[i]).norm() < 1e-10 * scale);
            prop_assert!((fast.driving_force[i] - full.driving_force[i]).abs() < 1e-10 * scale);
        }
    }

    /// Power balance: the actuators' power equals the rate of change of the rigid kinetic
    /// energy, the latter by central differences of T (an independent computation).
    #[test]
    fn actuator_power_equals_kinetic_energy_rate(traj in wobble(), t in 0.01..0.5f64) {
        let m = machine();
        let state = m.geometry.inverse_kinematics(&traj.motion(t)).unwrap();
        let forces = inverse_dynamics(&m, &state, None, t).unwrap();
        let power: f64 = (0..3).map(|i| forces.driving_force[i] * state.legs[i].rho_dot).sum();
        let h = 1e-6;
        let energy = |tt: f64| {
            let s = m.geometry.inverse_kinematics_unchecked(&traj.motion(tt)).unwrap();
            rigid_kinetic_energy(&m, &s)
        };
        let rate = (energy(t + h) - energy(t - h)) / (2.0 * h);
        let scale = (0..3).map(|i| (forces.driving_force[i] * state.legs[i].rho_dot).abs()).sum::<f64>().max(1e-6);
        prop_assert!((power - rate).abs() < 1e-5 * scale, "power {power} vs dT/dt {rate}");
    }
}

/// The joint-reaction axial force at `x = l` equals the platform's reaction along the link,
/// `F_C.e`, by the link's axial equilibrium (an independent law).
#[test]
fn joint_reaction_axial_force_closes_at_platform_end() {
    let m = Arc::new(machine());
    let traj = Arc::new(paper::trajectory(20.0).unwrap());
    let mut sys = ModalSystem::new(
        m.clone(),
        traj,
        Formulation::consistent(),
        ModalDamping::none(),
    )
    .unwrap();
    for k in 0..20 {
        let t = k as f64 * 0.0025;
        let inst = sys.instant(t).unwrap();
        let reactions = inst.reactions.unwrap();
        for i in 0..3 {
            let (_, p_c) = end_forces(&inst.loads[i], m.links[i].length());
            let f_c = reactions.platform_on_link[i].dot(&inst.state.legs[i].e);
            assert!(
                (p_c - f_c).abs() < 1e-9 * f_c.abs().max(1.0),
                "link {i} t {t}: {p_c} vs {f_c}"
            );
        }
    }
}

/// The radial home pose (all links through the platform centre) is type-II singular: the
/// inverse dynamics says so instead of returning huge forces.
#[test]
fn home_pose_is_a_clear_type_ii_error() {
    let m = machine();
    let state = m
        .geometry
        .inverse_kinematics_unchecked(&PlatformMotion::at_rest(Pose::new(0.0, 0.0, 0.0)))
        .unwrap();
    let err = inverse_dynamics(&m, &state, None, 0.25).unwrap_err();
    assert!(
        matches!(err, DynamicsError::SingularInverseDynamics { .. }),
        "{err}"
    );
    let msg = err.to_string();
    assert!(msg.contains("t = 0.25") && msg.contains("type-II"), "{msg}");
}
