//! Words and units of the scene keys a study sweeps most often, for plot axes and legends
//! (units as in the key tables of `docs/scenes.md`). A key not listed here is shown as
//! written.

/// (dotted scene key, words, SI unit).
const SCENE_KEYS: [(&str, &str, &str); 24] = [
    ("trajectory.frequency", "circle frequency f", "Hz"),
    ("trajectory.radius", "circle radius", "m"),
    ("trajectory.duration", "move duration", "s"),
    ("trajectory.phi_deg", "platform orientation", "deg"),
    ("machine.platform_mass", "platform mass", "kg"),
    ("machine.platform_inertia", "platform inertia", "kg m²"),
    ("machine.platform_side", "platform side", "m"),
    ("machine.slider_mass", "slider mass", "kg"),
    ("machine.half_travel", "slider half travel", "m"),
    ("links.length", "link length", "m"),
    ("links.section.thickness", "link thickness", "m"),
    ("links.section.height", "link height", "m"),
    ("links.section.thickness_start", "link thickness at B", "m"),
    ("links.section.thickness_end", "link thickness at C", "m"),
    ("links.material.youngs_modulus", "Young's modulus", "Pa"),
    ("links.material.density", "density", "kg/m³"),
    ("links.modes", "modes per link", ""),
    ("model.formulation", "formulation", ""),
    ("model.coupling", "coupling", ""),
    ("integrator.rtol", "relative tolerance", ""),
    ("integrator.atol", "absolute tolerance", ""),
    ("integrator.method", "integrator", ""),
    ("integrator.max_steps", "step budget", ""),
    ("time.end", "end time", "s"),
];

/// Words and unit of a scene key (the key itself and no unit if it is not known).
pub fn key_words(key: &str) -> (&str, &'static str) {
    SCENE_KEYS
        .iter()
        .find(|(k, _, _)| *k == key)
        .map_or((key, ""), |(_, words, unit)| (*words, *unit))
}

/// Axis label of a scene key: `platform mass (kg)`.
pub fn key_label(key: &str) -> String {
    let (words, unit) = key_words(key);
    crate::quantity::with_unit(words, unit)
}

/// Legend entry for one value of a key: `platform mass = 0.2 kg`, `formulation = paper`.
pub fn key_value_label(key: &str, value: &str) -> String {
    let (words, unit) = key_words(key);
    if unit.is_empty() {
        format!("{words} = {value}")
    } else {
        format!("{words} = {value} {unit}")
    }
}
