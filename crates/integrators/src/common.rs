//! Pieces every method shares: the error norm and the initial step.

use crate::{IntegratorError, OdeSystem, Options};

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
