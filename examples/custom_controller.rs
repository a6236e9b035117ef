//! Registers a new control law from outside the crates and runs a TOML scene that names it.
//!
//! The law is sliding-mode control with a boundary layer (Slotine & Li, *Applied Nonlinear
//! Control*, 1991, sections 7.1-7.2) on each slider, on top of the rigid feedforward:
//!
//! ```text
//! s = e' + lambda e,            e = rho_ref - rho
//! F = F_ff + m lambda e' + k sat(s / phi)
//! ```
//!
//! `m lambda e'` cancels the `-lambda e'` the sliding surface's own motion needs (for a
//! slider of mass `m`, `m s' = m e'' + m lambda e'` and `m e'' = -F + F_ff + d` with the
//! unmodelled force `d`: the links' elastic inertia); `k sat(s / phi)` pushes `s` into the
//! boundary layer `|s| <= phi` whenever `k` exceeds `|d|`, and inside it the law is linear,
//! with no chattering. The closed-loop guarantee that this example checks: a run that starts
//! on the path (`s = 0`) and keeps `|s| <= phi` keeps the position error within
//! `|e| <= phi / lambda` (the first-order filter `e' + lambda e = s`; Slotine & Li, eq. 7.17).
//!
//! The scene is `configs/servo_f20.toml` (the paper's machine on its 20 Hz circle, coupled
//! model, ideal force actuators) with its `[control]` table replaced by
//!
//! ```toml
//! [control]
//! kind = "sliding_mode"
//! lambda = 500        # 1/s
//! k = 100             # N
//! phi = 0.01          # m/s
//! mass = 0.5          # kg (the slider)
//! ```
//!
//! It prints the slider tracking errors of the PD law of the shipped scene and of this law,
//! and fails if the sliding-mode error leaves the bound `phi / lambda` (20 um here; measured:
//! peaks of 1.1-1.8 um against the PD law's 25-33 um, the law being much stiffer inside its
//! layer).
//!
//! Run: `cargo run --release --example custom_controller`

use std::sync::Arc;

use flexprr_control::{ControlInput, Controller};
use flexprr_scene::{ControllerFactory, Registry, ScenarioError, Scene, TableParams};

/// The sliding-mode law with a boundary layer, per slider.
#[derive(Debug, Clone, Copy)]
struct SlidingMode {
    /// Bandwidth of the sliding surface `s = e' + lambda e` (1/s).
    lambda: f64,
    /// Switching gain (N): at least the largest unmodelled force.
    k: f64,
    /// Boundary layer half-width in `s` (m/s).
    phi: f64,
    /// Mass the law assumes for the slider (kg).
    mass: f64,
}

impl Controller for SlidingMode {
    fn command(
        &self,
        input: &ControlInput<'_>,
        _states: &[f64],
        force: &mut [f64; 3],
        _rates: &mut [f64],
    ) {
        for (i, f) in force.iter_mut().enumerate() {
            let (reference, measured) = (input.reference[i], input.measured[i]);
            let e = reference.position - measured.position;
            let e_dot = reference.velocity - measured.velocity;
            let s = e_dot + self.lambda * e;
            let switching = self.k * (s / self.phi).clamp(-1.0, 1.0);
            *f = input.feedforward[i] + self.mass * self.lambda * e_dot + switching;
        }
    }
    fn name(&self) -> String {
        "sliding_mode".into()
    }
}

/// The keys of `kind = "sliding_mode"`.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct Keys {
    lambda: f64,
    k: f64,
    phi: f64,
    mass: f64,
}

/// What the registry calls for `control.kind = "sliding_mode"`: reads and checks the keys,
/// each error located at its key in the scene file.
struct SlidingModeFactory;

impl ControllerFactory for SlidingModeFactory {
    fn build(&self, params: &TableParams<'_>) -> Result<Arc<dyn Controller>, ScenarioError> {
        let keys: Keys = params.parse()?;
        for (key, value, unit) in [
            ("lambda", keys.lambda, "1/s"),
            ("k", keys.k, "N"),
            ("phi", keys.phi, "m/s"),
            ("mass", keys.mass, "kg"),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(params.error(
                    key,
                    format!("expected a positive number ({unit}), got {value}"),
                ));
            }
        }
        Ok(Arc::new(SlidingMode {
            lambda: keys.lambda,
            k: keys.k,
            phi: keys.phi,
            mass: keys.mass,
        }))
    }
}

const SLIDING_MODE: SlidingMode = SlidingMode {
    lambda: 500.0,
    k: 100.0,
    phi: 0.01,
    mass: 0.5,
};

/// `configs/servo_f20.toml` over 0.1 s, tracking only, with `control` as its `[control]`.
fn scene_text(control: Option<&str>) -> String {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/configs/servo_f20.toml");
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut text = text
        .replace("end = 0.2", "end = 0.1")
        .replace(
            "requests = [\"tracking\", \"deflections\", \"actuators\", \"viewer\"]",
            "requests = [\"tracking\"]",
        )
        .replace("plots = true", "plots = false");
    if let Some(control) = control {
        let start = 1 + text
            .find("\n[control]\n")
            .expect("the shipped scene has a [control] table");
        let end = start + text[start..].find("\n\n").expect("a blank line after it");
        text.replace_range(start..end, control);
    }
    text
}

/// Peak and RMS of each slider's tracking error (m).
fn errors(registry: &Registry, text: &str) -> (String, [(f64, f64); 3]) {
    let scene = Scene::from_text_with(registry, "custom_controller.toml", "custom", text)
        .unwrap_or_else(|e| panic!("scene rejected: {e}"));
    let result = flexprr_run::run(&scene, &mut |_| {}).unwrap_or_else(|e| panic!("run: {e}"));
    let servo = flexprr_run::control::report_of(&result)
        .servo
        .clone()
        .expect("an actuated run");
    let errors = servo.sliders.map(|s| (s.error.value, s.rms_error));
    (servo.controller, errors)
}

fn main() {
    let mut registry = Registry::default();
    registry.register_controller("sliding_mode", Arc::new(SlidingModeFactory));
    let law = SLIDING_MODE;
    let control = format!(
        "[control]\nkind = \"sliding_mode\"\nlambda = {}\nk = {}\nphi = {}\nmass = {}",
        law.lambda, law.k, law.phi, law.mass
    );
    let (pd_name, pd) = errors(&registry, &scene_text(None));
    let (name, sliding) = errors(&registry, &scene_text(Some(&control)));
    assert_eq!(name, "sliding_mode", "the scene ran the registered law");
    let bound = law.phi / law.lambda;
    println!("paper machine, 20 Hz circle, coupled model, ideal forces, 0-0.1 s");
    println!("| slider | {pd_name}: peak (um) | RMS (um) | {name}: peak (um) | RMS (um) |");
    println!("|---|---|---|---|---|");
    for i in 0..3 {
        println!(
            "| {} | {:.2} | {:.2} | {:.2} | {:.2} |",
            i + 1,
            1e6 * pd[i].0,
            1e6 * pd[i].1,
            1e6 * sliding[i].0,
            1e6 * sliding[i].1
        );
        assert!(
            sliding[i].0 <= bound,
            "slider {}: peak error {} m outside the boundary-layer bound phi / lambda = {bound} m",
            i + 1,
            sliding[i].0
        );
    }
    println!(
        "sliding-mode errors within the boundary-layer bound phi / lambda = {:.0} um; inside the \
         layer the law is linear with kp = k lambda / phi = {:.3e} N/m and kd = k / phi + m lambda \
         = {:.0} N s/m, stiffer than the shipped PD (2e5 N/m, 400 N s/m)",
        1e6 * bound,
        law.k * law.lambda / law.phi,
        law.k / law.phi + law.mass * law.lambda
    );
    // A bad key is located like a built-in law's.
    let bad = scene_text(Some(&control.replace("phi = 0.01", "phi = -1")));
    match Scene::from_text_with(&registry, "custom_controller.toml", "custom", &bad) {
        Err(e) => {
            assert!(e.to_string().contains("control.phi"), "{e}");
            println!("bad key refused: {e}");
        }
        Ok(_) => panic!("phi = -1 accepted"),
    }
    println!("ok");
}
