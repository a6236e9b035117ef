//! The scenes `flexprr plan` derives from the user's: the planned scene (its motion the
//! plan, its `[plan]` removed) and its unshaped variant, a named scene transformation of the
//! run layer ([`Unshaped`], a [`SceneVariant`] like the runs without axial force or without
//! vibration control).

use flexprr_kinematics::PlannedData;
use flexprr_run::{RunError, SceneVariant};
use flexprr_scene::{Scene, SceneFile, TrajectoryConfig};

/// The scene with `data` as its trajectory, `[plan]` removed, its time span from its own
/// start to `end` (s) and its stop times dropped (they belong to the old motion; a planned
/// motion's breakpoints are stepped onto by the run itself).
pub fn planned_scene_file(file: &SceneFile, data: PlannedData, end: f64) -> SceneFile {
    let mut planned = file.clone();
    planned.trajectory = TrajectoryConfig::Planned(Box::new(data));
    planned.plan = None;
    planned.time.end = end;
    planned.time.stops.clear();
    if let Some(name) = &file.name {
        planned.name = Some(format!("{name}_planned"));
    }
    planned
}

/// The unshaped variant of a planned scene: the same timing without its shaper's impulses,
/// its span shortened by the shaper's length so that the settling window after the move is
/// the same. A scene whose motion is not a shaped plan is returned unchanged.
pub fn unshaped(file: &SceneFile) -> SceneFile {
    let mut out = file.clone();
    if let TrajectoryConfig::Planned(data) = &mut out.trajectory
        && !data.shaper.is_empty()
    {
        let extra = data
            .shaper
            .iter()
            .map(|[_, delay]| *delay)
            .fold(0.0, f64::max);
        data.shaper.clear();
        out.time.end -= extra;
        if let Some(name) = &file.name {
            out.name = Some(format!("{name}_unshaped"));
        }
    }
    out
}

/// The unshaped variant of a planned scene ([`unshaped`] on its file, built and checked
/// like any scene): the scene transformation `unshaped`.
#[derive(Debug, Clone, Copy)]
pub struct Unshaped;

impl SceneVariant for Unshaped {
    fn name(&self) -> &'static str {
        "unshaped"
    }
    fn description(&self) -> &'static str {
        "the planned motion without its input shaper (same timing, span shortened by the shaper's length)"
    }
    fn transform(&self, scene: &Scene) -> Result<Option<Scene>, RunError> {
        let file = unshaped(&scene.file);
        let text = scene_toml(&file, "").unwrap_or_default();
        let label = format!("{} (planned)", scene.name);
        Ok(Some(Scene::from_file(&label, &text, file, &scene.name)?))
    }
}

/// The scene file as TOML text, with a header saying where it came from.
///
/// # Errors
/// A value TOML cannot hold (never for a scene that was read from TOML).
pub fn scene_toml(file: &SceneFile, header: &str) -> Result<String, String> {
    let body = toml::to_string(file).map_err(|e| e.to_string())?;
    let mut text = String::new();
    for line in header.lines() {
        text.push_str("# ");
        text.push_str(line);
        text.push('\n');
    }
    text.push('\n');
    text.push_str(&body);
    Ok(text)
}
