//! The viewer page of the paper scene in a real browser (headless Chromium).
//!
//! SYNTHETIC link series on the real machine and path (see `common/mod.rs`): they exercise
//! what the real paper scene does not have (a buckling interval, a platform deviation).
//! The viewer of the real paper run is tested in the workspace's `tests/cli/viewer_browser.rs`.
//! Needs the `chromium` binary (see `chromium/mod.rs`): without it the tests skip with one
//! line on stderr, unless `FLEXPRR_REQUIRE_BROWSER=1`.

mod chromium;
mod common;

use chromium::{
    changed_machine_pixels, check_instant, chromium, console_lines, expected_transform, f, report,
    run_chromium,
};

use flexprr_kinematics::Trajectory;
use flexprr_viewer::{ViewerOptions, frame_indices, viewer_html};
use serde_json::Value;

/// The page transform of `data`: its guides' travel ends and platform path.
fn data_transform(data: &flexprr_viewer::ViewerData) -> (f64, f64, f64) {
    let ends = data.guides.iter().flat_map(|g| {
        [g.travel.0, g.travel.1].map(|r| {
            [
                g.anchor[0] + r * g.direction[0],
                g.anchor[1] + r * g.direction[1],
            ]
        })
    });
    expected_transform(ends.chain(data.pose.iter().map(|p| [p[0], p[1]])))
}

/// Loads the paper scene's viewer in headless Chromium and checks: no console errors; the
/// frame and link counts; at t = 0 and t = 12.5 ms the drawn slider positions against the
/// inverse kinematics of `flexprr_kinematics` mapped through the page transform (itself
/// recomputed here), and the screenshot really shows a slider block there; the two
/// screenshots differ in the machine drawing; the buckling interval is announced.
#[test]
fn paper_scene_viewer_in_headless_chromium() {
    let Some(browser) = chromium() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let data = common::paper_scene(0.2, 1e-4, true);
    let html = viewer_html(&data).unwrap();
    assert!(
        html.len() < 2_000_000,
        "0.2 s scene page is {} bytes",
        html.len()
    );
    let page = dir.path().join("viewer.html");
    std::fs::write(&page, &html).unwrap();
    let url = |t: f64| format!("file://{}#t={t}", page.display());
    let expected_frames = frame_indices(data.frames(), ViewerOptions::default().max_frames).len();
    assert_eq!(expected_frames, 2001, "0.2 s at 0.1 ms: every sample kept");

    let geometry = common::paper_geometry();
    let circle = common::paper_circle();
    let (scale, ox, oy) = data_transform(&data);
    let shown: Vec<chromium::Shown> = [0.0, 0.0125]
        .into_iter()
        .enumerate()
        .map(|(run, t)| {
            check_instant(
                &browser,
                dir.path(),
                &run.to_string(),
                &url(t),
                t,
                expected_frames,
                (scale, ox, oy),
                &geometry,
                &circle.motion(t).pose,
            )
        })
        .collect();

    // The machine drawing changes between the two times.
    let changed = changed_machine_pixels(&shown[0], &shown[1]);
    assert!(
        changed > 2000,
        "only {changed} pixels of the machine changed between t = 0 and 12.5 ms"
    );

    // Inside the (synthetic) buckling interval of link 2 the page says so.
    let (dom, _) = run_chromium(
        &browser,
        &dir.path().join("profile-buckling"),
        &url(0.125),
        &["--dump-dom".into()],
    );
    let report = report(&dom);
    assert!((f(&report["time"]) - 0.125).abs() < 1e-6);
    assert_eq!(report["buckling"], serde_json::json!([2]), "{report}");
}

/// With a (SYNTHETIC) coupled-model platform deviation the page shows the deviation plot
/// and draws the platform at `pose + a * deviation`, `a` being the deviation
/// amplification it reports; no console errors.
#[test]
fn coupled_deviation_is_drawn_amplified() {
    let Some(browser) = chromium() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let mut data = common::paper_scene(0.05, 1e-4, false);
    // 20 um and 1 mrad, at 116 Hz: the order of the coupled model's deviations.
    let deviation: Vec<[f64; 3]> = data
        .time
        .iter()
        .map(|&t| {
            let s = (std::f64::consts::TAU * 116.0 * t).sin();
            [2e-5 * s, -1e-5 * s, 1e-3 * s]
        })
        .collect();
    data.deviation = Some(deviation.clone());
    let page = dir.path().join("viewer.html");
    std::fs::write(&page, viewer_html(&data).unwrap()).unwrap();
    let t = 0.0021;
    let (dom, stderr) = run_chromium(
        &browser,
        &dir.path().join("profile"),
        &format!("file://{}#t={t}", page.display()),
        &["--dump-dom".into()],
    );
    assert!(console_lines(&stderr).is_empty(), "{stderr}");
    let report = report(&dom);
    assert_eq!(report["errors"].as_array().unwrap().len(), 0, "{report}");
    assert_eq!(report["coupled"], Value::Bool(true));
    assert!(dom.contains("platform position deviation"));
    let k = 21; // t = 2.1 ms at 0.1 ms steps
    assert!((f(&report["time"]) - data.time[k]).abs() < 1e-7);
    let a = f(&report["deviationAmplification"]);
    assert!(a > 1.0, "deviation amplification {a}");
    let drawn = report["platform"].as_array().unwrap();
    for c in 0..3 {
        let expected = data.pose[k][c] + a * deviation[k][c];
        // f32 storage: pose to ~1e-8 m, deviation relative 1e-7 before amplification.
        let tolerance = 1e-7 + 1e-6 * (a * deviation[k][c]).abs();
        assert!(
            (f(&drawn[c]) - expected).abs() < tolerance,
            "component {c}: drawn {}, expected {expected}",
            f(&drawn[c])
        );
    }
}

/// `#t=0&speed=0.005&play` starts the animation: after the 5 s virtual-time budget the
/// page has played about 5 s x 0.005 = 25 ms of simulated time (at least half of it, as
/// loading uses part of the budget; well below the 50 ms end, as a loaded machine makes
/// Chromium overrun the budget by timer ticks: 26.6 ms was seen on two busy cores), without
/// errors.
#[test]
fn play_advances_time() {
    let Some(browser) = chromium() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let data = common::paper_scene(0.05, 1e-4, false);
    let page = dir.path().join("viewer.html");
    std::fs::write(&page, viewer_html(&data).unwrap()).unwrap();
    let (dom, stderr) = run_chromium(
        &browser,
        &dir.path().join("profile"),
        &format!("file://{}#t=0&speed=0.005&play", page.display()),
        &["--dump-dom".into()],
    );
    assert!(console_lines(&stderr).is_empty(), "{stderr}");
    let report = report(&dom);
    assert_eq!(report["errors"].as_array().unwrap().len(), 0, "{report}");
    let frame = report["frame"].as_u64().unwrap();
    assert!(
        frame > 0,
        "still at the first frame after playing: {report}"
    );
    let t = f(&report["time"]);
    assert!(
        t > 0.0125 && t < 0.04,
        "simulated time {t} s after 5 s at x0.005"
    );
}
