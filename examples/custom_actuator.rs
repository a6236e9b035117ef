//! Registers a new actuator kind from outside the crates, with signals of its own, and runs
//! a TOML scene that selects it with `[actuators] kind = "linear_motor"`.
//!
//! The kind is a direct-drive linear motor: force constant `K_f` (N/A), a current limit
//! `I_peak` (A) and a winding resistance `R` (ohm). The current command is `F_c / K_f`,
//! clipped at `I_peak`; the force is `K_f i`; the copper loss `R i^2`. It reports two
//! signals beside the force, `current` (A) and `copper_loss` (W), which become the columns
//! `current_I_A` and `copper_loss_I_W` of `actuators.csv` for each slider `I`.
//!
//! What the example checks, against laws rather than against its own earlier output:
//! * below the current limit the motor is an ideal force, so the same scene under
//!   `kind = "force"` (a built-in, a second code path) gives the same force on every slider
//!   at every output time;
//! * with a limit below the motion's peak force, every sample obeys the motor's laws as
//!   read back from the table: `|i| <= I_peak`, `F = K_f i`, `P = R i^2`, and the force is
//!   clipped at `K_f I_peak` exactly where the command is beyond it.
//!
//! Run: `cargo run --release --example custom_actuator`

use std::sync::Arc;

use flexprr_control::{Actuator, ActuatorOutput, ActuatorSignal};
use flexprr_dynamics::Table;
use flexprr_scene::{ActuatorFactory, Registry, ScenarioError, Scene, TableParams};

/// The linear motor's signals: the winding current after the limit and its copper loss.
const SIGNALS: [ActuatorSignal; 2] = [
    ActuatorSignal {
        name: "current",
        header_unit: "A",
        symbol: "i",
        unit: "A",
    },
    ActuatorSignal {
        name: "copper_loss",
        header_unit: "W",
        symbol: "P_Cu",
        unit: "W",
    },
];

/// A direct-drive linear motor (see the module documentation).
#[derive(Debug)]
struct LinearMotor {
    force_constant: f64,
    peak_current: f64,
    resistance: f64,
}

impl Actuator for LinearMotor {
    fn apply(&self, command: f64, _velocity: f64) -> ActuatorOutput {
        let wanted = command / self.force_constant;
        let current = wanted.clamp(-self.peak_current, self.peak_current);
        ActuatorOutput::with_signals(
            self.force_constant * current,
            wanted.abs() > self.peak_current,
            &SIGNALS,
            &[current, self.resistance * current * current],
        )
    }
    fn name(&self) -> &'static str {
        "linear_motor"
    }
    fn signals(&self) -> &'static [ActuatorSignal] {
        &SIGNALS
    }
    fn force_limit(&self) -> f64 {
        self.force_constant * self.peak_current
    }
}

/// The keys of `[actuators] kind = "linear_motor"`.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct Keys {
    force_constant: f64,
    peak_current: f64,
    resistance: f64,
}

struct LinearMotorFactory;

impl ActuatorFactory for LinearMotorFactory {
    fn build(&self, params: &TableParams<'_>) -> Result<Arc<dyn Actuator>, ScenarioError> {
        let keys: Keys = params.parse()?;
        for (key, value, unit) in [
            ("force_constant", keys.force_constant, "N/A"),
            ("peak_current", keys.peak_current, "A"),
            ("resistance", keys.resistance, "ohm"),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(
                    params.error(key, format!("must be finite and > 0 ({unit}), got {value}"))
                );
            }
        }
        Ok(Arc::new(LinearMotor {
            force_constant: keys.force_constant,
            peak_current: keys.peak_current,
            resistance: keys.resistance,
        }))
    }
}

/// The paper's machine on the 20 Hz circle for 0.05 s, coupled model, sliders under PD
/// control, with the `[actuators]` table `actuators`.
fn scene_text(actuators: &str) -> String {
    format!(
        r#"name = "custom_actuator"

[links]
length = 0.2
modes = 3
material = {{ youngs_modulus = 7.3e10, density = 2770.0 }}
section = {{ kind = "uniform", thickness = 0.002, height = 0.03 }}
basis = {{ kind = "sine" }}

[trajectory]
kind = "circle"
centre = [-0.05, 0.0]
radius = 0.05
frequency = 20.0
phi_deg = 45.0

[model]
formulation = "consistent"
coupling = "coupled"

{actuators}
[control]
kind = "pd"
kp = 2e5
kd = 400
feedforward = "rigid"

[integrator]
method = "abm"
rtol = 1e-8
atol = 1e-12

[time]
end = 0.05
output_step = 2e-4

[output]
requests = ["actuators"]
plots = false
"#
    )
}

/// The `actuators` table of a run of the scene with the `[actuators]` table `actuators`.
fn actuators(registry: &Registry, actuators: &str) -> Table {
    let scene = Scene::from_text_with(
        registry,
        "custom_actuator.toml",
        "custom",
        &scene_text(actuators),
    )
    .unwrap_or_else(|e| panic!("scene rejected: {e}"));
    let result = flexprr_run::run(&scene, &mut |_| {}).unwrap_or_else(|e| panic!("run: {e}"));
    result
        .tables
        .into_iter()
        .find(|t| t.name == "actuators")
        .expect("an actuators table")
}

fn column<'a>(table: &'a Table, header: &str) -> &'a [f64] {
    table
        .column(header)
        .unwrap_or_else(|| panic!("no column {header} in {:?}", table.headers()))
}

fn main() {
    let mut registry = Registry::default();
    registry.register_actuator("linear_motor", Arc::new(LinearMotorFactory));
    let k_f = 50.0;
    let motor = |peak: f64| {
        format!(
            "[actuators]\nkind = \"linear_motor\"\nforce_constant = {k_f}\npeak_current = {peak}\nresistance = 2.5\n"
        )
    };

    // Below the limit: the motor is an ideal force.
    let ideal = actuators(&registry, "[actuators]\nkind = \"force\"\n");
    let unclipped = actuators(&registry, &motor(1e3));
    println!("actuators.csv columns: {}", unclipped.headers().join(", "));
    let mut peak_force = 0.0f64;
    let mut difference = 0.0f64;
    for i in 1..=3 {
        let (a, b) = (
            column(&ideal, &format!("actuator_force_{i}_N")),
            column(&unclipped, &format!("actuator_force_{i}_N")),
        );
        for (x, y) in a.iter().zip(b) {
            peak_force = peak_force.max(x.abs());
            difference = difference.max((x - y).abs());
        }
    }
    println!(
        "peak slider force {peak_force:.3} N; linear motor below its limit vs ideal force: {difference:.3e} N"
    );
    assert!(
        difference <= 1e-9 * peak_force,
        "an unsaturated linear motor must deliver the ideal force"
    );

    // A limit at 80 % of the motion's peak force: the laws hold sample by sample.
    let peak_current = 0.8 * peak_force / k_f;
    let clipped = actuators(&registry, &motor(peak_current));
    let mut saturated = 0;
    let samples = clipped.rows();
    for i in 1..=3 {
        let command = column(&clipped, &format!("force_command_{i}_N"));
        let force = column(&clipped, &format!("actuator_force_{i}_N"));
        let current = column(&clipped, &format!("current_{i}_A"));
        let loss = column(&clipped, &format!("copper_loss_{i}_W"));
        for k in 0..samples {
            let i_k = current[k];
            assert!(i_k.abs() <= peak_current * (1.0 + 1e-12), "current {i_k} A");
            assert!(
                (force[k] - k_f * i_k).abs() <= 1e-9 * peak_force,
                "F = K_f i"
            );
            assert!(
                (loss[k] - 2.5 * i_k * i_k).abs() <= 1e-9 * (1.0 + loss[k]),
                "P = R i^2"
            );
            let beyond = command[k].abs() > k_f * peak_current;
            let at_limit = (force[k].abs() - k_f * peak_current).abs() <= 1e-9 * peak_force;
            assert!(
                !beyond || at_limit,
                "a command beyond the limit is clipped at it"
            );
            saturated += usize::from(beyond);
        }
    }
    println!(
        "limit {:.3} A ({:.3} N): {saturated} of {} slider samples clipped, every one at K_f I_peak",
        peak_current,
        k_f * peak_current,
        3 * samples
    );
    assert!(saturated > 0, "the limit must bind somewhere");
}
