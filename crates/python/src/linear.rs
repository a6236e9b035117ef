//! `flexprr.linearize`: a scene's linear model `x' = A x + B u`, `y = C x + D u` as NumPy
//! arrays (docs/linear.md, docs/python.md), the same model `flexprr statespace` writes. The
//! Python package wraps the returned dict in `flexprr.LinearModel`, whose arrays
//! `scipy.signal.StateSpace(A, B, C, D)` and `control.ss(A, B, C, D)` take as they are.

use flexprr_kinematics::Pose;
use flexprr_linear::{Input, Output};
use flexprr_run::linear::OperatingPoint;
use flexprr_run::statespace::{StateSpace, state_space};
use numpy::{PyArray1, PyArray2, ndarray::Array2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::errors::{RunError, key_error, scene_error};
use crate::progress::detached;
use crate::scene::PyScene;

/// Channel names as inputs or outputs, a bad one a `SceneError` at `key`.
fn channels<T>(names: &[String], key: &str) -> PyResult<Vec<T>>
where
    T: std::str::FromStr<Err = flexprr_linear::LinearError>,
{
    names
        .iter()
        .map(|n| n.parse::<T>().map_err(|e| key_error(key, e.to_string())))
        .collect()
}

/// A matrix as a 2-D float64 array.
fn matrix<'py>(py: Python<'py>, m: &faer::Mat<f64>) -> Bound<'py, PyArray2<f64>> {
    PyArray2::from_owned_array(
        py,
        Array2::from_shape_fn((m.nrows(), m.ncols()), |(i, j)| m[(i, j)]),
    )
}

/// What the Rust side computed, or why it could not.
enum Outcome {
    Done(Box<StateSpace>, String),
    Invalid(flexprr_scene::ScenarioError),
    Failed(flexprr_run::RunError),
}

/// The linear model of `scene` (a `Scene` or a path) at rest at `pose = (x_m, y_m,
/// phi_deg)` or along its motion at `t` (s); neither: at rest where its motion starts.
/// `inputs` and `outputs` are the CLI's channel names. Returns a dict (the package wraps it
/// in `LinearModel`): `A`, `B`, `C`, `D`, `x0`, `y0`, `inputs`, `outputs`, `states`,
/// `input_units`, `output_units`, `operating_point`, `t`, `model`, `scene`, `elastic_chords`,
/// and the modes as `frequency_hz`, `damping_ratio`, `eigenvalue_re`, `eigenvalue_im`
/// arrays. `rigid_chords` keeps the coupled model's chords rigid at rest (docs/linear.md).
#[pyfunction]
#[pyo3(name = "_linearize", signature = (scene, pose = None, t = None, inputs = Vec::new(), outputs = Vec::new(), rigid_chords = false))]
pub fn linearize<'py>(
    py: Python<'py>,
    scene: &Bound<'py, PyAny>,
    pose: Option<(f64, f64, f64)>,
    t: Option<f64>,
    inputs: Vec<String>,
    outputs: Vec<String>,
    rigid_chords: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let owned = PyScene::from_any(scene)?;
    let inputs: Vec<Input> = channels(&inputs, "inputs")?;
    let outputs: Vec<Output> = channels(&outputs, "outputs")?;
    let at = match (pose, t) {
        (Some(_), Some(_)) => {
            return Err(key_error(
                "t",
                "give either pose (at rest) or t (along the motion), not both".into(),
            ));
        }
        (Some((x, y, phi)), None) => {
            if !(x.is_finite() && y.is_finite() && phi.is_finite()) {
                return Err(key_error(
                    "pose",
                    format!("({x}, {y}, {phi}): expected three finite numbers (m, m, deg)"),
                ));
            }
            Some(OperatingPoint::Rest(Pose::new(x, y, phi.to_radians())))
        }
        (None, Some(t)) => Some(OperatingPoint::Time(t)),
        (None, None) => None,
    };
    let outcome = detached(py, None, 1.0, move |_| {
        let mut scene = match owned.build() {
            Ok(s) => s,
            Err(e) => return Outcome::Invalid(e),
        };
        scene.rigid_chords |= rigid_chords;
        let at = at.unwrap_or_else(|| {
            OperatingPoint::Rest(scene.trajectory.motion(scene.output_times[0]).pose)
        });
        match state_space(&scene, at, &inputs, &outputs) {
            Ok(ss) => Outcome::Done(Box::new(ss), scene.name.clone()),
            Err(flexprr_run::RunError::Scene(e @ flexprr_scene::ScenarioError::Input { .. })) => {
                Outcome::Invalid(e)
            }
            Err(e) => Outcome::Failed(e),
        }
    })?;
    let (ss, name) = match outcome {
        Outcome::Done(ss, name) => (ss, name),
        Outcome::Invalid(e) => return Err(scene_error(e)),
        Outcome::Failed(e) => {
            let err = RunError::new_err(e.to_string());
            let value = err.value(py);
            value.setattr("kind", e.kind())?;
            value.setattr("time", e.time())?;
            value.setattr("link", e.link().map(|l| l + 1))?;
            value.setattr("partial", py.None())?;
            return Err(err);
        }
    };
    to_dict(py, &ss, &name)
}

/// The dict handed to `LinearModel`.
fn to_dict<'py>(py: Python<'py>, ss: &StateSpace, scene: &str) -> PyResult<Bound<'py, PyDict>> {
    let lin = &ss.lin;
    let d = PyDict::new(py);
    d.set_item("A", matrix(py, &lin.a))?;
    d.set_item("B", matrix(py, &lin.b))?;
    d.set_item("C", matrix(py, &lin.c))?;
    d.set_item("D", matrix(py, &lin.d))?;
    d.set_item("x0", PyArray1::from_slice(py, &lin.state))?;
    d.set_item("y0", PyArray1::from_slice(py, &lin.output_values))?;
    let names = |v: Vec<String>| PyList::new(py, v);
    d.set_item(
        "inputs",
        names(lin.inputs.iter().map(ToString::to_string).collect())?,
    )?;
    d.set_item(
        "outputs",
        names(lin.outputs.iter().map(ToString::to_string).collect())?,
    )?;
    d.set_item("states", names(ss.states.clone())?)?;
    d.set_item("elastic_chords", lin.elastic_chords)?;
    d.set_item(
        "input_units",
        names(lin.inputs.iter().map(|i| i.unit().to_string()).collect())?,
    )?;
    d.set_item(
        "output_units",
        names(lin.outputs.iter().map(|o| o.unit().to_string()).collect())?,
    )?;
    let point = PyDict::new(py);
    match ss.at {
        OperatingPoint::Rest(p) => {
            point.set_item("kind", "rest")?;
            point.set_item("pose", (p.x, p.y, p.phi.to_degrees()))?;
        }
        OperatingPoint::Time(t) => {
            point.set_item("kind", "time")?;
            point.set_item("t", t)?;
        }
    }
    d.set_item("operating_point", point)?;
    d.set_item("t", lin.t)?;
    d.set_item("model", ss.model.clone())?;
    d.set_item("scene", scene)?;
    let column =
        |f: &dyn Fn(&flexprr_linear::Mode) -> f64| -> Vec<f64> { ss.modes.iter().map(f).collect() };
    d.set_item(
        "frequency_hz",
        PyArray1::from_vec(py, column(&|m| m.frequency_hz)),
    )?;
    d.set_item(
        "damping_ratio",
        PyArray1::from_vec(py, column(&|m| m.damping_ratio)),
    )?;
    d.set_item(
        "eigenvalue_re",
        PyArray1::from_vec(py, column(&|m| m.eigenvalue.re)),
    )?;
    d.set_item(
        "eigenvalue_im",
        PyArray1::from_vec(py, column(&|m| m.eigenvalue.im)),
    )?;
    Ok(d)
}
