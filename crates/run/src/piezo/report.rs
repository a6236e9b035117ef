//! What a run found about its patches: voltages against the limits, saturation, the work of
//! the actuators, and the reduction of the mid-point deflection against the uncontrolled run.

use flexprr_dynamics::PatchState;
use flexprr_scene::Scene;
use serde_json::{Value, json};

/// `null` for a non-finite number.
fn finite(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

/// `sqrt(mean(x_k^2))` over the samples (the RMS over the span for evenly spaced output
/// times; 0 for an empty series).
fn rms(x: &[f64]) -> f64 {
    if x.is_empty() {
        return 0.0;
    }
    (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
}

/// `100 (1 - controlled / uncontrolled)`: how much smaller the controlled value is (%);
/// `None` when the uncontrolled value is zero.
fn reduction_percent(controlled: f64, uncontrolled: f64) -> Option<f64> {
    (uncontrolled > 0.0).then(|| 100.0 * (1.0 - controlled / uncontrolled))
}

/// One patch over the run.
#[derive(Debug, Clone, PartialEq)]
pub struct PatchSummary {
    /// Its link (0-based).
    pub link: usize,
    /// Its index among the patches of its link (0-based).
    pub index: usize,
    /// Its span along the link.
    pub xi: [f64; 2],
    /// The voltage limit (V).
    pub voltage_limit: f64,
    /// `max |V|` applied (V).
    pub max_abs_voltage: f64,
    /// `max |V_command|` (V): above the limit when the patch saturated.
    pub max_abs_command: f64,
    /// `max |V_s|` (V).
    pub max_abs_sensor: f64,
    /// The fraction of the output samples at which the command was clipped.
    pub saturated_fraction: f64,
    /// The first output time at which it was clipped (s).
    pub first_saturated_s: Option<f64>,
    /// The work the actuator did on the link over the run (J, trapezoidal rule over the
    /// output samples of the power; negative when it removed energy).
    pub work_j: f64,
    /// `max |P|` (W).
    pub max_abs_power: f64,
}

/// The mid-point deflection of a link with and without vibration control.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkReduction {
    /// The link (0-based).
    pub link: usize,
    /// `max |w(l/2)|` with control (m).
    pub peak_controlled: f64,
    /// The same without control (m).
    pub peak_uncontrolled: f64,
    /// RMS of `w(l/2)` over the output samples with control (m).
    pub rms_controlled: f64,
    /// The same without control (m).
    pub rms_uncontrolled: f64,
}

impl LinkReduction {
    /// From the two series of the mid-point deflection of link `link`.
    pub fn of(link: usize, controlled: &[f64], uncontrolled: &[f64]) -> Self {
        let peak = |x: &[f64]| x.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        Self {
            link,
            peak_controlled: peak(controlled),
            peak_uncontrolled: peak(uncontrolled),
            rms_controlled: rms(controlled),
            rms_uncontrolled: rms(uncontrolled),
        }
    }

    /// Reduction of the peak (%): `100 (1 - controlled / uncontrolled)`.
    pub fn peak_reduction_percent(&self) -> Option<f64> {
        reduction_percent(self.peak_controlled, self.peak_uncontrolled)
    }

    /// Reduction of the RMS value (%).
    pub fn rms_reduction_percent(&self) -> Option<f64> {
        reduction_percent(self.rms_controlled, self.rms_uncontrolled)
    }
}

/// The patches of a run under their law, and the comparison with the uncontrolled run.
#[derive(Debug, Clone, PartialEq)]
pub struct PiezoReport {
    /// The law's name (`strain_rate`, `modal_velocity`, `none (sensors only)`).
    pub law: String,
    /// Its sample period (s; 0 for a continuous law).
    pub period_s: f64,
    /// Each patch, in the scene's order.
    pub patches: Vec<PatchSummary>,
    /// Whether the scene was also run without its law.
    pub uncontrolled_run: bool,
    /// Why that run gave no comparison, when it failed.
    pub uncontrolled_failure: Option<String>,
    /// Per link, the mid-point deflection with and without control.
    pub reduction: Option<Vec<LinkReduction>>,
}

impl PiezoReport {
    /// The summary of the patches' `states` (one list per output time `t`).
    pub(crate) fn of(scene: &Scene, t: &[f64], states: &[Vec<PatchState>]) -> Self {
        let patches = scene
            .patches
            .iter()
            .enumerate()
            .map(|(p, patch)| {
                let max = |f: fn(&PatchState) -> f64| {
                    states.iter().fold(0.0_f64, |m, s| m.max(f(&s[p]).abs()))
                };
                let saturated = states.iter().filter(|s| s[p].saturated).count();
                let first = states.iter().position(|s| s[p].saturated).map(|k| t[k]);
                let work = (1..states.len().min(t.len()))
                    .map(|k| {
                        0.5 * (states[k][p].power + states[k - 1][p].power) * (t[k] - t[k - 1])
                    })
                    .sum();
                PatchSummary {
                    link: patch.link,
                    index: super::index_on_link(scene, p),
                    xi: [patch.xi_start, patch.xi_end],
                    voltage_limit: patch.voltage_limit,
                    max_abs_voltage: max(|s| s.voltage),
                    max_abs_command: max(|s| s.command),
                    max_abs_sensor: max(|s| s.sensor),
                    saturated_fraction: saturated as f64 / states.len().max(1) as f64,
                    first_saturated_s: first,
                    work_j: work,
                    max_abs_power: max(|s| s.power),
                }
            })
            .collect();
        let law = scene.patch_control().map(|c| c.controller);
        Self {
            law: law.as_ref().map_or_else(String::new, |c| c.name()),
            period_s: law.as_ref().map_or(0.0, |c| c.period()),
            patches,
            uncontrolled_run: false,
            uncontrolled_failure: None,
            reduction: None,
        }
    }

    /// Whether any patch saturated.
    pub fn any_saturated(&self) -> bool {
        self.patches.iter().any(|p| p.saturated_fraction > 0.0)
    }

    /// The warnings of the run: a patch that saturated, a comparison run that failed.
    pub fn warnings(&self) -> Vec<String> {
        let mut out: Vec<String> = self
            .patches
            .iter()
            .filter(|p| p.saturated_fraction > 0.0)
            .map(|p| {
                format!(
                    "vibration control: patch {} of link {} ([{}, {}]) saturated at its {} V limit \
                     for {:.1} % of the output samples, from t = {:.5} s (command up to {:.1} V)",
                    p.index + 1,
                    p.link + 1,
                    p.xi[0],
                    p.xi[1],
                    p.voltage_limit,
                    100.0 * p.saturated_fraction,
                    p.first_saturated_s.unwrap_or(f64::NAN),
                    p.max_abs_command
                )
            })
            .collect();
        if let Some(why) = &self.uncontrolled_failure {
            out.push(format!(
                "vibration control: the comparison run without control failed ({why}); no \
                 reduction reported"
            ));
        }
        out
    }

    /// The `vibration_control` section of `summary.json`.
    pub fn to_json(&self) -> Value {
        let patches: Vec<Value> = self
            .patches
            .iter()
            .map(|p| {
                json!({
                    "link": p.link + 1,
                    "index": p.index + 1,
                    "xi": p.xi,
                    "voltage_limit_V": p.voltage_limit,
                    "max_abs_voltage_V": finite(p.max_abs_voltage),
                    "max_abs_command_V": finite(p.max_abs_command),
                    "max_abs_sensor_V": finite(p.max_abs_sensor),
                    "saturated": p.saturated_fraction > 0.0,
                    "saturated_fraction": finite(p.saturated_fraction),
                    "first_saturated_s": p.first_saturated_s,
                    "actuator_work_J": finite(p.work_j),
                    "max_abs_power_W": finite(p.max_abs_power),
                })
            })
            .collect();
        let links = self.reduction.as_ref().map(|r| {
            r.iter()
                .map(|l| {
                    json!({
                        "link": l.link + 1,
                        "xi": super::REDUCTION_XI,
                        "peak_controlled_m": finite(l.peak_controlled),
                        "peak_uncontrolled_m": finite(l.peak_uncontrolled),
                        "peak_reduction_percent": l.peak_reduction_percent().map(finite),
                        "rms_controlled_m": finite(l.rms_controlled),
                        "rms_uncontrolled_m": finite(l.rms_uncontrolled),
                        "rms_reduction_percent": l.rms_reduction_percent().map(finite),
                    })
                })
                .collect::<Vec<_>>()
        });
        let max_voltage = self
            .patches
            .iter()
            .fold(0.0_f64, |m, p| m.max(p.max_abs_voltage));
        let fraction = self
            .patches
            .iter()
            .fold(0.0_f64, |m, p| m.max(p.saturated_fraction));
        json!({
            "law": self.law,
            "period_s": self.period_s,
            "uncontrolled_run": self.uncontrolled_run,
            "uncontrolled_failure": self.uncontrolled_failure,
            "any_saturated": self.any_saturated(),
            "max_saturated_fraction": finite(fraction),
            "max_abs_voltage_V": finite(max_voltage),
            "patches": patches,
            "links": links,
        })
    }
}

impl crate::report::Report for PiezoReport {
    fn name(&self) -> &'static str {
        "piezo"
    }

    /// `vibration_control`.
    fn sections(&self) -> Vec<(&'static str, Value)> {
        vec![("vibration_control", self.to_json())]
    }

    fn warnings(&self) -> Vec<String> {
        PiezoReport::warnings(self)
    }

    /// Each patch's largest voltage and saturation, then each link's mid-point deflection
    /// with and without the law.
    fn print(&self) -> Vec<String> {
        let mut lines: Vec<String> = self
            .patches
            .iter()
            .map(|p| {
                format!(
                    "  patch {} of link {}: max |V| {:.1} V of {} V{}",
                    p.index + 1,
                    p.link + 1,
                    p.max_abs_voltage,
                    p.voltage_limit,
                    if p.saturated_fraction > 0.0 {
                        format!(
                            ", saturated {:.1} % of the time",
                            100.0 * p.saturated_fraction
                        )
                    } else {
                        String::new()
                    }
                )
            })
            .collect();
        for l in self.reduction.iter().flatten() {
            let percent = |r: Option<f64>| r.map_or("-".to_string(), |r| format!("{r:.1} %"));
            lines.push(format!(
                "  link {} mid-point deflection with/without {}: peak {:.3e}/{:.3e} m ({} lower), RMS {:.3e}/{:.3e} m ({} lower)",
                l.link + 1,
                self.law,
                l.peak_controlled,
                l.peak_uncontrolled,
                percent(l.peak_reduction_percent()),
                l.rms_controlled,
                l.rms_uncontrolled,
                percent(l.rms_reduction_percent()),
            ));
        }
        lines
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}
