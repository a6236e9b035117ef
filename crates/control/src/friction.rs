//! Friction with a stuck phase: the LuGre model (Canudas de Wit, Olsson, Astrom &
//! Lischinsky, "A new model for control of systems with friction", IEEE Transactions on
//! Automatic Control 40(3), 1995, eqs. 2-4), at a motor shaft.
//!
//! The contact is an average bristle of deflection `z` (rad at the shaft). With the shaft's
//! speed `omega` (rad/s):
//!
//! ```text
//! Stribeck curve     g(omega) = tau_C + (tau_S - tau_C) exp(-(omega / omega_s)^2)
//! bristles           z' = omega - sigma0 |omega| z / g(omega)
//! friction torque    tau_f = sigma0 z + sigma1 z' + sigma2 omega
//! ```
//!
//! `tau_S` is the static (breakaway) torque, `tau_C` the Coulomb (sliding) torque, `omega_s`
//! the Stribeck speed (`2 pi n_s` for `n_s` in rev/s), `sigma0` the bristles' stiffness,
//! `sigma1` their damping and `sigma2` the viscous friction.
//!
//! * **Stuck**: below the breakaway torque the bristles deflect like a spring of stiffness
//!   `sigma0` and the shaft comes to rest with `z = tau / sigma0` (`z' = 0` at `omega = 0`:
//!   a true equilibrium, not a creep). The displacement to get there is not `z`: on a
//!   monotone approach `dz/dphi = 1 - z / z_S` with `z_S = tau_S / sigma0`, so the shaft
//!   turns `phi = -z_S ln(1 - tau / tau_S)` (`tau / sigma0` only for `tau << tau_S`; the
//!   model's presliding is hysteretic, and a torque set back to zero leaves the shaft
//!   displaced: the "drift" Astrom & Canudas de Wit discuss in "Revisiting the LuGre
//!   model", IEEE Control Systems Magazine 28(6), 2008).
//! * **Breakaway**: under a slowly rising torque `phi` grows without bound as `tau ->
//!   tau_S`: the shaft breaks away at the static torque. A fast rise breaks away lower (the
//!   model's rate dependence, reported in the 1995 paper).
//! * **Sliding** at a constant speed the bristles settle at `z = sign(omega) g(omega) /
//!   sigma0` and the friction is the Stribeck curve plus the viscous term,
//!   `tau_f = sign(omega) g(omega) + sigma2 omega` ([`LuGre::steady_torque`]).
//!
//! The bristles are stiff: sliding, `z` relaxes at the rate `sigma0 |omega| / g(omega)`
//! (the inverse of the time the shaft takes to turn through the presliding deflection
//! `g / sigma0`), which an explicit integrator must resolve (docs/control.md, "Friction with
//! a stuck phase", measures it).

use crate::ControlError;
use crate::actuator::ActuatorSignal;
use crate::error::check;

/// The LuGre bristle deflection, the state a [`crate::MotorBallScrew`] with [`LuGre`]
/// friction carries (rad at the motor shaft).
pub const BRISTLE_DEFLECTION: [ActuatorSignal; 1] = [ActuatorSignal {
    name: "bristle_deflection",
    header_unit: "rad",
    symbol: "z",
    unit: "rad",
}];

/// The parameters of the LuGre model that the smoothed Coulomb friction lacks (module
/// documentation); the Coulomb torque `tau_C` and the viscous friction `sigma2` are the
/// motor's own (`coulomb_friction`, `viscous_friction`) and are passed in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LuGre {
    /// Static (breakaway) torque `tau_S` (N m), at least the Coulomb torque.
    pub static_friction: f64,
    /// Stribeck speed `n_s` (rev/s): the friction falls from `tau_S` towards `tau_C` over
    /// about this speed.
    pub stribeck_speed: f64,
    /// Bristle stiffness `sigma0` (N m/rad): the presliding spring.
    pub bristle_stiffness: f64,
    /// Bristle damping `sigma1` (N m s/rad).
    pub bristle_damping: f64,
}

impl LuGre {
    /// Checks every parameter against the motor's Coulomb torque `coulomb` (N m).
    ///
    /// # Errors
    /// The first parameter out of its range, by its key.
    pub fn validated(self, coulomb: f64) -> Result<Self, ControlError> {
        if coulomb.is_nan() || coulomb <= 0.0 {
            return Err(ControlError::InvalidParameter {
                name: "coulomb_friction",
                value: coulomb,
                rule: "must be > 0 with friction = \"lugre\" (N m): sliding, the bristles settle \
                       at g(omega) / sigma0, which needs a sliding friction",
            });
        }
        check(
            "static_friction",
            self.static_friction,
            0.0,
            true,
            "must be finite and > 0 (N m)",
        )?;
        if self.static_friction < coulomb {
            return Err(ControlError::InvalidParameter {
                name: "static_friction",
                value: self.static_friction,
                rule: "must be at least coulomb_friction (the breakaway torque is the Stribeck \
                       curve's top)",
            });
        }
        check(
            "stribeck_speed",
            self.stribeck_speed,
            0.0,
            true,
            "must be finite and > 0 (rev/s)",
        )?;
        check(
            "bristle_stiffness",
            self.bristle_stiffness,
            0.0,
            true,
            "must be finite and > 0 (N m/rad)",
        )?;
        check(
            "bristle_damping",
            self.bristle_damping,
            0.0,
            false,
            "must be finite and >= 0 (N m s/rad)",
        )?;
        for (name, value, max, rule) in [
            (
                "static_friction",
                self.static_friction,
                1e6,
                "must be at most 1e6 N m",
            ),
            (
                "stribeck_speed",
                self.stribeck_speed,
                1e5,
                "must be at most 1e5 rev/s",
            ),
            (
                "bristle_stiffness",
                self.bristle_stiffness,
                1e12,
                "must be at most 1e12 N m/rad (a presliding deflection of a picoradian per N m)",
            ),
            (
                "bristle_damping",
                self.bristle_damping,
                1e6,
                "must be at most 1e6 N m s/rad",
            ),
        ] {
            if value > max {
                return Err(ControlError::InvalidParameter { name, value, rule });
            }
        }
        Ok(self)
    }

    /// The Stribeck speed `omega_s` (rad/s).
    pub fn stribeck_rate(&self) -> f64 {
        std::f64::consts::TAU * self.stribeck_speed
    }

    /// The Stribeck curve `g(omega)` (N m) at the shaft speed `omega` (rad/s), with the
    /// Coulomb torque `coulomb` (N m).
    pub fn stribeck(&self, coulomb: f64, omega: f64) -> f64 {
        let r = omega / self.stribeck_rate();
        coulomb + (self.static_friction - coulomb) * (-r * r).exp()
    }

    /// The bristles' rate `z' = omega - sigma0 |omega| z / g(omega)` (rad/s) at the shaft
    /// speed `omega` (rad/s) and deflection `z` (rad).
    pub fn bristle_rate(&self, coulomb: f64, omega: f64, z: f64) -> f64 {
        omega - self.bristle_stiffness * omega.abs() * z / self.stribeck(coulomb, omega)
    }

    /// The friction torque `sigma0 z + sigma1 z' + sigma2 omega` (N m) and the bristles'
    /// rate `z'`, at the shaft speed `omega` (rad/s) and deflection `z` (rad), with the
    /// Coulomb torque `coulomb` (N m) and the viscous friction `viscous` (N m s/rad).
    pub fn torque(&self, coulomb: f64, viscous: f64, omega: f64, z: f64) -> (f64, f64) {
        let rate = self.bristle_rate(coulomb, omega, z);
        let torque = self.bristle_stiffness * z + self.bristle_damping * rate + viscous * omega;
        (torque, rate)
    }

    /// The deflection the bristles settle at when sliding at the constant speed `omega`
    /// (rad/s): `sign(omega) g(omega) / sigma0` (0 at rest, unloaded).
    pub fn steady_deflection(&self, coulomb: f64, omega: f64) -> f64 {
        sign(omega) * self.stribeck(coulomb, omega) / self.bristle_stiffness
    }

    /// The friction torque when sliding at the constant speed `omega` (rad/s): the
    /// Stribeck curve plus the viscous term, `sign(omega) g(omega) + sigma2 omega` (0 at
    /// rest: there any torque up to `tau_S` is held).
    pub fn steady_torque(&self, coulomb: f64, viscous: f64, omega: f64) -> f64 {
        sign(omega) * self.stribeck(coulomb, omega) + viscous * omega
    }

    /// The presliding spring and damper the shaft sees at rest, unloaded (`z = 0`):
    /// `tau_f = sigma0 phi + (sigma1 + sigma2) phi'` for small motions `phi`; with the
    /// shaft's inertia `J` its stuck mode is `sqrt(sigma0 / J)` rad/s.
    pub fn presliding_stiffness(&self) -> f64 {
        self.bristle_stiffness
    }
}

/// `signum` with `sign(0) = 0`.
fn sign(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lugre() -> LuGre {
        LuGre {
            static_friction: 0.03,
            stribeck_speed: 0.05,
            bristle_stiffness: 100.0,
            bristle_damping: 0.05,
        }
        .validated(0.02)
        .unwrap()
    }

    #[test]
    fn the_stribeck_curve_falls_from_the_static_to_the_coulomb_torque() {
        let f = lugre();
        let ws = f.stribeck_rate();
        assert!((f.stribeck(0.02, 0.0) - 0.03).abs() <= 1e-15);
        // At the Stribeck speed: tau_C + (tau_S - tau_C) / e.
        let at = 0.02 + 0.01 * (-1f64).exp();
        assert!((f.stribeck(0.02, -ws) - at).abs() <= 1e-15);
        assert!((f.stribeck(0.02, 10.0 * ws) - 0.02).abs() <= 1e-15);
    }

    #[test]
    fn sliding_settles_on_the_curve_and_rest_is_an_equilibrium() {
        let f = lugre();
        for omega in [-30.0, -0.2, 0.05, 0.3, 3.0, 300.0] {
            let z = f.steady_deflection(0.02, omega);
            let (torque, rate) = f.torque(0.02, 1e-4, omega, z);
            assert!(rate.abs() <= 1e-12 * omega.abs(), "{omega}: {rate}");
            let curve = omega.signum() * f.stribeck(0.02, omega) + 1e-4 * omega;
            assert!(
                (torque - curve).abs() <= 1e-12,
                "{omega}: {torque} vs {curve}"
            );
        }
        // At rest any deflection holds: z' = 0, the torque is the spring's.
        let (torque, rate) = f.torque(0.02, 1e-4, 0.0, 2e-4);
        assert!(rate.abs() <= 0.0 && (torque - 0.02).abs() <= 1e-15);
    }

    #[test]
    fn bad_parameters_are_refused_by_key() {
        let e = LuGre {
            static_friction: 0.01,
            ..lugre()
        }
        .validated(0.02)
        .unwrap_err();
        assert!(e.to_string().starts_with("static_friction = 0.01"), "{e}");
        let e = lugre().validated(0.0).unwrap_err();
        assert!(e.to_string().starts_with("coulomb_friction = 0"), "{e}");
        let e = LuGre {
            bristle_stiffness: 0.0,
            ..lugre()
        }
        .validated(0.02)
        .unwrap_err();
        assert!(e.to_string().starts_with("bristle_stiffness"), "{e}");
        let e = LuGre {
            stribeck_speed: f64::NAN,
            ..lugre()
        }
        .validated(0.02)
        .unwrap_err();
        assert!(e.to_string().starts_with("stribeck_speed"), "{e}");
    }
}
