//! State-space export of a scene's linear model (`flexprr statespace`, docs/linear.md):
//! `statespace.npz` (NumPy: `A`, `B`, `C`, `D` as `float64` matrices, the operating point
//! `x0`, `y0`, the period `dt`, the state's scales, and the names of the inputs, outputs and
//! states as unicode arrays, also as identifiers) and `statespace.json` (the same, with
//! units, the operating point, notes and the modes).
//!
//! The model is `x' = A x + B u`, `y = C x + D u` in deviations from the operating point,
//! or `x[k+1] = A x[k] + B u[k]` at the period `dt` of a sampled control law: `x` the
//! model's state (coordinates, their rates, then the control law's states) less `x0`,
//! divided by `state_scale` in the scaled realisation (the default:
//! `flexprr_linear::realization`), `y` the outputs less `y0`, `u` the inputs. Along a motion
//! (`--times`) the arrays gain a leading time axis: `A[k]` at `t[k]`, all from one
//! integration.

use std::time::Instant;

use flexprr_linear::realization::{Realization, realize, rescaled};
use flexprr_linear::{
    Input, Linearization, Mode, Output, Settings, linearize_with_settings, modes,
};
use flexprr_scene::{ScenarioError, Scene};
use serde_json::{Value, json};

use crate::frf::{modes_json, operating_point_json};
use crate::linear::{OperatingPoint, along_motion_states, linear_error, operating_point};
use crate::npz::{NpyData, npz};
use flexprr_run::RunError;

/// What to export.
#[derive(Debug, Clone, PartialEq)]
pub struct StateSpaceRequest {
    /// The inputs.
    pub inputs: Vec<Input>,
    /// The outputs.
    pub outputs: Vec<Output>,
    /// How the model is linearised.
    pub settings: Settings,
    /// How its state is realised.
    pub realization: Realization,
}

impl StateSpaceRequest {
    /// The default settings and the scaled realisation for `inputs` and `outputs`.
    pub fn new(inputs: Vec<Input>, outputs: Vec<Output>) -> Self {
        Self {
            inputs,
            outputs,
            settings: Settings::default(),
            realization: Realization::default(),
        }
    }
}

/// A scene's linear model with what its files say about it.
#[derive(Debug, Clone)]
pub struct StateSpace {
    /// Where it was taken.
    pub at: OperatingPoint,
    /// The model kind.
    pub model: String,
    /// The linear model in physical units.
    pub lin: Linearization,
    /// The model as exported (realised).
    pub exported: Linearization,
    /// The realisation of the exported model.
    pub realization: Realization,
    /// The state's scales: physical state = scale * exported state.
    pub scale: Vec<f64>,
    /// A name for each state component.
    pub states: Vec<String>,
    /// The modes of `A`.
    pub modes: Vec<Mode>,
}

/// Refuses a request without inputs or without outputs (a model without them has no
/// transfer to export; `flexprr modes` gives the modes).
///
/// # Errors
/// Bad input at `--input` or `--output`.
pub fn check_channels(inputs: &[Input], outputs: &[Output]) -> Result<(), RunError> {
    if inputs.is_empty() || outputs.is_empty() {
        return Err(RunError::Scene(ScenarioError::Input {
            location: None,
            key: if inputs.is_empty() {
                "--input"
            } else {
                "--output"
            }
            .into(),
            message: "give at least one input and one output (e.g. --input slider_force:1 \
                      --output slider:1); flexprr modes gives the modes alone"
                .into(),
        }));
    }
    Ok(())
}

/// The state-space model of `scene` at `at` for `request` (any channels: the Python API
/// takes a model without them for its modes; the command refuses it first).
///
/// # Errors
/// As [`crate::linear::linear_model`], or the eigenvalues of `A` failed.
pub fn state_space(
    scene: &Scene,
    at: OperatingPoint,
    request: &StateSpaceRequest,
) -> Result<StateSpace, RunError> {
    let mut point = operating_point(scene, at)?;
    let lin = linearize_with_settings(
        point.model.as_mut(),
        point.t,
        &point.state,
        &request.inputs,
        &request.outputs,
        &request.settings,
    )
    .map_err(|e| linear_error(scene, e))?;
    finish(scene, at, lin, request.realization, None)
}

/// The exported form of `lin`: realised (with `scale` when given, else its own), its modes.
fn finish(
    scene: &Scene,
    at: OperatingPoint,
    lin: Linearization,
    realization: Realization,
    scale: Option<&[f64]>,
) -> Result<StateSpace, RunError> {
    let modes = modes(&lin).map_err(|e| linear_error(scene, e))?;
    let (exported, scale) = match scale {
        Some(s) => (rescaled(&lin, s), s.to_vec()),
        None => realize(&lin, realization),
    };
    Ok(StateSpace {
        at,
        model: scene.coupling.name().to_string(),
        states: lin.states.iter().map(|s| s.name.clone()).collect(),
        exported,
        realization,
        scale,
        lin,
        modes,
    })
}

/// Linear models along the scene's motion from one integration (`--times`).
#[derive(Debug, Clone)]
pub struct StateSpaceSeries {
    /// The times (s).
    pub times: Vec<f64>,
    /// The model at each time, all realised with the scales of the first.
    pub models: Vec<StateSpace>,
    /// Wall-clock time of the integration (s).
    pub integration_s: f64,
    /// Wall-clock time of the linearisations (s).
    pub linearisation_s: f64,
}

/// The state-space models of `scene` along its motion at `times` (increasing, within its
/// span): one integration to the last time, a linearisation at each.
///
/// # Errors
/// As [`along_motion_states`]; a linearisation that fails (with its time).
pub fn state_space_series(
    scene: &Scene,
    times: &[f64],
    request: &StateSpaceRequest,
    progress: &mut dyn FnMut(f64),
) -> Result<StateSpaceSeries, RunError> {
    let clock = Instant::now();
    let (mut model, states) = along_motion_states(scene, times)?;
    let integration_s = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    let mut models: Vec<StateSpace> = Vec::with_capacity(times.len());
    for (k, (t, y)) in times.iter().zip(&states).enumerate() {
        progress(k as f64 / times.len() as f64);
        let lin = linearize_with_settings(
            model.as_mut(),
            *t,
            y,
            &request.inputs,
            &request.outputs,
            &request.settings,
        )
        .map_err(|e| match linear_error(scene, e) {
            RunError::Analysis {
                analysis: None,
                source,
            } => RunError::Analysis {
                analysis: Some(format!("at t = {t} s")),
                source,
            },
            other => other,
        })?;
        let scale = models.first().map(|m| m.scale.clone());
        models.push(finish(
            scene,
            OperatingPoint::Time(*t),
            lin,
            request.realization,
            scale.as_deref(),
        )?);
    }
    progress(1.0);
    Ok(StateSpaceSeries {
        times: times.to_vec(),
        models,
        integration_s,
        linearisation_s: clock.elapsed().as_secs_f64(),
    })
}

/// The names' arrays of `statespace.npz`.
fn name_arrays(ss: &StateSpace) -> Vec<(&'static str, NpyData)> {
    let lin = &ss.lin;
    let names = |v: Vec<String>| NpyData::Unicode(v);
    vec![
        (
            "inputs",
            names(lin.inputs.iter().map(ToString::to_string).collect()),
        ),
        (
            "outputs",
            names(lin.outputs.iter().map(ToString::to_string).collect()),
        ),
        ("states", names(ss.states.clone())),
        (
            "input_signals",
            names(lin.inputs.iter().map(Input::signal_name).collect()),
        ),
        (
            "output_signals",
            names(lin.outputs.iter().map(Output::signal_name).collect()),
        ),
        (
            "state_signals",
            names(lin.states.iter().map(|s| s.signal.clone()).collect()),
        ),
        (
            "input_units",
            names(lin.inputs.iter().map(|i| i.unit().to_string()).collect()),
        ),
        (
            "output_units",
            names(lin.outputs.iter().map(|o| o.unit().to_string()).collect()),
        ),
        (
            "realization",
            names(vec![ss.realization.name().to_string()]),
        ),
    ]
}

/// The arrays of `statespace.npz`, in order.
fn arrays(ss: &StateSpace) -> Vec<(&'static str, NpyData)> {
    let lin = &ss.exported;
    let of = |m: &faer::Mat<f64>| NpyData::matrix(m.nrows(), m.ncols(), |i, j| m[(i, j)]);
    let mut out = vec![
        ("A", of(&lin.a)),
        ("B", of(&lin.b)),
        ("C", of(&lin.c)),
        ("D", of(&lin.d)),
        ("x0", NpyData::vector(&lin.state)),
        ("y0", NpyData::vector(&lin.output_values)),
        (
            "dt",
            NpyData::F64 {
                shape: vec![],
                values: vec![lin.dt],
            },
        ),
        ("state_scale", NpyData::vector(&ss.scale)),
    ];
    out.extend(name_arrays(ss));
    out
}

/// `statespace.npz`.
///
/// # Errors
/// The archive would exceed 4 GiB.
pub fn statespace_npz(ss: &StateSpace) -> Result<Vec<u8>, String> {
    npz(&arrays(ss))
}

/// `statespace.npz` of a series: `t`, then `A` (`times x n x n`), `B`, `C`, `D`, `x0`,
/// `y0` with a leading time axis, the names as for one model.
///
/// # Errors
/// The archive would exceed 4 GiB.
pub fn series_npz(series: &StateSpaceSeries) -> Result<Vec<u8>, String> {
    let Some(first) = series.models.first() else {
        return Err("no model".into());
    };
    let stack = |pick: &dyn Fn(&Linearization) -> &faer::Mat<f64>| {
        let m = pick(&first.exported);
        let (r, c) = (m.nrows(), m.ncols());
        let mut values = Vec::with_capacity(series.models.len() * r * c);
        for ss in &series.models {
            let m = pick(&ss.exported);
            for i in 0..r {
                for j in 0..c {
                    values.push(m[(i, j)]);
                }
            }
        }
        NpyData::F64 {
            shape: vec![series.models.len(), r, c],
            values,
        }
    };
    let rows = |pick: &dyn Fn(&Linearization) -> &[f64]| {
        let width = pick(&first.exported).len();
        NpyData::F64 {
            shape: vec![series.models.len(), width],
            values: series
                .models
                .iter()
                .flat_map(|ss| pick(&ss.exported).to_vec())
                .collect(),
        }
    };
    let mut out = vec![
        ("t", NpyData::vector(&series.times)),
        ("A", stack(&|l| &l.a)),
        ("B", stack(&|l| &l.b)),
        ("C", stack(&|l| &l.c)),
        ("D", stack(&|l| &l.d)),
        ("x0", rows(&|l| &l.state)),
        ("y0", rows(&|l| &l.output_values)),
        (
            "dt",
            NpyData::F64 {
                shape: vec![],
                values: vec![first.exported.dt],
            },
        ),
        ("state_scale", NpyData::vector(&first.scale)),
    ];
    out.extend(name_arrays(first));
    npz(&out)
}

/// The realisation's description for `statespace.json`.
fn realization_json(ss: &StateSpace) -> Value {
    json!({
        "kind": ss.realization.name(),
        "state_scale": ss.scale,
        "rule": "physical state deviation = state_scale * x (the scales are powers of two that balance A; all 1 in the physical realisation)",
        "condition_number_A": flexprr_linear::realization::condition_number(&ss.exported.a),
        "condition_number_physical_A": flexprr_linear::realization::condition_number(&ss.lin.a),
    })
}

/// The form of the model in words.
fn form(dt: f64) -> String {
    if dt > 0.0 {
        format!(
            "x[k+1] = A x[k] + B u[k], y[k] = C x[k] + D u[k] at t_k = t0 + k dt, dt = {dt} s (the control law's period; inputs held over a period); x = (state - x0) / state_scale, y = outputs - y0"
        )
    } else {
        "x' = A x + B u, y = C x + D u; x = (state - x0) / state_scale, y = outputs - y0".into()
    }
}

/// `statespace.json`: the same arrays (matrices as lists of rows), the units, the
/// operating point, the notes and the modes.
pub fn statespace_json(scene: &Scene, ss: &StateSpace) -> Value {
    let rows = |m: &faer::Mat<f64>| -> Vec<Vec<f64>> {
        (0..m.nrows())
            .map(|i| (0..m.ncols()).map(|j| m[(i, j)]).collect())
            .collect()
    };
    let lin = &ss.exported;
    json!({
        "flexprr_version": env!("CARGO_PKG_VERSION"),
        "scene": scene.name,
        "model": ss.model,
        "operating_point": operating_point_json(&ss.at, lin),
        "form": form(lin.dt),
        "dt_s": lin.dt,
        "inputs": lin.inputs.iter().map(|i| json!({"name": i.to_string(), "signal": i.signal_name(), "unit": i.unit()})).collect::<Vec<_>>(),
        "outputs": lin.outputs.iter().map(|o| json!({"name": o.to_string(), "signal": o.signal_name(), "unit": o.unit()})).collect::<Vec<_>>(),
        "states": ss.states,
        "state_signals": lin.states.iter().map(|s| s.signal.clone()).collect::<Vec<_>>(),
        "coordinates": lin.coordinates,
        "chords": crate::machine_modes::chords_description(lin),
        "notes": lin.notes,
        "realization": realization_json(ss),
        "A": rows(&lin.a),
        "B": rows(&lin.b),
        "C": rows(&lin.c),
        "D": rows(&lin.d),
        "x0": lin.state,
        "y0": lin.output_values,
        "modes": modes_json(&ss.modes),
    })
}

/// `statespace.json` of a series: as for one model with `t` and the matrices per time.
pub fn series_json(scene: &Scene, series: &StateSpaceSeries) -> Value {
    let Some(first) = series.models.first() else {
        return json!({});
    };
    let mut value = statespace_json(scene, first);
    let rows = |m: &faer::Mat<f64>| -> Vec<Vec<f64>> {
        (0..m.nrows())
            .map(|i| (0..m.ncols()).map(|j| m[(i, j)]).collect())
            .collect()
    };
    let per_time = |pick: &dyn Fn(&Linearization) -> Value| -> Vec<Value> {
        series.models.iter().map(|ss| pick(&ss.exported)).collect()
    };
    value["operating_point"] = json!({"kind": "times", "t_s": series.times});
    value["t_s"] = json!(series.times);
    value["A"] = json!(per_time(&|l| json!(rows(&l.a))));
    value["B"] = json!(per_time(&|l| json!(rows(&l.b))));
    value["C"] = json!(per_time(&|l| json!(rows(&l.c))));
    value["D"] = json!(per_time(&|l| json!(rows(&l.d))));
    value["x0"] = json!(per_time(&|l| json!(l.state)));
    value["y0"] = json!(per_time(&|l| json!(l.output_values)));
    value["notes"] = json!(
        series
            .models
            .iter()
            .zip(&series.times)
            .flat_map(|(ss, t)| ss.lin.notes.iter().map(move |n| format!("t = {t} s: {n}")))
            .collect::<Vec<_>>()
    );
    value["modes"] = json!(
        series
            .models
            .iter()
            .map(|ss| modes_json(&ss.modes))
            .collect::<Vec<_>>()
    );
    value["timing_s"] = json!({
        "integration": series.integration_s,
        "linearisations": series.linearisation_s,
    });
    value
}

/// Writes `statespace.npz` and `statespace.json` into `dir` (staged, then published).
/// Returns the names written.
///
/// # Errors
/// [`ScenarioError::Io`] when a file cannot be written, [`ScenarioError::Input`] when the
/// directory was taken meanwhile, [`ScenarioError::Write`] for an archive over 4 GiB.
pub fn write_statespace(
    scene: &Scene,
    ss: &StateSpace,
    dir: &flexprr_outdir::OutputDir,
) -> Result<Vec<String>, ScenarioError> {
    let archive = statespace_npz(ss).map_err(npz_error)?;
    write_pair(dir, &archive, &statespace_json(scene, ss))
}

/// Writes the files of a series (see [`write_statespace`]).
///
/// # Errors
/// As [`write_statespace`].
pub fn write_series(
    scene: &Scene,
    series: &StateSpaceSeries,
    dir: &flexprr_outdir::OutputDir,
) -> Result<Vec<String>, ScenarioError> {
    let archive = series_npz(series).map_err(npz_error)?;
    write_pair(dir, &archive, &series_json(scene, series))
}

/// The error of an archive that cannot be made.
fn npz_error(message: String) -> ScenarioError {
    ScenarioError::Write {
        path: "statespace.npz".to_string(),
        message,
    }
}

fn write_pair(
    dir: &flexprr_outdir::OutputDir,
    archive: &[u8],
    json: &Value,
) -> Result<Vec<String>, ScenarioError> {
    let staging = dir.stage()?;
    let put = |name: &str, bytes: &[u8]| {
        std::fs::write(staging.path().join(name), bytes)
            .map_err(|e| flexprr_outdir::OutputError::io(&staging.path().join(name), e))
    };
    put("statespace.npz", archive)?;
    let text = serde_json::to_string_pretty(json).unwrap_or_else(|_| json.to_string()) + "\n";
    put("statespace.json", text.as_bytes())?;
    Ok(staging.publish()?)
}
