//! `flexprr statespace`: a scene's linear model as `statespace.npz` (NumPy) and
//! `statespace.json` (docs/linear.md, "State-space export").

use std::path::PathBuf;

use flexprr_linear::realization::Realization;
use flexprr_linear::{Input, Output};
use flexprr_linear_tools::statespace::{
    StateSpaceRequest, check_channels, state_space, state_space_series, write_series,
    write_statespace,
};
use flexprr_outdir::OutputDir;
use flexprr_outdir::STATESPACE;
use flexprr_scene::{ScenarioError, Scene};

use super::Failure;
use super::frf::{channels, located_failure, operating_point, parse_pose};
use super::run::failure;

/// Arguments of `flexprr statespace`.
#[derive(Debug, clap::Args)]
pub struct StateSpaceArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
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
    #[arg(long, value_name = "T_S", conflicts_with = "times")]
    pub time: Option<f64>,
    /// Models along the motion from one integration: at START, START + STEP, ... up to END
    /// (s), e.g. --times 0:0.05:0.001; statespace.npz then has a leading time axis.
    #[arg(long, value_name = "START:END:STEP", conflicts_with = "pose")]
    pub times: Option<String>,
    /// An input (repeatable): slider_force:I, point_force:LINK@XI, reference:I,
    /// reference_rate:I or patch_voltage:P (docs/linear.md, "Channels").
    #[arg(long = "input", value_name = "IN")]
    pub inputs: Vec<String>,
    /// An output (repeatable): slider:I, slider_velocity:I, slider_error:I,
    /// slider_error_rate:I, motor_torque:I, slider_command:I, platform:x|y|phi,
    /// platform_velocity:x|y|phi, deflection:LINK@XI, slope:LINK@XI, acceleration:LINK@XI or
    /// patch_sensor:P.
    #[arg(long = "output", value_name = "OUT")]
    pub outputs: Vec<String>,
    /// The exported state: scaled (divided by powers of two that balance A, the default) or
    /// physical (docs/linear.md, "Scaling").
    #[arg(long, value_name = "KIND", default_value = "scaled")]
    pub realization: String,
    /// How the actuators' Coulomb friction enters: left out (held at its value at the
    /// operating point, the default) or with its smoothed slope.
    #[arg(long, value_enum, default_value_t = super::frf::CoulombArg::LeftOut)]
    pub coulomb: super::frf::CoulombArg,
    /// Output directory (default out/<scene name>_statespace).
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

/// `START:END:STEP` as the times `START, START + STEP, ...` up to `END` (s).
fn parse_times(text: &str) -> Result<Vec<f64>, Failure> {
    let bad = |rule: &str| Failure::bad_input(format!("--times {text:?}: {rule}"));
    let parts: Vec<f64> = text
        .split(':')
        .map(|v| v.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| {
            bad("expected START:END:STEP, three numbers in seconds (e.g. 0:0.05:0.001)")
        })?;
    let [start, end, step] = parts.as_slice() else {
        return Err(bad(
            "expected START:END:STEP, three numbers in seconds (e.g. 0:0.05:0.001)",
        ));
    };
    if !(start.is_finite() && end.is_finite() && step.is_finite()) {
        return Err(bad("the numbers must be finite"));
    }
    if *step <= 0.0 || end < start {
        return Err(bad("STEP must be > 0 and END at least START"));
    }
    let count = ((end - start) / step + 1e-9).floor() as usize + 1;
    if count > MAX_TIMES {
        return Err(bad(&format!(
            "{count} times: at most {MAX_TIMES} (a larger STEP or a shorter span)"
        )));
    }
    Ok((0..count).map(|k| start + k as f64 * step).collect())
}

/// Most times of `--times`.
const MAX_TIMES: usize = 10_000;

/// Runs the command.
pub fn run(args: StateSpaceArgs) -> Result<(), Failure> {
    let mut scene = Scene::load_for_analysis(&args.scene).map_err(failure)?;
    scene.rigid_chords |= args.rigid_chords;
    let inputs: Vec<Input> = channels(&args.inputs)?;
    let outputs: Vec<Output> = channels(&args.outputs)?;
    check_channels(&inputs, &outputs).map_err(|e| located_failure(e, None, None, None))?;
    let realization: Realization = args.realization.parse().map_err(|m: String| {
        Failure::bad_input(format!("--realization {}: {m}", args.realization))
    })?;
    let times = args.times.as_deref().map(parse_times).transpose()?;
    let pose = args.pose.as_deref().map(parse_pose).transpose()?;
    let at = operating_point(&scene, pose, args.time)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(format!("{}_statespace", scene.name)));
    let target = OutputDir::check(&out, STATESPACE, args.force, &[&args.scene], &[])
        .map_err(|e| failure(e.into()))?;
    target.check_writable().map_err(|e| failure(e.into()))?;
    let request = StateSpaceRequest {
        inputs,
        outputs,
        settings: super::frf::settings(args.coulomb),
        realization,
    };
    let located = |e| {
        located_failure(
            e,
            Some(&args.scene),
            args.pose.as_deref(),
            args.time
                .map(|t| t.to_string())
                .or_else(|| args.times.clone()),
        )
    };
    let written_to = |e: ScenarioError| match e {
        ScenarioError::Io { .. } => Failure::run(e),
        other => failure(other),
    };
    if let Some(times) = times {
        let progress = super::progress::Progress::start("statespace", false);
        let series = state_space_series(&scene, &times, &request, &mut |share| {
            progress.update("linearisations", Some(share));
        });
        drop(progress);
        let series = series.map_err(|e| match e {
            flexprr_run::RunError::Scene(ScenarioError::Input { key, message, .. })
                if key == "times" =>
            {
                Failure::bad_input(format!(
                    "--times {}: {message}",
                    args.times.as_deref().unwrap_or_default()
                ))
            }
            other => located(other),
        })?;
        let written = write_series(&scene, &series, &target).map_err(written_to)?;
        let first = &series.models[0];
        println!(
            "{}: {} model, {} times from {} to {} s: {} states, {} inputs, {} outputs ({} realisation{}); one integration {:.3} s, linearisations {:.3} s; {} files written to {}",
            scene.name,
            first.model,
            series.times.len(),
            series.times[0],
            series.times[series.times.len() - 1],
            first.lin.a.nrows(),
            first.lin.b.ncols(),
            first.lin.c.nrows(),
            realization.name(),
            if first.lin.dt > 0.0 {
                format!(", discrete time at dt = {} s", first.lin.dt)
            } else {
                String::new()
            },
            series.integration_s,
            series.linearisation_s,
            written.len(),
            out.display()
        );
        return Ok(());
    }
    let ss = state_space(&scene, at, &request).map_err(located)?;
    let written = write_statespace(&scene, &ss, &target).map_err(written_to)?;
    let lin = &ss.lin;
    println!(
        "{}: {} model, {}: {} states, {} inputs, {} outputs ({} realisation, cond(A) {:.1e}{}); {} files written to {}",
        scene.name,
        ss.model,
        flexprr_linear_tools::frf::at_words(&ss.at),
        lin.a.nrows(),
        lin.b.ncols(),
        lin.c.nrows(),
        realization.name(),
        flexprr_linear::realization::condition_number(&ss.exported.a),
        if lin.dt > 0.0 {
            format!("; discrete time at dt = {} s", lin.dt)
        } else {
            String::new()
        },
        written.len(),
        out.display()
    );
    for note in &lin.notes {
        println!("  note: {note}");
    }
    let lowest: Vec<String> = ss
        .modes
        .iter()
        .take(6)
        .map(|m| format!("{:.2} Hz (zeta {:.4})", m.frequency_hz, m.damping_ratio))
        .collect();
    println!("  lowest modes: {}", lowest.join(", "));
    Ok(())
}
