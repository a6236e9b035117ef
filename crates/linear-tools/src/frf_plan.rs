//! Test plans of `flexprr frf --config PLAN` (docs/linear.md, "Test plans"): a TOML file
//! with the scene (`base = "scene.toml"`, relative to the plan, or an inline `[scene]`
//! table, with optional `[set]` overrides merged table by table, as in a study) and the
//! command's options as keys: `pose = [x_m, y_m, phi_deg]` or `time`, `inputs`, `outputs`,
//! `from`, `to`, `points`, `log` or `frequencies` (a file, relative to the plan), and
//! `identify`. `configs/modal_test.toml` is the paper's modal test.

use std::path::{Path, PathBuf};

use flexprr_kinematics::Pose;
use flexprr_linear::{Input, Output};
use flexprr_scene::{ScenarioError, Scene, locate, parse_toml, read_input_file};
use serde::Deserialize;

/// The plan file as written.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
struct PlanFile {
    #[serde(default)]
    name: Option<String>,
    #[serde(default)]
    description: Option<String>,
    #[serde(default)]
    base: Option<String>,
    #[serde(default)]
    scene: Option<toml::Table>,
    #[serde(default)]
    set: toml::Table,
    #[serde(default)]
    pose: Option<[f64; 3]>,
    #[serde(default)]
    time: Option<f64>,
    #[serde(default)]
    inputs: Vec<String>,
    #[serde(default)]
    outputs: Vec<String>,
    #[serde(default)]
    from: Option<f64>,
    #[serde(default)]
    to: Option<f64>,
    #[serde(default)]
    points: Option<usize>,
    #[serde(default)]
    log: bool,
    #[serde(default)]
    frequencies: Option<String>,
    #[serde(default)]
    identify: usize,
}

/// A test plan, read and checked.
#[derive(Debug, Clone)]
pub struct FrfPlan {
    /// Name (default: the plan's file stem): the default output directory's.
    pub name: String,
    /// Free text.
    pub description: Option<String>,
    /// The scene, when the plan names one (`base` or `[scene]`).
    pub scene: Option<Scene>,
    /// The pose at rest, if given (m, m, rad).
    pub pose: Option<Pose>,
    /// The time along the motion, if given (s).
    pub time: Option<f64>,
    /// Inputs.
    pub inputs: Vec<Input>,
    /// Outputs.
    pub outputs: Vec<Output>,
    /// Grid keys.
    pub from_hz: Option<f64>,
    /// See [`FrfPlan::from_hz`].
    pub to_hz: Option<f64>,
    /// See [`FrfPlan::from_hz`].
    pub points: Option<usize>,
    /// Log-spaced grid.
    pub log: bool,
    /// A frequency file, resolved against the plan's directory.
    pub frequencies: Option<PathBuf>,
    /// Mode shapes to identify.
    pub identify: usize,
    /// The files read (the plan and its base scene), so that outputs never replace them.
    pub files: Vec<PathBuf>,
    /// The plan's `[set]` overrides.
    pub set: toml::Table,
    /// How the plan is named in messages.
    shown: String,
}

/// Merges `overrides` into `target` table by table (a value that is not a table replaces).
fn merge_into(target: &mut toml::Table, overrides: &toml::Table) {
    for (key, value) in overrides {
        match (target.get_mut(key), value) {
            (Some(toml::Value::Table(t)), toml::Value::Table(o)) => merge_into(t, o),
            _ => {
                target.insert(key.clone(), value.clone());
            }
        }
    }
}

/// A scene error from generated text, without its (meaningless) location, named after
/// where the text came from.
fn unlocated(origin: &str, e: ScenarioError) -> ScenarioError {
    match e {
        ScenarioError::Input { key, message, .. } => ScenarioError::Input {
            location: None,
            key,
            message: format!("{origin}: {message}"),
        },
        other => other,
    }
}

impl FrfPlan {
    /// Reads the plan at `path`.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] located in the plan (unknown keys, wrong types, a bad
    /// channel name, both `pose` and `time`, both `base` and `[scene]`), or the scene's own
    /// errors; [`ScenarioError::Io`] for a file that cannot be read.
    pub fn load(path: &Path) -> Result<Self, ScenarioError> {
        let shown = path.display().to_string();
        let text = read_input_file(path)?;
        let raw: PlanFile = parse_toml(&shown, &text)?;
        let at = |key: &str, message: String| ScenarioError::Input {
            location: locate(&shown, &text, key),
            key: key.to_string(),
            message,
        };
        let dir = path.parent().unwrap_or(Path::new("."));
        let mut files = vec![path.to_path_buf()];
        let scene = Self::scene(&raw, dir, &shown, &mut files, &at)?;
        if raw.pose.is_some() && raw.time.is_some() {
            return Err(at(
                "time",
                "give either pose (at rest) or time (along the motion), not both".into(),
            ));
        }
        let pose = raw
            .pose
            .map(|[x, y, phi]| Pose::new(x, y, phi.to_radians()));
        let inputs = channels::<Input>(&raw.inputs, "inputs", &at)?;
        let outputs = channels::<Output>(&raw.outputs, "outputs", &at)?;
        if raw.frequencies.is_some()
            && (raw.from.is_some() || raw.to.is_some() || raw.points.is_some() || raw.log)
        {
            return Err(at(
                "frequencies",
                "give either a frequency file or from/to/points/log, not both".into(),
            ));
        }
        let name = raw.name.clone().unwrap_or_else(|| {
            path.file_stem()
                .map_or("frf".into(), |s| s.to_string_lossy().into_owned())
        });
        Ok(Self {
            name,
            description: raw.description,
            scene,
            pose,
            time: raw.time,
            inputs,
            outputs,
            from_hz: raw.from,
            to_hz: raw.to,
            points: raw.points,
            log: raw.log,
            frequencies: raw.frequencies.map(|f| dir.join(f)),
            identify: raw.identify,
            files,
            set: raw.set,
            shown,
        })
    }

    /// The scene file at `path` with the plan's `[set]` merged in (another scene under the
    /// same test).
    ///
    /// # Errors
    /// As [`Scene::load`]; an override the scene refuses, named after the plan.
    pub fn scene_with_set(&self, path: &Path) -> Result<Scene, ScenarioError> {
        if self.set.is_empty() {
            return Scene::load_for_analysis(path);
        }
        let shown = path.display().to_string();
        let text = read_input_file(path)?;
        let mut table = parse_toml::<toml::Table>(&shown, &text)?;
        merge_into(&mut table, &self.set);
        let origin = format!("{shown} with the [set] of {}", self.shown);
        let stem = path
            .file_stem()
            .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
        let generated = toml::to_string(&table).map_err(|e| ScenarioError::Write {
            path: origin.clone(),
            message: format!("cannot be written back as TOML: {e}"),
        })?;
        Scene::from_text_for_analysis(&origin, &stem, &generated).map_err(|e| unlocated(&origin, e))
    }

    /// The plan's scene, if it names one.
    fn scene(
        raw: &PlanFile,
        dir: &Path,
        shown: &str,
        files: &mut Vec<PathBuf>,
        at: &dyn Fn(&str, String) -> ScenarioError,
    ) -> Result<Option<Scene>, ScenarioError> {
        let (mut table, origin, base_text) = match (&raw.base, &raw.scene) {
            (Some(_), Some(_)) => {
                return Err(at(
                    "base",
                    "give either `base = \"scene.toml\"` or an inline `[scene]` table, not both"
                        .into(),
                ));
            }
            (None, None) if raw.set.is_empty() => return Ok(None),
            (None, None) => {
                return Err(at(
                    "set",
                    "[set] changes the plan's scene: give `base = \"scene.toml\"` or `[scene]`"
                        .into(),
                ));
            }
            (Some(base), None) => {
                let path = dir.join(base);
                let text = read_input_file(&path)?;
                let name = path.display().to_string();
                let table = parse_toml::<toml::Table>(&name, &text)?;
                files.push(path);
                (table, name, Some(text))
            }
            (None, Some(scene)) => (scene.clone(), format!("{shown} [scene]"), None),
        };
        let stem = Path::new(&origin)
            .file_stem()
            .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
        match base_text {
            Some(text) if raw.set.is_empty() => {
                Scene::from_text_for_analysis(&origin, &stem, &text).map(Some)
            }
            _ => {
                merge_into(&mut table, &raw.set);
                let origin = if raw.set.is_empty() {
                    origin
                } else {
                    format!("{origin} with the [set] of {shown}")
                };
                let text = toml::to_string(&table).map_err(|e| at("set", e.to_string()))?;
                Scene::from_text_for_analysis(&origin, &stem, &text)
                    .map(Some)
                    .map_err(|e| unlocated(&origin, e))
            }
        }
    }
}

/// Parses the channel names of the list `key`, an error located at the bad entry.
fn channels<T>(
    names: &[String],
    key: &str,
    at: &dyn Fn(&str, String) -> ScenarioError,
) -> Result<Vec<T>, ScenarioError>
where
    T: std::str::FromStr<Err = flexprr_linear::ChannelError>,
{
    names
        .iter()
        .enumerate()
        .map(|(k, name)| {
            name.parse::<T>()
                .map_err(|e| at(&format!("{key}.{k}"), e.to_string()))
        })
        .collect()
}

/// Reads a frequency file: one frequency (Hz) per line, or a CSV whose first column holds
/// them (a header line and `#` comments are skipped), such as an earlier `frf.csv`.
///
/// # Errors
/// [`ScenarioError::Input`] at `file:line` for a value that is not a number, and for a list
/// that is not a grid (see [`crate::frf::check_listed`]); [`ScenarioError::Io`].
pub fn read_frequencies(path: &Path) -> Result<Vec<f64>, ScenarioError> {
    let shown = path.display().to_string();
    let text = read_input_file(path)?;
    let mut values = Vec::new();
    let bad = |line: usize, message: String| ScenarioError::Input {
        location: Some(flexprr_scene::Location {
            file: shown.clone(),
            line,
            column: 1,
        }),
        key: "--frequencies".into(),
        message,
    };
    for (k, line) in text.lines().enumerate() {
        let first = line.split(',').next().unwrap_or("").trim();
        if first.is_empty() || first.starts_with('#') {
            continue;
        }
        match first.parse::<f64>() {
            Ok(v) => values.push(v),
            Err(_) if values.is_empty() && first.chars().any(char::is_alphabetic) && k == 0 => {}
            Err(_) => {
                return Err(bad(
                    k + 1,
                    format!(
                        "{first:?} is not a frequency (Hz): one number per line, or a CSV with the frequencies first"
                    ),
                ));
            }
        }
    }
    crate::frf::check_listed(&values).map_err(|m| ScenarioError::Input {
        location: None,
        key: "--frequencies".into(),
        message: format!("{shown}: {m}"),
    })?;
    Ok(values)
}
