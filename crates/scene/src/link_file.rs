//! Single-link files (`flexprr beam`, Python's `link_frequencies`): the schema and how one
//! becomes the link's basis, section and modal integrals (`docs/beam.md`). The material,
//! section and basis tables are those of scene files ([`crate::link`], [`BasisTable`]).

use std::path::Path;
use std::sync::Arc;

use flexprr_beam::{AxialLoad, Basis, Coupling, ModalIntegrals};
use serde::Deserialize;

use crate::error::ScenarioError;
use crate::input::read_input_file;
use crate::link::{MaterialConfig, SectionConfig, build_section, check_link};
use crate::locate::locate;
use crate::parse::parse_toml;
use crate::registry::{BasisParams, ModeCount, Registry};
use crate::schema::BasisTable;

/// A single-link file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkFile {
    /// Link length `l` (m).
    pub length: f64,
    /// Number of basis functions `r` for `sine` and `classical` bases; for `hermite`, the
    /// number of modes reported (at most the number of free nodal unknowns).
    pub modes: usize,
    /// `"full"` (default) or `"diagonal"` (the paper's eq. 22).
    #[serde(default)]
    pub coupling: CouplingConfig,
    /// Material of the link.
    pub material: MaterialConfig,
    /// Cross-section along the link.
    pub section: SectionConfig,
    /// Assumed-mode basis (`kind` and its keys, as in scene files).
    pub basis: BasisTable,
    /// Axial force, tension positive (default: none).
    #[serde(default)]
    pub load: LoadConfig,
}

/// Frequency coupling.
#[derive(Debug, Clone, Copy, Deserialize, Default, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum CouplingConfig {
    /// Generalized eigenproblem with the full matrices.
    #[default]
    Full,
    /// Diagonals only (eq. 22).
    Diagonal,
}

impl CouplingConfig {
    /// The beam layer's coupling.
    pub fn coupling(self) -> Coupling {
        match self {
            CouplingConfig::Full => Coupling::Full,
            CouplingConfig::Diagonal => Coupling::Diagonal,
        }
    }
}

/// `P(x) = p0 + p1 x + p2 x^2`, `x` in metres from the slider end, tension positive.
#[derive(Debug, Clone, Copy, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct LoadConfig {
    /// Constant part (N).
    #[serde(default)]
    pub p0: f64,
    /// Linear coefficient (N/m).
    #[serde(default)]
    pub p1: f64,
    /// Quadratic coefficient (N/m^2).
    #[serde(default)]
    pub p2: f64,
}

impl LoadConfig {
    /// The beam layer's load.
    pub fn axial_load(&self) -> AxialLoad {
        AxialLoad {
            p0: self.p0,
            p1: self.p1,
            p2: self.p2,
        }
    }
}

/// A link built from a file: basis, section values at the slider end and its integrals.
pub struct BuiltLink {
    /// The assumed-mode basis.
    pub basis: Arc<dyn Basis>,
    /// Bending stiffness `EI` at the slider end (N m^2).
    pub bending_stiffness_at_start: f64,
    /// Mass per length `rhoA` at the slider end (kg/m).
    pub mass_per_length_at_start: f64,
    /// Mass and stiffness integrals of the basis over the section.
    pub integrals: ModalIntegrals,
    /// Number of modes to report (`modes`).
    pub reported: usize,
}

impl LinkFile {
    /// Reads a link file with the input checks of every flexprr file
    /// ([`read_input_file`]: a regular file of at most [`crate::MAX_INPUT_BYTES`]) and
    /// parses it. Returns the file and its text (to locate later errors in).
    ///
    /// # Errors
    /// [`ScenarioError::Io`] or [`ScenarioError::Input`] located in the file.
    pub fn load(path: &Path) -> Result<(Self, String), ScenarioError> {
        let text = read_input_file(path)?;
        let file = Self::parse(&path.display().to_string(), &text)?;
        Ok((file, text))
    }

    /// Parses link text; errors say where (`file:line:column`), which key and what was
    /// expected (the same reporting as scene files).
    ///
    /// # Errors
    /// [`ScenarioError::Input`].
    pub fn parse(file: &str, text: &str) -> Result<Self, ScenarioError> {
        parse_toml(file, text)
    }

    /// Checks the values and builds the link with the built-in bases; `file` and `text`
    /// locate errors.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] naming the key (slenderness, positive values, a finite load,
    /// the basis keys, `modes` within the basis).
    pub fn build(&self, file: &str, text: &str) -> Result<BuiltLink, ScenarioError> {
        self.build_with(&Registry::default(), file, text)
    }

    /// As [`LinkFile::build`], with the bases of `registry`.
    ///
    /// # Errors
    /// As [`LinkFile::build`].
    pub fn build_with(
        &self,
        registry: &Registry,
        file: &str,
        text: &str,
    ) -> Result<BuiltLink, ScenarioError> {
        let error = |key: &str, message: String| ScenarioError::Input {
            location: locate(file, text, key),
            key: key.to_string(),
            message,
        };
        check_link(&self.material, &self.section, self.length)
            .map_err(|(key, message)| error(&key, message))?;
        for (key, value) in [
            ("load.p0", self.load.p0),
            ("load.p1", self.load.p1),
            ("load.p2", self.load.p2),
        ] {
            if !value.is_finite() {
                return Err(error(
                    key,
                    format!("expected a finite number, got {value:?}"),
                ));
            }
        }
        let section = build_section(&self.material, &self.section)
            .map_err(|(key, message)| error(&key, message))?;
        let params = BasisParams::new(file, text, "basis", &self.basis.params);
        // For a basis sized by its own keys, `modes` is only how many modes are reported.
        let sized_by_modes = registry
            .basis(&self.basis.kind)
            .is_none_or(|f| f.mode_count() == ModeCount::FromModes);
        let basis = registry.build_basis(
            &params,
            &self.basis.kind,
            "modes",
            sized_by_modes.then_some(self.modes),
        )?;
        if self.modes == 0 || self.modes > basis.len() {
            return Err(error(
                "modes",
                format!(
                    "modes = {} must be between 1 and the {} functions of the {} basis",
                    self.modes,
                    basis.len(),
                    basis.name()
                ),
            ));
        }
        let integrals = ModalIntegrals::compute(basis.as_ref(), section.as_ref(), self.length)
            .map_err(|e| error("", format!("{file}: modal integrals: {e}")))?;
        Ok(BuiltLink {
            bending_stiffness_at_start: section.bending_stiffness(0.0),
            mass_per_length_at_start: section.mass_per_length(0.0),
            basis,
            integrals,
            reported: self.modes,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_key_is_reported_with_line_and_column() {
        let text = "length = 0.2\nmodes = 3\nlenght = 1\n";
        let err = LinkFile::parse("link.toml", text).unwrap_err().to_string();
        assert!(err.contains("link.toml:3:1"), "{err}");
        assert!(err.contains("lenght"), "{err}");
    }

    #[test]
    fn unknown_key_inside_a_tagged_table_is_rejected() {
        let text = "length = 0.2\nmodes = 3\n[material]\nyoungs_modulus = 7e10\ndensity = 2770.0\n\
                    [section]\nkind = \"uniform\"\nthickness = 0.002\nheight = 0.03\nwidth = 1\n\
                    [basis]\nkind = \"sine\"\n";
        let err = LinkFile::parse("link.toml", text).unwrap_err().to_string();
        assert!(err.contains("section.width"), "{err}");
    }

    #[test]
    fn the_shipped_link_file_builds_with_the_mass_of_its_section() {
        let path = Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../configs/link_paper.toml"
        ));
        let (file, text) = LinkFile::load(path).unwrap();
        let link = file.build("link_paper.toml", &text).unwrap();
        let SectionConfig::Uniform { thickness, height } = file.section else {
            panic!("the shipped link is uniform");
        };
        // m = rho t h l
        let mass = file.material.density * thickness * height * file.length;
        assert!((link.integrals.total_mass - mass).abs() < 1e-12 * mass);
        assert_eq!(link.reported, file.modes);
    }

    #[test]
    fn a_non_finite_load_is_located() {
        let text = "length = 0.2\nmodes = 3\n[material]\nyoungs_modulus = 7e10\ndensity = 2770.0\n\
                    [section]\nkind = \"uniform\"\nthickness = 0.002\nheight = 0.03\n\
                    [basis]\nkind = \"sine\"\n[load]\np0 = nan\n";
        let file = LinkFile::parse("link.toml", text).unwrap();
        let err = file.build("link.toml", text).err().unwrap().to_string();
        assert!(err.contains("link.toml:13:1: load.p0"), "{err}");
    }
}
