//! `flexprr.link_frequencies`: natural frequencies of one link under an axial load
//! `P(x) = p0 + p1 x + p2 x^2` (model.md section 7), from a link description with the schema
//! of the CLI's `flexprr beam` link files.

use flexprr_beam::{AxialLoad, Coupling, ModalIntegrals, frequencies};
use flexprr_scene::link::{BasisConfig, MaterialConfig, SectionConfig, build_basis, build_section};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use serde::Deserialize;

use crate::convert::dict_to_table;
use crate::errors::{key_error, scene_error};

/// A link file (the schema of `flexprr beam`, `docs/beam.md`).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct LinkFile {
    length: f64,
    modes: usize,
    #[serde(default)]
    coupling: CouplingConfig,
    material: MaterialConfig,
    section: SectionConfig,
    basis: BasisConfig,
    #[serde(default)]
    load: LoadConfig,
}

#[derive(Debug, Clone, Copy, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
enum CouplingConfig {
    #[default]
    Full,
    Diagonal,
}

#[derive(Debug, Clone, Copy, Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct LoadConfig {
    #[serde(default)]
    p0: f64,
    #[serde(default)]
    p1: f64,
    #[serde(default)]
    p2: f64,
}

/// Natural frequencies of one link. `link` is a path to a link file (TOML) or a dict with
/// its keys (`length`, `modes`, `material`, `section`, `basis`, optional `coupling` and
/// `load`); `load = (p0, p1, p2)` (N, N/m, N/m^2, tension positive) replaces the file's
/// load. Returns a dict: `frequencies_hz` and `omega_squared` (arrays, one per mode),
/// `states`, `buckled`, `critical_load_factor`, `total_mass`.
#[pyfunction]
#[pyo3(signature = (link, load = None))]
pub fn link_frequencies<'py>(
    py: Python<'py>,
    link: &Bound<'py, PyAny>,
    load: Option<(f64, f64, f64)>,
) -> PyResult<Bound<'py, PyDict>> {
    let (file, text) = if let Ok(d) = link.cast::<PyDict>() {
        let table = dict_to_table(d, "")?;
        (
            "<link>".to_string(),
            toml::to_string(&table).map_err(|e| key_error("", e.to_string()))?,
        )
    } else {
        let path: std::path::PathBuf = link.extract()?;
        let name = path.display().to_string();
        let text = std::fs::read_to_string(&path).map_err(|source| {
            scene_error(flexprr_scene::ScenarioError::Io {
                path: name.clone(),
                source,
            })
        })?;
        (name, text)
    };
    let parsed: LinkFile = flexprr_scene::parse_toml(&file, &text).map_err(scene_error)?;
    let load = load.map_or(
        AxialLoad {
            p0: parsed.load.p0,
            p1: parsed.load.p1,
            p2: parsed.load.p2,
        },
        |(p0, p1, p2)| AxialLoad { p0, p1, p2 },
    );
    let coupling = match parsed.coupling {
        CouplingConfig::Full => Coupling::Full,
        CouplingConfig::Diagonal => Coupling::Diagonal,
    };
    let computed = py.detach(move || -> Result<_, (String, String)> {
        let section = build_section(&parsed.material, &parsed.section)?;
        let basis = build_basis(&parsed.basis, parsed.modes)?;
        if parsed.modes == 0 || parsed.modes > basis.len() {
            return Err((
                "modes".to_string(),
                format!(
                    "modes = {} must be between 1 and the {} functions of the basis",
                    parsed.modes,
                    basis.len()
                ),
            ));
        }
        let integrals = ModalIntegrals::compute(basis.as_ref(), section.as_ref(), parsed.length)
            .map_err(|e| ("length".to_string(), format!("modal integrals: {e}")))?;
        let result = frequencies(&integrals, &load, coupling)
            .map_err(|e| ("load".to_string(), e.to_string()))?;
        Ok((result, integrals.total_mass, parsed.modes))
    });
    let (result, mass, reported) =
        computed.map_err(|(key, message)| key_error(&key, format!("{file}: {message}")))?;
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
