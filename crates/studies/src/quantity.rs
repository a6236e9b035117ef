//! Derived quantities of one case and the typed columns they fill in `results.csv`
//! (`docs/studies.md`, "Derived quantities").

use flexprr_run::{Collapse, Quantity as RunQuantity, RunResult};
use serde::{Deserialize, Serialize};

use crate::record::format_value;

/// A derived quantity of one case (links and modes are 1-based, as in the output tables).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Eq)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Quantity {
    /// Lowest and highest frequency of a mode over the motion (output `frequencies`):
    /// columns `f_min_<link>_<mode>_Hz`, `f_max_<link>_<mode>_Hz`.
    FrequencyRange {
        /// Link (1-3).
        link: usize,
        /// Mode (1-based).
        mode: usize,
    },
    /// Lowest `omega^2 / omega_0^2` of a mode (1 unloaded, <= 0 buckled; output
    /// `frequencies`): column `stiffness_ratio_min_<link>_<mode>`.
    StiffnessRatio {
        /// Link (1-3).
        link: usize,
        /// Mode (1-based).
        mode: usize,
    },
    /// Largest tensile and compressive axial force at either end of a link over the motion
    /// (output `axial_forces`, else `frequencies`): columns `P_max_<link>_N`, `P_min_<link>_N`.
    PeakAxialForce {
        /// Link (1-3).
        link: usize,
    },
    /// Largest |w| at the first `deflection_xi` (output `deflections`): column
    /// `w_peak_<link>_m`.
    PeakDeflection {
        /// Link (1-3).
        link: usize,
    },
    /// Whether the link buckles (stiffness not positive definite) and when it first does
    /// (output `frequencies`): columns `buckles_<link>` (`yes`/`no`), `buckling_start_<link>_s`.
    Buckling {
        /// Link (1-3).
        link: usize,
    },
    /// Whether the mechanism collapses (a coupled or nonlinear run stopped with the collapse
    /// outcome: a link's mid-point deflection passed `model.collapse_deflection` of its
    /// length, or the chords reached a type-II pose) and when, which link and how far it
    /// was deflected: columns `collapses` (`yes`/`no`), `collapse_time_s`, `collapse_link`,
    /// `collapse_deflection_m` (empty without a collapse). A collapsed case is `ok`: the
    /// collapse is its result, and the other quantities cover the run up to it.
    Collapse,
    /// The lowest whole-machine natural frequency at rest at the case's start pose and its
    /// damping ratio (docs/linear.md: the case's model held there, sliders locked or on its
    /// control law, linearised): columns `f_machine_lowest_Hz`, `zeta_machine_lowest`.
    /// Coupled and nonlinear models; computed from the case's scene, whatever it requests.
    LowestFrequency,
    /// How much lower the peak and RMS mid-point deflection of a link are under the scene's
    /// vibration control than in the same scene without it (docs/piezo.md; the run does the
    /// uncontrolled run itself): columns `w_peak_reduction_<link>_percent`,
    /// `w_rms_reduction_<link>_percent`. Scenes with patches under a law, with the output
    /// `deflections` or `piezo`.
    DeflectionReduction {
        /// Link (1-3).
        link: usize,
    },
    /// The voltage the vibration control costs: the largest applied voltage of any patch,
    /// whether any patch saturated and the largest fraction of the output samples a patch
    /// spent saturated (docs/piezo.md): columns `V_patch_max_V`, `patch_saturated`
    /// (`yes`/`no`), `patch_saturated_fraction`. Scenes with patches.
    PatchVoltage,
    /// The plan of a scene with a `[plan]` section (docs/planning.md; the case runs
    /// `flexprr plan` with its flexible check instead of `flexprr run`, and the other
    /// quantities come from the planned motion's run): columns `cycle_time_s` (the move's
    /// duration or the period), `plan_frequency_Hz` (a periodic plan's largest repetition
    /// rate, else empty), `residual_vibration_m` (after a rest-to-rest move, else empty),
    /// `plan_peak_deflection_m`.
    Plan,
    /// A scalar an output producer offers by name (`flexprr_run::OutputProducer::quantities`,
    /// the built-in ones or a program's own): column `<name>`. The scenes must request the
    /// output that offers it.
    Output {
        /// The quantity's name, e.g. `slider_power_peak_W`.
        name: String,
        /// What the registry says of it (filled in when the study is checked).
        #[serde(skip)]
        about: OutputQuantity,
    },
}

/// What the output registry says of a named quantity: the output offering it, its unit and
/// label (empty until the study is checked against its registry).
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

    fn new(name: String, label: String, unit: &'static str, values: ColumnValues) -> Self {
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

impl Quantity {
    /// Column names.
    pub fn columns(&self) -> Vec<String> {
        self.column_specs().into_iter().map(|c| c.name).collect()
    }

    /// The typed columns, in table order.
    pub fn column_specs(&self) -> Vec<Column> {
        use ColumnValues::{Flag, Number, OptionalNumber};
        match *self {
            Quantity::FrequencyRange { link, mode } => vec![
                Column::new(
                    format!("f_min_{link}_{mode}_Hz"),
                    format!("lowest frequency of link {link}, mode {mode}"),
                    "Hz",
                    Number,
                ),
                Column::new(
                    format!("f_max_{link}_{mode}_Hz"),
                    format!("highest frequency of link {link}, mode {mode}"),
                    "Hz",
                    Number,
                ),
            ],
            Quantity::StiffnessRatio { link, mode } => vec![Column::new(
                format!("stiffness_ratio_min_{link}_{mode}"),
                format!("lowest ω²/ω₀² of link {link}, mode {mode}"),
                "",
                Number,
            )],
            Quantity::PeakAxialForce { link } => vec![
                Column::new(
                    format!("P_max_{link}_N"),
                    format!("largest tension in link {link}"),
                    "N",
                    Number,
                ),
                Column::new(
                    format!("P_min_{link}_N"),
                    format!("largest compression in link {link}"),
                    "N",
                    Number,
                ),
            ],
            Quantity::PeakDeflection { link } => vec![Column::new(
                format!("w_peak_{link}_m"),
                format!("peak deflection of link {link}"),
                "m",
                Number,
            )],
            Quantity::Collapse => vec![
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
            ],
            Quantity::LowestFrequency
            | Quantity::DeflectionReduction { .. }
            | Quantity::PatchVoltage => self.analysis_column_specs(),
            Quantity::Plan => vec![
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
            ],
            Quantity::Output { ref name, about } => vec![Column::new(
                name.clone(),
                if about.label.is_empty() {
                    name.clone()
                } else {
                    about.label.to_string()
                },
                about.unit,
                Number,
            )],
            Quantity::Buckling { link } => vec![
                Column::new(
                    format!("buckles_{link}"),
                    format!("link {link} buckles"),
                    "",
                    Flag,
                ),
                Column::new(
                    format!("buckling_start_{link}_s"),
                    format!("time link {link} starts to buckle"),
                    "s",
                    OptionalNumber,
                ),
            ],
        }
    }

    /// The columns of the quantities from the linear models and the vibration control.
    fn analysis_column_specs(&self) -> Vec<Column> {
        use ColumnValues::{Flag, Number};
        match *self {
            Quantity::LowestFrequency => vec![
                Column::new(
                    "f_machine_lowest_Hz".into(),
                    "lowest whole-machine frequency at rest".into(),
                    "Hz",
                    Number,
                ),
                Column::new(
                    "zeta_machine_lowest".into(),
                    "damping ratio of the lowest whole-machine mode".into(),
                    "",
                    Number,
                ),
            ],
            Quantity::DeflectionReduction { link } => vec![
                Column::new(
                    format!("w_peak_reduction_{link}_percent"),
                    format!("peak reduction, link {link}"),
                    "%",
                    Number,
                ),
                Column::new(
                    format!("w_rms_reduction_{link}_percent"),
                    format!("RMS reduction, link {link}"),
                    "%",
                    Number,
                ),
            ],
            Quantity::PatchVoltage => vec![
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
            ],
            _ => Vec::new(),
        }
    }

    /// Link (1-based), for the quantities of one link.
    pub fn link(&self) -> Option<usize> {
        match *self {
            Quantity::FrequencyRange { link, .. }
            | Quantity::StiffnessRatio { link, .. }
            | Quantity::PeakAxialForce { link }
            | Quantity::PeakDeflection { link }
            | Quantity::DeflectionReduction { link }
            | Quantity::Buckling { link } => Some(link),
            Quantity::Collapse
            | Quantity::LowestFrequency
            | Quantity::PatchVoltage
            | Quantity::Plan
            | Quantity::Output { .. } => None,
        }
    }

    /// Mode (1-based), for the quantities of one mode.
    pub fn mode(&self) -> Option<usize> {
        match *self {
            Quantity::FrequencyRange { mode, .. } | Quantity::StiffnessRatio { mode, .. } => {
                Some(mode)
            }
            _ => None,
        }
    }

    /// Why a case whose scene is `scene` cannot give this quantity (an output it does not
    /// request, a mode its links do not have, a model that cannot collapse); `None` when it
    /// can. A case is refused on this before it runs.
    pub fn unavailable(&self, scene: &flexprr_scene::Scene) -> Option<String> {
        use flexprr_scene::OutputKind;
        let has = |k: OutputKind| scene.outputs.contains(&k);
        let name = self.columns()[0].clone();
        let needs = |output: &str| {
            Some(format!(
                "quantity {name} needs the output \"{output}\" (add it to output.requests, \
                 e.g. in [set.output])"
            ))
        };
        match *self {
            Quantity::Output { about, .. } => (!scene.requests(about.output)).then(|| {
                format!(
                    "quantity {name} needs the output \"{}\" (add it to output.custom, e.g. \
                     in [set.output])",
                    about.output
                )
            }),
            Quantity::FrequencyRange { mode, .. } | Quantity::StiffnessRatio { mode, .. } => {
                if !has(OutputKind::Frequencies) {
                    return needs("frequencies");
                }
                let modes = scene.machine.links[0].modes();
                (mode > modes)
                    .then(|| format!("quantity {name}: the links have {modes} modes, not {mode}"))
            }
            Quantity::Buckling { .. } => (!has(OutputKind::Frequencies))
                .then(|| needs("frequencies"))
                .flatten(),
            Quantity::PeakAxialForce { .. } => (!has(OutputKind::AxialForces)
                && !has(OutputKind::Frequencies))
            .then(|| needs("axial_forces\" or \"frequencies"))
            .flatten(),
            Quantity::PeakDeflection { .. } => (!has(OutputKind::Deflections))
                .then(|| needs("deflections"))
                .flatten(),
            Quantity::DeflectionReduction { .. } => {
                if scene.patches.is_empty() || scene.vibration_controller.is_none() {
                    Some(format!(
                        "quantity {name} needs piezoelectric patches under a vibration control \
                         law ([[links.patches]] and [vibration_control], docs/piezo.md)"
                    ))
                } else if !has(OutputKind::Deflections) && !has(OutputKind::Piezo) {
                    needs("deflections")
                } else {
                    None
                }
            }
            Quantity::Plan => scene.file.plan.is_none().then(|| {
                "quantity cycle_time_s needs a [plan] section in the scene (docs/planning.md): \
                 add one to the base scene or the study's [set.plan]"
                    .to_string()
            }),
            Quantity::PatchVoltage => scene.patches.is_empty().then(|| {
                format!(
                    "quantity {name} needs piezoelectric patches ([[links.patches]], \
                     docs/piezo.md)"
                )
            }),
            Quantity::LowestFrequency => {
                (!scene.coupling.capabilities().free_platform).then(|| {
                    "quantity f_machine_lowest_Hz needs a model of the whole machine \
                 (model.coupling = \"coupled\" or \"nonlinear\"): the KED model prescribes the \
                 platform and the sliders"
                        .into()
                })
            }
            Quantity::Collapse => {
                if !scene.coupling.capabilities().free_platform {
                    Some(
                        "quantity collapses needs a coupled or nonlinear model (model.coupling): \
                         a KED model follows the rigid motion and cannot collapse"
                            .into(),
                    )
                } else if !scene.needs_integration() {
                    needs("deflections")
                } else {
                    None
                }
            }
        }
    }

    /// The quantity's values for one run, formatted with [`format_value`].
    ///
    /// # Errors
    /// A message when the run lacks the output the quantity needs or the mode does not exist.
    pub fn derive(&self, result: &RunResult) -> Result<Vec<String>, String> {
        self.derive_outcome(result, None)
    }

    /// The quantity's values for a run that finished, or (`collapse`) stopped with the
    /// collapse outcome; `result` is then the run up to the collapse.
    ///
    /// # Errors
    /// As [`Quantity::derive`].
    pub fn derive_outcome(
        &self,
        result: &RunResult,
        collapse: Option<&Collapse>,
    ) -> Result<Vec<String>, String> {
        if *self == Quantity::Collapse {
            return Ok(match collapse {
                Some(c) => vec![
                    "yes".into(),
                    format_value(c.t),
                    format_value((c.link + 1) as f64),
                    format_value(c.deflection),
                ],
                None => vec!["no".into(), String::new(), String::new(), String::new()],
            });
        }
        let i = self.link().unwrap_or(1) - 1;
        let needs = |output: &str| {
            format!(
                "quantity {} needs the output \"{output}\"",
                self.columns()[0]
            )
        };
        match *self {
            Quantity::FrequencyRange { mode, .. } | Quantity::StiffnessRatio { mode, .. } => {
                let history = result
                    .frequencies
                    .as_ref()
                    .ok_or_else(|| needs("frequencies"))?;
                let range = history
                    .ranges
                    .iter()
                    .find(|r| r.link == i && r.mode + 1 == mode)
                    .ok_or_else(|| format!("link {} has no mode {mode}", i + 1))?;
                Ok(match self {
                    Quantity::FrequencyRange { .. } => {
                        vec![format_value(range.min_hz), format_value(range.max_hz)]
                    }
                    _ => vec![format_value(range.min_stiffness_ratio)],
                })
            }
            Quantity::PeakAxialForce { .. } => {
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
                    return Err(needs("axial_forces\" or \"frequencies"));
                };
                let max = forces.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                let min = forces.iter().copied().fold(f64::INFINITY, f64::min);
                Ok(vec![format_value(max), format_value(min)])
            }
            Quantity::PeakDeflection { .. } => {
                let table = result
                    .table("deflections")
                    .ok_or_else(|| needs("deflections"))?;
                let column = table
                    .columns
                    .iter()
                    .position(|c| c.quantity == RunQuantity::Deflection && c.link == Some(i))
                    .ok_or_else(|| needs("deflections"))?;
                let peak = table.data[column]
                    .iter()
                    .fold(0.0_f64, |m, w| m.max(w.abs()));
                Ok(vec![format_value(peak)])
            }
            Quantity::Buckling { .. } => {
                let history = result
                    .frequencies
                    .as_ref()
                    .ok_or_else(|| needs("frequencies"))?;
                let start = history
                    .buckling
                    .iter()
                    .filter(|b| b.link == i)
                    .map(|b| b.t_start)
                    .fold(None, |m: Option<f64>, t| Some(m.map_or(t, |m| m.min(t))));
                Ok(match start {
                    Some(t) => vec!["yes".into(), format_value(t)],
                    None => vec!["no".into(), String::new()],
                })
            }
            Quantity::DeflectionReduction { .. } | Quantity::PatchVoltage => {
                self.derive_piezo(result, i, needs)
            }
            Quantity::Collapse => Err("the collapse is derived above".into()),
            Quantity::Plan => {
                let plan = result
                    .report::<flexprr_plan::PlanSummary>()
                    .ok_or_else(|| "quantity cycle_time_s: the case was not planned".to_string())?;
                let optional = |v: Option<f64>| v.map_or(String::new(), format_value);
                Ok(vec![
                    format_value(plan.cycle_time),
                    optional(plan.frequency),
                    optional(plan.residual_vibration),
                    format_value(plan.peak_deflection.unwrap_or(0.0)),
                ])
            }
            Quantity::Output { ref name, about } => match result.quantity(name) {
                Some(Ok(v)) => Ok(vec![format_value(v)]),
                Some(Err(why)) => Err(format!("quantity {name}: {why}")),
                None => Err(needs(about.output)),
            },
            Quantity::LowestFrequency => Err(
                "quantity f_machine_lowest_Hz is computed from the case's scene \
                 (Quantity::derive_from_scene), not from its run"
                    .into(),
            ),
        }
    }

    /// The vibration-control quantities of link `i` from the run's piezo report.
    fn derive_piezo(
        &self,
        result: &RunResult,
        i: usize,
        needs: impl Fn(&str) -> String,
    ) -> Result<Vec<String>, String> {
        match *self {
            Quantity::DeflectionReduction { .. } => {
                let reduction = result
                    .report::<flexprr_run::piezo::PiezoReport>()
                    .and_then(|p| p.reduction.as_ref())
                    .and_then(|r| r.get(i))
                    .ok_or_else(|| needs("deflections"))?;
                let percent = |r: Option<f64>| {
                    r.map(format_value).ok_or_else(|| {
                        format!(
                            "quantity {}: link {} does not deflect without control",
                            self.columns()[0],
                            i + 1
                        )
                    })
                };
                Ok(vec![
                    percent(reduction.peak_reduction_percent())?,
                    percent(reduction.rms_reduction_percent())?,
                ])
            }
            Quantity::PatchVoltage => {
                let piezo = result
                    .report::<flexprr_run::piezo::PiezoReport>()
                    .ok_or_else(|| "quantity V_patch_max_V: the run has no patches".to_string())?;
                let max = |f: fn(&flexprr_run::piezo::PatchSummary) -> f64| {
                    piezo.patches.iter().map(f).fold(0.0_f64, f64::max)
                };
                Ok(vec![
                    format_value(max(|p| p.max_abs_voltage)),
                    if piezo.any_saturated() { "yes" } else { "no" }.into(),
                    format_value(max(|p| p.saturated_fraction)),
                ])
            }
            _ => Err(format!(
                "quantity {} is not a vibration-control quantity",
                self.columns()[0]
            )),
        }
    }

    /// The values of a quantity computed from the case's scene rather than its run (the
    /// lowest whole-machine frequency at rest at the start pose); `None` for the others.
    pub fn derive_from_scene(
        &self,
        scene: &flexprr_scene::Scene,
    ) -> Option<Result<Vec<String>, String>> {
        use flexprr_linear_tools::linear::OperatingPoint;
        use flexprr_linear_tools::machine_modes::{lowest_frequency, start_pose};
        match self {
            Quantity::LowestFrequency => Some(
                lowest_frequency(scene, OperatingPoint::Rest(start_pose(scene)))
                    .map(|(f, zeta)| vec![format_value(f), format_value(zeta)])
                    .map_err(|e| format!("quantity f_machine_lowest_Hz: {e}")),
            ),
            _ => None,
        }
    }
}
