//! Variable-step, variable-order BDF (orders 1 to 5) in backward-difference form, with the
//! NDF variant as an option.
//!
//! # Method
//!
//! The formulation is the quasi-constant-step backward-difference form of Shampine & Reichelt,
//! *The MATLAB ODE Suite*, SIAM J. Sci. Comput. 18(1), 1997, section 2 (the code `ode15s`),
//! also described in Shampine, *Numerical Solution of ODEs*, Chapman & Hall 1994, ch. 5.
//! With the backward differences `D[j] = nabla^j y_n` at the current spacing `h`, a step of
//! order `k` predicts `y_pred = sum_{j=0..k} D[j]` and solves
//!
//! ```text
//! (1 - kappa_k) gamma_k (y - y_pred) + sum_{j=1..k} gamma_j D[j] = h f(t_{n+1}, y),
//! gamma_j = sum_{i=1..j} 1/i
//! ```
//!
//! for the correction `d = y - y_pred` (= `nabla^{k+1} y_{n+1}`), by simplified Newton
//! iterations with the iteration matrix `I - c J`, `c = h / ((1 - kappa_k) gamma_k)`
//! (Shampine & Reichelt 1997, section 2.1). `kappa = 0` is the BDF; the NDF uses the
//! `kappa` of their Table 1. The local error is `(kappa_k gamma_k + 1/(k+1)) d`, and the
//! error estimates of orders `k - 1` and `k + 1` come from `D[k]` and `nabla^{k+2} y_{n+1}`
//! (their section 2.3); the order with the largest admissible step is taken after `k + 1`
//! steps of constant size. A change of step size re-samples the interpolating polynomial on
//! the new spacing (their section 2.1: `D <- (R U)^T D`), which also gives the dense output.
//!
//! # Linear algebra and reuse (after CVODE)
//!
//! The Jacobian `J` comes from [`OdeSystem::jacobian`] when the system has an analytic one,
//! otherwise from [`finite_difference_jacobian`] (the trait's default, run here on
//! preallocated work vectors), and is kept across steps as CVODE does (Hindmarsh et al.,
//! *SUNDIALS*, ACM TOMS 31(3), 2005, the section on CVODE): it is re-evaluated after
//! [`JACOBIAN_MAX_AGE`] accepted steps, when `c` moved by more than
//! [`JACOBIAN_MAX_GAMMA_CHANGE`] since it was evaluated, and after a Newton convergence
//! failure with an old Jacobian. The iteration matrix `I - c J` is
//! re-factored (LU with partial pivoting, faer's `lu_in_place` into preallocated storage)
//! whenever `c` changed, so Newton never runs on a matrix with a wrong `c`. The Newton loop
//! itself allocates nothing.
//!
//! The Newton convergence test is CVODE's: the rate `R` is estimated from successive
//! corrections (`R <- max(0.3 R, |delta_m| / |delta_{m-1}|)`, carried over between steps
//! while the matrix is unchanged) and the iteration stops when
//! `min(1, R) |delta_m| (kappa_k gamma_k + 1/(k+1)) <= 0.1`, i.e. when the iteration error
//! is a tenth of what the error test admits. At most [`NEWTON_MAX_ITERATIONS`] iterations;
//! an iteration whose correction grows by more than 2x is divergent.

// Index loops below mirror the formulas (rows and columns of small coefficient tables).
#![allow(clippy::needless_range_loop)]

use faer::Mat;

use crate::common::{DenseLu, Span};
use crate::{
    IntegratorError, OdeSystem, Options, Stats, Stepper, error_norm, finite_difference_jacobian,
    initial_step,
};

/// Highest BDF order (orders above 5 are not zero-stable).
pub const MAX_ORDER: usize = 5;

/// Accepted steps after which the Jacobian is re-evaluated (CVODE's `MSBJ`).
pub const JACOBIAN_MAX_AGE: usize = 50;

/// Relative change of `c = h / alpha_k` since the last Jacobian that forces a new one.
pub const JACOBIAN_MAX_GAMMA_CHANGE: f64 = 0.3;

/// Newton iterations allowed per attempt (CVODE's `maxcor` is 3).
pub const NEWTON_MAX_ITERATIONS: usize = 4;

/// Consecutive failed attempts (Newton or singular matrix) before giving up.
const MAX_CONSECUTIVE_FAILURES: usize = 10;

/// Step reduction after a Newton failure (CVODE's `ETACF`).
const NEWTON_FAILURE_FACTOR: f64 = 0.25;

/// Safety factor on the predicted step size.
const SAFETY: f64 = 0.9;

/// Bounds of one step-size change.
const MIN_FACTOR: f64 = 0.2;
const MAX_FACTOR: f64 = 10.0;

/// A step increase below this ratio is not worth re-factoring for (as in `ode15s`).
const MIN_INCREASE: f64 = 1.2;

/// Weight of the Newton convergence test relative to the error test (CVODE's `nlscoef`).
const NEWTON_COEFFICIENT: f64 = 0.1;

/// Which member of the family.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BdfVariant {
    /// Backward differentiation formulas (Gear; CVODE, `scipy` `BDF` with `kappa = 0`).
    #[default]
    Bdf,
    /// Klopfenstein-Shampine numerical differentiation formulas (`ode15s` default): the
    /// same cost, a smaller error constant at orders 1-4 (Shampine & Reichelt 1997, Table 1).
    Ndf,
}

impl BdfVariant {
    /// `kappa_k` for `k = 0..=MAX_ORDER + 1` (Shampine & Reichelt 1997, Table 1).
    fn kappa(self) -> [f64; MAX_ORDER + 2] {
        match self {
            BdfVariant::Bdf => [0.0; MAX_ORDER + 2],
            BdfVariant::Ndf => [0.0, -0.1850, -1.0 / 9.0, -0.0823, -0.0415, 0.0, 0.0],
        }
    }
}

/// Variable-step, variable-order BDF/NDF for stiff systems (see the module documentation).
///
/// ```
/// use flexprr_integrators::{Bdf, Integrator, Options};
/// use flexprr_integrators::test_problems::{Robertson, TestProblem};
///
/// let mut p = Robertson::default();
/// let opts = Options::default().rtol(1e-4).atol_per_component(vec![1e-8, 1e-14, 1e-6]);
/// let y0 = p.y0();
/// let sol = Bdf::new(opts).solve(&mut p, 0.0, &y0, &[0.4, 4.0, 40.0]).unwrap();
/// let y = sol.y(0);
/// assert!((y[0] + y[1] + y[2] - 1.0).abs() < 1e-4);
/// ```
#[derive(Debug, Clone)]
pub struct Bdf {
    /// Shared options.
    pub options: Options,
    /// BDF or NDF.
    pub variant: BdfVariant,
    /// Highest order used (1 to [`MAX_ORDER`]).
    pub max_order: usize,
}

impl Bdf {
    /// BDF of orders 1 to 5 with the given options.
    pub fn new(options: Options) -> Self {
        Self {
            options,
            variant: BdfVariant::Bdf,
            max_order: MAX_ORDER,
        }
    }

    /// Chooses BDF or NDF.
    #[must_use]
    pub fn variant(mut self, variant: BdfVariant) -> Self {
        self.variant = variant;
        self
    }

    /// Limits the order (1 to [`MAX_ORDER`]; orders 3-5 are not A-stable, lower orders
    /// suit problems with eigenvalues near the imaginary axis).
    #[must_use]
    pub fn max_order(mut self, max_order: usize) -> Self {
        self.max_order = max_order;
        self
    }
}

/// Coefficients of the formulas of each order, `k = 0..=MAX_ORDER + 1`.
#[derive(Debug, Clone)]
struct Coefficients {
    /// `gamma_k = sum_{i=1..k} 1/i`.
    gamma: [f64; MAX_ORDER + 2],
    /// `alpha_k = (1 - kappa_k) gamma_k`.
    alpha: [f64; MAX_ORDER + 2],
    /// Local error constant `kappa_k gamma_k + 1/(k+1)`.
    error_const: [f64; MAX_ORDER + 2],
}

impl Coefficients {
    fn new(variant: BdfVariant) -> Self {
        let kappa = variant.kappa();
        let mut gamma = [0.0; MAX_ORDER + 2];
        let mut alpha = [0.0; MAX_ORDER + 2];
        let mut error_const = [0.0; MAX_ORDER + 2];
        for k in 0..MAX_ORDER + 2 {
            if k > 0 {
                gamma[k] = gamma[k - 1] + 1.0 / k as f64;
            }
            alpha[k] = (1.0 - kappa[k]) * gamma[k];
            error_const[k] = kappa[k] * gamma[k] + 1.0 / (k as f64 + 1.0);
        }
        Self {
            gamma,
            alpha,
            error_const,
        }
    }
}

/// Why one attempt at a step failed.
#[derive(Debug)]
enum AttemptFailure {
    /// Newton did not converge; `non_finite` names a component if the rhs was NaN/inf.
    Newton { non_finite: Option<usize> },
    /// `I - c J` had a zero (or non-finite) pivot.
    Singular,
    /// The Jacobian has a non-finite entry in this row.
    NonFiniteJacobian { row: usize },
}

/// The state of one BDF integration.
pub struct BdfStepper {
    options: Options,
    coefficients: Coefficients,
    max_order: usize,
    dim: usize,
    /// Where the stepper is, where it ends, its statistics (shared by every stepper).
    span: Span,
    direction: f64,
    /// Signed spacing of the difference table.
    h: f64,
    /// Step size magnitude wanted for the next step.
    h_next: f64,
    /// Order of the next step.
    order: usize,
    /// Order of the last accepted step (the dense output polynomial's degree).
    dense_order: usize,
    /// Accepted steps since the last change of step size or order.
    n_equal_steps: usize,
    /// Backward differences, `MAX_ORDER + 3` rows of `dim`.
    differences: Vec<f64>,
    /// Scratch rows for re-sampling the difference table.
    differences_scratch: Vec<f64>,
    y: Vec<f64>,
    y_new: Vec<f64>,
    y_predicted: Vec<f64>,
    psi: Vec<f64>,
    correction: Vec<f64>,
    f: Vec<f64>,
    delta: Vec<f64>,
    weights: Vec<f64>,
    error: Vec<f64>,
    jacobian: Mat<f64>,
    /// `f(t_n, y_n)` and work space for differenced Jacobians.
    jacobian_f0: Vec<f64>,
    jacobian_work: Vec<f64>,
    lu: DenseLu,
    /// `c` of the current factorization, if any.
    lu_c: Option<f64>,
    /// `c` when the Jacobian was evaluated, if ever.
    jacobian_c: Option<f64>,
    /// The Jacobian was evaluated at the current accepted point.
    jacobian_current: bool,
    steps_since_jacobian: usize,
    /// Newton rate estimate carried between steps while the matrix is unchanged.
    newton_rate: f64,
}

impl std::fmt::Debug for BdfStepper {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BdfStepper")
            .field("t", &self.span.t)
            .field("h", &self.h)
            .field("order", &self.order)
            .field("stats", &self.span.stats)
            .finish_non_exhaustive()
    }
}

/// First non-finite entry of `v`.
fn first_non_finite(v: &[f64]) -> Option<usize> {
    v.iter().position(|x| !x.is_finite())
}

/// The matrix `R(order, factor)` of Shampine & Reichelt (1997), section 2.1:
/// `R[i][j] = prod_{m=1..i} (m - 1 - factor j) / m`, `i, j = 0..=order`.
fn resampling_matrix(order: usize, factor: f64) -> [[f64; MAX_ORDER + 1]; MAX_ORDER + 1] {
    let mut r = [[0.0; MAX_ORDER + 1]; MAX_ORDER + 1];
    for j in 0..=order {
        r[0][j] = 1.0;
        for i in 1..=order {
            r[i][j] = r[i - 1][j] * (i as f64 - 1.0 - factor * j as f64) / i as f64;
        }
    }
    r
}

impl BdfStepper {
    /// Row `j` of the difference table.
    #[inline]
    fn diff(&self, j: usize) -> &[f64] {
        &self.differences[j * self.dim..(j + 1) * self.dim]
    }

    /// Re-samples the difference table of order `order` from spacing `h` to `factor h`
    /// (Shampine & Reichelt 1997, section 2.1): `D[0..=k] <- (R(k, factor) U(k))^T D[0..=k]`
    /// with `U(k) = R(k, 1)`. The interpolating polynomial is unchanged.
    fn rescale_differences(&mut self, order: usize, factor: f64) {
        let r = resampling_matrix(order, factor);
        let u = resampling_matrix(order, 1.0);
        let mut ru = [[0.0; MAX_ORDER + 1]; MAX_ORDER + 1];
        for i in 0..=order {
            for j in 0..=order {
                ru[i][j] = (0..=order).map(|m| r[i][m] * u[m][j]).sum();
            }
        }
        let n = self.dim;
        let rows = (order + 1) * n;
        self.differences_scratch[..rows].copy_from_slice(&self.differences[..rows]);
        for i in 0..=order {
            let row = &mut self.differences[i * n..(i + 1) * n];
            row.fill(0.0);
            for j in 0..=order {
                let w = ru[j][i];
                let src = &self.differences_scratch[j * n..(j + 1) * n];
                for (a, b) in row.iter_mut().zip(src) {
                    *a += w * b;
                }
            }
        }
    }

    /// Evaluates the Jacobian at the current accepted point.
    fn evaluate_jacobian<S: OdeSystem + ?Sized>(
        &mut self,
        system: &mut S,
        c: f64,
    ) -> Result<(), AttemptFailure> {
        if system.has_analytic_jacobian() {
            system.jacobian(self.span.t, &self.y, self.jacobian.as_mut());
            self.span.stats.rhs_evaluations += system.jacobian_rhs_evaluations();
        } else {
            // The trait's provided Jacobian is these same forward differences but allocates
            // its work vectors; with ours preallocated the step stays allocation-free.
            system.rhs(self.span.t, &self.y, &mut self.jacobian_f0);
            finite_difference_jacobian(
                system,
                self.span.t,
                &self.y,
                &self.jacobian_f0,
                self.jacobian.as_mut(),
                &mut self.jacobian_work,
            );
            self.span.stats.rhs_evaluations += self.dim + 1;
        }
        self.span.stats.jacobian_evaluations += 1;
        self.jacobian_c = Some(c);
        self.jacobian_current = true;
        self.steps_since_jacobian = 0;
        let n = self.dim;
        for j in 0..n {
            for i in 0..n {
                if !self.jacobian[(i, j)].is_finite() {
                    return Err(AttemptFailure::NonFiniteJacobian { row: i });
                }
            }
        }
        Ok(())
    }

    /// Forms and factors `I - c J` into the preallocated LU storage.
    fn factor(&mut self, c: f64) -> Result<(), AttemptFailure> {
        let n = self.dim;
        self.span.stats.lu_decompositions += 1;
        for j in 0..n {
            for i in 0..n {
                let identity = if i == j { 1.0 } else { 0.0 };
                self.lu.matrix[(i, j)] = identity - c * self.jacobian[(i, j)];
            }
        }
        self.newton_rate = 1.0;
        if !self.lu.factor() {
            self.lu_c = None;
            return Err(AttemptFailure::Singular);
        }
        self.lu_c = Some(c);
        Ok(())
    }

    /// Solves `(I - c J) x = delta` in place with the current factorization.
    fn solve_in_place(&mut self) {
        self.lu.solve_in_place(&mut self.delta);
    }

    /// Weighted RMS norm of `v` with the Newton weights.
    fn weighted_norm(&self, v: &[f64]) -> f64 {
        let sum: f64 = v
            .iter()
            .zip(&self.weights)
            .map(|(x, w)| (x / w) * (x / w))
            .sum();
        (sum / self.dim as f64).sqrt()
    }

    /// Simplified Newton iterations for the correction of a step to `t_new` with `c`;
    /// `y_new` and `correction` hold the result. Allocation-free.
    fn newton<S: OdeSystem + ?Sized>(
        &mut self,
        system: &mut S,
        t_new: f64,
        c: f64,
        error_const: f64,
    ) -> Result<(), AttemptFailure> {
        self.y_new.copy_from_slice(&self.y_predicted);
        self.correction.fill(0.0);
        let tolerance = NEWTON_COEFFICIENT / error_const;
        let mut previous_norm = f64::INFINITY;
        for m in 0..NEWTON_MAX_ITERATIONS {
            system.rhs(t_new, &self.y_new, &mut self.f);
            self.span.stats.rhs_evaluations += 1;
            self.span.stats.newton_iterations += 1;
            if let Some(i) = first_non_finite(&self.f) {
                return Err(AttemptFailure::Newton {
                    non_finite: Some(i),
                });
            }
            for i in 0..self.dim {
                self.delta[i] = c * self.f[i] - self.psi[i] - self.correction[i];
            }
            self.solve_in_place();
            let norm = self.weighted_norm(&self.delta);
            if !norm.is_finite() {
                return Err(AttemptFailure::Newton { non_finite: None });
            }
            if m > 0 {
                if norm > 2.0 * previous_norm {
                    return Err(AttemptFailure::Newton { non_finite: None });
                }
                self.newton_rate = (0.3 * self.newton_rate).max(norm / previous_norm);
            }
            for i in 0..self.dim {
                self.y_new[i] += self.delta[i];
                self.correction[i] += self.delta[i];
            }
            if norm * self.newton_rate.min(1.0) <= tolerance {
                return Ok(());
            }
            previous_norm = norm;
        }
        Err(AttemptFailure::Newton { non_finite: None })
    }

    /// One attempt with the current spacing `h` and order: predict, set up the matrix if
    /// needed, iterate. On success `y_new`, `correction` hold the corrected step.
    fn attempt<S: OdeSystem + ?Sized>(
        &mut self,
        system: &mut S,
        t_new: f64,
    ) -> Result<(), AttemptFailure> {
        let n = self.dim;
        let k = self.order;
        let alpha = self.coefficients.alpha[k];
        // Predictor y_pred = sum_{j<=k} D[j]; psi = sum_{1<=j<=k} gamma_j D[j] / alpha_k.
        self.y_predicted.copy_from_slice(&self.differences[..n]);
        self.psi.fill(0.0);
        for j in 1..=k {
            let g = self.coefficients.gamma[j] / alpha;
            let row = &self.differences[j * n..(j + 1) * n];
            for i in 0..n {
                self.y_predicted[i] += row[i];
                self.psi[i] += g * row[i];
            }
        }
        for i in 0..n {
            self.weights[i] =
                self.options.atol.get(i) + self.options.rtol * self.y_predicted[i].abs();
        }
        let c = self.h / alpha;
        let c_changed = self
            .lu_c
            .is_none_or(|lc| (c - lc).abs() > 4.0 * f64::EPSILON * c.abs());
        if c_changed {
            let jacobian_stale = match self.jacobian_c {
                None => true,
                Some(jc) => {
                    self.steps_since_jacobian >= JACOBIAN_MAX_AGE
                        || (c / jc - 1.0).abs() > JACOBIAN_MAX_GAMMA_CHANGE
                }
            };
            if jacobian_stale && !self.jacobian_current {
                self.evaluate_jacobian(system, c)?;
            }
            self.factor(c)?;
        }
        self.newton(system, t_new, c, self.coefficients.error_const[k])
    }

    /// After an accepted step of order `k`: choose the next order and step size
    /// (Shampine & Reichelt 1997, section 2.3). Returns `(order, factor)`.
    fn select_order(&mut self, k: usize, error: f64) -> (usize, f64) {
        let n = self.dim;
        let ec = self.coefficients.error_const;
        let norm_of_row = |stepper: &mut Self, row: usize, coefficient: f64| {
            for i in 0..n {
                stepper.error[i] = coefficient * stepper.differences[row * n + i];
            }
            error_norm(&stepper.error, &stepper.y, &stepper.y, &stepper.options)
        };
        let error_lower = if k > 1 {
            norm_of_row(self, k, ec[k - 1])
        } else {
            f64::INFINITY
        };
        let error_higher = if k < self.max_order {
            norm_of_row(self, k + 2, ec[k + 1])
        } else {
            f64::INFINITY
        };
        let factor_of = |e: f64, q: usize| {
            if e > 0.0 {
                e.powf(-1.0 / (q as f64 + 1.0))
            } else {
                MAX_FACTOR
            }
        };
        let candidates = [
            (k.saturating_sub(1), factor_of(error_lower, k - 1)),
            (k, factor_of(error, k)),
            (k + 1, factor_of(error_higher, k + 1)),
        ];
        let mut best = candidates[1];
        for cand in [candidates[0], candidates[2]] {
            if cand.0 >= 1 && cand.0 <= self.max_order && cand.1 > best.1 {
                best = cand;
            }
        }
        (best.0, (SAFETY * best.1).min(MAX_FACTOR))
    }
}

impl Stepper for BdfStepper {
    fn t(&self) -> f64 {
        self.span.t
    }

    fn y(&self) -> &[f64] {
        &self.y
    }

    fn t_previous(&self) -> f64 {
        self.span.t_previous
    }

    fn step<S: OdeSystem + ?Sized>(&mut self, system: &mut S) -> Result<(), IntegratorError> {
        self.span.check_open()?;
        let mut h_abs = self.h_next.min(self.options.max_step);
        let mut failures = 0usize;
        let mut error_failures = 0usize;
        let mut last_non_finite: Option<usize> = None;
        loop {
            self.span.check_budget(self.options.max_steps)?;
            self.span
                .check_step_size(h_abs * self.direction, last_non_finite)?;
            // Land exactly on t_end; avoid a sliver of a last step.
            let remaining = (self.span.t_end - self.span.t).abs();
            let last = h_abs >= remaining * (1.0 - 1e-10);
            if last {
                h_abs = remaining;
            }
            let t_new = if last {
                self.span.t_end
            } else {
                self.span.t + self.direction * h_abs
            };
            let h = self.direction * h_abs;
            if (h - self.h).abs() > 4.0 * f64::EPSILON * h_abs {
                let factor = h_abs / self.h.abs();
                self.rescale_differences(self.order, factor);
                self.h = h;
                self.n_equal_steps = 0;
            }
            match self.attempt(system, t_new) {
                Ok(()) => {}
                Err(AttemptFailure::NonFiniteJacobian { row }) => {
                    return Err(IntegratorError::NonFinite {
                        t: self.span.t,
                        component: row,
                    });
                }
                Err(failure) => {
                    self.span.stats.rejected_steps += 1;
                    failures += 1;
                    let singular = matches!(failure, AttemptFailure::Singular);
                    if let AttemptFailure::Newton { non_finite } = failure {
                        last_non_finite = non_finite;
                    }
                    if failures >= MAX_CONSECUTIVE_FAILURES {
                        return Err(if singular {
                            IntegratorError::SingularMatrix { t: self.span.t }
                        } else if let Some(component) = last_non_finite {
                            IntegratorError::NonFinite {
                                t: t_new,
                                component,
                            }
                        } else {
                            IntegratorError::NewtonFailure {
                                t: self.span.t,
                                h: self.h,
                            }
                        });
                    }
                    if !singular && !self.jacobian_current && last_non_finite.is_none() {
                        // Retry the same step with a fresh Jacobian (CVODE's recovery).
                        let c = self.h / self.coefficients.alpha[self.order];
                        if let Err(AttemptFailure::NonFiniteJacobian { row }) =
                            self.evaluate_jacobian(system, c)
                        {
                            return Err(IntegratorError::NonFinite {
                                t: self.span.t,
                                component: row,
                            });
                        }
                        self.lu_c = None;
                    } else {
                        h_abs *= NEWTON_FAILURE_FACTOR;
                    }
                    continue;
                }
            }
            // Error test on the local error estimate error_const_k * d.
            let k = self.order;
            let ec = self.coefficients.error_const[k];
            for i in 0..self.dim {
                self.error[i] = ec * self.correction[i];
            }
            let error = error_norm(&self.error, &self.y, &self.y_new, &self.options);
            if error.is_nan() || error > 1.0 {
                self.span.stats.rejected_steps += 1;
                error_failures += 1;
                let factor = if error.is_finite() {
                    (SAFETY * error.powf(-1.0 / (k as f64 + 1.0))).max(MIN_FACTOR)
                } else {
                    MIN_FACTOR
                };
                h_abs *= factor;
                continue;
            }
            if let Some(component) = first_non_finite(&self.y_new) {
                return Err(IntegratorError::NonFinite {
                    t: t_new,
                    component,
                });
            }
            // Accept: D[k+2] = d - D[k+1], D[k+1] = d, D[i] += D[i+1] for i = k..0.
            let n = self.dim;
            {
                let (head, tail) = self.differences.split_at_mut((k + 2) * n);
                let row_k2 = &mut tail[..n];
                let row_k1 = &mut head[(k + 1) * n..(k + 2) * n];
                for i in 0..n {
                    row_k2[i] = self.correction[i] - row_k1[i];
                    row_k1[i] = self.correction[i];
                }
            }
            for j in (0..=k).rev() {
                let (head, tail) = self.differences.split_at_mut((j + 1) * n);
                let row = &mut head[j * n..];
                for i in 0..n {
                    row[i] += tail[i];
                }
            }
            self.y.copy_from_slice(&self.differences[..n]);
            self.span.advance(t_new, false);
            self.dense_order = k;
            self.n_equal_steps += 1;
            self.span.stats.accepted_steps += 1;
            self.span.stats.record_order(k);
            self.steps_since_jacobian += 1;
            self.jacobian_current = false;
            if last {
                self.span.finished = true;
                return Ok(());
            }
            // Next step size and order.
            self.h_next = h_abs;
            if error_failures > 0 || failures > 0 {
                // No increase right after a failure.
                return Ok(());
            }
            if self.n_equal_steps > k {
                let (order, factor) = self.select_order(k, error);
                if order != k || !(1.0..MIN_INCREASE).contains(&factor) {
                    self.order = order;
                    self.h_next = h_abs * factor;
                    if order != k {
                        self.n_equal_steps = 0;
                    }
                }
            }
            return Ok(());
        }
    }

    fn interpolate(&self, t: f64, out: &mut [f64]) {
        // y(t) = sum_j D[j] prod_{m<j} (x + m) / (m + 1), x = (t - t_n) / h: the Newton
        // backward-difference form of the interpolating polynomial.
        let x = (t - self.span.t) / self.h;
        out.copy_from_slice(self.diff(0));
        let mut p = 1.0;
        for j in 1..=self.dense_order {
            p *= (x + (j - 1) as f64) / j as f64;
            for (o, d) in out.iter_mut().zip(self.diff(j)) {
                *o += p * d;
            }
        }
    }

    fn stats(&self) -> &Stats {
        &self.span.stats
    }
}

impl crate::Integrator for Bdf {
    type Stepper = BdfStepper;

    fn name(&self) -> &'static str {
        "bdf"
    }

    fn options(&self) -> &Options {
        &self.options
    }

    fn start<S: OdeSystem + ?Sized>(
        &self,
        system: &mut S,
        t0: f64,
        y0: &[f64],
        t_end: f64,
    ) -> Result<BdfStepper, IntegratorError> {
        let n = system.dim();
        crate::common::validate_start(&self.options, n, y0, t0, t_end)?;
        let options = self.options.for_system(&*system);
        if !(1..=MAX_ORDER).contains(&self.max_order) {
            return Err(IntegratorError::InvalidOptions(format!(
                "BDF max_order must be between 1 and {MAX_ORDER}, got {}",
                self.max_order
            )));
        }
        // Sized up front so that recording an order never allocates inside `step`.
        let mut stats = Stats {
            orders: vec![0; MAX_ORDER + 1],
            ..Stats::default()
        };
        let direction = (t_end - t0).signum();
        let mut f0 = vec![0.0; n];
        system.rhs(t0, y0, &mut f0);
        stats.rhs_evaluations += 1;
        if let Some(component) = first_non_finite(&f0) {
            return Err(IntegratorError::NonFinite { t: t0, component });
        }
        let span = (t_end - t0).abs();
        let h_max = options.max_step.min(span);
        let h0 = match options.initial_step {
            Some(h) => h.min(h_max),
            None => {
                let mut work = vec![0.0; 2 * n];
                stats.rhs_evaluations += 1;
                initial_step(
                    system, t0, y0, &f0, 1, direction, h_max, &options, &mut work,
                )
            }
        };
        let h = direction * h0;
        let mut differences = vec![0.0; (MAX_ORDER + 3) * n];
        differences[..n].copy_from_slice(y0);
        for i in 0..n {
            differences[n + i] = h * f0[i];
        }
        Ok(BdfStepper {
            options: options.clone(),
            coefficients: Coefficients::new(self.variant),
            max_order: self.max_order,
            dim: n,
            span: Span::new(t0, t_end, stats),
            direction,
            h,
            h_next: h0,
            order: 1,
            dense_order: 1,
            n_equal_steps: 0,
            differences,
            differences_scratch: vec![0.0; (MAX_ORDER + 1) * n],
            y: y0.to_vec(),
            y_new: vec![0.0; n],
            y_predicted: vec![0.0; n],
            psi: vec![0.0; n],
            correction: vec![0.0; n],
            f: vec![0.0; n],
            delta: vec![0.0; n],
            weights: vec![0.0; n],
            error: vec![0.0; n],
            jacobian: Mat::zeros(n, n),
            jacobian_f0: vec![0.0; n],
            jacobian_work: vec![0.0; 2 * n],
            lu: DenseLu::new(n),
            lu_c: None,
            jacobian_c: None,
            jacobian_current: false,
            steps_since_jacobian: 0,
            newton_rate: 1.0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Integrator;

    /// Re-sampling keeps the interpolating polynomial: differences of `y = t^3` taken at
    /// spacing 0.1 and re-sampled to 0.25 equal the differences taken at 0.25 directly.
    #[test]
    fn resampling_preserves_the_polynomial() {
        let cubic = |t: f64| t * t * t - 2.0 * t + 0.5;
        let backward = |h: f64| {
            let values: Vec<f64> = (0..4).map(|m| cubic(1.0 - m as f64 * h)).collect();
            // nabla^j at t = 1 by repeated differencing.
            let mut table = vec![values.clone()];
            for j in 1..4 {
                let prev = &table[j - 1];
                table.push((0..4 - j).map(|m| prev[m] - prev[m + 1]).collect());
            }
            table.iter().map(|row| row[0]).collect::<Vec<f64>>()
        };
        let mut stepper = Bdf::new(Options::default())
            .start(&mut Decay, 0.0, &[1.0], 1.0)
            .unwrap();
        let d01 = backward(0.1);
        stepper.differences[..4].copy_from_slice(&d01);
        stepper.rescale_differences(3, 2.5);
        let d025 = backward(0.25);
        for j in 0..4 {
            assert!((stepper.differences[j] - d025[j]).abs() < 1e-12, "row {j}");
        }
    }

    struct Decay;
    impl OdeSystem for Decay {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
            dy[0] = -y[0];
        }
    }

    /// The BDF error constants are `1/(k+1)` and the NDF ones match Shampine & Reichelt's
    /// Table 1 (`-0.185 + 1/2 = 0.315`, ...).
    #[test]
    fn error_constants() {
        let bdf = Coefficients::new(BdfVariant::Bdf);
        for k in 1..=MAX_ORDER {
            assert!((bdf.error_const[k] - 1.0 / (k as f64 + 1.0)).abs() < 1e-15);
            assert!((bdf.alpha[k] - bdf.gamma[k]).abs() < 1e-15);
        }
        let ndf = Coefficients::new(BdfVariant::Ndf);
        assert!((ndf.error_const[1] - 0.315).abs() < 1e-12);
        assert!((ndf.gamma[3] - 11.0 / 6.0).abs() < 1e-15);
    }

    /// A singular iteration matrix is detected at factorization time, not as NaNs later.
    #[test]
    fn singular_iteration_matrix_is_detected() {
        let mut stepper = Bdf::new(Options::default())
            .start(&mut Decay, 0.0, &[1.0], 1.0)
            .unwrap();
        // J = 2 makes I - c J singular at c = 0.5.
        stepper.jacobian[(0, 0)] = 2.0;
        assert!(matches!(stepper.factor(0.5), Err(AttemptFailure::Singular)));
        assert!(stepper.factor(0.25).is_ok());
        stepper.delta[0] = 1.0;
        stepper.solve_in_place();
        assert!((stepper.delta[0] - 2.0).abs() < 1e-15);
    }

    /// The LU solve agrees with the matrix on a 3x3 system with pivoting.
    #[test]
    fn lu_solve_matches_matrix_product() {
        struct Three;
        impl OdeSystem for Three {
            fn dim(&self) -> usize {
                3
            }
            fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
                dy.copy_from_slice(y);
            }
        }
        let mut stepper = Bdf::new(Options::default())
            .start(&mut Three, 0.0, &[1.0, 2.0, 3.0], 1.0)
            .unwrap();
        let j = [[0.0, 4.0, -1.0], [2.0, 1.0, 0.5], [-3.0, 0.2, 7.0]];
        for r in 0..3 {
            for c in 0..3 {
                stepper.jacobian[(r, c)] = j[r][c];
            }
        }
        let c = 0.7;
        stepper.factor(c).unwrap();
        let b = [1.0, -2.0, 0.5];
        stepper.delta.copy_from_slice(&b);
        stepper.solve_in_place();
        for r in 0..3 {
            let mut row = stepper.delta[r];
            for col in 0..3 {
                row -= c * j[r][col] * stepper.delta[col];
            }
            assert!((row - b[r]).abs() < 1e-13, "row {r}: {row} vs {}", b[r]);
        }
    }
}
