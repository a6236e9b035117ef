//! `flexprr.run(scene, controller=f)`: a `[control] kind = "python"` law whose commands the
//! Python function `f(t, y)` computes at each sample (docs/control.md, "Python laws"). The
//! run goes on with the GIL released; each sample takes it for the call only. An exception
//! (or a result that is not the right number of finite commands) stops the run at that
//! sample with the traceback in the `RunError`, which keeps the data computed so far.

use std::sync::Arc;

use flexprr_control::LawFunction;
use flexprr_scene::{CallbackLawFactory, Registry};
use numpy::PyArray1;
use pyo3::prelude::*;

/// The user's function as a [`LawFunction`].
struct PythonLaw {
    function: Py<PyAny>,
}

/// The Python traceback of `error`, as Python prints it.
fn traceback(py: Python<'_>, error: &PyErr) -> String {
    let formatted = py.import("traceback").and_then(|tb| {
        tb.call_method1(
            "format_exception",
            (error.get_type(py), error.value(py), error.traceback(py)),
        )?
        .extract::<Vec<String>>()
    });
    match formatted {
        Ok(lines) => lines.concat().trim_end().to_string(),
        Err(_) => error.to_string(),
    }
}

impl LawFunction for PythonLaw {
    fn call(&self, t: f64, y: &[f64], u: &mut [f64]) -> Result<(), String> {
        Python::attach(|py| {
            let result = self
                .function
                .call1(py, (t, PyArray1::from_slice(py, y)))
                .map_err(|e| format!("the controller raised:\n{}", traceback(py, &e)))?;
            let result = result.bind(py);
            if result.is_none() {
                return Err(format!(
                    "the controller returned None, not {} numbers (one per command)",
                    u.len()
                ));
            }
            let values = py
                .import("numpy")
                .and_then(|np| np.call_method1("asarray", (result, "float64")))
                .and_then(|a| {
                    if a.getattr("ndim")?.extract::<usize>()? > 1 {
                        return Err(pyo3::exceptions::PyValueError::new_err(format!(
                            "an array of shape {}",
                            a.getattr("shape")?
                        )));
                    }
                    a.call_method0("ravel")?.extract::<Vec<f64>>()
                })
                .map_err(|e| {
                    format!(
                        "the controller returned {}, not {} numbers (one per command): {e}",
                        result
                            .repr()
                            .map_or_else(|_| "?".to_string(), |r| short(&r.to_string())),
                        u.len()
                    )
                })?;
            if values.len() != u.len() {
                return Err(format!(
                    "the controller returned {} commands, expected {} (one per entry of \
                     control.commands)",
                    values.len(),
                    u.len()
                ));
            }
            u.copy_from_slice(&values);
            Ok(())
        })
    }
}

/// At most 80 characters of `text`.
fn short(text: &str) -> String {
    match text.char_indices().nth(80) {
        Some((k, _)) => format!("{}...", &text[..k]),
        None => text.to_string(),
    }
}

/// The law of a scene checked or run without its function: it fails at its first sample with
/// the way to give it.
struct Unbound;

impl LawFunction for Unbound {
    fn call(&self, _t: f64, _y: &[f64], _u: &mut [f64]) -> Result<(), String> {
        Err(flexprr_scene::PYTHON_LAW_NEEDS_PYTHON.to_string())
    }
}

/// The default registry with `kind = "python"` accepted without its function (so that
/// such scenes validate from Python; `run` asks for the function, the linear tools refuse
/// them).
pub(crate) fn unbound_registry() -> Registry {
    let mut registry = Registry::default();
    registry.register_controller(
        "python",
        Arc::new(CallbackLawFactory::new(Some(Arc::new(Unbound)))),
    );
    registry
}

/// A `SceneError` when `scene`'s law is a Python function, which a linear tool cannot
/// linearise.
pub(crate) fn refuse_python_law(scene: &crate::scene::PyScene) -> PyResult<()> {
    if scene.control_kind().as_deref() == Some("python") {
        return Err(crate::errors::key_error(
            "control.kind",
            "a Python control law has no linear model: the linear tools cannot differentiate a \
             Python function (which may keep states of its own); linearise the machine with a \
             built-in or state-space law"
                .to_string(),
        ));
    }
    Ok(())
}

/// The default registry with `kind = "python"` calling `function`.
pub(crate) fn registry_with(function: &Bound<'_, PyAny>) -> PyResult<Registry> {
    if !function.is_callable() {
        return Err(pyo3::exceptions::PyTypeError::new_err(format!(
            "controller must be a function f(t, y) returning the commands, got {}",
            function.get_type().name()?
        )));
    }
    let mut registry = Registry::default();
    let law = PythonLaw {
        function: function.clone().unbind(),
    };
    registry.register_controller(
        "python",
        Arc::new(CallbackLawFactory::new(Some(Arc::new(law)))),
    );
    Ok(registry)
}
