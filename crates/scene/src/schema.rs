//! The scene file schema: what serde reads (`docs/scenes.md` is the reference).
//!
//! Every table denies unknown keys, and every choice among fixed words is a serde enum, so
//! the parser itself reports a bad word with its line and column. Choices that programs can
//! extend (the integrator `method`, the basis `kind` and its keys, the `axial_force` model)
//! are names looked up in the [`crate::Registry`].

use serde::{Deserialize, Serialize};

use crate::link::{MaterialConfig, SectionConfig};

/// The whole scene file as written (echoed into `summary.json`).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Name used in outputs (default: the file stem).
    #[serde(default)]
    pub name: Option<String>,
    /// Free text.
    #[serde(default)]
    pub description: Option<String>,
    /// The machine.
    #[serde(default)]
    pub machine: MachineConfig,
    /// The three (identical) links.
    #[serde(default)]
    pub links: LinksConfig,
    /// The platform motion.
    pub trajectory: TrajectoryConfig,
    /// Formulation and damping.
    #[serde(default)]
    pub model: ModelConfig,
    /// Time integration.
    #[serde(default)]
    pub integrator: IntegratorConfig,
    /// Time span and sampling.
    pub time: TimeConfig,
    /// What to compute and write.
    #[serde(default)]
    pub output: OutputConfig,
    /// The sliders' actuators (docs/control.md): without `[control]`, what the commanded
    /// motion is checked against (feasibility); with it, what drives the sliders.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub actuators: Option<ActuatorsTable>,
    /// The control law of the sliders (docs/control.md): with it the sliders are degrees of
    /// freedom driven by the actuators (coupled and nonlinear models).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub control: Option<ControlTable>,
    /// The vibration control law of the links' piezoelectric patches (docs/piezo.md): its
    /// registered `kind` and that law's own keys.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub vibration_control: Option<ControlTable>,
    /// The settings of `flexprr plan` (docs/planning.md): limits, boundary, shaping and the
    /// platform's orientation; `flexprr run` ignores it, `flexprr check` validates it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plan: Option<flexprr_planning::PlanSpec>,
}

/// `[actuators]`: one actuator for all three sliders, the registered `kind` (`force`,
/// `motor_ballscrew`, or one a program registered) and that kind's own keys. A loaded scene
/// holds the keys as the kind completes them ([`crate::ActuatorFactory::canonical_keys`]:
/// defaults filled in) and writes them back in the kind's order.
#[derive(Debug, Clone, Deserialize, PartialEq)]
pub struct ActuatorsTable {
    /// Registered actuator kind.
    pub kind: String,
    /// The kind's own keys (each kind reads and checks them).
    #[serde(flatten)]
    pub params: toml::Table,
    /// The order the keys are written back in (the rest follow, sorted).
    #[serde(skip)]
    pub order: Vec<String>,
}

impl Serialize for ActuatorsTable {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut map = serializer.serialize_map(Some(self.params.len() + 1))?;
        map.serialize_entry("kind", &self.kind)?;
        for key in &self.order {
            if let Some(value) = self.params.get(key) {
                map.serialize_entry(key, value)?;
            }
        }
        for (key, value) in &self.params {
            if !self.order.contains(key) {
                map.serialize_entry(key, value)?;
            }
        }
        map.end()
    }
}

/// Default smoothing speed of the Coulomb friction (rev/s): 0.01 rev/s is 0.6 rpm, so the
/// friction has its full value (within 0.1 %) above 0.04 rev/s (2.4 rpm), far below any
/// working speed, while the right-hand side stays continuous through rest.
pub const DEFAULT_COULOMB_SMOOTHING: f64 = 0.01;

/// `[control]`: the registered control law `kind` and that law's own keys.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
pub struct ControlTable {
    /// Registered control law (`pd`, `pid`, or one a program registered).
    pub kind: String,
    /// The law's own keys (each law reads and checks them).
    #[serde(flatten)]
    pub params: toml::Table,
}

/// Machine layout and rigid-body inertia.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MachineConfig {
    /// `"radial"` (the paper's reconstructed layout, from `alpha_deg` and `platform_side`) or
    /// `"general"` (explicit `legs`).
    #[serde(default)]
    pub layout: Layout,
    /// Guide angles (deg), radial layout.
    #[serde(default = "default_alpha")]
    pub alpha_deg: [f64; 3],
    /// Platform side (m), radial layout.
    #[serde(default = "default_side")]
    pub platform_side: f64,
    /// Half the slider travel (m), radial layout.
    #[serde(default = "default_half_travel")]
    pub half_travel: f64,
    /// Explicit legs, general layout.
    #[serde(default)]
    pub legs: Vec<LegConfig>,
    /// Platform mass (kg).
    #[serde(default = "default_platform_mass")]
    pub platform_mass: f64,
    /// Platform inertia about its reference point (kg m^2; default `m_p s^2 / 12`).
    #[serde(default)]
    pub platform_inertia: Option<f64>,
    /// Slider mass (kg), one for all.
    #[serde(default = "default_slider_mass")]
    pub slider_mass: f64,
}

fn default_alpha() -> [f64; 3] {
    [150.0, 270.0, 30.0]
}
fn default_side() -> f64 {
    0.1
}
fn default_half_travel() -> f64 {
    0.2
}
fn default_platform_mass() -> f64 {
    0.2
}
fn default_slider_mass() -> f64 {
    0.5
}

impl Default for MachineConfig {
    fn default() -> Self {
        Self {
            layout: Layout::Radial,
            alpha_deg: default_alpha(),
            platform_side: default_side(),
            half_travel: default_half_travel(),
            legs: Vec::new(),
            platform_mass: default_platform_mass(),
            platform_inertia: None,
            slider_mass: default_slider_mass(),
        }
    }
}

/// One leg of a general layout.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LegConfig {
    /// Guide centre `A_i` (m).
    pub anchor: [f64; 2],
    /// Guide direction angle `alpha_i` (deg).
    pub direction_deg: f64,
    /// Slider travel `[min, max]` of `rho_i` (m).
    pub travel: [f64; 2],
    /// Platform joint in the platform frame (m).
    pub attachment: [f64; 2],
    /// `"behind"` (slider behind the platform joint, the paper's) or `"ahead"`.
    #[serde(default)]
    pub branch: BranchChoice,
}

/// Machine layout.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Layout {
    /// Guides at `alpha_deg`, platform an equilateral triangle (the paper's).
    #[default]
    Radial,
    /// Three explicit `[[machine.legs]]`.
    General,
}

/// Assembly branch of a leg.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum BranchChoice {
    /// Slider behind the platform joint (the paper's).
    #[default]
    Behind,
    /// Slider ahead of the platform joint.
    Ahead,
}

/// The links (all three identical).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LinksConfig {
    /// Length (m).
    #[serde(default = "default_length")]
    pub length: f64,
    /// Material.
    #[serde(default = "default_material")]
    pub material: MaterialConfig,
    /// Cross-section.
    #[serde(default = "default_section")]
    pub section: SectionConfig,
    /// Assumed-mode basis: `kind` (a registered name) and that kind's own keys.
    #[serde(default)]
    pub basis: BasisTable,
    /// Number of modes `r` for bases sized by it (sine, classical; default 3); refused for
    /// bases that size themselves (Hermite: `basis.elements`).
    #[serde(default)]
    pub modes: Option<usize>,
    /// Piezoelectric patches (`[[links.patches]]`, docs/piezo.md).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub patches: Vec<PatchConfig>,
}

/// One `[[links.patches]]` entry: a collocated actuator and sensor pair, on the links listed
/// (1-based; every link when left out).
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PatchConfig {
    /// The links carrying it (1, 2, 3); all three when left out.
    #[serde(default)]
    pub links: Option<Vec<usize>>,
    /// Where it starts along the link (0..1).
    pub xi_start: f64,
    /// Where it ends (0..1, after the start).
    pub xi_end: f64,
    /// Actuator constant: bending moment per volt (N m/V).
    pub actuator_constant: f64,
    /// Sensor constant: volts per radian of slope difference over the patch (V/rad).
    pub sensor_constant: f64,
    /// Largest voltage magnitude (V).
    pub voltage_limit: f64,
    /// Mass the pair adds to each link it is on (kg), spread evenly over its span; 0 (the
    /// default) leaves the link as it is.
    #[serde(default)]
    pub added_mass: f64,
    /// Bending stiffness the pair adds over its span (N m^2); 0 by default.
    #[serde(default)]
    pub added_bending_stiffness: f64,
}

fn default_length() -> f64 {
    0.2
}
fn default_material() -> MaterialConfig {
    MaterialConfig {
        youngs_modulus: 7.3e10,
        density: 2770.0,
    }
}
fn default_section() -> SectionConfig {
    SectionConfig::Uniform {
        thickness: 0.002,
        height: 0.03,
    }
}

impl Default for LinksConfig {
    fn default() -> Self {
        Self {
            length: default_length(),
            material: default_material(),
            section: default_section(),
            basis: BasisTable::default(),
            modes: None,
            patches: Vec::new(),
        }
    }
}

/// Platform trajectory.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum TrajectoryConfig {
    /// Circle at constant frequency and orientation (the paper's).
    Circle {
        /// Centre (m).
        #[serde(default = "default_centre")]
        centre: [f64; 2],
        /// Radius (m).
        #[serde(default = "default_radius")]
        radius: f64,
        /// Revolutions per second (Hz).
        frequency: f64,
        /// Constant orientation (deg).
        #[serde(default = "default_phi")]
        phi_deg: f64,
        /// Angle on the circle at t = 0 (deg).
        #[serde(default)]
        start_angle_deg: f64,
    },
    /// Straight line at constant velocity from `from` (at t = 0).
    Line {
        /// Start pose `[x, y, phi_deg]`.
        from: [f64; 3],
        /// Velocity `[x', y', phi'_deg]` (m/s, deg/s).
        velocity: [f64; 3],
    },
    /// Rest-to-rest move.
    PointToPoint {
        /// Start pose `[x, y, phi_deg]`.
        from: [f64; 3],
        /// End pose `[x, y, phi_deg]`.
        to: [f64; 3],
        /// Start time (s).
        #[serde(default)]
        start: f64,
        /// Duration (s).
        duration: f64,
        /// `"quintic"` or `"cycloidal"`.
        #[serde(default)]
        profile: ProfileChoice,
    },
    /// Cubic spline through `[t, x, y, phi_deg]` points, at rest at both ends.
    Waypoints {
        /// Points `[t, x, y, phi_deg]`, times increasing.
        points: Vec<[f64; 4]>,
    },
    /// A motion planned by `flexprr plan` (docs/planning.md): a path, the path speed on a
    /// grid, shaper impulses and smoothing, in SI units with angles in rad.
    Planned(Box<flexprr_kinematics::PlannedData>),
}

fn default_centre() -> [f64; 2] {
    [-0.05, 0.0]
}
fn default_radius() -> f64 {
    0.05
}
fn default_phi() -> f64 {
    45.0
}
/// Motion law of a point-to-point move.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum ProfileChoice {
    /// Quintic polynomial (zero velocity and acceleration at both ends).
    #[default]
    Quintic,
    /// Cycloidal (sine-on-ramp).
    Cycloidal,
}

/// An assumed-mode basis table: the registered `kind` and that kind's keys.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
pub struct BasisTable {
    /// Registered basis name (`sine`, `classical`, `hermite`, or one a program registered).
    pub kind: String,
    /// The kind's own keys (each kind reads and checks them).
    #[serde(flatten)]
    pub params: toml::Table,
}

impl Default for BasisTable {
    fn default() -> Self {
        Self {
            kind: "sine".into(),
            params: toml::Table::new(),
        }
    }
}

/// Named formulation preset.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum FormulationChoice {
    /// The paper's equations as printed.
    Paper,
    /// The consistent equations (model.md).
    #[default]
    Consistent,
}

/// Geometric stiffness coupling.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum StiffnessChoice {
    /// Diagonal of `Kp` only (the paper's eq. 21).
    Diagonal,
    /// Full `Kp`.
    Full,
}

/// How the coupled model's chords enter linear analyses at rest.
#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum ChordsChoice {
    /// The links' axial springs `EA / l`, the platform free on them.
    #[default]
    Elastic,
    /// Axially rigid: the paper's pinned-pinned idealisation of the locked machine.
    Rigid,
}

/// Formulation (named preset plus optional overrides) and damping.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ModelConfig {
    /// `"paper"` or `"consistent"` (default).
    #[serde(default)]
    pub formulation: FormulationChoice,
    /// Override: a registered axial force model (`"none"`, `"paper"`, `"joint-reaction"`).
    #[serde(default)]
    pub axial_force: Option<String>,
    /// Override: `"diagonal"` or `"full"` geometric stiffness.
    #[serde(default)]
    pub geometric_stiffness: Option<StiffnessChoice>,
    /// Override: the paper's coupling force `F_fg`.
    #[serde(default)]
    pub coriolis_forcing: Option<bool>,
    /// Override: centrifugal softening `-b'^2 M`.
    #[serde(default)]
    pub centrifugal_softening: Option<bool>,
    /// Modal damping ratios: one for all modes or one per mode.
    #[serde(default)]
    pub damping: Vec<f64>,
    /// The registered model kind ([`crate::Registry::register_model_kind`]): `"ked"`
    /// (prescribed rigid motion), `"coupled"` (platform moved by the links' foreshortening)
    /// or `"nonlinear"` (co-rotational beam elements and a free platform) among the built-ins.
    #[serde(default = "default_coupling")]
    pub coupling: String,
    /// Nonlinear model only: co-rotational elements per link (even, at least 2; default 32).
    #[serde(default)]
    pub elements: Option<usize>,
    /// Coupled and nonlinear models: the run stops as collapsed when a link's mid-point
    /// deflection passes this fraction of its length (default 0.1, the external model's
    /// collapse criterion; a type-II pose of the chords always stops them).
    #[serde(default)]
    pub collapse_deflection: Option<f64>,
    /// Nonlinear model only: Kelvin-Voigt time of the axial strain-rate damping (s, default 0).
    #[serde(default)]
    pub axial_damping_time: Option<f64>,
    /// Coupled model only: its chords in linear analyses at rest, `"elastic"` (default) or
    /// `"rigid"` (docs/linear.md, "Elastic chords").
    #[serde(default)]
    pub chords: Option<ChordsChoice>,
}

impl Default for ModelConfig {
    fn default() -> Self {
        Self {
            formulation: FormulationChoice::Consistent,
            axial_force: None,
            geometric_stiffness: None,
            coriolis_forcing: None,
            centrifugal_softening: None,
            damping: Vec::new(),
            coupling: default_coupling(),
            elements: None,
            collapse_deflection: None,
            axial_damping_time: None,
            chords: None,
        }
    }
}

/// Integrator choice and tolerances.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct IntegratorConfig {
    /// A registered integrator: `"auto"` (the default: `"magnus6"` for the KED model,
    /// `"generalized_alpha"` for the nonlinear one without a continuous control law's
    /// states, `"abm"` otherwise; resolved when the scene is loaded), `"abm"` (like the
    /// paper's ode113), `"rk45"`, `"bdf"`, `"magnus4"` and `"magnus6"` (exponential, KED
    /// model only), or `"generalized_alpha"` (implicit, for structural dynamics: models with
    /// a mechanical form, the nonlinear one, without continuous controller states; see
    /// `spectral_radius`).
    #[serde(default = "default_method")]
    pub method: String,
    /// Relative tolerance.
    #[serde(default = "default_rtol")]
    pub rtol: f64,
    /// Absolute tolerance (m and m/s of modal coordinates).
    #[serde(default = "default_atol")]
    pub atol: f64,
    /// Largest step (s).
    #[serde(default)]
    pub max_step: Option<f64>,
    /// First step (s; default automatic).
    #[serde(default)]
    pub initial_step: Option<f64>,
    /// Largest number of steps.
    #[serde(default = "default_max_steps")]
    pub max_steps: usize,
    /// `"generalized_alpha"` only (also when `"auto"` picks it): the spectral radius at
    /// infinite frequency, `0` (the most numerical dissipation of the unresolved modes) to
    /// `1` (none); default 0.7.
    #[serde(default)]
    pub spectral_radius: Option<f64>,
}

/// `auto`: the stress suite (docs/stability.md) found it right on every stress scene and the
/// work-precision runs (docs/performance.md) faster than `abm` on every KED scene measured.
fn default_method() -> String {
    "auto".into()
}
fn default_rtol() -> f64 {
    1e-8
}
fn default_atol() -> f64 {
    1e-12
}
fn default_max_steps() -> usize {
    10_000_000
}

impl Default for IntegratorConfig {
    fn default() -> Self {
        Self {
            method: default_method(),
            rtol: default_rtol(),
            atol: default_atol(),
            max_step: None,
            initial_step: None,
            max_steps: default_max_steps(),
            spectral_radius: None,
        }
    }
}

/// Time span and output sampling.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TimeConfig {
    /// Start (s).
    #[serde(default)]
    pub start: f64,
    /// End (s).
    pub end: f64,
    /// Output interval (s); default `(end - start) / 1000`.
    #[serde(default)]
    pub output_step: Option<f64>,
    /// Times (s) the integrator must step onto exactly (e.g. where a load or motion changes
    /// abruptly); each in `[start, end]`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub stops: Vec<f64>,
}

/// Requested outputs.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct OutputConfig {
    /// Any of `kinematics`, `driving_forces`, `joint_reactions`, `axial_forces`,
    /// `frequencies`, `modes`, `modal_forces`, `deflections`, `energies`.
    #[serde(default = "default_requests")]
    pub requests: Vec<OutputKind>,
    /// Outputs declared by the program that loads the scene (`Registry::register_output`),
    /// by name; none by default.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub custom: Vec<String>,
    /// Positions `xi` along the links for `deflections` (default mid-point).
    #[serde(default = "default_xi")]
    pub deflection_xi: Vec<f64>,
    /// Also integrate without axial force and write both deflections (the paper's figures 6-8).
    #[serde(default)]
    pub compare_without_axial_force: bool,
    /// Write SVG plots.
    #[serde(default = "default_true")]
    pub plots: bool,
}

fn default_requests() -> Vec<OutputKind> {
    vec![OutputKind::Deflections, OutputKind::Frequencies]
}
fn default_xi() -> Vec<f64> {
    vec![0.5]
}
fn default_true() -> bool {
    true
}

impl Default for OutputConfig {
    fn default() -> Self {
        Self {
            requests: default_requests(),
            custom: Vec::new(),
            deflection_xi: default_xi(),
            compare_without_axial_force: false,
            plots: true,
        }
    }
}

/// A requested output.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum OutputKind {
    /// Slider and link kinematics.
    Kinematics,
    /// Driving forces `F_a` (rigid, and with the links' elastic inertia when integrated).
    DrivingForces,
    /// Joint reactions `F_B`, `F_C`.
    JointReactions,
    /// Axial force at both ends of each link.
    AxialForces,
    /// Frequencies of every link and mode along the motion.
    Frequencies,
    /// Modal coordinates.
    Modes,
    /// Inertial and coupling modal forces (the paper's figure 9).
    ModalForces,
    /// Deflections at the requested `xi`.
    Deflections,
    /// Elastic and kinetic energies.
    Energies,
    /// The self-contained animated page `viewer.html` (docs/viewer.md).
    Viewer,
    /// `snapshots.svg`: the deformed links at a few instants, amplified.
    Snapshots,
    /// `machine.svg`: geometry, reachable workspace, type-II singularity locus and path.
    Machine,
    /// Slider and platform tracking errors (commanded minus actual).
    Tracking,
    /// The actuators' force commands and forces, and the motors' torque, speed and
    /// saturation where a motor is modelled.
    Actuators,
    /// The whole machine's lowest natural frequencies and damping ratios along the motion:
    /// the model linearised about its integrated state at (at most about 200 of) the output
    /// times (docs/linear.md); coupled and nonlinear models only.
    MachineFrequencies,
    /// The piezoelectric patches' sensor, commanded and applied voltages, saturation and
    /// actuator power (`piezo.csv`, docs/piezo.md); scenes with `[[links.patches]]` only.
    Piezo,
}

impl OutputKind {
    /// All kinds with their file-stem names.
    pub const ALL: [(OutputKind, &'static str); 16] = [
        (OutputKind::Kinematics, "kinematics"),
        (OutputKind::DrivingForces, "driving_forces"),
        (OutputKind::JointReactions, "joint_reactions"),
        (OutputKind::AxialForces, "axial_forces"),
        (OutputKind::Frequencies, "frequencies"),
        (OutputKind::Modes, "modes"),
        (OutputKind::ModalForces, "modal_forces"),
        (OutputKind::Deflections, "deflections"),
        (OutputKind::Energies, "energies"),
        (OutputKind::Viewer, "viewer"),
        (OutputKind::Snapshots, "snapshots"),
        (OutputKind::Machine, "machine"),
        (OutputKind::Tracking, "tracking"),
        (OutputKind::Actuators, "actuators"),
        (OutputKind::MachineFrequencies, "machine_frequencies"),
        (OutputKind::Piezo, "piezo"),
    ];

    /// The name used in scene files and output file names.
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(k, _)| *k == self)
            .map(|(_, n)| *n)
            .unwrap_or("?")
    }

    /// Whether this output needs the model integrated whatever the model (`actuators`
    /// needs it only where the sliders are actuated: [`crate::Scene::integrates_model`]).
    pub fn needs_integration(self) -> bool {
        matches!(
            self,
            OutputKind::Modes
                | OutputKind::Deflections
                | OutputKind::Energies
                | OutputKind::ModalForces
                | OutputKind::Viewer
                | OutputKind::Snapshots
                | OutputKind::Tracking
                | OutputKind::MachineFrequencies
                | OutputKind::Piezo
        )
    }
}

/// `model.coupling` when not given: the KED model.
fn default_coupling() -> String {
    "ked".to_string()
}
