//! The whole machine's modes at an operating point (docs/linear.md, `flexprr modes`): the
//! scene's model linearised there ([`crate::linear`], `flexprr_linear::linearize`) with the
//! shape outputs (slider positions, platform pose, each link's deflection at
//! [`SHAPE_POINTS`] points), its eigenvalues (`flexprr_linear::modes`), each mode's shape in
//! physical terms and a short classification of it; the files `modes.json`, `modes.csv` and
//! `modes.svg` ([`MODES_PRODUCTS`]).
//!
//! The lowest frequency alone ([`lowest_frequency`]) skips the shape outputs: what a
//! workspace map needs at each of its poses.

mod figure;
mod report;
mod shape;

use std::borrow::Cow;
use std::time::Instant;

use flexprr_kinematics::Pose;
use flexprr_linear::{
    Axis, Complex, Input, LinearError, Output, Settings, linearize, linearize_with_settings, modes,
};
use flexprr_scene::Scene;

use crate::linear::{OperatingPoint, operating_point};
use flexprr_outdir::Products;
use flexprr_run::RunError;

pub use figure::modes_svg;
pub use report::{modes_csv, modes_json, modes_summary_json};
pub use shape::ModeShape;

/// Points along each link (equally spaced from `xi = 0` to `1`) at which mode shapes are
/// given.
pub const SHAPE_POINTS: usize = 21;

/// The files of `flexprr modes --out` (docs/linear.md): what the output-directory policy
/// refuses to write over and recognises an earlier output by.
pub const MODES_PRODUCTS: Products = Products {
    kind: "modes",
    names: Cow::Borrowed(&["modes.json", "modes.csv", "modes.svg"]),
    patterns: Cow::Borrowed(&[]),
    legacy: None,
};

/// One whole-machine mode with its shape.
#[derive(Debug, Clone, PartialEq)]
pub struct MachineMode {
    /// The eigenvalue `lambda` (1/s): in discrete time `ln(z) / dt`.
    pub eigenvalue: Complex,
    /// The pole `z` of a discrete-time model (`None` in continuous time).
    pub z: Option<Complex>,
    /// `|lambda| / 2 pi` (Hz), the undamped natural frequency.
    pub frequency_hz: f64,
    /// `-Re(lambda) / |lambda|` (MATLAB's `damp`).
    pub damping_ratio: f64,
    /// What moves most: `servo` (the sliders on their control loops), `platform` (the
    /// platform on the links' axial stiffness), or `bending link 2`, `bending links 1, 3`
    /// with the number of half-waves of the dominant link.
    pub kind: String,
    /// The shape: sliders, platform and links.
    pub shape: ModeShape,
}

/// Wall-clock times of one modal analysis (s).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ModesTiming {
    /// Building the model at the operating point (and integrating to a time).
    pub model_s: f64,
    /// The linearisation (`A`, and `C` for the shape outputs).
    pub linearisation_s: f64,
    /// Balancing, the eigenvalues and eigenvectors, the shapes.
    pub eigen_s: f64,
}

/// The whole machine's modes at an operating point.
#[derive(Debug, Clone, PartialEq)]
pub struct MachineModes {
    /// The scene's name.
    pub scene: String,
    /// The scene's model as `flexprr check` describes it.
    pub model: String,
    /// `locked` (prescribed sliders) or `held by the <law> control law`.
    pub sliders: String,
    /// Where the model was linearised.
    pub operating_point: OperatingPoint,
    /// Time of the operating point (s).
    pub t: f64,
    /// The platform pose of the model there (m, m, rad).
    pub pose: Pose,
    /// The slider positions there (m).
    pub rho: [f64; 3],
    /// How the links' chords enter: `elastic` (the links' axial springs `EA / l`, the
    /// platform free on them: the coupled model at rest) or the model's own.
    pub chords: String,
    /// Length of the model's state (coordinates, rates, control states).
    pub state_dimension: usize,
    /// Number of generalized coordinates.
    pub coordinates: usize,
    /// The points along each link of the shapes.
    pub xi: Vec<f64>,
    /// Every mode, sorted by frequency, rigid-body (zero) modes left out.
    pub modes: Vec<MachineMode>,
    /// Where the time went.
    pub timing: ModesTiming,
    /// The sample period of a discrete-time model (s; 0 in continuous time): the modes are
    /// then the poles `z` of the sampled loop, with `lambda = ln(z) / dt`.
    pub dt: f64,
    /// What the linear model left out or found at the operating point (one line each).
    pub notes: Vec<String>,
    /// The assumed-mode basis' truncation, for a model whose links bend in assumed modes
    /// (the coupled model; `None` for the nonlinear model's elements).
    pub truncation: Option<Truncation>,
}

/// The bending families an assumed-mode basis leaves out (docs/linear.md, "Truncation").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Truncation {
    /// Modes per link of the basis (the fewest of the three links).
    pub modes_per_link: usize,
    /// The first family the basis leaves out (Hz), about `f_r ((r + 1) / r)^2` from the
    /// basis' own highest frequency `f_r` of the unloaded link (exact for a uniform
    /// pinned-pinned link in sine modes, `f_k = k^2 f_1`), the lowest of the links.
    pub first_missing_hz: f64,
    /// The basis' highest frequency of that link (Hz).
    pub highest_hz: f64,
}

/// Margin of [`Truncation::recommended`]: the first family left out should lie this far
/// above the highest mode of interest.
pub const TRUNCATION_MARGIN: f64 = 1.5;

impl Truncation {
    /// The truncation of `scene`'s links, for a model in assumed modes.
    pub fn of(scene: &Scene) -> Option<Self> {
        if !scene.coupling.capabilities().modal_machine() {
            return None;
        }
        scene
            .machine
            .links
            .iter()
            .filter_map(|link| {
                let f = link_frequencies_hz(&link.integrals.mass, &link.integrals.stiffness)?;
                let r = f.len();
                let top = *f.last()?;
                let ratio = (r + 1) as f64 / r as f64;
                Some(Self {
                    modes_per_link: r,
                    first_missing_hz: top * ratio * ratio,
                    highest_hz: top,
                })
            })
            .min_by(|a, b| a.first_missing_hz.total_cmp(&b.first_missing_hz))
    }

    /// Modes per link whose first family left out lies [`TRUNCATION_MARGIN`] times above
    /// `highest_hz` (the `k^2` law of the pinned-pinned link from the basis' highest mode).
    pub fn recommended(&self, highest_hz: f64) -> usize {
        let r = self.modes_per_link as f64;
        let next = (r * (TRUNCATION_MARGIN * highest_hz / self.highest_hz).sqrt()).ceil() as usize;
        next.saturating_sub(1).max(self.modes_per_link + 1)
    }

    /// Whether modes up to `highest_hz` lie clear of the first family left out (by
    /// [`TRUNCATION_MARGIN`]).
    pub fn complete(&self, highest_hz: f64) -> bool {
        TRUNCATION_MARGIN * highest_hz < self.first_missing_hz
    }

    /// The note when modes up to `highest_hz` are listed and some lie above the first family
    /// left out or within [`TRUNCATION_MARGIN`] below it (measured on the paper's machine
    /// against an external model: up to 1.5 % off with 3 modes per link, 0.8 % with 5, 0.13 %
    /// with 6, 0.03 % with 8; docs/linear.md, "Truncation").
    pub fn note(&self, highest_hz: f64) -> Option<String> {
        if self.complete(highest_hz) {
            return None;
        }
        Some(format!(
            "the basis has {} bending modes per link: the families from about {:.0} Hz (the \
             {}th) on are left out, and the modes listed up to {:.0} Hz reach within a factor \
             {} of them, so those near and above it miss their dynamics and may be off by a \
             percent or more; links.modes = {} brings in every family below {:.0} Hz",
            self.modes_per_link,
            self.first_missing_hz,
            self.modes_per_link + 1,
            highest_hz,
            TRUNCATION_MARGIN,
            self.recommended(highest_hz),
            TRUNCATION_MARGIN * highest_hz,
        ))
    }
}

/// The unloaded natural frequencies of a link's basis (Hz, ascending): the eigenvalues of
/// `M^-1 K`.
fn link_frequencies_hz(mass: &faer::Mat<f64>, stiffness: &faer::Mat<f64>) -> Option<Vec<f64>> {
    use faer::linalg::solvers::{Eigen, Solve};
    let k = mass.partial_piv_lu().solve(stiffness);
    let eigen = Eigen::new_from_real(k.as_ref()).ok()?;
    let mut f: Vec<f64> = (0..k.nrows())
        .map(|j| eigen.S()[j].re.max(0.0).sqrt() / std::f64::consts::TAU)
        .collect();
    f.sort_by(f64::total_cmp);
    Some(f)
}

/// The shape outputs: sliders, platform pose, each link's deflection at `points` points.
fn shape_outputs(points: usize) -> (Vec<Output>, Vec<f64>) {
    let xi: Vec<f64> = (0..points)
        .map(|j| j as f64 / (points - 1) as f64)
        .collect();
    let mut outputs: Vec<Output> = (0..3).map(Output::SliderPosition).collect();
    outputs.extend([Axis::X, Axis::Y, Axis::Phi].map(Output::Platform));
    for link in 0..3 {
        outputs.extend(xi.iter().map(|&xi| Output::Deflection { link, xi }));
    }
    (outputs, xi)
}

/// The linearisation's error as a run error: a model failure stays one, the rest is a
/// failure of the analysis.
fn linear_error(e: LinearError) -> RunError {
    match e {
        LinearError::Model(e) => RunError::Model(e),
        source => RunError::Analysis {
            analysis: None,
            source,
        },
    }
}

/// The whole machine's modes of `scene` at `at`, with shapes at `points` points along each
/// link (at least 2; [`SHAPE_POINTS`] is a good choice).
///
/// # Errors
/// As [`operating_point`] (a KED scene, a pose the machine cannot hold or a singular one, a
/// time outside the span, a run that fails before it), or the linearisation or the
/// eigenvalue problem fails.
pub fn machine_modes(
    scene: &Scene,
    at: OperatingPoint,
    points: usize,
    settings: &Settings,
) -> Result<MachineModes, RunError> {
    machine_modes_with_progress(scene, at, points, settings, &mut |_| {})
}

/// [`machine_modes`], calling `progress` with what it does next (`"model"`,
/// `"linearisation"`, `"eigenvalues"`).
///
/// # Errors
/// As [`machine_modes`].
pub fn machine_modes_with_progress(
    scene: &Scene,
    at: OperatingPoint,
    points: usize,
    settings: &Settings,
    progress: &mut dyn FnMut(&str),
) -> Result<MachineModes, RunError> {
    let points = points.max(2);
    let clock = Instant::now();
    progress("model");
    let mut point = operating_point(scene, at)?;
    let model_s = clock.elapsed().as_secs_f64();
    let snapshot = point.model.snapshot(point.t, &point.state)?;
    let (outputs, xi) = shape_outputs(points);
    let clock = Instant::now();
    let no_inputs: [Input; 0] = [];
    progress("linearisation");
    let lin = linearize_with_settings(
        point.model.as_mut(),
        point.t,
        &point.state,
        &no_inputs,
        &outputs,
        settings,
    )
    .map_err(|e| crate::linear::linear_error(scene, e))?;
    let linearisation_s = clock.elapsed().as_secs_f64();
    let clock = Instant::now();
    progress("eigenvalues");
    let found = modes(&lin).map_err(linear_error)?;
    let modes = found
        .iter()
        .map(|m| {
            let shape = ModeShape::from_outputs(
                &m.shape,
                &m.added,
                points,
                snapshot.platform.pose,
                &scene.machine,
            );
            MachineMode {
                eigenvalue: m.eigenvalue,
                z: m.z,
                frequency_hz: m.frequency_hz,
                damping_ratio: m.damping_ratio,
                kind: shape.kind(&scene.machine),
                shape,
            }
        })
        .collect();
    let eigen_s = clock.elapsed().as_secs_f64();
    Ok(MachineModes {
        scene: scene.name.clone(),
        model: scene.model_description(),
        sliders: sliders_description(scene),
        operating_point: at,
        t: point.t,
        pose: snapshot.platform.pose,
        rho: snapshot.sliders.map(|s| s.position),
        chords: chords_description(&lin),
        state_dimension: lin.a.nrows(),
        coordinates: lin.coordinates,
        xi,
        modes,
        timing: ModesTiming {
            model_s,
            linearisation_s,
            eigen_s,
        },
        dt: lin.dt,
        notes: lin.notes.clone(),
        truncation: Truncation::of(scene),
    })
}

/// How a linear model's chords enter it.
pub fn chords_description(lin: &flexprr_linear::Linearization) -> String {
    if lin.elastic_chords {
        "elastic: the links' axial springs EA/l, the platform free on them (the model's rigid \
         chords relaxed at rest; docs/linear.md)"
            .to_string()
    } else {
        "as the model has them".to_string()
    }
}

/// How the sliders are held in a scene's linear models.
pub fn sliders_description(scene: &Scene) -> String {
    match &scene.file.control {
        Some(control) => format!(
            "held by the {} control law (its gains act along the guides)",
            control.kind
        ),
        None => "locked".to_string(),
    }
}

/// The lowest whole-machine frequency (Hz) and its damping ratio at `at`, without mode
/// shapes (no outputs are linearised): what a workspace map computes at each pose.
///
/// # Errors
/// As [`machine_modes`]; a model without any non-rigid mode is a failure of the analysis.
pub fn lowest_frequency(scene: &Scene, at: OperatingPoint) -> Result<(f64, f64), RunError> {
    let mut point = operating_point(scene, at)?;
    let lin = linearize(point.model.as_mut(), point.t, &point.state, &[], &[])
        .map_err(|e| crate::linear::linear_error(scene, e))?;
    let found = modes(&lin).map_err(linear_error)?;
    let first = found.first().ok_or(RunError::NoMode)?;
    Ok((first.frequency_hz, first.damping_ratio))
}

/// The lowest whole-machine frequency at rest at one pose, or why there is none: what a
/// workspace map records at each of its poses.
#[derive(Debug, Clone, PartialEq)]
pub enum RestFrequency {
    /// The lowest frequency (Hz), its damping ratio and the pose's type-II measure.
    Found {
        /// `|lambda| / 2 pi` of the lowest mode (Hz).
        frequency_hz: f64,
        /// Its `-Re(lambda) / |lambda|`.
        damping_ratio: f64,
        /// The platform equilibrium's type-II measure there (1 far from a singularity, 0
        /// at one).
        type_ii_measure: f64,
    },
    /// The machine cannot assemble there, or a slider is out of its travel.
    Unreachable(String),
    /// Type-I or type-II singular, or closer to it than the geometry's threshold: the links
    /// do not hold the platform.
    Singular(String),
    /// The linearisation or the eigenvalue problem failed.
    Failed(String),
}

/// [`lowest_frequency`] of `scene` at rest at `pose`, with the pose first checked: out of
/// reach, and singular (type I, or type II by the kinematic or the equilibrium measure), are
/// marked as such rather than failures.
pub fn rest_frequency(scene: &Scene, pose: Pose) -> RestFrequency {
    let measure = match rest_pose(scene, pose) {
        Ok(measure) => measure,
        Err(other) => return other,
    };
    match lowest_frequency(scene, OperatingPoint::Rest(pose)) {
        Ok((frequency_hz, damping_ratio)) => RestFrequency::Found {
            frequency_hz,
            damping_ratio,
            type_ii_measure: measure,
        },
        // The rigid inverse dynamics (a controller's feedforward) measures the same
        // equilibrium at the pose, with its own rounding: singular too.
        Err(
            e @ RunError::Model(flexprr_dynamics::DynamicsError::SingularInverseDynamics { .. }),
        ) => RestFrequency::Singular(e.to_string()),
        Err(e) => RestFrequency::Failed(e.to_string()),
    }
}

/// Whether the machine holds the platform at rest at `pose`: the type-II measure of its
/// equilibrium there, or why not: out of reach (a leg does not close, a slider beyond its
/// travel), singular (type I, or type II by the kinematic or the equilibrium measure: the
/// links do not hold the platform), or a failure of the kinematics.
///
/// # Errors
/// The [`RestFrequency`] that says why (never `Found`).
pub fn rest_pose(scene: &Scene, pose: Pose) -> Result<f64, RestFrequency> {
    use flexprr_kinematics::{KinematicsError, PlatformMotion};
    let geometry = &scene.machine.geometry;
    let state = match geometry.inverse_kinematics(&PlatformMotion::at_rest(pose)) {
        Ok(state) => state,
        Err(e @ (KinematicsError::Unreachable { .. } | KinematicsError::TravelExceeded { .. })) => {
            return Err(RestFrequency::Unreachable(e.to_string()));
        }
        Err(e @ KinematicsError::Singular { .. }) => {
            return Err(RestFrequency::Singular(e.to_string()));
        }
        Err(e) => return Err(RestFrequency::Failed(e.to_string())),
    };
    let measure = flexprr_dynamics::equilibrium_measure(&state);
    if measure.is_nan() || measure < geometry.thresholds.type_ii {
        return Err(RestFrequency::Singular(format!(
            "type-II measure of the platform's equilibrium {measure:.2e} below {:.1e}",
            geometry.thresholds.type_ii
        )));
    }
    Ok(measure)
}

/// The scene's start pose: the trajectory's pose at the first output time, the default
/// operating point of `flexprr modes`.
pub fn start_pose(scene: &Scene) -> Pose {
    scene.trajectory.motion(scene.output_times[0]).pose
}
