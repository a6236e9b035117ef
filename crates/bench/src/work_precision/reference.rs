//! The reference solution of a work-precision measurement, computed once far below the
//! ladder and checked against a second method, and the achieved errors measured against it.

use std::path::Path;

use flexprr_dynamics::SceneModel;
use flexprr_integrators::{Options, Solution};
use flexprr_scene::{MethodHandle, ScenarioError, Scene};

use super::WorkPrecisionError;
use super::error::{Disagreement, FailedReference};

use super::{DEFLECTION_XI, ErrorMeasure, WorkPrecisionConfig, build};

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

/// Integrates the reference model as `flexprr run` does ([`flexprr_run::integrate_model`]:
/// the scene's stop times, the run layer's divergence guard, the model's own failure
/// causes such as a collapse), with `method` and `options`. `role` names the integration
/// in the error (`pilot run`, `reference`, `check`).
///
/// A reference that diverged or failed is never measured against: its failure comes back
/// as [`WorkPrecisionError::Reference`] naming the scene, the model, the integration, the
/// reason and the time.
fn solve_reference(
    scene: &Scene,
    label: &str,
    role: &'static str,
    model: &mut dyn SceneModel,
    method: &MethodHandle,
    options: Options,
) -> Result<Solution, WorkPrecisionError> {
    let _ = model.take_failure();
    let rtol = options.rtol;
    let integration = flexprr_run::integrate_model(
        scene,
        method.integrator(options).as_ref(),
        model,
        &mut |_| {},
    );
    match integration.failure {
        None => Ok(integration.solution),
        Some(failure) => {
            // Every failure names its time in its own words; added where one does not.
            Err(WorkPrecisionError::Reference(Box::new(FailedReference {
                scene: scene.name.clone(),
                model: label.to_string(),
                role,
                method: method.name().to_string(),
                rtol,
                time: failure.time(),
                reason: failure.to_string(),
            })))
        }
    }
}

/// The links' mid-point deflections `w_i(1/2)` (m) of `solution` of `model`: three per
/// output time, links in order, from [`SceneModel::deflection`] (the modal models'
/// `w = sum_j psi_j(1/2) eta_j`, the paper's eq. 1; the nonlinear model's from the chord of
/// the deflected link). These are the values of `deflections.csv` at `xi = 0.5`.
///
/// # Errors
/// [`WorkPrecisionError::Deflection`] or [`WorkPrecisionError::NotFinite`] naming the time and
/// link if a deflection cannot be computed or is not finite.
pub fn midpoint_deflections(
    model: &mut dyn SceneModel,
    solution: &Solution,
) -> Result<Vec<f64>, WorkPrecisionError> {
    let n = solution.t.len();
    let kind = model.kind();
    let mut w = Vec::with_capacity(3 * n);
    for k in 0..n {
        let (t, y) = (solution.t[k], solution.y(k));
        for i in 0..3 {
            w.push(model.deflection(t, i, DEFLECTION_XI, y).map_err(|source| {
                WorkPrecisionError::Deflection {
                    link: i + 1,
                    t,
                    model: kind.to_string(),
                    source,
                }
            })?);
        }
    }
    if let Some(j) = w.iter().position(|v| !v.is_finite()) {
        return Err(WorkPrecisionError::NotFinite {
            what: format!("mid-point deflection of link {}", j % 3 + 1),
            t: solution.t[j / 3],
            model: Some(kind.to_string()),
            value: w[j],
        });
    }
    Ok(w)
}

/// The error of `values` against `reference`, both row by row with `width` values per output
/// time `t[k]`: per row the largest `|v_i - v_ref_i| / size(i)`, at the end time and the
/// maximum over the rows.
///
/// # Errors
/// [`WorkPrecisionError::NotFinite`] naming the value (`name(i)`) and time of the first
/// non-finite one.
fn max_row_error(
    values: &[f64],
    reference: &[f64],
    width: usize,
    t: &[f64],
    size: impl Fn(usize) -> f64,
    name: impl Fn(usize) -> String,
) -> Result<AchievedError, WorkPrecisionError> {
    let (mut max, mut row_error) = (0.0_f64, 0.0_f64);
    for (k, (row, reference)) in values
        .chunks_exact(width)
        .zip(reference.chunks_exact(width))
        .enumerate()
    {
        row_error = 0.0;
        for (i, (v, v_ref)) in row.iter().zip(reference).enumerate() {
            if !v.is_finite() {
                return Err(WorkPrecisionError::NotFinite {
                    what: name(i),
                    t: t[k],
                    model: None,
                    value: *v,
                });
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
    ) -> Result<Self, WorkPrecisionError> {
        match measure {
            ErrorMeasure::State => Ok(Self::from_states(
                solution.t,
                solution.states,
                model.modes(),
            )?),
            ErrorMeasure::Deflection => {
                let w = midpoint_deflections(model, &solution)?;
                Ok(Self::from_deflections(solution.t, w)?)
            }
        }
    }

    /// Computes the reference for a scene: the reference model
    /// ([`WorkPrecisionConfig::reference_model`]) integrated as its [`ReferencePlan`](super::ReferencePlan) says
    /// ([`WorkPrecisionConfig::reference_plan`], [`default_reference`](super::default_reference)), checked against a
    /// second integration, in the error measure of [`WorkPrecisionConfig::error_measure`].
    /// A pilot run (ABM at `1e-8`) gives the size for the absolute tolerance.
    ///
    /// # Errors
    /// [`ScenarioError::Input`] (in [`WorkPrecisionError::Scene`]) for a bad configuration,
    /// [`WorkPrecisionError::Reference`], [`WorkPrecisionError::InModel`] or
    /// [`WorkPrecisionError::Unconfirmed`] if an
    /// integration fails or the two disagree by more than the plan's limit.
    pub fn compute(
        scene: &Scene,
        config: &WorkPrecisionConfig,
    ) -> Result<Self, WorkPrecisionError> {
        config.validate()?;
        let measure = config.error_measure(scene)?;
        let plan = config.reference_plan(scene)?;
        let choice = config.reference_model(scene);
        let label = choice.label(scene);
        let model_scene = choice.apply(scene)?;
        let mut system = build(&model_scene)?;
        let in_model = |stage: &'static str| {
            let model = label.clone();
            move |e: WorkPrecisionError| WorkPrecisionError::InModel {
                model,
                stage,
                source: Box::new(e),
            }
        };
        let pilot_rtol = 1e-8;
        let pilot = solve_reference(
            &model_scene,
            &label,
            "pilot run",
            system.as_mut(),
            &crate::work_precision::config::builtin("abm"),
            model_scene.options.clone().rtol(pilot_rtol),
        )?;
        let pilot = Self::from_solution(measure, system.as_mut(), pilot)
            .map_err(in_model("pilot run for the reference"))?;
        let size = pilot.displacement_size;
        let options = |rtol: f64| Options::default().rtol(rtol).atol(rtol * size);
        let check_rtol = plan.rtol * plan.check_factor;
        let main = solve_reference(
            &model_scene,
            &label,
            "reference",
            system.as_mut(),
            &plan.method,
            options(plan.rtol),
        )?;
        let check = solve_reference(
            &model_scene,
            &label,
            "check",
            system.as_mut(),
            &plan.check_method,
            options(check_rtol),
        )?;
        let mut reference =
            Self::from_solution(measure, system.as_mut(), main).map_err(in_model("reference"))?;
        let agreement = reference.errors_of(system.as_mut(), &check)?;
        if agreement.max.is_nan() || agreement.max > plan.agreement_limit {
            return Err(WorkPrecisionError::Unconfirmed(Box::new(Disagreement {
                model: label,
                method: plan.method.name().to_string(),
                rtol: plan.rtol,
                check_method: plan.check_method.name().to_string(),
                check_rtol,
                end: agreement.end,
                max: agreement.max,
                measure: measure.name(),
                limit: plan.agreement_limit,
            })));
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
    ) -> Result<AchievedError, WorkPrecisionError> {
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
    /// [`WorkPrecisionError::WrongMeasure`] if this is not a deflection reference,
    /// [`WorkPrecisionError::Shape`] if the shape differs, [`WorkPrecisionError::NotFinite`] if a
    /// value is not finite (naming the link and time).
    pub fn deflection_errors(&self, w: &[f64]) -> Result<AchievedError, WorkPrecisionError> {
        if self.measure != ErrorMeasure::Deflection {
            return Err(WorkPrecisionError::WrongMeasure {
                reference: self.measure,
            });
        }
        if w.len() != self.deflections.len() {
            return Err(WorkPrecisionError::Shape {
                measure: ErrorMeasure::Deflection,
                given: w.len(),
                expected: self.deflections.len(),
                times: self.t.len(),
                width: 3,
            });
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
    /// [`WorkPrecisionError::WrongMeasure`] if this is not a state reference,
    /// [`WorkPrecisionError::Shape`] if the shape differs, [`WorkPrecisionError::NotFinite`] if a
    /// value is not finite.
    pub fn errors(&self, states: &[f64]) -> Result<AchievedError, WorkPrecisionError> {
        if self.measure != ErrorMeasure::State {
            return Err(WorkPrecisionError::WrongMeasure {
                reference: self.measure,
            });
        }
        let dim = self.dim();
        if states.len() != self.states.len() {
            return Err(WorkPrecisionError::Shape {
                measure: ErrorMeasure::State,
                given: states.len(),
                expected: self.states.len(),
                times: self.t.len(),
                width: dim,
            });
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
    /// [`WorkPrecisionError::Write`] naming the file if it cannot be written.
    pub fn write_csv(&self, path: &Path) -> Result<(), WorkPrecisionError> {
        let mut w = csv::Writer::from_writer(Vec::new());
        let write_err = |e: &dyn std::fmt::Display| WorkPrecisionError::Write {
            path: path.display().to_string(),
            message: e.to_string(),
        };
        let csv_err = |e: csv::Error| write_err(&e);
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
        let bytes = w.into_inner().map_err(|e| write_err(&e))?;
        std::fs::write(path, bytes).map_err(|e| write_err(&e))
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
