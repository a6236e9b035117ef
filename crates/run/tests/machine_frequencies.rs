//! The `machine_frequencies` output (docs/linear.md): at rest with the sliders locked and
//! the chords kept rigid the coupled model's whole-machine frequencies are the pinned-pinned
//! closed form at every instant (with the chords the links' axial springs, the default, three
//! platform modes join them), beside the KED first modes (the same closed form without axial load); the
//! instants are decimated to at most 201 and `summary.json` says so; the progress still
//! ends at 1; a KED scene is refused when it loads, at the request.

use std::f64::consts::PI;

use flexprr_run::{run, summary_json};
use flexprr_scene::{ScenarioError, Scene};

/// The paper's machine (the defaults) with `trajectory` and `model` tables, 50 ms.
fn scene(trajectory: &str, model: &str, extra: &str) -> Scene {
    let text = format!(
        r#"
[trajectory]
{trajectory}
[model]
formulation = "consistent"
{model}
{extra}
[time]
end = 0.05
output_step = 1e-4
[output]
requests = ["machine_frequencies"]
plots = false
"#
    );
    Scene::from_text("machine.toml", "machine", &text).unwrap()
}

/// `f_n = (n^2 pi / 2 l^2) sqrt(EI / rho A)` of the paper's link (E = 7.3e10 Pa,
/// rho = 2770 kg/m^3, t = 2 mm, l = 0.2 m).
fn pinned_pinned(n: usize) -> f64 {
    let (e, rho, t, l): (f64, f64, f64, f64) = (7.3e10, 2770.0, 0.002, 0.2);
    (n * n) as f64 * PI / (2.0 * l * l) * t * (e / (12.0 * rho)).sqrt()
}

#[test]
fn at_rest_locked_the_whole_machine_has_the_pinned_pinned_frequencies_at_every_instant() {
    let mut s = scene(
        "kind = \"line\"\nfrom = [-0.05, 0.02, 30.0]\nvelocity = [0.0, 0.0, 0.0]",
        "coupling = \"coupled\"",
        "",
    );
    let elastic = run(&s, &mut |_| {}).expect("runs");
    assert_eq!(
        elastic
            .report::<flexprr_run::machine_frequencies::MachineFrequencyNote>()
            .expect("the note")
            .modes,
        12,
        "3 links x 3 modes and 3 platform modes on the links' axial springs"
    );
    s.rigid_chords = true;
    let mut fractions = Vec::new();
    let result = run(&s, &mut |f| fractions.push(f)).expect("runs");
    let table = result.table("machine_frequencies").expect("the table");
    // 501 output times: every 3rd (ceil(500 / 200)) and the last.
    let note = result
        .report::<flexprr_run::machine_frequencies::MachineFrequencyNote>()
        .expect("the note");
    assert_eq!(
        (note.output_times, note.stride, note.instants),
        (501, 3, 168)
    );
    assert_eq!(table.rows(), 168);
    assert_eq!(table.time()[1].to_bits(), s.output_times[3].to_bits());
    assert_eq!(
        table.time().last().unwrap().to_bits(),
        s.output_times[500].to_bits()
    );
    assert_eq!(note.modes, 9, "3 links x 3 modes, sliders locked");
    let headers = table.headers();
    assert_eq!(headers[1], "f_machine_1_Hz");
    assert_eq!(headers[10], "zeta_machine_1_ratio");
    assert_eq!(&headers[19..], ["f_1_1_Hz", "f_2_1_Hz", "f_3_1_Hz"]);
    for k in 0..9 {
        let exact = pinned_pinned(k / 3 + 1);
        let f = table.column(&format!("f_machine_{}_Hz", k + 1)).unwrap();
        let zeta = table
            .column(&format!("zeta_machine_{}_ratio", k + 1))
            .unwrap();
        for (fr, z) in f.iter().zip(zeta) {
            assert!(((fr - exact) / exact).abs() < 1e-6, "mode {}: {fr}", k + 1);
            assert!(z.abs() < 1e-6);
        }
    }
    for i in 1..=3 {
        for f in table.column(&format!("f_{i}_1_Hz")).unwrap() {
            assert!(((f - pinned_pinned(1)) / pinned_pinned(1)).abs() < 1e-6);
        }
    }
    // The integration reports up to 1 / (1 + 18 / 100) (18 states), the linearisations
    // the rest, up to 1.
    let share = 1.0 / 1.18;
    assert!(fractions.windows(2).all(|w| w[1] >= w[0]), "monotone");
    assert!((fractions.last().unwrap() - 1.0).abs() < 1e-12);
    let integrating = fractions.iter().filter(|f| **f <= share + 1e-12).count();
    let linearising = fractions.iter().filter(|f| **f > share + 1e-12).count();
    assert!(
        integrating > 0 && linearising == 168,
        "{integrating} {linearising}"
    );
    assert!(
        fractions.iter().any(|f| (f - share).abs() < 1e-12),
        "the integration ends at the share"
    );
    let summary = summary_json(&s, &result, None);
    let section = &summary["machine_frequencies"];
    assert_eq!(section["instants"], 168);
    assert_eq!(section["stride"], 3);
    assert!(
        section["note"]
            .as_str()
            .unwrap()
            .contains("every 3-th of 501")
    );
}

#[test]
fn along_a_servo_motion_twelve_modes_are_tabulated_with_their_damping() {
    let s = scene(
        "kind = \"circle\"\nfrequency = 20.0",
        "coupling = \"coupled\"",
        "[control]\nkind = \"pd\"\nkp = 2e5\nkd = 400\nfeedforward = \"rigid\"",
    );
    let result = run(&s, &mut |_| {}).expect("runs");
    let table = result.table("machine_frequencies").expect("the table");
    assert_eq!(
        result
            .report::<flexprr_run::machine_frequencies::MachineFrequencyNote>()
            .unwrap()
            .modes,
        12
    );
    for k in 1..=12 {
        let f = table.column(&format!("f_machine_{k}_Hz")).unwrap();
        assert!(f.iter().all(|v| v.is_finite() && *v > 50.0));
    }
    // The three servo modes are the lowest and the only ones damped by more than 0.3.
    let zeta = |k: usize| table.column(&format!("zeta_machine_{k}_ratio")).unwrap();
    for row in 0..table.rows() {
        let damped = (1..=12).filter(|&k| zeta(k)[row] > 0.3).count();
        assert_eq!(damped, 3, "row {row}");
    }
}

#[test]
fn a_ked_scene_is_refused_at_the_request() {
    let text = r#"
[trajectory]
kind = "circle"
frequency = 20.0
[time]
end = 0.01
output_step = 1e-3
[output]
requests = ["deflections", "machine_frequencies"]
"#;
    match Scene::from_text("ked.toml", "ked", text) {
        Err(ScenarioError::Input {
            location,
            key,
            message,
        }) => {
            assert_eq!(key, "output.requests.1");
            assert!(location.is_some(), "located in the file");
            assert!(
                message.contains("model.coupling = \"coupled\""),
                "{message}"
            );
        }
        other => panic!("expected a located refusal, got {other:?}"),
    }
}
