//! Checks of a study when it loads, before any work (`docs/studies.md`, "Errors"): the
//! base scene with `[set]` and the cases built from it, every search's probe scenes at both
//! ends of its bracket, the searched key, the quantities the cases can give, and the plot
//! file names. Each error is placed in the user's own file: a `[set]` value in the study
//! file, a base scene key in the base scene file, an axis's values, or a `[search]` key,
//! never the generated text of a case.

use flexprr_scene::{ScenarioError, Scene, locate};
use rayon::prelude::*;

use crate::error::StudyError;
use crate::file::AxisConfig;
use crate::search::{Search, probe_table, search_cases};
use crate::study::{BaseSource, Case, Locator, Study, keys_overlap};

/// Scene keys a search sets in every probe: the window (`time.end`) and the outputs its
/// criterion needs. Neither the searched key nor an axis may vary them.
const PROBE_KEYS: [&str; 4] = [
    "time.end",
    "output.requests",
    "output.plots",
    "output.compare_without_axial_force",
];

/// Most distinct output and model settings among the cases whose quantities are checked at
/// load (a sweep with more gets the check case by case, as it runs).
const MAX_SETTINGS_CHECKED: usize = 64;

/// What is needed to place an error in the user's files.
pub(crate) struct Context<'a> {
    /// The study file.
    pub(crate) at: &'a Locator<'a>,
    /// `[set]` as written.
    pub(crate) set: &'a toml::Table,
    /// The base scene's origin.
    pub(crate) source: &'a BaseSource,
    /// `[[axis]]` as written.
    pub(crate) axes: &'a [AxisConfig],
    /// The base scene with `[set]` applied.
    pub(crate) base: &'a toml::Table,
}

impl Context<'_> {
    /// Places a scene error of a case (described by `case`, e.g. `case 0:
    /// trajectory.frequency = 10`) in the user's files: at the values of an axis whose key
    /// it concerns, at a `[set]` value, or in the base scene.
    fn place(&self, e: ScenarioError, case: &str) -> StudyError {
        let ScenarioError::Input { key, message, .. } = e else {
            return StudyError::Scene(e);
        };
        let field = |k: usize| {
            let field = if self.axes[k].values.is_some() {
                "values"
            } else {
                "range"
            };
            format!("axis.{k}.{field}")
        };
        if let Some(k) = self.axes.iter().position(|a| keys_overlap(&a.key, &key)) {
            return self
                .at
                .input(&field(k), format!("{key}: {message} ({case})"));
        }
        // An axis whose table is missing from the base scene creates it holding only the
        // axis's key; the table's other required keys are then missing.
        if let Some((k, table)) = self.axes.iter().enumerate().find_map(|(k, a)| {
            let created = created_table(self.base, &a.key)?;
            keys_overlap(&created, &key).then_some((k, created))
        }) {
            return self.at.input(
                &format!("axis.{k}.key"),
                format!(
                    "{key}: {message}: the base scene has no `{table}` table, so the axis \
                     creates one holding only its own key; give the table in the base scene or \
                     in [set]"
                ),
            );
        }
        if !key.is_empty() && defines(self.set, &key) {
            return self.at.input(&format!("set.{key}"), message);
        }
        match self.source {
            BaseSource::File { shown, text, .. } => StudyError::Scene(ScenarioError::Input {
                location: locate(shown, text, &key),
                key,
                message,
            }),
            BaseSource::Inline if key.is_empty() => self.at.input("scene", message),
            BaseSource::Inline => self.at.input(&format!("scene.{key}"), message),
        }
    }
}

/// The outermost table on the dotted `key`'s path that `base` lacks (setting the key would
/// create it), if any.
fn created_table(base: &toml::Table, key: &str) -> Option<String> {
    let parts: Vec<&str> = key.split('.').collect();
    let mut node = toml::Value::Table(base.clone());
    for (k, part) in parts.iter().enumerate().take(parts.len().saturating_sub(1)) {
        let next = match &node {
            toml::Value::Table(t) => t.get(*part).cloned(),
            toml::Value::Array(a) => part.parse::<usize>().ok().and_then(|i| a.get(i).cloned()),
            _ => return None,
        };
        match next {
            Some(v) => node = v,
            None => return Some(parts[..=k].join(".")),
        }
    }
    None
}

/// The value at the dotted `key` of a scene table, if it is there.
fn value_at<'t>(table: &'t toml::Table, key: &str) -> Option<&'t toml::Value> {
    let mut parts = key.split('.');
    let mut node = table.get(parts.next()?)?;
    for part in parts {
        node = match node {
            toml::Value::Table(t) => t.get(part)?,
            toml::Value::Array(a) => a.get(part.parse::<usize>().ok()?)?,
            _ => return None,
        };
    }
    Some(node)
}

fn is_number(value: &toml::Value) -> bool {
    matches!(value, toml::Value::Float(_) | toml::Value::Integer(_))
}

/// Whether `[set]` gives the value at the dotted `key`: the key itself, or a value (not a
/// table) on its path that replaces everything below it.
fn defines(set: &toml::Table, key: &str) -> bool {
    let mut node = set;
    for part in key.split('.') {
        match node.get(part) {
            None => return false,
            Some(toml::Value::Table(t)) => node = t,
            Some(_) => return true,
        }
    }
    true
}

/// `case <id>: key = value, ...` of a case (the first few axes, values cut short).
fn describe(study: &Study, case: &Case) -> String {
    const SHOWN: usize = 4;
    let mut values: Vec<String> = study
        .axes
        .iter()
        .zip(study.case_parameters(case))
        .take(SHOWN)
        .map(|(a, v)| {
            let v: String = if v.chars().count() > 60 {
                v.chars().take(57).chain("...".chars()).collect()
            } else {
                v
            };
            format!("{} = {v}", a.key)
        })
        .collect();
    if study.axes.len() > SHOWN {
        values.push(format!("and {} more axes", study.axes.len() - SHOWN));
    }
    format!("case {}: {}", case.id, values.join(", "))
}

/// The search key and the axes of a search study: the key must not be the window or an
/// output the criterion sets, and no axis may overlap the key, the window or those outputs
/// (the probe would overwrite the axis's values without a word).
///
/// # Errors
/// [`StudyError::Input`] at `search.key` or the axis's key.
pub(crate) fn check_search_keys(
    search: &Search,
    axes: &[crate::study::Axis],
    at: &Locator<'_>,
) -> Result<(), StudyError> {
    if let Some(set) = PROBE_KEYS.iter().find(|k| keys_overlap(&search.key, k)) {
        return Err(at.input(
            "search.key",
            format!(
                "\"{}\" is set by every probe ({set}: the window, or an output the criterion \
                 needs): search over another key",
                search.key
            ),
        ));
    }
    for (k, axis) in axes.iter().enumerate() {
        if keys_overlap(&axis.key, &search.key) {
            return Err(at.input(
                &format!("axis.{k}.key"),
                format!(
                    "the search varies {} itself: an axis may vary any other key (one search \
                     runs per case), not the searched one or a table holding it",
                    search.key
                ),
            ));
        }
        if let Some(set) = PROBE_KEYS.iter().find(|p| keys_overlap(&axis.key, p)) {
            return Err(at.input(
                &format!("axis.{k}.key"),
                format!(
                    "\"{}\" is set by every probe of the search ({set}: the window, or an \
                     output the criterion needs), so this axis would change nothing",
                    axis.key
                ),
            ));
        }
    }
    Ok(())
}

/// A sweep's cases: when not one of them is a valid scene, the study is refused with the
/// error of a case, placed in the user's files (an error of the base scene or `[set]`
/// first). A sweep with some valid cases runs: the others are recorded as `invalid`.
///
/// # Errors
/// The placed error ([`StudyError::Input`] or [`StudyError::Scene`]).
pub(crate) fn check_cases(study: &Study, context: &Context<'_>) -> Result<(), StudyError> {
    let Some((first, rest)) = study.cases.split_first() else {
        return Ok(());
    };
    let first_error = match study.case_scene(first) {
        Ok(_) => return Ok(()),
        Err(e) => e,
    };
    if rest.par_iter().any(|c| study.case_scene(c).is_ok()) {
        return Ok(());
    }
    // Every case is invalid. An error that no axis explains is the base scene's or [set]'s.
    let of_axes = |e: &ScenarioError| match e {
        ScenarioError::Input { key, .. } => study.axes.iter().any(|a| keys_overlap(&a.key, key)),
        _ => false,
    };
    let (case, error) = if of_axes(&first_error) {
        rest.iter()
            .take(1000)
            .find_map(|c| {
                study
                    .case_scene(c)
                    .err()
                    .filter(|e| !of_axes(e))
                    .map(|e| (c, e))
            })
            .unwrap_or((first, first_error))
    } else {
        (first, first_error)
    };
    let what = if study.cases.len() == 1 {
        describe(study, case)
    } else {
        format!("every case is invalid, e.g. {}", describe(study, case))
    };
    Err(context.place(error, &what))
}

/// A search study's probe scenes at both ends of the bracket, for every search: each must
/// be a valid scene, and the searched key a numeric scene key.
///
/// # Errors
/// [`StudyError::Input`] at `search.key`, `search.low`/`search.high`, `search.criterion`,
/// or the placed error of the base scene, `[set]` or an axis.
pub(crate) fn check_searches(
    study: &Study,
    search: &Search,
    context: &Context<'_>,
) -> Result<(), StudyError> {
    let at = context.at;
    let cases = search_cases(study).map_err(|m| at.input("axis", m))?;
    for (labels, table) in &cases {
        let case: Vec<String> = labels.iter().map(|(k, v)| format!("{k} = {v}")).collect();
        let case = if case.is_empty() {
            "the base scene".to_string()
        } else {
            format!("the case {}", case.join(", "))
        };
        if let Some(held) = value_at(table, &search.key).filter(|v| !is_number(v)) {
            return Err(at.input(
                "search.key",
                format!(
                    "\"{}\" holds {held} in {case}, not a number: a search varies a numeric key",
                    search.key
                ),
            ));
        }
        let criterion = search.criterion_for(table).map_err(|m| {
            let message = if labels.is_empty() {
                m
            } else {
                format!("in {case}: {m}")
            };
            at.input("search.criterion", message)
        })?;
        for (end, value) in [("low", search.low), ("high", search.high)] {
            let probe = probe_table(search, table, criterion, value)
                .map_err(|m| at.input("search.key", m))?;
            let text = toml::to_string(&probe).map_err(|e| at.input("search", e.to_string()))?;
            if let Err(e) =
                Scene::from_text_with(&study.plugins.scenes, &study.name, &study.name, &text)
            {
                return Err(place_probe_error(context, search, e, end, value, &case));
            }
        }
    }
    Ok(())
}

/// Places the error of a probe scene: the searched key (not a numeric scene key), its value
/// at one end, the window, or else the base scene, `[set]` or an axis.
fn place_probe_error(
    context: &Context<'_>,
    search: &Search,
    e: ScenarioError,
    end: &str,
    value: f64,
    case: &str,
) -> StudyError {
    let at = context.at;
    let ScenarioError::Input { key, message, .. } = &e else {
        return StudyError::Scene(e);
    };
    if keys_overlap(key, &search.key) {
        // The parser's words for a key that takes no number; a value out of range is
        // reported with what it `got`.
        let not_numeric = ["unknown field", "invalid type", "wanted", "unknown variant"]
            .iter()
            .any(|w| message.contains(w));
        return if not_numeric {
            at.input(
                "search.key",
                format!(
                    "\"{}\" is not a numeric scene key: {key}: {message}",
                    search.key
                ),
            )
        } else {
            at.input(
                &format!("search.{end}"),
                format!("{} = {value:?} ({case}): {key}: {message}", search.key),
            )
        };
    }
    if keys_overlap(key, "time") {
        let window = format!("time.end = {:?} s", search.end(value));
        let field = match search.window {
            crate::search::Window::Revolutions(_) => "search.revolutions",
            crate::search::Window::Time(_) => "search.time",
        };
        return at.input(
            field,
            format!(
                "the window gives {window} at {} = {value:?} ({case}): {key}: {message}",
                search.key
            ),
        );
    }
    context.place(e, case)
}

/// Whether a sweep's quantities can be had: each must be available (its output requested,
/// its mode present, a model that gives it) in at least one valid case, or every case would
/// fail on it after running. Checked on the first valid case of each distinct setting of the
/// axes over `output`, `model` and `links`.
///
/// # Errors
/// [`StudyError::Input`] at `quantities.<k>` with why and what to add.
pub(crate) fn check_quantities_available(
    study: &Study,
    context: &Context<'_>,
) -> Result<(), StudyError> {
    if study.quantities.is_empty() {
        return Ok(());
    }
    let relevant: Vec<usize> = study
        .axes
        .iter()
        .enumerate()
        .filter(|(_, a)| {
            ["output", "model", "links"]
                .iter()
                .any(|k| keys_overlap(&a.key, k))
        })
        .map(|(i, _)| i)
        .collect();
    let mut settings: Vec<(Vec<String>, Option<Scene>)> = Vec::new();
    let mut tried = 0;
    for case in &study.cases {
        let setting: Vec<String> = relevant
            .iter()
            .map(|&i| case.values[i].to_string())
            .collect();
        let slot = match settings.iter().position(|(s, _)| *s == setting) {
            Some(k) if settings[k].1.is_some() => continue,
            Some(k) => k,
            None if settings.len() >= MAX_SETTINGS_CHECKED => return Ok(()),
            None => {
                settings.push((setting, None));
                settings.len() - 1
            }
        };
        tried += 1;
        if tried > 4 * MAX_SETTINGS_CHECKED {
            break;
        }
        settings[slot].1 = study.case_scene(case).ok();
    }
    let scenes: Vec<&Scene> = settings.iter().filter_map(|(_, s)| s.as_ref()).collect();
    if scenes.is_empty() {
        return Ok(());
    }
    for (k, q) in study.quantities.iter().enumerate() {
        let reasons: Vec<String> = scenes.iter().filter_map(|s| q.unavailable(s)).collect();
        if reasons.len() == scenes.len() {
            let every = if scenes.len() == 1 {
                ""
            } else {
                " in every case"
            };
            return Err(context
                .at
                .input(&format!("quantities.{k}"), format!("{}{every}", reasons[0])));
        }
    }
    Ok(())
}

/// Why a plot's `file` is not a plain `.svg` name inside the output directory (no path, not
/// hidden, safe characters, not one of the study's own files); `None` when it is.
pub(crate) fn plot_file_problem(file: &str) -> Option<String> {
    if let Some(why) = flexprr_scene::unsafe_name_reason(file) {
        return Some(format!(
            "\"{file}\" {why}: give a plain file name such as \"speed.svg\" (letters, digits, \
             `.`, `_`, `-`), written inside the output directory"
        ));
    }
    if !file.ends_with(".svg") || file.len() == ".svg".len() {
        return Some(format!(
            "\"{file}\" does not end in .svg: plots are SVG files (and the study's own files, \
             results.csv, study.json, search.json and search.md, are not plot names)"
        ));
    }
    None
}

/// A map study has none of a sweep's or a search's tables: its grid is its only variable.
///
/// # Errors
/// [`StudyError::Input`] at the first table or key that does not belong with `[map]`.
pub(crate) fn check_map_alone(
    raw: &crate::file::StudyFile,
    at: &Locator<'_>,
) -> Result<(), StudyError> {
    if raw.search.is_some() {
        return Err(at.input(
            "search",
            "a study is a sweep, a speed search or a workspace map: give [search] or [map], not both",
        ));
    }
    if !raw.axis.is_empty() {
        return Err(at.input(
            "axis.0",
            "a workspace map has no sweep axes: it varies the pose over its own grid (map.x, \
             map.y); to map variants (another model, other gains), run one map study per \
             variant with the change in [set]",
        ));
    }
    if !raw.quantities.is_empty() {
        return Err(at.input(
            "quantities",
            "a workspace map computes map.quantity at every pose; `quantities` are a sweep's \
             columns: remove them",
        ));
    }
    if !raw.plot.is_empty() {
        return Err(at.input(
            "plot.0",
            "a workspace map draws map.svg itself: remove the [[plot]] tables",
        ));
    }
    Ok(())
}

/// A map's base scene: a valid scene (its errors placed in the user's files), with a model
/// of the whole machine (coupled or nonlinear: the KED model prescribes the platform), and
/// at least one pose of the grid within reach.
///
/// # Errors
/// The placed error of the base scene or `[set]`, or [`StudyError::Input`] at `map`.
pub(crate) fn check_map(
    study: &Study,
    map: &crate::map::Map,
    context: &Context<'_>,
) -> Result<(), StudyError> {
    check_cases(study, context)?;
    let Some(scene) = study.cases.first().and_then(|c| study.case_scene(c).ok()) else {
        return Ok(());
    };
    if !scene.coupling.capabilities().free_platform {
        return Err(context.at.input(
            "map",
            format!(
                "{} needs a model of the whole machine, and the base scene's model.coupling is \
                 \"{}\", which prescribes the platform and the sliders: set model.coupling = \
                 \"coupled\" or \"nonlinear\" (in [set.model] or in the base scene)",
                map.quantity.name(),
                scene.coupling.name()
            ),
        ));
    }
    let phi = map.phi(&scene);
    let geometry = &scene.machine.geometry;
    let poses = map.poses(phi);
    let (mut singular, mut example) = (0, None);
    for pose in &poses {
        match flexprr_linear_tools::machine_modes::rest_pose(&scene, *pose) {
            Ok(_) => return Ok(()),
            Err(flexprr_linear_tools::machine_modes::RestFrequency::Singular(reason)) => {
                singular += 1;
                example.get_or_insert((*pose, reason));
            }
            Err(_) => {}
        }
    }
    let grid = format!(
        "{} x {} poses of the grid (x from {} to {} m, y from {} to {} m)",
        map.x.len(),
        map.y.len(),
        map.x[0],
        map.x[map.x.len() - 1],
        map.y[0],
        map.y[map.y.len() - 1],
    );
    let message = match example {
        Some((pose, reason)) => format!(
            "none of the {grid} can be mapped at phi = {} deg: {singular} {} singular, where \
             the links do not hold the platform (e.g. at ({} m, {} m): {reason}), and {} out of \
             reach; a map needs poses away from the singularity loci (another orientation \
             map.phi_deg, or another region): {}",
            phi.to_degrees(),
            if singular == 1 { "is" } else { "are" },
            pose.x,
            pose.y,
            poses.len() - singular,
            reachable_box(geometry, phi)
        ),
        None => format!(
            "none of the {grid} is within reach at phi = {} deg: {}",
            phi.to_degrees(),
            reachable_box(geometry, phi)
        ),
    };
    Err(context.at.input("map", message))
}

/// Where the platform reaches at orientation `phi`, in words: the bounding box of the
/// reachable nodes of a 121 x 121 section over the guides' box.
fn reachable_box(geometry: &flexprr_kinematics::Geometry, phi: f64) -> String {
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for leg in &geometry.legs {
        for r in [leg.guide.travel.0, leg.guide.travel.1] {
            let p = leg.guide.slider_point(r);
            (x0, x1, y0, y1) = (x0.min(p.x), x1.max(p.x), y0.min(p.y), y1.max(p.y));
        }
    }
    let section = flexprr_viewer::workspace_section(geometry, phi, (x0, x1), (y0, y1), 121);
    let n = section.x.len();
    let nodes: Vec<(f64, f64)> = (0..section.reachable.len())
        .filter(|&k| section.reachable[k])
        .map(|k| (section.x[k % n], section.y[k / n]))
        .collect();
    if nodes.is_empty() {
        return "the machine reaches no pose at this orientation".into();
    }
    let fold = |f: fn(f64, f64) -> f64, init: f64, pick: fn(&(f64, f64)) -> f64| {
        nodes.iter().map(pick).fold(init, f)
    };
    format!(
        "the reachable set spans about x from {:.3} to {:.3} m and y from {:.3} to {:.3} m",
        fold(f64::min, f64::MAX, |p| p.0),
        fold(f64::max, f64::MIN, |p| p.0),
        fold(f64::min, f64::MAX, |p| p.1),
        fold(f64::max, f64::MIN, |p| p.1)
    )
}
