//! The report of a work-precision measurement: `work_precision.csv`, the Markdown tables
//! (at equal error, cost against fidelity, every point) and the diagram.

use std::fmt::Write as _;
use std::path::Path;

use flexprr_scene::ScenarioError;

use super::WorkPrecisionError;

use super::{PACKAGE, WorkPrecisionRow};

/// The rows as CSV (header included).
///
/// # Errors
/// [`WorkPrecisionError::Write`] if serialisation fails.
pub fn csv_text(rows: &[WorkPrecisionRow]) -> Result<String, WorkPrecisionError> {
    let failed = |e: &dyn std::fmt::Display| WorkPrecisionError::Write {
        path: "work-precision CSV".to_string(),
        message: e.to_string(),
    };
    let mut w = csv::Writer::from_writer(Vec::new());
    for row in rows {
        w.serialize(row).map_err(|e| failed(&e))?;
    }
    if rows.is_empty() {
        return Ok(String::new());
    }
    let bytes = w.into_inner().map_err(|e| failed(&e))?;
    String::from_utf8(bytes).map_err(|e| failed(&e))
}

/// Reads rows (e.g. a peers file) in the [`WorkPrecisionRow`] format: at least one row,
/// each with a package and a method, a positive finite `rtol`, finite non-negative `atol`,
/// times and errors, and at least one timed run.
///
/// # Errors
/// [`ScenarioError::Io`] if unreadable, [`ScenarioError::Input`] naming the file and line
/// if the file holds no row or a row is malformed or out of range.
pub fn read_csv(path: &Path) -> Result<Vec<WorkPrecisionRow>, ScenarioError> {
    let text = std::fs::read_to_string(path).map_err(|source| ScenarioError::Io {
        path: path.display().to_string(),
        source,
    })?;
    let bad = |message: String| ScenarioError::Input {
        location: None,
        key: path.display().to_string(),
        message,
    };
    let mut rows = Vec::new();
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    for row in reader.deserialize::<WorkPrecisionRow>() {
        let line = rows.len() + 2;
        let row = row.map_err(|e| bad(format!("line {line}: {e}")))?;
        check_row(&row).map_err(|m| {
            bad(format!(
                "line {line} ({} {} at rtol {}): {m}",
                row.package, row.method, row.rtol
            ))
        })?;
        rows.push(row);
    }
    if rows.is_empty() {
        return Err(bad(
            "holds no rows: expected a header and at least one row in the work_precision.csv \
             format (package,method,rtol,atol,time_median_s,...)"
                .into(),
        ));
    }
    Ok(rows)
}

/// The range checks of one row read from a file.
fn check_row(row: &WorkPrecisionRow) -> Result<(), String> {
    if row.package.trim().is_empty() || row.method.trim().is_empty() {
        return Err("package and method must not be empty".into());
    }
    if !(row.rtol.is_finite() && row.rtol > 0.0) {
        return Err(format!(
            "rtol = {} is not a positive finite number",
            row.rtol
        ));
    }
    for (name, v) in [
        ("atol", row.atol),
        ("time_median_s", row.time_median_s),
        ("time_min_s", row.time_min_s),
        ("end_error", row.end_error),
        ("max_error", row.max_error),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(format!("{name} = {v} is not a finite non-negative number"));
        }
    }
    if row.repeats == 0 {
        return Err("repeats = 0: a row needs at least one timed run".into());
    }
    Ok(())
}

/// The series of the diagram: `(package, series label)` in order of first appearance (the
/// label is [`WorkPrecisionRow::series_label`]: the method, after the model if any).
pub fn series(rows: &[WorkPrecisionRow]) -> Vec<(String, String)> {
    let mut out: Vec<(String, String)> = Vec::new();
    for row in rows {
        let label = row.series_label();
        if !out.iter().any(|(p, m)| *p == row.package && *m == label) {
            out.push((row.package.clone(), label));
        }
    }
    out
}

/// Wall time a series (`method`: its [`WorkPrecisionRow::series_label`]) needs for a
/// maximum error of `target`, interpolated linearly in
/// `log(time)` against `log(error)` between the two ladder points (ordered loose to tight)
/// where the error first falls to `target`. If the loosest point is already at or below
/// the target its time is returned (an upper bound). `None` if the error never gets there.
pub fn time_at_error(
    rows: &[WorkPrecisionRow],
    package: &str,
    method: &str,
    target: f64,
) -> Option<f64> {
    let mut points: Vec<&WorkPrecisionRow> = rows
        .iter()
        .filter(|r| r.package == package && r.series_label() == method)
        .collect();
    points.sort_by(|a, b| b.rtol.total_cmp(&a.rtol));
    let first = points.first()?;
    if first.max_error <= target {
        return Some(first.time_median_s);
    }
    for pair in points.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        if a.max_error > target && b.max_error <= target {
            if b.max_error <= 0.0 || a.time_median_s <= 0.0 || b.time_median_s <= 0.0 {
                return Some(b.time_median_s);
            }
            let s = (target.ln() - a.max_error.ln()) / (b.max_error.ln() - a.max_error.ln());
            return Some(
                (a.time_median_s.ln() + s * (b.time_median_s.ln() - a.time_median_s.ln())).exp(),
            );
        }
    }
    None
}

/// A Markdown table: wall time of each series at maximum error `target`, and how many times
/// faster the best flexprr method is than each series.
pub fn markdown_at_error(rows: &[WorkPrecisionRow], target: f64) -> String {
    let all = series(rows);
    let times: Vec<Option<f64>> = all
        .iter()
        .map(|(p, m)| time_at_error(rows, p, m, target))
        .collect();
    let best = all
        .iter()
        .zip(&times)
        .filter(|((p, _), _)| p == PACKAGE)
        .filter_map(|((_, m), t)| t.map(|t| (m.clone(), t)))
        .min_by(|a, b| a.1.total_cmp(&b.1));
    let mut md = String::new();
    // Without a flexprr series that reaches the target there is nothing to compare with.
    let faster = best.as_ref().map_or("faster by".to_string(), |(m, _)| {
        format!("flexprr {m} is faster by")
    });
    let _ = writeln!(
        md,
        "| package | method | time at max error {target:.0e} (ms) | {faster} |"
    );
    let _ = writeln!(md, "|---|---|---:|---:|");
    for ((p, m), t) in all.iter().zip(&times) {
        let time = t.map_or("not reached".to_string(), |t| format!("{:.3}", 1e3 * t));
        let ratio = match (t, &best) {
            (Some(t), Some((_, b))) if *b > 0.0 => format!("{:.1}x", t / b),
            _ => "-".to_string(),
        };
        let _ = writeln!(md, "| {p} | {m} | {time} | {ratio} |");
    }
    md
}

/// A Markdown table of cost against fidelity, one line per series: the cheapest point (its
/// time and maximum error) and the most accurate point (its maximum error and time). With
/// models side by side, the most accurate error of a model is its model error against the
/// reference model once the tolerance no longer matters.
pub fn markdown_models(rows: &[WorkPrecisionRow]) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "| package | series | cheapest: time (ms) | its max error | most accurate: max error | its time (ms) | its rtol |"
    );
    let _ = writeln!(md, "|---|---|---:|---:|---:|---:|---:|");
    for (package, label) in series(rows) {
        let points: Vec<&WorkPrecisionRow> = rows
            .iter()
            .filter(|r| r.package == package && r.series_label() == label)
            .collect();
        let cheapest = points
            .iter()
            .min_by(|a, b| a.time_median_s.total_cmp(&b.time_median_s));
        let best = points
            .iter()
            .min_by(|a, b| a.max_error.total_cmp(&b.max_error));
        if let (Some(c), Some(b)) = (cheapest, best) {
            let _ = writeln!(
                md,
                "| {package} | {label} | {:.3} | {:.2e} | {:.2e} | {:.3} | {:.0e} |",
                1e3 * c.time_median_s,
                c.max_error,
                b.max_error,
                1e3 * b.time_median_s,
                b.rtol
            );
        }
    }
    md
}

/// A Markdown table of all rows.
pub fn markdown_rows(rows: &[WorkPrecisionRow]) -> String {
    let opt = |v: Option<usize>| v.map_or("-".to_string(), |v| v.to_string());
    let mut md = String::new();
    let _ = writeln!(
        md,
        "| package | method | rtol | time (ms) | steps | rejected | rhs evals | Jacobians | end error | max error |"
    );
    let _ = writeln!(md, "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        let _ = writeln!(
            md,
            "| {} | {} | {:.0e} | {:.3} | {} | {} | {} | {} | {:.2e} | {:.2e} |",
            r.package,
            r.series_label(),
            r.rtol,
            1e3 * r.time_median_s,
            opt(r.accepted_steps),
            opt(r.rejected_steps),
            opt(r.rhs_evaluations),
            opt(r.jacobian_evaluations),
            r.end_error,
            r.max_error
        );
    }
    md
}

/// Writes the work-precision diagram: maximum relative error against median wall time,
/// log-log, one line with markers per `(package, method)`; flexprr solid, peers dashed.
/// Points with a time or error that is not positive cannot be drawn on log axes and are
/// left out; the diagram is an error if no point is left.
///
/// # Errors
/// [`WorkPrecisionError::NothingToDraw`] if there is nothing to draw,
/// [`WorkPrecisionError::Write`] if the file cannot be written.
pub fn write_svg(
    rows: &[WorkPrecisionRow],
    path: &Path,
    title: &str,
) -> Result<(), WorkPrecisionError> {
    use flexprr_run::plot::{Axis, Dash, Figure, Marker, Panel, Series, Style};
    let positive = |v: &f64| v.is_finite() && *v > 0.0;
    let mut panel = Panel::new(Axis::log("max relative error", ""));
    for (k, (package, method)) in series(rows).iter().enumerate() {
        let mut line: Vec<&WorkPrecisionRow> = rows
            .iter()
            .filter(|r| &r.package == package && &r.series_label() == method)
            .filter(|r| positive(&r.time_median_s) && positive(&r.max_error))
            .collect();
        line.sort_by(|a, b| b.rtol.total_cmp(&a.rtol));
        let time: Vec<f64> = line.iter().map(|r| r.time_median_s).collect();
        let error: Vec<f64> = line.iter().map(|r| r.max_error).collect();
        let mut style = Style::nth(k).marker(Marker::CYCLE[k % Marker::CYCLE.len()]);
        if package != PACKAGE {
            style = style.dash(Dash::Dashed);
        }
        panel = panel.series(Series::new(
            format!("{package} {method}"),
            &time,
            &error,
            style,
        ));
    }
    if panel.series.iter().all(|s| s.x.is_empty()) {
        return Err(WorkPrecisionError::NothingToDraw {
            path: path.display().to_string(),
        });
    }
    Figure::new(Axis::log("median wall time", "s"))
        .title(title)
        .description("flexprr work-precision diagram")
        .panel(panel)
        .write_svg(path)
        .map_err(|message| WorkPrecisionError::Write {
            path: path.display().to_string(),
            message,
        })
}
