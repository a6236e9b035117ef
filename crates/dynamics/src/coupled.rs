//! The coupled rigid-flexible model: the sliders follow their inverse-kinematics path, the
//! platform is no longer prescribed but follows from the sliders and the links' *chords*,
//! which bending shortens (foreshortening). The axial forces are the constraint forces of the
//! chords, computed from the platform's and the links' equations of motion at every instant.
//!
//! The derivation is in the workspace's `docs/coupled.md`; in short, for link `i` with modal
//! coordinates `eta_i` (model.md section 6 notation, `x` from `B_i` along the chord):
//!
//! ```text
//! chord length      L_i = l - delta_i,   delta_i = (1/(2l)) eta_i^T G0 eta_i   (= (1/2) int w'^2 dx)
//! platform pose     q(eta, t): closure |C_i(q) - B_i(rho_i(t))| = L_i          (forward kinematics)
//!                   F q' = (g.u) rho' + L L',  F q'' = ... + L L''  with  L'' = L''_0 + dL . eta''
//! chord angle       b_i'' = [N_i . q'' - phi'^2 r_i.n_i - rho_i'' u_i.n_i - 2 L_i' b_i'] / L_i
//! modal equations   M eta_i'' + C eta_i' + (Kf + Kp(N_i) - b_i'^2 M) eta_i
//!                       = -m_psi rho_i'' sin(a_i - b_i) - l m_xipsi b_i''
//! axial force       N_i(x) = T_i - rhoA [rho_i'' cos(a_i - b_i) (l - x) - b_i'^2 (l^2 - x^2) / 2]
//! chord tension     T_i = F_Ci . e_i from the platform's Newton-Euler equations
//!                   M_p q'' = -sum_i (T_i E_i + S_i N_i),   S_i = Mom_i / L_i,
//!                   Mom_i = I_B b_i'' + (m l / 2) rho_i'' sin(a_i - b_i) + l m_xipsi.eta_i''
//!                           - rho_i'' cos(a_i - b_i) m_psi.eta_i      (moment about B_i)
//! ```
//!
//! with `E_i = (e_i, r_i x e_i)`, `N_i = (n_i, r_i x n_i)` and `M_p = diag(m_p, m_p, I_p)`.
//! These are Lagrange's equations for the generalized coordinates `eta` (kinetic energy of
//! links and platform through `(eta, t)`, strain energy of the links) in the virtual-work
//! form: the platform's and the links' rigid inertia seen through `dq/d eta` and
//! `d b / d eta` add up, by the Newton-Euler equations of the platform and the links, to
//! exactly the chord tension times `d delta / d eta`, which joins the links' own axial inertia
//! in `Kp(N)`. Terms whose coefficient is itself of second order in `eta` (the foreshortening
//! displacement in the transverse acceleration, `u_s b''` and `2 u_s' b'`, and the elastic
//! part of the links' axial inertia in `N(x)`) are left out.
//!
//! `eta''` enters `b''` (through `q''` and `L''`) and `T` (through `q''` and `Mom`), so the
//! accelerations solve a linear system per evaluation, `A eta'' = g` with `A` the block
//! diagonal modal mass plus low-rank terms; it reduces to a 6x6 system for the chord-length
//! and moment projections of `eta''` (see `solve_accelerations`), solved on the stack: the
//! right-hand side allocates nothing.
//!
//! With [`CoupledOptions::ked_limit`] (no foreshortening in the closure, no elastic inertia in
//! the reactions) these are the consistent KED equations of model.md section 6 for every
//! `eta`. Linearised about `eta = 0` with the rigid motion prescribed they are those equations
//! plus only the geometric stiffness of the tension that the forced `eta''` adds to the joint
//! reactions; with foreshortening, `L'' = -(1/l) eta^T G0 eta''` adds a first-order coupling
//! between the links through the platform (tests in `tests/coupled.rs`).

use std::str::FromStr;
use std::sync::Arc;

use faer::{Mat, Side};
use flexprr_integrators::OdeSystem;
use flexprr_kinematics::{MachineKinematics, PlatformMotion, Pose, Trajectory};
use nalgebra::{Matrix3, Vector2, Vector3};

use crate::{DynamicsError, Machine, ModalDamping};

/// Newton iterations allowed for the platform pose (it starts within a millimetre).
const FORWARD_ITERATIONS: usize = 20;

/// Which model of the links' interaction with the rigid machine a scene uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CouplingModel {
    /// Kineto-elasto-dynamics: rigid motion prescribed, axial forces from rigid inverse
    /// dynamics ([`crate::ModalSystem`]).
    #[default]
    Ked,
    /// The coupled model of this module ([`CoupledSystem`]).
    Coupled,
    /// Geometrically nonlinear links: co-rotational beam elements and a free platform
    /// ([`crate::NonlinearSystem`]).
    Nonlinear,
}

impl CouplingModel {
    /// The name used in scene files: `"ked"`, `"coupled"` or `"nonlinear"`.
    pub fn name(self) -> &'static str {
        match self {
            CouplingModel::Ked => "ked",
            CouplingModel::Coupled => "coupled",
            CouplingModel::Nonlinear => "nonlinear",
        }
    }
}

impl std::fmt::Display for CouplingModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for CouplingModel {
    type Err = DynamicsError;
    /// `"ked"`, `"coupled"` or `"nonlinear"`; anything else is
    /// [`DynamicsError::Inconsistent`] naming it.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "ked" => Ok(CouplingModel::Ked),
            "coupled" => Ok(CouplingModel::Coupled),
            "nonlinear" => Ok(CouplingModel::Nonlinear),
            _ => Err(DynamicsError::Inconsistent(format!(
                "unknown coupling {s:?}: expected \"ked\", \"coupled\" or \"nonlinear\""
            ))),
        }
    }
}

/// Switches of the coupled model (both on in [`CoupledOptions::full`], the default).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoupledOptions {
    /// Chords shortened by `delta_i` in the closure: the platform feels the deflection.
    /// Off: chord lengths stay `l` and the platform follows its nominal path.
    pub foreshortening: bool,
    /// The links' elastic inertia in their moment balance (and so in the chord tensions).
    /// Off: the tensions are the rigid inverse-dynamics ones for the actual chord motion.
    pub elastic_reactions: bool,
    /// Axial stiffness `EA` of each link (N). When given, [`CoupledOutput`] also reports the
    /// quasi-static axial stretch of each chord, `(1/EA) int N dx`, and the platform pose
    /// correction it causes to first order (`F dq = L stretch`, the closure's implicit
    /// differentiation). Output only: the dynamics stay rigid-axial (the axial modes, near
    /// 2 kHz for the paper's links, are far above the foreshortening excitation).
    pub axial_stiffness: Option<[f64; 3]>,
    /// Stop with [`DynamicsError::Collapse`] when a link's mid-point deflection exceeds this
    /// fraction of its length (`None`: stop only at a type-II pose). The small-deflection
    /// model leaves 5 % of a geometrically exact one near 12 % (docs/coupled.md), so 0.1 is
    /// both the external model's collapse criterion and the edge of this model's range.
    pub collapse_deflection: Option<f64>,
}

impl CoupledOptions {
    /// The full coupled model.
    pub const fn full() -> Self {
        Self {
            foreshortening: true,
            elastic_reactions: true,
            axial_stiffness: None,
            collapse_deflection: None,
        }
    }
    /// Both couplings off: the consistent KED equations (model.md section 6, joint-reaction
    /// axial force, full `Kp`), for checks.
    pub const fn ked_limit() -> Self {
        Self {
            foreshortening: false,
            elastic_reactions: false,
            axial_stiffness: None,
            collapse_deflection: None,
        }
    }
}

impl Default for CoupledOptions {
    fn default() -> Self {
        Self::full()
    }
}

/// Work counters of a coupled system.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CoupledCounters {
    /// Right-hand-side evaluations.
    pub rhs_evaluations: usize,
    /// Forward-kinematics solves (one per evaluation with foreshortening on).
    pub forward_kinematics_solves: usize,
    /// Linear solves for the modal accelerations.
    pub acceleration_solves: usize,
}

/// Everything the coupled model knows at one `(t, y)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CoupledOutput {
    /// Time (s).
    pub t: f64,
    /// The nominal platform motion (the trajectory's).
    pub nominal: PlatformMotion,
    /// The actual platform motion: pose from the sliders and chords, velocity and acceleration
    /// by implicit differentiation of the closure.
    pub platform: PlatformMotion,
    /// Chord lengths `L_i = l - delta_i` (m).
    pub chord_length: [f64; 3],
    /// Chord angles `b_i`, rates and accelerations (rad, rad/s, rad/s^2).
    pub chord_angle: [[f64; 3]; 3],
    /// Axial force of each link at `B_i` (tension positive, N).
    pub axial_force_b: [f64; 3],
    /// Axial force of each link at `C_i`: the chord constraint force (tension positive, N).
    pub axial_force_c: [f64; 3],
    /// Transverse deflection at each link's mid-point, along the chord normal (m).
    pub midpoint_deflection: [f64; 3],
    /// Driving force of each slider along its guide (N).
    pub driving_force: [f64; 3],
    /// Quasi-static axial stretch of each chord `(1/EA) int_0^l N dx` (m); zero unless
    /// [`CoupledOptions::axial_stiffness`] is given.
    pub axial_stretch: [f64; 3],
    /// Platform pose change `(dx, dy, dphi)` caused by the axial stretch, to first order;
    /// zero unless [`CoupledOptions::axial_stiffness`] is given.
    pub stretch_pose_correction: [f64; 3],
}

impl CoupledOutput {
    /// Platform pose minus the nominal pose `(dx, dy, dphi)` (m, m, rad).
    pub fn pose_deviation(&self) -> [f64; 3] {
        [
            self.platform.pose.x - self.nominal.pose.x,
            self.platform.pose.y - self.nominal.pose.y,
            self.platform.pose.phi - self.nominal.pose.phi,
        ]
    }

    /// [`CoupledOutput::pose_deviation`] plus the first-order effect of the quasi-static axial
    /// stretch of the links ([`CoupledOptions::axial_stiffness`]).
    pub fn pose_deviation_with_stretch(&self) -> [f64; 3] {
        let d = self.pose_deviation();
        std::array::from_fn(|k| d[k] + self.stretch_pose_correction[k])
    }
}

/// Per-link constants, matrices row-major `r x r`; `inv_*` have `M^-1` applied.
#[derive(Debug, Clone)]
struct LinkData {
    r: usize,
    length: f64,
    mass: f64,
    /// Inertia about `B`: `I_G + m l^2 / 4` (kg m^2).
    inertia_b: f64,
    /// `G0` (for `delta` and `dL / d eta`).
    g0: Vec<f64>,
    inv_flexural: Vec<f64>,
    inv_geometric: [Vec<f64>; 3],
    inv_damping: Vec<f64>,
    mass_psi: Vec<f64>,
    mass_xi_psi: Vec<f64>,
    inv_mass_psi: Vec<f64>,
    inv_mass_xi_psi: Vec<f64>,
    /// `m_xipsi . M^-1 m_xipsi`.
    xi_psi_inv_xi_psi: f64,
    /// `psi_j(1/2)`.
    psi_mid: Vec<f64>,
}

impl LinkData {
    fn new(
        link: &crate::LinkModel,
        damping: &ModalDamping,
        index: usize,
    ) -> Result<Self, DynamicsError> {
        use faer::linalg::solvers::DenseSolveCore;
        let ints = &link.integrals;
        let r = ints.r();
        let l = ints.length;
        let m = ints.total_mass;
        let m_inv = ints
            .mass
            .llt(Side::Lower)
            .map_err(|_| {
                DynamicsError::Inconsistent(format!(
                    "the modal mass matrix of link {} is not positive definite",
                    index + 1
                ))
            })?
            .inverse();
        let apply = |a: &Mat<f64>| crate::modal::to_row_major(&(&m_inv * a));
        let apply_vec = |v: &[f64]| -> Vec<f64> {
            (0..r)
                .map(|i| (0..r).map(|k| m_inv[(i, k)] * v[k]).sum())
                .collect()
        };
        let damping = crate::modal::damping_matrix(link, damping, index)?
            .map_or_else(|| vec![0.0; r * r], |c| crate::modal::to_row_major(&c));
        let damping = Mat::from_fn(r, r, |i, j| damping[i * r + j]);
        let inv_mass_xi_psi = apply_vec(&ints.mass_xi_psi);
        Ok(Self {
            r,
            length: l,
            mass: m,
            inertia_b: link.centroid_inertia + 0.25 * m * l * l,
            g0: crate::modal::to_row_major(&ints.g[0]),
            inv_flexural: apply(&ints.stiffness),
            inv_geometric: std::array::from_fn(|n| apply(&ints.g[n])),
            inv_damping: apply(&damping),
            mass_psi: ints.mass_psi.clone(),
            xi_psi_inv_xi_psi: dot(&ints.mass_xi_psi, &inv_mass_xi_psi),
            mass_xi_psi: ints.mass_xi_psi.clone(),
            inv_mass_psi: apply_vec(&ints.mass_psi),
            inv_mass_xi_psi,
            psi_mid: (0..r).map(|j| link.basis.eval(j, 0.5)[0]).collect(),
        })
    }
}

/// Per-evaluation scratch, preallocated (sizes fixed by the machine).
#[derive(Debug, Clone)]
struct Scratch {
    /// `G0 eta_i / l` per link, stacked (`n`).
    g0_eta: Vec<f64>,
    /// `M^-1 G0 eta_i / l`, stacked (`n`).
    inv_g0_eta: Vec<f64>,
    /// `dL_i / d eta_i`, stacked (`n`).
    length_gradient: Vec<f64>,
    /// The modal accelerations `eta''` of the last evaluation (`n`).
    acceleration: Vec<f64>,
}

/// Linear-in-`eta''` pieces of one evaluation: `b'' = beta0 + Bs s`,
/// `T = tension0 + Ts s + Tm m` with `s_j = dL_j . eta_j''` and `m_j = m_xipsi_j . eta_j''`.
#[derive(Debug, Clone, Copy)]
struct Kinetics {
    nominal: PlatformMotion,
    pose: Pose,
    velocity: Vector3<f64>,
    acceleration0: Vector3<f64>,
    /// `Q = F^-1 diag(L)`: `q'' = acceleration0 + Q s`.
    q_of_s: Matrix3<f64>,
    lengths: [f64; 3],
    rho: [[f64; 3]; 3],
    e: [Vector2<f64>; 3],
    n: [Vector2<f64>; 3],
    beta_dot: [f64; 3],
    beta0: Vector3<f64>,
    beta_s: Matrix3<f64>,
    tension0: Vector3<f64>,
    tension_s: Matrix3<f64>,
    tension_m: Matrix3<f64>,
    sin_ab: [f64; 3],
    cos_ab: [f64; 3],
    /// Type-II measure of the actual chords.
    type_ii_measure: f64,
}

/// The chords of the deflected links at one instant (module documentation).
struct Chords {
    /// `L_i` (m).
    lengths: [f64; 3],
    /// `L_i'` (m/s).
    length_dot: [f64; 3],
    /// The part of `L_i''` without `eta''` (m/s²).
    length_ddot0: [f64; 3],
}

/// The columns of the platform's balance at one instant: `E_i`, `N_i`, the normalised
/// columns of the type-II measure, and the links' moments about `B_i` over `L_i` (without
/// `eta''`, and their `s` rows).
struct Balance {
    e_cols: Matrix3<f64>,
    n_cols: Matrix3<f64>,
    measure_cols: Matrix3<f64>,
    moment0: Vector3<f64>,
    moment_s: Matrix3<f64>,
}

/// The coupled rigid-flexible 3-PRR as an [`OdeSystem`]: state
/// `y = (eta_1, eta_2, eta_3, eta_1', eta_2', eta_3')` as in [`crate::ModalSystem`].
pub struct CoupledSystem {
    machine: Arc<Machine>,
    /// Machine size for the closure's convergence test (m).
    size: f64,
    trajectory: Arc<dyn Trajectory + Send + Sync>,
    damping: ModalDamping,
    options: CoupledOptions,
    links: [LinkData; 3],
    offsets: [usize; 3],
    modes: usize,
    scratch: Scratch,
    counters: CoupledCounters,
    failure: Option<DynamicsError>,
}

impl std::fmt::Debug for CoupledSystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CoupledSystem")
            .field("options", &self.options)
            .field("modes", &self.modes)
            .field("counters", &self.counters)
            .finish_non_exhaustive()
    }
}

#[inline]
fn cross(a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    a.x * b.y - a.y * b.x
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// `out = A x` for row-major `r x r` `A`, accumulated with factor `scale`: `out += scale A x`.
#[inline]
fn mat_vec_acc(a: &[f64], x: &[f64], scale: f64, out: &mut [f64]) {
    let r = x.len();
    for (j, o) in out.iter_mut().enumerate() {
        *o += scale * dot(&a[j * r..(j + 1) * r], x);
    }
}

/// Solves `A x = b` in place (`A` row-major `n x n`, overwritten; `b` becomes `x`) by Gaussian
/// elimination with partial pivoting (Golub & Van Loan, *Matrix Computations*, 4th ed.,
/// algorithm 3.4.1). Returns the column of a zero pivot.
fn solve_in_place(a: &mut [f64], b: &mut [f64]) -> Result<(), usize> {
    let n = b.len();
    for k in 0..n {
        let (mut p, mut best) = (k, a[k * n + k].abs());
        for i in k + 1..n {
            let v = a[i * n + k].abs();
            if v > best {
                (p, best) = (i, v);
            }
        }
        if !(best > 0.0 && best.is_finite()) {
            return Err(k);
        }
        if p != k {
            for j in 0..n {
                a.swap(k * n + j, p * n + j);
            }
            b.swap(k, p);
        }
        let pivot = a[k * n + k];
        for i in k + 1..n {
            let factor = a[i * n + k] / pivot;
            if factor.abs() > 0.0 {
                for j in k + 1..n {
                    a[i * n + j] -= factor * a[k * n + j];
                }
                b[i] -= factor * b[k];
            }
        }
    }
    for k in (0..n).rev() {
        let mut sum = b[k];
        for j in k + 1..n {
            sum -= a[k * n + j] * b[j];
        }
        b[k] = sum / a[k * n + k];
    }
    Ok(())
}

impl CoupledSystem {
    /// Builds the system for a machine, a nominal platform trajectory (the sliders follow its
    /// inverse kinematics), modal damping and the model switches.
    ///
    /// # Errors
    /// A modal mass matrix that is not positive definite, inconsistent damping, or a
    /// non-positive axial stiffness.
    pub fn new(
        machine: Arc<Machine>,
        trajectory: Arc<dyn Trajectory + Send + Sync>,
        damping: ModalDamping,
        options: CoupledOptions,
    ) -> Result<Self, DynamicsError> {
        if let Some(limit) = options.collapse_deflection {
            if !(limit.is_finite() && limit > 0.0) {
                return Err(DynamicsError::InvalidParameter {
                    quantity: "collapse deflection fraction".into(),
                    value: limit,
                    reason: "must be finite and positive",
                });
            }
        }
        if let Some(stiffness) = options.axial_stiffness {
            if let Some((i, k)) = stiffness
                .iter()
                .enumerate()
                .find(|(_, k)| !(k.is_finite() && **k > 0.0))
            {
                return Err(DynamicsError::InvalidParameter {
                    quantity: format!("axial stiffness EA of link {}", i + 1),
                    value: *k,
                    reason: "must be finite and positive",
                });
            }
        }
        let [a, b, c] = [0, 1, 2].map(|i| LinkData::new(&machine.links[i], &damping, i));
        let links = [a?, b?, c?];
        let offsets = [0, links[0].r, links[0].r + links[1].r];
        let modes = offsets[2] + links[2].r;
        let size = machine
            .geometry
            .legs
            .iter()
            .map(|leg| {
                leg.guide.anchor.coords.norm()
                    + leg.attachment.norm()
                    + leg.link_length
                    + leg.guide.travel.0.abs().max(leg.guide.travel.1.abs())
            })
            .fold(0.0, f64::max);
        Ok(Self {
            size,
            machine,
            trajectory,
            damping,
            options,
            links,
            offsets,
            modes,
            scratch: Scratch {
                g0_eta: vec![0.0; modes],
                inv_g0_eta: vec![0.0; modes],
                length_gradient: vec![0.0; modes],
                acceleration: vec![0.0; modes],
            },
            counters: CoupledCounters::default(),
            failure: None,
        })
    }

    /// The machine.
    pub fn machine(&self) -> &Machine {
        &self.machine
    }
    /// The nominal trajectory.
    pub fn trajectory(&self) -> &Arc<dyn Trajectory + Send + Sync> {
        &self.trajectory
    }
    /// The damping.
    pub fn damping(&self) -> &ModalDamping {
        &self.damping
    }
    /// The model switches.
    pub fn options(&self) -> CoupledOptions {
        self.options
    }
    /// Total number of modal coordinates (half the state dimension).
    pub fn modes(&self) -> usize {
        self.modes
    }
    /// Range of link `i`'s coordinates in `eta`.
    pub fn link_range(&self, link: usize) -> std::ops::Range<usize> {
        self.offsets[link]..self.offsets[link] + self.links[link].r
    }
    /// Work counters so far.
    pub fn counters(&self) -> CoupledCounters {
        self.counters
    }
    /// The zero initial state `eta(0) = 0`, `eta'(0) = 0`: links straight, machine on its
    /// rigid inverse-kinematics path with the rigid velocities.
    pub fn initial_state(&self) -> Vec<f64> {
        vec![0.0; 2 * self.modes]
    }
    /// The first failure met inside the right-hand side (which then writes NaN so the
    /// integrator stops with a non-finite error): use it to report the real cause.
    pub fn take_failure(&mut self) -> Option<DynamicsError> {
        self.failure.take()
    }

    /// Chord shortening `delta_i = (1/(2l)) eta_i^T G0 eta_i` of each link (m).
    pub fn chord_shortening(&self, eta: &[f64]) -> [f64; 3] {
        std::array::from_fn(|i| {
            let link = &self.links[i];
            let e = &eta[self.link_range(i)];
            let mut s = 0.0;
            for j in 0..link.r {
                s += e[j] * dot(&link.g0[j * link.r..(j + 1) * link.r], e);
            }
            0.5 * s / link.length
        })
    }

    /// Platform pose, velocity and the part `a_0` of its acceleration independent of `eta''`
    /// for chord lengths `L` (and rates), by Newton's method on the closure
    /// `f_i = (|C_i - B_i|^2 - L_i^2) / 2 = 0` from the nominal pose (the deviation is a
    /// fraction of a millimetre: two or three iterations), then implicit differentiation:
    /// `F q' = (g.u) rho' + L L'`, `F q'' = (g.u) rho'' + L L'' + L'^2 - |g'|^2 + phi'^2 g.r`
    /// (as [`flexprr_kinematics::Geometry::forward_motion`], which this inlines to share `F^-1`).
    /// Returns the motion and `F^-1`.
    fn platform_motion(
        &self,
        t: f64,
        nominal: &Pose,
        rho: &[[f64; 3]; 3],
        lengths: [f64; 3],
        length_dot: [f64; 3],
        length_ddot0: [f64; 3],
    ) -> Result<(PlatformMotion, Matrix3<f64>), DynamicsError> {
        let geometry = &self.machine.geometry;
        let mut q = nominal.to_vector();
        let tolerance = 64.0 * f64::EPSILON * self.size;
        let mut g = [Vector2::zeros(); 3];
        let mut r = [Vector2::zeros(); 3];
        let mut f = Matrix3::zeros();
        let mut residual = Vector3::zeros();
        let mut iterations = 0;
        loop {
            let (sin, cos) = q.z.sin_cos();
            let mut worst: f64 = 0.0;
            for (i, leg) in geometry.legs.iter().enumerate() {
                let c = leg.attachment;
                r[i] = Vector2::new(cos * c.x - sin * c.y, sin * c.x + cos * c.y);
                g[i] = Vector2::new(q.x, q.y) + r[i]
                    - leg.guide.anchor.coords
                    - rho[i][0] * leg.guide.direction.into_inner();
                residual[i] = 0.5 * (g[i].norm_squared() - lengths[i] * lengths[i]);
                f.set_row(
                    i,
                    &nalgebra::RowVector3::new(g[i].x, g[i].y, cross(&r[i], &g[i])),
                );
                worst = worst.max((residual[i] / lengths[i]).abs());
            }
            if worst <= tolerance {
                break;
            }
            if iterations == FORWARD_ITERATIONS || !worst.is_finite() {
                return Err(DynamicsError::Kinematics {
                    t,
                    source: flexprr_kinematics::KinematicsError::NoConvergence {
                        iterations,
                        residual: worst,
                    },
                });
            }
            let step = f
                .try_inverse()
                .ok_or(DynamicsError::SingularInverseDynamics {
                    t,
                    measure: 0.0,
                    threshold: geometry.thresholds.type_ii,
                })?
                * residual;
            q -= step;
            iterations += 1;
        }
        let f_inv = f
            .try_inverse()
            .ok_or(DynamicsError::SingularInverseDynamics {
                t,
                measure: 0.0,
                threshold: geometry.thresholds.type_ii,
            })?;
        let mut rhs = Vector3::zeros();
        for i in 0..3 {
            let u = geometry.legs[i].guide.direction.into_inner();
            rhs[i] = g[i].dot(&u) * rho[i][1] + lengths[i] * length_dot[i];
        }
        let velocity = f_inv * rhs;
        let omega = velocity.z;
        for i in 0..3 {
            let u = geometry.legs[i].guide.direction.into_inner();
            let g_dot = Vector2::new(velocity.x - omega * r[i].y, velocity.y + omega * r[i].x)
                - rho[i][1] * u;
            rhs[i] = g[i].dot(&u) * rho[i][2]
                + lengths[i] * length_ddot0[i]
                + length_dot[i] * length_dot[i]
                - g_dot.norm_squared()
                + omega * omega * g[i].dot(&r[i]);
        }
        let acceleration = f_inv * rhs;
        Ok((
            PlatformMotion {
                pose: Pose::from_vector(&q),
                velocity,
                acceleration,
            },
            f_inv,
        ))
    }

    /// Rigid kinematics and the linear-in-`eta''` pieces at `(t, y)`; fills
    /// `scratch.g0_eta`, `scratch.inv_g0_eta` and `scratch.length_gradient`. In four steps
    /// (module documentation): the sliders on their inverse-kinematics path, the chords
    /// shortened by the bending ([`Self::foreshortened_chords`]), the platform that closes
    /// the chords ([`Self::closing_platform`]), the chord angles and the links' moments
    /// ([`Self::chord_kinetics`]), and the chord tensions from the platform's balance
    /// ([`Self::chord_tensions`]).
    fn kinetics(&mut self, t: f64, y: &[f64]) -> Result<Kinetics, DynamicsError> {
        let n = self.modes;
        let (eta, eta_dot) = y.split_at(n);
        let nominal = self.trajectory.motion(t);
        // Only the slider coordinates are read: in place, without the link angles.
        let mut rigid = MachineKinematics::default();
        self.machine
            .geometry
            .inverse_kinematics_unchecked_into(&nominal, &mut rigid)
            .map_err(|source| DynamicsError::Kinematics { t, source })?;
        let rho: [[f64; 3]; 3] = std::array::from_fn(|i| {
            let leg = &rigid.legs[i];
            [leg.rho, leg.rho_dot, leg.rho_ddot]
        });
        let chords = self.foreshortened_chords(eta, eta_dot);
        let (motion, f_inv) = self.closing_platform(t, nominal, &rho, &chords, eta, &rigid)?;
        let lengths = chords.lengths;
        let mut out = Kinetics {
            nominal,
            pose: motion.pose,
            velocity: motion.velocity,
            acceleration0: motion.acceleration,
            q_of_s: f_inv * Matrix3::from_diagonal(&Vector3::from(lengths)),
            lengths,
            rho,
            e: [Vector2::zeros(); 3],
            n: [Vector2::zeros(); 3],
            beta_dot: [0.0; 3],
            beta0: Vector3::zeros(),
            beta_s: Matrix3::zeros(),
            tension0: Vector3::zeros(),
            tension_s: Matrix3::zeros(),
            tension_m: Matrix3::zeros(),
            sin_ab: [0.0; 3],
            cos_ab: [0.0; 3],
            type_ii_measure: f64::NAN,
        };
        let balance = self.chord_kinetics(&mut out, &chords, eta);
        self.chord_tensions(t, eta, &rigid, &mut out, &balance)?;
        Ok(out)
    }

    /// The chords of the deflected links: `L_i = l - (1/(2l)) eta_i^T G0 eta_i`, its rate
    /// and the part of `L_i''` without `eta''` (module documentation), or the link lengths
    /// without foreshortening; fills `scratch.g0_eta` (`G0 eta / l`), `scratch.inv_g0_eta`
    /// and `scratch.length_gradient` (`dL / d eta`).
    fn foreshortened_chords(&mut self, eta: &[f64], eta_dot: &[f64]) -> Chords {
        let mut chords = Chords {
            lengths: [0.0; 3],
            length_dot: [0.0; 3],
            length_ddot0: [0.0; 3],
        };
        for (i, link) in self.links.iter().enumerate() {
            let range = self.offsets[i]..self.offsets[i] + link.r;
            let r = link.r;
            let (e, ed) = (&eta[range.clone()], &eta_dot[range.clone()]);
            let mut quad = 0.0;
            let mut quad_dot = 0.0;
            for j in 0..r {
                let row = &link.g0[j * r..(j + 1) * r];
                let g0e = dot(row, e) / link.length;
                self.scratch.g0_eta[range.start + j] = g0e;
                quad += e[j] * g0e;
                quad_dot += ed[j] * dot(row, ed) / link.length;
            }
            let inv_g0 = &link.inv_geometric[0];
            for j in 0..r {
                self.scratch.inv_g0_eta[range.start + j] =
                    dot(&inv_g0[j * r..(j + 1) * r], e) / link.length;
            }
            if self.options.foreshortening {
                chords.lengths[i] = link.length - 0.5 * quad;
                chords.length_dot[i] = -dot(&self.scratch.g0_eta[range.clone()], ed);
                chords.length_ddot0[i] = -quad_dot;
                for j in range {
                    self.scratch.length_gradient[j] = -self.scratch.g0_eta[j];
                }
            } else {
                chords.lengths[i] = link.length;
                self.scratch.length_gradient[range].fill(0.0);
            }
        }
        chords
    }

    /// The platform that the sliders and `chords` close, and `F^-1`: with foreshortening the
    /// forward kinematics of the chords ([`Self::platform_motion`]; a collapse when it
    /// fails), else the nominal motion with the closure's Jacobian at the nominal pose.
    fn closing_platform(
        &mut self,
        t: f64,
        nominal: PlatformMotion,
        rho: &[[f64; 3]; 3],
        chords: &Chords,
        eta: &[f64],
        rigid: &MachineKinematics,
    ) -> Result<(PlatformMotion, Matrix3<f64>), DynamicsError> {
        if self.options.foreshortening {
            self.counters.forward_kinematics_solves += 1;
            return self
                .platform_motion(
                    t,
                    &nominal.pose,
                    rho,
                    chords.lengths,
                    chords.length_dot,
                    chords.length_ddot0,
                )
                .map_err(|e| self.collapse_or(e, t, eta, rigid, 0.0));
        }
        // Chords of length l: the platform on its nominal path.
        let closure =
            self.machine
                .geometry
                .closure(&nominal.pose, rho.map(|r| r[0]), chords.lengths);
        let f_inv =
            closure
                .pose_jacobian
                .try_inverse()
                .ok_or(DynamicsError::SingularInverseDynamics {
                    t,
                    measure: 0.0,
                    threshold: self.machine.geometry.thresholds.type_ii,
                })?;
        Ok((nominal, f_inv))
    }

    /// Per chord: its direction `e_i` and normal `n_i`, the angle's rate `b_i'`, the part of
    /// `b_i''` without `eta''` and its `eta''` row (`N_i . Q / L_i`), and the link's moment
    /// about `B_i` split the same way (module documentation); into `out`, and the columns
    /// of the platform balance into the returned [`Balance`].
    fn chord_kinetics(&self, out: &mut Kinetics, chords: &Chords, eta: &[f64]) -> Balance {
        let geometry = &self.machine.geometry;
        let (lengths, length_dot) = (chords.lengths, chords.length_dot);
        let rho = out.rho;
        let (sin, cos) = out.pose.phi.sin_cos();
        let rotate = |c: &Vector2<f64>| Vector2::new(cos * c.x - sin * c.y, sin * c.x + cos * c.y);
        let (p, v) = (
            Vector2::new(out.pose.x, out.pose.y),
            Vector2::new(out.velocity.x, out.velocity.y),
        );
        let omega = out.velocity.z;
        let a0 = out.acceleration0;
        // Columns E_i = (e_i, r_i x e_i) and N_i = (n_i, r_i x n_i) of the platform balance.
        let mut balance = Balance {
            e_cols: Matrix3::zeros(),
            n_cols: Matrix3::zeros(),
            measure_cols: Matrix3::zeros(),
            moment0: Vector3::zeros(),
            moment_s: Matrix3::zeros(),
        };
        let centroid = rotate(&geometry.platform_centroid());
        let radius = geometry.platform_radius().max(f64::MIN_POSITIVE);
        for (i, leg) in geometry.legs.iter().enumerate() {
            let link = &self.links[i];
            let range = self.offsets[i]..self.offsets[i] + link.r;
            let u = leg.guide.direction.into_inner();
            let r_i = rotate(&leg.attachment);
            let chord = p + r_i - leg.guide.anchor.coords - rho[i][0] * u;
            let e = chord / lengths[i];
            let nrm = Vector2::new(-e.y, e.x);
            let c_dot = v + omega * Vector2::new(-r_i.y, r_i.x);
            let beta_dot = (c_dot - rho[i][1] * u).dot(&nrm) / lengths[i];
            let big_n = Vector3::new(nrm.x, nrm.y, cross(&r_i, &nrm));
            let sin_ab = u.dot(&nrm);
            let cos_ab = u.dot(&e);
            out.beta0[i] = (big_n.dot(&a0)
                - omega * omega * r_i.dot(&nrm)
                - rho[i][2] * sin_ab
                - 2.0 * length_dot[i] * beta_dot)
                / lengths[i];
            let row = big_n.transpose() * out.q_of_s / lengths[i];
            out.beta_s.set_row(i, &row);
            balance
                .e_cols
                .set_column(i, &Vector3::new(e.x, e.y, cross(&r_i, &e)));
            balance.n_cols.set_column(i, &big_n);
            let column = Vector3::new(e.x, e.y, cross(&(r_i - centroid), &e) / radius);
            balance.measure_cols.set_column(i, &column.normalize());
            // Moment about B_i of the link's inertia forces (the part independent of eta'').
            let mut m0 =
                link.inertia_b * out.beta0[i] + 0.5 * link.mass * link.length * rho[i][2] * sin_ab;
            if self.options.elastic_reactions {
                m0 -= rho[i][2] * cos_ab * dot(&link.mass_psi, &eta[range]);
            }
            balance.moment0[i] = m0 / lengths[i];
            balance
                .moment_s
                .set_row(i, &(row * (link.inertia_b / lengths[i])));
            out.e[i] = e;
            out.n[i] = nrm;
            out.beta_dot[i] = beta_dot;
            out.sin_ab[i] = sin_ab;
            out.cos_ab[i] = cos_ab;
        }
        balance
    }

    /// The chord tensions from the platform's Newton-Euler equations
    /// `M_p q'' = -sum_i (T_i E_i + S_i N_i)` (module documentation), split into the part
    /// without `eta''`, its `s` and its modal-moment rows; refused (a collapse, or a
    /// singular pose) when the actual chords' type-II measure, as
    /// [`crate::equilibrium_measure`], falls below the machine's threshold.
    fn chord_tensions(
        &self,
        t: f64,
        eta: &[f64],
        rigid: &MachineKinematics,
        out: &mut Kinetics,
        balance: &Balance,
    ) -> Result<(), DynamicsError> {
        let geometry = &self.machine.geometry;
        let singular = |measure: f64| {
            let rigid_singular = DynamicsError::SingularInverseDynamics {
                t,
                measure,
                threshold: geometry.thresholds.type_ii,
            };
            self.collapse_or(rigid_singular, t, eta, rigid, measure)
        };
        let measure = balance.measure_cols.determinant().abs();
        if measure.is_nan() || measure < geometry.thresholds.type_ii {
            return Err(singular(measure));
        }
        out.type_ii_measure = measure;
        let e_inv = balance
            .e_cols
            .try_inverse()
            .ok_or_else(|| singular(measure))?;
        let mp = Vector3::new(
            self.machine.platform_mass,
            self.machine.platform_mass,
            self.machine.platform_inertia,
        );
        let n_cols = balance.n_cols;
        out.tension0 = e_inv * (-out.acceleration0.component_mul(&mp) - n_cols * balance.moment0);
        out.tension_s =
            e_inv * (-(Matrix3::from_diagonal(&mp) * out.q_of_s) - n_cols * balance.moment_s);
        if self.options.elastic_reactions {
            let scale = Vector3::from(std::array::from_fn::<f64, 3, _>(|i| {
                self.links[i].length / out.lengths[i]
            }));
            out.tension_m = -(e_inv * n_cols * Matrix3::from_diagonal(&scale));
        }
        Ok(())
    }

    /// [`DynamicsError::Collapse`] when the largest mid-point deflection passes `limit` times
    /// its link's length.
    fn deflection_collapse(
        &self,
        t: f64,
        eta: &[f64],
        measure: f64,
        limit: f64,
    ) -> Option<DynamicsError> {
        (0..3).find_map(|i| {
            let w = dot(&self.links[i].psi_mid, &eta[self.link_range(i)]);
            let length = self.links[i].length;
            (w.abs() > limit * length).then_some(DynamicsError::Collapse {
                t,
                link: i + 1,
                deflection: w,
                length,
                type_ii_measure: measure,
            })
        })
    }

    /// A singular platform pose is a collapse when the nominal (rigid) pose is regular: the
    /// deflection, not the trajectory, made the chords concurrent. Then
    /// [`DynamicsError::Collapse`] with the most deflected link; otherwise `error` unchanged.
    fn collapse_or(
        &self,
        error: DynamicsError,
        t: f64,
        eta: &[f64],
        rigid: &flexprr_kinematics::MachineKinematics,
        measure: f64,
    ) -> DynamicsError {
        let nominal = crate::equilibrium_measure(rigid);
        if nominal.is_nan() || nominal < self.machine.geometry.thresholds.type_ii {
            return error;
        }
        let (link, deflection) = (0..3)
            .map(|i| (i, dot(&self.links[i].psi_mid, &eta[self.link_range(i)])))
            .fold(
                (0, 0.0_f64),
                |a, b| if b.1.abs() > a.1.abs() { b } else { a },
            );
        if deflection.abs() <= 0.0 {
            return error;
        }
        DynamicsError::Collapse {
            t,
            link: link + 1,
            deflection,
            length: self.links[link].length,
            type_ii_measure: measure,
        }
    }

    /// Solves for `eta''` (left in `scratch.acceleration`) and returns `(s, m)`,
    /// `s_j = dL_j . eta_j''`, `m_j = m_xipsi_j . eta_j''`.
    ///
    /// For link `i`, `M eta_i'' = g_i - l m_xipsi_i b_i'' - (G0 eta_i / l) T_i` with
    /// `b'' = beta_0 + Bs s` and `T = T_0 + Ts s + Tm m`, so
    /// `eta_i'' = a_i - l p_i (Bs s)_i - q_i (Ts s + Tm m)_i` with `a_i` the accelerations at
    /// `s = m = 0`, `p_i = M^-1 m_xipsi_i` and `q_i = M^-1 G0 eta_i / l`. Projecting on `dL_i`
    /// and `m_xipsi_i` gives a 6x6 system for `(s, m)` (the Sherman-Morrison-Woodbury
    /// reduction of the `n x n` system, Golub & Van Loan, *Matrix Computations*, 4th ed.,
    /// 2.1.4): cost linear in the modes per right-hand side after the `r x r` products.
    fn solve_accelerations(
        &mut self,
        t: f64,
        y: &[f64],
        kin: &Kinetics,
    ) -> Result<(Vector3<f64>, Vector3<f64>), DynamicsError> {
        let n = self.modes;
        let (eta, eta_dot) = y.split_at(n);
        let Scratch {
            g0_eta: _,
            inv_g0_eta,
            length_gradient,
            acceleration,
        } = &mut self.scratch;
        let mut w = [0.0; 36];
        let mut c = [0.0; 6];
        for (i, link) in self.links.iter().enumerate() {
            let r = link.r;
            let off = self.offsets[i];
            let (e, ed) = (&eta[off..off + r], &eta_dot[off..off + r]);
            let rho_a = link.mass / link.length;
            let (rho_ddot, b_dot) = (kin.rho[i][2], kin.beta_dot[i]);
            // Axial force N(x) = T + P0' + P1 x + P2 x^2 with the tension T at C unknown.
            let p1 = rho_a * rho_ddot * kin.cos_ab[i];
            let p2 = -0.5 * rho_a * b_dot * b_dot;
            let p0_known = -(p1 * link.length + p2 * link.length * link.length);
            let q = &inv_g0_eta[off..off + r];
            let a = &mut acceleration[off..off + r];
            let t0 = kin.tension0[i] + p0_known;
            for (j, aj) in a.iter_mut().enumerate() {
                *aj = -link.inv_mass_psi[j] * rho_ddot * kin.sin_ab[i]
                    - link.length * link.inv_mass_xi_psi[j] * kin.beta0[i]
                    - t0 * q[j]
                    + b_dot * b_dot * e[j];
            }
            mat_vec_acc(&link.inv_flexural, e, -1.0, a);
            mat_vec_acc(&link.inv_geometric[1], e, -p1, a);
            mat_vec_acc(&link.inv_geometric[2], e, -p2 * link.length, a);
            mat_vec_acc(&link.inv_damping, ed, -1.0, a);
            let dl = &length_gradient[off..off + r];
            let p = &link.inv_mass_xi_psi;
            let x = &link.mass_xi_psi;
            let (dla, dlp, dlq) = (dot(dl, a), dot(dl, p), dot(dl, q));
            let (xa, xq) = (dot(x, a), dot(x, q));
            let xp = link.xi_psi_inv_xi_psi;
            c[i] = dla;
            c[3 + i] = xa;
            let l = link.length;
            for col in 0..3 {
                let delta = if col == i { 1.0 } else { 0.0 };
                w[i * 6 + col] =
                    delta + dlp * l * kin.beta_s[(i, col)] + dlq * kin.tension_s[(i, col)];
                w[i * 6 + 3 + col] = dlq * kin.tension_m[(i, col)];
                w[(3 + i) * 6 + col] = xp * l * kin.beta_s[(i, col)] + xq * kin.tension_s[(i, col)];
                w[(3 + i) * 6 + 3 + col] = delta + xq * kin.tension_m[(i, col)];
            }
        }
        self.counters.acceleration_solves += 1;
        solve_in_place(&mut w, &mut c).map_err(|column| {
            DynamicsError::Inconsistent(format!(
                "at t = {t} s the coupled mass matrix is singular (zero pivot in column {column})"
            ))
        })?;
        let s = Vector3::new(c[0], c[1], c[2]);
        let m = Vector3::new(c[3], c[4], c[5]);
        let bs = kin.beta_s * s;
        let tsm = kin.tension_s * s + kin.tension_m * m;
        for (i, link) in self.links.iter().enumerate() {
            let off = self.offsets[i];
            let r = link.r;
            let q = &inv_g0_eta[off..off + r];
            let a = &mut acceleration[off..off + r];
            let lb = link.length * bs[i];
            for j in 0..r {
                a[j] -= lb * link.inv_mass_xi_psi[j] + tsm[i] * q[j];
            }
        }
        Ok((s, m))
    }

    /// The configuration-dependent mass matrix `A(eta, t)` of `A eta'' = g` (row-major
    /// `n x n`; allocating, for inspection and tests): block `(i, j)` is
    /// `delta_ij M + l m_xipsi_i (Bs_ij dL_j^T) + (G0 eta_i / l)(Ts_ij dL_j^T + Tm_ij m_xipsi_j^T)`
    /// (docs/coupled.md). Lagrange's equations make it symmetric: the platform's and chords'
    /// inertia enter through `dq / d eta` and `d b / d eta` on both sides.
    ///
    /// # Errors
    /// As [`CoupledSystem::modal_accelerations`].
    pub fn mass_matrix(&mut self, t: f64, y: &[f64]) -> Result<Vec<f64>, DynamicsError> {
        self.check_state(y)?;
        let kin = self.kinetics(t, y)?;
        let n = self.modes;
        let mut a = vec![0.0; n * n];
        for (i, link) in self.links.iter().enumerate() {
            let (off, r) = (self.offsets[i], link.r);
            let mass = &self.machine.links[i].integrals.mass;
            for j in 0..r {
                let row = (off + j) * n;
                for k in 0..r {
                    a[row + off + k] = mass[(j, k)];
                }
                let lx = link.length * link.mass_xi_psi[j];
                let kj = self.scratch.g0_eta[off + j];
                for (c, other) in self.links.iter().enumerate() {
                    let oc = self.offsets[c];
                    let ws = lx * kin.beta_s[(i, c)] + kj * kin.tension_s[(i, c)];
                    let wm = kj * kin.tension_m[(i, c)];
                    for k in 0..other.r {
                        a[row + oc + k] +=
                            ws * self.scratch.length_gradient[oc + k] + wm * other.mass_xi_psi[k];
                    }
                }
            }
        }
        Ok(a)
    }

    /// Modal accelerations `eta''` at `(t, y)` (allocating; for outputs and tests).
    ///
    /// # Errors
    /// Kinematic failure (forward or inverse), a type-II singular pose, a singular mass matrix.
    pub fn modal_accelerations(&mut self, t: f64, y: &[f64]) -> Result<Vec<f64>, DynamicsError> {
        self.check_state(y)?;
        let kin = self.kinetics(t, y)?;
        self.solve_accelerations(t, y, &kin)?;
        Ok(self.scratch.acceleration.clone())
    }

    /// Platform motion, chord kinematics, axial forces, mid-point deflections and driving
    /// forces at `(t, y)`.
    ///
    /// # Errors
    /// As [`CoupledSystem::modal_accelerations`].
    pub fn output(&mut self, t: f64, y: &[f64]) -> Result<CoupledOutput, DynamicsError> {
        self.check_state(y)?;
        let kin = self.kinetics(t, y)?;
        let (s, m) = self.solve_accelerations(t, y, &kin)?;
        let n = self.modes;
        let (eta, eta_dot) = y.split_at(n);
        let acceleration = kin.acceleration0 + kin.q_of_s * s;
        let beta_ddot = kin.beta0 + kin.beta_s * s;
        let tension = kin.tension0 + kin.tension_s * s + kin.tension_m * m;
        let mut out = CoupledOutput {
            t,
            nominal: kin.nominal,
            platform: PlatformMotion {
                pose: kin.pose,
                velocity: kin.velocity,
                acceleration,
            },
            chord_length: kin.lengths,
            chord_angle: [[0.0; 3]; 3],
            axial_force_b: [0.0; 3],
            axial_force_c: [0.0; 3],
            midpoint_deflection: [0.0; 3],
            driving_force: [0.0; 3],
            axial_stretch: [0.0; 3],
            stretch_pose_correction: [0.0; 3],
        };
        for (i, link) in self.links.iter().enumerate() {
            let range = self.offsets[i]..self.offsets[i] + link.r;
            let (e, ed, acc) = (
                &eta[range.clone()],
                &eta_dot[range.clone()],
                &self.scratch.acceleration[range],
            );
            let (l, mass) = (link.length, link.mass);
            let (rho_ddot, b_dot, b_ddot) = (kin.rho[i][2], kin.beta_dot[i], beta_ddot[i]);
            out.chord_angle[i] = [kin.e[i].y.atan2(kin.e[i].x), b_dot, b_ddot];
            out.axial_force_c[i] = tension[i];
            out.axial_force_b[i] =
                tension[i] - mass * (rho_ddot * kin.cos_ab[i] - 0.5 * b_dot * b_dot * l);
            out.midpoint_deflection[i] = dot(&link.psi_mid, e);
            if let Some(stiffness) = self.options.axial_stiffness {
                // int_0^l N dx for N(x) = P_B + rhoA rho'' cos x - rhoA b'^2 x^2 / 2.
                let rho_a = mass / l;
                let integral = out.axial_force_b[i] * l
                    + 0.5 * rho_a * rho_ddot * kin.cos_ab[i] * l * l
                    - rho_a * b_dot * b_dot * l * l * l / 6.0;
                out.axial_stretch[i] = integral / stiffness[i];
            }
            // Slider force on the link from the link's force balance: the rigid chord inertia
            // plus the elastic transverse and Coriolis/tangential parts, minus the force at C.
            let u = self.machine.geometry.legs[i].guide.direction.into_inner();
            let (ei, ni) = (kin.e[i], kin.n[i]);
            let m_psi_eta = dot(&link.mass_psi, e);
            let transverse = dot(&link.mass_psi, acc) - b_dot * b_dot * m_psi_eta;
            let tangential = -2.0 * b_dot * dot(&link.mass_psi, ed) - b_ddot * m_psi_eta;
            let inertia = mass * (rho_ddot * u + 0.5 * l * (b_ddot * ni - b_dot * b_dot * ei))
                + transverse * ni
                + tangential * ei;
            let mom = link.inertia_b * b_ddot
                + 0.5 * mass * l * rho_ddot * kin.sin_ab[i]
                + if self.options.elastic_reactions {
                    l * m[i] - rho_ddot * kin.cos_ab[i] * m_psi_eta
                } else {
                    0.0
                };
            let f_c = tension[i] * ei + (mom / kin.lengths[i]) * ni;
            let f_b = inertia - f_c;
            out.driving_force[i] = self.machine.slider_mass[i] * rho_ddot + f_b.dot(&u);
        }
        if self.options.axial_stiffness.is_some() {
            // F dq = L stretch with F the closure's pose Jacobian, Q = F^-1 diag(L).
            let dq = kin.q_of_s * Vector3::from(out.axial_stretch);
            out.stretch_pose_correction = [dq.x, dq.y, dq.z];
        }
        Ok(out)
    }

    fn check_state(&self, y: &[f64]) -> Result<(), DynamicsError> {
        if y.len() != 2 * self.modes {
            return Err(DynamicsError::Inconsistent(format!(
                "state has {} entries, the coupled system {}",
                y.len(),
                2 * self.modes
            )));
        }
        Ok(())
    }

    fn fail(&mut self, error: DynamicsError, dy: &mut [f64]) {
        if self.failure.is_none() {
            self.failure = Some(error);
        }
        dy.fill(f64::NAN);
    }
}

impl OdeSystem for CoupledSystem {
    fn dim(&self) -> usize {
        2 * self.modes
    }

    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        self.counters.rhs_evaluations += 1;
        let kin = match self.kinetics(t, y) {
            Ok(kin) => kin,
            Err(e) => return self.fail(e, dy),
        };
        if let Some(limit) = self.options.collapse_deflection {
            let measure = kin.type_ii_measure;
            if let Some(e) = self.deflection_collapse(t, &y[..self.modes], measure, limit) {
                return self.fail(e, dy);
            }
        }
        if let Err(e) = self.solve_accelerations(t, y, &kin) {
            return self.fail(e, dy);
        }
        let n = self.modes;
        dy[..n].copy_from_slice(&y[n..]);
        dy[n..].copy_from_slice(&self.scratch.acceleration);
    }
}
