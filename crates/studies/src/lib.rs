//! Studies: parameter sweeps over a base scene (any dotted key, lists or ranges, product or
//! zip), run in parallel, resumable and shardable, with derived quantities per case
//! (`docs/studies.md`).
//!
//! Study files are parsed with the scene parser, so a bad value names its file, line, column
//! and key; case records are checked against their case before a resume trusts them.

mod error;
mod file;
pub mod keys;
pub mod map;
mod map_figure;
mod plot;
pub mod quantity;
mod record;
mod runner;
pub mod search;
pub mod study;
mod validate;

pub use study::{
    Plugins, Study, StudyError, StudyOptions, merge_studies, merge_studies_with, run_map_study,
    run_search_study, run_study,
};
