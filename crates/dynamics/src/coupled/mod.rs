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

use flexprr_integrators::OdeSystem;
use flexprr_kinematics::{PlatformMotion, Trajectory};
use nalgebra::Vector2;

use crate::actuation::{Actuated, Actuation};
use crate::{DynamicsError, Machine, ModalDamping};

mod elastic;
mod kinetics;
mod links;
mod output;
mod solve;

use links::LinkData;

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
    /// [`DynamicsError::UnknownCoupling`] naming it.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "ked" => Ok(CouplingModel::Ked),
            "coupled" => Ok(CouplingModel::Coupled),
            "nonlinear" => Ok(CouplingModel::Nonlinear),
            _ => Err(DynamicsError::UnknownCoupling { name: s.into() }),
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
    /// With [`CoupledOptions::axial_stiffness`] given, linear analyses at rest relax the
    /// chords into the links' axial springs `EA / l`
    /// ([`crate::LinearHints::chord_compliance`]); off, they keep them rigid (the paper's
    /// pinned-pinned idealisation of the locked machine).
    pub elastic_chords_at_rest: bool,
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
            elastic_chords_at_rest: true,
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
            elastic_chords_at_rest: true,
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
    /// Rigid inverse-dynamics solves (the feedforward of actuated sliders).
    pub inverse_dynamics_solves: usize,
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
    /// Slider positions, velocities and accelerations `(rho_i, rho_i', rho_i'')` (m, m/s,
    /// m/s^2): the commanded ones.
    pub slider: [[f64; 3]; 3],
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
    /// The actuators' commands and outputs, when the sliders are actuated.
    pub actuators: Option<[crate::model::ActuatorState; 3]>,
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
    /// The change of `eta''` per unit slider acceleration, stacked (`n`; actuated sliders).
    slider_change: Vec<f64>,
    /// The accelerations the piezoelectric patches give (`n`; with patches).
    patch: Vec<f64>,
}

/// The coupled rigid-flexible 3-PRR as an [`OdeSystem`]: state
/// `y = (eta_1, eta_2, eta_3, eta_1', eta_2', eta_3')` as in [`crate::ModalSystem`] with the
/// sliders on their commanded path; with actuated sliders ([`CoupledSystem::with_actuation`])
/// `y = (eta, rho, eta', rho', z)` with `z` the states of a continuous control law.
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
    /// The sliders' actuators and controller, when the sliders are degrees of freedom.
    actuated: Option<Actuated>,
    /// The initial state (set by [`CoupledSystem::with_actuation`]; zero otherwise).
    initial: Vec<f64>,
    /// External loads (the inputs of linear models; none in a run).
    loads: AppliedLoads,
    /// Piezoelectric patches under a vibration control law (none by default).
    patches: Option<crate::patches::PatchLoop>,
}

/// External loads as the equations use them.
#[derive(Debug, Clone, Default)]
struct AppliedLoads {
    /// `M^-1 sum F psi(xi)` per modal coordinate (`n`; empty without point forces).
    modal: Vec<f64>,
    /// Moment about `B_i` of the point forces on link `i`, `sum F x` (N m).
    moment: [f64; 3],
    /// Sum of the point forces on link `i` (N).
    transverse: [f64; 3],
    /// Forces on the sliders along their guides (N).
    slider: [f64; 3],
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
                slider_change: vec![0.0; modes],
                patch: vec![0.0; modes],
            },
            counters: CoupledCounters::default(),
            failure: None,
            actuated: None,
            initial: vec![0.0; 2 * modes],
            loads: AppliedLoads::default(),
            patches: None,
        })
    }

    /// The same model with the sliders as degrees of freedom, driven along their guides by
    /// `actuation`'s actuators under its controller (docs/control.md), started at `t0` on
    /// the commanded path: sliders at `rho_ref(t0)` with `rho_ref'(t0)`, links straight at
    /// rest relative to their chords, the control law's initial states.
    ///
    /// # Errors
    /// The commanded motion's inverse kinematics fails at `t0`.
    pub fn with_actuation(mut self, actuation: Actuation, t0: f64) -> Result<Self, DynamicsError> {
        let actuated = Actuated::new(actuation, &self.machine, t0, self.modes + 3);
        let nominal = self.trajectory.motion(t0);
        let rigid = self
            .machine
            .geometry
            .inverse_kinematics_unchecked(&nominal)
            .map_err(|source| DynamicsError::Kinematics { t: t0, source })?;
        let mut y = vec![0.0; actuated.dim()];
        actuated.start(&rigid, &mut y);
        self.initial = y;
        self.actuated = Some(actuated);
        Ok(self)
    }

    /// Applies external loads from now on (the inputs of linear models): a point force `F`
    /// at `x` on link `i` adds `F psi_j(x / l)` to its modal forces and `F x` to the moment
    /// about `B_i` of the link's balance, and `F sin(a - b)` to the slider's (docs/linear.md).
    ///
    /// # Errors
    /// A point force off the links.
    pub fn set_loads(&mut self, loads: &crate::ExternalLoads) -> Result<(), DynamicsError> {
        use faer::linalg::solvers::Solve;
        let mut applied = AppliedLoads {
            slider: loads.slider,
            ..AppliedLoads::default()
        };
        let mut modal = vec![0.0; self.modes];
        for p in &loads.point {
            crate::model::check_point_force(p)?;
            let link = &self.machine.links[p.link];
            applied.moment[p.link] += p.force * p.xi * link.length();
            applied.transverse[p.link] += p.force;
            for (j, k) in self.link_range(p.link).enumerate() {
                modal[k] += p.force * link.basis.eval(j, p.xi)[0];
            }
        }
        if !loads.point.is_empty() {
            for i in 0..3 {
                let range = self.link_range(i);
                let ints = &self.machine.links[i].integrals;
                let rhs = faer::Mat::from_fn(range.len(), 1, |j, _| modal[range.start + j]);
                let solved = ints
                    .mass
                    .llt(faer::Side::Lower)
                    .map_err(|_| DynamicsError::ModalMass { link: i + 1 })?
                    .solve(&rhs);
                for j in 0..range.len() {
                    modal[range.start + j] = solved[(j, 0)];
                }
            }
            applied.modal = modal;
        }
        self.loads = applied;
        if let Some(actuated) = self.actuated.as_mut() {
            actuated.set_overrides(loads);
        }
        if let Some(patches) = self.patches.as_mut() {
            patches.law_mut().set_overrides(loads);
        }
        Ok(())
    }

    /// Number of piezoelectric patches.
    pub fn patch_count(&self) -> usize {
        self.patches.as_ref().map_or(0, |p| p.law().patches().len())
    }

    /// The sampled laws at `t` (see [`crate::ControlLaws::sampled_laws`]).
    pub fn sampled_laws(&self, t: f64) -> crate::SampledLaws {
        crate::actuation::sampled_laws(
            self.actuated.as_ref(),
            self.patches.as_ref().map_or(0.0, |p| p.law().period()),
            t,
        )
    }

    /// What the sampled laws command at a sample at `(t, y)` (see
    /// [`crate::ControlLaws::law_sample`]).
    ///
    /// # Errors
    /// A kinematic failure, or a singular rigid inverse dynamics (the feedforward).
    pub fn law_sample(
        &mut self,
        t: f64,
        y: &[f64],
        slider_states: &[f64],
    ) -> Result<crate::LawSample, DynamicsError> {
        self.check_state(y)?;
        let mut sample = crate::LawSample::default();
        if let Some(actuated) = self.actuated.as_ref().filter(|a| a.period() > 0.0) {
            let rigid = self
                .machine
                .geometry
                .inverse_kinematics_unchecked(&self.trajectory.motion(t))
                .map_err(|source| DynamicsError::Kinematics { t, source })?;
            (sample.slider_command, sample.slider_rates) =
                actuated.law_sample_at(&self.machine, &rigid, t, y, slider_states)?;
        }
        let (eta, eta_dot) = self.elastic_state(y);
        let (eta, eta_dot) = (eta.to_vec(), eta_dot.to_vec());
        if let Some(patches) = self.patches.as_mut().filter(|p| p.law().period() > 0.0) {
            sample.patch_command = patches.law_voltages(t, &eta, &eta_dot);
        }
        Ok(sample)
    }

    /// The same model with piezoelectric patches on the links under a vibration control law
    /// (docs/piezo.md), started at `t0`: the patches' moments act on the links' modal
    /// equations only (equal and opposite, they leave the joint reactions alone).
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
        let (eta, eta_dot) = self.elastic_state(y);
        let (eta, eta_dot) = (eta.to_vec(), eta_dot.to_vec());
        self.patches
            .as_mut()
            .map_or_else(Vec::new, |p| p.states(t, &eta, &eta_dot))
    }

    /// Slider masses (kg), with the actuators' reflected masses when actuated.
    pub fn slider_masses(&self) -> [f64; 3] {
        self.actuated
            .as_ref()
            .map_or(self.machine.slider_mass, |a| a.slider_mass)
    }

    /// The actuation, when the sliders are degrees of freedom.
    pub fn actuation(&self) -> Option<&Actuation> {
        self.actuated.as_ref().map(|a| &a.spec)
    }

    /// Number of generalized coordinates: the modal ones, and the three sliders when they
    /// are degrees of freedom.
    pub fn coordinates(&self) -> usize {
        self.modes + if self.actuated.is_some() { 3 } else { 0 }
    }

    /// The modal coordinates and their rates in `y`.
    fn elastic_state<'a>(&self, y: &'a [f64]) -> (&'a [f64], &'a [f64]) {
        let (n, coordinates) = (self.modes, self.coordinates());
        (&y[..n], &y[coordinates..coordinates + n])
    }

    /// The first sample time of a sampled controller (slider or vibration law) strictly
    /// after `t`: where the integration must stop next for the zero-order hold.
    pub fn next_sample(&self, t: f64) -> Option<f64> {
        crate::hold::earliest(
            self.actuated.as_ref().and_then(|a| a.next_sample(t)),
            self.patches.as_ref().and_then(|p| p.next_sample(t)),
        )
    }

    /// The actuators' force commands and outputs at `(t, y)` (the control law's state rates
    /// into `rates`), for the commanded state `rigid` at `t`.
    fn actuator_forces(
        &mut self,
        t: f64,
        y: &[f64],
        rigid: &flexprr_kinematics::MachineKinematics,
        rates: &mut [f64],
    ) -> Result<Option<crate::actuation::Commands>, DynamicsError> {
        let Some(actuated) = self.actuated.as_ref() else {
            return Ok(None);
        };
        self.counters.inverse_dynamics_solves += 1;
        actuated.forces(&self.machine, rigid, t, y, rates).map(Some)
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
    /// Number of modal coordinates (the first entries of the state; half of it unless the
    /// sliders are actuated).
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
    /// The initial state: `eta(0) = 0`, `eta'(0) = 0` (links straight, machine on its rigid
    /// inverse-kinematics path with the rigid velocities), and with actuated sliders those of
    /// [`CoupledSystem::with_actuation`].
    pub fn initial_state(&self) -> Vec<f64> {
        self.initial.clone()
    }
    /// Why the integration ended: the collapse found by the terminal event
    /// ([`OdeSystem::terminal_event`], on accepted states), or the latest failure met inside
    /// the right-hand side since the last accepted step (which then writes NaN so the
    /// integrator rejects the trial): use it to report the real cause.
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

    fn check_state(&self, y: &[f64]) -> Result<(), DynamicsError> {
        if y.len() != self.dim() {
            return Err(DynamicsError::Dimension {
                what: "state",
                unit: "entries",
                model: "coupled system",
                found: y.len(),
                expected: self.dim(),
            });
        }
        Ok(())
    }

    /// Records `error` and writes NaN so the integrator rejects the trial. The record is
    /// the latest failure met since the last accepted step (the one closest to where the
    /// integration stopped) at a finite state: a stage built from an earlier stage's NaN
    /// fails only as a consequence, and does not replace the cause.
    fn fail(&mut self, error: DynamicsError, y: &[f64], dy: &mut [f64]) {
        if self.failure.is_none() || y.iter().all(|v| v.is_finite()) {
            self.failure = Some(error);
        }
        dy.fill(f64::NAN);
    }
}

impl OdeSystem for CoupledSystem {
    fn dim(&self) -> usize {
        self.actuated.as_ref().map_or(2 * self.modes, Actuated::dim)
    }

    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        self.counters.rhs_evaluations += 1;
        let kin = match self.kinetics(t, y) {
            Ok(kin) => kin,
            Err(e) => return self.fail(e, y, dy),
        };
        if let Some(e) = self.actuated.as_ref().and_then(|a| a.failure_at(t)) {
            return self.fail(e, y, dy);
        }
        let (n, coordinates) = (self.modes, self.coordinates());
        let forces = match self.actuator_forces(t, y, &kin.rigid, &mut dy[2 * coordinates..]) {
            Ok(forces) => forces.map(|(_, outputs)| outputs.map(|o| o.force)),
            Err(e) => return self.fail(e, y, dy),
        };
        let z = match self.solve_accelerations(t, y, &kin, forces.as_ref()) {
            Ok(z) => z,
            Err(e) => return self.fail(e, y, dy),
        };
        dy[..coordinates].copy_from_slice(&y[coordinates..2 * coordinates]);
        dy[coordinates..coordinates + n].copy_from_slice(&self.scratch.acceleration);
        if forces.is_some() {
            dy[coordinates + n..2 * coordinates].copy_from_slice(z.r.as_slice());
        }
    }

    /// A sampled controller's next sample ([`CoupledSystem::next_sample`]).
    fn next_stop(&self, t: f64) -> Option<f64> {
        self.next_sample(t)
    }

    /// A failure met in a rejected trial is forgotten once a step is accepted.
    fn step_accepted(&mut self, _t: f64, _y: &[f64]) {
        self.failure = None;
    }

    /// The collapse ([`CoupledOptions::collapse_deflection`]) as a terminal event, decided on
    /// accepted states only: a mid-point deflection past its limit, or the deflected chords
    /// at a type-II pose while the commanded one is regular (where the right-hand side
    /// cannot be evaluated). The collapse is recorded for [`CoupledSystem::take_failure`].
    /// None without a deflection limit; where the commanded motion itself fails (the
    /// right-hand side reports that), not reached.
    fn terminal_event(&mut self, t: f64, y: &[f64]) -> Option<f64> {
        let limit = self.options.collapse_deflection?;
        if y.len() != self.dim() {
            return None;
        }
        let measure = match self.kinetics(t, y) {
            Ok(kin) => kin.type_ii_measure,
            Err(e @ DynamicsError::Collapse { .. }) => {
                self.failure = Some(e);
                return Some(f64::NAN);
            }
            Err(_) => return Some(-1.0),
        };
        let eta = &y[..self.modes];
        let margin = (0..3)
            .map(|i| {
                let w = dot(&self.links[i].psi_mid, &eta[self.link_range(i)]);
                w.abs() / (limit * self.links[i].length) - 1.0
            })
            .fold(f64::NEG_INFINITY, f64::max);
        if margin >= 0.0 || margin.is_nan() {
            self.failure = self.deflection_collapse(t, eta, measure, limit);
        }
        Some(margin)
    }

    /// A sampled controller takes its sample when a segment starts at one of its sample
    /// times (they are stop times: [`CoupledSystem::next_sample`]).
    fn segment_start(&mut self, t: f64, y: &[f64]) {
        if y.len() != self.dim() {
            return;
        }
        if let Some(mut patches) = self.patches.take() {
            let (eta, eta_dot) = self.elastic_state(y);
            patches.sample(t, eta, eta_dot);
            self.patches = Some(patches);
        }
        if let Some(actuated) = self.actuated.as_mut() {
            actuated.sample_at(&self.machine, self.trajectory.as_ref(), t, y);
        }
    }
}
