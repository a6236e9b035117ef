//! Hermite cubic finite elements as an assumed-mode basis.

use super::{Basis, EndCondition, EndConditions};
use crate::BeamError;

/// Cubic Hermite (Euler-Bernoulli beam) finite elements on `n` equal elements of `[0, 1]`:
/// nodal deflection `w_i` and slope `dw/dxi` at each of the `n + 1` nodes, the constrained
/// ones removed (pinned: `w = 0`; clamped: `w = 0` and `w' = 0`; free: none).
/// Each remaining nodal degree of freedom is one shape function, so the modal machinery of
/// this crate (`M`, `Kf`, `Gn`) yields the consistent FE mass, bending and geometric
/// stiffness matrices (e.g. Przemieniecki, *Theory of Matrix Structural Analysis*, ch. 5
/// and 15; Cook et al., *Concepts and Applications of FEA*, section 2.4).
/// Eigenvalues converge as `h^4` (`h = 1/n`) for smooth modes.
///
/// Element shape functions on `s = (xi - xi_e)/h in [0, 1]`:
/// `1 - 3s^2 + 2s^3`, `h (s - 2s^2 + s^3)`, `3s^2 - 2s^3`, `h (s^3 - s^2)`.
#[derive(Debug, Clone, PartialEq)]
pub struct HermiteBasis {
    elements: usize,
    ends: EndConditions,
    /// Global degree of freedom (`2 node + {0: value, 1: slope}`) of each basis function.
    dofs: Vec<usize>,
}

impl HermiteBasis {
    /// `elements` elements (`1..=250`) with the given end conditions.
    pub fn new(elements: usize, ends: EndConditions) -> Result<Self, BeamError> {
        if elements == 0 || elements > 250 {
            return Err(BeamError::InvalidCount {
                name: "elements",
                value: elements,
                reason: "must be between 1 and 250",
            });
        }
        let last = 2 * elements;
        let constrained = |dof: usize| -> bool {
            let (condition, node_dof) = if dof < 2 {
                (ends.left, dof)
            } else if dof >= last {
                (ends.right, dof - last)
            } else {
                return false;
            };
            match condition {
                EndCondition::Pinned => node_dof == 0,
                EndCondition::Clamped => true,
                EndCondition::Free => false,
            }
        };
        let dofs: Vec<usize> = (0..2 * (elements + 1))
            .filter(|&d| !constrained(d))
            .collect();
        Ok(Self {
            elements,
            ends,
            dofs,
        })
    }

    /// Pinned-pinned elements (the default, comparable with [`crate::SineBasis`]).
    pub fn pinned_pinned(elements: usize) -> Result<Self, BeamError> {
        Self::new(elements, EndConditions::PINNED_PINNED)
    }

    /// Number of elements.
    pub fn elements(&self) -> usize {
        self.elements
    }

    /// The end conditions.
    pub fn ends(&self) -> EndConditions {
        self.ends
    }
}

impl Basis for HermiteBasis {
    fn len(&self) -> usize {
        self.dofs.len()
    }

    fn eval(&self, j: usize, xi: f64) -> [f64; 3] {
        let dof = self.dofs[j];
        let node = dof / 2;
        let n = self.elements;
        let h = 1.0 / n as f64;
        // Element containing xi (the right one at an interior node: the second derivative
        // jumps there, and quadrature never samples nodes).
        let element = ((xi * n as f64).floor().max(0.0) as usize).min(n - 1);
        let local = if node == element {
            0
        } else if node == element + 1 {
            2
        } else {
            return [0.0; 3];
        } + dof % 2;
        let s = (xi - element as f64 * h) / h;
        let (s2, s3) = (s * s, s * s * s);
        match local {
            0 => [
                1.0 - 3.0 * s2 + 2.0 * s3,
                (-6.0 * s + 6.0 * s2) / h,
                (-6.0 + 12.0 * s) / (h * h),
            ],
            1 => [
                h * (s - 2.0 * s2 + s3),
                1.0 - 4.0 * s + 3.0 * s2,
                (-4.0 + 6.0 * s) / h,
            ],
            2 => [
                3.0 * s2 - 2.0 * s3,
                (6.0 * s - 6.0 * s2) / h,
                (6.0 - 12.0 * s) / (h * h),
            ],
            _ => [h * (s3 - s2), -2.0 * s + 3.0 * s2, (-2.0 + 6.0 * s) / h],
        }
    }

    fn name(&self) -> String {
        format!(
            "Hermite cubic FE ({}), {} elements, r = {}",
            self.ends.name(),
            self.elements,
            self.dofs.len()
        )
    }

    fn polynomial_degree(&self) -> Option<usize> {
        Some(3)
    }

    fn breakpoints(&self) -> Vec<f64> {
        (1..self.elements)
            .map(|i| i as f64 / self.elements as f64)
            .collect()
    }
}
