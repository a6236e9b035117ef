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
use flexprr_integrators::{Abm, GeneralizedAlpha, Integrator, Options};

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

/// Within 1 % of the converged external model at the default 8 elements (the element
/// error is 0.234 %, ABM at rtol 1e-8 measures it), at a tolerance 1000x looser than ABM
/// needs; 16 elements come closer still. Times are printed, not asserted.
#[test]
fn genalpha_matches_the_converged_external_model() {
    let (t, w_ref) = reference();
    // Issue 34's goal: 16 elements within 0.2 % at rtol 1e-7 (measured 0.04 %).
    for (elements, rtol, bound) in [
        (8, 1e-5, 0.005),
        (8, 1e-6, 0.005),
        (16, 1e-6, 0.005),
        (16, 1e-7, 0.002),
    ] {
        let mut s = nonlinear(30.0, elements);
        let ga = GeneralizedAlpha::new(Options::default().rtol(rtol).atol(rtol * 1e-3));
        let clock = Instant::now();
        let (w, stats) = deflections(&ga, &mut s, &t);
        let err = rel_l2(&w, &w_ref);
        println!(
            "{elements} elements, generalized-alpha rtol {rtol:e}: {:.3} % ({:.3} s, {} steps, \
             {} rejected, {} rhs, {} matrices, {} LU, {} Newton)",
            100.0 * err,
            clock.elapsed().as_secs_f64(),
            stats.accepted_steps,
            stats.rejected_steps,
            stats.rhs_evaluations,
            stats.jacobian_evaluations,
            stats.lu_decompositions,
            stats.newton_iterations
        );
        assert!(err < bound, "{elements} elements, rtol {rtol}: {err}");
    }
    let mut s = nonlinear(30.0, 8);
    let abm = Abm::new(Options::default().rtol(1e-8).atol(1e-11));
    let clock = Instant::now();
    let (w, stats) = deflections(&abm, &mut s, &t);
    let err = rel_l2(&w, &w_ref);
    println!(
        "8 elements, ABM rtol 1e-8: {:.3} % ({:.3} s, {} steps)",
        100.0 * err,
        clock.elapsed().as_secs_f64(),
        stats.accepted_steps
    );
    assert!(err < 0.005);
}

/// Undamped, the machine's energy changes by the work of the prescribed sliders,
/// `E(t) - E(0) = int sum F_B . B' dt` (the model's own energy and slider power, the
/// integral by the trapezoid on a 2 us grid of dense output), 20 Hz, 0-20 ms: the balance
/// error falls with the tolerance, with `rho_inf = 1` (no numerical
/// dissipation) and with the default 0.7 (which removes energy from the modes the steps do
/// not resolve). The tolerance is relative to the link length and one radian (the model's
/// tolerance scales).
#[test]
fn genalpha_keeps_the_energy_balance() {
    // Measured: 8.9e-3, 5.3e-4 and 1.9e-4 (rho_inf 1; 2.2e-5 at 1e-9), 3.3e-5 (0.7).
    let cases = [
        (1.0, 1e-6, 2e-2),
        (1.0, 1e-7, 1.2e-3),
        (1.0, 1e-8, 4e-4),
        (
            flexprr_integrators::genalpha::DEFAULT_SPECTRAL_RADIUS,
            1e-8,
            1e-4,
        ),
    ];
    for (rho, rtol, bound) in cases {
        let mut s = nonlinear(20.0, 8);
        let y0 = s.initial_state(0.0).unwrap();
        let dt = 2e-6;
        let times: Vec<f64> = (1..=10_000).map(|k| k as f64 * dt).collect();
        let ga = GeneralizedAlpha::new(Options::default().rtol(rtol).atol(rtol * 1e-3))
            .spectral_radius(rho);
        let sol = ga.solve(&mut s, 0.0, &y0, &times).unwrap();
        let mut outs = vec![s.output(0.0, &y0).unwrap()];
        for k in 0..sol.len() {
            outs.push(s.output(sol.t[k], sol.y(k)).unwrap());
        }
        let energy = |o: &flexprr_dynamics::NonlinearOutput| o.kinetic_energy + o.strain_energy;
        let (mut work, mut worst, mut scale) = (0.0, 0.0_f64, 0.0_f64);
        for k in 1..outs.len() {
            work += 0.5 * dt * (outs[k - 1].slider_power + outs[k].slider_power);
            let change = energy(&outs[k]) - energy(&outs[0]);
            worst = worst.max((change - work).abs());
            scale = scale.max(change.abs()).max(work.abs());
        }
        println!(
            "rho_inf {rho}, rtol {rtol:e}: energy balance off by {worst:.3e} J of {scale:.3e} J ({} steps)",
            sol.stats.accepted_steps
        );
        assert!(worst < bound * scale, "rho_inf {rho}: {worst} of {scale}");
    }
}

/// A tolerance that orders the error (issue 34): on the 30 Hz collapse (8 elements, 0-64 ms)
/// the relative L2 error of the mid-point deflections against a converged run of the same
/// model (ABM at rtol 1e-10) falls at every step of the ladder 1e-3, 3e-4, ..., 1e-8. It
/// used to rise from 1e-3 to 1e-4 (3.0, 3.1, 4.7 %) and from 3e-6 to 1e-6 (0.14, 0.18 %), with
/// 766 of 1 681 attempts rejected at 1e-4 (now 239 of 791). Generalized-alpha's error estimate
/// now has the method's own constant, its auxiliary acceleration follows changes of step, and
/// a PI controller sets the steps.
#[test]
fn genalpha_error_falls_with_the_tolerance() {
    let (t, _) = reference();
    let mut s = nonlinear(30.0, 8);
    let abm = Abm::new(
        Options::default()
            .rtol(1e-10)
            .atol(1e-13)
            .max_steps(100_000_000),
    );
    let (converged, _) = deflections(&abm, &mut s, &t);
    let mut previous = f64::INFINITY;
    for rtol in [
        1e-3, 3e-4, 1e-4, 3e-5, 1e-5, 3e-6, 1e-6, 3e-7, 1e-7, 3e-8, 1e-8,
    ] {
        let mut s = nonlinear(30.0, 8);
        let ga = GeneralizedAlpha::new(Options::default().rtol(rtol).atol(rtol * 1e-3));
        let (w, stats) = deflections(&ga, &mut s, &t);
        let err = rel_l2(&w, &converged);
        let attempts = stats.accepted_steps + stats.rejected_steps;
        println!(
            "rtol {rtol:e}: {:.4} % ({} steps, {} rejected)",
            100.0 * err,
            stats.accepted_steps,
            stats.rejected_steps
        );
        assert!(err < previous, "rtol {rtol:e}: {err} not below {previous}");
        if rtol <= 1e-4 {
            assert!(
                3 * stats.rejected_steps < attempts,
                "rtol {rtol:e}: {} of {attempts} rejected",
                stats.rejected_steps
            );
        }
        previous = err;
    }
}
