//! The page without a browser: size, embedded data, validation.

mod common;

use flexprr_viewer::{ViewerError, ViewerOptions, frame_indices, viewer_html, viewer_html_with};
use serde_json::Value;

/// The JSON payload embedded in a page.
fn payload(html: &str) -> Value {
    let open = "<script type=\"application/json\" id=\"flexprr-data\">";
    let start = html.find(open).unwrap() + open.len();
    let end = start + html[start..].find("</script>").unwrap();
    serde_json::from_str(&html[start..end]).unwrap()
}

/// Base64 (RFC 4648) decoding written independently of the crate's encoder.
fn decode_f32(text: &str) -> Vec<f64> {
    let value = |c: u8| -> u32 {
        match c {
            b'A'..=b'Z' => u32::from(c - b'A'),
            b'a'..=b'z' => u32::from(c - b'a') + 26,
            b'0'..=b'9' => u32::from(c - b'0') + 52,
            b'+' => 62,
            b'/' => 63,
            _ => panic!("not base64: {c}"),
        }
    };
    let mut bytes = Vec::new();
    for chunk in text.as_bytes().chunks(4) {
        let pad = chunk.iter().filter(|&&c| c == b'=').count();
        let n = chunk
            .iter()
            .map(|&c| if c == b'=' { 0 } else { value(c) })
            .fold(0u32, |acc, v| (acc << 6) | v);
        let three = [(n >> 16) as u8, (n >> 8) as u8, n as u8];
        bytes.extend_from_slice(&three[..3 - pad]);
    }
    bytes
        .chunks(4)
        .map(|b| f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])))
        .collect()
}

/// The paper scene of 0.2 s stays well under 2 MB; so does a 10 s scene at the same
/// 0.1 ms output step (100 001 samples, decimated to 5000 frames). Sizes are printed for
/// docs/viewer.md.
#[test]
fn page_sizes() {
    let short = viewer_html(&common::paper_scene(0.2, 1e-4, false)).unwrap();
    let long = viewer_html(&common::paper_scene(10.0, 1e-4, false)).unwrap();
    eprintln!(
        "viewer.html: 0.2 s scene {} bytes, 10 s scene {} bytes",
        short.len(),
        long.len()
    );
    assert!(short.len() < 1_000_000, "{}", short.len());
    assert!(long.len() < 2_000_000, "{}", long.len());
    let frames = payload(&long)["frames"]["count"].as_u64().unwrap();
    // stride ceil(100 000 / 4999) = 21: samples 0, 21, ..., 99 981 (4762 of them) + the last.
    assert_eq!(frames, 4763);
}

/// The embedded frames are the kept samples, in order, to f32 precision: times, slider
/// positions and modal coordinates; the plotted midspan deflection contains the exact
/// extremes of the sine-mode sum `q1 - q3` (psi_k(1/2) = sin(k pi / 2)).
#[test]
fn embedded_series_match_the_data() {
    let data = common::paper_scene(0.2, 1e-4, false);
    let options = ViewerOptions {
        max_frames: 300,
        ..ViewerOptions::default()
    };
    let html = viewer_html_with(&data, &options).unwrap();
    let p = payload(&html);
    let kept = frame_indices(data.frames(), 300);
    let time = decode_f32(p["frames"]["time"].as_str().unwrap());
    let sliders = decode_f32(p["frames"]["sliders"].as_str().unwrap());
    let modal = decode_f32(p["frames"]["modal"][2].as_str().unwrap());
    assert_eq!(time.len(), kept.len());
    for (j, &k) in kept.iter().enumerate() {
        assert!((time[j] - data.time[k]).abs() <= 1e-7 * data.time[k].abs().max(1e-3));
        for i in 0..3 {
            assert!((sliders[3 * j + i] - data.sliders[k][i]).abs() < 1e-7);
            assert!((modal[3 * j + i] - data.links[2].modal[k][i]).abs() < 1e-10);
        }
    }
    let plotted = decode_f32(p["plots"]["links"][0]["deflection"]["y"].as_str().unwrap());
    let exact: Vec<f64> = data.links[0].modal.iter().map(|q| q[0] - q[2]).collect();
    let max = exact.iter().copied().fold(f64::MIN, f64::max);
    let min = exact.iter().copied().fold(f64::MAX, f64::min);
    let plotted_max = plotted.iter().copied().fold(f64::MIN, f64::max);
    let plotted_min = plotted.iter().copied().fold(f64::MAX, f64::min);
    assert!((plotted_max - max).abs() < 1e-6 * max.abs());
    assert!((plotted_min - min).abs() < 1e-6 * min.abs());
    assert!(plotted.len() <= 2 * options.plot_buckets + 2);
}

/// Text that would close the data's script element is escaped.
#[test]
fn title_cannot_close_the_script() {
    let mut data = common::paper_scene(0.01, 1e-4, false);
    data.title = "a </script><script>alert(1)</script>".into();
    let html = viewer_html(&data).unwrap();
    let template = viewer_html(&common::paper_scene(0.01, 1e-4, false)).unwrap();
    assert_eq!(
        html.matches("</script>").count(),
        template.matches("</script>").count()
    );
    assert_eq!(payload(&html)["title"], data.title.as_str());
}

/// Bad data is refused with the field and the index.
#[test]
fn validation_names_field_and_index() {
    let good = common::paper_scene(0.01, 1e-4, false);
    let mut d = good.clone();
    d.links[1].axial_force[7] = f64::NAN;
    assert_eq!(
        viewer_html(&d).unwrap_err(),
        ViewerError::NotFinite {
            field: "links[1].axial_force".into(),
            index: 7
        }
    );
    let mut d = good.clone();
    d.sliders.pop();
    assert!(matches!(
        viewer_html(&d).unwrap_err(),
        ViewerError::Length { ref field, found: 100, expected: 101 } if field == "sliders"
    ));
    let mut d = good.clone();
    d.time[5] = d.time[4];
    assert!(matches!(
        viewer_html(&d).unwrap_err(),
        ViewerError::Invalid { ref field, index: 5, .. } if field == "time"
    ));
    let mut d = good.clone();
    d.links[0].modal[3].push(0.0);
    let err = viewer_html(&d).unwrap_err();
    assert!(err.to_string().contains("links[0].modal[3]"), "{err}");
    let mut d = good;
    d.guides[2].direction = [1.0, 1.0];
    let err = viewer_html(&d).unwrap_err();
    assert!(err.to_string().contains("guides[2].direction"), "{err}");
}

/// Midspan deflection of sine modes: psi_k(1/2) = sin(k pi / 2) = 1, 0, -1.
#[test]
fn deflection_of_sine_modes_at_midspan() {
    let data = common::paper_scene(0.01, 1e-4, false);
    let link = &data.links[0];
    for frame in [0, 33, 100] {
        let q = &link.modal[frame];
        assert!((link.deflection_at(frame, 0.5) - (q[0] - q[2])).abs() < 1e-15);
        // xi = 1/4 (a sample point): sin(pi/4), sin(pi/2), sin(3 pi/4).
        let quarter = link.deflection_at(frame, 0.25);
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let exact = q[0] * s + q[1] + q[2] * s;
        assert!((quarter - exact).abs() < 1e-12, "{quarter} vs {exact}");
    }
}
