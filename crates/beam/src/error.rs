//! The error type of the beam layer.

/// Everything that can go wrong while building a basis, a section, the modal integrals
/// or solving for the frequencies of one link. Each variant says which parameter, mode
/// or matrix entry was involved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BeamError {
    /// A physical or numerical parameter is out of its admissible range (or not finite).
    #[error("invalid {name} = {value}: {reason}")]
    InvalidParameter {
        /// Name of the parameter (e.g. `"length"`, `"youngs_modulus"`).
        name: &'static str,
        /// The value given.
        value: f64,
        /// What the value must satisfy.
        reason: &'static str,
    },
    /// A count (modes, elements, quadrature points) is out of range.
    #[error("invalid {name} = {value}: {reason}")]
    InvalidCount {
        /// Name of the count (e.g. `"modes"`, `"elements"`).
        name: &'static str,
        /// The value given.
        value: usize,
        /// What the value must satisfy.
        reason: &'static str,
    },
    /// Newton's iteration for a Gauss-Legendre node did not converge.
    #[error("Gauss-Legendre node {node} of the {points}-point rule did not converge")]
    QuadratureNode {
        /// Number of points of the rule.
        points: usize,
        /// Index of the node (0-based).
        node: usize,
    },
    /// The root of a characteristic equation was not found in the scanned range.
    #[error("characteristic root of mode {mode} ({ends}) not found below beta = {beta_max}")]
    CharacteristicRoot {
        /// Mode index (1-based, elastic modes).
        mode: usize,
        /// The end conditions, e.g. `"clamped-free"`.
        ends: String,
        /// Upper end of the scanned interval.
        beta_max: f64,
    },
    /// The modal integrals did not settle when the quadrature was refined.
    #[error(
        "modal integral {matrix} did not converge: relative change {change:e} with {points} points per panel"
    )]
    QuadratureNotConverged {
        /// Which integral (`"M"`, `"Kf"`, `"G0"`, ...).
        matrix: &'static str,
        /// Points per panel of the finest rule tried.
        points: usize,
        /// Relative change between the last two refinements.
        change: f64,
    },
    /// A basis function or section property evaluated to a non-finite number.
    #[error("{what} is not finite at xi = {xi} (mode {mode})")]
    NonFinite {
        /// What was evaluated (`"basis function"`, `"bending stiffness"`, ...).
        what: &'static str,
        /// Mode index (0-based), if relevant.
        mode: usize,
        /// Where.
        xi: f64,
    },
    /// The modal mass matrix is not positive definite (Cholesky failed).
    #[error("modal mass matrix ({size}x{size}) is not positive definite")]
    MassNotPositiveDefinite {
        /// Size r of the matrix.
        size: usize,
    },
    /// A matrix or output slice has the wrong size.
    #[error("{what} has size {found}, expected {expected}")]
    DimensionMismatch {
        /// Which argument.
        what: &'static str,
        /// Size expected.
        expected: usize,
        /// Size given.
        found: usize,
    },
    /// A stiffness entry passed to the frequency solver is not finite.
    #[error("stiffness entry ({row}, {col}) is not finite: {value}")]
    NonFiniteStiffness {
        /// Row (0-based).
        row: usize,
        /// Column (0-based).
        col: usize,
        /// The value.
        value: f64,
    },
    /// The symmetric eigenvalue iteration of faer did not converge.
    #[error("symmetric eigenvalue iteration did not converge (size {size})")]
    EigenNoConvergence {
        /// Size r of the problem.
        size: usize,
    },
}
