//! The dynamical system a scene integrates, whatever its model: one trait that the run
//! layer, studies and benchmarks see, so that a new model kind (a geometrically nonlinear
//! link, forward dynamics with actuator forces as inputs) is one more implementation and no
//! edit in the layers above.

use flexprr_integrators::OdeSystem;

use crate::{CoupledSystem, DynamicsError, Machine, ModalSystem, NonlinearSystem};

/// Work counters every scene model reports.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ModelCounters {
    /// Right-hand-side evaluations.
    pub rhs_evaluations: usize,
    /// Rigid inverse-dynamics solves.
    pub inverse_dynamics_solves: usize,
}

/// The dynamical system of a scene: an [`OdeSystem`] whose state holds the links' modal (or
/// nodal) coordinates, with what the layers above need to read it.
///
/// Required: the machine, the state layout per link, the failure a right-hand side met, and
/// the counters. Provided: the zero initial state and the deflection of a link at `xi` from
/// its coordinates through the link's shape functions; a model whose coordinates are not
/// the link's assumed modes overrides [`SceneModel::deflection`].
///
/// ```
/// use flexprr_dynamics::{DynamicsError, Machine, ModelCounters, SceneModel};
/// use flexprr_integrators::OdeSystem;
///
/// /// A stand-in model: three rigid links (no coordinates but one dummy state).
/// struct Rigid(std::sync::Arc<Machine>);
/// impl OdeSystem for Rigid {
///     fn dim(&self) -> usize { 2 }
///     fn rhs(&mut self, _t: f64, _y: &[f64], dy: &mut [f64]) { dy.fill(0.0); }
/// }
/// impl SceneModel for Rigid {
///     fn kind(&self) -> &'static str { "rigid" }
///     fn machine(&self) -> &Machine { &self.0 }
///     fn modes(&self) -> usize { 1 }
///     fn link_range(&self, _link: usize) -> std::ops::Range<usize> { 0..0 }
///     fn take_failure(&mut self) -> Option<DynamicsError> { None }
///     fn counters(&self) -> ModelCounters { ModelCounters::default() }
/// }
/// # let _ = |m: std::sync::Arc<Machine>| Box::new(Rigid(m)) as Box<dyn SceneModel>;
/// ```
pub trait SceneModel: OdeSystem + Send {
    /// The model's name in scene files and outputs (`"ked"`, `"coupled"`).
    fn kind(&self) -> &'static str;
    /// The machine.
    fn machine(&self) -> &Machine;
    /// Number of elastic coordinates (the state holds them, then their rates).
    fn modes(&self) -> usize;
    /// Range of link `link`'s coordinates in the first half of the state.
    fn link_range(&self, link: usize) -> std::ops::Range<usize>;
    /// The first failure met inside the right-hand side (which then writes NaN so the
    /// integrator stops): the real cause of a failed integration.
    fn take_failure(&mut self) -> Option<DynamicsError>;
    /// Work counters so far.
    fn counters(&self) -> ModelCounters;

    /// The initial state: undeflected links at rest (the paper's).
    fn initial_state(&self) -> Vec<f64> {
        vec![0.0; self.dim()]
    }
    /// Transverse deflection (m) of link `link` at `xi` (0..1 along the link) for the state
    /// `y`: `w = sum_j psi_j(xi) eta_j` (the paper's eq. 1).
    fn deflection(&self, link: usize, xi: f64, y: &[f64]) -> f64 {
        self.machine().links[link].deflection(&y[self.link_range(link)], xi)
    }
    /// The link (0-based) and the mode (0-based, within the link) of state component
    /// `component`, and whether it is a rate: the state holds every link's coordinates,
    /// then their rates, in [`Self::link_range`] order. `None` for other components.
    fn component_place(&self, component: usize) -> Option<(usize, usize, bool)> {
        let modes = self.modes();
        let (index, rate) = if component < modes {
            (component, false)
        } else if component < 2 * modes {
            (component - modes, true)
        } else {
            return None;
        };
        (0..3).find_map(|link| {
            let range = self.link_range(link);
            range
                .contains(&index)
                .then(|| (link, index - range.start, rate))
        })
    }
    /// A reader's name for state component `component`, for messages: the link, the mode and
    /// whether it is the coordinate `eta` or its rate (see [`Self::component_place`]).
    fn component_name(&self, component: usize) -> String {
        match self.component_place(component) {
            Some((link, mode, rate)) => format!(
                "{} of link {}, mode {}",
                if rate {
                    "modal rate d(eta)/dt"
                } else {
                    "modal coordinate eta"
                },
                link + 1,
                mode + 1
            ),
            None => format!("state component {component}"),
        }
    }
    /// The KED modal system, when this is one (outputs that need its operators).
    fn as_modal(&mut self) -> Option<&mut ModalSystem> {
        None
    }
    /// The coupled system, when this is one (platform deviation and coupled forces).
    fn as_coupled(&mut self) -> Option<&mut CoupledSystem> {
        None
    }
    /// The geometrically nonlinear system, when this is one (its outputs need the time).
    fn as_nonlinear(&mut self) -> Option<&mut NonlinearSystem> {
        None
    }
    /// Whether [`SceneModel::deflection`] is linear in the coordinates and needs no time
    /// (true for modal models). When false, the divergence guard, which tabulates the
    /// deflection once per coordinate, does not apply; such a model checks its own limits.
    fn linear_deflection(&self) -> bool {
        true
    }
}

impl SceneModel for ModalSystem {
    fn kind(&self) -> &'static str {
        "ked"
    }
    fn machine(&self) -> &Machine {
        ModalSystem::machine(self)
    }
    fn modes(&self) -> usize {
        ModalSystem::modes(self)
    }
    fn link_range(&self, link: usize) -> std::ops::Range<usize> {
        ModalSystem::link_range(self, link)
    }
    fn take_failure(&mut self) -> Option<DynamicsError> {
        ModalSystem::take_failure(self)
    }
    fn counters(&self) -> ModelCounters {
        let c = ModalSystem::counters(self);
        ModelCounters {
            rhs_evaluations: c.rhs_evaluations,
            inverse_dynamics_solves: c.inverse_dynamics_solves,
        }
    }
    fn as_modal(&mut self) -> Option<&mut ModalSystem> {
        Some(self)
    }
}

impl SceneModel for CoupledSystem {
    fn kind(&self) -> &'static str {
        "coupled"
    }
    fn machine(&self) -> &Machine {
        CoupledSystem::machine(self)
    }
    fn modes(&self) -> usize {
        CoupledSystem::modes(self)
    }
    fn link_range(&self, link: usize) -> std::ops::Range<usize> {
        CoupledSystem::link_range(self, link)
    }
    fn take_failure(&mut self) -> Option<DynamicsError> {
        CoupledSystem::take_failure(self)
    }
    fn counters(&self) -> ModelCounters {
        ModelCounters {
            rhs_evaluations: CoupledSystem::counters(self).rhs_evaluations,
            inverse_dynamics_solves: 0,
        }
    }
    fn as_coupled(&mut self) -> Option<&mut CoupledSystem> {
        Some(self)
    }
}
