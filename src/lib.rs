//! flexprr: planar parallel manipulators with flexible links.
//!
//! The workspace is layered; this root package re-exports each layer under a short name
//! and holds the `flexprr` command-line program.
//!
//! | layer | owns |
//! |---|---|
//! | [`kinematics`](flexprr_kinematics) | 3-PRR geometry, inverse/forward kinematics, singularity measures, trajectories |
//! | [`beam`](flexprr_beam) | assumed-mode bases, sections, Gauss quadrature, modal integrals, single-link analysis |
//! | [`integrators`](flexprr_integrators) | ODE integrators (Adams-Bashforth-Moulton, Dormand-Prince, BDF) behind one trait |
//! | [`dynamics`](flexprr_dynamics) | rigid inverse dynamics, axial forces, the modal system, frequencies |
//! | [`scene`](flexprr_scene) | TOML scene files, validation with located errors, the registry, the model builder |
//! | [`run`](flexprr_run) | the observed stepping loop, outputs on demand, CSV/JSON/SVG writers |
//! | [`studies`](flexprr_studies) | parameter sweeps, resumable and shardable |
//! | [`bench`](flexprr_bench) | work-precision and stress classification |
//!
//! See `docs/architecture.md` for how the layers join.

pub use flexprr_beam;
pub use flexprr_bench;
pub use flexprr_dynamics;
pub use flexprr_integrators;
pub use flexprr_kinematics;
pub use flexprr_run;
pub use flexprr_scene;
pub use flexprr_studies;
