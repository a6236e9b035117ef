//! Derivative-free minimisers for the orientation search (docs/planning.md, "The platform's
//! orientation"): Brent's method in one variable and Nelder-Mead in several. Both accept an
//! objective that is `+inf` where the design is infeasible (an unreachable pose, a limit no
//! timing can meet) and never evaluate it outside the given bracket (Brent) or at `NaN`.

/// Brent's minimisation of `f` on `[a, b]` (R. P. Brent, "Algorithms for Minimization without
/// Derivatives", 1973, ch. 5): golden-section steps, parabolic interpolation through the
/// three best points when it is safe, to the absolute tolerance `tol` in `x`, at most
/// `max_evaluations` evaluations. A parabola is never fitted through a non-finite value (the
/// step is then a golden section). Returns `(x, f(x), evaluations)`; the ends `a`, `b` are
/// not evaluated (the caller compares them).
pub(crate) fn brent(
    f: &mut dyn FnMut(f64) -> f64,
    a: f64,
    b: f64,
    tol: f64,
    max_evaluations: usize,
) -> (f64, f64, usize) {
    let golden = 0.5 * (3.0 - 5f64.sqrt());
    let (mut a, mut b) = (a.min(b), a.max(b));
    let mut x = a + golden * (b - a);
    let (mut w, mut v) = (x, x);
    let mut fx = f(x);
    let (mut fw, mut fv) = (fx, fx);
    let mut evaluations = 1;
    let (mut d, mut e) = (0.0f64, 0.0f64);
    let same = |p: f64, q: f64| p.to_bits() == q.to_bits();
    while evaluations < max_evaluations {
        let m = 0.5 * (a + b);
        let tol1 = f64::EPSILON.sqrt() * x.abs() * 1e-4 + tol / 3.0;
        let tol2 = 2.0 * tol1;
        if (x - m).abs() <= tol2 - 0.5 * (b - a) {
            break;
        }
        let mut golden_step = true;
        if e.abs() > tol1 && fx.is_finite() && fw.is_finite() && fv.is_finite() {
            let r = (x - w) * (fx - fv);
            let mut q = (x - v) * (fx - fw);
            let mut p = (x - v) * q - (x - w) * r;
            q = 2.0 * (q - r);
            if q > 0.0 {
                p = -p;
            } else {
                q = -q;
            }
            let previous = e;
            if p.abs() < (0.5 * q * previous).abs() && p > q * (a - x) && p < q * (b - x) {
                e = d;
                d = p / q;
                let u = x + d;
                if u - a < tol2 || b - u < tol2 {
                    d = if x < m { tol1 } else { -tol1 };
                }
                golden_step = false;
            }
        }
        if golden_step {
            e = if x < m { b - x } else { a - x };
            d = golden * e;
        }
        let u = x + if d.abs() >= tol1 {
            d
        } else if d > 0.0 {
            tol1
        } else {
            -tol1
        };
        let fu = f(u);
        evaluations += 1;
        if fu <= fx {
            if u < x {
                b = x;
            } else {
                a = x;
            }
            (v, fv) = (w, fw);
            (w, fw) = (x, fx);
            (x, fx) = (u, fu);
        } else {
            if u < x {
                a = u;
            } else {
                b = u;
            }
            if fu <= fw || same(w, x) {
                (v, fv) = (w, fw);
                (w, fw) = (u, fu);
            } else if fu <= fv || same(v, x) || same(v, w) {
                (v, fv) = (u, fu);
            }
        }
    }
    (x, fx, evaluations)
}

/// Settings of [`nelder_mead`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct SimplexSettings {
    /// Most objective evaluations.
    pub max_evaluations: usize,
    /// Stop when the values at the simplex's vertices differ by at most this, relative to the
    /// best value...
    pub value_tolerance: f64,
    /// ...and the simplex is at most this wide in every coordinate.
    pub size_tolerance: f64,
}

/// The result of [`nelder_mead`].
#[derive(Debug, Clone)]
pub(crate) struct SimplexMinimum {
    /// The best point found.
    pub x: Vec<f64>,
    /// Its value.
    pub value: f64,
    /// Evaluations made.
    pub evaluations: usize,
    /// Whether the tolerances were met (otherwise the evaluation budget ran out).
    pub converged: bool,
    /// Restarts made after a convergence (each from the best point with a fresh simplex).
    pub restarts: usize,
}

/// Nelder-Mead minimisation of `f` from `start` with initial steps `step` (J. A. Nelder,
/// R. Mead, Comput. J. 7, 1965; the ordering and tie rules of J. C. Lagarias et al., SIAM J.
/// Optim. 9, 1998; the dimension-adaptive coefficients of F. Gao, L. Han, Comput. Optim.
/// Appl. 51, 2012: reflection 1, expansion `1 + 2/n`, contraction `3/4 - 1/(2n)`, shrink
/// `1 - 1/n`). After the tolerances are met it restarts from the best point with half the
/// initial steps, and stops when a restart no longer improves the value by more than the
/// value tolerance (a simplex can collapse away from a minimum). The best value never
/// increases: the result is never worse than `start`. A local method.
pub(crate) fn nelder_mead(
    f: &mut dyn FnMut(&[f64]) -> f64,
    start: &[f64],
    step: &[f64],
    settings: SimplexSettings,
) -> SimplexMinimum {
    let n = start.len();
    let coefficients = Coefficients::of(n);
    let mut f = Counted { f, evaluations: 0 };
    let mut best_x = start.to_vec();
    let mut best = f.eval(&best_x);
    let mut scale = 1.0;
    let mut converged = false;
    let mut restarts = 0;
    // Rounds from a fresh simplex around the best point, while the budget lasts.
    while let Some(mut simplex) =
        Simplex::around(&best_x, best, scale, step, &mut f, settings.max_evaluations)
    {
        let round_start = best;
        converged = simplex.minimise(&mut f, coefficients, settings);
        let (k, value) = simplex.best();
        if value < best {
            best = value;
            best_x.clone_from(&simplex.points[k]);
        }
        let improved = round_start - best > settings.value_tolerance * best.abs();
        if !converged || f.evaluations >= settings.max_evaluations || (restarts > 0 && !improved) {
            break;
        }
        restarts += 1;
        scale *= 0.5;
    }
    SimplexMinimum {
        x: best_x,
        value: best,
        evaluations: f.evaluations,
        converged,
        restarts,
    }
}

/// The objective with a count of its evaluations; NaN reads as infinity (a point to leave).
struct Counted<'f> {
    f: &'f mut dyn FnMut(&[f64]) -> f64,
    evaluations: usize,
}

impl Counted<'_> {
    fn eval(&mut self, x: &[f64]) -> f64 {
        self.evaluations += 1;
        let v = (self.f)(x);
        if v.is_nan() { f64::INFINITY } else { v }
    }
}

/// Expansion, contraction and shrink coefficients (Gao and Han's for `n >= 2`, the
/// classical 2, 1/2, 1/2 in one dimension).
#[derive(Clone, Copy)]
struct Coefficients {
    expand: f64,
    contract: f64,
    shrink: f64,
}

impl Coefficients {
    fn of(n: usize) -> Self {
        let nf = n as f64;
        let (expand, contract, shrink) = if n >= 2 {
            (1.0 + 2.0 / nf, 0.75 - 0.5 / nf, 1.0 - 1.0 / nf)
        } else {
            (2.0, 0.5, 0.5)
        };
        Self {
            expand,
            contract,
            shrink,
        }
    }
}

/// The `n + 1` vertices of a simplex and their values.
struct Simplex {
    points: Vec<Vec<f64>>,
    values: Vec<f64>,
}

impl Simplex {
    /// A fresh simplex around `x` (value `fx`): `x` and `x + scale step_j e_j`; `None` when
    /// the evaluation budget runs out first.
    fn around(
        x: &[f64],
        fx: f64,
        scale: f64,
        step: &[f64],
        f: &mut Counted<'_>,
        max_evaluations: usize,
    ) -> Option<Self> {
        let n = x.len();
        let mut points: Vec<Vec<f64>> = vec![x.to_vec()];
        let mut values = vec![fx];
        for j in 0..n {
            if f.evaluations >= max_evaluations {
                break;
            }
            let mut p = x.to_vec();
            p[j] += scale * step[j];
            values.push(f.eval(&p));
            points.push(p);
        }
        (points.len() == n + 1).then_some(Self { points, values })
    }

    /// Orders the vertices by value (stable: ties keep the older vertex first).
    fn order(&mut self) {
        let mut order: Vec<usize> = (0..self.values.len()).collect();
        order.sort_by(|&i, &j| self.values[i].total_cmp(&self.values[j]));
        self.points = order.iter().map(|&i| self.points[i].clone()).collect();
        self.values = order.iter().map(|&i| self.values[i]).collect();
    }

    /// Whether the ordered simplex meets both tolerances: its values spread by at most the
    /// value tolerance relative to the best, and it is at most the size tolerance wide in
    /// every coordinate.
    fn converged(&self, settings: SimplexSettings) -> bool {
        let n = self.points.len() - 1;
        let (low, high) = (self.values[0], self.values[n]);
        let width = (0..n)
            .map(|j| {
                let (lo, hi) = self
                    .points
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |a, p| {
                        (a.0.min(p[j]), a.1.max(p[j]))
                    });
                hi - lo
            })
            .fold(0.0f64, f64::max);
        high - low <= settings.value_tolerance * low.abs().max(f64::MIN_POSITIVE)
            && width <= settings.size_tolerance
    }

    /// Nelder-Mead steps until the tolerances are met (`true`) or the budget runs out.
    fn minimise(
        &mut self,
        f: &mut Counted<'_>,
        c: Coefficients,
        settings: SimplexSettings,
    ) -> bool {
        let n = self.points.len() - 1;
        let mut centroid = vec![0.0; n];
        let mut trial = vec![0.0; n];
        let mut second = vec![0.0; n];
        while f.evaluations < settings.max_evaluations {
            self.order();
            if self.converged(settings) {
                return true;
            }
            self.step(f, c, settings, [&mut centroid, &mut trial, &mut second]);
        }
        false
    }

    /// One step on the ordered simplex: reflect the worst vertex through the centroid of
    /// the others, then expand, accept, contract (outside or inside) or shrink towards the
    /// best vertex.
    fn step(
        &mut self,
        f: &mut Counted<'_>,
        c: Coefficients,
        settings: SimplexSettings,
        [centroid, trial, second]: [&mut Vec<f64>; 3],
    ) {
        let n = self.points.len() - 1;
        let nf = n as f64;
        let (points, values) = (&mut self.points, &mut self.values);
        for (j, x) in centroid.iter_mut().enumerate() {
            *x = points[..n].iter().map(|p| p[j]).sum::<f64>() / nf;
        }
        let along = |t: f64, points: &[Vec<f64>], out: &mut Vec<f64>| {
            for j in 0..n {
                out[j] = centroid[j] + t * (points[n][j] - centroid[j]);
            }
        };
        along(-1.0, points, trial);
        let reflected = f.eval(trial);
        if reflected < values[0] {
            along(-c.expand, points, second);
            let expanded = f.eval(second);
            if expanded < reflected {
                points[n].clone_from(second);
                values[n] = expanded;
            } else {
                points[n].clone_from(trial);
                values[n] = reflected;
            }
            return;
        }
        if reflected < values[n - 1] {
            points[n].clone_from(trial);
            values[n] = reflected;
            return;
        }
        // Contraction: outside when the reflection beats the worst, inside otherwise.
        let outside = reflected < values[n];
        along(
            if outside { -c.contract } else { c.contract },
            points,
            second,
        );
        let contracted = f.eval(second);
        if (outside && contracted <= reflected) || (!outside && contracted < values[n]) {
            points[n].clone_from(second);
            values[n] = contracted;
            return;
        }
        // Shrink towards the best vertex.
        let (first, rest) = points.split_at_mut(1);
        for (k, point) in rest.iter_mut().enumerate() {
            if f.evaluations >= settings.max_evaluations {
                break;
            }
            for (x, b) in point.iter_mut().zip(&first[0]) {
                *x = b + c.shrink * (*x - b);
            }
            values[k + 1] = f.eval(point);
        }
    }

    /// The best vertex and its value (the first of equal values).
    fn best(&self) -> (usize, f64) {
        self.values.iter().enumerate().fold(
            (0, f64::INFINITY),
            |a, (k, v)| if *v < a.1 { (k, *v) } else { a },
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn brent_finds_smooth_kinked_and_boundary_minima() {
        let (x, fx, n) = brent(&mut |x| (x - 2.0) * (x - 2.0) + 1.0, 0.0, 5.0, 1e-8, 100);
        assert!(
            (x - 2.0).abs() <= 1e-7 && (fx - 1.0).abs() <= 1e-14,
            "{x} {fx} {n}"
        );
        // Fewer than golden sections alone would need (log(5e8) / log(1.618) = 42).
        assert!(n < 30, "{n}");
        let (x, _, _) = brent(&mut |x| (x - 1.3).abs(), 0.0, 5.0, 1e-8, 200);
        assert!((x - 1.3).abs() <= 1e-7, "{x}");
        // Infeasible below 1: the minimum sits on the edge of the feasible set.
        let (x, fx, _) = brent(
            &mut |x| {
                if x < 1.0 {
                    f64::INFINITY
                } else {
                    (x - 0.5).powi(2)
                }
            },
            0.0,
            3.0,
            1e-8,
            200,
        );
        assert!(
            (x - 1.0).abs() <= 1e-7 && (fx - 0.25).abs() <= 1e-7,
            "{x} {fx}"
        );
    }

    #[test]
    fn nelder_mead_minimises_rosenbrock_and_a_quadratic_with_a_barrier() {
        let settings = SimplexSettings {
            max_evaluations: 2000,
            value_tolerance: 1e-14,
            size_tolerance: 1e-8,
        };
        let mut rosenbrock =
            |x: &[f64]| 100.0 * (x[1] - x[0] * x[0]).powi(2) + (1.0 - x[0]).powi(2);
        let found = nelder_mead(&mut rosenbrock, &[-1.2, 1.0], &[0.1, 0.1], settings);
        assert!(found.converged, "{found:?}");
        assert!(
            (found.x[0] - 1.0).abs() <= 1e-5 && (found.x[1] - 1.0).abs() <= 1e-5,
            "{found:?}"
        );
        // A 4-d quadratic, infinite outside x_0 >= 0.5: the minimum (0.5, 1, -2, 3) is on the
        // barrier.
        let centre = [0.0, 1.0, -2.0, 3.0];
        let mut quadratic = |x: &[f64]| {
            if x[0] < 0.5 {
                return f64::INFINITY;
            }
            x.iter()
                .zip(&centre)
                .map(|(a, c)| (a - c) * (a - c))
                .sum::<f64>()
        };
        let found = nelder_mead(&mut quadratic, &[1.0, 0.0, 0.0, 0.0], &[0.2; 4], settings);
        let exact = [0.5, 1.0, -2.0, 3.0];
        for (a, b) in found.x.iter().zip(&exact) {
            assert!((a - b).abs() <= 1e-4, "{found:?}");
        }
        // Never worse than the start, even with a tiny budget.
        let start = [3.0, 3.0];
        let value = rosenbrock(&start);
        let short = nelder_mead(
            &mut rosenbrock,
            &start,
            &[1.0, 1.0],
            SimplexSettings {
                max_evaluations: 5,
                ..settings
            },
        );
        assert!(short.value <= value && !short.converged && short.evaluations <= 5);
    }
}
