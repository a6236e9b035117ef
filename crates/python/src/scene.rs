//! `flexprr.Scene`: a scene's TOML table, editable by dotted keys, validated by the same
//! checker as the CLI (`flexprr_scene::Scene::from_text`).

use std::path::PathBuf;

use flexprr_scene::{ScenarioError, Scene as RustScene};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{dict_to_table, py_to_toml, table_to_py, toml_to_py};
use crate::errors::scene_error;

/// A scene: the TOML table of a scene file plus where it came from.
///
/// The text of a file or string is kept as long as it is not modified, so that validation
/// errors give the same `file:line:column` as `flexprr check`; after `set` the table is
/// written back to TOML and errors are located in that text (the key stays the same).
#[pyclass(module = "flexprr._flexprr", name = "Scene")]
#[derive(Clone)]
pub struct PyScene {
    pub(crate) table: toml::Table,
    pub(crate) text: Option<String>,
    pub(crate) file: String,
    pub(crate) default_name: String,
}

impl PyScene {
    fn parse(file: &str, default_name: &str, text: String) -> PyResult<Self> {
        let table: toml::Table = flexprr_scene::parse_toml(file, &text).map_err(scene_error)?;
        Ok(Self {
            table,
            text: Some(text),
            file: file.to_string(),
            default_name: default_name.to_string(),
        })
    }

    /// The scene's TOML text (the original while unmodified).
    pub(crate) fn source(&self) -> String {
        self.text
            .clone()
            .unwrap_or_else(|| toml::to_string(&self.table).unwrap_or_default())
    }

    /// The scene's name: its `name` key, else the file stem or the name given.
    pub(crate) fn name_or_default(&self) -> String {
        self.table
            .get("name")
            .and_then(|v| v.as_str())
            .map_or_else(|| self.default_name.clone(), str::to_string)
    }

    /// Validates and builds the Rust scene (no Python involved: callable without the GIL).
    pub(crate) fn build(&self) -> Result<RustScene, ScenarioError> {
        let text = self.source();
        RustScene::from_text(&self.file, &self.default_name, &text)
    }
}

#[pymethods]
impl PyScene {
    /// Reads a scene file (TOML); syntax errors raise `SceneError` located in the file.
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Self> {
        let file = path.display().to_string();
        let text = std::fs::read_to_string(&path).map_err(|source| {
            scene_error(ScenarioError::Io {
                path: file.clone(),
                source,
            })
        })?;
        let name = path
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("scene")
            .to_string();
        Self::parse(&file, &name, text)
    }

    /// A scene from TOML text; `name` is used when the text has no `name` key and names the
    /// text in error messages.
    #[staticmethod]
    #[pyo3(signature = (text, name = "scene"))]
    fn from_toml(text: String, name: &str) -> PyResult<Self> {
        Self::parse(&format!("<{name}>"), name, text)
    }

    /// A scene from a dict with the structure of a scene file.
    #[staticmethod]
    #[pyo3(signature = (data, name = "scene"))]
    fn from_dict(data: &Bound<'_, PyDict>, name: &str) -> PyResult<Self> {
        let table = dict_to_table(data, "")?;
        Ok(Self {
            table,
            text: None,
            file: format!("<{name}>"),
            default_name: name.to_string(),
        })
    }

    /// Sets a dotted key (`links.section.thickness`, `machine.legs.0.branch`) to a value;
    /// an int written over a float becomes a float. Returns the scene, so calls chain.
    fn set<'py>(
        mut slf: PyRefMut<'py, Self>,
        key: &str,
        value: &Bound<'py, PyAny>,
    ) -> PyResult<PyRefMut<'py, Self>> {
        let value = py_to_toml(value, key)?;
        flexprr_studies::study::set_key(&mut slf.table, key, &value).map_err(|message| {
            scene_error(ScenarioError::Input {
                location: None,
                key: key.to_string(),
                message,
            })
        })?;
        slf.text = None;
        Ok(slf)
    }

    /// The value at a dotted key; `KeyError` if absent.
    fn get<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        let mut node: Option<&toml::Value> = None;
        for (i, part) in key.split('.').enumerate() {
            let next = match (i, node) {
                (0, _) => self.table.get(part),
                (_, Some(toml::Value::Table(t))) => t.get(part),
                (_, Some(toml::Value::Array(a))) => {
                    part.parse::<usize>().ok().and_then(|j| a.get(j))
                }
                _ => None,
            };
            match next {
                Some(v) => node = Some(v),
                None => {
                    return Err(pyo3::exceptions::PyKeyError::new_err(format!(
                        "{key}: not set in the scene (\"{part}\" not found)"
                    )));
                }
            }
        }
        match node {
            Some(v) => toml_to_py(py, v),
            None => Err(pyo3::exceptions::PyKeyError::new_err(key.to_string())),
        }
    }

    fn __getitem__<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        self.get(py, key)
    }

    fn __setitem__(&mut self, key: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let value = py_to_toml(value, key)?;
        flexprr_studies::study::set_key(&mut self.table, key, &value).map_err(|message| {
            scene_error(ScenarioError::Input {
                location: None,
                key: key.to_string(),
                message,
            })
        })?;
        self.text = None;
        Ok(())
    }

    /// Checks the scene with the CLI's checker (`flexprr check`); raises `SceneError` with
    /// the key, the location and what was expected.
    fn validate(&self, py: Python<'_>) -> PyResult<()> {
        let scene = self.clone();
        py.detach(move || scene.build().map(|_| ()))
            .map_err(scene_error)
    }

    /// A copy of the scene.
    fn copy(&self) -> Self {
        self.clone()
    }

    /// The scene as a dict (a copy: edit with `set`).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        table_to_py(py, &self.table)
    }

    /// The scene as TOML text (the original text while unmodified).
    fn to_toml(&self) -> String {
        self.source()
    }

    /// The scene's name: its `name` key, else the file stem or the name given.
    #[getter]
    fn name(&self) -> String {
        self.name_or_default()
    }

    fn __repr__(&self) -> String {
        format!("Scene(name={:?}, file={:?})", self.name(), self.file)
    }
}
