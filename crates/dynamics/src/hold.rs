//! The zero-order hold of a sampled law (slider or vibration control): samples at
//! `start + k period`, each held until the next. The samples are times where the
//! integration stops (so the right-hand side is smooth between them); they are taken when
//! an integration segment starts at one ([`flexprr_integrators::OdeSystem::segment_start`]),
//! and kept, so that outputs computed after the run see the value held at any time.

/// The earlier of two optional times.
pub(crate) fn earliest(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (a, b) => a.or(b),
    }
}

/// The samples of a sampled law, in time order.
#[derive(Debug, Clone)]
pub(crate) struct Hold<T> {
    start: f64,
    period: f64,
    samples: Vec<(f64, T)>,
}

impl<T> Hold<T> {
    /// A hold sampling at `start + k period` (`period` > 0; 0 gives a hold that never
    /// samples: a continuous law).
    pub(crate) fn new(start: f64, period: f64) -> Self {
        Self {
            start,
            period,
            samples: Vec::new(),
        }
    }

    /// Whether the law is sampled at all.
    pub(crate) fn is_sampled(&self) -> bool {
        self.period > 0.0
    }

    /// The period (s).
    pub(crate) fn period(&self) -> f64 {
        self.period
    }

    fn tolerance(&self) -> f64 {
        1e-9 * self.period
    }

    /// The first sample time strictly after `t` (beyond the hold's tolerance, so a time
    /// on a sample gives the next one): where the integration must stop next. `None` for a
    /// continuous law. The samples are generated one at a time, never listed.
    pub(crate) fn next_sample(&self, t: f64) -> Option<f64> {
        if !self.is_sampled() {
            return None;
        }
        let k = (((t - self.start) / self.period).floor() + 1.0).max(1.0);
        let mut next = self.start + k * self.period;
        if next <= t + self.tolerance() {
            next = self.start + (k + 1.0) * self.period;
        }
        Some(next)
    }

    /// Whether `t` is one of the sample times.
    pub(crate) fn is_sample_time(&self, t: f64) -> bool {
        if !self.is_sampled() {
            return false;
        }
        let k = ((t - self.start) / self.period).round();
        k >= 0.0 && (t - (self.start + k * self.period)).abs() <= self.tolerance()
    }

    /// The value held at `t` (the last sample at or before it).
    pub(crate) fn held(&self, t: f64) -> Option<&T> {
        let tolerance = self.tolerance();
        let k = self.samples.partition_point(|s| s.0 <= t + tolerance);
        k.checked_sub(1).map(|k| &self.samples[k].1)
    }

    /// Drops the samples at or after `t` (the model is integrated again from an earlier
    /// time) and returns the last one before it.
    pub(crate) fn rewind(&mut self, t: f64) -> Option<&T> {
        let tolerance = self.tolerance();
        let keep = self.samples.partition_point(|s| s.0 < t - tolerance);
        self.samples.truncate(keep);
        self.samples.last().map(|s| &s.1)
    }

    /// Records the sample `value` at `t` (after [`Hold::rewind`]).
    pub(crate) fn push(&mut self, t: f64, value: T) {
        self.samples.push((t, value));
    }
}

#[cfg(test)]
mod tests {
    use super::Hold;

    #[test]
    fn a_hold_samples_on_its_grid_and_holds_between() {
        let mut hold = Hold::new(0.1, 0.01);
        assert!((hold.next_sample(0.1).unwrap() - 0.11).abs() < 1e-15);
        assert!((hold.next_sample(0.11).unwrap() - 0.12).abs() < 1e-15);
        assert!((hold.next_sample(0.1234).unwrap() - 0.13).abs() < 1e-15);
        assert!((hold.next_sample(0.0).unwrap() - 0.11).abs() < 1e-15);
        assert_eq!(Hold::<u8>::new(0.0, 0.0).next_sample(0.5), None);
        assert!(hold.is_sample_time(0.12) && !hold.is_sample_time(0.125));
        hold.push(0.1, 1);
        hold.push(0.11, 2);
        assert_eq!(hold.held(0.105), Some(&1));
        assert_eq!(hold.held(0.11), Some(&2));
        assert_eq!(hold.held(0.05), None);
        assert_eq!(hold.rewind(0.11), Some(&1));
        assert_eq!(hold.held(0.2), Some(&1));
    }
}
