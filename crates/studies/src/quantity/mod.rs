//! Derived quantities of one case and the typed columns they fill in `results.csv`
//! (`docs/studies.md`, "Derived quantities"), as a registry of named kinds.
//!
//! A study's `quantities = [{ kind = "...", ... }]` names a [`QuantityKind`] registered in a
//! [`QuantityRegistry`] (the built-in kinds below, registered by [`QuantityRegistry::default`],
//! or a program's own). The kind reads its parameters from the table ([`QuantityParams`]:
//! each error at its key) and gives a [`Quantity`]: its columns, why a case's scene cannot
//! give it, and its values from the case's run ([`CaseRun`]).
//!
//! Built-in kinds, one file per theme: `frequency_range` and `stiffness_ratio`
//! ([`modes`]), `peak_axial_force`, `peak_deflection` and `buckling` ([`links`]),
//! `collapse` ([`collapse`]), `lowest_frequency` ([`machine`]), `deflection_reduction` and
//! `patch_voltage` ([`piezo`]), `plan` ([`plan`]) and `output` ([`output`]).

use std::fmt;
use std::sync::Arc;

use flexprr_run::{Collapse, RunResult};
use flexprr_scene::Scene;

use crate::record::format_value;
use crate::study::StudyError;

pub mod collapse;
pub mod links;
pub mod machine;
pub mod modes;
pub mod output;
mod params;
pub mod piezo;
pub mod plan;

pub use params::QuantityParams;

/// A kind of derived quantity, registered by name with [`QuantityRegistry::register`] and
/// selected with `kind = "<name>"` in a study's `quantities`.
///
/// A kind that tabulates the end time of each case's run:
///
/// ```
/// use flexprr_studies::quantity::{
///     CaseRun, Column, ColumnValues, Quantity, QuantityKind, QuantityParams,
/// };
/// use flexprr_studies::{Plugins, Study, StudyError};
/// use std::sync::Arc;
///
/// #[derive(Debug)]
/// struct EndTime;
/// impl Quantity for EndTime {
///     fn column_specs(&self) -> Vec<Column> {
///         vec![Column::new("t_end_s".into(), "end time".into(), "s", ColumnValues::Number)]
///     }
///     fn unavailable(&self, _scene: &flexprr_scene::Scene) -> Option<String> {
///         None
///     }
///     fn derive(&self, run: &CaseRun<'_>) -> Result<Vec<String>, String> {
///         let t = run.result.tables.first().and_then(|t| t.time().last().copied());
///         t.map(|t| vec![format!("{t}")]).ok_or_else(|| "no table".to_string())
///     }
/// }
///
/// struct EndTimeKind;
/// impl QuantityKind for EndTimeKind {
///     fn keys(&self) -> &'static [&'static str] {
///         &[]
///     }
///     fn parse(&self, _params: &QuantityParams<'_>) -> Result<Arc<dyn Quantity>, StudyError> {
///         Ok(Arc::new(EndTime))
///     }
/// }
///
/// let mut plugins = Plugins::default();
/// plugins.quantities.register("end_time", Arc::new(EndTimeKind));
/// let text = r#"
/// base = "paper_f20.toml"
/// quantities = [{ kind = "end_time" }]
/// [[axis]]
/// key = "trajectory.frequency"
/// values = [10.0]
/// "#;
/// let configs = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs");
/// let study = Study::from_text_with(plugins, "end.toml", "end", text, &configs).unwrap();
/// assert_eq!(study.columns()[2], "t_end_s");
/// // Unknown to the built-in registry:
/// let err = Study::from_text("end.toml", "end", text, &configs).unwrap_err();
/// assert!(err.to_string().contains("unknown variant `end_time`"), "{err}");
/// ```
pub trait QuantityKind: Send + Sync {
    /// The parameters a quantity of this kind takes (the keys of its table besides `kind`);
    /// any other key is refused at its place before [`QuantityKind::parse`] is called.
    fn keys(&self) -> &'static [&'static str];

    /// The quantity its table describes.
    ///
    /// # Errors
    /// [`StudyError::Input`] at the offending key ([`QuantityParams::error`]): a missing
    /// parameter, a value of the wrong type or out of range.
    fn parse(&self, params: &QuantityParams<'_>) -> Result<Arc<dyn Quantity>, StudyError>;
}

/// What a quantity's values are derived from: the case's scene, its run, and the collapse
/// that stopped it (when a quantity [`Quantity::keeps_collapse`]; the run is then the run up
/// to the collapse).
#[derive(Clone, Copy)]
pub struct CaseRun<'a> {
    /// The case's scene.
    pub scene: &'a Scene,
    /// Its run (of the planned motion, for a planned case).
    pub result: &'a RunResult,
    /// The collapse that stopped the run, if any.
    pub collapse: Option<&'a Collapse>,
}

impl<'a> CaseRun<'a> {
    /// A run of `scene` that finished.
    pub fn finished(scene: &'a Scene, result: &'a RunResult) -> Self {
        Self {
            scene,
            result,
            collapse: None,
        }
    }
}

/// A derived quantity of one case: one or more columns of `results.csv`.
pub trait Quantity: fmt::Debug + Send + Sync {
    /// The typed columns, in table order.
    fn column_specs(&self) -> Vec<Column>;

    /// Column names.
    fn columns(&self) -> Vec<String> {
        self.column_specs().into_iter().map(|c| c.name).collect()
    }

    /// Why a case whose scene is `scene` cannot give this quantity (an output it does not
    /// request, a mode its links do not have, a model that cannot collapse); `None` when it
    /// can. A case is refused on this before it runs.
    fn unavailable(&self, scene: &Scene) -> Option<String>;

    /// The quantity's values for one case, formatted with [`format_value`] (a flag as `yes`
    /// or `no`, an event that did not happen as an empty value).
    ///
    /// # Errors
    /// A message when the run lacks what the quantity needs.
    fn derive(&self, run: &CaseRun<'_>) -> Result<Vec<String>, String>;

    /// Whether a case with this quantity is planned (`flexprr plan` with its flexible check)
    /// rather than run.
    fn planned(&self) -> bool {
        false
    }

    /// Whether a run stopped by a collapse is this quantity's result rather than a failure.
    fn keeps_collapse(&self) -> bool {
        false
    }
}

/// The quantity kinds a study may name, in registration order (the order its messages list
/// them in).
#[derive(Clone)]
pub struct QuantityRegistry {
    kinds: Vec<(String, Arc<dyn QuantityKind>)>,
}

impl Default for QuantityRegistry {
    /// The built-in kinds.
    fn default() -> Self {
        let mut r = Self::empty();
        r.register("frequency_range", Arc::new(modes::FrequencyRangeKind));
        r.register("stiffness_ratio", Arc::new(modes::StiffnessRatioKind));
        r.register("peak_axial_force", Arc::new(links::PeakAxialForceKind));
        r.register("peak_deflection", Arc::new(links::PeakDeflectionKind));
        r.register("buckling", Arc::new(links::BucklingKind));
        r.register("collapse", Arc::new(collapse::CollapseKind));
        r.register("lowest_frequency", Arc::new(machine::LowestFrequencyKind));
        r.register(
            "deflection_reduction",
            Arc::new(piezo::DeflectionReductionKind),
        );
        r.register("patch_voltage", Arc::new(piezo::PatchVoltageKind));
        r.register("plan", Arc::new(plan::PlanKind));
        r.register("output", Arc::new(output::OutputKind));
        r
    }
}

impl fmt::Debug for QuantityRegistry {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.names()).finish()
    }
}

impl QuantityRegistry {
    /// A registry without any kind.
    pub fn empty() -> Self {
        Self { kinds: Vec::new() }
    }

    /// Registers `kind` under `name`, replacing a kind of that name.
    pub fn register(&mut self, name: &str, kind: Arc<dyn QuantityKind>) {
        match self.kinds.iter_mut().find(|(n, _)| n == name) {
            Some(slot) => slot.1 = kind,
            None => self.kinds.push((name.to_string(), kind)),
        }
    }

    /// The kind registered as `name`.
    pub fn kind(&self, name: &str) -> Option<&Arc<dyn QuantityKind>> {
        self.kinds.iter().find(|(n, _)| n == name).map(|(_, k)| k)
    }

    /// The registered names, in registration order.
    pub fn names(&self) -> Vec<&str> {
        self.kinds.iter().map(|(n, _)| n.as_str()).collect()
    }
}

/// What the output registry says of a named quantity: the output offering it, its unit and
/// label.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct OutputQuantity {
    /// The output (producer) that offers it.
    pub output: &'static str,
    /// SI unit.
    pub unit: &'static str,
    /// Words for an axis label.
    pub label: &'static str,
}

/// What a quantity column holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ColumnValues {
    /// A finite number, written by [`format_value`].
    Number,
    /// `yes` or `no`.
    Flag,
    /// A finite number, or empty when the event did not happen (e.g. no buckling).
    OptionalNumber,
    /// Not known (a merge knows only the header): any of the above.
    Unknown,
}

/// One quantity column of `results.csv`: its header, a label and unit for plots, and what
/// its values are (checked when a case record is read back).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Column {
    /// Header in `results.csv`, e.g. `P_max_1_N`.
    pub name: String,
    /// Words for an axis label, e.g. `largest tension in link 1`.
    pub label: String,
    /// SI unit (empty for ratios and flags).
    pub unit: &'static str,
    /// What the column holds.
    pub values: ColumnValues,
}

impl Column {
    /// A column known only by its header (its values may be anything a column holds).
    pub fn untyped(name: &str) -> Self {
        Self::new(
            name.to_string(),
            name.to_string(),
            "",
            ColumnValues::Unknown,
        )
    }

    /// A column: its header, the words of its axis label, its SI unit (empty for ratios and
    /// flags) and what its values are.
    pub fn new(name: String, label: String, unit: &'static str, values: ColumnValues) -> Self {
        Self {
            name,
            label,
            unit,
            values,
        }
    }

    /// Axis label: the words and the unit in parentheses, e.g. `largest tension in link 1 (N)`.
    pub fn axis_label(&self) -> String {
        with_unit(&self.label, self.unit)
    }

    /// Whether `value` is a well-formed entry of this column: a finite number in
    /// [`format_value`]'s canonical form, `yes`/`no`, or empty where allowed.
    pub fn accepts(&self, value: &str) -> bool {
        let number = || {
            value
                .parse::<f64>()
                .is_ok_and(|v| v.is_finite() && format_value(v) == value)
        };
        match self.values {
            ColumnValues::Number => number(),
            ColumnValues::Flag => value == "yes" || value == "no",
            ColumnValues::OptionalNumber => value.is_empty() || number(),
            ColumnValues::Unknown => {
                value.is_empty() || value == "yes" || value == "no" || number()
            }
        }
    }
}

/// `label (unit)`, or the label alone without a unit.
pub(crate) fn with_unit(label: &str, unit: &str) -> String {
    if unit.is_empty() {
        label.to_string()
    } else {
        format!("{label} ({unit})")
    }
}

/// The first column's header of `q`, which names it in messages.
pub(crate) fn first_column(q: &dyn Quantity) -> String {
    q.columns().into_iter().next().unwrap_or_default()
}

/// "quantity `name` needs the output ..." for a scene that does not request it.
pub(crate) fn needs_output(name: &str, output: &str) -> String {
    format!(
        "quantity {name} needs the output \"{output}\" (add it to output.requests, e.g. in \
         [set.output])"
    )
}

/// "quantity `name` needs the output ..." for a run that lacks it.
pub(crate) fn run_lacks(name: &str, output: &str) -> String {
    format!("quantity {name} needs the output \"{output}\"")
}

/// `value` formatted for the table.
pub(crate) fn value(v: f64) -> String {
    format_value(v)
}
