//! The self-contained viewer page: one HTML file with its data, styles and script inline.

use serde_json::{Value, json};

use crate::data::{ViewerData, ViewerError};
use crate::encode::pack_f32;
use flexprr_plot::decimate::{frame_indices, min_max_indices};

/// The page template (HTML, CSS and JavaScript); the data replaces [`DATA_MARKER`].
const TEMPLATE: &str = include_str!("viewer.html");

/// Placeholder in the template that receives the JSON payload.
const DATA_MARKER: &str = "\"__FLEXPRR_DATA__\"";

/// How much of a run goes into the page.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewerOptions {
    /// Largest number of animation frames (uniform stride over the run's samples, first
    /// and last always kept). Default 5000.
    pub max_frames: usize,
    /// Buckets of the min/max decimation of each plotted series (at most
    /// `2 plot_buckets + 2` points per series, every bucket's extremes kept). Default 600.
    pub plot_buckets: usize,
    /// Position `xi = x / l` of the deflection shown in the small plots. Default 0.5.
    pub plot_xi: f64,
}

impl Default for ViewerOptions {
    fn default() -> Self {
        Self {
            max_frames: 5000,
            plot_buckets: 600,
            plot_xi: 0.5,
        }
    }
}

/// The viewer page of `data` with [`ViewerOptions::default`].
///
/// # Errors
/// When `data` fails [`ViewerData::validate`].
pub fn viewer_html(data: &ViewerData) -> Result<String, ViewerError> {
    viewer_html_with(data, &ViewerOptions::default())
}

/// Min/max-decimated `(t, y)` series of `values` sampled at `time`.
fn plot_series(time: &[f64], values: &[f64], buckets: usize) -> Value {
    let kept = min_max_indices(values, buckets);
    json!({
        "t": pack_f32(kept.iter().map(|&i| time[i])),
        "y": pack_f32(kept.iter().map(|&i| values[i])),
    })
}

/// The viewer page of `data`.
///
/// The page needs no network and no server. Its script exposes `window.flexprrViewer`
/// (frame and link counts, `setTime(t)`, `sliderPixels()`, the world-to-pixel transform)
/// and writes a JSON report into `<pre id="flexprr-report">` for headless tests; a URL
/// fragment `#t=0.05` selects the time on load.
///
/// # Errors
/// When `data` fails [`ViewerData::validate`], or `options.plot_xi` is outside `[0, 1]`.
pub fn viewer_html_with(data: &ViewerData, options: &ViewerOptions) -> Result<String, ViewerError> {
    data.validate()?;
    if !(0.0..=1.0).contains(&options.plot_xi) {
        return Err(ViewerError::Invalid {
            field: "options.plot_xi".into(),
            index: 0,
            value: options.plot_xi,
            reason: "must lie in [0, 1]",
        });
    }
    let payload = payload(data, options);
    // serde_json leaves '<' alone; "</" inside a <script> element would end it early.
    let json = serde_json::to_string(&payload)
        .map_err(|e| ViewerError::Figure(format!("viewer payload: {e}")))?
        .replace("</", "<\\/");
    Ok(TEMPLATE.replacen(DATA_MARKER, &json, 1))
}

fn payload(data: &ViewerData, options: &ViewerOptions) -> Value {
    let n = data.frames();
    let kept = frame_indices(n, options.max_frames);
    let time = &data.time;

    let mut max_deflection: f64 = 0.0;
    let mut max_axial: f64 = 0.0;
    let mut links = Vec::new();
    let mut frame_modal = Vec::new();
    let mut frame_axial = Vec::new();
    let mut frame_freq = Vec::new();
    let mut plots = Vec::new();
    for link in &data.links {
        for frame in 0..n {
            for j in 0..link.xi.len() {
                max_deflection = max_deflection.max(link.deflection(frame, j).abs());
            }
        }
        max_axial = link
            .axial_force
            .iter()
            .fold(max_axial, |m, p| m.max(p.abs()));
        links.push(json!({
            "length": link.length,
            "basis": link.basis,
            "xi": link.xi,
            "shapes": link.mode_shapes,
            "buckling": link.buckling.iter().map(|&(a, b)| [a, b]).collect::<Vec<_>>(),
            "patches": link.patches.iter().map(|&(a, b)| [a, b]).collect::<Vec<_>>(),
        }));
        frame_modal.push(pack_f32(
            kept.iter().flat_map(|&i| link.modal[i].iter().copied()),
        ));
        frame_axial.push(pack_f32(kept.iter().map(|&i| link.axial_force[i])));
        frame_freq.push(pack_f32(kept.iter().map(|&i| link.first_frequency[i])));
        let deflection: Vec<f64> = (0..n)
            .map(|i| link.deflection_at(i, options.plot_xi))
            .collect();
        plots.push(json!({
            "deflection": plot_series(time, &deflection, options.plot_buckets),
            "axial": plot_series(time, &link.axial_force, options.plot_buckets),
            "frequency": plot_series(time, &link.first_frequency, options.plot_buckets),
        }));
    }
    let (frame_deviation, plot_deviation, max_deviation) = match &data.deviation {
        Some(dev) => {
            let magnitude: Vec<f64> = dev.iter().map(|d| d[0].hypot(d[1])).collect();
            let max = magnitude.iter().copied().fold(0.0, f64::max);
            (
                Value::String(pack_f32(kept.iter().flat_map(|&i| dev[i]))),
                plot_series(time, &magnitude, options.plot_buckets),
                max,
            )
        }
        None => (Value::Null, Value::Null, 0.0),
    };
    json!({
        "title": data.title,
        "subtitle": data.subtitle,
        "guides": data.guides.iter().map(|g| json!({
            "anchor": g.anchor,
            "direction": g.direction,
            "travel": [g.travel.0, g.travel.1],
        })).collect::<Vec<_>>(),
        "attachments": data.attachments,
        "links": links,
        "samples": n,
        "frames": {
            "count": kept.len(),
            "time": pack_f32(kept.iter().map(|&i| time[i])),
            "pose": pack_f32(kept.iter().flat_map(|&i| data.pose[i])),
            "sliders": pack_f32(kept.iter().flat_map(|&i| data.sliders[i])),
            "modal": frame_modal,
            "axial": frame_axial,
            "frequency": frame_freq,
            "deviation": frame_deviation,
            "reference_sliders": data.reference_sliders.as_ref().map(|r| {
                pack_f32(kept.iter().flat_map(|&i| r[i]))
            }),
        },
        "plots": {
            "xi": options.plot_xi,
            "links": plots,
            "deviation": plot_deviation,
        },
        "stats": {
            "t0": time[0],
            "t1": time[n - 1],
            "max_deflection": max_deflection,
            "max_axial": max_axial,
            "max_deviation": max_deviation,
        },
    })
}
