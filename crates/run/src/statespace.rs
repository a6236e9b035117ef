//! State-space export of a scene's linear model (`flexprr statespace`, docs/linear.md):
//! `statespace.npz` (NumPy: `A`, `B`, `C`, `D` as `float64` matrices, the operating point
//! `x0`, `y0`, and the names of the inputs, outputs and states as unicode arrays) and
//! `statespace.json` (the same, with units, the operating point and the modes).
//!
//! The model is `x' = A x + B u`, `y = C x + D u` in deviations from the operating point:
//! `x` the model's state (coordinates, their rates, then the control law's states) less
//! `x0`, `y` the outputs less `y0`, `u` the input forces (N).

use flexprr_linear::{Input, Linearization, Mode, Output, linearize, modes};
use flexprr_scene::{ScenarioError, Scene};
use serde_json::{Value, json};

use crate::error::RunError;
use crate::frf::{modes_json, operating_point_json};
use crate::linear::{OperatingPoint, operating_point};
use crate::npz::{NpyData, npz};

/// A scene's linear model with what its files say about it.
#[derive(Debug, Clone)]
pub struct StateSpace {
    /// Where it was taken.
    pub at: OperatingPoint,
    /// The model kind.
    pub model: String,
    /// The linear model.
    pub lin: Linearization,
    /// A name for each state component (the model's own: link, mode, rate).
    pub states: Vec<String>,
    /// The modes of `A`.
    pub modes: Vec<Mode>,
}

/// The state-space model of `scene` at `at` for `inputs` and `outputs`.
///
/// # Errors
/// As [`crate::linear::linear_model`], or the eigenvalues of `A` failed.
pub fn state_space(
    scene: &Scene,
    at: OperatingPoint,
    inputs: &[Input],
    outputs: &[Output],
) -> Result<StateSpace, RunError> {
    let mut point = operating_point(scene, at)?;
    let model = point.model.as_mut();
    let failed = |e: flexprr_linear::LinearError| match e {
        flexprr_linear::LinearError::Model(e) => RunError::Model(e),
        other => RunError::Scene(ScenarioError::Run(other.to_string())),
    };
    let lin = linearize(model, point.t, &point.state, inputs, outputs).map_err(failed)?;
    let states = (0..lin.a.nrows())
        .map(|k| match lin.model_component(k) {
            Some(own) => state_name(model, lin.coordinates, own, k),
            None => lin.added_component_name(k).unwrap_or_default(),
        })
        .collect();
    let modes = modes(&lin).map_err(failed)?;
    Ok(StateSpace {
        at,
        model: scene.coupling.name().to_string(),
        lin,
        states,
        modes,
    })
}

/// The model's name of its state component `own` (linear state component `k`), or the
/// place of `k` in the linear state (coordinate, rate or controller state) when the model
/// has no name for it.
fn state_name(
    model: &dyn flexprr_dynamics::SceneModel,
    coordinates: usize,
    own: usize,
    k: usize,
) -> String {
    let name = model.component_name(own);
    if name != format!("state component {own}") {
        return name;
    }
    if k < coordinates {
        format!("coordinate {}", k + 1)
    } else if k < 2 * coordinates {
        format!("rate of coordinate {}", k - coordinates + 1)
    } else {
        format!("controller state {}", k - 2 * coordinates + 1)
    }
}

/// The arrays of `statespace.npz`, in order.
fn arrays(ss: &StateSpace) -> Vec<(&'static str, NpyData)> {
    let lin = &ss.lin;
    let of = |m: &faer::Mat<f64>| NpyData::matrix(m.nrows(), m.ncols(), |i, j| m[(i, j)]);
    let names = |v: Vec<String>| NpyData::Unicode(v);
    vec![
        ("A", of(&lin.a)),
        ("B", of(&lin.b)),
        ("C", of(&lin.c)),
        ("D", of(&lin.d)),
        ("x0", NpyData::vector(&lin.state)),
        ("y0", NpyData::vector(&lin.output_values)),
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
            "input_units",
            names(lin.inputs.iter().map(|i| i.unit().to_string()).collect()),
        ),
        (
            "output_units",
            names(lin.outputs.iter().map(|o| o.unit().to_string()).collect()),
        ),
    ]
}

/// `statespace.npz`.
///
/// # Errors
/// The archive would exceed 4 GiB.
pub fn statespace_npz(ss: &StateSpace) -> Result<Vec<u8>, String> {
    npz(&arrays(ss))
}

/// `statespace.json`: the same arrays (matrices as lists of rows), the units, the
/// operating point and the modes.
pub fn statespace_json(scene: &Scene, ss: &StateSpace) -> Value {
    let rows = |m: &faer::Mat<f64>| -> Vec<Vec<f64>> {
        (0..m.nrows())
            .map(|i| (0..m.ncols()).map(|j| m[(i, j)]).collect())
            .collect()
    };
    let lin = &ss.lin;
    json!({
        "flexprr_version": env!("CARGO_PKG_VERSION"),
        "scene": scene.name,
        "model": ss.model,
        "operating_point": operating_point_json(&ss.at, lin),
        "form": "x' = A x + B u, y = C x + D u; x = state - x0, y = outputs - y0, u = input forces",
        "inputs": lin.inputs.iter().map(|i| json!({"name": i.to_string(), "unit": i.unit()})).collect::<Vec<_>>(),
        "outputs": lin.outputs.iter().map(|o| json!({"name": o.to_string(), "unit": o.unit()})).collect::<Vec<_>>(),
        "states": ss.states,
        "coordinates": lin.coordinates,
        "chords": crate::machine_modes::chords_description(lin),
        "A": rows(&lin.a),
        "B": rows(&lin.b),
        "C": rows(&lin.c),
        "D": rows(&lin.d),
        "x0": lin.state,
        "y0": lin.output_values,
        "modes": modes_json(&ss.modes),
    })
}

/// Writes `statespace.npz` and `statespace.json` into `dir` (staged, then published).
/// Returns the names written.
///
/// # Errors
/// [`ScenarioError::Io`] when a file cannot be written, [`ScenarioError::Input`] when the
/// directory was taken meanwhile, [`ScenarioError::Run`] for an archive over 4 GiB.
pub fn write_statespace(
    scene: &Scene,
    ss: &StateSpace,
    dir: &crate::OutputDir,
) -> Result<Vec<String>, ScenarioError> {
    let staging = dir.stage()?;
    let put = |name: &str, bytes: &[u8]| {
        std::fs::write(staging.path().join(name), bytes)
            .map_err(|e| crate::OutputError::io(&staging.path().join(name), e))
    };
    let archive =
        statespace_npz(ss).map_err(|m| ScenarioError::Run(format!("statespace.npz: {m}")))?;
    put("statespace.npz", &archive)?;
    let json = statespace_json(scene, ss);
    let text = serde_json::to_string_pretty(&json).unwrap_or_else(|_| json.to_string()) + "\n";
    put("statespace.json", text.as_bytes())?;
    Ok(staging.publish()?)
}
