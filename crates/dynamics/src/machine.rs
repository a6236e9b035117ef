//! The machine: geometry, link models and rigid-body inertia.

use std::sync::Arc;

use flexprr_beam::{Basis, ModalIntegrals, Section};
use flexprr_kinematics::Geometry;

use crate::DynamicsError;

/// One flexible link: its modal integrals (mass, stiffness, geometric stiffness, forcing
/// vectors) and the rigid-body inertia used by the inverse dynamics.
#[derive(Clone)]
pub struct LinkModel {
    /// The assumed-mode basis (for deflections at any `xi`).
    pub basis: Arc<dyn Basis>,
    /// Modal integrals from the beam layer (basis, section and length applied), computed once.
    pub integrals: ModalIntegrals,
    /// Mass moment of inertia about the link's centroid (kg m^2).
    pub centroid_inertia: f64,
}

impl std::fmt::Debug for LinkModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LinkModel")
            .field("basis", &self.basis.name())
            .field("length", &self.integrals.length)
            .field("mass", &self.integrals.total_mass)
            .field("centroid_inertia", &self.centroid_inertia)
            .finish()
    }
}

impl LinkModel {
    /// A link from its basis, section and length; the modal integrals are computed here,
    /// once. The rigid-body inertia is that of a uniform slender bar, `m l^2 / 12` (exact for
    /// uniform sections; stepped or tapered links are treated as uniform bars of the same mass
    /// by the rigid inverse dynamics).
    ///
    /// # Errors
    /// Invalid basis, section or length (from the beam layer).
    pub fn new(
        basis: Arc<dyn Basis>,
        section: &dyn Section,
        length: f64,
    ) -> Result<Self, DynamicsError> {
        let integrals = ModalIntegrals::compute(basis.as_ref(), section, length)?;
        let m = integrals.total_mass;
        Ok(Self {
            basis,
            centroid_inertia: m * length * length / 12.0,
            integrals,
        })
    }

    /// Transverse deflection `w(xi) = sum_j eta_j psi_j(xi)` for the link's modal
    /// coordinates `eta` (m).
    pub fn deflection(&self, eta: &[f64], xi: f64) -> f64 {
        eta.iter()
            .enumerate()
            .map(|(j, e)| e * self.basis.eval(j, xi)[0])
            .sum()
    }

    /// Link mass `m = int rhoA dx` (kg).
    pub fn mass(&self) -> f64 {
        self.integrals.total_mass
    }

    /// Link length `l` (m).
    pub fn length(&self) -> f64 {
        self.integrals.length
    }

    /// Mean mass per unit length `m / l` (kg/m), used for the distributed inertia part of
    /// the axial force (eq. 11).
    pub fn mass_per_length(&self) -> f64 {
        self.integrals.total_mass / self.integrals.length
    }

    /// Number of assumed modes `r`.
    pub fn modes(&self) -> usize {
        self.integrals.r()
    }
}

/// A 3-PRR machine with flexible links: everything the dynamics needs except the motion.
#[derive(Debug, Clone)]
pub struct Machine {
    /// Guides, platform attachment points, link lengths, branches.
    pub geometry: Geometry,
    /// The three links (their lengths must equal the geometry's).
    pub links: [LinkModel; 3],
    /// Slider masses `m_si` (kg).
    pub slider_mass: [f64; 3],
    /// Platform mass `m_p` (kg).
    pub platform_mass: f64,
    /// Platform moment of inertia about its reference point `I_p` (kg m^2).
    pub platform_inertia: f64,
}

impl Machine {
    /// A validated machine.
    ///
    /// # Errors
    /// Negative or non-finite masses and inertias, or link lengths that differ from the
    /// geometry's by more than 1e-9 relative.
    pub fn new(
        geometry: Geometry,
        links: [LinkModel; 3],
        slider_mass: [f64; 3],
        platform_mass: f64,
        platform_inertia: f64,
    ) -> Result<Self, DynamicsError> {
        let check = |quantity: String, value: f64| {
            if value.is_finite() && value >= 0.0 {
                Ok(())
            } else {
                Err(DynamicsError::InvalidParameter {
                    quantity,
                    value,
                    reason: "must be finite and non-negative",
                })
            }
        };
        for (i, m) in slider_mass.iter().enumerate() {
            check(format!("slider_mass of leg {}", i + 1), *m)?;
        }
        check("platform_mass".into(), platform_mass)?;
        check("platform_inertia".into(), platform_inertia)?;
        for (i, link) in links.iter().enumerate() {
            let lg = geometry.legs[i].link_length;
            let ll = link.length();
            if (lg - ll).abs() > 1e-9 * lg.abs().max(ll.abs()) {
                return Err(DynamicsError::InvalidParameter {
                    quantity: format!("length of link {}", i + 1),
                    value: ll,
                    reason: "must equal the geometry's link length",
                });
            }
            check(
                format!("centroid inertia of link {}", i + 1),
                link.centroid_inertia,
            )?;
        }
        Ok(Self {
            geometry,
            links,
            slider_mass,
            platform_mass,
            platform_inertia,
        })
    }

    /// Total number of modal coordinates `r_1 + r_2 + r_3`.
    pub fn total_modes(&self) -> usize {
        self.links.iter().map(LinkModel::modes).sum()
    }

    /// Offset of link `i`'s modal coordinates in the stacked vector `eta`.
    pub fn mode_offset(&self, link: usize) -> usize {
        self.links[..link].iter().map(LinkModel::modes).sum()
    }
}
