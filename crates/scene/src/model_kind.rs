//! Model kinds: the named dynamical models a scene selects with `model.coupling`, each a
//! factory of its [`SceneModel`] with capability queries.
//!
//! The scene, the run, the linear tools and the bench ask a kind what it can do (is it linear
//! in its state, does it have a mechanical form, is its platform free, are its links in
//! assumed modes) and never which kind it is, so a kind registered with
//! [`crate::Registry::register_model_kind`] is loaded, checked, integrated and benchmarked
//! like the built-in `ked`, `coupled` and `nonlinear` ([`crate::Registry::default`]).

use std::fmt;
use std::sync::Arc;

use flexprr_dynamics::{DynamicsError, SceneModel};

use crate::Scene;

/// What a model kind can do: the questions the layers above ask instead of matching on its
/// name. Each flag decides which scene keys, outputs, integrators and linear analyses the
/// kind accepts (docs/scenes.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ModelCapabilities {
    /// The model is linear in its state ([`flexprr_integrators::OdeSystem::linear_form`]):
    /// the Magnus methods apply and `auto` picks `magnus6` (the KED modal equations).
    pub linear_in_state: bool,
    /// The model has a mechanical form over its whole state when no control law adds
    /// continuous states ([`flexprr_integrators::OdeSystem::second_order_form`]):
    /// generalized-alpha applies and `auto` picks it (the nonlinear model).
    pub mechanical_form: bool,
    /// The platform and the sliders move under the links' forces (coupled, nonlinear): a
    /// control law, a collapse limit, whole-machine modes and the actual axial and driving
    /// forces along the solution apply. Without it the rigid motion is prescribed (KED).
    pub free_platform: bool,
    /// The links are in assumed modes (KED, coupled): modal damping, the `modes` and
    /// `modal_forces` outputs and the patches' added mass and stiffness apply. Without it the
    /// links are co-rotational elements (`model.elements`, `model.axial_damping_time`).
    pub assumed_modes: bool,
    /// The model is built on the consistent equations only (`model.formulation =
    /// "consistent"` without overrides or a registered axial force model).
    pub consistent_only: bool,
}

impl ModelCapabilities {
    /// The coupled model's combination: a free platform on links in assumed modes, whose
    /// chords may be kept rigid in linear analyses at rest (`model.chords`) and whose
    /// whole-machine modes are truncated by the links' modes.
    pub fn modal_machine(self) -> bool {
        self.free_platform && self.assumed_modes
    }

    /// The key that sets the model's size: `links.modes` in assumed modes, else
    /// `model.elements`.
    pub fn size_key(self) -> &'static str {
        if self.assumed_modes {
            "links.modes"
        } else {
            "model.elements"
        }
    }
}

/// A model kind: builds the dynamical system of a scene and says what it can do.
///
/// Registered by name with [`crate::Registry::register_model_kind`] and selected with
/// `model.coupling = "<name>"`. A minimal kind that integrates the KED modal equations
/// under another name:
///
/// ```
/// use flexprr_dynamics::{DynamicsError, SceneModel};
/// use flexprr_scene::{ModelCapabilities, ModelKind, Registry, Scene};
/// use std::sync::Arc;
///
/// struct Rigidless;
/// impl ModelKind for Rigidless {
///     fn capabilities(&self) -> ModelCapabilities {
///         ModelCapabilities { linear_in_state: true, assumed_modes: true, ..Default::default() }
///     }
///     fn build(&self, scene: &Scene) -> Result<Box<dyn SceneModel>, DynamicsError> {
///         Ok(Box::new(scene.build_ked(false)?))
///     }
/// }
/// let mut registry = Registry::default();
/// registry.register_model_kind("rigidless", Arc::new(Rigidless));
/// let kind = registry.model_kind("rigidless").unwrap();
/// assert!(kind.capabilities().linear_in_state);
/// assert_eq!(kind.name(), "rigidless");
/// ```
pub trait ModelKind: Send + Sync {
    /// What the model can do.
    fn capabilities(&self) -> ModelCapabilities;

    /// The dynamical system `scene` integrates, with its patches and actuation wired.
    ///
    /// # Errors
    /// The model's own construction errors (a mass matrix that is not positive definite, a
    /// kinematic failure at the start time, ...).
    fn build(&self, scene: &Scene) -> Result<Box<dyn SceneModel>, DynamicsError>;

    /// The model with the axial force switched off, for the paper's comparison "without
    /// axial force"; `None` (the default) where the axial force is the actual constraint
    /// force rather than a switch.
    ///
    /// # Errors
    /// As [`ModelKind::build`].
    fn build_without_axial_force(
        &self,
        scene: &Scene,
    ) -> Result<Option<Box<dyn SceneModel>>, DynamicsError> {
        let _ = scene;
        Ok(None)
    }

    /// What `flexprr check` says about the model, given the sliders' description (`sliders`
    /// starts with ", " when not empty); the default names the kind and its links' modes.
    fn describe(&self, name: &str, scene: &Scene, sliders: &str) -> String {
        let links = &scene.machine.links[0];
        format!(
            "{name} model{sliders}, {} modes per link: {}",
            links.modes(),
            links.basis.name()
        )
    }
}

/// The model kind a scene names: its registered name and factory.
#[derive(Clone)]
pub struct ModelKindHandle {
    name: String,
    kind: Arc<dyn ModelKind>,
}

impl ModelKindHandle {
    /// A handle from a name and a kind.
    pub fn new(name: impl Into<String>, kind: Arc<dyn ModelKind>) -> Self {
        Self {
            name: name.into(),
            kind,
        }
    }

    /// The name the scene file gives (`model.coupling`).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// What the model can do.
    pub fn capabilities(&self) -> ModelCapabilities {
        self.kind.capabilities()
    }

    /// The kind's factory.
    pub fn kind(&self) -> &Arc<dyn ModelKind> {
        &self.kind
    }
}

impl fmt::Debug for ModelKindHandle {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_tuple("ModelKindHandle").field(&self.name).finish()
    }
}

impl fmt::Display for ModelKindHandle {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name)
    }
}

impl PartialEq for ModelKindHandle {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
    }
}
