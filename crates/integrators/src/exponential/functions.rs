//! Closed forms of `exp` and the `phi` functions of a real 2 x 2 matrix.
//!
//! Any real 2 x 2 matrix is `Z = m I + Y` with `m = tr(Z) / 2` and `Y` traceless, and a
//! traceless 2 x 2 matrix squares to a multiple of the identity: `Y^2 = -theta2 I` with
//! `theta2 = det(Y)` (Cayley-Hamilton). Every power series in `Z` is therefore `P I + Q Y` with
//! two real scalars. For `phi_k(Z) = sum_n Z^n / (n + k)!` (Hochbruck & Ostermann,
//! "Exponential integrators", *Acta Numerica* 19 (2010) 209-286, eq. 2.10):
//!
//! * small `Z` (`|m| + sqrt|theta2| < 2`): the series for `phi_3` by Horner's rule, then the
//!   exact recurrence `phi_(k-1)(Z) = I / (k-1)! + Z phi_k(Z)` downwards (no cancellation);
//! * otherwise `exp(Z) = e^m (cos(theta) I + sin(theta)/theta Y)` (cosh/sinh when
//!   `theta2 < 0`, a buckling mode growing exponentially; a series for `sin(theta)/theta`
//!   near `theta2 = 0`) and the recurrence `phi_k(Z) = Z^-1 (phi_(k-1)(Z) - I / (k-1)!)`
//!   upwards, with `Z^-1 = (m I - Y) / (m^2 + theta2)`;
//! * when that inverse is ill-conditioned (`theta2 < 0` with `|m|` close to `sqrt(-theta2)`,
//!   an eigenvalue near zero): divided differences on the two real eigenvalues
//!   `m +- sqrt(-theta2)`, which are well separated there.

/// `phi_k(Z) = P I + Q Y` for `k = 0..=3` (`phi_0 = exp`), as `(P, Q)` pairs.
pub(crate) type PhiPairs = [(f64, f64); 4];

/// Terms of the Taylor series of `phi_3` on the small branch: `2^N / (N + 3)!` is below
/// `3e-19` for `N = 22`.
const SERIES_TERMS: usize = 22;
/// Size of `Z` (`|m| + sqrt|theta2|`) below which the series is used.
const SERIES_RADIUS: f64 = 2.0;

/// Terms of the series of `phi_3` for a matrix of size `size < 2`, such that
/// `size^N / (N + 3)!` is below `1e-17` (`0.25^11 / 14!`, `0.5^13 / 16!`, `1 / 19!`, `2^22 / 25!`).
#[inline]
fn series_terms(size: f64) -> usize {
    if size < 0.25 {
        11
    } else if size < 0.5 {
        13
    } else if size < 1.0 {
        16
    } else {
        SERIES_TERMS
    }
}

/// `(u I + v Y) Z` with `Z = m I + Y` and `Y^2 = -theta2 I`.
#[inline]
fn times_z(u: f64, v: f64, m: f64, theta2: f64) -> (f64, f64) {
    (u * m - v * theta2, u + v * m)
}

/// `1 / n!` for `n = 0..=40`, built at compile time.
const INV_FACTORIAL: [f64; 41] = {
    let mut t = [1.0; 41];
    let mut n = 1;
    while n < 41 {
        t[n] = t[n - 1] / n as f64;
        n += 1;
    }
    t
};

/// `1 / n!` for `n <= 40`.
#[inline]
fn inv_factorial(n: usize) -> f64 {
    INV_FACTORIAL[n]
}

/// `(cos theta, sin(theta) / theta)` for `theta^2 = theta2` of either sign (cosh and
/// sinh(kappa)/kappa when `theta2 = -kappa^2 < 0`), accurate near `theta2 = 0`.
#[inline]
pub(crate) fn cos_sinc(theta2: f64) -> (f64, f64) {
    if theta2.abs() < 1e-3 {
        // Taylor: cos = 1 - x/2 + x^2/24 - x^3/720, sinc = 1 - x/6 + x^2/120 - x^3/5040.
        let x = theta2;
        (
            1.0 - x / 2.0 * (1.0 - x / 12.0 * (1.0 - x / 30.0)),
            1.0 - x / 6.0 * (1.0 - x / 20.0 * (1.0 - x / 42.0)),
        )
    } else if theta2 > 0.0 {
        let th = theta2.sqrt();
        (th.cos(), th.sin() / th)
    } else {
        let ka = (-theta2).sqrt();
        (ka.cosh(), ka.sinh() / ka)
    }
}

/// Scalar `phi_k(x)`, `k = 0..=3`, for real `x`.
fn scalar_phi(x: f64) -> [f64; 4] {
    let mut out = [0.0; 4];
    if x.abs() < SERIES_RADIUS {
        let mut acc = inv_factorial(SERIES_TERMS + 3);
        for n in (0..SERIES_TERMS).rev() {
            acc = acc * x + inv_factorial(n + 3);
        }
        out[3] = acc;
        out[2] = 0.5 + x * out[3];
        out[1] = 1.0 + x * out[2];
        out[0] = 1.0 + x * out[1];
    } else {
        out[0] = x.exp();
        out[1] = (out[0] - 1.0) / x;
        out[2] = (out[1] - 1.0) / x;
        out[3] = (out[2] - 0.5) / x;
    }
    out
}

/// `phi_k(m I + Y)` for `k = 0..=3` where `Y` is traceless with `Y^2 = -theta2 I`.
///
/// Non-finite results (overflow of a strongly growing mode) are returned as they are; the
/// caller checks.
pub(crate) fn phi_pairs(m: f64, theta2: f64) -> PhiPairs {
    let size = m.abs() + theta2.abs().sqrt();
    let mut out = [(0.0, 0.0); 4];
    if size < SERIES_RADIUS {
        let terms = series_terms(size);
        let (mut u, mut v) = (inv_factorial(terms + 3), 0.0);
        for n in (0..terms).rev() {
            let (a, b) = times_z(u, v, m, theta2);
            u = a + inv_factorial(n + 3);
            v = b;
        }
        out[3] = (u, v);
        for k in (0..3).rev() {
            let (a, b) = times_z(out[k + 1].0, out[k + 1].1, m, theta2);
            out[k] = (a + inv_factorial(k), b);
        }
        return out;
    }
    let det = m * m + theta2;
    if theta2 < 0.0 && det.abs() < 0.25 * (m * m - theta2) {
        // Eigenvalues m +- kappa, well separated (kappa > |m| / 2 > 0.3 here).
        let kappa = (-theta2).sqrt();
        let fp = scalar_phi(m + kappa);
        let fm = scalar_phi(m - kappa);
        for k in 0..4 {
            out[k] = (0.5 * (fp[k] + fm[k]), (fp[k] - fm[k]) / (2.0 * kappa));
        }
        return out;
    }
    let (c, s) = cos_sinc(theta2);
    let e = m.exp();
    out[0] = (e * c, e * s);
    // Z^-1 (P I + Q Y) = ((m P + theta2 Q) I + (m Q - P) Y) / det, from (m I - Y)(P I + Q Y).
    for k in 1..4 {
        let (p, q) = out[k - 1];
        let p = p - inv_factorial(k - 1);
        out[k] = ((m * p + theta2 * q) / det, (m * q - p) / det);
    }
    out
}

/// A real 2 x 2 matrix `[[a, b], [c, d]]` split as `m I + Y`: returns `(m, p, q, r, theta2)`
/// with `Y = [[p, q], [r, -p]]` and `Y^2 = -theta2 I`.
#[inline]
pub(crate) fn split(a: f64, b: f64, c: f64, d: f64) -> (f64, f64, f64, f64, f64) {
    let m = 0.5 * (a + d);
    let p = 0.5 * (a - d);
    (m, p, b, c, -(p * p + b * c))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `exp` and `phi_k` of a 2 x 2 matrix by a long Taylor series with scaling and
    /// squaring-free summation (only for moderate norms), as an independent check.
    fn series_phi(z: [[f64; 2]; 2], k: usize) -> [[f64; 2]; 2] {
        let mul = |a: [[f64; 2]; 2], b: [[f64; 2]; 2]| {
            let mut c = [[0.0; 2]; 2];
            for i in 0..2 {
                for j in 0..2 {
                    c[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j];
                }
            }
            c
        };
        let mut term = [[1.0, 0.0], [0.0, 1.0]];
        let mut sum = [[0.0; 2]; 2];
        for n in 0..200 {
            let w = if n + k > 40 {
                0.0
            } else {
                inv_factorial(n + k)
            };
            for i in 0..2 {
                for j in 0..2 {
                    sum[i][j] += w * term[i][j];
                }
            }
            term = mul(term, z);
        }
        sum
    }

    /// Every branch (series, trigonometric, hyperbolic, near-singular divided differences)
    /// against the plain power series of the matrix.
    #[test]
    fn phi_pairs_match_the_power_series_on_every_branch() {
        let cases = [
            [[0.1, 0.3], [-0.2, -0.05]],  // small: series
            [[0.0, 1.0], [-9.0, 0.0]],    // oscillation, theta = 3
            [[-0.2, 2.0], [-12.0, -0.6]], // damped oscillation
            [[0.0, 1.0], [6.0, 0.0]],     // buckling: theta2 = -6
            [[-3.0, 1.0], [0.0, 0.0]],    // eigenvalues 0 and -3: divided differences
            [[0.5, 1.0], [2.5, 0.4]],     // growing, theta2 < 0
            [[0.0, 1.0], [-1e-12, 0.0]],  // theta2 tiny
            [[-4.0, 0.0], [0.0, -4.0]],   // pure shift
        ];
        for z in cases {
            let (m, p, q, r, t2) = split(z[0][0], z[0][1], z[1][0], z[1][1]);
            let pairs = phi_pairs(m, t2);
            for (k, &(pp, qq)) in pairs.iter().enumerate() {
                let got = [[pp + qq * p, qq * q], [qq * r, pp - qq * p]];
                let want = series_phi(z, k);
                for i in 0..2 {
                    for j in 0..2 {
                        let scale = want[i][j].abs().max(1.0);
                        assert!(
                            (got[i][j] - want[i][j]).abs() < 1e-12 * scale,
                            "z = {z:?}, phi_{k}[{i}][{j}]: {} vs {}",
                            got[i][j],
                            want[i][j]
                        );
                    }
                }
            }
        }
    }
}
