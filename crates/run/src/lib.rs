//! Running a flexprr scene: only the requested outputs are computed, then written as CSV
//! tables, `summary.json`, Table I and SVG plots.
//!
//! ```no_run
//! use flexprr_scene::Scene;
//! use flexprr_run::{run, write_outputs};
//! let scene = Scene::load(std::path::Path::new("configs/paper_f20.toml")).unwrap();
//! let result = run(&scene, &mut |_| {}).unwrap();
//! write_outputs(&scene, &result, std::path::Path::new("out/paper_f20")).unwrap();
//! ```

pub mod guard;
mod output;
pub mod plot;
mod run;

pub use output::{summary_json, table_one_markdown, write_outputs};
pub use run::{RunResult, RunStats, Table, integrate, run};
