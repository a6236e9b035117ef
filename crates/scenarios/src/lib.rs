//! The user-facing layer of flexprr: TOML scene files, running a scene with only the
//! requested outputs, and writing CSV tables, `summary.json` and SVG plots.
//!
//! ```no_run
//! use flexprr_scenarios::{Scene, run, write_outputs};
//! let scene = Scene::load(std::path::Path::new("configs/paper_f20.toml")).unwrap();
//! let result = run(&scene, &mut |_| {}).unwrap();
//! write_outputs(&scene, &result, std::path::Path::new("out/paper_f20")).unwrap();
//! ```

pub mod classify;
mod error;
pub mod link;
mod locate;
mod output;
pub mod plot;
mod run;
mod scene;
pub mod study;
pub mod work_precision;

pub use error::{Location, ScenarioError};
pub use locate::{line_column, locate};
pub use output::{summary_json, table_one_markdown, write_outputs};
pub use run::{RunResult, RunStats, Table, integrate, run};
pub use scene::{
    IntegratorConfig, LegConfig, LinksConfig, MachineConfig, Method, ModelConfig, OutputConfig,
    OutputKind, Scene, SceneFile, TimeConfig, TrajectoryConfig, parse_scene, parse_toml,
};
pub use study::{Study, StudyError, StudyOptions, merge_studies, run_study};
