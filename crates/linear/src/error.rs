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
}
