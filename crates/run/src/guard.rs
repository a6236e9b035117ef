//! The divergence guard: turns modal states into link deflections and finds where a link's
//! deflection leaves the range of the small-deflection model.

use std::fmt;

use flexprr_dynamics::ModalSystem;
use flexprr_integrators::Solution;
use flexprr_scene::Scene;

/// Points `xi` used for the divergence check.
pub const GUARD_POINTS: [f64; 9] = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9];

/// A link whose deflection passed its limit.
#[derive(Debug, Clone, PartialEq)]
pub struct Divergence {
    /// Link index (0-based).
    pub link: usize,
    /// Time (s).
    pub t: f64,
    /// Position `xi` along the link where the limit was exceeded.
    pub xi: f64,
    /// The deflection there (m).
    pub deflection_m: f64,
    /// The limit (m).
    pub limit_m: f64,
}

impl fmt::Display for Divergence {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "link {} diverged at t = {} s: deflection {:.3e} m at xi = {} exceeds the small-deflection limit {:.3e} m",
            self.link + 1,
            self.t,
            self.deflection_m,
            self.xi,
            self.limit_m
        )
    }
}

/// What is needed to turn modal states into deflections (kept with the attempt so that
/// [`the stress classification`] needs no scene).
#[derive(Debug, Clone)]
pub struct DeflectionModel {
    /// For each link: the coordinate range in the state and `psi_j(xi_p)` at
    /// [`CHECK_POINTS`], row `p`, column `j`.
    links: Vec<(std::ops::Range<usize>, Vec<Vec<f64>>)>,
}

impl DeflectionModel {
    /// The shape values `psi_j(xi)` of every link of `scene` at `points`.
    pub fn new(scene: &Scene, system: &ModalSystem, points: &[f64]) -> Self {
        let links = (0..3)
            .map(|i| {
                let link = &scene.machine.links[i];
                let r = link.modes();
                let table = points
                    .iter()
                    .map(|&xi| {
                        (0..r)
                            .map(|j| {
                                let mut unit = vec![0.0; r];
                                unit[j] = 1.0;
                                link.deflection(&unit, xi)
                            })
                            .collect()
                    })
                    .collect();
                (system.link_range(i), table)
            })
            .collect();
        Self { links }
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

    /// Number of points per link.
    pub fn points(&self) -> usize {
        self.links[0].1.len()
    }
}

/// A deflection limit for catching runaway growth after a run, as a fraction of the link
/// length: half the length. Far beyond the small-deflection range (the paper's own 30 Hz
/// scene peaks near a quarter of it), so it only catches a link whose linear model grows
/// exponentially, e.g. while it buckles. Use with [`deflection_excess`].
pub const RUNAWAY_DEFLECTION_FRACTION: f64 = 0.5;

/// The first output sample of `solution` (a run of `system`, built from `scene`) at which a
/// link's deflection at `xi = 0.1, ..., 0.9` exceeds `fraction` of its length, as a
/// [`Divergence`]; `None` if there is none.
pub fn deflection_excess(
    scene: &Scene,
    system: &ModalSystem,
    solution: &Solution,
    fraction: f64,
) -> Option<Divergence> {
    let model = DeflectionModel::new(scene, system, &GUARD_POINTS);
    for k in 0..solution.len() {
        let y = solution.y(k);
        for i in 0..3 {
            let limit = fraction * scene.machine.links[i].length();
            for (p, xi) in GUARD_POINTS.iter().enumerate() {
                let w = model.deflection(i, p, y);
                if w.is_nan() || w.abs() > limit {
                    return Some(Divergence {
                        link: i,
                        t: solution.t[k],
                        xi: *xi,
                        deflection_m: w,
                        limit_m: limit,
                    });
                }
            }
        }
    }
    None
}
