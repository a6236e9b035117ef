//! Input shapers (docs/planning.md, "Input shaping"): sequences of impulses `(A_j, t_j)` with
//! `sum A_j = 1` whose convolution with a command leaves little residual vibration of a
//! lightly damped mode (N. C. Singer, W. P. Seering, "Preshaping command inputs to reduce
//! system vibration", J. Dyn. Sys. Meas. Control 112, 1990; W. Singhose, W. Seering,
//! N. Singer, "Residual vibration reduction using vector diagrams to generate shaping
//! inputs", J. Mech. Design 116, 1994).
//!
//! For a mode of frequency `w` (rad/s) and damping ratio `z`, `K = exp(-z pi / sqrt(1 - z^2))`
//! and the damped half period `T = pi / (w sqrt(1 - z^2))`:
//!
//! | shaper | amplitudes | times |
//! |---|---|---|
//! | ZV | `1/(1+K), K/(1+K)` | `0, T` |
//! | ZVD | `1/(1+K)^2, 2K/(1+K)^2, K^2/(1+K)^2` | `0, T, 2T` |
//! | EI (tolerance `V`) | `(1+V)/4, (1-V)/2 K, (1+V)/4 K^2`, normalised | `0, T, 2T` |
//!
//! The EI amplitudes are the undamped ones of Singhose et al. weighted by `K^j` as the ZV and
//! ZVD amplitudes are (exact for `z = 0`; with damping the residual at the design frequency is
//! `V` times a factor within `z pi` of one, see [`residual_vibration`]). Shapers of several
//! modes are convolved ([`convolve`]). Applied to the path parameter,
//! `s_shaped(t) = sum_j A_j s(t - t_j)`, the platform stays on its path and the move is
//! longer by the last `t_j` ([`flexprr_kinematics::PlannedTrajectory::with_shaper`]).

use std::f64::consts::{PI, TAU};

use flexprr_kinematics::Impulse;
use serde::{Deserialize, Serialize};

use crate::error::PlanningError;

/// A vibration mode to shape for.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Mode {
    /// Natural frequency (Hz).
    pub frequency: f64,
    /// Damping ratio (`0 <= z < 1`).
    pub damping: f64,
}

impl Mode {
    /// An undamped mode.
    pub fn undamped(frequency: f64) -> Self {
        Self {
            frequency,
            damping: 0.0,
        }
    }

    fn check(&self) -> Result<(), PlanningError> {
        if !(self.frequency.is_finite() && self.frequency > 0.0) {
            return Err(PlanningError::InvalidSpec {
                key: "shaping frequency",
                value: self.frequency.to_string(),
                rule: "must be finite and > 0 (Hz)".into(),
            });
        }
        if !(self.damping.is_finite() && (0.0..1.0).contains(&self.damping)) {
            return Err(PlanningError::InvalidSpec {
                key: "shaping damping",
                value: self.damping.to_string(),
                rule: "must be in [0, 1)".into(),
            });
        }
        Ok(())
    }

    /// `K = exp(-z pi / sqrt(1 - z^2))` and the damped half period `T` (s).
    fn k_and_half_period(&self) -> (f64, f64) {
        let root = (1.0 - self.damping * self.damping).sqrt();
        let k = (-self.damping * PI / root).exp();
        let half = PI / (TAU * self.frequency * root);
        (k, half)
    }
}

/// Which shaper.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shaper {
    /// Zero vibration: two impulses, one half period.
    Zv,
    /// Zero vibration and derivative: three impulses, a full period.
    Zvd,
    /// Extra insensitive with tolerance `V` (0 < V < 1, e.g. 0.05): three impulses.
    Ei(f64),
}

fn from_weights(weights: [f64; 3], count: usize, half: f64) -> Vec<Impulse> {
    let total: f64 = weights[..count].iter().sum();
    (0..count)
        .map(|j| Impulse {
            amplitude: weights[j] / total,
            delay: j as f64 * half,
        })
        .collect()
}

/// The impulses of `shaper` for one `mode` (module documentation).
///
/// # Errors
/// A frequency that is not positive, a damping outside `[0, 1)`, an EI tolerance outside
/// `(0, 1)`.
pub fn design(shaper: Shaper, mode: Mode) -> Result<Vec<Impulse>, PlanningError> {
    mode.check()?;
    let (k, half) = mode.k_and_half_period();
    Ok(match shaper {
        Shaper::Zv => from_weights([1.0, k, 0.0], 2, half),
        Shaper::Zvd => from_weights([1.0, 2.0 * k, k * k], 3, half),
        Shaper::Ei(v) => {
            if !(v.is_finite() && v > 0.0 && v < 1.0) {
                return Err(PlanningError::InvalidSpec {
                    key: "shaping_tolerance",
                    value: v.to_string(),
                    rule: "must be in (0, 1): the residual vibration tolerated at the design frequency"
                        .into(),
                });
            }
            from_weights(
                [
                    0.25 * (1.0 + v),
                    0.5 * (1.0 - v) * k,
                    0.25 * (1.0 + v) * k * k,
                ],
                3,
                half,
            )
        }
    })
}

/// The convolution of two shapers: every pair of impulses, `(A_i B_j, t_i + t_j)`, with
/// coincident times merged.
pub fn convolve(a: &[Impulse], b: &[Impulse]) -> Vec<Impulse> {
    let mut out: Vec<Impulse> = Vec::with_capacity(a.len() * b.len());
    for i in a {
        for j in b {
            out.push(Impulse {
                amplitude: i.amplitude * j.amplitude,
                delay: i.delay + j.delay,
            });
        }
    }
    out.sort_by(|x, y| x.delay.total_cmp(&y.delay));
    let mut merged: Vec<Impulse> = Vec::with_capacity(out.len());
    for impulse in out {
        match merged.last_mut() {
            Some(last) if (impulse.delay - last.delay).abs() <= 1e-12 * (1.0 + last.delay) => {
                last.amplitude += impulse.amplitude;
            }
            _ => merged.push(impulse),
        }
    }
    merged
}

/// One shaper for several modes: the convolution of each mode's shaper.
///
/// # Errors
/// As [`design`]; no modes.
pub fn design_for_modes(shaper: Shaper, modes: &[Mode]) -> Result<Vec<Impulse>, PlanningError> {
    let Some((first, rest)) = modes.split_first() else {
        return Err(PlanningError::InvalidSpec {
            key: "shaping_modes",
            value: "0".into(),
            rule: "shaping needs at least one mode".into(),
        });
    };
    let mut impulses = design(shaper, *first)?;
    for mode in rest {
        impulses = convolve(&impulses, &design(shaper, *mode)?);
    }
    Ok(impulses)
}

/// Residual vibration of `mode` after the shaper: the amplitude of the ringing left at the
/// last impulse, as a fraction of the amplitude a single unit impulse (or step) starts with
/// (the "percentage vibration" of Singer & Seering):
/// `exp(-z w t_N) sqrt(C^2 + S^2)`, `C = sum A_j exp(z w t_j) cos(w_d t_j)`, `S` the same with
/// `sin`, `w_d = w sqrt(1 - z^2)`.
pub fn residual_vibration(impulses: &[Impulse], mode: Mode) -> f64 {
    let w = TAU * mode.frequency;
    let zw = mode.damping * w;
    let wd = w * (1.0 - mode.damping * mode.damping).max(0.0).sqrt();
    let last = impulses.last().map_or(0.0, |i| i.delay);
    let (mut c, mut s) = (0.0, 0.0);
    for impulse in impulses {
        // exp(z w (t_j - t_N)) keeps the terms bounded for long shapers.
        let weight = impulse.amplitude * (zw * (impulse.delay - last)).exp();
        let (sin, cos) = (wd * impulse.delay).sin_cos();
        c += weight * cos;
        s += weight * sin;
    }
    c.hypot(s)
}

/// Length of a shaper (s): its last delay, the time it adds to a move.
pub fn duration(impulses: &[Impulse]) -> f64 {
    impulses.last().map_or(0.0, |i| i.delay)
}
