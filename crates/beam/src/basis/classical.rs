//! Classical Euler-Bernoulli free-vibration modes of a uniform beam for any pair of end
//! conditions (clamped, pinned, free), with the characteristic equation solved numerically.
//!
//! # Numerically stable form
//! The textbook form `cosh(b xi) - cos(b xi) - sigma (sinh(b xi) - sin(b xi))` subtracts
//! numbers of size `e^b` to leave a result of size 1: at `b ~ 60` (mode 20) every digit is
//! lost. Here each mode is written in the equivalent, well-conditioned basis
//!
//! ```text
//! psi(xi) = a e^{b (xi - 1)} + c1 e^{-b xi} + c2 cos(b xi) + c3 sin(b xi),
//! ```
//!
//! whose four functions are all bounded by 1 on `[0, 1]` (the growing exponential is
//! anchored at `xi = 1`, the decaying one at `xi = 0`). The four boundary conditions,
//! divided by `b^k` for the `k`-th derivative, form a 4x4 matrix `B(b)` with entries of
//! order 1; the characteristic equation is `det B(b) = 0`, its roots are bracketed by a
//! scan and refined by bisection to machine precision, and the coefficients are the null
//! vector of `B(b)` (a row of cofactors). See Meirovitch, *Fundamentals of Vibrations*,
//! section 7.6 (Euler-Bernoulli modes) for the textbook characteristic equations
//! (`1 + cos b cosh b = 0` for clamped-free, `tan b = tanh b` for clamped-pinned and
//! pinned-free, `1 - cos b cosh b = 0` for clamped-clamped and free-free).
//!
//! # Rigid-body modes
//! Ends that do not fix the beam (pinned-free, free-pinned, free-free) admit rigid motions
//! (`b = 0`): the rotation about the pin `sqrt(3) xi` for pinned-free (as in the basis of
//! Kang & Mills), `sqrt(3) (1 - xi)` for free-pinned, and `1`, `sqrt(3) (2 xi - 1)` for
//! free-free. They come first and count in `r`.
//!
//! # Normalisation and sign
//! Every function has `int_0^1 psi^2 dxi = 1`. The sign makes the first non-vanishing of
//! `psi(0)`, `psi'(0)`, `psi''(0)` (the largest in `b`-scaled size) positive.

use super::{Basis, EndCondition, check_mode_count};
use crate::BeamError;
use crate::quadrature::GaussLegendre;

/// The end conditions of a link: at `xi = 0` (slider end B) and at `xi = 1` (platform end C).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct EndConditions {
    /// Condition at `xi = 0`.
    pub left: EndCondition,
    /// Condition at `xi = 1`.
    pub right: EndCondition,
}

impl EndConditions {
    /// Pinned at both ends (the paper's link).
    pub const PINNED_PINNED: Self = Self::new(EndCondition::Pinned, EndCondition::Pinned);
    /// Cantilever: clamped at `xi = 0`, free at `xi = 1`.
    pub const CLAMPED_FREE: Self = Self::new(EndCondition::Clamped, EndCondition::Free);
    /// Clamped at both ends.
    pub const CLAMPED_CLAMPED: Self = Self::new(EndCondition::Clamped, EndCondition::Clamped);
    /// Clamped at `xi = 0`, pinned at `xi = 1`.
    pub const CLAMPED_PINNED: Self = Self::new(EndCondition::Clamped, EndCondition::Pinned);
    /// Pinned at `xi = 0`, free at `xi = 1` (with a rigid rotation about the pin).
    pub const PINNED_FREE: Self = Self::new(EndCondition::Pinned, EndCondition::Free);

    /// Both ends.
    pub const fn new(left: EndCondition, right: EndCondition) -> Self {
        Self { left, right }
    }

    /// `"left-right"`, e.g. `"clamped-free"`.
    pub fn name(&self) -> String {
        format!("{}-{}", self.left.name(), self.right.name())
    }

    /// Rigid-body shape functions (degree <= 1) admitted by these ends, normalised to
    /// `int psi^2 = 1`, as `(value at 0, slope)` pairs: `psi = value + slope xi`.
    fn rigid_modes(&self) -> Vec<(f64, f64)> {
        use EndCondition::*;
        let s3 = 3f64.sqrt();
        match (self.left, self.right) {
            (Pinned, Free) => vec![(0.0, s3)],
            (Free, Pinned) => vec![(s3, -s3)],
            (Free, Free) => vec![(1.0, 0.0), (-s3, 2.0 * s3)],
            _ => vec![],
        }
    }
}

/// One function of the basis: rigid (linear) or elastic (exponential/trigonometric form).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Mode {
    Rigid {
        value: f64,
        slope: f64,
    },
    Elastic {
        beta: f64,
        /// Coefficients of `e^{b (xi-1)}`, `e^{-b xi}`, `cos(b xi)`, `sin(b xi)`.
        coefficients: [f64; 4],
    },
}

/// Euler-Bernoulli eigenfunctions of a uniform beam with the given end conditions.
#[derive(Debug, Clone, PartialEq)]
pub struct ClassicalBasis {
    ends: EndConditions,
    modes: Vec<Mode>,
}

impl ClassicalBasis {
    /// The first `r` modes (rigid ones first) for `ends`.
    pub fn new(ends: EndConditions, r: usize) -> Result<Self, BeamError> {
        check_mode_count(r)?;
        let mut modes: Vec<Mode> = ends
            .rigid_modes()
            .into_iter()
            .take(r)
            .map(|(value, slope)| Mode::Rigid { value, slope })
            .collect();
        let elastic = r - modes.len();
        for beta in characteristic_roots(&ends, elastic)? {
            modes.push(Mode::Elastic {
                beta,
                coefficients: mode_coefficients(&ends, beta)?,
            });
        }
        Ok(Self { ends, modes })
    }

    /// Cantilever modes (clamped at `xi = 0`).
    pub fn clamped_free(r: usize) -> Result<Self, BeamError> {
        Self::new(EndConditions::CLAMPED_FREE, r)
    }

    /// Clamped-clamped modes.
    pub fn clamped_clamped(r: usize) -> Result<Self, BeamError> {
        Self::new(EndConditions::CLAMPED_CLAMPED, r)
    }

    /// Clamped (`xi = 0`) - pinned (`xi = 1`) modes.
    pub fn clamped_pinned(r: usize) -> Result<Self, BeamError> {
        Self::new(EndConditions::CLAMPED_PINNED, r)
    }

    /// Pinned (`xi = 0`) - free (`xi = 1`) modes; the first is the rigid rotation `sqrt(3) xi`.
    pub fn pinned_free(r: usize) -> Result<Self, BeamError> {
        Self::new(EndConditions::PINNED_FREE, r)
    }

    /// The end conditions.
    pub fn ends(&self) -> EndConditions {
        self.ends
    }

    /// `beta_j l` of each function (0 for rigid modes): the uniform-beam natural frequency
    /// is `omega_j = beta_j^2 sqrt(EI / (rhoA l^4))`.
    pub fn wavenumbers(&self) -> Vec<f64> {
        self.modes
            .iter()
            .map(|m| match m {
                Mode::Rigid { .. } => 0.0,
                Mode::Elastic { beta, .. } => *beta,
            })
            .collect()
    }

    /// Number of rigid-body functions at the start of the basis.
    pub fn rigid_modes(&self) -> usize {
        self.modes
            .iter()
            .filter(|m| matches!(m, Mode::Rigid { .. }))
            .count()
    }
}

impl Basis for ClassicalBasis {
    fn len(&self) -> usize {
        self.modes.len()
    }

    fn eval(&self, j: usize, xi: f64) -> [f64; 3] {
        match self.modes[j] {
            Mode::Rigid { value, slope } => [value + slope * xi, slope, 0.0],
            Mode::Elastic { beta, coefficients } => elastic_eval(beta, &coefficients, xi),
        }
    }

    fn name(&self) -> String {
        format!("classical ({}), r = {}", self.ends.name(), self.modes.len())
    }

    fn max_wavenumber(&self) -> f64 {
        self.wavenumbers().into_iter().fold(0.0, f64::max)
    }
}

/// `[psi, psi', psi'']` of the stable form (module docs).
fn elastic_eval(beta: f64, c: &[f64; 4], xi: f64) -> [f64; 3] {
    let grow = (beta * (xi - 1.0)).exp();
    let decay = (-beta * xi).exp();
    let (s, co) = (beta * xi).sin_cos();
    let a = c[0] * grow;
    let b = c[1] * decay;
    [
        a + b + c[2] * co + c[3] * s,
        beta * (a - b - c[2] * s + c[3] * co),
        beta * beta * (a + b - c[2] * co - c[3] * s),
    ]
}

/// The two boundary-condition rows (derivatives scaled by `b^-k`) at one end.
fn end_rows(condition: EndCondition, beta: f64, at_right: bool) -> [[f64; 4]; 2] {
    let small = (-beta).exp();
    // e^{b(xi-1)} and e^{-b xi} at this end.
    let (grow, decay) = if at_right { (1.0, small) } else { (small, 1.0) };
    let (s, c) = if at_right { beta.sin_cos() } else { (0.0, 1.0) };
    let value = [grow, decay, c, s];
    let slope = [grow, -decay, -s, c];
    let moment = [grow, decay, -c, -s];
    let shear = [grow, -decay, s, -c];
    match condition {
        EndCondition::Pinned => [value, moment],
        EndCondition::Clamped => [value, slope],
        EndCondition::Free => [moment, shear],
    }
}

fn boundary_matrix(ends: &EndConditions, beta: f64) -> [[f64; 4]; 4] {
    let [r0, r1] = end_rows(ends.left, beta, false);
    let [r2, r3] = end_rows(ends.right, beta, true);
    [r0, r1, r2, r3]
}

fn det3(m: [[f64; 3]; 3]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Minor of the 4x4 matrix without row `skip_row` and column `skip_col`.
fn minor(m: &[[f64; 4]; 4], skip_row: usize, skip_col: usize) -> f64 {
    let mut sub = [[0.0; 3]; 3];
    for (ri, row) in (0..4).filter(|&i| i != skip_row).enumerate() {
        for (ci, col) in (0..4).filter(|&k| k != skip_col).enumerate() {
            sub[ri][ci] = m[row][col];
        }
    }
    det3(sub)
}

fn det4(m: &[[f64; 4]; 4]) -> f64 {
    (0..4)
        .map(|k| {
            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
            sign * m[0][k] * minor(m, 0, k)
        })
        .sum()
}

/// Characteristic function `det B(b)` (entries of order 1, so its roots are well conditioned).
fn characteristic(ends: &EndConditions, beta: f64) -> f64 {
    det4(&boundary_matrix(ends, beta))
}

/// The first `count` positive roots of the characteristic equation, ascending.
fn characteristic_roots(ends: &EndConditions, count: usize) -> Result<Vec<f64>, BeamError> {
    let mut roots = Vec::with_capacity(count);
    // Roots are about pi apart and the smallest (clamped-free) is 1.875; a step of pi/32
    // cannot skip a pair of them. b = 0 (rigid motion) is excluded by starting at 0.5.
    let step = std::f64::consts::PI / 32.0;
    let beta_max = (count as f64 + 3.0) * std::f64::consts::PI + 1.0;
    let mut lo = 0.5;
    let mut f_lo = characteristic(ends, lo);
    while roots.len() < count {
        let hi = lo + step;
        if hi > beta_max {
            return Err(BeamError::CharacteristicRoot {
                mode: roots.len() + 1,
                ends: ends.name(),
                beta_max,
            });
        }
        let f_hi = characteristic(ends, hi);
        if f_lo * f_hi <= 0.0 {
            roots.push(bisect(|b| characteristic(ends, b), lo, hi, f_lo));
        }
        lo = hi;
        f_lo = f_hi;
    }
    Ok(roots)
}

/// Bisection to machine precision on a bracket `[lo, hi]` with `f(lo) = f_lo`.
fn bisect(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64, mut f_lo: f64) -> f64 {
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        let f_mid = f(mid);
        if f_mid.abs() < f64::MIN_POSITIVE {
            return mid;
        }
        if f_lo * f_mid < 0.0 {
            hi = mid;
        } else {
            lo = mid;
            f_lo = f_mid;
        }
    }
    0.5 * (lo + hi)
}

/// Null vector of `B(b)` (largest row of cofactors), normalised and signed (module docs).
fn mode_coefficients(ends: &EndConditions, beta: f64) -> Result<[f64; 4], BeamError> {
    let m = boundary_matrix(ends, beta);
    let mut best = [0.0; 4];
    let mut best_norm = -1.0;
    for row in 0..4 {
        let mut cof = [0.0; 4];
        for (col, c) in cof.iter_mut().enumerate() {
            let sign = if (row + col) % 2 == 0 { 1.0 } else { -1.0 };
            *c = sign * minor(&m, row, col);
        }
        let norm = cof.iter().map(|x| x * x).sum::<f64>();
        if norm > best_norm {
            best_norm = norm;
            best = cof;
        }
    }
    // Normalise int_0^1 psi^2 = 1 with a Gauss rule far finer than the mode's wavelength and
    // its boundary layers (width 1/(2b)).
    let points = ((2.0 * beta).ceil() as usize + 24).min(crate::quadrature::MAX_GAUSS_POINTS);
    let rule = GaussLegendre::new(points)?;
    let norm2 = rule.integrate(0.0, 1.0, |xi| elastic_eval(beta, &best, xi)[0].powi(2));
    if !(norm2.is_finite() && norm2 > 0.0) {
        return Err(BeamError::NonFinite {
            what: "classical mode normalisation",
            mode: 0,
            xi: 0.0,
        });
    }
    let scale = 1.0 / norm2.sqrt();
    let at_zero = elastic_eval(beta, &best, 0.0);
    let scaled = [at_zero[0], at_zero[1] / beta, at_zero[2] / (beta * beta)];
    let dominant = scaled
        .iter()
        .copied()
        .fold(0.0f64, |acc, v| if v.abs() > acc.abs() { v } else { acc });
    let sign = if dominant < 0.0 { -1.0 } else { 1.0 };
    Ok(best.map(|c| c * scale * sign))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pinned_pinned_roots_are_multiples_of_pi() {
        let roots = characteristic_roots(&EndConditions::PINNED_PINNED, 5).unwrap();
        for (k, b) in roots.iter().enumerate() {
            let exact = (k + 1) as f64 * std::f64::consts::PI;
            assert!((b - exact).abs() < 1e-12 * exact, "{b} vs {exact}");
        }
    }
}
