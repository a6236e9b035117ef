//! Python exceptions of flexprr and how Rust errors become them.
//!
//! The exception types live in the module `flexprr` (their `__module__`), where the package
//! re-exports them, so that pickle finds them by name: an exception raised in a worker
//! process (`multiprocessing`, `concurrent.futures`, Dask) arrives in the parent with its
//! attributes (`key`, `file`, `line`, ..., which are in the instance's `__dict__`).

use flexprr_scene::ScenarioError;
use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

create_exception!(
    flexprr,
    SceneError,
    PyValueError,
    "A scene (or link, or study) is invalid: `key` is the dotted key, `file`, `line`, `column` locate it when known, `message` says what was expected. The text is the CLI's message."
);
create_exception!(
    flexprr,
    RunError,
    PyRuntimeError,
    "A run stopped early: `kind` (diverged, singular-pose, step-size-collapse, ...), `time` (s) and `link` (1-based) when known, and `partial`, the RunResult up to the failure."
);
create_exception!(
    flexprr,
    KinematicsError,
    PyValueError,
    "A pose is unreachable, outside the slider travel or too close to a singularity; `index` is the position of the pose in the input array."
);
create_exception!(
    flexprr,
    StudyError,
    PyRuntimeError,
    "A study could not be read or run (bad study file, base scene, output directory)."
);

/// A scene error as `SceneError`, with its key and location as attributes.
pub fn scene_error(e: ScenarioError) -> PyErr {
    Python::attach(|py| {
        let err = SceneError::new_err(e.to_string());
        let value = err.value(py);
        let (key, location, message) = match &e {
            ScenarioError::Input {
                location,
                key,
                message,
            } => (key.clone(), location.clone(), message.clone()),
            other => (String::new(), None, other.to_string()),
        };
        let set = || -> PyResult<()> {
            value.setattr("key", key)?;
            value.setattr("message", message)?;
            value.setattr("file", location.as_ref().map(|l| l.file.clone()))?;
            value.setattr("line", location.as_ref().map(|l| l.line))?;
            value.setattr("column", location.as_ref().map(|l| l.column))?;
            Ok(())
        };
        match set() {
            Ok(()) => err,
            Err(e) => e,
        }
    })
}

/// A plain `SceneError` for a key (no location).
pub fn key_error(key: &str, message: String) -> PyErr {
    scene_error(ScenarioError::Input {
        location: None,
        key: key.to_string(),
        message,
    })
}

/// A panic inside the extension as a plain `RuntimeError` (never a `PanicException`, which
/// `except Exception` does not catch): the message says it is a flexprr bug.
pub fn panic_error(payload: &(dyn std::any::Any + Send)) -> PyErr {
    let what = payload
        .downcast_ref::<&str>()
        .map(|s| (*s).to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".to_string());
    PyRuntimeError::new_err(format!(
        "internal error in flexprr (please report it): {what}"
    ))
}
