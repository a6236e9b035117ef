//! The Magnus integrators against problems with exact solutions: manufactured solutions of
//! time-varying (Mathieu-type) oscillators, scalar and coupled, damped and inside a
//! "buckling" interval (negative stiffness), for the empirical order of convergence; the
//! constant-coefficient oscillator with polynomial forcing, which one step must reproduce
//! exactly over many periods (and its dense output too); Dormand-Prince at tight tolerance as
//! a second method on a coupled block with a coordinate transform; heap allocations counted.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use flexprr_integrators::{
    BlockOperators, Integrator, IntegratorError, LinearSecondOrder, Magnus, MagnusOrder, OdeSystem,
    Options, Rk45, Stepper,
};

struct CountingAllocator;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

/// A manufactured exact solution: `x_j(t) = (1 + 0.2 j) cos(a_j t + b t^2) + 0.1 t`.
fn exact(j: usize, t: f64) -> (f64, f64, f64) {
    let a = 3.0 + 2.0 * j as f64;
    let b = 0.7;
    let amp = 1.0 + 0.2 * j as f64;
    let ph = a * t + b * t * t;
    let dph = a + 2.0 * b * t;
    (
        amp * ph.cos() + 0.1 * t,
        -amp * dph * ph.sin() + 0.1,
        -amp * (2.0 * b * ph.sin() + dph * dph * ph.cos()),
    )
}

/// `x'' + D x' + S(t) x = f(t)` in `n` coordinates, one block, with
/// `S(t) = S0 + sin(nu t) S1 + t S2` (all symmetric; coupled when `coupled`),
/// `D = damping I` (plus a small off-diagonal part when coupled), and the forcing chosen so
/// that [`exact`] solves it: `f = x'' + D x' + S x`, one forcing term per coordinate.
/// Optionally the state is `q = T x` with a fixed invertible `T`.
struct Manufactured {
    n: usize,
    s: [Vec<f64>; 3],
    d: Vec<f64>,
    transform: Option<(Vec<f64>, Vec<f64>)>,
    nu: f64,
}

impl Manufactured {
    fn new(n: usize, omega2: f64, coupled: bool, damping: f64, transformed: bool) -> Self {
        Self::with_coupling(
            n,
            omega2,
            if coupled { 1.0 } else { 0.0 },
            damping,
            transformed,
        )
    }

    /// As [`Manufactured::new`] with the off-diagonal terms scaled by `coupling`.
    fn with_coupling(
        n: usize,
        omega2: f64,
        coupling: f64,
        damping: f64,
        transformed: bool,
    ) -> Self {
        let coupled = coupling > 0.0;
        let mut s0 = vec![0.0; n * n];
        let mut s1 = vec![0.0; n * n];
        let mut s2 = vec![0.0; n * n];
        let mut d = vec![0.0; n * n];
        for i in 0..n {
            s0[i * n + i] = omega2 * (1.0 + i as f64).powi(2);
            // The time-varying part stays moderate at high frequency (as the geometric
            // stiffness of the modal equations does): it sets the step, not omega.
            s1[i * n + i] = 0.3 * omega2.abs().min(400.0);
            s2[i * n + i] = 0.5;
            d[i * n + i] = damping;
            if coupled {
                for j in 0..n {
                    if i != j {
                        s0[i * n + j] = coupling * 0.4 * omega2.abs() / (1.0 + (i + j) as f64);
                        s1[i * n + j] = coupling * 0.2 * omega2.abs();
                        s2[i * n + j] = coupling * 0.3;
                        d[i * n + j] = coupling * 0.1 * damping;
                    }
                }
            }
        }
        let transform = transformed.then(|| {
            // T = lower-triangular with unit-ish diagonal; its inverse by forward substitution.
            let mut t = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..=i {
                    t[i * n + j] = if i == j { 2.0 + i as f64 } else { 0.5 };
                }
            }
            let mut ti = vec![0.0; n * n];
            for c in 0..n {
                for i in 0..n {
                    let mut s = if i == c { 1.0 } else { 0.0 };
                    for p in 0..i {
                        s -= t[i * n + p] * ti[p * n + c];
                    }
                    ti[i * n + c] = s / t[i * n + i];
                }
            }
            (t, ti)
        });
        Self {
            n,
            s: [s0, s1, s2],
            d,
            transform,
            nu: 2.0,
        }
    }

    fn stiffness(&self, t: f64, out: &mut [f64]) {
        let c = [1.0, (self.nu * t).sin(), t];
        for (k, o) in out.iter_mut().enumerate() {
            *o = (0..3).map(|m| c[m] * self.s[m][k]).sum();
        }
    }

    /// `f_i(t) = x_i'' + (D x')_i + (S(t) x)_i` for the exact solution.
    fn forcing(&self, t: f64, out: &mut [f64]) {
        let n = self.n;
        let mut s = [0.0; 16];
        self.stiffness(t, &mut s[..n * n]);
        for i in 0..n {
            let mut f = exact(i, t).2;
            for j in 0..n {
                let (x, v, _) = exact(j, t);
                f += self.d[i * n + j] * v + s[i * n + j] * x;
            }
            out[i] = f;
        }
    }

    /// The exact state `(q, q')` at `t` in the system's variables.
    fn exact_state(&self, t: f64) -> Vec<f64> {
        let n = self.n;
        let x: Vec<f64> = (0..n).map(|j| exact(j, t).0).collect();
        let v: Vec<f64> = (0..n).map(|j| exact(j, t).1).collect();
        let map = |x: &[f64]| -> Vec<f64> {
            match &self.transform {
                Some((tm, _)) => (0..n)
                    .map(|i| (0..n).map(|k| tm[i * n + k] * x[k]).sum())
                    .collect(),
                None => x.to_vec(),
            }
        };
        [map(&x), map(&v)].concat()
    }
}

impl LinearSecondOrder for Manufactured {
    fn block_count(&self) -> usize {
        1
    }
    fn block_operators(&self, _block: usize) -> BlockOperators {
        let n = self.n;
        BlockOperators {
            size: n,
            stiffness: self.s.to_vec(),
            forcing: (0..n)
                .map(|i| (0..n).map(|j| if i == j { 1.0 } else { 0.0 }).collect())
                .collect(),
            damping: Some(self.d.clone()),
            transform: self.transform.clone(),
        }
    }
    fn coefficients(&mut self, t: f64, stiffness: &mut [f64], forcing: &mut [f64]) {
        stiffness[0] = 1.0;
        stiffness[1] = (self.nu * t).sin();
        stiffness[2] = t;
        self.forcing(t, forcing);
    }
}

impl OdeSystem for Manufactured {
    fn dim(&self) -> usize {
        2 * self.n
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        let n = self.n;
        let mut x = [0.0; 8];
        match &self.transform {
            Some((_, ti)) => {
                for (i, xi) in x[..2 * n].iter_mut().enumerate() {
                    let (part, row) = (i / n, i % n);
                    *xi = (0..n).map(|k| ti[row * n + k] * y[part * n + k]).sum();
                }
            }
            None => x[..2 * n].copy_from_slice(y),
        }
        let mut s = [0.0; 16];
        self.stiffness(t, &mut s[..n * n]);
        let mut f = [0.0; 4];
        self.forcing(t, &mut f[..n]);
        let mut acc = [0.0; 4];
        for i in 0..n {
            acc[i] = f[i];
            for j in 0..n {
                acc[i] -= s[i * n + j] * x[j] + self.d[i * n + j] * x[n + j];
            }
        }
        let mut dx = [0.0; 8];
        dx[..n].copy_from_slice(&x[n..2 * n]);
        dx[n..2 * n].copy_from_slice(&acc[..n]);
        match &self.transform {
            Some((tm, _)) => {
                for (i, dyi) in dy.iter_mut().enumerate() {
                    let (part, row) = (i / n, i % n);
                    *dyi = (0..n).map(|k| tm[row * n + k] * dx[part * n + k]).sum();
                }
            }
            None => dy.copy_from_slice(&dx[..2 * n]),
        }
    }
    fn linear_form(&mut self) -> Option<&mut dyn LinearSecondOrder> {
        Some(self)
    }
}

/// Maximum error at `t = 1` with fixed steps `h` (tolerances so loose nothing is rejected).
fn fixed_step_error(p: &mut Manufactured, order: MagnusOrder, steps: usize) -> f64 {
    let h = 1.0 / steps as f64;
    let opts = Options::default()
        .rtol(1e3)
        .atol(1e9)
        .initial_step(h)
        .max_step(h);
    let y0 = p.exact_state(0.0);
    let sol = Magnus::new(opts, order).solve(p, 0.0, &y0, &[1.0]).unwrap();
    assert_eq!(sol.stats.rejected_steps, 0);
    assert!(sol.stats.accepted_steps.abs_diff(steps) <= 1);
    let want = p.exact_state(1.0);
    sol.y(0)
        .iter()
        .zip(&want)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max)
}

/// Observed order from errors at `steps` and `2 steps`.
fn observed_order(p: &mut Manufactured, order: MagnusOrder, steps: usize) -> (f64, f64, f64) {
    let e1 = fixed_step_error(p, order, steps);
    let e2 = fixed_step_error(p, order, 2 * steps);
    ((e1 / e2).log2(), e1, e2)
}

/// Magnus-4 converges with order 4 and Magnus-6 with order 6 on a scalar damped Mathieu-type
/// oscillator with an exact solution, with steps up to `h omega ~ 1.5`.
#[test]
fn empirical_orders_on_a_scalar_mathieu_oscillator() {
    let mut p = Manufactured::new(1, 100.0, false, 0.3, false);
    let (o4, e1, e2) = observed_order(&mut p, MagnusOrder::Four, 16);
    assert!((o4 - 4.0).abs() < 0.35, "order 4: {o4} ({e1:e} -> {e2:e})");
    let (o6, e1, e2) = observed_order(&mut p, MagnusOrder::Six, 16);
    assert!((o6 - 6.0).abs() < 0.5, "order 6: {o6} ({e1:e} -> {e2:e})");
}

/// The same inside a buckling interval: negative stiffness (exponential growth) with a
/// time-varying part.
#[test]
fn empirical_orders_with_negative_stiffness() {
    let mut p = Manufactured::new(1, -4.0, false, 0.0, false);
    let (o4, e1, e2) = observed_order(&mut p, MagnusOrder::Four, 8);
    assert!((o4 - 4.0).abs() < 0.35, "order 4: {o4} ({e1:e} -> {e2:e})");
    let (o6, e1, e2) = observed_order(&mut p, MagnusOrder::Six, 8);
    assert!((o6 - 6.0).abs() < 0.5, "order 6: {o6} ({e1:e} -> {e2:e})");
}

/// A coupled block (full symmetric time-varying stiffness, off-diagonal damping, a
/// coordinate transform): the frozen-eigenbasis rotation and the coupling iteration keep
/// order 4 (and 6).
#[test]
fn empirical_orders_on_a_coupled_block() {
    let mut p = Manufactured::new(3, 25.0, true, 0.2, true);
    let (o4, e1, e2) = observed_order(&mut p, MagnusOrder::Four, 32);
    assert!((o4 - 4.0).abs() < 0.4, "order 4: {o4} ({e1:e} -> {e2:e})");
    let (o6, e1, e2) = observed_order(&mut p, MagnusOrder::Six, 32);
    assert!(o6 > 5.3, "order 6: {o6} ({e1:e} -> {e2:e})");
}

/// Constant coefficients with quadratic forcing: `x'' + w^2 x = c0 + c1 t + c2 t^2` has the
/// exact solution `x = A + B t + C t^2 + u cos(w t) + v sin(w t)`; one Magnus step over 80
/// periods reproduces it, and so does the dense output inside that step.
#[test]
fn one_step_is_exact_for_a_frozen_oscillator_with_quadratic_forcing() {
    struct Frozen;
    const W: f64 = 50.0;
    const C: [f64; 3] = [3.0, -2.0, 5.0];
    impl LinearSecondOrder for Frozen {
        fn block_count(&self) -> usize {
            1
        }
        fn block_operators(&self, _block: usize) -> BlockOperators {
            BlockOperators {
                size: 1,
                stiffness: vec![vec![W * W]],
                forcing: vec![vec![1.0]],
                damping: None,
                transform: None,
            }
        }
        fn coefficients(&mut self, t: f64, s: &mut [f64], f: &mut [f64]) {
            s[0] = 1.0;
            f[0] = C[0] + C[1] * t + C[2] * t * t;
        }
    }
    impl OdeSystem for Frozen {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
            dy[0] = y[1];
            dy[1] = C[0] + C[1] * t + C[2] * t * t - W * W * y[0];
        }
        fn linear_form(&mut self) -> Option<&mut dyn LinearSecondOrder> {
            Some(self)
        }
    }
    let w2 = W * W;
    let (cc, b) = (C[2] / w2, C[1] / w2);
    let a = (C[0] - 2.0 * cc) / w2;
    let (u, v) = (1.0 - a, (0.5 - b) / W); // x(0) = 1, x'(0) = 0.5
    let x = |t: f64| a + b * t + cc * t * t + u * (W * t).cos() + v * (W * t).sin();
    let xd = |t: f64| b + 2.0 * cc * t - u * W * (W * t).sin() + v * W * (W * t).cos();
    let t_end = 80.0 * 2.0 * std::f64::consts::PI / W + 0.37;
    for order in [MagnusOrder::Four, MagnusOrder::Six] {
        let m = Magnus::new(
            Options::default()
                .rtol(1e-10)
                .atol(1e-12)
                .initial_step(t_end),
            order,
        );
        let mut st = m.start(&mut Frozen, 0.0, &[1.0, 0.5], t_end).unwrap();
        st.step(&mut Frozen).unwrap();
        assert_eq!(st.stats().accepted_steps, 1, "{order:?}");
        assert!(
            (st.y()[0] - x(t_end)).abs() < 1e-11,
            "{order:?}: {}",
            st.y()[0]
        );
        assert!((st.y()[1] - xd(t_end)).abs() < 1e-9, "{order:?}");
        let mut out = [0.0; 2];
        for k in 1..50 {
            let t = t_end * k as f64 / 50.0;
            st.interpolate(t, &mut out);
            assert!((out[0] - x(t)).abs() < 1e-11, "{order:?} dense at {t}");
            assert!((out[1] - xd(t)).abs() < 1e-9, "{order:?} dense at {t}");
        }
    }
}

/// Adaptive runs at rtol 1e-10 stay within 1e-6 of the exact solution and of
/// Dormand-Prince at rtol 1e-12 at 201 dense outputs, on the coupled, damped, transformed
/// block and on its uncoupled version.
#[test]
fn adaptive_runs_agree_with_the_exact_solution_and_rk45() {
    let t_out: Vec<f64> = (0..=200).map(|k| 2.0 * k as f64 / 200.0).collect();
    for coupled in [false, true] {
        let mut p = Manufactured::new(3, 400.0, coupled, 0.5, true);
        let y0 = p.exact_state(0.0);
        let reference = Rk45::new(Options::default().rtol(1e-12).atol(1e-14))
            .solve(&mut p, 0.0, &y0, &t_out)
            .unwrap();
        for order in [MagnusOrder::Four, MagnusOrder::Six] {
            let sol = Magnus::new(Options::default().rtol(1e-10).atol(1e-12), order)
                .solve(&mut p, 0.0, &y0, &t_out)
                .unwrap();
            let mut worst: f64 = 0.0;
            let mut worst_rk: f64 = 0.0;
            for (k, &t) in t_out.iter().enumerate() {
                let want = p.exact_state(t);
                for (i, w) in want.iter().enumerate() {
                    worst = worst.max((sol.y(k)[i] - w).abs() / w.abs().max(1.0));
                    worst_rk =
                        worst_rk.max((sol.y(k)[i] - reference.y(k)[i]).abs() / w.abs().max(1.0));
                }
            }
            assert!(worst < 1e-6, "coupled {coupled}, {order:?}: {worst:e}");
            assert!(
                worst_rk < 1e-6,
                "coupled {coupled}, {order:?}: {worst_rk:e}"
            );
        }
    }
}

/// A nonlinear system (no linear form) is refused with a message naming the alternative.
#[test]
fn nonlinear_systems_are_refused() {
    struct Pendulum;
    impl OdeSystem for Pendulum {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
            dy[0] = y[1];
            dy[1] = -y[0].sin();
        }
    }
    let err = Magnus::magnus4(Options::default())
        .solve(&mut Pendulum, 0.0, &[1.0, 0.0], &[1.0])
        .unwrap_err();
    match err {
        IntegratorError::InvalidInput(msg) => assert!(msg.contains("abm"), "{msg}"),
        e => panic!("unexpected {e}"),
    }
}

/// Stepping and dense output allocate nothing once started.
#[test]
fn steps_and_dense_output_allocate_nothing() {
    let mut p = Manufactured::new(3, 400.0, true, 0.5, true);
    let y0 = p.exact_state(0.0);
    let m = Magnus::magnus4(Options::default().rtol(1e-8).atol(1e-10));
    let mut st = m.start(&mut p, 0.0, &y0, 1.0).unwrap();
    let mut out = vec![0.0; 6];
    let before = allocations();
    while st.t() < 1.0 {
        st.step(&mut p).unwrap();
        st.interpolate(0.5 * (st.t() + st.t_previous()), &mut out);
    }
    assert_eq!(allocations(), before);
    assert!(st.stats().accepted_steps > 5);
}

/// `w'' + (omega^2 + a sin(nu t)) w = 0`: a free oscillation at `omega` with a moderate
/// time-varying stiffness (as the geometric stiffness of a high mode), one coordinate.
struct FreeMathieu {
    omega2: f64,
}

impl LinearSecondOrder for FreeMathieu {
    fn block_count(&self) -> usize {
        1
    }
    fn block_operators(&self, _block: usize) -> BlockOperators {
        BlockOperators {
            size: 1,
            stiffness: vec![vec![self.omega2], vec![40.0]],
            forcing: vec![vec![1.0]],
            damping: None,
            transform: None,
        }
    }
    fn coefficients(&mut self, t: f64, s: &mut [f64], f: &mut [f64]) {
        s[0] = 1.0;
        s[1] = (3.0 * t).sin();
        f[0] = (2.0 * t).cos();
    }
}

impl OdeSystem for FreeMathieu {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = y[1];
        dy[1] = (2.0 * t).cos() - (self.omega2 + 40.0 * (3.0 * t).sin()) * y[0];
    }
    fn linear_form(&mut self) -> Option<&mut dyn LinearSecondOrder> {
        Some(self)
    }
}

/// The 6th-order step propagates the frozen oscillation exactly and integrates only the
/// stiffness variation (as a force at the Gauss nodes), while the 4th-order Magnus
/// generator's commutators carry powers of `h omega`. At one fixed step set by the
/// variation and `h omega` from 0.5 to 2.5, both against RK45 at rtol 1e-12 (displacement,
/// and velocity over `omega`): the 6th-order error stays at least ten times below the
/// 4th-order one (measured: 500x at `h omega = 0.5`, 19x at 2.5). It still grows with
/// `h omega` (the variation times the oscillating state is interpolated by a quadratic),
/// which docs/performance.md reports.
#[test]
fn the_sixth_order_step_stays_accurate_at_large_h_omega() {
    let h = 0.05;
    let error = |omega: f64, order: MagnusOrder| {
        let mut p = FreeMathieu {
            omega2: omega * omega,
        };
        let y0 = [1.0, 0.0];
        let t_out = [1.0, 2.0];
        let reference = Rk45::new(Options::default().rtol(1e-12).atol(1e-14))
            .solve(&mut p, 0.0, &y0, &t_out)
            .unwrap();
        let opts = Options::default()
            .rtol(1e3)
            .atol(1e9)
            .initial_step(h)
            .max_step(h);
        let sol = Magnus::new(opts, order)
            .solve(&mut p, 0.0, &y0, &t_out)
            .unwrap();
        assert_eq!(sol.stats.rejected_steps, 0);
        (0..2)
            .map(|k| {
                let (a, b) = (sol.y(k), reference.y(k));
                (a[0] - b[0]).abs().max((a[1] - b[1]).abs() / omega)
            })
            .fold(0.0, f64::max)
    };
    let six: Vec<f64> = [10.0, 20.0, 50.0]
        .map(|w| error(w, MagnusOrder::Six))
        .to_vec();
    let four: Vec<f64> = [10.0, 20.0, 50.0]
        .map(|w| error(w, MagnusOrder::Four))
        .to_vec();
    for (k, (s, f)) in six.iter().zip(&four).enumerate() {
        assert!(
            s.is_finite() && *s < 0.1 * f,
            "omega index {k}: order 6 error {s:e}, order 4 error {f:e}"
        );
    }
}
