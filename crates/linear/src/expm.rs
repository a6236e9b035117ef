//! The matrix exponential by scaling and squaring with Padé approximants, N. J. Higham,
//! "The scaling and squaring method for the matrix exponential revisited", *SIAM J. Matrix
//! Anal. Appl.* 26(4), 2005, pp. 1179-1193, algorithm 2.3: the degree `m` of the diagonal
//! Padé approximant `r_m(A) = q_m(A)^-1 p_m(A)` is the lowest of 3, 5, 7, 9, 13 whose
//! threshold `theta_m` bounds `||A||_1` (backward error below the unit roundoff); above
//! `theta_13` the matrix is scaled by `2^-s` and the result squared `s` times. The matrix is
//! balanced first by a diagonal similarity of powers of two (exact in floating point:
//! `exp(D^-1 A D) = D^-1 exp(A) D`), as the paper recommends for badly scaled matrices.
//!
//! Used for the zero-order-hold discretisation of a plant (`exp([[A B], [0 0]] T)` holds
//! `exp(A T)` and `int_0^T exp(A s) ds B`: C. F. Van Loan, "Computing integrals involving
//! the matrix exponential", *IEEE Trans. Automatic Control* 23(3), 1978, pp. 395-404).

use faer::Mat;
use faer::linalg::solvers::Solve;

use crate::LinearError;

/// `theta_m` of Higham (2005), table 2.3, for `m = 3, 5, 7, 9, 13`.
const THETA: [(usize, f64); 5] = [
    (3, 1.495_585_217_958_292e-2),
    (5, 2.539_398_330_063_23e-1),
    (7, 9.504_178_996_162_932e-1),
    (9, 2.097_847_961_257_068e0),
    (13, 5.371_920_351_148_152e0),
];

/// The coefficients `b_0 .. b_m` of the diagonal Padé approximant of degree `m` of `exp`:
/// `p_m(x) = sum b_j x^j`, `q_m(x) = p_m(-x)`.
fn pade_coefficients(m: usize) -> &'static [f64] {
    match m {
        3 => &[120.0, 60.0, 12.0, 1.0],
        5 => &[30240.0, 15120.0, 3360.0, 420.0, 30.0, 1.0],
        7 => &[
            17_297_280.0,
            8_648_640.0,
            1_995_840.0,
            277_200.0,
            25_200.0,
            1512.0,
            56.0,
            1.0,
        ],
        9 => &[
            17_643_225_600.0,
            8_821_612_800.0,
            2_075_673_600.0,
            302_702_400.0,
            30_270_240.0,
            2_162_160.0,
            110_880.0,
            3960.0,
            90.0,
            1.0,
        ],
        _ => &[
            64_764_752_532_480_000.0,
            32_382_376_266_240_000.0,
            7_771_770_303_897_600.0,
            1_187_353_796_428_800.0,
            129_060_195_264_000.0,
            10_559_470_521_600.0,
            670_442_572_800.0,
            33_522_128_640.0,
            1_323_241_920.0,
            40_840_800.0,
            960_960.0,
            16_380.0,
            182.0,
            1.0,
        ],
    }
}

/// `||A||_1`, the largest column sum.
fn norm_1(a: &Mat<f64>) -> f64 {
    (0..a.ncols())
        .map(|j| a.col_as_slice(j).iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max)
}

/// `sum_k c_k P_k` for matrices `P_k` (all `n x n`), plus `c_id I`.
fn combination(n: usize, c_id: f64, terms: &[(f64, &Mat<f64>)]) -> Mat<f64> {
    Mat::from_fn(n, n, |i, j| {
        let mut v = if i == j { c_id } else { 0.0 };
        for (c, p) in terms {
            v += c * p[(i, j)];
        }
        v
    })
}

/// `exp(a)`.
///
/// # Errors
/// A non-finite matrix, or a Padé denominator that cannot be solved (which the thresholds
/// rule out for finite input).
pub fn expm(a: &Mat<f64>) -> Result<Mat<f64>, LinearError> {
    let n = a.nrows();
    if (0..n).any(|j| a.col_as_slice(j).iter().any(|v| !v.is_finite())) {
        return Err(LinearError::Numerics(
            "the matrix exponential of a matrix with a non-finite entry".into(),
        ));
    }
    let (balanced, scale) = crate::balance::balance(a);
    let e = expm_unbalanced(&balanced)?;
    // exp(A) = D exp(D^-1 A D) D^-1.
    Ok(Mat::from_fn(n, n, |i, j| e[(i, j)] * scale[i] / scale[j]))
}

fn expm_unbalanced(a: &Mat<f64>) -> Result<Mat<f64>, LinearError> {
    let n = a.nrows();
    let norm = norm_1(a);
    let identity = Mat::<f64>::identity(n, n);
    let a2 = a * a;
    for &(m, theta) in &THETA[..4] {
        if norm <= theta {
            let b = pade_coefficients(m);
            // U = A sum_{odd j} b_j A^(j-1), V = sum_{even j} b_j A^j.
            let mut powers = vec![identity.clone(), a2.clone()];
            while powers.len() <= m / 2 {
                let next = &powers[powers.len() - 1] * &a2;
                powers.push(next);
            }
            let odd: Vec<(f64, &Mat<f64>)> =
                (0..=m / 2).map(|k| (b[2 * k + 1], &powers[k])).collect();
            let even: Vec<(f64, &Mat<f64>)> = (0..=m / 2).map(|k| (b[2 * k], &powers[k])).collect();
            let u = a * combination(n, 0.0, &odd);
            let v = combination(n, 0.0, &even);
            return pade_solve(&u, &v);
        }
    }
    let theta = THETA[4].1;
    let s = if norm > theta {
        (norm / theta).log2().ceil().max(0.0) as i32
    } else {
        0
    };
    let factor = 2f64.powi(-s);
    let a1 = Mat::from_fn(n, n, |i, j| a[(i, j)] * factor);
    let a2 = &a1 * &a1;
    let a4 = &a2 * &a2;
    let a6 = &a4 * &a2;
    let b = pade_coefficients(13);
    let inner_u = combination(n, 0.0, &[(b[13], &a6), (b[11], &a4), (b[9], &a2)]);
    let u = &a1 * (&a6 * &inner_u + combination(n, b[1], &[(b[7], &a6), (b[5], &a4), (b[3], &a2)]));
    let inner_v = combination(n, 0.0, &[(b[12], &a6), (b[10], &a4), (b[8], &a2)]);
    let v = &a6 * &inner_v + combination(n, b[0], &[(b[6], &a6), (b[4], &a4), (b[2], &a2)]);
    let mut r = pade_solve(&u, &v)?;
    for _ in 0..s {
        r = &r * &r;
    }
    Ok(r)
}

/// `(V - U)^-1 (V + U)`.
fn pade_solve(u: &Mat<f64>, v: &Mat<f64>) -> Result<Mat<f64>, LinearError> {
    let q = v - u;
    let p = v + u;
    let x = q.partial_piv_lu().solve(&p);
    let n = x.nrows();
    if (0..n).any(|j| x.col_as_slice(j).iter().any(|v| !v.is_finite())) {
        return Err(LinearError::Numerics(
            "the Pade denominator of the matrix exponential is singular".into(),
        ));
    }
    Ok(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: &Mat<f64>, b: &Mat<f64>, tol: f64) -> f64 {
        let mut worst = 0.0f64;
        for i in 0..a.nrows() {
            for j in 0..a.ncols() {
                worst = worst.max((a[(i, j)] - b[(i, j)]).abs());
            }
        }
        assert!(worst <= tol, "{worst:e} > {tol:e}");
        worst
    }

    #[test]
    fn a_rotation_generator_gives_the_rotation() {
        // exp([[0 w], [-w 0]] t) = [[cos wt, sin wt], [-sin wt, cos wt]], over every branch of
        // the degree selection (norms from 1e-3 to 1e4).
        for wt in [1e-3, 0.2, 0.9, 2.0, 5.0, 40.0, 1e4] {
            let a = Mat::from_fn(2, 2, |i, j| match (i, j) {
                (0, 1) => wt,
                (1, 0) => -wt,
                _ => 0.0,
            });
            let (s, c) = f64::sin_cos(wt);
            let exact = Mat::from_fn(2, 2, |i, j| match (i, j) {
                (0, 0) | (1, 1) => c,
                (0, 1) => s,
                _ => -s,
            });
            // Squaring s times amplifies the rounding by about the number of squarings
            // times the norm (Higham 2005, section 3).
            close(&expm(&a).unwrap(), &exact, 1e-15 * wt.max(1.0) * 40.0);
        }
    }

    #[test]
    fn a_jordan_block_and_a_zero_order_hold() {
        // exp([[a 1], [0 a]]) = e^a [[1 1], [0 1]].
        let a = Mat::from_fn(2, 2, |i, j| match (i, j) {
            (0, 1) => 1.0,
            (0, 0) | (1, 1) => -3.0,
            _ => 0.0,
        });
        let e = (-3f64).exp();
        let exact = Mat::from_fn(2, 2, |i, j| if i > j { 0.0 } else { e });
        close(&expm(&a).unwrap(), &exact, 1e-16);
        // A mass on a spring (omega), held force: x' = v, v' = -omega^2 x + u. The ZOH block
        // of exp([[A B], [0 0]] T) is int_0^T exp(A s) ds B = [(1 - cos wT) / w^2,
        // sin(wT) / w].
        let (w, t) = (2.0 * std::f64::consts::PI * 1300.0, 1e-3);
        let m = Mat::from_fn(3, 3, |i, j| match (i, j) {
            (0, 1) => t,
            (1, 0) => -w * w * t,
            (1, 2) => t,
            _ => 0.0,
        });
        let e = expm(&m).unwrap();
        let (s, c) = (w * t).sin_cos();
        let rel = |got: f64, want: f64| (got - want).abs() / want.abs();
        assert!(rel(e[(0, 0)], c) < 1e-12, "{}", e[(0, 0)]);
        assert!(rel(e[(1, 0)], -w * s) < 1e-12);
        assert!(rel(e[(0, 2)], (1.0 - c) / (w * w)) < 1e-12, "{}", e[(0, 2)]);
        assert!(rel(e[(1, 2)], s / w) < 1e-12);
        assert!((e[(2, 2)] - 1.0).abs() < 1e-15);
    }
}
