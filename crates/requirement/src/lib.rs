//! What a commanded rigid motion requires of the sliders' motors (docs/control.md,
//! "Feasibility"): the force on each slider from the rigid inverse dynamics, the motor torque
//! and speed through the actuator ([`feasibility`]), their peaks, RMS values and first
//! crossings of the ratings found on the motion itself between the output samples
//! ([`scan`]), and the statistics of sampled series the run's servo summary shares
//! ([`stats`]). It knows the machine, the actuators and the scene's motion; it knows nothing
//! of runs, models or files.

pub mod feasibility;
pub mod scan;
pub mod stats;

pub use feasibility::{Feasibility, LegRequirement, Required, SCAN_TOLERANCE, required};
pub use stats::Peak;
