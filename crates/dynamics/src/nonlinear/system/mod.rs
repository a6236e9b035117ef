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
use flexprr_kinematics::MachineState;

mod control;
mod geometry;
mod output;
mod rhs;
mod state;

pub use output::NonlinearOutput;

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
}
