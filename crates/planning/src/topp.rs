//! Time-optimal path parameterization by reachability analysis (TOPP-RA: H. Pham and
//! Q.-C. Pham, "A new approach to time-optimal path parameterization based on reachability
//! analysis", IEEE T-RO 34(3), 2018).
//!
//! On a grid `s_0 < ... < s_N` the state is `x_k = s'^2` at `s_k` and the control the
//! constant path acceleration `u_k` on `[s_k, s_{k+1}]`, so `x_{k+1} = x_k + 2 Delta_k u_k`.
//! The constraints of segment `k` are the rows of point `k` at `(u_k, x_k)` and, by the
//! first-order interpolation of the paper (its section on discretization), the rows of point
//! `k+1` at `(u_k, x_{k+1}) = (u_k, x_k + 2 Delta_k u_k)`: the motion is checked at both ends
//! of every segment with the acceleration it actually has there.
//!
//! 1. Backward pass: the controllable sets `K_N = {x_end}`,
//!    `K_k = {x >= 0 : exists u, (u, x) feasible on segment k, x + 2 Delta_k u in K_{k+1}}`,
//!    intervals `[lo_k, hi_k]`: each the projection of a polygon in `(u, x)` on `x`, a
//!    two-variable linear program solved here exactly by Fourier-Motzkin elimination of `u`
//!    (every pair of a lower and an upper bound on `u` gives one bound on `x`).
//! 2. Forward pass: from `x_0`, the largest `u_k` that keeps `x_{k+1}` in `K_{k+1}` (greedy,
//!    optimal by the paper's theorem).
//!
//! A row with a `sqrt(x)` term (viscous friction) is replaced by a half-plane inside it:
//! where `sqrt(x)` makes the row harder to meet (`c sqrt(x)` on the side of the limit, a
//! concave function) by its tangent at `x_0` (`sqrt(x) <= sqrt(x0)/2 + x/(2 sqrt(x0))`),
//! where it helps by chords on `[0, X]` (`X` the point's exact speed bound, below which the
//! chords of the concave `sqrt` lie under it) or, without such a bound, by nothing. The planner re-solves with the tangents at the solution until
//! the duration settles; every solution is feasible for the exact rows at the grid points.
//! Rows with only `sqrt(x)` (speed limits) are exact bounds on `x`.
//!
//! Periodic boundary (a closed path repeated): the backward pass is repeated around the loop,
//! `K_N <- K_0`, until the sets stop shrinking, and the forward pass from `x_0 = hi_0` is
//! repeated with `x_0 <- x_N` until the path speed closes on itself.

use crate::constraint::{Row, maximum_speed};

/// A half-plane `a u + b x <= g`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Plane {
    pub(crate) a: f64,
    pub(crate) b: f64,
    pub(crate) g: f64,
}

impl Plane {
    const NONE: Plane = Plane {
        a: 0.0,
        b: 0.0,
        g: f64::INFINITY,
    };
}

/// Why the exact bounds on `x` at a point are what they are.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct XBounds {
    pub(crate) lo: f64,
    pub(crate) hi: f64,
    /// The row that set `hi` (`usize::MAX`: none).
    pub(crate) hi_row: usize,
    /// The row that set `lo`.
    pub(crate) lo_row: usize,
}

/// The linearised rows of every grid point, as half-planes, and the exact bounds on `x`.
#[derive(Debug, Clone, Default)]
pub(crate) struct Linearized {
    /// The active planes of every point, point after point.
    pub(crate) planes: Vec<Plane>,
    /// Where each point's planes start in `planes` (one more entry than points).
    pub(crate) start: Vec<usize>,
    pub(crate) bounds: Vec<XBounds>,
    /// Scratch of the pruning: which of a point's planes to keep.
    keep: Vec<bool>,
}

/// Linearises the `m` rows per point of `rows` (row-major, `K x m`): `scale[k]` multiplies
/// the limits of point `k`, `constraint_scale[owner[j]]` those of row `j`; `tangent[k]` is
/// the tangent point of the `sqrt(x)` terms at point `k` (`None`: the first, optimistic pass
/// that drops the harmful `sqrt(x)` terms).
pub(crate) fn linearize(
    rows: &[Row],
    m: usize,
    owner: &[usize],
    scale: &[f64],
    constraint_scale: &[f64],
    tangent: Option<&[f64]>,
    out: &mut Linearized,
) {
    let points = scale.len();
    out.planes.clear();
    out.start.clear();
    out.bounds.clear();
    out.bounds.resize(
        points,
        XBounds {
            lo: 0.0,
            hi: f64::INFINITY,
            hi_row: usize::MAX,
            lo_row: usize::MAX,
        },
    );
    for k in 0..points {
        let point_rows = &rows[k * m..(k + 1) * m];
        let bounds = &mut out.bounds[k];
        // Exact bounds on x first (rows without u): they also give the chords' range.
        for (j, row) in point_rows.iter().enumerate() {
            if row.u.abs() > 0.0 || !row.is_active() {
                continue;
            }
            let row = row.scaled(scale[k] * constraint_scale[owner[j]]);
            if row.x.abs() > 0.0 && row.sqrt_x.abs() > 0.0 {
                continue; // mixed: a half-plane after linearisation, below
            }
            x_bound(&row, j, bounds);
        }
        // Chords of a helpful sqrt(x) term need a finite range of x: where no exact bound
        // gives one, the point's maximum velocity curve does (no feasible x lies above it, so
        // bounding x by it cuts nothing).
        let helpful = point_rows.iter().any(|r| {
            r.is_active()
                && r.sqrt_x.abs() > 0.0
                && (r.u.abs() > 0.0 || r.x.abs() > 0.0)
                && ((r.sqrt_x < 0.0 && r.upper.is_finite())
                    || (r.sqrt_x > 0.0 && r.lower.is_finite()))
        });
        if helpful && !bounds.hi.is_finite() {
            let factor = |j: usize| scale[k] * constraint_scale[owner[j]];
            let mvc = maximum_speed(
                point_rows
                    .iter()
                    .enumerate()
                    .map(|(j, r)| r.scaled(factor(j))),
            );
            if mvc.is_finite() && mvc > 0.0 {
                bounds.hi = mvc;
            }
        }
        let chord_max = bounds.hi;
        out.start.push(out.planes.len());
        let mut scratch = [Plane::NONE; SLOTS];
        for (j, row) in point_rows.iter().enumerate() {
            if !row.is_active() {
                continue;
            }
            let mixed = row.x.abs() > 0.0 && row.sqrt_x.abs() > 0.0;
            let pure = row.u.abs() <= 0.0 && !mixed;
            if pure {
                continue;
            }
            let row = row.scaled(scale[k] * constraint_scale[owner[j]]);
            let x0 = tangent.map(|t| t[k]);
            if row.upper.is_finite() {
                let n = side(
                    row.u,
                    row.x,
                    row.sqrt_x,
                    row.upper - row.offset,
                    x0,
                    chord_max,
                    &mut scratch,
                );
                out.planes.extend_from_slice(&scratch[..n]);
            }
            if row.lower.is_finite() {
                let n = side(
                    -row.u,
                    -row.x,
                    -row.sqrt_x,
                    row.offset - row.lower,
                    x0,
                    chord_max,
                    &mut scratch,
                );
                out.planes.extend_from_slice(&scratch[..n]);
            }
        }
        let first = out.start[k];
        let (lo, hi) = (bounds.lo.max(0.0), bounds.hi);
        prune(&mut out.planes, first, lo, hi, &mut out.keep);
    }
    out.start.push(out.planes.len());
}

/// Drops the planes of one point (`planes[first..]`) that never bind for `x` in `[lo, hi]`:
/// of the upper bounds `u <= alpha + beta x` only those on their lower envelope over the
/// interval, of the lower bounds only those on their upper envelope. The sets are equal, and
/// stay equal under the map `(u, x) -> (u, x + 2 Delta u)` of the interpolated constraints, so
/// the projections are exact; the Fourier-Motzkin step then pairs a few bounds, not all.
fn prune(planes: &mut Vec<Plane>, first: usize, lo: f64, hi: f64, keep: &mut Vec<bool>) {
    let count = planes.len() - first;
    if count < 3 || lo > hi || !lo.is_finite() {
        return;
    }
    keep.clear();
    keep.resize(count, false);
    for upper in [true, false] {
        // Lines y = alpha + beta x, negated for the lower bounds (so: a lower envelope).
        let line = |p: &Plane| -> Option<(f64, f64)> {
            let ok = if upper { p.a > 0.0 } else { p.a < 0.0 };
            ok.then(|| {
                let (alpha, beta) = (p.g / p.a, -p.b / p.a);
                if upper {
                    (alpha, beta)
                } else {
                    (-alpha, -beta)
                }
            })
        };
        let group = &planes[first..];
        // The lowest line at x = lo (ties: the smallest slope, which stays lowest).
        let mut current = None;
        let mut best = (f64::INFINITY, f64::INFINITY);
        for (j, p) in group.iter().enumerate() {
            if let Some((alpha, beta)) = line(p) {
                let value = alpha + beta * lo;
                if value < best.0 || (value <= best.0 && beta < best.1) {
                    best = (value, beta);
                    current = Some(j);
                }
            }
        }
        let mut x = lo;
        while let Some(c) = current {
            if keep[c] {
                break;
            }
            keep[c] = true;
            let (ac, bc) = line(&group[c]).unwrap_or((0.0, 0.0));
            // The next line to cross below it: smaller slope, first crossing after x.
            let mut next = None;
            let mut at = (hi, f64::INFINITY);
            for (j, p) in group.iter().enumerate() {
                if let Some((alpha, beta)) = line(p)
                    && beta < bc
                {
                    let cross = (alpha - ac) / (bc - beta);
                    let cross = cross.max(x);
                    if cross < at.0 || (cross <= at.0 && beta < at.1) {
                        at = (cross, beta);
                        next = Some(j);
                    }
                }
            }
            if next.is_some() && at.0 <= hi {
                x = at.0;
            }
            current = next;
        }
    }
    // Planes without u (bounds on x) are always kept.
    let mut write = first;
    for j in 0..count {
        let p = planes[first + j];
        if keep[j] || p.a.abs() <= 0.0 {
            planes[write] = p;
            write += 1;
        }
    }
    planes.truncate(write);
}

/// Half-planes per side of a row: one, or up to this many chords of a helpful `sqrt(x)`.
const SLOTS: usize = 4;

/// `a u + b x + c sqrt(x) <= g` as half-planes inside it (module documentation), written
/// into `out`; returns how many.
///
/// `c > 0` (the term makes the row harder): the tangent of `sqrt` at `x0` lies above it, so
/// `a u + (b + c / (2 sqrt(x0))) x <= g - c sqrt(x0) / 2` implies the row.
/// `c < 0` (the term helps): on `[0, X]` the piecewise-linear interpolant of `sqrt` through
/// `0, 0.8 x0, x0, 1.25 x0, X` lies below it (concavity), so the chords' half-planes together
/// with `x <= X` imply the row; the interpolant is exact at `x0` and its slopes next to `x0`
/// are within 6 % of the derivative, so that the re-linearisation can move past `x0`.
#[inline]
fn side(
    a: f64,
    b: f64,
    c: f64,
    g: f64,
    tangent: Option<f64>,
    chord_max: f64,
    out: &mut [Plane; SLOTS],
) -> usize {
    if c > 0.0 {
        out[0] = match tangent {
            Some(x0) => {
                let r = x0.sqrt();
                Plane {
                    a,
                    b: b + c / (2.0 * r),
                    g: g - 0.5 * c * r,
                }
            }
            None => Plane { a, b, g },
        };
        1
    } else if c < 0.0 && chord_max.is_finite() && chord_max > 0.0 {
        let x_max = chord_max;
        let centre = tangent.unwrap_or(x_max / 16.0).clamp(0.0, x_max);
        let mut knots = [0.0, 0.8 * centre, centre, (1.25 * centre).min(x_max), x_max];
        knots.sort_by(f64::total_cmp);
        let mut slot = 0;
        for pair in knots.windows(2) {
            let (xa, xb) = (pair[0], pair[1]);
            if xb <= xa || slot == out.len() {
                continue;
            }
            let (ra, rb) = (xa.sqrt(), xb.sqrt());
            let slope = 1.0 / (ra + rb);
            // sqrt(x) >= ra + slope (x - xa) on [xa, xb]; c < 0 turns it into an upper bound.
            out[slot] = Plane {
                a,
                b: b + c * slope,
                g: g - c * (ra - slope * xa),
            };
            slot += 1;
        }
        slot
    } else {
        out[0] = Plane { a, b, g };
        1
    }
}

/// The bounds on `x` of a row without `u` and with only one of the `x`, `sqrt(x)` terms.
fn x_bound(row: &Row, j: usize, bounds: &mut XBounds) {
    let (lower, upper) = (row.lower - row.offset, row.upper - row.offset);
    let mut tighten_hi = |hi: f64| {
        if hi < bounds.hi {
            bounds.hi = hi;
            bounds.hi_row = j;
        }
    };
    // v in [lower, upper] with v = b x (b != 0) or v = c sqrt(x) (c != 0), x >= 0.
    let (coefficient, root) = if row.x.abs() > 0.0 {
        (row.x, false)
    } else if row.sqrt_x.abs() > 0.0 {
        (row.sqrt_x, true)
    } else {
        // Constant row: broken at rest if its offset is out of bounds (checked before).
        if lower > 0.0 || upper < 0.0 {
            tighten_hi(-1.0);
        }
        return;
    };
    // y = x (or sqrt(x)) in [y_lo, y_hi].
    let (y_lo, y_hi) = if coefficient > 0.0 {
        (lower / coefficient, upper / coefficient)
    } else {
        (upper / coefficient, lower / coefficient)
    };
    let map = |y: f64| {
        if root {
            if y < 0.0 { y } else { y * y }
        } else {
            y
        }
    };
    if y_hi.is_finite() {
        tighten_hi(map(y_hi));
    }
    if y_lo.is_finite() && y_lo > 0.0 {
        let lo = map(y_lo);
        if lo > bounds.lo {
            bounds.lo = lo;
            bounds.lo_row = j;
        }
    }
}

/// Boundary conditions of the path speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Ends {
    /// Start and end at rest.
    Rest,
    /// `x_0 = x_N`, as large as possible.
    Periodic,
}

/// A solved profile: `x_k` at the grid points and `u_k` on the segments.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct Profile {
    pub(crate) x: Vec<f64>,
    pub(crate) u: Vec<f64>,
    pub(crate) lo: Vec<f64>,
    pub(crate) hi: Vec<f64>,
}

/// Why a solve failed, by grid point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Failure {
    /// The controllable set of point `k` is empty.
    Empty(usize),
    /// Nothing bounds the path speed at point `k`.
    Unbounded(usize),
}

/// Reusable buffers of the solver (no allocation once warm).
#[derive(Debug, Clone, Default)]
pub(crate) struct Workspace {
    uppers: Vec<(f64, f64)>,
    lowers: Vec<(f64, f64)>,
    /// The bounds of every segment from the last backward pass, for the forward pass.
    cached_uppers: Vec<(f64, f64)>,
    cached_lowers: Vec<(f64, f64)>,
    /// `(uppers start, uppers end, lowers start, lowers end)` per segment.
    ranges: Vec<[usize; 4]>,
}

/// Largest relative roundoff accepted between bounds.
const SLACK: f64 = 1e-12;

impl Workspace {
    /// The `u` bounds of segment `k` (points `k` and `k+1`, interpolated) into the buffers,
    /// and the `x` bounds from planes without `u`.
    #[inline]
    fn segment(&mut self, lin: &Linearized, k: usize, delta: f64, next: (f64, f64)) -> (f64, f64) {
        self.uppers.clear();
        self.lowers.clear();
        let b = &lin.bounds[k];
        let (mut x_lo, mut x_hi) = (b.lo.max(0.0), b.hi);
        let mut add = |a: f64,
                       bx: f64,
                       g: f64,
                       uppers: &mut Vec<(f64, f64)>,
                       lowers: &mut Vec<(f64, f64)>| {
            if a > 0.0 {
                uppers.push((g / a, -bx / a));
            } else if a < 0.0 {
                lowers.push((g / a, -bx / a));
            } else if bx > 0.0 {
                x_hi = x_hi.min(g / bx);
            } else if bx < 0.0 {
                x_lo = x_lo.max(g / bx);
            } else if g < 0.0 {
                x_hi = -1.0;
            }
        };
        for p in &lin.planes[lin.start[k]..lin.start[k + 1]] {
            if p.g.is_finite() {
                add(p.a, p.b, p.g, &mut self.uppers, &mut self.lowers);
            }
        }
        // Point k+1 at x + 2 delta u: a u + b (x + 2 delta u) <= g.
        for p in &lin.planes[lin.start[k + 1]..lin.start[k + 2]] {
            if p.g.is_finite() {
                add(
                    p.a + 2.0 * delta * p.b,
                    p.b,
                    p.g,
                    &mut self.uppers,
                    &mut self.lowers,
                );
            }
        }
        let (lo_next, hi_next) = next;
        if hi_next.is_finite() {
            self.uppers
                .push((hi_next / (2.0 * delta), -1.0 / (2.0 * delta)));
        }
        self.lowers
            .push((lo_next / (2.0 * delta), -1.0 / (2.0 * delta)));
        (x_lo, x_hi)
    }

    /// The interval of `x` for which some `u` meets every bound (Fourier-Motzkin).
    #[inline]
    fn project(&self, mut x_lo: f64, mut x_hi: f64) -> (f64, f64) {
        for &(alpha, beta) in &self.uppers {
            for &(gamma, delta) in &self.lowers {
                // gamma + delta x <= alpha + beta x  <=>  (delta - beta) x <= alpha - gamma
                let coef = delta - beta;
                let rhs = alpha - gamma;
                let scale = delta.abs() + beta.abs();
                if coef > SLACK * scale {
                    x_hi = x_hi.min(rhs / coef);
                } else if coef < -SLACK * scale {
                    x_lo = x_lo.max(rhs / coef);
                } else if rhs < -SLACK * (alpha.abs() + gamma.abs()) {
                    return (1.0, 0.0);
                }
            }
        }
        (x_lo, x_hi)
    }

    /// `(u_lo, u_hi)` at `x` on segment `k` of the last backward pass.
    #[inline]
    fn u_range(&self, k: usize, x: f64) -> (f64, f64) {
        let [u0, u1, l0, l1] = self.ranges[k];
        let hi = self.cached_uppers[u0..u1]
            .iter()
            .fold(f64::INFINITY, |m, &(a, b)| m.min(a + b * x));
        let lo = self.cached_lowers[l0..l1]
            .iter()
            .fold(f64::NEG_INFINITY, |m, &(a, b)| m.max(a + b * x));
        (lo, hi)
    }

    /// Keeps the bounds of segment `k` for the forward pass.
    #[inline]
    fn keep(&mut self, k: usize) {
        let (u0, l0) = (self.cached_uppers.len(), self.cached_lowers.len());
        self.cached_uppers.extend_from_slice(&self.uppers);
        self.cached_lowers.extend_from_slice(&self.lowers);
        self.ranges[k] = [u0, self.cached_uppers.len(), l0, self.cached_lowers.len()];
    }
}

/// TOPP-RA on the grid `s` with the linearised constraints `lin`.
pub(crate) fn solve(
    s: &[f64],
    lin: &Linearized,
    ends: Ends,
    work: &mut Workspace,
    out: &mut Profile,
) -> Result<(), Failure> {
    let n = s.len();
    out.x.clear();
    out.x.resize(n, 0.0);
    out.u.clear();
    out.u.resize(n - 1, 0.0);
    out.lo.clear();
    out.lo.resize(n, 0.0);
    out.hi.clear();
    out.hi.resize(n, 0.0);
    let last = &lin.bounds[n - 1];
    let (mut end_lo, mut end_hi) = match ends {
        Ends::Rest => (0.0, 0.0),
        Ends::Periodic => (last.lo.max(0.0), last.hi),
    };
    if end_hi < end_lo {
        return Err(Failure::Empty(n - 1));
    }
    let mut laps = 0;
    loop {
        out.lo[n - 1] = end_lo;
        out.hi[n - 1] = end_hi;
        backward(s, lin, work, out)?;
        if ends == Ends::Rest {
            break;
        }
        // Around the loop: point 0 is point N.
        let (lo, hi) = (out.lo[0].max(end_lo), out.hi[0].min(end_hi));
        laps += 1;
        let settled = (hi - end_hi).abs() <= 1e-13 * end_hi.abs()
            && (lo - end_lo).abs() <= 1e-13 * (1.0 + lo.abs());
        end_lo = lo;
        end_hi = hi;
        if settled || laps >= 200 {
            break;
        }
        if end_hi < end_lo {
            return Err(Failure::Empty(0));
        }
    }
    if !out.hi[0].is_finite() {
        return Err(Failure::Unbounded(0));
    }
    let mut x0 = match ends {
        Ends::Rest => 0.0,
        Ends::Periodic => out.hi[0],
    };
    for _ in 0..200 {
        forward(s, x0, work, out)?;
        if ends == Ends::Rest {
            break;
        }
        let x_end = out.x[n - 1];
        if (x_end - x0).abs() <= 1e-12 * x0 {
            break;
        }
        x0 = x_end;
    }
    if ends == Ends::Periodic {
        // Close the loop exactly (the last change was below 1e-12 relative).
        out.x[n - 1] = out.x[0];
        let delta = s[n - 1] - s[n - 2];
        out.u[n - 2] = (out.x[n - 1] - out.x[n - 2]) / (2.0 * delta);
    }
    Ok(())
}

fn backward(
    s: &[f64],
    lin: &Linearized,
    work: &mut Workspace,
    out: &mut Profile,
) -> Result<(), Failure> {
    let n = s.len();
    work.cached_uppers.clear();
    work.cached_lowers.clear();
    work.ranges.clear();
    work.ranges.resize(n - 1, [0; 4]);
    for k in (0..n - 1).rev() {
        let delta = s[k + 1] - s[k];
        let (x_lo, x_hi) = work.segment(lin, k, delta, (out.lo[k + 1], out.hi[k + 1]));
        work.keep(k);
        let (lo, hi) = work.project(x_lo, x_hi);
        let tolerance = SLACK * hi.abs().max(lo.abs()).max(f64::MIN_POSITIVE);
        if lo > hi + tolerance || lo.is_nan() || hi.is_nan() {
            return Err(Failure::Empty(k));
        }
        if k > 0 && !hi.is_finite() {
            return Err(Failure::Unbounded(k));
        }
        out.lo[k] = lo.max(0.0);
        out.hi[k] = hi.max(out.lo[k]);
    }
    Ok(())
}

fn forward(s: &[f64], x0: f64, work: &mut Workspace, out: &mut Profile) -> Result<(), Failure> {
    let n = s.len();
    out.x[0] = x0.clamp(out.lo[0], out.hi[0]);
    for k in 0..n - 1 {
        let delta = s[k + 1] - s[k];
        let x = out.x[k];
        let (u_lo, u_hi) = work.u_range(k, x);
        if !u_hi.is_finite() {
            return Err(Failure::Unbounded(k));
        }
        // The greedy choice; roundoff may put u_hi a hair below u_lo.
        let u = if u_hi >= u_lo {
            u_hi
        } else {
            0.5 * (u_hi + u_lo)
        };
        let next = (x + 2.0 * delta * u)
            .clamp(out.lo[k + 1], out.hi[k + 1])
            .max(0.0);
        out.x[k + 1] = next;
        out.u[k] = (next - x) / (2.0 * delta);
    }
    Ok(())
}

/// Duration of a profile: `sum 2 Delta_k / (sqrt(x_k) + sqrt(x_{k+1}))` (exact for a
/// constant `u` per segment). Infinite if the path speed vanishes on a whole segment.
pub(crate) fn duration(s: &[f64], x: &[f64]) -> f64 {
    s.windows(2)
        .zip(x.windows(2))
        .map(|(s, x)| 2.0 * (s[1] - s[0]) / (x[0].max(0.0).sqrt() + x[1].max(0.0).sqrt()))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A double integrator along s: |u| <= a, x <= v^2: the trapezoid, time L/v + v/a.
    fn double_integrator(n: usize, length: f64, v: f64, a: f64) -> (Vec<f64>, Linearized) {
        let s: Vec<f64> = (0..=n).map(|k| length * k as f64 / n as f64).collect();
        let rows: Vec<Row> = s
            .iter()
            .flat_map(|_| {
                [
                    Row {
                        sqrt_x: 1.0,
                        upper: v,
                        ..Row::INACTIVE
                    },
                    Row::symmetric(1.0, 0.0, 0.0, a),
                ]
            })
            .collect();
        let mut lin = Linearized::default();
        linearize(
            &rows,
            2,
            &[0, 1],
            &vec![1.0; n + 1],
            &[1.0, 1.0],
            None,
            &mut lin,
        );
        (s, lin)
    }

    #[test]
    fn trapezoid_and_triangle_converge_from_above() {
        let mut work = Workspace::default();
        let mut profile = Profile::default();
        for (v, expected) in [
            (0.5, 0.2 / 0.5 + 0.5 / 20.0),
            (10.0, 2.0 * (0.2f64 / 20.0).sqrt()),
        ] {
            for n in [7, 40, 1000] {
                let (s, lin) = double_integrator(n, 0.2, v, 20.0);
                solve(&s, &lin, Ends::Rest, &mut work, &mut profile).unwrap();
                let t = duration(&s, &profile.x);
                // The grid resolves the switches only to within a few intervals: at most a few
                // intervals' time at the peak speed.
                let peak = v.min((20.0f64 * 0.2).sqrt());
                let tolerance = 4.0 * (0.2 / n as f64) / peak;
                assert!(t - expected <= tolerance, "v {v} n {n}: {t} vs {expected}");
                assert!(
                    t >= expected * (1.0 - 1e-12),
                    "never faster than the optimum"
                );
                for u in &profile.u {
                    assert!(u.abs() <= 20.0 * (1.0 + 1e-12));
                }
                assert!(profile.x.iter().all(|x| *x <= v * v * (1.0 + 1e-12)));
            }
        }
    }

    #[global_allocator]
    static GLOBAL: flexprr_testkit::alloc::CountingAllocator =
        flexprr_testkit::alloc::CountingAllocator;

    #[test]
    fn a_warm_solve_allocates_nothing() {
        let (s, lin) = double_integrator(1000, 0.2, 0.5, 20.0);
        let mut work = Workspace::default();
        let mut profile = Profile::default();
        solve(&s, &lin, Ends::Rest, &mut work, &mut profile).unwrap();
        let (result, allocations) = flexprr_testkit::count_allocations(|| {
            solve(&s, &lin, Ends::Rest, &mut work, &mut profile)
        });
        assert!(result.is_ok());
        assert_eq!(allocations, 0);
        // Re-linearising into warm buffers allocates nothing either.
        let rows: Vec<Row> = vec![Row::symmetric(1.0, 0.5, 0.0, 3.0); 2 * 1001];
        let scale = vec![1.0; 1001];
        let mut out = Linearized::default();
        linearize(&rows, 2, &[0, 0], &scale, &[1.0], None, &mut out);
        let ((), allocations) = flexprr_testkit::count_allocations(|| {
            linearize(&rows, 2, &[0, 0], &scale, &[1.0], Some(&scale), &mut out);
        });
        assert_eq!(allocations, 0);
    }

    proptest::proptest! {
        /// Pruning keeps the feasible u-interval at every x of the range.
        #[test]
        fn pruning_keeps_the_feasible_set(
            raw in proptest::collection::vec((-2.0f64..2.0, -2.0f64..2.0, -2.0f64..2.0), 3..30),
            lo in 0.0f64..1.0, width in 0.0f64..5.0, probes in proptest::collection::vec(0.0f64..1.0, 20),
        ) {
            let planes: Vec<Plane> = raw.iter().map(|&(a, b, g)| Plane { a, b, g }).collect();
            let hi = lo + width;
            let mut pruned = planes.clone();
            let mut keep = Vec::new();
            prune(&mut pruned, 0, lo, hi, &mut keep);
            let range = |set: &[Plane], x: f64| {
                let mut r = (f64::NEG_INFINITY, f64::INFINITY);
                for p in set {
                    if p.a > 0.0 {
                        r.1 = r.1.min((p.g - p.b * x) / p.a);
                    } else if p.a < 0.0 {
                        r.0 = r.0.max((p.g - p.b * x) / p.a);
                    }
                }
                r
            };
            for w in probes {
                let x = lo + w * width;
                let (full, less) = (range(&planes, x), range(&pruned, x));
                let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * (1.0 + a.abs()) || (a.is_infinite() && b.is_infinite() && a.is_sign_positive() == b.is_sign_positive());
                proptest::prop_assert!(close(full.0, less.0) && close(full.1, less.1), "{full:?} vs {less:?} at {x}");
            }
        }
    }

    #[test]
    fn fourier_motzkin_projection_is_the_polygon_shadow() {
        // u <= 1 - x, u >= -1 + x/2  =>  -1 + x/2 <= 1 - x  <=>  x <= 4/3.
        let mut w = Workspace::default();
        w.uppers.push((1.0, -1.0));
        w.lowers.push((-1.0, 0.5));
        let (lo, hi) = w.project(0.0, f64::INFINITY);
        assert!(lo.abs() <= 0.0 && (hi - 4.0 / 3.0).abs() <= 1e-15);
        // Parallel and contradictory: u <= -1, u >= 1.
        w.uppers[0] = (-1.0, 0.0);
        w.lowers[0] = (1.0, 0.0);
        let (lo, hi) = w.project(0.0, 10.0);
        assert!(lo > hi);
    }
}
