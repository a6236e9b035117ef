//! Test support for the flexprr workspace: a dev-dependency only, never published.
//!
//! - [`alloc`]: a counting global allocator (per thread) for the "no allocation in right-hand
//!   sides and steppers" tests; each test binary declares the `#[global_allocator]` static
//!   itself, the implementation lives here once.
//! - [`tolerance`]: relative errors and `assert_close`-style checks with a scaled tolerance
//!   (`|a - b| <= atol + rtol |b|`), never `==` on floats.
//! - [`fuzz`]: the deterministic generator of the fuzz tests' mutants.
//! - [`paper`]: the paper's machine, link and trajectory constants (Zhang, Mills & Cleghorn,
//!   the parameters of `docs/model.md`), the workspace's scene files and the independent
//!   reference state at t = 0.2 s.
//!
//! The crate depends on no flexprr crate, so that every crate (the lowest layers included)
//! can take it as a dev-dependency without a cycle.

pub mod alloc;
pub mod csv;
pub mod fuzz;
pub mod paper;
pub mod tolerance;

pub use alloc::{CountingAllocator, allocations, count_allocations};
pub use tolerance::{assert_close, assert_slices_close, max_scaled_error, relative_error};
