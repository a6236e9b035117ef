//! Batch studies: a base scene, sweep axes over any scene key, derived quantities per case,
//! run in parallel, shardable across machines and resumable (`docs/studies.md`).
//!
//! A study file names a base scene (`base = "paper_f20.toml"`, relative to the study file,
//! or an inline `[scene]` table), optional overrides applied to every case (`[set]`, merged
//! key by key), sweep axes (`[[axis]]` with `key` a dotted path into the scene TOML and
//! either `values` or a linear/log `range`), how axes combine (`combine = "product"` or
//! `"zip"`) and the derived quantities to tabulate (`quantities = [{ kind = ..., link = 1 }]`).
//!
//! Each case's scene is built by editing the base scene as a TOML value, serialising it and
//! running [`Scene::from_text`], so a case gets exactly the validation a scene file gets;
//! an invalid or failing case is recorded with its error and the study goes on.
//!
//! Cases are numbered in a fixed order (product: the first axis varies slowest). Each
//! finished case is written atomically (temporary file + rename) as `cases/<id>.json`;
//! `results.csv` is assembled from those files, sorted by case id, with floats written by
//! [`format_value`], so the table does not depend on the number of threads, on sharding
//! (`id % n == k - 1` for shard `k/n`) or on interruptions followed by a resume.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use flexprr_run::plot::{Panel, Series, write_svg};
use flexprr_run::write_outputs;
use flexprr_run::{Quantity as RunQuantity, RunResult, run};
use flexprr_scene::ScenarioError;
use flexprr_scene::Scene;

/// Why a study could not be loaded, run or merged. Failures of single cases are not errors:
/// they are recorded in the case's row.
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum StudyError {
    /// Something is wrong in the study file (`key` is the study key involved).
    #[error("{file}: {}{message}", if key.is_empty() { String::new() } else { format!("{key}: ") })]
    Input {
        /// The study file.
        file: String,
        /// Study key, e.g. `axis.2.range.count`.
        key: String,
        /// What is wrong and what was expected.
        message: String,
    },
    /// The base scene itself cannot be read or parsed.
    #[error("base scene: {0}")]
    Scene(#[from] ScenarioError),
    /// Reading or writing a file.
    #[error("{path}: {source}")]
    Io {
        /// The file or directory involved.
        path: String,
        /// The I/O error.
        source: std::io::Error,
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
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> StudyError + '_ {
    move |source| StudyError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// The study file as written.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct StudyFile {
    /// Name (default: the file stem).
    #[serde(default)]
    pub name: Option<String>,
    /// Free text.
    #[serde(default)]
    pub description: Option<String>,
    /// Base scene file, relative to the study file. Exactly one of `base` and `scene`.
    #[serde(default)]
    pub base: Option<String>,
    /// Inline base scene.
    #[serde(default)]
    pub scene: Option<toml::Table>,
    /// Overrides applied to every case, merged table by table into the base scene.
    #[serde(default)]
    pub set: toml::Table,
    /// How the axes combine.
    #[serde(default)]
    pub combine: Combine,
    /// Sweep axes.
    #[serde(default)]
    pub axis: Vec<AxisConfig>,
    /// Derived quantities, one or more columns each.
    #[serde(default)]
    pub quantities: Vec<Quantity>,
    /// Plots of the results table written next to `results.csv`.
    #[serde(default)]
    pub plot: Vec<PlotConfig>,
}

/// How sweep axes combine into cases.
#[derive(Debug, Clone, Copy, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Combine {
    /// Cartesian product; the first axis varies slowest.
    #[default]
    Product,
    /// Element by element; all axes have the same length.
    Zip,
}

/// One sweep axis.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct AxisConfig {
    /// Dotted path into the scene TOML, e.g. `trajectory.frequency`,
    /// `links.section.thickness`, `machine.alpha_deg.0` (array index).
    pub key: String,
    /// Explicit values (any TOML type). Exactly one of `values` and `range`.
    #[serde(default)]
    pub values: Option<Vec<toml::Value>>,
    /// A linear or logarithmic range.
    #[serde(default)]
    pub range: Option<RangeConfig>,
}

/// `count` values from `start` to `end`, both included.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RangeConfig {
    /// First value.
    pub start: f64,
    /// Last value.
    pub end: f64,
    /// Number of values (at least 1).
    pub count: usize,
    /// Spacing.
    #[serde(default)]
    pub spacing: Spacing,
}

/// Spacing of a range.
#[derive(Debug, Clone, Copy, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum Spacing {
    /// Equal differences.
    #[default]
    Linear,
    /// Equal ratios (start and end positive).
    Log,
}

impl RangeConfig {
    /// The values: linear `start + k (end - start) / (count - 1)`, log
    /// `start (end / start)^(k / (count - 1))`; the last is exactly `end`.
    pub fn values(&self) -> Vec<f64> {
        let n = self.count;
        if n == 1 {
            return vec![self.start];
        }
        let last = (n - 1) as f64;
        (0..n)
            .map(|k| {
                if k + 1 == n {
                    return self.end;
                }
                let s = k as f64 / last;
                match self.spacing {
                    Spacing::Linear => self.start + s * (self.end - self.start),
                    Spacing::Log => self.start * (self.end / self.start).powf(s),
                }
            })
            .collect()
    }
}

/// A derived quantity of one case (links and modes are 1-based, as in the output tables).
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Quantity {
    /// Lowest and highest frequency of a mode over the motion (output `frequencies`):
    /// columns `f_min_<link>_<mode>_Hz`, `f_max_<link>_<mode>_Hz`.
    FrequencyRange {
        /// Link (1-3).
        link: usize,
        /// Mode (1-based).
        mode: usize,
    },
    /// Lowest `omega^2 / omega_0^2` of a mode (1 unloaded, <= 0 buckled; output
    /// `frequencies`): column `stiffness_ratio_min_<link>_<mode>`.
    StiffnessRatio {
        /// Link (1-3).
        link: usize,
        /// Mode (1-based).
        mode: usize,
    },
    /// Largest tensile and compressive axial force at either end of a link over the motion
    /// (output `axial_forces`, else `frequencies`): columns `P_max_<link>_N`, `P_min_<link>_N`.
    PeakAxialForce {
        /// Link (1-3).
        link: usize,
    },
    /// Largest |w| at the first `deflection_xi` (output `deflections`): column
    /// `w_peak_<link>_m`.
    PeakDeflection {
        /// Link (1-3).
        link: usize,
    },
    /// Whether the link buckles (stiffness not positive definite) and when it first does
    /// (output `frequencies`): columns `buckles_<link>` (`yes`/`no`), `buckling_start_<link>_s`.
    Buckling {
        /// Link (1-3).
        link: usize,
    },
}

impl Quantity {
    /// Column names.
    pub fn columns(&self) -> Vec<String> {
        match *self {
            Quantity::FrequencyRange { link, mode } => vec![
                format!("f_min_{link}_{mode}_Hz"),
                format!("f_max_{link}_{mode}_Hz"),
            ],
            Quantity::StiffnessRatio { link, mode } => {
                vec![format!("stiffness_ratio_min_{link}_{mode}")]
            }
            Quantity::PeakAxialForce { link } => {
                vec![format!("P_max_{link}_N"), format!("P_min_{link}_N")]
            }
            Quantity::PeakDeflection { link } => vec![format!("w_peak_{link}_m")],
            Quantity::Buckling { link } => {
                vec![
                    format!("buckles_{link}"),
                    format!("buckling_start_{link}_s"),
                ]
            }
        }
    }

    fn link(&self) -> usize {
        match *self {
            Quantity::FrequencyRange { link, .. }
            | Quantity::StiffnessRatio { link, .. }
            | Quantity::PeakAxialForce { link }
            | Quantity::PeakDeflection { link }
            | Quantity::Buckling { link } => link,
        }
    }

    fn mode(&self) -> Option<usize> {
        match *self {
            Quantity::FrequencyRange { mode, .. } | Quantity::StiffnessRatio { mode, .. } => {
                Some(mode)
            }
            _ => None,
        }
    }

    /// The quantity's values for one run, formatted with [`format_value`].
    ///
    /// # Errors
    /// A message when the run lacks the output the quantity needs or the mode does not exist.
    pub fn derive(&self, result: &RunResult) -> Result<Vec<String>, String> {
        let i = self.link() - 1;
        let needs = |output: &str| {
            format!(
                "quantity {} needs the output \"{output}\"",
                self.columns()[0]
            )
        };
        match *self {
            Quantity::FrequencyRange { mode, .. } | Quantity::StiffnessRatio { mode, .. } => {
                let history = result
                    .frequencies
                    .as_ref()
                    .ok_or_else(|| needs("frequencies"))?;
                let range = history
                    .ranges
                    .iter()
                    .find(|r| r.link == i && r.mode + 1 == mode)
                    .ok_or_else(|| format!("link {} has no mode {mode}", i + 1))?;
                Ok(match self {
                    Quantity::FrequencyRange { .. } => {
                        vec![format_value(range.min_hz), format_value(range.max_hz)]
                    }
                    _ => vec![format_value(range.min_stiffness_ratio)],
                })
            }
            Quantity::PeakAxialForce { .. } => {
                let forces: Vec<f64> = if let Some(table) = result.table("axial_forces") {
                    let b = table.column(&format!("P_B_{}_N", i + 1)).unwrap_or(&[]);
                    let c = table.column(&format!("P_C_{}_N", i + 1)).unwrap_or(&[]);
                    b.iter().chain(c).copied().collect()
                } else if let Some(history) = &result.frequencies {
                    history.end_forces[i]
                        .iter()
                        .flat_map(|&(b, c)| [b, c])
                        .collect()
                } else {
                    return Err(needs("axial_forces\" or \"frequencies"));
                };
                let max = forces.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                let min = forces.iter().copied().fold(f64::INFINITY, f64::min);
                Ok(vec![format_value(max), format_value(min)])
            }
            Quantity::PeakDeflection { .. } => {
                let table = result
                    .table("deflections")
                    .ok_or_else(|| needs("deflections"))?;
                let column = table
                    .columns
                    .iter()
                    .position(|c| c.quantity == RunQuantity::Deflection && c.link == Some(i))
                    .ok_or_else(|| needs("deflections"))?;
                let peak = table.data[column]
                    .iter()
                    .fold(0.0_f64, |m, w| m.max(w.abs()));
                Ok(vec![format_value(peak)])
            }
            Quantity::Buckling { .. } => {
                let history = result
                    .frequencies
                    .as_ref()
                    .ok_or_else(|| needs("frequencies"))?;
                let start = history
                    .buckling
                    .iter()
                    .filter(|b| b.link == i)
                    .map(|b| b.t_start)
                    .fold(None, |m: Option<f64>, t| Some(m.map_or(t, |m| m.min(t))));
                Ok(match start {
                    Some(t) => vec!["yes".into(), format_value(t)],
                    None => vec!["no".into(), String::new()],
                })
            }
        }
    }
}

/// A plot of the results table: `y` columns against the parameter `x`, one line per value
/// of the parameter `series` (if given). Only rows with status `ok` are drawn.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PlotConfig {
    /// File name (`.svg`) inside the output directory.
    pub file: String,
    /// Title.
    #[serde(default)]
    pub title: Option<String>,
    /// Axis key used as abscissa.
    pub x: String,
    /// Result columns, one panel each.
    pub y: Vec<String>,
    /// Axis key distinguishing lines.
    #[serde(default)]
    pub series: Option<String>,
}

/// Formats a float deterministically: rounded to 10 significant digits, then written in
/// Rust's shortest round-trip form (`20`, `116.4389235`, `1e-6`); `nan`, `inf`, `-inf`.
pub fn format_value(value: f64) -> String {
    if !value.is_finite() {
        return format!("{value}").to_lowercase();
    }
    let rounded: f64 = format!("{value:.9e}").parse().unwrap_or(value);
    format!("{rounded}")
}

fn format_parameter(value: &toml::Value) -> String {
    match value {
        toml::Value::Float(f) => format_value(*f),
        toml::Value::Integer(i) => i.to_string(),
        toml::Value::String(s) => s.clone(),
        toml::Value::Boolean(b) => b.to_string(),
        other => other.to_string(),
    }
}

/// Outcome of one case.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum CaseStatus {
    /// Ran; quantities filled in.
    Ok,
    /// The case's scene is invalid (bad parameters).
    Invalid,
    /// The run failed (integrator, buckling divergence, step-size collapse, missing output).
    Failed,
}

impl CaseStatus {
    /// Name written in the table.
    pub fn name(self) -> &'static str {
        match self {
            CaseStatus::Ok => "ok",
            CaseStatus::Invalid => "invalid",
            CaseStatus::Failed => "failed",
        }
    }
}

/// One finished case, as stored in `cases/<id>.json`.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CaseRecord {
    /// Case id (0-based).
    pub id: usize,
    /// Fingerprint of the study the case belongs to.
    pub fingerprint: String,
    /// Formatted axis values, in axis order.
    pub parameters: Vec<String>,
    /// Formatted quantity columns (empty strings when not ok).
    pub quantities: Vec<String>,
    /// Outcome.
    pub status: CaseStatus,
    /// Error message on one line (empty when ok).
    pub error: String,
}

/// One case of a study: its id and the value of each axis.
#[derive(Debug, Clone, PartialEq)]
pub struct Case {
    /// Case id (0-based, the position in the fixed case order).
    pub id: usize,
    /// Value of each axis.
    pub values: Vec<toml::Value>,
}

/// A sweep axis with its values expanded.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// Dotted scene key.
    pub key: String,
    /// Values.
    pub values: Vec<toml::Value>,
}

/// A loaded, checked study: the base scene (with `[set]` applied), the expanded cases and
/// the quantities.
#[derive(Debug, Clone)]
pub struct Study {
    /// Study name.
    pub name: String,
    /// Study file name, for messages.
    pub file: String,
    /// Base scene with the overrides applied.
    pub base: toml::Table,
    /// Axes.
    pub axes: Vec<Axis>,
    /// Cases in id order.
    pub cases: Vec<Case>,
    /// Quantities.
    pub quantities: Vec<Quantity>,
    /// Plots.
    pub plots: Vec<PlotConfig>,
    /// FNV-1a hash of everything that determines the table (base scene, axes, quantities).
    pub fingerprint: String,
}

/// Deep merge: tables merge key by key, anything else replaces.
fn merge_into(target: &mut toml::Table, overrides: &toml::Table) {
    for (key, value) in overrides {
        match (target.get_mut(key), value) {
            (Some(toml::Value::Table(t)), toml::Value::Table(o)) => merge_into(t, o),
            _ => {
                target.insert(key.clone(), value.clone());
            }
        }
    }
}

/// Sets `value` at the dotted `key` in `scene`, creating missing tables; an integer replacing
/// a float becomes a float. Numeric path segments index arrays.
///
/// # Errors
/// A message when the path runs through a value that is neither a table nor an array.
pub fn set_key(scene: &mut toml::Table, key: &str, value: &toml::Value) -> Result<(), String> {
    let parts: Vec<&str> = key.split('.').collect();
    if parts.iter().any(|p| p.is_empty()) {
        return Err(format!("key \"{key}\" has an empty segment"));
    }
    set_in_table(scene, &parts, key, value)
}

/// An integer written where the base scene has a float becomes a float.
fn coerce(old: Option<&toml::Value>, value: &toml::Value) -> toml::Value {
    match (old, value) {
        (Some(toml::Value::Float(_)), toml::Value::Integer(i)) => toml::Value::Float(*i as f64),
        _ => value.clone(),
    }
}

fn set_in_table(
    table: &mut toml::Table,
    parts: &[&str],
    key: &str,
    value: &toml::Value,
) -> Result<(), String> {
    let Some((first, rest)) = parts.split_first() else {
        return Err(format!("key \"{key}\" is empty"));
    };
    if rest.is_empty() {
        let new = coerce(table.get(*first), value);
        table.insert(first.to_string(), new);
        return Ok(());
    }
    let child = table
        .entry(first.to_string())
        .or_insert_with(|| toml::Value::Table(toml::Table::new()));
    set_in_value(child, rest, key, value)
}

fn set_in_value(
    node: &mut toml::Value,
    parts: &[&str],
    key: &str,
    value: &toml::Value,
) -> Result<(), String> {
    match node {
        toml::Value::Table(t) => set_in_table(t, parts, key, value),
        toml::Value::Array(a) => {
            let Some((first, rest)) = parts.split_first() else {
                return Err(format!("key \"{key}\" is empty"));
            };
            let index: usize = first
                .parse()
                .map_err(|_| format!("\"{first}\" in \"{key}\" is not an array index"))?;
            let len = a.len();
            let slot = a.get_mut(index).ok_or_else(|| {
                format!("index {index} in \"{key}\" is out of range (length {len})")
            })?;
            if rest.is_empty() {
                let new = coerce(Some(&*slot), value);
                *slot = new;
                Ok(())
            } else {
                set_in_value(slot, rest, key, value)
            }
        }
        _ => Err(format!(
            "\"{key}\": \"{}\" is not inside a table or an array",
            parts.first().copied().unwrap_or_default()
        )),
    }
}

/// FNV-1a, 64 bit (Fowler, Noll, Vo): a hash that is stable across builds and platforms.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

impl Study {
    /// Reads and checks a study file; `base` is resolved relative to its directory.
    ///
    /// # Errors
    /// [`StudyError::Io`] if a file cannot be read, [`StudyError::Input`] for anything wrong
    /// in the study, [`StudyError::Scene`] for a base scene that is not valid TOML.
    pub fn load(path: &Path) -> Result<Self, StudyError> {
        let text = std::fs::read_to_string(path).map_err(io_err(path))?;
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("study");
        let dir = path.parent().unwrap_or(Path::new("."));
        Self::from_text(&path.display().to_string(), name, &text, dir)
    }

    /// Parses and checks study text; `file` names it in messages, `default_name` is used
    /// without a `name`, `dir` resolves `base`.
    ///
    /// # Errors
    /// As [`Study::load`].
    pub fn from_text(
        file: &str,
        default_name: &str,
        text: &str,
        dir: &Path,
    ) -> Result<Self, StudyError> {
        let input = |key: &str, message: String| StudyError::Input {
            file: file.to_string(),
            key: key.to_string(),
            message,
        };
        let raw: StudyFile = toml::from_str(text).map_err(|e| {
            let (mut key, mut at) = (String::new(), String::new());
            if let Some(span) = e.span() {
                let (line, column) = flexprr_scene::line_column(text, span.start);
                at = format!("line {line}, column {column}: ");
                // The key assigned on that line, if any, names the problem.
                if let Some((name, _)) = text.lines().nth(line - 1).and_then(|l| l.split_once('='))
                {
                    key = name.trim().to_string();
                }
            }
            input(&key, format!("{at}{}", e.message().trim()))
        })?;
        let mut base = match (&raw.base, &raw.scene) {
            (Some(base), None) => {
                let path = dir.join(base);
                let text = std::fs::read_to_string(&path).map_err(io_err(&path))?;
                toml::from_str::<toml::Table>(&text).map_err(|e| ScenarioError::Input {
                    location: None,
                    key: String::new(),
                    message: format!("{}: {}", path.display(), e.message().trim()),
                })?
            }
            (None, Some(scene)) => scene.clone(),
            _ => {
                return Err(input(
                    "base",
                    "give exactly one of `base = \"scene.toml\"` and an inline `[scene]` table"
                        .into(),
                ));
            }
        };
        merge_into(&mut base, &raw.set);

        let mut axes = Vec::with_capacity(raw.axis.len());
        for (k, a) in raw.axis.iter().enumerate() {
            let key = format!("axis.{k}");
            let values = match (&a.values, &a.range) {
                (Some(v), None) => v.clone(),
                (None, Some(r)) => {
                    let bad = |m: &str| input(&format!("{key}.range"), m.to_string());
                    if !r.start.is_finite() || !r.end.is_finite() {
                        return Err(bad("start and end must be finite"));
                    }
                    if r.count == 0 {
                        return Err(bad("count must be at least 1"));
                    }
                    if r.spacing == Spacing::Log && !(r.start > 0.0 && r.end > 0.0) {
                        return Err(bad("a log range needs positive start and end"));
                    }
                    r.values().into_iter().map(toml::Value::Float).collect()
                }
                _ => {
                    return Err(input(
                        &key,
                        format!(
                            "axis \"{}\": give exactly one of `values` and `range`",
                            a.key
                        ),
                    ));
                }
            };
            if values.is_empty() {
                return Err(input(
                    &format!("{key}.values"),
                    format!("axis \"{}\" has no values", a.key),
                ));
            }
            if axes.iter().any(|b: &Axis| b.key == a.key) {
                return Err(input(&key, format!("axis \"{}\" appears twice", a.key)));
            }
            // The key must be settable in the base scene.
            let mut probe = base.clone();
            set_key(&mut probe, &a.key, &values[0]).map_err(|m| input(&key, m))?;
            axes.push(Axis {
                key: a.key.clone(),
                values,
            });
        }

        let cases = match raw.combine {
            Combine::Product => {
                let total: usize = axes.iter().map(|a| a.values.len()).product();
                (0..total)
                    .map(|id| {
                        let mut rest = id;
                        let mut values = vec![toml::Value::Boolean(false); axes.len()];
                        for (slot, axis) in values.iter_mut().zip(&axes).rev() {
                            let n = axis.values.len();
                            *slot = axis.values[rest % n].clone();
                            rest /= n;
                        }
                        Case { id, values }
                    })
                    .collect()
            }
            Combine::Zip => {
                let n = axes.first().map_or(1, |a| a.values.len());
                if let Some((k, a)) = axes.iter().enumerate().find(|(_, a)| a.values.len() != n) {
                    return Err(input(
                        &format!("axis.{k}"),
                        format!(
                            "zipped axes need equal lengths: \"{}\" has {}, \"{}\" has {n}",
                            a.key,
                            a.values.len(),
                            axes[0].key
                        ),
                    ));
                }
                (0..n)
                    .map(|id| Case {
                        id,
                        values: axes.iter().map(|a| a.values[id].clone()).collect(),
                    })
                    .collect()
            }
        };

        for (k, q) in raw.quantities.iter().enumerate() {
            if !(1..=3).contains(&q.link()) {
                return Err(input(
                    &format!("quantities.{k}.link"),
                    format!("link must be 1, 2 or 3, got {}", q.link()),
                ));
            }
            if q.mode() == Some(0) {
                return Err(input(
                    &format!("quantities.{k}.mode"),
                    "modes are numbered from 1".into(),
                ));
            }
        }

        let study = Study {
            name: raw.name.clone().unwrap_or_else(|| default_name.to_string()),
            file: file.to_string(),
            base,
            axes,
            cases,
            quantities: raw.quantities.clone(),
            plots: raw.plot.clone(),
            fingerprint: String::new(),
        };
        let columns = study.columns();
        for (k, p) in study.plots.iter().enumerate() {
            for key in std::iter::once(&p.x).chain(&p.series) {
                if !study.axes.iter().any(|a| &a.key == key) {
                    return Err(input(
                        &format!("plot.{k}"),
                        format!("\"{key}\" is not an axis key"),
                    ));
                }
            }
            if let Some(y) = p.y.iter().find(|y| !columns.contains(y)) {
                return Err(input(
                    &format!("plot.{k}.y"),
                    format!("\"{y}\" is not a results column"),
                ));
            }
        }
        let mut canonical = toml::to_string(&study.base).unwrap_or_default();
        for axis in &study.axes {
            let _ = write!(canonical, "\n{}:", axis.key);
            for v in &axis.values {
                let _ = write!(canonical, " {v}");
            }
        }
        let _ = write!(canonical, "\n{:?}\n{}", raw.combine, columns.join(","));
        Ok(Study {
            fingerprint: format!("{:016x}", fnv1a(canonical.as_bytes())),
            ..study
        })
    }

    /// Header of `results.csv`: `case`, the axis keys, the quantity columns, `status`,
    /// `error`.
    pub fn columns(&self) -> Vec<String> {
        let mut columns = vec!["case".to_string()];
        columns.extend(self.axes.iter().map(|a| a.key.clone()));
        columns.extend(self.quantities.iter().flat_map(Quantity::columns));
        columns.push("status".into());
        columns.push("error".into());
        columns
    }

    fn quantity_columns(&self) -> usize {
        self.quantities.iter().map(|q| q.columns().len()).sum()
    }

    /// The scene text of a case: the base scene with the case's axis values set.
    ///
    /// # Errors
    /// A message when a key cannot be set.
    pub fn case_scene_text(&self, case: &Case) -> Result<String, String> {
        let mut scene = self.base.clone();
        for (axis, value) in self.axes.iter().zip(&case.values) {
            set_key(&mut scene, &axis.key, value)?;
        }
        toml::to_string(&scene).map_err(|e| e.to_string())
    }

    /// Builds a case's scene (same validation as a scene file).
    ///
    /// # Errors
    /// [`ScenarioError::Input`] for bad parameters.
    pub fn case_scene(&self, case: &Case) -> Result<Scene, ScenarioError> {
        let text = self
            .case_scene_text(case)
            .map_err(|message| ScenarioError::Input {
                location: None,
                key: String::new(),
                message,
            })?;
        let name = format!("{}_{:06}", self.name, case.id);
        Scene::from_text(&format!("{} case {}", self.name, case.id), &name, &text)
    }

    /// Runs one case; never fails: bad parameters, run failures and panics are recorded in
    /// the returned record. The scene and run are returned when the case ran.
    pub fn run_case(&self, case: &Case) -> (CaseRecord, Option<(Scene, RunResult)>) {
        let mut record = CaseRecord {
            id: case.id,
            fingerprint: self.fingerprint.clone(),
            parameters: case.values.iter().map(format_parameter).collect(),
            quantities: vec![String::new(); self.quantity_columns()],
            status: CaseStatus::Ok,
            error: String::new(),
        };
        let fail = |mut record: CaseRecord, status, message: String| {
            record.status = status;
            record.error = message.split_whitespace().collect::<Vec<_>>().join(" ");
            (record, None)
        };
        let scene = match self.case_scene(case) {
            Ok(s) => s,
            Err(e) => return fail(record, CaseStatus::Invalid, e.to_string()),
        };
        let outcome = std::panic::catch_unwind(AssertUnwindSafe(|| run(&scene, &mut |_| {})));
        let result = match outcome {
            Ok(Ok(r)) => r,
            Ok(Err(e)) => return fail(record, CaseStatus::Failed, e.to_string()),
            Err(panic) => {
                let what = panic
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_default();
                return fail(record, CaseStatus::Failed, format!("panic: {what}"));
            }
        };
        if let Some(message) = divergence(&result) {
            return fail(record, CaseStatus::Failed, message);
        }
        let mut values = Vec::with_capacity(record.quantities.len());
        for q in &self.quantities {
            match q.derive(&result) {
                Ok(v) => values.extend(v),
                Err(message) => return fail(record, CaseStatus::Failed, message),
            }
        }
        record.quantities = values;
        (record, Some((scene, result)))
    }

    /// The cases of shard `shard` (all cases without a shard).
    pub fn shard_cases(&self, shard: Option<Shard>) -> Vec<&Case> {
        self.cases
            .iter()
            .filter(|c| shard.is_none_or(|s| s.contains(c.id)))
            .collect()
    }
}

/// Why a finished run is not physical: a non-finite value in a table (divergence itself is
/// the run layer's guard, which stops the run).
fn divergence(result: &RunResult) -> Option<String> {
    for table in &result.tables {
        let t = table.time();
        for (column, values) in table.columns.iter().zip(&table.data).skip(1) {
            if let Some(k) = values.iter().position(|v| !v.is_finite()) {
                let at = t.get(k).copied().unwrap_or(f64::NAN);
                return Some(format!(
                    "non-finite value: {}.{column} = {} at t = {at:.5} s",
                    table.name, values[k]
                ));
            }
        }
    }
    None
}

/// Slice `index` (1-based) of `count`: the cases with `id % count == index - 1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// 1-based index.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
}

impl Shard {
    /// Whether case `id` belongs to this shard.
    pub fn contains(&self, id: usize) -> bool {
        id % self.count == self.index - 1
    }
}

impl FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("shard \"{s}\": expected k/n with 1 <= k <= n, e.g. 2/8");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = k.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if index == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// How to run a study.
#[derive(Debug, Clone, Default)]
pub struct StudyOptions {
    /// Worker threads (default: all cores).
    pub threads: Option<usize>,
    /// Run only this slice of the cases.
    pub shard: Option<Shard>,
    /// Skip cases already recorded in the output directory.
    pub resume: bool,
    /// Write each case's full outputs into `cases/<id>/`.
    pub case_outputs: bool,
}

/// Progress after a case finished (for a progress bar).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StudyProgress {
    /// Cases of this run (shard), including those recorded before a resume.
    pub total: usize,
    /// Cases recorded so far (including those recorded before a resume).
    pub done: usize,
    /// Of those, not ok.
    pub failed: usize,
    /// Cases found already recorded when the run started.
    pub resumed: usize,
}

/// What a study run did.
#[derive(Debug, Clone, PartialEq)]
pub struct StudySummary {
    /// Final progress.
    pub progress: StudyProgress,
    /// Cases run now (not resumed).
    pub ran: usize,
    /// `results.csv`.
    pub results: PathBuf,
}

/// Contents of `study.json`: identifies the study an output directory belongs to.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
struct StudyManifest {
    name: String,
    fingerprint: String,
    cases: usize,
    columns: Vec<String>,
    shard: Option<String>,
}

fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), StudyError> {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("file");
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    std::fs::write(&tmp, bytes).map_err(io_err(&tmp))?;
    std::fs::rename(&tmp, path).map_err(io_err(path))
}

fn case_file(dir: &Path, id: usize) -> PathBuf {
    dir.join("cases").join(format!("{id:06}.json"))
}

/// Reads every `cases/<id>.json` in `dir`.
///
/// # Errors
/// [`StudyError::Io`] or [`StudyError::Directory`] for an unreadable record.
pub fn read_case_records(dir: &Path) -> Result<BTreeMap<usize, CaseRecord>, StudyError> {
    let cases = dir.join("cases");
    let mut records = BTreeMap::new();
    if !cases.is_dir() {
        return Ok(records);
    }
    for entry in std::fs::read_dir(&cases).map_err(io_err(&cases))? {
        let path = entry.map_err(io_err(&cases))?.path();
        let is_record = path.extension().is_some_and(|e| e == "json")
            && path
                .file_stem()
                .and_then(|s| s.to_str())
                .is_some_and(|s| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()));
        if !is_record {
            continue;
        }
        let text = std::fs::read_to_string(&path).map_err(io_err(&path))?;
        let record: CaseRecord =
            serde_json::from_str(&text).map_err(|e| StudyError::Directory {
                dir: path.display().to_string(),
                message: format!("not a case record: {e}"),
            })?;
        records.insert(record.id, record);
    }
    Ok(records)
}

/// `results.csv` bytes: the header, then one row per record in id order.
///
/// # Errors
/// [`StudyError::Directory`] if the CSV writer fails.
pub fn results_csv<'a>(
    columns: &[String],
    records: impl IntoIterator<Item = &'a CaseRecord>,
) -> Result<Vec<u8>, StudyError> {
    let err = |e: csv::Error| StudyError::Directory {
        dir: "results.csv".into(),
        message: e.to_string(),
    };
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(columns).map_err(err)?;
    let mut sorted: Vec<&CaseRecord> = records.into_iter().collect();
    sorted.sort_by_key(|r| r.id);
    for r in sorted {
        let mut row = vec![r.id.to_string()];
        row.extend(r.parameters.iter().cloned());
        row.extend(r.quantities.iter().cloned());
        row.push(r.status.name().into());
        row.push(r.error.clone());
        w.write_record(&row).map_err(err)?;
    }
    w.into_inner().map_err(|e| StudyError::Directory {
        dir: "results.csv".into(),
        message: e.to_string(),
    })
}

fn read_manifest(dir: &Path) -> Result<Option<StudyManifest>, StudyError> {
    let path = dir.join("study.json");
    if !path.exists() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(&path).map_err(io_err(&path))?;
    serde_json::from_str(&text)
        .map(Some)
        .map_err(|e| StudyError::Directory {
            dir: path.display().to_string(),
            message: format!("not a study manifest: {e}"),
        })
}

fn write_manifest(dir: &Path, manifest: &StudyManifest) -> Result<(), StudyError> {
    let text = serde_json::to_string_pretty(manifest).unwrap_or_default();
    write_atomic(&dir.join("study.json"), text.as_bytes())
}

/// Runs a study (or one shard of it) into `out`: `study.json`, `cases/<id>.json` written
/// atomically as each case finishes, `results.csv` at the end, plots if the study asks,
/// `cases/<id>/` full outputs with [`StudyOptions::case_outputs`]. `on_case` is called after
/// every finished case (from worker threads).
///
/// # Errors
/// [`StudyError::Directory`] when `out` holds another study's results, or results without
/// `resume`; [`StudyError::Io`] when files cannot be written. Failing cases are not errors.
pub fn run_study(
    study: &Study,
    out: &Path,
    options: &StudyOptions,
    on_case: &(dyn Fn(&StudyProgress, &CaseRecord) + Sync),
) -> Result<StudySummary, StudyError> {
    let cases_dir = out.join("cases");
    std::fs::create_dir_all(&cases_dir).map_err(io_err(&cases_dir))?;
    let dir_err = |message: String| StudyError::Directory {
        dir: out.display().to_string(),
        message,
    };
    let existing = read_case_records(out)?;
    if let Some(manifest) = read_manifest(out)? {
        if manifest.fingerprint != study.fingerprint {
            return Err(dir_err(format!(
                "holds results of another study or another version of it (\"{}\", fingerprint {}, this one {}); use a new directory",
                manifest.name, manifest.fingerprint, study.fingerprint
            )));
        }
    }
    if !existing.is_empty() && !options.resume {
        return Err(dir_err(format!(
            "already holds {} case results; pass --resume to complete it or use a new directory",
            existing.len()
        )));
    }
    if let Some(r) = existing
        .values()
        .find(|r| r.fingerprint != study.fingerprint)
    {
        return Err(dir_err(format!(
            "case {} was recorded by another study (fingerprint {})",
            r.id, r.fingerprint
        )));
    }
    write_manifest(
        out,
        &StudyManifest {
            name: study.name.clone(),
            fingerprint: study.fingerprint.clone(),
            cases: study.cases.len(),
            columns: study.columns(),
            shard: options.shard.map(|s| s.to_string()),
        },
    )?;

    let mine = study.shard_cases(options.shard);
    let pending: Vec<&Case> = mine
        .iter()
        .copied()
        .filter(|c| !existing.contains_key(&c.id))
        .collect();
    let resumed = mine.len() - pending.len();
    let failed_before = mine
        .iter()
        .filter(|c| {
            existing
                .get(&c.id)
                .is_some_and(|r| r.status != CaseStatus::Ok)
        })
        .count();
    let done = AtomicUsize::new(resumed);
    let failed = AtomicUsize::new(failed_before);
    let first_error: Mutex<Option<StudyError>> = Mutex::new(None);
    let total = mine.len();

    let work = || {
        pending.par_iter().for_each(|case| {
            if first_error.lock().map(|e| e.is_some()).unwrap_or(true) {
                return;
            }
            let (record, ran) = study.run_case(case);
            let mut outcome = Ok(());
            if options.case_outputs {
                if let Some((scene, result)) = &ran {
                    let dir = out.join("cases").join(format!("{:06}", case.id));
                    outcome = write_outputs(scene, result, &dir)
                        .map(|_| ())
                        .map_err(|e| dir_err(e.to_string()));
                }
            }
            if outcome.is_ok() {
                let bytes = serde_json::to_vec_pretty(&record).unwrap_or_default();
                outcome = write_atomic(&case_file(out, case.id), &bytes);
            }
            if let Err(e) = outcome {
                if let Ok(mut slot) = first_error.lock() {
                    slot.get_or_insert(e);
                }
                return;
            }
            if record.status != CaseStatus::Ok {
                failed.fetch_add(1, Ordering::SeqCst);
            }
            let progress = StudyProgress {
                total,
                done: done.fetch_add(1, Ordering::SeqCst) + 1,
                failed: failed.load(Ordering::SeqCst),
                resumed,
            };
            on_case(&progress, &record);
        });
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(options.threads.unwrap_or(0))
        .build()
        .map_err(|e| dir_err(format!("cannot start worker threads: {e}")))?;
    pool.install(work);
    if let Some(e) = first_error.into_inner().ok().flatten() {
        return Err(e);
    }

    let records = read_case_records(out)?;
    let mine_records: Vec<&CaseRecord> = mine.iter().filter_map(|c| records.get(&c.id)).collect();
    let results = out.join("results.csv");
    write_atomic(
        &results,
        &results_csv(&study.columns(), mine_records.iter().copied())?,
    )?;
    if options.shard.is_none() {
        write_plots(study, out, &records)?;
    }
    Ok(StudySummary {
        progress: StudyProgress {
            total,
            done: done.load(Ordering::SeqCst),
            failed: failed.load(Ordering::SeqCst),
            resumed,
        },
        ran: pending.len(),
        results,
    })
}

/// One drawn line: label, abscissae, ordinates.
type PlotLine = (String, Vec<f64>, Vec<f64>);

/// Writes the study's `[[plot]]`s from the case records.
///
/// # Errors
/// [`StudyError::Directory`] if a plot cannot be drawn.
pub fn write_plots(
    study: &Study,
    out: &Path,
    records: &BTreeMap<usize, CaseRecord>,
) -> Result<(), StudyError> {
    let columns = study.columns();
    let n_axes = study.axes.len();
    let parameter = |r: &CaseRecord, key: &str| -> Option<String> {
        let k = study.axes.iter().position(|a| a.key == key)?;
        r.parameters.get(k).cloned()
    };
    for plot in &study.plots {
        // One line per distinct `series` value, in order of first appearance.
        let mut lines: Vec<(String, Vec<&CaseRecord>)> = Vec::new();
        for r in records.values().filter(|r| r.status == CaseStatus::Ok) {
            let label = plot
                .series
                .as_ref()
                .and_then(|s| parameter(r, s))
                .unwrap_or_default();
            match lines.iter_mut().find(|(l, _)| *l == label) {
                Some((_, rs)) => rs.push(r),
                None => lines.push((label, vec![r])),
            }
        }
        let mut data: Vec<Vec<PlotLine>> = Vec::new();
        for y in &plot.y {
            let c = columns.iter().position(|c| c == y).unwrap_or(0);
            let q = c.saturating_sub(1 + n_axes);
            let mut panel = Vec::new();
            for (label, rs) in &lines {
                let mut points: Vec<(f64, f64)> = rs
                    .iter()
                    .filter_map(|r| {
                        let x = parameter(r, &plot.x)?.parse().ok()?;
                        let v = r.quantities.get(q)?.parse().ok()?;
                        Some((x, v))
                    })
                    .collect();
                points.sort_by(|a, b| a.0.total_cmp(&b.0));
                let (xs, ys) = points.into_iter().unzip();
                panel.push((label.clone(), xs, ys));
            }
            data.push(panel);
        }
        let panels: Vec<Panel<'_>> = plot
            .y
            .iter()
            .zip(&data)
            .map(|(y, lines)| Panel {
                y_label: y.clone(),
                series: lines
                    .iter()
                    .map(|(label, x, v)| Series {
                        label: if label.is_empty() {
                            y.clone()
                        } else {
                            label.clone()
                        },
                        x,
                        y: v,
                        dashed: false,
                    })
                    .collect(),
            })
            .collect();
        let title = plot.title.clone().unwrap_or_else(|| study.name.clone());
        write_svg(&out.join(&plot.file), &title, &plot.x, &panels).map_err(|message| {
            StudyError::Directory {
                dir: out.display().to_string(),
                message,
            }
        })?;
    }
    Ok(())
}

/// What a merge did.
#[derive(Debug, Clone, PartialEq)]
pub struct MergeSummary {
    /// Cases in the merged table.
    pub cases: usize,
    /// Of those, not ok.
    pub failed: usize,
    /// `results.csv`.
    pub results: PathBuf,
}

/// Combines shard directories of one study into `out`: checks that they belong to the same
/// study, that duplicated cases agree and that every case is present, then writes the case
/// records, `study.json` and the same `results.csv` a single run gives.
///
/// # Errors
/// [`StudyError::Directory`] for mixed studies, conflicting or missing cases;
/// [`StudyError::Io`] for unreadable or unwritable files.
pub fn merge_studies(dirs: &[PathBuf], out: &Path) -> Result<MergeSummary, StudyError> {
    let mut manifest: Option<StudyManifest> = None;
    let mut records: BTreeMap<usize, CaseRecord> = BTreeMap::new();
    for dir in dirs {
        let dir_err = |message: String| StudyError::Directory {
            dir: dir.display().to_string(),
            message,
        };
        let m = read_manifest(dir)?
            .ok_or_else(|| dir_err("no study.json: not a study output directory".into()))?;
        if let Some(first) = &manifest {
            if first.fingerprint != m.fingerprint || first.columns != m.columns {
                return Err(dir_err(format!(
                    "belongs to study \"{}\" (fingerprint {}), the first directory to \"{}\" ({})",
                    m.name, m.fingerprint, first.name, first.fingerprint
                )));
            }
        }
        for (id, r) in read_case_records(dir)? {
            if r.fingerprint != m.fingerprint {
                return Err(dir_err(format!("case {id} was recorded by another study")));
            }
            if id >= m.cases {
                return Err(dir_err(format!(
                    "case {id} is outside the study's {} cases",
                    m.cases
                )));
            }
            match records.get(&id) {
                Some(other) if *other != r => {
                    return Err(dir_err(format!(
                        "case {id} differs from the same case in another directory"
                    )));
                }
                _ => {
                    records.insert(id, r);
                }
            }
        }
        manifest.get_or_insert(m);
    }
    let mut manifest = manifest.ok_or_else(|| StudyError::Directory {
        dir: out.display().to_string(),
        message: "no directories to merge".into(),
    })?;
    let missing: Vec<usize> = (0..manifest.cases)
        .filter(|id| !records.contains_key(id))
        .collect();
    if !missing.is_empty() {
        let shown: Vec<String> = missing.iter().take(10).map(usize::to_string).collect();
        return Err(StudyError::Directory {
            dir: out.display().to_string(),
            message: format!(
                "{} of {} cases missing (e.g. {}); run the missing shards or --resume them first",
                missing.len(),
                manifest.cases,
                shown.join(", ")
            ),
        });
    }
    let cases_dir = out.join("cases");
    std::fs::create_dir_all(&cases_dir).map_err(io_err(&cases_dir))?;
    if let Some(existing) = read_manifest(out)? {
        if existing.fingerprint != manifest.fingerprint {
            return Err(StudyError::Directory {
                dir: out.display().to_string(),
                message: "holds results of another study".into(),
            });
        }
    }
    manifest.shard = None;
    write_manifest(out, &manifest)?;
    for r in records.values() {
        let bytes = serde_json::to_vec_pretty(r).unwrap_or_default();
        write_atomic(&case_file(out, r.id), &bytes)?;
    }
    let results = out.join("results.csv");
    write_atomic(&results, &results_csv(&manifest.columns, records.values())?)?;
    Ok(MergeSummary {
        cases: records.len(),
        failed: records
            .values()
            .filter(|r| r.status != CaseStatus::Ok)
            .count(),
        results,
    })
}
