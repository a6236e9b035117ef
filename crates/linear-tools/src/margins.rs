//! The loop margins of a scene's slider loops (docs/control.md, "Loop margins"): each slider
//! loop broken at its actuator (`actuator_command:I` in, `slider_command:I` out, the other
//! two loops closed) at the platform at rest at a pose, its gain and phase margins,
//! crossovers and sensitivity peak ([`flexprr_linear::loop_margins`]), on the discrete
//! model where the law is sampled. `flexprr.margins` in Python.

use flexprr_kinematics::Pose;
use flexprr_linear::{Input, LoopMargins, Output, linearize, loop_margins};
use flexprr_run::RunError;
use flexprr_scene::{ScenarioError, Scene};

use crate::linear::{OperatingPoint, operating_point};

/// The margins of one slider's loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SliderLoop {
    /// The margins.
    pub margins: LoopMargins,
    /// The model's sample period (s), 0 for a continuous loop.
    pub dt: f64,
}

/// The margins of the three slider loops of `scene` at rest at `pose` (the start pose of
/// its motion by default).
///
/// # Errors
/// A scene without `[control]`, a pose the machine cannot hold, a failed linearisation.
pub fn slider_loop_margins(scene: &Scene, pose: Option<Pose>) -> Result<Vec<SliderLoop>, RunError> {
    if scene.controller.is_none() {
        return Err(RunError::Scene(ScenarioError::Input {
            location: None,
            key: "control".into(),
            message: "margins need a control loop: the scene has no [control] table".into(),
        }));
    }
    let pose = pose.unwrap_or_else(|| crate::machine_modes::start_pose(scene));
    (0..3)
        .map(|i| {
            let mut at = operating_point(scene, OperatingPoint::Rest(pose))?;
            let failed = |source: flexprr_linear::LinearError| RunError::Analysis {
                analysis: Some(format!("margins: slider {}", i + 1)),
                source,
            };
            let lin = linearize(
                at.model.as_mut(),
                at.t,
                &at.state,
                &[Input::ActuatorCommand(i)],
                &[Output::SliderCommand(i)],
            )
            .map_err(failed)?;
            let margins = loop_margins(&lin).map_err(failed)?;
            Ok(SliderLoop {
                margins,
                dt: lin.dt,
            })
        })
        .collect()
}
