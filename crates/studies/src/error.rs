//! Errors of the studies layer: a bad study file (located), a bad base scene, an input file
//! that is not a regular file of sensible size, a bad case record, a directory that does not
//! fit the request, and I/O.

use std::io::Read as _;
use std::path::Path;

use flexprr_scene::{Location, ScenarioError};
use thiserror::Error;

/// Largest study or base scene file read (bytes). Study and scene files are a few kilobytes;
/// the limit only stops `flexprr study /dev/zero` or a mistyped path to a data file from
/// eating memory.
pub const MAX_INPUT_BYTES: u64 = 4 * 1024 * 1024;

/// Why a study could not be loaded, run or merged. Failures of single cases are not errors:
/// they are recorded in the case's record and row.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum StudyError {
    /// Something is wrong in the study file: `file:line:column: key: message` when the key
    /// can be located, `file: key: message` otherwise.
    #[error("{}{}{message}",
        location.as_ref().map_or_else(|| format!("{file}: "), |l| format!("{l}: ")),
        if key.is_empty() { String::new() } else { format!("{key}: ") })]
    Input {
        /// The study file.
        file: String,
        /// Where in the study file (if it could be located).
        location: Option<Location>,
        /// Dotted study key, e.g. `axis.2.range.count` (empty for syntax errors).
        key: String,
        /// What is wrong and what was expected.
        message: String,
    },
    /// The base scene itself cannot be read or parsed.
    #[error("base scene: {0}")]
    Scene(#[from] ScenarioError),
    /// An input file (study or base scene) that is missing or unreadable, not a regular
    /// file, too large or not UTF-8 text.
    #[error("{path}: {message}")]
    InputFile {
        /// The path as given.
        path: String,
        /// What it is instead, or its size and the limit.
        message: String,
    },
    /// Reading or writing a file.
    #[error("{path}: {source}")]
    Io {
        /// The file or directory involved.
        path: String,
        /// The I/O error.
        source: std::io::Error,
    },
    /// A case record (`cases/<id>.json`) that does not belong to its case: unreadable,
    /// edited parameters, a wrong number of values, a non-finite value, a status without its
    /// failure. Such a record is refused, not re-run: delete the file to run the case again.
    #[error("{path}: {message}; delete the file to run the case again")]
    Record {
        /// The record file.
        path: String,
        /// What does not fit.
        message: String,
    },
    /// An output directory does not fit the request (results of another study, existing
    /// results without `--resume`, shards that do not cover the study, ...).
    #[error("{dir}: {message}")]
    Directory {
        /// The directory involved.
        dir: String,
        /// What is wrong.
        message: String,
    },
    /// A directory given to `merge` is not a study's output, or belongs to another study.
    #[error("{dir}: {message}")]
    MergeInput {
        /// The directory as given.
        dir: String,
        /// What it is instead.
        message: String,
    },
    /// An option that does not fit the study (too many threads, `--resume` of a search).
    #[error("{option}: {message}")]
    Option {
        /// The option, e.g. `--threads`.
        option: String,
        /// What is wrong and what is allowed.
        message: String,
    },
    /// The output directory is refused by the output-directory policy
    /// ([`flexprr_outdir`]), or cannot be written.
    #[error("{0}")]
    Output(#[from] flexprr_outdir::OutputError),
}

impl StudyError {
    /// Whether this is bad input (study file, base scene, input file), as opposed to a
    /// problem with the output directory or the file system.
    pub fn is_input(&self) -> bool {
        matches!(
            self,
            StudyError::Input { .. }
                | StudyError::Scene(_)
                | StudyError::InputFile { .. }
                | StudyError::MergeInput { .. }
                | StudyError::Option { .. }
                | StudyError::Output(flexprr_outdir::OutputError::Refused { .. })
        )
    }

    /// A parse error of the study file itself, as a study error of that file (a scene
    /// error that is not about input stays a scene error).
    pub(crate) fn from_study_parse(file: &str, e: ScenarioError) -> Self {
        match e {
            ScenarioError::Input {
                location,
                key,
                message,
            } => StudyError::Input {
                file: file.to_string(),
                location,
                key,
                message,
            },
            other => StudyError::Scene(other),
        }
    }
}

/// The `Io` error for `path`.
pub(crate) fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> StudyError + '_ {
    move |source| StudyError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// Reads an input file (study or base scene) as UTF-8 text after checking that it is a
/// regular file of at most [`MAX_INPUT_BYTES`]; reads at most one byte more than the limit,
/// so a file that grows while being read cannot exhaust memory either.
///
/// # Errors
/// [`StudyError::InputFile`] for a missing or unreadable file, a directory, device, pipe or
/// socket, a file over the limit, or one that is not UTF-8.
pub fn read_input_file(path: &Path) -> Result<String, StudyError> {
    let refuse = |message: String| StudyError::InputFile {
        path: path.display().to_string(),
        message,
    };
    let unreadable = |e: std::io::Error| refuse(format!("cannot be read: {e}"));
    let meta = std::fs::metadata(path).map_err(unreadable)?;
    let kind = meta.file_type();
    if !kind.is_file() {
        let what = if kind.is_dir() {
            "a directory"
        } else {
            "a device, pipe or socket"
        };
        return Err(refuse(format!(
            "is {what}, not a regular file; give a study or scene file (TOML)"
        )));
    }
    let too_large = |size: u64| {
        refuse(format!(
            "is {size} bytes, more than the {} MiB allowed for a study or scene file",
            MAX_INPUT_BYTES / (1024 * 1024)
        ))
    };
    if meta.len() > MAX_INPUT_BYTES {
        return Err(too_large(meta.len()));
    }
    let file = std::fs::File::open(path).map_err(unreadable)?;
    let mut bytes = Vec::new();
    file.take(MAX_INPUT_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(unreadable)?;
    if bytes.len() as u64 > MAX_INPUT_BYTES {
        return Err(too_large(bytes.len() as u64));
    }
    String::from_utf8(bytes).map_err(|e| refuse(format!("is not UTF-8 text: {e}")))
}
