//! The modes as files: `modes.json` (everything), `modes.csv` (one row per mode) and the
//! summary `flexprr modes --json` prints (`{"modes": [...]}`).

use serde_json::{Value, json};

use super::{MachineMode, MachineModes};
use crate::linear::OperatingPoint;

/// `null` for a non-finite number (JSON has none).
fn finite(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

/// The fields every description of a mode has: frequency, damping ratio, eigenvalue, kind.
fn mode_head(k: usize, m: &MachineMode) -> serde_json::Map<String, Value> {
    let mut map = serde_json::Map::new();
    map.insert("mode".into(), json!(k + 1));
    map.insert("frequency_hz".into(), finite(m.frequency_hz));
    map.insert("damping_ratio".into(), finite(m.damping_ratio));
    map.insert(
        "eigenvalue".into(),
        json!([finite(m.eigenvalue.re), finite(m.eigenvalue.im)]),
    );
    if let Some(z) = m.z {
        map.insert("z".into(), json!([finite(z.re), finite(z.im)]));
    }
    map.insert("kind".into(), json!(m.kind));
    map
}

/// What `flexprr modes --json` prints: `{"modes": [{"frequency_hz", "damping_ratio",
/// "eigenvalue": [re, im], "kind", "mode"}, ...]}`, the lowest `count` modes sorted by
/// frequency, rigid-body (zero) modes left out.
pub fn modes_summary_json(modes: &MachineModes, count: usize) -> Value {
    let list: Vec<Value> = modes
        .modes
        .iter()
        .take(count)
        .enumerate()
        .map(|(k, m)| Value::Object(mode_head(k, m)))
        .collect();
    json!({ "modes": list })
}

/// The operating point as JSON: its kind, time, the model's platform pose and sliders.
fn operating_point_json(modes: &MachineModes) -> Value {
    let kind = match modes.operating_point {
        OperatingPoint::Rest(_) => "rest",
        OperatingPoint::Time(_) => "time",
    };
    json!({
        "kind": kind,
        "t_s": finite(modes.t),
        "pose": {
            "x_m": finite(modes.pose.x),
            "y_m": finite(modes.pose.y),
            "phi_deg": finite(modes.pose.phi.to_degrees()),
        },
        "sliders_m": modes.rho.map(finite),
    })
}

/// `modes.json`: the scene and model, the operating point, the definitions, the timing and
/// the lowest `count` modes with their shapes.
pub fn modes_json(modes: &MachineModes, count: usize) -> Value {
    let list: Vec<Value> = modes
        .modes
        .iter()
        .take(count)
        .enumerate()
        .map(|(k, m)| {
            let mut map = mode_head(k, m);
            let s = &m.shape;
            let numbers = |v: &[f64]| v.iter().map(|x| finite(*x)).collect::<Vec<_>>();
            map.insert(
                "shape".into(),
                json!({
                    "sliders": numbers(&s.sliders),
                    "platform": {
                        "x": finite(s.platform[0]),
                        "y": finite(s.platform[1]),
                        "phi_per_m": finite(s.platform[2]),
                    },
                    "platform_joints": s.joints.iter().map(|j| numbers(j)).collect::<Vec<_>>(),
                    "links": s.links.iter().map(|w| numbers(w)).collect::<Vec<_>>(),
                    "imaginary": finite(s.imaginary),
                }),
            );
            Value::Object(map)
        })
        .collect();
    json!({
        "scene": modes.scene,
        "flexprr_version": env!("CARGO_PKG_VERSION"),
        "model": modes.model,
        "sliders": modes.sliders,
        "chords": modes.chords,
        "operating_point": operating_point_json(modes),
        "state_dimension": modes.state_dimension,
        "coordinates": modes.coordinates,
        "modes_found": modes.modes.len(),
        "modes_written": list.len(),
        "dt_s": modes.dt,
        "notes": modes.notes,
        "truncation": modes.truncation.map(|t| {
            let highest = list_highest(modes, count);
            json!({
                "modes_per_link": t.modes_per_link,
                "first_missing_family_hz": t.first_missing_hz,
                "highest_mode_written_hz": highest,
                "complete": t.complete(highest),
                "modes_per_link_for_the_written_modes": t.recommended(highest),
                "note": t.note(highest),
            })
        }),
        "definitions": {
            "frequency_hz": "|lambda| / (2 pi), the undamped natural frequency of the eigenvalue lambda of A (of a discrete-time model, dt_s > 0: lambda = ln(z) / dt for its pole z, principal branch, so frequencies above the Nyquist frequency 1 / (2 dt) fold below it)",
            "damping_ratio": "-Re(lambda) / |lambda| (MATLAB's damp)",
            "shape": "real, scaled so that the largest displacement (a slider, a platform coordinate, the platform's rotation times its radius, or a link's deflection) is 1; sliders along their guides, platform x, y and phi (rad per unit), each platform joint's motion, each link's deflection from its chord at xi; imaginary: the largest imaginary part left (0 for an undamped mode)",
            "kind": "servo (the sliders move at least half as much as anything else), platform (the platform's kinetic energy exceeds the links' bending kinetic energy), or bending of the links that bend by at least a quarter of the largest deflection, with the half-waves of the most deflected one",
        },
        "timing_s": {
            "model": modes.timing.model_s,
            "linearisation": modes.timing.linearisation_s,
            "eigen": modes.timing.eigen_s,
        },
        "xi": modes.xi,
        "modes": list,
    })
}

/// The highest frequency of the lowest `count` modes (Hz).
fn list_highest(modes: &MachineModes, count: usize) -> f64 {
    modes
        .modes
        .iter()
        .take(count)
        .map(|m| m.frequency_hz)
        .fold(0.0, f64::max)
}

/// `modes.csv`: one row per mode (the lowest `count`): its frequency, damping ratio,
/// eigenvalue and kind, and its shape's slider and platform entries and each link's peak
/// deflection (numbers as in every flexprr CSV, `{:.10e}`).
///
/// # Errors
/// The CSV writer fails (it writes to memory).
pub fn modes_csv(modes: &MachineModes, count: usize) -> Result<Vec<u8>, String> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let e = |e: csv::Error| format!("writing modes.csv: {e}");
    w.write_record([
        "mode",
        "frequency_Hz",
        "damping_ratio",
        "eigenvalue_re_1_s",
        "eigenvalue_im_1_s",
        "kind",
        "shape_slider_1",
        "shape_slider_2",
        "shape_slider_3",
        "shape_platform_x",
        "shape_platform_y",
        "shape_platform_phi_per_m",
        "shape_w_peak_1",
        "shape_w_peak_2",
        "shape_w_peak_3",
    ])
    .map_err(e)?;
    let number = |v: f64| format!("{v:.10e}");
    for (k, m) in modes.modes.iter().take(count).enumerate() {
        let s = &m.shape;
        let (_, _, peaks) = s.amplitudes();
        let mut row = vec![
            (k + 1).to_string(),
            number(m.frequency_hz),
            number(m.damping_ratio),
            number(m.eigenvalue.re),
            number(m.eigenvalue.im),
            m.kind.clone(),
        ];
        row.extend(s.sliders.iter().map(|v| number(*v)));
        row.extend(s.platform.iter().map(|v| number(*v)));
        row.extend(peaks.iter().map(|v| number(*v)));
        w.write_record(&row).map_err(e)?;
    }
    w.into_inner()
        .map_err(|err| format!("writing modes.csv: {err}"))
}
