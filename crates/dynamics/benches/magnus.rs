//! Criterion benchmarks of the Magnus integrators on the KED scenes, against ABM in the same
//! run: the paper scene (0.2 s, r = 3, paper formulation, 2,001 outputs), r = 20 sine modes
//! (consistent formulation, 0.05 s, 501 outputs), Hermite FE links with 16 and 32 elements
//! (consistent, 0.5 % damping, 0.05 s, 501 outputs) and the long horizon (10 s, r = 3,
//! consistent, 2,001 outputs).
//!
//! Each case is calibrated first: the loosest tolerance of a ladder whose maximum error
//! (displacements over the largest `|eta|`, velocities over the largest `|eta'|`, as in the
//! work-precision runs) against Dormand-Prince at rtol 1e-12 is at most 1e-6; the chosen
//! tolerance, steps, evaluations and error are printed, then the solve at that tolerance is
//! timed. Figures are in docs/performance.md.

use std::sync::Arc;
use std::time::Duration;

use criterion::{Criterion, criterion_group};
use flexprr_beam::{Basis, HermiteBasis, UniformSection};
use flexprr_dynamics::{Formulation, LinkModel, Machine, ModalDamping, ModalSystem, paper};
use flexprr_integrators::{Abm, Integrator, Magnus, Options, Rk45, Solution, Stepper};

fn sine(r: usize, formulation: Formulation) -> ModalSystem {
    let machine = Arc::new(paper::machine(r, paper::YOUNGS_MODULUS).expect("machine"));
    let trajectory = Arc::new(paper::trajectory(20.0).expect("trajectory"));
    ModalSystem::new(machine, trajectory, formulation, ModalDamping::none()).expect("system")
}

fn hermite(elements: usize) -> ModalSystem {
    let section = UniformSection::rectangle(
        paper::YOUNGS_MODULUS,
        paper::DENSITY,
        paper::THICKNESS,
        paper::HEIGHT,
    )
    .expect("section");
    let basis: Arc<dyn Basis> = Arc::new(HermiteBasis::pinned_pinned(elements).expect("basis"));
    let link = LinkModel::new(basis, &section, paper::LINK_LENGTH).expect("link");
    let base = paper::machine(1, paper::YOUNGS_MODULUS).expect("machine");
    let machine = Machine::new(
        base.geometry,
        [link.clone(), link.clone(), link],
        base.slider_mass,
        base.platform_mass,
        base.platform_inertia,
    )
    .expect("machine");
    ModalSystem::new(
        Arc::new(machine),
        Arc::new(paper::trajectory(20.0).expect("trajectory")),
        Formulation::consistent(),
        ModalDamping::uniform(0.005),
    )
    .expect("system")
}

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

const LADDER: [f64; 9] = [1e-5, 3e-6, 1e-6, 3e-7, 1e-7, 3e-8, 1e-8, 3e-9, 1e-9];

/// The loosest ladder tolerance meeting 1e-6 for the integrator `make(rtol, atol)`.
fn calibrate<I: Integrator>(
    name: &str,
    sys: &mut ModalSystem,
    reference: &Solution,
    t_out: &[f64],
    size: f64,
    make: impl Fn(f64, f64) -> I,
) -> Option<f64> {
    let y0 = sys.initial_state();
    for tol in LADDER {
        let Ok(sol) = make(tol, tol * size).solve(sys, 0.0, &y0, t_out) else {
            continue;
        };
        let err = max_error(&sol, reference, sys.modes());
        if err <= 1e-6 {
            eprintln!(
                "{name}: tol {tol:e}: error {err:.2e}, {} steps ({} rejected), {} evaluations",
                sol.stats.accepted_steps, sol.stats.rejected_steps, sol.stats.rhs_evaluations
            );
            return Some(tol);
        }
    }
    eprintln!("{name}: no ladder tolerance reaches 1e-6");
    None
}

fn case(
    c: &mut Criterion,
    label: &str,
    mut sys: ModalSystem,
    t_end: f64,
    outputs: usize,
    with_abm: bool,
) {
    let t_out: Vec<f64> = (0..outputs)
        .map(|k| t_end * k as f64 / (outputs - 1) as f64)
        .collect();
    let y0 = sys.initial_state();
    let reference = Rk45::new(Options::default().rtol(1e-12).atol(1e-16))
        .solve(&mut sys, 0.0, &y0, &t_out)
        .expect("reference");
    let size = (0..reference.len())
        .flat_map(|k| reference.y(k)[..sys.modes()].to_vec())
        .fold(0.0_f64, |a, v| a.max(v.abs()));
    let mut group = c.benchmark_group(label);
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(4));
    let magnus4 = |r, a| Magnus::magnus4(Options::default().rtol(r).atol(a));
    let magnus6 = |r, a| Magnus::magnus6(Options::default().rtol(r).atol(a));
    let abm = |r, a| Abm::new(Options::default().rtol(r).atol(a));
    if let Some(tol) = calibrate(
        &format!("{label}/magnus4"),
        &mut sys,
        &reference,
        &t_out,
        size,
        magnus4,
    ) {
        group.bench_function("magnus4", |b| {
            b.iter(|| {
                magnus4(tol, tol * size)
                    .solve(&mut sys, 0.0, &y0, &t_out)
                    .expect("solve")
            });
        });
    }
    if let Some(tol) = calibrate(
        &format!("{label}/magnus6"),
        &mut sys,
        &reference,
        &t_out,
        size,
        magnus6,
    ) {
        group.bench_function("magnus6", |b| {
            b.iter(|| {
                magnus6(tol, tol * size)
                    .solve(&mut sys, 0.0, &y0, &t_out)
                    .expect("solve")
            });
        });
    }
    if with_abm {
        if let Some(tol) = calibrate(
            &format!("{label}/abm"),
            &mut sys,
            &reference,
            &t_out,
            size,
            abm,
        ) {
            group.bench_function("abm", |b| {
                b.iter(|| {
                    abm(tol, tol * size)
                        .solve(&mut sys, 0.0, &y0, &t_out)
                        .expect("solve")
                });
            });
        }
    }
    group.finish();
}

fn scenes(c: &mut Criterion) {
    let only = std::env::var("MAGNUS_BENCH_CASE").unwrap_or_default();
    let want = |name: &str| only.is_empty() || only == name;
    if want("paper") {
        case(
            c,
            "paper_r3_0.2s",
            sine(3, Formulation::paper()),
            0.2,
            2001,
            true,
        );
    }
    if want("r20") {
        case(
            c,
            "consistent_r20_0.05s",
            sine(20, Formulation::consistent()),
            0.05,
            501,
            false,
        );
    }
    if want("fe") {
        case(c, "fe16_0.05s", hermite(16), 0.05, 501, false);
        case(c, "fe32_0.05s", hermite(32), 0.05, 501, false);
    }
    if want("long") {
        case(
            c,
            "consistent_r3_10s",
            sine(3, Formulation::consistent()),
            10.0,
            2001,
            true,
        );
    }
}

/// Profiling mode, for instruction counts under callgrind (no criterion):
/// `MAGNUS_PROFILE=case:method:rtol[:repeats]` (case `paper`, `r8`, `r20`, `fe16`, `fe32`,
/// `long`; method `magnus4`, `magnus6`, `abm`) solves the case `repeats` times (default 1)
/// and prints the statistics; with `MAGNUS_PROFILE_ERROR=1` it also prints the max error
/// against Dormand-Prince at rtol 1e-12 (run that one natively, not under callgrind). The
/// instructions of one solve are the difference of the counts of two runs with different
/// `repeats`. `MAGNUS_PROFILE_TEND` changes the span (same number of outputs).
fn profile(spec: &str) {
    let parts: Vec<&str> = spec.split(':').collect();
    let (case_name, method, tol) = (parts[0], parts[1], parts[2].parse::<f64>().expect("rtol"));
    let repeats: usize = parts.get(3).map_or(1, |s| s.parse().expect("repeats"));
    let (mut sys, t_end, outputs) = match case_name {
        "paper" => (sine(3, Formulation::paper()), 0.2, 2001),
        "r8" => (sine(8, Formulation::paper()), 0.2, 2001),
        "r20" => (sine(20, Formulation::consistent()), 0.05, 501),
        "fe16" => (hermite(16), 0.05, 501),
        "fe32" => (hermite(32), 0.05, 501),
        "long" => (sine(3, Formulation::consistent()), 10.0, 2001),
        other => panic!("unknown case {other}"),
    };
    // MAGNUS_PROFILE_TEND shortens (or lengthens) the span, same number of outputs.
    let t_end = std::env::var("MAGNUS_PROFILE_TEND")
        .ok()
        .map_or(t_end, |s| s.parse().expect("t_end"));
    let t_out: Vec<f64> = (0..outputs)
        .map(|k| t_end * k as f64 / (outputs - 1) as f64)
        .collect();
    let y0 = sys.initial_state();
    let with_error = std::env::var("MAGNUS_PROFILE_ERROR").is_ok();
    let reference = with_error.then(|| {
        Rk45::new(Options::default().rtol(1e-12).atol(1e-16))
            .solve(&mut sys, 0.0, &y0, &t_out)
            .expect("reference")
    });
    // atol scaled like the work-precision runs: tol times the largest |eta| (from the
    // reference when there is one, else a fixed scale measured on the paper scene).
    let size = reference.as_ref().map_or(1e-4, |r| {
        (0..r.len())
            .flat_map(|k| r.y(k)[..sys.modes()].to_vec())
            .fold(0.0_f64, |a, v| a.max(v.abs()))
    });
    let size = std::env::var("MAGNUS_PROFILE_SIZE")
        .ok()
        .map_or(size, |s| s.parse().expect("size"));
    let opts = Options::default().rtol(tol).atol(tol * size);
    let mut last = None;
    for _ in 0..repeats {
        let sol = match method {
            "magnus4" => Magnus::magnus4(opts.clone()).solve(&mut sys, 0.0, &y0, &t_out),
            "magnus6" => Magnus::magnus6(opts.clone()).solve(&mut sys, 0.0, &y0, &t_out),
            "abm" => Abm::new(opts.clone()).solve(&mut sys, 0.0, &y0, &t_out),
            other => panic!("unknown method {other}"),
        }
        .expect("solve");
        last = Some(sol);
    }
    if with_error && std::env::var("MAGNUS_PROFILE_STEPS").is_ok() && method != "abm" {
        // The error at the step points only (no dense output): the stepper driven by hand.
        let integ = Magnus::new(
            opts.clone(),
            if method == "magnus4" {
                flexprr_integrators::MagnusOrder::Four
            } else {
                flexprr_integrators::MagnusOrder::Six
            },
        );
        let mut st = integ.start(&mut sys, 0.0, &y0, t_end).expect("start");
        let (mut ts, mut ys) = (Vec::new(), Vec::new());
        while st.t() < t_end {
            st.step(&mut sys).expect("step");
            ts.push(st.t());
            ys.push(st.y().to_vec());
        }
        let r = Rk45::new(Options::default().rtol(1e-12).atol(1e-16))
            .solve(&mut sys, 0.0, &y0, &ts)
            .expect("reference");
        let m = sys.modes();
        let vsize = (0..r.len())
            .flat_map(|k| r.y(k)[m..2 * m].to_vec())
            .fold(0.0_f64, |a, v| a.max(v.abs()));
        let (mut worst, mut worst_v): (f64, f64) = (0.0, 0.0);
        for (k, y) in ys.iter().enumerate() {
            for i in 0..m {
                worst = worst.max((y[i] - r.y(k)[i]).abs() / size);
                worst_v = worst_v.max((y[m + i] - r.y(k)[m + i]).abs() / vsize);
            }
        }
        println!(
            "  error at the {} step points: displacement {worst:.3e}, velocity {worst_v:.3e}",
            ts.len()
        );
        let rd = reference.as_ref().expect("reference");
        let sol = last.as_ref().expect("solution");
        let (mut dd, mut dv): (f64, f64) = (0.0, 0.0);
        let vs = (0..rd.len())
            .flat_map(|k| rd.y(k)[m..2 * m].to_vec())
            .fold(0.0_f64, |a, v| a.max(v.abs()));
        let mut per = vec![0.0_f64; 2 * m];
        // Where the worst velocity error is, and its size over time (tenths of the span).
        let mut tenths = [0.0_f64; 10];
        for k in 0..rd.len() {
            let bin = (10 * k / rd.len()).min(9);
            for i in 0..2 * m {
                let s = if i < m { size } else { vs };
                tenths[bin] = tenths[bin].max((sol.y(k)[i] - rd.y(k)[i]).abs() / s);
            }
        }
        println!(
            "  max error per tenth of the span: {}",
            tenths
                .iter()
                .map(|v| format!("{v:.1e}"))
                .collect::<Vec<_>>()
                .join(" ")
        );
        for k in 0..rd.len() {
            for i in 0..m {
                dd = dd.max((sol.y(k)[i] - rd.y(k)[i]).abs() / size);
                dv = dv.max((sol.y(k)[m + i] - rd.y(k)[m + i]).abs() / vs);
                per[i] = per[i].max((sol.y(k)[i] - rd.y(k)[i]).abs() / size);
                per[m + i] = per[m + i].max((sol.y(k)[m + i] - rd.y(k)[m + i]).abs() / vs);
            }
        }
        println!(
            "  per component: {}",
            per.iter()
                .map(|v| format!("{v:.1e}"))
                .collect::<Vec<_>>()
                .join(" ")
        );
        println!("  error at the outputs: displacement {dd:.3e}, velocity {dv:.3e}");
    }
    let sol = last.expect("at least one repeat");
    let err = reference
        .as_ref()
        .map_or(f64::NAN, |r| max_error(&sol, r, sys.modes()));
    println!(
        "{case_name} {method} rtol {tol:e} size {size:.3e}: {} steps, {} rejected, {} evaluations, max error {err:.3e}",
        sol.stats.accepted_steps, sol.stats.rejected_steps, sol.stats.rhs_evaluations
    );
}

criterion_group!(benches, scenes);

fn main() {
    if let Ok(spec) = std::env::var("MAGNUS_PROFILE") {
        profile(&spec);
        return;
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
