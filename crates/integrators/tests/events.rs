//! Terminal events and rejected trials (issue 34, "failures from accepted steps only"): the
//! stepping loop decides a system's terminal event on accepted states and their dense output
//! only, locates its first crossing, keeps the outputs up to it, and tells the system when a
//! step is accepted so it can forget what rejected trials met. Checked for every method
//! against the closed form of the oscillator `q'' = -w^2 q`, `q(0) = 1`: `q = cos(w t)`
//! first reaches `1/2` at `t* = pi / (3 w)`.
//!
//! Extend it by adding a method to `methods` or a system below; each test states the defect
//! it guards against.

use faer::MatMut;
use flexprr_integrators::{
    BlockOperators, DynIntegrator, EVENT_RESOLUTION, GeneralizedAlpha, IntegratorError,
    Interruption, LinearSecondOrder, Magnus, OdeSystem, Options, SecondOrderForm,
};

const W: f64 = 2.0 * std::f64::consts::PI * 5.0;

/// `q'' = -W^2 q` with a terminal event `g = 1/2 - q` (reached once `q <= 1/2`), the
/// right-hand side NaN (a failure it records) wherever `|q'| > nan_beyond W`, and a log of the
/// event calls and of the accepted steps.
struct Falling {
    nan_beyond: f64,
    /// When set, the event is instead reached only within `window` of the time `at`:
    /// `g = window - |t - at|`.
    window: Option<(f64, f64)>,
    failure: Option<f64>,
    /// Right-hand sides that failed.
    failed: usize,
    accepted: usize,
    last_event: Option<(f64, f64)>,
}

impl Falling {
    fn new(nan_beyond: f64) -> Self {
        Self {
            nan_beyond,
            window: None,
            failure: None,
            failed: 0,
            accepted: 0,
            last_event: None,
        }
    }
}

impl OdeSystem for Falling {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        if y[1].abs() > self.nan_beyond * W {
            self.failure = Some(t);
            self.failed += 1;
            dy.fill(f64::NAN);
            return;
        }
        dy[0] = y[1];
        dy[1] = -W * W * y[0];
    }
    fn step_accepted(&mut self, _t: f64, _y: &[f64]) {
        self.failure = None;
        self.accepted += 1;
    }
    fn terminal_event(&mut self, t: f64, y: &[f64]) -> Option<f64> {
        self.last_event = Some((t, y[0]));
        Some(match self.window {
            Some((at, window)) => window - (t - at).abs(),
            None => 0.5 - y[0],
        })
    }
    fn second_order_form(&mut self) -> Option<&mut dyn SecondOrderForm> {
        Some(self)
    }
    fn linear_form(&mut self) -> Option<&mut dyn LinearSecondOrder> {
        Some(self)
    }
}

impl SecondOrderForm for Falling {
    fn coordinates(&self) -> usize {
        1
    }
    fn matrices(
        &mut self,
        _t: f64,
        _y: &[f64],
        mut mass: MatMut<'_, f64>,
        _damping: MatMut<'_, f64>,
        mut stiffness: MatMut<'_, f64>,
    ) {
        mass[(0, 0)] = 1.0;
        stiffness[(0, 0)] = W * W;
    }
}

impl LinearSecondOrder for Falling {
    fn block_count(&self) -> usize {
        1
    }
    fn block_operators(&self, _block: usize) -> BlockOperators {
        BlockOperators {
            size: 1,
            stiffness: vec![vec![W * W]],
            forcing: vec![vec![0.0]],
            damping: None,
            transform: None,
        }
    }
    fn coefficients(&mut self, _t: f64, s: &mut [f64], f: &mut [f64]) {
        s[0] = 1.0;
        f[0] = 0.0;
    }
}

fn methods(options: Options) -> Vec<Box<dyn DynIntegrator>> {
    vec![
        Box::new(flexprr_integrators::Abm::new(options.clone())),
        Box::new(flexprr_integrators::Rk45::new(options.clone())),
        Box::new(flexprr_integrators::Bdf::new(options.clone())),
        Box::new(GeneralizedAlpha::new(options.clone())),
        Box::new(Magnus::magnus6(options)),
    ]
}

fn output_times() -> Vec<f64> {
    (0..=200).map(|k| k as f64 * 1e-3).collect()
}

/// The event is located where the closed form puts it, at loose and tight tolerances, for
/// every method; the outputs stop at it and the system's last call is at the located time.
#[test]
fn every_method_locates_the_event_on_the_dense_output() {
    let t_star = std::f64::consts::PI / (3.0 * W);
    for rtol in [1e-3, 1e-6, 1e-9] {
        for method in methods(Options::default().rtol(rtol).atol(rtol * 1e-2)) {
            let mut system = Falling::new(f64::INFINITY);
            let t_out = output_times();
            let stopped = method
                .solve_dyn(&mut system, 0.0, &[1.0, 0.0], &t_out, &[], &mut ())
                .unwrap_err();
            let Interruption::Event { t } = stopped.reason else {
                panic!("{} at {rtol:e}: {:?}", method.name(), stopped.reason);
            };
            // The located time is the crossing of the integrated solution: it agrees with the
            // closed form to the integration error (the time error is the state error over
            // the speed |q'| = W sin(W t*)).
            // Generalized-alpha's local error control is of the second-order method's
            // third-order local error: its global error falls like rtol^(2/3).
            let speed = W * (W * t_star).sin();
            let global = if method.name() == "generalized_alpha" {
                rtol.powf(2.0 / 3.0)
            } else {
                rtol
            };
            let tolerance = 50.0 * global / speed + 1e-12;
            assert!(
                (t - t_star).abs() < tolerance,
                "{} at {rtol:e}: event at {t}, closed form {t_star}",
                method.name()
            );
            let (t_last_call, q_last_call) = system.last_event.unwrap();
            assert!((t_last_call - t).abs() <= 0.0, "{}", method.name());
            assert!(
                (q_last_call - 0.5).abs() < 1e-6,
                "{}: {q_last_call}",
                method.name()
            );
            let last = *stopped.solution.t.last().unwrap();
            assert!(last <= t && t - last < 1e-3 + 1e-15, "{}", method.name());
            // The outputs kept are all before the event (q > 1/2 there).
            for k in 0..stopped.solution.len() {
                assert!(stopped.solution.y(k)[0] >= 0.5 - 1e-9, "{}", method.name());
            }
            assert_eq!(stopped.last_time(), Some(t));
        }
    }
}

/// An excursion between two accepted steps is seen at the output times within the step
/// (the data written): with 10 ms steps and an event reached only from 14.5 to 15.5 ms, no
/// step end sees it, the output at 15 ms does, and the crossing at 14.5 ms is located.
#[test]
fn an_event_between_step_ends_is_found_at_the_outputs() {
    let options = Options::default()
        .rtol(1.0)
        .atol(1e30)
        .initial_step(0.01)
        .max_step(0.01);
    let mut system = Falling::new(f64::INFINITY);
    system.window = Some((0.015, 0.5e-3));
    let t_out = output_times();
    let stopped = GeneralizedAlpha::new(options)
        .solve_dyn(&mut system, 0.0, &[1.0, 0.0], &t_out, &[], &mut ())
        .unwrap_err();
    let Interruption::Event { t } = stopped.reason else {
        panic!("{:?}", stopped.reason);
    };
    let resolution = EVENT_RESOLUTION * 0.01;
    assert!((t - 0.0145).abs() <= 2.0 * resolution, "{t}");
    assert_eq!(stopped.solution.len(), 15, "outputs 0..=14 ms");
}

/// A failure met only in trial steps that were then rejected is forgotten once a step is
/// accepted, so it cannot be reported as the run's outcome: with the right-hand side failing
/// beyond `|q'| > 1.05 W` (which the exact solution never reaches, but trial steps of 0.1 s
/// do), every method runs to the end, and the system's record is empty.
#[test]
fn failures_of_rejected_trials_are_forgotten() {
    let options = Options::default().rtol(1e-4).atol(1e-7).initial_step(0.1);
    for method in methods(options) {
        if method.name().starts_with("magnus") {
            // The exponential method evaluates no right-hand side on trial states.
            continue;
        }
        let mut system = Falling::new(1.05);
        let t_out = output_times();
        // No event: the oscillator runs to the end.
        system.last_event = None;
        let mut no_event = NoEvent(&mut system);
        let solution = method
            .solve_dyn(&mut no_event, 0.0, &[1.0, 0.0], &t_out, &[], &mut ())
            .unwrap_or_else(|e| panic!("{}: {e}", method.name()));
        assert_eq!(solution.len(), t_out.len(), "{}", method.name());
        assert!(system.accepted > 0);
        assert!(system.failed > 0, "{}: no trial failed", method.name());
        assert_eq!(
            system.failure,
            None,
            "{}: a rejected trial's failure was kept",
            method.name()
        );
        let q = solution.y(t_out.len() - 1)[0];
        assert!((q - (W * 0.2).cos()).abs() < 1e-2, "{}: {q}", method.name());
    }
}

/// `Falling` without its event (forwards everything else).
struct NoEvent<'a>(&'a mut Falling);

impl OdeSystem for NoEvent<'_> {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        self.0.rhs(t, y, dy);
    }
    fn step_accepted(&mut self, t: f64, y: &[f64]) {
        self.0.step_accepted(t, y);
    }
    fn second_order_form(&mut self) -> Option<&mut dyn SecondOrderForm> {
        Some(self.0)
    }
}

/// `solve` (no observer) turns a reached event into an error naming its time.
#[test]
fn solve_reports_the_event_as_an_error_with_its_time() {
    use flexprr_integrators::Integrator;
    let mut system = Falling::new(f64::INFINITY);
    let e = flexprr_integrators::Rk45::new(Options::default().rtol(1e-8))
        .solve(&mut system, 0.0, &[1.0, 0.0], &output_times())
        .unwrap_err();
    let IntegratorError::TerminalEvent { t } = e else {
        panic!("{e}");
    };
    assert!((t - std::f64::consts::PI / (3.0 * W)).abs() < 1e-6);
    assert!(e.to_string().contains("terminal event"));
}

/// An event reached at the start ends the run there with the initial outputs only.
#[test]
fn an_event_at_the_start_ends_the_run_at_once() {
    let mut system = Falling::new(f64::INFINITY);
    let stopped = flexprr_integrators::Abm::new(Options::default())
        .solve_dyn(&mut system, 0.0, &[0.4, 0.0], &output_times(), &[], &mut ())
        .unwrap_err();
    assert!(matches!(stopped.reason, Interruption::Event { t } if t.abs() < 1e-300));
    assert_eq!(stopped.solution.len(), 1);
}

/// `q'' = -q` with its own stop times every `period` (a sampled controller's samples).
struct Sampled {
    period: f64,
    starts: usize,
}

impl OdeSystem for Sampled {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
        dy[0] = y[1];
        dy[1] = -y[0];
    }
    fn next_stop(&self, t: f64) -> Option<f64> {
        // The first multiple of the period beyond t (a time on a sample gives the next).
        let k = (t / self.period).floor() + 1.0;
        let next = k * self.period;
        Some(if next <= t * (1.0 + 1e-12) {
            next + self.period
        } else {
            next
        })
    }
    fn segment_start(&mut self, _t: f64, _y: &[f64]) {
        self.starts += 1;
    }
}

/// A system's own stop times are generated as the run goes: a period of 1 ms over 0.1 s
/// gives 100 segments, and a period of 1e-15 s (1e15 samples over a second, which a list
/// would never hold) runs into `max_steps` at once instead of allocating them.
#[test]
fn a_systems_stop_times_are_generated_as_the_run_goes() {
    use flexprr_integrators::Integrator;
    let mut system = Sampled {
        period: 1e-3,
        starts: 0,
    };
    let sol = flexprr_integrators::Rk45::new(Options::default().rtol(1e-10).atol(1e-12))
        .solve_observed(&mut system, 0.0, &[1.0, 0.0], &[0.1], &[0.05], &mut ())
        .unwrap();
    assert_eq!(sol.stats.segments, 100);
    assert_eq!(system.starts, 100);
    assert!((sol.y(0)[0] - 0.1_f64.cos()).abs() < 1e-9);
    let mut tiny = Sampled {
        period: 1e-15,
        starts: 0,
    };
    let e = flexprr_integrators::Abm::new(Options::default().max_steps(1000))
        .solve_observed(&mut tiny, 0.0, &[1.0, 0.0], &[1.0], &[], &mut ())
        .unwrap_err();
    assert!(
        matches!(e.reason, Interruption::Failed(IntegratorError::TooManySteps { t, .. }) if t < 1e-11),
        "{e}"
    );
}
