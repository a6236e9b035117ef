//! Vibration control of the links by piezoelectric patches (docs/piezo.md): a
//! [`VibrationController`] maps the patches' sensor signals to their actuator voltages.
//!
//! * [`StrainRate`] (`kind = "strain_rate"`): collocated strain-rate feedback, each patch
//!   driven by its own sensor's rate, `V_p = -G dV_s,p/dt` (Sun & Huang, "Vibration suppression
//!   of laminated plates using strain rate feedback", 2000; the group's follow-up on the
//!   3-PRR uses it).
//! * [`ModalVelocity`] (`kind = "modal_velocity"`): a modal filter estimates the modal
//!   velocities of the targeted modes from the sensor rates (least squares), and the patches
//!   apply modal forces `f_j = -g_j eta_j'` (least squares again): independent modal space
//!   control (Meirovitch & Baruh, "Control of self-adjoint distributed-parameter systems",
//!   J. Guidance 5 (1982) 60-66).

use std::fmt;

use crate::ControlError;
use crate::error::check;

/// What a vibration control law sees at time `t`.
#[derive(Debug, Clone, Copy)]
pub struct VibrationInput<'a> {
    /// Time (s).
    pub t: f64,
    /// The patches' sensor voltages (V), in the scene's patch order.
    pub sensors: &'a [f64],
    /// Their rates (V/s).
    pub sensor_rates: &'a [f64],
}

/// A vibration control law: the patches' actuator voltages from their sensors, registered
/// by name like the slider control laws (`vibration_control.kind` in a scene).
///
/// Required: [`VibrationController::voltages`]. Provided: a continuous law (`period` 0), a
/// name. The model clips the voltages at each patch's limit and reports when it does.
///
/// ```
/// use flexprr_control::{VibrationController, VibrationInput};
///
/// /// Negative position feedback of each collocated pair: V = -k V_s.
/// #[derive(Debug)]
/// struct PositionFeedback(f64);
/// impl VibrationController for PositionFeedback {
///     fn voltages(&self, input: &VibrationInput<'_>, voltages: &mut [f64]) {
///         for (v, s) in voltages.iter_mut().zip(input.sensors) {
///             *v = -self.0 * s;
///         }
///     }
/// }
/// let mut v = [0.0; 2];
/// let input = VibrationInput { t: 0.0, sensors: &[0.5, -1.0], sensor_rates: &[0.0, 0.0] };
/// PositionFeedback(10.0).voltages(&input, &mut v);
/// assert!((v[1] - 10.0).abs() < 1e-12);
/// ```
pub trait VibrationController: fmt::Debug + Send + Sync {
    /// The actuator voltage of each patch (V) at `input`, one per sensor. Must not allocate:
    /// it runs inside the right-hand side.
    fn voltages(&self, input: &VibrationInput<'_>, voltages: &mut [f64]);
    /// Sample period (s): 0 for a continuous law; greater than 0 for a sampled law whose
    /// voltages are held (zero-order hold) between samples.
    fn period(&self) -> f64 {
        0.0
    }
    /// The law's name, for summaries.
    fn name(&self) -> String {
        "custom".to_string()
    }
}

/// `kind = "strain_rate"`: `V_p = -G dV_s,p/dt` for each collocated pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrainRate {
    gain: f64,
    period: f64,
}

impl StrainRate {
    /// Strain-rate feedback of gain `gain` (s: volts out per volt per second of the sensor),
    /// sample `period` (s, 0 for continuous).
    ///
    /// # Errors
    /// A negative or non-finite gain or period.
    pub fn new(gain: f64, period: f64) -> Result<Self, ControlError> {
        Ok(Self {
            gain: check("gain", gain, 0.0, false, "must be finite and >= 0 (s)")?,
            period: check(
                "period",
                period,
                0.0,
                false,
                "must be finite and >= 0 (0 for a continuous controller)",
            )?,
        })
    }

    /// The gain `G` (s).
    pub fn gain(&self) -> f64 {
        self.gain
    }
}

impl VibrationController for StrainRate {
    fn voltages(&self, input: &VibrationInput<'_>, voltages: &mut [f64]) {
        for (v, rate) in voltages.iter_mut().zip(input.sensor_rates) {
            *v = -self.gain * rate;
        }
    }
    fn period(&self) -> f64 {
        self.period
    }
    fn name(&self) -> String {
        "strain_rate".to_string()
    }
}

/// `kind = "modal_velocity"`: modal velocity feedback through a modal filter.
///
/// With `S` the sensing matrix (sensor volts per unit modal coordinate, patches x modes) and
/// `B` the forcing matrix (modal force per actuator volt, modes x patches), both restricted to
/// the targeted modes, the modal velocities are estimated as `eta_t' = S_t^+ V_s'` and the
/// voltages are `V = -B_t^+ diag(g) eta_t'` (least-squares pseudo-inverses: exact when there
/// are as many patches as targeted modes and they see them independently).
#[derive(Debug, Clone, PartialEq)]
pub struct ModalVelocity {
    /// `diag(g) S_t^+`: damping forces of the targeted modes per sensor rate (targets x patches).
    filter: Vec<f64>,
    /// `B_t^+` (patches x targets).
    drive: Vec<f64>,
    targets: usize,
    patches: usize,
    period: f64,
}

/// The least-squares pseudo-inverse `(A^T A)^-1 A^T` of `a` (`rows x cols`, row-major,
/// `rows >= cols`, full column rank), row-major `cols x rows`.
fn pseudo_inverse(a: &[f64], rows: usize, cols: usize) -> Option<Vec<f64>> {
    let mut normal = vec![0.0; cols * cols];
    for i in 0..cols {
        for j in 0..cols {
            normal[i * cols + j] = (0..rows).map(|k| a[k * cols + i] * a[k * cols + j]).sum();
        }
    }
    // Gauss-Jordan inverse of the normal matrix with partial pivoting.
    let mut inverse = vec![0.0; cols * cols];
    for i in 0..cols {
        inverse[i * cols + i] = 1.0;
    }
    let scale = normal.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    for k in 0..cols {
        let p = (k..cols).max_by(|&x, &y| {
            normal[x * cols + k]
                .abs()
                .total_cmp(&normal[y * cols + k].abs())
        })?;
        if normal[p * cols + k].abs() <= 1e-12 * scale {
            return None;
        }
        for j in 0..cols {
            normal.swap(k * cols + j, p * cols + j);
            inverse.swap(k * cols + j, p * cols + j);
        }
        let pivot = normal[k * cols + k];
        for j in 0..cols {
            normal[k * cols + j] /= pivot;
            inverse[k * cols + j] /= pivot;
        }
        for i in 0..cols {
            if i != k {
                let f = normal[i * cols + k];
                for j in 0..cols {
                    normal[i * cols + j] -= f * normal[k * cols + j];
                    inverse[i * cols + j] -= f * inverse[k * cols + j];
                }
            }
        }
    }
    let mut out = vec![0.0; cols * rows];
    for i in 0..cols {
        for k in 0..rows {
            out[i * rows + k] = (0..cols)
                .map(|j| inverse[i * cols + j] * a[k * cols + j])
                .sum();
        }
    }
    Some(out)
}

impl ModalVelocity {
    /// The law for `sensing[p][j]` (V per unit of targeted mode `j` at patch `p`),
    /// `forcing[j][p]` (modal force of targeted mode `j` per volt on patch `p`) and the
    /// modal damping gains `gains[j]` (N s/m per unit modal velocity), sample `period`.
    ///
    /// # Errors
    /// Mismatched sizes, more targeted modes than patches, targeted modes the patches
    /// cannot tell apart, or a negative gain or period.
    pub fn new(
        sensing: &[Vec<f64>],
        forcing: &[Vec<f64>],
        gains: &[f64],
        period: f64,
    ) -> Result<Self, ControlError> {
        let (patches, targets) = (sensing.len(), gains.len());
        let bad = |rule: &'static str| ControlError::InvalidParameter {
            name: "modes",
            value: targets as f64,
            rule,
        };
        if targets == 0 || targets > patches {
            return Err(bad(
                "target at least one mode and no more modes than there are patches to sense them",
            ));
        }
        if sensing.iter().any(|row| row.len() != targets)
            || forcing.len() != targets
            || forcing.iter().any(|row| row.len() != patches)
        {
            return Err(bad(
                "the sensing and forcing matrices must match the targeted modes",
            ));
        }
        for g in gains {
            check("gains", *g, 0.0, false, "must be finite and >= 0 (N s/m)")?;
        }
        let period = check(
            "period",
            period,
            0.0,
            false,
            "must be finite and >= 0 (0 for a continuous controller)",
        )?;
        let s: Vec<f64> = sensing.iter().flatten().copied().collect();
        let estimate = pseudo_inverse(&s, patches, targets).ok_or_else(|| {
            bad("the patches cannot tell the targeted modes apart (singular modal filter)")
        })?;
        // B is targets x patches; its pseudo-inverse B^T (B B^T)^-1 is patches x targets:
        // the transpose of the pseudo-inverse of B^T.
        let bt: Vec<f64> = (0..patches)
            .flat_map(|p| forcing.iter().map(move |row| row[p]))
            .collect();
        let drive_t = pseudo_inverse(&bt, patches, targets)
            .ok_or_else(|| bad("the patches cannot force the targeted modes independently"))?;
        let drive = (0..patches)
            .flat_map(|p| (0..targets).map(move |j| (p, j)))
            .map(|(p, j)| drive_t[j * patches + p])
            .collect();
        let filter = (0..targets)
            .flat_map(|j| (0..patches).map(move |p| (j, p)))
            .map(|(j, p)| gains[j] * estimate[j * patches + p])
            .collect();
        Ok(Self {
            filter,
            drive,
            targets,
            patches,
            period,
        })
    }
}

impl VibrationController for ModalVelocity {
    fn voltages(&self, input: &VibrationInput<'_>, voltages: &mut [f64]) {
        voltages.fill(0.0);
        for j in 0..self.targets {
            let force: f64 = (0..self.patches)
                .map(|p| self.filter[j * self.patches + p] * input.sensor_rates[p])
                .sum();
            for (p, v) in voltages.iter_mut().enumerate().take(self.patches) {
                *v -= self.drive[p * self.targets + j] * force;
            }
        }
    }
    fn period(&self) -> f64 {
        self.period
    }
    fn name(&self) -> String {
        "modal_velocity".to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strain_rate_feedback_opposes_the_sensor_rate() {
        let law = StrainRate::new(0.5, 0.0).unwrap();
        let mut v = [0.0; 2];
        let input = VibrationInput {
            t: 0.0,
            sensors: &[0.0, 0.0],
            sensor_rates: &[10.0, -4.0],
        };
        law.voltages(&input, &mut v);
        assert!((v[0] + 5.0).abs() < 1e-12 && (v[1] - 2.0).abs() < 1e-12);
        assert!(StrainRate::new(-1.0, 0.0).is_err());
    }

    #[test]
    fn the_modal_filter_recovers_the_modal_velocities_and_forces_them() {
        // Two patches, two modes: sensing S (patches x modes), forcing B = S^T (collocated).
        let sensing = vec![vec![2.0, 1.0], vec![1.0, -3.0]];
        let forcing = vec![vec![2.0, 1.0], vec![1.0, -3.0]];
        let law = ModalVelocity::new(&sensing, &forcing, &[5.0, 7.0], 0.0).unwrap();
        // Modal velocities (0.3, -0.2): sensor rates S eta'.
        let eta = [0.3, -0.2];
        let rates = [2.0 * 0.3 + 1.0 * -0.2, 1.0 * 0.3 - 3.0 * -0.2];
        let mut v = [0.0; 2];
        law.voltages(
            &VibrationInput {
                t: 0.0,
                sensors: &[0.0, 0.0],
                sensor_rates: &rates,
            },
            &mut v,
        );
        // The modal forces B V must be -g eta'.
        for j in 0..2 {
            let force: f64 = (0..2).map(|p| forcing[j][p] * v[p]).sum();
            let expected = -[5.0, 7.0][j] * eta[j];
            assert!(
                (force - expected).abs() < 1e-12,
                "mode {j}: {force} {expected}"
            );
        }
        assert!(
            ModalVelocity::new(&[vec![1.0, 2.0]], &[vec![1.0], vec![2.0]], &[1.0, 1.0], 0.0)
                .is_err()
        );
    }
}
