//! The viewer of the REAL paper scene in headless Chromium: `flexprr run
//! configs/paper_f20.toml` writes `viewer.html`; the page shows no console errors, the
//! expected frames and links, the slider joints where the closed-form inverse kinematics
//! of `flexprr_kinematics` puts them, and a moving machine.
//!
//! Needs the `chromium` binary (Debian: `apt-get install -y chromium`): without it the test
//! skips with one line on stderr, unless `FLEXPRR_REQUIRE_BROWSER=1`. With `FLEXPRR_README_IMAGES=<dir>` it also writes the
//! README's pictures there (docs/viewer.md):
//!
//! ```text
//! FLEXPRR_README_IMAGES=$PWD/docs/img cargo test --release --test cli viewer_browser
//! ```

#[path = "../../crates/viewer/tests/chromium/mod.rs"]
mod chromium;

use crate::common::config;
use std::path::{Path, PathBuf};
use std::process::Command;

use chromium::{
    changed_machine_pixels, check_instant, chromium, console_lines, expected_transform,
    run_chromium, run_chromium_sized,
};
use flexprr_kinematics::{Circle, Geometry, Trajectory};

/// Runs the shipped paper scene into `dir/paper_f20`.
fn run_paper_scene(dir: &Path) -> PathBuf {
    let out = dir.join("paper_f20");
    let output = Command::new(env!("CARGO_BIN_EXE_flexprr"))
        .arg("run")
        .arg(config("paper_f20.toml"))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    out
}

#[test]
fn paper_scene_viewer_from_the_real_run() {
    let Some(browser) = chromium() else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let out = run_paper_scene(dir.path());
    let page = out.join("viewer.html");
    let size = std::fs::metadata(&page).expect("viewer.html written").len();
    eprintln!("viewer.html of the 0.2 s paper scene: {size} bytes");
    assert!(size < 2_000_000, "0.2 s page is {size} bytes");
    for name in ["snapshots.svg", "machine.svg"] {
        assert!(out.join(name).is_file(), "{name} written");
    }
    let url = |t: f64| format!("file://{}#t={t}", page.display());

    // Independently: the paper's machine and 20 Hz circle, output every 0.1 ms over 0.2 s
    // (2001 times, fewer than the page's 5000-frame limit, so every one is a frame).
    let geometry = Geometry::paper();
    let circle = Circle::paper(20.0).unwrap();
    let frames = 2001;
    let times: Vec<f64> = (0..frames).map(|k| 0.2 * k as f64 / 2000.0).collect();
    let ends = geometry.legs.iter().flat_map(|leg| {
        let g = &leg.guide;
        [g.travel.0, g.travel.1].map(|r| {
            [
                g.anchor.x + r * g.direction.x,
                g.anchor.y + r * g.direction.y,
            ]
        })
    });
    let path = times.iter().map(|&t| {
        let p = circle.motion(t).pose;
        [p.x, p.y]
    });
    let (scale, ox, oy) = expected_transform(ends.chain(path));

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
                frames,
                (scale, ox, oy),
                &geometry,
                &circle.motion(t).pose,
            )
        })
        .collect();
    for s in &shown {
        assert_eq!(s.report["coupled"], serde_json::Value::Bool(false));
    }
    // The machine drawing changes between the two times.
    let changed = changed_machine_pixels(&shown[0], &shown[1]);
    assert!(
        changed > 2000,
        "only {changed} pixels of the machine changed between t = 0 and 12.5 ms"
    );

    if let Some(target) = std::env::var_os("FLEXPRR_README_IMAGES") {
        let target = PathBuf::from(target);
        let (_, stderr) = run_chromium(
            &browser,
            &dir.path().join("profile-readme"),
            &url(0.125),
            &[format!(
                "--screenshot={}",
                target.join("viewer.png").display()
            )],
        );
        assert!(console_lines(&stderr).is_empty(), "{stderr}");
        // snapshots.svg is 1320 x 440 CSS pixels; the window shows it whole.
        let (_, stderr) = run_chromium_sized(
            &browser,
            &dir.path().join("profile-snapshots"),
            &format!("file://{}", out.join("snapshots.svg").display()),
            &[format!(
                "--screenshot={}",
                target.join("paper_f20_snapshots.png").display()
            )],
            (1320, 440),
        );
        assert!(console_lines(&stderr).is_empty(), "{stderr}");
        eprintln!("README images written to {}", target.display());
    }
}
