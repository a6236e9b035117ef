//! `flexprr modes` (docs/linear.md): the locked machine at rest against the pinned-pinned
//! closed form, the JSON's shape and order, the files of `--out`, and every refusal (exit
//! code 2, one line naming the option or the scene key and the rule).

use crate::common::{config, flexprr};
use std::f64::consts::PI;
use std::process::Output;

fn modes(args: &[&str]) -> Output {
    flexprr().arg("modes").args(args).output().expect("runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The whole standard output as JSON (nothing else may be printed there).
fn json(o: &Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", stderr(o));
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| {
        panic!(
            "stdout is not one JSON document ({e}): {}",
            String::from_utf8_lossy(&o.stdout)
        )
    })
}

/// `(frequency_hz, damping_ratio)` of each mode of `{"modes": [...]}`.
fn frequencies(value: &serde_json::Value) -> Vec<(f64, f64)> {
    value["modes"]
        .as_array()
        .expect("modes")
        .iter()
        .map(|m| {
            (
                m["frequency_hz"].as_f64().expect("frequency_hz"),
                m["damping_ratio"].as_f64().expect("damping_ratio"),
            )
        })
        .collect()
}

/// A refusal: exit code 2 and one line on stderr holding every word of `needles`.
fn refused(o: &Output, needles: &[&str]) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "one line: {err}");
    for n in needles {
        assert!(err.contains(n), "{n:?} not in {err}");
    }
    assert!(o.stdout.is_empty(), "nothing on stdout when refused");
}

/// With the sliders locked, the platform at rest and the chords kept rigid
/// (`--rigid-chords`), the platform cannot move and each link is a pinned-pinned
/// Euler-Bernoulli beam without axial load: `f_n = (n^2 pi / 2 l^2) sqrt(EI / rho A)`
/// (116.39, 465.57, 1047.52 Hz for the paper's link, Blevins, *Formulas for natural
/// frequency and mode shape*, table 8-1), each three times, at any pose. The sine basis holds
/// these shapes exactly, so the only error is the linearisation's. By default the chords are
/// the links' axial springs: the same nine within 0.6 % (the platform's axial modes pull the
/// third family down), and three platform modes above them.
#[test]
fn locked_machine_at_rest_has_the_pinned_pinned_frequencies() {
    let (e, rho, t, l): (f64, f64, f64, f64) = (7.3e10, 2770.0, 0.002, 0.2);
    let c = t * (e / (12.0 * rho)).sqrt();
    for pose in ["0,0,45", "-0.05,0.02,30", "0.03,-0.04,60"] {
        let elastic = frequencies(&json(&modes(&[
            config("coupled_f20.toml").to_str().unwrap(),
            "--pose",
            pose,
            "--json",
        ])));
        assert_eq!(elastic.len(), 12, "{pose}: 9 bending and 3 platform modes");
        let value = json(&modes(&[
            config("coupled_f20.toml").to_str().unwrap(),
            "--pose",
            pose,
            "--json",
            "--rigid-chords",
        ]));
        let found = frequencies(&value);
        assert_eq!(found.len(), 9, "{pose}: 3 links x 3 modes");
        for ((f, _), (g, _)) in found.iter().zip(&elastic) {
            assert!(
                g <= f && (f - g) / f < 6e-3,
                "{pose}: {g} Hz against {f} Hz"
            );
        }
        assert!(elastic[9].0 > 1.2 * found[8].0, "{pose}: {:?}", elastic[9]);
        for (k, (f, zeta)) in found.iter().enumerate() {
            let n = (k / 3 + 1) as f64;
            let exact = n * n * PI / (2.0 * l * l) * c;
            assert!(
                ((f - exact) / exact).abs() < 1e-6,
                "{pose}, mode {}: {f} Hz against {exact} Hz",
                k + 1
            );
            assert!(zeta.abs() < 1e-6, "{pose}: undamped, got {zeta}");
        }
    }
}

/// `--json` prints `{"modes": [...]}` and nothing else: each mode with `frequency_hz` and
/// `damping_ratio`, sorted by frequency, no zero-frequency mode, and the two numbers agree
/// with the eigenvalue printed beside them (`|lambda| / 2 pi`, `-Re lambda / |lambda|`).
#[test]
fn json_is_the_modes_sorted_with_matlab_damp_definitions() {
    let value = json(&modes(&[
        config("servo_f20.toml").to_str().unwrap(),
        "--pose",
        "-0.1,0,45",
        "--json",
        "--count",
        "50",
    ]));
    let object = value.as_object().expect("an object");
    assert_eq!(object.keys().collect::<Vec<_>>(), ["modes"]);
    let list = value["modes"].as_array().unwrap();
    assert_eq!(
        list.len(),
        24,
        "9 bending, 3 servo, 3 platform and 9 axial link modes (state of 48)"
    );
    let mut last = 0.0;
    for m in list {
        let f = m["frequency_hz"].as_f64().unwrap();
        let zeta = m["damping_ratio"].as_f64().unwrap();
        let (re, im) = (
            m["eigenvalue"][0].as_f64().unwrap(),
            m["eigenvalue"][1].as_f64().unwrap(),
        );
        let modulus = re.hypot(im);
        assert!(
            f > 1.0 && f >= last,
            "sorted, no rigid mode: {f} after {last}"
        );
        assert!((f - modulus / (2.0 * PI)).abs() <= 1e-12 * f);
        assert!((zeta + re / modulus).abs() <= 1e-12);
        assert!(m["kind"].is_string());
        last = f;
    }
    // The PD servo (kd = 400 N s/m) damps the three lowest modes, which move the sliders.
    for m in &list[..3] {
        assert_eq!(m["kind"], "servo", "{m}");
        assert!(m["damping_ratio"].as_f64().unwrap() > 0.1);
    }
    let three = json(&modes(&[
        config("servo_f20.toml").to_str().unwrap(),
        "--pose",
        "-0.1,0,45",
        "--json",
        "--count",
        "3",
    ]));
    assert_eq!(frequencies(&three), frequencies(&value)[..3]);
}

#[test]
fn the_default_operating_point_is_the_start_pose_at_rest() {
    // coupled_f20's circle starts at (0, 0) with phi = 45 deg.
    let default = json(&modes(&[
        config("servo_f20.toml").to_str().unwrap(),
        "--json",
    ]));
    let explicit = json(&modes(&[
        config("servo_f20.toml").to_str().unwrap(),
        "--pose",
        "0,0,45",
        "--json",
    ]));
    assert_eq!(frequencies(&default), frequencies(&explicit));
}

#[test]
fn out_writes_json_csv_and_svg_through_the_output_policy() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("modes");
    let scene = config("servo_f20.toml");
    let o = modes(&[
        scene.to_str().unwrap(),
        "--pose",
        "-0.05,0,45",
        "--out",
        out.to_str().unwrap(),
        "--count",
        "7",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            ".flexprr-output.json",
            "modes.csv",
            "modes.json",
            "modes.svg"
        ]
    );
    let file: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("modes.json")).unwrap()).unwrap();
    let printed = json(&modes(&[
        scene.to_str().unwrap(),
        "--pose",
        "-0.05,0,45",
        "--json",
        "--count",
        "7",
    ]));
    assert_eq!(frequencies(&file), frequencies(&printed));
    assert_eq!(file["operating_point"]["kind"], "rest");
    assert_eq!(file["operating_point"]["pose"]["x_m"], -0.05);
    let xi = file["xi"].as_array().unwrap();
    assert_eq!(xi.len(), 21);
    for m in file["modes"].as_array().unwrap() {
        let links = m["shape"]["links"].as_array().unwrap();
        assert_eq!(links.len(), 3);
        for w in links {
            let w = w.as_array().unwrap();
            assert_eq!(w.len(), 21);
            // Pinned at both ends: no deflection from the chord at xi = 0 and 1.
            assert!(w[0].as_f64().unwrap().abs() < 1e-9 && w[20].as_f64().unwrap().abs() < 1e-9);
        }
    }
    let csv = std::fs::read_to_string(out.join("modes.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 7);
    assert!(csv.starts_with("mode,frequency_Hz,damping_ratio,"));
    let svg = std::fs::read_to_string(out.join("modes.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("(f) ") && !svg.contains("(g) "));
    // Run again into its own output: replaced. A foreign directory is refused.
    assert!(
        modes(&[scene.to_str().unwrap(), "--out", out.to_str().unwrap()])
            .status
            .success()
    );
    let foreign = dir.path().join("foreign");
    std::fs::create_dir(&foreign).unwrap();
    std::fs::write(foreign.join("notes.txt"), "mine").unwrap();
    let o = modes(&[scene.to_str().unwrap(), "--out", foreign.to_str().unwrap()]);
    refused(&o, &["--force"]);
    assert_eq!(
        std::fs::read_to_string(foreign.join("notes.txt")).unwrap(),
        "mine"
    );
}

#[test]
fn bad_options_are_refused_naming_the_option() {
    let scene = config("coupled_f20.toml");
    let s = scene.to_str().unwrap();
    refused(
        &modes(&[s, "--pose", "0,0,45", "--time", "0.01"]),
        &["--pose", "--time", "exclusive"],
    );
    refused(
        &modes(&[s, "--pose", "0,0"]),
        &["--pose", "X_M,Y_M,PHI_DEG"],
    );
    refused(&modes(&[s, "--pose", "0,nan,45"]), &["--pose"]);
    refused(&modes(&[s, "--time", "soon"]), &["--time", "seconds"]);
    refused(
        &modes(&[s, "--time", "5"]),
        &["--time", "outside the scene's time span"],
    );
    refused(&modes(&[s, "--count", "0"]), &["--count", "at least 1"]);
    // Out of reach, and the radial layout's home pose, which is type-II singular.
    refused(
        &modes(&[s, "--pose", "0.5,0,45"]),
        &["--pose 0.5,0,45", "cannot hold"],
    );
    refused(
        &modes(&[s, "--pose", "0,0,0"]),
        &["--pose 0,0,0", "type-II", "singularity"],
    );
}

#[test]
fn a_ked_scene_is_refused_at_its_coupling() {
    let o = modes(&[config("paper_f20.toml").to_str().unwrap(), "--json"]);
    refused(
        &o,
        &["paper_f20.toml:", "model.coupling", "KED", "\"coupled\""],
    );
}

/// Along the motion: the state at a time, integrated from the start, with the motion's
/// loads; inside the span it gives the same nine bending families near the rest values.
#[test]
fn time_linearises_the_motion_at_that_instant() {
    let value = json(&modes(&[
        config("coupled_f20.toml").to_str().unwrap(),
        "--time",
        "0.0125",
        "--json",
    ]));
    let found = frequencies(&value);
    assert_eq!(found.len(), 9);
    // The axial loads of the 20 Hz circle shift the first family by up to about 20 %
    // (docs/paper-reproduction.md), but not beyond the family's neighbours.
    for (k, (f, _)) in found.iter().enumerate() {
        let n = (k / 3 + 1) as f64;
        let rest = n * n * 116.39;
        assert!((f / rest - 1.0).abs() < 0.3, "mode {}: {f} Hz", k + 1);
    }
}

/// The `machine_frequencies` output of a scene at rest, at its first instant, is what
/// `flexprr modes --pose` gives at that pose: the same model, linearised about the same
/// state (the one reached by integration, the other built at rest).
#[test]
fn machine_frequencies_at_rest_equal_modes_at_the_pose() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("servo_rest.toml");
    std::fs::write(
        &scene,
        r#"
[trajectory]
kind = "line"
from = [-0.08, 0.03, 40.0]
velocity = [0.0, 0.0, 0.0]
[model]
formulation = "consistent"
coupling = "coupled"
[actuators]
kind = "force"
[control]
kind = "pd"
kp = 2e5
kd = 400
feedforward = "rigid"
[time]
end = 0.01
output_step = 1e-3
[output]
requests = ["machine_frequencies"]
plots = false
"#,
    )
    .unwrap();
    let out = dir.path().join("run");
    let o = flexprr()
        .arg("run")
        .arg(&scene)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let csv = std::fs::read_to_string(out.join("machine_frequencies.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let first: Vec<f64> = lines
        .next()
        .unwrap()
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    let value = json(&modes(&[
        scene.to_str().unwrap(),
        "--pose",
        "-0.08,0.03,40",
        "--json",
    ]));
    let expected = frequencies(&value);
    assert_eq!(expected.len(), 12);
    for (k, (f, zeta)) in expected.iter().enumerate() {
        let column = |name: String| header.iter().position(|h| *h == name).unwrap();
        let got_f = first[column(format!("f_machine_{}_Hz", k + 1))];
        let got_zeta = first[column(format!("zeta_machine_{}_ratio", k + 1))];
        assert!(
            ((got_f - f) / f).abs() < 1e-9,
            "mode {}: {got_f} vs {f}",
            k + 1
        );
        assert!(
            (got_zeta - zeta).abs() < 1e-9,
            "mode {}: {got_zeta} vs {zeta}",
            k + 1
        );
    }
}

/// The external model's variants are the shipped coupled scene with `model.coupling` set to
/// `nonlinear` and `elements = 16`, its `[output]` untouched: `modes` analyses it although
/// the scene requests the modal `modes` output, which a run of the nonlinear model refuses.
/// At rest with the sliders locked, each link's first bending modes are close to the
/// pinned-pinned ones (the platform is held by the links' axial stiffness, 1.9 kHz and up).
#[test]
fn a_nonlinear_variant_of_the_coupled_scene_is_analysed_whatever_it_requests() {
    let text = std::fs::read_to_string(config("coupled_f20.toml")).unwrap();
    assert!(
        text.contains("\"modes\""),
        "the shipped scene requests modes"
    );
    let text = text.replacen(
        "coupling = \"coupled\"",
        "coupling = \"nonlinear\"\nelements = 16",
        1,
    );
    assert!(text.contains("elements = 16"));
    let dir = std::env::temp_dir().join(format!("flexprr_modes_variant_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("coupled_nonlinear16.toml");
    std::fs::write(&scene, text).unwrap();
    let run = flexprr()
        .args(["check", scene.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2), "a run refuses the modal output");
    let value = json(&modes(&[
        scene.to_str().unwrap(),
        "--pose",
        "-0.05,0,45",
        "--json",
    ]));
    let found = frequencies(&value);
    let (e, rho, t, l): (f64, f64, f64, f64) = (7.3e10, 2770.0, 0.002, 0.2);
    let first = PI / (2.0 * l * l) * t * (e / (12.0 * rho)).sqrt();
    for (f, _) in &found[..3] {
        assert!(
            ((f - first) / first).abs() < 2e-3,
            "{f} Hz against {first} Hz"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 34, item 6: an orientation of many turns is refused at `--pose` with its
/// equivalent within a turn (on main `--pose 0,0,1e6` reported a collapse, exit 1).
#[test]
fn an_orientation_of_many_turns_is_refused_at_the_pose() {
    let scene = config("servo_f20.toml");
    refused(
        &modes(&[scene.to_str().unwrap(), "--pose", "0,0,1e6"]),
        &["--pose 0,0,1e6", "more than two turns", "280 deg"],
    );
    // Within two turns the pose is the same as its equivalent within one.
    let one = frequencies(&json(&modes(&[
        scene.to_str().unwrap(),
        "--pose",
        "-0.05,0,45",
        "--json",
    ])));
    let turned = frequencies(&json(&modes(&[
        scene.to_str().unwrap(),
        "--pose",
        "-0.05,0,-315",
        "--json",
    ])));
    for (a, b) in one.iter().zip(&turned) {
        assert!((a.0 - b.0).abs() < 1e-6 * a.0, "{a:?} {b:?}");
    }
}

/// Issue 34, item 4: a model whose dense linear analysis would exceed the memory bound is
/// refused before anything is built, at the key that sets its size, with the estimate (on
/// main, 512 elements built a state of 9,216 and aborted under 2.5 GB).
#[test]
fn a_model_too_large_for_a_dense_analysis_is_refused_with_its_estimate() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("fine.toml");
    let text = std::fs::read_to_string(config("nonlinear_f30.toml"))
        .unwrap()
        .lines()
        .map(|l| {
            if l.trim_start().starts_with("elements") {
                "elements = 512".to_string()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(&scene, text).unwrap();
    let o = modes(&[scene.to_str().unwrap()]);
    refused(
        &o,
        &[
            "fine.toml:",
            "model.elements",
            "state of 9216",
            "GB of memory",
            "docs/linear.md",
        ],
    );
}

/// The servo-motor scene at rest, closed form: each slider of mass `m = m_s + J g^2` (its
/// own and the rotor's reflected) on the PD law's spring `kp` and damper `kd` plus the
/// motor's viscous friction `b g^2 eta` reflected to the slider, `omega = sqrt(kp / m)`,
/// `zeta = (kd + b g^2 eta) / (2 sqrt(kp m))`. Issue 35, item 2: the Coulomb friction's
/// smoothed slope at zero speed (about 1e5 N s/m) is left out by default and the output
/// says so; on main it made three overdamped modes at 0.28 Hz.
#[test]
fn coulomb_friction_at_rest_is_left_out_and_said() {
    let scene = config("servo_motor_f2.toml");
    let o = modes(&[scene.to_str().unwrap(), "--count", "3"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(
        table.contains("note: Coulomb friction left out at sliders 1, 2 and 3"),
        "{table}"
    );
    let found = frequencies(&json(&modes(&[scene.to_str().unwrap(), "--json"])));
    let (kp, kd, ms, j, lead, b, eta) = (2e5, 2000.0, 0.5, 1.6e-5, 0.01, 1e-4, 0.9);
    let g = 2.0 * PI / lead;
    let m = ms + j * g * g;
    let (f, zeta) = (
        (kp / m).sqrt() / (2.0 * PI),
        (kd + b * g * g * eta) / (2.0 * (kp * m).sqrt()),
    );
    println!(
        "closed form {f:.3} Hz, zeta {zeta:.4}; found {:?}",
        &found[..3]
    );
    // The links and the platform add a little mass and coupling to each slider.
    for (fk, zk) in &found[..3] {
        assert!((fk / f - 1.0).abs() < 0.02, "{fk} Hz against {f} Hz");
        assert!((zk - zeta).abs() < 0.02, "zeta {zk} against {zeta}");
    }
    // Kept on request: the smoothing's stiff damper at rest.
    let smoothed = frequencies(&json(&modes(&[
        scene.to_str().unwrap(),
        "--coulomb",
        "smoothed",
        "--json",
    ])));
    assert!(
        smoothed[0].0 < 1.0 && (smoothed[0].1 - 1.0).abs() < 1e-6,
        "{smoothed:?}"
    );
}

/// Issue 35, item 2: an actuator saturated at the operating point is reported, and its
/// loop is open in the model: a motor whose peak torque is far below what the motion needs
/// saturates along it, and the servo modes held by `kp` are gone (the sliders are free).
#[test]
fn a_saturated_actuator_at_the_operating_point_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("weak.toml");
    let text = std::fs::read_to_string(config("servo_motor_f2.toml"))
        .unwrap()
        .replace("peak_torque = 3.5 ", "peak_torque = 0.02 ")
        .replace("continuous_torque = 1.2 ", "continuous_torque = 0.01 ");
    std::fs::write(&scene, text).unwrap();
    let o = modes(&[scene.to_str().unwrap(), "--time", "0.1", "--count", "4"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(
        table.contains("slider 1's actuator is saturated at the operating point")
            && table.contains("its loop is open in this model"),
        "{table}"
    );
    let found = frequencies(&json(&modes(&[
        scene.to_str().unwrap(),
        "--time",
        "0.1",
        "--json",
    ])));
    // Without kp the sliders have no spring: nothing is left near the 27 Hz servo modes.
    assert!(
        found.iter().all(|(f, _)| *f < 5.0 || *f > 100.0),
        "{found:?}"
    );
}

/// Issue 35, item 1: a sampled law's modes are the poles z of the discrete-time model of
/// its loop (s = ln z / T), and the output says so; without the law's period they were
/// the plant's, undamped (116 Hz at zeta 0 under a header saying the law holds the
/// sliders).
#[test]
fn a_sampled_law_gives_the_poles_of_its_discrete_loop() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("sampled.toml");
    let text = std::fs::read_to_string(config("servo_f20.toml"))
        .unwrap()
        .replace("period = 0 ", "period = 0.0002 ");
    std::fs::write(&scene, text).unwrap();
    let o = modes(&[
        scene.to_str().unwrap(),
        "--pose",
        "-0.1,0,45",
        "--count",
        "3",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(
        table.contains("discrete time at the law's period T = 0.0002 s"),
        "{table}"
    );
    let sampled = json(&modes(&[
        scene.to_str().unwrap(),
        "--pose",
        "-0.1,0,45",
        "--json",
    ]));
    let continuous = frequencies(&json(&modes(&[
        config("servo_f20.toml").to_str().unwrap(),
        "--pose",
        "-0.1,0,45",
        "--json",
    ])));
    // At 5 kHz the loop is nearly the continuous one: its servo modes within a few percent
    // and damped as much; each mode has its pole z.
    let found = frequencies(&sampled);
    for k in 0..3 {
        assert!(
            (found[k].0 / continuous[k].0 - 1.0).abs() < 0.05,
            "{:?} {:?}",
            found[k],
            continuous[k]
        );
        assert!((found[k].1 - continuous[k].1).abs() < 0.05);
        let z = &sampled["modes"][k]["z"];
        let (re, im) = (z[0].as_f64().unwrap(), z[1].as_f64().unwrap());
        let s = (re.hypot(im).ln() / 2e-4).hypot(im.atan2(re) / 2e-4);
        assert!((s / (2.0 * PI) / found[k].0 - 1.0).abs() < 1e-9);
    }
}

/// Issue 35, item 3: `flexprr modes` says when the listed modes reach the first bending
/// family the basis leaves out (the 4th of 3 sine modes per link, 16 f_1 = 1862 Hz; the
/// machine's is at 1840-1874 Hz) and how many modes per link bring every family in; not
/// when the listed modes stay below it.
#[test]
fn modes_say_where_the_basis_leaves_families_out() {
    let scene = config("coupled_f20.toml");
    let o = modes(&[scene.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(
        table.contains(
            "the basis has 3 bending modes per link: the families from about 1862 Hz (the 4th)"
        ) && table.contains("links.modes = 7"),
        "{table}"
    );
    let o = modes(&[scene.to_str().unwrap(), "--count", "9"]);
    assert!(!String::from_utf8_lossy(&o.stdout).contains("families from about"));
    let dir = tempfile::tempdir().unwrap();
    let o = modes(&[
        scene.to_str().unwrap(),
        "--out",
        dir.path().join("m").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("m").join("modes.json")).unwrap(),
    )
    .unwrap();
    let t = &json["truncation"];
    assert_eq!(t["modes_per_link"], 3);
    assert_eq!(t["complete"], false);
    let first = t["first_missing_family_hz"].as_f64().unwrap();
    assert!((first / (16.0 * 116.3914) - 1.0).abs() < 1e-4, "{first}");
}
