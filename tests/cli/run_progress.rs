//! `flexprr run` off a terminal: at most one progress line per tenth of the time span,
//! each a new tenth, on stderr only; `--quiet` prints nothing at all on stderr.

use std::path::Path;
use std::process::Command;

/// The paper scene over 10 s with one small output: long enough to show progress (lines
/// appear once a run has taken a second).
fn long_scene(dir: &Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/paper_f20.toml"),
    )
    .unwrap();
    let mut out = String::new();
    for line in text.lines() {
        let line = if line.starts_with("end = ") {
            "end = 10.0"
        } else if line.starts_with("output_step = ") {
            "output_step = 1e-2"
        } else if line.starts_with("requests = ") {
            "requests = [\"deflections\"]"
        } else if line.starts_with("compare_without_axial_force = ") {
            "compare_without_axial_force = false"
        } else if line.starts_with("plots = ") {
            "plots = false"
        } else {
            line
        };
        out.push_str(line);
        out.push('\n');
    }
    let path = dir.join("long.toml");
    std::fs::write(&path, out).unwrap();
    path
}

fn run(scene: &Path, out: &Path, quiet: bool) -> std::process::Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_flexprr"));
    command.arg("run").arg(scene).arg("--out").arg(out);
    if quiet {
        command.arg("--quiet");
    }
    let output = command.output().unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    output
}

#[test]
fn run_progress_off_a_terminal_is_one_line_per_tenth_and_quiet_is_silent() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = long_scene(tmp.path());
    let out = tmp.path().join("loud");
    let output = run(&scene, &out, false);
    let stderr = String::from_utf8_lossy(&output.stderr);
    let mut tenths = Vec::new();
    for line in stderr.lines() {
        let rest = line
            .strip_prefix("paper_f20: ")
            .unwrap_or_else(|| panic!("not a progress line: {line}"));
        let percent: usize = rest
            .split(" % integrated, ")
            .next()
            .and_then(|p| p.parse().ok())
            .unwrap_or_else(|| panic!("not a progress line: {line}"));
        assert!(percent % 10 == 0 && (10..=100).contains(&percent), "{line}");
        tenths.push(percent / 10);
    }
    assert!(tenths.len() <= 10, "{stderr}");
    assert!(tenths.windows(2).all(|w| w[0] < w[1]), "{stderr}");
    // The progress appears once a run has taken a second: the run says how long it took.
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let wall = summary["run"]["wall_time_s"].as_f64().unwrap();
    if wall > 1.5 {
        assert!(!tenths.is_empty(), "a {wall} s run showed no progress");
    }
    // The run's report goes to stdout, not among the progress lines.
    assert!(String::from_utf8_lossy(&output.stdout).contains("outputs written to"));

    let quiet = run(&scene, &tmp.path().join("quiet"), true);
    assert_eq!(String::from_utf8_lossy(&quiet.stderr), "");
}
