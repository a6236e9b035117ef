//! Criterion benchmark of the BDF: time per solve on the shared fixtures, plus a dense
//! modal system of the size the product integrates (30 modes, 60 states, analytic Jacobian).

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use faer::MatMut;
use flexprr_integrators::test_problems::{HarmonicOscillator, Robertson, VanDerPol};
use flexprr_integrators::{Bdf, Integrator, OdeSystem, Options};

/// `modes` lightly damped oscillators `q'' + 2 zeta w q' + w^2 q + c sum(q) = cos(t)` with
/// natural frequencies from 1 to 1000 rad/s and a weak all-to-all stiffness coupling `c`, so
/// that the Jacobian is dense and the problem stiff (like assumed-mode link models).
struct ModalChain {
    omega: Vec<f64>,
    zeta: f64,
    coupling: f64,
}

impl ModalChain {
    fn new(modes: usize) -> Self {
        let omega = (0..modes)
            .map(|k| 10f64.powf(3.0 * k as f64 / (modes - 1) as f64))
            .collect();
        Self {
            omega,
            zeta: 0.02,
            coupling: 0.5,
        }
    }
}

impl OdeSystem for ModalChain {
    fn dim(&self) -> usize {
        2 * self.omega.len()
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        let m = self.omega.len();
        let (q, v) = y.split_at(m);
        let sum_q: f64 = q.iter().sum();
        let force = t.cos();
        for k in 0..m {
            let w = self.omega[k];
            dy[k] = v[k];
            dy[m + k] = force - 2.0 * self.zeta * w * v[k] - w * w * q[k] - self.coupling * sum_q;
        }
    }
    fn jacobian(&mut self, _t: f64, _y: &[f64], mut jac: MatMut<'_, f64>) {
        let m = self.omega.len();
        jac.fill(0.0);
        for k in 0..m {
            let w = self.omega[k];
            jac[(k, m + k)] = 1.0;
            for j in 0..m {
                jac[(m + k, j)] = -self.coupling;
            }
            jac[(m + k, k)] -= w * w;
            jac[(m + k, m + k)] = -2.0 * self.zeta * w;
        }
    }
    fn has_analytic_jacobian(&self) -> bool {
        true
    }
}

fn benches(c: &mut Criterion) {
    let mut group = c.benchmark_group("bdf");
    group
        .sample_size(20)
        .measurement_time(Duration::from_secs(3));

    group.bench_function("harmonic_oscillator_t20_rtol1e-8", |b| {
        let bdf = Bdf::new(Options::default().rtol(1e-8).atol(1e-10));
        b.iter(|| {
            let mut p = HarmonicOscillator::default();
            black_box(bdf.solve(&mut p, 0.0, &[1.0, 0.0], &[20.0]).unwrap())
        })
    });

    group.bench_function("van_der_pol_mu1000_rtol1e-6", |b| {
        let bdf = Bdf::new(Options::default().rtol(1e-6).atol(1e-6));
        b.iter(|| {
            let mut p = VanDerPol::with_mu(1000.0);
            black_box(bdf.solve(&mut p, 0.0, &[2.0, 0.0], &[2.0]).unwrap())
        })
    });

    group.bench_function("robertson_t1e5_cvode_tolerances", |b| {
        let bdf = Bdf::new(
            Options::default()
                .rtol(1e-4)
                .atol_per_component(vec![1e-8, 1e-14, 1e-6]),
        );
        b.iter(|| {
            let mut p = Robertson::default();
            black_box(bdf.solve(&mut p, 0.0, &[1.0, 0.0, 0.0], &[1e5]).unwrap())
        })
    });

    for modes in [30, 60] {
        group.bench_function(
            format!("modal_chain_{}_states_t1_rtol1e-6", 2 * modes),
            |b| {
                let bdf = Bdf::new(Options::default().rtol(1e-6).atol(1e-9));
                let y0 = vec![0.0; 2 * modes];
                b.iter(|| {
                    let mut p = ModalChain::new(modes);
                    black_box(bdf.solve(&mut p, 0.0, &y0, &[1.0]).unwrap())
                })
            },
        );
    }
    group.finish();

    // Work counters for the documentation (printed once): the lightly damped modes sit
    // near the imaginary axis, where BDF orders 3-5 are not stable; compare max_order 2.
    for max_order in [2, 5] {
        let mut p = ModalChain::new(60);
        let sol = Bdf::new(Options::default().rtol(1e-6).atol(1e-9))
            .max_order(max_order)
            .solve(&mut p, 0.0, &[0.0; 120], &[1.0])
            .unwrap();
        println!(
            "modal chain 120 states, max_order {max_order}: {:?}",
            sol.stats
        );
    }
}

criterion_group!(bdf_benches, benches);
criterion_main!(bdf_benches);
