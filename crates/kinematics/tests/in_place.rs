//! The in-place, angle-free inverse kinematics (`inverse_kinematics_unchecked_into`,
//! `inverse_kinematics_into`) over random machines, poses and twists:
//!
//! - against an independent angle-based solution written here: the link angle from
//!   `atan2(C - B)` with the slider position the machine was built with, and the rates from
//!   the 2x2 system `[u, l n] (rho', b')^T = C'` (and the same with `C'' + l b'^2 e` for the
//!   second derivatives) solved by Cramer's rule with the angles, where the library
//!   projects on `e` and `n`;
//! - against the by-value functions, to 1e-14 relative, from a buffer filled with NaN
//!   (every field must be overwritten), with identical errors for the checked variant;
//! - `LegKinematics::beta` against `atan2` of the link vector.

// Legs and axes are indexed in parallel across several arrays.
#![allow(clippy::needless_range_loop)]

mod common;

use common::{Case, angle_diff, arb_case};
use flexprr_kinematics::{
    Geometry, KinematicsError, LegKinematics, MachineKinematics, PlatformMotion, Thresholds,
};
use nalgebra::{Point2, Vector2, Vector3};
use proptest::prelude::*;

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 256,
        max_global_rejects: 4096,
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

/// A state whose every number is NaN: whatever the IK leaves unwritten stays visible.
fn poisoned() -> MachineKinematics {
    let nan = f64::NAN;
    let v = Vector2::new(nan, nan);
    let p = Point2::new(nan, nan);
    let leg = LegKinematics {
        rho: nan,
        rho_dot: nan,
        rho_ddot: nan,
        beta_dot: nan,
        beta_ddot: nan,
        a: p,
        b: p,
        c: p,
        c_dot: v,
        c_ddot: v,
        e: v,
        n: v,
    };
    MachineKinematics {
        motion: PlatformMotion {
            pose: flexprr_kinematics::Pose::new(nan, nan, nan),
            velocity: Vector3::new(nan, nan, nan),
            acceleration: Vector3::new(nan, nan, nan),
        },
        legs: [leg; 3],
    }
}

/// Every number of a leg, in a fixed order, for field-by-field comparison.
fn numbers(leg: &LegKinematics) -> [f64; 19] {
    [
        leg.rho,
        leg.rho_dot,
        leg.rho_ddot,
        leg.beta_dot,
        leg.beta_ddot,
        leg.a.x,
        leg.a.y,
        leg.b.x,
        leg.b.y,
        leg.c.x,
        leg.c.y,
        leg.c_dot.x,
        leg.c_dot.y,
        leg.c_ddot.x,
        leg.c_ddot.y,
        leg.e.x,
        leg.e.y,
        leg.n.x,
        leg.n.y,
    ]
}

/// Independent rates of one leg from the link angle: returns `(beta, rho', b', rho'', b'')`.
fn angle_reference(
    geometry: &Geometry,
    case: &Case,
    motion: &PlatformMotion,
    i: usize,
) -> [f64; 5] {
    let leg = &geometry.legs[i];
    let (l, u) = (leg.link_length, leg.guide.direction.into_inner());
    let phi = motion.pose.phi;
    let r = Vector2::new(
        phi.cos() * leg.attachment.x - phi.sin() * leg.attachment.y,
        phi.sin() * leg.attachment.x + phi.cos() * leg.attachment.y,
    );
    let c = motion.pose.position() + r;
    let b = leg.guide.anchor + case.rho[i] * u;
    let link = c - b;
    let beta = link.y.atan2(link.x);
    let (sb, cb) = beta.sin_cos();
    let (ln_x, ln_y) = (-l * sb, l * cb);
    // Platform joint velocity and acceleration: C' = v + w k x r, C'' = a + w' k x r - w^2 r.
    let (v, w) = (motion.velocity, motion.velocity.z);
    let (acc, w_dot) = (motion.acceleration, motion.acceleration.z);
    let c_dot = Vector2::new(v.x - w * r.y, v.y + w * r.x);
    let c_ddot = Vector2::new(
        acc.x - w_dot * r.y - w * w * r.x,
        acc.y + w_dot * r.x - w * w * r.y,
    );
    // Cramer on [u, l n] x = rhs.
    let det = u.x * ln_y - u.y * ln_x;
    let solve = |rhs: Vector2<f64>| {
        (
            (rhs.x * ln_y - rhs.y * ln_x) / det,
            (u.x * rhs.y - u.y * rhs.x) / det,
        )
    };
    let (rho_dot, beta_dot) = solve(c_dot);
    let (rho_ddot, beta_ddot) = solve(c_ddot + l * beta_dot * beta_dot * Vector2::new(cb, sb));
    [beta, rho_dot, beta_dot, rho_ddot, beta_ddot]
}

prop_compose! {
    /// A random machine with a motion through its reachable pose: twist and acceleration
    /// scaled to the machine.
    fn arb_motion()(
        case in arb_case(),
        twist in prop::array::uniform3(-1.0f64..1.0),
        accel in prop::array::uniform3(-1.0f64..1.0),
    ) -> (Case, PlatformMotion) {
        let s = case.scale;
        let motion = PlatformMotion {
            pose: case.pose,
            velocity: Vector3::new(twist[0] * s, twist[1] * s, twist[2]),
            acceleration: Vector3::new(accel[0] * s, accel[1] * s, accel[2]),
        };
        (case, motion)
    }
}

proptest! {
    #![proptest_config(config())]

    /// The in-place result against the angle-based reference and against the by-value
    /// function; the angle on demand against `atan2` of the link vector.
    #[test]
    fn in_place_matches_angle_reference_and_by_value((case, motion) in arb_motion()) {
        let g = &case.geometry;
        let measures = g.singularity(&case.pose).unwrap();
        let mut lean = poisoned();
        g.inverse_kinematics_unchecked_into(&motion, &mut lean).unwrap();
        let full = g.inverse_kinematics_unchecked(&motion).unwrap();
        prop_assert_eq!(lean.motion, motion);
        for i in 0..3 {
            let s = &lean.legs[i];
            let sc = case.scale;
            // By value: every number to 1e-14 relative to its own size and the machine's.
            for (k, (a, b)) in numbers(s).iter().zip(numbers(&full.legs[i].kinematics)).enumerate() {
                prop_assert!((a - b).abs() <= 1e-14 * (a.abs().max(b.abs()) + 1e-300), "leg {i} number {k}: {a} vs {b}");
            }
            prop_assert!(angle_diff(s.beta(), full.legs[i].beta).abs() <= 1e-14 * std::f64::consts::PI);
            // Angle-based reference; the rates' rounding grows like 1 / |e.u|.
            let [beta, rho_dot, beta_dot, rho_ddot, beta_ddot] = angle_reference(g, &case, &motion, i);
            let k = 1.0 / measures.type_i[i].max(1e-300);
            prop_assert!(angle_diff(s.beta(), beta).abs() <= 1e-13 * k, "leg {i}: beta {} vs {beta}", s.beta());
            prop_assert!((s.e - Vector2::new(beta.cos(), beta.sin())).norm() <= 1e-13 * k);
            prop_assert!((s.n - Vector2::new(-beta.sin(), beta.cos())).norm() <= 1e-13 * k);
            prop_assert!((s.rho - case.rho[i]).abs() <= 1e-13 * sc * k);
            let close = |a: f64, b: f64, size: f64| (a - b).abs() <= 1e-11 * k * k * size;
            let speed = sc + s.c_dot.norm() + s.rho_dot.abs();
            prop_assert!(close(s.rho_dot, rho_dot, speed), "leg {i}: rho' {} vs {rho_dot}", s.rho_dot);
            prop_assert!(close(s.beta_dot, beta_dot, speed / g.legs[i].link_length), "leg {i}: b' {} vs {beta_dot}", s.beta_dot);
            let size2 = sc + s.c_ddot.norm() + s.rho_ddot.abs() + g.legs[i].link_length * s.beta_dot.powi(2);
            prop_assert!(close(s.rho_ddot, rho_ddot, size2 * k), "leg {i}: rho'' {} vs {rho_ddot}", s.rho_ddot);
            prop_assert!(close(s.beta_ddot, beta_ddot, size2 * k / g.legs[i].link_length), "leg {i}: b'' {} vs {beta_ddot}", s.beta_ddot);
        }
    }

    /// The checked in-place variant gives what the checked by-value one gives, error for
    /// error, for thresholds that reject a good share of the random poses.
    #[test]
    fn checked_in_place_matches_checked_by_value((case, motion) in arb_motion(), type_i in 0.0f64..0.5, type_ii in 0.0f64..0.5) {
        let g = case.geometry.with_thresholds(Thresholds { type_i, type_ii }).unwrap();
        let mut lean = poisoned();
        let in_place = g.inverse_kinematics_into(&motion, &mut lean);
        let by_value = g.inverse_kinematics(&motion);
        match (&in_place, &by_value) {
            (Ok(()), Ok(full)) => {
                for i in 0..3 {
                    prop_assert_eq!(&lean.legs[i], &full.legs[i].kinematics);
                    prop_assert_eq!(lean.legs[i].beta().to_bits(), full.legs[i].beta.to_bits());
                }
            }
            (Err(a), Err(b)) => prop_assert_eq!(a, b),
            _ => prop_assert!(false, "in place {in_place:?} vs by value {by_value:?}"),
        }
        // The same for the unchecked pair.
        let mut lean = poisoned();
        let in_place = g.inverse_kinematics_unchecked_into(&motion, &mut lean).map(|()| lean);
        let by_value = g.inverse_kinematics_unchecked(&motion);
        match (&in_place, &by_value) {
            (Ok(lean), Ok(full)) => prop_assert_eq!(lean.with_angles(), *full),
            (Err(a), Err(b)) => prop_assert_eq!(a, b),
            _ => prop_assert!(false, "in place {in_place:?} vs by value {by_value:?}"),
        }
    }
}

/// Non-finite input and an unreachable pose are errors of the in-place variants too, never
/// NaN in the state.
#[test]
fn in_place_errors_name_the_cause() {
    let g = Geometry::paper();
    let mut state = MachineKinematics::default();
    let mut bad = PlatformMotion::at_rest(flexprr_kinematics::Pose::new(0.01, 0.0, 0.1));
    bad.velocity.z = f64::NAN;
    assert!(matches!(
        g.inverse_kinematics_unchecked_into(&bad, &mut state),
        Err(KinematicsError::NonFinite { .. })
    ));
    assert!(matches!(
        g.inverse_kinematics_into(&bad, &mut state),
        Err(KinematicsError::NonFinite { .. })
    ));
    let far = PlatformMotion::at_rest(flexprr_kinematics::Pose::new(5.0, 0.0, 0.0));
    assert!(matches!(
        g.inverse_kinematics_unchecked_into(&far, &mut state),
        Err(KinematicsError::Unreachable { .. })
    ));
}
