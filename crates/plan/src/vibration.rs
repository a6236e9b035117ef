//! Vibration-aware planning: the shaper's design on the machine's lowest modes along the path
//! (from the linear model at rest at poses of the path), and the flexible check: the scene's
//! own model run on the planned motion, its unshaped variant and the scene's own motion, with
//! the residual vibration after each move.

use flexprr_kinematics::{GeometricPath, Impulse, Path, Pose};
use flexprr_linear_tools::linear::{OperatingPoint, operating_point};
use flexprr_planning::shaping::{self, Mode};
use flexprr_run::{RunError, RunResult, SceneVariant};
use flexprr_scene::{OutputKind, Scene, SceneFile};

use crate::error::PlanError;
use crate::pipeline::{PlanOutcome, build_scene};
use crate::variant::Unshaped;

/// Poses along the path at which the lowest modes are computed for the shaper.
pub const MODE_POSES: usize = 5;

/// The lowest modes at one pose of the path.
#[derive(Debug, Clone, PartialEq)]
pub struct ModesAt {
    /// Path parameter.
    pub s: f64,
    /// The pose.
    pub pose: Pose,
    /// The lowest modes (Hz and damping ratio), lowest first.
    pub modes: Vec<Mode>,
}

/// One shaped mode: its frequency range along the path and what the shaper leaves of it.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapedMode {
    /// Lowest and highest frequency along the path (Hz).
    pub range_hz: (f64, f64),
    /// Frequency at the end pose (Hz).
    pub end_hz: f64,
    /// The frequency the shaper is designed for: the middle of the range (Hz).
    pub design_hz: f64,
    /// Damping ratio at the end pose.
    pub damping: f64,
    /// Half the range relative to the design frequency.
    pub half_width: f64,
    /// The largest residual vibration of the shaper (Singer and Seering's percentage
    /// vibration, as a fraction) over the range, at the end pose's damping.
    pub worst_residual: f64,
}

/// The shaper of a plan and the modes it was designed for.
#[derive(Debug, Clone, PartialEq)]
pub struct ShapingDesign {
    /// The model whose linearisation gave the modes (`coupled` for a KED scene, whose
    /// platform is prescribed and has no whole-machine modes).
    pub model: String,
    /// The modes at each pose.
    pub poses: Vec<ModesAt>,
    /// The shaped modes.
    pub modes: Vec<ShapedMode>,
    /// The impulses (amplitude, delay).
    pub impulses: Vec<Impulse>,
}

/// The scene whose linear model gives the modes: the scene itself, or for a model that
/// prescribes the platform (KED) its coupled variant (a prescribed platform has no
/// whole-machine modes).
fn modal_scene(scene: &Scene) -> Result<(Scene, String), PlanError> {
    let mut file = scene.file.clone();
    file.output.requests.clear();
    file.plan = None;
    let model = if !scene.coupling.capabilities().free_platform {
        file.model.coupling = "coupled".to_string();
        "coupled (the scene's model prescribes the platform)".to_string()
    } else {
        scene.coupling.name().to_string()
    };
    Ok((build_scene(&scene.name, &file)?, model))
}

/// The lowest modes of `scene`'s machine at rest at `pose`.
fn modes_at(scene: &Scene, pose: Pose, count: usize) -> Result<Vec<Mode>, String> {
    let mut point =
        operating_point(scene, OperatingPoint::Rest(pose)).map_err(|e| e.to_string())?;
    let lin = flexprr_linear::linearize(point.model.as_mut(), point.t, &point.state, &[], &[])
        .map_err(|e| e.to_string())?;
    let mut modes: Vec<Mode> = flexprr_linear::modes(&lin)
        .map_err(|e| e.to_string())?
        .into_iter()
        .filter(|m| m.frequency_hz.is_finite() && m.frequency_hz > 0.0)
        .map(|m| Mode {
            frequency: m.frequency_hz,
            damping: m.damping_ratio.clamp(0.0, 0.99),
        })
        .collect();
    modes.sort_by(|a, b| a.frequency.total_cmp(&b.frequency));
    if modes.len() < count {
        return Err(format!(
            "the linear model has {} oscillatory modes, fewer than shaping_modes = {count}",
            modes.len()
        ));
    }
    modes.truncate(count);
    Ok(modes)
}

/// The shaper of `spec` on the machine's lowest `shaping_modes` modes: each mode's frequency
/// at [`MODE_POSES`] poses evenly along the path (the end pose among them), the shaper
/// designed for the middle of each mode's range (robust to the configuration dependence of
/// the frequencies; the width it must cover is reported, with the shaper's worst residual
/// over it).
///
/// # Errors
/// [`PlanError::Modes`] where the linear model fails (with the pose).
pub fn design_shaper(
    scene: &Scene,
    spec: &flexprr_planning::PlanSpec,
    path: &GeometricPath,
) -> Result<ShapingDesign, PlanError> {
    let (modal, model) = modal_scene(scene)?;
    let count = spec.shaping_modes;
    let length = path.length();
    let mut poses = Vec::with_capacity(MODE_POSES);
    for k in 0..MODE_POSES {
        let s = length * k as f64 / (MODE_POSES - 1) as f64;
        let pose = path.point(s).pose;
        let modes = modes_at(&modal, pose, count).map_err(|message| PlanError::Modes {
            scene: scene.name.clone(),
            at: format!(
                "s = {s:.6} (pose x = {:.6} m, y = {:.6} m, phi = {:.3} deg)",
                pose.x,
                pose.y,
                pose.phi.to_degrees()
            ),
            message,
        })?;
        poses.push(ModesAt { s, pose, modes });
    }
    let end = &poses[MODE_POSES - 1];
    let design: Vec<Mode> = (0..count)
        .map(|j| {
            let (lo, hi) = range(&poses, j);
            Mode {
                frequency: 0.5 * (lo + hi),
                damping: end.modes[j].damping,
            }
        })
        .collect();
    let impulses = spec.shaper(&design).map_err(|source| PlanError::Planning {
        scene: scene.name.clone(),
        stage: "the shaper",
        source: Box::new(source),
    })?;
    let modes = (0..count)
        .map(|j| {
            let (lo, hi) = range(&poses, j);
            let damping = end.modes[j].damping;
            let worst = (0..=40)
                .map(|i| {
                    let f = lo + (hi - lo) * i as f64 / 40.0;
                    shaping::residual_vibration(
                        &impulses,
                        Mode {
                            frequency: f,
                            damping,
                        },
                    )
                })
                .fold(0.0, f64::max);
            ShapedMode {
                range_hz: (lo, hi),
                end_hz: end.modes[j].frequency,
                design_hz: design[j].frequency,
                damping,
                half_width: (hi - lo) / (hi + lo),
                worst_residual: worst,
            }
        })
        .collect();
    Ok(ShapingDesign {
        model,
        poses,
        modes,
        impulses,
    })
}

fn range(poses: &[ModesAt], j: usize) -> (f64, f64) {
    poses.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), p| {
        (lo.min(p.modes[j].frequency), hi.max(p.modes[j].frequency))
    })
}

/// The links' deflection over one run of a motion, and its residual vibration.
#[derive(Debug, Clone, PartialEq)]
pub struct MotionVibration {
    /// Time (s).
    pub t: Vec<f64>,
    /// Largest `|w|` of any link at any requested `xi` at each time (m).
    pub deflection: Vec<f64>,
    /// When the move ends (s); `None` for a motion without an end.
    pub move_end: Option<f64>,
    /// Peak deflection during the move (m).
    pub peak_during: f64,
    /// Peak deflection after the move over the settling window (m): the residual vibration.
    pub residual: Option<f64>,
    /// Time of the residual's peak (s).
    pub residual_at: Option<f64>,
}

/// The flexible model's runs.
#[derive(Debug, Clone)]
pub struct FlexibleCheck {
    /// The model run (`KED`, `coupled`, `nonlinear`, with actuated sliders where the scene
    /// has control).
    pub model: String,
    /// The planned scene as run (its outputs the user's plus deflections and the viewer).
    pub planned_scene: Scene,
    /// Its run (written to `planned/`).
    pub planned_run: RunResult,
    /// The planned motion.
    pub planned: MotionVibration,
    /// The unshaped variant of a shaped plan.
    pub unshaped: Option<MotionVibration>,
    /// The scene's own motion (`Err`: its run failed, with why).
    pub original: Result<MotionVibration, String>,
    /// The settling window (s).
    pub settle_time: f64,
}

/// The file with the deflections (and the viewer, when `viewer`) among its requests.
pub(crate) fn with_deflections(file: &SceneFile, viewer: bool) -> SceneFile {
    let mut file = file.clone();
    let requests = &mut file.output.requests;
    let mut wanted = vec![OutputKind::Deflections];
    if viewer {
        wanted.extend([
            OutputKind::Kinematics,
            OutputKind::DrivingForces,
            OutputKind::Viewer,
        ]);
    }
    for kind in wanted {
        if !requests.contains(&kind) {
            requests.push(kind);
        }
    }
    file
}

/// Runs `scene`; the error names the motion.
pub(crate) fn run(scene: &Scene, motion: &'static str) -> Result<RunResult, PlanError> {
    flexprr_run::run(scene, &mut |_| {}).map_err(|f| PlanError::Run {
        scene: scene.name.clone(),
        motion,
        source: Box::new(f.error),
    })
}

/// The deflection history of a run and its residual vibration after `move_end`.
pub fn vibration_of(result: &RunResult, move_end: Option<f64>, settle: f64) -> MotionVibration {
    let (t, deflection) = match result.table("deflections") {
        Some(table) => {
            let columns: Vec<&[f64]> = table
                .columns
                .iter()
                .zip(&table.data)
                .filter(|(c, _)| c.quantity == flexprr_run::Quantity::Deflection)
                .map(|(_, d)| d.as_slice())
                .collect();
            let w = (0..table.rows())
                .map(|i| columns.iter().map(|c| c[i].abs()).fold(0.0, f64::max))
                .collect();
            (table.time().to_vec(), w)
        }
        None => (Vec::new(), Vec::new()),
    };
    let peak = |lo: f64, hi: f64| {
        t.iter()
            .zip(&deflection)
            .filter(|(ti, _)| **ti > lo && **ti <= hi)
            .fold(None, |best: Option<(f64, f64)>, (ti, w)| match best {
                Some((_, b)) if b >= *w => best,
                _ => Some((*ti, *w)),
            })
    };
    let peak_during =
        peak(f64::NEG_INFINITY, move_end.unwrap_or(f64::INFINITY)).map_or(0.0, |(_, w)| w);
    let after = move_end.and_then(|end| peak(end, end + settle * (1.0 + 1e-12)));
    MotionVibration {
        move_end,
        peak_during,
        residual: after.map(|(_, w)| w),
        residual_at: after.map(|(t, _)| t),
        t,
        deflection,
    }
}

/// The flexible check of a plan: the scene's model on the planned motion, on its unshaped
/// variant (a shaped plan) and on the scene's own motion.
///
/// # Errors
/// A run of the planned or unshaped motion that fails (with its time).
pub fn flexible_check(
    scene: &Scene,
    outcome: &PlanOutcome,
    progress: &mut dyn FnMut(&str),
) -> Result<FlexibleCheck, PlanError> {
    let rest = outcome.plan.boundary == flexprr_planning::Boundary::RestToRest;
    let settle = outcome.settle_time;
    progress("running the planned motion on the scene's flexible model");
    let planned_scene = build_scene(
        &outcome.scene,
        &with_deflections(&outcome.planned_file, true),
    )?;
    let planned_run = run(&planned_scene, "the planned motion")?;
    let end = rest.then_some(outcome.start + outcome.plan.duration);
    let planned = vibration_of(&planned_run, end, settle);
    let unshaped_vibration = if outcome.plan.impulses.is_empty() {
        None
    } else {
        progress("running the unshaped motion");
        let shaped = build_scene(
            &outcome.scene,
            &with_deflections(&outcome.planned_file, false),
        )?;
        let variant = match Unshaped.transform(&shaped) {
            Ok(Some(variant)) => variant,
            Ok(None) => shaped,
            Err(RunError::Scene(e)) => {
                return Err(PlanError::PlannedScene {
                    scene: outcome.scene.clone(),
                    source: Box::new(e),
                });
            }
            Err(e) => {
                return Err(PlanError::Run {
                    scene: outcome.scene.clone(),
                    motion: "the unshaped motion",
                    source: Box::new(e),
                });
            }
        };
        let result = run(&variant, "the unshaped motion")?;
        let end = outcome.start + outcome.plan.timing.duration() + outcome.plan.smoothing;
        Some(vibration_of(&result, rest.then_some(end), settle))
    };
    progress("running the scene's own motion");
    let original = build_scene(&outcome.scene, &with_deflections(&scene.file, false))
        .and_then(|s| run(&s, "the scene's own motion"))
        .map(|r| {
            let end = match &scene.file.trajectory {
                flexprr_scene::TrajectoryConfig::PointToPoint {
                    start, duration, ..
                } => Some(start + duration),
                _ => None,
            };
            vibration_of(&r, end, settle)
        })
        .map_err(|e| e.to_string());
    Ok(FlexibleCheck {
        model: planned_scene.model_description(),
        planned_scene,
        planned_run,
        planned,
        unshaped: unshaped_vibration,
        original,
        settle_time: settle,
    })
}
