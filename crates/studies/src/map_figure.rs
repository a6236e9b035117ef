//! `map.svg`: a workspace map as a heat map on the machine's plane. Each grid pose is a cell
//! coloured by its value on a perceptually uniform scale (viridis, van der Walt & Smith
//! 2015, sampled at nine points and interpolated), singular poses grey, failed ones red,
//! poses out of reach left white; over it the reachable set's boundary and the type-II
//! singularity locus at the map's orientation (the viewer's workspace section, the same
//! drawing as `machine.svg`) and the scene's path; a colour bar and a key on the right.
//! Axes in millimetres with equal scales (the plot module's axes).

use std::fmt::Write as _;

use flexprr_kinematics::Pose;
use flexprr_linear_tools::machine_modes::{RestFrequency, sliders_description};
use flexprr_run::plot::axes::{Area, Axes};
use flexprr_run::plot::decimate::frame_indices;
use flexprr_run::plot::svg::{
    FONT_LABEL, FONT_LEGEND, FONT_TICK, FONT_TITLE, close, color, open, text, wrap,
};
use flexprr_run::plot::ticks::{linear_ticks, tick_label};
use flexprr_run::plot::{Axis, Color, FAILED_COLOR};
use flexprr_scene::Scene;

use crate::map::{Map, MapOutcome};

const INK: Color = Color(34, 34, 34);
const SINGULAR: Color = Color(160, 160, 160);
const BOUNDARY: Color = Color(20, 20, 20);
const LOCUS: Color = Color(200, 30, 30);
const PATH: Color = Color(255, 255, 255);

/// Viridis at nine equally spaced points (0, 1/8, ..., 1).
const VIRIDIS: [(u8, u8, u8); 9] = [
    (68, 1, 84),
    (71, 44, 122),
    (59, 81, 139),
    (44, 113, 142),
    (33, 144, 141),
    (39, 173, 129),
    (92, 200, 99),
    (170, 220, 50),
    (253, 231, 37),
];

/// The colour of `s` in `[0, 1]` (clamped).
fn viridis(s: f64) -> Color {
    let s = if s.is_finite() {
        s.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let u = s * (VIRIDIS.len() - 1) as f64;
    let k = (u.floor() as usize).min(VIRIDIS.len() - 2);
    let f = u - k as f64;
    let mix = |a: u8, b: u8| (f64::from(a) + f * (f64::from(b) - f64::from(a))).round() as u8;
    let (a, b) = (VIRIDIS[k], VIRIDIS[k + 1]);
    Color(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// A filled rectangle between two corners (px), widened by a third of a pixel so that
/// neighbouring cells leave no seam.
fn cell(out: &mut String, a: (f64, f64), b: (f64, f64), fill: Color) {
    let _ = writeln!(
        out,
        "<rect x=\"{:.2}\" y=\"{:.2}\" width=\"{:.2}\" height=\"{:.2}\" fill=\"{}\"/>",
        a.0.min(b.0) - 0.17,
        a.1.min(b.1) - 0.17,
        (b.0 - a.0).abs() + 0.34,
        (b.1 - a.1).abs() + 0.34,
        color(fill)
    );
}

/// Straight pieces (m) as one path of `width` px.
fn pieces(out: &mut String, axes: &Axes, pieces: &[[[f64; 2]; 2]], c: Color, width: f64) {
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
        "<path d=\"{d}\" fill=\"none\" stroke=\"{}\" stroke-width=\"{width}\" stroke-linecap=\"round\"/>",
        color(c)
    );
}

/// A polyline (px).
fn polyline(out: &mut String, points: &[(f64, f64)], c: Color, width: f64) {
    let d: Vec<String> = points
        .iter()
        .map(|(x, y)| format!("{x:.1},{y:.1}"))
        .collect();
    let _ = writeln!(
        out,
        "<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"{width}\" stroke-linejoin=\"round\"/>",
        d.join(" "),
        color(c)
    );
}

/// The value range of the found poses (a degenerate range is widened by 1 % about it).
fn value_range(outcome: &MapOutcome) -> Option<(f64, f64)> {
    let values = outcome.points.iter().filter_map(|(_, v)| match v {
        RestFrequency::Found { frequency_hz, .. } => Some(*frequency_hz),
        _ => None,
    });
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
        (l.min(v), h.max(v))
    });
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    Some(if hi > lo {
        (lo, hi)
    } else {
        (lo * 0.99, hi * 1.01 + f64::MIN_POSITIVE)
    })
}

/// Size of the figure and of the plot's square (px).
const WIDTH: f64 = 900.0;
const SIDE: f64 = 600.0;

/// `map.svg` of `outcome` for the base scene `scene`.
pub fn map_svg(map: &Map, scene: &Scene, outcome: &MapOutcome) -> String {
    let geometry = &scene.machine.geometry;
    let (dx, dy) = (map.x[1] - map.x[0], map.y[1] - map.y[0]);
    let window = (
        (map.x[0] - 0.5 * dx, map.x[map.x.len() - 1] + 0.5 * dx),
        (map.y[0] - 0.5 * dy, map.y[map.y.len() - 1] + 0.5 * dy),
    );
    let phi_deg = outcome.phi.to_degrees();
    let title =
        format!("Lowest whole-machine frequency at rest, φ = {phi_deg:.4}°").replace(".0000°", "°");
    let about = format!(
        "{}: {}; sliders {}. {} x {} poses.",
        scene.name,
        scene.model_description(),
        sliders_description(scene),
        map.x.len(),
        map.y.len()
    );
    let title_lines = wrap(&title, WIDTH - 24.0, FONT_TITLE);
    let about_lines = wrap(&about, WIDTH - 24.0, FONT_LEGEND);
    let head = 12.0
        + 1.3 * FONT_TITLE * title_lines.len() as f64
        + 1.35 * FONT_LEGEND * about_lines.len() as f64;
    let height = head + SIDE + 10.0;
    let mut svg = String::new();
    open(
        &mut svg,
        WIDTH,
        height,
        &title,
        Some("flexprr workspace map: a quantity of the machine at rest over a grid of poses"),
    );
    let mut y = 4.0;
    for line in &title_lines {
        y += 1.3 * FONT_TITLE;
        text(&mut svg, (12.0, y), FONT_TITLE, "start", line);
    }
    for line in &about_lines {
        y += 1.35 * FONT_LEGEND;
        text(&mut svg, (12.0, y), FONT_LEGEND, "start", line);
    }
    let axes = Axes::fit(
        Area {
            left: 8.0,
            top: head + 4.0,
            width: SIDE - 8.0,
            height: SIDE - 8.0,
        },
        (&Axis::new("x", "m"), window.0),
        (&Axis::new("y", "m"), window.1),
        true,
    );
    axes.draw_with_clip(&mut svg, "map");
    let _ = writeln!(svg, "<g clip-path=\"url(#map)\">");
    let range = value_range(outcome);
    for (pose, value) in &outcome.points {
        let fill = match (value, range) {
            (RestFrequency::Found { frequency_hz, .. }, Some((lo, hi))) => {
                viridis((frequency_hz - lo) / (hi - lo))
            }
            (RestFrequency::Singular(_), _) => SINGULAR,
            (RestFrequency::Failed(_), _) => FAILED_COLOR,
            _ => continue,
        };
        let a = axes.to_px(pose.x - 0.5 * dx, pose.y - 0.5 * dy);
        let b = axes.to_px(pose.x + 0.5 * dx, pose.y + 0.5 * dy);
        cell(&mut svg, a, b, fill);
    }
    let section = flexprr_viewer::workspace_section(geometry, outcome.phi, window.0, window.1, 241);
    pieces(&mut svg, &axes, &section.boundary, BOUNDARY, 1.4);
    pieces(&mut svg, &axes, &section.locus, LOCUS, 2.0);
    let path = scene_path(scene);
    let path_px: Vec<(f64, f64)> = path.iter().map(|p| axes.to_px(p.x, p.y)).collect();
    polyline(&mut svg, &path_px, INK, 4.0);
    polyline(&mut svg, &path_px, PATH, 2.0);
    let _ = writeln!(svg, "</g>");
    let area = axes.area();
    let right = SIDE + 16.0;
    let bar_top = area.top + 2.0 * FONT_LABEL;
    if let Some((lo, hi)) = range {
        colour_bar(&mut svg, (right, bar_top), area.height * 0.5, (lo, hi));
    }
    let phis: Vec<f64> = path.iter().map(|p| p.phi.to_degrees()).collect();
    key(
        &mut svg,
        (right, bar_top + area.height * 0.5 + 40.0),
        (outcome, section.locus.is_empty()),
        &phis,
    );
    close(&mut svg);
    svg
}

/// The scene's path: its platform poses at the output times (at most 2000).
fn scene_path(scene: &Scene) -> Vec<Pose> {
    frame_indices(scene.output_times.len(), 2000)
        .into_iter()
        .map(|k| scene.trajectory.motion(scene.output_times[k]).pose)
        .collect()
}

/// A vertical colour bar at `corner` (px), `height` px high, for values `lo..hi` (Hz), with
/// its ticks and title.
fn colour_bar(out: &mut String, (x, top): (f64, f64), height: f64, (lo, hi): (f64, f64)) {
    let width = 20.0;
    text(
        out,
        (x, top - 0.6 * FONT_LABEL),
        FONT_LABEL,
        "start",
        "lowest f (Hz)",
    );
    let slices = 120;
    for k in 0..slices {
        let s0 = k as f64 / slices as f64;
        let s1 = (k + 1) as f64 / slices as f64;
        let y0 = top + height * (1.0 - s1);
        let y1 = top + height * (1.0 - s0);
        cell(out, (x, y0), (x + width, y1), viridis(0.5 * (s0 + s1)));
    }
    let _ = writeln!(
        out,
        "<rect x=\"{x:.1}\" y=\"{top:.1}\" width=\"{width}\" height=\"{height:.1}\" fill=\"none\" stroke=\"{}\" stroke-width=\"1\"/>",
        color(INK)
    );
    let (ticks, step) = linear_ticks(lo, hi, 6);
    for v in ticks {
        let y = top + height * (1.0 - (v - lo) / (hi - lo));
        let _ = writeln!(
            out,
            "<line x1=\"{:.1}\" y1=\"{y:.1}\" x2=\"{:.1}\" y2=\"{y:.1}\" stroke=\"{}\" stroke-width=\"1\"/>",
            x + width,
            x + width + 5.0,
            color(INK)
        );
        text(
            out,
            (x + width + 8.0, y + 0.35 * FONT_TICK),
            FONT_TICK,
            "start",
            &tick_label(v, step),
        );
    }
}

/// The key at `corner` (px): boundary, locus (or that there is none in the section), path
/// (with its orientation `phis`, deg), singular, failed and unreachable poses with their
/// counts.
fn key(
    out: &mut String,
    (x, top): (f64, f64),
    (outcome, no_locus): (&MapOutcome, bool),
    phis: &[f64],
) {
    let row = 22.0;
    let mut y = top;
    let mut entry = |out: &mut String, sample: &dyn Fn(&mut String, f64), label: &str| {
        sample(out, y);
        text(
            out,
            (x + 34.0, y + 0.35 * FONT_LEGEND),
            FONT_LEGEND,
            "start",
            label,
        );
        y += row;
    };
    let sample_line = |c: Color, w: f64| {
        move |out: &mut String, y: f64| polyline(out, &[(x, y), (x + 26.0, y)], c, w)
    };
    let sample_cell = |c: Color| {
        move |out: &mut String, y: f64| cell(out, (x + 6.0, y - 7.0), (x + 20.0, y + 7.0), c)
    };
    entry(out, &sample_line(BOUNDARY, 1.4), "reachable-set boundary");
    let locus = if no_locus {
        "type-II singularity locus (none here)"
    } else {
        "type-II singularity locus"
    };
    entry(out, &sample_line(LOCUS, 2.0), locus);
    let (lo, hi) = phis
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
            (l.min(*p), h.max(*p))
        });
    let path = if hi - lo < 1e-9 {
        format!("path of the scene (φ = {}°)", tick_label(lo, 0.01))
    } else {
        format!(
            "path of the scene (φ from {}° to {}°)",
            tick_label(lo, 0.1),
            tick_label(hi, 0.1)
        )
    };
    entry(
        out,
        &|out: &mut String, y: f64| {
            polyline(out, &[(x, y), (x + 26.0, y)], INK, 4.0);
            polyline(out, &[(x, y), (x + 26.0, y)], PATH, 2.0);
        },
        &path,
    );
    let p = &outcome.progress;
    entry(
        out,
        &sample_cell(SINGULAR),
        &format!("singular ({} poses)", p.singular),
    );
    if p.failed > 0 {
        entry(
            out,
            &sample_cell(FAILED_COLOR),
            &format!("failed ({} poses: map.csv says why)", p.failed),
        );
    }
    entry(
        out,
        &|out: &mut String, y: f64| {
            let _ = writeln!(
                out,
                "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"14\" height=\"14\" fill=\"white\" stroke=\"{}\" stroke-width=\"1\"/>",
                x + 6.0,
                y - 7.0,
                color(INK)
            );
        },
        &format!("out of reach ({} poses)", p.unreachable),
    );
}
