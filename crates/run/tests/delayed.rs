//! A motion that starts after `time.start` used to be stepped over by every integrator: the
//! forcing is exactly zero at first, so the error estimate is zero and the step grew past the
//! whole move (peak deflection exactly 0 m, exit 0). The run layer now stops every
//! integration at the trajectory's breakpoints. Each trajectory kind, delayed, with each
//! integrator must match the same scene integrated with a small `max_step` (which cannot step
//! over anything) to 1e-3 relative in the peak mid-point deflection of every link.

use flexprr_run::run;
use flexprr_scene::Scene;

const METHODS: [&str; 6] = ["abm", "rk45", "bdf", "magnus4", "magnus6", "auto"];

fn scene(trajectory: &str, method: &str, max_step: Option<f64>) -> Scene {
    let max_step = max_step.map_or(String::new(), |h| format!("max_step = {h:e}"));
    let text = format!(
        r#"
name = "delayed"
[links]
modes = 3
{trajectory}
[model]
formulation = "consistent"
damping = [0.01]
[integrator]
method = "{method}"
rtol = 1e-8
atol = 1e-12
{max_step}
[time]
end = 0.2
output_step = 1e-4
[output]
requests = ["deflections"]
plots = false
"#
    );
    Scene::from_text("delayed.toml", "delayed", &text).expect("valid scene")
}

/// Peak |w| at mid-span of each link.
fn peaks(scene: &Scene) -> [f64; 3] {
    let result = run(scene, &mut |_| {}).unwrap_or_else(|f| panic!("run failed: {f}"));
    let table = result.table("deflections").expect("requested");
    std::array::from_fn(|i| {
        table
            .column(&format!("w_{}_xi0.5_m", i + 1))
            .expect("column")
            .iter()
            .fold(0.0_f64, |m, w| m.max(w.abs()))
    })
}

fn check(kind: &str, trajectory: &str) {
    let reference = peaks(&scene(trajectory, "abm", Some(2e-5)));
    assert!(
        reference.iter().all(|w| *w > 1e-5),
        "{kind}: the reference must vibrate: {reference:?}"
    );
    for method in METHODS {
        let got = peaks(&scene(trajectory, method, None));
        for i in 0..3 {
            let rel = (got[i] - reference[i]).abs() / reference[i];
            assert!(
                rel < 1e-3,
                "{kind} with {method}: link {} peak {:.6e} m vs {:.6e} m with max_step (rel {rel:.2e})",
                i + 1,
                got[i],
                reference[i]
            );
        }
    }
}

#[test]
fn delayed_quintic_move_is_not_stepped_over() {
    check(
        "point-to-point quintic",
        r#"[trajectory]
kind = "point-to-point"
from = [-0.08, -0.03, 30.0]
to = [-0.02, 0.033, 30.0]
start = 0.05
duration = 0.02
profile = "quintic""#,
    );
}

#[test]
fn delayed_cycloidal_move_is_not_stepped_over() {
    check(
        "point-to-point cycloidal",
        r#"[trajectory]
kind = "point-to-point"
from = [-0.08, -0.03, 30.0]
to = [-0.02, 0.033, 30.0]
start = 0.05
duration = 0.02
profile = "cycloidal""#,
    );
}

#[test]
fn waypoint_path_with_a_late_first_knot_is_not_stepped_over() {
    check(
        "waypoints",
        r#"[trajectory]
kind = "waypoints"
points = [[0.06, -0.08, -0.03, 30.0], [0.08, -0.05, 0.0, 30.0], [0.1, -0.02, 0.033, 30.0]]"#,
    );
}

/// The scene's own `time.stops` were validated and then never passed to the integrator
/// (issue 34): they are stop times of every run now, beside the trajectory's breakpoints.
#[test]
fn the_scenes_own_stop_times_stop_the_integration() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../configs/paper_f20.toml"
    ))
    .unwrap()
    .replace("end = 0.2", "end = 0.2\nstops = [0.0125, 0.05]");
    let scene = Scene::from_text("stops.toml", "stops", &text).unwrap();
    let stops = flexprr_run::stop_times(&scene);
    assert_eq!(stops.len(), 2, "{stops:?}");
    assert!((stops[0] - 0.0125).abs() < 1e-15 && (stops[1] - 0.05).abs() < 1e-15);
}
