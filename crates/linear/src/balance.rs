//! Balancing of `A` before its eigenvalues (Parlett & Reinsch, "Balancing a matrix for
//! calculation of eigenvalues and eigenvectors", Numer. Math. 13 (1969) 293-304; LAPACK's
//! `gebal`): a diagonal similarity `D^-1 A D` with powers of two that makes each row and
//! column of about equal norm. A machine's first-order matrix pairs positions (m) with rates
//! (m/s) and stiff axial modes (`omega^2 ~ 1e12`) with slow servo modes: unbalanced, the
//! eigenvalues of the slow modes lose most of their digits.

use faer::Mat;

/// `D^-1 A D` and the diagonal `D`.
pub(crate) fn balance(a: &Mat<f64>) -> (Mat<f64>, Vec<f64>) {
    let n = a.nrows();
    let mut b = a.clone();
    let mut d = vec![1.0; n];
    const RADIX: f64 = 2.0;
    for _sweep in 0..100 {
        let mut converged = true;
        for i in 0..n {
            let (mut column, mut row) = (0.0, 0.0);
            for j in 0..n {
                if j != i {
                    column += b[(j, i)].abs();
                    row += b[(i, j)].abs();
                }
            }
            if column <= 0.0 || row <= 0.0 {
                continue;
            }
            let (mut f, sum) = (1.0, column + row);
            let (mut c, mut r) = (column, row);
            while c < r / RADIX {
                c *= RADIX;
                r /= RADIX;
                f *= RADIX;
            }
            while c >= r * RADIX {
                c /= RADIX;
                r *= RADIX;
                f /= RADIX;
            }
            if (c + r) < 0.95 * sum {
                converged = false;
                d[i] *= f;
                for j in 0..n {
                    b[(i, j)] /= f;
                    b[(j, i)] *= f;
                }
            }
        }
        if converged {
            break;
        }
    }
    (b, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn balancing_is_a_similarity_that_evens_the_norms() {
        let a = Mat::from_fn(4, 4, |i, j| {
            if i + 2 == j {
                1.0
            } else if i >= 2 && j < 2 {
                -1e12 * (1.0 + (i + j) as f64)
            } else {
                0.0
            }
        });
        let (b, d) = balance(&a);
        for i in 0..4 {
            for j in 0..4 {
                let back = b[(i, j)] * d[i] / d[j];
                assert!((back - a[(i, j)]).abs() <= 1e-15 * a[(i, j)].abs().max(1.0));
            }
        }
        let norm = |k: usize, row: bool| {
            (0..4)
                .map(|j| if row { b[(k, j)] } else { b[(j, k)] }.abs())
                .sum::<f64>()
        };
        for k in 0..4 {
            let ratio = norm(k, true) / norm(k, false);
            assert!(ratio > 0.1 && ratio < 10.0, "{k}: {ratio}");
        }
    }
}
