//! What a run produces: tables of typed columns, the frequency history, work statistics.

use flexprr_dynamics::FrequencyHistory;
use flexprr_integrators::Stats;

pub use flexprr_dynamics::Table;

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
    /// What the features found over the run (control, vibration control, the machine's
    /// frequencies, or reports added from outside), in the order they were added: see
    /// [`crate::report`].
    pub reports: Vec<crate::report::SharedReport>,
    /// The output producers the run asked, in order (see [`crate::producer`]): the writer
    /// draws their figures, studies ask them for quantities by name.
    pub producers: Vec<crate::producer::SharedProducer>,
}

impl RunResult {
    /// The table called `name`.
    pub fn table(&self, name: &str) -> Option<&Table> {
        self.tables.iter().find(|t| t.name == name)
    }

    /// Adds `report`, and its warnings to [`RunResult::warnings`].
    pub fn add_report(&mut self, report: impl crate::report::Report) {
        self.warnings.extend(report.warnings());
        self.reports.push(std::sync::Arc::new(report));
    }

    /// The report called `name`, if the run made one.
    pub fn report_named(&self, name: &str) -> Option<&dyn crate::report::Report> {
        self.reports
            .iter()
            .find(|r| r.name() == name)
            .map(|r| r.as_ref())
    }

    /// The scalar quantity called `name`: from the reports, then from the producers that
    /// made the run's outputs; `None` when none offers it.
    pub fn quantity(&self, name: &str) -> Option<Result<f64, String>> {
        self.reports
            .iter()
            .find_map(|r| r.quantity(name).map(Ok))
            .or_else(|| self.producers.iter().find_map(|p| p.quantity(self, name)))
    }

    /// The report of type `R`, if the run made one.
    pub fn report<R: crate::report::Report>(&self) -> Option<&R> {
        self.reports
            .iter()
            .find_map(|r| r.as_any().downcast_ref::<R>())
    }
}
