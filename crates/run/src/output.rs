//! Writing a run's results: one CSV per time series, `summary.json`, Table I and SVG plots.
//!
//! A run's directory is written whole, by the policy of [`flexprr_outdir`]: every file
//! goes into a staging directory, published at the end, so a crash never leaves a
//! half-written directory and a second run never leaves stale files of the first. A
//! directory flexprr did not write is refused unless the caller forces it, and even then
//! none of its files is overwritten or deleted.

use std::fmt::Write as _;
use std::path::Path;

use serde_json::{Value, json};

use crate::error::RunError;
use crate::table::{RunResult, Table};
use std::sync::LazyLock;

use crate::producer::OutputRegistry;
use flexprr_outdir::{OutputDir, Products};
use flexprr_scene::ScenarioError;
use flexprr_scene::Scene;

fn io(path: &Path) -> impl Fn(std::io::Error) -> ScenarioError + '_ {
    move |source| ScenarioError::Io {
        path: path.display().to_string(),
        source,
    }
}

/// A failure to produce the bytes of output file `name` (a CSV record, an SVG figure whose
/// data do not fit), as the I/O error of that file: it is the file that could not be written.
fn unwritable(dir: &Path, name: &str, reason: impl std::fmt::Display) -> ScenarioError {
    ScenarioError::Io {
        path: dir.join(name).display().to_string(),
        source: std::io::Error::other(reason.to_string()),
    }
}

fn csv_bytes(table: &Table, dir: &Path) -> Result<Vec<u8>, ScenarioError> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let file = format!("{}.csv", table.name);
    let csv_err = |e: csv::Error| unwritable(dir, &file, e);
    w.write_record(table.headers()).map_err(csv_err)?;
    let mut row = Vec::with_capacity(table.columns.len());
    for k in 0..table.rows() {
        row.clear();
        row.extend(table.data.iter().map(|c| format!("{:.10e}", c[k])));
        w.write_record(&row).map_err(csv_err)?;
    }
    w.into_inner().map_err(|e| unwritable(dir, &file, e))
}

/// `null` for a non-finite number (JSON has none; the summary never shows `NaN` or `inf`).
fn finite(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

/// The run's status for `summary.json`: `ok`, or `failed` with the failure's time, kind,
/// link and message.
fn status_json(failure: Option<&RunError>) -> (Value, Value) {
    match failure {
        None => (json!("ok"), Value::Null),
        Some(e) => {
            let mut failure = json!({
                "kind": e.kind(),
                "time_s": e.time().map_or(Value::Null, finite),
                "link": e.link().map(|l| l + 1),
                "message": e.to_string(),
            });
            if let (Some(c), Some(object)) = (e.collapse(), failure.as_object_mut()) {
                object.insert("deflection_m".into(), finite(c.deflection));
                object.insert(
                    "deflection_fraction".into(),
                    finite(c.deflection.abs() / c.length),
                );
                object.insert("type_ii_measure".into(), finite(c.type_ii_measure));
            }
            (json!("failed"), failure)
        }
    }
}

/// The summary of a run as JSON: status (and failure), scene echo, formulation, integrator
/// statistics, wall time, frequency ranges and buckling intervals.
pub fn summary_json(scene: &Scene, result: &RunResult, failure: Option<&RunError>) -> Value {
    let f = &scene.formulation;
    let stats = &result.stats;
    let integrator = stats.integrator.as_ref().map(|s| {
        json!({
            "method": scene.method.name(),
            "rtol": scene.options.rtol,
            "accepted_steps": s.accepted_steps,
            "rejected_steps": s.rejected_steps,
            "rhs_evaluations": s.rhs_evaluations,
            "jacobian_evaluations": s.jacobian_evaluations,
            "lu_decompositions": s.lu_decompositions,
            "orders_used": s.orders,
            "stiffness_detected_at_s": s.stiffness_detected_at,
        })
    });
    let frequencies = result.frequencies.as_ref().map(|h| {
        let ranges: Vec<Value> = h
            .ranges
            .iter()
            .map(|r| {
                json!({
                    "link": r.link + 1, "mode": r.mode + 1,
                    "rigid": is_rigid(r),
                    "nominal_hz": finite(r.nominal_hz), "min_hz": finite(r.min_hz),
                    "t_min_s": r.t_min, "max_hz": finite(r.max_hz), "t_max_s": r.t_max,
                    "min_stiffness_ratio": finite(r.min_stiffness_ratio),
                })
            })
            .collect();
        let buckling: Vec<Value> = h
            .buckling
            .iter()
            .map(|b| {
                json!({
                    "link": b.link + 1, "t_start_s": b.t_start, "t_end_s": b.t_end,
                    "min_eigenvalue_rad2_s2": finite(b.min_eigenvalue), "margin": finite(b.margin),
                })
            })
            .collect();
        json!({ "ranges": ranges, "buckling_intervals": buckling })
    });
    let peaks: serde_json::Map<String, Value> = result
        .tables
        .iter()
        .flat_map(|t| {
            t.columns
                .iter()
                .zip(&t.data)
                .skip(1)
                .map(move |(name, col)| {
                    let peak = col.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                    (format!("{}.{}", t.name, name), finite(peak))
                })
        })
        .collect();
    let (status, failure) = status_json(failure);
    let mut summary = json!({
        "status": status,
        "failure": failure,
        "warnings": result.warnings,
        "scene": scene.name,
        "flexprr_version": env!("CARGO_PKG_VERSION"),
        "formulation": {
            "name": f.name(),
            "coupling": scene.coupling.name(),
            "axial_force": scene.axial_model.name(),
            "geometric_stiffness": f.geometric_stiffness.name(),
            "coriolis_forcing": f.coriolis_forcing,
            "centrifugal_softening": f.centrifugal_softening,
            "damping": scene.damping.ratios,
        },
        "run": {
            "integrated": stats.integrated,
            "rhs_evaluations": stats.rhs_evaluations,
            "inverse_dynamics_solves": stats.inverse_dynamics_solves,
            "wall_time_s": stats.wall_time_s,
            "output_samples": scene.output_times.len(),
            "output_samples_written": result.tables.first().map_or(0, |t| t.rows()),
            "max_deflection_m": stats.max_deflection_m.map(finite),
        },
        "integrator": integrator,
        "frequencies": frequencies,
        "peak_abs": peaks,
        "scene_file": serde_json::to_value(&scene.file).unwrap_or(Value::Null),
    });
    if let Some(map) = summary.as_object_mut() {
        for key in crate::report::BUILT_IN_SECTIONS {
            map.insert((*key).to_string(), Value::Null);
        }
        for (key, value) in result.reports.iter().flat_map(|r| r.sections()) {
            map.insert(key.to_string(), value);
        }
    }
    summary
}

/// Whether a frequency range belongs to a rigid-body mode (free-free or pinned-free bases):
/// its nominal frequency is zero to rounding, so a relative change means nothing.
pub fn is_rigid(r: &flexprr_dynamics::ModeRange) -> bool {
    !(r.nominal_hz.is_finite() && r.nominal_hz > 1e-6 * r.max_hz.abs().max(1.0))
}

/// The paper's Table I for link 1 as markdown (nominal, min, max and relative change);
/// rigid-body modes are shown as `rigid (0 Hz)`, without a percentage.
pub fn table_one_markdown(result: &RunResult) -> Option<String> {
    let h = result.frequencies.as_ref()?;
    let mut s = String::from(
        "| link 1 | nominal (Hz) | minimum (Hz) | maximum (Hz) | change |\n|---|---|---|---|---|\n",
    );
    for r in h.ranges.iter().filter(|r| r.link == 0) {
        if is_rigid(r) {
            let _ = writeln!(s, "| mode {} | rigid (0 Hz) | - | - | - |", r.mode + 1);
            continue;
        }
        let change = (r.max_hz - r.min_hz) / r.nominal_hz * 100.0;
        let _ = writeln!(
            s,
            "| mode {} | {:.1} | {:.1} | {:.1} | {:.0} % |",
            r.mode + 1,
            r.nominal_hz,
            r.min_hz,
            r.max_hz,
            change
        );
    }
    Some(s)
}

/// How [`write_outputs_with`] treats an existing directory.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct WriteOptions {
    /// Write into a non-empty directory that is not a flexprr output, next to its files
    /// (none of which is overwritten or deleted).
    pub force: bool,
}

/// The files of a run with the built-in outputs (`docs/scenes.md`, "Outputs and their CSV
/// columns" and "Plots"), from the built-in producers ([`OutputRegistry::products`]): what
/// [`flexprr_outdir`] refuses to write over when it finds them in a directory flexprr did
/// not write, and what it recognises an earlier run's directory by. A program with outputs of
/// its own checks its directory with the products of its registry.
pub static RUN_PRODUCTS: LazyLock<Products> =
    LazyLock::new(|| OutputRegistry::built_in().products());

/// Writes every output of a successful run into `dir` (see [`write_outputs_with`]).
///
/// # Errors
/// As [`write_outputs_with`].
pub fn write_outputs(
    scene: &Scene,
    result: &RunResult,
    dir: &Path,
) -> Result<Vec<String>, ScenarioError> {
    write_outputs_with(scene, result, None, dir, WriteOptions::default())
}

/// Writes every output of `result` (a complete run, or the partial outputs of a failed one
/// with its `failure`) into `dir`, checked by [`OutputDir::check`] with the policy of
/// [`flexprr_outdir`]: CSV tables, `summary.json` with the status,
/// `table1.md`/`table1.csv` when frequencies were computed, SVG plots unless the scene turned
/// them off. A command should rather check the directory before the run, with
/// [`OutputDir::check`] and [`RUN_PRODUCTS`], and then call [`write_outputs_into`].
///
/// # Errors
/// [`ScenarioError::Input`] (key `--out`) for a target the policy refuses;
/// [`ScenarioError::Io`] when a file cannot be written.
pub fn write_outputs_with(
    scene: &Scene,
    result: &RunResult,
    failure: Option<&RunError>,
    dir: &Path,
    options: WriteOptions,
) -> Result<Vec<String>, ScenarioError> {
    let products = products_of(result);
    let target = OutputDir::check(dir, products, options.force, &[], &[])?;
    write_outputs_into(scene, result, failure, &target)
}

/// Writes the outputs of `result` into a checked directory: into a staging directory first,
/// published at the end ([`flexprr_outdir::Staging::publish`]). Returns the paths written.
///
/// # Errors
/// [`ScenarioError::Input`] (key `--out`) when a file would replace one flexprr did not
/// write; [`ScenarioError::Io`] when a file cannot be written.
pub fn write_outputs_into(
    scene: &Scene,
    result: &RunResult,
    failure: Option<&RunError>,
    target: &OutputDir,
) -> Result<Vec<String>, ScenarioError> {
    let staging = target.stage()?;
    let names = write_files(scene, result, failure, staging.path())?;
    staging.publish()?;
    Ok(names
        .iter()
        .map(|n| target.path().join(n).display().to_string())
        .collect())
}

/// The files a run that made `result` may write: the built-in ones and those of its
/// producers.
fn products_of(result: &RunResult) -> Products {
    let mut products = RUN_PRODUCTS.clone();
    for p in &result.producers {
        crate::producer::add_files(&mut products, p.as_ref());
    }
    products
}

/// Writes the files of a run into `dir`; returns their names.
fn write_files(
    scene: &Scene,
    result: &RunResult,
    failure: Option<&RunError>,
    dir: &Path,
) -> Result<Vec<String>, ScenarioError> {
    let mut written = Vec::new();
    let write = |written: &mut Vec<String>, name: String, bytes: &[u8]| {
        let path = dir.join(&name);
        std::fs::write(&path, bytes).map_err(io(&path))?;
        written.push(name);
        Ok::<(), ScenarioError>(())
    };
    for table in &result.tables {
        write(
            &mut written,
            format!("{}.csv", table.name),
            &csv_bytes(table, dir)?,
        )?;
    }
    if let Some(md) = table_one_markdown(result) {
        write(&mut written, "table1.md".into(), md.as_bytes())?;
        if let Some(h) = &result.frequencies {
            let mut csv = String::from("link,mode,nominal_hz,min_hz,t_min_s,max_hz,t_max_s\n");
            for r in &h.ranges {
                let _ = writeln!(
                    csv,
                    "{},{},{:.4},{:.4},{:.6},{:.4},{:.6}",
                    r.link + 1,
                    r.mode + 1,
                    r.nominal_hz.max(0.0),
                    r.min_hz.max(0.0),
                    r.t_min,
                    r.max_hz.max(0.0),
                    r.t_max
                );
            }
            write(&mut written, "table1.csv".into(), csv.as_bytes())?;
        }
    }
    if scene.file.output.plots {
        let mut figures: Vec<_> = (result.producers.iter())
            .flat_map(|p| p.figures(scene, result))
            .collect();
        figures.retain(|(_, f)| f.panels.iter().any(|p| !p.series.is_empty()));
        for (file, figure) in figures {
            let svg = figure.to_svg().map_err(|e| unwritable(dir, &file, e))?;
            write(&mut written, file, svg.as_bytes())?;
        }
    }
    for (name, text) in &result.documents {
        write(&mut written, name.clone(), text.as_bytes())?;
    }
    let summary = summary_json(scene, result, failure);
    let text = serde_json::to_string_pretty(&summary).unwrap_or_default();
    write(&mut written, "summary.json".into(), text.as_bytes())?;
    Ok(written)
}
