//! Placeholder: the Bdf method is being written.

use crate::Options;

/// Placeholder for the Bdf method.
#[derive(Debug, Clone)]
pub struct Bdf {
    /// Shared options.
    pub options: Options,
}
