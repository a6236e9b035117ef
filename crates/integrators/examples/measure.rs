//! Prints the "Measured, all methods" table of `docs/integrators.md`:
//! `cargo run --release -p flexprr-integrators --example measure`.

use flexprr_integrators::test_problems::{
    ForcedOscillator, HarmonicOscillator, Robertson, TestProblem, VanDerPol,
};
use flexprr_integrators::{Abm, Bdf, Integrator, Options, Rk45};

fn row<I: Integrator, P: TestProblem>(method: &I, mut problem: P, label: &str) {
    let y0 = problem.y0();
    let t_end = problem.t_end();
    let t0 = problem.t0();
    match method.solve(&mut problem, t0, &y0, &[t_end]) {
        Ok(sol) => {
            let s = &sol.stats;
            let note = match problem.exact(t_end) {
                Some(exact) => {
                    let err = sol
                        .y(0)
                        .iter()
                        .zip(&exact)
                        .map(|(a, b)| (a - b).abs())
                        .fold(0.0, f64::max);
                    format!("{err:.1e} at t_end")
                }
                None => String::new(),
            };
            println!(
                "| {label} | {} | {} | {} | {note} |",
                method.name(),
                s.accepted_steps + s.rejected_steps,
                s.rhs_evaluations
            );
        }
        Err(e) => println!("| {label} | {} | - | - | {e} |", method.name()),
    }
}

fn main() {
    let vdp = Options::default().rtol(1e-3).atol(1e-3);
    row(
        &Rk45::new(vdp.clone()),
        VanDerPol::default(),
        "Van der Pol eps = 0.003, rtol = atol = 1e-3",
    );
    row(
        &Abm::new(vdp.clone()),
        VanDerPol::default(),
        "Van der Pol eps = 0.003, rtol = atol = 1e-3",
    );
    row(
        &Bdf::new(vdp),
        VanDerPol::default(),
        "Van der Pol eps = 0.003, rtol = atol = 1e-3",
    );
    let tight = Options::default().rtol(1e-8).atol(1e-10);
    let label = "ForcedOscillator, rtol 1e-8, atol 1e-10";
    row(
        &Rk45::new(tight.clone()),
        ForcedOscillator::default(),
        label,
    );
    row(&Abm::new(tight.clone()), ForcedOscillator::default(), label);
    row(&Bdf::new(tight.clone()), ForcedOscillator::default(), label);
    let label = "HarmonicOscillator, rtol 1e-8, atol 1e-10";
    row(
        &Rk45::new(tight.clone()),
        HarmonicOscillator::default(),
        label,
    );
    row(
        &Abm::new(tight.clone()),
        HarmonicOscillator::default(),
        label,
    );
    row(&Bdf::new(tight), HarmonicOscillator::default(), label);
    let stiff = Options::default().rtol(1e-6).atol(1e-6);
    row(
        &Bdf::new(stiff),
        VanDerPol::with_mu(1000.0),
        "Van der Pol mu = 1000, rtol = atol = 1e-6",
    );
    let rob = Options::default()
        .rtol(1e-4)
        .atol_per_component(vec![1e-8, 1e-14, 1e-6]);
    row(
        &Bdf::new(rob),
        Robertson::default(),
        "Robertson to 1e5, CVODE's tolerances",
    );
}
