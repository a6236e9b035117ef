//! Tolerance scales ([`OdeSystem::tolerance_scales`], [`Options::for_system`]): the error
//! test of every method must not depend on where a frame puts its origin.
//!
//! The law checked: an oscillator `q'' = -omega^2 (q - c)` is the same motion whatever the
//! origin offset `c`. Like a node of a link lying along an axis, whose coordinate across
//! the axis is its small deflection about zero, it oscillates with an amplitude (0.01) far
//! below its coordinate's natural scale (1). With the scale given, the adaptive methods
//! take about the same steps about the origin (`c = 0`, where `atol + rtol |q|` alone asks
//! for 1 % of the tolerance) as half a scale away from it; without the scale they take
//! many more for the first. The closed form `q = c + A cos(omega t)` checks that the
//! error stays within the tolerance measured against the scale.

use faer::MatMut;
use flexprr_integrators::{
    Abm, Bdf, GeneralizedAlpha, Integrator, OdeSystem, Options, Rk45, SecondOrderForm, Tolerance,
};

/// Two uncoupled oscillators about `c`, amplitude [`AMPLITUDE`], with or without the scale
/// `1`.
struct Offset {
    omega: [f64; 2],
    c: f64,
    scaled: bool,
}

impl OdeSystem for Offset {
    fn dim(&self) -> usize {
        4
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
        for i in 0..2 {
            dy[i] = y[2 + i];
            dy[2 + i] = -self.omega[i] * self.omega[i] * (y[i] - self.c);
        }
    }
    fn second_order_form(&mut self) -> Option<&mut dyn SecondOrderForm> {
        Some(self)
    }
    fn tolerance_scales(&self, scales: &mut [f64]) -> bool {
        // Positions: 1; velocities: the speed of an oscillation of amplitude 1.
        scales.copy_from_slice(&[1.0, 1.0, self.omega[0], self.omega[1]]);
        self.scaled
    }
}

impl SecondOrderForm for Offset {
    fn coordinates(&self) -> usize {
        2
    }
    fn matrices(
        &mut self,
        _t: f64,
        _y: &[f64],
        mut mass: MatMut<'_, f64>,
        _damping: MatMut<'_, f64>,
        mut stiffness: MatMut<'_, f64>,
    ) {
        for i in 0..2 {
            mass[(i, i)] = 1.0;
            stiffness[(i, i)] = self.omega[i] * self.omega[i];
        }
    }
}

/// The oscillators' amplitude, against the scale 1.
const AMPLITUDE: f64 = 0.01;

/// Accepted steps over two periods of the slower oscillator, and the largest position
/// error against the closed form at 200 output times.
fn run<I: Integrator>(method: &I, c: f64, scaled: bool) -> (usize, f64) {
    let omega = [2.0 * std::f64::consts::PI, 2.0 * std::f64::consts::PI * 2.7];
    let mut s = Offset { omega, c, scaled };
    let times: Vec<f64> = (1..=200).map(|k| k as f64 * 0.01).collect();
    let y0 = [c + AMPLITUDE, c + AMPLITUDE, 0.0, 0.0];
    let sol = method.solve(&mut s, 0.0, &y0, &times).unwrap();
    let mut worst = 0.0_f64;
    for (k, t) in sol.t.iter().enumerate() {
        for (q, w) in sol.y(k).iter().zip(omega) {
            let exact = c + AMPLITUDE * (w * t).cos();
            worst = worst.max((q - exact).abs());
        }
    }
    (sol.stats.accepted_steps, worst)
}

fn check<I: Integrator>(method: &I, rtol: f64, error_bound: f64) {
    let name = method.name();
    let (about_origin, error) = run(method, 0.0, true);
    let (far, _) = run(method, 0.5, true);
    let (unscaled, _) = run(method, 0.0, false);
    println!(
        "{name}: {about_origin} steps about the origin, {far} at c = 0.5, {unscaled} without \
         the scale; error {error:.2e} (rtol {rtol:e})"
    );
    let ratio = about_origin as f64 / far as f64;
    assert!(
        (0.7..=1.4).contains(&ratio),
        "{name}: {about_origin} steps about the origin against {far} far from it"
    );
    assert!(
        unscaled as f64 > 1.5 * about_origin as f64,
        "{name}: the scale changed nothing ({unscaled} against {about_origin} steps)"
    );
    assert!(error < error_bound, "{name}: error {error}");
}

#[test]
fn every_method_measures_the_tolerance_against_the_scale() {
    let rtol = 1e-6;
    let options = Options::default().rtol(rtol).atol(1e-14);
    // Global errors of a few hundred local tolerances over two periods: the methods'
    // own (the same bound holds far from the origin without any scale).
    check(&Abm::new(options.clone()), rtol, 300.0 * rtol);
    check(&Rk45::new(options.clone()), rtol, 300.0 * rtol);
    check(&Bdf::new(options.clone()), rtol, 3000.0 * rtol);
    check(&GeneralizedAlpha::new(options), rtol, 3000.0 * rtol);
}

#[test]
fn scales_raise_the_absolute_tolerance_only() {
    let options = Options::default().rtol(1e-6).atol(1e-9);
    let scaled = options.with_scales(&[0.1, 0.0, f64::NAN, -1.0, 1e-4]);
    let Tolerance::PerComponent(atol) = &scaled.atol else {
        panic!("expected a tolerance per component");
    };
    assert_eq!(atol, &vec![1e-7, 1e-9, 1e-9, 1e-9, 1e-9]);
    assert_eq!(scaled.rtol.to_bits(), options.rtol.to_bits());
    // A system without scales keeps the options as they are.
    struct Plain;
    impl OdeSystem for Plain {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, _t: f64, _y: &[f64], dy: &mut [f64]) {
            dy[0] = 0.0;
        }
    }
    assert_eq!(options.for_system(&Plain), options);
}
