//! Natural frequencies of one link under an axial load (model.md section 7).

use crate::{BeamError, ModalIntegrals};
use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{self, ComputeEigenvectors};
use faer::{Mat, MatRef, Par, Side};

/// Axial force along the link, `P(x) = p0 + p1 x + p2 x^2`, `x` in metres from the slider
/// end B; tension positive (model.md section 5).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AxialLoad {
    /// Constant term (N).
    pub p0: f64,
    /// Linear coefficient (N/m).
    pub p1: f64,
    /// Quadratic coefficient (N/m^2).
    pub p2: f64,
}

impl AxialLoad {
    /// Uniform axial force `P` (N), tension positive.
    pub fn uniform(force: f64) -> Self {
        Self {
            p0: force,
            p1: 0.0,
            p2: 0.0,
        }
    }

    /// `P(x)` at `x` metres from B.
    pub fn at(&self, x: f64) -> f64 {
        self.p0 + x * (self.p1 + x * self.p2)
    }

    /// The load multiplied by `factor`.
    pub fn scaled(&self, factor: f64) -> Self {
        Self {
            p0: factor * self.p0,
            p1: factor * self.p1,
            p2: factor * self.p2,
        }
    }

    fn check(&self) -> Result<(), BeamError> {
        for (name, value) in [("p0", self.p0), ("p1", self.p1), ("p2", self.p2)] {
            if !value.is_finite() {
                return Err(BeamError::InvalidParameter {
                    name,
                    value,
                    reason: "axial load coefficients must be finite",
                });
            }
        }
        Ok(())
    }
}

/// How the modes are coupled in the frequency problem.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Coupling {
    /// Full symmetric matrices: the generalized eigenproblem `K v = omega^2 M v`.
    /// Eigenvalues are returned in ascending order.
    Full,
    /// Diagonals only, `omega_j^2 = k_jj / m_jj` (the paper's eq. 22). Eigenvalues keep the
    /// basis index `j` (not sorted), since the paper tracks "mode j".
    Diagonal,
}

impl Coupling {
    /// `"full"` or `"diagonal"`.
    pub fn name(self) -> &'static str {
        match self {
            Coupling::Full => "full",
            Coupling::Diagonal => "diagonal",
        }
    }
}

/// Reusable frequency solver for one link: the mass matrix is fixed, the stiffness changes
/// from call to call. Allocation-free after construction.
///
/// Full coupling: `M = L L^T` is factored once (Cholesky); each call forms the symmetric
/// `A = L^-1 K L^-T` by two triangular substitutions and takes its eigenvalues with faer's
/// self-adjoint eigensolver (Householder tridiagonalisation + implicit QR), which are the
/// eigenvalues `omega^2` of the pencil `(K, M)` (Golub & Van Loan, *Matrix Computations*,
/// section 8.7.2). Diagonal coupling: `omega_j^2 = K_jj / M_jj` (eq. 22).
pub struct FrequencySolver {
    coupling: Coupling,
    r: usize,
    mass_diagonal: Vec<f64>,
    cholesky_lower: Mat<f64>,
    half_solved: Mat<f64>,
    reduced: Mat<f64>,
    eigenvalues: Diag<f64>,
    scratch: MemBuffer,
}

impl std::fmt::Debug for FrequencySolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FrequencySolver")
            .field("coupling", &self.coupling)
            .field("r", &self.r)
            .finish_non_exhaustive()
    }
}

impl FrequencySolver {
    /// Prepares the solver for the mass matrix of `integrals`.
    pub fn new(integrals: &ModalIntegrals, coupling: Coupling) -> Result<Self, BeamError> {
        Self::from_mass(integrals.mass.as_ref(), coupling)
    }

    /// Prepares the solver for any symmetric positive definite mass matrix.
    pub fn from_mass(mass: MatRef<'_, f64>, coupling: Coupling) -> Result<Self, BeamError> {
        let r = mass.nrows();
        if r == 0 || mass.ncols() != r {
            return Err(BeamError::DimensionMismatch {
                what: "mass matrix columns",
                expected: r,
                found: mass.ncols(),
            });
        }
        let mass_diagonal: Vec<f64> = (0..r).map(|j| mass[(j, j)]).collect();
        if mass_diagonal.iter().any(|m| !(m.is_finite() && *m > 0.0)) {
            return Err(BeamError::MassNotPositiveDefinite { size: r });
        }
        let (cholesky_lower, scratch) = match coupling {
            Coupling::Full => {
                let llt = mass
                    .llt(Side::Lower)
                    .map_err(|_| BeamError::MassNotPositiveDefinite { size: r })?;
                let req = evd::self_adjoint_evd_scratch::<f64>(
                    r,
                    ComputeEigenvectors::No,
                    Par::Seq,
                    Default::default(),
                );
                (llt.L().to_owned(), MemBuffer::new(req))
            }
            Coupling::Diagonal => (
                Mat::zeros(0, 0),
                MemBuffer::new(faer::dyn_stack::StackReq::EMPTY),
            ),
        };
        let work = |n| Mat::zeros(n, n);
        let n_work = if coupling == Coupling::Full { r } else { 0 };
        let mut solver = Self {
            coupling,
            r,
            mass_diagonal,
            cholesky_lower,
            half_solved: work(n_work),
            reduced: work(n_work),
            eigenvalues: Diag::zeros(n_work),
            scratch,
        };
        // One solve now (K = M, all eigenvalues 1), so that faer's one-time lazy
        // initialisation (cache sizes) happens here and not in the first hot-path call.
        let mut warm_up = vec![0.0; r];
        solver.eigenvalues(mass, &mut warm_up)?;
        Ok(solver)
    }

    /// Number of modes `r`.
    pub fn r(&self) -> usize {
        self.r
    }

    /// The coupling.
    pub fn coupling(&self) -> Coupling {
        self.coupling
    }

    /// Eigenvalues `omega^2` (rad^2/s^2) of `(K, M)` written into `out` (length `r`):
    /// ascending for [`Coupling::Full`], in basis order for [`Coupling::Diagonal`].
    /// `K` must be symmetric (e.g. `Kf + Kp [- b'^2 M]`); a negative or zero eigenvalue
    /// means that mode is buckled (statically unstable) at this load.
    pub fn eigenvalues(
        &mut self,
        stiffness: MatRef<'_, f64>,
        out: &mut [f64],
    ) -> Result<(), BeamError> {
        let r = self.r;
        if stiffness.nrows() != r || stiffness.ncols() != r {
            return Err(BeamError::DimensionMismatch {
                what: "stiffness matrix",
                expected: r,
                found: if stiffness.nrows() == r {
                    stiffness.ncols()
                } else {
                    stiffness.nrows()
                },
            });
        }
        if out.len() != r {
            return Err(BeamError::DimensionMismatch {
                what: "eigenvalue output",
                expected: r,
                found: out.len(),
            });
        }
        match self.coupling {
            Coupling::Diagonal => {
                for (j, o) in out.iter_mut().enumerate() {
                    let k = stiffness[(j, j)];
                    if !k.is_finite() {
                        return Err(BeamError::NonFiniteStiffness {
                            row: j,
                            col: j,
                            value: k,
                        });
                    }
                    *o = k / self.mass_diagonal[j];
                }
            }
            Coupling::Full => {
                let l = &self.cholesky_lower;
                // X = L^-1 K, column by column (forward substitution).
                for c in 0..r {
                    for i in 0..r {
                        let k = stiffness[(i, c)];
                        if !k.is_finite() {
                            return Err(BeamError::NonFiniteStiffness {
                                row: i,
                                col: c,
                                value: k,
                            });
                        }
                        let mut sum = k;
                        for p in 0..i {
                            sum -= l[(i, p)] * self.half_solved[(p, c)];
                        }
                        self.half_solved[(i, c)] = sum / l[(i, i)];
                    }
                }
                // A = L^-1 X^T = L^-1 K L^-T (K symmetric): column c solves L a = X[c, :]^T.
                for c in 0..r {
                    for i in 0..r {
                        let mut sum = self.half_solved[(c, i)];
                        for p in 0..i {
                            sum -= l[(i, p)] * self.reduced[(p, c)];
                        }
                        self.reduced[(i, c)] = sum / l[(i, i)];
                    }
                }
                // Symmetrise the lower triangle (the only part the eigensolver reads).
                for c in 0..r {
                    for i in c + 1..r {
                        let mean = 0.5 * (self.reduced[(i, c)] + self.reduced[(c, i)]);
                        self.reduced[(i, c)] = mean;
                    }
                }
                evd::self_adjoint_evd(
                    self.reduced.as_ref(),
                    self.eigenvalues.as_mut(),
                    None,
                    Par::Seq,
                    MemStack::new(&mut self.scratch),
                    Default::default(),
                )
                .map_err(|_| BeamError::EigenNoConvergence { size: r })?;
                for (j, o) in out.iter_mut().enumerate() {
                    *o = self.eigenvalues[j];
                }
            }
        }
        Ok(())
    }
}

/// Whether a mode is statically stable at the load.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ModeState {
    /// `omega^2 > 0`: the mode vibrates at `frequency_hz`.
    Stable,
    /// `omega^2 = 0` within `1e-10` of the stiffness scale: neutral (exactly at a critical
    /// load, or an unloaded rigid-body mode). Counted as buckled: the stiffness is not
    /// positive definite.
    Neutral,
    /// `omega^2 < 0`: the link buckles in this mode (divergence).
    Buckled,
}

impl ModeState {
    /// `"stable"`, `"neutral"` or `"buckled"`.
    pub fn name(self) -> &'static str {
        match self {
            ModeState::Stable => "stable",
            ModeState::Neutral => "neutral",
            ModeState::Buckled => "buckled",
        }
    }
}

/// One mode of [`LinkFrequencies`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeFrequency {
    /// 1-based mode number: the basis index `j + 1` for [`Coupling::Diagonal`], the rank in
    /// ascending order for [`Coupling::Full`].
    pub mode: usize,
    /// Eigenvalue `omega^2` (rad^2/s^2); negative when buckled.
    pub omega_squared: f64,
    /// `sqrt(omega^2) / (2 pi)` (Hz) when stable, `0` otherwise (never NaN).
    pub frequency_hz: f64,
    /// Stability of the mode.
    pub state: ModeState,
}

/// Frequencies of one link at one load.
#[derive(Debug, Clone, PartialEq)]
pub struct LinkFrequencies {
    /// The coupling used.
    pub coupling: Coupling,
    /// One entry per mode (see [`ModeFrequency::mode`] for the order).
    pub modes: Vec<ModeFrequency>,
    /// Smallest factor `lambda > 0` such that the load `lambda P(x)` makes the stiffness
    /// `Kf + lambda Kp` singular (critical load factor); `< 1` means the given load already
    /// buckles the link; `None` if no positive multiple of this load buckles it (e.g. tension).
    pub critical_load_factor: Option<f64>,
}

impl LinkFrequencies {
    /// Smallest eigenvalue `omega^2` (rad^2/s^2).
    pub fn lowest_eigenvalue(&self) -> f64 {
        self.modes
            .iter()
            .map(|m| m.omega_squared)
            .fold(f64::INFINITY, f64::min)
    }

    /// True if any mode is not [`ModeState::Stable`] (stiffness not positive definite).
    pub fn is_buckled(&self) -> bool {
        self.modes.iter().any(|m| m.state != ModeState::Stable)
    }

    /// Frequencies in Hz, in mode order (0 for buckled modes).
    pub fn frequencies_hz(&self) -> Vec<f64> {
        self.modes.iter().map(|m| m.frequency_hz).collect()
    }
}

/// Relative size of `|omega^2|` below which a mode is [`ModeState::Neutral`].
const NEUTRAL: f64 = 1e-10;

/// Natural frequencies of one link under the axial load `P(x)` (model.md section 7):
/// eigenvalues of `(Kf + Kp, M)` (full) or eq. 22 (diagonal), with buckled modes flagged and
/// the critical load factor (full: the buckling eigenproblem `(-Kp, Kf)`, or bisection on
/// the lowest eigenvalue of `(Kf + lambda Kp, M)` when `Kf` has rigid-body modes;
/// diagonal: `min_j kf_jj / (-kp_jj)` over `kp_jj < 0`).
///
/// Allocates; for repeated calls use [`FrequencySolver`].
pub fn frequencies(
    integrals: &ModalIntegrals,
    load: &AxialLoad,
    coupling: Coupling,
) -> Result<LinkFrequencies, BeamError> {
    load.check()?;
    let r = integrals.r();
    let mut solver = FrequencySolver::new(integrals, coupling)?;
    let geometric = integrals.geometric_stiffness(load);
    let mut total = Mat::zeros(r, r);
    integrals.total_stiffness_into(load, total.as_mut());
    let mut omega2 = vec![0.0; r];
    solver.eigenvalues(total.as_ref(), &mut omega2)?;

    let scale = (0..r)
        .map(|j| {
            (integrals.stiffness[(j, j)].abs() + geometric[(j, j)].abs()) / integrals.mass[(j, j)]
        })
        .fold(0.0, f64::max);
    let modes = omega2
        .iter()
        .enumerate()
        .map(|(j, &w2)| {
            let state = if w2.abs() <= NEUTRAL * scale {
                ModeState::Neutral
            } else if w2 < 0.0 {
                ModeState::Buckled
            } else {
                ModeState::Stable
            };
            let frequency_hz = if state == ModeState::Stable {
                w2.sqrt() / (2.0 * std::f64::consts::PI)
            } else {
                0.0
            };
            ModeFrequency {
                mode: j + 1,
                omega_squared: w2,
                frequency_hz,
                state,
            }
        })
        .collect();

    let critical_load_factor = match coupling {
        Coupling::Diagonal => (0..r)
            .filter(|&j| geometric[(j, j)] < 0.0)
            .map(|j| integrals.stiffness[(j, j)].max(0.0) / -geometric[(j, j)])
            .reduce(f64::min),
        Coupling::Full => critical_factor_full(integrals, &geometric, &mut solver, &mut omega2)?,
    };
    Ok(LinkFrequencies {
        coupling,
        modes,
        critical_load_factor,
    })
}

/// Largest load factor tried before concluding that a load never buckles the link.
const MAX_LOAD_FACTOR: f64 = 1e15;

/// Critical load factor for full coupling.
///
/// If `Kf` is positive definite (no rigid-body modes): `Kf + lambda Kp` is singular when
/// `1/lambda` is an eigenvalue of the pencil `(-Kp, Kf)`, so the smallest positive `lambda`
/// is `1 / nu_max` (one eigenproblem, the buckling eigenproblem of structural stability).
/// Otherwise: bisection on `f(lambda) = lowest eigenvalue of (Kf + lambda Kp, M)`, which is
/// concave in `lambda`, so its positive root is unique.
fn critical_factor_full(
    integrals: &ModalIntegrals,
    geometric: &Mat<f64>,
    solver: &mut FrequencySolver,
    omega2: &mut [f64],
) -> Result<Option<f64>, BeamError> {
    let r = integrals.r();
    if let Ok(mut buckling) =
        FrequencySolver::from_mass(integrals.stiffness.as_ref(), Coupling::Full)
    {
        let compression = Mat::from_fn(r, r, |i, k| -geometric[(i, k)]);
        let mut nu = vec![0.0; r];
        buckling.eigenvalues(compression.as_ref(), &mut nu)?;
        let nu_max = nu[r - 1];
        return Ok((nu_max * MAX_LOAD_FACTOR > 1.0).then(|| 1.0 / nu_max));
    }
    let mut k = Mat::zeros(r, r);
    let mut lowest = |factor: f64| -> Result<f64, BeamError> {
        for c in 0..r {
            for i in 0..r {
                k[(i, c)] = integrals.stiffness[(i, c)] + factor * geometric[(i, c)];
            }
        }
        solver.eigenvalues(k.as_ref(), omega2)?;
        Ok(omega2[0])
    };
    let mut lo = 0.0;
    let mut hi = 1.0;
    while lowest(hi)? >= 0.0 {
        lo = hi;
        hi *= 2.0;
        if hi > MAX_LOAD_FACTOR {
            return Ok(None);
        }
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if hi - lo <= 1e-15 * hi || mid <= lo || mid >= hi {
            break;
        }
        if lowest(mid)? < 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Ok(Some(0.5 * (lo + hi)))
}
