//! Errors of the kinematics layer.
//!
//! Every variant names the leg (as a zero-based index in the field, printed one-based,
//! "leg 2", in the message), the quantity involved and its value, and prints on one line.

use crate::geometry::Branch;

/// Which kind of singularity a [`KinematicsError::Singular`] refers to
/// (classification of Gosselin & Angeles, IEEE Trans. Robot. Autom. 6(3), 1990).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SingularityKind {
    /// Type I (serial, inverse-kinematic) singularity of one leg: the link is perpendicular
    /// to its guide, `e_i . u_i -> 0`, and the slider rate `rho_i'` needed for a given platform
    /// twist grows without bound.
    TypeI,
    /// Type II (parallel, direct-kinematic) singularity: the three link lines are concurrent
    /// (or parallel), the direct Jacobian is singular and the platform gains an uncontrolled
    /// instantaneous motion; rigid-body inverse dynamics has no unique solution.
    TypeII,
}

impl std::fmt::Display for SingularityKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SingularityKind::TypeI => f.write_str("type-I (serial, |e.u|)"),
            SingularityKind::TypeII => {
                f.write_str("type-II (parallel, normalised det of the direct Jacobian)")
            }
        }
    }
}

/// Formats an optional zero-based leg index as "leg N" (one-based) or "platform".
fn leg_label(leg: &Option<usize>) -> String {
    match leg {
        Some(i) => format!("leg {}", i + 1),
        None => "platform".to_owned(),
    }
}

/// Formats an optional array index as `[k]`.
fn index_label(index: &Option<usize>) -> String {
    index.map_or_else(String::new, |k| format!("[{k}]"))
}

/// Everything that can go wrong in the kinematics layer.
///
/// Leg fields are zero-based indices into [`crate::Geometry::legs`]; messages print them
/// one-based ("leg 1" .. "leg 3"). Lengths are in metres, angles in radians, times in seconds.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum KinematicsError {
    /// The platform joint `C_i` is farther from the guide line of leg `leg` than the link
    /// length: the closure discriminant `l^2 - (d x u)^2` is negative.
    #[error(
        "leg {}: pose unreachable, platform joint lies {shortfall:.6e} m farther from the guide line than the link length",
        .leg + 1
    )]
    Unreachable {
        /// Zero-based leg index.
        leg: usize,
        /// `|d x u| - l > 0`: by how much the link is too short, in metres.
        shortfall: f64,
    },
    /// The slider position lies outside the travel of its guide.
    #[error(
        "leg {}: slider position rho = {rho:.6e} m outside travel [{min:.6e}, {max:.6e}] m by {excess:.6e} m",
        .leg + 1
    )]
    TravelExceeded {
        /// Zero-based leg index.
        leg: usize,
        /// Slider position `rho_i` (m).
        rho: f64,
        /// Lower end of the travel (m).
        min: f64,
        /// Upper end of the travel (m).
        max: f64,
        /// Distance beyond the nearer end of the travel (m, positive).
        excess: f64,
    },
    /// The pose is singular or closer to a singularity than the configured threshold.
    #[error("{}: {kind} singularity measure {measure:.6e} below threshold {threshold:.6e}", leg_label(.leg))]
    Singular {
        /// Type I (one leg) or type II (whole machine).
        kind: SingularityKind,
        /// Zero-based leg index for type I, `None` for type II.
        leg: Option<usize>,
        /// The dimensionless measure (see [`crate::SingularityMeasures`]).
        measure: f64,
        /// The threshold it fell below (`0` when the quantity is exactly singular).
        threshold: f64,
    },
    /// A geometry parameter is invalid.
    #[error("{}: invalid geometry, {quantity} = {value:.6e} ({reason})", leg_label(.leg))]
    InvalidGeometry {
        /// Zero-based leg index, `None` for whole-machine parameters.
        leg: Option<usize>,
        /// Name of the parameter.
        quantity: &'static str,
        /// Offending value.
        value: f64,
        /// What is required.
        reason: &'static str,
    },
    /// An input (pose, velocity, slider position, ...) is NaN or infinite.
    #[error("non-finite input: {quantity} = {value}")]
    NonFinite {
        /// Name of the quantity.
        quantity: &'static str,
        /// Offending value.
        value: f64,
    },
    /// Newton's method on the closure equations did not converge.
    #[error(
        "forward kinematics did not converge in {iterations} iterations (closure residual {residual:.6e} m)"
    )]
    NoConvergence {
        /// Iterations performed.
        iterations: usize,
        /// Largest closure residual `|C_i - B_i| - l_i` at the last iterate (m).
        residual: f64,
    },
    /// Forward kinematics converged to a pose in which a leg is in the other assembly mode.
    #[error(
        "leg {}: forward kinematics converged to the other assembly mode (e.u = {e_dot_u:.6e}, expected branch {expected:?})",
        .leg + 1
    )]
    BranchMismatch {
        /// Zero-based leg index.
        leg: usize,
        /// The branch the geometry asks for.
        expected: Branch,
        /// `e_i . u_i` at the converged pose (>= 0 for `Behind`, <= 0 for `Ahead`).
        e_dot_u: f64,
    },
    /// A trajectory parameter is invalid.
    #[error("invalid trajectory: {quantity} = {value:.6e} ({reason})")]
    InvalidTrajectory {
        /// Name of the parameter.
        quantity: &'static str,
        /// Offending value.
        value: f64,
        /// What is required.
        reason: &'static str,
    },
    /// A field of a planned trajectory's data (a path timing, a shaper) is invalid.
    #[error("invalid planned trajectory: {field}{} = {value:.6e} ({reason})", index_label(.index))]
    InvalidPlan {
        /// The data field (`s`, `s_dot`, `shaper`, `smoothing`, ...).
        field: &'static str,
        /// Zero-based index into the field's array, where it is one.
        index: Option<usize>,
        /// Offending value.
        value: f64,
        /// What is required.
        reason: &'static str,
    },
    /// An error found while sampling a trajectory, with the time of the sample.
    #[error("at t = {t:.9e} s: {error}")]
    AtTime {
        /// Time of the failing sample (s).
        t: f64,
        /// The error at that time (its message is included in this one's).
        error: Box<KinematicsError>,
    },
}

impl KinematicsError {
    /// The error without any [`KinematicsError::AtTime`] wrapper.
    pub fn innermost(&self) -> &KinematicsError {
        match self {
            KinematicsError::AtTime { error, .. } => error.innermost(),
            other => other,
        }
    }
}
