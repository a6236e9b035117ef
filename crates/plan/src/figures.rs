//! The plan's figures.

use flexprr_run::plot::Figure;

use crate::pipeline::PlanOutcome;

/// The figures of a plan: `(file name, figure)`.
pub fn plan_figures(_outcome: &PlanOutcome) -> Vec<(String, Figure)> {
    Vec::new()
}
