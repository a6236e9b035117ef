//! Frequency responses of a scene's linear model (`flexprr frf`, docs/linear.md): the
//! frequency grid, the responses from every input to every output, and their files:
//! `frf.csv` (magnitude and phase per pair), `frf.json` (operating point, channels, grid,
//! modes) and the Bode figure `bode.svg`. With an identification request the mode shapes
//! are picked from the responses as a modal test would ([`crate::modal_test`]).
//!
//! The responses are `H(i omega) = C (i omega I - A)^-1 B + D` by Laub's Hessenberg method
//! ([`flexprr_linear::frequency_response_direct`]), which stays exact when modes repeat (the
//! three identical links of a locked machine ring at the same frequencies, where an
//! eigenvector expansion loses its accuracy).

use flexprr_kinematics::Pose;
use flexprr_linear::{
    Complex, Input, LinearError, Linearization, Mode, Output, frequency_response_direct, modes,
};
use flexprr_scene::{ScenarioError, Scene};
use serde_json::{Value, json};

use crate::linear::{OperatingPoint, linear_model};
use crate::modal_test::{self, IdentifiedMode};
use flexprr_plot::{Axis, Color, Dash, Figure, Panel, Series, Style};
use flexprr_run::RunError;

/// Points of the default grid (log-spaced).
pub const DEFAULT_POINTS: usize = 2000;
/// Lower end of the default grid (Hz).
pub const DEFAULT_FROM_HZ: f64 = 1.0;
/// The default grid ends at [`HEADROOM`] times the highest of this many lowest modes.
pub const MODES_OF_INTEREST: usize = 12;
/// See [`MODES_OF_INTEREST`].
pub const HEADROOM: f64 = 1.5;
/// Points added about each mode inside the default grid (`-10..=10` quarter bandwidths).
pub const POINTS_PER_MODE: usize = 21;
/// Most frequencies of a grid.
pub const MAX_POINTS: usize = 1_000_000;
/// Most input-output pairs drawn in `bode.svg` (all are in `frf.csv`).
pub const MAX_DRAWN_PAIRS: usize = 12;

/// How the frequencies are chosen.
#[derive(Debug, Clone, PartialEq)]
pub enum Grid {
    /// Evenly spaced from `from_hz` to `to_hz`; an end left out takes the default (1 Hz,
    /// [`HEADROOM`] times the highest of the [`MODES_OF_INTEREST`] lowest modes), `points`
    /// defaults to [`DEFAULT_POINTS`]. With nothing given: log-spaced, plus
    /// [`POINTS_PER_MODE`] points about each mode in the range. With a range given: linear
    /// (an analyser's lines) unless `log`.
    Spaced {
        /// Lower end (Hz).
        from_hz: Option<f64>,
        /// Upper end (Hz).
        to_hz: Option<f64>,
        /// Number of points.
        points: Option<usize>,
        /// Log-spaced.
        log: bool,
    },
    /// Frequencies read from a file.
    Listed {
        /// Where they came from (for `frf.json`).
        source: String,
        /// The frequencies (Hz), increasing.
        frequencies_hz: Vec<f64>,
    },
}

impl Default for Grid {
    fn default() -> Self {
        Grid::Spaced {
            from_hz: None,
            to_hz: None,
            points: None,
            log: false,
        }
    }
}

/// What `flexprr frf` computes.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfRequest {
    /// Where the linear model is taken.
    pub at: OperatingPoint,
    /// Inputs (forces).
    pub inputs: Vec<Input>,
    /// Outputs.
    pub outputs: Vec<Output>,
    /// The frequencies.
    pub grid: Grid,
    /// Number of mode shapes to identify from the responses (0: none).
    pub identify: usize,
    /// How the model is linearised.
    pub settings: flexprr_linear::Settings,
}

/// The frequency responses of a scene at an operating point.
#[derive(Debug, Clone)]
pub struct Frf {
    /// Where the linear model was taken.
    pub at: OperatingPoint,
    /// The model kind (`coupled`, `nonlinear`, ...).
    pub model: String,
    /// The linear model.
    pub lin: Linearization,
    /// Its modes, by frequency.
    pub modes: Vec<Mode>,
    /// How the grid was made (`frf.json`).
    pub grid: Value,
    /// The frequencies (Hz).
    pub frequencies_hz: Vec<f64>,
    /// `response[f][output][input]`.
    pub response: Vec<Vec<Vec<Complex>>>,
    /// The identified mode shapes, when asked for: or why they could not be identified.
    pub identified: Option<Result<Vec<IdentifiedMode>, String>>,
}

/// Bad input at `key`.
fn bad(key: &str, message: impl Into<String>) -> RunError {
    RunError::Scene(ScenarioError::Input {
        location: None,
        key: key.to_string(),
        message: message.into(),
    })
}

/// A numerical failure of the linear layer as a run error.
fn numerics(e: LinearError) -> RunError {
    match e {
        LinearError::Model(e) => RunError::Model(e),
        source => RunError::Analysis {
            analysis: None,
            source,
        },
    }
}

/// The default upper end: [`HEADROOM`] times the highest of the lowest
/// [`MODES_OF_INTEREST`] modes (1 kHz for a model without modes).
pub fn default_upper_hz(modes: &[Mode]) -> f64 {
    modes
        .iter()
        .take(MODES_OF_INTEREST)
        .map(|m| m.frequency_hz)
        .fold(None, |hi: Option<f64>, f| Some(hi.map_or(f, |h| h.max(f))))
        .map_or(1000.0, |f| (HEADROOM * f).max(10.0 * DEFAULT_FROM_HZ))
}

/// `points` frequencies from `from` to `to`, both included, evenly or log-spaced.
fn spaced(from: f64, to: f64, points: usize, log: bool) -> Vec<f64> {
    let last = (points - 1) as f64;
    let mut f: Vec<f64> = (0..points)
        .map(|k| {
            let s = k as f64 / last;
            if log {
                from * (to / from).powf(s)
            } else {
                from + s * (to - from)
            }
        })
        .collect();
    f[points - 1] = to;
    f
}

/// [`POINTS_PER_MODE`] frequencies about each distinct mode in `[from, to]`, a quarter of its
/// half-power bandwidth `2 zeta f` apart (`zeta` taken between `1e-4` and `0.05`, so the
/// points stay within 25 % of the mode), avoiding the natural frequency itself when the
/// mode is undamped (the response is infinite there).
fn about_modes(modes: &[Mode], from: f64, to: f64) -> Vec<f64> {
    let half = (POINTS_PER_MODE / 2) as i32;
    let mut out = Vec::new();
    let mut previous: Option<f64> = None;
    for m in modes
        .iter()
        .filter(|m| m.frequency_hz >= from && m.frequency_hz <= to)
    {
        // A repeated mode (the three identical links) once.
        if previous.is_some_and(|p| (m.frequency_hz - p).abs() <= 1e-6 * p) {
            continue;
        }
        previous = Some(m.frequency_hz);
        let zeta = m.damping_ratio.clamp(1e-4, 0.05);
        let offset = if m.damping_ratio < 1e-9 { 0.5 } else { 0.0 };
        for j in -half..=half {
            let f = m.frequency_hz * (1.0 + (f64::from(j) + offset) * 0.5 * zeta);
            if f >= from && f <= to {
                out.push(f);
            }
        }
    }
    out
}

/// [`resolve_grid`] for a model sampled at the period `dt` (0: continuous): the default
/// upper end stops at the Nyquist frequency `1 / 2 dt`, and a grid beyond it is refused.
///
/// # Errors
/// As [`resolve_grid`]; a frequency above the Nyquist frequency of a discrete model.
pub fn resolve_grid_for(
    grid: &Grid,
    modes: &[Mode],
    dt: f64,
) -> Result<(Vec<f64>, Value), RunError> {
    if dt <= 0.0 {
        return resolve_grid(grid, modes);
    }
    let nyquist = 0.5 / dt;
    let capped = match grid {
        Grid::Spaced {
            from_hz,
            to_hz: None,
            points,
            log,
        } => Grid::Spaced {
            from_hz: *from_hz,
            to_hz: Some(default_upper_hz(modes).min(nyquist)),
            points: *points,
            log: *log || (from_hz.is_none() && points.is_none()),
        },
        other => other.clone(),
    };
    let defaulted = matches!(
        grid,
        Grid::Spaced {
            from_hz: None,
            to_hz: None,
            points: None,
            ..
        }
    );
    let (f, mut description) = resolve_grid(&capped, modes)?;
    if let Some(top) = f.iter().copied().find(|f| *f > nyquist * (1.0 + 1e-12)) {
        let key = if matches!(grid, Grid::Listed { .. }) {
            "--frequencies"
        } else {
            "--to"
        };
        return Err(bad(
            key,
            format!(
                "{top} Hz is above the Nyquist frequency {nyquist} Hz of the discrete-time model                  (the control law samples every {dt} s): a sampled loop's response repeats beyond it"
            ),
        ));
    }
    if defaulted {
        let mut f = f;
        f.extend(about_modes(modes, f[0], nyquist));
        f.retain(|v| *v <= nyquist);
        f.sort_by(f64::total_cmp);
        f.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * b.abs());
        description["kind"] = json!("default");
        description["nyquist_hz"] = json!(nyquist);
        description["points"] = json!(f.len());
        return Ok((f, description));
    }
    description["nyquist_hz"] = json!(nyquist);
    Ok((f, description))
}

/// The grid's frequencies and its description for `frf.json`.
///
/// # Errors
/// Bad grid values (an empty or reversed range, a log range from 0, too few or too many
/// points, listed frequencies that are negative, not finite or not increasing).
pub fn resolve_grid(grid: &Grid, modes: &[Mode]) -> Result<(Vec<f64>, Value), RunError> {
    match grid {
        Grid::Listed {
            source,
            frequencies_hz,
        } => {
            check_listed(frequencies_hz)
                .map_err(|m| bad("--frequencies", format!("{source}: {m}")))?;
            Ok((
                frequencies_hz.clone(),
                json!({"kind": "file", "file": source, "points": frequencies_hz.len()}),
            ))
        }
        Grid::Spaced {
            from_hz,
            to_hz,
            points,
            log,
        } => {
            let default = from_hz.is_none() && to_hz.is_none() && points.is_none();
            let log = *log || default;
            let from = from_hz.unwrap_or(DEFAULT_FROM_HZ);
            let to = to_hz.unwrap_or_else(|| default_upper_hz(modes));
            let points = points.unwrap_or(DEFAULT_POINTS);
            check_spaced(from, to, points, log)?;
            let mut f = spaced(from, to, points, log);
            if default {
                f.extend(about_modes(modes, from, to));
                f.sort_by(f64::total_cmp);
                f.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * b.abs());
            }
            let kind = match (default, log) {
                (true, _) => "default",
                (false, true) => "log",
                (false, false) => "linear",
            };
            let description = json!({
                "kind": kind,
                "from_hz": from,
                "to_hz": to,
                "spaced_points": points,
                "points_about_modes": if default { f.len() - points } else { 0 },
                "points": f.len(),
            });
            Ok((f, description))
        }
    }
}

fn check_spaced(from: f64, to: f64, points: usize, log: bool) -> Result<(), RunError> {
    if !(from.is_finite() && from >= 0.0) {
        return Err(bad(
            "--from",
            format!("{from} Hz: expected a finite frequency >= 0"),
        ));
    }
    if log && from <= 0.0 {
        return Err(bad(
            "--from",
            "a log-spaced grid needs --from > 0 Hz (0 lies at minus infinity on a log axis)",
        ));
    }
    if !(to.is_finite() && to > from) {
        return Err(bad(
            "--to",
            format!("{to} Hz: expected a finite frequency above --from ({from} Hz)"),
        ));
    }
    if !(2..=MAX_POINTS).contains(&points) {
        return Err(bad(
            "--points",
            format!("{points}: expected 2 to {MAX_POINTS} points"),
        ));
    }
    Ok(())
}

/// Why listed frequencies are not a grid, if they are not.
pub fn check_listed(f: &[f64]) -> Result<(), String> {
    if f.is_empty() || f.len() > MAX_POINTS {
        return Err(format!(
            "{} frequencies: expected 1 to {MAX_POINTS}",
            f.len()
        ));
    }
    if let Some((k, v)) = f
        .iter()
        .enumerate()
        .find(|(_, v)| !(v.is_finite() && **v >= 0.0))
    {
        return Err(format!(
            "frequency {} is {v}: expected a finite frequency >= 0 Hz",
            k + 1
        ));
    }
    if let Some(k) = (1..f.len()).find(|&k| f[k] <= f[k - 1]) {
        return Err(format!(
            "frequency {} ({} Hz) is not above the one before ({} Hz): list them increasing",
            k + 1,
            f[k],
            f[k - 1]
        ));
    }
    Ok(())
}

/// The frequency responses of `scene` for `request`: the linear model at the operating
/// point, its modes, the grid, the responses and, when asked for, the identified mode
/// shapes.
///
/// # Errors
/// As [`linear_model`]; a bad grid or an identification request the channels do not
/// allow (bad input); a response that is infinite at a grid frequency (an undamped mode
/// exactly there).
pub fn frequency_responses(scene: &Scene, request: &FrfRequest) -> Result<Frf, RunError> {
    frequency_responses_with_progress(scene, request, &mut |_, _| {})
}

/// [`frequency_responses`], calling `progress(stage, share)` as it goes: `"linear model"`
/// (0 at its start), then `"responses"` with the share of the frequencies done.
///
/// # Errors
/// As [`frequency_responses`].
pub fn frequency_responses_with_progress(
    scene: &Scene,
    request: &FrfRequest,
    progress: &mut dyn FnMut(&str, f64),
) -> Result<Frf, RunError> {
    if request.inputs.is_empty() || request.outputs.is_empty() {
        return Err(bad(
            if request.inputs.is_empty() {
                "--input"
            } else {
                "--output"
            },
            "give at least one input and one output (e.g. --input point_force:1@0.125 --output acceleration:1@0.5)",
        ));
    }
    let layout = if request.identify > 0 {
        Some(
            modal_test::layout(&request.inputs, &request.outputs)
                .map_err(|m| bad("--identify", m))?,
        )
    } else {
        None
    };
    progress("linear model", 0.0);
    let lin = linear_model(
        scene,
        request.at,
        &request.inputs,
        &request.outputs,
        &request.settings,
    )?;
    let modes = modes(&lin).map_err(numerics)?;
    let (frequencies_hz, grid) = resolve_grid_for(&request.grid, &modes, lin.dt)?;
    let response =
        flexprr_linear::frequency_response_with_progress(&lin, &frequencies_hz, &mut |share| {
            progress("responses", share);
        })
        .map_err(numerics)?;
    let identified = layout.map(|xi| {
        modal_test::identify(
            &frequencies_hz,
            &response,
            &xi,
            request.identify,
            &mut |f: &[f64]| frequency_response_direct(&lin, f).map_err(|e| e.to_string()),
        )
    });
    Ok(Frf {
        at: request.at,
        model: scene.coupling.name().to_string(),
        lin,
        modes,
        grid,
        frequencies_hz,
        response,
        identified,
    })
}

/// A channel as a header token: `deflection_1_xi0.5`, `slider_force_2`, `platform_phi`.
pub fn token(channel: &str) -> String {
    channel.replace(':', "_").replace('@', "_xi")
}

/// A unit as a header token (`m/s^2` -> `m_s2`, `N m` -> `Nm`).
fn unit_token(unit: &str) -> String {
    unit.replace("/s^2", "_s2")
        .replace('/', "_")
        .replace(' ', "")
}

/// The magnitude's unit (`m/N`, `m/s^2/N`) and its header token (`m_N`, `m_s2_N`).
fn ratio_unit(output: &Output, input: &Input) -> (String, String) {
    (
        format!("{}/{}", output.unit(), input.unit()),
        format!("{}_{}", unit_token(output.unit()), unit_token(input.unit())),
    )
}

/// The two CSV headers of a pair: magnitude (with its unit) and phase (deg).
pub fn pair_headers(output: &Output, input: &Input) -> (String, String) {
    let stem = format!(
        "{}_per_{}",
        token(&output.to_string()),
        token(&input.to_string())
    );
    let (_, unit) = ratio_unit(output, input);
    (format!("{stem}_mag_{unit}"), format!("{stem}_phase_deg"))
}

/// `frf.csv`: `f_Hz`, then for each output and each input its magnitude and phase
/// (degrees, in `(-180, 180]`), every value as `{:.10e}` like the run's tables.
pub fn frf_csv(frf: &Frf) -> String {
    let mut header = vec!["f_Hz".to_string()];
    for output in &frf.lin.outputs {
        for input in &frf.lin.inputs {
            let (mag, phase) = pair_headers(output, input);
            header.push(mag);
            header.push(phase);
        }
    }
    let mut text = header.join(",");
    text.push('\n');
    for (k, f) in frf.frequencies_hz.iter().enumerate() {
        let mut row = vec![format!("{f:.10e}")];
        for per_output in &frf.response[k] {
            for h in per_output {
                row.push(format!("{:.10e}", h.norm()));
                row.push(format!("{:.10e}", phase_deg(*h)));
            }
        }
        text.push_str(&row.join(","));
        text.push('\n');
    }
    text
}

/// The phase in degrees in `(-180, 180]` (0 for a zero response).
pub fn phase_deg(h: Complex) -> f64 {
    let p = h.arg().to_degrees();
    if p <= -180.0 { p + 360.0 } else { p }
}

/// The operating point for `frf.json` and `statespace.json`.
pub fn operating_point_json(at: &OperatingPoint, lin: &Linearization) -> Value {
    match at {
        OperatingPoint::Rest(Pose { x, y, phi }) => json!({
            "kind": "rest",
            "pose": {"x_m": x, "y_m": y, "phi_deg": phi.to_degrees()},
            "t_s": lin.t,
        }),
        OperatingPoint::Time(t) => json!({"kind": "time", "t_s": t}),
    }
}

/// The linear model's modes as JSON objects (frequency, damping ratio, eigenvalue).
pub fn modes_json(modes: &[Mode]) -> Vec<Value> {
    modes
        .iter()
        .map(|m| {
            json!({
                "frequency_hz": m.frequency_hz,
                "damping_ratio": m.damping_ratio,
                "eigenvalue": [m.eigenvalue.re, m.eigenvalue.im],
            })
        })
        .collect()
}

/// `frf.json`: the scene, the model, the operating point, the channels with their units
/// and values there, the grid, the columns of `frf.csv`, the modes up to the grid's end
/// and the identified mode shapes.
pub fn frf_json(scene: &Scene, frf: &Frf) -> Value {
    let lin = &frf.lin;
    let top = frf.frequencies_hz.last().copied().unwrap_or(0.0);
    let columns: Vec<Value> = lin
        .outputs
        .iter()
        .flat_map(|o| lin.inputs.iter().map(move |i| (o, i)))
        .map(|(o, i)| {
            let (mag, phase) = pair_headers(o, i);
            json!({
                "output": o.to_string(), "input": i.to_string(),
                "magnitude": mag, "phase": phase, "unit": ratio_unit(o, i).0,
            })
        })
        .collect();
    let mut value = json!({
        "flexprr_version": env!("CARGO_PKG_VERSION"),
        "scene": scene.name,
        "model": frf.model,
        "operating_point": operating_point_json(&frf.at, lin),
        "inputs": lin.inputs.iter().map(|i| json!({"name": i.to_string(), "unit": i.unit()})).collect::<Vec<_>>(),
        "outputs": lin.outputs.iter().zip(&lin.output_values).map(|(o, v)| json!({
            "name": o.to_string(), "unit": o.unit(), "value_at_operating_point": v,
        })).collect::<Vec<_>>(),
        "grid": frf.grid,
        "dt_s": lin.dt,
        "notes": lin.notes,
        "method": if lin.dt > 0.0 {
            "H(z) = C (z I - A)^-1 B + D at z = exp(i w dt) (the discrete-time model of the sampled loop), Hessenberg method (Laub 1981); A, B, C, D from flexprr-linear"
        } else {
            "H(i w) = C (i w I - A)^-1 B + D, Hessenberg method (Laub 1981); A, B, C, D from flexprr-linear"
        },
        "columns": columns,
        "modes": modes_json(&frf.modes.iter().filter(|m| m.frequency_hz <= top).cloned().collect::<Vec<_>>()),
    });
    if let Some(identified) = &frf.identified {
        value["identified"] = match identified {
            Ok(modes) => modal_test::identified_json(modes, &frf.modes),
            Err(reason) => json!({"failed": reason}),
        };
    }
    value
}

/// A short label of a pair for the legend.
fn pair_label(frf: &Frf, o: usize, i: usize) -> String {
    let (output, input) = (&frf.lin.outputs[o], &frf.lin.inputs[i]);
    match (frf.lin.outputs.len(), frf.lin.inputs.len()) {
        (_, 1) => output.to_string(),
        (1, _) => format!("from {input}"),
        _ => format!("{output} / {input}"),
    }
}

/// The distinct mode frequencies inside `[lo, hi]`.
fn marked_modes(modes: &[Mode], lo: f64, hi: f64) -> Vec<f64> {
    let mut f: Vec<f64> = modes
        .iter()
        .map(|m| m.frequency_hz)
        .filter(|f| *f >= lo && *f <= hi)
        .collect();
    f.dedup_by(|a, b| (*a - *b).abs() <= 1e-6 * b.abs());
    f
}

/// Grey dotted vertical lines at the modes, from `lo` to `hi` on the panel's y axis.
fn mode_lines(panel: Panel, modes: &[f64], (lo, hi): (f64, f64), label: bool) -> Panel {
    let style = Style {
        color: Color(140, 140, 140),
        dash: Dash::Dotted,
        marker: None,
        line: true,
    };
    modes.iter().enumerate().fold(panel, |panel, (k, f)| {
        let name = if label && k == 0 {
            "modes of the linear model"
        } else {
            ""
        };
        panel.series(Series::new(name, &[*f, *f], &[lo, hi], style))
    })
}

/// The phase of one pair in degrees at the frequencies `f`, with a gap (a point without
/// value) where it wraps.
fn phase_series(f: &[f64], values: &[Complex]) -> (Vec<f64>, Vec<f64>) {
    let mut x = Vec::with_capacity(values.len() + 8);
    let mut y = Vec::with_capacity(values.len() + 8);
    let mut last: Option<f64> = None;
    for (fk, h) in f.iter().zip(values) {
        let p = phase_deg(*h);
        if let (Some(q), Some(fq)) = (last, x.last().copied()) {
            if (p - q).abs() > 180.0 {
                x.push(0.5 * (fq + fk));
                y.push(f64::NAN);
            }
        }
        x.push(*fk);
        y.push(p);
        last = Some(p);
    }
    (x, y)
}

/// `bode.svg`: one magnitude panel (log) per unit of the pairs and one phase panel, against
/// log frequency, one curve per pair (the first [`MAX_DRAWN_PAIRS`]), the modes of the
/// linear model marked; pairs that are zero to round-off are named in the title, not drawn.
pub fn bode_figure(scene: &Scene, frf: &Frf) -> Figure {
    let (p, m) = (frf.lin.outputs.len(), frf.lin.inputs.len());
    let drawn_f: Vec<usize> = (0..frf.frequencies_hz.len())
        .filter(|&k| frf.frequencies_hz[k] > 0.0)
        .collect();
    let f: Vec<f64> = drawn_f.iter().map(|&k| frf.frequencies_hz[k]).collect();
    let magnitude = |o: usize, i: usize| -> Vec<f64> {
        drawn_f
            .iter()
            .map(|&k| frf.response[k][o][i].norm())
            .collect()
    };
    let largest = (0..p)
        .flat_map(|o| (0..m).map(move |i| (o, i)))
        .flat_map(|(o, i)| magnitude(o, i))
        .fold(0.0_f64, f64::max);
    let pairs: Vec<(usize, usize)> = (0..p).flat_map(|o| (0..m).map(move |i| (o, i))).collect();
    let (zero, nonzero): (Vec<_>, Vec<_>) = pairs.iter().partition(|&&(o, i)| {
        magnitude(o, i).iter().fold(0.0_f64, |a, b| a.max(*b)) <= 1e-9 * largest
    });
    let drawn: Vec<(usize, usize)> = nonzero.iter().take(MAX_DRAWN_PAIRS).copied().collect();
    let mut units: Vec<String> = Vec::new();
    for &(o, i) in &drawn {
        let unit = ratio_unit(&frf.lin.outputs[o], &frf.lin.inputs[i]).0;
        if !units.contains(&unit) {
            units.push(unit);
        }
    }
    let (lo_f, hi_f) = (
        f.first().copied().unwrap_or(1.0),
        f.last().copied().unwrap_or(1.0),
    );
    let marks = marked_modes(&frf.modes, lo_f, hi_f);
    let mut title = format!("Frequency response, {}", at_words(&frf.at));
    if drawn.len() < nonzero.len() {
        title.push_str(&format!(
            "; the first {} of {} pairs drawn (all in frf.csv)",
            drawn.len(),
            nonzero.len()
        ));
    }
    if !zero.is_empty() {
        let names: Vec<String> = zero.iter().map(|p| pair_label(frf, p.0, p.1)).collect();
        title.push_str(&format!(
            "; zero to round-off, not drawn: {}",
            names.join(", ")
        ));
    }
    let mut figure = Figure::new(Axis::log("f", "Hz")).title(title).description(format!(
        "flexprr frf: scene {}, {} model; magnitude and phase of H(i w) = C (i w I - A)^-1 B + D",
        scene.name, frf.model
    ));
    for (u, unit) in units.iter().enumerate() {
        let mut panel = Panel::new(Axis::log("|H|", unit.replace("^2", "²")));
        let (mut lo, mut hi) = (f64::INFINITY, 0.0_f64);
        for (k, &(o, i)) in drawn.iter().enumerate() {
            if ratio_unit(&frf.lin.outputs[o], &frf.lin.inputs[i]).0 != *unit {
                continue;
            }
            let y = magnitude(o, i);
            for v in y.iter().filter(|v| **v > 0.0) {
                lo = lo.min(*v);
                hi = hi.max(*v);
            }
            panel = panel.series(Series::new(pair_label(frf, o, i), &f, &y, Style::nth(k)));
        }
        if hi > 0.0 {
            panel = mode_lines(panel, &marks, (lo, hi), u == 0);
        }
        figure = figure.panel(panel);
    }
    let mut phase = Panel::new(Axis::new("phase", "deg"));
    for (k, &(o, i)) in drawn.iter().enumerate() {
        let values: Vec<Complex> = drawn_f.iter().map(|&j| frf.response[j][o][i]).collect();
        let (x, y) = phase_series(&f, &values);
        phase = phase.series(Series::new("", &x, &y, Style::nth(k)));
    }
    figure.panel(mode_lines(phase, &marks, (-180.0, 180.0), false))
}

/// The operating point in words (figure titles).
pub fn at_words(at: &OperatingPoint) -> String {
    match at {
        OperatingPoint::Rest(p) => format!(
            "at rest at ({} m, {} m, {} deg)",
            p.x,
            p.y,
            (p.phi.to_degrees() * 1e9).round() / 1e9
        ),
        OperatingPoint::Time(t) => format!("along the motion at t = {t} s"),
    }
}

/// Writes `frf.csv`, `frf.json`, `bode.svg` and, when mode shapes were identified,
/// `mode_shapes.csv` and `mode_shapes.svg` into `dir` (staged, then published). Returns the
/// names written.
///
/// # Errors
/// [`ScenarioError::Io`] when a file cannot be written, [`ScenarioError::Input`] when the
/// directory was taken meanwhile.
pub fn write_frf(
    scene: &Scene,
    frf: &Frf,
    dir: &flexprr_outdir::OutputDir,
) -> Result<Vec<String>, ScenarioError> {
    let staging = dir.stage()?;
    let put = |name: &str, text: &str| {
        std::fs::write(staging.path().join(name), text)
            .map_err(|e| flexprr_outdir::OutputError::io(&staging.path().join(name), e))
    };
    put("frf.csv", &frf_csv(frf))?;
    let json = frf_json(scene, frf);
    put(
        "frf.json",
        &(serde_json::to_string_pretty(&json).unwrap_or_else(|_| json.to_string()) + "\n"),
    )?;
    let svg = |figure: Figure| {
        figure.to_svg().map_err(|message| ScenarioError::Write {
            path: "bode.svg".to_string(),
            message,
        })
    };
    put("bode.svg", &svg(bode_figure(scene, frf))?)?;
    if let Some(Ok(identified)) = &frf.identified {
        put("mode_shapes.csv", &modal_test::mode_shapes_csv(identified))?;
        let figure = modal_test::mode_shapes_figure(identified, &at_words(&frf.at));
        put("mode_shapes.svg", &svg(figure)?)?;
    }
    Ok(staging.publish()?)
}

/// The response of output `o` to input `i` at the frequency `f` (Hz) in closed form for a
/// single undamped oscillator: used by the tests of this module.
#[cfg(test)]
fn oscillator(f: f64, natural_hz: f64) -> Complex {
    let w = std::f64::consts::TAU * f;
    let wn = std::f64::consts::TAU * natural_hz;
    Complex::new(1.0 / (wn * wn - w * w), 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_are_as_documented() {
        let f = spaced(1.0, 1000.0, 4, true);
        for (got, want) in f.iter().zip([1.0, 10.0, 100.0, 1000.0]) {
            assert!((got - want).abs() < 1e-9 * want);
        }
        assert_eq!(spaced(0.0, 3.0, 4, false), vec![0.0, 1.0, 2.0, 3.0]);
        assert!(check_listed(&[1.0, 1.0]).is_err());
        assert!(check_listed(&[-1.0]).is_err());
        assert!(check_listed(&[0.0, 2.0]).is_ok());
        assert!(check_spaced(0.0, 10.0, 10, true).is_err());
        assert!(check_spaced(5.0, 1.0, 10, false).is_err());
        assert!(check_spaced(1.0, 10.0, 1, false).is_err());
    }

    #[test]
    fn tokens_and_phases() {
        let (mag, phase) = pair_headers(
            &Output::Deflection { link: 0, xi: 0.5 },
            &Input::PointForce { link: 0, xi: 0.125 },
        );
        assert_eq!(mag, "deflection_1_xi0.5_per_point_force_1_xi0.125_mag_m_N");
        assert_eq!(
            phase,
            "deflection_1_xi0.5_per_point_force_1_xi0.125_phase_deg"
        );
        let (mag, _) = pair_headers(
            &Output::Acceleration { link: 2, xi: 1.0 },
            &Input::SliderForce(1),
        );
        assert_eq!(mag, "acceleration_3_xi1_per_slider_force_2_mag_m_s2_N");
        // Below resonance in phase, above it in antiphase.
        assert!(phase_deg(oscillator(5.0, 10.0)).abs() < 1e-12);
        assert!((phase_deg(oscillator(20.0, 10.0)) - 180.0).abs() < 1e-12);
        assert!((phase_deg(Complex::new(-1.0, -0.0)) - 180.0).abs() < 1e-12);
    }
}
