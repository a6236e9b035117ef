//! Legends of [`crate::Figure`] panels: where each goes (a free corner of the plot area, or
//! rows above it, never over data) and how it is drawn.

use std::fmt::Write as _;

use crate::Style;
use crate::svg::{FONT_LEGEND, MARKER, marker, polyline, text};

/// Height of a legend row (px).
pub(crate) const LEGEND_ROW: f64 = 16.0;
/// Length of a legend's line sample (px).
pub(crate) const LEGEND_SAMPLE: f64 = 26.0;

/// A series in pixels: its polylines (runs without gaps) and its marker points.
pub(crate) type Drawn = (Vec<Vec<(f64, f64)>>, Vec<(f64, f64)>);

/// A rectangle in pixels.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Rect {
    x: f64,
    y: f64,
    w: f64,
    h: f64,
}

impl Rect {
    /// Whether `p` lies in the rectangle grown by `pad`.
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

/// Where a panel's legend goes.
pub(crate) enum LegendPlace {
    /// No legend (fewer than two entries).
    None,
    /// In a free corner of the plot area (coordinates from the panel's top).
    Inside(Rect),
    /// In rows above the plot area: the entries of each row and the rows' height (px).
    Above { rows: Vec<Vec<usize>>, height: f64 },
}

/// A legend entry: the label, the series' style and the entry's width (px).
pub(crate) struct Entry<'a> {
    pub(crate) label: &'a str,
    pub(crate) style: Style,
    pub(crate) width: f64,
}

/// The legend's place: none for fewer than two entries; the first corner of the plot area
/// (upper right, upper left, lower right, lower left) that no line or marker touches;
/// otherwise rows above the plot area.
pub(crate) fn place_legend(
    entries: &[Entry<'_>],
    pixels: &[Drawn],
    left: f64,
    (plot_w, plot_h): (f64, f64),
) -> LegendPlace {
    if entries.len() < 2 {
        return LegendPlace::None;
    }
    let w = entries.iter().map(|e| e.width).fold(0.0, f64::max) + 12.0;
    let h = LEGEND_ROW * entries.len() as f64 + 8.0;
    let inset = 5.0;
    if w < 0.7 * plot_w && h < 0.7 * plot_h {
        let corners = [
            (left + plot_w - w - inset, inset),
            (left + inset, inset),
            (left + plot_w - w - inset, plot_h - h - inset),
            (left + inset, plot_h - h - inset),
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

/// One entry at `(x, y)` (px, the sample's centre line): the series' line and marker,
/// then its label.
fn legend_entry(out: &mut String, e: &Entry<'_>, (x, y): (f64, f64)) {
    if e.style.line {
        polyline(out, &[(x, y), (x + LEGEND_SAMPLE, y)], e.style);
    }
    if let Some(m) = e.style.marker {
        marker(out, m, e.style.color, (x + LEGEND_SAMPLE / 2.0, y));
    }
    text(
        out,
        (x + LEGEND_SAMPLE + 6.0, y + 0.35 * FONT_LEGEND),
        FONT_LEGEND,
        "start",
        e.label,
    );
}

/// Draws the legend `place` of `entries` for the panel whose plot area starts at `left`,
/// `top` (px).
pub(crate) fn draw_legend(
    out: &mut String,
    place: &LegendPlace,
    entries: &[Entry<'_>],
    left: f64,
    top: f64,
) {
    match place {
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
            for (k, e) in entries.iter().enumerate() {
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
                    legend_entry(out, &entries[k], (x, y));
                    x += entries[k].width + 14.0;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The plot height the tests lay legends out in (px).
    const H: f64 = 170.0;

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
        let diagonal = vec![(left, H), (left + w, 0.0)];
        match place_legend(&entries, &[(vec![diagonal], vec![])], left, (w, H)) {
            LegendPlace::Inside(r) => assert!(r.x < left + 10.0 && r.y < 10.0, "{r:?}"),
            _ => panic!("expected the upper-left corner"),
        }
        // Lines along the top and the bottom take every corner: the legend goes above.
        let lines = vec![
            vec![(left, 8.0), (left + w, 8.0)],
            vec![(left, H - 8.0), (left + w, H - 8.0)],
        ];
        assert!(matches!(
            place_legend(&entries, &[(lines, vec![])], left, (w, H)),
            LegendPlace::Above { .. }
        ));
        // Markers count as well as lines.
        let points: Vec<(f64, f64)> = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
            .iter()
            .map(|(a, b)| (left + 20.0 + a * (w - 40.0), 15.0 + b * (H - 30.0)))
            .collect();
        assert!(matches!(
            place_legend(&entries, &[(vec![], points)], left, (w, H)),
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
