//! Driving headless Chromium for the viewer's browser tests (shared by
//! `crates/viewer/tests/browser.rs` and the workspace's `tests/cli/viewer_browser.rs`).
//!
//! Needs the `chromium` binary (Debian: `apt-get install -y chromium`; `.ci/run` installs it
//! and requires it). Without it the tests skip and say so in one line on the test run's
//! stderr, unless `FLEXPRR_REQUIRE_BROWSER=1`, which makes a missing browser a failure.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

/// Browser window (CSS pixels) of every run.
pub const WINDOW: (u32, u32) = (1280, 900);

/// The browser to drive, or `None` when the test is to be skipped.
///
/// Looks for `chromium` on `PATH`. Without it, the test panics with the install command
/// when `FLEXPRR_REQUIRE_BROWSER=1` (CI); otherwise it is skipped, and the first skipped
/// test of this test binary writes one line saying so. The line goes straight to the
/// process's stderr (`io::stderr().write_all`, not `eprintln!`): the test harness captures
/// only the print macros of passing tests, so this line shows in a plain `cargo test`.
pub fn chromium() -> Option<PathBuf> {
    let found = std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|dir| dir.join("chromium"))
            .find(|p| p.is_file())
    });
    if found.is_some() {
        return found;
    }
    assert!(
        std::env::var("FLEXPRR_REQUIRE_BROWSER").as_deref() != Ok("1"),
        "FLEXPRR_REQUIRE_BROWSER=1 but no `chromium` on PATH: the viewer's browser tests \
         need headless Chromium, install it with `apt-get install -y chromium` (Debian)"
    );
    static SAID: std::sync::Once = std::sync::Once::new();
    SAID.call_once(|| {
        use std::io::Write;
        let line = format!(
            "note: skipping the viewer's browser tests ({} test `{}`): no `chromium` on PATH \
             (install it with `apt-get install -y chromium` to run them; \
             FLEXPRR_REQUIRE_BROWSER=1 makes a missing browser a failure)\n",
            env!("CARGO_PKG_NAME"),
            env!("CARGO_CRATE_NAME")
        );
        // Best effort: a closed stderr must not fail the test.
        let _ = std::io::stderr().lock().write_all(line.as_bytes());
    });
    None
}

/// Runs headless Chromium on `url` with `extra` arguments and a fresh profile in
/// `profile`, in a window of `window` CSS pixels; returns stdout and stderr.
pub fn run_chromium_sized(
    browser: &Path,
    profile: &Path,
    url: &str,
    extra: &[String],
    window: (u32, u32),
) -> (String, String) {
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
    command.arg(format!("--window-size={},{}", window.0, window.1));
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

/// [`run_chromium_sized`] in the [`WINDOW`].
pub fn run_chromium(
    browser: &Path,
    profile: &Path,
    url: &str,
    extra: &[String],
) -> (String, String) {
    run_chromium_sized(browser, profile, url, extra, WINDOW)
}

/// Console lines Chromium logs to stderr (`...:CONSOLE...] "message", source: ...`).
pub fn console_lines(stderr: &str) -> Vec<&str> {
    stderr.lines().filter(|l| l.contains(":CONSOLE")).collect()
}

/// The page's JSON report from a `--dump-dom` of it.
pub fn report(dom: &str) -> Value {
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

/// An 8-bit RGB(A) PNG screenshot.
pub struct Screenshot {
    /// Width in pixels.
    pub width: usize,
    /// Pixels, row by row.
    pub rgb: Vec<[u8; 3]>,
}

impl Screenshot {
    /// Reads the PNG at `path`.
    pub fn load(path: &Path) -> Self {
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

    /// The pixel containing the point `(x, y)`.
    pub fn at(&self, x: f64, y: f64) -> [u8; 3] {
        self.rgb[y.floor() as usize * self.width + x.floor() as usize]
    }
}

/// A JSON number.
pub fn f(v: &Value) -> f64 {
    v.as_f64()
        .unwrap_or_else(|| panic!("number expected, got {v}"))
}

/// The page maps the world to canvas pixels with equal scales and y up, fitting the
/// bounding box of the guides' travel ends and the platform path into a 640 px square
/// canvas with a 46 px margin, centred. Recomputed here from those points alone:
/// `(scale, ox, oy)` with `px = ox + scale x`, `py = oy - scale y`.
pub fn expected_transform(points: impl IntoIterator<Item = [f64; 2]>) -> (f64, f64, f64) {
    let (size, margin) = (640.0, 46.0);
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for [x, y] in points {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let scale = ((size - 2.0 * margin) / (x1 - x0)).min((size - 2.0 * margin) / (y1 - y0));
    (
        scale,
        (size - scale * (x0 + x1)) / 2.0,
        (size + scale * (y0 + y1)) / 2.0,
    )
}

/// What one instant of a viewer page showed: its report, its screenshot and where the
/// machine canvas sits in the screenshot.
pub struct Shown {
    /// The page's self-report (`report`).
    pub report: Value,
    /// The screenshot.
    pub shot: Screenshot,
    /// Left and top of the machine canvas in the screenshot (CSS pixels).
    pub canvas: (f64, f64),
}

/// Loads the page at `url` (showing time `t`) twice, for its report and a screenshot, and
/// checks everything that must hold at any instant, against independent values: no console
/// output or page errors; `frames` frames and 3 links; the page's time; the page transform
/// against `transform` (`expected_transform`, recomputed by the caller); each drawn slider
/// joint against the closed-form inverse kinematics of `geometry` at `motion`, mapped
/// through that transform; and, in the screenshot itself, a dark slider block around each
/// of them. `tag` keeps the browser profiles of different calls apart.
#[allow(clippy::too_many_arguments)]
pub fn check_instant(
    browser: &Path,
    dir: &Path,
    tag: &str,
    url: &str,
    t: f64,
    frames: usize,
    transform: (f64, f64, f64),
    geometry: &flexprr_kinematics::Geometry,
    pose: &flexprr_kinematics::Pose,
) -> Shown {
    let (scale, ox, oy) = transform;
    let (dom, stderr) = run_chromium(
        browser,
        &dir.join(format!("profile-{tag}")),
        url,
        &["--dump-dom".into()],
    );
    assert!(
        console_lines(&stderr).is_empty(),
        "console output at t = {t}: {:?}",
        console_lines(&stderr)
    );
    let report = report(&dom);
    assert_eq!(report["errors"].as_array().unwrap().len(), 0, "{report}");
    assert_eq!(report["frames"].as_u64(), Some(frames as u64));
    assert_eq!(report["links"].as_u64(), Some(3));
    assert!(
        (f(&report["time"]) - t).abs() < 1e-6,
        "page time {}",
        report["time"]
    );
    // The page computes its transform from f32 data: 1e-6 relative, 1e-3 px.
    let tr = &report["transform"];
    assert!((f(&tr["scale"]) - scale).abs() < 1e-6 * scale, "scale {tr}");
    assert!((f(&tr["ox"]) - ox).abs() < 1e-3 && (f(&tr["oy"]) - oy).abs() < 1e-3);

    let legs = geometry.inverse_position(pose).unwrap();
    let drawn = report["sliderPixels"].as_array().unwrap();
    assert_eq!(drawn.len(), 3);
    for (i, leg) in legs.iter().enumerate() {
        let expected = (ox + scale * leg.b.x, oy - scale * leg.b.y);
        let got = (f(&drawn[i][0]), f(&drawn[i][1]));
        // f32 storage of rho: < 1e-6 m, far below a pixel (about 2 mm).
        assert!(
            (got.0 - expected.0).abs() < 0.01 && (got.1 - expected.1).abs() < 0.01,
            "t = {t}, slider {}: drawn at {got:?}, inverse kinematics gives {expected:?}",
            i + 1
        );
    }

    let path = dir.join(format!("shot-{tag}.png"));
    let (_, stderr) = run_chromium(
        browser,
        &dir.join(format!("profile-shot-{tag}")),
        url,
        &[format!("--screenshot={}", path.display())],
    );
    assert!(console_lines(&stderr).is_empty(), "{stderr}");
    let shot = Screenshot::load(&path);
    let canvas = (f(&report["canvas"]["left"]), f(&report["canvas"]["top"]));
    // The dark slider block (26 x 14 px) is drawn at B on top of everything: 8 px either
    // way along the guide is block.
    for (i, leg) in legs.iter().enumerate() {
        let u = geometry.legs[i].guide.direction;
        for side in [-8.0, 8.0] {
            let x = canvas.0 + ox + scale * leg.b.x + side * u.x;
            let y = canvas.1 + oy - scale * leg.b.y - side * u.y;
            let [r, g, b] = shot.at(x, y);
            assert!(
                r < 80 && g < 80 && b < 80,
                "t = {t}: no slider block at ({x:.1}, {y:.1}) for leg {}: rgb {:?}",
                i + 1,
                [r, g, b]
            );
        }
    }
    Shown {
        report,
        shot,
        canvas,
    }
}

/// Number of pixels of the 640 px machine canvas that differ between two instants.
pub fn changed_machine_pixels(a: &Shown, b: &Shown) -> usize {
    let (left, top) = a.canvas;
    (0..640)
        .flat_map(|y| (0..640).map(move |x| (left + x as f64, top + y as f64)))
        .filter(|&(px, py)| a.shot.at(px, py) != b.shot.at(px, py))
        .count()
}
