//! How an integrator copes with a scene: solved (with its error against a reference), solved
//! but slow, or failed with a clear reason. Used by the stress suite (`configs/stress/`,
//! `docs/stability.md`).
//!
//! [`attempt`] integrates a scene's own model (KED or coupled, from the scene's one builder)
//! with a chosen registered method ([`MethodHandle`]; the scene's own method is ignored), resolved for that model the
//! way a scene resolves it (`auto` becomes `magnus6` on a KED model and `abm` otherwise; an
//! exponential method on a nonlinear model fails with the scene's message), through the run
//! layer's one observed stepping loop, so the integrator's work counters survive a failure
//! and the divergence guard ([`flexprr_run::guard`], one limit) stops a link that buckles with
//! [`Failure::Diverged`] instead of integrating to overflow.
//!
//! [`Attempt::classify`] then labels the attempt: [`Outcome::Solved`] with the relative
//! deflection error against a reference solution (the same scene with another integrator at
//! a much tighter tolerance), [`Outcome::SolvedSlow`] when it needed more right-hand-side
//! evaluations than a budget, or [`Outcome::Failed`].

use std::fmt;
use std::time::Instant as Clock;

use flexprr_dynamics::DynamicsError;
use flexprr_integrators::{IntegratorError, Solution, Stats};
use flexprr_run::RunError;
use flexprr_run::guard::{DeflectionModel, deflection_error};
use flexprr_scene::{MethodHandle, Scene};

/// Points `xi` along each link where deflections are checked and compared.
pub const CHECK_POINTS: [f64; 3] = [0.25, 0.5, 0.75];

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
    /// A link deflected beyond the divergence limit ([`flexprr_run::guard`]).
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
    /// The method does not integrate the scene's model (a linear-only method on a model
    /// that is not linear in its state, ...), in the registry's words.
    Method {
        /// The scene's name.
        scene: String,
        /// Why, and what to use instead.
        message: String,
    },
    /// The run failed for another reason (a non-finite state, an output that cannot be
    /// made): the run layer's kind, time and message.
    Run {
        /// [`RunError::kind`].
        kind: &'static str,
        /// [`RunError::time`].
        time: Option<f64>,
        /// The run layer's message.
        message: String,
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
            Failure::Method { scene, message } => write!(f, "{scene}: {message}"),
            Failure::Run { message, .. } => f.write_str(message),
        }
    }
}

/// One integration of a scene with one method.
#[derive(Debug, Clone)]
pub struct Attempt {
    /// The method asked for.
    pub method: MethodHandle,
    /// The method actually used: `method` itself, or the choice of `auto` for the model
    /// (`magnus6` on a KED model, `abm` otherwise).
    pub resolved: String,
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
    /// Right-hand-side evaluations used (including those of differenced Jacobians); for the
    /// exponential methods, evaluations of the linear form's coefficients (three per step
    /// attempt), a different unit: their costs are compared by wall time in
    /// `flexprr work-precision`.
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

impl From<RunError> for Failure {
    fn from(e: RunError) -> Self {
        match e {
            RunError::Diverged {
                link,
                t,
                xi,
                w,
                limit,
                ..
            } => Failure::Diverged {
                link,
                t,
                xi,
                deflection_m: w,
                limit_m: limit,
            },
            RunError::Model(source) => Failure::Model { source },
            RunError::Integrator { source, .. } => Failure::Integrator {
                error: source,
                stiffness_detected_at: None,
            },
            other => Failure::Run {
                kind: other.kind(),
                time: other.time(),
                message: other.to_string(),
            },
        }
    }
}

/// Integrates the scene's model with `method` and the scene's options through the run
/// layer's one stepping loop (divergence guard, stop times). Never panics on a failed run:
/// the failure is in [`Attempt::result`].
pub fn attempt(scene: &Scene, method: &MethodHandle) -> Attempt {
    let clock = Clock::now();
    let failed = |resolved: &str, failure: Failure| Attempt {
        method: method.clone(),
        resolved: resolved.to_string(),
        result: Err(failure),
        stats: Stats::default(),
        max_deflection_m: 0.0,
        wall_time_s: clock.elapsed().as_secs_f64(),
        deflection_model: None,
    };
    let mut model = match scene.build_model() {
        Ok(m) => m,
        Err(source) => return failed(method.name(), Failure::Model { source }),
    };
    // The method a scene naming `method` would run on this model.
    let linear = model.linear_form().is_some();
    let mechanical = flexprr_scene::mechanical_model(
        &scene.coupling,
        scene.controller.as_ref(),
        scene.actuator.as_ref(),
    );
    let mut registry = flexprr_scene::Registry::default();
    registry.register_method(method);
    let handle = match registry.resolve_method_for(method.name(), linear, mechanical, model.kind())
    {
        Ok(handle) => handle,
        Err(message) => {
            return failed(
                method.name(),
                Failure::Method {
                    scene: scene.name.clone(),
                    message,
                },
            );
        }
    };
    let resolved = handle.name().to_string();
    let integrator = handle.integrator(scene.options.clone());
    let integration =
        flexprr_run::integrate_model(scene, integrator.as_ref(), model.as_mut(), &mut |_| {});
    let stats = integration.solution.stats.clone();
    let result = match integration.failure {
        None => Ok(integration.solution),
        Some(e) => Err(match Failure::from(e) {
            Failure::Integrator { error, .. } => Failure::Integrator {
                error,
                stiffness_detected_at: stats.stiffness_detected_at,
            },
            other => other,
        }),
    };
    Attempt {
        method: method.clone(),
        resolved,
        result,
        stats,
        max_deflection_m: integration.max_deflection_m,
        wall_time_s: clock.elapsed().as_secs_f64(),
        deflection_model: Some(DeflectionModel::new(model.as_ref(), &CHECK_POINTS)),
    }
}
