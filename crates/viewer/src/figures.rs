//! Static figures: the machine with its reachable workspace and type-II singularity locus
//! (`machine.svg`), and the deformed links at a few instants (`snapshots.svg`).

use flexprr_kinematics::{Geometry, KinematicsError, Pose};
use plotters::coord::Shift;
use plotters::prelude::*;

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
fn signed_type_ii(legs: &[flexprr_kinematics::LegPosition; 3]) -> f64 {
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

const INK: RGBColor = RGBColor(34, 34, 34);
const GUIDE: RGBColor = RGBColor(150, 150, 150);
const WORKSPACE: RGBColor = RGBColor(205, 222, 245);
const LOCUS: RGBColor = RGBColor(200, 30, 30);
const LOCUS_REFERENCE: RGBColor = RGBColor(235, 150, 150);
const PATH: RGBColor = RGBColor(31, 95, 191);
const PLATFORM: RGBColor = RGBColor(250, 220, 120);
const LINK_COLORS: [RGBColor; 3] = [
    RGBColor(31, 119, 180),
    RGBColor(217, 95, 2),
    RGBColor(44, 160, 44),
];

fn figure_error(e: impl std::fmt::Display) -> ViewerError {
    ViewerError::Figure(e.to_string())
}

/// Millimetres, the unit of the static figures' axes.
fn mm(p: [f64; 2]) -> (f64, f64) {
    (1e3 * p[0], 1e3 * p[1])
}

/// Axis tick label in whole millimetres with a Unicode minus.
fn mm_label(v: &f64) -> String {
    if v.abs() < 0.5 {
        "0".into()
    } else {
        format!("{v:.0}").replace('-', "\u{2212}")
    }
}

/// `value` in engineering notation with an SI prefix, e.g. `12.5 ms`.
fn si(value: f64, unit: &str) -> String {
    if value.abs() < f64::MIN_POSITIVE || !value.is_finite() {
        return format!("0 {unit}");
    }
    let exponent = ((value.abs().log10() / 3.0).floor() * 3.0).clamp(-9.0, 6.0) as i32;
    let prefix = match exponent {
        -9 => "n",
        -6 => "\u{b5}",
        -3 => "m",
        3 => "k",
        6 => "M",
        _ => "",
    };
    let scaled = value / 10f64.powi(exponent);
    let text = format!("{scaled:.3}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    format!("{} {prefix}{unit}", text.replace('-', "\u{2212}"))
}

/// One entry of a legend drawn in its own column, outside the data.
enum Key {
    Fill(RGBColor),
    Line(RGBColor, u32),
}

fn draw_legend(
    area: &DrawingArea<SVGBackend<'_>, Shift>,
    top: i32,
    entries: &[(Key, String)],
) -> Result<(), ViewerError> {
    let font = ("sans-serif", 15).into_font().color(&INK);
    for (k, (key, label)) in entries.iter().enumerate() {
        let y = top + 24 * k as i32;
        match key {
            Key::Fill(c) => area
                .draw(&Rectangle::new(
                    [(8, y - 6), (36, y + 6)],
                    c.filled().stroke_width(1),
                ))
                .map_err(figure_error)?,
            Key::Line(c, w) => area
                .draw(&PathElement::new(vec![(8, y), (36, y)], c.stroke_width(*w)))
                .map_err(figure_error)?,
        }
        area.draw(&Text::new(label.clone(), (44, y - 8), font.clone()))
            .map_err(figure_error)?;
    }
    Ok(())
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

/// `machine.svg`: the guides with their travel stops, the reachable workspace of the
/// platform reference point at the orientation of the path's first pose with its type-II
/// singularity locus, the path, and the machine (rigid links, sliders, platform) at the
/// first pose. Axes in millimetres, equal scales; the legend sits in its own column.
///
/// `path` holds platform poses `(x, y, phi)` (m, m, rad); `grid` is the number of nodes
/// per axis of the workspace section (e.g. 241).
///
/// # Errors
/// An empty path, a first pose the machine cannot assemble in, or a drawing failure.
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
    let section = workspace_section(
        geometry,
        first[2],
        (cx - half, cx + half),
        (cy - half, cy + half),
        grid,
    );

    let (width, height, side) = (960u32, 700u32, 700u32);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(figure_error)?;
        let (left, right) = root.split_horizontally(side);
        let (margin, x_area, y_area) = (14u32, 46u32, 62u32);
        // Equal scales: stretch the x range to the plotting area's aspect ratio.
        let plot_w = f64::from(side - 2 * margin - y_area);
        let plot_h = f64::from(height - 2 * margin - x_area);
        let half_x = half * plot_w / plot_h;
        let mut chart = ChartBuilder::on(&left)
            .margin(margin)
            .x_label_area_size(x_area)
            .y_label_area_size(y_area)
            .build_cartesian_2d(
                1e3 * (cx - half_x)..1e3 * (cx + half_x),
                1e3 * (cy - half)..1e3 * (cy + half),
            )
            .map_err(figure_error)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("x [mm]")
            .y_desc("y [mm]")
            .x_label_formatter(&mm_label)
            .y_label_formatter(&mm_label)
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .draw()
            .map_err(figure_error)?;

        // Reachable workspace: horizontal runs of reachable nodes, one rectangle each.
        let nx = section.x.len();
        let dx = section.x[1] - section.x[0];
        let dy = section.y[1] - section.y[0];
        let mut runs = Vec::new();
        for (iy, &y) in section.y.iter().enumerate() {
            let mut ix = 0;
            while ix < nx {
                if section.reachable[iy * nx + ix] {
                    let start = ix;
                    while ix < nx && section.reachable[iy * nx + ix] {
                        ix += 1;
                    }
                    runs.push(Rectangle::new(
                        [
                            mm([section.x[start] - 0.5 * dx, y - 0.5 * dy]),
                            mm([section.x[ix - 1] + 0.5 * dx, y + 0.5 * dy]),
                        ],
                        WORKSPACE.filled(),
                    ));
                } else {
                    ix += 1;
                }
            }
        }
        chart.draw_series(runs).map_err(figure_error)?;
        chart
            .draw_series(section.boundary.iter().map(|s| {
                PathElement::new(
                    vec![mm(s[0]), mm(s[1])],
                    RGBColor(120, 150, 200).stroke_width(1),
                )
            }))
            .map_err(figure_error)?;
        chart
            .draw_series(
                section
                    .locus
                    .iter()
                    .map(|s| PathElement::new(vec![mm(s[0]), mm(s[1])], LOCUS.stroke_width(2))),
            )
            .map_err(figure_error)?;
        // None in this section: show where it lies at phi = 0 for reference (the paper's
        // radial layout is type-II singular at its home pose).
        let reference = if section.locus.is_empty() {
            workspace_section(
                geometry,
                0.0,
                (cx - half, cx + half),
                (cy - half, cy + half),
                grid,
            )
            .locus
        } else {
            Vec::new()
        };
        chart
            .draw_series(reference.iter().map(|s| {
                PathElement::new(vec![mm(s[0]), mm(s[1])], LOCUS_REFERENCE.stroke_width(1))
            }))
            .map_err(figure_error)?;

        // Guides with travel stops.
        for leg in &geometry.legs {
            let g = &leg.guide;
            let (a, b) = (g.slider_point(g.travel.0), g.slider_point(g.travel.1));
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![mm([a.x, a.y]), mm([b.x, b.y])],
                    GUIDE.stroke_width(5),
                )))
                .map_err(figure_error)?;
            let v = [-g.direction.y * 0.008, g.direction.x * 0.008];
            for end in [a, b] {
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![
                            mm([end.x - v[0], end.y - v[1]]),
                            mm([end.x + v[0], end.y + v[1]]),
                        ],
                        INK.stroke_width(2),
                    )))
                    .map_err(figure_error)?;
            }
        }
        // Path of the platform reference point.
        // At most 2000 points of the path (uniform stride, ends kept) keep the file small.
        chart
            .draw_series(std::iter::once(PathElement::new(
                crate::decimate::frame_indices(path.len(), 2000)
                    .into_iter()
                    .map(|k| mm([path[k][0], path[k][1]]))
                    .collect::<Vec<_>>(),
                PATH.stroke_width(2),
            )))
            .map_err(figure_error)?;
        // The machine at the first pose.
        for (i, leg) in legs.iter().enumerate() {
            chart
                .draw_series(std::iter::once(PathElement::new(
                    vec![mm([leg.b.x, leg.b.y]), mm([leg.c.x, leg.c.y])],
                    LINK_COLORS[i].stroke_width(4),
                )))
                .map_err(figure_error)?;
            chart
                .draw_series(std::iter::once(Circle::new(
                    mm([leg.b.x, leg.b.y]),
                    5,
                    INK.filled(),
                )))
                .map_err(figure_error)?;
        }
        chart
            .draw_series(std::iter::once(Polygon::new(
                legs.iter().map(|l| mm([l.c.x, l.c.y])).collect::<Vec<_>>(),
                PLATFORM.filled(),
            )))
            .map_err(figure_error)?;
        chart
            .draw_series(std::iter::once(PathElement::new(
                legs.iter()
                    .chain(std::iter::once(&legs[0]))
                    .map(|l| mm([l.c.x, l.c.y]))
                    .collect::<Vec<_>>(),
                RGBColor(107, 82, 0).stroke_width(1),
            )))
            .map_err(figure_error)?;

        // Title and legend in the right-hand column.
        let title_font = ("sans-serif", 17)
            .into_font()
            .style(FontStyle::Bold)
            .color(&INK);
        right
            .draw(&Text::new(title.to_string(), (8, 20), title_font))
            .map_err(figure_error)?;
        let phi_deg = first[2].to_degrees();
        let mut entries = vec![
            (
                Key::Fill(WORKSPACE),
                format!("reachable, \u{3c6} = {phi_deg:.0}\u{b0}"),
            ),
            if section.locus.is_empty() {
                (
                    Key::Line(LOCUS_REFERENCE, 1),
                    "type-II locus at \u{3c6} = 0\u{b0}".into(),
                )
            } else {
                (
                    Key::Line(LOCUS, 2),
                    format!("type-II singularity, \u{3c6} = {phi_deg:.0}\u{b0}"),
                )
            },
        ];
        entries.extend([
            (Key::Line(GUIDE, 5), "guide, travel stops".into()),
            (Key::Line(PATH, 2), "path of the platform".into()),
            (Key::Line(LINK_COLORS[0], 4), "links 1, 2, 3".into()),
            (Key::Fill(PLATFORM), "platform, sliders \u{25cf}".into()),
        ]);
        draw_legend(&right, 80, &entries)?;
        if section.locus.is_empty() {
            let note = ("sans-serif", 13).into_font().color(&INK);
            for (k, line) in [
                "No type-II singularity in the".to_string(),
                format!("reachable set at \u{3c6} = {phi_deg:.0}\u{b0}."),
            ]
            .into_iter()
            .enumerate()
            {
                right
                    .draw(&Text::new(
                        line,
                        (8, 80 + 24 * 6 + 10 + 18 * k as i32),
                        note.clone(),
                    ))
                    .map_err(figure_error)?;
            }
        }
        root.present().map_err(figure_error)?;
    }
    Ok(svg)
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

/// `snapshots.svg`: the deformed links at the frames nearest to `times`, one panel each,
/// with a common amplification (a 1-2-5 number making the largest deflection in the
/// shown frames about a tenth of the shortest link; `amplification` overrides it). Each
/// panel shows the undeformed chords dashed, the deformed centre lines from the scene's
/// mode shapes, sliders and platform, in millimetres with equal scales.
///
/// # Errors
/// Invalid `data`, no `times`, or a drawing failure.
pub fn snapshots_svg(
    data: &ViewerData,
    times: &[f64],
    amplification: Option<f64>,
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
    let mut max_w: f64 = 0.0;
    for &k in &frames {
        for link in &data.links {
            for j in 0..link.xi.len() {
                max_w = max_w.max(link.deflection(k, j).abs());
            }
        }
    }
    if let Some(a) = amplification.filter(|a| !(a.is_finite() && *a > 0.0)) {
        return Err(ViewerError::Invalid {
            field: "amplification".into(),
            index: 0,
            value: a,
            reason: "must be finite and positive",
        });
    }
    let min_length = data.links.iter().map(|l| l.length).fold(f64::MAX, f64::min);
    let amp = amplification.unwrap_or(if max_w > 0.0 {
        round_125(0.1 * min_length / max_w)
    } else {
        1.0
    });

    // Per frame: slider joints B, platform joints C and the deformed centre lines.
    struct Shape {
        b: [[f64; 2]; 3],
        c: [[f64; 2]; 3],
        lines: [Vec<(f64, f64)>; 3],
    }
    let shapes: Vec<Shape> = frames
        .iter()
        .map(|&k| {
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
            let lines = std::array::from_fn(|i| {
                let link = &data.links[i];
                let (dx, dy) = (c[i][0] - b[i][0], c[i][1] - b[i][1]);
                let chord = dx.hypot(dy);
                let (e, n) = ([dx / chord, dy / chord], [-dy / chord, dx / chord]);
                link.xi
                    .iter()
                    .enumerate()
                    .map(|(j, &xi)| {
                        let w = amp * link.deflection(k, j);
                        mm([
                            b[i][0] + xi * chord * e[0] + w * n[0],
                            b[i][1] + xi * chord * e[1] + w * n[1],
                        ])
                    })
                    .collect()
            });
            Shape { b, c, lines }
        })
        .collect();
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for shape in &shapes {
        for p in shape.b.iter().chain(&shape.c) {
            x0 = x0.min(p[0]);
            x1 = x1.max(p[0]);
            y0 = y0.min(p[1]);
            y1 = y1.max(p[1]);
        }
    }
    let half = 0.5 * (x1 - x0).max(y1 - y0) * 1.2;
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));

    let panels = shapes.len() as u32;
    let (panel_w, panel_h, head, key_h) = (330u32, 360u32, 40u32, 40u32);
    let (width, height) = (panel_w * panels, head + panel_h + key_h);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(figure_error)?;
        let title = format!(
            "{}: deformed links, deflection drawn \u{d7}{}",
            data.title,
            amplification_text(amp)
        );
        root.draw(&Text::new(
            title,
            (12, 12),
            ("serif", 18).into_font().color(&INK),
        ))
        .map_err(figure_error)?;
        let body = root.margin(head, key_h, 0, 0);
        let areas = body.split_evenly((1, panels as usize));
        let (margin, x_area, y_area) = (8u32, 40u32, 52u32);
        for (index, (area, shape)) in areas.iter().zip(&shapes).enumerate() {
            let plot_w = f64::from(panel_w - 2 * margin - y_area);
            let plot_h = f64::from(panel_h - 2 * margin - x_area - 22);
            let half_x = half * plot_w / plot_h;
            let mut chart = ChartBuilder::on(area)
                .margin(margin)
                .caption(
                    format!(
                        "({}) t = {}",
                        char::from(b'a' + (index % 26) as u8),
                        si(data.time[frames[index]], "s")
                    ),
                    ("serif", 16),
                )
                .x_label_area_size(x_area)
                .y_label_area_size(y_area)
                .build_cartesian_2d(
                    1e3 * (cx - half_x)..1e3 * (cx + half_x),
                    1e3 * (cy - half)..1e3 * (cy + half),
                )
                .map_err(figure_error)?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_desc("x [mm]")
                .y_desc("y [mm]")
                .x_label_formatter(&mm_label)
                .y_label_formatter(&mm_label)
                .x_labels(5)
                .y_labels(5)
                .label_style(("serif", 13))
                .axis_desc_style(("serif", 14))
                .draw()
                .map_err(figure_error)?;
            for i in 0..3 {
                chart
                    .draw_series(DashedLineSeries::new(
                        vec![mm(shape.b[i]), mm(shape.c[i])],
                        4,
                        4,
                        GUIDE.stroke_width(1),
                    ))
                    .map_err(figure_error)?;
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        shape.lines[i].clone(),
                        INK.stroke_width(2),
                    )))
                    .map_err(figure_error)?;
                chart
                    .draw_series(std::iter::once(Rectangle::new(
                        [
                            (1e3 * shape.b[i][0] - 6.0, 1e3 * shape.b[i][1] - 6.0),
                            (1e3 * shape.b[i][0] + 6.0, 1e3 * shape.b[i][1] + 6.0),
                        ],
                        INK.filled(),
                    )))
                    .map_err(figure_error)?;
            }
            chart
                .draw_series(std::iter::once(PathElement::new(
                    shape
                        .c
                        .iter()
                        .chain(std::iter::once(&shape.c[0]))
                        .map(|&p| mm(p))
                        .collect::<Vec<_>>(),
                    INK.stroke_width(1),
                )))
                .map_err(figure_error)?;
        }
        let key = root.margin(head + panel_h, 0, 0, 0);
        let font = ("serif", 14).into_font().color(&INK);
        key.draw(&PathElement::new(
            vec![(16, 18), (46, 18)],
            INK.stroke_width(2),
        ))
        .map_err(figure_error)?;
        key.draw(&Text::new("deformed centre line", (52, 11), font.clone()))
            .map_err(figure_error)?;
        for x in [230, 240, 250] {
            key.draw(&PathElement::new(
                vec![(x, 18), (x + 5, 18)],
                GUIDE.stroke_width(1),
            ))
            .map_err(figure_error)?;
        }
        key.draw(&Text::new("undeformed chord", (262, 11), font.clone()))
            .map_err(figure_error)?;
        key.draw(&Rectangle::new([(410, 15), (416, 21)], INK.filled()))
            .map_err(figure_error)?;
        key.draw(&Text::new("slider; triangle: platform", (424, 11), font))
            .map_err(figure_error)?;
        root.present().map_err(figure_error)?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn si_prefixes() {
        assert_eq!(si(0.0125, "s"), "12.5 ms");
        assert_eq!(si(2.0e-5, "m"), "20 \u{b5}m");
        assert_eq!(si(-350.4, "N"), "\u{2212}350.4 N");
        assert_eq!(si(1500.0, "N"), "1.5 kN");
    }

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
