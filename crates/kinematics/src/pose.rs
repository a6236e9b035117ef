//! Platform pose and its time derivatives.

use nalgebra::{Point2, Vector2, Vector3};

use crate::error::KinematicsError;

/// Platform pose in the fixed frame: position of the platform reference point and orientation.
///
/// `phi` (rad) is measured counter-clockwise from the platform frame's home orientation,
/// so a platform point with platform-frame coordinates `c` sits at `p + R(phi) c`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pose {
    /// x coordinate of the platform reference point (m).
    pub x: f64,
    /// y coordinate of the platform reference point (m).
    pub y: f64,
    /// Orientation (rad, counter-clockwise).
    pub phi: f64,
}

impl Pose {
    /// A pose from its coordinates.
    pub const fn new(x: f64, y: f64, phi: f64) -> Self {
        Self { x, y, phi }
    }

    /// The pose as the vector `(x, y, phi)`.
    pub fn to_vector(&self) -> Vector3<f64> {
        Vector3::new(self.x, self.y, self.phi)
    }

    /// The pose from a vector `(x, y, phi)`.
    pub fn from_vector(q: &Vector3<f64>) -> Self {
        Self::new(q.x, q.y, q.z)
    }

    /// Position of the platform reference point.
    pub fn position(&self) -> Point2<f64> {
        Point2::new(self.x, self.y)
    }

    /// `true` when all three coordinates are finite.
    pub fn is_finite(&self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.phi.is_finite()
    }

    /// Maps a platform-frame vector to the fixed frame: `R(phi) c`.
    pub fn rotate(&self, c: &Vector2<f64>) -> Vector2<f64> {
        let (sin, cos) = self.phi.sin_cos();
        Vector2::new(cos * c.x - sin * c.y, sin * c.x + cos * c.y)
    }

    pub(crate) fn check_finite(&self) -> Result<(), KinematicsError> {
        check_finite("pose.x", self.x)?;
        check_finite("pose.y", self.y)?;
        check_finite("pose.phi", self.phi)
    }
}

/// Platform pose with its first and second time derivatives.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PlatformMotion {
    /// Pose `(x, y, phi)`.
    pub pose: Pose,
    /// Twist `(x', y', phi')` in m/s and rad/s (velocity of the platform reference point).
    pub velocity: Vector3<f64>,
    /// `(x'', y'', phi'')` in m/s^2 and rad/s^2.
    pub acceleration: Vector3<f64>,
}

impl PlatformMotion {
    /// The platform at rest in `pose`.
    pub fn at_rest(pose: Pose) -> Self {
        Self {
            pose,
            velocity: Vector3::zeros(),
            acceleration: Vector3::zeros(),
        }
    }

    pub(crate) fn check_finite(&self) -> Result<(), KinematicsError> {
        self.pose.check_finite()?;
        for k in 0..3 {
            check_finite("platform velocity", self.velocity[k])?;
            check_finite("platform acceleration", self.acceleration[k])?;
        }
        Ok(())
    }
}

#[inline]
pub(crate) fn check_finite(quantity: &'static str, value: f64) -> Result<(), KinematicsError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(KinematicsError::NonFinite { quantity, value })
    }
}
