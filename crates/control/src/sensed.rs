//! A control law behind its sensors (docs/control.md, "Delay and quantisation"): the
//! measured sliders quantised to an encoder's resolution and delayed by a transport delay
//! before the law sees them. Any law can be wrapped ([`SensedLaw`]); the scene keys
//! `control.delay`, `control.delay_order` and `control.quantisation` do it for every kind.
//!
//! **Quantisation** rounds each measured signal the law reads to the nearest multiple of its
//! step, `Q(x) = q round(x / q)` (an encoder with resolution `q`): the error it adds is at
//! most `q / 2`. It is not linear: the linear models use the law without it
//! ([`Controller::linear_law`]).
//!
//! **Delay.** The law sees the sliders' deviations from the commanded path `d` late:
//! `rho_seen(t) = rho_ref(t) + (Q(rho) - rho_ref)(t - d)`, the same for the velocities, so
//! the tracking errors and their rates reach the law `d` late; before the start the machine
//! is on its commanded path (the deviation is 0). About a pose at rest (the linear models) this
//! is the transport delay `e^(-s d)` of the measurements.
//!
//! * A sampled law (period `T`) with `d = N T` sees the sample taken `N` periods earlier: a
//!   shift register of `N` states per delayed signal, exact in runs and in the discrete
//!   linear models (`z^-N`). With `d = (N + f) T`, `0 < f < 1`, it sees the samples `N` and
//!   `N + 1` periods old interpolated linearly, `(1 - f) y_(k-N) + f y_(k-N-1)`, an
//!   approximation (stated in a warning).
//! * A continuous law sees the deviations through the `[n/n]` Pade approximation of
//!   `e^(-s d)` (`n` = `delay_order` states per delayed signal, in runs and in the linear
//!   models alike): `P(-s d) / P(s d)`, `P(x) = sum_k c_k x^k`,
//!   `c_k = (2n - k)! n! / ((2n)! k! (n - k)!)` (Baker & Graves-Morris, *Pade Approximants*,
//!   1996), all-pass, its phase `-2 atan`-like and within 1e-3 rad of `-w d` up to
//!   `w d = 2` for `n = 4`.
//!
//! Only the signals the law reads ([`Controller::reads`]) are delayed.

use std::sync::Arc;

use crate::{ControlError, ControlInput, Controller, SliderState};

/// The largest delay of a sampled law, in periods (each costs a state per delayed signal).
pub const MAX_DELAY_PERIODS: usize = 1000;

/// The largest order of a continuous law's Pade delay.
pub const MAX_PADE_ORDER: usize = 10;

/// The sensors of a [`SensedLaw`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sensors {
    /// Transport delay of the measurements (s), `>= 0`.
    pub delay: f64,
    /// Order of the Pade approximation of a continuous law's delay (1 to
    /// [`MAX_PADE_ORDER`]; unused for a sampled law).
    pub pade_order: usize,
    /// Quantisation step of each slider's measured `[position (m), velocity (m/s)]`, 0 for
    /// none.
    pub quantisation: [[f64; 2]; 3],
}

impl Default for Sensors {
    fn default() -> Self {
        Self {
            delay: 0.0,
            pade_order: 4,
            quantisation: [[0.0; 2]; 3],
        }
    }
}

/// How the deviations are delayed.
#[derive(Debug, Clone, PartialEq)]
enum DelayLine {
    None,
    /// A sampled law's shift register: `whole` periods, then the fraction `fraction` of one
    /// more by linear interpolation; `length` states per signal.
    Shift {
        whole: usize,
        fraction: f64,
        length: usize,
        period: f64,
    },
    /// A continuous law's Pade approximation, controllable canonical form scaled so that the
    /// first state is the delayed input at rest: `x' = (A x + B u) / d`, `y = C x + D u`.
    Pade {
        order: usize,
        a: Vec<f64>,
        b: f64,
        c: Vec<f64>,
        d: f64,
        delay: f64,
    },
}

impl DelayLine {
    fn states(&self) -> usize {
        match self {
            Self::None => 0,
            Self::Shift { length, .. } => *length,
            Self::Pade { order, .. } => *order,
        }
    }
}

/// A law behind delaying, quantising sensors: see the module documentation.
///
/// ```
/// use std::sync::Arc;
/// use flexprr_control::{Controller, Pid, SensedLaw, Sensors};
///
/// // A PD law sampled at 1 ms that sees the sliders 2 ms late, through 1 um encoders.
/// let pd = Pid::pd(2e5, 2e3, true, 1e-3).unwrap();
/// let sensors = Sensors { delay: 2e-3, quantisation: [[1e-6, 0.0]; 3], ..Sensors::default() };
/// let law = SensedLaw::new(Arc::new(pd), sensors).unwrap();
/// assert_eq!(law.states(), 2 * 6); // two samples of each slider's position and velocity
/// assert!(law.linear_law().is_some()); // the linear models leave the encoders out
/// ```
#[derive(Debug, Clone)]
pub struct SensedLaw {
    inner: Arc<dyn Controller>,
    sensors: Sensors,
    line: DelayLine,
    /// The delayed signals: `(slider, 0 position / 1 velocity)`.
    signals: Vec<(usize, usize)>,
    /// The quantisation this law (a [`Controller::linear_law`]) leaves out.
    left_out: bool,
}

impl SensedLaw {
    /// `inner` behind `sensors`.
    ///
    /// # Errors
    /// A negative or non-finite delay or step, a Pade order out of 1 to
    /// [`MAX_PADE_ORDER`], a sampled law's delay of more than [`MAX_DELAY_PERIODS`]
    /// periods.
    pub fn new(inner: Arc<dyn Controller>, sensors: Sensors) -> Result<Self, ControlError> {
        let delay = crate::error::check(
            "delay",
            sensors.delay,
            0.0,
            false,
            "a delay must be finite and >= 0 (s)",
        )?;
        for step in sensors.quantisation.iter().flatten() {
            crate::error::check(
                "quantisation",
                *step,
                0.0,
                false,
                "a quantisation step must be finite and >= 0 (0 for none)",
            )?;
        }
        let reads = inner.reads();
        let signals: Vec<(usize, usize)> = (0..3)
            .flat_map(|i| (0..2).map(move |k| (i, k)))
            .filter(|&(i, k)| reads[i][k])
            .collect();
        let period = inner.period();
        let line = if delay <= 0.0 {
            DelayLine::None
        } else if period > 0.0 {
            let periods = delay / period;
            if periods > MAX_DELAY_PERIODS as f64 {
                return Err(ControlError::InvalidParameter {
                    name: "delay",
                    value: delay,
                    rule: "a sampled law's delay must be at most 1000 periods",
                });
            }
            // Within 1e-9 of a whole number of periods is that number (a delay written as
            // 2e-3 with a period of 1e-3 / 3 is not quite 6 periods in binary).
            let nearest = periods.round();
            let (whole, fraction) = if (periods - nearest).abs() <= 1e-9 * periods.max(1.0) {
                (nearest as usize, 0.0)
            } else {
                (periods.floor() as usize, periods - periods.floor())
            };
            DelayLine::Shift {
                whole,
                fraction,
                length: whole + usize::from(fraction > 0.0),
                period,
            }
        } else {
            let order = sensors.pade_order;
            if !(1..=MAX_PADE_ORDER).contains(&order) {
                return Err(ControlError::InvalidParameter {
                    name: "delay_order",
                    value: order as f64,
                    rule: "the Pade order of a continuous law's delay must be 1 to 10",
                });
            }
            pade(order, delay)
        };
        Ok(Self {
            inner,
            sensors,
            line,
            signals,
            left_out: false,
        })
    }

    /// The sensors.
    pub fn sensors(&self) -> &Sensors {
        &self.sensors
    }

    /// How the delay is modelled, for notes: `none`, `a shift of N samples`, `... with
    /// linear interpolation`, `its Pade approximation of order n`.
    pub fn delay_model(&self) -> String {
        match &self.line {
            DelayLine::None => "none".into(),
            DelayLine::Shift {
                whole,
                fraction: 0.0,
                ..
            } => format!("a shift of {whole} samples (exact in the discrete model)"),
            DelayLine::Shift {
                whole, fraction, ..
            } => format!(
                "{whole} + {fraction:.6} samples, the samples on either side interpolated linearly (an approximation)"
            ),
            DelayLine::Pade { order, .. } => {
                format!("its Pade approximation of order {order}")
            }
        }
    }

    fn quantised(&self, measured: [SliderState; 3]) -> [SliderState; 3] {
        let q = &self.sensors.quantisation;
        let round = |x: f64, step: f64| {
            if step > 0.0 {
                step * (x / step).round()
            } else {
                x
            }
        };
        std::array::from_fn(|i| SliderState {
            position: round(measured[i].position, q[i][0]),
            velocity: round(measured[i].velocity, q[i][1]),
            acceleration: measured[i].acceleration,
        })
    }

    /// The input the inner law sees, the delay line's rates into `rates` (its states are
    /// `states`).
    fn seen<'a>(
        &self,
        input: &ControlInput<'a>,
        states: &[f64],
        rates: &mut [f64],
    ) -> ControlInput<'a> {
        let mut seen = *input;
        seen.measured = self.quantised(input.measured);
        let per = self.line.states();
        if per == 0 {
            return seen;
        }
        for (j, &(i, k)) in self.signals.iter().enumerate() {
            let (r, m) = (&input.reference[i], &mut seen.measured[i]);
            let (reference, value) = if k == 0 {
                (r.position, &mut m.position)
            } else {
                (r.velocity, &mut m.velocity)
            };
            let now = *value - reference;
            let z = &states[j * per..(j + 1) * per];
            let dz = &mut rates[j * per..(j + 1) * per];
            let delayed = match &self.line {
                DelayLine::None => now,
                DelayLine::Shift {
                    whole,
                    fraction,
                    period,
                    ..
                } => {
                    let past = |n: usize| if n == 0 { now } else { z[n - 1] };
                    let delayed = if *fraction > 0.0 {
                        (1.0 - fraction) * past(*whole) + fraction * past(whole + 1)
                    } else {
                        past(*whole)
                    };
                    for (n, rate) in dz.iter_mut().enumerate() {
                        let next = if n == 0 { now } else { z[n - 1] };
                        *rate = (next - z[n]) / period;
                    }
                    delayed
                }
                DelayLine::Pade {
                    order,
                    a,
                    b,
                    c,
                    d,
                    delay,
                } => {
                    for n in 0..order - 1 {
                        dz[n] = z[n + 1] / delay;
                    }
                    let last: f64 = a.iter().zip(z).map(|(a, z)| a * z).sum();
                    dz[order - 1] = (last + b * now) / delay;
                    c.iter().zip(z).map(|(c, z)| c * z).sum::<f64>() + d * now
                }
            };
            *value = reference + delayed;
        }
        seen
    }
}

/// The `[n/n]` Pade approximation of `e^(-s d)` as [`DelayLine::Pade`].
fn pade(n: usize, delay: f64) -> DelayLine {
    // c_0 = 1, c_(k+1) = c_k (n - k) / ((2n - k)(k + 1)).
    let mut c = vec![1.0; n + 1];
    for k in 0..n {
        c[k + 1] = c[k] * (n - k) as f64 / (((2 * n - k) * (k + 1)) as f64);
    }
    // In tau = t / d: the denominator P(x) / c_n is monic with a_k = c_k / c_n; the
    // numerator P(-x) / c_n = (-1)^n x^n + ..., so D = (-1)^n and the strictly proper rest
    // has r_k = (c_k / c_n) ((-1)^k - (-1)^n). States scaled by a_0 so that x_1 = u at rest.
    let sign = |k: usize| if k % 2 == 0 { 1.0 } else { -1.0 };
    let monic: Vec<f64> = c.iter().map(|ck| ck / c[n]).collect();
    let a0 = monic[0];
    DelayLine::Pade {
        order: n,
        a: monic[..n].iter().map(|ak| -ak).collect(),
        b: a0,
        c: (0..n)
            .map(|k| monic[k] * (sign(k) - sign(n)) / a0)
            .collect(),
        d: sign(n),
        delay,
    }
}

impl Controller for SensedLaw {
    fn command(
        &self,
        input: &ControlInput<'_>,
        states: &[f64],
        force: &mut [f64; 3],
        rates: &mut [f64],
    ) {
        let k = self.inner.states();
        let seen = self.seen(input, &states[k..], &mut rates[k..]);
        self.inner
            .command(&seen, &states[..k], force, &mut rates[..k]);
    }

    fn try_command(
        &self,
        input: &ControlInput<'_>,
        states: &[f64],
        force: &mut [f64; 3],
        rates: &mut [f64],
    ) -> Result<(), ControlError> {
        let k = self.inner.states();
        let seen = self.seen(input, &states[k..], &mut rates[k..]);
        self.inner
            .try_command(&seen, &states[..k], force, &mut rates[..k])
    }

    fn states(&self) -> usize {
        self.inner.states() + self.signals.len() * self.line.states()
    }

    fn friction_feedforward(&self) -> bool {
        self.inner.friction_feedforward()
    }

    fn initial_states(&self) -> Vec<f64> {
        let mut z = self.inner.initial_states();
        z.resize(self.states(), 0.0);
        z
    }

    fn period(&self) -> f64 {
        self.inner.period()
    }

    fn name(&self) -> String {
        self.inner.name()
    }

    fn warnings(&self) -> Vec<String> {
        let mut warnings = self.inner.warnings();
        match &self.line {
            DelayLine::Shift { fraction, .. } if *fraction > 0.0 => warnings.push(format!(
                "control.delay: {} s is not a whole number of the law's periods: the law sees {}",
                self.sensors.delay,
                self.delay_model()
            )),
            _ => {}
        }
        warnings
    }

    fn reads(&self) -> [[bool; 2]; 3] {
        self.inner.reads()
    }

    fn linear_law(&self) -> Option<Arc<dyn Controller>> {
        let inner_linear = self.inner.linear_law();
        let quantised = self.sensors.quantisation.iter().flatten().any(|q| *q > 0.0);
        if !quantised && inner_linear.is_none() {
            return None;
        }
        Some(Arc::new(Self {
            inner: inner_linear.unwrap_or_else(|| self.inner.clone()),
            sensors: Sensors {
                quantisation: [[0.0; 2]; 3],
                ..self.sensors
            },
            left_out: quantised || self.left_out,
            ..self.clone()
        }))
    }

    fn linear_notes(&self) -> Vec<String> {
        let mut notes = self.inner.linear_notes();
        if self.sensors.delay > 0.0 {
            notes.push(format!(
                "the measurements' delay of {} s is {}",
                self.sensors.delay,
                self.delay_model()
            ));
        }
        if self.left_out {
            notes.push(
                "quantisation left out: rounding to the encoders' steps is not linear, so the \
                 linear model has the law without it (a run keeps it)"
                    .to_string(),
            );
        }
        notes
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Pid;

    fn input(t: f64, measured: f64) -> ControlInput<'static> {
        let at = |position| SliderState {
            position,
            velocity: 0.0,
            acceleration: 0.0,
        };
        ControlInput {
            t,
            reference: [at(0.0); 3],
            measured: [at(measured); 3],
            feedforward: [0.0; 3],
            force_limit: [f64::INFINITY; 3],
            sensors: &[],
        }
    }

    /// Steps a sampled law through the measurements `ys` as the model would (states
    /// advanced by `rate * period`); the force on slider 1 at each sample.
    fn run(law: &SensedLaw, ys: &[f64]) -> Vec<f64> {
        let mut z = law.initial_states();
        let mut rates = vec![0.0; z.len()];
        let t = law.period();
        ys.iter()
            .enumerate()
            .map(|(k, &y)| {
                let mut f = [0.0; 3];
                law.command(&input(k as f64 * t, y), &z, &mut f, &mut rates);
                for (z, r) in z.iter_mut().zip(&rates) {
                    *z += t * r;
                }
                f[0]
            })
            .collect()
    }

    #[test]
    fn a_whole_period_delay_is_a_shift_and_a_fraction_interpolates() {
        let p = Pid::pd(1.0, 0.0, false, 1e-3).unwrap();
        let ys = [1.0, 2.0, 4.0, 8.0, 16.0];
        let delayed = |d| {
            let s = Sensors {
                delay: d,
                ..Sensors::default()
            };
            run(&SensedLaw::new(Arc::new(p), s).unwrap(), &ys)
        };
        // kp (0 - y): the negated measurement two samples late (0 before the start).
        let two = delayed(2e-3);
        for (k, f) in two.iter().enumerate() {
            let expected = if k >= 2 { -ys[k - 2] } else { 0.0 };
            assert!((f - expected).abs() <= 1e-12, "{two:?}");
        }
        let late = delayed(1.25e-3);
        for (k, f) in late.iter().enumerate() {
            let past = |n: usize| if k >= n { -ys[k - n] } else { 0.0 };
            let expected = 0.75 * past(1) + 0.25 * past(2);
            assert!((f - expected).abs() <= 1e-12, "{late:?}");
        }
    }

    #[test]
    fn quantisation_rounds_to_the_nearest_step() {
        let p = Pid::pd(1.0, 0.0, false, 0.0).unwrap();
        let s = Sensors {
            quantisation: [[0.5, 0.0]; 3],
            ..Sensors::default()
        };
        let law = SensedLaw::new(Arc::new(p), s).unwrap();
        let mut f = [0.0; 3];
        law.command(&input(0.0, 1.2), &[], &mut f, &mut []);
        assert!((f[0] + 1.0).abs() < 1e-15, "{f:?}");
        law.command(&input(0.0, 1.3), &[], &mut f, &mut []);
        assert!((f[0] + 1.5).abs() < 1e-15, "{f:?}");
        let linear = law.linear_law().unwrap();
        linear.command(&input(0.0, 1.3), &[], &mut f, &mut []);
        assert!((f[0] + 1.3).abs() < 1e-15, "{f:?}");
    }

    /// The Pade line's frequency response `C (jw I - A/d)^-1 B/d + D` against `e^(-jw d)`.
    #[test]
    fn the_pade_line_is_all_pass_with_the_delays_phase() {
        use std::f64::consts::PI;
        let d = 2e-3;
        let DelayLine::Pade {
            order,
            a,
            b,
            c,
            d: dd,
            ..
        } = pade(4, d)
        else {
            panic!("not a Pade line");
        };
        for w in [10.0, 100.0, 500.0, 1000.0] {
            // Solve (jw - A/d) x = B/d for the companion form by forward substitution on
            // x_(k+1) = jw d x_k (from x_k' = x_(k+1) / d).
            let s = (0.0, w * d); // s d as a complex number
            let mul = |p: (f64, f64), q: (f64, f64)| (p.0 * q.0 - p.1 * q.1, p.0 * q.1 + p.1 * q.0);
            // x_k = (s d)^(k-1) x_1; last row: s d x_n = sum a_k x_k + b u.
            let mut powers = vec![(1.0, 0.0)];
            for _ in 0..order {
                let last = *powers.last().unwrap();
                powers.push(mul(last, s));
            }
            let mut den = powers[order];
            for k in 0..order {
                den.0 -= a[k] * powers[k].0;
                den.1 -= a[k] * powers[k].1;
            }
            let norm = den.0 * den.0 + den.1 * den.1;
            let x1 = (b * den.0 / norm, -b * den.1 / norm);
            let mut h = (dd, 0.0);
            for k in 0..order {
                let xk = mul(powers[k], x1);
                h.0 += c[k] * xk.0;
                h.1 += c[k] * xk.1;
            }
            let gain = h.0.hypot(h.1);
            let phase = h.1.atan2(h.0);
            let exact = -w * d;
            let wrapped = (phase - exact + PI).rem_euclid(2.0 * PI) - PI;
            assert!((gain - 1.0).abs() < 1e-12, "w = {w}: |H| = {gain}");
            assert!(wrapped.abs() < 1e-3, "w = {w}: phase {phase} vs {exact}");
        }
    }

    #[test]
    fn bad_sensors_are_named() {
        let p = Arc::new(Pid::pd(1.0, 0.0, false, 1e-3).unwrap());
        let bad = |s: Sensors| SensedLaw::new(p.clone(), s).unwrap_err().to_string();
        assert!(
            bad(Sensors {
                delay: -1.0,
                ..Sensors::default()
            })
            .starts_with("delay = -1")
        );
        assert!(
            bad(Sensors {
                delay: 2.0,
                ..Sensors::default()
            })
            .contains("1000 periods")
        );
        let q = [[f64::NAN, 0.0]; 3];
        assert!(
            bad(Sensors {
                quantisation: q,
                ..Sensors::default()
            })
            .starts_with("quantisation")
        );
    }
}
