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
