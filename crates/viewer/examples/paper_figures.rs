//! Writes `machine.svg` and `snapshots.svg` of the paper scene (real machine and
//! trajectory, SYNTHETIC link series, see `tests/common/mod.rs`) into the directory given
//! as the first argument.
//!
//! `cargo run --release -p flexprr-viewer --example paper_figures -- out/`

#[path = "../tests/common/mod.rs"]
mod common;

fn main() {
    let dir = std::path::PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| ".".into()));
    let data = common::paper_scene(0.2, 1e-4, false);
    let path: Vec<[f64; 3]> = data.pose.iter().take(501).copied().collect();
    let machine = flexprr_viewer::machine_svg(
        &common::paper_geometry(),
        &path,
        "paper machine, 20 Hz circle",
        241,
    )
    .expect("machine figure");
    std::fs::write(dir.join("machine.svg"), machine).expect("write machine.svg");
    let snapshots = flexprr_viewer::snapshots_svg(&data, &[0.0, 0.0125, 0.025, 0.0375], None)
        .expect("snapshots figure");
    std::fs::write(dir.join("snapshots.svg"), snapshots).expect("write snapshots.svg");
    println!("wrote machine.svg and snapshots.svg to {}", dir.display());
}
