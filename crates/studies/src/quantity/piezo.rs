//! The vibration-control quantities, from the run's piezo report (docs/piezo.md):
//! `deflection_reduction` and `patch_voltage`.

use std::sync::Arc;

use flexprr_run::piezo::{PatchSummary, PiezoReport};
use flexprr_scene::{OutputKind, Scene};

use super::{
    CaseRun, Column, ColumnValues, Quantity, QuantityKind, QuantityParams, first_column,
    needs_output, run_lacks, value,
};
use crate::study::StudyError;

/// How much lower the peak and RMS mid-point deflection of a link are under the scene's
/// vibration control than in the same scene without it (docs/piezo.md; the run does the
/// uncontrolled run itself): columns `w_peak_reduction_<link>_percent`,
/// `w_rms_reduction_<link>_percent`. Scenes with patches under a law, with the output
/// `deflections` or `piezo`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DeflectionReduction {
    /// Link (1-3).
    pub link: usize,
}

/// The voltage the vibration control costs: the largest applied voltage of any patch,
/// whether any patch saturated and the largest fraction of the output samples a patch spent
/// saturated (docs/piezo.md): columns `V_patch_max_V`, `patch_saturated` (`yes`/`no`),
/// `patch_saturated_fraction`. Scenes with patches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PatchVoltage;

/// The `deflection_reduction` kind: parameter `link`.
pub struct DeflectionReductionKind;

/// The `patch_voltage` kind: no parameters.
pub struct PatchVoltageKind;

impl QuantityKind for DeflectionReductionKind {
    fn keys(&self) -> &'static [&'static str] {
        &["link"]
    }
    fn parse(&self, params: &QuantityParams<'_>) -> Result<Arc<dyn Quantity>, StudyError> {
        Ok(Arc::new(DeflectionReduction {
            link: params.link()?,
        }))
    }
}

impl QuantityKind for PatchVoltageKind {
    fn keys(&self) -> &'static [&'static str] {
        &[]
    }
    fn parse(&self, _params: &QuantityParams<'_>) -> Result<Arc<dyn Quantity>, StudyError> {
        Ok(Arc::new(PatchVoltage))
    }
}

impl Quantity for DeflectionReduction {
    fn column_specs(&self) -> Vec<Column> {
        let link = self.link;
        vec![
            Column::new(
                format!("w_peak_reduction_{link}_percent"),
                format!("peak reduction, link {link}"),
                "%",
                ColumnValues::Number,
            ),
            Column::new(
                format!("w_rms_reduction_{link}_percent"),
                format!("RMS reduction, link {link}"),
                "%",
                ColumnValues::Number,
            ),
        ]
    }
    fn unavailable(&self, scene: &Scene) -> Option<String> {
        let name = first_column(self);
        let has = |k: OutputKind| scene.outputs.contains(&k);
        if scene.patches.is_empty() || scene.vibration_controller.is_none() {
            Some(format!(
                "quantity {name} needs piezoelectric patches under a vibration control law \
                 ([[links.patches]] and [vibration_control], docs/piezo.md)"
            ))
        } else if !has(OutputKind::Deflections) && !has(OutputKind::Piezo) {
            Some(needs_output(&name, "deflections"))
        } else {
            None
        }
    }
    fn derive(&self, run: &CaseRun<'_>) -> Result<Vec<String>, String> {
        let i = self.link - 1;
        let name = first_column(self);
        let reduction = run
            .result
            .report::<PiezoReport>()
            .and_then(|p| p.reduction.as_ref())
            .and_then(|r| r.get(i))
            .ok_or_else(|| run_lacks(&name, "deflections"))?;
        let percent = |r: Option<f64>| {
            r.map(value).ok_or_else(|| {
                format!(
                    "quantity {name}: link {} does not deflect without control",
                    self.link
                )
            })
        };
        Ok(vec![
            percent(reduction.peak_reduction_percent())?,
            percent(reduction.rms_reduction_percent())?,
        ])
    }
}

impl Quantity for PatchVoltage {
    fn column_specs(&self) -> Vec<Column> {
        use ColumnValues::{Flag, Number};
        vec![
            Column::new(
                "V_patch_max_V".into(),
                "largest patch voltage".into(),
                "V",
                Number,
            ),
            Column::new(
                "patch_saturated".into(),
                "a patch saturates".into(),
                "",
                Flag,
            ),
            Column::new(
                "patch_saturated_fraction".into(),
                "time saturated (fraction)".into(),
                "",
                Number,
            ),
        ]
    }
    fn unavailable(&self, scene: &Scene) -> Option<String> {
        scene.patches.is_empty().then(|| {
            "quantity V_patch_max_V needs piezoelectric patches ([[links.patches]], \
             docs/piezo.md)"
                .to_string()
        })
    }
    fn derive(&self, run: &CaseRun<'_>) -> Result<Vec<String>, String> {
        let piezo = run
            .result
            .report::<PiezoReport>()
            .ok_or_else(|| "quantity V_patch_max_V: the run has no patches".to_string())?;
        let max = |f: fn(&PatchSummary) -> f64| piezo.patches.iter().map(f).fold(0.0_f64, f64::max);
        Ok(vec![
            value(max(|p| p.max_abs_voltage)),
            if piezo.any_saturated() { "yes" } else { "no" }.into(),
            value(max(|p| p.saturated_fraction)),
        ])
    }
}
