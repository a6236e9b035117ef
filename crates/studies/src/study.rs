//! Batch studies: a base scene, sweep axes over any scene key, derived quantities per case,
//! run in parallel, shardable across machines and resumable (`docs/studies.md`).
//!
//! A study file names a base scene (`base = "paper_f20.toml"`, relative to the study file,
//! or an inline `[scene]` table), optional overrides applied to every case (`[set]`, merged
//! key by key), sweep axes (`[[axis]]` with `key` a dotted path into the scene TOML and
//! either `values` or a linear/log `range`), how axes combine (`combine = "product"` or
//! `"zip"`) and the derived quantities to tabulate (`quantities = [{ kind = ..., link = 1 }]`).
//! The file is parsed by [`flexprr_scene::parse_toml`], so every bad value is reported with
//! `file:line:column` and its dotted key, as in a scene file.
//!
//! Each case's scene is built by editing the base scene as a TOML value, serialising it and
//! running [`Scene::from_text`], so a case gets exactly the validation a scene file gets;
//! an invalid or failing case is recorded with its error and the study goes on.
//!
//! Cases are numbered in a fixed order (product: the first axis varies slowest). Each
//! finished case is written atomically (temporary file + rename) as `cases/<id>.json`;
//! `results.csv` is assembled from those files, sorted by case id, with floats written by
//! [`format_value`], so the table does not depend on the number of threads, on sharding
//! (`id % n == k - 1` for shard `k/n`) or on interruptions followed by a resume.

use std::fmt::Write as _;
use std::panic::AssertUnwindSafe;
use std::path::Path;
use std::sync::Arc;

use flexprr_run::{Collapse, RunResult, run_registered};
use flexprr_scene::{ScenarioError, Scene, locate, parse_toml};

pub use crate::error::{MAX_INPUT_BYTES, StudyError, read_input_file};
pub use crate::file::{AxisConfig, Combine, PlotConfig, RangeConfig, Spacing, StudyFile};
pub use crate::plot::write_plots;
pub use crate::quantity::{
    CaseRun, Column, ColumnValues, OutputQuantity, Quantity, QuantityKind, QuantityParams,
    QuantityRegistry,
};
pub use crate::record::{
    CaseFailure, CaseRecord, CaseStatus, FailureKind, classify_run_failure, format_value,
    read_case_records, results_csv,
};
pub use crate::runner::{
    MAX_THREADS_PER_CPU, MergeSummary, STUDY_PRODUCTS, Shard, StudyOptions, StudyProgress,
    StudySummary, merge_studies, merge_studies_with, run_map_study, run_search_study, run_study,
    worker_threads,
};

use crate::record::format_parameter;

/// One case of a study: its id and the value of each axis.
#[derive(Debug, Clone, PartialEq)]
pub struct Case {
    /// Case id (0-based, the position in the fixed case order).
    pub id: usize,
    /// Value of each axis.
    pub values: Vec<toml::Value>,
}

/// A sweep axis with its values expanded.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// Dotted scene key.
    pub key: String,
    /// Values.
    pub values: Vec<toml::Value>,
}

/// A loaded, checked study: the base scene (with `[set]` applied), the expanded cases and
/// the quantities.
#[derive(Debug, Clone)]
pub struct Study {
    /// Study name.
    pub name: String,
    /// Study file name, for messages.
    pub file: String,
    /// Base scene with the overrides applied.
    pub base: toml::Table,
    /// Axes.
    pub axes: Vec<Axis>,
    /// Cases in id order.
    pub cases: Vec<Case>,
    /// Quantities, each read by its registered kind.
    pub quantities: Vec<Arc<dyn Quantity>>,
    /// Plots.
    pub plots: Vec<PlotConfig>,
    /// FNV-1a hash of everything that determines the table (base scene, axes, quantities).
    pub fingerprint: String,
    /// The speed search, when the study is one (`[search]`) instead of a sweep.
    pub search: Option<crate::search::Search>,
    /// The workspace map, when the study is one (`[map]`) instead of a sweep.
    pub map: Option<crate::map::Map>,
    /// The files the study reads (the study file, when loaded from one, and the base
    /// scene file): an output directory never overwrites them.
    pub inputs: Vec<std::path::PathBuf>,
    /// The parts its scenes and runs may name beyond the built-in ones.
    pub plugins: Plugins,
}

/// The registries a study loads its scenes and runs its cases with: the scene layer's named
/// parts, the run's output producers (whose quantities a study reaches by name,
/// [`crate::quantity::output::Output`]) and the quantity kinds. The built-in ones by
/// default.
#[derive(Debug, Clone, Default)]
pub struct Plugins {
    /// Named parts of scenes (models, bases, laws, declared outputs).
    pub scenes: flexprr_scene::Registry,
    /// Output producers.
    pub outputs: flexprr_run::OutputRegistry,
    /// Quantity kinds (`quantities = [{ kind = "..." }]`).
    pub quantities: QuantityRegistry,
}

/// Deep merge: tables merge key by key, anything else replaces.
fn merge_into(target: &mut toml::Table, overrides: &toml::Table) {
    for (key, value) in overrides {
        match (target.get_mut(key), value) {
            (Some(toml::Value::Table(t)), toml::Value::Table(o)) => merge_into(t, o),
            _ => {
                target.insert(key.clone(), value.clone());
            }
        }
    }
}

/// Sets `value` at the dotted `key` in `scene`: the scene layer's
/// [`flexprr_scene::setting::set_key`] (missing tables created, an integer replacing a float
/// becomes a float, numeric segments index arrays, a refused key changes nothing).
///
/// # Errors
/// Its message: an empty segment, an index out of range or into an array that is not
/// there (give the whole array in the base scene or in `[set]`), or a path through a value
/// that is neither a table nor an array.
pub fn set_key(scene: &mut toml::Table, key: &str, value: &toml::Value) -> Result<(), String> {
    flexprr_scene::setting::set_key(scene, key, value)
}

/// FNV-1a, 64 bit (Fowler, Noll, Vo): a hash that is stable across builds and platforms.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// Locates study keys in the study's text for messages.
pub(crate) struct Locator<'a> {
    pub(crate) file: &'a str,
    pub(crate) text: &'a str,
}

impl Locator<'_> {
    /// A [`StudyError::Input`] for `key`, located in the study file when the key is there.
    pub(crate) fn input(&self, key: &str, message: impl Into<String>) -> StudyError {
        StudyError::Input {
            file: self.file.to_string(),
            location: locate(self.file, self.text, key),
            key: key.to_string(),
            message: message.into(),
        }
    }
}

impl Study {
    /// Reads and checks a study file; `base` is resolved relative to its directory.
    ///
    /// # Errors
    /// [`StudyError::InputFile`] if the study or the base scene is missing, unreadable or
    /// not a regular file of at most [`MAX_INPUT_BYTES`],
    /// [`StudyError::Input`] (with `file:line:column` and the key) for anything wrong in the
    /// study, [`StudyError::Scene`] for a base scene that is not valid TOML.
    pub fn load(path: &Path) -> Result<Self, StudyError> {
        Self::load_with(Plugins::default(), path)
    }

    /// As [`Study::load`], with the parts and outputs of `plugins`.
    ///
    /// # Errors
    /// As [`Study::load`].
    pub fn load_with(plugins: Plugins, path: &Path) -> Result<Self, StudyError> {
        let text = read_input_file(path)?;
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("study");
        let dir = path.parent().unwrap_or(Path::new("."));
        let file = path.display().to_string();
        let mut study = Self::from_text_with(plugins, &file, name, &text, dir)?;
        study.inputs.insert(0, path.to_path_buf());
        Ok(study)
    }

    /// Whether `text` looks like a study file rather than a scene or link file: it parses
    /// as TOML and has a top-level `[[axis]]` array, a `base` string or a `quantities`
    /// array, none of which a scene has (for `flexprr check`, to say what a file is).
    pub fn looks_like_study(text: &str) -> bool {
        let Ok(table) = text.parse::<toml::Table>() else {
            return false;
        };
        matches!(table.get("axis"), Some(toml::Value::Array(_)))
            || matches!(table.get("base"), Some(toml::Value::String(_)))
            || matches!(table.get("quantities"), Some(toml::Value::Array(_)))
    }

    /// Parses and checks study text; `file` names it in messages, `default_name` is used
    /// without a `name`, `dir` resolves `base`.
    ///
    /// # Errors
    /// As [`Study::load`].
    pub fn from_text(
        file: &str,
        default_name: &str,
        text: &str,
        dir: &Path,
    ) -> Result<Self, StudyError> {
        Self::from_text_with(Plugins::default(), file, default_name, text, dir)
    }

    /// As [`Study::from_text`], with the parts and outputs of `plugins`.
    ///
    /// # Errors
    /// As [`Study::load`].
    pub fn from_text_with(
        plugins: Plugins,
        file: &str,
        default_name: &str,
        text: &str,
        dir: &Path,
    ) -> Result<Self, StudyError> {
        let raw: StudyFile =
            parse_toml(file, text).map_err(|e| StudyError::from_study_parse(file, e))?;
        let at = Locator { file, text };
        let quantities = plugins
            .quantities
            .parse_all(&raw.quantities, &plugins.outputs, &at)?;
        let (mut base, source) = load_base(&raw, dir, &at)?;
        merge_into(&mut base, &raw.set);
        let axes = expand_axes(&raw.axis, &base, &at)?;
        let cases = combine_cases(raw.combine, &axes, &at)?;
        let search = match &raw.search {
            None => None,
            Some(config) => {
                let search = crate::search::Search::from_config(config)
                    .map_err(|(key, message)| at.input(key, message))?;
                crate::validate::check_search_keys(&search, &axes, &at)?;
                Some(search)
            }
        };
        let map = match &raw.map {
            None => None,
            Some(config) => {
                crate::validate::check_map_alone(&raw, &at)?;
                Some(
                    crate::map::Map::from_config(config)
                        .map_err(|(key, message)| at.input(&key, message))?,
                )
            }
        };
        let name = match &raw.name {
            Some(name) => {
                if let Some(why) = flexprr_scene::unsafe_name_reason(name) {
                    return Err(at.input(
                        "name",
                        format!(
                            "\"{name}\" {why}: a study name is 1 to {} characters of A-Z a-z 0-9 . _ -, not starting with .",
                            flexprr_scene::MAX_NAME_LEN
                        ),
                    ));
                }
                name.clone()
            }
            None => flexprr_scene::sanitize_name(default_name),
        };
        let study = Study {
            name,
            file: file.to_string(),
            base,
            axes,
            cases,
            quantities,
            plots: raw.plot.clone(),
            fingerprint: String::new(),
            search,
            map,
            inputs: source.path().into_iter().collect(),
            plugins,
        };
        study.check_plots(&at)?;
        let context = crate::validate::Context {
            at: &at,
            set: &raw.set,
            source: &source,
            axes: &raw.axis,
            base: &study.base,
        };
        match (&study.search, &study.map) {
            (Some(search), _) => crate::validate::check_searches(&study, search, &context)?,
            (None, Some(map)) => crate::validate::check_map(&study, map, &context)?,
            (None, None) => {
                crate::validate::check_cases(&study, &context)?;
                crate::validate::check_quantities_available(&study, &context)?;
            }
        }
        let fingerprint = study.compute_fingerprint(raw.combine);
        Ok(Study {
            fingerprint,
            ..study
        })
    }

    /// Plot files must be plain `.svg` names, each once; plot keys must be axes, `x` a
    /// numeric one; plotted columns must be quantity columns.
    fn check_plots(&self, at: &Locator<'_>) -> Result<(), StudyError> {
        let columns = self.quantity_column_specs();
        for (k, p) in self.plots.iter().enumerate() {
            if let Some(why) = crate::validate::plot_file_problem(&p.file) {
                return Err(at.input(&format!("plot.{k}.file"), why));
            }
            if let Some(j) = self.plots[..k].iter().position(|q| q.file == p.file) {
                return Err(at.input(
                    &format!("plot.{k}.file"),
                    format!(
                        "\"{}\" is also the file of plot {j}: give each plot its own file",
                        p.file
                    ),
                ));
            }
            let keys = [("x", Some(&p.x)), ("series", p.series.as_ref())];
            for (field, key) in keys {
                let Some(key) = key else { continue };
                let Some(axis) = self.axes.iter().find(|a| &a.key == key) else {
                    let axes: Vec<&str> = self.axes.iter().map(|a| a.key.as_str()).collect();
                    return Err(at.input(
                        &format!("plot.{k}.{field}"),
                        format!("\"{key}\" is not an axis key (axes: {})", axes.join(", ")),
                    ));
                };
                let text = axis
                    .values
                    .iter()
                    .find(|v| v.as_float().is_none() && v.as_integer().is_none());
                if let (Some(text), "x") = (text, field) {
                    return Err(at.input(
                        &format!("plot.{k}.x"),
                        format!(
                            "the axis \"{key}\" has values that are not numbers ({}): x must be a numeric axis; draw a text axis as `series`",
                            format_parameter(text)
                        ),
                    ));
                }
            }
            for (j, y) in p.y.iter().enumerate() {
                if !columns.iter().any(|c| &c.name == y) {
                    let names: Vec<&str> = columns.iter().map(|c| c.name.as_str()).collect();
                    return Err(at.input(
                        &format!("plot.{k}.y.{j}"),
                        format!(
                            "\"{y}\" is not a quantity column (columns: {})",
                            names.join(", ")
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// FNV-1a of everything that determines the table: the base scene, the axes, how they
    /// combine and the columns.
    fn compute_fingerprint(&self, combine: Combine) -> String {
        let mut canonical = toml::to_string(&self.base).unwrap_or_default();
        for axis in &self.axes {
            let _ = write!(canonical, "\n{}:", axis.key);
            for v in &axis.values {
                let _ = write!(canonical, " {v}");
            }
        }
        let _ = write!(canonical, "\n{combine:?}\n{}", self.columns().join(","));
        if let Some(map) = &self.map {
            let _ = write!(canonical, "\nmap: {map:?}");
        }
        format!("{:016x}", fnv1a(canonical.as_bytes()))
    }

    /// Header of `results.csv`: `case`, the axis keys, the quantity columns, `status`,
    /// `error`.
    pub fn columns(&self) -> Vec<String> {
        let mut columns = vec!["case".to_string()];
        columns.extend(self.axes.iter().map(|a| a.key.clone()));
        columns.extend(self.quantities.iter().flat_map(|q| q.columns()));
        columns.push("status".into());
        columns.push("error".into());
        columns
    }

    /// The typed quantity columns, in table order.
    pub fn quantity_column_specs(&self) -> Vec<Column> {
        self.quantities
            .iter()
            .flat_map(|q| q.column_specs())
            .collect()
    }

    fn quantity_columns(&self) -> usize {
        self.quantities.iter().map(|q| q.columns().len()).sum()
    }

    /// The formatted parameters of a case, as in its record and row.
    pub fn case_parameters(&self, case: &Case) -> Vec<String> {
        case.values.iter().map(format_parameter).collect()
    }

    /// Checks a record read back from an output directory against the study: it belongs to
    /// one of the study's cases, was written by this study (fingerprint), holds that case's
    /// parameters, and is consistent ([`CaseRecord::check`]: the right number of values,
    /// each of its column's type and finite, or a failure that matches its status).
    ///
    /// # Errors
    /// A message naming the first problem.
    pub fn check_record(&self, record: &CaseRecord) -> Result<(), String> {
        let case = self.cases.get(record.id).ok_or_else(|| {
            format!(
                "case {} is outside the study's {} cases",
                record.id,
                self.cases.len()
            )
        })?;
        if record.fingerprint != self.fingerprint {
            return Err(format!(
                "recorded by another study or another version of it (fingerprint {}, this one {})",
                record.fingerprint, self.fingerprint
            ));
        }
        let parameters = self.case_parameters(case);
        record.check(&self.quantity_column_specs(), Some(&parameters))
    }

    /// The scene text of a case: the base scene with the case's axis values set.
    ///
    /// # Errors
    /// A message when a key cannot be set.
    pub fn case_scene_text(&self, case: &Case) -> Result<String, String> {
        toml::to_string(&self.case_table(case)?).map_err(|e| e.to_string())
    }

    /// A case's scene as a TOML table: the base scene with the case's axis values set.
    ///
    /// # Errors
    /// The message of [`set_key`] when a value cannot be set.
    pub fn case_table(&self, case: &Case) -> Result<toml::Table, String> {
        let mut scene = self.base.clone();
        for (axis, value) in self.axes.iter().zip(&case.values) {
            set_key(&mut scene, &axis.key, value)?;
        }
        Ok(scene)
    }

    /// Builds a case's scene (same validation as a scene file).
    ///
    /// # Errors
    /// [`ScenarioError::Input`] for bad parameters.
    pub fn case_scene(&self, case: &Case) -> Result<Scene, ScenarioError> {
        let text = self
            .case_scene_text(case)
            .map_err(|message| ScenarioError::Input {
                location: None,
                key: String::new(),
                message,
            })?;
        let name = format!("{}_{:06}", self.name, case.id);
        let file = format!("{} case {}", self.name, case.id);
        Scene::from_text_with(&self.plugins.scenes, &file, &name, &text)
    }

    /// Runs one case; never fails: bad parameters, run failures and panics are recorded in
    /// the returned record (status, `error` and a [`CaseFailure`] with kind and time). The
    /// scene and run are returned when the case ran.
    pub fn run_case(&self, case: &Case) -> (CaseRecord, Option<(Scene, RunResult)>) {
        let mut record = CaseRecord {
            id: case.id,
            fingerprint: self.fingerprint.clone(),
            parameters: self.case_parameters(case),
            quantities: vec![String::new(); self.quantity_columns()],
            status: CaseStatus::Ok,
            error: String::new(),
            failure: None,
        };
        match self.try_case(case) {
            Ok((values, scene, result)) => {
                record.quantities = values;
                (record, Some((scene, result)))
            }
            Err(failure) => {
                record.fail(failure);
                (record, None)
            }
        }
    }

    /// Builds, runs and evaluates one case; a failure says why.
    fn try_case(&self, case: &Case) -> Result<(Vec<String>, Scene, RunResult), CaseFailure> {
        let scene = self
            .case_scene(case)
            .map_err(|e| CaseFailure::new(FailureKind::InvalidInput, None, &unlocated(e)))?;
        if let Some(why) = self.quantities.iter().find_map(|q| q.unavailable(&scene)) {
            return Err(CaseFailure::new(FailureKind::Quantity, None, &why));
        }
        if self.quantities.iter().any(|q| q.planned()) {
            return self.plan_case(scene);
        }
        let outputs = &self.plugins.outputs;
        let outcome = std::panic::catch_unwind(AssertUnwindSafe(|| {
            run_registered(&scene, outputs, &mut |_| {})
        }));
        let wants_collapse = self.quantities.iter().any(|q| q.keeps_collapse());
        let (result, collapse) = match outcome {
            Ok(Ok(r)) => (r, None),
            Ok(Err(failure)) if wants_collapse && failure.error.collapse().is_some() => {
                (*failure.partial, failure.error.collapse())
            }
            Ok(Err(failure)) => {
                let (kind, time) = classify_run_failure(&failure.error);
                return Err(CaseFailure::new(kind, time, &failure.error.to_string()));
            }
            Err(panic) => {
                let what = panic
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_default();
                return Err(CaseFailure::new(
                    FailureKind::Panic,
                    None,
                    &format!("panic: {what}"),
                ));
            }
        };
        if let Some((time, message)) = divergence(&result) {
            return Err(CaseFailure::new(FailureKind::Diverged, time, &message));
        }
        let values = self.derive_quantities(&scene, &result, collapse.as_ref())?;
        Ok((values, scene, result))
    }

    /// A case with the `plan` quantity: the scene planned by its `[plan]` section with the
    /// flexible check ([`flexprr_plan::plan_run`]), its quantities from the planned motion's
    /// run. A plan no motion can meet is an invalid input (the limit and where); a failed
    /// run of the flexible model is classified as any run failure.
    fn plan_case(&self, scene: Scene) -> Result<(Vec<String>, Scene, RunResult), CaseFailure> {
        use flexprr_plan::PlanError;
        let outcome = std::panic::catch_unwind(AssertUnwindSafe(|| flexprr_plan::plan_run(&scene)));
        let result = match outcome {
            Ok(Ok(result)) => result,
            Ok(Err(PlanError::Run { source, .. })) => {
                let (kind, time) = classify_run_failure(&source);
                return Err(CaseFailure::new(kind, time, &source.to_string()));
            }
            Ok(Err(e)) => {
                return Err(CaseFailure::new(
                    FailureKind::InvalidInput,
                    None,
                    &format!("plan: {e}"),
                ));
            }
            Err(_) => {
                return Err(CaseFailure::new(
                    FailureKind::Panic,
                    None,
                    "panic while planning",
                ));
            }
        };
        let values = self.derive_quantities(&scene, &result, None)?;
        Ok((values, scene, result))
    }

    /// The quantity values of a finished run, each checked against its column (a non-finite
    /// value fails the case instead of reaching the table).
    fn derive_quantities(
        &self,
        scene: &Scene,
        result: &RunResult,
        collapse: Option<&Collapse>,
    ) -> Result<Vec<String>, CaseFailure> {
        let mut values = Vec::with_capacity(self.quantity_columns());
        let run = CaseRun {
            scene,
            result,
            collapse,
        };
        for q in &self.quantities {
            let derived = q
                .derive(&run)
                .map_err(|m| CaseFailure::new(FailureKind::Quantity, None, &m))?;
            for (value, column) in derived.into_iter().zip(q.column_specs()) {
                if !column.accepts(&value) {
                    return Err(CaseFailure::new(
                        FailureKind::NonFinite,
                        None,
                        &format!("quantity {} is {value}", column.name),
                    ));
                }
                values.push(value);
            }
        }
        Ok(values)
    }

    /// The cases of shard `shard` (all cases without a shard).
    pub fn shard_cases(&self, shard: Option<Shard>) -> Vec<&Case> {
        self.cases
            .iter()
            .filter(|c| shard.is_none_or(|s| s.contains(c.id)))
            .collect()
    }
}

/// Where the base scene comes from, to place its errors.
#[derive(Debug, Clone)]
pub(crate) enum BaseSource {
    /// A scene file: its path, the path as shown in messages, and its text.
    File {
        path: std::path::PathBuf,
        shown: String,
        text: String,
    },
    /// The study's inline `[scene]` table.
    Inline,
}

impl BaseSource {
    /// The base scene file, if there is one.
    pub(crate) fn path(&self) -> Option<std::path::PathBuf> {
        match self {
            BaseSource::File { path, .. } => Some(path.clone()),
            BaseSource::Inline => None,
        }
    }
}

/// The base scene as a TOML table: the file named by `base` (relative to `dir`, parsed with
/// located errors) or the inline `[scene]`.
fn load_base(
    raw: &StudyFile,
    dir: &Path,
    at: &Locator<'_>,
) -> Result<(toml::Table, BaseSource), StudyError> {
    match (&raw.base, &raw.scene) {
        (Some(base), None) => {
            let path = dir.join(base);
            let text = read_input_file(&path)?;
            let shown = path.display().to_string();
            let table = parse_toml::<toml::Table>(&shown, &text)?;
            Ok((table, BaseSource::File { path, shown, text }))
        }
        (None, Some(scene)) => Ok((scene.clone(), BaseSource::Inline)),
        (Some(_), Some(_)) => Err(at.input(
            "base",
            "give either `base = \"scene.toml\"` or an inline `[scene]` table, not both",
        )),
        (None, None) => Err(at.input(
            "base",
            "missing: give `base = \"scene.toml\"` or an inline `[scene]` table",
        )),
    }
}

/// Most cases a study may have: every case is one record file in `cases/` and one row of
/// `results.csv`, assembled in memory; a million is already a job for a cluster (at the
/// milliseconds to seconds a case takes) and far more than any directory listing handles
/// comfortably. A larger sweep is almost always a typing error (`count = 1e12`).
pub const MAX_CASES: usize = 1_000_000;

/// Whether two dotted keys overlap: equal, or one names a table or array holding the other
/// (`machine` and `machine.platform_mass`).
pub(crate) fn keys_overlap(a: &str, b: &str) -> bool {
    let inside = |inner: &str, outer: &str| {
        inner.len() > outer.len()
            && inner.starts_with(outer)
            && inner.as_bytes()[outer.len()] == b'.'
    };
    a == b || inside(a, b) || inside(b, a)
}

/// The axes with their values: explicit or from a checked range; each key must be settable
/// in the base scene and overlap no other axis key (one would overwrite the other's values).
fn expand_axes(
    configs: &[AxisConfig],
    base: &toml::Table,
    at: &Locator<'_>,
) -> Result<Vec<Axis>, StudyError> {
    let mut axes: Vec<Axis> = Vec::with_capacity(configs.len());
    for (k, a) in configs.iter().enumerate() {
        let key = format!("axis.{k}");
        let values = match (&a.values, &a.range) {
            (Some(v), None) => v.clone(),
            (None, Some(r)) => range_values(r, &format!("{key}.range"), at)?,
            _ => {
                return Err(at.input(
                    &key,
                    format!(
                        "axis \"{}\": give exactly one of `values` and `range`",
                        a.key
                    ),
                ));
            }
        };
        if values.is_empty() {
            return Err(at.input(
                &format!("{key}.values"),
                format!("axis \"{}\" has no values", a.key),
            ));
        }
        if let Some(j) = values.iter().position(|v| !all_finite(v)) {
            return Err(at.input(
                &format!("{key}.values.{j}"),
                format!(
                    "{} is not a finite number: an axis value must be one (a case with it could \
                     only be invalid)",
                    values[j]
                ),
            ));
        }
        if values.len() > MAX_CASES {
            return Err(at.input(
                &format!("{key}.values"),
                format!(
                    "{} values, more than the {MAX_CASES} cases a study may have",
                    values.len()
                ),
            ));
        }
        if axes.iter().any(|b| b.key == a.key) {
            return Err(at.input(
                &format!("{key}.key"),
                format!("axis \"{}\" appears twice", a.key),
            ));
        }
        if let Some((j, b)) = axes
            .iter()
            .enumerate()
            .find(|(_, b)| keys_overlap(&a.key, &b.key))
        {
            return Err(at.input(
                &format!("{key}.key"),
                format!(
                    "\"{}\" overlaps axis {j} (\"{}\"): setting one would overwrite the other's \
                     values; vary the whole table in one axis (its values hold both), or two \
                     separate keys",
                    a.key, b.key
                ),
            ));
        }
        let mut probe = base.clone();
        set_key(&mut probe, &a.key, &values[0]).map_err(|m| at.input(&format!("{key}.key"), m))?;
        axes.push(Axis {
            key: a.key.clone(),
            values,
        });
    }
    Ok(axes)
}

/// Whether every float in `value` (inside arrays and tables too) is finite.
fn all_finite(value: &toml::Value) -> bool {
    match value {
        toml::Value::Float(f) => f.is_finite(),
        toml::Value::Array(a) => a.iter().all(all_finite),
        toml::Value::Table(t) => t.values().all(all_finite),
        _ => true,
    }
}

/// The values of a range after checking it (`key` is its study key, for messages).
fn range_values(
    r: &RangeConfig,
    key: &str,
    at: &Locator<'_>,
) -> Result<Vec<toml::Value>, StudyError> {
    if !r.start.is_finite() || !r.end.is_finite() {
        return Err(at.input(key, "start and end must be finite"));
    }
    if r.count == 0 {
        return Err(at.input(&format!("{key}.count"), "count must be at least 1"));
    }
    if r.count == 1 && r.start.total_cmp(&r.end).is_ne() {
        return Err(at.input(
            &format!("{key}.count"),
            format!(
                "count = 1 gives one value, but start ({:?}) and end ({:?}) differ: give count >= 2 \
                 for both ends, or the one value as `values = [...]`",
                r.start, r.end
            ),
        ));
    }
    if r.count > MAX_CASES {
        return Err(at.input(
            &format!("{key}.count"),
            format!(
                "{} values, more than the {MAX_CASES} cases a study may have",
                r.count
            ),
        ));
    }
    if r.spacing == Spacing::Log && !(r.start > 0.0 && r.end > 0.0) {
        return Err(at.input(
            key,
            format!(
                "a log range needs positive start and end, got {:?} and {:?}",
                r.start, r.end
            ),
        ));
    }
    Ok(r.values().into_iter().map(toml::Value::Float).collect())
}

/// The cases in id order: the product (first axis slowest) or the zip of the axes; at most
/// [`MAX_CASES`].
fn combine_cases(
    combine: Combine,
    axes: &[Axis],
    at: &Locator<'_>,
) -> Result<Vec<Case>, StudyError> {
    match combine {
        Combine::Product => {
            let mut total: usize = 1;
            for (k, a) in axes.iter().enumerate() {
                total = total
                    .checked_mul(a.values.len())
                    .filter(|&t| t <= MAX_CASES)
                    .ok_or_else(|| {
                        let counts: Vec<String> =
                            axes[..=k].iter().map(|a| a.values.len().to_string()).collect();
                        at.input(
                            &format!("axis.{k}"),
                            format!(
                                "the axes so far give {} cases, more than the {MAX_CASES} a study may have",
                                counts.join(" x ")
                            ),
                        )
                    })?;
            }
            Ok((0..total)
                .map(|id| {
                    let mut rest = id;
                    let mut values = vec![toml::Value::Boolean(false); axes.len()];
                    for (slot, axis) in values.iter_mut().zip(axes).rev() {
                        let n = axis.values.len();
                        *slot = axis.values[rest % n].clone();
                        rest /= n;
                    }
                    Case { id, values }
                })
                .collect())
        }
        Combine::Zip => {
            let n = axes.first().map_or(1, |a| a.values.len());
            if let Some((k, a)) = axes.iter().enumerate().find(|(_, a)| a.values.len() != n) {
                return Err(at.input(
                    &format!("axis.{k}"),
                    format!(
                        "zipped axes need equal lengths: \"{}\" has {}, \"{}\" has {n}",
                        a.key,
                        a.values.len(),
                        axes[0].key
                    ),
                ));
            }
            Ok((0..n)
                .map(|id| Case {
                    id,
                    values: axes.iter().map(|a| a.values[id].clone()).collect(),
                })
                .collect())
        }
    }
}

/// A case's scene error without its place in the generated scene text (which is in no
/// file): the key and the message.
fn unlocated(e: ScenarioError) -> String {
    match e {
        ScenarioError::Input { key, message, .. } if !key.is_empty() => format!("{key}: {message}"),
        ScenarioError::Input { message, .. } => message,
        other => other.to_string(),
    }
}

/// Why a finished run is not physical: a non-finite value in a table (a runaway deflection
/// is the run layer's divergence guard, which stops the run).
fn divergence(result: &RunResult) -> Option<(Option<f64>, String)> {
    for table in &result.tables {
        let t = table.time();
        for (column, values) in table.columns.iter().zip(&table.data).skip(1) {
            if let Some(k) = values.iter().position(|v| !v.is_finite()) {
                let at = t.get(k).copied();
                let message = format!(
                    "non-finite value: {}.{column} = {} at t = {:.5} s",
                    table.name,
                    values[k],
                    at.unwrap_or(f64::NAN)
                );
                return Some((at.filter(|t| t.is_finite()), message));
            }
        }
    }
    None
}
