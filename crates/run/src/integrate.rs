//! Integrating a scene's model: the one place that drives an integrator. Progress, the
//! divergence guard and partial results on failure all hang on the integrators' observed
//! stepping loop; the trajectory's breakpoints and the scene's own stop times are passed as
//! stops, so no integrator steps over a motion that starts late.

use flexprr_dynamics::SceneModel;
use flexprr_integrators::{
    DynIntegrator, Flow, Interrupted, Interruption, Observer, Solution, Stats,
};
use flexprr_scene::Scene;

use crate::error::RunError;
use crate::guard::DivergenceGuard;

/// What an integration gave: the states at the output times reached, and why it stopped
/// early, if it did.
#[derive(Debug)]
pub struct Integration {
    /// States at the output times up to the last accepted time.
    pub solution: Solution,
    /// Why the integration stopped before the end, if it did.
    pub failure: Option<RunError>,
    /// Largest deflection seen on any link over the accepted steps (m).
    pub max_deflection_m: f64,
}

impl Integration {
    /// The integrator's statistics.
    pub fn stats(&self) -> &Stats {
        &self.solution.stats
    }
}

/// Reports progress as the fraction of the time span, at most once per percent.
struct Progress<'a> {
    t0: f64,
    span: f64,
    last: f64,
    report: &'a mut dyn FnMut(f64),
}

impl Observer for Progress<'_> {
    fn on_step(&mut self, t: f64, _y: &[f64]) -> Flow {
        let fraction = ((t - self.t0) / self.span).clamp(0.0, 1.0);
        if fraction - self.last >= 0.01 {
            self.last = fraction;
            (self.report)(fraction);
        }
        Flow::Continue
    }
}

/// Both observers of a run.
struct RunObserver<'a> {
    progress: Progress<'a>,
    guard: DivergenceGuard,
}

impl Observer for RunObserver<'_> {
    fn on_step(&mut self, t: f64, y: &[f64]) -> Flow {
        self.progress.on_step(t, y);
        self.guard.on_step(t, y)
    }
    fn on_output(&mut self, index: usize, t: f64, y: &[f64]) -> Flow {
        self.guard.on_output(index, t, y)
    }
}

/// The times at which every integration of `scene` stops and restarts: the trajectory's
/// breakpoints and the scene's own stop times, inside the span.
pub fn stop_times(scene: &Scene) -> Vec<f64> {
    let t = &scene.output_times;
    let (t0, t1) = (t[0], t[t.len() - 1]);
    let mut stops: Vec<f64> = scene
        .trajectory
        .breakpoints()
        .into_iter()
        .chain(scene.stop_times.iter().copied())
        .filter(|s| *s > t0 && *s < t1)
        .collect();
    stops.sort_by(f64::total_cmp);
    stops.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * t1.abs().max(1.0));
    stops
}

/// The largest deflection of any link at the guard's points over the output times of
/// `solution` (m), for a model the guard cannot tabulate (its deflection needs the time);
/// points it cannot evaluate are skipped.
fn sampled_max_deflection(model: &dyn SceneModel, solution: &Solution) -> f64 {
    let mut max = 0.0_f64;
    for k in 0..solution.len() {
        for i in 0..3 {
            for &xi in &crate::guard::GUARD_POINTS {
                if let Ok(w) = model.deflection(solution.t[k], i, xi, solution.y(k)) {
                    max = max.max(w.abs());
                }
            }
        }
    }
    max
}

/// Integrates `model` over the scene's output times with `integrator`, the divergence
/// guard and the scene's stop times. Never panics and never loses what was computed: a
/// failure comes back in [`Integration::failure`] with the outputs up to the last accepted
/// time.
pub fn integrate_model(
    scene: &Scene,
    integrator: &dyn DynIntegrator,
    model: &mut dyn SceneModel,
    report: &mut dyn FnMut(f64),
) -> Integration {
    let t = &scene.output_times;
    let (t0, span) = (t[0], t[t.len() - 1] - t[0]);
    let y0 = model.initial_state();
    let mut observer = RunObserver {
        progress: Progress {
            t0,
            span,
            last: 0.0,
            report,
        },
        guard: DivergenceGuard::new(model),
    };
    // The model's own stops (a sampled controller's samples) come from the model as the
    // run goes (`OdeSystem::next_stop`).
    let stops = stop_times(scene);
    let result = integrator.solve_dyn(model, t0, &y0, t, &stops, &mut observer);
    let mut max_deflection_m = observer.guard.max_deflection();
    if !model.linear_deflection() {
        let solution = match &result {
            Ok(solution) | Err(Interrupted { solution, .. }) => solution,
        };
        max_deflection_m = sampled_max_deflection(model, solution);
    }
    match result {
        Ok(solution) => Integration {
            solution,
            failure: None,
            max_deflection_m,
        },
        Err(Interrupted { solution, reason }) => {
            let error =
                match reason {
                    Interruption::Stopped { .. } => observer
                        .guard
                        .take_divergence()
                        .unwrap_or_else(|| RunError::Integrator {
                            method: integrator.name().to_string(),
                            source: flexprr_integrators::IntegratorError::InvalidInput(
                                "stopped by an observer".to_string(),
                            ),
                        }),
                    Interruption::Event { t } => match model.take_failure() {
                        Some(cause) => RunError::Model(cause),
                        None => RunError::Integrator {
                            method: integrator.name().to_string(),
                            source: flexprr_integrators::IntegratorError::TerminalEvent { t },
                        },
                    },
                    Interruption::Failed(source) => match model.take_failure() {
                        Some(cause) => RunError::Model(cause),
                        None => match source {
                            flexprr_integrators::IntegratorError::NonFinite { t, component } => {
                                RunError::NonFinite {
                                    method: integrator.name().to_string(),
                                    t,
                                    state: model.component_name(component),
                                    link: model.component_place(component).map(|(l, _, _)| l),
                                }
                            }
                            source => RunError::Integrator {
                                method: integrator.name().to_string(),
                                source,
                            },
                        },
                    },
                };
            Integration {
                solution,
                failure: Some(error),
                max_deflection_m,
            }
        }
    }
}
