//! `flexprr frf`: frequency responses of a scene's linear model (docs/linear.md), from the
//! command line or a test plan (`--config`, e.g. `configs/modal_test.toml`, the paper's
//! modal test), with optional mode shapes identified from the responses.

use std::path::{Path, PathBuf};

use flexprr_kinematics::Pose;
use flexprr_linear::{Input, Output};
use flexprr_linear_tools::frf::{FrfRequest, Grid, frequency_responses_with_progress, write_frf};
use flexprr_linear_tools::frf_plan::{FrfPlan, read_frequencies};
use flexprr_linear_tools::linear::OperatingPoint;
use flexprr_outdir::FRF;
use flexprr_outdir::OutputDir;
use flexprr_scene::{ScenarioError, Scene};

use super::Failure;
use super::run::failure;

/// Arguments of `flexprr frf`.
#[derive(Debug, clap::Args)]
pub struct FrfArgs {
    /// Scene file (TOML). With --config, it replaces the plan's scene (the plan's [set]
    /// still applies).
    pub scene: Option<PathBuf>,
    /// A test plan (TOML): the scene and this command's options as keys; options given
    /// here override the plan's (see configs/modal_test.toml, the paper's modal test).
    #[arg(long, value_name = "PLAN")]
    pub config: Option<PathBuf>,
    /// The platform at rest at this pose (m, m, deg), sliders locked or under the scene's
    /// control (default: at rest at the pose where the scene's motion starts).
    #[arg(
        long,
        value_name = "X_M,Y_M,PHI_DEG",
        allow_hyphen_values = true,
        conflicts_with = "time"
    )]
    pub pose: Option<String>,
    /// The state of the scene's motion at this time (s).
    #[arg(long, value_name = "T_S")]
    pub time: Option<f64>,
    /// An input (repeatable): slider_force:I, point_force:LINK@XI (a hammer on the link),
    /// reference:I, reference_rate:I (the slider law's setpoint) or patch_voltage:P
    /// (docs/linear.md, "Channels").
    #[arg(long = "input", value_name = "IN")]
    pub inputs: Vec<String>,
    /// An output (repeatable): slider:I, slider_velocity:I, slider_error:I,
    /// slider_error_rate:I, motor_torque:I, slider_command:I, platform:x|y|phi,
    /// platform_velocity:x|y|phi, deflection:LINK@XI, slope:LINK@XI, acceleration:LINK@XI or
    /// patch_sensor:P.
    #[arg(long = "output", value_name = "OUT")]
    pub outputs: Vec<String>,
    /// How the actuators' Coulomb friction enters: left out (held at its value at the
    /// operating point, the default) or with its smoothed slope.
    #[arg(long, value_enum, default_value_t = CoulombArg::LeftOut)]
    pub coulomb: CoulombArg,
    /// Lowest frequency (Hz; default 1).
    #[arg(long, value_name = "HZ")]
    pub from: Option<f64>,
    /// Highest frequency (Hz; default 1.5 times the highest of the 12 lowest modes).
    #[arg(long, value_name = "HZ")]
    pub to: Option<f64>,
    /// Number of frequencies (default 2000). Without --from, --to and --points the grid is
    /// log-spaced with 21 more points about each mode; with any of them it is linear
    /// (an analyser's lines) unless --log.
    #[arg(long, value_name = "N")]
    pub points: Option<usize>,
    /// Read the frequencies from a file: one per line, or a CSV with them first (e.g. an
    /// earlier frf.csv).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["from", "to", "points", "log"])]
    pub frequencies: Option<PathBuf>,
    /// Log-spaced frequencies.
    #[arg(long)]
    pub log: bool,
    /// Identify this many mode shapes from the responses (one input; outputs along one
    /// link): mode_shapes.csv and mode_shapes.svg against the pinned-pinned sines.
    #[arg(long, value_name = "N")]
    pub identify: Option<usize>,
    /// Output directory (default out/<plan name>, or out/<scene name>_frf).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write into a non-empty directory that flexprr did not write, next to its files.
    #[arg(long)]
    pub force: bool,
    /// Keep the coupled model's chords axially rigid at rest (the paper's pinned-pinned
    /// idealisation of the locked machine) instead of the links' axial springs `EA / l`
    /// with the platform free on them (the default; docs/linear.md, "Elastic chords").
    #[arg(long)]
    pub rigid_chords: bool,
}

/// `--coulomb`: how the actuators' Coulomb friction enters the linear model.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum CoulombArg {
    /// Held at its value at the operating point (the default: at rest the smoothed law's
    /// slope is the smoothing's, not a damper).
    #[default]
    LeftOut,
    /// Its smoothed slope kept (the model as it is integrated).
    Smoothed,
}

/// The linearisation settings of `--coulomb`.
pub fn settings(coulomb: CoulombArg) -> flexprr_linear::Settings {
    flexprr_linear::Settings {
        coulomb: match coulomb {
            CoulombArg::LeftOut => flexprr_linear::Coulomb::LeftOut,
            CoulombArg::Smoothed => flexprr_linear::Coulomb::Smoothed,
        },
        ..flexprr_linear::Settings::default()
    }
}

/// `X,Y,PHI_DEG` as a pose (m, m, rad).
///
/// # Errors
/// A one-line message naming `--pose` and the expected form.
pub fn parse_pose(text: &str) -> Result<Pose, Failure> {
    let values: Vec<f64> = text
        .split(',')
        .map(|v| v.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad_pose(text))?;
    match values.as_slice() {
        [x, y, phi] if values.iter().all(|v| v.is_finite()) => {
            flexprr_linear_tools::linear::check_orientation_deg(*phi)
                .map_err(|m| Failure::bad_input(format!("--pose {text}: {m}")))?;
            Ok(Pose::new(*x, *y, phi.to_radians()))
        }
        _ => Err(bad_pose(text)),
    }
}

fn bad_pose(text: &str) -> Failure {
    Failure::bad_input(format!(
        "--pose {text:?}: expected X_M,Y_M,PHI_DEG, three finite numbers (e.g. --pose 0,0,45)"
    ))
}

/// The operating point of `--pose`/`--time` (or the plan's), by default the scene at rest
/// where its motion starts.
///
/// # Errors
/// A bad pose or time (exit 2).
pub fn operating_point(
    scene: &Scene,
    pose: Option<Pose>,
    time: Option<f64>,
) -> Result<OperatingPoint, Failure> {
    match (pose, time) {
        (Some(p), None) => Ok(OperatingPoint::Rest(p)),
        (None, Some(t)) if t.is_finite() => Ok(OperatingPoint::Time(t)),
        (None, Some(t)) => Err(Failure::bad_input(format!(
            "--time {t}: expected a finite time (s)"
        ))),
        (Some(_), Some(_)) => Err(Failure::bad_input(
            "give either --pose (at rest) or --time (along the motion), not both",
        )),
        (None, None) => {
            let t0 = scene.output_times[0];
            Ok(OperatingPoint::Rest(scene.trajectory.motion(t0).pose))
        }
    }
}

/// Parses channel names; the first bad one is the error (exit 2).
///
/// # Errors
/// The channel's own one-line message.
pub fn channels<T>(names: &[String]) -> Result<Vec<T>, Failure>
where
    T: std::str::FromStr<Err = flexprr_linear::ChannelError>,
{
    names
        .iter()
        .map(|n| n.parse::<T>().map_err(Failure::bad_input))
        .collect()
}

/// The scene and the plan (if any): the positional scene replaces the plan's.
fn scene_and_plan(args: &FrfArgs) -> Result<(Scene, Option<FrfPlan>, Vec<PathBuf>), Failure> {
    let plan = args
        .config
        .as_deref()
        .map(FrfPlan::load)
        .transpose()
        .map_err(failure)?;
    let mut files: Vec<PathBuf> = plan.as_ref().map(|p| p.files.clone()).unwrap_or_default();
    let scene = match (&args.scene, plan.as_ref().and_then(|p| p.scene.clone())) {
        (Some(path), _) => {
            files.push(path.clone());
            match &plan {
                Some(plan) => plan.scene_with_set(path).map_err(failure)?,
                None => Scene::load_for_analysis(path).map_err(failure)?,
            }
        }
        (None, Some(scene)) => scene,
        (None, None) => {
            return Err(Failure::bad_input(match &args.config {
                Some(p) => format!(
                    "{}: the plan names no scene (base = \"scene.toml\" or [scene]): give one on the command line",
                    p.display()
                ),
                None => {
                    "give a scene file (flexprr frf scene.toml ...) or a plan (--config plan.toml)"
                        .into()
                }
            }));
        }
    };
    Ok((scene, plan, files))
}

/// The grid from the options (flags over the plan's keys).
fn grid(args: &FrfArgs, plan: Option<&FrfPlan>) -> Result<Grid, Failure> {
    let flags_give_range =
        args.from.is_some() || args.to.is_some() || args.points.is_some() || args.log;
    let file = match (&args.frequencies, plan.and_then(|p| p.frequencies.clone())) {
        (Some(f), _) => Some(f.clone()),
        (None, Some(f)) if !flags_give_range => Some(f),
        _ => None,
    };
    if let Some(file) = file {
        let frequencies_hz = read_frequencies(&file).map_err(failure)?;
        return Ok(Grid::Listed {
            source: file.display().to_string(),
            frequencies_hz,
        });
    }
    Ok(Grid::Spaced {
        from_hz: args.from.or(plan.and_then(|p| p.from_hz)),
        to_hz: args.to.or(plan.and_then(|p| p.to_hz)),
        points: args.points.or(plan.and_then(|p| p.points)),
        log: args.log || plan.is_some_and(|p| p.log),
    })
}

/// Runs the command.
pub fn run(args: FrfArgs) -> Result<(), Failure> {
    let (mut scene, plan, files) = scene_and_plan(&args)?;
    scene.rigid_chords |= args.rigid_chords;
    let plan = plan.as_ref();
    let inputs: Vec<Input> = if args.inputs.is_empty() {
        plan.map(|p| p.inputs.clone()).unwrap_or_default()
    } else {
        channels(&args.inputs)?
    };
    let outputs: Vec<Output> = if args.outputs.is_empty() {
        plan.map(|p| p.outputs.clone()).unwrap_or_default()
    } else {
        channels(&args.outputs)?
    };
    let (pose, time) = match (&args.pose, args.time) {
        (Some(p), _) => (Some(parse_pose(p)?), None),
        (None, Some(t)) => (None, Some(t)),
        (None, None) => (plan.and_then(|p| p.pose), plan.and_then(|p| p.time)),
    };
    let at = operating_point(&scene, pose, time)?;
    let request = FrfRequest {
        at,
        inputs,
        outputs,
        grid: grid(&args, plan)?,
        identify: args.identify.or(plan.map(|p| p.identify)).unwrap_or(0),
        settings: settings(args.coulomb),
    };
    let out = args.out.clone().unwrap_or_else(|| match plan {
        Some(p) => PathBuf::from("out").join(&p.name),
        None => PathBuf::from("out").join(format!("{}_frf", scene.name)),
    });
    let mut inputs_read: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    if let Some(f) = &args.frequencies {
        inputs_read.push(f);
    }
    let target = OutputDir::check(&out, FRF, args.force, &inputs_read, &[])
        .map_err(|e| failure(e.into()))?;
    target.check_writable().map_err(|e| failure(e.into()))?;
    let progress = super::progress::Progress::start("frf", false);
    let frf = frequency_responses_with_progress(&scene, &request, &mut |stage, share| {
        progress.update(stage, (stage == "responses").then_some(share));
    });
    drop(progress);
    let frf = frf.map_err(|e| {
        located_failure(
            e,
            args.scene.as_deref(),
            args.pose.as_deref(),
            args.time.map(|t| t.to_string()),
        )
    })?;
    let written = write_frf(&scene, &frf, &target).map_err(|e| match e {
        ScenarioError::Io { .. } => Failure::run(e),
        other => failure(other),
    })?;
    report(&scene, &frf, written.len(), &out)
}

/// Maps a run-layer error: bad input exits 2, the rest 1.
pub fn run_failure(e: flexprr_run::RunError) -> Failure {
    match e {
        flexprr_run::RunError::Scene(s) => failure(s),
        other => Failure::run(other),
    }
}

/// As [`run_failure`], with bad input put at its place: a scene key at its line in
/// `scene` (e.g. `paper_f20.toml:30:2: model.coupling: ...` for a KED scene), a pose or
/// time after the option that gave it (`pose` and `time`, as written).
pub fn located_failure(
    e: flexprr_run::RunError,
    scene: Option<&Path>,
    pose: Option<&str>,
    time: Option<String>,
) -> Failure {
    let flexprr_run::RunError::Scene(ScenarioError::Input {
        location,
        key,
        message,
    }) = e
    else {
        return run_failure(e);
    };
    match (key.as_str(), pose, time) {
        ("pose", Some(p), _) => Failure::bad_input(format!("--pose {p}: {message}")),
        ("time", _, Some(t)) => Failure::bad_input(format!("--time {t}: {message}")),
        _ => {
            let location = location.or_else(|| {
                let path = scene?;
                let text = flexprr_scene::read_input_file(path).ok()?;
                flexprr_scene::locate(&path.display().to_string(), &text, &key)
            });
            failure(ScenarioError::Input {
                location,
                key,
                message,
            })
        }
    }
}

/// `f` to ten significant digits, briefly (`1571.283581`, `1e300`).
fn rounded(f: f64) -> String {
    super::short(f, 10)
}

/// Prints what was written, the modes in the grid and the identified shapes; an
/// identification that failed exits 1 after the responses were written.
fn report(
    scene: &Scene,
    frf: &flexprr_linear_tools::frf::Frf,
    files: usize,
    out: &Path,
) -> Result<(), Failure> {
    let top = frf.frequencies_hz.last().copied().unwrap_or(0.0);
    println!(
        "{}: {} model, {}: {} x {} responses at {} frequencies ({} to {} Hz); {files} files written to {}",
        scene.name,
        frf.model,
        flexprr_linear_tools::frf::at_words(&frf.at),
        frf.lin.outputs.len(),
        frf.lin.inputs.len(),
        frf.frequencies_hz.len(),
        rounded(frf.frequencies_hz.first().copied().unwrap_or(0.0)),
        rounded(top),
        out.display()
    );
    for note in &frf.lin.notes {
        println!("  note: {note}");
    }
    // Repeated modes (the three identical links) once, with their multiplicity.
    let mut grouped: Vec<(f64, usize)> = Vec::new();
    for m in frf.modes.iter().filter(|m| m.frequency_hz <= top) {
        match grouped.last_mut() {
            Some((f, n)) if (m.frequency_hz - *f).abs() <= 1e-6 * *f => *n += 1,
            _ => grouped.push((m.frequency_hz, 1)),
        }
    }
    let listed: Vec<String> = grouped
        .iter()
        .map(|(f, n)| {
            if *n > 1 {
                format!("{f:.2} (x{n})")
            } else {
                format!("{f:.2}")
            }
        })
        .collect();
    if listed.is_empty() {
        println!("  no mode up to {} Hz", rounded(top));
    } else {
        println!("  modes up to {} Hz: {}", rounded(top), listed.join(", "));
    }
    match &frf.identified {
        None => Ok(()),
        Some(Ok(modes)) => {
            for m in modes {
                println!(
                    "  mode {}: {:.3} Hz from the responses; shape against sin({} pi xi): largest difference {:.2e}, MAC {:.6}",
                    m.number, m.frequency_hz, m.sine, m.max_difference, m.mac
                );
            }
            Ok(())
        }
        Some(Err(reason)) => Err(Failure::run(format!(
            "mode shapes not identified: {reason} (the responses are written to {})",
            out.display()
        ))),
    }
}
