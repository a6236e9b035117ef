//! Helpers shared by the command-line tests: the binary under test, its error output and
//! the CSV tables it writes (read by `flexprr_testkit::csv`).

use std::path::Path;
use std::process::{Command, Output};

/// The `flexprr` binary built for these tests.
pub fn flexprr() -> Command {
    Command::new(env!("CARGO_BIN_EXE_flexprr"))
}

/// What a finished command printed on standard error.
pub fn stderr_of(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

/// A numeric CSV table written by `flexprr`: its header and rows.
pub fn read_csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    flexprr_testkit::csv::read_numeric(path)
}
