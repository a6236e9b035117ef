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

pub mod abm;
pub mod bdf;
pub mod exponential;
pub mod rk45;
pub mod test_problems;

pub use abm::Abm;
pub use bdf::Bdf;
pub use common::{error_norm, initial_step};
pub use error::IntegratorError;
pub use exponential::{BlockOperators, LinearSecondOrder, Magnus, MagnusOrder, MagnusStepper};
pub use options::{Options, Tolerance};
pub use rk45::{Rk45, Rk45Stepper, StiffnessDetection};
pub use solution::{Solution, Stats};
pub use system::{OdeSystem, finite_difference_jacobian};

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
pub trait Integrator {
    /// The state of one integration with this method.
    type Stepper: Stepper;

    /// Short name (`"rk45"`, `"abm"`, `"bdf"`).
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
    /// its last entry; times equal to `t0` return `y0`.
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
        let n = y0.len();
        let Some(&t_end) = t_out.last() else {
            return Err(IntegratorError::InvalidInput(
                "no output times requested".to_string(),
            ));
        };
        let dir = (t_end - t0).signum();
        let mut prev = t0;
        for (k, &t) in t_out.iter().enumerate() {
            if !t.is_finite() || (t - prev) * dir < 0.0 {
                return Err(IntegratorError::InvalidInput(format!(
                    "output time t_out[{k}] = {t} is not monotone from t0 = {t0} towards {t_end}"
                )));
            }
            prev = t;
        }
        let mut solution = Solution::with_capacity(n, t_out.len());
        // Leading outputs at t0 need no step (and t_end == t0 is not an integration).
        let mut k = 0;
        while k < t_out.len() && (t_out[k] - t0) * dir <= 0.0 {
            solution.push(t_out[k], y0);
            k += 1;
        }
        if k == t_out.len() {
            return Ok(solution);
        }
        let mut stepper = self.start(system, t0, y0, t_end)?;
        let mut buf = vec![0.0; n];
        while k < t_out.len() {
            stepper.step(system)?;
            let t_now = stepper.t();
            while k < t_out.len() && (t_out[k] - t_now) * dir <= 0.0 {
                if (t_out[k] - t_now).abs() <= f64::EPSILON * t_now.abs().max(1.0) {
                    buf.copy_from_slice(stepper.y());
                } else {
                    stepper.interpolate(t_out[k], &mut buf);
                }
                solution.push(t_out[k], &buf);
                k += 1;
            }
        }
        solution.stats = stepper.stats().clone();
        Ok(solution)
    }
}
