//! Gauss-Legendre quadrature, computed (not tabulated), and composite rules on panels.
//!
//! Nodes are the roots of the Legendre polynomial `P_n`, found by Newton's method from
//! Tricomi's initial guess `x_i ~ cos(pi (i + 3/4) / (n + 1/2))`, with `P_n` and its
//! derivative evaluated by the three-term (Bonnet) recurrence
//! `(k + 1) P_{k+1} = (2k + 1) x P_k - k P_{k-1}`, `P_n' = n (x P_n - P_{n-1}) / (x^2 - 1)`.
//! The weights are `w_i = 2 / ((1 - x_i^2) P_n'(x_i)^2)` (Abramowitz & Stegun 25.4.29;
//! Press et al., *Numerical Recipes*, section 4.6). Only half the nodes are computed;
//! the other half are their mirror images, so the rule is exactly symmetric.
//! An `n`-point rule integrates polynomials of degree `<= 2n - 1` exactly.

use crate::BeamError;

/// Largest number of points accepted for one Gauss-Legendre rule.
pub const MAX_GAUSS_POINTS: usize = 2048;

/// An `n`-point Gauss-Legendre rule on the reference interval `[-1, 1]`.
#[derive(Debug, Clone, PartialEq)]
pub struct GaussLegendre {
    nodes: Vec<f64>,
    weights: Vec<f64>,
}

impl GaussLegendre {
    /// Computes the `points`-point rule (`1 <= points <= MAX_GAUSS_POINTS`).
    pub fn new(points: usize) -> Result<Self, BeamError> {
        if points == 0 || points > MAX_GAUSS_POINTS {
            return Err(BeamError::InvalidCount {
                name: "quadrature points",
                value: points,
                reason: "must be between 1 and 2048",
            });
        }
        let n = points;
        let nf = n as f64;
        let mut nodes = vec![0.0; n];
        let mut weights = vec![0.0; n];
        // Nodes in descending order x_0 > x_1 > ...; the mirror fills the rest.
        for i in 0..n.div_ceil(2) {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (nf + 0.5)).cos();
            let mut derivative = 0.0;
            let mut converged = false;
            for _ in 0..100 {
                let (p, dp) = legendre_with_derivative(n, x);
                derivative = dp;
                let step = p / dp;
                x -= step;
                if step.abs() <= 4.0 * f64::EPSILON * x.abs().max(1e-3) {
                    // One more evaluation of the derivative at the converged node.
                    derivative = legendre_with_derivative(n, x).1;
                    converged = true;
                    break;
                }
            }
            if !converged || !x.is_finite() {
                return Err(BeamError::QuadratureNode { points: n, node: i });
            }
            // The middle node of an odd rule is exactly zero.
            if n % 2 == 1 && i == n / 2 {
                x = 0.0;
                derivative = legendre_with_derivative(n, 0.0).1;
            }
            let weight = 2.0 / ((1.0 - x * x) * derivative * derivative);
            nodes[i] = -x;
            nodes[n - 1 - i] = x;
            weights[i] = weight;
            weights[n - 1 - i] = weight;
        }
        Ok(Self { nodes, weights })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Always false (a rule has at least one point).
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Nodes on `[-1, 1]`, ascending.
    pub fn nodes(&self) -> &[f64] {
        &self.nodes
    }

    /// Weights on `[-1, 1]` (they sum to 2).
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Nodes and weights mapped affinely to `[a, b]`, appended to `nodes` and `weights`.
    pub fn append_mapped(&self, a: f64, b: f64, nodes: &mut Vec<f64>, weights: &mut Vec<f64>) {
        let half = 0.5 * (b - a);
        let mid = 0.5 * (a + b);
        for (x, w) in self.nodes.iter().zip(&self.weights) {
            nodes.push(mid + half * x);
            weights.push(half * w);
        }
    }

    /// `int_a^b f(x) dx` by this rule.
    pub fn integrate(&self, a: f64, b: f64, mut f: impl FnMut(f64) -> f64) -> f64 {
        let half = 0.5 * (b - a);
        let mid = 0.5 * (a + b);
        let sum: f64 = self
            .nodes
            .iter()
            .zip(&self.weights)
            .map(|(x, w)| w * f(mid + half * x))
            .sum();
        half * sum
    }
}

/// `(P_n(x), P_n'(x))` by Bonnet's recurrence.
fn legendre_with_derivative(n: usize, x: f64) -> (f64, f64) {
    let mut p_prev = 1.0; // P_0
    let mut p = x; // P_1
    if n == 0 {
        return (1.0, 0.0);
    }
    for k in 1..n {
        let kf = k as f64;
        let p_next = ((2.0 * kf + 1.0) * x * p - kf * p_prev) / (kf + 1.0);
        p_prev = p;
        p = p_next;
    }
    let nf = n as f64;
    let dp = nf * (x * p - p_prev) / (x * x - 1.0);
    (p, dp)
}

/// A composite Gauss-Legendre rule on `[0, 1]`: the same `n`-point rule on every panel
/// between consecutive breakpoints. Integrands that are smooth on each panel but not
/// across breakpoints (finite elements, stepped sections) are integrated as accurately as
/// smooth ones; piecewise polynomials of degree `<= 2n - 1` exactly.
#[derive(Debug, Clone, PartialEq)]
pub struct CompositeRule {
    nodes: Vec<f64>,
    weights: Vec<f64>,
    points_per_panel: usize,
    panels: usize,
}

impl CompositeRule {
    /// `points_per_panel`-point Gauss rule on each panel of `[0, 1]` cut at `breakpoints`
    /// (interior points; unsorted, duplicates and points outside `(0, 1)` are ignored).
    pub fn new(points_per_panel: usize, breakpoints: &[f64]) -> Result<Self, BeamError> {
        let rule = GaussLegendre::new(points_per_panel)?;
        let edges = panel_edges(breakpoints)?;
        let mut nodes = Vec::with_capacity(points_per_panel * (edges.len() - 1));
        let mut weights = Vec::with_capacity(nodes.capacity());
        for pair in edges.windows(2) {
            rule.append_mapped(pair[0], pair[1], &mut nodes, &mut weights);
        }
        Ok(Self {
            nodes,
            weights,
            points_per_panel,
            panels: edges.len() - 1,
        })
    }

    /// All nodes on `[0, 1]`, ascending.
    pub fn nodes(&self) -> &[f64] {
        &self.nodes
    }

    /// All weights (they sum to 1).
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Points per panel.
    pub fn points_per_panel(&self) -> usize {
        self.points_per_panel
    }

    /// Number of panels.
    pub fn panels(&self) -> usize {
        self.panels
    }

    /// `int_0^1 f(xi) dxi` by this rule.
    pub fn integrate(&self, mut f: impl FnMut(f64) -> f64) -> f64 {
        self.nodes
            .iter()
            .zip(&self.weights)
            .map(|(x, w)| w * f(*x))
            .sum()
    }
}

/// Sorted panel edges `0 = e_0 < e_1 < ... < e_m = 1` from interior breakpoints.
pub(crate) fn panel_edges(breakpoints: &[f64]) -> Result<Vec<f64>, BeamError> {
    let mut edges = Vec::with_capacity(breakpoints.len() + 2);
    edges.push(0.0);
    for &b in breakpoints {
        if !b.is_finite() {
            return Err(BeamError::InvalidParameter {
                name: "breakpoint",
                value: b,
                reason: "must be finite",
            });
        }
        if b > 1e-14 && b < 1.0 - 1e-14 {
            edges.push(b);
        }
    }
    edges.push(1.0);
    edges.sort_by(f64::total_cmp);
    edges.dedup_by(|a, b| (*a - *b).abs() <= 1e-14);
    Ok(edges)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_point_rule_is_the_textbook_one() {
        let rule = GaussLegendre::new(2).unwrap();
        let node = 1.0 / 3f64.sqrt();
        assert!((rule.nodes()[1] - node).abs() < 1e-15);
        assert!((rule.weights()[0] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn edges_sorted_and_deduplicated() {
        let e = panel_edges(&[0.5, 0.25, 0.5, 1.0, 0.0]).unwrap();
        assert_eq!(e.len(), 4);
        assert!((e[1] - 0.25).abs() < 1e-15 && (e[2] - 0.5).abs() < 1e-15);
    }
}
