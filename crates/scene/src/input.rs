//! Input limits: what a scene, link or study file may be before it is parsed, and what a
//! scene name may be before it becomes a directory.

use std::io::Read;
use std::path::Path;

use crate::error::ScenarioError;

/// Largest input file read (bytes): the shipped scenes are a few kB.
pub const MAX_INPUT_BYTES: u64 = 4 * 1024 * 1024;

/// Largest data file read (bytes): a reference solution or rows of other packages given to
/// `flexprr work-precision` (`--reference`, `--peers`). A reference holds every output time
/// of a run, so it may be far larger than a scene file, but a device or a mistyped path to
/// a huge file must still not be read into memory.
pub const MAX_DATA_BYTES: u64 = 1024 * 1024 * 1024;

/// Checks, from its metadata alone, that `path` is a regular file of at most `max_bytes`:
/// a device (`/dev/zero`), a pipe, a socket or a directory is refused at once, without
/// being opened (opening a pipe would block).
///
/// # Errors
/// [`ScenarioError::Io`] when it does not exist or cannot be examined,
/// [`ScenarioError::Input`] (naming the file) when it is not a regular file or is too large.
pub fn check_input_file(path: &Path, max_bytes: u64) -> Result<(), ScenarioError> {
    let shown = path.display().to_string();
    let meta = std::fs::metadata(path).map_err(|source| ScenarioError::Io {
        path: shown.clone(),
        source,
    })?;
    let refuse = |message: String| ScenarioError::Input {
        location: None,
        key: String::new(),
        message: format!("{shown}: {message}"),
    };
    if !meta.is_file() {
        let what = if meta.is_dir() {
            "a directory"
        } else {
            "not a regular file (a device, pipe or socket)"
        };
        return Err(refuse(format!("is {what}; expected a file")));
    }
    if meta.len() > max_bytes {
        return Err(refuse(format!(
            "is {} bytes, more than the {} MiB allowed",
            meta.len(),
            max_bytes / (1024 * 1024)
        )));
    }
    Ok(())
}

/// Longest scene name (characters).
pub const MAX_NAME_LEN: usize = 100;

/// Reads a TOML input file: it must be a regular file of at most [`MAX_INPUT_BYTES`] in
/// UTF-8. A device (`/dev/zero`), a directory or a pipe is refused at once instead of read
/// without end.
///
/// # Errors
/// [`ScenarioError::Io`] when it cannot be opened or read, [`ScenarioError::Input`] (naming
/// the file) when it is not a regular file, too large or not UTF-8.
pub fn read_input_file(path: &Path) -> Result<String, ScenarioError> {
    let shown = path.display().to_string();
    let io = |source| ScenarioError::Io {
        path: shown.clone(),
        source,
    };
    let refuse = |message: String| ScenarioError::Input {
        location: None,
        key: String::new(),
        message: format!("{shown}: {message}"),
    };
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        let what = if meta.is_dir() {
            "a directory"
        } else {
            "not a regular file (a device, pipe or socket)"
        };
        return Err(refuse(format!(
            "is {what}; expected a TOML file of at most {} MiB",
            MAX_INPUT_BYTES / (1024 * 1024)
        )));
    }
    let too_large = |size: u64| {
        refuse(format!(
            "is {size} bytes, more than the {} MiB an input file may have",
            MAX_INPUT_BYTES / (1024 * 1024)
        ))
    };
    if meta.len() > MAX_INPUT_BYTES {
        return Err(too_large(meta.len()));
    }
    // Read at most one byte past the limit, in case the file grew after the check.
    let file = std::fs::File::open(path).map_err(io)?;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(MAX_INPUT_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > MAX_INPUT_BYTES {
        return Err(too_large(bytes.len() as u64));
    }
    String::from_utf8(bytes).map_err(|e| {
        refuse(format!(
            "is not UTF-8 text (invalid byte at offset {})",
            e.utf8_error().valid_up_to()
        ))
    })
}

/// Why `name` is not a safe scene name (it names the default output directory `out/<name>`):
/// non-empty, at most [`MAX_NAME_LEN`] characters of `A-Z a-z 0-9 . _ -`, not starting with
/// `.`. `None` when it is safe.
pub fn unsafe_name_reason(name: &str) -> Option<String> {
    if name.is_empty() {
        return Some("is empty".to_string());
    }
    if name.chars().count() > MAX_NAME_LEN {
        return Some(format!(
            "has {} characters, more than {MAX_NAME_LEN}",
            name.chars().count()
        ));
    }
    if name.starts_with('.') {
        return Some("starts with '.' (a hidden or parent directory)".to_string());
    }
    if let Some(c) = name
        .chars()
        .find(|c| !(c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-')))
    {
        return Some(format!("contains {c:?}"));
    }
    None
}

/// A safe name from a file stem: characters outside the safe set become `_`, leading dots
/// are dropped, the length is cut to [`MAX_NAME_LEN`]; empty gives `scene`.
pub fn sanitize_name(stem: &str) -> String {
    let cleaned: String = stem
        .trim_start_matches('.')
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-') {
                c
            } else {
                '_'
            }
        })
        .take(MAX_NAME_LEN)
        .collect();
    if cleaned.is_empty() {
        "scene".to_string()
    } else {
        cleaned
    }
}

/// What kind of flexprr input a TOML text looks like, from its top-level keys (for a
/// helpful message when a file is given to the wrong command).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputKind {
    /// A scene (`trajectory` and `time` tables): `flexprr run` / `check`.
    Scene,
    /// A study (`base` scene and `[[axis]]` tables): `flexprr study`.
    Study,
    /// A single-link file (`length`, `material`, `load` or `coupling` at the top, no
    /// `trajectory`): `flexprr beam`.
    Link,
    /// Not recognised (or not TOML).
    Unknown,
}

impl InputKind {
    /// Guesses the kind of `text` from its top-level keys.
    pub fn of(text: &str) -> Self {
        let Ok(root) = toml::de::DeTable::parse(text) else {
            return InputKind::Unknown;
        };
        let root = root.get_ref();
        let has = |k: &str| root.iter().any(|(key, _)| key.get_ref().as_ref() == k);
        if has("trajectory") || has("time") {
            InputKind::Scene
        } else if has("base") || has("axis") || has("quantities") {
            InputKind::Study
        } else if has("length") && (has("material") || has("section") || has("load")) {
            InputKind::Link
        } else {
            InputKind::Unknown
        }
    }
}
