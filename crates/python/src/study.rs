//! `flexprr.run_study`: a study file (`docs/studies.md`) run in parallel with the GIL
//! released, as `flexprr study` does.

use std::path::PathBuf;

use flexprr_studies::{Study, StudyOptions, run_study as run_rust_study};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::StudyError;

/// Runs a study file into the directory `out` (its `results.csv`, `study.json` and, with
/// `case_outputs`, each case's outputs) on `threads` worker threads (default: all cores),
/// skipping recorded cases when `resume`. Returns a dict: `name`, `total`, `ran`, `resumed`,
/// `failed` and `results` (the path of `results.csv`). Raises `StudyError`.
#[pyfunction]
#[pyo3(signature = (path, out, threads = None, resume = false, case_outputs = false))]
pub fn run_study<'py>(
    py: Python<'py>,
    path: PathBuf,
    out: PathBuf,
    threads: Option<usize>,
    resume: bool,
    case_outputs: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let outcome = py.detach(move || {
        let study = Study::load(&path)?;
        let options = StudyOptions {
            threads,
            shard: None,
            resume,
            case_outputs,
            force: false,
        };
        let summary = run_rust_study(&study, &out, &options, &|_, _| {})?;
        Ok::<_, flexprr_studies::StudyError>((study.name, summary))
    });
    let (name, summary) = outcome.map_err(|e| StudyError::new_err(e.to_string()))?;
    let d = PyDict::new(py);
    d.set_item("name", name)?;
    d.set_item("total", summary.progress.total)?;
    d.set_item("ran", summary.ran)?;
    d.set_item("resumed", summary.progress.resumed)?;
    d.set_item("failed", summary.progress.failed)?;
    d.set_item("results", summary.results.display().to_string())?;
    Ok(d)
}
