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
//! braking torque is helped by the back-EMF.
//!
//! With a [`Winding`] the current is a state instead (the envelope is then the steady state
//! of its dynamics):
//!
//! ```text
//! winding            L i' = u - R i - K_e omega
//! current reference  i_r = clamp(tau_c, -tau_max, tau_max) / K_t      (tau_max: K_t I_max or the peak)
//! current loop (PI)  u* = k_p (i_r - i) + x + K_e omega,   u = clamp(u*, -V_bus, V_bus)
//!                    x' = k_i (i_r - i) + (u - u*) k_i / k_p               (back-calculation)
//!                    k_p = 2 pi f_c L,  k_i = 2 pi f_c R
//! no current loop    u = clamp(R i_r + K_e omega, -V_bus, V_bus)           (a voltage amplifier)
//! torque             tau = K_t i
//! ```
//!
//! The PI's zero `k_i / k_p = R / L` cancels the winding's pole, so that below the bus
//! voltage the current follows its reference as the first-order lag
//! `i / i_r = 2 pi f_c / (s + 2 pi f_c)`, whatever the speed: the back-EMF is fed forward
//! (the drive knows the speed). When the voltage clips, the back-calculation (tracking time
//! `k_p / k_i = L / R`; Åström & Hägglund, *Advanced PID Control*, 2006, 3.5) keeps the
//! integral where the loop comes out of saturation without overshoot. Without the current
//! loop the current reaches the reference with the winding's own time constant `L / R`.

use crate::ControlError;
use crate::error::{at_most, check};

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
    /// The winding's inductance and the amplifier's current loop, where modelled (the
    /// current is then a state); `None`: the steady state of the module documentation.
    pub winding: Option<Winding>,
}

/// The winding's inductance and the amplifier's current loop (module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Winding {
    /// Inductance `L` (H), terminal to terminal.
    pub inductance: f64,
    /// Bandwidth `f_c` (Hz) of the PI current loop; `None`: a voltage amplifier without a
    /// current loop.
    pub current_bandwidth: Option<f64>,
}

/// The winding's states, their rates and what the drive does at one instant
/// ([`Drive::winding`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindingOutput {
    /// The torque `K_t i` (N m).
    pub torque: f64,
    /// The current `i` (A).
    pub current: f64,
    /// The winding voltage `u` the amplifier applies (V).
    pub voltage: f64,
    /// Whether the current reference or the voltage was clipped.
    pub saturated: bool,
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
        if let Some(w) = self.winding {
            check(
                "inductance",
                w.inductance,
                0.0,
                true,
                "must be finite and > 0 (H; servo windings have 1e-4 to 0.1)",
            )?;
            at_most("inductance", w.inductance, 10.0, "must be at most 10 H")?;
            if let Some(f) = w.current_bandwidth {
                check(
                    "current_bandwidth",
                    f,
                    0.0,
                    true,
                    "must be finite and > 0 (Hz; current loops have 500 to 5000)",
                )?;
                at_most("current_bandwidth", f, 1e6, "must be at most 1e6 Hz")?;
            }
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

    /// The number of the winding's states: the current, and the current loop's integral
    /// (none without a [`Winding`]).
    pub fn states(&self) -> usize {
        match self.winding {
            None => 0,
            Some(Winding {
                current_bandwidth: None,
                ..
            }) => 1,
            Some(_) => 2,
        }
    }

    /// The PI gains `(k_p, k_i)` of the current loop (V/A, V/(A s)), where there is one.
    pub fn current_loop_gains(&self) -> Option<(f64, f64)> {
        let w = self.winding?;
        let omega_c = std::f64::consts::TAU * w.current_bandwidth?;
        Some((omega_c * w.inductance, omega_c * self.resistance))
    }

    /// The winding at the motor speed `omega` (rad/s) for the torque command `torque` (N m)
    /// limited to `+-torque_limit` (N m), with its states `states` (the current, then the
    /// loop's integral; [`Drive::states`] entries) and their rates into `rates` (module
    /// documentation). Without a [`Winding`], nothing (the steady state is
    /// [`Drive::voltage_limited_torque`]).
    pub fn winding(
        &self,
        torque: f64,
        torque_limit: f64,
        omega: f64,
        states: &[f64],
        rates: &mut [f64],
    ) -> Option<WindingOutput> {
        let w = self.winding?;
        let reference = torque.clamp(-torque_limit, torque_limit) / self.torque_constant;
        let current = states[0];
        let emf = self.torque_constant * omega;
        let wanted = match self.current_loop_gains() {
            Some((kp, _)) => kp * (reference - current) + states[1] + emf,
            None => self.resistance * reference + emf,
        };
        let voltage = wanted.clamp(-self.bus_voltage, self.bus_voltage);
        rates[0] = (voltage - self.resistance * current - emf) / w.inductance;
        if let Some((kp, ki)) = self.current_loop_gains() {
            rates[1] = ki * (reference - current) + (voltage - wanted) * ki / kp;
        }
        Some(WindingOutput {
            torque: self.torque_constant * current,
            current,
            voltage,
            saturated: torque.abs() > torque_limit || wanted.abs() > self.bus_voltage,
        })
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
            winding: None,
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
