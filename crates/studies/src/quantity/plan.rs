//! `plan`: the plan of a scene with a `[plan]` section (docs/planning.md).

use std::sync::Arc;

use flexprr_scene::Scene;

use super::{CaseRun, Column, ColumnValues, Quantity, QuantityKind, QuantityParams, value};
use crate::study::StudyError;

/// The plan of a scene with a `[plan]` section (docs/planning.md; the case runs `flexprr
/// plan` with its flexible check instead of `flexprr run`, and the other quantities come
/// from the planned motion's run): columns `cycle_time_s` (the move's duration or the
/// period), `plan_frequency_Hz` (a periodic plan's largest repetition rate, else empty),
/// `residual_vibration_m` (after a rest-to-rest move, else empty),
/// `plan_peak_deflection_m`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Plan;

/// The `plan` kind: no parameters.
pub struct PlanKind;

impl QuantityKind for PlanKind {
    fn keys(&self) -> &'static [&'static str] {
        &[]
    }
    fn parse(&self, _params: &QuantityParams<'_>) -> Result<Arc<dyn Quantity>, StudyError> {
        Ok(Arc::new(Plan))
    }
}

impl Quantity for Plan {
    fn column_specs(&self) -> Vec<Column> {
        use ColumnValues::{Number, OptionalNumber};
        vec![
            Column::new(
                "cycle_time_s".into(),
                "planned cycle time".into(),
                "s",
                Number,
            ),
            Column::new(
                "plan_frequency_Hz".into(),
                "largest repetition rate".into(),
                "Hz",
                OptionalNumber,
            ),
            Column::new(
                "residual_vibration_m".into(),
                "residual vibration after the planned move".into(),
                "m",
                OptionalNumber,
            ),
            Column::new(
                "plan_peak_deflection_m".into(),
                "peak deflection of the planned motion".into(),
                "m",
                Number,
            ),
        ]
    }
    fn unavailable(&self, scene: &Scene) -> Option<String> {
        scene.file.plan.is_none().then(|| {
            "quantity cycle_time_s needs a [plan] section in the scene (docs/planning.md): add \
             one to the base scene or the study's [set.plan]"
                .to_string()
        })
    }
    fn derive(&self, run: &CaseRun<'_>) -> Result<Vec<String>, String> {
        let plan = run
            .result
            .report::<flexprr_plan::PlanSummary>()
            .ok_or_else(|| "quantity cycle_time_s: the case was not planned".to_string())?;
        let optional = |v: Option<f64>| v.map_or(String::new(), value);
        Ok(vec![
            value(plan.cycle_time),
            optional(plan.frequency),
            optional(plan.residual_vibration),
            value(plan.peak_deflection.unwrap_or(0.0)),
        ])
    }
    fn planned(&self) -> bool {
        true
    }
}
