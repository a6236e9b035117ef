//! Frequency responses `H(i omega) = C (i omega I - A)^-1 B + D` without eigenvectors, by
//! Laub's Hessenberg method (A. J. Laub, "Efficient multivariable frequency response
//! computations", *IEEE Trans. Automatic Control* 26(2), 1981, pp. 407-408):
//!
//! 1. once, after balancing (`D^-1 A D` with powers of two, Parlett & Reinsch 1969, as for
//!    the eigenvalues), the orthogonal reduction `A = Q H Q^T` to upper Hessenberg form by Householder
//!    reflections (Golub & Van Loan, *Matrix Computations*, 4th ed., 2013, algorithm
//!    7.4.2), with `Q^T B` and `C Q` formed alongside;
//! 2. at each frequency, `(i omega I - H) X = Q^T B` by Gaussian elimination with partial
//!    pivoting between neighbouring rows (the only rows with an entry below the diagonal),
//!    `O(n^2)` per frequency, then `H = (C Q) X + D`.
//!
//! Unlike the modal form of [`crate::frequency_response`], nothing here depends on the
//! eigenvectors, so repeated eigenvalues (the three identical links of a machine with its
//! sliders locked vibrate at the same frequencies) cost no accuracy: the error is that of a
//! backward-stable solve with the matrix `i omega I - A`.

use faer::c64;

use crate::frf::Complex;
use crate::{LinearError, Linearization};

/// A dense row-major matrix of `f64`.
struct Dense {
    rows: usize,
    cols: usize,
    data: Vec<f64>,
}

impl Dense {
    fn of(m: &faer::Mat<f64>) -> Self {
        let (rows, cols) = (m.nrows(), m.ncols());
        let mut data = Vec::with_capacity(rows * cols);
        for i in 0..rows {
            for j in 0..cols {
                data.push(m[(i, j)]);
            }
        }
        Self { rows, cols, data }
    }
    fn at(&self, i: usize, j: usize) -> f64 {
        self.data[i * self.cols + j]
    }
    fn at_mut(&mut self, i: usize, j: usize) -> &mut f64 {
        &mut self.data[i * self.cols + j]
    }
}

/// `A = Q H Q^T`: `H` upper Hessenberg, and `Q^T B`, `C Q`.
struct Reduced {
    h: Dense,
    qtb: Dense,
    cq: Dense,
}

/// Applies the reflection `I - beta v v^T` (`v` zero before `from`) from the left to the
/// columns `cols` of `m`.
fn reflect_left(m: &mut Dense, v: &[f64], from: usize, beta: f64, cols: std::ops::Range<usize>) {
    for j in cols {
        let s = beta
            * v[from..]
                .iter()
                .enumerate()
                .map(|(r, vi)| vi * m.at(from + r, j))
                .sum::<f64>();
        for (r, vi) in v[from..].iter().enumerate() {
            *m.at_mut(from + r, j) -= s * vi;
        }
    }
}

/// Applies the reflection `I - beta v v^T` (`v` zero before `from`) from the right to
/// every row of `m`.
fn reflect_right(m: &mut Dense, v: &[f64], from: usize, beta: f64) {
    for i in 0..m.rows {
        let s = beta
            * v[from..]
                .iter()
                .enumerate()
                .map(|(c, vj)| m.at(i, from + c) * vj)
                .sum::<f64>();
        for (c, vj) in v[from..].iter().enumerate() {
            *m.at_mut(i, from + c) -= s * vj;
        }
    }
}

/// Householder reduction of `a` to upper Hessenberg form, applying the same reflections to
/// `b` from the left and to `c` from the right.
fn reduce(a: &faer::Mat<f64>, b: &faer::Mat<f64>, c: &faer::Mat<f64>) -> Reduced {
    let n = a.nrows();
    let (mut h, mut qtb, mut cq) = (Dense::of(a), Dense::of(b), Dense::of(c));
    let mut v = vec![0.0; n];
    for k in 0..n.saturating_sub(2) {
        v.fill(0.0);
        for (i, vi) in v.iter_mut().enumerate().skip(k + 1) {
            *vi = h.at(i, k);
        }
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm == 0.0 {
            continue;
        }
        let alpha = if v[k + 1] >= 0.0 { -norm } else { norm };
        v[k + 1] -= alpha;
        let vv: f64 = v.iter().map(|x| x * x).sum();
        if vv == 0.0 {
            continue;
        }
        let beta = 2.0 / vv;
        reflect_left(&mut h, &v, k + 1, beta, k..n);
        let m = qtb.cols;
        reflect_left(&mut qtb, &v, k + 1, beta, 0..m);
        reflect_right(&mut h, &v, k + 1, beta);
        reflect_right(&mut cq, &v, k + 1, beta);
        *h.at_mut(k + 1, k) = alpha;
        for i in k + 2..n {
            *h.at_mut(i, k) = 0.0;
        }
    }
    Reduced { h, qtb, cq }
}

/// Solves `(s I - H) X = R` in place (`R`: `n x m`, row-major), `H` upper Hessenberg, with
/// the work matrix `w` (`n x n`). Returns false when a pivot is zero (`s` is an eigenvalue).
fn solve_shifted(h: &Dense, s: c64, w: &mut [c64], r: &mut [c64], m: usize) -> bool {
    let n = h.rows;
    for i in 0..n {
        for j in 0..n {
            let d = if i == j { s } else { c64::new(0.0, 0.0) };
            w[i * n + j] = d - c64::new(h.at(i, j), 0.0);
        }
    }
    for k in 0..n.saturating_sub(1) {
        if w[(k + 1) * n + k].norm() > w[k * n + k].norm() {
            for j in k..n {
                w.swap(k * n + j, (k + 1) * n + j);
            }
            for j in 0..m {
                r.swap(k * m + j, (k + 1) * m + j);
            }
        }
        let pivot = w[k * n + k];
        if pivot.norm() == 0.0 {
            return false;
        }
        let l = w[(k + 1) * n + k] / pivot;
        if l.norm() == 0.0 {
            continue;
        }
        for j in k + 1..n {
            let above = w[k * n + j];
            w[(k + 1) * n + j] -= l * above;
        }
        for j in 0..m {
            let above = r[k * m + j];
            r[(k + 1) * m + j] -= l * above;
        }
    }
    for k in (0..n).rev() {
        let pivot = w[k * n + k];
        if pivot.norm() == 0.0 {
            return false;
        }
        for j in 0..m {
            let mut sum = r[k * m + j];
            for l in k + 1..n {
                sum -= w[k * n + l] * r[l * m + j];
            }
            r[k * m + j] = sum / pivot;
        }
    }
    true
}

/// Where the resolvent is evaluated at the frequency `f` (Hz): `s = i 2 pi f` in
/// continuous time, `z = exp(i 2 pi f T)` in discrete time at the period `dt = T`.
pub(crate) fn evaluation_point(dt: f64, f: f64) -> c64 {
    let omega = std::f64::consts::TAU * f;
    if dt > 0.0 {
        let (sin, cos) = (omega * dt).sin_cos();
        c64::new(cos, sin)
    } else {
        c64::new(0.0, omega)
    }
}

/// The response of every output to every input at each frequency of `frequencies_hz`
/// (`result[f][output][input]`), by Laub's Hessenberg method (module documentation): exact
/// to round-off whatever the eigenvalues' multiplicity. A discrete-time model (`dt > 0`) is
/// evaluated at `z = exp(i omega T)`, up to the Nyquist frequency `1 / 2T`.
///
/// # Errors
/// A frequency that is not finite (or above the Nyquist frequency of a discrete model), or
/// one at which `s I - A` is singular (an undamped mode exactly there: the response is
/// infinite), or a response that is not finite.
pub fn frequency_response_direct(
    lin: &Linearization,
    frequencies_hz: &[f64],
) -> Result<Vec<Vec<Vec<Complex>>>, LinearError> {
    frequency_response_with_progress(lin, frequencies_hz, &mut |_| {})
}

/// [`frequency_response_direct`], calling `progress` with the share done (0 to 1) after
/// every frequency.
///
/// # Errors
/// As [`frequency_response_direct`].
pub fn frequency_response_with_progress(
    lin: &Linearization,
    frequencies_hz: &[f64],
    progress: &mut dyn FnMut(f64),
) -> Result<Vec<Vec<Vec<Complex>>>, LinearError> {
    if let Some(f) = frequencies_hz.iter().find(|f| !f.is_finite()) {
        return Err(LinearError::Channel(format!(
            "frequency {f} Hz: frequencies must be finite"
        )));
    }
    if lin.dt > 0.0 {
        let nyquist = 0.5 / lin.dt;
        if let Some(f) = frequencies_hz
            .iter()
            .find(|f| f.abs() > nyquist * (1.0 + 1e-12))
        {
            return Err(LinearError::Channel(format!(
                "frequency {f} Hz is above the Nyquist frequency {nyquist} Hz of the discrete-time                  model (the law's period {} s): a sampled loop's response repeats beyond it",
                lin.dt
            )));
        }
    }
    progress(0.0);
    let n = lin.a.nrows();
    let (p, m) = (lin.c.nrows(), lin.b.ncols());
    // Balanced first (`D^-1 A D`, `D^-1 B`, `C D`, powers of two: exact), as for the
    // eigenvalues: positions and rates, stiff and slow modes differ by orders of magnitude.
    let (balanced, scaling) = crate::balance::balance(&lin.a);
    let b = faer::Mat::<f64>::from_fn(n, lin.b.ncols(), |i, j| lin.b[(i, j)] / scaling[i]);
    let c = faer::Mat::<f64>::from_fn(lin.c.nrows(), n, |i, j| lin.c[(i, j)] * scaling[j]);
    let reduced = reduce(&balanced, &b, &c);
    let mut w = vec![c64::new(0.0, 0.0); n * n];
    let mut x = vec![c64::new(0.0, 0.0); n * m];
    let mut out = Vec::with_capacity(frequencies_hz.len());
    let count = frequencies_hz.len().max(1) as f64;
    for (done, &f) in frequencies_hz.iter().enumerate() {
        progress(done as f64 / count);
        let s = evaluation_point(lin.dt, f);
        for (k, v) in reduced.qtb.data.iter().enumerate() {
            x[k] = c64::new(*v, 0.0);
        }
        let infinite = || {
            LinearError::Numerics(format!(
                "the response is infinite at f = {f} Hz: an undamped mode of the linear model \
                 is there (move the frequency, or give the modes damping)"
            ))
        };
        if !solve_shifted(&reduced.h, s, &mut w, &mut x, m) {
            return Err(infinite());
        }
        let mut rows = Vec::with_capacity(p);
        for o in 0..p {
            let mut row = Vec::with_capacity(m);
            for i in 0..m {
                let mut sum = c64::new(lin.d[(o, i)], 0.0);
                for k in 0..n {
                    sum += x[k * m + i] * reduced.cq.at(o, k);
                }
                if !(sum.re.is_finite() && sum.im.is_finite()) {
                    return Err(infinite());
                }
                row.push(Complex::new(sum.re, sum.im));
            }
            rows.push(row);
        }
        out.push(rows);
    }
    progress(1.0);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::Mat;

    /// A 3 x 3 system with a repeated eigenvalue pair and its resolvent in closed form:
    /// two uncoupled oscillators `x'' + 2 zeta w x' + w^2 x = u` of the same `w`, plus a
    /// first-order lag, scrambled by an orthogonal similarity.
    #[test]
    fn matches_the_closed_form_of_repeated_oscillators() {
        let (w, zeta, tau) = (2.0 * std::f64::consts::PI * 10.0, 0.0, 0.05);
        // States: x1, v1, x2, v2, z. Inputs: u on both oscillators, u on the lag.
        let mut a = Mat::<f64>::zeros(5, 5);
        for o in 0..2 {
            a[(2 * o, 2 * o + 1)] = 1.0;
            a[(2 * o + 1, 2 * o)] = -w * w;
            a[(2 * o + 1, 2 * o + 1)] = -2.0 * zeta * w;
        }
        a[(4, 4)] = -1.0 / tau;
        let mut b = Mat::<f64>::zeros(5, 1);
        b[(1, 0)] = 1.0;
        b[(3, 0)] = 2.0;
        b[(4, 0)] = 1.0 / tau;
        let mut c = Mat::<f64>::zeros(2, 5);
        c[(0, 0)] = 1.0;
        c[(0, 2)] = 1.0;
        c[(1, 4)] = 1.0;
        // An orthogonal change of coordinates (a Householder reflection) hides the structure.
        let u = [0.3, -0.5, 0.2, 0.7, 0.1];
        let uu: f64 = u.iter().map(|x| x * x).sum();
        let q = Mat::<f64>::from_fn(5, 5, |i, j| {
            f64::from(u8::from(i == j)) - 2.0 * u[i] * u[j] / uu
        });
        let lin =
            Linearization::from_matrices(&q * &a * &q, &q * &b, &c * &q, Mat::zeros(2, 1), 0.0);
        for f in [0.0, 3.0, 9.9, 10.1, 250.0] {
            let h = frequency_response_direct(&lin, &[f]).unwrap();
            let s = c64::new(0.0, std::f64::consts::TAU * f);
            let oscillator = c64::new(3.0, 0.0) / (s * s + c64::new(w * w, 0.0));
            let lag = c64::new(1.0, 0.0) / (s * tau + c64::new(1.0, 0.0));
            for (got, want) in [(h[0][0][0], oscillator), (h[0][1][0], lag)] {
                let error = c64::new(got.re, got.im) - want;
                assert!(
                    error.norm() < 1e-10 * want.norm(),
                    "{f} Hz: {got:?} {want:?}"
                );
            }
        }
        assert!(frequency_response_direct(&lin, &[f64::NAN]).is_err());
    }
}
