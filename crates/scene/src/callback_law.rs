//! `[control] kind = "python"` (docs/control.md, "Python laws"): a sampled law whose
//! commands a function computes at each sample, on the state-space law's channels
//! (`measurements`, `commands`, `feedforward`) with a required `period > 0`.
//!
//! The function comes from the program that loads the scene: the Python bindings register a
//! [`CallbackLawFactory`] holding the user's function (`flexprr.run(scene, controller=f)`).
//! The default registry's factory has none: it checks the keys and then refuses the scene at
//! `control.kind`, saying how to run it.

use std::sync::Arc;

use flexprr_control::{CallbackLaw, Controller, LawFunction};
use serde::Deserialize;

use crate::controllers::{ControllerFactory, Feedforward};
use crate::error::ScenarioError;
use crate::registry::TableParams;

/// The keys of `kind = "python"`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Keys {
    measurements: Vec<String>,
    commands: Vec<String>,
    #[serde(default)]
    feedforward: Feedforward,
    period: Option<f64>,
}

/// The factory of `kind = "python"` (or any name a program registers it under): with a
/// function, a [`CallbackLaw`] calling it; without one, a clear refusal after the keys are
/// checked.
///
/// ```
/// use std::sync::Arc;
/// use flexprr_control::LawFunction;
/// use flexprr_scene::{CallbackLawFactory, Registry};
///
/// /// A PD law on `slider_error:I, slider_error_rate:I` for each slider.
/// struct Pd;
/// impl LawFunction for Pd {
///     fn call(&self, _t: f64, y: &[f64], u: &mut [f64]) -> Result<(), String> {
///         for i in 0..u.len() {
///             u[i] = 2e5 * y[i] + 2e3 * y[u.len() + i];
///         }
///         Ok(())
///     }
/// }
/// let mut registry = Registry::default();
/// registry.register_controller("python", Arc::new(CallbackLawFactory::new(Some(Arc::new(Pd)))));
/// ```
#[derive(Clone, Default)]
pub struct CallbackLawFactory {
    function: Option<Arc<dyn LawFunction>>,
}

impl CallbackLawFactory {
    /// The factory of laws calling `function` (`None`: scenes are refused at `control.kind`
    /// with the way to run them from Python).
    pub fn new(function: Option<Arc<dyn LawFunction>>) -> Self {
        Self { function }
    }
}

/// What the default registry says of a `kind = "python"` scene.
pub const PYTHON_LAW_NEEDS_PYTHON: &str = "a \"python\" control law is a Python function: run \
     this scene from Python with flexprr.run(scene, controller=f), f(t, y) returning the \
     commands (the command line and the linear tools cannot call it)";

impl ControllerFactory for CallbackLawFactory {
    fn build(&self, params: &TableParams<'_>) -> Result<Arc<dyn Controller>, ScenarioError> {
        let keys: Keys = params.parse()?;
        let (measurements, commands) =
            crate::statespace_law::channels(params, &keys.measurements, &keys.commands)?;
        let Some(period) = keys.period else {
            return Err(params.error(
                "period",
                "a Python law is sampled: set period = T (s, > 0), the time between calls of \
                 its function (the command is held in between)",
            ));
        };
        if !(period.is_finite() && period > 0.0) {
            return Err(params.error(
                "period",
                format!(
                    "a Python law is sampled: the period must be finite and > 0 (s), got {}",
                    crate::error::number(period)
                ),
            ));
        }
        let Some(function) = self.function.clone() else {
            return Err(params.value_error("kind", PYTHON_LAW_NEEDS_PYTHON));
        };
        let law = CallbackLaw::new(
            "python",
            measurements,
            commands,
            keys.feedforward.on(),
            period,
            function,
        )
        .map_err(|e| params.control_error(e))?
        .with_friction_feedforward(keys.feedforward.friction());
        Ok(Arc::new(law))
    }
}
