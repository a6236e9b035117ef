//! The KED modal equations in the linear time-varying form of
//! [`flexprr_integrators::LinearSecondOrder`], for the exponential (Magnus) integrators.
//!
//! For link `i` (model.md section 6, eq. 16 of the paper) the modal equations are
//!
//! ```text
//! M eta'' + C eta' + (Kf + c0 G0' + c1 G1' + c2 G2' - s M) eta = a m_psi + b l m_xipsi
//! ```
//!
//! with `c0 = P0 / l`, `c1 = P1`, `c2 = P2 l` from the axial force, `s = beta'^2` when the
//! centrifugal softening is on, `G_n' = G_n` (full `Kp`) or its diagonal (the paper's),
//! `a = -rho'' sin(a - b) (+ rho' beta' cos(a - b) with F_fg)` and `b = -beta''`. In the
//! unloaded modal coordinates `eta = Phi x` with `Phi` the `M`-orthonormal eigenvectors of
//! `(Kf, M)` (Golub & Van Loan, *Matrix Computations*, 8.7.2: `M = L L^T`,
//! `L^-1 Kf L^-T = U Lambda U^T`, `Phi = L^-T U`) this becomes
//!
//! ```text
//! x'' + Phi^T C Phi x' + (Lambda + sum_n c_n Phi^T G_n' Phi - s I) x = a Phi^T m_psi + b l Phi^T m_xipsi
//! ```
//!
//! with symmetric stiffness terms and a diagonal damping (`Phi^T C Phi = diag(2 zeta_j
//! omega_j)`), for any basis (sine modes or Hermite elements) and any formulation. The map
//! back is `x = Phi^T M eta`. Each link is one block.

use faer::{Mat, Side};
use flexprr_integrators::{BlockOperators, LinearSecondOrder};

use crate::modal::{damping_matrix, forward_substitute, to_row_major};
use crate::{DynamicsError, ModalSystem};

/// Number of stiffness terms per link: `Kf`, `G0`, `G1`, `G2` and the softening `-I`.
const STIFFNESS_TERMS: usize = 5;
/// Number of forcing terms per link: the `rho''` and `beta''` inertia forces.
const FORCING_TERMS: usize = 2;

/// `Phi` (the `M`-orthonormal unloaded modes) and `M` of link `index`, or why not.
fn unloaded_modes(system: &ModalSystem, index: usize) -> Result<Mat<f64>, DynamicsError> {
    let ints = &system.machine.links[index].integrals;
    let r = ints.r();
    let llt = ints
        .mass
        .llt(Side::Lower)
        .map_err(|_| DynamicsError::ModalMass { link: index + 1 })?;
    let l = llt.L().to_owned();
    let mut x = ints.stiffness.clone();
    forward_substitute(&l, &mut x); // L^-1 Kf
    let mut a = x.transpose().to_owned();
    forward_substitute(&l, &mut a); // L^-1 Kf L^-T
    let a = Mat::from_fn(r, r, |i, j| 0.5 * (a[(i, j)] + a[(j, i)]));
    let eig = a
        .self_adjoint_eigen(Side::Lower)
        .map_err(|_| DynamicsError::Eigen { link: index + 1 })?;
    // Phi = L^-T U by back substitution with L^T, column by column.
    let u = eig.U();
    let mut phi = Mat::zeros(r, r);
    for c in 0..r {
        for i in (0..r).rev() {
            let mut sum = u[(i, c)];
            for p in i + 1..r {
                sum -= l[(p, i)] * phi[(p, c)];
            }
            phi[(i, c)] = sum / l[(i, i)];
        }
    }
    Ok(phi)
}

/// `Phi^T A Phi`, symmetrized, row-major.
fn project(phi: &Mat<f64>, a: &Mat<f64>) -> Vec<f64> {
    let p = phi.transpose() * a * phi;
    let r = p.nrows();
    to_row_major(&Mat::from_fn(r, r, |i, j| 0.5 * (p[(i, j)] + p[(j, i)])))
}

impl ModalSystem {
    /// The operators of link `index` in its unloaded modal coordinates (see the
    /// [module](self) docs).
    ///
    /// # Errors
    /// A mass matrix that is not positive definite, a failed eigen-decomposition, or
    /// inconsistent damping.
    pub fn linear_operators(&self, index: usize) -> Result<BlockOperators, DynamicsError> {
        let link = &self.machine.links[index];
        let ints = &link.integrals;
        let r = ints.r();
        let phi = unloaded_modes(self, index)?;
        let geometric = |n: usize| -> Mat<f64> {
            let g = &ints.g[n];
            match self.formulation.geometric_stiffness {
                flexprr_beam::Coupling::Full => g.clone(),
                flexprr_beam::Coupling::Diagonal => {
                    Mat::from_fn(r, r, |i, j| if i == j { g[(i, i)] } else { 0.0 })
                }
            }
        };
        let minus_identity = {
            let mut m = vec![0.0; r * r];
            for i in 0..r {
                m[i * r + i] = -1.0;
            }
            m
        };
        let stiffness = vec![
            project(&phi, &ints.stiffness),
            project(&phi, &geometric(0)),
            project(&phi, &geometric(1)),
            project(&phi, &geometric(2)),
            minus_identity,
        ];
        let phi_t_times = |v: &[f64], scale: f64| -> Vec<f64> {
            (0..r)
                .map(|j| scale * (0..r).map(|k| phi[(k, j)] * v[k]).sum::<f64>())
                .collect()
        };
        let forcing = vec![
            phi_t_times(&ints.mass_psi, 1.0),
            phi_t_times(&ints.mass_xi_psi, ints.length),
        ];
        let damping = damping_matrix(link, &self.damping, index)?.map(|c| project(&phi, &c));
        let inverse = phi.transpose() * &ints.mass;
        Ok(BlockOperators {
            size: r,
            stiffness,
            forcing,
            damping,
            transform: Some((to_row_major(&phi), to_row_major(&inverse))),
        })
    }
}

impl LinearSecondOrder for ModalSystem {
    fn block_count(&self) -> usize {
        3
    }

    /// The link's operators; if they cannot be formed (which [`ModalSystem::new`] already
    /// rules out), NaN operators that the integrator rejects at start.
    fn block_operators(&self, block: usize) -> BlockOperators {
        self.linear_operators(block).unwrap_or_else(|_| {
            let r = self.machine.links[block].integrals.r();
            BlockOperators {
                size: r,
                stiffness: vec![vec![f64::NAN; r * r]],
                ..BlockOperators::default()
            }
        })
    }

    /// Per link: stiffness coefficients `(1, P0 / l, P1, P2 l, beta'^2 or 0)` and forcing
    /// coefficients `(-rho'' sin(a - b) [+ rho' beta' cos(a - b)], -beta'')`, from the
    /// inverse kinematics (and the rigid inverse dynamics if the axial model needs it).
    fn coefficients(&mut self, t: f64, stiffness: &mut [f64], forcing: &mut [f64]) {
        let fail = |system: &mut Self, e: DynamicsError, s: &mut [f64], f: &mut [f64]| {
            system.failure = Some(e);
            s.fill(f64::NAN);
            f.fill(f64::NAN);
        };
        let mut state = flexprr_kinematics::MachineKinematics::default();
        if let Err(e) = self.kinematic_state(t, &mut state) {
            return fail(self, e, stiffness, forcing);
        }
        let loads = match self.axial_loads(&state, t) {
            Ok((_, loads)) => loads,
            Err(e) => return fail(self, e, stiffness, forcing),
        };
        for i in 0..3 {
            let leg = &state.legs[i];
            let u = self.machine.geometry.legs[i].guide.direction.into_inner();
            let length = self.machine.links[i].integrals.length;
            let load = &loads[i];
            let s = &mut stiffness[i * STIFFNESS_TERMS..(i + 1) * STIFFNESS_TERMS];
            s[0] = 1.0;
            s[1] = load.p0 / length;
            s[2] = load.p1;
            s[3] = load.p2 * length;
            s[4] = if self.formulation.centrifugal_softening {
                leg.beta_dot * leg.beta_dot
            } else {
                0.0
            };
            let mut rho_coef = -leg.rho_ddot * u.dot(&leg.n);
            if self.formulation.coriolis_forcing {
                rho_coef += leg.rho_dot * leg.beta_dot * u.dot(&leg.e);
            }
            forcing[i * FORCING_TERMS] = rho_coef;
            forcing[i * FORCING_TERMS + 1] = -leg.beta_ddot;
        }
    }
}
