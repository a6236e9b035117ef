//! Errors of the planning layer: each says which limit or key and where on the path.

use flexprr_dynamics::DynamicsError;
use flexprr_kinematics::{KinematicsError, Pose};
use thiserror::Error;

/// A place on the path: the parameter and the pose there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Where {
    /// Path parameter (in the path's unit).
    pub s: f64,
    /// Pose at `s`.
    pub pose: Pose,
}

impl std::fmt::Display for Where {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "s = {:.6} (pose x = {:.6} m, y = {:.6} m, phi = {:.3} deg)",
            self.s,
            self.pose.x,
            self.pose.y,
            self.pose.phi.to_degrees()
        )
    }
}

/// A limit that no motion can meet, and where.
#[derive(Debug, Clone, PartialEq, Error)]
#[error(
    "no motion can meet {constraint} ({label}) at {at}: {reason} ({value:.6e} against the limit {limit:.6e} {unit})"
)]
pub struct Infeasibility {
    /// The constraint's name.
    pub constraint: String,
    /// Which of its rows (`leg 2`, `link 1 at B`).
    pub label: String,
    /// Where.
    pub at: Where,
    /// Why.
    pub reason: &'static str,
    /// The value the row has there.
    pub value: f64,
    /// The limit.
    pub limit: f64,
    /// Unit of value and limit.
    pub unit: String,
}

/// What went wrong planning a motion.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum PlanningError {
    /// A plan setting is out of its range (the `[plan]` key, its value and the rule).
    #[error("plan.{key} = {value}: {rule}")]
    InvalidSpec {
        /// The key (`slider_speed`, `grid`, ...).
        key: &'static str,
        /// The value as written.
        value: String,
        /// What is required.
        rule: String,
    },
    /// The path leaves the workspace: unreachable, beyond a slider's travel, or too near a
    /// type-I/II singularity.
    #[error("the path leaves the workspace at {at}: {source}")]
    Workspace {
        /// Where.
        at: Where,
        /// The kinematic failure.
        source: KinematicsError,
    },
    /// The rigid inverse dynamics failed on the path (a type-II singular pose).
    #[error("the rigid inverse dynamics fails at {at}: {source}")]
    Dynamics {
        /// Where.
        at: Where,
        /// The failure.
        source: DynamicsError,
    },
    /// A limit that no motion can meet: already broken at rest, or one that leaves no path
    /// speed at all.
    #[error("{0}")]
    Infeasible(Box<Infeasibility>),
    /// No constraint bounds the path speed somewhere: the minimum time would be zero.
    #[error(
        "no constraint bounds the path speed at {at}: add a speed, acceleration or force limit"
    )]
    Unbounded {
        /// Where.
        at: Where,
    },
    /// A periodic plan on an open path.
    #[error(
        "a periodic plan needs a closed path (a circle); this path is open (use boundary = \"rest_to_rest\")"
    )]
    OpenPath,
    /// The axial force model is not of the form the buckling bound assumes.
    #[error("buckling constraint: {0}")]
    AxialModel(String),
    /// An iteration (grid refinement, jerk smoothing, RMS scaling) did not reach its target.
    #[error("{what} did not converge in {iterations} iterations: {detail}")]
    NotConverged {
        /// Which iteration.
        what: &'static str,
        /// Iterations made.
        iterations: usize,
        /// What was left.
        detail: String,
    },
    /// A plan slowed uniformly ([`crate::Planner::stretched`]) breaks a limit.
    #[error("the motion slowed {factor:.4} times breaks a limit: {detail}")]
    Slowed {
        /// The factor on every time.
        factor: f64,
        /// Which limit, by how much.
        detail: String,
    },
    /// No orientation in the search's bounds gives a feasible motion (every candidate left
    /// the workspace or met a limit no timing can meet).
    #[error(
        "no constant orientation in [{min_deg:.3}, {max_deg:.3}] deg gives a feasible motion ({tried} tried); at phi = {phi_deg:.3} deg: {reason}"
    )]
    NoFeasibleOrientation {
        /// Lower bound (deg).
        min_deg: f64,
        /// Upper bound (deg).
        max_deg: f64,
        /// Orientations tried.
        tried: usize,
        /// One of them (deg), the middle of the range.
        phi_deg: f64,
        /// Why it fails.
        reason: String,
    },
    /// An orientation law leaves the search's bounds somewhere on the path.
    #[error(
        "the orientation {phi_deg:.4} deg at s = {s:.6} is outside [{min_deg:.3}, {max_deg:.3}] deg (phi_min_deg, phi_max_deg)"
    )]
    OrientationBounds {
        /// Path parameter there.
        s: f64,
        /// The orientation there (deg).
        phi_deg: f64,
        /// Lower bound (deg).
        min_deg: f64,
        /// Upper bound (deg).
        max_deg: f64,
    },
    /// An invalid planned timing or shaper (from the kinematics layer).
    #[error(transparent)]
    Trajectory(#[from] KinematicsError),
}
