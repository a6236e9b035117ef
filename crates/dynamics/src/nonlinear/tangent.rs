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
//! * `C = sum_e A_e^T C_e A_e` with the Kelvin-Voigt damping matrices
//!   ([`super::CorotationalElement::damping_matrix`], exact for the strain-rate damping).
//! * Actuated sliders: the actuator forces' derivatives in the slider positions and rates,
//!   by forward differences of the control law (six evaluations of it).
//!
//! Left out (the iteration converges to the same solution, at most with more iterations):
//! the derivatives of the consistent element mass `M_e(z)` and of the velocity terms
//! (centripetal and gyroscopic: of the order `m v^2 / L`, against `EA / L` and `EI / L^3`).

use faer::MatMut;
use flexprr_integrators::SecondOrderForm;

use super::equations::NONE;
use super::system::NonlinearSystem;

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
        let Ok(frame) = self.frame(t, y) else {
            mass.fill(f64::NAN);
            return;
        };
        self.assemble(y, &frame);
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
                let inertia =
                    self.options
                        .mass
                        .inertia(link.element_mass, link.element.length, &q, &v);
                Self::add_mapped(&mut mass, &map, &inertia.mass);
                Self::add_mapped(&mut stiffness, &map, &link.element.tangent(&q));
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
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use faer::Mat;

    use super::*;
    use crate::NonlinearOptions;
    use crate::paper;

    /// A deformed, moving-free state of the paper machine at 30 Hz: the rigid state with the
    /// nodes displaced by a smooth bending shape and the velocities zeroed.
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
        for (k, v) in y[..n].iter_mut().enumerate() {
            *v += 2e-3 * (0.7 * k as f64).sin();
        }
        y[n..].fill(0.0);
        (s, y)
    }

    /// The generalized forces `F` at `(t, y)`.
    fn forces(s: &mut NonlinearSystem, t: f64, y: &[f64]) -> Vec<f64> {
        let frame = s.frame(t, y).unwrap();
        s.assemble(y, &frame);
        s.assemble_equations(y, &frame);
        s.generalized.clone()
    }

    /// `K = -dF/dz` against central differences of the assembled generalized forces at a
    /// deformed state at rest (where the left-out inertia derivatives multiply only the
    /// sliders' prescribed accelerations), and `M` is the mass the right-hand side solves
    /// with (its solve of `M a = F` gives the right-hand side's accelerations).
    #[test]
    fn stiffness_is_the_derivative_of_the_forces() {
        let (mut s, y) = deformed(4);
        let t = 0.01;
        let n = s.coordinates();
        let (mut m, mut c, mut k) = (Mat::zeros(n, n), Mat::zeros(n, n), Mat::zeros(n, n));
        s.matrices(t, &y, m.as_mut(), c.as_mut(), k.as_mut());
        let scale = (0..n)
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .map(|(i, j)| k[(i, j)].abs())
            .fold(0.0, f64::max);
        let mut worst: f64 = 0.0;
        for j in 0..n {
            let h = 1e-7;
            let (mut yp, mut ym) = (y.clone(), y.clone());
            yp[j] += h;
            ym[j] -= h;
            let (fp, fm) = (forces(&mut s, t, &yp), forces(&mut s, t, &ym));
            for i in 0..n {
                let fd = -(fp[i] - fm[i]) / (2.0 * h);
                worst = worst.max((fd - k[(i, j)]).abs());
            }
        }
        println!("max |K - FD| = {worst:.3e} of max |K| = {scale:.3e}");
        assert!(worst < 1e-6 * scale, "{worst} vs {scale}");
        // Symmetric mass, and M z'' = F with the right-hand side's accelerations.
        let mut dy = vec![0.0; 2 * n];
        flexprr_integrators::OdeSystem::rhs(&mut s, t, &y, &mut dy);
        let f = forces(&mut s, t, &y);
        for i in 0..n {
            let ma: f64 = (0..n).map(|j| m[(i, j)] * dy[n + j]).sum();
            assert!((ma - f[i]).abs() <= 1e-9 * f.iter().map(|v| v.abs()).fold(0.0, f64::max));
            for j in 0..n {
                assert_eq!(m[(i, j)], m[(j, i)]);
            }
        }
    }

    /// `C = -dF/dz'` against differences of the forces in the rates, with strain-rate
    /// damping on (the velocity terms of the consistent mass are quadratic in the rates:
    /// at rest their derivative vanishes).
    #[test]
    fn damping_is_the_derivative_of_the_forces_in_the_rates() {
        let (mut s, y) = deformed(4);
        s.options.axial_damping_time = 2e-5;
        s.options.bending_damping_time = 1e-4;
        let t = 0.01;
        let n = s.coordinates();
        let (mut m, mut c, mut k) = (Mat::zeros(n, n), Mat::zeros(n, n), Mat::zeros(n, n));
        s.matrices(t, &y, m.as_mut(), c.as_mut(), k.as_mut());
        let scale = (0..n)
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .map(|(i, j)| c[(i, j)].abs())
            .fold(0.0, f64::max);
        assert!(scale > 0.0);
        let mut worst: f64 = 0.0;
        for j in 0..n {
            let h = 1e-6;
            let (mut yp, mut ym) = (y.clone(), y.clone());
            yp[n + j] += h;
            ym[n + j] -= h;
            let (fp, fm) = (forces(&mut s, t, &yp), forces(&mut s, t, &ym));
            for i in 0..n {
                let fd = -(fp[i] - fm[i]) / (2.0 * h);
                worst = worst.max((fd - c[(i, j)]).abs());
            }
        }
        println!("max |C - FD| = {worst:.3e} of max |C| = {scale:.3e}");
        assert!(worst < 1e-5 * scale, "{worst} vs {scale}");
    }
}
