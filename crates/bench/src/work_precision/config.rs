//! What a work-precision measurement measures: the models side by side, the methods, the
//! tolerance ladder, the error measure and how the reference is computed.

use flexprr_dynamics::Formulation;
use flexprr_scene::{
    MethodHandle, ModelCapabilities, ModelKindHandle, Registry, ScenarioError, Scene,
};

use super::{DEFAULT_TOLERANCES, ErrorMeasure};

/// A model to measure: a registered model kind ([`flexprr_scene::Registry::model_kind`])
/// replacing the scene's `model.coupling`, and for a kind whose links are co-rotational
/// elements, optionally the elements per link replacing `model.elements`.
///
/// Everything the bench asks of a model (its label, how faithful it is, the formulation it
/// needs, the default reference) follows from the kind's [`ModelCapabilities`], never from
/// its name, so a kind registered by a program is measured like the built-in `ked`,
/// `coupled` and `nonlinear`:
///
/// ```
/// use flexprr_bench::work_precision::ModelChoice;
/// use flexprr_dynamics::{DynamicsError, SceneModel};
/// use flexprr_scene::{ModelCapabilities, ModelKind, Registry, Scene};
/// use std::sync::Arc;
///
/// struct Renamed;
/// impl ModelKind for Renamed {
///     fn capabilities(&self) -> ModelCapabilities {
///         ModelCapabilities { linear_in_state: true, assumed_modes: true, ..Default::default() }
///     }
///     fn build(&self, scene: &Scene) -> Result<Box<dyn SceneModel>, DynamicsError> {
///         Ok(Box::new(scene.build_ked(false)?))
///     }
/// }
/// let mut registry = Registry::default();
/// registry.register_model_kind("renamed", Arc::new(Renamed));
/// let choice = ModelChoice::parse_in(&registry, "renamed").unwrap();
/// assert_eq!(choice.name(), "renamed");
/// assert!(ModelChoice::parse("renamed").is_none()); // not a built-in kind
/// assert!(ModelChoice::names(&registry).contains("renamed"));
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ModelChoice {
    /// The registered model kind.
    kind: ModelKindHandle,
    /// Elements per link (kinds in co-rotational elements only); `None`: the scene's own.
    elements: Option<usize>,
}

/// The elements per link a `<kind>:N` name may ask for: even, 2 to 512 (`model.elements`).
const ELEMENTS: std::ops::RangeInclusive<usize> = 2..=512;

impl ModelChoice {
    /// The built-in model kind `name` of [`Registry::default`] (`ked`, `coupled`,
    /// `nonlinear`, `nonlinear:16`), if any: [`Self::parse_in`] on the default registry.
    pub fn parse(name: &str) -> Option<Self> {
        Self::parse_in(&Registry::default(), name)
    }

    /// The model named `name` in `registry`: a registered model kind, or `<kind>:N` for a
    /// kind whose links are co-rotational elements, with `N` elements per link (even, 2 to
    /// 512).
    pub fn parse_in(registry: &Registry, name: &str) -> Option<Self> {
        if let Some(kind) = registry.model_kind(name) {
            return Some(Self {
                kind,
                elements: None,
            });
        }
        let (kind, count) = name.split_once(':')?;
        let kind = registry.model_kind(kind)?;
        if kind.capabilities().assumed_modes {
            return None;
        }
        let n: usize = count.parse().ok()?;
        (ELEMENTS.contains(&n) && n % 2 == 0).then_some(Self {
            kind,
            elements: Some(n),
        })
    }

    /// The names [`Self::parse_in`] accepts in `registry`, for messages, from the least to
    /// the most faithful kind ([`Self::fidelity`]): on the default registry `ked, coupled,
    /// nonlinear, nonlinear:N (N even, 2 to 512)`.
    pub fn names(registry: &Registry) -> String {
        let mut kinds: Vec<ModelKindHandle> = registry
            .model_kind_names()
            .into_iter()
            .filter_map(|name| registry.model_kind(name))
            .collect();
        kinds.sort_by_key(|kind| rank(kind.capabilities()));
        let mut names = Vec::new();
        for kind in kinds {
            names.push(kind.name().to_string());
            if !kind.capabilities().assumed_modes {
                names.push(format!(
                    "{}:N (N even, {} to {})",
                    kind.name(),
                    ELEMENTS.start(),
                    ELEMENTS.end()
                ));
            }
        }
        names.join(", ")
    }

    /// The name [`Self::parse_in`] reads back (`ked`, `nonlinear`, `nonlinear:16`).
    pub fn name(&self) -> String {
        match self.elements {
            None => self.kind.name().to_string(),
            Some(n) => format!("{}:{n}", self.kind.name()),
        }
    }

    /// The scene's own model: its model kind, with its elements per link when its links are
    /// co-rotational elements.
    pub fn of(scene: &Scene) -> Self {
        Self {
            kind: scene.coupling.clone(),
            elements: (!scene.coupling.capabilities().assumed_modes)
                .then_some(scene.large_deflection.elements),
        }
    }

    /// The model kind.
    pub fn kind(&self) -> &ModelKindHandle {
        &self.kind
    }

    /// What the model can do.
    pub fn capabilities(&self) -> ModelCapabilities {
        self.kind.capabilities()
    }

    /// Whether the links are co-rotational elements (`model.elements` sets the model's size;
    /// their axial modes make the model stiff).
    pub fn in_elements(&self) -> bool {
        !self.capabilities().assumed_modes
    }

    /// The elements per link of a model in elements on `scene`.
    fn elements(&self, scene: &Scene) -> Option<usize> {
        self.in_elements()
            .then(|| self.elements.unwrap_or(scene.large_deflection.elements))
    }

    /// The row label on `scene`: the kind's name, with the elements per link when its links
    /// are elements (`nonlinear:16`), else with the scene's formulation unless the kind is
    /// built on the consistent one only (`ked (paper)`, `ked (consistent)`, `coupled`).
    pub fn label(&self, scene: &Scene) -> String {
        let caps = self.capabilities();
        match self.elements(scene) {
            Some(n) => format!("{}:{n}", self.kind.name()),
            None if caps.consistent_only => self.kind.name().to_string(),
            None => format!("{} ({})", self.kind.name(), scene.formulation.name()),
        }
    }

    /// How faithful the model is, for the default reference, from its capabilities: linear
    /// in its state (KED) below a free platform on assumed modes (coupled) below links in
    /// co-rotational elements (nonlinear), and more elements above fewer (the mesh
    /// convergence of docs/coupled.md).
    pub fn fidelity(&self, scene: &Scene) -> usize {
        rank(self.capabilities()) + self.elements(scene).unwrap_or(0)
    }

    /// `scene` with this model.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] at key `models` if a kind built on the consistent equations
    /// only (coupled, nonlinear) is asked of a scene whose formulation is not the consistent
    /// one.
    pub fn apply(&self, scene: &Scene) -> Result<Scene, ScenarioError> {
        let mut out = scene.clone();
        out.coupling = self.kind.clone();
        if let Some(n) = self.elements(scene) {
            out.large_deflection.elements = n;
        }
        if self.capabilities().consistent_only && scene.formulation != Formulation::consistent() {
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

/// The fidelity class of a model kind: 0 linear in its state (KED), 1 other models on
/// assumed modes (coupled), 2 links in co-rotational elements (nonlinear).
fn rank(caps: ModelCapabilities) -> usize {
    if caps.linear_in_state {
        0
    } else if caps.assumed_modes {
        1
    } else {
        2
    }
}

/// How the reference of a model kind is computed by default: the method, its check, the
/// relative tolerance and the accepted disagreement (in the error measure used).
///
/// The plan follows the kind's capabilities, so a registered kind gets the plan of the
/// built-in kind it resembles:
///
/// * KED (linear in its state): `rk45` at `1e-14` checked by `abm` at the same tolerance (a
///   one-step Runge-Kutta pair against a multistep Adams code, so their errors are
///   independent); agreement below `1e-9`.
/// * Coupled (and any other kind on assumed modes): `abm` at `1e-14` checked by `rk45` at the same tolerance;
///   agreement below `1e-9` (the 0.2 s coupled scene at 20 Hz: `8.7e-12` in deflections).
/// * Nonlinear (links in co-rotational elements): `abm` at `1e-10` checked by `rk45` at the same
///   tolerance; agreement below `1e-8`. Tighter costs minutes per run: the elements' axial
///   modes hold both methods to small steps already at loose tolerances, and from `1e-10`
///   on the steps become accuracy-limited on top (32 elements over 20 ms: 376 000 ABM steps
///   at `1e-10`, 1 003 000 at `1e-11`; RK45 193 000 steps of six right-hand sides each at
///   `1e-10`).
pub fn default_reference(capabilities: ModelCapabilities) -> ReferencePlan {
    match rank(capabilities) {
        0 => ReferencePlan {
            method: builtin("rk45"),
            check_method: builtin("abm"),
            rtol: 1e-14,
            check_factor: 1.0,
            agreement_limit: 1e-9,
        },
        2 => ReferencePlan {
            method: builtin("abm"),
            check_method: builtin("rk45"),
            rtol: 1e-10,
            check_factor: 1.0,
            agreement_limit: 1e-8,
        },
        _ => ReferencePlan {
            method: builtin("abm"),
            check_method: builtin("rk45"),
            rtol: 1e-14,
            check_factor: 1.0,
            agreement_limit: 1e-9,
        },
    }
}

/// How a reference is computed: see [`default_reference`].
#[derive(Debug, Clone, PartialEq)]
pub struct ReferencePlan {
    /// Method of the reference.
    pub method: MethodHandle,
    /// Method of its check.
    pub check_method: MethodHandle,
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
    /// Methods to measure: registered integrators ([`flexprr_scene::Registry::method`]), so
    /// a program's own integrator is measured like a built-in one.
    pub methods: Vec<MethodHandle>,
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
            methods: ["abm", "rk45", "bdf", "magnus4", "magnus6", "auto"]
                .into_iter()
                .map(builtin)
                .collect(),
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
        self.reference_model.clone().unwrap_or_else(|| {
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
        // The state measure compares the KED modal states: models linear in their state.
        let other = all.iter().find(|m| !m.capabilities().linear_in_state);
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
        let mut plan = default_reference(model.capabilities());
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

/// The built-in integrator `name` of [`flexprr_scene::Registry::default`].
///
/// # Panics
/// If `name` is not a built-in integrator (a programming error: callers name built-ins).
pub fn builtin(name: &str) -> MethodHandle {
    flexprr_scene::Registry::default()
        .method(name)
        .unwrap_or_else(|| unreachable!("{name} is a built-in integrator"))
}

/// The first element of `items` equal (by `same`) to an earlier one.
pub(crate) fn first_repeat<T>(items: &[T], same: impl Fn(&T, &T) -> bool) -> Option<&T> {
    items
        .iter()
        .enumerate()
        .find(|(k, a)| items[..*k].iter().any(|b| same(a, b)))
        .map(|(_, a)| a)
}
