//! What `flexprr run` leaves on disk, for good runs and failed ones: a failed run keeps its
//! outputs up to the failure with `"status": "failed"`; a second run replaces the first
//! whole (no stale files); a directory that is not a flexprr output is refused unless
//! `--force`; rigid-body modes are reported as rigid, never as `NaN %`.

use crate::common::{config, flexprr, stderr_of};
use std::path::Path;
use std::process::Output;

fn run_into(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    flexprr()
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .args(extra)
        .output()
        .unwrap()
}

fn summary(dir: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(dir.join("summary.json")).expect("summary.json");
    serde_json::from_str(&text).expect("valid JSON")
}

/// The visible files of `dir` (the hidden marker `.flexprr-output.json` aside).
fn files(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !n.starts_with('.'))
        .collect();
    names.sort();
    names
}

/// The 35 Hz stress scene buckles link 3: the run exits 1 with the divergence, and still
/// writes every requested output up to the failure, with the status and failure in
/// `summary.json`, and no non-finite number anywhere.
#[test]
fn failed_run_keeps_its_outputs_and_says_why() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("f35");
    let output = run_into(&config("stress/high_speed_f35.toml"), &out, &[]);
    assert_eq!(output.status.code(), Some(1), "{}", stderr_of(&output));
    let message = stderr_of(&output);
    assert!(message.contains("diverged"), "{message}");
    assert_eq!(message.trim().lines().count(), 1, "{message}");
    let s = summary(&out);
    assert_eq!(s["status"], "failed");
    assert_eq!(s["failure"]["kind"], "diverged");
    let t_fail = s["failure"]["time_s"].as_f64().expect("time");
    assert!(t_fail > 0.0 && t_fail < 0.2, "{t_fail}");
    assert!(s["failure"]["link"].as_u64().is_some());
    for name in ["deflections.csv", "frequencies.csv", "energies.csv"] {
        let text =
            std::fs::read_to_string(out.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        let rows: Vec<&str> = text.lines().skip(1).collect();
        assert!(rows.len() > 10, "{name}: {} rows", rows.len());
        let last_t: f64 = rows
            .last()
            .unwrap()
            .split(',')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        assert!(
            last_t <= t_fail + 1e-12 && last_t > t_fail - 2e-4,
            "{name}: {last_t}"
        );
        assert!(
            !text.contains("NaN") && !text.contains("inf"),
            "{name} has a non-finite value"
        );
        // (CSV holds only numbers and headers; no header contains "inf".)
    }
}

/// A second run into the same directory leaves only its own files; a failed run into a
/// previous output directory replaces its `summary.json` too.
#[test]
fn a_second_run_replaces_the_first_whole() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("out");
    let first = run_into(&config("paper_f20.toml"), &out, &[]);
    assert!(first.status.success(), "{}", stderr_of(&first));
    assert!(files(&out).len() > 10);
    let scene = tmp.path().join("small.toml");
    let text = std::fs::read_to_string(config("paper_f20.toml")).unwrap();
    let text = format!(
        "{}[output]\nrequests = [\"frequencies\"]\nplots = false\n",
        &text[..text.find("[output]").unwrap()]
    );
    std::fs::write(&scene, text).unwrap();
    let second = run_into(&scene, &out, &[]);
    assert!(second.status.success(), "{}", stderr_of(&second));
    assert_eq!(
        files(&out),
        ["frequencies.csv", "summary.json", "table1.csv", "table1.md"]
    );
    let failed = run_into(&config("stress/high_speed_f35.toml"), &out, &[]);
    assert_eq!(failed.status.code(), Some(1));
    assert_eq!(summary(&out)["status"], "failed");
    assert!(
        !out.join("kinematics.csv").exists(),
        "stale file of the first run"
    );
}

/// A non-empty directory that is not a flexprr output is refused (exit 2, nothing touched)
/// unless `--force`.
#[test]
fn a_foreign_directory_is_refused_without_force() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("mine");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("notes.txt"), "keep me").unwrap();
    let refused = run_into(&config("paper_f20.toml"), &out, &[]);
    assert_eq!(refused.status.code(), Some(2), "{}", stderr_of(&refused));
    assert!(
        stderr_of(&refused).contains("--force"),
        "{}",
        stderr_of(&refused)
    );
    assert_eq!(files(&out), ["notes.txt"]);
    let forced = run_into(&config("paper_f20.toml"), &out, &["--force"]);
    assert!(forced.status.success(), "{}", stderr_of(&forced));
    assert!(out.join("summary.json").is_file());
    assert_eq!(summary(&out)["status"], "ok");
}

/// A free-free basis has two rigid-body modes: Table I names them rigid, and neither stdout,
/// `table1.md` nor `summary.json` holds a non-finite number.
#[test]
fn rigid_body_modes_are_reported_as_rigid() {
    let tmp = tempfile::tempdir().unwrap();
    let scene = tmp.path().join("free.toml");
    std::fs::write(
        &scene,
        r#"
name = "free_free"
[links]
modes = 4
basis = { kind = "classical", ends = "free-free" }
[trajectory]
kind = "circle"
frequency = 10.0
[time]
end = 0.1
output_step = 1e-3
[output]
requests = ["frequencies"]
plots = false
"#,
    )
    .unwrap();
    let out = tmp.path().join("out");
    let output = run_into(&scene, &out, &[]);
    assert!(output.status.success(), "{}", stderr_of(&output));
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    let table = std::fs::read_to_string(out.join("table1.md")).unwrap();
    let json = std::fs::read_to_string(out.join("summary.json")).unwrap();
    assert!(table.contains("rigid (0 Hz)"), "{table}");
    for text in [&stdout, &table, &json] {
        for bad in ["NaN", "inf %", "-inf", "Infinity"] {
            assert!(!text.contains(bad), "{bad} in {text}");
        }
    }
}
