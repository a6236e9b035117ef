//! The figures of a run's tables (`docs/scenes.md`, "Plots"): the paper's figures 6-15, the
//! kinematics, energies and platform deviation ([`run`]), the whole machine's frequencies
//! ([`run::machine_frequencies`]), the control outputs ([`control`]) and the patches
//! ([`piezo`]), each from its table, with the typed names of the columns they read
//! ([`columns`]). It draws numbers with `flexprr-plot`; it knows no run, model or integrator:
//! the run layer hands it the tables.

pub mod columns;
pub mod control;
mod machine_frequencies;
pub mod piezo;
pub mod run;
