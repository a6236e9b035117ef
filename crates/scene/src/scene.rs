//! Scene files: everything one run needs, in TOML (`docs/scenes.md` is the reference).
//!
//! Parsing happens in two passes. Serde reads the file into [`SceneFile`] (unknown keys and
//! wrong types are errors with line and column); [`Scene::from_file`] then checks every
//! value's range, builds the machine, checks that the trajectory stays reachable, inside the
//! slider travel and away from singularities over the whole time span (before anything is
//! integrated), and reports any failure with the key and its location.

use std::collections::BTreeSet;
use std::path::Path;
use std::sync::Arc;

use flexprr_dynamics::{
    AxialForceModel, AxialModel, Coupling, CouplingModel, Formulation, LinkModel, Machine,
    ModalDamping,
};
use flexprr_integrators::Options;
use flexprr_kinematics::{
    Branch, Circle, Geometry, Guide, Leg, Line, PointToPoint, Pose, Profile, Trajectory,
    WaypointSpline, validate_trajectory,
};
use nalgebra::{Point2, Unit, Vector2};
use serde::{Deserialize, Serialize};
use toml::de::{DeTable, DeValue};

use crate::error::ScenarioError;
use crate::link::{BasisConfig, MaterialConfig, SectionConfig, build_basis, build_section};
use crate::locate::{line_column, locate};

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
}

/// Machine layout and rigid-body inertia.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MachineConfig {
    /// `"radial"` (the paper's reconstructed layout, from `alpha_deg` and `platform_side`) or
    /// `"general"` (explicit `legs`).
    #[serde(default = "default_layout")]
    pub layout: String,
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

fn default_layout() -> String {
    "radial".into()
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
            layout: default_layout(),
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
    #[serde(default = "default_branch")]
    pub branch: String,
}

fn default_branch() -> String {
    "behind".into()
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
    /// Assumed-mode basis.
    #[serde(default)]
    pub basis: BasisConfig,
    /// Number of modes `r` (sine and classical bases; Hermite takes its size from
    /// `basis.elements`).
    #[serde(default)]
    pub modes: Option<usize>,
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
            basis: BasisConfig::Sine,
            modes: None,
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
        #[serde(default = "default_profile")]
        profile: String,
    },
    /// Cubic spline through `[t, x, y, phi_deg]` points, at rest at both ends.
    Waypoints {
        /// Points `[t, x, y, phi_deg]`, times increasing.
        points: Vec<[f64; 4]>,
    },
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
fn default_profile() -> String {
    "quintic".into()
}

/// Formulation (named preset plus optional overrides) and damping.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ModelConfig {
    /// `"paper"` or `"consistent"` (default).
    #[serde(default = "default_formulation")]
    pub formulation: String,
    /// Override: `"none"`, `"paper"` or `"joint-reaction"`.
    #[serde(default)]
    pub axial_force: Option<String>,
    /// Override: `"diagonal"` or `"full"` geometric stiffness.
    #[serde(default)]
    pub geometric_stiffness: Option<String>,
    /// Override: the paper's coupling force `F_fg`.
    #[serde(default)]
    pub coriolis_forcing: Option<bool>,
    /// Override: centrifugal softening `-b'^2 M`.
    #[serde(default)]
    pub centrifugal_softening: Option<bool>,
    /// Modal damping ratios: one for all modes or one per mode.
    #[serde(default)]
    pub damping: Vec<f64>,
    /// `"ked"` (prescribed rigid motion; the only model in this version).
    #[serde(default = "default_coupling")]
    pub coupling: String,
}

fn default_formulation() -> String {
    "consistent".into()
}
fn default_coupling() -> String {
    "ked".into()
}

impl Default for ModelConfig {
    fn default() -> Self {
        Self {
            formulation: default_formulation(),
            axial_force: None,
            geometric_stiffness: None,
            coriolis_forcing: None,
            centrifugal_softening: None,
            damping: Vec::new(),
            coupling: default_coupling(),
        }
    }
}

/// Integrator choice and tolerances.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct IntegratorConfig {
    /// `"abm"` (default, like the paper's ode113), `"rk45"` or `"bdf"`.
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
}

fn default_method() -> String {
    "abm".into()
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
}

/// Requested outputs.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct OutputConfig {
    /// Any of `kinematics`, `driving_forces`, `joint_reactions`, `axial_forces`,
    /// `frequencies`, `modes`, `modal_forces`, `deflections`, `energies`.
    #[serde(default = "default_requests")]
    pub requests: Vec<String>,
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

fn default_requests() -> Vec<String> {
    vec!["deflections".into(), "frequencies".into()]
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
            deflection_xi: default_xi(),
            compare_without_axial_force: false,
            plots: true,
        }
    }
}

/// A requested output.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
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
}

impl OutputKind {
    /// All kinds with their file-stem names.
    pub const ALL: [(OutputKind, &'static str); 9] = [
        (OutputKind::Kinematics, "kinematics"),
        (OutputKind::DrivingForces, "driving_forces"),
        (OutputKind::JointReactions, "joint_reactions"),
        (OutputKind::AxialForces, "axial_forces"),
        (OutputKind::Frequencies, "frequencies"),
        (OutputKind::Modes, "modes"),
        (OutputKind::ModalForces, "modal_forces"),
        (OutputKind::Deflections, "deflections"),
        (OutputKind::Energies, "energies"),
    ];

    /// The name used in scene files and output file names.
    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(k, _)| *k == self)
            .map(|(_, n)| *n)
            .unwrap_or("?")
    }

    /// Whether this output needs the modal ODE integrated.
    pub fn needs_integration(self) -> bool {
        matches!(
            self,
            OutputKind::Modes
                | OutputKind::Deflections
                | OutputKind::Energies
                | OutputKind::ModalForces
        )
    }
}

/// Which integrator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Adams-Bashforth-Moulton.
    Abm,
    /// Dormand-Prince 5(4).
    Rk45,
    /// BDF.
    Bdf,
}

impl Method {
    /// Parses a method name.
    pub fn parse(name: &str) -> Option<Self> {
        match name {
            "abm" => Some(Method::Abm),
            "rk45" => Some(Method::Rk45),
            "bdf" => Some(Method::Bdf),
            _ => None,
        }
    }
    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Method::Abm => "abm",
            Method::Rk45 => "rk45",
            Method::Bdf => "bdf",
        }
    }

    /// The integrator this method names, with `options`, behind the object-safe adapter.
    pub fn integrator(
        self,
        options: flexprr_integrators::Options,
    ) -> Box<dyn flexprr_integrators::DynIntegrator> {
        use flexprr_integrators::{Abm, Bdf, Rk45};
        match self {
            Method::Abm => Box::new(Abm::new(options)),
            Method::Rk45 => Box::new(Rk45::new(options)),
            Method::Bdf => Box::new(Bdf::new(options)),
        }
    }

    /// Integrates `system` from `y0` at `t_out[0]` with this method, output at `t_out`.
    ///
    /// # Errors
    /// The integrator's error.
    pub fn solve<S: flexprr_integrators::OdeSystem>(
        self,
        options: flexprr_integrators::Options,
        system: &mut S,
        y0: &[f64],
        t_out: &[f64],
    ) -> Result<flexprr_integrators::Solution, flexprr_integrators::IntegratorError> {
        use flexprr_integrators::{Abm, Bdf, Integrator, Rk45};
        let t0 = t_out[0];
        match self {
            Method::Abm => Abm::new(options).solve(system, t0, y0, t_out),
            Method::Rk45 => Rk45::new(options).solve(system, t0, y0, t_out),
            Method::Bdf => Bdf::new(options).solve(system, t0, y0, t_out),
        }
    }
}

/// A validated, built scene: ready to run.
#[derive(Clone)]
pub struct Scene {
    /// Scene name.
    pub name: String,
    /// The file as written (with defaults filled in).
    pub file: SceneFile,
    /// The machine.
    pub machine: Arc<Machine>,
    /// The platform motion.
    pub trajectory: Arc<dyn Trajectory + Send + Sync>,
    /// Formulation.
    pub formulation: Formulation,
    /// The axial force model (the one `formulation.axial` names, or a registered one).
    pub axial_model: Arc<dyn AxialForceModel>,
    /// Modal damping.
    pub damping: ModalDamping,
    /// Integrator.
    pub method: Method,
    /// Integrator options.
    pub options: Options,
    /// Output times (s).
    pub output_times: Vec<f64>,
    /// Requested outputs.
    pub outputs: BTreeSet<OutputKind>,
    /// KED (prescribed rigid motion) or the coupled model.
    pub coupling: CouplingModel,
    /// Mean axial stiffness `EA` of the links (N), for the coupled model's stretch output.
    pub axial_stiffness: f64,
}

impl std::fmt::Debug for Scene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Scene")
            .field("name", &self.name)
            .field("formulation", &self.formulation)
            .field("method", &self.method)
            .field("outputs", &self.outputs)
            .finish_non_exhaustive()
    }
}

/// Checks and location context while building a scene.
struct Checker<'a> {
    file: &'a str,
    text: &'a str,
}

impl Checker<'_> {
    fn error(&self, key: &str, message: impl Into<String>) -> ScenarioError {
        ScenarioError::Input {
            location: locate(self.file, self.text, key),
            key: key.to_string(),
            message: message.into(),
        }
    }
    fn positive(&self, key: &str, value: f64, unit: &str) -> Result<f64, ScenarioError> {
        if value.is_finite() && value > 0.0 {
            Ok(value)
        } else {
            Err(self.error(
                key,
                format!("expected a positive number ({unit}), got {value:?}"),
            ))
        }
    }
    fn non_negative(&self, key: &str, value: f64, unit: &str) -> Result<f64, ScenarioError> {
        if value.is_finite() && value >= 0.0 {
            Ok(value)
        } else {
            Err(self.error(
                key,
                format!("expected a non-negative number ({unit}), got {value:?}"),
            ))
        }
    }
    fn finite(&self, key: &str, value: f64) -> Result<f64, ScenarioError> {
        if value.is_finite() {
            Ok(value)
        } else {
            Err(self.error(key, format!("expected a finite number, got {value:?}")))
        }
    }
    fn choice<T: Copy>(
        &self,
        key: &str,
        value: &str,
        choices: &[(&str, T)],
    ) -> Result<T, ScenarioError> {
        choices
            .iter()
            .find(|(n, _)| *n == value)
            .map(|(_, v)| *v)
            .ok_or_else(|| {
                let names: Vec<String> = choices.iter().map(|(n, _)| format!("\"{n}\"")).collect();
                self.error(
                    key,
                    format!(
                        "unknown value \"{value}\", expected one of {}",
                        names.join(", ")
                    ),
                )
            })
    }
}

fn pose_from(values: [f64; 3]) -> Pose {
    Pose::new(values[0], values[1], values[2].to_radians())
}

/// Parses scene text into the raw [`SceneFile`]; syntax, unknown keys and wrong types are
/// [`ScenarioError::Input`] with line and column and the dotted key involved.
///
/// The TOML deserializer reports a byte span and a message but not the key path, so the
/// path is recovered from a span-preserving parse of the same text. Where
/// the deserializer only knows the enclosing table (an unknown key or an unknown variant
/// inside a tagged table), the offending key or value is searched for inside that table; a
/// missing key is named after the table that lacks it; a syntax error is named after the
/// key assigned (or the table opened) on its line.
///
/// # Errors
/// As described.
pub fn parse_scene(file: &str, text: &str) -> Result<SceneFile, ScenarioError> {
    parse_toml(file, text)
}

/// Parses any TOML input file (scenes, link files, studies) into `T`, turning serde's errors
/// into [`ScenarioError::Input`] with `file:line:column`, the dotted key and what was expected.
///
/// # Errors
/// As described.
pub fn parse_toml<T: serde::de::DeserializeOwned>(
    file: &str,
    text: &str,
) -> Result<T, ScenarioError> {
    toml::from_str(text).map_err(|e| {
        let message = e.message().trim().to_string();
        let named = |prefix: &str| {
            message
                .strip_prefix(prefix)
                .and_then(|rest| rest.split('`').next())
                .map(str::to_string)
        };
        let syntax_error = DeTable::parse(text).is_err();
        let mut key = String::new();
        let mut missing_value = false;
        let location = e.span().map(|span| {
            let mut offset = span.start.min(text.len());
            if syntax_error {
                key = key_on_line(text, offset);
                missing_value = value_is_missing(text, offset);
            } else if let Some(name) = named("unknown field `") {
                if let Some(found) = find_key_within(text, span.clone(), &name)
                    .or_else(|| find_key_from(text, offset, &name))
                {
                    offset = found;
                }
                key = key_path_at(text, offset..offset + 1);
                if !key.ends_with(name.as_str()) {
                    key = join_key(&key, &name);
                }
            } else if let Some(name) = named("missing field `") {
                key = join_key(&key_path_at(text, span.clone()), &name);
            } else {
                if let Some(variant) = named("unknown variant `") {
                    let quoted = [format!("\"{variant}\""), format!("'{variant}'")];
                    if let Some(found) = quoted.iter().find_map(|q| {
                        text.get(span.clone())
                            .and_then(|region| region.find(q.as_str()))
                    }) {
                        offset += found;
                    }
                }
                key = key_path_at(text, offset..offset + 1);
                // Inside a tagged table (trajectory, section, basis) the deserializer only
                // knows the table: find the entry holding the offending value.
                if let Some((found, entry)) = entry_with_value(text, &key, &message) {
                    offset = found;
                    key = join_key(&key, &entry);
                }
            }
            let (line, column) = line_column(text, offset);
            crate::error::Location {
                file: file.to_string(),
                line,
                column,
            }
        });
        if key.is_empty() {
            if let Some(name) = named("missing field `") {
                key = name;
            }
        }
        let message = if missing_value {
            format!("expected a value after `=` ({message})")
        } else {
            message
        };
        ScenarioError::Input {
            location,
            key,
            message,
        }
    })
}

fn join_key(parent: &str, name: &str) -> String {
    if parent.is_empty() {
        name.to_string()
    } else {
        format!("{parent}.{name}")
    }
}

/// Dotted key path (array elements numbered from 0) of the deepest entry whose key or
/// value span holds all of `span` (byte offsets in `text`); empty when none does or `span`
/// is the root table's.
fn key_path_at(text: &str, span: std::ops::Range<usize>) -> String {
    fn holds(outer: std::ops::Range<usize>, inner: &std::ops::Range<usize>) -> bool {
        outer.start <= inner.start && inner.end <= outer.end.max(outer.start + 1)
    }
    fn search(value: &DeValue<'_>, span: &std::ops::Range<usize>, path: &mut Vec<String>) -> bool {
        match value {
            DeValue::Table(table) => {
                for (key, item) in table.iter() {
                    path.push(key.get_ref().to_string());
                    let covers = holds(key.span(), span) || holds(item.span(), span);
                    if search(item.get_ref(), span, path) || covers {
                        return true;
                    }
                    path.pop();
                }
                false
            }
            DeValue::Array(items) => {
                for (k, item) in items.iter().enumerate() {
                    path.push(k.to_string());
                    if search(item.get_ref(), span, path) || holds(item.span(), span) {
                        return true;
                    }
                    path.pop();
                }
                false
            }
            _ => false,
        }
    }
    let Ok(root) = DeTable::parse(text) else {
        return String::new();
    };
    if root.span() == span {
        // The deserializer names the root table (e.g. for a missing top-level table).
        return String::new();
    }
    let mut path = Vec::new();
    search(&DeValue::Table(root.into_inner()), &span, &mut path);
    path.join(".")
}

/// For an "invalid type" or "invalid value" message that names the offending value
/// (`` boolean `true` ``, `` string "0.1" ``, `` integer `-5` ``, `` floating point `0.5` ``),
/// the one entry of the table at `table_path` holding that value: its offset and name.
/// `None` when `table_path` is not a table, the message names no value, or the value is not
/// found exactly once.
fn entry_with_value(text: &str, table_path: &str, message: &str) -> Option<(usize, String)> {
    let rest = message
        .strip_prefix("invalid type: ")
        .or_else(|| message.strip_prefix("invalid value: "))?;
    let described = rest.split(", expected").next()?;
    let literal = if let Some((_, quoted)) = described.split_once('"') {
        quoted.rsplit_once('"')?.0
    } else {
        described.split('`').nth(1)?
    };
    let root = DeTable::parse(text).ok()?;
    let mut current = DeValue::Table(root.into_inner());
    for part in table_path.split('.').filter(|p| !p.is_empty()) {
        let next = match part.parse::<usize>() {
            Ok(index) => current.get(index),
            Err(_) => current.get(part),
        }?;
        current = next.get_ref().clone();
    }
    let DeValue::Table(table) = &current else {
        return None;
    };
    let same = |source: &str| {
        let source = source.trim();
        let unquoted = source.trim_matches(['"', '\'']);
        let as_number = |s: &str| s.replace('_', "").parse::<f64>().ok().map(f64::to_bits);
        unquoted == literal
            || (as_number(source).is_some() && as_number(source) == as_number(literal))
    };
    let mut hits = table.iter().filter(|(_, value)| {
        !matches!(value.get_ref(), DeValue::Table(_) | DeValue::Array(_))
            && text.get(value.span()).is_some_and(same)
    });
    let (key, _) = hits.next()?;
    if hits.next().is_some() {
        return None;
    }
    Some((key.span().start, key.get_ref().to_string()))
}

/// Whether the line holding `offset` is `key =` with nothing (or only a comment) after it.
fn value_is_missing(text: &str, offset: usize) -> bool {
    let offset = offset.min(text.len());
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let line = text[line_start..].lines().next().unwrap_or("");
    match line.split_once('=') {
        Some((assigned, value)) => {
            !assigned.trim().is_empty()
                && !assigned.contains(['{', '[', '"'])
                && value.split('#').next().unwrap_or("").trim().is_empty()
        }
        None => false,
    }
}

/// For a syntax error at `offset`: the key assigned on that line (`key = ...`) or the table
/// opened there (`[table`), prefixed with the last table header above it.
fn key_on_line(text: &str, offset: usize) -> String {
    let offset = offset.min(text.len());
    // An error at the end of a line belongs to that line.
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let line_end = text[line_start..]
        .find('\n')
        .map_or(text.len(), |i| line_start + i);
    let line = text[line_start..line_end].trim();
    let header_name = |l: &str| {
        l.trim_start_matches('[')
            .split([']', '#'])
            .next()
            .unwrap_or("")
            .trim()
            .to_string()
    };
    if line.starts_with('[') {
        return header_name(line);
    }
    let assigned = line.split('=').next().unwrap_or("").trim();
    let table = text[..line_start]
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('['))
        .map(header_name)
        .unwrap_or_default();
    if line.contains('=') {
        join_key(&table, assigned)
    } else {
        table
    }
}

/// Byte offset of `key =` inside `span` of `text` (e.g. in an inline table), if there.
fn find_key_within(text: &str, span: std::ops::Range<usize>, key: &str) -> Option<usize> {
    let end = span.end.min(text.len());
    let start = span.start.min(end);
    let region = text.get(start..end)?;
    let is_ident = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '-';
    region.match_indices(key).find_map(|(at, _)| {
        let before_ok = region[..at]
            .chars()
            .next_back()
            .is_none_or(|c| !is_ident(c));
        let after = &region[at + key.len()..];
        let after_ok = after.trim_start_matches([' ', '\t']).starts_with('=');
        (before_ok && after_ok).then_some(start + at)
    })
}

/// Byte offset of the first line at or after `from` that assigns `key`.
fn find_key_from(text: &str, from: usize, key: &str) -> Option<usize> {
    let line_start = text[..from.min(text.len())]
        .rfind('\n')
        .map_or(0, |i| i + 1);
    let mut offset = line_start;
    for line in text[line_start..].split_inclusive('\n') {
        let trimmed = line.trim_start();
        if let Some(rest) = trimmed.strip_prefix(key) {
            if rest.trim_start().starts_with('=') {
                return Some(offset + (line.len() - trimmed.len()));
            }
        }
        offset += line.len();
    }
    None
}

impl Scene {
    /// Reads, parses and validates a scene file.
    ///
    /// # Errors
    /// [`ScenarioError::Io`] if it cannot be read, [`ScenarioError::Input`] for anything wrong
    /// in it.
    pub fn load(path: &Path) -> Result<Self, ScenarioError> {
        let text = std::fs::read_to_string(path).map_err(|source| ScenarioError::Io {
            path: path.display().to_string(),
            source,
        })?;
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("scene");
        Self::from_text(&path.display().to_string(), name, &text)
    }

    /// Parses and validates scene text; `file` names it in messages, `default_name` is used
    /// when the scene has no `name`.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] for anything wrong.
    pub fn from_text(file: &str, default_name: &str, text: &str) -> Result<Self, ScenarioError> {
        let raw = parse_scene(file, text)?;
        Self::from_file(file, text, raw, default_name)
    }

    /// Validates and builds a parsed scene. `text` is the source, used to locate errors.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] naming the key, its location and what was expected.
    pub fn from_file(
        file: &str,
        text: &str,
        raw: SceneFile,
        default_name: &str,
    ) -> Result<Self, ScenarioError> {
        let c = Checker { file, text };
        let m = &raw.machine;
        // --- links
        let links = &raw.links;
        let length = c.positive("links.length", links.length, "m")?;
        c.positive(
            "links.material.youngs_modulus",
            links.material.youngs_modulus,
            "Pa",
        )?;
        c.positive("links.material.density", links.material.density, "kg/m^3")?;
        match &links.section {
            SectionConfig::Uniform { thickness, height } => {
                c.positive("links.section.thickness", *thickness, "m")?;
                c.positive("links.section.height", *height, "m")?;
            }
            SectionConfig::Tapered {
                thickness_start,
                thickness_end,
                height,
            } => {
                c.positive("links.section.thickness_start", *thickness_start, "m")?;
                c.positive("links.section.thickness_end", *thickness_end, "m")?;
                c.positive("links.section.height", *height, "m")?;
            }
            SectionConfig::Stepped { steps } => {
                for (k, s) in steps.iter().enumerate() {
                    c.positive(
                        &format!("links.section.steps.{k}.thickness"),
                        s.thickness,
                        "m",
                    )?;
                    c.positive(&format!("links.section.steps.{k}.height"), s.height, "m")?;
                }
            }
        }
        let modes = match (&links.basis, links.modes) {
            (BasisConfig::Hermite { .. }, Some(_)) => {
                return Err(c.error(
                    "links.modes",
                    "the Hermite basis takes its size from basis.elements; remove modes",
                ));
            }
            (BasisConfig::Hermite { elements, .. }, None) => {
                if *elements == 0 {
                    return Err(
                        c.error("links.basis.elements", "expected at least 1 element, got 0")
                    );
                }
                0
            }
            (_, Some(0)) => return Err(c.error("links.modes", "expected at least 1 mode, got 0")),
            (_, Some(r)) if r > 60 => {
                return Err(c.error(
                    "links.modes",
                    format!("{r} modes is more than the supported 60"),
                ));
            }
            (_, Some(r)) => r,
            (_, None) => 3,
        };
        let section = build_section(&links.material, &links.section)
            .map_err(|(k, msg)| c.error(&format!("links.{k}"), msg))?;
        let basis = build_basis(&links.basis, modes)
            .map_err(|(k, msg)| c.error(&format!("links.{k}"), msg))?;
        let link = LinkModel::new(basis, section.as_ref(), length)
            .map_err(|e| c.error("links", e.to_string()))?;
        // Mean cross-section area from the mass: EA for the coupled model's stretch output.
        let axial_stiffness =
            links.material.youngs_modulus * link.mass() / (length * links.material.density);
        // --- geometry
        let geometry = match m.layout.as_str() {
            "radial" => {
                for (k, a) in m.alpha_deg.iter().enumerate() {
                    c.finite(&format!("machine.alpha_deg.{k}"), *a)?;
                }
                c.positive("machine.platform_side", m.platform_side, "m")?;
                c.positive("machine.half_travel", m.half_travel, "m")?;
                if !m.legs.is_empty() {
                    return Err(c.error(
                        "machine.legs",
                        "legs are only read with layout = \"general\"",
                    ));
                }
                Geometry::radial(
                    m.alpha_deg.map(f64::to_radians),
                    length,
                    m.platform_side,
                    m.half_travel,
                )
                .map_err(|e| c.error("machine", e.to_string()))?
            }
            "general" => {
                if m.legs.len() != 3 {
                    return Err(c.error(
                        "machine.legs",
                        format!("expected 3 [[machine.legs]] tables, got {}", m.legs.len()),
                    ));
                }
                let mut legs = Vec::with_capacity(3);
                for (k, leg) in m.legs.iter().enumerate() {
                    let key = format!("machine.legs.{k}");
                    let branch = c.choice(
                        &format!("{key}.branch"),
                        &leg.branch,
                        &[("behind", Branch::Behind), ("ahead", Branch::Ahead)],
                    )?;
                    let a = leg.direction_deg.to_radians();
                    legs.push(Leg {
                        guide: Guide {
                            anchor: Point2::new(leg.anchor[0], leg.anchor[1]),
                            direction: Unit::new_normalize(Vector2::new(a.cos(), a.sin())),
                            travel: (leg.travel[0], leg.travel[1]),
                        },
                        attachment: Vector2::new(leg.attachment[0], leg.attachment[1]),
                        link_length: length,
                        branch,
                    });
                }
                let legs: [Leg; 3] = legs.try_into().expect("three legs");
                Geometry::new(legs).map_err(|e| c.error("machine.legs", e.to_string()))?
            }
            other => {
                return Err(c.error(
                    "machine.layout",
                    format!("unknown value \"{other}\", expected \"radial\" or \"general\""),
                ));
            }
        };
        let platform_mass = c.non_negative("machine.platform_mass", m.platform_mass, "kg")?;
        let platform_inertia = match m.platform_inertia {
            Some(i) => c.non_negative("machine.platform_inertia", i, "kg m^2")?,
            None => platform_mass * m.platform_side * m.platform_side / 12.0,
        };
        let slider_mass = c.non_negative("machine.slider_mass", m.slider_mass, "kg")?;
        let machine = Machine::new(
            geometry,
            [link.clone(), link.clone(), link],
            [slider_mass; 3],
            platform_mass,
            platform_inertia,
        )
        .map_err(|e| c.error("machine", e.to_string()))?;
        // --- time
        let t0 = c.finite("time.start", raw.time.start)?;
        let t1 = c.finite("time.end", raw.time.end)?;
        if t1 <= t0 {
            return Err(c.error(
                "time.end",
                format!("must be after time.start = {t0} s, got {t1} s"),
            ));
        }
        let dt = match raw.time.output_step {
            Some(dt) => c.positive("time.output_step", dt, "s")?,
            None => (t1 - t0) / 1000.0,
        };
        let samples = ((t1 - t0) / dt).round();
        if samples > 5e6 {
            return Err(c.error(
                "time.output_step",
                format!("{samples} output samples is too many (limit 5e6)"),
            ));
        }
        let samples = (samples as usize).max(1);
        let output_times: Vec<f64> = (0..=samples)
            .map(|k| t0 + (t1 - t0) * k as f64 / samples as f64)
            .collect();
        // --- trajectory
        let trajectory: Arc<dyn Trajectory + Send + Sync> = build_trajectory(&c, &raw.trajectory)?;
        let period_hint = match raw.trajectory {
            TrajectoryConfig::Circle { frequency, .. } => 1.0 / frequency.abs(),
            _ => t1 - t0,
        };
        let checks = ((t1 - t0) / period_hint * 400.0).clamp(2000.0, 200_000.0) as usize;
        validate_trajectory(&machine.geometry, trajectory.as_ref(), t0, t1, checks).map_err(
            |e| {
                let pose = match &e {
                    flexprr_kinematics::KinematicsError::AtTime { t, .. } => {
                        let p = trajectory.motion(*t).pose;
                        format!(
                            " (pose x = {:.4} m, y = {:.4} m, phi = {:.2} deg)",
                            p.x,
                            p.y,
                            p.phi.to_degrees()
                        )
                    }
                    _ => String::new(),
                };
                c.error(
                    "trajectory",
                    format!(
                        "leaves the usable workspace (expected every pose from {t0} s to {t1} s \
                         reachable, inside the slider travel and clear of singularities): {e}{pose}"
                    ),
                )
            },
        )?;
        // --- model
        let mo = &raw.model;
        let mut formulation = c.choice(
            "model.formulation",
            &mo.formulation,
            &[
                ("paper", Formulation::paper()),
                ("consistent", Formulation::consistent()),
            ],
        )?;
        if let Some(a) = &mo.axial_force {
            formulation.axial = c.choice(
                "model.axial_force",
                a,
                &[
                    ("none", AxialModel::None),
                    ("paper", AxialModel::Paper),
                    ("joint-reaction", AxialModel::JointReaction),
                ],
            )?;
        }
        if let Some(g) = &mo.geometric_stiffness {
            formulation.geometric_stiffness = c.choice(
                "model.geometric_stiffness",
                g,
                &[("diagonal", Coupling::Diagonal), ("full", Coupling::Full)],
            )?;
        }
        if let Some(b) = mo.coriolis_forcing {
            formulation.coriolis_forcing = b;
        }
        if let Some(b) = mo.centrifugal_softening {
            formulation.centrifugal_softening = b;
        }
        for (k, z) in mo.damping.iter().enumerate() {
            c.non_negative(
                &format!("model.damping.{k}"),
                *z,
                "ratio of critical damping",
            )?;
        }
        let r = machine.links[0].modes();
        if mo.damping.len() > 1 && mo.damping.len() != r {
            return Err(c.error(
                "model.damping",
                format!(
                    "give one ratio for all modes or one per mode ({r}), got {}",
                    mo.damping.len()
                ),
            ));
        }
        let coupling = c.choice(
            "model.coupling",
            &mo.coupling,
            &[
                ("ked", CouplingModel::Ked),
                ("coupled", CouplingModel::Coupled),
            ],
        )?;
        if coupling == CouplingModel::Coupled && formulation != Formulation::consistent() {
            return Err(c.error(
                "model.coupling",
                "the coupled model is built on the consistent equations (actual chord tension, full Kp, \
                 softening, no F_fg): set model.formulation = \"consistent\" without overrides",
            ));
        }
        let damping = ModalDamping {
            ratios: mo.damping.clone(),
        };
        // --- integrator
        let ic = &raw.integrator;
        let method = Method::parse(&ic.method).ok_or_else(|| {
            c.error(
                "integrator.method",
                format!(
                    "unknown value \"{}\", expected \"abm\", \"rk45\" or \"bdf\"",
                    ic.method
                ),
            )
        })?;
        c.positive("integrator.rtol", ic.rtol, "relative tolerance")?;
        if ic.rtol < 1e-14 {
            return Err(c.error(
                "integrator.rtol",
                format!(
                    "{:e} is below what double precision delivers (use >= 1e-14)",
                    ic.rtol
                ),
            ));
        }
        c.non_negative("integrator.atol", ic.atol, "absolute tolerance")?;
        let mut options = Options::default()
            .rtol(ic.rtol)
            .atol(ic.atol)
            .max_steps(ic.max_steps);
        if let Some(h) = ic.max_step {
            options = options.max_step(c.positive("integrator.max_step", h, "s")?);
        }
        if let Some(h) = ic.initial_step {
            options = options.initial_step(c.positive("integrator.initial_step", h, "s")?);
        }
        if ic.max_steps == 0 {
            return Err(c.error("integrator.max_steps", "expected at least 1"));
        }
        // --- outputs
        let mut outputs = BTreeSet::new();
        for (k, name) in raw.output.requests.iter().enumerate() {
            let kind = OutputKind::ALL
                .iter()
                .find(|(_, n)| n == name)
                .map(|(k, _)| *k)
                .ok_or_else(|| {
                    let names: Vec<&str> = OutputKind::ALL.iter().map(|(_, n)| *n).collect();
                    c.error(
                        &format!("output.requests.{k}"),
                        format!(
                            "unknown output \"{name}\", expected one of {}",
                            names.join(", ")
                        ),
                    )
                })?;
            outputs.insert(kind);
        }
        for (k, xi) in raw.output.deflection_xi.iter().enumerate() {
            if !(0.0..=1.0).contains(xi) {
                return Err(c.error(
                    &format!("output.deflection_xi.{k}"),
                    format!("expected a position xi in [0, 1] along the link, got {xi}"),
                ));
            }
        }
        let name = raw.name.clone().unwrap_or_else(|| default_name.to_string());
        Ok(Scene {
            name,
            file: raw,
            machine: Arc::new(machine),
            trajectory,
            axial_model: Arc::from(formulation.axial.model()),
            formulation,
            damping,
            method,
            options,
            output_times,
            outputs,
            coupling,
            axial_stiffness,
        })
    }

    /// Whether the scene needs the modal ODE integrated.
    pub fn needs_integration(&self) -> bool {
        self.outputs.iter().any(|k| k.needs_integration())
    }
}

fn build_trajectory(
    c: &Checker<'_>,
    t: &TrajectoryConfig,
) -> Result<Arc<dyn Trajectory + Send + Sync>, ScenarioError> {
    Ok(match t {
        TrajectoryConfig::Circle {
            centre,
            radius,
            frequency,
            phi_deg,
            start_angle_deg,
        } => {
            c.non_negative("trajectory.radius", *radius, "m")?;
            c.positive("trajectory.frequency", *frequency, "Hz")?;
            c.finite("trajectory.phi_deg", *phi_deg)?;
            Arc::new(
                Circle::new(
                    Point2::new(centre[0], centre[1]),
                    *radius,
                    *frequency,
                    phi_deg.to_radians(),
                    start_angle_deg.to_radians(),
                )
                .map_err(|e| c.error("trajectory", e.to_string()))?,
            )
        }
        TrajectoryConfig::Line { from, velocity } => {
            let v = [velocity[0], velocity[1], velocity[2].to_radians()];
            Arc::new(
                Line::new(pose_from(*from), nalgebra::Vector3::from(v), 0.0)
                    .map_err(|e| c.error("trajectory", e.to_string()))?,
            )
        }
        TrajectoryConfig::PointToPoint {
            from,
            to,
            start,
            duration,
            profile,
        } => {
            c.positive("trajectory.duration", *duration, "s")?;
            let profile = c.choice(
                "trajectory.profile",
                profile,
                &[
                    ("quintic", Profile::Quintic),
                    ("cycloidal", Profile::Cycloidal),
                ],
            )?;
            Arc::new(
                PointToPoint::new(pose_from(*from), pose_from(*to), *start, *duration, profile)
                    .map_err(|e| c.error("trajectory", e.to_string()))?,
            )
        }
        TrajectoryConfig::Waypoints { points } => {
            let pts: Vec<(f64, Pose)> = points
                .iter()
                .map(|p| (p[0], pose_from([p[1], p[2], p[3]])))
                .collect();
            Arc::new(
                WaypointSpline::new(&pts)
                    .map_err(|e| c.error("trajectory.points", e.to_string()))?,
            )
        }
    })
}
