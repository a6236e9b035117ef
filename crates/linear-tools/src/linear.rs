//! The operating points of a scene's linear models (docs/linear.md): the scene's own model
//! held at rest at a pose, or integrated along its motion to a time. The linearisation
//! itself is `flexprr-linear`'s, which knows no model kind.

use flexprr_dynamics::SceneModel;
use flexprr_kinematics::Pose;
use flexprr_linear::{Input, Linearization, Output, Settings, linearize_with_settings};
use flexprr_scene::{ScenarioError, Scene};

use flexprr_run::RunError;
use flexprr_run::integrate_model;
use flexprr_run::scene_integrator;

/// The largest orientation of a pose at rest (deg): two turns. Beyond it an angle is far
/// more likely a slip (radians for degrees, a missing decimal point) than meant, and its
/// sine and cosine lose digits.
pub const MAX_ORIENTATION_DEG: f64 = 720.0;

/// Why `phi_deg` is no orientation of a pose at rest, if it is not: not finite, or beyond
/// [`MAX_ORIENTATION_DEG`] (the message gives its equivalent within one turn).
///
/// # Errors
/// The rule, in words.
pub fn check_orientation_deg(phi_deg: f64) -> Result<(), String> {
    if !phi_deg.is_finite() {
        return Err(format!(
            "phi = {phi_deg} deg: expected a finite orientation (deg)"
        ));
    }
    if phi_deg.abs() > MAX_ORIENTATION_DEG {
        let equivalent = phi_deg.rem_euclid(360.0);
        return Err(format!(
            "phi = {phi_deg} deg is more than two turns: give the orientation between \
             -{MAX_ORIENTATION_DEG} and {MAX_ORIENTATION_DEG} deg (this one is {} deg)",
            (equivalent * 1e9).round() / 1e9
        ));
    }
    Ok(())
}

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

/// The scene as the linear tools see it: its control law replaced by the law's linear
/// part where they differ (`flexprr_control::Controller::linear_law`: a law behind
/// quantising encoders without the rounding, which is not linear; the model's notes say so).
/// The motion up to a time is integrated with that law too.
pub fn linear_scene(scene: &Scene) -> std::borrow::Cow<'_, Scene> {
    match scene.controller.as_ref().and_then(|c| c.linear_law()) {
        Some(law) => {
            let mut linear = scene.clone();
            linear.controller = Some(law);
            std::borrow::Cow::Owned(linear)
        }
        None => std::borrow::Cow::Borrowed(scene),
    }
}

/// The scene's model at `at`.
///
/// # Errors
/// A KED scene (its platform is prescribed: it has no whole-machine modes; use
/// `model.coupling = "coupled"` or `"nonlinear"`), a pose the machine cannot hold or a
/// singular one, a time outside the scene's span, or a run that fails before the time.
pub fn operating_point(scene: &Scene, at: OperatingPoint) -> Result<AtOperatingPoint, RunError> {
    if !scene.coupling.capabilities().free_platform {
        return Err(RunError::Scene(ScenarioError::Input {
            location: None,
            key: "model.coupling".into(),
            message: "the KED model prescribes the platform and the sliders, so it has no \
                      whole-machine modes (each link is a pinned-pinned beam: see the \
                      frequencies output); set model.coupling = \"coupled\" or \"nonlinear\""
                .into(),
        }));
    }
    let scene = linear_scene(scene);
    let scene = scene.as_ref();
    match at {
        OperatingPoint::Rest(pose) => {
            let rest = scene.at_rest(pose)?;
            let model = rest.build_model()?;
            check_size(scene, model.as_ref())?;
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
    let (model, mut states) = integrate_to(scene, &[t], "time")?;
    let state = states.pop().unwrap_or_default();
    Ok(AtOperatingPoint { model, t, state })
}

/// The model that integrated a motion and its states at the requested times.
pub type MotionStates = (Box<dyn SceneModel>, Vec<Vec<f64>>);

/// The states of the scene's motion at `times` (s, increasing, within its span) from one
/// integration, with the model that integrated them (its sampled laws' samples kept for the
/// linearisations that follow).
///
/// # Errors
/// A KED scene, a time outside the span or not increasing, or a run that fails before the
/// last time (with its time).
pub fn along_motion_states(scene: &Scene, times: &[f64]) -> Result<MotionStates, RunError> {
    integrate_to(scene, times, "times")
}

/// [`along_motion_states`] with a bad time refused at `key`.
fn integrate_to(scene: &Scene, times: &[f64], key: &str) -> Result<MotionStates, RunError> {
    if !scene.coupling.capabilities().free_platform {
        operating_point(scene, OperatingPoint::Time(scene.output_times[0]))?;
    }
    let (t0, t1) = (
        scene.output_times[0],
        scene.output_times[scene.output_times.len() - 1],
    );
    let bad = |message: String| {
        RunError::Scene(ScenarioError::Input {
            location: None,
            key: key.into(),
            message,
        })
    };
    if times.is_empty() {
        return Err(bad("no time given".into()));
    }
    if let Some(t) = times
        .iter()
        .find(|t| !(t.is_finite() && **t >= t0 && **t <= t1))
    {
        return Err(bad(format!(
            "t = {t:?} s is outside the scene's time span [{t0:?}, {t1:?}] s"
        )));
    }
    if let Some(k) = (1..times.len()).find(|&k| times[k] <= times[k - 1]) {
        return Err(bad(format!(
            "the times must increase: {} s follows {} s",
            times[k],
            times[k - 1]
        )));
    }
    let scene = linear_scene(scene);
    let scene = scene.as_ref();
    let mut model = scene.build_model()?;
    check_size(scene, model.as_ref())?;
    let mut span = scene.clone();
    let last = times[times.len() - 1];
    span.output_times = std::iter::once(t0)
        .chain(times.iter().copied().filter(|t| *t > t0))
        .collect();
    span.stop_times.retain(|s| *s < last);
    if last <= t0 {
        let state = model.initial_state();
        return Ok((model, vec![state; times.len()]));
    }
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
    let states = times
        .iter()
        .map(|t| {
            let k = (0..solution.len())
                .min_by(|&a, &b| {
                    (solution.t[a] - t)
                        .abs()
                        .total_cmp(&(solution.t[b] - t).abs())
                })
                .unwrap_or(0);
            solution.y(k).to_vec()
        })
        .collect();
    Ok((model, states))
}

/// Refuses a model whose dense linear analysis would exceed the documented bound
/// (`flexprr_linear::cost`), before anything dense is built or integrated.
///
/// # Errors
/// The estimate, at the key that sets the model's size.
pub fn check_size(scene: &Scene, model: &dyn SceneModel) -> Result<(), RunError> {
    flexprr_linear::cost::check(model.dim(), 0)
        .map(|_| ())
        .map_err(|e| linear_error(scene, e))
}

/// A linear-layer error as a run error: a model failure stays one; a model too large for a
/// dense analysis is refused at the key that sets its size; the rest fails the analysis.
pub fn linear_error(scene: &Scene, e: flexprr_linear::LinearError) -> RunError {
    use flexprr_linear::LinearError;
    match e {
        LinearError::Model(e) => RunError::Model(e),
        e @ LinearError::TooLarge { .. } => RunError::Scene(ScenarioError::Input {
            location: None,
            key: scene.coupling.capabilities().size_key().into(),
            message: e.to_string(),
        }),
        source => RunError::Analysis {
            analysis: None,
            source,
        },
    }
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
    settings: &Settings,
) -> Result<Linearization, RunError> {
    let mut point = operating_point(scene, at)?;
    linearize_with_settings(
        point.model.as_mut(),
        point.t,
        &point.state,
        inputs,
        outputs,
        settings,
    )
    .map_err(|e| linear_error(scene, e))
}
