//! `flexprr study` and `flexprr merge`: parameter sweeps in parallel, sharded and resumable
//! (`docs/studies.md`).

use std::collections::{BTreeMap, BTreeSet};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use flexprr_studies::search::{Criterion, Probe, SearchOutcome};
use flexprr_studies::study::{
    CaseRecord, CaseStatus, Shard, Study, StudyError, StudyOptions, StudyProgress, format_value,
    worker_threads,
};
use flexprr_studies::{merge_studies_with, run_search_study, run_study};
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
    /// Worker threads (default: all cores; at most 4 per core).
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
    /// No progress: neither the bar (on a terminal) nor the lines at every tenth of the
    /// cases (off a terminal). Failed cases are still printed, one short line each.
    #[arg(long)]
    pub quiet: bool,
    /// Write into a non-empty directory that flexprr did not write, next to its files (none
    /// of them is overwritten or deleted; a file with the name of an output is refused).
    #[arg(long)]
    pub force: bool,
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
    /// Write into a non-empty directory that flexprr did not write, next to its files (none
    /// of them is overwritten or deleted; a file with the name of an output is refused).
    #[arg(long)]
    pub force: bool,
}

fn failure(e: StudyError) -> Failure {
    if e.is_input() {
        Failure::bad_input(e)
    } else {
        Failure::run(e)
    }
}

/// Failure lines printed before the rest are only counted (all are in `results.csv`).
const MAX_FAILURE_LINES: usize = 20;
/// Longest failure message printed (characters); the full one is in `results.csv`.
const MAX_FAILURE_MESSAGE: usize = 90;
/// Parameters named in a failure line (the others are counted; all are in `results.csv`).
const MAX_FAILURE_PARAMETERS: usize = 4;

/// A short line for a failed case: its parameters by key, the status and kind, and the start
/// of the message, e.g. `case 19 (links.section.thickness = 0.002, machine.platform_mass =
/// 2): failed (diverged): link 2 diverged at t = 0.0084 s: deflection 1.027e-1 m at ...`.
fn failure_line(study: &Study, record: &CaseRecord) -> String {
    let mut parameters: Vec<String> = study
        .axes
        .iter()
        .zip(&record.parameters)
        .take(MAX_FAILURE_PARAMETERS)
        .map(|(axis, value)| format!("{} = {}", axis.key, shorten(value, 40)))
        .collect();
    if study.axes.len() > MAX_FAILURE_PARAMETERS {
        parameters.push(format!(
            "and {} more",
            study.axes.len() - MAX_FAILURE_PARAMETERS
        ));
    }
    let kind = record.failure.as_ref().map(|f| f.kind);
    // The status and kind are printed: drop the words that repeat them.
    let mut message = record.error.as_str();
    message = message.strip_prefix("run failed: ").unwrap_or(message);
    if let Some(kind) = kind {
        message = message
            .strip_prefix(&format!("{}: ", kind.name()))
            .unwrap_or(message);
    }
    format!(
        "case {} ({}): {} ({}): {}",
        record.id,
        parameters.join(", "),
        record.status.name(),
        kind.map_or("unknown", |k| k.name()),
        shorten(message, MAX_FAILURE_MESSAGE)
    )
}

/// `text` cut after at most `max` characters, at a space when there is one, with `...`.
fn shorten(text: &str, max: usize) -> String {
    if text.chars().count() <= max {
        return text.to_string();
    }
    let cut: String = text.chars().take(max).collect();
    let cut = cut.rsplit_once(' ').map_or(cut.as_str(), |(head, _)| head);
    format!("{cut} ...")
}

/// Progress of a study: a bar on a terminal; off a terminal (a log file, a batch job) one
/// line each time another tenth of the cases is done; nothing with `--quiet`.
struct StudyProgressView {
    bar: Option<ProgressBar>,
    lines: bool,
    name: String,
    start: Instant,
    last_tenth: std::sync::Mutex<usize>,
    failure_lines: std::sync::Mutex<usize>,
}

impl StudyProgressView {
    fn new(study: &Study, total: u64, quiet: bool) -> Self {
        let terminal = std::io::stderr().is_terminal();
        let bar = (!quiet && terminal).then(|| {
            let bar = ProgressBar::with_draw_target(Some(total), ProgressDrawTarget::stderr());
            bar.set_style(
                ProgressStyle::with_template(
                    "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} cases, {msg}, {per_sec}, ~{eta} left",
                )
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            bar.set_message("0 failed");
            bar.enable_steady_tick(Duration::from_millis(250));
            bar
        });
        Self {
            bar,
            lines: !quiet && !terminal,
            name: study.name.clone(),
            start: Instant::now(),
            last_tenth: std::sync::Mutex::new(0),
            failure_lines: std::sync::Mutex::new(0),
        }
    }

    fn update(&self, study: &Study, progress: &StudyProgress, record: &CaseRecord) {
        if let Some(bar) = &self.bar {
            if progress.done == progress.resumed + 1 && progress.resumed > 0 {
                bar.set_position(progress.resumed as u64);
                bar.reset_eta();
            }
            bar.set_position(progress.done as u64);
            bar.set_message(format!("{} failed", progress.failed));
        }
        if record.status != CaseStatus::Ok {
            // Count and print under one lock, so that the line saying that more failed cases
            // follow is printed after the last failure line, whatever the workers' timing.
            let mut shown = self
                .failure_lines
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            let line = match shown.cmp(&MAX_FAILURE_LINES) {
                std::cmp::Ordering::Less => Some(failure_line(study, record)),
                std::cmp::Ordering::Equal => Some(
                    "(more failed cases: see the status and error columns of results.csv)"
                        .to_string(),
                ),
                std::cmp::Ordering::Greater => None,
            };
            if let Some(line) = line {
                self.print(&line);
            }
            *shown += 1;
        }
        if self.lines && progress.total > 0 {
            let tenth = 10 * progress.done / progress.total;
            // Check and print under one lock, so that two workers finishing together cannot
            // print their tenths out of order (the last line must be the last tenth).
            let mut last = self
                .last_tenth
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            if *last < tenth {
                *last = tenth;
                eprintln!(
                    "{}: {}/{} cases ({} %), {} failed, {:.1} s",
                    self.name,
                    progress.done,
                    progress.total,
                    10 * tenth,
                    progress.failed,
                    self.start.elapsed().as_secs_f64()
                );
            }
        }
    }

    fn print(&self, line: &str) {
        match &self.bar {
            Some(bar) => bar.suspend(|| eprintln!("{line}")),
            None => eprintln!("{line}"),
        }
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

/// Runs a study.
pub fn study(args: StudyArgs) -> Result<(), Failure> {
    worker_threads(args.threads).map_err(failure)?;
    // A study file (or its base scene) that cannot be read is bad input, as for `flexprr run`.
    let study = Study::load(&args.study).map_err(|e| match e {
        StudyError::Io { .. } => Failure::bad_input(e),
        other => failure(other),
    })?;
    check_same_shard(&study, &args.out, args.shard)?;
    let options = StudyOptions {
        threads: args.threads,
        shard: args.shard,
        resume: args.resume,
        case_outputs: args.case_outputs,
        force: args.force,
    };
    if study.search.is_some() {
        return search(&study, &args, &options);
    }
    if study.map.is_some() {
        return super::map::run(&study, &args.out, &options, args.quiet, failure);
    }
    let total = study.shard_cases(args.shard).len() as u64;
    let view = StudyProgressView::new(&study, total, args.quiet);
    let summary = run_study(&study, &args.out, &options, &|progress, record| {
        view.update(&study, progress, record);
    });
    view.finish();
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

/// One probe of a speed search as a progress line: the search's case, the value, the outcome
/// and the time since the start.
fn probe_line(study: &Study, search: &SearchOutcome, probe: &Probe, start: Instant) -> String {
    let key = study.search.as_ref().map_or("", |s| s.key.as_str());
    let what = match (&probe.error, probe.reached, probe.time_s, probe.link) {
        (Some(e), _, _, _) => format!("failed: {}", shorten(e, 160)),
        (None, None, _, _) => "failed".to_string(),
        (None, Some(true), Some(t), Some(link)) => format!(
            "{} at t = {:.4} s (link {link})",
            match search.criterion {
                Criterion::Collapse => "collapses",
                Criterion::Buckling => "buckles",
            },
            t
        ),
        (None, Some(true), _, _) => "reaches the limit".to_string(),
        (None, Some(false), _, _) => {
            let end = format_value(probe.end_s);
            format!("no {} within {end} s", search.criterion.name())
        }
    };
    format!(
        "{} [{}]: {key} = {}: {what} ({:.1} s)",
        study.name,
        search.case_label(),
        format_value(probe.value),
        start.elapsed().as_secs_f64()
    )
}

/// The searched key of a search study (empty for another study).
fn search_key(study: &Study) -> String {
    study
        .search
        .as_ref()
        .map(|s| s.key.clone())
        .unwrap_or_default()
}

/// Runs a speed-search study: a line per probe on stderr (unless `--quiet`; each probe is a
/// whole run, up to minutes for the nonlinear model), then one line per search with its
/// bracket, and `search.md` with the speeds side by side.
fn search(study: &Study, args: &StudyArgs, options: &StudyOptions) -> Result<(), Failure> {
    let start = Instant::now();
    let summary = run_search_study(study, &args.out, options, &|search, probe| {
        if !args.quiet {
            eprintln!("{}", probe_line(study, search, probe, start));
        }
    })
    .map_err(failure)?;
    let show = |v: Option<f64>| v.map_or("-".to_string(), format_value);
    for s in &summary.searches {
        let cause = s
            .probes
            .iter()
            .filter(|_| s.status == "failed")
            .find_map(|p| p.error.as_deref())
            .map(|e| format!(": {}", shorten(e, 200)))
            .unwrap_or_default();
        println!(
            "{} [{}]: {} search {} (not reached at {}, reached at {}), {} probes in {} rounds after the ends{cause}",
            study.name,
            s.case_label(),
            s.criterion.name(),
            s.status,
            show(s.below),
            show(s.at_or_above),
            s.probes.len(),
            s.rounds
        );
        if s.status == "non-monotone" {
            eprintln!(
                "warning: {} [{}]: {}",
                study.name,
                s.case_label(),
                flexprr_studies::search::non_monotone_note(&search_key(study), s)
            );
        }
    }
    println!(
        "table {}; side by side in {}",
        summary.results.display(),
        args.out.join("search.md").display()
    );
    Ok(())
}

/// Merges shard directories.
pub fn merge(args: MergeArgs) -> Result<(), Failure> {
    if let Some(gaps) = shard_gaps(&args.dirs) {
        return Err(Failure::run(format!("{}: {gaps}", args.out.display())));
    }
    let summary = merge_studies_with(&args.dirs, &args.out, args.force).map_err(failure)?;
    println!(
        "merged {} directories: {} cases, {} not ok; table {}",
        args.dirs.len(),
        summary.cases,
        summary.failed,
        summary.results.display()
    );
    Ok(())
}

/// The fields of an output directory's `study.json` that the command line checks before the
/// library does the real work.
#[derive(serde::Deserialize)]
struct ManifestView {
    fingerprint: String,
    cases: usize,
    shard: Option<String>,
}

/// The manifest of `dir`, read only when it is a regular file of bounded size (a pipe or a
/// device named `study.json` is never opened).
fn manifest_view(dir: &Path) -> Option<ManifestView> {
    let text = flexprr_studies::study::read_input_file(&dir.join("study.json")).ok()?;
    serde_json::from_str(&text).ok()
}

/// Refuses to resume a directory of this study that was run as another shard (for example a
/// Slurm array task resubmitted with a different array size): the shard's cases would not be
/// the ones already recorded there.
fn check_same_shard(study: &Study, out: &Path, shard: Option<Shard>) -> Result<(), Failure> {
    let Some(m) = manifest_view(out) else {
        return Ok(());
    };
    // Another study's directory is refused by the library, with its own message.
    if m.fingerprint != study.fingerprint {
        return Ok(());
    }
    let now = shard.map(|s| s.to_string());
    if m.shard == now {
        return Ok(());
    }
    let describe = |s: &Option<String>| match s {
        Some(s) => format!("shard {s}"),
        None => "the whole study (no --shard)".to_string(),
    };
    Err(Failure::run(format!(
        "{}: holds {} of this study, and this run is {}; pass the same --shard or use a new directory",
        out.display(),
        describe(&m.shard),
        describe(&now)
    )))
}

/// Ids of the case records in `dir/cases` (file names `<id>.json`; temporary files are not
/// records).
fn recorded_ids(dir: &Path) -> BTreeSet<usize> {
    std::fs::read_dir(dir.join("cases"))
        .map(|entries| {
            entries
                .filter_map(|e| e.ok())
                .filter_map(|e| {
                    e.file_name()
                        .to_str()?
                        .strip_suffix(".json")?
                        .parse::<usize>()
                        .ok()
                })
                .collect()
        })
        .unwrap_or_default()
}

/// When every directory to merge is a shard `k/n` of the same study and some shard is absent
/// or incomplete, says which, with how many cases each has: what a user of a job array needs
/// to know to resubmit the right tasks. `None` when the shards are complete or the directories
/// are not all shards of one split; `merge_studies` then checks everything itself.
fn shard_gaps(dirs: &[PathBuf]) -> Option<String> {
    let mut split: Option<(usize, usize)> = None; // (n, cases)
    let mut by_index: BTreeMap<usize, Vec<&PathBuf>> = BTreeMap::new();
    for dir in dirs {
        let m = manifest_view(dir)?;
        let shard: Shard = m.shard?.parse().ok()?;
        if split.is_some_and(|s| s != (shard.count, m.cases)) {
            return None;
        }
        split = Some((shard.count, m.cases));
        by_index.entry(shard.index).or_default().push(dir);
    }
    let (n, cases) = split?;
    let mut missing = 0;
    let mut problems = Vec::new();
    for index in 1..=n {
        let shard = Shard { index, count: n };
        let expected = (0..cases).filter(|&id| shard.contains(id)).count();
        match by_index.get(&index) {
            None => {
                missing += expected;
                problems.push(format!("shard {shard} has no directory ({expected} cases)"));
            }
            Some(shard_dirs) => {
                let have = shard_dirs
                    .iter()
                    .flat_map(|d| recorded_ids(d))
                    .filter(|&id| id < cases && shard.contains(id))
                    .collect::<BTreeSet<_>>()
                    .len();
                if have < expected {
                    missing += expected - have;
                    let names: Vec<String> =
                        shard_dirs.iter().map(|d| d.display().to_string()).collect();
                    problems.push(format!(
                        "shard {shard} ({}) has {have} of its {expected} cases",
                        names.join(", ")
                    ));
                }
            }
        }
    }
    if problems.is_empty() {
        return None;
    }
    Some(format!(
        "{missing} of {cases} cases missing: {}; run the missing shards or --resume the incomplete ones (the same --shard k/{n}), then merge again",
        problems.join("; ")
    ))
}
