//! `modes.svg`: the first mode shapes drawn on the machine, one panel each: the guides, the
//! machine at rest (dashed), and the machine moved along the mode (sliders, platform and
//! each link's deflected centre line), amplified so that the largest displacement is 15 %
//! of a link's length; each panel labelled with its frequency, damping ratio and kind.
//! Drawn on the plot module's axes in millimetres with equal scales.

use std::fmt::Write as _;

use flexprr_kinematics::Geometry;
use flexprr_plot::axes::{Area, Axes};
use flexprr_plot::svg::{
    FONT_LABEL, FONT_LEGEND, FONT_TITLE, close, color, open, text, text_width, wrap,
};
use flexprr_plot::{Axis, Color, PALETTE};

use super::{MachineMode, MachineModes};

const INK: Color = Color(34, 34, 34);
const GUIDE: Color = Color(190, 190, 190);
const REST: Color = Color(150, 150, 150);
const PLATFORM: Color = Color(250, 220, 120);
const PLATFORM_EDGE: Color = Color(107, 82, 0);

/// Width and height of one panel, caption included (px).
const PANEL: (f64, f64) = (320.0, 350.0);
/// Height of the key band below the panels (px).
const BAND: f64 = 44.0;
/// Panels per row.
const COLUMNS: usize = 3;
/// The largest displacement of a drawn shape, as a fraction of the shortest link.
const AMPLITUDE: f64 = 0.15;

/// A polyline (px), `width` px wide, dashed when `dash`.
fn line(out: &mut String, points: &[(f64, f64)], c: Color, width: f64, dash: bool) {
    let d: Vec<String> = points
        .iter()
        .map(|(x, y)| format!("{x:.1},{y:.1}"))
        .collect();
    let dash = if dash {
        " stroke-dasharray=\"5 4\""
    } else {
        ""
    };
    let _ = writeln!(
        out,
        "<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"{width}\" \
         stroke-linejoin=\"round\" stroke-linecap=\"round\"{dash}/>",
        d.join(" "),
        color(c)
    );
}

/// A closed polygon (px), filled with `fill` or hollow, its edge dashed when `dash`.
fn polygon(out: &mut String, points: &[(f64, f64)], fill: Option<Color>, edge: Color, dash: bool) {
    let d: Vec<String> = points
        .iter()
        .map(|(x, y)| format!("{x:.1},{y:.1}"))
        .collect();
    let dash = if dash {
        " stroke-dasharray=\"5 4\""
    } else {
        ""
    };
    let _ = writeln!(
        out,
        "<polygon points=\"{}\" fill=\"{}\" stroke=\"{}\" stroke-width=\"1.2\"{dash}/>",
        d.join(" "),
        fill.map_or("none".to_string(), color),
        color(edge)
    );
}

/// A filled square of half-side `h` px centred on `p`.
fn square(out: &mut String, (x, y): (f64, f64), h: f64, c: Color) {
    let _ = writeln!(
        out,
        "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{:.1}\" fill=\"{}\"/>",
        x - h,
        y - h,
        2.0 * h,
        2.0 * h,
        color(c)
    );
}

/// The machine at the operating point moved `amp` times along `mode` (m): slider joints,
/// platform joints and each link's centre line.
struct Moved {
    b: [[f64; 2]; 3],
    c: [[f64; 2]; 3],
    lines: [Vec<[f64; 2]>; 3],
}

impl Moved {
    fn new(
        modes: &MachineModes,
        geometry: &Geometry,
        mode: Option<&MachineMode>,
        amp: f64,
    ) -> Self {
        let pose = modes.pose;
        let (sin, cos) = pose.phi.sin_cos();
        let b = std::array::from_fn(|i| {
            let ds = mode.map_or(0.0, |m| amp * m.shape.sliders[i]);
            let p = geometry.legs[i].guide.slider_point(modes.rho[i] + ds);
            [p.x, p.y]
        });
        let c = std::array::from_fn(|i| {
            let a = geometry.legs[i].attachment;
            let d = mode.map_or([0.0; 2], |m| m.shape.joints[i]);
            [
                pose.x + cos * a.x - sin * a.y + amp * d[0],
                pose.y + sin * a.x + cos * a.y + amp * d[1],
            ]
        });
        let lines = std::array::from_fn(|i: usize| {
            let (bi, ci): ([f64; 2], [f64; 2]) = (b[i], c[i]);
            let (dx, dy) = (ci[0] - bi[0], ci[1] - bi[1]);
            let chord = dx.hypot(dy).max(f64::MIN_POSITIVE);
            let n = [-dy / chord, dx / chord];
            modes
                .xi
                .iter()
                .enumerate()
                .map(|(j, &xi)| {
                    let w = mode.map_or(0.0, |m| amp * m.shape.links[i][j]);
                    [bi[0] + xi * dx + w * n[0], bi[1] + xi * dy + w * n[1]]
                })
                .collect()
        });
        Self { b, c, lines }
    }
}

/// `12.35 Hz`, `116.39 Hz`, `1047.5 Hz`: the frequency with about five significant digits.
fn frequency_text(f: f64) -> String {
    if f >= 1000.0 {
        format!("{f:.1} Hz")
    } else {
        format!("{f:.2} Hz")
    }
}

/// `ζ = 0.0123` (three significant digits), `ζ = 0` below 5e-5.
fn damping_text(zeta: f64) -> String {
    if zeta.is_nan() || zeta.abs() < 5e-5 {
        return "ζ = 0".into();
    }
    let decimals = (2.0 - zeta.abs().log10().floor()).max(0.0) as usize;
    format!("ζ = {zeta:.decimals$}")
}

/// `modes.svg` of the first `count` modes of `modes` on the machine `geometry`; `title`
/// names the scene and the operating point.
pub fn modes_svg(modes: &MachineModes, geometry: &Geometry, count: usize, title: &str) -> String {
    let shown: Vec<&MachineMode> = modes.modes.iter().take(count.max(1)).collect();
    let length = geometry
        .link_lengths()
        .iter()
        .fold(f64::INFINITY, |m, l| m.min(*l));
    let rest = Moved::new(modes, geometry, None, 0.0);
    // One window for every panel: the machine at rest with room for the largest motion.
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for p in rest.b.iter().chain(&rest.c) {
        x0 = x0.min(p[0]);
        x1 = x1.max(p[0]);
        y0 = y0.min(p[1]);
        y1 = y1.max(p[1]);
    }
    let margin = 1.6 * AMPLITUDE * length;
    let window = ((x0 - margin, x1 + margin), (y0 - margin, y1 + margin));
    let rows = shown.len().div_ceil(COLUMNS).max(1);
    let columns = shown.len().clamp(1, COLUMNS);
    let width = PANEL.0 * columns as f64;
    let about = format!(
        "{}; sliders {}. Each shape is drawn with its largest displacement {:.0} % of a link.",
        modes.model,
        modes.sliders,
        100.0 * AMPLITUDE
    );
    let title_lines = wrap(title, width - 24.0, FONT_TITLE);
    let about_lines = wrap(&about, width - 24.0, FONT_LEGEND);
    let head = 14.0
        + 1.3 * FONT_TITLE * title_lines.len() as f64
        + 1.35 * FONT_LEGEND * about_lines.len() as f64;
    let height = head + PANEL.1 * rows as f64 + BAND;
    let mut svg = String::new();
    open(
        &mut svg,
        width,
        height,
        title,
        Some("flexprr modes: the whole machine's mode shapes at an operating point"),
    );
    let mut y = 6.0;
    for line_text in &title_lines {
        y += 1.3 * FONT_TITLE;
        text(&mut svg, (12.0, y), FONT_TITLE, "start", line_text);
    }
    for line_text in &about_lines {
        y += 1.35 * FONT_LEGEND;
        text(&mut svg, (12.0, y), FONT_LEGEND, "start", line_text);
    }
    if shown.is_empty() {
        text(
            &mut svg,
            (12.0, head + 40.0),
            FONT_LABEL,
            "start",
            "The model has no mode of non-zero frequency.",
        );
    }
    for (k, mode) in shown.iter().enumerate() {
        let left = PANEL.0 * (k % COLUMNS) as f64;
        let top = head + PANEL.1 * (k / COLUMNS) as f64;
        let amp = AMPLITUDE * length / mode.shape.largest().max(f64::MIN_POSITIVE);
        let moved = Moved::new(modes, geometry, Some(mode), amp);
        let caption = format!(
            "({}) {}, {}",
            char::from(b'a' + (k % 26) as u8),
            frequency_text(mode.frequency_hz),
            damping_text(mode.damping_ratio)
        );
        draw_panel(
            &mut svg,
            (left, top),
            k,
            [&caption, &mode.kind],
            (geometry, &rest, &moved),
            window,
        );
    }
    key(&mut svg, height - 0.5 * BAND);
    close(&mut svg);
    svg
}

/// Panel `index` with its top-left corner at `corner`: the two caption lines, the axes over
/// `window` (m), the guides, the machine at rest and moved.
fn draw_panel(
    out: &mut String,
    (left, top): (f64, f64),
    index: usize,
    caption: [&str; 2],
    (geometry, rest, moved): (&Geometry, &Moved, &Moved),
    window: ((f64, f64), (f64, f64)),
) {
    for (k, line_text) in caption.iter().enumerate() {
        text(
            out,
            (
                left + 0.5 * PANEL.0,
                top + FONT_LABEL + 1.3 * FONT_LABEL * k as f64,
            ),
            FONT_LABEL,
            "middle",
            line_text,
        );
    }
    let caption_h = 2.6 * FONT_LABEL + 6.0;
    let axes = Axes::fit(
        Area {
            left: left + 4.0,
            top: top + caption_h,
            width: PANEL.0 - 12.0,
            height: PANEL.1 - caption_h - 6.0,
        },
        (&Axis::new("x", "m"), window.0),
        (&Axis::new("y", "m"), window.1),
        true,
    );
    let clip = format!("mode{index}");
    axes.draw_with_clip(out, &clip);
    let _ = writeln!(out, "<g clip-path=\"url(#{clip})\">");
    let px = |p: [f64; 2]| axes.to_px(p[0], p[1]);
    for leg in &geometry.legs {
        let g = &leg.guide;
        let (a, b) = (g.slider_point(g.travel.0), g.slider_point(g.travel.1));
        line(out, &[px([a.x, a.y]), px([b.x, b.y])], GUIDE, 4.0, false);
    }
    for i in 0..3 {
        line(out, &[px(rest.b[i]), px(rest.c[i])], REST, 1.2, true);
    }
    polygon(out, &rest.c.map(px), None, REST, true);
    polygon(out, &moved.c.map(px), Some(PLATFORM), PLATFORM_EDGE, false);
    for (i, colour) in PALETTE.iter().take(3).enumerate() {
        let centre: Vec<(f64, f64)> = moved.lines[i].iter().map(|&p| px(p)).collect();
        line(out, &centre, *colour, 2.5, false);
        square(out, px(moved.b[i]), 4.5, INK);
    }
    let _ = writeln!(out, "</g>");
}

/// The key below the panels, its centre line at `y` (px).
fn key(out: &mut String, y: f64) {
    let mut x = 16.0;
    let mut entry = |out: &mut String, sample: &dyn Fn(&mut String, f64), label: &str| {
        sample(out, x);
        text(
            out,
            (x + 36.0, y + 0.35 * FONT_LEGEND),
            FONT_LEGEND,
            "start",
            label,
        );
        x += 36.0 + text_width(label, FONT_LEGEND) + 24.0;
    };
    entry(
        out,
        &|out, x| {
            for (k, c) in PALETTE.iter().take(3).enumerate() {
                let dy = 4.0 * (k as f64 - 1.0);
                line(out, &[(x, y + dy), (x + 28.0, y + dy)], *c, 2.0, false);
            }
        },
        "links 1, 2, 3 along the mode",
    );
    entry(
        out,
        &|out, x| line(out, &[(x, y), (x + 28.0, y)], REST, 1.2, true),
        "at rest",
    );
    entry(
        out,
        &|out, x| square(out, (x + 14.0, y), 4.5, INK),
        "sliders",
    );
    entry(
        out,
        &|out, x| {
            polygon(
                out,
                &[(x + 4.0, y + 6.0), (x + 24.0, y + 6.0), (x + 14.0, y - 7.0)],
                Some(PLATFORM),
                PLATFORM_EDGE,
                false,
            )
        },
        "platform",
    );
    entry(
        out,
        &|out, x| line(out, &[(x, y), (x + 28.0, y)], GUIDE, 4.0, false),
        "guides",
    );
}
