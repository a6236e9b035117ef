//! A linear state-space control law of the sliders (`kind = "statespace"`, docs/control.md):
//! a controller designed elsewhere (an LQR with an observer, a notch, an H-infinity design)
//! run in the machine's loop.
//!
//! With the measurements `y` (each one of the sliders' signals, [`SliderSignal`]) and the
//! law's states `z`:
//!
//! ```text
//! continuous (period 0):   z' = A z + B y,           u = C z + D y
//! sampled (period T > 0):  z_{k+1} = A z_k + B y_k,   u_k = C z_k + D y_k   (held over T)
//! ```
//!
//! and each commanded slider's force is `F_i = F_ff_i + u_k` (`F_ff` the rigid feedforward
//! when it is on). A sampled law is handed to the model as the rates
//! `((A - I) z + B y) / T`, which the model's sample step `z + T rate` (forward Euler, the
//! discretisation of the other laws' states) turns back into `A z + B y` exactly.

use crate::{ControlError, ControlInput, Controller};

/// The largest number of measurements of a state-space law: each of the four signals of the
/// three sliders once.
pub const MAX_MEASUREMENTS: usize = 12;

/// One measured signal of a slider (1-based in scenes, 0-based here).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SliderSignal {
    /// `slider:I`: `rho_i` (m).
    Position(usize),
    /// `slider_velocity:I`: `rho_i'` (m/s).
    Velocity(usize),
    /// `slider_error:I`: `rho_ref_i - rho_i` (m).
    Error(usize),
    /// `slider_error_rate:I`: `rho_ref_i' - rho_i'` (m/s).
    ErrorRate(usize),
}

impl SliderSignal {
    /// The slider (0-based).
    pub fn slider(self) -> usize {
        match self {
            Self::Position(i) | Self::Velocity(i) | Self::Error(i) | Self::ErrorRate(i) => i,
        }
    }

    /// Whether the signal is the slider's velocity (or its error's rate) rather than its
    /// position (or its error).
    pub fn is_rate(self) -> bool {
        matches!(self, Self::Velocity(_) | Self::ErrorRate(_))
    }

    /// Which measured signals of each slider `signals` read (see [`Controller::reads`]).
    pub fn reads(signals: &[Self]) -> [[bool; 2]; 3] {
        let mut reads = [[false; 2]; 3];
        for s in signals {
            if let Some(slider) = reads.get_mut(s.slider()) {
                slider[usize::from(s.is_rate())] = true;
            }
        }
        reads
    }

    /// The value of the signal in `input`.
    pub fn value(self, input: &ControlInput<'_>) -> f64 {
        let (r, m) = (&input.reference, &input.measured);
        match self {
            Self::Position(i) => m[i].position,
            Self::Velocity(i) => m[i].velocity,
            Self::Error(i) => r[i].position - m[i].position,
            Self::ErrorRate(i) => r[i].velocity - m[i].velocity,
        }
    }
}

/// The matrices of a law, row-major: `A` (`n x n`), `B` (`n x p`), `C` (`m x n`), `D`
/// (`m x p`) for `n` states, `p` measurements and `m` commands.
#[derive(Debug, Clone, PartialEq)]
pub struct StateSpaceMatrices {
    /// `A`, `n x n`.
    pub a: Vec<f64>,
    /// `B`, `n x p`.
    pub b: Vec<f64>,
    /// `C`, `m x n`.
    pub c: Vec<f64>,
    /// `D`, `m x p`.
    pub d: Vec<f64>,
    /// `n`.
    pub states: usize,
}

/// `kind = "statespace"`: see the module documentation.
#[derive(Debug, Clone, PartialEq)]
pub struct StateSpaceLaw {
    m: StateSpaceMatrices,
    measurements: Vec<SliderSignal>,
    /// The slider of each command (0-based).
    commands: Vec<usize>,
    feedforward: bool,
    friction_feedforward: bool,
    period: f64,
    warnings: Vec<String>,
}

impl StateSpaceLaw {
    /// The law with the actuators' steady friction in its feedforward (when `on`, and the
    /// feedforward is on; [`Controller::friction_feedforward`]).
    #[must_use]
    pub fn with_friction_feedforward(mut self, on: bool) -> Self {
        self.friction_feedforward = on;
        self
    }

    /// A law on `measurements` commanding the sliders `commands` (0-based, each at most
    /// once); continuous when `period` is 0 (then `A`, `B` are a continuous-time law's),
    /// sampled otherwise (then they are the discrete-time law's at that period).
    ///
    /// # Errors
    /// Shapes that do not match the counts (named `A`, `B`, `C`, `D`), a non-finite entry,
    /// more than [`MAX_MEASUREMENTS`] measurements or a repeated one, a slider commanded
    /// twice or out of range, a negative or non-finite period.
    pub fn new(
        matrices: StateSpaceMatrices,
        measurements: Vec<SliderSignal>,
        commands: Vec<usize>,
        feedforward: bool,
        period: f64,
    ) -> Result<Self, ControlError> {
        let period = crate::error::check(
            "period",
            period,
            0.0,
            false,
            "must be finite and >= 0 (0 for a continuous controller)",
        )?;
        let invalid = |name: &'static str, value: f64, rule: &'static str| {
            Err(ControlError::InvalidParameter { name, value, rule })
        };
        check_channels(&measurements, &commands)?;
        let (n, p, m) = (matrices.states, measurements.len(), commands.len());
        for (name, len, rows, cols) in [
            ("A", matrices.a.len(), n, n),
            ("B", matrices.b.len(), n, p),
            ("C", matrices.c.len(), m, n),
            ("D", matrices.d.len(), m, p),
        ] {
            if len != rows * cols {
                return invalid(name, len as f64, "the matrix's size must match the counts");
            }
        }
        for (name, v) in [
            ("A", &matrices.a),
            ("B", &matrices.b),
            ("C", &matrices.c),
            ("D", &matrices.d),
        ] {
            if let Some(x) = v.iter().find(|x| !x.is_finite()) {
                return invalid(name, *x, "every entry must be finite");
            }
        }
        Ok(Self {
            m: matrices,
            measurements,
            commands,
            feedforward,
            friction_feedforward: false,
            period,
            warnings: Vec::new(),
        })
    }

    /// The law with `warnings` about it (reported with a run's).
    #[must_use]
    pub fn with_warnings(mut self, warnings: Vec<String>) -> Self {
        self.warnings = warnings;
        self
    }

    /// The matrices.
    pub fn matrices(&self) -> &StateSpaceMatrices {
        &self.m
    }

    /// The measurements, in order.
    pub fn measurements(&self) -> &[SliderSignal] {
        &self.measurements
    }

    /// The commanded slider of each command (0-based).
    pub fn commands(&self) -> &[usize] {
        &self.commands
    }
}

impl Controller for StateSpaceLaw {
    fn friction_feedforward(&self) -> bool {
        self.feedforward && self.friction_feedforward
    }
    fn command(
        &self,
        input: &ControlInput<'_>,
        states: &[f64],
        force: &mut [f64; 3],
        rates: &mut [f64],
    ) {
        let (n, p) = (self.m.states, self.measurements.len());
        let mut y = [0.0; MAX_MEASUREMENTS];
        for (yk, s) in y.iter_mut().zip(&self.measurements) {
            *yk = s.value(input);
        }
        let y = &y[..p];
        for (i, f) in force.iter_mut().enumerate() {
            *f = if self.feedforward {
                input.feedforward[i]
            } else {
                0.0
            };
        }
        for (k, &slider) in self.commands.iter().enumerate() {
            let c = &self.m.c[k * n..(k + 1) * n];
            let d = &self.m.d[k * p..(k + 1) * p];
            force[slider] += dot(c, states) + dot(d, y);
        }
        for (r, rate) in rates.iter_mut().enumerate().take(n) {
            let next =
                dot(&self.m.a[r * n..(r + 1) * n], states) + dot(&self.m.b[r * p..(r + 1) * p], y);
            *rate = if self.period > 0.0 {
                (next - states[r]) / self.period
            } else {
                next
            };
        }
    }
    fn states(&self) -> usize {
        self.m.states
    }
    fn period(&self) -> f64 {
        self.period
    }
    fn name(&self) -> String {
        "statespace".to_string()
    }
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }
    fn reads(&self) -> [[bool; 2]; 3] {
        SliderSignal::reads(&self.measurements)
    }
}

/// The measurements and commanded sliders of a law on named channels: at most
/// [`MAX_MEASUREMENTS`] measurements, each once, and each slider commanded at most once,
/// sliders 1 to 3.
pub(crate) fn check_channels(
    measurements: &[SliderSignal],
    commands: &[usize],
) -> Result<(), ControlError> {
    let invalid = |name: &'static str, value: usize, rule: &'static str| {
        Err(ControlError::InvalidParameter {
            name,
            value: value as f64,
            rule,
        })
    };
    let p = measurements.len();
    if p > MAX_MEASUREMENTS {
        return invalid(
            "measurements",
            p,
            "at most 12 measurements (each slider's four signals once)",
        );
    }
    if measurements
        .iter()
        .enumerate()
        .any(|(k, s)| measurements[..k].contains(s) || s.slider() > 2)
    {
        return invalid("measurements", p, "each measurement once, sliders 1 to 3");
    }
    if commands
        .iter()
        .enumerate()
        .any(|(k, s)| commands[..k].contains(s) || *s > 2)
    {
        return invalid(
            "commands",
            commands.len(),
            "each slider once, sliders 1 to 3",
        );
    }
    Ok(())
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SliderState;

    fn input() -> ControlInput<'static> {
        let at = |position, velocity| SliderState {
            position,
            velocity,
            acceleration: 0.0,
        };
        ControlInput {
            t: 0.0,
            reference: [at(1.0, 2.0), at(3.0, 4.0), at(5.0, 6.0)],
            measured: [at(0.5, 1.0), at(2.0, 3.0), at(4.0, 5.0)],
            feedforward: [10.0, 20.0, 30.0],
            force_limit: [f64::INFINITY; 3],
            sensors: &[],
        }
    }

    #[test]
    fn a_d_only_law_is_the_pd_law() {
        use SliderSignal::{Error, ErrorRate};
        let (kp, kd) = (2.0e5, 400.0);
        let mut d = vec![0.0; 18];
        for i in 0..3 {
            d[i * 6 + i] = kp;
            d[i * 6 + 3 + i] = kd;
        }
        let m = StateSpaceMatrices {
            a: vec![],
            b: vec![],
            c: vec![],
            d,
            states: 0,
        };
        let signals = vec![
            Error(0),
            Error(1),
            Error(2),
            ErrorRate(0),
            ErrorRate(1),
            ErrorRate(2),
        ];
        let law = StateSpaceLaw::new(m, signals, vec![0, 1, 2], true, 0.0).unwrap();
        let pd = crate::Pid::pd(kp, kd, true, 0.0).unwrap();
        let (mut f, mut g) = ([0.0; 3], [0.0; 3]);
        law.command(&input(), &[], &mut f, &mut []);
        pd.command(&input(), &[], &mut g, &mut []);
        for i in 0..3 {
            assert!((f[i] - g[i]).abs() <= 1e-12 * g[i].abs(), "{f:?} {g:?}");
        }
    }

    #[test]
    fn a_sampled_law_hands_rates_that_one_euler_step_turns_into_its_update() {
        // One state z' = -2 z + y, u = 3 z + y, on slider 2's error (1.0).
        let m = StateSpaceMatrices {
            a: vec![0.5],
            b: vec![0.25],
            c: vec![3.0],
            d: vec![1.0],
            states: 1,
        };
        let law =
            StateSpaceLaw::new(m, vec![SliderSignal::Error(1)], vec![1], false, 1e-3).unwrap();
        let (mut f, mut rate) = ([0.0; 3], [0.0]);
        law.command(&input(), &[2.0], &mut f, &mut rate);
        assert!((f[1] - (3.0 * 2.0 + 1.0)).abs() <= 1e-12);
        assert!(f[0].abs() < f64::MIN_POSITIVE && f[2].abs() < f64::MIN_POSITIVE);
        let next = 2.0 + 1e-3 * rate[0];
        assert!((next - (0.5 * 2.0 + 0.25 * 1.0)).abs() <= 1e-12);
    }

    #[test]
    fn wrong_shapes_and_entries_are_named() {
        let m = |d: Vec<f64>| StateSpaceMatrices {
            a: vec![],
            b: vec![],
            c: vec![],
            d,
            states: 0,
        };
        let e = StateSpaceLaw::new(m(vec![1.0]), vec![], vec![0], true, 0.0).unwrap_err();
        assert!(e.to_string().starts_with("D = 1"), "{e}");
        let signals = vec![SliderSignal::Error(0)];
        let e = StateSpaceLaw::new(m(vec![f64::NAN]), signals, vec![0], true, 0.0).unwrap_err();
        assert!(e.to_string().contains("finite"), "{e}");
    }
}
