//! The real drive of `configs/servo_drive_f2.toml` through the `flexprr` program (issue 38;
//! docs/control.md, "A real drive"): the winding's current under a PI current loop and the
//! compliant screw are states of the run and of the linear model.
//!
//! * `flexprr modes`: the current loop's integral leaves the winding's own pole `R / L` in
//!   the closed loop exactly (the PI's zero cancels it, so feedback cannot move it): three
//!   overdamped modes at `R / (2 pi L)`; the screw adds three oscillatory modes to the
//!   rigid screw's scene (their closed form on a rigid machine is checked in
//!   crates/linear/tests/closed_forms.rs);
//! * `flexprr run`: on the 2 Hz circle the 1 kHz current loop and the 2 kHz screw modes are
//!   far above the motion, so the run converges on the steady-state drive's (the same scene
//!   without `inductance`, `current_bandwidth` and the screw's keys).

use crate::common::{flexprr, read_csv, stderr_of};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

fn config(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("configs")
        .join(name)
}

/// The drive scene without the lines starting with the keys `keys`, written into `dir`.
fn without(dir: &Path, name: &str, keys: &[&str]) -> PathBuf {
    let text = std::fs::read_to_string(config("servo_drive_f2.toml")).unwrap();
    let kept: Vec<&str> = text
        .lines()
        .filter(|l| !keys.iter().any(|k| l.starts_with(&format!("{k} "))))
        .collect();
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, kept.join("\n")).unwrap();
    path
}

/// `(frequency_hz, damping_ratio)` of the modes `flexprr modes --json` finds for `scene`.
fn modes_of(scene: &Path) -> Vec<(f64, f64)> {
    let o = flexprr()
        .arg("modes")
        .arg(scene)
        .args(["--json", "--count", "100"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr_of(&o));
    let value: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    value["modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| {
            (
                m["frequency_hz"].as_f64().unwrap(),
                m["damping_ratio"].as_f64().unwrap(),
            )
        })
        .collect()
}

#[test]
fn the_drives_states_are_in_the_linear_model() {
    let scene = config("servo_drive_f2.toml");
    let found = modes_of(&scene);
    // R = 1.6 ohm, L = 2.8 mH.
    let winding = 1.6 / (2.0 * PI * 2.8e-3);
    let at_winding: Vec<_> = found
        .iter()
        .filter(|(f, zeta)| (f / winding - 1.0).abs() < 1e-6 && (zeta - 1.0).abs() < 1e-9)
        .collect();
    assert_eq!(at_winding.len(), 3, "R / 2 pi L = {winding} Hz: {found:?}");
    let dir = tempfile::tempdir().unwrap();
    let rigid = modes_of(&without(
        dir.path(),
        "rigid",
        &["screw_stiffness", "screw_damping"],
    ));
    let oscillatory = |modes: &[(f64, f64)]| modes.iter().filter(|(_, z)| *z < 1.0).count();
    assert_eq!(
        oscillatory(&found),
        oscillatory(&rigid) + 3,
        "with the screw {found:?}, rigid {rigid:?}"
    );
}

#[test]
fn on_a_slow_circle_the_drive_converges_on_the_steady_state_one() {
    let dir = tempfile::tempdir().unwrap();
    let steady = without(
        dir.path(),
        "steady",
        &[
            "inductance",
            "current_bandwidth",
            "screw_stiffness",
            "screw_damping",
        ],
    );
    let mut tables = Vec::new();
    for (name, scene) in [("drive", config("servo_drive_f2.toml")), ("steady", steady)] {
        let out = dir.path().join(name);
        let o = flexprr()
            .arg("run")
            .arg(&scene)
            .arg("--out")
            .arg(&out)
            .arg("--quiet")
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0), "{name}: {}", stderr_of(&o));
        assert!(o.stderr.is_empty(), "{name}: {}", stderr_of(&o));
        tables.push((
            read_csv(&out.join("tracking.csv")),
            read_csv(&out.join("actuators.csv")),
        ));
    }
    let ((drive_tracking, drive_actuators), (steady_tracking, _)) = (&tables[0], &tables[1]);
    let (header, rows) = drive_actuators;
    for column in [
        "motor_current_1_A",
        "motor_voltage_1_V",
        "motor_speed_1_rev_s",
    ] {
        assert!(header.iter().any(|h| h == column), "{header:?}");
    }
    // Slider tracking errors: the drive's within 5 % of the steady-state drive's peak.
    let (_, a) = drive_tracking;
    let (_, b) = steady_tracking;
    let peak = b
        .iter()
        .flat_map(|r| r[1..4].iter())
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    let difference = a
        .iter()
        .zip(b)
        .flat_map(|(x, y)| (1..4).map(move |k| (x[k] - y[k]).abs()))
        .fold(0.0_f64, f64::max);
    println!("drive minus steady-state drive: {difference:.3e} m of a peak error {peak:.3e} m");
    assert!(difference < 0.05 * peak, "{difference} vs {peak}");
    // The winding voltage stays within the bus, the current within its limit.
    let column = |name: &str| header.iter().position(|h| h == name).unwrap();
    for i in 1..=3 {
        let (u, c) = (
            column(&format!("motor_voltage_{i}_V")),
            column(&format!("motor_current_{i}_A")),
        );
        assert!(
            rows.iter()
                .all(|r| r[u].abs() <= 320.0 && r[c].abs() <= 16.0)
        );
    }
}

#[test]
fn bad_drive_and_screw_keys_are_refused_at_their_key() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(config("servo_drive_f2.toml")).unwrap();
    let replace = |from: &str, to: &str| {
        assert!(text.contains(from), "{from}");
        text.replace(from, to)
    };
    let drop = |keys: &[&str]| -> String {
        text.lines()
            .filter(|l| !keys.iter().any(|k| l.starts_with(&format!("{k} "))))
            .collect::<Vec<_>>()
            .join("\n")
    };
    for (scene, key, rule) in [
        (drop(&["resistance"]), "actuators:", "resistance is missing"),
        (
            drop(&[
                "torque_constant",
                "resistance",
                "bus_voltage",
                "current_limit",
            ]),
            "actuators.inductance:",
            "needs the drive",
        ),
        (
            drop(&["inductance"]),
            "actuators.current_bandwidth:",
            "needs inductance",
        ),
        (
            replace("current_bandwidth = 1000 ", "current_bandwidth = 0 "),
            "actuators.current_bandwidth:",
            "must be finite and > 0",
        ),
        (
            replace("inductance = 2.8e-3 ", "inductance = -1 "),
            "actuators.inductance:",
            "must be finite and > 0",
        ),
        (
            drop(&["screw_stiffness"]),
            "actuators.screw_damping:",
            "needs screw_stiffness",
        ),
        (
            replace("screw_stiffness = 1.0e8 ", "screw_stiffness = nan "),
            "actuators.screw_stiffness:",
            "must be finite and > 0",
        ),
        (
            replace("screw_damping = 300 ", "screw_damping = -1 "),
            "actuators.screw_damping:",
            "must be finite and >= 0",
        ),
        (
            replace("rotor_inertia = 1.6e-5 ", "rotor_inertia = 0 "),
            "actuators.rotor_inertia:",
            "with screw_stiffness",
        ),
    ] {
        let path = dir.path().join("bad.toml");
        std::fs::write(&path, scene).unwrap();
        let o = flexprr().arg("check").arg(&path).output().unwrap();
        let stderr = stderr_of(&o);
        assert_eq!(o.status.code(), Some(2), "{key}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
        assert!(
            stderr.contains("bad.toml:") && stderr.contains(key) && stderr.contains(rule),
            "{key} {rule}: {stderr}"
        );
    }
}

/// `friction_feedforward = true`: on `configs/servo_motor_f2.toml` the PD feedback carried
/// the motors' friction (about 0.2 mm of tracking error); with the friction in the
/// feedforward what is left is the law's own error.
#[test]
fn the_friction_in_the_feedforward_removes_the_error_it_caused() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(config("servo_motor_f2.toml")).unwrap();
    let from = "coulomb_smoothing = 0.01      # rev/s\n";
    assert!(text.contains(from));
    let with = dir.path().join("with.toml");
    std::fs::write(
        &with,
        text.replace(from, &format!("{from}friction_feedforward = true\n")),
    )
    .unwrap();
    let mut peaks = Vec::new();
    for (name, scene) in [("without", config("servo_motor_f2.toml")), ("with", with)] {
        let out = dir.path().join(name);
        let o = flexprr()
            .arg("run")
            .arg(&scene)
            .arg("--out")
            .arg(&out)
            .arg("--quiet")
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0), "{name}: {}", stderr_of(&o));
        let (_, rows) = read_csv(&out.join("tracking.csv"));
        peaks.push(
            rows.iter()
                .flat_map(|r| r[1..4].iter())
                .fold(0.0_f64, |m, v| m.max(v.abs())),
        );
    }
    println!(
        "peak slider errors: {:.3e} m without, {:.3e} m with the friction fed forward",
        peaks[0], peaks[1]
    );
    assert!(peaks[0] > 1e-4 && peaks[1] < 1e-3 * peaks[0], "{peaks:?}");
}
