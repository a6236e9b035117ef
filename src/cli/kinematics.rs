//! `flexprr kinematics`: the slider and link-angle time series of a scene's trajectory as CSV.

use std::io::Write;
use std::path::PathBuf;

use flexprr_outdir::{check_output_file, write_file_atomic};
use flexprr_scene::Scene;

use super::Failure;
use super::run::failure;

/// Arguments of `flexprr kinematics`.
#[derive(Debug, clap::Args)]
pub struct KinematicsArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Write the CSV here instead of standard output. An existing file is replaced only if
    /// it is a kinematics table (or with --force); the scene file never is.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Replace an existing --out file that is not a kinematics table.
    #[arg(long, requires = "out")]
    pub force: bool,
}

/// The header of the table: the time, the platform pose, then per leg the slider and link
/// angle with their rates.
fn header() -> String {
    let mut text = String::from("t_s,x_m,y_m,phi_rad");
    for i in 1..=3 {
        text.push_str(&format!(",rho_{i}_m,rho_dot_{i}_m_s,rho_ddot_{i}_m_s2,beta_{i}_rad,beta_dot_{i}_rad_s,beta_ddot_{i}_rad_s2"));
    }
    text
}

/// Whether a file starts with this command's header (an earlier output, safe to replace).
fn is_kinematics_table(head: &str) -> bool {
    head.lines().next() == Some(header().as_str())
}

/// Runs the command.
pub fn run(args: KinematicsArgs) -> Result<(), Failure> {
    // The output file is checked first: refusing it costs nothing.
    let out = match &args.out {
        Some(path) => Some(
            check_output_file(path, args.force, &[&args.scene], is_kinematics_table)
                .map_err(|e| failure(e.into()))?,
        ),
        None => None,
    };
    let scene = Scene::load(&args.scene).map_err(failure)?;
    let mut text = header();
    text.push('\n');
    for &t in &scene.output_times {
        let motion = scene.trajectory.motion(t);
        let state = scene
            .machine
            .geometry
            .inverse_kinematics(&motion)
            .map_err(|e| Failure::run(format!("at t = {t} s: {e}")))?;
        text.push_str(&format!(
            "{t:.10e},{:.10e},{:.10e},{:.10e}",
            motion.pose.x, motion.pose.y, motion.pose.phi
        ));
        for leg in &state.legs {
            text.push_str(&format!(
                ",{:.10e},{:.10e},{:.10e},{:.10e},{:.10e},{:.10e}",
                leg.rho, leg.rho_dot, leg.rho_ddot, leg.beta, leg.beta_dot, leg.beta_ddot
            ));
        }
        text.push('\n');
    }
    match out {
        Some(path) => {
            if let Some(parent) = path.parent() {
                std::fs::create_dir_all(parent)
                    .map_err(|e| Failure::run(format!("{}: {e}", parent.display())))?;
            }
            write_file_atomic(&path, text.as_bytes()).map_err(Failure::run)?
        }
        None => std::io::stdout()
            .write_all(text.as_bytes())
            .map_err(|e| Failure::run(e.to_string()))?,
    }
    Ok(())
}
