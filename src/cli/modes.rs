//! `flexprr modes <scene.toml> [--pose X_M,Y_M,PHI_DEG | --time T_S] [--json] [--out DIR]
//! [--force] [--count N]`: the whole machine's natural frequencies, damping ratios and mode
//! shapes at an operating point (docs/linear.md).
//!
//! Without `--pose` or `--time` the operating point is the scene's start pose at rest. The
//! sliders are locked unless the scene has `[control]`; then its law holds them. `--json`
//! prints `{"modes": [...]}` and nothing else on standard output.

use std::path::{Path, PathBuf};

use flexprr_kinematics::Pose;
use flexprr_linear_tools::linear::OperatingPoint;
use flexprr_linear_tools::machine_modes::{
    MODES_PRODUCTS, MachineModes, SHAPE_POINTS, machine_modes_with_progress, modes_csv, modes_json,
    modes_summary_json, modes_svg, start_pose,
};
use flexprr_outdir::OutputDir;
use flexprr_run::RunError;
use flexprr_scene::{ScenarioError, Scene};

use super::Failure;

/// Modes reported when `--count` is not given.
const DEFAULT_COUNT: usize = 12;
/// Most mode shapes drawn in `modes.svg`.
const DRAWN: usize = 6;

/// Arguments of `flexprr modes`.
#[derive(Debug, clap::Args)]
pub struct ModesArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// The platform at rest at this pose: x (m), y (m), phi (deg), e.g. `--pose -0.05,0,45`.
    /// Default: the scene's start pose.
    #[arg(long, value_name = "X_M,Y_M,PHI_DEG", allow_hyphen_values = true)]
    pub pose: Option<String>,
    /// The state of the scene's motion at this time (s), integrated from its start.
    #[arg(long, value_name = "T_S", allow_hyphen_values = true)]
    pub time: Option<String>,
    /// Print `{"modes": [...]}` (JSON) on standard output instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Keep the coupled model's chords axially rigid at rest (the paper's pinned-pinned
    /// idealisation of the locked machine) instead of the links' axial springs `EA / l`
    /// with the platform free on them (the default; docs/linear.md, "Elastic chords").
    #[arg(long)]
    pub rigid_chords: bool,
    /// Write `modes.json`, `modes.csv` and `modes.svg` into this directory.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write into a non-empty directory that flexprr did not write, next to its files (none
    /// of them is overwritten or deleted; a file with the name of an output is refused).
    #[arg(long)]
    pub force: bool,
    /// How many of the lowest modes to report (default 12); `modes.svg` draws up to six.
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub count: Option<String>,
    /// How the actuators' Coulomb friction enters: left out (held at its value at the
    /// operating point, the default) or with its smoothed slope.
    #[arg(long, value_enum, default_value_t = super::frf::CoulombArg::LeftOut)]
    pub coulomb: super::frf::CoulombArg,
}

/// `X,Y,PHI_DEG` as a pose (m, m, rad).
pub(crate) fn parse_pose(text: &str) -> Result<Pose, Failure> {
    let bad = || {
        Failure::bad_input(format!(
            "--pose {text:?}: expected three finite numbers X_M,Y_M,PHI_DEG (m, m, deg), e.g. --pose -0.05,0,45"
        ))
    };
    let values: Vec<f64> = text
        .split(',')
        .map(|v| v.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    match values.as_slice() {
        [x, y, phi] if values.iter().all(|v| v.is_finite()) => {
            flexprr_linear_tools::linear::check_orientation_deg(*phi)
                .map_err(|m| Failure::bad_input(format!("--pose {text}: {m}")))?;
            Ok(Pose::new(*x, *y, phi.to_radians()))
        }
        _ => Err(bad()),
    }
}

/// The operating point the options ask for.
fn operating_point_of(args: &ModesArgs, scene: &Scene) -> Result<OperatingPoint, Failure> {
    match (&args.pose, &args.time) {
        (Some(_), Some(_)) => Err(Failure::bad_input(
            "--pose and --time are exclusive: give --pose for the machine at rest at a pose, or \
             --time for the state of the scene's motion at a time",
        )),
        (Some(pose), None) => Ok(OperatingPoint::Rest(parse_pose(pose)?)),
        (None, Some(time)) => {
            let t: f64 = time.trim().parse().map_err(|_| {
                Failure::bad_input(format!(
                    "--time {time:?}: expected a time in seconds within the scene's span"
                ))
            })?;
            if !t.is_finite() {
                return Err(Failure::bad_input(format!(
                    "--time {time:?}: expected a finite time in seconds"
                )));
            }
            Ok(OperatingPoint::Time(t))
        }
        (None, None) => Ok(OperatingPoint::Rest(start_pose(scene))),
    }
}

/// `--count` as a number of modes (at least 1).
fn parse_count(count: Option<&str>) -> Result<usize, Failure> {
    let Some(text) = count else {
        return Ok(DEFAULT_COUNT);
    };
    match text.trim().parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(Failure::bad_input(format!(
            "--count {text:?}: expected a whole number of modes, at least 1"
        ))),
    }
}

/// A failure of the analysis as the command reports it: bad input (exit 2) placed at the
/// option or in the scene file, anything else a failure of the analysis (exit 1).
fn failure(e: RunError, args: &ModesArgs) -> Failure {
    let RunError::Scene(ScenarioError::Input {
        location,
        key,
        message,
    }) = e
    else {
        return match e {
            RunError::Scene(io @ ScenarioError::Io { .. }) => Failure::bad_input(io),
            other => Failure::run(format!("modes: {other}")),
        };
    };
    let shown = args.scene.display().to_string();
    match key.as_str() {
        "pose" => match &args.pose {
            Some(p) => Failure::bad_input(format!("--pose {p}: {message}")),
            None => Failure::bad_input(format!("{shown}: the scene's start pose: {message}")),
        },
        "time" => Failure::bad_input(format!(
            "--time {}: {message}",
            args.time.as_deref().unwrap_or_default()
        )),
        _ => {
            let location = location.or_else(|| {
                let text = flexprr_scene::read_input_file(&args.scene).ok()?;
                flexprr_scene::locate(&shown, &text, &key)
            });
            Failure::bad_input(ScenarioError::Input {
                location,
                key,
                message,
            })
        }
    }
}

/// Runs the command.
pub fn run(args: ModesArgs) -> Result<(), Failure> {
    let mut scene = Scene::load_for_analysis(&args.scene).map_err(super::run::failure)?;
    scene.rigid_chords |= args.rigid_chords;
    let at = operating_point_of(&args, &scene)?;
    let count = parse_count(args.count.as_deref())?;
    // The directory is checked before the work, so that a refusal costs nothing.
    let target = match &args.out {
        Some(out) => {
            let dir = OutputDir::check(out, MODES_PRODUCTS, args.force, &[&args.scene], &[])
                .map_err(|e| super::run::failure(e.into()))?;
            dir.check_writable()
                .map_err(|e| super::run::failure(e.into()))?;
            Some(dir)
        }
        None => None,
    };
    let progress = super::progress::Progress::start("modes", false);
    let modes = machine_modes_with_progress(
        &scene,
        at,
        SHAPE_POINTS,
        &super::frf::settings(args.coulomb),
        &mut |stage| progress.update(stage, None),
    );
    drop(progress);
    let modes = modes.map_err(|e| failure(e, &args))?;
    if let Some(target) = &target {
        write_files(&scene, &modes, count, target)?;
    }
    if args.json {
        for note in modes
            .notes
            .iter()
            .cloned()
            .chain(truncation_note(&modes, count))
        {
            eprintln!("note: {note}");
        }
        let value = modes_summary_json(&modes, count);
        let text = serde_json::to_string_pretty(&value).unwrap_or_else(|_| value.to_string());
        write_stdout(&(text + "\n"))?;
        if let Some(out) = &args.out {
            eprintln!(
                "modes.json, modes.csv, modes.svg written to {}",
                out.display()
            );
        }
        return Ok(());
    }
    write_stdout(&table(&modes, count, args.out.as_deref()))
}

/// Writes to standard output; a closed pipe (e.g. `| head`) is not an error.
fn write_stdout(text: &str) -> Result<(), Failure> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        Err(e) => Err(Failure::run(format!("cannot write output: {e}"))),
    }
}

/// Writes `modes.json`, `modes.csv` and `modes.svg` (staged, then published).
fn write_files(
    scene: &Scene,
    modes: &MachineModes,
    count: usize,
    target: &OutputDir,
) -> Result<(), Failure> {
    let io = |e: flexprr_outdir::OutputError| Failure::run(e);
    let staging = target.stage().map_err(io)?;
    let dir = staging.path();
    let write = |name: &str, bytes: &[u8]| {
        let path = dir.join(name);
        std::fs::write(&path, bytes).map_err(|e| Failure::run(format!("{}: {e}", path.display())))
    };
    let json = modes_json(modes, count);
    write(
        "modes.json",
        serde_json::to_string_pretty(&json)
            .unwrap_or_default()
            .as_bytes(),
    )?;
    write("modes.csv", &modes_csv(modes, count).map_err(Failure::run)?)?;
    let svg = modes_svg(
        modes,
        &scene.machine.geometry,
        count.min(DRAWN),
        &format!("{}: whole-machine modes {}", scene.name, where_text(modes)),
    );
    write("modes.svg", svg.as_bytes())?;
    staging.publish().map_err(io)?;
    Ok(())
}

/// `at rest at (x, y, φ) = (…)` or `at t = … s, (x, y, φ) = (…)`.
fn where_text(modes: &MachineModes) -> String {
    let pose = format!(
        "(x, y, φ) = ({:.4} m, {:.4} m, {:.2}°)",
        modes.pose.x,
        modes.pose.y,
        modes.pose.phi.to_degrees()
    );
    match modes.operating_point {
        OperatingPoint::Rest(_) => format!("at rest at {pose}"),
        OperatingPoint::Time(t) => format!("at t = {t} s, {pose}"),
    }
}

/// The basis' truncation, when the listed modes reach the first bending family it leaves
/// out.
fn truncation_note(modes: &MachineModes, count: usize) -> Option<String> {
    let highest = modes
        .modes
        .iter()
        .take(count)
        .map(|m| m.frequency_hz)
        .fold(0.0, f64::max);
    modes.truncation.and_then(|t| t.note(highest))
}

/// The table `flexprr modes` prints without `--json`.
fn table(modes: &MachineModes, count: usize, out: Option<&Path>) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{}: {}; sliders {}; {}",
        modes.scene,
        modes.model,
        modes.sliders,
        where_text(modes)
    );
    if modes.chords.starts_with("elastic") {
        let _ = writeln!(s, "chords {}", modes.chords);
    }
    for note in &modes.notes {
        let _ = writeln!(s, "note: {note}");
    }
    if let Some(note) = truncation_note(modes, count) {
        let _ = writeln!(s, "note: {note}");
    }
    let _ = writeln!(
        s,
        "{:>4}  {:>14}  {:>13}  kind",
        "mode", "frequency (Hz)", "damping ratio"
    );
    for (k, m) in modes.modes.iter().take(count).enumerate() {
        let _ = writeln!(
            s,
            "{:>4}  {:>14.4}  {:>13.6}  {}",
            k + 1,
            m.frequency_hz,
            // No `-0.000000` for an undamped mode's rounding.
            if m.damping_ratio.abs() < 5e-7 {
                0.0
            } else {
                m.damping_ratio
            },
            m.kind
        );
    }
    let shown = count.min(modes.modes.len());
    let more = if shown < modes.modes.len() {
        " (--count N for more)"
    } else {
        ""
    };
    let _ = writeln!(
        s,
        "{shown} of {} modes{more}; state of {} ({} coordinates); model {:.2} ms, linearisation {:.2} ms, eigenvalues {:.2} ms",
        modes.modes.len(),
        modes.state_dimension,
        modes.coordinates,
        1e3 * modes.timing.model_s,
        1e3 * modes.timing.linearisation_s,
        1e3 * modes.timing.eigen_s
    );
    if let Some(out) = out {
        let _ = writeln!(
            s,
            "modes.json, modes.csv, modes.svg written to {}",
            out.display()
        );
    }
    s
}
