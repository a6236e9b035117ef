//! The link description shared by scene files and the single-link CLI (`flexprr beam`).

use std::sync::Arc;

use flexprr_beam::{
    Basis, ClassicalBasis, EndCondition, EndConditions, HermiteBasis, Section, SineBasis,
    SteppedSection, TaperedSection, UniformSection,
};
use serde::{Deserialize, Serialize};

/// Material constants.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MaterialConfig {
    /// Young's modulus `E` (Pa).
    pub youngs_modulus: f64,
    /// Density (kg/m^3).
    pub density: f64,
}

/// Rectangular cross-section of in-plane (bending) thickness `t` and out-of-plane height `h`.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum SectionConfig {
    /// Constant `t` and `h`: `EI = E h t^3 / 12`, `rhoA = density t h`.
    Uniform {
        /// In-plane thickness `t` (m).
        thickness: f64,
        /// Out-of-plane height `h` (m).
        height: f64,
    },
    /// Thickness linear from `thickness_start` (slider end) to `thickness_end`.
    Tapered {
        /// Thickness at `xi = 0` (m).
        thickness_start: f64,
        /// Thickness at `xi = 1` (m).
        thickness_end: f64,
        /// Out-of-plane height (m).
        height: f64,
    },
    /// Piecewise-constant rectangles.
    Stepped {
        /// Pieces in order along the link.
        steps: Vec<StepConfig>,
    },
}

/// One piece of a stepped section.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct StepConfig {
    /// Where the piece ends, as a fraction `xi` of the length (the last one is 1).
    pub end: f64,
    /// In-plane thickness (m).
    pub thickness: f64,
    /// Out-of-plane height (m).
    pub height: f64,
}

/// End conditions, `"<at slider>-<at platform>"`.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, Default, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
#[allow(missing_docs)]
pub enum EndsConfig {
    #[default]
    PinnedPinned,
    PinnedClamped,
    PinnedFree,
    ClampedPinned,
    ClampedClamped,
    ClampedFree,
    FreePinned,
    FreeClamped,
    FreeFree,
}

impl EndsConfig {
    /// The beam layer's end conditions.
    pub fn to_ends(self) -> EndConditions {
        use EndCondition::{Clamped, Free, Pinned};
        let (left, right) = match self {
            EndsConfig::PinnedPinned => (Pinned, Pinned),
            EndsConfig::PinnedClamped => (Pinned, Clamped),
            EndsConfig::PinnedFree => (Pinned, Free),
            EndsConfig::ClampedPinned => (Clamped, Pinned),
            EndsConfig::ClampedClamped => (Clamped, Clamped),
            EndsConfig::ClampedFree => (Clamped, Free),
            EndsConfig::FreePinned => (Free, Pinned),
            EndsConfig::FreeClamped => (Free, Clamped),
            EndsConfig::FreeFree => (Free, Free),
        };
        EndConditions::new(left, right)
    }
}

/// Assumed-mode basis.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, Default)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum BasisConfig {
    /// `sin(j pi xi)` (pinned-pinned; the paper's).
    #[default]
    Sine,
    /// Euler-Bernoulli eigenfunctions of a uniform beam with the given ends.
    Classical {
        /// End conditions, e.g. `"clamped-free"`.
        ends: EndsConfig,
    },
    /// Hermite cubic finite elements.
    Hermite {
        /// Number of elements.
        elements: usize,
        /// End conditions (default `"pinned-pinned"`).
        #[serde(default)]
        ends: EndsConfig,
    },
}

/// Builds the section; errors name the offending key (relative to the section table).
pub fn build_section(
    material: &MaterialConfig,
    section: &SectionConfig,
) -> Result<Box<dyn Section>, (String, String)> {
    let (e, rho) = (material.youngs_modulus, material.density);
    fn wrap(key: &'static str) -> impl Fn(flexprr_beam::BeamError) -> (String, String) {
        move |err| (key.to_string(), err.to_string())
    }
    Ok(match section {
        SectionConfig::Uniform { thickness, height } => Box::new(
            UniformSection::rectangle(e, rho, *thickness, *height).map_err(wrap("section"))?,
        ),
        SectionConfig::Tapered {
            thickness_start,
            thickness_end,
            height,
        } => Box::new(
            TaperedSection::new(e, rho, *thickness_start, *thickness_end, *height)
                .map_err(wrap("section"))?,
        ),
        SectionConfig::Stepped { steps } => {
            let pieces = steps
                .iter()
                .enumerate()
                .map(|(k, s)| {
                    UniformSection::rectangle(e, rho, s.thickness, s.height)
                        .map(|u| (s.end, u))
                        .map_err(|err| (format!("section.steps.{k}"), err.to_string()))
                })
                .collect::<Result<Vec<_>, _>>()?;
            Box::new(SteppedSection::new(pieces).map_err(wrap("section.steps"))?)
        }
    })
}

/// Builds the basis with `modes` functions (for Hermite, the element count decides the size
/// and `modes` must not exceed it); errors name the offending key.
pub fn build_basis(basis: &BasisConfig, modes: usize) -> Result<Arc<dyn Basis>, (String, String)> {
    fn wrap(key: &'static str) -> impl Fn(flexprr_beam::BeamError) -> (String, String) {
        move |err| (key.to_string(), err.to_string())
    }
    Ok(match basis {
        BasisConfig::Sine => Arc::new(SineBasis::new(modes).map_err(wrap("modes"))?),
        BasisConfig::Classical { ends } => {
            Arc::new(ClassicalBasis::new(ends.to_ends(), modes).map_err(wrap("basis"))?)
        }
        BasisConfig::Hermite { elements, ends } => {
            Arc::new(HermiteBasis::new(*elements, ends.to_ends()).map_err(wrap("basis.elements"))?)
        }
    })
}
