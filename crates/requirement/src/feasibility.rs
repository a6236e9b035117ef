//! Feasibility of the commanded motion for the scene's motors (docs/control.md,
//! "Feasibility"): from the rigid inverse dynamics of the commanded motion, the force each
//! slider's actuator must deliver, `F_i = F_a_i_rigid + m_r rho_i''` (the rigid driving
//! force, slider mass included, plus the rotor's reflected inertia), and through
//! [`Actuator::required`] the motor torque and speed; compared with the peak torque, the
//! continuous torque (against the RMS torque) and the largest speed. The check is made on
//! the motion itself, between the output samples ([`crate::scan`]); the `actuators` table
//! gives the same requirement at the output times.

use flexprr_control::{Actuator, Drive, MotorRatings};
use flexprr_dynamics::{DynamicsError, inverse_dynamics};
use flexprr_scene::Scene;
use serde_json::{Value, json};

pub use crate::scan::TOLERANCE as SCAN_TOLERANCE;
use crate::scan::scan;
use crate::stats::{Peak, margin, num, number, sig};
use flexprr_dynamics::JointReactions;
use flexprr_kinematics::MachineState;

/// Per leg, a time series.
type PerLeg = [Vec<f64>; 3];

/// What the actuators must deliver along the commanded rigid motion, per leg, at the
/// samples' times.
#[derive(Debug, Clone, PartialEq)]
pub struct Required {
    /// Force on the slider (N): `F_a_rigid + m_r rho''`.
    pub force: [Vec<f64>; 3],
    /// Motor torque (N m) and speed (rev/s), where a motor is modelled.
    pub motor: Option<(PerLeg, PerLeg)>,
    /// The peak torque the torque saturates at, where a motor is modelled.
    pub peak_torque: Option<f64>,
}

/// The requirement of the commanded motion on `actuator` (the same on every leg) at the
/// output times, from the inverse kinematics `states` and the rigid joint `reactions` there.
pub fn required(
    actuator: &dyn Actuator,
    states: &[MachineState],
    reactions: &[JointReactions],
) -> Required {
    let reflected = actuator.reflected_mass();
    let force: [Vec<f64>; 3] = std::array::from_fn(|i| {
        states
            .iter()
            .zip(reactions)
            .map(|(state, r)| r.driving_force[i] + reflected * state.legs[i].rho_ddot)
            .collect()
    });
    let mut torque: [Vec<f64>; 3] = Default::default();
    let mut speed: [Vec<f64>; 3] = Default::default();
    let mut motor = true;
    for i in 0..3 {
        for (f, state) in force[i].iter().zip(states) {
            match actuator.required(*f, state.legs[i].rho_dot) {
                Some((tau, n)) => {
                    torque[i].push(tau);
                    speed[i].push(n);
                }
                None => motor = false,
            }
        }
    }
    Required {
        force,
        motor: motor.then_some((torque, speed)),
        peak_torque: actuator.ratings().map(|r| r.peak_torque),
    }
}

/// One leg's requirement against the ratings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegRequirement {
    /// Largest required torque magnitude (N m) and when.
    pub peak_torque: Peak,
    /// RMS of the required torque over the time span (N m): the root of the time mean of
    /// its square.
    pub rms_torque: f64,
    /// Largest required motor speed magnitude (rev/s) and when.
    pub peak_speed: Peak,
    /// First time the required torque exceeds the peak torque (s).
    pub over_torque: Option<f64>,
    /// First time the required speed exceeds the largest speed (s).
    pub over_speed: Option<f64>,
    /// With a drive: the largest steady-state winding voltage `R tau / K_t + K_e omega`
    /// (V) and when, its first time beyond the bus voltage, the largest current (A) and
    /// its first time beyond the current limit.
    pub electrical: Option<Electrical>,
}

/// One leg's electrical requirement on a motor with a [`Drive`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Electrical {
    /// Largest winding voltage magnitude (V) and when.
    pub peak_voltage: Peak,
    /// First time the voltage exceeds the bus voltage (s).
    pub over_voltage: Option<f64>,
    /// Largest current magnitude (A) and when.
    pub peak_current: Peak,
    /// First time the current exceeds the current limit (s).
    pub over_current: Option<f64>,
}

impl LegRequirement {
    /// `peak_torque / max |tau|`, `continuous_torque / rms(tau)`, `max_speed / max |n|`.
    pub fn margins(&self, r: &MotorRatings) -> [Option<f64>; 3] {
        [
            margin(r.peak_torque, self.peak_torque.value),
            margin(r.continuous_torque, self.rms_torque),
            margin(r.max_speed, self.peak_speed.value),
        ]
    }
}

/// The commanded motion against the motors' ratings.
#[derive(Debug, Clone, PartialEq)]
pub struct Feasibility {
    /// The actuator's name (`motor_ballscrew`).
    pub actuator: String,
    /// Its ratings.
    pub ratings: MotorRatings,
    /// Its drive, where modelled.
    pub drive: Option<Drive>,
    /// Each leg's requirement.
    pub legs: [LegRequirement; 3],
    /// Time span the requirement covers (s): the scene's whole time span (the commanded
    /// motion is known there even when a run stops early).
    pub span: (f64, f64),
    /// The largest step of the scan's grid (s): peaks are refined and crossings located
    /// between its points.
    pub grid_step: f64,
    /// Whether the scan's peaks and RMS values converged to [`SCAN_TOLERANCE`].
    pub converged: bool,
}

/// The earliest of per-leg event times, with its leg (0-based).
fn earliest(times: impl Iterator<Item = Option<f64>>) -> Option<(f64, usize)> {
    times
        .enumerate()
        .filter_map(|(i, t)| t.map(|t| (t, i)))
        .min_by(|a, b| a.0.total_cmp(&b.0))
}

impl Feasibility {
    /// The check of the commanded motion of `scene` on `actuator` over the scene's whole
    /// time span, between the output samples ([`crate::scan`]): at every time, the rigid
    /// inverse dynamics gives the force on each slider, `F_a_rigid + m_r rho''`, and the
    /// actuator the torque and speed it needs; their peaks, RMS values and first crossings
    /// of the ratings are found to the scan's resolution, whatever the output step. `None`
    /// when the actuator has no ratings or no motor.
    ///
    /// # Errors
    /// A pose of the commanded motion where the inverse kinematics or the rigid inverse
    /// dynamics fails, with its time.
    pub fn scan(scene: &Scene, actuator: &dyn Actuator) -> Result<Option<Self>, DynamicsError> {
        let Some(ratings) = actuator.ratings() else {
            return Ok(None);
        };
        if actuator.required(0.0, 0.0).is_none() {
            return Ok(None);
        }
        let machine = &scene.machine;
        let reflected = actuator.reflected_mass();
        let drive = actuator.drive();
        let mut requirement = |t: f64, out: &mut [f64]| -> Result<(), DynamicsError> {
            let motion = scene.trajectory.motion(t);
            let state = machine
                .geometry
                .inverse_kinematics_unchecked(&motion)
                .map_err(|source| DynamicsError::Kinematics { t, source })?;
            let reactions = inverse_dynamics(machine, &state, None, t)?;
            for i in 0..3 {
                let leg = &state.legs[i];
                let force = reactions.driving_force[i] + reflected * leg.rho_ddot;
                let (torque, speed) = actuator.required(force, leg.rho_dot).unwrap_or_default();
                out[i] = torque;
                out[3 + i] = speed;
                if let Some(d) = &drive {
                    out[6 + i] = d.voltage(torque, std::f64::consts::TAU * speed);
                    out[9 + i] = d.current(torque);
                }
            }
            Ok(())
        };
        let times = &scene.output_times;
        let span = (times[0], times[times.len() - 1]);
        let mut limits = vec![
            ratings.peak_torque,
            ratings.peak_torque,
            ratings.peak_torque,
            ratings.max_speed,
            ratings.max_speed,
            ratings.max_speed,
        ];
        if let Some(d) = &drive {
            limits.extend([d.bus_voltage; 3]);
            limits.extend([d.current_limit; 3]);
        }
        let found = scan(
            &mut requirement,
            span,
            &scene.trajectory.breakpoints(),
            &limits,
        )?;
        let legs = std::array::from_fn(|i| LegRequirement {
            peak_torque: found.peaks[i],
            rms_torque: found.rms[i],
            peak_speed: found.peaks[3 + i],
            over_torque: found.first_over[i],
            over_speed: found.first_over[3 + i],
            electrical: drive.map(|_| Electrical {
                peak_voltage: found.peaks[6 + i],
                over_voltage: found.first_over[6 + i],
                peak_current: found.peaks[9 + i],
                over_current: found.first_over[9 + i],
            }),
        });
        Ok(Some(Self {
            actuator: actuator.name().to_string(),
            ratings,
            drive,
            legs,
            span,
            grid_step: found.step,
            converged: found.converged,
        }))
    }

    /// Whether every leg stays within every rating (and its drive's bus voltage and
    /// current limit).
    pub fn feasible(&self) -> bool {
        self.legs.iter().all(|l| {
            l.margins(&self.ratings)
                .iter()
                .all(|m| m.is_none_or(|m| m >= 1.0))
                && l.electrical
                    .is_none_or(|e| e.over_voltage.is_none() && e.over_current.is_none())
        })
    }

    /// The first time and leg (0-based) at which the required winding voltage exceeds the
    /// bus voltage (with a drive).
    pub fn first_over_voltage(&self) -> Option<(f64, usize)> {
        earliest(
            self.legs
                .iter()
                .map(|l| l.electrical.and_then(|e| e.over_voltage)),
        )
    }

    /// The first time and leg (0-based) at which the required current exceeds the drive's
    /// current limit.
    pub fn first_over_current(&self) -> Option<(f64, usize)> {
        earliest(
            self.legs
                .iter()
                .map(|l| l.electrical.and_then(|e| e.over_current)),
        )
    }

    /// The first time and leg (0-based) at which the required speed exceeds the rating.
    pub fn first_over_speed(&self) -> Option<(f64, usize)> {
        earliest(self.legs.iter().map(|l| l.over_speed))
    }

    /// The first time and leg (0-based) at which the required torque exceeds the peak.
    pub fn first_over_torque(&self) -> Option<(f64, usize)> {
        earliest(self.legs.iter().map(|l| l.over_torque))
    }

    /// One warning per rating the motion exceeds, naming the first time and leg.
    pub fn warnings(&self) -> Vec<String> {
        let r = &self.ratings;
        let mut out = Vec::new();
        let worst = |f: &dyn Fn(&LegRequirement) -> f64| {
            (0..3).fold(0, |best, i| {
                if f(&self.legs[i]) > f(&self.legs[best]) {
                    i
                } else {
                    best
                }
            })
        };
        if let Some((t, leg)) = self.first_over_speed() {
            let w = worst(&|l| l.peak_speed.value);
            let p = self.legs[w].peak_speed;
            out.push(format!(
                "infeasible motion: the commanded motion needs its {} motors to turn faster \
                 than their max_speed of {} rev/s ({} rpm) from t = {} ms on leg {}, up to {} \
                 rev/s ({} rpm) on leg {} at t = {} ms",
                self.actuator,
                sig(r.max_speed),
                sig(60.0 * r.max_speed),
                sig(1e3 * t),
                leg + 1,
                sig(p.value),
                sig(60.0 * p.value),
                w + 1,
                sig(1e3 * p.t),
            ));
        }
        if let Some((t, leg)) = self.first_over_torque() {
            let w = worst(&|l| l.peak_torque.value);
            let p = self.legs[w].peak_torque;
            out.push(format!(
                "infeasible motion: the commanded motion needs more torque than the {} motors' \
                 peak_torque of {} N m from t = {} ms on leg {}, up to {} N m on leg {} at t = \
                 {} ms",
                self.actuator,
                sig(r.peak_torque),
                sig(1e3 * t),
                leg + 1,
                sig(p.value),
                w + 1,
                sig(1e3 * p.t),
            ));
        }
        if let (Some(d), Some((t, leg))) = (&self.drive, self.first_over_voltage()) {
            let w = worst(&|l| l.electrical.map_or(0.0, |e| e.peak_voltage.value));
            let p = self.legs[w]
                .electrical
                .map(|e| e.peak_voltage)
                .unwrap_or_default();
            out.push(format!(
                "infeasible motion: voltage: the commanded motion needs a winding voltage \
                 (R i + K_e omega, the back-EMF included) above the {} motors' bus_voltage of {} \
                 V from t = {} ms on leg {}, up to {} V on leg {} at t = {} ms (no-load speed \
                 V / K_e = {} rev/s)",
                self.actuator,
                sig(d.bus_voltage),
                sig(1e3 * t),
                leg + 1,
                sig(p.value),
                w + 1,
                sig(1e3 * p.t),
                sig(d.no_load_speed() / std::f64::consts::TAU),
            ));
        }
        if let (Some(d), Some((t, leg))) = (&self.drive, self.first_over_current()) {
            let w = worst(&|l| l.electrical.map_or(0.0, |e| e.peak_current.value));
            let p = self.legs[w]
                .electrical
                .map(|e| e.peak_current)
                .unwrap_or_default();
            out.push(format!(
                "infeasible motion: current: the commanded motion needs more current than the \
                 {} motors' current_limit of {} A from t = {} ms on leg {}, up to {} A on leg {} \
                 at t = {} ms",
                self.actuator,
                sig(d.current_limit),
                sig(1e3 * t),
                leg + 1,
                sig(p.value),
                w + 1,
                sig(1e3 * p.t),
            ));
        }
        let w = worst(&|l| l.rms_torque);
        let rms_torque = self.legs[w].rms_torque;
        if rms_torque > r.continuous_torque {
            out.push(format!(
                "the commanded motion's RMS torque reaches {} N m on leg {} ({} ms to {} ms), \
                 above the {} motors' continuous_torque of {} N m: they overheat if the \
                 motion goes on",
                sig(rms_torque),
                w + 1,
                sig(1e3 * self.span.0),
                sig(1e3 * self.span.1),
                self.actuator,
                sig(r.continuous_torque)
            ));
        }
        out
    }

    /// The `feasibility` section of `summary.json`.
    pub fn to_json(&self) -> Value {
        let r = &self.ratings;
        let legs: Vec<Value> = self
            .legs
            .iter()
            .enumerate()
            .map(|(i, l)| {
                let [peak, continuous, speed] = l.margins(r);
                let mut leg = json!({
                    "leg": i + 1,
                    "peak_torque_N_m": num(l.peak_torque.value),
                    "t_peak_torque_s": num(l.peak_torque.t),
                    "rms_torque_N_m": num(l.rms_torque),
                    "peak_speed_rev_s": num(l.peak_speed.value),
                    "t_peak_speed_s": num(l.peak_speed.t),
                    "peak_torque_margin": number(peak),
                    "continuous_torque_margin": number(continuous),
                    "speed_margin": number(speed),
                    "first_over_peak_torque_s": number(l.over_torque),
                    "first_over_max_speed_s": number(l.over_speed),
                });
                if let Some(e) = &l.electrical {
                    leg["peak_voltage_V"] = num(e.peak_voltage.value);
                    leg["t_peak_voltage_s"] = num(e.peak_voltage.t);
                    leg["first_over_bus_voltage_s"] = number(e.over_voltage);
                    leg["peak_current_A"] = num(e.peak_current.value);
                    leg["t_peak_current_s"] = num(e.peak_current.t);
                    leg["first_over_current_limit_s"] = number(e.over_current);
                }
                leg
            })
            .collect();
        let event = |e: Option<(f64, usize)>| {
            e.map_or(Value::Null, |(t, leg)| json!({ "t_s": t, "leg": leg + 1 }))
        };
        let mut out = json!({
            "actuator": self.actuator,
            "source": "rigid inverse dynamics of the commanded motion over the whole time span, between the output samples",
            "resolution": {
                "grid_step_s": num(self.grid_step),
                "tolerance": SCAN_TOLERANCE,
                "converged": self.converged,
                "method": "grid refined until every peak and RMS value changes by at most the tolerance times the peak; peaks by golden-section search, first crossings by bisection on the requirement itself",
            },
            "span_s": [num(self.span.0), num(self.span.1)],
            "ratings": {
                "peak_torque_N_m": num(r.peak_torque),
                "continuous_torque_N_m": num(r.continuous_torque),
                "max_speed_rev_s": num(r.max_speed),
            },
            "feasible": self.feasible(),
            "first_over_max_speed": event(self.first_over_speed()),
            "first_over_peak_torque": event(self.first_over_torque()),
            "legs": legs,
        });
        if let Some(d) = &self.drive {
            out["drive"] = json!({
                "torque_constant_N_m_A": num(d.torque_constant),
                "resistance_ohm": num(d.resistance),
                "bus_voltage_V": num(d.bus_voltage),
                "current_limit_A": number(Some(d.current_limit)),
                "no_load_speed_rev_s": num(d.no_load_speed() / std::f64::consts::TAU),
            });
            out["first_over_bus_voltage"] = event(self.first_over_voltage());
            out["first_over_current_limit"] = event(self.first_over_current());
        }
        out
    }
}
