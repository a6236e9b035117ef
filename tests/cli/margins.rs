//! `flexprr margins`: the PD servo's loops at the centre pose, where the three legs are
//! alike (120 deg symmetry), have the same margins; a PD loop never reaches -180 deg (no
//! gain margin) with a phase margin between 0 and 90 deg; a scene without
//! `[control]` is bad input. The numbers themselves are checked against closed forms in
//! `crates/linear/src/margins.rs`.

use super::{config, flexprr, stderr_of};

#[test]
fn margins_of_the_servo_loops_are_alike_at_the_centre_and_need_a_loop() {
    let output = flexprr()
        .args(["margins", "--json", "--pose", "0,0,45"])
        .arg(config("servo_f20.toml"))
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", stderr_of(&output));
    let v: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let loops = v["loops"].as_array().unwrap();
    assert_eq!(loops.len(), 3);
    let pm: Vec<f64> = loops
        .iter()
        .map(|l| l["phase_margin_deg"].as_f64().unwrap())
        .collect();
    assert!(
        pm.iter()
            .all(|p| (p - pm[0]).abs() < 1e-6 && *p > 0.0 && *p < 90.0),
        "{pm:?}"
    );
    assert!(loops.iter().all(|l| l["gain_margin"].is_null()));
    assert!(
        loops
            .iter()
            .all(|l| l["sensitivity_peak"].as_f64().unwrap() >= 1.0)
    );
    let output = flexprr()
        .arg("margins")
        .arg(config("paper_f20.toml"))
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(2));
    assert!(
        stderr_of(&output).contains("no [control]"),
        "{}",
        stderr_of(&output)
    );
}
