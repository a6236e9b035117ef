//! Time-optimal timing by numerical integration in the phase plane `(s, x = s'^2)`
//! (J. E. Bobrow, S. Dubowsky, J. S. Gibson, "Time-optimal control of robotic manipulators
//! along specified paths", IJRR 4(3), 1985; K. G. Shin, N. D. McKay, "Minimum-time control of
//! robotic manipulators with geometric path constraints", IEEE TAC 30(6), 1985): a second,
//! independent method to check TOPP-RA against.
//!
//! At each `s` the rows give, for a path speed `x`, an interval `[u_min(s, x), u_max(s, x)]`
//! of feasible path accelerations (evaluated exactly, `sqrt(x)` terms included); the maximum
//! velocity curve `MVC(s)` is the largest `x` with a non-empty interval (bisection). The
//! optimal profile is bang-bang: maximum acceleration curves `dx/ds = 2 u_max` and maximum
//! deceleration curves `dx/ds = 2 u_min`, switching on the MVC. It is found by integrating
//! (classical fourth-order Runge-Kutta in `s`, constraints evaluated at every stage):
//!
//! 1. backward from the end state with `u_min`, never above the MVC: the limit
//!    `x_b(s)` from which the end can still be reached (where it is held at the MVC it slides
//!    along the velocity limit curve; where it leaves the MVC is a switch point);
//! 2. forward from the start with `u_max`, never above `x_b`: where the forward curve meets
//!    `x_b` the motion switches from accelerating to decelerating.
//!
//! This is the switch-point construction of Bobrow et al. with the switch points found by the
//! envelope of the integrated curves rather than by a search along the MVC; the two agree
//! where the curves are integrated exactly. The switch points are reported.

use crate::constraint::{Row, maximum_speed, u_interval};
use crate::error::{Infeasibility, PlanningError};
use crate::plan::{Boundary, Planner};
use crate::sample::PathSample;

/// A time-optimal profile by phase-plane integration.
#[derive(Debug, Clone, PartialEq)]
pub struct PhasePlane {
    /// The integration grid.
    pub s: Vec<f64>,
    /// Squared path speed `x = s'^2` of the optimal profile on it.
    pub x: Vec<f64>,
    /// The maximum velocity curve on it.
    pub mvc: Vec<f64>,
    /// Where the profile switches between accelerating and decelerating or leaves the MVC.
    pub switch_points: Vec<f64>,
    /// Duration (s): of the move, or the period.
    pub duration: f64,
}

/// Rows of one sample, with the feasible `u` interval and MVC computations.
struct Point {
    rows: Vec<Row>,
    mvc: f64,
}

impl Point {
    fn u_range(&self, x: f64) -> Option<(f64, f64)> {
        u_interval(self.rows.iter().copied(), x)
    }

    /// `2 u` at `x` clamped into `[0, MVC]`, `u` the lower (`decelerate`) or upper bound
    /// (infinite where no row bounds it).
    fn slope(&self, x: f64, decelerate: bool) -> f64 {
        let x = if x.is_nan() { self.mvc } else { x }.clamp(0.0, self.mvc.max(0.0));
        match self.u_range(x) {
            Some((lo, hi)) => 2.0 * if decelerate { lo } else { hi },
            None => 0.0,
        }
    }
}

impl Planner<'_> {
    /// The time-optimal profile by phase-plane integration on `steps` uniform intervals
    /// (module documentation).
    ///
    /// # Errors
    /// As [`Planner::plan`]: workspace, dynamics and infeasibility errors with their place.
    pub fn phase_plane(&self, steps: usize) -> Result<PhasePlane, PlanningError> {
        if steps < 2 {
            return Err(PlanningError::InvalidSpec {
                key: "steps",
                value: steps.to_string(),
                rule: "need at least 2 integration steps".into(),
            });
        }
        let path = self.path();
        let periodic = self.settings().boundary == Boundary::Periodic;
        if periodic && !path.is_closed() {
            return Err(PlanningError::OpenPath);
        }
        let s = crate::plan::grid_points(path, steps, !periodic);
        let sampler = self.sampler();
        let width: usize = self.constraints().iter().map(|c| c.count()).sum();
        // Samples at the grid points and the midpoints (RK4 stages).
        let mut points = Vec::with_capacity(2 * steps + 1);
        for i in 0..=2 * steps {
            let at = if i % 2 == 0 {
                s[i / 2]
            } else {
                0.5 * (s[i / 2] + s[i / 2 + 1])
            };
            let sample: PathSample = sampler.sample(path, at)?;
            let mut rows = vec![Row::INACTIVE; width];
            let mut offset = 0;
            for c in self.constraints() {
                c.rows(&sample, &mut rows[offset..offset + c.count()]);
                offset += c.count();
            }
            let mut point = Point { rows, mvc: 0.0 };
            point.mvc = maximum_speed(point.rows.iter().copied());
            if point.mvc < 0.0 {
                return Err(PlanningError::Infeasible(Box::new(Infeasibility {
                    constraint: "the limits together".into(),
                    label: "all rows".into(),
                    at: sample.place(),
                    reason: "no path acceleration meets them with the machine at rest",
                    value: f64::NAN,
                    limit: f64::NAN,
                    unit: String::new(),
                })));
            }
            if !point.mvc.is_finite() && i > 0 && i < 2 * steps {
                return Err(PlanningError::Unbounded { at: sample.place() });
            }
            points.push(point);
        }
        let mvc: Vec<f64> = (0..=steps).map(|i| points[2 * i].mvc).collect();
        // One step from grid point i towards i+1 (forward, maximum acceleration) or i-1
        // (backward, maximum deceleration), never above `cap` at the end point. RK4; where a
        // slope is unbounded (a point where the path's slope vanishes, so no row bounds s'')
        // or the step overshoots below zero (the stiff approach to a force limit next to
        // such a point), implicit Euler at the end point instead: the largest x meeting
        // x <= x_start +/- 2 h u(end, x).
        let step = |i: usize, x: f64, backward: bool, cap: f64| -> f64 {
            let (j, sign) = if backward {
                (i - 1, -1.0)
            } else {
                (i + 1, 1.0)
            };
            let (p0, pm, p1) = (&points[2 * i], &points[i + j], &points[2 * j]);
            let h = sign * (s[j] - s[i]).abs();
            let k1 = p0.slope(x, backward);
            let k2 = pm.slope(x + 0.5 * h * k1, backward);
            let k3 = pm.slope(x + 0.5 * h * k2, backward);
            let k4 = p1.slope(x + h * k3, backward);
            let rk = x + h * (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0;
            if rk.is_finite() && rk >= 0.0 {
                return rk.min(cap);
            }
            let gap = |y: f64| x + h * p1.slope(y, backward) - y;
            if gap(cap) >= 0.0 {
                return cap;
            }
            let (mut lo, mut hi) = (0.0, cap);
            if gap(lo) < 0.0 {
                return 0.0;
            }
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if mid <= lo || mid >= hi {
                    break;
                }
                if gap(mid) >= 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            lo
        };
        let mut end = if periodic { mvc[steps] } else { 0.0 };
        let mut limit = vec![0.0; steps + 1];
        for _ in 0..200 {
            limit[steps] = end.min(mvc[steps]);
            for i in (1..=steps).rev() {
                limit[i - 1] = step(i, limit[i], true, mvc[i - 1]);
            }
            if !periodic {
                break;
            }
            let next = limit[0].min(mvc[steps]);
            if (next - end).abs() <= 1e-13 * end {
                break;
            }
            end = next;
        }
        let mut x = vec![0.0; steps + 1];
        let mut clamped = vec![false; steps + 1];
        let mut start = if periodic { limit[0] } else { 0.0 };
        for _ in 0..200 {
            x[0] = start.min(limit[0]);
            for i in 0..steps {
                let free = step(i, x[i], false, limit[i + 1]);
                clamped[i + 1] = free >= limit[i + 1] * (1.0 - 1e-14);
                x[i + 1] = free.min(limit[i + 1]);
            }
            if !periodic || (x[steps] - start).abs() <= 1e-12 * start {
                break;
            }
            start = x[steps];
        }
        let mut switch_points = Vec::new();
        for i in 1..steps {
            if clamped[i] != clamped[i + 1] {
                switch_points.push(s[i]);
            }
        }
        let duration = crate::topp::duration(&s, &x);
        Ok(PhasePlane {
            s,
            x,
            mvc,
            switch_points,
            duration,
        })
    }
}
