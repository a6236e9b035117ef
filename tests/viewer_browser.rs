//! The viewer of the REAL paper scene in headless Chromium: `flexprr run
//! configs/paper_f20.toml` writes `viewer.html`; the page shows no console errors, the
//! expected frames and links, the slider joints where the closed-form inverse kinematics
//! of `flexprr_kinematics` puts them, and a moving machine.
//!
//! Needs the `chromium` binary (Debian: `apt-get install -y chromium`); only
//! `FLEXPRR_SKIP_BROWSER=1` skips. With `FLEXPRR_README_IMAGES=<dir>` it also writes the
//! README's pictures there (docs/viewer.md):
//!
//! ```text
//! FLEXPRR_README_IMAGES=$PWD/docs/img cargo test --release --test viewer_browser
//! ```

#[path = "../crates/viewer/tests/chromium/mod.rs"]
mod chromium;

use std::path::{Path, PathBuf};
use std::process::Command;

use chromium::{
    Screenshot, chromium, console_lines, expected_transform, f, report, run_chromium,
    run_chromium_sized,
};
use flexprr_kinematics::{Circle, Geometry, Trajectory};

fn config(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("configs")
        .join(name)
}

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

    let mut shots = Vec::new();
    for (run, t) in [0.0, 0.0125].into_iter().enumerate() {
        let profile = dir.path().join(format!("profile-{run}"));
        let (dom, stderr) = run_chromium(&browser, &profile, &url(t), &["--dump-dom".into()]);
        assert!(
            console_lines(&stderr).is_empty(),
            "console output at t = {t}: {:?}",
            console_lines(&stderr)
        );
        let report = report(&dom);
        assert_eq!(report["errors"].as_array().unwrap().len(), 0, "{report}");
        assert_eq!(report["frames"].as_u64(), Some(frames as u64));
        assert_eq!(report["links"].as_u64(), Some(3));
        assert!((f(&report["time"]) - t).abs() < 1e-6, "{}", report["time"]);
        assert_eq!(report["coupled"], serde_json::Value::Bool(false));
        let tr = &report["transform"];
        assert!((f(&tr["scale"]) - scale).abs() < 1e-6 * scale, "scale {tr}");
        assert!((f(&tr["ox"]) - ox).abs() < 1e-3 && (f(&tr["oy"]) - oy).abs() < 1e-3);

        // The slider joints B_i of the closed-form inverse kinematics, through the transform.
        let legs = geometry.inverse_position(&circle.motion(t).pose).unwrap();
        let drawn = report["sliderPixels"].as_array().unwrap();
        assert_eq!(drawn.len(), 3);
        for (i, leg) in legs.iter().enumerate() {
            let expected = (ox + scale * leg.b.x, oy - scale * leg.b.y);
            let got = (f(&drawn[i][0]), f(&drawn[i][1]));
            // f32 storage of rho: < 1e-6 m, far below a pixel (about 1.5 mm here).
            assert!(
                (got.0 - expected.0).abs() < 0.01 && (got.1 - expected.1).abs() < 0.01,
                "t = {t}, slider {}: drawn at {got:?}, inverse kinematics gives {expected:?}",
                i + 1
            );
        }

        let shot = dir.path().join(format!("shot-{run}.png"));
        let (_, stderr) = run_chromium(
            &browser,
            &dir.path().join(format!("profile-shot-{run}")),
            &url(t),
            &[format!("--screenshot={}", shot.display())],
        );
        assert!(console_lines(&stderr).is_empty(), "{stderr}");
        let image = Screenshot::load(&shot);
        let canvas = &report["canvas"];
        let (left, top) = (f(&canvas["left"]), f(&canvas["top"]));
        // The dark slider block (26 x 14 px) is drawn at B on top of everything: 8 px either
        // way along the guide is block, in the screenshot itself.
        for (i, leg) in legs.iter().enumerate() {
            let u = geometry.legs[i].guide.direction;
            for side in [-8.0, 8.0] {
                let x = left + ox + scale * leg.b.x + side * u.x;
                let y = top + oy - scale * leg.b.y - side * u.y;
                let [r, g, b] = image.at(x, y);
                assert!(
                    r < 80 && g < 80 && b < 80,
                    "t = {t}: no slider block at ({x:.1}, {y:.1}) for leg {}: rgb {:?}",
                    i + 1,
                    [r, g, b]
                );
            }
        }
        shots.push((image, left, top));
    }

    // The machine drawing changes between the two times.
    let (a, left, top) = (&shots[0].0, shots[0].1, shots[0].2);
    let b = &shots[1].0;
    let changed = (0..640)
        .flat_map(|y| (0..640).map(move |x| (left + x as f64, top + y as f64)))
        .filter(|&(px, py)| a.at(px, py) != b.at(px, py))
        .count();
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
