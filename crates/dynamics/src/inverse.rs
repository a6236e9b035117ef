//! Rigid-body inverse dynamics of the 3-PRR (model.md section 4).
//!
//! Bodies: sliders (mass `m_s`, along their guides), links (mass `m`, centroid at mid-length,
//! inertia `I_G` about it), platform (`m_p`, `I_p`). Unknowns: the force `F_B` of each slider on
//! its link and `F_C` of the platform on each link (12 scalars). Gravity acts normal to the
//! plane and does not enter.
//!
//! # Reduction by hand (used by [`inverse_dynamics`])
//! Moment balance of link `i` about `B_i` fixes the normal component of `F_C`:
//! `l F_C.n = I_G b'' + (l/2) m a_G.n + M_el`, with `a_G = rho'' u + (l/2)(b'' n - b'^2 e)`
//! and `M_el` the moment of the elastic inertia (zero for the rigid machine). With
//! `F_C = f e + t n`, the platform's force and moment balance
//! `sum F_C = -m_p a_p`, `sum r x F_C = -I_p phi''` is a 3x3 system in the axial components
//! `f_i` whose matrix has the columns `(e_i, r_i x e_i)`: the direct kinematic Jacobian,
//! singular exactly at type-II poses. Then `F_B = m a_G + Q n - F_C` and the driving force is
//! `F_a = m_s rho'' + F_B.u`. [`inverse_dynamics_full`] solves the 12 equations directly
//! (tests prove the two agree).

use faer::Mat;
use faer::linalg::solvers::Solve;
use flexprr_kinematics::{LegKinematics, MachineState, PlatformMotion};
use nalgebra::{Vector2, Vector3};

use crate::{DynamicsError, Machine};

/// Joint reactions and actuator forces of the machine at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointReactions {
    /// Force of slider `i` on link `i` at `B_i` (N).
    pub slider_on_link: [Vector2<f64>; 3],
    /// Force of the platform on link `i` at `C_i` (N).
    pub platform_on_link: [Vector2<f64>; 3],
    /// Driving force `F_ai` on slider `i` along its guide (N).
    pub driving_force: [f64; 3],
}

/// Transverse inertia of the links' elastic motion, added to the rigid inertia when the
/// driving forces "with flexibility" are wanted (the paper's figures 10-11).
///
/// For link `i` with modal accelerations `eta''`: the resultant along `n_i` is
/// `Q = sum_j eta''_j l int rhoA psi_j dxi` and its moment about `B_i` is
/// `M_el = l sum_j eta''_j l int rhoA xi psi_j dxi` (the linear part of `int rhoA w'' dx`;
/// Coriolis and centripetal terms of the elastic motion are second order and left out).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ElasticInertia {
    /// Resultant transverse elastic inertia force per link, along `n_i` (N).
    pub force: [f64; 3],
    /// Its moment about `B_i` (N m).
    pub moment_about_b: [f64; 3],
}

/// Acceleration of link `i`'s centroid.
#[inline]
fn centroid_acceleration(leg: &LegKinematics, u: &Vector2<f64>, length: f64) -> Vector2<f64> {
    leg.rho_ddot * u + 0.5 * length * (leg.beta_ddot * leg.n - leg.beta_dot * leg.beta_dot * leg.e)
}

#[inline]
fn cross(a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    a.x * b.y - a.y * b.x
}

/// The legs of a state with or without the link angles (the dynamics never reads them).
#[inline]
fn legs_of<L: AsRef<LegKinematics>>(state: &MachineState<L>) -> [&LegKinematics; 3] {
    [
        state.legs[0].as_ref(),
        state.legs[1].as_ref(),
        state.legs[2].as_ref(),
    ]
}

/// Normalised determinant of the platform equilibrium matrix (rows `(e_i, ((C_i - c̄) x e_i)/L)`
/// scaled to unit length): the same dimensionless type-II measure as
/// [`flexprr_kinematics::SingularityMeasures::type_ii`]. `state` may carry the link angles
/// ([`MachineState`]) or not ([`flexprr_kinematics::MachineKinematics`]).
pub fn equilibrium_measure<L: AsRef<LegKinematics>>(state: &MachineState<L>) -> f64 {
    equilibrium_measure_of(legs_of(state))
}

#[inline]
fn equilibrium_measure_of(legs: [&LegKinematics; 3]) -> f64 {
    let centroid = (legs[0].c.coords + legs[1].c.coords + legs[2].c.coords) / 3.0;
    let radius = legs
        .iter()
        .map(|l| (l.c.coords - centroid).norm())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let mut rows = [[0.0; 3]; 3];
    for (row, leg) in rows.iter_mut().zip(legs) {
        let moment = cross(&(leg.c.coords - centroid), &leg.e) / radius;
        let norm = (leg.e.norm_squared() + moment * moment).sqrt();
        *row = [leg.e.x / norm, leg.e.y / norm, moment / norm];
    }
    det3(&rows).abs()
}

#[inline]
fn det3(m: &[[f64; 3]; 3]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Rigid-body inverse dynamics by the hand reduction (allocation-free, a 3x3 solve).
///
/// `elastic` adds the links' elastic transverse inertia ([`ElasticInertia`]); `t` is only
/// used in error messages.
///
/// # Errors
/// [`DynamicsError::SingularInverseDynamics`] when the pose is within the geometry's type-II
/// threshold (the axial link forces are then undetermined and would be huge).
pub fn inverse_dynamics<L: AsRef<LegKinematics>>(
    machine: &Machine,
    state: &MachineState<L>,
    elastic: Option<&ElasticInertia>,
    t: f64,
) -> Result<JointReactions, DynamicsError> {
    inverse_dynamics_of(machine, &state.motion, legs_of(state), elastic, t)
}

fn inverse_dynamics_of(
    machine: &Machine,
    motion: &PlatformMotion,
    legs: [&LegKinematics; 3],
    elastic: Option<&ElasticInertia>,
    t: f64,
) -> Result<JointReactions, DynamicsError> {
    let threshold = machine.geometry.thresholds.type_ii;
    let measure = equilibrium_measure_of(legs);
    if measure.is_nan() || measure < threshold {
        return Err(DynamicsError::SingularInverseDynamics {
            t,
            measure,
            threshold,
        });
    }
    let p = motion.pose.position().coords;
    let a_p = Vector2::new(motion.acceleration.x, motion.acceleration.y);
    let phi_ddot = motion.acceleration.z;
    let mut a = [[0.0; 3]; 3];
    let mut g = [
        -machine.platform_mass * a_p.x,
        -machine.platform_mass * a_p.y,
        -machine.platform_inertia * phi_ddot,
    ];
    let mut normal = [0.0; 3];
    let mut a_g = [Vector2::zeros(); 3];
    for i in 0..3 {
        let leg = legs[i];
        let link = &machine.links[i];
        let (m, l) = (link.mass(), link.length());
        let u = machine.geometry.legs[i].guide.direction.into_inner();
        a_g[i] = centroid_acceleration(leg, &u, l);
        let m_el = elastic.map_or(0.0, |e| e.moment_about_b[i]);
        let t_i =
            (link.centroid_inertia * leg.beta_ddot + 0.5 * l * m * a_g[i].dot(&leg.n) + m_el) / l;
        normal[i] = t_i;
        let r = leg.c.coords - p;
        a[0][i] = leg.e.x;
        a[1][i] = leg.e.y;
        a[2][i] = cross(&r, &leg.e);
        g[0] -= t_i * leg.n.x;
        g[1] -= t_i * leg.n.y;
        g[2] -= t_i * cross(&r, &leg.n);
    }
    // Cramer's rule on the 3x3 system A f = g without copying A: with the columns a_k of A,
    // det A = a_0 . (a_1 x a_2) and f_k = g . (a_{k+1} x a_{k+2}) / det A (indices mod 3).
    let column = |k: usize| Vector3::new(a[0][k], a[1][k], a[2][k]);
    let (a0, a1, a2) = (column(0), column(1), column(2));
    let (c12, c20, c01) = (a1.cross(&a2), a2.cross(&a0), a0.cross(&a1));
    let det = a0.dot(&c12);
    let g = Vector3::from(g);
    let f = [g.dot(&c12) / det, g.dot(&c20) / det, g.dot(&c01) / det];
    let mut out = JointReactions {
        slider_on_link: [Vector2::zeros(); 3],
        platform_on_link: [Vector2::zeros(); 3],
        driving_force: [0.0; 3],
    };
    for i in 0..3 {
        let leg = legs[i];
        let link = &machine.links[i];
        let u = machine.geometry.legs[i].guide.direction.into_inner();
        let f_c = f[i] * leg.e + normal[i] * leg.n;
        let q = elastic.map_or(0.0, |e| e.force[i]);
        let f_b = link.mass() * a_g[i] + q * leg.n - f_c;
        out.platform_on_link[i] = f_c;
        out.slider_on_link[i] = f_b;
        out.driving_force[i] = machine.slider_mass[i] * leg.rho_ddot + f_b.dot(&u);
    }
    Ok(out)
}

/// Rigid-body inverse dynamics by solving all 12 equations (force and moment balance of
/// each link about its centroid, force and moment balance of the platform) with a dense LU.
/// Allocates; a reference for [`inverse_dynamics`], not for hot paths.
///
/// # Errors
/// As [`inverse_dynamics`].
pub fn inverse_dynamics_full<L: AsRef<LegKinematics>>(
    machine: &Machine,
    state: &MachineState<L>,
    t: f64,
) -> Result<JointReactions, DynamicsError> {
    let legs = legs_of(state);
    let threshold = machine.geometry.thresholds.type_ii;
    let measure = equilibrium_measure(state);
    if measure.is_nan() || measure < threshold {
        return Err(DynamicsError::SingularInverseDynamics {
            t,
            measure,
            threshold,
        });
    }
    // Unknowns: for link i, columns 4i..4i+4 = (F_Bx, F_By, F_Cx, F_Cy).
    let mut a = Mat::<f64>::zeros(12, 12);
    let mut b = Mat::<f64>::zeros(12, 1);
    let p = state.motion.pose.position().coords;
    for (i, leg) in legs.into_iter().enumerate() {
        let link = &machine.links[i];
        let (m, l) = (link.mass(), link.length());
        let u = machine.geometry.legs[i].guide.direction.into_inner();
        let a_g = centroid_acceleration(leg, &u, l);
        let g = leg.b.coords + 0.5 * l * leg.e;
        let (rb, rc) = (leg.b.coords - g, leg.c.coords - g);
        let (row, col) = (3 * i, 4 * i);
        // F_B + F_C = m a_G
        a[(row, col)] = 1.0;
        a[(row, col + 2)] = 1.0;
        b[(row, 0)] = m * a_g.x;
        a[(row + 1, col + 1)] = 1.0;
        a[(row + 1, col + 3)] = 1.0;
        b[(row + 1, 0)] = m * a_g.y;
        // (B - G) x F_B + (C - G) x F_C = I_G b''
        a[(row + 2, col)] = -rb.y;
        a[(row + 2, col + 1)] = rb.x;
        a[(row + 2, col + 2)] = -rc.y;
        a[(row + 2, col + 3)] = rc.x;
        b[(row + 2, 0)] = link.centroid_inertia * leg.beta_ddot;
        // Platform: -sum F_C = m_p a_p, -sum r x F_C = I_p phi''
        let r = leg.c.coords - p;
        a[(9, col + 2)] = -1.0;
        a[(10, col + 3)] = -1.0;
        a[(11, col + 2)] = r.y;
        a[(11, col + 3)] = -r.x;
    }
    b[(9, 0)] = machine.platform_mass * state.motion.acceleration.x;
    b[(10, 0)] = machine.platform_mass * state.motion.acceleration.y;
    b[(11, 0)] = machine.platform_inertia * state.motion.acceleration.z;
    let lu = a.partial_piv_lu();
    lu.solve_in_place(b.as_mut());
    let mut out = JointReactions {
        slider_on_link: [Vector2::zeros(); 3],
        platform_on_link: [Vector2::zeros(); 3],
        driving_force: [0.0; 3],
    };
    for i in 0..3 {
        let u = machine.geometry.legs[i].guide.direction.into_inner();
        let f_b = Vector2::new(b[(4 * i, 0)], b[(4 * i + 1, 0)]);
        out.slider_on_link[i] = f_b;
        out.platform_on_link[i] = Vector2::new(b[(4 * i + 2, 0)], b[(4 * i + 3, 0)]);
        out.driving_force[i] = machine.slider_mass[i] * legs[i].rho_ddot + f_b.dot(&u);
    }
    Ok(out)
}

/// Rigid kinetic energy `T` of sliders, links and platform (J), for the power-balance check
/// `sum F_ai rho_i' = dT/dt`.
pub fn rigid_kinetic_energy<L: AsRef<LegKinematics>>(
    machine: &Machine,
    state: &MachineState<L>,
) -> f64 {
    let legs = legs_of(state);
    let mut energy = 0.0;
    for (i, leg) in legs.into_iter().enumerate() {
        let link = &machine.links[i];
        let u = machine.geometry.legs[i].guide.direction.into_inner();
        let v_g = leg.rho_dot * u + 0.5 * link.length() * leg.beta_dot * leg.n;
        energy += 0.5 * machine.slider_mass[i] * leg.rho_dot * leg.rho_dot
            + 0.5 * link.mass() * v_g.norm_squared()
            + 0.5 * link.centroid_inertia * leg.beta_dot * leg.beta_dot;
    }
    let v = &state.motion.velocity;
    energy
        + 0.5 * machine.platform_mass * (v.x * v.x + v.y * v.y)
        + 0.5 * machine.platform_inertia * v.z * v.z
}
