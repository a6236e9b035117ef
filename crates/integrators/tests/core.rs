//! Tests of the shared core: `Integrator::solve`, the differenced Jacobian, option
//! validation, the error norm and the automatic initial step.
//!
//! `solve` is checked with a stepper that advances the exact solution of `y' = -y` on a
//! fixed grid, so any error it shows comes from the plumbing, not from a method.

use faer::Mat;
use flexprr_integrators::test_problems::{
    ForcedOscillator, HarmonicOscillator, Mathieu, Robertson, StiffLinear, TestProblem, VanDerPol,
};
use flexprr_integrators::{
    Integrator, IntegratorError, OdeSystem, Options, Stats, Stepper, error_norm,
    finite_difference_jacobian, initial_step,
};

/// `y' = -y` (any dimension, components decay independently).
struct Decay {
    dim: usize,
}

impl OdeSystem for Decay {
    fn dim(&self) -> usize {
        self.dim
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
        for (d, v) in dy.iter_mut().zip(y) {
            *d = -v;
        }
    }
}

/// "Integrates" `y' = -y` exactly on a grid of fixed step `h`: `y(t) = exp(-(t - t0)) y0`.
struct ExactDecay {
    options: Options,
    h: f64,
}

struct ExactDecayStepper {
    h: f64,
    t0: f64,
    y0: Vec<f64>,
    t: f64,
    t_previous: f64,
    t_end: f64,
    y: Vec<f64>,
    stats: Stats,
}

impl ExactDecayStepper {
    fn exact(&self, t: f64, out: &mut [f64]) {
        let decay = (-(t - self.t0)).exp();
        for (o, v) in out.iter_mut().zip(&self.y0) {
            *o = decay * v;
        }
    }
}

impl Stepper for ExactDecayStepper {
    fn t(&self) -> f64 {
        self.t
    }
    fn y(&self) -> &[f64] {
        &self.y
    }
    fn t_previous(&self) -> f64 {
        self.t_previous
    }
    fn step<S: OdeSystem + ?Sized>(&mut self, _system: &mut S) -> Result<(), IntegratorError> {
        let dir = (self.t_end - self.t0).signum();
        let h = self.h * dir;
        self.t_previous = self.t;
        // Land on t_end, stretching the last step by up to 1% rather than leave a sliver.
        self.t = if (self.t + 1.01 * h - self.t_end) * dir >= 0.0 {
            self.t_end
        } else {
            self.t + h
        };
        let mut y = std::mem::take(&mut self.y);
        self.exact(self.t, &mut y);
        self.y = y;
        self.stats.accepted_steps += 1;
        Ok(())
    }
    fn interpolate(&self, t: f64, out: &mut [f64]) {
        self.exact(t, out);
    }
    fn stats(&self) -> &Stats {
        &self.stats
    }
}

impl Integrator for ExactDecay {
    type Stepper = ExactDecayStepper;
    fn name(&self) -> &'static str {
        "exact decay"
    }
    fn options(&self) -> &Options {
        &self.options
    }
    fn start<S: OdeSystem + ?Sized>(
        &self,
        _system: &mut S,
        t0: f64,
        y0: &[f64],
        t_end: f64,
    ) -> Result<ExactDecayStepper, IntegratorError> {
        Ok(ExactDecayStepper {
            h: self.h,
            t0,
            y0: y0.to_vec(),
            t: t0,
            t_previous: t0,
            t_end,
            y: y0.to_vec(),
            stats: Stats::default(),
        })
    }
}

fn exact_decay() -> ExactDecay {
    ExactDecay {
        options: Options::default(),
        h: 0.3,
    }
}

#[test]
fn solve_returns_y0_at_t0_and_the_exact_solution_elsewhere() {
    let y0 = [1.0, -2.0];
    let t_out = [0.0, 0.0, 0.1, 0.3, 0.45, 1.0, 2.2, 2.2, 3.0];
    let sol = exact_decay()
        .solve(&mut Decay { dim: 2 }, 0.0, &y0, &t_out)
        .unwrap();
    assert_eq!(sol.len(), t_out.len());
    assert_eq!(sol.dim, 2);
    // Outputs at t0 are y0 itself, bit for bit.
    for k in 0..2 {
        assert_eq!(sol.y(k)[0].to_bits(), y0[0].to_bits());
        assert_eq!(sol.y(k)[1].to_bits(), y0[1].to_bits());
    }
    for (k, &t) in t_out.iter().enumerate() {
        assert_eq!(sol.t[k].to_bits(), t.to_bits());
        for (y, y_start) in sol.y(k).iter().zip(y0) {
            let exact = y_start * (-t).exp();
            assert!((y - exact).abs() < 1e-15, "t = {t}");
        }
    }
    // 3.0 / 0.3 = 10 steps; the last lands on t_end.
    assert_eq!(sol.stats.accepted_steps, 10);
    let last = sol.last().unwrap();
    assert!((last[0] - (-3.0_f64).exp()).abs() < 1e-15);
}

#[test]
fn solve_integrates_backwards() {
    let y0 = [0.5];
    let t_out = [1.0, 0.7, -0.2, -1.0];
    let sol = exact_decay()
        .solve(&mut Decay { dim: 1 }, 1.0, &y0, &t_out)
        .unwrap();
    for (k, &t) in t_out.iter().enumerate() {
        let exact = 0.5 * (-(t - 1.0)).exp();
        assert!((sol.y(k)[0] - exact).abs() < 1e-14, "t = {t}");
    }
}

#[test]
fn solve_with_only_t0_requested_takes_no_step() {
    let sol = exact_decay()
        .solve(&mut Decay { dim: 1 }, 2.0, &[3.0], &[2.0])
        .unwrap();
    assert_eq!(sol.len(), 1);
    assert!((sol.y(0)[0] - 3.0).abs() < 1e-300);
    assert_eq!(sol.stats.accepted_steps, 0);
}

#[test]
fn solve_rejects_empty_unsorted_and_non_finite_output_times() {
    let m = exact_decay();
    let mut sys = Decay { dim: 1 };
    let cases: [(&[f64], &str); 4] = [
        (&[], "no output times"),
        (&[0.5, 0.2, 1.0], "t_out[1] = 0.2"),
        (&[-0.1, 1.0], "t_out[0] = -0.1"),
        (&[0.5, f64::NAN, 1.0], "t_out[1] = NaN"),
    ];
    for (t_out, expected) in cases {
        match m.solve(&mut sys, 0.0, &[1.0], t_out) {
            Err(IntegratorError::InvalidInput(msg)) => {
                assert!(
                    msg.contains(expected),
                    "{msg:?} should mention {expected:?}"
                )
            }
            other => panic!("{t_out:?}: expected InvalidInput, got {other:?}"),
        }
    }
    // Backwards: increasing times are the unsorted ones.
    assert!(matches!(
        m.solve(&mut sys, 0.0, &[1.0], &[-0.5, -0.2, -1.0]),
        Err(IntegratorError::InvalidInput(_))
    ));
}

/// The forward-difference Jacobian agrees with each fixture's closed form within its error
/// bound: rounding (about `sqrt(eps)` relative to the entries) plus the Taylor remainder
/// `M delta_j / 2`, with `M` a bound on the second derivatives of `f` and
/// `delta_j = sqrt(eps) max(|y_j|, 1)` (Dennis & Schnabel 5.4).
#[test]
fn finite_difference_jacobian_matches_analytic_jacobians() {
    fn check<P: TestProblem>(mut p: P, t: f64, y: &[f64], curvature: f64) {
        let n = p.dim();
        let mut exact = Mat::<f64>::zeros(n, n);
        p.jacobian(t, y, exact.as_mut());
        let mut f0 = vec![0.0; n];
        p.rhs(t, y, &mut f0);
        let mut fd = Mat::<f64>::zeros(n, n);
        let mut work = vec![0.0; 2 * n];
        finite_difference_jacobian(&mut p, t, y, &f0, fd.as_mut(), &mut work);
        let scale = (0..n)
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .map(|(i, j)| exact[(i, j)].abs())
            .fold(1.0_f64, f64::max);
        for i in 0..n {
            for j in 0..n {
                let delta = f64::EPSILON.sqrt() * y[j].abs().max(1.0);
                assert!(
                    (fd[(i, j)] - exact[(i, j)]).abs() <= 1e-6 * scale + 0.5 * curvature * delta,
                    "{}: J[{i},{j}] differenced {} vs exact {}",
                    p.name(),
                    fd[(i, j)],
                    exact[(i, j)]
                );
            }
        }
        // The work vector holds no stale perturbation: y is untouched and f0 reproducible.
        let mut f_again = vec![0.0; n];
        p.rhs(t, y, &mut f_again);
        assert_eq!(f0, f_again);
    }
    // Linear problems: no truncation error.
    check(HarmonicOscillator::default(), 0.2, &[0.3, -1.1], 0.0);
    check(ForcedOscillator::default(), 1.2, &[0.3, -1.1], 0.0);
    check(Mathieu::default(), 0.7, &[0.3, -1.1], 0.0);
    check(StiffLinear::default(), 0.0, &[1.0, -0.5], 0.0);
    // Van der Pol: |d2 f2 / dy1^2| = |2 y2| / eps, |d2 f2 / dy1 dy2| = |2 y1| / eps.
    check(VanDerPol::default(), 0.0, &[2.0, -0.4], 4.0 / 0.003);
    check(VanDerPol::with_mu(10.0), 0.0, &[-1.3, 0.8], 2.6 * 100.0);
    // Robertson: |d2 f2 / dy2^2| = 6e7 dominates; with y2 = 2e-5 the truncation error of
    // J[1][1] is 3e7 delta, about 0.45 of 1700.
    check(Robertson::default(), 0.0, &[0.95, 2e-5, 0.05], 6e7);
}

/// A system that does not override `jacobian` gets the provided differenced one, which
/// costs `dim + 1` evaluations; analytic fixtures report zero.
#[test]
fn provided_jacobian_is_differenced_and_counted() {
    struct Counting {
        calls: usize,
    }
    impl OdeSystem for Counting {
        fn dim(&self) -> usize {
            3
        }
        fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
            self.calls += 1;
            // f = (y0 y1, sin y2, y0^2): J = [[y1, y0, 0], [0, 0, cos y2], [2 y0, 0, 0]].
            dy[0] = y[0] * y[1];
            dy[1] = y[2].sin();
            dy[2] = y[0] * y[0];
        }
    }
    let mut sys = Counting { calls: 0 };
    assert!(!sys.has_analytic_jacobian());
    assert_eq!(sys.jacobian_rhs_evaluations(), 4);
    let y = [0.7, -1.2, 0.4];
    let mut jac = Mat::<f64>::zeros(3, 3);
    sys.jacobian(0.0, &y, jac.as_mut());
    assert_eq!(sys.calls, 4);
    let exact = [
        [y[1], y[0], 0.0],
        [0.0, 0.0, y[2].cos()],
        [2.0 * y[0], 0.0, 0.0],
    ];
    for i in 0..3 {
        for j in 0..3 {
            assert!((jac[(i, j)] - exact[i][j]).abs() < 1e-7, "J[{i},{j}]");
        }
    }
    assert_eq!(VanDerPol::default().jacobian_rhs_evaluations(), 0);
}

#[test]
fn options_validate_names_the_offending_option() {
    let dim = 2;
    assert!(Options::default().validate(dim).is_ok());
    let cases: Vec<(Options, &str)> = vec![
        (Options::default().rtol(-1e-6), "rtol must be positive"),
        (Options::default().rtol(f64::NAN), "rtol must be positive"),
        (
            Options::default().rtol(1e-17),
            "below what double precision",
        ),
        (Options::default().atol(-1.0), "atol must be non-negative"),
        (
            Options::default().atol(f64::INFINITY),
            "atol must be non-negative",
        ),
        (
            Options::default().atol_per_component(vec![1e-9; 3]),
            "atol has 3 components but the system has 2",
        ),
        (
            Options::default().atol_per_component(vec![1e-9, f64::NAN]),
            "atol[1] must be non-negative",
        ),
        (
            Options::default().initial_step(0.0),
            "initial_step must be positive",
        ),
        (
            Options::default().initial_step(-1e-3),
            "initial_step must be positive",
        ),
        (
            Options::default().max_step(0.0),
            "max_step must be positive",
        ),
        (
            Options::default().max_step(f64::NAN),
            "max_step must be positive",
        ),
        (
            Options::default().max_steps(0),
            "max_steps must be at least 1",
        ),
    ];
    for (opts, expected) in cases {
        match opts.validate(dim) {
            Err(IntegratorError::InvalidOptions(msg)) => {
                assert!(
                    msg.contains(expected),
                    "{msg:?} should contain {expected:?}"
                );
                // The Display form says what kind of error it is.
                let shown = IntegratorError::InvalidOptions(msg).to_string();
                assert!(shown.starts_with("invalid integrator option"), "{shown}");
            }
            other => panic!("{opts:?}: expected InvalidOptions, got {other:?}"),
        }
    }
    assert!(
        Options::default()
            .atol_per_component(vec![0.0, 1e-9])
            .validate(dim)
            .is_ok()
    );
}

/// The weighted RMS norm of Hairer-Norsett-Wanner I, eq. II.4.11: an error that is the same
/// multiple `c` of every component's scale has norm `c`; `(3, 4)` scales give
/// `sqrt((9 + 16) / 2)`.
#[test]
fn error_norm_is_the_weighted_rms() {
    let opts = Options::default()
        .rtol(1e-3)
        .atol_per_component(vec![1e-6, 1e-4]);
    let y = [2.0, -0.5];
    let y_new = [-1.0, 3.0];
    // Scales use the larger of |y| and |y_new|: 1e-6 + 2e-3 and 1e-4 + 3e-3.
    let scale = [1e-6 + 1e-3 * 2.0, 1e-4 + 1e-3 * 3.0];
    let err = [0.5 * scale[0], -0.5 * scale[1]];
    assert!((error_norm(&err, &y, &y_new, &opts) - 0.5).abs() < 1e-15);
    let err = [3.0 * scale[0], 4.0 * scale[1]];
    let expected = (25.0_f64 / 2.0).sqrt();
    assert!((error_norm(&err, &y, &y_new, &opts) - expected).abs() < 1e-14);
    // Symmetric in y and y_new.
    assert!(
        (error_norm(&err, &y_new, &y, &opts) - expected).abs() < 1e-14,
        "swapping y and y_new changes the norm"
    );
    // Zero error, zero norm.
    assert!(error_norm(&[0.0, 0.0], &y, &y_new, &opts).abs() < 1e-300);
}

/// Hairer's starting step (HNW I, II.4) on `y' = lambda y`, `y0 = 1`, evaluated by hand:
/// with `sk = atol + rtol`, `d0 = 1/sk`, `d1 = |lambda|/sk`, the Euler probe gives
/// `d2 = lambda^2 / sk`, so `h0 = 0.01 d0/d1 = 0.01/|lambda|` and
/// `h = min(100 h0, (0.01 / max(d1, d2))^(1/(p+1)), h_max)`. The step follows the time
/// scale `1/|lambda|` of the problem.
#[test]
fn initial_step_follows_the_time_scale_of_exponential_growth_and_decay() {
    struct Exponential {
        lambda: f64,
    }
    impl OdeSystem for Exponential {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
            dy[0] = self.lambda * y[0];
        }
    }
    let (rtol, atol) = (1e-6, 1e-9);
    let opts = Options::default().rtol(rtol).atol(atol);
    let sk = atol + rtol;
    let order = 5;
    for lambda in [-1e4, -30.0, -1.0, 0.5, 2.0, 1e3] {
        for direction in [1.0, -1.0] {
            let mut sys = Exponential { lambda };
            let f0 = [lambda];
            let mut work = [0.0; 2];
            let h = initial_step(
                &mut sys,
                0.0,
                &[1.0],
                &f0,
                order,
                direction,
                f64::INFINITY,
                &opts,
                &mut work,
            );
            let d1 = lambda.abs() / sk;
            let d2 = lambda * lambda / sk;
            let expected =
                (1.0 / lambda.abs()).min((0.01 / d1.max(d2)).powf(1.0 / (order as f64 + 1.0)));
            assert!(
                (h - expected).abs() <= 1e-12 * expected,
                "lambda = {lambda}, direction {direction}: h = {h}, expected {expected}"
            );
            // Capped by h_max.
            let capped = initial_step(
                &mut sys,
                0.0,
                &[1.0],
                &f0,
                order,
                direction,
                1e-7,
                &opts,
                &mut work,
            );
            assert!(capped <= 1e-7 && capped > 0.0);
        }
    }
    // At rest (y0 = 0, f0 = 0) there is no scale: Hairer's fallback 1e-6.
    let mut rest = Exponential { lambda: -1.0 };
    let mut work = [0.0; 2];
    let h = initial_step(
        &mut rest,
        0.0,
        &[0.0],
        &[0.0],
        order,
        1.0,
        f64::INFINITY,
        &opts,
        &mut work,
    );
    assert!((h - 1e-6).abs() < 1e-18, "h = {h}");
}
