//! Writes the viewer page of the paper scene (real machine and trajectory, SYNTHETIC link
//! series, see `tests/common/mod.rs`) to the path given as the first argument.
//!
//! `cargo run --release -p flexprr-viewer --example paper_viewer -- viewer.html`

#[path = "../tests/common/mod.rs"]
mod common;

fn main() {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "viewer.html".into());
    let data = common::paper_scene(0.2, 1e-4, true);
    let html = flexprr_viewer::viewer_html(&data).expect("valid viewer data");
    std::fs::write(&path, &html).expect("write the viewer page");
    println!("{path}: {} bytes", html.len());
}
