//! Timing flexprr's integrators over the tolerance ladder against a [`Reference`], model by
//! model and method by method.

use std::time::Instant as Clock;

use flexprr_dynamics::SceneModel;
use flexprr_integrators::{Options, Solution};
use flexprr_scene::{MethodHandle, ScenarioError, Scene};

use super::WorkPrecisionError;
use serde::{Deserialize, Serialize};

use super::config::first_repeat;
use super::{PACKAGE, Reference, WorkPrecisionConfig, build};

/// One point of the diagram: a package's method at one tolerance. Columns of
/// `work_precision.csv`; counts a package does not report are empty.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WorkPrecisionRow {
    /// Package (`flexprr`, `ode_solvers`, `scipy`, ...).
    pub package: String,
    /// Method within the package (`abm`, `dop853`, `LSODA`, ...).
    pub method: String,
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance (scalar).
    pub atol: f64,
    /// Median wall time of the timed runs (s).
    pub time_median_s: f64,
    /// Fastest timed run (s).
    pub time_min_s: f64,
    /// Number of timed runs.
    pub repeats: usize,
    /// Accepted steps.
    pub accepted_steps: Option<usize>,
    /// Rejected steps.
    pub rejected_steps: Option<usize>,
    /// Right-hand-side evaluations (including those of differenced Jacobians).
    pub rhs_evaluations: Option<usize>,
    /// Jacobian evaluations.
    pub jacobian_evaluations: Option<usize>,
    /// Relative error at the end time.
    pub end_error: f64,
    /// Relative error, maximum over the output times.
    pub max_error: f64,
    /// The model measured when models are set side by side (`ked (consistent)`, `coupled`,
    /// `nonlinear:16`); empty otherwise and for other packages' rows (a file without the
    /// column reads as empty).
    #[serde(default)]
    pub model: String,
}

impl WorkPrecisionRow {
    /// The row's series within its package: the method, after the model when there is one
    /// (`abm`, `nonlinear:16 abm`).
    pub fn series_label(&self) -> String {
        if self.model.is_empty() {
            self.method.clone()
        } else {
            format!("{} {}", self.model, self.method)
        }
    }
}

/// Wall times of repeated runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timing {
    /// Median (s).
    pub median_s: f64,
    /// Fastest (s).
    pub min_s: f64,
    /// Number of timed runs.
    pub repeats: usize,
}

/// Runs `run` `warmup` times untimed, then `repeats` times timed; returns the result of
/// the last run with the median and fastest wall time.
///
/// # Errors
/// The first error of `run`.
pub fn time_runs<T, E>(
    warmup: usize,
    repeats: usize,
    mut run: impl FnMut() -> Result<T, E>,
) -> Result<(T, Timing), E> {
    for _ in 0..warmup {
        run()?;
    }
    let repeats = repeats.max(1);
    let mut times = Vec::with_capacity(repeats);
    let mut last = None;
    for _ in 0..repeats {
        let clock = Clock::now();
        let out = run()?;
        times.push(clock.elapsed().as_secs_f64());
        last = Some(out);
    }
    times.sort_by(f64::total_cmp);
    let n = times.len();
    let median_s = if n % 2 == 1 {
        times[n / 2]
    } else {
        0.5 * (times[n / 2 - 1] + times[n / 2])
    };
    let timing = Timing {
        median_s,
        min_s: times[0],
        repeats: n,
    };
    match last {
        Some(out) => Ok((out, timing)),
        None => unreachable!("repeats is at least one"),
    }
}

/// A whole measurement: the reference, the rows, and the points that failed.
#[derive(Debug, Clone)]
pub struct WorkPrecision {
    /// The reference solution.
    pub reference: Reference,
    /// One row per method and tolerance that succeeded.
    pub rows: Vec<WorkPrecisionRow>,
    /// `method at rtol: reason` for each point that failed (e.g. too many steps).
    pub failures: Vec<String>,
}

/// Measures flexprr's integrators on `scene` over the ladder against `reference`, for each
/// model of [`WorkPrecisionConfig::measured_models`] (rows labelled by model when
/// [`WorkPrecisionConfig::models`] is set). Only the integration is timed; the errors
/// (and, in the deflection measure, the deflections) are computed afterwards.
/// `progress` sees each row as it is measured.
///
/// # Errors
/// [`ScenarioError::Input`] for a bad configuration or a reference of another measure,
/// [`WorkPrecisionError::Model`] if a model cannot be built. A point whose integration fails is
/// listed in the failures instead.
pub fn measure(
    scene: &Scene,
    reference: &Reference,
    config: &WorkPrecisionConfig,
    progress: &mut dyn FnMut(&WorkPrecisionRow),
) -> Result<(Vec<WorkPrecisionRow>, Vec<String>), WorkPrecisionError> {
    config.validate()?;
    let measure = config.error_measure(scene)?;
    if reference.measure != measure {
        return Err(WorkPrecisionError::Scene(ScenarioError::Input {
            location: None,
            key: "reference".to_string(),
            message: format!(
                "the reference is for the {} measure, the measurement uses the {} measure",
                reference.measure.name(),
                measure.name()
            ),
        }));
    }
    let models = config.measured_models(scene);
    let labels: Vec<String> = models.iter().map(|m| m.label(scene)).collect();
    if let Some(twice) = first_repeat(&labels, |a, b| a == b) {
        return Err(WorkPrecisionError::Scene(ScenarioError::Input {
            location: None,
            key: "models".to_string(),
            message: format!("{twice} is named twice (on scene {:?})", scene.name),
        }));
    }
    let (mut rows, mut failures) = (Vec::new(), Vec::new());
    for choice in models {
        let model_scene = choice.apply(scene)?;
        let label = if config.models.is_empty() {
            String::new()
        } else {
            choice.label(scene)
        };
        let mut system = build(&model_scene)?;
        let place = if label.is_empty() {
            String::new()
        } else {
            format!("{label}: ")
        };
        for method in &config.methods {
            // A linear-only method (magnus4, magnus6) does not apply to a coupled or
            // nonlinear model: said once, not once per tolerance.
            if let Err(why) = method_applies(&model_scene, method) {
                failures.push(format!("{place}{} skipped: {why}", method.name()));
                continue;
            }
            for &rtol in &config.tolerances {
                match measure_point(
                    &model_scene,
                    system.as_mut(),
                    reference,
                    config,
                    method,
                    rtol,
                ) {
                    Ok(mut row) => {
                        row.model.clone_from(&label);
                        progress(&row);
                        rows.push(row);
                    }
                    Err(why) => failures.push(format!("{place}{why}")),
                }
            }
        }
    }
    Ok((rows, failures))
}

/// One point of the diagram: `method` at `rtol` on the model of `model_scene` (`model`
/// built from it), timed over the configured warm-up and repeats, its error measured
/// against `reference` afterwards, untimed. The row's `model` is left empty for the caller.
///
/// # Errors
/// The one-line reason (method, tolerance, cause) if the integration fails, its solution
/// passes the run layer's divergence limit (a run-away solution is a failed point, not a
/// large error), or its error cannot be measured.
fn measure_point(
    model_scene: &Scene,
    model: &mut dyn SceneModel,
    reference: &Reference,
    config: &WorkPrecisionConfig,
    method: &MethodHandle,
    rtol: f64,
) -> Result<WorkPrecisionRow, String> {
    let atol = reference.atol(rtol);
    // The scene's spectral radius stays (generalized-alpha's; the other methods ignore it).
    let options = Options {
        spectral_radius: model_scene.options.spectral_radius,
        ..Options::default().rtol(rtol).atol(atol)
    };
    let (solution, timing) = time_runs(config.warmup, config.repeats, || {
        solve(model_scene, model, method, options.clone())
    })?;
    let at = |why: &dyn std::fmt::Display| format!("{} at rtol {rtol:e}: {why}", method.name());
    if let Some(diverged) = divergence(model, &solution) {
        return Err(at(&diverged));
    }
    let error = reference.errors_of(model, &solution).map_err(|e| at(&e))?;
    let s = &solution.stats;
    Ok(WorkPrecisionRow {
        package: PACKAGE.to_string(),
        method: method.name().to_string(),
        rtol,
        atol,
        time_median_s: timing.median_s,
        time_min_s: timing.min_s,
        repeats: timing.repeats,
        accepted_steps: Some(s.accepted_steps),
        rejected_steps: Some(s.rejected_steps),
        rhs_evaluations: Some(s.rhs_evaluations),
        jacobian_evaluations: Some(s.jacobian_evaluations),
        end_error: error.end,
        max_error: error.max,
        model: String::new(),
    })
}

/// Whether `method` can integrate the model of `scene`: the scene's own rule
/// ([`flexprr_scene::Registry::resolve_method`]: a linear-only method needs the KED model),
/// with `method` registered beside the built-ins (so a registered integrator is judged by its
/// own kind).
///
/// # Errors
/// The registry's one-line reason.
pub fn method_applies(scene: &Scene, method: &MethodHandle) -> Result<(), String> {
    let mut registry = flexprr_scene::Registry::default();
    registry.register_method(method);
    registry
        .resolve_method_for(
            method.name(),
            scene.coupling.capabilities().linear_in_state,
            flexprr_scene::mechanical_model(
                &scene.coupling,
                scene.controller.as_ref(),
                scene.actuator.as_ref(),
            ),
            scene.coupling.name(),
        )
        .map(|_| ())
}

/// Reference plus measurement for a scene.
///
/// # Errors
/// As [`Reference::compute`] and [`measure`].
pub fn work_precision(
    scene: &Scene,
    config: &WorkPrecisionConfig,
    progress: &mut dyn FnMut(&WorkPrecisionRow),
) -> Result<WorkPrecision, WorkPrecisionError> {
    let reference = Reference::compute(scene, config)?;
    let (rows, failures) = measure(scene, &reference, config, progress)?;
    Ok(WorkPrecision {
        reference,
        rows,
        failures,
    })
}

/// Solves the scene's model with `method` and `options` over the scene's output times,
/// stopping at the scene's stop times (the same loop as `flexprr run`). On failure, the
/// message names the method, the tolerance and the model's own cause when it has one (a
/// cause left over from an earlier run, e.g. a trial step of a rejected stage that an
/// integration recovered from, is cleared first so that it cannot be blamed).
fn solve(
    scene: &Scene,
    model: &mut dyn SceneModel,
    method: &MethodHandle,
    options: Options,
) -> Result<Solution, String> {
    let _ = model.take_failure();
    let rtol = options.rtol;
    let t_out = &scene.output_times;
    let y0 = model.initial_state();
    let stops = flexprr_run::stop_times(scene);
    method
        .integrator(options)
        .solve_dyn(model, t_out[0], &y0, t_out, &stops, &mut ())
        .map_err(|interrupted| match model.take_failure() {
            Some(cause) => format!(
                "{} at rtol {rtol:e}: {cause} (integrator: {interrupted})",
                method.name()
            ),
            None => format!("{} at rtol {rtol:e}: {interrupted}", method.name()),
        })
}

/// The first output time at which `solution` of `model` passes the run layer's divergence
/// limit ([`flexprr_run::guard::DivergenceGuard`], the check `flexprr run` makes after every
/// step, made here at the output times of a timed integration that ran without it).
fn divergence(model: &dyn SceneModel, solution: &Solution) -> Option<flexprr_run::RunError> {
    use flexprr_integrators::{Flow, Observer as _};
    let mut guard = flexprr_run::guard::DivergenceGuard::new(model);
    (0..solution.len()).find_map(|k| match guard.on_step(solution.t[k], solution.y(k)) {
        Flow::Stop => guard.take_divergence(),
        _ => None,
    })
}
