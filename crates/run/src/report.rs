//! Feature reports on a run's result: what a feature (control, vibration control, the
//! machine's frequencies, or one registered from outside) found over the run, kept in one
//! list ([`crate::RunResult::reports`]) rather than a field per feature. Each report names
//! itself, fills its sections of `summary.json`, gives its warnings, the lines the command
//! line prints, and the scalar quantities studies ask it for by name.
//!
//! ```
//! use std::any::Any;
//! use flexprr_run::{Report, RunResult};
//! use serde_json::{Value, json};
//!
//! /// The largest tip speed a post-processing step found (m/s).
//! #[derive(Debug)]
//! struct TipSpeed(f64);
//!
//! impl Report for TipSpeed {
//!     fn name(&self) -> &'static str {
//!         "tip_speed"
//!     }
//!     fn sections(&self) -> Vec<(&'static str, Value)> {
//!         vec![("tip_speed", json!({ "max_m_s": self.0 }))]
//!     }
//!     fn quantity(&self, name: &str) -> Option<f64> {
//!         (name == "tip_speed_max_m_s").then_some(self.0)
//!     }
//!     fn as_any(&self) -> &dyn Any {
//!         self
//!     }
//! }
//!
//! let mut result = RunResult::default();
//! result.add_report(TipSpeed(1.5));
//! assert_eq!(result.report_named("tip_speed").and_then(|r| r.quantity("tip_speed_max_m_s")), Some(1.5));
//! assert!(result.report::<TipSpeed>().is_some());
//! ```

use std::any::Any;
use std::sync::Arc;

use serde_json::Value;

/// The `summary.json` sections of the reports built into the run (`control` and
/// `feasibility` of the control report, `vibration_control` of the piezo report,
/// `machine_frequencies`): always present, `null` when the run has no such report.
pub const BUILT_IN_SECTIONS: &[&str] = &[
    "control",
    "feasibility",
    "vibration_control",
    "machine_frequencies",
];

/// What a feature found over a run (see the module documentation).
pub trait Report: std::fmt::Debug + Send + Sync + Any {
    /// The name studies and the command line find it by (`control`, `piezo`,
    /// `machine_frequencies`).
    fn name(&self) -> &'static str;

    /// Its sections of `summary.json`, `(key, value)`; a key of [`BUILT_IN_SECTIONS`] that
    /// no report fills is written as `null`.
    fn sections(&self) -> Vec<(&'static str, Value)>;

    /// Warnings about the run's validity it adds (copied into
    /// [`crate::RunResult::warnings`] when the report is added).
    fn warnings(&self) -> Vec<String> {
        Vec::new()
    }

    /// Lines the command line prints after a run (none by default).
    fn print(&self) -> Vec<String> {
        Vec::new()
    }

    /// A scalar quantity called `name`, for studies, if the report offers it.
    fn quantity(&self, _name: &str) -> Option<f64> {
        None
    }

    /// The report as [`Any`], to read its own type back ([`crate::RunResult::report`]).
    fn as_any(&self) -> &dyn Any;
}

/// A shared report: cloning a result clones the handles, not the reports.
pub type SharedReport = Arc<dyn Report>;
