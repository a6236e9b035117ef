//! The linear-model tools of flexprr (docs/linear.md): a scene's model at an operating
//! point ([`linear`]), its whole-machine modes ([`machine_modes`]), frequency responses
//! ([`frf`], sweeps planned by [`frf_plan`]), the modal-test identification of modes from
//! responses ([`modal_test`]) and the state-space export ([`statespace`], written as NumPy
//! archives by [`npz`]). The linearisation itself is `flexprr-linear`'s; the integration to
//! an operating point along the motion is the run's (`flexprr_run::integrate_model`).
//!
//! ```no_run
//! use flexprr_linear_tools::linear::OperatingPoint;
//! use flexprr_linear_tools::machine_modes::{SHAPE_POINTS, machine_modes};
//! use flexprr_scene::Scene;
//! let scene = Scene::load(std::path::Path::new("configs/paper_f20.toml")).unwrap();
//! let at = OperatingPoint::Time(0.01);
//! let modes = machine_modes(&scene, at, SHAPE_POINTS, &Default::default()).unwrap();
//! println!("{} modes at t = {} s", modes.modes.len(), modes.t);
//! ```

pub mod frf;
pub mod frf_plan;
pub mod linear;
pub mod machine_modes;
pub mod margins;
pub mod modal_test;
pub mod npz;
pub mod statespace;
