//! What a run produces: tables of typed columns, the frequency history, work statistics.

use flexprr_dynamics::FrequencyHistory;
use flexprr_integrators::Stats;

use crate::column::{Column, Quantity};

/// A time-series table: the time column first, then typed columns.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// File stem (`kinematics`, `deflections`, ...).
    pub name: String,
    /// Column identities, time first.
    pub columns: Vec<Column>,
    /// Column data, `data[column][row]`.
    pub data: Vec<Vec<f64>>,
}

impl Table {
    /// A table with only the time column.
    pub fn new(name: &str, t: &[f64]) -> Self {
        Self {
            name: name.to_string(),
            columns: vec![Column::of(Quantity::Time)],
            data: vec![t.to_vec()],
        }
    }
    /// Appends a column.
    pub fn push(&mut self, column: Column, values: Vec<f64>) {
        self.columns.push(column);
        self.data.push(values);
    }
    /// The values of `column`.
    pub fn get(&self, column: &Column) -> Option<&[f64]> {
        self.columns
            .iter()
            .position(|c| c == column)
            .map(|i| self.data[i].as_slice())
    }
    /// The values of the column whose CSV header is `header` (for readers of the files).
    pub fn column(&self, header: &str) -> Option<&[f64]> {
        self.columns
            .iter()
            .position(|c| c.header() == header)
            .map(|i| self.data[i].as_slice())
    }
    /// The CSV headers, rendered from the column identities.
    pub fn headers(&self) -> Vec<String> {
        self.columns.iter().map(Column::header).collect()
    }
    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.data.first().map_or(0, Vec::len)
    }
    /// The time column.
    pub fn time(&self) -> &[f64] {
        &self.data[0]
    }
}

/// What a run did (tests use it to prove that only the needed work was done).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RunStats {
    /// Whether the model's ODE was integrated.
    pub integrated: bool,
    /// Right-hand-side evaluations of the model(s).
    pub rhs_evaluations: usize,
    /// Rigid inverse-dynamics solves (inside the ODE and for outputs).
    pub inverse_dynamics_solves: usize,
    /// Integrator statistics of the main integration.
    pub integrator: Option<Stats>,
    /// Largest deflection of any link over the accepted steps (m), when integrated.
    pub max_deflection_m: Option<f64>,
    /// Wall-clock time of the whole run (s).
    pub wall_time_s: f64,
}

/// Everything a run produced.
#[derive(Debug, Clone, Default)]
pub struct RunResult {
    /// The requested time series.
    pub tables: Vec<Table>,
    /// Frequencies along the motion, when requested.
    pub frequencies: Option<FrequencyHistory>,
    /// Work statistics.
    pub stats: RunStats,
    /// Warnings about the run's validity (e.g. a small-deflection model near the edge of
    /// its range): written to `summary.json`, printed by the command line.
    pub warnings: Vec<String>,
    /// Finished text files `(name, contents)` written as they are: `viewer.html`,
    /// `snapshots.svg`, `machine.svg` when requested.
    pub documents: Vec<(String, String)>,
    /// What `viewer.html` and `snapshots.svg` draw, when either was requested: the run's
    /// frames mapped to [`flexprr_viewer::ViewerData`] (see docs/viewer.md).
    pub viewer: Option<flexprr_viewer::ViewerData>,
}

impl RunResult {
    /// The table called `name`.
    pub fn table(&self, name: &str) -> Option<&Table> {
        self.tables.iter().find(|t| t.name == name)
    }
}
