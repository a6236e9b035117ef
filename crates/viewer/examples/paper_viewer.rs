//! Writes the viewer page of the paper scene (real machine and trajectory, SYNTHETIC link
//! series, see `tests/common/mod.rs`) to the path given as the first argument.
//!
//! `cargo run --release -p flexprr-viewer --example paper_viewer -- viewer.html [--coupled]`
//!
//! `--coupled` adds a SYNTHETIC platform deviation (20 um, 1 mrad at 116 Hz) to show the
//! coupled model's panels.

#[path = "../tests/common/mod.rs"]
mod common;

fn main() {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "viewer.html".into());
    let mut data = common::paper_scene(0.2, 1e-4, true);
    if std::env::args().any(|a| a == "--coupled") {
        data.deviation = Some(
            data.time
                .iter()
                .map(|&t| {
                    let s = (std::f64::consts::TAU * 116.0 * t).sin();
                    [2e-5 * s, -1e-5 * s, 1e-3 * s]
                })
                .collect(),
        );
    }
    let html = flexprr_viewer::viewer_html(&data).expect("valid viewer data");
    std::fs::write(&path, &html).expect("write the viewer page");
    println!("{path}: {} bytes", html.len());
}
