//! The path form of the rigid machine at one path point (docs/planning.md, "The path form").
//!
//! Along a timing `s(t)` with `x = s'^2` and `u = s''`, every slider rate and every rigid
//! force is a function of `(u, x)` whose coefficients depend on `s` only:
//!
//! ```text
//! rho_i'  (time) = rho_i'(s) s'                          rho_i'(s) = drho_i/ds
//! rho_i'' (time) = rho_i'(s) u + rho_i''(s) x
//! rho_i''' (time) = rho_i'''(s) s'^3 + 3 rho_i''(s) s' u + rho_i'(s) s'''
//! F_a_i = a_i(s) u + b_i(s) x                            (horizontal plane, no friction)
//! P_i(xi) = P_u(s, xi) u + P_x(s, xi) x + P_0(s, xi)     (axial force along link i)
//! ```
//!
//! The rigid inverse dynamics is linear in the accelerations and quadratic in the velocities,
//! so `a_i` is exactly the drive force of the motion with twist 0 and twist rate `p'` and
//! `b_i` that of twist `p'` and twist rate `p''` (`s' = 1`, `s'' = 0`): two evaluations of the
//! inverse dynamics, no differences. The slider derivatives come from the closed-form inverse
//! kinematics with the same two motions; `rho'''` from differentiating the closure
//! `|C_i - B_i|^2 = l_i^2` three times:
//!
//! ```text
//! d = C - B = l e,  d' = C' - rho' u,  d'' = C'' - rho'' u
//! rho''' = (e.C''' + 3 d'.d'' / l) / (e.u)
//! C''' = p''' + phi''' J r - 3 phi' phi'' r - phi'^3 J r
//! ```

use flexprr_beam::AxialLoad;
use flexprr_dynamics::{AxialForceModel, AxialInput, Machine, end_forces, inverse_dynamics};
use flexprr_kinematics::{MachineKinematics, Path, PathPoint, PlatformMotion};
use nalgebra::Vector2;

use crate::error::{PlanningError, Where};

/// A quantity affine in the path acceleration `u = s''` and the squared path speed
/// `x = s'^2`: `u_coef u + x_coef x + constant`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Affine {
    /// Coefficient of `u`.
    pub u: f64,
    /// Coefficient of `x`.
    pub x: f64,
    /// Constant part (the value at rest).
    pub constant: f64,
}

impl Affine {
    /// The value at `(u, x)`.
    #[inline]
    pub fn at(&self, u: f64, x: f64) -> f64 {
        self.u * u + self.x * x + self.constant
    }
}

/// One leg's slider along the path: position and its derivatives in `s`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LegPath {
    /// Slider position `rho_i` (m).
    pub rho: f64,
    /// `drho_i/ds`.
    pub d1: f64,
    /// `d^2 rho_i/ds^2`.
    pub d2: f64,
    /// `d^3 rho_i/ds^3`.
    pub d3: f64,
    /// Type-I measure `|e_i . u_i|` (0 at a type-I singularity).
    pub type_i: f64,
    /// Distance of the slider from the nearer end of its travel (m).
    pub travel_margin: f64,
}

impl LegPath {
    /// Slider velocity (m/s) at path speed `s_dot`.
    #[inline]
    pub fn velocity(&self, s_dot: f64) -> f64 {
        self.d1 * s_dot
    }

    /// Slider acceleration (m/s^2).
    #[inline]
    pub fn acceleration(&self, s_dot: f64, s_ddot: f64) -> f64 {
        self.d1 * s_ddot + self.d2 * s_dot * s_dot
    }

    /// Slider jerk (m/s^3).
    #[inline]
    pub fn jerk(&self, s_dot: f64, s_ddot: f64, s_dddot: f64) -> f64 {
        self.d3 * s_dot * s_dot * s_dot + 3.0 * self.d2 * s_dot * s_ddot + self.d1 * s_dddot
    }
}

/// Everything a [`crate::Constraint`] reads at one path point.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PathSample {
    /// The path point (pose and `p'`, `p''`, `p'''`).
    pub point: PathPoint,
    /// The three sliders.
    pub legs: [LegPath; 3],
    /// Type-II measure (normalised determinant of the direct Jacobian).
    pub type_ii: f64,
    /// Rigid drive force of each slider, `F_a_i = a_i u + b_i x` (N): the `driving_forces`
    /// output `F_a_i_rigid_N`, slider mass included.
    pub drive: [Affine; 3],
    /// Axial force (tension positive, N) of each link at its slider end B (`[i][0]`) and at
    /// its platform end C (`[i][1]`), from the sampler's axial-force model; zero without one.
    pub axial: [[Affine; 2]; 3],
}

impl PathSample {
    /// Where this sample is, for messages.
    pub fn place(&self) -> Where {
        Where {
            s: self.point.s,
            pose: self.point.pose,
        }
    }
}

/// Computes [`PathSample`]s of a machine along a path. Allocation-free.
#[derive(Debug, Clone, Copy)]
pub struct Sampler<'a> {
    machine: &'a Machine,
    axial: Option<&'a dyn AxialForceModel>,
}

impl<'a> Sampler<'a> {
    /// A sampler of `machine`; with `axial`, the samples carry the links' axial end forces
    /// (for the buckling constraint).
    pub fn new(machine: &'a Machine, axial: Option<&'a dyn AxialForceModel>) -> Self {
        Self { machine, axial }
    }

    /// The machine.
    pub fn machine(&self) -> &'a Machine {
        self.machine
    }

    /// Whether the samples carry axial forces.
    pub fn has_axial(&self) -> bool {
        self.axial.is_some()
    }

    /// The path form at `s`.
    ///
    /// # Errors
    /// [`PlanningError::Workspace`] where the pose is unreachable, beyond a slider's travel or
    /// within the geometry's singularity thresholds; [`PlanningError::Dynamics`] where the
    /// inverse dynamics is singular; [`PlanningError::AxialModel`] if the axial model is not
    /// affine in `(u, x)` with a force concave along the link (see [`crate::Buckling`]).
    pub fn sample(&self, path: &dyn Path, s: f64) -> Result<PathSample, PlanningError> {
        let point = path.point(s);
        let at = Where {
            s: point.s,
            pose: point.pose,
        };
        let geometry = &self.machine.geometry;
        let workspace = |source| PlanningError::Workspace { at, source };
        let dynamics = |source| PlanningError::Dynamics { at, source };
        // s' = 1, s'' = 0: twist p', twist rate p''. The checked IK (travel, singularities).
        let mut quadratic = MachineKinematics::default();
        geometry
            .inverse_kinematics_into(&point.motion(1.0, 0.0), &mut quadratic)
            .map_err(workspace)?;
        // s' = 0, s'' = 1: twist 0, twist rate p'.
        let mut linear = MachineKinematics::default();
        geometry
            .inverse_kinematics_unchecked_into(&point.motion(0.0, 1.0), &mut linear)
            .map_err(workspace)?;
        let reactions_b =
            inverse_dynamics(self.machine, &quadratic, None, point.s).map_err(dynamics)?;
        let reactions_a =
            inverse_dynamics(self.machine, &linear, None, point.s).map_err(dynamics)?;

        let mut sample = PathSample {
            point,
            type_ii: flexprr_dynamics::equilibrium_measure(&quadratic),
            ..PathSample::default()
        };
        let p = point.pose.position().coords;
        let (phi1, phi2, phi3) = (point.d1.z, point.d2.z, point.d3.z);
        for i in 0..3 {
            let leg = &quadratic.legs[i];
            let guide = &geometry.legs[i].guide;
            let u = guide.direction.into_inner();
            let length = geometry.legs[i].link_length;
            let r = leg.c.coords - p;
            let jr = Vector2::new(-r.y, r.x);
            let c3 = Vector2::new(point.d3.x, point.d3.y) + phi3 * jr
                - 3.0 * phi1 * phi2 * r
                - phi1 * phi1 * phi1 * jr;
            let d1 = leg.c_dot - leg.rho_dot * u;
            let d2 = leg.c_ddot - leg.rho_ddot * u;
            let e_dot_u = leg.e.dot(&u);
            sample.legs[i] = LegPath {
                rho: leg.rho,
                d1: leg.rho_dot,
                d2: leg.rho_ddot,
                d3: (leg.e.dot(&c3) + 3.0 * d1.dot(&d2) / length) / e_dot_u,
                type_i: e_dot_u.abs(),
                travel_margin: guide.travel_margin(leg.rho),
            };
            sample.drive[i] = Affine {
                u: reactions_a.driving_force[i],
                x: reactions_b.driving_force[i],
                constant: 0.0,
            };
        }
        if let Some(model) = self.axial {
            let rest = PlatformMotion::at_rest(point.pose);
            let mut still = MachineKinematics::default();
            geometry
                .inverse_kinematics_unchecked_into(&rest, &mut still)
                .map_err(workspace)?;
            let reactions_0 =
                inverse_dynamics(self.machine, &still, None, point.s).map_err(dynamics)?;
            for i in 0..3 {
                let link = &self.machine.links[i];
                let guide_direction = geometry.legs[i].guide.direction.into_inner();
                let load = |legs: &MachineKinematics, reactions| {
                    model.load(&AxialInput {
                        leg: &legs.legs[i],
                        guide_direction,
                        link,
                        reactions: Some(reactions),
                        index: i,
                    })
                };
                let l0 = load(&still, &reactions_0);
                let la = minus(load(&linear, &reactions_a), l0);
                let lb = minus(load(&quadratic, &reactions_b), l0);
                // Concavity of P along the link for every x >= 0 and any u: the largest
                // compression is then at an end (docs/planning.md, "Buckling").
                let scale = la.p0.abs() + lb.p0.abs() + 1e-300;
                let length = link.length();
                if la.p2.abs() * length * length > 1e-9 * scale || lb.p2 > 0.0 || l0.p2 > 0.0 {
                    return Err(PlanningError::AxialModel(format!(
                        "the axial force model `{}` gives a force that is not concave along link {} at {at} (P2 = {:.3e} u + {:.3e} x + {:.3e} N/m^2); the bound on the end compressions would not bound the whole link",
                        model.name(),
                        i + 1,
                        la.p2,
                        lb.p2,
                        l0.p2
                    )));
                }
                let (a0, al) = end_forces(&la, length);
                let (b0, bl) = end_forces(&lb, length);
                let (c0, cl) = end_forces(&l0, length);
                sample.axial[i] = [
                    Affine {
                        u: a0,
                        x: b0,
                        constant: c0,
                    },
                    Affine {
                        u: al,
                        x: bl,
                        constant: cl,
                    },
                ];
            }
        }
        Ok(sample)
    }
}

fn minus(a: AxialLoad, b: AxialLoad) -> AxialLoad {
    AxialLoad {
        p0: a.p0 - b.p0,
        p1: a.p1 - b.p1,
        p2: a.p2 - b.p2,
    }
}
