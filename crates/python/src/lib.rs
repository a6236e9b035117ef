//! Python bindings of flexprr (PyO3, abi3 for CPython 3.9+): the native module
//! `flexprr._flexprr`, re-exported by the Python package `flexprr` (`docs/python.md`).
//!
//! Scenes load from a TOML path, a TOML string or a dict, change by dotted keys and
//! validate with the CLI's checker; `run` returns the run layer's tables as NumPy arrays
//! under the CLI's CSV column names, the `summary.json` contents and the statistics.
//! Every call that does real work releases the GIL; progress callbacks are called back in
//! the caller's thread (`progress`). Scenes, results and exceptions pickle, so they cross
//! process boundaries. Nothing here may crash the interpreter: Python values are converted
//! with depth, cycle and size limits (`convert`), and a panic becomes a `RuntimeError`.

mod beam;
mod convert;
mod errors;
mod kinematics;
mod law;
mod linear;
mod plan;
mod progress;
mod run;
mod scene;
mod study;

use pyo3::prelude::*;

/// The native module; the Python package `flexprr` re-exports it.
#[pymodule]
#[pyo3(name = "_flexprr")]
fn flexprr_native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<scene::PyScene>()?;
    m.add_class::<run::PyRunResult>()?;
    m.add_class::<run::PyTable>()?;
    m.add_function(wrap_pyfunction!(run::run, m)?)?;
    m.add_function(wrap_pyfunction!(run::run_many_threads, m)?)?;
    m.add_function(wrap_pyfunction!(kinematics::inverse_kinematics, m)?)?;
    m.add_function(wrap_pyfunction!(kinematics::forward_kinematics, m)?)?;
    m.add_function(wrap_pyfunction!(kinematics::singularity, m)?)?;
    m.add_function(wrap_pyfunction!(beam::link_frequencies, m)?)?;
    m.add_function(wrap_pyfunction!(study::run_study, m)?)?;
    m.add_function(wrap_pyfunction!(linear::linearize, m)?)?;
    m.add_function(wrap_pyfunction!(linear::frequency_response, m)?)?;
    m.add_function(wrap_pyfunction!(linear::margins, m)?)?;
    m.add_class::<plan::PyPlan>()?;
    m.add_function(wrap_pyfunction!(plan::plan, m)?)?;
    m.add("SceneError", py.get_type::<errors::SceneError>())?;
    m.add("RunError", py.get_type::<errors::RunError>())?;
    m.add("KinematicsError", py.get_type::<errors::KinematicsError>())?;
    m.add("StudyError", py.get_type::<errors::StudyError>())?;
    Ok(())
}
