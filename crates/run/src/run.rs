//! Running a scene: only the requested outputs are computed ("leave out what a scene does
//! not need"): a frequencies-only scene never integrates the ODE, a kinematics-only scene
//! never solves the inverse dynamics. The model comes from the scene's one builder
//! ([`Scene::build_model`]); the integration from the one observed loop
//! ([`integrate_model`]); every output kind from the shared samples, so the inverse
//! kinematics is computed once per output time.

use std::time::Instant as Clock;

use flexprr_dynamics::{CouplingModel, DynamicsError, ModalSystem, SceneModel};
use flexprr_integrators::{DynIntegrator, Solution};
use flexprr_scene::{OutputKind, Scene};

use crate::error::{RunError, RunFailure};
use crate::integrate::{Integration, integrate_model};
use crate::outputs;
use crate::samples::Samples;
use crate::table::{RunResult, RunStats};
use crate::viewer;

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
struct Integrated {
    model: Box<dyn SceneModel>,
    solution: Solution,
    without_axial: Option<(Box<dyn SceneModel>, Solution)>,
}

/// Runs a scene, computing only what it requests. `report` receives the progress of the
/// integration (fraction of the time span).
///
/// # Errors
/// A [`RunFailure`]: why the run stopped, with every requested output computed up to the
/// last accepted time.
pub fn run(scene: &Scene, report: &mut dyn FnMut(f64)) -> Result<RunResult, RunFailure> {
    let clock = Clock::now();
    let mut result = RunResult::default();
    let outcome = run_into(scene, report, &mut result);
    result.stats.wall_time_s = clock.elapsed().as_secs_f64();
    match outcome {
        Ok(()) => Ok(result),
        Err(error) => Err(RunFailure {
            error,
            partial: Box::new(result),
        }),
    }
}

fn wants(scene: &Scene, kind: OutputKind) -> bool {
    scene.outputs.contains(&kind)
}

/// Whether the scene's main model must be integrated: for its states, or (coupled,
/// nonlinear) for its actual forces.
fn needs_model_integration(scene: &Scene) -> bool {
    scene.needs_integration()
        || (scene.coupling != CouplingModel::Ked
            && (wants(scene, OutputKind::AxialForces) || wants(scene, OutputKind::DrivingForces)))
}

/// Largest deflection of a coupled run, as a fraction of the link length, beyond which the
/// run warns and recommends the nonlinear model. Measured on the paper scene at 30 Hz
/// (docs/coupled.md, "Which model when"): the coupled mid-point deflections leave 5 %
/// (relative L2 over 10 ms windows) of the nonlinear model's when the largest deflection has
/// reached 11 % of the link length, and are within 1 % of it up to 5 %. The warning comes at
/// 5 %: the coupled results are still good there, and a collapsing run is told early (at
/// 30 Hz the largest deflection passes 5 % at about 11 ms, the 10 % collapse limit at 29.8 ms).
pub const NONLINEAR_ADVICE_FRACTION: f64 = 0.05;

/// The warning of a coupled run whose deflection passed [`NONLINEAR_ADVICE_FRACTION`].
fn large_deflection_warning(scene: &Scene, max_deflection: f64) -> Option<String> {
    let length = scene.machine.links[0].length();
    let fraction = max_deflection / length;
    (scene.coupling == CouplingModel::Coupled && fraction > NONLINEAR_ADVICE_FRACTION).then(|| {
        format!(
            "the largest link deflection reached {:.1} mm ({:.1} % of the link length, above {:.0} %): \
             the coupled model assumes small deflections and drifts from a geometrically exact one \
             beyond this; rerun with model.coupling = \"nonlinear\" (docs/coupled.md)",
            max_deflection * 1e3,
            100.0 * fraction,
            100.0 * NONLINEAR_ADVICE_FRACTION
        )
    })
}

/// Integrates what the scene needs; on failure, the error with the partial states.
fn integrate_all(
    scene: &Scene,
    report: &mut dyn FnMut(f64),
    stats: &mut RunStats,
) -> Result<(Integrated, Option<RunError>), RunError> {
    let (main, model) = integrate(scene, report)?;
    stats.integrated = true;
    stats.integrator = Some(main.stats().clone());
    stats.max_deflection_m = Some(main.max_deflection_m);
    let Integration {
        solution, failure, ..
    } = main;
    let mut integrated = Integrated {
        model,
        solution,
        without_axial: None,
    };
    if failure.is_none()
        && integrated.model.as_modal().is_some()
        && scene.file.output.compare_without_axial_force
    {
        let mut plain = scene.build_model_without_axial_force()?;
        let integ = integrate_model(
            scene,
            scene_integrator(scene).as_ref(),
            plain.as_mut(),
            &mut |_| {},
        );
        let counters = plain.counters();
        stats.rhs_evaluations += counters.rhs_evaluations;
        stats.inverse_dynamics_solves += counters.inverse_dynamics_solves;
        if let Some(e) = integ.failure {
            return Ok((integrated, Some(e)));
        }
        integrated.without_axial = Some((plain, integ.solution));
    }
    Ok((integrated, failure))
}

/// The body of [`run`]: fills `result` as far as it gets.
fn run_into(
    scene: &Scene,
    report: &mut dyn FnMut(f64),
    result: &mut RunResult,
) -> Result<(), RunError> {
    let mut ked = scene.build_ked(false)?;
    let (mut integrated, failure) = if needs_model_integration(scene) {
        let (i, f) = integrate_all(scene, report, &mut result.stats)?;
        (Some(i), f)
    } else {
        (None, None)
    };
    // Every output stops at the last time the integration reached.
    let times: Vec<f64> = match (&integrated, &failure) {
        (Some(i), Some(_)) => i.solution.t.clone(),
        _ => scene.output_times.clone(),
    };
    let outcome = produce(scene, &times, &mut ked, integrated.as_mut(), result);
    if let Some(i) = &integrated {
        let c = i.model.counters();
        result.stats.rhs_evaluations += c.rhs_evaluations;
        result.stats.inverse_dynamics_solves += c.inverse_dynamics_solves;
    }
    let c = ked.counters();
    result.stats.rhs_evaluations += c.rhs_evaluations;
    result.stats.inverse_dynamics_solves += c.inverse_dynamics_solves;
    if let Some(w) = result
        .stats
        .max_deflection_m
        .and_then(|d| large_deflection_warning(scene, d))
    {
        result.warnings.push(w);
    }
    outcome?;
    match failure {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

/// Produces every requested output at `times` into `result`.
fn produce(
    scene: &Scene,
    times: &[f64],
    ked: &mut ModalSystem,
    mut integrated: Option<&mut Integrated>,
    result: &mut RunResult,
) -> Result<(), RunError> {
    let rigid_outputs = [
        OutputKind::Kinematics,
        OutputKind::DrivingForces,
        OutputKind::JointReactions,
        OutputKind::AxialForces,
        OutputKind::ModalForces,
        OutputKind::Energies,
        OutputKind::Viewer,
        OutputKind::Snapshots,
        OutputKind::Machine,
    ];
    let mut samples = if rigid_outputs.iter().any(|k| wants(scene, *k)) {
        Some(Samples::new(scene, times)?)
    } else {
        None
    };
    let tables = &mut result.tables;
    if let Some(s) = samples.as_mut() {
        if wants(scene, OutputKind::Kinematics) {
            tables.push(outputs::kinematics(s));
        }
        if wants(scene, OutputKind::DrivingForces) {
            let flexible = integrated.as_deref_mut().and_then(|i| {
                let solution = &i.solution;
                i.model.as_modal().map(|m| (m, solution))
            });
            let (table, solves) = outputs::driving_forces(scene, s, flexible)?;
            result.stats.inverse_dynamics_solves += solves;
            tables.push(table);
        }
        if wants(scene, OutputKind::JointReactions) {
            tables.push(outputs::joint_reactions(scene, s)?);
        }
        if wants(scene, OutputKind::AxialForces) {
            tables.push(outputs::axial_forces(scene, s)?);
        }
        if wants(scene, OutputKind::Machine) {
            result.documents.push(viewer::machine_file(scene, s)?);
        }
    }
    if wants(scene, OutputKind::Frequencies) {
        let (table, hist) = outputs::frequencies(ked, times)?;
        tables.push(table);
        result.frequencies = Some(hist);
    }
    let Some(integrated) = integrated else {
        return Ok(());
    };
    if let Some(system) = integrated.model.as_nonlinear() {
        let produced = crate::nonlinear::tables(scene, system, &integrated.solution)?;
        tables.extend(produced.tables);
        result.stats.max_deflection_m = Some(produced.max_midpoint_deflection);
        return Ok(());
    }
    if let Some(coupled) = integrated.model.as_coupled() {
        tables.extend(outputs::coupled(coupled, &integrated.solution)?);
    }
    let (model, solution) = (integrated.model.as_ref(), &integrated.solution);
    if wants(scene, OutputKind::Modes) {
        tables.push(outputs::modes(model, solution));
    }
    if wants(scene, OutputKind::Deflections) {
        let plain = integrated
            .without_axial
            .as_ref()
            .map(|(m, s)| (m.as_ref(), s));
        tables.push(outputs::deflections(scene, model, solution, plain));
    }
    if let Some(s) = samples.as_ref() {
        if wants(scene, OutputKind::ModalForces) {
            tables.push(outputs::modal_forces(scene, s));
        }
        if wants(scene, OutputKind::Energies) {
            tables.push(outputs::energies(scene, model, s, solution));
        }
        if wants(scene, OutputKind::Viewer) || wants(scene, OutputKind::Snapshots) {
            let data = viewer::viewer_data(
                scene,
                s,
                model,
                solution,
                ked,
                result.frequencies.as_ref(),
                &result.tables,
            )?;
            result.documents.extend(viewer::viewer_files(scene, &data)?);
            result.viewer = Some(data);
        }
    }
    Ok(())
}
