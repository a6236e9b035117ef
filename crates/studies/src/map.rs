//! Workspace maps (`[map]` in a study file, `docs/studies.md`, "Workspace maps"): a
//! quantity of the whole machine at rest over a grid of platform poses at one orientation,
//! for now the lowest whole-machine frequency (`lowest_frequency`, docs/linear.md): the base
//! scene's model held at rest at each pose, sliders locked or held by the scene's control
//! law, linearised, its lowest non-zero frequency. Poses out of reach (a leg that does not
//! assemble, a slider beyond its travel) and singular ones (type I, or type II closer than
//! the geometry's threshold) are marked, not failures of the map.
//!
//! The poses run in parallel on the study's worker threads; `map.csv` (one row per pose),
//! `map.json` (the settings and a summary) and `map.svg` (the heat map with the reachable
//! set's boundary, the type-II locus and the scene's path) are written together at the end.

use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use flexprr_kinematics::Pose;
use flexprr_linear_tools::machine_modes::{
    RestFrequency, rest_frequency, sliders_description, start_pose,
};
use flexprr_scene::Scene;
use serde::{Deserialize, Serialize};

use crate::error::StudyError;
use crate::file::{RangeConfig, Spacing};
use crate::record::format_value;
use crate::study::Study;

/// Most grid points along either axis of a map.
pub const MAX_GRID: usize = 1000;

/// `[map]` as written.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MapConfig {
    /// The platform reference point's `x` (m): `start`, `end`, `count` (linear).
    pub x: RangeConfig,
    /// Its `y` (m).
    pub y: RangeConfig,
    /// The platform's orientation (deg); default: the base scene's start orientation.
    #[serde(default)]
    pub phi_deg: Option<f64>,
    /// What is mapped.
    #[serde(default)]
    pub quantity: MapQuantity,
}

/// What a map shows at each pose.
#[derive(Debug, Clone, Copy, Default, Deserialize, Serialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum MapQuantity {
    /// The lowest whole-machine natural frequency at rest (Hz), with its damping ratio.
    #[default]
    LowestFrequency,
}

impl MapQuantity {
    /// The name in study files.
    pub fn name(self) -> &'static str {
        match self {
            MapQuantity::LowestFrequency => "lowest_frequency",
        }
    }
}

/// A checked `[map]`: the grid's abscissae and ordinates and the orientation.
#[derive(Debug, Clone, PartialEq)]
pub struct Map {
    /// Grid abscissae (m), increasing.
    pub x: Vec<f64>,
    /// Grid ordinates (m), increasing.
    pub y: Vec<f64>,
    /// The orientation as written (deg), or `None` for the base scene's start orientation.
    pub phi_deg: Option<f64>,
    /// What is mapped.
    pub quantity: MapQuantity,
}

impl Map {
    /// Checks `[map]`: finite linear ranges from `start` to a larger `end`, 2 to
    /// [`MAX_GRID`] points each, a finite orientation.
    ///
    /// # Errors
    /// A `(key, message)` pair for the first bad value.
    pub fn from_config(c: &MapConfig) -> Result<Self, (String, String)> {
        let axis = |name: &str, r: &RangeConfig| -> Result<Vec<f64>, (String, String)> {
            let key = format!("map.{name}");
            if !(r.start.is_finite() && r.end.is_finite() && r.start < r.end) {
                return Err((
                    key,
                    format!(
                        "expected finite start < end (m), got start = {:?} and end = {:?}",
                        r.start, r.end
                    ),
                ));
            }
            if !(2..=MAX_GRID).contains(&r.count) {
                return Err((
                    format!("{key}.count"),
                    format!(
                        "expected 2 to {MAX_GRID} grid points, got {}: a map needs both ends of each axis, and {MAX_GRID} x {MAX_GRID} poses are already hours of linearisations",
                        r.count
                    ),
                ));
            }
            if r.spacing != Spacing::Linear {
                return Err((
                    format!("{key}.spacing"),
                    "a map's grid is evenly spaced (linear): positions can be negative".into(),
                ));
            }
            Ok(r.values())
        };
        if let Some(Err(message)) = c
            .phi_deg
            .map(flexprr_linear_tools::linear::check_orientation_deg)
        {
            return Err(("map.phi_deg".into(), message));
        }
        Ok(Self {
            x: axis("x", &c.x)?,
            y: axis("y", &c.y)?,
            phi_deg: c.phi_deg,
            quantity: c.quantity,
        })
    }

    /// The orientation of the map for the base scene `scene` (rad).
    pub fn phi(&self, scene: &Scene) -> f64 {
        self.phi_deg
            .map_or_else(|| start_pose(scene).phi, f64::to_radians)
    }

    /// The poses of the grid, `y` slowest (row by row from the lowest `y`).
    pub fn poses(&self, phi: f64) -> Vec<Pose> {
        self.y
            .iter()
            .flat_map(|&y| self.x.iter().map(move |&x| Pose::new(x, y, phi)))
            .collect()
    }
}

/// Progress of a map after a pose is done.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MapProgress {
    /// Poses of the map.
    pub total: usize,
    /// Poses done.
    pub done: usize,
    /// Of those, out of reach.
    pub unreachable: usize,
    /// Singular.
    pub singular: usize,
    /// Failed.
    pub failed: usize,
}

/// What a map computed.
#[derive(Debug, Clone, PartialEq)]
pub struct MapOutcome {
    /// The orientation (rad).
    pub phi: f64,
    /// Each pose and its value, `y` slowest.
    pub points: Vec<(Pose, RestFrequency)>,
    /// The final counts.
    pub progress: MapProgress,
    /// Wall-clock time of the poses (s).
    pub wall_time_s: f64,
    /// Worker threads.
    pub threads: usize,
}

/// The base scene of a map study (with `[set]`): its one case's scene.
///
/// # Errors
/// [`StudyError::Input`] when the scene is not valid (checked at load already).
pub fn map_scene(study: &Study) -> Result<Scene, StudyError> {
    let case = study.cases.first().ok_or_else(|| StudyError::Input {
        file: study.file.clone(),
        location: None,
        key: "map".into(),
        message: "the study has no base scene".into(),
    })?;
    study.case_scene(case).map_err(StudyError::Scene)
}

/// Computes `map` for the base scene `scene` on `threads` workers; `on_pose` sees the
/// progress after every pose (from the workers).
///
/// # Errors
/// [`StudyError::Io`] when the workers cannot start.
pub fn run_map(
    study: &Study,
    map: &Map,
    scene: &Scene,
    threads: usize,
    on_pose: &(dyn Fn(&MapProgress) + Sync),
) -> Result<MapOutcome, StudyError> {
    use rayon::prelude::*;
    let clock = Instant::now();
    let phi = map.phi(scene);
    let poses = map.poses(phi);
    let counters: [AtomicUsize; 4] = Default::default();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| StudyError::Io {
            path: study.file.clone(),
            source: std::io::Error::other(format!("cannot start worker threads: {e}")),
        })?;
    let total = poses.len();
    let points: Vec<(Pose, RestFrequency)> = pool.install(|| {
        poses
            .par_iter()
            .map(|&pose| {
                let value = match map.quantity {
                    MapQuantity::LowestFrequency => rest_frequency(scene, pose),
                };
                let slot = match &value {
                    RestFrequency::Found { .. } => None,
                    RestFrequency::Unreachable(_) => Some(1),
                    RestFrequency::Singular(_) => Some(2),
                    RestFrequency::Failed(_) => Some(3),
                };
                if let Some(k) = slot {
                    counters[k].fetch_add(1, Ordering::SeqCst);
                }
                let done = counters[0].fetch_add(1, Ordering::SeqCst) + 1;
                on_pose(&MapProgress {
                    total,
                    done,
                    unreachable: counters[1].load(Ordering::SeqCst),
                    singular: counters[2].load(Ordering::SeqCst),
                    failed: counters[3].load(Ordering::SeqCst),
                });
                (pose, value)
            })
            .collect()
    });
    let count = |k: usize| counters[k].load(Ordering::SeqCst);
    Ok(MapOutcome {
        phi,
        points,
        progress: MapProgress {
            total,
            done: count(0),
            unreachable: count(1),
            singular: count(2),
            failed: count(3),
        },
        wall_time_s: clock.elapsed().as_secs_f64(),
        threads,
    })
}

/// The status word of a pose in `map.csv`.
fn status(value: &RestFrequency) -> &'static str {
    match value {
        RestFrequency::Found { .. } => "ok",
        RestFrequency::Unreachable(_) => "unreachable",
        RestFrequency::Singular(_) => "singular",
        RestFrequency::Failed(_) => "failed",
    }
}

/// `map.csv`: `x_m, y_m, phi_deg, status, lowest_frequency_Hz, damping_ratio,
/// type_ii_measure, error`, one row per pose, `y` slowest; numbers as in `results.csv`
/// (10 significant digits, shortest form), empty where a pose has none.
///
/// # Errors
/// [`StudyError::Directory`] if the CSV writer fails.
pub fn map_csv(outcome: &MapOutcome) -> Result<Vec<u8>, StudyError> {
    let err = |e: &dyn std::fmt::Display| StudyError::Directory {
        dir: "map.csv".into(),
        message: e.to_string(),
    };
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "x_m",
        "y_m",
        "phi_deg",
        "status",
        "lowest_frequency_Hz",
        "damping_ratio",
        "type_ii_measure",
        "error",
    ])
    .map_err(|e| err(&e))?;
    let phi = format_value(outcome.phi.to_degrees());
    for (pose, value) in &outcome.points {
        let (f, zeta, measure, error) = match value {
            RestFrequency::Found {
                frequency_hz,
                damping_ratio,
                type_ii_measure,
            } => (
                format_value(*frequency_hz),
                format_value(*damping_ratio),
                format_value(*type_ii_measure),
                String::new(),
            ),
            RestFrequency::Unreachable(m)
            | RestFrequency::Singular(m)
            | RestFrequency::Failed(m) => (String::new(), String::new(), String::new(), m.clone()),
        };
        w.write_record([
            format_value(pose.x),
            format_value(pose.y),
            phi.clone(),
            status(value).to_string(),
            f,
            zeta,
            measure,
            error,
        ])
        .map_err(|e| err(&e))?;
    }
    w.into_inner().map_err(|e| err(&e))
}

/// The lowest and highest value of a map with their poses.
fn extremes(outcome: &MapOutcome) -> Option<((f64, Pose), (f64, Pose))> {
    let found = outcome.points.iter().filter_map(|(pose, v)| match v {
        RestFrequency::Found { frequency_hz, .. } => Some((*frequency_hz, *pose)),
        _ => None,
    });
    let mut lowest: Option<(f64, Pose)> = None;
    let mut highest: Option<(f64, Pose)> = None;
    for (f, pose) in found {
        if lowest.is_none_or(|(l, _)| f < l) {
            lowest = Some((f, pose));
        }
        if highest.is_none_or(|(h, _)| f > h) {
            highest = Some((f, pose));
        }
    }
    Some((lowest?, highest?))
}

/// `map.json`: the study, the scene's model and sliders, the grid, the counts, the lowest
/// and highest value and where, the time.
pub fn map_json(
    study: &Study,
    map: &Map,
    scene: &Scene,
    outcome: &MapOutcome,
) -> serde_json::Value {
    let at = |(f, pose): (f64, Pose)| serde_json::json!({ "frequency_hz": f, "x_m": pose.x, "y_m": pose.y });
    let (lowest, highest) = match extremes(outcome) {
        Some((l, h)) => (at(l), at(h)),
        None => (serde_json::Value::Null, serde_json::Value::Null),
    };
    let p = &outcome.progress;
    serde_json::json!({
        "study": study.name,
        "fingerprint": study.fingerprint,
        "scene": scene.name,
        "model": scene.model_description(),
        "sliders": sliders_description(scene),
        "quantity": map.quantity.name(),
        "grid": {
            "x_m": { "start": map.x[0], "end": map.x[map.x.len() - 1], "count": map.x.len() },
            "y_m": { "start": map.y[0], "end": map.y[map.y.len() - 1], "count": map.y.len() },
            "phi_deg": map.phi_deg.unwrap_or_else(|| outcome.phi.to_degrees()),
        },
        "poses": {
            "total": p.total,
            "ok": p.total - p.unreachable - p.singular - p.failed,
            "unreachable": p.unreachable,
            "singular": p.singular,
            "failed": p.failed,
        },
        "lowest": lowest,
        "highest": highest,
        "wall_time_s": outcome.wall_time_s,
        "threads": outcome.threads,
    })
}

/// Writes `map.csv`, `map.json` and `map.svg` into `dir`.
///
/// # Errors
/// [`StudyError::Io`] when a file cannot be written.
pub fn write_map_files(
    study: &Study,
    map: &Map,
    scene: &Scene,
    outcome: &MapOutcome,
    dir: &Path,
) -> Result<(), StudyError> {
    let write = |name: &str, bytes: &[u8]| {
        let path = dir.join(name);
        std::fs::write(&path, bytes).map_err(|source| StudyError::Io {
            path: path.display().to_string(),
            source,
        })
    };
    write("map.csv", &map_csv(outcome)?)?;
    let json = map_json(study, map, scene, outcome);
    write(
        "map.json",
        &serde_json::to_vec_pretty(&json).unwrap_or_default(),
    )?;
    let svg = crate::map_figure::map_svg(map, scene, outcome);
    write("map.svg", svg.as_bytes())
}
