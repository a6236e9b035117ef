//! `flexprr work-precision` from the command line: models side by side (`--models`) give rows
//! labelled by model, measured in mid-point deflections against the most faithful model, and
//! the cost-against-fidelity table; model names, error measures and tolerances that do not
//! apply are refused with exit code 2 and one line naming the option and the value.

use crate::common::{flexprr, stderr_of};
use std::path::{Path, PathBuf};
use std::process::Output;

/// The paper scene at 30 Hz over 2 ms, consistent formulation, with the nonlinear model at 4
/// elements per link (a few thousand steps).
fn short_scene(dir: &Path) -> PathBuf {
    let text = r#"
name = "wp_cli"

[links]
length = 0.2
modes = 3
material = { youngs_modulus = 7.3e10, density = 2770.0 }
section = { kind = "uniform", thickness = 0.002, height = 0.03 }
basis = { kind = "sine" }

[trajectory]
kind = "circle"
centre = [-0.05, 0.0]
radius = 0.05
frequency = 30.0
phi_deg = 45.0

[model]
formulation = "consistent"
coupling = "nonlinear"
elements = 4

[integrator]
method = "abm"
rtol = 1e-8
atol = 1e-12

[time]
start = 0.0
end = 0.002
output_step = 2e-4

[output]
requests = ["deflections"]
plots = false
"#;
    let path = dir.join("wp_cli.toml");
    std::fs::write(&path, text).expect("write scene");
    path
}

fn work_precision(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    flexprr()
        .arg("work-precision")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .args(["--repeats", "1", "--warmup", "0", "--methods", "abm"])
        .args(extra)
        .output()
        .expect("runs")
}

#[test]
fn models_side_by_side_are_labelled_and_measured_against_the_most_faithful() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = short_scene(dir.path());
    let out = dir.path().join("wp");
    let output = work_precision(
        &scene,
        &out,
        &["--models", "ked,nonlinear:4", "--tolerances", "1e-5,1e-7"],
    );
    assert!(output.status.success(), "{}", stderr_of(&output));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        stdout.contains("reference: nonlinear:4 with abm at rtol 1e-10, checked with rk45"),
        "{stdout}"
    );

    let csv = std::fs::read_to_string(out.join("work_precision.csv")).expect("csv");
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let model = header
        .iter()
        .position(|h| *h == "model")
        .expect("model column");
    let max_error = header
        .iter()
        .position(|h| *h == "max_error")
        .expect("error");
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let models: Vec<&str> = rows.iter().map(|r| r[model]).collect();
    assert_eq!(
        models,
        [
            "ked (consistent)",
            "ked (consistent)",
            "nonlinear:4",
            "nonlinear:4"
        ]
    );
    // KED floors at its model error (percent over 2 ms at 30 Hz); the reference model's own
    // rows fall far below it.
    let error = |k: usize| -> f64 { rows[k][max_error].parse().expect("number") };
    assert!(error(1) > 1e-3, "{csv}");
    assert!(error(3) < 1e-3 * error(1), "{csv}");

    let reference = std::fs::read_to_string(out.join("reference.csv")).expect("reference");
    assert!(reference.starts_with("t_s,w_1_xi0.5_m,w_2_xi0.5_m,w_3_xi0.5_m\n"));
    let md = std::fs::read_to_string(out.join("work_precision.md")).expect("md");
    assert!(md.contains("Cost against fidelity"), "{md}");
    assert!(md.contains("mid-point deflections"), "{md}");
    let svg = std::fs::read_to_string(out.join("work_precision.svg")).expect("svg");
    assert!(
        svg.contains("nonlinear:4 abm"),
        "legend names model and method"
    );
}

#[test]
fn choices_that_do_not_apply_are_refused_in_one_located_line() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = short_scene(dir.path());
    let out = dir.path().join("wp");
    let cases: [(&[&str], &[&str]); 7] = [
        (
            &["--models", "ked,linear"],
            &["--models", "\"linear\"", "ked, coupled, nonlinear"],
        ),
        (
            &["--models", "nonlinear:5"],
            &["--models", "\"nonlinear:5\"", "N even"],
        ),
        (
            &["--reference-model", "rigid"],
            &["--reference-model", "\"rigid\""],
        ),
        (
            &["--error", "energy"],
            &["--error", "\"energy\"", "deflection, state"],
        ),
        (
            &["--error", "state"],
            &["--error state", "nonlinear:4", "deflection measure"],
        ),
        (
            &["--tolerances", "1e-6,1e-11"],
            &["--reference-rtol", "1e-10", "1e-11"],
        ),
        (
            &["--methods", "magnus6"],
            &[
                "--methods",
                "magnus6 needs a linear (KED) model",
                "nonlinear:4",
            ],
        ),
    ];
    for (args, expected) in cases {
        let output = work_precision(&scene, &out, args);
        let stderr = stderr_of(&output);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{args:?}: {stderr}");
        for part in expected {
            assert!(stderr.contains(part), "{args:?}: {part:?} not in {stderr}");
        }
    }
    assert!(!out.exists(), "nothing written for refused input");
}

/// A shipped stress scene (`configs/stress/`).
fn stress_scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("configs/stress")
        .join(format!("{name}.toml"))
}

#[test]
fn a_diverged_reference_is_refused_with_exit_1_and_nothing_written() {
    // At 40 Hz link 3 buckles: `flexprr run` with the reference's pilot settings (ABM at
    // rtol 1e-8) reports "diverged" at a time; work-precision refuses to measure against
    // that solution, in one line naming the scene, the model and the same reason and time.
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = stress_scene("high_speed_f40");
    let text = std::fs::read_to_string(&scene).expect("scene").replace(
        "method = \"bdf\"\nrtol = 1e-6",
        "method = \"abm\"\nrtol = 1e-8",
    );
    let pilot = dir.path().join("pilot.toml");
    std::fs::write(&pilot, text).expect("write");
    let run = flexprr()
        .arg("run")
        .arg(&pilot)
        .args(["--quiet", "--out"])
        .arg(dir.path().join("run"))
        .output()
        .expect("runs");
    assert_eq!(run.status.code(), Some(1), "{}", stderr_of(&run));
    let run_stderr = stderr_of(&run);
    // "diverged: link 3 at t = 15.9792 ms", up to the next colon.
    let start = run_stderr.find("diverged: link").expect("run diverged");
    let rest = &run_stderr[start + "diverged:".len()..];
    let reason = &run_stderr[start..start + "diverged:".len() + rest.find(':').expect("colon")];

    let out = dir.path().join("wp");
    let output = work_precision(&scene, &out, &[]);
    let stderr = stderr_of(&output);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    for part in ["high_speed_f40", "ked (consistent)", "pilot run", reason] {
        assert!(stderr.contains(part), "{part:?} not in {stderr}");
    }
    assert!(!out.exists(), "nothing written for a refused reference");
}

#[test]
fn a_method_or_model_named_twice_is_refused_naming_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = short_scene(dir.path());
    let out = dir.path().join("wp");
    for (args, expected) in [
        (
            ["--methods", "abm,rk45,abm", "--models", "ked"],
            "--methods: \"abm\" is named twice",
        ),
        (
            ["--methods", "abm", "--models", "ked,nonlinear,ked"],
            "--models: \"ked\" is named twice",
        ),
        // The scene has 4 elements: `nonlinear` and `nonlinear:4` are one model.
        (
            ["--methods", "abm", "--models", "nonlinear,nonlinear:4"],
            "--models: \"nonlinear:4\" is named twice",
        ),
    ] {
        let output = flexprr()
            .arg("work-precision")
            .arg(&scene)
            .arg("--out")
            .arg(&out)
            .args(args)
            .output()
            .expect("runs");
        let stderr = stderr_of(&output);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{args:?}: {stderr}");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
    }
    assert!(!out.exists(), "nothing written for refused input");
}
