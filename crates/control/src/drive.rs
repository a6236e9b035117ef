//! The motor's electrics under its drive: a permanent-magnet servo motor fed from a DC bus by
//! a current-controlled amplifier, in steady state (the current loop settles much faster than
//! the mechanics):
//!
//! ```text
//! torque           tau = K_t i                   (K_t: torque constant, N m/A)
//! winding voltage  u = R i + K_e omega           (K_e = K_t in SI units, V s/rad)
//! limits           |u| <= V_bus,  |i| <= I_max
//! ```
//!
//! so the torque the drive can give at the motor speed `omega` is the interval
//!
//! ```text
//! K_t (-V_bus - K_e omega) / R  <=  tau  <=  K_t (V_bus - K_e omega) / R,   |tau| <= K_t I_max
//! ```
//!
//! the motor's torque-speed envelope: the peak (or current-limited) torque up to the corner
//! speed, then falling linearly to zero at the no-load speed `V_bus / K_e` when motoring; a
//! braking torque is helped by the back-EMF. The winding's inductance and the current loop's
//! own dynamics are not modelled here (the envelope is their steady state).

use crate::ControlError;
use crate::error::check;

/// The drive of a servo motor (module documentation): its torque-speed envelope from the bus
/// voltage, the winding resistance, the torque constant and the current limit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drive {
    /// Torque constant `K_t` (N m/A), equal to the back-EMF constant `K_e` (V s/rad) in SI.
    pub torque_constant: f64,
    /// Winding resistance `R` (ohm), terminal to terminal as the amplifier sees it.
    pub resistance: f64,
    /// DC bus voltage `V_bus` (V): the largest winding voltage the amplifier can apply.
    pub bus_voltage: f64,
    /// Current limit `I_max` (A) of the amplifier (infinite: none).
    pub current_limit: f64,
}

impl Drive {
    /// Checks every parameter.
    ///
    /// # Errors
    /// The first parameter out of its range, by its key.
    pub fn validated(self) -> Result<Self, ControlError> {
        check(
            "torque_constant",
            self.torque_constant,
            0.0,
            true,
            "must be finite and > 0 (N m/A; servo motors have 0.01 to 10)",
        )?;
        check(
            "resistance",
            self.resistance,
            0.0,
            true,
            "must be finite and > 0 (ohm; servo windings have 0.05 to 100)",
        )?;
        check(
            "bus_voltage",
            self.bus_voltage,
            0.0,
            true,
            "must be finite and > 0 (V; servo drives have 24 to 800)",
        )?;
        if self.current_limit.is_nan() || self.current_limit <= 0.0 {
            return Err(ControlError::InvalidParameter {
                name: "current_limit",
                value: self.current_limit,
                rule: "must be > 0 (A)",
            });
        }
        for (name, value, max, rule) in [
            (
                "torque_constant",
                self.torque_constant,
                1e3,
                "must be at most 1e3 N m/A",
            ),
            (
                "resistance",
                self.resistance,
                1e6,
                "must be at most 1e6 ohm",
            ),
            (
                "bus_voltage",
                self.bus_voltage,
                1e6,
                "must be at most 1e6 V",
            ),
        ] {
            if value > max {
                return Err(ControlError::InvalidParameter { name, value, rule });
            }
        }
        Ok(self)
    }

    /// The no-load speed `V_bus / K_e` (rad/s): the fastest the motor turns with no torque.
    pub fn no_load_speed(&self) -> f64 {
        self.bus_voltage / self.torque_constant
    }

    /// The torque the current limit allows, `K_t I_max` (N m).
    pub fn current_limited_torque(&self) -> f64 {
        self.torque_constant * self.current_limit
    }

    /// The winding current for the torque `torque` (A).
    pub fn current(&self, torque: f64) -> f64 {
        torque / self.torque_constant
    }

    /// The winding voltage `R i + K_e omega` for the torque `torque` at the motor speed
    /// `omega` (rad/s), in steady state (V).
    pub fn voltage(&self, torque: f64, omega: f64) -> f64 {
        self.resistance * self.current(torque) + self.torque_constant * omega
    }

    /// The torque interval the bus voltage allows at the motor speed `omega` (rad/s),
    /// `K_t (+-V_bus - K_e omega) / R` (N m); the current limit is
    /// [`Drive::current_limited_torque`].
    pub fn voltage_limited_torque(&self, omega: f64) -> (f64, f64) {
        let k = self.torque_constant / self.resistance;
        let emf = self.torque_constant * omega;
        (k * (-self.bus_voltage - emf), k * (self.bus_voltage - emf))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drive() -> Drive {
        Drive {
            torque_constant: 0.5,
            resistance: 2.0,
            bus_voltage: 300.0,
            current_limit: 10.0,
        }
        .validated()
        .unwrap()
    }

    #[test]
    fn the_envelope_falls_to_zero_at_the_no_load_speed() {
        let d = drive();
        // V / K_e = 600 rad/s.
        assert!((d.no_load_speed() - 600.0).abs() <= 1e-12);
        let (lo, hi) = d.voltage_limited_torque(d.no_load_speed());
        assert!(hi.abs() <= 1e-12, "{hi}");
        // Braking at the no-load speed: the back-EMF doubles the voltage available.
        assert!((lo + 2.0 * 0.5 * 300.0 / 2.0).abs() <= 1e-9, "{lo}");
        // At rest the stall torque K_t V / R, symmetric.
        let (lo, hi) = d.voltage_limited_torque(0.0);
        assert!((hi - 75.0).abs() <= 1e-12 && (lo + 75.0).abs() <= 1e-12);
        // On the envelope the winding voltage is the bus voltage.
        let omega = 250.0;
        let (_, hi) = d.voltage_limited_torque(omega);
        assert!((d.voltage(hi, omega) - 300.0).abs() <= 1e-9);
        assert!((d.current_limited_torque() - 5.0).abs() <= 1e-12);
    }

    #[test]
    fn bad_parameters_are_named() {
        let bad = Drive {
            resistance: 0.0,
            ..drive()
        };
        let e = bad.validated().unwrap_err().to_string();
        assert!(e.starts_with("resistance = 0"), "{e}");
        let bad = Drive {
            current_limit: f64::NAN,
            ..drive()
        };
        assert!(bad.validated().is_err());
    }
}
