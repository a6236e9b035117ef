//! Linear models of the whole machine (docs/linear.md): any scene model
//! ([`flexprr_dynamics::SceneModel`]) linearised about an operating point, a pose at rest or
//! the state of a motion at a time, into `x' = A x + B u`, `y = C x + D u` with named inputs
//! (slider forces, point forces on the links) and outputs (slider positions, platform pose,
//! deflection, slope and acceleration at link points); from that one linearisation the
//! whole-machine modes (frequencies, damping ratios, shapes) and frequency responses. Nothing
//! here knows a model kind: the coupled, nonlinear and actuated models are linearised alike.

mod balance;
mod channel;
mod direct;
mod error;
mod frf;
mod linearize;
mod modes;

pub use channel::{Axis, Input, Output};
pub use direct::frequency_response_direct;
pub use error::LinearError;
pub use frf::{Complex, frequency_response};
pub use linearize::{Derivatives, Linearization, linearize, linearize_with};
pub use modes::{Mode, modes};
