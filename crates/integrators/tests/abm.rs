//! Tests of the Adams-Bashforth-Moulton integrator against closed-form solutions, an
//! independent fixed-step classical Runge-Kutta reference, counting laws, and the Dormand-Prince
//! integrator of this crate (work at equal accuracy).

use flexprr_integrators::abm::AbmStepper;
use flexprr_integrators::test_problems::{
    ForcedOscillator, HarmonicOscillator, Mathieu, StiffLinear, TestProblem, VanDerPol,
};
use flexprr_integrators::{
    Abm, Integrator, IntegratorError, OdeSystem, Options, Rk45, Stats, Stepper,
};
use proptest::prelude::*;

// ---------------------------------------------------------------------------------------
// Allocation counter (per thread, so parallel tests do not disturb each other).

use flexprr_testkit::alloc::{CountingAllocator, allocations};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

// ---------------------------------------------------------------------------------------
// Helpers.

fn options(rtol: f64, atol: f64) -> Options {
    Options::default().rtol(rtol).atol(atol)
}

/// Evenly spaced output times in `(t0, t_end]`.
fn grid(t0: f64, t_end: f64, n: usize) -> Vec<f64> {
    (1..=n)
        .map(|i| t0 + (t_end - t0) * i as f64 / n as f64)
        .collect()
}

/// Largest absolute error against the exact solution over the output times.
fn max_error_vs_exact<P: TestProblem>(
    p: &P,
    t: &[f64],
    sol: &flexprr_integrators::Solution,
) -> f64 {
    let mut e: f64 = 0.0;
    for (k, &tk) in t.iter().enumerate() {
        let exact = p.exact(tk).expect("problem has a closed form");
        for (a, b) in sol.y(k).iter().zip(&exact) {
            e = e.max((a - b).abs());
        }
    }
    e
}

/// Classical fourth-order Runge-Kutta with a fixed step (Kutta 1901; Hairer, Norsett &
/// Wanner I, Table II.1.2), written here independently of the crate, as the reference for
/// problems without a closed form. Returns the states at `t0 + j * (t_end - t0) / n_out`.
fn rk4_reference<S: OdeSystem>(
    system: &mut S,
    y0: &[f64],
    t_end: f64,
    steps: usize,
    n_out: usize,
) -> Vec<Vec<f64>> {
    assert_eq!(steps % n_out, 0);
    let n = y0.len();
    let h = t_end / steps as f64;
    let mut y = y0.to_vec();
    let (mut k1, mut k2, mut k3, mut k4, mut tmp) = (
        vec![0.0; n],
        vec![0.0; n],
        vec![0.0; n],
        vec![0.0; n],
        vec![0.0; n],
    );
    let mut out = Vec::with_capacity(n_out);
    for s in 0..steps {
        let t = s as f64 * h;
        system.rhs(t, &y, &mut k1);
        for i in 0..n {
            tmp[i] = y[i] + 0.5 * h * k1[i];
        }
        system.rhs(t + 0.5 * h, &tmp, &mut k2);
        for i in 0..n {
            tmp[i] = y[i] + 0.5 * h * k2[i];
        }
        system.rhs(t + 0.5 * h, &tmp, &mut k3);
        for i in 0..n {
            tmp[i] = y[i] + h * k3[i];
        }
        system.rhs(t + h, &tmp, &mut k4);
        for i in 0..n {
            y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        if (s + 1) % (steps / n_out) == 0 {
            out.push(y.clone());
        }
    }
    out
}

/// Least-squares slope of `log10(err)` against `log10(tol)`.
fn log_log_slope(tol: &[f64], err: &[f64]) -> f64 {
    let x: Vec<f64> = tol.iter().map(|t| t.log10()).collect();
    let y: Vec<f64> = err.iter().map(|e| e.log10()).collect();
    let m = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / m, y.iter().sum::<f64>() / m);
    let sxy: f64 = x.iter().zip(&y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
}

/// Counts every right-hand-side call, to check the statistics.
struct Counted<S> {
    inner: S,
    calls: usize,
}

impl<S: OdeSystem> OdeSystem for Counted<S> {
    fn dim(&self) -> usize {
        self.inner.dim()
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        self.calls += 1;
        self.inner.rhs(t, y, dy);
    }
}

/// `n` uncoupled oscillators `q_j'' = -omega_j^2 q_j` with `omega_j = omega_1 j^2` (the
/// frequency ladder of pinned-pinned beam modes), `q_j(0) = 1 / j`, `q_j'(0) = 0`; exact
/// `q_j = cos(omega_j t) / j`. A stand-in for the modal equations, which grow mildly stiff
/// with the number of modes.
#[derive(Clone)]
struct ModalLadder {
    omega: Vec<f64>,
}

impl ModalLadder {
    fn new(modes: usize, omega_1: f64) -> Self {
        Self {
            omega: (1..=modes).map(|j| omega_1 * (j * j) as f64).collect(),
        }
    }
    fn y0(&self) -> Vec<f64> {
        let m = self.omega.len();
        let mut y = vec![0.0; 2 * m];
        for (j, q) in y[..m].iter_mut().enumerate() {
            *q = 1.0 / (j + 1) as f64;
        }
        y
    }
    fn exact(&self, t: f64) -> Vec<f64> {
        let m = self.omega.len();
        let mut y = vec![0.0; 2 * m];
        for (j, w) in self.omega.iter().enumerate() {
            let a = 1.0 / (j + 1) as f64;
            y[j] = a * (w * t).cos();
            y[m + j] = -a * w * (w * t).sin();
        }
        y
    }
}

impl OdeSystem for ModalLadder {
    fn dim(&self) -> usize {
        2 * self.omega.len()
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
        let m = self.omega.len();
        for j in 0..m {
            dy[j] = y[m + j];
            dy[m + j] = -self.omega[j] * self.omega[j] * y[j];
        }
    }
}

// ---------------------------------------------------------------------------------------
// Accuracy on the non-stiff fixtures.

/// Harmonic and forced oscillators at rtol 1e-8 (atol 1e-10), 500 dense outputs each, against
/// their closed forms: error within 10x of the tolerance.
#[test]
fn oscillators_match_closed_forms_within_ten_times_tolerance() {
    let (rtol, atol) = (1e-8, 1e-10);
    let harmonic = HarmonicOscillator::default();
    let t = grid(0.0, harmonic.t_end(), 500);
    let sol = Abm::new(options(rtol, atol))
        .solve(&mut harmonic.clone(), 0.0, &harmonic.y0(), &t)
        .unwrap();
    let e = max_error_vs_exact(&harmonic, &t, &sol);
    assert!(e < 10.0 * rtol, "harmonic oscillator error {e:e}");

    let forced = ForcedOscillator::default();
    let sol = Abm::new(options(rtol, atol))
        .solve(&mut forced.clone(), 0.0, &forced.y0(), &t)
        .unwrap();
    let e = max_error_vs_exact(&forced, &t, &sol);
    assert!(e < 10.0 * rtol, "forced oscillator error {e:e}");
    assert!(sol.stats.max_order_used() >= 8, "{:?}", sol.stats.orders);
}

/// Mathieu's equation and Van der Pol (eps = 0.003) have no closed form: compare with a
/// fixed-step classical RK4 reference whose own error is bounded by step halving.
#[test]
fn mathieu_and_van_der_pol_match_rk4_reference() {
    fn check<P: TestProblem + Clone>(p: P, steps: usize, rtol: f64, allowed: f64) {
        let n_out = 50;
        let t_end = p.t_end();
        let y0 = p.y0();
        let fine = rk4_reference(&mut p.clone(), &y0, t_end, steps, n_out);
        let coarse = rk4_reference(&mut p.clone(), &y0, t_end, steps / 2, n_out);
        let mut ref_err: f64 = 0.0;
        for (a, b) in fine.iter().zip(&coarse) {
            for (x, y) in a.iter().zip(b) {
                // RK4: the error of the fine solution is about 1/15 of the difference.
                ref_err = ref_err.max((x - y).abs() / 15.0);
            }
        }
        assert!(
            ref_err < 0.01 * allowed,
            "{}: reference error {ref_err:e}",
            p.name()
        );

        let t = grid(0.0, t_end, n_out);
        let mut sys = p.clone();
        let sol = Abm::new(options(rtol, rtol * 1e-2))
            .solve(&mut sys, 0.0, &y0, &t)
            .unwrap();
        let mut e: f64 = 0.0;
        for (k, r) in fine.iter().enumerate() {
            for (x, y) in sol.y(k).iter().zip(r) {
                e = e.max((x - y).abs() / y.abs().max(1.0));
            }
        }
        assert!(e < allowed, "{}: error {e:e}", p.name());
    }
    check(Mathieu::default(), 20_000, 1e-9, 1e-7);
    check(VanDerPol::default(), 400_000, 1e-7, 1e-4);
}

/// The achieved error falls with the tolerance: over rtol 1e-4 .. 1e-12 (8 decades) the
/// fitted log-log slope of error against tolerance lies in [0.8, 1.2], and every tightening
/// by 10x reduces the error.
#[test]
fn error_is_proportional_to_tolerance() {
    let tolerances = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12];
    fn errors<P: TestProblem>(mut p: P, tolerances: &[f64]) -> Vec<f64> {
        let t = grid(0.0, p.t_end(), 200);
        let y0 = p.y0();
        tolerances
            .iter()
            .map(|&rtol| {
                let sol = Abm::new(options(rtol, 1e-2 * rtol))
                    .solve(&mut p, 0.0, &y0, &t)
                    .unwrap();
                max_error_vs_exact(&p, &t, &sol)
            })
            .collect()
    }
    for (name, err) in [
        (
            "harmonic",
            errors(HarmonicOscillator::default(), &tolerances),
        ),
        ("forced", errors(ForcedOscillator::default(), &tolerances)),
    ] {
        let slope = log_log_slope(&tolerances, &err);
        assert!(
            (0.8..=1.2).contains(&slope),
            "{name}: slope {slope}, errors {err:?}"
        );
        for w in err.windows(2) {
            assert!(w[1] < w[0], "{name}: errors not decreasing: {err:?}");
        }
    }
}

/// Dense output between steps: at each accepted step, interpolate at 7 interior points and
/// compare with the closed form; the interpolation error stays within the same small multiple
/// of the tolerance as the step-end error. The interpolant also reproduces the previous step
/// end to within the tolerance (not exactly: it interpolates f re-evaluated at the corrected
/// value, which differs from the f(prediction) the step integrated by about the local error).
#[test]
fn dense_output_is_accurate_between_steps() {
    for rtol in [1e-6, 1e-10] {
        let mut p = ForcedOscillator::default();
        let mut stepper = Abm::new(options(rtol, 1e-2 * rtol))
            .start(&mut p.clone(), 0.0, &p.y0(), p.t_end())
            .unwrap();
        let mut out = [0.0; 2];
        let mut worst_interior: f64 = 0.0;
        let mut worst_end: f64 = 0.0;
        let mut y_prev = stepper.y().to_vec();
        while stepper.t() < p.t_end() {
            stepper.step(&mut p).unwrap();
            let (t0, t1) = (stepper.t_previous(), stepper.t());
            for (a, b) in stepper.y().iter().zip(p.exact(t1).unwrap()) {
                worst_end = worst_end.max((a - b).abs());
            }
            for j in 1..8 {
                let t = t0 + (t1 - t0) * j as f64 / 8.0;
                stepper.interpolate(t, &mut out);
                for (a, b) in out.iter().zip(p.exact(t).unwrap()) {
                    worst_interior = worst_interior.max((a - b).abs());
                }
            }
            stepper.interpolate(t0, &mut out);
            for (a, b) in out.iter().zip(&y_prev) {
                assert!(
                    (a - b).abs() <= rtol * b.abs().max(1.0),
                    "interpolant misses the previous step end at t = {t0}"
                );
            }
            y_prev.copy_from_slice(stepper.y());
        }
        assert!(
            worst_interior < 10.0 * rtol,
            "rtol {rtol:e}: interior error {worst_interior:e}, step-end error {worst_end:e}"
        );
        assert!(worst_interior < 3.0 * worst_end.max(rtol));
    }
}

/// The dense output from `solve` at 2000 off-step times (harmonic oscillator, rtol 1e-9)
/// agrees with cos/sin and costs no extra right-hand-side evaluations.
#[test]
fn solve_dense_output_costs_no_extra_evaluations() {
    let p = HarmonicOscillator::default();
    let opts = options(1e-9, 1e-11);
    let sparse = Abm::new(opts.clone())
        .solve(&mut p.clone(), 0.0, &p.y0(), &[p.t_end()])
        .unwrap();
    let t = grid(0.0, p.t_end(), 2000);
    let dense = Abm::new(opts)
        .solve(&mut p.clone(), 0.0, &p.y0(), &t)
        .unwrap();
    assert_eq!(sparse.stats, dense.stats);
    assert!(max_error_vs_exact(&p, &t, &dense) < 1e-8);
}

// ---------------------------------------------------------------------------------------
// Work: Adams against Dormand-Prince at equal accuracy.

/// At rtol 1e-10 on the harmonic and forced oscillators the Adams code needs fewer than half
/// the right-hand-side evaluations that the 5th-order Dormand-Prince pair of this crate needs
/// at the same tolerance, while its error is no larger than 3x Dormand-Prince's (so the
/// comparison is at (about) equal accuracy, not bought by a looser result).
#[test]
fn fewer_than_half_the_evaluations_of_rk45_at_tight_tolerance() {
    fn compare<P: TestProblem + Clone>(p: P) {
        let (rtol, atol) = (1e-10, 1e-12);
        let t = grid(0.0, p.t_end(), 100);
        let y0 = p.y0();
        let abm = Abm::new(options(rtol, atol))
            .solve(&mut p.clone(), 0.0, &y0, &t)
            .unwrap();
        let rk = Rk45::new(options(rtol, atol))
            .solve(&mut p.clone(), 0.0, &y0, &t)
            .unwrap();
        let (e_abm, e_rk) = (
            max_error_vs_exact(&p, &t, &abm),
            max_error_vs_exact(&p, &t, &rk),
        );
        let (n_abm, n_rk) = (abm.stats.rhs_evaluations, rk.stats.rhs_evaluations);
        assert!(
            (n_abm as f64) < 0.5 * n_rk as f64,
            "{}: ABM {n_abm} evaluations (error {e_abm:e}), RK45 {n_rk} (error {e_rk:e})",
            p.name()
        );
        assert!(
            e_abm < 3.0 * e_rk.max(rtol),
            "{}: ABM error {e_abm:e}, RK45 error {e_rk:e}",
            p.name()
        );
    }
    compare(HarmonicOscillator::default());
    compare(ForcedOscillator::default());
}

// ---------------------------------------------------------------------------------------
// Stepping rules.

/// Backwards in time: y(-t) of the harmonic oscillator is cos(t) (even) with odd velocity.
#[test]
fn integrates_backwards_in_time() {
    let p = HarmonicOscillator::default();
    let t = grid(0.0, -15.0, 300);
    let sol = Abm::new(options(1e-9, 1e-11))
        .solve(&mut p.clone(), 0.0, &p.y0(), &t)
        .unwrap();
    let e = max_error_vs_exact(&p, &t, &sol);
    assert!(e < 1e-8, "backward error {e:e}");
}

/// The last step lands on t_end exactly (forwards and backwards, with awkward end times),
/// never beyond; steps respect max_step; the given initial step is the first step.
#[test]
fn lands_on_t_end_and_honours_step_limits() {
    for (t0, t_end) in [
        (0.0, 0.1 + 0.2),
        (1.0, 7.3),
        (3.0, -1.0 / 3.0),
        (1e6, 1e6 + 0.7),
    ] {
        let mut p = HarmonicOscillator::default();
        let max_step = 0.05;
        let h0 = 1e-4;
        let y0 = p.exact(t0).unwrap();
        let mut stepper = Abm::new(options(1e-8, 1e-10).max_step(max_step).initial_step(h0))
            .start(&mut p, t0, &y0, t_end)
            .unwrap();
        let dir = (t_end - t0).signum();
        let mut first = true;
        loop {
            stepper.step(&mut p).unwrap();
            let h = stepper.t() - stepper.t_previous();
            assert!(h * dir > 0.0);
            assert!(
                h.abs() <= max_step * (1.0 + 1e-12) + 4.0 * f64::EPSILON * t0.abs(),
                "step {h} > max_step"
            );
            assert!((stepper.t() - t_end) * dir <= 0.0, "stepped past t_end");
            if first && stepper.stats().rejected_steps == 0 {
                assert!((h.abs() - h0).abs() <= 1e-9 * h0 + 4.0 * f64::EPSILON * t0.abs());
            }
            first = false;
            if stepper.t().to_bits() == t_end.to_bits() {
                break;
            }
        }
        let e = (stepper.y()[0] - p.exact(t_end).unwrap()[0]).abs();
        assert!(e < 1e-7, "({t0}, {t_end}): error {e:e}");
        // Further calls are no-ops.
        let stats = stepper.stats().clone();
        stepper.step(&mut p).unwrap();
        assert_eq!(stepper.stats(), &stats);
        assert_eq!(stepper.t().to_bits(), t_end.to_bits());
    }
}

/// The statistics count every call of the right-hand side (checked with a counting wrapper),
/// the per-order counts add up to the accepted steps, and a PECE step costs exactly two
/// evaluations: calls = 2 (start: f(t0), initial step) + 2 accepted + 1 rejected.
#[test]
fn statistics_count_every_evaluation() {
    let mut sys = Counted {
        inner: ForcedOscillator::default(),
        calls: 0,
    };
    let sol = Abm::new(options(1e-7, 1e-9))
        .solve(&mut sys, 0.0, &[0.0, 0.0], &[20.0])
        .unwrap();
    let s: &Stats = &sol.stats;
    assert_eq!(s.rhs_evaluations, sys.calls);
    assert_eq!(
        s.rhs_evaluations,
        2 + 2 * s.accepted_steps + s.rejected_steps
    );
    assert_eq!(s.orders.iter().sum::<usize>(), s.accepted_steps);
    assert_eq!(s.jacobian_evaluations, 0);
    assert_eq!(s.lu_decompositions, 0);

    // With a given initial step there is no trial evaluation.
    sys.calls = 0;
    let sol = Abm::new(options(1e-7, 1e-9).initial_step(1e-3))
        .solve(&mut sys, 0.0, &[0.0, 0.0], &[20.0])
        .unwrap();
    assert_eq!(sol.stats.rhs_evaluations, sys.calls);
    assert_eq!(
        sol.stats.rhs_evaluations,
        1 + 2 * sol.stats.accepted_steps + sol.stats.rejected_steps
    );
}

/// The start phase raises the order by one per step (1, 2, 3, ...) and a limited order is
/// respected while the solution stays accurate.
#[test]
fn order_ramps_up_and_respects_max_order() {
    let mut p = HarmonicOscillator::default();
    let mut stepper = Abm::new(options(1e-10, 1e-12))
        .start(&mut p.clone(), 0.0, &p.y0(), p.t_end())
        .unwrap();
    let mut orders = Vec::new();
    for _ in 0..4 {
        stepper.step(&mut p).unwrap();
        orders.push(stepper.last_order());
    }
    assert_eq!(orders, [1, 2, 3, 4]);

    for max_order in [2, 5] {
        let t = grid(0.0, p.t_end(), 50);
        let sol = Abm::new(options(1e-8, 1e-10))
            .max_order(max_order)
            .solve(&mut p.clone(), 0.0, &p.y0(), &t)
            .unwrap();
        assert_eq!(sol.stats.max_order_used(), max_order);
        let e = max_error_vs_exact(&p, &t, &sol);
        // More steps at low order accumulate more global error: allow 30x the tolerance.
        assert!(e < 3e-7, "max_order {max_order}: error {e:e}");
    }
}

/// A step count predicted by hand: for y' = 1 every error estimate vanishes. STEP's rules
/// then give: step 1 at order 1 (start phase: raise the order, double the step); step 2 at
/// order 2, where the test "lower if ERKM1 <= ERK / 2" holds with both zero, which lowers the
/// order to 1 and ends the start phase; from then on order 1 (raising needs k + 1 steps of
/// equal size) with the step doubled every time (zero error allows it). From h0 = 1e-3 the
/// steps are 1e-3 * 2^j; after 9 steps t = 0.511 and the 10th (proposed 0.512) is shortened to
/// land on t_end = 1. Expected: 10 accepted steps, one at order 2, none rejected,
/// 1 + 2 * 10 = 21 evaluations, and y = 1 + t to rounding.
#[test]
fn start_phase_step_count_matches_hand_count() {
    struct Constant;
    impl OdeSystem for Constant {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, _t: f64, _y: &[f64], dy: &mut [f64]) {
            dy[0] = 1.0;
        }
    }
    let sol = Abm::new(options(1e-8, 1e-10).initial_step(1e-3))
        .solve(&mut Constant, 0.0, &[1.0], &[0.25, 1.0])
        .unwrap();
    let s = &sol.stats;
    assert_eq!(s.accepted_steps, 10);
    assert_eq!(s.rejected_steps, 0);
    assert_eq!(s.rhs_evaluations, 21);
    assert_eq!(s.orders, vec![0, 9, 1]);
    assert!((sol.y(0)[0] - 1.25).abs() < 1e-14);
    assert!((sol.y(1)[0] - 2.0).abs() < 1e-14);
}

/// 30 modal oscillators with frequencies 1 .. 900 rad/s (the beam ladder omega_1 j^2) over
/// 2 s (286 periods of the fastest mode): against the closed form, the error is no more than
/// 2x that of the Dormand-Prince integrator at the same tolerance, which needs over 3x the
/// evaluations. (Both codes control the local error per step; the global error grows with the
/// number of periods, here to a few hundred times the tolerance.)
#[test]
fn modal_ladder_of_thirty_modes() {
    let p = ModalLadder::new(30, 1.0);
    let t = grid(0.0, 2.0, 40);
    let error = |sol: &flexprr_integrators::Solution| {
        let mut e: f64 = 0.0;
        for (k, &tk) in t.iter().enumerate() {
            let exact = p.exact(tk);
            for (i, (a, b)) in sol.y(k).iter().zip(&exact).enumerate() {
                // Velocities have amplitude omega_j / j = j: compare relative to that.
                let scale = if i < 30 { 1.0 } else { (i - 29) as f64 };
                e = e.max((a - b).abs() / scale);
            }
        }
        e
    };
    let opts = options(1e-8, 1e-10);
    let abm = Abm::new(opts.clone())
        .solve(&mut p.clone(), 0.0, &p.y0(), &t)
        .unwrap();
    let rk = Rk45::new(opts)
        .solve(&mut p.clone(), 0.0, &p.y0(), &t)
        .unwrap();
    let (e_abm, e_rk) = (error(&abm), error(&rk));
    assert!(e_abm < 1e-5, "modal ladder error {e_abm:e}");
    assert!(
        e_abm < 2.0 * e_rk,
        "ABM error {e_abm:e}, RK45 error {e_rk:e}"
    );
    assert!(
        3 * abm.stats.rhs_evaluations < rk.stats.rhs_evaluations,
        "ABM {} evaluations, RK45 {}",
        abm.stats.rhs_evaluations,
        rk.stats.rhs_evaluations
    );
}

/// On a stiff linear problem (eigenvalues -1 and -1000) the explicit Adams code still gets the
/// closed-form answer, but only with stability-bounded steps at low order, and DE's stiffness
/// test (50 steps in a row at order <= 4) flags it; on the smooth harmonic oscillator at a
/// tight tolerance it does not.
#[test]
fn stiffness_is_flagged_on_a_stiff_problem_only() {
    let p = StiffLinear {
        lambda_fast: 1e3,
        t_end: 2.0,
        ..Default::default()
    };
    let t = grid(0.0, p.t_end, 20);
    let sol = Abm::new(options(1e-6, 1e-9))
        .solve(&mut p.clone(), 0.0, &p.y0(), &t)
        .unwrap();
    let e = max_error_vs_exact(&p, &t, &sol);
    assert!(e < 1e-5, "stiff linear error {e:e}");
    assert!(sol.stats.stiffness_detected_at.is_some(), "{:?}", sol.stats);
    // Stability, not accuracy, bounds the step: far more steps than the slow mode needs.
    assert!(sol.stats.accepted_steps > 500, "{:?}", sol.stats);

    let h = HarmonicOscillator::default();
    let sol = Abm::new(options(1e-10, 1e-12))
        .solve(&mut h.clone(), 0.0, &h.y0(), &[h.t_end()])
        .unwrap();
    assert_eq!(sol.stats.stiffness_detected_at, None);
}

/// No heap allocation inside `step` or `interpolate` (counted with a global allocator).
#[test]
fn step_and_interpolate_do_not_allocate() {
    let mut p = ModalLadder::new(20, 1.0);
    let y0 = p.y0();
    let mut stepper: AbmStepper = Abm::new(options(1e-9, 1e-11))
        .start(&mut p, 0.0, &y0, 1.0)
        .unwrap();
    let mut out = vec![0.0; p.dim()];
    let before = allocations();
    while stepper.t() < 1.0 {
        stepper.step(&mut p).unwrap();
        let tm = 0.5 * (stepper.t() + stepper.t_previous());
        stepper.interpolate(tm, &mut out);
    }
    assert_eq!(allocations(), before);
    assert!(stepper.stats().accepted_steps > 50);
}

// ---------------------------------------------------------------------------------------
// Errors.

/// y' = y^2, y(0) = 1 blows up at t = 1: the integration stops near 1 with the step-size
/// floor (or a non-finite state), never passes it, and reports the time.
#[test]
fn finite_time_blow_up_stops_near_the_singularity() {
    struct BlowUp;
    impl OdeSystem for BlowUp {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
            dy[0] = y[0] * y[0];
        }
    }
    let err = Abm::new(options(1e-8, 1e-10))
        .solve(&mut BlowUp, 0.0, &[1.0], &[2.0])
        .unwrap_err();
    match err {
        IntegratorError::StepSizeTooSmall { t, h } => {
            assert!((t - 1.0).abs() < 1e-3, "stopped at t = {t}, h = {h}");
        }
        IntegratorError::NonFinite { t, .. } => {
            assert!((t - 1.0).abs() < 1e-3, "stopped at t = {t}");
        }
        other => panic!("unexpected error {other:?}"),
    }
}

/// A right-hand side that returns NaN from t = 1.5 on: NonFinite with the component and a
/// time at (or just after) 1.5.
#[test]
fn non_finite_rhs_is_reported_with_time_and_component() {
    struct Poisoned;
    impl OdeSystem for Poisoned {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
            dy[0] = y[1];
            dy[1] = if t >= 1.5 { f64::NAN } else { -y[0] };
        }
    }
    let err = Abm::new(options(1e-8, 1e-10))
        .solve(&mut Poisoned, 0.0, &[1.0, 0.0], &[3.0])
        .unwrap_err();
    match err {
        IntegratorError::NonFinite { t, component } => {
            assert_eq!(component, 1);
            assert!((1.5..1.5 + 1e-6).contains(&t), "reported at t = {t}");
        }
        other => panic!("unexpected error {other:?}"),
    }
    // Non-finite already at t0.
    struct NanAtStart;
    impl OdeSystem for NanAtStart {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, _t: f64, _y: &[f64], dy: &mut [f64]) {
            dy[0] = f64::INFINITY;
        }
    }
    let err = Abm::new(Options::default())
        .solve(&mut NanAtStart, 0.0, &[1.0], &[1.0])
        .unwrap_err();
    assert_eq!(
        err,
        IntegratorError::NonFinite {
            t: 0.0,
            component: 0
        }
    );
}

/// max_steps is a hard limit reported with the time reached.
#[test]
fn too_many_steps_is_reported() {
    let p = HarmonicOscillator::default();
    let err = Abm::new(options(1e-10, 1e-12).max_steps(25))
        .solve(&mut p.clone(), 0.0, &p.y0(), &[20.0])
        .unwrap_err();
    match err {
        IntegratorError::TooManySteps { t, max_steps } => {
            assert_eq!(max_steps, 25);
            assert!(t > 0.0 && t < 20.0);
        }
        other => panic!("unexpected error {other:?}"),
    }
}

/// Bad options and inputs are errors naming the problem, not panics.
#[test]
fn bad_options_and_inputs_are_rejected() {
    let mut p = HarmonicOscillator::default();
    let y0 = p.y0();
    let cases: Vec<(Abm, Vec<f64>, f64)> = vec![
        (Abm::new(Options::default().rtol(-1.0)), y0.clone(), 1.0),
        (Abm::new(Options::default().rtol(1e-20)), y0.clone(), 1.0),
        (Abm::new(Options::default().atol(f64::NAN)), y0.clone(), 1.0),
        (
            Abm::new(Options::default().atol_per_component(vec![1e-9])),
            y0.clone(),
            1.0,
        ),
        (Abm::new(Options::default().max_step(0.0)), y0.clone(), 1.0),
        (
            Abm::new(Options::default().initial_step(-0.1)),
            y0.clone(),
            1.0,
        ),
        (Abm::new(Options::default()).max_order(0), y0.clone(), 1.0),
        (Abm::new(Options::default()).max_order(13), y0.clone(), 1.0),
    ];
    for (abm, y0, t_end) in cases {
        let err = abm.start(&mut p, 0.0, &y0, t_end).unwrap_err();
        assert!(
            matches!(err, IntegratorError::InvalidOptions(_)),
            "{abm:?}: {err}"
        );
    }
    let abm = Abm::new(Options::default());
    for (y0, t_end) in [
        (vec![1.0], 1.0),
        (vec![1.0, f64::NAN], 1.0),
        (vec![1.0, 0.0], 0.0),
        (vec![1.0, 0.0], f64::INFINITY),
    ] {
        let err = abm.start(&mut p, 0.0, &y0, t_end).unwrap_err();
        assert!(
            matches!(err, IntegratorError::InvalidInput(_)),
            "{y0:?} -> {t_end}: {err}"
        );
    }
}

// ---------------------------------------------------------------------------------------
// Properties.

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// y' = a y + b cos(t) with random a, b, y0 and direction, against the closed form
    /// y = C e^{a t} + b (a cos t - sin t)... written as the particular solution
    /// b (sin t - a cos t) / (1 + a^2) plus the homogeneous part.
    #[test]
    fn scalar_linear_problems_match_closed_form(
        a in -3.0f64..1.0,
        b in -2.0f64..2.0,
        y0 in -2.0f64..2.0,
        t_end in prop_oneof![0.3f64..4.0, -4.0f64..-0.3],
        rtol_exp in 4.0f64..11.0,
    ) {
        struct Linear { a: f64, b: f64 }
        impl OdeSystem for Linear {
            fn dim(&self) -> usize { 1 }
            fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
                dy[0] = self.a * y[0] + self.b * t.cos();
            }
        }
        let particular = |t: f64| b * (t.sin() - a * t.cos()) / (1.0 + a * a);
        let c = y0 - particular(0.0);
        let exact = |t: f64| c * (a * t).exp() + particular(t);
        let rtol = 10f64.powf(-rtol_exp);
        let t = grid(0.0, t_end, 20);
        let sol = Abm::new(options(rtol, rtol))
            .solve(&mut Linear { a, b }, 0.0, &[y0], &t)
            .unwrap();
        for (k, &tk) in t.iter().enumerate() {
            let e = (sol.y(k)[0] - exact(tk)).abs();
            let scale = exact(tk).abs().max(1.0) * (a * t_end).abs().exp().max(1.0);
            prop_assert!(e < 50.0 * rtol * scale, "t = {tk}: error {e:e}, rtol {rtol:e}");
        }
    }
}
