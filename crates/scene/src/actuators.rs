//! Actuator kinds that a scene's `[actuators]` table names by `kind`: the factory trait and
//! the built-in `force` and `motor_ballscrew` (docs/control.md).

use std::sync::Arc;

use flexprr_control::{
    Actuator, Drive, IdealForce, LuGre, MotorBallScrew, MotorRatings, Screw, Winding,
};
use serde::Deserialize;

use crate::error::ScenarioError;
use crate::registry::TableParams;
use crate::schema::DEFAULT_COULOMB_SMOOTHING;

/// A kind of actuator that a scene can name in `actuators.kind`: it reads its own keys from
/// the `[actuators]` table (everything but `kind`) and builds the actuator of every slider.
/// The actuator's named signals ([`Actuator::signals`]) become columns of `actuators.csv`.
///
/// Register one with [`crate::Registry::register_actuator`] and load scenes with
/// [`crate::Scene::load_with`].
///
/// ```
/// use std::sync::Arc;
/// use flexprr_control::{Actuator, ActuatorOutput, ActuatorSignal};
/// use flexprr_scene::{ActuatorFactory, Registry, ScenarioError, TableParams};
///
/// /// The force it delivers (N), reported as a signal.
/// const GAIN: [ActuatorSignal; 1] =
///     [ActuatorSignal { name: "scaled_command", header_unit: "N", symbol: "kF", unit: "N" }];
///
/// /// A force scaled by a gain `k` (an amplifier with a known gain error).
/// #[derive(Debug)]
/// struct Scaled(f64);
/// impl Actuator for Scaled {
///     fn apply(&self, command: f64, _velocity: f64) -> ActuatorOutput {
///         let force = self.0 * command;
///         ActuatorOutput::with_signals(force, false, &GAIN, &[force])
///     }
///     fn name(&self) -> &'static str { "scaled" }
///     fn signals(&self) -> &'static [ActuatorSignal] { &GAIN }
/// }
///
/// #[derive(serde::Deserialize)]
/// #[serde(deny_unknown_fields)]
/// struct Keys {
///     k: f64,
/// }
///
/// struct ScaledFactory;
/// impl ActuatorFactory for ScaledFactory {
///     fn build(&self, params: &TableParams<'_>) -> Result<Arc<dyn Actuator>, ScenarioError> {
///         let keys: Keys = params.parse()?;
///         if !(keys.k.is_finite() && keys.k > 0.0) {
///             return Err(params.error("k", format!("must be finite and > 0, got {}", keys.k)));
///         }
///         Ok(Arc::new(Scaled(keys.k)))
///     }
/// }
///
/// let mut registry = Registry::default();
/// registry.register_actuator("scaled", Arc::new(ScaledFactory));
/// assert!(registry.actuator_names().contains(&"scaled"));
/// ```
pub trait ActuatorFactory: Send + Sync {
    /// Builds the actuator from the keys of its table.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] naming the offending key (use [`TableParams::error`], or
    /// [`TableParams::control_error`] for a [`flexprr_control::ControlError`]).
    fn build(&self, params: &TableParams<'_>) -> Result<Arc<dyn Actuator>, ScenarioError>;

    /// The keys of a table that [`ActuatorFactory::build`] accepted, as the loaded scene keeps
    /// them and writes them back (`flexprr plan`'s `planned.toml`), in this order: a kind
    /// with defaults fills them in. By default the keys as written, sorted.
    fn canonical_keys(&self, params: &toml::Table) -> Vec<(String, toml::Value)> {
        params.iter().map(|(k, v)| (k.clone(), v.clone())).collect()
    }
}

/// Completes the scene's `[actuators]` table through its kind's
/// [`ActuatorFactory::canonical_keys`] (after the kind built it).
pub(crate) fn complete(factory: &dyn ActuatorFactory, table: &mut crate::ActuatorsTable) {
    let keys = factory.canonical_keys(&table.params);
    table.order = keys.iter().map(|(k, _)| k.clone()).collect();
    table.params = keys.into_iter().collect();
}

/// `kind = "force"`: takes no keys.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ForceKeys {}

/// `kind = "force"`: the ideal force.
pub(crate) struct ForceFactory;

impl ActuatorFactory for ForceFactory {
    fn build(&self, params: &TableParams<'_>) -> Result<Arc<dyn Actuator>, ScenarioError> {
        let ForceKeys {} = params.parse()?;
        Ok(Arc::new(IdealForce))
    }
}

/// The keys of `kind = "motor_ballscrew"`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MotorKeys {
    /// Rotor (with coupling and screw) inertia (kg m^2).
    rotor_inertia: f64,
    /// Screw lead (m/rev).
    lead: f64,
    /// Screw efficiency, in (0, 1].
    efficiency: f64,
    /// Peak torque (N m): the torque saturates here.
    peak_torque: f64,
    /// Continuous torque (N m): the RMS torque should stay below it.
    continuous_torque: f64,
    /// Largest motor speed (rev/s): reported, not enforced.
    max_speed: f64,
    /// Viscous friction at the motor shaft (N m s/rad).
    #[serde(default)]
    viscous_friction: f64,
    /// Coulomb friction torque at the motor shaft (N m).
    #[serde(default)]
    coulomb_friction: f64,
    /// Speed of the Coulomb friction's tanh smoothing (rev/s).
    #[serde(default = "default_coulomb_smoothing")]
    coulomb_smoothing: f64,
    /// The drive's torque constant (N m/A): with `resistance` and `bus_voltage`, the
    /// torque-speed envelope.
    #[serde(default)]
    torque_constant: Option<f64>,
    /// Winding resistance (ohm).
    #[serde(default)]
    resistance: Option<f64>,
    /// DC bus voltage (V).
    #[serde(default)]
    bus_voltage: Option<f64>,
    /// The drive's current limit (A); none unless set.
    #[serde(default)]
    current_limit: Option<f64>,
    /// The winding's inductance (H): the current becomes a state (needs the drive).
    #[serde(default)]
    inductance: Option<f64>,
    /// The bandwidth of the drive's PI current loop (Hz; needs `inductance`).
    #[serde(default)]
    current_bandwidth: Option<f64>,
    /// The screw's axial stiffness (N/m): the rotor becomes a mass on a spring.
    #[serde(default)]
    screw_stiffness: Option<f64>,
    /// The screw's axial damping (N s/m; needs `screw_stiffness`).
    #[serde(default)]
    screw_damping: Option<f64>,
    /// Whether a law's feedforward adds the steady friction at the commanded velocity.
    #[serde(default)]
    friction_feedforward: bool,
    /// The friction model: `"coulomb"` (viscous and smoothed Coulomb, the default) or
    /// `"lugre"` (with the four keys below).
    #[serde(default)]
    friction: FrictionKind,
    /// Static (breakaway) torque of LuGre friction (N m).
    #[serde(default)]
    static_friction: Option<f64>,
    /// Stribeck speed of LuGre friction (rev/s).
    #[serde(default)]
    stribeck_speed: Option<f64>,
    /// Bristle stiffness of LuGre friction (N m/rad).
    #[serde(default)]
    bristle_stiffness: Option<f64>,
    /// Bristle damping of LuGre friction (N m s/rad); by default critical damping of the
    /// rotor on the bristles, `2 sqrt(sigma0 J)`.
    #[serde(default)]
    bristle_damping: Option<f64>,
}

/// `friction` of a motor.
#[derive(Debug, Clone, Copy, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
enum FrictionKind {
    /// Viscous plus `tanh`-smoothed Coulomb friction.
    #[default]
    Coulomb,
    /// LuGre friction: a stuck phase, breakaway and a Stribeck curve.
    Lugre,
}

/// The LuGre keys, all required with `friction = "lugre"` but `bristle_damping`.
const LUGRE_KEYS: [&str; 4] = [
    "static_friction",
    "stribeck_speed",
    "bristle_stiffness",
    "bristle_damping",
];

impl MotorKeys {
    /// The LuGre friction of the keys (`None` without `friction = "lugre"`); a key that
    /// does not fit the friction model: its name and the rule.
    fn lugre(&self, written: &toml::Table) -> Result<Option<LuGre>, (&'static str, String)> {
        let k = self;
        if self.friction == FrictionKind::Coulomb {
            return match LUGRE_KEYS.iter().find(|key| written.contains_key(**key)) {
                Some(key) => Err((
                    key,
                    format!("{key} is a key of LuGre friction: set friction = \"lugre\" with it"),
                )),
                None => Ok(None),
            };
        }
        if written.contains_key("coulomb_smoothing") {
            return Err((
                "coulomb_smoothing",
                "LuGre friction is not smoothed (its bristles make it continuous): remove coulomb_smoothing with friction = \"lugre\"".to_string(),
            ));
        }
        let required = [
            ("static_friction", k.static_friction, "N m"),
            ("stribeck_speed", k.stribeck_speed, "rev/s"),
            ("bristle_stiffness", k.bristle_stiffness, "N m/rad"),
        ];
        if let Some((key, _, unit)) = required.iter().find(|(_, v, _)| v.is_none()) {
            return Err((
                "friction",
                format!(
                    "{key} is missing: friction = \"lugre\" needs static_friction, stribeck_speed and bristle_stiffness ({key} in {unit})"
                ),
            ));
        }
        let stiffness = k.bristle_stiffness.unwrap_or(0.0);
        Ok(Some(LuGre {
            static_friction: k.static_friction.unwrap_or(0.0),
            stribeck_speed: k.stribeck_speed.unwrap_or(0.0),
            bristle_stiffness: stiffness,
            bristle_damping: k
                .bristle_damping
                .unwrap_or_else(|| default_bristle_damping(stiffness, self.rotor_inertia)),
        }))
    }
}

/// The default bristle damping: critical damping of the rotor's inertia `J` on the bristle
/// spring `sigma0`, `2 sqrt(sigma0 J)` (N m s/rad; 0 for a non-positive product).
fn default_bristle_damping(stiffness: f64, rotor_inertia: f64) -> f64 {
    2.0 * (stiffness * rotor_inertia).max(0.0).sqrt()
}

/// The drive keys of a motor, all or none (`current_limit` optional with the others).
const DRIVE_KEYS: [&str; 3] = ["torque_constant", "resistance", "bus_voltage"];

impl MotorKeys {
    /// A key given without the keys it needs: `(key, message)`.
    fn orphan(&self) -> Option<(&'static str, &'static str)> {
        if self.current_bandwidth.is_some() && self.inductance.is_none() {
            return Some((
                "current_bandwidth",
                "needs inductance: the current loop acts on the winding's inductance (set inductance, or remove current_bandwidth for the steady-state drive)",
            ));
        }
        if self.screw_damping.is_some() && self.screw_stiffness.is_none() {
            return Some((
                "screw_damping",
                "needs screw_stiffness: the damping acts beside the screw's spring (set screw_stiffness, or remove screw_damping for a rigid screw)",
            ));
        }
        None
    }

    /// The screw, when compliant.
    fn screw(&self) -> Option<Screw> {
        self.screw_stiffness.map(|stiffness| Screw {
            stiffness,
            damping: self.screw_damping.unwrap_or(0.0),
        })
    }

    /// The drive, when its keys are given; the first missing key of a partial drive.
    fn drive(&self) -> Result<Option<Drive>, &'static str> {
        let given = [self.torque_constant, self.resistance, self.bus_voltage];
        match given {
            [None, None, None] if self.current_limit.is_none() && self.inductance.is_none() => {
                Ok(None)
            }
            [Some(torque_constant), Some(resistance), Some(bus_voltage)] => Ok(Some(Drive {
                torque_constant,
                resistance,
                bus_voltage,
                current_limit: self.current_limit.unwrap_or(f64::INFINITY),
                winding: self.inductance.map(|inductance| Winding {
                    inductance,
                    current_bandwidth: self.current_bandwidth,
                }),
            })),
            _ => Err(DRIVE_KEYS
                .iter()
                .zip(given)
                .find(|(_, v)| v.is_none())
                .map_or("torque_constant", |(k, _)| *k)),
        }
    }
}

fn default_coulomb_smoothing() -> f64 {
    DEFAULT_COULOMB_SMOOTHING
}

impl From<MotorKeys> for MotorBallScrew {
    fn from(k: MotorKeys) -> Self {
        let drive = k.drive().ok().flatten();
        MotorBallScrew {
            rotor_inertia: k.rotor_inertia,
            lead: k.lead,
            efficiency: k.efficiency,
            ratings: MotorRatings {
                peak_torque: k.peak_torque,
                continuous_torque: k.continuous_torque,
                max_speed: k.max_speed,
            },
            viscous_friction: k.viscous_friction,
            coulomb_friction: k.coulomb_friction,
            coulomb_smoothing: k.coulomb_smoothing,
            drive,
            screw: k.screw(),
            friction_feedforward: k.friction_feedforward,
            lugre: k.lugre(&toml::Table::new()).ok().flatten(),
        }
    }
}

/// The motor and ball screw of the keys `params` of a `kind = "motor_ballscrew"` table, not
/// yet validated; `None` if they do not read as one.
pub(crate) fn motor_ballscrew_of(params: &toml::Table) -> Option<MotorBallScrew> {
    params
        .clone()
        .try_into::<MotorKeys>()
        .ok()
        .map(MotorBallScrew::from)
}

/// `kind = "motor_ballscrew"`: a servo motor on a ball screw, every parameter checked at
/// its key.
pub(crate) struct MotorBallScrewFactory;

impl ActuatorFactory for MotorBallScrewFactory {
    fn build(&self, params: &TableParams<'_>) -> Result<Arc<dyn Actuator>, ScenarioError> {
        let keys: MotorKeys = params.parse()?;
        if let Some((key, message)) = keys.orphan() {
            return Err(params.error(key, message.to_string()));
        }
        if keys.inductance.is_some()
            && keys.torque_constant.is_none()
            && keys.resistance.is_none()
            && keys.bus_voltage.is_none()
        {
            return Err(params.error(
                "inductance",
                "needs the drive: torque_constant, resistance and bus_voltage (the winding's time constant is L / R, its current limited by the bus voltage)".to_string(),
            ));
        }
        if let Err(missing) = keys.drive() {
            return Err(params.error(
                "",
                format!(
                    "{missing} is missing: the drive needs torque_constant, resistance and bus_voltage together (current_limit is optional); set all three, or none for a motor without electrics"
                ),
            ));
        }
        if let Err((key, message)) = keys.lugre(params.table()) {
            return Err(params.error(key, message));
        }
        let motor = MotorBallScrew::from(keys)
            .validated()
            .map_err(|e| params.control_error(e))?;
        Ok(Arc::new(motor))
    }

    /// Every key, defaults filled in, as numbers (`max_speed = 100.0`), in the order of the
    /// documentation.
    fn canonical_keys(&self, params: &toml::Table) -> Vec<(String, toml::Value)> {
        let Ok(k) = params.clone().try_into::<MotorKeys>() else {
            return params.iter().map(|(k, v)| (k.clone(), v.clone())).collect();
        };
        let mut keys: Vec<(String, toml::Value)> = [
            ("rotor_inertia", k.rotor_inertia),
            ("lead", k.lead),
            ("efficiency", k.efficiency),
            ("peak_torque", k.peak_torque),
            ("continuous_torque", k.continuous_torque),
            ("max_speed", k.max_speed),
            ("viscous_friction", k.viscous_friction),
            ("coulomb_friction", k.coulomb_friction),
            ("coulomb_smoothing", k.coulomb_smoothing),
        ]
        .into_iter()
        .chain(
            [
                ("torque_constant", k.torque_constant),
                ("resistance", k.resistance),
                ("bus_voltage", k.bus_voltage),
                ("current_limit", k.current_limit),
                ("inductance", k.inductance),
                ("current_bandwidth", k.current_bandwidth),
                ("screw_stiffness", k.screw_stiffness),
                ("screw_damping", k.screw_damping),
            ]
            .into_iter()
            .filter_map(|(key, value)| value.map(|v| (key, v))),
        )
        .map(|(key, value)| (key.to_string(), toml::Value::Float(value)))
        .chain(k.friction_feedforward.then(|| {
            (
                "friction_feedforward".to_string(),
                toml::Value::Boolean(true),
            )
        }))
        .collect();
        if let Ok(Some(lugre)) = k.lugre(params) {
            // LuGre friction has no smoothing: its keys replace coulomb_smoothing.
            keys.retain(|(key, _)| key != "coulomb_smoothing");
            keys.push((
                "friction".to_string(),
                toml::Value::String("lugre".to_string()),
            ));
            keys.extend(
                LUGRE_KEYS
                    .into_iter()
                    .zip([
                        lugre.static_friction,
                        lugre.stribeck_speed,
                        lugre.bristle_stiffness,
                        lugre.bristle_damping,
                    ])
                    .map(|(key, value)| (key.to_string(), toml::Value::Float(value))),
            );
        }
        keys
    }
}
