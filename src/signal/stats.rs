//! Summaries of samples: the running smallest, mean and largest of a stream, for the min/max
//! bands and block means that plots show and the closed loop's period summaries, and the one
//! [`median`] every caller takes.
//!
//! ## NaN and ±∞
//!
//! The minimum and maximum skip NaN samples (`f64::min`/`f64::max` return the other operand), so
//! a band stays drawn around a glitch; they are NaN only when every sample was. The mean is NaN
//! once any sample was NaN, and ±∞ once any was infinite. With no samples all three are NaN.

/// The minimum, mean and maximum of the samples pushed so far.
///
/// ```
/// use cutlab::signal::stats::MinMeanMax;
/// let mut s = MinMeanMax::new();
/// for x in [2.0, -1.0, 5.0, f64::NAN] {
///     s.push(x);
/// }
/// assert_eq!((s.count(), s.min(), s.max()), (4, -1.0, 5.0));
/// assert!(s.mean().is_nan());
/// let mut t = MinMeanMax::new();
/// t.push(1.0);
/// t.push(2.0);
/// assert_eq!((t.mean(), t.min_max()), (1.5, (1.0, 2.0)));
/// assert!(MinMeanMax::new().min().is_nan());
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MinMeanMax {
    count: usize,
    sum: f64,
    // NaN until the first sample: `NaN.min(x)` is `x`, so the first sample needs no branch.
    min: f64,
    max: f64,
}

impl Default for MinMeanMax {
    fn default() -> Self {
        Self::new()
    }
}

impl MinMeanMax {
    /// Nothing seen yet.
    pub const fn new() -> Self {
        Self {
            count: 0,
            sum: 0.0,
            min: f64::NAN,
            max: f64::NAN,
        }
    }

    /// Takes one sample.
    #[inline(always)]
    pub fn push(&mut self, x: f64) {
        self.count += 1;
        self.sum += x;
        self.min = crate::math::min(self.min, x);
        self.max = crate::math::max(self.max, x);
    }

    /// Samples pushed.
    pub fn count(&self) -> usize {
        self.count
    }

    /// The smallest sample (NaN before the first).
    pub fn min(&self) -> f64 {
        self.min
    }

    /// The largest sample (NaN before the first).
    pub fn max(&self) -> f64 {
        self.max
    }

    /// (smallest, largest).
    pub fn min_max(&self) -> (f64, f64) {
        (self.min, self.max)
    }

    /// The mean: the sum in arrival order over the count (NaN before the first sample).
    pub fn mean(&self) -> f64 {
        if self.count == 0 {
            f64::NAN
        } else {
            self.sum / self.count as f64
        }
    }
}

/// The median of the finite values, as numpy and pandas take it: the middle value of an odd
/// count, the mean of the two middle values of an even one; NaN when no value is finite.
/// Non-finite values are left out rather than sorted in (a NaN has no place in an order, and
/// one ±∞ would pull the median by a whole position).
///
/// ```
/// use cutlab::signal::stats::median;
/// assert_eq!(median([3.0, 1.0, 2.0]), 2.0);
/// assert_eq!(median([4.0, 1.0, 3.0, 2.0]), 2.5);
/// assert_eq!(median([f64::NAN, 5.0, f64::INFINITY]), 5.0);
/// assert!(median([]).is_nan());
/// ```
pub fn median(values: impl IntoIterator<Item = f64>) -> f64 {
    let mut finite: Vec<f64> = values.into_iter().filter(|v| v.is_finite()).collect();
    let n = finite.len();
    if n == 0 {
        return f64::NAN;
    }
    let (below, upper, _) = finite.select_nth_unstable_by(n / 2, f64::total_cmp);
    let upper = *upper;
    if n % 2 == 1 {
        return upper;
    }
    // The lower middle value is the largest of those before the upper one.
    let lower = below.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    0.5 * (lower + upper)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extremes_skip_nan_unless_every_sample_is_nan() {
        let mut s = MinMeanMax::new();
        s.push(f64::NAN);
        assert!(s.min().is_nan() && s.max().is_nan());
        s.push(3.0);
        s.push(f64::NAN);
        assert_eq!(s.min_max(), (3.0, 3.0));
        assert!(s.mean().is_nan());
    }

    #[test]
    fn the_mean_is_the_running_sum_over_the_count() {
        let mut s = MinMeanMax::default();
        let xs = [0.1, 0.2, 0.3, -7.5, 1e-3];
        let mut sum = 0.0;
        for x in xs {
            s.push(x);
            sum += x;
        }
        // The same bits as summing by hand: callers rely on it for bit-identical block means.
        assert_eq!(s.mean().to_bits(), (sum / xs.len() as f64).to_bits());
        assert_eq!(s.min_max(), (-7.5, 0.3));
    }
}
