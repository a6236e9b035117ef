//! One policy for every output directory flexprr writes (`flexprr run`, `study`, `merge`,
//! `work-precision`, with the viewer and figure files among their outputs) and for a single
//! output file (`flexprr kinematics --out`). `docs/scenes.md`, "Output directory", states
//! the rules for users; this module is the only place that applies them.
//!
//! - **Ours or not.** A directory flexprr wrote holds a marker, [`MARKER`]: a small JSON file
//!   with the kind of output (`run`, `study`, `work-precision`) and the names of the files
//!   it wrote. A directory written before the marker existed is recognised by its own
//!   manifest (`summary.json` of a run, `study.json` of a study). Anything else that is not
//!   empty is *foreign*.
//! - **Foreign directories** are refused unless the caller forces it; forced, flexprr writes
//!   next to their files and still never overwrites or deletes a file it did not write: a
//!   foreign file with the name of an output is refused before any work.
//! - **Inputs are never touched**: an output directory that is an input, or an input with
//!   the name of an output in the directory, is refused; a directory that holds an input is
//!   never replaced whole.
//! - **Atomic publish.** A command that writes its directory at the end stages the files in
//!   a hidden directory and renames it into place; a previous output of the same kind is
//!   swapped out and removed when it holds nothing but its own files. A directory that
//!   cannot be renamed (`.`, the current directory, a mount point, a symbolic link) or that
//!   holds other files is updated in place: each file is renamed in, and the files of the
//!   previous output that the new one does not have are removed (they are ours).
//! - `/` is refused, whatever the options.
//!
//! ```no_run
//! use std::borrow::Cow;
//! use flexprr_outdir::{OutputDir, Products};
//! # fn main() -> Result<(), flexprr_outdir::OutputError> {
//! const PRODUCTS: Products = Products {
//!     kind: "example",
//!     names: Cow::Borrowed(&["table.csv"]),
//!     patterns: Cow::Borrowed(&[]),
//!     legacy: None,
//! };
//! let input = std::path::Path::new("scene.toml");
//! let dir = OutputDir::check(std::path::Path::new("out/x"), PRODUCTS, false, &[input], &[])?;
//! let staging = dir.stage()?;
//! std::fs::write(staging.path().join("table.csv"), "t_s\n0\n")
//!     .map_err(|e| flexprr_outdir::OutputError::io(staging.path(), e))?;
//! staging.publish()?;
//! # Ok(())
//! # }
//! ```

use std::borrow::Cow;
use std::collections::BTreeSet;
use std::io::Read as _;
use std::path::{Component, Path, PathBuf};

use serde_json::{Value, json};
use thiserror::Error;

/// The marker of a directory flexprr wrote: `{"kind", "flexprr_version", "files"}`.
pub const MARKER: &str = ".flexprr-output.json";

/// Hidden working entries of flexprr (staging directories, temporary files) start with
/// this; they are ours wherever they are.
const WORKING_PREFIX: &str = ".flexprr-";

/// Largest marker read (bytes): it lists file names only.
const MAX_MARKER_BYTES: u64 = 1024 * 1024;

/// Largest old manifest (`summary.json`, `study.json`) read to recognise an output written
/// before markers existed (bytes).
const MAX_LEGACY_BYTES: u64 = 64 * 1024 * 1024;

/// Why an output directory or file was refused or could not be written.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum OutputError {
    /// The target is not usable for this command: `/`, a file, a foreign directory without
    /// force, a clash with an input or a foreign file. Bad input (exit code 2 in the CLI).
    #[error("{}: {message}", path.display())]
    Refused {
        /// The directory or file as given.
        path: PathBuf,
        /// What is wrong and what to do.
        message: String,
    },
    /// Reading or writing failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or directory involved.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
}

impl OutputError {
    /// The [`OutputError::Io`] of `path`.
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        OutputError::Io {
            path: path.to_path_buf(),
            source,
        }
    }

    fn refused(path: &Path, message: impl Into<String>) -> Self {
        OutputError::Refused {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
}

impl From<OutputError> for flexprr_scene::ScenarioError {
    fn from(e: OutputError) -> Self {
        match e {
            OutputError::Refused { .. } => flexprr_scene::ScenarioError::Input {
                location: None,
                key: "--out".to_string(),
                message: e.to_string(),
            },
            OutputError::Io { path, source } => flexprr_scene::ScenarioError::Io {
                path: path.display().to_string(),
                source,
            },
        }
    }
}

/// How a directory written before markers existed is recognised: a file of that output
/// kind that flexprr always wrote, and what its text must hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Legacy {
    /// A JSON object with this key in `file`.
    JsonKey {
        /// The file.
        file: &'static str,
        /// A key of its top-level object.
        key: &'static str,
    },
    /// `file` starts with this text.
    Prefix {
        /// The file.
        file: &'static str,
        /// Its first characters.
        text: &'static str,
    },
}

/// The files a kind of output consists of: what it may write, so that a foreign file with
/// such a name is refused before any work, and how an old directory of its kind looks.
#[derive(Debug, Clone)]
pub struct Products {
    /// Kind written to the marker (`run`, `study`, `work-precision`); a directory of another
    /// kind is refused.
    pub kind: &'static str,
    /// Exact file (or directory) names (borrowed for a fixed list, owned for one made from
    /// plug-ins).
    pub names: Cow<'static, [&'static str]>,
    /// `(prefix, suffix)` patterns of names, e.g. `("deflections_xi", ".svg")`.
    pub patterns: Cow<'static, [(&'static str, &'static str)]>,
    /// How an output of this kind written before markers existed is recognised.
    pub legacy: Option<Legacy>,
}

impl Products {
    /// Whether `name` can be one of these outputs.
    pub fn is_product(&self, name: &str) -> bool {
        self.names.contains(&name)
            || self.patterns.iter().any(|(p, s)| {
                name.len() >= p.len() + s.len() && name.starts_with(p) && name.ends_with(s)
            })
    }

    /// Whether `dir` is an output of this kind written before markers existed.
    fn recognises_legacy(&self, dir: &Path) -> bool {
        match self.legacy {
            None => false,
            Some(Legacy::JsonKey { file, key }) => read_small(&dir.join(file), MAX_LEGACY_BYTES)
                .and_then(|t| serde_json::from_str::<Value>(&t).ok())
                .is_some_and(|v| v.get(key).is_some()),
            Some(Legacy::Prefix { file, text }) => {
                read_head(&dir.join(file), text.len()).is_some_and(|t| t.starts_with(text))
            }
        }
    }
}

/// The products of `flexprr work-precision` (written by `flexprr_bench`).
pub const WORK_PRECISION: Products = Products {
    kind: "work-precision",
    names: Cow::Borrowed(&[
        "work_precision.csv",
        "work_precision.svg",
        "work_precision.md",
        "reference.csv",
    ]),
    patterns: Cow::Borrowed(&[]),
    legacy: Some(Legacy::Prefix {
        file: "work_precision.md",
        text: "# Work-precision:",
    }),
};

/// The products of `flexprr frf` (`flexprr_linear_tools::frf`; the mode shapes with `--identify`).
pub const FRF: Products = Products {
    kind: "frf",
    names: Cow::Borrowed(&[
        "frf.csv",
        "frf.json",
        "bode.svg",
        "mode_shapes.csv",
        "mode_shapes.svg",
    ]),
    patterns: Cow::Borrowed(&[]),
    legacy: None,
};

/// The products of `flexprr statespace` (`flexprr_linear_tools::statespace`).
pub const STATESPACE: Products = Products {
    kind: "statespace",
    names: Cow::Borrowed(&["statespace.npz", "statespace.json"]),
    patterns: Cow::Borrowed(&[]),
    legacy: None,
};

/// What an existing target holds.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Contents {
    /// Nothing there yet.
    Absent,
    /// An empty directory (flexprr's hidden working entries aside).
    Empty,
    /// An output of this kind: the files it wrote, and the other entries.
    Ours {
        owned: BTreeSet<String>,
        other: BTreeSet<String>,
    },
    /// A non-empty directory flexprr did not write.
    Foreign { entries: BTreeSet<String> },
}

impl Contents {
    fn owned(&self) -> BTreeSet<String> {
        match self {
            Contents::Ours { owned, .. } => owned.clone(),
            _ => BTreeSet::new(),
        }
    }

    fn others(&self) -> BTreeSet<String> {
        match self {
            Contents::Ours { other, .. } => other.clone(),
            Contents::Foreign { entries } => entries.clone(),
            _ => BTreeSet::new(),
        }
    }
}

/// An output directory checked for one command: where it is, what it holds and how it can
/// be written. Made by [`OutputDir::check`], before any work, so that a refusal costs
/// nothing.
#[derive(Debug, Clone)]
pub struct OutputDir {
    path: PathBuf,
    real: PathBuf,
    products: Products,
    expected: BTreeSet<String>,
    inputs: Vec<PathBuf>,
    renamable: bool,
}

impl OutputDir {
    /// Checks `path` as the output directory of a command writing `products` (plus the
    /// `expected` names it knows it will write, such as a study's plot files), with the
    /// command's `inputs` (files or directories it reads).
    ///
    /// # Errors
    /// [`OutputError::Refused`] for an empty path, `/`, something that is not a directory,
    /// a directory that is an input, an output of another kind, a foreign non-empty
    /// directory without `force`, and a foreign file or an input with the name of an
    /// output; [`OutputError::Io`] when it cannot be read.
    pub fn check(
        path: &Path,
        products: Products,
        force: bool,
        inputs: &[&Path],
        expected: &[&str],
    ) -> Result<Self, OutputError> {
        if path.as_os_str().is_empty() {
            return Err(OutputError::refused(
                path,
                "an empty path: give an output directory",
            ));
        }
        let real = resolve(path).map_err(|e| OutputError::io(path, e))?;
        if real.parent().is_none() {
            return Err(OutputError::refused(
                path,
                "is the root directory: give a directory of its own for the outputs",
            ));
        }
        let inputs: Vec<PathBuf> = inputs
            .iter()
            .filter_map(|p| std::fs::canonicalize(p).ok())
            .collect();
        if let Some(input) = inputs.iter().find(|i| **i == real) {
            return Err(OutputError::refused(
                path,
                format!(
                    "is also an input of the command ({}); choose another output directory",
                    input.display()
                ),
            ));
        }
        let (contents, is_link) = inspect(path, &products)?;
        if contents == Contents::Absent {
            if let Some(blocker) = real
                .ancestors()
                .skip(1)
                .find(|a| a.exists())
                .filter(|a| !a.is_dir())
            {
                return Err(OutputError::refused(
                    path,
                    format!(
                        "cannot be created: {} is not a directory",
                        blocker.display()
                    ),
                ));
            }
        }
        let dir = OutputDir {
            path: path.to_path_buf(),
            renamable: !is_link && renamable(path, &real, &inputs),
            real,
            products,
            expected: expected.iter().map(|s| s.to_string()).collect(),
            inputs,
        };
        if let Contents::Foreign { entries } = &contents {
            if !force {
                return Err(OutputError::refused(
                    path,
                    format!(
                        "is a non-empty directory that flexprr did not write (no {MARKER}; it \
                         holds {}); choose another output directory, or pass --force to write \
                         next to its files (flexprr never overwrites or deletes a file it did \
                         not write)",
                        list(entries, 3)
                    ),
                ));
            }
        }
        dir.check_names(&contents, None)?;
        Ok(dir)
    }

    /// The directory as given.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Refuses writing `names` (or, before the work, every name these products may have)
    /// over a file flexprr did not write, or over an input.
    fn check_names(
        &self,
        contents: &Contents,
        names: Option<&[String]>,
    ) -> Result<(), OutputError> {
        let owned = contents.owned();
        let is_ours = |name: &str| match names {
            Some(names) => names.iter().any(|n| n == name),
            None => self.products.is_product(name) || self.expected.contains(name),
        };
        for input in &self.inputs {
            let name = input.file_name().map(|n| n.to_string_lossy().into_owned());
            if input.parent() == Some(self.real.as_path()) && name.as_deref().is_some_and(is_ours) {
                return Err(OutputError::refused(
                    &self.path,
                    format!(
                        "the input {} has the name of an output this command writes there; \
                         move it or choose another output directory",
                        input.display()
                    ),
                ));
            }
        }
        let clashes: BTreeSet<String> = contents
            .others()
            .into_iter()
            .filter(|n| is_ours(n) && !owned.contains(n))
            .collect();
        if !clashes.is_empty() {
            return Err(OutputError::refused(
                &self.path,
                format!(
                    "holds {}, not written by flexprr, with the name of an output of this \
                     command; move it away or choose another output directory",
                    list(&clashes, 5)
                ),
            ));
        }
        Ok(())
    }

    /// A fresh staging directory for a command that writes its whole output at the end:
    /// fill [`Staging::path`], then [`Staging::publish`]. It is removed if dropped before.
    ///
    /// # Errors
    /// [`OutputError::Io`] when it cannot be created (a read-only place, a missing
    /// permission): call this before the work to learn it early.
    pub fn stage(&self) -> Result<Staging, OutputError> {
        let pid = std::process::id();
        let path = if self.renamable {
            let parent = self.real.parent().unwrap_or(Path::new("/"));
            std::fs::create_dir_all(parent).map_err(|e| OutputError::io(parent, e))?;
            let name = self
                .real
                .file_name()
                .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
            remove_abandoned_staging(parent, &name);
            parent.join(format!("{WORKING_PREFIX}staging-{pid}-{name}"))
        } else {
            std::fs::create_dir_all(&self.real).map_err(|e| OutputError::io(&self.path, e))?;
            remove_abandoned_staging(&self.real, "");
            self.real.join(format!("{WORKING_PREFIX}staging-{pid}"))
        };
        if path.exists() {
            std::fs::remove_dir_all(&path).map_err(|e| OutputError::io(&path, e))?;
        }
        std::fs::create_dir(&path).map_err(|e| OutputError::io(&path, e))?;
        Ok(Staging {
            dir: self.clone(),
            inside: !self.renamable,
            path,
        })
    }

    /// Creates and removes a staging directory: a command calls this before its work, so
    /// that an output place it cannot write to (read-only, no permission) is reported at
    /// once rather than after the work.
    ///
    /// # Errors
    /// As [`OutputDir::stage`].
    pub fn check_writable(&self) -> Result<(), OutputError> {
        self.stage().map(drop)
    }

    /// Opens the directory for a command that writes its files one by one (a study: case
    /// records as they finish): creates it and writes the marker, listing what it already
    /// owned and every name expected. Files are then written into the directory returned
    /// (the path as given, or its resolved form when it goes through `..`).
    ///
    /// # Errors
    /// [`OutputError::Io`] when the directory or the marker cannot be written.
    pub fn open(&self) -> Result<PathBuf, OutputError> {
        std::fs::create_dir_all(&self.real).map_err(|e| OutputError::io(&self.path, e))?;
        let (contents, _) = inspect(&self.real, &self.products)?;
        let mut owned = contents.owned();
        owned.extend(
            self.expected
                .iter()
                .cloned()
                .chain(self.products.names.iter().map(|s| s.to_string())),
        );
        write_marker(&self.real, self.products.kind, &owned)?;
        // A `..` after a part that did not exist would create that part when written
        // through: write through the resolved path then.
        let through_parent = self
            .path
            .components()
            .any(|c| matches!(c, Component::ParentDir));
        Ok(if through_parent {
            self.real.clone()
        } else {
            self.path.clone()
        })
    }
}

/// A staging directory (see [`OutputDir::stage`]).
#[derive(Debug)]
pub struct Staging {
    dir: OutputDir,
    path: PathBuf,
    /// The staging directory is inside the target (which cannot be renamed).
    inside: bool,
}

impl Staging {
    /// Where to write the files.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Moves the staged files into the output directory: by renaming the whole staging
    /// directory when the target is absent, or is an output of its kind holding only its
    /// own files (that output is then removed), otherwise file by file, removing the files
    /// of the previous output that this one does not have. Returns the names written.
    ///
    /// # Errors
    /// [`OutputError::Refused`] when a staged name would replace a file flexprr did not
    /// write, or an input; [`OutputError::Io`] when a rename fails.
    pub fn publish(self) -> Result<Vec<String>, OutputError> {
        let names = entry_names(&self.path)?;
        // Read again: the directory may have changed during the work.
        let (contents, _) = inspect(&self.dir.real, &self.dir.products)?;
        self.dir.check_names(&contents, Some(&names))?;
        if !self.inside {
            let whole = match &contents {
                Contents::Absent | Contents::Empty => true,
                Contents::Ours { other, .. } => other.is_empty(),
                Contents::Foreign { .. } => false,
            };
            if whole {
                write_marker(
                    &self.path,
                    self.dir.products.kind,
                    &names.iter().cloned().collect(),
                )?;
                if self.swap_in(&contents)? {
                    return Ok(names);
                }
            }
        }
        self.move_in(&names, &contents)?;
        Ok(names)
    }

    /// Renames the staging directory to the target, swapping out an old output; `false`
    /// when the target cannot be renamed (then nothing changed).
    fn swap_in(&self, contents: &Contents) -> Result<bool, OutputError> {
        let target = &self.dir.real;
        if *contents == Contents::Absent {
            return Ok(std::fs::rename(&self.path, target).is_ok());
        }
        let old = self
            .path
            .with_file_name(format!("{WORKING_PREFIX}old-{}", std::process::id()));
        if std::fs::rename(target, &old).is_err() {
            return Ok(false);
        }
        if let Err(e) = std::fs::rename(&self.path, target) {
            let _ = std::fs::rename(&old, target);
            return Err(OutputError::io(target, e));
        }
        std::fs::remove_dir_all(&old).map_err(|e| OutputError::io(&old, e))?;
        Ok(true)
    }

    /// Moves the staged files in one by one; removes the previous output's files that are
    /// not replaced (never an input).
    fn move_in(&self, names: &[String], contents: &Contents) -> Result<(), OutputError> {
        let target = &self.dir.real;
        std::fs::create_dir_all(target).map_err(|e| OutputError::io(target, e))?;
        let owned = contents.owned();
        let kind = self.dir.products.kind;
        let mut all = owned.clone();
        all.extend(names.iter().cloned());
        write_marker(target, kind, &all)?;
        for name in names {
            let (from, to) = (self.path.join(name), target.join(name));
            if to.is_dir() && !to.is_symlink() {
                std::fs::remove_dir_all(&to).map_err(|e| OutputError::io(&to, e))?;
            }
            move_entry(&from, &to)?;
        }
        for stale in owned.iter().filter(|n| !names.contains(n)) {
            let path = target.join(stale);
            let real = std::fs::canonicalize(&path).ok();
            if real.is_some_and(|r| self.dir.inputs.iter().any(|i| i.starts_with(&r))) {
                continue;
            }
            let _ = if path.is_dir() && !path.is_symlink() {
                std::fs::remove_dir_all(&path)
            } else {
                std::fs::remove_file(&path)
            };
        }
        write_marker(target, kind, &names.iter().cloned().collect())?;
        Ok(())
    }
}

impl Drop for Staging {
    /// Removes what is left of the staging directory: all of it when the work failed,
    /// nothing (it was renamed) or an empty directory after a publish.
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.path);
    }
}

/// Removes the staging directories for `name` in `parent` (beside the output, or with an
/// empty `name` inside it) left by flexprr processes that no longer run (killed during their
/// work), so that they do not pile up. Only on systems with `/proc`; elsewhere they stay,
/// hidden.
fn remove_abandoned_staging(parent: &Path, name: &str) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    let prefix = format!("{WORKING_PREFIX}staging-");
    let suffix = if name.is_empty() {
        String::new()
    } else {
        format!("-{name}")
    };
    for entry in entries.filter_map(Result::ok) {
        let file = entry.file_name().to_string_lossy().into_owned();
        let pid = file
            .strip_prefix(&prefix)
            .and_then(|rest| rest.strip_suffix(&suffix))
            .and_then(|pid| pid.parse::<u32>().ok());
        if let Some(pid) = pid {
            if pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists() {
                let _ = std::fs::remove_dir_all(entry.path());
            }
        }
    }
}

/// Renames `from` to `to`; across file systems, copies and removes instead.
fn move_entry(from: &Path, to: &Path) -> Result<(), OutputError> {
    if std::fs::rename(from, to).is_ok() {
        return Ok(());
    }
    if from.is_dir() {
        copy_dir(from, to)?;
        std::fs::remove_dir_all(from).map_err(|e| OutputError::io(from, e))
    } else {
        let tmp = temporary(to);
        std::fs::copy(from, &tmp).map_err(|e| OutputError::io(to, e))?;
        std::fs::rename(&tmp, to).map_err(|e| OutputError::io(to, e))?;
        std::fs::remove_file(from).map_err(|e| OutputError::io(from, e))
    }
}

fn copy_dir(from: &Path, to: &Path) -> Result<(), OutputError> {
    std::fs::create_dir_all(to).map_err(|e| OutputError::io(to, e))?;
    for entry in std::fs::read_dir(from).map_err(|e| OutputError::io(from, e))? {
        let entry = entry.map_err(|e| OutputError::io(from, e))?;
        let (src, dst) = (entry.path(), to.join(entry.file_name()));
        if src.is_dir() {
            copy_dir(&src, &dst)?;
        } else {
            std::fs::copy(&src, &dst).map_err(|e| OutputError::io(&dst, e))?;
        }
    }
    Ok(())
}

/// A hidden temporary name beside `path`, in flexprr's working namespace.
fn temporary(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(|| "file".into(), |n| n.to_string_lossy().into_owned());
    path.with_file_name(format!("{WORKING_PREFIX}tmp-{}-{name}", std::process::id()))
}

/// Writes `bytes` to `path` through a temporary file in the same directory and a rename,
/// so that the file is never seen half-written.
///
/// # Errors
/// [`OutputError::Io`] when either step fails (the temporary file is then removed).
pub fn write_file_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let tmp = temporary(path);
    let outcome = std::fs::write(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, path));
    outcome.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        OutputError::io(path, e)
    })
}

fn write_marker(dir: &Path, kind: &str, files: &BTreeSet<String>) -> Result<(), OutputError> {
    let marker = json!({
        "kind": kind,
        "flexprr_version": env!("CARGO_PKG_VERSION"),
        "files": files,
    });
    let text = serde_json::to_string_pretty(&marker).unwrap_or_default();
    write_file_atomic(&dir.join(MARKER), text.as_bytes())
}

/// The names in a staging directory.
fn entry_names(dir: &Path) -> Result<Vec<String>, OutputError> {
    let mut names = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(|e| OutputError::io(dir, e))? {
        let entry = entry.map_err(|e| OutputError::io(dir, e))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if name != MARKER {
            names.push(name);
        }
    }
    names.sort();
    Ok(names)
}

/// Reads a regular file of at most `max` bytes as text; `None` otherwise (a device or a
/// pipe is never opened).
fn read_small(path: &Path, max: u64) -> Option<String> {
    let meta = std::fs::metadata(path).ok()?;
    if !meta.is_file() || meta.len() > max {
        return None;
    }
    let mut text = String::new();
    std::fs::File::open(path)
        .ok()?
        .take(max)
        .read_to_string(&mut text)
        .ok()?;
    Some(text)
}

/// The first `n` bytes of a regular file as text (lossy); `None` for anything else.
fn read_head(path: &Path, n: usize) -> Option<String> {
    if !std::fs::metadata(path).ok()?.is_file() {
        return None;
    }
    let mut bytes = Vec::with_capacity(n);
    std::fs::File::open(path)
        .ok()?
        .take(n as u64)
        .read_to_end(&mut bytes)
        .ok()?;
    Some(String::from_utf8_lossy(&bytes).into_owned())
}

/// What `path` holds, and whether it is a symbolic link.
fn inspect(path: &Path, products: &Products) -> Result<(Contents, bool), OutputError> {
    let link = match std::fs::symlink_metadata(path) {
        Err(e)
            if matches!(
                e.kind(),
                std::io::ErrorKind::NotFound | std::io::ErrorKind::NotADirectory
            ) =>
        {
            return Ok((Contents::Absent, false));
        }
        Err(e) => return Err(OutputError::io(path, e)),
        Ok(m) => m.file_type().is_symlink(),
    };
    let meta = std::fs::metadata(path)
        .map_err(|_| OutputError::refused(path, "is a broken symbolic link"))?;
    if !meta.is_dir() {
        return Err(OutputError::refused(
            path,
            "exists and is not a directory; give a directory for the outputs",
        ));
    }
    let mut entries = BTreeSet::new();
    for entry in std::fs::read_dir(path).map_err(|e| OutputError::io(path, e))? {
        let name = entry
            .map_err(|e| OutputError::io(path, e))?
            .file_name()
            .to_string_lossy()
            .into_owned();
        if name == MARKER || !name.starts_with(WORKING_PREFIX) {
            entries.insert(name);
        }
    }
    if entries.remove(MARKER) {
        let marker = read_small(&path.join(MARKER), MAX_MARKER_BYTES)
            .and_then(|t| serde_json::from_str::<Value>(&t).ok());
        let kind = marker
            .as_ref()
            .and_then(|m| m.get("kind")?.as_str().map(String::from));
        let files: Option<BTreeSet<String>> = marker
            .as_ref()
            .and_then(|m| serde_json::from_value(m.get("files")?.clone()).ok());
        match (kind, files) {
            (Some(kind), Some(files)) if kind == products.kind => {
                let other = entries
                    .iter()
                    .filter(|n| !files.contains(*n))
                    .cloned()
                    .collect();
                return Ok((
                    Contents::Ours {
                        owned: files,
                        other,
                    },
                    link,
                ));
            }
            (Some(kind), Some(_)) => {
                return Err(OutputError::refused(
                    path,
                    format!(
                        "holds the output of `flexprr {kind}`, not of this command; choose \
                         another output directory"
                    ),
                ));
            }
            _ => {
                // An unreadable marker proves nothing: the directory counts as foreign.
                entries.insert(MARKER.to_string());
                return Ok((Contents::Foreign { entries }, link));
            }
        }
    }
    if entries.is_empty() {
        return Ok((Contents::Empty, link));
    }
    // Outputs of other flexprr commands inside (`out/<scene>/work_precision` next to a run's
    // files) are not foreign: they are left alone, like any file that is not ours.
    if entries.iter().all(|n| path.join(n).join(MARKER).is_file()) {
        return Ok((
            Contents::Ours {
                owned: BTreeSet::new(),
                other: entries,
            },
            link,
        ));
    }
    if products.recognises_legacy(path) {
        let (owned, other) = entries.into_iter().partition(|n| products.is_product(n));
        return Ok((Contents::Ours { owned, other }, link));
    }
    Ok((Contents::Foreign { entries }, link))
}

/// Whether the directory `path` (absolute form `real`) can be replaced by a rename: not
/// `.` or `..`, not the current directory or one holding it, not a mount point, and
/// holding no input.
fn renamable(path: &Path, real: &Path, inputs: &[PathBuf]) -> bool {
    let last = path.components().next_back();
    if matches!(last, Some(Component::CurDir | Component::ParentDir) | None) {
        return false;
    }
    if std::env::current_dir()
        .and_then(std::fs::canonicalize)
        .is_ok_and(|cwd| cwd.starts_with(real))
    {
        return false;
    }
    if inputs.iter().any(|i| i.starts_with(real)) {
        return false;
    }
    !is_mount_point(real)
}

#[cfg(unix)]
fn is_mount_point(dir: &Path) -> bool {
    use std::os::unix::fs::MetadataExt as _;
    let (Ok(m), Some(parent)) = (std::fs::metadata(dir), dir.parent()) else {
        return false;
    };
    std::fs::metadata(parent).is_ok_and(|p| p.dev() != m.dev())
}

#[cfg(not(unix))]
fn is_mount_point(_dir: &Path) -> bool {
    false
}

/// The absolute path of `path` with every existing part's symbolic links resolved; the
/// parts that do not exist yet are appended as written (`.` dropped, `..` going up).
fn resolve(path: &Path) -> std::io::Result<PathBuf> {
    let absolute = if path.is_absolute() {
        path.to_path_buf()
    } else {
        std::env::current_dir()?.join(path)
    };
    let parts: Vec<Component<'_>> = absolute.components().collect();
    for k in (1..=parts.len()).rev() {
        let prefix: PathBuf = parts[..k].iter().collect();
        if let Ok(mut real) = std::fs::canonicalize(&prefix) {
            for part in &parts[k..] {
                match part {
                    Component::ParentDir => {
                        real.pop();
                    }
                    Component::Normal(n) => real.push(n),
                    _ => {}
                }
            }
            return Ok(real);
        }
    }
    Ok(absolute)
}

/// At most `n` names, then how many more.
fn list(names: &BTreeSet<String>, n: usize) -> String {
    let shown: Vec<&str> = names.iter().take(n).map(String::as_str).collect();
    let more = names.len().saturating_sub(n);
    if more == 0 {
        shown.join(", ")
    } else {
        format!("{} and {more} more", shown.join(", "))
    }
}

/// Checks `path` as a single output file (`flexprr kinematics --out`): never an input,
/// never a directory, device or pipe; an existing file is replaced only when `is_ours`
/// recognises its first bytes as this command's output, or with `force`. Returns the path
/// to write (a symbolic link resolved to its file).
///
/// # Errors
/// [`OutputError::Refused`] with what is wrong and what to do.
pub fn check_output_file(
    path: &Path,
    force: bool,
    inputs: &[&Path],
    is_ours: fn(&str) -> bool,
) -> Result<PathBuf, OutputError> {
    if path.as_os_str().is_empty() || path.file_name().is_none() {
        return Err(OutputError::refused(path, "is not a file name"));
    }
    let real = resolve(path).map_err(|e| OutputError::io(path, e))?;
    let inputs: Vec<PathBuf> = inputs
        .iter()
        .filter_map(|p| std::fs::canonicalize(p).ok())
        .collect();
    if inputs.contains(&real) {
        return Err(OutputError::refused(
            path,
            "is an input of the command: it is never overwritten; choose another output file",
        ));
    }
    match std::fs::metadata(&real) {
        Err(_) => match real.ancestors().skip(1).find(|a| a.exists()) {
            Some(blocker) if !blocker.is_dir() => Err(OutputError::refused(
                path,
                format!(
                    "cannot be created: {} is not a directory",
                    blocker.display()
                ),
            )),
            _ => Ok(real),
        },
        Ok(m) if m.is_dir() => Err(OutputError::refused(
            path,
            "is a directory; give a file name for the output",
        )),
        Ok(m) if !m.is_file() => Err(OutputError::refused(
            path,
            "is not a regular file (a device, pipe or socket); to write to standard output, \
             leave out --out",
        )),
        Ok(_) => {
            if force || read_head(&real, 4096).is_some_and(|head| is_ours(&head)) {
                Ok(real)
            } else {
                Err(OutputError::refused(
                    path,
                    "exists and is not an output of this command; choose another file, or \
                     pass --force to replace it",
                ))
            }
        }
    }
}
