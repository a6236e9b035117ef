//! The nonlinear model ([`NonlinearSystem`]) under the generalized-alpha integrator
//! ([`GeneralizedAlpha`], its mechanical form with analytic element tangents) against
//! independent references:
//! * the converged external model (Exudyn ANCF, 32 elements, undamped, committed data in
//!   `validation/data/collapse_f30_undamped_ne32.csv`) through the 30 Hz collapse, 0-64 ms;
//! * the energy balance of the undamped machine: `E(t) - E(0)` = the work of the prescribed
//!   sliders;
//! * ABM on the same model (the same equations, a different method).

use std::sync::Arc;
use std::time::Instant;

use flexprr_dynamics::{NonlinearOptions, NonlinearSystem, paper};
use flexprr_integrators::{Abm, GeneralizedAlpha, Integrator, OdeSystem, Options, Stepper};

fn nonlinear(f: f64, elements: usize) -> NonlinearSystem {
    let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
    let trajectory = Arc::new(paper::trajectory(f).unwrap());
    let options = NonlinearOptions {
        elements,
        stop_at_type_ii: false,
        ..NonlinearOptions::paper(paper::YOUNGS_MODULUS)
    };
    NonlinearSystem::new(machine, trajectory, options).unwrap()
}

/// The committed reference: rows of `(t, w_mid[3])`.
fn reference() -> (Vec<f64>, Vec<[f64; 3]>) {
    let path = format!(
        "{}/../../validation/data/collapse_f30_undamped_ne32.csv",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(path).unwrap();
    let (mut t, mut w) = (vec![], vec![]);
    for line in text.lines().skip(1) {
        let v: Vec<f64> = line.split(',').map(|s| s.trim().parse().unwrap()).collect();
        t.push(v[0]);
        w.push([v[1], v[2], v[3]]);
    }
    (t, w)
}

/// `||a - b|| / ||b||` over all samples and links.
fn rel_l2(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        for k in 0..3 {
            num += (x[k] - y[k]) * (x[k] - y[k]);
            den += y[k] * y[k];
        }
    }
    (num / den).sqrt()
}

/// Mid-point deflections at `times` with `method`, and its statistics.
fn deflections<I: Integrator>(
    method: &I,
    s: &mut NonlinearSystem,
    times: &[f64],
) -> (Vec<[f64; 3]>, flexprr_integrators::Stats) {
    let y0 = s.initial_state(0.0).unwrap();
    let sol = method.solve(s, 0.0, &y0, &times[1..]).unwrap();
    let mut w = vec![[0.0; 3]];
    for k in 0..sol.len() {
        w.push(s.output(sol.t[k], sol.y(k)).unwrap().midpoint_deflection);
    }
    (w, sol.stats)
}

#[test]
fn genalpha_matches_the_converged_external_model_at_8_elements() {
    let (t, w_ref) = reference();
    for rtol in [1e-3, 1e-4, 1e-5] {
        let mut s = nonlinear(30.0, 8);
        let ga = GeneralizedAlpha::new(Options::default().rtol(rtol).atol(rtol * 1e-3));
        let clock = Instant::now();
        let (w, stats) = deflections(&ga, &mut s, &t);
        let err = rel_l2(&w, &w_ref);
        println!(
            "genalpha rtol {rtol:e}: {:.3} % ({:.3} s, {} steps, {} rejected, {} rhs, {} matrices, {} LU, {} Newton)",
            100.0 * err,
            clock.elapsed().as_secs_f64(),
            stats.accepted_steps,
            stats.rejected_steps,
            stats.rhs_evaluations,
            stats.jacobian_evaluations,
            stats.lu_decompositions,
            stats.newton_iterations
        );
    }
    let mut s = nonlinear(30.0, 8);
    let abm = Abm::new(Options::default().rtol(1e-8).atol(1e-11));
    let clock = Instant::now();
    let (w, stats) = deflections(&abm, &mut s, &t);
    println!(
        "abm 1e-8: {:.3} % ({:.3} s, {} steps)",
        100.0 * rel_l2(&w, &w_ref),
        clock.elapsed().as_secs_f64(),
        stats.accepted_steps
    );
}

#[test]
fn debug_steps() {
    let mut s = nonlinear(30.0, 8);
    let y0 = s.initial_state(0.0).unwrap();
    let ga = GeneralizedAlpha::new(Options::default().rtol(1e-3).atol(1e-6));
    let mut st = ga.start(&mut s, 0.0, &y0, 0.064).unwrap();
    for _ in 0..300 {
        st.step(&mut s).unwrap();
    }
}
