//! `flexprr plan` as a library (docs/planning.md): a scene with a `[plan]` section re-timed
//! time-optimally along its path within every limit ([`flexprr_planning`]), with the
//! platform's orientation searched and the motion shaped on the machine's lowest modes when
//! asked, checked on the scene's own flexible model for its residual vibration, and written
//! back as a runnable scene.
//!
//! ```no_run
//! use flexprr_plan::{Options, plan_scene};
//! let scene = flexprr_scene::Scene::load(std::path::Path::new("configs/plan_pick_and_place.toml"))?;
//! let outcome = plan_scene(&scene, Options::default(), &mut |stage| eprintln!("{stage}"))?;
//! println!("{} s", outcome.plan.duration);
//! let planned = outcome.planned_scene()?; // runs with flexprr_run::run
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod deflection;
mod error;
mod figures;
mod pipeline;
mod report;
mod summary;
mod variant;
mod vibration;
mod write;

pub use deflection::{DeflectionSearch, MAX_STRETCH, Probe, STRETCH_TOLERANCE, peak_deflection};
pub use error::PlanError;
pub use figures::plan_figures;
pub use pipeline::{
    DEFAULT_SETTLE_TIME, Options, OrientationSearch, PlanOutcome, SceneTiming, plan_scene,
};
pub use report::plan_report;
pub use summary::{PlanSummary, plan_run};
pub use variant::{Unshaped, planned_scene_file, scene_toml, unshaped};
pub use vibration::{
    FlexibleCheck, MODE_POSES, ModesAt, MotionVibration, ShapedMode, ShapingDesign, design_shaper,
    vibration_of,
};
pub use write::{PLAN_PRODUCTS, PLANNED_RUN_DIR, write_files, write_plan};
