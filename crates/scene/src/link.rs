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

/// Smallest length-to-thickness ratio accepted for an Euler-Bernoulli link: below about 10
/// shear deformation and rotary inertia (Timoshenko) change the first frequency by several
/// per cent, and the model ignores both.
pub const MIN_SLENDERNESS: f64 = 10.0;

/// Checks the material and section values of a link of length `length` before anything is
/// built: positive, finite Young's modulus, density and dimensions, and slender enough for
/// Euler-Bernoulli bending (`length / thickness >= MIN_SLENDERNESS` for the thickest part,
/// and `height <= length`: a link taller than it is long is a plate). Errors name the key
/// relative to the link table (`material.youngs_modulus`, `section.steps.1.thickness`).
///
/// # Errors
/// `(key, message)` of the first bad value.
pub fn check_link(
    material: &MaterialConfig,
    section: &SectionConfig,
    length: f64,
) -> Result<(), (String, String)> {
    let positive = |key: &str, value: f64, unit: &str| {
        if value.is_finite() && value > 0.0 {
            Ok(())
        } else {
            Err((
                key.to_string(),
                format!("expected a positive number ({unit}), got {value:?}"),
            ))
        }
    };
    positive("material.youngs_modulus", material.youngs_modulus, "Pa")?;
    positive("material.density", material.density, "kg/m^3")?;
    // (key, thickness, height) of every rectangle.
    let mut parts: Vec<(String, f64, f64)> = Vec::new();
    match section {
        SectionConfig::Uniform { thickness, height } => {
            positive("section.thickness", *thickness, "m")?;
            positive("section.height", *height, "m")?;
            parts.push(("section".into(), *thickness, *height));
        }
        SectionConfig::Tapered {
            thickness_start,
            thickness_end,
            height,
        } => {
            positive("section.thickness_start", *thickness_start, "m")?;
            positive("section.thickness_end", *thickness_end, "m")?;
            positive("section.height", *height, "m")?;
            parts.push((
                "section".into(),
                thickness_start.max(*thickness_end),
                *height,
            ));
        }
        SectionConfig::Stepped { steps } => {
            for (k, s) in steps.iter().enumerate() {
                positive(&format!("section.steps.{k}.thickness"), s.thickness, "m")?;
                positive(&format!("section.steps.{k}.height"), s.height, "m")?;
                parts.push((format!("section.steps.{k}"), s.thickness, s.height));
            }
        }
    }
    if !(length.is_finite() && length > 0.0) {
        return Err((
            "length".into(),
            format!("expected a positive number (m), got {length:?}"),
        ));
    }
    for (key, thickness, height) in parts {
        let ratio = length / thickness;
        if ratio < MIN_SLENDERNESS {
            let thickness_key =
                if key == "section" && !matches!(section, SectionConfig::Uniform { .. }) {
                    "section".to_string()
                } else {
                    format!("{key}.thickness")
                };
            return Err((
                thickness_key,
                format!(
                    "length / thickness = {length} m / {thickness} m = {ratio:.3} is below {MIN_SLENDERNESS}: \
                     the Euler-Bernoulli link model needs a slender link (thickness at most length / {MIN_SLENDERNESS} = {:.4e} m)",
                    length / MIN_SLENDERNESS
                ),
            ));
        }
        if height > length {
            return Err((
                format!("{key}.height"),
                format!(
                    "height {height} m is more than the length {length} m: such a link is a plate, \
                     not the Euler-Bernoulli beam the model assumes"
                ),
            ));
        }
    }
    Ok(())
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
