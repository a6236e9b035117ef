//! The parameters of one quantity as its kind reads them: typed values from the study's
//! `quantities.<k>` table, each error at its key (file, line, column).

use std::sync::Arc;

use flexprr_scene::{locate, locate_value};

use super::{Quantity, QuantityRegistry};
use crate::study::{Locator, StudyError};

/// The table of one entry of a study's `quantities` (`quantities.<k>`), read by its
/// [`super::QuantityKind`]: typed parameters, errors located at their key, and the output
/// registry whose quantities the `output` kind names.
pub struct QuantityParams<'a> {
    table: &'a toml::Table,
    key: String,
    at: &'a Locator<'a>,
    outputs: &'a flexprr_run::OutputRegistry,
}

impl QuantityParams<'_> {
    /// The dotted key of the quantity's table, e.g. `quantities.2`.
    pub fn key(&self) -> &str {
        &self.key
    }

    /// The output producers of the study, whose quantities `output` reaches by name.
    pub fn outputs(&self) -> &flexprr_run::OutputRegistry {
        self.outputs
    }

    /// The raw value of parameter `name`, if given.
    pub fn value(&self, name: &str) -> Option<&toml::Value> {
        self.table.get(name)
    }

    /// An input error at parameter `name` (at its key in the study file).
    pub fn error(&self, name: &str, message: impl Into<String>) -> StudyError {
        self.at.input(&format!("{}.{name}", self.key), message)
    }

    /// An input error about the value of parameter `name` (located at the value).
    pub fn value_error(&self, name: &str, message: impl Into<String>) -> StudyError {
        let key = format!("{}.{name}", self.key);
        StudyError::Input {
            file: self.at.file.to_string(),
            location: locate_value(self.at.file, self.at.text, &key),
            key,
            message: message.into(),
        }
    }

    /// The required parameter `name`.
    fn required(&self, name: &str) -> Result<&toml::Value, StudyError> {
        self.table
            .get(name)
            .ok_or_else(|| self.at.input(&self.key, format!("missing field `{name}`")))
    }

    /// The required non-negative integer parameter `name`.
    ///
    /// # Errors
    /// Missing (at the table), or not a non-negative integer (at the value).
    pub fn usize(&self, name: &str) -> Result<usize, StudyError> {
        match self.required(name)? {
            toml::Value::Integer(i) => usize::try_from(*i).map_err(|_| {
                self.value_error(
                    name,
                    format!("invalid value: integer `{i}`, expected usize"),
                )
            }),
            other => Err(self.value_error(name, invalid_type(other, "usize"))),
        }
    }

    /// The required string parameter `name`.
    ///
    /// # Errors
    /// Missing (at the table), or not a string (at the value).
    pub fn string(&self, name: &str) -> Result<String, StudyError> {
        match self.required(name)? {
            toml::Value::String(s) => Ok(s.clone()),
            other => Err(self.value_error(name, invalid_type(other, "a string"))),
        }
    }

    /// The link of a quantity of one link: parameter `link`, 1, 2 or 3.
    ///
    /// # Errors
    /// As [`Self::usize`], and at `link` when it is not 1, 2 or 3.
    pub fn link(&self) -> Result<usize, StudyError> {
        let link = self.usize("link")?;
        if (1..=3).contains(&link) {
            Ok(link)
        } else {
            Err(self.error("link", format!("link must be 1, 2 or 3, got {link}")))
        }
    }

    /// The mode of a quantity of one mode: parameter `mode`, numbered from 1.
    ///
    /// # Errors
    /// As [`Self::usize`], and at `mode` when it is 0.
    pub fn mode(&self) -> Result<usize, StudyError> {
        let mode = self.usize("mode")?;
        if mode == 0 {
            Err(self.error("mode", "modes are numbered from 1"))
        } else {
            Ok(mode)
        }
    }
}

/// serde's words for a value of the wrong type: `invalid type: string "a", expected usize`.
fn invalid_type(value: &toml::Value, expected: &str) -> String {
    let found = match value {
        toml::Value::String(s) => format!("string {s:?}"),
        toml::Value::Integer(i) => format!("integer `{i}`"),
        toml::Value::Float(f) => format!("floating point `{f}`"),
        toml::Value::Boolean(b) => format!("boolean `{b}`"),
        toml::Value::Datetime(d) => format!("date-time `{d}`"),
        toml::Value::Array(_) => "sequence".to_string(),
        toml::Value::Table(_) => "map".to_string(),
    };
    format!("invalid type: {found}, expected {expected}")
}

/// serde's words for a key a table does not take: ``unknown field `x`, expected `link` or
/// `mode` ``.
fn unknown_field(name: &str, keys: &[&str]) -> String {
    let quoted: Vec<String> = keys.iter().map(|k| format!("`{k}`")).collect();
    match quoted.as_slice() {
        [] => format!("unknown field `{name}`, there are no fields"),
        [one] => format!("unknown field `{name}`, expected {one}"),
        [first, second] => format!("unknown field `{name}`, expected {first} or {second}"),
        _ => format!(
            "unknown field `{name}`, expected one of {}",
            quoted.join(", ")
        ),
    }
}

impl QuantityRegistry {
    /// The quantities of a study's `quantities` array, each read by the kind its `kind`
    /// names.
    ///
    /// # Errors
    /// [`StudyError::Input`] at the entry or key: not a table, no `kind` or an unregistered
    /// one (listing the registered kinds), a key the kind does not take, or the kind's own
    /// refusal of its parameters.
    pub(crate) fn parse_all(
        &self,
        entries: &[toml::Value],
        outputs: &flexprr_run::OutputRegistry,
        at: &Locator<'_>,
    ) -> Result<Vec<Arc<dyn Quantity>>, StudyError> {
        let mut quantities = Vec::with_capacity(entries.len());
        for (k, entry) in entries.iter().enumerate() {
            let key = format!("quantities.{k}");
            let located = |path: &str, value: bool, message: String| StudyError::Input {
                file: at.file.to_string(),
                location: if value {
                    locate_value(at.file, at.text, path)
                } else {
                    locate(at.file, at.text, path)
                },
                key: path.to_string(),
                message,
            };
            let Some(table) = entry.as_table() else {
                return Err(located(
                    &key,
                    false,
                    invalid_type(entry, "a quantity table"),
                ));
            };
            let kind_key = format!("{key}.kind");
            let name = match table.get("kind") {
                None => {
                    return Err(StudyError::Input {
                        file: at.file.to_string(),
                        location: locate(at.file, at.text, &key),
                        key: kind_key,
                        message: "missing field `kind`".to_string(),
                    });
                }
                Some(toml::Value::String(name)) => name,
                Some(other) => {
                    return Err(located(
                        &kind_key,
                        true,
                        invalid_type(other, "variant identifier"),
                    ));
                }
            };
            let Some(kind) = self.kind(name) else {
                let known: Vec<String> = self.names().iter().map(|n| format!("`{n}`")).collect();
                return Err(located(
                    &kind_key,
                    true,
                    format!(
                        "unknown variant `{name}`, expected one of {}",
                        known.join(", ")
                    ),
                ));
            };
            let keys = kind.keys();
            if let Some(extra) = table
                .keys()
                .find(|k| *k != "kind" && !keys.contains(&k.as_str()))
            {
                return Err(at.input(&format!("{key}.{extra}"), unknown_field(extra, keys)));
            }
            let params = QuantityParams {
                table,
                key,
                at,
                outputs,
            };
            quantities.push(kind.parse(&params)?);
        }
        Ok(quantities)
    }
}
