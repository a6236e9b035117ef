//! Tests of the one stepping loop (`Integrator::solve_observed`): stop times against the
//! closed-form response of a forced oscillator, observers that stop the run, failures that
//! keep the outputs computed so far, the object-safe adapter, and allocation freedom.

use std::f64::consts::PI;

use faer::MatMut;
use flexprr_integrators::{
    Abm, Bdf, DynIntegrator, Flow, Integrator, IntegratorError, Interrupted, Interruption,
    Observer, OdeSystem, Options, Rk45,
};

// ---------------------------------------------------------------------------------------
// Allocation counter (per thread, so parallel tests do not disturb each other).

use flexprr_testkit::alloc::{CountingAllocator, allocations};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

// ---------------------------------------------------------------------------------------
// The forced oscillator x'' + w^2 x = f(t), at rest until a pulse starts at t1.

/// Start and end of the pulse, and the end of the run.
const T1: f64 = 0.05;
const T2: f64 = 0.07;
const T_END: f64 = 0.2;

/// `x'' + w^2 x = f(t)` with `f = a sin^2(pi (t - t1) / T)` on `[t1, t1 + T]` and zero
/// elsewhere: the acceleration profile of a cycloidal move (its derivative is continuous,
/// its second derivative jumps at both ends). Optionally the right-hand side turns NaN after
/// `nan_after` (a model failing mid-run).
#[derive(Clone)]
struct PulsedOscillator {
    w: f64,
    a: f64,
    nan_after: Option<f64>,
}

impl PulsedOscillator {
    fn new() -> Self {
        // 20 Hz, and a force that makes the response of order 1.
        let w = 2.0 * PI * 20.0;
        Self {
            w,
            a: w * w,
            nan_after: None,
        }
    }

    fn force(&self, t: f64) -> f64 {
        if (T1..=T2).contains(&t) {
            let s = (PI * (t - T1) / (T2 - T1)).sin();
            self.a * s * s
        } else {
            0.0
        }
    }

    /// Closed-form `(x, x')` from rest: on the pulse, `f = a/2 (1 - cos(W s))` with
    /// `s = t - t1`, `W = 2 pi / T`, gives
    /// `x = a/(2w^2) (1 - cos ws) - a/(2 (w^2 - W^2)) (cos Ws - cos ws)`; after it the free
    /// oscillation from the state at `t2`.
    fn exact(&self, t: f64) -> [f64; 2] {
        let w = self.w;
        let big_w = 2.0 * PI / (T2 - T1);
        let on_pulse = |s: f64| {
            let c1 = self.a / (2.0 * w * w);
            let c2 = self.a / (2.0 * (w * w - big_w * big_w));
            [
                c1 * (1.0 - (w * s).cos()) - c2 * ((big_w * s).cos() - (w * s).cos()),
                c1 * w * (w * s).sin() - c2 * (-big_w * (big_w * s).sin() + w * (w * s).sin()),
            ]
        };
        if t <= T1 {
            [0.0, 0.0]
        } else if t <= T2 {
            on_pulse(t - T1)
        } else {
            let [x, v] = on_pulse(T2 - T1);
            let s = t - T2;
            [
                x * (w * s).cos() + v / w * (w * s).sin(),
                -x * w * (w * s).sin() + v * (w * s).cos(),
            ]
        }
    }
}

impl OdeSystem for PulsedOscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = y[1];
        dy[1] = -self.w * self.w * y[0] + self.force(t);
        if self.nan_after.is_some_and(|t_nan| t > t_nan) {
            dy[1] = f64::NAN;
        }
    }
    fn jacobian(&mut self, _t: f64, _y: &[f64], mut jac: MatMut<'_, f64>) {
        jac[(0, 0)] = 0.0;
        jac[(0, 1)] = 1.0;
        jac[(1, 0)] = -self.w * self.w;
        jac[(1, 1)] = 0.0;
    }
    fn has_analytic_jacobian(&self) -> bool {
        true
    }
}

fn output_times() -> Vec<f64> {
    (0..=200).map(|k| k as f64 * 1e-3).collect()
}

fn methods(options: &Options) -> Vec<Box<dyn DynIntegrator>> {
    vec![
        Box::new(Abm::new(options.clone())),
        Box::new(Rk45::new(options.clone())),
        Box::new(Bdf::new(options.clone())),
    ]
}

/// Largest error in `x` over the outputs, relative to the peak `|x|` of the exact response.
fn relative_error(p: &PulsedOscillator, t: &[f64], states: &[f64]) -> f64 {
    let peak = t.iter().map(|&t| p.exact(t)[0].abs()).fold(0.0, f64::max);
    let err = t
        .iter()
        .enumerate()
        .map(|(k, &t)| (states[2 * k] - p.exact(t)[0]).abs())
        .fold(0.0, f64::max);
    err / peak
}

// ---------------------------------------------------------------------------------------
// Tests.

/// The closed form itself: it satisfies the ODE (central differences) and is continuous
/// with its derivative at both ends of the pulse; so the comparison below is with a true
/// solution, not with a formula that only looks like one.
#[test]
fn closed_form_solves_the_ode() {
    let p = PulsedOscillator::new();
    let d = 1e-6;
    for &t in &[0.051, 0.06, 0.0699, 0.08, 0.15] {
        let [x, v] = p.exact(t);
        let xpp = (p.exact(t + d)[0] - 2.0 * x + p.exact(t - d)[0]) / (d * d);
        let resid = xpp + p.w * p.w * x - p.force(t);
        assert!(resid.abs() < 1e-3 * p.a, "t = {t}: residual {resid:e}");
        let xp = (p.exact(t + d)[0] - p.exact(t - d)[0]) / (2.0 * d);
        assert!((xp - v).abs() < 1e-6 * p.w, "t = {t}: x' {v} vs {xp}");
    }
    for tk in [T1, T2] {
        let (a, b) = (p.exact(tk - 1e-12), p.exact(tk + 1e-12));
        assert!((a[0] - b[0]).abs() < 1e-9 && (a[1] - b[1]).abs() < 1e-6);
    }
    // The response is of order one: a missed pulse is a large error, not a rounding one.
    assert!(p.exact(T2)[0].abs() > 0.1);
}

/// With the pulse's ends as stop times, every method follows the closed form to 1e-6
/// relative; without them (the bug the stops fix) the step grows over the whole pulse while
/// the forcing is still exactly zero, and the response is missed.
#[test]
fn stops_catch_a_pulse_that_starts_late() {
    let p = PulsedOscillator::new();
    let t_out = output_times();
    let options = Options::default().rtol(1e-10).atol(1e-12);
    for m in methods(&options) {
        let with = m
            .solve_dyn(
                &mut p.clone(),
                0.0,
                &[0.0, 0.0],
                &t_out,
                &[T2, T1, T1, 1.0, -1.0],
                &mut (),
            )
            .unwrap_or_else(|e| panic!("{}: {e}", m.name()));
        let err = relative_error(&p, &with.t, &with.states);
        assert!(
            err < 1e-6,
            "{} with stops: relative error {err:e}",
            m.name()
        );
        assert_eq!(with.stats.segments, 3, "{}", m.name());
        assert_eq!(with.len(), t_out.len());

        let without = m
            .solve_dyn(&mut p.clone(), 0.0, &[0.0, 0.0], &t_out, &[], &mut ())
            .unwrap_or_else(|e| panic!("{}: {e}", m.name()));
        let err = relative_error(&p, &without.t, &without.states);
        let peak = (0..without.len())
            .map(|k| without.y(k)[0].abs())
            .fold(0.0, f64::max);
        println!(
            "{}: without stops relative error {err:.3}, peak |x| {peak:e}",
            m.name()
        );
        assert!(
            err > 0.5,
            "{} without stops: error {err:e}; the test no longer shows the missed pulse",
            m.name()
        );
        // Not merely inaccurate: the state never leaves rest.
        assert!(peak < 1e-12, "{}: peak {peak:e}", m.name());
        assert_eq!(without.stats.segments, 1);
    }
}

/// The steps of the segments are summed, and `max_steps` bounds them all together.
#[test]
fn statistics_sum_over_segments_and_max_steps_is_global() {
    let p = PulsedOscillator::new();
    let t_out = output_times();
    let options = Options::default().rtol(1e-8).atol(1e-10);
    let rk45 = Rk45::new(options.clone());
    // The segments one by one with plain `solve`, chained by hand.
    let mut steps = 0;
    let mut y = vec![0.0, 0.0];
    for (a, b) in [(0.0, T1), (T1, T2), (T2, T_END)] {
        let sol = rk45.solve(&mut p.clone(), a, &y, &[b]).unwrap();
        steps += sol.stats.accepted_steps;
        y = sol.y(0).to_vec();
    }
    let sol = rk45
        .solve_observed(&mut p.clone(), 0.0, &[0.0, 0.0], &t_out, &[T1, T2], &mut ())
        .unwrap();
    assert_eq!(sol.stats.accepted_steps, steps);
    let last = sol.last().unwrap();
    assert!((last[0] - y[0]).abs() < 1e-12 && (last[1] - y[1]).abs() < 1e-9);
    // A step budget smaller than the total, but larger than any one segment needs.
    let budget = steps - 2;
    let e = Rk45::new(options.max_steps(budget))
        .solve_observed(&mut p.clone(), 0.0, &[0.0, 0.0], &t_out, &[T1, T2], &mut ())
        .unwrap_err();
    match e.reason {
        Interruption::Failed(IntegratorError::TooManySteps { t, max_steps }) => {
            assert_eq!(max_steps, budget);
            assert!(t > T2 && t < T_END, "t = {t}");
            let n = e.solution.stats.accepted_steps + e.solution.stats.rejected_steps;
            assert_eq!(n, budget);
        }
        other => panic!("expected TooManySteps, got {other:?}"),
    }
}

/// Stops the run at the first accepted step at or after `t_stop`; counts what it saw.
struct StopAfter {
    t_stop: f64,
    steps: usize,
    outputs: usize,
    last_step: f64,
}

impl Observer for StopAfter {
    fn on_step(&mut self, t: f64, _y: &[f64]) -> Flow {
        assert!(t > self.last_step, "steps out of order");
        self.last_step = t;
        self.steps += 1;
        if t >= self.t_stop {
            Flow::Stop
        } else {
            Flow::Continue
        }
    }
    fn on_output(&mut self, index: usize, _t: f64, _y: &[f64]) -> Flow {
        assert_eq!(index, self.outputs, "outputs out of order");
        self.outputs += 1;
        Flow::Continue
    }
}

/// An observer's `Stop` ends the run with `Stopped` at the time of the step, every output
/// up to that time (matching the closed form) and none after it.
#[test]
fn observer_stop_keeps_the_outputs_so_far() {
    let p = PulsedOscillator::new();
    let t_out = output_times();
    let options = Options::default().rtol(1e-10).atol(1e-12);
    for m in methods(&options) {
        let mut observer = StopAfter {
            t_stop: 0.1,
            steps: 0,
            outputs: 0,
            last_step: f64::NEG_INFINITY,
        };
        let e = m
            .solve_dyn(
                &mut p.clone(),
                0.0,
                &[0.0, 0.0],
                &t_out,
                &[T1, T2],
                &mut observer,
            )
            .unwrap_err();
        let Interruption::Stopped { t } = e.reason else {
            panic!("{}: expected Stopped, got {:?}", m.name(), e.reason);
        };
        assert!((0.1..T_END).contains(&t), "{}: stopped at {t}", m.name());
        assert_eq!(e.last_time(), Some(t));
        let expected = t_out.iter().filter(|&&s| s <= t).count();
        assert_eq!(e.solution.len(), expected, "{}", m.name());
        assert_eq!(observer.outputs, expected);
        assert_eq!(e.solution.stats.accepted_steps, observer.steps);
        assert!(relative_error(&p, &e.solution.t, &e.solution.states) < 1e-6);
        assert!(e.to_string().contains("stopped by the observer"), "{e}");
    }
    // A stop from `on_output` ends with exactly the outputs up to that index.
    struct FirstOutputs(usize);
    impl Observer for FirstOutputs {
        fn on_output(&mut self, index: usize, _t: f64, _y: &[f64]) -> Flow {
            if index + 1 >= self.0 {
                Flow::Stop
            } else {
                Flow::Continue
            }
        }
    }
    for m in methods(&options) {
        let e = m
            .solve_dyn(
                &mut p.clone(),
                0.0,
                &[0.0, 0.0],
                &t_out,
                &[],
                &mut FirstOutputs(31),
            )
            .unwrap_err();
        assert_eq!(e.solution.len(), 31, "{}", m.name());
        assert!(matches!(e.reason, Interruption::Stopped { t } if (t - 0.03).abs() < 1e-15));
    }
}

/// A right-hand side that turns NaN after t = 0.1 fails every method with `Interrupted`
/// holding the outputs up to the last accepted time (correct by the closed form), never
/// values at or after the failure.
#[test]
fn a_failing_run_keeps_the_outputs_up_to_the_last_accepted_time() {
    let mut p = PulsedOscillator::new();
    p.nan_after = Some(0.1);
    let t_out = output_times();
    let options = Options::default().rtol(1e-10).atol(1e-12);
    for m in methods(&options) {
        let e: Interrupted = m
            .solve_dyn(&mut p.clone(), 0.0, &[0.0, 0.0], &t_out, &[T1, T2], &mut ())
            .unwrap_err();
        let Interruption::Failed(error) = &e.reason else {
            panic!("{}: expected a failure, got {:?}", m.name(), e.reason);
        };
        let t_fail = e.last_time().expect("a time");
        assert!(
            (0.09..=0.1 + 1e-12).contains(&t_fail),
            "{}: failed at {t_fail} ({error})",
            m.name()
        );
        assert!(e.solution.t.iter().all(|&t| t <= t_fail));
        // Every output before the last step is there (steps here are far below 0.01 s).
        assert!(
            e.solution.len() >= 91,
            "{}: {} outputs",
            m.name(),
            e.solution.len()
        );
        assert!(e.solution.states.iter().all(|v| v.is_finite()));
        assert!(relative_error(&p, &e.solution.t, &e.solution.states) < 1e-6);
        assert!(e.solution.stats.accepted_steps > 0);
        assert!(std::error::Error::source(&e).is_some());
    }
}

/// Input errors come back as `Interrupted` too, with nothing computed.
#[test]
fn bad_input_is_an_interruption_with_no_output() {
    let p = PulsedOscillator::new();
    let rk45 = Rk45::new(Options::default());
    for (t_out, stops) in [
        (vec![], vec![]),
        (vec![0.1, 0.05], vec![]),
        (vec![0.1], vec![f64::NAN]),
    ] {
        let e = rk45
            .solve_observed(&mut p.clone(), 0.0, &[0.0, 0.0], &t_out, &stops, &mut ())
            .unwrap_err();
        assert!(matches!(
            e.reason,
            Interruption::Failed(IntegratorError::InvalidInput(_))
        ));
        assert!(e.solution.is_empty());
        assert_eq!(e.last_time(), None);
    }
}

/// Backwards in time with stops: the free oscillation integrated from t = 0.2 back to 0.07
/// through stops in any order matches the closed form.
#[test]
fn stops_work_backwards_in_time() {
    let p = PulsedOscillator::new();
    let t_out: Vec<f64> = (0..=13).map(|k| T_END - 0.01 * k as f64).collect();
    let y0 = p.exact(T_END);
    for m in methods(&Options::default().rtol(1e-10).atol(1e-12)) {
        let sol = m
            .solve_dyn(
                &mut p.clone(),
                T_END,
                &y0,
                &t_out,
                &[0.1, 0.15, 0.3],
                &mut (),
            )
            .unwrap();
        assert_eq!(sol.stats.segments, 3);
        assert!(
            relative_error(&p, &sol.t, &sol.states) < 1e-6,
            "{}",
            m.name()
        );
    }
}

/// The methods are `Send + Sync`, so boxed integrators can move between threads.
#[test]
fn methods_are_send_and_sync() {
    fn check<T: Send + Sync>() {}
    check::<Abm>();
    check::<Rk45>();
    check::<Bdf>();
    check::<Box<dyn DynIntegrator>>();
    let boxed = methods(&Options::default());
    let names: Vec<String> = std::thread::scope(|s| {
        boxed
            .iter()
            .map(|m| s.spawn(|| m.name().to_string()))
            .collect::<Vec<_>>()
            .into_iter()
            .map(|h| h.join().unwrap())
            .collect()
    });
    assert_eq!(names, ["abm", "rk45", "bdf"]);
}

/// Counts steps and outputs without allocating.
#[derive(Default)]
struct Counter {
    steps: usize,
    outputs: usize,
}

impl Observer for Counter {
    fn on_step(&mut self, _t: f64, _y: &[f64]) -> Flow {
        self.steps += 1;
        Flow::Continue
    }
    fn on_output(&mut self, _index: usize, _t: f64, _y: &[f64]) -> Flow {
        self.outputs += 1;
        Flow::Continue
    }
}

/// The loop allocates only up front (per segment start) and for the outputs, never per step:
/// a run at a tolerance needing more than twice the steps makes exactly as many allocations.
#[test]
fn the_loop_allocates_per_segment_not_per_step() {
    let p = PulsedOscillator::new();
    let t_out = output_times();
    let count = |m: &dyn DynIntegrator| {
        let mut observer = Counter::default();
        let mut system = p.clone();
        let before = allocations();
        let sol = m
            .solve_dyn(
                &mut system,
                0.0,
                &[0.0, 0.0],
                &t_out,
                &[T2, T1],
                &mut observer,
            )
            .unwrap();
        let n = allocations() - before;
        assert_eq!(observer.steps, sol.stats.accepted_steps);
        assert_eq!(observer.outputs, t_out.len());
        (n, sol.stats.accepted_steps)
    };
    let loose = methods(&Options::default().rtol(1e-5).atol(1e-7));
    let tight = methods(&Options::default().rtol(1e-10).atol(1e-12));
    for (a, b) in loose.iter().zip(&tight) {
        let (n_loose, steps_loose) = count(a.as_ref());
        let (n_tight, steps_tight) = count(b.as_ref());
        assert!(
            steps_tight > 2 * steps_loose,
            "{}: {steps_loose} vs {steps_tight} steps",
            a.name()
        );
        assert_eq!(
            n_loose,
            n_tight,
            "{}: allocations depend on the step count",
            a.name()
        );
    }
}
