//! Peaks, RMS values and first crossings of sampled series.

use serde_json::{Value, json};

/// The largest absolute value of a series and when it occurs.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Peak {
    /// `max |x_k|`.
    pub value: f64,
    /// The time of the first sample where it occurs (s).
    pub t: f64,
}

impl Peak {
    /// The peak of `x` sampled at `t` (zero at the first time for an empty series).
    pub fn of(t: &[f64], x: &[f64]) -> Self {
        let mut peak = Peak {
            value: 0.0,
            t: t.first().copied().unwrap_or(0.0),
        };
        for (tk, xk) in t.iter().zip(x) {
            if xk.abs() > peak.value {
                peak = Peak {
                    value: xk.abs(),
                    t: *tk,
                };
            }
        }
        peak
    }
}

/// `sqrt(mean(x_k^2))` over the samples: the RMS value over the time span for the run's
/// evenly spaced output times (0 for an empty series).
pub fn rms(x: &[f64]) -> f64 {
    // Scaled by the largest magnitude, so that the squares of huge values do not overflow.
    let scale = x.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    if scale == 0.0 || !scale.is_finite() {
        return scale;
    }
    scale * (x.iter().map(|v| (v / scale).powi(2)).sum::<f64>() / x.len() as f64).sqrt()
}

/// The first time at which `|x|` exceeds `limit`: the first sample if it already does,
/// else the crossing interpolated linearly in `|x|` between the last sample at or below the
/// limit and the first above it. `None` when `|x|` stays at or below the limit.
pub fn first_crossing(t: &[f64], x: &[f64], limit: f64) -> Option<f64> {
    let k = x.iter().position(|v| v.abs() > limit)?;
    if k == 0 {
        return Some(t[0]);
    }
    let (a, b) = (x[k - 1].abs(), x[k].abs());
    let s = ((limit - a) / (b - a)).clamp(0.0, 1.0);
    Some(t[k - 1] + s * (t[k] - t[k - 1]))
}

/// `rating / required`: how many times the requirement fits into the rating (1 or more is
/// within it); `null` in JSON when the requirement is zero.
pub fn margin(rating: f64, required: f64) -> Option<f64> {
    let m = rating / required;
    m.is_finite().then_some(m)
}

/// `x` with four significant digits and no trailing zeros, for messages (`100`, `830.7`,
/// `0.0125`).
pub fn sig(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    if !(1e-4..1e7).contains(&x.abs()) {
        // Four significant digits with an exponent: `1.235e12`, `2.5e-7`.
        let text = format!("{x:.3e}");
        let (mantissa, exponent) = text.split_once('e').unwrap_or((&text, "0"));
        let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
        return format!("{mantissa}e{exponent}");
    }
    let decimals = (3 - x.abs().log10().floor() as i32).max(0) as usize;
    let text = format!("{x:.decimals$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

/// A number, or `null` when it is not finite.
pub fn num(v: f64) -> Value {
    number(Some(v))
}

/// A number, or `null` when it is not finite or absent.
pub fn number(v: Option<f64>) -> Value {
    match v {
        Some(v) if v.is_finite() => json!(v),
        _ => Value::Null,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn peaks_rms_and_crossings_of_a_ramp() {
        let t = [0.0, 1.0, 2.0, 3.0];
        let x = [0.0, -1.0, 2.0, -3.0];
        assert_eq!(Peak::of(&t, &x), Peak { value: 3.0, t: 3.0 });
        assert!((rms(&x) - (14.0f64 / 4.0).sqrt()).abs() < 1e-15);
        // |x| passes 1.5 halfway between t = 1 (1) and t = 2 (2).
        assert_eq!(first_crossing(&t, &x, 1.5), Some(1.5));
        assert_eq!(first_crossing(&t, &x, -1.0), Some(0.0));
        assert_eq!(first_crossing(&t, &x, 3.0), None);
        assert_eq!(margin(3.5, 7.0), Some(0.5));
        assert_eq!(margin(3.5, 0.0), None);
        assert_eq!(sig(100.0), "100");
        assert_eq!(sig(830.73567), "830.7");
        assert_eq!(sig(0.0125), "0.0125");
        assert_eq!(sig(49844.1), "49844");
        assert_eq!(sig(0.0), "0");
        assert_eq!(sig(1.23456e200), "1.235e200");
        assert_eq!(sig(-2.5e-7), "-2.5e-7");
        // Huge values: no overflow of the squares.
        assert!((rms(&[3e200, -4e200]) - 12.5_f64.sqrt() * 1e200).abs() < 1e188);
    }
}
