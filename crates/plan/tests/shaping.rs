//! Vibration-aware planning on the machine, measured by the scene's flexible model: a
//! ZVD-shaped time-optimal pick-and-place move leaves a small fraction of the unshaped move's
//! residual vibration (both runs of the coupled model), the shaper is designed for the
//! machine's lowest mode (the paper's link frequency, Table I: 116.4 Hz), and the shaped
//! move is longer by the ZVD shaper's length `1 / f_d`.

use flexprr_plan::{Options, plan_scene};
use flexprr_scene::Scene;

#[test]
fn shaped_move_leaves_a_small_fraction_of_the_unshaped_residual_vibration() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../configs/plan_pick_and_place.toml");
    let scene = Scene::load(&path).unwrap();
    let outcome = plan_scene(&scene, Options::default(), &mut |_| {}).unwrap();
    let design = outcome.shaping.as_ref().unwrap();
    let mode = &design.modes[0];
    // Table I of the paper: the link's first frequency at rest, 116.4 Hz; along this path
    // the machine's lowest mode stays within 0.1 % of its middle.
    assert!(
        (mode.design_hz - 116.4).abs() / 116.4 < 0.005,
        "{}",
        mode.design_hz
    );
    assert!(mode.half_width < 1e-3);
    // ZVD adds two half periods of the damped mode.
    let unshaped = outcome.unshaped.as_ref().unwrap();
    let extra = outcome.plan.duration - unshaped.duration;
    let expected = 1.0 / (mode.design_hz * (1.0 - mode.damping * mode.damping).sqrt());
    assert!(
        (extra - expected).abs() / expected < 2e-3,
        "{extra} {expected}"
    );
    // The flexible model's residual vibration, 50 ms after each move.
    let flexible = outcome.flexible.as_ref().unwrap();
    assert!((flexible.settle_time - 0.05).abs() < 1e-12);
    let shaped = flexible.planned.residual.unwrap();
    let bare = flexible.unshaped.as_ref().unwrap().residual.unwrap();
    assert!(
        bare > 1e-4,
        "the unshaped time-optimal move rings: {bare} m"
    );
    assert!(shaped < 0.05 * bare, "shaped {shaped} m, unshaped {bare} m");
    // The check ran the move to its end and past it.
    let end = flexible.planned.move_end.unwrap();
    assert!((end - outcome.plan.duration).abs() < 1e-12);
    assert!(flexible.planned.t.last().unwrap() + 1e-9 >= end + 0.05);
}
