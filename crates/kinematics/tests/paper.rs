//! The paper's machine and trajectory (model.md sections 1-2).

// Legs and axes are indexed in parallel across several arrays.
#![allow(clippy::needless_range_loop)]

use std::f64::consts::{PI, TAU};

use flexprr_kinematics::{
    Circle, Geometry, KinematicsError, PlatformMotion, Pose, SingularityKind, Trajectory,
    validate_trajectory,
};
use nalgebra::Vector2;

fn paper_geometry() -> Geometry {
    Geometry::radial(
        [150f64.to_radians(), 270f64.to_radians(), 30f64.to_radians()],
        0.2,
        0.1,
        0.2,
    )
    .unwrap()
}

/// The circle at 20 Hz stays inside the +-0.2 m travel and away from both singularity
/// thresholds over a whole period, and every sample closes.
#[test]
fn paper_circle_at_20_hz_is_feasible() {
    let geometry = paper_geometry();
    let f = 20.0;
    let circle = Circle::paper(f).unwrap();
    let samples = 2001;
    let report = validate_trajectory(&geometry, &circle, 0.0, 1.0 / f, samples).unwrap();
    assert_eq!(report.samples, samples);
    assert!(report.min_travel_margin > 0.0);
    for (i, (lo, hi)) in report.rho_range.iter().enumerate() {
        assert!(
            *lo >= -0.2 && *hi <= 0.2,
            "leg {}: rho in [{lo}, {hi}]",
            i + 1
        );
    }
    for m in report.min_type_i {
        assert!(m > geometry.thresholds.type_i, "type-I measure {m}");
    }
    assert!(report.min_type_ii > geometry.thresholds.type_ii);

    // Independent checks at every sample: the trajectory formula of the paper, closure and
    // the slider speed bound |rho'| <= |C'| / |e.u| (from rho' = e.C' / e.u).
    for k in 0..samples {
        let t = k as f64 / (f * (samples - 1) as f64);
        let m = circle.motion(t);
        let w = TAU * f * t;
        assert!((m.pose.x - (0.05 * w.cos() - 0.05)).abs() < 1e-15);
        assert!((m.pose.y - 0.05 * w.sin()).abs() < 1e-15);
        assert!((m.pose.phi - PI / 4.0).abs() < 1e-15);
        let state = geometry.inverse_kinematics(&m).unwrap();
        for (i, leg) in state.legs.iter().enumerate() {
            assert!((((leg.c - leg.b).norm()) - 0.2).abs() < 1e-12 * 0.2);
            let e_dot_u = leg.e.dot(&geometry.legs[i].guide.direction);
            // Platform speed 2 pi f R = 2 pi m/s at constant orientation: |C'| is that speed.
            assert!((leg.c_dot.norm() - TAU * f * 0.05).abs() < 1e-12);
            // ... and C_i runs on a circle too: centripetal acceleration (2 pi f)^2 R.
            assert!((leg.c_ddot.norm() - (TAU * f).powi(2) * 0.05).abs() < 1e-9);
            assert!(leg.rho_dot.abs() <= leg.c_dot.norm() / e_dot_u.abs() * (1.0 + 1e-12));
        }
    }
}

/// At the radial home pose the sliders are at the guide centres, the links lie along their
/// guides (e.u = 1), and the three link lines meet at the platform centre: type II.
#[test]
fn radial_home_pose_is_type_ii_singular() {
    let geometry = paper_geometry();
    let home = Pose::new(0.0, 0.0, 0.0);
    let legs = geometry.inverse_position(&home).unwrap();
    for (i, leg) in legs.iter().enumerate() {
        assert!(leg.rho.abs() < 1e-15, "leg {}: rho = {}", i + 1, leg.rho);
        let u = geometry.legs[i].guide.direction.into_inner();
        assert!((leg.e - u).norm() < 1e-15);
        // The link line passes through the platform centre.
        assert!(leg.c.coords.perp(&leg.e).abs() < 1e-16);
    }
    let measures = geometry.singularity(&home).unwrap();
    assert!(measures.type_ii < 1e-12);
    assert!(measures.type_i.iter().all(|m| (m - 1.0).abs() < 1e-15));
    match geometry.inverse_kinematics(&PlatformMotion::at_rest(home)) {
        Err(
            err @ KinematicsError::Singular {
                kind: SingularityKind::TypeII,
                leg: None,
                ..
            },
        ) => {
            let msg = err.to_string();
            assert!(msg.contains("type-II") && !msg.contains('\n'), "{msg}");
        }
        other => panic!("expected type-II singularity, got {other:?}"),
    }
    // The paper's 45 degrees keeps it well away.
    assert!(
        geometry
            .singularity(&Pose::new(0.0, 0.0, PI / 4.0))
            .unwrap()
            .type_ii
            > 0.5
    );
}

/// Radial layout geometry (model.md section 1): c_i on a circle of radius s / sqrt(3),
/// A_i at distance R_p + l from the origin, opposite to u_i.
#[test]
fn radial_layout_matches_model() {
    let g = paper_geometry();
    let rp = 0.1 / 3f64.sqrt();
    for (i, a) in [150f64, 270.0, 30.0].iter().enumerate() {
        let u = Vector2::new(a.to_radians().cos(), a.to_radians().sin());
        let leg = &g.legs[i];
        assert!((leg.guide.direction.into_inner() - u).norm() < 1e-15);
        assert!((leg.attachment + rp * u).norm() < 1e-15);
        assert!((leg.guide.anchor.coords + (rp + 0.2) * u).norm() < 1e-15);
        assert!(
            (leg.guide.travel.0 + 0.2).abs() < 1e-15 && (leg.guide.travel.1 - 0.2).abs() < 1e-15
        );
    }
    // Equilateral platform of side 0.1 m.
    for (i, j) in [(0, 1), (1, 2), (2, 0)] {
        assert!(((g.legs[i].attachment - g.legs[j].attachment).norm() - 0.1).abs() < 1e-15);
    }
    assert!((g.platform_radius() - rp).abs() < 1e-15);
}

/// Three-fold symmetry of the radial layout: rotating a pose by 120 deg about the origin
/// at the same orientation moves leg i's state to leg i+1 (alpha_i + 120 deg = alpha_{i+1}):
/// the equilateral platform turned by 120 deg carries c_i onto c_{i+1}.
#[test]
fn radial_layout_is_three_fold_symmetric() {
    let g = paper_geometry();
    let turn = 120f64.to_radians();
    let (s, c) = turn.sin_cos();
    for k in 0..50 {
        let t = k as f64 / 50.0;
        let pose = Pose::new(
            0.06 * (7.0 * t).sin() - 0.02,
            0.05 * (3.0 * t).cos(),
            0.3 + 0.5 * t,
        );
        let turned = Pose::new(c * pose.x - s * pose.y, s * pose.x + c * pose.y, pose.phi);
        let a = g.inverse_position(&pose).unwrap();
        let b = g.inverse_position(&turned).unwrap();
        for i in 0..3 {
            let j = (i + 1) % 3;
            assert!(
                (a[i].rho - b[j].rho).abs() < 1e-14,
                "rho {} vs {}",
                a[i].rho,
                b[j].rho
            );
            let dbeta = (b[j].beta - a[i].beta - turn).rem_euclid(TAU);
            assert!(dbeta.min(TAU - dbeta) < 1e-13);
        }
    }
}

/// A circle too large for the travel: validate_trajectory names the leg and the time, and
/// the IK at that time fails the same way while the sample before passes.
#[test]
fn validation_reports_time_of_first_failure() {
    let g = paper_geometry();
    let circle = Circle::new(nalgebra::Point2::new(0.1, 0.0), 0.15, 1.0, PI / 4.0, PI).unwrap();
    let samples = 1001;
    let err = validate_trajectory(&g, &circle, 0.0, 1.0, samples).unwrap_err();
    let KinematicsError::AtTime { t, error } = &err else {
        panic!("expected AtTime, got {err:?}");
    };
    let msg = err.to_string();
    assert!(
        msg.starts_with("at t = ") && msg.contains("leg ") && !msg.contains('\n'),
        "{msg}"
    );
    let direct = g.inverse_kinematics(&circle.motion(*t)).unwrap_err();
    assert_eq!(&direct, error.as_ref());
    assert_eq!(err.innermost(), &direct);
    let dt = 1.0 / (samples - 1) as f64;
    assert!(*t > 0.0, "the start pose is feasible");
    assert!(g.inverse_kinematics(&circle.motion(t - dt)).is_ok());
}

/// Bad input never panics or returns NaN.
#[test]
fn non_finite_input_is_rejected() {
    let g = paper_geometry();
    let bad = PlatformMotion::at_rest(Pose::new(f64::NAN, 0.0, 0.0));
    assert!(matches!(
        g.inverse_kinematics(&bad),
        Err(KinematicsError::NonFinite { .. })
    ));
    assert!(matches!(
        g.inverse_kinematics_unchecked(&bad),
        Err(KinematicsError::NonFinite { .. })
    ));
    let mut fast = PlatformMotion::at_rest(Pose::new(0.0, 0.0, 0.5));
    fast.velocity.x = f64::INFINITY;
    assert!(matches!(
        g.inverse_kinematics_unchecked(&fast),
        Err(KinematicsError::NonFinite { .. })
    ));
    assert!(matches!(
        g.forward_kinematics([f64::NAN, 0.0, 0.0], &Pose::default()),
        Err(KinematicsError::NonFinite { .. })
    ));
    assert!(validate_trajectory(&g, &Circle::paper(20.0).unwrap(), 0.0, 1.0, 1).is_err());
}

/// Geometry validation names the leg and the quantity.
#[test]
fn invalid_geometry_is_rejected() {
    let g = paper_geometry();
    let mut legs = g.legs;
    legs[1].link_length = -0.2;
    let err = Geometry::new(legs).unwrap_err();
    assert!(matches!(
        err,
        KinematicsError::InvalidGeometry {
            leg: Some(1),
            quantity: "link length",
            ..
        }
    ));
    assert!(err.to_string().starts_with("leg 2: "), "{err}");
    let mut legs = g.legs;
    legs[2].guide.travel = (0.1, -0.1);
    assert!(matches!(
        Geometry::new(legs),
        Err(KinematicsError::InvalidGeometry { leg: Some(2), .. })
    ));
    let mut legs = g.legs;
    legs[0].guide.anchor.x = f64::NAN;
    assert!(matches!(
        Geometry::new(legs),
        Err(KinematicsError::InvalidGeometry { leg: Some(0), .. })
    ));
    let mut legs = g.legs;
    for leg in &mut legs {
        leg.attachment = Vector2::new(0.01, 0.02);
    }
    assert!(matches!(
        Geometry::new(legs),
        Err(KinematicsError::InvalidGeometry { leg: None, .. })
    ));
    assert!(Geometry::radial([0.0, 1.0, 2.0], 0.2, -0.1, 0.2).is_err());
    assert!(
        g.with_thresholds(flexprr_kinematics::Thresholds {
            type_i: f64::NAN,
            type_ii: 0.1
        })
        .is_err()
    );
}
