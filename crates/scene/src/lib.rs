//! Scene files of flexprr: the TOML schema (`docs/scenes.md`), validation with errors that
//! give the file, line, column and key, the [`Registry`] of named parts (integrators, bases,
//! axial force models, control laws) and the built [`Scene`] that runs, studies and
//! benchmarks all start from.
//!
//! ```no_run
//! use flexprr_scene::Scene;
//! let scene = Scene::load(std::path::Path::new("configs/paper_f20.toml")).unwrap();
//! assert_eq!(scene.name, "paper_f20");
//! ```

mod actuators;
mod callback_law;
mod control;
mod controllers;
mod error;
mod input;
pub mod link;
pub mod link_file;
mod locate;
mod model;
mod model_kind;
mod npz;
mod parse;
mod piezo;
mod plan;
mod registry;
mod scene;
mod schema;
pub mod setting;
mod statespace_law;

pub use flexprr_integrators::DynIntegrator;

pub use actuators::ActuatorFactory;
pub use callback_law::{CallbackLawFactory, PYTHON_LAW_NEEDS_PYTHON};
pub use controllers::{ControllerFactory, VibrationControllerFactory};
pub use error::{Location, ScenarioError};
pub use input::{
    InputKind, MAX_DATA_BYTES, MAX_INPUT_BYTES, MAX_NAME_LEN, check_input_file, read_input_file,
    sanitize_name, unsafe_name_reason,
};
pub use locate::{line_column, locate, locate_value};
pub use model::{CoupledKind, KedKind, NonlinearKind};
pub use model_kind::{ModelCapabilities, ModelKind, ModelKindHandle};
pub use parse::{parse_scene, parse_toml};
pub use piezo::PatchContext;
pub use plan::{motor_of, path_of};
pub use registry::{
    BasisFactory, BasisParams, IntegratorConstructor, MethodHandle, MethodKind, ModeCount,
    Registry, TableParams, mechanical_model,
};
pub use scene::{
    CustomOutput, DEFAULT_COLLAPSE_DEFLECTION, DEFAULT_ELEMENTS, LargeDeflection, MAX_ANGLE_DEG,
    Scene,
};
pub use schema::{
    ActuatorsTable, BasisTable, BranchChoice, ControlTable, DEFAULT_COULOMB_SMOOTHING,
    FormulationChoice, IntegratorConfig, Layout, LegConfig, LinksConfig, MachineConfig,
    ModelConfig, OutputConfig, OutputKind, ProfileChoice, SceneFile, StiffnessChoice, TimeConfig,
    TrajectoryConfig,
};
