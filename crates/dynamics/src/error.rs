//! Errors of the dynamics layer.

use thiserror::Error;

/// What went wrong in the dynamics layer; each variant says where (time, link, mode).
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum DynamicsError {
    /// The kinematics failed (unreachable, travel, singular), with the time if known.
    #[error("at t = {t} s: {source}")]
    Kinematics {
        /// Time (s).
        t: f64,
        /// The kinematic failure.
        source: flexprr_kinematics::KinematicsError,
    },
    /// The platform equilibrium cannot be solved: the link lines are (nearly) concurrent or
    /// parallel, so the axial link forces are not determined (type-II singularity).
    #[error(
        "at t = {t} s the rigid inverse dynamics is singular: the link lines are nearly concurrent (type-II measure {measure:.3e} below {threshold:.1e})"
    )]
    SingularInverseDynamics {
        /// Time (s).
        t: f64,
        /// Normalised determinant of the platform equilibrium matrix.
        measure: f64,
        /// Threshold it fell below.
        threshold: f64,
    },
    /// The mechanism collapsed: a link's mid-point deflection passed the model's collapse
    /// limit (a fraction of the link length), or the deflection drove the platform into (or
    /// near) a type-II singular pose. A physical outcome, not a numerical failure: the
    /// history up to `t` is valid.
    #[error(
        "the mechanism collapsed at t = {:.1} ms: link {link} deflection {:.1} mm ({:.1} % of its length), type-II measure {type_ii_measure:.1e}",
        .t * 1e3,
        .deflection.abs() * 1e3,
        100.0 * .deflection.abs() / .length
    )]
    Collapse {
        /// Time (s).
        t: f64,
        /// The link with the largest mid-point deflection (1-based, as in the message).
        link: usize,
        /// Its mid-point deflection from the chord (m).
        deflection: f64,
        /// Its length (m).
        length: f64,
        /// Type-II measure of the (deflected) chords at `t`.
        type_ii_measure: f64,
    },
    /// A beam-layer failure (basis, section, eigenproblem).
    #[error(transparent)]
    Beam(#[from] flexprr_beam::BeamError),
    /// Invalid machine or model parameters.
    #[error("invalid {quantity} = {value}: {reason}")]
    InvalidParameter {
        /// Which parameter.
        quantity: String,
        /// Its value.
        value: f64,
        /// What is expected.
        reason: &'static str,
    },
    /// A sampled control law failed to compute its command (a law in another language
    /// raised): the run stops at that sample.
    #[error(transparent)]
    Control(#[from] flexprr_control::ControlError),
    /// Inconsistent model set-up (e.g. a damping list longer than the modes).
    #[error("{0}")]
    Inconsistent(String),
}
