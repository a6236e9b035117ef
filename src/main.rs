//! The `flexprr` command-line program: parses arguments, calls the library, prints.

mod cli;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Simulate 3-PRR planar parallel manipulators with flexible links.
#[derive(Debug, Parser)]
#[command(name = "flexprr", version, about, long_about = None)]
struct Args {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run a scene: kinematics, forces, frequencies and vibration as the scene requests.
    Run(cli::run::RunArgs),
    /// Validate a scene file without running it.
    Check(cli::run::CheckArgs),
    /// Write the slider and link-angle time series of a scene's trajectory as CSV.
    Kinematics(cli::kinematics::KinematicsArgs),
    /// Natural frequencies of a single link under an axial load.
    Beam(cli::beam::BeamArgs),
    /// Run a parameter study: many scenes in parallel, one results table.
    Study(cli::study::StudyArgs),
    /// Merge the output directories of a sharded study into one results table.
    Merge(cli::study::MergeArgs),
    /// Wall time against achieved error for each integrator over a ladder of tolerances.
    WorkPrecision(cli::work_precision::WorkPrecisionArgs),
    /// The whole machine's natural frequencies, damping ratios and mode shapes at a pose or
    /// a time of the motion.
    Modes(cli::modes::ModesArgs),
    /// Gain and phase margins and the sensitivity peak of each slider loop, broken at its actuator.
    Margins(cli::margins::MarginsArgs),
    /// Frequency responses of a scene's linear model (CSV, JSON, Bode SVG; mode shapes from a modal test).
    Frf(cli::frf::FrfArgs),
    /// Export a scene's linear model as state space (NumPy .npz and JSON).
    Statespace(cli::statespace::StateSpaceArgs),
    /// The fastest motion along a scene's path within its [plan] limits, written back as a
    /// runnable scene (plan.json, planned.toml, figures).
    Plan(cli::plan::PlanArgs),
}

/// Let a closed reader end the program quietly, as it ends `cat` or `head`.
///
/// Rust starts programs with `SIGPIPE` ignored, so writing to a pipe whose reader has gone
/// (`flexprr kinematics scene.toml | head`) turns into an `EPIPE` error, and `println!`
/// panics on it. Restoring the default action makes the kernel end the process at that
/// write, silently, which is what every Unix filter does.
#[cfg(unix)]
fn end_quietly_on_closed_pipe() {
    // SAFETY: called first thing in `main`, before any other thread exists; `signal` with
    // `SIG_DFL` installs no handler code, it only restores the kernel's default action.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

#[cfg(not(unix))]
fn end_quietly_on_closed_pipe() {}

fn main() -> ExitCode {
    end_quietly_on_closed_pipe();
    let args = Args::parse();
    let result = match args.command {
        Command::Run(a) => cli::run::run(a),
        Command::Check(a) => cli::run::check(a),
        Command::Kinematics(a) => cli::kinematics::run(a),
        Command::Beam(a) => cli::beam::run(a),
        Command::Study(a) => cli::study::study(a),
        Command::Merge(a) => cli::study::merge(a),
        Command::WorkPrecision(a) => cli::work_precision::run(a),
        Command::Modes(a) => cli::modes::run(a),
        Command::Margins(a) => cli::margins::run(a),
        Command::Frf(a) => cli::frf::run(a),
        Command::Statespace(a) => cli::statespace::run(a),
        Command::Plan(a) => cli::plan::plan(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(failure) => {
            eprintln!("error: {}", failure.message);
            ExitCode::from(failure.code)
        }
    }
}
