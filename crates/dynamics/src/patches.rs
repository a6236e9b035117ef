//! Piezoelectric patches on the links, as actuators and sensors, under a vibration control
//! law (docs/piezo.md).
//!
//! A patch on link `i` from `x1 = xi_start l` to `x2 = xi_end l` is a collocated pair:
//!
//! * the **actuator** at voltage `V` puts equal and opposite bending moments `M = k_a V` at
//!   its ends (`+M` at `x2`, `-M` at `x1`, counter-clockwise, the sense that bends the link
//!   towards positive `w`); their virtual work `M (dw'(x2) - dw'(x1))` gives the modal force
//!   `Q_j = k_a V (psi_j'(x2) - psi_j'(x1))` with `psi' = d psi / dx` (eq. P1 of
//!   docs/piezo.md), for any basis;
//! * the **sensor** reads the slope difference over the patch,
//!   `V_s = k_s (w'(x2) - w'(x1)) = k_s sum_j (psi_j'(x2) - psi_j'(x1)) eta_j` (eq. P2), and
//!   its rate `V_s' = k_s sum_j (psi_j'(x2) - psi_j'(x1)) eta_j'`, both exact functions of the
//!   state (no differentiation of a signal).
//!
//! The law's voltages are clipped at each patch's limit (and the clipping reported). Under
//! strain-rate feedback `V = -G V_s'` a patch adds the modal damping matrix
//! `G k_a k_s d d^T`, `d_j = psi_j'(x2) - psi_j'(x1)`: to first order the damping ratio of mode
//! `j` grows by `G k_a k_s d_j^2 / (2 m_j omega_j)` (eq. P3).

use std::sync::Arc;

use faer::linalg::solvers::Solve;
use flexprr_control::{VibrationController, VibrationInput};

use crate::hold::Hold;
use crate::{DynamicsError, Machine};

/// A piezoelectric patch: a collocated actuator and sensor pair on a link.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Patch {
    /// The link (0-based).
    pub link: usize,
    /// Where it starts along the link (0..1).
    pub xi_start: f64,
    /// Where it ends (greater than the start, up to 1).
    pub xi_end: f64,
    /// Actuator constant `k_a`: bending moment per volt (N m/V).
    pub actuator_constant: f64,
    /// Sensor constant `k_s`: volts per radian of slope difference over the patch (V/rad).
    pub sensor_constant: f64,
    /// The largest voltage magnitude the amplifier gives (V).
    pub voltage_limit: f64,
}

impl Patch {
    /// Checks the patch.
    ///
    /// # Errors
    /// A link other than 0, 1, 2, an empty or reversed span outside `[0, 1]`, a non-positive
    /// constant or limit.
    pub fn validated(self) -> Result<Self, DynamicsError> {
        let invalid =
            |quantity: &str, value: f64, reason: &'static str| DynamicsError::InvalidParameter {
                quantity: format!("patch on link {}: {quantity}", self.link + 1),
                value,
                reason,
            };
        if self.link > 2 {
            return Err(invalid("link", self.link as f64 + 1.0, "must be 1, 2 or 3"));
        }
        // Each end at its own key: a start outside [0, 1), an end outside (0, 1], an end
        // at or before the start (the end is the one named then).
        if !(self.xi_start >= 0.0 && self.xi_start < 1.0) {
            return Err(invalid(
                "xi_start",
                self.xi_start,
                "the patch must start within the link: 0 <= xi_start < 1",
            ));
        }
        if !(self.xi_end > 0.0 && self.xi_end <= 1.0) {
            return Err(invalid(
                "xi_end",
                self.xi_end,
                "the patch must end within the link: 0 < xi_end <= 1",
            ));
        }
        if self.xi_end <= self.xi_start {
            return Err(invalid(
                "xi_end",
                self.xi_end,
                "the patch must end after it starts: xi_start < xi_end",
            ));
        }
        for (name, v) in [
            ("actuator_constant", self.actuator_constant),
            ("sensor_constant", self.sensor_constant),
            ("voltage_limit", self.voltage_limit),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(invalid(name, v, "must be finite and positive"));
            }
        }
        Ok(self)
    }
}

/// The patches of a machine and their vibration control law.
#[derive(Debug, Clone)]
pub struct PatchControl {
    /// The patches, in the order of the law's sensors and voltages.
    pub patches: Vec<Patch>,
    /// The law.
    pub controller: Arc<dyn VibrationController>,
}

/// A patch at one instant.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PatchState {
    /// Sensor voltage `V_s` (V).
    pub sensor: f64,
    /// Its rate `V_s'` (V/s).
    pub sensor_rate: f64,
    /// The law's voltage command (V).
    pub command: f64,
    /// The voltage applied (V): the command clipped at the limit.
    pub voltage: f64,
    /// Whether the command was clipped.
    pub saturated: bool,
    /// Mechanical power the actuator delivers to the link, `M (dw'(x2) - dw'(x1))' =
    /// (k_a / k_s) V V_s'` (W); negative when it removes energy.
    pub power: f64,
}

/// A vibration control law with its running state: the patches' sensors (filled by the
/// model), the law's commands, and the samples of a sampled law.
#[derive(Debug, Clone)]
pub(crate) struct PatchLaw {
    spec: PatchControl,
    pub(crate) sensors: Vec<f64>,
    pub(crate) rates: Vec<f64>,
    commands: Vec<f64>,
    hold: Hold<Vec<f64>>,
    /// Voltages added to the patches' (a linear model's inputs; empty in a run).
    extra: Vec<f64>,
    /// Voltage commands that replace the law's (its loop opened by a linear analysis).
    open: Option<Vec<f64>>,
}

impl PatchLaw {
    /// The law of `spec` (patches checked), started at `start`.
    ///
    /// # Errors
    /// A bad patch.
    pub(crate) fn new(spec: PatchControl, start: f64) -> Result<Self, DynamicsError> {
        for patch in &spec.patches {
            patch.validated()?;
        }
        let count = spec.patches.len();
        let hold = Hold::new(start, spec.controller.period());
        Ok(Self {
            spec,
            sensors: vec![0.0; count],
            rates: vec![0.0; count],
            commands: vec![0.0; count],
            hold,
            extra: Vec::new(),
            open: None,
        })
    }

    /// Takes the patch inputs and the opened loop of `loads`.
    pub(crate) fn set_overrides(&mut self, loads: &crate::ExternalLoads) {
        self.extra.clone_from(&loads.patch_voltage);
        self.open.clone_from(&loads.patch_command);
    }

    /// The law's sample period (s; 0 for a continuous law).
    pub(crate) fn period(&self) -> f64 {
        self.hold.period()
    }

    /// The law's voltage commands from the current sensors, as at a sample.
    pub(crate) fn law_voltages(&self, t: f64) -> Vec<f64> {
        let input = VibrationInput {
            t,
            sensors: &self.sensors,
            sensor_rates: &self.rates,
        };
        let mut commands = vec![0.0; self.sensors.len()];
        self.spec.controller.voltages(&input, &mut commands);
        commands
    }

    /// The patches.
    pub(crate) fn patches(&self) -> &[Patch] {
        &self.spec.patches
    }

    /// The first sample time of a sampled law strictly after `t`.
    pub(crate) fn next_sample(&self, t: f64) -> Option<f64> {
        self.hold.next_sample(t)
    }

    /// The voltages at `t` from the current sensors (held for a sampled law), clipped at
    /// each patch's limit: patch `p`'s is `self.voltage(p)` afterwards.
    pub(crate) fn drive(&mut self, t: f64) {
        if self.hold.is_sampled() {
            match self.hold.held(t) {
                Some(held) => self.commands.copy_from_slice(held),
                None => self.commands.fill(0.0),
            }
            return;
        }
        let input = VibrationInput {
            t,
            sensors: &self.sensors,
            sensor_rates: &self.rates,
        };
        self.spec.controller.voltages(&input, &mut self.commands);
    }

    /// Patch `p`'s voltage after [`PatchLaw::drive`]: the command clipped at its limit.
    pub(crate) fn voltage(&self, p: usize) -> f64 {
        self.applied(p).clamp(
            -self.spec.patches[p].voltage_limit,
            self.spec.patches[p].voltage_limit,
        )
    }

    /// Patch `p`'s voltage before its limit: the law's command (or the one that replaces
    /// it) plus an input voltage.
    fn applied(&self, p: usize) -> f64 {
        let command = self
            .open
            .as_ref()
            .and_then(|o| o.get(p).copied())
            .unwrap_or(self.commands[p]);
        match self.extra.get(p) {
            Some(extra) => command + extra,
            None => command,
        }
    }

    /// A sample of a sampled law at `t` from the current sensors, when `t` is one of its
    /// sample times (a segment starts there).
    pub(crate) fn sample(&mut self, t: f64) {
        if !self.hold.is_sample_time(t) {
            return;
        }
        let input = VibrationInput {
            t,
            sensors: &self.sensors,
            sensor_rates: &self.rates,
        };
        let mut commands = vec![0.0; self.sensors.len()];
        self.spec.controller.voltages(&input, &mut commands);
        self.hold.rewind(t);
        self.hold.push(t, commands);
    }

    /// Every patch's state after [`PatchLaw::drive`].
    pub(crate) fn states(&self) -> Vec<PatchState> {
        self.spec
            .patches
            .iter()
            .enumerate()
            .map(|(p, patch)| {
                let command = self.commands[p];
                let voltage = self.voltage(p);
                PatchState {
                    sensor: self.sensors[p],
                    sensor_rate: self.rates[p],
                    command,
                    voltage,
                    saturated: self.applied(p).abs() > patch.voltage_limit,
                    power: patch.actuator_constant / patch.sensor_constant
                        * voltage
                        * self.rates[p],
                }
            })
            .collect()
    }
}

/// The patches of a modal model: for each patch, its link's first modal coordinate, the
/// slope differences `d_j` of the link's shape functions, and `k_a M^-1 d` (the
/// accelerations per volt).
#[derive(Debug, Clone)]
pub(crate) struct PatchLoop {
    law: PatchLaw,
    /// Per patch: the first coordinate of its link in the modal coordinates.
    offsets: Vec<usize>,
    /// Per patch: `d_j` (1/m), one per mode of its link.
    slopes: Vec<Vec<f64>>,
    /// Per patch: `k_a M^-1 d` (accelerations per volt).
    forcing: Vec<Vec<f64>>,
}

impl PatchLoop {
    /// The loop of `spec` on `machine`, whose link `i`'s modal coordinates start at
    /// `offsets[i]`, started at `start` (the first sample of a sampled law).
    ///
    /// # Errors
    /// A bad patch, or a link whose modal mass matrix is not positive definite.
    pub(crate) fn new(
        machine: &Machine,
        offsets: [usize; 3],
        spec: PatchControl,
        start: f64,
    ) -> Result<Self, DynamicsError> {
        let law = PatchLaw::new(spec, start)?;
        let mut slopes = Vec::with_capacity(law.patches().len());
        let mut forcing = Vec::with_capacity(law.patches().len());
        for patch in law.patches() {
            let link = &machine.links[patch.link];
            let l = link.length();
            let d: Vec<f64> = (0..link.modes())
                .map(|j| {
                    (link.basis.eval(j, patch.xi_end)[1] - link.basis.eval(j, patch.xi_start)[1])
                        / l
                })
                .collect();
            let rhs = faer::Mat::from_fn(d.len(), 1, |j, _| patch.actuator_constant * d[j]);
            let inverse = link
                .integrals
                .mass
                .llt(faer::Side::Lower)
                .map_err(|_| DynamicsError::ModalMass {
                    link: patch.link + 1,
                })?
                .solve(&rhs);
            forcing.push((0..d.len()).map(|j| inverse[(j, 0)]).collect());
            slopes.push(d);
        }
        Ok(Self {
            offsets: law.patches().iter().map(|p| offsets[p.link]).collect(),
            law,
            slopes,
            forcing,
        })
    }

    /// The first sample time of a sampled law strictly after `t`.
    pub(crate) fn next_sample(&self, t: f64) -> Option<f64> {
        self.law.next_sample(t)
    }

    /// The sensors and their rates from the modal coordinates `eta` and rates `eta_dot`.
    fn sense(&mut self, eta: &[f64], eta_dot: &[f64]) {
        for p in 0..self.slopes.len() {
            let k_s = self.law.patches()[p].sensor_constant;
            let (off, d) = (self.offsets[p], &self.slopes[p]);
            let (mut s, mut r) = (0.0, 0.0);
            for (j, dj) in d.iter().enumerate() {
                s += dj * eta[off + j];
                r += dj * eta_dot[off + j];
            }
            self.law.sensors[p] = k_s * s;
            self.law.rates[p] = k_s * r;
        }
    }

    /// Adds the patches' accelerations at `(t, eta, eta_dot)` to the modal accelerations
    /// `acceleration`. Allocates nothing.
    pub(crate) fn accelerate(
        &mut self,
        t: f64,
        eta: &[f64],
        eta_dot: &[f64],
        acceleration: &mut [f64],
    ) {
        self.sense(eta, eta_dot);
        self.law.drive(t);
        for (p, forcing) in self.forcing.iter().enumerate() {
            let (voltage, off) = (self.law.voltage(p), self.offsets[p]);
            for (j, f) in forcing.iter().enumerate() {
                acceleration[off + j] += voltage * f;
            }
        }
    }

    /// The law.
    pub(crate) fn law(&self) -> &PatchLaw {
        &self.law
    }

    /// The law (with its overrides).
    pub(crate) fn law_mut(&mut self) -> &mut PatchLaw {
        &mut self.law
    }

    /// The law's voltage commands at `(t, eta, eta_dot)` as at a sample.
    pub(crate) fn law_voltages(&mut self, t: f64, eta: &[f64], eta_dot: &[f64]) -> Vec<f64> {
        self.sense(eta, eta_dot);
        self.law.law_voltages(t)
    }

    /// A sample of a sampled law when `t` is one of its sample times.
    pub(crate) fn sample(&mut self, t: f64, eta: &[f64], eta_dot: &[f64]) {
        self.sense(eta, eta_dot);
        self.law.sample(t);
    }

    /// Every patch's state at `(t, eta, eta_dot)`.
    pub(crate) fn states(&mut self, t: f64, eta: &[f64], eta_dot: &[f64]) -> Vec<PatchState> {
        self.sense(eta, eta_dot);
        self.law.drive(t);
        self.law.states()
    }
}

/// Why a modal velocity law does not fit the scene's patches and links, or a model gives no
/// patch states (docs/piezo.md): each message says what to change. Modes and links are
/// 1-based in the fields, as in the messages.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PatchError {
    /// The targeted modes and the damping ratios do not pair up (or there are none).
    #[error(
        "modal velocity control needs one damping ratio per targeted mode: {modes} modes, \
         {ratios} ratios"
    )]
    Ratios {
        /// Targeted modes.
        modes: usize,
        /// Damping ratios.
        ratios: usize,
    },
    /// A targeted mode the link does not have.
    #[error("modal velocity control targets mode {mode} of link {link}, which has {modes} modes")]
    NoSuchMode {
        /// The mode.
        mode: usize,
        /// The link.
        link: usize,
        /// The link's modes.
        modes: usize,
    },
    /// More targeted modes than patches on a link.
    #[error(
        "modal velocity control targets {} modes ({}) on link {link}, which has {patches} \
         patch{} ({spans}): a link's patches sense at most as many modes as there are \
         patches; add patches on link {link} or target fewer modes",
        .modes.len(),
        list(.modes),
        if *.patches == 1 { "" } else { "es" }
    )]
    TooFewPatches {
        /// The targeted modes.
        modes: Vec<usize>,
        /// The link.
        link: usize,
        /// Its patches.
        patches: usize,
        /// Their spans, `[xi_start, xi_end], ...`.
        spans: String,
    },
    /// A targeted mode none of the link's patches bends.
    #[error(
        "modal velocity control targets mode {mode} of link {link}, which its patches \
         ({spans}) cannot see: the mode's slope is the same at both ends of each patch, so it \
         bends none of them (a patch placed symmetrically about a node of the mode's \
         curvature); move a patch or leave mode {mode} out"
    )]
    UnseenMode {
        /// The mode.
        mode: usize,
        /// The link.
        link: usize,
        /// The link's patches' spans.
        spans: String,
    },
    /// The modal filter of the law cannot be built.
    #[error(
        "modal velocity control of modes {} on the patches of links {}: {source}",
        list(.modes),
        list(.links)
    )]
    Filter {
        /// The targeted modes.
        modes: Vec<usize>,
        /// The links with patches.
        links: Vec<usize>,
        /// Why.
        source: flexprr_control::ControlError,
    },
    /// A model that reports no state for the scene's patches.
    #[error("the {model} model reports no state for the scene's {patches} patches")]
    NoPatchStates {
        /// The model's kind.
        model: String,
        /// The scene's patches.
        patches: usize,
    },
}

impl From<PatchError> for DynamicsError {
    fn from(e: PatchError) -> Self {
        DynamicsError::Patch(Box::new(e))
    }
}

/// `1, 2, 3`.
fn list(values: &[usize]) -> String {
    values
        .iter()
        .map(usize::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The modal velocity law (`kind = "modal_velocity"`) for `patches` on `machine`: each
/// link carrying patches has its modes `modes` (0-based) targeted, each given the damping
/// ratio `damping_ratios[k]` of `modes[k]` through the modal gain `g = 2 zeta m_j omega_j`
/// (`m_j`, `omega_j` of the link's unloaded mode `j`), so the law's modal forces
/// `f_j = -g_j eta_j'` damp the targeted modes at those ratios in the unloaded link at rest.
/// The sensing matrix is `k_s d_p,j` and the forcing matrix `k_a d_p,j`, zero across links.
///
/// # Errors
/// A bad patch, a mode the links do not have, mismatched lists, or targets the patches
/// cannot tell apart (fewer patches than targeted modes on a link).
pub fn modal_velocity_law(
    machine: &Machine,
    patches: &[Patch],
    modes: &[usize],
    damping_ratios: &[f64],
    period: f64,
) -> Result<flexprr_control::ModalVelocity, DynamicsError> {
    if modes.len() != damping_ratios.len() || modes.is_empty() {
        return Err(PatchError::Ratios {
            modes: modes.len(),
            ratios: damping_ratios.len(),
        }
        .into());
    }
    for patch in patches {
        patch.validated()?;
    }
    let mut links: Vec<usize> = patches.iter().map(|p| p.link).collect();
    links.sort_unstable();
    links.dedup();
    let mut targets = Vec::new();
    let mut gains = Vec::new();
    for &link in &links {
        let model = &machine.links[link];
        for (&j, &zeta) in modes.iter().zip(damping_ratios) {
            if j >= model.modes() {
                return Err(PatchError::NoSuchMode {
                    mode: j + 1,
                    link: link + 1,
                    modes: model.modes(),
                }
                .into());
            }
            let (m, k) = (
                model.integrals.mass[(j, j)],
                model.integrals.stiffness[(j, j)],
            );
            targets.push((link, j));
            gains.push(2.0 * zeta * m * (k / m).sqrt());
        }
    }
    let slope = |p: &Patch, j: usize| {
        let model = &machine.links[p.link];
        (model.basis.eval(j, p.xi_end)[1] - model.basis.eval(j, p.xi_start)[1]) / model.length()
    };
    let sensing: Vec<Vec<f64>> = patches
        .iter()
        .map(|p| {
            targets
                .iter()
                .map(|&(link, j)| {
                    if link == p.link {
                        p.sensor_constant * slope(p, j)
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect();
    // Name what is wrong before the modal filter would only find it singular: each link's
    // patches sense (and force) a mode through its slope difference over the patch, so a
    // link needs at least as many patches as targeted modes, and each targeted mode must
    // change its slope over one of them.
    for &link in &links {
        let on_link: Vec<&Patch> = patches.iter().filter(|p| p.link == link).collect();
        let spans = on_link
            .iter()
            .map(|p| format!("[{}, {}]", p.xi_start, p.xi_end))
            .collect::<Vec<_>>()
            .join(", ");
        if modes.len() > on_link.len() {
            return Err(PatchError::TooFewPatches {
                modes: modes.iter().map(|j| j + 1).collect(),
                link: link + 1,
                patches: on_link.len(),
                spans,
            }
            .into());
        }
        for &j in modes {
            let seen = on_link
                .iter()
                .map(|p| slope(p, j).abs() * machine.links[link].length())
                .fold(0.0_f64, f64::max);
            if seen <= 1e-9 {
                return Err(PatchError::UnseenMode {
                    mode: j + 1,
                    link: link + 1,
                    spans,
                }
                .into());
            }
        }
    }
    let forcing: Vec<Vec<f64>> = targets
        .iter()
        .map(|&(link, j)| {
            patches
                .iter()
                .map(|p| {
                    if link == p.link {
                        p.actuator_constant * slope(p, j)
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect();
    flexprr_control::ModalVelocity::new(&sensing, &forcing, &gains, period).map_err(|source| {
        PatchError::Filter {
            modes: modes.iter().map(|j| j + 1).collect(),
            links: links.iter().map(|l| l + 1).collect(),
            source,
        }
        .into()
    })
}
