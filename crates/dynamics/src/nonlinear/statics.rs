//! A planar beam of co-rotational elements and its static equilibrium (Newton's method
//! with load / displacement increments; Crisfield 1991, vol. 1, chapter 1 and 9).

use nalgebra::{DMatrix, DVector};

use super::element::{CorotationalElement, LocalStrain};
use crate::DynamicsError;

/// Newton iterations allowed per increment.
const NEWTON_ITERATIONS: usize = 50;

/// A planar beam: a chain of co-rotational elements between nodes `0..=elements`, with
/// three coordinates per node `(x, y, psi)` (position and tangent angle), stacked.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanarBeam {
    /// The elements (element `e` joins nodes `e` and `e + 1`).
    pub elements: Vec<CorotationalElement>,
    /// Reference (unloaded, straight) nodal coordinates, `3 (elements + 1)` entries.
    pub reference: Vec<f64>,
}

/// A static equilibrium found by [`PlanarBeam::solve_static`].
#[derive(Debug, Clone, PartialEq)]
pub struct StaticSolution {
    /// Nodal coordinates `(x, y, psi)` per node, stacked.
    pub coordinates: Vec<f64>,
    /// `f_int - f_ext` per coordinate: zero on free coordinates (to the tolerance), the
    /// support reactions' negatives on constrained ones (N, N m).
    pub residual: Vec<f64>,
    /// Newton iterations over all increments.
    pub iterations: usize,
}

impl PlanarBeam {
    /// A straight uniform beam of `length` along the x axis from the origin, in `elements`
    /// equal elements.
    ///
    /// # Errors
    /// Zero elements, or a non-positive or non-finite length or stiffness.
    pub fn straight(
        length: f64,
        axial_stiffness: f64,
        bending_stiffness: f64,
        elements: usize,
    ) -> Result<Self, DynamicsError> {
        for (quantity, value) in [
            ("beam length", length),
            ("axial stiffness EA", axial_stiffness),
            ("bending stiffness EI", bending_stiffness),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(DynamicsError::InvalidParameter {
                    quantity: quantity.into(),
                    value,
                    reason: "must be finite and positive",
                });
            }
        }
        if elements == 0 {
            return Err(DynamicsError::InvalidParameter {
                quantity: "number of beam elements".into(),
                value: 0.0,
                reason: "must be at least 1",
            });
        }
        let le = length / elements as f64;
        let element = CorotationalElement {
            length: le,
            axial_stiffness,
            bending_stiffness,
            strain: LocalStrain::default(),
        };
        let reference = (0..=elements)
            .flat_map(|k| [k as f64 * le, 0.0, 0.0])
            .collect();
        Ok(Self {
            elements: vec![element; elements],
            reference,
        })
    }

    /// The same beam with every element's local strain set to `strain`.
    #[must_use]
    pub fn with_strain(mut self, strain: LocalStrain) -> Self {
        for e in &mut self.elements {
            e.strain = strain;
        }
        self
    }

    /// Number of nodes.
    pub fn nodes(&self) -> usize {
        self.elements.len() + 1
    }

    /// Number of coordinates, `3 nodes`.
    pub fn dofs(&self) -> usize {
        3 * self.nodes()
    }

    fn element_coordinates(q: &[f64], e: usize) -> [f64; 6] {
        std::array::from_fn(|j| q[3 * e + j])
    }

    /// Internal force vector (the strain energy's gradient) at `q` into `f`.
    pub fn internal_force(&self, q: &[f64], f: &mut [f64]) {
        f.fill(0.0);
        for (e, element) in self.elements.iter().enumerate() {
            let (fe, _) = element.internal_force(&Self::element_coordinates(q, e));
            for (j, v) in fe.iter().enumerate() {
                f[3 * e + j] += v;
            }
        }
    }

    /// Assembled tangent stiffness at `q` (dense; for the static solver and checks).
    pub fn tangent(&self, q: &[f64]) -> DMatrix<f64> {
        let n = self.dofs();
        let mut k = DMatrix::zeros(n, n);
        for (e, element) in self.elements.iter().enumerate() {
            let ke = element.tangent(&Self::element_coordinates(q, e));
            for i in 0..6 {
                for j in 0..6 {
                    k[(3 * e + i, 3 * e + j)] += ke[i][j];
                }
            }
        }
        k
    }

    /// Static equilibrium `f_int(q) = f_ext` with coordinates `constrained` held at given
    /// values, by Newton's method in `increments` equal steps: step `k` applies `k /
    /// increments` of the loads and moves the constrained coordinates linearly from their
    /// values in `guess` to their targets. Converged when the free residual is below
    /// `1e-10` of the largest of the loads and reactions (plus an absolute floor), or when a
    /// Newton correction is below `1e-13` of the beam's length (the round-off floor).
    ///
    /// `loads` and `constrained` are `(coordinate index, value)` pairs.
    ///
    /// A cantilever under a small tip load deflects by the linear `P L^3 / (3 EI)`:
    ///
    /// ```
    /// use flexprr_dynamics::nonlinear::PlanarBeam;
    /// let (l, ea, ei, p) = (0.2, 4.38e6, 1.46, 0.1);
    /// let beam = PlanarBeam::straight(l, ea, ei, 8).unwrap();
    /// let tip = 3 * 8;
    /// // Clamp node 0 (x, y, psi), pull the tip down.
    /// let sol = beam
    ///     .solve_static(&beam.reference, &[(0, 0.0), (1, 0.0), (2, 0.0)], &[(tip + 1, -p)], 1)
    ///     .unwrap();
    /// let linear = p * l.powi(3) / (3.0 * ei);
    /// assert!((-sol.coordinates[tip + 1] - linear).abs() < 1e-3 * linear);
    /// ```
    ///
    /// # Errors
    /// A wrong-length guess, an index out of range, a singular tangent or no convergence
    /// (say at which increment, with the residual).
    pub fn solve_static(
        &self,
        guess: &[f64],
        constrained: &[(usize, f64)],
        loads: &[(usize, f64)],
        increments: usize,
    ) -> Result<StaticSolution, DynamicsError> {
        let n = self.dofs();
        if guess.len() != n {
            return Err(DynamicsError::Dimension {
                what: "static guess",
                unit: "coordinates",
                model: "beam",
                found: guess.len(),
                expected: n,
            });
        }
        if let Some((i, _)) = constrained.iter().chain(loads).find(|(i, _)| *i >= n) {
            return Err(DynamicsError::CoordinateIndex {
                index: *i,
                count: n,
            });
        }
        let increments = increments.max(1);
        let mut fixed = vec![false; n];
        for (i, _) in constrained {
            fixed[*i] = true;
        }
        let free: Vec<usize> = (0..n).filter(|i| !fixed[*i]).collect();
        let start: Vec<f64> = constrained.iter().map(|(i, _)| guess[*i]).collect();
        let mut q = guess.to_vec();
        let mut f = vec![0.0; n];
        let mut iterations = 0;
        let size: f64 = self.elements.iter().map(|e| e.length).sum();
        let load_scale = loads.iter().map(|(_, v)| v.abs()).fold(0.0, f64::max);
        for step in 1..=increments {
            let lambda = step as f64 / increments as f64;
            for ((i, target), s) in constrained.iter().zip(&start) {
                q[*i] = s + lambda * (target - s);
            }
            let mut converged = false;
            let mut worst = f64::INFINITY;
            for _ in 0..NEWTON_ITERATIONS {
                self.internal_force(&q, &mut f);
                for (i, v) in loads {
                    f[*i] -= lambda * v;
                }
                let scale = f.iter().map(|v| v.abs()).fold(load_scale, f64::max);
                worst = free.iter().map(|i| f[*i].abs()).fold(0.0, f64::max);
                if worst <= 1e-10 * scale + 1e-12 {
                    converged = true;
                    break;
                }
                let k = self.tangent(&q);
                let kff = DMatrix::from_fn(free.len(), free.len(), |a, b| k[(free[a], free[b])]);
                let rhs = DVector::from_iterator(free.len(), free.iter().map(|i| -f[*i]));
                let dq = kff
                    .lu()
                    .solve(&rhs)
                    .ok_or(DynamicsError::StaticSingular { step, increments })?;
                for (a, i) in free.iter().enumerate() {
                    q[*i] += dq[a];
                }
                iterations += 1;
                // At the round-off floor of the residual (EA times the rounding of the
                // coordinates), a correction below 1e-13 of the beam's size is convergence.
                if dq.amax() <= 1e-13 * size {
                    converged = true;
                    break;
                }
            }
            if !converged {
                return Err(DynamicsError::StaticNewton {
                    step,
                    increments,
                    residual: worst,
                    iterations: NEWTON_ITERATIONS,
                });
            }
        }
        self.internal_force(&q, &mut f);
        for (i, v) in loads {
            f[*i] -= v;
        }
        Ok(StaticSolution {
            coordinates: q,
            residual: f,
            iterations,
        })
    }
}
