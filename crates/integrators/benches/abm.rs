//! Criterion benchmark of the Adams-Bashforth-Moulton integrator: time per solve.
//!
//! * Harmonic oscillator, t in [0, 20], rtol 1e-8 (atol 1e-10).
//! * Van der Pol in Hairer's scaling with mu = 100 (eps = 1e-4) over [0, 2], rtol 1e-6: an
//!   explicit method's step is bounded by stability on the stiff stretches, so mu = 1000 (eps =
//!   1e-6) would take about 10^7 steps; mu = 100 shows the cost of that regime in reasonable
//!   time.
//! * 30 uncoupled modal oscillators (60 states, omega_j = j^2 rad/s) over [0, 2], rtol 1e-8:
//!   the shape of the product's modal equations.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use flexprr_integrators::test_problems::{HarmonicOscillator, TestProblem, VanDerPol};
use flexprr_integrators::{Abm, Integrator, OdeSystem, Options};

/// `q_j'' = -omega_j^2 q_j`, `omega_j = j^2`, as a first-order system of `2 m` states.
struct ModalLadder {
    omega_squared: Vec<f64>,
}

impl OdeSystem for ModalLadder {
    fn dim(&self) -> usize {
        2 * self.omega_squared.len()
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
        let m = self.omega_squared.len();
        let (q, v) = y.split_at(m);
        let (dq, dv) = dy.split_at_mut(m);
        dq.copy_from_slice(v);
        for ((a, w2), x) in dv.iter_mut().zip(&self.omega_squared).zip(q) {
            *a = -w2 * x;
        }
    }
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("abm");
    group.sample_size(20);
    group.measurement_time(Duration::from_secs(3));
    group.warm_up_time(Duration::from_secs(1));

    let mut harmonic = HarmonicOscillator::default();
    let y0 = harmonic.y0();
    let abm = Abm::new(Options::default().rtol(1e-8).atol(1e-10));
    group.bench_function("harmonic_t20_rtol1e-8", |b| {
        b.iter(|| {
            abm.solve(&mut harmonic, 0.0, black_box(&y0), &[20.0])
                .unwrap()
        })
    });

    let mut vdp = VanDerPol::with_mu(100.0);
    let y0 = vdp.y0();
    let abm = Abm::new(Options::default().rtol(1e-6).atol(1e-8));
    group.bench_function("van_der_pol_mu100_rtol1e-6", |b| {
        b.iter(|| abm.solve(&mut vdp, 0.0, black_box(&y0), &[2.0]).unwrap())
    });

    let modes = 30;
    let mut ladder = ModalLadder {
        omega_squared: (1..=modes).map(|j| ((j * j) as f64).powi(2)).collect(),
    };
    let mut y0 = vec![0.0; 2 * modes];
    for (j, q) in y0[..modes].iter_mut().enumerate() {
        *q = 1.0 / (j + 1) as f64;
    }
    let abm = Abm::new(Options::default().rtol(1e-8).atol(1e-10));
    group.bench_function("modal_ladder_30_modes_t2_rtol1e-8", |b| {
        b.iter(|| abm.solve(&mut ladder, 0.0, black_box(&y0), &[2.0]).unwrap())
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
