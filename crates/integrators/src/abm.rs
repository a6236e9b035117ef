//! Variable-step, variable-order Adams-Bashforth-Moulton PECE with local extrapolation,
//! orders 1 to 12, after Shampine & Gordon's code STEP.
//!
//! Sources:
//!
//! * L. F. Shampine & M. K. Gordon, *Computer Solution of Ordinary Differential Equations:
//!   the Initial Value Problem*, Freeman, 1975, chapters 4-6 (modified divided differences,
//!   the coefficients `psi`, `alpha`, `beta`, `sigma`, `g`, the error estimates at orders
//!   `k - 2 .. k + 1`, order and step selection, the start phase) and chapter 7 (STEP,
//!   INTRP and the driver DE).
//! * The SLATEC/DEPAC documentation of `DEABM`/`DSTEPS`/`DINTP` (Shampine & Watts), which
//!   uses the same algorithm.
//! * L. F. Shampine & M. W. Reichelt, "The MATLAB ODE suite", *SIAM J. Sci. Comput.* 18
//!   (1997): `ode113` is this algorithm (with an infinity norm and MATLAB's tolerances).
//!
//! What differs from STEP, and why, is listed in the crate docs (`docs/integrators/abm.md`):
//! the error norm is the crate's weighted RMS norm (accept when `<= 1`), the `g` coefficients
//! are recomputed from the `alpha` directly instead of through STEP's `v`/`w` work arrays
//! (same values, `O(k^2)` flops, no bookkeeping across rejected steps), propagated round-off
//! control is always on, the first step size comes from the crate's [`crate::initial_step`],
//! and a non-finite predicted derivative is treated as a failed step.

// The recurrences are written with the book's 1-based indices; iterator chains would hide
// which difference or coefficient is meant.
#![allow(clippy::needless_range_loop)]

use crate::common::{Span, step_floor};
use crate::{Integrator, IntegratorError, OdeSystem, Options, Stats, Stepper, initial_step};

/// Highest order of the Adams formulas (the corrector with local extrapolation has order
/// `k + 1`, so up to 13 as in `ode113`).
pub const MAX_ORDER: usize = 12;

/// Number of modified divided differences stored (`phi_1 .. phi_{k+2}` for `k <= 12`).
const N_DIFF: usize = MAX_ORDER + 2;

/// Length of the fixed coefficient arrays (1-based, as in the book, index 0 unused).
const N_COEF: usize = MAX_ORDER + 3;

/// Consecutive steps at order `<= 4` after which the problem is reported stiff (the driver
/// DE of Shampine & Gordon, section 7.3, flags `IFLAG = 4` after 50 such steps).
const STIFF_LOW_ORDER_STEPS: usize = 50;

/// The error constants `|gamma*_j|` of the Adams-Moulton formulas, `j = 0 .. 13`
/// (`GSTR` in STEP, where they are rounded to three digits).
///
/// They satisfy `sum_{i=0}^{j} gamma*_i / (j + 1 - i) = 0` for `j >= 1`, `gamma*_0 = 1`
/// (Hairer, Norsett & Wanner I, III.1, eq. 1.14 with the generating function
/// `-t / ((1 - t) log(1 - t))`), so `gamma*_1 = -1/2`, `gamma*_2 = -1/12`, `gamma*_3 = -1/24`.
const ADAMS_MOULTON_ERROR_CONSTANTS: [f64; N_DIFF] = adams_moulton_error_constants();

const fn adams_moulton_error_constants() -> [f64; N_DIFF] {
    let mut gamma = [0.0; N_DIFF];
    gamma[0] = 1.0;
    let mut j = 1;
    while j < N_DIFF {
        let mut sum = 0.0;
        let mut i = 0;
        while i < j {
            sum += gamma[i] / (j + 1 - i) as f64;
            i += 1;
        }
        gamma[j] = -sum;
        j += 1;
    }
    let mut j = 0;
    while j < N_DIFF {
        if gamma[j] < 0.0 {
            gamma[j] = -gamma[j];
        }
        j += 1;
    }
    gamma
}

/// Variable-step, variable-order Adams-Bashforth-Moulton PECE in modified divided
/// differences, orders 1 to 12 with local extrapolation (Shampine & Gordon 1975, the code
/// DE/STEP; the algorithm of MATLAB's `ode113`).
///
/// Each step predicts with the Adams-Bashforth formula of order `k`, evaluates, corrects
/// with the Adams-Moulton formula of order `k + 1` (local extrapolation: the error is
/// estimated for order `k` but the more accurate value is kept), and evaluates again: two
/// right-hand-side evaluations per step whatever the order. The order is chosen from error
/// estimates at orders `k - 2, k - 1, k, k + 1`; in the start phase the order is raised and
/// the step doubled after every step until the first failure or the first sign that a lower
/// order would do better.
///
/// Best on smooth non-stiff problems at tight tolerances and when the right-hand side is
/// expensive. On stiff problems the step size is limited by stability; the code then runs at
/// low orders and [`Stats::stiffness_detected_at`] is set (DE's test: 50 steps in a row at
/// order 4 or less), but it keeps integrating.
#[derive(Debug, Clone)]
pub struct Abm {
    /// Shared options.
    pub options: Options,
    /// Highest order allowed, `1 ..= 12` (default 12).
    pub max_order: usize,
}

impl Abm {
    /// An Adams integrator with the given options and the full order range 1 to 12.
    pub fn new(options: Options) -> Self {
        Self {
            options,
            max_order: MAX_ORDER,
        }
    }

    /// Limits the order (`1 ..= 12`; checked when the integration starts).
    #[must_use]
    pub fn max_order(mut self, max_order: usize) -> Self {
        self.max_order = max_order;
        self
    }
}

impl Default for Abm {
    fn default() -> Self {
        Self::new(Options::default())
    }
}

/// Coefficients of the variable-step Adams formulas in modified divided differences
/// (Shampine & Gordon 1975, ch. 5; 1-based as in the book: index 0 unused).
///
/// With `h_j` the step ending at `x_j`: `psi_i(n+1) = h_{n+1} + ... + h_{n+2-i}`,
/// `alpha_i = h_{n+1} / psi_i(n+1)`,
/// `beta_i = prod_{j<i} psi_j(n+1) / psi_j(n)`,
/// `sigma_{i+1} = i alpha_i sigma_i`, and `g_i` the integration coefficients of the
/// predictor `p = y_n + h sum_{i<=k} g_i phi*_i(n)`.
#[derive(Debug, Clone)]
struct Coefficients {
    psi: [f64; N_COEF],
    alpha: [f64; N_COEF],
    beta: [f64; N_COEF],
    sigma: [f64; N_COEF],
    g: [f64; N_COEF],
}

impl Coefficients {
    fn new() -> Self {
        let mut c = Self {
            psi: [0.0; N_COEF],
            alpha: [0.0; N_COEF],
            beta: [0.0; N_COEF],
            sigma: [0.0; N_COEF],
            g: [0.0; N_COEF],
        };
        c.g[1] = 1.0;
        c.g[2] = 0.5;
        c.sigma[1] = 1.0;
        c
    }

    /// Updates the coefficients for a step of size `h` at order `k` when `ns` steps
    /// (including this one) have been taken with size `h` (STEP, block 1).
    ///
    /// For `i < ns` the values are the constant-step ones (`alpha_i = 1/i`, `beta_i = 1`,
    /// `sigma_{i+1} = 1`, `psi_i = i h`); only indices `>= ns` change. The `g_i` follow from
    /// the `alpha` by the triangular recursion of Shampine & Gordon (eq. 5.18):
    /// `c_{1,q} = 1/q`, `c_{i,q} = c_{i-1,q} - alpha_{i-1} c_{i-1,q+1}`, `g_i = c_{i,1}`.
    fn update(&mut self, h: f64, k: usize, ns: usize) {
        for i in 1..ns {
            self.alpha[i] = 1.0 / i as f64;
            self.beta[i] = 1.0;
            self.sigma[i + 1] = 1.0;
        }
        self.beta[ns] = 1.0;
        self.alpha[ns] = 1.0 / ns as f64;
        self.sigma[ns + 1] = 1.0;
        let mut psi_new = h * ns as f64;
        for i in ns + 1..=k {
            let psi_old = self.psi[i - 1];
            self.psi[i - 1] = psi_new;
            self.beta[i] = self.beta[i - 1] * psi_new / psi_old;
            psi_new = psi_old + h;
            self.alpha[i] = h / psi_new;
            self.sigma[i + 1] = i as f64 * self.alpha[i] * self.sigma[i];
        }
        self.psi[k] = psi_new;

        let mut c = [0.0; N_COEF + 1];
        for (q, cq) in c.iter_mut().enumerate().take(k + 2).skip(1) {
            *cq = 1.0 / q as f64;
        }
        self.g[1] = 1.0;
        for i in 2..=k + 1 {
            let a = self.alpha[i - 1];
            for q in 1..=k + 2 - i {
                c[q] -= a * c[q + 1];
            }
            self.g[i] = c[1];
        }
    }
}

/// Column `i` (1-based) of the difference table `phi` stored column after column.
#[inline]
fn column(phi: &[f64], n: usize, i: usize) -> &[f64] {
    &phi[(i - 1) * n..i * n]
}

/// Column `i` (1-based), mutable.
#[inline]
fn column_mut(phi: &mut [f64], n: usize, i: usize) -> &mut [f64] {
    &mut phi[(i - 1) * n..i * n]
}

/// Columns `i` (mutable) and `i + 1` (shared) of the difference table.
#[inline]
fn column_and_next(phi: &mut [f64], n: usize, i: usize) -> (&mut [f64], &[f64]) {
    let (low, high) = phi.split_at_mut(i * n);
    (&mut low[(i - 1) * n..], &high[..n])
}

/// Columns `i < j` (1-based), both mutable.
#[inline]
fn two_columns_mut(phi: &mut [f64], n: usize, i: usize, j: usize) -> (&mut [f64], &mut [f64]) {
    debug_assert!(i < j);
    let (low, high) = phi.split_at_mut((j - 1) * n);
    (&mut low[(i - 1) * n..i * n], &mut high[..n])
}

/// Index of the first non-finite entry, if any.
#[inline]
fn first_non_finite(v: &[f64]) -> Option<usize> {
    v.iter().position(|x| !x.is_finite())
}

/// The state of one Adams integration: the modified divided differences of `f` at the
/// last accepted point, the step and order history, and the statistics.
///
/// All work vectors are allocated in [`Integrator::start`]; [`Stepper::step`] and
/// [`Stepper::interpolate`] allocate nothing.
#[derive(Debug, Clone)]
pub struct AbmStepper {
    options: Options,
    max_order: usize,
    dim: usize,
    /// Where the stepper is, where it ends, its statistics (shared by every stepper).
    span: Span,
    /// Largest step magnitude: `min(max_step, |t_end - t0|)`.
    h_max: f64,
    /// Signed step size to try next.
    h: f64,
    /// Signed size of the last accepted step (0 before the first one).
    h_old: f64,
    /// Order to try next.
    order: usize,
    /// Order of the last accepted step (0 before the first one).
    order_old: usize,
    /// Steps taken with the current step size, including the current one (STEP's `NS`).
    steps_at_h: usize,
    /// Start phase: raise the order and double the step after every step.
    start_phase: bool,
    /// Consecutive accepted steps at order <= 4 (DE's `KLE4`).
    low_order_steps: usize,
    coef: Coefficients,
    y: Vec<f64>,
    /// Derivative: `f(t, y)` after a step, `f` at the prediction during one.
    dy: Vec<f64>,
    /// Predicted state.
    predicted: Vec<f64>,
    /// Modified divided differences `phi_1 .. phi_{k+2}`, `N_DIFF` columns of `dim`.
    phi: Vec<f64>,
    /// Absolute tolerance of each component.
    atol: Vec<f64>,
    /// Rounding error of the last correction (STEP's `PHI(*, 15)`).
    correction_rounding: Vec<f64>,
    /// Rounding error of the current prediction (STEP's `PHI(*, 16)`).
    prediction_rounding: Vec<f64>,
    /// Reciprocal error weights of the current step.
    inv_weight: Vec<f64>,
}

impl AbmStepper {
    /// Order that the next step will try.
    pub fn order(&self) -> usize {
        self.order
    }

    /// Order of the last accepted step (0 before the first one).
    pub fn last_order(&self) -> usize {
        self.order_old
    }

    /// Signed step size that the next step will try (before limiting to `max_step` and
    /// `t_end`).
    pub fn step_size(&self) -> f64 {
        self.h
    }

    /// Weighted RMS norm of `v` with the current reciprocal weights.
    #[inline]
    fn weighted_rms(&self, v: &[f64]) -> f64 {
        let mut sum = 0.0;
        for (x, w) in v.iter().zip(&self.inv_weight) {
            let r = x * w;
            sum += r * r;
        }
        (sum / self.dim as f64).sqrt()
    }
}

impl Integrator for Abm {
    type Stepper = AbmStepper;

    fn name(&self) -> &'static str {
        "abm"
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
    ) -> Result<AbmStepper, IntegratorError> {
        let n = system.dim();
        crate::common::validate_start(&self.options, n, y0, t0, t_end)?;
        let options = self.options.for_system(&*system);
        if !(1..=MAX_ORDER).contains(&self.max_order) {
            return Err(IntegratorError::InvalidOptions(format!(
                "max_order must be between 1 and {MAX_ORDER}, got {}",
                self.max_order
            )));
        }
        let direction = (t_end - t0).signum();
        let h_max = options.max_step.min((t_end - t0).abs());

        // Room for every order, so that recording one never allocates inside `step`.
        let mut stats = Stats {
            orders: Vec::with_capacity(MAX_ORDER + 1),
            ..Stats::default()
        };
        let mut dy = vec![0.0; n];
        system.rhs(t0, y0, &mut dy);
        stats.rhs_evaluations += 1;
        if let Some(component) = first_non_finite(&dy) {
            return Err(IntegratorError::NonFinite { t: t0, component });
        }

        let h0 = match options.initial_step {
            Some(h0) => h0.min(h_max),
            None => {
                let mut work = vec![0.0; 2 * n];
                let h = initial_step(
                    system, t0, y0, &dy, 1, direction, h_max, &options, &mut work,
                );
                stats.rhs_evaluations += 1;
                if h.is_finite() && h > 0.0 {
                    h
                } else {
                    // The trial evaluation failed (non-finite): start small and let the
                    // error test sort it out.
                    1e-6 * h_max
                }
            }
        };

        let mut phi = vec![0.0; N_DIFF * n];
        column_mut(&mut phi, n, 1).copy_from_slice(&dy);
        let atol = (0..n).map(|i| options.atol.get(i)).collect();

        Ok(AbmStepper {
            options: options.clone(),
            max_order: self.max_order,
            dim: n,
            span: Span::new(t0, t_end, stats),
            h_max,
            h: direction * h0.max(step_floor(t0)),
            h_old: 0.0,
            order: 1,
            order_old: 0,
            steps_at_h: 0,
            start_phase: true,
            low_order_steps: 0,
            coef: Coefficients::new(),
            y: y0.to_vec(),
            dy,
            predicted: vec![0.0; n],
            phi,
            atol,
            correction_rounding: vec![0.0; n],
            prediction_rounding: vec![0.0; n],
            inv_weight: vec![0.0; n],
        })
    }
}

impl Stepper for AbmStepper {
    fn t(&self) -> f64 {
        self.span.t
    }

    fn y(&self) -> &[f64] {
        &self.y
    }

    fn t_previous(&self) -> f64 {
        self.span.t_previous
    }

    fn stats(&self) -> &Stats {
        &self.span.stats
    }

    /// One accepted step of STEP (Shampine & Gordon 1975, ch. 7), retrying rejected attempts
    /// with half the step (and order 1 from the third failure on). Once `t_end` is reached,
    /// further calls do nothing.
    fn step<S: OdeSystem + ?Sized>(&mut self, system: &mut S) -> Result<(), IntegratorError> {
        if self.span.finished {
            return Ok(());
        }
        let n = self.dim;
        let direction = (self.span.t_end - self.span.t).signum();

        // Limit the step to max_step and to what is left (DE, label 100); land on t_end
        // exactly rather than leave a sliver of a step.
        let remaining = (self.span.t_end - self.span.t).abs();
        let mut abs_h = self.h.abs().min(self.h_max);
        let mut last = false;
        if remaining <= abs_h * (1.0 + 4.0 * f64::EPSILON) + step_floor(self.span.t_end) {
            abs_h = remaining;
            last = true;
        }
        let mut h = direction * abs_h;
        let mut failures = 0usize;

        loop {
            self.span.check_budget(self.options.max_steps)?;
            self.span.check_step_size(h, None)?;

            // ---- Block 1: coefficients (only those changed by the step history).
            let k = self.order;
            if h.to_bits() != self.h_old.to_bits() {
                self.steps_at_h = 0;
            }
            if self.steps_at_h <= self.order_old {
                self.steps_at_h += 1;
            }
            let ns = self.steps_at_h;
            if k >= ns {
                self.coef.update(h, k, ns);
            }
            let coef = &self.coef;

            // ---- Block 2: predict, evaluate, estimate errors at orders k-2 .. k.
            // phi -> phi* (scaled to the new step pattern: beta_i = 1 for i <= ns), the
            // predicted differences phi^p_i = phi*_i + phi^p_{i+1} (phi^p_{k+1} = 0, the old
            // phi_{k+1} kept in column k + 2 for the order k + 1 estimate) and
            // sum_{i<=k} g_i phi*_i, one column at a time.
            {
                let (phi_k1, phi_k2) = two_columns_mut(&mut self.phi, n, k + 1, k + 2);
                phi_k2.copy_from_slice(phi_k1);
                phi_k1.fill(0.0);
            }
            let sum = &mut self.predicted[..n];
            sum.fill(0.0);
            for i in (1..=k).rev() {
                let gi = coef.g[i];
                let beta_i = if i > ns { coef.beta[i] } else { 1.0 };
                let (phi_i, phi_next) = column_and_next(&mut self.phi, n, i);
                let (phi_i, phi_next) = (&mut phi_i[..n], &phi_next[..n]);
                for l in 0..n {
                    let star = beta_i * phi_i[l];
                    sum[l] += gi * star;
                    phi_i[l] = star + phi_next[l];
                }
            }
            // p = y + h sum g_i phi*_i with the rounding of the last correction carried
            // along (propagated round-off control, Shampine & Gordon 1975, ch. 7).
            for l in 0..n {
                let increment = h * self.predicted[l] - self.correction_rounding[l];
                let p = self.y[l] + increment;
                self.prediction_rounding[l] = (p - self.y[l]) - increment;
                self.predicted[l] = p;
            }
            let t_new = if last {
                self.span.t_end
            } else {
                self.span.t + h
            };
            system.rhs(t_new, &self.predicted, &mut self.dy);
            self.span.stats.rhs_evaluations += 1;
            let non_finite =
                first_non_finite(&self.predicted).or_else(|| first_non_finite(&self.dy));

            let (err, mut err_k, err_km1, order_new) = if non_finite.is_some() {
                (f64::INFINITY, f64::INFINITY, f64::INFINITY, k)
            } else {
                // Error weights atol + rtol max(|y_n|, |p|) and the estimates of
                // Shampine & Gordon (eq. 6.5-6.8): with e = f(p) - phi_1,
                // ERK(k-j) = |h| sigma_{k+1-j} gamma*_{k-j} |phi_{k+1-j} + e| (phi after
                // prediction), ERR = |h| (g_k - g_{k+1}) |e|.
                let rtol = self.options.rtol;
                let (mut s_km2, mut s_km1, mut s_k) = (0.0, 0.0, 0.0);
                let phi1 = column(&self.phi, n, 1);
                let phik = column(&self.phi, n, k);
                let phikm1 = column(&self.phi, n, k.saturating_sub(1).max(1));
                let components = self
                    .inv_weight
                    .iter_mut()
                    .zip(&self.atol)
                    .zip(self.y.iter().zip(&self.predicted))
                    .zip(self.dy.iter().zip(phi1))
                    .zip(phikm1.iter().zip(phik));
                for ((((w, atol), (y, p)), (f, f1)), (dkm1, dk)) in components {
                    let scale = atol + rtol * y.abs().max(p.abs());
                    *w = 1.0 / scale.max(f64::MIN_POSITIVE);
                    let e = f - f1;
                    let (a, b, c) = ((dkm1 + e) * *w, (dk + e) * *w, e * *w);
                    s_km2 += a * a;
                    s_km1 += b * b;
                    s_k += c * c;
                }
                let abs_h = h.abs();
                let nf = n as f64;
                let gstr = &ADAMS_MOULTON_ERROR_CONSTANTS;
                let err_km2 = if k >= 3 {
                    abs_h * coef.sigma[k - 1] * gstr[k - 2] * (s_km2 / nf).sqrt()
                } else {
                    0.0
                };
                let err_km1 = if k >= 2 {
                    abs_h * coef.sigma[k] * gstr[k - 1] * (s_km1 / nf).sqrt()
                } else {
                    0.0
                };
                let base = abs_h * (s_k / nf).sqrt();
                let err = base * (coef.g[k] - coef.g[k + 1]);
                let err_k = base * coef.sigma[k + 1] * gstr[k];
                // Lower the order if the lower-order estimates are no worse.
                let mut order_new = k;
                if k >= 3 && err_km1.max(err_km2) <= err_k {
                    order_new = k - 1;
                }
                if k == 2 && err_km1 <= 0.5 * err_k {
                    order_new = 1;
                }
                (err, err_k, err_km1, order_new)
            };

            if err <= 1.0 {
                // ---- Block 4: correct, evaluate, update the differences, choose the next
                // order and step.
                self.order_old = k;
                self.h_old = h;
                let gk1 = h * coef.g[k + 1];
                {
                    let phi1 = column(&self.phi, n, 1);
                    for l in 0..n {
                        let correction = gk1 * (self.dy[l] - phi1[l]) - self.prediction_rounding[l];
                        let y_new = self.predicted[l] + correction;
                        self.correction_rounding[l] = (y_new - self.predicted[l]) - correction;
                        self.y[l] = y_new;
                    }
                }
                self.span.advance(t_new, false);
                system.rhs(self.span.t, &self.y, &mut self.dy);
                self.span.stats.rhs_evaluations += 1;
                if let Some(component) =
                    first_non_finite(&self.y).or_else(|| first_non_finite(&self.dy))
                {
                    return Err(IntegratorError::NonFinite {
                        t: self.span.t,
                        component,
                    });
                }
                // phi_{k+1}(n+1) = f_{n+1} - phi^p_1, phi_{k+2} = its change, and
                // phi_i(n+1) = phi^p_i + phi_{k+1}(n+1) for i <= k.
                {
                    let (low, high) = self.phi.split_at_mut(k * n);
                    let (phi_k1, rest) = high.split_at_mut(n);
                    let phi_k2 = &mut rest[..n];
                    for l in 0..n {
                        phi_k1[l] = self.dy[l] - low[l];
                        phi_k2[l] = phi_k1[l] - phi_k2[l];
                    }
                    for chunk in low.chunks_exact_mut(n) {
                        for (v, e) in chunk.iter_mut().zip(phi_k1.iter()) {
                            *v += e;
                        }
                    }
                }

                // Order for the next step.
                let mut order = k;
                if order_new + 1 == k || k == self.max_order {
                    self.start_phase = false;
                }
                if self.start_phase {
                    order = k + 1;
                    err_k = 0.0;
                } else if order_new + 1 == k {
                    order = k - 1;
                    err_k = err_km1;
                } else if k < ns {
                    // Constant step over the last k + 1 steps: phi_{k+2} estimates the
                    // error at order k + 1.
                    let err_kp1 = h.abs()
                        * ADAMS_MOULTON_ERROR_CONSTANTS[k + 1]
                        * self.weighted_rms(column(&self.phi, n, k + 2));
                    let can_raise = k < self.max_order;
                    if k > 1 {
                        if err_km1 <= err_k.min(err_kp1) {
                            order = k - 1;
                            err_k = err_km1;
                        } else if err_kp1 < err_k && can_raise {
                            order = k + 1;
                            err_k = err_kp1;
                        }
                    } else if err_kp1 < 0.5 * err_k && can_raise {
                        order = k + 1;
                        err_k = err_kp1;
                    }
                }
                self.order = order;

                // Step for the next step: double if the error would allow it, keep if the
                // error is below half the tolerance, else shrink by the asymptotic ratio
                // within [0.5, 0.9].
                let half_tol = 0.5;
                let abs_h = h.abs();
                let h_new = if self.start_phase || half_tol >= err_k * 2f64.powi(order as i32 + 1) {
                    2.0 * abs_h
                } else if half_tol >= err_k {
                    abs_h
                } else {
                    let r = (half_tol / err_k).powf(1.0 / (order as f64 + 1.0));
                    (abs_h * r.clamp(0.5, 0.9)).max(step_floor(self.span.t))
                };
                self.h = direction * h_new;

                // Book-keeping.
                self.span.stats.accepted_steps += 1;
                self.span.stats.record_order(k);
                if k > 4 {
                    self.low_order_steps = 0;
                } else {
                    self.low_order_steps += 1;
                    if self.low_order_steps >= STIFF_LOW_ORDER_STEPS
                        && self.span.stats.stiffness_detected_at.is_none()
                    {
                        self.span.stats.stiffness_detected_at = Some(self.span.t);
                    }
                }
                if last {
                    self.span.finished = true;
                }
                return Ok(());
            }

            // ---- Block 3: the step failed. Restore phi and psi, halve the step; order 1
            // from the third failure on, then the asymptotic step estimate.
            self.span.stats.rejected_steps += 1;
            self.start_phase = false;
            for i in 1..=k {
                let inv_beta = 1.0 / self.coef.beta[i];
                let (phi_i, phi_next) = column_and_next(&mut self.phi, n, i);
                for (a, b) in phi_i.iter_mut().zip(phi_next) {
                    *a = inv_beta * (*a - b);
                }
            }
            for i in 2..=k {
                self.coef.psi[i - 1] = self.coef.psi[i] - h;
            }
            failures += 1;
            let mut factor = 0.5;
            if failures > 3 && non_finite.is_none() && 0.5 < 0.25 * err_k {
                factor = (0.5 / err_k).sqrt();
            }
            self.order = if failures >= 3 { 1 } else { order_new };
            h *= factor;
            last = false;
            self.steps_at_h = 0;
            if h.is_nan() || h.abs() < step_floor(self.span.t) {
                return Err(match non_finite {
                    Some(component) => IntegratorError::NonFinite {
                        t: t_new,
                        component,
                    },
                    None => IntegratorError::StepSizeTooSmall { t: self.span.t, h },
                });
            }
        }
    }

    /// Dense output by the Adams interpolating polynomial of degree `k_old + 1` through the
    /// stored differences (Shampine & Gordon 1975, ch. 7, routine INTRP):
    /// `y(x + s) = y + s sum_{i<=k+1} g_i(s) phi_i`, with `g_i(s)` from the recursion on
    /// `psi` (the same recursion as `Coefficients::update` for a step of length `s`).
    fn interpolate(&self, t: f64, out: &mut [f64]) {
        let n = self.dim;
        let s = t - self.span.t;
        let ki = self.order_old + 1;
        let mut w = [0.0; N_COEF + 1];
        let mut g = [0.0; N_COEF + 1];
        for (i, wi) in w.iter_mut().enumerate().take(ki + 1).skip(1) {
            *wi = 1.0 / i as f64;
        }
        g[1] = 1.0;
        let mut term = 0.0;
        for j in 2..=ki {
            let psi = self.coef.psi[j - 1];
            let gamma = (s + term) / psi;
            let eta = s / psi;
            for i in 1..=ki + 1 - j {
                w[i] = gamma * w[i] - eta * w[i + 1];
            }
            g[j] = w[1];
            term = psi;
        }
        out.fill(0.0);
        for i in (1..=ki).rev() {
            let gi = g[i];
            for (o, p) in out.iter_mut().zip(column(&self.phi, n, i)) {
                *o += gi * p;
            }
        }
        for (o, y) in out.iter_mut().zip(&self.y) {
            *o = y + s * *o;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The error constants agree with the known fractions (Hairer, Norsett & Wanner I,
    /// Table III.1.2): 1/2, 1/12, 1/24, 19/720, 3/160, 863/60480, 275/24192.
    #[test]
    fn adams_moulton_error_constants_match_table() {
        let expected = [
            1.0,
            1.0 / 2.0,
            1.0 / 12.0,
            1.0 / 24.0,
            19.0 / 720.0,
            3.0 / 160.0,
            863.0 / 60480.0,
            275.0 / 24192.0,
            33953.0 / 3628800.0,
        ];
        for (j, e) in expected.iter().enumerate() {
            assert!(
                (ADAMS_MOULTON_ERROR_CONSTANTS[j] - e).abs() < 1e-15,
                "gamma*_{j}"
            );
        }
        // STEP's three-digit table for the higher ones.
        for (j, e) in [(10, 0.00679), (11, 0.00592), (12, 0.00524), (13, 0.00468)] {
            assert!(
                (ADAMS_MOULTON_ERROR_CONSTANTS[j] - e).abs() < 6e-6,
                "gamma*_{j}"
            );
        }
    }

    /// With constant steps the `g_i` are the Adams-Bashforth coefficients `gamma_{i-1}`
    /// (1, 1/2, 5/12, 3/8, 251/720, 95/288, ...; Hairer, Norsett & Wanner I, III.1).
    #[test]
    fn constant_step_g_are_adams_bashforth_gammas() {
        let mut c = Coefficients::new();
        let h = 0.1;
        // psi_i = i h for a history of constant steps.
        for i in 1..N_COEF {
            c.psi[i] = i as f64 * h;
        }
        c.update(h, 12, 1);
        let gamma = [
            1.0,
            1.0 / 2.0,
            5.0 / 12.0,
            3.0 / 8.0,
            251.0 / 720.0,
            95.0 / 288.0,
            19087.0 / 60480.0,
        ];
        for (i, e) in gamma.iter().enumerate() {
            assert!((c.g[i + 1] - e).abs() < 1e-14, "g_{}", i + 1);
        }
        for i in 1..=12 {
            assert!((c.beta[i] - 1.0).abs() < 1e-14);
            assert!((c.alpha[i] - 1.0 / i as f64).abs() < 1e-14);
            assert!((c.sigma[i] - 1.0).abs() < 1e-14);
        }
    }

    /// For a step h after a step 2h the two-step predictor (k = 2) integrates a linear f
    /// exactly: g_2 must be 1/2 and the scaled difference beta_2 phi_2 must account for the
    /// step ratio (beta_2 = psi_1(n+1)/psi_1(n) = 1/2).
    #[test]
    fn variable_step_coefficients_follow_the_definitions() {
        let mut c = Coefficients::new();
        // Previous step 2h: psi_1(n) = 2h, psi_2(n) = 2h + h_{n-1} with h_{n-1} = 2h.
        let h = 0.1;
        c.psi[1] = 2.0 * h;
        c.psi[2] = 4.0 * h;
        c.update(h, 3, 1);
        assert!((c.psi[1] - h).abs() < 1e-15);
        assert!((c.psi[2] - 3.0 * h).abs() < 1e-15);
        assert!((c.psi[3] - 5.0 * h).abs() < 1e-15);
        assert!((c.beta[2] - 0.5).abs() < 1e-15);
        assert!((c.beta[3] - 0.5 * 3.0 / 4.0).abs() < 1e-15);
        assert!((c.alpha[2] - 1.0 / 3.0).abs() < 1e-15);
        assert!((c.alpha[3] - 1.0 / 5.0).abs() < 1e-15);
        assert!((c.sigma[3] - 2.0 / 3.0).abs() < 1e-15);
        // g_i = c_{i,1}: g_2 = 1/2, g_3 = 1/2 - alpha_2 (1/2 - 1/3 ... ) from the recursion:
        // c_2 = (1/2, 1/6, 1/12), c_3,1 = 1/2 - alpha_2 / 6.
        assert!((c.g[2] - 0.5).abs() < 1e-15);
        assert!((c.g[3] - (0.5 - 1.0 / 18.0)).abs() < 1e-15);
    }
}
