//! `flexprr kinematics`: placeholder.
use super::Failure;
/// Arguments of `flexprr kinematics`.
#[derive(Debug, clap::Args)]
pub struct KinematicsArgs {
    /// Scene file (TOML).
    pub scene: std::path::PathBuf,
}
/// Runs the command.
pub fn run(_args: KinematicsArgs) -> Result<(), Failure> {
    Err(Failure::run("not implemented yet"))
}
