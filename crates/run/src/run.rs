//! Running a scene: only the requested outputs are computed ("leave out what a scene does
//! not need"): a frequencies-only scene never integrates the ODE, a kinematics-only scene
//! never solves the inverse dynamics. The model comes from the scene's one builder
//! ([`Scene::build_model`]) or from the caller ([`run_model`]); the integration from the one
//! observed loop ([`integrate_model`]); every output kind from the shared samples and the
//! model's [`SceneModel`] interface, so nothing here knows which model it runs.

use std::time::Instant as Clock;

use flexprr_dynamics::{DynamicsError, MachineSnapshot, SceneModel};
use flexprr_integrators::{DynIntegrator, Solution};
use flexprr_scene::{OutputKind, Scene};

use crate::error::{RunError, RunFailure};
use crate::integrate::{Integration, integrate_model};
use crate::producer::{OutputContext, OutputRegistry};
use crate::samples::Samples;
use crate::table::{RunResult, RunStats};
use crate::variant::{self, OnFailure, SceneVariant, VariantRun};

/// The integrator the scene names, with the scene's options.
pub fn scene_integrator(scene: &Scene) -> Box<dyn DynIntegrator> {
    scene.method.integrator(scene.options.clone())
}

/// Integrates the scene's own model over its output times (progress to `report`).
///
/// # Errors
/// The model could not be built; a failed integration comes back inside the
/// [`Integration`] with its outputs up to the last accepted time.
pub fn integrate(
    scene: &Scene,
    report: &mut dyn FnMut(f64),
) -> Result<(Integration, Box<dyn SceneModel>), DynamicsError> {
    let mut model = scene.build_model()?;
    let integration = integrate_model(
        scene,
        scene_integrator(scene).as_ref(),
        model.as_mut(),
        report,
    );
    Ok((integration, model))
}

/// The integrated models of a run.
pub(crate) struct Integrated {
    pub(crate) model: Box<dyn SceneModel>,
    pub(crate) solution: Solution,
    /// The variant runs the scene asked for, by the variant's name (see [`crate::variant`]).
    pub(crate) variants: Vec<(&'static str, VariantRun)>,
    /// The model's [`MachineSnapshot`] at every output time reached, once an output needs
    /// them.
    snapshots: Option<Vec<MachineSnapshot>>,
}

impl Integrated {
    /// The model's snapshots at the solution's output times (computed once).
    pub(crate) fn snapshots(&mut self) -> Result<&[MachineSnapshot], DynamicsError> {
        if self.snapshots.is_none() {
            let all = (0..self.solution.len())
                .map(|k| self.model.snapshot(self.solution.t[k], self.solution.y(k)))
                .collect::<Result<Vec<_>, _>>()?;
            self.snapshots = Some(all);
        }
        Ok(self.snapshots.as_deref().unwrap_or(&[]))
    }
}

/// Runs a scene, computing only what it requests. `report` receives the progress of the
/// integration (fraction of the time span).
///
/// # Errors
/// A [`RunFailure`]: why the run stopped, with every requested output computed up to the
/// last accepted time.
pub fn run(scene: &Scene, report: &mut dyn FnMut(f64)) -> Result<RunResult, RunFailure> {
    run_with(scene, &OutputRegistry::built_in(), None, report)
}

/// [`run`] with the producers of `outputs` (the built-in ones and a program's own, see
/// [`crate::producer`]): every producer the scene wants is asked, in the registry's order.
///
/// # Errors
/// As [`run`]; a scene requesting an output (`output.custom`) no producer of `outputs`
/// makes fails with [`RunError::Output`] before any work.
pub fn run_registered(
    scene: &Scene,
    outputs: &OutputRegistry,
    report: &mut dyn FnMut(f64),
) -> Result<RunResult, RunFailure> {
    run_with(scene, outputs, None, report)
}

/// [`run`] with a model built outside the scene's builder: any [`SceneModel`] runs through
/// the same pipeline (outputs, failure outcome, divergence guard). The scene still gives the
/// commanded motion, the integrator, the output times and the requested outputs; the model
/// is integrated even when the requested outputs would not need it.
///
/// # Errors
/// As [`run`].
pub fn run_model(
    scene: &Scene,
    model: Box<dyn SceneModel>,
    report: &mut dyn FnMut(f64),
) -> Result<RunResult, RunFailure> {
    run_with(scene, &OutputRegistry::built_in(), Some(model), report)
}

/// [`run`] or [`run_model`]: `model` is the scene's own when `None`.
fn run_with(
    scene: &Scene,
    outputs: &OutputRegistry,
    model: Option<Box<dyn SceneModel>>,
    report: &mut dyn FnMut(f64),
) -> Result<RunResult, RunFailure> {
    let clock = Clock::now();
    let mut result = RunResult::default();
    let outcome = run_into(scene, outputs, model, report, &mut result);
    result.stats.wall_time_s = clock.elapsed().as_secs_f64();
    match outcome {
        Ok(()) => Ok(result),
        Err(error) => Err(RunFailure {
            error,
            partial: Box::new(result),
        }),
    }
}

/// Integrates `model` (the scene's own when `None`), then, when it reached the end, every
/// built-in variant the scene asks for ([`crate::variant::built_in`]) in order; the main
/// run and the variants that show progress share it equally. On failure, the error with the
/// partial states.
fn integrate_all(
    scene: &Scene,
    model: Option<Box<dyn SceneModel>>,
    report: &mut dyn FnMut(f64),
    stats: &mut RunStats,
) -> Result<(Integrated, Option<RunError>), RunError> {
    let mut model = match model {
        Some(model) => model,
        None => scene.build_model()?,
    };
    let wanted: Vec<&dyn SceneVariant> = variant::built_in()
        .into_iter()
        .filter(|v| v.wanted(scene))
        .collect();
    let shares = 1 + wanted.iter().filter(|v| v.shows_progress()).count();
    let share = 1.0 / shares as f64;
    let main = integrate_model(
        scene,
        scene_integrator(scene).as_ref(),
        model.as_mut(),
        &mut |f| report(share * f),
    );
    stats.integrated = true;
    stats.integrator = Some(main.stats().clone());
    stats.max_deflection_m = Some(main.max_deflection_m);
    let Integration {
        solution, failure, ..
    } = main;
    let mut integrated = Integrated {
        model,
        solution,
        variants: Vec::new(),
        snapshots: None,
    };
    if failure.is_some() {
        return Ok((integrated, failure));
    }
    let mut done = 1;
    for v in wanted {
        let start = done as f64 * share;
        let mut progress = |f: f64| report(start + share * f);
        let quiet = &mut |_: f64| {};
        let progress: &mut dyn FnMut(f64) = if v.shows_progress() {
            done += 1;
            &mut progress
        } else {
            quiet
        };
        let outcome = integrate_variant(scene, v, progress, stats);
        let run = match (outcome, v.on_failure()) {
            (Ok(Some(run)), _) => run,
            (Ok(None), _) => continue,
            (Err(e), OnFailure::Recorded) => VariantRun::Failed(e.to_string()),
            (Err(VariantFailure::Start(e)), OnFailure::FailsRun) => return Err(e),
            (Err(VariantFailure::Stopped(e)), OnFailure::FailsRun) => {
                return Ok((integrated, Some(e)));
            }
        };
        integrated.variants.push((v.name(), run));
    }
    Ok((integrated, None))
}

/// Why a variant run has no states: it could not start, or it stopped.
enum VariantFailure {
    Start(RunError),
    Stopped(RunError),
}

impl std::fmt::Display for VariantFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            VariantFailure::Start(e) | VariantFailure::Stopped(e) => e.fmt(f),
        }
    }
}

/// Integrates `variant` of `scene` over its output times (progress to `report`), adding its
/// work to `stats`; `None` when the scene has no such variant.
fn integrate_variant(
    scene: &Scene,
    variant: &dyn SceneVariant,
    report: &mut dyn FnMut(f64),
    stats: &mut RunStats,
) -> Result<Option<VariantRun>, VariantFailure> {
    let Some(changed) = variant.transform(scene).map_err(VariantFailure::Start)? else {
        return Ok(None);
    };
    let mut model = changed
        .build_model()
        .map_err(|e| VariantFailure::Start(e.into()))?;
    let integration = integrate_model(
        &changed,
        scene_integrator(&changed).as_ref(),
        model.as_mut(),
        report,
    );
    let counters = model.counters();
    stats.rhs_evaluations += counters.rhs_evaluations;
    stats.inverse_dynamics_solves += counters.inverse_dynamics_solves;
    match integration.failure {
        Some(e) => Err(VariantFailure::Stopped(e)),
        None => Ok(Some(VariantRun::Solved(model, integration.solution))),
    }
}

/// The body of [`run`]: fills `result` as far as it gets.
fn run_into(
    scene: &Scene,
    outputs: &OutputRegistry,
    model: Option<Box<dyn SceneModel>>,
    report: &mut dyn FnMut(f64),
    result: &mut RunResult,
) -> Result<(), RunError> {
    if let Some(missing) = scene
        .custom_outputs
        .iter()
        .find(|o| outputs.get(&o.name).is_none())
    {
        return Err(RunError::Output {
            output: missing.name.clone(),
            reason: "the scene requests it and no producer of the run makes it (give the \
                     run its producer: flexprr_run::run_registered)"
                .into(),
        });
    }
    let mut ked = scene.build_ked(false)?;
    let model = match model {
        None if scene.integrates_model() => Some(scene.build_model()?),
        model => model,
    };
    // Linearising along the motion takes the last part of the progress.
    let share = match &model {
        Some(m) if scene.outputs.contains(&OutputKind::MachineFrequencies) => {
            crate::machine_frequencies::integration_share(m.dim())
        }
        _ => 1.0,
    };
    let (mut integrated, failure) = if model.is_some() {
        let (i, f) = integrate_all(scene, model, &mut |f| report(share * f), &mut result.stats)?;
        (Some(i), f)
    } else {
        (None, None)
    };
    // Every output stops at the last time the integration reached.
    let times: Vec<f64> = match (&integrated, &failure) {
        (Some(i), Some(_)) => i.solution.t.clone(),
        _ => scene.output_times.clone(),
    };
    let mut later = |f: f64| report(share + (1.0 - share) * f);
    let outcome = produce(
        outputs,
        OutputContext {
            scene,
            times: &times,
            samples: None,
            ked: &mut ked,
            integrated: integrated.as_mut(),
            progress: &mut later,
        },
        result,
    );
    if let Some(i) = &integrated {
        let c = i.model.counters();
        result.stats.rhs_evaluations += c.rhs_evaluations;
        result.stats.inverse_dynamics_solves += c.inverse_dynamics_solves;
        if let Some(w) = result
            .stats
            .max_deflection_m
            .and_then(|d| i.model.deflection_advice(d))
        {
            result.warnings.push(w);
        }
    }
    if let Some(law) = &scene.controller {
        result.warnings.extend(law.warnings());
    }
    let c = ked.counters();
    result.stats.rhs_evaluations += c.rhs_evaluations;
    result.stats.inverse_dynamics_solves += c.inverse_dynamics_solves;
    outcome?;
    match failure {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// Asks every producer of `outputs` the scene wants, in order, into `result`; the shared
/// samples first, when one of them needs them. A producer that needs the integrated model is
/// skipped when the run did not integrate.
fn produce(
    outputs: &OutputRegistry,
    mut ctx: OutputContext<'_>,
    result: &mut RunResult,
) -> Result<(), RunError> {
    let wanted: Vec<_> = outputs
        .producers()
        .iter()
        .filter(|p| p.wanted(ctx.scene))
        .collect();
    if wanted.iter().any(|p| p.needs().samples) {
        ctx.samples = Some(Samples::new(ctx.scene, ctx.times)?);
    }
    for producer in wanted {
        if producer.needs().integration && ctx.integrated.is_none() {
            continue;
        }
        result.producers.push(producer.clone());
        producer.produce(&mut ctx, result)?;
    }
    Ok(())
}
