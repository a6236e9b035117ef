//! The accelerations of one evaluation: the low-rank reduction of `A eta'' = g` (and, for
//! sliders that are degrees of freedom, of their equations of motion).

use nalgebra::Vector3;

use super::kinetics::Kinetics;
use super::links::LinkData;
use super::{CoupledSystem, Scratch, dot, mat_vec_acc, solve_in_place};
use crate::DynamicsError;

/// The projections of the accelerations that the reduced system solves for:
/// `s_j = dL_j . eta_j''`, `m_j = m_xipsi_j . eta_j''` and the slider accelerations
/// `r_j = rho_j''` (zero increments when the sliders are prescribed).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Projections {
    pub(super) s: Vector3<f64>,
    pub(super) m: Vector3<f64>,
    pub(super) r: Vector3<f64>,
}

/// One link's vectors of the reduction: `a` (accelerations at zero projections), `h`
/// (their change per unit slider acceleration), and the projections of `a`, `h`,
/// `p = M^-1 m_xipsi` and `q = M^-1 G0 eta / l` on a direction `v` (`dL`, `m_xipsi`, `m_psi`).
#[derive(Debug, Clone, Copy, Default)]
struct Projected {
    a: f64,
    h: f64,
    p: f64,
    q: f64,
}

/// Row `row` of the reduced system for the projection of `eta_i''` on a direction `v`:
/// `v . eta_i'' = v.a + (v.h) r_i - l (v.p) (Bs s + Br r)_i - (v.q) (Ts s + Tm m + Tr r)_i`,
/// written as `coefficient . (s, m, r) = rhs`, scaled by `sign` (the projection itself,
/// when it is one of the unknowns, adds its identity column `own`).
fn projection_row(
    w: &mut [f64],
    unknowns: usize,
    kin: &Kinetics,
    i: usize,
    length: f64,
    v: &Projected,
    sign: f64,
) {
    for col in 0..3 {
        w[col] += sign * (v.p * length * kin.beta_s[(i, col)] + v.q * kin.tension_s[(i, col)]);
        w[3 + col] += sign * v.q * kin.tension_m[(i, col)];
        if unknowns == 9 {
            let own = if col == i { v.h } else { 0.0 };
            w[6 + col] +=
                sign * (-own + v.p * length * kin.beta_r[(i, col)] + v.q * kin.tension_r[(i, col)]);
        }
    }
}

impl CoupledSystem {
    /// The accelerations `a_i` of link `i` at zero projections (`M eta_i'' = g_i` with
    /// `b'' = beta_0`, `T = T_0` and the known slider acceleration), into `out`, and their
    /// change per unit slider acceleration `h_i = -sin(a - b) M^-1 m_psi +
    /// rhoA cos(a - b) (l q_i - M^-1 G1 eta_i)` into `h` (the slider's acceleration enters the
    /// forcing and the axial force `N(x)`; docs/control.md).
    #[allow(clippy::too_many_arguments)]
    fn free_accelerations(
        link: &LinkData,
        kin: &Kinetics,
        i: usize,
        e: &[f64],
        ed: &[f64],
        q: &[f64],
        out: &mut [f64],
        h: &mut [f64],
    ) {
        let rho_a = link.mass / link.length;
        let (rho_ddot, b_dot) = (kin.rho[i][2], kin.beta_dot[i]);
        // Axial force N(x) = T + P0' + P1 x + P2 x^2 with the tension T at C unknown.
        let p1 = rho_a * rho_ddot * kin.cos_ab[i];
        let p2 = -0.5 * rho_a * b_dot * b_dot;
        let p0_known = -(p1 * link.length + p2 * link.length * link.length);
        let t0 = kin.tension0[i] + p0_known;
        for (j, aj) in out.iter_mut().enumerate() {
            *aj = -link.inv_mass_psi[j] * rho_ddot * kin.sin_ab[i]
                - link.length * link.inv_mass_xi_psi[j] * kin.beta0[i]
                - t0 * q[j]
                + b_dot * b_dot * e[j];
        }
        mat_vec_acc(&link.inv_flexural, e, -1.0, out);
        mat_vec_acc(&link.inv_geometric[1], e, -p1, out);
        mat_vec_acc(&link.inv_geometric[2], e, -p2 * link.length, out);
        mat_vec_acc(&link.inv_damping, ed, -1.0, out);
        if h.is_empty() {
            return;
        }
        let axial = rho_a * kin.cos_ab[i];
        for (j, hj) in h.iter_mut().enumerate() {
            *hj = -link.inv_mass_psi[j] * kin.sin_ab[i] + axial * link.length * q[j];
        }
        mat_vec_acc(&link.inv_geometric[1], e, -axial, h);
    }

    /// Solves for the accelerations: `eta''` into `scratch.acceleration`, and the
    /// projections `(s, m)` and, for actuated sliders (`forces` their actuator forces, N),
    /// the slider accelerations `r`.
    ///
    /// For link `i`, `M eta_i'' = g_i - l m_xipsi_i b_i'' - (G0 eta_i / l) T_i` with
    /// `b'' = beta_0 + Bs s + Br r` and `T = T_0 + Ts s + Tm m + Tr r`, so
    /// The configuration-dependent mass matrix `A(eta, t)` of `A eta'' = g` (row-major
    /// `n x n`; allocating, for inspection and tests): block `(i, j)` is
    /// `delta_ij M + l m_xipsi_i (Bs_ij dL_j^T) + (G0 eta_i / l)(Ts_ij dL_j^T + Tm_ij m_xipsi_j^T)`
    /// (docs/coupled.md). Lagrange's equations make it symmetric: the platform's and chords'
    /// inertia enter through `dq / d eta` and `d b / d eta` on both sides.
    ///
    /// # Errors
    /// As [`CoupledSystem::modal_accelerations`].
    pub fn mass_matrix(&mut self, t: f64, y: &[f64]) -> Result<Vec<f64>, DynamicsError> {
        self.check_state(y)?;
        if self.actuated.is_some() {
            return Err(DynamicsError::ActuatedMassMatrix);
        }
        let kin = self.kinetics(t, y)?;
        let n = self.modes;
        let mut a = vec![0.0; n * n];
        for (i, link) in self.links.iter().enumerate() {
            let (off, r) = (self.offsets[i], link.r);
            let mass = &self.machine.links[i].integrals.mass;
            for j in 0..r {
                let row = (off + j) * n;
                for k in 0..r {
                    a[row + off + k] = mass[(j, k)];
                }
                let lx = link.length * link.mass_xi_psi[j];
                let kj = self.scratch.g0_eta[off + j];
                for (c, other) in self.links.iter().enumerate() {
                    let oc = self.offsets[c];
                    let ws = lx * kin.beta_s[(i, c)] + kj * kin.tension_s[(i, c)];
                    let wm = kj * kin.tension_m[(i, c)];
                    for k in 0..other.r {
                        a[row + oc + k] +=
                            ws * self.scratch.length_gradient[oc + k] + wm * other.mass_xi_psi[k];
                    }
                }
            }
        }
        Ok(a)
    }

    /// `eta_i'' = a_i + h_i r_i - l p_i (Bs s + Br r)_i - q_i (Ts s + Tm m + Tr r)_i` with
    /// `p_i = M^-1 m_xipsi_i` and `q_i = M^-1 G0 eta_i / l`. Projecting on `dL_i` and
    /// `m_xipsi_i` gives 6 equations for `(s, m)` (the Sherman-Morrison-Woodbury reduction of
    /// the `n x n` system, Golub & Van Loan, *Matrix Computations*, 4th ed., 2.1.4); an
    /// actuated slider adds its equation of motion `(m_s + m_r) r_i = F_i - F_B_i . u_i`, in
    /// which the force of the slider on the link `F_B_i` is linear in the same unknowns and
    /// in `k_i = m_psi_i . eta_i''` (docs/control.md). Cost linear in the modes per
    /// right-hand side after the `r x r` products; nothing is allocated.
    pub(super) fn solve_accelerations(
        &mut self,
        t: f64,
        y: &[f64],
        kin: &Kinetics,
        forces: Option<&[f64; 3]>,
    ) -> Result<Projections, DynamicsError> {
        let unknowns = if forces.is_some() { 9 } else { 6 };
        let (eta, eta_dot) = self.elastic_state(y);
        if let Some(patches) = self.patches.as_mut() {
            self.scratch.patch.fill(0.0);
            patches.accelerate(t, eta, eta_dot, &mut self.scratch.patch);
        }
        let with_patches = self.patches.is_some();
        let Scratch {
            inv_g0_eta,
            length_gradient,
            acceleration,
            slider_change,
            patch,
            ..
        } = &mut self.scratch;
        let slider_mass: [f64; 3] = self
            .actuated
            .as_ref()
            .map_or(self.machine.slider_mass, |a| a.slider_mass);
        let mut w = [0.0; 81];
        let mut c = [0.0; 9];
        for (i, link) in self.links.iter().enumerate() {
            let (off, r) = (self.offsets[i], link.r);
            let (e, ed) = (&eta[off..off + r], &eta_dot[off..off + r]);
            let q = &inv_g0_eta[off..off + r];
            let a = &mut acceleration[off..off + r];
            let h = if unknowns == 9 {
                &mut slider_change[off..off + r]
            } else {
                &mut slider_change[off..off]
            };
            Self::free_accelerations(link, kin, i, e, ed, q, a, h);
            if !self.loads.modal.is_empty() {
                for (aj, load) in a.iter_mut().zip(&self.loads.modal[off..off + r]) {
                    *aj += load;
                }
            }
            if with_patches {
                for (aj, piezo) in a.iter_mut().zip(&patch[off..off + r]) {
                    *aj += piezo;
                }
            }
            let (a, h) = (&*a, &*h);
            let project = |v: &[f64]| Projected {
                a: dot(v, a),
                h: if h.is_empty() { 0.0 } else { dot(v, h) },
                p: dot(v, &link.inv_mass_xi_psi),
                q: dot(v, q),
            };
            let along = project(&length_gradient[off..off + r]);
            let moment = Projected {
                p: link.xi_psi_inv_xi_psi,
                ..project(&link.mass_xi_psi)
            };
            let (row_s, row_m) = (i * unknowns, (3 + i) * unknowns);
            w[row_s + i] = 1.0;
            w[row_m + 3 + i] = 1.0;
            projection_row(
                &mut w[row_s..row_s + unknowns],
                unknowns,
                kin,
                i,
                link.length,
                &along,
                1.0,
            );
            projection_row(
                &mut w[row_m..row_m + unknowns],
                unknowns,
                kin,
                i,
                link.length,
                &moment,
                1.0,
            );
            c[i] = along.a;
            c[3 + i] = moment.a;
            if let Some(forces) = forces {
                let row = (6 + i) * unknowns;
                let inertia = project(&link.mass_psi);
                let slider = Slider {
                    link,
                    mass: slider_mass[i],
                    elastic_reactions: self.options.elastic_reactions,
                    // The slider's own load, and the transverse loads on the link seen along
                    // the guide (the slider carries `-F n` of them: `F_B . u` loses `F sin`).
                    load: self.loads.slider[i] + self.loads.transverse[i] * kin.sin_ab[i],
                };
                c[6 + i] = slider.row(
                    &mut w[row..row + unknowns],
                    kin,
                    i,
                    e,
                    ed,
                    &inertia,
                    forces[i],
                );
            }
        }
        let z = self.solve_projections(t, &mut w, &mut c, unknowns)?;
        self.reconstruct(kin, &z, unknowns == 9);
        Ok(z)
    }

    /// Solves the reduced system `w z = c` (6 unknowns `(s, m)`, or 9 with the sliders'
    /// accelerations `r`) in place.
    fn solve_projections(
        &mut self,
        t: f64,
        w: &mut [f64; 81],
        c: &mut [f64; 9],
        unknowns: usize,
    ) -> Result<Projections, DynamicsError> {
        self.counters.acceleration_solves += 1;
        solve_in_place(&mut w[..unknowns * unknowns], &mut c[..unknowns])
            .map_err(|column| DynamicsError::SingularMass { t, column })?;
        Ok(Projections {
            s: Vector3::new(c[0], c[1], c[2]),
            m: Vector3::new(c[3], c[4], c[5]),
            r: if unknowns == 9 {
                Vector3::new(c[6], c[7], c[8])
            } else {
                Vector3::zeros()
            },
        })
    }

    /// `eta_i'' = a_i + h_i r_i - l p_i (Bs s + Br r)_i - q_i (Ts s + Tm m + Tr r)_i` in
    /// `scratch.acceleration` (which holds `a`).
    fn reconstruct(&mut self, kin: &Kinetics, z: &Projections, actuated: bool) {
        let bs = kin.beta_s * z.s + kin.beta_r * z.r;
        let tsm = kin.tension_s * z.s + kin.tension_m * z.m + kin.tension_r * z.r;
        let Scratch {
            inv_g0_eta,
            acceleration,
            slider_change,
            ..
        } = &mut self.scratch;
        for (i, link) in self.links.iter().enumerate() {
            let (off, r) = (self.offsets[i], link.r);
            let q = &inv_g0_eta[off..off + r];
            let a = &mut acceleration[off..off + r];
            let lb = link.length * bs[i];
            for j in 0..r {
                a[j] -= lb * link.inv_mass_xi_psi[j] + tsm[i] * q[j];
                if actuated {
                    a[j] += slider_change[off + j] * z.r[i];
                }
            }
        }
    }
}

/// A slider that is a degree of freedom, for its row of the reduced system.
struct Slider<'a> {
    link: &'a LinkData,
    /// Slider mass plus the actuator's reflected mass (kg).
    mass: f64,
    elastic_reactions: bool,
    /// External load along the guide (N).
    load: f64,
}

impl Slider<'_> {
    /// Row of slider `i`'s equation of motion `(m_s + m_r) r_i + F_B_i . u_i = F_i` in the
    /// unknowns `(s, m, r)`; returns its right-hand side. With `F_C = T e + S n` and the
    /// link's inertia force,
    ///
    /// ```text
    /// F_B . u = m r + c_b b'' + sin(a - b) k - cos(a - b) T - sin(a - b) S + c_0
    /// c_b = (m l / 2) sin(a - b) - cos(a - b) m_psi.eta
    /// c_0 = -(m l / 2) b'^2 cos(a - b) - b'^2 sin(a - b) m_psi.eta - 2 b' cos(a - b) m_psi.eta'
    /// ```
    ///
    /// with `k = m_psi . eta''` (projected like `s` and `m`).
    #[allow(clippy::too_many_arguments)]
    fn row(
        &self,
        w: &mut [f64],
        kin: &Kinetics,
        i: usize,
        e: &[f64],
        ed: &[f64],
        inertia: &Projected,
        force: f64,
    ) -> f64 {
        let link = self.link;
        let (mass, l) = (link.mass, link.length);
        let (sin_ab, cos_ab, b_dot) = (kin.sin_ab[i], kin.cos_ab[i], kin.beta_dot[i]);
        let (m_psi_eta, m_psi_rate) = (dot(&link.mass_psi, e), dot(&link.mass_psi, ed));
        let c_b = 0.5 * mass * l * sin_ab - cos_ab * m_psi_eta;
        let c_0 = -0.5 * mass * l * b_dot * b_dot * cos_ab
            - b_dot * b_dot * sin_ab * m_psi_eta
            - 2.0 * b_dot * cos_ab * m_psi_rate;
        let slider_mass = self.mass;
        let elastic = if self.elastic_reactions {
            l / kin.lengths[i]
        } else {
            0.0
        };
        // k_i = m_psi . eta_i'' in the unknowns, times sin(a - b).
        projection_row(w, 9, kin, i, l, inertia, -sin_ab);
        w[6 + i] += slider_mass + mass;
        for col in 0..3 {
            w[col] += c_b * kin.beta_s[(i, col)]
                - cos_ab * kin.tension_s[(i, col)]
                - sin_ab * kin.moment_s[(i, col)];
            w[3 + col] -= cos_ab * kin.tension_m[(i, col)];
            w[6 + col] += c_b * kin.beta_r[(i, col)]
                - cos_ab * kin.tension_r[(i, col)]
                - sin_ab * kin.moment_r[(i, col)];
        }
        w[3 + i] -= sin_ab * elastic;
        force + self.load - c_0 - c_b * kin.beta0[i] - sin_ab * inertia.a
            + cos_ab * kin.tension0[i]
            + sin_ab * kin.moment0[i]
    }
}
