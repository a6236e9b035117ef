//! Closed-form inverse kinematics of position, velocity and acceleration
//! (model.md section 3), velocity Jacobians and singularity measures.

use nalgebra::{Matrix3, Point2, Vector2, Vector3};

use crate::error::{KinematicsError, SingularityKind};
use crate::geometry::{Geometry, Leg};
use crate::pose::{PlatformMotion, Pose};

/// Position-level state of one leg.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegPosition {
    /// Slider position `rho_i` along the guide from `A_i` (m).
    pub rho: f64,
    /// Link angle `beta_i = atan2(e_i)` in `(-pi, pi]` (rad).
    pub beta: f64,
    /// Guide centre `A_i`.
    pub a: Point2<f64>,
    /// Slider joint `B_i = A_i + rho_i u_i`.
    pub b: Point2<f64>,
    /// Platform joint `C_i = p + R(phi) c_i`.
    pub c: Point2<f64>,
    /// Unit link direction `e_i = (C_i - B_i) / l_i`.
    pub e: Vector2<f64>,
    /// Link normal `n_i = (-e_y, e_x)`.
    pub n: Vector2<f64>,
    /// Attachment vector in the fixed frame, `r_i = R(phi) c_i = C_i - p`.
    pub r: Vector2<f64>,
}

/// Position, velocity and acceleration of one leg without the link angle: everything the
/// dynamics reads (the link direction `e_i` replaces `beta_i = atan2(e_i)`).
///
/// Computed in place by [`Geometry::inverse_kinematics_unchecked_into`] and
/// [`Geometry::inverse_kinematics_into`]; the angle is available on demand from
/// [`LegKinematics::beta`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LegKinematics {
    /// Slider position `rho_i` (m).
    pub rho: f64,
    /// Slider velocity `rho_i'` (m/s).
    pub rho_dot: f64,
    /// Slider acceleration `rho_i''` (m/s^2).
    pub rho_ddot: f64,
    /// Link angular velocity `beta_i'` (rad/s).
    pub beta_dot: f64,
    /// Link angular acceleration `beta_i''` (rad/s^2).
    pub beta_ddot: f64,
    /// Guide centre `A_i`.
    pub a: Point2<f64>,
    /// Slider joint `B_i`.
    pub b: Point2<f64>,
    /// Platform joint `C_i`.
    pub c: Point2<f64>,
    /// Velocity of `C_i`.
    pub c_dot: Vector2<f64>,
    /// Acceleration of `C_i`.
    pub c_ddot: Vector2<f64>,
    /// Unit link direction `e_i = (C_i - B_i) / l_i = (cos beta_i, sin beta_i)`.
    pub e: Vector2<f64>,
    /// Link normal `n_i = (-e_y, e_x)`.
    pub n: Vector2<f64>,
}

impl LegKinematics {
    /// Link angle `beta_i = atan2(e_y, e_x)` in `(-pi, pi]` (rad), computed on each call.
    #[inline]
    pub fn beta(&self) -> f64 {
        self.e.y.atan2(self.e.x)
    }
}

impl AsRef<LegKinematics> for LegKinematics {
    fn as_ref(&self) -> &LegKinematics {
        self
    }
}

/// Position, velocity and acceleration state of one leg: [`LegKinematics`] and the link
/// angle `beta_i`.
///
/// The fields of [`LegKinematics`] are read through `Deref` (`leg.rho_dot`), so a
/// `&LegState` is accepted where a `&LegKinematics` is expected.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LegState {
    /// Everything but the angle.
    pub kinematics: LegKinematics,
    /// Link angle `beta_i = atan2(e_i)` in `(-pi, pi]` (rad).
    pub beta: f64,
}

impl LegState {
    /// The state of a leg with its angle computed from the link direction.
    #[inline]
    pub fn from_kinematics(kinematics: LegKinematics) -> Self {
        Self {
            beta: kinematics.beta(),
            kinematics,
        }
    }
}

impl std::ops::Deref for LegState {
    type Target = LegKinematics;
    #[inline]
    fn deref(&self) -> &LegKinematics {
        &self.kinematics
    }
}

impl std::ops::DerefMut for LegState {
    #[inline]
    fn deref_mut(&mut self) -> &mut LegKinematics {
        &mut self.kinematics
    }
}

impl AsRef<LegKinematics> for LegState {
    fn as_ref(&self) -> &LegKinematics {
        &self.kinematics
    }
}

/// Full rigid-body state of the machine for one platform motion.
///
/// The leg type `L` is [`LegState`] (with the link angles) by default, or [`LegKinematics`]
/// (without them, see [`MachineKinematics`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MachineState<L = LegState> {
    /// The platform motion the state was computed from.
    pub motion: PlatformMotion,
    /// The three legs.
    pub legs: [L; 3],
}

/// The machine's rigid-body state without the link angles: what a right-hand side needs,
/// filled in place by [`Geometry::inverse_kinematics_unchecked_into`].
pub type MachineKinematics = MachineState<LegKinematics>;

impl MachineKinematics {
    /// The state with the link angles `beta_i = atan2(e_i)` added.
    pub fn with_angles(&self) -> MachineState {
        MachineState {
            motion: self.motion,
            legs: [
                LegState::from_kinematics(self.legs[0]),
                LegState::from_kinematics(self.legs[1]),
                LegState::from_kinematics(self.legs[2]),
            ],
        }
    }
}

/// Distance to the two kinds of singularity (small = close; both dimensionless, in `[0, 1]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SingularityMeasures {
    /// `|e_i . u_i| = |cos(beta_i - alpha_i)|` per leg: 0 at a type-I singularity of leg i
    /// (link perpendicular to its guide), 1 when the link lies along its guide.
    pub type_i: [f64; 3],
    /// `|det N|`, where row `i` of `N` is the row `(e_i, ((r_i - r_bar) x e_i) / L)` of the
    /// direct Jacobian normalised to unit length; `r_bar` is the centroid of the platform
    /// joints and `L` their largest distance from it. 0 when the link lines are concurrent or
    /// parallel (type II), 1 when the rows are mutually orthogonal. Invariant under
    /// translation, rotation and uniform scaling of the machine.
    pub type_ii: f64,
}

/// Velocity Jacobians of the closure, `direct * twist = diag(inverse) * rho'`
/// (Gosselin & Angeles 1990 form `A t = B q'`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VelocityJacobians {
    /// Direct Jacobian, row `i` = `(e_i^T, r_i x e_i)` (the link line's Plucker coordinates
    /// about the platform reference point); singular at type II.
    pub direct: Matrix3<f64>,
    /// Diagonal of the inverse Jacobian, `e_i . u_i`; zero entry at type I.
    pub inverse: Vector3<f64>,
}

impl VelocityJacobians {
    /// Slider rates `rho_i' = (direct * twist)_i / (e_i . u_i)` for a platform twist
    /// `(x', y', phi')`. Non-finite at a type-I singularity.
    pub fn slider_rates(&self, twist: &Vector3<f64>) -> Vector3<f64> {
        (self.direct * twist).component_div(&self.inverse)
    }

    /// Platform twist for given slider rates (forward velocity problem); `None` at a
    /// type-II singularity.
    pub fn platform_twist(&self, rho_dot: &Vector3<f64>) -> Option<Vector3<f64>> {
        self.direct.lu().solve(&self.inverse.component_mul(rho_dot))
    }
}

#[inline]
pub(crate) fn cross(a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    a.x * b.y - a.y * b.x
}

#[inline]
fn perp(a: &Vector2<f64>) -> Vector2<f64> {
    Vector2::new(-a.y, a.x)
}

/// Position IK of one leg without the angle (the shared core of every IK entry point).
#[derive(Debug, Clone, Copy)]
pub(crate) struct LegPoint {
    pub(crate) rho: f64,
    pub(crate) a: Point2<f64>,
    pub(crate) b: Point2<f64>,
    pub(crate) c: Point2<f64>,
    pub(crate) e: Vector2<f64>,
    pub(crate) n: Vector2<f64>,
    pub(crate) r: Vector2<f64>,
}

impl LegPoint {
    /// The public position with the angle `beta = atan2(e)`.
    #[inline]
    fn with_angle(&self) -> LegPosition {
        LegPosition {
            rho: self.rho,
            beta: self.e.y.atan2(self.e.x),
            a: self.a,
            b: self.b,
            c: self.c,
            e: self.e,
            n: self.n,
            r: self.r,
        }
    }
}

/// Position IK of one leg with the given link length: the root of the closure
/// `|C - A - rho u|^2 = l^2` on the leg's branch and the link direction
/// `e = (C - B) / l` straight from it (no angle).
#[inline]
pub(crate) fn leg_point(
    index: usize,
    leg: &Leg,
    pose: &Pose,
    sin_cos: (f64, f64),
    length: f64,
) -> Result<LegPoint, KinematicsError> {
    let (sin, cos) = sin_cos;
    let c_local = leg.attachment;
    let r = Vector2::new(
        cos * c_local.x - sin * c_local.y,
        sin * c_local.x + cos * c_local.y,
    );
    let c = Point2::new(pose.x + r.x, pose.y + r.y);
    let a = leg.guide.anchor;
    let u = leg.guide.direction.into_inner();
    let d = c - a;
    let along = d.dot(&u);
    let offset = cross(&d, &u);
    let discriminant = length * length - offset * offset;
    if discriminant < 0.0 {
        return Err(KinematicsError::Unreachable {
            leg: index,
            shortfall: offset.abs() - length,
        });
    }
    let rho = along + leg.branch.sign() * discriminant.sqrt();
    let link = d - rho * u;
    let e = link / length;
    Ok(LegPoint {
        rho,
        a,
        b: a + rho * u,
        c,
        e,
        n: perp(&e),
        r,
    })
}

/// Type-II measure from link directions and attachment vectors (see [`SingularityMeasures`]).
#[inline]
pub(crate) fn type_ii_measure(e: [Vector2<f64>; 3], r: [Vector2<f64>; 3]) -> f64 {
    let centroid = (r[0] + r[1] + r[2]) / 3.0;
    let rel = [r[0] - centroid, r[1] - centroid, r[2] - centroid];
    let radius = rel[0].norm().max(rel[1].norm()).max(rel[2].norm());
    if radius.is_nan() || radius <= 0.0 {
        return 0.0;
    }
    let mut rows = Matrix3::zeros();
    for i in 0..3 {
        let moment = cross(&rel[i], &e[i]) / radius;
        let norm = (e[i].norm_squared() + moment * moment).sqrt();
        rows[(i, 0)] = e[i].x / norm;
        rows[(i, 1)] = e[i].y / norm;
        rows[(i, 2)] = moment / norm;
    }
    rows.determinant().abs()
}

impl Geometry {
    /// Position inverse kinematics (closed form, model.md section 3):
    /// `rho_i = d_i.u_i -/+ sqrt(l_i^2 - (d_i x u_i)^2)` with `d_i = C_i - A_i`.
    ///
    /// Errors only on a non-finite pose or an unreachable leg; travel and singularities are
    /// not checked (see [`Geometry::inverse_kinematics`]).
    pub fn inverse_position(&self, pose: &Pose) -> Result<[LegPosition; 3], KinematicsError> {
        self.inverse_position_with_lengths(pose, self.link_lengths())
    }

    /// [`Geometry::inverse_position`] with link lengths overriding the geometry's
    /// (e.g. foreshortened links `l_i - delta_i`).
    pub fn inverse_position_with_lengths(
        &self,
        pose: &Pose,
        lengths: [f64; 3],
    ) -> Result<[LegPosition; 3], KinematicsError> {
        pose.check_finite()?;
        check_lengths(lengths)?;
        let sin_cos = pose.phi.sin_cos();
        Ok([
            leg_point(0, &self.legs[0], pose, sin_cos, lengths[0])?.with_angle(),
            leg_point(1, &self.legs[1], pose, sin_cos, lengths[1])?.with_angle(),
            leg_point(2, &self.legs[2], pose, sin_cos, lengths[2])?.with_angle(),
        ])
    }

    /// Inverse kinematics of position, velocity and acceleration without travel or
    /// singularity-threshold checks. Allocation-free.
    ///
    /// Differentiating `|C_i - B_i|^2 = l_i^2` once and twice (model.md section 3):
    ///
    /// ```text
    /// C' = p' + phi' J r,          C'' = p'' + phi'' J r - phi'^2 r,     J r = (-r_y, r_x)
    /// rho'  = e.C' / (e.u)
    /// beta' = (C' - rho' u).n / l
    /// rho'' = (e.C'' + l beta'^2) / (e.u)
    /// beta''= (C'' - rho'' u).n / l
    /// ```
    ///
    /// Errors on non-finite input, an unreachable leg, or an exactly type-I singular leg
    /// (the rates would be infinite): never returns NaN. The same computation as
    /// [`Geometry::inverse_kinematics_unchecked_into`], plus the link angles.
    pub fn inverse_kinematics_unchecked(
        &self,
        motion: &PlatformMotion,
    ) -> Result<MachineState, KinematicsError> {
        let mut state = MachineKinematics::default();
        self.inverse_kinematics_unchecked_into(motion, &mut state)?;
        Ok(state.with_angles())
    }

    /// [`Geometry::inverse_kinematics_unchecked`] written into `state`, without the link
    /// angles: no `atan2`, no copy of the state. The link direction comes straight from the
    /// closure, `e_i = (C_i - B_i) / l_i`; the angle, where an output needs it, is
    /// [`LegKinematics::beta`] or [`MachineKinematics::with_angles`]. Allocation-free; meant
    /// for ODE right-hand sides.
    ///
    /// # Errors
    /// As [`Geometry::inverse_kinematics_unchecked`]. On error `state` is partly
    /// overwritten and must not be used.
    ///
    /// ```
    /// use flexprr_kinematics::{Circle, Geometry, MachineKinematics, Trajectory};
    ///
    /// let geometry = Geometry::paper();
    /// let motion = Circle::paper(20.0).unwrap().motion(0.01);
    /// let mut state = MachineKinematics::default();
    /// geometry.inverse_kinematics_unchecked_into(&motion, &mut state).unwrap();
    /// let full = geometry.inverse_kinematics_unchecked(&motion).unwrap();
    /// for (lean, leg) in state.legs.iter().zip(&full.legs) {
    ///     assert_eq!(lean, &leg.kinematics);
    ///     assert!((lean.beta() - leg.beta).abs() < 1e-15);
    /// }
    /// ```
    pub fn inverse_kinematics_unchecked_into(
        &self,
        motion: &PlatformMotion,
        state: &mut MachineKinematics,
    ) -> Result<(), KinematicsError> {
        motion.check_finite()?;
        let positions = self.leg_points(&motion.pose)?;
        self.rates_into(motion, &positions, state)
    }

    /// Position IK of the three legs with the geometry's link lengths (input checked finite).
    #[inline]
    fn leg_points(&self, pose: &Pose) -> Result<[LegPoint; 3], KinematicsError> {
        let sin_cos = pose.phi.sin_cos();
        Ok([
            leg_point(0, &self.legs[0], pose, sin_cos, self.legs[0].link_length)?,
            leg_point(1, &self.legs[1], pose, sin_cos, self.legs[1].link_length)?,
            leg_point(2, &self.legs[2], pose, sin_cos, self.legs[2].link_length)?,
        ])
    }

    /// Velocity and acceleration level of the IK from the legs' positions, into `state`.
    #[inline]
    fn rates_into(
        &self,
        motion: &PlatformMotion,
        positions: &[LegPoint; 3],
        state: &mut MachineKinematics,
    ) -> Result<(), KinematicsError> {
        let v = Vector2::new(motion.velocity.x, motion.velocity.y);
        let omega = motion.velocity.z;
        let acc = Vector2::new(motion.acceleration.x, motion.acceleration.y);
        let alpha = motion.acceleration.z;
        state.motion = *motion;
        for (index, (out, pos)) in state.legs.iter_mut().zip(positions).enumerate() {
            let leg = &self.legs[index];
            let length = leg.link_length;
            let u = leg.guide.direction.into_inner();
            let jr = perp(&pos.r);
            let c_dot = v + omega * jr;
            let c_ddot = acc + alpha * jr - omega * omega * pos.r;
            let e_dot_u = pos.e.dot(&u);
            let rho_dot = pos.e.dot(&c_dot) / e_dot_u;
            let beta_dot = (c_dot - rho_dot * u).dot(&pos.n) / length;
            let rho_ddot = (pos.e.dot(&c_ddot) + length * beta_dot * beta_dot) / e_dot_u;
            let beta_ddot = (c_ddot - rho_ddot * u).dot(&pos.n) / length;
            if !(rho_ddot.is_finite() && beta_ddot.is_finite()) {
                return Err(KinematicsError::Singular {
                    kind: SingularityKind::TypeI,
                    leg: Some(index),
                    measure: e_dot_u.abs(),
                    threshold: 0.0,
                });
            }
            *out = LegKinematics {
                rho: pos.rho,
                rho_dot,
                rho_ddot,
                beta_dot,
                beta_ddot,
                a: pos.a,
                b: pos.b,
                c: pos.c,
                c_dot,
                c_ddot,
                e: pos.e,
                n: pos.n,
            };
        }
        Ok(())
    }

    /// Inverse kinematics with all checks: reachability, slider travel, type-I and type-II
    /// thresholds ([`Geometry::thresholds`]), in that order; the first failure is returned.
    /// Allocation-free. The same computation as [`Geometry::inverse_kinematics_into`], plus
    /// the link angles.
    pub fn inverse_kinematics(
        &self,
        motion: &PlatformMotion,
    ) -> Result<MachineState, KinematicsError> {
        let mut state = MachineKinematics::default();
        self.inverse_kinematics_into(motion, &mut state)?;
        Ok(state.with_angles())
    }

    /// [`Geometry::inverse_kinematics`] written into `state`, without the link angles (see
    /// [`Geometry::inverse_kinematics_unchecked_into`]). Allocation-free.
    ///
    /// # Errors
    /// As [`Geometry::inverse_kinematics`]. On error `state` is partly overwritten and must
    /// not be used.
    pub fn inverse_kinematics_into(
        &self,
        motion: &PlatformMotion,
        state: &mut MachineKinematics,
    ) -> Result<(), KinematicsError> {
        motion.check_finite()?;
        // Position level first, so that travel and singularity are reported before rates
        // that may be huge near a type-I singularity.
        let positions = self.leg_points(&motion.pose)?;
        for (i, (leg, pos)) in self.legs.iter().zip(&positions).enumerate() {
            let (min, max) = leg.guide.travel;
            if pos.rho < min || pos.rho > max {
                return Err(KinematicsError::TravelExceeded {
                    leg: i,
                    rho: pos.rho,
                    min,
                    max,
                    excess: (min - pos.rho).max(pos.rho - max),
                });
            }
        }
        let measures = measures_from(
            self,
            [positions[0].e, positions[1].e, positions[2].e],
            [positions[0].r, positions[1].r, positions[2].r],
        );
        for (i, &measure) in measures.type_i.iter().enumerate() {
            if measure < self.thresholds.type_i {
                return Err(KinematicsError::Singular {
                    kind: SingularityKind::TypeI,
                    leg: Some(i),
                    measure,
                    threshold: self.thresholds.type_i,
                });
            }
        }
        if measures.type_ii < self.thresholds.type_ii {
            return Err(KinematicsError::Singular {
                kind: SingularityKind::TypeII,
                leg: None,
                measure: measures.type_ii,
                threshold: self.thresholds.type_ii,
            });
        }
        self.rates_into(motion, &positions, state)
    }

    /// Singularity measures at a pose (errors only if the pose is unreachable or not finite).
    pub fn singularity(&self, pose: &Pose) -> Result<SingularityMeasures, KinematicsError> {
        let legs = self.inverse_position(pose)?;
        Ok(measures_of(self, &legs))
    }

    /// Velocity Jacobians at a pose (errors only if the pose is unreachable or not finite).
    pub fn velocity_jacobians(&self, pose: &Pose) -> Result<VelocityJacobians, KinematicsError> {
        let legs = self.inverse_position(pose)?;
        let mut direct = Matrix3::zeros();
        let mut inverse = Vector3::zeros();
        for i in 0..3 {
            let p = &legs[i];
            direct[(i, 0)] = p.e.x;
            direct[(i, 1)] = p.e.y;
            direct[(i, 2)] = cross(&p.r, &p.e);
            inverse[i] = p.e.dot(&self.legs[i].guide.direction);
        }
        Ok(VelocityJacobians { direct, inverse })
    }
}

/// Singularity measures from already computed leg positions.
pub(crate) fn measures_of(geometry: &Geometry, legs: &[LegPosition; 3]) -> SingularityMeasures {
    measures_from(
        geometry,
        [legs[0].e, legs[1].e, legs[2].e],
        [legs[0].r, legs[1].r, legs[2].r],
    )
}

/// Singularity measures from the link directions `e_i` and attachment vectors `r_i`.
fn measures_from(
    geometry: &Geometry,
    e: [Vector2<f64>; 3],
    r: [Vector2<f64>; 3],
) -> SingularityMeasures {
    let mut type_i = [0.0; 3];
    for i in 0..3 {
        type_i[i] = e[i].dot(&geometry.legs[i].guide.direction).abs();
    }
    SingularityMeasures {
        type_i,
        type_ii: type_ii_measure(e, r),
    }
}

pub(crate) fn check_lengths(lengths: [f64; 3]) -> Result<(), KinematicsError> {
    for (i, l) in lengths.iter().enumerate() {
        if !(l.is_finite() && *l > 0.0) {
            return Err(KinematicsError::InvalidGeometry {
                leg: Some(i),
                quantity: "link length",
                value: *l,
                reason: "must be finite and positive",
            });
        }
    }
    Ok(())
}
