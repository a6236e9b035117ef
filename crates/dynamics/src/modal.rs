//! The modal system of the three links: the time-varying ODE of eq. (16) (paper) or of
//! model.md section 6 (consistent), as an [`flexprr_integrators::OdeSystem`].
//!
//! State: `y = (eta_1, eta_2, eta_3, eta_1', eta_2', eta_3')` with `eta_i` the `r_i` modal
//! coordinates of link `i` (the paper's ordering, eq. 3). For link `i`:
//!
//! ```text
//! eta'' = M^-1 [ -rho'' sin(a - b) m_psi - l b'' m_xipsi  (+ rho' b' cos(a - b) m_psi)   forcing (+ F_fg)
//!               - (Kf + (P0/l) G0 + P1 G1 + P2 l G2) eta  (+ b'^2 M eta)                 stiffness (- softening)
//!               - C eta' ]                                                               modal damping
//! ```
//! with `m_psi = l int rhoA psi` and `m_xipsi = l int rhoA xi psi`. All products with `M^-1`
//! are formed once at construction, so the right-hand side is a few `r x r` matrix-vector
//! products per link after the inverse kinematics (and, if the axial force model needs them,
//! the rigid joint reactions). It allocates nothing.

use std::sync::Arc;

use faer::linalg::solvers::DenseSolveCore;
use faer::{Mat, MatMut, Side};
use flexprr_beam::{AxialLoad, Coupling};
use flexprr_integrators::OdeSystem;
use flexprr_kinematics::{MachineKinematics, MachineState, Trajectory};

use crate::axial::{AxialForceModel, AxialInput};
use crate::inverse::{ElasticInertia, JointReactions, inverse_dynamics};
use crate::{DynamicsError, Formulation, Machine};

/// Modal damping: ratio `zeta_j` of critical damping per unloaded mode `j`, the same for every
/// link. `C = M Phi diag(2 zeta_j omega_j) Phi^T M` with `Phi` the `M`-orthonormal modes of
/// `(Kf, M)`: exactly `2 zeta_j omega_j m_jj` on the diagonal for the sine basis.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ModalDamping {
    /// One ratio for all modes, or one per mode (in order of increasing frequency).
    pub ratios: Vec<f64>,
}

impl ModalDamping {
    /// No damping.
    pub fn none() -> Self {
        Self { ratios: Vec::new() }
    }
    /// One ratio for every mode.
    pub fn uniform(ratio: f64) -> Self {
        Self {
            ratios: vec![ratio],
        }
    }
    fn ratio(&self, mode: usize) -> f64 {
        match self.ratios.len() {
            0 => 0.0,
            1 => self.ratios[0],
            _ => self.ratios[mode],
        }
    }
    fn is_none(&self) -> bool {
        self.ratios.iter().all(|z| *z == 0.0)
    }
}

/// Per-link operators with `M^-1` applied, row-major `r x r`.
#[derive(Debug, Clone)]
struct LinkOperators {
    r: usize,
    length: f64,
    /// `[M^-1 Kf, M^-1 G0, M^-1 G1, M^-1 G2]` entry by entry (row-major), interleaved so that
    /// the right-hand side reads one contiguous stream per row.
    stiffness: Vec<[f64; 4]>,
    damping: Vec<f64>,
    rho_forcing: Vec<f64>,
    beta_forcing: Vec<f64>,
}

/// A matrix as a row-major vector.
pub(crate) fn to_row_major(m: &Mat<f64>) -> Vec<f64> {
    let (r, c) = (m.nrows(), m.ncols());
    let mut out = Vec::with_capacity(r * c);
    for i in 0..r {
        for j in 0..c {
            out.push(m[(i, j)]);
        }
    }
    out
}

/// Solves `L X = B` in place for lower-triangular `L` (forward substitution, column by column).
pub(crate) fn forward_substitute(l: &Mat<f64>, b: &mut Mat<f64>) {
    let n = l.nrows();
    for c in 0..b.ncols() {
        for i in 0..n {
            let mut sum = b[(i, c)];
            for p in 0..i {
                sum -= l[(i, p)] * b[(p, c)];
            }
            b[(i, c)] = sum / l[(i, i)];
        }
    }
}

/// The modal damping matrix `C = M Phi diag(2 zeta_j omega_j) Phi^T M` of one link, with
/// `Phi` the `M`-orthonormal modes of `(Kf, M)`; `None` when there is no damping.
///
/// With `M = L L^T` and `V` the eigenvectors of `L^-1 Kf L^-T` (eigenvalues `omega_j^2`),
/// `M Phi = L V`, so `C = L V D V^T L^T` (Golub & Van Loan, *Matrix Computations*, 8.7.2).
/// Shared by the KED ([`ModalSystem`]) and coupled models.
///
/// # Errors
/// A ratio list whose length is neither 1 nor `r`, a negative or non-finite ratio, a mass
/// matrix that is not positive definite, or a failed eigen-decomposition.
pub(crate) fn damping_matrix(
    link: &crate::LinkModel,
    damping: &ModalDamping,
    index: usize,
) -> Result<Option<Mat<f64>>, DynamicsError> {
    if damping.is_none() {
        return Ok(None);
    }
    let ints = &link.integrals;
    let r = ints.r();
    if damping.ratios.len() > 1 && damping.ratios.len() != r {
        return Err(DynamicsError::DampingRatios {
            ratios: damping.ratios.len(),
            link: index + 1,
            modes: r,
        });
    }
    if let Some(z) = damping
        .ratios
        .iter()
        .find(|z| !(z.is_finite() && **z >= 0.0))
    {
        return Err(DynamicsError::InvalidParameter {
            quantity: "damping ratio".into(),
            value: *z,
            reason: "must be finite and non-negative",
        });
    }
    let llt = ints
        .mass
        .llt(Side::Lower)
        .map_err(|_| DynamicsError::ModalMass { link: index + 1 })?;
    let l = llt.L().to_owned();
    let mut x = ints.stiffness.clone();
    forward_substitute(&l, &mut x); // L^-1 Kf
    let mut a = x.transpose().to_owned();
    forward_substitute(&l, &mut a); // L^-1 (L^-1 Kf)^T = L^-1 Kf L^-T
    let a = Mat::from_fn(r, r, |i, j| 0.5 * (a[(i, j)] + a[(j, i)]));
    let eig = a
        .self_adjoint_eigen(Side::Lower)
        .map_err(|_| DynamicsError::Eigen { link: index + 1 })?;
    let s = eig.S();
    let d = Mat::from_fn(r, r, |i, j| {
        if i == j {
            2.0 * damping.ratio(i) * s[i].max(0.0).sqrt()
        } else {
            0.0
        }
    });
    let lv = &l * eig.U();
    Ok(Some(&lv * &d * lv.transpose()))
}

impl LinkOperators {
    fn new(
        link: &crate::LinkModel,
        coupling: Coupling,
        damping: &ModalDamping,
        index: usize,
    ) -> Result<Self, DynamicsError> {
        let ints = &link.integrals;
        let r = ints.r();
        let llt = ints
            .mass
            .llt(Side::Lower)
            .map_err(|_| DynamicsError::ModalMass { link: index + 1 })?;
        let m_inv = llt.inverse();
        let apply = |m: &Mat<f64>| to_row_major(&(&m_inv * m));
        let geometric: [Vec<f64>; 3] = std::array::from_fn(|n| {
            let g = &ints.g[n];
            match coupling {
                Coupling::Full => apply(g),
                Coupling::Diagonal => {
                    let d = Mat::from_fn(r, r, |i, j| if i == j { g[(i, i)] } else { 0.0 });
                    apply(&d)
                }
            }
        });
        let vec_apply = |v: &[f64], scale: f64| -> Vec<f64> {
            (0..r)
                .map(|i| scale * (0..r).map(|k| m_inv[(i, k)] * v[k]).sum::<f64>())
                .collect()
        };
        let damping_op = damping_matrix(link, damping, index)?.map_or_else(Vec::new, |c| apply(&c));
        let flexural = apply(&ints.stiffness);
        let stiffness = (0..r * r)
            .map(|idx| {
                [
                    flexural[idx],
                    geometric[0][idx],
                    geometric[1][idx],
                    geometric[2][idx],
                ]
            })
            .collect();
        Ok(Self {
            r,
            length: ints.length,
            stiffness,
            damping: damping_op,
            rho_forcing: vec_apply(&ints.mass_psi, 1.0),
            beta_forcing: vec_apply(&ints.mass_xi_psi, ints.length),
        })
    }
}

/// Work counters of a modal system (how much was evaluated: tests use them to prove that
/// a scene computes only what it needs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counters {
    /// Right-hand-side evaluations.
    pub rhs_evaluations: usize,
    /// Rigid inverse dynamics solves.
    pub inverse_dynamics_solves: usize,
    /// Analytic Jacobian evaluations.
    pub jacobian_evaluations: usize,
}

/// The instantaneous rigid-body data a right-hand side needs.
#[derive(Debug, Clone, Copy)]
pub struct Instant {
    /// Kinematic state.
    pub state: MachineState,
    /// Rigid joint reactions, when computed.
    pub reactions: Option<JointReactions>,
    /// Axial load of each link.
    pub loads: [AxialLoad; 3],
}

/// The modal ODE of the three links under a prescribed platform motion (KED).
pub struct ModalSystem {
    pub(crate) machine: Arc<Machine>,
    trajectory: Arc<dyn Trajectory + Send + Sync>,
    pub(crate) formulation: Formulation,
    pub(crate) damping: ModalDamping,
    axial: Arc<dyn AxialForceModel>,
    ops: [LinkOperators; 3],
    offsets: [usize; 3],
    modes: usize,
    counters: Counters,
    pub(crate) failure: Option<DynamicsError>,
    /// Piezoelectric patches under a vibration control law (none by default).
    patches: Option<crate::patches::PatchLoop>,
}

impl std::fmt::Debug for ModalSystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ModalSystem")
            .field("formulation", &self.formulation)
            .field("modes", &self.modes)
            .field("counters", &self.counters)
            .finish_non_exhaustive()
    }
}

impl ModalSystem {
    /// Builds the system: forms `M^-1 Kf`, `M^-1 Gn`, `M^-1 C` and the forcing vectors once.
    ///
    /// # Errors
    /// A modal mass matrix that is not positive definite, or inconsistent damping.
    pub fn new(
        machine: Arc<Machine>,
        trajectory: Arc<dyn Trajectory + Send + Sync>,
        formulation: Formulation,
        damping: ModalDamping,
    ) -> Result<Self, DynamicsError> {
        let axial = Arc::from(formulation.axial.model());
        Self::with_axial_model(machine, trajectory, formulation, damping, axial)
    }

    /// As [`ModalSystem::new`], with any axial force model in place of the one
    /// `formulation.axial` names (the other switches of `formulation` still apply).
    ///
    /// # Errors
    /// As [`ModalSystem::new`].
    pub fn with_axial_model(
        machine: Arc<Machine>,
        trajectory: Arc<dyn Trajectory + Send + Sync>,
        formulation: Formulation,
        damping: ModalDamping,
        axial: Arc<dyn AxialForceModel>,
    ) -> Result<Self, DynamicsError> {
        let ops = [0, 1, 2].map(|i| {
            LinkOperators::new(
                &machine.links[i],
                formulation.geometric_stiffness,
                &damping,
                i,
            )
        });
        let [a, b, c] = ops;
        let ops = [a?, b?, c?];
        let offsets = [0, ops[0].r, ops[0].r + ops[1].r];
        let modes = offsets[2] + ops[2].r;
        Ok(Self {
            axial,
            machine,
            trajectory,
            formulation,
            damping,
            ops,
            offsets,
            modes,
            counters: Counters::default(),
            failure: None,
            patches: None,
        })
    }

    /// The machine.
    pub fn machine(&self) -> &Machine {
        &self.machine
    }
    /// The formulation.
    pub fn formulation(&self) -> &Formulation {
        &self.formulation
    }
    /// The axial force model.
    pub fn axial_model(&self) -> &Arc<dyn AxialForceModel> {
        &self.axial
    }
    /// The damping.
    pub fn damping(&self) -> &ModalDamping {
        &self.damping
    }
    /// The trajectory.
    pub fn trajectory(&self) -> &Arc<dyn Trajectory + Send + Sync> {
        &self.trajectory
    }
    /// Total number of modal coordinates (half the state dimension).
    pub fn modes(&self) -> usize {
        self.modes
    }
    /// Range of link `i`'s coordinates in `eta`.
    pub fn link_range(&self, link: usize) -> std::ops::Range<usize> {
        self.offsets[link]..self.offsets[link] + self.ops[link].r
    }
    /// Work counters so far.
    pub fn counters(&self) -> Counters {
        self.counters
    }
    /// The zero initial state `eta(0) = 0`, `eta'(0) = 0` (the paper's).
    pub fn initial_state(&self) -> Vec<f64> {
        vec![0.0; 2 * self.modes]
    }
    /// The latest failure met inside the right-hand side since the last accepted step
    /// (which then writes NaN so the integrator rejects the trial): use it to report the
    /// real cause of a failed integration.
    pub fn take_failure(&mut self) -> Option<DynamicsError> {
        self.failure.take()
    }

    /// Kinematics, joint reactions (if the axial model needs them) and axial loads at `t`.
    ///
    /// # Errors
    /// Kinematic failure or a singular inverse dynamics, with the time.
    #[inline]
    pub fn instant(&mut self, t: f64) -> Result<Instant, DynamicsError> {
        let mut state = MachineKinematics::default();
        self.kinematic_state(t, &mut state)?;
        let (reactions, loads) = self.axial_loads(&state, t)?;
        Ok(Instant {
            state: state.with_angles(),
            reactions,
            loads,
        })
    }

    /// Inverse kinematics of the prescribed motion at `t`, in place and without the link
    /// angles (the right-hand side needs only `e`, `n` and the rates).
    #[inline]
    pub(crate) fn kinematic_state(
        &self,
        t: f64,
        state: &mut MachineKinematics,
    ) -> Result<(), DynamicsError> {
        let motion = self.trajectory.motion(t);
        self.machine
            .geometry
            .inverse_kinematics_unchecked_into(&motion, state)
            .map_err(|source| DynamicsError::Kinematics { t, source })
    }

    /// Rigid joint reactions (if the axial model needs them) and the axial load of each link.
    #[inline]
    pub(crate) fn axial_loads(
        &mut self,
        state: &MachineKinematics,
        t: f64,
    ) -> Result<(Option<JointReactions>, [AxialLoad; 3]), DynamicsError> {
        let reactions = if self.axial.needs_inverse_dynamics() {
            self.counters.inverse_dynamics_solves += 1;
            Some(inverse_dynamics(&self.machine, state, None, t)?)
        } else {
            None
        };
        let loads = std::array::from_fn(|i| {
            self.axial.load(&AxialInput {
                leg: &state.legs[i],
                guide_direction: self.machine.geometry.legs[i].guide.direction.into_inner(),
                link: &self.machine.links[i],
                reactions: reactions.as_ref(),
                index: i,
            })
        });
        Ok((reactions, loads))
    }

    /// Modal accelerations `eta''` for the state `y` at the kinematic state `state` with the
    /// axial loads `loads`, written into `out`.
    #[inline]
    fn accelerations(
        &self,
        state: &MachineKinematics,
        loads: &[AxialLoad; 3],
        y: &[f64],
        out: &mut [f64],
    ) {
        let n = self.modes;
        let (eta, eta_dot) = y.split_at(n);
        for (i, op) in self.ops.iter().enumerate() {
            let leg = &state.legs[i];
            let u = self.machine.geometry.legs[i].guide.direction.into_inner();
            let load = &loads[i];
            let (c0, c1, c2) = (load.p0 / op.length, load.p1, load.p2 * op.length);
            let sin_ab = u.dot(&leg.n); // sin(a - b)
            let mut rho_coef = -leg.rho_ddot * sin_ab;
            if self.formulation.coriolis_forcing {
                rho_coef += leg.rho_dot * leg.beta_dot * u.dot(&leg.e); // F_fg, cos(a - b)
            }
            let beta_coef = -leg.beta_ddot;
            let softening = if self.formulation.centrifugal_softening {
                leg.beta_dot * leg.beta_dot
            } else {
                0.0
            };
            let off = self.offsets[i];
            let r = op.r;
            let eta_i = &eta[off..off + r];
            let eta_dot_i = &eta_dot[off..off + r];
            let out_i = &mut out[off..off + r];
            // Row j of M^-1 (Kf + Kp) from the interleaved operators: one contiguous stream.
            for (j, (row, acc_j)) in op
                .stiffness
                .chunks_exact(r)
                .zip(out_i.iter_mut())
                .enumerate()
            {
                let stiffness: f64 = row
                    .iter()
                    .zip(eta_i)
                    .map(|(k, e)| (k[0] + c0 * k[1] + c1 * k[2] + c2 * k[3]) * e)
                    .sum();
                let mut acc = rho_coef * op.rho_forcing[j]
                    + beta_coef * op.beta_forcing[j]
                    + softening * eta_i[j]
                    - stiffness;
                if !op.damping.is_empty() {
                    let d = &op.damping[j * r..(j + 1) * r];
                    acc -= d.iter().zip(eta_dot_i).map(|(d, v)| d * v).sum::<f64>();
                }
                *acc_j = acc;
            }
        }
    }

    /// Modal accelerations `eta''` at `(t, y)` (allocating; for outputs).
    ///
    /// # Errors
    /// As [`ModalSystem::instant`].
    pub fn modal_accelerations(&mut self, t: f64, y: &[f64]) -> Result<Vec<f64>, DynamicsError> {
        let mut state = MachineKinematics::default();
        self.kinematic_state(t, &mut state)?;
        let (_, loads) = self.axial_loads(&state, t)?;
        let mut out = vec![0.0; self.modes];
        self.accelerations(&state, &loads, y, &mut out);
        Ok(out)
    }

    /// The same system with piezoelectric patches on the links under a vibration control
    /// law (docs/piezo.md), started at `t0` (the first sample of a sampled law). The
    /// equations stay linear in the state for a linear law, but the exponential integrators'
    /// linear form does not carry the patches: they are refused for it.
    ///
    /// # Errors
    /// A bad patch.
    pub fn with_patch_control(
        mut self,
        control: crate::PatchControl,
        t0: f64,
    ) -> Result<Self, DynamicsError> {
        self.patches = Some(crate::patches::PatchLoop::new(
            &self.machine,
            self.offsets,
            control,
            t0,
        )?);
        Ok(self)
    }

    /// The patches' states at `(t, y)` (none without patches).
    pub fn patch_states(&mut self, t: f64, y: &[f64]) -> Vec<crate::PatchState> {
        let n = self.modes;
        self.patches
            .as_mut()
            .map_or_else(Vec::new, |p| p.states(t, &y[..n], &y[n..2 * n]))
    }

    /// Number of piezoelectric patches (0 without).
    pub fn patch_count(&self) -> usize {
        self.patches.as_ref().map_or(0, |p| p.law().patches().len())
    }

    /// The first sample time of a sampled vibration law strictly after `t`.
    pub fn next_sample(&self, t: f64) -> Option<f64> {
        self.patches.as_ref().and_then(|p| p.next_sample(t))
    }

    /// Counts one rigid inverse-dynamics solve made for this system's outputs.
    pub(crate) fn count_inverse_dynamics(&mut self) {
        self.counters.inverse_dynamics_solves += 1;
    }

    /// Elastic transverse inertia of each link for modal accelerations `eta_ddot`.
    pub fn elastic_inertia(&self, eta_ddot: &[f64]) -> ElasticInertia {
        let mut e = ElasticInertia::default();
        for i in 0..3 {
            let ints = &self.machine.links[i].integrals;
            let range = self.link_range(i);
            let acc = &eta_ddot[range];
            e.force[i] = acc.iter().zip(&ints.mass_psi).map(|(a, m)| a * m).sum();
            e.moment_about_b[i] = ints.length
                * acc
                    .iter()
                    .zip(&ints.mass_xi_psi)
                    .map(|(a, m)| a * m)
                    .sum::<f64>();
        }
        e
    }

    /// Records `error` (the latest one met since the last accepted step: the one closest to
    /// where the integration stopped) and writes NaN so the integrator rejects the trial.
    fn fail(&mut self, error: DynamicsError, dy: &mut [f64]) {
        self.failure = Some(error);
        dy.fill(f64::NAN);
    }
}

impl OdeSystem for ModalSystem {
    fn dim(&self) -> usize {
        2 * self.modes
    }

    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        self.counters.rhs_evaluations += 1;
        // The kinematic state (without link angles) is filled in place and the loads are
        // used where they are computed (no `Instant` is assembled).
        let mut state = MachineKinematics::default();
        if let Err(e) = self.kinematic_state(t, &mut state) {
            return self.fail(e, dy);
        }
        let loads = match self.axial_loads(&state, t) {
            Ok((_, loads)) => loads,
            Err(e) => return self.fail(e, dy),
        };
        let n = self.modes;
        dy[..n].copy_from_slice(&y[n..]);
        let (_, acc) = dy.split_at_mut(n);
        self.accelerations(&state, &loads, y, acc);
        if let Some(patches) = self.patches.as_mut() {
            patches.accelerate(t, &y[..n], &y[n..], acc);
        }
    }

    /// A sampled vibration law's next sample ([`ModalSystem::next_sample`]).
    fn next_stop(&self, t: f64) -> Option<f64> {
        self.next_sample(t)
    }

    /// A failure met in a rejected trial is forgotten once a step is accepted.
    fn step_accepted(&mut self, _t: f64, _y: &[f64]) {
        self.failure = None;
    }

    fn segment_start(&mut self, t: f64, y: &[f64]) {
        let n = self.modes;
        if let (Some(patches), true) = (self.patches.as_mut(), y.len() == 2 * n) {
            patches.sample(t, &y[..n], &y[n..]);
        }
    }

    /// `J = [[0, I], [-M^-1 K(t) (+ b'^2 I), -M^-1 C]]`, block diagonal per link.
    fn jacobian(&mut self, t: f64, y: &[f64], mut jac: MatMut<'_, f64>) {
        self.counters.jacobian_evaluations += 1;
        if self.patches.is_some() {
            // The control law is any function of the sensors: differenced.
            let mut f0 = vec![0.0; y.len()];
            self.rhs(t, y, &mut f0);
            let mut work = vec![0.0; 2 * y.len()];
            flexprr_integrators::finite_difference_jacobian(self, t, y, &f0, jac, &mut work);
            return;
        }
        let n = self.modes;
        jac.fill(0.0);
        for k in 0..n {
            jac[(k, n + k)] = 1.0;
        }
        let mut state = MachineKinematics::default();
        let loaded = self
            .kinematic_state(t, &mut state)
            .and_then(|()| self.axial_loads(&state, t));
        let loads = match loaded {
            Ok((_, loads)) => loads,
            Err(e) => {
                self.failure = Some(e);
                jac.fill(f64::NAN);
                return;
            }
        };
        for (i, op) in self.ops.iter().enumerate() {
            let leg = &state.legs[i];
            let load = &loads[i];
            let (c0, c1, c2) = (load.p0 / op.length, load.p1, load.p2 * op.length);
            let softening = if self.formulation.centrifugal_softening {
                leg.beta_dot * leg.beta_dot
            } else {
                0.0
            };
            let off = self.offsets[i];
            let r = op.r;
            for j in 0..r {
                for k in 0..r {
                    let idx = j * r + k;
                    let [kf, g0, g1, g2] = op.stiffness[idx];
                    let mut v = -(kf + c0 * g0 + c1 * g1 + c2 * g2);
                    if j == k {
                        v += softening;
                    }
                    jac[(n + off + j, off + k)] = v;
                    if !op.damping.is_empty() {
                        jac[(n + off + j, n + off + k)] = -op.damping[idx];
                    }
                }
            }
        }
    }

    fn has_analytic_jacobian(&self) -> bool {
        self.patches.is_none()
    }

    /// The KED modal equations are linear in the state (see [`crate::linear`]); with
    /// piezoelectric patches under a control law they have no such form here.
    fn linear_form(&mut self) -> Option<&mut dyn flexprr_integrators::LinearSecondOrder> {
        if self.patches.is_some() {
            return None;
        }
        Some(self)
    }
}
