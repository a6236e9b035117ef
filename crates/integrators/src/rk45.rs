//! Placeholder: the Rk45 method is being written.

use crate::Options;

/// Placeholder for the Rk45 method.
#[derive(Debug, Clone)]
pub struct Rk45 {
    /// Shared options.
    pub options: Options,
}
