//! Motion planning for the 3-PRR (docs/planning.md): the fastest motion along a path that the
//! machine can make within its sliders', motors' and links' limits.
//!
//! * [`Sampler`]: the path form of the rigid machine at a path point ([`PathSample`]): slider
//!   derivatives in `s` from the closed-form inverse kinematics, drive forces
//!   `F_a_i = a_i s'' + b_i s'^2` and axial end forces, both from two evaluations of the rigid
//!   inverse dynamics.
//! * [`Constraint`]: a limit as rows linear in `(s'', s'^2)` (plus a `s'` term for viscous
//!   friction): [`SliderSpeed`], [`SliderAcceleration`], [`SliderForce`], [`PlatformSpeed`],
//!   [`MotorTorque`], [`MotorSpeed`], [`Buckling`]; a user's own by implementing the trait.
//! * [`Planner`]: time-optimal path parameterization by reachability analysis (TOPP-RA,
//!   Pham & Pham 2018), written here, with the limits checked between grid points, grid
//!   convergence, an RMS torque limit, a jerk limit by smoothing and input shaping; and
//!   phase-plane integration ([`Planner::phase_plane`]: Bobrow et al. 1985, Shin & McKay
//!   1985) as an independent second method; the largest frequency of a closed path at
//!   constant speed ([`Planner::constant_speed`]).
//! * [`shaping`]: ZV, ZVD and EI shapers (Singer & Seering 1990; Singhose et al.), for one or
//!   several modes, and their residual vibration.
//! * The platform's orientation as a design variable ([`Planner::best_constant_phi`],
//!   [`Planner::free_phi`]): the best constant `phi`, or `phi(s)` a smooth law, for the
//!   shortest motion or the largest buckling margin ([`Planner::compression`]) at a given
//!   timing ([`Schedule`]).
//! * [`PlanSpec`]: the `[plan]` settings as data (serde), validated by key.
//!
//! The result is a [`Plan`] whose timing, with the path, is a
//! [`flexprr_kinematics::PlannedTrajectory`].

mod check;
mod constraint;
mod error;
mod optimize;
mod orientation;
mod phase;
mod plan;
mod sample;
pub mod shaping;
mod spec;
mod speed;
mod topp;

pub use check::{Check, Usage};
pub use constraint::{
    Buckling, Constraint, Efficiency, MotorSpeed, MotorTorque, MotorVoltage, PlatformSpeed, Row,
    SliderAcceleration, SliderForce, SliderSpeed,
};
pub use error::{Infeasibility, PlanningError, Where};
pub use orientation::{
    Compression, ConstantPhi, FreePhi, PhiEnds, PhiObjective, PhiSearch, ScanPoint, Schedule,
};
pub use phase::PhasePlane;
pub use plan::{
    Binding, Boundary, CHECK_TOLERANCE, Convergence, Plan, Planner, RmsLimit, Settings, Solution,
};
pub use sample::{Affine, LegPath, PathSample, Sampler};
pub use spec::{PhiGoal, PhiMode, PlanSpec, Shaping};
pub use speed::ConstantSpeed;
