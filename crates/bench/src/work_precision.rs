//! Work-precision measurement: how much wall time each integrator needs for a given achieved
//! accuracy on a scene's modal ODE.
//!
//! For every method and every tolerance of a ladder the scene's modal system is integrated
//! over the scene's output times; the wall time is the median of several timed repeats after
//! warm-up runs, and the achieved error is measured against a [`Reference`] solution computed
//! once at a far tighter tolerance and checked against a second method. This is the
//! work-precision diagram of Hairer, Norsett & Wanner, *Solving ODEs I*, 2nd ed., II.10
//! (error against computing time, log-log), as DiffEqDevTools and the SciPy benchmarks draw it.
//!
//! Tolerances: at ladder value `tol` every solver gets `rtol = tol` and the scalar
//! `atol = tol * s`, with `s` the size of the modal coordinates (largest `|eta|` of the
//! reference), so that a zero initial state does not make the absolute tolerance meaningless.
//!
//! Errors are relative to the solution's size, block by block: the state is `(eta, eta')`,
//! and a difference in a displacement is divided by the largest `|eta|` of the reference,
//! one in a velocity by the largest `|eta'|`. Two numbers are reported: at the end time
//! ([`AchievedError::end`]) and the maximum over all output times ([`AchievedError::max`]).
//!
//! Rows of other packages (the `benches/peers` crate, the SciPy script) use the same CSV
//! columns ([`WorkPrecisionRow`]) and can be merged with [`read_csv`].

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant as Clock;

use flexprr_dynamics::SceneModel;
use flexprr_integrators::{Options, Solution};
use serde::{Deserialize, Serialize};

use flexprr_scene::ScenarioError;
use flexprr_scene::{Method, Scene};

/// The default tolerance ladder, `1e-3` down to `1e-12` (one per decade).
pub const DEFAULT_TOLERANCES: [f64; 10] = [
    1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12,
];

/// The name of this package in the `package` column.
pub const PACKAGE: &str = "flexprr";

/// What to measure and how.
#[derive(Debug, Clone, PartialEq)]
pub struct WorkPrecisionConfig {
    /// Relative tolerances of the ladder (loose to tight).
    pub tolerances: Vec<f64>,
    /// Methods to measure.
    pub methods: Vec<Method>,
    /// Untimed runs before the timed ones (caches, branch predictors, page faults).
    pub warmup: usize,
    /// Timed runs per point; the median is reported.
    pub repeats: usize,
    /// Relative tolerance of the reference and of its check (far below the ladder).
    pub reference_rtol: f64,
    /// Largest accepted disagreement between the reference and its check, in the relative
    /// error measure of [`Reference::errors`].
    pub reference_agreement_limit: f64,
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
            warmup: 2,
            repeats: 7,
            reference_rtol: 1e-14,
            reference_agreement_limit: 1e-9,
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
        if self.repeats == 0 {
            return bad("repeats", "at least one timed run is needed".to_string());
        }
        let tightest = self.tolerances.iter().copied().fold(1.0, f64::min);
        if !(self.reference_rtol > 0.0 && self.reference_rtol < tightest) {
            return bad(
                "reference_rtol",
                format!(
                    "{} must be positive and below the tightest ladder tolerance {tightest}",
                    self.reference_rtol
                ),
            );
        }
        if self.reference_agreement_limit.is_nan() || self.reference_agreement_limit <= 0.0 {
            return bad(
                "reference_agreement_limit",
                format!("{} must be positive", self.reference_agreement_limit),
            );
        }
        Ok(())
    }
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
#[derive(Debug, Clone, PartialEq)]
pub struct Reference {
    /// Output times (s).
    pub t: Vec<f64>,
    /// States row by row, `t.len()` rows of `2 * modes` values `(eta, eta')`.
    pub states: Vec<f64>,
    /// Number of modal coordinates (half the state dimension).
    pub modes: usize,
    /// Largest `|eta|` over all coordinates and times (m).
    pub displacement_size: f64,
    /// Largest `|eta'|` over all coordinates and times (m/s).
    pub velocity_size: f64,
    /// Method that computed the reference (empty if read from a file).
    pub method: String,
    /// Method that checked it.
    pub check_method: String,
    /// Disagreement between the reference and the check.
    pub agreement: Option<AchievedError>,
}

/// Solves the scene's model with `method` and `options` over the scene's output times,
/// stopping at the scene's stop times (the same loop as `flexprr run`). On failure, the
/// message names the method, the tolerance and the model's own cause when it has one.
fn solve(
    scene: &Scene,
    model: &mut dyn SceneModel,
    method: Method,
    options: Options,
) -> Result<Solution, String> {
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

/// The scene's model from its one builder.
fn build(scene: &Scene) -> Result<Box<dyn SceneModel>, ScenarioError> {
    scene
        .build_model()
        .map_err(|e| ScenarioError::Run(e.to_string()))
}

impl Reference {
    /// A reference from states at output times; the sizes are taken from the states.
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
            states,
            modes,
            displacement_size,
            velocity_size,
            method: String::new(),
            check_method: String::new(),
            agreement: None,
        })
    }

    /// Computes the reference for a scene: [`flexprr_integrators::Rk45`] at `config.reference_rtol`, checked
    /// against [`flexprr_integrators::Abm`] at the same tolerance (a different method family: a one-step
    /// Runge-Kutta pair against a multistep Adams code, so their errors are independent).
    ///
    /// # Errors
    /// [`ScenarioError::Run`] if an integration fails or the two disagree by more than
    /// `config.reference_agreement_limit`.
    pub fn compute(scene: &Scene, config: &WorkPrecisionConfig) -> Result<Self, ScenarioError> {
        config.validate()?;
        let mut system = build(scene)?;
        let t_out = scene.output_times.clone();
        let modes = system.modes();
        // A pilot run gives the size of the displacements for the absolute tolerance.
        let pilot_rtol = 1e-8;
        let pilot = solve(
            scene,
            system.as_mut(),
            Method::Abm,
            scene.options.clone().rtol(pilot_rtol),
        )
        .map_err(ScenarioError::Run)?;
        let pilot = Self::from_states(t_out.clone(), pilot.states, modes)
            .map_err(|e| ScenarioError::Run(format!("pilot run for the reference: {e}")))?;
        let rtol = config.reference_rtol;
        let options = Options::default()
            .rtol(rtol)
            .atol(rtol * pilot.displacement_size);
        let mut solve_with = |method: Method| {
            solve(scene, system.as_mut(), method, options.clone()).map_err(ScenarioError::Run)
        };
        let main = solve_with(Method::Rk45)?;
        let check = solve_with(Method::Abm)?;
        let mut reference = Self::from_states(t_out, main.states, modes)
            .map_err(|e| ScenarioError::Run(format!("reference: {e}")))?;
        let agreement = reference.errors(&check.states)?;
        if agreement.max.is_nan() || agreement.max > config.reference_agreement_limit {
            return Err(ScenarioError::Run(format!(
                "the reference (rk45) and its check (abm) at rtol {rtol:e} disagree by {:e} \
                 (end) / {:e} (max), above the limit {:e}",
                agreement.end, agreement.max, config.reference_agreement_limit
            )));
        }
        reference.method = Method::Rk45.name().to_string();
        reference.check_method = Method::Abm.name().to_string();
        reference.agreement = Some(agreement);
        Ok(reference)
    }

    /// State dimension.
    pub fn dim(&self) -> usize {
        2 * self.modes
    }

    /// The scalar absolute tolerance that goes with relative tolerance `tol`.
    pub fn atol(&self, tol: f64) -> f64 {
        tol * self.displacement_size
    }

    /// Errors of `states` (row by row at the reference's times) relative to the solution's
    /// size: `|y_i - y_ref_i| / s_i` with `s_i` the displacement or velocity size.
    ///
    /// # Errors
    /// [`ScenarioError::Run`] if the shape differs or a value is not finite.
    pub fn errors(&self, states: &[f64]) -> Result<AchievedError, ScenarioError> {
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
        let mut max = 0.0_f64;
        let mut row_error = 0.0_f64;
        for (k, (row, reference)) in states
            .chunks_exact(dim)
            .zip(self.states.chunks_exact(dim))
            .enumerate()
        {
            row_error = 0.0;
            for (i, (y, y_ref)) in row.iter().zip(reference).enumerate() {
                if !y.is_finite() {
                    return Err(ScenarioError::Run(format!(
                        "component {i} at t = {} s is not finite ({y})",
                        self.t[k]
                    )));
                }
                let size = if i < self.modes {
                    self.displacement_size
                } else {
                    self.velocity_size
                };
                row_error = row_error.max((y - y_ref).abs() / size);
            }
            max = max.max(row_error);
        }
        Ok(AchievedError {
            end: row_error,
            max,
        })
    }

    /// Writes the reference as CSV: `t_s`, then `eta_1 .. eta_n`, then `eta_dot_1 ..`.
    ///
    /// # Errors
    /// [`ScenarioError::Io`] or [`ScenarioError::Run`] if the file cannot be written.
    pub fn write_csv(&self, path: &Path) -> Result<(), ScenarioError> {
        let mut w = csv::Writer::from_writer(Vec::new());
        let csv_err = |e: csv::Error| ScenarioError::Run(format!("{}: {e}", path.display()));
        let mut header = vec!["t_s".to_string()];
        header.extend((1..=self.modes).map(|j| format!("eta_{j}")));
        header.extend((1..=self.modes).map(|j| format!("eta_dot_{j}")));
        w.write_record(&header).map_err(csv_err)?;
        for (t, row) in self.t.iter().zip(self.states.chunks_exact(self.dim())) {
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

    /// Reads a reference written by [`Reference::write_csv`].
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
        let columns = r.headers().map_err(|e| bad(e.to_string()))?.len();
        if columns < 3 || (columns - 1) % 2 != 0 {
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

/// Measures flexprr's integrators on `scene` over the ladder against `reference`.
/// `progress` sees each row as it is measured.
///
/// # Errors
/// [`ScenarioError::Input`] for a bad configuration, [`ScenarioError::Run`] if the system
/// cannot be built. A point whose integration fails is listed in the failures instead.
pub fn measure(
    scene: &Scene,
    reference: &Reference,
    config: &WorkPrecisionConfig,
    progress: &mut dyn FnMut(&WorkPrecisionRow),
) -> Result<(Vec<WorkPrecisionRow>, Vec<String>), ScenarioError> {
    config.validate()?;
    let mut system = build(scene)?;
    let (mut rows, mut failures) = (Vec::new(), Vec::new());
    for &method in &config.methods {
        for &rtol in &config.tolerances {
            let atol = reference.atol(rtol);
            let options = Options::default().rtol(rtol).atol(atol);
            let timed = time_runs(config.warmup, config.repeats, || {
                solve(scene, system.as_mut(), method, options.clone())
            });
            let (solution, timing) = match timed {
                Ok(ok) => ok,
                Err(message) => {
                    failures.push(message);
                    continue;
                }
            };
            let error = match reference.errors(&solution.states) {
                Ok(error) => error,
                Err(e) => {
                    failures.push(format!("{} at rtol {rtol:e}: {e}", method.name()));
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
            };
            progress(&row);
            rows.push(row);
        }
    }
    Ok((rows, failures))
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

/// The series of the diagram: `(package, method)` in order of first appearance.
pub fn series(rows: &[WorkPrecisionRow]) -> Vec<(String, String)> {
    let mut out: Vec<(String, String)> = Vec::new();
    for row in rows {
        if !out
            .iter()
            .any(|(p, m)| *p == row.package && *m == row.method)
        {
            out.push((row.package.clone(), row.method.clone()));
        }
    }
    out
}

/// Wall time a series needs for a maximum error of `target`, interpolated linearly in
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
        .filter(|r| r.package == package && r.method == method)
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
            r.method,
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
            .filter(|r| &r.package == package && &r.method == method)
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
