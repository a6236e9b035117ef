//! Studies: parameter sweeps over a base scene (any dotted key, lists or ranges, product or
//! zip), run in parallel, resumable and shardable, with derived quantities per case
//! (`docs/studies.md`).

pub mod study;

pub use study::{Study, StudyError, StudyOptions, merge_studies, run_study};
