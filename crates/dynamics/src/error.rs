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
    /// A state or guess whose length is not the model's.
    #[error("{what} has {found} {unit}, the {model} {expected}")]
    Dimension {
        /// What was given (`"state"`, `"static guess"`).
        what: &'static str,
        /// Its unit of length (`"entries"`, `"coordinates"`).
        unit: &'static str,
        /// The model it was given to (`"coupled system"`, `"beam"`).
        model: &'static str,
        /// Its length.
        found: usize,
        /// The model's length.
        expected: usize,
    },
    /// A coordinate index past the model's coordinates.
    #[error("coordinate index {index} out of range (the beam has {count})")]
    CoordinateIndex {
        /// The index given (0-based).
        index: usize,
        /// Number of coordinates.
        count: usize,
    },
    /// A point force on a link that does not exist, outside the link, or not finite.
    #[error(
        "a point force needs link 1, 2 or 3, xi in [0, 1] and a finite force; got link {link}, xi {xi}, force {force}"
    )]
    PointForce {
        /// The link (1-based, as in the message).
        link: usize,
        /// Where along it.
        xi: f64,
        /// The force (N).
        force: f64,
    },
    /// A link's modal mass matrix is not positive definite (a bad section or basis).
    #[error("the modal mass matrix of link {link} is not positive definite")]
    ModalMass {
        /// The link (1-based).
        link: usize,
    },
    /// A link's modal eigen-decomposition failed.
    #[error("eigen-decomposition failed for link {link}")]
    Eigen {
        /// The link (1-based).
        link: usize,
    },
    /// The modal damping list does not fit a link's modes.
    #[error(
        "modal damping lists {ratios} ratios but link {link} has {modes} modes (give one ratio for all, or one per mode)"
    )]
    DampingRatios {
        /// Number of ratios given.
        ratios: usize,
        /// The link (1-based).
        link: usize,
        /// Its modes.
        modes: usize,
    },
    /// The coupled model's mass matrix is singular at a pose: the pose cannot be integrated.
    #[error("at t = {t} s the coupled mass matrix is singular (zero pivot in column {column})")]
    SingularMass {
        /// Time (s).
        t: f64,
        /// The column of the zero pivot (0-based).
        column: usize,
    },
    /// The nonlinear model's generalized mass matrix is not positive definite (a bug or a
    /// non-finite state).
    #[error("at t = {t} s the generalized mass matrix is not positive definite")]
    MassNotPositive {
        /// Time (s).
        t: f64,
    },
    /// The chords' lines meet in a point, so they do not hold the platform (a type-II pose
    /// of the chords).
    #[error("at t = {t} s the chords do not hold the platform (their lines meet in a point)")]
    ChordsConcurrent {
        /// Time (s).
        t: f64,
    },
    /// The static solution of a beam met a singular tangent stiffness.
    #[error("static beam: singular tangent stiffness at increment {step} of {increments}")]
    StaticSingular {
        /// The load increment (1-based).
        step: usize,
        /// Number of increments.
        increments: usize,
    },
    /// Newton's method for the static solution of a beam did not converge.
    #[error(
        "static beam: Newton did not converge at increment {step} of {increments} (residual {residual:.3e} after {iterations} iterations)"
    )]
    StaticNewton {
        /// The load increment (1-based).
        step: usize,
        /// Number of increments.
        increments: usize,
        /// The largest residual left.
        residual: f64,
        /// Iterations made.
        iterations: usize,
    },
    /// A model kind name that no model has.
    #[error("unknown coupling {name:?}: expected \"ked\", \"coupled\" or \"nonlinear\"")]
    UnknownCoupling {
        /// The name given.
        name: String,
    },
    /// A query the model cannot answer: it lacks the capability (docs/architecture.md).
    #[error("the {kind} model {capability}")]
    NoCapability {
        /// The model's kind.
        kind: &'static str,
        /// What it lacks.
        capability: Capability,
    },
    /// The modal mass matrix asked of a coupled model whose sliders are actuated (it is that
    /// of prescribed sliders).
    #[error(
        "the modal mass matrix is that of prescribed sliders; this model's sliders are actuated"
    )]
    ActuatedMassMatrix,
    /// The nonlinear model asked of links without one bending stiffness (tapered or
    /// stepped).
    #[error("the nonlinear model needs uniform links (one bending stiffness)")]
    NonUniformLinks,
    /// Patches, their modal velocity law or a model's patch states that do not fit.
    #[error(transparent)]
    Patch(Box<crate::patches::PatchError>),
}

/// A capability a model may lack ([`DynamicsError::NoCapability`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Capability {
    /// External loads ([`crate::LoadInput`]).
    Loads,
    /// A sampled control law ([`crate::ControlLaws::law_sample`]).
    SampledLaw,
}

impl std::fmt::Display for Capability {
    /// The predicate of the error message: "the ked model takes no external loads (...)".
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Capability::Loads => "takes no external loads (the coupled and nonlinear models do)",
            Capability::SampledLaw => "has no sampled control law",
        })
    }
}
