//! Banded blocks with a dense border: the sparsity of a mechanical system whose coordinates
//! fall into chains (a flexible link's nodes, coupled only to their neighbours) joined through
//! a few shared coordinates (a platform, actuated sliders), and the LU factorisation that
//! exploits it.
//!
//! ```text
//!       blocks          border
//! [ A_1           | B_1 ]
//! [      A_2      | B_2 ]      A_b banded (half-bandwidth p), the border rows and
//! [           A_3 | B_3 ]      columns (B_b, R_b, D) dense
//! [ R_1  R_2  R_3 | D   ]
//! ```
//!
//! The factorisation is block elimination (Golub & Van Loan, *Matrix Computations*, 4th ed.,
//! 3.2.11 and 4.3): each `A_b = P_b L_b U_b` by Gaussian elimination with partial pivoting in
//! the band (the LAPACK `gbtf2` scheme, G&VL algorithm 4.3.5 with pivoting: `U_b` gets upper
//! bandwidth `2p`), `Y_b = A_b^-1 B_b`, the Schur complement `S = D - sum_b R_b Y_b` and its
//! dense LU with partial pivoting; a solve is `z_b = A_b^-1 r_b`,
//! `x_d = S^-1 (r_d - sum_b R_b z_b)`, `x_b = z_b - Y_b x_d`. The work is
//! `O(n p^2 + n p k + k^3)` for `n` coordinates and a border of `k` (dense LU: `n^3 / 3`),
//! and nothing is allocated after the storage is made (at the start of an integration).
//! Pivoting is within each block only, so the blocks themselves must be regular (a singular
//! block is reported like a singular matrix): for the iteration matrix of a mechanical
//! system, `M_b + gamma' h C_b + beta' h^2 K_b` of a chain with its border held, whose mass
//! part is positive definite.

// Index loops below mirror the formulas (rows and columns of small matrices).
#![allow(clippy::needless_range_loop)]

use std::ops::Range;

use faer::Mat;

use crate::IntegratorError;

/// The sparsity of an `n x n` matrix: diagonal blocks of consecutive coordinates, each
/// banded with half-bandwidth `p` (`a_ij = 0` for `|i - j| > p` within a block), no entries
/// between different blocks, and a dense border of the coordinates in no block (module
/// documentation of [`crate::structured`]).
///
/// ```
/// use flexprr_integrators::BlockBanded;
///
/// // Two chains of 4 coordinates (tridiagonal) after a shared coordinate 0.
/// let s = BlockBanded::new(9, vec![1..5, 5..9], 1).unwrap();
/// assert_eq!(s.border(), vec![0]);
/// assert!(s.contains(2, 3) && s.contains(0, 7) && s.contains(8, 0));
/// assert!(!s.contains(2, 4) && !s.contains(4, 5));
/// assert!(BlockBanded::new(9, vec![1..5, 4..9], 1).is_err()); // overlapping blocks
/// ```
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BlockBanded {
    n: usize,
    blocks: Vec<Range<usize>>,
    half_bandwidth: usize,
}

impl BlockBanded {
    /// `n` coordinates, the blocks as ranges of coordinates (in increasing order, disjoint,
    /// non-empty), the half-bandwidth of every block; the coordinates in no block form the
    /// border.
    ///
    /// # Errors
    /// [`IntegratorError::InvalidInput`] for a block that is empty, reaches past `n`, or
    /// overlaps or precedes the one before it.
    pub fn new(
        n: usize,
        blocks: Vec<Range<usize>>,
        half_bandwidth: usize,
    ) -> Result<Self, IntegratorError> {
        let mut end = 0;
        for (b, r) in blocks.iter().enumerate() {
            if r.start >= r.end || r.end > n || r.start < end {
                return Err(IntegratorError::InvalidInput(format!(
                    "block {b} ({}..{}) of a structure of {n} coordinates must be non-empty, \
                     within 0..{n} and after the block before it (ending at {end})",
                    r.start, r.end
                )));
            }
            end = r.end;
        }
        Ok(Self {
            n,
            blocks,
            half_bandwidth,
        })
    }

    /// Number of coordinates.
    pub fn coordinates(&self) -> usize {
        self.n
    }

    /// The blocks.
    pub fn blocks(&self) -> &[Range<usize>] {
        &self.blocks
    }

    /// The half-bandwidth of the blocks.
    pub fn half_bandwidth(&self) -> usize {
        self.half_bandwidth
    }

    /// The coordinates in no block, increasing (allocates).
    pub fn border(&self) -> Vec<usize> {
        (0..self.n)
            .filter(|&i| !self.blocks.iter().any(|r| r.contains(&i)))
            .collect()
    }

    /// The block holding coordinate `i`, if any.
    fn block_of(&self, i: usize) -> Option<usize> {
        self.blocks.iter().position(|r| r.contains(&i))
    }

    /// Whether entry `(i, j)` may be non-zero.
    pub fn contains(&self, i: usize, j: usize) -> bool {
        match (self.block_of(i), self.block_of(j)) {
            (Some(a), Some(b)) => a == b && i.abs_diff(j) <= self.half_bandwidth,
            _ => true,
        }
    }
}

/// Where a coordinate sits in [`BandedBordered`].
#[derive(Debug, Clone, Copy)]
enum Place {
    /// Position in the concatenated blocks, and the block.
    Block(usize, usize),
    /// Index in the border.
    Border(usize),
}

/// A matrix of a [`BlockBanded`] structure in compact storage, its product with vectors, and
/// its LU factorisation in place (module documentation). All storage is allocated by
/// [`BandedBordered::new`].
#[derive(Debug, Clone)]
pub(crate) struct BandedBordered {
    n: usize,
    p: usize,
    /// Rows of band storage per column: `3p + 1` (`p` below, `2p` above for the fill of
    /// pivoting).
    ld: usize,
    /// `(first coordinate, length, first position)` of each block.
    blocks: Vec<(usize, usize, usize)>,
    /// Positions in the blocks (their total length).
    nb: usize,
    border: Vec<usize>,
    place: Vec<Place>,
    /// Column `j` of block position `o + j` holds rows `j - 2p ..= j + p` at
    /// `(o + j) ld + (i + 2p - j)`; the factors `L`, `U` after [`BandedBordered::factor`].
    band: Vec<f64>,
    /// Row interchanges of the blocks' factorisations (local indices), per position.
    pivots: Vec<usize>,
    /// `1 / U_jj` of the blocks' factors, per position (the back substitution multiplies:
    /// a division in its chain of dependent steps costs several times a product).
    inverse_diagonal: Vec<f64>,
    /// `B_b`, column `c` of block `b` at `o k + c len .. + len`; `Y_b = A_b^-1 B_b` after
    /// factoring.
    right: Vec<f64>,
    /// `R`, row `c` at `c nb .. (c + 1) nb`.
    bottom: Vec<f64>,
    /// `D` column-major `k x k`; the LU of the Schur complement after factoring.
    corner: Vec<f64>,
    corner_pivots: Vec<usize>,
    /// Work: the right-hand side in block order, and the border's part.
    work: Vec<f64>,
    work_border: Vec<f64>,
}

/// `|pivot|` at or below this (or not finite) is a singular matrix.
const TINY: f64 = f64::MIN_POSITIVE;

impl BandedBordered {
    /// Zero storage for matrices of the structure `s`.
    pub(crate) fn new(s: &BlockBanded) -> Self {
        let p = s.half_bandwidth.min(s.n);
        let border = s.border();
        let k = border.len();
        let mut place = vec![Place::Border(0); s.n];
        for (c, &d) in border.iter().enumerate() {
            place[d] = Place::Border(c);
        }
        let mut blocks = Vec::with_capacity(s.blocks.len());
        let mut o = 0;
        for (b, r) in s.blocks.iter().enumerate() {
            blocks.push((r.start, r.len(), o));
            for (j, i) in r.clone().enumerate() {
                place[i] = Place::Block(o + j, b);
            }
            o += r.len();
        }
        let ld = 3 * p + 1;
        Self {
            n: s.n,
            p,
            ld,
            blocks,
            nb: o,
            border,
            place,
            band: vec![0.0; o * ld],
            pivots: vec![0; o],
            inverse_diagonal: vec![0.0; o],
            right: vec![0.0; o * k],
            bottom: vec![0.0; o * k],
            corner: vec![0.0; k * k],
            corner_pivots: vec![0; k],
            work: vec![0.0; o],
            work_border: vec![0.0; k],
        }
    }

    /// The first row `i` at which `column` (column `j` of an `n x n` matrix) is non-zero
    /// outside the structure, if any: every row of another block, and the rows of `j`'s own
    /// block beyond the half-bandwidth (border columns and rows hold anything). `column` must
    /// be finite. Contiguous slices, so that checking a whole matrix costs a pass over it.
    pub(crate) fn first_outside(&self, j: usize, column: &[f64]) -> Option<usize> {
        let Place::Block(_, own) = self.place[j] else {
            return None;
        };
        // A sum of magnitudes (vectorized) first, the position only when there is one; the
        // caller has checked that the column is finite.
        let nonzero = |rows: std::ops::Range<usize>| {
            let part = &column[rows.clone()];
            if part.iter().map(|v| v.abs()).sum::<f64>() > 0.0 {
                part.iter().position(|v| *v != 0.0).map(|r| rows.start + r)
            } else {
                None
            }
        };
        for (b, &(first, len, _)) in self.blocks.iter().enumerate() {
            let found = if b == own {
                let local = j - first;
                let (lo, hi) = (local.saturating_sub(self.p), (local + self.p + 1).min(len));
                nonzero(first..first + lo).or_else(|| nonzero(first + hi..first + len))
            } else {
                nonzero(first..first + len)
            };
            if found.is_some() {
                return found;
            }
        }
        None
    }

    /// The rows of column `j` inside the structure, as at most two ranges: a border column
    /// has every row (`None`); a block column the rows of its block within the
    /// half-bandwidth (the range returned) and the border's rows.
    fn rows_within(&self, j: usize) -> Option<std::ops::Range<usize>> {
        let Place::Block(_, own) = self.place[j] else {
            return None;
        };
        let (first, len, _) = self.blocks[own];
        let local = j - first;
        Some(first + local.saturating_sub(self.p)..first + (local + self.p + 1).min(len))
    }

    /// Zeroes the entries of the dense `n x n` column-major `a` inside the structure (the
    /// only ones [`BandedBordered::load`] reads), a pass over `O(n (2p + 1 + k))` entries
    /// instead of `n^2`.
    pub(crate) fn zero_within(&self, a: &mut Mat<f64>) {
        for j in 0..self.n {
            let column = a.col_as_slice_mut(j);
            match self.rows_within(j) {
                None => column.fill(0.0),
                Some(rows) => {
                    column[rows].fill(0.0);
                    for &d in &self.border {
                        column[d] = 0.0;
                    }
                }
            }
        }
    }

    /// The first row of column `j` of `column` inside the structure with a non-finite
    /// entry, if any (the entries outside are never read).
    pub(crate) fn first_non_finite_within(&self, j: usize, column: &[f64]) -> Option<usize> {
        match self.rows_within(j) {
            None => column.iter().position(|v| !v.is_finite()),
            Some(rows) => column[rows.clone()]
                .iter()
                .position(|v| !v.is_finite())
                .map(|r| rows.start + r)
                .or_else(|| {
                    self.border
                        .iter()
                        .copied()
                        .find(|&d| !column[d].is_finite())
                }),
        }
    }

    /// Border size.
    fn k(&self) -> usize {
        self.border.len()
    }

    /// `sum_t c_t A_t[(i, j)]` of the dense terms.
    #[inline]
    fn combined(terms: &[(f64, &Mat<f64>)], i: usize, j: usize) -> f64 {
        terms.iter().map(|(c, a)| c * a[(i, j)]).sum()
    }

    /// `out[r] = sum_t c_t A_t[(rows.start + r, j)]` over a range of rows of column `j`.
    #[inline]
    fn combined_column(terms: &[(f64, &Mat<f64>)], rows: Range<usize>, j: usize, out: &mut [f64]) {
        out.fill(0.0);
        for (c, a) in terms {
            let column = &a.col_as_slice(j)[rows.clone()];
            for (o, v) in out.iter_mut().zip(column) {
                *o += c * v;
            }
        }
    }

    /// Loads `sum_t c_t A_t` of dense `n x n` matrices, reading only the entries of the
    /// structure.
    pub(crate) fn load(&mut self, terms: &[(f64, &Mat<f64>)]) {
        let (p, ld, k) = (self.p, self.ld, self.k());
        for &(first, len, o) in &self.blocks {
            for j in 0..len {
                let col = &mut self.band[(o + j) * ld..(o + j + 1) * ld];
                let (i0, i1) = (j.saturating_sub(p), (j + p + 1).min(len));
                col[..i0 + 2 * p - j].fill(0.0);
                col[i1 + 2 * p - j..].fill(0.0);
                let rows = first + i0..first + i1;
                Self::combined_column(
                    terms,
                    rows,
                    first + j,
                    &mut col[i0 + 2 * p - j..i1 + 2 * p - j],
                );
            }
            for (c, &d) in self.border.iter().enumerate() {
                let out = &mut self.right[o * k + c * len..o * k + (c + 1) * len];
                Self::combined_column(terms, first..first + len, d, out);
                for i in 0..len {
                    self.bottom[c * self.nb + o + i] = Self::combined(terms, d, first + i);
                }
            }
        }
        for (c, &dc) in self.border.iter().enumerate() {
            for (r, &dr) in self.border.iter().enumerate() {
                self.corner[c * k + r] = Self::combined(terms, dr, dc);
            }
        }
    }

    /// `out = sign A x` (coordinates in the original order; before [`BandedBordered::factor`]).
    pub(crate) fn multiply(&self, x: &[f64], sign: f64, out: &mut [f64]) {
        let (p, ld, k, nb) = (self.p, self.ld, self.k(), self.nb);
        for &(first, len, o) in &self.blocks {
            let xb = &x[first..first + len];
            let ob = &mut out[first..first + len];
            ob.fill(0.0);
            for j in 0..len {
                let col = &self.band[(o + j) * ld..(o + j + 1) * ld];
                let xj = xb[j];
                if p == 5 && j >= 5 && j + 5 < len {
                    // The nonlinear links' half-bandwidth, a column of fixed length.
                    let c: &[f64; 11] = col[5..16].try_into().unwrap_or(&[0.0; 11]);
                    let o11: &mut [f64; 11] = (&mut ob[j - 5..j + 6])
                        .try_into()
                        .unwrap_or_else(|_| unreachable!("11 rows around an interior column"));
                    for i in 0..11 {
                        o11[i] += c[i] * xj;
                    }
                    continue;
                }
                for i in j.saturating_sub(p)..(j + p + 1).min(len) {
                    ob[i] += col[i + 2 * p - j] * xj;
                }
            }
            for (c, &d) in self.border.iter().enumerate() {
                let xd = x[d];
                let column = &self.right[o * k + c * len..o * k + (c + 1) * len];
                for (o_i, a) in ob.iter_mut().zip(column) {
                    *o_i += a * xd;
                }
            }
            for v in ob.iter_mut() {
                *v *= sign;
            }
        }
        for (r, &dr) in self.border.iter().enumerate() {
            let row = &self.bottom[r * nb..(r + 1) * nb];
            let mut sum = 0.0;
            for &(first, len, o) in &self.blocks {
                for (a, xi) in row[o..o + len].iter().zip(&x[first..first + len]) {
                    sum += a * xi;
                }
            }
            for (c, &dc) in self.border.iter().enumerate() {
                sum += self.corner[c * k + r] * x[dc];
            }
            out[dr] = sign * sum;
        }
    }

    /// Factors in place; `false` when a pivot is zero or not finite (a block or the Schur
    /// complement is singular to working precision).
    pub(crate) fn factor(&mut self) -> bool {
        let k = self.k();
        for b in 0..self.blocks.len() {
            let (_, len, o) = self.blocks[b];
            if !self.factor_block(o, len) {
                return false;
            }
            // Y_b = A_b^-1 B_b, column by column.
            let band = &self.band[o * self.ld..(o + len) * self.ld];
            let pivots = &self.pivots[o..o + len];
            let inverse = &self.inverse_diagonal[o..o + len];
            for c in 0..k {
                let start = o * k + c * len;
                solve_band(
                    band,
                    pivots,
                    inverse,
                    self.p,
                    &mut self.right[start..start + len],
                );
            }
            // D -= R_b Y_b.
            for c in 0..k {
                let y = &self.right[o * k + c * len..o * k + (c + 1) * len];
                for r in 0..k {
                    let row = &self.bottom[r * self.nb + o..r * self.nb + o + len];
                    let dot: f64 = row.iter().zip(y).map(|(a, b)| a * b).sum();
                    self.corner[c * k + r] -= dot;
                }
            }
        }
        dense_lu(&mut self.corner, &mut self.corner_pivots, k)
    }

    /// Banded LU with partial pivoting of the block at position `o`, `len` long (LAPACK's
    /// `gbtf2`).
    fn factor_block(&mut self, o: usize, len: usize) -> bool {
        let (p, ld) = (self.p, self.ld);
        let a = &mut self.band[o * ld..(o + len) * ld];
        let at = |i: usize, j: usize| j * ld + i + 2 * p - j;
        for j in 0..len {
            let last = (j + p).min(len - 1);
            let mut ip = j;
            let mut best = a[at(j, j)].abs();
            for i in j + 1..=last {
                let v = a[at(i, j)].abs();
                if v > best {
                    best = v;
                    ip = i;
                }
            }
            self.pivots[o + j] = ip;
            if !(best.is_finite() && best > TINY) {
                return false;
            }
            let cmax = (j + 2 * p).min(len - 1);
            if ip != j {
                for c in j..=cmax {
                    a.swap(at(j, c), at(ip, c));
                }
            }
            let inv = 1.0 / a[at(j, j)];
            self.inverse_diagonal[o + j] = inv;
            // Column j's multipliers (rows j+1..=last) and each later column's rows
            // j+1..=last are contiguous in the band storage.
            let (head, tail) = a.split_at_mut((j + 1) * ld);
            let below = j * ld + 2 * p + 1;
            let multipliers = &mut head[below..below + (last - j)];
            for l in multipliers.iter_mut() {
                *l *= inv;
            }
            for c in j + 1..=cmax {
                let col = &mut tail[(c - j - 1) * ld..(c - j) * ld];
                let u = col[j + 2 * p - c];
                if u != 0.0 {
                    let rows = &mut col[j + 1 + 2 * p - c..=last + 2 * p - c];
                    for (x, l) in rows.iter_mut().zip(multipliers.iter()) {
                        *x -= l * u;
                    }
                }
            }
        }
        true
    }

    /// The band storage of the block at position `o`, `len` long.
    fn block_band(&self, o: usize, len: usize) -> &[f64] {
        &self.band[o * self.ld..(o + len) * self.ld]
    }

    /// Solves `A x = rhs` in place with the factors (coordinates in the original order).
    pub(crate) fn solve_in_place(&mut self, rhs: &mut [f64]) {
        debug_assert_eq!(rhs.len(), self.n);
        let (k, nb) = (self.k(), self.nb);
        let mut w = std::mem::take(&mut self.work);
        let mut s = std::mem::take(&mut self.work_border);
        for (i, place) in self.place.iter().enumerate() {
            match *place {
                Place::Block(pos, _) => w[pos] = rhs[i],
                Place::Border(c) => s[c] = rhs[i],
            }
        }
        for &(_, len, o) in &self.blocks {
            let pivots = &self.pivots[o..o + len];
            let inverse = &self.inverse_diagonal[o..o + len];
            solve_band(
                self.block_band(o, len),
                pivots,
                inverse,
                self.p,
                &mut w[o..o + len],
            );
        }
        for r in 0..k {
            let row = &self.bottom[r * nb..(r + 1) * nb];
            s[r] -= row.iter().zip(&w).map(|(a, b)| a * b).sum::<f64>();
        }
        dense_solve(&self.corner, &self.corner_pivots, k, &mut s);
        for &(_, len, o) in &self.blocks {
            for c in 0..k {
                let y = &self.right[o * k + c * len..o * k + (c + 1) * len];
                let sc = s[c];
                for (wi, yi) in w[o..o + len].iter_mut().zip(y) {
                    *wi -= yi * sc;
                }
            }
        }
        for (i, place) in self.place.iter().enumerate() {
            rhs[i] = match *place {
                Place::Block(pos, _) => w[pos],
                Place::Border(c) => s[c],
            };
        }
        self.work = w;
        self.work_border = s;
    }
}

/// Solves in place with the banded LU factors `a` (band storage of
/// [`BandedBordered::factor_block`], `3p + 1` rows per column), row interchanges `pivots` and
/// the reciprocals of `U`'s diagonal `inverse`.
fn solve_band(a: &[f64], pivots: &[usize], inverse: &[f64], p: usize, r: &mut [f64]) {
    // The half-bandwidths the models use, with loops of fixed length the compiler unrolls
    // (the nonlinear links' 5: a third of the solve's instructions).
    match p {
        5 => return solve_band_fixed::<5, 10>(a, pivots, inverse, r),
        2 => return solve_band_fixed::<2, 4>(a, pivots, inverse, r),
        _ => {}
    }
    solve_band_any(a, pivots, inverse, p, r);
}

/// [`solve_band`] for the half-bandwidth `P` (`Q = 2 P`): the same operations, with the
/// interior columns' multipliers and `U` columns as arrays of fixed length.
fn solve_band_fixed<const P: usize, const Q: usize>(
    a: &[f64],
    pivots: &[usize],
    inverse: &[f64],
    r: &mut [f64],
) {
    let (len, ld) = (r.len(), 3 * P + 1);
    if len <= Q {
        solve_band_any(a, pivots, inverse, P, r);
        return;
    }
    for j in 0..len {
        let ip = pivots[j];
        if ip != j {
            r.swap(j, ip);
        }
        let rj = r[j];
        if rj != 0.0 {
            let start = j * ld + 2 * P + 1;
            if j + P < len {
                let l: &[f64; P] = a[start..start + P].try_into().unwrap_or(&[0.0; P]);
                let x: &mut [f64; P] = (&mut r[j + 1..j + 1 + P])
                    .try_into()
                    .unwrap_or_else(|_| unreachable!("P rows below an interior column"));
                for i in 0..P {
                    x[i] -= l[i] * rj;
                }
            } else {
                let end = len;
                for (x, l) in r[j + 1..end]
                    .iter_mut()
                    .zip(&a[start..start + (end - j - 1)])
                {
                    *x -= l * rj;
                }
            }
        }
    }
    for j in (0..len).rev() {
        let col = &a[j * ld..(j + 1) * ld];
        r[j] *= inverse[j];
        let rj = r[j];
        if rj != 0.0 {
            if j >= Q {
                let u: &[f64; Q] = col[..Q].try_into().unwrap_or(&[0.0; Q]);
                let x: &mut [f64; Q] = (&mut r[j - Q..j])
                    .try_into()
                    .unwrap_or_else(|_| unreachable!("Q rows above an interior column"));
                for i in 0..Q {
                    x[i] -= u[i] * rj;
                }
            } else {
                let u = &col[Q - j..Q];
                for (x, u) in r[..j].iter_mut().zip(u) {
                    *x -= u * rj;
                }
            }
        }
    }
}

/// [`solve_band`] for any half-bandwidth `p`.
fn solve_band_any(a: &[f64], pivots: &[usize], inverse: &[f64], p: usize, r: &mut [f64]) {
    let (len, ld) = (r.len(), 3 * p + 1);
    for j in 0..len {
        let ip = pivots[j];
        if ip != j {
            r.swap(j, ip);
        }
        let rj = r[j];
        if rj != 0.0 {
            // Column j's multipliers, rows j+1..j+p+1, are contiguous.
            let end = (j + p + 1).min(len);
            let l = &a[j * ld + 2 * p + 1..j * ld + 2 * p + 1 + (end - j - 1)];
            for (x, l) in r[j + 1..end].iter_mut().zip(l) {
                *x -= l * rj;
            }
        }
    }
    for j in (0..len).rev() {
        let col = &a[j * ld..(j + 1) * ld];
        r[j] *= inverse[j];
        let rj = r[j];
        if rj != 0.0 {
            // Column j of U, rows first..j, at offsets first + 2p - j .. 2p.
            let first = j.saturating_sub(2 * p);
            let u = &col[first + 2 * p - j..2 * p];
            for (x, u) in r[first..j].iter_mut().zip(u) {
                *x -= u * rj;
            }
        }
    }
}

/// LU with partial pivoting of the column-major `k x k` matrix `a` in place (G&VL algorithm
/// 3.4.1); `false` for a zero or non-finite pivot.
fn dense_lu(a: &mut [f64], pivots: &mut [usize], k: usize) -> bool {
    for j in 0..k {
        let mut ip = j;
        let mut best = a[j * k + j].abs();
        for i in j + 1..k {
            if a[j * k + i].abs() > best {
                best = a[j * k + i].abs();
                ip = i;
            }
        }
        pivots[j] = ip;
        if !(best.is_finite() && best > TINY) {
            return false;
        }
        // Rows from column j on (L stays unpermuted: the solve applies the interchanges
        // as it goes, as LAPACK's gbtf2 / gbtrs).
        if ip != j {
            for c in j..k {
                a.swap(c * k + j, c * k + ip);
            }
        }
        let inv = 1.0 / a[j * k + j];
        for i in j + 1..k {
            a[j * k + i] *= inv;
        }
        for c in j + 1..k {
            let u = a[c * k + j];
            for i in j + 1..k {
                a[c * k + i] -= a[j * k + i] * u;
            }
        }
    }
    true
}

/// Solves with the factors of [`dense_lu`] in place.
fn dense_solve(a: &[f64], pivots: &[usize], k: usize, r: &mut [f64]) {
    for j in 0..k {
        r.swap(j, pivots[j]);
        for i in j + 1..k {
            r[i] -= a[j * k + i] * r[j];
        }
    }
    for j in (0..k).rev() {
        r[j] /= a[j * k + j];
        for i in 0..j {
            r[i] -= a[j * k + i] * r[j];
        }
    }
}

#[cfg(test)]
#[allow(
    clippy::single_range_in_vec_init,
    reason = "structures of one block are lists of one range"
)]
mod tests {
    use super::*;
    use crate::common::DenseLu;

    /// A linear congruential generator on `[-0.5, 0.5)`.
    fn random(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64) / (1u64 << 53) as f64 - 0.5
    }

    /// A random non-symmetric matrix of the structure: small diagonals in some blocks so
    /// that the banded elimination must pivot, a border at both ends and in between.
    fn random_matrix(s: &BlockBanded, seed: &mut u64) -> Mat<f64> {
        let n = s.coordinates();
        let mut a = Mat::zeros(n, n);
        for j in 0..n {
            for i in 0..n {
                if s.contains(i, j) {
                    a[(i, j)] = random(seed);
                }
            }
            a[(j, j)] += if j % 3 == 0 { 0.01 } else { 2.0 };
        }
        a
    }

    /// `max_i |(A x - b)_i| / (|A| |x| + |b|)_i` by plain loops over the dense matrix.
    fn residual(a: &Mat<f64>, x: &[f64], b: &[f64]) -> f64 {
        let n = b.len();
        (0..n)
            .map(|i| {
                let (mut r, mut scale) = (-b[i], b[i].abs());
                for j in 0..n {
                    r += a[(i, j)] * x[j];
                    scale += (a[(i, j)] * x[j]).abs();
                }
                r.abs() / scale
            })
            .fold(0.0, f64::max)
    }

    /// The structured LU solves random banded-bordered systems to round-off, as faer's dense
    /// LU does (both checked by the residual `A x - b` over the dense matrix), and the
    /// product agrees with the dense one; several shapes, including no border and no block.
    #[test]
    fn structured_lu_solves_like_the_dense_lu() {
        let shapes = [
            (40, vec![2..14, 14..26, 26..38], 3),
            (23, vec![0..10, 13..23], 2),
            (12, vec![0..12], 1),
            (9, vec![], 2),
            (30, vec![1..9, 9..17, 17..25], 5),
        ];
        let mut seed = 7;
        for (n, blocks, p) in shapes {
            let s = BlockBanded::new(n, blocks, p).unwrap();
            for trial in 0..5 {
                let a = random_matrix(&s, &mut seed);
                let b: Vec<f64> = (0..n).map(|_| random(&mut seed)).collect();
                let mut structured = BandedBordered::new(&s);
                structured.load(&[(1.0, &a)]);
                let mut product = vec![0.0; n];
                structured.multiply(&b, -2.0, &mut product);
                for i in 0..n {
                    let dense: f64 = (0..n).map(|j| a[(i, j)] * b[j]).sum();
                    assert!((product[i] + 2.0 * dense).abs() < 1e-14 * (1.0 + dense.abs()));
                }
                assert!(structured.factor(), "shape n = {n}, trial {trial}");
                let mut x = b.clone();
                structured.solve_in_place(&mut x);
                let mut lu = DenseLu::new(n);
                lu.matrix.copy_from(&a);
                assert!(lu.factor());
                let mut x_dense = b.clone();
                lu.solve_in_place(&mut x_dense);
                let (r_s, r_d) = (residual(&a, &x, &b), residual(&a, &x_dense, &b));
                assert!(r_s < 1e-13 && r_d < 1e-13, "residuals {r_s:e}, {r_d:e}");
                let size = x_dense.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                for i in 0..n {
                    assert!((x[i] - x_dense[i]).abs() < 1e-10 * size, "n = {n}: {i}");
                }
            }
        }
    }

    /// `first_outside` finds an entry exactly where `BlockBanded::contains` (written
    /// independently, by searching the block ranges) says it may not be, in every column,
    /// with a second, admitted entry before it that must not be reported.
    #[test]
    fn entries_outside_the_structure_are_found() {
        let shapes = [
            (40, vec![2..14, 14..26, 26..38], 3),
            (23, vec![0..10, 13..23], 2),
            (9, vec![], 2),
        ];
        for (n, blocks, p) in shapes {
            let s = BlockBanded::new(n, blocks, p).unwrap();
            let structured = BandedBordered::new(&s);
            for j in 0..n {
                for i in 0..n {
                    let mut column = vec![0.0; n];
                    column[j] = 1.0;
                    column[i] = -2.0;
                    let expected = (!s.contains(i, j)).then_some(i);
                    assert_eq!(structured.first_outside(j, &column), expected, "({i}, {j})");
                }
            }
        }
    }

    /// A singular block and a singular Schur complement are refused.
    #[test]
    fn singular_matrices_are_refused() {
        let s = BlockBanded::new(5, vec![0..4], 1).unwrap();
        let mut a = Mat::zeros(5, 5);
        for i in 0..5 {
            a[(i, i)] = 1.0;
        }
        let mut m = BandedBordered::new(&s);
        a[(2, 2)] = 0.0;
        m.load(&[(1.0, &a)]);
        assert!(!m.factor());
        // The block regular, the whole singular: rows 3 and 4 equal.
        a[(2, 2)] = 1.0;
        a[(3, 4)] = 1.0;
        a[(4, 3)] = 1.0;
        a[(4, 4)] = 1.0;
        m.load(&[(1.0, &a)]);
        assert!(!m.factor());
    }
}
