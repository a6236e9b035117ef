//! The servo scenes through the `flexprr` program: `check` names the actuated model, `run`
//! writes the control outputs and figures, and a motor beyond its ratings is a warning on
//! stderr (exit 0) while a bad control key is one located line (exit 2).

use crate::common::{check_ok, config, flexprr, stderr_of};

#[test]
fn check_names_the_actuated_model() {
    for (name, expected) in [
        (
            "servo_f20.toml",
            "coupled model, actuated sliders (pd, force actuators), consistent formulation, 3 modes per link",
        ),
        (
            "servo_motor_f2.toml",
            "coupled model, actuated sliders (pd, motor_ballscrew actuators)",
        ),
        (
            "servo_motor_f20.toml",
            "coupled model, prescribed sliders (motor_ballscrew actuators: the motion is checked against their ratings)",
        ),
    ] {
        let (stdout, _) = check_ok(&config(name));
        assert!(stdout.contains(expected), "{name}: {stdout}");
        assert!(stdout.contains("abm integrator"), "{name}: {stdout}");
    }
}

#[test]
fn the_servo_scene_writes_its_control_outputs() {
    let out = tempfile::tempdir().unwrap();
    let output = flexprr()
        .arg("run")
        .arg(config("servo_f20.toml"))
        .arg("--out")
        .arg(out.path())
        .arg("--quiet")
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(0), "{}", stderr_of(&output));
    assert!(
        output.stderr.is_empty(),
        "no warning: {}",
        stderr_of(&output)
    );
    for file in [
        "tracking.csv",
        "actuators.csv",
        "deflections.csv",
        "tracking.svg",
        "actuators.svg",
        "viewer.html",
    ] {
        assert!(out.path().join(file).is_file(), "{file}");
    }
    let header = std::fs::read_to_string(out.path().join("tracking.csv")).unwrap();
    assert!(header.starts_with(
        "t_s,slider_error_1_m,slider_error_2_m,slider_error_3_m,platform_error_x_m,\
         platform_error_y_m,platform_error_phi_rad\n"
    ));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.path().join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["status"], "ok");
    assert_eq!(summary["control"]["controller"], "pd");
    assert!(summary["feasibility"].is_null());
    // The scene echo holds the tables as written, so it can be pasted back.
    assert_eq!(summary["scene_file"]["control"]["kp"], 2e5);
    assert_eq!(summary["scene_file"]["actuators"]["kind"], "force");
    // Microns of tracking error: the servo tracks the 20 Hz circle.
    for slider in summary["control"]["sliders"].as_array().unwrap() {
        let peak = slider["peak_error_m"].as_f64().unwrap();
        assert!(peak > 1e-6 && peak < 1e-4, "{slider}");
    }
    let viewer = std::fs::read_to_string(out.path().join("viewer.html")).unwrap();
    assert!(
        viewer.contains("\"reference_sliders\":\""),
        "the commanded sliders are drawn"
    );
}

#[test]
fn motors_beyond_their_ratings_are_warned_about_on_stderr() {
    let out = tempfile::tempdir().unwrap();
    let output = flexprr()
        .arg("run")
        .arg(config("servo_motor_f20.toml"))
        .arg("--out")
        .arg(out.path())
        .arg("--quiet")
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(0), "{}", stderr_of(&output));
    let stderr = stderr_of(&output);
    assert!(
        stderr.contains("warning: infeasible motion")
            && stderr.contains("max_speed of 100 rev/s (6000 rpm) from t = 0 ms on leg 1")
            && stderr.contains("49845 rpm"),
        "{stderr}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.path().join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(summary["feasibility"]["feasible"], false);
    assert_eq!(summary["feasibility"]["first_over_max_speed"]["leg"], 1);
    assert_eq!(
        summary["warnings"].as_array().unwrap().len(),
        stderr
            .lines()
            .filter(|l| l.starts_with("warning: "))
            .count()
    );
    assert!(summary["control"].is_null(), "the sliders are prescribed");
}

#[test]
fn a_bad_control_key_is_one_located_line() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(config("servo_f20.toml"))
        .unwrap()
        .replace("kd = 400 ", "kd = -400 ");
    let path = dir.path().join("bad.toml");
    std::fs::write(&path, &text).unwrap();
    let output = flexprr().arg("check").arg(&path).output().unwrap();
    assert_eq!(output.status.code(), Some(2));
    let stderr = stderr_of(&output);
    let line = 1 + text
        .lines()
        .position(|l| l.starts_with("kd = -400"))
        .unwrap();
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains(&format!(
            "bad.toml:{line}:1: control.kd: a gain must be finite and >= 0, got -400"
        )),
        "{stderr}"
    );
}
