//! Dormand-Prince 5(4): an explicit embedded Runge-Kutta pair with FSAL, PI step-size
//! control, a 4th-order continuous extension and Hairer's stiffness detection.
//!
//! Sources: J. R. Dormand & P. J. Prince, "A family of embedded Runge-Kutta formulae",
//! *J. Comput. Appl. Math.* 6 (1980) 19-26 (the tableau); E. Hairer, S. P. Norsett &
//! G. Wanner, *Solving Ordinary Differential Equations I*, 2nd ed., Springer 1993:
//! Table II.5.2 (tableau), II.4 (error norm, starting step), II.6 (dense output, with the
//! coefficients of the code DOPRI5); E. Hairer & G. Wanner, *Solving Ordinary Differential
//! Equations II*, 2nd ed., Springer 1996, IV.2 (automatic stiffness detection, and the PI
//! "stabilized" step-size control of K. Gustafsson, *ACM TOMS* 17 (1991), as used in DOPRI5).

use crate::common::{Span, error_norm, initial_step};
use crate::{Integrator, IntegratorError, OdeSystem, Options, Stats, Stepper};

// Butcher tableau of Dormand & Prince (1980), Hairer-Norsett-Wanner I, Table II.5.2.
const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
// 5th-order weights (= last row of the tableau, hence FSAL).
const B1: f64 = 35.0 / 384.0;
const B3: f64 = 500.0 / 1113.0;
const B4: f64 = 125.0 / 192.0;
const B5: f64 = -2187.0 / 6784.0;
const B6: f64 = 11.0 / 84.0;
// Error weights b - b_hat (5th minus embedded 4th order).
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;
// Dense output of order 4 (Hairer-Norsett-Wanner I, II.6, the coefficients of DOPRI5).
const D1: f64 = -12715105075.0 / 11282082432.0;
const D3: f64 = 87487479700.0 / 32700410799.0;
const D4: f64 = -10690763975.0 / 1880347072.0;
const D5: f64 = 701980252875.0 / 199316789632.0;
const D6: f64 = -1453857185.0 / 822651844.0;
const D7: f64 = 69997945.0 / 29380423.0;

/// Order of the propagated (5th-order) solution.
const ORDER: usize = 5;
/// Safety factor of the step-size prediction (DOPRI5's `SAFE`).
const SAFETY: f64 = 0.9;
/// Largest step decrease per attempt (`h_new >= FAC_MIN h`; DOPRI5's `FAC1`).
const FAC_MIN: f64 = 0.2;
/// Largest step increase per step (`h_new <= FAC_MAX h`; DOPRI5's `FAC2`).
const FAC_MAX: f64 = 10.0;
/// Exponent of the previous error in the PI controller (DOPRI5's `BETA`).
const PI_BETA: f64 = 0.04;
/// Step-size reduction after a trial step produced non-finite values.
const NON_FINITE_SHRINK: f64 = 0.1;
/// Consecutive non-finite trial steps tolerated before reporting [`IntegratorError::NonFinite`].
const NON_FINITE_RETRIES: usize = 3;
/// `|h lambda|` above which a step counts as stability-limited: the real stability boundary
/// of DOPRI5 is about 3.3 (Hairer & Wanner II, IV.2; DOPRI5 uses 3.25).
const STIFF_H_LAMBDA: f64 = 3.25;
/// Stability-limited accepted steps (without 6 non-stiff ones in between) that make the
/// problem "stiff" (DOPRI5's `IASTI = 15`).
const STIFF_STEPS: usize = 15;
/// Non-stiff accepted steps that reset the stiff count (DOPRI5's `NONSTI = 6`).
const NONSTIFF_RESET: usize = 6;

/// What [`Rk45`] does when its stiffness test fires.
///
/// The test (Hairer & Wanner II, IV.2; the code DOPRI5) estimates `|h lambda|`, the
/// step size times the dominant eigenvalue of the Jacobian, from the last two stages, which
/// share the abscissa `t + h`:
/// `h_lambda = |h| * ||f(t + h, y_new) - f(t + h, y_6)|| / ||y_new - y_6||`. When it exceeds
/// 3.25 (near the stability boundary of the method on the negative real axis) on 15 accepted
/// steps without 6 non-stiff ones in between, stability rather than accuracy limits the step,
/// and an implicit method (BDF) would be much cheaper.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StiffnessDetection {
    /// No test.
    Off,
    /// Test every accepted step; record the first detection in
    /// [`Stats::stiffness_detected_at`] and carry on (the default).
    #[default]
    Report,
    /// Test every accepted step; stop with [`IntegratorError::Stiff`] when it fires.
    Error,
}

/// Dormand-Prince 5(4) with PI step-size control and 4th-order dense output, after the code
/// DOPRI5 of Hairer & Wanner (Hairer-Norsett-Wanner I, II.4-II.6).
///
/// Six right-hand-side evaluations per step attempt (the seventh stage is the first of the
/// next step: "first same as last"). Best for non-stiff problems at moderate tolerances
/// (`rtol` about 1e-3 to 1e-9).
///
/// ```
/// use flexprr_integrators::{Integrator, Rk45, StiffnessDetection, Options};
/// use flexprr_integrators::test_problems::{HarmonicOscillator, TestProblem};
///
/// let mut p = HarmonicOscillator::default();
/// let rk = Rk45::new(Options::default().rtol(1e-8).atol(1e-10))
///     .with_stiffness(StiffnessDetection::Error);
/// let y0 = p.y0();
/// let sol = rk.solve(&mut p, 0.0, &y0, &[5.0, 10.0]).unwrap();
/// assert!((sol.y(1)[0] - 10.0_f64.cos()).abs() < 1e-7);
/// assert!(sol.stats.stiffness_detected_at.is_none());
/// ```
#[derive(Debug, Clone)]
pub struct Rk45 {
    /// Shared options.
    pub options: Options,
    /// What to do when the stiffness test fires.
    pub stiffness: StiffnessDetection,
}

impl Rk45 {
    /// The method with the given options and stiffness detection in
    /// [`StiffnessDetection::Report`] mode.
    pub fn new(options: Options) -> Self {
        Self {
            options,
            stiffness: StiffnessDetection::default(),
        }
    }

    /// Turns the stiffness test on (report only, [`StiffnessDetection::Report`]) or off.
    #[must_use]
    pub fn with_stiffness_detection(mut self, on: bool) -> Self {
        self.stiffness = if on {
            StiffnessDetection::Report
        } else {
            StiffnessDetection::Off
        };
        self
    }

    /// Chooses what the stiffness test does, e.g. [`StiffnessDetection::Error`] to stop with
    /// [`IntegratorError::Stiff`] instead of reporting.
    #[must_use]
    pub fn with_stiffness(mut self, mode: StiffnessDetection) -> Self {
        self.stiffness = mode;
        self
    }
}

/// One Dormand-Prince integration in progress (see [`Rk45`]).
#[derive(Debug, Clone)]
pub struct Rk45Stepper {
    options: Options,
    stiffness: StiffnessDetection,
    /// +1 forwards, -1 backwards.
    direction: f64,
    /// Where the stepper is, where it ends, its statistics (shared by every stepper).
    span: Span,
    /// Signed size of the next step attempt.
    h: f64,
    /// Signed size of the last accepted step (for dense output).
    h_previous: f64,
    /// Largest step magnitude.
    h_max: f64,
    y: Vec<f64>,
    /// Stage derivatives; `k[0] = f(t, y)` (FSAL), `k[6] = f(t + h, y_new)`.
    k: [Vec<f64>; 7],
    /// Stage argument (holds the 6th stage argument after an attempt, for the stiffness test).
    y_stage: Vec<f64>,
    y_new: Vec<f64>,
    /// Local error estimate of the last attempt.
    error: Vec<f64>,
    /// Dense-output coefficients of the last accepted step, `4 * dim` values
    /// (`y_prev` is the 5th; see [`Stepper::interpolate`]).
    dense: Vec<f64>,
    y_previous: Vec<f64>,
    /// Error norm of the last accepted step (PI controller memory, DOPRI5's `FACOLD`).
    error_previous: f64,
    /// The step before this one was rejected (no growth after a rejection).
    last_rejected: bool,
    /// Component that was non-finite if the latest rejection was for non-finite values.
    non_finite_component: Option<usize>,
    stiff_count: usize,
    nonstiff_count: usize,
}

impl Integrator for Rk45 {
    type Stepper = Rk45Stepper;

    fn name(&self) -> &'static str {
        "rk45"
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
    ) -> Result<Rk45Stepper, IntegratorError> {
        let n = system.dim();
        crate::common::validate_start(&self.options, n, y0, t0, t_end)?;
        let options = self.options.for_system(&*system);
        let span = t_end - t0;
        let direction = span.signum();
        let h_max = options.max_step.min(span.abs());

        let mut stats = Stats {
            orders: vec![0; ORDER + 1],
            ..Stats::default()
        };
        let mut k: [Vec<f64>; 7] = std::array::from_fn(|_| vec![0.0; n]);
        system.rhs(t0, y0, &mut k[0]);
        stats.rhs_evaluations += 1;
        if let Some(component) = k[0].iter().position(|v| !v.is_finite()) {
            return Err(IntegratorError::NonFinite { t: t0, component });
        }

        let h_abs = match options.initial_step {
            Some(h0) => h0.min(h_max),
            None => {
                let mut work = vec![0.0; 2 * n];
                let h = initial_step(
                    system, t0, y0, &k[0], ORDER, direction, h_max, &options, &mut work,
                );
                stats.rhs_evaluations += 1;
                if h.is_finite() && h > 0.0 {
                    h
                } else {
                    // Hairer's fallback for a zero or unusable derivative scale.
                    1e-6_f64.min(h_max)
                }
            }
        };

        Ok(Rk45Stepper {
            options: options.clone(),
            stiffness: self.stiffness,
            direction,
            span: Span::new(t0, t_end, stats),
            h: direction * h_abs,
            h_previous: 0.0,
            h_max,
            y: y0.to_vec(),
            k,
            y_stage: vec![0.0; n],
            y_new: vec![0.0; n],
            error: vec![0.0; n],
            dense: vec![0.0; 4 * n],
            y_previous: y0.to_vec(),
            error_previous: 1e-4,
            last_rejected: false,
            non_finite_component: None,
            stiff_count: 0,
            nonstiff_count: 0,
        })
    }
}

impl Rk45Stepper {
    /// Signed size of the next step attempt (as chosen by the controller, before `max_step`
    /// and landing on `t_end` are applied).
    pub fn step_size(&self) -> f64 {
        self.h
    }

    /// Signed size of the last accepted step (0 before the first).
    pub fn last_step_size(&self) -> f64 {
        self.h_previous
    }

    /// One trial step of size `h` from `(t, y)`: fills `k[1..7]`, `y_new` and `error`.
    /// Six right-hand-side evaluations (stages 2-7).
    fn attempt<S: OdeSystem + ?Sized>(&mut self, system: &mut S, h: f64) {
        let t = self.span.t;
        let n = self.y.len();
        let y = &self.y;
        let ys = &mut self.y_stage;
        let [k1, k2, k3, k4, k5, k6, k7] = &mut self.k;

        for i in 0..n {
            ys[i] = y[i] + h * A21 * k1[i];
        }
        system.rhs(t + C2 * h, ys, k2);
        for i in 0..n {
            ys[i] = y[i] + h * (A31 * k1[i] + A32 * k2[i]);
        }
        system.rhs(t + C3 * h, ys, k3);
        for i in 0..n {
            ys[i] = y[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i]);
        }
        system.rhs(t + C4 * h, ys, k4);
        for i in 0..n {
            ys[i] = y[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i]);
        }
        system.rhs(t + C5 * h, ys, k5);
        for i in 0..n {
            ys[i] =
                y[i] + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i]);
        }
        // The last stage lands exactly on t + h (c6 = c7 = 1); when this is the final step,
        // t + h is t_end up to rounding, and the caller stores t_end itself.
        let t_new = t + h;
        system.rhs(t_new, ys, k6);
        for i in 0..n {
            self.y_new[i] =
                y[i] + h * (B1 * k1[i] + B3 * k3[i] + B4 * k4[i] + B5 * k5[i] + B6 * k6[i]);
        }
        system.rhs(t_new, &self.y_new, k7);
        for i in 0..n {
            self.error[i] =
                h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i]);
        }
        self.span.stats.rhs_evaluations += 6;
    }

    /// First non-finite component of `y_new` or `f(t + h, y_new)`.
    fn first_non_finite(&self) -> Option<usize> {
        self.y_new
            .iter()
            .position(|v| !v.is_finite())
            .or_else(|| self.k[6].iter().position(|v| !v.is_finite()))
    }

    /// Hairer's stiffness test on an accepted step of size `h` (see [`StiffnessDetection`]);
    /// returns the `|h lambda|` estimate when the problem has just been found stiff.
    fn stiffness_test(&mut self, h: f64) -> Option<f64> {
        let mut num = 0.0;
        let mut den = 0.0;
        for i in 0..self.y.len() {
            num += (self.k[6][i] - self.k[5][i]).powi(2);
            den += (self.y_new[i] - self.y_stage[i]).powi(2);
        }
        if den <= 0.0 {
            return None;
        }
        let h_lambda = h.abs() * (num / den).sqrt();
        if h_lambda > STIFF_H_LAMBDA {
            self.nonstiff_count = 0;
            self.stiff_count += 1;
            if self.stiff_count == STIFF_STEPS {
                return Some(h_lambda);
            }
        } else {
            self.nonstiff_count += 1;
            if self.nonstiff_count == NONSTIFF_RESET {
                self.stiff_count = 0;
            }
        }
        None
    }

    /// Accepts the attempted step of size `h`: dense-output coefficients, state, FSAL.
    fn accept(&mut self, h: f64, last: bool) {
        let n = self.y.len();
        let [k1, _, k3, k4, k5, k6, k7] = &self.k;
        let (ydiff, rest) = self.dense.split_at_mut(n);
        let (bspl, rest) = rest.split_at_mut(n);
        let (c4, c5) = rest.split_at_mut(n);
        // Hairer-Norsett-Wanner I, II.6: the continuous extension of DOPRI5 written as
        // y(t + theta h) = y0 + theta (ydiff + (1 - theta) (bspl + theta (c4 + (1 - theta) c5))).
        for i in 0..n {
            ydiff[i] = self.y_new[i] - self.y[i];
            bspl[i] = h * k1[i] - ydiff[i];
            c4[i] = ydiff[i] - h * k7[i] - bspl[i];
            c5[i] =
                h * (D1 * k1[i] + D3 * k3[i] + D4 * k4[i] + D5 * k5[i] + D6 * k6[i] + D7 * k7[i]);
        }
        self.y_previous.copy_from_slice(&self.y);
        self.y.copy_from_slice(&self.y_new);
        self.k.swap(0, 6);
        self.h_previous = h;
        self.span.advance(self.span.t + h, last);
        self.span.stats.accepted_steps += 1;
        self.span.stats.record_order(ORDER);
    }
}

impl Stepper for Rk45Stepper {
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
        let expo = 1.0 / ORDER as f64 - 0.75 * PI_BETA;
        let mut non_finite_tries = 0;
        loop {
            self.span.check_budget(self.options.max_steps)?;
            let h = self.direction * self.h.abs().min(self.h_max);
            self.span.check_step_size(h, self.non_finite_component)?;
            let (h, last) = self.span.land(h, self.h_max);
            self.attempt(system, h);

            let err = error_norm(&self.error, &self.y, &self.y_new, &self.options);
            if let Some(component) = self.first_non_finite().or(err.is_nan().then_some(0)) {
                // Overflow in a too-large trial step is handled like a rejection; a
                // right-hand side that keeps failing is reported.
                self.span.stats.rejected_steps += 1;
                non_finite_tries += 1;
                if non_finite_tries > NON_FINITE_RETRIES {
                    return Err(IntegratorError::NonFinite {
                        t: self.span.t,
                        component,
                    });
                }
                self.h = h * NON_FINITE_SHRINK;
                self.last_rejected = true;
                self.non_finite_component = Some(component);
                continue;
            }

            // PI controller (Gustafsson; DOPRI5): h_new = h / fac with
            // fac = err^(1/5 - 0.75 beta) / err_prev^beta / safety, bounded to [1/10, 5].
            let fac_err = err.powf(expo);
            if err <= 1.0 {
                let fac = (fac_err / self.error_previous.powf(PI_BETA) / SAFETY)
                    .clamp(1.0 / FAC_MAX, 1.0 / FAC_MIN);
                let mut h_new = h / fac;
                self.error_previous = err.max(1e-4);
                let stiff_at = if self.stiffness == StiffnessDetection::Off {
                    None
                } else {
                    self.stiffness_test(h)
                };
                self.accept(h, last);
                if h_new.abs() > self.h_max {
                    h_new = self.direction * self.h_max;
                }
                if self.last_rejected {
                    // No growth straight after a rejection.
                    h_new = self.direction * h_new.abs().min(h.abs());
                }
                self.last_rejected = false;
                self.h = h_new;
                self.span.finished = last;
                if let Some(h_lambda) = stiff_at {
                    if self.span.stats.stiffness_detected_at.is_none() {
                        self.span.stats.stiffness_detected_at = Some(self.span.t);
                    }
                    if self.stiffness == StiffnessDetection::Error {
                        return Err(IntegratorError::Stiff {
                            t: self.span.t,
                            h_lambda,
                        });
                    }
                }
                return Ok(());
            }
            self.span.stats.rejected_steps += 1;
            self.last_rejected = true;
            self.non_finite_component = None;
            self.h = h / (fac_err / SAFETY).min(1.0 / FAC_MIN);
        }
    }

    /// The 4th-order continuous extension of DOPRI5 (Hairer-Norsett-Wanner I, II.6, with the
    /// coefficients `d_i` of the code): with `theta = (t - t_prev) / h`,
    /// `y(t) = y_prev + theta (ydiff + (1 - theta) (bspl + theta (c4 + (1 - theta) c5)))`.
    /// Exact at both ends of the step, with the right derivatives there (Hermite-like).
    fn interpolate(&self, t: f64, out: &mut [f64]) {
        let n = self.y.len();
        if self.span.stats.accepted_steps == 0 {
            out.copy_from_slice(&self.y);
            return;
        }
        let theta = (t - self.span.t_previous) / self.h_previous;
        let theta1 = 1.0 - theta;
        let (ydiff, rest) = self.dense.split_at(n);
        let (bspl, rest) = rest.split_at(n);
        let (c4, c5) = rest.split_at(n);
        for i in 0..n {
            out[i] = self.y_previous[i]
                + theta * (ydiff[i] + theta1 * (bspl[i] + theta * (c4[i] + theta1 * c5[i])));
        }
    }

    fn stats(&self) -> &Stats {
        &self.span.stats
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Row sums of the tableau equal the abscissae (c_i = sum_j a_ij), and both weight sets
    /// sum to one: necessary conditions for order >= 1 with consistent stages.
    #[test]
    fn tableau_is_consistent() {
        let close = |a: f64, b: f64| (a - b).abs() < 1e-14;
        assert!(close(A21, C2));
        assert!(close(A31 + A32, C3));
        assert!(close(A41 + A42 + A43, C4));
        assert!(close(A51 + A52 + A53 + A54, C5));
        assert!(close(A61 + A62 + A63 + A64 + A65, 1.0));
        assert!(close(B1 + B3 + B4 + B5 + B6, 1.0));
        // The error weights are b - b_hat, so they sum to zero.
        assert!(close(E1 + E3 + E4 + E5 + E6 + E7, 0.0));
        // Order conditions of order 5 for the b weights: sum b_i c_i^(q-1) = 1/q.
        let c = [0.0, C2, C3, C4, C5, 1.0];
        let b = [B1, 0.0, B3, B4, B5, B6];
        for q in 1..=5 {
            let s: f64 = b.iter().zip(c).map(|(b, c)| b * c.powi(q - 1)).sum();
            assert!(close(s, 1.0 / q as f64), "quadrature condition q = {q}");
        }
    }

    /// The continuous extension at theta = 1/2 integrates y' = t^3 exactly (order 4), and is
    /// exact at theta = 1 where it reproduces the step.
    #[test]
    fn dense_output_is_exact_for_cubic_growth() {
        struct Cubic;
        impl OdeSystem for Cubic {
            fn dim(&self) -> usize {
                1
            }
            fn rhs(&mut self, t: f64, _y: &[f64], dy: &mut [f64]) {
                dy[0] = t * t * t;
            }
        }
        let rk = Rk45::new(Options::default().initial_step(1.0));
        let mut stepper = rk.start(&mut Cubic, 0.0, &[0.0], 1.0).unwrap();
        stepper.step(&mut Cubic).unwrap();
        assert!((stepper.t() - 1.0).abs() < 1e-15);
        let mut out = [0.0];
        for theta in [0.1, 0.25, 0.5, 0.8, 1.0] {
            stepper.interpolate(theta, &mut out);
            let exact = theta.powi(4) / 4.0;
            assert!(
                (out[0] - exact).abs() < 1e-14,
                "theta = {theta}: {}",
                out[0]
            );
        }
    }

    /// Stepping after t_end is an error, not a silent no-op.
    #[test]
    fn stepping_past_the_end_is_refused() {
        struct Decay;
        impl OdeSystem for Decay {
            fn dim(&self) -> usize {
                1
            }
            fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
                dy[0] = -y[0];
            }
        }
        let mut stepper = Rk45::new(Options::default())
            .start(&mut Decay, 0.0, &[1.0], 0.5)
            .unwrap();
        while stepper.t() < 0.5 {
            stepper.step(&mut Decay).unwrap();
        }
        assert!((stepper.t() - 0.5).abs() < 1e-300);
        assert!(matches!(
            stepper.step(&mut Decay),
            Err(IntegratorError::InvalidInput(_))
        ));
    }
}
