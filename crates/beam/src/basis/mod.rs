//! Assumed-mode bases `psi_j(xi)`, `xi = x / l in [0, 1]`, for the transverse deflection
//! `w(x, t) = sum_j eta_j(t) psi_j(x / l)` of one link (model.md section 6).
//!
//! Derivatives are with respect to `xi` (dimensionless); the `1/l` factors are applied by
//! [`crate::ModalIntegrals`].

mod classical;
mod hermite;
mod sine;

pub use classical::{ClassicalBasis, EndConditions};
pub use hermite::HermiteBasis;
pub use sine::SineBasis;

/// A set of `r` shape functions on `[0, 1]` with their first and second derivatives.
///
/// Implementations must be cheap to evaluate and allocation-free in [`Basis::eval`];
/// the modal integrals call it `r` times per quadrature node.
///
/// # Implementing
/// A one-function pinned-pinned basis `psi = xi (1 - xi)` (a Rayleigh-Ritz trial function).
/// Its integrals have closed forms, `int psi^2 = 1/30` and `int psi''^2 = 4`, so a uniform
/// link of length `l` gets `M = rhoA l / 30` and `Kf = 4 EI / l^3`, and Rayleigh's quotient
/// `omega^2 = 120 EI / (rhoA l^4)` is `120 / pi^4` times the exact `pi^4 EI / (rhoA l^4)`,
/// an upper bound as Rayleigh's principle requires (Meirovitch, *Fundamentals of
/// Vibrations*, section 8.13):
///
/// ```
/// use flexprr_beam::{Basis, ModalIntegrals, UniformSection};
///
/// struct Parabola;
///
/// impl Basis for Parabola {
///     fn len(&self) -> usize {
///         1
///     }
///     fn eval(&self, _j: usize, xi: f64) -> [f64; 3] {
///         [xi * (1.0 - xi), 1.0 - 2.0 * xi, -2.0]
///     }
///     fn name(&self) -> String {
///         "parabola, r = 1".into()
///     }
///     fn polynomial_degree(&self) -> Option<usize> {
///         Some(2)
///     }
/// }
///
/// let (ei, rho_a, l) = (1.46, 0.1662, 0.2);
/// let section = UniformSection::new(ei, rho_a).unwrap();
/// let integrals = ModalIntegrals::compute(&Parabola, &section, l).unwrap();
/// let (mass, stiffness) = (integrals.mass[(0, 0)], integrals.stiffness[(0, 0)]);
/// assert!((mass - rho_a * l / 30.0).abs() <= 1e-14 * mass);
/// assert!((stiffness - 4.0 * ei / l.powi(3)).abs() <= 1e-12 * stiffness);
/// let ratio = (stiffness / mass) / (std::f64::consts::PI.powi(4) * ei / (rho_a * l.powi(4)));
/// assert!((ratio - 120.0 / std::f64::consts::PI.powi(4)).abs() <= 1e-12);
/// ```
pub trait Basis: Send + Sync {
    /// Number of shape functions `r`.
    fn len(&self) -> usize;

    /// `[psi_j, dpsi_j/dxi, d2psi_j/dxi2]` at `xi` for the 0-based index `j`.
    ///
    /// # Panics
    /// May panic if `j >= self.len()` (a programming error, like slice indexing).
    fn eval(&self, j: usize, xi: f64) -> [f64; 3];

    /// Short human-readable name, e.g. `"sine (pinned-pinned), r = 3"`.
    fn name(&self) -> String;

    /// Polynomial degree of every shape function on each panel between
    /// [`Basis::breakpoints`], if the basis is piecewise polynomial. The modal integrals then
    /// use the Gauss rule that is exact for the integrands; otherwise they refine until the
    /// integrals settle, starting from [`Basis::max_wavenumber`].
    fn polynomial_degree(&self) -> Option<usize> {
        None
    }

    /// Interior knots in `(0, 1)` (finite-element ends) where the second derivative may jump;
    /// quadrature panels are cut there.
    fn breakpoints(&self) -> Vec<f64> {
        vec![]
    }

    /// Largest wavenumber `k` (in `1/xi`) of the shape functions, e.g. `r pi` for sines:
    /// a hint for the initial quadrature order of non-polynomial bases.
    fn max_wavenumber(&self) -> f64 {
        0.0
    }

    /// True if there are no shape functions (never for the bases of this crate).
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Condition at one end of a link.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EndCondition {
    /// `w = 0`, `w'' = 0` (pin: no deflection, no moment).
    Pinned,
    /// `w = 0`, `w' = 0` (built-in end).
    Clamped,
    /// `w'' = 0`, `w''' = 0` (no moment, no shear).
    Free,
}

impl EndCondition {
    /// Lower-case name: `"pinned"`, `"clamped"`, `"free"`.
    pub fn name(self) -> &'static str {
        match self {
            EndCondition::Pinned => "pinned",
            EndCondition::Clamped => "clamped",
            EndCondition::Free => "free",
        }
    }
}

pub(crate) fn check_mode_count(r: usize) -> Result<(), crate::BeamError> {
    if r == 0 || r > 500 {
        return Err(crate::BeamError::InvalidCount {
            name: "modes",
            value: r,
            reason: "must be between 1 and 500",
        });
    }
    Ok(())
}
