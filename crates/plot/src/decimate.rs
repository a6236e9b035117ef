//! Decimation of long series for drawing, keeping every series' extremes: the one place
//! for it, used by the figures ([`decimate`]) and the viewer (its animation frames,
//! [`frame_indices`], and its small linked plots, [`min_max_indices`]).
//!
//! For figures, the abscissa is cut into buckets about a pixel wide; each bucket keeps its first, lowest,
//! highest and last point, in their order (the "M4" aggregation of Jugel et al., "M4: a
//! visualization-oriented time series data aggregation", *Proc. VLDB Endow.* 7(10), 2014).
//! A polyline through them covers the same pixels as the full series, so the drawing does
//! not change, and the global minimum and maximum are always kept.

/// At most `4 * buckets` points of `(x, y)` (sorted by `x`) that draw like all of them:
/// per bucket of equal `x` width its first, lowest, highest and last point. Points that
/// are not finite are kept as gaps (one per run of them). A series short enough is
/// returned whole.
pub fn decimate(x: &[f64], y: &[f64], buckets: usize) -> (Vec<f64>, Vec<f64>) {
    let n = x.len().min(y.len());
    let buckets = buckets.max(1);
    let sorted = x[..n].windows(2).all(|w| w[0] <= w[1] || w[1].is_nan());
    if n <= 4 * buckets || !sorted {
        return (x[..n].to_vec(), y[..n].to_vec());
    }
    let finite_x = || x[..n].iter().copied().filter(|v| v.is_finite());
    let lo = finite_x().fold(f64::INFINITY, f64::min);
    let hi = finite_x().fold(f64::NEG_INFINITY, f64::max);
    let width = (hi - lo) / buckets as f64;
    if !(width.is_finite() && width > 0.0) {
        return (x[..n].to_vec(), y[..n].to_vec());
    }
    let bucket_of = |v: f64| (((v - lo) / width) as usize).min(buckets - 1);
    let mut keep: Vec<usize> = Vec::with_capacity(4 * buckets + 8);
    let mut k = 0;
    while k < n {
        if !(x[k].is_finite() && y[k].is_finite()) {
            // One gap marker per run of missing values.
            keep.push(k);
            while k < n && !(x[k].is_finite() && y[k].is_finite()) {
                k += 1;
            }
            continue;
        }
        let b = bucket_of(x[k]);
        let (first, mut low, mut high, mut last) = (k, k, k, k);
        while k < n && x[k].is_finite() && y[k].is_finite() && bucket_of(x[k]) == b {
            if y[k] < y[low] {
                low = k;
            }
            if y[k] > y[high] {
                high = k;
            }
            last = k;
            k += 1;
        }
        let mut four = [first, low, high, last];
        four.sort_unstable();
        for i in four {
            if keep.last() != Some(&i) {
                keep.push(i);
            }
        }
    }
    keep.iter().map(|&i| (x[i], y[i])).unzip()
}

/// Indices of the animation frames kept from `n` samples with at most `max_frames`
/// (at least 2): every `ceil((n - 1) / (max_frames - 1))`-th sample, always with the
/// first and the last.
pub fn frame_indices(n: usize, max_frames: usize) -> Vec<usize> {
    let max_frames = max_frames.max(2);
    if n <= max_frames {
        return (0..n).collect();
    }
    let stride = (n - 1).div_ceil(max_frames - 1);
    let mut kept: Vec<usize> = (0..n).step_by(stride).collect();
    if kept.last() != Some(&(n - 1)) {
        kept.push(n - 1);
    }
    kept
}

/// Min/max decimation for line plots (the "M4"/envelope idea: Jugel et al., VLDB 2014):
/// the samples are cut into `buckets` runs of consecutive indices, and from each run the
/// indices of its smallest and largest value are kept, in time order, plus the first and
/// the last sample. Every local extreme that is a bucket extreme survives, in particular
/// the global minimum and maximum; at most `2 buckets + 2` indices are returned.
/// Returns all indices when `n <= 2 buckets + 2`.
pub fn min_max_indices(values: &[f64], buckets: usize) -> Vec<usize> {
    let n = values.len();
    let buckets = buckets.max(1);
    if n <= 2 * buckets + 2 {
        return (0..n).collect();
    }
    let mut kept = Vec::with_capacity(2 * buckets + 2);
    kept.push(0);
    for b in 0..buckets {
        let lo = b * n / buckets;
        let hi = (b + 1) * n / buckets;
        let (mut imin, mut imax) = (lo, lo);
        for i in lo..hi {
            if values[i] < values[imin] {
                imin = i;
            }
            if values[i] > values[imax] {
                imax = i;
            }
        }
        let (first, second) = if imin <= imax {
            (imin, imax)
        } else {
            (imax, imin)
        };
        for i in [first, second] {
            if kept.last() != Some(&i) {
                kept.push(i);
            }
        }
    }
    if kept.last() != Some(&(n - 1)) {
        kept.push(n - 1);
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::{decimate, frame_indices, min_max_indices};
    use proptest::prelude::*;

    fn extremes(v: &[f64]) -> (f64, f64) {
        v.iter()
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            })
    }

    #[test]
    fn a_spike_survives() {
        // 100 001 points of a slow sine with one spike of one sample: the spike is the
        // global maximum and must be kept exactly.
        let n = 100_001;
        let x: Vec<f64> = (0..n).map(|k| k as f64 * 1e-4).collect();
        let mut y: Vec<f64> = x.iter().map(|t| (2.0 * t).sin()).collect();
        y[54_321] = 7.0;
        let (dx, dy) = decimate(&x, &y, 500);
        assert!(dx.len() <= 2000, "{}", dx.len());
        let k = dy
            .iter()
            .position(|v| v.to_bits() == 7f64.to_bits())
            .unwrap();
        assert_eq!(dx[k].to_bits(), x[54_321].to_bits());
        // First and last points stay, so the drawn x range does not shrink.
        assert_eq!(dx[0].to_bits(), x[0].to_bits());
        assert_eq!(dx[dx.len() - 1].to_bits(), x[n - 1].to_bits());
    }

    proptest! {
        /// The global min and max of every series are kept, the size is bounded by four
        /// points a bucket, and the kept points are a subsequence of the series.
        #[test]
        fn keeps_extremes_and_is_bounded(
            y in prop::collection::vec(-1e3f64..1e3, 1..3000),
            buckets in 1usize..200,
        ) {
            let x: Vec<f64> = (0..y.len()).map(|k| k as f64 * 0.01).collect();
            let (dx, dy) = decimate(&x, &y, buckets);
            prop_assert!(dx.len() <= 4 * buckets);
            let (lo, hi) = extremes(&y);
            let (dlo, dhi) = extremes(&dy);
            prop_assert_eq!(lo.to_bits(), dlo.to_bits());
            prop_assert_eq!(hi.to_bits(), dhi.to_bits());
            // Subsequence: every kept x is an original x, in increasing order.
            for w in dx.windows(2) {
                prop_assert!(w[0] < w[1]);
            }
            for (xv, yv) in dx.iter().zip(&dy) {
                let k = (xv / 0.01).round() as usize;
                prop_assert_eq!(y[k].to_bits(), yv.to_bits());
            }
        }
    }

    #[test]
    fn frames_keep_ends_and_respect_the_cap() {
        assert_eq!(frame_indices(5, 10), vec![0, 1, 2, 3, 4]);
        for (n, cap) in [(2001, 500), (100_001, 5000), (10, 3), (7, 2)] {
            let kept = frame_indices(n, cap);
            assert!(
                kept.len() <= cap,
                "{n} samples, cap {cap}: {} kept",
                kept.len()
            );
            assert_eq!(kept[0], 0);
            assert_eq!(*kept.last().unwrap(), n - 1);
            assert!(kept.windows(2).all(|w| w[0] < w[1]));
            // Uniform stride except possibly the last gap.
            let stride = kept[1] - kept[0];
            assert!(kept.windows(2).all(|w| w[1] - w[0] <= stride));
        }
    }

    /// A noisy sine: every bucket's extremes (computed here by brute force) are kept,
    /// hence the global extremes too, and the output is bounded and in time order.
    #[test]
    fn min_max_keeps_every_bucket_extreme() {
        let n = 10_007;
        let values: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 / n as f64;
                (40.0 * t).sin() + 0.3 * ((i * 7919) % 101) as f64 / 101.0
            })
            .collect();
        let buckets = 300;
        let kept = min_max_indices(&values, buckets);
        assert!(kept.len() <= 2 * buckets + 2);
        assert!(kept.windows(2).all(|w| w[0] < w[1]));
        for b in 0..buckets {
            let (lo, hi) = (b * n / buckets, (b + 1) * n / buckets);
            let bucket = &values[lo..hi];
            let min = bucket.iter().copied().fold(f64::INFINITY, f64::min);
            let max = bucket.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let kept_here: Vec<f64> = kept
                .iter()
                .filter(|&&i| (lo..hi).contains(&i))
                .map(|&i| values[i])
                .collect();
            assert!(
                kept_here.iter().any(|v| v.to_bits() == min.to_bits()),
                "bucket {b} min"
            );
            assert!(
                kept_here.iter().any(|v| v.to_bits() == max.to_bits()),
                "bucket {b} max"
            );
        }
        assert_eq!(kept[0], 0);
        assert_eq!(*kept.last().unwrap(), n - 1);
    }

    #[test]
    fn short_series_are_kept_whole() {
        let values = [3.0, 1.0, 2.0];
        assert_eq!(min_max_indices(&values, 10), vec![0, 1, 2]);
    }
}
