//! Frequency responses `H(i omega) = C (i omega I - A)^-1 B + D` (in discrete time at
//! `z = exp(i omega T)`) through the eigenvalues of `A`: with `A = V Lambda V^-1`, `H = (C V) (i omega - Lambda)^-1 (V^-1 B) + D`, formed once
//! and evaluated at each frequency in `O(n)` per input-output pair.

use faer::linalg::solvers::{DenseSolveCore, Eigen};
use faer::{Mat, c64};

use crate::{LinearError, Linearization};

/// A complex number `re + i im` (the eigenvalues, shapes and responses).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Complex {
    /// Real part.
    pub re: f64,
    /// Imaginary part.
    pub im: f64,
}

impl Complex {
    /// `re + i im`.
    pub const fn new(re: f64, im: f64) -> Self {
        Self { re, im }
    }
    /// The modulus.
    pub fn norm(self) -> f64 {
        self.re.hypot(self.im)
    }
    /// The argument (rad).
    pub fn arg(self) -> f64 {
        self.im.atan2(self.re)
    }
    /// `self * s` for a real `s`.
    pub fn scale(self, s: f64) -> Self {
        Self::new(self.re * s, self.im * s)
    }
}

impl std::ops::Div for Complex {
    type Output = Self;
    fn div(self, other: Self) -> Self {
        let d = other.re * other.re + other.im * other.im;
        Self::new(
            (self.re * other.re + self.im * other.im) / d,
            (self.im * other.re - self.re * other.im) / d,
        )
    }
}

impl std::ops::Add for Complex {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self::new(self.re + o.re, self.im + o.im)
    }
}

impl std::ops::Mul for Complex {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        Self::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
}

/// The response of every output to every input at each frequency of `frequencies_hz`:
/// `result[f][output][input]`.
///
/// # Errors
/// The eigenvalue problem failed, or `A` is too close to defective for its eigenvectors to
/// be inverted.
pub fn frequency_response(
    lin: &Linearization,
    frequencies_hz: &[f64],
) -> Result<Vec<Vec<Vec<Complex>>>, LinearError> {
    let n = lin.a.nrows();
    let (balanced, scaling) = crate::balance::balance(&lin.a);
    let eigen = Eigen::new_from_real(balanced.as_ref())
        .map_err(|e| LinearError::Numerics(format!("eigenvalues of A ({n} x {n}): {e:?}")))?;
    let (values, vectors) = (eigen.S(), eigen.U());
    // The eigenvectors of A itself: D times those of the balanced matrix.
    let v = Mat::<c64>::from_fn(n, n, |i, j| vectors[(i, j)] * scaling[i]);
    let lu = v.partial_piv_lu();
    let inverse = lu.inverse();
    let to_complex =
        |m: &Mat<f64>| Mat::<c64>::from_fn(m.nrows(), m.ncols(), |i, j| c64::new(m[(i, j)], 0.0));
    let cv = &to_complex(&lin.c) * &v;
    let vb = &inverse * &to_complex(&lin.b);
    // The eigenvectors must reconstruct A: a defective A would make V^-1 meaningless.
    let reconstructed =
        &v * Mat::<c64>::from_fn(n, n, |i, j| {
            if i == j {
                values[i]
            } else {
                c64::new(0.0, 0.0)
            }
        }) * &inverse;
    let error = (0..n)
        .flat_map(|i| (0..n).map(move |j| (i, j)))
        .map(|(i, j)| (reconstructed[(i, j)] - c64::new(lin.a[(i, j)], 0.0)).norm())
        .fold(0.0, f64::max);
    let scale = (0..n)
        .flat_map(|i| (0..n).map(move |j| (i, j)))
        .map(|(i, j)| lin.a[(i, j)].abs())
        .fold(0.0, f64::max);
    if error.is_nan() || error > 1e-6 * scale.max(f64::MIN_POSITIVE) {
        return Err(LinearError::Numerics(format!(
            "A is too close to defective for a modal frequency response (reconstruction error {error:.1e} of {scale:.1e})"
        )));
    }
    let (p, m) = (lin.c.nrows(), lin.b.ncols());
    Ok(frequencies_hz
        .iter()
        .map(|f| {
            let s = crate::direct::evaluation_point(lin.dt, *f);
            let weights: Vec<c64> = (0..n)
                .map(|k| c64::new(1.0, 0.0) / (s - values[k]))
                .collect();
            (0..p)
                .map(|o| {
                    (0..m)
                        .map(|i| {
                            let h = (0..n).fold(c64::new(lin.d[(o, i)], 0.0), |sum, k| {
                                sum + cv[(o, k)] * weights[k] * vb[(k, i)]
                            });
                            Complex::new(h.re, h.im)
                        })
                        .collect()
                })
                .collect()
        })
        .collect())
}
