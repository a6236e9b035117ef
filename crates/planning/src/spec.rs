//! The plan's settings as data: what a scene's `[plan]` table holds (docs/planning.md,
//! "Settings"). Deserialised with unknown keys refused; [`PlanSpec::validate`] names the key
//! of the first value out of its range, so that the scene layer can point at its line.

use flexprr_control::MotorBallScrew;
use flexprr_dynamics::Machine;
use serde::{Deserialize, Serialize};

use crate::constraint::{
    Buckling, Constraint, Efficiency, MotorSpeed, MotorTorque, MotorVoltage, PlatformSpeed,
    SliderAcceleration, SliderForce, SliderSpeed,
};
use crate::error::PlanningError;
use crate::orientation::{PhiEnds, PhiObjective, PhiSearch, Schedule};
use crate::plan::{Boundary, RmsLimit, Settings};
use crate::shaping::{Mode, Shaper, design_for_modes};

/// What the plan minimises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Objective {
    /// The time of the motion.
    #[default]
    MinTime,
}

/// Input shaping of the planned motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Shaping {
    /// None.
    #[default]
    None,
    /// Zero vibration.
    Zv,
    /// Zero vibration and derivative.
    Zvd,
    /// Extra insensitive (tolerance `shaping_tolerance`).
    Ei,
}

/// How the platform's orientation `phi` is chosen (`phi` key).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PhiMode {
    /// The path's own orientation.
    #[default]
    Fixed,
    /// The best constant orientation within the bounds.
    BestConstant,
    /// A smooth orientation law along the path, from the best constant.
    Free,
}

/// What the orientation is chosen for (`phi_objective` key).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PhiGoal {
    /// The shortest time-optimal motion (the largest frequency of a periodic one).
    #[default]
    MinTime,
    /// The largest buckling margin at the scene's own timing of the path.
    MaxMargin,
}

fn goal_name(goal: PhiGoal) -> &'static str {
    match goal {
        PhiGoal::MinTime => "min_time",
        PhiGoal::MaxMargin => "max_margin",
    }
}

fn ends_name(ends: PhiEnds) -> &'static str {
    match ends {
        PhiEnds::Free => "free",
        PhiEnds::Fixed => "fixed",
    }
}

fn yes() -> bool {
    true
}
fn default_grid() -> usize {
    1000
}
fn default_check_factor() -> usize {
    10
}
fn default_refinements() -> usize {
    3
}
fn default_tolerance() -> f64 {
    0.05
}
fn default_modes() -> usize {
    1
}
fn default_scan_step() -> f64 {
    2.0
}
fn default_phi_tolerance() -> f64 {
    0.01
}
fn default_phi_step() -> f64 {
    5.0
}
fn default_brackets() -> usize {
    3
}
fn default_spline_points() -> usize {
    6
}
fn default_harmonics() -> usize {
    2
}
fn default_evaluations() -> usize {
    1000
}
fn default_samples() -> usize {
    1000
}

/// The `[plan]` settings (docs/planning.md, "Settings"). Every limit is optional; at least
/// one must bound the motion.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanSpec {
    /// `min_time`.
    #[serde(default)]
    pub objective: Objective,
    /// `rest_to_rest` or `periodic`.
    #[serde(default)]
    pub boundary: Boundary,
    /// `|rho_i'|` on every slider (m/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slider_speed: Option<f64>,
    /// `|rho_i''|` on every slider (m/s^2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slider_acceleration: Option<f64>,
    /// `|rho_i'''|` on every slider (m/s^3), met by smoothing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slider_jerk: Option<f64>,
    /// `|F_a_i|` of the rigid inverse dynamics (N).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slider_force: Option<f64>,
    /// Speed of the platform's reference point (m/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub platform_speed: Option<f64>,
    /// Axial compression of each link at most this fraction of its critical load, (0, 1].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub buckling_margin: Option<f64>,
    /// Largest deflection `|w|` of any link at any time of the planned motion's run on the
    /// scene's flexible model (m): the motion is slowed uniformly until it holds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub deflection_limit: Option<f64>,
    /// With a `motor_ballscrew` actuator: its peak torque and speed limit the motion.
    #[serde(default = "yes")]
    pub motor: bool,
    /// With a motor: its continuous torque limits the RMS torque of the motion.
    #[serde(default = "yes")]
    pub motor_rms: bool,
    /// Rest time added to the move in the RMS average (s).
    #[serde(default)]
    pub dwell: f64,
    /// How the screw efficiency enters the torque.
    #[serde(default)]
    pub efficiency: Efficiency,
    /// Input shaping.
    #[serde(default)]
    pub shaping: Shaping,
    /// EI tolerance `V`.
    #[serde(default = "default_tolerance")]
    pub shaping_tolerance: f64,
    /// Number of the machine's lowest modes to shape for.
    #[serde(default = "default_modes")]
    pub shaping_modes: usize,
    /// Settling window after a rest-to-rest move over which its residual vibration (the
    /// links' peak deflection) is measured (s); `flexprr plan` takes the scene's own time
    /// after its move unless set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub settle_time: Option<f64>,
    /// Grid intervals.
    #[serde(default = "default_grid")]
    pub grid: usize,
    /// Checked points per grid interval.
    #[serde(default = "default_check_factor")]
    pub check_factor: usize,
    /// Refinement rounds before tightening.
    #[serde(default = "default_refinements")]
    pub refinements: usize,
    /// The platform's orientation: `fixed` (the path's), `best_constant` or `free`.
    #[serde(default)]
    pub phi: PhiMode,
    /// Lower bound on the orientation everywhere on the path (deg; -180 unless set).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub phi_min_deg: Option<f64>,
    /// Upper bound (deg; 180 unless set; at most 360 above the lower bound).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub phi_max_deg: Option<f64>,
    /// What the orientation is chosen for: `min_time` or `max_margin`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub phi_objective: Option<PhiGoal>,
    /// A free orientation of a rest-to-rest move: `free` ends or `fixed` (the path's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub phi_ends: Option<PhiEnds>,
    /// Spacing of the scan of constant orientations (deg).
    #[serde(default = "default_scan_step")]
    pub phi_scan_step_deg: f64,
    /// Tolerance of the best constant, and the simplex size of the free search (deg).
    #[serde(default = "default_phi_tolerance")]
    pub phi_tolerance_deg: f64,
    /// Initial step of the free search's coefficients (deg).
    #[serde(default = "default_phi_step")]
    pub phi_step_deg: f64,
    /// Local minima of the scan refined.
    #[serde(default = "default_brackets")]
    pub phi_brackets: usize,
    /// Control values of the free law of a non-periodic motion (cubic B-spline, >= 4).
    #[serde(default = "default_spline_points")]
    pub phi_spline_points: usize,
    /// Harmonics of the free law of a periodic motion (Fourier series, >= 1).
    #[serde(default = "default_harmonics")]
    pub phi_harmonics: usize,
    /// Most objective evaluations of the free search.
    #[serde(default = "default_evaluations")]
    pub phi_evaluations: usize,
    /// Instants sampled for the buckling margin.
    #[serde(default = "default_samples")]
    pub phi_samples: usize,
}

impl Default for PlanSpec {
    fn default() -> Self {
        Self {
            objective: Objective::MinTime,
            boundary: Boundary::RestToRest,
            slider_speed: None,
            slider_acceleration: None,
            slider_jerk: None,
            slider_force: None,
            platform_speed: None,
            buckling_margin: None,
            deflection_limit: None,
            motor: true,
            motor_rms: true,
            dwell: 0.0,
            efficiency: Efficiency::Symmetric,
            shaping: Shaping::None,
            shaping_tolerance: default_tolerance(),
            shaping_modes: default_modes(),
            settle_time: None,
            grid: default_grid(),
            check_factor: default_check_factor(),
            refinements: default_refinements(),
            phi: PhiMode::Fixed,
            phi_min_deg: None,
            phi_max_deg: None,
            phi_objective: None,
            phi_ends: None,
            phi_scan_step_deg: default_scan_step(),
            phi_tolerance_deg: default_phi_tolerance(),
            phi_step_deg: default_phi_step(),
            phi_brackets: default_brackets(),
            phi_spline_points: default_spline_points(),
            phi_harmonics: default_harmonics(),
            phi_evaluations: default_evaluations(),
            phi_samples: default_samples(),
        }
    }
}

fn positive(key: &'static str, value: Option<f64>) -> Result<(), PlanningError> {
    match value {
        Some(v) if !(v.is_finite() && v > 0.0) => Err(PlanningError::InvalidSpec {
            key,
            value: v.to_string(),
            rule: "must be finite and > 0".into(),
        }),
        _ => Ok(()),
    }
}

impl PlanSpec {
    /// Checks every value; the first one out of range is named by its key.
    ///
    /// # Errors
    /// [`PlanningError::InvalidSpec`].
    pub fn validate(&self) -> Result<(), PlanningError> {
        positive("slider_speed", self.slider_speed)?;
        positive("slider_acceleration", self.slider_acceleration)?;
        positive("slider_jerk", self.slider_jerk)?;
        positive("slider_force", self.slider_force)?;
        positive("platform_speed", self.platform_speed)?;
        positive("settle_time", self.settle_time)?;
        positive("deflection_limit", self.deflection_limit)?;
        if let Some(m) = self.buckling_margin
            && !(m.is_finite() && m > 0.0 && m <= 1.0)
        {
            return Err(PlanningError::InvalidSpec {
                key: "buckling_margin",
                value: m.to_string(),
                rule: "must be in (0, 1]: the fraction of each link's critical load".into(),
            });
        }
        if !(self.dwell.is_finite() && self.dwell >= 0.0) {
            return Err(PlanningError::InvalidSpec {
                key: "dwell",
                value: self.dwell.to_string(),
                rule: "must be finite and >= 0 (s)".into(),
            });
        }
        if !(self.shaping_tolerance.is_finite()
            && self.shaping_tolerance > 0.0
            && self.shaping_tolerance < 1.0)
        {
            return Err(PlanningError::InvalidSpec {
                key: "shaping_tolerance",
                value: self.shaping_tolerance.to_string(),
                rule: "must be in (0, 1)".into(),
            });
        }
        if self.shaping_modes == 0 {
            return Err(PlanningError::InvalidSpec {
                key: "shaping_modes",
                value: "0".into(),
                rule: "must be >= 1".into(),
            });
        }
        self.settings().validate()?;
        self.validate_phi()?;
        if self.boundary == Boundary::Periodic && self.shaping != Shaping::None {
            return Err(PlanningError::InvalidSpec {
                key: "shaping",
                value: format!("{:?}", self.shaping).to_lowercase(),
                rule: "shaping applies to rest-to-rest moves (boundary = \"rest_to_rest\")".into(),
            });
        }
        Ok(())
    }

    /// The orientation keys: their ranges, and no key that the chosen `phi` ignores.
    fn validate_phi(&self) -> Result<(), PlanningError> {
        let unused = |key: &'static str, value: String, rule: &str| {
            Err(PlanningError::InvalidSpec {
                key,
                value,
                rule: rule.into(),
            })
        };
        if self.phi == PhiMode::Fixed {
            let ignored =
                "has no effect with phi = \"fixed\" (set phi = \"best_constant\" or \"free\")";
            if let Some(v) = self.phi_min_deg {
                return unused("phi_min_deg", v.to_string(), ignored);
            }
            if let Some(v) = self.phi_max_deg {
                return unused("phi_max_deg", v.to_string(), ignored);
            }
            if let Some(v) = self.phi_objective {
                return unused("phi_objective", goal_name(v).into(), ignored);
            }
            if let Some(v) = self.phi_ends {
                return unused("phi_ends", ends_name(v).into(), ignored);
            }
        }
        if let Some(ends) = self.phi_ends {
            if self.phi == PhiMode::BestConstant {
                return unused(
                    "phi_ends",
                    ends_name(ends).into(),
                    "applies to phi = \"free\" (a constant orientation sets the end orientations too)",
                );
            }
            if self.boundary == Boundary::Periodic {
                return unused(
                    "phi_ends",
                    ends_name(ends).into(),
                    "applies to rest-to-rest motions (a periodic motion has no ends)",
                );
            }
        }
        self.search(PhiObjective::MinTime).validate()
    }

    /// The orientation search of these settings with `objective` (not validated).
    fn search(&self, objective: PhiObjective) -> PhiSearch {
        PhiSearch {
            min: self.phi_min_deg.unwrap_or(-180.0).to_radians(),
            max: self.phi_max_deg.unwrap_or(180.0).to_radians(),
            objective,
            scan_step: self.phi_scan_step_deg.to_radians(),
            tolerance: self.phi_tolerance_deg.to_radians(),
            brackets: self.phi_brackets,
            ends: self.phi_ends.unwrap_or_default(),
            spline_points: self.phi_spline_points,
            harmonics: self.phi_harmonics,
            max_evaluations: self.phi_evaluations,
            step: self.phi_step_deg.to_radians(),
            samples: self.phi_samples,
        }
    }

    /// The orientation search (`None` with `phi = "fixed"`). `scene_timing` is the scene's
    /// own timing of its path, which `phi_objective = "max_margin"` needs.
    ///
    /// # Errors
    /// An invalid value (as [`PlanSpec::validate`]); `max_margin` without a timing.
    pub fn phi_search(
        &self,
        scene_timing: Option<Schedule>,
    ) -> Result<Option<PhiSearch>, PlanningError> {
        self.validate()?;
        if self.phi == PhiMode::Fixed {
            return Ok(None);
        }
        let objective = match (self.phi_objective.unwrap_or_default(), scene_timing) {
            (PhiGoal::MinTime, _) => PhiObjective::MinTime,
            (PhiGoal::MaxMargin, Some(schedule)) => PhiObjective::MaxMargin(schedule),
            (PhiGoal::MaxMargin, None) => {
                return Err(PlanningError::InvalidSpec {
                    key: "phi_objective",
                    value: "max_margin".into(),
                    rule: "needs the scene's own timing of the path (the margin is that motion's)"
                        .into(),
                });
            }
        };
        let search = self.search(objective);
        search.validate()?;
        Ok(Some(search))
    }

    /// The numerical settings.
    pub fn settings(&self) -> Settings {
        Settings {
            grid: self.grid,
            boundary: self.boundary,
            check_factor: self.check_factor,
            refinements: self.refinements,
            convergence: true,
        }
    }

    /// The constraints of this spec on `machine`, with the scene's motor if it has one (its
    /// peak torque and speed when `motor` is set).
    ///
    /// # Errors
    /// An invalid value (as [`PlanSpec::validate`]); no limit at all.
    pub fn constraints(
        &self,
        machine: &Machine,
        motor: Option<&MotorBallScrew>,
    ) -> Result<Vec<Box<dyn Constraint>>, PlanningError> {
        self.validate()?;
        let mut out: Vec<Box<dyn Constraint>> = Vec::new();
        if let Some(v) = self.slider_speed {
            out.push(Box::new(SliderSpeed::new(v)?));
        }
        if let Some(a) = self.slider_acceleration {
            out.push(Box::new(SliderAcceleration::new(a)?));
        }
        if let Some(f) = self.slider_force {
            out.push(Box::new(SliderForce::new(f)?));
        }
        if let Some(v) = self.platform_speed {
            out.push(Box::new(PlatformSpeed::new(v)?));
        }
        if let Some(m) = self.buckling_margin {
            out.push(Box::new(Buckling::new(machine, m)?));
        }
        if let (true, Some(motor)) = (self.motor, motor) {
            out.push(Box::new(MotorTorque::new(*motor, self.efficiency)?));
            out.push(Box::new(MotorSpeed::new(motor)));
            if let Some(voltage) = MotorVoltage::new(*motor, self.efficiency)? {
                out.push(Box::new(voltage));
            }
        }
        if out.is_empty() {
            return Err(PlanningError::InvalidSpec {
                key: "limits",
                value: "none".into(),
                rule: "set at least one of slider_speed, slider_acceleration, slider_force, platform_speed, buckling_margin, or give the scene a motor_ballscrew actuator".into(),
            });
        }
        Ok(out)
    }

    /// The RMS limit with the scene's motor, when `motor` and `motor_rms` are set.
    ///
    /// # Errors
    /// An invalid motor.
    pub fn rms(&self, motor: Option<&MotorBallScrew>) -> Result<Option<RmsLimit>, PlanningError> {
        match (self.motor && self.motor_rms, motor) {
            (true, Some(motor)) => Ok(Some(RmsLimit {
                motor: MotorTorque::new(*motor, self.efficiency)?,
                continuous_torque: motor.ratings.continuous_torque,
                dwell: self.dwell,
            })),
            _ => Ok(None),
        }
    }

    /// The shaper for the machine's lowest `modes` (the first `shaping_modes` of them are
    /// used), or none.
    ///
    /// # Errors
    /// Fewer modes than `shaping_modes`; invalid modes.
    pub fn shaper(
        &self,
        modes: &[Mode],
    ) -> Result<Vec<flexprr_kinematics::Impulse>, PlanningError> {
        let kind = match self.shaping {
            Shaping::None => return Ok(Vec::new()),
            Shaping::Zv => Shaper::Zv,
            Shaping::Zvd => Shaper::Zvd,
            Shaping::Ei => Shaper::Ei(self.shaping_tolerance),
        };
        if modes.len() < self.shaping_modes {
            return Err(PlanningError::InvalidSpec {
                key: "shaping_modes",
                value: self.shaping_modes.to_string(),
                rule: format!("the model gives only {} modes", modes.len()),
            });
        }
        design_for_modes(kind, &modes[..self.shaping_modes])
    }
}
