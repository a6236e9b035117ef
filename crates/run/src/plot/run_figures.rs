//! The run's figures, drawn by `flexprr-figures` from the tables a result holds: each
//! built-in output's figures ([`crate::OutputProducer::figures`]) and all of them at once
//! ([`run_figures`]).

use flexprr_figures as fig;
use flexprr_scene::Scene;

use super::Figure;
use crate::table::{RunResult, Table};

/// The run's figures as (file name, figure): those of every built-in output, for the tables
/// `result` holds (a figure without data is left out).
pub fn run_figures(scene: &Scene, result: &RunResult) -> Vec<(String, Figure)> {
    let mut out: Vec<_> = crate::OutputRegistry::built_in()
        .producers()
        .iter()
        .flat_map(|p| p.figures(scene, result))
        .collect();
    out.retain(|(_, f)| f.panels.iter().any(|p| !p.series.is_empty()));
    out
}

/// The figures `draw` makes of `result`'s table `name`, none without it.
fn of(
    scene: &Scene,
    result: &RunResult,
    name: &str,
    draw: fn(&Scene, &Table) -> Vec<(String, Figure)>,
) -> Vec<(String, Figure)> {
    result.table(name).map_or_else(Vec::new, |t| draw(scene, t))
}

/// A built-in output's figures from its table.
pub(crate) type Figures = fn(&Scene, &RunResult) -> Vec<(String, Figure)>;

pub(crate) const DEFLECTIONS: Figures = |s, r| of(s, r, "deflections", fig::run::deflections);
pub(crate) const MODES: Figures = |s, r| of(s, r, "modes", fig::run::modes);
pub(crate) const MODAL_FORCES: Figures = |s, r| of(s, r, "modal_forces", fig::run::modal_forces);
pub(crate) const DRIVING_FORCES: Figures =
    |s, r| of(s, r, "driving_forces", fig::run::driving_forces);
pub(crate) const FREQUENCIES: Figures = |s, r| of(s, r, "frequencies", fig::run::frequencies);
pub(crate) const AXIAL_FORCES: Figures = |s, r| of(s, r, "axial_forces", fig::run::axial_forces);
pub(crate) const PLATFORM_DEVIATION: Figures =
    |s, r| of(s, r, "platform_deviation", fig::run::platform_deviation);
pub(crate) const KINEMATICS: Figures = |s, r| of(s, r, "kinematics", fig::run::kinematics);
pub(crate) const ENERGIES: Figures = |s, r| of(s, r, "energies", fig::run::energies);
pub(crate) const MACHINE_FREQUENCIES: Figures =
    |s, r| of(s, r, "machine_frequencies", fig::run::machine_frequencies);
pub(crate) const CONTROL: Figures =
    |s, r| fig::control::figures(s, r.table("tracking"), r.table("actuators"));
pub(crate) const PIEZO: Figures = |s, r| {
    let saturated = (r.report::<crate::piezo::PiezoReport>()).is_some_and(|p| p.any_saturated());
    fig::piezo::figures(s, r.table("piezo"), saturated)
};
pub(crate) const NONE: Figures = |_, _| Vec::new();
