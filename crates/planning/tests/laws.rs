//! Laws the minimum time obeys, over random paths and limits (proptest).

mod common;

use flexprr_kinematics::{Pose, SegmentPath};
use flexprr_planning::{Planner, Settings, SliderAcceleration, SliderForce, SliderSpeed};
use proptest::prelude::*;

fn settings() -> Settings {
    Settings {
        grid: 200,
        convergence: false,
        ..Settings::default()
    }
}

fn segment(x0: f64, y0: f64, dx: f64, dy: f64, phi: f64) -> SegmentPath {
    SegmentPath::new(Pose::new(x0, y0, phi), Pose::new(x0 + dx, y0 + dy, phi)).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    /// Time scaling: with speed limits times c, acceleration and rigid-force limits (no
    /// friction, horizontal plane) times c^2, the same path takes 1/c of the time, on the same
    /// grid exactly (the rows scale, the solution scales).
    #[test]
    fn minimum_time_scales_with_the_limits(
        x0 in -0.07f64..-0.03, y0 in -0.03f64..0.0, dx in 0.01f64..0.04, dy in 0.01f64..0.04,
        phi in 0.2f64..0.7, c in 0.3f64..3.0,
    ) {
        let machine = common::machine();
        let path = segment(x0, y0, dx, dy, phi);
        let time = |c: f64| {
            Planner::new(&machine, &path, settings())
                .constraint(SliderSpeed::new(c * 1.0).unwrap())
                .constraint(SliderAcceleration::new(c * c * 200.0).unwrap())
                .constraint(SliderForce::new(c * c * 150.0).unwrap())
                .solve_uniform(200)
                .unwrap()
                .duration
        };
        let (t1, tc) = (time(1.0), time(c));
        prop_assert!((tc * c - t1).abs() <= 1e-9 * t1, "{} vs {}", tc * c, t1);
    }

    /// A tighter limit never makes the checked motion faster, and the motion keeps it.
    #[test]
    fn tighter_limits_are_never_faster(
        x0 in -0.07f64..-0.03, y0 in -0.03f64..0.0, dx in 0.01f64..0.04, dy in 0.01f64..0.04,
        phi in 0.2f64..0.7, shrink in 0.3f64..1.0,
    ) {
        let machine = common::machine();
        let path = segment(x0, y0, dx, dy, phi);
        let plan = |force: f64| {
            Planner::new(&machine, &path, settings())
                .constraint(SliderSpeed::new(1.0).unwrap())
                .constraint(SliderForce::new(force).unwrap())
                .plan()
                .unwrap()
        };
        let (loose, tight) = (plan(300.0), plan(300.0 * shrink));
        prop_assert!(tight.duration >= loose.duration * (1.0 - 1e-9));
        prop_assert!(tight.check.max_usage <= 1.0 + 1e-9);
        prop_assert!(loose.check.max_usage <= 1.0 + 1e-9);
    }
}
