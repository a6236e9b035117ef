//! The plan of a scene as a run's report ([`flexprr_run::Report`]): what a study case with a
//! `[plan]` section records (its cycle time, the frequency of a periodic plan, the residual
//! vibration and the peak deflection of the planned motion on the scene's flexible model).

use std::any::Any;

use flexprr_planning::Boundary;
use flexprr_run::{Report, RunResult};
use flexprr_scene::Scene;
use serde_json::{Value, json};

use crate::deflection::peak_deflection;
use crate::error::PlanError;
use crate::pipeline::{Options, plan_scene};

/// The plan's numbers, as a report on the planned motion's run.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanSummary {
    /// The move's duration (rest to rest) or the period (s).
    pub cycle_time: f64,
    /// The largest repetition rate of a periodic plan (Hz).
    pub frequency: Option<f64>,
    /// Peak deflection after a rest-to-rest move over the settling window (m).
    pub residual_vibration: Option<f64>,
    /// Largest deflection of any link over the planned motion's run (m).
    pub peak_deflection: Option<f64>,
    /// The constraints that bind along the path, in order, each once.
    pub binding: Vec<String>,
}

impl Report for PlanSummary {
    fn name(&self) -> &'static str {
        "plan"
    }
    fn sections(&self) -> Vec<(&'static str, Value)> {
        vec![(
            "plan",
            json!({
                "cycle_time_s": self.cycle_time,
                "frequency_hz": self.frequency,
                "residual_vibration_m": self.residual_vibration,
                "peak_deflection_m": self.peak_deflection,
                "binding": self.binding,
            }),
        )]
    }
    fn quantity(&self, name: &str) -> Option<f64> {
        match name {
            "cycle_time_s" => Some(self.cycle_time),
            "plan_frequency_Hz" => self.frequency,
            "residual_vibration_m" => self.residual_vibration,
            "plan_peak_deflection_m" => self.peak_deflection,
            _ => None,
        }
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
}

/// Plans `scene` by its `[plan]` section with the flexible check, and returns the planned
/// motion's run (the scene's outputs on the planned motion) with a [`PlanSummary`] among its
/// reports: what a study case with a `[plan]` section runs.
///
/// # Errors
/// As [`plan_scene`].
pub fn plan_run(scene: &Scene) -> Result<RunResult, PlanError> {
    let outcome = plan_scene(
        scene,
        Options {
            flexible_check: true,
        },
        &mut |_| {},
    )?;
    let mut binding: Vec<String> = Vec::new();
    for b in &outcome.plan.binding {
        if b.constraint != "none" && !binding.contains(&b.constraint) {
            binding.push(b.constraint.clone());
        }
    }
    let flexible = outcome.flexible;
    let summary = PlanSummary {
        cycle_time: outcome.plan.duration,
        frequency: (outcome.plan.boundary == Boundary::Periodic)
            .then(|| 1.0 / outcome.plan.duration),
        residual_vibration: flexible.as_ref().and_then(|f| f.planned.residual),
        peak_deflection: flexible.as_ref().map(|f| peak_deflection(&f.planned_run)),
        binding,
    };
    let mut run = flexible.map(|f| f.planned_run).unwrap_or_default();
    run.add_report(summary);
    Ok(run)
}
