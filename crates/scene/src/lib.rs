//! Scene files of flexprr: the TOML schema (`docs/scenes.md`), validation with errors that
//! give the file, line, column and key, and the built [`Scene`] that runs, studies and
//! benchmarks all start from.
//!
//! ```no_run
//! use flexprr_scene::Scene;
//! let scene = Scene::load(std::path::Path::new("configs/paper_f20.toml")).unwrap();
//! assert_eq!(scene.name, "paper_f20");
//! ```

mod error;
pub mod link;
mod locate;
mod model;
mod scene;

pub use error::{Location, ScenarioError};
pub use locate::{line_column, locate};
pub use scene::{
    IntegratorConfig, LegConfig, LinksConfig, MachineConfig, Method, ModelConfig, OutputConfig,
    OutputKind, Scene, SceneFile, TimeConfig, TrajectoryConfig, parse_scene, parse_toml,
};
