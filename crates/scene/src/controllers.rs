//! Control laws that a scene's `[control]` table names by `kind`: the factory trait and the
//! built-in `pd` and `pid` (docs/control.md).

use std::sync::Arc;

use flexprr_control::{Controller, Pid};
use serde::Deserialize;

use crate::error::ScenarioError;
use crate::registry::TableParams;

/// A kind of control law that a scene can name in `control.kind`: it reads its own keys from
/// the `[control]` table (everything but `kind`) and builds the law.
///
/// Register one with [`crate::Registry::register_controller`] and load scenes with
/// [`crate::Scene::load_with`].
///
/// ```
/// use std::sync::Arc;
/// use flexprr_control::{ControlInput, Controller};
/// use flexprr_scene::{ControllerFactory, Registry, ScenarioError, TableParams};
///
/// /// A proportional law on the position error alone, with its gain `k` (N/m).
/// #[derive(Debug)]
/// struct Proportional(f64);
/// impl Controller for Proportional {
///     fn command(&self, input: &ControlInput<'_>, _: &[f64], force: &mut [f64; 3], _: &mut [f64]) {
///         for i in 0..3 {
///             force[i] = self.0 * (input.reference[i].position - input.measured[i].position);
///         }
///     }
/// }
///
/// #[derive(serde::Deserialize)]
/// #[serde(deny_unknown_fields)]
/// struct Keys {
///     k: f64,
/// }
///
/// struct ProportionalFactory;
/// impl ControllerFactory for ProportionalFactory {
///     fn build(&self, params: &TableParams<'_>) -> Result<Arc<dyn Controller>, ScenarioError> {
///         let keys: Keys = params.parse()?;
///         if !(keys.k.is_finite() && keys.k > 0.0) {
///             return Err(params.error("k", format!("expected a positive gain (N/m), got {}", keys.k)));
///         }
///         Ok(Arc::new(Proportional(keys.k)))
///     }
/// }
///
/// let mut registry = Registry::default();
/// registry.register_controller("p", Arc::new(ProportionalFactory));
/// assert!(registry.controller_names().contains(&"p"));
/// ```
pub trait ControllerFactory: Send + Sync {
    /// Builds the law from the keys of its table.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] naming the offending key (use [`TableParams::error`], or
    /// [`TableParams::control_error`] for a [`flexprr_control::ControlError`]).
    fn build(&self, params: &TableParams<'_>) -> Result<Arc<dyn Controller>, ScenarioError>;
}

/// `feedforward`: the rigid inverse-dynamics force of the commanded motion, with the
/// actuators' steady friction or not, or none.
#[derive(Debug, Clone, Copy, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub(crate) enum Feedforward {
    /// The rigid-body driving force of the commanded motion (with the actuators' reflected
    /// inertia).
    #[default]
    Rigid,
    /// `"rigid+friction"`: [`Feedforward::Rigid`] plus the actuators' steady friction at the
    /// commanded slider velocity.
    #[serde(rename = "rigid+friction")]
    RigidFriction,
    /// No feedforward: the feedback does all the work.
    None,
}

impl Feedforward {
    /// Whether a feedforward is added.
    pub(crate) fn on(self) -> bool {
        self != Self::None
    }

    /// Whether it includes the actuators' friction.
    pub(crate) fn friction(self) -> bool {
        self == Self::RigidFriction
    }
}

/// The keys of `kind = "pd"`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PdKeys {
    kp: f64,
    kd: f64,
    #[serde(default)]
    feedforward: Feedforward,
    #[serde(default)]
    period: f64,
}

/// The keys of `kind = "pid"`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PidKeys {
    kp: f64,
    kd: f64,
    ki: f64,
    #[serde(default)]
    feedforward: Feedforward,
    #[serde(default)]
    period: f64,
}

/// The built-in `pd`: `F = F_ff + kp e + kd e'` on each slider ([`Pid::pd`]).
pub(crate) struct PdFactory;

impl ControllerFactory for PdFactory {
    fn build(&self, params: &TableParams<'_>) -> Result<Arc<dyn Controller>, ScenarioError> {
        if params.table().contains_key("ki") {
            return Err(params.error(
                "ki",
                "the pd law has no integral term: use kind = \"pid\" for an integral gain",
            ));
        }
        let keys: PdKeys = params.parse()?;
        let law = Pid::pd(keys.kp, keys.kd, keys.feedforward.on(), keys.period)
            .map_err(|e| params.control_error(e))?
            .with_friction_feedforward(keys.feedforward.friction());
        Ok(Arc::new(law))
    }
}

/// The built-in `pid`: [`PdFactory`]'s law plus `ki` times the error's integral, with
/// conditional-integration anti-windup ([`Pid::pid`]).
pub(crate) struct PidFactory;

impl ControllerFactory for PidFactory {
    fn build(&self, params: &TableParams<'_>) -> Result<Arc<dyn Controller>, ScenarioError> {
        let keys: PidKeys = params.parse()?;
        let law = Pid::new(
            keys.kp,
            keys.kd,
            keys.ki,
            keys.feedforward.on(),
            keys.period,
        )
        .map_err(|e| params.control_error(e))?
        .with_friction_feedforward(keys.feedforward.friction());
        Ok(Arc::new(law))
    }
}

/// A kind of vibration control law that a scene can name in `vibration_control.kind`: it
/// reads its own keys from the `[vibration_control]` table and builds the law for the
/// scene's patches on its machine.
///
/// ```
/// use std::sync::Arc;
/// use flexprr_control::{VibrationController, VibrationInput};
/// use flexprr_scene::{PatchContext, Registry, ScenarioError, TableParams, VibrationControllerFactory};
///
/// /// Negative position feedback `V = -k V_s` on each collocated pair.
/// #[derive(Debug)]
/// struct Position(f64);
/// impl VibrationController for Position {
///     fn voltages(&self, input: &VibrationInput<'_>, voltages: &mut [f64]) {
///         for (v, s) in voltages.iter_mut().zip(input.sensors) {
///             *v = -self.0 * s;
///         }
///     }
/// }
///
/// #[derive(serde::Deserialize)]
/// #[serde(deny_unknown_fields)]
/// struct Keys {
///     k: f64,
/// }
///
/// struct PositionFactory;
/// impl VibrationControllerFactory for PositionFactory {
///     fn build(
///         &self,
///         params: &TableParams<'_>,
///         _context: &PatchContext<'_>,
///     ) -> Result<Arc<dyn VibrationController>, ScenarioError> {
///         let keys: Keys = params.parse()?;
///         Ok(Arc::new(Position(keys.k)))
///     }
/// }
///
/// let mut registry = Registry::default();
/// registry.register_vibration_controller("position", Arc::new(PositionFactory));
/// assert!(registry.vibration_controller_names().contains(&"position"));
/// ```
pub trait VibrationControllerFactory: Send + Sync {
    /// Builds the law from the keys of its table for the patches of `context`.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] naming the offending key.
    fn build(
        &self,
        params: &TableParams<'_>,
        context: &crate::PatchContext<'_>,
    ) -> Result<Arc<dyn flexprr_control::VibrationController>, ScenarioError>;
}

/// The keys of `kind = "strain_rate"`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StrainRateKeys {
    gain: f64,
    #[serde(default)]
    period: f64,
}

/// The built-in `strain_rate`: `V = -gain V_s'` on each collocated pair.
pub(crate) struct StrainRateFactory;

impl VibrationControllerFactory for StrainRateFactory {
    fn build(
        &self,
        params: &TableParams<'_>,
        _context: &crate::PatchContext<'_>,
    ) -> Result<Arc<dyn flexprr_control::VibrationController>, ScenarioError> {
        let keys: StrainRateKeys = params.parse()?;
        let law = flexprr_control::StrainRate::new(keys.gain, keys.period)
            .map_err(|e| params.control_error(e))?;
        Ok(Arc::new(law))
    }
}

/// The keys of `kind = "modal_velocity"`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ModalVelocityKeys {
    /// Targeted modes of each link with patches (1-based).
    modes: Vec<usize>,
    /// The damping ratio given to each targeted mode.
    damping_ratio: Vec<f64>,
    #[serde(default)]
    period: f64,
}

/// The built-in `modal_velocity`: a modal filter and modal velocity feedback giving each
/// targeted mode of every link with patches its damping ratio
/// ([`flexprr_dynamics::modal_velocity_law`]).
pub(crate) struct ModalVelocityFactory;

impl VibrationControllerFactory for ModalVelocityFactory {
    fn build(
        &self,
        params: &TableParams<'_>,
        context: &crate::PatchContext<'_>,
    ) -> Result<Arc<dyn flexprr_control::VibrationController>, ScenarioError> {
        let keys: ModalVelocityKeys = params.parse()?;
        if keys.modes.contains(&0) {
            return Err(params.error("modes", "modes are numbered from 1"));
        }
        if let Some((k, m)) = keys
            .modes
            .iter()
            .enumerate()
            .find(|(k, m)| keys.modes[..*k].contains(m))
        {
            return Err(params.error(
                "modes",
                format!(
                    "mode {m} is named twice (entries {} and {}): name each targeted mode once",
                    keys.modes.iter().position(|x| x == m).unwrap_or(0) + 1,
                    k + 1
                ),
            ));
        }
        if keys.modes.len() != keys.damping_ratio.len() {
            return Err(params.error(
                "damping_ratio",
                format!(
                    "give one damping ratio per targeted mode: {} modes, {} ratios",
                    keys.modes.len(),
                    keys.damping_ratio.len()
                ),
            ));
        }
        if let Some(z) = keys
            .damping_ratio
            .iter()
            .find(|z| !(z.is_finite() && **z >= 0.0))
        {
            return Err(params.error(
                "damping_ratio",
                format!(
                    "a damping ratio must be finite and >= 0, got {}",
                    crate::error::number(*z)
                ),
            ));
        }
        let modes: Vec<usize> = keys.modes.iter().map(|m| m - 1).collect();
        let law = flexprr_dynamics::modal_velocity_law(
            context.machine,
            context.patches,
            &modes,
            &keys.damping_ratio,
            keys.period,
        )
        .map_err(|e| params.error("modes", e.to_string()))?;
        Ok(Arc::new(law))
    }
}
