//! Errors of the linear-model layer.

use flexprr_dynamics::DynamicsError;
use thiserror::Error;

/// What went wrong building or using a linear model.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum LinearError {
    /// The model failed at or near the operating point.
    #[error(transparent)]
    Model(#[from] DynamicsError),
    /// A bad input or output name, or one the model cannot give.
    #[error("{0}")]
    Channel(String),
    /// The eigenvalue problem or a frequency-response solve failed.
    #[error("{0}")]
    Numerics(String),
    /// The dense linear analysis of this state would exceed the memory bound
    /// ([`crate::cost`]).
    #[error(
        "a dense linear model of this scene has a state of {state}: estimated {memory_gb:.1} GB of \
         memory and {seconds:.0} s for its modes, above the bound of {limit_gb:.1} GB \
         (docs/linear.md, \"Cost\"); use fewer elements per link (model.elements) or modes"
    )]
    TooLarge {
        /// The state's length.
        state: usize,
        /// Estimated peak memory (GB).
        memory_gb: f64,
        /// Estimated time of the eigenvalues (s).
        seconds: f64,
        /// The bound (GB).
        limit_gb: f64,
    },
}

impl From<flexprr_dynamics::channel::ChannelError> for LinearError {
    fn from(e: flexprr_dynamics::channel::ChannelError) -> Self {
        LinearError::Channel(e.0)
    }
}
