//! Placeholder: the Abm method is being written.

use crate::Options;

/// Placeholder for the Abm method.
#[derive(Debug, Clone)]
pub struct Abm {
    /// Shared options.
    pub options: Options,
}
