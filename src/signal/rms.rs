//! Root-mean-square measures of motor current.
//!
//! - [`block_rms`]: the RMS of a block of samples.
//! - [`SlidingRms`]: the RMS of the last `window` samples, every sample, for hours without
//!   drifting (see its docs for how).
//! - [`three_phase_rms`]: paper 003 eq 7, `√((i_u² + i_v² + i_w²)/3)`, an RMS from one instant of
//!   three balanced phases.
//! - [`RevolutionPeak`]: the peak of an RMS signal over each spindle revolution, the quantity
//!   paper 003 relates to the peak cutting force per revolution; driven by the spindle speed.
//! - [`RmsDetector`]: `√(low-pass(x²))`, an RMS meter with a filter's smooth response.
//!
//! NaN samples make [`block_rms`], [`SlidingRms`] (while the NaN is inside the window),
//! [`three_phase_rms`] and [`RmsDetector`] (until reset: the NaN enters the filter) return NaN.
//! [`RevolutionPeak`] ignores NaN values when taking its maximum and treats a non-finite spindle
//! speed as standing still.

use std::fmt;

use super::butterworth::{butter, ButterworthSpec, Cutoff, DesignError, FilterKind};
use super::filter::SosFilter;
use super::sos::Sos;

/// The RMS of `samples`, or `None` for an empty slice.
///
/// Sums the squares with Neumaier's compensation, so a block of millions of samples loses no
/// more than a couple of bits.
///
/// ```
/// use cutlab::signal::rms::block_rms;
/// assert_eq!(block_rms(&[3.0, -4.0, 3.0, -4.0]), Some((12.5f64).sqrt()));
/// assert_eq!(block_rms(&[]), None);
/// ```
pub fn block_rms(samples: &[f64]) -> Option<f64> {
    if samples.is_empty() {
        return None;
    }
    let mut sum = 0.0f64;
    let mut compensation = 0.0f64;
    for &x in samples {
        let term = x * x;
        let t = sum + term;
        if sum.abs() >= term.abs() {
            compensation += (sum - t) + term;
        } else {
            compensation += (term - t) + sum;
        }
        sum = t;
    }
    Some(((sum + compensation) / samples.len() as f64).sqrt())
}

/// The RMS of three phase currents at one instant, paper 003 eq 7:
/// `√((i_u² + i_v² + i_w²) / 3)`.
///
/// For balanced sinusoidal phases of amplitude `I` the sum of squares is `3I²/2` at every
/// instant, so this equals the per-phase RMS `I/√2` without averaging over a period: an RMS with
/// no delay.
///
/// ```
/// use cutlab::signal::rms::three_phase_rms;
/// use std::f64::consts::PI;
/// let amplitude_a = 10.0;
/// for theta in [0.0, 0.3, 1.7] {
///     let u = amplitude_a * f64::cos(theta);
///     let v = amplitude_a * f64::cos(theta - 2.0 * PI / 3.0);
///     let w = amplitude_a * f64::cos(theta + 2.0 * PI / 3.0);
///     assert!((three_phase_rms(u, v, w) - amplitude_a / 2f64.sqrt()).abs() < 1e-12);
/// }
/// ```
#[inline(always)]
pub fn three_phase_rms(i_u: f64, i_v: f64, i_w: f64) -> f64 {
    ((i_u * i_u + i_v * i_v + i_w * i_w) / 3.0).sqrt()
}

/// A parameter of an RMS processor that cannot be used.
#[derive(Debug, Clone, PartialEq)]
pub enum RmsError {
    /// The window holds no samples.
    EmptyWindow,
    /// A duration or rate is not a positive finite number.
    NotPositive {
        /// Which parameter.
        name: &'static str,
        /// The value given.
        value: f64,
    },
}

impl fmt::Display for RmsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::EmptyWindow => f.write_str("the RMS window must hold at least one sample"),
            Self::NotPositive { name, value } => {
                write!(f, "{name} must be a positive, finite number, got {value}")
            }
        }
    }
}

impl std::error::Error for RmsError {}

fn positive(name: &'static str, value: f64) -> Result<f64, RmsError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(RmsError::NotPositive { name, value })
    }
}

/// The RMS of the last `window` samples, updated every sample in O(1) amortised time.
///
/// A running sum of squares (add the new square, subtract the one leaving) drifts: every
/// subtraction leaves a rounding error that is never taken back, and after a loud cut the
/// subtraction of large squares wipes out the quiet ones (at 10⁶ A² and 10⁻⁶ A² the quiet RMS
/// is pure noise). This keeps no running difference. It splits the window into an older part,
/// whose suffix sums are computed afresh each time the window has moved by its length, and a
/// newer part summed as it arrives; the window's sum is always one suffix sum plus the newer
/// sum, both sums of non-negative terms, so the relative error stays below `window · ε` forever.
///
/// Until the window has filled, the RMS is over the samples so far.
///
/// ```
/// use cutlab::signal::rms::SlidingRms;
/// let mut rms = SlidingRms::new(4).unwrap();
/// let out: Vec<f64> = [3.0, 3.0, 3.0, 3.0, 0.0, 0.0].iter().map(|&x| rms.process(x)).collect();
/// assert_eq!(out[3], 3.0);
/// assert!((out[5] - (4.5f64).sqrt()).abs() < 1e-15); // two 3s and two 0s
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct SlidingRms {
    window: usize,
    /// Ring buffer of the squares in the window; `next` is where the next square goes (and, once
    /// full, where the oldest one is).
    squares: Vec<f64>,
    next: usize,
    filled: usize,
    /// `suffix[j]`: the sum of the older part's squares from its `j`-th on (`suffix[window]` is
    /// 0), computed when the older part was taken.
    suffix: Vec<f64>,
    /// How many squares of the older part are still inside the window.
    older_left: usize,
    /// The sum of the squares that arrived since the older part was taken.
    newer_sum: f64,
}

impl SlidingRms {
    /// A sliding RMS over `window` samples.
    pub fn new(window: usize) -> Result<Self, RmsError> {
        if window == 0 {
            return Err(RmsError::EmptyWindow);
        }
        Ok(Self {
            window,
            squares: vec![0.0; window],
            next: 0,
            filled: 0,
            suffix: vec![0.0; window + 1],
            older_left: 0,
            newer_sum: 0.0,
        })
    }

    /// A sliding RMS over `window_s` seconds at `sample_rate_hz` (rounded to whole samples, at
    /// least one).
    ///
    /// ```
    /// use cutlab::signal::rms::SlidingRms;
    /// let rms = SlidingRms::with_duration(0.02, 10_000.0).unwrap();
    /// assert_eq!(rms.window(), 200);
    /// ```
    pub fn with_duration(window_s: f64, sample_rate_hz: f64) -> Result<Self, RmsError> {
        let window_s = positive("window duration (s)", window_s)?;
        let rate = positive("sample rate (Hz)", sample_rate_hz)?;
        let samples = (window_s * rate).round().max(1.0);
        if samples > 1e9 {
            return Err(RmsError::NotPositive {
                name: "window duration × sample rate (at most 10⁹ samples)",
                value: samples,
            });
        }
        Self::new(samples as usize)
    }

    /// The window length in samples.
    pub fn window(&self) -> usize {
        self.window
    }

    /// Adds a sample and returns the RMS of the window.
    pub fn process(&mut self, x: f64) -> f64 {
        let square = x * x;
        if self.filled < self.window {
            self.squares[self.next] = square;
            self.next = (self.next + 1) % self.window;
            self.filled += 1;
            self.newer_sum += square;
            return (self.newer_sum / self.filled as f64).sqrt();
        }
        if self.older_left == 0 {
            // The whole window is "newer": make it the older part.
            self.take_older_part();
        }
        // The oldest square leaves; its slot takes the new one.
        self.older_left -= 1;
        self.squares[self.next] = square;
        self.next = (self.next + 1) % self.window;
        self.newer_sum += square;
        let sum = self.suffix[self.window - self.older_left] + self.newer_sum;
        (sum / self.window as f64).sqrt()
    }

    /// Filters `samples` in place into their sliding RMS; the same bits as
    /// [`process`](Self::process) on each.
    pub fn process_slice(&mut self, samples: &mut [f64]) {
        for x in samples {
            *x = self.process(*x);
        }
    }

    /// Empties the window.
    pub fn reset(&mut self) {
        self.squares.fill(0.0);
        self.suffix.fill(0.0);
        self.next = 0;
        self.filled = 0;
        self.older_left = 0;
        self.newer_sum = 0.0;
    }

    fn take_older_part(&mut self) {
        // Oldest first: the oldest square sits at `next`.
        let n = self.window;
        self.suffix[n] = 0.0;
        for j in (0..n).rev() {
            self.suffix[j] = self.suffix[j + 1] + self.squares[(self.next + j) % n];
        }
        self.older_left = n;
        self.newer_sum = 0.0;
    }
}

/// An RMS meter: `√(low-pass(x²))`.
///
/// The low-pass averages the square; its cut-off sets the trade-off between ripple (at twice the
/// current's frequency) and delay. The filtered square can dip below zero during the filter's
/// ringing; that reads as 0.
///
/// ```
/// use cutlab::signal::rms::RmsDetector;
/// let rate_hz = 10_000.0;
/// let mut meter = RmsDetector::butterworth(2, 5.0, rate_hz).unwrap();
/// let mut reading = 0.0;
/// for n in 0..20_000 {
///     let t = n as f64 / rate_hz;
///     reading = meter.process(10.0 * (2.0 * std::f64::consts::PI * 50.0 * t).sin());
/// }
/// assert!((reading - 10.0 / 2f64.sqrt()).abs() < 0.01);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct RmsDetector {
    filter: SosFilter,
}

impl RmsDetector {
    /// A meter whose averaging filter is `lowpass` (its DC gain should be 1).
    pub fn new(lowpass: &Sos) -> Self {
        Self {
            filter: SosFilter::new(lowpass),
        }
    }

    /// A meter averaging with a Butterworth low-pass of `order` and `cutoff_hz`.
    pub fn butterworth(
        order: usize,
        cutoff_hz: f64,
        sample_rate_hz: f64,
    ) -> Result<Self, DesignError> {
        let sos = butter(&ButterworthSpec {
            kind: FilterKind::Lowpass,
            order,
            cutoff_hz: Cutoff::Single(cutoff_hz),
            sample_rate_hz,
        })?;
        Ok(Self::new(&sos))
    }

    /// Adds a sample and returns the current RMS reading.
    pub fn process(&mut self, x: f64) -> f64 {
        let mean_square = self.filter.process(x * x);
        // `!(v < 0)` keeps NaN as NaN (f64::max would turn it into 0).
        if mean_square < 0.0 {
            0.0
        } else {
            mean_square.sqrt()
        }
    }

    /// [`process`](Self::process) on each sample, in place; the same bits.
    pub fn process_slice(&mut self, samples: &mut [f64]) {
        for x in samples {
            *x = self.process(*x);
        }
    }

    /// Back to a reading of 0 with no history.
    pub fn reset(&mut self) {
        self.filter.reset();
    }
}

/// The peak of a signal over each spindle revolution, the revolution tracked by integrating the
/// spindle speed.
///
/// Paper 003 regulates the *peak* force per revolution and relates it to the peak RMS spindle
/// current per revolution; the spindle speed (there from an F/V converter) tells where one
/// revolution ends. `process` returns the peak of the last completed revolution, held until the
/// next one completes, and NaN before the first completes (a chart shows nothing there rather
/// than a false zero). A speed of 0 never completes a revolution; the sign of the speed (the
/// direction) does not matter.
///
/// ```
/// use cutlab::signal::rms::RevolutionPeak;
/// // 600 rpm = 10 rev/s at 1 kHz: 100 samples per revolution.
/// let mut peak = RevolutionPeak::new(1_000.0).unwrap();
/// let mut held = f64::NAN;
/// for n in 0..250 {
///     let rms_a = if n == 42 { 7.5 } else { 1.0 + (n % 100) as f64 * 0.01 };
///     held = peak.process(rms_a, 600.0);
/// }
/// assert_eq!(peak.completed_revolutions(), 2);
/// assert_eq!(held, 1.99); // the second revolution's largest value
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct RevolutionPeak {
    sample_interval_s: f64,
    /// Fraction of the current revolution done, in [0, 1).
    phase_rev: f64,
    /// The largest non-NaN value of the current revolution so far.
    running_peak: Option<f64>,
    held_peak: f64,
    revolutions: u64,
}

impl RevolutionPeak {
    /// A tracker for samples at `sample_rate_hz`.
    pub fn new(sample_rate_hz: f64) -> Result<Self, RmsError> {
        let rate = positive("sample rate (Hz)", sample_rate_hz)?;
        Ok(Self {
            sample_interval_s: 1.0 / rate,
            phase_rev: 0.0,
            running_peak: None,
            held_peak: f64::NAN,
            revolutions: 0,
        })
    }

    /// Adds one sample of the signal with the spindle speed at that instant; returns the held
    /// peak of the last completed revolution (NaN before the first).
    pub fn process(&mut self, value: f64, spindle_rpm: f64) -> f64 {
        if !value.is_nan() && self.running_peak.is_none_or(|peak| value > peak) {
            self.running_peak = Some(value);
        }
        let revs_per_s = if spindle_rpm.is_finite() {
            spindle_rpm.abs() / 60.0
        } else {
            0.0
        };
        self.phase_rev += revs_per_s * self.sample_interval_s;
        if self.phase_rev >= 1.0 {
            // Faster than one revolution per sample counts once: the samples cannot resolve it.
            self.phase_rev = (self.phase_rev - 1.0).fract();
            self.revolutions += 1;
            // A revolution of only NaN values holds NaN.
            self.held_peak = self.running_peak.take().unwrap_or(f64::NAN);
        }
        self.held_peak
    }

    /// [`process`](Self::process) over paired slices, writing the held peaks to `held_peak`; the
    /// same bits as sample by sample.
    ///
    /// # Panics
    ///
    /// If the three slices differ in length (a bug in the caller).
    pub fn process_slice(&mut self, values: &[f64], spindle_rpm: &[f64], held_peak: &mut [f64]) {
        assert!(
            values.len() == spindle_rpm.len() && values.len() == held_peak.len(),
            "values, speeds and outputs must be equally long"
        );
        for ((v, rpm), out) in values.iter().zip(spindle_rpm).zip(held_peak) {
            *out = self.process(*v, *rpm);
        }
    }

    /// The number of revolutions completed.
    pub fn completed_revolutions(&self) -> u64 {
        self.revolutions
    }

    /// The peak of the last completed revolution, if any.
    pub fn last_peak(&self) -> Option<f64> {
        (self.revolutions > 0).then_some(self.held_peak)
    }

    /// Back to the start of a revolution with nothing held.
    pub fn reset(&mut self) {
        self.phase_rev = 0.0;
        self.running_peak = None;
        self.held_peak = f64::NAN;
        self.revolutions = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn sliding_rms_equals_block_rms_of_the_window_after_millions_of_samples() {
        let window = 1000;
        let mut sliding = SlidingRms::new(window).unwrap();
        let mut rng = Rng::seed_from(5);
        let mut recent = std::collections::VecDeque::new();
        let mut last = 0.0;
        for n in 0..2_000_000u32 {
            // Loud, then very quiet: a running sum would be left with the loud part's rounding.
            let scale = if n < 1_000_000 { 1e6 } else { 1e-6 };
            let x = scale * rng.normal();
            last = sliding.process(x);
            recent.push_back(x);
            if recent.len() > window {
                recent.pop_front();
            }
        }
        let exact = block_rms(recent.make_contiguous()).unwrap();
        assert!((last - exact).abs() <= 1e-12 * exact, "{last} vs {exact}");
    }

    #[test]
    fn sliding_slice_equals_per_sample_and_reset_restores_the_start() {
        let mut rng = Rng::seed_from(2);
        let x: Vec<f64> = (0..5000).map(|_| rng.normal()).collect();
        let mut a = SlidingRms::new(37).unwrap();
        let expected: Vec<f64> = x.iter().map(|&v| a.process(v)).collect();
        let mut b = SlidingRms::new(37).unwrap();
        let mut y = x.clone();
        b.process_slice(&mut y);
        assert_eq!(y, expected);
        b.reset();
        assert_eq!(b, SlidingRms::new(37).unwrap());
    }

    #[test]
    fn detector_slice_equals_per_sample() {
        let mut a = RmsDetector::butterworth(2, 10.0, 1000.0).unwrap();
        let x: Vec<f64> = (0..500).map(|i| (i as f64 * 0.3).sin()).collect();
        let expected: Vec<f64> = x.iter().map(|&v| a.process(v)).collect();
        let mut b = RmsDetector::butterworth(2, 10.0, 1000.0).unwrap();
        let mut y = x;
        b.process_slice(&mut y);
        assert_eq!(y, expected);
    }

    #[test]
    fn revolution_peak_follows_the_spindle_speed() {
        // 3840 rpm at 8192 Hz: exactly 128 samples per revolution (binary fractions, so the
        // boundaries fall on known samples); then 1920 rpm: 256.
        let mut peak = RevolutionPeak::new(8192.0).unwrap();
        let mut completions = Vec::new();
        for n in 0..1000 {
            let rpm = if n < 512 { 3840.0 } else { 1920.0 };
            let before = peak.completed_revolutions();
            peak.process(n as f64, rpm);
            if peak.completed_revolutions() > before {
                completions.push(n);
            }
        }
        assert_eq!(completions, [127, 255, 383, 511, 767]);
        assert_eq!(peak.last_peak(), Some(767.0));
        peak.reset();
        assert!(peak.process(1.0, 0.0).is_nan());
        assert_eq!(peak.last_peak(), None);
    }

    #[test]
    fn bad_parameters_are_errors() {
        assert_eq!(SlidingRms::new(0), Err(RmsError::EmptyWindow));
        assert!(SlidingRms::with_duration(-1.0, 1e4).is_err());
        assert!(RevolutionPeak::new(f64::NAN).is_err());
        assert!(RmsDetector::butterworth(0, 5.0, 1e3).is_err());
    }

    #[test]
    fn nan_propagates_where_documented() {
        assert!(block_rms(&[1.0, f64::NAN]).unwrap().is_nan());
        assert!(three_phase_rms(f64::NAN, 0.0, 0.0).is_nan());
        let mut d = RmsDetector::butterworth(1, 10.0, 1000.0).unwrap();
        assert!(d.process(f64::NAN).is_nan());
        let mut p = RevolutionPeak::new(128.0).unwrap();
        for _ in 0..128 {
            p.process(f64::NAN, 60.0);
        }
        // One revolution of only NaN values holds NaN.
        assert_eq!(p.completed_revolutions(), 1);
        assert!(p.last_peak().unwrap().is_nan());
    }
}
