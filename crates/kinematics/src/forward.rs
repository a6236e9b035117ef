//! Forward kinematics: platform pose from slider positions by Newton's method on the
//! closure equations, the closure Jacobian, and implicit differentiation for rates.

use nalgebra::{Matrix3, Vector2, Vector3};

use crate::error::{KinematicsError, SingularityKind};
use crate::geometry::{Branch, Geometry};
use crate::inverse::{check_lengths, cross, type_ii_measure};
use crate::pose::{PlatformMotion, Pose, check_finite};

/// Maximum number of Newton iterations in [`Geometry::forward_kinematics`].
pub const FORWARD_MAX_ITERATIONS: usize = 50;

/// Closure equations `f_i = (|C_i - B_i|^2 - l_i^2) / 2 = 0` and their partial derivatives,
/// with `g_i = C_i - B_i`, `C_i = p + R(phi) c_i`, `B_i = A_i + rho_i u_i`.
///
/// For implicit differentiation: `pose_jacobian * q' + slider_jacobian o rho' +
/// length_jacobian o l' = 0` (`o`: element-wise product).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Closure {
    /// `f_i` (m^2).
    pub residual: Vector3<f64>,
    /// `df_i / d(x, y, phi)`: row `i` = `(g_i^T, r_i x g_i)`.
    pub pose_jacobian: Matrix3<f64>,
    /// `df_i / d rho_i = -g_i . u_i` (the closure is diagonal in `rho`).
    pub slider_jacobian: Vector3<f64>,
    /// `df_i / d l_i = -l_i`.
    pub length_jacobian: Vector3<f64>,
}

/// Slider motion and (possibly time-varying) link lengths driving the forward problem.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegDrive {
    /// Slider positions `rho_i` (m).
    pub rho: [f64; 3],
    /// Slider velocities (m/s).
    pub rho_dot: [f64; 3],
    /// Slider accelerations (m/s^2).
    pub rho_ddot: [f64; 3],
    /// Link lengths, e.g. `l_i - delta_i` for foreshortened links (m).
    pub length: [f64; 3],
    /// Rates of the link lengths (m/s).
    pub length_dot: [f64; 3],
    /// Second derivatives of the link lengths (m/s^2).
    pub length_ddot: [f64; 3],
}

impl LegDrive {
    /// Sliders driven with rigid links of the geometry's lengths.
    pub fn rigid(
        geometry: &Geometry,
        rho: [f64; 3],
        rho_dot: [f64; 3],
        rho_ddot: [f64; 3],
    ) -> Self {
        Self {
            rho,
            rho_dot,
            rho_ddot,
            length: geometry.link_lengths(),
            length_dot: [0.0; 3],
            length_ddot: [0.0; 3],
        }
    }
}

impl Geometry {
    /// Closure residual and Jacobians at `pose` for slider positions `rho` and link lengths
    /// `lengths`. No checks; allocation-free.
    pub fn closure(&self, pose: &Pose, rho: [f64; 3], lengths: [f64; 3]) -> Closure {
        let (sin, cos) = pose.phi.sin_cos();
        let mut out = Closure {
            residual: Vector3::zeros(),
            pose_jacobian: Matrix3::zeros(),
            slider_jacobian: Vector3::zeros(),
            length_jacobian: Vector3::zeros(),
        };
        for (i, leg) in self.legs.iter().enumerate() {
            let c = leg.attachment;
            let r = Vector2::new(cos * c.x - sin * c.y, sin * c.x + cos * c.y);
            let u = leg.guide.direction.into_inner();
            let g = Vector2::new(pose.x, pose.y) + r - leg.guide.anchor.coords - rho[i] * u;
            out.residual[i] = 0.5 * (g.norm_squared() - lengths[i] * lengths[i]);
            out.pose_jacobian[(i, 0)] = g.x;
            out.pose_jacobian[(i, 1)] = g.y;
            out.pose_jacobian[(i, 2)] = cross(&r, &g);
            out.slider_jacobian[i] = -g.dot(&u);
            out.length_jacobian[i] = -lengths[i];
        }
        out
    }

    /// Forward kinematics with the geometry's link lengths; see
    /// [`Geometry::forward_kinematics_with_lengths`].
    pub fn forward_kinematics(&self, rho: [f64; 3], guess: &Pose) -> Result<Pose, KinematicsError> {
        self.forward_kinematics_with_lengths(rho, self.link_lengths(), guess)
    }

    /// Platform pose from slider positions (and link lengths), by Newton's method on the
    /// closure equations `|C_i - B_i|^2 = l_i^2` starting from `guess`, with a backtracking
    /// line search on the scaled residual `max_i |f_i| / l_i` (Dennis & Schnabel, Numerical
    /// Methods for Unconstrained Optimization, ch. 6).
    ///
    /// A 3-PRR has up to six assembly modes for given `rho`; Newton finds the one the guess
    /// leads to, so pass a nearby pose (e.g. the previous time step's). After convergence each
    /// leg's branch is checked (`e_i.u_i >= 0` for `Behind`, `<= 0` for `Ahead`).
    ///
    /// Errors: non-finite input, invalid lengths, [`KinematicsError::NoConvergence`],
    /// [`KinematicsError::Singular`] (type II) when the closure Jacobian is singular along the
    /// way, [`KinematicsError::BranchMismatch`] when a leg ended in the other assembly mode.
    pub fn forward_kinematics_with_lengths(
        &self,
        rho: [f64; 3],
        lengths: [f64; 3],
        guess: &Pose,
    ) -> Result<Pose, KinematicsError> {
        guess.check_finite()?;
        for value in rho {
            check_finite("slider position rho", value)?;
        }
        check_lengths(lengths)?;
        let scaled = |closure: &Closure| {
            (0..3)
                .map(|i| (closure.residual[i] / lengths[i]).abs())
                .fold(0.0, f64::max)
        };
        // Residual level below which the iterate is converged: a few ulps of the machine size.
        let size = self
            .legs
            .iter()
            .map(|leg| leg.guide.anchor.coords.norm() + leg.attachment.norm() + leg.link_length)
            .fold(0.0, f64::max)
            + rho.iter().fold(0.0, |m: f64, r| m.max(r.abs()));
        let tolerance = 64.0 * f64::EPSILON * size;
        let mut q = guess.to_vector();
        let mut closure = self.closure(guess, rho, lengths);
        let mut residual = scaled(&closure);
        let mut iterations = 0;
        while residual > tolerance {
            if iterations == FORWARD_MAX_ITERATIONS {
                return Err(KinematicsError::NoConvergence {
                    iterations,
                    residual,
                });
            }
            iterations += 1;
            let step = match closure.pose_jacobian.lu().solve(&(-closure.residual)) {
                Some(step) if step.iter().all(|s| s.is_finite()) => step,
                _ => {
                    let pose = Pose::from_vector(&q);
                    return Err(KinematicsError::Singular {
                        kind: SingularityKind::TypeII,
                        leg: None,
                        measure: self.closure_type_ii(&pose, rho),
                        threshold: 0.0,
                    });
                }
            };
            let mut lambda = 1.0;
            let mut accepted = false;
            for _ in 0..40 {
                let trial = q + lambda * step;
                let trial_closure = self.closure(&Pose::from_vector(&trial), rho, lengths);
                let trial_residual = scaled(&trial_closure);
                if trial_residual < residual || trial_residual <= tolerance {
                    q = trial;
                    closure = trial_closure;
                    residual = trial_residual;
                    accepted = true;
                    break;
                }
                lambda *= 0.5;
            }
            if !accepted {
                // No decrease along the Newton direction: either at rounding level (accept if
                // nearly converged) or stuck at a local minimum of the residual (no solution
                // near the guess, e.g. unreachable slider positions).
                if residual <= 1e3 * tolerance {
                    break;
                }
                return Err(KinematicsError::NoConvergence {
                    iterations,
                    residual,
                });
            }
        }
        let pose = Pose::from_vector(&q);
        let (sin, cos) = pose.phi.sin_cos();
        for (i, leg) in self.legs.iter().enumerate() {
            let c = leg.attachment;
            let r = Vector2::new(cos * c.x - sin * c.y, sin * c.x + cos * c.y);
            let u = leg.guide.direction.into_inner();
            let g = Vector2::new(pose.x, pose.y) + r - leg.guide.anchor.coords - rho[i] * u;
            let e_dot_u = g.dot(&u) / lengths[i];
            let wrong = match leg.branch {
                Branch::Behind => e_dot_u < -1e-12,
                Branch::Ahead => e_dot_u > 1e-12,
            };
            if wrong {
                return Err(KinematicsError::BranchMismatch {
                    leg: i,
                    expected: leg.branch,
                    e_dot_u,
                });
            }
        }
        Ok(pose)
    }

    /// Type-II measure of the (possibly not closed) configuration, with link directions
    /// `g_i / |g_i|`; used in error reports.
    fn closure_type_ii(&self, pose: &Pose, rho: [f64; 3]) -> f64 {
        let mut e = [Vector2::zeros(); 3];
        let mut r = [Vector2::zeros(); 3];
        for (i, leg) in self.legs.iter().enumerate() {
            r[i] = pose.rotate(&leg.attachment);
            let g = Vector2::new(pose.x, pose.y) + r[i]
                - leg.guide.anchor.coords
                - rho[i] * leg.guide.direction.into_inner();
            e[i] = g.try_normalize(0.0).unwrap_or_else(Vector2::zeros);
        }
        type_ii_measure(e, r)
    }

    /// Forward kinematics of position, velocity and acceleration: the pose by
    /// [`Geometry::forward_kinematics_with_lengths`], then the twist and its derivative by
    /// implicit differentiation of the closure `f_i = (g_i.g_i - l_i^2) / 2 = 0`:
    ///
    /// ```text
    /// F q'  = (g.u) rho' + l l'
    /// F q'' = (g.u) rho'' + l l'' + l'^2 - |g'|^2 + phi'^2 g.r,   g' = p' + phi' J r - rho' u
    /// ```
    ///
    /// with `F` the closure's pose Jacobian (rows `(g_i^T, r_i x g_i)`).
    pub fn forward_motion(
        &self,
        drive: &LegDrive,
        guess: &Pose,
    ) -> Result<PlatformMotion, KinematicsError> {
        for k in 0..3 {
            check_finite("slider velocity", drive.rho_dot[k])?;
            check_finite("slider acceleration", drive.rho_ddot[k])?;
            check_finite("link length rate", drive.length_dot[k])?;
            check_finite("link length acceleration", drive.length_ddot[k])?;
        }
        let pose = self.forward_kinematics_with_lengths(drive.rho, drive.length, guess)?;
        let closure = self.closure(&pose, drive.rho, drive.length);
        let lu = closure.pose_jacobian.lu();
        let singular = || KinematicsError::Singular {
            kind: SingularityKind::TypeII,
            leg: None,
            measure: self.closure_type_ii(&pose, drive.rho),
            threshold: 0.0,
        };
        let mut rhs = Vector3::zeros();
        for i in 0..3 {
            rhs[i] = -closure.slider_jacobian[i] * drive.rho_dot[i]
                + drive.length[i] * drive.length_dot[i];
        }
        let velocity = lu.solve(&rhs).ok_or_else(singular)?;
        let omega = velocity.z;
        let (sin, cos) = pose.phi.sin_cos();
        for (i, leg) in self.legs.iter().enumerate() {
            let c = leg.attachment;
            let r = Vector2::new(cos * c.x - sin * c.y, sin * c.x + cos * c.y);
            let u = leg.guide.direction.into_inner();
            let g = Vector2::new(pose.x, pose.y) + r - leg.guide.anchor.coords - drive.rho[i] * u;
            let g_dot = Vector2::new(velocity.x - omega * r.y, velocity.y + omega * r.x)
                - drive.rho_dot[i] * u;
            rhs[i] = g.dot(&u) * drive.rho_ddot[i]
                + drive.length[i] * drive.length_ddot[i]
                + drive.length_dot[i] * drive.length_dot[i]
                - g_dot.norm_squared()
                + omega * omega * g.dot(&r);
        }
        let acceleration = lu.solve(&rhs).ok_or_else(singular)?;
        if !(velocity
            .iter()
            .chain(acceleration.iter())
            .all(|v| v.is_finite()))
        {
            return Err(singular());
        }
        Ok(PlatformMotion {
            pose,
            velocity,
            acceleration,
        })
    }
}
