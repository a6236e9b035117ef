//! `[plan] deflection_limit`: the time-optimal pick-and-place move slowed until the coupled
//! flexible model keeps the links within the limit. Checked by an independent re-run of the
//! written planned scene (its TOML text, a finer output step), by the time-scaling law of a
//! uniformly slowed timing, by the bracket the search reports (a probe within the tolerance
//! below the answer breaks the limit) and by the rigid limits, which still hold.

use flexprr_plan::{
    Options, PlanError, STRETCH_TOLERANCE, peak_deflection, plan_scene, scene_toml,
};
use flexprr_scene::{OutputKind, Scene};

fn scene(plan_extra: &str) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../configs/plan_pick_and_place.toml");
    let text = std::fs::read_to_string(path)
        .unwrap()
        .replace("shaping = \"zvd\"", "shaping = \"none\"");
    Scene::from_text("test.toml", "test", &format!("{text}{plan_extra}\n")).unwrap()
}

/// The planned scene re-run from its TOML text at a fifth of its output step: the largest
/// `|w|` of any link, and the largest slider speed.
fn rerun(outcome: &flexprr_plan::PlanOutcome) -> (f64, f64) {
    let mut file = outcome.planned_file.clone();
    file.time.output_step = Some(2e-5);
    file.output.requests = vec![OutputKind::Kinematics, OutputKind::Deflections];
    file.output.plots = false;
    let text = scene_toml(&file, "planned").unwrap();
    let planned = Scene::from_text("planned.toml", "planned", &text).unwrap();
    let result = flexprr_run::run(&planned, &mut |_| {}).unwrap();
    let speed = result
        .table("kinematics")
        .unwrap()
        .columns
        .iter()
        .zip(&result.table("kinematics").unwrap().data)
        .filter(|(c, _)| c.header().starts_with("rho_dot_"))
        .flat_map(|(_, d)| d.iter())
        .fold(0.0f64, |m, v| m.max(v.abs()));
    (peak_deflection(&result), speed)
}

#[test]
fn a_deflection_limit_slows_the_move_until_the_flexible_model_meets_it() {
    let fastest = plan_scene(&scene(""), Options::default(), &mut |_| {}).unwrap();
    let fastest_peak = peak_deflection(&fastest.flexible.as_ref().unwrap().planned_run);
    assert!(fastest_peak > 0.0);

    // A limit above the time-optimal motion's peak leaves the plan as it is.
    let loose = plan_scene(
        &scene(&format!("deflection_limit = {}", 2.0 * fastest_peak)),
        Options::default(),
        &mut |_| {},
    )
    .unwrap();
    let search = loose.deflection.as_ref().unwrap();
    assert!(!search.binds());
    assert_eq!(
        loose.plan.duration.to_bits(),
        fastest.plan.duration.to_bits()
    );

    // Half the peak: the move is slowed.
    let limit = 0.5 * fastest_peak;
    let slowed = plan_scene(
        &scene(&format!("deflection_limit = {limit}")),
        Options::default(),
        &mut |_| {},
    )
    .unwrap();
    let search = slowed.deflection.as_ref().unwrap();
    assert!(search.binds(), "{search:?}");
    let k = search.stretch;
    assert!(k > 1.0 && k < 8.0, "stretch {k}");
    // A uniformly slowed timing lasts k times longer (no shaper, no smoothing here).
    let expected = k * fastest.plan.timing.duration();
    assert!(
        (slowed.plan.duration - expected).abs() <= 1e-9 * expected,
        "{} against {expected}",
        slowed.plan.duration
    );
    // The bracket is real: a probe no more than the tolerance below breaks the limit.
    assert!(search.probes.iter().any(|p| {
        p.stretch < k
            && p.stretch >= k / (1.0 + STRETCH_TOLERANCE) * (1.0 - 1e-12)
            && p.peak.as_ref().is_ok_and(|w| *w > limit)
    }));
    // The delivered plan meets the limit on the search's run and on an independent re-run
    // of the written scene at a finer output step (1 % for the integration's own error).
    assert!(search.peak <= limit, "{} > {limit}", search.peak);
    let (peak, speed) = rerun(&slowed);
    assert!(peak <= 1.01 * limit, "re-run peak {peak} over {limit}");
    // The rigid limits still hold (1 m/s on every slider).
    assert!(speed <= 1.0 + 1e-3, "slider speed {speed}");
    assert!(slowed.plan.check.max_usage <= 1.0 + 1e-9);
}

#[test]
fn a_deflection_limit_needs_the_flexible_model_and_a_positive_value() {
    let err = plan_scene(
        &scene("deflection_limit = 1e-4"),
        Options {
            flexible_check: false,
        },
        &mut |_| {},
    )
    .unwrap_err();
    assert!(matches!(err, PlanError::DeflectionLimit { .. }), "{err}");
    assert!(err.to_string().contains("--no-flexible-check"), "{err}");

    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../configs/plan_pick_and_place.toml");
    let text = std::fs::read_to_string(path).unwrap();
    let err = Scene::from_text(
        "bad.toml",
        "bad",
        &format!("{text}deflection_limit = -1e-4\n"),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("plan.deflection_limit"), "{err}");
    assert!(err.contains("bad.toml:"), "{err}");
}
