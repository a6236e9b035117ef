//! The figures of the paper scene, rendered: axis units carry the SI prefix that the data
//! needs (checked by reading the tick labels back and comparing them with the data), tick
//! labels are plain (`0.05`, never `0.0000`, `−0` or `1.0`), symbols are Unicode, and long
//! series are decimated to a bounded size that keeps their extremes.

use std::path::Path;

use flexprr_run::plot::{Axis, Figure, Panel, Series, Style};
use flexprr_run::run;
use flexprr_scene::Scene;

/// The texts of `<text>` elements whose opening tag contains `attr`, tags inside removed.
fn texts(svg: &str, attr: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = svg;
    while let Some(start) = rest.find("<text ") {
        let tail = &rest[start..];
        let open_end = tail.find('>').unwrap();
        let end = tail.find("</text>").unwrap();
        if tail[..open_end].contains(attr) {
            let mut inner = String::new();
            let mut in_tag = false;
            for c in tail[open_end + 1..end].chars() {
                match c {
                    '<' => in_tag = true,
                    '>' => in_tag = false,
                    c if !in_tag => inner.push(c),
                    _ => {}
                }
            }
            out.push(inner);
        }
        rest = &tail[end..];
    }
    out
}

/// SI prefixes by hand (BIPM SI brochure, table 7).
fn prefix_factor(prefix: &str) -> f64 {
    match prefix {
        "p" => 1e-12,
        "n" => 1e-9,
        "µ" => 1e-6,
        "m" => 1e-3,
        "" => 1.0,
        "k" => 1e3,
        "M" => 1e6,
        "G" => 1e9,
        other => panic!("unknown prefix {other:?}"),
    }
}

/// Checks one panel of a rendered figure against its data: the unit in the axis label is
/// the SI unit with a prefix, the ticks read back in SI units lie within the data range
/// (plus padding) and span most of it, the shown magnitudes are in [1, 1000), and the
/// tick labels are plain numbers.
fn check_panel(file: &str, chunk: &str, panel: &Panel) {
    let label = texts(chunk, "rotate(-90)").pop().expect("a y label");
    let shown_unit = label
        .rsplit_once('(')
        .map(|(_, u)| u.trim_end_matches(')'))
        .unwrap_or_default();
    let base = &panel.y.unit;
    let factor = if base.is_empty() {
        1.0
    } else {
        let prefix = shown_unit
            .strip_suffix(base.as_str())
            .unwrap_or_else(|| panic!("{file}: `{label}` does not end in a prefixed {base}"));
        prefix_factor(prefix)
    };
    let ticks = texts(chunk, "text-anchor=\"end\"");
    let values: Vec<f64> = ticks
        .iter()
        .filter(|t| {
            t.chars()
                .next()
                .is_some_and(|c| c.is_ascii_digit() || c == '−')
        })
        .map(|t| {
            assert!(!t.contains('e'), "{file}: exponent in tick {t}");
            assert!(t != "−0" && !t.contains("0.0000"), "{file}: tick {t}");
            assert!(
                !(t.contains('.') && t.ends_with('0')),
                "{file}: trailing zero in {t}"
            );
            t.replace('−', "-").parse::<f64>().unwrap() * factor
        })
        .collect();
    assert!(values.len() >= 2, "{file}: ticks {ticks:?}");
    let data: Vec<f64> = panel
        .series
        .iter()
        .flat_map(|s| s.y.iter().copied())
        .filter(|v| v.is_finite())
        .collect();
    let lo = data.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = data.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let span = (hi - lo).max(1e-9 * hi.abs().max(lo.abs()));
    for v in &values {
        assert!(
            *v >= lo - 0.1 * span && *v <= hi + 0.1 * span,
            "{file} `{label}`: tick {v} outside the data [{lo}, {hi}]"
        );
    }
    let tick_span = values.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        - values.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(
        tick_span >= 0.4 * span,
        "{file} `{label}`: ticks {values:?} on [{lo}, {hi}]"
    );
    if !base.is_empty() {
        let shown = hi.abs().max(lo.abs()) / factor;
        assert!(
            (1.0..1000.0).contains(&shown),
            "{file} `{label}`: largest shown magnitude {shown}"
        );
    }
}

#[test]
fn paper_scene_figures_have_prefixed_units_and_plain_ticks() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs/paper_f20.toml");
    let scene = Scene::load(&path).unwrap();
    let result = run(&scene, &mut |_| {}).unwrap();
    let figures = flexprr_run::plot::run_figures(&scene, &result);
    let names: Vec<&str> = figures.iter().map(|(f, _)| f.as_str()).collect();
    for expected in [
        "deflections_xi0.5.svg",
        "modes.svg",
        "modal_forces.svg",
        "driving_forces.svg",
        "axial_force_frequency_mode1.svg",
        "axial_forces.svg",
        "kinematics.svg",
        "energies.svg",
    ] {
        assert!(names.contains(&expected), "{expected} missing: {names:?}");
    }
    for (file, figure) in &figures {
        let svg = figure.to_svg().unwrap();
        // The paper's motion lasts 0.2 s: time in ms, ticks 0 to 200.
        assert!(svg.contains(">t (ms)<"), "{file}");
        assert!(
            !svg.contains("_{") && !svg.contains("eta"),
            "{file}: raw label"
        );
        for (chunk, panel) in svg.split("<clipPath id=\"p").skip(1).zip(&figure.panels) {
            check_panel(file, chunk, panel);
        }
    }
    let svg = |name: &str| {
        figures
            .iter()
            .find(|(f, _)| f == name)
            .unwrap()
            .1
            .to_svg()
            .unwrap()
    };
    // Mid-link deflections of a few millimetres (the paper's figs 6-7), so mm.
    let w = result
        .table("deflections")
        .unwrap()
        .column("w_1_xi0.5_m")
        .unwrap()
        .iter()
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    assert!((1e-3..1e-2).contains(&w), "peak deflection {w} m");
    let deflections = svg("deflections_xi0.5.svg");
    for text in ["w₁ (mm)", "w₃ (mm)", "with axial force", "ξ = 0.5"] {
        assert!(deflections.contains(text), "deflections lack {text}");
    }
    assert!(svg("driving_forces.svg").contains("Fₐ₁ (N)"));
    assert!(svg("modes.svg").contains("η₁,₁ ("));
    assert!(
        svg("kinematics.svg").contains("β (rad)") || svg("kinematics.svg").contains("β (mrad)")
    );
}

#[test]
fn a_long_run_is_decimated_to_a_small_file_with_its_extremes() {
    // 10 s at a 0.1 ms output step: 100 001 samples, three panels of two series, with a
    // one-sample spike that must survive.
    let n = 100_001;
    let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-4).collect();
    let mut figure = Figure::new(Axis::new("t", "s"));
    for i in 0..3 {
        let mut a: Vec<f64> = t
            .iter()
            .map(|t| 1e-4 * (40.0 * t + i as f64).sin())
            .collect();
        let b: Vec<f64> = t.iter().map(|t| 0.8e-4 * (37.0 * t).cos()).collect();
        a[77_777] = 3e-4;
        figure = figure.panel(
            Panel::new(Axis::new(format!("w_{{{}}}", i + 1), "m"))
                .series(Series::new("a", &t, &a, Style::nth(0)))
                .series(Series::new("b", &t, &b, Style::nth(1))),
        );
    }
    let svg = figure.to_svg().unwrap();
    // Without decimation: 600 006 points of about 12 bytes each.
    assert!(svg.len() < 250_000, "{} bytes", svg.len());
    assert!(svg.contains("(µm)"));
    for (chunk, panel) in svg.split("<clipPath id=\"p").skip(1).zip(&figure.panels) {
        check_panel("long run", chunk, panel);
        // The spike (300 µm, the top of the data) is drawn: the highest polyline point is
        // within the top padding of the plot area, where no point of the sines (at most
        // 100 µm, some 75 px lower) comes.
        let top: f64 = number_after(chunk, "y=\"");
        let highest = chunk
            .split("points=\"")
            .skip(1)
            .flat_map(|p| {
                p[..p.find('"').unwrap()]
                    .split(' ')
                    .map(|xy| xy.split_once(',').unwrap().1.parse::<f64>().unwrap())
                    .collect::<Vec<_>>()
            })
            .fold(f64::INFINITY, f64::min);
        assert!(
            highest < top + 15.0,
            "highest point {highest} px, plot top {top} px"
        );
    }
}

/// The number that follows the first `marker` in `text`.
fn number_after(text: &str, marker: &str) -> f64 {
    let rest = &text[text.find(marker).unwrap() + marker.len()..];
    rest[..rest.find('"').unwrap()].parse().unwrap()
}
