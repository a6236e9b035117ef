//! The rigid chords of a model relaxed into the links' axial springs at rest
//! ([`flexprr_dynamics::ChordCompliance`]; docs/linear.md, "Elastic chords"): the relaxed
//! state's layout and the relaxed `A` and `B`.

use faer::Mat;
use flexprr_dynamics::ChordCompliance;
use flexprr_dynamics::channel::{Axis, Output};

use crate::LinearError;

/// The layout of a linear state with relaxed chords: the model's coordinates, the added
/// ones (the platform's deviation, the links' axial coordinates), their rates, then the
/// model's further states (a continuous law's).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Relaxation<'a> {
    /// The model's coordinates.
    pub(crate) own: usize,
    /// All coordinates.
    pub(crate) total: usize,
    /// The model's state length.
    pub(crate) model_dim: usize,
    /// The relaxation, when the chords are relaxed.
    pub(crate) compliance: Option<&'a ChordCompliance>,
}

impl<'a> Relaxation<'a> {
    pub(crate) fn new(
        compliance: Option<&'a ChordCompliance>,
        coordinates: usize,
        model_dim: usize,
    ) -> Self {
        let added = compliance.map_or(0, ChordCompliance::size);
        Self {
            own: coordinates,
            total: coordinates + added,
            model_dim,
            compliance,
        }
    }

    /// Coordinates added.
    pub(crate) fn added(&self) -> usize {
        self.total - self.own
    }

    /// The relaxed state's length.
    pub(crate) fn dim(&self) -> usize {
        self.model_dim + 2 * self.added()
    }

    /// The relaxed index of the model's state component `k`.
    pub(crate) fn index(&self, k: usize) -> usize {
        let (own, added) = (self.own, self.added());
        if k < own {
            k
        } else if k < 2 * own {
            k + added
        } else {
            k + 2 * added
        }
    }

    /// The model's state `y` in the relaxed layout (the added coordinates 0).
    pub(crate) fn state(&self, y: &[f64]) -> Vec<f64> {
        let mut state = vec![0.0; self.dim()];
        for (k, v) in y.iter().enumerate() {
            state[self.index(k)] = *v;
        }
        state
    }

    /// The gradient of `output` in the added coordinates (empty without them): the
    /// platform pose moves with the deviation, a link point at `xi` by `xi` times its
    /// joint's motion (and the links' axial motion does not move it transversely).
    pub(crate) fn gradient(&self, output: &Output) -> Vec<f64> {
        let Some(cc) = self.compliance else {
            return Vec::new();
        };
        let mut g = vec![0.0; cc.size()];
        match *output {
            Output::Platform(axis) => g[axis_index(axis)] = 1.0,
            Output::Acceleration { link, xi } => {
                for (k, v) in cc.joint_normal[link].iter().enumerate() {
                    g[k] = xi * v;
                }
            }
            _ => {}
        }
        g
    }

    /// The gradient of `output` in the added coordinates' rates.
    pub(crate) fn rate_gradient(&self, output: &Output) -> Vec<f64> {
        let Some(cc) = self.compliance else {
            return Vec::new();
        };
        let mut g = vec![0.0; cc.size()];
        if let Output::PlatformVelocity(axis) = *output {
            g[axis_index(axis)] = 1.0;
        }
        g
    }
}

fn axis_index(axis: Axis) -> usize {
    axis.index()
}

/// `A` and `B` of the model with its chords relaxed ([`flexprr_dynamics::ChordCompliance`]):
/// the model's generalized forces `F = M (A, B)` on its coordinates' acceleration rows, the
/// chords' springs and the point loads' share on the added coordinates, solved with the
/// mass of all coordinates together. `points[k]` is where column `k` of `B` acts when it is
/// a point force.
pub(crate) fn relax_chords(
    a: &Mat<f64>,
    b: &Mat<f64>,
    coordinates: usize,
    cc: &ChordCompliance,
    points: &[Option<(usize, f64)>],
) -> Result<(Mat<f64>, Mat<f64>), LinearError> {
    use faer::linalg::solvers::Solve;
    let added = cc.size();
    let (n, m, nz) = (a.nrows(), b.ncols(), coordinates);
    let layout = Relaxation::new(Some(cc), coordinates, n);
    let total = nz + added;
    let n_new = layout.dim();
    let map = |k| layout.index(k);
    let mut forces = Mat::<f64>::zeros(total, n_new);
    let mut load_forces = Mat::<f64>::zeros(total, m);
    for i in 0..nz {
        for col in 0..n {
            forces[(i, map(col))] = (0..nz).map(|k| cc.mass[(i, k)] * a[(nz + k, col)]).sum();
        }
        for col in 0..m {
            load_forces[(i, col)] = (0..nz).map(|k| cc.mass[(i, k)] * b[(nz + k, col)]).sum();
        }
    }
    for q in 0..added {
        for r in 0..added {
            forces[(nz + q, nz + r)] = -cc.stiffness[(q, r)];
            forces[(nz + q, total + nz + r)] = -cc.damping[(q, r)];
        }
        for (col, point) in points.iter().enumerate() {
            if let Some((link, xi)) = *point {
                if q < 3 {
                    load_forces[(nz + q, col)] = xi * cc.joint_normal[link][q];
                }
            }
        }
    }
    let mass = Mat::from_fn(total, total, |i, j| match (i < nz, j < nz) {
        (true, true) => cc.mass[(i, j)],
        (true, false) => cc.coupling[(i, j - nz)],
        (false, true) => cc.coupling[(j, i - nz)],
        (false, false) => cc.deviation_mass[(i - nz, j - nz)],
    });
    let llt = mass.llt(faer::Side::Lower).map_err(|_| {
        LinearError::Channel(
            "the mass matrix of the machine with elastic chords is not positive definite".into(),
        )
    })?;
    let accelerations = llt.solve(&forces);
    let load_accelerations = llt.solve(&load_forces);
    let mut relaxed = Mat::<f64>::zeros(n_new, n_new);
    let mut relaxed_b = Mat::<f64>::zeros(n_new, m);
    for i in 0..total {
        relaxed[(i, total + i)] = 1.0;
        for col in 0..n_new {
            relaxed[(total + i, col)] = accelerations[(i, col)];
        }
        for col in 0..m {
            relaxed_b[(total + i, col)] = load_accelerations[(i, col)];
        }
    }
    for row in 2 * nz..n {
        for col in 0..n {
            relaxed[(map(row), map(col))] = a[(row, col)];
        }
        for col in 0..m {
            relaxed_b[(map(row), col)] = b[(row, col)];
        }
    }
    Ok((relaxed, relaxed_b))
}
