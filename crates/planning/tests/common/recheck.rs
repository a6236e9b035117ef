//! The independent re-check of a planned motion: run as a trajectory through the layers below
//! the planner (closed-form inverse kinematics, rigid inverse dynamics, the actuator's own
//! torque model, the joint-reaction axial force and Euler's load), none of it through the
//! planner's path form.

use flexprr_control::{Actuator, MotorBallScrew};
use flexprr_dynamics::{
    AxialForceModel, AxialInput, JointReactionAxialForce, JointReactions, Machine, end_forces,
    inverse_dynamics,
};
use flexprr_kinematics::{MachineState, Path, PlannedTrajectory, Trajectory};
use flexprr_planning::Plan;

/// Limits as the independent check sees them.
#[derive(Debug, Default, Clone, Copy)]
pub struct Limits {
    pub speed: Option<f64>,
    pub acceleration: Option<f64>,
    pub force: Option<f64>,
    pub motor: Option<MotorBallScrew>,
    pub buckling: Option<f64>,
    pub jerk: Option<f64>,
    pub rms: Option<f64>,
}

/// Largest use of each limit over `samples` instants of the motion (and the RMS torque).
/// The lowest axial force (tension positive, N) anywhere along link `i` of the machine in
/// `state` under `reactions`, from `model`: its two ends and 49 interior points (a fine scan,
/// not only the ends).
pub fn lowest_axial_force(
    machine: &Machine,
    state: &MachineState,
    reactions: &JointReactions,
    i: usize,
    model: &dyn AxialForceModel,
) -> f64 {
    let load = model.load(&AxialInput {
        leg: &state.legs[i].kinematics,
        guide_direction: machine.geometry.legs[i].guide.direction.into_inner(),
        link: &machine.links[i],
        reactions: Some(reactions),
        index: i,
    });
    let length = machine.links[i].length();
    let (p0, pl) = end_forces(&load, length);
    (1..50)
        .map(|j| load.at(length * j as f64 / 50.0))
        .fold(p0.min(pl), f64::min)
}

pub fn recheck(
    machine: &Machine,
    trajectory: &dyn Trajectory,
    span: (f64, f64),
    samples: usize,
    limits: &Limits,
) -> (f64, String) {
    let euler = flexprr_testkit::paper::euler_load();
    let mut worst = (0.0f64, String::new());
    let mut note = |usage: f64, what: &str, t: f64| {
        if usage > worst.0 {
            worst = (usage, format!("{what} at t = {t}"));
        }
    };
    let mut torque_squares = [0.0; 3];
    let dt = (span.1 - span.0) / samples as f64;
    for k in 0..=samples {
        let t = span.0 + dt * k as f64;
        let motion = trajectory.motion(t);
        let state = machine.geometry.inverse_kinematics(&motion).unwrap();
        let reactions = inverse_dynamics(machine, &state, None, t).unwrap();
        for (i, squares) in torque_squares.iter_mut().enumerate() {
            let leg = &state.legs[i];
            let force = reactions.driving_force[i];
            if let Some(v) = limits.speed {
                note(leg.rho_dot.abs() / v, "slider speed", t);
            }
            if let Some(a) = limits.acceleration {
                note(leg.rho_ddot.abs() / a, "slider acceleration", t);
            }
            if let Some(f) = limits.force {
                note(force.abs() / f, "slider force", t);
            }
            if let Some(motor) = limits.motor {
                let actuator_force = force + motor.reflected_mass() * leg.rho_ddot;
                let (torque, speed) = motor.required(actuator_force, leg.rho_dot).unwrap();
                note(torque.abs() / motor.ratings.peak_torque, "motor torque", t);
                note(speed.abs() / motor.ratings.max_speed, "motor speed", t);
                if k < samples {
                    *squares += torque * torque * dt;
                }
            }
            if let Some(margin) = limits.buckling {
                let lowest =
                    lowest_axial_force(machine, &state, &reactions, i, &JointReactionAxialForce);
                note(-lowest / (margin * euler), "buckling", t);
            }
            if let Some(j) = limits.jerk {
                let h = 1e-7;
                let ahead = machine
                    .geometry
                    .inverse_kinematics(&trajectory.motion(t + h))
                    .unwrap();
                let behind = machine
                    .geometry
                    .inverse_kinematics(&trajectory.motion(t - h))
                    .unwrap();
                let jerk = (ahead.legs[i].rho_ddot - behind.legs[i].rho_ddot) / (2.0 * h);
                note(jerk.abs() / j, "slider jerk", t);
            }
        }
    }
    if let Some(limit) = limits.rms {
        for q in torque_squares {
            note((q / (span.1 - span.0)).sqrt() / limit, "RMS torque", span.1);
        }
    }
    worst
}

pub fn trajectory_of<'p>(plan: &Plan, path: &'p dyn Path) -> PlannedTrajectory<&'p dyn Path> {
    plan.trajectory(path, 0.0).unwrap()
}

/// Checks `plan` at ten times its grid resolution (in time) and returns the worst use.
pub fn ten_times_finer(machine: &Machine, plan: &Plan, path: &dyn Path, limits: &Limits) -> f64 {
    let trajectory = trajectory_of(plan, path);
    let samples = 10 * plan.grid_points;
    let (worst, what) = recheck(machine, &trajectory, (0.0, plan.duration), samples, limits);
    println!(
        "worst use {worst:.9} ({what}), duration {:.6} s",
        plan.duration
    );
    assert!(worst <= 1.001, "{what}: {worst}");
    worst
}
