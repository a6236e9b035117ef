//! The fully nonlinear 3-PRR: each link a chain of co-rotational Euler-Bernoulli elements
//! ([`super::CorotationalElement`]), the sliders prescribed by the rigid inverse kinematics
//! of the trajectory (position control), the platform a free rigid body pinned to the links'
//! last nodes. No small-deflection assumption anywhere: the links may bend, rotate and
//! shorten as far as they like, so the model follows the mechanism through a collapse.
//!
//! Generalized coordinates (model.md notation, `c_i` the platform attachment points):
//!
//! ```text
//! z = (x_p, y_p, phi,  per link i: psi_0, (x_k, y_k, psi_k) for k = 1..N-1, psi_N)
//! node 0 of link i      at B_i(t) = A_i + rho_i(t) u_i          (prescribed; revolute: psi_0 free)
//! node N of link i      at C_i = p + R(phi) c_i                  (pinned to the platform; psi_N free)
//! ```
//!
//! Masses are lumped (Hinton, Rock & Zienkiewicz, "A note on mass lumping and related
//! processes in the finite element method", Earthquake Eng. Struct. Dyn. 4 (1976) 245-249):
//! `rhoA L_e / 2` and rotary inertia `rhoA L_e^3 / 78` per element end. With a constant
//! diagonal mass the equations of the free nodes are explicit,
//! `m_k x_k'' = -f_k(z, z')`, `J_k psi_k'' = -f_psi_k`; the platform carries the links' end
//! nodes, `(M_p + sum_i m_N G_i^T G_i) q'' = -sum_i G_i^T (f_Ni - m_N phi'^2 r_i)` with
//! `G_i = [I | r_i^perp]`, `r_i = R(phi) c_i` (the Newton-Euler equations of the platform
//! with the node masses moving with it: a 3x3 solve per evaluation). `f` is the assembled
//! element internal force plus optional strain-rate damping (Kelvin-Voigt on the local axial
//! stretch and end rotations, as the external ANCF model's axial damping).
//!
//! The initial state is the rigid one, as [`crate::CoupledSystem::initial_state`]: straight,
//! unstrained links on the chords of the rigid inverse kinematics at `t0` with the rigid
//! velocity field `B' + x b' n`, the platform at the nominal pose with the nominal velocity.

use std::sync::Arc;

use flexprr_integrators::OdeSystem;
use flexprr_kinematics::{PlatformMotion, Pose, Trajectory};
use nalgebra::{Matrix3, Vector2, Vector3};

use super::banded::BorderedBanded;
use super::element::{CorotationalElement, LocalStrain, wrap_angle};
use super::inertia::NodalMass;
use crate::actuation::{Actuated, Actuation};
use crate::model::ActuatorState;
use crate::{DynamicsError, Machine};
use flexprr_control::SliderState;
use flexprr_kinematics::MachineState;

/// Half-bandwidth of a link's block of the generalized mass: an element couples the six
/// consecutive coordinates of its two nodes.
pub(super) const MASS_BANDWIDTH: usize = 5;

/// Elements per link of [`NonlinearOptions::paper`], and of scenes (`model.elements`): with
/// the default element ([`LocalStrain::ShallowArch`], [`NodalMass::Consistent`]) within
/// 0.25 % of the converged external model through the 30 Hz collapse (0-64 ms; 0.026 % at 16
/// elements) and within 0.4 % of its whole-machine frequencies, at about 9 times the coupled
/// model's cost under generalized-alpha at rtol 1e-5 (docs/performance.md).
pub const DEFAULT_ELEMENTS: usize = 8;

/// Model switches of a [`NonlinearSystem`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NonlinearOptions {
    /// Elements per link (even, so that the mid-point is a node; at least 2).
    pub elements: usize,
    /// Axial stiffness `EA` of each link (N).
    pub axial_stiffness: [f64; 3],
    /// Bending stiffness `EI` of each link (N m^2). The links are uniform: mass per length
    /// is the machine link's `m / l`.
    pub bending_stiffness: [f64; 3],
    /// Kelvin-Voigt time `beta_a` (s) of the axial damping `N_d = beta_a EA u' / L_e`.
    pub axial_damping_time: f64,
    /// Kelvin-Voigt time `beta_b` (s) of the bending damping `M_d = beta_b M(th')`
    /// (stiffness proportional: damping ratio `beta_b omega / 2` in the mode at `omega`).
    pub bending_damping_time: f64,
    /// Stop with [`DynamicsError::Collapse`] when the type-II measure of the chords falls
    /// below the geometry's threshold.
    pub stop_at_type_ii: bool,
    /// Stop with [`DynamicsError::Collapse`] when a mid-point deflection exceeds this
    /// fraction of its link's length (`None`: no limit).
    pub collapse_deflection: Option<f64>,
    /// The elements' local strain energy ([`LocalStrain`]).
    pub strain: LocalStrain,
    /// The elements' mass ([`NodalMass`]).
    pub mass: NodalMass,
}

impl NonlinearOptions {
    /// Uniform links of the given `EA` and `EI`, `elements` per link, undamped, stopping at a
    /// type-II pose and not at a deflection limit.
    pub fn uniform(elements: usize, axial_stiffness: f64, bending_stiffness: f64) -> Self {
        Self {
            elements,
            axial_stiffness: [axial_stiffness; 3],
            bending_stiffness: [bending_stiffness; 3],
            axial_damping_time: 0.0,
            bending_damping_time: 0.0,
            stop_at_type_ii: true,
            collapse_deflection: None,
            strain: LocalStrain::default(),
            mass: NodalMass::default(),
        }
    }

    /// The paper's links ([`crate::paper`]: `EA = E t h`, `EI = E h t^3 / 12`) with Young's
    /// modulus `youngs_modulus`, [`DEFAULT_ELEMENTS`] elements per link (shallow-arch
    /// elements with consistent masses converge at fourth order: 8 elements put the 30 Hz
    /// collapse's mid-point deflections over 0-64 ms 0.23 % from the converged external ANCF
    /// model; docs/coupled.md).
    pub fn paper(youngs_modulus: f64) -> Self {
        use crate::paper::{HEIGHT, THICKNESS};
        Self::uniform(
            DEFAULT_ELEMENTS,
            youngs_modulus * THICKNESS * HEIGHT,
            youngs_modulus * HEIGHT * THICKNESS.powi(3) / 12.0,
        )
    }
}

/// Work counters of a nonlinear system.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NonlinearCounters {
    /// Right-hand-side evaluations.
    pub rhs_evaluations: usize,
}

/// Everything the nonlinear model reports at one `(t, y)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NonlinearOutput {
    /// Time (s).
    pub t: f64,
    /// The nominal platform motion (the trajectory's).
    pub nominal: PlatformMotion,
    /// The actual platform motion (pose and velocity from the state, acceleration from the
    /// equations of motion).
    pub platform: PlatformMotion,
    /// Slider positions, velocities and accelerations `(rho_i, rho_i', rho_i'')` (m, m/s,
    /// m/s^2): the commanded ones.
    pub slider: [[f64; 3]; 3],
    /// Chord lengths `|C_i - B_i|` (m).
    pub chord_length: [f64; 3],
    /// Chord angles `b_i` (rad).
    pub chord_angle: [f64; 3],
    /// Transverse deflection of each link's mid-point (the middle node) from its chord, along
    /// the chord normal `n = (-sin b, cos b)` (m).
    pub midpoint_deflection: [f64; 3],
    /// Axial force at `B_i`, `-F_B . e` with `F_B` the slider's force on the link (tension
    /// positive, N).
    pub axial_force_b: [f64; 3],
    /// Axial force at `C_i`, `F_C . e` with `F_C` the platform's force on the link (N).
    pub axial_force_c: [f64; 3],
    /// Driving force of each slider along its guide, `m_s rho'' + F_B . u` (N).
    pub driving_force: [f64; 3],
    /// Type-II measure of the chords ([`crate::equilibrium_measure`]'s definition).
    pub type_ii_measure: f64,
    /// Kinetic energy of the links' nodes and the platform, and of the sliders (with the
    /// actuators' reflected inertia) when they are actuated (J).
    pub kinetic_energy: f64,
    /// Strain energy of the links (J).
    pub strain_energy: f64,
    /// Strain energy of each link (J).
    pub link_strain_energy: [f64; 3],
    /// Power the sliders deliver to the links, `sum_i F_B_i . B_i'` (W): the rate of change
    /// of the total energy when there is no damping.
    pub slider_power: f64,
    /// The actuators' commands and outputs, when the sliders are actuated.
    pub actuators: Option<[ActuatorState; 3]>,
}

impl NonlinearOutput {
    /// Platform pose minus the nominal pose `(dx, dy, dphi)` (m, m, rad).
    pub fn pose_deviation(&self) -> [f64; 3] {
        [
            self.platform.pose.x - self.nominal.pose.x,
            self.platform.pose.y - self.nominal.pose.y,
            self.platform.pose.phi - self.nominal.pose.phi,
        ]
    }
}

/// Per-link constants.
#[derive(Debug, Clone, Copy)]
pub(super) struct LinkData {
    pub(super) element: CorotationalElement,
    /// Mass of one element, `rhoA L_e` (kg).
    pub(super) element_mass: f64,
}

/// Prescribed and platform kinematics of one evaluation.
#[derive(Debug, Clone, Copy)]
pub(super) struct Frame {
    /// Time (s).
    pub(super) t: f64,
    pub(super) nominal: PlatformMotion,
    /// The commanded machine (inverse kinematics of the trajectory).
    pub(super) rigid: MachineState,
    pub(super) rho: [[f64; 3]; 3],
    /// `B_i`, `B_i'`, `B_i''` (for actuated sliders `B''` is unknown and set to zero).
    pub(super) b: [[Vector2<f64>; 3]; 3],
    /// `r_i = R(phi) c_i`.
    pub(super) r: [Vector2<f64>; 3],
    /// `C_i`, `C_i'`.
    pub(super) c: [[Vector2<f64>; 2]; 3],
}

/// A patch's two ends: each one's element and position in it (0..1).
type PatchEnds = [(usize, f64); 2];

/// The fully nonlinear 3-PRR as an [`OdeSystem`]: state `y = (z, z')` with `z` the
/// generalized coordinates of the module documentation (`3 + 3 (3 N - 1)` of them).
pub struct NonlinearSystem {
    pub(super) machine: Arc<Machine>,
    trajectory: Arc<dyn Trajectory + Send + Sync>,
    pub(super) options: NonlinearOptions,
    pub(super) links: [LinkData; 3],
    /// Coordinates per link, `3 N - 1`.
    pub(super) per_link: usize,
    /// Nodal force buffer of each link, `3 (N + 1)` entries per link (internal + damping).
    pub(super) forces: Vec<f64>,
    /// The generalized mass of the last evaluation (factorized after a solve).
    pub(super) mass: BorderedBanded,
    /// The generalized forces `F` of the last evaluation, one per coordinate.
    pub(super) generalized: Vec<f64>,
    counters: NonlinearCounters,
    failure: Option<DynamicsError>,
    /// The initial state set by [`NonlinearSystem::start_at`].
    initial: Vec<f64>,
    /// The sliders' actuators and controller, when the sliders are degrees of freedom.
    pub(super) actuated: Option<Actuated>,
    /// The actuator forces of the last evaluation (actuated sliders).
    pub(super) slider_forces: [f64; 3],
    /// External point forces `(link, element, position in the element, force)` and slider
    /// loads (the inputs of linear models; none in a run).
    point_loads: Vec<(usize, usize, f64, f64)>,
    pub(super) slider_loads: [f64; 3],
    /// Piezoelectric patches under a vibration control law, with each end's element and
    /// position in it.
    patches: Option<(crate::patches::PatchLaw, Vec<PatchEnds>)>,
    /// A state-sized work vector for the differenced actuator derivatives (super::tangent).
    pub(super) tangent_work: Vec<f64>,
}

impl std::fmt::Debug for NonlinearSystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NonlinearSystem")
            .field("options", &self.options)
            .field("counters", &self.counters)
            .finish_non_exhaustive()
    }
}

#[inline]
fn cross(a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    a.x * b.y - a.y * b.x
}

#[inline]
pub(super) fn perp(a: &Vector2<f64>) -> Vector2<f64> {
    Vector2::new(-a.y, a.x)
}

impl NonlinearSystem {
    /// Builds the system for a machine (its link lengths and masses; sections from
    /// `options`), a nominal trajectory (the sliders follow its rigid inverse kinematics)
    /// and the options.
    ///
    /// # Errors
    /// An odd or too small number of elements, non-positive stiffnesses, negative damping
    /// times or a non-positive deflection limit.
    pub fn new(
        machine: Arc<Machine>,
        trajectory: Arc<dyn Trajectory + Send + Sync>,
        options: NonlinearOptions,
    ) -> Result<Self, DynamicsError> {
        let invalid =
            |quantity: String, value: f64, reason: &'static str| DynamicsError::InvalidParameter {
                quantity,
                value,
                reason,
            };
        let ne = options.elements;
        if ne < 2 || ne % 2 == 1 {
            return Err(invalid(
                "elements per link".into(),
                ne as f64,
                "must be even and at least 2 (the mid-point is a node)",
            ));
        }
        for i in 0..3 {
            for (name, v) in [
                ("axial stiffness EA", options.axial_stiffness[i]),
                ("bending stiffness EI", options.bending_stiffness[i]),
            ] {
                if !(v.is_finite() && v > 0.0) {
                    return Err(invalid(
                        format!("{name} of link {}", i + 1),
                        v,
                        "must be finite and positive",
                    ));
                }
            }
        }
        for (name, v) in [
            ("axial damping time", options.axial_damping_time),
            ("bending damping time", options.bending_damping_time),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(invalid(name.into(), v, "must be finite and non-negative"));
            }
        }
        if let Some(limit) = options.collapse_deflection {
            if !(limit.is_finite() && limit > 0.0) {
                return Err(invalid(
                    "collapse deflection fraction".into(),
                    limit,
                    "must be finite and positive",
                ));
            }
        }
        let links = std::array::from_fn(|i| {
            let link = &machine.links[i];
            let le = link.length() / ne as f64;
            LinkData {
                element: CorotationalElement {
                    length: le,
                    axial_stiffness: options.axial_stiffness[i],
                    bending_stiffness: options.bending_stiffness[i],
                    strain: options.strain,
                },
                element_mass: link.mass_per_length() * le,
            }
        });
        let per_link = 3 * ne - 1;
        Ok(Self {
            machine,
            trajectory,
            options,
            links,
            per_link,
            forces: vec![0.0; 9 * (ne + 1)],
            mass: BorderedBanded::new(3, per_link, MASS_BANDWIDTH, 3),
            generalized: vec![0.0; 3 + 3 * per_link],
            counters: NonlinearCounters::default(),
            failure: None,
            initial: Vec::new(),
            actuated: None,
            slider_forces: [0.0; 3],
            point_loads: Vec::new(),
            slider_loads: [0.0; 3],
            patches: None,
            tangent_work: vec![0.0; 2 * (3 + 3 * per_link)],
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
    /// The options.
    pub fn options(&self) -> NonlinearOptions {
        self.options
    }
    /// Number of generalized coordinates: the platform's, every link's nodal ones, and the
    /// three sliders' when they are actuated (they come last).
    pub fn coordinates(&self) -> usize {
        3 + 3 * self.per_link + if self.actuated.is_some() { 3 } else { 0 }
    }
    /// Index of slider `i`'s coordinate (actuated sliders).
    pub(super) fn slider_index(&self, i: usize) -> usize {
        3 + 3 * self.per_link + i
    }
    /// The measured sliders of `y` (actuated sliders).
    fn measured_sliders(&self, y: &[f64]) -> [SliderState; 3] {
        let n = self.coordinates();
        std::array::from_fn(|i| SliderState {
            position: y[self.slider_index(i)],
            velocity: y[n + self.slider_index(i)],
            acceleration: 0.0,
        })
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
    /// The first sample time of a sampled controller (slider or vibration law) strictly
    /// after `t`: where the integration must stop next for the zero-order hold.
    pub fn next_sample(&self, t: f64) -> Option<f64> {
        crate::hold::earliest(
            self.actuated.as_ref().and_then(|a| a.next_sample(t)),
            self.patches
                .as_ref()
                .and_then(|(law, _)| law.next_sample(t)),
        )
    }
    /// Range of link `link`'s nodal coordinates (0-based link) among the generalized
    /// coordinates; the platform's three come first.
    pub fn link_range(&self, link: usize) -> std::ops::Range<usize> {
        let start = 3 + link * self.per_link;
        start..start + self.per_link
    }
    /// The state set by [`NonlinearSystem::start_at`], empty before.
    pub(crate) fn start_state(&self) -> &[f64] {
        &self.initial
    }
    /// Work counters so far.
    pub fn counters(&self) -> NonlinearCounters {
        self.counters
    }
    /// Why the integration ended: the collapse found by the terminal event
    /// ([`OdeSystem::terminal_event`], on accepted states), or the latest failure met inside
    /// the right-hand side since the last accepted step (which then writes NaN so the
    /// integrator rejects the trial), such as a kinematic failure.
    pub fn take_failure(&mut self) -> Option<DynamicsError> {
        self.failure.take()
    }

    /// The rigid initial state at `t0`: straight, unstrained links on the rigid chords with
    /// the rigid velocity field, the platform on its nominal pose and velocity.
    ///
    /// # Errors
    /// The rigid inverse kinematics fails at `t0`.
    pub fn initial_state(&self, t0: f64) -> Result<Vec<f64>, DynamicsError> {
        let nominal = self.trajectory.motion(t0);
        let rigid = self
            .machine
            .geometry
            .inverse_kinematics_unchecked(&nominal)
            .map_err(|source| DynamicsError::Kinematics { t: t0, source })?;
        let n = self.coordinates();
        let mut y = vec![0.0; self.dim()];
        if let Some(actuated) = &self.actuated {
            for (i, leg) in rigid.legs.iter().enumerate() {
                y[self.slider_index(i)] = leg.rho;
                y[n + self.slider_index(i)] = leg.rho_dot;
            }
            if actuated.ode_states() > 0 {
                y[2 * n..].copy_from_slice(&actuated.spec.controller.initial_states());
            }
        }
        let (z, zd) = y[..2 * n].split_at_mut(n);
        let p = nominal.pose;
        z[..3].copy_from_slice(&[p.x, p.y, p.phi]);
        zd[..3].copy_from_slice(nominal.velocity.as_slice());
        let ne = self.options.elements;
        for (i, leg) in rigid.legs.iter().enumerate() {
            let off = 3 + i * self.per_link;
            let le = self.links[i].element.length;
            let u = self.machine.geometry.legs[i].guide.direction.into_inner();
            let b_dot = leg.rho_dot * u;
            z[off] = leg.beta;
            zd[off] = leg.beta_dot;
            for k in 1..ne {
                let x = k as f64 * le;
                let pos = leg.b.coords + x * leg.e;
                let vel = b_dot + x * leg.beta_dot * leg.n;
                let j = off + 3 * k - 2;
                z[j..j + 3].copy_from_slice(&[pos.x, pos.y, leg.beta]);
                zd[j..j + 3].copy_from_slice(&[vel.x, vel.y, leg.beta_dot]);
            }
            z[off + 3 * ne - 2] = leg.beta;
            zd[off + 3 * ne - 2] = leg.beta_dot;
        }
        Ok(y)
    }

    /// The same model with the sliders as degrees of freedom, driven along their guides by
    /// `actuation`'s actuators under its controller (docs/control.md), started at `t0` on
    /// the commanded path: each slider carries its mass, the actuator's reflected mass and
    /// half the mass of its link's first node, `(m_s + m_r + m_0) rho'' = F - f_0 . u` with
    /// `f_0` the internal force at the node.
    ///
    /// # Errors
    /// The commanded motion's inverse kinematics fails at `t0`.
    pub fn with_actuation(mut self, actuation: Actuation, t0: f64) -> Result<Self, DynamicsError> {
        self.actuated = Some(Actuated::new(actuation, &self.machine, t0));
        self.mass = BorderedBanded::new(3, self.per_link, MASS_BANDWIDTH, 6);
        self.generalized = vec![0.0; self.coordinates()];
        self.tangent_work = vec![0.0; self.dim()];
        self.start_at(t0)?;
        Ok(self)
    }

    /// Sets the initial state of the integration to the rigid state at `t0`
    /// ([`NonlinearSystem::initial_state`]); [`crate::SceneModel::initial_state`] returns it.
    ///
    /// # Errors
    /// The rigid inverse kinematics fails at `t0`.
    pub fn start_at(&mut self, t0: f64) -> Result<(), DynamicsError> {
        self.initial = self.initial_state(t0)?;
        Ok(())
    }

    /// Transverse deflection (m) of link `link` (0-based) at `xi` (0..1 of the undeformed
    /// length) from its chord `B_i -> C_i`, along the chord normal, at `(t, y)`. Between
    /// nodes the element's centre line is the cubic Hermite curve through its end positions
    /// and tangents `(cos psi, sin psi)` (the co-rotational element's own interpolation of
    /// the transverse displacement, Crisfield 1991, section 7.3, to the order of the local
    /// rotations).
    ///
    /// # Errors
    /// A wrong state length or a kinematic failure.
    pub fn deflection_at(
        &self,
        t: f64,
        link: usize,
        xi: f64,
        y: &[f64],
    ) -> Result<f64, DynamicsError> {
        self.check_state(y)?;
        let frame = self.frame(t, y)?;
        Ok(self.deflection_in(&frame, y, link.min(2), xi))
    }

    /// [`NonlinearSystem::deflection_at`] in a computed frame.
    fn deflection_in(&self, frame: &Frame, y: &[f64], i: usize, xi: f64) -> f64 {
        let (point, _) = self.centre_line(frame, y, i, xi);
        let b = frame.b[i][0];
        let chord = (frame.c[i][0] - b).normalize();
        (point - b).dot(&perp(&chord))
    }

    /// The slope `dw/dx` (rad) of link `link`'s deflection from its chord at `xi`, at
    /// `(t, y)`: the tangent of the element's cubic Hermite centre line in the chord's frame,
    /// `(T . n) / (T . e)`.
    ///
    /// # Errors
    /// A wrong state length or a kinematic failure.
    pub fn slope_at(&self, t: f64, link: usize, xi: f64, y: &[f64]) -> Result<f64, DynamicsError> {
        self.check_state(y)?;
        let frame = self.frame(t, y)?;
        let i = link.min(2);
        let (_, tangent) = self.centre_line(&frame, y, i, xi);
        let chord = (frame.c[i][0] - frame.b[i][0]).normalize();
        Ok(tangent.dot(&perp(&chord)) / tangent.dot(&chord))
    }

    /// The point at `xi` of link `i`'s centre line and its tangent `d r / d xi`: the cubic
    /// Hermite curve through the element's end positions and tangents `(cos psi, sin psi)`.
    fn centre_line(
        &self,
        frame: &Frame,
        y: &[f64],
        i: usize,
        xi: f64,
    ) -> (Vector2<f64>, Vector2<f64>) {
        let ne = self.options.elements;
        let s = xi.clamp(0.0, 1.0) * ne as f64;
        let e = (s.floor() as usize).min(ne - 1);
        let a = s - e as f64;
        let (q1, _) = self.node(y, frame, i, e);
        let (q2, _) = self.node(y, frame, i, e + 1);
        let le = self.links[i].element.length;
        let (p1, p2) = (Vector2::new(q1[0], q1[1]), Vector2::new(q2[0], q2[1]));
        let (t1, t2) = (
            Vector2::new(q1[2].cos(), q1[2].sin()) * le,
            Vector2::new(q2[2].cos(), q2[2].sin()) * le,
        );
        let (h00, h10) = (
            2.0 * a * a * a - 3.0 * a * a + 1.0,
            a * a * a - 2.0 * a * a + a,
        );
        let (h01, h11) = (-2.0 * a * a * a + 3.0 * a * a, a * a * a - a * a);
        let point = p1 * h00 + t1 * h10 + p2 * h01 + t2 * h11;
        let (d00, d10) = (6.0 * a * a - 6.0 * a, 3.0 * a * a - 4.0 * a + 1.0);
        let (d01, d11) = (-6.0 * a * a + 6.0 * a, 3.0 * a * a - 2.0 * a);
        let tangent = p1 * d00 + t1 * d10 + p2 * d01 + t2 * d11;
        (point, tangent)
    }

    /// Sliders from the rigid inverse kinematics of the nominal motion, platform points from
    /// the state.
    pub(super) fn frame(&self, t: f64, y: &[f64]) -> Result<Frame, DynamicsError> {
        let n = self.coordinates();
        let nominal = self.trajectory.motion(t);
        let rigid = self
            .machine
            .geometry
            .inverse_kinematics_unchecked(&nominal)
            .map_err(|source| DynamicsError::Kinematics { t, source })?;
        let (phi, omega) = (y[2], y[n + 2]);
        let (sin, cos) = phi.sin_cos();
        let p = Vector2::new(y[0], y[1]);
        let v = Vector2::new(y[n], y[n + 1]);
        let mut frame = Frame {
            t,
            nominal,
            rigid,
            rho: [[0.0; 3]; 3],
            b: [[Vector2::zeros(); 3]; 3],
            r: [Vector2::zeros(); 3],
            c: [[Vector2::zeros(); 2]; 3],
        };
        let measured = self.actuated.is_some().then(|| self.measured_sliders(y));
        for (i, leg) in self.machine.geometry.legs.iter().enumerate() {
            let s = &frame.rigid.legs[i];
            let u = leg.guide.direction.into_inner();
            // Actuated sliders: from the state, their acceleration still unknown.
            frame.rho[i] = match measured {
                Some(m) => [m[i].position, m[i].velocity, 0.0],
                None => [s.rho, s.rho_dot, s.rho_ddot],
            };
            let [rho, rho_dot, rho_ddot] = frame.rho[i];
            frame.b[i] = [leg.guide.anchor.coords + rho * u, rho_dot * u, rho_ddot * u];
            let a = leg.attachment;
            let r = Vector2::new(cos * a.x - sin * a.y, sin * a.x + cos * a.y);
            frame.r[i] = r;
            frame.c[i] = [p + r, v + omega * perp(&r)];
        }
        Ok(frame)
    }

    /// Coordinates and rates `(x, y, psi)` of node `k` of link `i`.
    #[inline]
    pub(super) fn node(
        &self,
        y: &[f64],
        frame: &Frame,
        i: usize,
        k: usize,
    ) -> ([f64; 3], [f64; 3]) {
        let n = self.coordinates();
        let ne = self.options.elements;
        let off = 3 + i * self.per_link;
        if k == 0 {
            let [b, bd, _] = frame.b[i];
            ([b.x, b.y, y[off]], [bd.x, bd.y, y[n + off]])
        } else if k == ne {
            let [c, cd] = frame.c[i];
            let j = off + 3 * ne - 2;
            ([c.x, c.y, y[j]], [cd.x, cd.y, y[n + j]])
        } else {
            let j = off + 3 * k - 2;
            (
                [y[j], y[j + 1], y[j + 2]],
                [y[n + j], y[n + j + 1], y[n + j + 2]],
            )
        }
    }

    /// Assembles the nodal forces (internal plus damping) of every link into `self.forces`.
    pub(super) fn assemble(&mut self, y: &[f64], frame: &Frame) {
        let ne = self.options.elements;
        let stride = 3 * (ne + 1);
        let (beta_a, beta_b) = (
            self.options.axial_damping_time,
            self.options.bending_damping_time,
        );
        let mut forces = std::mem::take(&mut self.forces);
        forces.fill(0.0);
        for i in 0..3 {
            let el = self.links[i].element;
            let f = &mut forces[i * stride..(i + 1) * stride];
            let (mut q1, mut v1) = self.node(y, frame, i, 0);
            for e in 0..ne {
                let (q2, v2) = self.node(y, frame, i, e + 1);
                let q = [q1[0], q1[1], q1[2], q2[0], q2[1], q2[2]];
                let mut st = el.state(&q);
                if beta_a > 0.0 || beta_b > 0.0 {
                    let [c, s] = st.direction;
                    let (dvx, dvy) = (v2[0] - v1[0], v2[1] - v1[1]);
                    let stretch_rate = c * dvx + s * dvy;
                    let beta_rate = (c * dvy - s * dvx) / st.chord_length;
                    let (w1, w2) = (v1[2] - beta_rate, v2[2] - beta_rate);
                    st.axial_force += beta_a * el.axial_stiffness * stretch_rate / el.length;
                    let k = beta_b * 2.0 * el.bending_stiffness / el.length;
                    st.moments[0] += k * (2.0 * w1 + w2);
                    st.moments[1] += k * (w1 + 2.0 * w2);
                }
                let fe = CorotationalElement::force_from_state(&st);
                for (j, v) in fe.iter().enumerate() {
                    f[3 * e + j] += v;
                }
                (q1, v1) = (q2, v2);
            }
        }
        self.forces = forces;
        self.apply_point_loads(frame);
        self.apply_patches(y, frame);
    }

    /// Sets external loads (the inputs of linear models): a transverse point force on a
    /// link goes to the nodes of its element as the element's consistent load (the cubic
    /// Hermite shape functions: forces `P h00(a)`, `P h01(a)` along the chord normal, moments
    /// `P L_e h10(a)`, `P L_e h11(a)`); a slider load adds to the actuator's force.
    ///
    /// # Errors
    /// A point force off the links.
    pub fn set_loads(&mut self, loads: &crate::ExternalLoads) -> Result<(), DynamicsError> {
        let ne = self.options.elements;
        let mut points = Vec::with_capacity(loads.point.len());
        for p in &loads.point {
            crate::model::check_point_force(p)?;
            let s = p.xi * ne as f64;
            let e = (s.floor() as usize).min(ne - 1);
            points.push((p.link, e, s - e as f64, p.force));
        }
        self.point_loads = points;
        self.slider_loads = loads.slider;
        if let Some(actuated) = self.actuated.as_mut() {
            actuated.set_overrides(loads);
        }
        if let Some((law, _)) = self.patches.as_mut() {
            law.set_overrides(loads);
        }
        Ok(())
    }

    /// Number of piezoelectric patches.
    pub fn patch_count(&self) -> usize {
        self.patches
            .as_ref()
            .map_or(0, |(law, _)| law.patches().len())
    }

    /// The sampled laws at `t` (see [`crate::SceneModel::sampled_laws`]).
    pub fn sampled_laws(&self, t: f64) -> crate::SampledLaws {
        crate::actuation::sampled_laws(
            self.actuated.as_ref(),
            self.patches.as_ref().map_or(0.0, |(law, _)| law.period()),
            t,
        )
    }

    /// What the sampled laws command at a sample at `(t, y)` (see
    /// [`crate::SceneModel::law_sample`]).
    ///
    /// # Errors
    /// A wrong state length, a kinematic failure, or a singular rigid inverse dynamics (the
    /// feedforward).
    pub fn law_sample(
        &mut self,
        t: f64,
        y: &[f64],
        slider_states: &[f64],
    ) -> Result<crate::LawSample, DynamicsError> {
        self.check_state(y)?;
        let frame = self.frame(t, y)?;
        let mut sample = crate::LawSample::default();
        if let Some(actuated) = self.actuated.as_ref().filter(|a| a.period() > 0.0) {
            let input =
                actuated.sample_input(&self.machine, &frame.rigid, t, self.measured_sliders(y))?;
            (sample.slider_command, sample.slider_rates) =
                actuated.law_sample(&input, slider_states);
        }
        if self
            .patches
            .as_ref()
            .is_some_and(|(law, _)| law.period() > 0.0)
        {
            self.sense_patches(y, &frame);
            if let Some((law, _)) = &self.patches {
                sample.patch_command = law.law_voltages(t);
            }
        }
        Ok(sample)
    }

    /// The same model with piezoelectric patches on the links under a vibration control law
    /// (docs/piezo.md), started at `t0`. A patch's sensor reads the rotation of the centre
    /// line between its ends (the slope difference, exact for any deflection); its actuator
    /// puts moments `-k_a V` and `+k_a V` at its ends, each as the consistent nodal load of
    /// its element (forces `C h'(a) / L_e` across the element, moments `C L_e h'(a)` of the
    /// Hermite functions' derivatives).
    ///
    /// # Errors
    /// A bad patch.
    pub fn with_patch_control(
        mut self,
        control: crate::PatchControl,
        t0: f64,
    ) -> Result<Self, DynamicsError> {
        let law = crate::patches::PatchLaw::new(control, t0)?;
        let ne = self.options.elements;
        let place = |xi: f64| {
            let s = xi * ne as f64;
            let e = (s.floor() as usize).min(ne - 1);
            (e, s - e as f64)
        };
        let places = law
            .patches()
            .iter()
            .map(|p| [place(p.xi_start), place(p.xi_end)])
            .collect();
        self.patches = Some((law, places));
        Ok(self)
    }

    /// The angle of link `i`'s centre line at position `a` of element `e`, and its rate.
    fn tangent_angle(
        &self,
        y: &[f64],
        frame: &Frame,
        i: usize,
        (e, a): (usize, f64),
    ) -> (f64, f64) {
        let (q1, v1) = self.node(y, frame, i, e);
        let (q2, v2) = self.node(y, frame, i, e + 1);
        let le = self.links[i].element.length;
        let (d00, d10) = (6.0 * a * a - 6.0 * a, 3.0 * a * a - 4.0 * a + 1.0);
        let (d01, d11) = (-6.0 * a * a + 6.0 * a, 3.0 * a * a - 2.0 * a);
        let (c1, s1) = (q1[2].cos(), q1[2].sin());
        let (c2, s2) = (q2[2].cos(), q2[2].sin());
        let tangent = Vector2::new(q1[0], q1[1]) * d00
            + Vector2::new(c1, s1) * (le * d10)
            + Vector2::new(q2[0], q2[1]) * d01
            + Vector2::new(c2, s2) * (le * d11);
        let rate = Vector2::new(v1[0], v1[1]) * d00
            + Vector2::new(-s1, c1) * (le * v1[2] * d10)
            + Vector2::new(v2[0], v2[1]) * d01
            + Vector2::new(-s2, c2) * (le * v2[2] * d11);
        (
            tangent.y.atan2(tangent.x),
            cross(&tangent, &rate) / tangent.norm_squared(),
        )
    }

    /// The patches' sensors from the state (their laws' sensor buffers).
    fn sense_patches(&mut self, y: &[f64], frame: &Frame) {
        let Some((mut law, places)) = self.patches.take() else {
            return;
        };
        for (p, place) in places.iter().enumerate() {
            let patch = law.patches()[p];
            let (theta1, rate1) = self.tangent_angle(y, frame, patch.link, place[0]);
            let (theta2, rate2) = self.tangent_angle(y, frame, patch.link, place[1]);
            law.sensors[p] = patch.sensor_constant * wrap_angle(theta2 - theta1);
            law.rates[p] = patch.sensor_constant * (rate2 - rate1);
        }
        self.patches = Some((law, places));
    }

    /// Subtracts the patches' nodal loads at `(t, y)` from the nodal force buffer (after the
    /// law's voltages at the frame's time).
    fn apply_patches(&mut self, y: &[f64], frame: &Frame) {
        if self.patches.is_none() {
            return;
        }
        self.sense_patches(y, frame);
        let Some((mut law, places)) = self.patches.take() else {
            return;
        };
        law.drive(frame.t);
        let stride = 3 * (self.options.elements + 1);
        for (p, place) in places.iter().enumerate() {
            let patch = law.patches()[p];
            let moment = patch.actuator_constant * law.voltage(p);
            let i = patch.link;
            for (&(e, a), c) in place.iter().zip([-moment, moment]) {
                let (q1, _) = self.node(y, frame, i, e);
                let (q2, _) = self.node(y, frame, i, e + 1);
                let chord = Vector2::new(q2[0] - q1[0], q2[1] - q1[1]);
                let length = chord.norm();
                let normal = perp(&(chord / length));
                let (d00, d10) = (6.0 * a * a - 6.0 * a, 3.0 * a * a - 4.0 * a + 1.0);
                let (d01, d11) = (-6.0 * a * a + 6.0 * a, 3.0 * a * a - 2.0 * a);
                let f = &mut self.forces[i * stride..(i + 1) * stride];
                for (node, force, torque) in [(e, d00, d10), (e + 1, d01, d11)] {
                    f[3 * node] -= c * force / length * normal.x;
                    f[3 * node + 1] -= c * force / length * normal.y;
                    f[3 * node + 2] -= c * torque;
                }
            }
        }
        self.patches = Some((law, places));
    }

    /// The patches' states at `(t, y)` (none without patches).
    ///
    /// # Errors
    /// A wrong state length or a kinematic failure.
    pub fn patch_states(
        &mut self,
        t: f64,
        y: &[f64],
    ) -> Result<Vec<crate::PatchState>, DynamicsError> {
        if self.patches.is_none() {
            return Ok(Vec::new());
        }
        self.check_state(y)?;
        let frame = self.frame(t, y)?;
        self.sense_patches(y, &frame);
        Ok(self.patches.as_mut().map_or_else(Vec::new, |(law, _)| {
            law.drive(t);
            law.states()
        }))
    }

    /// Subtracts the external point loads from the nodal force buffer (it holds the internal
    /// forces, which the accelerations oppose).
    fn apply_point_loads(&mut self, frame: &Frame) {
        let stride = 3 * (self.options.elements + 1);
        for &(i, e, a, force) in &self.point_loads {
            let chord = frame.c[i][0] - frame.b[i][0];
            let n = perp(&chord.normalize());
            let le = self.links[i].element.length;
            let (h00, h10) = (
                2.0 * a * a * a - 3.0 * a * a + 1.0,
                a * a * a - 2.0 * a * a + a,
            );
            let (h01, h11) = (-2.0 * a * a * a + 3.0 * a * a, a * a * a - a * a);
            let f = &mut self.forces[i * stride..(i + 1) * stride];
            for (node, shape, moment) in [(e, h00, h10), (e + 1, h01, h11)] {
                f[3 * node] -= force * shape * n.x;
                f[3 * node + 1] -= force * shape * n.y;
                f[3 * node + 2] -= force * le * moment;
            }
        }
    }

    /// Type-II measure of the chords `B_i -> C_i` (as [`crate::equilibrium_measure`]).
    fn measure(&self, frame: &Frame) -> f64 {
        let centroid = (frame.r[0] + frame.r[1] + frame.r[2]) / 3.0;
        let radius = frame
            .r
            .iter()
            .map(|r| (r - centroid).norm())
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        let mut m = Matrix3::zeros();
        for i in 0..3 {
            let e = (frame.c[i][0] - frame.b[i][0]).normalize();
            let moment = cross(&(frame.r[i] - centroid), &e) / radius;
            let col = Vector3::new(e.x, e.y, moment);
            m.set_column(i, &(col / col.norm()));
        }
        m.determinant().abs()
    }

    /// Mid-point deflections from the chords (m).
    fn midpoint_deflections(&self, y: &[f64], frame: &Frame) -> [f64; 3] {
        let mid = self.options.elements / 2;
        std::array::from_fn(|i| {
            let (q, _) = self.node(y, frame, i, mid);
            let b = frame.b[i][0];
            let e = (frame.c[i][0] - b).normalize();
            (Vector2::new(q[0], q[1]) - b).dot(&perp(&e))
        })
    }

    /// The collapse checks of [`NonlinearOptions`] at `(t, y)`: the margin (negative while
    /// no check fires: the largest of the most deflected link's deflection over its limit,
    /// minus one, and one minus the type-II measure over its threshold; NaN for a NaN
    /// measure) and the collapse it describes.
    fn collapse_margin(&self, t: f64, y: &[f64], frame: &Frame) -> (f64, DynamicsError) {
        let measure = self.measure(frame);
        let w = self.midpoint_deflections(y, frame);
        let lengths: [f64; 3] = std::array::from_fn(|i| self.machine.links[i].length());
        let mut margin = f64::NEG_INFINITY;
        if let Some(f) = self.options.collapse_deflection {
            for i in 0..3 {
                margin = margin.max(w[i].abs() / (f * lengths[i]) - 1.0);
            }
        }
        if self.options.stop_at_type_ii {
            let threshold = self.machine.geometry.thresholds.type_ii;
            margin = if measure.is_nan() {
                f64::NAN
            } else {
                margin.max(1.0 - measure / threshold)
            };
        }
        let (link, deflection) =
            (0..3).map(|i| (i, w[i])).fold(
                (0, 0.0_f64),
                |a, b| if b.1.abs() > a.1.abs() { b } else { a },
            );
        let collapse = DynamicsError::Collapse {
            t,
            link: link + 1,
            deflection,
            length: lengths[link],
            type_ii_measure: measure,
        };
        (margin, collapse)
    }

    /// Accelerations `z''` into `acc` (the second block of `dy`): assembles and solves
    /// `M z'' = F` (`self.forces` and the actuators' forces must be assembled).
    pub(super) fn accelerations(
        &mut self,
        t: f64,
        y: &[f64],
        frame: &Frame,
        acc: &mut [f64],
    ) -> Result<(), DynamicsError> {
        self.assemble_equations(y, frame);
        self.solve_equations(t, acc)
    }

    /// The actuators' commands and outputs at `(t, y)` for the frame's commanded state
    /// (the control law's state rates into `rates`); their forces into `slider_forces`.
    pub(super) fn actuate(
        &mut self,
        t: f64,
        y: &[f64],
        frame: &Frame,
        rates: &mut [f64],
    ) -> Result<Option<crate::actuation::Commands>, DynamicsError> {
        let Some(actuated) = self.actuated.as_ref() else {
            return Ok(None);
        };
        let measured = self.measured_sliders(y);
        let states = &y[2 * self.coordinates()..];
        let (command, outputs) =
            actuated.forces(&self.machine, &frame.rigid, t, measured, states, rates)?;
        self.slider_forces = outputs.map(|o| o.force);
        Ok(Some((command, outputs)))
    }

    /// Platform motion, chords, mid-point deflections, axial and driving forces at `(t, y)`.
    ///
    /// # Errors
    /// A wrong state length or a kinematic failure (not the collapse checks: the output of a
    /// collapsed state is still reported).
    pub fn output(&mut self, t: f64, y: &[f64]) -> Result<NonlinearOutput, DynamicsError> {
        self.check_state(y)?;
        let mut frame = self.frame(t, y)?;
        self.assemble(y, &frame);
        let n = self.coordinates();
        let mut rates = vec![0.0; y.len() - 2 * n];
        let actuators = self.actuate(t, y, &frame, &mut rates)?;
        let mut acc = vec![0.0; n];
        self.accelerations(t, y, &frame, &mut acc)?;
        if self.actuated.is_some() {
            for i in 0..3 {
                let rho_ddot = acc[self.slider_index(i)];
                let u = self.machine.geometry.legs[i].guide.direction.into_inner();
                frame.rho[i][2] = rho_ddot;
                frame.b[i][2] = rho_ddot * u;
            }
        }
        let slider_mass = self.slider_masses();
        let ne = self.options.elements;
        let stride = 3 * (ne + 1);
        let omega = y[n + 2];
        let qdd = Vector3::new(acc[0], acc[1], acc[2]);
        let mut out = NonlinearOutput {
            t,
            nominal: frame.nominal,
            platform: PlatformMotion {
                pose: Pose::new(y[0], y[1], y[2]),
                velocity: Vector3::new(y[n], y[n + 1], y[n + 2]),
                acceleration: qdd,
            },
            slider: frame.rho,
            actuators: actuators.map(|(command, outputs)| {
                std::array::from_fn(|i| ActuatorState {
                    command: command[i],
                    output: outputs[i],
                })
            }),
            chord_length: [0.0; 3],
            chord_angle: [0.0; 3],
            midpoint_deflection: self.midpoint_deflections(y, &frame),
            axial_force_b: [0.0; 3],
            axial_force_c: [0.0; 3],
            driving_force: [0.0; 3],
            type_ii_measure: self.measure(&frame),
            kinetic_energy: 0.5
                * (self.machine.platform_mass * (y[n] * y[n] + y[n + 1] * y[n + 1])
                    + self.machine.platform_inertia * omega * omega),
            strain_energy: 0.0,
            link_strain_energy: [0.0; 3],
            slider_power: 0.0,
        };
        for (i, link) in self.links.iter().enumerate() {
            let f = &self.forces[i * stride..(i + 1) * stride];
            let chord = frame.c[i][0] - frame.b[i][0];
            let e = chord.normalize();
            out.chord_length[i] = chord.norm();
            out.chord_angle[i] = wrap_angle(e.y.atan2(e.x));
            // Node 0: F_B = (its inertia) + f_0; node N: F_C = (its inertia) + f_N.
            let first = self.element_inertia_force(&frame, y, &acc, i, 0);
            let last = self.element_inertia_force(&frame, y, &acc, i, ne - 1);
            let f_b = Vector2::new(first[0] + f[0], first[1] + f[1]);
            let f_c = Vector2::new(last[3] + f[3 * ne], last[4] + f[3 * ne + 1]);
            out.axial_force_b[i] = -f_b.dot(&e);
            out.axial_force_c[i] = f_c.dot(&e);
            let u = self.machine.geometry.legs[i].guide.direction.into_inner();
            // Actuated: the slider's equation of motion makes this the actuator's force.
            out.driving_force[i] = slider_mass[i] * frame.rho[i][2] + f_b.dot(&u);
            if self.actuated.is_some() {
                out.kinetic_energy += 0.5 * slider_mass[i] * frame.rho[i][1] * frame.rho[i][1];
            }
            out.slider_power += f_b.dot(&frame.b[i][1]);
            out.kinetic_energy += self.link_kinetic_energy(y, &frame, i);
            let el = link.element;
            for k in 0..ne {
                let (q, v) = self.element_state(y, &frame, i, k);
                let _ = v;
                out.link_strain_energy[i] += el.strain_energy(&el.state(&q));
            }
        }
        out.strain_energy = out.link_strain_energy.iter().sum();
        Ok(out)
    }

    /// Positions of every node of link `link` (0-based) at `(t, y)` (allocating; for plots).
    ///
    /// # Errors
    /// A wrong state length or a kinematic failure.
    pub fn node_positions(
        &self,
        t: f64,
        y: &[f64],
        link: usize,
    ) -> Result<Vec<[f64; 2]>, DynamicsError> {
        self.check_state(y)?;
        let frame = self.frame(t, y)?;
        Ok((0..=self.options.elements)
            .map(|k| {
                let (q, _) = self.node(y, &frame, link.min(2), k);
                [q[0], q[1]]
            })
            .collect())
    }

    fn check_state(&self, y: &[f64]) -> Result<(), DynamicsError> {
        if y.len() != self.dim() {
            return Err(DynamicsError::Inconsistent(format!(
                "state has {} entries, the nonlinear system {}",
                y.len(),
                self.dim()
            )));
        }
        Ok(())
    }

    /// The residual `M(z) acc - F(t, z, z')` of the equations of motion at `(t, y)` into
    /// `out` (the mechanical form's residual: no solve with the mass); NaN and a recorded
    /// failure where the right-hand side would fail.
    pub(super) fn motion_residual(&mut self, t: f64, y: &[f64], acc: &[f64], out: &mut [f64]) {
        self.counters.rhs_evaluations += 1;
        let frame = match self.frame(t, y) {
            Ok(f) => f,
            Err(e) => return self.fail(e, y, out),
        };
        self.assemble(y, &frame);
        // The form exists only without a control law's states: no rates to write.
        if let Err(e) = self.actuate(t, y, &frame, &mut []) {
            return self.fail(e, y, out);
        }
        self.assemble_equations(y, &frame);
        self.equations_residual(acc, out);
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

impl OdeSystem for NonlinearSystem {
    fn dim(&self) -> usize {
        2 * self.coordinates() + self.actuated.as_ref().map_or(0, Actuated::ode_states)
    }

    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        self.counters.rhs_evaluations += 1;
        if let Some(e) = self.actuated.as_ref().and_then(|a| a.failure_at(t)) {
            return self.fail(e, y, dy);
        }
        let frame = match self.frame(t, y) {
            Ok(f) => f,
            Err(e) => return self.fail(e, y, dy),
        };
        self.assemble(y, &frame);
        let n = self.coordinates();
        let (dz, rest) = dy.split_at_mut(n);
        let (dzd, rates) = rest.split_at_mut(n);
        dz.copy_from_slice(&y[n..2 * n]);
        if let Err(e) = self.actuate(t, y, &frame, rates) {
            return self.fail(e, y, dy);
        }
        if let Err(e) = self.accelerations(t, y, &frame, dzd) {
            self.fail(e, y, dy);
        }
    }

    /// The natural scales of the absolute coordinates (positions: the link length; angles:
    /// one radian), so that a node or a link angle passing the frame's origin or zero does
    /// not tighten the error test (`OdeSystem::tolerance_scales`). Velocities and the
    /// controller's states keep their own values.
    fn tolerance_scales(&self, scales: &mut [f64]) -> bool {
        scales.fill(0.0);
        let lengths: [f64; 3] =
            std::array::from_fn(|i| self.links[i].element.length * self.options.elements as f64);
        let mean = lengths.iter().sum::<f64>() / 3.0;
        scales[0] = mean;
        scales[1] = mean;
        scales[2] = 1.0;
        for (link, length) in lengths.iter().enumerate() {
            for (k, scale) in scales[self.link_range(link)].iter_mut().enumerate() {
                // psi_0, (x_k, y_k, psi_k) for k = 1..N-1, psi_N
                *scale = if k == 0 || k % 3 == 0 || k + 1 == self.per_link {
                    1.0
                } else {
                    *length
                };
            }
        }
        if self.actuated.is_some() {
            for i in 0..3 {
                scales[self.slider_index(i)] = mean;
            }
        }
        true
    }

    /// A sampled controller's next sample ([`NonlinearSystem::next_sample`]).
    fn next_stop(&self, t: f64) -> Option<f64> {
        self.next_sample(t)
    }

    /// A failure met in a rejected trial is forgotten once a step is accepted.
    fn step_accepted(&mut self, _t: f64, _y: &[f64]) {
        self.failure = None;
    }

    /// The collapse checks ([`NonlinearOptions::collapse_deflection`],
    /// [`NonlinearOptions::stop_at_type_ii`]) as a terminal event, decided on accepted
    /// states only; where it is reached the collapse is recorded for
    /// [`NonlinearSystem::take_failure`]. None without checks; where the commanded motion
    /// itself fails (the right-hand side reports that), not reached.
    fn terminal_event(&mut self, t: f64, y: &[f64]) -> Option<f64> {
        if !(self.options.stop_at_type_ii || self.options.collapse_deflection.is_some())
            || y.len() != self.dim()
        {
            return None;
        }
        let Ok(frame) = self.frame(t, y) else {
            return Some(-1.0);
        };
        let (margin, collapse) = self.collapse_margin(t, y, &frame);
        if margin >= 0.0 || margin.is_nan() {
            self.failure = Some(collapse);
        }
        Some(margin)
    }

    /// The mechanical form for implicit integrators (super::tangent); none when a
    /// continuous control law adds first-order states.
    fn second_order_form(&mut self) -> Option<&mut dyn flexprr_integrators::SecondOrderForm> {
        if self.actuated.as_ref().is_some_and(|a| a.ode_states() > 0) {
            return None;
        }
        Some(self)
    }

    /// A sampled controller takes its sample when a segment starts at one of its sample
    /// times (they are stop times: [`NonlinearSystem::next_sample`]).
    fn segment_start(&mut self, t: f64, y: &[f64]) {
        if y.len() != self.dim() {
            return;
        }
        if self.patches.is_some() {
            if let Ok(frame) = self.frame(t, y) {
                self.sense_patches(y, &frame);
                if let Some((law, _)) = self.patches.as_mut() {
                    law.sample(t);
                }
            }
        }
        if self.actuated.is_none() {
            return;
        }
        let measured = self.measured_sliders(y);
        if let Some(actuated) = self.actuated.as_mut() {
            actuated.sample_at(&self.machine, self.trajectory.as_ref(), t, measured);
        }
    }
}
