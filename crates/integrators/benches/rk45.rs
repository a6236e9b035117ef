//! Criterion benchmark of the Dormand-Prince 5(4) integrator: time per solve on the shared
//! fixtures. Van der Pol is run at the published non-stiff setting (eps = 0.003) and at
//! mu = 1000 (eps = 1e-6), where the explicit method is stability-limited to about two
//! million steps: that case shows what the stiffness report warns about.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use flexprr_integrators::test_problems::{HarmonicOscillator, VanDerPol};
use flexprr_integrators::{Integrator, Options, Rk45};

fn benches(c: &mut Criterion) {
    let mut group = c.benchmark_group("rk45");
    group
        .sample_size(20)
        .measurement_time(Duration::from_secs(3));

    group.bench_function("harmonic_oscillator_t20_rtol1e-8", |b| {
        let rk = Rk45::new(Options::default().rtol(1e-8).atol(1e-10));
        b.iter(|| {
            let mut p = HarmonicOscillator::default();
            black_box(rk.solve(&mut p, 0.0, &[1.0, 0.0], &[20.0]).unwrap())
        })
    });

    group.bench_function("van_der_pol_eps0.003_rtol1e-3", |b| {
        let rk = Rk45::new(Options::default().rtol(1e-3).atol(1e-3));
        b.iter(|| {
            let mut p = VanDerPol::default();
            black_box(rk.solve(&mut p, 0.0, &[2.0, 0.0], &[2.0]).unwrap())
        })
    });

    group.bench_function("van_der_pol_eps0.003_rtol1e-8", |b| {
        let rk = Rk45::new(Options::default().rtol(1e-8).atol(1e-8));
        b.iter(|| {
            let mut p = VanDerPol::default();
            black_box(rk.solve(&mut p, 0.0, &[2.0, 0.0], &[2.0]).unwrap())
        })
    });

    // Stiff: a handful of samples is enough to show the cost.
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(5));
    group.bench_function("van_der_pol_mu1000_rtol1e-6", |b| {
        let rk = Rk45::new(
            Options::default()
                .rtol(1e-6)
                .atol(1e-6)
                .max_steps(10_000_000),
        );
        b.iter(|| {
            let mut p = VanDerPol::with_mu(1000.0);
            black_box(rk.solve(&mut p, 0.0, &[2.0, 0.0], &[2.0]).unwrap())
        })
    });
    group.finish();
}

criterion_group!(rk45, benches);
criterion_main!(rk45);
