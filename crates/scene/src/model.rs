//! The one builder of a scene's dynamical system: runs, studies, work-precision and the stress
//! classification all get their model from here, so a coupled scene is integrated with the
//! coupled model everywhere.

use flexprr_dynamics::{
    Actuation, AxialModel, CoupledOptions, CoupledSystem, DynamicsError, ModalSystem,
    NonlinearOptions, NonlinearSystem, PatchControl, SceneModel,
};

use crate::{ModelCapabilities, ModelKind, ScenarioError, Scene};

/// The KED model (`model.coupling = "ked"`): rigid motion prescribed, the links' modal
/// equations linear in their state ([`ModalSystem`]).
pub struct KedKind;

/// The coupled model (`"coupled"`): the platform moved by the links' foreshortening, links in
/// assumed modes ([`CoupledSystem`]).
pub struct CoupledKind;

/// The geometrically nonlinear model (`"nonlinear"`): co-rotational elements and a free
/// platform ([`NonlinearSystem`]).
pub struct NonlinearKind;

impl ModelKind for KedKind {
    fn capabilities(&self) -> ModelCapabilities {
        ModelCapabilities {
            linear_in_state: true,
            assumed_modes: true,
            ..ModelCapabilities::default()
        }
    }
    fn build(&self, scene: &Scene) -> Result<Box<dyn SceneModel>, DynamicsError> {
        let system = scene.build_ked(false)?;
        match scene.patch_control() {
            None => Ok(Box::new(system)),
            Some(p) => Ok(Box::new(
                system.with_patch_control(p, scene.output_times[0])?,
            )),
        }
    }
    fn build_without_axial_force(
        &self,
        scene: &Scene,
    ) -> Result<Option<Box<dyn SceneModel>>, DynamicsError> {
        Ok(Some(Box::new(scene.build_ked(true)?)))
    }
    fn describe(&self, _name: &str, scene: &Scene, sliders: &str) -> String {
        modal_description("KED", scene, sliders)
    }
}

impl ModelKind for CoupledKind {
    fn capabilities(&self) -> ModelCapabilities {
        ModelCapabilities {
            free_platform: true,
            assumed_modes: true,
            consistent_only: true,
            ..ModelCapabilities::default()
        }
    }
    fn build(&self, scene: &Scene) -> Result<Box<dyn SceneModel>, DynamicsError> {
        let system = scene.build_coupled()?;
        match scene.patch_control() {
            None => Ok(Box::new(system)),
            Some(p) => Ok(Box::new(
                system.with_patch_control(p, scene.output_times[0])?,
            )),
        }
    }
    fn describe(&self, _name: &str, scene: &Scene, sliders: &str) -> String {
        modal_description("coupled", scene, sliders)
    }
}

impl ModelKind for NonlinearKind {
    fn capabilities(&self) -> ModelCapabilities {
        ModelCapabilities {
            mechanical_form: true,
            free_platform: true,
            consistent_only: true,
            ..ModelCapabilities::default()
        }
    }
    fn build(&self, scene: &Scene) -> Result<Box<dyn SceneModel>, DynamicsError> {
        let system = scene.build_nonlinear()?;
        match scene.patch_control() {
            None => Ok(Box::new(system)),
            Some(p) => Ok(Box::new(
                system.with_patch_control(p, scene.output_times[0])?,
            )),
        }
    }
    fn describe(&self, _name: &str, scene: &Scene, sliders: &str) -> String {
        format!(
            "nonlinear model{sliders}, {} co-rotational elements per link",
            scene.large_deflection.elements
        )
    }
}

/// `"<label> model<sliders>, <formulation> formulation, <r> modes per link: <basis>"`.
fn modal_description(label: &str, scene: &Scene, sliders: &str) -> String {
    let links = &scene.machine.links[0];
    format!(
        "{label} model{sliders}, {} formulation, {} modes per link: {}",
        scene.formulation.name(),
        links.modes(),
        links.basis.name()
    )
}

impl Scene {
    /// Builds the dynamical system the scene integrates: the KED [`ModalSystem`] with the
    /// scene's formulation and axial force model, the [`CoupledSystem`] when
    /// `model.coupling = "coupled"`, or the [`NonlinearSystem`] when `"nonlinear"`; with a
    /// `[control]` table the coupled or nonlinear model has its sliders driven by the
    /// actuators under the control law ([`Scene::actuation`]), started on the commanded path
    /// at the first output time.
    ///
    /// # Errors
    /// A modal mass matrix that is not positive definite, inconsistent damping, or (nonlinear)
    /// a kinematic failure at the start time.
    pub fn build_model(&self) -> Result<Box<dyn SceneModel>, DynamicsError> {
        self.coupling.kind().build(self)
    }

    /// The links' patches under their vibration control law (sensors only without one),
    /// when the scene has patches.
    pub fn patch_control(&self) -> Option<PatchControl> {
        if self.patches.is_empty() {
            return None;
        }
        let controller = self
            .vibration_controller
            .clone()
            .unwrap_or_else(|| std::sync::Arc::new(crate::piezo::Passive));
        Some(PatchControl {
            patches: self.patches.clone(),
            controller,
        })
    }

    /// The scene without its vibration control law (the patches only sense): the
    /// uncontrolled run a controlled one is compared with.
    pub fn without_vibration_control(&self) -> Scene {
        let mut scene = self.clone();
        scene.vibration_controller = None;
        scene.file.vibration_control = None;
        scene
    }

    /// The geometrically nonlinear system of the scene: `model.elements` co-rotational
    /// elements per link with the links' `EA` and `EI`, the collapse limit, the axial
    /// damping, started in the rigid state at the first output time.
    ///
    /// # Errors
    /// A tapered or stepped section (no single `EI`), bad options, or a kinematic failure at
    /// the start time.
    pub fn build_nonlinear(&self) -> Result<NonlinearSystem, DynamicsError> {
        let settings = self.large_deflection;
        let bending = settings
            .bending_stiffness
            .ok_or(DynamicsError::NonUniformLinks)?;
        let options = NonlinearOptions {
            axial_damping_time: settings.axial_damping_time,
            collapse_deflection: Some(settings.collapse_deflection),
            ..NonlinearOptions::uniform(settings.elements, self.axial_stiffness, bending)
        };
        let mut system =
            NonlinearSystem::new(self.machine.clone(), self.trajectory.clone(), options)?;
        system.start_at(self.output_times[0])?;
        match self.actuation() {
            Some(actuation) => system.with_actuation(actuation, self.output_times[0]),
            None => Ok(system),
        }
    }

    /// The sliders' actuation when the scene has a `[control]` table: the control law and
    /// the scene's actuator on each slider.
    pub fn actuation(&self) -> Option<Actuation> {
        let controller = self.controller.clone()?;
        let actuator = self.actuator.clone()?;
        Some(Actuation {
            controller,
            actuators: [actuator.clone(), actuator.clone(), actuator],
        })
    }

    /// What `flexprr check` says about the scene's model: the model, its sliders (actuated
    /// under a control law, or prescribed with actuators to check), and its links, e.g.
    /// `coupled model, actuated sliders (pd, force actuators), 3 modes per link: sine`.
    pub fn model_description(&self) -> String {
        let sliders = match (&self.file.control, &self.actuator) {
            (Some(control), Some(actuator)) => format!(
                ", actuated sliders ({}, {} actuators)",
                control.kind,
                actuator.name()
            ),
            (None, Some(actuator)) if actuator.ratings().is_some() => format!(
                ", prescribed sliders ({} actuators: the motion is checked against their ratings)",
                actuator.name()
            ),
            (None, Some(actuator)) => {
                format!(", prescribed sliders ({} actuators)", actuator.name())
            }
            _ => String::new(),
        };
        self.coupling
            .kind()
            .describe(self.coupling.name(), self, &sliders)
    }

    /// The scene's model with the axial force switched off, for the paper's comparison
    /// "without axial force" (figures 6-8): the KED modal system without it. `None` for the
    /// coupled and nonlinear models, whose axial force is the actual constraint force, not a
    /// switch.
    ///
    /// # Errors
    /// As [`Scene::build_model`].
    pub fn build_model_without_axial_force(
        &self,
    ) -> Result<Option<Box<dyn SceneModel>>, DynamicsError> {
        self.coupling.kind().build_without_axial_force(self)
    }

    /// Whether a run of the scene integrates its model: for its states, or because the
    /// model's actual forces (coupled, nonlinear) or its actuators' states (actuated
    /// sliders) are only known along its solution.
    pub fn integrates_model(&self) -> bool {
        use crate::OutputKind;
        self.needs_integration()
            || (self.coupling.capabilities().free_platform
                && (self.outputs.contains(&OutputKind::AxialForces)
                    || self.outputs.contains(&OutputKind::DrivingForces)))
            || (self.controller.is_some() && self.outputs.contains(&OutputKind::Actuators))
    }

    /// The KED modal system of the scene (also for a coupled scene: its frequencies and
    /// rigid-body outputs are the KED ones).
    ///
    /// # Errors
    /// As [`Scene::build_model`].
    pub fn build_ked(&self, axial_off: bool) -> Result<ModalSystem, DynamicsError> {
        let mut formulation = self.formulation;
        if axial_off {
            formulation.axial = AxialModel::None;
            return ModalSystem::new(
                self.machine.clone(),
                self.trajectory.clone(),
                formulation,
                self.damping.clone(),
            );
        }
        ModalSystem::with_axial_model(
            self.machine.clone(),
            self.trajectory.clone(),
            formulation,
            self.damping.clone(),
            self.axial_model.clone(),
        )
    }

    /// The coupled system of the scene ([`CoupledSystem`]), with its actuation.
    ///
    /// # Errors
    /// As [`Scene::build_model`].
    pub fn build_coupled(&self) -> Result<CoupledSystem, DynamicsError> {
        let options = CoupledOptions {
            axial_stiffness: Some([self.axial_stiffness; 3]),
            elastic_chords_at_rest: !self.rigid_chords,
            collapse_deflection: Some(self.large_deflection.collapse_deflection),
            ..CoupledOptions::full()
        };
        let system = CoupledSystem::new(
            self.machine.clone(),
            self.trajectory.clone(),
            self.damping.clone(),
            options,
        )?;
        match self.actuation() {
            Some(actuation) => system.with_actuation(actuation, self.output_times[0]),
            None => Ok(system),
        }
    }

    /// The scene with its platform held at rest in `pose` (m, m, rad) from the scene's start
    /// time: the operating point of whole-machine modes and frequency responses at a pose
    /// (docs/linear.md). The scene's model, damping and control are kept: prescribed sliders
    /// stay locked on the pose's inverse kinematics, actuated ones are held there by their
    /// controller.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] at `pose` when the machine cannot reach it or the pose is
    /// (nearly) type-II singular, where the platform is not held.
    pub fn at_rest(&self, pose: flexprr_kinematics::Pose) -> Result<Scene, ScenarioError> {
        use flexprr_kinematics::{Line, PlatformMotion};
        let bad = |message: String| ScenarioError::Input {
            location: None,
            key: "pose".into(),
            message,
        };
        let where_ = format!(
            "(x, y, phi) = ({:?} m, {:?} m, {:?} deg)",
            pose.x,
            pose.y,
            pose.phi.to_degrees()
        );
        let state = self
            .machine
            .geometry
            .inverse_kinematics(&PlatformMotion::at_rest(pose))
            .map_err(|e| {
                bad(format!(
                    "the machine cannot hold the platform at {where_}: {e}"
                ))
            })?;
        let measure = flexprr_dynamics::equilibrium_measure(&state);
        let threshold = self.machine.geometry.thresholds.type_ii;
        if measure.is_nan() || measure < threshold {
            return Err(bad(format!(
                "{where_} is type-II singular (measure {measure:.2e} below {threshold:.1e}): \
                 the link lines meet in a point and the links do not hold the platform"
            )));
        }
        let t0 = self.output_times[0];
        let line = Line::new(pose, nalgebra::Vector3::zeros(), t0)
            .map_err(|e| bad(format!("{where_}: {e}")))?;
        let mut scene = self.clone();
        scene.trajectory = std::sync::Arc::new(line);
        Ok(scene)
    }
}
