//! Work-precision measurement: how much wall time each integrator needs for a given achieved
//! accuracy on a scene's model, and, side by side, what each model (KED, coupled,
//! geometrically nonlinear) costs for the fidelity it reaches.
//!
//! For every model, every method and every tolerance of a ladder the scene is integrated over
//! its output times; the wall time is the median of several timed repeats after warm-up runs,
//! and the achieved error is measured against a [`Reference`] solution computed once at a far
//! tighter tolerance and checked against a second method. This is the work-precision diagram
//! of Hairer, Norsett & Wanner, *Solving ODEs I*, 2nd ed., II.10 (error against computing
//! time, log-log), as DiffEqDevTools and the SciPy benchmarks draw it.
//!
//! Two error measures ([`ErrorMeasure`]):
//!
//! * `state` (KED models only, the default when every model is KED): the state is
//!   `(eta, eta')`, and a difference in a displacement is divided by the largest `|eta|` of the
//!   reference, one in a velocity by the largest `|eta'|`.
//! * `deflection` (every model; the only one for coupled and nonlinear models, whose states
//!   are not modal amplitudes or not comparable between models): the links' mid-point
//!   deflections `w_i(1/2, t)` (the `deflections.csv` quantity at `xi = 0.5`, what the
//!   external models report), differences divided by the largest `|w_i(1/2)|` of the
//!   reference.
//!
//! Two numbers are reported: at the end time ([`AchievedError::end`]) and the maximum over all
//! output times ([`AchievedError::max`]).
//!
//! Tolerances: at ladder value `tol` every solver gets `rtol = tol` and the scalar
//! `atol = tol * s`, with `s` the size the errors are relative to (largest `|eta|`, or largest
//! `|w(1/2)|`, of the reference), so that a zero initial state does not make the absolute
//! tolerance meaningless.
//!
//! Models side by side ([`WorkPrecisionConfig::models`], [`ModelChoice`]): each row is the
//! scene with `model.coupling` (and `model.elements`) overridden, all measured in deflections
//! against one reference, by default the most accurate model of the set (the nonlinear one
//! with the most elements). A model's error then floors at its model error, which is the
//! point: cost against achieved fidelity.
//!
//! Rows of other packages (the `benches/peers` crate, the SciPy script) use the same CSV
//! columns ([`WorkPrecisionRow`]) and can be merged with [`read_csv`].

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant as Clock;

use flexprr_dynamics::{CouplingModel, Formulation, SceneModel};
use flexprr_integrators::{Options, Solution};
use serde::{Deserialize, Serialize};

use flexprr_scene::ScenarioError;
use flexprr_scene::{Method, Scene};

/// The default tolerance ladder, `1e-3` down to `1e-12` (one per decade).
pub const DEFAULT_TOLERANCES: [f64; 10] = [
    1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12,
];

/// The default ladder when a nonlinear model is measured, `1e-3` down to `1e-8`: its steps
/// are set by the elements' axial modes down to about `1e-8` (docs/performance.md,
/// "Nonlinear links"), and tighter points would need a reference beyond what finishes.
pub const NONLINEAR_TOLERANCES: [f64; 6] = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8];

/// The name of this package in the `package` column.
pub const PACKAGE: &str = "flexprr";

/// The point of the links where the deflection measure looks: the mid-point, `xi = 1/2`.
pub const DEFLECTION_XI: f64 = 0.5;

/// How achieved errors are measured (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorMeasure {
    /// The modal state `(eta, eta')`, block by block; KED models only.
    State,
    /// The three links' mid-point deflections; every model.
    Deflection,
}

impl ErrorMeasure {
    /// Every measure, in the order of [`ErrorMeasure::name`]'s help.
    pub const ALL: [ErrorMeasure; 2] = [ErrorMeasure::Deflection, ErrorMeasure::State];

    /// The measure's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ErrorMeasure::State => "state",
            ErrorMeasure::Deflection => "deflection",
        }
    }

    /// The measure named `name`, if any.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.name() == name)
    }
}

/// A model to measure: the scene with `model.coupling` (and, for the nonlinear model,
/// `model.elements`) replaced.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelChoice {
    /// Kineto-elasto-dynamics with the scene's formulation (`"ked"`).
    Ked,
    /// The coupled rigid-flexible model (`"coupled"`; consistent formulation only).
    Coupled,
    /// Co-rotational nonlinear links (`"nonlinear"` with the scene's `model.elements`, or
    /// `"nonlinear:N"` with `N` elements per link, even, 2 to 512).
    Nonlinear(Option<usize>),
}

impl ModelChoice {
    /// The names [`ModelChoice::parse`] accepts, for messages.
    pub const NAMES: &'static str = "ked, coupled, nonlinear, nonlinear:N (N even, 2 to 512)";

    /// The model named `name` (`ked`, `coupled`, `nonlinear`, `nonlinear:16`), if any.
    pub fn parse(name: &str) -> Option<Self> {
        match name {
            "ked" => Some(Self::Ked),
            "coupled" => Some(Self::Coupled),
            "nonlinear" => Some(Self::Nonlinear(None)),
            _ => {
                let n: usize = name.strip_prefix("nonlinear:")?.parse().ok()?;
                ((2..=512).contains(&n) && n % 2 == 0).then_some(Self::Nonlinear(Some(n)))
            }
        }
    }

    /// The name [`ModelChoice::parse`] reads back (`ked`, `nonlinear`, `nonlinear:16`).
    pub fn name(self) -> String {
        match self {
            Self::Ked => "ked".to_string(),
            Self::Coupled => "coupled".to_string(),
            Self::Nonlinear(None) => "nonlinear".to_string(),
            Self::Nonlinear(Some(n)) => format!("nonlinear:{n}"),
        }
    }

    /// The scene's own model.
    pub fn of(scene: &Scene) -> Self {
        match scene.coupling {
            CouplingModel::Ked => Self::Ked,
            CouplingModel::Coupled => Self::Coupled,
            CouplingModel::Nonlinear => Self::Nonlinear(Some(scene.large_deflection.elements)),
        }
    }

    /// The elements per link of a nonlinear choice on `scene`.
    fn elements(self, scene: &Scene) -> Option<usize> {
        match self {
            Self::Nonlinear(n) => Some(n.unwrap_or(scene.large_deflection.elements)),
            _ => None,
        }
    }

    /// The row label on `scene`: `ked (paper)`, `ked (consistent)`, `coupled`,
    /// `nonlinear:16`.
    pub fn label(self, scene: &Scene) -> String {
        match self {
            Self::Ked => format!("ked ({})", scene.formulation.name()),
            Self::Coupled => "coupled".to_string(),
            Self::Nonlinear(_) => format!("nonlinear:{}", self.elements(scene).unwrap_or(0)),
        }
    }

    /// The model kind.
    pub fn kind(self) -> CouplingModel {
        match self {
            Self::Ked => CouplingModel::Ked,
            Self::Coupled => CouplingModel::Coupled,
            Self::Nonlinear(_) => CouplingModel::Nonlinear,
        }
    }

    /// How faithful the model is, for the default reference: KED below coupled below
    /// nonlinear, and more elements above fewer (the mesh convergence of docs/coupled.md).
    pub fn fidelity(self, scene: &Scene) -> usize {
        match self {
            Self::Ked => 0,
            Self::Coupled => 1,
            Self::Nonlinear(_) => 2 + self.elements(scene).unwrap_or(0),
        }
    }

    /// `scene` with this model.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] at key `models` if the coupled or nonlinear model is asked of
    /// a scene whose formulation is not the consistent one (they are built on it).
    pub fn apply(self, scene: &Scene) -> Result<Scene, ScenarioError> {
        let mut out = scene.clone();
        out.coupling = self.kind();
        if let Some(n) = self.elements(scene) {
            out.large_deflection.elements = n;
        }
        if self != Self::Ked && scene.formulation != Formulation::consistent() {
            return Err(ScenarioError::Input {
                location: None,
                key: "models".to_string(),
                message: format!(
                    "model {} needs model.formulation = \"consistent\"; scene {:?} uses {:?}",
                    self.label(scene),
                    scene.name,
                    scene.formulation.name()
                ),
            });
        }
        Ok(out)
    }
}

/// How the reference of a model kind is computed by default: the method, its check, the
/// relative tolerance and the accepted disagreement (in the error measure used).
///
/// * KED: [`Method::Rk45`] at `1e-14` checked by [`Method::Abm`] at the same tolerance (a
///   one-step Runge-Kutta pair against a multistep Adams code, so their errors are
///   independent); agreement below `1e-9`.
/// * Coupled: [`Method::Abm`] at `1e-14` checked by [`Method::Rk45`] at the same tolerance;
///   agreement below `1e-9` (the 0.2 s coupled scene at 20 Hz: `8.7e-12` in deflections).
/// * Nonlinear: [`Method::Abm`] at `1e-10` checked by [`Method::Rk45`] at the same
///   tolerance; agreement below `1e-8`. Tighter costs minutes per run: the elements' axial
///   modes hold both methods to small steps already at loose tolerances, and from `1e-10`
///   on the steps become accuracy-limited on top (32 elements over 20 ms: 376 000 ABM steps
///   at `1e-10`, 1 003 000 at `1e-11`; RK45 193 000 steps of six right-hand sides each at
///   `1e-10`).
pub fn default_reference(kind: CouplingModel) -> ReferencePlan {
    match kind {
        CouplingModel::Ked => ReferencePlan {
            method: Method::Rk45,
            check_method: Method::Abm,
            rtol: 1e-14,
            check_factor: 1.0,
            agreement_limit: 1e-9,
        },
        CouplingModel::Coupled => ReferencePlan {
            method: Method::Abm,
            check_method: Method::Rk45,
            rtol: 1e-14,
            check_factor: 1.0,
            agreement_limit: 1e-9,
        },
        CouplingModel::Nonlinear => ReferencePlan {
            method: Method::Abm,
            check_method: Method::Rk45,
            rtol: 1e-10,
            check_factor: 1.0,
            agreement_limit: 1e-8,
        },
    }
}

/// How a reference is computed: see [`default_reference`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferencePlan {
    /// Method of the reference.
    pub method: Method,
    /// Method of its check.
    pub check_method: Method,
    /// Relative tolerance of the reference.
    pub rtol: f64,
    /// The check's tolerance over the reference's (1 for a second method, 0.1 for the same
    /// method ten times tighter).
    pub check_factor: f64,
    /// Largest accepted disagreement between the reference and its check.
    pub agreement_limit: f64,
}

/// What to measure and how.
#[derive(Debug, Clone, PartialEq)]
pub struct WorkPrecisionConfig {
    /// Relative tolerances of the ladder (loose to tight).
    pub tolerances: Vec<f64>,
    /// Methods to measure.
    pub methods: Vec<Method>,
    /// Models to measure, side by side; empty: the scene's own model.
    pub models: Vec<ModelChoice>,
    /// Model of the reference; `None`: the most faithful of [`Self::models`] (the scene's own
    /// model when that is empty).
    pub reference_model: Option<ModelChoice>,
    /// Error measure; `None`: [`ErrorMeasure::State`] when every model is KED, else
    /// [`ErrorMeasure::Deflection`].
    pub error: Option<ErrorMeasure>,
    /// Untimed runs before the timed ones (caches, branch predictors, page faults).
    pub warmup: usize,
    /// Timed runs per point; the median is reported.
    pub repeats: usize,
    /// Relative tolerance of the reference (far below the ladder); `None`: the reference
    /// model's default ([`default_reference`]).
    pub reference_rtol: Option<f64>,
    /// Largest accepted disagreement between the reference and its check, in the error
    /// measure; `None`: the reference model's default ([`default_reference`]).
    pub reference_agreement_limit: Option<f64>,
}

impl Default for WorkPrecisionConfig {
    fn default() -> Self {
        Self {
            tolerances: DEFAULT_TOLERANCES.to_vec(),
            methods: vec![
                Method::Abm,
                Method::Rk45,
                Method::Bdf,
                Method::Magnus4,
                Method::Magnus6,
                Method::Auto,
            ],
            models: Vec::new(),
            reference_model: None,
            error: None,
            warmup: 2,
            repeats: 7,
            reference_rtol: None,
            reference_agreement_limit: None,
        }
    }
}

impl WorkPrecisionConfig {
    /// Checks the configuration.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] naming the offending setting and value.
    pub fn validate(&self) -> Result<(), ScenarioError> {
        let bad = |key: &str, message: String| {
            Err(ScenarioError::Input {
                location: None,
                key: key.to_string(),
                message,
            })
        };
        if self.tolerances.is_empty() {
            return bad("tolerances", "the ladder is empty".to_string());
        }
        if let Some((k, tol)) = self
            .tolerances
            .iter()
            .enumerate()
            .find(|(_, t)| !(t.is_finite() && **t > 0.0 && **t < 1.0))
        {
            return bad(
                "tolerances",
                format!("tolerance {k} is {tol}; expected a value in (0, 1)"),
            );
        }
        if self.methods.is_empty() {
            return bad("methods", "no method to measure".to_string());
        }
        // Each method, model and tolerance once: a repeat would only give duplicate rows.
        if let Some(m) = first_repeat(&self.methods, |a, b| a == b) {
            return bad("methods", format!("{} is named twice", m.name()));
        }
        if let Some(m) = first_repeat(&self.models, |a, b| a == b) {
            return bad("models", format!("{} is named twice", m.name()));
        }
        if let Some(t) = first_repeat(&self.tolerances, |a, b| a.to_bits() == b.to_bits()) {
            return bad("tolerances", format!("{t:e} is named twice"));
        }
        if self.repeats == 0 {
            return bad("repeats", "at least one timed run is needed".to_string());
        }
        let tightest = self.tightest();
        if let Some(rtol) = self.reference_rtol
            && !(rtol > 0.0 && rtol < tightest)
        {
            return bad(
                "reference_rtol",
                format!(
                    "{rtol} must be positive and below the tightest ladder tolerance {tightest}"
                ),
            );
        }
        if let Some(limit) = self.reference_agreement_limit
            && (limit.is_nan() || limit <= 0.0)
        {
            return bad(
                "reference_agreement_limit",
                format!("{limit} must be positive"),
            );
        }
        Ok(())
    }

    /// The tightest tolerance of the ladder.
    fn tightest(&self) -> f64 {
        self.tolerances.iter().copied().fold(1.0, f64::min)
    }

    /// The models measured on `scene`: [`Self::models`], or the scene's own.
    pub fn measured_models(&self, scene: &Scene) -> Vec<ModelChoice> {
        if self.models.is_empty() {
            vec![ModelChoice::of(scene)]
        } else {
            self.models.clone()
        }
    }

    /// The model of the reference on `scene`: [`Self::reference_model`], or the most
    /// faithful measured model ([`ModelChoice::fidelity`]).
    pub fn reference_model(&self, scene: &Scene) -> ModelChoice {
        self.reference_model.unwrap_or_else(|| {
            self.measured_models(scene)
                .into_iter()
                .max_by_key(|m| m.fidelity(scene))
                .unwrap_or_else(|| ModelChoice::of(scene))
        })
    }

    /// The error measure on `scene` (see [`Self::error`]).
    ///
    /// # Errors
    /// [`ScenarioError::Input`] at key `error` if the state measure is asked for with a
    /// coupled or nonlinear model (their states are not the KED modal state).
    pub fn error_measure(&self, scene: &Scene) -> Result<ErrorMeasure, ScenarioError> {
        let mut all = self.measured_models(scene);
        all.push(self.reference_model(scene));
        let other = all.iter().find(|m| **m != ModelChoice::Ked);
        match (self.error, other) {
            (Some(ErrorMeasure::State), Some(model)) => Err(ScenarioError::Input {
                location: None,
                key: "error".to_string(),
                message: format!(
                    "the state measure compares KED modal states and does not apply to model {}; \
                     use the deflection measure",
                    model.label(scene)
                ),
            }),
            (Some(measure), _) => Ok(measure),
            (None, Some(_)) => Ok(ErrorMeasure::Deflection),
            (None, None) => Ok(ErrorMeasure::State),
        }
    }

    /// How the reference is computed on `scene`: the reference model's
    /// [`default_reference`] with [`Self::reference_rtol`] and
    /// [`Self::reference_agreement_limit`] when given.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] at key `reference_rtol` if the reference tolerance is not
    /// below the tightest ladder tolerance.
    pub fn reference_plan(&self, scene: &Scene) -> Result<ReferencePlan, ScenarioError> {
        let model = self.reference_model(scene);
        let mut plan = default_reference(model.kind());
        if let Some(rtol) = self.reference_rtol {
            plan.rtol = rtol;
        }
        if let Some(limit) = self.reference_agreement_limit {
            plan.agreement_limit = limit;
        }
        let tightest = self.tightest();
        if plan.rtol >= tightest {
            return Err(ScenarioError::Input {
                location: None,
                key: "reference_rtol".to_string(),
                message: format!(
                    "the reference ({}, {}) at rtol {:e} is not below the tightest ladder \
                     tolerance {tightest:e}: loosen the ladder or tighten the reference",
                    model.label(scene),
                    plan.method.name(),
                    plan.rtol
                ),
            });
        }
        Ok(plan)
    }
}

/// The first element of `items` equal (by `same`) to an earlier one.
fn first_repeat<T>(items: &[T], same: impl Fn(&T, &T) -> bool) -> Option<&T> {
    items
        .iter()
        .enumerate()
        .find(|(k, a)| items[..*k].iter().any(|b| same(a, b)))
        .map(|(_, a)| a)
}

/// An achieved error, relative to the solution's size (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AchievedError {
    /// At the end time.
    pub end: f64,
    /// Maximum over the output times.
    pub max: f64,
}

/// The reference solution at the scene's output times, with the sizes errors are scaled by.
/// A state reference ([`ErrorMeasure::State`]) holds the modal states; a deflection
/// reference ([`ErrorMeasure::Deflection`]) holds the three mid-point deflections per time
/// and no states (`modes` is 0).
#[derive(Debug, Clone, PartialEq)]
pub struct Reference {
    /// Output times (s).
    pub t: Vec<f64>,
    /// The error measure this reference serves.
    pub measure: ErrorMeasure,
    /// States row by row, `t.len()` rows of `2 * modes` values `(eta, eta')` (state
    /// reference; empty otherwise).
    pub states: Vec<f64>,
    /// Number of modal coordinates (half the state dimension; 0 for a deflection reference).
    pub modes: usize,
    /// Largest `|eta|` over all coordinates and times (m); for a deflection reference the
    /// largest `|w(1/2)|`.
    pub displacement_size: f64,
    /// Largest `|eta'|` over all coordinates and times (m/s; 0 for a deflection reference).
    pub velocity_size: f64,
    /// Mid-point deflections `w_1, w_2, w_3` (m) row by row (deflection reference; empty
    /// otherwise).
    pub deflections: Vec<f64>,
    /// The reference's model (`ked (paper)`, `nonlinear:32`; empty if read from a file).
    pub model: String,
    /// Method that computed the reference (empty if read from a file).
    pub method: String,
    /// Relative tolerance of the reference (NaN if read from a file).
    pub rtol: f64,
    /// Method that checked it.
    pub check_method: String,
    /// Relative tolerance of the check (NaN if read from a file).
    pub check_rtol: f64,
    /// Disagreement between the reference and the check.
    pub agreement: Option<AchievedError>,
}

/// Solves the scene's model with `method` and `options` over the scene's output times,
/// stopping at the scene's stop times (the same loop as `flexprr run`). On failure, the
/// message names the method, the tolerance and the model's own cause when it has one (a
/// cause left over from an earlier run, e.g. a trial step of a rejected stage that an
/// integration recovered from, is cleared first so that it cannot be blamed).
fn solve(
    scene: &Scene,
    model: &mut dyn SceneModel,
    method: Method,
    options: Options,
) -> Result<Solution, String> {
    let _ = model.take_failure();
    let rtol = options.rtol;
    let t_out = &scene.output_times;
    let y0 = model.initial_state();
    let stops = flexprr_run::stop_times(scene);
    let handle = flexprr_scene::Registry::default()
        .method(method.name())
        .ok_or_else(|| format!("no integrator {:?} in the default registry", method.name()))?;
    handle
        .integrator(options)
        .solve_dyn(model, t_out[0], &y0, t_out, &stops, &mut ())
        .map_err(|interrupted| match model.take_failure() {
            Some(cause) => format!(
                "{} at rtol {rtol:e}: {cause} (integrator: {interrupted})",
                method.name()
            ),
            None => format!("{} at rtol {rtol:e}: {interrupted}", method.name()),
        })
}

/// Integrates the reference model as `flexprr run` does ([`flexprr_run::integrate_model`]:
/// the scene's stop times, the run layer's divergence guard, the model's own failure
/// causes such as a collapse), with `method` and `options`. `role` names the integration
/// in the error (`pilot run`, `reference`, `check`).
///
/// A reference that diverged or failed is never measured against: its failure comes back
/// as [`ScenarioError::Run`] naming the scene, the model, the integration, the reason and
/// the time.
fn solve_reference(
    scene: &Scene,
    label: &str,
    role: &str,
    model: &mut dyn SceneModel,
    method: Method,
    options: Options,
) -> Result<Solution, ScenarioError> {
    let _ = model.take_failure();
    let rtol = options.rtol;
    let handle = flexprr_scene::Registry::default()
        .method(method.name())
        .ok_or_else(|| {
            ScenarioError::Run(format!(
                "no integrator {:?} in the default registry",
                method.name()
            ))
        })?;
    let integration = flexprr_run::integrate_model(
        scene,
        handle.integrator(options).as_ref(),
        model,
        &mut |_| {},
    );
    match integration.failure {
        None => Ok(integration.solution),
        Some(failure) => {
            let reason = failure.to_string();
            // Every failure names its time in its own words; added where one does not.
            let when = match failure.time() {
                Some(t) if !reason.contains("t = ") => format!(" at t = {t} s"),
                _ => String::new(),
            };
            Err(ScenarioError::Run(format!(
                "scene {:?}, reference model {label}: the {role} ({} at rtol {rtol:e}) failed{when}: \
                 {reason}; a failed reference is not measured against",
                scene.name,
                method.name(),
            )))
        }
    }
}

/// The first output time at which `solution` of `model` passes the run layer's divergence
/// limit ([`flexprr_run::guard::DivergenceGuard`], the check `flexprr run` makes after every
/// step, made here at the output times of a timed integration that ran without it).
fn divergence(model: &dyn SceneModel, solution: &Solution) -> Option<flexprr_run::RunError> {
    use flexprr_integrators::{Flow, Observer as _};
    let mut guard = flexprr_run::guard::DivergenceGuard::new(model);
    (0..solution.len()).find_map(|k| match guard.on_step(solution.t[k], solution.y(k)) {
        Flow::Stop => guard.take_divergence(),
        _ => None,
    })
}

/// The scene's model from its one builder.
fn build(scene: &Scene) -> Result<Box<dyn SceneModel>, ScenarioError> {
    scene
        .build_model()
        .map_err(|e| ScenarioError::Run(format!("scene {:?}: {e}", scene.name)))
}

/// The links' mid-point deflections `w_i(1/2)` (m) of `solution` of `model`: three per
/// output time, links in order. The modal models give `w = sum_j psi_j(1/2) eta_j` (the
/// paper's eq. 1, [`SceneModel::deflection`]); the nonlinear model measures from the chord
/// of the deflected link, which needs the time
/// ([`flexprr_dynamics::NonlinearSystem::deflection_at`]). These are the values of
/// `deflections.csv` at `xi = 0.5`.
///
/// # Errors
/// [`ScenarioError::Run`] naming the time and link if a deflection cannot be computed or is
/// not finite.
pub fn midpoint_deflections(
    model: &mut dyn SceneModel,
    solution: &Solution,
) -> Result<Vec<f64>, ScenarioError> {
    let n = solution.t.len();
    let kind = model.kind();
    let mut w = Vec::with_capacity(3 * n);
    if let Some(system) = model.as_nonlinear() {
        for k in 0..n {
            let (t, y) = (solution.t[k], solution.y(k));
            for i in 0..3 {
                w.push(system.deflection_at(t, i, DEFLECTION_XI, y).map_err(|e| {
                    ScenarioError::Run(format!(
                        "mid-point deflection of link {} at t = {t} s ({kind} model): {e}",
                        i + 1
                    ))
                })?);
            }
        }
    } else {
        for k in 0..n {
            w.extend((0..3).map(|i| model.deflection(i, DEFLECTION_XI, solution.y(k))));
        }
    }
    if let Some(j) = w.iter().position(|v| !v.is_finite()) {
        return Err(ScenarioError::Run(format!(
            "mid-point deflection of link {} at t = {} s ({kind} model) is not finite ({})",
            j % 3 + 1,
            solution.t[j / 3],
            w[j]
        )));
    }
    Ok(w)
}

/// The error of `values` against `reference`, both row by row with `width` values per output
/// time `t[k]`: per row the largest `|v_i - v_ref_i| / size(i)`, at the end time and the
/// maximum over the rows.
///
/// # Errors
/// [`ScenarioError::Run`] naming the value (`name(i)`) and time of the first non-finite one.
fn max_row_error(
    values: &[f64],
    reference: &[f64],
    width: usize,
    t: &[f64],
    size: impl Fn(usize) -> f64,
    name: impl Fn(usize) -> String,
) -> Result<AchievedError, ScenarioError> {
    let (mut max, mut row_error) = (0.0_f64, 0.0_f64);
    for (k, (row, reference)) in values
        .chunks_exact(width)
        .zip(reference.chunks_exact(width))
        .enumerate()
    {
        row_error = 0.0;
        for (i, (v, v_ref)) in row.iter().zip(reference).enumerate() {
            if !v.is_finite() {
                return Err(ScenarioError::Run(format!(
                    "{} at t = {} s is not finite ({v})",
                    name(i),
                    t[k]
                )));
            }
            row_error = row_error.max((v - v_ref).abs() / size(i));
        }
        max = max.max(row_error);
    }
    Ok(AchievedError {
        end: row_error,
        max,
    })
}

impl Reference {
    /// A state reference from states at output times; the sizes are taken from the states.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] if the shapes do not match, a value is not finite, or the
    /// solution is identically zero (no size to be relative to).
    pub fn from_states(t: Vec<f64>, states: Vec<f64>, modes: usize) -> Result<Self, ScenarioError> {
        let bad = |message: String| ScenarioError::Input {
            location: None,
            key: "reference".to_string(),
            message,
        };
        let dim = 2 * modes;
        if modes == 0 || t.is_empty() || states.len() != t.len() * dim {
            return Err(bad(format!(
                "{} values for {} times and {modes} modes (expected {})",
                states.len(),
                t.len(),
                t.len() * dim
            )));
        }
        if let Some(k) = states.iter().position(|v| !v.is_finite()) {
            return Err(bad(format!(
                "value {} of row {} (t = {} s) is not finite",
                k % dim,
                k / dim,
                t[k / dim]
            )));
        }
        let (mut displacement_size, mut velocity_size) = (0.0_f64, 0.0_f64);
        for row in states.chunks_exact(dim) {
            let (eta, eta_dot) = row.split_at(modes);
            displacement_size = eta.iter().fold(displacement_size, |m, v| m.max(v.abs()));
            velocity_size = eta_dot.iter().fold(velocity_size, |m, v| m.max(v.abs()));
        }
        if displacement_size <= 0.0 || velocity_size <= 0.0 {
            return Err(bad(
                "the solution is identically zero: no size to measure errors against".to_string(),
            ));
        }
        Ok(Self {
            t,
            measure: ErrorMeasure::State,
            states,
            modes,
            displacement_size,
            velocity_size,
            deflections: Vec::new(),
            model: String::new(),
            method: String::new(),
            rtol: f64::NAN,
            check_method: String::new(),
            check_rtol: f64::NAN,
            agreement: None,
        })
    }

    /// A deflection reference from the three mid-point deflections per output time; the
    /// size is the largest `|w|`.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] if the shapes do not match, a value is not finite, or every
    /// deflection is zero.
    pub fn from_deflections(t: Vec<f64>, deflections: Vec<f64>) -> Result<Self, ScenarioError> {
        let bad = |message: String| ScenarioError::Input {
            location: None,
            key: "reference".to_string(),
            message,
        };
        if t.is_empty() || deflections.len() != 3 * t.len() {
            return Err(bad(format!(
                "{} deflections for {} times (expected three per time)",
                deflections.len(),
                t.len()
            )));
        }
        if let Some(k) = deflections.iter().position(|v| !v.is_finite()) {
            return Err(bad(format!(
                "the deflection of link {} at t = {} s is not finite",
                k % 3 + 1,
                t[k / 3]
            )));
        }
        let size = deflections.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        if size <= 0.0 {
            return Err(bad(
                "every deflection is zero: no size to measure errors against".to_string(),
            ));
        }
        Ok(Self {
            t,
            measure: ErrorMeasure::Deflection,
            states: Vec::new(),
            modes: 0,
            displacement_size: size,
            velocity_size: 0.0,
            deflections,
            model: String::new(),
            method: String::new(),
            rtol: f64::NAN,
            check_method: String::new(),
            check_rtol: f64::NAN,
            agreement: None,
        })
    }

    /// A reference of `measure` from a solution of `model`.
    fn from_solution(
        measure: ErrorMeasure,
        model: &mut dyn SceneModel,
        solution: Solution,
    ) -> Result<Self, ScenarioError> {
        match measure {
            ErrorMeasure::State => Self::from_states(solution.t, solution.states, model.modes()),
            ErrorMeasure::Deflection => {
                let w = midpoint_deflections(model, &solution)?;
                Self::from_deflections(solution.t, w)
            }
        }
    }

    /// Computes the reference for a scene: the reference model
    /// ([`WorkPrecisionConfig::reference_model`]) integrated as its [`ReferencePlan`] says
    /// ([`WorkPrecisionConfig::reference_plan`], [`default_reference`]), checked against a
    /// second integration, in the error measure of [`WorkPrecisionConfig::error_measure`].
    /// A pilot run (ABM at `1e-8`) gives the size for the absolute tolerance.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] for a bad configuration, [`ScenarioError::Run`] if an
    /// integration fails or the two disagree by more than the plan's limit.
    pub fn compute(scene: &Scene, config: &WorkPrecisionConfig) -> Result<Self, ScenarioError> {
        config.validate()?;
        let measure = config.error_measure(scene)?;
        let plan = config.reference_plan(scene)?;
        let choice = config.reference_model(scene);
        let label = choice.label(scene);
        let model_scene = choice.apply(scene)?;
        let mut system = build(&model_scene)?;
        let in_model = |e: String| ScenarioError::Run(format!("reference model {label}: {e}"));
        let pilot_rtol = 1e-8;
        let pilot = solve_reference(
            &model_scene,
            &label,
            "pilot run",
            system.as_mut(),
            Method::Abm,
            model_scene.options.clone().rtol(pilot_rtol),
        )?;
        let pilot = Self::from_solution(measure, system.as_mut(), pilot)
            .map_err(|e| in_model(format!("pilot run for the reference: {e}")))?;
        let size = pilot.displacement_size;
        let options = |rtol: f64| Options::default().rtol(rtol).atol(rtol * size);
        let check_rtol = plan.rtol * plan.check_factor;
        let main = solve_reference(
            &model_scene,
            &label,
            "reference",
            system.as_mut(),
            plan.method,
            options(plan.rtol),
        )?;
        let check = solve_reference(
            &model_scene,
            &label,
            "check",
            system.as_mut(),
            plan.check_method,
            options(check_rtol),
        )?;
        let mut reference = Self::from_solution(measure, system.as_mut(), main)
            .map_err(|e| in_model(format!("reference: {e}")))?;
        let agreement = reference.errors_of(system.as_mut(), &check)?;
        if agreement.max.is_nan() || agreement.max > plan.agreement_limit {
            return Err(ScenarioError::Run(format!(
                "reference model {label}: the reference ({} at rtol {:e}) and its check ({} at \
                 rtol {check_rtol:e}) disagree by {:e} (end) / {:e} (max) in the {} measure, \
                 above the limit {:e}",
                plan.method.name(),
                plan.rtol,
                plan.check_method.name(),
                agreement.end,
                agreement.max,
                measure.name(),
                plan.agreement_limit
            )));
        }
        reference.model = label;
        reference.method = plan.method.name().to_string();
        reference.rtol = plan.rtol;
        reference.check_method = plan.check_method.name().to_string();
        reference.check_rtol = check_rtol;
        reference.agreement = Some(agreement);
        Ok(reference)
    }

    /// Errors of a solution of `model` in this reference's measure ([`Self::errors`] or
    /// [`Self::deflection_errors`]).
    ///
    /// # Errors
    /// As those two, and [`midpoint_deflections`].
    pub fn errors_of(
        &self,
        model: &mut dyn SceneModel,
        solution: &Solution,
    ) -> Result<AchievedError, ScenarioError> {
        match self.measure {
            ErrorMeasure::State => self.errors(&solution.states),
            ErrorMeasure::Deflection => {
                self.deflection_errors(&midpoint_deflections(model, solution)?)
            }
        }
    }

    /// Errors of mid-point deflections `w` (three per time, at the reference's times)
    /// relative to the reference's largest `|w|`: `max_i |w_i - w_ref_i| / s`, at the end
    /// time and the maximum over the times.
    ///
    /// # Errors
    /// [`ScenarioError::Run`] if this is not a deflection reference, the shape differs or a
    /// value is not finite (naming the link and time).
    pub fn deflection_errors(&self, w: &[f64]) -> Result<AchievedError, ScenarioError> {
        if self.measure != ErrorMeasure::Deflection {
            return Err(ScenarioError::Run(
                "the reference holds modal states, not deflections: compute it with the \
                 deflection measure"
                    .to_string(),
            ));
        }
        if w.len() != self.deflections.len() {
            return Err(ScenarioError::Run(format!(
                "{} deflections cannot be compared with the reference's {} ({} times x 3 links)",
                w.len(),
                self.deflections.len(),
                self.t.len()
            )));
        }
        max_row_error(
            w,
            &self.deflections,
            3,
            &self.t,
            |_| self.displacement_size,
            |i| format!("the mid-point deflection of link {}", i + 1),
        )
    }

    /// State dimension (0 for a deflection reference).
    pub fn dim(&self) -> usize {
        2 * self.modes
    }

    /// The scalar absolute tolerance that goes with relative tolerance `tol`: `tol` times
    /// the size errors are relative to (largest `|eta|`, or largest `|w(1/2)|`).
    pub fn atol(&self, tol: f64) -> f64 {
        tol * self.displacement_size
    }

    /// Errors of `states` (row by row at the reference's times) relative to the solution's
    /// size: `|y_i - y_ref_i| / s_i` with `s_i` the displacement or velocity size.
    ///
    /// # Errors
    /// [`ScenarioError::Run`] if this is not a state reference, the shape differs or a
    /// value is not finite.
    pub fn errors(&self, states: &[f64]) -> Result<AchievedError, ScenarioError> {
        if self.measure != ErrorMeasure::State {
            return Err(ScenarioError::Run(
                "the reference holds mid-point deflections, not modal states: measure in \
                 deflections"
                    .to_string(),
            ));
        }
        let dim = self.dim();
        if states.len() != self.states.len() {
            return Err(ScenarioError::Run(format!(
                "a solution with {} values cannot be compared with the reference's {} \
                 ({} times x {dim})",
                states.len(),
                self.states.len(),
                self.t.len()
            )));
        }
        max_row_error(
            states,
            &self.states,
            dim,
            &self.t,
            |i| {
                if i < self.modes {
                    self.displacement_size
                } else {
                    self.velocity_size
                }
            },
            |i| format!("component {i}"),
        )
    }

    /// Writes the reference as CSV: `t_s`, then `eta_1 .. eta_n`, then `eta_dot_1 ..` (state
    /// reference), or `t_s`, `w_1_xi0.5_m`, `w_2_xi0.5_m`, `w_3_xi0.5_m` (deflection
    /// reference, the columns of `deflections.csv`).
    ///
    /// # Errors
    /// [`ScenarioError::Io`] or [`ScenarioError::Run`] if the file cannot be written.
    pub fn write_csv(&self, path: &Path) -> Result<(), ScenarioError> {
        let mut w = csv::Writer::from_writer(Vec::new());
        let csv_err = |e: csv::Error| ScenarioError::Run(format!("{}: {e}", path.display()));
        let mut header = vec!["t_s".to_string()];
        let (values, width) = match self.measure {
            ErrorMeasure::State => {
                header.extend((1..=self.modes).map(|j| format!("eta_{j}")));
                header.extend((1..=self.modes).map(|j| format!("eta_dot_{j}")));
                (&self.states, self.dim())
            }
            ErrorMeasure::Deflection => {
                header.extend((1..=3).map(|i| format!("w_{i}_xi{DEFLECTION_XI}_m")));
                (&self.deflections, 3)
            }
        };
        w.write_record(&header).map_err(csv_err)?;
        for (t, row) in self.t.iter().zip(values.chunks_exact(width)) {
            let mut record = vec![format!("{t:.17e}")];
            record.extend(row.iter().map(|v| format!("{v:.17e}")));
            w.write_record(&record).map_err(csv_err)?;
        }
        let bytes = w
            .into_inner()
            .map_err(|e| ScenarioError::Run(format!("{}: {e}", path.display())))?;
        std::fs::write(path, bytes).map_err(|source| ScenarioError::Io {
            path: path.display().to_string(),
            source,
        })
    }

    /// Reads a reference written by [`Reference::write_csv`]: a deflection reference when
    /// the second column is a deflection (`w_...`), else a state reference.
    ///
    /// # Errors
    /// [`ScenarioError::Io`] if unreadable, [`ScenarioError::Input`] (with the row) if
    /// malformed.
    pub fn read_csv(path: &Path) -> Result<Self, ScenarioError> {
        let text = std::fs::read_to_string(path).map_err(|source| ScenarioError::Io {
            path: path.display().to_string(),
            source,
        })?;
        let bad = |message: String| ScenarioError::Input {
            location: None,
            key: path.display().to_string(),
            message,
        };
        let mut r = csv::Reader::from_reader(text.as_bytes());
        let headers = r.headers().map_err(|e| bad(e.to_string()))?;
        let columns = headers.len();
        let deflection = headers.get(1).is_some_and(|h| h.starts_with("w_"));
        if deflection && columns != 4 {
            return Err(bad(format!(
                "{columns} columns; expected t_s and the three links' mid-point deflections"
            )));
        }
        if !deflection && (columns < 3 || (columns - 1) % 2 != 0) {
            return Err(bad(format!(
                "{columns} columns; expected t_s and an even number of state columns"
            )));
        }
        let modes = (columns - 1) / 2;
        let (mut t, mut states) = (Vec::new(), Vec::new());
        for (k, record) in r.records().enumerate() {
            let record = record.map_err(|e| bad(format!("row {}: {e}", k + 1)))?;
            for (c, field) in record.iter().enumerate() {
                let v: f64 = field.trim().parse().map_err(|_| {
                    bad(format!(
                        "row {}, column {}: {field:?} is not a number",
                        k + 1,
                        c + 1
                    ))
                })?;
                if c == 0 {
                    t.push(v);
                } else {
                    states.push(v);
                }
            }
        }
        if deflection {
            return Self::from_deflections(t, states);
        }
        Self::from_states(t, states, modes)
    }
}

/// One point of the diagram: a package's method at one tolerance. Columns of
/// `work_precision.csv`; counts a package does not report are empty.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WorkPrecisionRow {
    /// Package (`flexprr`, `ode_solvers`, `scipy`, ...).
    pub package: String,
    /// Method within the package (`abm`, `dop853`, `LSODA`, ...).
    pub method: String,
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance (scalar).
    pub atol: f64,
    /// Median wall time of the timed runs (s).
    pub time_median_s: f64,
    /// Fastest timed run (s).
    pub time_min_s: f64,
    /// Number of timed runs.
    pub repeats: usize,
    /// Accepted steps.
    pub accepted_steps: Option<usize>,
    /// Rejected steps.
    pub rejected_steps: Option<usize>,
    /// Right-hand-side evaluations (including those of differenced Jacobians).
    pub rhs_evaluations: Option<usize>,
    /// Jacobian evaluations.
    pub jacobian_evaluations: Option<usize>,
    /// Relative error at the end time.
    pub end_error: f64,
    /// Relative error, maximum over the output times.
    pub max_error: f64,
    /// The model measured when models are set side by side (`ked (consistent)`, `coupled`,
    /// `nonlinear:16`); empty otherwise and for other packages' rows (a file without the
    /// column reads as empty).
    #[serde(default)]
    pub model: String,
}

impl WorkPrecisionRow {
    /// The row's series within its package: the method, after the model when there is one
    /// (`abm`, `nonlinear:16 abm`).
    pub fn series_label(&self) -> String {
        if self.model.is_empty() {
            self.method.clone()
        } else {
            format!("{} {}", self.model, self.method)
        }
    }
}

/// Wall times of repeated runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timing {
    /// Median (s).
    pub median_s: f64,
    /// Fastest (s).
    pub min_s: f64,
    /// Number of timed runs.
    pub repeats: usize,
}

/// Runs `run` `warmup` times untimed, then `repeats` times timed; returns the result of
/// the last run with the median and fastest wall time.
///
/// # Errors
/// The first error of `run`.
pub fn time_runs<T, E>(
    warmup: usize,
    repeats: usize,
    mut run: impl FnMut() -> Result<T, E>,
) -> Result<(T, Timing), E> {
    for _ in 0..warmup {
        run()?;
    }
    let repeats = repeats.max(1);
    let mut times = Vec::with_capacity(repeats);
    let mut last = None;
    for _ in 0..repeats {
        let clock = Clock::now();
        let out = run()?;
        times.push(clock.elapsed().as_secs_f64());
        last = Some(out);
    }
    times.sort_by(f64::total_cmp);
    let n = times.len();
    let median_s = if n % 2 == 1 {
        times[n / 2]
    } else {
        0.5 * (times[n / 2 - 1] + times[n / 2])
    };
    let timing = Timing {
        median_s,
        min_s: times[0],
        repeats: n,
    };
    match last {
        Some(out) => Ok((out, timing)),
        None => unreachable!("repeats is at least one"),
    }
}

/// A whole measurement: the reference, the rows, and the points that failed.
#[derive(Debug, Clone)]
pub struct WorkPrecision {
    /// The reference solution.
    pub reference: Reference,
    /// One row per method and tolerance that succeeded.
    pub rows: Vec<WorkPrecisionRow>,
    /// `method at rtol: reason` for each point that failed (e.g. too many steps).
    pub failures: Vec<String>,
}

/// Measures flexprr's integrators on `scene` over the ladder against `reference`, for each
/// model of [`WorkPrecisionConfig::measured_models`] (rows labelled by model when
/// [`WorkPrecisionConfig::models`] is set). Only the integration is timed; the errors
/// (and, in the deflection measure, the deflections) are computed afterwards.
/// `progress` sees each row as it is measured.
///
/// # Errors
/// [`ScenarioError::Input`] for a bad configuration or a reference of another measure,
/// [`ScenarioError::Run`] if a model cannot be built. A point whose integration fails is
/// listed in the failures instead.
pub fn measure(
    scene: &Scene,
    reference: &Reference,
    config: &WorkPrecisionConfig,
    progress: &mut dyn FnMut(&WorkPrecisionRow),
) -> Result<(Vec<WorkPrecisionRow>, Vec<String>), ScenarioError> {
    config.validate()?;
    let measure = config.error_measure(scene)?;
    if reference.measure != measure {
        return Err(ScenarioError::Input {
            location: None,
            key: "reference".to_string(),
            message: format!(
                "the reference is for the {} measure, the measurement uses the {} measure",
                reference.measure.name(),
                measure.name()
            ),
        });
    }
    let models = config.measured_models(scene);
    let labels: Vec<String> = models.iter().map(|m| m.label(scene)).collect();
    if let Some(twice) = first_repeat(&labels, |a, b| a == b) {
        return Err(ScenarioError::Input {
            location: None,
            key: "models".to_string(),
            message: format!("{twice} is named twice (on scene {:?})", scene.name),
        });
    }
    let (mut rows, mut failures) = (Vec::new(), Vec::new());
    for choice in models {
        let model_scene = choice.apply(scene)?;
        let label = if config.models.is_empty() {
            String::new()
        } else {
            choice.label(scene)
        };
        let mut system = build(&model_scene)?;
        for &method in &config.methods {
            // A linear-only method (magnus4, magnus6) does not apply to a coupled or
            // nonlinear model: said once, not once per tolerance.
            if let Err(why) = method_applies(&model_scene, method) {
                let place = if label.is_empty() {
                    String::new()
                } else {
                    format!("{label}: ")
                };
                failures.push(format!("{place}{} skipped: {why}", method.name()));
                continue;
            }
            for &rtol in &config.tolerances {
                let atol = reference.atol(rtol);
                let options = Options::default().rtol(rtol).atol(atol);
                let timed = time_runs(config.warmup, config.repeats, || {
                    solve(&model_scene, system.as_mut(), method, options.clone())
                });
                let place = if label.is_empty() {
                    String::new()
                } else {
                    format!("{label}: ")
                };
                let (solution, timing) = match timed {
                    Ok(ok) => ok,
                    Err(message) => {
                        failures.push(format!("{place}{message}"));
                        continue;
                    }
                };
                // Untimed: a point that left the small-deflection range, as the run
                // layer's guard sees it, is a failed point, not a large error.
                if let Some(diverged) = divergence(system.as_ref(), &solution) {
                    failures.push(format!(
                        "{place}{} at rtol {rtol:e}: {diverged}",
                        method.name()
                    ));
                    continue;
                }
                let error = match reference.errors_of(system.as_mut(), &solution) {
                    Ok(error) => error,
                    Err(e) => {
                        failures.push(format!("{place}{} at rtol {rtol:e}: {e}", method.name()));
                        continue;
                    }
                };
                let s = &solution.stats;
                let row = WorkPrecisionRow {
                    package: PACKAGE.to_string(),
                    method: method.name().to_string(),
                    rtol,
                    atol,
                    time_median_s: timing.median_s,
                    time_min_s: timing.min_s,
                    repeats: timing.repeats,
                    accepted_steps: Some(s.accepted_steps),
                    rejected_steps: Some(s.rejected_steps),
                    rhs_evaluations: Some(s.rhs_evaluations),
                    jacobian_evaluations: Some(s.jacobian_evaluations),
                    end_error: error.end,
                    max_error: error.max,
                    model: label.clone(),
                };
                progress(&row);
                rows.push(row);
            }
        }
    }
    Ok((rows, failures))
}

/// Whether `method` can integrate the model of `scene`: the scene's own rule
/// ([`flexprr_scene::Registry::resolve_method`]: a linear-only method needs the KED model).
///
/// # Errors
/// The registry's one-line reason.
pub fn method_applies(scene: &Scene, method: Method) -> Result<(), String> {
    flexprr_scene::Registry::default()
        .resolve_method(
            method.name(),
            scene.coupling == flexprr_dynamics::CouplingModel::Ked,
            scene.coupling.name(),
        )
        .map(|_| ())
}

/// Reference plus measurement for a scene.
///
/// # Errors
/// As [`Reference::compute`] and [`measure`].
pub fn work_precision(
    scene: &Scene,
    config: &WorkPrecisionConfig,
    progress: &mut dyn FnMut(&WorkPrecisionRow),
) -> Result<WorkPrecision, ScenarioError> {
    let reference = Reference::compute(scene, config)?;
    let (rows, failures) = measure(scene, &reference, config, progress)?;
    Ok(WorkPrecision {
        reference,
        rows,
        failures,
    })
}

/// The rows as CSV (header included).
///
/// # Errors
/// [`ScenarioError::Run`] if serialisation fails.
pub fn csv_text(rows: &[WorkPrecisionRow]) -> Result<String, ScenarioError> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for row in rows {
        w.serialize(row)
            .map_err(|e| ScenarioError::Run(format!("work-precision CSV: {e}")))?;
    }
    if rows.is_empty() {
        return Ok(String::new());
    }
    let bytes = w
        .into_inner()
        .map_err(|e| ScenarioError::Run(format!("work-precision CSV: {e}")))?;
    String::from_utf8(bytes).map_err(|e| ScenarioError::Run(format!("work-precision CSV: {e}")))
}

/// Reads rows (e.g. a peers file) in the [`WorkPrecisionRow`] format.
///
/// # Errors
/// [`ScenarioError::Io`] if unreadable, [`ScenarioError::Input`] naming the file and row if
/// a row is malformed or has a non-positive time or error.
pub fn read_csv(path: &Path) -> Result<Vec<WorkPrecisionRow>, ScenarioError> {
    let text = std::fs::read_to_string(path).map_err(|source| ScenarioError::Io {
        path: path.display().to_string(),
        source,
    })?;
    let bad = |message: String| ScenarioError::Input {
        location: None,
        key: path.display().to_string(),
        message,
    };
    let mut rows = Vec::new();
    for (k, row) in csv::Reader::from_reader(text.as_bytes())
        .deserialize::<WorkPrecisionRow>()
        .enumerate()
    {
        let row = row.map_err(|e| bad(format!("row {}: {e}", k + 1)))?;
        for (name, v) in [
            ("time_median_s", row.time_median_s),
            ("end_error", row.end_error),
            ("max_error", row.max_error),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(bad(format!(
                    "row {} ({} {} at rtol {}): {name} = {v} is not a finite non-negative number",
                    k + 1,
                    row.package,
                    row.method,
                    row.rtol
                )));
            }
        }
        rows.push(row);
    }
    Ok(rows)
}

/// The series of the diagram: `(package, series label)` in order of first appearance (the
/// label is [`WorkPrecisionRow::series_label`]: the method, after the model if any).
pub fn series(rows: &[WorkPrecisionRow]) -> Vec<(String, String)> {
    let mut out: Vec<(String, String)> = Vec::new();
    for row in rows {
        let label = row.series_label();
        if !out.iter().any(|(p, m)| *p == row.package && *m == label) {
            out.push((row.package.clone(), label));
        }
    }
    out
}

/// Wall time a series (`method`: its [`WorkPrecisionRow::series_label`]) needs for a
/// maximum error of `target`, interpolated linearly in
/// `log(time)` against `log(error)` between the two ladder points (ordered loose to tight)
/// where the error first falls to `target`. If the loosest point is already at or below
/// the target its time is returned (an upper bound). `None` if the error never gets there.
pub fn time_at_error(
    rows: &[WorkPrecisionRow],
    package: &str,
    method: &str,
    target: f64,
) -> Option<f64> {
    let mut points: Vec<&WorkPrecisionRow> = rows
        .iter()
        .filter(|r| r.package == package && r.series_label() == method)
        .collect();
    points.sort_by(|a, b| b.rtol.total_cmp(&a.rtol));
    let first = points.first()?;
    if first.max_error <= target {
        return Some(first.time_median_s);
    }
    for pair in points.windows(2) {
        let (a, b) = (pair[0], pair[1]);
        if a.max_error > target && b.max_error <= target {
            if b.max_error <= 0.0 || a.time_median_s <= 0.0 || b.time_median_s <= 0.0 {
                return Some(b.time_median_s);
            }
            let s = (target.ln() - a.max_error.ln()) / (b.max_error.ln() - a.max_error.ln());
            return Some(
                (a.time_median_s.ln() + s * (b.time_median_s.ln() - a.time_median_s.ln())).exp(),
            );
        }
    }
    None
}

/// A Markdown table: wall time of each series at maximum error `target`, and how many times
/// faster the best flexprr method is than each series.
pub fn markdown_at_error(rows: &[WorkPrecisionRow], target: f64) -> String {
    let all = series(rows);
    let times: Vec<Option<f64>> = all
        .iter()
        .map(|(p, m)| time_at_error(rows, p, m, target))
        .collect();
    let best = all
        .iter()
        .zip(&times)
        .filter(|((p, _), _)| p == PACKAGE)
        .filter_map(|((_, m), t)| t.map(|t| (m.clone(), t)))
        .min_by(|a, b| a.1.total_cmp(&b.1));
    let mut md = String::new();
    let best_name = best
        .as_ref()
        .map_or("-".to_string(), |(m, _)| format!("flexprr {m}"));
    let _ = writeln!(
        md,
        "| package | method | time at max error {target:.0e} (ms) | {best_name} is faster by |"
    );
    let _ = writeln!(md, "|---|---|---:|---:|");
    for ((p, m), t) in all.iter().zip(&times) {
        let time = t.map_or("not reached".to_string(), |t| format!("{:.3}", 1e3 * t));
        let ratio = match (t, &best) {
            (Some(t), Some((_, b))) if *b > 0.0 => format!("{:.1}x", t / b),
            _ => "-".to_string(),
        };
        let _ = writeln!(md, "| {p} | {m} | {time} | {ratio} |");
    }
    md
}

/// A Markdown table of cost against fidelity, one line per series: the cheapest point (its
/// time and maximum error) and the most accurate point (its maximum error and time). With
/// models side by side, the most accurate error of a model is its model error against the
/// reference model once the tolerance no longer matters.
pub fn markdown_models(rows: &[WorkPrecisionRow]) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "| package | series | cheapest: time (ms) | its max error | most accurate: max error | its time (ms) | its rtol |"
    );
    let _ = writeln!(md, "|---|---|---:|---:|---:|---:|---:|");
    for (package, label) in series(rows) {
        let points: Vec<&WorkPrecisionRow> = rows
            .iter()
            .filter(|r| r.package == package && r.series_label() == label)
            .collect();
        let cheapest = points
            .iter()
            .min_by(|a, b| a.time_median_s.total_cmp(&b.time_median_s));
        let best = points
            .iter()
            .min_by(|a, b| a.max_error.total_cmp(&b.max_error));
        if let (Some(c), Some(b)) = (cheapest, best) {
            let _ = writeln!(
                md,
                "| {package} | {label} | {:.3} | {:.2e} | {:.2e} | {:.3} | {:.0e} |",
                1e3 * c.time_median_s,
                c.max_error,
                b.max_error,
                1e3 * b.time_median_s,
                b.rtol
            );
        }
    }
    md
}

/// A Markdown table of all rows.
pub fn markdown_rows(rows: &[WorkPrecisionRow]) -> String {
    let opt = |v: Option<usize>| v.map_or("-".to_string(), |v| v.to_string());
    let mut md = String::new();
    let _ = writeln!(
        md,
        "| package | method | rtol | time (ms) | steps | rejected | rhs evals | Jacobians | end error | max error |"
    );
    let _ = writeln!(md, "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        let _ = writeln!(
            md,
            "| {} | {} | {:.0e} | {:.3} | {} | {} | {} | {} | {:.2e} | {:.2e} |",
            r.package,
            r.series_label(),
            r.rtol,
            1e3 * r.time_median_s,
            opt(r.accepted_steps),
            opt(r.rejected_steps),
            opt(r.rhs_evaluations),
            opt(r.jacobian_evaluations),
            r.end_error,
            r.max_error
        );
    }
    md
}

/// Writes the work-precision diagram: maximum relative error against median wall time,
/// log-log, one line with markers per `(package, method)`; flexprr solid, peers dashed.
/// Points with a time or error that is not positive cannot be drawn on log axes and are
/// left out; the diagram is an error if no point is left.
///
/// # Errors
/// [`ScenarioError::Run`] if there is nothing to draw or the file cannot be written.
pub fn write_svg(rows: &[WorkPrecisionRow], path: &Path, title: &str) -> Result<(), ScenarioError> {
    use flexprr_run::plot::{Axis, Dash, Figure, Marker, Panel, Series, Style};
    let positive = |v: &f64| v.is_finite() && *v > 0.0;
    let mut panel = Panel::new(Axis::log("max relative error", ""));
    for (k, (package, method)) in series(rows).iter().enumerate() {
        let mut line: Vec<&WorkPrecisionRow> = rows
            .iter()
            .filter(|r| &r.package == package && &r.series_label() == method)
            .filter(|r| positive(&r.time_median_s) && positive(&r.max_error))
            .collect();
        line.sort_by(|a, b| b.rtol.total_cmp(&a.rtol));
        let time: Vec<f64> = line.iter().map(|r| r.time_median_s).collect();
        let error: Vec<f64> = line.iter().map(|r| r.max_error).collect();
        let mut style = Style::nth(k).marker(Marker::CYCLE[k % Marker::CYCLE.len()]);
        if package != PACKAGE {
            style = style.dash(Dash::Dashed);
        }
        panel = panel.series(Series::new(
            format!("{package} {method}"),
            &time,
            &error,
            style,
        ));
    }
    if panel.series.iter().all(|s| s.x.is_empty()) {
        return Err(ScenarioError::Run(format!(
            "plot {}: no positive times and errors to draw",
            path.display()
        )));
    }
    Figure::new(Axis::log("median wall time", "s"))
        .title(title)
        .description("flexprr work-precision diagram")
        .panel(panel)
        .write_svg(path)
        .map_err(ScenarioError::Run)
}
