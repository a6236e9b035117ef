//! How generalized-alpha's error follows its tolerance on the nonlinear 30 Hz collapse
//! (docs/performance.md, "A tolerance that orders the error").
//!
//! The paper machine at 30 Hz with geometrically nonlinear links (`elements` per link,
//! undamped, no collapse stop), 0-64 ms, mid-point deflections every 0.25 ms (the external
//! model's samples). For each `rtol` (atol = rtol x 1e-3): steps, rejected attempts,
//! residuals, factorisations, the relative L2 error of the deflections against a converged
//! run of the same model (the time-integration error alone) and against the converged
//! external model (Exudyn ANCF, 32 elements, `validation/data/collapse_f30_undamped_ne32.csv`:
//! time and mesh error together), and the median wall time of `repeats` runs on this thread.
//! The converged run is ABM at rtol 1e-10 (checked against RK45 at 1e-10); it is written to
//! and read back from `--reference FILE`, so it is computed once.
//!
//! `cargo run --release -p flexprr-dynamics --example genalpha_tolerance -- [--elements 16]
//! [--rtols 1e-3,1e-4,...] [--repeats 3] [--reference out/reference_16.csv] [--rho 0.7]`

use std::sync::Arc;
use std::time::Instant;

use flexprr_dynamics::{NonlinearOptions, NonlinearSystem, paper};
use flexprr_integrators::{Abm, GeneralizedAlpha, Options, Rk45, Stats};

fn nonlinear(elements: usize) -> NonlinearSystem {
    let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
    let trajectory = Arc::new(paper::trajectory(30.0).unwrap());
    let options = NonlinearOptions {
        elements,
        stop_at_type_ii: false,
        ..NonlinearOptions::paper(paper::YOUNGS_MODULUS)
    };
    NonlinearSystem::new(machine, trajectory, options).unwrap()
}

/// The external model's samples: `(t, w_mid[3])` rows.
fn external() -> (Vec<f64>, Vec<[f64; 3]>) {
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

/// `||a - b|| / ||b||` over all samples and links, and `max |a - b| / max |b|`.
fn errors(a: &[[f64; 3]], b: &[[f64; 3]]) -> (f64, f64) {
    let (mut num, mut den, mut worst, mut peak) = (0.0, 0.0, 0.0_f64, 0.0_f64);
    for (x, y) in a.iter().zip(b) {
        for k in 0..3 {
            num += (x[k] - y[k]) * (x[k] - y[k]);
            den += y[k] * y[k];
            worst = worst.max((x[k] - y[k]).abs());
            peak = peak.max(y[k].abs());
        }
    }
    ((num / den).sqrt(), worst / peak)
}

/// Mid-point deflections at `times` (the first is the start) with `method`.
fn deflections(
    method: &dyn flexprr_integrators::DynIntegrator,
    elements: usize,
    times: &[f64],
) -> (Vec<[f64; 3]>, Stats, f64) {
    let mut s = nonlinear(elements);
    let y0 = s.initial_state(0.0).unwrap();
    let clock = Instant::now();
    let sol = method
        .solve_dyn(&mut s, 0.0, &y0, &times[1..], &[], &mut ())
        .unwrap_or_else(|e| panic!("{}: {e}", method.name()));
    let wall = clock.elapsed().as_secs_f64();
    let mut w = vec![[0.0; 3]];
    for k in 0..sol.len() {
        w.push(s.output(sol.t[k], sol.y(k)).unwrap().midpoint_deflection);
    }
    (w, sol.stats, wall)
}

fn read_reference(path: &str) -> Option<Vec<[f64; 3]>> {
    let text = std::fs::read_to_string(path).ok()?;
    Some(
        text.lines()
            .map(|l| {
                let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
                [v[0], v[1], v[2]]
            })
            .collect(),
    )
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1).cloned())
    };
    let elements: usize = value("--elements").map_or(16, |v| v.parse().unwrap());
    let repeats: usize = value("--repeats").map_or(3, |v| v.parse().unwrap());
    let rho: Option<f64> = value("--rho").map(|v| v.parse().unwrap());
    let rtols: Vec<f64> = value("--rtols")
        .unwrap_or_else(|| "1e-3,3e-4,1e-4,3e-5,1e-5,3e-6,1e-6,3e-7,1e-7,3e-8,1e-8".into())
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    let reference_file =
        value("--reference").unwrap_or_else(|| format!("out/genalpha_reference_{elements}.csv"));
    let (times, external_w) = external();
    let reference = match read_reference(&reference_file) {
        Some(r) if r.len() == times.len() => r,
        _ => {
            eprintln!("computing the converged reference ({elements} elements, ABM rtol 1e-10)");
            let abm = Abm::new(
                Options::default()
                    .rtol(1e-10)
                    .atol(1e-13)
                    .max_steps(100_000_000),
            );
            let (w, stats, wall) = deflections(&abm, elements, &times);
            let rk = Rk45::new(
                Options::default()
                    .rtol(1e-10)
                    .atol(1e-13)
                    .max_steps(100_000_000),
            );
            let (w2, _, wall2) = deflections(&rk, elements, &times);
            eprintln!(
                "ABM: {} steps, {wall:.1} s; RK45 check {wall2:.1} s: they differ by {:.2e} (L2), {:.2e} (max)",
                stats.accepted_steps,
                errors(&w2, &w).0,
                errors(&w2, &w).1
            );
            if let Some(dir) = std::path::Path::new(&reference_file).parent() {
                let _ = std::fs::create_dir_all(dir);
            }
            let text: String = w
                .iter()
                .map(|r| format!("{:e},{:e},{:e}\n", r[0], r[1], r[2]))
                .collect();
            std::fs::write(&reference_file, text).unwrap();
            w
        }
    };
    let (mesh, _) = errors(&reference, &external_w);
    println!(
        "{elements} elements: the converged run is {:.3} % off the external model (mesh error)",
        100.0 * mesh
    );
    println!(
        "rtol,steps,rejected,residuals,factorisations,matrices,err_vs_converged_l2,err_vs_converged_max,err_vs_external_l2,wall_s"
    );
    for rtol in rtols {
        let mut options = Options::default().rtol(rtol).atol(rtol * 1e-3);
        if let Some(rho) = rho {
            options = options.spectral_radius(rho);
        }
        let ga = GeneralizedAlpha::new(options);
        let mut walls = Vec::new();
        let mut last = None;
        for _ in 0..repeats.max(1) {
            let (w, stats, wall) = deflections(&ga, elements, &times);
            walls.push(wall);
            last = Some((w, stats));
        }
        walls.sort_by(f64::total_cmp);
        let (w, stats) = last.unwrap();
        if let Some(dir) = value("--dump") {
            let text: String = times
                .iter()
                .zip(w.iter().zip(&reference))
                .map(|(t, (a, b))| {
                    format!(
                        "{t:e},{:e},{:e},{:e},{:e},{:e},{:e}\n",
                        a[0], a[1], a[2], b[0], b[1], b[2]
                    )
                })
                .collect();
            std::fs::write(format!("{dir}/w_{rtol:e}.csv"), text).unwrap();
        }
        let (l2, max) = errors(&w, &reference);
        let (ext, _) = errors(&w, &external_w);
        println!(
            "{rtol:e},{},{},{},{},{},{:.3e},{:.3e},{:.3e},{:.4}",
            stats.accepted_steps,
            stats.rejected_steps,
            stats.newton_iterations,
            stats.lu_decompositions,
            stats.jacobian_evaluations,
            l2,
            max,
            ext,
            walls[walls.len() / 2]
        );
    }
}
