//! The mechanical form of [`NonlinearSystem`] for implicit integrators
//! ([`flexprr_integrators::SecondOrderForm`]): the generalized mass `M`, and the tangent
//! stiffness `K ~ -dF/dz` and damping `C ~ -dF/dz'` of the equations of motion
//! `M(z) z'' = F(t, z, z')` (super::equations).
//!
//! * `M = M_own + sum_e A_e^T M_e A_e`: the same mass the right-hand side solves with.
//! * `K = sum_e A_e^T K_e A_e + K_phi`: the analytic co-rotational element tangents
//!   ([`super::CorotationalElement::tangent`], Crisfield 1991, eq. 7.23) mapped to the
//!   generalized coordinates, plus the term of the platform's rotation, whose attachment
//!   points `C_i = p + R(phi) c_i` are nonlinear in `phi`:
//!   `K_phi,phi = -sum_i r_i . f_N,i` (`f_N,i` the nodal force at link `i`'s last node,
//!   `d^2 C_i / dphi^2 = -r_i`).
//! * the derivatives of the elements' inertia forces (with the platform's rotation: the
//!   attachment point's acceleration `p'' + perp(r_i) phi'' - phi'^2 r_i` and the inertia
//!   force there turn with `phi`, like `f_N,i`) `Q_e = M_e(x_e) x_e'' + h_e(x_e, x_e')`
//!   at the current accelerations ([`super::NodalMass::derivatives`]: the consistent mass
//!   turns with the nodal tangents), `A_e^T dQ_e/dx_e A_e` into `K` and
//!   `A_e^T dQ_e/dx_e' A_e` into `C` (not symmetric);
//! * `C = sum_e A_e^T C_e A_e` with the Kelvin-Voigt damping matrices
//!   ([`super::CorotationalElement::damping_matrix`], exact for the strain-rate damping).
//! * Actuated sliders: the actuator forces' derivatives in the slider positions and rates,
//!   by forward differences of the control law (six evaluations of it).
//!
//! Left out (the iteration converges to the same solution, at most with more iterations):
//! the platform's centripetal acceleration `-phi'^2 r_i` in `phi` and `phi'`, and the
//! damping forces' change with the element rotations (`dC/dz z'`).

use faer::MatMut;
use flexprr_integrators::{BlockBanded, SecondOrderForm};

use super::equations::NONE;
use super::system::{MASS_BANDWIDTH, NonlinearSystem};

impl NonlinearSystem {
    /// Adds `A^T E A` of one element (its 6x6 matrix `e` and map `map`) into `out`.
    fn add_mapped(
        out: &mut MatMut<'_, f64>,
        map: &[super::equations::CoordinateMap; 6],
        e: &[[f64; 6]; 6],
    ) {
        for (c1, m1) in map.iter().enumerate() {
            for (c2, m2) in map.iter().enumerate() {
                let v = e[c1][c2];
                if v == 0.0 {
                    continue;
                }
                for &(g1, a1) in m1.iter().filter(|(g, _)| *g != NONE) {
                    for &(g2, a2) in m2.iter().filter(|(g, _)| *g != NONE) {
                        out[(g1, g2)] += a1 * a2 * v;
                    }
                }
            }
        }
    }

    /// Writes `M`, `C`, `K` at `(t, y)` into zeroed `n x n` storage (module documentation).
    /// A state where the model cannot be evaluated (a kinematic failure) writes NaN into
    /// `M`, which the integrator reports.
    fn mechanical_matrices(
        &mut self,
        t: f64,
        y: &[f64],
        mut mass: MatMut<'_, f64>,
        mut damping: MatMut<'_, f64>,
        mut stiffness: MatMut<'_, f64>,
    ) {
        let n = self.coordinates();
        let Ok(frame) = self.frame(t, y) else {
            mass.fill(f64::NAN);
            return;
        };
        self.assemble(y, &frame);
        // The accelerations at (t, y), for the derivatives of the inertia forces.
        let mut acc = std::mem::take(&mut self.tangent_work);
        let mut no_rates = [0.0; 0];
        let solved = y.len() == 2 * n
            && self.actuate(t, y, &frame, &mut no_rates).is_ok()
            && self.accelerations(t, y, &frame, &mut acc[..n]).is_ok();
        if !solved {
            self.tangent_work = acc;
            mass.fill(f64::NAN);
            return;
        }
        let ne = self.options.elements;
        let stride = 3 * (ne + 1);
        let (beta_a, beta_b) = (
            self.options.axial_damping_time,
            self.options.bending_damping_time,
        );
        let damped = beta_a > 0.0 || beta_b > 0.0;
        for i in 0..3 {
            let link = self.links[i];
            for e in 0..ne {
                let (q, v) = self.element_state(y, &frame, i, e);
                let (map, _) = self.element_map(&frame, y, i, e);
                let (m, l) = (link.element_mass, link.element.length);
                let inertia = self.options.mass.inertia(m, l, &q, &v);
                Self::add_mapped(&mut mass, &map, &inertia.mass);
                Self::add_mapped(&mut stiffness, &map, &link.element.tangent(&q));
                let a = self.element_acceleration(&frame, y, &acc[..n], i, e);
                let d = self.options.mass.derivatives(m, l, &q, &v, &a);
                Self::add_mapped(&mut stiffness, &map, &d.position);
                Self::add_mapped(&mut damping, &map, &d.velocity);
                if e == ne - 1 {
                    // The platform's rotation: the attachment point's acceleration has the
                    // term perp(r) phi'' (d/dphi: -r phi''), and its inertia force turns
                    // with r (d^2 C / dphi^2 = -r).
                    let r = frame.r[i];
                    let phi_dd = acc[2];
                    let mut q_inertia = inertia.velocity_terms;
                    for (c, row) in inertia.mass.iter().enumerate() {
                        q_inertia[c] += row.iter().zip(&a).map(|(m, x)| m * x).sum::<f64>();
                        let g = -(row[3] * r.x + row[4] * r.y) * phi_dd;
                        for &(g1, a1) in map[c].iter().filter(|(g, _)| *g != NONE) {
                            stiffness[(g1, 2)] += a1 * g;
                        }
                    }
                    stiffness[(2, 2)] -= r.x * q_inertia[3] + r.y * q_inertia[4];
                }
                if damped {
                    let c = link.element.damping_matrix(&q, beta_a, beta_b);
                    Self::add_mapped(&mut damping, &map, &c);
                }
            }
            // The platform's rotation moves the attachment point on a circle.
            let f = &self.forces[i * stride + 3 * ne..i * stride + 3 * ne + 2];
            let r = frame.r[i];
            stiffness[(2, 2)] -= r.x * f[0] + r.y * f[1];
        }
        self.tangent_work = acc;
        let (mp, ip) = (self.machine.platform_mass, self.machine.platform_inertia);
        mass[(0, 0)] += mp;
        mass[(1, 1)] += mp;
        mass[(2, 2)] += ip;
        if self.actuated.is_some() {
            let masses = self.slider_masses();
            for (i, m) in masses.iter().enumerate() {
                let g = self.slider_index(i);
                mass[(g, g)] += m;
            }
            self.actuator_derivatives(t, y, &mut damping, &mut stiffness);
        }
    }

    /// The actuator forces' derivatives in the slider positions (into `stiffness`) and rates
    /// (into `damping`), by forward differences of the control law.
    fn actuator_derivatives(
        &mut self,
        t: f64,
        y: &[f64],
        damping: &mut MatMut<'_, f64>,
        stiffness: &mut MatMut<'_, f64>,
    ) {
        let n = self.coordinates();
        let mut work = std::mem::take(&mut self.tangent_work);
        let mut no_rates = [0.0; 0];
        let base = match self.slider_forces_at(t, y, &mut no_rates) {
            Some(f) => f,
            None => {
                self.tangent_work = work;
                return;
            }
        };
        work.copy_from_slice(y);
        for j in 0..3 {
            let g = self.slider_index(j);
            for rate in [false, true] {
                let k = if rate { n + g } else { g };
                let d = f64::EPSILON.sqrt() * work[k].abs().max(1e-3);
                work[k] = y[k] + d;
                if let Some(f) = self.slider_forces_at(t, &work, &mut no_rates) {
                    for i in 0..3 {
                        let v = (f[i] - base[i]) / d;
                        if rate {
                            damping[(self.slider_index(i), g)] -= v;
                        } else {
                            stiffness[(self.slider_index(i), g)] -= v;
                        }
                    }
                }
                work[k] = y[k];
            }
        }
        self.tangent_work = work;
    }

    /// The actuator forces at `(t, y)` (`None` when the control law fails there).
    fn slider_forces_at(&mut self, t: f64, y: &[f64], rates: &mut [f64]) -> Option<[f64; 3]> {
        let frame = self.frame(t, y).ok()?;
        self.actuate(t, y, &frame, rates).ok()?;
        Some(self.slider_forces)
    }
}

/// The mechanical form for [`flexprr_integrators::GeneralizedAlpha`] (module documentation).
/// A continuous control law with states of its own has no such form (its states are
/// first-order): the integrator then refuses the system.
impl SecondOrderForm for NonlinearSystem {
    fn coordinates(&self) -> usize {
        NonlinearSystem::coordinates(self)
    }

    fn matrices(
        &mut self,
        t: f64,
        y: &[f64],
        mass: MatMut<'_, f64>,
        damping: MatMut<'_, f64>,
        stiffness: MatMut<'_, f64>,
    ) {
        self.mechanical_matrices(t, y, mass, damping, stiffness);
    }

    /// One banded block per link (half-bandwidth 5: an element couples its two nodes' six
    /// consecutive coordinates), the platform's and the sliders' coordinates the border.
    fn structure(&self) -> Option<BlockBanded> {
        let blocks = (0..3).map(|i| self.link_range(i)).collect();
        BlockBanded::new(NonlinearSystem::coordinates(self), blocks, MASS_BANDWIDTH).ok()
    }

    fn has_residual(&self) -> bool {
        true
    }

    /// `M a - F` with the banded mass the right-hand side assembles, without its solve.
    fn residual(&mut self, t: f64, y: &[f64], acc: &[f64], residual: &mut [f64]) {
        self.motion_residual(t, y, acc, residual);
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use faer::Mat;
    use flexprr_integrators::OdeSystem;

    use super::*;
    use crate::NonlinearOptions;
    use crate::paper;

    /// A deformed, moving state of the paper machine at 30 Hz: the rigid state with the nodes
    /// displaced by a smooth bending shape and smooth rates, the platform not turning (where
    /// the one left-out term, the platform's centripetal acceleration, has no derivative).
    fn deformed(elements: usize) -> (NonlinearSystem, Vec<f64>) {
        let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
        let trajectory = Arc::new(paper::trajectory(30.0).unwrap());
        let options = NonlinearOptions {
            elements,
            stop_at_type_ii: false,
            ..NonlinearOptions::paper(paper::YOUNGS_MODULUS)
        };
        let s = NonlinearSystem::new(machine, trajectory, options).unwrap();
        let mut y = s.initial_state(0.01).unwrap();
        let n = s.coordinates();
        for k in 0..n {
            y[k] += 2e-3 * (0.7 * k as f64).sin();
            y[n + k] += 0.5 * (1.3 * k as f64).cos();
        }
        y[n + 2] = 0.0;
        (s, y)
    }

    /// `-M d(z'')/dz` and `-M d(z'')/dz'` by central differences of the right-hand side.
    fn differenced(
        s: &mut NonlinearSystem,
        t: f64,
        y: &[f64],
        m: &Mat<f64>,
        column: usize,
    ) -> Vec<f64> {
        let n = s.coordinates();
        // The forces are quadratic in the rates: central differences are exact in any step.
        let h = if column < n { 1e-7 } else { 1e-2 };
        let (mut yp, mut ym) = (y.to_vec(), y.to_vec());
        yp[column] += h;
        ym[column] -= h;
        let (mut fp, mut fm) = (vec![0.0; 2 * n], vec![0.0; 2 * n]);
        s.rhs(t, &yp, &mut fp);
        s.rhs(t, &ym, &mut fm);
        let da: Vec<f64> = (0..n)
            .map(|i| (fp[n + i] - fm[n + i]) / (2.0 * h))
            .collect();
        (0..n)
            .map(|i| -(0..n).map(|j| m[(i, j)] * da[j]).sum::<f64>())
            .collect()
    }

    fn largest(a: &Mat<f64>) -> f64 {
        let mut v: f64 = 0.0;
        for j in 0..a.ncols() {
            for i in 0..a.nrows() {
                v = v.max(a[(i, j)].abs());
            }
        }
        v
    }

    /// Newton's matrix is the derivative of the equations of motion: `K = -M dz''/dz` and
    /// `C = -M dz''/dz'` (at fixed accelerations, the inertia derivatives included) against
    /// central differences of the right-hand side, without and with strain-rate damping;
    /// and `M` is the mass the right-hand side solves with (`M z'' = F`).
    #[test]
    fn matrices_are_the_derivatives_of_the_equations_of_motion() {
        for damped in [false, true] {
            let (mut s, y) = deformed(4);
            if damped {
                s.options.axial_damping_time = 2e-5;
                s.options.bending_damping_time = 1e-4;
            }
            let t = 0.01;
            let n = s.coordinates();
            let (mut m, mut c, mut k) = (Mat::zeros(n, n), Mat::zeros(n, n), Mat::zeros(n, n));
            s.matrices(t, &y, m.as_mut(), c.as_mut(), k.as_mut());
            let (scale_k, scale_c) = (largest(&k), largest(&c));
            let (mut worst_k, mut worst_c): (f64, f64) = (0.0, 0.0);
            for j in 0..n {
                let dk = differenced(&mut s, t, &y, &m, j);
                let dc = differenced(&mut s, t, &y, &m, n + j);
                for i in 0..n {
                    worst_k = worst_k.max((dk[i] - k[(i, j)]).abs());
                    worst_c = worst_c.max((dc[i] - c[(i, j)]).abs());
                }
            }
            println!(
                "damped {damped}: max |K - FD| = {worst_k:.3e} of {scale_k:.3e}, \
                 max |C - FD| = {worst_c:.3e} of {scale_c:.3e}"
            );
            // With damping, the one left-out term (the damping forces' change with the
            // element rotations at these rates, 0.5 m/s and 0.5 rad/s) shows at 1e-3.
            let bound = if damped { 2e-3 } else { 1e-9 };
            assert!(worst_k < bound * scale_k, "{worst_k} vs {scale_k}");
            // Undamped, C is the small gyroscopic part (2e-3 N s/m): rounding shows at 1e-5.
            assert!(worst_c < 1e-4 * scale_c, "{worst_c} vs {scale_c}");
            for i in 0..n {
                for j in 0..n {
                    assert_eq!(m[(i, j)].to_bits(), m[(j, i)].to_bits(), "M ({i}, {j})");
                }
            }
        }
    }

    /// The residual form: zero at the right-hand side's accelerations (`M z'' = F`), and its
    /// change with the accelerations is the mass of the matrices (`r(a + d e_j) - r(a) =
    /// d M e_j`); the structure holds every entry of `M`, `C` and `K`.
    #[test]
    fn residual_vanishes_at_the_accelerations_and_its_slope_is_the_mass() {
        let (mut s, y) = deformed(4);
        let t = 0.01;
        let n = s.coordinates();
        let mut dy = vec![0.0; 2 * n];
        s.rhs(t, &y, &mut dy);
        let acc = dy[n..].to_vec();
        assert!(s.has_residual());
        let mut r = vec![0.0; n];
        s.residual(t, &y, &acc, &mut r);
        let forces = s.generalized.iter().fold(0.0_f64, |m, f| m.max(f.abs()));
        let worst = r.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!(worst < 1e-12 * forces, "{worst} of {forces}");
        let (mut m, mut c, mut k) = (Mat::zeros(n, n), Mat::zeros(n, n), Mat::zeros(n, n));
        s.matrices(t, &y, m.as_mut(), c.as_mut(), k.as_mut());
        let structure = s.structure().unwrap();
        for j in 0..n {
            let mut shifted = acc.clone();
            shifted[j] += 1.0;
            let mut r1 = vec![0.0; n];
            s.residual(t, &y, &shifted, &mut r1);
            for i in 0..n {
                let slope = r1[i] - r[i];
                assert!((slope - m[(i, j)]).abs() < 1e-9 * largest(&m), "({i}, {j})");
                let outside = !structure.contains(i, j);
                if outside {
                    assert_eq!(
                        (m[(i, j)], c[(i, j)], k[(i, j)]),
                        (0.0, 0.0, 0.0),
                        "({i}, {j})"
                    );
                }
            }
        }
    }
}
