//! `flexprr run` and `flexprr check`: placeholder.
use super::Failure;
/// Arguments of `flexprr run`.
#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// Scene file (TOML).
    pub scene: std::path::PathBuf,
}
/// Arguments of `flexprr check`.
#[derive(Debug, clap::Args)]
pub struct CheckArgs {
    /// Scene file (TOML).
    pub scene: std::path::PathBuf,
}
/// Runs a scene.
pub fn run(_args: RunArgs) -> Result<(), Failure> {
    Err(Failure::run("not implemented yet"))
}
/// Checks a scene.
pub fn check(_args: CheckArgs) -> Result<(), Failure> {
    Err(Failure::run("not implemented yet"))
}
