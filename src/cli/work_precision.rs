//! `flexprr work-precision`: wall time against achieved error for each integrator over a
//! ladder of tolerances, optionally for several models side by side (`--models`), with
//! optional rows of other packages merged in.

use std::path::PathBuf;

use flexprr_bench::work_precision::{
    ErrorMeasure, ModelChoice, NONLINEAR_TOLERANCES, Reference, WorkPrecisionConfig,
    WorkPrecisionError, WorkPrecisionRow, csv_text, markdown_at_error, markdown_models,
    markdown_rows, measure, method_applies, read_csv, write_svg,
};
use flexprr_scene::{Registry, ScenarioError, Scene};

use super::Failure;
use super::run::failure;

/// Arguments of `flexprr work-precision`.
#[derive(Debug, clap::Args)]
pub struct WorkPrecisionArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Output directory (default `out/<scene name>/work_precision`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Relative tolerances of the ladder, comma-separated (default 1e-3 to 1e-12; 1e-3 to
    /// 1e-8 when a nonlinear model is measured).
    #[arg(long, value_delimiter = ',')]
    pub tolerances: Option<Vec<f64>>,
    /// Models to set side by side, comma-separated, each overriding the scene's
    /// `model.coupling` (and `model.elements`): ked, coupled, nonlinear, nonlinear:N (N even,
    /// 2 to 512). All are measured in mid-point deflections against one reference. Default:
    /// the scene's own model.
    #[arg(long, value_delimiter = ',')]
    pub models: Option<Vec<String>>,
    /// Model of the reference (a name as in --models). Default: the most faithful model
    /// measured (nonlinear with the most elements, then coupled, then KED).
    #[arg(long)]
    pub reference_model: Option<String>,
    /// Error measure: deflection (the links' mid-point deflections; every model) or state
    /// (the modal state; KED models only). Default: state when every model is KED, else
    /// deflection.
    #[arg(long)]
    pub error: Option<String>,
    /// Relative tolerance of the reference. Default per reference model: 1e-14 (KED and
    /// coupled), 1e-10 (nonlinear).
    #[arg(long)]
    pub reference_rtol: Option<f64>,
    /// Methods to measure, comma-separated (default abm,rk45,bdf,magnus4,magnus6,auto).
    #[arg(long, value_delimiter = ',')]
    pub methods: Option<Vec<String>>,
    /// Timed runs per point (the median is reported).
    #[arg(long, default_value_t = 7)]
    pub repeats: usize,
    /// Untimed warm-up runs per point.
    #[arg(long, default_value_t = 2)]
    pub warmup: usize,
    /// Reference solution file to use instead of computing one (as written by this command).
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Rows of other packages to merge (CSV in the work_precision.csv format); repeatable.
    #[arg(long)]
    pub peers: Vec<PathBuf>,
    /// Maximum relative error at which the methods are compared.
    #[arg(long, default_value_t = 1e-6)]
    pub target_error: f64,
    /// Write into a non-empty directory that flexprr did not write, next to its files.
    #[arg(long)]
    pub force: bool,
    /// Another scene measured side by side in the same run, against its own reference
    /// (repeatable): e.g. the actuated `configs/servo_f20.toml` beside the prescribed
    /// `configs/coupled_f20.toml`. Its rows are labelled with its scene name.
    #[arg(long)]
    pub compare: Vec<PathBuf>,
}

/// Measures, merges the peers' rows and writes `work_precision.csv`, `work_precision.svg`,
/// `work_precision.md` and `reference.csv`.
pub fn run(args: WorkPrecisionArgs) -> Result<(), Failure> {
    let scene = Scene::load(&args.scene).map_err(failure)?;
    for path in args.reference.iter().chain(&args.peers) {
        flexprr_scene::check_input_file(path, flexprr_scene::MAX_DATA_BYTES).map_err(failure)?;
    }
    // The peers' rows are read before anything is measured: a bad file is refused at once.
    let mut peers: Vec<WorkPrecisionRow> = Vec::new();
    for path in &args.peers {
        peers.extend(read_csv(path).map_err(failure)?);
    }
    let config = config_of(&args, &scene)?;
    let measure_name = check_choices(&args, &config, &scene)?;
    let out_dir = output_dir(&args, &scene)?;
    let (reference, reference_line) = reference_of(&args, &config, &scene, measure_name)?;
    // Opened once there is a reference to measure against: a refused one writes nothing.
    let out = out_dir.open().map_err(|e| failure(e.into()))?;
    reference
        .write_csv(&out.join("reference.csv"))
        .map_err(measure_failure)?;
    let (mut rows, mut failures) = measure_printed(&scene, &reference, &config)?;
    if !args.compare.is_empty() {
        label_with_scene(&mut rows, &scene);
        let (more, more_failures) = measure_compared(&args, measure_name)?;
        rows.extend(more);
        failures.extend(more_failures);
    }
    let measured = rows.len();
    rows.extend(peers);
    let report = Report {
        scene: &scene,
        rows: &rows,
        failures: &failures,
        measure_name,
        reference_line: reference_line.as_deref(),
        side_by_side: !config.models.is_empty() || !args.compare.is_empty(),
        target_error: args.target_error,
    };
    report.write_tables(&out)?;
    if measured == 0 {
        return Err(Failure::run(format!(
            "work-precision of scene {:?}: no point was measured, every one failed ({}; all \
             in {})",
            scene.name,
            failures.first().map_or("no method applies", String::as_str),
            out.join("work_precision.md").display()
        )));
    }
    write_svg(
        &rows,
        &out.join("work_precision.svg"),
        &format!("Work-precision: {}", scene.name),
    )
    .map_err(measure_failure)?;
    println!("\n{}", markdown_at_error(&rows, args.target_error));
    println!(
        "{} rows written to {}",
        rows.len(),
        out.join("work_precision.csv").display()
    );
    Ok(())
}

/// A failed measurement: bad input (exit 2) for the scene layer's input errors, a failed run
/// (exit 1) for the rest (a failed or unconfirmed reference, a file that cannot be written).
fn measure_failure(e: WorkPrecisionError) -> Failure {
    match e {
        WorkPrecisionError::Scene(e) => failure(e),
        other => Failure::run(other),
    }
}

/// The model named `name` after `option` (`--models`, `--reference-model`).
fn model_named(option: &str, name: &str) -> Result<ModelChoice, Failure> {
    ModelChoice::parse(name.trim()).ok_or_else(|| {
        Failure::bad_input(format!(
            "{option}: unknown model {name:?} (expected one of {})",
            ModelChoice::names(&Registry::default())
        ))
    })
}

/// The measurement's configuration from the options: models, reference model, error
/// measure, ladder (the nonlinear default when a nonlinear model is involved) and methods,
/// each name parsed and checked, repeats refused.
///
/// # Errors
/// Bad input (exit 2) naming the option and the value.
fn config_of(args: &WorkPrecisionArgs, scene: &Scene) -> Result<WorkPrecisionConfig, Failure> {
    let mut config = WorkPrecisionConfig {
        repeats: args.repeats,
        warmup: args.warmup,
        reference_rtol: args.reference_rtol,
        ..WorkPrecisionConfig::default()
    };
    if let Some(names) = &args.models {
        config.models = names
            .iter()
            .map(|name| model_named("--models", name))
            .collect::<Result<_, _>>()?;
        refuse_repeats("--models", names)?;
    }
    if let Some(name) = &args.reference_model {
        config.reference_model = Some(model_named("--reference-model", name)?);
    }
    if let Some(name) = &args.error {
        config.error = Some(ErrorMeasure::parse(name.trim()).ok_or_else(|| {
            let known: Vec<&str> = ErrorMeasure::ALL.iter().map(|m| m.name()).collect();
            Failure::bad_input(format!(
                "--error: unknown error measure {name:?} (expected one of {})",
                known.join(", ")
            ))
        })?);
    }
    let nonlinear = config
        .measured_models(scene)
        .into_iter()
        .chain([config.reference_model(scene)])
        .any(|m| m.in_elements());
    match &args.tolerances {
        Some(tolerances) => config.tolerances.clone_from(tolerances),
        None if nonlinear => config.tolerances = NONLINEAR_TOLERANCES.to_vec(),
        None => {}
    }
    if let Some(names) = &args.methods {
        let registry = Registry::default();
        config.methods = names
            .iter()
            .map(|name| {
                registry.method(name.trim()).ok_or_else(|| {
                    let known = registry.integrator_names();
                    Failure::bad_input(format!(
                        "--methods: unknown method {name:?} (expected one of {})",
                        known.join(", ")
                    ))
                })
            })
            .collect::<Result<_, _>>()?;
        refuse_repeats("--methods", names)?;
    }
    if !(args.target_error.is_finite() && args.target_error > 0.0) {
        return Err(Failure::bad_input(format!(
            "--target-error must be positive, got {}",
            args.target_error
        )));
    }
    config.validate().map_err(failure)?;
    Ok(config)
}

/// Checks, before any work, that every choice applies to the scene: the error measure to
/// the models, each model to the scene's formulation (and no model twice under two names),
/// each method named on the command line to at least one measured model (the default list
/// simply skips those that do not, said in the output), the reference model and its
/// tolerance. Returns the error measure's name.
///
/// # Errors
/// Bad input (exit 2) naming the option.
fn check_choices(
    args: &WorkPrecisionArgs,
    config: &WorkPrecisionConfig,
    scene: &Scene,
) -> Result<&'static str, Failure> {
    let option_error = |option: String| {
        move |e: ScenarioError| match e {
            ScenarioError::Input { message, .. } => {
                Failure::bad_input(format!("{option}: {message}"))
            }
            other => failure(other),
        }
    };
    let measure_name = config
        .error_measure(scene)
        .map_err(option_error(format!(
            "--error {}",
            args.error.as_deref().unwrap_or_default()
        )))?
        .name();
    let mut model_scenes = Vec::new();
    for choice in config.measured_models(scene) {
        let applied = choice
            .apply(scene)
            .map_err(option_error("--models".to_string()))?;
        model_scenes.push((choice.label(scene), applied));
    }
    if let Some(names) = &args.models {
        let labels: Vec<String> = model_scenes.iter().map(|(l, _)| l.clone()).collect();
        refuse_repeats("--models", &labels).map_err(|e| {
            Failure::bad_input(format!("{} (given: {})", e.message, names.join(",")))
        })?;
    }
    if args.methods.is_some() {
        for method in &config.methods {
            let reasons: Vec<String> = model_scenes
                .iter()
                .filter_map(|(_, s)| method_applies(s, method).err())
                .collect();
            if let (true, Some(why)) = (reasons.len() == model_scenes.len(), reasons.first()) {
                let models: Vec<&str> = model_scenes.iter().map(|(l, _)| l.as_str()).collect();
                return Err(Failure::bad_input(format!(
                    "--methods: {why} (measured: {})",
                    models.join(", ")
                )));
            }
        }
    }
    config
        .reference_model(scene)
        .apply(scene)
        .map_err(option_error("--reference-model".to_string()))?;
    if args.reference.is_none() {
        config
            .reference_plan(scene)
            .map_err(option_error("--reference-rtol".to_string()))?;
    }
    Ok(measure_name)
}

/// The reference: read from `--reference`, or computed (and refused if it diverged or
/// failed, exit 1); with the line that says how it was computed and checked, printed.
fn reference_of(
    args: &WorkPrecisionArgs,
    config: &WorkPrecisionConfig,
    scene: &Scene,
    measure_name: &str,
) -> Result<(Reference, Option<String>), Failure> {
    let clock = std::time::Instant::now();
    let reference = match &args.reference {
        Some(path) => Reference::read_csv(path).map_err(failure)?,
        None => Reference::compute(scene, config).map_err(measure_failure)?,
    };
    let reference_s = clock.elapsed().as_secs_f64();
    let line = reference.agreement.map(|a| {
        format!(
            "reference: {} with {} at rtol {:e}, checked with {} at rtol {:e}: agree to {:.1e} \
             (end) / {:.1e} (max) in the {measure_name} measure ({reference_s:.1} s with its \
             pilot run)",
            reference.model,
            reference.method,
            reference.rtol,
            reference.check_method,
            reference.check_rtol,
            a.end,
            a.max
        )
    });
    if let Some(line) = &line {
        println!("{line}");
    }
    Ok((reference, line))
}

/// Measures every point, printing a table line per row as it comes and each failed point
/// on stderr.
fn measure_printed(
    scene: &Scene,
    reference: &Reference,
    config: &WorkPrecisionConfig,
) -> Result<(Vec<WorkPrecisionRow>, Vec<String>), Failure> {
    println!(
        "{:<24} {:>7} {:>10} {:>8} {:>9} {:>10} {:>10}",
        "method", "rtol", "time_ms", "steps", "rhs", "end_err", "max_err"
    );
    let (rows, failures) = measure(scene, reference, config, &mut |r| {
        println!(
            "{:<24} {:>7.0e} {:>10.3} {:>8} {:>9} {:>10.2e} {:>10.2e}",
            r.series_label(),
            r.rtol,
            1e3 * r.time_median_s,
            r.accepted_steps.unwrap_or(0),
            r.rhs_evaluations.unwrap_or(0),
            r.end_error,
            r.max_error
        );
    })
    .map_err(measure_failure)?;
    for f in &failures {
        eprintln!("failed: {f}");
    }
    Ok((rows, failures))
}

/// What `work_precision.csv` and `work_precision.md` say.
struct Report<'a> {
    scene: &'a Scene,
    rows: &'a [WorkPrecisionRow],
    failures: &'a [String],
    measure_name: &'a str,
    reference_line: Option<&'a str>,
    side_by_side: bool,
    target_error: f64,
}

impl Report<'_> {
    /// Writes `work_precision.csv` and `work_precision.md` (the reference, cost against
    /// fidelity with models side by side, the equal-error table, every point, the failed
    /// points) into `out`.
    fn write_tables(&self, out: &std::path::Path) -> Result<(), Failure> {
        let write = |name: &str, text: &str| {
            let path = out.join(name);
            std::fs::write(&path, text)
                .map_err(|e| Failure::run(format!("{}: {e}", path.display())))
        };
        write(
            "work_precision.csv",
            &csv_text(self.rows).map_err(measure_failure)?,
        )?;
        write("work_precision.md", &self.markdown())
    }

    /// The text of `work_precision.md`.
    fn markdown(&self) -> String {
        let what = match self.measure_name {
            "state" => "the modal state, relative to the solution's size",
            _ => "the links' mid-point deflections, relative to the reference's largest",
        };
        let mut md = format!(
            "# Work-precision: {}\n\nErrors: maximum over the output times of {what}.\n\n",
            self.scene.name
        );
        if let Some(line) = self.reference_line {
            md.push_str(&format!("{line}\n\n"));
        }
        if self.side_by_side {
            md.push_str(&format!(
                "Cost against fidelity:\n\n{}\n",
                markdown_models(self.rows)
            ));
        }
        md.push_str(&format!(
            "At equal achieved error:\n\n{}\nAll points:\n\n{}",
            markdown_at_error(self.rows, self.target_error),
            markdown_rows(self.rows)
        ));
        if !self.failures.is_empty() {
            md.push_str("\nFailed points:\n\n");
            for f in self.failures {
                md.push_str(&format!("- {f}\n"));
            }
        }
        md
    }
}

/// Refuses a name given twice to `option` (a repeat would only give duplicate rows).
fn refuse_repeats(option: &str, names: &[String]) -> Result<(), Failure> {
    let trimmed: Vec<&str> = names.iter().map(|n| n.trim()).collect();
    match (1..trimmed.len()).find(|&k| trimmed[..k].contains(&trimmed[k])) {
        Some(k) => Err(Failure::bad_input(format!(
            "{option}: {:?} is named twice; each is measured once",
            trimmed[k]
        ))),
        None => Ok(()),
    }
}

/// The output directory (`--out`, default `out/<scene name>/work_precision`) checked
/// against the output-directory policy before any work: refused when foreign without
/// `--force`, when it is an input, or `/`.
///
/// # Errors
/// Bad input (exit 2) saying why the directory is refused.
fn output_dir(
    args: &WorkPrecisionArgs,
    scene: &Scene,
) -> Result<flexprr_outdir::OutputDir, Failure> {
    let out = args.out.clone().unwrap_or_else(|| {
        PathBuf::from("out")
            .join(&scene.name)
            .join("work_precision")
    });
    let inputs: Vec<&std::path::Path> = [args.scene.as_path()]
        .into_iter()
        .chain(args.reference.as_deref())
        .chain(args.peers.iter().map(PathBuf::as_path))
        .chain(args.compare.iter().map(PathBuf::as_path))
        .collect();
    flexprr_outdir::OutputDir::check(
        &out,
        flexprr_outdir::WORK_PRECISION,
        args.force,
        &inputs,
        &[],
    )
    .map_err(|e| failure(e.into()))
}

/// Prefixes the model label of `rows` with the scene's name (`servo_f20: coupled`).
fn label_with_scene(rows: &mut [WorkPrecisionRow], scene: &Scene) {
    for row in rows {
        row.model = if row.model.is_empty() {
            format!("{}: {}", scene.name, ModelChoice::of(scene).label(scene))
        } else {
            format!("{}: {}", scene.name, row.model)
        };
    }
}

/// The `--compare` scenes, each measured against its own reference with the same options,
/// labelled with its name.
///
/// # Errors
/// Bad input (exit 2): `--compare` with `--models` or `--reference` (one reference per
/// scene is computed), a scene whose error measure differs from the main one's; or a
/// failed reference (exit 1).
fn measure_compared(
    args: &WorkPrecisionArgs,
    measure_name: &str,
) -> Result<(Vec<WorkPrecisionRow>, Vec<String>), Failure> {
    if args.models.is_some() || args.reference.is_some() {
        return Err(Failure::bad_input(
            "--compare measures each scene against its own computed reference: it does not combine with --models or --reference".to_string(),
        ));
    }
    let (mut rows, mut failures) = (Vec::new(), Vec::new());
    for path in &args.compare {
        let other = Scene::load(path).map_err(failure)?;
        let config = config_of(args, &other)?;
        let name = check_choices(args, &config, &other)?;
        if name != measure_name {
            return Err(Failure::bad_input(format!(
                "--compare {}: its error measure is {name}, the scene's {measure_name}; set --error",
                path.display()
            )));
        }
        println!("\n{}:", other.name);
        let (reference, _) = reference_of(args, &config, &other, measure_name)?;
        let (mut more, more_failures) = measure_printed(&other, &reference, &config)?;
        label_with_scene(&mut more, &other);
        rows.extend(more);
        failures.extend(more_failures);
    }
    Ok((rows, failures))
}
