//! The `machine_frequencies` output (docs/linear.md): the whole machine's lowest natural
//! frequencies and damping ratios along the motion. At (at most [`MAX_INSTANTS`] of) the
//! output times the run's own model is linearised about its integrated state
//! (`flexprr_linear::linearize`: the motion's axial loads, centrifugal and gyroscopic
//! terms and the controller are in `A`), with nothing integrated again; the eigenvalues of
//! each `A` give the frequencies (`flexprr_linear::modes`). Beside them, for comparison,
//! each link's first KED frequency (the per-link pinned-pinned estimate of the
//! `frequencies` output) at the same instants.
//!
//! The frequencies of a frozen `A` along a motion are the instantaneous ("frozen-time")
//! frequencies of a slowly varying system: meaningful while the motion changes little over
//! a period of the mode, as for the bending modes of the paper's 20 Hz circle.

use std::time::Instant;

use flexprr_dynamics::{FrequencyHistory, ModalSystem, SceneModel};
use flexprr_integrators::Solution;
use flexprr_linear::{LinearError, Mode, linearize, modes};
use flexprr_plot::decimate::frame_indices;
use serde_json::{Value, json};

use crate::column::{Column, Quantity as Q};
use crate::error::RunError;
use crate::table::Table;

pub use flexprr_figures::columns::{MACHINE_DAMPING_RATIO, MACHINE_FREQUENCY};

/// Most instants linearised: every `ceil((n - 1) / 200)`-th output time, with the first
/// and the last (201 of 2001 output times, for instance).
pub const MAX_INSTANTS: usize = 201;

/// Most modes tabulated per instant.
pub const MAX_MODES: usize = 12;

/// Share of a run's progress given to its integration when it also linearises along the
/// motion, for a model whose state has `dimension` entries; the linearisations take the
/// rest. Their cost grows with the state (`4 n` right-hand sides and an `n x n` eigenvalue
/// problem per instant) while the integration's grows with the time span: measured, the
/// linearisations of a coupled run (18-24 states) take a few percent of it, those of the
/// nonlinear model with 16 elements (288 states) several times its integration over 50 ms.
/// `1 / (1 + n / 100)` follows both.
pub(crate) fn integration_share(dimension: usize) -> f64 {
    1.0 / (1.0 + dimension as f64 / 100.0)
}

/// What the `machine_frequencies` output did, for `summary.json`.
#[derive(Debug, Clone, PartialEq)]
pub struct MachineFrequencyNote {
    /// Instants linearised.
    pub instants: usize,
    /// Output times the run reached.
    pub output_times: usize,
    /// Every how many output times an instant was taken.
    pub stride: usize,
    /// Modes tabulated per instant: the lowest `min(12, fewest found at any instant)`.
    pub modes: usize,
    /// Wall-clock time of the linearisations and eigenvalues (s).
    pub wall_time_s: f64,
}

impl MachineFrequencyNote {
    /// The `machine_frequencies` section of `summary.json`.
    pub fn to_json(&self) -> Value {
        json!({
            "instants": self.instants,
            "output_times": self.output_times,
            "stride": self.stride,
            "modes": self.modes,
            "wall_time_s": self.wall_time_s,
            "note": format!(
                "the model linearised about its integrated state at every {}-th of {} output times (at most {MAX_INSTANTS} instants); the lowest {} modes of each",
                self.stride, self.output_times, self.modes
            ),
        })
    }
}

/// What the producer computed: the table up to the first instant that failed, its note,
/// and that failure.
pub(crate) struct MachineFrequencies {
    pub(crate) table: Option<Table>,
    pub(crate) note: Option<MachineFrequencyNote>,
    pub(crate) failure: Option<RunError>,
}

/// The error of a linearisation at `t`.
fn at_time(e: LinearError, t: f64) -> RunError {
    match e {
        LinearError::Model(e) => RunError::Model(e),
        source => RunError::Linear {
            output: "machine_frequencies",
            t,
            source,
        },
    }
}

/// The `machine_frequencies` table of `model` along `solution`, with each link's first KED
/// frequency from `ked` at the same instants; `report` sees the fraction of instants done.
pub(crate) fn machine_frequencies(
    model: &mut dyn SceneModel,
    solution: &Solution,
    ked: &mut ModalSystem,
    report: &mut dyn FnMut(f64),
) -> MachineFrequencies {
    let clock = Instant::now();
    let indices = frame_indices(solution.len(), MAX_INSTANTS);
    let mut found: Vec<Vec<Mode>> = Vec::with_capacity(indices.len());
    let mut failure = None;
    for (k, &i) in indices.iter().enumerate() {
        let t = solution.t[i];
        let outcome = linearize(model, t, solution.y(i), &[], &[]).and_then(|lin| modes(&lin));
        match outcome {
            Ok(m) => found.push(m),
            Err(e) => {
                failure = Some(at_time(e, t));
                break;
            }
        }
        report((k + 1) as f64 / indices.len() as f64);
    }
    let times: Vec<f64> = indices[..found.len()]
        .iter()
        .map(|&i| solution.t[i])
        .collect();
    let count = found.iter().map(Vec::len).min().unwrap_or(0).min(MAX_MODES);
    if times.is_empty() {
        return MachineFrequencies {
            table: None,
            note: None,
            failure,
        };
    }
    let mut table = Table::new("machine_frequencies", &times);
    let column = |quantity, k| Column {
        quantity,
        link: None,
        mode: Some(k),
        xi: None,
    };
    for k in 0..count {
        let f = found.iter().map(|m| m[k].frequency_hz).collect();
        table.push(column(MACHINE_FREQUENCY, k), f);
    }
    for k in 0..count {
        let zeta = found.iter().map(|m| m[k].damping_ratio).collect();
        table.push(column(MACHINE_DAMPING_RATIO, k), zeta);
    }
    match FrequencyHistory::sample(ked, &times) {
        Ok(history) => {
            for (i, link) in history.omega_squared.iter().enumerate() {
                if let Some(first) = link.first() {
                    let hz = first
                        .iter()
                        .map(|w| w.max(0.0).sqrt() / std::f64::consts::TAU)
                        .collect();
                    table.push(Column::mode(Q::Frequency, i, 0), hz);
                }
            }
        }
        Err(e) => failure = failure.or(Some(RunError::Model(e))),
    }
    let note = MachineFrequencyNote {
        instants: times.len(),
        output_times: solution.len(),
        stride: indices.get(1).copied().unwrap_or(1).max(1),
        modes: count,
        wall_time_s: clock.elapsed().as_secs_f64(),
    };
    MachineFrequencies {
        table: Some(table),
        note: Some(note),
        failure,
    }
}

impl crate::report::Report for MachineFrequencyNote {
    fn name(&self) -> &'static str {
        "machine_frequencies"
    }

    /// `machine_frequencies`.
    fn sections(&self) -> Vec<(&'static str, Value)> {
        vec![("machine_frequencies", self.to_json())]
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}
