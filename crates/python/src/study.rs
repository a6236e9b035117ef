//! `flexprr.run_study`: a study file (`docs/studies.md`) run in parallel with the GIL
//! released, as `flexprr study` does (the studies crate loads the file with the CLI's input
//! checks and writes `out` with its own output policy).

use std::path::PathBuf;

use flexprr_studies::{Study, StudyOptions, run_study as run_rust_study};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::StudyError;
use crate::progress::detached;

/// Most worker threads a call may ask for: far more than any machine's cores, few enough
/// that asking cannot exhaust the system.
pub const MAX_THREADS: usize = 256;

/// `threads` checked: `None` (all cores) or 1 to [`MAX_THREADS`].
pub fn check_threads(threads: Option<usize>) -> PyResult<Option<usize>> {
    match threads {
        Some(n) if n == 0 || n > MAX_THREADS => Err(pyo3::exceptions::PyValueError::new_err(
            format!("threads = {n}: expected 1 to {MAX_THREADS} (or None for all cores)"),
        )),
        other => Ok(other),
    }
}

/// Runs a study file (str or `os.PathLike`) into the directory `out` (its `results.csv`,
/// `study.json` and, with `case_outputs`, each case's outputs) on `threads` worker threads
/// (default: all cores), skipping recorded cases when `resume`. `progress(fraction)` is
/// called in the calling thread after each finished case with the fraction of cases done
/// (resumed cases count as done), for a workspace map after each pose, for a speed search
/// after each probe (the fraction of the probes its schedule plans), and with 1.0 at the
/// end. Returns a dict: `name`, `total`, `ran`, `resumed`,
/// `failed` and `results` (the path of `results.csv`). Raises `StudyError`.
#[pyfunction]
#[pyo3(signature = (path, out, threads = None, resume = false, case_outputs = false, progress = None))]
pub fn run_study<'py>(
    py: Python<'py>,
    path: PathBuf,
    out: PathBuf,
    threads: Option<usize>,
    resume: bool,
    case_outputs: bool,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let threads = check_threads(threads)?;
    let outcome = detached(py, progress, 0.0, move |report| {
        let study = Study::load(&path)?;
        let options = StudyOptions {
            threads,
            shard: None,
            resume,
            case_outputs,
            force: false,
        };
        // Progress per case of a sweep, per pose of a map, per probe of a search (against
        // the probes its schedule plans, the same for any thread count).
        let summary = if let Some(search) = &study.search {
            let planned = search.planned_probes() * study.cases.len().max(1);
            let done = std::sync::atomic::AtomicUsize::new(0);
            let on_probe = |_: &_, _: &_| {
                let n = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                report((n as f64 / planned.max(1) as f64).min(0.99));
            };
            flexprr_studies::run_search_study(&study, &out, &options, &on_probe)?
        } else if study.map.is_some() {
            let on_pose = |p: &flexprr_studies::map::MapProgress| {
                if p.total > 0 {
                    report(p.done as f64 / p.total as f64);
                }
            };
            flexprr_studies::run_map_study(&study, &out, &options, &on_pose)?.0
        } else {
            let on_case = |p: &flexprr_studies::study::StudyProgress, _: &_| {
                if p.total > 0 {
                    report(p.done as f64 / p.total as f64);
                }
            };
            run_rust_study(&study, &out, &options, &on_case)?
        };
        report(1.0);
        Ok::<_, flexprr_studies::StudyError>((study.name, summary))
    })?;
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
