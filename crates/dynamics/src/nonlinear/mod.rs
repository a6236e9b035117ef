//! Geometrically nonlinear links: planar co-rotational Euler-Bernoulli beam elements
//! (Crisfield 1991, vol. 1, section 7.3; Felippa, *Nonlinear Finite Element Methods*), a
//! static solver for validation against the elastica, and the fully nonlinear 3-PRR
//! [`NonlinearSystem`] whose links stay right at large deflection.
//!
//! * [`CorotationalElement`]: one element's strains, forces and tangent stiffness;
//! * [`PlanarBeam`]: a chain of elements with [`PlanarBeam::solve_static`] (Newton with
//!   load or displacement increments);
//! * [`NonlinearSystem`]: the machine with co-rotational links, prescribed sliders and a free
//!   rigid platform, as an [`flexprr_integrators::OdeSystem`].

mod banded;
mod element;
mod equations;
mod inertia;
mod statics;
mod system;
mod tangent;

pub use element::{CorotationalElement, ElementState, LocalStrain};
pub use inertia::{ElementInertia, InertiaDerivatives, NodalMass};
pub use statics::{PlanarBeam, StaticSolution};
pub use system::{
    DEFAULT_ELEMENTS, NonlinearCounters, NonlinearOptions, NonlinearOutput, NonlinearSystem,
};
