//! Decimation of long series for drawing, keeping every series' extremes.
//!
//! The abscissa is cut into buckets about a pixel wide; each bucket keeps its first, lowest,
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

#[cfg(test)]
mod tests {
    use super::decimate;
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
}
