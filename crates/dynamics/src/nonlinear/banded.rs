//! A symmetric positive definite "arrowhead" of banded blocks: the generalized mass of the
//! nonlinear machine (one banded block per link, coupled only through a small dense border:
//! the platform's coordinates and the actuated sliders).
//!
//! ```text
//! [ A_1          C_1 ] [x_1]   [r_1]
//! [      A_2     C_2 ] [x_2] = [r_2]      A_b banded (half-bandwidth w), border D dense
//! [ C_1^T C_2^T  D   ] [x_d]   [r_d]
//! ```
//!
//! solved by block elimination: banded Cholesky `A_b = L_b L_b^T` (Golub & Van Loan,
//! *Matrix Computations*, 4th ed., algorithm 4.3.5), `Y_b = L_b^-1 C_b`, the Schur complement
//! `S = D - sum_b Y_b^T Y_b` by a dense Cholesky, then back substitution. Storage is allocated
//! once; factorizations and solves allocate nothing. `O(blocks n w^2 + blocks n w k + k^3)`
//! for a border of size `k`.

// Index loops below mirror the formulas (rows and columns of small matrices).
#![allow(clippy::needless_range_loop)]

/// The matrix, its factors and the work space (see the module documentation).
#[derive(Debug, Clone, Default)]
pub(crate) struct BorderedBanded {
    blocks: usize,
    n: usize,
    w: usize,
    k: usize,
    /// Lower band of each block, row-major `[block][i][d]` = `A[i][i - d]`, `d = 0..=w`;
    /// replaced by `L` on factorization.
    band: Vec<f64>,
    /// `C_b`, `[block][i][c]`; replaced by `Y_b = L_b^-1 C_b`.
    coupling: Vec<f64>,
    /// `D`, `[r][c]`; replaced by the Cholesky factor of the Schur complement (lower).
    border: Vec<f64>,
}

/// The matrix was not numerically positive definite (a pivot at or below zero).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct NotPositiveDefinite;

impl BorderedBanded {
    /// Zero matrix of `blocks` blocks of size `n` with half-bandwidth `w` and a border of
    /// size `k`.
    pub(crate) fn new(blocks: usize, n: usize, w: usize, k: usize) -> Self {
        Self {
            blocks,
            n,
            w,
            k,
            band: vec![0.0; blocks * n * (w + 1)],
            coupling: vec![0.0; blocks * n * k],
            border: vec![0.0; k * k],
        }
    }

    /// Size of the border.
    pub(crate) fn border_size(&self) -> usize {
        self.k
    }

    /// Sets every entry to zero.
    pub(crate) fn clear(&mut self) {
        self.band.fill(0.0);
        self.coupling.fill(0.0);
        self.border.fill(0.0);
    }

    /// Adds `v` to `A_b[i][j]` and `A_b[j][i]` (once if `i == j`); `|i - j| <= w`.
    #[inline]
    pub(crate) fn add_block(&mut self, b: usize, i: usize, j: usize, v: f64) {
        let (hi, lo) = if i >= j { (i, j) } else { (j, i) };
        debug_assert!(hi - lo <= self.w, "outside the band");
        self.band[(b * self.n + hi) * (self.w + 1) + (hi - lo)] += v;
    }

    /// Adds `v` to `C_b[i][c]` (and its transpose).
    #[inline]
    pub(crate) fn add_coupling(&mut self, b: usize, i: usize, c: usize, v: f64) {
        self.coupling[(b * self.n + i) * self.k + c] += v;
    }

    /// Adds `v` to `D[r][c]` (the caller adds both triangles).
    #[inline]
    pub(crate) fn add_border(&mut self, r: usize, c: usize, v: f64) {
        self.border[r * self.k + c] += v;
    }

    /// `A x` before factorization: `blocks_x` holds `x_1 .. x_B` (`blocks n` values),
    /// `border_x` holds `x_d` (`k` values); the product into `blocks_out`, `border_out`.
    pub(crate) fn multiply(
        &self,
        blocks_x: &[f64],
        border_x: &[f64],
        blocks_out: &mut [f64],
        border_out: &mut [f64],
    ) {
        let (n, w, k) = (self.n, self.w, self.k);
        for (r, out) in border_out.iter_mut().enumerate() {
            *out = (0..k).map(|c| self.border[r * k + c] * border_x[c]).sum();
        }
        // The models' sizes, with loops of fixed length the compiler unrolls.
        match (w, k) {
            (5, 3) => {
                return self.multiply_fixed::<5, 3>(blocks_x, border_x, blocks_out, border_out);
            }
            (5, 6) => {
                return self.multiply_fixed::<5, 6>(blocks_x, border_x, blocks_out, border_out);
            }
            _ => {}
        }
        for b in 0..self.blocks {
            let band = &self.band[b * n * (w + 1)..(b + 1) * n * (w + 1)];
            let c = &self.coupling[b * n * k..(b + 1) * n * k];
            let x = &blocks_x[b * n..(b + 1) * n];
            let out = &mut blocks_out[b * n..(b + 1) * n];
            for i in 0..n {
                // The diagonal and the lower band of row i, and the lower band's transpose:
                // `row[d] = A[i][i - d]` against `x[i - d]`, `out[i - d]` (d = 1..=m), the
                // windows below `i` walked backwards (no index arithmetic in the loop).
                let row = &band[i * (w + 1)..(i + 1) * (w + 1)];
                let (xi, m) = (x[i], w.min(i));
                let mut sum = row[0] * xi;
                let lower = row[1..=m]
                    .iter()
                    .zip(x[i - m..i].iter().rev())
                    .zip(out[i - m..i].iter_mut().rev());
                for ((a, xj), oj) in lower {
                    sum += a * xj;
                    *oj += a * xi;
                }
                let coupling = &c[i * k..(i + 1) * k];
                out[i] = sum
                    + coupling
                        .iter()
                        .zip(border_x)
                        .map(|(a, y)| a * y)
                        .sum::<f64>();
                for (o, a) in border_out.iter_mut().zip(coupling) {
                    *o += a * x[i];
                }
            }
        }
    }

    /// The blocks' part of [`BorderedBanded::multiply`] for the half-bandwidth `W` and the
    /// border size `K` (the border's own product is done): the same sums, each row's lower
    /// band and coupling as arrays of fixed length.
    fn multiply_fixed<const W: usize, const K: usize>(
        &self,
        blocks_x: &[f64],
        border_x: &[f64],
        blocks_out: &mut [f64],
        border_out: &mut [f64],
    ) {
        let n = self.n;
        let bx: &[f64; K] = border_x.try_into().unwrap_or(&[0.0; K]);
        let mut border_sum = [0.0; K];
        for b in 0..self.blocks {
            let band = &self.band[b * n * (W + 1)..(b + 1) * n * (W + 1)];
            let c = &self.coupling[b * n * K..(b + 1) * n * K];
            let x = &blocks_x[b * n..(b + 1) * n];
            let out = &mut blocks_out[b * n..(b + 1) * n];
            for i in 0..n {
                let row = &band[i * (W + 1)..(i + 1) * (W + 1)];
                let xi = x[i];
                let mut sum = row[0] * xi;
                if i >= W {
                    // `row[d] = A[i][i - d]` against `x[i - d]` and into `out[i - d]`.
                    let xs: &[f64; W] = x[i - W..i].try_into().unwrap_or(&[0.0; W]);
                    let os: &mut [f64; W] = (&mut out[i - W..i])
                        .try_into()
                        .unwrap_or_else(|_| unreachable!("W rows below row i"));
                    for d in 1..=W {
                        let a = row[d];
                        sum += a * xs[W - d];
                        os[W - d] += a * xi;
                    }
                } else {
                    for d in 1..=i {
                        let a = row[d];
                        sum += a * x[i - d];
                        out[i - d] += a * xi;
                    }
                }
                let coupling: &[f64; K] = c[i * K..(i + 1) * K].try_into().unwrap_or(&[0.0; K]);
                let mut cross = 0.0;
                for j in 0..K {
                    cross += coupling[j] * bx[j];
                    border_sum[j] += coupling[j] * xi;
                }
                out[i] = sum + cross;
            }
        }
        for (o, s) in border_out.iter_mut().zip(border_sum) {
            *o += s;
        }
    }

    /// Factorizes in place.
    pub(crate) fn factor(&mut self) -> Result<(), NotPositiveDefinite> {
        let (n, w, k) = (self.n, self.w, self.k);
        for b in 0..self.blocks {
            let band = &mut self.band[b * n * (w + 1)..(b + 1) * n * (w + 1)];
            // Banded Cholesky, row by row: L[i][j] for j in i-w..=i.
            for i in 0..n {
                let j0 = i.saturating_sub(w);
                for j in j0..=i {
                    let mut sum = band[i * (w + 1) + (i - j)];
                    let m0 = j0.max(j.saturating_sub(w));
                    for m in m0..j {
                        sum -= band[i * (w + 1) + (i - m)] * band[j * (w + 1) + (j - m)];
                    }
                    if i == j {
                        if !(sum > 0.0 && sum.is_finite()) {
                            return Err(NotPositiveDefinite);
                        }
                        band[i * (w + 1)] = sum.sqrt();
                    } else {
                        band[i * (w + 1) + (i - j)] = sum / band[j * (w + 1)];
                    }
                }
            }
            // Y = L^-1 C, column by column (forward substitution in the band).
            let c = &mut self.coupling[b * n * k..(b + 1) * n * k];
            for col in 0..k {
                for i in 0..n {
                    let mut sum = c[i * k + col];
                    for m in i.saturating_sub(w)..i {
                        sum -= band[i * (w + 1) + (i - m)] * c[m * k + col];
                    }
                    c[i * k + col] = sum / band[i * (w + 1)];
                }
            }
            // D -= Y^T Y.
            for r in 0..k {
                for s in 0..k {
                    let mut sum = 0.0;
                    for i in 0..n {
                        sum += c[i * k + r] * c[i * k + s];
                    }
                    self.border[r * k + s] -= sum;
                }
            }
        }
        // Dense Cholesky of the Schur complement (lower triangle).
        let d = &mut self.border;
        for i in 0..k {
            for j in 0..=i {
                let mut sum = d[i * k + j];
                for m in 0..j {
                    sum -= d[i * k + m] * d[j * k + m];
                }
                if i == j {
                    if !(sum > 0.0 && sum.is_finite()) {
                        return Err(NotPositiveDefinite);
                    }
                    d[i * k + i] = sum.sqrt();
                } else {
                    d[i * k + j] = sum / d[j * k + j];
                }
            }
        }
        Ok(())
    }

    /// Solves in place with the factors: `blocks_rhs` holds `r_1 .. r_B` (`blocks n`
    /// values), `border_rhs` holds `r_d` (`k` values).
    pub(crate) fn solve(&self, blocks_rhs: &mut [f64], border_rhs: &mut [f64]) {
        let (n, w, k) = (self.n, self.w, self.k);
        // Forward: z_b = L_b^-1 r_b; s = r_d - sum Y_b^T z_b.
        for b in 0..self.blocks {
            let band = &self.band[b * n * (w + 1)..(b + 1) * n * (w + 1)];
            let r = &mut blocks_rhs[b * n..(b + 1) * n];
            for i in 0..n {
                let mut sum = r[i];
                for m in i.saturating_sub(w)..i {
                    sum -= band[i * (w + 1) + (i - m)] * r[m];
                }
                r[i] = sum / band[i * (w + 1)];
            }
            let c = &self.coupling[b * n * k..(b + 1) * n * k];
            for (col, s) in border_rhs.iter_mut().enumerate() {
                let mut sum = 0.0;
                for i in 0..n {
                    sum += c[i * k + col] * r[i];
                }
                *s -= sum;
            }
        }
        // Border: S x_d = s by the dense factor.
        let d = &self.border;
        for i in 0..k {
            let mut sum = border_rhs[i];
            for m in 0..i {
                sum -= d[i * k + m] * border_rhs[m];
            }
            border_rhs[i] = sum / d[i * k + i];
        }
        for i in (0..k).rev() {
            let mut sum = border_rhs[i];
            for m in i + 1..k {
                sum -= d[m * k + i] * border_rhs[m];
            }
            border_rhs[i] = sum / d[i * k + i];
        }
        // Back: L_b^T x_b = z_b - Y_b x_d.
        for b in 0..self.blocks {
            let band = &self.band[b * n * (w + 1)..(b + 1) * n * (w + 1)];
            let c = &self.coupling[b * n * k..(b + 1) * n * k];
            let r = &mut blocks_rhs[b * n..(b + 1) * n];
            for i in 0..n {
                let mut sum = 0.0;
                for col in 0..k {
                    sum += c[i * k + col] * border_rhs[col];
                }
                r[i] -= sum;
            }
            for i in (0..n).rev() {
                let mut sum = r[i];
                for m in i + 1..(i + w + 1).min(n) {
                    sum -= band[m * (w + 1) + (m - i)] * r[m];
                }
                r[i] = sum / band[i * (w + 1)];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against a dense solve of the same matrix (three blocks of 7, bandwidth 2, border 3).
    #[test]
    fn solves_like_the_dense_matrix() {
        let (blocks, n, w, k) = (3, 7, 2, 3);
        let size = blocks * n + k;
        let mut dense = vec![vec![0.0; size]; size];
        let mut m = BorderedBanded::new(blocks, n, w, k);
        let mut seed = 1u64;
        let mut random = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 33) as f64) / (1u64 << 31) as f64 - 0.5
        };
        for b in 0..blocks {
            for i in 0..n {
                for j in i.saturating_sub(w)..=i {
                    let v = if i == j { 4.0 + random() } else { random() };
                    m.add_block(b, i, j, v);
                    dense[b * n + i][b * n + j] += v;
                    if i != j {
                        dense[b * n + j][b * n + i] += v;
                    }
                }
                for c in 0..k {
                    let v = 0.3 * random();
                    m.add_coupling(b, i, c, v);
                    dense[b * n + i][blocks * n + c] += v;
                    dense[blocks * n + c][b * n + i] += v;
                }
            }
        }
        for r in 0..k {
            for c in 0..=r {
                let v = if r == c { 5.0 } else { 0.5 * random() };
                m.add_border(r, c, v);
                dense[blocks * n + r][blocks * n + c] += v;
                if r != c {
                    m.add_border(c, r, v);
                    dense[blocks * n + c][blocks * n + r] += v;
                }
            }
        }
        let rhs: Vec<f64> = (0..size).map(|i| (i as f64).sin()).collect();
        let (mut p_blocks, mut p_border) = (vec![0.0; blocks * n], vec![0.0; k]);
        m.multiply(
            &rhs[..blocks * n],
            &rhs[blocks * n..],
            &mut p_blocks,
            &mut p_border,
        );
        for (i, p) in p_blocks.iter().chain(&p_border).enumerate() {
            let dense: f64 = (0..size).map(|j| dense[i][j] * rhs[j]).sum();
            assert!((p - dense).abs() < 1e-14, "product row {i}: {p} vs {dense}");
        }
        m.factor().unwrap();
        let (mut x_blocks, mut x_border) = (rhs[..blocks * n].to_vec(), rhs[blocks * n..].to_vec());
        m.solve(&mut x_blocks, &mut x_border);
        let x: Vec<f64> = x_blocks.into_iter().chain(x_border).collect();
        for i in 0..size {
            let ax: f64 = (0..size).map(|j| dense[i][j] * x[j]).sum();
            assert!((ax - rhs[i]).abs() < 1e-12, "row {i}: {ax} vs {}", rhs[i]);
        }
        // Not positive definite: refused.
        let mut bad = BorderedBanded::new(1, 2, 1, 0);
        bad.add_block(0, 0, 0, 1.0);
        bad.add_block(0, 1, 1, 1.0);
        bad.add_block(0, 1, 0, 2.0);
        assert_eq!(bad.factor(), Err(NotPositiveDefinite));
    }
}
