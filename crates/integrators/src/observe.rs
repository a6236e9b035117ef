//! The one stepping loop: outputs by dense output, observers, stop times (breakpoints), and
//! the object-safe adapter [`DynIntegrator`].
//!
//! Every integration in this crate runs through [`drive`], reached from
//! [`Integrator::solve_observed`] (and from [`Integrator::solve`], which calls it without
//! stops or observer).
//!
//! Stop times follow the advice of Hairer, Norsett & Wanner (*Solving ODEs I*, 2nd ed.,
//! II.6, "Discontinuities") and Shampine & Gordon (1975, ch. 10): a multistep or embedded
//! Runge-Kutta method must not integrate across a point where the right-hand side (or one of
//! its low derivatives) is not smooth; the integration is stopped exactly there and restarted
//! as a new initial value problem. This also keeps the step-size controller from stepping
//! over a forcing that is exactly zero at first and starts later: a fresh start at the
//! switching time chooses a small initial step from the local derivatives.

use std::fmt;

use crate::{Integrator, IntegratorError, OdeSystem, Options, Solution, Stats, Stepper};

/// What an observer tells the stepping loop after each call.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flow {
    /// Go on integrating.
    Continue,
    /// End the integration now; the solve returns [`Interruption::Stopped`].
    Stop,
}

/// Sees every accepted step and every output sample; can stop the run.
///
/// Both methods default to [`Flow::Continue`]; `()` is the observer that watches nothing.
/// Within one accepted step the outputs it covers are reported first (in order), then the
/// step itself. An observer must not allocate per call if the caller cares about an
/// allocation-free loop.
///
/// ```
/// use flexprr_integrators::{Flow, Integrator, Interruption, Observer, OdeSystem, Options, Rk45};
///
/// /// Counts accepted steps and stops once the first state component turns negative.
/// #[derive(Default)]
/// struct UntilNegative {
///     steps: usize,
/// }
/// impl Observer for UntilNegative {
///     fn on_step(&mut self, _t: f64, y: &[f64]) -> Flow {
///         self.steps += 1;
///         if y[0] < 0.0 { Flow::Stop } else { Flow::Continue }
///     }
/// }
///
/// /// y'' = -y, starting at y = 1: y = cos t turns negative after t = pi/2.
/// struct Oscillator;
/// impl OdeSystem for Oscillator {
///     fn dim(&self) -> usize { 2 }
///     fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
///         dy[0] = y[1];
///         dy[1] = -y[0];
///     }
/// }
///
/// let t_out: Vec<f64> = (0..=40).map(|k| 0.1 * k as f64).collect();
/// let mut observer = UntilNegative::default();
/// let rk45 = Rk45::new(Options::default().rtol(1e-8).atol(1e-10));
/// let stopped = rk45
///     .solve_observed(&mut Oscillator, 0.0, &[1.0, 0.0], &t_out, &[], &mut observer)
///     .unwrap_err();
/// let Interruption::Stopped { t } = stopped.reason else { panic!("not stopped") };
/// assert!(t > std::f64::consts::FRAC_PI_2 && t < 4.0);
/// // Every output up to the stop time is there, and none after it.
/// let last = *stopped.solution.t.last().unwrap();
/// assert!(last <= t && t - last < 0.1 + 1e-12);
/// assert!(observer.steps > 0);
/// ```
pub trait Observer {
    /// Called after every accepted step with the new time and state.
    fn on_step(&mut self, t: f64, y: &[f64]) -> Flow {
        let _ = (t, y);
        Flow::Continue
    }
    /// Called for every output sample, with its index in `t_out`.
    fn on_output(&mut self, index: usize, t: f64, y: &[f64]) -> Flow {
        let _ = (index, t, y);
        Flow::Continue
    }
}

impl Observer for () {}

impl<O: Observer + ?Sized> Observer for &mut O {
    fn on_step(&mut self, t: f64, y: &[f64]) -> Flow {
        (**self).on_step(t, y)
    }
    fn on_output(&mut self, index: usize, t: f64, y: &[f64]) -> Flow {
        (**self).on_output(index, t, y)
    }
}

/// An observer made of a closure called after every accepted step (for progress reports).
///
/// ```
/// use flexprr_integrators::{Flow, Integrator, OdeSystem, OnStep, Options, Rk45};
///
/// struct Decay;
/// impl OdeSystem for Decay {
///     fn dim(&self) -> usize { 1 }
///     fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) { dy[0] = -y[0]; }
/// }
/// let mut reached = 0.0;
/// let mut progress = OnStep(|t: f64, _y: &[f64]| {
///     reached = t;
///     Flow::Continue
/// });
/// Rk45::new(Options::default())
///     .solve_observed(&mut Decay, 0.0, &[1.0], &[2.0], &[], &mut progress)
///     .unwrap();
/// assert!((reached - 2.0_f64).abs() < 1e-15);
/// ```
pub struct OnStep<F>(pub F);

impl<F: FnMut(f64, &[f64]) -> Flow> Observer for OnStep<F> {
    fn on_step(&mut self, t: f64, y: &[f64]) -> Flow {
        (self.0)(t, y)
    }
}

/// Why a solve ended early, with every output computed up to the last accepted time.
#[derive(Debug, Clone)]
pub struct Interrupted {
    /// The outputs whose times are at most the last accepted time (by dense output, never
    /// extrapolated), and the work statistics so far.
    pub solution: Solution,
    /// Why the integration ended.
    pub reason: Interruption,
}

/// Why an integration ended before its last output time.
#[derive(Debug, Clone)]
pub enum Interruption {
    /// The method or the input failed.
    Failed(IntegratorError),
    /// An [`Observer`] returned [`Flow::Stop`]; `t` is the time it was called with.
    Stopped {
        /// Time at which the observer stopped the run.
        t: f64,
    },
    /// The system's terminal event ([`OdeSystem::terminal_event`]) was reached on an
    /// accepted step or its dense output; `t` is the located time of its first crossing.
    Event {
        /// Time of the event.
        t: f64,
    },
}

impl Interrupted {
    /// The time the integration reached: the observer's time for [`Interruption::Stopped`],
    /// the time carried by the error for [`Interruption::Failed`] (for input and option
    /// errors, which carry none, the last output time, or `None` when there is no output).
    pub fn last_time(&self) -> Option<f64> {
        match &self.reason {
            Interruption::Stopped { t } | Interruption::Event { t } => Some(*t),
            Interruption::Failed(e) => e.time().or_else(|| self.solution.t.last().copied()),
        }
    }

    /// The integrator error, if the run failed (rather than being stopped).
    pub fn error(&self) -> Option<&IntegratorError> {
        match &self.reason {
            Interruption::Failed(e) => Some(e),
            Interruption::Stopped { .. } | Interruption::Event { .. } => None,
        }
    }

    /// The reason as an [`IntegratorError`], for callers that have no observer and treat
    /// every early end as an error ([`Integrator::solve`]).
    pub fn into_error(self) -> IntegratorError {
        match self.reason {
            Interruption::Failed(e) => e,
            Interruption::Event { t } => IntegratorError::TerminalEvent { t },
            // The `()` observer never stops; say so rather than panic if another one did.
            Interruption::Stopped { t } => IntegratorError::InvalidInput(format!(
                "the run was stopped at t = {t} s by an observer"
            )),
        }
    }
}

impl fmt::Display for Interrupted {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.reason {
            Interruption::Failed(e) => write!(f, "{e}")?,
            Interruption::Stopped { t } => write!(f, "stopped by the observer at t = {t} s")?,
            Interruption::Event { t } => write!(f, "terminal event at t = {t} s")?,
        }
        match self.solution.t.last() {
            Some(t) => write!(
                f,
                " ({} outputs kept, up to t = {t} s)",
                self.solution.len()
            ),
            None => write!(f, " (no output kept)"),
        }
    }
}

impl std::error::Error for Interrupted {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match &self.reason {
            Interruption::Failed(e) => Some(e),
            Interruption::Stopped { .. } | Interruption::Event { .. } => None,
        }
    }
}

/// The resolution of event location, relative to the length of the step in which the event
/// is found (the bisection also stops at a few ulps of `t`).
pub const EVENT_RESOLUTION: f64 = 1e-9;

/// Whether `a` and `b` are the same number (bit for bit).
fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits()
}

/// Whether a terminal event value counts as reached: not negative (NaN included).
fn reached(g: Option<f64>) -> bool {
    g.is_some_and(|g| g >= 0.0 || g.is_nan())
}

/// The first time in `(lo, hi]` at which the terminal event is reached, by bisection on the
/// dense output of the last accepted step (`g` is not reached at `lo`, reached at `hi`),
/// to [`EVENT_RESOLUTION`] of the step `step`; the system's last call is at the returned time
/// with its state, which is left in `buf`.
fn locate_event<T: Stepper, S: OdeSystem + ?Sized>(
    stepper: &T,
    system: &mut S,
    mut lo: f64,
    mut hi: f64,
    step: f64,
    buf: &mut [f64],
) -> f64 {
    let resolution = (EVENT_RESOLUTION * step.abs()).max(4.0 * f64::EPSILON * hi.abs());
    let state_at = |t: f64, buf: &mut [f64]| {
        if same(t, stepper.t()) {
            buf.copy_from_slice(stepper.y());
        } else {
            stepper.interpolate(t, buf);
        }
    };
    while (hi - lo).abs() > resolution {
        let mid = 0.5 * (lo + hi);
        if same(mid, lo) || same(mid, hi) {
            break;
        }
        state_at(mid, buf);
        if reached(system.terminal_event(mid, buf)) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    state_at(hi, buf);
    system.terminal_event(hi, buf);
    hi
}

/// Whether `a` and `b` are distinguishable as the ends of an integration (the criterion of
/// [`crate::validate_start`]).
fn distinct(a: f64, b: f64) -> bool {
    (a - b).abs() > 16.0 * f64::EPSILON * a.abs().max(b.abs())
}

/// The stop times strictly inside `(t0, t_end)`, sorted in the direction of integration, with
/// duplicates (and times indistinguishable from a neighbour or an end) removed.
fn interior_stops(t0: f64, t_end: f64, stops: &[f64]) -> Result<Vec<f64>, IntegratorError> {
    if let Some(k) = stops.iter().position(|s| !s.is_finite()) {
        return Err(IntegratorError::InvalidInput(format!(
            "stop time stops[{k}] = {} is not finite",
            stops[k]
        )));
    }
    let dir = (t_end - t0).signum();
    let mut inside: Vec<f64> = stops
        .iter()
        .copied()
        .filter(|&s| (s - t0) * dir > 0.0 && (t_end - s) * dir > 0.0)
        .filter(|&s| distinct(s, t0) && distinct(s, t_end))
        .collect();
    inside.sort_by(|a, b| (dir * a).total_cmp(&(dir * b)));
    inside.dedup_by(|later, earlier| !distinct(*later, *earlier));
    Ok(inside)
}

/// The end of the segment that starts at `t_start`: the first of the listed stops (sorted,
/// `next` the first not yet passed), the system's own next stop ([`OdeSystem::next_stop`],
/// forwards in time only) and `t_end`, ignoring times indistinguishable from the start or
/// from an earlier candidate.
fn next_stop<S: OdeSystem + ?Sized>(
    system: &S,
    stops: &[f64],
    next: &mut usize,
    t_start: f64,
    t_end: f64,
) -> f64 {
    let dir = (t_end - t_start).signum();
    while *next < stops.len()
        && ((stops[*next] - t_start) * dir <= 0.0 || !distinct(stops[*next], t_start))
    {
        *next += 1;
    }
    let listed = stops.get(*next).copied().unwrap_or(t_end);
    if dir > 0.0 {
        if let Some(own) = system.next_stop(t_start) {
            if own > t_start && own < listed && distinct(own, t_start) && distinct(own, listed) {
                return own;
            }
        }
    }
    listed
}

/// The stepping loop behind [`Integrator::solve_observed`] (see there).
#[allow(
    clippy::result_large_err,
    reason = "the error carries the partial solution, as large as the Ok value; returned once per run"
)]
pub(crate) fn drive<I: Integrator + ?Sized, S: OdeSystem + ?Sized>(
    integrator: &I,
    system: &mut S,
    t0: f64,
    y0: &[f64],
    t_out: &[f64],
    stops: &[f64],
    observer: &mut dyn Observer,
) -> Result<Solution, Interrupted> {
    let n = y0.len();
    let mut solution = Solution::with_capacity(n, t_out.len());
    let fail = |solution: Solution, e: IntegratorError| Interrupted {
        solution,
        reason: Interruption::Failed(e),
    };
    let Some(&t_end) = t_out.last() else {
        let e = IntegratorError::InvalidInput("no output times requested".to_string());
        return Err(fail(solution, e));
    };
    if !t0.is_finite() {
        let e = IntegratorError::InvalidInput(format!("t0 = {t0} is not finite"));
        return Err(fail(solution, e));
    }
    let dir = (t_end - t0).signum();
    let mut prev = t0;
    for (k, &t) in t_out.iter().enumerate() {
        if !t.is_finite() || (t - prev) * dir < 0.0 {
            let e = IntegratorError::InvalidInput(format!(
                "output time t_out[{k}] = {t} is not monotone from t0 = {t0} towards {t_end}"
            ));
            return Err(fail(solution, e));
        }
        prev = t;
    }
    let stops = match interior_stops(t0, t_end, stops) {
        Ok(s) => s,
        Err(e) => return Err(fail(solution, e)),
    };
    let stopped = |solution: Solution, t: f64| Interrupted {
        solution,
        reason: Interruption::Stopped { t },
    };

    let event = |solution: Solution, t: f64| Interrupted {
        solution,
        reason: Interruption::Event { t },
    };

    // Leading outputs at t0 need no step (and t_end == t0 is not an integration).
    let mut k = 0;
    while k < t_out.len() && (t_out[k] - t0) * dir <= 0.0 {
        solution.push(t_out[k], y0);
        if observer.on_output(k, t_out[k], y0) == Flow::Stop {
            return Err(stopped(solution, t_out[k]));
        }
        k += 1;
    }
    if k == t_out.len() {
        return Ok(solution);
    }
    // The terminal event at the start: a system that has one is checked from here on.
    let start_event = system.terminal_event(t0, y0);
    if reached(start_event) {
        return Err(event(solution, t0));
    }
    let has_event = start_event.is_some();

    let max_steps = integrator.options().max_steps;
    let mut total = Stats::default();
    let mut buf = vec![0.0; n];
    let mut t_start = t0;
    let mut y_start = y0.to_vec();
    let mut next_listed = 0;
    while (t_end - t_start) * dir > 0.0 {
        let t_stop = next_stop(system, &stops, &mut next_listed, t_start, t_end);
        system.segment_start(t_start, &y_start);
        let mut stepper = match integrator.start(system, t_start, &y_start, t_stop) {
            Ok(s) => s,
            Err(e) => {
                solution.stats = total;
                return Err(fail(solution, e));
            }
        };
        total.segments += 1;
        let used = total.accepted_steps + total.rejected_steps;
        while (t_stop - stepper.t()) * dir > 0.0 {
            let s = stepper.stats();
            let result = if used + s.accepted_steps + s.rejected_steps >= max_steps {
                Err(IntegratorError::TooManySteps {
                    t: stepper.t(),
                    max_steps,
                })
            } else {
                stepper.step(system)
            };
            if let Err(e) = result {
                total.accumulate(stepper.stats());
                solution.stats = total;
                return Err(fail(solution, e));
            }
            let t_now = stepper.t();
            system.step_accepted(t_now, stepper.y());
            // The terminal event is checked on the accepted step in time order: at each
            // output time within it (before that output is kept), then at its end.
            let step = t_now - stepper.t_previous();
            let mut not_reached = stepper.t_previous();
            while k < t_out.len() && (t_out[k] - t_now) * dir <= 0.0 {
                if (t_out[k] - t_now).abs() <= f64::EPSILON * t_now.abs().max(1.0) {
                    buf.copy_from_slice(stepper.y());
                } else {
                    stepper.interpolate(t_out[k], &mut buf);
                }
                if has_event && reached(system.terminal_event(t_out[k], &buf)) {
                    let t_event =
                        locate_event(&stepper, system, not_reached, t_out[k], step, &mut buf);
                    if same(t_event, t_out[k]) {
                        solution.push(t_out[k], &buf);
                    }
                    total.accumulate(stepper.stats());
                    solution.stats = total;
                    return Err(event(solution, t_event));
                }
                not_reached = t_out[k];
                solution.push(t_out[k], &buf);
                if observer.on_output(k, t_out[k], &buf) == Flow::Stop {
                    total.accumulate(stepper.stats());
                    solution.stats = total;
                    return Err(stopped(solution, t_out[k]));
                }
                k += 1;
            }
            if has_event
                && !same(not_reached, t_now)
                && reached(system.terminal_event(t_now, stepper.y()))
            {
                let t_event = locate_event(&stepper, system, not_reached, t_now, step, &mut buf);
                total.accumulate(stepper.stats());
                solution.stats = total;
                return Err(event(solution, t_event));
            }
            if observer.on_step(t_now, stepper.y()) == Flow::Stop {
                total.accumulate(stepper.stats());
                solution.stats = total;
                return Err(stopped(solution, t_now));
            }
        }
        total.accumulate(stepper.stats());
        t_start = t_stop;
        y_start.copy_from_slice(stepper.y());
    }
    solution.stats = total;
    Ok(solution)
}

/// The object-safe face of an [`Integrator`], so methods can be chosen at run time
/// (`Box<dyn DynIntegrator>`). Every `Integrator + Send + Sync` is one.
///
/// Implementing it by hand (rather than through [`Integrator`]) is possible, e.g. to wrap
/// another integrator:
///
/// ```
/// use flexprr_integrators::{
///     DynIntegrator, Integrator, Interrupted, Observer, OdeSystem, Options, Rk45, Solution,
/// };
///
/// /// Integrates with RK45 but always also stops at t = 1.
/// struct StopAtOne(Rk45);
/// impl DynIntegrator for StopAtOne {
///     fn name(&self) -> &str { "rk45 (stop at 1)" }
///     fn options(&self) -> &Options { Integrator::options(&self.0) }
///     fn solve_dyn(
///         &self,
///         system: &mut dyn OdeSystem,
///         t0: f64,
///         y0: &[f64],
///         t_out: &[f64],
///         stops: &[f64],
///         observer: &mut dyn Observer,
///     ) -> Result<Solution, Interrupted> {
///         let mut all = stops.to_vec();
///         all.push(1.0);
///         self.0.solve_dyn(system, t0, y0, t_out, &all, observer)
///     }
/// }
///
/// struct Decay;
/// impl OdeSystem for Decay {
///     fn dim(&self) -> usize { 1 }
///     fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) { dy[0] = -y[0]; }
/// }
///
/// let methods: Vec<Box<dyn DynIntegrator>> = vec![
///     Box::new(Rk45::new(Options::default().rtol(1e-8))),
///     Box::new(StopAtOne(Rk45::new(Options::default().rtol(1e-8)))),
/// ];
/// for m in &methods {
///     let sol = m.solve_dyn(&mut Decay, 0.0, &[1.0], &[2.0], &[], &mut ()).unwrap();
///     assert!((sol.y(0)[0] - (-2.0_f64).exp()).abs() < 1e-7, "{}", m.name());
/// }
/// ```
#[allow(
    clippy::result_large_err,
    reason = "the error carries the partial solution, as large as the Ok value; returned once per run"
)]
pub trait DynIntegrator: Send + Sync {
    /// Short name of the method.
    fn name(&self) -> &str;
    /// The shared options.
    fn options(&self) -> &Options;
    /// As [`Integrator::solve_observed`], for a system behind `dyn`.
    ///
    /// # Errors
    /// As [`Integrator::solve_observed`].
    fn solve_dyn(
        &self,
        system: &mut dyn OdeSystem,
        t0: f64,
        y0: &[f64],
        t_out: &[f64],
        stops: &[f64],
        observer: &mut dyn Observer,
    ) -> Result<Solution, Interrupted>;
}

impl<I: Integrator + Send + Sync> DynIntegrator for I {
    fn name(&self) -> &str {
        Integrator::name(self)
    }
    fn options(&self) -> &Options {
        Integrator::options(self)
    }
    fn solve_dyn(
        &self,
        system: &mut dyn OdeSystem,
        t0: f64,
        y0: &[f64],
        t_out: &[f64],
        stops: &[f64],
        observer: &mut dyn Observer,
    ) -> Result<Solution, Interrupted> {
        self.solve_observed(system, t0, y0, t_out, stops, observer)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stops_are_filtered_sorted_and_deduplicated() {
        let s =
            interior_stops(0.0, 1.0, &[0.5, -1.0, 0.2, 0.5, 1.0, 0.0, 2.0, 0.2 + 1e-18]).unwrap();
        assert_eq!(s.len(), 2);
        assert!((s[0] - 0.2).abs() < 1e-15 && (s[1] - 0.5).abs() < 1e-15);
        // Backwards in time: sorted downwards.
        let s = interior_stops(1.0, 0.0, &[0.2, 0.7, 0.5]).unwrap();
        assert!(s[0] > s[1] && s[1] > s[2]);
        assert!(matches!(
            interior_stops(0.0, 1.0, &[0.5, f64::NAN]),
            Err(IntegratorError::InvalidInput(m)) if m.contains("stops[1]")
        ));
    }
}
