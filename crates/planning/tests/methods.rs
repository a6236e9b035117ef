//! TOPP-RA against phase-plane integration (two independent methods on the same rows), grid
//! convergence, and the checked plan never faster than the optimum.

mod common;

use flexprr_kinematics::{Path, Pose, SplinePath, WaypointSpline};
use flexprr_planning::{
    Boundary, Buckling, Efficiency, MotorSpeed, MotorTorque, Planner, Settings, SliderAcceleration,
    SliderForce, SliderSpeed,
};

fn spline() -> SplinePath {
    let d = |deg: f64| deg.to_radians();
    let points = [
        (0.0, Pose::new(-0.08, -0.03, d(30.0))),
        (0.04, Pose::new(-0.05, 0.02, d(40.0))),
        (0.1, Pose::new(-0.02, 0.033, d(20.0))),
    ];
    SplinePath::new(&WaypointSpline::new(&points).unwrap()).unwrap()
}

/// Plans `path` both ways and returns (checked TOPP-RA, raw TOPP-RA at 4000, phase plane).
fn both(planner: &Planner<'_>) -> (f64, f64, f64) {
    let plan = planner.plan().unwrap();
    assert!(
        plan.check.max_usage <= 1.0 + 1e-9,
        "{:?}",
        plan.check.worst()
    );
    let raw = planner.solve_uniform(4000).unwrap().duration;
    let pp = planner.phase_plane(20_000).unwrap().duration;
    (plan.duration, raw, pp)
}

#[test]
fn topp_ra_and_the_phase_plane_agree_on_the_paper_machine() {
    let machine = common::machine();
    let circle = common::circle();
    let segment = common::pick_and_place();
    let spline = spline();
    let paths: [(&str, &dyn Path, Boundary); 4] = [
        ("circle periodic", &circle, Boundary::Periodic),
        ("circle rest", &circle, Boundary::RestToRest),
        ("pick and place", &segment, Boundary::RestToRest),
        ("spline", &spline, Boundary::RestToRest),
    ];
    for (name, path, boundary) in paths {
        let settings = Settings {
            boundary,
            ..Settings::default()
        };
        let sets: Vec<Planner<'_>> = vec![
            Planner::new(&machine, path, settings)
                .constraint(SliderSpeed::new(1.0).unwrap())
                .constraint(SliderForce::new(400.0).unwrap()),
            Planner::new(&machine, path, settings)
                .constraint(SliderSpeed::new(2.0).unwrap())
                .constraint(SliderAcceleration::new(300.0).unwrap())
                .constraint(SliderForce::new(150.0).unwrap()),
            Planner::new(&machine, path, settings)
                .constraint(MotorTorque::new(common::motor(), Efficiency::PowerFlow).unwrap())
                .constraint(MotorSpeed::new(&common::motor()))
                .constraint(Buckling::new(&machine, 0.5).unwrap()),
            // Viscous friction with no speed limit: the chords of the helpful side need the
            // maximum velocity curve.
            Planner::new(&machine, path, settings)
                .constraint(MotorTorque::new(common::motor(), Efficiency::Symmetric).unwrap()),
        ];
        for (k, planner) in sets.iter().enumerate() {
            let (checked, raw, pp) = both(planner);
            println!("{name} set {k}: checked {checked:.9} raw(4000) {raw:.9} phase plane {pp:.9}");
            // Independent methods agree: the checked plan on 1000 intervals to 1e-3 relative,
            // raw TOPP-RA on 4000 intervals to 2e-4 (first-order convergence where a
            // friction term or an acceleration limit binds on an arc, second order where a
            // speed limit binds: docs/planning.md, "Convergence").
            assert!(
                (checked - pp).abs() <= 1e-3 * pp,
                "{name} set {k}: {checked} vs {pp}"
            );
            assert!(
                (raw - pp).abs() <= 2e-4 * pp,
                "{name} set {k}: {raw} vs {pp}"
            );
            // The checked motion keeps every limit, so it is not faster than the optimum (up
            // to the phase plane's own integration error).
            assert!(
                checked >= pp * (1.0 - 1e-6),
                "{name} set {k}: {checked} < {pp}"
            );
        }
    }
}

#[test]
fn the_duration_converges_with_the_grid() {
    let machine = common::machine();
    let segment = common::pick_and_place();
    let planner = Planner::new(&machine, &segment, Settings::default())
        .constraint(SliderSpeed::new(1.0).unwrap())
        .constraint(SliderForce::new(400.0).unwrap());
    let reference = planner.phase_plane(100_000).unwrap().duration;
    let errors: Vec<f64> = [125, 250, 500, 1000, 2000]
        .iter()
        .map(|&n| (planner.solve_uniform(n).unwrap().duration - reference).abs())
        .collect();
    println!("errors {errors:?}");
    for w in errors.windows(2) {
        let order = (w[0] / w[1]).log2();
        assert!(order > 0.9, "order {order}: {errors:?}");
    }
    let plan = planner.plan().unwrap();
    let convergence = plan.convergence.unwrap();
    println!("{convergence:?}");
    assert!(convergence.order > 0.9, "{convergence:?}");
}
