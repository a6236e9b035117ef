//! `flexprr plan`: the fastest motion along a scene's path within its `[plan]` limits.

use std::path::PathBuf;
use std::time::Instant;

use flexprr_outdir::OutputDir;
use flexprr_plan::{Options, PLAN_PRODUCTS, PlanError, PlanOutcome, plan_scene, write_plan};
use flexprr_scene::{ScenarioError, Scene};

use super::Failure;
use super::run::failure;

/// Arguments of `flexprr plan`.
#[derive(Debug, clap::Args)]
pub struct PlanArgs {
    /// Scene file (TOML) with a `[plan]` section.
    pub scene: PathBuf,
    /// Output directory (default `out/<scene name>_plan`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// No progress lines (they appear only once the command takes more than a second).
    #[arg(long)]
    pub quiet: bool,
    /// Write into a non-empty directory that flexprr did not write, next to its files (none
    /// of them is overwritten or deleted; a file with the name of an output is refused).
    #[arg(long)]
    pub force: bool,
    /// Skip the runs of the scene's flexible model (no residual vibration, no deflection
    /// figure, no viewer of the planned motion).
    #[arg(long)]
    pub no_flexible_check: bool,
}

/// The exit code of a plan error: the scene's settings, path or limits are bad input (2); a
/// failed run or analysis of the flexible model is a run failure (1).
fn plan_failure(e: PlanError) -> Failure {
    match e {
        PlanError::NoPlan { .. }
        | PlanError::Path { .. }
        | PlanError::Planning { .. }
        | PlanError::DeflectionLimit { .. } => Failure::bad_input(e),
        PlanError::Output(inner) => failure(inner),
        other => Failure::run(other),
    }
}

/// Plans the scene, writes `plan.json`, `planned.toml`, the figures and the planned motion's
/// run, and prints the result.
pub fn plan(args: PlanArgs) -> Result<(), Failure> {
    let scene = Scene::load(&args.scene).map_err(failure)?;
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(format!("{}_plan", scene.name)));
    let target = OutputDir::check(&out, PLAN_PRODUCTS, args.force, &[&args.scene], &[])
        .map_err(|e| failure(e.into()))?;
    target.check_writable().map_err(|e| failure(e.into()))?;
    let start = Instant::now();
    let quiet = args.quiet;
    let name = scene.name.clone();
    let mut progress = |stage: &str| {
        let elapsed = start.elapsed().as_secs_f64();
        if !quiet && elapsed > 1.0 {
            eprintln!("{name}: {stage} ({elapsed:.1} s)");
        }
    };
    let options = Options {
        flexible_check: !args.no_flexible_check,
    };
    let outcome = plan_scene(&scene, options, &mut progress).map_err(plan_failure)?;
    let names = write_plan(&outcome, &target).map_err(|e| match e {
        ScenarioError::Io { .. } => Failure::run(e),
        other => failure(other),
    })?;
    report(&outcome, names.len(), &out);
    Ok(())
}

/// Prints what the plan found.
fn report(outcome: &PlanOutcome, files: usize, out: &std::path::Path) {
    let plan = &outcome.plan;
    let what = match plan.frequency() {
        Some(f) => format!("{f:.6} Hz (period {:.6} s)", plan.duration),
        None => format!("{:.6} s", plan.duration),
    };
    println!(
        "{}: {what}, {files} outputs written to {} in {:.3} s",
        outcome.scene,
        out.display(),
        outcome.wall_time_s
    );
    let binding: Vec<&str> = plan
        .binding
        .iter()
        .map(|b| b.constraint.as_str())
        .filter(|c| *c != "none")
        .collect();
    let mut seen = Vec::new();
    for b in binding {
        if !seen.contains(&b) {
            seen.push(b);
        }
    }
    println!("  binding along the path: {}", seen.join(", "));
    let own = &outcome.scene_timing;
    let use_of = match &own.check {
        Ok(check) => check.worst().map_or(String::new(), |u| {
            format!(
                ", uses {:.1} % of {} ({})",
                100.0 * u.usage,
                u.constraint,
                u.label
            )
        }),
        Err(why) => format!(", not checked: {why}"),
    };
    println!("  the scene's own timing: {:.6} s{use_of}", own.duration);
    if let (Some(unshaped), Some(design)) = (&outcome.unshaped, &outcome.shaping) {
        let shaped = outcome.deflection.as_ref().map_or(plan, |d| &d.fastest);
        let modes: Vec<String> = design
            .modes
            .iter()
            .map(|m| {
                format!(
                    "{:.2} Hz ({:.2}-{:.2} Hz along the path)",
                    m.design_hz, m.range_hz.0, m.range_hz.1
                )
            })
            .collect();
        println!(
            "  shaped for {}: {:.6} s longer than the unshaped {:.6} s",
            modes.join(", "),
            shaped.duration - unshaped.duration,
            unshaped.duration
        );
    }
    if let Some(search) = &outcome.deflection {
        if search.binds() {
            println!(
                "  deflection limit {:.3e} m: slowed {:.4} times from {:.6} s ({} runs of the flexible model), peak {:.3e} m",
                search.limit,
                search.stretch,
                search.fastest.duration,
                search.probes.len(),
                search.peak
            );
        } else {
            println!(
                "  deflection limit {:.3e} m: met by the time-optimal motion (peak {:.3e} m)",
                search.limit, search.peak
            );
        }
    }
    if let Some(flexible) = &outcome.flexible {
        if let Some(residual) = flexible.planned.residual {
            let against = flexible
                .unshaped
                .as_ref()
                .and_then(|u| u.residual)
                .map_or(String::new(), |u| {
                    format!(" ({:.1} % of the unshaped {u:.3e} m)", 100.0 * residual / u)
                });
            println!(
                "  residual vibration ({}, {:.3} s after the move): {residual:.3e} m{against}",
                flexible.model, flexible.settle_time
            );
        }
    }
}
