//! The piezoelectric patches through the run layer (docs/piezo.md, "Outputs"): the shipped
//! scene configs/piezo_f20.toml over a shorter span, checked against
//!
//! * the uncontrolled run at zero gain (identical to the integration tolerance);
//! * the law and the power computed independently from the written sensor signal: the
//!   strain-rate command `-G dV_s/dt` and the power `(k_a / k_s) V dV_s/dt`, with `dV_s/dt`
//!   by central differences of `V_sensor` (the model computes the rate from the modal
//!   velocities, not by differencing);
//! * the clipping at a tight voltage limit, reported in `summary.json`;
//! * the reduction reported in `summary.json` against the peaks and RMS of the written
//!   deflection columns.

use std::path::Path;

use flexprr_run::{RunResult, run, summary_json};
use flexprr_scene::Scene;
use serde_json::Value;

const K_A: f64 = 3.7e-4;
const K_S: f64 = 8.0e3;

/// The shipped scene with its gain, limit and requests replaced, over 50 ms.
fn scene(gain: f64, limit: f64, requests: &str) -> Scene {
    let path = Path::new(WORKSPACE).join("configs/piezo_f20.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let text = text
        .lines()
        .map(|line| {
            let key = line.split('=').next().unwrap_or("").trim();
            match key {
                "gain" => format!("gain = {gain}"),
                "voltage_limit" => format!("voltage_limit = {limit}"),
                "requests" => format!("requests = {requests}"),
                "end" => "end = 0.05".to_string(),
                _ => line.to_string(),
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    Scene::from_text("piezo_f20.toml", "piezo_f20", &text).unwrap()
}

fn column<'a>(result: &'a RunResult, table: &str, header: &str) -> &'a [f64] {
    result
        .table(table)
        .unwrap_or_else(|| panic!("no table {table}"))
        .column(header)
        .unwrap_or_else(|| panic!("no column {header} in {table}"))
}

fn peak(x: &[f64]) -> f64 {
    x.iter().fold(0.0_f64, |m, v| m.max(v.abs()))
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
}

#[test]
fn zero_gain_reproduces_the_uncontrolled_run() {
    let scene = scene(0.0, 200.0, r#"["deflections", "piezo"]"#);
    let result = run(&scene, &mut |_| {}).unwrap();
    for i in 1..=3 {
        let w = column(&result, "deflections", &format!("w_{i}_xi0.5_m"));
        let free = column(
            &result,
            "deflections",
            &format!("w_{i}_xi0.5_uncontrolled_m"),
        );
        let scale = peak(free);
        assert!(scale > 1e-4, "link {i} hardly deflects: {scale}");
        let diff = w
            .iter()
            .zip(free)
            .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
        // rtol 1e-8 on the states: the two runs agree far below a micrometre.
        assert!(diff <= 1e-7 * scale, "link {i}: {diff} of {scale}");
        let applied = column(&result, "piezo", &format!("V_applied_{i}_1_V"));
        assert!(peak(applied) == 0.0);
    }
    let summary = summary_json(&scene, &result, None);
    let section = &summary["vibration_control"];
    assert_eq!(section["uncontrolled_run"], Value::Bool(true));
    assert_eq!(section["any_saturated"], Value::Bool(false));
    for link in section["links"].as_array().unwrap() {
        let r = link["peak_reduction_percent"].as_f64().unwrap();
        assert!(r.abs() < 1e-5, "{link}");
    }
}

#[test]
fn the_law_and_the_power_follow_the_written_sensor_signal() {
    let gain = 3e-3;
    let scene = scene(gain, 200.0, r#"["piezo"]"#);
    let result = run(&scene, &mut |_| {}).unwrap();
    let t = result.table("piezo").unwrap().time().to_vec();
    for i in 1..=3 {
        let sensor = column(&result, "piezo", &format!("V_sensor_{i}_1_V"));
        let command = column(&result, "piezo", &format!("V_command_{i}_1_V"));
        let applied = column(&result, "piezo", &format!("V_applied_{i}_1_V"));
        let power = column(&result, "piezo", &format!("P_patch_{i}_1_W"));
        assert!(
            peak(applied) < 200.0 && peak(applied) > 10.0,
            "{}",
            peak(applied)
        );
        let (mut law_err, mut power_err) = (Vec::new(), Vec::new());
        for k in 1..t.len() - 1 {
            let rate = (sensor[k + 1] - sensor[k - 1]) / (t[k + 1] - t[k - 1]);
            law_err.push(command[k] + gain * rate);
            power_err.push(power[k] - K_A / K_S * applied[k] * rate);
        }
        // Central differences at 0.1 ms of signals up to ~350 Hz: ~1 % of the signal.
        let (law, p) = (rms(&law_err) / rms(command), rms(&power_err) / rms(power));
        assert!(law < 0.02 && p < 0.04, "link {i}: law {law}, power {p}");
        // Strain-rate feedback only takes energy out.
        assert!(power.iter().all(|&p| p <= 1e-15), "link {i}");
    }
}

#[test]
fn a_tight_limit_clips_and_the_summary_says_so() {
    let limit = 20.0;
    let scene = scene(3e-3, limit, r#"["piezo"]"#);
    let result = run(&scene, &mut |_| {}).unwrap();
    let command = column(&result, "piezo", "V_command_1_1_V");
    let applied = column(&result, "piezo", "V_applied_1_1_V");
    let flag = column(&result, "piezo", "patch_saturated_1_1_flag");
    for k in 0..command.len() {
        // Exactly the clipped command: compare the bits.
        assert_eq!(
            applied[k].to_bits(),
            command[k].clamp(-limit, limit).to_bits()
        );
        assert_eq!(flag[k] > 0.5, command[k].abs() > limit);
    }
    let clipped = flag.iter().filter(|&&f| f > 0.5).count() as f64 / flag.len() as f64;
    let summary = summary_json(&scene, &result, None);
    let section = &summary["vibration_control"];
    assert_eq!(section["any_saturated"], Value::Bool(true));
    assert_eq!(section["max_abs_voltage_V"].as_f64(), Some(limit));
    let patch = &section["patches"][0];
    assert_eq!(patch["saturated_fraction"].as_f64(), Some(clipped));
    assert!(clipped > 0.05);
    assert!(result.warnings.iter().any(|w| w.contains("saturated")));
}

#[test]
fn the_reduction_is_that_of_the_written_deflections() {
    let scene = scene(3e-3, 200.0, r#"["deflections"]"#);
    let result = run(&scene, &mut |_| {}).unwrap();
    let summary = summary_json(&scene, &result, None);
    let links = summary["vibration_control"]["links"]
        .as_array()
        .unwrap()
        .clone();
    for (i, link) in (1..=3).zip(&links) {
        let w = column(&result, "deflections", &format!("w_{i}_xi0.5_m"));
        let free = column(
            &result,
            "deflections",
            &format!("w_{i}_xi0.5_uncontrolled_m"),
        );
        let expect = 100.0 * (1.0 - peak(w) / peak(free));
        let got = link["peak_reduction_percent"].as_f64().unwrap();
        assert!((got - expect).abs() < 1e-9, "link {i}: {got} vs {expect}");
        let expect = 100.0 * (1.0 - rms(w) / rms(free));
        let got = link["rms_reduction_percent"].as_f64().unwrap();
        assert!((got - expect).abs() < 1e-9, "link {i}: {got} vs {expect}");
    }
    // Link 1 rings at its first mode, which the patch damps.
    assert!(links[0]["peak_reduction_percent"].as_f64().unwrap() > 5.0);
}

#[test]
fn no_second_run_without_deflections_or_piezo_requested() {
    let scene = scene(3e-3, 200.0, r#"["energies"]"#);
    let result = run(&scene, &mut |_| {}).unwrap();
    let summary = summary_json(&scene, &result, None);
    let section = &summary["vibration_control"];
    assert_eq!(section["uncontrolled_run"], Value::Bool(false));
    assert!(section["links"].is_null());
    // The patches are still summarised.
    assert!(section["max_abs_voltage_V"].as_f64().unwrap() > 10.0);
}

#[test]
fn piezo_without_patches_is_refused_at_its_request() {
    let path = Path::new(WORKSPACE).join("configs/paper_f20.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let text = text.replace(
        "requests = [\"kinematics\",",
        "requests = [\"piezo\", \"kinematics\",",
    );
    let err = Scene::from_text("paper_f20.toml", "p", &text)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("output.requests.0") && err.contains("[[links.patches]]"),
        "{err}"
    );
}

#[test]
fn the_study_quantities_are_the_runs_reduction_and_voltage() {
    use flexprr_studies::quantity::piezo::{DeflectionReduction, PatchVoltage};
    use flexprr_studies::study::{CaseRun, Quantity};
    let scene = scene(3e-3, 100.0, r#"["deflections"]"#);
    let result = run(&scene, &mut |_| {}).unwrap();
    let summary = summary_json(&scene, &result, None);
    let section = &summary["vibration_control"];
    for link in 1..=3 {
        let q = DeflectionReduction { link };
        assert!(q.unavailable(&scene).is_none());
        let values = q.derive(&CaseRun::finished(&scene, &result)).unwrap();
        let l = &section["links"][link - 1];
        for (value, key) in values
            .iter()
            .zip(["peak_reduction_percent", "rms_reduction_percent"])
        {
            let expect = l[key].as_f64().unwrap();
            assert!((value.parse::<f64>().unwrap() - expect).abs() <= 1e-9 * expect.abs().max(1.0));
        }
    }
    let values = PatchVoltage
        .derive(&CaseRun::finished(&scene, &result))
        .unwrap();
    // At a 100 V limit the 3 ms gain saturates link 1's patch (its command reaches 161 V).
    assert_eq!(values[0], "100");
    assert_eq!(values[1], "yes");
    let fraction = section["max_saturated_fraction"].as_f64().unwrap();
    // Written to ten significant digits.
    assert!(
        (values[2].parse::<f64>().unwrap() - fraction).abs() <= 1e-9 * fraction && fraction > 0.0
    );
    // Without the law there is no reduction to report; without patches no voltage.
    let free = scene.without_vibration_control();
    assert!(DeflectionReduction { link: 1 }.unavailable(&free).is_some());
    let path = Path::new(WORKSPACE).join("configs/paper_f20.toml");
    let paper = Scene::load(&path).unwrap();
    let why = PatchVoltage.unavailable(&paper).unwrap();
    assert!(why.contains("[[links.patches]]"), "{why}");
}

/// The workspace root: the tests read its configs and validation data.
const WORKSPACE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
