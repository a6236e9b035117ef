//! The divergence guard: one limit, checked after every accepted step of every run.
//!
//! The small-deflection models are linear in the deflection, so a link that buckles grows
//! exponentially without bound. A run whose deflection passes
//! [`DIVERGENCE_FRACTION`] of a link's length anywhere on the link (checked at
//! [`GUARD_POINTS`]) stops there with [`RunError::Diverged`], keeping every output up to that
//! step, instead of integrating to overflow and returning deflections of kilometres.
//!
//! Half the length is far beyond the small-deflection range (the paper's own 30 Hz KED scene
//! peaks near 12 % of it), so the guard catches a runaway, not a large but bounded vibration;
//! where the small-deflection model itself stops being accurate is a separate question
//! (`docs/stability.md`).

use flexprr_dynamics::SceneModel;
use flexprr_integrators::{Flow, Observer, Solution};

use crate::error::RunError;

/// Points `xi` along each link where the guard checks the deflection.
pub const GUARD_POINTS: [f64; 9] = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9];

/// The divergence limit: a deflection beyond this fraction of the link length is a runaway.
pub const DIVERGENCE_FRACTION: f64 = 0.5;

/// Deflections of every link at fixed points, from a model's state: `w_i(xi_p) =
/// sum_j psi_ij(xi_p) y_j`, with the shape values tabulated once (the models' deflection is
/// linear in their coordinates).
#[derive(Debug, Clone)]
pub struct DeflectionModel {
    points: Vec<f64>,
    /// For each link: the coordinate range in the state and `psi_j(xi_p)`, row `p`.
    links: Vec<(std::ops::Range<usize>, Vec<Vec<f64>>)>,
    lengths: [f64; 3],
}

impl DeflectionModel {
    /// Tabulates the shape values of every link of `model` at `points`; none for a model
    /// whose deflection is not linear in its coordinates ([`flexprr_dynamics::LinearHints::linear_deflection`]:
    /// the nonlinear model, which checks its own collapse limit), so [`DeflectionModel::links`]
    /// is 0 and nothing is checked.
    pub fn new(model: &dyn SceneModel, points: &[f64]) -> Self {
        let mut unit = vec![0.0; model.dim()];
        let tabulated = if model.linear_deflection() { 3 } else { 0 };
        let links = (0..tabulated)
            .map(|i| {
                let range = model.link_range(i);
                let table = points
                    .iter()
                    .map(|&xi| {
                        range
                            .clone()
                            .map(|j| {
                                unit[j] = 1.0;
                                // Linear and time-free (`linear_deflection`): any time will do.
                                let w = model.deflection(0.0, i, xi, &unit).unwrap_or(f64::NAN);
                                unit[j] = 0.0;
                                w
                            })
                            .collect()
                    })
                    .collect();
                (range, table)
            })
            .collect();
        let lengths = std::array::from_fn(|i| model.machine().links[i].length());
        Self {
            points: points.to_vec(),
            links,
            lengths,
        }
    }

    /// Deflection of link `i` at point `p` for the state `y` (m).
    pub fn deflection(&self, i: usize, p: usize, y: &[f64]) -> f64 {
        let (range, table) = &self.links[i];
        table[p]
            .iter()
            .zip(&y[range.clone()])
            .map(|(psi, eta)| psi * eta)
            .sum()
    }

    /// Number of links tabulated (3, or 0 for a model with a nonlinear deflection).
    pub fn links(&self) -> usize {
        self.links.len()
    }

    /// Number of points per link.
    pub fn points(&self) -> usize {
        self.points.len()
    }

    /// The points `xi`.
    pub fn xi(&self) -> &[f64] {
        &self.points
    }

    /// Length of link `i` (m).
    pub fn length(&self, i: usize) -> f64 {
        self.lengths[i]
    }
}

/// The observer that stops a run at the first accepted step beyond the divergence limit.
#[derive(Debug)]
pub struct DivergenceGuard {
    shapes: DeflectionModel,
    max_deflection: f64,
    divergence: Option<RunError>,
}

impl DivergenceGuard {
    /// A guard for `model`'s links at [`GUARD_POINTS`].
    pub fn new(model: &dyn SceneModel) -> Self {
        Self {
            shapes: DeflectionModel::new(model, &GUARD_POINTS),
            max_deflection: 0.0,
            divergence: None,
        }
    }

    /// Largest deflection seen (m).
    pub fn max_deflection(&self) -> f64 {
        self.max_deflection
    }

    /// The divergence that stopped the run, if any.
    pub fn take_divergence(&mut self) -> Option<RunError> {
        self.divergence.take()
    }

    /// The first point of `(t, y)` beyond the limit.
    fn check(&mut self, t: f64, y: &[f64]) -> Option<RunError> {
        for i in 0..self.shapes.links() {
            let limit = DIVERGENCE_FRACTION * self.shapes.length(i);
            for (p, &xi) in GUARD_POINTS.iter().enumerate() {
                let w = self.shapes.deflection(i, p, y);
                self.max_deflection = self.max_deflection.max(w.abs());
                if w.is_nan() || w.abs() > limit {
                    return Some(RunError::Diverged {
                        link: i,
                        t,
                        xi,
                        w,
                        limit,
                        fraction: DIVERGENCE_FRACTION,
                    });
                }
            }
        }
        None
    }
}

/// Checks every accepted step and every output sample (the data written), so a divergence
/// is reported at the first of them beyond the limit, with its value there.
impl Observer for DivergenceGuard {
    fn on_step(&mut self, t: f64, y: &[f64]) -> Flow {
        match self.check(t, y) {
            Some(e) => {
                self.divergence = Some(e);
                Flow::Stop
            }
            None => Flow::Continue,
        }
    }
    fn on_output(&mut self, _index: usize, t: f64, y: &[f64]) -> Flow {
        self.on_step(t, y)
    }
}

/// Relative deflection error of `solution` against `reference` at the points of `model`:
/// the largest difference over all links, points and output times, divided by the largest
/// reference deflection there. `None` when the output times differ or the reference is
/// identically zero.
pub fn deflection_error(
    model: &DeflectionModel,
    solution: &Solution,
    reference: &Solution,
) -> Option<f64> {
    if solution.len() != reference.len() || solution.dim != reference.dim {
        return None;
    }
    let (mut worst, mut scale) = (0.0_f64, 0.0_f64);
    for k in 0..solution.len() {
        let (y, y_ref) = (solution.y(k), reference.y(k));
        for i in 0..model.links() {
            for p in 0..model.points() {
                let w_ref = model.deflection(i, p, y_ref);
                worst = worst.max((model.deflection(i, p, y) - w_ref).abs());
                scale = scale.max(w_ref.abs());
            }
        }
    }
    (scale > 0.0).then(|| worst / scale)
}
