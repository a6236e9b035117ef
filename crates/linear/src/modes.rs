//! Whole-machine modes from a linearisation: the eigenvalues `lambda` of `A`, each pair of
//! complex conjugates one mode, with `frequency_hz = |lambda| / 2 pi` (the undamped natural
//! frequency) and `damping_ratio = -Re(lambda) / |lambda|`, as MATLAB's `damp` reports them,
//! and the mode's shape at the linearisation's outputs.

use faer::Mat;
use faer::linalg::solvers::Eigen;

use crate::frf::Complex;
use crate::{LinearError, Linearization};

/// Frequencies below this (Hz) are rigid-body (zero) modes and are left out.
const ZERO_FREQUENCY_HZ: f64 = 1e-3;

/// One mode of a linear model.
#[derive(Debug, Clone, PartialEq)]
pub struct Mode {
    /// The eigenvalue `lambda` (1/s): of `A` in continuous time; in discrete time the
    /// equivalent continuous one, `ln(z) / T` (principal branch: `|Im| <= pi / T`).
    pub eigenvalue: Complex,
    /// The eigenvalue `z` of a discrete-time `A` (`None` in continuous time).
    pub z: Option<Complex>,
    /// `|lambda| / 2 pi` (Hz).
    pub frequency_hz: f64,
    /// `-Re(lambda) / |lambda|`.
    pub damping_ratio: f64,
    /// The eigenvector seen at the linearisation's outputs (`C v`), scaled so that its
    /// largest entry is 1 (real).
    pub shape: Vec<Complex>,
    /// The eigenvector's coordinates that the relaxation of the chords added (the
    /// platform's deviation, then each link's axial modes), scaled as `shape`; empty
    /// without them.
    pub added: Vec<Complex>,
}

/// `ln(z) / dt`, principal branch.
fn continuous_equivalent(z: Complex, dt: f64) -> Complex {
    Complex::new(z.norm().ln() / dt, z.arg() / dt)
}

/// The modes of `lin` sorted by frequency, rigid-body (zero-frequency) modes left out; a
/// real eigenvalue (an overdamped motion, a controller's integral) is a mode of damping
/// ratio 1. A discrete-time model's eigenvalues `z` give `lambda = ln(z) / T`; a mode at
/// `z = 0` (settled in one sample) has no continuous equivalent and is left out.
///
/// # Errors
/// The eigenvalue problem did not converge.
pub fn modes(lin: &Linearization) -> Result<Vec<Mode>, LinearError> {
    let n = lin.a.nrows();
    let (balanced, scaling) = crate::balance::balance(&lin.a);
    let eigen = Eigen::new_from_real(balanced.as_ref())
        .map_err(|e| LinearError::Numerics(format!("eigenvalues of A ({n} x {n}): {e:?}")))?;
    let (values, vectors) = (eigen.S(), eigen.U());
    let discrete = lin.dt > 0.0;
    let scale = (0..n)
        .map(|k| {
            let v = values[k];
            v.re.hypot(v.im)
        })
        .fold(0.0, f64::max);
    let mut modes = Vec::new();
    for k in 0..n {
        let raw = Complex::new(values[k].re, values[k].im);
        if raw.im < -1e-9 * scale.max(1.0) {
            continue;
        }
        let lambda = if discrete {
            if raw.norm() < f64::MIN_POSITIVE.sqrt() {
                continue;
            }
            continuous_equivalent(raw, lin.dt)
        } else {
            raw
        };
        let modulus = lambda.norm();
        if !modulus.is_finite() || modulus / std::f64::consts::TAU < ZERO_FREQUENCY_HZ {
            continue;
        }
        let column: Vec<Complex> = (0..n)
            .map(|j| Complex::new(vectors[(j, k)].re, vectors[(j, k)].im).scale(scaling[j]))
            .collect();
        let (shape, added) = normalised(
            &lin.c,
            &column,
            lin.coordinates - lin.added..lin.coordinates,
        );
        modes.push(Mode {
            eigenvalue: lambda,
            z: discrete.then_some(raw),
            frequency_hz: modulus / std::f64::consts::TAU,
            damping_ratio: -lambda.re / modulus,
            shape,
            added,
        });
    }
    modes.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
    Ok(modes)
}

/// `C v` and the entries of `v` in `added`, both divided by the entry of `C v` of largest
/// modulus.
fn normalised(
    c: &Mat<f64>,
    v: &[Complex],
    added: std::ops::Range<usize>,
) -> (Vec<Complex>, Vec<Complex>) {
    let seen: Vec<Complex> = (0..c.nrows())
        .map(|i| (0..c.ncols()).fold(Complex::default(), |sum, j| sum + v[j].scale(c[(i, j)])))
        .collect();
    let extra: Vec<Complex> = v[added].to_vec();
    let largest = seen
        .iter()
        .copied()
        .max_by(|a, b| a.norm().total_cmp(&b.norm()))
        .unwrap_or_default();
    if largest.norm() <= 0.0 {
        return (seen, extra);
    }
    (
        seen.iter().map(|s| *s / largest).collect(),
        extra.iter().map(|s| *s / largest).collect(),
    )
}
