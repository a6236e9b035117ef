//! `method = "auto"` on the shipped paper scene: the scene resolves it to the exponential
//! method (the KED model is linear in its state), the run names that method, and the modal
//! state at t = 0.2 s matches the shared reference state of an independent implementation
//! (Python, DOP853 at rtol 1e-13: `tests/data/paper_f20_state_t0.2.json`).

use flexprr_run::run;
use flexprr_scene::Scene;

fn reference_eta() -> Vec<f64> {
    let text = include_str!("../../../tests/data/paper_f20_state_t0.2.json");
    let start = text.find("\"state\"").expect("state key");
    let open = start + text[start..].find('[').expect("[");
    let close = open + text[open..].find(']').expect("]");
    let state: Vec<f64> = text[open + 1..close]
        .split(',')
        .map(|v| v.trim().parse().expect("number"))
        .collect();
    assert_eq!(state.len(), 18);
    state[..9].to_vec()
}

fn paper_scene(method: &str) -> Scene {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../configs/paper_f20.toml");
    let text = std::fs::read_to_string(path).expect("configs/paper_f20.toml");
    assert!(text.contains("method = \"abm\""));
    let text = text
        .replacen("method = \"abm\"", &format!("method = \"{method}\""), 1)
        .replace(
            "compare_without_axial_force = true",
            "compare_without_axial_force = false",
        );
    Scene::from_text("paper_f20.toml", "paper_f20", &text).expect("valid scene")
}

#[test]
fn auto_runs_the_paper_scene_with_magnus6_and_matches_the_reference_state() {
    let scene = paper_scene("auto");
    assert_eq!(scene.method.name(), "magnus6");
    let result = run(&scene, &mut |_| {}).unwrap_or_else(|f| panic!("run failed: {f}"));
    let modes = result.table("modes").expect("modes requested");
    let want = reference_eta();
    let size = want.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    for link in 1..=3 {
        for mode in 1..=3 {
            let column = modes
                .column(&format!("eta_{link}_{mode}_m"))
                .expect("modal coordinate column");
            let got = *column.last().expect("rows");
            let w = want[3 * (link - 1) + (mode - 1)];
            let e = (got - w).abs() / size;
            // The scene's rtol is 1e-8; the reference is far tighter.
            assert!(
                e < 1e-6,
                "eta_{link}{mode} at 0.2 s: {got:e} vs reference {w:e} (relative {e:.2e})"
            );
        }
    }
}
