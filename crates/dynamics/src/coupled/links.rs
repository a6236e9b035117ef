//! Per-link constants of the coupled model, formed once per system.

use faer::{Mat, Side};

use super::dot;
use crate::{DynamicsError, ModalDamping};

/// Per-link constants, matrices row-major `r x r`; `inv_*` have `M^-1` applied.
#[derive(Debug, Clone)]
pub(super) struct LinkData {
    pub(super) r: usize,
    pub(super) length: f64,
    pub(super) mass: f64,
    /// Inertia about `B`: `I_G + m l^2 / 4` (kg m^2).
    pub(super) inertia_b: f64,
    /// `G0` (for `delta` and `dL / d eta`).
    pub(super) g0: Vec<f64>,
    pub(super) inv_flexural: Vec<f64>,
    pub(super) inv_geometric: [Vec<f64>; 3],
    pub(super) inv_damping: Vec<f64>,
    pub(super) mass_psi: Vec<f64>,
    pub(super) mass_xi_psi: Vec<f64>,
    pub(super) inv_mass_psi: Vec<f64>,
    pub(super) inv_mass_xi_psi: Vec<f64>,
    /// `m_xipsi . M^-1 m_xipsi`.
    pub(super) xi_psi_inv_xi_psi: f64,
    /// `psi_j(1/2)`.
    pub(super) psi_mid: Vec<f64>,
}

impl LinkData {
    pub(super) fn new(
        link: &crate::LinkModel,
        damping: &ModalDamping,
        index: usize,
    ) -> Result<Self, DynamicsError> {
        use faer::linalg::solvers::DenseSolveCore;
        let ints = &link.integrals;
        let r = ints.r();
        let l = ints.length;
        let m = ints.total_mass;
        let m_inv = ints
            .mass
            .llt(Side::Lower)
            .map_err(|_| DynamicsError::ModalMass { link: index + 1 })?
            .inverse();
        let apply = |a: &Mat<f64>| crate::modal::to_row_major(&(&m_inv * a));
        let apply_vec = |v: &[f64]| -> Vec<f64> {
            (0..r)
                .map(|i| (0..r).map(|k| m_inv[(i, k)] * v[k]).sum())
                .collect()
        };
        let damping = crate::modal::damping_matrix(link, damping, index)?
            .map_or_else(|| vec![0.0; r * r], |c| crate::modal::to_row_major(&c));
        let damping = Mat::from_fn(r, r, |i, j| damping[i * r + j]);
        let inv_mass_xi_psi = apply_vec(&ints.mass_xi_psi);
        Ok(Self {
            r,
            length: l,
            mass: m,
            inertia_b: link.centroid_inertia + 0.25 * m * l * l,
            g0: crate::modal::to_row_major(&ints.g[0]),
            inv_flexural: apply(&ints.stiffness),
            inv_geometric: std::array::from_fn(|n| apply(&ints.g[n])),
            inv_damping: apply(&damping),
            mass_psi: ints.mass_psi.clone(),
            xi_psi_inv_xi_psi: dot(&ints.mass_xi_psi, &inv_mass_xi_psi),
            mass_xi_psi: ints.mass_xi_psi.clone(),
            inv_mass_psi: apply_vec(&ints.mass_psi),
            inv_mass_xi_psi,
            psi_mid: (0..r).map(|j| link.basis.eval(j, 0.5)[0]).collect(),
        })
    }
}
