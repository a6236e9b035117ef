//! Work in Rust with the GIL released, with an optional Python progress callback called in
//! the caller's own thread.
//!
//! Without a callback the work runs in the calling thread with the GIL released. With one,
//! the work runs on a scoped worker thread and reports fractions over a channel; the calling
//! thread (GIL still released) waits on the channel and, for each fraction at least
//! `min_step` past the last one reported (and for 1), takes the GIL back and calls the
//! callback. So Python code always runs in the thread that called flexprr, holding the GIL,
//! and at most about `1 / min_step` times. An exception raised by the callback stops further
//! calls and is raised once the work has ended (the run layer cannot be interrupted midway).
//! A panic in the work becomes a `RuntimeError`, never a `PanicException`.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::mpsc;

use pyo3::prelude::*;

use crate::errors::panic_error;

/// Calls `work` with the GIL released, giving it a thread-safe reporter of fractions in
/// `[0, 1]`; `callback(fraction)` is called as described in the module documentation.
///
/// # Errors
/// The callback's exception, or a `RuntimeError` when the work panicked.
pub fn detached<T, W>(
    py: Python<'_>,
    callback: Option<&Bound<'_, PyAny>>,
    min_step: f64,
    work: W,
) -> PyResult<T>
where
    T: Send,
    W: FnOnce(&(dyn Fn(f64) + Sync)) -> T + Send,
{
    let Some(callback) = callback else {
        return py
            .detach(|| catch_unwind(AssertUnwindSafe(|| work(&|_| {}))))
            .map_err(|payload| panic_error(payload.as_ref()));
    };
    let callback: Py<PyAny> = callback.clone().unbind();
    let (tx, rx) = mpsc::channel::<f64>();
    let (outcome, failed) = py.detach(move || {
        std::thread::scope(|scope| {
            let worker = scope.spawn(move || {
                let report = move |fraction: f64| {
                    // The receiver only goes away after the work: a failed send is harmless.
                    let _ = tx.send(fraction);
                };
                work(&report)
            });
            let mut last = f64::NEG_INFINITY;
            let mut failed: Option<PyErr> = None;
            for fraction in rx.iter() {
                let due = fraction >= last + min_step || (fraction >= 1.0 && last < 1.0);
                if failed.is_some() || !due || !fraction.is_finite() {
                    continue;
                }
                last = fraction;
                let called =
                    Python::attach(|py| callback.call1(py, (fraction.clamp(0.0, 1.0),)).map(drop));
                if let Err(e) = called {
                    failed = Some(e);
                }
            }
            (worker.join(), failed)
        })
    });
    let value = outcome.map_err(|payload| panic_error(payload.as_ref()))?;
    match failed {
        Some(e) => Err(e),
        None => Ok(value),
    }
}
