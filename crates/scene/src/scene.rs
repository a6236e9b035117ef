//! The built scene and how a [`SceneFile`] becomes one.
//!
//! Parsing happens in two passes. Serde reads the file into [`SceneFile`] (unknown keys,
//! wrong types and unknown words are errors with line and column; see `crate::parse`);
//! [`Scene::from_file_with`] then checks every value's range, looks the named parts up in the
//! [`Registry`], builds the machine, checks that the trajectory stays reachable, inside the
//! slider travel and away from singularities over the whole time span (before anything is
//! integrated), and reports any failure with the key and its location. Each section of the
//! file has its own function below.

use std::collections::BTreeSet;
use std::path::Path;
use std::sync::Arc;

use flexprr_control::{Actuator, Controller};
use flexprr_dynamics::{AxialForceModel, Coupling, Formulation, LinkModel, Machine, ModalDamping};
use flexprr_integrators::Options;
use flexprr_kinematics::{
    Branch, Circle, Geometry, Guide, Leg, Line, PointToPoint, Pose, Profile, Trajectory,
    WaypointSpline, validate_trajectory,
};
use nalgebra::{Point2, Unit, Vector2};

use crate::control::build_control;
use crate::error::ScenarioError;
use crate::input::{read_input_file, sanitize_name, unsafe_name_reason};
use crate::link::{build_section, check_link};
use crate::locate::{locate, locate_value};
use crate::parse::parse_scene;
use crate::registry::{BasisParams, MethodHandle, Registry, quoted_list};
use crate::schema::{
    BranchChoice, FormulationChoice, Layout, LinksConfig, MachineConfig, ModelConfig, OutputKind,
    ProfileChoice, SceneFile, StiffnessChoice, TimeConfig, TrajectoryConfig,
};

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
    /// Integrator: the registered method the scene names.
    pub method: MethodHandle,
    /// Integrator options.
    pub options: Options,
    /// Output times (s).
    pub output_times: Vec<f64>,
    /// User stop times (s) from `time.stops`: sorted, without duplicates, inside the span.
    pub stop_times: Vec<f64>,
    /// Requested outputs.
    pub outputs: BTreeSet<OutputKind>,
    /// Requested outputs declared by the program (`output.custom`), in the scene's order.
    pub custom_outputs: Vec<CustomOutput>,
    /// The registered model kind `model.coupling` names (KED, coupled, nonlinear or a
    /// program's own), with its capabilities.
    pub coupling: crate::ModelKindHandle,
    /// Mean axial stiffness `EA` of the links (N), for the coupled model's stretch output.
    pub axial_stiffness: f64,
    /// Linear analyses at rest keep the coupled model's chords axially rigid (the paper's
    /// pinned-pinned idealisation) instead of relaxing them into the links' axial springs
    /// `EA / l` (docs/linear.md): `model.chords = "rigid"`, or `--rigid-chords` of
    /// `flexprr modes/frf/statespace`.
    pub rigid_chords: bool,
    /// The nonlinear model's settings (`model.elements`, `model.collapse_deflection`,
    /// `model.axial_damping_time`; see docs/scenes.md).
    pub large_deflection: LargeDeflection,
    /// The actuator of every slider (`[actuators]`; the ideal force when only `[control]` is
    /// given), when the scene names one: a motor's ratings are what the commanded motion is
    /// checked against (docs/control.md).
    pub actuator: Option<Arc<dyn Actuator>>,
    /// The sliders' control law (`[control]`): when given, the sliders are degrees of
    /// freedom driven by [`Scene::actuator`] under it.
    pub controller: Option<Arc<dyn Controller>>,
    /// The links' piezoelectric patches (`[[links.patches]]`, docs/piezo.md).
    pub patches: Vec<flexprr_dynamics::Patch>,
    /// Their vibration control law (`[vibration_control]`); patches without one only sense.
    pub vibration_controller: Option<Arc<dyn flexprr_control::VibrationController>>,
}

/// Settings of the models that follow a collapse: the coupled one's collapse limit and the
/// nonlinear one's mesh, section and damping.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LargeDeflection {
    /// Co-rotational elements per link (nonlinear model).
    pub elements: usize,
    /// Collapse limit: mid-point deflection as a fraction of the link length (coupled and
    /// nonlinear models).
    pub collapse_deflection: f64,
    /// Kelvin-Voigt time of the axial damping (s, nonlinear model).
    pub axial_damping_time: f64,
    /// Bending stiffness `EI` of the (uniform) links (N m^2); `None` for tapered or stepped
    /// sections, which the nonlinear model refuses.
    pub bending_stiffness: Option<f64>,
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
pub(crate) struct Checker<'a> {
    pub(crate) file: &'a str,
    pub(crate) text: &'a str,
}

impl Checker<'_> {
    /// An error at the value of `key` (for an unknown name).
    pub(crate) fn value_error(&self, key: &str, message: impl Into<String>) -> ScenarioError {
        ScenarioError::Input {
            location: locate_value(self.file, self.text, key),
            key: key.to_string(),
            message: message.into(),
        }
    }
    pub(crate) fn error(&self, key: &str, message: impl Into<String>) -> ScenarioError {
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
    pub(crate) fn non_negative(
        &self,
        key: &str,
        value: f64,
        unit: &str,
    ) -> Result<f64, ScenarioError> {
        if value.is_finite() && value >= 0.0 {
            Ok(value)
        } else {
            Err(self.error(
                key,
                format!("expected a non-negative number ({unit}), got {value:?}"),
            ))
        }
    }
    /// An angle in degrees: finite and within [`MAX_ANGLE_DEG`] of zero. Beyond a few turns
    /// an angle keeps fewer of its digits for the part that matters (`1e19` degrees has
    /// none left), and every angle the scene takes is a direction or an orientation, whose
    /// value within a turn is what counts.
    fn angle(&self, key: &str, value: f64) -> Result<f64, ScenarioError> {
        self.finite(key, value)?;
        if value.abs() > MAX_ANGLE_DEG {
            let advice = if value.abs() < 1e9 {
                format!(
                    "write it reduced to a turn ({} deg), which is the same direction",
                    crate::error::number(value.rem_euclid(360.0))
                )
            } else {
                "at this size the number keeps no digits within a turn".to_string()
            };
            return Err(self.error(
                key,
                format!(
                    "expected an angle within two turns (|angle| <= {MAX_ANGLE_DEG} deg), got \
                     {} deg: {advice}",
                    crate::error::number(value)
                ),
            ));
        }
        Ok(value)
    }
    fn finite(&self, key: &str, value: f64) -> Result<f64, ScenarioError> {
        if value.is_finite() {
            Ok(value)
        } else {
            Err(self.error(key, format!("expected a finite number, got {value:?}")))
        }
    }
}

/// The largest angle (deg, either sign) a scene key takes: two turns.
pub const MAX_ANGLE_DEG: f64 = 720.0;

fn pose_from(values: [f64; 3]) -> Pose {
    Pose::new(values[0], values[1], values[2].to_radians())
}

impl Scene {
    /// Reads, parses and validates a scene file with the built-in parts
    /// ([`Registry::default`]).
    ///
    /// # Errors
    /// [`ScenarioError::Io`] if it cannot be read, [`ScenarioError::Input`] for anything wrong
    /// in it (including a file that is not a regular file or is larger than
    /// [`crate::MAX_INPUT_BYTES`]).
    pub fn load(path: &Path) -> Result<Self, ScenarioError> {
        Self::load_with(&Registry::default(), path)
    }

    /// As [`Scene::load`], with the parts of `registry`.
    ///
    /// # Errors
    /// As [`Scene::load`].
    pub fn load_with(registry: &Registry, path: &Path) -> Result<Self, ScenarioError> {
        let text = read_input_file(path)?;
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("scene");
        Self::from_text_with(registry, &path.display().to_string(), name, &text)
    }

    /// As [`Scene::load`], for commands that build the scene's model and never write its run
    /// outputs (`flexprr modes`, `frf`, `statespace`): the `[output]` requests are left out
    /// instead of being checked against the model kind, so that a coupled scene switched to
    /// `model.coupling = "nonlinear"` still analyses although it requests the modal `modes`
    /// output. A request that is not an output at all is still an error.
    ///
    /// # Errors
    /// As [`Scene::load`].
    pub fn load_for_analysis(path: &Path) -> Result<Self, ScenarioError> {
        let text = read_input_file(path)?;
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("scene");
        Self::from_text_for_analysis(&path.display().to_string(), name, &text)
    }

    /// As [`Scene::from_text`], with the `[output]` requests left out as in
    /// [`Scene::load_for_analysis`].
    ///
    /// # Errors
    /// As [`Scene::from_text`].
    pub fn from_text_for_analysis(
        file: &str,
        default_name: &str,
        text: &str,
    ) -> Result<Self, ScenarioError> {
        let mut raw = parse_scene(file, text)?;
        raw.output.requests.clear();
        Self::from_file_with(&Registry::default(), file, text, raw, default_name)
    }

    /// Parses and validates scene text; `file` names it in messages, `default_name` is used
    /// (made safe, see [`crate::sanitize_name`]) when the scene has no `name`.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] for anything wrong.
    pub fn from_text(file: &str, default_name: &str, text: &str) -> Result<Self, ScenarioError> {
        Self::from_text_with(&Registry::default(), file, default_name, text)
    }

    /// As [`Scene::from_text`], with the parts of `registry`.
    ///
    /// # Errors
    /// As [`Scene::from_text`].
    pub fn from_text_with(
        registry: &Registry,
        file: &str,
        default_name: &str,
        text: &str,
    ) -> Result<Self, ScenarioError> {
        let raw = parse_scene(file, text)?;
        Self::from_file_with(registry, file, text, raw, default_name)
    }

    /// Validates and builds a parsed scene with the built-in parts. `text` is the source,
    /// used to locate errors.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] naming the key, its location and what was expected.
    pub fn from_file(
        file: &str,
        text: &str,
        raw: SceneFile,
        default_name: &str,
    ) -> Result<Self, ScenarioError> {
        Self::from_file_with(&Registry::default(), file, text, raw, default_name)
    }

    /// As [`Scene::from_file`], with the parts of `registry`.
    ///
    /// # Errors
    /// As [`Scene::from_file`].
    pub fn from_file_with(
        registry: &Registry,
        file: &str,
        text: &str,
        mut raw: SceneFile,
        default_name: &str,
    ) -> Result<Self, ScenarioError> {
        let c = Checker { file, text };
        let name = scene_name(&c, raw.name.as_deref(), default_name)?;
        let kind = model_kind(&c, registry, &raw.model)?;
        let caps = kind.capabilities();
        let link = build_link(&c, registry, &raw.links)?;
        // Mean cross-section area from the bare link's mass: EA for the coupled model's
        // stretch output (the patches' layers carry no axial load).
        let links = &raw.links;
        let axial_stiffness =
            links.material.youngs_modulus * link.mass() / (links.length * links.material.density);
        let link_models = crate::piezo::with_patch_layers(&c, &raw, link, caps)?;
        let machine = build_machine(&c, &raw.machine, link_models)?;
        let output_times = build_times(&c, &raw.time)?;
        let stop_times = build_stops(&c, &raw.time, &output_times)?;
        let trajectory = build_trajectory_checked(&c, &raw.trajectory, &machine, &output_times)?;
        let model = build_model_section(&c, registry, &raw.model, machine.links[0].modes(), kind)?;
        let large_deflection = build_large_deflection(&c, &raw.model, &raw.links, caps)?;
        let rigid_chords = rigid_chords(&c, &raw.model, caps)?;
        let control = build_control(&c, registry, &raw, caps)?;
        if let Some(table) = raw.actuators.as_mut()
            && let Some(factory) = registry.actuator(&table.kind)
        {
            crate::actuators::complete(factory.as_ref(), table);
        }
        let piezo = crate::piezo::build_piezo(&c, registry, &raw, &machine)?;
        let (method, options) = build_integrator(&c, registry, &raw)?;
        let span = (output_times[0], output_times[output_times.len() - 1]);
        if let Some(law) = &control.controller {
            check_sample_period(&c, "control", law.period(), span, options.max_steps)?;
        }
        if let Some(law) = &piezo.controller {
            check_sample_period(
                &c,
                "vibration_control",
                law.period(),
                span,
                options.max_steps,
            )?;
        }
        // `auto` becomes its choice for the model; a linear-only method needs the KED model
        // (an actuated model is never linear: it is coupled or nonlinear).
        let mut model_name = match control.controller {
            Some(_) => format!("{} with actuated sliders", model.coupling.name()),
            None => model.coupling.name().to_string(),
        };
        if !piezo.patches.is_empty() {
            model_name.push_str(" with piezoelectric patches");
        }
        let method = registry
            .resolve_method_for(
                method.name(),
                caps.linear_in_state && piezo.patches.is_empty(),
                crate::mechanical_model(
                    &model.coupling,
                    control.controller.as_ref(),
                    control.actuator.as_ref(),
                ),
                &model_name,
            )
            .map_err(|m| c.value_error("integrator.method", m))?;
        let options = spectral_radius(&c, registry, &raw.integrator, method.name(), options)?;
        let outputs = build_outputs(&c, &raw, caps)?;
        let custom_outputs = custom_outputs(&c, registry, &raw)?;
        crate::plan::check_plan(&c, &raw, &machine, span)?;
        Ok(Scene {
            name,
            file: raw,
            machine: Arc::new(machine),
            trajectory,
            axial_model: model.axial_model,
            formulation: model.formulation,
            damping: model.damping,
            method,
            options,
            output_times,
            stop_times,
            outputs,
            custom_outputs,
            coupling: model.coupling,
            axial_stiffness,
            rigid_chords,
            large_deflection,
            actuator: control.actuator,
            controller: control.controller,
            patches: piezo.patches,
            vibration_controller: piezo.controller,
        })
    }

    /// Whether the scene needs the modal ODE integrated.
    pub fn needs_integration(&self) -> bool {
        self.outputs.iter().any(|k| k.needs_integration())
            || self.custom_outputs.iter().any(|o| o.needs_integration)
    }

    /// Whether the scene requests the output called `name` (built in or declared).
    pub fn requests(&self, name: &str) -> bool {
        self.outputs.iter().any(|k| k.name() == name)
            || self.custom_outputs.iter().any(|o| o.name == name)
    }
}

/// An output a program declared ([`Registry::register_output`]) and a scene requests in
/// `output.custom`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CustomOutput {
    /// Its name (`output.custom`).
    pub name: String,
    /// Whether it reads the integrated model.
    pub needs_integration: bool,
}

/// `output.custom`: each name declared in `registry`, not a built-in output, once.
fn custom_outputs(
    c: &Checker<'_>,
    registry: &Registry,
    raw: &SceneFile,
) -> Result<Vec<CustomOutput>, ScenarioError> {
    let mut out: Vec<CustomOutput> = Vec::new();
    for (k, name) in raw.output.custom.iter().enumerate() {
        let key = format!("output.custom.{k}");
        if OutputKind::ALL.iter().any(|(_, n)| n == name) {
            return Err(c.value_error(
                &key,
                format!("\"{name}\" is a built-in output: request it in output.requests"),
            ));
        }
        let Some(output) = registry.output(name) else {
            let names = registry.output_names();
            let known = if names.is_empty() {
                "none is declared (a program declares its own with Registry::register_output)"
                    .to_string()
            } else {
                format!("expected one of {}", quoted_list(&names))
            };
            return Err(c.value_error(&key, format!("unknown output \"{name}\": {known}")));
        };
        if out.iter().any(|o| o.name == *name) {
            return Err(c.value_error(&key, format!("\"{name}\" is requested twice")));
        }
        out.push(output.clone());
    }
    Ok(out)
}

/// The scene's name: `name` if given (it must be safe, it names `out/<name>`), else the file
/// stem made safe.
fn scene_name(
    c: &Checker<'_>,
    name: Option<&str>,
    default_name: &str,
) -> Result<String, ScenarioError> {
    match name {
        Some(name) => match unsafe_name_reason(name) {
            None => Ok(name.to_string()),
            Some(reason) => Err(c.error(
                "name",
                format!(
                    "{name:?} {reason}; a scene name names its output directory, so it must be \
                     1 to {} characters of A-Z a-z 0-9 . _ - not starting with '.'",
                    crate::input::MAX_NAME_LEN
                ),
            )),
        },
        None => Ok(sanitize_name(default_name)),
    }
}

/// `[links]`: material, section (with the slenderness rule) and the registered basis.
fn build_link(
    c: &Checker<'_>,
    registry: &Registry,
    links: &LinksConfig,
) -> Result<LinkModel, ScenarioError> {
    check_link(&links.material, &links.section, links.length)
        .map_err(|(k, msg)| c.error(&format!("links.{k}"), msg))?;
    let params = BasisParams::new(c.file, c.text, "links.basis", &links.basis.params);
    let basis = registry.build_basis(&params, &links.basis.kind, "links.modes", links.modes)?;
    let section = build_section(&links.material, &links.section)
        .map_err(|(k, msg)| c.error(&format!("links.{k}"), msg))?;
    LinkModel::new(basis, section.as_ref(), links.length)
        .map_err(|e| c.error("links", e.to_string()))
}

/// `[machine]`: the guides' geometry and the rigid-body inertia.
/// The machine of `raw` with its links' patch layers, and its patches with the vibration
/// control law (`[[links.patches]]`, `[vibration_control]`), as validation builds them: for
/// checking a changed `vibration_control` table against the law's own keys.
pub(crate) fn build_patches(
    c: &Checker<'_>,
    registry: &Registry,
    raw: &SceneFile,
) -> Result<(), ScenarioError> {
    let caps = model_kind(c, registry, &raw.model)?.capabilities();
    let link = build_link(c, registry, &raw.links)?;
    let link_models = crate::piezo::with_patch_layers(c, raw, link, caps)?;
    let machine = build_machine(c, &raw.machine, link_models)?;
    crate::piezo::build_piezo(c, registry, raw, &machine).map(|_| ())
}

fn build_machine(
    c: &Checker<'_>,
    m: &MachineConfig,
    links: [LinkModel; 3],
) -> Result<Machine, ScenarioError> {
    let geometry = match m.layout {
        Layout::Radial => radial_geometry(c, m, links[0].length())?,
        Layout::General => general_geometry(c, m, links[0].length())?,
    };
    let platform_mass = c.non_negative("machine.platform_mass", m.platform_mass, "kg")?;
    let platform_inertia = match m.platform_inertia {
        Some(i) => c.non_negative("machine.platform_inertia", i, "kg m^2")?,
        None => platform_mass * m.platform_side * m.platform_side / 12.0,
    };
    let slider_mass = c.non_negative("machine.slider_mass", m.slider_mass, "kg")?;
    Machine::new(
        geometry,
        links,
        [slider_mass; 3],
        platform_mass,
        platform_inertia,
    )
    .map_err(|e| c.error("machine", e.to_string()))
}

fn radial_geometry(
    c: &Checker<'_>,
    m: &MachineConfig,
    length: f64,
) -> Result<Geometry, ScenarioError> {
    for (k, a) in m.alpha_deg.iter().enumerate() {
        c.angle(&format!("machine.alpha_deg.{k}"), *a)?;
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
    .map_err(|e| c.error("machine", e.to_string()))
}

fn general_geometry(
    c: &Checker<'_>,
    m: &MachineConfig,
    length: f64,
) -> Result<Geometry, ScenarioError> {
    let [l0, l1, l2] = m.legs.as_slice() else {
        return Err(c.error(
            "machine.legs",
            format!("expected 3 [[machine.legs]] tables, got {}", m.legs.len()),
        ));
    };
    let mut legs = Vec::with_capacity(3);
    for (k, leg) in [l0, l1, l2].into_iter().enumerate() {
        let key = format!("machine.legs.{k}");
        for (field, values) in [
            ("anchor", &leg.anchor[..]),
            ("travel", &leg.travel[..]),
            ("attachment", &leg.attachment[..]),
            ("direction_deg", std::slice::from_ref(&leg.direction_deg)),
        ] {
            for v in values {
                c.finite(&format!("{key}.{field}"), *v)?;
            }
        }
        c.angle(&format!("{key}.direction_deg"), leg.direction_deg)?;
        let a = leg.direction_deg.to_radians();
        legs.push(Leg {
            guide: Guide {
                anchor: Point2::new(leg.anchor[0], leg.anchor[1]),
                direction: Unit::new_normalize(Vector2::new(a.cos(), a.sin())),
                travel: (leg.travel[0], leg.travel[1]),
            },
            attachment: Vector2::new(leg.attachment[0], leg.attachment[1]),
            link_length: length,
            branch: match leg.branch {
                BranchChoice::Behind => Branch::Behind,
                BranchChoice::Ahead => Branch::Ahead,
            },
        });
    }
    let legs: [Leg; 3] = match legs.try_into() {
        Ok(legs) => legs,
        Err(_) => unreachable!("three legs were matched above"),
    };
    Geometry::new(legs).map_err(|e| c.error("machine.legs", e.to_string()))
}

/// `[time]`: the output times, evenly spaced by `output_step` (at most the span).
fn build_times(c: &Checker<'_>, time: &TimeConfig) -> Result<Vec<f64>, ScenarioError> {
    let t0 = c.finite("time.start", time.start)?;
    let t1 = c.finite("time.end", time.end)?;
    if t1 <= t0 {
        return Err(c.error(
            "time.end",
            format!("must be after time.start = {t0} s, got {t1} s"),
        ));
    }
    let dt = match time.output_step {
        Some(dt) => c.positive("time.output_step", dt, "s")?,
        None => (t1 - t0) / 1000.0,
    };
    if dt > t1 - t0 {
        return Err(c.error(
            "time.output_step",
            format!(
                "{dt:?} s is longer than the time span {:?} s (time.end - time.start)",
                t1 - t0
            ),
        ));
    }
    let samples = ((t1 - t0) / dt).round();
    if samples > 5e6 {
        return Err(c.error(
            "time.output_step",
            format!("{samples:.3e} output samples is too many (limit 5e6)"),
        ));
    }
    let samples = (samples as usize).max(1);
    Ok((0..=samples)
        .map(|k| t0 + (t1 - t0) * k as f64 / samples as f64)
        .collect())
}

/// `time.stops`: finite, inside `[start, end]`; returned sorted without duplicates.
fn build_stops(
    c: &Checker<'_>,
    time: &TimeConfig,
    times: &[f64],
) -> Result<Vec<f64>, ScenarioError> {
    let (t0, t1) = (times[0], times[times.len() - 1]);
    let mut stops = Vec::with_capacity(time.stops.len());
    for (k, &t) in time.stops.iter().enumerate() {
        let key = format!("time.stops.{k}");
        c.finite(&key, t)?;
        if t < t0 || t > t1 {
            return Err(c.error(
                &key,
                format!("stop time {t} s is outside the time span [{t0}, {t1}] s"),
            ));
        }
        stops.push(t);
    }
    stops.sort_by(f64::total_cmp);
    stops.dedup_by(|a, b| (*a - *b).abs() <= f64::EPSILON * a.abs().max(1.0));
    Ok(stops)
}

/// The most samples a sampled law may take over a run: as many as output samples, and never
/// more than the integration's steps (each sample restarts the integration).
const MAX_SAMPLES: f64 = 5e6;

/// A sampled law's `period` (the key `{table}.period`) against what a run can resolve: its
/// samples are stop times of the integration, generated as the run goes, and each is kept
/// for the outputs, so their number over the time span must stay within
/// `integrator.max_steps` and [`MAX_SAMPLES`].
fn check_sample_period(
    c: &Checker<'_>,
    table: &str,
    period: f64,
    (t0, t1): (f64, f64),
    max_steps: usize,
) -> Result<(), ScenarioError> {
    if period.is_nan() || period <= 0.0 {
        return Ok(());
    }
    let samples = (t1 - t0) / period;
    let limit = MAX_SAMPLES.min(max_steps as f64);
    if samples > limit {
        let key = format!("{table}.period");
        let why = if (max_steps as f64) < MAX_SAMPLES {
            format!("each sample restarts the integration, and integrator.max_steps is {max_steps}")
        } else {
            format!(
                "each sample restarts the integration and is kept for the outputs: at most {} \
                 samples, as for output samples",
                crate::error::number(MAX_SAMPLES)
            )
        };
        return Err(c.error(
            &key,
            format!(
                "a sample period of {} s gives {} samples over the {} s time span, more than \
                 a run can resolve ({why}); use a period of at least {} s, or 0 for a \
                 continuous law",
                crate::error::number(period),
                crate::error::number(samples.round()),
                crate::error::number(t1 - t0),
                crate::error::number((t1 - t0) / limit)
            ),
        ));
    }
    Ok(())
}

/// `[trajectory]`, checked over the whole time span against the machine's workspace.
fn build_trajectory_checked(
    c: &Checker<'_>,
    config: &TrajectoryConfig,
    machine: &Machine,
    times: &[f64],
) -> Result<Arc<dyn Trajectory + Send + Sync>, ScenarioError> {
    let (t0, t1) = (times[0], times[times.len() - 1]);
    let trajectory = build_trajectory(c, config, t1)?;
    let period_hint = match config {
        TrajectoryConfig::Circle { frequency, .. } => 1.0 / frequency.abs(),
        _ => t1 - t0,
    };
    let checks = ((t1 - t0) / period_hint * 400.0).clamp(2000.0, 200_000.0) as usize;
    validate_trajectory(&machine.geometry, trajectory.as_ref(), t0, t1, checks).map_err(|e| {
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
    })?;
    Ok(trajectory)
}

/// What `[model]` builds.
struct ModelParts {
    formulation: Formulation,
    axial_model: Arc<dyn AxialForceModel>,
    damping: ModalDamping,
    coupling: crate::ModelKindHandle,
}

/// The registered model kind `model.coupling` names.
fn model_kind(
    c: &Checker<'_>,
    registry: &Registry,
    mo: &ModelConfig,
) -> Result<crate::ModelKindHandle, ScenarioError> {
    registry.model_kind(&mo.coupling).ok_or_else(|| {
        c.value_error(
            "model.coupling",
            format!(
                "unknown model \"{}\", expected one of {}",
                mo.coupling,
                quoted_list(&registry.model_kind_names())
            ),
        )
    })
}

/// `[model]`: formulation preset and overrides, the registered axial force model, damping
/// ratios for `modes` modes, KED or coupled.
fn build_model_section(
    c: &Checker<'_>,
    registry: &Registry,
    mo: &ModelConfig,
    modes: usize,
    coupling: crate::ModelKindHandle,
) -> Result<ModelParts, ScenarioError> {
    let caps = coupling.capabilities();
    let mut formulation = match mo.formulation {
        FormulationChoice::Paper => Formulation::paper(),
        FormulationChoice::Consistent => Formulation::consistent(),
    };
    let mut axial_model: Arc<dyn AxialForceModel> = Arc::from(formulation.axial.model());
    let mut custom_axial = false;
    if let Some(name) = &mo.axial_force {
        let entry = registry.axial_entry(name).ok_or_else(|| {
            c.value_error(
                "model.axial_force",
                format!(
                    "unknown axial force model \"{name}\", expected one of {}",
                    quoted_list(&registry.axial_force_names())
                ),
            )
        })?;
        axial_model = entry.model.clone();
        match entry.preset {
            Some(preset) => formulation.axial = preset,
            None => custom_axial = true,
        }
    }
    if let Some(g) = mo.geometric_stiffness {
        formulation.geometric_stiffness = match g {
            StiffnessChoice::Diagonal => Coupling::Diagonal,
            StiffnessChoice::Full => Coupling::Full,
        };
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
    if mo.damping.len() > 1 && mo.damping.len() != modes {
        return Err(c.error(
            "model.damping",
            format!(
                "give one ratio for all modes or one per mode ({modes}), got {}",
                mo.damping.len()
            ),
        ));
    }
    if caps.consistent_only && (formulation != Formulation::consistent() || custom_axial) {
        return Err(c.error(
            "model.coupling",
            "the coupled and nonlinear models are built on the consistent equations (actual chord tension, full Kp, \
             softening, no F_fg): set model.formulation = \"consistent\" without overrides",
        ));
    }
    if !caps.assumed_modes && !mo.damping.is_empty() {
        return Err(c.error(
            "model.damping",
            "the nonlinear model has no modes to damp: remove model.damping (model.axial_damping_time damps its axial strain rate)",
        ));
    }
    Ok(ModelParts {
        formulation,
        axial_model,
        damping: ModalDamping {
            ratios: mo.damping.clone(),
        },
        coupling,
    })
}

/// Default elements per link of the nonlinear model: the dynamics crate's
/// [`flexprr_dynamics::nonlinear::DEFAULT_ELEMENTS`] (one default for code, docs and scenes;
/// docs/scenes.md, "elements", and docs/performance.md give its error and cost).
pub const DEFAULT_ELEMENTS: usize = flexprr_dynamics::nonlinear::DEFAULT_ELEMENTS;

/// Default collapse limit: 10 % of the link length, the external model's criterion
/// (validation/data/collapse_speeds.json) and where the coupled model is still within 2 % of it.
pub const DEFAULT_COLLAPSE_DEFLECTION: f64 = 0.1;

/// `model.chords`: whether linear analyses at rest keep the coupled model's chords rigid;
/// refused for the other models.
fn rigid_chords(
    c: &Checker<'_>,
    mo: &ModelConfig,
    caps: crate::ModelCapabilities,
) -> Result<bool, ScenarioError> {
    match mo.chords {
        None => Ok(false),
        Some(_) if !caps.modal_machine() => Err(c.error(
            "model.chords",
            "the chords of linear analyses at rest are a setting of the coupled model (the nonlinear model's links stretch): set model.coupling = \"coupled\" or remove the key",
        )),
        Some(choice) => Ok(choice == crate::schema::ChordsChoice::Rigid),
    }
}

/// `model.elements`, `model.collapse_deflection`, `model.axial_damping_time`: checked, and
/// refused where the scene's model does not use them.
fn build_large_deflection(
    c: &Checker<'_>,
    mo: &ModelConfig,
    links: &crate::schema::LinksConfig,
    caps: crate::ModelCapabilities,
) -> Result<LargeDeflection, ScenarioError> {
    let nonlinear = !caps.assumed_modes;
    let elements = mo.elements.unwrap_or(DEFAULT_ELEMENTS);
    if mo.elements.is_some() && !nonlinear {
        return Err(c.error(
            "model.elements",
            "elements per link are a setting of the nonlinear model: set model.coupling = \"nonlinear\" or remove the key",
        ));
    }
    if !(2..=512).contains(&elements) || elements % 2 == 1 {
        return Err(c.value_error(
            "model.elements",
            format!("{elements} elements per link: expected an even number from 2 to 512 (the mid-point is a node)"),
        ));
    }
    if mo.axial_damping_time.is_some() && !nonlinear {
        return Err(c.error(
            "model.axial_damping_time",
            "the axial damping time is a setting of the nonlinear model: set model.coupling = \"nonlinear\" or remove the key",
        ));
    }
    let axial_damping_time = mo.axial_damping_time.unwrap_or(0.0);
    c.non_negative(
        "model.axial_damping_time",
        axial_damping_time,
        "time in seconds",
    )?;
    if mo.collapse_deflection.is_some() && !caps.free_platform {
        return Err(c.error(
            "model.collapse_deflection",
            "the KED model prescribes the rigid platform motion and cannot collapse: set model.coupling = \"coupled\" or \"nonlinear\", or remove the key",
        ));
    }
    let collapse_deflection = mo
        .collapse_deflection
        .unwrap_or(DEFAULT_COLLAPSE_DEFLECTION);
    if !(collapse_deflection.is_finite() && collapse_deflection > 0.0 && collapse_deflection <= 1.0)
    {
        return Err(c.value_error(
            "model.collapse_deflection",
            format!("{collapse_deflection}: expected a fraction of the link length in (0, 1]"),
        ));
    }
    let bending_stiffness = match links.section {
        crate::link::SectionConfig::Uniform { thickness, height } => {
            Some(links.material.youngs_modulus * height * thickness.powi(3) / 12.0)
        }
        _ => None,
    };
    if nonlinear && bending_stiffness.is_none() {
        return Err(c.error(
            "links.section",
            "the nonlinear model has uniform links only: use section.kind = \"uniform\" or model.coupling = \"coupled\"",
        ));
    }
    Ok(LargeDeflection {
        elements,
        collapse_deflection,
        axial_damping_time,
        bending_stiffness,
    })
}

/// `integrator.spectral_radius`: in `[0, 1]`, and only for a method with numerical
/// dissipation (a mechanical one: `generalized_alpha`, also when `auto` resolves to it).
fn spectral_radius(
    c: &Checker<'_>,
    registry: &Registry,
    ic: &crate::schema::IntegratorConfig,
    resolved: &str,
    options: Options,
) -> Result<Options, ScenarioError> {
    let Some(rho) = ic.spectral_radius else {
        return Ok(options);
    };
    let key = "integrator.spectral_radius";
    if !matches!(
        registry.method_kind(resolved),
        Some(crate::registry::MethodKind::Mechanical)
    ) {
        return Err(c.error(
            key,
            format!(
                "the spectral radius is generalized_alpha's, and this scene is integrated by \
                 {resolved}: remove the key or set integrator.method = \"generalized_alpha\" \
                 (nonlinear model)"
            ),
        ));
    }
    if !(0.0..=1.0).contains(&rho) {
        return Err(c.error(
            key,
            format!(
                "expected a spectral radius at infinite frequency from 0 (most numerical \
                 dissipation) to 1 (none), got {}",
                crate::error::number(rho)
            ),
        ));
    }
    Ok(options.spectral_radius(rho))
}

/// `[integrator]`: the registered method and its options.
fn build_integrator(
    c: &Checker<'_>,
    registry: &Registry,
    raw: &SceneFile,
) -> Result<(MethodHandle, Options), ScenarioError> {
    let ic = &raw.integrator;
    let method = registry.method(&ic.method).ok_or_else(|| {
        c.value_error(
            "integrator.method",
            format!(
                "unknown value \"{}\", expected one of {}",
                ic.method,
                quoted_list(&registry.integrator_names())
            ),
        )
    })?;
    if !(ic.rtol.is_finite() && ic.rtol > 0.0 && ic.rtol < 1.0) {
        return Err(c.error(
            "integrator.rtol",
            format!(
                "expected a positive relative tolerance below 1, got {:?}",
                ic.rtol
            ),
        ));
    }
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
    if ic.atol <= 0.0 {
        return Err(c.error(
            "integrator.atol",
            "0 is not allowed: the modal coordinates start at zero, where a purely relative \
             tolerance cannot be met; give a positive absolute tolerance (e.g. 1e-12)",
        ));
    }
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
    Ok((method, options))
}

/// `[output]`: the requested outputs and deflection positions.
fn build_outputs(
    c: &Checker<'_>,
    raw: &SceneFile,
    caps: crate::ModelCapabilities,
) -> Result<BTreeSet<OutputKind>, ScenarioError> {
    for (k, xi) in raw.output.deflection_xi.iter().enumerate() {
        if !(0.0..=1.0).contains(xi) {
            return Err(c.error(
                &format!("output.deflection_xi.{k}"),
                format!(
                    "expected a position xi in [0, 1] along the link, got {}",
                    crate::error::number(*xi)
                ),
            ));
        }
    }
    if !caps.free_platform {
        let whole = OutputKind::MachineFrequencies;
        if let Some(k) = raw.output.requests.iter().position(|r| *r == whole) {
            return Err(c.value_error(
                &format!("output.requests.{k}"),
                "\"machine_frequencies\" linearises the whole machine (sliders, links and \
                 platform together), which the KED model does not have: it prescribes the \
                 platform and the sliders (its per-link frequencies are the \"frequencies\" \
                 output); set model.coupling = \"coupled\" or \"nonlinear\"",
            ));
        }
    }
    if raw.links.patches.is_empty() {
        if let Some(k) = raw
            .output
            .requests
            .iter()
            .position(|r| *r == OutputKind::Piezo)
        {
            return Err(c.value_error(
                &format!("output.requests.{k}"),
                "\"piezo\" reports the piezoelectric patches' voltages and power, and the \
                 scene has none: add [[links.patches]] (docs/piezo.md) or remove the request",
            ));
        }
    }
    if !caps.assumed_modes {
        let modal = [
            (OutputKind::Modes, "modes"),
            (OutputKind::ModalForces, "modal_forces"),
        ];
        for (k, request) in raw.output.requests.iter().enumerate() {
            if let Some((_, name)) = modal.iter().find(|(kind, _)| kind == request) {
                return Err(c.value_error(
                    &format!("output.requests.{k}"),
                    format!(
                        "\"{name}\" is a modal output; the nonlinear model has nodal coordinates, \
                         not modes (it gives deflections, platform_deviation, nonlinear_forces and \
                         energies): remove it or use model.coupling = \"coupled\""
                    ),
                ));
            }
        }
    }
    Ok(raw.output.requests.iter().copied().collect())
}

fn build_trajectory(
    c: &Checker<'_>,
    t: &TrajectoryConfig,
    end: f64,
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
            c.angle("trajectory.phi_deg", *phi_deg)?;
            c.angle("trajectory.start_angle_deg", *start_angle_deg)?;
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
            c.angle("trajectory.from.2", from[2])?;
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
            c.angle("trajectory.from.2", from[2])?;
            c.angle("trajectory.to.2", to[2])?;
            let profile = match profile {
                ProfileChoice::Quintic => Profile::Quintic,
                ProfileChoice::Cycloidal => Profile::Cycloidal,
            };
            Arc::new(
                PointToPoint::new(pose_from(*from), pose_from(*to), *start, *duration, profile)
                    .map_err(|e| c.error("trajectory", e.to_string()))?,
            )
        }
        TrajectoryConfig::Waypoints { points } => {
            for (k, p) in points.iter().enumerate() {
                c.angle(&format!("trajectory.points.{k}.3"), p[3])?;
            }
            let pts: Vec<(f64, Pose)> = points
                .iter()
                .map(|p| (p[0], pose_from([p[1], p[2], p[3]])))
                .collect();
            Arc::new(
                WaypointSpline::new(&pts)
                    .map_err(|e| c.error("trajectory.points", e.to_string()))?,
            )
        }
        TrajectoryConfig::Planned(data) => crate::plan::planned_trajectory(c, data, end)?,
    })
}
