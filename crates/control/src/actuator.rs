//! Actuators: what turns a slider's force command into the force on the slider.
//!
//! [`MotorBallScrew`] (a rotary servo motor driving the slider through a ball screw of lead
//! `p`, transmission ratio `g = 2 pi / p` rad per metre):
//!
//! ```text
//! motor speed        omega = g rho'                                   (rad/s; rev/s = rho' / p)
//! reflected mass     m_r = J g^2                                      (added to the slider)
//! torque command     tau_c = F_c / (g eta)                            (eta: screw efficiency)
//! torque             tau = clamp(tau_c, tau_lo(omega), tau_hi(omega)) (the envelope)
//! friction torque    tau_f = b omega + tau_C tanh(omega / omega_s)    (viscous + smoothed Coulomb)
//! force on slider    F = g eta (tau - tau_f)
//! ```
//!
//! The envelope `[tau_lo, tau_hi]` is `[-tau_peak, tau_peak]`, narrowed with a [`Drive`] by
//! its current limit and by the bus voltage at the motor speed (the torque-speed envelope,
//! [`crate::drive`]).
//!
//! The rotor's inertia torque `J omega'` seen at the slider is `g J omega' = m_r rho''`: the
//! model adds `m_r` to the slider's mass. The smoothing speed `omega_s` replaces the sign of
//! the Coulomb friction by `tanh(omega / omega_s)` (a continuous right-hand side; within
//! 0.1 % of the full Coulomb torque above `4 omega_s`). The efficiency is the same in both
//! directions of the power flow (a simple model: a back-driven screw is usually less
//! efficient). The speed limit is not enforced: a run reports when and on which leg the
//! motor speed exceeds it.

use crate::ControlError;
use crate::drive::Drive;
use crate::error::{at_most, check};
use crate::friction::{BRISTLE_DEFLECTION, LuGre};

/// A named signal an actuator reports beside its force (a motor's torque and speed, a
/// linear motor's current, ...): one column per slider in `actuators.csv`, headed
/// `{name}_{slider}_{header_unit}` (`motor_torque_1_N_m`), and the name a run's summary and
/// channels reach it by.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ActuatorSignal {
    /// The name: an identifier (`motor_torque`).
    pub name: &'static str,
    /// The unit as written in a CSV header (`N_m`, `rev_s`, `flag` for a 0/1 signal).
    pub header_unit: &'static str,
    /// The plot symbol (`τ`).
    pub symbol: &'static str,
    /// The unit as written in plot labels (`N·m`).
    pub unit: &'static str,
}

/// The most signals one actuator reports: [`ActuatorOutput`] holds their values inline, so
/// that applying an actuator never allocates.
pub const MAX_ACTUATOR_SIGNALS: usize = 6;

/// Name of the motor torque signal of [`MotorBallScrew`] (N m, after saturation).
pub const MOTOR_TORQUE: &str = "motor_torque";
/// Name of the motor speed signal of [`MotorBallScrew`] (rev/s).
pub const MOTOR_SPEED: &str = "motor_speed";
/// Name of the winding current signal of a [`MotorBallScrew`] with a [`Drive`] (A).
pub const MOTOR_CURRENT: &str = "motor_current";
/// Name of the winding voltage signal of a [`MotorBallScrew`] with a [`Drive`] (V).
pub const MOTOR_VOLTAGE: &str = "motor_voltage";

/// The signals of [`MotorBallScrew`]: torque after saturation, speed, and whether the
/// torque command was clipped at the peak (1) or not (0).
pub const MOTOR_SIGNALS: [ActuatorSignal; 3] = [
    ActuatorSignal {
        name: MOTOR_TORQUE,
        header_unit: "N_m",
        symbol: "τ",
        unit: "N·m",
    },
    ActuatorSignal {
        name: MOTOR_SPEED,
        header_unit: "rev_s",
        symbol: "n",
        unit: "rev/s",
    },
    ActuatorSignal {
        name: "motor_saturated",
        header_unit: "flag",
        symbol: "sat",
        unit: "1",
    },
];

/// The signals of [`MotorBallScrew`] with a [`Drive`]: [`MOTOR_SIGNALS`], then the winding
/// current and voltage.
pub const MOTOR_DRIVE_SIGNALS: [ActuatorSignal; 5] = [
    MOTOR_SIGNALS[0],
    MOTOR_SIGNALS[1],
    MOTOR_SIGNALS[2],
    ActuatorSignal {
        name: MOTOR_CURRENT,
        header_unit: "A",
        symbol: "i",
        unit: "A",
    },
    ActuatorSignal {
        name: MOTOR_VOLTAGE,
        header_unit: "V",
        symbol: "u",
        unit: "V",
    },
];

/// The winding current state of a [`MotorBallScrew`] with a [`crate::Winding`] (A).
const CURRENT_STATE: ActuatorSignal = ActuatorSignal {
    name: MOTOR_CURRENT,
    header_unit: "A",
    symbol: "i",
    unit: "A",
};
/// The current loop's integral (V).
const INTEGRAL_STATE: ActuatorSignal = ActuatorSignal {
    name: "current_loop_integral",
    header_unit: "V",
    symbol: "x",
    unit: "V",
};
/// The screw's twist `theta - g rho` (rad).
const TWIST_STATE: ActuatorSignal = ActuatorSignal {
    name: "screw_twist",
    header_unit: "rad",
    symbol: "φ",
    unit: "rad",
};
/// The rotor's speed (rad/s).
const ROTOR_STATE: ActuatorSignal = ActuatorSignal {
    name: "rotor_speed",
    header_unit: "rad_s",
    symbol: "ω",
    unit: "rad/s",
};
/// The states of a [`MotorBallScrew`] by (winding states, screw, LuGre friction): the
/// winding's current and loop integral first, then the screw's twist and the rotor's speed,
/// then the bristle deflection.
const MOTOR_STATES: [[[&[ActuatorSignal]; 2]; 2]; 3] = [
    [
        [&[], &[BRISTLE]],
        [
            &[TWIST_STATE, ROTOR_STATE],
            &[TWIST_STATE, ROTOR_STATE, BRISTLE],
        ],
    ],
    [
        [&[CURRENT_STATE], &[CURRENT_STATE, BRISTLE]],
        [
            &[CURRENT_STATE, TWIST_STATE, ROTOR_STATE],
            &[CURRENT_STATE, TWIST_STATE, ROTOR_STATE, BRISTLE],
        ],
    ],
    [
        [
            &[CURRENT_STATE, INTEGRAL_STATE],
            &[CURRENT_STATE, INTEGRAL_STATE, BRISTLE],
        ],
        [
            &[CURRENT_STATE, INTEGRAL_STATE, TWIST_STATE, ROTOR_STATE],
            &[
                CURRENT_STATE,
                INTEGRAL_STATE,
                TWIST_STATE,
                ROTOR_STATE,
                BRISTLE,
            ],
        ],
    ],
];
/// The bristle deflection state of LuGre friction (rad).
const BRISTLE: ActuatorSignal = BRISTLE_DEFLECTION[0];

/// What an actuator does at one instant.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ActuatorOutput {
    /// Force on the slider along its guide (N).
    pub force: f64,
    /// Whether the command was beyond the actuator's limit and was clipped.
    pub saturated: bool,
    /// The actuator's own signals ([`Actuator::signals`]); `values[k]` is the value of
    /// `signals[k]`.
    pub signals: &'static [ActuatorSignal],
    /// The signals' values, in the order of `signals` (the rest unused).
    pub values: [f64; MAX_ACTUATOR_SIGNALS],
}

impl ActuatorOutput {
    /// A force with the values `values` of the signals `signals` (as many values as
    /// signals; at most [`MAX_ACTUATOR_SIGNALS`], extra signals are dropped).
    pub fn with_signals(
        force: f64,
        saturated: bool,
        signals: &'static [ActuatorSignal],
        values: &[f64],
    ) -> Self {
        let n = signals.len().min(values.len()).min(MAX_ACTUATOR_SIGNALS);
        let mut out = [0.0; MAX_ACTUATOR_SIGNALS];
        out[..n].copy_from_slice(&values[..n]);
        Self {
            force,
            saturated,
            signals: &signals[..n],
            values: out,
        }
    }

    /// The value of the signal `name`, if the actuator reports it.
    pub fn signal(&self, name: &str) -> Option<f64> {
        self.signals
            .iter()
            .position(|s| s.name == name)
            .map(|k| self.values[k])
    }

    /// The signals with their values, in the actuator's order.
    pub fn signal_values(&self) -> impl Iterator<Item = (&'static ActuatorSignal, f64)> + '_ {
        self.signals.iter().zip(self.values)
    }
}

/// The ratings a motion is checked against.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotorRatings {
    /// Peak torque (N m): the command saturates here.
    pub peak_torque: f64,
    /// Continuous torque (N m): the RMS torque of a motion should stay below it.
    pub continuous_torque: f64,
    /// Largest speed (rev/s).
    pub max_speed: f64,
}

impl MotorRatings {
    /// Checks the ratings: positive and finite, the continuous torque within the peak.
    ///
    /// # Errors
    /// The first rating out of its range, by its key.
    pub fn validated(self) -> Result<Self, ControlError> {
        check(
            "peak_torque",
            self.peak_torque,
            0.0,
            true,
            "must be finite and > 0 (N m)",
        )?;
        check(
            "continuous_torque",
            self.continuous_torque,
            0.0,
            true,
            "must be finite and > 0 (N m)",
        )?;
        at_most(
            "continuous_torque",
            self.continuous_torque,
            self.peak_torque,
            "must not exceed peak_torque",
        )?;
        check(
            "max_speed",
            self.max_speed,
            0.0,
            true,
            "must be finite and > 0 (rev/s)",
        )?;
        Ok(self)
    }
}

/// An actuator of one slider.
///
/// Required: the force on the slider for a force command at a slider velocity, and a name.
/// Provided: no signals besides the force, no reflected mass, no limit, no ratings, no
/// states of its own (an ideal force). A scene names an actuator through a factory
/// registered in the scene layer (`flexprr_scene::ActuatorFactory`).
///
/// An actuator with dynamics of its own (a winding's current, a compliant screw's rotor)
/// declares its states ([`Actuator::states`], [`Actuator::state_names`],
/// [`Actuator::initial_states`]) and computes their rates in
/// [`Actuator::apply_with_states`]: the model carries them in its ODE state after the
/// control law's, and its linear models include them.
///
/// ```
/// use flexprr_control::{Actuator, ActuatorOutput, ActuatorSignal};
///
/// /// The part of the command it clips (N), reported as a signal.
/// const CLIPPED: [ActuatorSignal; 1] =
///     [ActuatorSignal { name: "clipped_force", header_unit: "N", symbol: "ΔF", unit: "N" }];
/// /// Its one state: the force it delivers (N).
/// const LAGGED: [ActuatorSignal; 1] =
///     [ActuatorSignal { name: "lagged_force", header_unit: "N", symbol: "F", unit: "N" }];
///
/// /// A force that clips at 500 N and follows the clipped command with a first-order lag
/// /// of time constant `0.001` s (an amplifier's bandwidth).
/// #[derive(Debug)]
/// struct Clipped;
/// impl Actuator for Clipped {
///     /// In steady state the lag has settled: the clipped command.
///     fn apply(&self, command: f64, _velocity: f64) -> ActuatorOutput {
///         let force = command.clamp(-500.0, 500.0);
///         ActuatorOutput::with_signals(force, command.abs() > 500.0, &CLIPPED, &[command - force])
///     }
///     fn force_limit(&self) -> f64 { 500.0 }
///     fn name(&self) -> &'static str { "clipped" }
///     fn signals(&self) -> &'static [ActuatorSignal] { &CLIPPED }
///     fn states(&self) -> usize { 1 }
///     fn state_names(&self) -> &'static [ActuatorSignal] { &LAGGED }
///     /// `F' = (clamp(F_c) - F) / T`; the force on the slider is the state `F`.
///     fn apply_with_states(
///         &self,
///         command: f64,
///         _velocity: f64,
///         _friction_velocity: Option<f64>,
///         states: &[f64],
///         rates: &mut [f64],
///     ) -> ActuatorOutput {
///         let target = command.clamp(-500.0, 500.0);
///         rates[0] = (target - states[0]) / 0.001;
///         ActuatorOutput::with_signals(states[0], command.abs() > 500.0, &CLIPPED, &[command - target])
///     }
/// }
/// let out = Clipped.apply(800.0, 0.0);
/// assert!(out.saturated);
/// assert_eq!(out.signal("clipped_force"), Some(300.0));
/// // Started at rest, the lagged force rises towards the clipped command at 500 kN/s.
/// let (mut state, mut rate) = ([0.0], [0.0]);
/// Clipped.initial_states(0.0, &mut state);
/// let out = Clipped.apply_with_states(800.0, 0.0, None, &state, &mut rate);
/// assert_eq!((out.force, rate[0]), (0.0, 5.0e5));
/// ```
pub trait Actuator: std::fmt::Debug + Send + Sync {
    /// The force on the slider (and the motor's state) for the force command `command` (N)
    /// at the slider velocity `velocity` (m/s). Must not allocate.
    fn apply(&self, command: f64, velocity: f64) -> ActuatorOutput;
    /// The actuator's name in scene files (`force`, `motor_ballscrew`).
    fn name(&self) -> &'static str;
    /// The named signals [`Actuator::apply`] reports beside the force, in the order of
    /// [`ActuatorOutput::values`] (at most [`MAX_ACTUATOR_SIGNALS`]). None by default.
    fn signals(&self) -> &'static [ActuatorSignal] {
        &[]
    }
    /// The actuator's moving inertia reflected to the slider along its guide (kg): the rotor
    /// inertia `J g^2`. What a motion's feedforward and feasibility add to the slider's mass;
    /// the model adds [`Actuator::mass_on_slider`].
    fn reflected_mass(&self) -> f64 {
        0.0
    }
    /// The largest force it can deliver (N), for anti-windup.
    fn force_limit(&self) -> f64 {
        f64::INFINITY
    }
    /// The motor ratings, where a motor is modelled.
    fn ratings(&self) -> Option<MotorRatings> {
        None
    }
    /// The motor torque (N m) and speed (rev/s) needed to deliver the force `force` (N) on
    /// the slider at the velocity `velocity` (m/s) with no saturation, where a motor is
    /// modelled (the feasibility check of a commanded motion).
    fn required(&self, force: f64, velocity: f64) -> Option<(f64, f64)> {
        let _ = (force, velocity);
        None
    }
    /// The motor's drive (its torque-speed envelope), where one is modelled: what the
    /// feasibility check of a commanded motion compares the winding voltage and current
    /// with. None by default.
    fn drive(&self) -> Option<Drive> {
        None
    }
    /// As [`Actuator::apply`], with the actuator's non-smooth friction (Coulomb friction,
    /// whose smoothed slope at rest is an artefact of the smoothing, not a damper) evaluated
    /// at the velocity `friction_velocity` instead of `velocity`: a linearisation holds it
    /// at its value at the operating point (docs/linear.md, "Friction"). Actuators without
    /// such a term: `apply` itself (the default).
    fn apply_with_friction_at(
        &self,
        command: f64,
        velocity: f64,
        friction_velocity: f64,
    ) -> ActuatorOutput {
        let _ = friction_velocity;
        self.apply(command, velocity)
    }
    /// Whether at the slider velocity `velocity` (m/s) the actuator's friction is within its
    /// non-smooth range (Coulomb friction near zero speed, where a smoothed model's slope is
    /// far steeper than any physical damping): what a linearisation reports when it leaves
    /// that friction out. False without such a term (the default).
    fn friction_is_non_smooth_at(&self, velocity: f64) -> bool {
        let _ = velocity;
        false
    }
    /// Number of the actuator's own states, carried in the model's ODE state (after the
    /// control law's): none by default (the actuator is a function of the command and the
    /// slider velocity, [`Actuator::apply`]).
    fn states(&self) -> usize {
        0
    }
    /// The actuator's states, one per state in their order (name and unit; the linear
    /// models name their states by them). None by default.
    fn state_names(&self) -> &'static [ActuatorSignal] {
        &[]
    }
    /// The states at the start of a run whose slider starts at the velocity `velocity`
    /// (m/s), into `states` ([`Actuator::states`] entries). Zero by default.
    fn initial_states(&self, velocity: f64, states: &mut [f64]) {
        let _ = velocity;
        states.fill(0.0);
    }
    /// The force on the slider for the force command `command` (N) at the slider velocity
    /// `velocity` (m/s) with the actuator's states `states`, their rates into `rates` (both
    /// [`Actuator::states`] entries). `friction_velocity`: a slider velocity at which a
    /// linearisation holds the non-smooth friction (see
    /// [`Actuator::apply_with_friction_at`]); `None` in a run (the friction at the
    /// actuator's own speed). Must not allocate. By default (no states)
    /// [`Actuator::apply_with_friction_at`].
    fn apply_with_states(
        &self,
        command: f64,
        velocity: f64,
        friction_velocity: Option<f64>,
        states: &[f64],
        rates: &mut [f64],
    ) -> ActuatorOutput {
        let _ = (states, rates);
        self.apply_with_friction_at(command, velocity, friction_velocity.unwrap_or(velocity))
    }
    /// The force command (N) that holds the actuator's steady-state friction at the slider
    /// velocity `velocity` (m/s): what a law's feedforward adds at the commanded velocity
    /// (besides the rigid inverse dynamics and the reflected inertia), so that the feedback
    /// does not have to carry the friction. None by default.
    fn friction_feedforward(&self, velocity: f64) -> f64 {
        let _ = velocity;
        0.0
    }
    /// Mass the actuator adds to the slider's own equation of motion (kg): the reflected
    /// mass ([`Actuator::reflected_mass`]) when the transmission is rigid (the default), none
    /// when the actuator carries its rotor in its own states (a compliant screw).
    fn mass_on_slider(&self) -> f64 {
        self.reflected_mass()
    }
}

/// `kind = "force"`: the command is the force.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct IdealForce;

impl Actuator for IdealForce {
    fn apply(&self, command: f64, _velocity: f64) -> ActuatorOutput {
        ActuatorOutput {
            force: command,
            ..ActuatorOutput::default()
        }
    }
    fn name(&self) -> &'static str {
        "force"
    }
}

/// `kind = "motor_ballscrew"`: a servo motor driving the slider through a ball screw (see
/// the module documentation for the equations).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotorBallScrew {
    /// Rotor (plus coupling and screw) inertia `J` (kg m^2).
    pub rotor_inertia: f64,
    /// Screw lead `p` (m/rev).
    pub lead: f64,
    /// Screw efficiency `eta` (0 < eta <= 1).
    pub efficiency: f64,
    /// Ratings: peak and continuous torque, largest speed.
    pub ratings: MotorRatings,
    /// Viscous friction `b` at the motor shaft (N m s/rad).
    pub viscous_friction: f64,
    /// Coulomb friction torque `tau_C` at the motor shaft (N m).
    pub coulomb_friction: f64,
    /// Speed `omega_s` of the Coulomb friction's smoothing (rev/s).
    pub coulomb_smoothing: f64,
    /// The drive's electrics (the torque-speed envelope, and the winding's dynamics where
    /// modelled); `None`: the peak torque at any speed.
    pub drive: Option<Drive>,
    /// The screw's axial compliance, where modelled; `None`: a rigid screw.
    pub screw: Option<Screw>,
    /// Whether a law's feedforward adds the force of the steady friction at the commanded
    /// slider velocity ([`Actuator::friction_feedforward`]).
    pub friction_feedforward: bool,
    /// LuGre friction with a stuck phase ([`crate::friction`]), where modelled: it replaces
    /// the smoothed Coulomb friction (the Coulomb and viscous torques are its `tau_C` and
    /// `sigma2`; `coulomb_smoothing` is unused) and adds the bristle deflection as the
    /// motor's state. `None`: viscous plus smoothed Coulomb friction.
    pub lugre: Option<LuGre>,
}

/// The axial compliance of a ball screw (with its nut and bearings): a spring and damper
/// between the motor, seen at the slider as the travel `theta / g` of its angle `theta`,
/// and the slider (module documentation of [`MotorBallScrew`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Screw {
    /// Axial stiffness `k` (N/m).
    pub stiffness: f64,
    /// Axial damping `c` (N s/m).
    pub damping: f64,
}

impl Screw {
    /// Checks the stiffness and damping, and that the rotor on the spring (of inertia
    /// `rotor_inertia`, kg m^2) has a mass.
    ///
    /// # Errors
    /// The first parameter out of its range, by its key.
    pub fn validated(self, rotor_inertia: f64) -> Result<Self, ControlError> {
        check(
            "screw_stiffness",
            self.stiffness,
            0.0,
            true,
            "must be finite and > 0 (N/m; ball screws have 1e7 to 1e9)",
        )?;
        at_most(
            "screw_stiffness",
            self.stiffness,
            1e12,
            "must be at most 1e12 N/m",
        )?;
        check(
            "screw_damping",
            self.damping,
            0.0,
            false,
            "must be finite and >= 0 (N s/m)",
        )?;
        at_most(
            "screw_damping",
            self.damping,
            1e9,
            "must be at most 1e9 N s/m",
        )?;
        if rotor_inertia <= 0.0 {
            return Err(ControlError::InvalidParameter {
                name: "rotor_inertia",
                value: rotor_inertia,
                rule: "must be > 0 with screw_stiffness: the rotor is a mass on the screw's \
                       spring",
            });
        }
        Ok(self)
    }
}

impl MotorBallScrew {
    /// Checks every parameter.
    ///
    /// # Errors
    /// The first parameter out of its range, by its key.
    pub fn validated(self) -> Result<Self, ControlError> {
        check(
            "rotor_inertia",
            self.rotor_inertia,
            0.0,
            false,
            "must be finite and >= 0 (kg m^2)",
        )?;
        check(
            "lead",
            self.lead,
            0.0,
            true,
            "must be finite and > 0 (m/rev)",
        )?;
        check(
            "efficiency",
            self.efficiency,
            0.0,
            true,
            "must be in (0, 1]",
        )?;
        at_most("efficiency", self.efficiency, 1.0, "must be in (0, 1]")?;
        self.ratings.validated()?;
        check(
            "viscous_friction",
            self.viscous_friction,
            0.0,
            false,
            "must be finite and >= 0 (N m s/rad)",
        )?;
        check(
            "coulomb_friction",
            self.coulomb_friction,
            0.0,
            false,
            "must be finite and >= 0 (N m)",
        )?;
        check(
            "coulomb_smoothing",
            self.coulomb_smoothing,
            0.0,
            true,
            "must be finite and > 0 (rev/s)",
        )?;
        // Bounds far beyond any motor and screw (by orders of magnitude), which keep the
        // torque, the reflected inertia `J (2 pi / p)^2` and their squares (the RMS torque)
        // finite: a value beyond them is a unit slip, and would overflow.
        for (name, value, max, rule) in [
            (
                "rotor_inertia",
                self.rotor_inertia,
                1e3,
                "must be at most 1e3 kg m^2 (servo rotors are 1e-6 to 1e-1)",
            ),
            (
                "lead",
                self.lead,
                10.0,
                "must be at most 10 m/rev (ball screws have 1 to 50 mm)",
            ),
            (
                "peak_torque",
                self.ratings.peak_torque,
                1e6,
                "must be at most 1e6 N m (servo motors give 0.1 to 1e3)",
            ),
            (
                "max_speed",
                self.ratings.max_speed,
                1e5,
                "must be at most 1e5 rev/s (servo motors turn up to about 300)",
            ),
            (
                "viscous_friction",
                self.viscous_friction,
                1e6,
                "must be at most 1e6 N m s/rad",
            ),
            (
                "coulomb_friction",
                self.coulomb_friction,
                1e6,
                "must be at most 1e6 N m",
            ),
            (
                "coulomb_smoothing",
                self.coulomb_smoothing,
                1e5,
                "must be at most 1e5 rev/s",
            ),
        ] {
            if value > max {
                return Err(ControlError::InvalidParameter { name, value, rule });
            }
        }
        if self.lead < 1e-6 {
            return Err(ControlError::InvalidParameter {
                name: "lead",
                value: self.lead,
                rule: "must be at least 1e-6 m/rev (1 um per turn; ball screws have 1 to 50 mm): \
                       a finer lead makes the reflected rotor inertia J (2 pi / lead)^2 and the \
                       friction torque overflow",
            });
        }
        if self.efficiency < 0.01 {
            return Err(ControlError::InvalidParameter {
                name: "efficiency",
                value: self.efficiency,
                rule: "must be in [0.01, 1] (screws have 0.2 to 0.95): the torque is the force \
                       divided by it",
            });
        }
        if let Some(drive) = self.drive {
            drive.validated()?;
        }
        if let Some(screw) = self.screw {
            screw.validated(self.rotor_inertia)?;
        }
        if let Some(lugre) = self.lugre {
            lugre.validated(self.coulomb_friction)?;
        }
        Ok(self)
    }

    /// Transmission ratio `g = 2 pi / p` (rad per metre of slider travel).
    pub fn ratio(&self) -> f64 {
        std::f64::consts::TAU / self.lead
    }

    /// The frequency (Hz) of the screw's mode with the slider held,
    /// `(1/2 pi) sqrt(k / m_r)`, `m_r = J g^2` (none for a rigid screw). With a free slider of
    /// mass `m_s` it rises to `(1/2 pi) sqrt(k (1/m_r + 1/m_s))`.
    pub fn screw_mode_held_hz(&self) -> Option<f64> {
        let k = self.screw?.stiffness;
        Some((k / self.reflected_mass()).sqrt() / std::f64::consts::TAU)
    }

    /// The number of the winding's states (the drive's [`Drive::states`]).
    fn winding_states(&self) -> usize {
        self.drive.map_or(0, |d| d.states())
    }

    /// Friction torque at the motor shaft (N m) at the motor speed `omega` (rad/s), in
    /// steady state (with [`LuGre`] friction: sliding at `omega`, [`LuGre::steady_torque`]).
    pub fn friction_torque(&self, omega: f64) -> f64 {
        if let Some(lugre) = self.lugre {
            return lugre.steady_torque(self.coulomb_friction, self.viscous_friction, omega);
        }
        self.smoothed_friction(omega, omega)
    }

    /// The viscous friction at the motor speed `omega` plus the `tanh`-smoothed Coulomb
    /// friction at the motor speed `coulomb_speed` (rad/s; a linearisation holds it apart,
    /// [`Actuator::apply_with_friction_at`]): the friction torque without LuGre (N m).
    fn smoothed_friction(&self, omega: f64, coulomb_speed: f64) -> f64 {
        let smoothing = std::f64::consts::TAU * self.coulomb_smoothing;
        self.viscous_friction * omega + self.coulomb_friction * (coulomb_speed / smoothing).tanh()
    }

    /// The largest torque the motor can hold at any speed (N m): the peak torque, or the
    /// drive's current limit times its torque constant when lower.
    pub fn torque_limit(&self) -> f64 {
        let peak = self.ratings.peak_torque;
        self.drive
            .map_or(peak, |d| peak.min(d.current_limited_torque()))
    }

    /// The torque interval the motor can give at the motor speed `omega` (rad/s): within
    /// [`MotorBallScrew::torque_limit`], and with a [`Drive`] within its bus voltage (the
    /// torque-speed envelope). Beyond the no-load speed, where the voltage allows no torque
    /// within the current limit, the drive brakes as hard as its current allows.
    pub fn torque_range(&self, omega: f64) -> (f64, f64) {
        let limit = self.torque_limit();
        let Some(drive) = self.drive else {
            return (-limit, limit);
        };
        let (lo, hi) = drive.voltage_limited_torque(omega);
        let (lo, hi) = (lo.max(-limit), hi.min(limit));
        if lo <= hi {
            (lo, hi)
        } else {
            let brake = -limit * omega.signum();
            (brake, brake)
        }
    }

    /// The output for the force command `command` (N) at the slider velocity `velocity`
    /// (m/s) against the friction torque `friction` (N m): the torque within its envelope,
    /// the force on the slider and the signals.
    fn output(&self, command: f64, velocity: f64, friction: f64) -> ActuatorOutput {
        let g = self.ratio();
        let omega = g * velocity;
        let wanted = command / (g * self.efficiency);
        let (lo, hi) = self.torque_range(omega);
        let torque = wanted.clamp(lo, hi);
        let saturated = wanted < lo || wanted > hi;
        let force = g * self.efficiency * (torque - friction);
        let flag = f64::from(u8::from(saturated));
        match self.drive {
            None => ActuatorOutput::with_signals(
                force,
                saturated,
                &MOTOR_SIGNALS,
                &[torque, velocity / self.lead, flag],
            ),
            Some(drive) => ActuatorOutput::with_signals(
                force,
                saturated,
                &MOTOR_DRIVE_SIGNALS,
                &[
                    torque,
                    velocity / self.lead,
                    flag,
                    drive.current(torque),
                    drive.voltage(torque, omega),
                ],
            ),
        }
    }
}

impl Actuator for MotorBallScrew {
    fn apply(&self, command: f64, velocity: f64) -> ActuatorOutput {
        self.apply_with_friction_at(command, velocity, velocity)
    }
    /// The viscous friction at `velocity`, the Coulomb friction at `friction_velocity`.
    fn apply_with_friction_at(
        &self,
        command: f64,
        velocity: f64,
        friction_velocity: f64,
    ) -> ActuatorOutput {
        let g = self.ratio();
        let omega = g * velocity;
        let friction = if let Some(lugre) = self.lugre {
            // Stateless: the bristles as when sliding (the Stribeck curve).
            let coulomb = lugre.steady_torque(self.coulomb_friction, 0.0, g * friction_velocity);
            coulomb + self.viscous_friction * omega
        } else {
            self.smoothed_friction(omega, g * friction_velocity)
        };
        self.output(command, velocity, friction)
    }
    /// Within four smoothing speeds of rest (`|rho'| / p < 4 omega_s`), where
    /// `tanh(omega / omega_s)` is still 0.1 % or more short of the full Coulomb torque and
    /// its slope `tau_C / omega_s` is the smoothing's, not the machine's.
    /// LuGre friction has no smoothing (its bristles are the physics): never.
    fn friction_is_non_smooth_at(&self, velocity: f64) -> bool {
        self.lugre.is_none()
            && self.coulomb_friction > 0.0
            && (velocity / self.lead).abs() < 4.0 * self.coulomb_smoothing
    }
    /// The winding's current and the current loop's integral (with a [`crate::Winding`]),
    /// then the screw's twist and the rotor's speed (with a [`Screw`]).
    fn states(&self) -> usize {
        self.winding_states()
            + if self.screw.is_some() { 2 } else { 0 }
            + usize::from(self.lugre.is_some())
    }
    fn state_names(&self) -> &'static [ActuatorSignal] {
        MOTOR_STATES[self.winding_states()][usize::from(self.screw.is_some())]
            [usize::from(self.lugre.is_some())]
    }
    /// No current, no integral, no twist; the rotor turning with the slider, `g rho'`; with
    /// [`LuGre`] friction the bristles as when sliding at that speed
    /// ([`LuGre::steady_deflection`]; unloaded at rest).
    fn initial_states(&self, velocity: f64, states: &mut [f64]) {
        states.fill(0.0);
        let omega = self.ratio() * velocity;
        let mechanical = self.winding_states();
        if self.screw.is_some() {
            states[mechanical + 1] = omega;
        }
        if let Some(lugre) = self.lugre {
            states[self.states() - 1] = lugre.steady_deflection(self.coulomb_friction, omega);
        }
    }
    /// The module documentation's equations with the winding's dynamics ([`crate::drive`])
    /// and the compliant screw: `phi' = omega - g rho'`,
    /// `J omega' = eta (tau - tau_f) - F_s / g`, `F_s = k phi / g + c (omega / g - rho')` the
    /// force on the slider (the efficiency acts on the motor's torque as for the rigid
    /// screw, so that the stiff limit is the rigid model).
    fn apply_with_states(
        &self,
        command: f64,
        velocity: f64,
        friction_velocity: Option<f64>,
        states: &[f64],
        rates: &mut [f64],
    ) -> ActuatorOutput {
        if self.states() == 0 {
            return self.apply_with_friction_at(
                command,
                velocity,
                friction_velocity.unwrap_or(velocity),
            );
        }
        let g = self.ratio();
        let electric = self.winding_states();
        let omega = if self.screw.is_some() {
            states[electric + 1]
        } else {
            g * velocity
        };
        let wanted = command / (g * self.efficiency);
        let (torque, saturated, electrics) = match self.drive {
            Some(drive) if electric > 0 => {
                let w = drive
                    .winding(
                        wanted,
                        self.torque_limit(),
                        omega,
                        &states[..electric],
                        &mut rates[..electric],
                    )
                    .unwrap_or(crate::WindingOutput {
                        torque: 0.0,
                        current: 0.0,
                        voltage: 0.0,
                        saturated: false,
                    });
                (w.torque, w.saturated, Some((w.current, w.voltage)))
            }
            drive => {
                let (lo, hi) = self.torque_range(omega);
                let torque = wanted.clamp(lo, hi);
                let electrics = drive.map(|d| (d.current(torque), d.voltage(torque, omega)));
                (torque, wanted < lo || wanted > hi, electrics)
            }
        };
        let friction = if let Some(lugre) = self.lugre {
            let bristle = self.states() - 1;
            let (torque, rate) = lugre.torque(
                self.coulomb_friction,
                self.viscous_friction,
                omega,
                states[bristle],
            );
            rates[bristle] = rate;
            torque
        } else {
            self.smoothed_friction(omega, friction_velocity.map_or(omega, |v| g * v))
        };
        let force = match self.screw {
            Some(screw) => {
                let twist = states[electric];
                let force = screw.stiffness * twist / g + screw.damping * (omega / g - velocity);
                rates[electric] = omega - g * velocity;
                rates[electric + 1] =
                    (self.efficiency * (torque - friction) - force / g) / self.rotor_inertia;
                force
            }
            None => g * self.efficiency * (torque - friction),
        };
        let flag = f64::from(u8::from(saturated));
        let speed = omega / std::f64::consts::TAU;
        match electrics {
            None => ActuatorOutput::with_signals(
                force,
                saturated,
                &MOTOR_SIGNALS,
                &[torque, speed, flag],
            ),
            Some((current, voltage)) => ActuatorOutput::with_signals(
                force,
                saturated,
                &MOTOR_DRIVE_SIGNALS,
                &[torque, speed, flag, current, voltage],
            ),
        }
    }
    /// With [`MotorBallScrew::friction_feedforward`], `g eta tau_f(g rho')`: the command
    /// whose torque `tau_f` holds the friction (the force on the slider is
    /// `g eta (tau - tau_f)`).
    fn friction_feedforward(&self, velocity: f64) -> f64 {
        if !self.friction_feedforward {
            return 0.0;
        }
        let g = self.ratio();
        g * self.efficiency * self.friction_torque(g * velocity)
    }
    /// The reflected mass with a rigid screw; none with a compliant one (the rotor is a
    /// state of its own).
    fn mass_on_slider(&self) -> f64 {
        if self.screw.is_some() {
            0.0
        } else {
            self.reflected_mass()
        }
    }
    fn name(&self) -> &'static str {
        "motor_ballscrew"
    }
    fn signals(&self) -> &'static [ActuatorSignal] {
        if self.drive.is_some() {
            &MOTOR_DRIVE_SIGNALS
        } else {
            &MOTOR_SIGNALS
        }
    }
    fn reflected_mass(&self) -> f64 {
        let g = self.ratio();
        self.rotor_inertia * g * g
    }
    fn force_limit(&self) -> f64 {
        self.ratio() * self.efficiency * self.torque_limit()
    }
    fn ratings(&self) -> Option<MotorRatings> {
        Some(self.ratings)
    }
    fn drive(&self) -> Option<Drive> {
        self.drive
    }
    /// The torque that delivers `force` against the friction at `velocity`:
    /// `tau = F / (g eta) + tau_f(g rho')`, and the speed `rho' / p`.
    fn required(&self, force: f64, velocity: f64) -> Option<(f64, f64)> {
        let g = self.ratio();
        let torque = force / (g * self.efficiency) + self.friction_torque(g * velocity);
        Some((torque, velocity / self.lead))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Winding;

    fn motor() -> MotorBallScrew {
        MotorBallScrew {
            rotor_inertia: 1.0e-5,
            lead: 0.01,
            efficiency: 0.9,
            ratings: MotorRatings {
                peak_torque: 3.5,
                continuous_torque: 1.2,
                max_speed: 100.0,
            },
            viscous_friction: 1.0e-4,
            coulomb_friction: 0.02,
            coulomb_smoothing: 0.01,
            drive: None,
            friction_feedforward: false,
            screw: None,
            lugre: None,
        }
        .validated()
        .unwrap()
    }

    #[test]
    fn the_ball_screw_reflects_inertia_and_force_by_its_ratio() {
        let m = motor();
        let g = std::f64::consts::TAU / 0.01;
        assert!((m.reflected_mass() - 1.0e-5 * g * g).abs() <= 1e-12);
        // Below the peak and at rest the commanded force arrives (friction tanh(0) = 0).
        let out = m.apply(100.0, 0.0);
        assert!((out.force - 100.0).abs() <= 1e-9, "{out:?}");
        assert!(!out.saturated);
        // Power balance without friction: F v = eta tau omega.
        let frictionless = MotorBallScrew {
            viscous_friction: 0.0,
            coulomb_friction: 0.0,
            ..m
        };
        let (v, f) = (0.5, 300.0);
        let out = frictionless.apply(f, v);
        let (tau, omega) = (out.signal(MOTOR_TORQUE).unwrap(), g * v);
        assert!((out.force * v - 0.9 * tau * omega).abs() <= 1e-9 * f * v);
        assert!((out.signal(MOTOR_SPEED).unwrap() - 50.0).abs() <= 1e-12);
        // `required` inverts `apply` below the peak.
        let (torque, _) = m.required(f, v).unwrap();
        let back = m.apply(g * 0.9 * torque, v);
        assert!((back.force - f).abs() <= 1e-9 * f, "{back:?}");
    }

    #[test]
    fn the_torque_saturates_at_the_peak_and_says_so() {
        let m = motor();
        let limit = m.force_limit();
        let out = m.apply(2.0 * limit, 0.0);
        assert!(out.saturated);
        assert!((out.signal(MOTOR_TORQUE).unwrap() - 3.5).abs() <= 1e-12);
        assert!((out.force - limit).abs() <= 1e-9 * limit);
    }

    #[test]
    fn the_coulomb_friction_opposes_the_motion_and_is_smooth() {
        let m = MotorBallScrew {
            viscous_friction: 0.0,
            ..motor()
        };
        let g = m.ratio();
        // Well above the smoothing speed: the full Coulomb torque, opposing the motion.
        let fast = 4.0 * m.coulomb_smoothing * m.lead;
        assert!((m.friction_torque(g * fast) / 0.02 - 1.0).abs() < 1e-3);
        assert!(m.apply(0.0, -fast).force > 0.0);
        // Continuous through zero speed.
        assert!(m.friction_torque(0.0).abs() <= 0.0);
    }

    #[test]
    fn bad_parameters_are_refused_by_key() {
        let e = MotorBallScrew {
            lead: 0.0,
            ..motor()
        }
        .validated()
        .unwrap_err();
        assert!(e.to_string().starts_with("lead = 0"), "{e}");
        let e = MotorBallScrew {
            efficiency: 1.5,
            ..motor()
        }
        .validated()
        .unwrap_err();
        assert!(e.to_string().contains("(0, 1]"), "{e}");
        let mut bad = motor();
        bad.ratings.continuous_torque = 5.0;
        let e = bad.validated().unwrap_err();
        assert!(e.to_string().contains("peak_torque"), "{e}");
    }

    #[test]
    fn a_drive_holds_the_torque_within_its_envelope() {
        let drive = Drive {
            torque_constant: 0.2,
            resistance: 1.5,
            bus_voltage: 100.0,
            current_limit: 12.0,
            winding: None,
        };
        let m = MotorBallScrew {
            drive: Some(drive),
            ..motor()
        };
        let m = m.validated().unwrap();
        let g = m.ratio();
        assert_eq!(m.signals().len(), 5);
        // At rest the current limit holds the torque at K_t I_max = 2.4 N m (peak 3.5).
        let out = m.apply(1e4, 0.0);
        let torque = out.signal(MOTOR_TORQUE).unwrap();
        assert!((torque - 2.4).abs() <= 1e-12, "{torque}");
        assert!(out.saturated);
        assert!((out.signal(MOTOR_CURRENT).unwrap() - 12.0).abs() <= 1e-12);
        // At 75 rev/s motoring: K_t (V - K_e omega) / R, and the winding voltage is the bus.
        let v = 75.0 * m.lead;
        let omega = g * v;
        let out = m.apply(1e4, v);
        let expected = 0.2 * (100.0 - 0.2 * omega) / 1.5;
        let torque = out.signal(MOTOR_TORQUE).unwrap();
        assert!((torque - expected).abs() <= 1e-12, "{torque} vs {expected}");
        assert!((out.signal(MOTOR_VOLTAGE).unwrap() - 100.0).abs() <= 1e-9);
        // Braking at the same speed: the back-EMF helps, the current limit binds.
        let out = m.apply(-1e4, v);
        assert!((out.signal(MOTOR_TORQUE).unwrap() + 2.4).abs() <= 1e-12);
        // Beyond the no-load speed V / K_e (79.6 rev/s) no motoring torque is left.
        let v = 90.0 * m.lead;
        let out = m.apply(1e4, v);
        assert!(out.signal(MOTOR_TORQUE).unwrap() <= 0.0);
        // Within the envelope the command arrives and the signals obey u = R i + K_e omega.
        let out = m.apply(50.0, 10.0 * m.lead);
        assert!(!out.saturated);
        let (i, u) = (
            out.signal(MOTOR_CURRENT).unwrap(),
            out.signal(MOTOR_VOLTAGE).unwrap(),
        );
        assert!((u - (1.5 * i + 0.2 * g * 10.0 * m.lead)).abs() <= 1e-9);
        // The anti-windup limit follows the current limit.
        assert!((m.force_limit() - g * 0.9 * 2.4).abs() <= 1e-9);
    }

    /// Every combination of winding, compliant screw and LuGre friction names each of its
    /// states, and the bristles ride last: with a compliant screw they see the rotor's
    /// speed, and the rotor feels their torque (LuGre at `z = 0`: `z' = omega`, friction
    /// `(sigma1 + sigma2) omega`).
    #[test]
    fn the_motor_states_combine_winding_screw_and_bristles() {
        let lugre = LuGre {
            static_friction: 0.03,
            stribeck_speed: 0.05,
            bristle_stiffness: 30.0,
            bristle_damping: 0.02,
        };
        let screw = Screw {
            stiffness: 1e8,
            damping: 300.0,
        };
        let drive = |winding: Option<Winding>| Drive {
            torque_constant: 0.2,
            resistance: 1.5,
            bus_voltage: 320.0,
            current_limit: 16.0,
            winding,
        };
        let windings = [
            None,
            Some(drive(None)),
            Some(drive(Some(Winding {
                inductance: 2.6e-3,
                current_bandwidth: None,
            }))),
            Some(drive(Some(Winding {
                inductance: 2.6e-3,
                current_bandwidth: Some(1000.0),
            }))),
        ];
        for d in windings {
            for s in [None, Some(screw)] {
                for l in [None, Some(lugre)] {
                    let m = MotorBallScrew {
                        drive: d,
                        screw: s,
                        lugre: l,
                        ..motor()
                    }
                    .validated()
                    .unwrap();
                    assert_eq!(m.state_names().len(), m.states(), "{d:?} {s:?} {l:?}");
                    if let Some(l) = l {
                        assert_eq!(m.state_names().last().unwrap().name, "bristle_deflection");
                        let mut y = vec![0.0; m.states()];
                        m.initial_states(0.05, &mut y);
                        let omega = m.ratio() * 0.05;
                        let z = l.steady_deflection(m.coulomb_friction, omega);
                        assert!((y[m.states() - 1] - z).abs() <= 1e-15);
                    }
                }
            }
        }
        // Screw and bristles, no drive: the rotor turns at 10 rad/s, the slider at rest, the
        // screw untwisted, the bristles unloaded.
        let m = MotorBallScrew {
            screw: Some(screw),
            lugre: Some(lugre),
            ..motor()
        }
        .validated()
        .unwrap();
        let omega = 10.0;
        let (y, mut rates) = ([0.0, omega, 0.0], [0.0; 3]);
        let out = m.apply_with_states(0.0, 0.0, None, &y, &mut rates);
        let g = m.ratio();
        let force = screw.damping * omega / g;
        assert!((out.force - force).abs() <= 1e-12 * force);
        assert!((rates[2] - omega).abs() <= 1e-12 * omega);
        let friction = (lugre.bristle_damping + m.viscous_friction) * omega;
        let rotor = (-m.efficiency * friction - force / g) / m.rotor_inertia;
        assert!(
            (rates[1] - rotor).abs() <= 1e-9 * rotor.abs(),
            "{} vs {rotor}",
            rates[1]
        );
        assert!((rates[0] - omega).abs() <= 1e-12 * omega);
    }
}
