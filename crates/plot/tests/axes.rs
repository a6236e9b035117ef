//! Axes of a custom drawing: equal scales hold, the data box fits in the plot area, and
//! every tick label is drawn where `to_px` puts its value (the labels read back from the
//! SVG text, parsed as numbers, so the drawing and the mapping are checked against each
//! other).

use flexprr_plot::Axis;
use flexprr_plot::axes::{Area, Axes};

/// `(x, y, anchor, text)` of every `<text x=.. y=..>` element of `svg`.
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
            let content = body.split_once("</text>")?.0.to_string();
            Some((
                attr(&tag, "x")?.parse().ok()?,
                attr(&tag, "y")?.parse().ok()?,
                attr(&tag, "text-anchor")?,
                content,
            ))
        })
        .collect()
}

#[test]
fn ticks_are_drawn_where_their_values_map_and_scales_are_equal() {
    let outer = Area {
        left: 20.0,
        top: 10.0,
        width: 500.0,
        height: 300.0,
    };
    let (xr, yr) = ((-0.41, 0.37), (-0.12, 0.25));
    let axes = Axes::fit(
        outer,
        (&Axis::new("x", "m"), xr),
        (&Axis::new("y", "m"), yr),
        true,
    );
    let (sx, sy) = axes.px_per_unit();
    assert!((sx - sy).abs() < 1e-12 * sx, "{sx} vs {sy}");
    let a = axes.area();
    assert!(a.left >= outer.left && a.left + a.width <= outer.left + outer.width);
    assert!(a.top >= outer.top && a.bottom() <= outer.top + outer.height);
    // The data box lies inside the plot area and fills it in one direction.
    let (p0, p1) = (axes.to_px(xr.0, yr.0), axes.to_px(xr.1, yr.1));
    let eps = 1e-9;
    assert!(p0.0 >= a.left - eps && p1.0 <= a.left + a.width + eps);
    assert!(p1.1 >= a.top - eps && p0.1 <= a.bottom() + eps);
    let fills_x = (p1.0 - p0.0 - a.width).abs() < 1e-6;
    let fills_y = (p0.1 - p1.1 - a.height).abs() < 1e-6;
    assert!(fills_x || fills_y);

    let mut svg = String::new();
    axes.draw(&mut svg);
    assert!(svg.contains("x (mm)") && svg.contains("y (mm)"), "{svg}");
    let value = |t: &str| -> Option<f64> { t.replace('−', "-").parse::<f64>().ok() };
    let (mut nx, mut ny) = (0, 0);
    for (x, y, anchor, label) in texts(&svg) {
        let Some(mm) = value(&label) else { continue };
        if anchor == "middle" {
            // x tick: centred on its value, below the plot area.
            let (px, _) = axes.to_px(1e-3 * mm, 0.0);
            assert!(
                (x - px).abs() < 0.051,
                "x tick {label} at {x}, maps to {px}"
            );
            assert!(y > a.bottom());
            nx += 1;
        } else {
            // y tick: right-aligned left of the area, baseline 0.35 em below its value.
            let (_, py) = axes.to_px(0.0, 1e-3 * mm);
            assert!((y - (py + 0.35 * 13.0)).abs() < 0.051, "y tick {label}");
            assert!(x < a.left);
            ny += 1;
        }
    }
    assert!(nx >= 3 && ny >= 3, "{nx} x ticks, {ny} y ticks");
}
