//! Study plots: result columns against a swept parameter, one line per value of another
//! parameter. Axis labels and units come from the quantity columns and the scene-key table,
//! legends read `platform mass = 0.2 kg`, every case is a marker, and failed cases are
//! drawn as crosses on the lower edge at their parameter value instead of being dropped.

use std::collections::BTreeMap;
use std::path::Path;

use plotters::prelude::*;

use crate::error::StudyError;
use crate::file::PlotConfig;
use crate::keys::{key_label, key_value_label};
use crate::quantity::Column;
use crate::record::{CaseRecord, CaseStatus};
use crate::study::Study;

const COLORS: [RGBColor; 7] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
    RGBColor(23, 190, 207),
    RGBColor(140, 86, 75),
];

/// Point markers, one per line in turn, so that lines drawn on top of each other stay
/// distinguishable.
#[derive(Debug, Clone, Copy)]
enum Marker {
    Disc,
    Ring,
    Triangle,
}

impl Marker {
    fn of(line: usize) -> Self {
        [Marker::Disc, Marker::Ring, Marker::Triangle][line % 3]
    }

    /// The marker at `p`, as one element type for every shape.
    fn at<C: Copy + 'static, DB: DrawingBackend>(
        self,
        p: C,
        color: RGBColor,
    ) -> DynElement<'static, DB, C> {
        match self {
            Marker::Disc => Circle::new(p, 3, color.filled()).into_dyn(),
            Marker::Ring => Circle::new(p, 5, color.stroke_width(2)).into_dyn(),
            Marker::Triangle => TriangleMarker::new(p, 5, color.filled()).into_dyn(),
        }
    }
}

const WIDTH: u32 = 1100;
const LEGEND_WIDTH: u32 = 290;
const PANEL_HEIGHT: u32 = 320;

/// One line of one panel: its legend, the ok points sorted by x, and the parameter values of
/// the cases that failed.
struct Line {
    label: String,
    points: Vec<(f64, f64)>,
    failed: Vec<f64>,
}

/// One panel: the column drawn and its lines.
struct PanelData<'a> {
    column: &'a Column,
    lines: Vec<Line>,
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
        let panels: Vec<PanelData<'_>> = plot
            .y
            .iter()
            .filter_map(|y| {
                let c = columns.iter().position(|c| &c.name == y)?;
                Some(PanelData {
                    column: &columns[c],
                    lines: plot_lines(study, plot, c, records),
                })
            })
            .collect();
        let title = plot.title.clone().unwrap_or_else(|| study.name.clone());
        let path = out.join(&plot.file);
        draw(&path, &title, &key_label(&plot.x), &panels).map_err(|message| {
            StudyError::Directory {
                dir: out.display().to_string(),
                message,
            }
        })?;
    }
    Ok(())
}

/// The value of the parameter `key` in a record, if `key` is an axis.
fn parameter<'r>(study: &Study, record: &'r CaseRecord, key: &str) -> Option<&'r str> {
    let k = study.axes.iter().position(|a| a.key == key)?;
    record.parameters.get(k).map(String::as_str)
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
                    Some(key) => key_value_label(key, &value),
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

/// `[lo, hi]` of the finite values with 5 % padding; `[-1, 1]` without values.
fn bounds(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let pad = if hi > lo {
        0.05 * (hi - lo)
    } else {
        lo.abs().max(1e-12) * 0.1
    };
    (lo - pad, hi + pad)
}

/// A tick label with at most four significant digits (`0.0015`, `120`, `1e-5`); a value
/// within rounding of zero on an axis spanning `span` is written `0`.
fn tick(v: f64, span: f64) -> String {
    if v.abs() <= 1e-9 * span.abs() || v.abs() < 1e-300 {
        return "0".into();
    }
    let rounded: f64 = format!("{v:.3e}").parse().unwrap_or(v);
    let plain = format!("{rounded}");
    if plain.len() > 9 {
        format!("{rounded:e}")
    } else {
        plain
    }
}

fn draw(path: &Path, title: &str, x_label: &str, panels: &[PanelData<'_>]) -> Result<(), String> {
    let height = 70 + PANEL_HEIGHT * panels.len().max(1) as u32;
    let root = SVGBackend::new(path, (WIDTH, height)).into_drawing_area();
    let err = |e: &dyn std::fmt::Display| format!("plot {}: {e}", path.display());
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let root = root
        .titled(title, ("sans-serif", 22))
        .map_err(|e| err(&e))?;
    let areas = root.split_evenly((panels.len().max(1), 1));
    for (panel, area) in panels.iter().zip(areas.iter()) {
        let (chart_area, legend_area) = area.split_horizontally(WIDTH - LEGEND_WIDTH);
        let xs = panel
            .lines
            .iter()
            .flat_map(|l| l.points.iter().map(|p| p.0).chain(l.failed.iter().copied()));
        let (x0, x1) = bounds(xs);
        let ys = panel
            .lines
            .iter()
            .flat_map(|l| l.points.iter().map(|p| p.1));
        let (y0, y1) = bounds(ys);
        let mut chart = ChartBuilder::on(&chart_area)
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(85)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_desc(x_label)
            .y_desc(panel.column.axis_label())
            .x_label_formatter(&|v| tick(*v, x1 - x0))
            .y_label_formatter(&|v| tick(*v, y1 - y0))
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .draw()
            .map_err(|e| err(&e))?;
        // Failed cases: crosses on the lower edge, stacked where several lines fail at the
        // same parameter value.
        let mut crosses: Vec<(f64, f64, RGBColor)> = Vec::new();
        for (k, line) in panel.lines.iter().enumerate() {
            let color = COLORS[k % COLORS.len()];
            for &x in &line.failed {
                let below = crosses.iter().filter(|c| c.0.total_cmp(&x).is_eq()).count();
                let y = y0 + (0.025 + 0.04 * below as f64) * (y1 - y0);
                crosses.push((x, y, color));
            }
            chart
                .draw_series(LineSeries::new(
                    line.points.iter().copied(),
                    color.stroke_width(2),
                ))
                .map_err(|e| err(&e))?;
            let marker = Marker::of(k);
            chart
                .draw_series(line.points.iter().map(|&p| marker.at(p, color)))
                .map_err(|e| err(&e))?;
        }
        chart
            .draw_series(
                crosses
                    .iter()
                    .map(|&(x, y, color)| Cross::new((x, y), 5, color.stroke_width(2))),
            )
            .map_err(|e| err(&e))?;
        draw_legend(&legend_area, &panel.lines).map_err(|e| err(&e))?;
    }
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

/// The legend beside a panel: one entry per line (its marker and label), then the failed
/// cases' cross and how many there are.
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    lines: &[Line],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let font = ("sans-serif", 14).into_font();
    let mut y = 30;
    for (k, line) in lines.iter().enumerate() {
        let color = COLORS[k % COLORS.len()];
        let label = if line.label.is_empty() {
            "cases"
        } else {
            line.label.as_str()
        };
        area.draw(&PathElement::new(
            vec![(8, y), (36, y)],
            color.stroke_width(2),
        ))?;
        area.draw(&Marker::of(k).at((22, y), color))?;
        area.draw(&Text::new(label.to_string(), (44, y - 8), font.clone()))?;
        y += 22;
    }
    let failed: usize = lines.iter().map(|l| l.failed.len()).sum();
    if failed > 0 {
        y += 6;
        area.draw(&Cross::new((22, y), 5, BLACK.stroke_width(2)))?;
        area.draw(&Text::new(
            format!("failed case ({failed}), drawn"),
            (44, y - 8),
            font.clone(),
        ))?;
        area.draw(&Text::new(
            "on the lower edge at its x".to_string(),
            (44, y + 10),
            font,
        ))?;
    }
    Ok(())
}
