//! Running summaries of a stream of samples: the smallest, the mean and the largest, for the
//! min/max bands and block means that plots show and the closed loop's period summaries.
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
