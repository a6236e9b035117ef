//! Stability margins of a loop broken at one point (docs/linear.md, "Loop margins"): the
//! gain and phase margins with their crossover frequencies and the sensitivity peak of the
//! SISO loop gain `L = -H` of a model from the break's input to its output (`H` from
//! `actuator_command:I` to `slider_command:I`: the law's command answering the actuator's).
//!
//! From the exact frequency response (Laub's Hessenberg method,
//! [`crate::frequency_response_direct`], at `z = e^(i w dt)` in discrete time: exact whatever
//! the eigenvalues' multiplicity, so a delay's shift register, a nilpotent block, is no
//! harm) on a grid of 4000 log-spaced frequencies from 1 rad/s to ten times the
//! fastest mode (to the Nyquist frequency `pi / dt` in discrete time), with 41 more about each
//! mode within a quarter of its half-power bandwidth; every crossing of `|L| = 1` and of the
//! negative real axis is refined by bisection in `log w` on the response itself (the links'
//! lightly damped modes make a machine's loop gain cross several times). Of several
//! crossings: the phase margin smallest in absolute value, the gain margin closest to 1
//! (in `|log|`). The definitions are the usual ones (Astrom & Murray, *Feedback Systems*,
//! 2nd ed., 2021, section 10.3; the sensitivity peak `M_s = max |1 / (1 + L)|`, section
//! 13.3).

use crate::{Complex, LinearError, Linearization, frequency_response_direct, modes};

/// The margins of one loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopMargins {
    /// The factor by which the loop gain can grow before the loop is unstable
    /// (`1 / |L|` where `L` crosses the negative real axis); infinite without a crossing.
    pub gain_margin: f64,
    /// `180 deg + arg L` at the gain crossover (deg); infinite when `|L|` never reaches 1.
    pub phase_margin_deg: f64,
    /// Where `|L| = 1` (Hz); NaN without one.
    pub gain_crossover_hz: f64,
    /// Where `L` crosses the negative real axis (Hz); NaN without one.
    pub phase_crossover_hz: f64,
    /// `max |1 / (1 + L)|` over the grid.
    pub sensitivity_peak: f64,
    /// Where it is reached (Hz).
    pub sensitivity_peak_hz: f64,
}

/// `L = -H` at the angular frequencies `w` (rad/s).
fn loop_gain(lin: &Linearization, w: &[f64]) -> Result<Vec<Complex>, LinearError> {
    let hz: Vec<f64> = w.iter().map(|w| w / std::f64::consts::TAU).collect();
    Ok(frequency_response_direct(lin, &hz)?
        .into_iter()
        .map(|h| h[0][0].scale(-1.0))
        .collect())
}

/// The root of `f` between `lo` and `hi` (a sign change) by bisection in `log w`.
fn refine(
    f: &dyn Fn(f64) -> Result<f64, LinearError>,
    mut lo: f64,
    mut hi: f64,
) -> Result<f64, LinearError> {
    let mut below = f(lo)? < 0.0;
    for _ in 0..60 {
        let mid = (lo * hi).sqrt();
        if (f(mid)? < 0.0) == below {
            lo = mid;
            below = f(lo)? < 0.0;
        } else {
            hi = mid;
        }
        if hi / lo - 1.0 < 1e-12 {
            break;
        }
    }
    Ok((lo * hi).sqrt())
}

/// The default grid (rad/s) of [`loop_margins`].
///
/// # Errors
/// The modes of the model failed.
pub fn margin_grid(lin: &Linearization) -> Result<Vec<f64>, LinearError> {
    let modes = modes(lin)?;
    let fastest =
        modes.iter().map(|m| m.frequency_hz).fold(1.0f64, f64::max) * std::f64::consts::TAU;
    let top = if lin.dt > 0.0 {
        std::f64::consts::PI / lin.dt
    } else {
        10.0 * fastest
    };
    let mut w: Vec<f64> = (0..4000).map(|k| top.powf(f64::from(k) / 3999.0)).collect();
    for m in &modes {
        let wn = m.frequency_hz * std::f64::consts::TAU;
        let band = m.damping_ratio.abs().clamp(1e-4, 0.05);
        w.extend((-20..=20).map(|k| wn * (1.0 + 0.25 * band * f64::from(k))));
    }
    w.retain(|w| *w > 0.0 && *w <= top);
    w.sort_by(f64::total_cmp);
    w.dedup_by(|a, b| (*a - *b).abs() <= 1e-14 * b.abs());
    Ok(w)
}

/// The margins of the SISO model `lin` (one input, one output), its loop gain `L = -H`.
///
/// # Errors
/// Not one input and one output, or the response failed.
pub fn loop_margins(lin: &Linearization) -> Result<LoopMargins, LinearError> {
    if lin.b.ncols() != 1 || lin.c.nrows() != 1 {
        return Err(LinearError::Channel(format!(
            "loop margins need one input and one output (the loop broken at one point), got {} and {}",
            lin.b.ncols(),
            lin.c.nrows()
        )));
    }
    let w = margin_grid(lin)?;
    let h = loop_gain(lin, &w)?;
    let at = |x: f64| -> Result<Complex, LinearError> { Ok(loop_gain(lin, &[x])?[0]) };
    let (mut pm, mut wgc) = (f64::INFINITY, f64::NAN);
    for k in 0..w.len() - 1 {
        if (h[k].norm() - 1.0).signum() != (h[k + 1].norm() - 1.0).signum() {
            let wc = refine(&|x| Ok(at(x)?.norm() - 1.0), w[k], w[k + 1])?;
            let mut margin = 180.0 + at(wc)?.arg().to_degrees();
            if margin > 180.0 {
                margin -= 360.0;
            }
            if margin.abs() < pm.abs() {
                (pm, wgc) = (margin, wc);
            }
        }
    }
    let (mut gm, mut wpc) = (f64::INFINITY, f64::NAN);
    for k in 0..w.len() - 1 {
        if h[k].im.signum() == h[k + 1].im.signum() || (h[k].re >= 0.0 && h[k + 1].re >= 0.0) {
            continue;
        }
        let wc = refine(&|x| Ok(at(x)?.im), w[k], w[k + 1])?;
        let value = at(wc)?;
        if value.re < 0.0 {
            let g = 1.0 / value.re.abs();
            if g.ln().abs() < gm.ln().abs() {
                (gm, wpc) = (g, wc);
            }
        }
    }
    let (mut peak, mut w_peak) = (0.0f64, w[0]);
    for (l, x) in h.iter().zip(&w) {
        let s = 1.0 / Complex::new(1.0 + l.re, l.im).norm();
        if s > peak {
            (peak, w_peak) = (s, *x);
        }
    }
    let hz = |x: f64| x / std::f64::consts::TAU;
    Ok(LoopMargins {
        gain_margin: gm,
        phase_margin_deg: pm,
        gain_crossover_hz: hz(wgc),
        phase_crossover_hz: hz(wpc),
        sensitivity_peak: peak,
        sensitivity_peak_hz: hz(w_peak),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Mat;

    /// `L = 30 / ((s + 1)(s + 2)(s + 3))` as `H = -L` in companion form.
    fn third_order() -> Linearization {
        // (s+1)(s+2)(s+3) = s^3 + 6 s^2 + 11 s + 6.
        let a = Mat::from_fn(3, 3, |i, j| match (i, j) {
            (0, 1) | (1, 2) => 1.0,
            (2, 0) => -6.0,
            (2, 1) => -11.0,
            (2, 2) => -6.0,
            _ => 0.0,
        });
        let b = Mat::from_fn(3, 1, |i, _| if i == 2 { 1.0 } else { 0.0 });
        let c = Mat::from_fn(1, 3, |_, j| if j == 0 { -30.0 } else { 0.0 });
        Linearization::from_matrices(a, b, c, Mat::zeros(1, 1), 0.0)
    }

    #[test]
    fn the_margins_of_a_third_order_loop_are_its_closed_forms() {
        let m = loop_margins(&third_order()).unwrap();
        // Phase crossover: Im (i w + 1)(i w + 2)(i w + 3) = 11 w - w^3 = 0, w = sqrt(11);
        // there the denominator is 6 - 6 * 11 = -60: L = -0.5, gain margin 2.
        assert!((m.gain_margin - 2.0).abs() < 1e-9, "{m:?}");
        assert!((m.phase_crossover_hz * std::f64::consts::TAU - 11f64.sqrt()).abs() < 1e-9);
        // Gain crossover: (w^2 + 1)(w^2 + 4)(w^2 + 9) = 900, solved here by bisection on
        // the polynomial; the phase margin is 180 deg minus the three lags there.
        let (mut lo, mut hi) = (0.1f64, 10.0f64);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            let x = mid * mid;
            if (x + 1.0) * (x + 4.0) * (x + 9.0) < 900.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let wc = 0.5 * (lo + hi);
        let pm = 180.0 - (wc.atan() + (wc / 2.0).atan() + (wc / 3.0).atan()).to_degrees();
        assert!((m.gain_crossover_hz * std::f64::consts::TAU - wc).abs() < 1e-9 * wc);
        assert!(
            (m.phase_margin_deg - pm).abs() < 1e-8,
            "{} {pm}",
            m.phase_margin_deg
        );
        assert!(m.sensitivity_peak > 1.0 && m.sensitivity_peak.is_finite());
    }
}
