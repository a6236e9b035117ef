//! `flexprr plan` end to end: the shipped pick-and-place plan writes `plan.json` (its
//! duration, binding limits, margins and residual vibration), a `planned.toml` that
//! `flexprr run` runs and whose slider speeds and forces stay within the plan's limits, the
//! figures and the planned motion's viewer; bad input exits 2 with one line naming the key;
//! the output directory follows the run's rules.

use super::{config, flexprr, scene_file, stderr_of};

fn largest(csv: &str, prefix: &str, suffix: &str) -> f64 {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let columns: Vec<usize> = header
        .iter()
        .enumerate()
        .filter(|(_, h)| h.starts_with(prefix) && h.ends_with(suffix))
        .map(|(i, _)| i)
        .collect();
    assert_eq!(columns.len(), 3, "{prefix}*{suffix} in {header:?}");
    lines
        .flat_map(|line| {
            let cells: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
            columns
                .iter()
                .map(move |&i| cells[i].abs())
                .collect::<Vec<_>>()
        })
        .fold(0.0, f64::max)
}

#[test]
fn plan_writes_a_runnable_planned_scene_within_its_limits() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("plan");
    let output = flexprr()
        .args(["plan", "--quiet", "--out"])
        .arg(&out)
        .arg(config("plan_pick_and_place.toml"))
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", stderr_of(&output));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("residual vibration"), "{stdout}");
    for name in [
        "plan.json",
        "planned.toml",
        "phase_plane.svg",
        "sliders.svg",
        "deflections.svg",
    ] {
        assert!(out.join(name).is_file(), "{name}");
    }
    assert!(out.join("planned/viewer.html").is_file());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("plan.json")).unwrap()).unwrap();
    let duration = json["duration_s"].as_f64().unwrap();
    assert!(duration > 0.09 && duration < 0.11, "{duration}");
    let limits = json["plan"]["check"]["limits"].as_array().unwrap();
    for limit in limits {
        assert!(limit["usage"].as_f64().unwrap() <= 1.0 + 1e-9, "{limit}");
        assert!(limit["pose"]["x_m"].is_f64());
    }
    let ratio = json["flexible_check"]["shaped_over_unshaped"]
        .as_f64()
        .unwrap();
    assert!(ratio < 0.05, "{ratio}");
    assert!(json["scene_timing"]["check"]["max_usage"].as_f64().unwrap() > 1.5);
    // The planned scene runs as it is; its slider speeds and rigid forces keep the limits.
    let run_out = dir.path().join("run");
    let output = flexprr()
        .args(["run", "--quiet", "--out"])
        .arg(&run_out)
        .arg(out.join("planned.toml"))
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", stderr_of(&output));
    let kinematics = std::fs::read_to_string(run_out.join("kinematics.csv")).unwrap();
    let speed = largest(&kinematics, "rho_dot_", "_m_s");
    assert!(speed <= 1.001 && speed > 0.99, "{speed}");
    let forces = std::fs::read_to_string(run_out.join("driving_forces.csv")).unwrap();
    let force = largest(&forces, "F_a_", "_rigid_N");
    assert!(force <= 400.4, "{force}");
    // Planning again into the same directory replaces the plan's own outputs.
    let again = flexprr()
        .args(["plan", "--quiet", "--no-flexible-check", "--out"])
        .arg(&out)
        .arg(config("plan_pick_and_place.toml"))
        .output()
        .unwrap();
    assert!(again.status.success(), "{}", stderr_of(&again));
    assert!(!out.join("planned").exists());
}

#[test]
fn plan_bad_input_exits_2_with_one_line_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(config("pick_and_place.toml")).unwrap();
    let cases = [
        ("", "[plan]"),
        (
            "[plan]\nboundary = \"periodic\"\nslider_speed = 1.0\n",
            "plan.boundary",
        ),
        ("[plan]\nslider_force = 0.0\n", "plan.slider_force"),
    ];
    for (k, (plan, key)) in cases.iter().enumerate() {
        let scene = scene_file(
            dir.path(),
            &format!("s{k}.toml"),
            &format!("{text}\n{plan}"),
        );
        let out = dir.path().join(format!("out{k}"));
        let output = flexprr()
            .arg("plan")
            .arg(&scene)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        assert_eq!(output.status.code(), Some(2), "{}", stderr_of(&output));
        let stderr = stderr_of(&output);
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
        assert!(stderr.contains(key), "{stderr}");
        assert!(!out.exists());
    }
    // A deflection limit needs the flexible model that --no-flexible-check turns off.
    let scene = scene_file(
        dir.path(),
        "d.toml",
        &format!("{text}\n[plan]\nslider_speed = 1.0\ndeflection_limit = 1e-4\n"),
    );
    let out = dir.path().join("out_d");
    let output = flexprr()
        .args(["plan", "--no-flexible-check", "--out"])
        .arg(&out)
        .arg(&scene)
        .output()
        .unwrap();
    let stderr = stderr_of(&output);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("plan.deflection_limit"), "{stderr}");
    assert!(stderr.contains("--no-flexible-check"), "{stderr}");
    assert!(!out.exists());
    // `check` validates [plan] the same way.
    let scene = scene_file(
        dir.path(),
        "c.toml",
        &format!("{text}\n[plan]\nslider_speed = -2.0\n"),
    );
    let output = flexprr().arg("check").arg(&scene).output().unwrap();
    assert_eq!(output.status.code(), Some(2));
    assert!(stderr_of(&output).contains("plan.slider_speed"));
}
