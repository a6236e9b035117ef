//! Axes: the scaled frame of an axis (SI prefix, range, 1-2-5 or power-of-ten ticks) and
//! how axes are drawn (grid, tick marks, tick labels, axis titles, the border). The
//! [`crate::Figure`] renderer draws its panels' axes with these functions, and [`Axes`]
//! offers the same axes to a custom drawing (the viewer's machine and snapshot figures):
//! it maps data (SI units) to pixels, with equal scales on request, and draws the axes in
//! the house style around it.
//!
//! ```
//! use flexprr_plot::Axis;
//! use flexprr_plot::axes::{Area, Axes};
//! // A 0.8 m x 0.6 m box drawn with equal scales in a 400 x 300 px region.
//! let axes = Axes::fit(
//!     Area { left: 0.0, top: 0.0, width: 400.0, height: 300.0 },
//!     (&Axis::new("x", "m"), (-0.4, 0.4)),
//!     (&Axis::new("y", "m"), (-0.3, 0.3)),
//!     true,
//! );
//! let (sx, sy) = axes.px_per_unit();
//! assert!((sx - sy).abs() < 1e-9 * sx);
//! let mut svg = String::new();
//! axes.draw(&mut svg);
//! assert!(svg.contains("x (mm)") && svg.contains("y (mm)"));
//! ```

use std::fmt::Write as _;

use crate::svg::{FONT_LABEL, FONT_TICK, axis_title, text, text_width, wrap};
use crate::ticks::{Scaled, linear_ticks, log_ticks, power_label, scale_for, tick_label};
use crate::{Axis, Scale};

/// An axis after scaling: the shown unit and factor, the range and ticks (in shown units,
/// or log10 of the values on a log axis).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Frame {
    pub(crate) factor: f64,
    pub(crate) label: String,
    pub(crate) log: bool,
    pub(crate) lo: f64,
    pub(crate) hi: f64,
    /// (position, label) of the major ticks.
    pub(crate) ticks: Vec<(f64, String)>,
    /// Positions of the minor ticks.
    pub(crate) minor: Vec<f64>,
}

impl Frame {
    /// The value `v` (SI) as an axis coordinate (shown units, or log10), if drawable.
    pub(crate) fn coordinate(&self, v: f64) -> Option<f64> {
        let c = if self.log {
            if v > 0.0 { v.log10() } else { f64::NAN }
        } else {
            v * self.factor
        };
        c.is_finite().then_some(c)
    }

    /// An empty frame of `axis` shown as `scaled`.
    fn new(axis: &Axis, scaled: Scaled) -> Self {
        let log = axis.scale == Scale::Log;
        let (factor, unit) = if log {
            (1.0, axis.unit.clone())
        } else {
            (scaled.factor, scaled.unit)
        };
        Self {
            factor,
            label: axis_title(&axis.label, &unit),
            log,
            lo: 0.0,
            hi: 0.0,
            ticks: Vec::new(),
            minor: Vec::new(),
        }
    }

    /// Sets the range `[lo, hi]` (coordinates) and the ticks: powers of ten (and minor
    /// ticks) on a log axis, about `target` multiples of a 1-2-5 step from `data_lo` on a
    /// linear one; none below `data_lo` (the strip of failed cases lies below it).
    fn set_range(&mut self, lo: f64, hi: f64, data_lo: f64, target: usize) {
        self.lo = lo;
        self.hi = hi;
        if self.log {
            let (major, minor) = log_ticks(10f64.powf(lo), 10f64.powf(hi));
            self.ticks = major
                .into_iter()
                .map(|e| (f64::from(e), power_label(e)))
                .collect();
            self.minor = minor.into_iter().map(f64::log10).collect();
        } else {
            let (ticks, step) = linear_ticks(data_lo, hi, target);
            self.ticks = ticks
                .into_iter()
                .map(|v| (v, tick_label(v, step)))
                .collect();
        }
        self.ticks.retain(|t| t.0 >= data_lo - 1e-9 * (hi - lo));
        self.minor.retain(|&t| t >= data_lo);
    }

    /// Widest tick label (px).
    pub(crate) fn tick_width(&self) -> f64 {
        self.ticks
            .iter()
            .map(|t| text_width(&t.1, FONT_TICK))
            .fold(0.0, f64::max)
    }

    /// Width of the last tick label (px), which overhangs the plot area's right edge.
    fn last_tick_width(&self) -> f64 {
        self.ticks
            .last()
            .map_or(0.0, |t| text_width(&t.1, FONT_TICK))
    }
}

/// The frame of a data axis of a [`crate::Figure`] panel over the values `values` (SI),
/// with `pad` of the span added on each side, `strip` px of the `height` px plot area kept
/// free below the data (for failed cases), and about `target` ticks. The SI prefix is
/// chosen from the largest magnitude shown.
pub(crate) fn data_frame(
    axis: &Axis,
    values: &[f64],
    pad: f64,
    (strip, height): (f64, f64),
    target: usize,
) -> Frame {
    let max_abs = values
        .iter()
        .filter(|v| v.is_finite())
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    let mut f = Frame::new(axis, scale_for(max_abs, &axis.unit));
    let log = f.log;
    let coords: Vec<f64> = values.iter().filter_map(|&v| f.coordinate(v)).collect();
    let (mut lo, mut hi) = coords
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        (lo, hi) = if log { (0.0, 1.0) } else { (-1.0, 1.0) };
    }
    if hi - lo <= 1e-12 * lo.abs().max(hi.abs()) {
        let half = if log {
            0.5
        } else if lo.abs() > 0.0 {
            0.1 * lo.abs()
        } else {
            1.0
        };
        (lo, hi) = (lo - half, hi + half);
    } else {
        let p = pad * (hi - lo);
        (lo, hi) = (lo - p, hi + p);
    }
    let data_lo = lo;
    if strip > 0.0 {
        lo -= (hi - lo) * strip / (height - strip);
    }
    f.set_range(lo, hi, data_lo, target);
    f
}

/// A rectangle of the drawing in pixels (y down).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Area {
    /// Left edge (px).
    pub left: f64,
    /// Top edge (px).
    pub top: f64,
    /// Width (px).
    pub width: f64,
    /// Height (px).
    pub height: f64,
}

impl Area {
    /// The bottom edge (px).
    pub fn bottom(&self) -> f64 {
        self.top + self.height
    }
}

/// Space between the plot area and its tick labels, and around the axis titles (px).
const GAP: f64 = 6.0;
/// Height of the x tick labels below a plot area (px).
pub(crate) const BELOW: f64 = 4.0 + FONT_TICK + 4.0;
/// Height of the x axis title (px).
pub(crate) const X_TITLE: f64 = FONT_LABEL + 8.0;

/// The x pixel of coordinate `c` of frame `f` over `area`.
fn x_px(f: &Frame, area: Area, c: f64) -> f64 {
    area.left + (c - f.lo) / (f.hi - f.lo) * area.width
}

/// The y pixel of coordinate `c` of frame `f` over `area` (y up).
fn y_px(f: &Frame, area: Area, c: f64) -> f64 {
    area.top + area.height - (c - f.lo) / (f.hi - f.lo) * area.height
}

/// The tick labels (x below, y left), the light grid and the tick marks (inward, on both
/// sides) of the frames `fx`, `fy` around `area`.
pub(crate) fn draw_ticks(out: &mut String, fx: &Frame, fy: &Frame, area: Area) {
    let (left, top, bottom) = (area.left, area.top, area.bottom());
    let right = left + area.width;
    let mut grid = String::new();
    let mut marks = String::new();
    for (c, label) in &fx.ticks {
        let x = x_px(fx, area, *c);
        let _ = write!(grid, "M{x:.1} {top:.1}V{bottom:.1}");
        let _ = write!(marks, "M{x:.1} {bottom:.1}v-4M{x:.1} {top:.1}v4");
        text(
            out,
            (x, bottom + 4.0 + FONT_TICK),
            FONT_TICK,
            "middle",
            label,
        );
    }
    for c in &fx.minor {
        let x = x_px(fx, area, *c);
        let _ = write!(marks, "M{x:.1} {bottom:.1}v-2.5M{x:.1} {top:.1}v2.5");
    }
    for (c, label) in &fy.ticks {
        let y = y_px(fy, area, *c);
        let _ = write!(grid, "M{left:.1} {y:.1}H{right:.1}");
        let _ = write!(marks, "M{left:.1} {y:.1}h4M{right:.1} {y:.1}h-4");
        text(
            out,
            (left - GAP, y + 0.35 * FONT_TICK),
            FONT_TICK,
            "end",
            label,
        );
    }
    for c in &fy.minor {
        let y = y_px(fy, area, *c);
        let _ = write!(marks, "M{left:.1} {y:.1}h2.5M{right:.1} {y:.1}h-2.5");
    }
    let _ = writeln!(
        out,
        "<path d=\"{grid}\" stroke=\"#e3e3e3\" stroke-width=\"0.8\" fill=\"none\"/>"
    );
    let _ = writeln!(
        out,
        "<path d=\"{marks}\" stroke=\"black\" stroke-width=\"1\" fill=\"none\"/>"
    );
}

/// The y axis title of `area` in `lines`, rotated, centred on the area, right-aligned in
/// a column of `columns` lines starting at `x0` (px).
pub(crate) fn draw_y_title(
    out: &mut String,
    lines: &[String],
    columns: usize,
    x0: f64,
    area: Area,
) {
    let cy = area.top + area.height / 2.0;
    for (i, line) in lines.iter().enumerate() {
        let x =
            x0 + 4.0 + FONT_LABEL * 0.85 + 1.2 * FONT_LABEL * (i + columns - lines.len()) as f64;
        let _ = writeln!(
            out,
            "<text transform=\"translate({x:.1} {cy:.1}) rotate(-90)\" font-size=\"{FONT_LABEL}\" text-anchor=\"middle\">{}</text>",
            crate::svg::markup(line, FONT_LABEL)
        );
    }
}

/// The x axis title centred under `area`, its baseline at `y` (px).
pub(crate) fn draw_x_title(out: &mut String, label: &str, area: Area, y: f64) {
    text(
        out,
        (area.left + area.width / 2.0, y),
        FONT_LABEL,
        "middle",
        label,
    );
}

/// A clip path `id` of `area`.
pub(crate) fn draw_clip_path(out: &mut String, id: &str, area: Area) {
    let _ = writeln!(
        out,
        "<clipPath id=\"{id}\"><rect x=\"{}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{}\"/></clipPath>",
        area.left, area.top, area.width, area.height
    );
}

/// The black border of `area`.
pub(crate) fn draw_border(out: &mut String, area: Area) {
    let _ = writeln!(
        out,
        "<rect x=\"{}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{}\" fill=\"none\" stroke=\"black\" stroke-width=\"1\"/>",
        area.left, area.top, area.width, area.height
    );
}

/// Width of the column of a y title of `lines` lines (px).
pub(crate) fn y_title_width(lines: usize) -> f64 {
    1.2 * FONT_LABEL * lines.max(1) as f64
}

/// Linear axes around a custom drawing: data in SI units mapped to a plot area, with the
/// house style's SI prefixes, 1-2-5 ticks, tick labels, grid, axis titles and border
/// (the same drawing as a [`crate::Figure`] panel's axes).
#[derive(Debug, Clone, PartialEq)]
pub struct Axes {
    x: Frame,
    y: Frame,
    y_lines: Vec<String>,
    outer: Area,
    area: Area,
}

impl Axes {
    /// Axes of `x` over `x_range` and `y` over `y_range` (SI, lower and upper bound) fitted
    /// into `outer` (px): the plot area is what is left after the y tick labels and title
    /// on the left, the x tick labels and title below and room for the last x tick label on
    /// the right. With `equal`, one unit is as long on both axes: the shorter range is
    /// widened about its centre to fill the plot area, and when both axes have the same
    /// unit they share one SI prefix, chosen from the larger magnitude. Ticks are about one
    /// per 80 px along x and per 60 px along y.
    pub fn fit(
        outer: Area,
        (x, x_range): (&Axis, (f64, f64)),
        (y, y_range): (&Axis, (f64, f64)),
        equal: bool,
    ) -> Self {
        let (mut xr, mut yr) = (x_range, y_range);
        let mut axes = Self::place(outer, (x, xr), (y, yr), equal, None);
        // Tick labels set the margins and the margins set the ranges (equal scales): a few
        // rounds settle both.
        for _ in 0..4 {
            if equal {
                let a = axes.area;
                let scale =
                    (a.width / (x_range.1 - x_range.0)).min(a.height / (y_range.1 - y_range.0));
                xr = widened(x_range, a.width / scale);
                yr = widened(y_range, a.height / scale);
            }
            let next = Self::place(outer, (x, xr), (y, yr), equal, Some(axes.area));
            if next == axes {
                break;
            }
            axes = next;
        }
        axes
    }

    /// The axes over exactly these ranges in `outer`, the plot area's margins from the
    /// tick labels, ticks from the plot area of the previous round (`previous`).
    fn place(
        outer: Area,
        (x, xr): (&Axis, (f64, f64)),
        (y, yr): (&Axis, (f64, f64)),
        equal: bool,
        previous: Option<Area>,
    ) -> Self {
        let guess = previous.unwrap_or(outer);
        let max = |r: (f64, f64)| r.0.abs().max(r.1.abs());
        let (sx, sy) = if equal && x.unit == y.unit && x.scale == y.scale {
            let s = scale_for(max(xr).max(max(yr)), &x.unit);
            (s.clone(), s)
        } else {
            (scale_for(max(xr), &x.unit), scale_for(max(yr), &y.unit))
        };
        let fixed = |axis: &Axis, scaled: Scaled, r: (f64, f64), px: f64, per: f64| {
            let mut f = Frame::new(axis, scaled);
            let (lo, hi) = if f.log {
                (r.0.log10(), r.1.log10())
            } else {
                (r.0 * f.factor, r.1 * f.factor)
            };
            f.set_range(lo, hi, lo, ((px / per).round() as usize).max(2));
            f
        };
        let fx = fixed(x, sx, xr, guess.width, 80.0);
        let fy = fixed(y, sy, yr, guess.height, 60.0);
        let y_lines = wrap(&fy.label, guess.height - GAP, FONT_LABEL);
        let left = (4.0 + y_title_width(y_lines.len()) + GAP + fy.tick_width() + GAP).ceil();
        let right = (0.5 * fx.last_tick_width() + 4.0).max(12.0).ceil();
        let top = (0.5 * FONT_TICK).ceil();
        let area = Area {
            left: outer.left + left,
            top: outer.top + top,
            width: outer.width - left - right,
            height: outer.height - top - BELOW - X_TITLE,
        };
        Self {
            x: fx,
            y: fy,
            y_lines,
            outer,
            area,
        }
    }

    /// The plot area (px).
    pub fn area(&self) -> Area {
        self.area
    }

    /// The pixel of the data point `(x, y)` (SI units; NaN where a value cannot be drawn,
    /// a non-positive value on a log axis).
    pub fn to_px(&self, x: f64, y: f64) -> (f64, f64) {
        let c = |f: &Frame, v: f64| f.coordinate(v).unwrap_or(f64::NAN);
        (
            x_px(&self.x, self.area, c(&self.x, x)),
            y_px(&self.y, self.area, c(&self.y, y)),
        )
    }

    /// Pixels per SI unit along x and along y (linear axes).
    pub fn px_per_unit(&self) -> (f64, f64) {
        (
            self.area.width / (self.x.hi - self.x.lo) * self.x.factor,
            self.area.height / (self.y.hi - self.y.lo) * self.y.factor,
        )
    }

    /// Draws the axes: tick labels, light grid, tick marks, both axis titles and the
    /// border of the plot area; and a clip path `clip_id` of the plot area for the drawing
    /// (`clip-path="url(#clip_id)"`).
    pub fn draw_with_clip(&self, out: &mut String, clip_id: &str) {
        draw_clip_path(out, clip_id, self.area);
        self.draw(out);
    }

    /// Draws the axes: tick labels, light grid, tick marks, both axis titles and the
    /// border of the plot area.
    pub fn draw(&self, out: &mut String) {
        draw_ticks(out, &self.x, &self.y, self.area);
        draw_y_title(
            out,
            &self.y_lines,
            self.y_lines.len(),
            self.outer.left,
            self.area,
        );
        draw_x_title(
            out,
            &self.x.label,
            self.area,
            self.area.bottom() + BELOW + X_TITLE - GAP,
        );
        draw_border(out, self.area);
    }
}

/// `range` widened about its centre to `span` (never narrowed).
fn widened(range: (f64, f64), span: f64) -> (f64, f64) {
    let span = span.max(range.1 - range.0);
    let centre = 0.5 * (range.0 + range.1);
    (centre - 0.5 * span, centre + 0.5 * span)
}
