//! What can go wrong in `flexprr plan`.

use flexprr_planning::PlanningError;
use flexprr_run::RunError;
use flexprr_scene::ScenarioError;

/// An error of the plan pipeline, with what it was doing.
#[derive(Debug, thiserror::Error)]
pub enum PlanError {
    /// The scene has no `[plan]` section.
    #[error(
        "{scene}: the scene has no [plan] section: add one with at least one limit (docs/planning.md), e.g. [plan] slider_speed = 1.0"
    )]
    NoPlan {
        /// The scene's name.
        scene: String,
    },
    /// The scene's path cannot be formed.
    #[error("{scene}: trajectory: its path cannot be planned: {source}")]
    Path {
        /// The scene's name.
        scene: String,
        /// Why.
        source: flexprr_kinematics::KinematicsError,
    },
    /// The planner failed (an unreachable path, a limit no motion can meet, a periodic plan
    /// on an open path, an invalid setting): the library's message names the limit and where.
    #[error("{scene}: {stage}: {source}")]
    Planning {
        /// The scene's name.
        scene: String,
        /// What was being planned (`the time-optimal motion`, `the orientation`, ...).
        stage: &'static str,
        /// The planner's error.
        source: Box<PlanningError>,
    },
    /// The machine's modes for shaping could not be computed.
    #[error("{scene}: the modes for shaping at {at}: {message}")]
    Modes {
        /// The scene's name.
        scene: String,
        /// Where on the path.
        at: String,
        /// Why.
        message: String,
    },
    /// A run of the scene's flexible model failed.
    #[error("{scene}: the flexible check of {motion} failed: {source}")]
    Run {
        /// The scene's name.
        scene: String,
        /// Which motion (`the planned motion`, `the unshaped motion`, `the scene's own motion`).
        motion: &'static str,
        /// The run's error (with its time).
        source: Box<RunError>,
    },
    /// The planned scene is not a valid scene (a planned motion the scene builder refuses).
    #[error("{scene}: the planned scene: {source}")]
    PlannedScene {
        /// The scene's name.
        scene: String,
        /// The builder's error.
        source: Box<ScenarioError>,
    },
    /// The deflection limit cannot be met or checked.
    #[error("{scene}: plan.deflection_limit = {limit} m: {detail}")]
    DeflectionLimit {
        /// The scene's name.
        scene: String,
        /// The limit (m).
        limit: f64,
        /// Why, with the probes made.
        detail: String,
    },
    /// Writing the products.
    #[error("{0}")]
    Output(#[from] ScenarioError),
}
