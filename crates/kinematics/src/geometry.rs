//! Geometry of a general 3-PRR: guides, platform attachment points, link lengths, branches.

use nalgebra::{Point2, Unit, Vector2};

use crate::error::KinematicsError;

/// Assembly mode of one leg: on which side of the foot of the perpendicular from `C_i` to
/// the guide line the slider `B_i` sits.
///
/// With `d = C_i - A_i`, the closure `|d - rho u|^2 = l^2` has the two roots
/// `rho = d.u -/+ sqrt(l^2 - (d x u)^2)` (model.md section 3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Branch {
    /// `rho = d.u - sqrt(l^2 - (d x u)^2)`: the slider is behind `C_i` along `u_i`, so
    /// `e_i . u_i >= 0` (the paper's choice).
    Behind,
    /// `rho = d.u + sqrt(l^2 - (d x u)^2)`: the slider is ahead of `C_i`, `e_i . u_i <= 0`.
    Ahead,
}

impl Branch {
    /// Sign in front of the square root: `-1` for `Behind`, `+1` for `Ahead`.
    #[inline]
    pub fn sign(self) -> f64 {
        match self {
            Branch::Behind => -1.0,
            Branch::Ahead => 1.0,
        }
    }

    /// The other assembly mode.
    pub fn other(self) -> Self {
        match self {
            Branch::Behind => Branch::Ahead,
            Branch::Ahead => Branch::Behind,
        }
    }
}

/// A straight guide of a prismatic joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Guide {
    /// Guide centre `A_i` (fixed frame, m); `rho_i` is measured from here.
    pub anchor: Point2<f64>,
    /// Unit direction `u_i` of positive `rho_i`.
    pub direction: Unit<Vector2<f64>>,
    /// Travel `(min, max)` of `rho_i` (m), `min < max`.
    pub travel: (f64, f64),
}

impl Guide {
    /// Slider joint `B_i = A_i + rho u_i`.
    pub fn slider_point(&self, rho: f64) -> Point2<f64> {
        self.anchor + self.direction.into_inner() * rho
    }

    /// Signed distance inside the travel: `min(rho - min, max - rho)`; negative outside.
    pub fn travel_margin(&self, rho: f64) -> f64 {
        (rho - self.travel.0).min(self.travel.1 - rho)
    }
}

/// One P-R-R leg: guide, link and platform attachment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Leg {
    /// The guide of the actuated prismatic joint.
    pub guide: Guide,
    /// Platform joint `c_i` in the platform frame (m).
    pub attachment: Vector2<f64>,
    /// Link length `l_i` between `B_i` and `C_i` (m).
    pub link_length: f64,
    /// Assembly mode.
    pub branch: Branch,
}

/// Singularity thresholds used by the checked inverse kinematics.
///
/// A pose is rejected when `|e_i . u_i| < type_i` for some leg or when the type-II measure
/// (see [`crate::SingularityMeasures`]) is below `type_ii`. Both measures are dimensionless
/// and in `[0, 1]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Thresholds {
    /// Threshold on `|e_i . u_i| = |cos(beta_i - alpha_i)|`. Default `1e-2`
    /// (the slider rate is then at most 100 times the platform-joint speed).
    pub type_i: f64,
    /// Threshold on the normalised determinant of the direct Jacobian. Default `1e-2`.
    pub type_ii: f64,
}

impl Default for Thresholds {
    fn default() -> Self {
        Self {
            type_i: 1e-2,
            type_ii: 1e-2,
        }
    }
}

/// A 3-PRR planar parallel manipulator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geometry {
    /// The three legs.
    pub legs: [Leg; 3],
    /// Singularity thresholds for the checked inverse kinematics.
    pub thresholds: Thresholds,
}

fn invalid(
    leg: Option<usize>,
    quantity: &'static str,
    value: f64,
    reason: &'static str,
) -> KinematicsError {
    KinematicsError::InvalidGeometry {
        leg,
        quantity,
        value,
        reason,
    }
}

impl Geometry {
    /// A validated geometry with default [`Thresholds`].
    ///
    /// Checks: every coordinate finite, guide directions of unit length, link lengths
    /// positive, travel `min < max`, and the attachment points not all coincident (the
    /// platform would then be a point and its rotation uncontrolled).
    pub fn new(legs: [Leg; 3]) -> Result<Self, KinematicsError> {
        let mut max_length: f64 = 0.0;
        for (i, leg) in legs.iter().enumerate() {
            let g = &leg.guide;
            for (quantity, value) in [
                ("anchor.x", g.anchor.x),
                ("anchor.y", g.anchor.y),
                ("direction.x", g.direction.x),
                ("direction.y", g.direction.y),
                ("attachment.x", leg.attachment.x),
                ("attachment.y", leg.attachment.y),
                ("travel min", g.travel.0),
                ("travel max", g.travel.1),
            ] {
                if !value.is_finite() {
                    return Err(invalid(Some(i), quantity, value, "must be finite"));
                }
            }
            let norm = g.direction.norm();
            if (norm - 1.0).abs() > 1e-12 {
                return Err(invalid(Some(i), "|direction|", norm, "must be 1"));
            }
            if !(leg.link_length.is_finite() && leg.link_length > 0.0) {
                return Err(invalid(
                    Some(i),
                    "link length",
                    leg.link_length,
                    "must be finite and positive",
                ));
            }
            if g.travel.0 >= g.travel.1 {
                return Err(invalid(
                    Some(i),
                    "travel max - min",
                    g.travel.1 - g.travel.0,
                    "must be positive",
                ));
            }
            max_length = max_length.max(leg.link_length);
        }
        let geometry = Self {
            legs,
            thresholds: Thresholds::default(),
        };
        let radius = geometry.platform_radius();
        if radius <= 1e-12 * max_length {
            return Err(invalid(
                None,
                "platform radius",
                radius,
                "attachment points must not all coincide",
            ));
        }
        Ok(geometry)
    }

    /// The paper's radial layout (model.md section 1).
    ///
    /// Guide `i` has direction `u(alpha_i)`; with `R_p = side / sqrt(3)` the platform joints
    /// are `c_i = R_p u(alpha_i + pi)` and the guide centres `A_i = (R_p + l) u(alpha_i + pi)`,
    /// so at the home pose `(0, 0, 0)` every slider is at `rho_i = 0` and every link lies
    /// along its guide (a type-II singular pose). Travel is `[-half_travel, half_travel]`,
    /// every leg on the [`Branch::Behind`] branch. `alpha` in radians.
    pub fn radial(
        alpha: [f64; 3],
        link_length: f64,
        platform_side: f64,
        half_travel: f64,
    ) -> Result<Self, KinematicsError> {
        for (i, a) in alpha.iter().enumerate() {
            if !a.is_finite() {
                return Err(invalid(Some(i), "alpha", *a, "must be finite"));
            }
        }
        if !(platform_side.is_finite() && platform_side > 0.0) {
            return Err(invalid(
                None,
                "platform side",
                platform_side,
                "must be finite and positive",
            ));
        }
        if !(half_travel.is_finite() && half_travel > 0.0) {
            return Err(invalid(
                None,
                "half travel",
                half_travel,
                "must be finite and positive",
            ));
        }
        let platform_radius = platform_side / 3f64.sqrt();
        let leg = |a: f64| {
            let u = Vector2::new(a.cos(), a.sin());
            Leg {
                guide: Guide {
                    anchor: Point2::from(-(platform_radius + link_length) * u),
                    direction: Unit::new_normalize(u),
                    travel: (-half_travel, half_travel),
                },
                attachment: -platform_radius * u,
                link_length,
                branch: Branch::Behind,
            }
        };
        Self::new([leg(alpha[0]), leg(alpha[1]), leg(alpha[2])])
    }

    /// The paper's machine: `radial([150, 270, 30] deg, 0.2 m, 0.1 m, 0.2 m)`.
    pub fn paper() -> Self {
        Self::radial(
            [150f64.to_radians(), 270f64.to_radians(), 30f64.to_radians()],
            0.2,
            0.1,
            0.2,
        )
        .expect("the paper's geometry is valid")
    }

    /// The same geometry with other singularity thresholds (both finite and `>= 0`).
    pub fn with_thresholds(mut self, thresholds: Thresholds) -> Result<Self, KinematicsError> {
        for (quantity, value) in [
            ("type-I threshold", thresholds.type_i),
            ("type-II threshold", thresholds.type_ii),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(invalid(None, quantity, value, "must be finite and >= 0"));
            }
        }
        self.thresholds = thresholds;
        Ok(self)
    }

    /// The three link lengths `l_i`.
    pub fn link_lengths(&self) -> [f64; 3] {
        [
            self.legs[0].link_length,
            self.legs[1].link_length,
            self.legs[2].link_length,
        ]
    }

    /// Centroid of the attachment points in the platform frame.
    pub fn platform_centroid(&self) -> Vector2<f64> {
        (self.legs[0].attachment + self.legs[1].attachment + self.legs[2].attachment) / 3.0
    }

    /// Largest distance of an attachment point from their centroid (m): the length that
    /// makes the moment column of the type-II measure dimensionless.
    pub fn platform_radius(&self) -> f64 {
        let centroid = self.platform_centroid();
        self.legs
            .iter()
            .map(|leg| (leg.attachment - centroid).norm())
            .fold(0.0, f64::max)
    }
}
