//! The dynamical system a scene integrates, whatever its model: one trait that the run
//! layer, studies and benchmarks see, so that a new model kind (a geometrically nonlinear
//! link, the machine driven by its actuators) is one more implementation and no edit in the
//! layers above.
//!
//! What the layers above read from a model goes through this trait only: the machine at an
//! instant ([`MachineSnapshot`]: platform, sliders, axial and driving forces), the deflection
//! along a link, the energies, and the model's own extra tables. Nothing above asks which
//! model it holds.

mod compliance;
mod coupled;
mod ked;
mod nonlinear;

pub use compliance::{AXIAL_MODES, ChordCompliance};
pub use coupled::NONLINEAR_ADVICE_FRACTION;

use flexprr_integrators::{OdeSystem, Solution};
use flexprr_kinematics::PlatformMotion;

use crate::{Capability, DynamicsError, Machine, Table};

/// Work counters every scene model reports.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ModelCounters {
    /// Right-hand-side evaluations.
    pub rhs_evaluations: usize,
    /// Rigid inverse-dynamics solves.
    pub inverse_dynamics_solves: usize,
}

/// Position, velocity and acceleration of one slider along its guide (m, m/s, m/s^2).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SliderMotion {
    /// `rho_i` (m), from the guide's centre along its direction.
    pub position: f64,
    /// `rho_i'` (m/s).
    pub velocity: f64,
    /// `rho_i''` (m/s^2).
    pub acceleration: f64,
}

/// An actuator at one instant: the force command its controller gave and what it did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ActuatorState {
    /// The controller's force command (N).
    pub command: f64,
    /// The force on the slider, and the motor's torque, speed and saturation where a motor
    /// is modelled.
    pub output: flexprr_control::ActuatorOutput,
}

/// The machine as a model sees it at one `(t, y)`: what outputs, the viewer, studies and
/// benchmarks read, for any model kind.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MachineSnapshot {
    /// Time (s).
    pub t: f64,
    /// The commanded platform motion (the scene's trajectory).
    pub nominal: PlatformMotion,
    /// The platform motion of the model: the commanded one where the model prescribes it
    /// (KED), else the one that follows from the sliders and the links.
    pub platform: PlatformMotion,
    /// The sliders (the commanded ones where the model prescribes them).
    pub sliders: [SliderMotion; 3],
    /// Axial force of each link at `B_i` (tension positive, N).
    pub axial_force_b: [f64; 3],
    /// Axial force of each link at `C_i`: the chord force (tension positive, N).
    pub axial_force_c: [f64; 3],
    /// Force each slider's actuator exerts along its guide (N): the force needed to move it
    /// on its path where the sliders are prescribed.
    pub driving_force: [f64; 3],
    /// The actuators' commands and outputs, where the sliders are driven by actuators under
    /// a controller (`None` where they are prescribed).
    pub actuators: Option<[ActuatorState; 3]>,
}

impl MachineSnapshot {
    /// Platform pose minus the commanded pose `(dx, dy, dphi)` (m, m, rad).
    pub fn pose_deviation(&self) -> [f64; 3] {
        [
            self.platform.pose.x - self.nominal.pose.x,
            self.platform.pose.y - self.nominal.pose.y,
            self.platform.pose.phi - self.nominal.pose.phi,
        ]
    }
}

/// A transverse point force on a link.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PointForce {
    /// The link (0-based).
    pub link: usize,
    /// Where along it (0..1).
    pub xi: f64,
    /// The force along the link's chord normal `n` (positive towards positive `w`, N).
    pub force: f64,
}

/// External loads on a model, and the changes to its control loops, that its linear models
/// apply (docs/linear.md): the inputs (forces, setpoints, patch voltages) and what a
/// linearisation holds fixed or opens. The default changes nothing.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ExternalLoads {
    /// Force on each slider along its guide (N); a prescribed or locked slider takes it in
    /// its drive, so it moves nothing.
    pub slider: [f64; 3],
    /// Transverse point forces on the links.
    pub point: Vec<PointForce>,
    /// Added to the commanded slider positions the slider control law sees (m).
    pub reference: [f64; 3],
    /// Added to the commanded slider velocities the slider control law sees (m/s).
    pub reference_rate: [f64; 3],
    /// Added to each patch's actuator voltage before its limit (V), in the scene's patch
    /// order (shorter: the rest 0).
    pub patch_voltage: Vec<f64>,
    /// Force commands that replace the slider control law's (N) for the sliders given: the
    /// loop opened at that actuator (a sampled law's discretisation, a loop gain). The law
    /// still runs (its states follow the error) and reports its own command.
    pub slider_command: [Option<f64>; 3],
    /// Voltage commands that replace the vibration control law's (V), when given: its loop
    /// opened.
    pub patch_command: Option<Vec<f64>>,
    /// The slider velocities (m/s) at which the actuators' non-smooth friction (Coulomb) is
    /// evaluated instead of the actual ones: a linearisation holds it at its value at the
    /// operating point ([`flexprr_control::Actuator::apply_with_friction_at`]).
    pub friction_velocity: Option<[f64; 3]>,
}

/// The sampled control laws of a model at an instant (docs/linear.md, "Discrete time").
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SampledLaws {
    /// Sample period of the slider control law (s); 0 when it is continuous or absent.
    pub slider_period: f64,
    /// Sample period of the vibration control law of the patches (s); 0 when it is
    /// continuous or absent.
    pub patch_period: f64,
    /// The states of a sampled slider law held at the instant (empty for a law without
    /// states or a continuous one, whose states are in the model's state).
    pub slider_states: Vec<f64>,
}

/// What the sampled control laws command at a sample ([`ControlLaws::law_sample`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LawSample {
    /// The slider law's force commands (N) (0 without a sampled slider law).
    pub slider_command: [f64; 3],
    /// The rates of the slider law's states (advanced by `rate * period` to the next
    /// sample).
    pub slider_rates: Vec<f64>,
    /// The vibration law's voltage commands (V), one per patch (empty without a sampled
    /// vibration law).
    pub patch_command: Vec<f64>,
}

/// Energies of a model's state (J).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ModelEnergies {
    /// Kinetic energy of the whole moving machine model (links, platform and, where they are
    /// degrees of freedom, sliders), when the model has it in closed form.
    pub kinetic: Option<f64>,
    /// Strain energy of each link.
    pub strain: [f64; 3],
    /// Kinetic energy of each link's elastic motion relative to its chord (modal models:
    /// `eta'^T M eta' / 2`).
    pub elastic_kinetic: Option<[f64; 3]>,
}

/// `v^T m v / 2` for a square matrix `m`.
fn half_quadratic_form(m: &faer::Mat<f64>, v: &[f64]) -> f64 {
    let mut s = 0.0;
    for (a, va) in v.iter().enumerate() {
        for (b, vb) in v.iter().enumerate() {
            s += va * m[(a, b)] * vb;
        }
    }
    0.5 * s
}

/// Each link's strain energy `eta^T Kf eta / 2` and elastic kinetic energy
/// `eta'^T M eta' / 2` of a model whose coordinates are the links' assumed modes.
pub(crate) fn modal_energies<M: SceneModel + ?Sized>(model: &M, y: &[f64]) -> ModelEnergies {
    let n = model.modes();
    let mut strain = [0.0; 3];
    let mut kinetic = [0.0; 3];
    for i in 0..3 {
        let ints = &model.machine().links[i].integrals;
        let r = model.link_range(i);
        strain[i] = half_quadratic_form(&ints.stiffness, &y[r.clone()]);
        kinetic[i] = half_quadratic_form(&ints.mass, &y[n + r.start..n + r.end]);
    }
    ModelEnergies {
        kinetic: None,
        strain,
        elastic_kinetic: Some(kinetic),
    }
}

/// The dynamical system of a scene: an [`OdeSystem`] whose state holds the links' modal (or
/// nodal) coordinates, with what the layers above need to read it.
///
/// Required: the machine, the state layout per link, the failure a right-hand side met, the
/// counters, and the machine at an instant ([`SceneModel::snapshot`]). Provided, for models
/// whose coordinates are the links' assumed modes: the zero initial state, the deflection
/// through the links' shape functions and the modal energies. A model with other
/// coordinates overrides them; a model with tables of its own returns them from
/// [`SceneModel::tables`].
///
/// What only some models have is a capability, reached through an accessor that is `None`
/// by default: piezoelectric patches ([`PatchReadout`]), external loads ([`LoadInput`]),
/// hints for linear analyses and outputs ([`LinearHints`]) and control laws
/// ([`ControlLaws`]). A new feature adds a capability, not methods on every model. The
/// queries on `dyn SceneModel` (say [`SceneModel::slider_law`](#method.slider_law)) answer
/// for every model, with the default where it lacks the capability.
///
/// ```
/// use flexprr_dynamics::{DynamicsError, Machine, MachineSnapshot, ModelCounters, SceneModel, SliderMotion};
/// use flexprr_integrators::OdeSystem;
/// use flexprr_kinematics::{PlatformMotion, Pose};
///
/// /// A stand-in model: rigid links (one dummy state), the platform at rest at the origin.
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
///     fn snapshot(&mut self, t: f64, _y: &[f64]) -> Result<MachineSnapshot, DynamicsError> {
///         let rest = PlatformMotion::at_rest(Pose::new(0.0, 0.0, 0.0));
///         Ok(MachineSnapshot {
///             t,
///             nominal: rest,
///             platform: rest,
///             sliders: [SliderMotion::default(); 3],
///             axial_force_b: [0.0; 3],
///             axial_force_c: [0.0; 3],
///             driving_force: [0.0; 3],
///             actuators: None,
///         })
///     }
/// }
/// let model: Box<dyn SceneModel> = Box::new(Rigid(std::sync::Arc::new(
///     flexprr_dynamics::paper::machine(1, 210e9).unwrap(),
/// )));
/// // Without capabilities the queries give the defaults: no control law, a modal deflection,
/// // the platform on its commanded path.
/// assert!(!model.slider_law() && model.linear_deflection() && !model.platform_follows_links());
/// ```
pub trait SceneModel: OdeSystem + Send {
    /// The model's name in scene files and outputs (`"ked"`, `"coupled"`).
    fn kind(&self) -> &'static str;
    /// The machine.
    fn machine(&self) -> &Machine;
    /// Number of generalized coordinates (the state holds them, then their rates).
    fn modes(&self) -> usize;
    /// Range of link `link`'s coordinates in the first half of the state.
    fn link_range(&self, link: usize) -> std::ops::Range<usize>;
    /// The first failure met inside the right-hand side (which then writes NaN so the
    /// integrator stops): the real cause of a failed integration.
    fn take_failure(&mut self) -> Option<DynamicsError>;
    /// Work counters so far.
    fn counters(&self) -> ModelCounters;
    /// The machine at `(t, y)`: platform, sliders, axial and driving forces.
    ///
    /// # Errors
    /// A wrong state length, a kinematic failure or a singular pose, with the time.
    fn snapshot(&mut self, t: f64, y: &[f64]) -> Result<MachineSnapshot, DynamicsError>;

    /// The initial state: undeflected links at rest (the paper's).
    fn initial_state(&self) -> Vec<f64> {
        vec![0.0; self.dim()]
    }
    /// Transverse deflection (m) of link `link` at `xi` (0..1 along the link) for the state
    /// `y` at time `t`, along the chord normal: for modal coordinates
    /// `w = sum_j psi_j(xi) eta_j` (the paper's eq. 1), which needs no time.
    ///
    /// # Errors
    /// A model that needs the time for it (its chord moves with a prescribed slider) may fail
    /// kinematically there.
    fn deflection(&self, t: f64, link: usize, xi: f64, y: &[f64]) -> Result<f64, DynamicsError> {
        let _ = t;
        Ok(self.machine().links[link].deflection(&y[self.link_range(link)], xi))
    }
    /// Slope `dw/dx` of link `link`'s deflection at `xi` (rad) for the state `y` at `t`: for
    /// modal coordinates `sum_j psi_j'(xi) eta_j / l`.
    ///
    /// # Errors
    /// As [`SceneModel::deflection`].
    fn slope(&self, t: f64, link: usize, xi: f64, y: &[f64]) -> Result<f64, DynamicsError> {
        let _ = t;
        let model = &self.machine().links[link];
        let eta = &y[self.link_range(link)];
        let derivative: f64 = eta
            .iter()
            .enumerate()
            .map(|(j, e)| e * model.basis.eval(j, xi)[1])
            .sum();
        Ok(derivative / model.length())
    }
    /// Energies at `(t, y)`: for modal coordinates each link's strain energy
    /// `eta^T Kf eta / 2` and elastic kinetic energy `eta'^T M eta' / 2`.
    ///
    /// # Errors
    /// A model that needs kinematics for them may fail there.
    fn energies(&mut self, t: f64, y: &[f64]) -> Result<ModelEnergies, DynamicsError> {
        let _ = t;
        Ok(modal_energies(self, y))
    }
    /// The model's own tables at the output times of `solution` (say, the coupled model's
    /// platform deviation and chord forces); none by default.
    ///
    /// # Errors
    /// A failure at one of the times, with the time.
    fn tables(&mut self, solution: &Solution) -> Result<Vec<Table>, DynamicsError> {
        let _ = solution;
        Ok(Vec::new())
    }
    /// Advice about the validity of the model's results given the largest deflection a run
    /// reached (m), e.g. that a small-deflection model is past its range; none by default.
    fn deflection_advice(&self, max_deflection: f64) -> Option<String> {
        let _ = max_deflection;
        None
    }

    /// The piezoelectric patches on the links, when the model has them.
    fn patches(&mut self) -> Option<&mut dyn PatchReadout> {
        None
    }
    /// The external loads a linear model applies, when the model takes them.
    fn loads(&mut self) -> Option<&mut dyn LoadInput> {
        None
    }
    /// What linear analyses and outputs may assume of the model, when it differs from the
    /// defaults of [`LinearHints`].
    fn linear_hints(&self) -> Option<&dyn LinearHints> {
        None
    }
    /// [`SceneModel::linear_hints`], for the hints that evaluate the model.
    fn linear_hints_mut(&mut self) -> Option<&mut dyn LinearHints> {
        None
    }
    /// The model's control laws (the sliders' actuators and law, the patches' vibration
    /// law), when it has any.
    fn control(&self) -> Option<&dyn ControlLaws> {
        None
    }
    /// [`SceneModel::control`], for what evaluates the laws.
    fn control_mut(&mut self) -> Option<&mut dyn ControlLaws> {
        None
    }
}

/// Capability of a model with piezoelectric patches on its links ([`SceneModel::patches`]).
pub trait PatchReadout {
    /// Number of patches (in the scene's patch order).
    fn patch_count(&self) -> usize;
    /// The patches' sensors, voltages and powers at `(t, y)`.
    ///
    /// # Errors
    /// A model that needs kinematics for them may fail there.
    fn patch_states(&mut self, t: f64, y: &[f64]) -> Result<Vec<crate::PatchState>, DynamicsError>;
}

/// Capability of a model that takes external loads ([`SceneModel::loads`]): the inputs of
/// its linear models (docs/linear.md).
pub trait LoadInput {
    /// Applies `loads` from now on in the right-hand side; replaces the loads set before.
    ///
    /// # Errors
    /// A load names a link or point that does not exist.
    fn set_loads(&mut self, loads: &ExternalLoads) -> Result<(), DynamicsError>;
}

/// Hints for linear analyses and outputs ([`SceneModel::linear_hints`]); each default is
/// what a model without the capability is taken to be: a modal model whose platform follows
/// the commanded motion.
pub trait LinearHints {
    /// For a model whose chords are axially rigid, at a state at rest (no motion, straight
    /// links): the data that relax the chords into the links' axial springs in a linear
    /// analysis ([`ChordCompliance`]). `None` (the default) for a model whose chords already
    /// stretch, or away from rest, where the linearisation keeps the model as it is.
    ///
    /// # Errors
    /// A kinematic failure at the state.
    fn chord_compliance(
        &mut self,
        t: f64,
        y: &[f64],
    ) -> Result<Option<ChordCompliance>, DynamicsError> {
        let _ = (t, y);
        Ok(None)
    }
    /// Whether the matrices `M`, `C`, `K` of the model's mechanical form
    /// ([`OdeSystem::second_order_form`]) are the exact derivatives of its right-hand side at
    /// `(t, y)`: `A = [0 I; -M^-1 K  -M^-1 C]`. Then a linearisation takes `A` from them
    /// instead of differences. False by default (and wherever a model's tangents are only
    /// good enough for Newton iterations).
    fn exact_mechanical_form(&mut self, t: f64, y: &[f64]) -> bool {
        let _ = (t, y);
        false
    }
    /// Whether [`SceneModel::deflection`] is linear in the coordinates and needs no time
    /// (true for modal models, the default). When false, the divergence guard, which
    /// tabulates the deflection once per coordinate, does not apply; such a model checks its
    /// own limits.
    fn linear_deflection(&self) -> bool {
        true
    }
    /// Whether the platform follows the links (coupled and nonlinear models) rather than the
    /// commanded motion (the default): then its deviation from the commanded pose is a
    /// result worth showing.
    fn platform_follows_links(&self) -> bool {
        false
    }
    /// A reader's name and an identifier of generalized coordinate `k`, where the model's
    /// coordinates are not the links' modes; `None` (the default) for the modal names of
    /// [`SceneModel::coordinate_label`](trait.SceneModel.html#method.coordinate_label).
    fn coordinate_label(&self, k: usize) -> Option<(String, String)> {
        let _ = k;
        None
    }
}

/// Capability of a model under control laws ([`SceneModel::control`]): the sliders'
/// actuators and law, the patches' vibration law.
pub trait ControlLaws {
    /// The sliders' actuators and control law, when the sliders are driven by them (`None`
    /// where the sliders are prescribed or locked).
    fn actuation(&self) -> Option<&crate::Actuation>;
    /// The model's sampled control laws at `t`: their periods and the slider law's states
    /// held there (docs/linear.md, "Discrete time").
    fn sampled_laws(&self, t: f64) -> SampledLaws;
    /// What the sampled control laws would command at a sample at `(t, y)`, the slider law
    /// with the states `slider_states`, under the loads set ([`LoadInput::set_loads`]:
    /// references added): the discretisation of a sampled loop differentiates it.
    ///
    /// # Errors
    /// A kinematic failure, a singular rigid inverse dynamics (the feedforward).
    fn law_sample(
        &mut self,
        t: f64,
        y: &[f64],
        slider_states: &[f64],
    ) -> Result<LawSample, DynamicsError>;
}

/// The queries the layers above ask of any model: each answers through the model's
/// capability, with the default where it has none.
impl dyn SceneModel + '_ {
    /// The piezoelectric patches' sensors, voltages and powers at `(t, y)`; none for a
    /// model without patches.
    ///
    /// # Errors
    /// A model that needs kinematics for them may fail there.
    pub fn patch_states(
        &mut self,
        t: f64,
        y: &[f64],
    ) -> Result<Vec<crate::PatchState>, DynamicsError> {
        self.patches()
            .map_or(Ok(Vec::new()), |p| p.patch_states(t, y))
    }
    /// Number of piezoelectric patches on the links (0 without).
    pub fn patch_count(&mut self) -> usize {
        self.patches().map_or(0, |p| p.patch_count())
    }
    /// Applies `loads` from now on in the right-hand side ([`LoadInput::set_loads`]).
    ///
    /// # Errors
    /// The model takes no external loads, or a load names a link or point that does not
    /// exist.
    pub fn set_loads(&mut self, loads: &ExternalLoads) -> Result<(), DynamicsError> {
        let kind = self.kind();
        match self.loads() {
            Some(input) => input.set_loads(loads),
            None => Err(DynamicsError::NoCapability {
                kind,
                capability: Capability::Loads,
            }),
        }
    }
    /// [`LinearHints::chord_compliance`]; `None` for a model without hints.
    ///
    /// # Errors
    /// A kinematic failure at the state.
    pub fn chord_compliance(
        &mut self,
        t: f64,
        y: &[f64],
    ) -> Result<Option<ChordCompliance>, DynamicsError> {
        self.linear_hints_mut()
            .map_or(Ok(None), |h| h.chord_compliance(t, y))
    }
    /// [`LinearHints::exact_mechanical_form`]; false for a model without hints.
    pub fn exact_mechanical_form(&mut self, t: f64, y: &[f64]) -> bool {
        self.linear_hints_mut()
            .is_some_and(|h| h.exact_mechanical_form(t, y))
    }
    /// [`LinearHints::linear_deflection`]; true for a model without hints.
    pub fn linear_deflection(&self) -> bool {
        self.linear_hints().is_none_or(|h| h.linear_deflection())
    }
    /// [`LinearHints::platform_follows_links`]; false for a model without hints.
    pub fn platform_follows_links(&self) -> bool {
        self.linear_hints()
            .is_some_and(|h| h.platform_follows_links())
    }
    /// The sliders' actuators and control law ([`ControlLaws::actuation`]); `None` where
    /// the sliders are prescribed or locked.
    pub fn actuation(&self) -> Option<&crate::Actuation> {
        self.control().and_then(|c| c.actuation())
    }
    /// Whether the sliders are driven by actuators under a control law.
    pub fn slider_law(&self) -> bool {
        self.actuation().is_some()
    }
    /// The model's sampled control laws at `t` ([`ControlLaws::sampled_laws`]); none for a
    /// model without control laws.
    pub fn sampled_laws(&self, t: f64) -> SampledLaws {
        self.control()
            .map_or_else(SampledLaws::default, |c| c.sampled_laws(t))
    }
    /// What the sampled control laws command at a sample ([`ControlLaws::law_sample`]).
    ///
    /// # Errors
    /// A model without sampled laws, a kinematic failure, a singular rigid inverse dynamics
    /// (the feedforward).
    pub fn law_sample(
        &mut self,
        t: f64,
        y: &[f64],
        slider_states: &[f64],
    ) -> Result<LawSample, DynamicsError> {
        let kind = self.kind();
        match self.control_mut() {
            Some(laws) => laws.law_sample(t, y, slider_states),
            None => Err(DynamicsError::NoCapability {
                kind,
                capability: Capability::SampledLaw,
            }),
        }
    }
    /// The link (0-based) and the mode (0-based, within the link) of state component
    /// `component`, and whether it is a rate: the state holds every link's coordinates,
    /// then their rates, in [`SceneModel::link_range`] order. `None` for other components.
    pub fn component_place(&self, component: usize) -> Option<(usize, usize, bool)> {
        component_place(self, component)
    }
    /// A reader's name (`link 1, mode 2`) and an identifier (`eta_1_2`) of generalized
    /// coordinate `k` (`k < modes()`): the model's own ([`LinearHints::coordinate_label`]),
    /// else through [`component_place`](#method.component_place), and the sliders' positions after the links'
    /// coordinates when they are actuated.
    pub fn coordinate_label(&self, k: usize) -> (String, String) {
        if let Some(label) = self.linear_hints().and_then(|h| h.coordinate_label(k)) {
            return label;
        }
        match self.component_place(k) {
            Some((link, mode, _)) => (
                format!("modal coordinate of link {}, mode {}", link + 1, mode + 1),
                format!("eta_{}_{}", link + 1, mode + 1),
            ),
            None if self.slider_law() && k + 3 >= self.modes() && k < self.modes() => {
                let i = k + 3 - self.modes();
                (
                    format!("position of slider {}", i + 1),
                    format!("rho_{}", i + 1),
                )
            }
            None => (format!("coordinate {}", k + 1), format!("q_{}", k + 1)),
        }
    }
    /// A reader's name for state component `component`, for messages: the link, the mode and
    /// whether it is the coordinate `eta` or its rate (see [`component_place`](#method.component_place)).
    pub fn component_name(&self, component: usize) -> String {
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
}

/// [`SceneModel::component_place`](trait.SceneModel.html#method.component_place) for any
/// model, also a sized one.
pub(crate) fn component_place<M: SceneModel + ?Sized>(
    model: &M,
    component: usize,
) -> Option<(usize, usize, bool)> {
    let modes = model.modes();
    let (index, rate) = if component < modes {
        (component, false)
    } else if component < 2 * modes {
        (component - modes, true)
    } else {
        return None;
    };
    (0..3).find_map(|link| {
        let range = model.link_range(link);
        range
            .contains(&index)
            .then(|| (link, index - range.start, rate))
    })
}

/// Checks a point force's link and position.
///
/// # Errors
/// A link other than 0, 1, 2 or a position outside `[0, 1]` or a non-finite force.
pub(crate) fn check_point_force(p: &PointForce) -> Result<(), DynamicsError> {
    if p.link > 2 || !(0.0..=1.0).contains(&p.xi) || !p.force.is_finite() {
        return Err(DynamicsError::PointForce {
            link: p.link + 1,
            xi: p.xi,
            force: p.force,
        });
    }
    Ok(())
}

/// The table of the platform's deviation from its commanded pose at the snapshots
/// (`platform_deviation.csv`: `dx`, `dy`, `dphi`).
pub fn platform_deviation_table(t: &[f64], snapshots: &[MachineSnapshot]) -> Table {
    use crate::{Column, Quantity as Q};
    let mut table = Table::new("platform_deviation", t);
    for (q, quantity) in [Q::DeviationX, Q::DeviationY, Q::DeviationPhi]
        .into_iter()
        .enumerate()
    {
        let values = snapshots.iter().map(|s| s.pose_deviation()[q]).collect();
        table.push(Column::of(quantity), values);
    }
    table
}

/// The table of the actual end forces and driving forces at the snapshots (`name`:
/// `P_B_i`, `P_C_i`, `F_a_i` per link).
pub fn force_table(name: &str, t: &[f64], snapshots: &[MachineSnapshot]) -> Table {
    use crate::{Column, Quantity as Q};
    let mut table = Table::new(name, t);
    for i in 0..3 {
        table.push(
            Column::link(Q::AxialForceB, i),
            snapshots.iter().map(|s| s.axial_force_b[i]).collect(),
        );
        table.push(
            Column::link(Q::AxialForceC, i),
            snapshots.iter().map(|s| s.axial_force_c[i]).collect(),
        );
        table.push(
            Column::link(Q::CoupledDrivingForce, i),
            snapshots.iter().map(|s| s.driving_force[i]).collect(),
        );
    }
    table
}
