//! Peaks, RMS values and first crossings of a function of time known everywhere (the
//! commanded motion's requirement on the motors), to a stated resolution that does not
//! depend on the run's output step.
//!
//! The function is evaluated on a grid that holds the span's breakpoints (where it may have a
//! kink) and is refined by halving its step until every channel's peak and RMS value change
//! by at most [`TOLERANCE`] of the channel's peak between two refinements. The peak of each
//! channel is refined between grid points by golden-section search (Press et al., *Numerical
//! Recipes*, 3rd ed., 10.2), the RMS value is Simpson's rule on each segment between
//! breakpoints, and a first crossing of a limit is located by bisection on the function
//! itself, including a crossing inside a hump that lies between two grid points.

use flexprr_dynamics::DynamicsError;

use crate::stats::Peak;

/// Largest change of a peak or an RMS value between two refinements, relative to the
/// channel's peak, at which the grid counts as converged.
pub const TOLERANCE: f64 = 1e-6;

/// Grid intervals over the whole span at the first level.
const START_INTERVALS: usize = 1024;

/// Grid intervals over the whole span beyond which the grid is not refined further.
const MAX_INTERVALS: usize = 1 << 18;

/// Golden-section and bisection iterations: the bracket shrinks below 1e-12 of a grid step.
const SEARCH_ITERATIONS: usize = 60;

/// A function of time writing its channels into the slice, or failing at that time.
pub type Channels<'a> = dyn FnMut(f64, &mut [f64]) -> Result<(), DynamicsError> + 'a;

/// What a scan found, per channel.
#[derive(Debug, Clone, PartialEq)]
pub struct Scan {
    /// The span scanned (s).
    pub span: (f64, f64),
    /// The largest grid step of the last level (s).
    pub step: f64,
    /// Whether the peaks and RMS values converged to [`TOLERANCE`] before the grid reached
    /// its largest size.
    pub converged: bool,
    /// Each channel's largest magnitude and when.
    pub peaks: Vec<Peak>,
    /// Each channel's RMS value over the span (the root of the time mean of its square).
    pub rms: Vec<f64>,
    /// Each channel's first time beyond its limit (magnitude strictly above it).
    pub first_over: Vec<Option<f64>>,
}

/// A function of time with `channels` values, its grid segment by segment.
struct Grid<'a> {
    f: &'a mut Channels<'a>,
    channels: usize,
    /// Segment ends: the span's ends and the breakpoints inside it.
    edges: Vec<f64>,
    /// Per segment: the values at its `n + 1` grid points, row by row.
    values: Vec<Vec<f64>>,
    /// Per segment: its number of intervals (even, for Simpson's rule).
    intervals: Vec<usize>,
    scratch: Vec<f64>,
}

impl Grid<'_> {
    fn time(&self, segment: usize, k: usize) -> f64 {
        let (a, b) = (self.edges[segment], self.edges[segment + 1]);
        a + (b - a) * k as f64 / self.intervals[segment] as f64
    }

    fn value(&self, segment: usize, k: usize, channel: usize) -> f64 {
        self.values[segment][k * self.channels + channel]
    }

    /// `|f_channel(t)|`.
    fn magnitude(&mut self, t: f64, channel: usize) -> Result<f64, DynamicsError> {
        (self.f)(t, &mut self.scratch)?;
        Ok(self.scratch[channel].abs())
    }

    /// The first level: each segment gets its share of [`START_INTERVALS`] (at least 2).
    fn start(&mut self) -> Result<(), DynamicsError> {
        let span = self.edges[self.edges.len() - 1] - self.edges[0];
        for s in 0..self.edges.len() - 1 {
            let share = (self.edges[s + 1] - self.edges[s]) / span;
            let n = ((share * START_INTERVALS as f64).ceil() as usize).max(2);
            self.intervals[s] = n + n % 2;
            let mut row = vec![0.0; (self.intervals[s] + 1) * self.channels];
            for k in 0..=self.intervals[s] {
                let t = self.time(s, k);
                (self.f)(t, &mut row[k * self.channels..(k + 1) * self.channels])?;
            }
            self.values[s] = row;
        }
        Ok(())
    }

    /// Halves every segment's step, evaluating the new midpoints only.
    fn refine(&mut self) -> Result<(), DynamicsError> {
        let c = self.channels;
        for s in 0..self.edges.len() - 1 {
            let n = self.intervals[s];
            let old = std::mem::take(&mut self.values[s]);
            let mut row = vec![0.0; (2 * n + 1) * c];
            self.intervals[s] = 2 * n;
            for k in 0..=2 * n {
                if k % 2 == 0 {
                    row[k * c..(k + 1) * c].copy_from_slice(&old[(k / 2) * c..(k / 2 + 1) * c]);
                } else {
                    let t = self.time(s, k);
                    (self.f)(t, &mut row[k * c..(k + 1) * c])?;
                }
            }
            self.values[s] = row;
        }
        Ok(())
    }

    fn total_intervals(&self) -> usize {
        self.intervals.iter().sum()
    }

    fn largest_step(&self) -> f64 {
        (0..self.edges.len() - 1)
            .map(|s| (self.edges[s + 1] - self.edges[s]) / self.intervals[s] as f64)
            .fold(0.0, f64::max)
    }

    /// The RMS value of `channel` over the span: Simpson's rule on each segment, on the
    /// values scaled by their largest magnitude (so that squares of huge values do not
    /// overflow).
    fn rms(&self, channel: usize) -> f64 {
        let mut scale = 0.0_f64;
        for s in 0..self.edges.len() - 1 {
            for k in 0..=self.intervals[s] {
                scale = scale.max(self.value(s, k, channel).abs());
            }
        }
        if scale == 0.0 || !scale.is_finite() {
            return scale;
        }
        let mut integral = 0.0;
        for s in 0..self.edges.len() - 1 {
            let n = self.intervals[s];
            let h = (self.edges[s + 1] - self.edges[s]) / n as f64;
            let mut sum = 0.0;
            for k in 0..=n {
                let x = self.value(s, k, channel) / scale;
                let w = if k == 0 || k == n {
                    1.0
                } else if k % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                sum += w * x * x;
            }
            integral += sum * h / 3.0;
        }
        let span = self.edges[self.edges.len() - 1] - self.edges[0];
        scale * (integral / span).max(0.0).sqrt()
    }

    /// The grid points (segment, index) where `|f_channel|` has a local maximum of at least
    /// `floor`, in time order (segment ends included).
    fn local_maxima(&self, channel: usize, floor: f64) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for s in 0..self.edges.len() - 1 {
            let n = self.intervals[s];
            for k in 0..=n {
                let x = self.value(s, k, channel).abs();
                let left = if k > 0 {
                    self.value(s, k - 1, channel).abs()
                } else {
                    0.0
                };
                let right = if k < n {
                    self.value(s, k + 1, channel).abs()
                } else {
                    0.0
                };
                if x >= floor && x >= left && x >= right {
                    out.push((s, k));
                }
            }
        }
        out
    }

    /// The largest `|f_channel|` near grid point `(s, k)`: golden-section search between its
    /// neighbours within the segment (the function is smooth there), as `(t, value)`.
    fn refine_maximum(
        &mut self,
        s: usize,
        k: usize,
        channel: usize,
    ) -> Result<(f64, f64), DynamicsError> {
        let n = self.intervals[s];
        let (mut a, mut b) = (
            self.time(s, k.saturating_sub(1)),
            self.time(s, (k + 1).min(n)),
        );
        let mut best = (self.time(s, k), self.value(s, k, channel).abs());
        let ratio = 0.5 * (5.0_f64.sqrt() - 1.0);
        let mut c = b - ratio * (b - a);
        let mut d = a + ratio * (b - a);
        let mut fc = self.magnitude(c, channel)?;
        let mut fd = self.magnitude(d, channel)?;
        for _ in 0..SEARCH_ITERATIONS {
            if fc > fd {
                b = d;
                d = c;
                fd = fc;
                c = b - ratio * (b - a);
                fc = self.magnitude(c, channel)?;
            } else {
                a = c;
                c = d;
                fc = fd;
                d = a + ratio * (b - a);
                fd = self.magnitude(d, channel)?;
            }
        }
        for (t, v) in [(c, fc), (d, fd)] {
            if v > best.1 {
                best = (t, v);
            }
        }
        Ok(best)
    }

    /// The peak of `channel`: the grid's largest magnitude, refined around every grid local
    /// maximum within 10 % of it.
    fn peak(&mut self, channel: usize) -> Result<Peak, DynamicsError> {
        let mut sampled = Peak {
            value: 0.0,
            t: self.edges[0],
        };
        for s in 0..self.edges.len() - 1 {
            for k in 0..=self.intervals[s] {
                let x = self.value(s, k, channel).abs();
                if x > sampled.value {
                    sampled = Peak {
                        value: x,
                        t: self.time(s, k),
                    };
                }
            }
        }
        let mut peak = sampled;
        for (s, k) in self.local_maxima(channel, 0.9 * sampled.value) {
            let (t, v) = self.refine_maximum(s, k, channel)?;
            if v > peak.value {
                peak = Peak { value: v, t };
            }
        }
        Ok(peak)
    }

    /// The first time `|f_channel|` exceeds `limit`, by bisection between the last time it
    /// was at or below it and the first grid point (or refined hump) above it.
    fn first_over(&mut self, channel: usize, limit: f64) -> Result<Option<f64>, DynamicsError> {
        if self.value(0, 0, channel).abs() > limit {
            return Ok(Some(self.edges[0]));
        }
        let humps = self.local_maxima(channel, 0.5 * limit);
        let mut h = 0;
        for s in 0..self.edges.len() - 1 {
            for k in 1..=self.intervals[s] {
                // A hump at grid point (s, k - 1) or (s, k) rises above the limit between
                // the grid points: its refined top is the first point above.
                let mut above = None;
                while h < humps.len() && humps[h] <= (s, k) {
                    let (hs, hk) = humps[h];
                    h += 1;
                    let (t, v) = self.refine_maximum(hs, hk, channel)?;
                    if v > limit && t > self.time(s, k - 1) {
                        above = Some(t);
                        break;
                    }
                }
                if self.value(s, k, channel).abs() > limit {
                    let t = self.time(s, k);
                    above = Some(above.map_or(t, |a: f64| a.min(t)));
                }
                if let Some(hi) = above {
                    return self
                        .bisect(channel, limit, self.time(s, k - 1), hi)
                        .map(Some);
                }
            }
        }
        Ok(None)
    }

    /// The crossing of `limit` by `|f_channel|` in `(lo, hi]`, at or below at `lo`, above
    /// at `hi`: the first time above it found by bisection.
    fn bisect(
        &mut self,
        channel: usize,
        limit: f64,
        mut lo: f64,
        mut hi: f64,
    ) -> Result<f64, DynamicsError> {
        for _ in 0..SEARCH_ITERATIONS {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if self.magnitude(mid, channel)? > limit {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        Ok(hi)
    }
}

/// Scans `f` (writing `limits.len()` channels at a time) over `[t0, t1]` with the
/// breakpoints `breakpoints` (those inside the span are kept): peaks, RMS values and the
/// first time each channel's magnitude exceeds its limit (`f64::INFINITY` for none).
///
/// # Errors
/// The first evaluation of `f` that fails.
pub fn scan(
    f: &mut Channels<'_>,
    (t0, t1): (f64, f64),
    breakpoints: &[f64],
    limits: &[f64],
) -> Result<Scan, DynamicsError> {
    let channels = limits.len();
    let mut edges = vec![t0];
    let mut inside: Vec<f64> = breakpoints
        .iter()
        .copied()
        .filter(|b| *b > t0 && *b < t1)
        .collect();
    inside.sort_by(f64::total_cmp);
    let floor = 1e-12 * (t1 - t0);
    for b in inside {
        if b - edges[edges.len() - 1] > floor && t1 - b > floor {
            edges.push(b);
        }
    }
    edges.push(t1);
    let segments = edges.len() - 1;
    let mut grid = Grid {
        f,
        channels,
        edges,
        values: vec![Vec::new(); segments],
        intervals: vec![0; segments],
        scratch: vec![0.0; channels],
    };
    grid.start()?;
    let mut previous: Option<(Vec<Peak>, Vec<f64>)> = None;
    let mut converged = false;
    let (peaks, rms) = loop {
        let peaks = (0..channels)
            .map(|c| grid.peak(c))
            .collect::<Result<Vec<_>, _>>()?;
        let rms: Vec<f64> = (0..channels).map(|c| grid.rms(c)).collect();
        if let Some((p0, r0)) = &previous {
            converged = (0..channels).all(|c| {
                let scale = peaks[c].value.max(f64::MIN_POSITIVE);
                (peaks[c].value - p0[c].value).abs() <= TOLERANCE * scale
                    && (rms[c] - r0[c]).abs() <= TOLERANCE * scale
            });
        }
        if converged || 2 * grid.total_intervals() > MAX_INTERVALS {
            break (peaks, rms);
        }
        previous = Some((peaks, rms));
        grid.refine()?;
    };
    let first_over = limits
        .iter()
        .enumerate()
        .map(|(c, &limit)| {
            if limit.is_finite() {
                grid.first_over(c, limit)
            } else {
                Ok(None)
            }
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Scan {
        span: (t0, t1),
        step: grid.largest_step(),
        converged,
        peaks,
        rms,
        first_over,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `x = sin(2 pi 2.5 t)` scaled by 103.8 and `y = t^2` with a kink-free ramp: the peaks,
    /// RMS values and crossings of their closed forms, whatever the grid.
    #[test]
    fn closed_forms_of_a_sine_and_a_parabola() {
        let w = 2.0 * std::f64::consts::PI * 2.5;
        let mut f = |t: f64, out: &mut [f64]| {
            out[0] = 103.8 * (w * t).sin();
            out[1] = t * t;
            Ok(())
        };
        let s = scan(&mut f, (0.0, 0.2), &[0.05], &[100.0, 0.01]).unwrap();
        assert!(s.converged);
        // Peak 103.8 at t = 0.1 s (a quarter period).
        assert!((s.peaks[0].value - 103.8).abs() < 1e-9, "{:?}", s.peaks[0]);
        assert!((s.peaks[0].t - 0.1).abs() < 1e-6, "{:?}", s.peaks[0]);
        // RMS of a sine over half a period: amplitude / sqrt(2).
        assert!((s.rms[0] - 103.8 / 2.0_f64.sqrt()).abs() < 1e-7 * 103.8);
        // First above 100: asin(100 / 103.8) / w.
        let t = (100.0_f64 / 103.8).asin() / w;
        assert!(
            (s.first_over[0].unwrap() - t).abs() < 1e-12,
            "{:?}",
            s.first_over
        );
        // t^2 passes 0.01 at 0.1 s; its RMS over [0, 0.2] is sqrt(0.2^4 / 5).
        assert!((s.first_over[1].unwrap() - 0.1).abs() < 1e-12);
        assert!((s.rms[1] - (0.2_f64.powi(4) / 5.0).sqrt()).abs() < 1e-12);
    }

    /// A hump narrower than the first grid's step, between two grid points, is still
    /// found: the grid is refined until the peak converges, and its crossing is located.
    #[test]
    fn a_narrow_hump_between_grid_points_is_found() {
        let mut f = |t: f64, out: &mut [f64]| {
            let d = (t - 0.50037) / 2e-4;
            out[0] = 2.0 * (-d * d).exp();
            Ok(())
        };
        let s = scan(&mut f, (0.0, 1.0), &[], &[1.0]).unwrap();
        assert!((s.peaks[0].value - 2.0).abs() < 1e-9);
        let t = 0.50037 - 2e-4 * 2.0_f64.ln().sqrt();
        assert!(
            (s.first_over[0].unwrap() - t).abs() < 1e-12,
            "{:?}",
            s.first_over
        );
    }
}
