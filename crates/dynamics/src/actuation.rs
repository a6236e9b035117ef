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
#[derive(Debug, Clone)]
pub(crate) struct Actuated {
    pub(crate) spec: Actuation,
    /// Slider mass plus the actuator's reflected mass, per slider (kg).
    pub(crate) slider_mass: [f64; 3],
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
/// plus the actuators' reflected inertia `m_r rho_ref''`.
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
        let feedforward = std::array::from_fn(|i| {
            forces.driving_force[i] + actuated.spec.actuators[i].reflected_mass() * legs[i].rho_ddot
        });
        Ok(Self {
            sliders,
            feedforward,
        })
    }
}

impl Actuated {
    /// The actuation of `machine`'s sliders, started at `start`.
    pub(crate) fn new(spec: Actuation, machine: &Machine, start: f64) -> Self {
        let slider_mass =
            std::array::from_fn(|i| machine.slider_mass[i] + spec.actuators[i].reflected_mass());
        let rates = vec![0.0; spec.controller.states()];
        let spec_period = spec.controller.period();
        Self {
            spec,
            slider_mass,
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
    pub(crate) fn ode_states(&self) -> usize {
        if self.period() > 0.0 {
            0
        } else {
            self.spec.controller.states()
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

    /// The force commands and the actuators' outputs at `t` for the commanded state `rigid`
    /// and the measured sliders, with the continuous law's states `states` (their rates into
    /// `rates`; a sampled law holds its command).
    ///
    /// # Errors
    /// A singular rigid inverse dynamics of the commanded motion (the feedforward).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn forces<L: AsRef<LegKinematics>>(
        &self,
        machine: &Machine,
        rigid: &MachineState<L>,
        t: f64,
        measured: [SliderState; 3],
        states: &[f64],
        rates: &mut [f64],
    ) -> Result<Commands, DynamicsError> {
        let reference = Reference::of(machine, self, rigid, t)?;
        let input = self.input(t, &reference, measured);
        let command = self.command(&input, states, rates);
        let applied = std::array::from_fn(|i| self.overrides.command[i].unwrap_or(command[i]));
        Ok((command, self.apply(&applied, measured.map(|m| m.velocity))))
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
    /// [`Actuated::sample`]), for the commanded motion `trajectory` and the measured
    /// sliders; a kinematic failure there is left to the right-hand side, which meets and
    /// reports it.
    pub(crate) fn sample_at(
        &mut self,
        machine: &Machine,
        trajectory: &dyn flexprr_kinematics::Trajectory,
        t: f64,
        measured: [SliderState; 3],
    ) {
        if self.period() <= 0.0 {
            return;
        }
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

    /// The actuator outputs for the force commands at the slider velocities.
    pub(crate) fn apply(&self, command: &[f64; 3], velocity: [f64; 3]) -> [ActuatorOutput; 3] {
        let friction = self.overrides.friction_velocity.unwrap_or(velocity);
        std::array::from_fn(|i| {
            self.spec.actuators[i].apply_with_friction_at(command[i], velocity[i], friction[i])
        })
    }
}
