//! The paper's machine (docs/planning.md, "The paper's machine"): the fastest 0.05 m circle
//! and the pick-and-place move of configs/pick_and_place.toml under slider_speed = 1 m/s and
//! slider_force = 400 N, against the scene's own timing of the same path.

mod common;

use flexprr_kinematics::{Path, PathState, Profile};
use flexprr_planning::{Boundary, Planner, Settings, SliderForce, SliderSpeed};

fn limits(planner: Planner<'_>) -> Planner<'_> {
    planner
        .constraint(SliderSpeed::new(1.0).unwrap())
        .constraint(SliderForce::new(400.0).unwrap())
}

#[test]
fn the_paper_circle_and_the_pick_and_place_move() {
    let machine = common::machine();
    let circle = common::circle();
    let periodic = limits(Planner::new(
        &machine,
        &circle,
        Settings {
            boundary: Boundary::Periodic,
            ..Settings::default()
        },
    ));
    let constant = periodic.constant_speed().unwrap();
    let optimal = periodic.plan().unwrap();
    let revolution = limits(Planner::new(&machine, &circle, Settings::default()))
        .plan()
        .unwrap();
    println!(
        "circle: constant speed {:.4} Hz ({} {}), time-optimal periodic {:.4} Hz (period {:.6} s), rest-to-rest revolution {:.6} s",
        constant.frequency,
        constant.constraint,
        constant.label,
        optimal.frequency().unwrap(),
        optimal.duration,
        revolution.duration
    );
    assert_eq!(constant.constraint, "slider_speed");
    assert!(optimal.frequency().unwrap() > constant.frequency);
    assert!(revolution.duration > optimal.duration);

    let segment = common::pick_and_place();
    let planner = limits(Planner::new(&machine, &segment, Settings::default()));
    let plan = planner.plan().unwrap();
    // The scene's own timing: a quintic over 0.1 s.
    let (length, scene_duration) = (segment.length(), 0.1);
    let quintic = |t: f64| {
        let (s, ds, dds) = Profile::Quintic.evaluate(t / scene_duration);
        PathState {
            s: length * s,
            s_dot: length * ds / scene_duration,
            s_ddot: length * dds / (scene_duration * scene_duration),
            s_dddot: 0.0,
        }
    };
    let scene = planner
        .check_timing(&[], (0.0, scene_duration), 10_000, quintic, None)
        .unwrap();
    let worst = scene.worst().unwrap();
    println!(
        "pick and place: time-optimal {:.6} s (binding {:?}), the scene's quintic 0.1 s uses {:.3} of {} ({})",
        plan.duration,
        plan.binding
            .iter()
            .map(|b| b.constraint.as_str())
            .collect::<Vec<_>>(),
        worst.usage,
        worst.constraint,
        worst.label
    );
    // The quintic at 0.1 s needs more slider speed than 1 m/s; the time-optimal motion is
    // both faster and within the limit.
    assert!(worst.usage > 1.0);
    assert!(plan.duration < scene_duration && plan.check.max_usage <= 1.0 + 1e-9);
}
