//! The planner: a path, a machine and constraints in; a checked time-optimal timing out
//! (docs/planning.md, "The method").
//!
//! 1. Sample the path form of the machine at the grid points (uniform in `s`, plus the path's
//!    breakpoints) and write every constraint's rows; a row broken at rest is an error.
//! 2. TOPP-RA ([`crate::topp`]) on the grid, re-linearising `sqrt(x)` terms at the solution.
//! 3. Check the continuous piecewise-quadratic timing at `check_factor` points per grid
//!    interval against the exact rows. Where a limit is exceeded between grid points, split
//!    those intervals (up to `refinements` rounds); what is still exceeded after that is
//!    removed by tightening the limits at the interval's two grid points by the excess
//!    (repeated until the check passes). The reported motion keeps every limit at every
//!    checked point.
//! 4. Report the duration, the grid convergence (raw TOPP-RA at `N`, `2N`, `4N`), the
//!    largest use of every limit and the constraint that binds along the path.
//!
//! Optional: a continuous (RMS) motor torque, by lowering the peak torque limit (bisection
//! on a uniform factor) until the RMS torque of the time-optimal motion meets it; a jerk
//! limit, by smoothing the timing with a moving average ([`flexprr_kinematics::Timing`]),
//! checked densely; input shaping of the path parameter. Both filters are followed by a
//! dense check of the filtered motion, and the limits are tightened until it passes.

use flexprr_dynamics::{AxialForceModel, JointReactionAxialForce, Machine};
use flexprr_kinematics::{Impulse, Path, PathState, PlannedTrajectory, Timing};
use serde::{Deserialize, Serialize};

use crate::check::{Check, Usage};
use crate::constraint::{Constraint, MotorTorque, Row};
use crate::error::{Infeasibility, PlanningError};
use crate::sample::{PathSample, Sampler};
use crate::topp::{self, Ends, Failure, Linearized, Profile, Workspace, linearize};

/// Boundary conditions of the motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Boundary {
    /// Start and end at rest.
    #[default]
    RestToRest,
    /// A closed path repeated: the path speed at the end equals that at the start.
    Periodic,
}

/// Numerical settings of the planner.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// Number of grid intervals `N` (the path's breakpoints are added).
    pub grid: usize,
    /// Boundary conditions.
    pub boundary: Boundary,
    /// Checked points per grid interval (10: ten times finer than the grid).
    pub check_factor: usize,
    /// Rounds of local grid refinement before limits are tightened.
    pub refinements: usize,
    /// Whether to report the grid convergence (raw TOPP-RA at `N`, `2N`, `4N`).
    pub convergence: bool,
}

impl Settings {
    /// Checks the grid and the check factor.
    ///
    /// # Errors
    /// [`PlanningError::InvalidSpec`] on the key `grid` or `check_factor`.
    pub fn validate(&self) -> Result<(), PlanningError> {
        if self.grid < 2 {
            return Err(PlanningError::InvalidSpec {
                key: "grid",
                value: self.grid.to_string(),
                rule: "must be >= 2 intervals".into(),
            });
        }
        if self.check_factor < 2 {
            return Err(PlanningError::InvalidSpec {
                key: "check_factor",
                value: self.check_factor.to_string(),
                rule: "must be >= 2 points per interval".into(),
            });
        }
        Ok(())
    }
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            grid: 1000,
            boundary: Boundary::RestToRest,
            check_factor: 10,
            refinements: 3,
            convergence: true,
        }
    }
}

/// Largest use of a limit accepted by the dense check (roundoff).
pub const CHECK_TOLERANCE: f64 = 1e-9;

/// Excess between grid points above which an interval is split rather than its limits
/// tightened: an excess this large means the grid misses a feature of a limit.
const REFINE_ABOVE: f64 = 1e-4;

/// A continuous-torque (RMS) limit on the motor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RmsLimit {
    /// The motor model (as in the `motor_torque` constraint).
    pub motor: MotorTorque,
    /// The continuous torque (N m).
    pub continuous_torque: f64,
    /// Time at rest added to the move in the RMS average (s): the cycle is the move plus the
    /// dwell, during which the torque is zero (a horizontal machine at rest).
    pub dwell: f64,
}

/// Grid convergence of the raw TOPP-RA duration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Convergence {
    /// Grid intervals `N`, `2N`, `4N`.
    pub intervals: [usize; 3],
    /// The durations (s).
    pub durations: [f64; 3],
    /// Observed order `log2(|T_N - T_2N| / |T_2N - T_4N|)` (NaN when the differences vanish).
    pub order: f64,
}

/// A stretch of the path along which one constraint binds.
#[derive(Debug, Clone, PartialEq)]
pub struct Binding {
    /// Start of the stretch (path parameter).
    pub from: f64,
    /// End of the stretch.
    pub to: f64,
    /// The binding constraint's name (`none` where no limit is within 2 % of binding).
    pub constraint: String,
}

/// A raw TOPP-RA solution on a grid (no refinement, no check).
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// The grid.
    pub s: Vec<f64>,
    /// Squared path speed at the grid points.
    pub x: Vec<f64>,
    /// Path acceleration on each interval.
    pub u: Vec<f64>,
    /// Controllable sets `[lo, hi]` of `x` at the grid points.
    pub controllable: Vec<(f64, f64)>,
    /// Duration (s): of the move, or the period.
    pub duration: f64,
}

/// A planned motion.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// Boundary conditions.
    pub boundary: Boundary,
    /// Time of the motion (s): the move (shaping and smoothing included), or the period.
    pub duration: f64,
    /// Time of the unfiltered time-optimal timing (s).
    pub optimal_duration: f64,
    /// The timing (before shaping and smoothing).
    pub timing: Timing,
    /// Shaper impulses applied to the path parameter (empty: none).
    pub impulses: Vec<Impulse>,
    /// Smoothing window (s) for a jerk limit (0: none).
    pub smoothing: f64,
    /// Factor on every limit that the filters needed (1: none).
    pub tightening: f64,
    /// Factor on the peak torque that the RMS limit needed (1: none).
    pub peak_torque_factor: f64,
    /// RMS motor torque per leg over the cycle (N m), with an RMS limit.
    pub rms_torque: Option<[f64; 3]>,
    /// Grid points of the final grid.
    pub grid_points: usize,
    /// Refinement rounds used.
    pub refinements: usize,
    /// Grid points whose limits were tightened to hold between grid points.
    pub tightened_points: usize,
    /// The dense check of the final motion.
    pub check: Check,
    /// Where each constraint binds along the path.
    pub binding: Vec<Binding>,
    /// Grid convergence of the raw TOPP-RA duration.
    pub convergence: Option<Convergence>,
}

impl Plan {
    /// The planned motion along `path` from `start` (s), shaped and smoothed as planned.
    ///
    /// # Errors
    /// A path that does not match the plan's grid (another path).
    pub fn trajectory<P: Path>(
        &self,
        path: P,
        start: f64,
    ) -> Result<PlannedTrajectory<P>, PlanningError> {
        Ok(PlannedTrajectory::new(path, self.timing.clone(), start)?
            .with_shaper(self.impulses.clone())?
            .with_smoothing(self.smoothing)?)
    }

    /// The largest path frequency of a periodic plan (Hz): `1 / period`.
    pub fn frequency(&self) -> Option<f64> {
        (self.boundary == Boundary::Periodic).then(|| 1.0 / self.duration)
    }
}

/// `n + 1` grid points on `[0, S]`: uniform for a periodic motion; clustered like
/// `(1 - cos)` (Chebyshev points) towards the ends of a rest-to-rest motion. Near rest the
/// path speed changes fastest relative to itself (`s' ~ sqrt(s)`, or `1/s` where the path's
/// slope `p'` vanishes, as at a waypoint spline's ends) and limits with a `s'` term change
/// with it; a uniform grid resolves that only to first order in the interval, the clustered
/// one to second order (measured: docs/planning.md, "Convergence").
pub(crate) fn grid_points(path: &dyn Path, n: usize, rest: bool) -> Vec<f64> {
    let length = path.length();
    let map = |w: f64| {
        if rest {
            0.5 * (1.0 - (std::f64::consts::PI * w).cos())
        } else {
            w
        }
    };
    let mut s: Vec<f64> = (0..=n).map(|k| length * map(k as f64 / n as f64)).collect();
    s[0] = 0.0;
    s[n] = length;
    s
}

/// The samples and rows of a grid.
#[derive(Debug, Clone)]
struct Grid {
    s: Vec<f64>,
    samples: Vec<PathSample>,
    rows: Vec<Row>,
}

/// Time-optimal planning of a path on a machine (module documentation).
pub struct Planner<'a> {
    machine: &'a Machine,
    path: &'a dyn Path,
    axial: Option<&'a dyn AxialForceModel>,
    constraints: Vec<Box<dyn Constraint + 'a>>,
    settings: Settings,
    rms: Option<RmsLimit>,
    jerk: Option<f64>,
    impulses: Vec<Impulse>,
}

impl std::fmt::Debug for Planner<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Planner")
            .field("constraints", &self.constraints)
            .field("settings", &self.settings)
            .field("rms", &self.rms)
            .field("jerk", &self.jerk)
            .field("impulses", &self.impulses)
            .finish()
    }
}

static JOINT_REACTION: JointReactionAxialForce = JointReactionAxialForce;

/// A constraint borrowed from another planner ([`Planner::on_path`]).
#[derive(Debug)]
struct Shared<'b>(&'b dyn Constraint);

impl Constraint for Shared<'_> {
    fn name(&self) -> &str {
        self.0.name()
    }
    fn unit(&self) -> &str {
        self.0.unit()
    }
    fn count(&self) -> usize {
        self.0.count()
    }
    fn label(&self, row: usize) -> String {
        self.0.label(row)
    }
    fn rows(&self, sample: &PathSample, rows: &mut [Row]) {
        self.0.rows(sample, rows);
    }
}

impl<'a> Planner<'a> {
    /// A planner of `path` on `machine` without constraints (add them with
    /// [`Planner::constraint`]).
    pub fn new(machine: &'a Machine, path: &'a dyn Path, settings: Settings) -> Self {
        Self {
            machine,
            path,
            axial: None,
            constraints: Vec::new(),
            settings,
            rms: None,
            jerk: None,
            impulses: Vec::new(),
        }
    }

    /// Adds a constraint.
    pub fn constraint(mut self, constraint: impl Constraint + 'a) -> Self {
        self.constraints.push(Box::new(constraint));
        self
    }

    /// Adds a boxed constraint.
    pub fn boxed(mut self, constraint: Box<dyn Constraint + 'a>) -> Self {
        self.constraints.push(constraint);
        self
    }

    /// The axial-force model of the samples (for [`crate::Buckling`]); the joint-reaction
    /// model unless set.
    pub fn axial_model(mut self, model: &'a dyn AxialForceModel) -> Self {
        self.axial = Some(model);
        self
    }

    /// A continuous (RMS) torque limit (module documentation).
    pub fn rms(mut self, limit: RmsLimit) -> Self {
        self.rms = Some(limit);
        self
    }

    /// A limit on the jerk of every slider (m/s^3), met by smoothing (module documentation).
    pub fn jerk(mut self, limit: f64) -> Self {
        self.jerk = Some(limit);
        self
    }

    /// Input shaping of the path parameter (impulses summing to one).
    pub fn shaper(mut self, impulses: Vec<Impulse>) -> Self {
        self.impulses = impulses;
        self
    }

    /// The settings.
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// The constraints.
    pub fn constraints(&self) -> &[Box<dyn Constraint + 'a>] {
        &self.constraints
    }

    /// The path.
    pub fn path(&self) -> &'a dyn Path {
        self.path
    }

    /// The machine.
    pub fn machine(&self) -> &'a Machine {
        self.machine
    }

    /// The same planner (constraints, axial model, RMS and jerk limits, shaper) on another
    /// path, with other settings: the constraints are shared, not copied.
    pub fn on_path<'b>(&'b self, path: &'b dyn Path, settings: Settings) -> Planner<'b> {
        Planner {
            machine: self.machine,
            path,
            axial: self.axial,
            constraints: self
                .constraints
                .iter()
                .map(|c| Box::new(Shared(c.as_ref())) as Box<dyn Constraint + 'b>)
                .collect(),
            settings,
            rms: self.rms,
            jerk: self.jerk,
            impulses: self.impulses.clone(),
        }
    }

    /// Whether the plan filters or rescales the time-optimal timing (RMS limit, jerk
    /// smoothing, shaping).
    pub(crate) fn has_filters(&self) -> bool {
        self.rms.is_some() || self.jerk.is_some() || !self.impulses.is_empty()
    }

    /// A sampler with the planner's axial-force model (the joint-reaction model unless set),
    /// whatever the constraints.
    pub(crate) fn axial_sampler(&self) -> Sampler<'a> {
        Sampler::new(self.machine, Some(self.axial.unwrap_or(&JOINT_REACTION)))
    }

    /// The sampler the planner uses (axial forces only when a constraint needs them).
    pub fn sampler(&self) -> Sampler<'a> {
        let needs_axial = self.constraints.iter().any(|c| c.name() == "buckling");
        let model = self.axial.unwrap_or(&JOINT_REACTION);
        Sampler::new(self.machine, needs_axial.then_some(model))
    }

    fn width(&self) -> usize {
        self.constraints.iter().map(|c| c.count()).sum()
    }

    /// `(constraint, row within it)` of every row.
    fn owners(&self) -> Vec<(usize, usize)> {
        self.constraints
            .iter()
            .enumerate()
            .flat_map(|(c, constraint)| (0..constraint.count()).map(move |r| (c, r)))
            .collect()
    }

    fn write_rows(&self, sample: &PathSample, rows: &mut [Row]) {
        let mut offset = 0;
        for constraint in &self.constraints {
            let n = constraint.count();
            constraint.rows(sample, &mut rows[offset..offset + n]);
            offset += n;
        }
    }

    fn validate(&self) -> Result<(), PlanningError> {
        let s = &self.settings;
        s.validate()?;
        if self.constraints.is_empty() {
            return Err(PlanningError::InvalidSpec {
                key: "limits",
                value: "none".into(),
                rule: "a time-optimal plan needs at least one limit".into(),
            });
        }
        let length = self.path.length();
        if !(length.is_finite() && length > 0.0) {
            return Err(PlanningError::InvalidSpec {
                key: "path",
                value: length.to_string(),
                rule: "the path must have a positive finite length".into(),
            });
        }
        if s.boundary == Boundary::Periodic && !self.path.is_closed() {
            return Err(PlanningError::OpenPath);
        }
        if let Some(j) = self.jerk
            && !(j.is_finite() && j > 0.0)
        {
            return Err(PlanningError::InvalidSpec {
                key: "slider_jerk",
                value: j.to_string(),
                rule: "must be finite and > 0 (m/s^3)".into(),
            });
        }
        if let Some(r) = &self.rms {
            if !(r.continuous_torque.is_finite() && r.continuous_torque > 0.0) {
                return Err(PlanningError::InvalidSpec {
                    key: "continuous_torque",
                    value: r.continuous_torque.to_string(),
                    rule: "must be finite and > 0 (N m)".into(),
                });
            }
            if !(r.dwell.is_finite() && r.dwell >= 0.0) {
                return Err(PlanningError::InvalidSpec {
                    key: "dwell",
                    value: r.dwell.to_string(),
                    rule: "must be finite and >= 0 (s)".into(),
                });
            }
        }
        flexprr_kinematics::check_impulses(&self.impulses)?;
        Ok(())
    }

    /// The grid of `n` intervals ([`grid_points`]) plus the path's breakpoints.
    fn uniform(&self, n: usize) -> Vec<f64> {
        let length = self.path.length();
        let rest = self.settings.boundary == Boundary::RestToRest;
        let mut s = grid_points(self.path, n, rest);
        let gap = 1e-6 * length / n as f64;
        for b in self.path.breakpoints() {
            if b > 0.0 && b < length && s.iter().all(|g| (g - b).abs() > gap) {
                s.push(b);
            }
        }
        s.sort_by(f64::total_cmp);
        s
    }

    fn sample_grid(&self, s: Vec<f64>, old: Option<&Grid>) -> Result<Grid, PlanningError> {
        let sampler = self.sampler();
        let m = self.width();
        let mut samples = Vec::with_capacity(s.len());
        let mut reuse = old.map(|g| g.s.iter().zip(&g.samples).peekable());
        for &sk in &s {
            let mut found = None;
            if let Some(it) = reuse.as_mut() {
                while let Some((os, _)) = it.peek() {
                    if **os < sk {
                        it.next();
                    } else {
                        break;
                    }
                }
                if let Some((os, sample)) = it.peek()
                    && (**os - sk).abs() <= 0.0
                {
                    found = Some(**sample);
                }
            }
            samples.push(match found {
                Some(sample) => sample,
                None => sampler.sample(self.path, sk)?,
            });
        }
        let mut rows = vec![Row::INACTIVE; s.len() * m];
        for (k, sample) in samples.iter().enumerate() {
            self.write_rows(sample, &mut rows[k * m..(k + 1) * m]);
        }
        let grid = Grid { s, samples, rows };
        self.check_at_rest(&grid)?;
        Ok(grid)
    }

    fn infeasible(
        &self,
        j: usize,
        sample: &PathSample,
        reason: &'static str,
        value: f64,
        limit: f64,
    ) -> PlanningError {
        let (c, r) = self.owners()[j];
        PlanningError::Infeasible(Box::new(Infeasibility {
            constraint: self.constraints[c].name().to_owned(),
            label: self.constraints[c].label(r),
            at: sample.place(),
            reason,
            value,
            limit,
            unit: self.constraints[c].unit().to_owned(),
        }))
    }

    /// Every row must hold with the platform at rest somewhere on its range of speeds: a row
    /// broken at `(u, x) = (0, 0)` is a limit no motion can meet.
    fn check_at_rest(&self, grid: &Grid) -> Result<(), PlanningError> {
        let m = self.width();
        for (k, sample) in grid.samples.iter().enumerate() {
            for (j, row) in grid.rows[k * m..(k + 1) * m].iter().enumerate() {
                if row.offset > row.upper || row.offset < row.lower {
                    let limit = if row.offset > row.upper {
                        row.upper
                    } else {
                        row.lower
                    };
                    return Err(self.infeasible(
                        j,
                        sample,
                        "the limit is broken with the machine at rest",
                        row.offset,
                        limit,
                    ));
                }
            }
        }
        Ok(())
    }

    fn bounds_check(&self, grid: &Grid, lin: &Linearized) -> Result<(), PlanningError> {
        let m = self.width();
        let n = grid.s.len();
        for (k, b) in lin.bounds.iter().enumerate() {
            let sample = &grid.samples[k];
            let interior = k > 0 && k < n - 1;
            if b.hi < b.lo
                || (interior && b.hi <= 0.0 && self.settings.boundary == Boundary::RestToRest)
                || (b.hi <= 0.0 && self.settings.boundary == Boundary::Periodic)
            {
                let j = if b.hi_row < m {
                    b.hi_row
                } else {
                    b.lo_row.min(m - 1)
                };
                let row = &grid.rows[k * m + j];
                return Err(self.infeasible(
                    j,
                    sample,
                    "no path speed meets it: the path cannot be traversed here",
                    row.offset,
                    row.upper.min(-row.lower),
                ));
            }
        }
        Ok(())
    }

    fn failure(&self, grid: &Grid, failure: Failure) -> PlanningError {
        match failure {
            Failure::Unbounded(k) => PlanningError::Unbounded {
                at: grid.samples[k].place(),
            },
            Failure::Empty(k) => PlanningError::Infeasible(Box::new(Infeasibility {
                constraint: "the limits together".into(),
                label: "all rows".into(),
                at: grid.samples[k].place(),
                reason: "no path speed here can be reached and left within the limits",
                value: f64::NAN,
                limit: f64::NAN,
                unit: String::new(),
            })),
        }
    }

    fn ends(&self) -> Ends {
        match self.settings.boundary {
            Boundary::RestToRest => Ends::Rest,
            Boundary::Periodic => Ends::Periodic,
        }
    }

    /// TOPP-RA on a sampled grid, with the `sqrt(x)` terms re-linearised at the solution.
    fn solve_grid(
        &self,
        grid: &Grid,
        point_scale: &[f64],
        constraint_scale: &[f64],
    ) -> Result<Profile, PlanningError> {
        let m = self.width();
        let owner: Vec<usize> = self.owners().iter().map(|o| o.0).collect();
        let any_sqrt = grid
            .rows
            .iter()
            .any(|r| r.sqrt_x.abs() > 0.0 && r.is_active() && (r.u.abs() > 0.0 || r.x.abs() > 0.0));
        let mut lin = Linearized::default();
        let mut work = Workspace::default();
        let mut profile = Profile::default();
        linearize(
            &grid.rows,
            m,
            &owner,
            point_scale,
            constraint_scale,
            None,
            &mut lin,
        );
        self.bounds_check(grid, &lin)?;
        topp::solve(&grid.s, &lin, self.ends(), &mut work, &mut profile)
            .map_err(|f| self.failure(grid, f))?;
        if !any_sqrt {
            return Ok(profile);
        }
        // The first pass dropped the friction terms that make limits harder: re-solve with
        // their tangents at the solution (each pass is feasible; the duration settles to 1e-8
        // in two or three passes).
        let mut previous = f64::INFINITY;
        for _ in 0..40 {
            let peak = profile.x.iter().fold(0.0f64, |a, &b| a.max(b));
            let floor = 1e-9 * peak + f64::MIN_POSITIVE;
            let tangent: Vec<f64> = profile.x.iter().map(|x| x.max(floor)).collect();
            linearize(
                &grid.rows,
                m,
                &owner,
                point_scale,
                constraint_scale,
                Some(&tangent),
                &mut lin,
            );
            topp::solve(&grid.s, &lin, self.ends(), &mut work, &mut profile)
                .map_err(|f| self.failure(grid, f))?;
            let t = topp::duration(&grid.s, &profile.x);
            if (t - previous).abs() <= 1e-8 * t {
                break;
            }
            previous = t;
        }
        Ok(profile)
    }

    /// Raw TOPP-RA on the grid `s` (ascending, from 0 to the path's length): no refinement,
    /// no dense check. For convergence studies and comparisons.
    ///
    /// # Errors
    /// Workspace, dynamics and infeasibility errors (with the place on the path).
    pub fn solve_on(&self, s: &[f64]) -> Result<Solution, PlanningError> {
        self.validate()?;
        let grid = self.sample_grid(s.to_vec(), None)?;
        let n = grid.s.len();
        let profile = self.solve_grid(&grid, &vec![1.0; n], &vec![1.0; self.constraints.len()])?;
        Ok(Solution {
            duration: topp::duration(&grid.s, &profile.x),
            controllable: profile
                .lo
                .iter()
                .copied()
                .zip(profile.hi.iter().copied())
                .collect(),
            s: grid.s,
            x: profile.x,
            u: profile.u,
        })
    }

    /// Raw TOPP-RA on `n` uniform intervals (plus the path's breakpoints).
    ///
    /// # Errors
    /// As [`Planner::solve_on`].
    pub fn solve_uniform(&self, n: usize) -> Result<Solution, PlanningError> {
        self.solve_on(&self.uniform(n))
    }

    fn new_check(&self) -> Check {
        Check::new(
            self.constraints
                .iter()
                .map(|c| (c.name().to_owned(), c.unit().to_owned())),
        )
    }

    fn label_check(&self, check: &mut Check) {
        for (usage, constraint) in check.constraints.iter_mut().zip(&self.constraints) {
            usage.label = constraint.label(usage.row);
        }
    }

    /// The rows at the `factor - 1` interior check points of every interval of `grid`
    /// (they do not depend on the timing: computed once per grid, reused while limits are
    /// tightened).
    fn dense_rows(&self, grid: &Grid, factor: usize) -> Result<Vec<Row>, PlanningError> {
        let sampler = self.sampler();
        let m = self.width();
        let n = grid.s.len();
        let mut rows = vec![Row::INACTIVE; (n - 1) * (factor - 1) * m];
        let mut chunks = rows.chunks_exact_mut(m);
        for k in 0..n - 1 {
            let (s0, s1) = (grid.s[k], grid.s[k + 1]);
            for j in 1..factor {
                let s = s0 + (s1 - s0) * j as f64 / factor as f64;
                let sample = sampler.sample(self.path, s)?;
                if let Some(chunk) = chunks.next() {
                    self.write_rows(&sample, chunk);
                }
            }
        }
        Ok(rows)
    }

    /// Dense check of a grid profile: `factor` points per interval (`dense`: the rows at the
    /// interior ones), the timing's own piecewise-constant `u`. Returns the check and the
    /// largest use per interval.
    fn check_profile(
        &self,
        grid: &Grid,
        dense: &[Row],
        profile: &Profile,
        factor: usize,
    ) -> Result<(Check, Vec<f64>), PlanningError> {
        let m = self.width();
        let owners = self.owners();
        let mut check = self.new_check();
        let n = grid.s.len();
        let mut worst = vec![0.0f64; n - 1];
        let mut t0 = 0.0;
        for (k, segment_worst) in worst.iter_mut().enumerate() {
            let (s0, s1) = (grid.s[k], grid.s[k + 1]);
            let (x0, u) = (profile.x[k], profile.u[k]);
            let root0 = x0.max(0.0).sqrt();
            for j in 0..=factor {
                let s = s0 + (s1 - s0) * j as f64 / factor as f64;
                let x = if j == factor {
                    profile.x[k + 1]
                } else {
                    (x0 + 2.0 * u * (s - s0)).max(0.0)
                };
                let s_dot = x.sqrt();
                let t = t0 + 2.0 * (s - s0) / (root0 + s_dot).max(f64::MIN_POSITIVE);
                let rows = if j == 0 {
                    &grid.rows[k * m..(k + 1) * m]
                } else if j == factor {
                    &grid.rows[(k + 1) * m..(k + 2) * m]
                } else {
                    let at = (k * (factor - 1) + j - 1) * m;
                    &dense[at..at + m]
                };
                check.samples += 1;
                for (r, row) in rows.iter().enumerate() {
                    if !row.is_active() {
                        continue;
                    }
                    let value = row.value(u, s_dot);
                    let usage = row.usage(value);
                    let limit = if value >= 0.0 { row.upper } else { row.lower };
                    let (c, local) = owners[r];
                    check.record(c, local, usage, value, limit, s, t);
                    *segment_worst = segment_worst.max(usage);
                }
            }
            t0 += 2.0 * (s1 - s0) / (root0 + profile.x[k + 1].max(0.0).sqrt());
        }
        self.label_check(&mut check);
        Ok((check, worst))
    }

    /// Dense check of any planned motion along this planner's path (shaped, smoothed, or
    /// from elsewhere): `per_piece` instants between consecutive breakpoints, the exact rows
    /// at the motion's `(s'', s')`, and the slider jerk against `jerk` if given.
    ///
    /// # Errors
    /// Workspace and dynamics errors where the motion's path parameter leaves the path's
    /// workspace.
    pub fn check_trajectory<P: Path>(
        &self,
        trajectory: &PlannedTrajectory<P>,
        per_piece: usize,
        jerk: Option<f64>,
    ) -> Result<Check, PlanningError> {
        use flexprr_kinematics::Trajectory;
        let start = trajectory.start();
        let end = trajectory
            .duration()
            .unwrap_or(start + trajectory.timing().duration());
        self.check_timing(
            &trajectory.breakpoints(),
            (start, end),
            per_piece,
            |t| trajectory.path_state(t),
            jerk,
        )
    }

    /// Dense check of any timing `s(t)` of this planner's path, given as the path state at a
    /// time (the scene's own timing of the path, to compare with the plan): `per_piece`
    /// instants between consecutive `breakpoints` within `span` (one-sided at the pieces'
    /// ends).
    ///
    /// # Errors
    /// As [`Planner::check_trajectory`].
    pub fn check_timing(
        &self,
        breakpoints: &[f64],
        span: (f64, f64),
        per_piece: usize,
        state_at: impl Fn(f64) -> PathState,
        jerk: Option<f64>,
    ) -> Result<Check, PlanningError> {
        let sampler = self.sampler();
        let m = self.width();
        let owners = self.owners();
        let mut rows = vec![Row::INACTIVE; m];
        let mut check = self.new_check();
        let jerk_index = check.constraints.len();
        if jerk.is_some() {
            check.constraints.push(Usage::new("slider_jerk", "m/s^3"));
        }
        let (start, end) = span;
        let mut times: Vec<f64> = breakpoints.to_vec();
        times.retain(|t| *t >= start && *t <= end);
        times.push(start);
        times.push(end);
        times.sort_by(f64::total_cmp);
        times.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * (1.0 + b.abs()));
        let length = self.path.length();
        let closed = self.path.is_closed();
        for w in times.windows(2) {
            for j in 0..=per_piece {
                let t = w[0] + (w[1] - w[0]) * j as f64 / per_piece as f64;
                // Just inside the piece at its ends (one-sided derivatives).
                let t = t.clamp(w[0] + 1e-12 * (w[1] - w[0]), w[1] - 1e-12 * (w[1] - w[0]));
                let state = state_at(t);
                let s = if closed {
                    state.s.rem_euclid(length)
                } else {
                    state.s
                };
                let sample = sampler.sample(self.path, s)?;
                self.write_rows(&sample, &mut rows);
                check.samples += 1;
                for (r, row) in rows.iter().enumerate() {
                    if !row.is_active() {
                        continue;
                    }
                    let value = row.value(state.s_ddot, state.s_dot);
                    let usage = row.usage(value);
                    let limit = if value >= 0.0 { row.upper } else { row.lower };
                    let (c, local) = owners[r];
                    check.record(c, local, usage, value, limit, s, t);
                }
                if let Some(limit) = jerk {
                    for (i, leg) in sample.legs.iter().enumerate() {
                        let value = leg.jerk(state.s_dot, state.s_ddot, state.s_dddot);
                        check.record(jerk_index, i, value.abs() / limit, value, limit, s, t);
                    }
                }
            }
        }
        self.label_check(&mut check);
        if jerk.is_some() {
            let usage = &mut check.constraints[jerk_index];
            usage.label = format!("leg {}", usage.row + 1);
        }
        Ok(check)
    }

    fn split(&self, grid: &Grid, worst: &[f64], scale: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let mut s = Vec::with_capacity(grid.s.len() * 2);
        let mut new_scale = Vec::with_capacity(grid.s.len() * 2);
        for k in 0..grid.s.len() - 1 {
            s.push(grid.s[k]);
            new_scale.push(scale[k]);
            if worst[k] > 1.0 + REFINE_ABOVE {
                s.push(0.5 * (grid.s[k] + grid.s[k + 1]));
                new_scale.push(scale[k].min(scale[k + 1]));
            }
        }
        s.push(grid.s[grid.s.len() - 1]);
        new_scale.push(scale[scale.len() - 1]);
        (s, new_scale)
    }

    /// The checked time-optimal motion on the grid with the given limit factors.
    fn checked(
        &self,
        constraint_scale: &[f64],
    ) -> Result<(Grid, Profile, Check, usize, usize), PlanningError> {
        let mut grid = self.sample_grid(self.uniform(self.settings.grid), None)?;
        let mut scale = vec![1.0; grid.s.len()];
        let mut rounds = 0;
        let mut tightened = vec![false; grid.s.len()];
        let factor = self.settings.check_factor;
        let mut dense = self.dense_rows(&grid, factor)?;
        for iteration in 0..40 {
            let profile = self.solve_grid(&grid, &scale, constraint_scale)?;
            let (check, worst) = self.check_profile(&grid, &dense, &profile, factor)?;
            if check.max_usage <= 1.0 + CHECK_TOLERANCE {
                let count = tightened.iter().filter(|t| **t).count();
                return Ok((grid, profile, check, rounds, count));
            }
            if check.max_usage.is_nan() {
                return Err(PlanningError::NotConverged {
                    what: "the dense check",
                    iterations: iteration,
                    detail: "a constraint gave NaN".into(),
                });
            }
            let coarse = worst.iter().any(|w| *w > 1.0 + REFINE_ABOVE);
            if coarse && rounds < self.settings.refinements {
                // Intervals that miss a feature of a limit by more than REFINE_ABOVE are split.
                let (s, new_scale) = self.split(&grid, &worst, &scale);
                let mut new_tightened = vec![false; s.len()];
                let mut i = 0;
                for (j, sj) in s.iter().enumerate() {
                    while i < grid.s.len() && grid.s[i] < *sj {
                        i += 1;
                    }
                    if i < grid.s.len() && (grid.s[i] - sj).abs() <= 0.0 {
                        new_tightened[j] = tightened[i];
                    }
                }
                grid = self.sample_grid(s, Some(&grid))?;
                dense = self.dense_rows(&grid, factor)?;
                scale = new_scale;
                tightened = new_tightened;
                rounds += 1;
            } else {
                // What is left is the interpolation error of a smooth limit between grid
                // points: lower the limits at both ends of those intervals by the excess.
                let n = grid.s.len();
                let mut factor = vec![1.0f64; n];
                for k in 0..n - 1 {
                    if worst[k] > 1.0 + CHECK_TOLERANCE {
                        let f = (1.0 - 1e-7) / worst[k];
                        factor[k] = factor[k].min(f);
                        factor[k + 1] = factor[k + 1].min(f);
                    }
                }
                if self.settings.boundary == Boundary::Periodic {
                    let f = factor[0].min(factor[n - 1]);
                    factor[0] = f;
                    factor[n - 1] = f;
                }
                for k in 0..n {
                    if factor[k] < 1.0 {
                        scale[k] *= factor[k];
                        tightened[k] = true;
                    }
                }
            }
        }
        Err(PlanningError::NotConverged {
            what: "holding the limits between grid points",
            iterations: 40,
            detail: "the dense check still finds a limit exceeded".into(),
        })
    }

    fn binding(&self, grid: &Grid, profile: &Profile) -> Vec<Binding> {
        let m = self.width();
        let owners = self.owners();
        let n = grid.s.len();
        let mut out: Vec<Binding> = Vec::new();
        for k in 0..n {
            let s_dot = profile.x[k].max(0.0).sqrt();
            let mut best = (0.0, usize::MAX);
            for u in [k.checked_sub(1), (k < n - 1).then_some(k)]
                .into_iter()
                .flatten()
            {
                for (j, row) in grid.rows[k * m..(k + 1) * m].iter().enumerate() {
                    if row.is_active() {
                        let usage = row.usage(row.value(profile.u[u], s_dot));
                        if usage > best.0 {
                            best = (usage, owners[j].0);
                        }
                    }
                }
            }
            let name = if best.0 >= 0.98 {
                self.constraints[best.1].name()
            } else {
                "none"
            };
            match out.last_mut() {
                Some(last) if last.constraint == name => last.to = grid.s[k],
                _ => out.push(Binding {
                    from: grid.s[k],
                    to: grid.s[k],
                    constraint: name.to_owned(),
                }),
            }
        }
        out
    }

    fn convergence(&self, constraint_scale: &[f64]) -> Result<Convergence, PlanningError> {
        let n = self.settings.grid;
        let intervals = [n, 2 * n, 4 * n];
        let mut durations = [0.0; 3];
        for (d, &i) in durations.iter_mut().zip(&intervals) {
            let grid = self.sample_grid(self.uniform(i), None)?;
            let profile = self.solve_grid(&grid, &vec![1.0; grid.s.len()], constraint_scale)?;
            *d = topp::duration(&grid.s, &profile.x);
        }
        let order =
            ((durations[0] - durations[1]).abs() / (durations[1] - durations[2]).abs()).log2();
        Ok(Convergence {
            intervals,
            durations,
            order,
        })
    }

    /// RMS motor torque per leg of a profile over the cycle (move plus dwell): the midpoint
    /// rule in time with `factor` points per interval.
    fn rms_of(
        &self,
        grid: &Grid,
        profile: &Profile,
        motor: &MotorTorque,
        dwell: f64,
    ) -> Result<[f64; 3], PlanningError> {
        self.rms_along(&grid.s, &profile.x, &profile.u, motor, dwell)
    }

    /// [`Planner::rms_of`] for the squared path speeds `x` and path accelerations `u` on the
    /// grid `s`.
    fn rms_along(
        &self,
        grid: &[f64],
        x: &[f64],
        u: &[f64],
        motor: &MotorTorque,
        dwell: f64,
    ) -> Result<[f64; 3], PlanningError> {
        let sampler = self.sampler();
        let factor = self.settings.check_factor;
        let mut sum = [0.0; 3];
        let mut total = 0.0;
        for k in 0..grid.len() - 1 {
            let (s0, x0, u) = (grid[k], x[k], u[k]);
            let v0 = x0.max(0.0).sqrt();
            let h = 2.0 * (grid[k + 1] - s0) / (v0 + x[k + 1].max(0.0).sqrt());
            for j in 0..factor {
                let tau = h * (j as f64 + 0.5) / factor as f64;
                let s = s0 + v0 * tau + 0.5 * u * tau * tau;
                let s_dot = (v0 + u * tau).max(0.0);
                let sample = sampler.sample(self.path, s)?;
                for (i, acc) in sum.iter_mut().enumerate() {
                    let torque = motor.torque(&sample, i, s_dot, u);
                    *acc += torque * torque * h / factor as f64;
                }
            }
            total += h;
        }
        let cycle = total + dwell;
        Ok(sum.map(|q| (q / cycle).sqrt()))
    }

    /// `plan` slowed uniformly by `factor` (>= 1): every instant of its timing `factor` times
    /// later, path speeds divided by `factor` and path accelerations by its square, its shaper
    /// and smoothing window kept, and its dense check and RMS torque made again; no limit
    /// binds it (its [`Plan::binding`] is `none` over the whole path). Without
    /// friction a slower motion of the horizontal machine needs less of every limit (slider
    /// speeds go with `1/factor`, rigid forces with `1/factor^2`); with friction and an RMS
    /// average over a dwell that is not so in general, so the limits are checked, not assumed.
    ///
    /// # Errors
    /// A `factor` below one or not finite ([`PlanningError::InvalidSpec`], key `stretch`); a
    /// limit the slower motion breaks ([`PlanningError::Slowed`]: which, by how much); the
    /// dense check's own errors.
    pub fn stretched(&self, plan: &Plan, factor: f64) -> Result<Plan, PlanningError> {
        if !(factor.is_finite() && factor >= 1.0) {
            return Err(PlanningError::InvalidSpec {
                key: "stretch",
                value: factor.to_string(),
                rule: "must be finite and >= 1 (a slower motion)".into(),
            });
        }
        let speeds: Vec<f64> = plan.timing.speeds().iter().map(|v| v / factor).collect();
        let timing = Timing::new(
            plan.timing.grid().to_vec(),
            speeds,
            plan.timing.is_periodic(),
        )?;
        let trajectory = PlannedTrajectory::new(self.path, timing.clone(), 0.0)?
            .with_shaper(plan.impulses.clone())?
            .with_smoothing(plan.smoothing)?;
        let check = self.check_trajectory(&trajectory, self.settings.check_factor, self.jerk)?;
        if check.max_usage > 1.0 + CHECK_TOLERANCE {
            let worst = check.worst().map_or_else(String::new, |u| {
                format!(
                    "{} ({}) at {:.4} of its limit",
                    u.constraint, u.label, u.usage
                )
            });
            return Err(PlanningError::Slowed {
                factor,
                detail: worst,
            });
        }
        let rms_torque = match &self.rms {
            Some(limit) => {
                let x: Vec<f64> = timing.speeds().iter().map(|v| v * v).collect();
                let rms = self.rms_along(
                    timing.grid(),
                    &x,
                    timing.accelerations(),
                    &limit.motor,
                    limit.dwell,
                )?;
                let worst = rms.iter().fold(0.0f64, |a, b| a.max(*b));
                if worst > limit.continuous_torque * (1.0 + CHECK_TOLERANCE) {
                    return Err(PlanningError::Slowed {
                        factor,
                        detail: format!(
                            "the RMS motor torque {worst:.4} N m exceeds the continuous torque {} N m (friction and the dwell weigh more in a longer cycle)",
                            limit.continuous_torque
                        ),
                    });
                }
                Some(rms)
            }
            None => plan.rms_torque,
        };
        // Slower than the optimum everywhere, so no limit binds (the caller names what
        // slowed it).
        let whole = (
            plan.timing.grid()[0],
            plan.timing.grid()[plan.timing.grid().len() - 1],
        );
        Ok(Plan {
            duration: timing.duration() + trajectory.extra_time(),
            timing,
            check,
            rms_torque,
            binding: vec![Binding {
                from: whole.0,
                to: whole.1,
                constraint: "none".into(),
            }],
            ..plan.clone()
        })
    }

    /// The checked time-optimal motion (module documentation).
    ///
    /// # Errors
    /// Bad settings ([`PlanningError::InvalidSpec`], [`PlanningError::OpenPath`]); a path
    /// that leaves the workspace; a limit no motion can meet (which, where); an iteration that
    /// does not converge.
    pub fn plan(&self) -> Result<Plan, PlanningError> {
        self.validate()?;
        let constraints = self.constraints.len();
        let mut scale = vec![1.0; constraints];
        let mut peak_factor = 1.0;
        let mut rms_torque = None;
        let (mut grid, mut profile, mut check, mut rounds, mut tightened) = self.checked(&scale)?;
        if let Some(limit) = &self.rms {
            let torque_rows: Vec<usize> = self
                .constraints
                .iter()
                .enumerate()
                .filter(|(_, c)| c.name() == "motor_torque")
                .map(|(i, _)| i)
                .collect();
            let worst = |r: [f64; 3]| r.iter().fold(0.0f64, |a, b| a.max(*b));
            let mut rms = self.rms_of(&grid, &profile, &limit.motor, limit.dwell)?;
            if worst(rms) > limit.continuous_torque {
                if torque_rows.is_empty() {
                    return Err(PlanningError::InvalidSpec {
                        key: "continuous_torque",
                        value: limit.continuous_torque.to_string(),
                        rule: "an RMS limit needs the motor_torque constraint".into(),
                    });
                }
                // Bisection on the peak-torque factor: [lo feasible, hi infeasible].
                let mut hi = 1.0;
                let mut lo = 0.5;
                let mut best = None;
                for _ in 0..60 {
                    for &i in &torque_rows {
                        scale[i] = lo;
                    }
                    let attempt = self.checked(&scale);
                    if let Ok(result) = attempt {
                        let r = self.rms_of(&result.0, &result.1, &limit.motor, limit.dwell)?;
                        if worst(r) <= limit.continuous_torque {
                            best = Some((result, r, lo));
                            break;
                        }
                    }
                    hi = lo;
                    lo *= 0.5;
                    if lo < 1e-4 {
                        break;
                    }
                }
                let Some(mut found) = best else {
                    return Err(PlanningError::NotConverged {
                        what: "the continuous-torque (RMS) limit",
                        iterations: 60,
                        detail: format!(
                            "even at 1e-4 of the peak torque the RMS torque exceeds {} N m (friction alone may exceed it)",
                            limit.continuous_torque
                        ),
                    });
                };
                while hi - found.2 > 1e-3 * hi {
                    let mid = 0.5 * (hi + found.2);
                    for &i in &torque_rows {
                        scale[i] = mid;
                    }
                    match self.checked(&scale) {
                        Ok(result) => {
                            let r = self.rms_of(&result.0, &result.1, &limit.motor, limit.dwell)?;
                            if worst(r) <= limit.continuous_torque {
                                found = (result, r, mid);
                            } else {
                                hi = mid;
                            }
                        }
                        Err(_) => hi = mid,
                    }
                }
                for &i in &torque_rows {
                    scale[i] = found.2;
                }
                peak_factor = found.2;
                ((grid, profile, check, rounds, tightened), rms) = (found.0, found.1);
            }
            rms_torque = Some(rms);
        }
        let optimal_duration = topp::duration(&grid.s, &profile.x);
        let convergence = if self.settings.convergence {
            Some(self.convergence(&scale)?)
        } else {
            None
        };
        let timing = self.timing(&grid, &profile)?;
        let binding = self.binding(&grid, &profile);
        let mut plan = Plan {
            boundary: self.settings.boundary,
            duration: optimal_duration,
            optimal_duration,
            timing,
            impulses: Vec::new(),
            smoothing: 0.0,
            tightening: 1.0,
            peak_torque_factor: peak_factor,
            rms_torque,
            grid_points: grid.s.len(),
            refinements: rounds,
            tightened_points: tightened,
            check: check.clone(),
            binding,
            convergence,
        };
        if self.jerk.is_some() || !self.impulses.is_empty() {
            plan = self.filtered(plan, &scale)?;
        }
        Ok(plan)
    }

    fn timing(&self, grid: &Grid, profile: &Profile) -> Result<Timing, PlanningError> {
        let speeds: Vec<f64> = profile.x.iter().map(|x| x.max(0.0).sqrt()).collect();
        Ok(Timing::new(
            grid.s.clone(),
            speeds,
            self.settings.boundary == Boundary::Periodic,
        )?)
    }

    /// Shaping and jerk smoothing with a dense check of the filtered motion; every limit is
    /// tightened by a common factor until the check passes.
    fn filtered(&self, base: Plan, scale: &[f64]) -> Result<Plan, PlanningError> {
        let per_piece = self.settings.check_factor;
        let mut lambda = 1.0;
        let mut plan = base;
        let mut window = 0.0;
        if let Some(limit) = self.jerk {
            // The box filter's own jerk: |rho'| (u_max - u_min) / W.
            let u = plan.timing.accelerations();
            let span = u.iter().fold(f64::NEG_INFINITY, |a, b| a.max(*b))
                - u.iter().fold(f64::INFINITY, |a, b| a.min(*b));
            let sampler = self.sampler();
            let mut rate = 0.0f64;
            for s in plan.timing.grid() {
                let sample = sampler.sample(self.path, *s)?;
                for leg in &sample.legs {
                    rate = rate.max(leg.d1.abs());
                }
            }
            window = (rate * span / limit).max(1e-6 * plan.duration);
        }
        for iteration in 0..60 {
            let trajectory = PlannedTrajectory::new(self.path, plan.timing.clone(), 0.0)?
                .with_shaper(self.impulses.clone())?
                .with_smoothing(window)?;
            let mut check = self.check_trajectory(&trajectory, per_piece, self.jerk)?;
            if check.max_usage <= 1.0 + CHECK_TOLERANCE {
                if self.jerk.is_some() {
                    // The shortest window that still meets every limit (bisection; the
                    // window found is feasible, a zero window is not).
                    let (mut lo, mut hi) = (0.0, window);
                    for _ in 0..12 {
                        let mid = 0.5 * (lo + hi);
                        let trial = PlannedTrajectory::new(self.path, plan.timing.clone(), 0.0)?
                            .with_shaper(self.impulses.clone())?
                            .with_smoothing(mid)?;
                        let attempt = self.check_trajectory(&trial, per_piece, self.jerk)?;
                        if attempt.max_usage <= 1.0 + CHECK_TOLERANCE {
                            hi = mid;
                            check = attempt;
                        } else {
                            lo = mid;
                        }
                    }
                    window = hi;
                }
                let trajectory = PlannedTrajectory::new(self.path, plan.timing.clone(), 0.0)?
                    .with_shaper(self.impulses.clone())?
                    .with_smoothing(window)?;
                plan.duration = plan.timing.duration() + trajectory.extra_time();
                plan.impulses = self.impulses.clone();
                plan.smoothing = window;
                plan.tightening = lambda;
                plan.check = check;
                return Ok(plan);
            }
            let jerk_usage = self.jerk.map_or(0.0, |_| {
                check.constraints[check.constraints.len() - 1].usage
            });
            let others = check.constraints[..self.constraints.len()]
                .iter()
                .fold(0.0f64, |a, u| a.max(u.usage));
            let mut retime = false;
            if others > 1.0 + CHECK_TOLERANCE {
                lambda *= (1.0 - 1e-6) / others;
                retime = true;
            }
            if jerk_usage > 1.0 + CHECK_TOLERANCE {
                // Widen the window for the part of the jerk it controls, and slow down too
                // once the window is long (the rest grows with the path speed).
                window *= jerk_usage.min(4.0);
                if iteration > 6 {
                    lambda *= 0.9;
                    retime = true;
                }
            }
            if retime {
                let scaled: Vec<f64> = scale.iter().map(|f| f * lambda).collect();
                let (grid, profile, _, _, _) = self.checked(&scaled)?;
                plan.timing = self.timing(&grid, &profile)?;
                plan.optimal_duration = topp::duration(&grid.s, &profile.x);
            }
        }
        Err(PlanningError::NotConverged {
            what: "shaping and jerk smoothing",
            iterations: 60,
            detail: "the filtered motion still exceeds a limit".into(),
        })
    }
}
