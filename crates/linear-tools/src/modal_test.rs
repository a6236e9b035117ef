//! Mode shapes identified from frequency responses, as an experimental modal test does it
//! (the paper's Section 2.3: one hammer point, the accelerometer moved along link 1): the
//! quadrature ("imaginary part") peak picking of D. J. Ewins, *Modal Testing: Theory,
//! Practice and Application*, 2nd ed., 2000, section 4.2.
//!
//! Near a lightly damped, well separated mode `r`, the accelerance between the hammer at
//! `k` and a point `j` is dominated by `-omega^2 phi_jr phi_kr / (omega_r^2 - omega^2 + 2 i
//! zeta_r omega_r omega)`, whose imaginary part at resonance is `phi_jr phi_kr / (2
//! zeta_r)`: over the points `j` it is the mode shape times a constant. So:
//!
//! 1. the resonances are the prominent peaks of `S(f) = sum_j |Im H_jk(f)|` on the grid;
//! 2. each is refined by zooming (the analyser's zoom band: 41 lines between the peak's
//!    neighbours, five times, each band the neighbours of the last maximum);
//! 3. the shape is `Im H_jk` at the refined resonance, normalised to 1 at its largest entry
//!    and signed so that the first point that moves (|value| above 1 %) is positive, as
//!    `sin(j pi xi)` is near `xi = 0`;
//! 4. it is compared with the pinned-pinned sines `sin(j pi xi)` sampled at the points and
//!    normalised the same way: the best match by the modal assurance criterion (MAC,
//!    Ewins 2000, section 8.4), and the largest difference at the points.

use serde_json::{Value, json};

use flexprr_linear::{Complex, Input, Mode, Output};

use flexprr_plot::{Axis, Figure, Marker, Panel, Series, Style};

/// Lines of each zoom band.
const ZOOM_LINES: usize = 41;
/// Zoom bands per resonance.
const ZOOMS: usize = 5;
/// A resonance's peak must stand this many times above the higher of its two bases.
const PROMINENCE: f64 = 2.0;
/// Relative size of the first point that moves, for the sign of a shape.
const MOVES: f64 = 0.01;

/// One mode shape identified from the responses.
#[derive(Debug, Clone, PartialEq)]
pub struct IdentifiedMode {
    /// 1-based, in order of frequency.
    pub number: usize,
    /// The resonance, refined by zooming (Hz).
    pub frequency_hz: f64,
    /// The grid frequency of the peak (Hz).
    pub grid_frequency_hz: f64,
    /// Where the points are along the link.
    pub xi: Vec<f64>,
    /// The normalised imaginary parts at the points.
    pub shape: Vec<f64>,
    /// `j` of the best-matching pinned-pinned sine `sin(j pi xi)`.
    pub sine: usize,
    /// That sine at the points, normalised as the shape.
    pub sine_shape: Vec<f64>,
    /// Largest difference between the shape and the sine at the points.
    pub max_difference: f64,
    /// Modal assurance criterion of the shape and the sine.
    pub mac: f64,
}

/// The positions `xi` of the outputs when they allow an identification: one input, and
/// outputs that are all accelerations (accelerance) or all deflections (receptance) on
/// one link at three or more distinct points.
///
/// # Errors
/// The rule broken, in one line.
pub fn layout(inputs: &[Input], outputs: &[Output]) -> Result<Vec<f64>, String> {
    if inputs.len() != 1 {
        return Err(format!(
            "identifying mode shapes needs exactly one input (the hammer), got {}",
            inputs.len()
        ));
    }
    let point = |o: &Output| match *o {
        Output::Acceleration { link, xi } => Some((0, link, xi)),
        Output::Deflection { link, xi } => Some((1, link, xi)),
        _ => None,
    };
    let points: Vec<_> = outputs.iter().map(point).collect();
    let Some(Some((kind, link, _))) = points.first().copied() else {
        return Err("identifying mode shapes needs outputs acceleration:LINK@XI (or deflection:LINK@XI) along one link".into());
    };
    if points
        .iter()
        .any(|p| !matches!(p, Some((k, l, _)) if *k == kind && *l == link))
    {
        return Err(format!(
            "identifying mode shapes needs every output of the same kind on the same link \
             (all acceleration:{0}@XI or all deflection:{0}@XI)",
            link + 1
        ));
    }
    let xi: Vec<f64> = points.iter().flatten().map(|p| p.2).collect();
    let mut distinct = xi.clone();
    distinct.sort_by(f64::total_cmp);
    distinct.dedup();
    if distinct.len() < 3 {
        return Err(format!(
            "identifying mode shapes needs outputs at three or more points of the link, got {}",
            distinct.len()
        ));
    }
    Ok(xi)
}

/// `S(f) = sum_j |Im H_j|` of the single input at each frequency.
fn quadrature_sum(response: &[Vec<Vec<Complex>>]) -> Vec<f64> {
    response
        .iter()
        .map(|per_output| per_output.iter().map(|r| r[0].im.abs()).sum())
        .collect()
}

/// Indices of the prominent interior peaks of `s`, in order.
fn prominent_peaks(s: &[f64]) -> Vec<usize> {
    let n = s.len();
    let mut peaks = Vec::new();
    for k in 1..n.saturating_sub(1) {
        if !(s[k] > s[k - 1] && s[k] >= s[k + 1]) {
            continue;
        }
        let base = |range: &mut dyn Iterator<Item = usize>| {
            let mut low = s[k];
            for j in range {
                if s[j] > s[k] {
                    break;
                }
                low = low.min(s[j]);
            }
            low
        };
        let left = base(&mut (0..k).rev());
        let right = base(&mut (k + 1..n));
        if s[k] >= PROMINENCE * left.max(right) {
            peaks.push(k);
        }
    }
    peaks
}

/// A response at frequencies (Hz), for zooming: `[f][output][input]`.
pub type Zoom<'a> = dyn FnMut(&[f64]) -> Result<Vec<Vec<Vec<Complex>>>, String> + 'a;

/// The frequency of the largest `S` between `lo` and `hi`, by repeated zoom bands.
fn zoom_in(mut lo: f64, mut hi: f64, zoom: &mut Zoom<'_>) -> Result<(f64, Vec<f64>), String> {
    let mut best = (0.5 * (lo + hi), Vec::new());
    for _ in 0..ZOOMS {
        let band: Vec<f64> = (0..ZOOM_LINES)
            .map(|k| lo + (hi - lo) * k as f64 / (ZOOM_LINES - 1) as f64)
            .collect();
        let response = zoom(&band)?;
        let s = quadrature_sum(&response);
        let k = (0..s.len())
            .max_by(|a, b| s[*a].total_cmp(&s[*b]))
            .unwrap_or(0);
        best = (band[k], response[k].iter().map(|r| r[0].im).collect());
        lo = band[k.saturating_sub(1)];
        hi = band[(k + 1).min(ZOOM_LINES - 1)];
    }
    Ok(best)
}

/// `v` divided by its entry of largest magnitude, signed so that the first entry above
/// [`MOVES`] is positive.
fn normalise(v: &[f64]) -> Vec<f64> {
    let largest = v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    if largest == 0.0 {
        return v.to_vec();
    }
    let sign = v
        .iter()
        .find(|x| x.abs() > MOVES * largest)
        .map_or(1.0, |x| x.signum());
    v.iter().map(|x| sign * x / largest).collect()
}

/// The modal assurance criterion of two real shapes.
fn mac(a: &[f64], b: &[f64]) -> f64 {
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>();
    let d = dot(a, a) * dot(b, b);
    if d > 0.0 { dot(a, b).powi(2) / d } else { 0.0 }
}

/// The best-matching pinned-pinned sine of `shape` at the points `xi`: `(j, sine, MAC)`,
/// `j` from 1 to the number of distinct points less 2 (higher sines alias on them).
fn best_sine(shape: &[f64], xi: &[f64]) -> (usize, Vec<f64>, f64) {
    let mut distinct = xi.to_vec();
    distinct.sort_by(f64::total_cmp);
    distinct.dedup();
    let top = distinct.len().saturating_sub(2).max(1);
    (1..=top)
        .map(|j| {
            let sine: Vec<f64> = xi
                .iter()
                .map(|x| (j as f64 * std::f64::consts::PI * x).sin())
                .collect();
            let sine = normalise(&sine);
            let m = mac(shape, &sine);
            (j, sine, m)
        })
        .max_by(|a, b| a.2.total_cmp(&b.2))
        .unwrap_or((1, vec![0.0; xi.len()], 0.0))
}

/// The first `count` mode shapes identified from the responses `response[f][output][0]`
/// over `frequencies_hz` at the points `xi` (module documentation); `zoom` evaluates the
/// responses at more frequencies.
///
/// # Errors
/// Fewer than `count` prominent resonances inside the grid (the message says how many and
/// where), or a zoom that failed.
pub fn identify(
    frequencies_hz: &[f64],
    response: &[Vec<Vec<Complex>>],
    xi: &[f64],
    count: usize,
    zoom: &mut Zoom<'_>,
) -> Result<Vec<IdentifiedMode>, String> {
    let s = quadrature_sum(response);
    let peaks = prominent_peaks(&s);
    if peaks.len() < count {
        let found: Vec<String> = peaks
            .iter()
            .map(|k| format!("{:.2} Hz", frequencies_hz[*k]))
            .collect();
        return Err(format!(
            "found {} resonance(s) inside the grid ({}), fewer than the {count} asked for: \
             extend the grid (--to), make it denser (--points), or give the modes damping \
             (model.damping) so that their peaks stand out in the imaginary part",
            peaks.len(),
            if found.is_empty() {
                "none".to_string()
            } else {
                found.join(", ")
            }
        ));
    }
    peaks
        .iter()
        .take(count)
        .enumerate()
        .map(|(r, &k)| {
            let (f, imaginary) = zoom_in(frequencies_hz[k - 1], frequencies_hz[k + 1], &mut *zoom)?;
            let shape = normalise(&imaginary);
            let (sine, sine_shape, mac) = best_sine(&shape, xi);
            let max_difference = shape
                .iter()
                .zip(&sine_shape)
                .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
            Ok(IdentifiedMode {
                number: r + 1,
                frequency_hz: f,
                grid_frequency_hz: frequencies_hz[k],
                xi: xi.to_vec(),
                shape,
                sine,
                sine_shape,
                max_difference,
                mac,
            })
        })
        .collect()
}

/// The nearest mode of the linear model to `f`.
fn nearest(modes: &[Mode], f: f64) -> Option<&Mode> {
    modes.iter().min_by(|a, b| {
        (a.frequency_hz - f)
            .abs()
            .total_cmp(&(b.frequency_hz - f).abs())
    })
}

/// The identified shapes for `frf.json`, each with the nearest mode of the linear model.
pub fn identified_json(identified: &[IdentifiedMode], modes: &[Mode]) -> Value {
    let list: Vec<Value> = identified
        .iter()
        .map(|m| {
            let model = nearest(modes, m.frequency_hz);
            json!({
                "mode": m.number,
                "frequency_hz": m.frequency_hz,
                "grid_frequency_hz": m.grid_frequency_hz,
                "model_frequency_hz": model.map(|n| n.frequency_hz),
                "model_damping_ratio": model.map(|n| n.damping_ratio),
                "relative_frequency_difference": model.map(|n| (m.frequency_hz - n.frequency_hz) / n.frequency_hz),
                "xi": m.xi,
                "shape": m.shape,
                "sine": format!("sin({} pi xi)", m.sine),
                "sine_j": m.sine,
                "sine_shape": m.sine_shape,
                "max_difference": m.max_difference,
                "mac": m.mac,
            })
        })
        .collect();
    json!({
        "method": "quadrature peak picking (Ewins, Modal Testing, 2000, 4.2): Im H at each resonance, zoom-refined; normalised to 1 at the largest point, first moving point positive",
        "modes": list,
    })
}

/// `mode_shapes.csv`: the point number (1-based, in the order of the outputs), `xi`, and
/// for each identified mode its normalised shape and its best-matching sine.
pub fn mode_shapes_csv(identified: &[IdentifiedMode]) -> String {
    let mut header = vec!["point".to_string(), "xi".to_string()];
    for m in identified {
        header.push(format!("mode_{}", m.number));
        header.push(format!("sine_{}", m.number));
    }
    let mut text = header.join(",") + "\n";
    let points = identified.first().map_or(0, |m| m.xi.len());
    for p in 0..points {
        let mut row = vec![
            format!("{}", p + 1),
            format!("{:.10e}", identified[0].xi[p]),
        ];
        for m in identified {
            row.push(format!("{:.10e}", m.shape[p]));
            row.push(format!("{:.10e}", m.sine_shape[p]));
        }
        text.push_str(&row.join(","));
        text.push('\n');
    }
    text
}

/// `mode_shapes.svg`, like the paper's Figs. 3-4: one panel per identified mode, the
/// normalised shape at the points as markers and its pinned-pinned sine as a line.
pub fn mode_shapes_figure(identified: &[IdentifiedMode], context: &str) -> Figure {
    let mut figure = Figure::new(Axis::new("ξ", ""))
        .title(format!(
            "Mode shapes from the frequency responses (Im H at resonance) and the pinned-pinned sines, {context}"
        ))
        .description("flexprr frf --identify: quadrature peak picking (Ewins 2000)");
    for m in identified {
        let x: Vec<f64> = (0..=200).map(|k| k as f64 / 200.0).collect();
        // The sine normalised by the same factor as its samples at the points.
        let sampled: Vec<f64> =
            m.xi.iter()
                .map(|x| (m.sine as f64 * std::f64::consts::PI * x).sin())
                .collect();
        let scale = m
            .sine_shape
            .iter()
            .zip(&sampled)
            .find(|(_, s)| s.abs() > MOVES)
            .map_or(1.0, |(n, s)| n / s);
        let y: Vec<f64> = x
            .iter()
            .map(|x| scale * (m.sine as f64 * std::f64::consts::PI * x).sin())
            .collect();
        let sine_label = if m.sine == 1 {
            "sin(π ξ)".to_string()
        } else {
            format!("sin({} π ξ)", m.sine)
        };
        let points = Style {
            line: false,
            ..Style::nth(1).marker(Marker::Disc)
        };
        let panel = Panel::new(Axis::new(format!("mode {}", m.number), ""))
            .series(Series::new(sine_label, &x, &y, Style::nth(0)))
            .series(Series::new(
                format!(
                    "identified at {:.2} Hz (max. difference {:.1e})",
                    m.frequency_hz, m.max_difference
                ),
                &m.xi,
                &m.shape,
                points,
            ));
        figure = figure.panel(panel);
    }
    figure
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two modes of a pinned-pinned beam (unit modal masses) seen at nine points, hammer at
    /// `xi = 0.125`, 1 % damping: the identified shapes are the sines.
    fn beam(f: &[f64], xi: &[f64]) -> Vec<Vec<Vec<Complex>>> {
        let hammer = 0.125;
        f.iter()
            .map(|&f| {
                let w = std::f64::consts::TAU * f;
                xi.iter()
                    .map(|&x| {
                        let mut h = Complex::default();
                        for (j, fr) in [(1.0, 116.4), (2.0, 465.6)] {
                            let wr = std::f64::consts::TAU * fr;
                            let pi = std::f64::consts::PI;
                            let residue = (j * pi * x).sin() * (j * pi * hammer).sin();
                            let denominator = Complex::new(wr * wr - w * w, 2.0 * 0.01 * wr * w);
                            h = h + Complex::new(-w * w * residue, 0.0) / denominator;
                        }
                        vec![h]
                    })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn the_sines_come_back_from_a_two_mode_beam() {
        let xi: Vec<f64> = (0..9).map(|k| k as f64 / 8.0).collect();
        let f: Vec<f64> = (1..=1000).map(f64::from).collect();
        let response = beam(&f, &xi);
        let mut zoom = |g: &[f64]| Ok(beam(g, &xi));
        let modes = identify(&f, &response, &xi, 2, &mut zoom).unwrap();
        assert_eq!((modes[0].sine, modes[1].sine), (1, 2));
        for m in &modes {
            assert!(m.max_difference < 1e-3 && m.mac > 0.9999, "{m:?}");
        }
        assert!((modes[0].frequency_hz - 116.4).abs() < 0.05);
        assert!((modes[1].frequency_hz - 465.6).abs() < 0.1);
        assert!(identify(&f, &response, &xi, 3, &mut zoom).is_err());
    }

    #[test]
    fn layouts_are_checked() {
        let acc = |xi| Output::Acceleration { link: 0, xi };
        let hammer = [Input::PointForce { link: 0, xi: 0.1 }];
        assert!(layout(&hammer, &[acc(0.1), acc(0.5), acc(0.9)]).is_ok());
        assert!(layout(&hammer, &[acc(0.1), acc(0.5)]).is_err());
        assert!(layout(&[], &[acc(0.1), acc(0.5), acc(0.9)]).is_err());
        let mixed = [acc(0.1), acc(0.5), Output::Deflection { link: 0, xi: 0.9 }];
        assert!(layout(&hammer, &mixed).is_err());
        let other_link = [
            acc(0.1),
            acc(0.5),
            Output::Acceleration { link: 1, xi: 0.9 },
        ];
        assert!(layout(&hammer, &other_link).is_err());
    }
}
