//! Decimation of long series: uniform frame strides for the animation, min/max buckets
//! for the plots so that no extreme is lost.

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
    use super::*;

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
