//! Static figures: the machine with its reachable workspace and type-II singularity locus
//! (`machine.svg`), and the deformed links at a few instants (`snapshots.svg`).
//!
//! The machine itself (guides, links, sliders, platform, workspace) is drawn here as plain
//! SVG; the axes, ticks, axis titles and text come from the one plot module
//! ([`flexprr_plot::axes::Axes`], [`flexprr_plot::svg`]), with equal scales.

use std::fmt::Write as _;

use flexprr_kinematics::{Geometry, KinematicsError, LegPosition, Pose};
use flexprr_plot::axes::{Area, Axes};
use flexprr_plot::decimate::frame_indices;
use flexprr_plot::svg::{
    FONT_LABEL, FONT_LEGEND, FONT_TITLE, close, color, open, text, text_width, wrap,
};
use flexprr_plot::ticks::value_label;
use flexprr_plot::{Axis, Color};

use crate::data::{ViewerData, ViewerError};

/// A section of the reachable workspace at constant platform orientation, sampled on a
/// regular grid of platform reference points.
#[derive(Debug, Clone, PartialEq)]
pub struct WorkspaceSection {
    /// Platform orientation of the section (rad).
    pub phi: f64,
    /// Grid abscissae (m), increasing.
    pub x: Vec<f64>,
    /// Grid ordinates (m), increasing.
    pub y: Vec<f64>,
    /// Per node `[iy * x.len() + ix]`: every leg assembles on its branch and every slider
    /// is inside its travel.
    pub reachable: Vec<bool>,
    /// Straight pieces `[[x0, y0], [x1, y1]]` (m) of the reachable set's boundary.
    pub boundary: Vec<[[f64; 2]; 2]>,
    /// Straight pieces (m) of the type-II singularity locus inside the reachable set: the
    /// zero set of the signed determinant of the direct Jacobian (link lines concurrent or
    /// parallel; Gosselin & Angeles 1990).
    pub locus: Vec<[[f64; 2]; 2]>,
}

/// Signed determinant of the direct Jacobian with rows `(e_i, ((r_i - r_bar) x e_i) / L)`
/// normalised to unit length, as in [`flexprr_kinematics::SingularityMeasures`] but keeping
/// the sign, so that its zero set can be contoured.
fn signed_type_ii(legs: &[LegPosition; 3]) -> f64 {
    let centroid = (legs[0].r + legs[1].r + legs[2].r) / 3.0;
    let radius = legs
        .iter()
        .map(|l| (l.r - centroid).norm())
        .fold(0.0, f64::max);
    let rows: Vec<[f64; 3]> = legs
        .iter()
        .map(|l| {
            let rel = l.r - centroid;
            let moment = (rel.x * l.e.y - rel.y * l.e.x) / radius;
            let norm = (l.e.norm_squared() + moment * moment).sqrt();
            [l.e.x / norm, l.e.y / norm, moment / norm]
        })
        .collect();
    let [a, b, c] = [rows[0], rows[1], rows[2]];
    a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
        + a[2] * (b[0] * c[1] - b[1] * c[0])
}

/// Marching squares (Lorensen & Cline 1987, in 2D): the pieces of the zero set of the
/// node values `f` on the grid, linearly interpolated along cell edges; cells with a
/// `false` in `mask` at a corner are skipped. A saddle cell (four crossings) is split by
/// the sign of its centre value.
fn contour(x: &[f64], y: &[f64], f: &[f64], mask: Option<&[bool]>) -> Vec<[[f64; 2]; 2]> {
    let nx = x.len();
    let mut pieces = Vec::new();
    for iy in 0..y.len() - 1 {
        for ix in 0..nx - 1 {
            let id = [
                iy * nx + ix,
                iy * nx + ix + 1,
                (iy + 1) * nx + ix + 1,
                (iy + 1) * nx + ix,
            ];
            if mask.is_some_and(|m| id.iter().any(|&i| !m[i])) {
                continue;
            }
            let corner = [
                [x[ix], y[iy]],
                [x[ix + 1], y[iy]],
                [x[ix + 1], y[iy + 1]],
                [x[ix], y[iy + 1]],
            ];
            let v = id.map(|i| f[i]);
            let mut crossings = Vec::with_capacity(4);
            for e in 0..4 {
                let (a, b) = (e, (e + 1) % 4);
                if (v[a] < 0.0) != (v[b] < 0.0) {
                    let s = v[a] / (v[a] - v[b]);
                    crossings.push([
                        corner[a][0] + s * (corner[b][0] - corner[a][0]),
                        corner[a][1] + s * (corner[b][1] - corner[a][1]),
                    ]);
                }
            }
            match crossings.len() {
                2 => pieces.push([crossings[0], crossings[1]]),
                4 => {
                    let centre = v.iter().sum::<f64>() / 4.0;
                    if (centre < 0.0) == (v[0] < 0.0) {
                        pieces.push([crossings[0], crossings[1]]);
                        pieces.push([crossings[2], crossings[3]]);
                    } else {
                        pieces.push([crossings[3], crossings[0]]);
                        pieces.push([crossings[1], crossings[2]]);
                    }
                }
                _ => {}
            }
        }
    }
    pieces
}

/// The workspace section of `geometry` at orientation `phi` on an `n x n` grid over the
/// box `x_range x y_range` (m).
///
/// A node is reachable when the closed-form inverse kinematics assembles every leg on its
/// branch and every slider lies in its travel. The boundary is the zero contour of the
/// smallest travel margin (negative shortfall where a leg does not assemble); the locus is
/// the zero contour of the signed type-II determinant over cells with four reachable
/// corners.
pub fn workspace_section(
    geometry: &Geometry,
    phi: f64,
    x_range: (f64, f64),
    y_range: (f64, f64),
    n: usize,
) -> WorkspaceSection {
    let n = n.max(3);
    let axis = |(a, b): (f64, f64)| -> Vec<f64> {
        (0..n)
            .map(|i| a + (b - a) * i as f64 / (n - 1) as f64)
            .collect()
    };
    let (x, y) = (axis(x_range), axis(y_range));
    let mut reachable = Vec::with_capacity(n * n);
    let mut margin = Vec::with_capacity(n * n);
    let mut det = Vec::with_capacity(n * n);
    for &py in &y {
        for &px in &x {
            match geometry.inverse_position(&Pose::new(px, py, phi)) {
                Ok(legs) => {
                    let m = (0..3)
                        .map(|i| geometry.legs[i].guide.travel_margin(legs[i].rho))
                        .fold(f64::INFINITY, f64::min);
                    reachable.push(m >= 0.0);
                    margin.push(m);
                    det.push(signed_type_ii(&legs));
                }
                Err(KinematicsError::Unreachable { shortfall, .. }) => {
                    reachable.push(false);
                    margin.push(-shortfall.abs().max(1e-9));
                    det.push(0.0);
                }
                Err(_) => {
                    reachable.push(false);
                    margin.push(-1e-9);
                    det.push(0.0);
                }
            }
        }
    }
    let boundary = contour(&x, &y, &margin, None);
    let locus = contour(&x, &y, &det, Some(&reachable));
    WorkspaceSection {
        phi,
        x,
        y,
        reachable,
        boundary,
        locus,
    }
}

const INK: Color = Color(34, 34, 34);
const GUIDE: Color = Color(150, 150, 150);
const WORKSPACE: Color = Color(205, 222, 245);
const WORKSPACE_EDGE: Color = Color(120, 150, 200);
const LOCUS: Color = Color(200, 30, 30);
const LOCUS_REFERENCE: Color = Color(235, 150, 150);
const PATH: Color = Color(31, 95, 191);
const PLATFORM: Color = Color(250, 220, 120);
const PLATFORM_EDGE: Color = Color(107, 82, 0);
/// The piezoelectric patches' band on the links.
const PATCH: Color = Color(142, 68, 173);
const LINK_COLORS: [Color; 3] = [Color(31, 119, 180), Color(217, 95, 2), Color(44, 160, 44)];

/// A polyline through `points` (px), `width` px wide, dashed `dash` (an SVG dash array) if
/// given.
fn line(out: &mut String, points: &[(f64, f64)], c: Color, width: f64, dash: Option<&str>) {
    let mut d = String::new();
    for (k, (x, y)) in points.iter().enumerate() {
        let sep = if k == 0 { "" } else { " " };
        let _ = write!(d, "{sep}{x:.1},{y:.1}");
    }
    let dash = dash.map_or(String::new(), |a| format!(" stroke-dasharray=\"{a}\""));
    let _ = writeln!(
        out,
        "<polyline points=\"{d}\" fill=\"none\" stroke=\"{}\" stroke-width=\"{width}\" \
         stroke-linejoin=\"round\" stroke-linecap=\"round\"{dash}/>",
        color(c)
    );
}

/// A closed polygon through `points` (px), filled with `fill` (none if `None`), outlined in
/// `edge` 1 px wide.
/// A thick polyline with square-cut ends, exactly as long as `points` (the patches' band).
fn band(out: &mut String, points: &[(f64, f64)], c: Color, width: f64) {
    let mut d = String::new();
    for (k, (x, y)) in points.iter().enumerate() {
        let sep = if k == 0 { "" } else { " " };
        let _ = write!(d, "{sep}{x:.1},{y:.1}");
    }
    let _ = writeln!(
        out,
        "<polyline points=\"{d}\" fill=\"none\" stroke=\"{}\" stroke-width=\"{width}\" \
         stroke-linejoin=\"round\" stroke-linecap=\"butt\"/>",
        color(c)
    );
}

fn polygon(out: &mut String, points: &[(f64, f64)], fill: Option<Color>, edge: Color) {
    let mut d = String::new();
    for (k, (x, y)) in points.iter().enumerate() {
        let sep = if k == 0 { "" } else { " " };
        let _ = write!(d, "{sep}{x:.1},{y:.1}");
    }
    let fill = fill.map_or("none".to_string(), color);
    let _ = writeln!(
        out,
        "<polygon points=\"{d}\" fill=\"{fill}\" stroke=\"{}\" stroke-width=\"1\" \
         stroke-linejoin=\"round\"/>",
        color(edge)
    );
}

/// A filled rectangle between the corners `a` and `b` (px).
fn rect(out: &mut String, a: (f64, f64), b: (f64, f64), fill: Color) {
    let _ = writeln!(
        out,
        "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"{:.1}\" height=\"{:.1}\" fill=\"{}\"/>",
        a.0.min(b.0),
        a.1.min(b.1),
        (b.0 - a.0).abs(),
        (b.1 - a.1).abs(),
        color(fill)
    );
}

/// A filled disc of radius `r` at `(x, y)` (px).
fn disc(out: &mut String, (x, y): (f64, f64), r: f64, fill: Color) {
    let _ = writeln!(
        out,
        "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"{r}\" fill=\"{}\"/>",
        color(fill)
    );
}

/// Bounding box of the guides' travel ends.
fn guide_box(geometry: &Geometry) -> ((f64, f64), (f64, f64)) {
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for leg in &geometry.legs {
        for r in [leg.guide.travel.0, leg.guide.travel.1] {
            let p = leg.guide.slider_point(r);
            x0 = x0.min(p.x);
            x1 = x1.max(p.x);
            y0 = y0.min(p.y);
            y1 = y1.max(p.y);
        }
    }
    ((x0, x1), (y0, y1))
}

/// One entry of a legend drawn in its own column, outside the data.
enum Key {
    Fill(Color),
    Line(Color, f64),
}

/// The legend `entries` in a column at `x`, the first row's centre line at `top` (px),
/// `row` px apart.
fn column_legend(out: &mut String, (x, top): (f64, f64), row: f64, entries: &[(Key, String)]) {
    for (k, (key, label)) in entries.iter().enumerate() {
        let y = top + row * k as f64;
        match key {
            Key::Fill(c) => rect(out, (x, y - 6.0), (x + 28.0, y + 6.0), *c),
            Key::Line(c, w) => line(out, &[(x, y), (x + 28.0, y)], *c, *w, None),
        }
        text(
            out,
            (x + 36.0, y + 0.35 * FONT_LABEL),
            FONT_LABEL,
            "start",
            label,
        );
    }
}

/// `machine.svg`: the guides with their travel stops, the reachable workspace of the
/// platform reference point at the orientation of the path's first pose with its type-II
/// singularity locus, the path, and the machine (rigid links, sliders, platform) at the
/// first pose. Axes in millimetres with equal scales (the plot module's axes); the title
/// and the legend sit in their own column on the right.
///
/// `path` holds platform poses `(x, y, phi)` (m, m, rad); `grid` is the number of nodes
/// per axis of the workspace section (e.g. 241).
///
/// # Errors
/// An empty path, or a first pose the machine cannot assemble in.
pub fn machine_svg(
    geometry: &Geometry,
    path: &[[f64; 3]],
    title: &str,
    grid: usize,
) -> Result<String, ViewerError> {
    let first = *path.first().ok_or_else(|| ViewerError::Length {
        field: "path".into(),
        found: 0,
        expected: 1,
    })?;
    let legs = geometry
        .inverse_position(&Pose::new(first[0], first[1], first[2]))
        .map_err(|e| ViewerError::Figure(format!("machine at the first pose of the path: {e}")))?;
    let ((x0, x1), (y0, y1)) = guide_box(geometry);
    let half = 0.5 * (x1 - x0).max(y1 - y0) * 1.06;
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let window = ((cx - half, cx + half), (cy - half, cy + half));
    let section = workspace_section(geometry, first[2], window.0, window.1, grid);
    // None in this section: show where it lies at phi = 0 for reference (the paper's
    // radial layout is type-II singular at its home pose).
    let reference = if section.locus.is_empty() {
        workspace_section(geometry, 0.0, window.0, window.1, grid).locus
    } else {
        Vec::new()
    };

    let (width, height, side) = (960.0, 700.0, 700.0);
    let axes = Axes::fit(
        Area {
            left: 8.0,
            top: 10.0,
            width: side - 16.0,
            height: height - 16.0,
        },
        (&Axis::new("x", "m"), window.0),
        (&Axis::new("y", "m"), window.1),
        true,
    );
    let mut svg = String::new();
    open(
        &mut svg,
        width,
        height,
        title,
        Some("flexprr machine figure: guides, reachable workspace, type-II locus, path"),
    );
    axes.draw_with_clip(&mut svg, "machine");
    let _ = writeln!(svg, "<g clip-path=\"url(#machine)\">");
    draw_workspace(&mut svg, &axes, &section, &reference);
    draw_guides(&mut svg, &axes, geometry);
    // At most 2000 points of the path (uniform stride, ends kept) keep the file small.
    let path_px: Vec<(f64, f64)> = frame_indices(path.len(), 2000)
        .into_iter()
        .map(|k| axes.to_px(path[k][0], path[k][1]))
        .collect();
    line(&mut svg, &path_px, PATH, 2.0, None);
    draw_machine(&mut svg, &axes, &legs);
    let _ = writeln!(svg, "</g>");
    machine_legend(
        &mut svg,
        (side + 12.0, width - side - 20.0),
        title,
        first[2],
        section.locus.is_empty(),
    );
    close(&mut svg);
    Ok(svg)
}

/// The reachable workspace (horizontal runs of reachable grid cells, one rectangle each,
/// all in one path so that no seam shows between rows), its boundary, the type-II locus in
/// it and, when it has none, the `reference` locus.
fn draw_workspace(
    out: &mut String,
    axes: &Axes,
    section: &WorkspaceSection,
    reference: &[[[f64; 2]; 2]],
) {
    let nx = section.x.len();
    let dx = section.x[1] - section.x[0];
    let dy = section.y[1] - section.y[0];
    let mut d = String::new();
    for (iy, &y) in section.y.iter().enumerate() {
        let mut ix = 0;
        while ix < nx {
            if !section.reachable[iy * nx + ix] {
                ix += 1;
                continue;
            }
            let start = ix;
            while ix < nx && section.reachable[iy * nx + ix] {
                ix += 1;
            }
            let (x0, y0) = axes.to_px(section.x[start] - 0.5 * dx, y - 0.5 * dy);
            let (x1, y1) = axes.to_px(section.x[ix - 1] + 0.5 * dx, y + 0.5 * dy);
            let _ = write!(d, "M{x0:.1} {y0:.1}H{x1:.1}V{y1:.1}H{x0:.1}Z");
        }
    }
    let _ = writeln!(out, "<path d=\"{d}\" fill=\"{}\"/>", color(WORKSPACE));
    // Each set of contour pieces as one path.
    let pieces = |out: &mut String, pieces: &[[[f64; 2]; 2]], c: Color, w: f64| {
        if pieces.is_empty() {
            return;
        }
        let mut d = String::new();
        for s in pieces {
            let (a, b) = (axes.to_px(s[0][0], s[0][1]), axes.to_px(s[1][0], s[1][1]));
            let _ = write!(d, "M{:.1} {:.1}L{:.1} {:.1}", a.0, a.1, b.0, b.1);
        }
        let _ = writeln!(
            out,
            "<path d=\"{d}\" fill=\"none\" stroke=\"{}\" stroke-width=\"{w}\" \
             stroke-linecap=\"round\"/>",
            color(c)
        );
    };
    pieces(out, &section.boundary, WORKSPACE_EDGE, 1.0);
    pieces(out, &section.locus, LOCUS, 2.0);
    pieces(out, reference, LOCUS_REFERENCE, 1.0);
}

/// The guides, from travel stop to travel stop, with a short bar across each stop.
fn draw_guides(out: &mut String, axes: &Axes, geometry: &Geometry) {
    for leg in &geometry.legs {
        let g = &leg.guide;
        let (a, b) = (g.slider_point(g.travel.0), g.slider_point(g.travel.1));
        line(
            out,
            &[axes.to_px(a.x, a.y), axes.to_px(b.x, b.y)],
            GUIDE,
            5.0,
            None,
        );
        let v = [-g.direction.y * 0.008, g.direction.x * 0.008];
        for end in [a, b] {
            let bar = [
                axes.to_px(end.x - v[0], end.y - v[1]),
                axes.to_px(end.x + v[0], end.y + v[1]),
            ];
            line(out, &bar, INK, 2.0, None);
        }
    }
}

/// The rigid machine at one pose: the links (in the link colours), the sliders (discs at
/// the slider joints) and the platform.
fn draw_machine(out: &mut String, axes: &Axes, legs: &[LegPosition; 3]) {
    for (i, leg) in legs.iter().enumerate() {
        let ends = [axes.to_px(leg.b.x, leg.b.y), axes.to_px(leg.c.x, leg.c.y)];
        line(out, &ends, LINK_COLORS[i], 4.0, None);
        disc(out, ends[0], 5.0, INK);
    }
    let corners: Vec<(f64, f64)> = legs.iter().map(|l| axes.to_px(l.c.x, l.c.y)).collect();
    polygon(out, &corners, Some(PLATFORM), PLATFORM_EDGE);
}

/// The right-hand column of `machine.svg` at `x`, `width` px wide: the title, the legend
/// and, when the section at `phi` has no type-II locus (`no_locus`), a note saying so.
fn machine_legend(out: &mut String, (x, width): (f64, f64), title: &str, phi: f64, no_locus: bool) {
    let title_lines = wrap(title, width, FONT_TITLE);
    for (k, line) in title_lines.iter().enumerate() {
        let y = 28.0 + 1.25 * FONT_TITLE * k as f64;
        text(out, (x, y), FONT_TITLE, "start", line);
    }
    let phi_deg = phi.to_degrees();
    let locus = if no_locus {
        (
            Key::Line(LOCUS_REFERENCE, 1.0),
            "type-II locus at \u{3c6} = 0\u{b0}".to_string(),
        )
    } else {
        (
            Key::Line(LOCUS, 2.0),
            format!("type-II singularity, \u{3c6} = {phi_deg:.0}\u{b0}"),
        )
    };
    let entries = [
        (
            Key::Fill(WORKSPACE),
            format!("reachable, \u{3c6} = {phi_deg:.0}\u{b0}"),
        ),
        locus,
        (Key::Line(GUIDE, 5.0), "guide, travel stops".into()),
        (Key::Line(PATH, 2.0), "path of the platform".into()),
        (Key::Line(LINK_COLORS[0], 4.0), "links 1, 2, 3".into()),
        (Key::Fill(PLATFORM), "platform, sliders \u{25cf}".into()),
    ];
    let top = 40.0 + 1.25 * FONT_TITLE * title_lines.len() as f64;
    column_legend(out, (x, top), 24.0, &entries);
    if no_locus {
        let note =
            format!("No type-II singularity in the reachable set at \u{3c6} = {phi_deg:.0}\u{b0}.");
        let y = top + 24.0 * entries.len() as f64 + 8.0;
        for (k, line) in wrap(&note, width, FONT_LEGEND).iter().enumerate() {
            text(
                out,
                (x, y + 1.3 * FONT_LEGEND * k as f64),
                FONT_LEGEND,
                "start",
                line,
            );
        }
    }
}

/// Index of the frame nearest to `t`.
fn nearest_frame(time: &[f64], t: f64) -> usize {
    let k = time.partition_point(|&s| s < t);
    if k == 0 {
        0
    } else if k == time.len() || t - time[k - 1] <= time[k] - t {
        k - 1
    } else {
        k
    }
}

/// An amplification factor as text: whole numbers from 10 on, else 3 significant digits.
fn amplification_text(a: f64) -> String {
    if a >= 10.0 {
        format!("{a:.0}")
    } else {
        let decimals = (2.0 - a.log10().floor()).max(0.0) as usize;
        format!("{a:.decimals$}")
    }
}

/// A 1-2-5 number near `value` (for amplification factors).
fn round_125(value: f64) -> f64 {
    let magnitude = 10f64.powf(value.log10().floor());
    let f = value / magnitude;
    let step = if f < 1.5 {
        1.0
    } else if f < 3.5 {
        2.0
    } else if f < 7.5 {
        5.0
    } else {
        10.0
    };
    step * magnitude
}

/// One instant of `snapshots.svg` (m): slider joints B, platform joints C and the deformed
/// centre lines, deflections amplified.
struct Shape {
    b: [[f64; 2]; 3],
    c: [[f64; 2]; 3],
    lines: [Vec<[f64; 2]>; 3],
    /// Per link, the deformed centre line over each piezoelectric patch.
    patches: [Vec<Vec<[f64; 2]>>; 3],
}

impl Shape {
    /// The machine at frame `k` of `data` (the platform moved by the coupled model's
    /// deviation when there is one), each link's centre line deflected `amp` times its
    /// deflection normal to its chord (the paper's eq. 1 along the chord B-C).
    fn at(data: &ViewerData, k: usize, amp: f64) -> Self {
        let mut p = data.pose[k];
        if let Some(dev) = &data.deviation {
            for (a, d) in p.iter_mut().zip(dev[k]) {
                *a += d;
            }
        }
        let (s, co) = p[2].sin_cos();
        let b: [[f64; 2]; 3] = std::array::from_fn(|i| {
            let g = &data.guides[i];
            let rho = data.sliders[k][i];
            [
                g.anchor[0] + rho * g.direction[0],
                g.anchor[1] + rho * g.direction[1],
            ]
        });
        let c: [[f64; 2]; 3] = std::array::from_fn(|i| {
            let a = data.attachments[i];
            [p[0] + co * a[0] - s * a[1], p[1] + s * a[0] + co * a[1]]
        });
        // The point at `xi` of link `i`'s deflected centre line, `w` its deflection.
        let point = |i: usize, xi: f64, w: f64| {
            let (dx, dy) = (c[i][0] - b[i][0], c[i][1] - b[i][1]);
            let chord = dx.hypot(dy);
            let (e, n) = ([dx / chord, dy / chord], [-dy / chord, dx / chord]);
            [
                b[i][0] + xi * chord * e[0] + amp * w * n[0],
                b[i][1] + xi * chord * e[1] + amp * w * n[1],
            ]
        };
        let lines = std::array::from_fn(|i| {
            let link = &data.links[i];
            link.xi
                .iter()
                .enumerate()
                .map(|(j, &xi)| point(i, xi, link.deflection(k, j)))
                .collect()
        });
        let patches = std::array::from_fn(|i| {
            let link = &data.links[i];
            link.patches
                .iter()
                .map(|&(start, end)| {
                    let inside = link
                        .xi
                        .iter()
                        .enumerate()
                        .filter(|(_, x)| **x > start && **x < end)
                        .map(|(j, &x)| point(i, x, link.deflection(k, j)));
                    std::iter::once(point(i, start, link.deflection_at(k, start)))
                        .chain(inside)
                        .chain(std::iter::once(point(i, end, link.deflection_at(k, end))))
                        .collect()
                })
                .collect()
        });
        Self {
            b,
            c,
            lines,
            patches,
        }
    }
}

/// The amplification of `snapshots.svg`: `requested`, or a 1-2-5 number making the largest
/// deflection in `frames` about a tenth of the shortest link (1 when nothing deflects).
///
/// # Errors
/// A requested amplification that is not finite and positive.
fn amplification(
    data: &ViewerData,
    frames: &[usize],
    requested: Option<f64>,
) -> Result<f64, ViewerError> {
    if let Some(a) = requested {
        if !(a.is_finite() && a > 0.0) {
            return Err(ViewerError::Invalid {
                field: "amplification".into(),
                index: 0,
                value: a,
                reason: "must be finite and positive",
            });
        }
        return Ok(a);
    }
    let mut max_w: f64 = 0.0;
    for &k in frames {
        for link in &data.links {
            for j in 0..link.xi.len() {
                max_w = max_w.max(link.deflection(k, j).abs());
            }
        }
    }
    let min_length = data.links.iter().map(|l| l.length).fold(f64::MAX, f64::min);
    Ok(if max_w > 0.0 {
        round_125(0.1 * min_length / max_w)
    } else {
        1.0
    })
}

/// Width of one panel of `snapshots.svg` (px).
const PANEL_W: f64 = 330.0;
/// Height of one panel of `snapshots.svg`, caption included (px).
const PANEL_H: f64 = 360.0;
/// Height of the title above the panels and of the key below them (px).
const BAND: f64 = 40.0;

/// `snapshots.svg`: the deformed links at the frames nearest to `times`, one panel each,
/// with a common amplification (a 1-2-5 number making the largest deflection in the
/// shown frames about a tenth of the shortest link; `amplification` overrides it). Each
/// panel shows the undeformed chords dashed, the deformed centre lines from the scene's
/// mode shapes (with a purple band over each piezoelectric patch), sliders and platform, on the plot module's axes in millimetres with equal
/// scales, the same window in every panel.
///
/// # Errors
/// Invalid `data`, no `times`, or an amplification that is not finite and positive.
pub fn snapshots_svg(
    data: &ViewerData,
    times: &[f64],
    amplification_factor: Option<f64>,
) -> Result<String, ViewerError> {
    data.validate()?;
    if times.is_empty() {
        return Err(ViewerError::Length {
            field: "times".into(),
            found: 0,
            expected: 1,
        });
    }
    let frames: Vec<usize> = times
        .iter()
        .map(|&t| nearest_frame(&data.time, t))
        .collect();
    let amp = amplification(data, &frames, amplification_factor)?;
    let shapes: Vec<Shape> = frames.iter().map(|&k| Shape::at(data, k, amp)).collect();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for p in shapes.iter().flat_map(|s| s.b.iter().chain(&s.c)) {
        x0 = x0.min(p[0]);
        x1 = x1.max(p[0]);
        y0 = y0.min(p[1]);
        y1 = y1.max(p[1]);
    }
    let half = 0.5 * (x1 - x0).max(y1 - y0) * 1.2;
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let window = ((cx - half, cx + half), (cy - half, cy + half));

    let width = PANEL_W * shapes.len() as f64;
    let height = BAND + PANEL_H + BAND;
    let title = format!(
        "{}: deformed links, deflection drawn \u{d7}{}",
        data.title,
        amplification_text(amp)
    );
    let mut svg = String::new();
    open(
        &mut svg,
        width,
        height,
        &title,
        Some("flexprr snapshots: deformed links at a few instants"),
    );
    text(
        &mut svg,
        (12.0, 8.0 + FONT_TITLE),
        FONT_TITLE,
        "start",
        &title,
    );
    for (index, shape) in shapes.iter().enumerate() {
        let caption = format!(
            "({}) t = {}",
            char::from(b'a' + (index % 26) as u8),
            value_label(data.time[frames[index]], "s")
        );
        draw_snapshot(&mut svg, index, shape, &caption, window);
    }
    let patches = data.links.iter().any(|l| !l.patches.is_empty());
    snapshot_key(&mut svg, BAND + PANEL_H + 0.5 * BAND, patches);
    close(&mut svg);
    Ok(svg)
}

/// Panel `index` of `snapshots.svg`: its caption, the axes over `window` (m) and the shape.
fn draw_snapshot(
    out: &mut String,
    index: usize,
    shape: &Shape,
    caption: &str,
    window: ((f64, f64), (f64, f64)),
) {
    let left = PANEL_W * index as f64;
    let caption_h = FONT_LABEL + 10.0;
    text(
        out,
        (left + 0.5 * PANEL_W, BAND + FONT_LABEL),
        FONT_LABEL,
        "middle",
        caption,
    );
    let axes = Axes::fit(
        Area {
            left: left + 4.0,
            top: BAND + caption_h,
            width: PANEL_W - 12.0,
            height: PANEL_H - caption_h - 4.0,
        },
        (&Axis::new("x", "m"), window.0),
        (&Axis::new("y", "m"), window.1),
        true,
    );
    let clip = format!("snapshot{index}");
    axes.draw_with_clip(out, &clip);
    let _ = writeln!(out, "<g clip-path=\"url(#{clip})\">");
    let px = |p: [f64; 2]| axes.to_px(p[0], p[1]);
    for i in 0..3 {
        line(
            out,
            &[px(shape.b[i]), px(shape.c[i])],
            GUIDE,
            1.0,
            Some("4 4"),
        );
        for band in &shape.patches[i] {
            let band: Vec<(f64, f64)> = band.iter().map(|&p| px(p)).collect();
            self::band(out, &band, PATCH, 7.0);
        }
        let centre: Vec<(f64, f64)> = shape.lines[i].iter().map(|&p| px(p)).collect();
        line(out, &centre, INK, 2.0, None);
        let (x, y) = px(shape.b[i]);
        rect(out, (x - 4.0, y - 4.0), (x + 4.0, y + 4.0), INK);
    }
    let platform: Vec<(f64, f64)> = shape.c.iter().map(|&p| px(p)).collect();
    polygon(out, &platform, None, INK);
    let _ = writeln!(out, "</g>");
}

/// The key below the panels of `snapshots.svg`, its centre line at `y` (px), with the
/// patches' band when there are `patches`.
fn snapshot_key(out: &mut String, y: f64, patches: bool) {
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
        x += 36.0 + text_width(label, FONT_LEGEND) + 28.0;
    };
    entry(
        out,
        &|out, x| line(out, &[(x, y), (x + 28.0, y)], INK, 2.0, None),
        "deformed centre line",
    );
    entry(
        out,
        &|out, x| line(out, &[(x, y), (x + 28.0, y)], GUIDE, 1.0, Some("4 4")),
        "undeformed chord",
    );
    entry(
        out,
        &|out, x| rect(out, (x + 10.0, y - 4.0), (x + 18.0, y + 4.0), INK),
        "slider; triangle: platform",
    );
    if patches {
        entry(
            out,
            &|out, x| band(out, &[(x, y), (x + 28.0, y)], PATCH, 7.0),
            "piezo patch",
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn amplification_labels() {
        assert_eq!(amplification_text(2000.0), "2000");
        assert_eq!(amplification_text(5.0), "5.00");
        assert_eq!(amplification_text(0.5), "0.500");
    }

    #[test]
    fn one_two_five() {
        assert!((round_125(0.93) - 1.0).abs() < 1e-12);
        assert!((round_125(180.0) - 200.0).abs() < 1e-9);
        assert!((round_125(4.1e3) - 5e3).abs() < 1e-6);
    }

    /// Marching squares on the plane `f = x - 0.3` gives pieces on the line `x = 0.3`
    /// that together span the grid's height.
    #[test]
    fn contour_of_a_plane() {
        let axis: Vec<f64> = (0..11).map(|i| i as f64 / 10.0).collect();
        let f: Vec<f64> = axis
            .iter()
            .flat_map(|_| axis.iter().map(|x| x - 0.33))
            .collect();
        let pieces = contour(&axis, &axis, &f, None);
        assert_eq!(pieces.len(), 10);
        for p in &pieces {
            assert!((p[0][0] - 0.33).abs() < 1e-12 && (p[1][0] - 0.33).abs() < 1e-12);
        }
        let length: f64 = pieces.iter().map(|p| (p[1][1] - p[0][1]).abs()).sum();
        assert!((length - 1.0).abs() < 1e-12);
    }
}
