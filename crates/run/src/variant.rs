//! Variant runs as named scene transformations: a run that compares a scene with a changed
//! copy of itself (the paper's run "without axial force", figures 6-8; the piezo run without
//! its vibration control law, docs/piezo.md; the planning crate's "unshaped" motion) asks a
//! [`SceneVariant`] for the changed scene and integrates it with the scene's integrator over
//! the same output times. The run's built-in variants are listed by [`built_in`]; the
//! outputs find a variant's states by its name ([`VariantRun`]).
//!
//! ```
//! use flexprr_run::{RunError, SceneVariant};
//! use flexprr_scene::Scene;
//!
//! /// The scene with its damping removed.
//! struct Undamped;
//!
//! impl SceneVariant for Undamped {
//!     fn name(&self) -> &'static str {
//!         "undamped"
//!     }
//!     fn description(&self) -> &'static str {
//!         "the scene without structural damping"
//!     }
//!     fn transform(&self, scene: &Scene) -> Result<Option<Scene>, RunError> {
//!         let mut out = scene.clone();
//!         out.damping = Default::default();
//!         Ok(Some(out))
//!     }
//! }
//!
//! let scene = Scene::load(std::path::Path::new("../../configs/paper_f20.toml")).unwrap();
//! let undamped = Undamped.transform(&scene).unwrap().unwrap();
//! assert_eq!(undamped.output_times, scene.output_times);
//! ```

use flexprr_dynamics::{AxialModel, SceneModel};
use flexprr_integrators::Solution;
use flexprr_scene::{OutputKind, Scene};

use crate::error::RunError;

/// What a failed variant run does to the run that asked for it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OnFailure {
    /// The run fails with the variant's error (a variant the requested output cannot do
    /// without), keeping every output computed up to that point.
    FailsRun,
    /// The run goes on; the variant's reason is kept ([`VariantRun::Failed`]) for the
    /// report that compares with it.
    Recorded,
}

/// A named transformation of a scene (see the module documentation).
pub trait SceneVariant: Send + Sync {
    /// The name outputs find the variant's run by (`without_axial_force`, `uncontrolled`).
    fn name(&self) -> &'static str;

    /// One line saying what the variant changes.
    fn description(&self) -> &'static str;

    /// Whether a run of `scene` also runs this variant (what the scene requests); never by
    /// default (a variant used only through [`SceneVariant::transform`]).
    fn wanted(&self, _scene: &Scene) -> bool {
        false
    }

    /// The transformed scene, or `None` when `scene` has no such variant (its model has no
    /// such switch).
    ///
    /// # Errors
    /// The transformed scene cannot be built.
    fn transform(&self, scene: &Scene) -> Result<Option<Scene>, RunError>;

    /// What a failure of the variant's run does to the run ([`OnFailure::Recorded`] by
    /// default).
    fn on_failure(&self) -> OnFailure {
        OnFailure::Recorded
    }

    /// Whether the variant's integration counts in the run's progress (the main run and
    /// each such variant take equal shares); `true` by default.
    fn shows_progress(&self) -> bool {
        true
    }
}

/// The run of a variant: its model and states, or why it stopped or could not start.
pub enum VariantRun {
    /// Integrated over the whole span.
    Solved(Box<dyn SceneModel>, Solution),
    /// Stopped or could not start (a variant with [`OnFailure::Recorded`]): the reason.
    Failed(String),
}

impl VariantRun {
    /// The model and its states, when the run reached the end.
    pub fn solved(&self) -> Option<(&dyn SceneModel, &Solution)> {
        match self {
            VariantRun::Solved(model, solution) => Some((model.as_ref(), solution)),
            VariantRun::Failed(_) => None,
        }
    }
}

/// The paper's comparison run (figures 6-8): the KED model with its axial force switched
/// off, its sliders prescribed and its links bare (no patches), requested by
/// `output.compare_without_axial_force`. Coupled and nonlinear models have no such variant:
/// their axial force is the actual constraint force, not a switch. Its failure fails the
/// run.
#[derive(Debug, Clone, Copy)]
pub struct WithoutAxialForce;

impl SceneVariant for WithoutAxialForce {
    fn name(&self) -> &'static str {
        "without_axial_force"
    }
    fn description(&self) -> &'static str {
        "the KED model with the axial force switched off (the paper's figures 6-8)"
    }
    fn wanted(&self, scene: &Scene) -> bool {
        scene.file.output.compare_without_axial_force
    }
    fn transform(&self, scene: &Scene) -> Result<Option<Scene>, RunError> {
        if scene.build_model_without_axial_force()?.is_none() {
            return Ok(None);
        }
        let mut out = scene.clone();
        out.formulation.axial = AxialModel::None;
        out.axial_model = std::sync::Arc::from(AxialModel::None.model());
        out.patches.clear();
        out.vibration_controller = None;
        out.file.vibration_control = None;
        out.controller = None;
        out.file.control = None;
        Ok(Some(out))
    }
    fn on_failure(&self) -> OnFailure {
        OnFailure::FailsRun
    }
    fn shows_progress(&self) -> bool {
        false
    }
}

/// The scene without its vibration control law ([`Scene::without_vibration_control`]: the
/// patches only sense), run when the scene has patches under a law and the deflections or
/// the piezo output are requested; its failure is recorded in the piezo report.
#[derive(Debug, Clone, Copy)]
pub struct Uncontrolled;

impl SceneVariant for Uncontrolled {
    fn name(&self) -> &'static str {
        "uncontrolled"
    }
    fn description(&self) -> &'static str {
        "the scene without its vibration control law (the patches only sense)"
    }
    fn wanted(&self, scene: &Scene) -> bool {
        !scene.patches.is_empty()
            && scene.vibration_controller.is_some()
            && (scene.outputs.contains(&OutputKind::Deflections)
                || scene.outputs.contains(&OutputKind::Piezo))
    }
    fn transform(&self, scene: &Scene) -> Result<Option<Scene>, RunError> {
        Ok(Some(scene.without_vibration_control()))
    }
}

/// The variants a run makes when its scene asks for them, in the order they run.
pub fn built_in() -> [&'static dyn SceneVariant; 2] {
    [&WithoutAxialForce, &Uncontrolled]
}

/// The built-in variant called `name`.
pub fn built_in_named(name: &str) -> Option<&'static dyn SceneVariant> {
    built_in().into_iter().find(|v| v.name() == name)
}
