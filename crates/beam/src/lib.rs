//! The beam layer of flexprr: assumed-mode bases, cross-sections, Gauss-Legendre
//! quadrature, the modal integrals of one link and its natural frequencies under an axial
//! load.
//!
//! The transverse deflection of a link of length `l` is `w(x, t) = sum_j eta_j(t) psi_j(x/l)`
//! (model.md section 6). A [`Basis`] gives `psi_j` and its derivatives on `[0, 1]`; a
//! [`Section`] gives `EI(xi)` and `rhoA(xi)`; [`ModalIntegrals::compute`] integrates them
//! once into the mass, bending and geometric stiffness matrices; [`FrequencySolver`] and
//! [`frequencies`] solve the generalized eigenproblem `(Kf + Kp) v = omega^2 M v`
//! (or the paper's diagonal eq. 22).
//!
//! ```
//! use flexprr_beam::{AxialLoad, Coupling, ModalIntegrals, SineBasis, UniformSection, frequencies};
//! // The paper's link: l = 0.2 m, t = 2 mm, h = 30 mm, aluminium (E = 7.3e10 Pa).
//! let section = UniformSection::rectangle(7.3e10, 2770.0, 0.002, 0.03).unwrap();
//! let integrals = ModalIntegrals::compute(&SineBasis::new(3).unwrap(), &section, 0.2).unwrap();
//! let f = frequencies(&integrals, &AxialLoad::uniform(0.0), Coupling::Full).unwrap();
//! assert!((f.modes[0].frequency_hz - 116.39).abs() < 0.01);
//! ```

mod basis;
mod error;
mod frequency;
mod integrals;
mod patched;
pub mod quadrature;
mod section;

pub use basis::{Basis, ClassicalBasis, EndCondition, EndConditions, HermiteBasis, SineBasis};
pub use error::BeamError;
pub use frequency::{
    AxialLoad, Coupling, FrequencySolver, LinkFrequencies, ModeFrequency, ModeState, frequencies,
};
pub use integrals::ModalIntegrals;
pub use patched::{Layer, LayeredSection};
pub use quadrature::{CompositeRule, GaussLegendre};
pub use section::{Section, SteppedSection, TaperedSection, UniformSection};
