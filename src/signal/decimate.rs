//! Min/max decimation: a long series reduced for plotting without losing a peak.
//!
//! An hour of current at 10 kHz is 36 million samples; a chart is a thousand pixels wide. Taking
//! every n-th sample would drop a one-sample spike (a tool breaking) with probability `1 − 1/n`.
//! Instead the series is cut into equal buckets and each bucket keeps its smallest and its
//! largest value, in their original order, so the envelope drawn is exactly the envelope of the
//! data.
//!
//! Non-finite values (NaN, ±∞) are gaps (a disarmed estimator, a missing sample): they are never
//! an extreme, but a bucket that holds one keeps its first one in place, so the chart breaks the
//! line there instead of drawing straight across the missing span or to infinity.

/// The indices [`min_max`] keeps: for each of `buckets` equal index ranges, the index of its
/// smallest and of its largest finite value (once if they coincide) and of its first non-finite
/// value if it has one, ascending. With no more than `2 · buckets` values, every index.
///
/// ```
/// use cutlab::signal::decimate::min_max_indices;
/// let values = [0.0, 5.0, 1.0, 1.0, -3.0, 1.0, 1.0, 2.0];
/// // Two buckets: [0, 5, 1, 1] keeps 0 (index 0) and 5 (index 1); [-3, 1, 1, 2] keeps 4 and 7.
/// assert_eq!(min_max_indices(&values, 2), [0, 1, 4, 7]);
/// ```
pub fn min_max_indices(values: &[f64], buckets: usize) -> Vec<usize> {
    let buckets = buckets.max(1);
    let n = values.len();
    if n <= 2 * buckets {
        return (0..n).collect();
    }
    let mut kept = Vec::with_capacity(2 * buckets);
    for b in 0..buckets {
        // Bucket b covers [b·n/buckets, (b+1)·n/buckets): sizes differ by at most one.
        let start = b * n / buckets;
        let end = (b + 1) * n / buckets;
        let mut min: Option<usize> = None;
        let mut max: Option<usize> = None;
        let mut gap: Option<usize> = None;
        for (i, &v) in values.iter().enumerate().take(end).skip(start) {
            if !v.is_finite() {
                gap = gap.or(Some(i));
                continue;
            }
            if min.is_none_or(|m| v < values[m]) {
                min = Some(i);
            }
            if max.is_none_or(|m| v > values[m]) {
                max = Some(i);
            }
        }
        let mut chosen = [min, max, gap];
        chosen.sort_unstable();
        let bucket_start = kept.len();
        for i in chosen.into_iter().flatten() {
            if kept.len() == bucket_start || kept.last() != Some(&i) {
                kept.push(i);
            }
        }
    }
    kept
}

/// Reduces `points` (x, y), ordered by x, to at most `max_points` (at least 2) by keeping each
/// bucket's minimum and maximum y in order, plus one non-finite point per bucket that has a gap
/// (so a gappy series may keep up to half as many again). Series no longer than `max_points`
/// come back whole.
///
/// ```
/// use cutlab::signal::decimate::min_max;
/// // A million samples of a small wave with one spike.
/// let points: Vec<(f64, f64)> = (0..1_000_000)
///     .map(|i| (i as f64 * 1e-4, if i == 654_321 { 50.0 } else { ((i % 100) as f64).sin() }))
///     .collect();
/// let shown = min_max(&points, 1000);
/// assert!(shown.len() <= 1000);
/// assert!(shown.contains(&(654_321.0 * 1e-4, 50.0)));
/// assert!(shown.windows(2).all(|w| w[0].0 < w[1].0));
/// ```
pub fn min_max(points: &[(f64, f64)], max_points: usize) -> Vec<(f64, f64)> {
    let values: Vec<f64> = points.iter().map(|p| p.1).collect();
    let buckets = if points.len() <= max_points.max(2) {
        points.len()
    } else {
        (max_points / 2).max(1)
    };
    min_max_indices(&values, buckets)
        .into_iter()
        .map(|i| points[i])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_bucket_extreme_survives() {
        let values: Vec<f64> = (0..10_007).map(|i| ((i * 7919) % 1013) as f64).collect();
        let buckets = 37;
        let kept = min_max_indices(&values, buckets);
        assert!(kept.len() <= 2 * buckets);
        assert!(kept.windows(2).all(|w| w[0] < w[1]));
        let global_max = values.iter().copied().fold(f64::MIN, f64::max);
        let global_min = values.iter().copied().fold(f64::MAX, f64::min);
        assert!(kept.iter().any(|&i| values[i] == global_max));
        assert!(kept.iter().any(|&i| values[i] == global_min));
    }

    #[test]
    fn non_finite_values_are_kept_as_gaps_but_never_as_extremes() {
        let values = [f64::NAN, 1.0, f64::INFINITY, -2.0, f64::NAN, f64::NAN, 7.0];
        // Buckets [NaN, 1], [∞, -2], [NaN, NaN, 7].
        assert_eq!(min_max_indices(&values, 3), [0, 1, 2, 3, 4, 6]);
        let short = [(0.0, 1.0), (1.0, f64::NAN), (2.0, 3.0)];
        let kept = min_max(&short, 10);
        assert_eq!(kept.len(), 3);
        assert!(kept[1].1.is_nan(), "the gap must survive");
    }

    #[test]
    fn a_gap_in_a_long_series_survives_decimation() {
        // A series disarmed in the middle third: the decimated line must break there.
        let n = 90_000;
        let values: Vec<f64> = (0..n)
            .map(|i| {
                if (n / 3..2 * n / 3).contains(&i) {
                    f64::NAN
                } else {
                    (i as f64 * 0.001).sin()
                }
            })
            .collect();
        let kept = min_max_indices(&values, 100);
        assert!(kept.windows(2).all(|w| w[0] < w[1]));
        assert!(kept.len() <= 3 * 100);
        let first_gap = kept.iter().position(|&i| values[i].is_nan());
        assert!(first_gap.is_some_and(|k| kept[k] == n / 3), "{kept:?}");
        assert!(kept
            .iter()
            .filter(|&&i| values[i].is_finite())
            .all(|&i| !(n / 3..2 * n / 3).contains(&i)));
    }

    #[test]
    fn tiny_budgets_still_keep_both_extremes() {
        let points: Vec<(f64, f64)> = (0..100)
            .map(|i| (i as f64, (i as f64 - 30.0).abs()))
            .collect();
        let shown = min_max(&points, 0);
        assert_eq!(shown, [(30.0, 0.0), (99.0, 69.0)]);
    }
}
