//! The operating points of a scene's linear models (docs/linear.md): the scene's own model
//! held at rest at a pose, or integrated along its motion to a time. The linearisation
//! itself is `flexprr-linear`'s, which knows no model kind.

use flexprr_dynamics::{CouplingModel, SceneModel};
use flexprr_kinematics::Pose;
use flexprr_linear::{Input, Linearization, Output, linearize};
use flexprr_scene::{ScenarioError, Scene};

use crate::error::RunError;
use crate::integrate::integrate_model;
use crate::run::scene_integrator;

/// Where a linear model is taken.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OperatingPoint {
    /// The platform at rest at a pose (m, m, rad): sliders locked, or held by the scene's
    /// controller.
    Rest(Pose),
    /// The state of the scene's motion at a time (s), with its axial loads, centrifugal and
    /// gyroscopic terms and its controller.
    Time(f64),
}

/// A scene's model at an operating point: the model, the time and the state.
pub struct AtOperatingPoint {
    /// The scene's model (for a pose, built with the platform held there).
    pub model: Box<dyn SceneModel>,
    /// Time of the operating point (s).
    pub t: f64,
    /// The model's state there.
    pub state: Vec<f64>,
}

impl std::fmt::Debug for AtOperatingPoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("AtOperatingPoint")
            .field("model", &self.model.kind())
            .field("t", &self.t)
            .finish_non_exhaustive()
    }
}

/// The scene's model at `at`.
///
/// # Errors
/// A KED scene (its platform is prescribed: it has no whole-machine modes; use
/// `model.coupling = "coupled"` or `"nonlinear"`), a pose the machine cannot hold or a
/// singular one, a time outside the scene's span, or a run that fails before the time.
pub fn operating_point(scene: &Scene, at: OperatingPoint) -> Result<AtOperatingPoint, RunError> {
    if scene.coupling == CouplingModel::Ked {
        return Err(RunError::Scene(ScenarioError::Input {
            location: None,
            key: "model.coupling".into(),
            message: "the KED model prescribes the platform and the sliders, so it has no \
                      whole-machine modes (each link is a pinned-pinned beam: see the \
                      frequencies output); set model.coupling = \"coupled\" or \"nonlinear\""
                .into(),
        }));
    }
    match at {
        OperatingPoint::Rest(pose) => {
            let rest = scene.at_rest(pose)?;
            let model = rest.build_model()?;
            let state = model.initial_state();
            Ok(AtOperatingPoint {
                model,
                t: rest.output_times[0],
                state,
            })
        }
        OperatingPoint::Time(t) => along_motion(scene, t),
    }
}

/// The scene's model integrated from its start to `t`.
fn along_motion(scene: &Scene, t: f64) -> Result<AtOperatingPoint, RunError> {
    let (t0, t1) = (
        scene.output_times[0],
        scene.output_times[scene.output_times.len() - 1],
    );
    if !(t.is_finite() && t >= t0 && t <= t1) {
        return Err(RunError::Scene(ScenarioError::Input {
            location: None,
            key: "time".into(),
            message: format!("t = {t:?} s is outside the scene's time span [{t0:?}, {t1:?}] s"),
        }));
    }
    let mut model = scene.build_model()?;
    if t <= t0 {
        let state = model.initial_state();
        return Ok(AtOperatingPoint { model, t, state });
    }
    let mut span = scene.clone();
    span.output_times = vec![t0, t];
    span.stop_times.retain(|s| *s < t);
    let integration = integrate_model(
        &span,
        scene_integrator(scene).as_ref(),
        model.as_mut(),
        &mut |_| {},
    );
    if let Some(failure) = integration.failure {
        return Err(failure);
    }
    let solution = integration.solution;
    let state = solution.y(solution.len() - 1).to_vec();
    Ok(AtOperatingPoint { model, t, state })
}

/// The scene's linear model at `at` for `inputs` and `outputs`.
///
/// # Errors
/// As [`operating_point`], or the model fails near the operating point or cannot take an
/// input.
pub fn linear_model(
    scene: &Scene,
    at: OperatingPoint,
    inputs: &[Input],
    outputs: &[Output],
) -> Result<Linearization, RunError> {
    let mut point = operating_point(scene, at)?;
    linearize(point.model.as_mut(), point.t, &point.state, inputs, outputs).map_err(|e| match e {
        flexprr_linear::LinearError::Model(e) => RunError::Model(e),
        other => RunError::Scene(ScenarioError::Run(other.to_string())),
    })
}
