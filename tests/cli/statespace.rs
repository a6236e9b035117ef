//! `flexprr statespace` through the program: `statespace.npz` parsed back here with a ZIP
//! and `.npy` reader of this test's own (CRC-32 bit by bit, not by table), against
//! `statespace.json`, the run layer's linear model of the same scene and pose, and a closed
//! form: the servo scene's static compliance of a slider under its own force.
//!
//! With the chords axially rigid, a force `F` on slider 1 of the machine at rest under PD
//! springs `kp` on every slider leaves the platform free of external load, so at
//! equilibrium the three chord tensions vanish (they could only balance each other at a
//! singular pose): sliders 2 and 3 carry no force and stay, and slider 1 moves `F / kp`.
//! The static gain `-C A^-1 B + D` of `slider:1` per `slider_force:1` is `1 / kp`.

use crate::common::config;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

use flexprr_kinematics::Pose;
use flexprr_linear::{Input, Output};
use flexprr_linear_tools::linear::{OperatingPoint, linear_model};
use flexprr_scene::Scene;
use nalgebra::DMatrix;
use serde_json::Value;

/// CRC-32 (ISO 3309), bit by bit.
fn crc32_bitwise(bytes: &[u8]) -> u32 {
    let mut crc = 0xFFFF_FFFFu32;
    for b in bytes {
        crc ^= u32::from(*b);
        for _ in 0..8 {
            let mask = (crc & 1).wrapping_neg();
            crc = (crc >> 1) ^ (0xEDB8_8320 & mask);
        }
    }
    !crc
}

fn u16_at(b: &[u8], k: usize) -> usize {
    usize::from(u16::from_le_bytes([b[k], b[k + 1]]))
}

fn u32_at(b: &[u8], k: usize) -> usize {
    u32::from_le_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]) as usize
}

/// The entries of a stored ZIP archive, through its central directory, each checked
/// against its local header and its CRC.
fn unzip(bytes: &[u8]) -> BTreeMap<String, Vec<u8>> {
    let end = bytes.len() - 22;
    assert_eq!(u32_at(bytes, end), 0x0605_4b50, "end of central directory");
    let (entries, size, offset) = (
        u16_at(bytes, end + 10),
        u32_at(bytes, end + 12),
        u32_at(bytes, end + 16),
    );
    assert_eq!(offset + size, end);
    let mut files = BTreeMap::new();
    let mut k = offset;
    for _ in 0..entries {
        assert_eq!(u32_at(bytes, k), 0x0201_4b50, "central directory entry");
        assert_eq!(u16_at(bytes, k + 10), 0, "stored");
        let (crc, compressed, size) = (
            u32_at(bytes, k + 16),
            u32_at(bytes, k + 20),
            u32_at(bytes, k + 24),
        );
        let name_len = u16_at(bytes, k + 28);
        let extra = u16_at(bytes, k + 30) + u16_at(bytes, k + 32);
        let local = u32_at(bytes, k + 42);
        let name = std::str::from_utf8(&bytes[k + 46..k + 46 + name_len])
            .unwrap()
            .to_string();
        assert_eq!(compressed, size);
        assert_eq!(u32_at(bytes, local), 0x0403_4b50, "local header");
        assert_eq!(u32_at(bytes, local + 14), crc);
        let data_at = local + 30 + u16_at(bytes, local + 26) + u16_at(bytes, local + 28);
        let data = bytes[data_at..data_at + size].to_vec();
        assert_eq!(crc32_bitwise(&data) as usize, crc, "{name}: CRC-32");
        files.insert(name, data);
        k += 46 + name_len + extra;
    }
    files
}

/// An `.npy` array: its dtype, shape, and values (numbers or strings).
#[derive(Debug)]
enum Array {
    Numbers(Vec<usize>, Vec<f64>),
    Strings(Vec<String>),
}

fn npy(bytes: &[u8]) -> Array {
    assert_eq!(&bytes[..8], b"\x93NUMPY\x01\x00");
    let len = u16_at(bytes, 8);
    assert_eq!((10 + len) % 64, 0, "aligned data");
    let header = std::str::from_utf8(&bytes[10..10 + len]).unwrap();
    assert!(header.ends_with('\n') && header.contains("'fortran_order': False"));
    let field = |key: &str| {
        let at = header.find(key).unwrap() + key.len();
        header[at..].trim_start().to_string()
    };
    let descr = field("'descr':");
    let shape_text = field("'shape':");
    let shape: Vec<usize> = shape_text[1..shape_text.find(')').unwrap()]
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|s| s.trim().parse().unwrap())
        .collect();
    let data = &bytes[10 + len..];
    if descr.starts_with("'<f8'") {
        let values: Vec<f64> = data
            .chunks_exact(8)
            .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
            .collect();
        assert_eq!(values.len(), shape.iter().product::<usize>());
        Array::Numbers(shape, values)
    } else {
        assert!(descr.starts_with("'<U"), "{descr}");
        let width: usize = descr[3..].split('\'').next().unwrap().parse().unwrap();
        let strings = data
            .chunks_exact(4 * width)
            .map(|c| {
                c.chunks_exact(4)
                    .map(|u| u32::from_le_bytes(u.try_into().unwrap()))
                    .take_while(|u| *u != 0)
                    .map(|u| char::from_u32(u).unwrap())
                    .collect()
            })
            .collect::<Vec<String>>();
        assert_eq!(strings.len(), shape[0]);
        Array::Strings(strings)
    }
}

fn matrix(array: &Array) -> DMatrix<f64> {
    match array {
        Array::Numbers(shape, v) => DMatrix::from_row_slice(shape[0], shape[1], v),
        Array::Strings(_) => panic!("expected numbers"),
    }
}

fn json_matrix(v: &Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            r.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        })
        .collect();
    let cols = rows.first().map_or(0, Vec::len);
    DMatrix::from_fn(rows.len(), cols, |i, j| rows[i][j])
}

#[test]
fn the_npz_holds_the_linear_model_and_its_static_compliance_is_one_over_kp() {
    let out = tempfile::tempdir().unwrap();
    let scene_path = config("servo_f20.toml");
    let status = Command::new(env!("CARGO_BIN_EXE_flexprr"))
        .arg("statespace")
        .arg(&scene_path)
        .args(["--pose", "-0.05,0.02,40"])
        .args(["--input", "slider_force:1", "--input", "point_force:2@0.25"])
        .args(["--output", "slider:1", "--output", "platform:phi"])
        .args([
            "--output",
            "deflection:2@0.5",
            "--output",
            "acceleration:2@0.5",
        ])
        .arg("--out")
        .arg(out.path())
        .output()
        .unwrap();
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let files = unzip(&std::fs::read(out.path().join("statespace.npz")).unwrap());
    let names: Vec<&str> = files.keys().map(String::as_str).collect();
    for name in [
        "A.npy",
        "B.npy",
        "C.npy",
        "D.npy",
        "inputs.npy",
        "outputs.npy",
        "states.npy",
        "x0.npy",
        "y0.npy",
    ] {
        assert!(names.contains(&name), "{name} in {names:?}");
    }
    let arrays: BTreeMap<String, Array> = files
        .iter()
        .map(|(k, v)| (k.trim_end_matches(".npy").to_string(), npy(v)))
        .collect();
    let (a, b, c, d) = (
        matrix(&arrays["A"]),
        matrix(&arrays["B"]),
        matrix(&arrays["C"]),
        matrix(&arrays["D"]),
    );
    // The scaled realisation (the default): x = s * x~ with powers of two.
    let Array::Numbers(_, scale) = &arrays["state_scale"] else {
        panic!()
    };
    assert!(
        scale
            .iter()
            .all(|s| *s > 0.0 && s.log2().fract().abs() < 1e-15),
        "{scale:?}"
    );
    let Array::Numbers(dt_shape, dt) = &arrays["dt"] else {
        panic!()
    };
    assert!(
        dt_shape.is_empty() && dt[0].abs() <= 0.0,
        "continuous: {dt:?}"
    );
    let Array::Strings(inputs) = &arrays["inputs"] else {
        panic!()
    };
    let Array::Strings(outputs) = &arrays["outputs"] else {
        panic!()
    };
    assert_eq!(inputs, &["slider_force:1", "point_force:2@0.25"]);
    assert_eq!(outputs[3], "acceleration:2@0.5");
    let Array::Strings(states) = &arrays["states"] else {
        panic!()
    };
    assert_eq!(states.len(), a.nrows());
    // The JSON holds the same numbers (written as the shortest exact decimals; serde_json's
    // default reader may land one ulp off).
    let json: Value =
        serde_json::from_str(&std::fs::read_to_string(out.path().join("statespace.json")).unwrap())
            .unwrap();
    for (key, m) in [("A", &a), ("B", &b), ("C", &c), ("D", &d)] {
        let from_json = json_matrix(&json[key]);
        assert_eq!(from_json.shape(), m.shape(), "{key}");
        for (x, y) in from_json.iter().zip(m.iter()) {
            assert!(
                (x - y).abs() <= 4.0 * f64::EPSILON * y.abs(),
                "{key}: {x} {y}"
            );
        }
    }
    assert_eq!(json["outputs"][1]["unit"], "rad");
    // The run layer's linear model of the same scene and pose, bit for bit once the
    // scaling (powers of two: exact) is undone.
    let a = DMatrix::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)] * scale[i] / scale[j]);
    let b = DMatrix::from_fn(b.nrows(), b.ncols(), |i, j| b[(i, j)] * scale[i]);
    let c = DMatrix::from_fn(c.nrows(), c.ncols(), |i, j| c[(i, j)] / scale[j]);
    let scene = Scene::load(&scene_path).unwrap();
    let lin = linear_model(
        &scene,
        OperatingPoint::Rest(Pose::new(-0.05, 0.02, 40f64.to_radians())),
        &[
            Input::SliderForce(0),
            Input::PointForce { link: 1, xi: 0.25 },
        ],
        &[
            Output::SliderPosition(0),
            Output::Platform(flexprr_linear::Axis::Phi),
            Output::Deflection { link: 1, xi: 0.5 },
            Output::Acceleration { link: 1, xi: 0.5 },
        ],
        &flexprr_linear::Settings::default(),
    )
    .unwrap();
    assert_eq!(
        a,
        DMatrix::from_fn(a.nrows(), a.ncols(), |i, j| lin.a[(i, j)])
    );
    assert_eq!(
        c,
        DMatrix::from_fn(c.nrows(), c.ncols(), |i, j| lin.c[(i, j)])
    );
    // The static gain of slider 1 per its own force: 1 / kp (kp = 2e5 N/m).
    let static_gain = -(&c * a.clone().lu().solve(&b).unwrap()) + &d;
    let compliance = static_gain[(0, 0)];
    println!("static compliance of slider 1: {compliance:.10e} m/N, 1/kp = 5e-6");
    assert!((compliance - 5e-6).abs() < 1e-9 * 5e-6, "{compliance}");
}

#[test]
fn bad_channels_are_refused_before_any_work() {
    let out = tempfile::tempdir().unwrap();
    let output = Command::new(env!("CARGO_BIN_EXE_flexprr"))
        .arg("statespace")
        .arg(config("servo_f20.toml"))
        .args(["--input", "slider_force:0", "--output", "slider:1"])
        .arg("--out")
        .arg(out.path().join("x"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2));
    assert_eq!(
        stderr.trim(),
        "error: slider_force:0: the slider must be 1, 2 or 3"
    );
    assert!(!out.path().join("x").exists());
}

/// Runs `flexprr statespace` with `args` into a fresh directory; the exit code, stdout,
/// stderr and the directory.
fn statespace(args: &[&str]) -> (Option<i32>, String, String, tempfile::TempDir) {
    let out = tempfile::tempdir().unwrap();
    let output = Command::new(env!("CARGO_BIN_EXE_flexprr"))
        .arg("statespace")
        .args(args)
        .arg("--out")
        .arg(out.path().join("ss"))
        .output()
        .unwrap();
    (
        output.status.code(),
        String::from_utf8_lossy(&output.stdout).into_owned(),
        String::from_utf8_lossy(&output.stderr).into_owned(),
        out,
    )
}

/// Issue 35, item 8: a model without inputs or outputs is refused, as `flexprr frf`
/// refuses it (on main it wrote an A-only model and exited 0).
#[test]
fn a_model_without_channels_is_refused() {
    let scene = config("servo_f20.toml");
    let scene = scene.to_str().unwrap();
    for args in [
        vec![scene],
        vec![scene, "--input", "slider_force:1"],
        vec![scene, "--output", "slider:1"],
    ] {
        let (code, _, stderr, out) = statespace(&args);
        assert_eq!(code, Some(2), "{args:?}: {stderr}");
        assert!(
            stderr.contains("give at least one input and one output")
                && stderr.trim().lines().count() == 1,
            "{stderr}"
        );
        assert!(!out.path().join("ss").exists());
    }
}

/// The 2-norm condition number of a square matrix (its singular values).
fn condition(a: &DMatrix<f64>) -> f64 {
    let s = a.clone().svd(false, false).singular_values;
    s.max() / s.min()
}

/// Issue 35, item 5: the exported `A` of every shipped coupled and nonlinear scene has a
/// condition number of at most 1e7 in the default (scaled) realisation, where the
/// physical one reaches 1e8 to 1e13; both realisations have the same transfer at a
/// frequency (checked here at the static gain of the servo scene: 1 / kp).
#[test]
fn the_scaled_export_is_well_conditioned_on_every_shipped_scene() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs");
    let mut checked = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        let coupled =
            text.contains("coupling = \"coupled\"") || text.contains("coupling = \"nonlinear\"");
        let study = path
            .file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with("study_"));
        if !coupled || study {
            continue;
        }
        let scene = path.to_str().unwrap();
        let mut cond = [0.0; 2];
        for (k, realization) in ["scaled", "physical"].iter().enumerate() {
            let (code, _, stderr, out) = statespace(&[
                scene,
                "--input",
                "slider_force:1",
                "--output",
                "slider:1",
                "--realization",
                realization,
            ]);
            assert_eq!(code, Some(0), "{scene}: {stderr}");
            let files =
                unzip(&std::fs::read(out.path().join("ss").join("statespace.npz")).unwrap());
            cond[k] = condition(&matrix(&npy(&files["A.npy"])));
        }
        println!(
            "{}: cond(A) scaled {:.2e}, physical {:.2e}",
            path.file_name().unwrap().to_string_lossy(),
            cond[0],
            cond[1]
        );
        assert!(cond[0] <= 1e7, "{scene}: {}", cond[0]);
        checked += 1;
    }
    assert!(checked >= 5, "{checked} scenes");
}

/// Issue 35, item 7: `--times START:END:STEP` gives A(t) .. D(t) on a leading time axis from
/// one integration, each equal (to the integration's tolerance) to the model `--time` gives
/// at that instant by an integration of its own.
#[test]
fn models_along_the_motion_come_from_one_integration() {
    let scene = config("servo_f20.toml");
    let scene = scene.to_str().unwrap();
    let channels = [
        "--input",
        "slider_force:1",
        "--output",
        "slider:1",
        "--output",
        "deflection:1@0.5",
    ];
    let mut args = vec![
        scene,
        "--times",
        "0.002:0.01:0.004",
        "--realization",
        "physical",
    ];
    args.extend(channels);
    let (code, stdout, stderr, out) = statespace(&args);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(
        stdout.contains("3 times") && stdout.contains("one integration"),
        "{stdout}"
    );
    let files = unzip(&std::fs::read(out.path().join("ss").join("statespace.npz")).unwrap());
    let Array::Numbers(shape, values) = npy(&files["A.npy"]) else {
        panic!()
    };
    let Array::Numbers(_, t) = npy(&files["t.npy"]) else {
        panic!()
    };
    assert_eq!(shape.len(), 3);
    assert_eq!(shape[0], 3);
    let n = shape[1];
    for (k, time) in t.iter().enumerate() {
        let time = format!("{time}");
        let mut one = vec![scene, "--time", &time, "--realization", "physical"];
        one.extend(channels);
        let (code, _, stderr, single) = statespace(&one);
        assert_eq!(code, Some(0), "{stderr}");
        let files = unzip(&std::fs::read(single.path().join("ss").join("statespace.npz")).unwrap());
        let a = matrix(&npy(&files["A.npy"]));
        let largest = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut worst = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                worst = worst.max((values[k * n * n + i * n + j] - a[(i, j)]).abs());
            }
        }
        println!("t = {time} s: largest difference {worst:.2e} of {largest:.2e}");
        assert!(worst <= 1e-6 * largest, "t = {time}: {worst} of {largest}");
    }
}

/// Issue 35, item 1: a sampled law gives the discrete-time model: `dt` in the files, and
/// its modes are the poles z of the sampled loop.
#[test]
fn a_sampled_law_exports_its_discrete_time_model() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(config("servo_f20.toml"))
        .unwrap()
        .replace("period = 0 ", "period = 0.001 ");
    let path = dir.path().join("sampled.toml");
    std::fs::write(&path, text).unwrap();
    let (code, stdout, stderr, out) = statespace(&[
        path.to_str().unwrap(),
        "--input",
        "slider_force:1",
        "--output",
        "slider:1",
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(stdout.contains("discrete time at dt = 0.001 s"), "{stdout}");
    let files = unzip(&std::fs::read(out.path().join("ss").join("statespace.npz")).unwrap());
    let Array::Numbers(_, dt) = npy(&files["dt.npy"]) else {
        panic!()
    };
    assert!((dt[0] - 1e-3).abs() < 1e-18);
    let json: Value = serde_json::from_str(
        &std::fs::read_to_string(out.path().join("ss").join("statespace.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(json["dt_s"], 1e-3);
    assert!(json["form"].as_str().unwrap().starts_with("x[k+1]"));
    // The static gain of the discrete model, C (I - A)^-1 B + D, is the continuous one:
    // 1 / kp for slider 1's own force.
    let (a, b, c, d) = (
        matrix(&npy(&files["A.npy"])),
        matrix(&npy(&files["B.npy"])),
        matrix(&npy(&files["C.npy"])),
        matrix(&npy(&files["D.npy"])),
    );
    let identity = DMatrix::<f64>::identity(a.nrows(), a.ncols());
    let gain = &c * (identity - &a).lu().solve(&b).unwrap() + &d;
    assert!(
        (gain[(0, 0)] - 5e-6).abs() < 1e-6 * 5e-6,
        "{}",
        gain[(0, 0)]
    );
}
