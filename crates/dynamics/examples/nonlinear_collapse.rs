//! Collapse times and cost of the three link models on the paper scene.
//!
//! For each speed: the time at which the largest mid-point deflection first passes 10 % of
//! the link length (the external model's collapse criterion, validation/data/
//! collapse_speeds.json) for the nonlinear model (32 elements) and the coupled model,
//! and the wall time of each run. Then the cost of a fixed 0.2 s run at 20 Hz (rtol 1e-6):
//! KED (consistent), coupled, nonlinear 16 and 32 elements.
//!
//! `cargo run --release -p flexprr-dynamics --example nonlinear_collapse [-- speeds... | cost]`

use std::sync::Arc;
use std::time::Instant;

use flexprr_dynamics::{
    CoupledOptions, CoupledSystem, Formulation, ModalDamping, ModalSystem, NonlinearOptions,
    NonlinearSystem, paper,
};
use flexprr_integrators::{Integrator, OdeSystem, Options, Rk45, Stepper};

/// Integrates to `t_end`, the system's terminal event (a collapse limit) or the first
/// failure; returns (end time, rhs evaluations, steps).
fn run<S: OdeSystem>(s: &mut S, y0: &[f64], t_end: f64, rtol: f64) -> (f64, usize, usize) {
    let rk = Rk45::new(Options::default().rtol(rtol).atol(rtol * 1e-3));
    match rk.solve_observed(s, 0.0, y0, &[t_end], &[], &mut ()) {
        Ok(sol) => (t_end, sol.stats.rhs_evaluations, sol.stats.accepted_steps),
        Err(e) => (
            e.last_time().unwrap_or(0.0),
            e.solution.stats.rhs_evaluations,
            e.solution.stats.accepted_steps,
        ),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let cost_only = args.first().is_some_and(|a| a == "cost");
    let speeds: Vec<f64> = if cost_only {
        vec![]
    } else {
        args.iter()
            .map(|a| a.parse().expect("speed in Hz"))
            .collect()
    };
    let speeds = if speeds.is_empty() && !cost_only {
        vec![25.0, 26.0, 27.0, 28.0, 29.0, 30.0]
    } else {
        speeds
    };
    let machine = Arc::new(paper::machine(6, paper::YOUNGS_MODULUS).unwrap());
    let t_end = 0.5;
    println!("speed_Hz,model,collapse_t_s,message,wall_s");
    for &f in &speeds {
        let traj = Arc::new(paper::trajectory(f).unwrap());
        {
            let elements = 32;
            let options = NonlinearOptions {
                elements,
                stop_at_type_ii: false,
                collapse_deflection: Some(0.1),
                ..NonlinearOptions::paper(paper::YOUNGS_MODULUS)
            };
            let mut s = NonlinearSystem::new(machine.clone(), traj.clone(), options).unwrap();
            let y0 = s.initial_state(0.0).unwrap();
            let clock = Instant::now();
            let (t, _, _) = run(&mut s, &y0, t_end, 1e-7);
            let wall = clock.elapsed().as_secs_f64();
            let failure = s.take_failure().map(|e| e.to_string()).unwrap_or_default();
            let tc = if failure.is_empty() { f64::NAN } else { t };
            println!("{f},nonlinear{elements},{tc:.5},\"{failure}\",{wall:.2}");
        }
        let mut c = CoupledSystem::new(
            machine.clone(),
            traj.clone(),
            ModalDamping::none(),
            CoupledOptions::full(),
        )
        .unwrap();
        let y0 = c.initial_state();
        let clock = Instant::now();
        let rk = Rk45::new(Options::default().rtol(1e-9).atol(1e-12));
        let mut st = rk.start(&mut c, 0.0, &y0, t_end).unwrap();
        let mut collapse = f64::NAN;
        let mut message = String::new();
        let range: Vec<_> = (0..3).map(|i| c.link_range(i)).collect();
        let psi_mid: Vec<f64> = (0..6)
            .map(|j| machine.links[0].basis.eval(j, 0.5)[0])
            .collect();
        while st.t() < t_end {
            if st.step(&mut c).is_err() {
                message = c.take_failure().map(|e| e.to_string()).unwrap_or_default();
                collapse = st.t();
                break;
            }
            let y = st.y();
            let w = range
                .iter()
                .map(|r| {
                    y[r.clone()]
                        .iter()
                        .zip(&psi_mid)
                        .map(|(a, b)| a * b)
                        .sum::<f64>()
                        .abs()
                })
                .fold(0.0, f64::max);
            if w > 0.02 {
                collapse = st.t();
                message = format!("mid-point deflection {:.1} mm", w * 1e3);
                break;
            }
        }
        let wall = clock.elapsed().as_secs_f64();
        println!("{f},coupled,{collapse:.5},\"{message}\",{wall:.2}");
    }
    // Cost of one 0.2 s run at 20 Hz, rtol 1e-6.
    let traj = Arc::new(paper::trajectory(20.0).unwrap());
    println!("\nmodel,rhs_evaluations,steps,wall_s (20 Hz, 0.2 s, RK45 rtol 1e-6)");
    let mut k = ModalSystem::new(
        machine.clone(),
        traj.clone(),
        Formulation::consistent(),
        ModalDamping::none(),
    )
    .unwrap();
    let y0 = k.initial_state();
    let clock = Instant::now();
    let (_, rhs, steps) = run(&mut k, &y0, 0.2, 1e-6);
    println!(
        "ked_consistent_r6,{rhs},{steps},{:.4}",
        clock.elapsed().as_secs_f64()
    );
    let mut c = CoupledSystem::new(
        machine.clone(),
        traj.clone(),
        ModalDamping::none(),
        CoupledOptions::full(),
    )
    .unwrap();
    let y0 = c.initial_state();
    let clock = Instant::now();
    let (_, rhs, steps) = run(&mut c, &y0, 0.2, 1e-6);
    println!(
        "coupled_r6,{rhs},{steps},{:.4}",
        clock.elapsed().as_secs_f64()
    );
    for elements in [16, 32] {
        let options = NonlinearOptions {
            elements,
            stop_at_type_ii: false,
            ..NonlinearOptions::paper(paper::YOUNGS_MODULUS)
        };
        let mut s = NonlinearSystem::new(machine.clone(), traj.clone(), options).unwrap();
        let y0 = s.initial_state(0.0).unwrap();
        let clock = Instant::now();
        let (_, rhs, steps) = run(&mut s, &y0, 0.2, 1e-6);
        println!(
            "nonlinear{elements},{rhs},{steps},{:.4}",
            clock.elapsed().as_secs_f64()
        );
    }
}
