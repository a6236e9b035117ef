//! `flexprr statespace`: a scene's linear model as `statespace.npz` (NumPy) and
//! `statespace.json` (docs/linear.md, "State-space export").

use std::path::PathBuf;

use flexprr_linear::{Input, Output};
use flexprr_run::OutputDir;
use flexprr_run::output_dir::STATESPACE;
use flexprr_run::statespace::{state_space, write_statespace};
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
    #[arg(long, value_name = "T_S")]
    pub time: Option<f64>,
    /// An input (repeatable): slider_force:I or point_force:LINK@XI.
    #[arg(long = "input", value_name = "IN")]
    pub inputs: Vec<String>,
    /// An output (repeatable): slider:I, platform:x|y|phi, deflection:LINK@XI,
    /// slope:LINK@XI or acceleration:LINK@XI.
    #[arg(long = "output", value_name = "OUT")]
    pub outputs: Vec<String>,
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

/// Runs the command.
pub fn run(args: StateSpaceArgs) -> Result<(), Failure> {
    let mut scene = Scene::load_for_analysis(&args.scene).map_err(failure)?;
    scene.rigid_chords |= args.rigid_chords;
    let inputs: Vec<Input> = channels(&args.inputs)?;
    let outputs: Vec<Output> = channels(&args.outputs)?;
    let pose = args.pose.as_deref().map(parse_pose).transpose()?;
    let at = operating_point(&scene, pose, args.time)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(format!("{}_statespace", scene.name)));
    let target = OutputDir::check(&out, STATESPACE, args.force, &[&args.scene], &[])
        .map_err(|e| failure(e.into()))?;
    target.check_writable().map_err(|e| failure(e.into()))?;
    let ss = state_space(&scene, at, &inputs, &outputs).map_err(|e| {
        located_failure(
            e,
            Some(&args.scene),
            args.pose.as_deref(),
            args.time.map(|t| t.to_string()),
        )
    })?;
    let written = write_statespace(&scene, &ss, &target).map_err(|e| match e {
        ScenarioError::Io { .. } => Failure::run(e),
        other => failure(other),
    })?;
    let lin = &ss.lin;
    println!(
        "{}: {} model, {}: {} states, {} inputs, {} outputs; {} files written to {}",
        scene.name,
        ss.model,
        flexprr_run::frf::at_words(&ss.at),
        lin.a.nrows(),
        lin.b.ncols(),
        lin.c.nrows(),
        written.len(),
        out.display()
    );
    let lowest: Vec<String> = ss
        .modes
        .iter()
        .take(6)
        .map(|m| format!("{:.2} Hz (zeta {:.4})", m.frequency_hz, m.damping_ratio))
        .collect();
    println!("  lowest modes: {}", lowest.join(", "));
    Ok(())
}
