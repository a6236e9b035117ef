//! `flexprr study` and `flexprr merge`: parameter sweeps in parallel, sharded and resumable
//! (`docs/studies.md`).

use std::path::PathBuf;
use std::time::Duration;

use flexprr_studies::study::{CaseStatus, Shard, Study, StudyError, StudyOptions};
use flexprr_studies::{merge_studies, run_study};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use super::Failure;

/// Arguments of `flexprr study`.
#[derive(Debug, clap::Args)]
pub struct StudyArgs {
    /// Study file (TOML).
    pub study: PathBuf,
    /// Output directory: `results.csv`, `study.json`, `cases/<id>.json`.
    #[arg(long)]
    pub out: PathBuf,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Run only slice k of n (cases with id % n == k - 1), e.g. `--shard 2/8`.
    #[arg(long)]
    pub shard: Option<Shard>,
    /// Complete an interrupted run: skip the cases already recorded in `--out`.
    #[arg(long)]
    pub resume: bool,
    /// Also write every case's full outputs (tables, summary, plots) into `cases/<id>/`.
    #[arg(long)]
    pub case_outputs: bool,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

/// Arguments of `flexprr merge`.
#[derive(Debug, clap::Args)]
pub struct MergeArgs {
    /// Output directories of the shards.
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    /// Directory for the merged table.
    #[arg(long)]
    pub out: PathBuf,
}

fn failure(e: StudyError) -> Failure {
    match e {
        StudyError::Input { .. } | StudyError::Scene(_) => Failure::bad_input(e),
        other => Failure::run(other),
    }
}

/// Runs a study.
pub fn study(args: StudyArgs) -> Result<(), Failure> {
    if args.threads == Some(0) {
        return Err(Failure::bad_input("--threads must be at least 1"));
    }
    let study = Study::load(&args.study).map_err(failure)?;
    let total = study.shard_cases(args.shard).len() as u64;
    let bar = ProgressBar::with_draw_target(
        Some(total),
        if args.quiet {
            ProgressDrawTarget::hidden()
        } else {
            ProgressDrawTarget::stderr()
        },
    );
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} cases, {msg}, {per_sec}, ~{eta} left",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_message("0 failed");
    bar.enable_steady_tick(Duration::from_millis(250));
    let options = StudyOptions {
        threads: args.threads,
        shard: args.shard,
        resume: args.resume,
        case_outputs: args.case_outputs,
    };
    let summary = run_study(&study, &args.out, &options, &|progress, record| {
        if progress.done == progress.resumed + 1 && progress.resumed > 0 {
            bar.set_position(progress.resumed as u64);
            bar.reset_eta();
        }
        bar.set_position(progress.done as u64);
        bar.set_message(format!("{} failed", progress.failed));
        if record.status != CaseStatus::Ok {
            bar.suspend(|| {
                eprintln!(
                    "case {} ({}): {}: {}",
                    record.id,
                    record.parameters.join(", "),
                    record.status.name(),
                    record.error
                );
            });
        }
    });
    bar.finish_and_clear();
    let summary = summary.map_err(failure)?;
    let p = summary.progress;
    println!(
        "{}: {} cases{} ({} run now, {} resumed), {} not ok; table {}",
        study.name,
        p.total,
        args.shard
            .map(|s| format!(" in shard {s} of {}", study.cases.len()))
            .unwrap_or_default(),
        summary.ran,
        p.resumed,
        p.failed,
        summary.results.display()
    );
    Ok(())
}

/// Merges shard directories.
pub fn merge(args: MergeArgs) -> Result<(), Failure> {
    let summary = merge_studies(&args.dirs, &args.out).map_err(failure)?;
    println!(
        "merged {} directories: {} cases, {} not ok; table {}",
        args.dirs.len(),
        summary.cases,
        summary.failed,
        summary.results.display()
    );
    Ok(())
}
