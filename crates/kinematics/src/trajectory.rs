//! Platform trajectories: pose, velocity and acceleration as functions of time, and a
//! sampling validator that checks a trajectory against a geometry.

use std::f64::consts::{PI, TAU};

use nalgebra::{Point2, Vector3};

use crate::error::KinematicsError;
use crate::geometry::Geometry;
use crate::inverse::measures_of;
use crate::pose::{PlatformMotion, Pose};

/// A prescribed platform motion. Object-safe: scenes hold `Box<dyn Trajectory + Send + Sync>`.
///
/// # Implementing
/// A platform drifting at a constant velocity `v` along `x` from `x0`, with no rotation. The
/// inverse kinematics must then give slider rates `rho'` equal to the time derivative of the
/// slider positions `rho(t)`, here checked by a central difference (error `O(h^2)`):
///
/// ```
/// use flexprr_kinematics::{Geometry, PlatformMotion, Pose, Trajectory};
/// use nalgebra::Vector3;
///
/// struct Drift {
///     start: Pose,
///     speed: f64,
/// }
///
/// impl Trajectory for Drift {
///     fn motion(&self, t: f64) -> PlatformMotion {
///         let pose = Pose::new(self.start.x + self.speed * t, self.start.y, self.start.phi);
///         PlatformMotion {
///             pose,
///             velocity: Vector3::new(self.speed, 0.0, 0.0),
///             acceleration: Vector3::zeros(),
///         }
///     }
/// }
///
/// let drift = Drift { start: Pose::new(-0.05, 0.0, std::f64::consts::FRAC_PI_4), speed: 0.1 };
/// let geometry = Geometry::paper();
/// let (t, h) = (0.1, 1e-5);
/// let now = geometry.inverse_kinematics(&drift.motion(t)).unwrap();
/// let after = geometry.inverse_kinematics(&drift.motion(t + h)).unwrap();
/// let before = geometry.inverse_kinematics(&drift.motion(t - h)).unwrap();
/// for i in 0..3 {
///     let difference = (after.legs[i].rho - before.legs[i].rho) / (2.0 * h);
///     assert!((now.legs[i].rho_dot - difference).abs() <= 1e-6 * (1.0 + difference.abs()));
/// }
/// assert!(drift.breakpoints().is_empty() && drift.duration().is_none());
/// ```
pub trait Trajectory {
    /// Pose, twist and its derivative at time `t` (s).
    fn motion(&self, t: f64) -> PlatformMotion;

    /// Time (s, on the same clock as `t`) at which the motion ends and the platform rests,
    /// when it has a natural end; `None` for periodic or unbounded motions.
    fn duration(&self) -> Option<f64> {
        None
    }

    /// Times (s) at which a derivative of the motion up to the third jumps: the start and
    /// end of a move, the knots of a spline. The forcing of the modal equations follows the
    /// acceleration, so an integrator must stop and restart at each (an error estimate
    /// cannot see a motion that has not started yet). Empty for smooth motions.
    fn breakpoints(&self) -> Vec<f64> {
        Vec::new()
    }
}

pub(crate) fn invalid(quantity: &'static str, value: f64, reason: &'static str) -> KinematicsError {
    KinematicsError::InvalidTrajectory {
        quantity,
        value,
        reason,
    }
}

pub(crate) fn finite(quantity: &'static str, value: f64) -> Result<(), KinematicsError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(invalid(quantity, value, "must be finite"))
    }
}

fn finite_pose(pose: &Pose) -> Result<(), KinematicsError> {
    finite("pose.x", pose.x)?;
    finite("pose.y", pose.y)?;
    finite("pose.phi", pose.phi)
}

/// The paper's trajectory: the platform reference point runs around a circle at constant
/// frequency with constant orientation,
/// `x = x_c + R cos(2 pi f t + theta_0)`, `y = y_c + R sin(2 pi f t + theta_0)`, `phi = phi_0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Circle {
    centre: Point2<f64>,
    radius: f64,
    frequency: f64,
    phi: f64,
    start_angle: f64,
}

impl Circle {
    /// A circle with centre (m), radius (m, `>= 0`), frequency (Hz, any sign: negative runs
    /// clockwise), constant orientation `phi` (rad) and start angle `theta_0` (rad).
    pub fn new(
        centre: Point2<f64>,
        radius: f64,
        frequency: f64,
        phi: f64,
        start_angle: f64,
    ) -> Result<Self, KinematicsError> {
        finite("circle centre x", centre.x)?;
        finite("circle centre y", centre.y)?;
        finite("circle frequency", frequency)?;
        finite("circle phi", phi)?;
        finite("circle start angle", start_angle)?;
        if !(radius.is_finite() && radius >= 0.0) {
            return Err(invalid("circle radius", radius, "must be finite and >= 0"));
        }
        Ok(Self {
            centre,
            radius,
            frequency,
            phi,
            start_angle,
        })
    }

    /// The paper's circle at frequency `f` (Hz): `x = 0.05 cos(2 pi f t) - 0.05`,
    /// `y = 0.05 sin(2 pi f t)`, `phi = 45 deg` (model.md section 2).
    pub fn paper(frequency: f64) -> Result<Self, KinematicsError> {
        Self::new(Point2::new(-0.05, 0.0), 0.05, frequency, PI / 4.0, 0.0)
    }

    /// Period `1 / |f|` (s); infinite for `f = 0`.
    pub fn period(&self) -> f64 {
        1.0 / self.frequency.abs()
    }

    /// Centre (m).
    pub fn centre(&self) -> Point2<f64> {
        self.centre
    }

    /// Radius (m).
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// Frequency (Hz; negative runs clockwise).
    pub fn frequency(&self) -> f64 {
        self.frequency
    }

    /// Constant orientation `phi` (rad).
    pub fn phi(&self) -> f64 {
        self.phi
    }

    /// Angle on the circle at `t = 0` (rad).
    pub fn start_angle(&self) -> f64 {
        self.start_angle
    }
}

impl Trajectory for Circle {
    fn motion(&self, t: f64) -> PlatformMotion {
        let omega = TAU * self.frequency;
        let (sin, cos) = (omega * t + self.start_angle).sin_cos();
        let r = self.radius;
        PlatformMotion {
            pose: Pose::new(self.centre.x + r * cos, self.centre.y + r * sin, self.phi),
            velocity: Vector3::new(-r * omega * sin, r * omega * cos, 0.0),
            acceleration: Vector3::new(-r * omega * omega * cos, -r * omega * omega * sin, 0.0),
        }
    }
}

/// Constant-velocity motion `q(t) = q_0 + v (t - t_0)` in `(x, y, phi)`: a straight line
/// traversed at constant speed while the orientation changes at a constant rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Line {
    start: Pose,
    velocity: Vector3<f64>,
    start_time: f64,
}

impl Line {
    /// Start pose at `start_time` (s) and constant twist `(x', y', phi')`.
    pub fn new(
        start: Pose,
        velocity: Vector3<f64>,
        start_time: f64,
    ) -> Result<Self, KinematicsError> {
        finite_pose(&start)?;
        for v in velocity.iter() {
            finite("line velocity", *v)?;
        }
        finite("line start time", start_time)?;
        Ok(Self {
            start,
            velocity,
            start_time,
        })
    }

    /// Pose at the start time.
    pub fn start(&self) -> Pose {
        self.start
    }

    /// Constant twist `(x', y', phi')` (m/s, rad/s).
    pub fn velocity(&self) -> Vector3<f64> {
        self.velocity
    }
}

impl Trajectory for Line {
    fn motion(&self, t: f64) -> PlatformMotion {
        PlatformMotion {
            pose: Pose::from_vector(
                &(self.start.to_vector() + self.velocity * (t - self.start_time)),
            ),
            velocity: self.velocity,
            acceleration: Vector3::zeros(),
        }
    }
}

/// Normalised rest-to-rest motion law `s(tau)`, `tau in [0, 1]`, with `s(0) = 0`, `s(1) = 1`
/// and zero velocity and acceleration at both ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Profile {
    /// `s = 10 tau^3 - 15 tau^4 + 6 tau^5` (minimum-jerk quintic; Biagiotti & Melchiorri,
    /// Trajectory Planning for Automatic Machines and Robots, sec. 2.1.7). Peak `s' = 15/8`,
    /// peak `|s''| = 10 / sqrt(3)`.
    Quintic,
    /// `s = tau - sin(2 pi tau) / (2 pi)` (cycloidal; same book, sec. 2.2.3). Peak `s' = 2`,
    /// peak `|s''| = 2 pi`.
    Cycloidal,
}

impl Profile {
    /// `(s, ds/dtau, d^2s/dtau^2)`; `tau` is clamped to `[0, 1]` (rest outside).
    pub fn evaluate(self, tau: f64) -> (f64, f64, f64) {
        if tau <= 0.0 {
            return (0.0, 0.0, 0.0);
        }
        if tau >= 1.0 {
            return (1.0, 0.0, 0.0);
        }
        match self {
            Profile::Quintic => {
                let t2 = tau * tau;
                let m = 1.0 - tau;
                (
                    t2 * tau * (10.0 - 15.0 * tau + 6.0 * t2),
                    30.0 * t2 * m * m,
                    60.0 * tau * m * (1.0 - 2.0 * tau),
                )
            }
            Profile::Cycloidal => {
                let (sin, cos) = (TAU * tau).sin_cos();
                (tau - sin / TAU, 1.0 - cos, TAU * sin)
            }
        }
    }
}

/// Rest-to-rest move from one pose to another along a straight line in `(x, y, phi)` with a
/// [`Profile`]: `q(t) = q_0 + (q_1 - q_0) s((t - t_0) / T)`. At rest before `t_0` and after
/// `t_0 + T`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointToPoint {
    start: Pose,
    end: Pose,
    start_time: f64,
    duration: f64,
    profile: Profile,
}

impl PointToPoint {
    /// A move from `start` to `end` starting at `start_time` and lasting `duration > 0` (s).
    pub fn new(
        start: Pose,
        end: Pose,
        start_time: f64,
        duration: f64,
        profile: Profile,
    ) -> Result<Self, KinematicsError> {
        finite_pose(&start)?;
        finite_pose(&end)?;
        finite("move start time", start_time)?;
        if !(duration.is_finite() && duration > 0.0) {
            return Err(invalid(
                "move duration",
                duration,
                "must be finite and positive",
            ));
        }
        Ok(Self {
            start,
            end,
            start_time,
            duration,
            profile,
        })
    }

    /// Start pose.
    pub fn start(&self) -> Pose {
        self.start
    }

    /// End pose.
    pub fn end(&self) -> Pose {
        self.end
    }
}

impl Trajectory for PointToPoint {
    fn motion(&self, t: f64) -> PlatformMotion {
        let (s, ds, dds) = self.profile.evaluate((t - self.start_time) / self.duration);
        let q0 = self.start.to_vector();
        let delta = self.end.to_vector() - q0;
        PlatformMotion {
            pose: Pose::from_vector(&(q0 + delta * s)),
            velocity: delta * (ds / self.duration),
            acceleration: delta * (dds / (self.duration * self.duration)),
        }
    }

    fn duration(&self) -> Option<f64> {
        Some(self.start_time + self.duration)
    }

    /// The start and the end of the move (the profile's higher derivatives jump there).
    fn breakpoints(&self) -> Vec<f64> {
        vec![self.start_time, self.start_time + self.duration]
    }
}

/// Piecewise-cubic path through waypoints `(t_k, pose_k)`: in each of `x`, `y` and `phi`
/// the clamped cubic spline with zero velocity at the first and last waypoint (de Boor,
/// A Practical Guide to Splines, ch. IV). Position, velocity and acceleration are
/// continuous on `[t_0, t_n]` (C2); the end accelerations are in general not zero, so the
/// acceleration jumps to zero where the path is held at rest before `t_0` and after `t_n`.
#[derive(Debug, Clone, PartialEq)]
pub struct WaypointSpline {
    times: Vec<f64>,
    values: Vec<Vector3<f64>>,
    /// Second derivatives at the knots.
    curvature: Vec<Vector3<f64>>,
}

impl WaypointSpline {
    /// A spline through `waypoints` `(t_k, pose_k)`: at least two, times finite and strictly
    /// increasing.
    pub fn new(waypoints: &[(f64, Pose)]) -> Result<Self, KinematicsError> {
        let n = waypoints.len();
        if n < 2 {
            return Err(invalid("number of waypoints", n as f64, "need at least 2"));
        }
        for (k, (t, pose)) in waypoints.iter().enumerate() {
            finite("waypoint time", *t)?;
            finite_pose(pose)?;
            if k > 0 && *t <= waypoints[k - 1].0 {
                return Err(invalid(
                    "waypoint time step",
                    *t - waypoints[k - 1].0,
                    "times must increase strictly",
                ));
            }
        }
        let times: Vec<f64> = waypoints.iter().map(|w| w.0).collect();
        let values: Vec<Vector3<f64>> = waypoints.iter().map(|w| w.1.to_vector()).collect();
        let h: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
        // Tridiagonal system for the knot second derivatives M_k (clamped, zero end slopes):
        //   2 h_0 M_0 + h_0 M_1                          = 6 (y_1 - y_0) / h_0
        //   h_{k-1} M_{k-1} + 2 (h_{k-1} + h_k) M_k + h_k M_{k+1}
        //                     = 6 ((y_{k+1} - y_k) / h_k - (y_k - y_{k-1}) / h_{k-1})
        //   h_{n-1} M_{n-1} + 2 h_{n-1} M_n              = -6 (y_n - y_{n-1}) / h_{n-1}
        let slope = |k: usize| (values[k + 1] - values[k]) / h[k];
        let mut sub = vec![0.0; n];
        let mut diag = vec![0.0; n];
        let mut sup = vec![0.0; n];
        let mut rhs = vec![Vector3::zeros(); n];
        diag[0] = 2.0 * h[0];
        sup[0] = h[0];
        rhs[0] = 6.0 * slope(0);
        for k in 1..n - 1 {
            sub[k] = h[k - 1];
            diag[k] = 2.0 * (h[k - 1] + h[k]);
            sup[k] = h[k];
            rhs[k] = 6.0 * (slope(k) - slope(k - 1));
        }
        sub[n - 1] = h[n - 2];
        diag[n - 1] = 2.0 * h[n - 2];
        rhs[n - 1] = -6.0 * slope(n - 2);
        // Thomas algorithm (the matrix is strictly diagonally dominant, no pivoting needed).
        for k in 1..n {
            let w = sub[k] / diag[k - 1];
            diag[k] -= w * sup[k - 1];
            let prev = rhs[k - 1];
            rhs[k] -= w * prev;
        }
        let mut curvature = vec![Vector3::zeros(); n];
        curvature[n - 1] = rhs[n - 1] / diag[n - 1];
        for k in (0..n - 1).rev() {
            curvature[k] = (rhs[k] - sup[k] * curvature[k + 1]) / diag[k];
        }
        Ok(Self {
            times,
            values,
            curvature,
        })
    }

    /// The knot times.
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// The waypoints `(t_k, pose_k)`.
    pub fn waypoints(&self) -> Vec<(f64, Pose)> {
        self.times
            .iter()
            .zip(&self.values)
            .map(|(t, q)| (*t, Pose::from_vector(q)))
            .collect()
    }

    /// Position and its first three derivatives in the spline's own parameter at `t`,
    /// clamped into `[t_0, t_n]`; at a knot the interval to its right (to its left at
    /// `t_n`) is used, so the one-sided third derivative is that of the next piece.
    pub(crate) fn derivatives(&self, t: f64) -> [Vector3<f64>; 4] {
        let n = self.times.len();
        let t = t.clamp(self.times[0], self.times[n - 1]);
        let k = (self.times.partition_point(|&tk| tk <= t).max(1) - 1).min(n - 2);
        let h = self.times[k + 1] - self.times[k];
        let a = self.times[k + 1] - t;
        let b = t - self.times[k];
        let (m0, m1) = (self.curvature[k], self.curvature[k + 1]);
        let c0 = self.values[k] / h - m0 * (h / 6.0);
        let c1 = self.values[k + 1] / h - m1 * (h / 6.0);
        [
            m0 * (a * a * a / (6.0 * h)) + m1 * (b * b * b / (6.0 * h)) + c0 * a + c1 * b,
            m1 * (b * b / (2.0 * h)) - m0 * (a * a / (2.0 * h)) + c1 - c0,
            m0 * (a / h) + m1 * (b / h),
            (m1 - m0) / h,
        ]
    }
}

impl Trajectory for WaypointSpline {
    fn motion(&self, t: f64) -> PlatformMotion {
        let n = self.times.len();
        if t <= self.times[0] {
            return PlatformMotion::at_rest(Pose::from_vector(&self.values[0]));
        }
        if t >= self.times[n - 1] {
            return PlatformMotion::at_rest(Pose::from_vector(&self.values[n - 1]));
        }
        let [q, velocity, acceleration, _] = self.derivatives(t);
        PlatformMotion {
            pose: Pose::from_vector(&q),
            velocity,
            acceleration,
        }
    }

    fn duration(&self) -> Option<f64> {
        Some(self.times[self.times.len() - 1])
    }

    /// Every knot: the cubic pieces join with a jump in the third derivative, and the path
    /// rests before the first knot and after the last.
    fn breakpoints(&self) -> Vec<f64> {
        self.times.clone()
    }
}

impl<T: Trajectory + ?Sized> Trajectory for Box<T> {
    fn motion(&self, t: f64) -> PlatformMotion {
        (**self).motion(t)
    }

    fn duration(&self) -> Option<f64> {
        (**self).duration()
    }

    fn breakpoints(&self) -> Vec<f64> {
        (**self).breakpoints()
    }
}

/// What [`validate_trajectory`] found over the samples (all of which passed).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrajectoryReport {
    /// Number of samples checked.
    pub samples: usize,
    /// Smallest distance of any slider from the ends of its travel (m).
    pub min_travel_margin: f64,
    /// Leg (zero-based) and time (s) of the smallest travel margin.
    pub min_travel_margin_at: (usize, f64),
    /// Range `(min, max)` of each slider position (m).
    pub rho_range: [(f64, f64); 3],
    /// Largest `|rho_i'|` per leg (m/s).
    pub max_slider_speed: [f64; 3],
    /// Largest `|rho_i''|` per leg (m/s^2).
    pub max_slider_acceleration: [f64; 3],
    /// Smallest type-I measure `|e_i.u_i|` per leg.
    pub min_type_i: [f64; 3],
    /// Smallest type-II measure.
    pub min_type_ii: f64,
    /// Time (s) of the smallest type-II measure.
    pub min_type_ii_at: f64,
}

/// Samples `trajectory` at `samples >= 2` equally spaced times on `[t0, t1]` (both ends
/// included) and runs the checked inverse kinematics ([`Geometry::inverse_kinematics`]) at
/// each. Returns the first failure wrapped in [`KinematicsError::AtTime`], otherwise the
/// margins found. Sampling cannot see an excursion narrower than the spacing: use a spacing
/// well below the shortest time scale of the motion.
pub fn validate_trajectory(
    geometry: &Geometry,
    trajectory: &dyn Trajectory,
    t0: f64,
    t1: f64,
    samples: usize,
) -> Result<TrajectoryReport, KinematicsError> {
    finite("validation start time", t0)?;
    finite("validation end time", t1)?;
    if t1 < t0 {
        return Err(invalid(
            "validation interval t1 - t0",
            t1 - t0,
            "must be >= 0",
        ));
    }
    if samples < 2 {
        return Err(invalid(
            "validation samples",
            samples as f64,
            "need at least 2",
        ));
    }
    let mut report = TrajectoryReport {
        samples,
        min_travel_margin: f64::INFINITY,
        min_travel_margin_at: (0, t0),
        rho_range: [(f64::INFINITY, f64::NEG_INFINITY); 3],
        max_slider_speed: [0.0; 3],
        max_slider_acceleration: [0.0; 3],
        min_type_i: [f64::INFINITY; 3],
        min_type_ii: f64::INFINITY,
        min_type_ii_at: t0,
    };
    for k in 0..samples {
        let t = t0 + (t1 - t0) * (k as f64) / ((samples - 1) as f64);
        let at_time = |error: KinematicsError| KinematicsError::AtTime {
            t,
            error: Box::new(error),
        };
        let motion = trajectory.motion(t);
        let state = geometry.inverse_kinematics(&motion).map_err(at_time)?;
        let positions = geometry.inverse_position(&motion.pose).map_err(at_time)?;
        let measures = measures_of(geometry, &positions);
        for (i, leg) in state.legs.iter().enumerate() {
            let margin = geometry.legs[i].guide.travel_margin(leg.rho);
            if margin < report.min_travel_margin {
                report.min_travel_margin = margin;
                report.min_travel_margin_at = (i, t);
            }
            let range = &mut report.rho_range[i];
            range.0 = range.0.min(leg.rho);
            range.1 = range.1.max(leg.rho);
            report.max_slider_speed[i] = report.max_slider_speed[i].max(leg.rho_dot.abs());
            report.max_slider_acceleration[i] =
                report.max_slider_acceleration[i].max(leg.rho_ddot.abs());
            report.min_type_i[i] = report.min_type_i[i].min(measures.type_i[i]);
        }
        if measures.type_ii < report.min_type_ii {
            report.min_type_ii = measures.type_ii;
            report.min_type_ii_at = t;
        }
    }
    Ok(report)
}
