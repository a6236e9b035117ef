//! Rigid-body kinematics of the 3-PRR planar parallel manipulator (flexprr).
//!
//! - [`Geometry`]: any 3-PRR (per leg a [`Guide`], a platform attachment point, a link
//!   length and a [`Branch`]), with [`Geometry::radial`] for the paper's layout
//!   (model.md section 1).
//! - Inverse kinematics in closed form, allocation-free:
//!   [`Geometry::inverse_kinematics`] (checked against travel and singularity
//!   [`Thresholds`]), [`Geometry::inverse_kinematics_unchecked`], [`Geometry::inverse_position`];
//!   in place and without the link angles (no `atan2`, for right-hand sides):
//!   [`Geometry::inverse_kinematics_unchecked_into`], [`Geometry::inverse_kinematics_into`]
//!   filling a [`MachineKinematics`].
//! - Forward kinematics by Newton on the closure: [`Geometry::forward_kinematics`],
//!   [`Geometry::forward_kinematics_with_lengths`] (link lengths overridden, e.g. `l - delta`),
//!   [`Geometry::forward_motion`] (rates by implicit differentiation), [`Geometry::closure`].
//! - Velocity Jacobians and singularity measures: [`Geometry::velocity_jacobians`],
//!   [`Geometry::singularity`].
//! - Trajectories: the object-safe [`Trajectory`] trait, [`Circle`], [`Line`],
//!   [`PointToPoint`] with a rest-to-rest [`Profile`], [`WaypointSpline`]; and
//!   [`validate_trajectory`].
//! - Geometric paths `p(s)` with three derivatives ([`Path`]: [`CirclePath`], [`SegmentPath`],
//!   [`SplinePath`], as data [`GeometricPath`]); a base path with a designed orientation
//!   ([`OrientedPath`]: `phi(s)` a constant, a cubic B-spline or a Fourier series, replacing or
//!   correcting the base path's); and the planned motion along one
//!   ([`PlannedTrajectory`]: a path, a piecewise-quadratic [`Timing`], input-shaper
//!   [`Impulse`]s and a smoothing window; serialisable as [`PlannedData`]).
//!
//! Conventions, equations and thresholds are in the workspace's `docs/kinematics.md`.
//!
//! ```
//! use flexprr_kinematics::{validate_trajectory, Circle, Geometry, Pose};
//!
//! let geometry = Geometry::paper();
//! let circle = Circle::paper(20.0).unwrap();
//! let report = validate_trajectory(&geometry, &circle, 0.0, 0.05, 501).unwrap();
//! assert!(report.min_travel_margin > 0.0);
//! // The home pose is type-II singular: the three links point at the platform centre.
//! assert!(geometry.singularity(&Pose::new(0.0, 0.0, 0.0)).unwrap().type_ii < 1e-12);
//! ```

mod error;
mod forward;
mod geometry;
mod inverse;
mod oriented;
mod path;
mod planned;
mod pose;
mod trajectory;

pub use error::{KinematicsError, SingularityKind};
pub use forward::{Closure, FORWARD_MAX_ITERATIONS, LegDrive};
pub use geometry::{Branch, Geometry, Guide, Leg, Thresholds};
pub use inverse::{
    LegKinematics, LegPosition, LegState, MachineKinematics, MachineState, SingularityMeasures,
    VelocityJacobians,
};
pub use oriented::{
    Orientation, OrientedData, OrientedPath, PhiFourier, PhiFourierData, PhiLaw, PhiSpline,
    PhiSplineData,
};
pub use path::{
    CircleData, CirclePath, GeometricPath, Path, PathPoint, SegmentData, SegmentPath, SplineData,
    SplinePath,
};
pub use planned::{Impulse, PathState, PlannedData, PlannedTrajectory, Timing, check_impulses};
pub use pose::{PlatformMotion, Pose};
pub use trajectory::{
    Circle, Line, PointToPoint, Profile, Trajectory, TrajectoryReport, WaypointSpline,
    validate_trajectory,
};
