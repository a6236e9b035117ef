//! Registers a new model kind from outside the crates and runs a scene that selects it with
//! `model.coupling`.
//!
//! The kind, `ked-general`, builds the KED modal equations of the paper (eq. 21: rigid motion
//! prescribed, links in assumed modes) but declares itself not linear in its state: a model
//! kind is asked what it can do, never which kind it is. The scene layer follows the
//! capabilities, so `integrator.method = "auto"` resolves to `abm` for it (and to `magnus6`
//! for the built-in `ked`), and `magnus6` named explicitly is refused at load. The two runs
//! integrate the same equations with two independent methods (a Magnus exponential
//! integrator and an Adams multistep code, both at rtol 1e-10), so their mid-point
//! deflections must agree far below the deflection itself.
//!
//! Run: `cargo run --release --example custom_model`

mod common;

use std::sync::Arc;

use flexprr_dynamics::{DynamicsError, SceneModel};
use flexprr_scene::{ModelCapabilities, ModelKind, Registry, Scene};

/// The KED equations under a kind that does not promise a linear form.
struct GeneralKed;

impl ModelKind for GeneralKed {
    fn capabilities(&self) -> ModelCapabilities {
        ModelCapabilities {
            assumed_modes: true,
            ..ModelCapabilities::default()
        }
    }

    fn build(&self, scene: &Scene) -> Result<Box<dyn SceneModel>, DynamicsError> {
        Ok(Box::new(scene.build_ked(false)?))
    }

    fn describe(&self, name: &str, scene: &Scene, sliders: &str) -> String {
        format!(
            "{name} model{sliders}: the KED equations, {} modes per link, integrated as a general ODE",
            scene.machine.links[0].modes()
        )
    }
}

/// The paper's scene with the model kind `coupling` and the method `method`.
fn scene_text(coupling: &str, method: &str) -> String {
    common::paper_scene_text(
        &format!("custom_model_{coupling}_{method}"),
        coupling,
        method,
    )
}

/// The scene `text` loaded through `registry`.
fn load(registry: &Registry, text: &str) -> Scene {
    Scene::from_text_with(registry, "custom_model.toml", "custom", text)
        .unwrap_or_else(|e| panic!("scene rejected: {e}"))
}

fn main() {
    let mut registry = Registry::default();
    registry.register_model_kind("ked-general", Arc::new(GeneralKed));

    let builtin = load(&registry, &scene_text("ked", "auto"));
    let custom = load(&registry, &scene_text("ked-general", "auto"));
    println!("{}", builtin.model_description());
    println!("{}", custom.model_description());
    println!(
        "auto resolves to {} for ked and to {} for ked-general",
        builtin.method.name(),
        custom.method.name()
    );
    assert_eq!(builtin.method.name(), "magnus6");
    assert_eq!(custom.method.name(), "abm");

    let refused = Scene::from_text_with(
        &registry,
        "custom_model.toml",
        "custom",
        &scene_text("ked-general", "magnus6"),
    )
    .expect_err("magnus6 needs a model linear in its state");
    println!("magnus6 on ked-general: {refused}");
    assert!(refused.to_string().contains("needs a linear"), "{refused}");

    let (reference, general) = (
        common::link1_deflections(&builtin),
        common::link1_deflections(&custom),
    );
    let peak = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let difference = common::max_difference(&general, &reference);
    println!("link 1 mid-point deflection, 0.05 s of the paper's 20 Hz circle:");
    println!("  peak |w| (ked, magnus6)                {peak:.6e} m");
    println!("  max |ked-general (abm) - ked (magnus6)| {difference:.3e} m");
    assert!(peak > 1e-6, "the scene must deflect the link");
    assert!(
        difference < 1e-6 * peak,
        "the two integrations of the same equations disagree: {difference:e} m against a peak of {peak:e} m"
    );
    println!("ok");
}
