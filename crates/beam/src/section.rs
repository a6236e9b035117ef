//! Cross-section properties along a link: bending stiffness `EI(xi)` and mass per length
//! `rhoA(xi)`, `xi = x / l`.

use crate::BeamError;

/// Bending stiffness and mass per unit length along the link.
///
/// # Implementing
/// A link whose mass per length grows linearly, `rhoA = m0 (1 + xi)`, with constant `EI`.
/// With the first sine mode `psi = sin(pi xi)` the integrals have closed forms:
/// `M = l m0 int (1 + xi) sin^2(pi xi) dxi = 3 l m0 / 4` (since `int xi sin^2 = 1/4`),
/// `Kf = EI pi^4 / (2 l^3)`, and the link's mass is `3 l m0 / 2`:
///
/// ```
/// use flexprr_beam::{ModalIntegrals, Section, SineBasis};
///
/// struct Wedge {
///     ei: f64,
///     m0: f64,
/// }
///
/// impl Section for Wedge {
///     fn bending_stiffness(&self, _xi: f64) -> f64 {
///         self.ei
///     }
///     fn mass_per_length(&self, xi: f64) -> f64 {
///         self.m0 * (1.0 + xi)
///     }
///     fn polynomial_degrees(&self) -> Option<(usize, usize)> {
///         Some((0, 1))
///     }
/// }
///
/// let (section, l) = (Wedge { ei: 1.46, m0: 0.1662 }, 0.2);
/// let integrals = ModalIntegrals::compute(&SineBasis::new(1).unwrap(), &section, l).unwrap();
/// let pi4 = std::f64::consts::PI.powi(4);
/// let expected_mass = 0.75 * l * section.m0;
/// let expected_stiffness = section.ei * pi4 / (2.0 * l.powi(3));
/// assert!((integrals.mass[(0, 0)] - expected_mass).abs() <= 1e-12 * expected_mass);
/// assert!((integrals.stiffness[(0, 0)] - expected_stiffness).abs() <= 1e-12 * expected_stiffness);
/// assert!((integrals.total_mass - 1.5 * l * section.m0).abs() <= 1e-12 * integrals.total_mass);
/// ```
pub trait Section: Send + Sync {
    /// `EI(xi)` in N m^2 (bending in the plane of the mechanism).
    fn bending_stiffness(&self, xi: f64) -> f64;

    /// `rhoA(xi)` in kg/m.
    fn mass_per_length(&self, xi: f64) -> f64;

    /// Interior points of `(0, 1)` where the properties jump (quadrature panels are cut there).
    fn breakpoints(&self) -> Vec<f64> {
        vec![]
    }

    /// Polynomial degrees of `(EI, rhoA)` on each panel between breakpoints, if they are
    /// polynomials: used to pick an exact Gauss rule. `None` makes the modal integrals refine
    /// until they settle.
    fn polynomial_degrees(&self) -> Option<(usize, usize)> {
        None
    }
}

fn positive(name: &'static str, value: f64) -> Result<f64, BeamError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(BeamError::InvalidParameter {
            name,
            value,
            reason: "must be finite and positive",
        })
    }
}

/// Constant `EI` and `rhoA`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UniformSection {
    bending_stiffness: f64,
    mass_per_length: f64,
}

impl UniformSection {
    /// From `EI` (N m^2) and `rhoA` (kg/m), both positive.
    pub fn new(bending_stiffness: f64, mass_per_length: f64) -> Result<Self, BeamError> {
        Ok(Self {
            bending_stiffness: positive("bending_stiffness", bending_stiffness)?,
            mass_per_length: positive("mass_per_length", mass_per_length)?,
        })
    }

    /// Solid rectangle of in-plane `thickness` t (the bending dimension) and out-of-plane
    /// `height` h: `EI = E h t^3 / 12`, `rhoA = density t h` (model.md section 2).
    pub fn rectangle(
        youngs_modulus: f64,
        density: f64,
        thickness: f64,
        height: f64,
    ) -> Result<Self, BeamError> {
        let e = positive("youngs_modulus", youngs_modulus)?;
        let rho = positive("density", density)?;
        let t = positive("thickness", thickness)?;
        let h = positive("height", height)?;
        Self::new(e * h * t.powi(3) / 12.0, rho * t * h)
    }

    /// `EI` in N m^2.
    pub fn ei(&self) -> f64 {
        self.bending_stiffness
    }

    /// `rhoA` in kg/m.
    pub fn rho_a(&self) -> f64 {
        self.mass_per_length
    }
}

impl Section for UniformSection {
    fn bending_stiffness(&self, _xi: f64) -> f64 {
        self.bending_stiffness
    }
    fn mass_per_length(&self, _xi: f64) -> f64 {
        self.mass_per_length
    }
    fn polynomial_degrees(&self) -> Option<(usize, usize)> {
        Some((0, 0))
    }
}

/// Piecewise-constant section: piece `k` is uniform on `(end_{k-1}, end_k)`.
#[derive(Debug, Clone, PartialEq)]
pub struct SteppedSection {
    ends: Vec<f64>,
    pieces: Vec<UniformSection>,
}

impl SteppedSection {
    /// Pieces as `(end, section)`, with strictly increasing ends in `(0, 1]`, the last = 1.
    pub fn new(pieces: Vec<(f64, UniformSection)>) -> Result<Self, BeamError> {
        if pieces.is_empty() {
            return Err(BeamError::InvalidCount {
                name: "section pieces",
                value: 0,
                reason: "at least one piece is needed",
            });
        }
        let mut previous = 0.0;
        for &(end, _) in &pieces {
            if !(end.is_finite() && end > previous && end <= 1.0 + 1e-12) {
                return Err(BeamError::InvalidParameter {
                    name: "section piece end",
                    value: end,
                    reason: "ends must increase strictly within (0, 1]",
                });
            }
            previous = end;
        }
        if (previous - 1.0).abs() > 1e-12 {
            return Err(BeamError::InvalidParameter {
                name: "last section piece end",
                value: previous,
                reason: "must be 1 (the whole link)",
            });
        }
        let (ends, pieces) = pieces.into_iter().unzip();
        Ok(Self { ends, pieces })
    }

    fn piece(&self, xi: f64) -> &UniformSection {
        let k = self.ends.partition_point(|&end| end <= xi);
        &self.pieces[k.min(self.pieces.len() - 1)]
    }
}

impl Section for SteppedSection {
    fn bending_stiffness(&self, xi: f64) -> f64 {
        self.piece(xi).bending_stiffness
    }
    fn mass_per_length(&self, xi: f64) -> f64 {
        self.piece(xi).mass_per_length
    }
    fn breakpoints(&self) -> Vec<f64> {
        self.ends[..self.ends.len() - 1].to_vec()
    }
    fn polynomial_degrees(&self) -> Option<(usize, usize)> {
        Some((0, 0))
    }
}

/// Rectangle whose in-plane thickness varies linearly, `t(xi) = t0 + (t1 - t0) xi`, at
/// constant height: `EI = E h t(xi)^3 / 12` (cubic), `rhoA = density t(xi) h` (linear).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TaperedSection {
    youngs_modulus: f64,
    density: f64,
    thickness_start: f64,
    thickness_end: f64,
    height: f64,
}

impl TaperedSection {
    /// Thickness `thickness_start` at `xi = 0` and `thickness_end` at `xi = 1`.
    pub fn new(
        youngs_modulus: f64,
        density: f64,
        thickness_start: f64,
        thickness_end: f64,
        height: f64,
    ) -> Result<Self, BeamError> {
        Ok(Self {
            youngs_modulus: positive("youngs_modulus", youngs_modulus)?,
            density: positive("density", density)?,
            thickness_start: positive("thickness_start", thickness_start)?,
            thickness_end: positive("thickness_end", thickness_end)?,
            height: positive("height", height)?,
        })
    }

    /// In-plane thickness at `xi` (m).
    pub fn thickness(&self, xi: f64) -> f64 {
        self.thickness_start + (self.thickness_end - self.thickness_start) * xi
    }
}

impl Section for TaperedSection {
    fn bending_stiffness(&self, xi: f64) -> f64 {
        self.youngs_modulus * self.height * self.thickness(xi).powi(3) / 12.0
    }
    fn mass_per_length(&self, xi: f64) -> f64 {
        self.density * self.thickness(xi) * self.height
    }
    fn polynomial_degrees(&self) -> Option<(usize, usize)> {
        Some((3, 1))
    }
}
