//! The SVG renderer of [`Figure`]: layout, axes, ticks, series and legends.

use std::fmt::Write as _;

use super::decimate::decimate;
use super::ticks::{linear_ticks, log_ticks, power_label, scale_for, tick_label};
use super::{Axis, Color, Dash, Figure, Marker, Placement, Scale, Series, Style};

/// Width of a figure (px): one paper column of 8.5 cm.
pub(crate) const WIDTH: f64 = 420.0;
/// Height of a plot area (px).
const PLOT_HEIGHT: f64 = 170.0;
const FONT_TICK: f64 = 13.0;
const FONT_LABEL: f64 = 14.0;
const FONT_LEGEND: f64 = 12.5;
const FONT_TITLE: f64 = 15.0;
/// Average advance of a character as a fraction of the font size (DejaVu Sans and
/// Helvetica run about 0.55; the extra margin keeps estimated boxes on the safe side).
const CHAR_WIDTH: f64 = 0.6;
const LINE_WIDTH: f64 = 1.6;
const LEGEND_ROW: f64 = 16.0;
const LEGEND_SAMPLE: f64 = 26.0;
/// Buckets per pixel of plot width for decimation (M4 keeps four points a pixel column).
const BUCKETS_PER_PX: f64 = 1.0;

/// An axis after scaling: the shown unit and factor, the range and ticks (in shown units,
/// or log10 of the values on a log axis).
struct Frame {
    factor: f64,
    label: String,
    log: bool,
    lo: f64,
    hi: f64,
    /// (position, label) of the major ticks.
    ticks: Vec<(f64, String)>,
    /// Positions of the minor ticks.
    minor: Vec<f64>,
}

impl Frame {
    /// The value `v` (SI) as an axis coordinate (shown units, or log10), if drawable.
    fn coordinate(&self, v: f64) -> Option<f64> {
        let c = if self.log {
            if v > 0.0 { v.log10() } else { f64::NAN }
        } else {
            v * self.factor
        };
        c.is_finite().then_some(c)
    }
}

/// A rectangle in pixels.
#[derive(Debug, Clone, Copy)]
struct Rect {
    x: f64,
    y: f64,
    w: f64,
    h: f64,
}

impl Rect {
    fn contains(&self, p: (f64, f64), pad: f64) -> bool {
        p.0 >= self.x - pad
            && p.0 <= self.x + self.w + pad
            && p.1 >= self.y - pad
            && p.1 <= self.y + self.h + pad
    }
}

/// Whether the segment `p`-`q` meets rectangle `r` (Liang-Barsky clipping: Foley, van Dam
/// et al., *Computer Graphics*, 2nd ed., 3.12.4).
fn segment_meets(p: (f64, f64), q: (f64, f64), r: &Rect) -> bool {
    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
    let (mut t0, mut t1) = (0.0_f64, 1.0_f64);
    for (num, den) in [
        (p.0 - r.x, -dx),
        (r.x + r.w - p.0, dx),
        (p.1 - r.y, -dy),
        (r.y + r.h - p.1, dy),
    ] {
        if den.abs() < 1e-12 {
            if num < 0.0 {
                return false;
            }
        } else {
            let t = num / den;
            if den < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
            if t0 > t1 {
                return false;
            }
        }
    }
    true
}

/// Text with `_{xy}` subscripts as SVG content: Unicode subscripts where every character
/// has one, otherwise a lowered smaller `tspan`; XML special characters escaped. A `_`
/// without `{` is an underscore (scene names such as `paper_f20`).
pub(crate) fn markup(text: &str, font: f64) -> String {
    let mut out = String::new();
    let mut rest = text;
    while let Some(at) = rest.find("_{") {
        let Some(close) = rest[at..].find('}') else {
            break;
        };
        for c in rest[..at].chars() {
            push_escaped(&mut out, c);
        }
        let sub = &rest[at + 2..at + close];
        rest = &rest[at + close + 1..];
        match sub.chars().map(subscript).collect::<Option<String>>() {
            Some(unicode) => out.push_str(&unicode),
            None => {
                let shift = 0.3 * font;
                let _ = write!(
                    out,
                    "<tspan dy=\"{shift:.1}\" font-size=\"{:.1}\">",
                    0.72 * font
                );
                for c in sub.chars() {
                    push_escaped(&mut out, unsubscript(c).unwrap_or(c));
                }
                let _ = write!(out, "</tspan><tspan dy=\"{:.1}\"></tspan>", -shift);
            }
        }
    }
    for c in rest.chars() {
        push_escaped(&mut out, c);
    }
    out
}

fn push_escaped(out: &mut String, c: char) {
    match c {
        '&' => out.push_str("&amp;"),
        '<' => out.push_str("&lt;"),
        '>' => out.push_str("&gt;"),
        '"' => out.push_str("&quot;"),
        _ => out.push(c),
    }
}

const SUBSCRIPTS: [(char, char); 33] = [
    ('0', '₀'),
    ('1', '₁'),
    ('2', '₂'),
    ('3', '₃'),
    ('4', '₄'),
    ('5', '₅'),
    ('6', '₆'),
    ('7', '₇'),
    ('8', '₈'),
    ('9', '₉'),
    ('a', 'ₐ'),
    ('e', 'ₑ'),
    ('o', 'ₒ'),
    ('x', 'ₓ'),
    ('h', 'ₕ'),
    ('k', 'ₖ'),
    ('l', 'ₗ'),
    ('m', 'ₘ'),
    ('n', 'ₙ'),
    ('p', 'ₚ'),
    ('s', 'ₛ'),
    ('t', 'ₜ'),
    ('i', 'ᵢ'),
    ('r', 'ᵣ'),
    ('u', 'ᵤ'),
    ('v', 'ᵥ'),
    ('j', 'ⱼ'),
    ('β', 'ᵦ'),
    ('ρ', 'ᵨ'),
    ('φ', 'ᵩ'),
    (',', ','),
    ('+', '₊'),
    ('=', '₌'),
];

/// The Unicode subscript of `c` (an existing subscript is kept).
fn subscript(c: char) -> Option<char> {
    if unsubscript(c).is_some() {
        return Some(c);
    }
    SUBSCRIPTS.iter().find(|(p, _)| *p == c).map(|(_, s)| *s)
}

/// The plain character of a Unicode subscript.
fn unsubscript(c: char) -> Option<char> {
    SUBSCRIPTS
        .iter()
        .find(|(p, s)| *s == c && *p != c)
        .map(|(p, _)| *p)
}

/// Estimated width of `text` at `font` (px), subscript markup not counted.
fn text_width(text: &str, font: f64) -> f64 {
    let n = text
        .chars()
        .filter(|c| !matches!(c, '_' | '{' | '}'))
        .count();
    n as f64 * CHAR_WIDTH * font
}

/// `text` in lines of at most `width` px at `font`, broken between words.
fn wrap(text: &str, width: f64, font: f64) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in text.split_whitespace() {
        match lines.last_mut() {
            Some(line) if text_width(&format!("{line} {word}"), font) <= width => {
                line.push(' ');
                line.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines
}

/// `label (unit)`, or the label alone.
fn axis_title(label: &str, unit: &str) -> String {
    if unit.is_empty() {
        label.to_string()
    } else {
        format!("{label} ({unit})")
    }
}

/// The drawable coordinates of a series on a frame pair (x, y), gaps as `None`.
fn coordinates(s: &Series, fx: &Frame, fy: &Frame) -> Vec<Option<(f64, f64)>> {
    s.x.iter()
        .zip(&s.y)
        .map(|(&x, &y)| match s.placement {
            Placement::Data => Some((fx.coordinate(x)?, fy.coordinate(y)?)),
            Placement::LowerEdge => Some((fx.coordinate(x)?, f64::NAN)),
        })
        .collect()
}

/// The frame of an axis over the values `values` (SI), with `pad` of the span added on
/// each side, `strip` px of the plot height below the data kept free (for failed cases),
/// and about `target` ticks.
fn frame(axis: &Axis, values: &[f64], pad: f64, strip: f64, target: usize) -> Frame {
    let log = axis.scale == Scale::Log;
    let (factor, unit) = if log {
        (1.0, axis.unit.clone())
    } else {
        let max_abs = values
            .iter()
            .filter(|v| v.is_finite())
            .fold(0.0_f64, |m, v| m.max(v.abs()));
        let s = scale_for(max_abs, &axis.unit);
        (s.factor, s.unit)
    };
    let mut f = Frame {
        factor,
        label: axis_title(&axis.label, &unit),
        log,
        lo: 0.0,
        hi: 0.0,
        ticks: Vec::new(),
        minor: Vec::new(),
    };
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
        lo -= (hi - lo) * strip / (PLOT_HEIGHT - strip);
    }
    f.lo = lo;
    f.hi = hi;
    if log {
        let (major, minor) = log_ticks(10f64.powf(lo), 10f64.powf(hi));
        f.ticks = major
            .into_iter()
            .map(|e| (f64::from(e), power_label(e)))
            .collect();
        f.minor = minor.into_iter().map(f64::log10).collect();
    } else {
        let (ticks, step) = linear_ticks(data_lo, hi, target);
        f.ticks = ticks
            .into_iter()
            .map(|v| (v, tick_label(v, step)))
            .collect();
    }
    // No ticks in the strip for failed cases.
    f.ticks.retain(|t| t.0 >= data_lo - 1e-9 * (hi - lo));
    f.minor.retain(|&t| t >= data_lo);
    f
}

/// Height of the strip for failed cases (px).
const STRIP: f64 = 16.0;

/// Where a panel's legend goes.
enum LegendPlace {
    None,
    Inside(Rect),
    Above { rows: Vec<Vec<usize>>, height: f64 },
}

struct Entry<'a> {
    label: &'a str,
    style: Style,
    width: f64,
}

fn color(c: Color) -> String {
    format!("#{:02x}{:02x}{:02x}", c.0, c.1, c.2)
}

fn dasharray(d: Dash) -> &'static str {
    match d {
        Dash::Solid => "",
        Dash::Dashed => " stroke-dasharray=\"6 3\"",
        Dash::Dotted => " stroke-dasharray=\"1.5 2.5\"",
        Dash::DashDot => " stroke-dasharray=\"7 3 1.5 3\"",
    }
}

/// Radius of a marker (px).
const MARKER: f64 = 3.4;

fn marker_svg(out: &mut String, m: Marker, c: Color, (x, y): (f64, f64)) {
    let c = color(c);
    let r = MARKER;
    let _ = match m {
        Marker::Disc => writeln!(
            out,
            "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"{r}\" fill=\"{c}\"/>"
        ),
        Marker::Ring => writeln!(
            out,
            "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"{r}\" fill=\"white\" stroke=\"{c}\" stroke-width=\"1.4\"/>"
        ),
        Marker::Square => writeln!(
            out,
            "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{:.1}\" fill=\"{c}\"/>",
            x - 0.85 * r,
            y - 0.85 * r,
            1.7 * r,
            1.7 * r
        ),
        Marker::Triangle => writeln!(
            out,
            "<path d=\"M{:.1} {:.1}L{:.1} {:.1}L{:.1} {:.1}Z\" fill=\"{c}\"/>",
            x,
            y - 1.15 * r,
            x + r,
            y + 0.75 * r,
            x - r,
            y + 0.75 * r
        ),
        Marker::TriangleDown => writeln!(
            out,
            "<path d=\"M{:.1} {:.1}L{:.1} {:.1}L{:.1} {:.1}Z\" fill=\"{c}\"/>",
            x,
            y + 1.15 * r,
            x + r,
            y - 0.75 * r,
            x - r,
            y - 0.75 * r
        ),
        Marker::Diamond => writeln!(
            out,
            "<path d=\"M{:.1} {:.1}L{:.1} {:.1}L{:.1} {:.1}L{:.1} {:.1}Z\" fill=\"{c}\"/>",
            x,
            y - 1.2 * r,
            x + r,
            y,
            x,
            y + 1.2 * r,
            x - r,
            y
        ),
    };
}

fn line_svg(out: &mut String, points: &[(f64, f64)], s: Style) {
    if points.len() < 2 {
        return;
    }
    let _ = write!(out, "<polyline points=\"");
    for (k, (x, y)) in points.iter().enumerate() {
        let sep = if k == 0 { "" } else { " " };
        let _ = write!(out, "{sep}{x:.1},{y:.1}");
    }
    let _ = writeln!(
        out,
        "\" fill=\"none\" stroke=\"{}\" stroke-width=\"{LINE_WIDTH}\" stroke-linejoin=\"round\"{}/>",
        color(s.color),
        dasharray(s.dash)
    );
}

fn text_svg(out: &mut String, (x, y): (f64, f64), font: f64, anchor: &str, text: &str) {
    let _ = writeln!(
        out,
        "<text x=\"{x:.1}\" y=\"{y:.1}\" font-size=\"{font}\" text-anchor=\"{anchor}\">{}</text>",
        markup(text, font)
    );
}

/// A series in pixels: its polylines (runs without gaps) and its marker points.
type Drawn = (Vec<Vec<(f64, f64)>>, Vec<(f64, f64)>);

/// One laid-out panel: its frame, the series in pixels and the legend place.
struct Laid<'a> {
    fy: Frame,
    /// Pixel polylines (runs without gaps) and marker points per series.
    pixels: Vec<Drawn>,
    /// Failed-case circles standing for more than one case, and how many.
    counts: Vec<((f64, f64), usize)>,
    entries: Vec<Entry<'a>>,
    legend: LegendPlace,
}

pub(crate) fn render(figure: &Figure) -> Result<String, String> {
    let name = figure.title.as_deref().unwrap_or(&figure.x.label);
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
    // Time series run edge to edge; points with markers get room.
    let fx = frame(&figure.x, &xs, if markers { 0.05 } else { 0.0 }, 0.0, 6);
    let frames: Vec<Frame> = figure
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
            frame(&p.y, &ys, 0.06, if edge { STRIP } else { 0.0 }, 5)
        })
        .collect();
    // Horizontal layout, common to all panels so the plot areas align.
    let tick_width = frames
        .iter()
        .flat_map(|f| f.ticks.iter().map(|t| text_width(&t.1, FONT_TICK)))
        .fold(0.0, f64::max);
    let y_labels: Vec<Vec<String>> = frames
        .iter()
        .map(|f| wrap(&f.label, PLOT_HEIGHT - 6.0, FONT_LABEL))
        .collect();
    let label_lines = y_labels.iter().map(Vec::len).max().unwrap_or(1).max(1);
    let label_w = 1.2 * FONT_LABEL * label_lines as f64;
    let left = (4.0 + label_w + 6.0 + tick_width + 6.0).ceil();
    let last_x_tick = fx.ticks.last().map_or(0.0, |t| text_width(&t.1, FONT_TICK));
    let right = (0.5 * last_x_tick + 4.0).max(12.0).ceil();
    let plot_w = WIDTH - left - right;
    let buckets = (BUCKETS_PER_PX * plot_w) as usize;
    let px = |c: f64| left + (c - fx.lo) / (fx.hi - fx.lo) * plot_w;

    let mut laid: Vec<Laid<'_>> = Vec::new();
    for (panel, fy) in figure.panels.iter().zip(frames) {
        let py = |c: f64| PLOT_HEIGHT - (c - fy.lo) / (fy.hi - fy.lo) * PLOT_HEIGHT;
        let mut pixels = Vec::new();
        let mut edge: Vec<((f64, f64), usize)> = Vec::new();
        for s in &panel.series {
            let (dx, dy) = if s.style.marker.is_none() {
                decimate(&s.x, &s.y, buckets)
            } else {
                (s.x.clone(), s.y.clone())
            };
            let short = Series {
                x: dx,
                y: dy,
                ..s.clone()
            };
            let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
            let mut points = Vec::new();
            for c in coordinates(&short, &fx, &fy) {
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
            pixels.push((runs, points));
        }
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
        let legend = place_legend(&entries, &pixels, left, plot_w);
        laid.push(Laid {
            fy,
            pixels,
            counts: edge.into_iter().filter(|e| e.1 > 1).collect(),
            entries,
            legend,
        });
    }

    // Vertical layout.
    let title_lines = figure
        .title
        .as_deref()
        .map_or_else(Vec::new, |t| wrap(t, WIDTH - 16.0, FONT_TITLE));
    let title_h = if title_lines.is_empty() {
        4.0
    } else {
        8.0 + 1.25 * FONT_TITLE * title_lines.len() as f64
    };
    let below = 4.0 + FONT_TICK + 4.0;
    let x_label_h = FONT_LABEL + 8.0;
    let mut tops = Vec::new();
    let mut y = title_h;
    for l in &laid {
        if let LegendPlace::Above { height, .. } = l.legend {
            y += height;
        }
        y += 6.0;
        tops.push(y);
        y += PLOT_HEIGHT + below;
    }
    let height = (y + x_label_h).ceil();

    let mut out = String::new();
    let _ = writeln!(
        out,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{WIDTH}\" height=\"{height}\" \
         viewBox=\"0 0 {WIDTH} {height}\" font-family=\"DejaVu Sans, Helvetica, Arial, sans-serif\">"
    );
    let mut head = String::new();
    for c in name.chars() {
        push_escaped(&mut head, c);
    }
    let _ = writeln!(out, "<title>{head}</title>");
    if let Some(d) = &figure.description {
        let mut desc = String::new();
        for c in d.chars() {
            push_escaped(&mut desc, c);
        }
        let _ = writeln!(out, "<desc>{desc}</desc>");
    }
    let _ = writeln!(out, "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>");
    for (k, line) in title_lines.iter().enumerate() {
        let y = 4.0 + FONT_TITLE + 1.25 * FONT_TITLE * k as f64;
        text_svg(&mut out, (WIDTH / 2.0, y), FONT_TITLE, "middle", line);
    }
    let xmap = |c: f64| px(c);
    for (k, (l, top)) in laid.iter().zip(&tops).enumerate() {
        let top = *top;
        let bottom = top + PLOT_HEIGHT;
        let ymap = |c: f64| top + PLOT_HEIGHT - (c - l.fy.lo) / (l.fy.hi - l.fy.lo) * PLOT_HEIGHT;
        let _ = writeln!(
            out,
            "<clipPath id=\"p{k}\"><rect x=\"{left}\" y=\"{top:.1}\" width=\"{plot_w:.1}\" height=\"{PLOT_HEIGHT}\"/></clipPath>"
        );
        // Grid and ticks.
        let mut grid = String::new();
        let mut marks = String::new();
        for (c, label) in &fx.ticks {
            let x = xmap(*c);
            let _ = write!(grid, "M{x:.1} {top:.1}V{bottom:.1}");
            let _ = write!(marks, "M{x:.1} {bottom:.1}v-4M{x:.1} {top:.1}v4");
            text_svg(
                &mut out,
                (x, bottom + 4.0 + FONT_TICK),
                FONT_TICK,
                "middle",
                label,
            );
        }
        for c in &fx.minor {
            let x = xmap(*c);
            let _ = write!(marks, "M{x:.1} {bottom:.1}v-2.5M{x:.1} {top:.1}v2.5");
        }
        for (c, label) in &l.fy.ticks {
            let y = ymap(*c);
            let _ = write!(grid, "M{left:.1} {y:.1}H{:.1}", left + plot_w);
            let _ = write!(marks, "M{left:.1} {y:.1}h4M{:.1} {y:.1}h-4", left + plot_w);
            text_svg(
                &mut out,
                (left - 6.0, y + 0.35 * FONT_TICK),
                FONT_TICK,
                "end",
                label,
            );
        }
        for c in &l.fy.minor {
            let y = ymap(*c);
            let _ = write!(
                marks,
                "M{left:.1} {y:.1}h2.5M{:.1} {y:.1}h-2.5",
                left + plot_w
            );
        }
        let _ = writeln!(
            out,
            "<path d=\"{grid}\" stroke=\"#e3e3e3\" stroke-width=\"0.8\" fill=\"none\"/>"
        );
        let _ = writeln!(
            out,
            "<path d=\"{marks}\" stroke=\"black\" stroke-width=\"1\" fill=\"none\"/>"
        );
        // y label, rotated, centred on the plot area, in lines if it is long.
        let cy = top + PLOT_HEIGHT / 2.0;
        let lines = &y_labels[k];
        for (i, line) in lines.iter().enumerate() {
            let x =
                4.0 + FONT_LABEL * 0.85 + 1.2 * FONT_LABEL * (i + label_lines - lines.len()) as f64;
            let _ = writeln!(
                out,
                "<text transform=\"translate({x:.1} {cy:.1}) rotate(-90)\" font-size=\"{FONT_LABEL}\" text-anchor=\"middle\">{}</text>",
                markup(line, FONT_LABEL)
            );
        }
        // Series, clipped to the plot area.
        let _ = writeln!(out, "<g clip-path=\"url(#p{k})\">");
        for ((runs, points), s) in l.pixels.iter().zip(&figure.panels[k].series) {
            for run in runs {
                let moved: Vec<(f64, f64)> = run.iter().map(|&(x, y)| (x, y + top)).collect();
                line_svg(&mut out, &moved, s.style);
            }
            if let Some(m) = s.style.marker {
                for &(x, y) in points {
                    marker_svg(&mut out, m, s.style.color, (x, y + top));
                }
            }
        }
        for ((x, y), n) in &l.counts {
            let _ = writeln!(
                out,
                "<text x=\"{:.1}\" y=\"{:.1}\" font-size=\"10\" fill=\"{}\">×{n}</text>",
                x + MARKER + 2.0,
                y + top + 3.5,
                color(super::FAILED_COLOR)
            );
        }
        let _ = writeln!(out, "</g>");
        let _ = writeln!(
            out,
            "<rect x=\"{left}\" y=\"{top:.1}\" width=\"{plot_w:.1}\" height=\"{PLOT_HEIGHT}\" fill=\"none\" stroke=\"black\" stroke-width=\"1\"/>"
        );
        draw_legend(&mut out, l, left, top);
    }
    text_svg(
        &mut out,
        (left + plot_w / 2.0, height - 6.0),
        FONT_LABEL,
        "middle",
        &fx.label,
    );
    out.push_str("</svg>\n");
    Ok(out)
}

/// The legend's place: none for fewer than two entries; the first corner of the plot area
/// (upper right, upper left, lower right, lower left) that no line or marker touches;
/// otherwise rows above the plot area.
fn place_legend(entries: &[Entry<'_>], pixels: &[Drawn], left: f64, plot_w: f64) -> LegendPlace {
    if entries.len() < 2 {
        return LegendPlace::None;
    }
    let w = entries.iter().map(|e| e.width).fold(0.0, f64::max) + 12.0;
    let h = LEGEND_ROW * entries.len() as f64 + 8.0;
    let inset = 5.0;
    if w < 0.7 * plot_w && h < 0.7 * PLOT_HEIGHT {
        let corners = [
            (left + plot_w - w - inset, inset),
            (left + inset, inset),
            (left + plot_w - w - inset, PLOT_HEIGHT - h - inset),
            (left + inset, PLOT_HEIGHT - h - inset),
        ];
        for (x, y) in corners {
            let r = Rect { x, y, w, h };
            let free = pixels.iter().all(|(runs, points)| {
                !points.iter().any(|&p| r.contains(p, MARKER + 1.0))
                    && !runs.iter().any(|run| {
                        run.windows(2).any(|s| segment_meets(s[0], s[1], &r))
                            || run.first().is_some_and(|&p| r.contains(p, 1.0))
                    })
            });
            if free {
                return LegendPlace::Inside(r);
            }
        }
    }
    // Rows above the plot, entries side by side.
    let mut rows: Vec<Vec<usize>> = vec![Vec::new()];
    let mut used = 0.0;
    for (k, e) in entries.iter().enumerate() {
        let wk = e.width + 14.0;
        if used + wk > plot_w && !rows.last().is_some_and(Vec::is_empty) {
            rows.push(Vec::new());
            used = 0.0;
        }
        if let Some(r) = rows.last_mut() {
            r.push(k);
        }
        used += wk;
    }
    let height = LEGEND_ROW * rows.len() as f64 + 2.0;
    LegendPlace::Above { rows, height }
}

fn legend_entry(out: &mut String, e: &Entry<'_>, (x, y): (f64, f64)) {
    if e.style.line {
        line_svg(out, &[(x, y), (x + LEGEND_SAMPLE, y)], e.style);
    }
    if let Some(m) = e.style.marker {
        marker_svg(out, m, e.style.color, (x + LEGEND_SAMPLE / 2.0, y));
    }
    text_svg(
        out,
        (x + LEGEND_SAMPLE + 6.0, y + 0.35 * FONT_LEGEND),
        FONT_LEGEND,
        "start",
        e.label,
    );
}

fn draw_legend(out: &mut String, l: &Laid<'_>, left: f64, top: f64) {
    match &l.legend {
        LegendPlace::None => {}
        LegendPlace::Inside(r) => {
            let _ = writeln!(
                out,
                "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{:.1}\" fill=\"white\" fill-opacity=\"0.9\" stroke=\"#b0b0b0\" stroke-width=\"0.8\"/>",
                r.x,
                top + r.y,
                r.w,
                r.h
            );
            for (k, e) in l.entries.iter().enumerate() {
                let y = top + r.y + 4.0 + LEGEND_ROW * (k as f64 + 0.5);
                legend_entry(out, e, (r.x + 6.0, y));
            }
        }
        LegendPlace::Above { rows, height } => {
            let y0 = top - 6.0 - height;
            for (i, row) in rows.iter().enumerate() {
                let y = y0 + LEGEND_ROW * (i as f64 + 0.5) + 1.0;
                let mut x = left;
                for &k in row {
                    legend_entry(out, &l.entries[k], (x, y));
                    x += l.entries[k].width + 14.0;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn subscripts() {
        assert_eq!(markup("F_{a1}", 14.0), "Fₐ₁");
        assert_eq!(markup("δ_{max}", 14.0), "δₘₐₓ");
        assert_eq!(markup("M_{ρ} ρ̈", 14.0), "Mᵨ ρ̈");
        assert_eq!(markup("paper_f20", 14.0), "paper_f20");
        let p = markup("P_{B1} (N)", 10.0);
        assert!(
            p.starts_with("P<tspan dy=\"3.0\" font-size=\"7.2\">B1</tspan>"),
            "{p}"
        );
        assert!(p.ends_with(" (N)"), "{p}");
        assert_eq!(markup("a<b & c", 14.0), "a&lt;b &amp; c");
    }

    #[test]
    fn legend_avoids_data() {
        let entry = |label| Entry {
            label,
            style: Style::nth(0),
            width: 60.0,
        };
        let entries = [entry("a"), entry("b")];
        let (left, w) = (50.0, 300.0);
        // A diagonal from the lower left to the upper right corner: the upper-right corner
        // is taken, the upper-left one is free.
        let diagonal = vec![(left, PLOT_HEIGHT), (left + w, 0.0)];
        match place_legend(&entries, &[(vec![diagonal], vec![])], left, w) {
            LegendPlace::Inside(r) => assert!(r.x < left + 10.0 && r.y < 10.0, "{r:?}"),
            _ => panic!("expected the upper-left corner"),
        }
        // Lines along the top and the bottom take every corner: the legend goes above.
        let lines = vec![
            vec![(left, 8.0), (left + w, 8.0)],
            vec![(left, PLOT_HEIGHT - 8.0), (left + w, PLOT_HEIGHT - 8.0)],
        ];
        assert!(matches!(
            place_legend(&entries, &[(lines, vec![])], left, w),
            LegendPlace::Above { .. }
        ));
        // Markers count as well as lines.
        let points: Vec<(f64, f64)> = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
            .iter()
            .map(|(a, b)| {
                (
                    left + 20.0 + a * (w - 40.0),
                    15.0 + b * (PLOT_HEIGHT - 30.0),
                )
            })
            .collect();
        assert!(matches!(
            place_legend(&entries, &[(vec![], points)], left, w),
            LegendPlace::Above { .. }
        ));
    }

    #[test]
    fn segments_and_rectangles() {
        let r = Rect {
            x: 0.0,
            y: 0.0,
            w: 10.0,
            h: 10.0,
        };
        // Crossing the box without an end inside it.
        assert!(segment_meets((-5.0, 5.0), (15.0, 5.0), &r));
        assert!(segment_meets((-5.0, -5.0), (15.0, 15.0), &r));
        assert!(!segment_meets((-5.0, 11.0), (15.0, 11.0), &r));
        assert!(!segment_meets((11.0, -5.0), (30.0, 5.0), &r));
    }
}
