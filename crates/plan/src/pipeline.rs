//! The plan of a scene: its `[plan]` settings, its path, the orientation search, the
//! time-optimal (and shaped) plan, the comparison with the scene's own timing, and the
//! planned scene.

use flexprr_kinematics::{
    GeometricPath, Orientation, Path, PlannedData, PlannedTrajectory, Profile,
};
use flexprr_planning::{
    Boundary, Check, ConstantPhi, FreePhi, PhiMode, Plan, PlanSpec, Planner, PlanningError,
    Schedule,
};
use flexprr_scene::{ProfileChoice, Scene, SceneFile, TrajectoryConfig};

use crate::deflection::{self, DeflectionSearch, Retiming};
use crate::error::PlanError;
use crate::variant::planned_scene_file;
use crate::vibration::{self, FlexibleCheck, ShapingDesign};

/// Settling window after a move when neither `[plan] settle_time` nor the scene's own time
/// after its move gives one (s).
pub const DEFAULT_SETTLE_TIME: f64 = 0.1;

/// What `flexprr plan` computes beyond the plan itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Options {
    /// Run the scene's flexible model on the planned motion (and on the unshaped motion and
    /// the scene's own motion): the residual vibration and the deflection figures.
    pub flexible_check: bool,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            flexible_check: true,
        }
    }
}

/// The scene's own timing of its path, checked against the plan's limits.
#[derive(Debug, Clone)]
pub struct SceneTiming {
    /// The scene's move duration (rest-to-rest) or period (a circle), s.
    pub duration: f64,
    /// Whether it repeats.
    pub periodic: bool,
    /// The dense check of the scene's timing against every limit (`Err`: the timing leaves
    /// the path's workspace somewhere, with the reason).
    pub check: Result<Check, String>,
}

/// The orientation search's results (with `phi` other than `fixed`).
#[derive(Debug, Clone)]
pub enum OrientationSearch {
    /// The best constant orientation.
    Constant(Box<ConstantPhi>),
    /// A free law along the path, from the best constant.
    Free {
        /// The best constant (the free search's start).
        constant: Box<ConstantPhi>,
        /// The free law.
        free: Box<FreePhi>,
    },
}

/// Everything `flexprr plan` found for a scene.
#[derive(Debug, Clone)]
pub struct PlanOutcome {
    /// The scene's name.
    pub scene: String,
    /// The settings.
    pub spec: PlanSpec,
    /// The scene's path (its own orientation).
    pub base_path: GeometricPath,
    /// The path planned (oriented when `phi` is not `fixed`).
    pub path: GeometricPath,
    /// The plan (shaped when `shaping` is set).
    pub plan: Plan,
    /// The time-optimal plan without shaping, when the plan is shaped.
    pub unshaped: Option<Plan>,
    /// The shaper's design (modes along the path), when the plan is shaped.
    pub shaping: Option<ShapingDesign>,
    /// Start time of the planned motion (s).
    pub start: f64,
    /// The planned motion as data (the planned scene's trajectory).
    pub data: PlannedData,
    /// The planned scene: the scene with the planned motion, `[plan]` removed.
    pub planned_file: SceneFile,
    /// The scene's own timing, checked against the same limits.
    pub scene_timing: SceneTiming,
    /// The orientation search, with `phi` other than `fixed`.
    pub orientation: Option<OrientationSearch>,
    /// The settling window of the residual vibration (s).
    pub settle_time: f64,
    /// The scene's flexible model on the planned motion, the unshaped one and the scene's
    /// own (with [`Options::flexible_check`]).
    pub flexible: Option<FlexibleCheck>,
    /// The deflection limit's search, with `[plan] deflection_limit`.
    pub deflection: Option<DeflectionSearch>,
    /// Wall time of the whole pipeline (s).
    pub wall_time_s: f64,
    /// The scene planned (its machine and axial-force model draw the limit curves).
    pub source: Scene,
}

impl PlanOutcome {
    /// The planned scene, built (runnable as it is).
    ///
    /// # Errors
    /// The scene builder's refusal (never for a plan this pipeline made).
    pub fn planned_scene(&self) -> Result<Scene, PlanError> {
        build_scene(&self.scene, &self.planned_file)
    }
}

/// Builds a derived scene file (checked like any scene, located in the planned file's text).
pub(crate) fn build_scene(name: &str, file: &SceneFile) -> Result<Scene, PlanError> {
    let text = crate::variant::scene_toml(file, "").unwrap_or_default();
    let label = format!("{name} (planned)");
    Scene::from_file(&label, &text, file.clone(), name).map_err(|e| PlanError::PlannedScene {
        scene: name.to_string(),
        source: Box::new(e),
    })
}

/// The scene's own timing of its path, as a [`Schedule`] of the path parameter, and the
/// start time and duration of its move (`None`: a motion without an end).
fn scene_schedule(
    config: &TrajectoryConfig,
    length: f64,
    span: (f64, f64),
) -> (Schedule, f64, Option<f64>) {
    match config {
        TrajectoryConfig::Circle { frequency, .. } => {
            (Schedule::revolution(length, frequency.abs()), span.0, None)
        }
        TrajectoryConfig::Line { .. } => {
            let duration = span.1 - span.0;
            (
                Schedule::ConstantSpeed {
                    speed: length / duration,
                    duration,
                },
                span.0,
                None,
            )
        }
        TrajectoryConfig::PointToPoint {
            start,
            duration,
            profile,
            ..
        } => (
            Schedule::Profile {
                profile: match profile {
                    ProfileChoice::Quintic => Profile::Quintic,
                    ProfileChoice::Cycloidal => Profile::Cycloidal,
                },
                duration: *duration,
            },
            *start,
            Some(start + duration),
        ),
        TrajectoryConfig::Waypoints { points } => {
            let t0 = points.first().map_or(0.0, |p| p[0]);
            (
                Schedule::ConstantSpeed {
                    speed: 1.0,
                    duration: length,
                },
                t0,
                Some(t0 + length),
            )
        }
        TrajectoryConfig::Planned(data) => {
            let timing =
                flexprr_kinematics::Timing::new(data.s.clone(), data.s_dot.clone(), data.periodic);
            match timing {
                Ok(timing) => {
                    let d = timing.duration();
                    let end = (!data.periodic).then_some(data.start + d);
                    (Schedule::Timing(timing), data.start, end)
                }
                Err(_) => (
                    Schedule::ConstantSpeed {
                        speed: 1.0,
                        duration: length,
                    },
                    data.start,
                    None,
                ),
            }
        }
    }
}

/// The dense check of `schedule` against the planner's limits.
fn check_schedule(
    planner: &Planner<'_>,
    schedule: &Schedule,
    length: f64,
) -> Result<Check, String> {
    let duration = schedule.duration();
    let n = planner.settings().grid.max(1);
    let breakpoints: Vec<f64> = (0..=n).map(|k| duration * k as f64 / n as f64).collect();
    planner
        .check_timing(
            &breakpoints,
            (0.0, duration),
            planner.settings().check_factor.max(1),
            |t| schedule.state(length, t),
            None,
        )
        .map_err(|e| e.to_string())
}

/// The flexible check of `outcome`'s plan, and with `[plan] deflection_limit` the plan slowed
/// until the flexible model meets it (checked again on the slowed plan).
fn flexible_stage(
    scene: &Scene,
    outcome: &mut PlanOutcome,
    retiming: &Retiming<'_>,
    progress: &mut dyn FnMut(&str),
) -> Result<(), PlanError> {
    let check = vibration::flexible_check(scene, outcome, progress)?;
    let Some(limit) = outcome.spec.deflection_limit else {
        outcome.flexible = Some(check);
        return Ok(());
    };
    let peak = deflection::peak_deflection(&check.planned_run);
    let search = deflection::meet_limit(outcome, limit, peak, retiming, progress)?;
    outcome.flexible = Some(if search.binds() {
        vibration::flexible_check(scene, outcome, progress)?
    } else {
        check
    });
    outcome.deflection = Some(search);
    Ok(())
}

/// Plans `scene` by its `[plan]` section (docs/planning.md): the path its trajectory sweeps,
/// the orientation search (with `phi` other than `fixed`), the time-optimal motion within
/// every limit, checked between grid points, shaped on the machine's lowest modes when
/// `shaping` is set, the scene's own timing checked against the same limits, the planned
/// scene, and (with [`Options::flexible_check`]) the scene's flexible model run on the
/// planned motion for its residual vibration. `progress` receives a line for each stage.
///
/// # Errors
/// [`PlanError`]: no `[plan]`, a path the planner refuses, a limit no motion can meet (the
/// limit and where), a failed run of the flexible model (with its time).
pub fn plan_scene(
    scene: &Scene,
    options: Options,
    progress: &mut dyn FnMut(&str),
) -> Result<PlanOutcome, PlanError> {
    let clock = std::time::Instant::now();
    let name = scene.name.clone();
    let spec = scene.file.plan.clone().ok_or_else(|| PlanError::NoPlan {
        scene: name.clone(),
    })?;
    if let (Some(limit), false) = (spec.deflection_limit, options.flexible_check) {
        return Err(PlanError::DeflectionLimit {
            scene: name,
            limit,
            detail: "the limit is checked on the scene's flexible model, which --no-flexible-check (flexible_check = False) turns off: drop one or the other".into(),
        });
    }
    let planning = |stage: &'static str| planning_error(&name, stage);
    let times = &scene.output_times;
    let span = (times[0], times[times.len() - 1]);
    let base_path =
        flexprr_scene::path_of(&scene.file.trajectory, span.0, span.1).map_err(|source| {
            PlanError::Path {
                scene: name.clone(),
                source,
            }
        })?;
    let length = base_path.length();
    let (schedule, scene_start, scene_end) = scene_schedule(&scene.file.trajectory, length, span);
    let planner = limited_planner(scene, &spec, &base_path)?;
    let (path, orientation) = orient(scene, &planner, &spec, &schedule, &base_path, progress)?;

    // The time-optimal plan, then the shaped one.
    let oriented_planner = planner.on_path(&path, spec.settings());
    let (plan, unshaped, shaping) =
        plan_motion(scene, &spec, &planner, &oriented_planner, &path, progress)?;
    let start = match spec.boundary {
        Boundary::Periodic => span.0,
        Boundary::RestToRest => scene_start,
    };
    // The scene's own timing against the same limits (on the scene's own path: the
    // orientation is the scene's there).
    let scene_check = check_schedule(&planner, &schedule, length);
    let scene_timing = SceneTiming {
        duration: schedule.duration(),
        periodic: scene_end.is_none() && base_path.is_closed(),
        check: scene_check,
    };

    // The planned scene's span.
    let own_settle = match scene_end {
        Some(end) if span.1 - end > 0.0 => span.1 - end,
        _ => DEFAULT_SETTLE_TIME,
    };
    let settle_time = spec.settle_time.unwrap_or(own_settle);
    let revolutions = ((span.1 - span.0) / schedule.duration()).round().max(1.0);
    let boundary = spec.boundary;
    // The outcome's motion, planned scene and span for a plan.
    let apply = |outcome: &mut PlanOutcome, plan: Plan| -> Result<(), PlanError> {
        let end = match boundary {
            Boundary::Periodic => span.0 + revolutions * plan.duration,
            Boundary::RestToRest => start + plan.duration + settle_time,
        };
        let trajectory: PlannedTrajectory<GeometricPath> = plan
            .trajectory(outcome.path.clone(), start)
            .map_err(planning("the planned trajectory"))?;
        outcome.data = PlannedData::from(&trajectory);
        outcome.planned_file = planned_scene_file(&scene.file, outcome.data.clone(), end);
        outcome.plan = plan;
        Ok(())
    };
    let mut outcome = PlanOutcome {
        scene: name.clone(),
        spec,
        base_path: base_path.clone(),
        path: path.clone(),
        plan: plan.clone(),
        unshaped,
        shaping,
        start,
        planned_file: scene.file.clone(),
        data: PlannedData::from(
            &plan
                .trajectory(path.clone(), start)
                .map_err(planning("the planned trajectory"))?,
        ),
        scene_timing,
        orientation,
        settle_time,
        flexible: None,
        deflection: None,
        wall_time_s: 0.0,
        source: scene.clone(),
    };
    apply(&mut outcome, plan)?;
    if options.flexible_check {
        let retiming = Retiming {
            planner: &oriented_planner,
            apply: &apply,
        };
        flexible_stage(scene, &mut outcome, &retiming, progress)?;
    }
    outcome.wall_time_s = clock.elapsed().as_secs_f64();
    Ok(outcome)
}

/// The `PlanError::Planning` of scene `name` at `stage`.
fn planning_error(name: &str, stage: &'static str) -> impl FnOnce(PlanningError) -> PlanError {
    let name = name.to_string();
    move |source: PlanningError| PlanError::Planning {
        scene: name,
        stage,
        source: Box::new(source),
    }
}

/// The planner of `scene`'s path under every limit of its `[plan]`: the boxed limits, the
/// RMS limit of its motor and the slider jerk.
fn limited_planner<'a>(
    scene: &'a Scene,
    spec: &PlanSpec,
    base_path: &'a GeometricPath,
) -> Result<Planner<'a>, PlanError> {
    let planning = |stage: &'static str| planning_error(&scene.name, stage);
    let motor = flexprr_scene::motor_of(&scene.file);
    let constraints = spec
        .constraints(&scene.machine, motor.as_ref())
        .map_err(planning("the limits"))?;
    let mut planner = Planner::new(&scene.machine, base_path, spec.settings())
        .axial_model(scene.axial_model.as_ref());
    for c in constraints {
        planner = planner.boxed(c);
    }
    if let Some(rms) = spec
        .rms(motor.as_ref())
        .map_err(planning("the RMS limit"))?
    {
        planner = planner.rms(rms);
    }
    if let Some(jerk) = spec.slider_jerk {
        planner = planner.jerk(jerk);
    }
    Ok(planner)
}

/// The orientation along the path: the scene's own with `phi = "fixed"` (or without a
/// search), else the best constant orientation and, with `phi = "free"`, a free law from it.
fn orient(
    scene: &Scene,
    planner: &Planner<'_>,
    spec: &PlanSpec,
    schedule: &Schedule,
    base_path: &GeometricPath,
    progress: &mut dyn FnMut(&str),
) -> Result<(GeometricPath, Option<OrientationSearch>), PlanError> {
    let name = scene.name.clone();
    let planning = |stage: &'static str| planning_error(&name, stage);
    let search = spec
        .phi_search(Some(schedule.clone()))
        .map_err(planning("the orientation"))?;
    Ok(match (spec.phi, search) {
        (PhiMode::Fixed, _) | (_, None) => (base_path.clone(), None),
        (mode, Some(search)) => {
            progress("searching the best constant orientation");
            let constant = planner
                .best_constant_phi(&search)
                .map_err(planning("the best constant orientation"))?;
            let (law, found) = if mode == PhiMode::Free {
                progress("searching a free orientation along the path");
                let free = planner
                    .free_phi(&search, &constant)
                    .map_err(planning("the free orientation"))?;
                (
                    free.orientation.clone(),
                    OrientationSearch::Free {
                        constant: Box::new(constant),
                        free: Box::new(free),
                    },
                )
            } else {
                (
                    Orientation::constant(constant.phi),
                    OrientationSearch::Constant(Box::new(constant)),
                )
            };
            let oriented = law
                .on(base_path.clone())
                .map_err(|source| PlanError::Path {
                    scene: name.clone(),
                    source,
                })?;
            (GeometricPath::Oriented(Box::new(oriented)), Some(found))
        }
    })
}

/// The time-optimal motion along `path` (planned by `oriented`, the planner on that path)
/// and, when `[plan] shaping` is set, the motion shaped on the machine's lowest modes along
/// it: the plan, the unshaped plan and the shaper's design (the last two with shaping only).
fn plan_motion(
    scene: &Scene,
    spec: &PlanSpec,
    planner: &Planner<'_>,
    oriented: &Planner<'_>,
    path: &GeometricPath,
    progress: &mut dyn FnMut(&str),
) -> Result<(Plan, Option<Plan>, Option<ShapingDesign>), PlanError> {
    let planning = |stage: &'static str| planning_error(&scene.name, stage);
    progress("planning the time-optimal motion");
    let optimal = oriented
        .plan()
        .map_err(planning("the time-optimal motion"))?;
    if spec.shaping == flexprr_planning::Shaping::None {
        return Ok((optimal, None, None));
    }
    progress("the machine's lowest modes along the path (linear model)");
    let design = vibration::design_shaper(scene, spec, path)?;
    let shaped = planner
        .on_path(path, spec.settings())
        .shaper(design.impulses.clone())
        .plan()
        .map_err(planning("the shaped motion"))?;
    Ok((shaped, Some(optimal), Some(design)))
}
