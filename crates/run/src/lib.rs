//! Running a flexprr scene: the one observed stepping loop, only the requested outputs,
//! then CSV tables, `summary.json`, Table I and SVG plots.
//!
//! ```no_run
//! use flexprr_scene::Scene;
//! use flexprr_run::{run, write_outputs};
//! let scene = Scene::load(std::path::Path::new("configs/paper_f20.toml")).unwrap();
//! let result = run(&scene, &mut |_| {}).unwrap();
//! write_outputs(&scene, &result, std::path::Path::new("out/paper_f20")).unwrap();
//! ```

mod built_in;
pub mod column;
pub mod control;
mod error;
pub mod guard;
mod integrate;
pub mod machine_frequencies;
mod output;
mod outputs;
pub mod piezo;
pub mod plot;
pub mod producer;
pub mod report;
mod run;
mod samples;
mod table;
pub mod variant;
mod viewer;

pub use column::{Column, Quantity};
pub use error::{Collapse, RunError, RunFailure};
pub use flexprr_dynamics::NONLINEAR_ADVICE_FRACTION;
pub use integrate::{Integration, integrate_model, stop_times};
pub use output::{
    RUN_PRODUCTS, WriteOptions, is_rigid, summary_json, table_one_markdown, write_outputs,
    write_outputs_into, write_outputs_with,
};
pub use producer::{OutputContext, OutputProducer, OutputRegistry, SharedProducer};
pub use report::{Report, SharedReport};
pub use run::{integrate, run, run_model, run_registered, scene_integrator};
pub use table::{RunResult, RunStats, Table};
pub use variant::{OnFailure, SceneVariant, VariantRun};
