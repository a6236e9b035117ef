//! `flexprr.run`, `flexprr.run_many` and the result objects: the run layer's tables
//! (`flexprr_run::Table`) as NumPy arrays under the CLI's CSV column names.

use std::sync::Arc;

use flexprr_run::{
    RunFailure, RunResult, Table, run as run_scene, summary_json, table_one_markdown,
};
use numpy::{PyArray1, PyArray2, ndarray::Array2};
use pyo3::exceptions::{PyKeyError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use rayon::prelude::*;

use crate::convert::json_to_py;
use crate::errors::{RunError, scene_error};
use crate::scene::PyScene;

/// One time-series table of a run (a CSV file of the CLI), columns by their CSV headers.
#[pyclass(module = "flexprr._flexprr", name = "Table", frozen)]
pub struct PyTable {
    table: Table,
}

#[pymethods]
impl PyTable {
    /// The table's name (the CSV file stem: `kinematics`, `deflections`, ...).
    #[getter]
    fn name(&self) -> String {
        self.table.name.clone()
    }

    /// The column names, time (`t_s`) first, as in the CLI's CSV header.
    #[getter]
    fn columns(&self) -> Vec<String> {
        self.table.headers()
    }

    /// Number of rows.
    fn __len__(&self) -> usize {
        self.table.rows()
    }

    fn __contains__(&self, column: &str) -> bool {
        self.table.column(column).is_some()
    }

    /// One column as a 1-D float64 array.
    fn __getitem__<'py>(
        &self,
        py: Python<'py>,
        column: &str,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        match self.table.column(column) {
            Some(values) => Ok(PyArray1::from_slice(py, values)),
            None => Err(PyKeyError::new_err(format!(
                "table {}: no column {column:?} (columns: {})",
                self.table.name,
                self.table.headers().join(", ")
            ))),
        }
    }

    /// All columns as a 2-D float64 array of shape (rows, columns).
    fn to_numpy<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let rows = self.table.rows();
        let cols = self.table.columns.len();
        let array = Array2::from_shape_fn((rows, cols), |(r, c)| self.table.data[c][r]);
        Ok(PyArray2::from_owned_array(py, array))
    }

    /// The columns as a dict of 1-D arrays, in column order.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for (header, values) in self.table.headers().iter().zip(&self.table.data) {
            dict.set_item(header, PyArray1::from_slice(py, values))?;
        }
        Ok(dict)
    }

    /// The table as a `pandas.DataFrame` (requires pandas).
    fn to_pandas<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let pandas = py.import("pandas").map_err(|e| {
            pyo3::exceptions::PyImportError::new_err(format!(
                "Table.to_pandas needs pandas (pip install pandas): {e}"
            ))
        })?;
        pandas.call_method1("DataFrame", (self.to_dict(py)?,))
    }

    fn __repr__(&self) -> String {
        format!(
            "Table(name={:?}, rows={}, columns={:?})",
            self.table.name,
            self.table.rows(),
            self.table.headers()
        )
    }
}

/// What a run produced: its tables, the summary (the CLI's `summary.json`) and statistics.
#[pyclass(module = "flexprr._flexprr", name = "RunResult", frozen)]
pub struct PyRunResult {
    result: Arc<RunResult>,
    summary: serde_json::Value,
    scene_name: String,
}

impl PyRunResult {
    fn new(
        scene: &flexprr_scene::Scene,
        result: RunResult,
        failure: Option<&flexprr_run::RunError>,
    ) -> Self {
        let summary = summary_json(scene, &result, failure);
        Self {
            result: Arc::new(result),
            summary,
            scene_name: scene.name.clone(),
        }
    }
}

#[pymethods]
impl PyRunResult {
    /// The scene's name.
    #[getter]
    fn scene(&self) -> String {
        self.scene_name.clone()
    }

    /// The names of the tables, in the order the CLI writes them.
    #[getter]
    fn tables(&self) -> Vec<String> {
        self.result.tables.iter().map(|t| t.name.clone()).collect()
    }

    /// The table called `name`; `KeyError` if the scene did not request it.
    fn table(&self, name: &str) -> PyResult<PyTable> {
        match self.result.table(name) {
            Some(t) => Ok(PyTable { table: t.clone() }),
            None => Err(PyKeyError::new_err(format!(
                "no table {name:?} in this run (tables: {}); add its request to output.requests",
                self.tables().join(", ")
            ))),
        }
    }

    fn __getitem__(&self, name: &str) -> PyResult<PyTable> {
        self.table(name)
    }

    /// The summary as a dict: the contents of the CLI's `summary.json`.
    #[getter]
    fn summary<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, &self.summary)
    }

    /// Run statistics: integrated, rhs_evaluations, inverse_dynamics_solves, steps,
    /// rejected_steps, max_deflection_m, wall_time_s.
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = &self.result.stats;
        let d = PyDict::new(py);
        d.set_item("integrated", s.integrated)?;
        d.set_item("rhs_evaluations", s.rhs_evaluations)?;
        d.set_item("inverse_dynamics_solves", s.inverse_dynamics_solves)?;
        d.set_item("steps", s.integrator.as_ref().map(|i| i.accepted_steps))?;
        d.set_item(
            "rejected_steps",
            s.integrator.as_ref().map(|i| i.rejected_steps),
        )?;
        d.set_item("max_deflection_m", s.max_deflection_m)?;
        d.set_item("wall_time_s", s.wall_time_s)?;
        Ok(d)
    }

    /// Table I as Markdown (link 1 frequencies over the motion), when frequencies were
    /// requested.
    #[getter]
    fn table_one(&self) -> Option<String> {
        table_one_markdown(&self.result)
    }

    fn __repr__(&self) -> String {
        format!(
            "RunResult(scene={:?}, tables={:?})",
            self.scene_name,
            self.tables()
        )
    }
}

/// The outcome of one run without the GIL: a result, a failure with partial data, or an
/// invalid scene.
enum Outcome {
    Done(PyRunResult),
    Failed(PyRunResult, RunFailure),
    Invalid(flexprr_scene::ScenarioError),
}

fn run_one(scene: &PyScene) -> Outcome {
    let built = match scene.build() {
        Ok(s) => s,
        Err(e) => return Outcome::Invalid(e),
    };
    match run_scene(&built, &mut |_| {}) {
        Ok(result) => Outcome::Done(PyRunResult::new(&built, result, None)),
        Err(mut failure) => {
            let partial = std::mem::take(&mut *failure.partial);
            let result = PyRunResult::new(&built, partial, Some(&failure.error));
            Outcome::Failed(result, failure)
        }
    }
}

/// `RunError` with `kind`, `time`, `link` (1-based) and `partial` set.
fn run_error(
    py: Python<'_>,
    scene: &str,
    partial: PyRunResult,
    failure: &RunFailure,
) -> PyResult<PyErr> {
    let e = &failure.error;
    let rows = partial.result.tables.first().map_or(0, Table::rows);
    let err = RunError::new_err(format!(
        "{scene}: {e} (partial outputs up to the failure, {rows} samples, on .partial)"
    ));
    let value = err.value(py);
    value.setattr("kind", e.kind())?;
    value.setattr("time", e.time())?;
    value.setattr("link", e.link().map(|l| l + 1))?;
    value.setattr("partial", Py::new(py, partial)?)?;
    Ok(err)
}

fn outcome_to_py(
    py: Python<'_>,
    scene: &str,
    outcome: Outcome,
) -> PyResult<Result<Py<PyRunResult>, PyErr>> {
    Ok(match outcome {
        Outcome::Done(r) => Ok(Py::new(py, r)?),
        Outcome::Failed(partial, failure) => Err(run_error(py, scene, partial, &failure)?),
        Outcome::Invalid(e) => Err(scene_error(e)),
    })
}

/// Validates and runs a scene with the GIL released; returns a `RunResult`, raises
/// `SceneError` for an invalid scene and `RunError` (with `.partial`) for a failed run.
#[pyfunction]
pub fn run(py: Python<'_>, scene: &PyScene) -> PyResult<Py<PyRunResult>> {
    let owned = scene.clone();
    let outcome = py.detach(move || run_one(&owned));
    outcome_to_py(py, &scene.name_or_default(), outcome)?
}

/// Runs several scenes in parallel (Rayon, GIL released) and returns one entry per scene,
/// in order: a `RunResult`, or with `return_exceptions=True` the `SceneError`/`RunError`
/// of that scene (otherwise the first error is raised after all runs ended).
#[pyfunction]
#[pyo3(signature = (scenes, threads = None, return_exceptions = false))]
pub fn run_many<'py>(
    py: Python<'py>,
    scenes: Vec<PyRef<'py, PyScene>>,
    threads: Option<usize>,
    return_exceptions: bool,
) -> PyResult<Bound<'py, PyList>> {
    let owned: Vec<PyScene> = scenes.iter().map(|s| (**s).clone()).collect();
    let names: Vec<String> = owned.iter().map(PyScene::name_or_default).collect();
    if threads == Some(0) {
        return Err(PyValueError::new_err("threads must be at least 1"));
    }
    let outcomes: Result<Vec<Outcome>, String> = py.detach(move || {
        let work = || owned.par_iter().map(run_one).collect::<Vec<_>>();
        match threads {
            Some(n) => rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map(|pool| pool.install(work))
                .map_err(|e| format!("cannot start {n} threads: {e}")),
            None => Ok(work()),
        }
    });
    let outcomes = outcomes.map_err(pyo3::exceptions::PyRuntimeError::new_err)?;
    let list = PyList::empty(py);
    let mut first_error = None;
    for (name, outcome) in names.iter().zip(outcomes) {
        match outcome_to_py(py, name, outcome)? {
            Ok(r) => list.append(r)?,
            Err(e) => {
                list.append(e.value(py))?;
                if first_error.is_none() {
                    first_error = Some(e);
                }
            }
        }
    }
    match first_error {
        Some(e) if !return_exceptions => Err(e),
        _ => Ok(list),
    }
}
