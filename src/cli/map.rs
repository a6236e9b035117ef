//! `flexprr study` of a workspace map (`[map]`, docs/studies.md "Workspace maps"): the
//! progress of its poses on stderr and a summary line.

use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use flexprr_linear_tools::machine_modes::RestFrequency;
use flexprr_studies::map::MapProgress;
use flexprr_studies::run_map_study;
use flexprr_studies::study::{Study, StudyError, StudyOptions, format_value};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use super::Failure;

/// Progress of a map: a bar on a terminal; off a terminal one line each time another tenth
/// of the poses is done (and the first after a second when a tenth takes longer); nothing
/// when `quiet`.
struct MapView {
    bar: Option<ProgressBar>,
    lines: bool,
    name: String,
    start: Instant,
    last_tenth: Mutex<usize>,
}

impl MapView {
    fn new(name: &str, total: usize, quiet: bool) -> Self {
        let terminal = std::io::stderr().is_terminal();
        let bar = (!quiet && terminal).then(|| {
            let bar = ProgressBar::with_draw_target(Some(total as u64), ProgressDrawTarget::stderr());
            bar.set_style(
                ProgressStyle::with_template(
                    "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} poses, {msg}, {per_sec}, ~{eta} left",
                )
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            bar.enable_steady_tick(Duration::from_millis(250));
            bar
        });
        Self {
            bar,
            lines: !quiet && !terminal,
            name: name.to_string(),
            start: Instant::now(),
            last_tenth: Mutex::new(0),
        }
    }

    fn update(&self, p: &MapProgress) {
        let marked = format!(
            "{} out of reach, {} singular, {} failed",
            p.unreachable, p.singular, p.failed
        );
        if let Some(bar) = &self.bar {
            bar.set_position(p.done as u64);
            bar.set_message(marked.clone());
        }
        if self.lines && p.total > 0 {
            let tenth = 10 * p.done / p.total;
            let mut last = self
                .last_tenth
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            // Every tenth, and once a second has passed with less than a tenth done.
            let slow = *last == 0 && self.start.elapsed().as_secs_f64() >= 1.0;
            if *last < tenth || (slow && p.done < p.total) {
                *last = tenth.max(usize::from(slow));
                eprintln!(
                    "{}: {}/{} poses ({} %), {marked}, {:.1} s",
                    self.name,
                    p.done,
                    p.total,
                    10 * tenth,
                    self.start.elapsed().as_secs_f64()
                );
            }
        }
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

/// Runs a map study into `out` and prints its summary.
pub fn run(
    study: &Study,
    out: &std::path::Path,
    options: &StudyOptions,
    quiet: bool,
    failure: fn(StudyError) -> Failure,
) -> Result<(), Failure> {
    let total = study.map.as_ref().map_or(0, |m| m.x.len() * m.y.len());
    let view = MapView::new(&study.name, total, quiet);
    let outcome = run_map_study(study, out, options, &|p| view.update(p));
    view.finish();
    let (_, map) = outcome.map_err(failure)?;
    let p = map.progress;
    let found = map.points.iter().filter_map(|(pose, v)| match v {
        RestFrequency::Found { frequency_hz, .. } => Some((*frequency_hz, *pose)),
        _ => None,
    });
    let lowest = found.clone().min_by(|a, b| a.0.total_cmp(&b.0));
    let highest = found.max_by(|a, b| a.0.total_cmp(&b.0));
    let range = match (lowest, highest) {
        (Some((l, lp)), Some((h, hp))) => format!(
            "; lowest {l:.2} Hz at ({:.4}, {:.4}) m, highest {h:.2} Hz at ({:.4}, {:.4}) m",
            lp.x, lp.y, hp.x, hp.y
        ),
        _ => String::new(),
    };
    println!(
        "{}: {} poses at phi = {} deg ({} ok, {} out of reach, {} singular, {} failed) in {:.2} s on {} threads{range}; map.csv, map.json, map.svg in {}",
        study.name,
        p.total,
        format_value(map.phi.to_degrees()),
        p.total - p.unreachable - p.singular - p.failed,
        p.unreachable,
        p.singular,
        p.failed,
        map.wall_time_s,
        map.threads,
        out.display()
    );
    Ok(())
}
