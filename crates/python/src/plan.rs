//! `flexprr.plan`: the plan of a scene's `[plan]` section (`flexprr_plan`), as plain data: the
//! duration or frequency, `plan.json`'s contents as a dict, the timing as NumPy arrays, and
//! the planned scene (`to_scene()`), runnable by `flexprr.run`.

use flexprr_plan::{Options, PlanError, plan_report, plan_scene, scene_toml};
use numpy::PyArray1;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::convert::json_to_py;
use crate::errors::{RunError, scene_error};
use crate::scene::PyScene;

/// A plan: what `flexprr plan` writes to `plan.json` and `planned.toml`.
#[pyclass(module = "flexprr._flexprr", name = "Plan", frozen)]
pub struct PyPlan {
    report: serde_json::Value,
    planned: String,
    name: String,
    duration: f64,
    periodic: bool,
    s: Vec<f64>,
    s_dot: Vec<f64>,
    t: Vec<f64>,
}

#[pymethods]
impl PyPlan {
    /// The move's duration, or the period of a periodic plan (s).
    #[getter]
    fn duration(&self) -> f64 {
        self.duration
    }

    /// The largest frequency of a periodic plan (Hz), `None` for a rest-to-rest move.
    #[getter]
    fn frequency_hz(&self) -> Option<f64> {
        self.periodic.then(|| 1.0 / self.duration)
    }

    /// The contents of `plan.json` (binding limits, margins, convergence, the scene's own
    /// timing, the orientation search, shaping, residual vibration) as a dict.
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, &self.report)
    }

    /// The timing before shaping: `{"s": ..., "s_dot": ..., "t": ...}`, NumPy arrays of the
    /// path position, path speed and time at the grid points.
    #[getter]
    fn timing<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        let d = pyo3::types::PyDict::new(py);
        d.set_item("s", PyArray1::from_slice(py, &self.s))?;
        d.set_item("s_dot", PyArray1::from_slice(py, &self.s_dot))?;
        d.set_item("t", PyArray1::from_slice(py, &self.t))?;
        Ok(d)
    }

    /// The planned scene (`planned.toml`): the scene with the planned motion, `[plan]`
    /// removed, runnable by `flexprr.run`.
    fn to_scene(&self) -> PyResult<PyScene> {
        PyScene::from_text(
            "planned.toml",
            &format!("{}_planned", self.name),
            self.planned.clone(),
        )
    }

    /// The planned scene as TOML text.
    fn to_toml(&self) -> String {
        self.planned.clone()
    }

    fn __repr__(&self) -> String {
        match self.periodic {
            true => format!("Plan({}: {:.6} Hz)", self.name, 1.0 / self.duration),
            false => format!("Plan({}: {:.6} s)", self.name, self.duration),
        }
    }
}

/// Plans a scene (a `Scene` or a path) by its `[plan]` section, as `flexprr plan` does.
/// With `flexible_check` (default) the scene's flexible model is run on the planned motion
/// for its residual vibration (in `report["flexible_check"]`). Raises `SceneError` for an
/// invalid scene or `[plan]` or a plan no motion can meet (the limit and where), and
/// `RunError` when a run of the flexible model fails.
#[pyfunction]
#[pyo3(signature = (scene, flexible_check = true))]
pub fn plan(py: Python<'_>, scene: &Bound<'_, PyAny>, flexible_check: bool) -> PyResult<PyPlan> {
    let owned = PyScene::from_any(scene)?;
    let built = owned.build().map_err(scene_error)?;
    let outcome = py
        .detach(|| plan_scene(&built, Options { flexible_check }, &mut |_| {}))
        .map_err(|e| match e {
            PlanError::Run { .. } | PlanError::Modes { .. } => RunError::new_err(e.to_string()),
            PlanError::Output(inner) => scene_error(inner),
            other => crate::errors::SceneError::new_err(other.to_string()),
        })?;
    let planned = scene_toml(&outcome.planned_file, "Planned by flexprr.plan")
        .map_err(PyValueError::new_err)?;
    let timing = &outcome.plan.timing;
    Ok(PyPlan {
        report: plan_report(&outcome),
        planned,
        name: outcome.scene.clone(),
        duration: outcome.plan.duration,
        periodic: outcome.plan.frequency().is_some(),
        s: timing.grid().to_vec(),
        s_dot: timing.speeds().to_vec(),
        t: timing.times().to_vec(),
    })
}
