//! The run's figures ([`run_figures`]) and, re-exported, the one plot module of flexprr
//! ([`flexprr_plot`]: [`Figure`], [`Panel`], [`Axis`], [`Series`], ticks, decimation), so
//! that `flexprr_run::plot::Figure` and the like keep working.

pub(crate) mod run_figures;

pub use flexprr_plot::*;
pub use run_figures::run_figures;
