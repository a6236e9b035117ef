//! The `flexprr` program end to end: `run` on the paper's 20 Hz scene writes the CSV tables,
//! `summary.json` (link 1's frequency ranges checked against the paper's Table I), `table1.md`
//! and labelled SVG plots; `check` validates; bad input exits 2 and a failed run exits 1, each
//! with one line on stderr; `kinematics` prints CSV.

use crate::common::{check_ok, config, flexprr, stderr_of};
use std::path::{Path, PathBuf};

#[path = "margins.rs"]
mod margins;
#[path = "plan.rs"]
mod plan;

/// Writes `text` as `name` in `dir` and returns its path.
fn scene_file(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn run_paper_f20_writes_tables_summary_and_plots() {
    let out = tempfile::tempdir().unwrap();
    let output = flexprr()
        .arg("run")
        .arg(config("paper_f20.toml"))
        .arg("--out")
        .arg(out.path())
        .arg("--quiet")
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", stderr_of(&output));
    let dir = out.path();

    // One CSV per requested output, each with the time column first and 2001 rows
    // (0 to 0.2 s every 0.1 ms) under its header.
    for name in [
        "kinematics",
        "driving_forces",
        "joint_reactions",
        "axial_forces",
        "frequencies",
        "modes",
        "modal_forces",
        "deflections",
        "energies",
    ] {
        let text = std::fs::read_to_string(dir.join(format!("{name}.csv")))
            .unwrap_or_else(|e| panic!("{name}.csv: {e}"));
        let mut lines = text.lines();
        let header = lines.next().unwrap();
        assert!(header.starts_with("t_s,"), "{name}: {header}");
        let columns = header.split(',').count();
        let rows: Vec<&str> = lines.collect();
        assert_eq!(rows.len(), 2001, "{name}");
        assert!(
            rows.iter().all(|r| r.split(',').count() == columns),
            "{name}"
        );
        let last_t: f64 = rows[2000].split(',').next().unwrap().parse().unwrap();
        assert!((last_t - 0.2).abs() < 1e-12, "{name}: {last_t}");
    }
    let deflections = std::fs::read_to_string(dir.join("deflections.csv")).unwrap();
    let header = deflections.lines().next().unwrap();
    assert!(header.contains("w_1_xi0.5_m") && header.contains("w_1_xi0.5_no_axial_m"));

    // Table I of the paper, link 1 (Hz): the ranges to the paper's rounding (half a unit of
    // the last printed digit).
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let ranges = summary["frequencies"]["ranges"].as_array().unwrap();
    let table_one = [
        (1, 90.2, 141.3, 0.05),
        (2, 441.7, 492.4, 0.05),
        (3, 1024.0, 1075.0, 0.5),
    ];
    for (mode, min, max, half_unit) in table_one {
        let range = ranges
            .iter()
            .find(|r| r["link"] == 1 && r["mode"] == mode)
            .unwrap_or_else(|| panic!("no range for link 1 mode {mode}"));
        let got_min = range["min_hz"].as_f64().unwrap();
        let got_max = range["max_hz"].as_f64().unwrap();
        assert!(
            (got_min - min).abs() <= half_unit,
            "mode {mode} minimum {got_min} Hz vs Table I {min}"
        );
        assert!(
            (got_max - max).abs() <= half_unit,
            "mode {mode} maximum {got_max} Hz vs Table I {max}"
        );
    }
    assert_eq!(summary["scene"], "paper_f20");
    assert_eq!(summary["formulation"]["name"], "paper");
    assert_eq!(summary["run"]["integrated"], true);
    assert_eq!(summary["run"]["output_samples"], 2001);
    assert!(summary["integrator"]["accepted_steps"].as_u64().unwrap() > 0);

    // table1.md: a markdown table with a row per mode of link 1.
    let table = std::fs::read_to_string(dir.join("table1.md")).unwrap();
    assert!(table.starts_with("| link 1 |"), "{table}");
    for mode in 1..=3 {
        assert!(table.contains(&format!("| mode {mode} |")), "{table}");
    }

    // SVG plots with axis labels carrying SI-prefixed units, Unicode symbols and a legend.
    let plots = [
        (
            "deflections_xi0.5.svg",
            &[
                "t (ms)",
                "w₁ (mm)",
                "with axial force",
                "without axial force",
            ][..],
        ),
        (
            "driving_forces.svg",
            &["t (ms)", "Fₐ₁ (N)", "rigid links"][..],
        ),
        (
            "axial_force_frequency_mode1.svg",
            &["t (ms)", "(N)", "f₁,₁ (Hz)", "at B (slider)"][..],
        ),
        ("modes.svg", &["t (ms)", "η₁,₁ (", "η₁,₃ ("][..]),
        ("kinematics.svg", &["ρ (mm)", "β (rad)", "ρ₁"][..]),
    ];
    for (file, phrases) in plots {
        let svg = std::fs::read_to_string(dir.join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert!(svg.starts_with("<svg"), "{file}");
        for phrase in phrases {
            assert!(svg.contains(phrase), "{file} lacks `{phrase}`");
        }
    }
}

#[test]
fn check_accepts_the_shipped_configs() {
    for name in [
        "paper_f20.toml",
        "consistent_f20.toml",
        "pick_and_place.toml",
        "clamped_free_links.toml",
        "fe_links.toml",
    ] {
        let (stdout, stderr) = check_ok(&config(name));
        assert!(stdout.contains(": ok ("), "{name}: {stdout}");
        assert!(stderr.is_empty(), "{name}: {stderr}");
    }
}

/// `check` names the model the scene asks for, with its own discretisation: modes and basis
/// for the KED and coupled models, elements for the nonlinear one.
#[test]
fn check_names_the_model() {
    let dir = tempfile::tempdir().unwrap();
    let coupled = std::fs::read_to_string(config("coupled_f20.toml")).unwrap();
    assert!(coupled.contains("coupling = \"coupled\""));
    let nonlinear = coupled.replace(
        "coupling = \"coupled\"",
        "coupling = \"nonlinear\"\nelements = 12",
    );
    let nonlinear = nonlinear.replace(
        "requests = [\"axial_forces\", \"driving_forces\", \"frequencies\", \"modes\", \"deflections\"]",
        "requests = [\"deflections\"]",
    );
    for (name, text, expected) in [
        (
            "ked",
            std::fs::read_to_string(config("paper_f20.toml")).unwrap(),
            "KED model, paper formulation, 3 modes per link",
        ),
        (
            "coupled",
            coupled.clone(),
            "coupled model, consistent formulation, 3 modes per link",
        ),
        (
            "nonlinear",
            nonlinear,
            "nonlinear model, 12 co-rotational elements per link",
        ),
    ] {
        let path = scene_file(dir.path(), &format!("{name}.toml"), &text);
        let output = flexprr().arg("check").arg(&path).output().unwrap();
        let stdout = String::from_utf8_lossy(&output.stdout);
        assert_eq!(
            output.status.code(),
            Some(0),
            "{name}: {}",
            stderr_of(&output)
        );
        assert!(stdout.contains(expected), "{name}: {stdout}");
    }
}

#[test]
fn the_short_example_configs_run() {
    for name in [
        "pick_and_place.toml",
        "clamped_free_links.toml",
        "fe_links.toml",
    ] {
        let out = tempfile::tempdir().unwrap();
        let output = flexprr()
            .arg("run")
            .arg(config(name))
            .arg("--out")
            .arg(out.path())
            .arg("--quiet")
            .output()
            .unwrap();
        assert_eq!(
            output.status.code(),
            Some(0),
            "{name}: {}",
            stderr_of(&output)
        );
        let summary: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(out.path().join("summary.json")).unwrap(),
        )
        .unwrap();
        assert_eq!(summary["run"]["integrated"], true, "{name}");
        assert!(out.path().join("deflections.csv").exists(), "{name}");
    }
}

#[test]
fn bad_scene_exits_2_with_one_line_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(config("paper_f20.toml"))
        .unwrap()
        .replace("platform_mass = 0.2 ", "platform_mass = -0.2");
    let path = scene_file(dir.path(), "negative_mass.toml", &text);
    let line = text
        .lines()
        .position(|l| l.starts_with("platform_mass"))
        .unwrap()
        + 1;
    for command in ["check", "run"] {
        let output = flexprr().arg(command).arg(&path).output().unwrap();
        assert_eq!(output.status.code(), Some(2), "{command}");
        let stderr = stderr_of(&output);
        assert_eq!(stderr.lines().count(), 1, "{command}: {stderr}");
        assert!(
            stderr.contains(&format!(
                "negative_mass.toml:{line}:1: machine.platform_mass"
            )),
            "{command}: {stderr}"
        );
        assert!(stderr.contains("non-negative"), "{command}: {stderr}");
        assert!(output.stdout.is_empty(), "{command}");
    }
}

#[test]
fn unknown_key_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(config("paper_f20.toml"))
        .unwrap()
        .replace("rtol = 1e-8", "rtol = 1e-8\nreltol = 1e-8");
    let path = scene_file(dir.path(), "typo.toml", &text);
    let output = flexprr().arg("check").arg(&path).output().unwrap();
    assert_eq!(output.status.code(), Some(2));
    let stderr = stderr_of(&output);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("reltol"), "{stderr}");
}

#[test]
fn missing_file_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let output = flexprr()
        .arg("check")
        .arg(dir.path().join("absent.toml"))
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(2));
    assert_eq!(stderr_of(&output).lines().count(), 1);
}

#[test]
fn run_failure_exits_1_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(config("paper_f20.toml"))
        .unwrap()
        .replace("atol = 1e-12", "atol = 1e-12\nmax_steps = 10");
    let path = scene_file(dir.path(), "few_steps.toml", &text);
    // The scene itself is valid...
    let check = flexprr().arg("check").arg(&path).output().unwrap();
    assert_eq!(check.status.code(), Some(0), "{}", stderr_of(&check));
    // ...but ten steps cannot cover 0.2 s of vibration.
    let out = tempfile::tempdir().unwrap();
    let output = flexprr()
        .arg("run")
        .arg(&path)
        .arg("--out")
        .arg(out.path())
        .arg("--quiet")
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(1));
    let stderr = stderr_of(&output);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("run failed"), "{stderr}");
    // The outputs up to the failure are kept, and the summary says why.
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.path().join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["status"], "failed");
    assert_eq!(summary["failure"]["kind"], "too-many-steps");
}

#[test]
fn kinematics_prints_csv_with_a_header() {
    let output = flexprr()
        .arg("kinematics")
        .arg(config("paper_f20.toml"))
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", stderr_of(&output));
    let text = String::from_utf8(output.stdout).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(&header[..4], &["t_s", "x_m", "y_m", "phi_rad"]);
    assert_eq!(header.len(), 4 + 18);
    assert!(header.contains(&"rho_3_m") && header.contains(&"beta_dot_2_rad_s"));
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 2001);
    // The scene's circle: x = 0.05 cos(2 pi 20 t) - 0.05, y = 0.05 sin(2 pi 20 t), phi = 45 deg.
    // Values carry 11 significant digits (docs/scenes.md): t to 1e-11 s, which moves the
    // platform (6.3 m/s) by 7e-11 m, and x, y to 5e-12 m.
    for row in &rows {
        let angle = std::f64::consts::TAU * 20.0 * row[0];
        assert!((row[1] - (0.05 * angle.cos() - 0.05)).abs() < 1e-10);
        assert!((row[2] - 0.05 * angle.sin()).abs() < 1e-10);
        assert!((row[3] - 45f64.to_radians()).abs() < 1e-11);
    }
}
