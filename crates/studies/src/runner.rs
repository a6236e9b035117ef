//! Running a study into an output directory (in parallel, sharded, resumable) and merging
//! shard directories (`docs/studies.md`, "Output directory").

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use flexprr_outdir::{Legacy, OutputDir, Products, write_file_atomic};
use flexprr_run::write_outputs;

use crate::error::{StudyError, io_err};
use crate::plot::write_plots;
use crate::quantity::Column;
use crate::record::{CaseRecord, CaseStatus, case_file, read_case_record_files, results_csv};
use crate::study::{Case, Study};

/// Slice `index` (1-based) of `count`: the cases with `id % count == index - 1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// 1-based index.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
}

impl Shard {
    /// Whether case `id` belongs to this shard.
    pub fn contains(&self, id: usize) -> bool {
        id % self.count == self.index - 1
    }
}

impl FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("shard \"{s}\": expected k/n with 1 <= k <= n, e.g. 2/8");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = k.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if index == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// The files of a study's output directory (`docs/studies.md`, "Output directory"), for the
/// output-directory policy of [`flexprr_outdir`]; the plots' own names are added
/// per study.
pub const STUDY_PRODUCTS: Products = Products {
    kind: "study",
    names: Cow::Borrowed(&[
        "study.json",
        "results.csv",
        "cases",
        "search.json",
        "search.md",
        "map.csv",
        "map.json",
        "map.svg",
    ]),
    patterns: Cow::Borrowed(&[]),
    legacy: Some(Legacy::JsonKey {
        file: "study.json",
        key: "fingerprint",
    }),
};

/// Most worker threads per available CPU. A case runs on one thread and uses the CPU all
/// the time, so threads beyond the CPUs only share them; a few times more is harmless (a
/// machine whose CPU count is reported low), thousands exhaust memory and processes.
pub const MAX_THREADS_PER_CPU: usize = 4;

/// The number of worker threads for `requested` (`None`: one per available CPU, whatever
/// `RAYON_NUM_THREADS` says).
///
/// # Errors
/// [`StudyError::Option`] for 0, or more than [`MAX_THREADS_PER_CPU`] times the CPUs.
pub fn worker_threads(requested: Option<usize>) -> Result<usize, StudyError> {
    let cpus = std::thread::available_parallelism().map_or(1, usize::from);
    let max = MAX_THREADS_PER_CPU * cpus;
    match requested {
        None => Ok(cpus),
        Some(0) => Err(StudyError::Option {
            option: "--threads".into(),
            message: "must be at least 1".into(),
        }),
        Some(n) if n > max => Err(StudyError::Option {
            option: "--threads".into(),
            message: format!(
                "{n} is more than {MAX_THREADS_PER_CPU} per available CPU ({cpus} CPUs, so at \
                 most {max}): each case keeps one thread busy, so more threads only share the \
                 CPUs and cost memory"
            ),
        }),
        Some(n) => Ok(n),
    }
}

/// How to run a study.
#[derive(Debug, Clone, Default)]
pub struct StudyOptions {
    /// Worker threads (default: all cores; at most [`MAX_THREADS_PER_CPU`] per CPU).
    pub threads: Option<usize>,
    /// Run only this slice of the cases.
    pub shard: Option<Shard>,
    /// Skip cases already recorded in the output directory.
    pub resume: bool,
    /// Write each case's full outputs into `cases/<id>/`.
    pub case_outputs: bool,
    /// Write into a non-empty directory flexprr did not write, next to its files (none of
    /// which is overwritten or deleted).
    pub force: bool,
}

/// Progress after a case finished (for a progress bar).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct StudyProgress {
    /// Cases of this run (shard), including those recorded before a resume.
    pub total: usize,
    /// Cases recorded so far (including those recorded before a resume).
    pub done: usize,
    /// Of those, not ok.
    pub failed: usize,
    /// Cases found already recorded when the run started.
    pub resumed: usize,
}

/// What a study run did.
#[derive(Debug, Clone, PartialEq)]
pub struct StudySummary {
    /// Final progress.
    pub progress: StudyProgress,
    /// Cases run now (not resumed).
    pub ran: usize,
    /// `results.csv`.
    pub results: PathBuf,
    /// The searches' outcomes (one per case of the axes, or one), when the study is a speed
    /// search; empty for a sweep.
    pub searches: Vec<crate::search::SearchOutcome>,
}

/// Contents of `study.json`: identifies the study an output directory belongs to.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
struct StudyManifest {
    name: String,
    fingerprint: String,
    cases: usize,
    columns: Vec<String>,
    shard: Option<String>,
}

/// Writes a case record through a hidden temporary file `.<id>.json.<pid>.tmp` and a rename.
fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), StudyError> {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("file");
    let tmp = path.with_file_name(format!(".{name}.{}.tmp", std::process::id()));
    std::fs::write(&tmp, bytes).map_err(io_err(&tmp))?;
    std::fs::rename(&tmp, path).map_err(io_err(path))
}

fn read_manifest(dir: &Path) -> Result<Option<StudyManifest>, StudyError> {
    let path = dir.join("study.json");
    if std::fs::symlink_metadata(&path).is_err() {
        return Ok(None);
    }
    let text = crate::error::read_input_file(&path).map_err(|e| StudyError::Directory {
        dir: path.display().to_string(),
        message: match e {
            StudyError::InputFile { message, .. } => format!("not a study manifest: it {message}"),
            other => format!("not a study manifest: {other}"),
        },
    })?;
    serde_json::from_str(&text)
        .map(Some)
        .map_err(|e| StudyError::Directory {
            dir: path.display().to_string(),
            message: format!("not a study manifest: {e}"),
        })
}

fn write_manifest(dir: &Path, manifest: &StudyManifest) -> Result<(), StudyError> {
    let text = serde_json::to_string_pretty(manifest).unwrap_or_default();
    Ok(write_file_atomic(&dir.join("study.json"), text.as_bytes())?)
}

/// The study's output directory, checked by the output-directory policy before any work:
/// never an input, never a foreign directory without `force`, never over a file flexprr did
/// not write.
fn output_dir(
    study: &Study,
    out: &Path,
    force: bool,
    extra: &[&Path],
) -> Result<OutputDir, StudyError> {
    let mut inputs: Vec<&Path> = study.inputs.iter().map(PathBuf::as_path).collect();
    inputs.extend_from_slice(extra);
    let plots: Vec<&str> = study.plots.iter().map(|p| p.file.as_str()).collect();
    Ok(OutputDir::check(
        out,
        STUDY_PRODUCTS,
        force,
        &inputs,
        &plots,
    )?)
}

/// The records already in `out`, each checked against its case with [`Study::check_record`];
/// refuses a directory of another study, or one with records but no `resume`.
fn existing_records(
    study: &Study,
    out: &Path,
    resume: bool,
) -> Result<BTreeMap<usize, CaseRecord>, StudyError> {
    let dir_err = |message: String| StudyError::Directory {
        dir: out.display().to_string(),
        message,
    };
    let files = read_case_record_files(out)?;
    if let Some(manifest) = read_manifest(out)? {
        if manifest.fingerprint != study.fingerprint {
            return Err(dir_err(format!(
                "holds results of another study or another version of it (\"{}\", fingerprint {}, this one {}); use a new directory",
                manifest.name, manifest.fingerprint, study.fingerprint
            )));
        }
    }
    if !files.is_empty() && !resume {
        return Err(dir_err(format!(
            "already holds {} case results; pass --resume to complete it or use a new directory",
            files.len()
        )));
    }
    let mut records = BTreeMap::new();
    for (id, (path, record)) in files {
        if record.fingerprint != study.fingerprint {
            return Err(dir_err(format!(
                "case {id} was recorded by another study (fingerprint {})",
                record.fingerprint
            )));
        }
        study
            .check_record(&record)
            .map_err(|message| StudyError::Record {
                path: path.display().to_string(),
                message,
            })?;
        records.insert(id, record);
    }
    Ok(records)
}

/// Runs a study (or one shard of it) into `out`: `study.json`, `cases/<id>.json` written
/// atomically as each case finishes, `results.csv` at the end, plots if the study asks,
/// `cases/<id>/` full outputs with [`StudyOptions::case_outputs`]. `on_case` is called after
/// every finished case (from worker threads).
///
/// With `resume`, every record already in `out` is checked against its case first (same
/// parameters, the right number of finite values or a failure matching its status); a record
/// that does not fit is refused with [`StudyError::Record`] naming its file, never copied
/// into the table.
///
/// # Errors
/// [`StudyError::Directory`] when `out` holds another study's results, or results without
/// `resume`; [`StudyError::Record`] for a bad record; [`StudyError::Io`] when files cannot
/// be written. Failing cases are not errors.
pub fn run_study(
    study: &Study,
    out: &Path,
    options: &StudyOptions,
    on_case: &(dyn Fn(&StudyProgress, &CaseRecord) + Sync),
) -> Result<StudySummary, StudyError> {
    if study.search.is_some() {
        return run_search_study(study, out, options, &|_, _| {});
    }
    if study.map.is_some() {
        return run_map_study(study, out, options, &|_| {}).map(|(summary, _)| summary);
    }
    let threads = worker_threads(options.threads)?;
    let target = output_dir(study, out, options.force, &[])?;
    // Everything already there is checked before anything is written.
    let existing = existing_records(study, out, options.resume)?;
    let out = &target.open()?;
    let cases_dir = out.join("cases");
    std::fs::create_dir_all(&cases_dir).map_err(io_err(&cases_dir))?;
    write_manifest(
        out,
        &StudyManifest {
            name: study.name.clone(),
            fingerprint: study.fingerprint.clone(),
            cases: study.cases.len(),
            columns: study.columns(),
            shard: options.shard.map(|s| s.to_string()),
        },
    )?;

    let mine = study.shard_cases(options.shard);
    let pending: Vec<&Case> = mine
        .iter()
        .copied()
        .filter(|c| !existing.contains_key(&c.id))
        .collect();
    let resumed = mine.len() - pending.len();
    let failed_before = mine
        .iter()
        .filter(|c| {
            existing
                .get(&c.id)
                .is_some_and(|r| r.status != CaseStatus::Ok)
        })
        .count();
    let progress = StudyProgress {
        total: mine.len(),
        done: resumed,
        failed: failed_before,
        resumed,
    };
    let progress = run_pending(study, out, options, threads, &pending, progress, on_case)?;

    let records: BTreeMap<usize, CaseRecord> = read_case_record_files(out)?
        .into_iter()
        .map(|(id, (_, r))| (id, r))
        .collect();
    let mine_records: Vec<&CaseRecord> = mine.iter().filter_map(|c| records.get(&c.id)).collect();
    let results = out.join("results.csv");
    write_file_atomic(
        &results,
        &results_csv(&study.columns(), mine_records.iter().copied())?,
    )?;
    if options.shard.is_none() {
        write_plots(study, out, &records)?;
    }
    Ok(StudySummary {
        progress,
        ran: pending.len(),
        results,
        searches: Vec::new(),
    })
}

/// Runs a speed-search study ([`crate::search`]): one search per case of its axes (or one),
/// the searches and the probes of each round in parallel on [`StudyOptions::threads`]
/// workers (k-section with the study's `probes_per_round`, see
/// [`crate::search::section_search`]; the same probes for any thread count); no shards and
/// no resume. `on_probe` sees every probe as it ends, with its search
/// (for progress). A sweep study (no `[search]`) is refused.
///
/// # Errors
/// As [`run_study`]; [`StudyError::Directory`] for a shard, a resume or a sweep study.
pub fn run_search_study(
    study: &Study,
    out: &Path,
    options: &StudyOptions,
    on_probe: &(dyn Fn(&crate::search::SearchOutcome, &crate::search::Probe) + Sync),
) -> Result<StudySummary, StudyError> {
    let Some(search) = &study.search else {
        return Err(StudyError::Directory {
            dir: out.display().to_string(),
            message: "the study has no [search] table: run it with run_study".into(),
        });
    };
    if options.shard.is_some() || options.resume {
        return Err(StudyError::Option {
            option: if options.resume {
                "--resume"
            } else {
                "--shard"
            }
            .into(),
            message: "a speed search runs its probes in rounds, each depending on the \
                      last: it cannot be sharded or resumed"
                .into(),
        });
    }
    let threads = worker_threads(options.threads)?;
    let target = output_dir(study, out, options.force, &[])?;
    target.check_writable()?;
    let searches = crate::search::run_search(study, search, threads, on_probe)?;
    let staging = target.stage()?;
    crate::search::write_search_files(study, search, &searches, staging.path())?;
    staging.publish()?;
    let probes = || searches.iter().flat_map(|s| &s.probes);
    let n = probes().count();
    let failed = probes().filter(|p| p.error.is_some()).count();
    Ok(StudySummary {
        progress: StudyProgress {
            total: n,
            done: n,
            failed,
            resumed: 0,
        },
        ran: n,
        results: out.join("results.csv"),
        searches,
    })
}

/// Runs a workspace-map study ([`crate::map`]): every pose of the grid in parallel on
/// [`StudyOptions::threads`] workers, then `map.csv`, `map.json` and `map.svg` written
/// together (staged and published); no shards and no resume (a map takes seconds to
/// minutes). `on_pose` sees the progress after each pose. Returns the summary and the map.
///
/// # Errors
/// As [`run_study`]; [`StudyError::Option`] for a shard or a resume,
/// [`StudyError::Directory`] for a study without `[map]`.
pub fn run_map_study(
    study: &Study,
    out: &Path,
    options: &StudyOptions,
    on_pose: &(dyn Fn(&crate::map::MapProgress) + Sync),
) -> Result<(StudySummary, crate::map::MapOutcome), StudyError> {
    let Some(map) = &study.map else {
        return Err(StudyError::Directory {
            dir: out.display().to_string(),
            message: "the study has no [map] table: run it with run_study".into(),
        });
    };
    if options.shard.is_some() || options.resume {
        return Err(StudyError::Option {
            option: if options.resume {
                "--resume"
            } else {
                "--shard"
            }
            .into(),
            message: "a workspace map is computed and written whole (seconds for the coupled \
                      model): it cannot be sharded or resumed"
                .into(),
        });
    }
    let threads = worker_threads(options.threads)?;
    let target = output_dir(study, out, options.force, &[])?;
    target.check_writable()?;
    let scene = crate::map::map_scene(study)?;
    let outcome = crate::map::run_map(study, map, &scene, threads, on_pose)?;
    let staging = target.stage()?;
    crate::map::write_map_files(study, map, &scene, &outcome, staging.path())?;
    staging.publish()?;
    let p = outcome.progress;
    let summary = StudySummary {
        progress: StudyProgress {
            total: p.total,
            done: p.done,
            failed: p.failed,
            resumed: 0,
        },
        ran: p.done,
        results: out.join("map.csv"),
        searches: Vec::new(),
    };
    Ok((summary, outcome))
}

/// Runs `pending` cases on the worker pool, writing each record (and its full outputs when
/// asked) as it finishes; stops at the first file-system error. Returns the final progress.
fn run_pending(
    study: &Study,
    out: &Path,
    options: &StudyOptions,
    threads: usize,
    pending: &[&Case],
    start: StudyProgress,
    on_case: &(dyn Fn(&StudyProgress, &CaseRecord) + Sync),
) -> Result<StudyProgress, StudyError> {
    let done = AtomicUsize::new(start.done);
    let failed = AtomicUsize::new(start.failed);
    let first_error: Mutex<Option<StudyError>> = Mutex::new(None);
    let dir_err = |message: String| StudyError::Directory {
        dir: out.display().to_string(),
        message,
    };
    let work = || {
        pending.par_iter().for_each(|case| {
            if first_error.lock().map(|e| e.is_some()).unwrap_or(true) {
                return;
            }
            let (record, ran) = study.run_case(case);
            let mut outcome = Ok(());
            if options.case_outputs {
                if let Some((scene, result)) = &ran {
                    let dir = out.join("cases").join(format!("{:06}", case.id));
                    outcome = write_outputs(scene, result, &dir)
                        .map(|_| ())
                        .map_err(|e| dir_err(e.to_string()));
                }
            }
            if outcome.is_ok() {
                let bytes = serde_json::to_vec_pretty(&record).unwrap_or_default();
                outcome = write_atomic(&case_file(out, case.id), &bytes);
            }
            if let Err(e) = outcome {
                if let Ok(mut slot) = first_error.lock() {
                    slot.get_or_insert(e);
                }
                return;
            }
            if record.status != CaseStatus::Ok {
                failed.fetch_add(1, Ordering::SeqCst);
            }
            let progress = StudyProgress {
                done: done.fetch_add(1, Ordering::SeqCst) + 1,
                failed: failed.load(Ordering::SeqCst),
                ..start
            };
            on_case(&progress, &record);
        });
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| dir_err(format!("cannot start worker threads: {e}")))?;
    pool.install(work);
    if let Some(e) = first_error.into_inner().ok().flatten() {
        return Err(e);
    }
    Ok(StudyProgress {
        done: done.load(Ordering::SeqCst),
        failed: failed.load(Ordering::SeqCst),
        ..start
    })
}

/// What a merge did.
#[derive(Debug, Clone, PartialEq)]
pub struct MergeSummary {
    /// Cases in the merged table.
    pub cases: usize,
    /// Of those, not ok.
    pub failed: usize,
    /// `results.csv`.
    pub results: PathBuf,
}

/// Reads one shard directory into `records`: its manifest must match `first` (when there is
/// one), and each record must be consistent, inside the study and equal to the same case
/// from other directories.
fn merge_one(
    dir: &Path,
    first: Option<&StudyManifest>,
    records: &mut BTreeMap<usize, CaseRecord>,
) -> Result<StudyManifest, StudyError> {
    let dir_err = |message: String| StudyError::Directory {
        dir: dir.display().to_string(),
        message,
    };
    let not_input = |message: String| StudyError::MergeInput {
        dir: dir.display().to_string(),
        message,
    };
    if !dir.is_dir() {
        return Err(not_input(
            "is not a directory: give the output directories of the shards".into(),
        ));
    }
    let m = read_manifest(dir)
        .map_err(|e| match e {
            StudyError::Directory { dir, message } => StudyError::MergeInput { dir, message },
            other => other,
        })?
        .ok_or_else(|| not_input("no study.json: not a study output directory".into()))?;
    if let Some(first) = first {
        if first.fingerprint != m.fingerprint || first.columns != m.columns {
            return Err(not_input(format!(
                "belongs to study \"{}\" (fingerprint {}), the first directory to \"{}\" ({})",
                m.name, m.fingerprint, first.name, first.fingerprint
            )));
        }
    }
    for (id, (path, r)) in read_case_record_files(dir)? {
        if r.fingerprint != m.fingerprint {
            return Err(dir_err(format!("case {id} was recorded by another study")));
        }
        if id >= m.cases {
            return Err(dir_err(format!(
                "case {id} is outside the study's {} cases",
                m.cases
            )));
        }
        // The header is all a merge knows of the columns: case, axes, quantities, status,
        // error; the parameters fill the axis cells.
        let quantity_cells = m.columns.len().saturating_sub(3 + r.parameters.len());
        let start = 1 + r.parameters.len();
        let columns: Vec<Column> = m
            .columns
            .iter()
            .skip(start)
            .take(quantity_cells)
            .map(|name| Column::untyped(name))
            .collect();
        r.check(&columns, None)
            .map_err(|message| StudyError::Record {
                path: path.display().to_string(),
                message,
            })?;
        match records.get(&id) {
            Some(other) if *other != r => {
                return Err(dir_err(format!(
                    "case {id} differs from the same case in another directory"
                )));
            }
            _ => {
                records.insert(id, r);
            }
        }
    }
    Ok(m)
}

/// Combines shard directories of one study into `out` (see [`merge_studies_with`]), which
/// must not be a foreign non-empty directory.
///
/// # Errors
/// As [`merge_studies_with`].
pub fn merge_studies(dirs: &[PathBuf], out: &Path) -> Result<MergeSummary, StudyError> {
    merge_studies_with(dirs, out, false)
}

/// Combines shard directories of one study into `out`: checks that they belong to the same
/// study, that each record is consistent, that duplicated cases agree and that every case
/// is present, then writes the case records, `study.json` and the same `results.csv` a
/// single run gives, staged and published by the output-directory policy (`out` is checked
/// first: never one of the shards, never a foreign directory without `force`, never another
/// study's results).
///
/// # Errors
/// [`StudyError::Directory`] for mixed studies, conflicting or missing cases, or an `out`
/// holding another study's results; [`StudyError::Record`] for an inconsistent record;
/// [`StudyError::Output`] for an `out` the policy refuses; [`StudyError::Io`] for unreadable
/// or unwritable files.
pub fn merge_studies_with(
    dirs: &[PathBuf],
    out: &Path,
    force: bool,
) -> Result<MergeSummary, StudyError> {
    let inputs: Vec<&Path> = dirs.iter().map(PathBuf::as_path).collect();
    let target = OutputDir::check(out, STUDY_PRODUCTS, force, &inputs, &[])?;
    let mut manifest: Option<StudyManifest> = None;
    let mut records: BTreeMap<usize, CaseRecord> = BTreeMap::new();
    for dir in dirs {
        let m = merge_one(dir, manifest.as_ref(), &mut records)?;
        manifest.get_or_insert(m);
    }
    let out_err = |message: String| StudyError::Directory {
        dir: out.display().to_string(),
        message,
    };
    let mut manifest = manifest.ok_or_else(|| out_err("no directories to merge".into()))?;
    let missing: Vec<usize> = (0..manifest.cases)
        .filter(|id| !records.contains_key(id))
        .collect();
    if !missing.is_empty() {
        let shown: Vec<String> = missing.iter().take(10).map(usize::to_string).collect();
        return Err(out_err(format!(
            "{} of {} cases missing (e.g. {}); run the missing shards or --resume them first",
            missing.len(),
            manifest.cases,
            shown.join(", ")
        )));
    }
    if let Some(existing) = read_manifest(out)? {
        if existing.fingerprint != manifest.fingerprint {
            return Err(out_err(format!(
                "holds results of another study (\"{}\"); use a new directory",
                existing.name
            )));
        }
    }
    let staging = target.stage()?;
    let dir = staging.path();
    let cases_dir = dir.join("cases");
    std::fs::create_dir_all(&cases_dir).map_err(io_err(&cases_dir))?;
    manifest.shard = None;
    write_manifest(dir, &manifest)?;
    for r in records.values() {
        let bytes = serde_json::to_vec_pretty(r).unwrap_or_default();
        write_atomic(&case_file(dir, r.id), &bytes)?;
    }
    write_file_atomic(
        &dir.join("results.csv"),
        &results_csv(&manifest.columns, records.values())?,
    )?;
    staging.publish()?;
    Ok(MergeSummary {
        cases: records.len(),
        failed: records
            .values()
            .filter(|r| r.status != CaseStatus::Ok)
            .count(),
        results: out.join("results.csv"),
    })
}
