//! `flexprr study` of a workspace map (docs/studies.md, "Workspace maps"): its value at a
//! grid pose is what `flexprr modes --pose` gives there, its files and summary, and the
//! options a map refuses.

use crate::common::{config, flexprr};
use std::path::{Path, PathBuf};

/// A 5 x 4 map of the servo scene at phi = 30 deg, written beside a copy of nothing: the
/// base is the shipped servo scene by its absolute path.
fn map_study(dir: &Path) -> PathBuf {
    let study = dir.join("map.toml");
    std::fs::write(
        &study,
        format!(
            "base = {:?}\n[map]\nx = {{ start = -0.12, end = 0.08, count = 5 }}\ny = {{ start = -0.06, end = 0.06, count = 4 }}\nphi_deg = 30.0\n",
            config("servo_f20.toml").display().to_string()
        ),
    )
    .unwrap();
    study
}

#[test]
fn the_map_at_a_grid_pose_is_flexprr_modes_there() {
    let dir = tempfile::tempdir().unwrap();
    let study = map_study(dir.path());
    let out = dir.path().join("out");
    let o = flexprr()
        .args([
            "study",
            study.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        stdout.starts_with("map: 20 poses at phi = 30 deg ("),
        "{stdout}"
    );
    let text = std::fs::read_to_string(out.join("map.csv")).unwrap();
    let mut checked = 0;
    for line in text.lines().skip(1) {
        let cells: Vec<&str> = line.split(',').collect();
        if cells[3] != "ok" {
            continue;
        }
        let pose = format!("{},{},{}", cells[0], cells[1], cells[2]);
        let m = flexprr()
            .args([
                "modes",
                config("servo_f20.toml").to_str().unwrap(),
                "--pose",
                &pose,
                "--json",
            ])
            .output()
            .unwrap();
        assert!(m.status.success(), "{}", String::from_utf8_lossy(&m.stderr));
        let value: serde_json::Value = serde_json::from_slice(&m.stdout).unwrap();
        let lowest = &value["modes"][0];
        let (f, zeta): (f64, f64) = (cells[4].parse().unwrap(), cells[5].parse().unwrap());
        let expected_f = lowest["frequency_hz"].as_f64().unwrap();
        let expected_zeta = lowest["damping_ratio"].as_f64().unwrap();
        // map.csv keeps 10 significant digits.
        assert!(
            ((f - expected_f) / expected_f).abs() < 1e-9,
            "{pose}: {f} vs {expected_f}"
        );
        assert!(
            (zeta - expected_zeta).abs() < 1e-9,
            "{pose}: {zeta} vs {expected_zeta}"
        );
        checked += 1;
    }
    assert!(checked >= 15, "{checked} poses checked");
    for name in ["map.json", "map.svg", ".flexprr-output.json"] {
        assert!(out.join(name).is_file(), "{name}");
    }
}

#[test]
fn a_map_refuses_shards_and_resume() {
    let dir = tempfile::tempdir().unwrap();
    let study = map_study(dir.path());
    for extra in [["--shard", "1/2"], ["--resume", "--quiet"]] {
        let out = dir.path().join("out");
        let o = flexprr()
            .args([
                "study",
                study.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ])
            .args(extra)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains("cannot be sharded or resumed"), "{err}");
        assert!(!out.exists());
    }
}

/// Issue 34, item 6: a map whose poses are all type-II singular is refused as singular,
/// not as out of reach (on main: "none of the poses is within reach").
#[test]
fn a_map_of_singular_poses_says_singular() {
    let dir = tempfile::tempdir().unwrap();
    let study = dir.path().join("singular.toml");
    std::fs::write(
        &study,
        format!(
            "base = {:?}\n[map]\nx = {{ start = -0.01, end = 0.01, count = 3 }}\ny = {{ start = -0.01, end = 0.01, count = 3 }}\nphi_deg = 0.0\n",
            config("servo_f20.toml").display().to_string()
        ),
    )
    .unwrap();
    let o = flexprr()
        .args(["study", study.to_str().unwrap(), "--out"])
        .arg(dir.path().join("out"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("9 are singular") && err.contains("type-II") && err.contains("0 out of reach"),
        "{err}"
    );
    assert!(!err.contains("is within reach"), "{err}");
    // An orientation of many turns is refused at its key.
    std::fs::write(
        &study,
        format!(
            "base = {:?}\n[map]\nx = {{ start = -0.01, end = 0.01, count = 3 }}\ny = {{ start = -0.01, end = 0.01, count = 3 }}\nphi_deg = 1e6\n",
            config("servo_f20.toml").display().to_string()
        ),
    )
    .unwrap();
    let o = flexprr()
        .args(["study", study.to_str().unwrap(), "--out"])
        .arg(dir.path().join("out2"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("map.phi_deg") && err.contains("more than two turns"),
        "{err}"
    );
}
