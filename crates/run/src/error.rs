//! Why a run failed, typed: the lower layers' errors, a divergence, an I/O failure.

use flexprr_dynamics::DynamicsError;
use flexprr_integrators::IntegratorError;
use flexprr_linear::LinearError;
use flexprr_scene::ScenarioError;
use flexprr_viewer::ViewerError;
use thiserror::Error;

use crate::RunResult;

/// Why a run stopped before the end of its time span, or could not write its outputs.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum RunError {
    /// The model failed: a singular pose, a kinematic failure, a bad parameter.
    #[error(transparent)]
    Model(#[from] DynamicsError),
    /// The integrator gave up (step size collapse, too many steps, non-finite state).
    #[error("{method} integrator: {source}")]
    Integrator {
        /// The method's name.
        method: String,
        /// The integrator's reason, with the time.
        #[source]
        source: IntegratorError,
    },
    /// A link's deflection passed the divergence limit (see [`crate::guard`]).
    #[error(
        "diverged: link {} at t = {}: deflection {w:.3e} m at xi = {xi} exceeds {limit:.3e} m ({fraction} of the link length); the small-deflection model has left its range (a link buckles, or the tolerance is too loose); request \"frequencies\" to see the buckling intervals",
        link + 1,
        seconds(*t)
    )]
    Diverged {
        /// Link (0-based).
        link: usize,
        /// Time (s).
        t: f64,
        /// Position along the link.
        xi: f64,
        /// The deflection there (m).
        w: f64,
        /// The limit (m).
        limit: f64,
        /// The limit as a fraction of the link length.
        fraction: f64,
    },
    /// The state became NaN or infinite (named by link, mode and derivative).
    #[error(
        "{method} integrator: {state} became non-finite at t = {} (the solution blew up within one step: check masses, stiffness, speed and tolerances for absurd values)",
        seconds(*t)
    )]
    NonFinite {
        /// The method's name.
        method: String,
        /// Time (s).
        t: f64,
        /// Which state component, in words (`modal rate d(eta)/dt of link 2, mode 1`).
        state: String,
        /// The link (0-based), where the component belongs to one.
        link: Option<usize>,
    },
    /// Linearising the run's model along its motion failed (an output such as
    /// `machine_frequencies`): the output, the time and why.
    #[error("{output} at t = {t} s: {source}")]
    Linear {
        /// The output that linearises (`machine_frequencies`).
        output: &'static str,
        /// Time of the operating point (s).
        t: f64,
        /// Why the linearisation or its eigenvalue problem failed.
        #[source]
        source: LinearError,
    },
    /// A figure or document of the run could not be drawn from the run's data.
    #[error("{file}: {source}")]
    Figure {
        /// The file it was for (`viewer.html`, `snapshots.svg`, `machine.svg`).
        file: String,
        /// What is wrong with the data.
        #[source]
        source: ViewerError,
    },
    /// An output producer could not make its output: a scene requests an output no
    /// producer of the run makes, or a producer lacks what it needs or fails for a reason of
    /// its own.
    #[error("output {output}: {reason}")]
    Output {
        /// The output's name.
        output: String,
        /// Why, in words.
        reason: String,
    },
    /// A linear analysis of the scene (its modes, frequency response or loop margins at an
    /// operating point) failed numerically: what was analysed, where it says more, and why.
    #[error("run failed: {}{source}", analysis_prefix(.analysis))]
    Analysis {
        /// What was analysed, e.g. `margins: slider 2`.
        analysis: Option<String>,
        /// Why the linearisation or its eigenvalue problem failed.
        #[source]
        source: LinearError,
    },
    /// The lowest mode of a linear model was asked for and it has none of non-zero
    /// frequency.
    #[error("run failed: the linear model has no mode of non-zero frequency")]
    NoMode,
    /// Reading or writing outputs, or bad input met while running.
    #[error(transparent)]
    Scene(#[from] ScenarioError),
}

/// `<analysis>: ` when the analysis is named.
fn analysis_prefix(analysis: &Option<String>) -> String {
    analysis
        .as_ref()
        .map(|a| format!("{a}: "))
        .unwrap_or_default()
}

impl RunError {
    /// A one-word kind for `summary.json` and study records: `collapse` (the mechanism
    /// collapsed: a physical outcome), `diverged`, `singular-pose`, `kinematics`,
    /// `step-size-collapse`, `too-many-steps`, `non-finite`, `integrator`, `model`,
    /// `linearisation`, `figure`, `output`, `io`, `input`.
    pub fn kind(&self) -> &'static str {
        match self {
            RunError::Model(DynamicsError::Collapse { .. }) => "collapse",
            RunError::Diverged { .. } => "diverged",
            RunError::NonFinite { .. } => "non-finite",
            RunError::Model(DynamicsError::SingularInverseDynamics { .. }) => "singular-pose",
            RunError::Model(DynamicsError::Kinematics { .. }) => "kinematics",
            RunError::Model(_) => "model",
            RunError::Integrator { source, .. } => match source {
                IntegratorError::StepSizeTooSmall { .. } => "step-size-collapse",
                IntegratorError::TooManySteps { .. } => "too-many-steps",
                IntegratorError::NonFinite { .. } => "non-finite",
                IntegratorError::Stiff { .. } => "stiff",
                _ => "integrator",
            },
            RunError::Linear { .. } | RunError::Analysis { .. } | RunError::NoMode => {
                "linearisation"
            }
            RunError::Figure { .. } => "figure",
            RunError::Output { .. } => "output",
            RunError::Scene(ScenarioError::Io { .. }) => "io",
            RunError::Scene(_) => "input",
        }
    }

    /// When it happened (s), where the error knows.
    pub fn time(&self) -> Option<f64> {
        match self {
            RunError::Diverged { t, .. }
            | RunError::NonFinite { t, .. }
            | RunError::Linear { t, .. } => Some(*t),
            RunError::Model(DynamicsError::SingularInverseDynamics { t, .. })
            | RunError::Model(DynamicsError::Kinematics { t, .. })
            | RunError::Model(DynamicsError::Collapse { t, .. }) => Some(*t),
            RunError::Integrator { source, .. } => source.time(),
            _ => None,
        }
    }

    /// The link involved (0-based), where there is one.
    pub fn link(&self) -> Option<usize> {
        match self {
            RunError::Diverged { link, .. } => Some(*link),
            RunError::NonFinite { link, .. } => *link,
            RunError::Model(DynamicsError::Collapse { link, .. }) => Some(link.saturating_sub(1)),
            _ => None,
        }
    }

    /// The collapse, when the run ended with one: time (s), link (0-based), its mid-point
    /// deflection (m) and length (m), and the chords' type-II measure.
    pub fn collapse(&self) -> Option<Collapse> {
        match self {
            RunError::Model(DynamicsError::Collapse {
                t,
                link,
                deflection,
                length,
                type_ii_measure,
            }) => Some(Collapse {
                t: *t,
                link: link.saturating_sub(1),
                deflection: *deflection,
                length: *length,
                type_ii_measure: *type_ii_measure,
            }),
            _ => None,
        }
    }
}

/// A collapse of the mechanism, as [`RunError::collapse`] reports it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Collapse {
    /// Time (s).
    pub t: f64,
    /// Link (0-based).
    pub link: usize,
    /// Its mid-point deflection from the chord (m).
    pub deflection: f64,
    /// Its length (m).
    pub length: f64,
    /// Type-II measure of the chords at `t`.
    pub type_ii_measure: f64,
}

/// A run that stopped early: why, and everything computed up to the last accepted time.
#[derive(Debug)]
pub struct RunFailure {
    /// Why.
    pub error: RunError,
    /// The outputs up to the last accepted time (tables may be empty when nothing was
    /// computed).
    pub partial: Box<RunResult>,
}

impl std::fmt::Display for RunFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.error)
    }
}

impl std::error::Error for RunFailure {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.error)
    }
}

/// A time for a message, with an SI prefix (`25.6 ms`, `333.3 ps`) so that tiny times do not
/// print as long runs of zeros.
fn seconds(t: f64) -> String {
    crate::plot::ticks::value_label(t, "s")
}
