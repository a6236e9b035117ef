//! The static figures: workspace section, singularity locus, SVG output.

mod common;

use flexprr_kinematics::{Pose, Trajectory};
use flexprr_viewer::{ViewerError, machine_svg, snapshots_svg, workspace_section};

const BOX: (f64, f64) = (-0.3, 0.3);

/// At phi = 0 the paper's radial home pose is type-II singular (the three link lines meet
/// at the platform centre; kinematics docs and tests): the locus passes through it. Every
/// point of the locus is type-II singular by the kinematics crate's own measure, up to
/// the linear interpolation on a 2.5 mm grid, while the section holds poses far from it.
#[test]
fn locus_at_phi_zero_is_type_ii_and_passes_through_home() {
    let geometry = common::paper_geometry();
    let n = 241;
    let spacing = (BOX.1 - BOX.0) / (n - 1) as f64;
    let section = workspace_section(&geometry, 0.0, BOX, BOX, n);
    assert!(!section.locus.is_empty());
    let nearest_home = section
        .locus
        .iter()
        .flatten()
        .map(|p| p[0].hypot(p[1]))
        .fold(f64::INFINITY, f64::min);
    assert!(nearest_home < spacing, "locus {nearest_home} m from home");
    let mut worst: f64 = 0.0;
    for p in section.locus.iter().flatten() {
        let measure = geometry
            .singularity(&Pose::new(p[0], p[1], 0.0))
            .unwrap()
            .type_ii;
        worst = worst.max(measure);
    }
    assert!(worst < 0.02, "type-II measure on the locus up to {worst}");
    let mut best: f64 = 0.0;
    for (k, reachable) in section.reachable.iter().enumerate() {
        if *reachable {
            let (x, y) = (section.x[k % n], section.y[k / n]);
            let measure = geometry.singularity(&Pose::new(x, y, 0.0)).unwrap().type_ii;
            best = best.max(measure);
        }
    }
    assert!(
        best > 0.2,
        "the section never leaves the locus (max measure {best})"
    );
}

/// The paper's 20 Hz circle is feasible (inside the travel; kinematics test
/// `paper_circle_at_20_hz_is_feasible`) and far from type II: in the phi = 45 deg section
/// every node next to the path is reachable, and the section has no type-II locus.
#[test]
fn paper_circle_lies_in_the_reachable_section() {
    let geometry = common::paper_geometry();
    let circle = common::paper_circle();
    let n = 241;
    let section = workspace_section(&geometry, 45f64.to_radians(), BOX, BOX, n);
    let spacing = (BOX.1 - BOX.0) / (n - 1) as f64;
    for k in 0..200 {
        let pose = circle.motion(k as f64 * 0.05 / 200.0).pose;
        let ix = ((pose.x - BOX.0) / spacing).round() as usize;
        let iy = ((pose.y - BOX.0) / spacing).round() as usize;
        assert!(
            section.reachable[iy * n + ix],
            "path point ({}, {}) in an unreachable cell",
            pose.x,
            pose.y
        );
    }
    assert!(section.locus.is_empty());
    // And the machine cannot reach 0.3 m from the centre (links 0.2 m, guides end 0.059 m
    // from the centre on the inside): the corner node is unreachable.
    assert!(!section.reachable[n * n - 1]);
}

/// The machine figure names its section and says that the locus is absent there.
#[test]
fn machine_figure_of_the_paper_scene() {
    let data = common::paper_scene(0.05, 1e-4, false);
    let svg = machine_svg(&common::paper_geometry(), &data.pose, "paper", 121).unwrap();
    assert!(svg.contains("<svg") && svg.trim_end().ends_with("</svg>"));
    assert!(svg.contains("\u{3c6} = 45\u{b0}"));
    assert!(svg.contains("No type-II singularity"));
    assert!(matches!(
        machine_svg(&common::paper_geometry(), &[], "empty", 121),
        Err(ViewerError::Length { .. })
    ));
}

/// Panels are labelled with their times in SI-prefixed units, the amplification is
/// stated, and an empty list of times is an error.
#[test]
fn snapshots_figure_labels_and_errors() {
    let data = common::paper_scene(0.05, 1e-4, false);
    let svg = snapshots_svg(&data, &[0.0, 0.0125, 0.025], Some(500.0)).unwrap();
    assert!(svg.contains("\u{d7}500"));
    assert!(svg.contains("(a) t = 0 s"));
    assert!(svg.contains("(b) t = 12.5 ms"));
    assert!(svg.contains("(c) t = 25 ms"));
    assert!(matches!(
        snapshots_svg(&data, &[], None),
        Err(ViewerError::Length { .. })
    ));
    assert!(matches!(
        snapshots_svg(&data, &[0.0], Some(f64::NAN)),
        Err(ViewerError::Invalid { .. })
    ));
}

/// `(x, y, anchor, content)` of every `<text x=.. y=..>` element of `svg`.
fn texts(svg: &str) -> Vec<(f64, f64, String, String)> {
    let attr = |tag: &str, name: &str| -> Option<String> {
        let at = tag.find(&format!(" {name}=\""))? + name.len() + 3;
        Some(tag[at..at + tag[at..].find('"')?].to_string())
    };
    svg.split("<text ")
        .skip(1)
        .filter_map(|rest| {
            let (tag, body) = rest.split_once('>')?;
            let tag = format!(" {tag}");
            Some((
                attr(&tag, "x")?.parse().ok()?,
                attr(&tag, "y")?.parse().ok()?,
                attr(&tag, "text-anchor")?,
                body.split_once("</text>")?.0.to_string(),
            ))
        })
        .collect()
}

/// Least-squares line `pixel = a + b value` through `(value, pixel)` pairs.
fn fit(points: &[(f64, f64)]) -> (f64, f64) {
    let n = points.len() as f64;
    let (mx, my) = (
        points.iter().map(|p| p.0).sum::<f64>() / n,
        points.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let b = sxy / sxx;
    (my - b * mx, b)
}

/// The machine is drawn where its axes say, with equal scales: the tick labels of
/// `machine.svg` (millimetres at pixel positions) give the map from the page to the plane;
/// through it the three slider discs sit at the slider joints that the closed-form inverse
/// kinematics of `flexprr_kinematics` gives for the first pose, and a millimetre is as long
/// along x as along y.
#[test]
fn machine_figure_draws_the_sliders_where_its_axes_put_them() {
    let data = common::paper_scene(0.05, 1e-4, false);
    let geometry = common::paper_geometry();
    let svg = machine_svg(&geometry, &data.pose, "paper", 121).unwrap();
    let number = |t: &str| t.replace('\u{2212}', "-").parse::<f64>().ok();
    let tick = flexprr_plot::svg::FONT_TICK;
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    for (x, y, anchor, content) in texts(&svg) {
        match (number(&content), anchor.as_str()) {
            (Some(mm), "middle") => xs.push((mm, x)),
            // The label's baseline is 0.35 em below its tick.
            (Some(mm), "end") => ys.push((mm, y - 0.35 * tick)),
            _ => {}
        }
    }
    assert!(xs.len() >= 4 && ys.len() >= 4, "{xs:?} {ys:?}");
    let ((ax, bx), (ay, by)) = (fit(&xs), fit(&ys));
    // Equal scales (y down on the page), to the 0.1 px the labels are written with.
    assert!(
        (bx + by).abs() < 2e-3 * bx,
        "{bx} px/mm along x, {by} along y"
    );
    let discs: Vec<(f64, f64)> = svg
        .split("<circle ")
        .skip(1)
        .filter(|c| c.contains("r=\"5\""))
        .map(|c| {
            let value = |name: &str| -> f64 {
                let at = c.find(&format!("{name}=\"")).unwrap() + name.len() + 2;
                c[at..at + c[at..].find('"').unwrap()].parse().unwrap()
            };
            ((value("cx") - ax) / bx, (value("cy") - ay) / by)
        })
        .collect();
    assert_eq!(discs.len(), 3, "{discs:?}");
    let p = data.pose[0];
    let legs = geometry
        .inverse_position(&flexprr_kinematics::Pose::new(p[0], p[1], p[2]))
        .unwrap();
    for (leg, (x, y)) in legs.iter().zip(&discs) {
        let (bx_mm, by_mm) = (1e3 * leg.b.x, 1e3 * leg.b.y);
        assert!(
            (x - bx_mm).abs() < 0.5 && (y - by_mm).abs() < 0.5,
            "slider drawn at ({x:.2}, {y:.2}) mm, inverse kinematics ({bx_mm:.2}, {by_mm:.2})"
        );
    }
}
