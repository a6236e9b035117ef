//! `flexprr work-precision`: wall time against achieved error for each integrator over a
//! ladder of tolerances, optionally for several models side by side (`--models`), with
//! optional rows of other packages merged in.

use std::path::PathBuf;

use flexprr_bench::work_precision::{
    ErrorMeasure, ModelChoice, NONLINEAR_TOLERANCES, Reference, WorkPrecisionConfig,
    WorkPrecisionRow, csv_text, markdown_at_error, markdown_models, markdown_rows, measure,
    method_applies, read_csv, write_svg,
};
use flexprr_scene::{Method, ScenarioError, Scene};

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
}

/// Measures, merges the peers' rows and writes `work_precision.csv`, `work_precision.svg`,
/// `work_precision.md` and `reference.csv`.
pub fn run(args: WorkPrecisionArgs) -> Result<(), Failure> {
    let scene = Scene::load(&args.scene).map_err(failure)?;
    for path in args.reference.iter().chain(&args.peers) {
        flexprr_scene::check_input_file(path, flexprr_scene::MAX_DATA_BYTES).map_err(failure)?;
    }
    let mut config = WorkPrecisionConfig {
        repeats: args.repeats,
        warmup: args.warmup,
        reference_rtol: args.reference_rtol,
        ..WorkPrecisionConfig::default()
    };
    let model = |option: &str, name: &str| {
        ModelChoice::parse(name.trim()).ok_or_else(|| {
            Failure::bad_input(format!(
                "{option}: unknown model {name:?} (expected one of {})",
                ModelChoice::NAMES
            ))
        })
    };
    if let Some(names) = &args.models {
        config.models = names
            .iter()
            .map(|name| model("--models", name))
            .collect::<Result<_, _>>()?;
    }
    if let Some(name) = &args.reference_model {
        config.reference_model = Some(model("--reference-model", name)?);
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
        .measured_models(&scene)
        .into_iter()
        .chain([config.reference_model(&scene)])
        .any(|m| matches!(m, ModelChoice::Nonlinear(_)));
    match args.tolerances {
        Some(tolerances) => config.tolerances = tolerances,
        None if nonlinear => config.tolerances = NONLINEAR_TOLERANCES.to_vec(),
        None => {}
    }
    if let Some(names) = &args.methods {
        config.methods = names
            .iter()
            .map(|name| {
                Method::parse(name.trim()).ok_or_else(|| {
                    let known: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
                    Failure::bad_input(format!(
                        "--methods: unknown method {name:?} (expected one of {})",
                        known.join(", ")
                    ))
                })
            })
            .collect::<Result<_, _>>()?;
    }
    if !(args.target_error.is_finite() && args.target_error > 0.0) {
        return Err(Failure::bad_input(format!(
            "--target-error must be positive, got {}",
            args.target_error
        )));
    }
    config.validate().map_err(failure)?;
    let option_error = |option: String| {
        move |e: ScenarioError| match e {
            ScenarioError::Input { message, .. } => {
                Failure::bad_input(format!("{option}: {message}"))
            }
            other => failure(other),
        }
    };
    let measure_name = config
        .error_measure(&scene)
        .map_err(option_error(format!(
            "--error {}",
            args.error.as_deref().unwrap_or_default()
        )))?
        .name();
    let mut model_scenes = Vec::new();
    for choice in config.measured_models(&scene) {
        let applied = choice
            .apply(&scene)
            .map_err(option_error("--models".to_string()))?;
        model_scenes.push((choice.label(&scene), applied));
    }
    // A method named on the command line must apply to at least one measured model; the
    // default list simply skips those that do not (said in the output).
    if args.methods.is_some() {
        for &method in &config.methods {
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
        .reference_model(&scene)
        .apply(&scene)
        .map_err(option_error("--reference-model".to_string()))?;
    if args.reference.is_none() {
        config
            .reference_plan(&scene)
            .map_err(option_error("--reference-rtol".to_string()))?;
    }
    let out = args.out.unwrap_or_else(|| {
        PathBuf::from("out")
            .join(&scene.name)
            .join("work_precision")
    });
    let inputs: Vec<&std::path::Path> = [args.scene.as_path()]
        .into_iter()
        .chain(args.reference.as_deref())
        .chain(args.peers.iter().map(PathBuf::as_path))
        .collect();
    let out = flexprr_run::OutputDir::check(
        &out,
        flexprr_run::output_dir::WORK_PRECISION,
        args.force,
        &inputs,
        &[],
    )
    .and_then(|dir| dir.open())
    .map_err(|e| failure(e.into()))?;

    let clock = std::time::Instant::now();
    let reference = match &args.reference {
        Some(path) => Reference::read_csv(path).map_err(failure)?,
        None => Reference::compute(&scene, &config).map_err(failure)?,
    };
    let reference_s = clock.elapsed().as_secs_f64();
    let reference_line = reference.agreement.map(|a| {
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
    if let Some(line) = &reference_line {
        println!("{line}");
    }
    reference
        .write_csv(&out.join("reference.csv"))
        .map_err(failure)?;

    let mut peers: Vec<WorkPrecisionRow> = Vec::new();
    for path in &args.peers {
        peers.extend(read_csv(path).map_err(failure)?);
    }
    println!(
        "{:<24} {:>7} {:>10} {:>8} {:>9} {:>10} {:>10}",
        "method", "rtol", "time_ms", "steps", "rhs", "end_err", "max_err"
    );
    let (mut rows, failures) = measure(&scene, &reference, &config, &mut |r| {
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
    .map_err(failure)?;
    for f in &failures {
        eprintln!("failed: {f}");
    }
    rows.extend(peers);

    let csv = csv_text(&rows).map_err(failure)?;
    let write = |name: &str, text: &str| {
        let path = out.join(name);
        std::fs::write(&path, text).map_err(|e| Failure::run(format!("{}: {e}", path.display())))
    };
    write("work_precision.csv", &csv)?;
    let at_error = markdown_at_error(&rows, args.target_error);
    let what = match measure_name {
        "state" => "the modal state, relative to the solution's size",
        _ => "the links' mid-point deflections, relative to the reference's largest",
    };
    let mut md = format!(
        "# Work-precision: {}\n\nErrors: maximum over the output times of {what}.\n\n",
        scene.name
    );
    if let Some(line) = &reference_line {
        md.push_str(&format!("{line}\n\n"));
    }
    if !config.models.is_empty() {
        md.push_str(&format!(
            "Cost against fidelity:\n\n{}\n",
            markdown_models(&rows)
        ));
    }
    md.push_str(&format!(
        "At equal achieved error:\n\n{at_error}\nAll points:\n\n{}",
        markdown_rows(&rows)
    ));
    if !failures.is_empty() {
        md.push_str("\nFailed points:\n\n");
        for f in &failures {
            md.push_str(&format!("- {f}\n"));
        }
    }
    write("work_precision.md", &md)?;
    write_svg(
        &rows,
        &out.join("work_precision.svg"),
        &format!("Work-precision: {}", scene.name),
    )
    .map_err(failure)?;
    println!("\n{at_error}");
    println!(
        "{} rows written to {}",
        rows.len(),
        out.join("work_precision.csv").display()
    );
    Ok(())
}
