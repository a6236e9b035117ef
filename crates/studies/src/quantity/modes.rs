//! Quantities of one mode of one link over the motion, from the run's frequency history
//! (output `frequencies`): `frequency_range` and `stiffness_ratio`.

use std::sync::Arc;

use flexprr_run::RunResult;
use flexprr_scene::{OutputKind, Scene};

use super::{
    CaseRun, Column, ColumnValues, Quantity, QuantityKind, QuantityParams, needs_output, run_lacks,
    value,
};
use crate::study::StudyError;

/// Lowest and highest frequency of a mode over the motion (output `frequencies`): columns
/// `f_min_<link>_<mode>_Hz`, `f_max_<link>_<mode>_Hz`. Links and modes are 1-based.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrequencyRange {
    /// Link (1-3).
    pub link: usize,
    /// Mode (1-based).
    pub mode: usize,
}

/// Lowest `omega^2 / omega_0^2` of a mode (1 unloaded, <= 0 buckled; output
/// `frequencies`): column `stiffness_ratio_min_<link>_<mode>`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StiffnessRatio {
    /// Link (1-3).
    pub link: usize,
    /// Mode (1-based).
    pub mode: usize,
}

/// The `frequency_range` kind: parameters `link`, `mode`.
pub struct FrequencyRangeKind;

/// The `stiffness_ratio` kind: parameters `link`, `mode`.
pub struct StiffnessRatioKind;

impl QuantityKind for FrequencyRangeKind {
    fn keys(&self) -> &'static [&'static str] {
        &["link", "mode"]
    }
    fn parse(&self, params: &QuantityParams<'_>) -> Result<Arc<dyn Quantity>, StudyError> {
        Ok(Arc::new(FrequencyRange {
            link: params.link()?,
            mode: params.mode()?,
        }))
    }
}

impl QuantityKind for StiffnessRatioKind {
    fn keys(&self) -> &'static [&'static str] {
        &["link", "mode"]
    }
    fn parse(&self, params: &QuantityParams<'_>) -> Result<Arc<dyn Quantity>, StudyError> {
        Ok(Arc::new(StiffnessRatio {
            link: params.link()?,
            mode: params.mode()?,
        }))
    }
}

/// Why `scene` cannot give the quantity `name` of mode `mode`: no `frequencies` output, or
/// links with fewer modes.
fn mode_unavailable(name: &str, mode: usize, scene: &Scene) -> Option<String> {
    if !scene.outputs.contains(&OutputKind::Frequencies) {
        return Some(needs_output(name, "frequencies"));
    }
    let modes = scene.machine.links[0].modes();
    (mode > modes).then(|| format!("quantity {name}: the links have {modes} modes, not {mode}"))
}

/// The lowest and highest frequency and the lowest stiffness ratio of mode `mode` of link
/// `link` (1-based) over the run.
fn range(
    name: &str,
    result: &RunResult,
    link: usize,
    mode: usize,
) -> Result<(f64, f64, f64), String> {
    let history = result
        .frequencies
        .as_ref()
        .ok_or_else(|| run_lacks(name, "frequencies"))?;
    history
        .ranges
        .iter()
        .find(|r| r.link + 1 == link && r.mode + 1 == mode)
        .map(|r| (r.min_hz, r.max_hz, r.min_stiffness_ratio))
        .ok_or_else(|| format!("link {link} has no mode {mode}"))
}

impl Quantity for FrequencyRange {
    fn column_specs(&self) -> Vec<Column> {
        let Self { link, mode } = *self;
        vec![
            Column::new(
                format!("f_min_{link}_{mode}_Hz"),
                format!("lowest frequency of link {link}, mode {mode}"),
                "Hz",
                ColumnValues::Number,
            ),
            Column::new(
                format!("f_max_{link}_{mode}_Hz"),
                format!("highest frequency of link {link}, mode {mode}"),
                "Hz",
                ColumnValues::Number,
            ),
        ]
    }
    fn unavailable(&self, scene: &Scene) -> Option<String> {
        mode_unavailable(&super::first_column(self), self.mode, scene)
    }
    fn derive(&self, run: &CaseRun<'_>) -> Result<Vec<String>, String> {
        let (min, max, _) = range(&super::first_column(self), run.result, self.link, self.mode)?;
        Ok(vec![value(min), value(max)])
    }
}

impl Quantity for StiffnessRatio {
    fn column_specs(&self) -> Vec<Column> {
        let Self { link, mode } = *self;
        vec![Column::new(
            format!("stiffness_ratio_min_{link}_{mode}"),
            format!("lowest ω²/ω₀² of link {link}, mode {mode}"),
            "",
            ColumnValues::Number,
        )]
    }
    fn unavailable(&self, scene: &Scene) -> Option<String> {
        mode_unavailable(&super::first_column(self), self.mode, scene)
    }
    fn derive(&self, run: &CaseRun<'_>) -> Result<Vec<String>, String> {
        let (_, _, ratio) = range(&super::first_column(self), run.result, self.link, self.mode)?;
        Ok(vec![value(ratio)])
    }
}
