//! The controller trait: what an actuated model hands a control law at each evaluation, and
//! what it gets back.

use std::fmt;
use std::sync::Arc;

use crate::ControlError;

/// Position and velocity of one slider along its guide (m, m/s), and its acceleration where
/// it is known (the commanded motion's; 0 for a measured slider).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SliderState {
    /// `rho` (m).
    pub position: f64,
    /// `rho'` (m/s).
    pub velocity: f64,
    /// `rho''` (m/s^2).
    pub acceleration: f64,
}

/// What a control law sees at time `t`.
#[derive(Debug, Clone, Copy)]
pub struct ControlInput<'a> {
    /// Time (s).
    pub t: f64,
    /// The commanded sliders: the closed-form inverse kinematics of the scene's trajectory,
    /// `rho_ref`, `rho_ref'`, `rho_ref''`.
    pub reference: [SliderState; 3],
    /// The measured sliders `rho`, `rho'` (acceleration 0: not measured).
    pub measured: [SliderState; 3],
    /// The feedforward force of each slider (N): the rigid-body inverse-dynamics driving
    /// force of the commanded motion (with the actuators' reflected inertia), or 0 when the
    /// scene turns it off.
    pub feedforward: [f64; 3],
    /// The largest force each actuator can deliver (N; infinite for an ideal force), for
    /// anti-windup.
    pub force_limit: [f64; 3],
    /// Further sensor signals (none yet; strain sensors on the links come next).
    pub sensors: &'a [f64],
}

/// A control law for the three sliders, registered by name like the integrators
/// (`control.kind` in a scene).
///
/// Required: [`Controller::command`], the force command of each slider from the input and
/// the law's own states. Provided: no states, a continuous law (`period` 0), a name. A law
/// with states (an integral of the error) says how many in [`Controller::states`], starts
/// them at [`Controller::initial_states`] and writes their rates in `command`; a continuous
/// law's states are integrated with the machine's, a sampled law's are advanced by
/// `rate * period` at each sample (forward Euler, the usual discrete form of an integral).
///
/// ```
/// use flexprr_control::{ControlInput, Controller};
///
/// /// Bang-bang: the full force limit towards the commanded position (or 100 N).
/// #[derive(Debug)]
/// struct BangBang;
/// impl Controller for BangBang {
///     fn command(&self, input: &ControlInput<'_>, _states: &[f64], force: &mut [f64; 3], _rates: &mut [f64]) {
///         for i in 0..3 {
///             let error = input.reference[i].position - input.measured[i].position;
///             force[i] = input.force_limit[i].min(100.0) * error.signum();
///         }
///     }
/// }
/// let input = ControlInput {
///     t: 0.0,
///     reference: Default::default(),
///     measured: Default::default(),
///     feedforward: [0.0; 3],
///     force_limit: [f64::INFINITY; 3],
///     sensors: &[],
/// };
/// let mut force = [0.0; 3];
/// BangBang.command(&input, &[], &mut force, &mut []);
/// assert_eq!(BangBang.states(), 0);
/// ```
pub trait Controller: fmt::Debug + Send + Sync {
    /// The force command of each slider (N) at `input`, with the law's states `states`;
    /// writes the rates of those states into `rates` (same length). Must not allocate: it
    /// runs inside the right-hand side.
    fn command(
        &self,
        input: &ControlInput<'_>,
        states: &[f64],
        force: &mut [f64; 3],
        rates: &mut [f64],
    );
    /// Whether the law's feedforward includes the actuators' steady friction at the
    /// commanded slider velocity ([`crate::Actuator::friction_force`]): the actuated models
    /// then add it to [`ControlInput::feedforward`] (`feedforward = "rigid+friction"`).
    /// False by default.
    fn friction_feedforward(&self) -> bool {
        false
    }
    /// Number of states of the law (0 for PD).
    fn states(&self) -> usize {
        0
    }
    /// The states at the start.
    fn initial_states(&self) -> Vec<f64> {
        vec![0.0; self.states()]
    }
    /// Sample period (s): 0 for a continuous law; greater than 0 for a sampled law whose
    /// command is held (zero-order hold) between samples at `t0 + k period`.
    fn period(&self) -> f64 {
        0.0
    }
    /// The law's name, for summaries.
    fn name(&self) -> String {
        "custom".to_string()
    }
    /// Warnings about the law on its own (a state-space law unstable without the machine),
    /// reported with a run's.
    fn warnings(&self) -> Vec<String> {
        Vec::new()
    }
    /// [`Controller::command`] for a law whose computation can fail (one that calls out to
    /// another language): the actuated models take a sampled law's samples through it and
    /// stop the run with its error. By default `command`, which cannot fail.
    ///
    /// # Errors
    /// The law's own failure at `input.t`.
    fn try_command(
        &self,
        input: &ControlInput<'_>,
        states: &[f64],
        force: &mut [f64; 3],
        rates: &mut [f64],
    ) -> Result<(), ControlError> {
        self.command(input, states, force, rates);
        Ok(())
    }
    /// Which measured signals of each slider the law reads: `[position, velocity]` per
    /// slider (a delay line keeps only those). All of them by default.
    fn reads(&self) -> [[bool; 2]; 3] {
        [[true; 2]; 3]
    }
    /// The law the linear models use in place of this one, when they differ: a law behind
    /// quantising sensors ([`crate::SensedLaw`]) without its quantisation, which is not
    /// linear. `None` (the default): this law.
    fn linear_law(&self) -> Option<Arc<dyn Controller>> {
        None
    }
    /// What a linear model of the loop should say about the law (how a delay is modelled,
    /// what was left out), one line each. None by default.
    fn linear_notes(&self) -> Vec<String> {
        Vec::new()
    }
}
