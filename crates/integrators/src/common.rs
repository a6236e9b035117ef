//! Pieces every method shares: the error norm, the initial step, the checks of `start`, and
//! the stepper's span ([`Span`]: where it is, where it ends, its statistics and the checks
//! every step makes).

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::lu::partial_pivoting::{factor as lu_factor, solve as lu_solve};
use faer::perm::PermRef;
use faer::{Mat, MatMut, Par};

use crate::{IntegratorError, OdeSystem, Options, Stats};

/// Weighted RMS norm of a local error estimate (Hairer, Norsett & Wanner I, eq. II.4.11):
/// `sqrt(1/n sum (err_i / (atol_i + rtol max(|y_i|, |y_new_i|)))^2)`.
#[inline]
pub fn error_norm(err: &[f64], y: &[f64], y_new: &[f64], options: &Options) -> f64 {
    let n = err.len();
    let mut sum = 0.0;
    for i in 0..n {
        let scale = options.atol.get(i) + options.rtol * y[i].abs().max(y_new[i].abs());
        let r = err[i] / scale;
        sum += r * r;
    }
    (sum / n as f64).sqrt()
}

/// Automatic initial step size for a method of order `order` (Hairer, Norsett & Wanner I,
/// II.4, "Starting step size"; the routine HINIT of DOPRI5).
///
/// `f0 = f(t0, y0)`; `direction` is `+1` or `-1`; `work` needs `2 * dim` entries. Costs one
/// right-hand-side evaluation, which the caller must count.
#[allow(clippy::too_many_arguments)]
pub fn initial_step<S: OdeSystem + ?Sized>(
    system: &mut S,
    t0: f64,
    y0: &[f64],
    f0: &[f64],
    order: usize,
    direction: f64,
    h_max: f64,
    options: &Options,
    work: &mut [f64],
) -> f64 {
    let n = y0.len();
    let (y1, f1) = work.split_at_mut(n);
    let f1 = &mut f1[..n];
    let mut dnf = 0.0;
    let mut dny = 0.0;
    for i in 0..n {
        let sk = options.atol.get(i) + options.rtol * y0[i].abs();
        dnf += (f0[i] / sk).powi(2);
        dny += (y0[i] / sk).powi(2);
    }
    let mut h = if dnf <= 1e-10 || dny <= 1e-10 {
        1e-6
    } else {
        (dny / dnf).sqrt() * 0.01
    };
    h = h.min(h_max);
    for i in 0..n {
        y1[i] = y0[i] + direction * h * f0[i];
    }
    system.rhs(t0 + direction * h, y1, f1);
    let mut der2 = 0.0;
    for i in 0..n {
        let sk = options.atol.get(i) + options.rtol * y0[i].abs();
        der2 += ((f1[i] - f0[i]) / sk).powi(2);
    }
    let der2 = der2.sqrt() / h;
    let der12 = der2.max(dnf.sqrt());
    let h1 = if der12 <= 1e-15 {
        (h * 1e-3).max(1e-6)
    } else {
        (0.01 / der12).powf(1.0 / (order as f64 + 1.0))
    };
    (100.0 * h).min(h1).min(h_max)
}

/// Checks what every method's `start` needs: valid options, a non-empty system whose
/// dimension matches `y0`, finite `t0`, `t_end` and `y0`, and `t_end` distinguishable from `t0`.
///
/// Every built-in [`crate::Integrator::start`] calls it first; a new method should too, so
/// that bad input fails with the same messages whatever the method.
///
/// # Errors
/// [`IntegratorError::InvalidOptions`] or [`IntegratorError::InvalidInput`] saying which.
pub fn validate_start(
    options: &Options,
    dim: usize,
    y0: &[f64],
    t0: f64,
    t_end: f64,
) -> Result<(), IntegratorError> {
    options.validate(dim)?;
    let input = |msg: String| Err(IntegratorError::InvalidInput(msg));
    if dim == 0 {
        return input("the system has no state components".to_string());
    }
    if y0.len() != dim {
        return input(format!(
            "y0 has {} components but the system has {dim}",
            y0.len()
        ));
    }
    if let Some(i) = y0.iter().position(|v| !v.is_finite()) {
        return input(format!("y0[{i}] = {} is not finite", y0[i]));
    }
    if !t0.is_finite() || !t_end.is_finite() {
        return input(format!("t0 = {t0} and t_end = {t_end} must be finite"));
    }
    if (t_end - t0).abs() <= 16.0 * f64::EPSILON * t0.abs().max(t_end.abs()) {
        return input(format!(
            "t_end = {t_end} is not distinguishable from t0 = {t0}: nothing to integrate"
        ));
    }
    Ok(())
}

/// The step-size floor at time `t`: `16 eps |t|`, and never below the smallest positive
/// normal number. A step below it no longer advances `t` meaningfully (Hairer, Norsett &
/// Wanner I, II.4; Shampine & Gordon 1975, ch. 7, STEP's `FOURU`).
#[inline]
pub(crate) fn step_floor(t: f64) -> f64 {
    (16.0 * f64::EPSILON * t.abs()).max(f64::MIN_POSITIVE)
}

/// What every built-in stepper keeps the same way: the time reached, the start of the last
/// accepted step, the end of the span, whether the end was reached, and the statistics;
/// with the checks each step makes before an attempt (the attempt budget, the step-size
/// floor) and the bookkeeping of an accepted step. The steppers' own algorithms (their
/// step-size control, how they land on `t_end`) stay with them.
#[derive(Debug, Clone)]
pub(crate) struct Span {
    /// Time of the current state.
    pub(crate) t: f64,
    /// Start of the last accepted step (`t0` before the first).
    pub(crate) t_previous: f64,
    /// End of the span.
    pub(crate) t_end: f64,
    /// Whether `t_end` was reached.
    pub(crate) finished: bool,
    /// Statistics so far.
    pub(crate) stats: Stats,
}

impl Span {
    /// A span from `t0` to `t_end`, with the statistics of the start (e.g. the right-hand
    /// sides of the initial step).
    pub(crate) fn new(t0: f64, t_end: f64, stats: Stats) -> Self {
        Self {
            t: t0,
            t_previous: t0,
            t_end,
            finished: false,
            stats,
        }
    }

    /// Refuses a step once `t_end` was reached.
    ///
    /// # Errors
    /// [`IntegratorError::InvalidInput`] naming `t_end`.
    pub(crate) fn check_open(&self) -> Result<(), IntegratorError> {
        if self.finished {
            return Err(IntegratorError::InvalidInput(format!(
                "the integration already reached t_end = {}",
                self.t_end
            )));
        }
        Ok(())
    }

    /// Refuses another attempt once `max_steps` attempts (accepted and rejected) were made.
    ///
    /// # Errors
    /// [`IntegratorError::TooManySteps`] at the current time.
    pub(crate) fn check_budget(&self, max_steps: usize) -> Result<(), IntegratorError> {
        if self.stats.accepted_steps + self.stats.rejected_steps >= max_steps {
            return Err(IntegratorError::TooManySteps {
                t: self.t,
                max_steps,
            });
        }
        Ok(())
    }

    /// Refuses a step `h` below the floor ([`step_floor`]) or not a number. When
    /// non-finite values drove the step down (`non_finite`: the component of the latest
    /// rejection for non-finite values), that is the better diagnosis (e.g. a right-hand
    /// side undefined beyond some time).
    ///
    /// # Errors
    /// [`IntegratorError::NonFinite`] or [`IntegratorError::StepSizeTooSmall`] at the
    /// current time.
    pub(crate) fn check_step_size(
        &self,
        h: f64,
        non_finite: Option<usize>,
    ) -> Result<(), IntegratorError> {
        if h.abs() >= step_floor(self.t) {
            return Ok(());
        }
        Err(match non_finite {
            Some(component) => IntegratorError::NonFinite {
                t: self.t,
                component,
            },
            None => IntegratorError::StepSizeTooSmall { t: self.t, h },
        })
    }

    /// The step to attempt from a proposed signed step `h`, landing exactly on `t_end`
    /// rather than leaving a sliver: within 1 % of the end the step is stretched to it, or,
    /// when that would exceed `h_max`, the remainder is halved (DOPRI5's rule, Hairer,
    /// Norsett & Wanner I, II.10). Returns the step and whether it is the last.
    pub(crate) fn land(&self, h: f64, h_max: f64) -> (f64, bool) {
        let remaining = self.t_end - self.t;
        if remaining.abs() <= 1.01 * h.abs() {
            if remaining.abs() <= h_max {
                return (remaining, true);
            }
            return (0.5 * remaining, false);
        }
        (h, false)
    }

    /// Records an accepted step to `t_new` (`t_end` itself when it is the `last`).
    pub(crate) fn advance(&mut self, t_new: f64, last: bool) {
        self.t_previous = self.t;
        self.t = if last { self.t_end } else { t_new };
    }
}

/// A dense `n x n` LU factorisation with partial pivoting (faer), with its permutation and
/// scratch held for reuse: the implicit steppers write their iteration matrix into
/// [`DenseLu::matrix`], factor it and solve with it without allocating.
pub(crate) struct DenseLu {
    /// The matrix to factor; its LU factors after [`DenseLu::factor`].
    pub(crate) matrix: Mat<f64>,
    row_perm: Vec<usize>,
    row_perm_inv: Vec<usize>,
    stack: MemBuffer,
}

impl DenseLu {
    /// Storage for an `n x n` matrix and one right-hand side.
    pub(crate) fn new(n: usize) -> Self {
        let scratch = StackReq::any_of(&[
            lu_factor::lu_in_place_scratch::<usize, f64>(n, n, Par::Seq, Default::default()),
            lu_solve::solve_in_place_scratch::<usize, f64>(n, 1, Par::Seq),
        ]);
        Self {
            matrix: Mat::zeros(n, n),
            row_perm: vec![0; n],
            row_perm_inv: vec![0; n],
            stack: MemBuffer::new(scratch),
        }
    }

    /// Factors [`DenseLu::matrix`] in place; `false` when a pivot is zero or not finite (the
    /// matrix is singular to working precision).
    pub(crate) fn factor(&mut self) -> bool {
        lu_factor::lu_in_place(
            self.matrix.as_mut(),
            &mut self.row_perm,
            &mut self.row_perm_inv,
            Par::Seq,
            MemStack::new(&mut self.stack),
            Default::default(),
        );
        (0..self.matrix.nrows()).all(|i| {
            let p = self.matrix[(i, i)];
            p.is_finite() && p.abs() > f64::MIN_POSITIVE
        })
    }

    /// Solves with the factors in place in `rhs`.
    pub(crate) fn solve_in_place(&mut self, rhs: &mut [f64]) {
        let n = self.matrix.nrows();
        let perm = PermRef::new_checked(&self.row_perm, &self.row_perm_inv, n);
        let rhs = MatMut::from_column_major_slice_mut(rhs, n, 1);
        lu_solve::solve_in_place(
            self.matrix.as_ref(),
            self.matrix.as_ref(),
            perm,
            rhs,
            Par::Seq,
            MemStack::new(&mut self.stack),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// DOPRI5's landing rule by hand: within 1 % of the end the step goes to the end, a
    /// stretched step beyond `h_max` halves the remainder instead, and a step well short
    /// of the end is kept; backwards alike.
    #[test]
    fn landing_on_the_end() {
        let span = Span::new(0.0, 1.0, Stats::default());
        assert_eq!(span.land(0.995, 2.0), (1.0, true));
        assert_eq!(span.land(0.5, 2.0), (0.5, false));
        assert_eq!(span.land(0.995, 0.99), (0.5, false));
        let back = Span::new(1.0, 0.0, Stats::default());
        assert_eq!(back.land(-0.995, 2.0), (-1.0, true));
    }

    /// The floor is `16 eps |t|` (the smallest normal number at `t = 0`); a NaN step is
    /// refused too; non-finite values that drove the step down are named instead.
    #[test]
    fn step_size_floor() {
        let mut span = Span::new(0.0, 10.0, Stats::default());
        span.t = 1.0;
        let floor = 16.0 * f64::EPSILON;
        assert!(span.check_step_size(floor, None).is_ok());
        assert!(span.check_step_size(-floor, None).is_ok());
        assert!(matches!(
            span.check_step_size(0.5 * floor, None),
            Err(IntegratorError::StepSizeTooSmall { .. })
        ));
        assert!(matches!(
            span.check_step_size(f64::NAN, None),
            Err(IntegratorError::StepSizeTooSmall { .. })
        ));
        assert!(matches!(
            span.check_step_size(0.5 * floor, Some(3)),
            Err(IntegratorError::NonFinite { component: 3, .. })
        ));
        assert_eq!(step_floor(0.0).to_bits(), f64::MIN_POSITIVE.to_bits());
    }

    /// The attempt budget counts accepted and rejected attempts; a finished span refuses.
    #[test]
    fn budget_and_end() {
        let mut span = Span::new(0.0, 1.0, Stats::default());
        span.stats.accepted_steps = 3;
        span.stats.rejected_steps = 2;
        assert!(span.check_budget(6).is_ok());
        assert!(matches!(
            span.check_budget(5),
            Err(IntegratorError::TooManySteps { max_steps: 5, .. })
        ));
        assert!(span.check_open().is_ok());
        span.advance(0.4, false);
        assert_eq!((span.t_previous, span.t), (0.0, 0.4));
        span.advance(0.99, true);
        assert_eq!((span.t_previous, span.t), (0.4, 1.0));
        span.finished = true;
        assert!(span.check_open().is_err());
    }
}
