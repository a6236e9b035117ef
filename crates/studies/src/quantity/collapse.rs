//! `collapse`: whether the mechanism collapses, and when, which link and how far.

use std::sync::Arc;

use flexprr_scene::Scene;

use super::{CaseRun, Column, ColumnValues, Quantity, QuantityKind, QuantityParams, value};
use crate::study::StudyError;

/// Whether the mechanism collapses (a coupled or nonlinear run stopped with the collapse
/// outcome: a link's mid-point deflection passed `model.collapse_deflection` of its length,
/// or the chords reached a type-II pose) and when, which link and how far it was deflected:
/// columns `collapses` (`yes`/`no`), `collapse_time_s`, `collapse_link`,
/// `collapse_deflection_m` (empty without a collapse). A collapsed case is `ok`: the
/// collapse is its result, and the other quantities cover the run up to it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Collapse;

/// The `collapse` kind: no parameters.
pub struct CollapseKind;

impl QuantityKind for CollapseKind {
    fn keys(&self) -> &'static [&'static str] {
        &[]
    }
    fn parse(&self, _params: &QuantityParams<'_>) -> Result<Arc<dyn Quantity>, StudyError> {
        Ok(Arc::new(Collapse))
    }
}

impl Quantity for Collapse {
    fn column_specs(&self) -> Vec<Column> {
        use ColumnValues::{Flag, OptionalNumber};
        vec![
            Column::new(
                "collapses".into(),
                "the mechanism collapses".into(),
                "",
                Flag,
            ),
            Column::new(
                "collapse_time_s".into(),
                "time of collapse".into(),
                "s",
                OptionalNumber,
            ),
            Column::new(
                "collapse_link".into(),
                "most deflected link at collapse".into(),
                "",
                OptionalNumber,
            ),
            Column::new(
                "collapse_deflection_m".into(),
                "its mid-point deflection at collapse".into(),
                "m",
                OptionalNumber,
            ),
        ]
    }
    fn unavailable(&self, scene: &Scene) -> Option<String> {
        if !scene.coupling.capabilities().free_platform {
            Some(
                "quantity collapses needs a coupled or nonlinear model (model.coupling): a KED \
                 model follows the rigid motion and cannot collapse"
                    .into(),
            )
        } else if !scene.needs_integration() {
            Some(super::needs_output("collapses", "deflections"))
        } else {
            None
        }
    }
    fn derive(&self, run: &CaseRun<'_>) -> Result<Vec<String>, String> {
        Ok(match run.collapse {
            Some(c) => vec![
                "yes".into(),
                value(c.t),
                value((c.link + 1) as f64),
                value(c.deflection),
            ],
            None => vec!["no".into(), String::new(), String::new(), String::new()],
        })
    }
    fn keeps_collapse(&self) -> bool {
        true
    }
}
