//! Tests of the Dormand-Prince 5(4) integrator against closed-form solutions, an independent
//! fixed-step classical Runge-Kutta reference, published step counts and error laws.

use flexprr_integrators::test_problems::{
    ForcedOscillator, HarmonicOscillator, Mathieu, StiffLinear, TestProblem, VanDerPol,
};
use flexprr_integrators::{
    Integrator, IntegratorError, OdeSystem, Options, Rk45, Stepper, StiffnessDetection,
};
use flexprr_testkit::alloc::{CountingAllocator, allocations as allocations_so_far};
use proptest::prelude::*;

/// Reference solution by the classical 4th-order Runge-Kutta method with a fixed step
/// (Kutta 1901; Hairer-Norsett-Wanner I, Table II.1.2): independent of the code under test.
fn classical_rk4<S: OdeSystem>(
    system: &mut S,
    t0: f64,
    y0: &[f64],
    t_end: f64,
    steps: usize,
) -> Vec<f64> {
    let n = y0.len();
    let h = (t_end - t0) / steps as f64;
    let mut y = y0.to_vec();
    let (mut k1, mut k2, mut k3, mut k4, mut ys) = (
        vec![0.0; n],
        vec![0.0; n],
        vec![0.0; n],
        vec![0.0; n],
        vec![0.0; n],
    );
    for s in 0..steps {
        let t = t0 + s as f64 * h;
        system.rhs(t, &y, &mut k1);
        for i in 0..n {
            ys[i] = y[i] + 0.5 * h * k1[i];
        }
        system.rhs(t + 0.5 * h, &ys, &mut k2);
        for i in 0..n {
            ys[i] = y[i] + 0.5 * h * k2[i];
        }
        system.rhs(t + 0.5 * h, &ys, &mut k3);
        for i in 0..n {
            ys[i] = y[i] + h * k3[i];
        }
        system.rhs(t + h, &ys, &mut k4);
        for i in 0..n {
            y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }
    y
}

// Heap allocations made by the current thread, to check that stepping allocates nothing
// (tests run in parallel threads, hence the thread-local counter of the test kit).
#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

/// Largest componentwise absolute difference.
fn max_abs_difference(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Largest absolute error against the exact solution over `n_out` equally spaced times
/// (almost all of them between steps, so this tests dense output too).
fn max_error_vs_exact<P: TestProblem>(p: &mut P, opts: Options, n_out: usize) -> (f64, usize) {
    let t0 = p.t0();
    let t_end = p.t_end();
    let t_out: Vec<f64> = (1..=n_out)
        .map(|k| t0 + (t_end - t0) * k as f64 / n_out as f64)
        .collect();
    let y0 = p.y0();
    let sol = Rk45::new(opts).solve(p, t0, &y0, &t_out).unwrap();
    let mut worst: f64 = 0.0;
    for (k, &t) in t_out.iter().enumerate() {
        let exact = p.exact(t).unwrap();
        for (a, b) in sol.y(k).iter().zip(&exact) {
            worst = worst.max((a - b).abs());
        }
    }
    (worst, sol.stats.accepted_steps)
}

#[test]
fn harmonic_and_forced_oscillators_match_their_closed_forms() {
    let opts = Options::default().rtol(1e-9).atol(1e-12);
    let (err, steps) = max_error_vs_exact(&mut HarmonicOscillator::default(), opts.clone(), 400);
    assert!(err < 1e-7, "harmonic: max error {err:e} in {steps} steps");
    let (err, steps) = max_error_vs_exact(&mut ForcedOscillator::default(), opts, 400);
    assert!(err < 1e-7, "forced: max error {err:e} in {steps} steps");
}

/// Mathieu's equation has no closed form: compare with classical RK4 at h = 1e-3
/// (global error about 1e-12 here).
#[test]
fn mathieu_matches_a_fine_classical_runge_kutta_solution() {
    let mut p = Mathieu::default();
    let (y0, t_end) = (p.y0(), p.t_end());
    let reference = classical_rk4(&mut p, 0.0, &y0, t_end, 20_000);
    let opts = Options::default().rtol(1e-10).atol(1e-12);
    let sol = Rk45::new(opts).solve(&mut p, 0.0, &y0, &[t_end]).unwrap();
    for (a, b) in sol.last().unwrap().iter().zip(&reference) {
        assert!((a - b).abs() < 1e-8, "{a} vs reference {b}");
    }
}

/// Van der Pol at eps = 0.003 (mildly stiff relaxation): compare with classical RK4 at
/// h = 2e-5 (well inside its stability region, |h lambda| <= 0.03).
#[test]
fn van_der_pol_matches_a_fine_classical_runge_kutta_solution() {
    let mut p = VanDerPol::default();
    let (y0, t_end) = (p.y0(), p.t_end());
    let reference = classical_rk4(&mut p, 0.0, &y0, t_end, 100_000);
    let opts = Options::default().rtol(1e-9).atol(1e-9);
    let sol = Rk45::new(opts).solve(&mut p, 0.0, &y0, &[t_end]).unwrap();
    let y = sol.last().unwrap();
    // y1 is O(1), y2 up to O(1/eps) on the fast jump; compare relative to the size.
    for (a, b) in y.iter().zip(&reference) {
        assert!(
            (a - b).abs() < 1e-6 * b.abs().max(1.0),
            "{a} vs reference {b}"
        );
    }
}

/// Published figures for DOPRI5 on Hairer's Van der Pol problem (eps = 0.003, y(0) = (2, 0),
/// t in [0, 2], rtol = atol = 1e-3), as quoted in the task issue from Hairer's DOPRI5 runs:
/// 522 steps and 3133 function evaluations. We must be within a factor 1.5 of both.
#[test]
fn van_der_pol_step_counts_are_comparable_with_dopri5() {
    const DOPRI5_STEPS: f64 = 522.0;
    const DOPRI5_EVALUATIONS: f64 = 3133.0;
    let mut p = VanDerPol::default();
    let (y0, t_end) = (p.y0(), p.t_end());
    let opts = Options::default().rtol(1e-3).atol(1e-3);
    let sol = Rk45::new(opts).solve(&mut p, 0.0, &y0, &[t_end]).unwrap();
    let s = &sol.stats;
    let steps = (s.accepted_steps + s.rejected_steps) as f64;
    let evals = s.rhs_evaluations as f64;
    println!(
        "VdP eps=0.003: {} accepted, {} rejected, {} evaluations",
        s.accepted_steps, s.rejected_steps, s.rhs_evaluations
    );
    assert!(
        steps / DOPRI5_STEPS < 1.5 && DOPRI5_STEPS / steps < 1.5,
        "{steps} steps vs DOPRI5's {DOPRI5_STEPS}"
    );
    assert!(
        evals / DOPRI5_EVALUATIONS < 1.5 && DOPRI5_EVALUATIONS / evals < 1.5,
        "{evals} evaluations vs DOPRI5's {DOPRI5_EVALUATIONS}"
    );
}

/// FSAL bookkeeping: one evaluation for f(t0, y0), one for the starting-step probe, six per
/// attempted step; every accepted step has order 5.
#[test]
fn evaluation_count_follows_the_fsal_design() {
    let mut p = ForcedOscillator::default();
    let (y0, t_end) = (p.y0(), p.t_end());
    let opts = Options::default().rtol(1e-6).atol(1e-8);
    let sol = Rk45::new(opts.clone())
        .solve(&mut p, 0.0, &y0, &[t_end])
        .unwrap();
    let s = &sol.stats;
    assert_eq!(
        s.rhs_evaluations,
        2 + 6 * (s.accepted_steps + s.rejected_steps)
    );
    assert_eq!(s.orders.get(5).copied(), Some(s.accepted_steps));
    assert_eq!(s.max_order_used(), 5);
    assert_eq!(
        s.jacobian_evaluations + s.lu_decompositions + s.newton_iterations,
        0
    );
    // A given initial step saves the probe.
    let sol = Rk45::new(opts.initial_step(1e-3))
        .solve(&mut p, 0.0, &y0, &[t_end])
        .unwrap();
    let s = &sol.stats;
    assert_eq!(
        s.rhs_evaluations,
        1 + 6 * (s.accepted_steps + s.rejected_steps)
    );
}

/// The global error falls in proportion to the tolerance: a least-squares fit of
/// log10(error) against log10(rtol) over 6 decades has a slope near 1 (tolerance
/// proportionality; Hairer-Norsett-Wanner I, II.4).
#[test]
fn error_is_proportional_to_the_tolerance() {
    let mut xs = Vec::new();
    let mut ys = Vec::new();
    for k in 0..=12 {
        let rtol = 10f64.powf(-4.0 - 0.5 * k as f64);
        let opts = Options::default().rtol(rtol).atol(rtol * 1e-2);
        let (err, _) = max_error_vs_exact(&mut ForcedOscillator::default(), opts, 200);
        xs.push(rtol.log10());
        ys.push(err.log10());
    }
    let n = xs.len() as f64;
    let mx = xs.iter().sum::<f64>() / n;
    let my = ys.iter().sum::<f64>() / n;
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
    let slope = sxy / sxx;
    println!("error vs tolerance slope {slope:.3}");
    assert!((0.75..=1.15).contains(&slope), "slope {slope}");
}

/// ForcedOscillator at rtol = 1e-8, atol = 1e-10 over 20 s: the largest error at 1000 output
/// times is within 10x of the tolerance scale `rtol * max|y| + atol`.
#[test]
fn forced_oscillator_error_is_within_ten_times_the_tolerance() {
    let mut p = ForcedOscillator::default();
    let (rtol, atol) = (1e-8, 1e-10);
    let (err, steps) = max_error_vs_exact(&mut p, Options::default().rtol(rtol).atol(atol), 1000);
    // Amplitudes: |y1| <= 2 F / (omega^2 - Omega^2), |y2| <= F (omega + Omega) / (omega^2 - Omega^2).
    let denom = p.omega * p.omega - p.forcing_omega * p.forcing_omega;
    let y_max = (p.amplitude * (p.omega + p.forcing_omega) / denom).max(2.0 * p.amplitude / denom);
    let scale = rtol * y_max + atol;
    println!(
        "forced oscillator rtol 1e-8: max error {err:e} ({:.2} x tolerance), {steps} steps",
        err / scale
    );
    assert!(
        err < 10.0 * scale,
        "error {err:e} vs tolerance scale {scale:e}"
    );
}

/// Dense output: within each step, at 9 interior points, the interpolant is as accurate as
/// the step end points (the 4th-order extension's error is below the global error here).
#[test]
fn dense_output_is_as_accurate_as_the_steps() {
    let p = HarmonicOscillator {
        omega: 2.0,
        t_end: 10.0,
    };
    for rtol in [1e-5, 1e-8] {
        let mut sys = p.clone();
        let rk = Rk45::new(Options::default().rtol(rtol).atol(rtol * 1e-2));
        let mut stepper = rk.start(&mut sys, 0.0, &p.y0(), p.t_end).unwrap();
        let mut out = [0.0; 2];
        let mut worst_end: f64 = 0.0;
        let mut worst_dense: f64 = 0.0;
        while stepper.t() < p.t_end {
            stepper.step(&mut sys).unwrap();
            let exact = p.exact(stepper.t()).unwrap();
            worst_end = worst_end.max(max_abs_difference(stepper.y(), &exact));
            let (ta, tb) = (stepper.t_previous(), stepper.t());
            for j in 1..10 {
                let t = ta + (tb - ta) * j as f64 / 10.0;
                stepper.interpolate(t, &mut out);
                let exact = p.exact(t).unwrap();
                worst_dense = worst_dense.max(max_abs_difference(&out, &exact));
            }
        }
        println!("rtol {rtol:e}: step-end error {worst_end:e}, dense error {worst_dense:e}");
        assert!(
            worst_dense <= 2.0 * worst_end + rtol * 1e-2,
            "rtol {rtol}: dense {worst_dense:e} vs ends {worst_end:e}"
        );
        // And the interpolant is continuous with the steps: at theta = 1 it gives y.
        stepper.interpolate(stepper.t(), &mut out);
        assert!(max_abs_difference(&out, stepper.y()) < 1e-14);
    }
}

/// Integration backwards in time: cos(omega t) at negative times.
#[test]
fn integrates_backwards_in_time() {
    let mut p = HarmonicOscillator::default();
    let y0 = p.y0();
    let t_out: Vec<f64> = (1..=50).map(|k| -0.2 * k as f64).collect();
    let sol = Rk45::new(Options::default().rtol(1e-9).atol(1e-12))
        .solve(&mut p, 0.0, &y0, &t_out)
        .unwrap();
    for (k, &t) in t_out.iter().enumerate() {
        let exact = p.exact(t).unwrap();
        assert!(max_abs_difference(sol.y(k), &exact) < 1e-7, "t = {t}");
    }
}

/// The last step lands on t_end exactly (forwards and backwards), and max_step bounds every
/// step.
#[test]
fn lands_on_t_end_exactly_and_honours_max_step() {
    for (t_end, max_step) in [
        (7.3, f64::INFINITY),
        (-7.3, f64::INFINITY),
        (7.3, 0.05),
        (-3.1, 0.07),
    ] {
        let mut p = HarmonicOscillator::default();
        let opts = Options::default().rtol(1e-6).max_step(max_step);
        let mut stepper = Rk45::new(opts)
            .start(&mut p, 0.0, &[1.0, 0.0], t_end)
            .unwrap();
        let mut longest: f64 = 0.0;
        let mut steps = 0;
        loop {
            stepper.step(&mut p).unwrap();
            steps += 1;
            longest = longest.max((stepper.t() - stepper.t_previous()).abs());
            if (stepper.t() - t_end).abs() < 1e-9 {
                break;
            }
        }
        assert_eq!(stepper.t().to_bits(), t_end.to_bits(), "t_end {t_end}");
        assert!(
            longest <= max_step * (1.0 + 1e-12),
            "longest step {longest} > max_step {max_step}"
        );
        if max_step.is_finite() {
            assert!(steps as f64 >= (t_end.abs() / max_step).floor());
        }
    }
}

/// A given initial step is used for the first attempt.
#[test]
fn honours_the_initial_step() {
    let mut p = HarmonicOscillator::default();
    let opts = Options::default().rtol(1e-6).initial_step(1e-4);
    let mut stepper = Rk45::new(opts)
        .start(&mut p, 0.0, &[1.0, 0.0], 10.0)
        .unwrap();
    stepper.step(&mut p).unwrap();
    assert!(
        (stepper.t() - 1e-4).abs() < 1e-18,
        "first step ended at {}",
        stepper.t()
    );
    assert_eq!(stepper.stats().rejected_steps, 0);
    assert!((stepper.last_step_size() - 1e-4).abs() < 1e-18);
    // The controller grows the next step (error far below tolerance), by at most 10x.
    assert!(stepper.step_size() > 1e-4 && stepper.step_size() <= 1e-3 * (1.0 + 1e-12));
}

/// Hairer's stiffness test fires on a stiff linear problem (eigenvalues -1 and -1e4) once the
/// fast transient has died out, is silent on oscillators, and can stop the integration.
#[test]
fn stiffness_detection_reports_or_stops() {
    let p = StiffLinear {
        lambda_fast: 1e4,
        t_end: 1.0,
        ..Default::default()
    };
    let opts = Options::default().rtol(1e-6).atol(1e-9);

    // Report (the default): the integration finishes, accurately, and records the time.
    let mut sys = p.clone();
    let sol = Rk45::new(opts.clone())
        .solve(&mut sys, 0.0, &p.y0(), &[p.t_end])
        .unwrap();
    let t_stiff = sol
        .stats
        .stiffness_detected_at
        .expect("stiffness not detected");
    // The fast mode decays as exp(-1e4 t); afterwards the step is stability-limited to
    // |h| <= 3.3e-4, so 15 such steps take a few ms.
    assert!(t_stiff > 0.0 && t_stiff < 0.05, "detected at t = {t_stiff}");
    let exact = p.exact(p.t_end).unwrap();
    for (a, b) in sol.last().unwrap().iter().zip(&exact) {
        assert!((a - b).abs() < 1e-6, "{a} vs exact {b}");
    }
    // About t_end * lambda_fast / 3.3 steps: stability, not accuracy, sets the cost.
    assert!(sol.stats.accepted_steps > 2000);

    // Error: stops at the same time with the h*lambda estimate above the threshold.
    let mut sys = p.clone();
    let result = Rk45::new(opts.clone())
        .with_stiffness(StiffnessDetection::Error)
        .solve(&mut sys, 0.0, &p.y0(), &[p.t_end]);
    match result {
        Err(IntegratorError::Stiff { t, h_lambda }) => {
            assert!(
                (t - t_stiff).abs() < 1e-12,
                "stopped at {t}, reported at {t_stiff}"
            );
            assert!((3.25..6.0).contains(&h_lambda), "h lambda = {h_lambda}");
        }
        other => panic!("expected Stiff, got {other:?}"),
    }

    // Off: nothing recorded.
    let mut sys = p.clone();
    let sol = Rk45::new(opts.clone())
        .with_stiffness_detection(false)
        .solve(&mut sys, 0.0, &p.y0(), &[p.t_end])
        .unwrap();
    assert!(sol.stats.stiffness_detected_at.is_none());

    // Non-stiff problems never trigger it, even in Error mode.
    let mut osc = ForcedOscillator::default();
    let sol = Rk45::new(opts)
        .with_stiffness(StiffnessDetection::Error)
        .solve(&mut osc, 0.0, &[0.0, 0.0], &[20.0])
        .unwrap();
    assert!(sol.stats.stiffness_detected_at.is_none());
}

/// y' = y^2, y(0) = 1 blows up at t = 1 (y = 1 / (1 - t)): the step collapses there.
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
    let result =
        Rk45::new(Options::default().rtol(1e-6).atol(1e-9)).solve(&mut BlowUp, 0.0, &[1.0], &[2.0]);
    match result {
        Err(IntegratorError::StepSizeTooSmall { t, h }) => {
            assert!((t - 1.0).abs() < 1e-3, "stopped at t = {t}");
            assert!(h.abs() < 1e-10, "h = {h}");
        }
        Err(IntegratorError::NonFinite { t, .. }) => {
            assert!((t - 1.0).abs() < 1e-3, "stopped at t = {t}");
        }
        other => panic!("expected a step collapse near t = 1, got {other:?}"),
    }
}

/// A right-hand side that returns NaN beyond t = 0.5 is reported with the time reached.
#[test]
fn non_finite_right_hand_side_is_reported_with_its_time() {
    struct Breaks;
    impl OdeSystem for Breaks {
        fn dim(&self) -> usize {
            2
        }
        fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
            dy[0] = y[1];
            dy[1] = if t > 0.5 { f64::NAN } else { -y[0] };
        }
    }
    let result = Rk45::new(Options::default()).solve(&mut Breaks, 0.0, &[1.0, 0.0], &[1.0]);
    match result {
        Err(IntegratorError::NonFinite { t, component }) => {
            assert!(t <= 0.5 && t > 0.3, "t = {t}");
            assert!(component <= 1);
        }
        other => panic!("expected NonFinite, got {other:?}"),
    }
    // Non-finite at the start: f(t0, y0) itself.
    let result = Rk45::new(Options::default()).solve(&mut Breaks, 0.6, &[1.0, 0.0], &[1.0]);
    assert!(
        matches!(result, Err(IntegratorError::NonFinite { t, component: 1 }) if (t - 0.6).abs() < 1e-15)
    );
}

#[test]
fn bad_input_and_options_are_errors() {
    let mut p = HarmonicOscillator::default();
    let rk = Rk45::new(Options::default().rtol(-1.0));
    assert!(matches!(
        rk.solve(&mut p, 0.0, &[1.0, 0.0], &[1.0]),
        Err(IntegratorError::InvalidOptions(_))
    ));
    let rk = Rk45::new(Options::default());
    assert!(
        matches!(rk.solve(&mut p, 0.0, &[1.0], &[1.0]), Err(IntegratorError::InvalidInput(m)) if m.contains("y0 has 1 components"))
    );
    assert!(
        matches!(rk.solve(&mut p, 0.0, &[f64::NAN, 0.0], &[1.0]), Err(IntegratorError::InvalidInput(m)) if m.contains("y0[0]"))
    );
    assert!(matches!(
        rk.start(&mut p, 1.0, &[1.0, 0.0], 1.0),
        Err(IntegratorError::InvalidInput(_))
    ));
    assert!(matches!(
        rk.start(&mut p, 0.0, &[1.0, 0.0], f64::INFINITY),
        Err(IntegratorError::InvalidInput(_))
    ));
    let rk = Rk45::new(Options::default().max_steps(10));
    match rk.solve(&mut p, 0.0, &[1.0, 0.0], &[20.0]) {
        Err(IntegratorError::TooManySteps { t, max_steps: 10 }) => assert!(t > 0.0 && t < 20.0),
        other => panic!("expected TooManySteps, got {other:?}"),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, failure_persistence: None, ..ProptestConfig::default() })]

    /// y' = lambda y from any start, forwards or backwards, at any output times: dense output
    /// within a small multiple of the tolerance of y0 exp(lambda (t - t0)).
    #[test]
    fn linear_growth_and_decay_match_the_exponential(
        lambda in -5.0_f64..1.0,
        y0 in -3.0_f64..3.0,
        t0 in -2.0_f64..2.0,
        span in prop_oneof![-3.0_f64..-0.1, 0.1_f64..3.0],
        fractions in proptest::collection::vec(0.0_f64..1.0, 1..8),
    ) {
        struct Linear(f64);
        impl OdeSystem for Linear {
            fn dim(&self) -> usize { 1 }
            fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) { dy[0] = self.0 * y[0]; }
        }
        let mut fr = fractions;
        fr.sort_by(f64::total_cmp);
        fr.push(1.0);
        let t_out: Vec<f64> = fr.iter().map(|f| t0 + f * span).collect();
        let (rtol, atol) = (1e-8, 1e-10);
        let sol = Rk45::new(Options::default().rtol(rtol).atol(atol))
            .solve(&mut Linear(lambda), t0, &[y0], &t_out)
            .unwrap();
        for (k, &t) in t_out.iter().enumerate() {
            let exact = y0 * (lambda * (t - t0)).exp();
            let err = (sol.y(k)[0] - exact).abs();
            prop_assert!(err <= 20.0 * (rtol * exact.abs().max(y0.abs()) + atol), "t = {}: err {:e}", t, err);
        }
    }
}

/// `step` and `interpolate` allocate nothing: all work vectors come from `start`
/// (including the stiffness test, rejected steps and the order statistics).
#[test]
fn stepping_and_dense_output_do_not_allocate() {
    let mut p = VanDerPol::default();
    let rk = Rk45::new(Options::default().rtol(1e-4).atol(1e-6));
    let mut stepper = rk.start(&mut p, 0.0, &[2.0, 0.0], 2.0).unwrap();
    let mut out = [0.0; 2];
    let before = allocations_so_far();
    while stepper.t() < 2.0 {
        stepper.step(&mut p).unwrap();
        let t_mid = 0.5 * (stepper.t_previous() + stepper.t());
        stepper.interpolate(t_mid, &mut out);
    }
    let allocated = allocations_so_far() - before;
    let s = stepper.stats();
    assert!(
        s.rejected_steps > 0 && s.stiffness_detected_at.is_some(),
        "{s:?}"
    );
    assert_eq!(
        allocated, 0,
        "{allocated} allocations in {} steps",
        s.accepted_steps
    );
}
