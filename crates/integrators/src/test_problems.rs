//! Reference problems with exact or independently computed solutions, shared by the tests and
//! benchmarks of every method (in the manner of diffsol's `test_models`).
//!
//! Each problem is an [`OdeSystem`] with its initial value, time span and, where one exists,
//! its exact solution. Stiff problems supply their Jacobian in closed form.

use faer::MatMut;

use crate::OdeSystem;

/// A test problem: a system, where it starts, where it ends, and what it should give.
pub trait TestProblem: OdeSystem {
    /// Short name for reports.
    fn name(&self) -> &'static str;
    /// Initial time.
    fn t0(&self) -> f64 {
        0.0
    }
    /// Initial state.
    fn y0(&self) -> Vec<f64>;
    /// Final time of the standard run.
    fn t_end(&self) -> f64;
    /// The exact solution at `t`, if known in closed form.
    fn exact(&self, _t: f64) -> Option<Vec<f64>> {
        None
    }
}

/// Harmonic oscillator `y'' = -omega^2 y`, `y(0) = 1`, `y'(0) = 0`; exact
/// `y = cos(omega t)`.
#[derive(Debug, Clone)]
pub struct HarmonicOscillator {
    /// Angular frequency (rad/s).
    pub omega: f64,
    /// Final time.
    pub t_end: f64,
}

impl Default for HarmonicOscillator {
    fn default() -> Self {
        Self {
            omega: 1.0,
            t_end: 20.0,
        }
    }
}

impl OdeSystem for HarmonicOscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = y[1];
        dy[1] = -self.omega * self.omega * y[0];
    }
    fn jacobian(&mut self, _t: f64, _y: &[f64], mut jac: MatMut<'_, f64>) {
        jac[(0, 0)] = 0.0;
        jac[(0, 1)] = 1.0;
        jac[(1, 0)] = -self.omega * self.omega;
        jac[(1, 1)] = 0.0;
    }
    fn has_analytic_jacobian(&self) -> bool {
        true
    }
}

impl TestProblem for HarmonicOscillator {
    fn name(&self) -> &'static str {
        "harmonic oscillator"
    }
    fn y0(&self) -> Vec<f64> {
        vec![1.0, 0.0]
    }
    fn t_end(&self) -> f64 {
        self.t_end
    }
    fn exact(&self, t: f64) -> Option<Vec<f64>> {
        let w = self.omega;
        Some(vec![(w * t).cos(), -w * (w * t).sin()])
    }
}

/// Undamped oscillator forced off resonance: `y'' + omega^2 y = F cos(Omega t)` from rest;
/// exact `y = F (cos(Omega t) - cos(omega t)) / (omega^2 - Omega^2)`.
#[derive(Debug, Clone)]
pub struct ForcedOscillator {
    /// Natural angular frequency (rad/s).
    pub omega: f64,
    /// Forcing angular frequency (rad/s), not equal to `omega`.
    pub forcing_omega: f64,
    /// Forcing amplitude per unit mass.
    pub amplitude: f64,
    /// Final time.
    pub t_end: f64,
}

impl Default for ForcedOscillator {
    fn default() -> Self {
        Self {
            omega: 3.0,
            forcing_omega: 1.7,
            amplitude: 1.0,
            t_end: 20.0,
        }
    }
}

impl OdeSystem for ForcedOscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = y[1];
        dy[1] = -self.omega * self.omega * y[0] + self.amplitude * (self.forcing_omega * t).cos();
    }
    fn jacobian(&mut self, _t: f64, _y: &[f64], mut jac: MatMut<'_, f64>) {
        jac[(0, 0)] = 0.0;
        jac[(0, 1)] = 1.0;
        jac[(1, 0)] = -self.omega * self.omega;
        jac[(1, 1)] = 0.0;
    }
    fn has_analytic_jacobian(&self) -> bool {
        true
    }
}

impl TestProblem for ForcedOscillator {
    fn name(&self) -> &'static str {
        "forced oscillator"
    }
    fn y0(&self) -> Vec<f64> {
        vec![0.0, 0.0]
    }
    fn t_end(&self) -> f64 {
        self.t_end
    }
    fn exact(&self, t: f64) -> Option<Vec<f64>> {
        let (w, wf, f) = (self.omega, self.forcing_omega, self.amplitude);
        let c = f / (w * w - wf * wf);
        Some(vec![
            c * ((wf * t).cos() - (w * t).cos()),
            c * (-wf * (wf * t).sin() + w * (w * t).sin()),
        ])
    }
}

/// Mathieu equation `y'' + (a - 2 q cos 2t) y = 0`, `y(0) = 1`, `y'(0) = 0`: a linear
/// oscillator with time-varying stiffness, like the modal equations of a link under a
/// periodic axial force. No closed form: tests compare with another method at `rtol = 1e-13`.
#[derive(Debug, Clone)]
pub struct Mathieu {
    /// Parameter `a`.
    pub a: f64,
    /// Parameter `q`.
    pub q: f64,
    /// Final time.
    pub t_end: f64,
}

impl Default for Mathieu {
    fn default() -> Self {
        Self {
            a: 1.0,
            q: 0.2,
            t_end: 20.0,
        }
    }
}

impl OdeSystem for Mathieu {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = y[1];
        dy[1] = -(self.a - 2.0 * self.q * (2.0 * t).cos()) * y[0];
    }
    fn jacobian(&mut self, t: f64, _y: &[f64], mut jac: MatMut<'_, f64>) {
        jac[(0, 0)] = 0.0;
        jac[(0, 1)] = 1.0;
        jac[(1, 0)] = -(self.a - 2.0 * self.q * (2.0 * t).cos());
        jac[(1, 1)] = 0.0;
    }
    fn has_analytic_jacobian(&self) -> bool {
        true
    }
}

impl TestProblem for Mathieu {
    fn name(&self) -> &'static str {
        "Mathieu equation"
    }
    fn y0(&self) -> Vec<f64> {
        vec![1.0, 0.0]
    }
    fn t_end(&self) -> f64 {
        self.t_end
    }
}

/// Van der Pol oscillator in Hairer's scaling (Hairer & Wanner II, IV.1):
/// `y1' = y2`, `y2' = ((1 - y1^2) y2 - y1) / eps`, `y(0) = (2, 0)`.
/// `eps = 1e-6` corresponds to `mu = 1000` in the classical form; `eps = 0.003` on
/// `[0, 2]` is the non-stiff-ish benchmark with published DOPRI5 counts.
#[derive(Debug, Clone)]
pub struct VanDerPol {
    /// Stiffness parameter `eps = 1 / mu^2`.
    pub eps: f64,
    /// Final time.
    pub t_end: f64,
}

impl VanDerPol {
    /// The classical `mu` form rescaled (`t -> t / mu`): `eps = 1 / mu^2`, over two time units
    /// of the scaled variable (about one relaxation period).
    pub fn with_mu(mu: f64) -> Self {
        Self {
            eps: 1.0 / (mu * mu),
            t_end: 2.0,
        }
    }
}

impl Default for VanDerPol {
    fn default() -> Self {
        Self {
            eps: 0.003,
            t_end: 2.0,
        }
    }
}

impl OdeSystem for VanDerPol {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = y[1];
        dy[1] = ((1.0 - y[0] * y[0]) * y[1] - y[0]) / self.eps;
    }
    fn jacobian(&mut self, _t: f64, y: &[f64], mut jac: MatMut<'_, f64>) {
        jac[(0, 0)] = 0.0;
        jac[(0, 1)] = 1.0;
        jac[(1, 0)] = (-2.0 * y[0] * y[1] - 1.0) / self.eps;
        jac[(1, 1)] = (1.0 - y[0] * y[0]) / self.eps;
    }
    fn has_analytic_jacobian(&self) -> bool {
        true
    }
}

impl TestProblem for VanDerPol {
    fn name(&self) -> &'static str {
        "Van der Pol"
    }
    fn y0(&self) -> Vec<f64> {
        vec![2.0, 0.0]
    }
    fn t_end(&self) -> f64 {
        self.t_end
    }
}

/// Robertson's chemical kinetics (Hairer & Wanner II, IV.1; CVODE's `cvRoberts_dns`):
/// `y1' = -0.04 y1 + 1e4 y2 y3`, `y2' = 0.04 y1 - 1e4 y2 y3 - 3e7 y2^2`, `y3' = 3e7 y2^2`,
/// `y(0) = (1, 0, 0)`. Invariant: `y1 + y2 + y3 = 1`.
#[derive(Debug, Clone)]
pub struct Robertson {
    /// Final time.
    pub t_end: f64,
}

impl Default for Robertson {
    fn default() -> Self {
        Self { t_end: 1e5 }
    }
}

impl OdeSystem for Robertson {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
        let r1 = 0.04 * y[0];
        let r2 = 1e4 * y[1] * y[2];
        let r3 = 3e7 * y[1] * y[1];
        dy[0] = -r1 + r2;
        dy[1] = r1 - r2 - r3;
        dy[2] = r3;
    }
    fn jacobian(&mut self, _t: f64, y: &[f64], mut jac: MatMut<'_, f64>) {
        jac[(0, 0)] = -0.04;
        jac[(0, 1)] = 1e4 * y[2];
        jac[(0, 2)] = 1e4 * y[1];
        jac[(1, 0)] = 0.04;
        jac[(1, 1)] = -1e4 * y[2] - 6e7 * y[1];
        jac[(1, 2)] = -1e4 * y[1];
        jac[(2, 0)] = 0.0;
        jac[(2, 1)] = 6e7 * y[1];
        jac[(2, 2)] = 0.0;
    }
    fn has_analytic_jacobian(&self) -> bool {
        true
    }
}

impl TestProblem for Robertson {
    fn name(&self) -> &'static str {
        "Robertson"
    }
    fn y0(&self) -> Vec<f64> {
        vec![1.0, 0.0, 0.0]
    }
    fn t_end(&self) -> f64 {
        self.t_end
    }
}

/// Linear system `y' = A y` with `A = Q diag(-lambda_slow, -lambda_fast) Q^T`, `Q` a rotation
/// by `theta`: stiffness ratio `lambda_fast / lambda_slow` (1e6 by default). Exact solution
/// `y(t) = Q exp(diag(...) t) Q^T y0`.
#[derive(Debug, Clone)]
pub struct StiffLinear {
    /// Slow decay rate (1/s).
    pub lambda_slow: f64,
    /// Fast decay rate (1/s).
    pub lambda_fast: f64,
    /// Rotation angle of the eigenvectors (rad).
    pub theta: f64,
    /// Final time.
    pub t_end: f64,
}

impl Default for StiffLinear {
    fn default() -> Self {
        Self {
            lambda_slow: 1.0,
            lambda_fast: 1e6,
            theta: 0.5,
            t_end: 10.0,
        }
    }
}

impl StiffLinear {
    fn matrix(&self) -> [[f64; 2]; 2] {
        let (s, c) = self.theta.sin_cos();
        let (l1, l2) = (-self.lambda_slow, -self.lambda_fast);
        // A = Q diag(l1, l2) Q^T with Q = [[c, -s], [s, c]].
        [
            [c * c * l1 + s * s * l2, c * s * (l1 - l2)],
            [c * s * (l1 - l2), s * s * l1 + c * c * l2],
        ]
    }
}

impl OdeSystem for StiffLinear {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
        let a = self.matrix();
        dy[0] = a[0][0] * y[0] + a[0][1] * y[1];
        dy[1] = a[1][0] * y[0] + a[1][1] * y[1];
    }
    fn jacobian(&mut self, _t: f64, _y: &[f64], mut jac: MatMut<'_, f64>) {
        let a = self.matrix();
        for i in 0..2 {
            for j in 0..2 {
                jac[(i, j)] = a[i][j];
            }
        }
    }
    fn has_analytic_jacobian(&self) -> bool {
        true
    }
}

impl TestProblem for StiffLinear {
    fn name(&self) -> &'static str {
        "stiff linear (ratio 1e6)"
    }
    fn y0(&self) -> Vec<f64> {
        vec![1.0, 1.0]
    }
    fn t_end(&self) -> f64 {
        self.t_end
    }
    fn exact(&self, t: f64) -> Option<Vec<f64>> {
        let (s, c) = self.theta.sin_cos();
        let y0 = self.y0();
        // Modal coordinates z = Q^T y0, decayed, mapped back.
        let z1 = (c * y0[0] + s * y0[1]) * (-self.lambda_slow * t).exp();
        let z2 = (-s * y0[0] + c * y0[1]) * (-self.lambda_fast * t).exp();
        Some(vec![c * z1 - s * z2, s * z1 + c * z2])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Mat;

    /// Each closed-form Jacobian agrees with central differences of its right-hand side
    /// (exact for the quadratic terms of Robertson's problem up to rounding).
    fn check_jacobian<P: TestProblem>(mut p: P, t: f64, y: &[f64]) {
        let n = p.dim();
        let mut exact = Mat::<f64>::zeros(n, n);
        p.jacobian(t, y, exact.as_mut());
        let (mut fp, mut fm) = (vec![0.0; n], vec![0.0; n]);
        for j in 0..n {
            let h = 1e-6 * y[j].abs().max(1e-6);
            let mut yp = y.to_vec();
            let mut ym = y.to_vec();
            yp[j] += h;
            ym[j] -= h;
            p.rhs(t, &yp, &mut fp);
            p.rhs(t, &ym, &mut fm);
            for i in 0..n {
                let fd = (fp[i] - fm[i]) / (2.0 * h);
                let scale = exact[(i, j)].abs().max(1.0);
                assert!(
                    (exact[(i, j)] - fd).abs() <= 1e-6 * scale,
                    "{}: J[{i},{j}] = {} vs differenced {fd}",
                    p.name(),
                    exact[(i, j)],
                );
            }
        }
    }

    #[test]
    fn analytic_jacobians_match_finite_differences() {
        check_jacobian(HarmonicOscillator::default(), 0.3, &[0.2, -0.7]);
        check_jacobian(ForcedOscillator::default(), 0.3, &[0.2, -0.7]);
        check_jacobian(Mathieu::default(), 0.3, &[0.2, -0.7]);
        check_jacobian(VanDerPol::default(), 0.3, &[1.5, -0.7]);
        check_jacobian(Robertson::default(), 0.3, &[0.9, 3e-5, 0.1]);
        check_jacobian(
            StiffLinear {
                lambda_fast: 1e3,
                ..Default::default()
            },
            0.3,
            &[0.2, -0.7],
        );
    }

    /// The closed forms satisfy their differential equations (central differences in t).
    #[test]
    fn exact_solutions_satisfy_their_equations() {
        fn check<P: TestProblem>(mut p: P, t: f64) {
            let h = 1e-5;
            let y = p.exact(t).unwrap();
            let yp = p.exact(t + h).unwrap();
            let ym = p.exact(t - h).unwrap();
            let mut f = vec![0.0; p.dim()];
            p.rhs(t, &y, &mut f);
            for i in 0..p.dim() {
                let d = (yp[i] - ym[i]) / (2.0 * h);
                assert!(
                    (d - f[i]).abs() < 1e-7 * f[i].abs().max(1.0),
                    "{}",
                    p.name()
                );
            }
            let y0 = p.exact(p.t0()).unwrap();
            for (a, b) in y0.iter().zip(p.y0()) {
                assert!((a - b).abs() < 1e-14);
            }
        }
        check(HarmonicOscillator::default(), 1.3);
        check(ForcedOscillator::default(), 1.3);
        check(
            StiffLinear {
                lambda_fast: 10.0,
                ..Default::default()
            },
            0.4,
        );
    }
}
