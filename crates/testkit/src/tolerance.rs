//! Tolerance helpers: every comparison is `|a - b| <= atol + rtol |b|` with `b` the expected
//! (independent) value, the componentwise error test of Hairer, Norsett & Wanner, *Solving
//! Ordinary Differential Equations I*, section II.4 (eq. 4.10). Never `==` on floats.
//!
//! ```
//! use flexprr_testkit::{assert_close, relative_error};
//!
//! // pi^2 EI / l^2 against its closed form written out.
//! let ei = 7.3e10 * 0.03 * 0.002_f64.powi(3) / 12.0;
//! let euler = std::f64::consts::PI.powi(2) * ei / 0.04;
//! assert_close(euler, 360.24, 1e-5, 0.0, "Euler load (N)");
//! assert!(relative_error(&[1.0, 2.0], &[1.0, 2.0 + 1e-12]) < 1e-12);
//! ```

/// Euclidean relative error `|a - b|_2 / |b|_2` of `a` against the expected `b`.
///
/// # Panics
/// If the lengths differ, or the norm of `b` is zero or not finite (a relative error is then
/// undefined): the message names the lengths or the norm.
pub fn relative_error(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(
        a.len(),
        b.len(),
        "relative_error: {} values against {} expected",
        a.len(),
        b.len()
    );
    let diff = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt();
    let norm = b.iter().map(|y| y * y).sum::<f64>().sqrt();
    assert!(
        norm.is_finite() && norm > 0.0,
        "relative_error: the expected values have norm {norm}, a relative error is undefined"
    );
    diff / norm
}

/// Largest componentwise error scaled by `atol + rtol |expected|` (at most 1 means every
/// component passes the mixed test). NaN in either input gives NaN, which fails every `<=`.
///
/// # Panics
/// If the lengths differ, or both tolerances are zero.
pub fn max_scaled_error(actual: &[f64], expected: &[f64], rtol: f64, atol: f64) -> f64 {
    assert_eq!(
        actual.len(),
        expected.len(),
        "max_scaled_error: {} values against {} expected",
        actual.len(),
        expected.len()
    );
    assert!(
        rtol >= 0.0 && atol >= 0.0 && rtol + atol > 0.0,
        "max_scaled_error: tolerances rtol = {rtol}, atol = {atol} must be >= 0, not both 0"
    );
    let mut worst = 0.0_f64;
    for (a, b) in actual.iter().zip(expected) {
        let e = (a - b).abs() / (atol + rtol * b.abs());
        if e.is_nan() {
            return f64::NAN;
        }
        worst = worst.max(e);
    }
    worst
}

/// Asserts `|actual - expected| <= atol + rtol |expected|`; the message names `what`, both
/// values, the error and the tolerance. NaN or infinite values always fail.
///
/// # Panics
/// When the check fails (that is the assertion), or both tolerances are zero.
#[track_caller]
pub fn assert_close(actual: f64, expected: f64, rtol: f64, atol: f64, what: &str) {
    assert!(
        rtol >= 0.0 && atol >= 0.0 && rtol + atol > 0.0,
        "assert_close({what}): tolerances rtol = {rtol}, atol = {atol} must be >= 0, not both 0"
    );
    let error = (actual - expected).abs();
    let tolerance = atol + rtol * expected.abs();
    assert!(
        actual.is_finite() && expected.is_finite() && error <= tolerance,
        "{what}: {actual:e} against {expected:e}: error {error:.3e} > tolerance {tolerance:.3e} \
         (rtol {rtol:e}, atol {atol:e})"
    );
}

/// [`assert_close`] componentwise; the message names `what`, the first failing index and both
/// values.
///
/// # Panics
/// When a component fails, the lengths differ, or both tolerances are zero.
#[track_caller]
pub fn assert_slices_close(actual: &[f64], expected: &[f64], rtol: f64, atol: f64, what: &str) {
    assert_eq!(
        actual.len(),
        expected.len(),
        "{what}: {} values against {} expected",
        actual.len(),
        expected.len()
    );
    for (i, (a, b)) in actual.iter().zip(expected).enumerate() {
        assert_close(*a, *b, rtol, atol, &format!("{what}[{i}]"));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_error_of_a_known_perturbation() {
        // b = (3, 4), |b| = 5; a = b + (0, 1e-3): error 1e-3 / 5.
        let e = relative_error(&[3.0, 4.001], &[3.0, 4.0]);
        assert!((e - 2e-4).abs() <= 1e-15, "{e}");
    }

    #[test]
    #[should_panic(expected = "norm 0")]
    fn relative_error_to_zero_is_refused() {
        relative_error(&[1.0], &[0.0]);
    }

    #[test]
    fn scaled_error_is_one_on_the_boundary_and_nan_propagates() {
        // |1.1 - 1| = 0.1 = atol 0.05 + rtol 0.05 * 1.
        let e = max_scaled_error(&[1.1, 2.0], &[1.0, 2.0], 0.05, 0.05);
        assert!((e - 1.0).abs() <= 1e-12, "{e}");
        assert!(max_scaled_error(&[f64::NAN], &[1.0], 1e-3, 0.0).is_nan());
    }

    #[test]
    fn assert_close_passes_inside_and_fails_outside() {
        assert_close(1.0 + 1e-10, 1.0, 1e-9, 0.0, "inside");
        let outside = std::panic::catch_unwind(|| assert_close(1.0 + 1e-8, 1.0, 1e-9, 0.0, "x"));
        assert!(outside.is_err());
        let nan = std::panic::catch_unwind(|| assert_close(f64::NAN, 1.0, 1.0, 1.0, "nan"));
        assert!(nan.is_err());
    }

    #[test]
    #[should_panic(expected = "v[1]")]
    fn slices_name_the_failing_index() {
        assert_slices_close(&[1.0, 2.5], &[1.0, 2.0], 1e-6, 0.0, "v");
    }
}
