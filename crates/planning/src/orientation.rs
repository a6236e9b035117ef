//! The platform's orientation as a design variable (docs/planning.md, "The platform's
//! orientation"). The paper ends on it: for a prescribed motion of the platform's centre,
//! "the configurations of the manipulator may be optimized so that the axial forces in the
//! flexible links are in extension". Along a path whose `(x, y)(s)` is given, the orientation
//! `phi` is chosen within `[phi_min, phi_max]`:
//!
//! * **the best constant `phi`** ([`Planner::best_constant_phi`]): a scan of the interval
//!   (the objective is not unimodal, and parts of the interval are infeasible: unreachable
//!   poses, slider travel, singularities, limits no timing can meet), then Brent's method in
//!   the brackets of the scan's best local minima;
//! * **`phi` free along the path** ([`Planner::free_phi`]): `phi(s)` a smooth law of a few
//!   coefficients ([`flexprr_kinematics::PhiLaw`]: a Fourier series for a periodic motion, a
//!   clamped cubic B-spline otherwise, vanishing at the ends when the end orientations are
//!   kept), optimised by Nelder-Mead from the best constant. A local search: the result is
//!   never worse than its start, and no better than a local optimum of the chosen law.
//!
//! Two objectives ([`PhiObjective`]): the time-optimal motion under the planner's limits
//! (rest-to-rest: its duration; periodic: its period, so the largest frequency), or the
//! largest buckling margin at a given timing of the path ([`Schedule`], the scene's own):
//! the largest compression of any link, at either end, as a fraction of its critical load,
//! over the whole motion ([`Compression`]), minimised. The axial force along a link is
//! concave (docs/planning.md, "Buckling"), so its end values bound its compression and its
//! tension: a ratio `<= 0` means every link is in tension throughout.

use flexprr_kinematics::{
    Orientation, Path, PathState, PhiFourier, PhiLaw, PhiSpline, Profile, Timing,
};

use serde::{Deserialize, Serialize};

use crate::constraint::Buckling;
use crate::error::{PlanningError, Where};
use crate::optimize::{SimplexSettings, brent, nelder_mead};
use crate::plan::{Boundary, Plan, Planner};

/// A timing of the path parameter `s(t)`, independent of the orientation (an oriented path
/// keeps its base path's parameter): the scene's own timing of its path.
#[derive(Debug, Clone, PartialEq)]
pub enum Schedule {
    /// `s = speed t` for `0 <= t <= duration` (a circle at its frequency, a line; wrapped on a
    /// closed path).
    ConstantSpeed {
        /// Path speed (path unit per second, > 0).
        speed: f64,
        /// Duration (s, > 0).
        duration: f64,
    },
    /// The whole path from rest to rest in `duration` with a normalised profile,
    /// `s = S profile(t / duration)` (a point-to-point move).
    Profile {
        /// The profile.
        profile: Profile,
        /// Duration (s, > 0).
        duration: f64,
    },
    /// A planned timing ([`Plan::timing`]).
    Timing(Timing),
}

impl Schedule {
    /// One revolution of a closed path of length `length` at `frequency` revolutions per
    /// second (the paper's circle: `Schedule::revolution(2 pi R, 20.0)`).
    pub fn revolution(length: f64, frequency: f64) -> Self {
        Schedule::ConstantSpeed {
            speed: length * frequency.abs(),
            duration: 1.0 / frequency.abs(),
        }
    }

    /// Duration (s).
    pub fn duration(&self) -> f64 {
        match self {
            Schedule::ConstantSpeed { duration, .. } | Schedule::Profile { duration, .. } => {
                *duration
            }
            Schedule::Timing(timing) => timing.duration(),
        }
    }

    /// Whether the motion repeats (a constant speed over a whole number of revolutions of
    /// a closed path of length `length`, or a periodic timing).
    pub fn is_periodic(&self, length: f64) -> bool {
        match self {
            Schedule::ConstantSpeed { speed, duration } => {
                let turns = speed * duration / length;
                turns >= 1.0 - 1e-9 && (turns - turns.round()).abs() <= 1e-9 * turns
            }
            Schedule::Profile { .. } => false,
            Schedule::Timing(timing) => timing.is_periodic(),
        }
    }

    /// The path state at `t` on a path of length `length`.
    pub fn state(&self, length: f64, t: f64) -> PathState {
        match self {
            Schedule::ConstantSpeed { speed, .. } => PathState {
                s: speed * t,
                s_dot: *speed,
                s_ddot: 0.0,
                s_dddot: 0.0,
            },
            Schedule::Profile { profile, duration } => {
                let (s, ds, dds) = profile.evaluate(t / duration);
                PathState {
                    s: length * s,
                    s_dot: length * ds / duration,
                    s_ddot: length * dds / (duration * duration),
                    s_dddot: 0.0,
                }
            }
            Schedule::Timing(timing) => timing.state(t),
        }
    }

    fn validate(&self) -> Result<(), PlanningError> {
        let bad = |value: f64, rule: &str| {
            Err(PlanningError::InvalidSpec {
                key: "schedule",
                value: value.to_string(),
                rule: rule.into(),
            })
        };
        match self {
            Schedule::ConstantSpeed { speed, duration } => {
                if !(speed.is_finite() && *speed > 0.0) {
                    return bad(*speed, "the path speed must be finite and > 0");
                }
                if !(duration.is_finite() && *duration > 0.0) {
                    return bad(*duration, "the duration must be finite and > 0 (s)");
                }
            }
            Schedule::Profile { duration, .. } => {
                if !(duration.is_finite() && *duration > 0.0) {
                    return bad(*duration, "the duration must be finite and > 0 (s)");
                }
            }
            Schedule::Timing(_) => {}
        }
        Ok(())
    }
}

/// The largest compression of the links over a motion (module documentation).
#[derive(Debug, Clone, PartialEq)]
pub struct Compression {
    /// Largest `-P / P_cr` of any link at either end over the motion: the largest compression
    /// as a fraction of the critical load (1: buckling); negative when every link is in
    /// tension throughout (its magnitude then the smallest tension, as a fraction).
    pub ratio: f64,
    /// Per link, its largest ratio.
    pub links: [f64; 3],
    /// The link where the ratio is largest (0-based).
    pub link: usize,
    /// Its end there: `B` (slider) or `C` (platform).
    pub end: char,
    /// Time there (s).
    pub t: f64,
    /// Where on the path.
    pub at: Where,
    /// The critical load of each link (N).
    pub critical_loads: [f64; 3],
    /// Instants sampled (before the local refinement of the largest).
    pub samples: usize,
}

impl Compression {
    /// Whether every link stays in tension (ratio at most `tolerance`; a rest-to-rest motion
    /// starts and ends with no axial force, so its ratio is never below 0).
    pub fn in_tension(&self, tolerance: f64) -> bool {
        self.ratio <= tolerance
    }
}

/// What the orientation is chosen for.
#[derive(Debug, Clone, PartialEq)]
pub enum PhiObjective {
    /// The shortest time-optimal motion under the planner's limits: the duration of a
    /// rest-to-rest motion, the period of a periodic one (so the largest frequency).
    MinTime,
    /// The largest buckling margin at this timing of the path: [`Compression::ratio`]
    /// minimised. Only the workspace limits the orientation (the timing is given; the
    /// planner's limits do not apply to it).
    MaxMargin(Schedule),
}

/// Whether a free orientation keeps the path's end orientations (rest-to-rest motions).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PhiEnds {
    /// The law may change the end orientations (it starts from the best constant).
    #[default]
    Free,
    /// The law corrects the path's own orientation and vanishes at both ends.
    Fixed,
}

/// The orientation search: bounds, objective and numerical settings.
#[derive(Debug, Clone, PartialEq)]
pub struct PhiSearch {
    /// Lower bound on `phi` everywhere on the path (rad).
    pub min: f64,
    /// Upper bound (rad); `max - min <= 2 pi`.
    pub max: f64,
    /// The objective.
    pub objective: PhiObjective,
    /// Spacing of the scan of constant orientations (rad; 2 deg by default).
    pub scan_step: f64,
    /// Tolerance of the refinement of a constant orientation, and the simplex size at which
    /// the free search stops (rad; 0.01 deg by default).
    pub tolerance: f64,
    /// Local minima of the scan refined (3).
    pub brackets: usize,
    /// Free orientation of a non-periodic motion: ends free or kept (a periodic motion has
    /// no ends: ignored).
    pub ends: PhiEnds,
    /// Control values of the B-spline law (non-periodic motions; 6, at least 4).
    pub spline_points: usize,
    /// Harmonics of the Fourier law (periodic motions; 2, at least 1).
    pub harmonics: usize,
    /// Most objective evaluations of the free search (1000).
    pub max_evaluations: usize,
    /// Initial step of every coefficient in the free search (rad; 5 deg).
    pub step: f64,
    /// Instants sampled for the buckling margin (1000; the largest is then refined).
    pub samples: usize,
}

impl PhiSearch {
    /// A search over `[min, max]` (rad) with the default settings.
    ///
    /// # Errors
    /// As [`PhiSearch::validate`].
    pub fn new(min: f64, max: f64, objective: PhiObjective) -> Result<Self, PlanningError> {
        let search = Self {
            min,
            max,
            objective,
            scan_step: 2f64.to_radians(),
            tolerance: 0.01f64.to_radians(),
            brackets: 3,
            ends: PhiEnds::Free,
            spline_points: 6,
            harmonics: 2,
            max_evaluations: 1000,
            step: 5f64.to_radians(),
            samples: 1000,
        };
        search.validate()?;
        Ok(search)
    }

    /// Checks every setting; the first one out of range is named by its `[plan]` key.
    ///
    /// # Errors
    /// [`PlanningError::InvalidSpec`].
    pub fn validate(&self) -> Result<(), PlanningError> {
        let bad = |key: &'static str, value: String, rule: &str| {
            Err(PlanningError::InvalidSpec {
                key,
                value,
                rule: rule.into(),
            })
        };
        let deg = |x: f64| format!("{}", x.to_degrees());
        if !self.min.is_finite() {
            return bad("phi_min_deg", deg(self.min), "must be finite");
        }
        if !(self.max.is_finite() && self.max > self.min) {
            return bad(
                "phi_max_deg",
                deg(self.max),
                "must be finite and > phi_min_deg",
            );
        }
        if self.max - self.min > std::f64::consts::TAU * (1.0 + 1e-12) {
            return bad(
                "phi_max_deg",
                deg(self.max),
                "the range phi_max_deg - phi_min_deg must be at most 360 deg",
            );
        }
        if !(self.scan_step.is_finite() && self.scan_step > 0.0) {
            return bad(
                "phi_scan_step_deg",
                deg(self.scan_step),
                "must be finite and > 0",
            );
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return bad(
                "phi_tolerance_deg",
                deg(self.tolerance),
                "must be finite and > 0",
            );
        }
        if !(self.step.is_finite() && self.step > 0.0) {
            return bad("phi_step_deg", deg(self.step), "must be finite and > 0");
        }
        if self.brackets == 0 {
            return bad("phi_brackets", "0".into(), "must be >= 1");
        }
        if self.spline_points < 4 {
            return bad(
                "phi_spline_points",
                self.spline_points.to_string(),
                "a cubic B-spline needs at least 4 control values",
            );
        }
        if self.harmonics == 0 {
            return bad("phi_harmonics", "0".into(), "must be >= 1");
        }
        if self.max_evaluations < 2 {
            return bad(
                "phi_evaluations",
                self.max_evaluations.to_string(),
                "must be >= 2",
            );
        }
        if self.samples < 2 {
            return bad("phi_samples", self.samples.to_string(), "must be >= 2");
        }
        if let PhiObjective::MaxMargin(schedule) = &self.objective {
            schedule.validate()?;
        }
        Ok(())
    }
}

/// One constant orientation of the scan.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanPoint {
    /// The orientation (rad).
    pub phi: f64,
    /// The objective there, or why the motion is infeasible there.
    pub value: Result<f64, String>,
}

/// The best constant orientation.
#[derive(Debug, Clone, PartialEq)]
pub struct ConstantPhi {
    /// The orientation (rad).
    pub phi: f64,
    /// The objective there, checked: the duration of the plan with the planner's own
    /// settings (s, the period of a periodic plan) for [`PhiObjective::MinTime`], the ratio for
    /// [`PhiObjective::MaxMargin`].
    pub value: f64,
    /// The objective with the path's own orientation (checked), or why it is infeasible.
    pub original: Result<f64, String>,
    /// The scan, with the search's objective (for a minimum time: raw TOPP-RA's duration).
    pub scan: Vec<ScanPoint>,
    /// Objective evaluations (scan, refinement and the final evaluation).
    pub evaluations: usize,
    /// With [`PhiObjective::MinTime`]: the plan there (the planner's own settings, dense check
    /// included).
    pub plan: Option<Plan>,
    /// With [`PhiObjective::MaxMargin`]: the compression there.
    pub compression: Option<Compression>,
}

/// The best orientation law found along the path.
#[derive(Debug, Clone, PartialEq)]
pub struct FreePhi {
    /// The orientation (apply it to the planner's path with [`Orientation::on`]).
    pub orientation: Orientation,
    /// The objective there (checked, as [`ConstantPhi::value`]).
    pub value: f64,
    /// The objective at the search's start (checked; the best constant, or with fixed ends
    /// the better of the path's own orientation and the best constant in the interior).
    pub start_value: f64,
    /// The objective at the best constant orientation.
    pub constant_value: f64,
    /// The objective with the path's own orientation, or why it is infeasible.
    pub original: Result<f64, String>,
    /// Smallest and largest `phi` along the path (rad).
    pub range: (f64, f64),
    /// Objective evaluations of the free search (the best constant's not included).
    pub evaluations: usize,
    /// Whether the simplex met its tolerances (otherwise the evaluation budget ran out).
    pub converged: bool,
    /// Restarts of the simplex from its best point.
    pub restarts: usize,
    /// With [`PhiObjective::MinTime`]: the plan there.
    pub plan: Option<Plan>,
    /// With [`PhiObjective::MaxMargin`]: the compression there.
    pub compression: Option<Compression>,
}

/// An evaluation of the objective on one orientation.
enum Evaluation {
    Duration(f64),
    Plan(Box<Plan>),
    Compression(Compression),
}

impl Evaluation {
    fn value(&self) -> f64 {
        match self {
            Evaluation::Duration(duration) => *duration,
            Evaluation::Plan(plan) => plan.duration,
            Evaluation::Compression(c) => c.ratio,
        }
    }

    fn split(self) -> (Option<Plan>, Option<Compression>) {
        match self {
            Evaluation::Duration(_) => (None, None),
            Evaluation::Plan(plan) => (Some(*plan), None),
            Evaluation::Compression(c) => (None, Some(c)),
        }
    }
}

/// Points at which an orientation law is checked against the bounds.
const BOUND_POINTS: usize = 2000;

impl Planner<'_> {
    /// The largest compression of the links over `schedule` along this planner's path
    /// (module documentation): `samples + 1` instants, uniform in time, then the largest
    /// refined by a golden-section search between its neighbours.
    ///
    /// # Errors
    /// An invalid schedule; workspace and dynamics errors where the motion leaves the
    /// workspace; an axial-force model whose force is not concave along the links; links
    /// without a critical load.
    pub fn compression(
        &self,
        schedule: &Schedule,
        samples: usize,
    ) -> Result<Compression, PlanningError> {
        schedule.validate()?;
        let critical = Buckling::new(self.machine(), 1.0)?.critical_loads();
        let sampler = self.axial_sampler();
        let path = self.path();
        let length = path.length();
        let closed = path.is_closed();
        let duration = schedule.duration();
        let samples = samples.max(2);
        let ratios = |t: f64| -> Result<([f64; 6], Where), PlanningError> {
            let state = schedule.state(length, t);
            let s = if closed {
                state.s.rem_euclid(length)
            } else {
                state.s
            };
            let sample = sampler.sample(path, s)?;
            let x = state.s_dot * state.s_dot;
            let mut out = [0.0; 6];
            for (i, ends) in sample.axial.iter().enumerate() {
                for (e, force) in ends.iter().enumerate() {
                    out[2 * i + e] = -force.at(state.s_ddot, x) / critical[i];
                }
            }
            Ok((out, sample.place()))
        };
        let mut links = [f64::NEG_INFINITY; 3];
        let mut worst = (f64::NEG_INFINITY, 0usize, 0usize);
        for k in 0..=samples {
            let (r, _) = ratios(duration * k as f64 / samples as f64)?;
            for (j, value) in r.iter().enumerate() {
                links[j / 2] = links[j / 2].max(*value);
                if *value > worst.0 {
                    worst = (*value, j, k);
                }
            }
        }
        // Golden-section search for the largest value of the worst row between the
        // neighbouring samples.
        let row = worst.1;
        let dt = duration / samples as f64;
        let centre = dt * worst.2 as f64;
        let (mut a, mut b) = ((centre - dt).max(0.0), (centre + dt).min(duration));
        let ratio = 0.5 * (5f64.sqrt() - 1.0);
        let (mut c, mut d) = (b - ratio * (b - a), a + ratio * (b - a));
        let (mut fc, mut fd) = (ratios(c)?.0[row], ratios(d)?.0[row]);
        for _ in 0..50 {
            if fc > fd {
                (b, d, fd) = (d, c, fc);
                c = b - ratio * (b - a);
                fc = ratios(c)?.0[row];
            } else {
                (a, c, fc) = (c, d, fd);
                d = a + ratio * (b - a);
                fd = ratios(d)?.0[row];
            }
            if b - a <= 1e-12 * duration {
                break;
            }
        }
        let mut t = centre;
        let (refined, at_refined) = ratios(0.5 * (a + b))?;
        let (mut value, mut at) = ratios(centre).map(|(r, w)| (r[row], w))?;
        if refined[row] > value {
            (value, at, t) = (refined[row], at_refined, 0.5 * (a + b));
        }
        links[row / 2] = links[row / 2].max(value);
        Ok(Compression {
            ratio: value,
            links,
            link: row / 2,
            end: if row % 2 == 0 { 'B' } else { 'C' },
            t,
            at,
            critical_loads: critical,
            samples,
        })
    }

    /// The objective on `orientation` applied to this planner's path. While searching
    /// (`checked = false`) a minimum time is raw TOPP-RA's on the planner's grid (without the
    /// dense check, which changes a duration by about `1e-6` relative and costs ten times
    /// more), or the plan without its grid-convergence study when the planner has an RMS
    /// limit, a jerk limit or a shaper; `checked = true` gives the plan with the planner's
    /// own settings. The orientation must stay within the bounds at every one of
    /// [`BOUND_POINTS`] points of the path.
    fn evaluate(
        &self,
        search: &PhiSearch,
        orientation: &Orientation,
        checked: bool,
    ) -> Result<Evaluation, PlanningError> {
        let path = orientation.on(self.path())?;
        let length = path.length();
        let slack = 1e-12 * (1.0 + search.min.abs().max(search.max.abs()));
        for k in 0..=BOUND_POINTS {
            let s = length * k as f64 / BOUND_POINTS as f64;
            let phi = path.point(s).pose.phi;
            if !(phi >= search.min - slack && phi <= search.max + slack) {
                return Err(PlanningError::OrientationBounds {
                    s,
                    phi_deg: phi.to_degrees(),
                    min_deg: search.min.to_degrees(),
                    max_deg: search.max.to_degrees(),
                });
            }
        }
        let mut settings = *self.settings();
        if !checked {
            settings.convergence = false;
        }
        let planner = self.on_path(&path, settings);
        match &search.objective {
            PhiObjective::MinTime if checked || planner.has_filters() => {
                Ok(Evaluation::Plan(Box::new(planner.plan()?)))
            }
            PhiObjective::MinTime => Ok(Evaluation::Duration(
                planner.solve_uniform(settings.grid)?.duration,
            )),
            PhiObjective::MaxMargin(schedule) => Ok(Evaluation::Compression(
                planner.compression(schedule, search.samples)?,
            )),
        }
    }

    /// The objective of `search` with `orientation` on this planner's path (the value the
    /// searches minimise: a duration or period in s, or a compression ratio).
    ///
    /// # Errors
    /// An orientation outside the bounds; anything that makes the motion infeasible (as
    /// [`Planner::plan`] or [`Planner::compression`]).
    pub fn phi_objective(
        &self,
        search: &PhiSearch,
        orientation: &Orientation,
    ) -> Result<f64, PlanningError> {
        search.validate()?;
        Ok(self.evaluate(search, orientation, false)?.value())
    }

    /// The best constant orientation within the search's bounds (module documentation):
    /// a scan every `scan_step`, then Brent's method between the neighbours of the scan's
    /// `brackets` best local minima, to `tolerance`.
    ///
    /// # Errors
    /// Invalid search settings; no feasible orientation in the bounds (with the reason at the
    /// middle of the range); the final evaluation's errors.
    pub fn best_constant_phi(&self, search: &PhiSearch) -> Result<ConstantPhi, PlanningError> {
        search.validate()?;
        let (lo, hi) = (search.min, search.max);
        let n = (((hi - lo) / search.scan_step).ceil() as usize).max(2) + 1;
        let phis: Vec<f64> = (0..n)
            .map(|k| lo + (hi - lo) * k as f64 / (n - 1) as f64)
            .collect();
        let mut evaluations = 0;
        let mut objective = |phi: f64| -> Result<f64, String> {
            evaluations += 1;
            self.evaluate(search, &Orientation::constant(phi), false)
                .map(|e| e.value())
                .map_err(|e| e.to_string())
        };
        let scan: Vec<ScanPoint> = phis
            .iter()
            .map(|&phi| ScanPoint {
                phi,
                value: objective(phi),
            })
            .collect();
        let values: Vec<f64> = scan
            .iter()
            .map(|p| *p.value.as_ref().unwrap_or(&f64::INFINITY))
            .collect();
        if values.iter().all(|v| !v.is_finite()) {
            let middle = &scan[n / 2];
            return Err(PlanningError::NoFeasibleOrientation {
                min_deg: lo.to_degrees(),
                max_deg: hi.to_degrees(),
                tried: n,
                phi_deg: middle.phi.to_degrees(),
                reason: middle.value.clone().err().unwrap_or_default(),
            });
        }
        // The scan's local minima, best first.
        let mut minima: Vec<usize> = (0..n)
            .filter(|&k| {
                values[k].is_finite()
                    && (k == 0 || values[k] <= values[k - 1])
                    && (k == n - 1 || values[k] <= values[k + 1])
            })
            .collect();
        minima.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
        minima.truncate(search.brackets);
        let mut best = (phis[minima[0]], values[minima[0]]);
        for &k in &minima {
            let (a, b) = (phis[k.saturating_sub(1)], phis[(k + 1).min(n - 1)]);
            let mut f = |phi: f64| objective(phi).unwrap_or(f64::INFINITY);
            let (phi, value, _) = brent(&mut f, a, b, search.tolerance, 60);
            if value < best.1 {
                best = (phi, value);
            }
        }
        let original = self
            .evaluate(search, &Orientation::unchanged(), true)
            .map(|e| e.value())
            .map_err(|e| e.to_string());
        let checked = self.evaluate(search, &Orientation::constant(best.0), true)?;
        let value = checked.value();
        let (plan, compression) = checked.split();
        Ok(ConstantPhi {
            phi: best.0,
            value,
            original,
            scan,
            evaluations: evaluations + 2,
            plan,
            compression,
        })
    }

    /// Whether the search's motion repeats: a periodic plan, or a margin at a periodic
    /// schedule on a closed path.
    fn periodic_motion(&self, search: &PhiSearch) -> bool {
        let path = self.path();
        path.is_closed()
            && match &search.objective {
                PhiObjective::MinTime => self.settings().boundary == Boundary::Periodic,
                PhiObjective::MaxMargin(schedule) => schedule.is_periodic(path.length()),
            }
    }

    /// The best orientation law along the path from the best constant `constant` (module
    /// documentation): a Fourier series of `harmonics` for a periodic motion, a cubic
    /// B-spline of `spline_points` control values otherwise (with fixed ends: a correction
    /// of the path's own orientation vanishing at both ends, started from the better of no
    /// correction and the best constant in the interior), by Nelder-Mead within
    /// `max_evaluations`. Local: never worse than its start.
    ///
    /// # Errors
    /// Invalid search settings; a start that is itself infeasible; the final evaluation's
    /// errors.
    pub fn free_phi(
        &self,
        search: &PhiSearch,
        constant: &ConstantPhi,
    ) -> Result<FreePhi, PlanningError> {
        search.validate()?;
        let path = self.path();
        let length = path.length();
        let c = constant.phi;
        // The law's family, the map from the free variables to its coefficients, and the
        // starts.
        let (template, relative, fixed_ends, starts): (PhiLaw, bool, bool, Vec<Vec<f64>>) =
            if self.periodic_motion(search) {
                let h = search.harmonics;
                let mut start = vec![0.0; 1 + 2 * h];
                start[0] = c;
                let law = PhiLaw::Fourier(PhiFourier::new(c, vec![0.0; h], vec![0.0; h])?);
                (law, false, false, vec![start])
            } else {
                let n = search.spline_points;
                let law = PhiLaw::Spline(PhiSpline::new(vec![0.0; n])?);
                match search.ends {
                    PhiEnds::Free => (law, false, false, vec![vec![c; n]]),
                    PhiEnds::Fixed => {
                        // Interior control values that bring the orientation to the best
                        // constant near their Greville abscissae.
                        let towards: Vec<f64> = (1..n - 1)
                            .map(|k| {
                                let w = greville(k, n);
                                c - path.point(w * length).pose.phi
                            })
                            .collect();
                        (law, true, true, vec![vec![0.0; n - 2], towards])
                    }
                }
            };
        let coefficients = |x: &[f64]| -> Vec<f64> {
            if fixed_ends {
                let mut full = vec![0.0];
                full.extend_from_slice(x);
                full.push(0.0);
                full
            } else {
                x.to_vec()
            }
        };
        let orientation_of = |x: &[f64]| -> Result<Orientation, PlanningError> {
            Ok(Orientation {
                relative,
                law: template.with_coefficients(&coefficients(x))?,
            })
        };
        let mut objective = |x: &[f64]| -> f64 {
            orientation_of(x)
                .and_then(|o| self.evaluate(search, &o, false))
                .map_or(f64::INFINITY, |e| e.value())
        };
        let mut start = (starts[0].clone(), f64::INFINITY);
        for x in &starts {
            let value = objective(x);
            if value < start.1 {
                start = (x.clone(), value);
            }
        }
        if !start.1.is_finite() {
            let reason = self
                .evaluate(search, &orientation_of(&start.0)?, false)
                .err()
                .map(|e| e.to_string())
                .unwrap_or_default();
            return Err(PlanningError::NoFeasibleOrientation {
                min_deg: search.min.to_degrees(),
                max_deg: search.max.to_degrees(),
                tried: starts.len(),
                phi_deg: c.to_degrees(),
                reason: format!("the free search has no feasible start: {reason}"),
            });
        }
        // A constant on a bound leaves the simplex no room: every harmonic or control value
        // moved by a step crosses the bound. The simplex then starts one step inside (the
        // result is still compared with the start).
        let mut origin = start.0.clone();
        if !relative && search.max - search.min > 2.0 * search.step {
            let inside = c.clamp(search.min + search.step, search.max - search.step);
            if (inside - c).abs() > 0.0 {
                match template {
                    PhiLaw::Fourier(_) => origin[0] = inside,
                    _ => origin.iter_mut().for_each(|v| *v = inside),
                }
            }
        }
        let step = vec![search.step; origin.len()];
        let budget = search.max_evaluations.saturating_sub(starts.len()).max(2);
        let found = nelder_mead(
            &mut objective,
            &origin,
            &step,
            SimplexSettings {
                max_evaluations: budget,
                value_tolerance: 1e-7,
                size_tolerance: search.tolerance,
            },
        );
        let same = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(p, q)| p.to_bits() == q.to_bits());
        let x = if found.value < start.1 {
            found.x
        } else {
            start.0.clone()
        };
        // The checked objective there, never worse than the checked start (the search's
        // objective and the checked one differ by the dense check's tightening).
        let mut orientation = orientation_of(&x)?;
        let mut checked = self.evaluate(search, &orientation, true)?;
        let mut extra = 1;
        let start_value = if same(&x, &start.0) {
            checked.value()
        } else {
            let start_orientation = orientation_of(&start.0)?;
            let start_checked = self.evaluate(search, &start_orientation, true)?;
            extra += 1;
            let value = start_checked.value();
            if value < checked.value() {
                (orientation, checked) = (start_orientation, start_checked);
            }
            value
        };
        let oriented = orientation.on(path)?;
        let range = (0..=BOUND_POINTS).fold((f64::INFINITY, f64::NEG_INFINITY), |r, k| {
            let phi = oriented
                .point(length * k as f64 / BOUND_POINTS as f64)
                .pose
                .phi;
            (r.0.min(phi), r.1.max(phi))
        });
        let value = checked.value();
        let (plan, compression) = checked.split();
        Ok(FreePhi {
            orientation,
            value,
            start_value,
            constant_value: constant.value,
            original: constant.original.clone(),
            range,
            evaluations: starts.len() + found.evaluations + extra,
            converged: found.converged,
            restarts: found.restarts,
            plan,
            compression,
        })
    }
}

/// The Greville abscissa of control value `k` of the uniform clamped cubic B-spline with `n`
/// control values: the mean of its three inner knots (where a control value acts most).
fn greville(k: usize, n: usize) -> f64 {
    let pieces = (n - 3) as f64;
    let knot = |j: usize| ((j as f64 - 3.0) / pieces).clamp(0.0, 1.0);
    (knot(k + 1) + knot(k + 2) + knot(k + 3)) / 3.0
}
