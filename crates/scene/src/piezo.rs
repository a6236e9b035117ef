//! `[[links.patches]]` and `[vibration_control]` (docs/piezo.md): the links' piezoelectric
//! patches and their vibration control law.
//!
//! * Patches without a law are sensors only (their actuators at 0 V): a run reports their
//!   signals.
//! * A law without patches is refused at `vibration_control`.
//! * Every model takes patches (KED, coupled, actuated, nonlinear); a KED scene with patches
//!   is no longer linear in the exponential integrators' sense, so `auto` picks the general
//!   method for it.

use std::sync::Arc;

use flexprr_beam::{Layer, LayeredSection};
use flexprr_control::{VibrationController, VibrationInput};
use flexprr_dynamics::{LinkModel, Machine, Patch};

use crate::error::ScenarioError;
use crate::link::build_section;
use crate::registry::{Registry, TableParams};
use crate::scene::Checker;
use crate::schema::SceneFile;

/// What `[[links.patches]]` and `[vibration_control]` build.
pub(crate) struct PiezoParts {
    /// The patches, link by link in the order of the file.
    pub(crate) patches: Vec<Patch>,
    /// The law, when the scene names one.
    pub(crate) controller: Option<Arc<dyn VibrationController>>,
}

/// The machine and patches a vibration law is built for (a modal filter needs them).
#[derive(Debug, Clone, Copy)]
pub struct PatchContext<'a> {
    /// The machine (its links' modal integrals and shape functions).
    pub machine: &'a Machine,
    /// The scene's patches, in the order of the law's sensors and voltages.
    pub patches: &'a [Patch],
}

/// The law of patches that only sense: every voltage 0.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Passive;

impl VibrationController for Passive {
    fn voltages(&self, _input: &VibrationInput<'_>, voltages: &mut [f64]) {
        voltages.fill(0.0);
    }
    fn name(&self) -> String {
        "none (sensors only)".to_string()
    }
}

/// `[[links.patches]]` and `[vibration_control]`, each patch checked at its keys.
pub(crate) fn build_piezo(
    c: &Checker<'_>,
    registry: &Registry,
    raw: &SceneFile,
    machine: &Machine,
) -> Result<PiezoParts, ScenarioError> {
    let mut patches = Vec::new();
    for (k, config) in raw.links.patches.iter().enumerate() {
        let key = |name: &str| format!("links.patches.{k}.{name}");
        let links = config.links.clone().unwrap_or_else(|| vec![1, 2, 3]);
        if links.is_empty() {
            return Err(c.error(
                &key("links"),
                "name at least one link (1, 2 or 3), or leave the key out for all three",
            ));
        }
        for &link in &links {
            if !(1..=3).contains(&link) {
                return Err(c.error(
                    &key("links"),
                    format!("link {link} does not exist: links are 1, 2 and 3"),
                ));
            }
            if links.iter().filter(|&&l| l == link).count() > 1 {
                return Err(c.error(&key("links"), format!("link {link} is named twice")));
            }
            let patch = Patch {
                link: link - 1,
                xi_start: config.xi_start,
                xi_end: config.xi_end,
                actuator_constant: config.actuator_constant,
                sensor_constant: config.sensor_constant,
                voltage_limit: config.voltage_limit,
            };
            patch.validated().map_err(|e| {
                let name = match &e {
                    flexprr_dynamics::DynamicsError::InvalidParameter { quantity, .. } => quantity
                        .rsplit(": ")
                        .next()
                        .unwrap_or("xi_start")
                        .to_string(),
                    _ => "xi_start".to_string(),
                };
                c.error(&key(&name), e.to_string())
            })?;
            patches.push(patch);
        }
    }
    for (a, p) in patches.iter().enumerate() {
        if let Some(q) = patches[..a]
            .iter()
            .find(|q| q.link == p.link && q.xi_start < p.xi_end && p.xi_start < q.xi_end)
        {
            return Err(c.error(
                "links.patches",
                format!(
                    "two patches overlap on link {}: [{}, {}] and [{}, {}]",
                    p.link + 1,
                    q.xi_start,
                    q.xi_end,
                    p.xi_start,
                    p.xi_end
                ),
            ));
        }
    }
    let controller = match &raw.vibration_control {
        None => None,
        Some(_) if patches.is_empty() => {
            return Err(c.error(
                "vibration_control",
                "a vibration control law needs piezoelectric patches: add [[links.patches]]",
            ));
        }
        Some(table) => {
            let params = TableParams::new(c.file, c.text, "vibration_control", &table.params);
            let context = PatchContext {
                machine,
                patches: &patches,
            };
            Some(registry.build_vibration_controller(&params, &table.kind, &context)?)
        }
    };
    Ok(PiezoParts {
        patches,
        controller,
    })
}

/// The three links with the mass and bending stiffness of their patches bonded on
/// (`added_mass`, `added_bending_stiffness` of each `[[links.patches]]` entry, as layers of
/// [`flexprr_beam::LayeredSection`]); a link without such patches is `link` itself.
///
/// The nonlinear model's elements are uniform, so it refuses a patch that adds mass or
/// stiffness, at that key.
pub(crate) fn with_patch_layers(
    c: &Checker<'_>,
    raw: &SceneFile,
    link: LinkModel,
    caps: crate::ModelCapabilities,
) -> Result<[LinkModel; 3], ScenarioError> {
    let mut layers: [Vec<Layer>; 3] = Default::default();
    for (k, config) in raw.links.patches.iter().enumerate() {
        let key = |name: &str| format!("links.patches.{k}.{name}");
        let added = [
            ("added_mass", config.added_mass, "kg"),
            (
                "added_bending_stiffness",
                config.added_bending_stiffness,
                "N m^2",
            ),
        ];
        for (name, value, unit) in added {
            c.non_negative(&key(name), value, unit)?;
            if value > 0.0 && !caps.assumed_modes {
                return Err(c.value_error(
                    &key(name),
                    "the nonlinear model's elements are uniform and carry no patch mass or \
                     stiffness: set it to 0, or use model.coupling = \"ked\" or \"coupled\"",
                ));
            }
        }
        let span = config.xi_end - config.xi_start;
        // An invalid span is refused, at its key, where the patch itself is checked.
        if !(span > 0.0 && config.xi_start >= 0.0 && config.xi_end <= 1.0)
            || (config.added_mass == 0.0 && config.added_bending_stiffness == 0.0)
        {
            continue;
        }
        let layer = Layer {
            xi_start: config.xi_start,
            xi_end: config.xi_end,
            mass_per_length: config.added_mass / (span * raw.links.length),
            bending_stiffness: config.added_bending_stiffness,
        };
        for &l in config.links.as_deref().unwrap_or(&[1, 2, 3]) {
            if (1..=3).contains(&l) {
                layers[l - 1].push(layer);
            }
        }
    }
    if layers.iter().all(Vec::is_empty) {
        return Ok([link.clone(), link.clone(), link]);
    }
    let section = build_section(&raw.links.material, &raw.links.section)
        .map_err(|(k, msg)| c.error(&format!("links.{k}"), msg))?;
    let build = |layers: &Vec<Layer>| {
        if layers.is_empty() {
            return Ok(link.clone());
        }
        let layered = LayeredSection::new(section.as_ref(), layers.clone());
        LinkModel::new(link.basis.clone(), &layered, raw.links.length)
            .map_err(|e| c.error("links.patches", e.to_string()))
    };
    Ok([build(&layers[0])?, build(&layers[1])?, build(&layers[2])?])
}
