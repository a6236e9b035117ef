//! `lowest_frequency`: the lowest whole-machine natural frequency at rest at the case's
//! start pose.

use std::sync::Arc;

use flexprr_scene::Scene;

use super::{CaseRun, Column, ColumnValues, Quantity, QuantityKind, QuantityParams, value};
use crate::study::StudyError;

/// The lowest whole-machine natural frequency at rest at the case's start pose and its
/// damping ratio (docs/linear.md: the case's model held there, sliders locked or on its
/// control law, linearised): columns `f_machine_lowest_Hz`, `zeta_machine_lowest`.
/// Coupled and nonlinear models; computed from the case's scene, whatever it requests.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LowestFrequency;

/// The `lowest_frequency` kind: no parameters.
pub struct LowestFrequencyKind;

impl QuantityKind for LowestFrequencyKind {
    fn keys(&self) -> &'static [&'static str] {
        &[]
    }
    fn parse(&self, _params: &QuantityParams<'_>) -> Result<Arc<dyn Quantity>, StudyError> {
        Ok(Arc::new(LowestFrequency))
    }
}

impl Quantity for LowestFrequency {
    fn column_specs(&self) -> Vec<Column> {
        vec![
            Column::new(
                "f_machine_lowest_Hz".into(),
                "lowest whole-machine frequency at rest".into(),
                "Hz",
                ColumnValues::Number,
            ),
            Column::new(
                "zeta_machine_lowest".into(),
                "damping ratio of the lowest whole-machine mode".into(),
                "",
                ColumnValues::Number,
            ),
        ]
    }
    fn unavailable(&self, scene: &Scene) -> Option<String> {
        (!scene.coupling.capabilities().free_platform).then(|| {
            "quantity f_machine_lowest_Hz needs a model of the whole machine (model.coupling = \
             \"coupled\" or \"nonlinear\"): the KED model prescribes the platform and the \
             sliders"
                .into()
        })
    }
    /// Computed from the case's scene, not from its run.
    fn derive(&self, run: &CaseRun<'_>) -> Result<Vec<String>, String> {
        use flexprr_linear_tools::linear::OperatingPoint;
        use flexprr_linear_tools::machine_modes::{lowest_frequency, start_pose};
        lowest_frequency(run.scene, OperatingPoint::Rest(start_pose(run.scene)))
            .map(|(f, zeta)| vec![value(f), value(zeta)])
            .map_err(|e| format!("quantity f_machine_lowest_Hz: {e}"))
    }
}
