//! Cyclic Jacobi diagonalization of a small symmetric matrix, in place and without
//! allocation (Golub & Van Loan, *Matrix Computations*, 4th ed., Algorithms 8.5.1-8.5.3).

/// Largest number of sweeps; a warm-started matrix needs one or two.
#[cfg(test)]
const MAX_SWEEPS: usize = 30;

/// Diagonalizes the symmetric `n x n` row-major `a` by plane rotations `J`: on return `a`
/// holds `R^T a R` (diagonal up to `1e-15` of its norm) and `v` holds `v R` (its columns are
/// rotated). Returns the number of sweeps used.
#[cfg(test)]
pub(crate) fn jacobi_diagonalize(a: &mut [f64], v: &mut [f64], n: usize) -> usize {
    let norm: f64 = a.iter().map(|x| x * x).sum::<f64>().sqrt();
    if norm <= 0.0 {
        return 0;
    }
    for sweep in 0..MAX_SWEEPS {
        let mut off = 0.0;
        for i in 0..n {
            for j in 0..n {
                if i != j {
                    off += a[i * n + j] * a[i * n + j];
                }
            }
        }
        if off.sqrt() <= 1e-15 * norm {
            return sweep;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = a[p * n + q];
                if apq.abs() <= 0.0 {
                    continue;
                }
                let (c, s) = schur_rotation(a[p * n + p], a[q * n + q], apq);
                rotate_congruence(a, n, p, q, c, s);
                rotate_columns(v, n, p, q, c, s);
            }
        }
    }
    MAX_SWEEPS
}

/// The rotation `(c, s)` of the symmetric Schur decomposition that zeroes the `(p, q)` entry
/// of a symmetric matrix with diagonal entries `app`, `aqq` and off-diagonal `apq != 0`
/// (Golub & Van Loan, Algorithm 8.5.1).
#[inline]
pub(crate) fn schur_rotation(app: f64, aqq: f64, apq: f64) -> (f64, f64) {
    let tau = (aqq - app) / (2.0 * apq);
    let t = if tau >= 0.0 { 1.0 } else { -1.0 } / (tau.abs() + (1.0 + tau * tau).sqrt());
    let c = 1.0 / (1.0 + t * t).sqrt();
    (c, t * c)
}

/// `a <- J^T a J` for the rotation `J` in the `(p, q)` plane (`O(n)`).
#[inline]
pub(crate) fn rotate_congruence(a: &mut [f64], n: usize, p: usize, q: usize, c: f64, s: f64) {
    rotate_columns(a, n, p, q, c, s);
    for k in 0..n {
        let apk = a[p * n + k];
        let aqk = a[q * n + k];
        a[p * n + k] = c * apk - s * aqk;
        a[q * n + k] = s * apk + c * aqk;
    }
}

/// `v <- v J`: columns `p` and `q` of the row-major `n x n` `v` rotated.
#[inline]
pub(crate) fn rotate_columns(v: &mut [f64], n: usize, p: usize, q: usize, c: f64, s: f64) {
    for k in 0..n {
        let vkp = v[k * n + p];
        let vkq = v[k * n + q];
        v[k * n + p] = c * vkp - s * vkq;
        v[k * n + q] = s * vkp + c * vkq;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `V^T A V` is diagonal, `V` orthogonal, and the eigenvalues of a matrix with known
    /// spectrum (a rotated diagonal) are recovered.
    #[test]
    fn diagonalizes_a_rotated_diagonal_matrix() {
        let n = 4;
        let lambda = [3.0, -1.0, 10.0, 0.5];
        // An orthogonal Q from two Givens rotations and a reflection-free mix.
        let mut q = vec![0.0; n * n];
        for i in 0..n {
            q[i * n + i] = 1.0;
        }
        let rot = |p: usize, r: usize, ang: f64, q: &mut Vec<f64>| {
            let (s, c) = ang.sin_cos();
            for k in 0..n {
                let a = q[k * n + p];
                let b = q[k * n + r];
                q[k * n + p] = c * a - s * b;
                q[k * n + r] = s * a + c * b;
            }
        };
        rot(0, 1, 0.3, &mut q);
        rot(1, 3, -1.1, &mut q);
        rot(0, 2, 0.7, &mut q);
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                a[i * n + j] = (0..n)
                    .map(|k| q[i * n + k] * lambda[k] * q[j * n + k])
                    .sum();
            }
        }
        let orig = a.clone();
        let mut v = vec![0.0; n * n];
        for i in 0..n {
            v[i * n + i] = 1.0;
        }
        jacobi_diagonalize(&mut a, &mut v, n);
        let mut got: Vec<f64> = (0..n).map(|i| a[i * n + i]).collect();
        got.sort_by(f64::total_cmp);
        let mut want = lambda.to_vec();
        want.sort_by(f64::total_cmp);
        for (g, w) in got.iter().zip(&want) {
            assert!((g - w).abs() < 1e-13, "{got:?} vs {want:?}");
        }
        // V^T orig V equals the diagonal result.
        for i in 0..n {
            for j in 0..n {
                let mut s = 0.0;
                for k in 0..n {
                    for l in 0..n {
                        s += v[k * n + i] * orig[k * n + l] * v[l * n + j];
                    }
                }
                let want = if i == j { a[i * n + i] } else { 0.0 };
                assert!((s - want).abs() < 1e-12, "({i},{j}): {s}");
            }
        }
    }
}
