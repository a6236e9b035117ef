//! `flexprr.run`, `flexprr.run_many` and the result objects: the run layer's tables
//! (`flexprr_run::Table`) as NumPy arrays under the CLI's CSV column names.
//!
//! A `RunResult` holds plain data (tables by CSV header, the `summary.json` contents, the
//! statistics and Table I), so it pickles: results cross process boundaries
//! (`multiprocessing`, `concurrent.futures`, Dask) whole.

use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

use flexprr_run::{RunFailure, RunResult, run as run_scene, summary_json, table_one_markdown};
use numpy::{PyArray1, PyArray2, ndarray::Array2};
use pyo3::exceptions::{PyKeyError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict, PyList, PyTuple, PyType};
use rayon::prelude::*;

use crate::convert::{json_to_py, py_to_json};
use crate::errors::{RunError, scene_error};
use crate::progress::detached;
use crate::scene::PyScene;

/// One table: its name, CSV headers and columns (`data[column][row]`).
struct PlainTable {
    name: String,
    headers: Vec<String>,
    data: Vec<Vec<f64>>,
}

impl PlainTable {
    fn rows(&self) -> usize {
        self.data.first().map_or(0, Vec::len)
    }
    fn column(&self, header: &str) -> Option<&[f64]> {
        self.headers
            .iter()
            .position(|h| h == header)
            .and_then(|i| self.data.get(i))
            .map(Vec::as_slice)
    }
}

/// One time-series table of a run (a CSV file of the CLI), columns by their CSV headers.
#[pyclass(module = "flexprr._flexprr", name = "Table", frozen)]
pub struct PyTable {
    table: Arc<PlainTable>,
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
        self.table.headers.clone()
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
                self.table.headers.join(", ")
            ))),
        }
    }

    /// All columns as a 2-D float64 array of shape (rows, columns).
    fn to_numpy<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let rows = self.table.rows();
        let cols = self.table.data.len();
        let array = Array2::from_shape_fn((rows, cols), |(r, c)| self.table.data[c][r]);
        Ok(PyArray2::from_owned_array(py, array))
    }

    /// The columns as a dict of 1-D arrays, in column order.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for (header, values) in self.table.headers.iter().zip(&self.table.data) {
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
            self.table.headers
        )
    }
}

/// Run statistics (see `RunResult.stats`).
#[derive(Clone, Copy)]
struct PlainStats {
    integrated: bool,
    rhs_evaluations: usize,
    inverse_dynamics_solves: usize,
    steps: Option<usize>,
    rejected_steps: Option<usize>,
    max_deflection_m: Option<f64>,
    wall_time_s: f64,
}

/// What a run produced: its tables, the summary (the CLI's `summary.json`) and statistics.
#[pyclass(module = "flexprr._flexprr", name = "RunResult", frozen)]
pub struct PyRunResult {
    scene_name: String,
    tables: Vec<Arc<PlainTable>>,
    summary: serde_json::Value,
    stats: PlainStats,
    table_one: Option<String>,
}

impl PyRunResult {
    fn new(
        scene: &flexprr_scene::Scene,
        result: &RunResult,
        failure: Option<&flexprr_run::RunError>,
    ) -> Self {
        let s = &result.stats;
        Self {
            scene_name: scene.name.clone(),
            tables: result
                .tables
                .iter()
                .map(|t| {
                    Arc::new(PlainTable {
                        name: t.name.clone(),
                        headers: t.headers(),
                        data: t.data.clone(),
                    })
                })
                .collect(),
            summary: summary_json(scene, result, failure),
            stats: PlainStats {
                integrated: s.integrated,
                rhs_evaluations: s.rhs_evaluations,
                inverse_dynamics_solves: s.inverse_dynamics_solves,
                steps: s.integrator.as_ref().map(|i| i.accepted_steps),
                rejected_steps: s.integrator.as_ref().map(|i| i.rejected_steps),
                max_deflection_m: s.max_deflection_m,
                wall_time_s: s.wall_time_s,
            },
            table_one: table_one_markdown(result),
        }
    }

    fn table_names(&self) -> Vec<String> {
        self.tables.iter().map(|t| t.name.clone()).collect()
    }
}

/// Column data as little-endian bytes (the pickled form) and back.
fn column_bytes(values: &[f64]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn column_from_bytes(bytes: &[u8]) -> PyResult<Vec<f64>> {
    if bytes.len() % 8 != 0 {
        return Err(PyValueError::new_err(
            "RunResult state: a column's bytes are not a whole number of float64",
        ));
    }
    Ok(bytes
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes([c[0], c[1], c[2], c[3], c[4], c[5], c[6], c[7]]))
        .collect())
}

/// The pickled state of a `RunResult`: scene name, tables `(name, headers, column bytes)`,
/// `summary.json` contents (as Python objects: floats pickle exactly), statistics and
/// Table I.
type TableState = (String, Vec<String>, Vec<Vec<u8>>);
type StatsState = (
    bool,
    usize,
    usize,
    Option<usize>,
    Option<usize>,
    Option<f64>,
    f64,
);
type RunResultState<'py> = (
    String,
    Vec<TableState>,
    Bound<'py, PyAny>,
    StatsState,
    Option<String>,
);

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
        self.table_names()
    }

    /// The table called `name`; `KeyError` if the scene did not request it.
    fn table(&self, name: &str) -> PyResult<PyTable> {
        match self.tables.iter().find(|t| t.name == name) {
            Some(t) => Ok(PyTable { table: t.clone() }),
            None => Err(PyKeyError::new_err(format!(
                "no table {name:?} in this run (tables: {}); add its request to output.requests",
                self.table_names().join(", ")
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
        let s = &self.stats;
        let d = PyDict::new(py);
        d.set_item("integrated", s.integrated)?;
        d.set_item("rhs_evaluations", s.rhs_evaluations)?;
        d.set_item("inverse_dynamics_solves", s.inverse_dynamics_solves)?;
        d.set_item("steps", s.steps)?;
        d.set_item("rejected_steps", s.rejected_steps)?;
        d.set_item("max_deflection_m", s.max_deflection_m)?;
        d.set_item("wall_time_s", s.wall_time_s)?;
        Ok(d)
    }

    /// Table I as Markdown (link 1 frequencies over the motion), when frequencies were
    /// requested.
    #[getter]
    fn table_one(&self) -> Option<String> {
        self.table_one.clone()
    }

    fn __repr__(&self) -> String {
        format!(
            "RunResult(scene={:?}, tables={:?})",
            self.scene_name,
            self.table_names()
        )
    }

    /// Pickle support: the result rebuilt from its plain data.
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let this = slf.get();
        let tables: Vec<(String, Vec<String>, Vec<Bound<'py, PyBytes>>)> = this
            .tables
            .iter()
            .map(|t| {
                (
                    t.name.clone(),
                    t.headers.clone(),
                    t.data
                        .iter()
                        .map(|c| PyBytes::new(py, &column_bytes(c)))
                        .collect(),
                )
            })
            .collect();
        let s = this.stats;
        let state = (
            this.scene_name.clone(),
            tables,
            json_to_py(py, &this.summary)?,
            (
                s.integrated,
                s.rhs_evaluations,
                s.inverse_dynamics_solves,
                s.steps,
                s.rejected_steps,
                s.max_deflection_m,
                s.wall_time_s,
            ),
            this.table_one.clone(),
        );
        let restore = slf.get_type().getattr("_restore")?;
        Ok((restore, PyTuple::new(py, [state.into_pyobject(py)?])?))
    }

    /// Rebuilds a pickled result (see `__reduce__`).
    #[classmethod]
    fn _restore<'py>(_cls: &Bound<'py, PyType>, state: RunResultState<'py>) -> PyResult<Self> {
        let (scene_name, tables, summary, stats, table_one) = state;
        let tables = tables
            .into_iter()
            .map(|(name, headers, columns)| {
                let data = columns
                    .iter()
                    .map(|c| column_from_bytes(c))
                    .collect::<PyResult<Vec<_>>>()?;
                let rows = data.first().map_or(0, Vec::len);
                if data.len() != headers.len() || data.iter().any(|c| c.len() != rows) {
                    return Err(PyValueError::new_err(format!(
                        "RunResult state: table {name} has {} headers for {} columns of unequal or wrong length",
                        headers.len(),
                        data.len()
                    )));
                }
                Ok(Arc::new(PlainTable {
                    name,
                    headers,
                    data,
                }))
            })
            .collect::<PyResult<Vec<_>>>()?;
        let summary = py_to_json(&summary, 0)?;
        let (
            integrated,
            rhs_evaluations,
            inverse_dynamics_solves,
            steps,
            rejected_steps,
            max_deflection_m,
            wall_time_s,
        ) = stats;
        Ok(Self {
            scene_name,
            tables,
            summary,
            stats: PlainStats {
                integrated,
                rhs_evaluations,
                inverse_dynamics_solves,
                steps,
                rejected_steps,
                max_deflection_m,
                wall_time_s,
            },
            table_one,
        })
    }
}

/// The outcome of one run without the GIL: a result, a failure with partial data, or an
/// invalid scene.
enum Outcome {
    Done(PyRunResult),
    Failed(PyRunResult, RunFailure),
    Invalid(flexprr_scene::ScenarioError),
}

/// Validates, builds and runs a scene; `report` receives the fraction of the time span done.
fn run_one(scene: &PyScene, report: &mut dyn FnMut(f64)) -> Outcome {
    run_one_with(scene, &crate::law::unbound_registry(), report)
}

/// As [`run_one`], with the parts of `registry` (a Python control law's).
fn run_one_with(
    scene: &PyScene,
    registry: &flexprr_scene::Registry,
    report: &mut dyn FnMut(f64),
) -> Outcome {
    let built = match scene.build_with(registry) {
        Ok(s) => s,
        Err(e) => return Outcome::Invalid(e),
    };
    match run_scene(&built, report) {
        Ok(result) => {
            report(1.0);
            Outcome::Done(PyRunResult::new(&built, &result, None))
        }
        Err(failure) => {
            let partial = PyRunResult::new(&built, &failure.partial, Some(&failure.error));
            Outcome::Failed(partial, failure)
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
    let rows = partial.tables.first().map_or(0, |t| t.rows());
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

/// Validates and runs a scene (a `Scene`, or the path of a scene file as str or
/// `os.PathLike`) with the GIL released; returns a `RunResult`, raises `SceneError` for an
/// invalid scene and `RunError` (with `.partial`) for a failed run. `progress`, when given,
/// is called as `progress(fraction)` with the fraction of the time span done, in the
/// calling thread, at most about once per percent, and with 1.0 when the run succeeded.
/// `controller` is the law of a scene with `[control] kind = "python"`: `controller(t, y)`
/// receives the measurements `y` (a float64 array in the order of `control.measurements`)
/// at each sample time `t` and returns the commands (array-like, one per entry of
/// `control.commands`, N); an exception stops the run at that sample with its traceback in
/// the `RunError` (with `.partial`).
#[pyfunction]
#[pyo3(signature = (scene, progress = None, controller = None))]
pub fn run(
    py: Python<'_>,
    scene: &Bound<'_, PyAny>,
    progress: Option<&Bound<'_, PyAny>>,
    controller: Option<&Bound<'_, PyAny>>,
) -> PyResult<Py<PyRunResult>> {
    let owned = PyScene::from_any(scene)?;
    let name = owned.name_or_default();
    let kind = owned.control_kind();
    let registry = match (controller, kind.as_deref()) {
        (Some(f), Some("python")) => crate::law::registry_with(f)?,
        (Some(_), other) => {
            return Err(crate::errors::key_error(
                "control.kind",
                format!(
                    "controller= is the function of a control.kind = \"python\" law; this \
                     scene's control law is {}",
                    other.map_or_else(
                        || "absent (no [control] table)".to_string(),
                        |k| format!("{k:?}")
                    )
                ),
            ));
        }
        (None, Some("python")) => {
            return Err(crate::errors::key_error(
                "control.kind",
                "the scene's control law is a Python function (control.kind = \"python\"): \
                 pass it as flexprr.run(scene, controller=f), f(t, y) returning the commands"
                    .to_string(),
            ));
        }
        (None, _) => crate::law::unbound_registry(),
    };
    let outcome = detached(py, progress, 0.01, move |report| {
        // Only fractions the caller will use cross the channel (the run reports every step).
        let mut last = f64::NEG_INFINITY;
        run_one_with(&owned, &registry, &mut |f| {
            if f >= last + 0.01 || (f >= 1.0 && last < 1.0) {
                last = f;
                report(f);
            }
        })
    })?;
    outcome_to_py(py, &name, outcome)?
}

/// Runs several scenes (each a `Scene` or a path) in parallel on threads (Rayon, GIL
/// released) and returns one entry per scene, in order: a `RunResult`, or with
/// `return_exceptions=True` the exception of that scene in its slot (a path that cannot be
/// read or parsed, or an entry that is neither a `Scene` nor a path: raised at once without
/// it; an invalid scene's `SceneError` or a failed run's `RunError` (with `.partial`):
/// otherwise the first of them is raised after all runs ended). `progress(fraction)` is
/// called in the calling thread after each finished scene with the fraction of scenes done.
#[pyfunction]
#[pyo3(signature = (scenes, threads = None, return_exceptions = false, progress = None))]
pub fn run_many_threads<'py>(
    py: Python<'py>,
    scenes: &Bound<'py, PyAny>,
    threads: Option<usize>,
    return_exceptions: bool,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyList>> {
    let threads = crate::study::check_threads(threads)?;
    // Each entry is read on its own: one that cannot be read keeps its exception in its
    // slot and does not stop the others.
    let mut entries: Vec<Result<usize, PyErr>> = Vec::new();
    let mut owned: Vec<PyScene> = Vec::new();
    for item in scenes.try_iter()? {
        match item.and_then(|s| PyScene::from_any(&s)) {
            Ok(scene) => {
                entries.push(Ok(owned.len()));
                owned.push(scene);
            }
            Err(e) if return_exceptions => entries.push(Err(e)),
            Err(e) => return Err(e),
        }
    }
    let names: Vec<String> = owned.iter().map(PyScene::name_or_default).collect();
    let total = owned.len();
    let outcomes = detached(py, progress, 0.0, move |report| {
        let done = AtomicUsize::new(0);
        let work = || {
            owned
                .par_iter()
                .map(|scene| {
                    let outcome = run_one(scene, &mut |_| {});
                    let finished = done.fetch_add(1, Ordering::Relaxed) + 1;
                    report(finished as f64 / total as f64);
                    outcome
                })
                .collect::<Vec<_>>()
        };
        match threads {
            Some(n) => rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map(|pool| pool.install(work))
                .map_err(|e| format!("cannot start {n} threads: {e}")),
            None => Ok(work()),
        }
    })?;
    let outcomes = outcomes.map_err(pyo3::exceptions::PyRuntimeError::new_err)?;
    let mut results: Vec<Option<Outcome>> = outcomes.into_iter().map(Some).collect();
    let list = PyList::empty(py);
    let mut first_error = None;
    for entry in entries {
        let converted = match entry {
            Ok(k) => match results[k].take() {
                Some(outcome) => outcome_to_py(py, &names[k], outcome)?,
                None => Err(pyo3::exceptions::PyRuntimeError::new_err(format!(
                    "{}: no outcome",
                    names[k]
                ))),
            },
            Err(e) => Err(e),
        };
        match converted {
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
