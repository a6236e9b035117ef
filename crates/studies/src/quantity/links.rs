//! Quantities of one link over the motion: `peak_axial_force`, `peak_deflection` and
//! `buckling`.

use std::sync::Arc;

use flexprr_run::Quantity as RunQuantity;
use flexprr_scene::{OutputKind, Scene};

use super::{
    CaseRun, Column, ColumnValues, Quantity, QuantityKind, QuantityParams, needs_output, run_lacks,
    value,
};
use crate::study::StudyError;

/// Largest tensile and compressive axial force at either end of a link over the motion
/// (output `axial_forces`, else `frequencies`): columns `P_max_<link>_N`, `P_min_<link>_N`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PeakAxialForce {
    /// Link (1-3).
    pub link: usize,
}

/// Largest |w| at the first `deflection_xi` (output `deflections`): column
/// `w_peak_<link>_m`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PeakDeflection {
    /// Link (1-3).
    pub link: usize,
}

/// Whether the link buckles (stiffness not positive definite) and when it first does
/// (output `frequencies`): columns `buckles_<link>` (`yes`/`no`), `buckling_start_<link>_s`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Buckling {
    /// Link (1-3).
    pub link: usize,
}

/// The `peak_axial_force` kind: parameter `link`.
pub struct PeakAxialForceKind;

/// The `peak_deflection` kind: parameter `link`.
pub struct PeakDeflectionKind;

/// The `buckling` kind: parameter `link`.
pub struct BucklingKind;

impl QuantityKind for PeakAxialForceKind {
    fn keys(&self) -> &'static [&'static str] {
        &["link"]
    }
    fn parse(&self, params: &QuantityParams<'_>) -> Result<Arc<dyn Quantity>, StudyError> {
        Ok(Arc::new(PeakAxialForce {
            link: params.link()?,
        }))
    }
}

impl QuantityKind for PeakDeflectionKind {
    fn keys(&self) -> &'static [&'static str] {
        &["link"]
    }
    fn parse(&self, params: &QuantityParams<'_>) -> Result<Arc<dyn Quantity>, StudyError> {
        Ok(Arc::new(PeakDeflection {
            link: params.link()?,
        }))
    }
}

impl QuantityKind for BucklingKind {
    fn keys(&self) -> &'static [&'static str] {
        &["link"]
    }
    fn parse(&self, params: &QuantityParams<'_>) -> Result<Arc<dyn Quantity>, StudyError> {
        Ok(Arc::new(Buckling {
            link: params.link()?,
        }))
    }
}

impl Quantity for PeakAxialForce {
    fn column_specs(&self) -> Vec<Column> {
        let link = self.link;
        vec![
            Column::new(
                format!("P_max_{link}_N"),
                format!("largest tension in link {link}"),
                "N",
                ColumnValues::Number,
            ),
            Column::new(
                format!("P_min_{link}_N"),
                format!("largest compression in link {link}"),
                "N",
                ColumnValues::Number,
            ),
        ]
    }
    fn unavailable(&self, scene: &Scene) -> Option<String> {
        let has = |k: OutputKind| scene.outputs.contains(&k);
        (!has(OutputKind::AxialForces) && !has(OutputKind::Frequencies)).then(|| {
            needs_output(
                &super::first_column(self),
                "axial_forces\" or \"frequencies",
            )
        })
    }
    fn derive(&self, run: &CaseRun<'_>) -> Result<Vec<String>, String> {
        let i = self.link - 1;
        let result = run.result;
        let forces: Vec<f64> = if let Some(table) = result.table("axial_forces") {
            let b = table.column(&format!("P_B_{}_N", i + 1)).unwrap_or(&[]);
            let c = table.column(&format!("P_C_{}_N", i + 1)).unwrap_or(&[]);
            b.iter().chain(c).copied().collect()
        } else if let Some(history) = &result.frequencies {
            history.end_forces[i]
                .iter()
                .flat_map(|&(b, c)| [b, c])
                .collect()
        } else {
            return Err(run_lacks(
                &super::first_column(self),
                "axial_forces\" or \"frequencies",
            ));
        };
        let max = forces.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let min = forces.iter().copied().fold(f64::INFINITY, f64::min);
        Ok(vec![value(max), value(min)])
    }
}

impl Quantity for PeakDeflection {
    fn column_specs(&self) -> Vec<Column> {
        let link = self.link;
        vec![Column::new(
            format!("w_peak_{link}_m"),
            format!("peak deflection of link {link}"),
            "m",
            ColumnValues::Number,
        )]
    }
    fn unavailable(&self, scene: &Scene) -> Option<String> {
        (!scene.outputs.contains(&OutputKind::Deflections))
            .then(|| needs_output(&super::first_column(self), "deflections"))
    }
    fn derive(&self, run: &CaseRun<'_>) -> Result<Vec<String>, String> {
        let i = self.link - 1;
        let lacks = || run_lacks(&super::first_column(self), "deflections");
        let table = run.result.table("deflections").ok_or_else(lacks)?;
        let column = table
            .columns
            .iter()
            .position(|c| c.quantity == RunQuantity::Deflection && c.link == Some(i))
            .ok_or_else(lacks)?;
        let peak = table.data[column]
            .iter()
            .fold(0.0_f64, |m, w| m.max(w.abs()));
        Ok(vec![value(peak)])
    }
}

impl Quantity for Buckling {
    fn column_specs(&self) -> Vec<Column> {
        let link = self.link;
        vec![
            Column::new(
                format!("buckles_{link}"),
                format!("link {link} buckles"),
                "",
                ColumnValues::Flag,
            ),
            Column::new(
                format!("buckling_start_{link}_s"),
                format!("time link {link} starts to buckle"),
                "s",
                ColumnValues::OptionalNumber,
            ),
        ]
    }
    fn unavailable(&self, scene: &Scene) -> Option<String> {
        (!scene.outputs.contains(&OutputKind::Frequencies))
            .then(|| needs_output(&super::first_column(self), "frequencies"))
    }
    fn derive(&self, run: &CaseRun<'_>) -> Result<Vec<String>, String> {
        let i = self.link - 1;
        let history = run
            .result
            .frequencies
            .as_ref()
            .ok_or_else(|| run_lacks(&super::first_column(self), "frequencies"))?;
        let start = history
            .buckling
            .iter()
            .filter(|b| b.link == i)
            .map(|b| b.t_start)
            .fold(None, |m: Option<f64>, t| Some(m.map_or(t, |m| m.min(t))));
        Ok(match start {
            Some(t) => vec!["yes".into(), value(t)],
            None => vec!["no".into(), String::new()],
        })
    }
}
