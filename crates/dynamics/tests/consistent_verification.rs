//! Verification of the consistent formulation (model.md section 6) by two independent means.
//!
//! 1. **A second discretization.** The same transverse equation is discretized with cubic
//!    Hermite finite elements (`flexprr_beam::HermiteBasis`, pinned-pinned: nodal deflections and
//!    slopes, full consistent mass and stiffness matrices) instead of the sine modes. Both are
//!    Galerkin projections of one PDE, so as elements and modes are added the mid-point
//!    deflection histories of the three links on the paper's f = 20 Hz scene must converge to
//!    each other. Both converge at fourth order in the mesh size / mode count (the forcing's
//!    sine coefficients fall as `1/j`, the quasi-static response as `1/j^5`).
//! 2. **A manufactured solution.** For a prescribed deflection `w(x, t)` (not a solution) and
//!    the paper's rigid motion, the PDE residual
//!
//!    ```text
//!    R(x, t) = rhoA (w_tt + rho'' sin(a - b) + x b'' - b'^2 w) + EI w'''' - (P w')'
//!    ```
//!
//!    is evaluated from closed-form derivatives of `w`, the joint-reaction axial force
//!    `P(x) = -F_B.e + rhoA (rho'' cos(b - a) x - b'^2 x^2 / 2)` with `F_B` from the
//!    independent 12-equation inverse dynamics, and projected on each shape function by
//!    Gauss-Legendre quadrature (exact here: the integrands are polynomials of degree <= 12, or
//!    trigonometric polynomials integrated with many points). The modal system's rhs implies
//!    the same projection as `M (eta'' - f_eta''(t, eta, eta'))`: the two must agree to
//!    rounding. This checks every term of the modal equations (mass, bending stiffness, the
//!    geometric stiffness of the quadratic axial force, the centrifugal softening, both
//!    forcing vectors) against the PDE itself. The shapes `psi_1 = xi - 2 xi^3 + xi^4` and
//!    `psi_2 = (7 xi - 10 xi^3 + 3 xi^5) / 3` (static deflections under uniform and linearly
//!    varying loads) are not modes of anything here, and satisfy `w = w'' = 0` at both ends,
//!    so the integration by parts that turns `int EI w'''' psi` into `int EI w'' psi''`
//!    leaves no boundary terms.

use std::f64::consts::{PI, TAU};
use std::sync::Arc;

use flexprr_beam::{Basis, GaussLegendre, HermiteBasis, SineBasis, UniformSection};
use flexprr_dynamics::{
    Formulation, LinkModel, Machine, ModalDamping, ModalSystem, inverse_dynamics_full, paper,
};
use flexprr_integrators::{Abm, Integrator, OdeSystem, Options};
use flexprr_kinematics::Geometry;

/// The paper's machine (model.md sections 1-2, as `flexprr_dynamics::paper::machine` builds it) with
/// the links discretized by `basis`.
fn machine_with(basis: Arc<dyn Basis>) -> Arc<Machine> {
    let alpha = paper::ALPHA_DEG.map(f64::to_radians);
    let geometry = Geometry::radial(
        alpha,
        paper::LINK_LENGTH,
        paper::PLATFORM_SIDE,
        paper::HALF_TRAVEL,
    )
    .unwrap();
    let section = UniformSection::rectangle(
        paper::YOUNGS_MODULUS,
        paper::DENSITY,
        paper::THICKNESS,
        paper::HEIGHT,
    )
    .unwrap();
    let link = LinkModel::new(basis, &section, paper::LINK_LENGTH).unwrap();
    let m_p = paper::PLATFORM_MASS;
    Arc::new(
        Machine::new(
            geometry,
            [link.clone(), link.clone(), link],
            [paper::SLIDER_MASS; 3],
            m_p,
            m_p * paper::PLATFORM_SIDE * paper::PLATFORM_SIDE / 12.0,
        )
        .unwrap(),
    )
}

fn consistent_system(machine: Arc<Machine>, frequency: f64) -> ModalSystem {
    let trajectory = Arc::new(paper::trajectory(frequency).unwrap());
    ModalSystem::new(
        machine,
        trajectory,
        Formulation::consistent(),
        ModalDamping::none(),
    )
    .unwrap()
}

// ---------------------------------------------------------------------------------------
// 1. Hermite elements against sine modes.

const HORIZON: f64 = 0.1;
const SAMPLES: usize = 200;

/// Mid-point deflections `w_i(l/2, t_k)` of the three links at `SAMPLES` times in
/// `(0, HORIZON]` (two periods of the circle), flattened. Solved with the Adams method at a
/// tolerance far below the discretization differences measured (RK45 gives the same figures to
/// three digits); the absolute tolerance leaves the tiny, very fast element modes unresolved
/// in step size, which keeps the FE solves cheap.
fn midpoint_history(basis: Arc<dyn Basis>) -> Vec<f64> {
    let machine = machine_with(basis);
    let mut sys = consistent_system(machine.clone(), 20.0);
    let y0 = sys.initial_state();
    let t_out: Vec<f64> = (1..=SAMPLES)
        .map(|k| HORIZON * k as f64 / SAMPLES as f64)
        .collect();
    let sol = Abm::new(Options::default().rtol(1e-9).atol(1e-12))
        .solve(&mut sys, 0.0, &y0, &t_out)
        .unwrap();
    let mut out = Vec::with_capacity(3 * SAMPLES);
    for k in 0..SAMPLES {
        let y = sol.y(k);
        for i in 0..3 {
            let range = sys.link_range(i);
            out.push(machine.links[i].deflection(&y[range], 0.5));
        }
    }
    out
}

fn relative_l2(a: &[f64], b: &[f64]) -> f64 {
    let diff: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum();
    let norm: f64 = b.iter().map(|y| y * y).sum();
    (diff / norm).sqrt()
}

/// The sine-mode and Hermite-element discretizations of the consistent formulation converge
/// to the same mid-point deflection histories as modes and elements are added. Measured
/// (relative L2, three links, 0-0.1 s): about 1.0, 0.1, 7e-3 and 1e-3 for the pairs below; the
/// sine side converges faster (`r^-4`), so the last figures are the elements' error.
#[test]
fn hermite_elements_and_sine_modes_converge_to_each_other() {
    let pairs = [(1, 1), (3, 2), (5, 4), (9, 8)];
    let mut differences = Vec::new();
    for (modes, elements) in pairs {
        let sine = midpoint_history(Arc::new(SineBasis::new(modes).unwrap()));
        let fe = midpoint_history(Arc::new(HermiteBasis::pinned_pinned(elements).unwrap()));
        let d = relative_l2(&sine, &fe);
        println!("sine r = {modes:2} vs Hermite {elements:2} elements: relative L2 {d:.3e}");
        differences.push(d);
    }
    for w in differences.windows(2) {
        assert!(w[1] < 0.2 * w[0], "no convergence: {differences:?}");
    }
    assert!(
        *differences.last().unwrap() < 2e-3,
        "finest pair still differs: {differences:?}"
    );
}

// ---------------------------------------------------------------------------------------
// 2. Manufactured solution of the transverse PDE.

/// Two non-modal shapes with `psi(0) = psi(1) = psi''(0) = psi''(1) = 0`: the static
/// deflections of a pinned-pinned beam under a uniform and a linearly varying load.
#[derive(Debug)]
struct LoadShapes;

impl LoadShapes {
    /// `[psi, psi', psi'', psi''', psi'''']` in `xi`.
    fn derivatives(j: usize, xi: f64) -> [f64; 5] {
        let (x2, x3) = (xi * xi, xi * xi * xi);
        match j {
            0 => [
                xi - 2.0 * x3 + x3 * xi,
                1.0 - 6.0 * x2 + 4.0 * x3,
                -12.0 * xi + 12.0 * x2,
                -12.0 + 24.0 * xi,
                24.0,
            ],
            _ => [
                (7.0 * xi - 10.0 * x3 + 3.0 * x3 * x2) / 3.0,
                (7.0 - 30.0 * x2 + 15.0 * x2 * x2) / 3.0,
                -20.0 * xi + 20.0 * x3,
                -20.0 + 60.0 * x2,
                120.0 * xi,
            ],
        }
    }
}

impl Basis for LoadShapes {
    fn len(&self) -> usize {
        2
    }
    fn eval(&self, j: usize, xi: f64) -> [f64; 3] {
        let d = Self::derivatives(j, xi);
        [d[0], d[1], d[2]]
    }
    fn name(&self) -> String {
        "static load shapes".into()
    }
    fn polynomial_degree(&self) -> Option<usize> {
        Some(5)
    }
}

/// `[psi, psi', psi'', psi''', psi'''']` of `sin(j pi xi)` in `xi`.
fn sine_derivatives(j: usize, xi: f64) -> [f64; 5] {
    let k = (j + 1) as f64 * PI;
    let (s, c) = (k * xi).sin_cos();
    [s, k * c, -k * k * s, -k * k * k * c, k.powi(4) * s]
}

/// A prescribed, non-solution modal history: `(eta, eta', eta'')` of mode `j` of link `i`.
fn prescribed(i: usize, j: usize, t: f64) -> (f64, f64, f64) {
    let amplitude = 1e-3 / (1.0 + j as f64).powi(2) * (1.0 + 0.3 * i as f64);
    let omega = TAU * (37.0 + 23.0 * j as f64 + 5.0 * i as f64);
    let phase = 0.4 * (i + j) as f64;
    let (s, c) = (omega * t + phase).sin_cos();
    (
        amplitude * s,
        amplitude * omega * c,
        -amplitude * omega * omega * s,
    )
}

fn manufactured_check(basis: Arc<dyn Basis>, derivatives: fn(usize, f64) -> [f64; 5]) {
    let r = basis.len();
    let machine = machine_with(basis);
    let mut sys = consistent_system(machine.clone(), 20.0);
    let l = paper::LINK_LENGTH;
    let ei = paper::YOUNGS_MODULUS * paper::HEIGHT * paper::THICKNESS.powi(3) / 12.0;
    let rho_a = paper::DENSITY * paper::HEIGHT * paper::THICKNESS;
    let rule = GaussLegendre::new(40).unwrap();
    for t in [0.0, 0.0071, 0.0163, 0.0254, 0.0388, 0.047] {
        // The state (eta, eta') of the prescribed history and the modal system's eta''.
        let mut y = vec![0.0; 6 * r];
        let mut eta_ddot = vec![0.0; 3 * r];
        for i in 0..3 {
            for j in 0..r {
                let (e, ed, edd) = prescribed(i, j, t);
                y[i * r + j] = e;
                y[3 * r + i * r + j] = ed;
                eta_ddot[i * r + j] = edd;
            }
        }
        let mut dy = vec![0.0; 6 * r];
        sys.rhs(t, &y, &mut dy);
        let model_acc = &dy[3 * r..];
        // Rigid motion from the inverse kinematics, forces from the 12-equation system.
        let state = sys.instant(t).unwrap().state;
        let reactions = inverse_dynamics_full(&machine, &state, t).unwrap();
        for i in 0..3 {
            let leg = &state.legs[i];
            let a = paper::ALPHA_DEG[i].to_radians();
            let (sin_ab, cos_ba) = ((a - leg.beta).sin(), (leg.beta - a).cos());
            let p0 = -reactions.slider_on_link[i].dot(&leg.e);
            let (p1, p2) = (
                rho_a * leg.rho_ddot * cos_ba,
                -0.5 * rho_a * leg.beta_dot.powi(2),
            );
            // w and its derivatives at x (closed form, chain rule d/dx = (1/l) d/dxi).
            let field = |x: f64| {
                let xi = x / l;
                let mut w = [0.0; 5];
                let mut w_tt = 0.0;
                for j in 0..r {
                    let (e, _, edd) = prescribed(i, j, t);
                    let d = derivatives(j, xi);
                    for (n, wn) in w.iter_mut().enumerate() {
                        *wn += e * d[n] / l.powi(n as i32);
                    }
                    w_tt += edd * d[0];
                }
                (w, w_tt)
            };
            let residual = |x: f64| {
                let (w, w_tt) = field(x);
                let p = p0 + p1 * x + p2 * x * x;
                let p_x = p1 + 2.0 * p2 * x;
                rho_a
                    * (w_tt + leg.rho_ddot * sin_ab + x * leg.beta_ddot
                        - leg.beta_dot.powi(2) * w[0])
                    + ei * w[4]
                    - (p_x * w[1] + p * w[2])
            };
            // Scale: the largest single term, for a relative tolerance.
            let scale = rule.integrate(0.0, l, |x| {
                let (w, _) = field(x);
                (ei * w[4]).abs() + rho_a * (leg.rho_ddot.abs() + x * leg.beta_ddot.abs())
            });
            let mass = &machine.links[i].integrals.mass;
            for k in 0..r {
                let projected = rule.integrate(0.0, l, |x| residual(x) * derivatives(k, x / l)[0]);
                let implied: f64 = (0..r)
                    .map(|q| mass[(k, q)] * (eta_ddot[i * r + q] - model_acc[i * r + q]))
                    .sum();
                assert!(
                    (projected - implied).abs() <= 1e-10 * scale,
                    "t = {t}, link {i}, shape {k}: projected residual {projected} vs M (eta'' - f) {implied} (scale {scale})"
                );
            }
        }
    }
}

/// The manufactured check on the two non-modal load shapes.
#[test]
fn modal_equations_are_the_galerkin_projection_of_the_pde_for_non_modal_shapes() {
    manufactured_check(Arc::new(LoadShapes), LoadShapes::derivatives);
}

/// The same check with a combination of five sine modes.
#[test]
fn modal_equations_are_the_galerkin_projection_of_the_pde_for_sine_modes() {
    manufactured_check(Arc::new(SineBasis::new(5).unwrap()), sine_derivatives);
}
