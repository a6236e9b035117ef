//! Geometric paths: the pose curve `p(s) = (x, y, phi)(s)`, `s in [0, S]`, with its first
//! three derivatives in `s`, independent of any timing (docs/planning.md, "Paths").
//!
//! A timing `s(t)` turns a path into a motion: `q' = p'(s) s'`, `q'' = p'(s) s'' + p''(s) s'^2`
//! ([`PathPoint::motion`]). A time-optimal planner needs the path in this form: the slider
//! rates and the drive forces become functions of `(s'', s'^2)` that are linear
//! (Bobrow, Dubowsky & Gibson 1985; Pham & Pham 2018).
//!
//! The paths of the scene's trajectories ([`GeometricPath`]):
//! * [`CirclePath`]: a full revolution of a [`Circle`], `s` its arc length (closed);
//! * [`SegmentPath`]: the straight line in `(x, y, phi)` between two poses, `s` the arc
//!   length of the reference point, or the rotation angle (rad) when the platform only turns;
//! * [`SplinePath`]: the curve a [`WaypointSpline`] sweeps, `s` the spline's own parameter
//!   (its time, shifted to start at zero) — a monotone parameter, not the arc length, so that
//!   the path is the spline's exact geometry (the arc length of a cubic has no closed form).

use std::f64::consts::TAU;

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::error::KinematicsError;
use crate::oriented::OrientedPath;
use crate::pose::{PlatformMotion, Pose};
use crate::trajectory::{Circle, Line, PointToPoint, Trajectory, WaypointSpline, finite, invalid};

/// The pose and its first three derivatives with respect to the path parameter at one `s`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PathPoint {
    /// Path parameter (m, rad or s: [`Path::unit`]).
    pub s: f64,
    /// Pose `p(s)`.
    pub pose: Pose,
    /// `p'(s) = dp/ds`.
    pub d1: Vector3<f64>,
    /// `p''(s)`.
    pub d2: Vector3<f64>,
    /// `p'''(s)`.
    pub d3: Vector3<f64>,
}

impl PathPoint {
    /// The platform motion for the path speed `s_dot = ds/dt` and acceleration `s_ddot`:
    /// twist `p' s_dot`, its rate `p' s_ddot + p'' s_dot^2` (chain rule).
    pub fn motion(&self, s_dot: f64, s_ddot: f64) -> PlatformMotion {
        PlatformMotion {
            pose: self.pose,
            velocity: self.d1 * s_dot,
            acceleration: self.d1 * s_ddot + self.d2 * (s_dot * s_dot),
        }
    }
}

/// A geometric path `p(s)`, `s in [0, length]`.
///
/// Required: the length and the point with its derivatives. Provided: open (not closed), no
/// interior breakpoints, parameter in metres.
///
/// # Implementing
/// A quarter circle of radius `R` about the origin traversed by arc length, with the
/// orientation turning with the tangent (`phi = s / R`). The derivatives must agree with
/// central differences of the pose (error `O(h^2)`):
///
/// ```
/// use flexprr_kinematics::{Path, PathPoint, Pose};
/// use nalgebra::Vector3;
///
/// struct Quarter(f64);
///
/// impl Path for Quarter {
///     fn length(&self) -> f64 {
///         std::f64::consts::FRAC_PI_2 * self.0
///     }
///     fn point(&self, s: f64) -> PathPoint {
///         let r = self.0;
///         let s = s.clamp(0.0, self.length());
///         let (sin, cos) = (s / r).sin_cos();
///         PathPoint {
///             s,
///             pose: Pose::new(r * cos, r * sin, s / r),
///             d1: Vector3::new(-sin, cos, 1.0 / r),
///             d2: Vector3::new(-cos / r, -sin / r, 0.0),
///             d3: Vector3::new(sin / (r * r), -cos / (r * r), 0.0),
///         }
///     }
/// }
///
/// let path = Quarter(0.05);
/// let (s, h) = (0.03, 1e-6);
/// let (before, here, after) = (path.point(s - h), path.point(s), path.point(s + h));
/// let slope = (after.pose.to_vector() - before.pose.to_vector()) / (2.0 * h);
/// assert!((slope - here.d1).norm() <= 1e-6);
/// let curvature = (after.d1 - before.d1) / (2.0 * h);
/// assert!((curvature - here.d2).norm() <= 1e-5);
/// assert!(!path.is_closed() && path.breakpoints().is_empty() && path.unit() == "m");
/// ```
pub trait Path {
    /// Length `S` of the parameter range (in [`Path::unit`]).
    fn length(&self) -> f64;

    /// The pose and its derivatives at `s`. Open paths clamp `s` into `[0, S]`; closed paths
    /// wrap it modulo `S`. Must not allocate.
    fn point(&self, s: f64) -> PathPoint;

    /// Whether the path is closed (`p(S) = p(0)` with all derivatives): only closed paths can
    /// be repeated periodically.
    fn is_closed(&self) -> bool {
        false
    }

    /// Interior parameters at which `p''` or `p'''` jump (spline knots), ascending. A
    /// planner puts grid points there.
    fn breakpoints(&self) -> Vec<f64> {
        Vec::new()
    }

    /// Unit of `s`: `"m"` (arc length), `"rad"` (rotation angle) or `"s"` (a spline's time).
    fn unit(&self) -> &'static str {
        "m"
    }
}

/// One revolution of a circle at constant orientation, by arc length `s = R theta`
/// (counter-clockwise unless `clockwise`): `p = c + R (cos theta, sin theta)`,
/// `theta = theta_0 +/- s / R`, `phi = phi_0`. Closed, `S = 2 pi R`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "CircleData", into = "CircleData")]
pub struct CirclePath {
    data: CircleData,
}

/// The serialised form of a [`CirclePath`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CircleData {
    /// Centre `(x, y)` (m).
    pub centre: [f64; 2],
    /// Radius (m, > 0).
    pub radius: f64,
    /// Constant orientation (rad).
    pub phi: f64,
    /// Angle on the circle at `s = 0` (rad).
    #[serde(default)]
    pub start_angle: f64,
    /// Direction of travel.
    #[serde(default)]
    pub clockwise: bool,
}

impl TryFrom<CircleData> for CirclePath {
    type Error = KinematicsError;
    fn try_from(data: CircleData) -> Result<Self, KinematicsError> {
        Self::new(
            data.centre,
            data.radius,
            data.phi,
            data.start_angle,
            data.clockwise,
        )
    }
}

impl From<CirclePath> for CircleData {
    fn from(path: CirclePath) -> Self {
        path.data
    }
}

impl CirclePath {
    /// A checked circle path.
    ///
    /// # Errors
    /// Non-finite values, or a radius that is not positive.
    pub fn new(
        centre: [f64; 2],
        radius: f64,
        phi: f64,
        start_angle: f64,
        clockwise: bool,
    ) -> Result<Self, KinematicsError> {
        finite("circle centre x", centre[0])?;
        finite("circle centre y", centre[1])?;
        finite("circle phi", phi)?;
        finite("circle start angle", start_angle)?;
        if !(radius.is_finite() && radius > 0.0) {
            return Err(invalid(
                "circle radius",
                radius,
                "must be finite and > 0 for a path",
            ));
        }
        Ok(Self {
            data: CircleData {
                centre,
                radius,
                phi,
                start_angle,
                clockwise,
            },
        })
    }

    /// The revolution a [`Circle`] trajectory sweeps from its start angle, in its direction.
    ///
    /// # Errors
    /// A zero radius (a point is no path).
    pub fn of_circle(circle: &Circle) -> Result<Self, KinematicsError> {
        let c = circle.centre();
        Self::new(
            [c.x, c.y],
            circle.radius(),
            circle.phi(),
            circle.start_angle(),
            circle.frequency() < 0.0,
        )
    }

    /// The parameters.
    pub fn data(&self) -> &CircleData {
        &self.data
    }
}

impl Path for CirclePath {
    fn length(&self) -> f64 {
        TAU * self.data.radius
    }

    fn point(&self, s: f64) -> PathPoint {
        let c = &self.data;
        let r = c.radius;
        let s = s.rem_euclid(self.length());
        let dir = if c.clockwise { -1.0 } else { 1.0 };
        let (sin, cos) = (c.start_angle + dir * s / r).sin_cos();
        PathPoint {
            s,
            pose: Pose::new(c.centre[0] + r * cos, c.centre[1] + r * sin, c.phi),
            d1: Vector3::new(-dir * sin, dir * cos, 0.0),
            d2: Vector3::new(-cos / r, -sin / r, 0.0),
            d3: Vector3::new(dir * sin / (r * r), -dir * cos / (r * r), 0.0),
        }
    }

    fn is_closed(&self) -> bool {
        true
    }
}

/// The straight line in `(x, y, phi)` from one pose to another: `p(s) = q_0 + (q_1 - q_0) s / S`.
/// `S` is the distance the reference point travels, `|(x_1 - x_0, y_1 - y_0)|` (m); when the
/// platform only turns (`x`, `y` fixed) `S = |phi_1 - phi_0|` and `s` is the rotation angle
/// (rad). `p'' = p''' = 0`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "SegmentData", into = "SegmentData")]
pub struct SegmentPath {
    from: Pose,
    to: Pose,
    length: f64,
    rotation_only: bool,
}

/// The serialised form of a [`SegmentPath`]: the two poses `[x (m), y (m), phi (rad)]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SegmentData {
    /// Start pose `[x, y, phi]` (m, m, rad).
    pub from: [f64; 3],
    /// End pose `[x, y, phi]` (m, m, rad).
    pub to: [f64; 3],
}

impl TryFrom<SegmentData> for SegmentPath {
    type Error = KinematicsError;
    fn try_from(data: SegmentData) -> Result<Self, KinematicsError> {
        let pose = |q: [f64; 3]| Pose::new(q[0], q[1], q[2]);
        Self::new(pose(data.from), pose(data.to))
    }
}

impl From<SegmentPath> for SegmentData {
    fn from(path: SegmentPath) -> Self {
        let array = |p: Pose| [p.x, p.y, p.phi];
        Self {
            from: array(path.from),
            to: array(path.to),
        }
    }
}

impl SegmentPath {
    /// The segment from `from` to `to`.
    ///
    /// # Errors
    /// Non-finite poses, or equal poses (no path to plan).
    pub fn new(from: Pose, to: Pose) -> Result<Self, KinematicsError> {
        for (q, name) in [(&from, "segment start"), (&to, "segment end")] {
            finite(name, q.x)?;
            finite(name, q.y)?;
            finite(name, q.phi)?;
        }
        let translation = (to.x - from.x).hypot(to.y - from.y);
        let rotation = (to.phi - from.phi).abs();
        let (length, rotation_only) = if translation > 0.0 {
            (translation, false)
        } else if rotation > 0.0 {
            (rotation, true)
        } else {
            return Err(invalid(
                "segment length",
                0.0,
                "start and end pose are the same: no path",
            ));
        };
        Ok(Self {
            from,
            to,
            length,
            rotation_only,
        })
    }

    /// The path of a [`PointToPoint`] move.
    ///
    /// # Errors
    /// As [`SegmentPath::new`].
    pub fn of_move(motion: &PointToPoint) -> Result<Self, KinematicsError> {
        Self::new(motion.start(), motion.end())
    }

    /// The segment a constant-velocity [`Line`] sweeps from `t0` to `t1` (e.g. a scene's
    /// time span).
    ///
    /// # Errors
    /// `t1 <= t0` or a zero velocity (as [`SegmentPath::new`]).
    pub fn of_line(line: &Line, t0: f64, t1: f64) -> Result<Self, KinematicsError> {
        if !(t0.is_finite() && t1.is_finite() && t1 > t0) {
            return Err(invalid(
                "line span t1 - t0",
                t1 - t0,
                "must be finite and > 0",
            ));
        }
        Self::new(line.motion(t0).pose, line.motion(t1).pose)
    }

    /// Start pose.
    pub fn from(&self) -> Pose {
        self.from
    }

    /// End pose.
    pub fn to(&self) -> Pose {
        self.to
    }
}

impl Path for SegmentPath {
    fn length(&self) -> f64 {
        self.length
    }

    fn point(&self, s: f64) -> PathPoint {
        let s = s.clamp(0.0, self.length);
        let (q0, q1) = (self.from.to_vector(), self.to.to_vector());
        let d1 = (q1 - q0) / self.length;
        PathPoint {
            s,
            pose: Pose::from_vector(&(q0 + d1 * s)),
            d1,
            d2: Vector3::zeros(),
            d3: Vector3::zeros(),
        }
    }

    fn unit(&self) -> &'static str {
        if self.rotation_only { "rad" } else { "m" }
    }
}

/// The curve a [`WaypointSpline`] sweeps, `p(s) = q(t_0 + s)`, `S = t_n - t_0`: the spline's
/// own parameter (its time, in s), shifted to start at zero. The clamped spline has zero
/// slope at both ends (`p'(0) = p'(S) = 0`), which a time-optimal planner handles (the path
/// speed there is unbounded but the platform's is zero); `p'''` jumps at the interior knots
/// ([`Path::breakpoints`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "SplineData", into = "SplineData")]
pub struct SplinePath {
    spline: WaypointSpline,
    start: f64,
}

/// The serialised form of a [`SplinePath`]: the waypoints `[t (s), x (m), y (m), phi (rad)]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SplineData {
    /// Waypoints `[t, x, y, phi]`, times strictly increasing.
    pub points: Vec<[f64; 4]>,
}

impl TryFrom<SplineData> for SplinePath {
    type Error = KinematicsError;
    fn try_from(data: SplineData) -> Result<Self, KinematicsError> {
        let points: Vec<(f64, Pose)> = data
            .points
            .iter()
            .map(|p| (p[0], Pose::new(p[1], p[2], p[3])))
            .collect();
        Self::new(&WaypointSpline::new(&points)?)
    }
}

impl From<SplinePath> for SplineData {
    fn from(path: SplinePath) -> Self {
        Self {
            points: path
                .spline
                .waypoints()
                .iter()
                .map(|(t, p)| [*t, p.x, p.y, p.phi])
                .collect(),
        }
    }
}

impl SplinePath {
    /// The geometric path of `spline`.
    ///
    /// # Errors
    /// A spline whose poses are all the same (no path).
    pub fn new(spline: &WaypointSpline) -> Result<Self, KinematicsError> {
        let points = spline.waypoints();
        let first = points[0].1.to_vector();
        if points
            .iter()
            .all(|(_, p)| (p.to_vector() - first).norm() <= 0.0)
        {
            return Err(invalid(
                "waypoint poses",
                0.0,
                "all waypoints are the same pose: no path",
            ));
        }
        Ok(Self {
            spline: spline.clone(),
            start: points[0].0,
        })
    }

    /// The spline.
    pub fn spline(&self) -> &WaypointSpline {
        &self.spline
    }
}

impl Path for SplinePath {
    fn length(&self) -> f64 {
        let times = self.spline.times();
        times[times.len() - 1] - self.start
    }

    fn point(&self, s: f64) -> PathPoint {
        let s = s.clamp(0.0, self.length());
        let [q, d1, d2, d3] = self.spline.derivatives(self.start + s);
        PathPoint {
            s,
            pose: Pose::from_vector(&q),
            d1,
            d2,
            d3,
        }
    }

    fn breakpoints(&self) -> Vec<f64> {
        let times = self.spline.times();
        times[1..times.len() - 1]
            .iter()
            .map(|t| t - self.start)
            .collect()
    }

    fn unit(&self) -> &'static str {
        "s"
    }
}

/// The path of any of the scene's trajectory kinds, as data (serde: a table with `kind =
/// "circle"`, `"segment"`, `"spline"` or `"oriented"` and that kind's fields; SI units, angles
/// in rad).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum GeometricPath {
    /// [`CirclePath`].
    Circle(CirclePath),
    /// [`SegmentPath`].
    Segment(SegmentPath),
    /// [`SplinePath`].
    Spline(SplinePath),
    /// An [`OrientedPath`]: a base path with a designed orientation.
    Oriented(Box<OrientedPath>),
}

impl GeometricPath {
    fn inner(&self) -> &dyn Path {
        match self {
            GeometricPath::Circle(p) => p,
            GeometricPath::Segment(p) => p,
            GeometricPath::Spline(p) => p,
            GeometricPath::Oriented(p) => p.as_ref(),
        }
    }

    /// The path's kind as spelled in data (`circle`, `segment`, `spline`, `oriented`).
    pub fn kind(&self) -> &'static str {
        match self {
            GeometricPath::Circle(_) => "circle",
            GeometricPath::Segment(_) => "segment",
            GeometricPath::Spline(_) => "spline",
            GeometricPath::Oriented(_) => "oriented",
        }
    }
}

impl Path for GeometricPath {
    fn length(&self) -> f64 {
        self.inner().length()
    }
    fn point(&self, s: f64) -> PathPoint {
        self.inner().point(s)
    }
    fn is_closed(&self) -> bool {
        self.inner().is_closed()
    }
    fn breakpoints(&self) -> Vec<f64> {
        self.inner().breakpoints()
    }
    fn unit(&self) -> &'static str {
        self.inner().unit()
    }
}

impl<P: Path + ?Sized> Path for &P {
    fn length(&self) -> f64 {
        (**self).length()
    }
    fn point(&self, s: f64) -> PathPoint {
        (**self).point(s)
    }
    fn is_closed(&self) -> bool {
        (**self).is_closed()
    }
    fn breakpoints(&self) -> Vec<f64> {
        (**self).breakpoints()
    }
    fn unit(&self) -> &'static str {
        (**self).unit()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_derivatives(path: &dyn Path, s: f64) {
        let h = 1e-5 * path.length();
        let (a, p, b) = (path.point(s - h), path.point(s), path.point(s + h));
        let scale = 1.0 + p.d1.norm();
        let d1 = (b.pose.to_vector() - a.pose.to_vector()) / (2.0 * h);
        assert!(
            (d1 - p.d1).norm() <= 1e-6 * scale,
            "p' at {s}: {d1} vs {}",
            p.d1
        );
        let d2 = (b.d1 - a.d1) / (2.0 * h);
        assert!(
            (d2 - p.d2).norm() <= 1e-5 * (1.0 + p.d2.norm()),
            "p'' at {s}"
        );
        let d3 = (b.d2 - a.d2) / (2.0 * h);
        assert!(
            (d3 - p.d3).norm() <= 1e-5 * (1.0 + p.d3.norm()),
            "p''' at {s}"
        );
    }

    #[test]
    fn circle_derivatives_agree_with_differences_and_close_the_loop() {
        for clockwise in [false, true] {
            let path = CirclePath::new([-0.05, 0.0], 0.05, 0.7, 0.3, clockwise).unwrap();
            for k in 1..10 {
                check_derivatives(&path, path.length() * k as f64 / 10.0);
            }
            let (a, b) = (path.point(0.0), path.point(path.length()));
            assert!((a.pose.to_vector() - b.pose.to_vector()).norm() <= 1e-15);
            // Unit speed: s is the arc length.
            assert!((path.point(0.1).d1.norm() - 1.0).abs() <= 1e-15);
        }
    }

    #[test]
    fn circle_path_follows_the_circle_trajectory() {
        let circle = Circle::new(nalgebra::Point2::new(0.01, -0.02), 0.04, -3.0, 0.2, 0.5).unwrap();
        let path = CirclePath::of_circle(&circle).unwrap();
        // The trajectory at time t is the path at s = R |omega| t.
        for t in [0.0, 0.03, 0.11, 0.2] {
            let s = 0.04 * TAU * 3.0 * t;
            let q = circle.motion(t);
            let p = path.point(s);
            assert!((q.pose.to_vector() - p.pose.to_vector()).norm() <= 1e-14);
            let speed = 0.04 * TAU * 3.0;
            assert!((q.velocity - p.d1 * speed).norm() <= 1e-12);
            assert!((q.acceleration - p.motion(speed, 0.0).acceleration).norm() <= 1e-10);
        }
    }

    #[test]
    fn segment_is_parameterised_by_distance_or_by_rotation() {
        let a = Pose::new(-0.08, -0.03, 0.5);
        let b = Pose::new(-0.02, 0.033, 0.2);
        let path = SegmentPath::new(a, b).unwrap();
        assert!((path.length() - (0.06f64).hypot(0.063)).abs() <= 1e-15);
        assert_eq!(path.unit(), "m");
        let end = path.point(path.length()).pose;
        assert!((end.to_vector() - b.to_vector()).norm() <= 1e-15);
        let turn = SegmentPath::new(a, Pose::new(a.x, a.y, 1.5)).unwrap();
        assert_eq!(turn.unit(), "rad");
        assert!((turn.length() - 1.0).abs() <= 1e-15);
        assert!((turn.point(0.3).d1 - Vector3::new(0.0, 0.0, 1.0)).norm() <= 1e-15);
        assert!(SegmentPath::new(a, a).is_err());
    }

    #[test]
    fn spline_path_is_the_spline_and_its_derivatives() {
        let points = [
            (0.5, Pose::new(-0.08, -0.03, 0.5)),
            (0.6, Pose::new(-0.05, 0.0, 0.6)),
            (0.75, Pose::new(-0.02, 0.03, 0.4)),
        ];
        let spline = WaypointSpline::new(&points).unwrap();
        let path = SplinePath::new(&spline).unwrap();
        assert!((path.length() - 0.25).abs() <= 1e-15);
        assert_eq!(path.breakpoints().len(), 1);
        assert!((path.breakpoints()[0] - 0.1).abs() <= 1e-15);
        for s in [0.03, 0.07, 0.13, 0.2] {
            check_derivatives(&path, s);
            let q = spline.motion(0.5 + s);
            let p = path.point(s);
            assert!((q.pose.to_vector() - p.pose.to_vector()).norm() <= 1e-15);
            assert!((q.velocity - p.d1).norm() <= 1e-13);
            assert!((q.acceleration - p.d2).norm() <= 1e-10);
        }
        // Zero slope at both ends (the clamped spline).
        assert!(path.point(0.0).d1.norm() <= 1e-15);
        assert!(path.point(path.length()).d1.norm() <= 1e-12);
    }

    #[test]
    fn paths_round_trip_through_serde() {
        let spline = WaypointSpline::new(&[
            (0.0, Pose::new(0.0, 0.01, 0.0)),
            (1.0, Pose::new(0.02, 0.01, 0.1)),
        ])
        .unwrap();
        let paths = [
            GeometricPath::Circle(CirclePath::new([0.0, 0.0], 0.05, 0.1, 0.0, true).unwrap()),
            GeometricPath::Segment(
                SegmentPath::new(Pose::new(0.0, 0.0, 0.0), Pose::new(0.01, 0.0, 0.0)).unwrap(),
            ),
            GeometricPath::Spline(SplinePath::new(&spline).unwrap()),
        ];
        for path in paths {
            let text = serde_json::to_string(&path).unwrap();
            let back: GeometricPath = serde_json::from_str(&text).unwrap();
            assert_eq!(back, path, "{text}");
        }
        let bad = r#"{"kind": "segment", "from": [0, 0, 0], "to": [0, 0, 0]}"#;
        let error = serde_json::from_str::<GeometricPath>(bad).unwrap_err();
        assert!(error.to_string().contains("are the same"), "{error}");
        let unknown = r#"{"kind": "circle", "centre": [0, 0], "radius": 0.1, "phi": 0,
            "start_angle": 0, "speed": 2}"#;
        assert!(serde_json::from_str::<GeometricPath>(unknown).is_err());
    }
}
