//! The linear time-varying form of the KED modal system against independent checks: its
//! accelerations against the system's own right-hand side (a second implementation of the
//! same equations, in other coordinates), and the Magnus integrators against Dormand-Prince
//! at rtol 1e-12 on the paper scene, the consistent formulation with damping, more modes and
//! Hermite finite-element links, and against the shared reference state of an independent
//! Python implementation (paper scene, t = 0.2 s).

use std::sync::Arc;

use flexprr_beam::{Basis, HermiteBasis, UniformSection};
use flexprr_dynamics::{Formulation, LinkModel, Machine, ModalDamping, ModalSystem, paper};
use flexprr_integrators::{
    Integrator, IntegratorError, Magnus, MagnusOrder, OdeSystem, Options, Rk45, Solution,
};

fn sine_system(r: usize, formulation: Formulation, damping: ModalDamping) -> ModalSystem {
    let machine = Arc::new(paper::machine(r, paper::YOUNGS_MODULUS).unwrap());
    let trajectory = Arc::new(paper::trajectory(20.0).unwrap());
    ModalSystem::new(machine, trajectory, formulation, damping).unwrap()
}

fn hermite_system(elements: usize, formulation: Formulation) -> ModalSystem {
    let section = UniformSection::rectangle(
        paper::YOUNGS_MODULUS,
        paper::DENSITY,
        paper::THICKNESS,
        paper::HEIGHT,
    )
    .unwrap();
    let basis: Arc<dyn Basis> = Arc::new(HermiteBasis::pinned_pinned(elements).unwrap());
    let link = LinkModel::new(basis, &section, paper::LINK_LENGTH).unwrap();
    let base = paper::machine(1, paper::YOUNGS_MODULUS).unwrap();
    let machine = Machine::new(
        base.geometry,
        [link.clone(), link.clone(), link],
        base.slider_mass,
        base.platform_mass,
        base.platform_inertia,
    )
    .unwrap();
    ModalSystem::new(
        Arc::new(machine),
        Arc::new(paper::trajectory(20.0).unwrap()),
        formulation,
        ModalDamping::uniform(0.005),
    )
    .unwrap()
}

/// The accelerations of the linear form, mapped back to `eta`, equal the right-hand side's
/// for an arbitrary state: `eta'' = Phi (g - S x - D x')` with `x = Phi^T M eta`.
#[test]
fn linear_form_reproduces_the_right_hand_side() {
    let systems = [
        sine_system(3, Formulation::paper(), ModalDamping::none()),
        sine_system(4, Formulation::consistent(), ModalDamping::uniform(0.02)),
        hermite_system(3, Formulation::consistent()),
    ];
    for mut sys in systems {
        let n = sys.modes();
        let y: Vec<f64> = (0..2 * n)
            .map(|i| 1e-4 * ((i * 7 + 3) as f64).sin() * if i < n { 1.0 } else { 50.0 })
            .collect();
        for t in [0.013, 0.071, 0.155] {
            let mut dy = vec![0.0; 2 * n];
            sys.rhs(t, &y, &mut dy);
            let lin = sys.linear_form().unwrap();
            let ops: Vec<_> = (0..3).map(|b| lin.block_operators(b)).collect();
            let mut s = vec![0.0; 3 * ops[0].stiffness.len()];
            let mut f = vec![0.0; 3 * ops[0].forcing.len()];
            lin.coefficients(t, &mut s, &mut f);
            let mut offset = 0;
            for (b, op) in ops.iter().enumerate() {
                let r = op.size;
                let (tm, ti) = op.transform.as_ref().unwrap();
                let to_x = |v: &[f64]| -> Vec<f64> {
                    (0..r)
                        .map(|i| (0..r).map(|k| ti[i * r + k] * v[k]).sum())
                        .collect()
                };
                let x = to_x(&y[offset..offset + r]);
                let xd = to_x(&y[n + offset..n + offset + r]);
                let ns = op.stiffness.len();
                let nf = op.forcing.len();
                let mut acc_x = vec![0.0; r];
                for i in 0..r {
                    let mut a = 0.0;
                    for (m, g) in op.forcing.iter().enumerate() {
                        a += f[b * nf + m] * g[i];
                    }
                    for k in 0..r {
                        let sik: f64 = (0..ns)
                            .map(|m| s[b * ns + m] * op.stiffness[m][i * r + k])
                            .sum();
                        a -= sik * x[k];
                        if let Some(d) = &op.damping {
                            a -= d[i * r + k] * xd[k];
                        }
                    }
                    acc_x[i] = a;
                }
                for i in 0..r {
                    let acc: f64 = (0..r).map(|k| tm[i * r + k] * acc_x[k]).sum();
                    let want = dy[n + offset + i];
                    assert!(
                        (acc - want).abs() <= 1e-9 * want.abs().max(1e-6),
                        "block {b}, mode {i}, t = {t}: {acc} vs {want}"
                    );
                }
                offset += r;
            }
        }
    }
}

/// Error measure of the project's work-precision runs: displacement differences over the
/// largest reference `|eta|`, velocity differences over the largest `|eta'|`, maximum over
/// all output times.
fn max_error(sol: &Solution, reference: &Solution, modes: usize) -> f64 {
    let size = |range: std::ops::Range<usize>| {
        (0..reference.len())
            .flat_map(|k| reference.y(k)[range.clone()].to_vec())
            .fold(0.0_f64, |a, v| a.max(v.abs()))
    };
    let (sd, sv) = (size(0..modes), size(modes..2 * modes));
    let mut worst: f64 = 0.0;
    for k in 0..reference.len() {
        for i in 0..2 * modes {
            let s = if i < modes { sd } else { sv };
            worst = worst.max((sol.y(k)[i] - reference.y(k)[i]).abs() / s);
        }
    }
    worst
}

/// Runs `method` at `tol` and Dormand-Prince at 1e-12 on `sys` over `[0, t_end]` with
/// `outputs` dense outputs; returns the error and the two solutions.
fn compare(
    sys: &mut ModalSystem,
    order: MagnusOrder,
    tol: f64,
    t_end: f64,
    outputs: usize,
) -> (f64, Solution, Solution) {
    let n = sys.modes();
    let t_out: Vec<f64> = (0..outputs)
        .map(|k| t_end * k as f64 / (outputs - 1) as f64)
        .collect();
    let y0 = sys.initial_state();
    // Displacements are of order 1e-4 m: atol as the project's work-precision runs set it.
    let size = 1e-4;
    let reference = Rk45::new(Options::default().rtol(1e-12).atol(1e-12 * size))
        .solve(sys, 0.0, &y0, &t_out)
        .unwrap();
    let sol = Magnus::new(Options::default().rtol(tol).atol(tol * size), order)
        .solve(sys, 0.0, &y0, &t_out)
        .unwrap();
    (max_error(&sol, &reference, n), sol, reference)
}

/// Paper scene (paper formulation, r = 3, 0.2 s, 401 outputs): both orders within 1e-6 of
/// Dormand-Prince at 1e-12, with far fewer steps.
#[test]
fn paper_scene_agrees_with_rk45() {
    let mut sys = sine_system(3, Formulation::paper(), ModalDamping::none());
    for order in [MagnusOrder::Four, MagnusOrder::Six] {
        let (err, sol, reference) = compare(&mut sys, order, 1e-7, 0.2, 401);
        assert!(err < 1e-6, "{order:?}: {err:e}");
        assert!(sol.stats.accepted_steps * 5 < reference.stats.accepted_steps);
    }
}

/// Consistent formulation (full Kp couples the modes, softening) with 1 % damping and
/// r = 8 sine modes, and Hermite finite-element links (full mass matrix): within 1e-6.
#[test]
fn consistent_damped_and_finite_element_scenes_agree_with_rk45() {
    let mut systems = [
        sine_system(3, Formulation::consistent(), ModalDamping::uniform(0.01)),
        sine_system(8, Formulation::consistent(), ModalDamping::uniform(0.01)),
        hermite_system(4, Formulation::consistent()),
        hermite_system(4, Formulation::paper()),
    ];
    for sys in &mut systems {
        for order in [MagnusOrder::Four, MagnusOrder::Six] {
            let (err, _, _) = compare(sys, order, 1e-7, 0.05, 201);
            assert!(err < 1e-6, "{} modes, {order:?}: {err:e}", sys.modes());
        }
    }
}

/// The state at t = 0.2 s against the shared reference of an independent implementation
/// (Python, DOP853 at rtol 1e-13).
#[test]
fn paper_scene_matches_the_independent_reference_state() {
    let text = include_str!("../../../tests/data/paper_f20_state_t0.2.json");
    let start = text.find("\"state\"").unwrap();
    let open = start + text[start..].find('[').unwrap();
    let close = open + text[open..].find(']').unwrap();
    let want: Vec<f64> = text[open + 1..close]
        .split(',')
        .map(|v| v.trim().parse().unwrap())
        .collect();
    assert_eq!(want.len(), 18);
    let mut sys = sine_system(3, Formulation::paper(), ModalDamping::none());
    let y0 = sys.initial_state();
    let sol = Magnus::magnus6(Options::default().rtol(1e-9).atol(1e-13))
        .solve(&mut sys, 0.0, &y0, &[0.2])
        .unwrap();
    let sd = want[..9].iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    let sv = want[9..].iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    for (i, (got, w)) in sol.y(0).iter().zip(&want).enumerate() {
        let s = if i < 9 { sd } else { sv };
        let e = (got - w).abs() / s;
        assert!(e < 1e-6, "component {i}: {got} vs {w} ({e:e})");
    }
}

/// The coupled model is nonlinear: Magnus refuses it and names the method to use.
#[test]
fn coupled_model_is_refused() {
    use flexprr_dynamics::{CoupledOptions, CoupledSystem};
    let machine = Arc::new(paper::machine(2, paper::YOUNGS_MODULUS).unwrap());
    let trajectory = Arc::new(paper::trajectory(20.0).unwrap());
    let mut sys = CoupledSystem::new(
        machine,
        trajectory,
        ModalDamping::none(),
        CoupledOptions::default(),
    )
    .unwrap();
    let y0 = sys.initial_state();
    let err = Magnus::magnus4(Options::default())
        .solve(&mut sys, 0.0, &y0, &[0.01])
        .unwrap_err();
    match err {
        IntegratorError::InvalidInput(msg) => assert!(msg.contains("abm"), "{msg}"),
        e => panic!("unexpected {e}"),
    }
}
