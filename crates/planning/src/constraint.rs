//! Constraints in path form (docs/planning.md, "Constraints"): each limit is a set of rows
//!
//! ```text
//! lower <= a u + b x + c sqrt(x) + d <= upper        u = s'',  x = s'^2 >= 0
//! ```
//!
//! per path point. Without the `sqrt(x)` term a row is a pair of half-planes in `(u, x)`,
//! the structure time-optimal path parameterization needs (Pham & Pham 2018). The
//! `sqrt(x) = s'` term is a viscous friction (a force proportional to a speed); the planner
//! replaces it by a line that never underestimates its effect (see [`crate::topp`]), and the
//! dense check evaluates it exactly. A row with only the `sqrt(x)` term is a speed limit and
//! is handled exactly.

use flexprr_beam::{AxialLoad, Coupling, frequencies};
use flexprr_control::{Actuator, MotorBallScrew};
use flexprr_dynamics::Machine;

use crate::error::PlanningError;
use crate::sample::PathSample;

/// One row of a constraint at one path point (module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row {
    /// Coefficient `a` of `u = s''`.
    pub u: f64,
    /// Coefficient `b` of `x = s'^2`.
    pub x: f64,
    /// Coefficient `c` of `sqrt(x) = s'`.
    pub sqrt_x: f64,
    /// Constant `d` (the value at rest).
    pub offset: f64,
    /// Lower limit (`<= 0`, may be `-inf`).
    pub lower: f64,
    /// Upper limit (`>= 0`, may be `+inf`).
    pub upper: f64,
}

impl Default for Row {
    /// An inactive row (no bounds).
    fn default() -> Self {
        Self::INACTIVE
    }
}

impl Row {
    /// A row that never binds.
    pub const INACTIVE: Row = Row {
        u: 0.0,
        x: 0.0,
        sqrt_x: 0.0,
        offset: 0.0,
        lower: f64::NEG_INFINITY,
        upper: f64::INFINITY,
    };

    /// `|a u + b x + d| <= limit`.
    pub fn symmetric(u: f64, x: f64, offset: f64, limit: f64) -> Self {
        Self {
            u,
            x,
            sqrt_x: 0.0,
            offset,
            lower: -limit,
            upper: limit,
        }
    }

    /// The value `a u + b x + c sqrt(x) + d` of the row for the path acceleration `u` and
    /// the path speed `s_dot` (`x = s_dot^2`).
    #[inline]
    pub fn value(&self, u: f64, s_dot: f64) -> f64 {
        self.u * u + self.x * s_dot * s_dot + self.sqrt_x * s_dot + self.offset
    }

    /// How much of the limit a value uses: `value / upper` above zero, `value / lower` below
    /// (1 = at the limit, > 1 = beyond it; 0 for an unbounded side).
    #[inline]
    pub fn usage(&self, value: f64) -> f64 {
        if value >= 0.0 {
            if self.upper.is_finite() && self.upper > 0.0 {
                value / self.upper
            } else if self.upper.is_finite() {
                // A limit at zero: any positive value breaks it.
                if value > 0.0 { f64::INFINITY } else { 0.0 }
            } else {
                0.0
            }
        } else if self.lower.is_finite() && self.lower < 0.0 {
            value / self.lower
        } else if self.lower.is_finite() {
            f64::INFINITY
        } else {
            0.0
        }
    }

    /// Whether the row is active at all.
    pub fn is_active(&self) -> bool {
        self.lower.is_finite() || self.upper.is_finite()
    }

    /// The row with both limits multiplied by `factor` (tightening for `factor < 1`).
    #[inline]
    pub fn scaled(&self, factor: f64) -> Self {
        Self {
            lower: self.lower * factor,
            upper: self.upper * factor,
            ..*self
        }
    }
}

/// The interval `[u_min, u_max]` of path accelerations that meet every row at the squared
/// path speed `x` (exact, `sqrt(x)` terms included), or `None` if a row without `u` fails
/// at `x` or the interval is empty.
pub(crate) fn u_interval(rows: impl Iterator<Item = Row>, x: f64) -> Option<(f64, f64)> {
    let v = x.max(0.0).sqrt();
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for row in rows {
        if !row.is_active() {
            continue;
        }
        let rest = row.x * x + row.sqrt_x * v + row.offset;
        let (a, b) = (row.lower - rest, row.upper - rest);
        if row.u > 0.0 {
            lo = lo.max(a / row.u);
            hi = hi.min(b / row.u);
        } else if row.u < 0.0 {
            lo = lo.max(b / row.u);
            hi = hi.min(a / row.u);
        } else if a > 1e-12 * row.lower.abs() || b < -1e-12 * row.upper.abs() {
            return None;
        }
    }
    (lo <= hi).then_some((lo, hi))
}

/// The maximum velocity curve at one point: the largest `x` for which some `u` meets every
/// row (doubling, then bisection to full precision). `-1` if the rows fail at rest, infinite
/// if nothing bounds `x`.
pub(crate) fn maximum_speed(rows: impl Iterator<Item = Row> + Clone) -> f64 {
    if u_interval(rows.clone(), 0.0).is_none() {
        return -1.0;
    }
    let mut hi = 1e-12;
    while u_interval(rows.clone(), hi).is_some() {
        hi *= 4.0;
        if hi > 1e30 {
            return f64::INFINITY;
        }
    }
    let mut lo = 0.0;
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if u_interval(rows.clone(), mid).is_some() {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// A limit on the motion along a path, as [`Row`]s at each path point.
///
/// Required: a name (for "the constraint that binds"), the unit of its values, the number of
/// rows it writes per point and their labels, and the rows. The planner scales the limits
/// (both bounds of every row) to tighten a constraint; a row's limits must therefore bracket
/// zero (`lower <= 0 <= upper`), which every physical limit does.
///
/// # Implementing
/// A limit on the speed of the platform's reference point along a straight line, as a custom
/// constraint: `|p'_xy| s' <= v_max`, one row with only the `sqrt(x) = s'` term (handled
/// exactly by the planner). On a straight segment the fastest rest-to-rest motion under a
/// speed limit alone would be infinitely quick to accelerate, so the example adds a path
/// acceleration limit `|s''| <= a_max` too; the minimum time is then the trapezoid's
/// `L / v + v / a`:
///
/// ```
/// use flexprr_kinematics::{Pose, SegmentPath};
/// use flexprr_planning::{Boundary, Constraint, PathSample, Planner, Row, Settings};
///
/// #[derive(Debug)]
/// struct ReferencePointSpeed(f64);
///
/// impl Constraint for ReferencePointSpeed {
///     fn name(&self) -> &str {
///         "reference_point_speed"
///     }
///     fn unit(&self) -> &str {
///         "m/s"
///     }
///     fn count(&self) -> usize {
///         1
///     }
///     fn label(&self, _row: usize) -> String {
///         "platform".into()
///     }
///     fn rows(&self, sample: &PathSample, rows: &mut [Row]) {
///         let d1 = sample.point.d1;
///         rows[0] = Row { sqrt_x: d1.x.hypot(d1.y), upper: self.0, ..Row::INACTIVE };
///     }
/// }
///
/// #[derive(Debug)]
/// struct PathAcceleration(f64);
///
/// impl Constraint for PathAcceleration {
///     fn name(&self) -> &str {
///         "path_acceleration"
///     }
///     fn unit(&self) -> &str {
///         "m/s^2"
///     }
///     fn count(&self) -> usize {
///         1
///     }
///     fn label(&self, _row: usize) -> String {
///         "s''".into()
///     }
///     fn rows(&self, _sample: &PathSample, rows: &mut [Row]) {
///         rows[0] = Row::symmetric(1.0, 0.0, 0.0, self.0);
///     }
/// }
///
/// let machine = flexprr_dynamics::paper::machine(1, flexprr_dynamics::paper::YOUNGS_MODULUS)
///     .unwrap();
/// let path = SegmentPath::new(Pose::new(-0.08, -0.03, 0.5), Pose::new(-0.02, 0.033, 0.5))
///     .unwrap();
/// let (v, a) = (0.5, 20.0);
/// let planner = Planner::new(&machine, &path, Settings::default())
///     .constraint(ReferencePointSpeed(v))
///     .constraint(PathAcceleration(a));
/// let plan = planner.plan().unwrap();
/// let exact = path_length(&path) / v + v / a;
/// assert!((plan.duration - exact).abs() <= 2e-3 * exact, "{} vs {exact}", plan.duration);
/// assert!(plan.check.max_usage <= 1.0 + 1e-9);
/// # fn path_length(p: &SegmentPath) -> f64 { flexprr_kinematics::Path::length(p) }
/// # let _ = Boundary::RestToRest;
/// ```
pub trait Constraint: std::fmt::Debug + Send + Sync {
    /// The constraint's name (`slider_speed`, `motor_torque`, ...).
    fn name(&self) -> &str;
    /// Unit of the rows' values (`m/s`, `N`, `N m`).
    fn unit(&self) -> &str;
    /// Number of rows written per path point (fixed).
    fn count(&self) -> usize;
    /// Label of row `row` (`leg 2`, `link 1 at B`).
    fn label(&self, row: usize) -> String;
    /// Writes the `count()` rows at `sample` into `rows` (inactive rows: [`Row::INACTIVE`]).
    /// Must not allocate.
    fn rows(&self, sample: &PathSample, rows: &mut [Row]);
}

fn leg_label(row: usize) -> String {
    format!("leg {}", row % 3 + 1)
}

fn check_limit(key: &'static str, value: f64) -> Result<f64, PlanningError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(PlanningError::InvalidSpec {
            key,
            value: format!("{value}"),
            rule: "must be finite and > 0".into(),
        })
    }
}

/// `|rho_i'| <= v_max` on every slider (m/s): `|rho_i'(s)| sqrt(x) <= v_max`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SliderSpeed {
    limit: f64,
}

impl SliderSpeed {
    /// The limit `v_max > 0` (m/s).
    ///
    /// # Errors
    /// [`PlanningError::InvalidSpec`] on the key `slider_speed`.
    pub fn new(limit: f64) -> Result<Self, PlanningError> {
        Ok(Self {
            limit: check_limit("slider_speed", limit)?,
        })
    }
}

impl Constraint for SliderSpeed {
    fn name(&self) -> &str {
        "slider_speed"
    }
    fn unit(&self) -> &str {
        "m/s"
    }
    fn count(&self) -> usize {
        3
    }
    fn label(&self, row: usize) -> String {
        leg_label(row)
    }
    fn rows(&self, sample: &PathSample, rows: &mut [Row]) {
        for (row, leg) in rows.iter_mut().zip(&sample.legs) {
            *row = Row {
                sqrt_x: leg.d1.abs(),
                lower: f64::NEG_INFINITY,
                upper: self.limit,
                ..Row::INACTIVE
            };
        }
    }
}

/// `|rho_i''| <= a_max` on every slider (m/s^2): `|rho_i' u + rho_i'' x| <= a_max`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SliderAcceleration {
    limit: f64,
}

impl SliderAcceleration {
    /// The limit `a_max > 0` (m/s^2).
    ///
    /// # Errors
    /// [`PlanningError::InvalidSpec`] on the key `slider_acceleration`.
    pub fn new(limit: f64) -> Result<Self, PlanningError> {
        Ok(Self {
            limit: check_limit("slider_acceleration", limit)?,
        })
    }
}

impl Constraint for SliderAcceleration {
    fn name(&self) -> &str {
        "slider_acceleration"
    }
    fn unit(&self) -> &str {
        "m/s^2"
    }
    fn count(&self) -> usize {
        3
    }
    fn label(&self, row: usize) -> String {
        leg_label(row)
    }
    fn rows(&self, sample: &PathSample, rows: &mut [Row]) {
        for (row, leg) in rows.iter_mut().zip(&sample.legs) {
            *row = Row::symmetric(leg.d1, leg.d2, 0.0, self.limit);
        }
    }
}

/// `|F_a_i| <= F_max` on every slider (N), the rigid drive force (the `driving_forces`
/// output `F_a_i_rigid_N`): `|a_i u + b_i x| <= F_max`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SliderForce {
    limit: f64,
}

impl SliderForce {
    /// The limit `F_max > 0` (N).
    ///
    /// # Errors
    /// [`PlanningError::InvalidSpec`] on the key `slider_force`.
    pub fn new(limit: f64) -> Result<Self, PlanningError> {
        Ok(Self {
            limit: check_limit("slider_force", limit)?,
        })
    }
}

impl Constraint for SliderForce {
    fn name(&self) -> &str {
        "slider_force"
    }
    fn unit(&self) -> &str {
        "N"
    }
    fn count(&self) -> usize {
        3
    }
    fn label(&self, row: usize) -> String {
        leg_label(row)
    }
    fn rows(&self, sample: &PathSample, rows: &mut [Row]) {
        for (row, f) in rows.iter_mut().zip(&sample.drive) {
            *row = Row::symmetric(f.u, f.x, f.constant, self.limit);
        }
    }
}

/// `|v_p| <= v_max`: the speed of the platform's reference point (m/s),
/// `|p'_xy(s)| sqrt(x) <= v_max`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlatformSpeed {
    limit: f64,
}

impl PlatformSpeed {
    /// The limit `v_max > 0` (m/s).
    ///
    /// # Errors
    /// [`PlanningError::InvalidSpec`] on the key `platform_speed`.
    pub fn new(limit: f64) -> Result<Self, PlanningError> {
        Ok(Self {
            limit: check_limit("platform_speed", limit)?,
        })
    }
}

impl Constraint for PlatformSpeed {
    fn name(&self) -> &str {
        "platform_speed"
    }
    fn unit(&self) -> &str {
        "m/s"
    }
    fn count(&self) -> usize {
        1
    }
    fn label(&self, _row: usize) -> String {
        "platform".into()
    }
    fn rows(&self, sample: &PathSample, rows: &mut [Row]) {
        let d1 = sample.point.d1;
        rows[0] = Row {
            sqrt_x: d1.x.hypot(d1.y),
            upper: self.limit,
            ..Row::INACTIVE
        };
    }
}

/// How the screw's efficiency enters the motor torque.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Efficiency {
    /// `tau = F / (g eta) + friction` in both directions of the power flow: the model of
    /// [`MotorBallScrew`] (`Actuator::required`), which a run's feasibility check uses.
    #[default]
    Symmetric,
    /// `F / (g eta)` while the motor drives (`F v > 0`), `F eta / g` while the load drives it
    /// back (docs/planning.md): piecewise affine in `F`, less torque when braking.
    PowerFlow,
}

/// The motor's peak torque through its ball screw (N m), per slider
/// (docs/planning.md, "Motor"):
///
/// ```text
/// F     = F_a_i + m_r rho_i''                  force on the slider, reflected rotor inertia m_r
/// tau   = F / (g eta) + b g rho_i' + tau_C sign(rho_i')      (g = 2 pi / lead)
/// |tau| <= scale * tau_max                     tau_max: the peak torque, or K_t I_max if lower
/// ```
///
/// The viscous term `b g rho_i'(s) sqrt(x)` is the `sqrt(x)` term of a row; Coulomb friction
/// is the sign term `tau_C sign(rho_i'(s))` (the full torque at any speed, never less than the
/// actuator's smoothed `tanh`); where `rho_i'(s) = 0` the sign is unknown and both signs are
/// imposed. With [`Efficiency::PowerFlow`] the torque is `max(F/(g eta), F eta/g) + friction`
/// for `rho_i' > 0` (`min` for `rho_i' < 0`): the two branches give one two-sided and one
/// one-sided row (a monotone piecewise-linear map of `F`, so the feasible set stays convex).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotorTorque {
    motor: MotorBallScrew,
    efficiency: Efficiency,
    scale: f64,
}

impl MotorTorque {
    /// The peak-torque limit of `motor` (its `ratings.peak_torque`).
    ///
    /// # Errors
    /// The motor's own validation.
    pub fn new(motor: MotorBallScrew, efficiency: Efficiency) -> Result<Self, PlanningError> {
        let motor = motor.validated().map_err(|e| PlanningError::InvalidSpec {
            key: "motor",
            value: format!("{e}"),
            rule: "the actuator's parameters must be valid".into(),
        })?;
        Ok(Self {
            motor,
            efficiency,
            scale: 1.0,
        })
    }

    /// The same limit at `scale * tau_peak` (the RMS iteration lowers the peak torque).
    pub fn scaled(mut self, scale: f64) -> Self {
        self.scale = scale;
        self
    }

    /// The motor.
    pub fn motor(&self) -> &MotorBallScrew {
        &self.motor
    }

    /// The motor torque (N m) of leg `i` at the path state `(s', s'')`, by the same model as
    /// the rows, with the exact sign of the velocity (`0` at rest: Coulomb friction is then
    /// whatever holds the load, taken as zero).
    pub fn torque(&self, sample: &PathSample, leg: usize, s_dot: f64, s_ddot: f64) -> f64 {
        let m = &self.motor;
        let g = m.ratio();
        let eta = m.efficiency;
        let l = &sample.legs[leg];
        let force = sample.drive[leg].at(s_ddot, s_dot * s_dot)
            + m.reflected_mass() * l.acceleration(s_dot, s_ddot);
        let v = l.velocity(s_dot);
        let friction = m.viscous_friction * g * v + m.coulomb_friction * sign(v);
        let load = match self.efficiency {
            Efficiency::Symmetric => force / (g * eta),
            Efficiency::PowerFlow => {
                if force * v >= 0.0 {
                    force / (g * eta)
                } else {
                    force * eta / g
                }
            }
        };
        load + friction
    }
}

fn sign(v: f64) -> f64 {
    if v > 0.0 {
        1.0
    } else if v < 0.0 {
        -1.0
    } else {
        0.0
    }
}

impl Constraint for MotorTorque {
    fn name(&self) -> &str {
        "motor_torque"
    }
    fn unit(&self) -> &str {
        "N m"
    }
    fn count(&self) -> usize {
        6
    }
    fn label(&self, row: usize) -> String {
        leg_label(row)
    }
    fn rows(&self, sample: &PathSample, rows: &mut [Row]) {
        let m = &self.motor;
        let g = m.ratio();
        let eta = m.efficiency;
        let peak = self.scale * m.torque_limit();
        let reflected = m.reflected_mass();
        for i in 0..3 {
            let l = &sample.legs[i];
            let f = &sample.drive[i];
            // Force on the slider, affine in (u, x).
            let (fu, fx, f0) = (f.u + reflected * l.d1, f.x + reflected * l.d2, f.constant);
            let sigma = sign(l.d1);
            let at_rest = l.d1.abs() <= 0.0;
            let viscous = m.viscous_friction * g * l.d1;
            let coulomb = m.coulomb_friction;
            let (first, second) = (i, i + 3);
            let driving = 1.0 / (g * eta);
            if at_rest {
                // No velocity at this point: the Coulomb torque may have either sign.
                rows[first] = Row {
                    u: fu * driving,
                    x: fx * driving,
                    sqrt_x: 0.0,
                    offset: f0 * driving + coulomb,
                    lower: f64::NEG_INFINITY,
                    upper: peak,
                };
                rows[second] = Row {
                    offset: f0 * driving - coulomb,
                    lower: -peak,
                    upper: f64::INFINITY,
                    ..rows[first]
                };
                continue;
            }
            let row = |k: f64, lower: f64, upper: f64| Row {
                u: fu * k,
                x: fx * k,
                sqrt_x: viscous,
                offset: f0 * k + sigma * coulomb,
                lower,
                upper,
            };
            match self.efficiency {
                Efficiency::Symmetric => {
                    rows[first] = row(driving, -peak, peak);
                    rows[second] = Row::INACTIVE;
                }
                Efficiency::PowerFlow => {
                    let driven = eta / g;
                    rows[first] = row(driven, -peak, peak);
                    rows[second] = if sigma > 0.0 {
                        row(driving, f64::NEG_INFINITY, peak)
                    } else {
                        row(driving, -peak, f64::INFINITY)
                    };
                }
            }
        }
    }
}

/// The drive's bus voltage on each leg's motor (docs/planning.md, "Motor"): the winding
/// voltage of the steady-state drive ([`flexprr_control::Drive`]) within the bus voltage,
///
/// ```text
/// -V_bus <= R tau / K_t + K_e g rho_i'(s) sqrt(x) <= V_bus
/// ```
///
/// with `tau` the motor torque of [`MotorTorque`] (the same rows, so the same friction and
/// efficiency branches: the voltage is increasing in the torque) and the back-EMF a `sqrt(x)`
/// term. With the torque limit this is the motor's torque-speed envelope: the peak torque
/// up to the corner speed, then a torque falling to zero at the no-load speed `V_bus / K_e`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotorVoltage {
    torque: MotorTorque,
    drive: flexprr_control::Drive,
}

impl MotorVoltage {
    /// The voltage limit of `motor`'s drive; `None` for a motor without a drive.
    ///
    /// # Errors
    /// The motor's own validation.
    pub fn new(
        motor: MotorBallScrew,
        efficiency: Efficiency,
    ) -> Result<Option<Self>, PlanningError> {
        let torque = MotorTorque::new(motor, efficiency)?;
        Ok(motor.drive.map(|drive| Self { torque, drive }))
    }
}

impl Constraint for MotorVoltage {
    fn name(&self) -> &str {
        "motor_voltage"
    }
    fn unit(&self) -> &str {
        "V"
    }
    fn count(&self) -> usize {
        6
    }
    fn label(&self, row: usize) -> String {
        leg_label(row)
    }
    fn rows(&self, sample: &PathSample, rows: &mut [Row]) {
        self.torque.rows(sample, rows);
        let d = &self.drive;
        let r = d.resistance / d.torque_constant;
        let emf = d.torque_constant * self.torque.motor.ratio();
        let bus = d.bus_voltage;
        for (k, row) in rows.iter_mut().enumerate() {
            if row.lower == f64::NEG_INFINITY && row.upper == f64::INFINITY {
                continue;
            }
            *row = Row {
                u: r * row.u,
                x: r * row.x,
                sqrt_x: r * row.sqrt_x + emf * sample.legs[k % 3].d1,
                offset: r * row.offset,
                lower: if row.lower.is_finite() {
                    -bus
                } else {
                    f64::NEG_INFINITY
                },
                upper: if row.upper.is_finite() {
                    bus
                } else {
                    f64::INFINITY
                },
            };
        }
    }
}

/// The motor's speed limit as a slider speed, `|rho_i'| <= n_max lead` (rev/s times m/rev).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotorSpeed {
    max_speed: f64,
    lead: f64,
}

impl MotorSpeed {
    /// The speed limit of `motor` (`ratings.max_speed`, rev/s).
    pub fn new(motor: &MotorBallScrew) -> Self {
        Self {
            max_speed: motor.ratings.max_speed,
            lead: motor.lead,
        }
    }
}

impl Constraint for MotorSpeed {
    fn name(&self) -> &str {
        "motor_speed"
    }
    fn unit(&self) -> &str {
        "rev/s"
    }
    fn count(&self) -> usize {
        3
    }
    fn label(&self, row: usize) -> String {
        leg_label(row)
    }
    fn rows(&self, sample: &PathSample, rows: &mut [Row]) {
        for (row, leg) in rows.iter_mut().zip(&sample.legs) {
            *row = Row {
                sqrt_x: leg.d1.abs() / self.lead,
                upper: self.max_speed,
                ..Row::INACTIVE
            };
        }
    }
}

/// A buckling margin on each link: the axial compression at both ends at most `margin`
/// times the link's critical load `P_cr` (N), `-P_i(end) <= margin P_cr,i`
/// (docs/planning.md, "Buckling").
///
/// `P_cr` is the uniform compression at which the link's own modal model (its basis and
/// section, pinned-pinned) loses stiffness (the buckling eigenproblem of the beam layer;
/// `pi^2 EI / l^2` for a uniform link). The axial force of the rigid motion, from the
/// sampler's axial-force model (the joint-reaction model by default), is
/// `P(xi) = P0 + P1 xi + P2 xi^2` with `P2 = -rhoA beta'^2 / 2 <= 0`: concave along the link,
/// so its largest compression is at an end, and bounding both ends bounds it everywhere.
/// A compression at most `C` everywhere makes the geometric stiffness no softer than that of
/// the uniform compression `C` (the geometric stiffness is monotone in the force), so the
/// link's lowest stiffness stays at least that under `margin * P_cr < P_cr`: the link does
/// not buckle, and its first frequency stays above about `sqrt(1 - margin)` of its value at
/// rest.
#[derive(Debug, Clone, PartialEq)]
pub struct Buckling {
    margin: f64,
    critical: [f64; 3],
}

impl Buckling {
    /// The margin `0 < margin <= 1` on the links of `machine`.
    ///
    /// # Errors
    /// [`PlanningError::InvalidSpec`] on the key `buckling_margin`; a link with no critical
    /// load (its model does not buckle under compression).
    pub fn new(machine: &Machine, margin: f64) -> Result<Self, PlanningError> {
        if !(margin.is_finite() && margin > 0.0 && margin <= 1.0) {
            return Err(PlanningError::InvalidSpec {
                key: "buckling_margin",
                value: format!("{margin}"),
                rule: "must be in (0, 1]: the fraction of each link's critical load".into(),
            });
        }
        let mut critical = [0.0; 3];
        for (i, link) in machine.links.iter().enumerate() {
            let unit = frequencies(&link.integrals, &AxialLoad::uniform(-1.0), Coupling::Full)
                .map_err(|e| PlanningError::AxialModel(format!("link {}: {e}", i + 1)))?;
            critical[i] = unit.critical_load_factor.ok_or_else(|| {
                PlanningError::AxialModel(format!(
                    "link {} has no critical load: its model does not buckle under compression",
                    i + 1
                ))
            })?;
        }
        Ok(Self { margin, critical })
    }

    /// The critical (Euler) load of each link (N).
    pub fn critical_loads(&self) -> [f64; 3] {
        self.critical
    }
}

impl Constraint for Buckling {
    fn name(&self) -> &str {
        "buckling"
    }
    fn unit(&self) -> &str {
        "N"
    }
    fn count(&self) -> usize {
        6
    }
    fn label(&self, row: usize) -> String {
        format!(
            "link {} at {}",
            row / 2 + 1,
            if row % 2 == 0 { "B" } else { "C" }
        )
    }
    fn rows(&self, sample: &PathSample, rows: &mut [Row]) {
        for i in 0..3 {
            for end in 0..2 {
                let p = &sample.axial[i][end];
                rows[2 * i + end] = Row {
                    u: p.u,
                    x: p.x,
                    sqrt_x: 0.0,
                    offset: p.constant,
                    lower: -self.margin * self.critical[i],
                    upper: f64::INFINITY,
                };
            }
        }
    }
}
