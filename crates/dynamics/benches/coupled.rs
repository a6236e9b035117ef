//! Criterion benchmark of the coupled model against the KED model on the paper's scene
//! (f = 20 Hz, 0-0.2 s, r = 3 sine modes per link, zero initial state): one right-hand side,
//! and whole runs with each integrator at the same tolerance. The budget: a coupled
//! run within 5x of the KED run.

use std::hint::black_box;
use std::sync::Arc;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use flexprr_dynamics::{
    CoupledOptions, CoupledSystem, Formulation, ModalDamping, ModalSystem, paper,
};
use flexprr_integrators::{Abm, Bdf, Integrator, OdeSystem, Options, Rk45};

fn systems() -> (ModalSystem, CoupledSystem) {
    let machine = Arc::new(paper::machine(3, paper::YOUNGS_MODULUS).unwrap());
    let trajectory = Arc::new(paper::trajectory(20.0).unwrap());
    let ked = ModalSystem::new(
        machine.clone(),
        trajectory.clone(),
        Formulation::consistent(),
        ModalDamping::none(),
    )
    .unwrap();
    let coupled = CoupledSystem::new(
        machine,
        trajectory,
        ModalDamping::none(),
        CoupledOptions::full(),
    )
    .unwrap();
    (ked, coupled)
}

fn run<I: Integrator, S: OdeSystem>(integrator: &I, system: &mut S) -> f64 {
    let y0 = vec![0.0; system.dim()];
    let sol = integrator.solve(system, 0.0, &y0, &[0.2]).unwrap();
    sol.y(0)[0]
}

fn benches(c: &mut Criterion) {
    let mut group = c.benchmark_group("coupled");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(4));

    let (mut ked, mut coupled) = systems();
    let y: Vec<f64> = (0..18).map(|k| 1e-4 * (k as f64 + 1.0).sin()).collect();
    let mut dy = vec![0.0; 18];
    group.bench_function("rhs_ked_consistent", |b| {
        b.iter(|| ked.rhs(black_box(0.0371), black_box(&y), &mut dy))
    });
    group.bench_function("rhs_coupled", |b| {
        b.iter(|| coupled.rhs(black_box(0.0371), black_box(&y), &mut dy))
    });

    let opts = Options::default().rtol(1e-8).atol(1e-12);
    let rk45 = Rk45::new(opts.clone());
    let abm = Abm::new(opts.clone());
    let bdf = Bdf::new(opts);
    group.bench_function("ked_f20_rk45_rtol1e-8", |b| {
        b.iter(|| black_box(run(&rk45, &mut systems().0)))
    });
    group.bench_function("coupled_f20_rk45_rtol1e-8", |b| {
        b.iter(|| black_box(run(&rk45, &mut systems().1)))
    });
    group.bench_function("ked_f20_abm_rtol1e-8", |b| {
        b.iter(|| black_box(run(&abm, &mut systems().0)))
    });
    group.bench_function("coupled_f20_abm_rtol1e-8", |b| {
        b.iter(|| black_box(run(&abm, &mut systems().1)))
    });
    group.bench_function("ked_f20_bdf_rtol1e-8", |b| {
        b.iter(|| black_box(run(&bdf, &mut systems().0)))
    });
    group.bench_function("coupled_f20_bdf_rtol1e-8", |b| {
        b.iter(|| black_box(run(&bdf, &mut systems().1)))
    });
    // The tolerance of docs/performance.md's paper-scene table.
    let loose = Options::default().rtol(1e-6).atol(1e-10);
    let abm_loose = Abm::new(loose.clone());
    let rk45_loose = Rk45::new(loose);
    group.bench_function("ked_f20_abm_rtol1e-6", |b| {
        b.iter(|| black_box(run(&abm_loose, &mut systems().0)))
    });
    group.bench_function("coupled_f20_abm_rtol1e-6", |b| {
        b.iter(|| black_box(run(&abm_loose, &mut systems().1)))
    });
    group.bench_function("ked_f20_rk45_rtol1e-6", |b| {
        b.iter(|| black_box(run(&rk45_loose, &mut systems().0)))
    });
    group.bench_function("coupled_f20_rk45_rtol1e-6", |b| {
        b.iter(|| black_box(run(&rk45_loose, &mut systems().1)))
    });
    group.finish();
}

criterion_group!(coupled_benches, benches);
criterion_main!(coupled_benches);
