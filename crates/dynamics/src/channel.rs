//! The named signals of the machine: what can be measured on a scene model (outputs) and
//! what can be applied to it (inputs), with their spelling on the command line and in files
//! (`slider_force:2`, `point_force:1@0.125`, `deflection:1@0.5`, `patch_sensor:1`), their
//! units, their names as identifiers (`deflection_1_at_0p5`, the signal names python-control
//! and MATLAB accept), and the measurement of an output on a model's state ([`measure`]).
//!
//! The linear models (`flexprr-linear`) take them as inputs and outputs; a control law that
//! reads measurements or drives inputs can name them the same way. Sliders, links and
//! patches are numbered from 1 in text and from 0 in the types.

use std::fmt;
use std::str::FromStr;

use thiserror::Error;

use crate::{DynamicsError, ExternalLoads, MachineSnapshot, SceneModel};

/// A channel name that does not parse, or one the model cannot give: the one-line reason,
/// which starts with the name.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("{0}")]
pub struct ChannelError(pub String);

/// An input of the machine.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Input {
    /// `slider_force:I`: a force on slider `i` (0-based) along its guide (N).
    SliderForce(usize),
    /// `point_force:LINK@XI`: a transverse point force on link `link` (0-based) at `xi` along
    /// it, along the chord normal `n` (N; the impact of a modal hammer).
    PointForce {
        /// The link (0-based).
        link: usize,
        /// Where along it (0..1).
        xi: f64,
    },
    /// `reference:I`: the commanded position of slider `i` that the slider control law
    /// compares with the measured one (m): a change of the setpoint, its rate and the
    /// feedforward unchanged.
    Reference(usize),
    /// `reference_rate:I`: the commanded velocity of slider `i` that the law compares with
    /// the measured one (m/s). With [`Input::Reference`] it makes the tracking response of a
    /// smooth command: `rho / rho_ref = H_ref(s) + s H_ref_rate(s)`.
    ReferenceRate(usize),
    /// `patch_voltage:P`: a voltage added to patch `p`'s actuator voltage (V), the patches
    /// numbered in the scene's order.
    PatchVoltage(usize),
    /// `actuator_command:I`: the force command of slider `i`'s actuator in place of the
    /// control law's (N): the loop of slider `i` broken at its actuator. The law still runs
    /// and reports its command as the output `slider_command:I`, so that the loop gain is
    /// `L = -slider_command:I / actuator_command:I`.
    ActuatorCommand(usize),
}

/// A platform coordinate.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axis {
    /// `x` (m).
    X,
    /// `y` (m).
    Y,
    /// `phi` (rad).
    Phi,
}

impl Axis {
    /// `x`, `y` or `phi`.
    pub fn name(self) -> &'static str {
        match self {
            Axis::X => "x",
            Axis::Y => "y",
            Axis::Phi => "phi",
        }
    }
    /// The index in `(x, y, phi)`.
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Phi => 2,
        }
    }
    fn parse(text: &str) -> Option<Self> {
        match text.trim() {
            "x" => Some(Axis::X),
            "y" => Some(Axis::Y),
            "phi" => Some(Axis::Phi),
            _ => None,
        }
    }
}

/// An output of the machine.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Output {
    /// `slider:I`: slider `i`'s position `rho_i` (m).
    SliderPosition(usize),
    /// `slider_velocity:I`: its velocity `rho_i'` (m/s).
    SliderVelocity(usize),
    /// `slider_error:I`: the commanded minus the actual position (m), as the slider law
    /// sees it (with a [`Input::Reference`] input added to the command).
    SliderError(usize),
    /// `slider_error_rate:I`: the commanded minus the actual velocity (m/s).
    SliderErrorRate(usize),
    /// `motor_torque:I`: the torque of slider `i`'s motor after saturation (N m).
    MotorTorque(usize),
    /// `slider_command:I`: the force command of the slider control law for slider `i` (N),
    /// before the actuator.
    SliderCommand(usize),
    /// `platform:x|y|phi`: a platform coordinate (m or rad).
    Platform(Axis),
    /// `platform_velocity:x|y|phi`: its rate (m/s or rad/s).
    PlatformVelocity(Axis),
    /// `deflection:LINK@XI`: the transverse deflection `w` of link `link` at `xi`, from its
    /// chord (m).
    Deflection {
        /// The link (0-based).
        link: usize,
        /// Where along it (0..1).
        xi: f64,
    },
    /// `slope:LINK@XI`: the slope `dw/dx` of link `link` at `xi` (rad).
    Slope {
        /// The link (0-based).
        link: usize,
        /// Where along it (0..1).
        xi: f64,
    },
    /// `acceleration:LINK@XI`: the absolute acceleration of the point of link `link` at
    /// `xi` along the chord normal (m/s^2): what an accelerometer on the link reads.
    Acceleration {
        /// The link (0-based).
        link: usize,
        /// Where along it (0..1).
        xi: f64,
    },
    /// `patch_sensor:P`: the sensor voltage of patch `p` (V).
    PatchSensor(usize),
}

/// `link@xi` with a 1-based link and `xi` in `[0, 1]`.
fn link_point(text: &str, what: &str) -> Result<(usize, f64), ChannelError> {
    let bad = |rule: &str| ChannelError(format!("{what}:{text}: {rule}"));
    let (link, xi) = text
        .split_once('@')
        .ok_or_else(|| bad("expected LINK@XI, e.g. 1@0.5 (link 1, 2 or 3; xi from 0 to 1)"))?;
    let link: usize = link
        .trim()
        .parse()
        .map_err(|_| bad("the link must be 1, 2 or 3"))?;
    if !(1..=3).contains(&link) {
        return Err(bad("the link must be 1, 2 or 3"));
    }
    let xi: f64 = xi
        .trim()
        .parse()
        .map_err(|_| bad("xi must be a number from 0 to 1"))?;
    if !(0.0..=1.0).contains(&xi) {
        return Err(bad("xi must be a number from 0 to 1"));
    }
    Ok((link - 1, xi))
}

/// A 1-based slider number.
fn slider(text: &str, what: &str) -> Result<usize, ChannelError> {
    match text.trim().parse::<usize>() {
        Ok(i @ 1..=3) => Ok(i - 1),
        _ => Err(ChannelError(format!(
            "{what}:{text}: the slider must be 1, 2 or 3"
        ))),
    }
}

/// A 1-based patch number (the scene's count is checked where the model is known).
fn patch(text: &str, what: &str) -> Result<usize, ChannelError> {
    match text.trim().parse::<usize>() {
        Ok(p) if p >= 1 => Ok(p - 1),
        _ => Err(ChannelError(format!(
            "{what}:{text}: the patch must be a number from 1 (the scene's patches in order)"
        ))),
    }
}

/// The inputs as `--help` and messages list them.
pub const INPUT_FORMS: &str = "slider_force:I, point_force:LINK@XI, reference:I, reference_rate:I, \
     patch_voltage:P or actuator_command:I";

/// The outputs as `--help` and messages list them.
pub const OUTPUT_FORMS: &str = "slider:I, slider_velocity:I, slider_error:I, slider_error_rate:I, \
     motor_torque:I, slider_command:I, platform:x|y|phi, platform_velocity:x|y|phi, \
     deflection:LINK@XI, slope:LINK@XI, acceleration:LINK@XI or patch_sensor:P";

impl FromStr for Input {
    type Err = ChannelError;
    /// One of [`INPUT_FORMS`] (1-based slider, link and patch).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let unknown = || ChannelError(format!("unknown input {s:?}: expected {INPUT_FORMS}"));
        let (kind, rest) = s.trim().split_once(':').ok_or_else(unknown)?;
        Ok(match kind {
            "slider_force" => Input::SliderForce(slider(rest, kind)?),
            "point_force" => {
                let (link, xi) = link_point(rest, kind)?;
                Input::PointForce { link, xi }
            }
            "reference" => Input::Reference(slider(rest, kind)?),
            "reference_rate" => Input::ReferenceRate(slider(rest, kind)?),
            "patch_voltage" => Input::PatchVoltage(patch(rest, kind)?),
            "actuator_command" => Input::ActuatorCommand(slider(rest, kind)?),
            _ => return Err(unknown()),
        })
    }
}

impl FromStr for Output {
    type Err = ChannelError;
    /// One of [`OUTPUT_FORMS`] (1-based slider, link and patch).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let unknown = || ChannelError(format!("unknown output {s:?}: expected {OUTPUT_FORMS}"));
        let (kind, rest) = s.trim().split_once(':').ok_or_else(unknown)?;
        let axis = || Axis::parse(rest).ok_or_else(unknown);
        Ok(match kind {
            "slider" => Output::SliderPosition(slider(rest, kind)?),
            "slider_velocity" => Output::SliderVelocity(slider(rest, kind)?),
            "slider_error" => Output::SliderError(slider(rest, kind)?),
            "slider_error_rate" => Output::SliderErrorRate(slider(rest, kind)?),
            "motor_torque" => Output::MotorTorque(slider(rest, kind)?),
            "slider_command" => Output::SliderCommand(slider(rest, kind)?),
            "platform" => Output::Platform(axis()?),
            "platform_velocity" => Output::PlatformVelocity(axis()?),
            "deflection" | "slope" | "acceleration" => {
                let (link, xi) = link_point(rest, kind)?;
                match kind {
                    "deflection" => Output::Deflection { link, xi },
                    "slope" => Output::Slope { link, xi },
                    _ => Output::Acceleration { link, xi },
                }
            }
            "patch_sensor" => Output::PatchSensor(patch(rest, kind)?),
            _ => return Err(unknown()),
        })
    }
}

impl fmt::Display for Input {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Input::SliderForce(i) => write!(f, "slider_force:{}", i + 1),
            Input::PointForce { link, xi } => write!(f, "point_force:{}@{xi}", link + 1),
            Input::Reference(i) => write!(f, "reference:{}", i + 1),
            Input::ReferenceRate(i) => write!(f, "reference_rate:{}", i + 1),
            Input::PatchVoltage(p) => write!(f, "patch_voltage:{}", p + 1),
            Input::ActuatorCommand(i) => write!(f, "actuator_command:{}", i + 1),
        }
    }
}

impl fmt::Display for Output {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Output::SliderPosition(i) => write!(f, "slider:{}", i + 1),
            Output::SliderVelocity(i) => write!(f, "slider_velocity:{}", i + 1),
            Output::SliderError(i) => write!(f, "slider_error:{}", i + 1),
            Output::SliderErrorRate(i) => write!(f, "slider_error_rate:{}", i + 1),
            Output::MotorTorque(i) => write!(f, "motor_torque:{}", i + 1),
            Output::SliderCommand(i) => write!(f, "slider_command:{}", i + 1),
            Output::Platform(a) => write!(f, "platform:{}", a.name()),
            Output::PlatformVelocity(a) => write!(f, "platform_velocity:{}", a.name()),
            Output::Deflection { link, xi } => write!(f, "deflection:{}@{xi}", link + 1),
            Output::Slope { link, xi } => write!(f, "slope:{}@{xi}", link + 1),
            Output::Acceleration { link, xi } => write!(f, "acceleration:{}@{xi}", link + 1),
            Output::PatchSensor(p) => write!(f, "patch_sensor:{}", p + 1),
        }
    }
}

/// A channel's text as an identifier: `:` becomes `_`, `@` becomes `_at_`, a decimal point
/// `p` and a minus sign `m` (`deflection:1@0.5` is `deflection_1_at_0p5`): letters, digits
/// and single underscores, starting with a letter, as python-control, MATLAB and Simulink
/// take signal names.
pub fn identifier(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 4);
    for c in text.chars() {
        match c {
            ':' => out.push('_'),
            '@' => out.push_str("_at_"),
            '.' => out.push('p'),
            '-' => out.push('m'),
            '+' => {}
            c if c.is_ascii_alphanumeric() || c == '_' => out.push(c),
            _ => out.push('_'),
        }
    }
    out
}

impl Input {
    /// The SI unit.
    pub fn unit(&self) -> &'static str {
        match self {
            Input::SliderForce(_) | Input::PointForce { .. } | Input::ActuatorCommand(_) => "N",
            Input::Reference(_) => "m",
            Input::ReferenceRate(_) => "m/s",
            Input::PatchVoltage(_) => "V",
        }
    }
    /// The name as an identifier ([`identifier`]): `slider_force_1`, `point_force_1_at_0p125`.
    pub fn signal_name(&self) -> String {
        identifier(&self.to_string())
    }
    /// Whether it enters through the slider control law (a reference), which the model must
    /// have.
    pub fn through_slider_law(&self) -> bool {
        matches!(
            self,
            Input::Reference(_) | Input::ReferenceRate(_) | Input::ActuatorCommand(_)
        )
    }
    /// The loads of this input at `value` (added to `loads`).
    pub fn add_to(&self, loads: &mut ExternalLoads, value: f64, patches: usize) {
        match *self {
            Input::SliderForce(i) => loads.slider[i] += value,
            Input::PointForce { link, xi } => loads.point.push(crate::PointForce {
                link,
                xi,
                force: value,
            }),
            Input::Reference(i) => loads.reference[i] += value,
            Input::ActuatorCommand(i) => {
                loads.slider_command[i] = Some(loads.slider_command[i].unwrap_or(0.0) + value);
            }
            Input::ReferenceRate(i) => loads.reference_rate[i] += value,
            Input::PatchVoltage(p) => {
                if loads.patch_voltage.len() < patches {
                    loads.patch_voltage.resize(patches, 0.0);
                }
                if let Some(v) = loads.patch_voltage.get_mut(p) {
                    *v += value;
                }
            }
        }
    }
}

impl Output {
    /// The SI unit.
    pub fn unit(&self) -> &'static str {
        match self {
            Output::SliderPosition(_) | Output::SliderError(_) | Output::Deflection { .. } => "m",
            Output::SliderVelocity(_) | Output::SliderErrorRate(_) => "m/s",
            Output::MotorTorque(_) => "N m",
            Output::SliderCommand(_) => "N",
            Output::Platform(Axis::Phi) | Output::Slope { .. } => "rad",
            Output::Platform(_) => "m",
            Output::PlatformVelocity(Axis::Phi) => "rad/s",
            Output::PlatformVelocity(_) => "m/s",
            Output::Acceleration { .. } => "m/s^2",
            Output::PatchSensor(_) => "V",
        }
    }
    /// The name as an identifier ([`identifier`]): `slider_1`, `deflection_2_at_0p5`.
    pub fn signal_name(&self) -> String {
        identifier(&self.to_string())
    }
}

/// Why `model` cannot give `input`, if it cannot: a reference without a slider control law,
/// a patch the scene does not have.
///
/// # Errors
/// The reason, starting with the input's name.
pub fn check_input(model: &mut dyn SceneModel, input: &Input) -> Result<(), ChannelError> {
    match *input {
        Input::Reference(_) | Input::ReferenceRate(_) | Input::ActuatorCommand(_)
            if !model.slider_law() =>
        {
            Err(ChannelError(format!(
                "{input}: the sliders are locked (the scene has no [control] law and no \
                 actuators): there is no loop to drive"
            )))
        }
        Input::PatchVoltage(p) => check_patch(model, p, &input.to_string()),
        _ => Ok(()),
    }
}

/// Why `model` cannot give `output` at `(t, y)`, if it cannot.
///
/// # Errors
/// The reason, starting with the output's name.
pub fn check_output(
    model: &mut dyn SceneModel,
    t: f64,
    y: &[f64],
    output: &Output,
) -> Result<(), ChannelError> {
    let name = output.to_string();
    match *output {
        Output::SliderError(_)
        | Output::SliderErrorRate(_)
        | Output::SliderCommand(_)
        | Output::MotorTorque(_)
            if !model.slider_law() =>
        {
            Err(ChannelError(format!(
                "{name}: the sliders are locked (the scene has no [control] law and no actuators)"
            )))
        }
        Output::MotorTorque(i) => {
            let snapshot = model
                .snapshot(t, y)
                .map_err(|e| ChannelError(format!("{name}: {e}")))?;
            match snapshot
                .actuators
                .map(|a| a[i].output.signal(flexprr_control::MOTOR_TORQUE))
            {
                Some(Some(_)) => Ok(()),
                _ => Err(ChannelError(format!(
                    "{name}: slider {}'s actuator is an ideal force, without a motor (actuators.kind = \"motor_ballscrew\" has one)",
                    i + 1
                ))),
            }
        }
        Output::PatchSensor(p) => check_patch(model, p, &name),
        _ => Ok(()),
    }
}

fn check_patch(model: &mut dyn SceneModel, p: usize, name: &str) -> Result<(), ChannelError> {
    let count = model.patch_count();
    if p < count {
        return Ok(());
    }
    Err(ChannelError(if count == 0 {
        format!("{name}: the scene has no piezoelectric patches (links.patches)")
    } else {
        format!(
            "{name}: the scene has {count} patch{} (patch_voltage:1 to :{count})",
            if count == 1 { "" } else { "es" }
        )
    }))
}

/// The commanded slider positions and velocities at `t` (the inverse kinematics of the
/// scene's commanded platform motion), plus the reference inputs of `loads`.
fn commanded(
    model: &dyn SceneModel,
    snapshot: &MachineSnapshot,
    loads: &ExternalLoads,
) -> Result<[(f64, f64); 3], DynamicsError> {
    let legs = model
        .machine()
        .geometry
        .inverse_kinematics_unchecked(&snapshot.nominal)
        .map_err(|source| DynamicsError::Kinematics {
            t: snapshot.t,
            source,
        })?;
    Ok(std::array::from_fn(|i| {
        (
            legs.legs[i].rho + loads.reference[i],
            legs.legs[i].rho_dot + loads.reference_rate[i],
        )
    }))
}

/// The value of each of `outputs` at `(t, y)` under `loads` into `out`, but for an
/// acceleration, which is not a function of the state alone: there the position of the
/// link point projected on `normals[k]` (a linearisation differentiates it twice through
/// the model's equations). The snapshot and the patches are read once.
///
/// # Errors
/// The model fails at `(t, y)`; an output the model does not have (checked first with
/// [`check_output`]) gives NaN.
pub fn measure(
    model: &mut dyn SceneModel,
    t: f64,
    y: &[f64],
    loads: &ExternalLoads,
    outputs: &[Output],
    normals: &[[f64; 2]],
    out: &mut [f64],
) -> Result<(), DynamicsError> {
    let needs_snapshot = outputs.iter().any(|o| {
        !matches!(
            o,
            Output::Deflection { .. } | Output::Slope { .. } | Output::PatchSensor(_)
        )
    });
    let snapshot = if needs_snapshot {
        Some(model.snapshot(t, y)?)
    } else {
        None
    };
    let patches = if outputs.iter().any(|o| matches!(o, Output::PatchSensor(_))) {
        model.patch_states(t, y)?
    } else {
        Vec::new()
    };
    let needs_command = outputs
        .iter()
        .any(|o| matches!(o, Output::SliderError(_) | Output::SliderErrorRate(_)));
    let reference = match (&snapshot, needs_command) {
        (Some(s), true) => Some(commanded(model, s, loads)?),
        _ => None,
    };
    for (k, output) in outputs.iter().enumerate() {
        let s = snapshot.as_ref();
        out[k] = match *output {
            Output::Deflection { link, xi } => model.deflection(t, link, xi, y)?,
            Output::Slope { link, xi } => model.slope(t, link, xi, y)?,
            Output::PatchSensor(p) => patches.get(p).map_or(f64::NAN, |p| p.sensor),
            _ => {
                let Some(s) = s else {
                    unreachable!("the snapshot is taken for these outputs")
                };
                match *output {
                    Output::SliderPosition(i) => s.sliders[i].position,
                    Output::SliderVelocity(i) => s.sliders[i].velocity,
                    Output::SliderError(i) => {
                        reference.map_or(f64::NAN, |r| r[i].0) - s.sliders[i].position
                    }
                    Output::SliderErrorRate(i) => {
                        reference.map_or(f64::NAN, |r| r[i].1) - s.sliders[i].velocity
                    }
                    Output::MotorTorque(i) => s
                        .actuators
                        .and_then(|a| a[i].output.signal(flexprr_control::MOTOR_TORQUE))
                        .unwrap_or(f64::NAN),
                    Output::SliderCommand(i) => s.actuators.map_or(f64::NAN, |a| a[i].command),
                    Output::Platform(axis) => match axis {
                        Axis::X => s.platform.pose.x,
                        Axis::Y => s.platform.pose.y,
                        Axis::Phi => s.platform.pose.phi,
                    },
                    Output::PlatformVelocity(axis) => s.platform.velocity[axis.index()],
                    Output::Acceleration { link, xi } => {
                        let (b, c) = chord(model, s, link);
                        let w = model.deflection(t, link, xi, y)?;
                        let (dx, dy) = (c[0] - b[0], c[1] - b[1]);
                        let length = dx.hypot(dy);
                        let point = [
                            b[0] + xi * dx - w * dy / length,
                            b[1] + xi * dy + w * dx / length,
                        ];
                        point[0] * normals[k][0] + point[1] * normals[k][1]
                    }
                    _ => unreachable!("handled above"),
                }
            }
        };
    }
    Ok(())
}

/// The chord `B_i`, `C_i` of link `link` in the machine `snapshot`.
pub fn chord(
    model: &dyn SceneModel,
    snapshot: &MachineSnapshot,
    link: usize,
) -> ([f64; 2], [f64; 2]) {
    let leg = &model.machine().geometry.legs[link];
    let u = leg.guide.direction.into_inner();
    let rho = snapshot.sliders[link].position;
    let b = leg.guide.anchor.coords + rho * u;
    let pose = snapshot.platform.pose;
    let (sin, cos) = pose.phi.sin_cos();
    let a = leg.attachment;
    let c = [
        pose.x + cos * a.x - sin * a.y,
        pose.y + sin * a.x + cos * a.y,
    ];
    ([b.x, b.y], c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channels_parse_and_print_back() {
        for text in [
            "slider_force:2",
            "point_force:1@0.125",
            "reference:3",
            "reference_rate:1",
            "patch_voltage:2",
            "actuator_command:3",
        ] {
            assert_eq!(text.parse::<Input>().unwrap().to_string(), text);
        }
        for text in [
            "slider:3",
            "slider_velocity:1",
            "slider_error:2",
            "slider_error_rate:3",
            "motor_torque:1",
            "slider_command:2",
            "platform:phi",
            "platform_velocity:x",
            "deflection:2@0.5",
            "slope:3@0",
            "acceleration:1@1",
            "patch_sensor:4",
        ] {
            assert_eq!(text.parse::<Output>().unwrap().to_string(), text);
        }
        for bad in [
            "slider_force:4",
            "point_force:1@1.5",
            "deflection:0@0.5",
            "platform:z",
            "patch_sensor:0",
            "x",
        ] {
            let e = bad
                .parse::<Output>()
                .err()
                .zip(bad.parse::<Input>().err())
                .expect("refused");
            assert!(!e.0.to_string().is_empty() && !e.1.to_string().contains('\n'));
        }
    }

    #[test]
    fn signal_names_are_identifiers() {
        let names = [
            ("deflection:1@0.5", "deflection_1_at_0p5"),
            ("point_force:2@0.125", "point_force_2_at_0p125"),
            ("platform_velocity:phi", "platform_velocity_phi"),
            ("slider:1", "slider_1"),
        ];
        for (text, name) in names {
            assert_eq!(identifier(text), name);
            assert!(
                name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
                    && !name.contains("__")
                    && name.starts_with(|c: char| c.is_ascii_alphabetic())
            );
        }
    }
}
