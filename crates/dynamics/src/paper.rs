//! The paper's machine (model.md sections 1-2), for tests, benchmarks and examples.
//!
//! Scenes normally come from TOML files (`configs/paper_f20.toml`); this constructor builds
//! the same machine in code. Parameter provenance: link dimensions, density, layout angles,
//! platform side and travel are stated in the paper; `E = 7.3e10` Pa (not the stated 7.1e10)
//! reproduces the paper's pinned-pinned frequencies; the platform mass 0.2 kg is
//! reconstructed from Table I; the slider mass 0.5 kg and `I_p = m_p s^2 / 12` are assumptions.

use std::sync::Arc;

use flexprr_beam::{SineBasis, UniformSection};
use flexprr_kinematics::{Circle, Geometry};

use crate::{DynamicsError, LinkModel, Machine};

/// Young's modulus that reproduces the paper's printed frequencies (Pa).
pub const YOUNGS_MODULUS: f64 = 7.3e10;
/// Link density (kg/m^3).
pub const DENSITY: f64 = 2770.0;
/// Link length (m).
pub const LINK_LENGTH: f64 = 0.2;
/// In-plane link thickness (m).
pub const THICKNESS: f64 = 0.002;
/// Link height, normal to the plane (m).
pub const HEIGHT: f64 = 0.03;
/// Platform side (m).
pub const PLATFORM_SIDE: f64 = 0.1;
/// Platform mass (kg, reconstructed).
pub const PLATFORM_MASS: f64 = 0.2;
/// Slider mass (kg, assumed).
pub const SLIDER_MASS: f64 = 0.5;
/// Half the slider travel (m).
pub const HALF_TRAVEL: f64 = 0.2;
/// Guide angles (deg).
pub const ALPHA_DEG: [f64; 3] = [150.0, 270.0, 30.0];

/// The paper's machine with `r` sine modes per link and Young's modulus `youngs_modulus`.
///
/// # Errors
/// Only for invalid `r` (zero).
pub fn machine(r: usize, youngs_modulus: f64) -> Result<Machine, DynamicsError> {
    let alpha = ALPHA_DEG.map(f64::to_radians);
    let geometry = Geometry::radial(alpha, LINK_LENGTH, PLATFORM_SIDE, HALF_TRAVEL)
        .map_err(|source| DynamicsError::Kinematics { t: 0.0, source })?;
    let section = UniformSection::rectangle(youngs_modulus, DENSITY, THICKNESS, HEIGHT)?;
    let basis: Arc<dyn flexprr_beam::Basis> = Arc::new(SineBasis::new(r)?);
    let link = LinkModel::new(basis, &section, LINK_LENGTH)?;
    Machine::new(
        geometry,
        [link.clone(), link.clone(), link],
        [SLIDER_MASS; 3],
        PLATFORM_MASS,
        PLATFORM_MASS * PLATFORM_SIDE * PLATFORM_SIDE / 12.0,
    )
}

/// The paper's circle at `frequency` Hz: `x = 0.05 cos(2 pi f t) - 0.05`, `y = 0.05 sin(2 pi f t)`,
/// `phi = 45 deg`.
///
/// # Errors
/// Non-positive or non-finite frequency.
pub fn trajectory(frequency: f64) -> Result<Circle, DynamicsError> {
    Circle::paper(frequency).map_err(|source| DynamicsError::Kinematics { t: 0.0, source })
}
