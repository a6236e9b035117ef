//! A planned motion: a geometric [`Path`] and a timing `s(t)` (docs/planning.md, "The planned
//! trajectory").
//!
//! The timing of a time-optimal path parameterization on a grid `s_0 < ... < s_N` is exactly
//! the grid's path speeds `s_dot_k`: with `x = s_dot^2` piecewise linear in `s` (a constant
//! path acceleration `u_k = (x_{k+1} - x_k) / (2 (s_{k+1} - s_k))` on each segment, Pham &
//! Pham 2018), `s(t)` is piecewise quadratic and each segment lasts
//! `2 (s_{k+1} - s_k) / (s_dot_k + s_dot_{k+1})`. [`Timing`] holds that form.
//!
//! Two linear filters of `s(t)` keep the platform on its path while changing the timing:
//! * input shaping, `s_shaped(t) = sum_j A_j s(t - t_j)` with `sum_j A_j = 1` (Singer &
//!   Seering 1990; the impulses of a ZV, ZVD or EI shaper);
//! * a moving average over a window `W`, `s_W(t) = (1/W) int_{t-W}^t s`, whose third
//!   derivative `(s''(t) - s''(t - W)) / W` is bounded: the jerk-limited smoothing of a
//!   piecewise-quadratic timing.
//!
//! [`PlannedTrajectory`] composes path, timing and filters into a [`Trajectory`];
//! [`PlannedData`] is its serialisable form (for a scene's `planned.toml`).

use serde::{Deserialize, Serialize};

use crate::error::KinematicsError;
use crate::path::{GeometricPath, Path};
use crate::pose::PlatformMotion;
use crate::trajectory::Trajectory;

/// An [`KinematicsError::InvalidPlan`] for `field` (at `index`).
pub(crate) fn bad(
    field: &'static str,
    index: Option<usize>,
    value: f64,
    reason: &'static str,
) -> KinematicsError {
    KinematicsError::InvalidPlan {
        field,
        index,
        value,
        reason,
    }
}

/// The path parameter and its first three time derivatives at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PathState {
    /// `s` (unwrapped: a periodic timing keeps counting past the path's length).
    pub s: f64,
    /// `s' = ds/dt`.
    pub s_dot: f64,
    /// `s''`.
    pub s_ddot: f64,
    /// `s'''`, between breakpoints (a timing without smoothing has jumps of `s''` at its
    /// breakpoints, impulses of `s'''` that this value does not show).
    pub s_dddot: f64,
}

impl PathState {
    fn scaled_add(&mut self, weight: f64, other: &PathState) {
        self.s += weight * other.s;
        self.s_dot += weight * other.s_dot;
        self.s_ddot += weight * other.s_ddot;
        self.s_dddot += weight * other.s_dddot;
    }
}

/// A piecewise-quadratic timing `s(t)` from the path speeds `s_dot_k` at grid points `s_k`
/// (constant `s''` on each segment, see the module documentation). Rest-to-rest timings start
/// and end at rest and hold still outside `[0, T]`; periodic timings repeat with period `T`,
/// `s(t + T) = s(t) + (s_N - s_0)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Timing {
    s: Vec<f64>,
    s_dot: Vec<f64>,
    t: Vec<f64>,
    u: Vec<f64>,
    integral: Vec<f64>,
    periodic: bool,
}

impl Timing {
    /// A timing from the grid `s` (strictly increasing, at least two points) and the path
    /// speeds `s_dot` (finite, `>= 0`, never zero at both ends of a segment). Rest-to-rest
    /// (`periodic = false`): `s_dot` is zero at both ends. Periodic: `s_dot` is positive and
    /// equal (to 1e-9 relative) at both ends.
    ///
    /// # Errors
    /// [`KinematicsError::InvalidPlan`] naming the field and index that break a rule.
    pub fn new(s: Vec<f64>, s_dot: Vec<f64>, periodic: bool) -> Result<Self, KinematicsError> {
        let n = s.len();
        if n < 2 {
            return Err(bad("s", None, n as f64, "need at least 2 grid points"));
        }
        if s_dot.len() != n {
            return Err(bad(
                "s_dot",
                None,
                s_dot.len() as f64,
                "must have as many entries as s",
            ));
        }
        for k in 0..n {
            if !s[k].is_finite() {
                return Err(bad("s", Some(k), s[k], "must be finite"));
            }
            if k > 0 && s[k] <= s[k - 1] {
                return Err(bad("s", Some(k), s[k], "must increase strictly"));
            }
            if !(s_dot[k].is_finite() && s_dot[k] >= 0.0) {
                return Err(bad("s_dot", Some(k), s_dot[k], "must be finite and >= 0"));
            }
            if k > 0 && s_dot[k] + s_dot[k - 1] <= 0.0 {
                return Err(bad(
                    "s_dot",
                    Some(k),
                    s_dot[k],
                    "zero at both ends of a segment: the segment would never be traversed",
                ));
            }
        }
        if periodic {
            let (a, b) = (s_dot[0], s_dot[n - 1]);
            if a <= 0.0 || (a - b).abs() > 1e-9 * a.max(b) {
                return Err(bad(
                    "s_dot",
                    Some(n - 1),
                    b,
                    "a periodic timing needs equal positive path speeds at both ends",
                ));
            }
        } else {
            for k in [0, n - 1] {
                if s_dot[k] > 0.0 {
                    return Err(bad(
                        "s_dot",
                        Some(k),
                        s_dot[k],
                        "a rest-to-rest timing starts and ends at rest (0)",
                    ));
                }
            }
        }
        let mut t = vec![0.0; n];
        let mut u = vec![0.0; n - 1];
        let mut integral = vec![0.0; n];
        for k in 0..n - 1 {
            let ds = s[k + 1] - s[k];
            let h = 2.0 * ds / (s_dot[k] + s_dot[k + 1]);
            u[k] = (s_dot[k + 1] * s_dot[k + 1] - s_dot[k] * s_dot[k]) / (2.0 * ds);
            t[k + 1] = t[k] + h;
            integral[k + 1] = integral[k] + h * (s[k] + h * (0.5 * s_dot[k] + h * u[k] / 6.0));
        }
        Ok(Self {
            s,
            s_dot,
            t,
            u,
            integral,
            periodic,
        })
    }

    /// Duration `T` (s): of the move, or the period.
    pub fn duration(&self) -> f64 {
        self.t[self.t.len() - 1]
    }

    /// Whether the timing repeats.
    pub fn is_periodic(&self) -> bool {
        self.periodic
    }

    /// The grid `s_k`.
    pub fn grid(&self) -> &[f64] {
        &self.s
    }

    /// The path speeds `s_dot_k` at the grid.
    pub fn speeds(&self) -> &[f64] {
        &self.s_dot
    }

    /// The times `t_k` at which the grid points are reached (`t_0 = 0`).
    pub fn times(&self) -> &[f64] {
        &self.t
    }

    /// The constant path acceleration `u_k` of each segment.
    pub fn accelerations(&self) -> &[f64] {
        &self.u
    }

    fn span(&self) -> f64 {
        self.s[self.s.len() - 1] - self.s[0]
    }

    /// Segment index and time since its start for `tau` in `[0, T]`.
    #[inline]
    fn locate(&self, tau: f64) -> (usize, f64) {
        let n = self.t.len();
        let k = (self.t.partition_point(|&tk| tk <= tau).max(1) - 1).min(n - 2);
        (k, tau - self.t[k])
    }

    /// Splits `tau` into whole periods and the time within one (periodic timings).
    #[inline]
    fn wrap(&self, tau: f64) -> (f64, f64) {
        let period = self.duration();
        let n = (tau / period).floor();
        (n, (tau - n * period).clamp(0.0, period))
    }

    /// `s`, `s'`, `s''` at `tau` (s since the timing's start); `s''' = 0` between grid times.
    pub fn state(&self, tau: f64) -> PathState {
        let last = self.s.len() - 1;
        let (periods, tau) = if self.periodic {
            self.wrap(tau)
        } else if tau <= 0.0 {
            return PathState {
                s: self.s[0],
                ..PathState::default()
            };
        } else if tau >= self.duration() {
            return PathState {
                s: self.s[last],
                ..PathState::default()
            };
        } else {
            (0.0, tau)
        };
        let (k, h) = self.locate(tau);
        let u = self.u[k];
        PathState {
            s: self.s[k] + h * (self.s_dot[k] + 0.5 * u * h) + periods * self.span(),
            s_dot: self.s_dot[k] + u * h,
            s_ddot: u,
            s_dddot: 0.0,
        }
    }

    /// `int_0^tau s(t) dt`, for any `tau` (held or repeated outside `[0, T]`).
    fn integral(&self, tau: f64) -> f64 {
        let last = self.s.len() - 1;
        let total = self.integral[last];
        if self.periodic {
            let (n, local) = self.wrap(tau);
            let (k, h) = self.locate(local);
            let inner = self.integral[k]
                + h * (self.s[k] + h * (0.5 * self.s_dot[k] + h * self.u[k] / 6.0));
            let period = self.duration();
            n * total + self.span() * (period * 0.5 * n * (n - 1.0) + n * local) + inner
        } else if tau <= 0.0 {
            self.s[0] * tau
        } else if tau >= self.duration() {
            total + self.s[last] * (tau - self.duration())
        } else {
            let (k, h) = self.locate(tau);
            self.integral[k] + h * (self.s[k] + h * (0.5 * self.s_dot[k] + h * self.u[k] / 6.0))
        }
    }

    /// `int_a^b s(t) dt`; periodic timings are shifted by whole periods first, so that the
    /// difference of integrals is taken near the origin (no loss of precision late in a run).
    fn window_integral(&self, a: f64, b: f64) -> f64 {
        if self.periodic {
            let period = self.duration();
            let n = (a / period).floor();
            let shift = n * period;
            self.integral(b - shift) - self.integral(a - shift) + n * self.span() * (b - a)
        } else {
            self.integral(b) - self.integral(a)
        }
    }

    /// The state of the timing averaged over the window `[tau - w, tau]` (`w > 0`): the
    /// jerk-limited smoothing, `s''' = (s''(tau) - s''(tau - w)) / w`.
    pub fn smoothed_state(&self, tau: f64, w: f64) -> PathState {
        let (now, before) = (self.state(tau), self.state(tau - w));
        PathState {
            s: self.window_integral(tau - w, tau) / w,
            s_dot: (now.s - before.s) / w,
            s_ddot: (now.s_dot - before.s_dot) / w,
            s_dddot: (now.s_ddot - before.s_ddot) / w,
        }
    }
}

/// One impulse of an input shaper: amplitude and delay (s).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Impulse {
    /// Amplitude `A_j` (the amplitudes of a shaper sum to one).
    pub amplitude: f64,
    /// Delay `t_j >= 0` (s).
    pub delay: f64,
}

/// Checks a shaper's impulses: finite, delays `>= 0` and ascending, amplitudes summing to one
/// (to 1e-9), so that the shaped timing still ends at the end of the path.
///
/// # Errors
/// [`KinematicsError::InvalidPlan`] on the field `shaper`.
pub fn check_impulses(impulses: &[Impulse]) -> Result<(), KinematicsError> {
    let mut sum = 0.0;
    for (j, impulse) in impulses.iter().enumerate() {
        if !impulse.amplitude.is_finite() {
            return Err(bad(
                "shaper amplitude",
                Some(j),
                impulse.amplitude,
                "must be finite",
            ));
        }
        if !(impulse.delay.is_finite() && impulse.delay >= 0.0) {
            return Err(bad(
                "shaper delay",
                Some(j),
                impulse.delay,
                "must be finite and >= 0",
            ));
        }
        if j > 0 && impulse.delay < impulses[j - 1].delay {
            return Err(bad(
                "shaper delay",
                Some(j),
                impulse.delay,
                "delays must be ascending",
            ));
        }
        sum += impulse.amplitude;
    }
    if !impulses.is_empty() && (sum - 1.0).abs() > 1e-9 {
        return Err(bad(
            "shaper amplitudes",
            None,
            sum,
            "must sum to 1 (the shaped motion must reach the end of the path)",
        ));
    }
    Ok(())
}

/// A path and a timing as a [`Trajectory`], optionally shaped and smoothed (module
/// documentation):
/// `s_final(t) = sum_j A_j s_W(t - t_start - t_j)`, pose `p(s_final)`, twist `p' s'`,
/// its rate `p' s'' + p'' s'^2`.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedTrajectory<P = GeometricPath> {
    path: P,
    timing: Timing,
    impulses: Vec<Impulse>,
    smoothing: f64,
    start: f64,
    horizon: f64,
}

impl<P: Path> PlannedTrajectory<P> {
    /// The trajectory of `path` under `timing` starting at `start` (s), unshaped and unsmoothed.
    ///
    /// # Errors
    /// A timing whose grid leaves `[0, S]` of the path (to 1e-9 relative), a periodic timing on
    /// an open path or one that does not cover exactly `[0, S]`, a non-finite start.
    pub fn new(path: P, timing: Timing, start: f64) -> Result<Self, KinematicsError> {
        let length = path.length();
        let grid = timing.grid();
        let (first, last) = (grid[0], grid[grid.len() - 1]);
        let tolerance = 1e-9 * length;
        if first < -tolerance {
            return Err(bad(
                "s",
                Some(0),
                first,
                "must be >= 0 (the path starts at 0)",
            ));
        }
        if last > length + tolerance {
            return Err(bad(
                "s",
                Some(grid.len() - 1),
                last,
                "beyond the end of the path",
            ));
        }
        if timing.is_periodic() {
            if !path.is_closed() {
                return Err(bad(
                    "periodic",
                    None,
                    1.0,
                    "a periodic timing needs a closed path",
                ));
            }
            if first.abs() > tolerance || (last - length).abs() > tolerance {
                return Err(bad(
                    "s",
                    Some(grid.len() - 1),
                    last,
                    "a periodic timing covers the whole closed path, s from 0 to its length",
                ));
            }
        }
        if !start.is_finite() {
            return Err(bad("start", None, start, "must be finite"));
        }
        let horizon = start + timing.duration();
        Ok(Self {
            path,
            timing,
            impulses: Vec::new(),
            smoothing: 0.0,
            start,
            horizon,
        })
    }

    /// The same motion shaped by `impulses` ([`check_impulses`]).
    ///
    /// # Errors
    /// As [`check_impulses`].
    pub fn with_shaper(mut self, impulses: Vec<Impulse>) -> Result<Self, KinematicsError> {
        check_impulses(&impulses)?;
        self.impulses = impulses;
        Ok(self)
    }

    /// The same motion averaged over a window of `window >= 0` seconds (0: none).
    ///
    /// # Errors
    /// A negative or non-finite window.
    pub fn with_smoothing(mut self, window: f64) -> Result<Self, KinematicsError> {
        if !(window.is_finite() && window >= 0.0) {
            return Err(bad(
                "smoothing",
                None,
                window,
                "must be finite and >= 0 (s)",
            ));
        }
        self.smoothing = window;
        Ok(self)
    }

    /// Time up to which a periodic trajectory lists its [`Trajectory::breakpoints`] (a
    /// scene's end time); one period by default. Ignored for rest-to-rest motions.
    pub fn with_horizon(mut self, end: f64) -> Self {
        self.horizon = end;
        self
    }

    /// The path.
    pub fn path(&self) -> &P {
        &self.path
    }

    /// The timing before shaping and smoothing.
    pub fn timing(&self) -> &Timing {
        &self.timing
    }

    /// The shaper's impulses (empty: unshaped).
    pub fn impulses(&self) -> &[Impulse] {
        &self.impulses
    }

    /// The smoothing window (s, 0: none).
    pub fn smoothing(&self) -> f64 {
        self.smoothing
    }

    /// Start time (s).
    pub fn start(&self) -> f64 {
        self.start
    }

    /// Time the shaper and the smoothing add to the move (s): the last delay plus the window.
    pub fn extra_time(&self) -> f64 {
        self.impulses.last().map_or(0.0, |i| i.delay) + self.smoothing
    }

    /// The period (s) of a periodic motion.
    pub fn period(&self) -> Option<f64> {
        self.timing.is_periodic().then(|| self.timing.duration())
    }

    fn filtered(&self, tau: f64) -> PathState {
        if self.smoothing > 0.0 {
            self.timing.smoothed_state(tau, self.smoothing)
        } else {
            self.timing.state(tau)
        }
    }

    /// The path parameter and its derivatives at time `t` (s), after shaping and smoothing.
    pub fn path_state(&self, t: f64) -> PathState {
        let tau = t - self.start;
        if self.impulses.is_empty() {
            return self.filtered(tau);
        }
        let mut state = PathState::default();
        for impulse in &self.impulses {
            state.scaled_add(impulse.amplitude, &self.filtered(tau - impulse.delay));
        }
        state
    }
}

impl<P: Path> Trajectory for PlannedTrajectory<P> {
    fn motion(&self, t: f64) -> PlatformMotion {
        let state = self.path_state(t);
        self.path.point(state.s).motion(state.s_dot, state.s_ddot)
    }

    fn duration(&self) -> Option<f64> {
        (!self.timing.is_periodic())
            .then(|| self.start + self.timing.duration() + self.extra_time())
    }

    /// Every time at which `s''` (or, smoothed, `s'''`) jumps: the grid times shifted by each
    /// impulse's delay and, smoothed, by the window too; periodic motions repeat them up to
    /// the horizon ([`PlannedTrajectory::with_horizon`]).
    fn breakpoints(&self) -> Vec<f64> {
        let delays: Vec<f64> = if self.impulses.is_empty() {
            vec![0.0]
        } else {
            self.impulses.iter().map(|i| i.delay).collect()
        };
        let windows: &[f64] = if self.smoothing > 0.0 {
            &[0.0, self.smoothing]
        } else {
            &[0.0]
        };
        let period = self.timing.duration();
        let repeats = if self.timing.is_periodic() {
            ((self.horizon - self.start) / period).ceil().max(1.0) as usize
        } else {
            1
        };
        let mut times = Vec::with_capacity(self.timing.times().len() * delays.len() * 2);
        for r in 0..repeats {
            for &delay in &delays {
                for &window in windows {
                    let offset = self.start + delay + window + r as f64 * period;
                    times.extend(self.timing.times().iter().map(|t| t + offset));
                }
            }
        }
        times.sort_by(f64::total_cmp);
        times.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * (1.0 + b.abs()));
        times
    }
}

/// The serialisable form of a [`PlannedTrajectory`] on a [`GeometricPath`]: what a scene's
/// `planned.toml` stores as its trajectory. SI units, angles in rad.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlannedData {
    /// The path.
    pub path: GeometricPath,
    /// Grid of the path parameter, from 0 (strictly increasing).
    pub s: Vec<f64>,
    /// Path speed at each grid point (`>= 0`).
    pub s_dot: Vec<f64>,
    /// Whether the timing repeats (closed paths only).
    #[serde(default)]
    pub periodic: bool,
    /// Start time (s).
    #[serde(default)]
    pub start: f64,
    /// Shaper impulses `[amplitude, delay (s)]` (empty: unshaped).
    #[serde(default)]
    pub shaper: Vec<[f64; 2]>,
    /// Smoothing window (s, 0: none).
    #[serde(default)]
    pub smoothing: f64,
}

impl TryFrom<PlannedData> for PlannedTrajectory<GeometricPath> {
    type Error = KinematicsError;
    fn try_from(data: PlannedData) -> Result<Self, KinematicsError> {
        let timing = Timing::new(data.s, data.s_dot, data.periodic)?;
        let impulses = data
            .shaper
            .iter()
            .map(|[amplitude, delay]| Impulse {
                amplitude: *amplitude,
                delay: *delay,
            })
            .collect();
        PlannedTrajectory::new(data.path, timing, data.start)?
            .with_shaper(impulses)?
            .with_smoothing(data.smoothing)
    }
}

impl From<&PlannedTrajectory<GeometricPath>> for PlannedData {
    fn from(planned: &PlannedTrajectory<GeometricPath>) -> Self {
        Self {
            path: planned.path.clone(),
            s: planned.timing.s.clone(),
            s_dot: planned.timing.s_dot.clone(),
            periodic: planned.timing.periodic,
            start: planned.start,
            shaper: planned
                .impulses
                .iter()
                .map(|i| [i.amplitude, i.delay])
                .collect(),
            smoothing: planned.smoothing,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::path::{CirclePath, SegmentPath};
    use crate::pose::Pose;

    /// Constant path acceleration `a` from rest over `[0, L]`, then constant deceleration:
    /// the triangle profile, `s_dot = sqrt(2 a s)` up to the middle.
    fn triangle(n: usize, length: f64, a: f64) -> Timing {
        let s: Vec<f64> = (0..=n).map(|k| length * k as f64 / n as f64).collect();
        let s_dot = s
            .iter()
            .map(|&s| (2.0 * a * s.min(length - s)).max(0.0).sqrt())
            .collect();
        Timing::new(s, s_dot, false).unwrap()
    }

    #[test]
    fn triangle_timing_matches_its_closed_form() {
        let (length, a) = (0.1, 2.0);
        let timing = triangle(10, length, a);
        let half = (length / a).sqrt();
        assert!((timing.duration() - 2.0 * half).abs() <= 1e-12);
        for tau in [0.0, 0.3 * half, half, 1.4 * half, 2.0 * half] {
            let state = timing.state(tau);
            let (s, v) = if tau <= half {
                (0.5 * a * tau * tau, a * tau)
            } else {
                let r = 2.0 * half - tau;
                (length - 0.5 * a * r * r, a * r)
            };
            assert!((state.s - s).abs() <= 1e-12, "s at {tau}");
            assert!((state.s_dot - v).abs() <= 1e-12, "s_dot at {tau}");
        }
        assert!((timing.state(-1.0).s).abs() <= 0.0);
        assert!((timing.state(9.0).s - length).abs() <= 0.0);
        // The integral of s over the move: int_0^T s dt = L T / 2 by symmetry.
        let total = timing.integral(timing.duration());
        assert!((total - 0.5 * length * timing.duration()).abs() <= 1e-14);
    }

    #[test]
    fn smoothing_is_the_moving_average_and_its_derivatives() {
        let timing = triangle(40, 0.1, 3.0);
        let w = 0.02;
        for tau in [0.005, 0.05, 0.12, 0.2, 0.21] {
            let state = timing.smoothed_state(tau, w);
            // Moving average by the midpoint rule on a fine grid.
            let m = 20_000;
            let average: f64 = (0..m)
                .map(|j| timing.state(tau - w + w * (j as f64 + 0.5) / m as f64).s)
                .sum::<f64>()
                / m as f64;
            assert!((state.s - average).abs() <= 1e-9, "s at {tau}");
            let h = 1e-7;
            let slope = (timing.smoothed_state(tau + h, w).s - timing.smoothed_state(tau - h, w).s)
                / (2.0 * h);
            assert!((state.s_dot - slope).abs() <= 1e-6, "s_dot at {tau}");
        }
    }

    #[test]
    fn shaped_trajectory_reaches_the_end_later_by_the_shaper_length() {
        let path =
            SegmentPath::new(Pose::new(-0.08, -0.03, 0.5), Pose::new(-0.02, 0.03, 0.5)).unwrap();
        let length = path.length();
        let timing = triangle(20, length, 5.0);
        let duration = timing.duration();
        let planned = PlannedTrajectory::new(path, timing, 0.1)
            .unwrap()
            .with_shaper(vec![
                Impulse {
                    amplitude: 0.5,
                    delay: 0.0,
                },
                Impulse {
                    amplitude: 0.5,
                    delay: 0.004,
                },
            ])
            .unwrap()
            .with_smoothing(0.003)
            .unwrap();
        let end = planned.duration().unwrap();
        assert!((end - (0.1 + duration + 0.007)).abs() <= 1e-15);
        let last = planned.motion(end);
        assert!((last.pose.to_vector() - path.to().to_vector()).norm() <= 1e-15);
        assert!(last.velocity.norm() <= 1e-12);
        let before = planned.motion(0.1);
        assert!((before.pose.to_vector() - path.from().to_vector()).norm() <= 1e-15);
        let breaks = planned.breakpoints();
        assert!(breaks.windows(2).all(|w| w[1] > w[0]));
        assert!((breaks[breaks.len() - 1] - end).abs() <= 1e-12);
    }

    #[test]
    fn periodic_timing_repeats_and_round_trips() {
        let path = CirclePath::new([-0.05, 0.0], 0.05, 0.7, 0.0, false).unwrap();
        let length = path.length();
        let n = 16;
        let s: Vec<f64> = (0..=n).map(|k| length * k as f64 / n as f64).collect();
        let s_dot: Vec<f64> = s.iter().map(|s| 1.0 + 0.2 * (s / 0.05).cos()).collect();
        let timing = Timing::new(s, s_dot, true).unwrap();
        let period = timing.duration();
        let planned = PlannedTrajectory::new(GeometricPath::Circle(path), timing, 0.0)
            .unwrap()
            .with_smoothing(0.01)
            .unwrap()
            .with_horizon(3.0 * period);
        assert!(planned.duration().is_none());
        for t in [0.013, 0.2 * period] {
            let (a, b) = (planned.motion(t), planned.motion(t + 2.0 * period));
            assert!((a.pose.to_vector() - b.pose.to_vector()).norm() <= 1e-12);
            assert!((a.velocity - b.velocity).norm() <= 1e-9);
        }
        let data = PlannedData::from(&planned);
        let text = serde_json::to_string(&data).unwrap();
        let back = PlannedTrajectory::try_from(serde_json::from_str::<PlannedData>(&text).unwrap())
            .unwrap();
        let m = back.motion(0.37);
        let want = planned.motion(0.37);
        assert!((m.pose.to_vector() - want.pose.to_vector()).norm() <= 1e-15);
    }

    #[test]
    fn bad_timings_name_the_field_and_index() {
        let error = Timing::new(vec![0.0, 1.0, 0.5], vec![0.0, 1.0, 0.0], false).unwrap_err();
        assert!(error.to_string().contains("s[2]"), "{error}");
        let error = Timing::new(vec![0.0, 1.0], vec![0.0, 1.0], false).unwrap_err();
        assert!(error.to_string().contains("s_dot[1]"), "{error}");
        let error = Timing::new(vec![0.0, 1.0, 2.0], vec![0.0, 0.0, 0.0], false).unwrap_err();
        assert!(error.to_string().contains("never be traversed"), "{error}");
        let path = SegmentPath::new(Pose::new(0.0, 0.0, 0.0), Pose::new(0.1, 0.0, 0.0)).unwrap();
        let periodic = Timing::new(vec![0.0, 0.1], vec![1.0, 1.0], true).unwrap();
        let error = PlannedTrajectory::new(path, periodic, 0.0).unwrap_err();
        assert!(error.to_string().contains("closed path"), "{error}");
        let impulses = [Impulse {
            amplitude: 0.7,
            delay: 0.0,
        }];
        assert!(check_impulses(&impulses).is_err());
    }
}
