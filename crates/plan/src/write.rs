//! The products of `flexprr plan` in one output directory, under the run's output-directory
//! policy (`flexprr_outdir`): staged, published at the end, nothing written outside.

use std::borrow::Cow;
use std::path::Path;

use flexprr_outdir::{OutputDir, Products};
use flexprr_run::{WriteOptions, write_outputs_with};
use flexprr_scene::ScenarioError;

use crate::pipeline::PlanOutcome;

/// The directory of the planned motion's run (its viewer, tables and figures) inside the
/// plan's output directory.
pub const PLANNED_RUN_DIR: &str = "planned";

/// What `flexprr plan` writes.
pub const PLAN_PRODUCTS: Products = Products {
    kind: "plan",
    names: Cow::Borrowed(&[
        "plan.json",
        "planned.toml",
        PLANNED_RUN_DIR,
        "phase_plane.svg",
        "sliders.svg",
        "deflections.svg",
    ]),
    patterns: Cow::Borrowed(&[]),
    legacy: None,
};

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ScenarioError + '_ {
    move |source| ScenarioError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// The header of `planned.toml`.
fn header(outcome: &PlanOutcome) -> String {
    let what = match outcome.plan.frequency() {
        Some(f) => format!(
            "repeats at {f:.6} Hz (period {:.6} s)",
            outcome.plan.duration
        ),
        None => format!("takes {:.6} s", outcome.plan.duration),
    };
    format!(
        "Planned by `flexprr plan` from the scene {}: the motion {what} within the limits of its \
         [plan] section\n(in plan.json). Run it with `flexprr run`. The trajectory is the path \
         with its planned speed s_dot on the grid s\n(SI units, angles in rad); see \
         docs/planning.md.",
        outcome.scene
    )
}

/// The products' files into `dir` (the staging directory): `plan.json`, `planned.toml`, the
/// figures and, with a flexible check, the planned motion's run in `planned/`. Returns the
/// names written.
///
/// # Errors
/// [`ScenarioError::Io`] when a file cannot be written.
pub fn write_files(outcome: &PlanOutcome, dir: &Path) -> Result<Vec<String>, ScenarioError> {
    let mut names = Vec::new();
    let json =
        serde_json::to_string_pretty(&crate::report::plan_report(outcome)).unwrap_or_default();
    let path = dir.join("plan.json");
    std::fs::write(&path, json).map_err(io(&path))?;
    names.push("plan.json".to_string());
    let toml =
        crate::variant::scene_toml(&outcome.planned_file, &header(outcome)).map_err(|message| {
            ScenarioError::Input {
                location: None,
                key: "planned.toml".into(),
                message,
            }
        })?;
    let path = dir.join("planned.toml");
    std::fs::write(&path, toml).map_err(io(&path))?;
    names.push("planned.toml".to_string());
    for (name, figure) in crate::figures::plan_figures(outcome) {
        let path = dir.join(&name);
        // A figure that cannot be drawn or written is that file's I/O error.
        figure
            .write_svg(&path)
            .map_err(|e| io(&path)(std::io::Error::other(e)))?;
        names.push(name);
    }
    if let Some(flexible) = &outcome.flexible {
        write_outputs_with(
            &flexible.planned_scene,
            &flexible.planned_run,
            None,
            &dir.join(PLANNED_RUN_DIR),
            WriteOptions::default(),
        )?;
        names.push(PLANNED_RUN_DIR.to_string());
    }
    Ok(names)
}

/// Writes the products into a checked output directory (staged, then published).
///
/// # Errors
/// As [`write_files`]; a refusal of the directory's policy at publication.
pub fn write_plan(outcome: &PlanOutcome, target: &OutputDir) -> Result<Vec<String>, ScenarioError> {
    let staging = target.stage()?;
    let names = write_files(outcome, staging.path())?;
    staging.publish()?;
    Ok(names)
}
