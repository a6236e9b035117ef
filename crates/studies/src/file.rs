//! The study file as written: the serde schema (`docs/studies.md`, "Study files"). Every
//! choice is a serde enum and every table denies unknown fields, so the parser itself names
//! a bad value with its file, line, column and key; the quantities are read by their
//! registered kinds afterwards, with the same locations.

use serde::{Deserialize, Serialize};

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
    /// Derived quantities, one or more columns each: tables with a `kind`, read by the
    /// registered quantity kinds ([`crate::quantity::QuantityRegistry`]) once the file is
    /// parsed.
    #[serde(default)]
    pub quantities: Vec<toml::Value>,
    /// Plots of the results table written next to `results.csv`.
    #[serde(default)]
    pub plot: Vec<PlotConfig>,
    /// A speed search instead of a sweep (`crate::search`): bisection (or k-section) over
    /// one key for the smallest value that collapses.
    #[serde(default)]
    pub search: Option<crate::search::SearchConfig>,
    /// A workspace map instead of a sweep (`crate::map`): a quantity of the machine at rest
    /// over a grid of poses.
    #[serde(default)]
    pub map: Option<crate::map::MapConfig>,
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
