//! The named columns of the run's feature outputs that the figures draw: the machine
//! frequencies, the control outputs (motor torque, speed, saturation) and the patches (their
//! voltages and power, the deflection without vibration control). The run layer re-exports
//! them where it fills the tables (`flexprr_run::machine_frequencies`, `control`, `piezo`).

use flexprr_dynamics::{NamedQuantity, Quantity as Q};
use flexprr_scene::Scene;

/// A whole-machine natural frequency `|lambda| / 2 pi` of the linearised model (Hz):
/// `f_machine_<k>_Hz`.
pub const MACHINE_FREQUENCY: Q = Q::Named(NamedQuantity::new("f_machine", "Hz", "f", "Hz"));
/// A whole-machine damping ratio `-Re(lambda) / |lambda|` (dimensionless):
/// `zeta_machine_<k>_ratio`.
pub const MACHINE_DAMPING_RATIO: Q =
    Q::Named(NamedQuantity::new("zeta_machine", "ratio", "ζ", "1"));

/// Motor torque after saturation (N m): `actuators.csv`, `motor_torque_<i>_N_m`.
pub const MOTOR_TORQUE: Q = Q::Named(NamedQuantity::new("motor_torque", "N_m", "τ", "N·m"));
/// Motor speed (rev/s): `motor_speed_<i>_rev_s`.
pub const MOTOR_SPEED: Q = Q::Named(NamedQuantity::new("motor_speed", "rev_s", "n", "rev/s"));
/// Whether the motor torque is saturated at its peak (1) or not (0):
/// `motor_saturated_<i>_flag`.
pub const MOTOR_SATURATED: Q = Q::Named(NamedQuantity::new("motor_saturated", "flag", "sat", "1"));

/// Transverse deflection w at xi of the same scene without its vibration control (m):
/// `w_<i>_xi<xi>_uncontrolled_m`.
pub const DEFLECTION_UNCONTROLLED: Q =
    Q::Named(NamedQuantity::new("w", "m", "w", "m").with_suffix("uncontrolled"));
/// A patch's sensor voltage `V_s` (V); link and the patch's index on it.
pub const PATCH_SENSOR_VOLTAGE: Q = Q::Named(NamedQuantity::new("V_sensor", "V", "V_s", "V"));
/// A patch's voltage command from the vibration control law (V).
pub const PATCH_COMMAND_VOLTAGE: Q = Q::Named(NamedQuantity::new("V_command", "V", "V_c", "V"));
/// A patch's applied voltage: the command clipped at its limit (V).
pub const PATCH_VOLTAGE: Q = Q::Named(NamedQuantity::new("V_applied", "V", "V", "V"));
/// Whether a patch's command was clipped at its limit (1) or not (0).
pub const PATCH_SATURATED: Q = Q::Named(NamedQuantity::new("patch_saturated", "flag", "sat", "1"));
/// Mechanical power a patch's actuator delivers to its link (W; negative when it removes
/// energy).
pub const PATCH_POWER: Q = Q::Named(NamedQuantity::new("P_patch", "W", "P", "W"));

/// Patch `p`'s index among the patches on its link (0-based): the second index of its
/// columns.
pub fn index_on_link(scene: &Scene, p: usize) -> usize {
    let link = scene.patches[p].link;
    scene.patches[..p].iter().filter(|q| q.link == link).count()
}
