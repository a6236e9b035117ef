//! The `[actuators]` and `[control]` tables (docs/control.md): what they build, the model
//! rules, and every error located at its key with line and column on one line; the
//! controller registry with a custom law; `set` of the same keys.

use std::sync::Arc;

use flexprr_control::{ControlInput, Controller, SliderState};
use flexprr_scene::{ControllerFactory, Registry, ScenarioError, Scene, TableParams, setting};

/// A servo scene: the paper's machine on a 10 Hz circle, coupled model, with `extra` tables.
fn text(coupling: &str, extra: &str) -> String {
    format!(
        r#"name = "servo"
[trajectory]
kind = "circle"
frequency = 10.0
[model]
coupling = "{coupling}"
[time]
end = 0.01
{extra}"#
    )
}

const PD: &str = r#"[control]
kind = "pd"
kp = 2e5
kd = 400
feedforward = "rigid"
period = 0
"#;

const MOTOR: &str = r#"[actuators]
kind = "motor_ballscrew"
rotor_inertia = 1.6e-5
lead = 0.01
efficiency = 0.9
peak_torque = 3.5
continuous_torque = 1.2
max_speed = 100
viscous_friction = 1e-4
coulomb_friction = 0.02
"#;

fn load(text: &str) -> Result<Scene, ScenarioError> {
    Scene::from_text("servo.toml", "servo", text)
}

/// The located error of `text`: (line, column, key, message), and its one-line display.
fn refused(text: &str) -> (usize, usize, String, String) {
    match load(text) {
        Err(e @ ScenarioError::Input { .. }) => {
            let shown = e.to_string();
            assert!(!shown.contains('\n'), "one line: {shown}");
            let ScenarioError::Input {
                location,
                key,
                message,
            } = e
            else {
                unreachable!()
            };
            let location = location.unwrap_or_else(|| panic!("not located: {shown}"));
            assert_eq!(location.file, "servo.toml");
            (location.line, location.column, key, message)
        }
        other => panic!("accepted: {other:?}"),
    }
}

/// The 1-based line of the first line of `text` that starts with `start`.
fn line_of(text: &str, start: &str) -> usize {
    1 + text
        .lines()
        .position(|l| l.starts_with(start))
        .unwrap_or_else(|| panic!("no line starts with {start:?}"))
}

/// As [`line_of`], below the header of `table`.
fn line_in(text: &str, table: &str, start: &str) -> usize {
    let header = line_of(text, &format!("[{table}]"));
    header
        + text
            .lines()
            .skip(header)
            .position(|l| l.starts_with(start))
            .unwrap_or_else(|| panic!("no line of [{table}] starts with {start:?}"))
        + 1
}

#[test]
fn control_without_actuators_drives_the_sliders_with_ideal_forces() {
    let scene = load(&text("coupled", PD)).expect("valid");
    assert_eq!(scene.actuator.as_ref().map(|a| a.name()), Some("force"));
    let controller = scene.controller.as_ref().expect("a controller");
    assert_eq!(controller.name(), "pd");
    assert!(controller.period() <= 0.0);
    // The actuated coupled model is nonlinear: auto chooses abm.
    assert_eq!(scene.method.name(), "abm");
    assert_eq!(
        scene.model_description(),
        "coupled model, actuated sliders (pd, force actuators), consistent formulation, \
         3 modes per link: sine (pinned-pinned), r = 3"
    );
    let model = scene.build_model().expect("builds");
    // Three modes per link and the three sliders, as coordinates and rates.
    assert_eq!(model.dim(), 2 * (9 + 3));
    assert_eq!(
        model.initial_state().len(),
        model.dim(),
        "started on the commanded path"
    );
}

#[test]
fn the_pd_law_is_the_one_the_keys_give() {
    let scene = load(&text("coupled", PD)).expect("valid");
    let controller = scene.controller.expect("pd");
    let reference = SliderState {
        position: 1e-3,
        velocity: -2e-2,
        acceleration: 0.0,
    };
    let input = ControlInput {
        t: 0.0,
        reference: [reference; 3],
        measured: [SliderState::default(); 3],
        feedforward: [10.0; 3],
        force_limit: [f64::INFINITY; 3],
        sensors: &[],
    };
    let mut force = [0.0; 3];
    controller.command(&input, &[], &mut force, &mut []);
    let expected = 10.0 + 2e5 * 1e-3 + 400.0 * -2e-2;
    assert!((force[0] - expected).abs() <= 1e-12 * expected, "{force:?}");
    // feedforward = "none" drops the 10 N.
    let none = text("coupled", &PD.replace("\"rigid\"", "\"none\""));
    let controller = load(&none).expect("valid").controller.expect("pd");
    controller.command(&input, &[], &mut force, &mut []);
    assert!((force[1] - (expected - 10.0)).abs() <= 1e-12 * expected);
    // pid: one integral state per slider.
    let pid = PD.replace("\"pd\"", "\"pid\"") + "ki = 1e6\n";
    let controller = load(&text("coupled", &pid)).expect("valid").controller;
    assert_eq!(controller.expect("pid").states(), 3);
}

#[test]
fn a_motor_with_control_and_one_without() {
    let scene = load(&text("coupled", &format!("{MOTOR}{PD}"))).expect("valid");
    let actuator = scene.actuator.as_ref().expect("motor");
    assert_eq!(actuator.name(), "motor_ballscrew");
    let ratings = actuator.ratings().expect("ratings");
    assert!((ratings.peak_torque - 3.5).abs() < 1e-15);
    // Reflected mass J (2 pi / p)^2.
    let g = std::f64::consts::TAU / 0.01;
    assert!((actuator.reflected_mass() - 1.6e-5 * g * g).abs() <= 1e-12);
    assert!(
        scene
            .model_description()
            .contains("actuated sliders (pd, motor_ballscrew actuators)")
    );
    // [actuators] alone is allowed for every model, the KED one included: feasibility only.
    for coupling in ["ked", "coupled", "nonlinear"] {
        let scene = load(&text(coupling, MOTOR)).expect("valid");
        assert!(scene.controller.is_none(), "{coupling}");
        assert!(scene.actuator.is_some(), "{coupling}");
        assert!(scene.actuation().is_none(), "{coupling}");
        assert!(
            scene.model_description().contains("prescribed sliders"),
            "{}",
            scene.model_description()
        );
    }
    // The Coulomb smoothing has a documented default.
    let echoed = toml::to_string(&scene.file).expect("serializes");
    assert!(echoed.contains("coulomb_smoothing = 0.01"), "{echoed}");
}

#[test]
fn control_on_the_ked_model_is_refused_at_the_control_table() {
    let t = text("ked", PD);
    let (line, column, key, message) = refused(&t);
    assert_eq!((line, column), (line_of(&t, "[control]"), 2));
    assert_eq!(key, "control");
    assert!(
        message.contains("model.coupling = \"coupled\""),
        "{message}"
    );
}

#[test]
fn exponential_methods_are_refused_for_actuated_models() {
    let t = text("coupled", PD) + "[integrator]\nmethod = \"magnus6\"\n";
    let (line, _, key, message) = refused(&t);
    assert_eq!(line, line_of(&t, "method"));
    assert_eq!(key, "integrator.method");
    assert!(
        message.contains("coupled with actuated sliders") && message.contains("abm"),
        "{message}"
    );
}

#[test]
fn bad_control_keys_are_located_with_their_rule() {
    let cases: [(&str, &str, &str, &str); 7] = [
        // (replace, with, key, words of the message)
        (
            "kp = 2e5",
            "kp = -1",
            "control.kp",
            "a gain must be finite and >= 0, got -1",
        ),
        (
            "kd = 400",
            "kd = 400\nkq = 1",
            "control.kq",
            "unknown field `kq`",
        ),
        (
            "period = 0",
            "period = -0.001",
            "control.period",
            "got -0.001",
        ),
        (
            "kind = \"pd\"",
            "kind = \"lqr\"",
            "control.kind",
            "unknown control law \"lqr\"",
        ),
        ("\"rigid\"", "\"full\"", "control.feedforward", "rigid"),
        ("kd = 400\n", "", "control.kd", "missing field `kd`"),
        (
            "kd = 400",
            "kd = 400\nki = 5",
            "control.ki",
            "use kind = \"pid\"",
        ),
    ];
    for (from, to, key, words) in cases {
        let t = text("coupled", &PD.replace(from, to));
        let (line, _, found, message) = refused(&t);
        assert_eq!(found, key, "{message}");
        assert!(message.contains(words), "{key}: {message}");
        let first = key.rsplit('.').next().unwrap_or(key);
        let expected = if words.starts_with("missing") {
            line_of(&t, "[control]")
        } else {
            line_in(&t, "control", &format!("{first} ="))
        };
        assert_eq!(line, expected, "{key}: {message}");
    }
}

#[test]
fn bad_actuator_keys_are_located_with_their_rule() {
    let cases: [(&str, &str, &str, &str); 6] = [
        (
            "lead = 0.01",
            "lead = 0",
            "actuators.lead",
            "> 0 (m/rev), got 0",
        ),
        (
            "efficiency = 0.9",
            "efficiency = 1.5",
            "actuators.efficiency",
            "(0, 1], got 1.5",
        ),
        (
            "continuous_torque = 1.2",
            "continuous_torque = 4",
            "actuators.continuous_torque",
            "must not exceed peak_torque",
        ),
        (
            "max_speed = 100",
            "max_speed = -5",
            "actuators.max_speed",
            "got -5",
        ),
        (
            "lead = 0.01",
            "leed = 0.01",
            "actuators.leed",
            "unknown field `leed`",
        ),
        (
            "kind = \"motor_ballscrew\"",
            "kind = \"linear_motor\"",
            "actuators.kind",
            "unknown variant `linear_motor`",
        ),
    ];
    for (from, to, key, words) in cases {
        let t = text("coupled", &MOTOR.replace(from, to));
        let (line, _, found, message) = refused(&t);
        assert_eq!(found, key, "{message}");
        assert!(message.contains(words), "{key}: {message}");
        let first = to.split(' ').next().unwrap_or(to);
        assert_eq!(line, line_in(&t, "actuators", first), "{key}: {message}");
    }
    // The ideal force takes no other key.
    let t = text("coupled", "[actuators]\nkind = \"force\"\nlead = 0.01\n");
    let (line, _, key, message) = refused(&t);
    assert_eq!(
        (line, key.as_str()),
        (line_in(&t, "actuators", "lead"), "actuators.lead")
    );
    assert!(message.contains("unknown field `lead`"), "{message}");
}

/// A custom law: proportional on the position error, with a gain the factory reads and
/// checks.
#[derive(Debug)]
struct Proportional(f64);

impl Controller for Proportional {
    fn command(&self, input: &ControlInput<'_>, _: &[f64], force: &mut [f64; 3], _: &mut [f64]) {
        for (i, f) in force.iter_mut().enumerate() {
            *f = self.0 * (input.reference[i].position - input.measured[i].position);
        }
    }
    fn name(&self) -> String {
        "p".into()
    }
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct Keys {
    k: f64,
}

struct ProportionalFactory;

impl ControllerFactory for ProportionalFactory {
    fn build(&self, params: &TableParams<'_>) -> Result<Arc<dyn Controller>, ScenarioError> {
        let keys: Keys = params.parse()?;
        if !(keys.k.is_finite() && keys.k > 0.0) {
            return Err(params.error("k", format!("expected a positive gain, got {}", keys.k)));
        }
        Ok(Arc::new(Proportional(keys.k)))
    }
}

#[test]
fn a_registered_controller_is_named_by_scenes_and_reads_its_keys() {
    let mut registry = Registry::default();
    registry.register_controller("p", Arc::new(ProportionalFactory));
    assert_eq!(
        registry.controller_names(),
        ["p", "pd", "pid", "python", "statespace"]
    );
    let t = text("coupled", "[control]\nkind = \"p\"\nk = 5e4\n");
    let scene = Scene::from_text_with(&registry, "servo.toml", "servo", &t).expect("valid");
    assert_eq!(
        scene.controller.as_ref().map(|c| c.name()),
        Some("p".into())
    );
    assert!(
        scene
            .model_description()
            .contains("actuated sliders (p, force")
    );
    // Its own key errors are located like the built-ins'.
    let bad = t.replace("k = 5e4", "k = -1");
    let Err(ScenarioError::Input { location, key, .. }) =
        Scene::from_text_with(&registry, "servo.toml", "servo", &bad)
    else {
        panic!("accepted");
    };
    assert_eq!(key, "control.k");
    assert_eq!(location.map(|l| l.line), Some(line_of(&bad, "k =")));
    // The default registry does not know it.
    let (_, _, key, message) = refused(&t);
    assert_eq!(key, "control.kind");
    assert!(message.contains("\"pd\", \"pid\""), "{message}");
}

#[test]
fn set_checks_control_and_actuator_keys_at_once() {
    let mut table: toml::Table = text("coupled", "").parse().expect("toml");
    let set = |table: &mut toml::Table, key: &str, value: toml::Value| {
        setting::set_checked(table, key, &value)
    };
    // A table built key by key: incomplete in between, checked as it goes.
    set(&mut table, "control.kind", "pd".into()).expect("kind");
    set(&mut table, "control.kp", 200_000.into()).expect("an integer gain");
    set(&mut table, "control.kd", 400.0.into()).expect("kd");
    set(&mut table, "actuators.kind", "motor_ballscrew".into()).expect("kind");
    for (key, value) in [
        ("rotor_inertia", 1.6e-5),
        ("lead", 0.01),
        ("efficiency", 0.9),
        ("peak_torque", 3.5),
        ("continuous_torque", 1.2),
        ("max_speed", 100.0),
    ] {
        set(&mut table, &format!("actuators.{key}"), value.into()).expect(key);
    }
    let text = toml::to_string(&table).expect("toml");
    let scene = load(&text).expect("the set scene loads");
    assert!(scene.controller.is_some() && scene.actuator.is_some());
    // Unknown keys, wrong types and bad gains are refused where they are set.
    for (key, value, words) in [
        ("control.kq", toml::Value::from(1.0), "unknown field `kq`"),
        ("control.kp", toml::Value::from(-1.0), "got -1"),
        ("control.feedforward", toml::Value::from("full"), "rigid"),
        (
            "actuators.leed",
            toml::Value::from(0.01),
            "unknown field `leed`",
        ),
        ("actuators.lead", toml::Value::from("ten"), "string \"ten\""),
    ] {
        let before = table.clone();
        let e = set(&mut table, key, value).expect_err(key);
        assert!(e.to_string().contains(words), "{key}: {e}");
        assert_eq!(table, before, "{key}: a refused set changed the table");
    }
}

#[test]
fn a_motor_drive_is_all_three_keys_or_none_and_each_is_checked_at_its_key() {
    let drive = "torque_constant = 0.2\nresistance = 1.5\nbus_voltage = 100\ncurrent_limit = 12\n";
    let scene = load(&text("coupled", &format!("{MOTOR}{drive}{PD}"))).expect("valid");
    let actuator = scene.actuator.as_ref().expect("motor");
    let names: Vec<&str> = actuator.signals().iter().map(|s| s.name).collect();
    assert_eq!(
        names,
        [
            "motor_torque",
            "motor_speed",
            "motor_saturated",
            "motor_current",
            "motor_voltage"
        ]
    );
    // The drive is echoed with the motor's other keys (a planned scene keeps it).
    let echoed = toml::to_string(&scene.file).expect("serializes");
    assert!(echoed.contains("bus_voltage = 100"), "{echoed}");
    // Without a drive the motor's signals are the three of before.
    let plain = load(&text("coupled", &format!("{MOTOR}{PD}"))).expect("valid");
    assert_eq!(plain.actuator.as_ref().unwrap().signals().len(), 3);

    let (_, _, key, message) = refused(&text(
        "coupled",
        &format!("{MOTOR}torque_constant = 0.2\nbus_voltage = 100\n{PD}"),
    ));
    assert_eq!(key, "actuators", "{message}");
    assert!(message.contains("resistance is missing"), "{message}");
    let (_, _, key, message) = refused(&text(
        "coupled",
        &format!("{MOTOR}torque_constant = 0.2\nresistance = 0\nbus_voltage = 100\n{PD}"),
    ));
    assert_eq!(key, "actuators.resistance", "{message}");
    assert!(message.contains("> 0"), "{message}");
}
