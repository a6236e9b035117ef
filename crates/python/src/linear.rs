//! `flexprr.linearize`: a scene's linear model `x' = A x + B u`, `y = C x + D u` (or the
//! discrete-time model of a sampled loop) as NumPy arrays (docs/linear.md, docs/python.md),
//! the same model `flexprr statespace` writes; along a motion at several times from one
//! integration. The Python package wraps the returned dicts in `flexprr.LinearModel`
//! (`to_control()`, `to_scipy()`, `frequency_response`), and `_frequency_response`
//! evaluates a model's response by the CLI's Hessenberg method.

use flexprr_kinematics::Pose;
use flexprr_linear::realization::Realization;
use flexprr_linear::{Coulomb, Input, Linearization, Output, Settings};
use flexprr_linear_tools::linear::OperatingPoint;
use flexprr_linear_tools::statespace::{
    StateSpace, StateSpaceRequest, state_space, state_space_series,
};
use numpy::ndarray::{Array2, Array3};
use numpy::{Complex64, PyArray1, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::errors::{RunError, key_error, scene_error};
use crate::progress::detached;
use crate::scene::PyScene;

/// Channel names as inputs or outputs, a bad one a `SceneError` at `key`.
fn channels<T>(names: &[String], key: &str) -> PyResult<Vec<T>>
where
    T: std::str::FromStr<Err = flexprr_linear::ChannelError>,
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
    One(Box<StateSpace>, String),
    Many(Vec<StateSpace>, String),
    Invalid(flexprr_scene::ScenarioError),
    Failed(flexprr_run::RunError),
}

/// Where the model is taken: at rest at a pose, at one time, at several times.
enum Where {
    Default,
    One(OperatingPoint),
    Times(Vec<f64>),
}

/// The linear model of `scene` (a `Scene` or a path) at rest at `pose = (x_m, y_m,
/// phi_deg)`, or along its motion at `t` (s; a list of times gives one model per time from
/// one integration); neither: at rest where its motion starts. `inputs` and `outputs` are
/// the CLI's channel names; `coulomb` is `"left-out"` or `"smoothed"`, `realization`
/// `"scaled"` or `"physical"`. Returns a dict (a list of dicts for several times; the
/// package wraps them in `LinearModel`): `A`, `B`, `C`, `D`, `x0`, `y0`, `dt`, the names
/// (`inputs`, `outputs`, `states`, their identifiers `input_signals`, `output_signals`,
/// `state_signals`), units, `state_scale`, `realization`, `notes`, `operating_point`, `t`,
/// `model`, `scene`, `elastic_chords`, and the modes as `frequency_hz`, `damping_ratio`,
/// `eigenvalue_re`, `eigenvalue_im` arrays. `rigid_chords` keeps the coupled model's chords
/// rigid at rest (docs/linear.md).
#[pyfunction]
#[pyo3(name = "_linearize", signature = (scene, pose = None, t = None, inputs = Vec::new(), outputs = Vec::new(), rigid_chords = false, coulomb = "left-out".to_string(), realization = "scaled".to_string()))]
#[allow(clippy::too_many_arguments)]
pub fn linearize<'py>(
    py: Python<'py>,
    scene: &Bound<'py, PyAny>,
    pose: Option<(f64, f64, f64)>,
    t: Option<Bound<'py, PyAny>>,
    inputs: Vec<String>,
    outputs: Vec<String>,
    rigid_chords: bool,
    coulomb: String,
    realization: String,
) -> PyResult<Bound<'py, PyAny>> {
    let owned = PyScene::from_any(scene)?;
    crate::law::refuse_python_law(&owned)?;
    let settings = Settings {
        coulomb: match coulomb.as_str() {
            "left-out" => Coulomb::LeftOut,
            "smoothed" => Coulomb::Smoothed,
            other => {
                return Err(key_error(
                    "coulomb",
                    format!("{other:?}: expected \"left-out\" (the default) or \"smoothed\""),
                ));
            }
        },
        ..Settings::default()
    };
    let realization: Realization = realization
        .parse()
        .map_err(|m: String| key_error("realization", m))?;
    let request = StateSpaceRequest {
        inputs: channels::<Input>(&inputs, "inputs")?,
        outputs: channels::<Output>(&outputs, "outputs")?,
        settings,
        realization,
    };
    let times: Option<Vec<f64>> = match &t {
        None => None,
        Some(value) => Some(match value.extract::<f64>() {
            Ok(one) => vec![one],
            Err(_) => value.extract::<Vec<f64>>().map_err(|_| {
                key_error("t", "expected a time in seconds or a list of times".into())
            })?,
        }),
    };
    let several = t.as_ref().is_some_and(|v| v.extract::<f64>().is_err());
    let at = match (pose, times) {
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
            flexprr_linear_tools::linear::check_orientation_deg(phi)
                .map_err(|m| key_error("pose", format!("({x}, {y}, {phi}): {m}")))?;
            Where::One(OperatingPoint::Rest(Pose::new(x, y, phi.to_radians())))
        }
        (None, Some(times)) if several => Where::Times(times),
        (None, Some(times)) => Where::One(OperatingPoint::Time(times[0])),
        (None, None) => Where::Default,
    };
    let outcome = detached(py, None, 1.0, move |_| {
        let mut scene = match owned.build() {
            Ok(s) => s,
            Err(e) => return Outcome::Invalid(e),
        };
        scene.rigid_chords |= rigid_chords;
        let failed = |e: flexprr_run::RunError| match e {
            flexprr_run::RunError::Scene(e @ flexprr_scene::ScenarioError::Input { .. }) => {
                Outcome::Invalid(e)
            }
            e => Outcome::Failed(e),
        };
        let name = scene.name.clone();
        let at = match at {
            Where::Times(times) => {
                return match state_space_series(&scene, &times, &request, &mut |_| {}) {
                    Ok(series) => Outcome::Many(series.models, name),
                    Err(e) => failed(e),
                };
            }
            Where::One(at) => at,
            Where::Default => {
                OperatingPoint::Rest(scene.trajectory.motion(scene.output_times[0]).pose)
            }
        };
        match state_space(&scene, at, &request) {
            Ok(ss) => Outcome::One(Box::new(ss), name),
            Err(e) => failed(e),
        }
    })?;
    match outcome {
        Outcome::One(ss, name) => Ok(to_dict(py, &ss, &name)?.into_any()),
        Outcome::Many(models, name) => {
            let list = PyList::empty(py);
            for ss in &models {
                list.append(to_dict(py, ss, &name)?)?;
            }
            Ok(list.into_any())
        }
        Outcome::Invalid(e) => Err(scene_error(e)),
        Outcome::Failed(e) => {
            let err = RunError::new_err(e.to_string());
            let value = err.value(py);
            value.setattr("kind", e.kind())?;
            value.setattr("time", e.time())?;
            value.setattr("link", e.link().map(|l| l + 1))?;
            value.setattr("partial", py.None())?;
            Err(err)
        }
    }
}

/// The dict handed to `LinearModel`.
fn to_dict<'py>(py: Python<'py>, ss: &StateSpace, scene: &str) -> PyResult<Bound<'py, PyDict>> {
    let lin = &ss.exported;
    let d = PyDict::new(py);
    d.set_item("A", matrix(py, &lin.a))?;
    d.set_item("B", matrix(py, &lin.b))?;
    d.set_item("C", matrix(py, &lin.c))?;
    d.set_item("D", matrix(py, &lin.d))?;
    d.set_item("x0", PyArray1::from_slice(py, &lin.state))?;
    d.set_item("y0", PyArray1::from_slice(py, &lin.output_values))?;
    d.set_item("dt", lin.dt)?;
    d.set_item("state_scale", PyArray1::from_slice(py, &ss.scale))?;
    d.set_item("realization", ss.realization.name())?;
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
    d.set_item(
        "input_signals",
        names(lin.inputs.iter().map(Input::signal_name).collect())?,
    )?;
    d.set_item(
        "output_signals",
        names(lin.outputs.iter().map(Output::signal_name).collect())?,
    )?;
    d.set_item(
        "state_signals",
        names(lin.states.iter().map(|s| s.signal.clone()).collect())?,
    )?;
    d.set_item("notes", names(lin.notes.clone())?)?;
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

/// `H` of the model `(A, B, C, D)` (continuous for `dt = 0`, else discrete at `dt`) at the
/// angular frequencies `omega` (rad/s) as a complex array `(outputs, inputs, frequencies)`,
/// python-control's layout, by Laub's Hessenberg method (the CLI's `flexprr frf`).
/// Raises `ValueError` for mismatched shapes, a frequency above the Nyquist frequency of a
/// discrete model, or one at an undamped pole.
#[pyfunction]
#[pyo3(name = "_frequency_response")]
pub fn frequency_response<'py>(
    py: Python<'py>,
    a: PyReadonlyArray2<'py, f64>,
    b: PyReadonlyArray2<'py, f64>,
    c: PyReadonlyArray2<'py, f64>,
    d: PyReadonlyArray2<'py, f64>,
    dt: f64,
    omega: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray3<Complex64>>> {
    let to_mat = |m: &PyReadonlyArray2<'py, f64>| {
        let v = m.as_array();
        faer::Mat::from_fn(v.nrows(), v.ncols(), |i, j| v[(i, j)])
    };
    let (a, b, c, d) = (to_mat(&a), to_mat(&b), to_mat(&c), to_mat(&d));
    let (n, m, p) = (a.nrows(), b.ncols(), c.nrows());
    if a.ncols() != n || b.nrows() != n || c.ncols() != n || d.nrows() != p || d.ncols() != m {
        return Err(PyValueError::new_err(format!(
            "inconsistent shapes: A {n}x{}, B {}x{m}, C {p}x{}, D {}x{}",
            a.ncols(),
            b.nrows(),
            c.ncols(),
            d.nrows(),
            d.ncols()
        )));
    }
    if !(dt.is_finite() && dt >= 0.0) {
        return Err(PyValueError::new_err(format!(
            "dt = {dt}: expected 0 (continuous) or a period > 0 (s)"
        )));
    }
    let frequencies: Vec<f64> = omega
        .as_array()
        .iter()
        .map(|w| w / std::f64::consts::TAU)
        .collect();
    let lin = Linearization::from_matrices(a, b, c, d, dt);
    let response = py
        .detach(|| flexprr_linear::frequency_response_direct(&lin, &frequencies))
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let out = Array3::from_shape_fn((p, m, frequencies.len()), |(o, i, k)| {
        let h = response[k][o][i];
        Complex64::new(h.re, h.im)
    });
    Ok(PyArray3::from_owned_array(py, out))
}

/// The margins of the three slider loops of `scene` (a `Scene` or a path) at rest at `pose
/// = (x_m, y_m, phi_deg)` (default: the start pose of its motion): what `flexprr margins
/// --json` prints, `{"loops": [...]}` with per slider `slider`, `dt_s`, `gain_margin`,
/// `gain_margin_db`, `phase_margin_deg`, `gain_crossover_hz`, `phase_crossover_hz`,
/// `sensitivity_peak`, `sensitivity_peak_hz` (`None` where there is no crossing). Raises
/// `SceneError` for a scene without `[control]` or a bad pose, `RunError` for a failed
/// linearisation.
#[pyfunction]
#[pyo3(signature = (scene, pose = None))]
pub fn margins<'py>(
    py: Python<'py>,
    scene: &Bound<'py, PyAny>,
    pose: Option<(f64, f64, f64)>,
) -> PyResult<Bound<'py, PyDict>> {
    let owned = PyScene::from_any(scene)?;
    crate::law::refuse_python_law(&owned)?;
    let pose = match pose {
        None => None,
        Some((x, y, phi)) => {
            if !(x.is_finite() && y.is_finite() && phi.is_finite()) {
                return Err(key_error(
                    "pose",
                    format!("({x}, {y}, {phi}): expected three finite numbers (m, m, deg)"),
                ));
            }
            flexprr_linear_tools::linear::check_orientation_deg(phi)
                .map_err(|m| key_error("pose", format!("({x}, {y}, {phi}): {m}")))?;
            Some(Pose::new(x, y, phi.to_radians()))
        }
    };
    let outcome = detached(py, None, 1.0, move |_| {
        let scene = owned.build().map_err(flexprr_run::RunError::Scene)?;
        flexprr_linear_tools::margins::slider_loop_margins(&scene, pose)
    })?;
    let loops = match outcome {
        Ok(loops) => loops,
        Err(flexprr_run::RunError::Scene(e @ flexprr_scene::ScenarioError::Input { .. })) => {
            return Err(scene_error(e));
        }
        Err(e) => return Err(RunError::new_err(e.to_string())),
    };
    let finite = |x: f64| x.is_finite().then_some(x);
    let rows = PyList::empty(py);
    for (i, l) in loops.iter().enumerate() {
        let m = &l.margins;
        let row = PyDict::new(py);
        row.set_item("slider", i + 1)?;
        row.set_item("dt_s", l.dt)?;
        row.set_item("gain_margin", finite(m.gain_margin))?;
        row.set_item("gain_margin_db", finite(20.0 * m.gain_margin.log10()))?;
        row.set_item("phase_margin_deg", finite(m.phase_margin_deg))?;
        row.set_item("gain_crossover_hz", finite(m.gain_crossover_hz))?;
        row.set_item("phase_crossover_hz", finite(m.phase_crossover_hz))?;
        row.set_item("sensitivity_peak", m.sensitivity_peak)?;
        row.set_item("sensitivity_peak_hz", m.sensitivity_peak_hz)?;
        rows.append(row)?;
    }
    let out = PyDict::new(py);
    out.set_item("loops", rows)?;
    Ok(out)
}
