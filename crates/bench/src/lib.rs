//! Benchmarking flexprr (not published): work-precision measurements of the integrators on a
//! scene (`flexprr work-precision`, `docs/performance.md`) and the classification of how an
//! integrator copes with a stress scene (`docs/stability.md`).

pub mod classify;
pub mod work_precision;
