//! How an integrator copes with a scene: solved (with its error against a reference), solved
//! but slow, or failed with a clear reason. Used by the stress suite (`configs/stress/`,
//! `docs/stability.md`).
//!
//! [`attempt`] integrates a scene's modal ODE with a chosen [`Method`] (the scene's own method
//! is ignored), stepping by hand so that the integrator's work counters survive a failure and
//! so that the deflection of every link can be checked after each accepted step: the modal
//! equations are linear (small deflections), so a link that buckles grows exponentially and
//! the run is stopped with [`Failure::Diverged`] once a deflection exceeds a fraction of the
//! link length ([`Limits::deflection_fraction`]), instead of integrating to overflow.
//!
//! [`Attempt::classify`] then labels the attempt: [`Outcome::Solved`] with the relative
//! deflection error against a reference solution (the same scene with another integrator at
//! a much tighter tolerance), [`Outcome::SolvedSlow`] when it needed more right-hand-side
//! evaluations than a budget, or [`Outcome::Failed`].

use std::fmt;
use std::time::Instant as Clock;

use flexprr_dynamics::{DynamicsError, ModalSystem};
use flexprr_integrators::{
    Abm, Bdf, Integrator, IntegratorError, OdeSystem, Rk45, Solution, Stats, Stepper,
};

use flexprr_run::guard::{DeflectionModel, GUARD_POINTS};
use flexprr_scene::{Method, Scene};

/// Points `xi` along each link where deflections are checked and compared.
pub const CHECK_POINTS: [f64; 3] = [0.25, 0.5, 0.75];

/// Limits applied while integrating.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Largest transverse deflection allowed anywhere on a link, as a fraction of the link
    /// length. Beyond a few percent of the length the small-deflection (linear) beam model
    /// no longer holds, so a larger deflection is reported as a divergence. Default 0.1
    /// (20 mm on the paper's 0.2 m links, slopes up to about 0.3 rad).
    pub deflection_fraction: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            deflection_fraction: 0.1,
        }
    }
}

/// Why an attempt failed.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Failure {
    /// The integrator stopped (too many steps, step size collapse, non-finite values, ...).
    Integrator {
        /// The integrator's error (with the time).
        error: IntegratorError,
        /// When the method had found the problem stiff before it stopped, if it did.
        stiffness_detected_at: Option<f64>,
    },
    /// A link deflected beyond [`Limits::deflection_fraction`] of its length.
    Diverged {
        /// Link index (0-based).
        link: usize,
        /// Time of the first accepted step beyond the limit (s).
        t: f64,
        /// Position `xi` along the link where the limit was exceeded.
        xi: f64,
        /// The deflection there (m).
        deflection_m: f64,
        /// The limit (m).
        limit_m: f64,
    },
    /// The model failed inside the right-hand side or while being built (kinematics,
    /// singular inverse dynamics, inconsistent damping).
    Model {
        /// The dynamics error.
        source: DynamicsError,
    },
}

impl fmt::Display for Failure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Failure::Integrator {
                error,
                stiffness_detected_at,
            } => {
                write!(f, "{error}")?;
                if let Some(t) = stiffness_detected_at {
                    write!(f, " (stiffness detected at t = {t} s)")?;
                }
                Ok(())
            }
            Failure::Diverged {
                link,
                t,
                xi,
                deflection_m,
                limit_m,
            } => write!(
                f,
                "link {} diverged at t = {t} s: deflection {deflection_m:.3e} m at xi = {xi} exceeds the small-deflection limit {limit_m:.3e} m",
                link + 1
            ),
            Failure::Model { source } => write!(f, "{source}"),
        }
    }
}

/// One integration of a scene with one method.
#[derive(Debug, Clone)]
pub struct Attempt {
    /// The method used.
    pub method: Method,
    /// The states at the scene's output times, or why the integration stopped.
    pub result: Result<Solution, Failure>,
    /// The integrator's work counters (also when it failed).
    pub stats: Stats,
    /// Largest deflection seen on any link (at `xi` = 0.1, 0.2, ..., 0.9) over the accepted
    /// steps (m).
    pub max_deflection_m: f64,
    /// Wall-clock time (s); reported, never asserted.
    pub wall_time_s: f64,
    /// Deflections at [`CHECK_POINTS`] from modal states (for the error).
    deflection_model: Option<DeflectionModel>,
}

/// The classification of an [`Attempt`].
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Solved within the work budget.
    Solved {
        /// Relative deflection error against the reference (see [`deflection_error`]), when
        /// a reference was given.
        error: Option<f64>,
        /// Right-hand-side evaluations used.
        rhs_evaluations: usize,
    },
    /// Solved, but with more right-hand-side evaluations than the budget.
    SolvedSlow {
        /// Relative deflection error against the reference, when given.
        error: Option<f64>,
        /// Right-hand-side evaluations used.
        rhs_evaluations: usize,
        /// The budget it exceeded.
        budget: usize,
    },
    /// Failed with a reason.
    Failed {
        /// Why.
        reason: Failure,
    },
}

impl Outcome {
    /// A one-word label: `solved`, `slow` or `failed`.
    pub fn label(&self) -> &'static str {
        match self {
            Outcome::Solved { .. } => "solved",
            Outcome::SolvedSlow { .. } => "slow",
            Outcome::Failed { .. } => "failed",
        }
    }
    /// The error against the reference, for a solved attempt with a reference.
    pub fn error(&self) -> Option<f64> {
        match self {
            Outcome::Solved { error, .. } | Outcome::SolvedSlow { error, .. } => *error,
            Outcome::Failed { .. } => None,
        }
    }
}

impl Attempt {
    /// Right-hand-side evaluations used (including those of differenced Jacobians).
    pub fn rhs_evaluations(&self) -> usize {
        self.stats.rhs_evaluations
    }

    /// Classifies the attempt: failed if it failed; otherwise slow if it used more than
    /// `budget` right-hand-side evaluations, else solved. The error is measured against
    /// `reference` (same output times) when given.
    pub fn classify(&self, reference: Option<&Solution>, budget: Option<usize>) -> Outcome {
        let solution = match &self.result {
            Ok(s) => s,
            Err(reason) => {
                return Outcome::Failed {
                    reason: reason.clone(),
                };
            }
        };
        let error = reference.and_then(|r| self.deflection_error_against(solution, r));
        let rhs_evaluations = self.stats.rhs_evaluations;
        match budget {
            Some(budget) if rhs_evaluations > budget => Outcome::SolvedSlow {
                error,
                rhs_evaluations,
                budget,
            },
            _ => Outcome::Solved {
                error,
                rhs_evaluations,
            },
        }
    }

    fn deflection_error_against(&self, solution: &Solution, reference: &Solution) -> Option<f64> {
        self.deflection_model
            .as_ref()
            .and_then(|m| deflection_error(m, solution, reference))
    }
}

/// Relative deflection error of `solution` against `reference`: the largest difference of
/// the deflections at [`CHECK_POINTS`] of all links over all output times, divided by the
/// largest reference deflection there. `None` when the output times differ or the
/// reference is identically zero.
pub fn deflection_error(
    model: &DeflectionModel,
    solution: &Solution,
    reference: &Solution,
) -> Option<f64> {
    if solution.len() != reference.len() || solution.dim != reference.dim {
        return None;
    }
    let (mut worst, mut scale) = (0.0_f64, 0.0_f64);
    for k in 0..solution.len() {
        let (y, y_ref) = (solution.y(k), reference.y(k));
        for i in 0..3 {
            for p in 0..model.points() {
                let w_ref = model.deflection(i, p, y_ref);
                worst = worst.max((model.deflection(i, p, y) - w_ref).abs());
                scale = scale.max(w_ref.abs());
            }
        }
    }
    (scale > 0.0).then(|| worst / scale)
}

/// Integrates the scene's modal ODE with `method` and the scene's options, checking the
/// deflections after every accepted step against `limits`. Never panics on a failed run:
/// the failure is in [`Attempt::result`].
pub fn attempt(scene: &Scene, method: Method, limits: &Limits) -> Attempt {
    let clock = Clock::now();
    let failed = |source: DynamicsError| Attempt {
        method,
        result: Err(Failure::Model { source }),
        stats: Stats::default(),
        max_deflection_m: 0.0,
        wall_time_s: clock.elapsed().as_secs_f64(),
        deflection_model: None,
    };
    let mut system = match ModalSystem::new(
        scene.machine.clone(),
        scene.trajectory.clone(),
        scene.formulation,
        scene.damping.clone(),
    ) {
        Ok(s) => s,
        Err(e) => return failed(e),
    };
    let guard = DeflectionModel::new(scene, &system, &GUARD_POINTS);
    let lengths: [f64; 3] = std::array::from_fn(|i| scene.machine.links[i].length());
    let opts = scene.options.clone();
    let mut run = Run {
        guard: &guard,
        limits: [0, 1, 2].map(|i| limits.deflection_fraction * lengths[i]),
        max_deflection: 0.0,
    };
    let (result, stats) = match method {
        Method::Abm => run.drive(&Abm::new(opts), &mut system, &scene.output_times),
        Method::Rk45 => run.drive(&Rk45::new(opts), &mut system, &scene.output_times),
        Method::Bdf => run.drive(&Bdf::new(opts), &mut system, &scene.output_times),
    };
    let result = result.map_err(|e| match e {
        Failure::Integrator { .. } => match system.take_failure() {
            Some(source) => Failure::Model { source },
            None => e,
        },
        other => other,
    });
    Attempt {
        method,
        result,
        stats,
        max_deflection_m: run.max_deflection,
        wall_time_s: clock.elapsed().as_secs_f64(),
        deflection_model: Some(DeflectionModel::new(scene, &system, &CHECK_POINTS)),
    }
}

/// The stepping loop with the deflection guard.
struct Run<'a> {
    guard: &'a DeflectionModel,
    limits: [f64; 3],
    max_deflection: f64,
}

impl Run<'_> {
    /// Like [`Integrator::solve`], but keeps the statistics on failure and stops when a
    /// deflection exceeds its limit.
    fn drive<I: Integrator, S: OdeSystem>(
        &mut self,
        integrator: &I,
        system: &mut S,
        t_out: &[f64],
    ) -> (Result<Solution, Failure>, Stats) {
        let integ = |error: IntegratorError, stats: &Stats| Failure::Integrator {
            error,
            stiffness_detected_at: stats.stiffness_detected_at,
        };
        let y0 = vec![0.0; system.dim()];
        let (t0, t_end) = (t_out[0], t_out[t_out.len() - 1]);
        let mut solution = Solution::with_capacity(y0.len(), t_out.len());
        solution.push(t0, &y0);
        let mut stepper = match integrator.start(system, t0, &y0, t_end) {
            Ok(s) => s,
            Err(e) => return (Err(integ(e, &Stats::default())), Stats::default()),
        };
        let mut buf = y0;
        let mut k = 1;
        while k < t_out.len() {
            if let Err(e) = stepper.step(system) {
                let stats = stepper.stats().clone();
                return (Err(integ(e, &stats)), stats);
            }
            let t_now = stepper.t();
            if let Some(failure) = self.check(t_now, stepper.y()) {
                return (Err(failure), stepper.stats().clone());
            }
            while k < t_out.len() && t_out[k] <= t_now {
                if (t_out[k] - t_now).abs() <= f64::EPSILON * t_now.abs().max(1.0) {
                    buf.copy_from_slice(stepper.y());
                } else {
                    stepper.interpolate(t_out[k], &mut buf);
                }
                solution.push(t_out[k], &buf);
                k += 1;
            }
        }
        solution.stats = stepper.stats().clone();
        let stats = solution.stats.clone();
        (Ok(solution), stats)
    }

    fn check(&mut self, t: f64, y: &[f64]) -> Option<Failure> {
        for (i, limit) in self.limits.iter().enumerate() {
            for (p, xi) in GUARD_POINTS.iter().enumerate() {
                let w = self.guard.deflection(i, p, y);
                self.max_deflection = self.max_deflection.max(w.abs());
                if w.abs() > *limit {
                    return Some(Failure::Diverged {
                        link: i,
                        t,
                        xi: *xi,
                        deflection_m: w,
                        limit_m: *limit,
                    });
                }
            }
        }
        None
    }
}
