//! The two named formulations and their independent switches (model.md section 6).

use std::fmt;

use flexprr_beam::Coupling;

use crate::axial::{AxialForceModel, JointReactionAxialForce, NoAxialForce, PaperAxialForce};

/// Which axial force model to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AxialModel {
    /// No axial force.
    None,
    /// The paper's eq. (12).
    Paper,
    /// The joint-reaction form (model.md section 5).
    JointReaction,
}

impl AxialModel {
    /// The model object.
    pub fn model(self) -> Box<dyn AxialForceModel> {
        match self {
            AxialModel::None => Box::new(NoAxialForce),
            AxialModel::Paper => Box::new(PaperAxialForce),
            AxialModel::JointReaction => Box::new(JointReactionAxialForce),
        }
    }
}

/// Switches that define the modal equations of the links.
///
/// `M eta'' + C eta' + (Kf + Kp [- b'^2 M]) eta = -M_rho rho'' - M_beta b'' [+ F_fg]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Formulation {
    /// Axial force model feeding `Kp`.
    pub axial: AxialModel,
    /// `Kp` full or diagonal only (the paper keeps the diagonal, eq. 21).
    pub geometric_stiffness: Coupling,
    /// The paper's coupling force `F_fg = m rho' b' cos(a - b) int psi` (eq. 15-16).
    pub coriolis_forcing: bool,
    /// The centrifugal softening `-b'^2 M` of the consistent linearisation.
    pub centrifugal_softening: bool,
}

impl Formulation {
    /// The paper's formulation: eq. (16) as printed (with `b''` in the `M_beta` term),
    /// diagonal `Kp`, the axial force of eq. (12), `F_fg`, no softening.
    pub const fn paper() -> Self {
        Self {
            axial: AxialModel::Paper,
            geometric_stiffness: Coupling::Diagonal,
            coriolis_forcing: true,
            centrifugal_softening: false,
        }
    }

    /// The consistent linearisation of model.md section 6: no `F_fg`, centrifugal softening,
    /// joint-reaction axial force, full `Kp`.
    pub const fn consistent() -> Self {
        Self {
            axial: AxialModel::JointReaction,
            geometric_stiffness: Coupling::Full,
            coriolis_forcing: false,
            centrifugal_softening: true,
        }
    }

    /// The name of the preset this equals, or `"custom"`.
    pub fn name(&self) -> &'static str {
        if *self == Self::paper() {
            "paper"
        } else if *self == Self::consistent() {
            "consistent"
        } else {
            "custom"
        }
    }
}

impl Default for Formulation {
    fn default() -> Self {
        Self::consistent()
    }
}

impl fmt::Display for Formulation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} (axial force {:?}, Kp {:?}, F_fg {}, softening {})",
            self.name(),
            self.axial,
            self.geometric_stiffness,
            if self.coriolis_forcing { "on" } else { "off" },
            if self.centrifugal_softening {
                "on"
            } else {
                "off"
            }
        )
    }
}
