//! `[actuators]` and `[control]` (docs/control.md): the sliders' actuator and control law,
//! and the rules that tie them to the model.
//!
//! * `[control]` makes the sliders degrees of freedom driven by the actuators: only the
//!   coupled and nonlinear models have them (the KED model prescribes the platform, and so
//!   the sliders). Without `[actuators]` the actuator is the ideal force.
//! * `[actuators]` without `[control]` is allowed for every model: the sliders stay on their
//!   commanded path, and a motor's ratings are what the motion is checked against
//!   (feasibility).

use std::sync::Arc;

use flexprr_control::{Actuator, Controller, IdealForce};

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
            let params = TableParams::new(c.file, c.text, "control", &table.params);
            Some(registry.build_controller(&params, &table.kind)?)
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
