//! Dense checks of a timed motion against every limit (docs/planning.md, "Between grid
//! points"): the planner enforces the limits at its grid points; a check evaluates the exact
//! rows (with the exact `sqrt(x)` terms) at many more points of the continuous timing.

/// The worst use of one limit found by a check.
#[derive(Debug, Clone, PartialEq)]
pub struct Usage {
    /// The constraint's name.
    pub constraint: String,
    /// Unit of value and limit.
    pub unit: String,
    /// The row (`leg 2`, `link 1 at B`) where the use is largest.
    pub label: String,
    /// Its index among the constraint's rows.
    pub row: usize,
    /// Largest `value / limit` (1 = at the limit).
    pub usage: f64,
    /// The value there.
    pub value: f64,
    /// The limit there (the bound on the value's side).
    pub limit: f64,
    /// Path parameter there.
    pub s: f64,
    /// Time there (s).
    pub t: f64,
}

impl Usage {
    pub(crate) fn new(constraint: &str, unit: &str) -> Self {
        Self {
            constraint: constraint.to_owned(),
            unit: unit.to_owned(),
            label: String::new(),
            row: 0,
            usage: 0.0,
            value: 0.0,
            limit: f64::INFINITY,
            s: 0.0,
            t: 0.0,
        }
    }

    /// Margin `1 - usage` (negative: broken).
    pub fn margin(&self) -> f64 {
        1.0 - self.usage
    }
}

/// The result of a dense check.
#[derive(Debug, Clone, PartialEq)]
pub struct Check {
    /// Number of instants checked.
    pub samples: usize,
    /// Largest use of any limit.
    pub max_usage: f64,
    /// Per constraint, its largest use (in the planner's order; a jerk limit last).
    pub constraints: Vec<Usage>,
}

impl Check {
    pub(crate) fn new(names: impl Iterator<Item = (String, String)>) -> Self {
        Self {
            samples: 0,
            max_usage: 0.0,
            constraints: names.map(|(n, u)| Usage::new(&n, &u)).collect(),
        }
    }

    /// The constraint with the largest use.
    pub fn worst(&self) -> Option<&Usage> {
        self.constraints
            .iter()
            .max_by(|a, b| a.usage.total_cmp(&b.usage))
    }

    /// Records a use; returns it.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub(crate) fn record(
        &mut self,
        constraint: usize,
        row: usize,
        usage: f64,
        value: f64,
        limit: f64,
        s: f64,
        t: f64,
    ) -> f64 {
        let entry = &mut self.constraints[constraint];
        if usage > entry.usage || usage.is_nan() {
            entry.usage = usage;
            entry.value = value;
            entry.limit = limit;
            entry.s = s;
            entry.t = t;
            entry.row = row;
        }
        if usage > self.max_usage || usage.is_nan() {
            self.max_usage = usage;
        }
        usage
    }
}
