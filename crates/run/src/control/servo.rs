//! The servo summary of a run whose sliders are actuated: tracking errors, actuator forces
//! and, where a motor is modelled, its torque against the ratings, the saturated fraction
//! of time and when the motor speed first exceeds its largest speed.

use flexprr_control::{MOTOR_SPEED, MOTOR_TORQUE, MotorRatings};
use flexprr_dynamics::MachineSnapshot;
use flexprr_scene::Scene;
use serde_json::{Value, json};

use crate::samples::Samples;
use flexprr_requirement::stats::{Peak, first_crossing, margin, num, number, rms, sig};

/// One slider of an actuated run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SliderSummary {
    /// Largest tracking error `|rho_ref - rho|` (m) and when.
    pub error: Peak,
    /// RMS tracking error (m).
    pub rms_error: f64,
    /// Largest force on the slider (N) and when.
    pub force: Peak,
    /// RMS force on the slider (N).
    pub rms_force: f64,
    /// Where a motor is modelled: largest torque (N m) and when.
    pub torque: Option<Peak>,
    /// Where a motor is modelled: RMS torque (N m).
    pub rms_torque: Option<f64>,
    /// Where a motor is modelled: fraction of the output times at which the torque is
    /// saturated.
    pub saturated_fraction: Option<f64>,
    /// Where a motor is modelled: largest motor speed (rev/s) and when.
    pub speed: Option<Peak>,
    /// Where a motor is modelled: first time the motor speed exceeds its largest speed (s).
    pub over_speed: Option<f64>,
}

/// The platform's tracking errors (commanded minus actual pose).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlatformSummary {
    /// Largest position error `sqrt(e_x^2 + e_y^2)` (m) and when.
    pub position: Peak,
    /// RMS position error (m).
    pub rms_position: f64,
    /// Largest orientation error (rad) and when.
    pub orientation: Peak,
    /// RMS orientation error (rad).
    pub rms_orientation: f64,
}

/// Tracking and actuator loads of an actuated run, at its output times.
#[derive(Debug, Clone, PartialEq)]
pub struct ServoSummary {
    /// The control law (`control.kind`).
    pub controller: String,
    /// The actuator's name.
    pub actuator: String,
    /// The motor ratings, where a motor is modelled.
    pub ratings: Option<MotorRatings>,
    /// Each slider.
    pub sliders: [SliderSummary; 3],
    /// The platform.
    pub platform: PlatformSummary,
}

impl ServoSummary {
    /// The summary of the snapshots of an actuated model against the commanded motion of
    /// `samples` (both at the same output times; the shorter length counts).
    pub(crate) fn of(scene: &Scene, samples: &Samples, snapshots: &[MachineSnapshot]) -> Self {
        let n = snapshots.len().min(samples.len());
        let t = &samples.t[..n];
        let ratings = scene.actuator.as_ref().and_then(|a| a.ratings());
        let sliders = std::array::from_fn(|i| {
            let error: Vec<f64> = (0..n)
                .map(|k| samples.states[k].legs[i].rho - snapshots[k].sliders[i].position)
                .collect();
            let state = |k: usize| snapshots[k].actuators.map(|a| a[i]).unwrap_or_default();
            let force: Vec<f64> = (0..n).map(|k| state(k).output.force).collect();
            let torque: Option<Vec<f64>> = (0..n)
                .map(|k| state(k).output.signal(MOTOR_TORQUE))
                .collect();
            let speed: Option<Vec<f64>> = (0..n)
                .map(|k| state(k).output.signal(MOTOR_SPEED))
                .collect();
            let saturated = (0..n).filter(|&k| state(k).output.saturated).count();
            let motor = torque.is_some() && n > 0;
            SliderSummary {
                error: Peak::of(t, &error),
                rms_error: rms(&error),
                force: Peak::of(t, &force),
                rms_force: rms(&force),
                torque: torque.as_deref().map(|x| Peak::of(t, x)),
                rms_torque: torque.as_deref().map(rms),
                saturated_fraction: motor.then(|| saturated as f64 / n as f64),
                speed: speed.as_deref().map(|x| Peak::of(t, x)),
                over_speed: speed
                    .as_deref()
                    .zip(ratings)
                    .and_then(|(x, r)| first_crossing(t, x, r.max_speed)),
            }
        });
        let pose_error = |k: usize| {
            let (c, a) = (&samples.motions[k].pose, &snapshots[k].platform.pose);
            [c.x - a.x, c.y - a.y, c.phi - a.phi]
        };
        let position: Vec<f64> = (0..n)
            .map(|k| {
                let e = pose_error(k);
                e[0].hypot(e[1])
            })
            .collect();
        let orientation: Vec<f64> = (0..n).map(|k| pose_error(k)[2]).collect();
        Self {
            controller: scene
                .file
                .control
                .as_ref()
                .map_or_else(|| "custom".to_string(), |c| c.kind.clone()),
            actuator: scene
                .actuator
                .as_ref()
                .map_or_else(|| "force".to_string(), |a| a.name().to_string()),
            ratings,
            sliders,
            platform: PlatformSummary {
                position: Peak::of(t, &position),
                rms_position: rms(&position),
                orientation: Peak::of(t, &orientation),
                rms_orientation: rms(&orientation),
            },
        }
    }

    /// The first time and slider (0-based) at which the motor speed exceeds its largest
    /// speed.
    pub fn first_over_speed(&self) -> Option<(f64, usize)> {
        self.sliders
            .iter()
            .enumerate()
            .filter_map(|(i, s)| s.over_speed.map(|t| (t, i)))
            .min_by(|a, b| a.0.total_cmp(&b.0))
    }

    /// Warnings: the motor speed beyond its largest speed (not enforced by the model), the
    /// RMS torque beyond the continuous torque.
    pub fn warnings(&self) -> Vec<String> {
        let mut out = Vec::new();
        let Some(r) = self.ratings else {
            return out;
        };
        if let Some((t, i)) = self.first_over_speed() {
            let peak = self.sliders[i].speed.unwrap_or_default();
            out.push(format!(
                "the motor of slider {} turns faster than its max_speed of {} rev/s ({} rpm) \
                 from t = {} ms, up to {} rev/s at t = {} ms: the model does not limit the \
                 speed, so this run goes beyond what the motor can do",
                i + 1,
                sig(r.max_speed),
                sig(60.0 * r.max_speed),
                sig(1e3 * t),
                sig(peak.value),
                sig(1e3 * peak.t)
            ));
        }
        let hot: Vec<(usize, f64)> = self
            .sliders
            .iter()
            .enumerate()
            .filter_map(|(i, s)| {
                s.rms_torque
                    .filter(|x| *x > r.continuous_torque)
                    .map(|x| (i, x))
            })
            .collect();
        if !hot.is_empty() {
            let which: Vec<String> = hot.iter().map(|(i, _)| (i + 1).to_string()).collect();
            let values: Vec<String> = hot.iter().map(|(_, x)| sig(*x)).collect();
            out.push(format!(
                "the RMS torque of the motors of {} ({} N m) is above their \
                 continuous_torque of {} N m: they overheat if the motion goes on",
                if hot.len() == 1 {
                    format!("slider {}", which[0])
                } else {
                    format!("sliders {}", which.join(", "))
                },
                values.join(", "),
                sig(r.continuous_torque)
            ));
        }
        out
    }

    /// The `control` section of `summary.json`.
    pub fn to_json(&self) -> Value {
        let sliders: Vec<Value> = self
            .sliders
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let mut v = json!({
                    "slider": i + 1,
                    "peak_error_m": num(s.error.value),
                    "t_peak_error_s": num(s.error.t),
                    "rms_error_m": num(s.rms_error),
                    "peak_force_N": num(s.force.value),
                    "rms_force_N": num(s.rms_force),
                });
                if let (Some(torque), Some(rms_torque), Some(object)) =
                    (s.torque, s.rms_torque, v.as_object_mut())
                {
                    let r = self.ratings;
                    let entries = [
                        ("peak_torque_N_m", num(torque.value)),
                        ("t_peak_torque_s", num(torque.t)),
                        ("rms_torque_N_m", num(rms_torque)),
                        (
                            "peak_torque_margin",
                            number(r.and_then(|r| margin(r.peak_torque, torque.value))),
                        ),
                        (
                            "continuous_torque_margin",
                            number(r.and_then(|r| margin(r.continuous_torque, rms_torque))),
                        ),
                        ("saturated_fraction", number(s.saturated_fraction)),
                        ("peak_speed_rev_s", number(s.speed.map(|p| p.value))),
                        (
                            "speed_margin",
                            number(
                                r.zip(s.speed)
                                    .and_then(|(r, p)| margin(r.max_speed, p.value)),
                            ),
                        ),
                        ("first_over_max_speed_s", number(s.over_speed)),
                    ];
                    for (key, value) in entries {
                        object.insert(key.to_string(), value);
                    }
                }
                v
            })
            .collect();
        let p = &self.platform;
        json!({
            "controller": self.controller,
            "actuator": self.actuator,
            "ratings": self.ratings.map(|r| json!({
                "peak_torque_N_m": num(r.peak_torque),
                "continuous_torque_N_m": num(r.continuous_torque),
                "max_speed_rev_s": num(r.max_speed),
            })),
            "sliders": sliders,
            "platform": {
                "peak_position_error_m": num(p.position.value),
                "t_peak_position_error_s": num(p.position.t),
                "rms_position_error_m": num(p.rms_position),
                "peak_orientation_error_rad": num(p.orientation.value),
                "t_peak_orientation_error_s": num(p.orientation.t),
                "rms_orientation_error_rad": num(p.rms_orientation),
            },
            "first_over_max_speed": self.first_over_speed().map_or(Value::Null, |(t, i)| {
                json!({ "t_s": t, "slider": i + 1 })
            }),
        })
    }
}
