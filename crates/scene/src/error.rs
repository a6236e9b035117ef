//! Errors of the scenarios layer: bad input (with file, line, column and key) or a failed run.

use std::fmt;

use thiserror::Error;

/// Where in a scene file something is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Location {
    /// File name as given by the user.
    pub file: String,
    /// 1-based line.
    pub line: usize,
    /// 1-based column.
    pub column: usize,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file, self.line, self.column)
    }
}

/// Why a scene could not be loaded or run.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum ScenarioError {
    /// The scene file has a problem: syntax, unknown key, wrong type, value out of range,
    /// trajectory outside the workspace. Exit code 2 in the CLI.
    #[error("{}{}{message}", location.as_ref().map(|l| format!("{l}: ")).unwrap_or_default(), if key.is_empty() { String::new() } else { format!("{key}: ") })]
    Input {
        /// Where (if it could be located).
        location: Option<Location>,
        /// Dotted key path, e.g. `links.section.thickness` (empty for syntax errors).
        key: String,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A file whose content cannot be produced (a figure that cannot be drawn, an archive
    /// over its format's limit, a generated scene that cannot be written back as TOML).
    /// Exit code 1: the work was done, its file was not.
    #[error("{path}: {message}")]
    Write {
        /// The file (its name in the output directory), or what was being written.
        path: String,
        /// Why.
        message: String,
    },
    /// Reading or writing files.
    #[error("{path}: {source}")]
    Io {
        /// The file involved.
        path: String,
        /// The I/O error.
        source: std::io::Error,
    },
}

impl ScenarioError {
    /// Whether this is bad input (as opposed to a run failure).
    pub fn is_input(&self) -> bool {
        matches!(self, ScenarioError::Input { .. })
    }
}

/// A number for a message: as written for ordinary magnitudes (`-400`, `0.003`), with an
/// exponent for tiny and huge ones (`1e-300`, `2.5e200`), never hundreds of digits.
pub(crate) fn number(value: f64) -> String {
    let magnitude = value.abs();
    if value == 0.0 || !value.is_finite() || (1e-4..1e9).contains(&magnitude) {
        format!("{value}")
    } else {
        format!("{value:e}")
    }
}
