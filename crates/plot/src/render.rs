//! The SVG renderer of [`Figure`]: the panels' frames, the horizontal layout shared by
//! every panel, each panel's series in pixels and its legend, the vertical layout, then the
//! drawing. Axes are drawn by [`crate::axes`], legends by [`crate::legend`].

use std::fmt::Write as _;

use crate::axes::{
    Area, BELOW, Frame, X_TITLE, data_frame, draw_border, draw_clip_path, draw_ticks, draw_x_title,
    draw_y_title, y_title_width,
};
use crate::decimate::decimate;
use crate::legend::{Drawn, Entry, LEGEND_SAMPLE, LegendPlace, draw_legend, place_legend};
use crate::svg::{
    FONT_LABEL, FONT_LEGEND, FONT_TITLE, MARKER, WIDTH, close, color, marker, open, polyline, text,
    text_width, wrap,
};
use crate::{FAILED_COLOR, Figure, Panel, Placement, Series};

/// Height of a plot area (px).
const PLOT_HEIGHT: f64 = 170.0;
/// Buckets per pixel of plot width for decimation (M4 keeps four points a pixel column).
const BUCKETS_PER_PX: f64 = 1.0;
/// Height of the strip for failed cases (px).
const STRIP: f64 = 16.0;

/// The figure as SVG text (see [`Figure::to_svg`]).
pub(crate) fn render(figure: &Figure) -> Result<String, String> {
    let name = figure.title.as_deref().unwrap_or(&figure.x.label);
    check_shapes(figure, name)?;
    let (fx, frames) = frames(figure);
    let columns = Columns::of(&fx, &frames);
    let laid: Vec<Laid<'_>> = figure
        .panels
        .iter()
        .zip(frames)
        .map(|(panel, fy)| lay_out_panel(panel, fy, &fx, &columns))
        .collect();
    let rows = Rows::of(figure, &laid);

    let mut out = String::new();
    open(
        &mut out,
        WIDTH,
        rows.height,
        name,
        figure.description.as_deref(),
    );
    for (k, line) in rows.title.iter().enumerate() {
        let y = 4.0 + FONT_TITLE + 1.25 * FONT_TITLE * k as f64;
        text(&mut out, (WIDTH / 2.0, y), FONT_TITLE, "middle", line);
    }
    for (k, (l, top)) in laid.iter().zip(&rows.tops).enumerate() {
        draw_panel(&mut out, k, l, &figure.panels[k], &fx, &columns, *top);
    }
    let bottom = Area {
        top: 0.0,
        ..columns.area(0.0)
    };
    draw_x_title(&mut out, &fx.label, bottom, rows.height - 6.0);
    close(&mut out);
    Ok(out)
}

/// A figure has panels, and every series as many x values as y values.
fn check_shapes(figure: &Figure, name: &str) -> Result<(), String> {
    if figure.panels.is_empty() {
        return Err(format!("figure \"{name}\" has no panel"));
    }
    for (k, p) in figure.panels.iter().enumerate() {
        for s in &p.series {
            if s.x.len() != s.y.len() {
                return Err(format!(
                    "figure \"{name}\", panel {} ({}), series \"{}\": {} x values but {} y values",
                    k + 1,
                    p.y.label,
                    s.label,
                    s.x.len(),
                    s.y.len()
                ));
            }
        }
    }
    Ok(())
}

/// The shared x frame and each panel's y frame. Time series run edge to edge; points with
/// markers get room; a panel with failed cases keeps a strip below its data.
fn frames(figure: &Figure) -> (Frame, Vec<Frame>) {
    let markers = figure
        .panels
        .iter()
        .flat_map(|p| &p.series)
        .any(|s| s.style.marker.is_some());
    let xs: Vec<f64> = figure
        .panels
        .iter()
        .flat_map(|p| p.series.iter().flat_map(|s| s.x.iter().copied()))
        .collect();
    let pad = if markers { 0.05 } else { 0.0 };
    let fx = data_frame(&figure.x, &xs, pad, (0.0, PLOT_HEIGHT), 6);
    let frames = figure
        .panels
        .iter()
        .map(|p| {
            let ys: Vec<f64> = p
                .series
                .iter()
                .filter(|s| s.placement == Placement::Data)
                .flat_map(|s| s.y.iter().copied())
                .collect();
            let edge = p
                .series
                .iter()
                .any(|s| s.placement == Placement::LowerEdge && !s.x.is_empty());
            let strip = if edge { STRIP } else { 0.0 };
            data_frame(&p.y, &ys, 0.06, (strip, PLOT_HEIGHT), 5)
        })
        .collect();
    (fx, frames)
}

/// The horizontal layout, common to all panels so that the plot areas align: the y titles
/// (wrapped to the plot height) and the plot area's left edge and width.
struct Columns {
    /// Each panel's y title in lines.
    y_titles: Vec<Vec<String>>,
    /// Lines of the longest y title (the column they share).
    title_lines: usize,
    /// Left edge of the plot areas (px).
    left: f64,
    /// Width of the plot areas (px).
    plot_w: f64,
}

impl Columns {
    /// Room for the widest y tick label and the longest y title on the left, and for half
    /// the last x tick label on the right.
    fn of(fx: &Frame, frames: &[Frame]) -> Self {
        let tick_width = frames.iter().map(Frame::tick_width).fold(0.0, f64::max);
        let y_titles: Vec<Vec<String>> = frames
            .iter()
            .map(|f| wrap(&f.label, PLOT_HEIGHT - 6.0, FONT_LABEL))
            .collect();
        let title_lines = y_titles.iter().map(Vec::len).max().unwrap_or(1).max(1);
        let left = (4.0 + y_title_width(title_lines) + 6.0 + tick_width + 6.0).ceil();
        let last_x_tick = fx
            .ticks
            .last()
            .map_or(0.0, |t| text_width(&t.1, crate::svg::FONT_TICK));
        let right = (0.5 * last_x_tick + 4.0).max(12.0).ceil();
        Self {
            y_titles,
            title_lines,
            left,
            plot_w: WIDTH - left - right,
        }
    }

    /// The plot area of a panel whose top is at `top` (px).
    fn area(&self, top: f64) -> Area {
        Area {
            left: self.left,
            top,
            width: self.plot_w,
            height: PLOT_HEIGHT,
        }
    }
}

/// One laid-out panel: its frame, the series in pixels and the legend place.
struct Laid<'a> {
    fy: Frame,
    /// Pixel polylines (runs without gaps) and marker points per series, from the panel's
    /// top.
    pixels: Vec<Drawn>,
    /// Failed-case circles standing for more than one case, and how many.
    counts: Vec<((f64, f64), usize)>,
    entries: Vec<Entry<'a>>,
    legend: LegendPlace,
}

/// A panel in pixels (from its top): each series decimated to the plot width and cut at
/// its gaps, failed cases one circle per x in the strip, and the legend placed where no
/// data is.
fn lay_out_panel<'a>(panel: &'a Panel, fy: Frame, fx: &Frame, columns: &Columns) -> Laid<'a> {
    let area = columns.area(0.0);
    let mut edge: Vec<((f64, f64), usize)> = Vec::new();
    let pixels: Vec<Drawn> = panel
        .series
        .iter()
        .map(|s| series_pixels(s, fx, &fy, area, &mut edge))
        .collect();
    let entries: Vec<Entry<'_>> = panel
        .series
        .iter()
        .filter(|s| !s.label.is_empty())
        .map(|s| Entry {
            label: &s.label,
            style: s.style,
            width: LEGEND_SAMPLE + 6.0 + text_width(&s.label, FONT_LEGEND),
        })
        .collect();
    let legend = place_legend(&entries, &pixels, area.left, (area.width, area.height));
    Laid {
        fy,
        pixels,
        counts: edge.into_iter().filter(|e| e.1 > 1).collect(),
        entries,
        legend,
    }
}

/// The series `s` in pixels of `area`: its runs without gaps (none when it has no line) and
/// its marker points. A series without markers is decimated to [`BUCKETS_PER_PX`] buckets
/// a pixel column first. Failed cases go to the strip along the lower edge, one circle per
/// x, counted in `edge`.
fn series_pixels(
    s: &Series,
    fx: &Frame,
    fy: &Frame,
    area: Area,
    edge: &mut Vec<((f64, f64), usize)>,
) -> Drawn {
    let buckets = (BUCKETS_PER_PX * area.width) as usize;
    // Buckets a pixel wide on the axis as drawn: in log10(x) on a log axis.
    let (dx, dy) = if s.style.marker.is_none() && fx.log {
        let lx: Vec<f64> =
            s.x.iter()
                .map(|&x| fx.coordinate(x).unwrap_or(f64::NAN))
                .collect();
        let (lx, dy) = decimate(&lx, &s.y, buckets);
        (lx.into_iter().map(|c| 10f64.powf(c)).collect(), dy)
    } else if s.style.marker.is_none() {
        decimate(&s.x, &s.y, buckets)
    } else {
        (s.x.clone(), s.y.clone())
    };
    let px = |c: f64| area.left + (c - fx.lo) / (fx.hi - fx.lo) * area.width;
    let py = |c: f64| area.top + area.height - (c - fy.lo) / (fy.hi - fy.lo) * area.height;
    let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
    let mut points = Vec::new();
    for (&x, &y) in dx.iter().zip(&dy) {
        let c = match s.placement {
            Placement::Data => fx.coordinate(x).zip(fy.coordinate(y)),
            Placement::LowerEdge => fx.coordinate(x).map(|cx| (cx, f64::NAN)),
        };
        match c {
            Some((x, _)) if s.placement == Placement::LowerEdge => {
                // One circle per x, counted.
                let p = (px(x), PLOT_HEIGHT - 0.5 * STRIP);
                match edge.iter_mut().find(|e| (e.0.0 - p.0).abs() < 1.0) {
                    Some(e) => e.1 += 1,
                    None => {
                        edge.push((p, 1));
                        points.push(p);
                    }
                }
            }
            Some((x, y)) => {
                let p = (px(x), py(y));
                if let Some(r) = runs.last_mut() {
                    r.push(p);
                }
                if s.style.marker.is_some() {
                    points.push(p);
                }
            }
            None => {
                if runs.last().is_some_and(|r| !r.is_empty()) {
                    runs.push(Vec::new());
                }
            }
        }
    }
    if !s.style.line {
        runs.clear();
    }
    runs.retain(|r| !r.is_empty());
    (runs, points)
}

/// The vertical layout: the title's lines, each panel's top (below its legend when the
/// legend is above it) and the figure's height.
struct Rows {
    title: Vec<String>,
    tops: Vec<f64>,
    height: f64,
}

impl Rows {
    fn of(figure: &Figure, laid: &[Laid<'_>]) -> Self {
        let title = figure
            .title
            .as_deref()
            .map_or_else(Vec::new, |t| wrap(t, WIDTH - 16.0, FONT_TITLE));
        let title_h = if title.is_empty() {
            4.0
        } else {
            8.0 + 1.25 * FONT_TITLE * title.len() as f64
        };
        let mut tops = Vec::new();
        let mut y = title_h;
        for l in laid {
            if let LegendPlace::Above { height, .. } = l.legend {
                y += height;
            }
            y += 6.0;
            tops.push(y);
            y += PLOT_HEIGHT + BELOW;
        }
        Self {
            title,
            tops,
            height: (y + X_TITLE).ceil(),
        }
    }
}

/// Draws panel `k` at `top`: clip path, ticks and grid, y title, the series clipped to the
/// plot area, the counts of failed cases, the border and the legend.
fn draw_panel(
    out: &mut String,
    k: usize,
    l: &Laid<'_>,
    panel: &Panel,
    fx: &Frame,
    columns: &Columns,
    top: f64,
) {
    let area = columns.area(top);
    draw_clip_path(out, &format!("p{k}"), area);
    draw_ticks(out, fx, &l.fy, area);
    draw_y_title(out, &columns.y_titles[k], columns.title_lines, 0.0, area);
    let _ = writeln!(out, "<g clip-path=\"url(#p{k})\">");
    for ((runs, points), s) in l.pixels.iter().zip(&panel.series) {
        for run in runs {
            let moved: Vec<(f64, f64)> = run.iter().map(|&(x, y)| (x, y + top)).collect();
            polyline(out, &moved, s.style);
        }
        if let Some(m) = s.style.marker {
            for &(x, y) in points {
                marker(out, m, s.style.color, (x, y + top));
            }
        }
    }
    for ((x, y), n) in &l.counts {
        let _ = writeln!(
            out,
            "<text x=\"{:.1}\" y=\"{:.1}\" font-size=\"10\" fill=\"{}\">×{n}</text>",
            x + MARKER + 2.0,
            y + top + 3.5,
            color(FAILED_COLOR)
        );
    }
    let _ = writeln!(out, "</g>");
    draw_border(out, area);
    draw_legend(out, &l.legend, &l.entries, area.left, top);
}
