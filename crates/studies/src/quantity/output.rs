//! `output`: a scalar an output producer offers by name.

use std::sync::Arc;

use flexprr_scene::Scene;

use super::{CaseRun, Column, ColumnValues, Quantity, QuantityKind, QuantityParams, value};
use crate::study::StudyError;

use super::OutputQuantity;

/// A scalar an output producer offers by name (`flexprr_run::OutputProducer::quantities`,
/// the built-in ones or a program's own): column `<name>`. The scenes must request the
/// output that offers it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Output {
    /// The quantity's name, e.g. `slider_power_peak_W`.
    pub name: String,
    /// What the output registry says of it.
    pub about: OutputQuantity,
}

/// The `output` kind: parameter `name`, one of the quantities the study's output producers
/// offer.
pub struct OutputKind;

impl QuantityKind for OutputKind {
    fn keys(&self) -> &'static [&'static str] {
        &["name"]
    }
    fn parse(&self, params: &QuantityParams<'_>) -> Result<Arc<dyn Quantity>, StudyError> {
        let name = params.string("name")?;
        let offered = params.outputs().quantities();
        let Some((output, found)) = offered.iter().find(|(_, o)| o.name == name) else {
            let names: Vec<String> = offered
                .iter()
                .map(|(_, o)| format!("`{}`", o.name))
                .collect();
            let known = if names.is_empty() {
                "no output offers quantities".to_string()
            } else {
                format!("expected one of {}", names.join(", "))
            };
            return Err(params.error("name", format!("unknown output quantity `{name}`, {known}")));
        };
        Ok(Arc::new(Output {
            name,
            about: OutputQuantity {
                output,
                unit: found.unit,
                label: found.label,
            },
        }))
    }
}

impl Quantity for Output {
    fn column_specs(&self) -> Vec<Column> {
        let label = if self.about.label.is_empty() {
            self.name.clone()
        } else {
            self.about.label.to_string()
        };
        vec![Column::new(
            self.name.clone(),
            label,
            self.about.unit,
            ColumnValues::Number,
        )]
    }
    fn unavailable(&self, scene: &Scene) -> Option<String> {
        (!scene.requests(self.about.output)).then(|| {
            format!(
                "quantity {} needs the output \"{}\" (add it to output.custom, e.g. in \
                 [set.output])",
                self.name, self.about.output
            )
        })
    }
    fn derive(&self, run: &CaseRun<'_>) -> Result<Vec<String>, String> {
        let name = &self.name;
        match run.result.quantity(name) {
            Some(Ok(v)) => Ok(vec![value(v)]),
            Some(Err(why)) => Err(format!("quantity {name}: {why}")),
            None => Err(super::run_lacks(name, self.about.output)),
        }
    }
}
