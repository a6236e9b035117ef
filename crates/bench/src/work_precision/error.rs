//! Why a work-precision measurement failed, typed: bad input (the scene layer's
//! [`ScenarioError`]), a model that cannot be built, a reference that failed or was not
//! confirmed by its check, a value that is not finite, a solution that does not fit the
//! reference, a file that cannot be written.

use flexprr_dynamics::DynamicsError;
use flexprr_scene::ScenarioError;
use thiserror::Error;

use super::ErrorMeasure;

/// Why a work-precision measurement, its reference or its files failed. Everything but
/// [`WorkPrecisionError::Scene`] is a failure of the run (exit code 1 in the CLI); the
/// messages name the scene, model, integration and time where they apply.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum WorkPrecisionError {
    /// Bad input (configuration, scene, a reference or peers file that cannot be read).
    #[error(transparent)]
    Scene(#[from] ScenarioError),
    /// The scene's model cannot be built.
    #[error("run failed: scene {scene:?}: {source}")]
    Model {
        /// The scene's name.
        scene: String,
        /// Why.
        source: DynamicsError,
    },
    /// An integration of the reference failed (the run layer's divergence guard, an
    /// integrator failure, the model's own cause such as a collapse): a failed reference is
    /// never measured against.
    #[error("{0}")]
    Reference(Box<FailedReference>),
    /// A step of the reference model's computation failed (`stage`: e.g. `pilot run for the
    /// reference`).
    #[error("run failed: reference model {model}: {stage}: {source}")]
    InModel {
        /// The reference model's label.
        model: String,
        /// What was being done.
        stage: &'static str,
        /// Why.
        source: Box<WorkPrecisionError>,
    },
    /// The reference and its check disagree by more than the plan's limit.
    #[error("{0}")]
    Unconfirmed(Box<Disagreement>),
    /// A link's mid-point deflection cannot be computed.
    #[error(
        "run failed: mid-point deflection of link {link} at t = {t} s ({model} model): {source}"
    )]
    Deflection {
        /// Link (1-based).
        link: usize,
        /// Time (s).
        t: f64,
        /// The model's kind.
        model: String,
        /// Why.
        source: DynamicsError,
    },
    /// A value is not finite.
    #[error(
        "run failed: {what} at t = {t} s{} is not finite ({value})",
        in_model(.model)
    )]
    NotFinite {
        /// The value, e.g. `the mid-point deflection of link 2` or `component 3`.
        what: String,
        /// Time (s).
        t: f64,
        /// The model's kind, where it says more.
        model: Option<String>,
        /// The value.
        value: f64,
    },
    /// A solution measured in one measure against a reference of the other.
    #[error("run failed: {}", wrong_measure(.reference))]
    WrongMeasure {
        /// What the reference holds.
        reference: ErrorMeasure,
    },
    /// A solution whose size does not fit the reference's.
    #[error("run failed: {}", shape(.measure, .given, .expected, .times, .width))]
    Shape {
        /// The measure compared in.
        measure: ErrorMeasure,
        /// Values given.
        given: usize,
        /// Values of the reference.
        expected: usize,
        /// Output times of the reference.
        times: usize,
        /// Values per time.
        width: usize,
    },
    /// A file (or its text) that cannot be produced: serialising or writing it failed.
    #[error("{path}: {message}")]
    Write {
        /// The file, or what was being written (`work-precision CSV`).
        path: String,
        /// Why.
        message: String,
    },
    /// A diagram with nothing to draw: no point with a positive time and error.
    #[error("plot {path}: no positive times and errors to draw")]
    NothingToDraw {
        /// The diagram's file.
        path: String,
    },
}

/// A failed integration of a reference: which (scene, model, role, method and tolerance),
/// when and why.
#[derive(Debug, Clone, PartialEq)]
pub struct FailedReference {
    /// The scene's name.
    pub scene: String,
    /// The reference model's label.
    pub model: String,
    /// Which integration: `pilot run`, `reference` or `check`.
    pub role: &'static str,
    /// The method.
    pub method: String,
    /// Its relative tolerance.
    pub rtol: f64,
    /// When it failed, if known.
    pub time: Option<f64>,
    /// Why, in the run layer's words.
    pub reason: String,
}

impl std::fmt::Display for FailedReference {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let Self {
            scene,
            model,
            role,
            method,
            rtol,
            time,
            reason,
        } = self;
        write!(
            f,
            "run failed: scene {scene:?}, reference model {model}: the {role} ({method} at \
             rtol {rtol:e}) failed{}: {reason}; a failed reference is not measured against",
            when(time, reason)
        )
    }
}

/// A reference and its check that disagree by more than the accepted limit.
#[derive(Debug, Clone, PartialEq)]
pub struct Disagreement {
    /// The reference model's label.
    pub model: String,
    /// The reference's method.
    pub method: String,
    /// Its relative tolerance.
    pub rtol: f64,
    /// The check's method.
    pub check_method: String,
    /// Its relative tolerance.
    pub check_rtol: f64,
    /// Their disagreement at the end time.
    pub end: f64,
    /// Their largest disagreement.
    pub max: f64,
    /// The error measure's name.
    pub measure: &'static str,
    /// The accepted disagreement.
    pub limit: f64,
}

impl std::fmt::Display for Disagreement {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let Self {
            model,
            method,
            rtol,
            check_method,
            check_rtol,
            end,
            max,
            measure,
            limit,
        } = self;
        write!(
            f,
            "run failed: reference model {model}: the reference ({method} at rtol {rtol:e}) and \
             its check ({check_method} at rtol {check_rtol:e}) disagree by {end:e} (end) / \
             {max:e} (max) in the {measure} measure, above the limit {limit:e}"
        )
    }
}

/// ` at t = <t> s` when the reason does not name its time itself.
fn when(time: &Option<f64>, reason: &str) -> String {
    match *time {
        Some(t) if !reason.contains("t = ") => format!(" at t = {t} s"),
        _ => String::new(),
    }
}

/// ` (<kind> model)` when the model is named.
fn in_model(model: &Option<String>) -> String {
    model
        .as_ref()
        .map(|m| format!(" ({m} model)"))
        .unwrap_or_default()
}

/// What a reference of `reference` cannot be compared with.
fn wrong_measure(reference: &ErrorMeasure) -> &'static str {
    match reference {
        ErrorMeasure::State => {
            "the reference holds modal states, not deflections: compute it with the \
             deflection measure"
        }
        ErrorMeasure::Deflection => {
            "the reference holds mid-point deflections, not modal states: measure in \
             deflections"
        }
    }
}

/// Why `given` values do not fit a reference of `expected` (`times` x `width`).
fn shape(
    measure: &ErrorMeasure,
    given: &usize,
    expected: &usize,
    times: &usize,
    width: &usize,
) -> String {
    match measure {
        ErrorMeasure::Deflection => format!(
            "{given} deflections cannot be compared with the reference's {expected} ({times} \
             times x 3 links)"
        ),
        ErrorMeasure::State => format!(
            "a solution with {given} values cannot be compared with the reference's {expected} \
             ({times} times x {width})"
        ),
    }
}
