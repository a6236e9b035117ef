//! The registry of named parts: the TOML names of integrators (`integrator.method`), bases
//! (`links.basis.kind`), axial force models (`model.axial_force`), control laws
//! (`control.kind`) and model kinds (`model.coupling`) and how to build each.
//!
//! [`Registry::default`] holds the built-ins; a program adds its own parts with
//! [`Registry::register_integrator`], [`Registry::register_basis`],
//! [`Registry::register_axial_force`], [`Registry::register_controller`] and
//! [`Registry::register_model_kind`] and loads scenes
//! through it with
//! [`crate::Scene::load_with`] or [`crate::Scene::from_text_with`]. Nothing in the scene code
//! matches on a name: a new part is one registration.

use std::collections::BTreeMap;
use std::fmt;
use std::sync::Arc;

use flexprr_beam::{Basis, ClassicalBasis, HermiteBasis, SineBasis};
use flexprr_dynamics::{
    AxialForceModel, AxialModel, JointReactionAxialForce, NoAxialForce, PaperAxialForce,
};
use flexprr_integrators::{
    Abm, Auto, Bdf, DynIntegrator, GeneralizedAlpha, IntegratorError, Interrupted, Magnus,
    OdeSystem, Options, Rk45, Solution,
};
use serde::Deserialize;
use serde::de::DeserializeOwned;

use crate::controllers::{
    ControllerFactory, ModalVelocityFactory, PdFactory, PidFactory, StrainRateFactory,
    VibrationControllerFactory,
};
use crate::error::ScenarioError;
use crate::link::EndsConfig;
use crate::locate::{locate, locate_value};
use flexprr_control::{ControlError, Controller};

/// Builds an integrator from the scene's options.
pub type IntegratorConstructor = Arc<dyn Fn(Options) -> Box<dyn DynIntegrator> + Send + Sync>;

/// The integrator a scene names: its registered name, constructor and what it asks of the
/// model. Scenes, the bench and `flexprr work-precision` all reach integrators through these
/// handles, so a registered integrator runs, resolves and is benchmarked like a built-in one.
#[derive(Clone)]
pub struct MethodHandle {
    name: String,
    constructor: IntegratorConstructor,
    kind: MethodKind,
}

impl MethodHandle {
    /// A handle from a name and a constructor, for a method that integrates any model
    /// ([`MethodKind::General`]).
    pub fn new(name: impl Into<String>, constructor: IntegratorConstructor) -> Self {
        Self::with_kind(name, constructor, MethodKind::General)
    }

    /// A handle from a name, a constructor and what the method asks of the model.
    pub fn with_kind(
        name: impl Into<String>,
        constructor: IntegratorConstructor,
        kind: MethodKind,
    ) -> Self {
        Self {
            name: name.into(),
            constructor,
            kind,
        }
    }

    /// The name the scene file gives (`integrator.method`).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// What the method asks of the model.
    pub fn kind(&self) -> &MethodKind {
        &self.kind
    }

    /// The constructor it was registered with.
    pub fn constructor(&self) -> &IntegratorConstructor {
        &self.constructor
    }

    /// The integrator configured with `options` (built by the registered constructor).
    pub fn integrator(&self, options: Options) -> Box<dyn DynIntegrator> {
        (self.constructor)(options)
    }

    /// Integrates `system` from `y0` at `t_out[0]` with this method and `options`, output at
    /// `t_out` (the convenience the run layer uses).
    ///
    /// # Errors
    /// The integrator's error; an empty `t_out` is [`IntegratorError::InvalidInput`].
    pub fn solve<S: OdeSystem>(
        &self,
        options: Options,
        system: &mut S,
        y0: &[f64],
        t_out: &[f64],
    ) -> Result<Solution, IntegratorError> {
        let Some(&t0) = t_out.first() else {
            return Err(IntegratorError::InvalidInput(
                "no output times requested".to_string(),
            ));
        };
        self.integrator(options)
            .solve_dyn(system, t0, y0, t_out, &[], &mut ())
            .map_err(Interrupted::into_error)
    }
}

impl fmt::Debug for MethodHandle {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_tuple("MethodHandle").field(&self.name).finish()
    }
}

impl PartialEq for MethodHandle {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
    }
}

/// What a registered integrator asks of the scene's model.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub enum MethodKind {
    /// Integrates any model (`abm`, `rk45`, `bdf`).
    #[default]
    General,
    /// Needs a model that is linear in its state ([`OdeSystem::linear_form`]: the KED modal
    /// equations); `magnus4` and `magnus6`. A scene with another model is refused at load.
    Linear,
    /// Needs a model with a mechanical form ([`OdeSystem::second_order_form`]: state
    /// `(q, q')`, mass, damping and stiffness): the nonlinear model without a continuous
    /// control law's or an actuator's states; `generalized_alpha`. A scene with another model is refused at
    /// load.
    Mechanical,
    /// Stands for one of the registered methods, chosen by the scene's model: `linear` for a
    /// linear (KED) model, `mechanical` (when set) for a model with a mechanical form,
    /// `general` otherwise (`auto`: `magnus6`, `generalized_alpha` or `abm`). The scene
    /// records the method chosen, so runs and summaries name the method actually used.
    Auto {
        /// The method for linear models.
        linear: String,
        /// The method for every other model.
        general: String,
        /// The method for models with a mechanical form, if not `general`.
        mechanical: Option<String>,
    },
}

/// Whether a scene's model has a mechanical form ([`MethodKind::Mechanical`]): a kind with
/// [`crate::ModelCapabilities::mechanical_form`] (the nonlinear model), with no control law
/// or one without continuous states (a sampled or stateless law), and actuators without
/// states of their own ([`flexprr_control::Actuator::states`]).
pub fn mechanical_model(
    coupling: &crate::ModelKindHandle,
    controller: Option<&Arc<dyn flexprr_control::Controller>>,
    actuator: Option<&Arc<dyn flexprr_control::Actuator>>,
) -> bool {
    coupling.capabilities().mechanical_form
        && controller.is_none_or(|c| c.period() > 0.0 || c.states() == 0)
        && actuator.is_none_or(|a| a.states() == 0)
}

/// How a basis gets its number of functions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModeCount {
    /// `links.modes` (default 3, 1 to 60) is the number of functions; in a link file,
    /// `modes` is too.
    FromModes,
    /// The basis's own keys fix its size (e.g. Hermite elements); `links.modes` is refused
    /// in a scene, and in a link file `modes` is only the number of modes reported.
    FromBasisKeys,
}

/// The keys of one table of a registered part (everything but `kind`: a basis table, the
/// `[control]` table), with what is needed to put an error at the right key, line and column.
pub struct TableParams<'a> {
    file: &'a str,
    text: &'a str,
    prefix: &'a str,
    table: &'a toml::Table,
}

/// The keys of a basis table: [`TableParams`] under the name the basis factories have
/// always used.
pub type BasisParams<'a> = TableParams<'a>;

impl<'a> TableParams<'a> {
    /// The keys `table` of the part's table at dotted key `prefix` (e.g. `links.basis`,
    /// `control`) of the source `text` of `file`.
    pub fn new(file: &'a str, text: &'a str, prefix: &'a str, table: &'a toml::Table) -> Self {
        Self {
            file,
            text,
            prefix,
            table,
        }
    }

    /// The raw keys.
    pub fn table(&self) -> &toml::Table {
        self.table
    }

    /// Reads the keys into `T` (declare it `deny_unknown_fields` so a key of another kind
    /// is an error); errors name the key under the part's table and its location.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] for an unknown or missing key or a wrong type.
    pub fn parse<T: DeserializeOwned>(&self) -> Result<T, ScenarioError> {
        let text = toml::to_string(self.table).map_err(|e| self.error("", e.to_string()))?;
        crate::parse::parse_toml::<T>("", &text).map_err(|e| match e {
            ScenarioError::Input { key, message, .. } if message.starts_with("unknown variant") => {
                self.value_error(&key, message)
            }
            ScenarioError::Input { key, message, .. } => self.error(&key, message),
            other => other,
        })
    }

    /// The file the table was read from, as named in messages (a law's own files, such as
    /// a state-space law's `.npz`, are relative to its directory).
    pub fn file(&self) -> &str {
        self.file
    }

    /// The dotted key of the part's table (`links.basis`, `control`).
    pub fn prefix(&self) -> &str {
        self.prefix
    }

    /// A bad-input error at `key` (relative to the part's table; empty for the table).
    pub fn error(&self, key: &str, message: impl Into<String>) -> ScenarioError {
        self.error_impl(key, message.into(), false)
    }

    /// As [`TableParams::error`], located at the value of `key` (for a bad word).
    pub fn value_error(&self, key: &str, message: impl Into<String>) -> ScenarioError {
        self.error_impl(key, message.into(), true)
    }

    /// A controller's or actuator's parameter error ([`ControlError`]) at the key it names,
    /// with its rule and value: `control.kp: a gain must be finite and >= 0, got -1`.
    pub fn control_error(&self, error: ControlError) -> ScenarioError {
        match error {
            ControlError::InvalidParameter { name, value, rule } => {
                self.error(name, format!("{rule}, got {}", crate::error::number(value)))
            }
            other => self.error("", other.to_string()),
        }
    }

    fn error_impl(&self, key: &str, message: String, at_value: bool) -> ScenarioError {
        let key = if key.is_empty() {
            self.prefix.to_string()
        } else {
            format!("{}.{key}", self.prefix)
        };
        let location = if at_value {
            locate_value(self.file, self.text, &key)
        } else {
            locate(self.file, self.text, &key)
        };
        ScenarioError::Input {
            location,
            key,
            message,
        }
    }
}

/// A kind of assumed-mode basis that scene and link files can name in `basis.kind`.
///
/// ```
/// use std::sync::Arc;
/// use flexprr_beam::{Basis, SineBasis};
/// use flexprr_scene::{BasisFactory, BasisParams, ModeCount, Registry, ScenarioError};
///
/// /// The sine basis under another name, with a scale-free check of one key.
/// struct Pinned;
/// #[derive(serde::Deserialize)]
/// #[serde(deny_unknown_fields)]
/// struct Keys {
///     #[serde(default)]
///     note: String,
/// }
/// impl BasisFactory for Pinned {
///     fn mode_count(&self) -> ModeCount {
///         ModeCount::FromModes
///     }
///     fn build(
///         &self,
///         params: &BasisParams<'_>,
///         modes: Option<usize>,
///     ) -> Result<Arc<dyn Basis>, ScenarioError> {
///         let _keys: Keys = params.parse()?;
///         let r = modes.unwrap_or(3);
///         Ok(Arc::new(SineBasis::new(r).map_err(|e| params.error("", e.to_string()))?))
///     }
/// }
/// let mut registry = Registry::default();
/// registry.register_basis("pinned", Arc::new(Pinned));
/// assert!(registry.basis_names().contains(&"pinned"));
/// ```
pub trait BasisFactory: Send + Sync {
    /// How the number of functions is set.
    fn mode_count(&self) -> ModeCount;
    /// Builds the basis from its keys; `modes` is `Some(r)` exactly when
    /// [`BasisFactory::mode_count`] is [`ModeCount::FromModes`].
    ///
    /// # Errors
    /// [`ScenarioError::Input`] naming the offending key (use [`BasisParams::error`]).
    fn build(
        &self,
        params: &BasisParams<'_>,
        modes: Option<usize>,
    ) -> Result<Arc<dyn Basis>, ScenarioError>;
}

/// The built-in `sine` basis: `sin(j pi xi)`, pinned-pinned (the paper's eq. 5).
struct SineFactory;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct NoKeys {}

impl BasisFactory for SineFactory {
    fn mode_count(&self) -> ModeCount {
        ModeCount::FromModes
    }
    fn build(
        &self,
        params: &BasisParams<'_>,
        modes: Option<usize>,
    ) -> Result<Arc<dyn Basis>, ScenarioError> {
        let NoKeys {} = params.parse()?;
        let basis =
            SineBasis::new(modes.unwrap_or(3)).map_err(|e| params.error("", e.to_string()))?;
        Ok(Arc::new(basis))
    }
}

/// The built-in `classical` basis: uniform-beam eigenfunctions with the given `ends`.
struct ClassicalFactory;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ClassicalKeys {
    ends: EndsConfig,
}

impl BasisFactory for ClassicalFactory {
    fn mode_count(&self) -> ModeCount {
        ModeCount::FromModes
    }
    fn build(
        &self,
        params: &BasisParams<'_>,
        modes: Option<usize>,
    ) -> Result<Arc<dyn Basis>, ScenarioError> {
        let keys: ClassicalKeys = params.parse()?;
        let basis = ClassicalBasis::new(keys.ends.to_ends(), modes.unwrap_or(3))
            .map_err(|e| params.error("ends", e.to_string()))?;
        Ok(Arc::new(basis))
    }
}

/// The built-in `hermite` basis: cubic Hermite finite elements; `elements` fixes the size.
struct HermiteFactory;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct HermiteKeys {
    elements: usize,
    #[serde(default)]
    ends: EndsConfig,
}

impl BasisFactory for HermiteFactory {
    fn mode_count(&self) -> ModeCount {
        ModeCount::FromBasisKeys
    }
    fn build(
        &self,
        params: &BasisParams<'_>,
        _modes: Option<usize>,
    ) -> Result<Arc<dyn Basis>, ScenarioError> {
        let keys: HermiteKeys = params.parse()?;
        if keys.elements == 0 {
            return Err(params.error("elements", "expected at least 1 element, got 0"));
        }
        if keys.elements > 200 {
            return Err(params.error(
                "elements",
                format!("{} elements is more than the supported 200", keys.elements),
            ));
        }
        let basis = HermiteBasis::new(keys.elements, keys.ends.to_ends())
            .map_err(|e| params.error("elements", e.to_string()))?;
        Ok(Arc::new(basis))
    }
}

/// A registered axial force model.
#[derive(Clone)]
pub(crate) struct AxialEntry {
    pub(crate) model: Arc<dyn AxialForceModel>,
    /// The formulation switch it corresponds to, for the built-ins.
    pub(crate) preset: Option<AxialModel>,
}

/// The named parts scenes can use. [`Registry::default`] holds the built-ins: integrators
/// `abm`, `rk45`, `bdf`, `generalized_alpha` (mechanical models), `magnus4`, `magnus6`
/// (linear models only) and `auto`; bases `sine`,
/// `classical`, `hermite`; axial force models `none`, `paper`, `joint-reaction`; control
/// laws `pd` and `pid`; model kinds `ked`, `coupled` and `nonlinear`; actuators `force` and
/// `motor_ballscrew`.
#[derive(Clone)]
pub struct Registry {
    integrators: BTreeMap<String, IntegratorConstructor>,
    method_kinds: BTreeMap<String, MethodKind>,
    bases: BTreeMap<String, Arc<dyn BasisFactory>>,
    axial: BTreeMap<String, AxialEntry>,
    controllers: BTreeMap<String, Arc<dyn ControllerFactory>>,
    vibration_controllers: BTreeMap<String, Arc<dyn VibrationControllerFactory>>,
    model_kinds: BTreeMap<String, Arc<dyn crate::ModelKind>>,
    actuators: BTreeMap<String, Arc<dyn crate::ActuatorFactory>>,
    outputs: BTreeMap<String, crate::CustomOutput>,
}

impl fmt::Debug for Registry {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Registry")
            .field("integrators", &self.integrator_names())
            .field("bases", &self.basis_names())
            .field("axial_forces", &self.axial_force_names())
            .field("controllers", &self.controller_names())
            .field("vibration_controllers", &self.vibration_controller_names())
            .field("model_kinds", &self.model_kind_names())
            .field("actuators", &self.actuator_names())
            .field("outputs", &self.output_names())
            .finish()
    }
}

impl Default for Registry {
    fn default() -> Self {
        let mut r = Self::empty();
        r.register_integrator("abm", Arc::new(|o| Box::new(Abm::new(o))));
        r.register_integrator("rk45", Arc::new(|o| Box::new(Rk45::new(o))));
        r.register_integrator("bdf", Arc::new(|o| Box::new(Bdf::new(o))));
        r.register_integrator_kind(
            "generalized_alpha",
            Arc::new(|o| Box::new(GeneralizedAlpha::new(o))),
            MethodKind::Mechanical,
        );
        r.register_integrator_kind(
            "magnus4",
            Arc::new(|o| Box::new(Magnus::magnus4(o))),
            MethodKind::Linear,
        );
        r.register_integrator_kind(
            "magnus6",
            Arc::new(|o| Box::new(Magnus::magnus6(o))),
            MethodKind::Linear,
        );
        r.register_integrator_kind(
            "auto",
            Arc::new(|o| Box::new(Auto::new(o))),
            MethodKind::Auto {
                linear: Auto::LINEAR.to_string(),
                general: Auto::GENERAL.to_string(),
                mechanical: Some(Auto::MECHANICAL.to_string()),
            },
        );
        r.register_model_kind("ked", Arc::new(crate::model::KedKind));
        r.register_model_kind("coupled", Arc::new(crate::model::CoupledKind));
        r.register_model_kind("nonlinear", Arc::new(crate::model::NonlinearKind));
        r.register_basis("sine", Arc::new(SineFactory));
        r.register_basis("classical", Arc::new(ClassicalFactory));
        r.register_basis("hermite", Arc::new(HermiteFactory));
        r.register_actuator("force", Arc::new(crate::actuators::ForceFactory));
        r.register_actuator(
            "motor_ballscrew",
            Arc::new(crate::actuators::MotorBallScrewFactory),
        );
        r.register_controller("pd", Arc::new(PdFactory));
        r.register_controller("pid", Arc::new(PidFactory));
        r.register_controller(
            "statespace",
            Arc::new(crate::statespace_law::StateSpaceFactory),
        );
        r.register_controller(
            "python",
            Arc::new(crate::callback_law::CallbackLawFactory::default()),
        );
        r.register_vibration_controller("strain_rate", Arc::new(StrainRateFactory));
        r.register_vibration_controller("modal_velocity", Arc::new(ModalVelocityFactory));
        for (name, preset, model) in [
            (
                "none",
                AxialModel::None,
                Arc::new(NoAxialForce) as Arc<dyn AxialForceModel>,
            ),
            ("paper", AxialModel::Paper, Arc::new(PaperAxialForce)),
            (
                "joint-reaction",
                AxialModel::JointReaction,
                Arc::new(JointReactionAxialForce),
            ),
        ] {
            r.axial.insert(
                name.to_string(),
                AxialEntry {
                    model,
                    preset: Some(preset),
                },
            );
        }
        r
    }
}

impl Registry {
    /// A registry with nothing in it.
    pub fn empty() -> Self {
        Self {
            integrators: BTreeMap::new(),
            method_kinds: BTreeMap::new(),
            bases: BTreeMap::new(),
            axial: BTreeMap::new(),
            controllers: BTreeMap::new(),
            vibration_controllers: BTreeMap::new(),
            model_kinds: BTreeMap::new(),
            actuators: BTreeMap::new(),
            outputs: BTreeMap::new(),
        }
    }

    /// Declares (or replaces) the output `name` a scene may request in `output.custom`: an
    /// output produced by a program's own producer (`flexprr_run::OutputRegistry::register`
    /// declares it here and gives the run its producer). `needs_integration`: whether it
    /// reads the integrated model, so that a scene requesting it is integrated.
    pub fn register_output(&mut self, name: &str, needs_integration: bool) {
        let output = crate::CustomOutput {
            name: name.to_string(),
            needs_integration,
        };
        self.outputs.insert(name.to_string(), output);
    }

    /// The declared outputs, sorted.
    pub fn output_names(&self) -> Vec<&str> {
        self.outputs.keys().map(String::as_str).collect()
    }

    /// The declared output `name`.
    pub fn output(&self, name: &str) -> Option<&crate::CustomOutput> {
        self.outputs.get(name)
    }

    /// Registers (or replaces) the model kind `name` for `model.coupling`.
    pub fn register_model_kind(&mut self, name: &str, kind: Arc<dyn crate::ModelKind>) {
        self.model_kinds.insert(name.to_string(), kind);
    }

    /// The model kind `name`, as a handle.
    pub fn model_kind(&self, name: &str) -> Option<crate::ModelKindHandle> {
        self.model_kinds
            .get(name)
            .map(|k| crate::ModelKindHandle::new(name, k.clone()))
    }

    /// Registered model kind names, sorted.
    pub fn model_kind_names(&self) -> Vec<&str> {
        self.model_kinds.keys().map(String::as_str).collect()
    }

    /// Registers (or replaces) the integrator `name` for `integrator.method`; it integrates
    /// any model ([`MethodKind::General`]).
    pub fn register_integrator(&mut self, name: &str, constructor: IntegratorConstructor) {
        self.register_integrator_kind(name, constructor, MethodKind::General);
    }

    /// Registers (or replaces) the integrator `name` with what it asks of the model. For a
    /// [`MethodKind::Auto`], the constructor is used where no scene resolves the choice (it
    /// should choose per system, like [`Auto`]).
    pub fn register_integrator_kind(
        &mut self,
        name: &str,
        constructor: IntegratorConstructor,
        kind: MethodKind,
    ) {
        self.integrators.insert(name.to_string(), constructor);
        self.method_kinds.insert(name.to_string(), kind);
    }

    /// What the integrator `name` asks of the model.
    pub fn method_kind(&self, name: &str) -> Option<&MethodKind> {
        self.method_kinds.get(name)
    }

    /// The method a scene with the integrator `name` runs, given whether its model is linear
    /// in the state (`model_name` names the model in the error): an `auto` name becomes its
    /// choice for the model, a linear-only method on another model is refused. The same as
    /// [`Registry::resolve_method_for`] for a model without a mechanical form.
    ///
    /// # Errors
    /// One line saying which method needs what and what to use instead, or naming an
    /// unregistered method.
    pub fn resolve_method(
        &self,
        name: &str,
        linear_model: bool,
        model_name: &str,
    ) -> Result<MethodHandle, String> {
        self.resolve_method_for(name, linear_model, false, model_name)
    }

    /// The method a scene with the integrator `name` runs, given whether its model is linear
    /// in the state and whether it has a mechanical form ([`mechanical_model`]): an `auto`
    /// name becomes its choice for the model, a linear-only or mechanical-only method on
    /// another model is refused.
    ///
    /// # Errors
    /// One line saying which method needs what and what to use instead, or naming an
    /// unregistered method.
    pub fn resolve_method_for(
        &self,
        name: &str,
        linear_model: bool,
        mechanical_model: bool,
        model_name: &str,
    ) -> Result<MethodHandle, String> {
        let unknown = |n: &str| {
            format!(
                "unknown value \"{n}\", expected one of {}",
                quoted_list(&self.integrator_names())
            )
        };
        let needs = |kind: &str| {
            format!(
                "method {name} needs {kind}; this scene is {model_name}: use {}",
                self.fallbacks().join(" or ")
            )
        };
        let chosen = match self.method_kind(name) {
            Some(MethodKind::Auto {
                linear,
                general,
                mechanical,
            }) => match mechanical {
                _ if linear_model => linear.as_str(),
                Some(m) if mechanical_model => m.as_str(),
                _ => general.as_str(),
            },
            Some(MethodKind::Linear) if !linear_model => {
                return Err(needs("a linear (KED) model"));
            }
            Some(MethodKind::Mechanical) if !mechanical_model => {
                return Err(needs(
                    "a mechanical model (nonlinear, without a continuous control law's states)",
                ));
            }
            _ => name,
        };
        match self.method_kind(chosen) {
            Some(MethodKind::Auto { .. }) if chosen != name => Err(format!(
                "method {name} chooses {chosen}, which is itself a choice; register a concrete method"
            )),
            Some(MethodKind::Linear) if !linear_model => Err(format!(
                "method {name} chooses {chosen}, which needs a linear (KED) model; this scene is {model_name}"
            )),
            Some(MethodKind::Mechanical) if !mechanical_model => Err(format!(
                "method {name} chooses {chosen}, which needs a mechanical model; this scene is {model_name}"
            )),
            _ => self.method(chosen).ok_or_else(|| unknown(chosen)),
        }
    }

    /// The methods `auto` falls back to, then the `auto` names themselves (or, without an
    /// `auto`, every general method): what to use instead of a method the model refuses.
    fn fallbacks(&self) -> Vec<&str> {
        let mut alternatives: Vec<&str> = Vec::new();
        for (n, kind) in &self.method_kinds {
            if let MethodKind::Auto { general, .. } = kind {
                for a in [general.as_str(), n.as_str()] {
                    if !alternatives.contains(&a) {
                        alternatives.push(a);
                    }
                }
            }
        }
        if alternatives.is_empty() {
            alternatives = self
                .integrator_names()
                .into_iter()
                .filter(|n| self.method_kind(n) == Some(&MethodKind::General))
                .collect();
        }
        alternatives
    }

    /// Registers (or replaces) the basis `name` for `basis.kind`.
    pub fn register_basis(&mut self, name: &str, factory: Arc<dyn BasisFactory>) {
        self.bases.insert(name.to_string(), factory);
    }

    /// Registers (or replaces) the axial force model `name` for `model.axial_force`.
    pub fn register_axial_force(&mut self, name: &str, model: Arc<dyn AxialForceModel>) {
        self.axial.insert(
            name.to_string(),
            AxialEntry {
                model,
                preset: None,
            },
        );
    }

    /// Registers (or replaces) the control law `name` for `control.kind`.
    pub fn register_controller(&mut self, name: &str, factory: Arc<dyn ControllerFactory>) {
        self.controllers.insert(name.to_string(), factory);
    }

    /// Registers (or replaces) the vibration control law `name` for
    /// `vibration_control.kind`.
    pub fn register_vibration_controller(
        &mut self,
        name: &str,
        factory: Arc<dyn VibrationControllerFactory>,
    ) {
        self.vibration_controllers.insert(name.to_string(), factory);
    }

    /// Registered vibration control law names, sorted.
    pub fn vibration_controller_names(&self) -> Vec<&str> {
        self.vibration_controllers
            .keys()
            .map(String::as_str)
            .collect()
    }

    /// Builds the vibration control law of the table `at` (`vibration_control`) for the
    /// patches of `context`.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] with the key and location of an unknown kind, or the law's
    /// own key errors.
    pub fn build_vibration_controller(
        &self,
        at: &TableParams<'_>,
        kind: &str,
        context: &crate::PatchContext<'_>,
    ) -> Result<Arc<dyn flexprr_control::VibrationController>, ScenarioError> {
        let factory = self.vibration_controllers.get(kind).ok_or_else(|| {
            at.value_error(
                "kind",
                format!(
                    "unknown vibration control law \"{kind}\", expected one of {}",
                    quoted_list(&self.vibration_controller_names())
                ),
            )
        })?;
        factory.build(at, context)
    }

    /// The control law `name`.
    pub fn controller(&self, name: &str) -> Option<&Arc<dyn ControllerFactory>> {
        self.controllers.get(name)
    }

    /// Registered control law names, sorted.
    pub fn controller_names(&self) -> Vec<&str> {
        self.controllers.keys().map(String::as_str).collect()
    }

    /// Builds the control law of the table `at` (`control`): looks up `kind` and lets its
    /// factory read its own keys.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] with the key and location of an unknown kind, or the law's
    /// own key errors.
    pub fn build_controller(
        &self,
        at: &TableParams<'_>,
        kind: &str,
    ) -> Result<Arc<dyn Controller>, ScenarioError> {
        let factory = self.controller(kind).ok_or_else(|| {
            at.value_error(
                "kind",
                format!(
                    "unknown control law \"{kind}\", expected one of {}",
                    quoted_list(&self.controller_names())
                ),
            )
        })?;
        factory.build(at)
    }

    /// Registers (or replaces) the actuator kind `name` for `actuators.kind`.
    pub fn register_actuator(&mut self, name: &str, factory: Arc<dyn crate::ActuatorFactory>) {
        self.actuators.insert(name.to_string(), factory);
    }

    /// The factory of the actuator kind `name`.
    pub fn actuator(&self, name: &str) -> Option<&Arc<dyn crate::ActuatorFactory>> {
        self.actuators.get(name)
    }

    /// The registered actuator kinds, sorted.
    pub fn actuator_names(&self) -> Vec<&str> {
        self.actuators.keys().map(String::as_str).collect()
    }

    /// Builds the actuator of the table `at` (`actuators`): looks up `kind` and lets its
    /// factory read its own keys.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] at the value of `kind` for an unknown kind (worded as the
    /// scene parser words an unknown word), or the kind's own key errors.
    pub fn build_actuator(
        &self,
        at: &TableParams<'_>,
        kind: &str,
    ) -> Result<Arc<dyn flexprr_control::Actuator>, ScenarioError> {
        let factory = self.actuators.get(kind).ok_or_else(|| {
            let names: Vec<String> = self.actuators.keys().map(|n| format!("`{n}`")).collect();
            let expected = match names.as_slice() {
                [] => "no kind is registered".to_string(),
                [one] => format!("expected {one}"),
                [a, b] => format!("expected {a} or {b}"),
                all => format!("expected one of {}", all.join(", ")),
            };
            at.value_error("kind", format!("unknown variant `{kind}`, {expected}"))
        })?;
        factory.build(at)
    }

    /// The integrator `name`, as a handle.
    pub fn method(&self, name: &str) -> Option<MethodHandle> {
        self.integrators.get(name).map(|c| {
            let kind = self.method_kind(name).cloned().unwrap_or_default();
            MethodHandle::with_kind(name, c.clone(), kind)
        })
    }

    /// Registers (or replaces) the integrator of `handle`, under its name and kind.
    pub fn register_method(&mut self, handle: &MethodHandle) {
        self.register_integrator_kind(
            handle.name(),
            handle.constructor().clone(),
            handle.kind().clone(),
        );
    }

    /// The basis kind `name`.
    pub fn basis(&self, name: &str) -> Option<&Arc<dyn BasisFactory>> {
        self.bases.get(name)
    }

    /// The axial force model `name`.
    pub fn axial_force(&self, name: &str) -> Option<Arc<dyn AxialForceModel>> {
        self.axial.get(name).map(|e| e.model.clone())
    }

    pub(crate) fn axial_entry(&self, name: &str) -> Option<&AxialEntry> {
        self.axial.get(name)
    }

    /// Registered integrator names, sorted.
    pub fn integrator_names(&self) -> Vec<&str> {
        self.integrators.keys().map(String::as_str).collect()
    }

    /// Registered basis kinds, sorted.
    pub fn basis_names(&self) -> Vec<&str> {
        self.bases.keys().map(String::as_str).collect()
    }

    /// Registered axial force model names, sorted.
    pub fn axial_force_names(&self) -> Vec<&str> {
        self.axial.keys().map(String::as_str).collect()
    }

    /// Builds the basis of the table `at` (e.g. `links.basis`): looks up `kind`, applies the
    /// kind's [`ModeCount`] rule to `modes` (what the file gives at the dotted key
    /// `modes_key`: default 3, 1 to 60, refused for a kind that sizes itself) and builds it.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] with the key and location of an unknown kind, a `modes` the
    /// kind does not take or out of range, or the kind's own key errors.
    pub fn build_basis(
        &self,
        at: &BasisParams<'_>,
        kind: &str,
        modes_key: &str,
        modes: Option<usize>,
    ) -> Result<Arc<dyn Basis>, ScenarioError> {
        let factory = self.basis(kind).ok_or_else(|| {
            at.value_error(
                "kind",
                format!(
                    "unknown basis kind \"{kind}\", expected one of {}",
                    quoted_list(&self.basis_names())
                ),
            )
        })?;
        let given = match factory.mode_count() {
            ModeCount::FromBasisKeys => {
                if modes.is_some() {
                    return Err(key_error(
                        at,
                        modes_key,
                        format!(
                            "the {kind} basis takes its size from its own keys ({}), not from modes; remove modes",
                            at.prefix
                        ),
                    ));
                }
                None
            }
            ModeCount::FromModes => {
                let r = modes.unwrap_or(3);
                if r == 0 {
                    return Err(key_error(at, modes_key, "expected at least 1 mode, got 0"));
                }
                if r > 60 {
                    return Err(key_error(
                        at,
                        modes_key,
                        format!("{r} modes is more than the supported 60"),
                    ));
                }
                Some(r)
            }
        };
        factory.build(at, given)
    }
}

fn key_error(at: &BasisParams<'_>, key: &str, message: impl Into<String>) -> ScenarioError {
    ScenarioError::Input {
        location: locate(at.file, at.text, key),
        key: key.to_string(),
        message: message.into(),
    }
}

/// `"a", "b", "c"`.
pub(crate) fn quoted_list(names: &[&str]) -> String {
    names
        .iter()
        .map(|n| format!("\"{n}\""))
        .collect::<Vec<_>>()
        .join(", ")
}
