//! `flexprr.Scene`: a scene's TOML table, editable by dotted keys checked at once against
//! the scene schema (`flexprr_scene::setting`), validated by the same checker as the CLI
//! (`flexprr_scene::Scene::from_text`).

use std::path::PathBuf;

use flexprr_scene::{ScenarioError, Scene as RustScene, locate};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple, PyType};

use crate::convert::{dict_to_table, py_to_toml, table_to_py, toml_to_py};
use crate::errors::{key_error, scene_error};

/// Where a scene's text came from: a file or a string, with the text as written.
#[derive(Clone)]
pub(crate) struct Origin {
    file: String,
    text: String,
}

/// A scene: the TOML table of a scene file, where it came from and what was changed.
///
/// While unmodified, the scene validates from its original text, so errors carry the same
/// `file:line:column` as `flexprr check`. After `set`, it validates from its table; an error
/// at a key that was set (or inside or around one) names that key and no line (the user
/// wrote no line), and an error elsewhere is located in the original file.
#[pyclass(module = "flexprr._flexprr", name = "Scene")]
#[derive(Clone)]
pub struct PyScene {
    pub(crate) table: toml::Table,
    origin: Option<Origin>,
    /// Dotted keys given to `set`, in order, without repeats.
    set_keys: Vec<String>,
    pub(crate) default_name: String,
}

impl PyScene {
    /// A scene from TOML text (`file` names it in messages).
    pub(crate) fn from_text(file: &str, default_name: &str, text: String) -> PyResult<Self> {
        Self::parse(file, default_name, text)
    }

    fn parse(file: &str, default_name: &str, text: String) -> PyResult<Self> {
        let table: toml::Table = flexprr_scene::parse_toml(file, &text).map_err(scene_error)?;
        Ok(Self {
            table,
            origin: Some(Origin {
                file: file.to_string(),
                text,
            }),
            set_keys: Vec::new(),
            default_name: default_name.to_string(),
        })
    }

    /// Reads a scene file with the CLI's input checks (a regular file of at most 4 MiB).
    pub(crate) fn read(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let file = path.display().to_string();
        let text = py
            .detach(|| flexprr_scene::read_input_file(&path))
            .map_err(scene_error)?;
        let name = path
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("scene")
            .to_string();
        Self::parse(&file, &name, text)
    }

    /// The scene from a `Scene` or a path (str or `os.PathLike`).
    pub(crate) fn from_any(value: &Bound<'_, PyAny>) -> PyResult<Self> {
        if let Ok(scene) = value.cast::<PyScene>() {
            return Ok(scene.borrow().clone());
        }
        match value.extract::<PathBuf>() {
            Ok(path) => Self::read(value.py(), path),
            Err(_) => Err(pyo3::exceptions::PyTypeError::new_err(format!(
                "expected a Scene or the path of a scene file (str or os.PathLike), got {}",
                value
                    .get_type()
                    .name()
                    .map_or_else(|_| "?".to_string(), |n| n.to_string())
            ))),
        }
    }

    /// The scene's TOML text: the original while unmodified, else the table written out.
    pub(crate) fn source(&self) -> String {
        match &self.origin {
            Some(o) if self.set_keys.is_empty() => o.text.clone(),
            _ => toml::to_string(&self.table).unwrap_or_default(),
        }
    }

    /// The scene's name: its `name` key, else the file stem or the name given.
    pub(crate) fn name_or_default(&self) -> String {
        self.table
            .get("name")
            .and_then(|v| v.as_str())
            .map_or_else(|| self.default_name.clone(), str::to_string)
    }

    /// Validates and builds the Rust scene (no Python involved: callable without the GIL).
    /// A `kind = "python"` law is accepted without its function (`crate::law`).
    pub(crate) fn build(&self) -> Result<RustScene, ScenarioError> {
        self.build_with(&crate::law::unbound_registry())
    }

    /// As [`PyScene::build`], with the parts of `registry` (a Python control law's).
    pub(crate) fn build_with(
        &self,
        registry: &flexprr_scene::Registry,
    ) -> Result<RustScene, ScenarioError> {
        match &self.origin {
            Some(o) if self.set_keys.is_empty() => {
                RustScene::from_text_with(registry, &o.file, &self.default_name, &o.text)
            }
            _ => {
                let text = toml::to_string(&self.table).map_err(|e| ScenarioError::Input {
                    location: None,
                    key: String::new(),
                    message: format!("the scene cannot be written as TOML: {e}"),
                })?;
                let file = self
                    .origin
                    .as_ref()
                    .map_or_else(|| format!("<{}>", self.default_name), |o| o.file.clone());
                RustScene::from_text_with(registry, &file, &self.default_name, &text)
                    .map_err(|e| self.relocate(e))
            }
        }
    }

    /// The scene's `control.kind`, if it has `[control]`.
    pub(crate) fn control_kind(&self) -> Option<String> {
        self.table
            .get("control")
            .and_then(|c| c.get("kind"))
            .and_then(|k| k.as_str())
            .map(str::to_string)
    }

    /// An error found in the written-out table, placed where the user can find it: at the
    /// key that was set (no line: the user wrote none), or in the original file.
    fn relocate(&self, error: ScenarioError) -> ScenarioError {
        let ScenarioError::Input { key, message, .. } = error else {
            return error;
        };
        let related = |set: &str| {
            set == key
                || key.is_empty()
                || set.starts_with(&format!("{key}."))
                || key.starts_with(&format!("{set}."))
        };
        let touched: Vec<&str> = self
            .set_keys
            .iter()
            .map(String::as_str)
            .filter(|s| related(s))
            .collect();
        let changed = |keys: &[&str]| {
            let mut shown: Vec<&str> = keys.iter().copied().take(8).collect();
            if keys.len() > 8 {
                shown.push("...");
            }
            shown.join(", ")
        };
        if touched.is_empty() {
            let location = self
                .origin
                .as_ref()
                .and_then(|o| locate(&o.file, &o.text, &key));
            let set: Vec<&str> = self.set_keys.iter().map(String::as_str).collect();
            return ScenarioError::Input {
                location,
                key,
                message: format!(
                    "{message} (in the scene changed by Scene.set of {})",
                    changed(&set)
                ),
            };
        }
        let message = if touched == [key.as_str()] {
            format!("{message} (the value given to Scene.set)")
        } else {
            format!("{message} (after Scene.set of {})", changed(&touched))
        };
        ScenarioError::Input {
            location: None,
            key,
            message,
        }
    }

    fn set_checked(&mut self, key: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let value = py_to_toml(value, key)?;
        flexprr_scene::setting::set_checked(&mut self.table, key, &value).map_err(scene_error)?;
        if !self.set_keys.iter().any(|k| k == key) {
            self.set_keys.push(key.to_string());
        }
        Ok(())
    }
}

#[pymethods]
impl PyScene {
    /// Reads a scene file (TOML) with the CLI's input checks: a regular file (not a
    /// directory, device or pipe) of at most 4 MiB. Syntax errors raise `SceneError`
    /// located in the file.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        Self::read(py, path)
    }

    /// A scene from TOML text; `name` is used when the text has no `name` key and names the
    /// text in error messages.
    #[staticmethod]
    #[pyo3(signature = (text, name = "scene"))]
    fn from_toml(text: String, name: &str) -> PyResult<Self> {
        if text.len() as u64 > flexprr_scene::MAX_INPUT_BYTES {
            return Err(key_error(
                "",
                format!(
                    "<{name}>: the text has {} bytes, more than the {} MiB a scene file may have",
                    text.len(),
                    flexprr_scene::MAX_INPUT_BYTES / (1024 * 1024)
                ),
            ));
        }
        Self::parse(&format!("<{name}>"), name, text)
    }

    /// A scene from a dict with the structure of a scene file.
    #[staticmethod]
    #[pyo3(signature = (data, name = "scene"))]
    fn from_dict(data: &Bound<'_, PyDict>, name: &str) -> PyResult<Self> {
        let table = dict_to_table(data, "")?;
        Ok(Self {
            table,
            origin: None,
            set_keys: Vec::new(),
            default_name: name.to_string(),
        })
    }

    /// Sets a dotted key (`links.section.thickness`, `machine.legs.0.branch`) to a value,
    /// checking the key and the value's type against the scene schema at once: `SceneError`
    /// naming the key, with the scene unchanged. An int where the schema wants a float
    /// becomes a float. Returns the scene, so calls chain.
    fn set<'py>(
        mut slf: PyRefMut<'py, Self>,
        key: &str,
        value: &Bound<'py, PyAny>,
    ) -> PyResult<PyRefMut<'py, Self>> {
        slf.set_checked(key, value)?;
        Ok(slf)
    }

    /// The value at a dotted key; `KeyError` if absent.
    fn get<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        match flexprr_scene::setting::get_key(&self.table, key) {
            Some(v) => toml_to_py(py, v),
            None => Err(pyo3::exceptions::PyKeyError::new_err(format!(
                "{key}: not set in the scene"
            ))),
        }
    }

    fn __getitem__<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        self.get(py, key)
    }

    fn __setitem__(&mut self, key: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        self.set_checked(key, value)
    }

    /// Checks the scene with the CLI's checker (`flexprr check`); raises `SceneError` with
    /// the key, the location and what was expected.
    fn validate(&self, py: Python<'_>) -> PyResult<()> {
        let scene = self.clone();
        crate::progress::detached(py, None, 1.0, move |_| scene.build().map(|_| ()))?
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

    /// The dotted keys given to `set` since the scene was loaded, in order.
    #[getter]
    fn changed_keys(&self) -> Vec<String> {
        self.set_keys.clone()
    }

    fn __repr__(&self) -> String {
        let file = self
            .origin
            .as_ref()
            .map_or_else(|| format!("<{}>", self.default_name), |o| o.file.clone());
        format!("Scene(name={:?}, file={:?})", self.name(), file)
    }

    /// Pickle support: the scene rebuilt from its table, origin and changed keys.
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let this = slf.borrow();
        let (file, text) = match &this.origin {
            Some(o) => (Some(o.file.clone()), Some(o.text.clone())),
            None => (None, None),
        };
        let state = (
            table_to_py(py, &this.table)?,
            file,
            text,
            this.set_keys.clone(),
            this.default_name.clone(),
        );
        let restore = slf.get_type().getattr("_restore")?;
        Ok((restore, PyTuple::new(py, [state.into_pyobject(py)?])?))
    }

    /// Rebuilds a pickled scene (see `__reduce__`).
    #[classmethod]
    fn _restore(
        _cls: &Bound<'_, PyType>,
        state: (
            Bound<'_, PyDict>,
            Option<String>,
            Option<String>,
            Vec<String>,
            String,
        ),
    ) -> PyResult<Self> {
        let (table, file, text, set_keys, default_name) = state;
        let origin = match (file, text) {
            (Some(file), Some(text)) => Some(Origin { file, text }),
            _ => None,
        };
        Ok(Self {
            table: dict_to_table(&table, "")?,
            origin,
            set_keys,
            default_name,
        })
    }
}
