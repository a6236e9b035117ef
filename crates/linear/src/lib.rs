//! Linear models of the whole machine (docs/linear.md): any scene model
//! ([`flexprr_dynamics::SceneModel`]) linearised about an operating point, a pose at rest or
//! the state of a motion at a time, into `x' = A x + B u`, `y = C x + D u` with named inputs
//! (slider forces, point forces on the links, setpoints, patch voltages) and outputs (slider
//! positions, velocities and tracking errors, motor torques, the platform pose and its rates,
//! deflection, slope and acceleration at link points, patch sensors); a sampled control law
//! gives the exact discrete-time model of its loop. From that one linearisation the
//! whole-machine modes (frequencies, damping ratios, shapes), frequency responses and
//! well-scaled realisations. Nothing here knows a model kind: the coupled, nonlinear and
//! actuated models are linearised alike.

mod balance;
pub mod cost;
mod direct;
mod discrete;
mod error;
pub mod expm;
mod frf;
mod linearize;
mod margins;
mod modes;
mod names;
mod outputs;
pub mod realization;
mod relax;

pub use direct::{frequency_response_direct, frequency_response_with_progress};
pub use error::LinearError;
pub use flexprr_dynamics::channel::{Axis, ChannelError, Input, Output};
pub use frf::{Complex, frequency_response};
pub use linearize::{
    Coulomb, Derivatives, Linearization, Settings, StateName, linearize, linearize_with,
    linearize_with_settings,
};
pub use margins::{LoopMargins, loop_margins, margin_grid};
pub use modes::{Mode, modes};
