//! `flexprr frf` through the program: the paper's modal test (configs/modal_test.toml)
//! against the pinned-pinned beam in closed form, the responses against the beam's modal
//! sum, the grid options, and bad input (exit 2, one line).
//!
//! With the sliders locked and the platform at rest, the coupled machine's chords are
//! fixed (three rigid chords hold the platform's three degrees of freedom), so each link is
//! a pinned-pinned Euler-Bernoulli beam: natural frequencies `f_k = k^2 pi / (2 l^2)
//! sqrt(EI / rho A)`, modes `sin(k pi xi)` with modal mass `rho A l / 2`, and with modal
//! damping `zeta` the accelerance between the hammer at `xi_f` and a point `xi` is
//! `sum_k -w^2 sin(k pi xi) sin(k pi xi_f) / ((rho A l / 2)(w_k^2 - w^2 + 2 i zeta w_k w))`
//! (the three sine modes the model has).

use crate::common::{config, flexprr, read_csv, stderr_of};
use std::path::Path;

use serde_json::Value;

/// The paper's link (docs/model.md): E, rho, l, thickness, height.
const E: f64 = 7.3e10;
const RHO: f64 = 2770.0;
const L: f64 = 0.2;
const T: f64 = 0.002;
const H: f64 = 0.03;

/// `f_k` of the pinned-pinned link (Hz).
fn pinned_pinned_hz(k: f64) -> f64 {
    let ei = E * H * T.powi(3) / 12.0;
    let rho_a = RHO * H * T;
    k * k * std::f64::consts::PI / (2.0 * L * L) * (ei / rho_a).sqrt()
}

/// The accelerance of the three-mode pinned-pinned link with 1 % modal damping:
/// `(re, im)`.
fn accelerance(f: f64, xi: f64, xi_f: f64) -> (f64, f64) {
    let modal_mass = RHO * H * T * L / 2.0;
    let w = std::f64::consts::TAU * f;
    let (mut re, mut im) = (0.0, 0.0);
    for k in 1..=3 {
        let k = f64::from(k);
        let wk = std::f64::consts::TAU * pinned_pinned_hz(k);
        let residue = (k * std::f64::consts::PI * xi).sin()
            * (k * std::f64::consts::PI * xi_f).sin()
            / modal_mass;
        let (a, b) = (wk * wk - w * w, 2.0 * 0.01 * wk * w);
        let d = a * a + b * b;
        re += -w * w * residue * a / d;
        im += w * w * residue * b / d;
    }
    (re, im)
}

fn read_json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[test]
fn the_modal_test_identifies_the_pinned_pinned_sines() {
    let out = tempfile::tempdir().unwrap();
    let output = flexprr()
        .args(["frf", "--config"])
        .arg(config("modal_test.toml"))
        .arg("--out")
        .arg(out.path())
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(0), "{}", stderr_of(&output));
    for name in [
        "frf.csv",
        "frf.json",
        "bode.svg",
        "mode_shapes.csv",
        "mode_shapes.svg",
    ] {
        assert!(out.path().join(name).is_file(), "{name}");
    }
    // The shapes at the nine points against the sines, normalised to 1 at their largest.
    let (header, rows) = read_csv(&out.path().join("mode_shapes.csv"));
    assert_eq!(header[..4], ["point", "xi", "mode_1", "sine_1"]);
    assert_eq!(rows.len(), 9);
    let mut worst = [0.0_f64; 2];
    for (p, row) in rows.iter().enumerate() {
        let xi = p as f64 / 8.0;
        assert!((row[1] - xi).abs() < 1e-12);
        let sines = [
            (std::f64::consts::PI * xi).sin(),
            (std::f64::consts::TAU * xi).sin(),
        ];
        for (m, sine) in sines.iter().enumerate() {
            worst[m] = worst[m].max((row[2 + 2 * m] - sine).abs());
        }
    }
    println!(
        "largest difference from sin(pi xi): {:.2e}, from sin(2 pi xi): {:.2e}",
        worst[0], worst[1]
    );
    assert!(worst[0] < 0.01 && worst[1] < 0.01, "{worst:?}");
    // The paper's observations: nothing moves at the joints (points 1, 9), and the second
    // mode's midpoint (point 5) is still. The slider joint is locked; the platform joint
    // moves with the platform on the links' axial springs, by a few thousandths of the
    // mid-span (`xi` times its motion at `xi = 1`, fifth decimal at point 2).
    println!(
        "mode 1 at the platform joint: {:.2e} of the largest",
        rows[8][2]
    );
    assert!(rows[0][2].abs() < 1e-9 && rows[8][2].abs() < 5e-3);
    assert!(rows[4][4].abs() < 1e-3);
    // The resonances picked from the responses against the closed form and the modes of
    // the linear model.
    let json = read_json(&out.path().join("frf.json"));
    let identified = json["identified"]["modes"].as_array().unwrap();
    for (k, m) in identified.iter().enumerate() {
        let f = m["frequency_hz"].as_f64().unwrap();
        let closed = pinned_pinned_hz(k as f64 + 1.0);
        let model = m["model_frequency_hz"].as_f64().unwrap();
        println!(
            "mode {}: {f:.4} Hz from the FRFs, {model:.4} Hz model, {closed:.4} Hz closed form",
            k + 1
        );
        assert!((f - closed).abs() < 1e-3 * closed, "{f} {closed}");
        assert!((f - model).abs() < 1e-3 * model, "{f} {model}");
        assert_eq!(m["sine_j"].as_u64(), Some(k as u64 + 1));
    }
    assert_eq!(
        json["operating_point"]["pose"]["phi_deg"].as_f64(),
        Some(45.0)
    );
    assert_eq!(json["model"], "coupled");
}

#[test]
fn the_responses_are_the_pinned_pinned_modal_sum() {
    let out = tempfile::tempdir().unwrap();
    let frequencies = out.path().join("f.txt");
    std::fs::write(
        &frequencies,
        "# Hz\n5\n50\n116.39\n300\n465.6\n800\n1047.5\n1500\n",
    )
    .unwrap();
    let outputs = [
        "acceleration:1@0.5",
        "acceleration:1@0.3",
        "acceleration:1@0.125",
    ];
    let mut command = flexprr();
    command
        .args(["frf", "--rigid-chords", "--config"])
        .arg(config("modal_test.toml"))
        .arg("--frequencies")
        .arg(&frequencies)
        .args(["--identify", "0"])
        .arg("--out")
        .arg(out.path().join("out"));
    for o in outputs {
        command.args(["--output", o]);
    }
    let output = command.output().unwrap();
    assert_eq!(output.status.code(), Some(0), "{}", stderr_of(&output));
    let (header, rows) = read_csv(&out.path().join("out/frf.csv"));
    assert_eq!(header[0], "f_Hz");
    assert_eq!(
        header[1],
        "acceleration_1_xi0.5_per_point_force_1_xi0.125_mag_m_s2_N"
    );
    assert_eq!(
        header[2],
        "acceleration_1_xi0.5_per_point_force_1_xi0.125_phase_deg"
    );
    assert_eq!(rows.len(), 8);
    let mut worst = 0.0_f64;
    for row in &rows {
        for (o, xi) in [0.5, 0.3, 0.125].into_iter().enumerate() {
            let (re, im) = accelerance(row[0], xi, 0.125);
            let (mag, phase) = (row[1 + 2 * o], row[2 + 2 * o].to_radians());
            let error = (mag * phase.cos() - re).hypot(mag * phase.sin() - im) / re.hypot(im);
            worst = worst.max(error);
        }
    }
    println!("largest relative difference from the modal sum: {worst:.2e}");
    assert!(worst < 1e-6, "{worst}");
}

#[test]
fn grids_follow_the_options() {
    let out = tempfile::tempdir().unwrap();
    let scene = config("coupled_f20.toml");
    let run = |args: &[&str], dir: &str| {
        let output = flexprr()
            .args(["frf", "--rigid-chords"])
            .arg(&scene)
            .args(["--pose", "-0.05,0.02,40", "--input", "slider_force:1"])
            .args([
                "--input",
                "point_force:2@0.3",
                "--output",
                "deflection:2@0.5",
            ])
            .args(args)
            .arg("--out")
            .arg(out.path().join(dir))
            .output()
            .unwrap();
        assert_eq!(
            output.status.code(),
            Some(0),
            "{args:?}: {}",
            stderr_of(&output)
        );
        let json = read_json(&out.path().join(dir).join("frf.json"));
        let (_, rows) = read_csv(&out.path().join(dir).join("frf.csv"));
        (json, rows.iter().map(|r| r[0]).collect::<Vec<f64>>())
    };
    let (json, f) = run(&["--from", "10", "--to", "20", "--points", "11"], "linear");
    assert_eq!(json["grid"]["kind"], "linear");
    assert_eq!(f, (10..=20).map(f64::from).collect::<Vec<_>>());
    let (json, f) = run(
        &["--from", "1", "--to", "1000", "--points", "4", "--log"],
        "log",
    );
    assert_eq!(json["grid"]["kind"], "log");
    for (got, want) in f.iter().zip([1.0, 10.0, 100.0, 1000.0]) {
        assert!((got - want).abs() < 1e-9 * want, "{got}");
    }
    // The default: 1 Hz to 1.5 x the highest of the 12 lowest modes (the nine bending
    // modes of the locked machine, the highest 1047.5 Hz), 2000 log-spaced points and 21
    // about each of the 3 distinct modes (each is three links' mode).
    let (json, f) = run(&[], "default");
    assert_eq!(json["grid"]["kind"], "default");
    let top = 1.5 * pinned_pinned_hz(3.0);
    assert!(
        (f[f.len() - 1] - top).abs() < 1e-3 * top,
        "{}",
        f[f.len() - 1]
    );
    assert_eq!(f.len(), 2000 + 3 * 21);
    assert!(f.windows(2).all(|w| w[1] > w[0]));
    // The slider force moves nothing on a locked machine; the link-2 force does.
    assert_eq!(json["columns"].as_array().unwrap().len(), 2);
    // Reading back an earlier frf.csv as the frequency file gives the same grid.
    let (_, g) = run(
        &[
            "--frequencies",
            out.path().join("log/frf.csv").to_str().unwrap(),
        ],
        "again",
    );
    let (_, f_log) = read_csv(&out.path().join("log/frf.csv"));
    assert_eq!(g, f_log.iter().map(|r| r[0]).collect::<Vec<_>>());
}

#[test]
fn bad_input_is_one_line_and_exit_two() {
    let out = tempfile::tempdir().unwrap();
    let scene = config("coupled_f20.toml");
    let bad_file = out.path().join("bad.txt");
    std::fs::write(&bad_file, "10\n20\nabc\n").unwrap();
    let bad_plan = out.path().join("plan.toml");
    std::fs::write(
        &bad_plan,
        "base = \"nowhere.toml\"\ninputs = [\"point_force:1@2\"]\n",
    )
    .unwrap();
    let bad_key = out.path().join("key.toml");
    std::fs::write(
        &bad_key,
        "pose = [0.0, 0.0, 45.0]\ninputs = [\"slider_force:1\", \"point_force:9@0.5\"]\n",
    )
    .unwrap();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec![
                "--input".into(),
                "point_force:4@0.5".into(),
                "--output".into(),
                "slider:1".into(),
            ],
            "point_force:4@0.5: the link must be 1, 2 or 3",
        ),
        (
            vec![
                "--input".into(),
                "slider_force:1".into(),
                "--output".into(),
                "platform:z".into(),
            ],
            "unknown output \"platform:z\"",
        ),
        (
            vec![
                "--input".into(),
                "slider_force:1".into(),
                "--output".into(),
                "slider:1".into(),
                "--pose".into(),
                "0,0".into(),
            ],
            "--pose \"0,0\": expected X_M,Y_M,PHI_DEG",
        ),
        (
            vec![
                "--input".into(),
                "slider_force:1".into(),
                "--output".into(),
                "slider:1".into(),
                "--pose".into(),
                "0,0,0".into(),
            ],
            "type-II",
        ),
        (
            vec![
                "--input".into(),
                "slider_force:1".into(),
                "--output".into(),
                "slider:1".into(),
                "--identify".into(),
                "2".into(),
            ],
            "--identify: identifying mode shapes needs outputs acceleration",
        ),
        (
            vec![
                "--input".into(),
                "slider_force:1".into(),
                "--output".into(),
                "slider:1".into(),
                "--from".into(),
                "100".into(),
                "--to".into(),
                "10".into(),
            ],
            "--to: 10 Hz: expected a finite frequency above --from",
        ),
        (
            vec![
                "--input".into(),
                "slider_force:1".into(),
                "--output".into(),
                "slider:1".into(),
                "--frequencies".into(),
                bad_file.display().to_string(),
            ],
            "bad.txt:3:1",
        ),
        (
            vec!["--input".into(), "slider_force:1".into()],
            "give at least one input and one output",
        ),
    ];
    for (args, expected) in cases {
        let output = flexprr()
            .arg("frf")
            .arg(&scene)
            .args(&args)
            .arg("--out")
            .arg(out.path().join("o"))
            .output()
            .unwrap();
        let stderr = stderr_of(&output);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
    }
    // A plan: its bad scene path, and a bad channel located at its line.
    let output = flexprr()
        .args(["frf", "--config"])
        .arg(&bad_plan)
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(2));
    assert!(
        stderr_of(&output).contains("nowhere.toml"),
        "{}",
        stderr_of(&output)
    );
    let output = flexprr()
        .arg("frf")
        .arg(&scene)
        .arg("--config")
        .arg(&bad_key)
        .output()
        .unwrap();
    let stderr = stderr_of(&output);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("key.toml:2:")
            && stderr.contains("inputs.1")
            && stderr.contains("point_force:9@0.5"),
        "{stderr}"
    );
    // A KED scene has no whole-machine linear model.
    let output = flexprr()
        .arg("frf")
        .arg(config("paper_f20.toml"))
        .args(["--input", "slider_force:1", "--output", "slider:1"])
        .arg("--out")
        .arg(out.path().join("k"))
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(2));
    assert!(stderr_of(&output).contains("model.coupling"));
    assert!(!out.path().join("o").exists() && !out.path().join("k").exists());
}

#[test]
fn a_failed_identification_keeps_the_responses_and_exits_one() {
    let out = tempfile::tempdir().unwrap();
    // Up to 300 Hz there is one resonance: the second cannot be identified.
    let output = flexprr()
        .args(["frf", "--config"])
        .arg(config("modal_test.toml"))
        .args(["--from", "1", "--to", "300", "--points", "600"])
        .arg("--out")
        .arg(out.path())
        .output()
        .unwrap();
    let stderr = stderr_of(&output);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("found 1 resonance(s)") && stderr.contains("116."),
        "{stderr}"
    );
    assert!(out.path().join("frf.csv").is_file() && out.path().join("bode.svg").is_file());
    assert!(!out.path().join("mode_shapes.svg").exists());
    let json = read_json(&out.path().join("frf.json"));
    assert!(json["identified"]["failed"].as_str().is_some());
}

/// Issue 35, item 1: a sampled law's frequency response is that of the discrete-time model
/// of its loop, `H(z)` at `z = exp(i w T)`, up to the Nyquist frequency: at 1 Hz slider 1
/// yields `1 / kp` to its own force (on main the held command made it a free mass, 3.4e-2
/// m/N at 1 Hz); the default grid stops at the Nyquist frequency and a grid beyond it is
/// refused.
#[test]
fn a_sampled_law_responds_as_its_discrete_loop_up_to_nyquist() {
    let out = tempfile::tempdir().unwrap();
    let scene = out.path().join("sampled.toml");
    let text = std::fs::read_to_string(config("servo_f20.toml"))
        .unwrap()
        .replace("period = 0 ", "period = 0.001 ");
    std::fs::write(&scene, text).unwrap();
    let run = |extra: &[&str], dir: &str| {
        flexprr()
            .arg("frf")
            .arg(&scene)
            .args(["--input", "slider_force:1", "--output", "slider:1"])
            .args(extra)
            .arg("--out")
            .arg(out.path().join(dir))
            .output()
            .unwrap()
    };
    let o = run(&["--from", "1", "--to", "2", "--points", "2"], "low");
    assert!(o.status.success(), "{}", stderr_of(&o));
    let (_, rows) = read_csv(&out.path().join("low").join("frf.csv"));
    let compliance = rows[0][1];
    println!("|H| at 1 Hz: {compliance:.6e} m/N (1/kp = 5e-6)");
    assert!((compliance / 5e-6 - 1.0).abs() < 1e-3, "{compliance}");
    let json = read_json(&out.path().join("low").join("frf.json"));
    assert_eq!(json["dt_s"], 1e-3);
    let o = run(&[], "default");
    assert!(o.status.success(), "{}", stderr_of(&o));
    let (_, rows) = read_csv(&out.path().join("default").join("frf.csv"));
    let top = rows.last().unwrap()[0];
    assert!(top <= 500.0 && top > 400.0, "{top}");
    let o = run(&["--to", "600"], "beyond");
    assert_eq!(o.status.code(), Some(2));
    let err = stderr_of(&o);
    assert!(
        err.contains("--to") && err.contains("Nyquist frequency 500 Hz"),
        "{err}"
    );
}
