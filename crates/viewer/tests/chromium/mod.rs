//! Driving headless Chromium for the viewer's browser tests (shared by
//! `crates/viewer/tests/browser.rs` and the workspace's `tests/viewer_browser.rs`).
//!
//! Needs the `chromium` binary (Debian: `apt-get install -y chromium`; `.ci/run` installs it
//! when missing). Without it the tests fail with the install command, unless
//! `FLEXPRR_SKIP_BROWSER=1` is set, the only way to skip them.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

/// Browser window (CSS pixels) of every run.
pub const WINDOW: (u32, u32) = (1280, 900);

/// The browser to drive, or `None` when the test is to be skipped.
pub fn chromium() -> Option<PathBuf> {
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
