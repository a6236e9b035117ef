//! Case records (`cases/<id>.json`): what one finished case produced, how a failure is
//! described, how records are read back and checked, and how `results.csv` is assembled.

use flexprr_integrators::IntegratorError;
use flexprr_run::RunError;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::error::{StudyError, io_err};
use crate::quantity::Column;

/// Formats a float deterministically: rounded to 10 significant digits, then written in
/// Rust's shortest round-trip form (`20`, `116.4389235`, `0.000001`), in scientific notation
/// only where that form would run to more than about twenty digits (below 1e-15 or from 1e21
/// on: `1e-300`, not three hundred zeros); `nan`, `inf`, `-inf`.
pub fn format_value(value: f64) -> String {
    if !value.is_finite() {
        return format!("{value}").to_lowercase();
    }
    let rounded: f64 = format!("{value:.9e}").parse().unwrap_or(value);
    let magnitude = rounded.abs();
    if magnitude != 0.0 && !(1e-15..1e21).contains(&magnitude) {
        format!("{rounded:e}")
    } else {
        format!("{rounded}")
    }
}

/// An axis value as written in the table: floats by [`format_value`], strings bare.
pub fn format_parameter(value: &toml::Value) -> String {
    match value {
        toml::Value::Float(f) => format_value(*f),
        toml::Value::Integer(i) => i.to_string(),
        toml::Value::String(s) => s.clone(),
        toml::Value::Boolean(b) => b.to_string(),
        other => other.to_string(),
    }
}

/// Outcome of one case.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum CaseStatus {
    /// Ran; quantities filled in.
    Ok,
    /// The case's scene is invalid (bad parameters): a failure of kind `invalid_input`.
    Invalid,
    /// The run failed (integrator, buckling divergence, step-size collapse, missing output).
    Failed,
}

impl CaseStatus {
    /// Name written in the table.
    pub fn name(self) -> &'static str {
        match self {
            CaseStatus::Ok => "ok",
            CaseStatus::Invalid => "invalid",
            CaseStatus::Failed => "failed",
        }
    }
}

/// What kind of failure ended a case.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum FailureKind {
    /// The case's scene failed validation (status `invalid`).
    InvalidInput,
    /// The step size collapsed.
    StepSize,
    /// The step budget (`integrator.max_steps`) ran out.
    StepBudget,
    /// A non-finite state, derivative or quantity.
    NonFinite,
    /// Newton iterations of an implicit method failed, or its matrix was singular.
    Newton,
    /// An explicit method found the problem stiff.
    Stiff,
    /// The deflection left the range of the small-deflection model (typically buckling).
    Diverged,
    /// The mechanism collapsed (a study without the `collapse` quantity, for which that
    /// is a failure).
    Collapse,
    /// A quantity could not be derived (an output not requested, a mode that does not exist).
    Quantity,
    /// The run panicked (a bug: please report it).
    Panic,
    /// Any other run failure.
    Run,
}

impl FailureKind {
    /// Name as written in the record.
    pub fn name(self) -> &'static str {
        match self {
            FailureKind::InvalidInput => "invalid_input",
            FailureKind::StepSize => "step_size",
            FailureKind::StepBudget => "step_budget",
            FailureKind::NonFinite => "non_finite",
            FailureKind::Newton => "newton",
            FailureKind::Stiff => "stiff",
            FailureKind::Diverged => "diverged",
            FailureKind::Collapse => "collapse",
            FailureKind::Quantity => "quantity",
            FailureKind::Panic => "panic",
            FailureKind::Run => "run",
        }
    }
}

/// Why a case failed: the kind, the simulated time it happened at (when known, s) and the
/// full message on one line.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CaseFailure {
    /// What kind of failure.
    pub kind: FailureKind,
    /// Simulated time of the failure (s), when known.
    pub time: Option<f64>,
    /// The message (also the `error` column of the table).
    pub message: String,
}

impl CaseFailure {
    /// A failure with its message folded onto one line (runs of white space become one
    /// space); a non-finite time is dropped.
    pub fn new(kind: FailureKind, time: Option<f64>, message: &str) -> Self {
        Self {
            kind,
            time: time.filter(|t| t.is_finite()),
            message: message.split_whitespace().collect::<Vec<_>>().join(" "),
        }
    }

    /// The status a case with this failure gets.
    pub fn status(&self) -> CaseStatus {
        if self.kind == FailureKind::InvalidInput {
            CaseStatus::Invalid
        } else {
            CaseStatus::Failed
        }
    }
}

/// The kind and time of a failed run, from the run layer's typed error.
pub fn classify_run_failure(e: &RunError) -> (FailureKind, Option<f64>) {
    let kind = match e.kind() {
        "diverged" => FailureKind::Diverged,
        "collapse" => FailureKind::Collapse,
        "step-size-collapse" => FailureKind::StepSize,
        "too-many-steps" => FailureKind::StepBudget,
        "non-finite" => FailureKind::NonFinite,
        "stiff" => FailureKind::Stiff,
        "input" => FailureKind::InvalidInput,
        _ => match e {
            RunError::Integrator {
                source:
                    IntegratorError::NewtonFailure { .. } | IntegratorError::SingularMatrix { .. },
                ..
            } => FailureKind::Newton,
            _ => FailureKind::Run,
        },
    };
    (kind, e.time())
}

/// One finished case, as stored in `cases/<id>.json`.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CaseRecord {
    /// Case id (0-based).
    pub id: usize,
    /// Fingerprint of the study the case belongs to.
    pub fingerprint: String,
    /// Formatted axis values, in axis order.
    pub parameters: Vec<String>,
    /// Formatted quantity columns (empty strings when not ok).
    pub quantities: Vec<String>,
    /// Outcome.
    pub status: CaseStatus,
    /// Error message on one line (empty when ok; the failure's message otherwise).
    pub error: String,
    /// Why the case failed (absent when ok).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failure: Option<CaseFailure>,
}

impl CaseRecord {
    /// Marks the record failed: status from the failure, quantities emptied, `error` set.
    pub fn fail(&mut self, failure: CaseFailure) {
        self.status = failure.status();
        self.error.clone_from(&failure.message);
        self.quantities.iter_mut().for_each(String::clear);
        self.failure = Some(failure);
    }

    /// Checks the record's own consistency: `parameters` + `quantities` make `width` table
    /// cells between `case` and `status`; an ok record has a value in every quantity cell
    /// (a finite number, `yes`/`no` or an empty optional), no error and no failure; a record
    /// that is not ok has empty quantities and a failure whose status and message match.
    /// `columns` are the quantity columns when known (then each value is checked against
    /// its column's type), `parameters` the case's parameters when known.
    ///
    /// # Errors
    /// A message naming the first problem.
    pub fn check(
        &self,
        quantity_columns: &[Column],
        parameters: Option<&[String]>,
    ) -> Result<(), String> {
        if let Some(expected) = parameters {
            check_parameters(&self.parameters, expected)?;
        }
        if self.quantities.len() != quantity_columns.len() {
            return Err(format!(
                "{} quantity values, the study has {} quantity columns",
                self.quantities.len(),
                quantity_columns.len()
            ));
        }
        match (&self.status, &self.failure) {
            (CaseStatus::Ok, None) => {
                if !self.error.is_empty() {
                    return Err("status ok with an error message".into());
                }
                for (value, column) in self.quantities.iter().zip(quantity_columns) {
                    if !column.accepts(value) {
                        return Err(format!(
                            "{} = \"{value}\" is not {}",
                            column.name,
                            match column.values {
                                crate::quantity::ColumnValues::Number => "a finite number",
                                crate::quantity::ColumnValues::Flag => "yes or no",
                                crate::quantity::ColumnValues::OptionalNumber =>
                                    "a finite number or empty",
                                crate::quantity::ColumnValues::Unknown =>
                                    "a finite number, yes, no or empty",
                            }
                        ));
                    }
                }
                Ok(())
            }
            (CaseStatus::Ok, Some(_)) => Err("status ok with a failure".into()),
            (status, None) => Err(format!("status {} without a failure", status.name())),
            (status, Some(failure)) => {
                if failure.status() != *status {
                    return Err(format!(
                        "status {} with a failure of kind {}",
                        status.name(),
                        failure.kind.name()
                    ));
                }
                if failure.message != self.error || self.error.is_empty() {
                    return Err("the error differs from the failure's message".into());
                }
                if let Some(c) = self.quantities.iter().position(|q| !q.is_empty()) {
                    return Err(format!(
                        "status {} with a value for {}",
                        status.name(),
                        quantity_columns
                            .get(c)
                            .map_or("a quantity", |c| c.name.as_str())
                    ));
                }
                Ok(())
            }
        }
    }
}

fn check_parameters(found: &[String], expected: &[String]) -> Result<(), String> {
    if found.len() != expected.len() {
        return Err(format!(
            "{} parameters, the study has {} axes",
            found.len(),
            expected.len()
        ));
    }
    match found.iter().zip(expected).position(|(f, e)| f != e) {
        Some(k) => Err(format!(
            "parameter {} is \"{}\", the case has \"{}\" (edited, or written by another study)",
            k + 1,
            found[k],
            expected[k]
        )),
        None => Ok(()),
    }
}

/// The record file of case `id` in the output directory `dir`.
pub(crate) fn case_file(dir: &Path, id: usize) -> PathBuf {
    dir.join("cases").join(format!("{id:06}.json"))
}

/// The case id a record file name stands for (`000042.json`), if it is one.
fn record_id(path: &Path) -> Option<usize> {
    if path.extension().is_none_or(|e| e != "json") {
        return None;
    }
    let stem = path.file_stem()?.to_str()?;
    if stem.is_empty() || !stem.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    stem.parse().ok()
}

/// Reads every `cases/<id>.json` in `dir`, checking that each parses and holds the id its
/// file is named after.
///
/// # Errors
/// [`StudyError::Io`] for an unreadable file, [`StudyError::Record`] (naming the file) for
/// one that is not a case record or holds another id.
pub fn read_case_records(dir: &Path) -> Result<BTreeMap<usize, CaseRecord>, StudyError> {
    Ok(read_case_record_files(dir)?
        .into_iter()
        .map(|(id, (_, record))| (id, record))
        .collect())
}

/// As [`read_case_records`], keeping each record's path for messages.
pub(crate) fn read_case_record_files(
    dir: &Path,
) -> Result<BTreeMap<usize, (PathBuf, CaseRecord)>, StudyError> {
    let cases = dir.join("cases");
    let mut records = BTreeMap::new();
    if !cases.is_dir() {
        return Ok(records);
    }
    for entry in std::fs::read_dir(&cases).map_err(io_err(&cases))? {
        let path = entry.map_err(io_err(&cases))?.path();
        let Some(id) = record_id(&path) else {
            continue;
        };
        let bad = |message: String| StudyError::Record {
            path: path.display().to_string(),
            message,
        };
        let text = crate::error::read_input_file(&path).map_err(|e| match e {
            StudyError::InputFile { message, .. } => bad(message),
            other => other,
        })?;
        let record: CaseRecord =
            serde_json::from_str(&text).map_err(|e| bad(format!("not a case record: {e}")))?;
        if record.id != id {
            return Err(bad(format!("holds case {}, not case {id}", record.id)));
        }
        records.insert(id, (path, record));
    }
    Ok(records)
}

/// `results.csv` bytes: the header, then one row per record in id order.
///
/// # Errors
/// [`StudyError::Directory`] if the CSV writer fails.
pub fn results_csv<'a>(
    columns: &[String],
    records: impl IntoIterator<Item = &'a CaseRecord>,
) -> Result<Vec<u8>, StudyError> {
    let err = |e: &dyn std::fmt::Display| StudyError::Directory {
        dir: "results.csv".into(),
        message: e.to_string(),
    };
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(columns).map_err(|e| err(&e))?;
    let mut sorted: Vec<&CaseRecord> = records.into_iter().collect();
    sorted.sort_by_key(|r| r.id);
    for r in sorted {
        let mut row = vec![r.id.to_string()];
        row.extend(r.parameters.iter().cloned());
        row.extend(r.quantities.iter().cloned());
        row.push(r.status.name().into());
        row.push(r.error.clone());
        if row.len() != columns.len() {
            return Err(err(&format!(
                "case {} has {} cells, the header {}",
                r.id,
                row.len(),
                columns.len()
            )));
        }
        w.write_record(&row).map_err(|e| err(&e))?;
    }
    w.into_inner().map_err(|e| err(&e))
}
