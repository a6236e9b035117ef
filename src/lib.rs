//! flexprr: planar parallel manipulators with flexible links.
//!
//! The workspace is layered; this root package re-exports each layer under a short name
//! and holds the `flexprr` command-line program.
//!
//! | layer | owns |
//! |---|---|
//! | [`kinematics`] | 3-PRR geometry, inverse/forward kinematics, singularity measures, trajectories |
//! | [`beam`] | assumed-mode bases, sections, Gauss quadrature, modal integrals, single-link analysis |
//! | [`integrators`] | ODE integrators (Adams-Bashforth-Moulton, Dormand-Prince, BDF) behind one trait |
//! | [`dynamics`] | rigid inverse dynamics, axial forces, the modal system, frequencies |
//! | [`scenarios`] | TOML scenes and studies, outputs, plots |
//!
//! See `docs/architecture.md` for how the layers join.

pub use flexprr_beam;
pub use flexprr_dynamics;
pub use flexprr_integrators;
pub use flexprr_kinematics;
pub use flexprr_scenarios;
