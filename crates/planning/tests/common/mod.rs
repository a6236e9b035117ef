//! Shared fixtures: the paper's machine, its circle and the pick-and-place move.
#![allow(dead_code)]

pub mod recheck;

use flexprr_control::{MotorBallScrew, MotorRatings};
use flexprr_dynamics::{Machine, paper};
use flexprr_kinematics::{CirclePath, Pose, SegmentPath};

/// The paper's machine with one sine mode per link (the rigid planner needs no more).
pub fn machine() -> Machine {
    paper::machine(1, paper::YOUNGS_MODULUS).expect("paper machine")
}

/// The paper's circle: centre (-0.05, 0), radius 0.05 m, phi = 45 deg.
pub fn circle() -> CirclePath {
    CirclePath::new([-0.05, 0.0], 0.05, std::f64::consts::FRAC_PI_4, 0.0, false).expect("circle")
}

/// configs/pick_and_place.toml's path: (-0.08, -0.03) to (-0.02, 0.033) at phi = 30 deg.
pub fn pick_and_place() -> SegmentPath {
    let phi = 30f64.to_radians();
    SegmentPath::new(Pose::new(-0.08, -0.03, phi), Pose::new(-0.02, 0.033, phi)).expect("segment")
}

/// A servo motor through a 10 mm ball screw with viscous and Coulomb friction (illustrative
/// values of a small servo: 0.64 N m peak, 0.32 N m continuous, 100 rev/s).
pub fn motor() -> MotorBallScrew {
    MotorBallScrew {
        rotor_inertia: 1.6e-5,
        lead: 0.01,
        efficiency: 0.9,
        ratings: MotorRatings {
            peak_torque: 0.64,
            continuous_torque: 0.32,
            max_speed: 100.0,
        },
        viscous_friction: 2e-4,
        coulomb_friction: 0.01,
        coulomb_smoothing: 0.01,
        drive: None,
        friction_feedforward: false,
        screw: None,
        lugre: None,
    }
}
