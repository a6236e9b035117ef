//! Integrator errors, each with the time at which it happened.

use thiserror::Error;

/// Why an integration stopped.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum IntegratorError {
    /// The step size fell below the floor `16 eps |t|` (or a method's own floor).
    #[error(
        "step size collapsed to {h:e} s at t = {t} s: the right-hand side is probably not smooth there (a jump in it or a low derivative, e.g. a forcing switching on: pass that time as a stop) or the solution is singular"
    )]
    StepSizeTooSmall {
        /// Time reached.
        t: f64,
        /// The step size that was too small.
        h: f64,
    },
    /// More than `max_steps` steps were needed.
    #[error(
        "gave up after {max_steps} steps at t = {t} s (raise max_steps or loosen the tolerance; if an explicit method takes tiny steps while the solution is smooth, the problem is stiff)"
    )]
    TooManySteps {
        /// Time reached.
        t: f64,
        /// The limit that was hit.
        max_steps: usize,
    },
    /// The state or its derivative became NaN or infinite.
    #[error(
        "non-finite value in component {component} at t = {t} s (the solution diverged or the right-hand side failed)"
    )]
    NonFinite {
        /// Time at which it was detected.
        t: f64,
        /// Index of the first non-finite component.
        component: usize,
    },
    /// Newton iterations of an implicit method kept failing even with a fresh Jacobian.
    #[error("Newton iterations failed to converge at t = {t} s with step {h:e} s")]
    NewtonFailure {
        /// Time reached.
        t: f64,
        /// Last step size tried.
        h: f64,
    },
    /// The iteration matrix `I - h gamma J` was singular.
    #[error("singular iteration matrix at t = {t} s")]
    SingularMatrix {
        /// Time reached.
        t: f64,
    },
    /// An explicit method found the problem stiff and was asked to stop
    /// (see [`crate::rk45::StiffnessDetection::Error`]).
    #[error(
        "the problem looks stiff at t = {t} s (stability, not accuracy, limits the step: h*|lambda| ~ {h_lambda:.2}); use an implicit method such as BDF"
    )]
    Stiff {
        /// Time at which the test fired.
        t: f64,
        /// Estimate of `|h lambda|` on the step that fired the test.
        h_lambda: f64,
    },
    /// The system's terminal event ([`crate::OdeSystem::terminal_event`]) was reached: the
    /// integration ended there as the system asked (what it means is the system's to say).
    #[error("the system's terminal event was reached at t = {t} s")]
    TerminalEvent {
        /// The located time of the event.
        t: f64,
    },
    /// An option is out of range.
    #[error("invalid integrator option: {0}")]
    InvalidOptions(String),
    /// The initial value or the requested output times are not usable.
    #[error("invalid integration input: {0}")]
    InvalidInput(String),
}

impl IntegratorError {
    /// The time at which the error happened, if it arose during the integration (input and
    /// option errors have none).
    pub fn time(&self) -> Option<f64> {
        match self {
            Self::StepSizeTooSmall { t, .. }
            | Self::TooManySteps { t, .. }
            | Self::NonFinite { t, .. }
            | Self::NewtonFailure { t, .. }
            | Self::SingularMatrix { t }
            | Self::Stiff { t, .. }
            | Self::TerminalEvent { t } => Some(*t),
            Self::InvalidOptions(_) | Self::InvalidInput(_) => None,
        }
    }
}
