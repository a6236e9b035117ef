//! The piezoelectric patches on the links (docs/piezo.md): `snapshots.svg` draws one band
//! per patch and frame, from the deflected centre line's point at `xi_start` to the one at
//! `xi_end` (checked against the chord geometry of an undeflected frame), the page carries
//! the spans, and a bad span is refused.

mod common;

use flexprr_viewer::{ViewerError, snapshots_svg, viewer_html};

/// The `points` of every polyline drawn in the patches' colour.
fn bands(svg: &str) -> Vec<Vec<(f64, f64)>> {
    svg.lines()
        .filter(|l| l.contains("<polyline") && l.contains("stroke=\"#8e44ad\""))
        .map(|l| {
            let start = l.find("points=\"").unwrap() + 8;
            let end = start + l[start..].find('"').unwrap();
            l[start..end]
                .split(' ')
                .map(|p| {
                    let (x, y) = p.split_once(',').unwrap();
                    (x.parse().unwrap(), y.parse().unwrap())
                })
                .collect()
        })
        .collect()
}

#[test]
fn snapshots_draw_one_band_per_patch_between_its_ends() {
    let mut data = common::paper_scene(0.05, 1e-3, false);
    for link in &mut data.links {
        // An undeflected machine: the band lies on the chord.
        for q in &mut link.modal {
            q.iter_mut().for_each(|v| *v = 0.0);
        }
    }
    data.links[0].patches = vec![(0.2, 0.4), (0.6, 0.8)];
    data.links[2].patches = vec![(0.45, 0.55)];
    let times = [0.0, 0.02];
    let svg = snapshots_svg(&data, &times, Some(1.0)).unwrap();
    let found = bands(&svg);
    // Three patches in each of two panels, and the key.
    assert_eq!(found.len(), 3 * times.len() + 1);
    assert!(svg.contains("piezo patch"));
    // On a straight link the band is a fifth (0.2 of the chord) or a tenth of the link
    // between slider and platform; compare its length with the chord's.
    let chord = |i: usize| {
        let lines: Vec<&str> = svg
            .lines()
            .filter(|l| l.contains("stroke-dasharray=\"4 4\""))
            .collect();
        let l = lines[i];
        let start = l.find("points=\"").unwrap() + 8;
        let end = start + l[start..].find('"').unwrap();
        let p: Vec<(f64, f64)> = l[start..end]
            .split(' ')
            .map(|p| {
                let (x, y) = p.split_once(',').unwrap();
                (x.parse().unwrap(), y.parse().unwrap())
            })
            .collect();
        (p[1].0 - p[0].0).hypot(p[1].1 - p[0].1)
    };
    let length = |b: &[(f64, f64)]| (b[b.len() - 1].0 - b[0].0).hypot(b[b.len() - 1].1 - b[0].1);
    let (link1, link3) = (chord(0), chord(2));
    for (band, expect) in found[..3]
        .iter()
        .zip([0.2 * link1, 0.2 * link1, 0.1 * link3])
    {
        // Pixel coordinates are written to 0.1 px.
        assert!(
            (length(band) - expect).abs() < 0.3,
            "{} vs {expect}",
            length(band)
        );
    }
}

#[test]
fn the_page_carries_the_spans() {
    let mut data = common::paper_scene(0.02, 1e-3, false);
    data.links[1].patches = vec![(0.45, 0.55)];
    let html = viewer_html(&data).unwrap();
    assert!(html.contains("\"patches\":[[0.45,0.55]]"));
    assert!(html.contains("piezoelectric patch"));
}

#[test]
fn a_reversed_or_outside_span_is_refused() {
    for span in [(0.6, 0.4), (-0.1, 0.2), (0.9, 1.1), (f64::NAN, 0.5)] {
        let mut data = common::paper_scene(0.01, 1e-3, false);
        data.links[2].patches = vec![(0.1, 0.2), span];
        match data.validate() {
            Err(ViewerError::Invalid { field, index, .. }) => {
                assert_eq!((field.as_str(), index), ("links[2].patches", 1), "{span:?}");
            }
            other => panic!("{span:?}: {other:?}"),
        }
    }
}
