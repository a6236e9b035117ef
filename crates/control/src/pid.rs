//! PD and PID control of each slider's position with the rigid feedforward.
//!
//! On slider `i`, with the error `e = rho_ref - rho` and its rate `e' = rho_ref' - rho'`:
//!
//! ```text
//! F_i = F_ff_i + kp e + kd e' + ki I,     I' = e   (conditional integration)
//! ```
//!
//! `F_ff` is the feedforward the model hands in ([`crate::ControlInput::feedforward`]).
//! Anti-windup by conditional integration (Astrom & Hagglund, *Advanced PID Control*, 2006,
//! section 3.5, "conditional integration"): while the command is beyond the actuator's force
//! limit and the error would drive it further out, the integral holds (`I' = 0`).

use crate::error::check;
use crate::{ControlError, ControlInput, Controller};

/// `kind = "pd"` (`ki` = 0, no state) and `kind = "pid"` (one integral state per slider).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pid {
    kp: f64,
    kd: f64,
    ki: f64,
    feedforward: bool,
    friction_feedforward: bool,
    period: f64,
}

impl Pid {
    /// A PD law: `kp` (N/m), `kd` (N s/m), the feedforward on or off, sample `period` (s, 0
    /// for continuous).
    ///
    /// # Errors
    /// A negative or non-finite gain or period.
    pub fn pd(kp: f64, kd: f64, feedforward: bool, period: f64) -> Result<Self, ControlError> {
        Self::new(kp, kd, 0.0, feedforward, period)
    }

    /// A PID law: as [`Pid::pd`] with the integral gain `ki` (N/(m s)).
    ///
    /// # Errors
    /// A negative, non-finite or absurdly large gain (`kp` above 1e12 N/m, `kd` above 1e9
    /// N s/m, `ki` above 1e15 N/(m s)), or a negative or non-finite period.
    pub fn new(
        kp: f64,
        kd: f64,
        ki: f64,
        feedforward: bool,
        period: f64,
    ) -> Result<Self, ControlError> {
        // Bounds far beyond any servo (stiffer than a steel bar by orders of magnitude):
        // beyond them the loop's frequency, sqrt(kp / m), is out of any step's reach and the
        // run would fail at its start with a step size of zero instead of here.
        for (name, value, max, rule) in [
            (
                "kp",
                kp,
                1e12,
                "a gain must be at most 1e12 N/m (servo loops are 1e4 to 1e8)",
            ),
            (
                "kd",
                kd,
                1e9,
                "a gain must be at most 1e9 N s/m (servo loops are 1e1 to 1e5)",
            ),
            ("ki", ki, 1e15, "a gain must be at most 1e15 N/(m s)"),
        ] {
            if value > max {
                return Err(ControlError::InvalidParameter { name, value, rule });
            }
        }
        Ok(Self {
            kp: check("kp", kp, 0.0, false, "a gain must be finite and >= 0")?,
            kd: check("kd", kd, 0.0, false, "a gain must be finite and >= 0")?,
            ki: check("ki", ki, 0.0, false, "a gain must be finite and >= 0")?,
            feedforward,
            friction_feedforward: false,
            period: check(
                "period",
                period,
                0.0,
                false,
                "must be finite and >= 0 (0 for a continuous controller)",
            )?,
        })
    }

    /// `(kp, kd, ki)`.
    pub fn gains(&self) -> (f64, f64, f64) {
        (self.kp, self.kd, self.ki)
    }

    /// Whether the feedforward is added.
    pub fn feedforward(&self) -> bool {
        self.feedforward
    }

    /// The law with the actuators' steady friction in its feedforward (when `on`, and the
    /// feedforward is on; [`Controller::friction_feedforward`]).
    #[must_use]
    pub fn with_friction_feedforward(mut self, on: bool) -> Self {
        self.friction_feedforward = on;
        self
    }
}

impl Controller for Pid {
    fn friction_feedforward(&self) -> bool {
        self.feedforward && self.friction_feedforward
    }
    fn command(
        &self,
        input: &ControlInput<'_>,
        states: &[f64],
        force: &mut [f64; 3],
        rates: &mut [f64],
    ) {
        for i in 0..3 {
            let (reference, measured) = (&input.reference[i], &input.measured[i]);
            let error = reference.position - measured.position;
            let error_rate = reference.velocity - measured.velocity;
            let integral = if self.ki > 0.0 { states[i] } else { 0.0 };
            let feedforward = if self.feedforward {
                input.feedforward[i]
            } else {
                0.0
            };
            let command = feedforward + self.kp * error + self.kd * error_rate + self.ki * integral;
            force[i] = command;
            if self.ki > 0.0 {
                let limit = input.force_limit[i];
                let winding_up = command.abs() > limit && error * command > 0.0;
                rates[i] = if winding_up { 0.0 } else { error };
            }
        }
    }
    fn states(&self) -> usize {
        if self.ki > 0.0 { 3 } else { 0 }
    }
    fn period(&self) -> f64 {
        self.period
    }
    fn name(&self) -> String {
        if self.ki > 0.0 { "pid" } else { "pd" }.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SliderState;

    fn input(error: f64, error_rate: f64, limit: f64) -> ControlInput<'static> {
        let reference = SliderState {
            position: error,
            velocity: error_rate,
            acceleration: 0.0,
        };
        ControlInput {
            t: 0.0,
            reference: [reference; 3],
            measured: [SliderState::default(); 3],
            feedforward: [10.0; 3],
            force_limit: [limit; 3],
            sensors: &[],
        }
    }

    #[test]
    fn the_law_is_feedforward_plus_kp_e_plus_kd_e_dot_plus_ki_integral() {
        let pid = Pid::new(2.0e5, 400.0, 1.0e6, true, 0.0).unwrap();
        let (mut force, mut rates) = ([0.0; 3], [0.0; 3]);
        pid.command(&input(1e-3, -2e-2, 1e9), &[1e-5; 3], &mut force, &mut rates);
        let expected = 10.0 + 2.0e5 * 1e-3 + 400.0 * -2e-2 + 1.0e6 * 1e-5;
        assert!((force[0] - expected).abs() <= 1e-12 * expected.abs());
        assert!((rates[1] - 1e-3).abs() <= 1e-18);
        let pd = Pid::pd(2.0e5, 400.0, false, 0.0).unwrap();
        pd.command(&input(1e-3, 0.0, 1e9), &[], &mut force, &mut []);
        assert!((force[2] - 200.0).abs() <= 1e-10);
        assert_eq!(pd.states(), 0);
    }

    #[test]
    fn the_integral_holds_while_saturated_and_winding_up() {
        let pid = Pid::new(1.0e5, 0.0, 1.0e6, false, 0.0).unwrap();
        let (mut force, mut rates) = ([0.0; 3], [1.0; 3]);
        // Command 1e5 * 1e-2 = 1000 N beyond a 500 N limit, error of the same sign: hold.
        pid.command(&input(1e-2, 0.0, 500.0), &[0.0; 3], &mut force, &mut rates);
        assert!(rates.iter().all(|r| r.abs() < f64::MIN_POSITIVE));
        // Within the limit: integrate the error.
        pid.command(&input(1e-3, 0.0, 500.0), &[0.0; 3], &mut force, &mut rates);
        assert!(rates.iter().all(|r| (*r - 1e-3).abs() <= 1e-18));
        // Beyond the limit, but the error pulls back: integrate (it unwinds): command
        // 100 - 1000 = -900 N with an error of +1 mm.
        pid.command(
            &input(1e-3, 0.0, 500.0),
            &[-1e-3; 3],
            &mut force,
            &mut rates,
        );
        assert!(force[0] < -500.0);
        assert!(rates.iter().all(|r| (*r - 1e-3).abs() <= 1e-18));
    }

    #[test]
    fn bad_gains_are_refused_with_their_name() {
        let e = Pid::new(-1.0, 0.0, 0.0, true, 0.0).unwrap_err();
        assert!(e.to_string().starts_with("kp = -1"), "{e}");
        let e = Pid::pd(1.0, f64::NAN, true, 0.0).unwrap_err();
        assert!(e.to_string().starts_with("kd = NaN"), "{e}");
        let e = Pid::pd(1.0, 1.0, true, -1e-3).unwrap_err();
        assert!(e.to_string().contains("period"), "{e}");
    }
}
