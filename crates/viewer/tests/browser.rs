//! The viewer page of the paper scene in a real browser (headless Chromium).
//!
//! Needs the `chromium` binary (Debian: `apt-get install -y chromium`; `.ci/run` installs it
//! when missing). Without it the test fails, unless `FLEXPRR_SKIP_BROWSER=1` is set.
//! `FLEXPRR_VIEWER_SCREENSHOT=<path.png>` also saves the screenshot used in the README:
//!
//! ```text
//! FLEXPRR_VIEWER_SCREENSHOT=$PWD/docs/img/viewer.png \
//!     cargo test --release -p flexprr-viewer --test browser
//! ```

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use flexprr_kinematics::Trajectory;
use flexprr_viewer::{ViewerOptions, frame_indices, viewer_html};
use serde_json::Value;

const WINDOW: (u32, u32) = (1280, 900);

/// The browser to drive, or `None` when the test is to be skipped.
fn chromium() -> Option<PathBuf> {
    let found = std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|dir| dir.join("chromium"))
            .find(|p| p.is_file())
    });
    match found {
        Some(path) => Some(path),
        None if std::env::var("FLEXPRR_SKIP_BROWSER").as_deref() == Ok("1") => {
            eprintln!("browser test skipped: no chromium on PATH and FLEXPRR_SKIP_BROWSER=1");
            None
        }
        None => panic!(
            "the viewer's browser tests need headless Chromium: install it with \
             `apt-get update && apt-get install -y chromium` (Debian), or set \
             FLEXPRR_SKIP_BROWSER=1 to skip them"
        ),
    }
}

/// Runs headless Chromium on `url` with `extra` arguments; returns stdout and stderr.
fn run_chromium(browser: &Path, profile: &Path, url: &str, extra: &[String]) -> (String, String) {
    let mut command = Command::new(browser);
    command.args([
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--hide-scrollbars",
        "--force-device-scale-factor=1",
        "--enable-logging=stderr",
        "--v=0",
        "--virtual-time-budget=5000",
    ]);
    command.arg(format!("--user-data-dir={}", profile.display()));
    command.arg(format!("--window-size={},{}", WINDOW.0, WINDOW.1));
    command.args(extra);
    command.arg(url);
    let output = command.output().expect("start chromium");
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(
        output.status.success(),
        "chromium failed on {url}: {}\n{stderr}",
        output.status
    );
    (stdout, stderr)
}

/// Console lines Chromium logs to stderr (`...:CONSOLE...] "message", source: ...`).
fn console_lines(stderr: &str) -> Vec<&str> {
    stderr.lines().filter(|l| l.contains(":CONSOLE")).collect()
}

/// The page's JSON report from a `--dump-dom` of it.
fn report(dom: &str) -> Value {
    let start = dom
        .find("<pre id=\"flexprr-report\">")
        .expect("report element in the DOM")
        + "<pre id=\"flexprr-report\">".len();
    let end = start + dom[start..].find("</pre>").expect("end of report");
    let text = dom[start..end]
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&");
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("report is not JSON ({e}): {text}"))
}

struct Screenshot {
    width: usize,
    rgb: Vec<[u8; 3]>,
}

impl Screenshot {
    fn load(path: &Path) -> Self {
        let decoder = png::Decoder::new(std::io::BufReader::new(
            std::fs::File::open(path).expect("screenshot written"),
        ));
        let mut reader = decoder.read_info().expect("PNG header");
        let mut buffer = vec![0; reader.output_buffer_size().expect("PNG size")];
        let info = reader.next_frame(&mut buffer).expect("PNG data");
        let channels = info.color_type.samples();
        assert_eq!(info.bit_depth, png::BitDepth::Eight);
        assert!(channels >= 3, "colour screenshot");
        let rgb = buffer[..info.buffer_size()]
            .chunks(channels)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        Self {
            width: info.width as usize,
            rgb,
        }
    }

    fn at(&self, x: f64, y: f64) -> [u8; 3] {
        self.rgb[y.floor() as usize * self.width + x.floor() as usize]
    }
}

fn f(v: &Value) -> f64 {
    v.as_f64()
        .unwrap_or_else(|| panic!("number expected, got {v}"))
}

/// The page maps the world to canvas pixels with equal scales and y up, fitting the
/// bounding box of the guides' travel ends and the platform path into a 640 px square
/// canvas with a 46 px margin, centred. Recomputed here from the geometry alone.
fn expected_transform(data: &flexprr_viewer::ViewerData) -> (f64, f64, f64) {
    let (size, margin) = (640.0, 46.0);
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    let mut include = |x: f64, y: f64| {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    };
    for g in &data.guides {
        for r in [g.travel.0, g.travel.1] {
            include(
                g.anchor[0] + r * g.direction[0],
                g.anchor[1] + r * g.direction[1],
            );
        }
    }
    for p in &data.pose {
        include(p[0], p[1]);
    }
    let scale = ((size - 2.0 * margin) / (x1 - x0)).min((size - 2.0 * margin) / (y1 - y0));
    (
        scale,
        (size - scale * (x0 + x1)) / 2.0,
        (size + scale * (y0 + y1)) / 2.0,
    )
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
    let (scale, ox, oy) = expected_transform(&data);
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
        assert_eq!(report["frames"].as_u64(), Some(expected_frames as u64));
        assert_eq!(report["links"].as_u64(), Some(3));
        assert!(
            (f(&report["time"]) - t).abs() < 1e-6,
            "page time {}",
            report["time"]
        );
        let tr = &report["transform"];
        assert!((f(&tr["scale"]) - scale).abs() < 1e-9 * scale, "scale {tr}");
        assert!((f(&tr["ox"]) - ox).abs() < 1e-6 && (f(&tr["oy"]) - oy).abs() < 1e-6);

        // Inverse kinematics of the commanded pose at t, through the transform.
        let legs = geometry.inverse_position(&circle.motion(t).pose).unwrap();
        let drawn = report["sliderPixels"].as_array().unwrap();
        assert_eq!(drawn.len(), 3);
        for (i, leg) in legs.iter().enumerate() {
            let expected = (ox + scale * leg.b.x, oy - scale * leg.b.y);
            let got = (f(&drawn[i][0]), f(&drawn[i][1]));
            // f32 storage of rho: < 1e-6 m, far below a pixel (~2.4 mm here).
            assert!(
                (got.0 - expected.0).abs() < 0.01 && (got.1 - expected.1).abs() < 0.01,
                "t = {t}, slider {}: drawn at {got:?}, IK gives {expected:?}",
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
        // The slider block (26 x 14 px, #2b2b2b) is drawn on top of everything at B, with a
        // small white joint circle in its middle: 8 px either way along the guide is block.
        for (i, leg) in legs.iter().enumerate() {
            let u = geometry.legs[i].guide.direction;
            for side in [-8.0, 8.0] {
                let x = left + ox + scale * leg.b.x + side * u.x;
                let y = top + oy - scale * leg.b.y - side * u.y;
                let [r, g, b] = image.at(x, y);
                assert!(
                    r < 80 && g < 80 && b < 80,
                    "t = {t}: no slider block drawn at ({x:.1}, {y:.1}) for leg {}: rgb {:?}",
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
    let mut changed = 0;
    for y in 0..640 {
        for x in 0..640 {
            let (px, py) = (left + x as f64, top + y as f64);
            if a.at(px, py) != b.at(px, py) {
                changed += 1;
            }
        }
    }
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

    if let Some(path) = std::env::var_os("FLEXPRR_VIEWER_SCREENSHOT") {
        let (_, stderr) = run_chromium(
            &browser,
            &dir.path().join("profile-readme"),
            &url(0.125),
            &[format!("--screenshot={}", PathBuf::from(&path).display())],
        );
        assert!(console_lines(&stderr).is_empty(), "{stderr}");
        eprintln!("screenshot saved to {}", PathBuf::from(path).display());
    }
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
/// loading uses part of the budget; at most 6 % more, as Chromium may overrun the budget by
/// a timer tick and the nearest frame is shown), without errors.
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
        t > 0.0125 && t < 0.0265,
        "simulated time {t} s after 5 s at x0.005"
    );
}
