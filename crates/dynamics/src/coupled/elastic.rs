//! The coupled model's chords relaxed into the links' axial springs for a linear analysis at
//! rest ([`ChordCompliance`]; docs/linear.md, "Elastic chords").
//!
//! The coupled model takes the chords as axially rigid: the platform pose follows from the
//! sliders. At rest (no motion, straight links, no axial force) the linear model of the
//! axially elastic machine adds the platform's deviation `d` from that pose. Link `i` with
//! joints `B_i` (slider) and `C_i` (platform), chord direction `e_i`, normal `n_i`, moves as
//! `r(xi) = (1 - xi) B_i + xi C_i + w n_i` (the joints' motion interpolated linearly,
//! axially and transversely, plus the bending `w = psi . eta`), so its kinetic energy is
//!
//! ```text
//! T_i = [m_aa |B'|^2 + 2 m_ab B'.C' + m_bb |C'|^2] / 2
//!       + (n.B') (m_psi - m_xipsi).eta' + (n.C') m_xipsi.eta' + eta'^T M eta' / 2
//! ```
//!
//! with the moments `m_bb = m_aa = I_B / l^2`, `m_ab = m/2 - I_B / l^2` of the rigid model
//! (a bar with its centroid at mid-length and inertia `I_B` about `B`), `m_psi = int rhoA psi
//! dx`, `m_xipsi = int rhoA (x/l) psi dx`. With rigid chords these are exactly the coupled
//! model's energies (`n.C' = n.B' + l b'`, `e.C' = e.B'`), which a test checks through the
//! model's own slider-force response.
//!
//! The links' axial inertia is distributed: along the chord each link also moves by
//! `u(xi) = sum_k a_k sin(k pi xi)`, [`AXIAL_MODES`] fixed-fixed axial modes (zero at both
//! joints, so that the joints' motion stays the linear interpolation's), a Ritz basis
//! complete for the axial displacement of a uniform rod (`rhoA = m / l`). They add
//!
//! ```text
//! T_a = (m / 2) sum_k a_k'^2 / 2 + sum_k a_k' m [(e.B') / (k pi) + (e.C') (-1)^(k+1) / (k pi)]
//! U_a = (EA / l) sum_k (k pi)^2 a_k^2 / 4
//! ```
//!
//! (the integrals of `(1 - xi) sin(k pi xi)`, `xi sin(k pi xi)` and `sin^2(k pi xi)`; the
//! modes are orthogonal to each other and, in strain, to the chord's uniform stretch).
//! Without them the linear axial shape alone (a Rayleigh estimate) puts the platform's
//! highest mode about 0.9 % above an axially exact model.

use faer::Mat;
use nalgebra::{Matrix3, Vector2, Vector3};

use super::CoupledSystem;
use crate::{AXIAL_MODES, ChordCompliance, DynamicsError};

/// The joint Jacobian `dC/dp` (2 x 3) of a platform joint at offset `r = C - p`.
fn joint_jacobian(r: Vector2<f64>) -> [Vector3<f64>; 2] {
    [Vector3::new(1.0, 0.0, -r.y), Vector3::new(0.0, 1.0, r.x)]
}

/// `J^T v` for the joint Jacobian rows `j` and a plane vector `v`.
fn transpose_times(j: &[Vector3<f64>; 2], v: Vector2<f64>) -> Vector3<f64> {
    j[0] * v.x + j[1] * v.y
}

impl CoupledSystem {
    /// The relaxation of the chords into springs `EA / l` at `(t, y)` (see the module
    /// documentation), or `None` when the model has no axial stiffness
    /// ([`super::CoupledOptions::axial_stiffness`]), keeps its chords rigid
    /// ([`super::CoupledOptions::elastic_chords_at_rest`] off) or the state is not at rest: a
    /// coordinate or a rate not zero, or the commanded platform moving.
    ///
    /// # Errors
    /// A kinematic failure at the state, or a pose where the chords do not hold the
    /// platform (singular `G`).
    pub fn chord_compliance(
        &mut self,
        t: f64,
        y: &[f64],
    ) -> Result<Option<ChordCompliance>, DynamicsError> {
        let Some(axial) = self.options.axial_stiffness else {
            return Ok(None);
        };
        if !self.options.elastic_chords_at_rest {
            return Ok(None);
        }
        let (modes, n) = (self.modes, self.coordinates());
        let at_rest = y[..modes].iter().all(|v| *v == 0.0) && y[n..2 * n].iter().all(|v| *v == 0.0);
        if !at_rest {
            return Ok(None);
        }
        let out = self.output(t, y)?;
        let still = |m: &flexprr_kinematics::PlatformMotion| {
            m.velocity
                .iter()
                .chain(m.acceleration.iter())
                .all(|v| *v == 0.0)
        };
        if !still(&out.nominal) {
            return Ok(None);
        }
        let pose = out.platform.pose;
        let (sin, cos) = pose.phi.sin_cos();
        let slider_mass = self.slider_masses();
        let actuated = self.actuated.is_some();
        let mut mass_zz = Mat::<f64>::zeros(n, n);
        let mut mass_zp = Mat::<f64>::zeros(n, 3);
        let mut deviation_mass = Matrix3::from_diagonal(&Vector3::new(
            self.machine.platform_mass,
            self.machine.platform_mass,
            self.machine.platform_inertia,
        ));
        let mut g = Matrix3::<f64>::zeros();
        let mut h = Matrix3::<f64>::zeros();
        let mut springs = Matrix3::<f64>::zeros();
        let mut joint_normal = [[0.0; 3]; 3];
        // Per link: its mass, EA / l, e.u and J^T e, for the axial modes.
        let mut axial_links = [(0.0, 0.0, 0.0, Vector3::zeros()); 3];
        for i in 0..3 {
            let leg = &self.machine.geometry.legs[i];
            let u = leg.guide.direction.into_inner();
            let b = leg.guide.anchor.coords + out.slider[i][0] * u;
            let a = leg.attachment;
            let r = Vector2::new(cos * a.x - sin * a.y, sin * a.x + cos * a.y);
            let c = Vector2::new(pose.x, pose.y) + r;
            let chord = c - b;
            let length = chord.norm();
            let e = chord / length;
            let normal = Vector2::new(-e.y, e.x);
            let jac = joint_jacobian(r);
            let link = &self.links[i];
            let ints = &self.machine.links[i].integrals;
            let m_bb = link.inertia_b / (link.length * link.length);
            let m_ab = 0.5 * link.mass - m_bb;
            let range = self.link_range(i);
            let jn = transpose_times(&jac, normal);
            joint_normal[i] = [jn.x, jn.y, jn.z];
            for (k, row) in range.clone().enumerate() {
                for (l, col) in range.clone().enumerate() {
                    mass_zz[(row, col)] += ints.mass[(k, l)];
                }
                for q in 0..3 {
                    mass_zp[(row, q)] += ints.mass_xi_psi[k] * jn[q];
                }
            }
            if actuated {
                let s = modes + i;
                mass_zz[(s, s)] += slider_mass[i] + m_bb;
                let sin_ab = normal.dot(&u);
                for (k, row) in range.enumerate() {
                    let v = sin_ab * (ints.mass_psi[k] - ints.mass_xi_psi[k]);
                    mass_zz[(row, s)] += v;
                    mass_zz[(s, row)] += v;
                }
                let ju = transpose_times(&jac, u);
                for q in 0..3 {
                    mass_zp[(s, q)] += m_ab * ju[q];
                }
            }
            deviation_mass += m_bb * (jac[0] * jac[0].transpose() + jac[1] * jac[1].transpose());
            let ge = transpose_times(&jac, e);
            g.set_row(i, &ge.transpose());
            h[(i, i)] = e.dot(&u);
            springs[(i, i)] = axial[i] / length;
            axial_links[i] = (link.mass, axial[i] / length, e.dot(&u), ge);
        }
        let g_inv = g
            .try_inverse()
            .ok_or(DynamicsError::ChordsConcurrent { t })?;
        // p = P_z z: only the sliders move the platform through rigid chords (P = G^-1 H).
        let slider_map = g_inv * h;
        let mut p_z = Mat::<f64>::zeros(3, n);
        if actuated {
            for q in 0..3 {
                for i in 0..3 {
                    p_z[(q, modes + i)] = slider_map[(q, i)];
                }
            }
        }
        let m_d = Mat::from_fn(3, 3, |i, j| deviation_mass[(i, j)]);
        let coupling = &mass_zp + p_z.transpose() * &m_d;
        let mass = &mass_zz
            + &mass_zp * &p_z
            + p_z.transpose() * mass_zp.transpose()
            + p_z.transpose() * &m_d * &p_z;
        let k_d = g.transpose() * springs * g;
        // The added coordinates: the platform deviation d, then each link's axial modes.
        let added = 3 + 3 * AXIAL_MODES;
        let mut full_coupling = Mat::<f64>::zeros(n, added);
        let mut full_mass = Mat::<f64>::zeros(added, added);
        let mut full_stiffness = Mat::<f64>::zeros(added, added);
        for q in 0..3 {
            for row in 0..n {
                full_coupling[(row, q)] = coupling[(row, q)];
            }
            for r in 0..3 {
                full_mass[(q, r)] = m_d[(q, r)];
                full_stiffness[(q, r)] = k_d[(q, r)];
            }
        }
        for (i, &(mass, spring, e_u, ge)) in axial_links.iter().enumerate() {
            // e.C' = ge . p' with p' = P_z z' + d'.
            let through_platform: Vec<f64> = (0..n)
                .map(|col| (0..3).map(|q| ge[q] * p_z[(q, col)]).sum())
                .collect();
            for k in 1..=AXIAL_MODES {
                let col = 3 + i * AXIAL_MODES + (k - 1);
                let kpi = k as f64 * std::f64::consts::PI;
                let sign = if k % 2 == 1 { 1.0 } else { -1.0 };
                let (at_start, at_end) = (mass / kpi, sign * mass / kpi);
                full_mass[(col, col)] = 0.5 * mass;
                full_stiffness[(col, col)] = 0.5 * spring * kpi * kpi;
                for q in 0..3 {
                    full_mass[(q, col)] += at_end * ge[q];
                    full_mass[(col, q)] += at_end * ge[q];
                }
                for (row, v) in through_platform.iter().enumerate() {
                    full_coupling[(row, col)] += at_end * v;
                }
                if actuated {
                    full_coupling[(modes + i, col)] += at_start * e_u;
                }
            }
        }
        // The scene's modal damping ratio of the links' highest bending mode, for each added
        // coordinate in its own motion.
        let zeta = self.damping.ratios.last().copied().unwrap_or(0.0);
        let full_damping = Mat::from_fn(added, added, |i, j| {
            if i == j {
                2.0 * zeta * (full_stiffness[(i, i)] * full_mass[(i, i)]).max(0.0).sqrt()
            } else {
                0.0
            }
        });
        Ok(Some(ChordCompliance {
            mass,
            coupling: full_coupling,
            deviation_mass: full_mass,
            stiffness: full_stiffness,
            damping: full_damping,
            joint_normal,
        }))
    }
}
