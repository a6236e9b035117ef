//! Pinned-pinned sine modes (the paper's basis, model.md eq. 1).

use super::{Basis, check_mode_count};
use crate::BeamError;
use std::f64::consts::PI;

/// `psi_j(xi) = sin(j pi xi)`, `j = 1..r`: the exact free-vibration modes of a uniform
/// pinned-pinned Euler-Bernoulli beam, as used by Zhang, Mills & Cleghorn (eq. 1).
/// Normalisation: `int_0^1 psi_j^2 dxi = 1/2`.
#[derive(Debug, Clone, PartialEq)]
pub struct SineBasis {
    r: usize,
}

impl SineBasis {
    /// `r` sine modes (`1 <= r <= 500`).
    pub fn new(r: usize) -> Result<Self, BeamError> {
        check_mode_count(r)?;
        Ok(Self { r })
    }
}

impl Basis for SineBasis {
    fn len(&self) -> usize {
        self.r
    }

    fn eval(&self, j: usize, xi: f64) -> [f64; 3] {
        assert!(
            j < self.r,
            "sine mode index {j} out of range (r = {})",
            self.r
        );
        let k = (j + 1) as f64 * PI;
        let (s, c) = (k * xi).sin_cos();
        [s, k * c, -k * k * s]
    }

    fn name(&self) -> String {
        format!("sine (pinned-pinned), r = {}", self.r)
    }

    fn max_wavenumber(&self) -> f64 {
        self.r as f64 * PI
    }
}
