//! `[control] kind = "statespace"` against independent facts: a feedthrough-only law with
//! the PD gains is the `pd` law (the same run to integration tolerance, the same closed-loop
//! poles, continuous and sampled); a dynamic law (a PD with a filtered derivative) closes
//! the plant's linear model (the machine with no feedback, from `slider_force` to
//! `slider_error`) to exactly the poles flexprr's linear model of the loop has; a law that
//! is unstable on its own is a warning; bad files are errors at `control.file`.

use std::path::Path;

use faer::linalg::solvers::Eigen;
use flexprr_kinematics::Pose;
use flexprr_linear::{Input, Linearization, Output, linearize};
use flexprr_linear_tools::linear::{OperatingPoint, operating_point};
use flexprr_linear_tools::npz::{NpyData, npz};
use flexprr_run::{integrate, run};
use flexprr_scene::Scene;

const KP: f64 = 2e5;
const KD: f64 = 400.0;

fn servo() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/servo_f20.toml");
    std::fs::read_to_string(path)
        .expect("shipped config")
        .replace("end = 0.2", "end = 0.03")
}

/// The servo scene with its `[control]` table replaced by `control` (written with the
/// scene into `dir`, so that a law's file is found beside it).
fn with_control(dir: &Path, control: &str) -> Result<Scene, String> {
    let text = servo();
    let start = text.find("\n[control]").expect("control table") + 1;
    let end = text[start..]
        .find("[integrator]")
        .expect("integrator table")
        + start;
    let text = format!("{}{control}\n{}", &text[..start], &text[end..]);
    let file = dir.join("servo.toml");
    std::fs::write(&file, &text).expect("written");
    Scene::load(&file).map_err(|e| e.to_string())
}

fn matrix(rows: usize, cols: usize, values: Vec<f64>) -> NpyData {
    NpyData::F64 {
        shape: vec![rows, cols],
        values,
    }
}

/// `D = [kp I, kd I]` on `slider_error:1..3, slider_error_rate:1..3`.
fn pd_feedthrough() -> Vec<f64> {
    let mut d = vec![0.0; 18];
    for i in 0..3 {
        d[i * 6 + i] = KP;
        d[i * 6 + 3 + i] = KD;
    }
    d
}

const PD_CHANNELS: &str = "measurements = [\"slider_error:1\", \"slider_error:2\", \"slider_error:3\", \"slider_error_rate:1\", \"slider_error_rate:2\", \"slider_error_rate:3\"]\ncommands = [\"slider_force:1\", \"slider_force:2\", \"slider_force:3\"]";

fn write_npz(dir: &Path, name: &str, arrays: &[(&str, NpyData)]) {
    std::fs::write(dir.join(name), npz(arrays).expect("npz")).expect("written");
}

fn eigenvalues(lin: &Linearization) -> Vec<(f64, f64)> {
    let e = Eigen::new_from_real(lin.a.as_ref()).expect("eigen");
    let mut v: Vec<(f64, f64)> = (0..lin.a.nrows())
        .map(|k| (e.S()[k].re, e.S()[k].im))
        .collect();
    v.sort_by(|p, q| p.0.total_cmp(&q.0).then(p.1.total_cmp(&q.1)));
    v
}

/// The largest distance from a pole of `want` to the nearest of `got`, relative to the
/// largest pole.
fn pole_distance(want: &[(f64, f64)], got: &[(f64, f64)]) -> f64 {
    assert_eq!(want.len(), got.len());
    let size = want.iter().fold(0.0f64, |m, p| m.max(p.0.hypot(p.1)));
    want.iter()
        .map(|w| {
            got.iter()
                .map(|g| (w.0 - g.0).hypot(w.1 - g.1))
                .fold(f64::INFINITY, f64::min)
        })
        .fold(0.0f64, f64::max)
        / size
}

fn at_rest(scene: &Scene, inputs: &[Input], outputs: &[Output]) -> Linearization {
    let pose = Pose::new(-0.05, 0.0, 45f64.to_radians());
    let mut at = operating_point(scene, OperatingPoint::Rest(pose)).expect("operating point");
    linearize(at.model.as_mut(), at.t, &at.state, inputs, outputs).expect("linearises")
}

#[test]
fn a_feedthrough_law_with_the_pd_gains_is_the_pd_law() {
    let dir = tempfile::tempdir().unwrap();
    write_npz(
        dir.path(),
        "pd.npz",
        &[("D", matrix(3, 6, pd_feedthrough()))],
    );
    for period in [0.0, 5e-4] {
        let law = with_control(
            dir.path(),
            &format!(
                "[control]\nkind = \"statespace\"\nfile = \"pd.npz\"\n{PD_CHANNELS}\nperiod = {period:e}\n"
            ),
        )
        .unwrap();
        let pd = with_control(
            dir.path(),
            &format!("[control]\nkind = \"pd\"\nkp = {KP:e}\nkd = {KD}\nperiod = {period:e}\n"),
        )
        .unwrap();
        let (a, _) = integrate(&law, &mut |_| {}).unwrap();
        let (b, _) = integrate(&pd, &mut |_| {}).unwrap();
        assert!(a.failure.is_none() && b.failure.is_none());
        assert_eq!(a.solution.len(), b.solution.len());
        // Sliders (m) and modal coordinates: the same run to the integrator's tolerance.
        let (mut worst, mut size) = (0.0f64, 0.0f64);
        for k in 0..a.solution.len() {
            for (x, y) in a.solution.y(k).iter().zip(b.solution.y(k)) {
                worst = worst.max((x - y).abs());
                size = size.max(y.abs());
            }
        }
        println!("period {period}: largest state difference {worst:.2e} of {size:.2e}");
        assert!(worst <= 1e-7 * size, "{worst} of {size}");
        // The same closed-loop poles.
        let d = pole_distance(
            &eigenvalues(&at_rest(&pd, &[], &[])),
            &eigenvalues(&at_rest(&law, &[], &[])),
        );
        println!("period {period}: poles within {d:.1e}");
        assert!(d < 1e-8, "{d}");
    }
}

/// `C(s) = kp + kd s / (tau s + 1)` on each slider's error: `z' = (-z + e) / tau`,
/// `u = kp e + (kd / tau) (e - z)`.
fn filtered_pd(tau: f64) -> [(&'static str, NpyData); 4] {
    let eye = |v: f64| {
        (0..9)
            .map(|k| if k % 4 == 0 { v } else { 0.0 })
            .collect::<Vec<_>>()
    };
    [
        ("A", matrix(3, 3, eye(-1.0 / tau))),
        ("B", matrix(3, 3, eye(1.0 / tau))),
        ("C", matrix(3, 3, eye(-KD / tau))),
        ("D", matrix(3, 3, eye(KP + KD / tau))),
    ]
}

#[test]
fn a_dynamic_law_closes_the_plant_to_the_poles_its_interconnection_predicts() {
    let dir = tempfile::tempdir().unwrap();
    let tau = 2e-4;
    write_npz(dir.path(), "filtered.npz", &filtered_pd(tau));
    let channels = "measurements = [\"slider_error:1\", \"slider_error:2\", \"slider_error:3\"]\ncommands = [\"slider_force:1\", \"slider_force:2\", \"slider_force:3\"]";
    let law = with_control(
        dir.path(),
        &format!("[control]\nkind = \"statespace\"\nfile = \"filtered.npz\"\n{channels}\n"),
    )
    .unwrap();
    // The plant: the sliders actuated with no feedback.
    let open = with_control(dir.path(), "[control]\nkind = \"pd\"\nkp = 0\nkd = 0\n").unwrap();
    let inputs: Vec<Input> = (0..3).map(Input::SliderForce).collect();
    let outputs: Vec<Output> = (0..3).map(Output::SliderError).collect();
    let plant = at_rest(&open, &inputs, &outputs);
    let n = plant.a.nrows();
    // u = Ck z + Dk y, y = Cp x (no feedthrough from a force to a position).
    let (ak, bk, ck, dk) = (-1.0 / tau, 1.0 / tau, -KD / tau, KP + KD / tau);
    for o in 0..3 {
        for i in 0..3 {
            assert!(plant.d[(o, i)].abs() < 1e-12);
        }
    }
    let closed = faer::Mat::<f64>::from_fn(n + 3, n + 3, |i, j| match (i < n, j < n) {
        (true, true) => {
            plant.a[(i, j)]
                + (0..3)
                    .map(|k| plant.b[(i, k)] * dk * plant.c[(k, j)])
                    .sum::<f64>()
        }
        (true, false) => plant.b[(i, j - n)] * ck,
        (false, true) => bk * plant.c[(i - n, j)],
        (false, false) => {
            if i == j {
                ak
            } else {
                0.0
            }
        }
    });
    let mut predicted = plant.clone();
    predicted.a = closed;
    let got = at_rest(&law, &[], &[]);
    assert_eq!(
        got.a.nrows(),
        n + 3,
        "the law's three states are in the loop"
    );
    let d = pole_distance(&eigenvalues(&predicted), &eigenvalues(&got));
    println!("filtered PD: closed-loop poles within {d:.1e} of the interconnection's");
    // Both are linearised by differences (the coupled model), each about its own loop:
    // the axial modes near 2.4e5 1/s carry their truncation error (4e-6 of the largest
    // pole); a law misplaced in the loop moves its poles near 1/tau by percents.
    assert!(d < 2e-5, "{d}");
    assert!(eigenvalues(&got).iter().all(|p| p.0 < 0.0), "stable");
    // And it runs: the filtered derivative tracks like the PD (microns).
    let result = run(&law, &mut |_| {}).expect("runs");
    assert!(result.warnings.is_empty(), "{:?}", result.warnings);
}

#[test]
fn a_law_unstable_on_its_own_is_a_warning_and_bad_files_are_errors_at_their_key() {
    let dir = tempfile::tempdir().unwrap();
    // An integrator that grows (z' = z + e): unstable alone.
    write_npz(
        dir.path(),
        "growing.npz",
        &[
            ("A", matrix(1, 1, vec![1.0])),
            ("B", matrix(1, 1, vec![1.0])),
            ("C", matrix(1, 1, vec![0.0])),
            ("D", matrix(1, 1, vec![KP])),
        ],
    );
    let one = "measurements = [\"slider_error:1\"]\ncommands = [\"slider_force:1\"]";
    let scene = with_control(
        dir.path(),
        &format!("[control]\nkind = \"statespace\"\nfile = \"growing.npz\"\n{one}\n"),
    )
    .unwrap();
    let warnings = scene.controller.as_ref().unwrap().warnings();
    assert!(warnings[0].contains("unstable on its own"), "{warnings:?}");
    let error = |control: &str| with_control(dir.path(), control).unwrap_err();
    let law = |file: &str, rest: &str| {
        format!("[control]\nkind = \"statespace\"\nfile = \"{file}\"\n{one}\n{rest}")
    };
    let e = error(&law("missing.npz", ""));
    assert!(
        e.contains("control.file") && e.contains("cannot read"),
        "{e}"
    );
    std::fs::write(dir.path().join("text.npz"), "A = 1").unwrap();
    let e = error(&law("text.npz", ""));
    assert!(
        e.contains("control.file") && e.contains("not an .npz"),
        "{e}"
    );
    write_npz(
        dir.path(),
        "wide.npz",
        &[("D", matrix(1, 2, vec![1.0, 2.0]))],
    );
    let e = error(&law("wide.npz", ""));
    assert!(
        e.contains("control.file") && e.contains("D is 1 x 2, expected 1 x 1"),
        "{e}"
    );
    write_npz(
        dir.path(),
        "nan.npz",
        &[("D", matrix(1, 1, vec![f64::NAN]))],
    );
    let e = error(&law("nan.npz", ""));
    assert!(e.contains("D[0, 0] = NaN"), "{e}");
    write_npz(
        dir.path(),
        "discrete.npz",
        &[
            ("D", matrix(1, 1, vec![KP])),
            (
                "dt",
                NpyData::F64 {
                    shape: vec![],
                    values: vec![1e-3],
                },
            ),
        ],
    );
    let e = error(&law("discrete.npz", ""));
    assert!(
        e.contains("control.period") && e.contains("set period = 0.001"),
        "{e}"
    );
    let e = error(&law("discrete.npz", "period = 5e-4"));
    assert!(
        e.contains("control.period") && e.contains("must be equal"),
        "{e}"
    );
    let e = error(
        "[control]\nkind = \"statespace\"\nfile = \"discrete.npz\"\nmeasurements = [\"platform:x\"]\ncommands = [\"slider_force:1\"]\nperiod = 1e-3\n",
    );
    assert!(
        e.contains("control.measurements") && e.contains("cannot measure yet"),
        "{e}"
    );
    let e = error(
        "[control]\nkind = \"statespace\"\nfile = \"discrete.npz\"\nmeasurements = [\"slider_error:1\"]\ncommands = [\"slider_frce:1\"]\nperiod = 1e-3\n",
    );
    assert!(
        e.contains("control.commands") && e.contains("unknown input"),
        "{e}"
    );
}

/// The shipped `configs/servo_statespace.npz`: [`filtered_pd`] at `tau = 1e-4` s. Run with
/// `FLEXPRR_WRITE_SHIPPED=1` to write it; otherwise the shipped file must be what this
/// helper writes, and its law must have the filtered PD's response
/// `kp + kd i w / (i w tau + 1)` (closed form) at every frequency checked.
#[test]
fn the_shipped_law_is_the_filtered_pd_its_scene_names() {
    let configs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs");
    let tau = 1e-4;
    let bytes = npz(&filtered_pd(tau)).expect("npz");
    let path = configs.join("servo_statespace.npz");
    if std::env::var_os("FLEXPRR_WRITE_SHIPPED").is_some() {
        std::fs::write(&path, &bytes).expect("written");
    }
    assert!(
        std::fs::read(&path).expect("shipped npz") == bytes,
        "configs/servo_statespace.npz is not the filtered PD of this test: write it again with FLEXPRR_WRITE_SHIPPED=1"
    );
    let mut scene = Scene::load(&configs.join("servo_statespace.toml")).expect("loads");
    let law = scene.controller.clone().expect("law");
    assert_eq!((law.name().as_str(), law.states()), ("statespace", 3));
    // The law's response from the error of slider 1 to its force, by its own commands:
    // with e(t) = cos(w t) the steady state is z = Re(Z e^{iwt}), Z = 1 / (1 + i w tau).
    for w in [10.0, 1e3, 1e4, 1e5] {
        let z = (
            1.0 / (1.0 + (w * tau).powi(2)),
            -w * tau / (1.0 + (w * tau).powi(2)),
        );
        let want = (
            KP + KD * w * w * tau / (1.0 + (w * tau).powi(2)),
            KD * w / (1.0 + (w * tau).powi(2)),
        );
        let force = |e: f64, state: f64| {
            let reference = flexprr_control::SliderState {
                position: e,
                velocity: 0.0,
                acceleration: 0.0,
            };
            let input = flexprr_control::ControlInput {
                t: 0.0,
                reference: [reference; 3],
                measured: Default::default(),
                feedforward: [0.0; 3],
                force_limit: [f64::INFINITY; 3],
                sensors: &[],
            };
            let (mut f, mut rates) = ([0.0; 3], [0.0; 3]);
            law.command(&input, &[state; 3], &mut f, &mut rates);
            f[0]
        };
        // Real part: e = 1, z = Re Z; imaginary part: e = 0, z = Im Z (u is linear in both).
        let (re, im) = (force(1.0, z.0), force(0.0, z.1));
        let scale = want.0.hypot(want.1);
        assert!(
            (re - want.0).abs() <= 1e-9 * scale && (im - want.1).abs() <= 1e-9 * scale,
            "w = {w}: ({re}, {im}) against {want:?}"
        );
    }
    // It runs on the 20 Hz circle.
    scene.output_times.retain(|t| *t <= 0.03);
    let (integration, _) = integrate(&scene, &mut |_| {}).expect("builds");
    assert!(integration.failure.is_none());
}
