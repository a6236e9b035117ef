//! Controllers and actuators of the 3-PRR's sliders (docs/control.md). This crate knows no
//! physics of the machine: a [`Controller`] maps the commanded and measured slider states
//! (and a feedforward) to force commands, an [`Actuator`] turns a force command into the
//! force on the slider, with its own inertia, friction and limits. The actuated models of
//! `flexprr-dynamics` call both through these traits.
//!
//! * [`Controller`]: one required method, [`Controller::command`]; continuous
//!   ([`Controller::period`] = 0) or sampled with a zero-order hold; optional states of its own
//!   (an integrator) whose rates it writes.
//! * [`Pid`]: `kind = "pd"` and `kind = "pid"` on each slider's position error, with the
//!   rigid feedforward and anti-windup by conditional integration.
//! * [`Actuator`]: [`IdealForce`] (`kind = "force"`) and [`MotorBallScrew`]
//!   (`kind = "motor_ballscrew"`: reflected rotor inertia, efficiency, torque saturation,
//!   viscous and smoothed Coulomb friction, speed limit reported), with a [`Drive`] its
//!   torque-speed envelope from the bus voltage and current limit, with [`LuGre`] friction
//!   a stuck phase, breakaway at the static torque and a Stribeck curve ([`friction`]).
//! * [`StateSpaceLaw`]: `kind = "statespace"`, a linear law designed elsewhere.
//! * [`CallbackLaw`]: a sampled law whose commands a [`LawFunction`] computes
//!   (`kind = "python"`: the Python bindings fill it).
//! * [`SensedLaw`]: any law behind delaying, quantising sensors (`control.delay`,
//!   `control.quantisation`).
//! * [`VibrationController`]: the voltages of piezoelectric patches on the links from their
//!   sensors: [`StrainRate`] (`kind = "strain_rate"`) and [`ModalVelocity`]
//!   (`kind = "modal_velocity"`).

mod actuator;
mod callback;
mod controller;
pub mod drive;
mod error;
pub mod friction;
mod pid;
mod sensed;
mod statespace;
mod vibration;

pub use actuator::{
    Actuator, ActuatorOutput, ActuatorSignal, IdealForce, MAX_ACTUATOR_SIGNALS, MOTOR_CURRENT,
    MOTOR_DRIVE_SIGNALS, MOTOR_SIGNALS, MOTOR_SPEED, MOTOR_TORQUE, MOTOR_VOLTAGE, MotorBallScrew,
    MotorRatings, Screw,
};
pub use callback::{CallbackLaw, LawFunction};
pub use controller::{ControlInput, Controller, SliderState};
pub use drive::{Drive, Winding, WindingOutput};
pub use error::ControlError;
pub use friction::LuGre;
pub use pid::Pid;
pub use sensed::{MAX_DELAY_PERIODS, MAX_PADE_ORDER, SensedLaw, Sensors};
pub use statespace::{MAX_MEASUREMENTS, SliderSignal, StateSpaceLaw, StateSpaceMatrices};
pub use vibration::{ModalVelocity, StrainRate, VibrationController, VibrationInput};
