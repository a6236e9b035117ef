//! The paper's fixtures: the 3-PRR of Zhang, Mills & Cleghorn as parametrised in
//! `docs/model.md` ("parameter provenance"), the scene files of the workspace and the
//! independent reference state.
//!
//! The numbers are plain constants (this crate depends on no flexprr crate); the
//! unit tests of this module check them against `configs/paper_f20.toml` and against the
//! parameters recorded in the reference file, which were written independently.
//!
//! ```
//! use flexprr_testkit::paper;
//!
//! // The first pinned-pinned bending frequency (pi / l)^2 sqrt(EI / (rho A)) / (2 pi) is the
//! // paper's 116.4 Hz at the reconstructed E.
//! let f1 = (std::f64::consts::PI / paper::LINK_LENGTH).powi(2)
//!     * (paper::flexural_rigidity() / paper::mass_per_length()).sqrt()
//!     / (2.0 * std::f64::consts::PI);
//! flexprr_testkit::assert_close(f1, 116.4, 1e-3, 0.0, "f1 (Hz)");
//! let reference = paper::reference_state_f20();
//! assert_eq!(reference.state.len(), 18);
//! ```

use std::path::PathBuf;

/// Young's modulus (Pa) that reproduces the paper's printed 116.4 Hz.
pub const YOUNGS_MODULUS: f64 = 7.3e10;
/// Density of the aluminium links (kg/m^3).
pub const DENSITY: f64 = 2770.0;
/// Link length (m).
pub const LINK_LENGTH: f64 = 0.2;
/// Link thickness, the bending direction (m).
pub const THICKNESS: f64 = 0.002;
/// Link height (m).
pub const HEIGHT: f64 = 0.03;
/// Side of the equilateral platform (m).
pub const PLATFORM_SIDE: f64 = 0.1;
/// Platform mass (kg).
pub const PLATFORM_MASS: f64 = 0.2;
/// Slider mass (kg, assumed).
pub const SLIDER_MASS: f64 = 0.5;
/// Half travel of each guide (m).
pub const HALF_TRAVEL: f64 = 0.2;
/// Directions of the three guides (degrees).
pub const ALPHA_DEG: [f64; 3] = [150.0, 270.0, 30.0];
/// Platform orientation along the circle (degrees).
pub const PHI_DEG: f64 = 45.0;
/// Centre of the platform's circular path (m).
pub const CIRCLE_CENTRE: [f64; 2] = [-0.05, 0.0];
/// Radius of the platform's circular path (m).
pub const CIRCLE_RADIUS: f64 = 0.05;
/// Modes per link in the paper (r = 3).
pub const MODES: usize = 3;

/// Cross-section area `t h` (m^2).
pub fn area() -> f64 {
    THICKNESS * HEIGHT
}

/// Flexural rigidity `E h t^3 / 12` (N m^2) of the rectangular section bent across its thickness.
pub fn flexural_rigidity() -> f64 {
    YOUNGS_MODULUS * HEIGHT * THICKNESS.powi(3) / 12.0
}

/// Mass per unit length `rho t h` (kg/m).
pub fn mass_per_length() -> f64 {
    DENSITY * area()
}

/// Euler's buckling load of a pinned-pinned link, `pi^2 EI / l^2` (N).
pub fn euler_load() -> f64 {
    std::f64::consts::PI.powi(2) * flexural_rigidity() / LINK_LENGTH.powi(2)
}

/// The workspace root (the directory of the top `Cargo.toml`).
pub fn workspace_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join("..")
}

/// A scene file of `configs/` by name, e.g. `config("paper_f20.toml")`.
pub fn config(name: &str) -> PathBuf {
    workspace_root().join("configs").join(name)
}

/// `configs/paper_f20.toml`: the paper's scene at f = 20 Hz.
pub fn paper_f20_config() -> PathBuf {
    config("paper_f20.toml")
}

/// The file of [`reference_state_f20`], under `tests/data/`.
pub fn reference_state_f20_path() -> PathBuf {
    workspace_root()
        .join("tests")
        .join("data")
        .join("paper_f20_state_t0.2.json")
}

/// A modal state computed independently (Python, Dormand-Prince 8(5,3) at rtol 1e-13).
#[derive(Debug, Clone)]
pub struct ReferenceState {
    /// Time of the state (s).
    pub t: f64,
    /// `eta_11, eta_12, ..., eta_33` (m), then their time derivatives (m/s).
    pub state: Vec<f64>,
    /// The `parameters` object of the file, for checks against the constants.
    pub parameters: serde_json::Value,
}

impl ReferenceState {
    /// The modal displacements (first half of the state).
    pub fn displacements(&self) -> &[f64] {
        &self.state[..self.state.len() / 2]
    }

    /// The modal velocities (second half of the state).
    pub fn velocities(&self) -> &[f64] {
        &self.state[self.state.len() / 2..]
    }
}

/// The paper formulation's modal state at t = 0.2 s, f = 20 Hz, r = 3, from rest.
///
/// # Panics
/// If the file is missing or malformed; the message names the file and the key.
pub fn reference_state_f20() -> ReferenceState {
    let path = reference_state_f20_path();
    let text = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("reference state {}: {e}", path.display()));
    let json: serde_json::Value = serde_json::from_str(&text)
        .unwrap_or_else(|e| panic!("reference state {}: {e}", path.display()));
    let t = json["t_s"]
        .as_f64()
        .unwrap_or_else(|| panic!("reference state {}: no number `t_s`", path.display()));
    let state = json["state"]
        .as_array()
        .unwrap_or_else(|| panic!("reference state {}: no array `state`", path.display()))
        .iter()
        .enumerate()
        .map(|(i, v)| {
            v.as_f64().unwrap_or_else(|| {
                panic!(
                    "reference state {}: state[{i}] = {v} is not a number",
                    path.display()
                )
            })
        })
        .collect::<Vec<_>>();
    assert!(
        state.len() == 2 * 3 * MODES && state.iter().all(|x| x.is_finite()),
        "reference state {}: {} values, expected {} finite ones",
        path.display(),
        state.len(),
        2 * 3 * MODES
    );
    ReferenceState {
        t,
        state,
        parameters: json["parameters"].clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::assert_close;

    fn number(value: &toml::Value, keys: &[&str]) -> f64 {
        let mut v = value;
        for k in keys {
            v = v
                .get(*k)
                .unwrap_or_else(|| panic!("paper_f20.toml: no key {keys:?}"));
        }
        v.as_float()
            .or_else(|| v.as_integer().map(|i| i as f64))
            .unwrap_or_else(|| panic!("paper_f20.toml: {keys:?} is not a number"))
    }

    /// The constants agree with the scene file the CLI runs.
    #[test]
    fn constants_match_the_paper_scene_file() {
        let text = std::fs::read_to_string(paper_f20_config()).unwrap();
        let scene: toml::Value = toml::from_str(&text).unwrap();
        let checks = [
            (&["links", "material", "youngs_modulus"][..], YOUNGS_MODULUS),
            (&["links", "material", "density"], DENSITY),
            (&["links", "length"], LINK_LENGTH),
            (&["links", "section", "thickness"], THICKNESS),
            (&["links", "section", "height"], HEIGHT),
            (&["links", "modes"], MODES as f64),
            (&["machine", "platform_side"], PLATFORM_SIDE),
            (&["machine", "platform_mass"], PLATFORM_MASS),
            (&["machine", "slider_mass"], SLIDER_MASS),
            (&["machine", "half_travel"], HALF_TRAVEL),
            (&["trajectory", "radius"], CIRCLE_RADIUS),
            (&["trajectory", "phi_deg"], PHI_DEG),
        ];
        for (keys, value) in checks {
            assert_close(number(&scene, keys), value, 1e-15, 0.0, &keys.join("."));
        }
        for (i, alpha) in ALPHA_DEG.iter().enumerate() {
            let read = scene["machine"]["alpha_deg"][i].as_float().unwrap();
            assert_close(read, *alpha, 1e-15, 0.0, "machine.alpha_deg");
        }
        for (i, centre) in CIRCLE_CENTRE.iter().enumerate() {
            // The centre's y is 0: an absolute tolerance far below the metre scale.
            let read = scene["trajectory"]["centre"][i].as_float().unwrap();
            assert_close(read, *centre, 1e-15, 1e-18, "trajectory.centre");
        }
    }

    /// The constants agree with the parameters the independent reference was computed with.
    #[test]
    fn constants_match_the_reference_parameters() {
        let reference = reference_state_f20();
        let p = &reference.parameters;
        let get = |k: &str| p[k].as_f64().unwrap_or_else(|| panic!("parameters.{k}"));
        assert_close(get("E_Pa"), YOUNGS_MODULUS, 1e-15, 0.0, "E");
        assert_close(get("density_kg_m3"), DENSITY, 1e-15, 0.0, "density");
        assert_close(get("link_length_m"), LINK_LENGTH, 1e-15, 0.0, "length");
        assert_close(get("thickness_m"), THICKNESS, 1e-15, 0.0, "thickness");
        assert_close(get("height_m"), HEIGHT, 1e-15, 0.0, "height");
        assert_close(get("platform_side_m"), PLATFORM_SIDE, 1e-15, 0.0, "side");
        assert_close(get("platform_mass_kg"), PLATFORM_MASS, 1e-15, 0.0, "mass");
        assert_close(get("phi_deg"), PHI_DEG, 1e-15, 0.0, "phi");
        for (i, a) in ALPHA_DEG.iter().enumerate() {
            assert_close(p["alpha_deg"][i].as_f64().unwrap(), *a, 1e-15, 0.0, "alpha");
        }
        assert_close(reference.t, 0.2, 1e-15, 0.0, "t");
        assert_eq!(reference.displacements().len(), 9);
        assert_eq!(reference.velocities().len(), 9);
    }

    /// Euler's load by hand: EI = 7.3e10 * 0.03 * 8e-9 / 12 = 1.46 N m^2,
    /// pi^2 * 1.46 / 0.04 = 36.5 pi^2 N.
    #[test]
    fn derived_quantities_by_hand() {
        assert_close(flexural_rigidity(), 1.46, 1e-14, 0.0, "EI");
        assert_close(
            euler_load(),
            36.5 * std::f64::consts::PI.powi(2),
            1e-14,
            0.0,
            "P_cr",
        );
        assert_close(mass_per_length(), 0.1662, 1e-14, 0.0, "rho A");
    }
}
