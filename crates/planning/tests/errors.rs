//! Bad input gets an error that names the key or the limit and the place on the path.

mod common;

use flexprr_control::{MotorBallScrew, MotorRatings};
use flexprr_kinematics::{Pose, SegmentPath};
use flexprr_planning::{
    Boundary, Efficiency, MotorTorque, PlanSpec, Planner, PlanningError, Settings, SliderForce,
    SliderSpeed,
};

#[test]
fn a_path_that_leaves_the_workspace_says_where() {
    let machine = common::machine();
    // Through the singular home pose (0, 0, 0): the link lines meet at the platform centre.
    let through_home =
        SegmentPath::new(Pose::new(-0.05, 0.0, 0.0), Pose::new(0.05, 0.0, 0.0)).unwrap();
    let planner = Planner::new(&machine, &through_home, Settings::default())
        .constraint(SliderSpeed::new(1.0).unwrap());
    let error = planner.plan().unwrap_err();
    let text = error.to_string();
    assert!(matches!(error, PlanningError::Workspace { .. }), "{text}");
    assert!(
        text.contains("leaves the workspace at s = ") && text.contains("type-II"),
        "{text}"
    );
    // Far outside the reach of the links.
    let far = SegmentPath::new(Pose::new(0.0, 0.05, 0.3), Pose::new(0.0, 0.6, 0.3)).unwrap();
    let error = Planner::new(&machine, &far, Settings::default())
        .constraint(SliderSpeed::new(1.0).unwrap())
        .plan()
        .unwrap_err();
    let text = error.to_string();
    assert!(
        text.contains("leaves the workspace") && text.contains("pose x ="),
        "{text}"
    );
}

#[test]
fn a_limit_no_motion_can_meet_is_named_with_its_place() {
    let machine = common::machine();
    let path = common::pick_and_place();
    // Coulomb friction above the peak torque: broken at rest.
    let motor = MotorBallScrew {
        rotor_inertia: 1e-5,
        lead: 0.01,
        efficiency: 0.9,
        ratings: MotorRatings {
            peak_torque: 0.5,
            continuous_torque: 0.2,
            max_speed: 100.0,
        },
        viscous_friction: 0.0,
        coulomb_friction: 0.6,
        coulomb_smoothing: 0.01,
        drive: None,
        friction_feedforward: false,
        screw: None,
        lugre: None,
    };
    let error = Planner::new(&machine, &path, Settings::default())
        .constraint(MotorTorque::new(motor, Efficiency::Symmetric).unwrap())
        .plan()
        .unwrap_err();
    let text = error.to_string();
    assert!(
        text.contains("no motion can meet motor_torque (leg ")
            && text.contains("broken with the machine at rest")
            && text.contains("at s = 0.000000"),
        "{text}"
    );
}

#[test]
fn a_periodic_plan_on_an_open_path_is_refused() {
    let machine = common::machine();
    let path = common::pick_and_place();
    let planner = Planner::new(
        &machine,
        &path,
        Settings {
            boundary: Boundary::Periodic,
            ..Settings::default()
        },
    )
    .constraint(SliderSpeed::new(1.0).unwrap());
    for error in [
        planner.plan().unwrap_err(),
        planner.constant_speed().unwrap_err(),
    ] {
        assert_eq!(error, PlanningError::OpenPath);
        assert!(error.to_string().contains("rest_to_rest"));
    }
}

#[test]
fn no_limit_or_an_unbounded_speed_is_an_error() {
    let machine = common::machine();
    let path = common::pick_and_place();
    let error = Planner::new(&machine, &path, Settings::default())
        .plan()
        .unwrap_err();
    assert!(error.to_string().contains("plan.limits"), "{error}");
    // A force limit alone bounds accelerations, and the speed through the path's curvature
    // terms; a straight line at constant phi still has the links' centripetal terms, so it is
    // bounded: the plan exists.
    let plan = Planner::new(&machine, &path, Settings::default())
        .constraint(SliderForce::new(100.0).unwrap())
        .plan();
    assert!(plan.is_ok(), "{plan:?}");
}

#[test]
fn spec_values_and_keys_are_checked() {
    for (text, key) in [
        ("slider_speed = -1.0", "plan.slider_speed"),
        ("slider_force = 0.0", "plan.slider_force"),
        ("buckling_margin = 1.5", "plan.buckling_margin"),
        ("grid = 1", "plan.grid"),
        (
            "shaping = \"zv\"\nboundary = \"periodic\"\nslider_speed = 1.0",
            "plan.shaping",
        ),
    ] {
        let spec: PlanSpec = toml::from_str(text).unwrap();
        let error = spec.validate().unwrap_err();
        assert!(error.to_string().starts_with(key), "{text}: {error}");
    }
    let unknown = toml::from_str::<PlanSpec>("slider_sped = 1.0").unwrap_err();
    assert!(unknown.to_string().contains("slider_sped"), "{unknown}");
    let bad = toml::from_str::<PlanSpec>("boundary = \"cyclic\"").unwrap_err();
    assert!(bad.to_string().contains("cyclic"), "{bad}");
    // The example section.
    let spec: PlanSpec = toml::from_str(
        "objective = \"min_time\"\nboundary = \"rest_to_rest\"\nslider_speed = 1.0\nslider_force = 400.0\nshaping = \"none\"",
    )
    .unwrap();
    spec.validate().unwrap();
    let machine = common::machine();
    let constraints = spec.constraints(&machine, None).unwrap();
    let names: Vec<&str> = constraints.iter().map(|c| c.name()).collect();
    assert_eq!(names, ["slider_speed", "slider_force"]);
    let none = PlanSpec::default().constraints(&machine, None).unwrap_err();
    assert!(none.to_string().contains("plan.limits"), "{none}");
}
