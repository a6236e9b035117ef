//! What a dense linear analysis of a state of `n` costs, estimated before anything dense is
//! built, and the bound above which it is refused (docs/linear.md, "Cost").
//!
//! A linearisation holds `A` (`n x n`) and, with relaxed chords or a sampled law, a few
//! copies of it; the eigenvalues (balancing, a Hessenberg-Schur QR iteration and the
//! complex eigenvectors, faer) hold about ten more `n x n` real arrays; a frequency response
//! by Laub's method holds the Hessenberg form and a complex work matrix. Measured peak
//! resident memory of `flexprr modes` on the nonlinear model (32 to 128 elements per link,
//! states of 582 to 2316): about `MEMORY_PER_ENTRY` bytes per entry of `A`. The time is
//! dominated by the QR iteration, `O(n^3)`: measured `TIME_PER_CUBE` seconds per `n^3` on
//! the development machine (2 cores, shared): 0.26 / 1.3 / 9.1-13 s at 32 / 64 / 128 elements
//! (states of 582 / 1152 / 2304); peak memory 78 and 272 MB at 64 and 128 elements (59 and
//! 51 bytes per entry).

use crate::LinearError;

/// Peak bytes per entry of `A` of a modal analysis (measured, with margin).
pub const MEMORY_PER_ENTRY: f64 = 80.0;

/// Seconds per `n^3` of a modal analysis (measured on the development machine).
pub const TIME_PER_CUBE: f64 = 1.0e-9;

/// The largest estimated memory of a linear analysis (bytes): 2 GiB.
pub const MAX_MEMORY: f64 = 2.0 * 1024.0 * 1024.0 * 1024.0;

/// The estimated cost of a dense linear analysis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cost {
    /// The state's length.
    pub state: usize,
    /// Peak memory (bytes).
    pub memory_bytes: f64,
    /// Time of the linearisation and the eigenvalues (s, on the development machine).
    pub seconds: f64,
}

/// The cost of a dense analysis of a state of `n` with `outputs` outputs: the relaxed
/// chords add a few coordinates, which the margin covers.
pub fn estimate(n: usize, outputs: usize) -> Cost {
    let size = n as f64;
    Cost {
        state: n,
        memory_bytes: MEMORY_PER_ENTRY * size * size + 8.0 * size * outputs as f64 * 4.0,
        seconds: TIME_PER_CUBE * size * size * size,
    }
}

/// Refuses an analysis whose estimated memory exceeds [`MAX_MEMORY`].
///
/// # Errors
/// [`LinearError::TooLarge`] with the estimate.
pub fn check(n: usize, outputs: usize) -> Result<Cost, LinearError> {
    let cost = estimate(n, outputs);
    if cost.memory_bytes > MAX_MEMORY {
        return Err(LinearError::TooLarge {
            state: n,
            memory_gb: cost.memory_bytes / 1e9,
            seconds: cost.seconds,
            limit_gb: MAX_MEMORY / 1e9,
        });
    }
    Ok(cost)
}
