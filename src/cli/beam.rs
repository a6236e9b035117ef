//! `flexprr beam`: placeholder until the beam layer lands.
use super::Failure;
/// Arguments of `flexprr beam`.
#[derive(Debug, clap::Args)]
pub struct BeamArgs {
    /// Link file (TOML).
    pub file: std::path::PathBuf,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}
/// Runs the command.
pub fn run(_args: BeamArgs) -> Result<(), Failure> {
    Err(Failure::run("not implemented yet"))
}
