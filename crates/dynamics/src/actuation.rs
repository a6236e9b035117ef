//! The sliders as degrees of freedom, driven by their actuators under a controller
//! (docs/control.md): the control input of one evaluation, the actuator forces, and the
//! zero-order hold of a sampled controller.

use std::sync::Arc;

use flexprr_control::{ActuatorOutput, ControlInput, Controller, SliderState};
use flexprr_kinematics::{LegKinematics, MachineState};

use crate::hold::Hold;
use crate::{DynamicsError, Machine, inverse_dynamics};

pub use flexprr_control::Actuator;

/// The controller and the three actuators of an actuated model.
#[derive(Debug, Clone)]
pub struct Actuation {
    /// The control law (continuous or sampled).
    pub controller: Arc<dyn Controller>,
    /// The actuator of each slider.
    pub actuators: [Arc<dyn Actuator>; 3],
}

/// The sampled laws of a model with the slider law `actuated` (if any) and a vibration law
/// of period `patch_period` (0 for none or a continuous one), at `t`.
pub(crate) fn sampled_laws(
    actuated: Option<&Actuated>,
    patch_period: f64,
    t: f64,
) -> crate::SampledLaws {
    let slider_period = actuated.map_or(0.0, Actuated::period);
    crate::SampledLaws {
        slider_period,
        patch_period,
        slider_states: match actuated {
            Some(a) if slider_period > 0.0 => a.held_states(t),
            _ => Vec::new(),
        },
    }
}

/// The force commands of the three sliders and what their actuators did with them.
pub(crate) type Commands = ([f64; 3], [ActuatorOutput; 3]);

/// One sample of a sampled controller: the command held until the next.
#[derive(Debug, Clone)]
struct Sample {
    command: [f64; 3],
    /// The law's states at the sample (advanced by `rate * period` to the next one).
    states: Vec<f64>,
    rates: Vec<f64>,
    /// Why the law could not compute its command here (the run stops at this sample).
    failure: Option<flexprr_control::ControlError>,
}

/// The actuation of a model with its running state.
///
/// It owns the wiring the actuated models share: their state is
/// `y = (q, rho, q', rho', z, x_1, x_2, x_3)`, the sliders the last three of the model's
/// `coordinates` generalized coordinates, then the continuous law's states `z` and each
/// actuator's own states `x_i` ([`Actuator::states`]).
#[derive(Debug, Clone)]
pub(crate) struct Actuated {
    pub(crate) spec: Actuation,
    /// Slider mass plus the mass the actuator adds to it ([`Actuator::mass_on_slider`]),
    /// per slider (kg).
    pub(crate) slider_mass: [f64; 3],
    /// The model's generalized coordinates (the sliders the last three).
    coordinates: usize,
    /// Where each actuator's states start among the actuators' states, and their end.
    actuator_offsets: [usize; 4],
    /// The samples of a sampled law.
    hold: Hold<Sample>,
    /// Scratch for the law's state rates (continuous law: written into `dy`).
    rates: Vec<f64>,
    /// What a linear analysis changes in the loop (none in a run).
    overrides: LoopOverrides,
}

/// The changes a linear analysis makes to the slider loops ([`crate::ExternalLoads`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct LoopOverrides {
    /// Added to the commanded positions the law sees (m).
    reference: [f64; 3],
    /// Added to the commanded velocities the law sees (m/s).
    reference_rate: [f64; 3],
    /// Force commands that replace the law's (N).
    command: [Option<f64>; 3],
    /// Velocities at which the actuators' Coulomb friction is evaluated (m/s).
    friction_velocity: Option<[f64; 3]>,
}

/// The commanded sliders at `t` (the closed-form inverse kinematics of the trajectory) and
/// the feedforward: the rigid-body inverse-dynamics driving force of the commanded motion
/// plus the actuators' reflected inertia `m_r rho_ref''`, and when the law asks for it
/// ([`flexprr_control::Controller::friction_feedforward`]) the actuators' steady friction
/// at the commanded velocity ([`Actuator::friction_force`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Reference {
    pub(crate) sliders: [SliderState; 3],
    pub(crate) feedforward: [f64; 3],
}

impl Reference {
    /// The reference of the commanded state `rigid` at `t`.
    ///
    /// # Errors
    /// A singular rigid inverse dynamics (a type-II pose of the commanded motion).
    pub(crate) fn of<L: AsRef<LegKinematics>>(
        machine: &Machine,
        actuated: &Actuated,
        rigid: &MachineState<L>,
        t: f64,
    ) -> Result<Self, DynamicsError> {
        let forces = inverse_dynamics(machine, rigid, None, t)?;
        let legs: [&LegKinematics; 3] = std::array::from_fn(|i| rigid.legs[i].as_ref());
        let sliders = std::array::from_fn(|i| SliderState {
            position: legs[i].rho,
            velocity: legs[i].rho_dot,
            acceleration: legs[i].rho_ddot,
        });
        let friction = actuated.spec.controller.friction_feedforward();
        let feedforward = std::array::from_fn(|i| {
            let actuator = &actuated.spec.actuators[i];
            let rigid = forces.driving_force[i] + actuator.reflected_mass() * legs[i].rho_ddot;
            if friction {
                rigid + actuator.friction_force(legs[i].rho_dot)
            } else {
                rigid
            }
        });
        Ok(Self {
            sliders,
            feedforward,
        })
    }
}

impl Actuated {
    /// The actuation of `machine`'s sliders, started at `start`, in a model of
    /// `coordinates` generalized coordinates (the sliders the last three).
    pub(crate) fn new(spec: Actuation, machine: &Machine, start: f64, coordinates: usize) -> Self {
        let slider_mass =
            std::array::from_fn(|i| machine.slider_mass[i] + spec.actuators[i].mass_on_slider());
        let rates = vec![0.0; spec.controller.states()];
        let spec_period = spec.controller.period();
        let mut actuator_offsets = [0; 4];
        for i in 0..3 {
            actuator_offsets[i + 1] = actuator_offsets[i] + spec.actuators[i].states();
        }
        Self {
            spec,
            slider_mass,
            coordinates,
            actuator_offsets,
            hold: Hold::new(start, spec_period),
            rates,
            overrides: LoopOverrides::default(),
        }
    }

    /// Takes the loop changes of `loads` (references, opened loops, friction held).
    pub(crate) fn set_overrides(&mut self, loads: &crate::ExternalLoads) {
        self.overrides = LoopOverrides {
            reference: loads.reference,
            reference_rate: loads.reference_rate,
            command: loads.slider_command,
            friction_velocity: loads.friction_velocity,
        };
    }

    /// The law's command and state rates as at a sample at `input` with the law's states
    /// `states` (a sampled law's discretisation: what it would hold from now).
    pub(crate) fn law_sample(
        &self,
        input: &ControlInput<'_>,
        states: &[f64],
    ) -> ([f64; 3], Vec<f64>) {
        let mut command = [0.0; 3];
        let mut rates = vec![0.0; states.len()];
        self.spec
            .controller
            .command(input, states, &mut command, &mut rates);
        (command, rates)
    }

    /// The states of a sampled law held at `t` (those of its last sample at or before `t`;
    /// the initial states before the first).
    pub(crate) fn held_states(&self, t: f64) -> Vec<f64> {
        self.hold.held(t).map_or_else(
            || self.spec.controller.initial_states(),
            |s| s.states.clone(),
        )
    }

    /// The failure of the sampled law's sample held at `t` (a law that could not compute
    /// its command there): the right-hand side stops the run with it.
    pub(crate) fn failure_at(&self, t: f64) -> Option<DynamicsError> {
        self.hold
            .held(t)
            .and_then(|s| s.failure.clone())
            .map(DynamicsError::Control)
    }

    /// Sample period (s), 0 for a continuous law.
    pub(crate) fn period(&self) -> f64 {
        self.spec.controller.period()
    }

    /// Number of the law's states carried in the ODE state (a continuous law's).
    pub(crate) fn law_states(&self) -> usize {
        if self.period() > 0.0 {
            0
        } else {
            self.spec.controller.states()
        }
    }

    /// Number of the actuators' own states carried in the ODE state.
    pub(crate) fn actuator_states(&self) -> usize {
        self.actuator_offsets[3]
    }

    /// Number of states carried in the ODE state after the mechanical ones: the
    /// continuous law's, then the actuators'.
    pub(crate) fn ode_states(&self) -> usize {
        self.law_states() + self.actuator_states()
    }

    /// The length of the model's state.
    pub(crate) fn dim(&self) -> usize {
        2 * self.coordinates + self.ode_states()
    }

    /// The measured sliders of the state `y`: the last three coordinates and their rates.
    pub(crate) fn measured(&self, y: &[f64]) -> [SliderState; 3] {
        let (n, first) = (self.coordinates, self.coordinates - 3);
        std::array::from_fn(|i| SliderState {
            position: y[first + i],
            velocity: y[n + first + i],
            acceleration: 0.0,
        })
    }

    /// Writes the start of a run on the commanded state `rigid` into the model's state `y`:
    /// the sliders at `rho_ref(t0)` with `rho_ref'(t0)`, the law's initial states, the
    /// actuators' ([`Actuator::initial_states`]). The rest of `y` is the model's.
    pub(crate) fn start<L: AsRef<LegKinematics>>(&self, rigid: &MachineState<L>, y: &mut [f64]) {
        let (n, first) = (self.coordinates, self.coordinates - 3);
        for (i, leg) in rigid.legs.iter().enumerate() {
            let leg = leg.as_ref();
            y[first + i] = leg.rho;
            y[n + first + i] = leg.rho_dot;
        }
        let (law, actuators) = y[2 * n..].split_at_mut(self.law_states());
        if !law.is_empty() {
            law.copy_from_slice(&self.spec.controller.initial_states());
        }
        for (i, leg) in rigid.legs.iter().enumerate() {
            let range = self.actuator_offsets[i]..self.actuator_offsets[i + 1];
            self.spec.actuators[i].initial_states(leg.as_ref().rho_dot, &mut actuators[range]);
        }
    }

    /// The first sample time of a sampled law strictly after `t`: the next breakpoint of
    /// the integration.
    pub(crate) fn next_sample(&self, t: f64) -> Option<f64> {
        self.hold.next_sample(t)
    }

    /// The control input at `t` for the measured sliders `measured`.
    pub(crate) fn input<'a>(
        &self,
        t: f64,
        reference: &Reference,
        measured: [SliderState; 3],
    ) -> ControlInput<'a> {
        let mut commanded = reference.sliders;
        for (i, slider) in commanded.iter_mut().enumerate() {
            slider.position += self.overrides.reference[i];
            slider.velocity += self.overrides.reference_rate[i];
        }
        ControlInput {
            t,
            reference: commanded,
            measured,
            feedforward: reference.feedforward,
            force_limit: std::array::from_fn(|i| self.spec.actuators[i].force_limit()),
            sensors: &[],
        }
    }

    /// The force command at `t`: the continuous law now (its state rates into `rates`), or
    /// the command a sampled law holds at `t`.
    pub(crate) fn command(
        &self,
        input: &ControlInput<'_>,
        states: &[f64],
        rates: &mut [f64],
    ) -> [f64; 3] {
        let mut force = [0.0; 3];
        if self.period() > 0.0 {
            if let Some(sample) = self.hold.held(input.t) {
                force = sample.command;
            }
            return force;
        }
        self.spec
            .controller
            .command(input, states, &mut force, rates);
        force
    }

    /// A sample at `t` when `t` is one of the law's sample times (a segment starts there):
    /// the law's command from the input, held until the next; its states advance by
    /// `rate * period` from the previous sample.
    pub(crate) fn sample(&mut self, input: &ControlInput<'_>) {
        let t = input.t;
        if !self.hold.is_sample_time(t) {
            return;
        }
        let period = self.hold.period();
        let states = match self.hold.rewind(t) {
            Some(previous) => previous
                .states
                .iter()
                .zip(&previous.rates)
                .map(|(x, rate)| x + rate * period)
                .collect(),
            None => self.spec.controller.initial_states(),
        };
        let mut rates = std::mem::take(&mut self.rates);
        rates.resize(states.len(), 0.0);
        let mut command = [0.0; 3];
        let failure = self
            .spec
            .controller
            .try_command(input, &states, &mut command, &mut rates)
            .err();
        if failure.is_some() {
            // The outputs at the failed sample show the command held until then.
            command = self.hold.held(t).map_or([0.0; 3], |s| s.command);
        }
        self.hold.push(
            t,
            Sample {
                command,
                states,
                rates: rates.clone(),
                failure,
            },
        );
        self.rates = rates;
    }

    /// The force commands and the actuators' outputs at `(t, y)` for the commanded state
    /// `rigid`: the sliders measured from `y`, the continuous law's and the actuators' states
    /// from its tail, their rates into `rates` (the tail of the model's `dy`; a sampled law
    /// holds its command).
    ///
    /// # Errors
    /// A singular rigid inverse dynamics of the commanded motion (the feedforward).
    pub(crate) fn forces<L: AsRef<LegKinematics>>(
        &self,
        machine: &Machine,
        rigid: &MachineState<L>,
        t: f64,
        y: &[f64],
        rates: &mut [f64],
    ) -> Result<Commands, DynamicsError> {
        let measured = self.measured(y);
        let (law, actuators) = y[2 * self.coordinates..].split_at(self.law_states());
        let (law_rates, actuator_rates) = rates.split_at_mut(self.law_states());
        let reference = Reference::of(machine, self, rigid, t)?;
        let input = self.input(t, &reference, measured);
        let command = self.command(&input, law, law_rates);
        let applied = std::array::from_fn(|i| self.overrides.command[i].unwrap_or(command[i]));
        let outputs = self.apply(
            &applied,
            measured.map(|m| m.velocity),
            actuators,
            actuator_rates,
        );
        Ok((command, outputs))
    }

    /// What the sampled law commands at a sample at `(t, y)` with its states
    /// `slider_states`, for the commanded state `rigid` (see
    /// [`crate::ControlLaws::law_sample`]).
    ///
    /// # Errors
    /// A singular rigid inverse dynamics of the commanded motion (the feedforward).
    pub(crate) fn law_sample_at<L: AsRef<LegKinematics>>(
        &self,
        machine: &Machine,
        rigid: &MachineState<L>,
        t: f64,
        y: &[f64],
        slider_states: &[f64],
    ) -> Result<([f64; 3], Vec<f64>), DynamicsError> {
        let input = self.sample_input(machine, rigid, t, self.measured(y))?;
        Ok(self.law_sample(&input, slider_states))
    }

    /// The control input of a sample at `t` for the commanded state `rigid` and the
    /// measured sliders (the law's view of the machine).
    ///
    /// # Errors
    /// A singular rigid inverse dynamics of the commanded motion (the feedforward).
    pub(crate) fn sample_input<L: AsRef<LegKinematics>>(
        &self,
        machine: &Machine,
        rigid: &MachineState<L>,
        t: f64,
        measured: [SliderState; 3],
    ) -> Result<ControlInput<'static>, DynamicsError> {
        let reference = Reference::of(machine, self, rigid, t)?;
        Ok(self.input(t, &reference, measured))
    }

    /// Takes a sampled law's sample when `t` is one of its sample times (see
    /// [`Actuated::sample`]), for the commanded motion `trajectory` and the sliders measured
    /// from the state `y` (of the model's length); a kinematic failure there is left to the
    /// right-hand side, which meets and reports it.
    pub(crate) fn sample_at(
        &mut self,
        machine: &Machine,
        trajectory: &dyn flexprr_kinematics::Trajectory,
        t: f64,
        y: &[f64],
    ) {
        if self.period() <= 0.0 || y.len() != self.dim() {
            return;
        }
        let measured = self.measured(y);
        let Ok(rigid) = machine
            .geometry
            .inverse_kinematics_unchecked(&trajectory.motion(t))
        else {
            return;
        };
        let Ok(reference) = Reference::of(machine, self, &rigid, t) else {
            return;
        };
        let input = self.input(t, &reference, measured);
        self.sample(&input);
    }

    /// The actuator outputs for the force commands at the slider velocities, with the
    /// actuators' states `states` (their rates into `rates`).
    fn apply(
        &self,
        command: &[f64; 3],
        velocity: [f64; 3],
        states: &[f64],
        rates: &mut [f64],
    ) -> [ActuatorOutput; 3] {
        let friction = self.overrides.friction_velocity;
        let o = self.actuator_offsets;
        let (rates_1, rest) = rates.split_at_mut(o[1]);
        let (rates_2, rates_3) = rest.split_at_mut(o[2] - o[1]);
        let rates = [rates_1, rates_2, rates_3];
        let mut i = 0;
        rates.map(|r| {
            let out = self.spec.actuators[i].apply_with_states(
                command[i],
                velocity[i],
                friction.map(|f| f[i]),
                &states[o[i]..o[i + 1]],
                r,
            );
            i += 1;
            out
        })
    }
}
