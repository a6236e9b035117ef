//! Study plots: result columns against a swept parameter, one line per value of another
//! parameter, drawn with the one plot module of `flexprr_run::plot`. Axis labels and units
//! come from the quantity columns and the scene-key table, legends read
//! `platform mass = 0.2 kg` (values with an SI prefix, `link thickness = 2 mm`), every case
//! is a marker, and failed cases are hollow red circles on the lower edge at their
//! parameter value, with a legend entry, instead of being dropped.

use std::collections::BTreeMap;
use std::path::Path;

use flexprr_run::plot::ticks::value_label;
use flexprr_run::plot::{Axis, Figure, Marker, Panel, Series, Style};

use crate::error::StudyError;
use crate::file::PlotConfig;
use crate::keys::key_words;
use crate::quantity::Column;
use crate::record::{CaseRecord, CaseStatus};
use crate::study::Study;

/// One line of one panel: its legend, the ok points sorted by x, and the parameter values of
/// the cases that failed.
struct Line {
    label: String,
    points: Vec<(f64, f64)>,
    failed: Vec<f64>,
}

/// Writes the study's `[[plot]]`s from the case records.
///
/// # Errors
/// [`StudyError::Directory`] if a plot cannot be drawn or written.
pub fn write_plots(
    study: &Study,
    out: &Path,
    records: &BTreeMap<usize, CaseRecord>,
) -> Result<(), StudyError> {
    let columns = study.quantity_column_specs();
    for plot in &study.plots {
        let (words, unit) = key_words(&plot.x);
        let mut figure = Figure::new(Axis::new(words, unit))
            .description(format!("flexprr study {}", study.name));
        if let Some(title) = &plot.title {
            figure = figure.title(title.as_str());
        }
        for y in &plot.y {
            let Some(c) = columns.iter().position(|c| &c.name == y) else {
                continue;
            };
            let lines = plot_lines(study, plot, c, records);
            // The legend once, on the top panel: lines and failed cases are drawn alike below.
            let legend = figure.panels.is_empty();
            figure = figure.panel(panel(&columns[c], &lines, legend));
        }
        let path = out.join(&plot.file);
        figure
            .write_svg(&path)
            .map_err(|message| StudyError::Directory {
                dir: out.display().to_string(),
                message,
            })?;
    }
    Ok(())
}

/// The panel of column `column`: a line with markers per series value, then the failed
/// cases of all lines as one series; with legend labels if `legend`.
fn panel(column: &Column, lines: &[Line], legend: bool) -> Panel {
    let mut panel = Panel::new(Axis::new(column.label.as_str(), column.unit));
    let mut failed = Vec::new();
    for (k, line) in lines.iter().enumerate() {
        let (x, y): (Vec<f64>, Vec<f64>) = line.points.iter().copied().unzip();
        let style = Style::nth(k).marker(Marker::CYCLE[k % Marker::CYCLE.len()]);
        let label = if !legend {
            ""
        } else if line.label.is_empty() && lines.len() == 1 {
            "cases"
        } else {
            line.label.as_str()
        };
        panel = panel.series(Series::new(label, &x, &y, style));
        failed.extend(line.failed.iter().copied());
    }
    if !failed.is_empty() {
        let n = failed.len();
        let label = if !legend {
            String::new()
        } else if n == 1 {
            "failed case".to_string()
        } else {
            format!("failed cases ({n})")
        };
        panel = panel.series(Series::failed(label, failed));
    }
    panel
}

/// The value of the parameter `key` in a record, if `key` is an axis.
fn parameter<'r>(study: &Study, record: &'r CaseRecord, key: &str) -> Option<&'r str> {
    let k = study.axes.iter().position(|a| a.key == key)?;
    record.parameters.get(k).map(String::as_str)
}

/// Legend entry for one value of a key: `platform mass = 0.2 kg`, `link thickness = 2 mm`,
/// `formulation = paper`.
fn legend(key: &str, value: &str) -> String {
    let (words, unit) = key_words(key);
    match value.parse::<f64>() {
        Ok(v) if v.is_finite() => format!("{words} = {}", value_label(v, unit)),
        _ => format!("{words} = {value}"),
    }
}

/// The lines of quantity column `c`: one per distinct value of the plot's `series` parameter
/// (in order of first appearance), or one line for the whole study without `series`.
fn plot_lines(
    study: &Study,
    plot: &PlotConfig,
    c: usize,
    records: &BTreeMap<usize, CaseRecord>,
) -> Vec<Line> {
    let mut lines: Vec<(String, Line)> = Vec::new();
    for r in records.values() {
        let Some(x) = parameter(study, r, &plot.x).and_then(|x| x.parse::<f64>().ok()) else {
            continue;
        };
        let value = plot
            .series
            .as_ref()
            .and_then(|s| parameter(study, r, s))
            .unwrap_or_default()
            .to_string();
        let index = match lines.iter().position(|(v, _)| *v == value) {
            Some(i) => i,
            None => {
                let label = match &plot.series {
                    Some(key) => legend(key, &value),
                    None => String::new(),
                };
                lines.push((
                    value,
                    Line {
                        label,
                        points: Vec::new(),
                        failed: Vec::new(),
                    },
                ));
                lines.len() - 1
            }
        };
        let line = &mut lines[index].1;
        if r.status == CaseStatus::Ok {
            // Empty optional cells (no buckling) are not points.
            if let Some(y) = r.quantities.get(c).and_then(|v| v.parse::<f64>().ok()) {
                line.points.push((x, y));
            }
        } else {
            line.failed.push(x);
        }
    }
    lines
        .into_iter()
        .map(|(_, mut line)| {
            line.points.sort_by(|a, b| a.0.total_cmp(&b.0));
            line
        })
        .collect()
}
