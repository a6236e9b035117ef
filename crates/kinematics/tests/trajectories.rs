//! Trajectories: derivatives against central differences, rest-to-rest laws against their
//! textbook values, the spline against an exact cubic, and object safety.

// Legs and axes are indexed in parallel across several arrays.
#![allow(clippy::needless_range_loop)]

use std::f64::consts::{PI, TAU};

use flexprr_kinematics::{
    Circle, Line, PlatformMotion, PointToPoint, Pose, Profile, Trajectory, WaypointSpline,
};
use nalgebra::{Point2, Vector3};
use proptest::prelude::*;

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 256,
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

/// Checks velocity and acceleration of `traj` at `t` against five-point central differences
/// of the pose and of the velocity, with step `h`.
fn check_derivatives(traj: &dyn Trajectory, t: f64, h: f64, tol: f64) -> Result<(), TestCaseError> {
    let q = |k: i32| traj.motion(t + k as f64 * h);
    let m: Vec<PlatformMotion> = (-2..=2).map(q).collect();
    let centre = traj.motion(t);
    for axis in 0..3 {
        let p: Vec<f64> = m.iter().map(|s| s.pose.to_vector()[axis]).collect();
        let v: Vec<f64> = m.iter().map(|s| s.velocity[axis]).collect();
        let dp = (p[0] - 8.0 * p[1] + 8.0 * p[3] - p[4]) / (12.0 * h);
        let dv = (v[0] - 8.0 * v[1] + 8.0 * v[3] - v[4]) / (12.0 * h);
        let scale_v = 1.0 + centre.velocity.norm();
        let scale_a = 1.0 + centre.acceleration.norm();
        prop_assert!(
            (centre.velocity[axis] - dp).abs() <= tol * scale_v,
            "axis {axis}: v {} vs fd {dp}",
            centre.velocity[axis]
        );
        prop_assert!(
            (centre.acceleration[axis] - dv).abs() <= tol * scale_a,
            "axis {axis}: a {} vs fd {dv}",
            centre.acceleration[axis]
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn circle_derivatives(cx in -1.0f64..1.0, cy in -1.0f64..1.0, r in 0.0f64..0.5, f in -30.0f64..30.0, phi in -PI..PI, th in -PI..PI, t in 0.0f64..1.0) {
        let c = Circle::new(Point2::new(cx, cy), r, f, phi, th).unwrap();
        check_derivatives(&c, t, 1e-5, 1e-6)?;
        let m = c.motion(t);
        // On the circle, speed 2 pi |f| r, centripetal acceleration (2 pi f)^2 r towards the centre.
        let rel = Vector3::new(m.pose.x - cx, m.pose.y - cy, 0.0);
        prop_assert!((rel.norm() - r).abs() < 1e-12);
        prop_assert!((m.velocity.norm() - TAU * f.abs() * r).abs() < 1e-9 * (1.0 + TAU * f.abs() * r));
        prop_assert!((m.acceleration + (TAU * f).powi(2) * rel).norm() < 1e-8 * (1.0 + m.acceleration.norm()));
        prop_assert!((m.pose.phi - phi).abs() < 1e-15);
    }

    #[test]
    fn line_derivatives(q0 in prop::array::uniform3(-1.0f64..1.0), v in prop::array::uniform3(-1.0f64..1.0), t0 in -1.0f64..1.0, t in -2.0f64..2.0) {
        let line = Line::new(Pose::new(q0[0], q0[1], q0[2]), Vector3::from(v), t0).unwrap();
        check_derivatives(&line, t, 1e-4, 1e-9)?;
        let m = line.motion(t0);
        prop_assert!((m.pose.to_vector() - Vector3::from(q0)).norm() < 1e-15);
    }

    #[test]
    fn point_to_point_derivatives_and_ends(
        a in prop::array::uniform3(-1.0f64..1.0), b in prop::array::uniform3(-1.0f64..1.0),
        t0 in -1.0f64..1.0, duration in 0.05f64..2.0, tau in 0.01f64..0.99, cycloidal in any::<bool>(),
    ) {
        let profile = if cycloidal { Profile::Cycloidal } else { Profile::Quintic };
        let start = Pose::new(a[0], a[1], a[2]);
        let end = Pose::new(b[0], b[1], b[2]);
        let mv = PointToPoint::new(start, end, t0, duration, profile).unwrap();
        check_derivatives(&mv, t0 + tau * duration, 1e-5 * duration, 1e-5)?;
        // Rest-to-rest: at the ends and outside, the pose is the end pose and the platform rests.
        for (t, pose) in [(t0, start), (t0 - 1.0, start), (t0 + duration, end), (t0 + duration + 1.0, end)] {
            let m = mv.motion(t);
            prop_assert!((m.pose.to_vector() - pose.to_vector()).norm() < 1e-14);
            prop_assert!(m.velocity.norm() < 1e-12 && m.acceleration.norm() < 1e-9);
        }
        prop_assert!((mv.duration().unwrap() - (t0 + duration)).abs() < 1e-15);
        // The path is the straight segment: pose - start is parallel to end - start.
        let m = mv.motion(t0 + tau * duration);
        let d = end.to_vector() - start.to_vector();
        prop_assert!((m.pose.to_vector() - start.to_vector()).cross(&d).norm() < 1e-12);
    }

    /// Clamped cubic spline through samples of the cubic q(t) = q0 + dq (3 s^2 - 2 s^3),
    /// s = (t - t_0) / (t_n - t_0), which has zero slope at both ends, is that cubic exactly.
    #[test]
    fn spline_reproduces_clamped_cubic(q0 in prop::array::uniform3(-1.0f64..1.0), dq in prop::array::uniform3(-1.0f64..1.0), gaps in prop::collection::vec(0.05f64..1.0, 1..8), t0 in -1.0f64..1.0, probe in 0.0f64..1.0) {
        let mut times = vec![t0];
        for g in &gaps {
            times.push(times.last().unwrap() + g);
        }
        let span = times.last().unwrap() - t0;
        let exact = |t: f64| {
            let s = (t - t0) / span;
            let q = Vector3::from(q0) + Vector3::from(dq) * (3.0 * s * s - 2.0 * s * s * s);
            let v = Vector3::from(dq) * ((6.0 * s - 6.0 * s * s) / span);
            let a = Vector3::from(dq) * ((6.0 - 12.0 * s) / (span * span));
            (q, v, a)
        };
        let waypoints: Vec<(f64, Pose)> = times.iter().map(|&t| (t, Pose::from_vector(&exact(t).0))).collect();
        let spline = WaypointSpline::new(&waypoints).unwrap();
        let t = t0 + probe * span;
        let m = spline.motion(t);
        let (q, v, a) = exact(t);
        prop_assert!((m.pose.to_vector() - q).norm() < 1e-12);
        prop_assert!((m.velocity - v).norm() < 1e-11 / span);
        prop_assert!((m.acceleration - a).norm() < 1e-10 / (span * span));
    }

    /// Through random waypoints: interpolates them, zero end velocities, and position,
    /// velocity and acceleration continuous across every interior knot (C2).
    #[test]
    fn spline_is_c2_and_interpolates(points in prop::collection::vec((0.05f64..1.0, prop::array::uniform3(-1.0f64..1.0)), 2..8)) {
        let mut t = 0.0;
        let waypoints: Vec<(f64, Pose)> = points.iter().map(|(gap, q)| { t += gap; (t, Pose::new(q[0], q[1], q[2])) }).collect();
        let spline = WaypointSpline::new(&waypoints).unwrap();
        for (tk, pose) in &waypoints {
            prop_assert!((spline.motion(*tk).pose.to_vector() - pose.to_vector()).norm() < 1e-12);
        }
        let n = waypoints.len();
        let eps = 1e-9;
        // Just inside the ends v ~ a eps: zero end velocity up to that.
        for t in [waypoints[0].0 + eps, waypoints[n - 1].0 - eps] {
            let m = spline.motion(t);
            prop_assert!(m.velocity.norm() <= 2.0 * eps * m.acceleration.norm() + 1e-12);
        }
        for (tk, _) in &waypoints[1..n - 1] {
            let l = spline.motion(tk - eps);
            let r = spline.motion(tk + eps);
            let scale = 1.0 + l.acceleration.norm();
            prop_assert!((l.pose.to_vector() - r.pose.to_vector()).norm() < 1e-6 * scale);
            prop_assert!((l.velocity - r.velocity).norm() < 1e-6 * scale);
            prop_assert!((l.acceleration - r.acceleration).norm() < 1e-5 * scale, "jump {}", (l.acceleration - r.acceleration).norm());
        }
        let mid = 0.5 * (waypoints[0].0 + waypoints[1].0);
        check_derivatives(&spline, mid, 1e-5, 1e-6)?;
    }
}

/// Textbook values of the rest-to-rest laws (Biagiotti & Melchiorri 2008): ends, peak
/// velocity at tau = 1/2 (quintic 15/8, cycloidal 2) and peak acceleration (quintic
/// 10/sqrt(3) at tau = 1/2 -/+ sqrt(3)/6, cycloidal 2 pi at tau = 1/4).
#[test]
fn profile_textbook_values() {
    for profile in [Profile::Quintic, Profile::Cycloidal] {
        let (s0, v0, a0) = profile.evaluate(0.0);
        let (s1, v1, a1) = profile.evaluate(1.0);
        assert!(s0.abs() < 1e-15 && (s1 - 1.0).abs() < 1e-15);
        assert!(v0.abs() < 1e-15 && v1.abs() < 1e-15 && a0.abs() < 1e-12 && a1.abs() < 1e-12);
        // Just inside the ends, the acceleration tends to zero too (continuous at rest).
        assert!(
            profile.evaluate(1e-9).2.abs() < 1e-6 && profile.evaluate(1.0 - 1e-9).2.abs() < 1e-6
        );
        let (s_half, _, a_half) = profile.evaluate(0.5);
        assert!((s_half - 0.5).abs() < 1e-15 && a_half.abs() < 1e-12);
    }
    assert!((Profile::Quintic.evaluate(0.5).1 - 15.0 / 8.0).abs() < 1e-15);
    assert!((Profile::Cycloidal.evaluate(0.5).1 - 2.0).abs() < 1e-15);
    let tau_peak = 0.5 - 3f64.sqrt() / 6.0;
    assert!((Profile::Quintic.evaluate(tau_peak).2 - 10.0 / 3f64.sqrt()).abs() < 1e-12);
    assert!((Profile::Cycloidal.evaluate(0.25).2 - TAU).abs() < 1e-12);
    // The integral of s' over [0, 1] is 1 (Simpson, 1000 panels, exact for the quintic's
    // quartic velocity up to rounding).
    for profile in [Profile::Quintic, Profile::Cycloidal] {
        let n = 1000;
        let h = 1.0 / n as f64;
        let sum: f64 = (0..=n)
            .map(|k| {
                let w = if k == 0 || k == n {
                    1.0
                } else if k % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                w * profile.evaluate(k as f64 * h).1
            })
            .sum();
        assert!((sum * h / 3.0 - 1.0).abs() < 1e-10);
    }
}

/// The trait is object-safe and boxed trajectories work where `&dyn Trajectory` is expected.
#[test]
fn trajectories_are_object_safe() {
    let list: Vec<Box<dyn Trajectory + Send + Sync>> = vec![
        Box::new(Circle::paper(20.0).unwrap()),
        Box::new(Line::new(Pose::default(), Vector3::new(0.1, 0.0, 0.0), 0.0).unwrap()),
        Box::new(
            PointToPoint::new(
                Pose::default(),
                Pose::new(0.01, 0.0, 0.1),
                0.0,
                0.5,
                Profile::Quintic,
            )
            .unwrap(),
        ),
        Box::new(
            WaypointSpline::new(&[(0.0, Pose::default()), (1.0, Pose::new(0.01, 0.01, 0.0))])
                .unwrap(),
        ),
    ];
    let durations: Vec<Option<f64>> = list.iter().map(|t| t.duration()).collect();
    assert_eq!(durations[0], None);
    assert_eq!(durations[1], None);
    assert!((durations[2].unwrap() - 0.5).abs() < 1e-15);
    assert!((durations[3].unwrap() - 1.0).abs() < 1e-15);
    let geometry = flexprr_kinematics::Geometry::paper();
    // The small moves around the type-II singular home pose are rejected by validation.
    let err = flexprr_kinematics::validate_trajectory(&geometry, list[3].as_ref(), 0.0, 1.0, 11)
        .unwrap_err();
    assert!(matches!(
        err.innermost(),
        flexprr_kinematics::KinematicsError::Singular { .. }
    ));
    assert!(flexprr_kinematics::validate_trajectory(&geometry, &list[0], 0.0, 0.05, 101).is_ok());
}

/// Invalid trajectory parameters are errors, not panics.
#[test]
fn invalid_trajectories_are_rejected() {
    assert!(Circle::new(Point2::new(0.0, 0.0), -1.0, 1.0, 0.0, 0.0).is_err());
    assert!(Circle::paper(f64::NAN).is_err());
    assert!(
        PointToPoint::new(
            Pose::default(),
            Pose::default(),
            0.0,
            0.0,
            Profile::Cycloidal
        )
        .is_err()
    );
    assert!(WaypointSpline::new(&[(0.0, Pose::default())]).is_err());
    assert!(WaypointSpline::new(&[(0.0, Pose::default()), (0.0, Pose::default())]).is_err());
    assert!(Line::new(Pose::new(f64::INFINITY, 0.0, 0.0), Vector3::zeros(), 0.0).is_err());
}
