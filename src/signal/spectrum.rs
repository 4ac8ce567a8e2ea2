//! Spectra of motor current: where the cutting load shows up in frequency.
//!
//! - [`amplitude_spectrum`]: single-sided amplitude spectrum with a choice of [`Window`], scaled
//!   so that a sine of amplitude `A` reads `A` (exactly on a bin for every window, anywhere to
//!   within 0.1 % with the flat-top). Paper 000 finds the load in a 4 Hz peak of such a spectrum.
//! - [`welch`]: power spectral density by Welch's method, equal to `scipy.signal.welch(x, fs,
//!   nperseg=n)` with its defaults (periodic Hann window, 50 % overlap, each segment's mean
//!   removed, density scaling, one-sided, mean of the segments).
//! - [`find_peaks`]: the largest local maxima, with a parabolic refinement of their frequency.
//! - [`milling_markers`]: spindle and tooth-passing frequencies and their harmonics, to draw over
//!   a spectrum.
//! - [`uniform_sample_rate_hz`]: checks that time stamps are evenly spaced and reports the first
//!   step that is not, instead of silently assuming a rate. [`amplitude_spectrum_of_log`] and
//!   [`welch_of_log`] go through it.
//!
//! The FFT is rustfft's; its twiddle factors come from the platform's `sin`/`cos`, so spectra may
//! differ between native and wasm in the last bit. NaN or ±∞ in a segment makes every bin of that
//! segment's transform NaN.

use std::fmt;
use std::str::FromStr;
use std::sync::Arc;

use rustfft::algorithm::butterflies::Butterfly5;
use rustfft::algorithm::{BluesteinsAlgorithm, MixedRadix, Radix4};
use rustfft::num_complex::Complex64;
use rustfft::{Fft, FftDirection};

use crate::math;

/// Relative deviation of a time step from the mean step that [`amplitude_spectrum_of_log`] and
/// [`welch_of_log`] accept (1 %).
pub const TIME_STEP_TOLERANCE: f64 = 0.01;

/// A tapering window for spectra (periodic form, as for FFT analysis).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum Window {
    /// No taper: the sharpest peaks, the most leakage and up to 36 % amplitude error between bins.
    Rectangular,
    /// Hann: the usual compromise; up to 15 % amplitude error between bins.
    Hann,
    /// Flat-top (scipy's coefficients): wide peaks, amplitude right to 0.1 % anywhere.
    FlatTop,
}

impl Window {
    /// Every window, in the order the UI lists them.
    pub const ALL: [Window; 3] = [Window::Rectangular, Window::Hann, Window::FlatTop];

    /// A label for people.
    ///
    /// ```
    /// use cutlab::signal::spectrum::Window;
    /// assert_eq!(Window::FlatTop.label(), "Flat-top");
    /// ```
    pub fn label(self) -> &'static str {
        match self {
            Self::Rectangular => "Rectangular",
            Self::Hann => "Hann",
            Self::FlatTop => "Flat-top",
        }
    }

    /// The machine name: `"rectangular"`, `"hann"`, `"flattop"`.
    ///
    /// ```
    /// use cutlab::signal::spectrum::Window;
    /// for w in Window::ALL {
    ///     assert_eq!(w.name().parse::<Window>().unwrap(), w);
    /// }
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            Self::Rectangular => "rectangular",
            Self::Hann => "hann",
            Self::FlatTop => "flattop",
        }
    }

    /// The `len` window coefficients (periodic: the window of length `len + 1` without its last
    /// point, so its DFT has no leakage between harmonics of the segment).
    ///
    /// ```
    /// use cutlab::signal::spectrum::Window;
    /// let w = Window::Hann.coefficients(4);
    /// let expected = [0.0, 0.5, 1.0, 0.5];
    /// assert!(w.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-15));
    /// ```
    pub fn coefficients(self, len: usize) -> Vec<f64> {
        // As scipy.signal.get_window: a one-point window of any kind is [1], not the cosine
        // sum's value at zero (0 for Hann), which would make a one-sample segment's PSD 0/0.
        if len <= 1 {
            return vec![1.0; len];
        }
        let cosine_sum = |a: &[f64]| -> Vec<f64> {
            (0..len)
                .map(|n| {
                    let x = 2.0 * std::f64::consts::PI * n as f64 / len as f64;
                    a.iter()
                        .enumerate()
                        .map(|(k, ak)| {
                            let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                            sign * ak * math::cos(k as f64 * x)
                        })
                        .sum()
                })
                .collect()
        };
        match self {
            Self::Rectangular => vec![1.0; len],
            Self::Hann => cosine_sum(&[0.5, 0.5]),
            Self::FlatTop => cosine_sum(&[
                0.215_578_95,
                0.416_631_58,
                0.277_263_158,
                0.083_578_947,
                0.006_947_368,
            ]),
        }
    }
}

impl FromStr for Window {
    type Err = SpectrumError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let key = text
            .trim()
            .to_ascii_lowercase()
            .replace(['-', ' ', '_'], "");
        match key.as_str() {
            "rectangular" | "rect" | "boxcar" | "none" => Ok(Self::Rectangular),
            "hann" | "hanning" => Ok(Self::Hann),
            "flattop" => Ok(Self::FlatTop),
            _ => Err(SpectrumError::UnknownWindow(text.to_string())),
        }
    }
}

/// Why a spectrum could not be computed.
#[derive(Debug, Clone, PartialEq)]
pub enum SpectrumError {
    /// Not enough samples (or time stamps) for the computation.
    TooFewSamples {
        /// Samples given.
        samples: usize,
        /// Samples needed.
        needed: usize,
    },
    /// The sampling rate is not a positive finite number.
    SampleRate {
        /// The rate given, Hz.
        sample_rate_hz: f64,
    },
    /// The Welch segment length is zero.
    SegmentLength,
    /// Time stamps and values differ in number.
    LengthMismatch {
        /// Number of time stamps.
        times: usize,
        /// Number of values.
        values: usize,
    },
    /// A time stamp is not finite or not after the one before it.
    TimeNotIncreasing {
        /// Index of the offending time stamp.
        index: usize,
        /// Its value, s.
        time_s: f64,
    },
    /// A time step differs from the median step by more than the tolerance.
    UnevenTimeSteps {
        /// Index of the time stamp that ends the offending step.
        index: usize,
        /// The step, s.
        step_s: f64,
        /// The median step, s.
        median_step_s: f64,
        /// The relative tolerance.
        tolerance: f64,
    },
    /// A window name that is not one of [`Window::ALL`].
    UnknownWindow(String),
}

impl fmt::Display for SpectrumError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::TooFewSamples { samples, needed } => {
                write!(f, "need at least {needed} samples, got {samples}")
            }
            Self::SampleRate { sample_rate_hz } => write!(
                f,
                "sample rate must be a positive, finite number of Hz, got {sample_rate_hz}"
            ),
            Self::SegmentLength => f.write_str("segment length (nperseg) must be at least 1"),
            Self::LengthMismatch { times, values } => write!(
                f,
                "{times} time stamps but {values} values: each value needs its time stamp"
            ),
            Self::TimeNotIncreasing { index, time_s } => write!(
                f,
                "time stamp {index} ({time_s} s) is not after the one before it"
            ),
            Self::UnevenTimeSteps {
                index,
                step_s,
                median_step_s,
                tolerance,
            } => write!(
                f,
                "uneven sampling: the step ending at time stamp {index} is {step_s} s, but the \
                 median step is {median_step_s} s (tolerance {}%); resample the log to a fixed \
                 rate first",
                tolerance * 100.0
            ),
            Self::UnknownWindow(name) => write!(
                f,
                "unknown window {name:?}; windows: rectangular, hann, flattop"
            ),
        }
    }
}

impl std::error::Error for SpectrumError {}

/// A forward FFT of `n` ≥ 1 points from a few of rustfft's algorithms: radix-4 for a power of
/// two, a mixed radix of radix-4 and radix-5 stages for 2^a·5^b (the lengths of whole seconds or
/// tenths at the lab's rates: 4 s at 10 kHz is 2⁶·5⁴), and Bluestein's (through a radix-4 FFT of
/// at least 2n − 1 points) for any other length. rustfft's planner chooses among a dozen
/// algorithms by length and so links all of them (~150 KB of the browser's download); these are
/// as accurate for spectra (tests/signal_spectrum.rs holds Welch's bins to scipy's within a
/// relative 1e-9). Bluestein's costs two FFTs of the padded length, about six times the mixed
/// radix's work for 40 000 points: 40 ms of a page's task in the browser.
fn forward_fft(n: usize) -> Arc<dyn Fft<f64>> {
    let n = n.max(1);
    let twos = 1usize << n.trailing_zeros();
    let odd = n / twos;
    let radix4 =
        |len: usize| -> Arc<dyn Fft<f64>> { Arc::new(Radix4::new(len, FftDirection::Forward)) };
    if odd == 1 {
        radix4(n)
    } else if let Some(fives) = power_of_five_fft(odd) {
        if twos == 1 {
            fives
        } else {
            Arc::new(MixedRadix::new(radix4(twos), fives))
        }
    } else {
        Arc::new(BluesteinsAlgorithm::new(
            n,
            radix4((2 * n - 1).next_power_of_two()),
        ))
    }
}

/// A forward FFT of `len` = 5^b points (b ≥ 1) as radix-5 stages, or `None` for another length.
fn power_of_five_fft(len: usize) -> Option<Arc<dyn Fft<f64>>> {
    let butterfly = || -> Arc<dyn Fft<f64>> { Arc::new(Butterfly5::new(FftDirection::Forward)) };
    match len {
        5 => Some(butterfly()),
        _ if len > 5 && len.is_multiple_of(5) => {
            let rest = power_of_five_fft(len / 5)?;
            Some(Arc::new(MixedRadix::new(butterfly(), rest)))
        }
        _ => None,
    }
}

fn check_rate(sample_rate_hz: f64) -> Result<(), SpectrumError> {
    if sample_rate_hz.is_finite() && sample_rate_hz > 0.0 {
        Ok(())
    } else {
        Err(SpectrumError::SampleRate { sample_rate_hz })
    }
}

/// A single-sided amplitude spectrum: `amplitude[k]` is the amplitude of the sine at
/// `freq_hz[k]`, in the unit of the samples (the DC bin is the mean).
#[derive(Debug, Clone, PartialEq)]
pub struct AmplitudeSpectrum {
    /// Bin frequencies `k · f_s / N`, `k = 0 ..= N/2`, Hz.
    pub freq_hz: Vec<f64>,
    /// Amplitude at each bin.
    pub amplitude: Vec<f64>,
    /// The window used.
    pub window: Window,
}

/// The single-sided amplitude spectrum of `samples` taken at `sample_rate_hz`, tapered by
/// `window`.
///
/// `|X_k|` is divided by the window's sum, which makes a sine exactly on a bin read its
/// amplitude whatever the window, and doubled except at DC and at Nyquist (even `N`), which have
/// no mirror image.
///
/// ```
/// use cutlab::signal::spectrum::{amplitude_spectrum, Window};
/// let rate_hz = 1000.0;
/// // 3 A at 40 Hz, exactly on a bin (N = 1000 gives 1 Hz bins), on 0.5 A DC.
/// let x: Vec<f64> = (0..1000)
///     .map(|n| 0.5 + 3.0 * (2.0 * std::f64::consts::PI * 40.0 * n as f64 / rate_hz).sin())
///     .collect();
/// for window in Window::ALL {
///     let s = amplitude_spectrum(&x, rate_hz, window).unwrap();
///     assert_eq!(s.freq_hz[40], 40.0);
///     assert!((s.amplitude[40] - 3.0).abs() < 1e-9, "{window:?}");
///     assert!((s.amplitude[0] - 0.5).abs() < 1e-9);
/// }
/// ```
pub fn amplitude_spectrum(
    samples: &[f64],
    sample_rate_hz: f64,
    window: Window,
) -> Result<AmplitudeSpectrum, SpectrumError> {
    check_rate(sample_rate_hz)?;
    let n = samples.len();
    if n < 2 {
        return Err(SpectrumError::TooFewSamples {
            samples: n,
            needed: 2,
        });
    }
    let w = window.coefficients(n);
    let window_sum: f64 = w.iter().sum();
    let mut buffer: Vec<Complex64> = samples
        .iter()
        .zip(&w)
        .map(|(x, wi)| Complex64::new(x * wi, 0.0))
        .collect();
    forward_fft(n).process(&mut buffer);
    let bins = n / 2 + 1;
    let amplitude = buffer[..bins]
        .iter()
        .enumerate()
        .map(|(k, x)| {
            let unpaired = k == 0 || (n.is_multiple_of(2) && k == n / 2);
            let scale = if unpaired { 1.0 } else { 2.0 };
            scale * x.norm() / window_sum
        })
        .collect();
    Ok(AmplitudeSpectrum {
        freq_hz: bin_frequencies(bins, n, sample_rate_hz),
        amplitude,
        window,
    })
}

fn bin_frequencies(bins: usize, n: usize, sample_rate_hz: f64) -> Vec<f64> {
    // numpy's rfftfreq: k · (1 / (n · d)) with d = 1/fs.
    let step = 1.0 / (n as f64 * (1.0 / sample_rate_hz));
    (0..bins).map(|k| k as f64 * step).collect()
}

/// A one-sided power spectral density, in (unit of the samples)²/Hz.
#[derive(Debug, Clone, PartialEq)]
pub struct Psd {
    /// Bin frequencies, Hz.
    pub freq_hz: Vec<f64>,
    /// Power spectral density at each bin.
    pub psd: Vec<f64>,
    /// The segment length actually used (shorter input shortens it, as scipy does).
    pub segment_len: usize,
    /// How many segments were averaged.
    pub segments: usize,
}

/// Welch's power spectral density, equal to `scipy.signal.welch(samples, fs=sample_rate_hz,
/// nperseg=segment_len)`: periodic Hann window, `segment_len / 2` overlap, each segment's mean
/// removed, density scaling `1/(f_s·Σw²)`, one-sided (doubled except DC and an even length's
/// Nyquist bin), the mean over segments. A `segment_len` longer than the input is shortened to
/// it, as scipy does (scipy also warns).
///
/// ```
/// use cutlab::signal::spectrum::welch;
/// let rate_hz = 1000.0;
/// // White noise of variance σ² has a flat one-sided density 2σ²/f_s; a deterministic check:
/// // a sine of amplitude A carries power A²/2, the integral of its peak.
/// let x: Vec<f64> = (0..4096)
///     .map(|n| 2.0 * (2.0 * std::f64::consts::PI * 125.0 * n as f64 / rate_hz).sin())
///     .collect();
/// let p = welch(&x, rate_hz, 256).unwrap();
/// assert_eq!(p.freq_hz.len(), 129);
/// assert_eq!(p.segments, 31);
/// let df = p.freq_hz[1];
/// let power: f64 = p.psd.iter().sum::<f64>() * df;
/// assert!((power - 2.0).abs() < 0.05 * 2.0);
/// ```
pub fn welch(
    samples: &[f64],
    sample_rate_hz: f64,
    segment_len: usize,
) -> Result<Psd, SpectrumError> {
    check_rate(sample_rate_hz)?;
    if segment_len == 0 {
        return Err(SpectrumError::SegmentLength);
    }
    if samples.is_empty() {
        return Err(SpectrumError::TooFewSamples {
            samples: 0,
            needed: 1,
        });
    }
    let nperseg = segment_len.min(samples.len());
    let noverlap = nperseg / 2;
    let step = nperseg - noverlap;
    let segments = (samples.len() - noverlap) / step;
    let window = Window::Hann.coefficients(nperseg);
    let window_power: f64 = window.iter().map(|w| w * w).sum();
    let scale = 1.0 / (sample_rate_hz * window_power);
    let bins = nperseg / 2 + 1;
    let fft = forward_fft(nperseg);
    let mut buffer = vec![Complex64::new(0.0, 0.0); nperseg];
    let mut scratch = vec![Complex64::new(0.0, 0.0); fft.get_inplace_scratch_len()];
    let mut sum = vec![0.0; bins];
    for s in 0..segments {
        let segment = &samples[s * step..s * step + nperseg];
        let mean = segment.iter().sum::<f64>() / nperseg as f64;
        for ((b, x), w) in buffer.iter_mut().zip(segment).zip(&window) {
            *b = Complex64::new(w * (x - mean), 0.0);
        }
        fft.process_with_scratch(&mut buffer, &mut scratch);
        for (k, (acc, x)) in sum.iter_mut().zip(&buffer).enumerate() {
            let unpaired = k == 0 || (nperseg.is_multiple_of(2) && k == nperseg / 2);
            let doubling = if unpaired { 1.0 } else { 2.0 };
            *acc += x.norm_sqr() * scale * doubling;
        }
    }
    let psd = sum.iter().map(|p| p / segments as f64).collect();
    Ok(Psd {
        freq_hz: bin_frequencies(bins, nperseg, sample_rate_hz),
        psd,
        segment_len: nperseg,
        segments,
    })
}

/// Checks that `times_s` are evenly spaced and returns the sampling rate.
///
/// Every step must be within `relative_tolerance` of the median step (the median, so that one
/// gap does not shift the reference); the error names the first time stamp that is not (a dropped
/// sample, a pause in logging, a clock jump). The rate returned is `(n − 1) / (t_last − t_first)`.
///
/// ```
/// use cutlab::signal::spectrum::uniform_sample_rate_hz;
/// let even: Vec<f64> = (0..100).map(|n| n as f64 * 1e-3).collect();
/// assert!((uniform_sample_rate_hz(&even, 0.01).unwrap() - 1000.0).abs() < 1e-6);
/// let mut gap = even.clone();
/// gap.remove(50); // a dropped sample
/// let e = uniform_sample_rate_hz(&gap, 0.01).unwrap_err();
/// assert!(e.to_string().contains("time stamp 50"), "{e}");
/// ```
pub fn uniform_sample_rate_hz(
    times_s: &[f64],
    relative_tolerance: f64,
) -> Result<f64, SpectrumError> {
    if times_s.len() < 2 {
        return Err(SpectrumError::TooFewSamples {
            samples: times_s.len(),
            needed: 2,
        });
    }
    for (i, w) in times_s.windows(2).enumerate() {
        if !(w[0].is_finite() && w[1].is_finite() && w[1] > w[0]) {
            let index = if w[0].is_finite() { i + 1 } else { i };
            return Err(SpectrumError::TimeNotIncreasing {
                index,
                time_s: times_s[index],
            });
        }
    }
    let median_step_s = super::stats::median(times_s.windows(2).map(|w| w[1] - w[0]));
    let tolerance = relative_tolerance.abs();
    for (i, w) in times_s.windows(2).enumerate() {
        let step_s = w[1] - w[0];
        if (step_s - median_step_s).abs() > tolerance * median_step_s {
            return Err(SpectrumError::UnevenTimeSteps {
                index: i + 1,
                step_s,
                median_step_s,
                tolerance,
            });
        }
    }
    let span_s = times_s[times_s.len() - 1] - times_s[0];
    Ok((times_s.len() - 1) as f64 / span_s)
}

fn check_log(times_s: &[f64], values: &[f64]) -> Result<f64, SpectrumError> {
    if times_s.len() != values.len() {
        return Err(SpectrumError::LengthMismatch {
            times: times_s.len(),
            values: values.len(),
        });
    }
    uniform_sample_rate_hz(times_s, TIME_STEP_TOLERANCE)
}

/// [`amplitude_spectrum`] of a time-stamped log, after checking that the stamps are evenly
/// spaced (within [`TIME_STEP_TOLERANCE`]).
///
/// ```
/// use cutlab::signal::spectrum::{amplitude_spectrum_of_log, Window};
/// let t: Vec<f64> = vec![0.0, 0.001, 0.002, 0.0035];
/// let e = amplitude_spectrum_of_log(&t, &[1.0; 4], Window::Hann).unwrap_err();
/// assert!(e.to_string().starts_with("uneven sampling"));
/// ```
pub fn amplitude_spectrum_of_log(
    times_s: &[f64],
    values: &[f64],
    window: Window,
) -> Result<AmplitudeSpectrum, SpectrumError> {
    let rate = check_log(times_s, values)?;
    amplitude_spectrum(values, rate, window)
}

/// [`welch`] of a time-stamped log, after checking that the stamps are evenly spaced (within
/// [`TIME_STEP_TOLERANCE`]).
///
/// ```
/// use cutlab::signal::spectrum::welch_of_log;
/// let t: Vec<f64> = (0..512).map(|n| n as f64 / 1000.0).collect();
/// let x: Vec<f64> = t.iter().map(|t| (t * 600.0).sin()).collect();
/// let p = welch_of_log(&t, &x, 128).unwrap();
/// assert!((p.freq_hz[1] - 1000.0 / 128.0).abs() < 1e-6);
/// ```
pub fn welch_of_log(
    times_s: &[f64],
    values: &[f64],
    segment_len: usize,
) -> Result<Psd, SpectrumError> {
    let rate = check_log(times_s, values)?;
    welch(values, rate, segment_len)
}

/// A local maximum of a spectrum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Peak {
    /// Bin index.
    pub index: usize,
    /// The bin's frequency, Hz.
    pub freq_hz: f64,
    /// The frequency refined by the parabola through the bin and its neighbours, Hz.
    pub interpolated_freq_hz: f64,
    /// The value at the bin.
    pub value: f64,
}

/// The `max_peaks` largest interior local maxima of `values` (a bin above its left neighbour and
/// not below its right one) at or above `min_freq_hz`, largest first. NaN bins are never peaks
/// and break no comparison.
///
/// `min_freq_hz` keeps the DC component's main lobe out: a window spreads DC over a few bins, and
/// the one-sided doubling (bins above 0 count twice, DC once) can make the first of them a local
/// maximum.
///
/// ```
/// use cutlab::signal::spectrum::find_peaks;
/// let f = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
/// let v = [9.0, 1.0, 3.0, 1.0, 0.5, 2.0, 0.1];
/// let peaks = find_peaks(&f, &v, 0.0, 5);
/// assert_eq!(peaks.iter().map(|p| p.freq_hz).collect::<Vec<_>>(), [2.0, 5.0]);
/// assert_eq!(peaks[0].interpolated_freq_hz, 2.0); // symmetric neighbours
/// assert_eq!(find_peaks(&f, &v, 3.0, 5).len(), 1);
/// ```
pub fn find_peaks(
    freq_hz: &[f64],
    values: &[f64],
    min_freq_hz: f64,
    max_peaks: usize,
) -> Vec<Peak> {
    let n = freq_hz.len().min(values.len());
    let mut peaks: Vec<Peak> = (1..n.saturating_sub(1))
        .filter(|&i| freq_hz[i] >= min_freq_hz)
        .filter(|&i| values[i] > values[i - 1] && values[i] >= values[i + 1])
        .map(|i| {
            let (left, centre, right) = (values[i - 1], values[i], values[i + 1]);
            let curvature = left - 2.0 * centre + right;
            let offset = if curvature < 0.0 {
                (0.5 * (left - right) / curvature).clamp(-0.5, 0.5)
            } else {
                0.0
            };
            let spacing = 0.5 * (freq_hz[i + 1] - freq_hz[i - 1]);
            Peak {
                index: i,
                freq_hz: freq_hz[i],
                interpolated_freq_hz: freq_hz[i] + offset * spacing,
                value: centre,
            }
        })
        .collect();
    peaks.sort_by(|a, b| b.value.total_cmp(&a.value));
    peaks.truncate(max_peaks);
    peaks
}

/// What a [`Marker`] marks.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MarkerKind {
    /// A harmonic of the spindle rotation frequency `rpm / 60` (run-out, unbalance).
    Spindle,
    /// A harmonic of the tooth-passing frequency `teeth · rpm / 60` (the cutting force's own
    /// rhythm). Spindle harmonics that coincide with one are marked as this.
    ToothPassing,
}

/// A frequency to draw over a spectrum.
#[derive(Debug, Clone, PartialEq)]
pub struct Marker {
    /// The frequency, Hz.
    pub freq_hz: f64,
    /// Spindle or tooth-passing.
    pub kind: MarkerKind,
    /// Which multiple of the base frequency (1 = the fundamental).
    pub harmonic: u32,
    /// A short label, e.g. `"tooth 2×"`.
    pub label: String,
}

/// Spindle and tooth-passing frequencies with their harmonics up to `max_freq_hz`, sorted by
/// frequency, at most `max_harmonic` of each. A non-finite or zero speed gives no markers; zero
/// teeth gives only spindle markers. The sign of the speed (direction) does not matter.
///
/// ```
/// use cutlab::signal::spectrum::{milling_markers, MarkerKind};
/// // 3000 rpm, 2 teeth: spindle 50 Hz, tooth passing 100 Hz.
/// let m = milling_markers(3000.0, 2, 210.0, 10);
/// let listed: Vec<(f64, MarkerKind)> = m.iter().map(|m| (m.freq_hz, m.kind)).collect();
/// assert_eq!(
///     listed,
///     [
///         (50.0, MarkerKind::Spindle),
///         (100.0, MarkerKind::ToothPassing),
///         (150.0, MarkerKind::Spindle),
///         (200.0, MarkerKind::ToothPassing),
///     ]
/// );
/// assert_eq!(m[1].label, "tooth 1×");
/// ```
pub fn milling_markers(
    spindle_rpm: f64,
    teeth: u32,
    max_freq_hz: f64,
    max_harmonic: u32,
) -> Vec<Marker> {
    let spindle_hz = spindle_rpm.abs() / 60.0;
    if !(spindle_hz.is_finite() && spindle_hz > 0.0) {
        return Vec::new();
    }
    let mut markers = Vec::new();
    for h in 1..=max_harmonic {
        let freq_hz = f64::from(h) * spindle_hz;
        if freq_hz > max_freq_hz {
            break;
        }
        if teeth > 0 && h % teeth == 0 {
            let harmonic = h / teeth;
            markers.push(Marker {
                freq_hz,
                kind: MarkerKind::ToothPassing,
                harmonic,
                label: format!("tooth {harmonic}×"),
            });
        } else {
            markers.push(Marker {
                freq_hz,
                kind: MarkerKind::Spindle,
                harmonic: h,
                label: format!("spindle {h}×"),
            });
        }
    }
    // Tooth-passing harmonics beyond the spindle harmonics listed (max_harmonic counts each kind).
    if teeth > 0 {
        let listed = markers
            .iter()
            .filter(|m| m.kind == MarkerKind::ToothPassing)
            .count() as u32;
        for harmonic in listed + 1..=max_harmonic {
            let freq_hz = f64::from(harmonic) * f64::from(teeth) * spindle_hz;
            if freq_hz > max_freq_hz {
                break;
            }
            markers.push(Marker {
                freq_hz,
                kind: MarkerKind::ToothPassing,
                harmonic,
                label: format!("tooth {harmonic}×"),
            });
        }
    }
    markers.sort_by(|a, b| a.freq_hz.total_cmp(&b.freq_hz));
    markers
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn tone(n: usize, rate_hz: f64, freq_hz: f64, amplitude: f64) -> Vec<f64> {
        (0..n)
            .map(|i| amplitude * (2.0 * PI * freq_hz * i as f64 / rate_hz).sin())
            .collect()
    }

    #[test]
    fn every_plan_computes_the_discrete_fourier_transform() {
        // Radix-4 (16, 2), the mixed radix-4/5 plans (5, 10, 40, 125, 250, 2000) and
        // Bluestein's (3, 7, 12, 15, 45): each against the transform summed term by term.
        for n in [1, 2, 16, 5, 10, 40, 125, 250, 2000, 3, 7, 12, 15, 45] {
            let x: Vec<Complex64> = (0..n)
                .map(|i| Complex64::new((0.37 * i as f64).sin() + 0.1, (0.11 * i as f64).cos()))
                .collect();
            let mut fast = x.clone();
            forward_fft(n).process(&mut fast);
            let scale = x.iter().map(|v| v.norm()).sum::<f64>();
            for (k, got) in fast.iter().enumerate() {
                let exact: Complex64 = x
                    .iter()
                    .enumerate()
                    .map(|(i, v)| {
                        let angle = -2.0 * PI * ((i * k) % n) as f64 / n as f64;
                        v * Complex64::new(angle.cos(), angle.sin())
                    })
                    .sum();
                assert!(
                    (got - exact).norm() <= 1e-12 * scale,
                    "n {n}, bin {k}: {got} vs {exact}"
                );
            }
        }
    }

    #[test]
    fn flat_top_reads_the_amplitude_between_bins_and_hann_does_not() {
        // 40.5 Hz with 1 Hz bins: half a bin off, the worst case.
        let x = tone(1000, 1000.0, 40.5, 2.0);
        let read = |w: Window| {
            let s = amplitude_spectrum(&x, 1000.0, w).unwrap();
            s.amplitude.iter().copied().fold(0.0, f64::max)
        };
        assert!((read(Window::FlatTop) - 2.0).abs() < 0.002 * 2.0);
        let hann = read(Window::Hann);
        assert!(hann < 0.9 * 2.0 && hann > 0.8 * 2.0, "{hann}");
        let rect = read(Window::Rectangular);
        assert!(rect < 0.7 * 2.0, "{rect}");
    }

    #[test]
    fn welch_integrates_to_the_variance() {
        let mut rng = crate::rng::Rng::seed_from(11);
        let x: Vec<f64> = (0..100_000).map(|_| 3.0 * rng.normal()).collect();
        let p = welch(&x, 2000.0, 512).unwrap();
        let df = p.freq_hz[1] - p.freq_hz[0];
        let variance: f64 = p.psd.iter().sum::<f64>() * df;
        assert!((variance - 9.0).abs() < 0.2, "{variance}");
    }

    #[test]
    fn welch_shortens_the_segment_to_the_input_like_scipy() {
        let p = welch(&[1.0, 2.0, 0.0, -1.0, 3.0], 10.0, 256).unwrap();
        assert_eq!((p.segment_len, p.segments, p.freq_hz.len()), (5, 1, 3));
        assert!(welch(&[], 10.0, 8).is_err());
        assert!(welch(&[1.0], 10.0, 0).is_err());
        assert!(welch(&[1.0], 0.0, 8).is_err());
    }

    #[test]
    fn one_sample_segments_give_zero_power_like_scipy() {
        // scipy.signal.welch([3.0, 1.0, 2.0], fs=10, nperseg=1) == ([0.], [0.]): a one-point
        // window is [1] and the segment minus its mean is 0, not 0/0.
        assert_eq!(Window::Hann.coefficients(1), [1.0]);
        assert_eq!(Window::FlatTop.coefficients(1), [1.0]);
        let p = welch(&[3.0, 1.0, 2.0], 10.0, 1).unwrap();
        assert_eq!(
            (p.freq_hz.as_slice(), p.psd.as_slice()),
            (&[0.0][..], &[0.0][..])
        );
    }

    #[test]
    fn the_4_hz_peak_of_paper_000_is_found() {
        let rate = 1000.0;
        let x: Vec<f64> = (0..8000)
            .map(|i| {
                let t = i as f64 / rate;
                1.0 * (2.0 * PI * 4.0 * t).sin() + 0.3 * (2.0 * PI * 50.0 * t).sin()
            })
            .collect();
        let s = amplitude_spectrum(&x, rate, Window::FlatTop).unwrap();
        let peaks = find_peaks(&s.freq_hz, &s.amplitude, 1.0, 2);
        assert_eq!(peaks.len(), 2);
        assert!(
            (peaks[0].interpolated_freq_hz - 4.0).abs() < 0.05,
            "{peaks:?}"
        );
        assert!((peaks[1].interpolated_freq_hz - 50.0).abs() < 0.05);
    }

    #[test]
    fn time_stamps_are_checked() {
        assert!(matches!(
            uniform_sample_rate_hz(&[0.0, 1.0, 1.0], 0.01),
            Err(SpectrumError::TimeNotIncreasing { index: 2, .. })
        ));
        assert!(matches!(
            uniform_sample_rate_hz(&[0.0, f64::NAN, 2.0], 0.01),
            Err(SpectrumError::TimeNotIncreasing { index: 1, .. })
        ));
        assert!(matches!(
            amplitude_spectrum_of_log(&[0.0, 1.0], &[1.0], Window::Hann),
            Err(SpectrumError::LengthMismatch {
                times: 2,
                values: 1
            })
        ));
        // Jitter inside the tolerance is fine.
        let t: Vec<f64> = (0..100)
            .map(|n| n as f64 * 1e-3 + if n % 2 == 0 { 2e-6 } else { 0.0 })
            .collect();
        assert!(uniform_sample_rate_hz(&t, 0.01).is_ok());
    }

    #[test]
    fn markers_cap_each_kind_and_ignore_a_stopped_spindle() {
        assert!(milling_markers(0.0, 4, 1e4, 10).is_empty());
        assert!(milling_markers(f64::NAN, 4, 1e4, 10).is_empty());
        let m = milling_markers(-6000.0, 4, 1e4, 3);
        let teeth: Vec<f64> = m
            .iter()
            .filter(|m| m.kind == MarkerKind::ToothPassing)
            .map(|m| m.freq_hz)
            .collect();
        assert_eq!(teeth, [400.0, 800.0, 1200.0]);
        assert_eq!(
            m.iter().filter(|m| m.kind == MarkerKind::Spindle).count(),
            3
        );
    }
}
