//! The one builder of a scene's dynamical system: runs, studies, work-precision and the stress
//! classification all get their model from here, so a coupled scene is integrated with the
//! coupled model everywhere.

use flexprr_dynamics::{
    Actuation, AxialModel, CoupledOptions, CoupledSystem, CouplingModel, DynamicsError,
    ModalSystem, NonlinearOptions, NonlinearSystem, PatchControl, SceneModel,
};

use crate::{ScenarioError, Scene};

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
        let t0 = self.output_times[0];
        match (self.coupling, self.patch_control()) {
            (CouplingModel::Ked, None) => Ok(Box::new(self.build_ked(false)?)),
            (CouplingModel::Ked, Some(p)) => {
                Ok(Box::new(self.build_ked(false)?.with_patch_control(p, t0)?))
            }
            (CouplingModel::Coupled, None) => Ok(Box::new(self.build_coupled()?)),
            (CouplingModel::Coupled, Some(p)) => {
                Ok(Box::new(self.build_coupled()?.with_patch_control(p, t0)?))
            }
            (CouplingModel::Nonlinear, None) => Ok(Box::new(self.build_nonlinear()?)),
            (CouplingModel::Nonlinear, Some(p)) => {
                Ok(Box::new(self.build_nonlinear()?.with_patch_control(p, t0)?))
            }
        }
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
        let bending = settings.bending_stiffness.ok_or_else(|| {
            DynamicsError::Inconsistent(
                "the nonlinear model needs uniform links (one bending stiffness)".into(),
            )
        })?;
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
        let links = &self.machine.links[0];
        match self.coupling {
            CouplingModel::Nonlinear => format!(
                "nonlinear model{sliders}, {} co-rotational elements per link",
                self.large_deflection.elements
            ),
            coupling => format!(
                "{} model{sliders}, {} formulation, {} modes per link: {}",
                if coupling == CouplingModel::Ked {
                    "KED"
                } else {
                    "coupled"
                },
                self.formulation.name(),
                links.modes(),
                links.basis.name()
            ),
        }
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
        match self.coupling {
            CouplingModel::Ked => Ok(Some(Box::new(self.build_ked(true)?))),
            CouplingModel::Coupled | CouplingModel::Nonlinear => Ok(None),
        }
    }

    /// Whether a run of the scene integrates its model: for its states, or because the
    /// model's actual forces (coupled, nonlinear) or its actuators' states (actuated
    /// sliders) are only known along its solution.
    pub fn integrates_model(&self) -> bool {
        use crate::OutputKind;
        self.needs_integration()
            || (self.coupling != CouplingModel::Ked
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

    fn build_coupled(&self) -> Result<CoupledSystem, DynamicsError> {
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
