//! Criterion benchmarks of the modal system of the paper's scene (model.md sections 1-2,
//! f = 20 Hz): one right-hand-side evaluation (inverse kinematics, rigid inverse dynamics
//! when the axial model needs it, axial loads and the modal accelerations of the three links)
//! for both formulations at r = 3 (the paper's) and r = 12, and the whole 0.2 s solve at
//! rtol 1e-6 with each integrator. Figures are in docs/performance.md.

use std::hint::black_box;
use std::sync::Arc;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use flexprr_dynamics::{Formulation, ModalDamping, ModalSystem, paper};
use flexprr_integrators::{Abm, Bdf, Integrator, OdeSystem, Options, Rk45};

fn system(r: usize, formulation: Formulation) -> ModalSystem {
    let machine = Arc::new(paper::machine(r, paper::YOUNGS_MODULUS).expect("paper machine"));
    let trajectory = Arc::new(paper::trajectory(20.0).expect("paper trajectory"));
    ModalSystem::new(machine, trajectory, formulation, ModalDamping::none()).expect("system")
}

/// A state with every mode displaced and moving (the rhs does the same work at any state,
/// but a non-zero one keeps the optimiser honest).
fn state(dim: usize) -> Vec<f64> {
    (0..dim)
        .map(|k| 1e-4 * ((k as f64 + 1.0) * 0.7).sin())
        .collect()
}

fn rhs(c: &mut Criterion) {
    let mut group = c.benchmark_group("rhs");
    group
        .sample_size(50)
        .measurement_time(Duration::from_secs(3));
    for r in [3, 12] {
        for formulation in [Formulation::paper(), Formulation::consistent()] {
            let mut sys = system(r, formulation);
            let y = state(sys.dim());
            let mut dy = vec![0.0; sys.dim()];
            let mut t = 0.0;
            group.bench_function(format!("{}_r{r}", formulation.name()), |b| {
                b.iter(|| {
                    // Advance t so that no evaluation repeats the previous instant.
                    t += 1.234e-5;
                    if t > 0.2 {
                        t -= 0.2;
                    }
                    sys.rhs(black_box(t), black_box(&y), &mut dy);
                    black_box(&dy);
                })
            });
        }
    }
    group.finish();
}

fn solve(c: &mut Criterion) {
    let mut group = c.benchmark_group("paper_scene_0.2s_rtol1e-6");
    group
        .sample_size(20)
        .measurement_time(Duration::from_secs(4));
    let options = Options::default().rtol(1e-6).atol(1e-10);
    for formulation in [Formulation::paper(), Formulation::consistent()] {
        let name = formulation.name();
        let mut sys = system(3, formulation);
        let y0 = sys.initial_state();
        let rk = Rk45::new(options.clone());
        group.bench_function(format!("rk45_{name}"), |b| {
            b.iter(|| black_box(rk.solve(&mut sys, 0.0, &y0, &[0.2]).expect("rk45")))
        });
        let abm = Abm::new(options.clone());
        group.bench_function(format!("abm_{name}"), |b| {
            b.iter(|| black_box(abm.solve(&mut sys, 0.0, &y0, &[0.2]).expect("abm")))
        });
        let bdf = Bdf::new(options.clone());
        group.bench_function(format!("bdf_{name}"), |b| {
            b.iter(|| black_box(bdf.solve(&mut sys, 0.0, &y0, &[0.2]).expect("bdf")))
        });
    }
    group.finish();
}

criterion_group!(benches, rhs, solve);
criterion_main!(benches);
