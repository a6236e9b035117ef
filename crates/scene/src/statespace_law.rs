//! `[control] kind = "statespace"` (docs/control.md, "State-space laws"): a linear law read
//! from an `.npz` file (arrays `A`, `B`, `C`, `D` and an optional `dt`), its measurements
//! and commands named by the linear tools' channels, checked at its keys.

use std::path::Path;
use std::sync::Arc;

use flexprr_control::{Controller, SliderSignal, StateSpaceLaw, StateSpaceMatrices};
use flexprr_dynamics::channel::{Input, Output};
use nalgebra::DMatrix;
use serde::Deserialize;

use crate::controllers::{ControllerFactory, Feedforward};
use crate::error::ScenarioError;
use crate::registry::TableParams;

/// The keys of `kind = "statespace"`.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Keys {
    file: String,
    measurements: Vec<String>,
    commands: Vec<String>,
    #[serde(default)]
    feedforward: Feedforward,
    #[serde(default)]
    period: f64,
}

/// What a state-space law can measure (the signals a control law sees).
const MEASURABLE: &str = "slider:I, slider_velocity:I, slider_error:I, slider_error_rate:I";

/// The built-in `statespace` ([`StateSpaceLaw`]).
pub(crate) struct StateSpaceFactory;

impl ControllerFactory for StateSpaceFactory {
    fn build(&self, params: &TableParams<'_>) -> Result<Arc<dyn Controller>, ScenarioError> {
        let keys: Keys = params.parse()?;
        let (measurements, commands) = channels(params, &keys.measurements, &keys.commands)?;
        if !(keys.period.is_finite() && keys.period >= 0.0) {
            return Err(params.error(
                "period",
                format!(
                    "must be finite and >= 0 (0 for a continuous law), got {}",
                    crate::error::number(keys.period)
                ),
            ));
        }
        let path = Path::new(params.file())
            .parent()
            .unwrap_or(Path::new(""))
            .join(&keys.file);
        let bytes = std::fs::read(&path)
            .map_err(|e| params.error("file", format!("cannot read {}: {e}", path.display())))?;
        let arrays = crate::npz::read(&bytes)
            .map_err(|e| params.error("file", format!("{}: {e}", path.display())))?;
        let at_file = |message: String| params.error("file", format!("{}: {message}", keys.file));
        let (p, m) = (measurements.len(), commands.len());
        if !arrays.contains_key("D") {
            return Err(at_file(
                "no array D (the feedthrough, commands x measurements)".into(),
            ));
        }
        let n = arrays
            .get("A")
            .map_or(0, |a| a.shape.first().copied().unwrap_or(0));
        let mut matrices = StateSpaceMatrices {
            a: Vec::new(),
            b: Vec::new(),
            c: Vec::new(),
            d: Vec::new(),
            states: n,
        };
        for (name, rows, cols, what) in [
            ("A", n, n, "states x states"),
            ("B", n, p, "states x measurements"),
            ("C", m, n, "commands x states"),
            ("D", m, p, "commands x measurements"),
        ] {
            let array = match arrays.get(name) {
                Some(array) => array,
                None if n == 0 && name != "D" => continue,
                None => return Err(at_file(format!("no array {name} ({what})"))),
            };
            let empty = rows * cols == 0 && array.data.is_empty();
            if !empty && array.shape != [rows, cols] {
                return Err(at_file(format!(
                    "{name} is {}, expected {rows} x {cols} ({what}: {n} states, {p} measurements, {m} commands)",
                    shape_text(&array.shape)
                )));
            }
            if let Some(k) = array.data.iter().position(|x| !x.is_finite()) {
                return Err(at_file(format!(
                    "{name}[{}, {}] = {}: every entry must be finite",
                    k / cols.max(1),
                    k % cols.max(1),
                    crate::error::number(array.data[k])
                )));
            }
            let data = array.data.clone();
            match name {
                "A" => matrices.a = data,
                "B" => matrices.b = data,
                "C" => matrices.c = data,
                _ => matrices.d = data,
            }
        }
        let dt = match arrays.get("dt") {
            None => None,
            Some(a) if a.data.len() == 1 && a.shape.iter().all(|s| *s == 1) => Some(a.data[0]),
            Some(a) => {
                return Err(at_file(format!(
                    "dt is {}, expected a scalar (the law's sample period, s)",
                    shape_text(&a.shape)
                )));
            }
        };
        let mut warnings = Vec::new();
        match dt {
            Some(dt) if !(dt.is_finite() && dt > 0.0) => {
                return Err(at_file(format!(
                    "dt = {}: a discrete law's sample period must be finite and > 0",
                    crate::error::number(dt)
                )));
            }
            Some(dt) if keys.period <= 0.0 => {
                return Err(params.error(
                    "period",
                    format!(
                        "{} holds a discrete-time law (dt = {dt} s): set period = {dt} (a discrete law is sampled)",
                        keys.file
                    ),
                ));
            }
            Some(dt) if (dt - keys.period).abs() > 1e-9 * dt => {
                return Err(params.error(
                    "period",
                    format!(
                        "{} holds a discrete-time law with dt = {dt} s, but period = {} s: they must be equal",
                        keys.file, keys.period
                    ),
                ));
            }
            Some(_) => {
                if let Some(r) = spectral_radius(&matrices.a, n).filter(|r| *r > 1.0 + 1e-9) {
                    warnings.push(format!(
                        "control.file: the discrete law of {} is unstable on its own (largest |eigenvalue| of A {r:.6} > 1); the loop may still be stable",
                        keys.file
                    ));
                }
            }
            None => {
                if let Some(s) = largest_real(&matrices.a, n).filter(|s| *s > 1e-9) {
                    warnings.push(format!(
                        "control.file: the law of {} is unstable on its own (an eigenvalue of A has real part {s:.6e} 1/s > 0); the loop may still be stable",
                        keys.file
                    ));
                }
                if keys.period > 0.0 && n > 0 {
                    // A continuous law sampled: its zero-order-hold discretisation.
                    let (ad, bd) = zero_order_hold(&matrices.a, &matrices.b, n, p, keys.period)
                        .ok_or_else(|| {
                            at_file(
                                "the zero-order hold of A, B at the period is not finite".into(),
                            )
                        })?;
                    matrices.a = ad;
                    matrices.b = bd;
                }
            }
        }
        let law = StateSpaceLaw::new(
            matrices,
            measurements,
            commands,
            keys.feedforward.on(),
            keys.period,
        )
        .map_err(|e| params.control_error(e))?
        .with_friction_feedforward(keys.feedforward.friction())
        .with_warnings(warnings);
        Ok(Arc::new(law))
    }
}

fn shape_text(shape: &[usize]) -> String {
    if shape.is_empty() {
        "a scalar".into()
    } else {
        shape
            .iter()
            .map(ToString::to_string)
            .collect::<Vec<_>>()
            .join(" x ")
    }
}

/// The `measurements` and `commands` of a slider law as slider signals and commanded
/// sliders (0-based), each name checked at its key; at least one command.
///
/// # Errors
/// An unknown channel name, one a law cannot measure or command, or no command.
pub(crate) fn channels(
    params: &TableParams<'_>,
    measurements: &[String],
    commands: &[String],
) -> Result<(Vec<SliderSignal>, Vec<usize>), ScenarioError> {
    let measurements = measurements
        .iter()
        .map(|name| measurement(name).map_err(|e| params.error("measurements", e)))
        .collect::<Result<Vec<_>, _>>()?;
    let commands = commands
        .iter()
        .map(|name| command(name).map_err(|e| params.error("commands", e)))
        .collect::<Result<Vec<_>, _>>()?;
    if commands.is_empty() {
        return Err(params.error("commands", "name at least one command (slider_force:I)"));
    }
    Ok((measurements, commands))
}

/// A measurement's channel name as a slider signal.
pub(crate) fn measurement(name: &str) -> Result<SliderSignal, String> {
    match name.parse::<Output>().map_err(|e| e.0)? {
        Output::SliderPosition(i) => Ok(SliderSignal::Position(i)),
        Output::SliderVelocity(i) => Ok(SliderSignal::Velocity(i)),
        Output::SliderError(i) => Ok(SliderSignal::Error(i)),
        Output::SliderErrorRate(i) => Ok(SliderSignal::ErrorRate(i)),
        _ => Err(format!(
            "{name:?} is a channel of the linear tools that a slider law cannot measure yet: a law measures {MEASURABLE}"
        )),
    }
}

/// A command's channel name as the commanded slider.
fn command(name: &str) -> Result<usize, String> {
    match name.parse::<Input>().map_err(|e| e.0)? {
        Input::SliderForce(i) => Ok(i),
        _ => Err(format!(
            "{name:?} cannot be a slider law's command: a law commands slider_force:I"
        )),
    }
}

fn matrix(a: &[f64], rows: usize, cols: usize) -> DMatrix<f64> {
    DMatrix::from_row_slice(rows, cols, a)
}

/// The largest real part of the eigenvalues of the `n x n` row-major `a` (None for none).
fn largest_real(a: &[f64], n: usize) -> Option<f64> {
    (n > 0).then(|| {
        matrix(a, n, n)
            .complex_eigenvalues()
            .iter()
            .map(|l| l.re)
            .fold(f64::NEG_INFINITY, f64::max)
    })
}

/// The largest modulus of the eigenvalues of `a`.
fn spectral_radius(a: &[f64], n: usize) -> Option<f64> {
    (n > 0).then(|| {
        matrix(a, n, n)
            .complex_eigenvalues()
            .iter()
            .map(|l| l.norm())
            .fold(0.0, f64::max)
    })
}

/// `Ad = e^(A T)`, `Bd = int_0^T e^(A s) ds B` from the exponential of `[[A B]; [0 0]] T`
/// (Van Loan 1978), row-major.
fn zero_order_hold(
    a: &[f64],
    b: &[f64],
    n: usize,
    p: usize,
    period: f64,
) -> Option<(Vec<f64>, Vec<f64>)> {
    let mut m = DMatrix::<f64>::zeros(n + p, n + p);
    for i in 0..n {
        for j in 0..n {
            m[(i, j)] = a[i * n + j] * period;
        }
        for j in 0..p {
            m[(i, n + j)] = b[i * p + j] * period;
        }
    }
    let e = m.exp();
    let ad: Vec<f64> = (0..n * n).map(|k| e[(k / n, k % n)]).collect();
    let bd: Vec<f64> = (0..n * p)
        .map(|k| e[(k / p.max(1), n + k % p.max(1))])
        .collect();
    (ad.iter().chain(&bd).all(|x| x.is_finite())).then_some((ad, bd))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_hold_of_a_first_order_lag_is_its_closed_form() {
        // z' = -a z + y: Ad = e^(-a T), Bd = (1 - e^(-a T)) / a.
        let (a, t) = (50.0, 2e-3);
        let (ad, bd) = zero_order_hold(&[-a], &[1.0], 1, 1, t).unwrap();
        assert!((ad[0] - (-a * t).exp()).abs() < 1e-14);
        assert!((bd[0] - (1.0 - (-a * t).exp()) / a).abs() < 1e-15);
    }

    #[test]
    fn channels_map_to_slider_signals_or_say_what_is_measurable() {
        assert_eq!(measurement("slider_error:2"), Ok(SliderSignal::Error(1)));
        assert_eq!(measurement("slider:3"), Ok(SliderSignal::Position(2)));
        let e = measurement("platform:x").unwrap_err();
        assert!(
            e.contains("cannot measure yet") && e.contains(MEASURABLE),
            "{e}"
        );
        assert!(
            measurement("slider_eror:1")
                .unwrap_err()
                .contains("unknown output")
        );
        assert_eq!(command("slider_force:1"), Ok(0));
        assert!(command("motor_torque:1").is_err());
    }
}
