//! `flexprr run` and `flexprr check`.

use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use flexprr_outdir::OutputDir;
use flexprr_run::{
    RUN_PRODUCTS, RunResult, run as run_scene, table_one_markdown, write_outputs_into,
};
use flexprr_scene::{InputKind, ScenarioError, Scene};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use super::Failure;

/// Arguments of `flexprr run`.
#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Output directory (default `out/<scene name>`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// No progress: neither the bar (on a terminal) nor the lines at every tenth of the
    /// time span (off a terminal). Both appear only once a run takes more than a second.
    #[arg(long)]
    pub quiet: bool,
    /// Write into a non-empty directory that flexprr did not write, next to its files (none
    /// of them is overwritten or deleted; a file with the name of an output is refused).
    #[arg(long)]
    pub force: bool,
}

/// Arguments of `flexprr check`.
#[derive(Debug, clap::Args)]
pub struct CheckArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
}

/// Maps a scenario error to the exit code convention (2 bad input, 1 run failure).
pub fn failure(e: ScenarioError) -> Failure {
    match e {
        ScenarioError::Input { .. } | ScenarioError::Io { .. } => Failure::bad_input(e),
        other => Failure::run(other),
    }
}

/// Progress of a run on stderr, shown only once the run has taken more than a second: a bar
/// on a terminal (like `flexprr study`); off a terminal (a log file, a batch job) one line
/// each time another tenth of the time span is integrated, so at most ten lines; nothing
/// with `--quiet`.
pub struct RunProgress {
    name: String,
    start: Instant,
    quiet: bool,
    terminal: bool,
    bar: Option<ProgressBar>,
    last_tenth: usize,
}

impl RunProgress {
    /// Progress of the scene `name` (silent when `quiet`).
    pub fn new(name: &str, quiet: bool) -> Self {
        Self {
            name: name.to_string(),
            start: Instant::now(),
            quiet,
            terminal: std::io::stderr().is_terminal(),
            bar: None,
            last_tenth: 0,
        }
    }

    /// Reports the fraction of the time span integrated.
    pub fn update(&mut self, fraction: f64) {
        let elapsed = self.start.elapsed();
        if self.quiet || elapsed < Duration::from_secs(1) || !fraction.is_finite() {
            return;
        }
        let fraction = fraction.clamp(0.0, 1.0);
        if self.terminal {
            let bar = self.bar.get_or_insert_with(|| {
                let bar = ProgressBar::with_draw_target(Some(1000), ProgressDrawTarget::stderr())
                    .with_elapsed(elapsed);
                bar.set_style(
                    ProgressStyle::with_template(
                        "{spinner} [{elapsed_precise}] {bar:30} {percent:>3} % integrated, ~{eta} left",
                    )
                    .unwrap_or_else(|_| ProgressStyle::default_bar()),
                );
                bar.enable_steady_tick(Duration::from_millis(250));
                bar
            });
            bar.set_position((1000.0 * fraction) as u64);
            return;
        }
        let tenth = (10.0 * fraction).floor() as usize;
        if tenth > self.last_tenth {
            self.last_tenth = tenth;
            let seconds = elapsed.as_secs_f64();
            let left = if fraction > 0.0 {
                seconds * (1.0 - fraction) / fraction
            } else {
                0.0
            };
            eprintln!(
                "{}: {} % integrated, {seconds:.1} s, ~{left:.1} s left",
                self.name,
                10 * tenth
            );
        }
    }

    /// Removes the bar.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

/// Runs a scene and writes its outputs; a failed run writes what it computed up to the
/// failure, with `"status": "failed"` in `summary.json`, and exits 1.
pub fn run(args: RunArgs) -> Result<(), Failure> {
    let scene = Scene::load(&args.scene).map_err(failure)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(&scene.name));
    // The directory is checked before the run, so that a refusal costs nothing.
    let target = OutputDir::check(&out, RUN_PRODUCTS.clone(), args.force, &[&args.scene], &[])
        .map_err(|e| failure(e.into()))?;
    target.check_writable().map_err(|e| failure(e.into()))?;
    if flexprr_run::SceneVariant::wanted(&flexprr_run::variant::Uncontrolled, &scene) && !args.quiet
    {
        eprintln!(
            "{}: the scene is also run without its vibration control law, for the reduction \
             of the deflection (a second integration, the second half of the progress)",
            scene.name
        );
    }
    let mut progress = RunProgress::new(&scene.name, args.quiet);
    let outcome = run_scene(&scene, &mut |f| progress.update(f));
    progress.finish();
    let (result, error) = match &outcome {
        Ok(result) => (result, None),
        Err(f) => (f.partial.as_ref(), Some(&f.error)),
    };
    // The run has happened: a file that cannot be written now is a failure of the run
    // (exit 1), not bad input.
    let written = write_outputs_into(&scene, result, error, &target).map_err(|e| match e {
        ScenarioError::Io { .. } => Failure::run(e),
        other => failure(other),
    })?;
    for w in &result.warnings {
        eprintln!("warning: {w}");
    }
    if let Some(e) = error {
        let rows = result.tables.first().map_or(0, |t| t.rows());
        return Err(Failure::run(format!(
            "run failed: {e} (outputs up to the failure, {rows} samples, written to {} with \"status\": \"failed\")",
            out.display()
        )));
    }
    report(&scene, result, written.len(), &out);
    Ok(())
}

/// Prints what a successful run did, Table I and the buckling warnings.
fn report(scene: &Scene, result: &RunResult, files: usize, out: &std::path::Path) {
    let stats = &result.stats;
    println!(
        "{}: {} formulation, {} model, {files} outputs written to {} in {:.3} s",
        scene.name,
        scene.formulation.name(),
        scene.coupling.name(),
        out.display(),
        stats.wall_time_s
    );
    if let Some(s) = &stats.integrator {
        println!(
            "  integrator {}: {} steps ({} rejected), {} rhs evaluations",
            scene.method.name(),
            s.accepted_steps,
            s.rejected_steps,
            s.rhs_evaluations
        );
    }
    for line in result.reports.iter().flat_map(|r| r.print()) {
        println!("{line}");
    }
    if let Some(table) = table_one_markdown(result) {
        println!("\nTable I (link 1 frequencies over the motion):\n{table}");
    }
    if let Some(h) = &result.frequencies {
        for b in &h.buckling {
            let margin = if b.margin.is_finite() {
                format!(", margin {:.3}", b.margin)
            } else {
                String::new()
            };
            println!(
                "  warning: link {} buckles from t = {:.5} s to {:.5} s (lowest omega^2 = {:.3e} rad^2/s^2{margin})",
                b.link + 1,
                b.t_start,
                b.t_end,
                b.min_eigenvalue,
            );
        }
    }
}

/// The scene's patches and their law, for `flexprr check` (empty without patches).
fn patch_description(scene: &Scene) -> String {
    let Some(control) = scene.patch_control() else {
        return String::new();
    };
    let patches: Vec<String> = control
        .patches
        .iter()
        .map(|p| {
            format!(
                "link {} xi {}-{} (k_a {} N m/V, k_s {} V/rad, {} V)",
                p.link + 1,
                p.xi_start,
                p.xi_end,
                p.actuator_constant,
                p.sensor_constant,
                p.voltage_limit
            )
        })
        .collect();
    let law = &control.controller;
    let timing = if law.period() > 0.0 {
        format!("sampled every {} s", law.period())
    } else {
        "continuous".to_string()
    };
    format!(
        "\n  piezoelectric patches: {}\n  vibration control: {} ({timing})",
        patches.join("; "),
        law.name()
    )
}

/// Validates a scene without running it. A study or link file is named as such, with the
/// command that reads it, instead of being reported key by key.
pub fn check(args: CheckArgs) -> Result<(), Failure> {
    let text = flexprr_scene::read_input_file(&args.scene).map_err(failure)?;
    let shown = args.scene.display().to_string();
    let other = match InputKind::of(&text) {
        InputKind::Study => Some(("a study file", "flexprr study")),
        InputKind::Link => Some(("a single-link file", "flexprr beam")),
        InputKind::Scene | InputKind::Unknown => None,
    };
    if let Some((what, command)) = other {
        return Err(Failure::bad_input(format!(
            "{shown}: this is {what}, not a scene; check it with `{command} {shown}`"
        )));
    }
    let name = args
        .scene
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("scene");
    let scene = Scene::from_text(&shown, name, &text).map_err(failure)?;
    let requests: Vec<&str> = scene.outputs.iter().map(|k| k.name()).collect();
    let model = scene.model_description();
    println!(
        "{}: ok ({model}, {} integrator, {} output times, outputs: {}){}",
        args.scene.display(),
        scene.method.name(),
        scene.output_times.len(),
        requests.join(", "),
        patch_description(&scene)
    );
    Ok(())
}
