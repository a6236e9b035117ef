//! `flexprr beam` on the example link file: the printed frequencies against the exact
//! axially loaded pinned-pinned frequencies, and bad input reported with its place.

use crate::common::flexprr;
use std::f64::consts::PI;
use std::path::Path;

fn example() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/link_paper.toml")
}

#[test]
fn example_link_json_matches_exact_loaded_frequencies() {
    let output = flexprr()
        .arg("beam")
        .arg(example())
        .arg("--json")
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    // The example: E = 7.3e10, density 2770, t = 2 mm, h = 30 mm, l = 0.2 m, P = +50 N.
    let (e, rho, t, h, l, force) = (7.3e10, 2770.0, 0.002, 0.03, 0.2, 50.0);
    let ei = e * h * t * t * t / 12.0;
    let rho_a = rho * t * h;
    let modes = report["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 3);
    for (j, mode) in modes.iter().enumerate() {
        let k = (j + 1) as f64 * PI / l;
        let exact = ((ei * k.powi(4) + force * k * k) / rho_a).sqrt() / (2.0 * PI);
        let got = mode["frequency_hz"].as_f64().unwrap();
        assert!(
            ((got - exact) / exact).abs() < 1e-10,
            "mode {}: {got} vs {exact}",
            j + 1
        );
        assert_eq!(mode["state"], "stable");
        assert_eq!(mode["mode"], j + 1);
    }
    assert!(report["critical_load_factor"].is_null());
    assert_eq!(report["buckled"], false);
    let mass = report["total_mass"].as_f64().unwrap();
    assert!((mass - rho_a * l).abs() < 1e-14);
}

#[test]
fn example_link_table_lists_three_modes() {
    let output = flexprr().arg("beam").arg(example()).output().unwrap();
    assert!(output.status.success());
    let text = String::from_utf8(output.stdout).unwrap();
    // Unloaded paper values are 116.39 / 465.57 / 1047.52 Hz; at +50 N all rise.
    let rows: Vec<f64> = text
        .lines()
        .filter_map(|line| {
            let mut words = line.split_whitespace();
            let mode: usize = words.next()?.parse().ok()?;
            let hz: f64 = words.next()?.parse().ok()?;
            (mode >= 1).then_some(hz)
        })
        .collect();
    assert_eq!(rows.len(), 3, "{text}");
    for (got, unloaded) in rows.iter().zip([116.39, 465.57, 1047.52]) {
        assert!(*got > unloaded && *got < unloaded * 1.08, "{text}");
    }
}

#[test]
fn buckled_link_is_reported_not_nan() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(example())
        .unwrap()
        .replace("p0 = 50.0", "p0 = -500.0");
    let path = dir.path().join("buckled.toml");
    std::fs::write(&path, text).unwrap();
    let output = flexprr()
        .arg("beam")
        .arg(&path)
        .arg("--json")
        .output()
        .unwrap();
    assert!(output.status.success());
    let report: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(report["buckled"], true);
    assert_eq!(report["modes"][0]["state"], "buckled");
    assert!(report["modes"][0]["omega_squared"].as_f64().unwrap() < 0.0);
    // Euler load pi^2 EI / l^2 = 360.27 N at E = 7.3e10: factor 0.7205.
    let p_cr = PI * PI * (7.3e10 * 0.03 * 0.002f64.powi(3) / 12.0) / 0.04;
    let factor = report["critical_load_factor"].as_f64().unwrap();
    assert!((factor - p_cr / 500.0).abs() < 1e-9);
}

#[test]
fn unknown_key_is_bad_input_with_line_and_key() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(example())
        .unwrap()
        .replace("height = 0.03", "heigth = 0.03");
    let path = dir.path().join("typo.toml");
    std::fs::write(&path, &text).unwrap();
    let output = flexprr().arg("beam").arg(&path).output().unwrap();
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&output.stderr);
    let line = text.lines().position(|l| l.starts_with("heigth")).unwrap() + 1;
    assert!(stderr.contains(&format!(":{line}:")), "{stderr}");
    assert!(stderr.contains("heigth"), "{stderr}");
}

#[test]
fn invalid_value_is_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(example())
        .unwrap()
        .replace("thickness = 0.002", "thickness = -0.002");
    let path = dir.path().join("negative.toml");
    std::fs::write(&path, text).unwrap();
    let output = flexprr().arg("beam").arg(&path).output().unwrap();
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&output.stderr).contains("thickness"));
}

fn run_json(dir: &Path, name: &str, text: &str) -> serde_json::Value {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    let output = flexprr()
        .arg("beam")
        .arg(&path)
        .arg("--json")
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "{name}: {}",
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_slice(&output.stdout).unwrap()
}

fn first_frequencies(report: &serde_json::Value) -> Vec<f64> {
    report["modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["frequency_hz"].as_f64().unwrap())
        .collect()
}

#[test]
fn stepped_and_hermite_files_agree_with_the_uniform_sine_example() {
    // A stepped section of two identical pieces is the uniform section; 32 Hermite elements
    // reproduce the sine frequencies to O(h^4) ~ 1e-5.
    let dir = tempfile::tempdir().unwrap();
    let base = std::fs::read_to_string(example()).unwrap();
    let uniform = first_frequencies(&run_json(dir.path(), "uniform.toml", &base));
    let section_start = base.find("[section]").unwrap();
    let basis_start = base.find("[basis]").unwrap();
    let stepped_text = format!(
        "{}[section]\nkind = \"stepped\"\n[[section.steps]]\nend = 0.4\nthickness = 0.002\nheight = 0.03\n\
         [[section.steps]]\nend = 1.0\nthickness = 0.002\nheight = 0.03\n\n{}",
        &base[..section_start],
        &base[basis_start..]
    );
    let stepped = first_frequencies(&run_json(dir.path(), "stepped.toml", &stepped_text));
    let hermite_text = base.replace(
        "kind = \"sine\"",
        "kind = \"hermite\"\nelements = 32\nends = \"pinned-pinned\"",
    );
    let hermite = first_frequencies(&run_json(dir.path(), "hermite.toml", &hermite_text));
    assert_eq!(stepped.len(), 3);
    assert_eq!(hermite.len(), 3);
    for j in 0..3 {
        assert!(
            (stepped[j] - uniform[j]).abs() < 1e-10 * uniform[j],
            "{stepped:?}"
        );
        let rel = (hermite[j] - uniform[j]) / uniform[j];
        assert!(rel > 0.0 && rel < 1e-5, "mode {}: {rel}", j + 1);
    }
}
