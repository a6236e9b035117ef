//! Time integrators for first-order ODE systems `y' = f(t, y)`.
//!
//! This crate knows nothing of manipulators: it sees only the [`OdeSystem`] trait.
//! Three families are provided behind one interface, [`Integrator`]:
//!
//! * [`Rk45`]: Dormand-Prince 5(4) with PI step control, 4th-order dense output and
//!   Hairer's stiffness detection ([`StiffnessDetection`]) (Hairer, Norsett & Wanner,
//!   *Solving ODEs I*, 2nd ed., II.4-II.6, and Hairer & Wanner II, IV.2; the code DOPRI5).
//! * [`Abm`]: variable-step, variable-order Adams-Bashforth-Moulton PECE, orders 1-12, in the
//!   spirit of Shampine & Gordon, *Computer Solution of ODEs* (1975) (the code DE/STEP, and
//!   MATLAB's `ode113`).
//! * [`Bdf`]: variable-step, variable-order BDF, orders 1-5, with simplified Newton iterations
//!   and Jacobian/LU reuse, after CVODE (Hindmarsh et al., *ACM TOMS* 31, 2005) and Byrne &
//!   Hindmarsh (1975).
//! * [`GeneralizedAlpha`]: the generalized-alpha method of Chung & Hulbert (1993) for
//!   mechanical systems `M q'' = F` ([`SecondOrderForm`]), second order with controllable
//!   high-frequency dissipation, modified Newton on the `n x n` iteration matrix
//!   `M + c_C C + c_K K`, local error control and Hermite dense output.
//!
//! A new method is a new file: implement [`Stepper`] for its state and [`Integrator`] for
//! its configuration; [`Integrator::solve`] (dense output at requested times) comes free.
//!
//! ```
//! use flexprr_integrators::{Integrator, OdeSystem, Options, Rk45};
//!
//! /// y'' = -y as a first-order system.
//! struct Oscillator;
//! impl OdeSystem for Oscillator {
//!     fn dim(&self) -> usize { 2 }
//!     fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) {
//!         dy[0] = y[1];
//!         dy[1] = -y[0];
//!     }
//! }
//!
//! let opts = Options::default().rtol(1e-9).atol(1e-12);
//! let sol = Rk45::new(opts).solve(&mut Oscillator, 0.0, &[1.0, 0.0], &[1.0, 2.0]).unwrap();
//! assert!((sol.y(1)[0] - 2.0_f64.cos()).abs() < 1e-7);
//! ```

mod common;
mod error;
mod options;
mod solution;
mod system;

mod observe;

pub mod abm;
pub mod bdf;
pub mod exponential;
pub mod genalpha;
pub mod rk45;
pub mod structured;
#[cfg(feature = "test-problems")]
pub mod test_problems;

pub use abm::Abm;
pub use bdf::Bdf;
pub use common::{error_norm, initial_step, validate_start};
pub use error::IntegratorError;
pub use exponential::{
    Auto, BlockOperators, LinearSecondOrder, Magnus, MagnusOrder, MagnusStepper,
};
pub use genalpha::{GeneralizedAlpha, GeneralizedAlphaStepper};
pub use observe::{
    DynIntegrator, EVENT_RESOLUTION, Flow, Interrupted, Interruption, Observer, OnStep,
};
pub use options::{Options, Tolerance};
pub use rk45::{Rk45, Rk45Stepper, StiffnessDetection};
pub use solution::{Solution, Stats};
pub use structured::BlockBanded;
pub use system::{OdeSystem, SecondOrderForm, finite_difference_jacobian};

/// An integration in progress: the method's state between steps.
///
/// The system is passed to every call instead of being owned, so one system value can be
/// integrated several times and inspected in between. A stepper never steps past the
/// `t_end` it was started with: the last step lands on it exactly (the right-hand side may
/// not be defined beyond it, e.g. a trajectory that ends there).
pub trait Stepper {
    /// Time of the current state.
    fn t(&self) -> f64;
    /// The current state.
    fn y(&self) -> &[f64];
    /// Start of the last accepted step; dense output is valid on `[t_previous, t]`.
    fn t_previous(&self) -> f64;
    /// Takes one accepted step (rejected attempts are retried inside).
    ///
    /// # Errors
    /// Step size below the floor, too many steps, a non-finite state or derivative, or
    /// repeated Newton failures; each carries the time at which it happened.
    fn step<S: OdeSystem + ?Sized>(&mut self, system: &mut S) -> Result<(), IntegratorError>;
    /// Dense output: writes the state at `t` (within the last accepted step) into `out`.
    fn interpolate(&self, t: f64, out: &mut [f64]);
    /// Statistics so far.
    fn stats(&self) -> &Stats;
}

/// A configured integration method.
///
/// Implementing [`Integrator::start`] (and [`Stepper`] for the state it returns) is all a
/// method needs; [`Integrator::solve`] and [`Integrator::solve_observed`] come with it. For
/// example the explicit Euler method `y_{n+1} = y_n + h f(t_n, y_n)` (Hairer, Norsett &
/// Wanner I, I.7) with a fixed step and linear dense output:
///
/// ```
/// use flexprr_integrators::{
///     validate_start, Integrator, IntegratorError, OdeSystem, Options, Stats, Stepper,
/// };
///
/// struct Euler { options: Options, h: f64 }
/// struct EulerState { t: f64, t_prev: f64, t_end: f64, h: f64, y: Vec<f64>, y_prev: Vec<f64>, f: Vec<f64>, stats: Stats }
///
/// impl Stepper for EulerState {
///     fn t(&self) -> f64 { self.t }
///     fn y(&self) -> &[f64] { &self.y }
///     fn t_previous(&self) -> f64 { self.t_prev }
///     fn step<S: OdeSystem + ?Sized>(&mut self, system: &mut S) -> Result<(), IntegratorError> {
///         let remaining = self.t_end - self.t;
///         if remaining * self.h <= 0.0 {
///             return Err(IntegratorError::InvalidInput(format!("already at t_end = {}", self.t_end)));
///         }
///         // Land exactly on t_end.
///         let last = remaining.abs() <= self.h.abs();
///         let h = if last { remaining } else { self.h };
///         system.rhs(self.t, &self.y, &mut self.f);
///         self.stats.rhs_evaluations += 1;
///         self.y_prev.copy_from_slice(&self.y);
///         for (y, f) in self.y.iter_mut().zip(&self.f) {
///             *y += h * f;
///         }
///         if let Some(component) = self.y.iter().position(|v| !v.is_finite()) {
///             return Err(IntegratorError::NonFinite { t: self.t + h, component });
///         }
///         self.t_prev = self.t;
///         self.t = if last { self.t_end } else { self.t + h };
///         self.stats.accepted_steps += 1;
///         self.stats.record_order(1);
///         Ok(())
///     }
///     fn interpolate(&self, t: f64, out: &mut [f64]) {
///         let theta = (t - self.t_prev) / (self.t - self.t_prev);
///         for i in 0..out.len() {
///             out[i] = self.y_prev[i] + theta * (self.y[i] - self.y_prev[i]);
///         }
///     }
///     fn stats(&self) -> &Stats { &self.stats }
/// }
///
/// impl Integrator for Euler {
///     type Stepper = EulerState;
///     fn name(&self) -> &'static str { "euler" }
///     fn options(&self) -> &Options { &self.options }
///     fn start<S: OdeSystem + ?Sized>(
///         &self, system: &mut S, t0: f64, y0: &[f64], t_end: f64,
///     ) -> Result<EulerState, IntegratorError> {
///         validate_start(&self.options, system.dim(), y0, t0, t_end)?;
///         let h = self.h.min(self.options.max_step) * (t_end - t0).signum();
///         Ok(EulerState {
///             t: t0, t_prev: t0, t_end, h,
///             y: y0.to_vec(), y_prev: y0.to_vec(), f: vec![0.0; y0.len()],
///             stats: Stats::default(),
///         })
///     }
/// }
///
/// /// y' = -y.
/// struct Decay;
/// impl OdeSystem for Decay {
///     fn dim(&self) -> usize { 1 }
///     fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) { dy[0] = -y[0]; }
/// }
///
/// // First order: halving the step halves the error at t = 1 (closed form e^-1).
/// let error = |h: f64| {
///     let euler = Euler { options: Options::default(), h };
///     let sol = euler.solve(&mut Decay, 0.0, &[1.0], &[1.0]).unwrap();
///     (sol.y(0)[0] - (-1.0_f64).exp()).abs()
/// };
/// let ratio = error(1e-3) / error(5e-4);
/// assert!((ratio - 2.0).abs() < 0.01, "ratio {ratio}");
/// // Stop times split the run into segments that land on them.
/// let euler = Euler { options: Options::default(), h: 0.3 };
/// let sol = euler.solve_observed(&mut Decay, 0.0, &[1.0], &[1.0], &[0.5], &mut ()).unwrap();
/// assert_eq!(sol.stats.segments, 2);
/// assert_eq!(sol.stats.accepted_steps, 4); // 0.3, 0.5 | 0.8, 1.0
/// ```
#[allow(
    clippy::result_large_err,
    reason = "the error carries the partial solution, as large as the Ok value; returned once per run"
)]
pub trait Integrator {
    /// The state of one integration with this method.
    type Stepper: Stepper;

    /// Short name (`"rk45"`, `"abm"`, `"bdf"`, `"generalized_alpha"`).
    fn name(&self) -> &'static str;

    /// The shared options.
    fn options(&self) -> &Options;

    /// Starts an integration from `(t0, y0)` towards `t_end` (which may be below `t0`:
    /// integration backwards in time is allowed).
    ///
    /// # Errors
    /// Invalid options or input (dimension mismatch, non-finite `y0`, `t_end == t0`).
    fn start<S: OdeSystem + ?Sized>(
        &self,
        system: &mut S,
        t0: f64,
        y0: &[f64],
        t_end: f64,
    ) -> Result<Self::Stepper, IntegratorError>;

    /// Integrates from `t0` to the last of `t_out`, writing the state at each time in
    /// `t_out` by dense output (the requested times never shorten the steps).
    ///
    /// `t_out` must be monotone in the direction of integration and lie between `t0` and
    /// its last entry; times equal to `t0` return `y0`. The same as
    /// [`Integrator::solve_observed`] without stop times or observer.
    ///
    /// # Errors
    /// As [`Integrator::start`] and [`Stepper::step`]; an empty or unsorted `t_out` is an
    /// [`IntegratorError::InvalidInput`].
    fn solve<S: OdeSystem + ?Sized>(
        &self,
        system: &mut S,
        t0: f64,
        y0: &[f64],
        t_out: &[f64],
    ) -> Result<Solution, IntegratorError> {
        self.solve_observed(system, t0, y0, t_out, &[], &mut ())
            .map_err(Interrupted::into_error)
    }

    /// Integrates from `t0` to the last of `t_out` (as [`Integrator::solve`]), restarting
    /// the method at every stop time and reporting to `observer`.
    ///
    /// `stops` are times at which the right-hand side or its derivatives may jump (a forcing
    /// that switches on, a trajectory segment that ends). They may come in any order, repeat,
    /// or lie outside `(t0, t_end)` (those are ignored). The span is integrated segment by
    /// segment: each segment starts a fresh stepper ([`Integrator::start`]) towards the next
    /// stop, so every method lands exactly on it, restarts its history there (ABM and BDF
    /// at order 1, RK45 with a new initial step), and can never step past it. This is the
    /// standard treatment of known discontinuities (Hairer, Norsett & Wanner I, II.6); without
    /// it a forcing that is exactly zero at first and starts later can be stepped over
    /// entirely (the error estimate is zero while it is off).
    ///
    /// `max_steps` bounds the steps of all segments together; the returned [`Stats`] sum the
    /// segments ([`Stats::segments`] counts them).
    ///
    /// # Errors
    /// [`Interrupted`] with every output up to the last accepted time (dense output, never
    /// extrapolated) and the statistics so far: [`Interruption::Failed`] for the errors of
    /// [`Integrator::solve`] (and a non-finite stop time), [`Interruption::Stopped`] when the
    /// observer returned [`Flow::Stop`], [`Interruption::Event`] when the system's terminal
    /// event ([`OdeSystem::terminal_event`]) was reached (the outputs up to its located time).
    fn solve_observed<S: OdeSystem + ?Sized>(
        &self,
        system: &mut S,
        t0: f64,
        y0: &[f64],
        t_out: &[f64],
        stops: &[f64],
        observer: &mut dyn Observer,
    ) -> Result<Solution, Interrupted> {
        observe::drive(self, system, t0, y0, t_out, stops, observer)
    }
}
