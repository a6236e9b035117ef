//! The keys of LuGre friction and of the friction feedforward under `[actuators]`
//! (docs/control.md, "Friction with a stuck phase"): what they build, what a
//! loaded scene writes back, and every error at its key.

use flexprr_scene::{ScenarioError, Scene};

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

const LUGRE: &str = "friction = \"lugre\"\nstatic_friction = 0.03\nstribeck_speed = 0.05\nbristle_stiffness = 30.0\n";

fn scene(actuators: &str, feedforward: &str) -> String {
    format!(
        r#"name = "servo"
[trajectory]
kind = "circle"
frequency = 2.0
[model]
coupling = "coupled"
[time]
end = 0.01
{actuators}
[control]
kind = "pd"
kp = 2e5
kd = 2000
feedforward = "{feedforward}"
"#
    )
}

fn load(text: &str) -> Result<Scene, ScenarioError> {
    Scene::from_text("servo.toml", "servo", text)
}

/// The key and message of the located error of `text`.
fn refused(text: &str) -> (String, String) {
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
            assert!(location.is_some(), "not located: {shown}");
            (key, message)
        }
        other => panic!("accepted: {other:?}"),
    }
}

#[test]
fn lugre_friction_gives_the_motor_its_bristle_state_and_is_written_back_in_full() {
    let loaded = load(&scene(
        &format!("{MOTOR}{LUGRE}friction_feedforward = true\n"),
        "rigid",
    ))
    .expect("valid");
    let actuator = loaded.actuator.as_ref().expect("motor");
    assert_eq!(actuator.states(), 1);
    assert_eq!(actuator.state_names()[0].name, "bristle_deflection");
    // Sliding at 1 rev/s (far above the Stribeck speed) the steady friction is tau_C plus
    // the viscous torque, as a force at the slider.
    let g = std::f64::consts::TAU / 0.01;
    let omega = std::f64::consts::TAU;
    let expected = g * 0.9 * (0.02 + 0.01 * (-(1.0f64 / 0.05).powi(2)).exp() + 1e-4 * omega);
    assert!((actuator.friction_feedforward(0.01) - expected).abs() <= 1e-12 * expected);
    let echoed = toml::to_string(&loaded.file).expect("serializes");
    assert!(echoed.contains("\nfriction = \"lugre\""), "{echoed}");
    assert!(!echoed.contains("coulomb_smoothing"), "{echoed}");
    // The default damping is critical damping of the rotor on the bristles.
    let damping = 2.0 * (30.0f64 * 1.6e-5).sqrt();
    assert!(
        echoed.contains(&format!("bristle_damping = {damping}")),
        "{echoed}"
    );
    // Written back, the scene loads to the same motor.
    let again = load(&echoed).expect("the echoed scene loads");
    assert_eq!(
        format!("{:?}", again.actuator.as_ref().unwrap()),
        format!("{actuator:?}")
    );
    // Without friction = "lugre" the motor has no state and writes no friction key.
    let plain = load(&scene(MOTOR, "rigid")).expect("valid");
    assert_eq!(plain.actuator.as_ref().unwrap().states(), 0);
    let echoed = toml::to_string(&plain.file).expect("serializes");
    assert!(!echoed.contains("\nfriction = "), "{echoed}");
}

#[test]
fn bad_friction_keys_are_refused_at_their_key() {
    let cases = [
        (
            format!("{MOTOR}static_friction = 0.03\n"),
            "actuators.static_friction",
            "set friction = \"lugre\"",
        ),
        (
            format!("{MOTOR}friction = \"lugre\"\nstatic_friction = 0.03\nstribeck_speed = 0.05\n"),
            "actuators.friction",
            "bristle_stiffness is missing",
        ),
        (
            format!("{MOTOR}{LUGRE}coulomb_smoothing = 0.01\n"),
            "actuators.coulomb_smoothing",
            "not smoothed",
        ),
        (
            format!("{MOTOR}{}", LUGRE.replace("0.03", "0.01")),
            "actuators.static_friction",
            "at least coulomb_friction",
        ),
        (
            format!("{MOTOR}{}", LUGRE.replace("30.0", "-1.0")),
            "actuators.bristle_stiffness",
            "> 0",
        ),
        (
            format!("{MOTOR}{LUGRE}bristle_damping = nan\n"),
            "actuators.bristle_damping",
            "finite",
        ),
        (
            format!("{}{LUGRE}", MOTOR.replace("0.02\n", "0\n")),
            "actuators.coulomb_friction",
            "> 0 with friction = \"lugre\"",
        ),
        (
            format!("{MOTOR}friction = \"stribeck\"\n"),
            "actuators.friction",
            "lugre",
        ),
    ];
    for (actuators, key, rule) in cases {
        let (got, message) = refused(&scene(&actuators, "rigid"));
        assert_eq!(got, key, "{actuators}: {message}");
        assert!(message.contains(rule), "{actuators}: {message}");
    }
    let (key, message) = refused(&scene(MOTOR, "rigid+frictio"));
    assert_eq!(key, "control.feedforward", "{message}");
}
