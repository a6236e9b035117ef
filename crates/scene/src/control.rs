//! `[actuators]` and `[control]` (docs/control.md): the sliders' actuator and control law,
//! and the rules that tie them to the model.
//!
//! * `[control]` makes the sliders degrees of freedom driven by the actuators: only the
//!   coupled and nonlinear models have them (the KED model prescribes the platform, and so
//!   the sliders). Without `[actuators]` the actuator is the ideal force.
//! * `[actuators]` without `[control]` is allowed for every model: the sliders stay on their
//!   commanded path, and a motor's ratings are what the motion is checked against
//!   (feasibility).
//! * `delay`, `delay_order` and `quantisation` are read here for every law (built in or
//!   registered): the law the factory builds is wrapped in a [`SensedLaw`].

use std::sync::Arc;

use flexprr_control::{Actuator, Controller, IdealForce, SensedLaw, Sensors};
use serde::Deserialize;

use crate::error::ScenarioError;
use crate::registry::{Registry, TableParams};
use crate::scene::Checker;
use crate::schema::SceneFile;

/// What `[actuators]` and `[control]` build.
pub(crate) struct ControlParts {
    /// The actuator of every slider: `[actuators]`, or the ideal force under `[control]`.
    pub(crate) actuator: Option<Arc<dyn Actuator>>,
    /// The control law, when the sliders are actuated.
    pub(crate) controller: Option<Arc<dyn Controller>>,
}

/// `[actuators]` and `[control]`, checked against the scene's model.
pub(crate) fn build_control(
    c: &Checker<'_>,
    registry: &Registry,
    raw: &SceneFile,
    caps: crate::ModelCapabilities,
) -> Result<ControlParts, ScenarioError> {
    let actuator = raw
        .actuators
        .as_ref()
        .map(|a| {
            let params = TableParams::new(c.file, c.text, "actuators", &a.params);
            registry.build_actuator(&params, &a.kind)
        })
        .transpose()?;
    let controller = match &raw.control {
        None => None,
        Some(table) => {
            if !caps.free_platform {
                return Err(c.error(
                    "control",
                    "the KED model prescribes the platform motion, and with it the sliders, so \
                     there is nothing to control: set model.coupling = \"coupled\" or \
                     \"nonlinear\" (the sliders then move under the actuators), or remove \
                     [control] ([actuators] alone checks the motion against the motors)",
                ));
            }
            let mut law_keys = table.params.clone();
            let mut sensor_keys = toml::Table::new();
            for key in SENSOR_KEYS {
                if let Some(value) = law_keys.remove(key) {
                    sensor_keys.insert(key.to_string(), value);
                }
            }
            let params = TableParams::new(c.file, c.text, "control", &law_keys);
            let law = registry.build_controller(&params, &table.kind)?;
            let sensors = TableParams::new(c.file, c.text, "control", &sensor_keys);
            Some(sensed(&params, &sensors, law)?)
        }
    };
    let actuator = match (actuator, &controller) {
        (None, Some(_)) => Some(Arc::new(IdealForce) as Arc<dyn Actuator>),
        (actuator, _) => actuator,
    };
    Ok(ControlParts {
        actuator,
        controller,
    })
}

/// The keys every law has: its sensors.
const SENSOR_KEYS: [&str; 3] = ["delay", "delay_order", "quantisation"];

/// `delay`, `delay_order`, `quantisation` of `[control]`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SensorKeys {
    #[serde(default)]
    delay: f64,
    delay_order: Option<usize>,
    quantisation: Option<Vec<f64>>,
}

/// `law` behind the sensors of `keys` (`law` itself without any); the law's own keys
/// `params` name its measurements when it lists them.
fn sensed(
    params: &TableParams<'_>,
    keys: &TableParams<'_>,
    law: Arc<dyn Controller>,
) -> Result<Arc<dyn Controller>, ScenarioError> {
    if keys.table().is_empty() {
        return Ok(law);
    }
    let k: SensorKeys = keys.parse()?;
    if !(k.delay.is_finite() && k.delay >= 0.0) {
        return Err(keys.error(
            "delay",
            format!(
                "a transport delay must be finite and >= 0 (s), got {}",
                crate::error::number(k.delay)
            ),
        ));
    }
    if k.delay_order.is_some() && (law.period() > 0.0 || k.delay <= 0.0) {
        return Err(keys.error(
            "delay_order",
            "the Pade order of a continuous law's delay: a sampled law's delay is a shift of              its samples, and without a delay there is nothing to approximate",
        ));
    }
    let mut sensors = Sensors {
        delay: k.delay,
        ..Sensors::default()
    };
    if let Some(order) = k.delay_order {
        sensors.pade_order = order;
    }
    if let Some(steps) = &k.quantisation {
        sensors.quantisation = quantisation(params, keys, steps)?;
    }
    let law = SensedLaw::new(law, sensors).map_err(|e| keys.control_error(e))?;
    Ok(Arc::new(law))
}

/// The step of each slider's measured `[position, velocity]` from `quantisation`: one per
/// measurement of a law that lists its `measurements` (the signal each reads: a position or
/// an error quantises the slider's position, a velocity or an error rate its velocity),
/// else one per slider (its position encoder).
fn quantisation(
    params: &TableParams<'_>,
    keys: &TableParams<'_>,
    steps: &[f64],
) -> Result<[[f64; 2]; 3], ScenarioError> {
    if let Some(bad) = steps.iter().find(|q| !(q.is_finite() && **q >= 0.0)) {
        return Err(keys.error(
            "quantisation",
            format!(
                "a quantisation step must be finite and >= 0 (0 for none), got {}",
                crate::error::number(*bad)
            ),
        ));
    }
    let mut out = [[0.0; 2]; 3];
    let listed = params
        .table()
        .get("measurements")
        .and_then(|m| m.as_array());
    let Some(listed) = listed else {
        if steps.len() != 3 {
            return Err(keys.error(
                "quantisation",
                format!(
                    "{} steps, expected 3: the resolution of each slider's position encoder (m),                      0 for none",
                    steps.len()
                ),
            ));
        }
        for (slider, q) in out.iter_mut().zip(steps) {
            slider[0] = *q;
        }
        return Ok(out);
    };
    if steps.len() != listed.len() {
        return Err(keys.error(
            "quantisation",
            format!(
                "{} steps, expected {}: one per entry of measurements (its resolution, 0 for                  none)",
                steps.len(),
                listed.len()
            ),
        ));
    }
    for (name, q) in listed.iter().zip(steps) {
        let Some(signal) = name
            .as_str()
            .and_then(|n| crate::statespace_law::measurement(n).ok())
        else {
            continue;
        };
        let slot = &mut out[signal.slider()][usize::from(signal.is_rate())];
        if *slot > 0.0 && *q > 0.0 && (*slot - q).abs() > 1e-12 * q {
            return Err(keys.error(
                "quantisation",
                format!(
                    "two measurements read slider {}'s {} through different steps ({} and {}):                      one sensor has one resolution",
                    signal.slider() + 1,
                    if signal.is_rate() { "velocity" } else { "position" },
                    *slot,
                    q
                ),
            ));
        }
        if *q > 0.0 {
            *slot = *q;
        }
    }
    Ok(out)
}
