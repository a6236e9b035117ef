//! Dynamics of a 3-PRR with flexible links under prescribed rigid motion
//! (kineto-elasto-dynamics, the paper's sections 3-4 and model.md sections 4-7).
//!
//! * [`inverse_dynamics`]: rigid-body joint reactions and driving forces (model.md section 4).
//! * [`AxialForceModel`]: the axial force `P(x)` in each link: none, the paper's eq. (12), or
//!   the joint-reaction form (model.md section 5).
//! * [`ModalSystem`]: the modal equations of the three links (eq. 16 or the consistent form
//!   of model.md section 6) as an [`flexprr_integrators::OdeSystem`] with an analytic Jacobian.
//! * [`FrequencyTracker`]: configuration-dependent frequencies (eq. 22 or the generalized
//!   eigenproblem), buckling detection.
//! * [`nonlinear`]: geometrically exact links (co-rotational beam elements) and the fully
//!   nonlinear 3-PRR [`NonlinearSystem`], for large deflection and collapse.
//! * [`Formulation`]: the named formulations `paper` and `consistent` and their switches.

mod actuation;
mod axial;
pub mod channel;
mod column;
mod coupled;
mod error;
mod formulation;
mod frequencies;
mod hold;
mod inverse;
pub mod linear;
mod machine;
mod modal;
mod model;
pub mod nonlinear;
pub mod paper;
mod patches;

pub use actuation::Actuation;
pub use axial::{
    AxialForceModel, AxialInput, JointReactionAxialForce, NoAxialForce, PaperAxialForce, end_forces,
};
pub use column::{Column, NamedQuantity, Quantity, Table};
pub use coupled::{CoupledCounters, CoupledOptions, CoupledOutput, CoupledSystem, CouplingModel};
pub use error::{Capability, DynamicsError};
pub use formulation::{AxialModel, Formulation};
pub use frequencies::{BucklingInterval, FrequencyHistory, FrequencyTracker, ModeRange};
pub use inverse::{
    ElasticInertia, JointReactions, equilibrium_measure, inverse_dynamics, inverse_dynamics_full,
    rigid_kinetic_energy,
};
pub use machine::{LinkModel, Machine};
pub use modal::{Counters, Instant, ModalDamping, ModalSystem};
pub use model::{
    AXIAL_MODES, ActuatorState, ChordCompliance, ControlLaws, ExternalLoads, LawSample,
    LinearHints, LoadInput, MachineSnapshot, ModelCounters, ModelEnergies,
    NONLINEAR_ADVICE_FRACTION, PatchReadout, PointForce, SampledLaws, SceneModel, SliderMotion,
    force_table, platform_deviation_table,
};
pub use nonlinear::{NonlinearOptions, NonlinearOutput, NonlinearSystem};
pub use patches::{Patch, PatchControl, PatchError, PatchState, modal_velocity_law};

pub use flexprr_beam::{AxialLoad, Coupling};
