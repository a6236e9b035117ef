//! A sampled law computed by a function given at run time (`kind = "python"`,
//! docs/control.md, "Python laws"): the function receives the measurements in the listed
//! order at each sample and returns the commands, held over the period (zero-order hold).
//!
//! This crate knows nothing of Python: the Python bindings fill a [`CallbackLaw`] with a
//! [`LawFunction`] that calls the user's function under the GIL. The function is called
//! only at samples (never inside the right-hand side), may be slow and may fail: a failure
//! or a command that is not a finite number stops the run at that sample
//! ([`ControlError::LawFailed`], through [`Controller::try_command`]).

use std::fmt;
use std::sync::Arc;

use crate::statespace::check_channels;
use crate::{ControlError, ControlInput, Controller, MAX_MEASUREMENTS, SliderSignal};

/// The function of a [`CallbackLaw`]: the commands from the measurements at a sample.
///
/// ```
/// use flexprr_control::LawFunction;
///
/// /// `u = -k y` on as many commands as measurements.
/// struct Gain(f64);
/// impl LawFunction for Gain {
///     fn call(&self, _t: f64, y: &[f64], u: &mut [f64]) -> Result<(), String> {
///         if y.len() != u.len() {
///             return Err("one command per measurement".into());
///         }
///         for (u, y) in u.iter_mut().zip(y) {
///             *u = -self.0 * y;
///         }
///         Ok(())
///     }
/// }
/// let mut u = [0.0; 2];
/// Gain(2.0).call(0.0, &[1.0, -0.5], &mut u).unwrap();
/// assert_eq!(u, [-2.0, 1.0]);
/// ```
pub trait LawFunction: Send + Sync {
    /// Writes the commands `u` (one per command of the law, N) from the measurements `y`
    /// (in the law's order) at the sample time `t` (s).
    ///
    /// # Errors
    /// Why no command could be computed (reported with the sample time).
    fn call(&self, t: f64, y: &[f64], u: &mut [f64]) -> Result<(), String>;
}

/// A sampled law whose commands a [`LawFunction`] computes: see the module documentation.
/// `F_i = F_ff_i + u_k` for each commanded slider (`F_ff` when the feedforward is on), the
/// feedforward alone on the others.
#[derive(Clone)]
pub struct CallbackLaw {
    measurements: Vec<SliderSignal>,
    commands: Vec<usize>,
    feedforward: bool,
    friction_feedforward: bool,
    period: f64,
    function: Arc<dyn LawFunction>,
    name: String,
}

impl fmt::Debug for CallbackLaw {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("CallbackLaw")
            .field("name", &self.name)
            .field("measurements", &self.measurements)
            .field("commands", &self.commands)
            .field("feedforward", &self.feedforward)
            .field("period", &self.period)
            .finish_non_exhaustive()
    }
}

impl CallbackLaw {
    /// The law with the actuators' steady friction in its feedforward (when `on`, and the
    /// feedforward is on; [`Controller::friction_feedforward`]).
    #[must_use]
    pub fn with_friction_feedforward(mut self, on: bool) -> Self {
        self.friction_feedforward = on;
        self
    }

    /// The law `name` (for summaries) on `measurements`, commanding the sliders `commands`
    /// (0-based, each at most once), sampled every `period` s.
    ///
    /// # Errors
    /// A period that is not finite and > 0 (a function is called at samples only), more
    /// than [`MAX_MEASUREMENTS`] measurements or a repeated one, a slider commanded twice or
    /// out of range.
    pub fn new(
        name: &str,
        measurements: Vec<SliderSignal>,
        commands: Vec<usize>,
        feedforward: bool,
        period: f64,
        function: Arc<dyn LawFunction>,
    ) -> Result<Self, ControlError> {
        let period = crate::error::check(
            "period",
            period,
            0.0,
            true,
            "a law computed by a function is sampled: the period must be finite and > 0",
        )?;
        check_channels(&measurements, &commands)?;
        Ok(Self {
            measurements,
            commands,
            feedforward,
            friction_feedforward: false,
            period,
            function,
            name: name.to_string(),
        })
    }

    /// The measurements, in order.
    pub fn measurements(&self) -> &[SliderSignal] {
        &self.measurements
    }

    /// The commanded slider of each command (0-based).
    pub fn commands(&self) -> &[usize] {
        &self.commands
    }
}

impl Controller for CallbackLaw {
    fn friction_feedforward(&self) -> bool {
        self.feedforward && self.friction_feedforward
    }
    /// As [`Controller::try_command`], with NaN commands where the function failed.
    fn command(
        &self,
        input: &ControlInput<'_>,
        states: &[f64],
        force: &mut [f64; 3],
        rates: &mut [f64],
    ) {
        if self.try_command(input, states, force, rates).is_err() {
            *force = [f64::NAN; 3];
        }
    }

    fn try_command(
        &self,
        input: &ControlInput<'_>,
        _states: &[f64],
        force: &mut [f64; 3],
        _rates: &mut [f64],
    ) -> Result<(), ControlError> {
        let mut y = [0.0; MAX_MEASUREMENTS];
        for (yk, s) in y.iter_mut().zip(&self.measurements) {
            *yk = s.value(input);
        }
        let mut u = [0.0; 3];
        let u = &mut u[..self.commands.len()];
        let failed = |message: String| ControlError::LawFailed {
            t: input.t,
            message,
        };
        self.function
            .call(input.t, &y[..self.measurements.len()], u)
            .map_err(failed)?;
        if let Some(k) = u.iter().position(|x| !x.is_finite()) {
            return Err(failed(format!(
                "command {} (slider_force:{}) is {}: commands must be finite numbers",
                k,
                self.commands[k] + 1,
                u[k]
            )));
        }
        for (i, f) in force.iter_mut().enumerate() {
            *f = if self.feedforward {
                input.feedforward[i]
            } else {
                0.0
            };
        }
        for (&slider, uk) in self.commands.iter().zip(u.iter()) {
            force[slider] += uk;
        }
        Ok(())
    }

    fn period(&self) -> f64 {
        self.period
    }

    fn name(&self) -> String {
        self.name.clone()
    }

    fn reads(&self) -> [[bool; 2]; 3] {
        SliderSignal::reads(&self.measurements)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SliderState;

    struct Pd(f64, f64);
    impl LawFunction for Pd {
        fn call(&self, t: f64, y: &[f64], u: &mut [f64]) -> Result<(), String> {
            if t > 1.0 {
                return Err("Traceback: ValueError: late".into());
            }
            u[0] = self.0 * y[0] + self.1 * y[1];
            u[1] = if t > 0.5 { f64::NAN } else { 0.0 };
            Ok(())
        }
    }

    fn input(t: f64) -> ControlInput<'static> {
        let at = |position, velocity| SliderState {
            position,
            velocity,
            acceleration: 0.0,
        };
        ControlInput {
            t,
            reference: [at(1.0, 2.0), at(3.0, 4.0), at(5.0, 6.0)],
            measured: [at(0.5, 1.0), at(2.0, 3.0), at(4.0, 5.0)],
            feedforward: [10.0, 20.0, 30.0],
            force_limit: [f64::INFINITY; 3],
            sensors: &[],
        }
    }

    #[test]
    fn the_function_sees_the_listed_measurements_and_its_failures_name_the_sample() {
        use SliderSignal::{Error, ErrorRate};
        let law = CallbackLaw::new(
            "python",
            vec![Error(1), ErrorRate(1)],
            vec![1, 2],
            true,
            1e-3,
            Arc::new(Pd(100.0, 2.0)),
        )
        .unwrap();
        assert_eq!(law.reads(), [[false; 2], [true; 2], [false; 2]]);
        let mut f = [0.0; 3];
        law.try_command(&input(0.0), &[], &mut f, &mut []).unwrap();
        // Slider 2: error 1, rate 1; slider 3 commanded 0, slider 1 feedforward only.
        let expected = [10.0, 20.0 + 100.0 + 2.0, 30.0];
        assert!(
            f.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-12),
            "{f:?}"
        );
        let e = law
            .try_command(&input(0.75), &[], &mut f, &mut [])
            .unwrap_err();
        assert!(
            e.to_string().contains("t = 0.75 s") && e.to_string().contains("slider_force:3"),
            "{e}"
        );
        let e = law
            .try_command(&input(2.0), &[], &mut f, &mut [])
            .unwrap_err();
        assert!(e.to_string().contains("ValueError: late"), "{e}");
        law.command(&input(2.0), &[], &mut f, &mut []);
        assert!(f.iter().all(|x| x.is_nan()));
    }

    #[test]
    fn a_callback_law_needs_a_period() {
        let e = CallbackLaw::new("python", vec![], vec![0], true, 0.0, Arc::new(Pd(1.0, 1.0)))
            .unwrap_err();
        assert!(e.to_string().contains("> 0"), "{e}");
    }
}
