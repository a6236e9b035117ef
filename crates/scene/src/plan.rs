//! `[plan]`, the settings of `flexprr plan` (docs/planning.md), checked at their keys; the
//! path a scene's `[trajectory]` sweeps (what the planner re-times); and the `planned`
//! trajectory kind that a planned scene runs.

use std::sync::Arc;

use flexprr_control::{MotorBallScrew, MotorRatings};
use flexprr_dynamics::Machine;
use flexprr_kinematics::{
    Circle, CirclePath, GeometricPath, KinematicsError, Line, Path as _, PlannedData,
    PlannedTrajectory, PointToPoint, Pose, Profile, SegmentPath, SplinePath, Trajectory,
    WaypointSpline,
};
use flexprr_planning::{Boundary, PlanningError};

use crate::error::ScenarioError;
use crate::scene::Checker;
use crate::schema::{ActuatorsConfig, ProfileChoice, SceneFile, TrajectoryConfig};

/// The geometric path that the scene's trajectory sweeps over the span `[t0, t1]`
/// (docs/planning.md, "Paths"): one revolution of a circle, the segment of a point-to-point
/// move or of a line over the span, the curve of a waypoint spline, the path of a planned
/// motion.
///
/// # Errors
/// The trajectory's own parameters (already checked when the scene was built).
pub fn path_of(
    config: &TrajectoryConfig,
    t0: f64,
    t1: f64,
) -> Result<GeometricPath, KinematicsError> {
    let pose = |v: &[f64; 3]| Pose::new(v[0], v[1], v[2].to_radians());
    Ok(match config {
        TrajectoryConfig::Circle {
            centre,
            radius,
            frequency,
            phi_deg,
            start_angle_deg,
        } => GeometricPath::Circle(CirclePath::of_circle(&Circle::new(
            nalgebra::Point2::new(centre[0], centre[1]),
            *radius,
            *frequency,
            phi_deg.to_radians(),
            start_angle_deg.to_radians(),
        )?)?),
        TrajectoryConfig::Line { from, velocity } => {
            let v = nalgebra::Vector3::new(velocity[0], velocity[1], velocity[2].to_radians());
            let line = Line::new(pose(from), v, 0.0)?;
            GeometricPath::Segment(SegmentPath::of_line(&line, t0, t1)?)
        }
        TrajectoryConfig::PointToPoint {
            from,
            to,
            start,
            duration,
            profile,
        } => GeometricPath::Segment(SegmentPath::of_move(&PointToPoint::new(
            pose(from),
            pose(to),
            *start,
            *duration,
            profile_of(*profile),
        )?)?),
        TrajectoryConfig::Waypoints { points } => {
            let points: Vec<(f64, Pose)> = points
                .iter()
                .map(|p| (p[0], pose(&[p[1], p[2], p[3]])))
                .collect();
            GeometricPath::Spline(SplinePath::new(&WaypointSpline::new(&points)?)?)
        }
        TrajectoryConfig::Planned(data) => data.path.clone(),
    })
}

/// The motion law of a point-to-point move.
fn profile_of(choice: ProfileChoice) -> Profile {
    match choice {
        ProfileChoice::Quintic => Profile::Quintic,
        ProfileChoice::Cycloidal => Profile::Cycloidal,
    }
}

/// The scene's motor and ball screw (`[actuators] kind = "motor_ballscrew"`), whose ratings
/// `[plan]` applies; `None` for any other actuator or none.
pub fn motor_of(file: &SceneFile) -> Option<MotorBallScrew> {
    match file.actuators.as_ref()? {
        ActuatorsConfig::Force {} => None,
        ActuatorsConfig::MotorBallscrew {
            rotor_inertia,
            lead,
            efficiency,
            peak_torque,
            continuous_torque,
            max_speed,
            viscous_friction,
            coulomb_friction,
            coulomb_smoothing,
        } => Some(MotorBallScrew {
            rotor_inertia: *rotor_inertia,
            lead: *lead,
            efficiency: *efficiency,
            ratings: MotorRatings {
                peak_torque: *peak_torque,
                continuous_torque: *continuous_torque,
                max_speed: *max_speed,
            },
            viscous_friction: *viscous_friction,
            coulomb_friction: *coulomb_friction,
            coulomb_smoothing: *coulomb_smoothing,
        }),
    }
}

/// A `planned` trajectory: the data's own checks, named by the field (`s_dot[12]`); a
/// periodic one lists its breakpoints up to `end`.
pub(crate) fn planned_trajectory(
    c: &Checker<'_>,
    data: &PlannedData,
    end: f64,
) -> Result<Arc<dyn Trajectory + Send + Sync>, ScenarioError> {
    let planned = PlannedTrajectory::try_from(data.clone())
        .map_err(|e| c.error("trajectory", format!("invalid planned motion: {e}")))?;
    Ok(Arc::new(planned.with_horizon(end)))
}

/// `[plan]`: every value in its range (the key named), a boundary that fits the path, and at
/// least one limit (a `[plan]` limit or the scene's motor).
pub(crate) fn check_plan(
    c: &Checker<'_>,
    raw: &SceneFile,
    machine: &Machine,
    span: (f64, f64),
) -> Result<(), ScenarioError> {
    let Some(spec) = &raw.plan else {
        return Ok(());
    };
    let at_key = |e: PlanningError| match e {
        PlanningError::InvalidSpec {
            key: "limits",
            rule,
            ..
        } => c.error("plan", format!("no limit bounds the motion: {rule}")),
        PlanningError::InvalidSpec { key, value, rule } => {
            c.value_error(&format!("plan.{key}"), format!("{value}: {rule}"))
        }
        other => c.error("plan", other.to_string()),
    };
    spec.validate().map_err(at_key)?;
    spec.constraints(machine, motor_of(raw).as_ref())
        .map_err(at_key)?;
    let path = path_of(&raw.trajectory, span.0, span.1)
        .map_err(|e| c.error("trajectory", e.to_string()))?;
    if spec.boundary == Boundary::Periodic && !path.is_closed() {
        return Err(c.value_error(
            "plan.boundary",
            format!(
                "\"periodic\" needs a closed path (a circle), and this trajectory's path is an \
                 open {}: use boundary = \"rest_to_rest\"",
                path.kind()
            ),
        ));
    }
    Ok(())
}
