//! `flexprr.link_frequencies`: natural frequencies of one link under an axial load
//! `P(x) = p0 + p1 x + p2 x^2` (model.md section 7), from a link description with the schema
//! of the CLI's `flexprr beam` link files.

use flexprr_beam::frequencies;
use flexprr_scene::ScenarioError;
use flexprr_scene::link_file::LinkFile;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::convert::dict_to_table;
use crate::errors::scene_error;
use crate::progress::detached;

/// A link error found in text generated from a dict: the key, without the generated line.
fn unlocated(error: ScenarioError) -> ScenarioError {
    match error {
        ScenarioError::Input { key, message, .. } => ScenarioError::Input {
            location: None,
            key,
            message: format!("link: {message}"),
        },
        other => other,
    }
}

/// Natural frequencies of one link. `link` is the path of a link file (TOML, str or
/// `os.PathLike`; read with the CLI's input checks) or a dict with its keys (`length`,
/// `modes`, `material`, `section`, `basis`, optional `coupling` and `load`); the schema and
/// checks are `flexprr beam`'s (`flexprr_scene::link_file`). `load = (p0, p1, p2)` (N, N/m,
/// N/m^2, tension positive) replaces the file's load. Returns a dict: `frequencies_hz` and
/// `omega_squared` (arrays, one per mode), `states`, `buckled`, `critical_load_factor`,
/// `total_mass`, `coupling`.
#[pyfunction]
#[pyo3(signature = (link, load = None))]
pub fn link_frequencies<'py>(
    py: Python<'py>,
    link: &Bound<'py, PyAny>,
    load: Option<(f64, f64, f64)>,
) -> PyResult<Bound<'py, PyDict>> {
    let (file, text, from_dict) = if let Ok(d) = link.cast::<PyDict>() {
        let table = dict_to_table(d, "")?;
        let text = toml::to_string(&table).map_err(|e| {
            crate::errors::key_error("", format!("link: cannot be written as TOML: {e}"))
        })?;
        ("<link>".to_string(), text, true)
    } else {
        let path: std::path::PathBuf = link.extract().map_err(|_| {
            pyo3::exceptions::PyTypeError::new_err(
                "link: expected the path of a link file (str or os.PathLike) or a dict of its keys",
            )
        })?;
        let name = path.display().to_string();
        let text = py
            .detach(|| flexprr_scene::read_input_file(&path))
            .map_err(scene_error)?;
        (name, text, false)
    };
    let place = |e: ScenarioError| if from_dict { unlocated(e) } else { e };
    let parsed = LinkFile::parse(&file, &text).map_err(|e| scene_error(place(e)))?;
    if let Some((p0, p1, p2)) = load {
        for (key, value) in [("load.p0", p0), ("load.p1", p1), ("load.p2", p2)] {
            if !value.is_finite() {
                return Err(crate::errors::key_error(
                    key,
                    format!("expected a finite number, got {value:?}"),
                ));
            }
        }
    }
    let load = load.map_or(parsed.load.axial_load(), |(p0, p1, p2)| {
        flexprr_beam::AxialLoad { p0, p1, p2 }
    });
    let coupling = parsed.coupling.coupling();
    let computed = detached(py, None, 1.0, move |_| {
        let link = parsed.build(&file, &text).map_err(place)?;
        let result =
            frequencies(&link.integrals, &load, coupling).map_err(|e| ScenarioError::Input {
                location: None,
                key: "load".to_string(),
                message: format!("{file}: {e}"),
            })?;
        Ok::<_, ScenarioError>((result, link.integrals.total_mass, link.reported))
    })?;
    let (result, mass, reported) = computed.map_err(scene_error)?;
    let modes = &result.modes[..reported];
    let d = PyDict::new(py);
    let hz: Vec<f64> = modes.iter().map(|m| m.frequency_hz).collect();
    let w2: Vec<f64> = modes.iter().map(|m| m.omega_squared).collect();
    d.set_item("frequencies_hz", PyArray1::from_vec(py, hz))?;
    d.set_item("omega_squared", PyArray1::from_vec(py, w2))?;
    d.set_item(
        "states",
        PyList::new(py, modes.iter().map(|m| m.state.name()))?,
    )?;
    d.set_item("buckled", result.is_buckled())?;
    d.set_item("critical_load_factor", result.critical_load_factor)?;
    d.set_item("total_mass", mass)?;
    d.set_item("coupling", result.coupling.name())?;
    Ok(d)
}
