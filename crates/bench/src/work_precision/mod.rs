//! Work-precision measurement: how much wall time each integrator needs for a given achieved
//! accuracy on a scene's model, and, side by side, what each model (KED, coupled,
//! geometrically nonlinear) costs for the fidelity it reaches.
//!
//! For every model, every method and every tolerance of a ladder the scene is integrated over
//! its output times; the wall time is the median of several timed repeats after warm-up runs,
//! and the achieved error is measured against a [`Reference`] solution computed once at a far
//! tighter tolerance and checked against a second method. This is the work-precision diagram
//! of Hairer, Norsett & Wanner, *Solving ODEs I*, 2nd ed., II.10 (error against computing
//! time, log-log), as DiffEqDevTools and the SciPy benchmarks draw it.
//!
//! Two error measures ([`ErrorMeasure`]):
//!
//! * `state` (KED models only, the default when every model is KED): the state is
//!   `(eta, eta')`, and a difference in a displacement is divided by the largest `|eta|` of the
//!   reference, one in a velocity by the largest `|eta'|`.
//! * `deflection` (every model; the only one for coupled and nonlinear models, whose states
//!   are not modal amplitudes or not comparable between models): the links' mid-point
//!   deflections `w_i(1/2, t)` (the `deflections.csv` quantity at `xi = 0.5`, what the
//!   external models report), differences divided by the largest `|w_i(1/2)|` of the
//!   reference.
//!
//! Two numbers are reported: at the end time ([`AchievedError::end`]) and the maximum over all
//! output times ([`AchievedError::max`]).
//!
//! Tolerances: at ladder value `tol` every solver gets `rtol = tol` and the scalar
//! `atol = tol * s`, with `s` the size the errors are relative to (largest `|eta|`, or largest
//! `|w(1/2)|`, of the reference), so that a zero initial state does not make the absolute
//! tolerance meaningless.
//!
//! Models side by side ([`WorkPrecisionConfig::models`], [`ModelChoice`]): each row is the
//! scene with `model.coupling` (and `model.elements`) overridden, all measured in deflections
//! against one reference, by default the most accurate model of the set (the nonlinear one
//! with the most elements). A model's error then floors at its model error, which is the
//! point: cost against achieved fidelity.
//!
//! Rows of other packages (the `benches/peers` crate, the SciPy script) use the same CSV
//! columns ([`WorkPrecisionRow`]) and can be merged with [`read_csv`].
//!
//! The module is split by job: [`config`] (what to measure: models, methods, the ladder and
//! the reference plan), [`reference`](mod@reference) (the reference solution and the error measures),
//! [`measure`](mod@measure) (timing flexprr's integrators against it) and [`report`] (the CSV,
//! Markdown tables and the diagram). Everything is re-exported here.

pub mod config;
mod error;
pub mod measure;
pub mod reference;
pub mod report;

pub use config::{ModelChoice, ReferencePlan, WorkPrecisionConfig, builtin, default_reference};
pub use error::{Disagreement, FailedReference, WorkPrecisionError};
pub use measure::{
    Timing, WorkPrecision, WorkPrecisionRow, measure, method_applies, time_runs, work_precision,
};
pub use reference::{AchievedError, Reference, midpoint_deflections};
pub use report::{
    csv_text, markdown_at_error, markdown_models, markdown_rows, read_csv, series, time_at_error,
    write_svg,
};

use flexprr_dynamics::SceneModel;
use flexprr_scene::Scene;

/// The default tolerance ladder, `1e-3` down to `1e-12` (one per decade).
pub const DEFAULT_TOLERANCES: [f64; 10] = [
    1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12,
];

/// The default ladder when a nonlinear model is measured, `1e-3` down to `1e-8`: its steps
/// are set by the elements' axial modes down to about `1e-8` (docs/performance.md,
/// "Nonlinear links"), and tighter points would need a reference beyond what finishes.
pub const NONLINEAR_TOLERANCES: [f64; 6] = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8];

/// The name of this package in the `package` column.
pub const PACKAGE: &str = "flexprr";

/// The point of the links where the deflection measure looks: the mid-point, `xi = 1/2`.
pub const DEFLECTION_XI: f64 = 0.5;

/// How achieved errors are measured (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorMeasure {
    /// The modal state `(eta, eta')`, block by block; KED models only.
    State,
    /// The three links' mid-point deflections; every model.
    Deflection,
}

impl ErrorMeasure {
    /// Every measure, in the order of [`ErrorMeasure::name`]'s help.
    pub const ALL: [ErrorMeasure; 2] = [ErrorMeasure::Deflection, ErrorMeasure::State];

    /// The measure's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ErrorMeasure::State => "state",
            ErrorMeasure::Deflection => "deflection",
        }
    }

    /// The measure named `name`, if any.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// The scene's model from its one builder.
pub(crate) fn build(scene: &Scene) -> Result<Box<dyn SceneModel>, WorkPrecisionError> {
    scene
        .build_model()
        .map_err(|source| WorkPrecisionError::Model {
            scene: scene.name.clone(),
            source,
        })
}
