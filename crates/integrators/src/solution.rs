//! Results of an integration.

/// Work counters, the same for every method (fields a method does not use stay zero).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Stats {
    /// Accepted steps.
    pub accepted_steps: usize,
    /// Rejected steps (error test or Newton failure).
    pub rejected_steps: usize,
    /// Right-hand-side evaluations (including those of differenced Jacobians).
    pub rhs_evaluations: usize,
    /// Jacobian evaluations.
    pub jacobian_evaluations: usize,
    /// LU factorizations of the iteration matrix.
    pub lu_decompositions: usize,
    /// Newton iterations.
    pub newton_iterations: usize,
    /// `orders[k]` counts accepted steps taken with order `k` (index 0 unused).
    pub orders: Vec<usize>,
    /// Time at which the method found the problem stiff, if it checks and did.
    pub stiffness_detected_at: Option<f64>,
    /// Segments integrated: stepper starts, one more per stop time crossed (see
    /// [`crate::Integrator::solve_observed`]); 0 when the statistics are one stepper's.
    pub segments: usize,
}

impl Stats {
    /// Records an accepted step of order `order`.
    pub fn record_order(&mut self, order: usize) {
        if self.orders.len() <= order {
            self.orders.resize(order + 1, 0);
        }
        self.orders[order] += 1;
    }

    /// Adds the work of `other` (a later segment of the same integration): counters and
    /// order counts are summed; the first stiffness detection is kept.
    pub fn accumulate(&mut self, other: &Stats) {
        self.accepted_steps += other.accepted_steps;
        self.rejected_steps += other.rejected_steps;
        self.rhs_evaluations += other.rhs_evaluations;
        self.jacobian_evaluations += other.jacobian_evaluations;
        self.lu_decompositions += other.lu_decompositions;
        self.newton_iterations += other.newton_iterations;
        if self.orders.len() < other.orders.len() {
            self.orders.resize(other.orders.len(), 0);
        }
        for (mine, theirs) in self.orders.iter_mut().zip(&other.orders) {
            *mine += theirs;
        }
        self.stiffness_detected_at = self.stiffness_detected_at.or(other.stiffness_detected_at);
        self.segments += other.segments;
    }

    /// The highest order used in an accepted step (0 if none).
    pub fn max_order_used(&self) -> usize {
        self.orders.iter().rposition(|&c| c > 0).unwrap_or(0)
    }
}

/// States at the requested output times, row by row, with the work statistics.
#[derive(Debug, Clone, Default)]
pub struct Solution {
    /// Output times.
    pub t: Vec<f64>,
    /// States, `t.len()` rows of `dim` values.
    pub states: Vec<f64>,
    /// System dimension.
    pub dim: usize,
    /// Work statistics.
    pub stats: Stats,
}

impl Solution {
    /// An empty solution for a system of dimension `dim`.
    pub fn with_capacity(dim: usize, n_out: usize) -> Self {
        Self {
            t: Vec::with_capacity(n_out),
            states: Vec::with_capacity(n_out * dim),
            dim,
            stats: Stats::default(),
        }
    }
    /// Appends one output.
    pub fn push(&mut self, t: f64, y: &[f64]) {
        self.t.push(t);
        self.states.extend_from_slice(y);
    }
    /// Number of outputs.
    pub fn len(&self) -> usize {
        self.t.len()
    }
    /// Whether there are no outputs.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }
    /// The state at output `k`.
    pub fn y(&self, k: usize) -> &[f64] {
        &self.states[k * self.dim..(k + 1) * self.dim]
    }
    /// The last state.
    pub fn last(&self) -> Option<&[f64]> {
        (!self.is_empty()).then(|| self.y(self.len() - 1))
    }
}
