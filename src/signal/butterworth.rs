//! Digital Butterworth filters of order 1–20 as second-order sections.
//!
//! The design follows the classical route, step for step as `scipy.signal.butter(N, Wn, btype,
//! fs=fs, output='sos')` takes it, so that the sections agree with scipy's one by one (same order,
//! gain in the first section) to about 1e-12 relative:
//!
//! 1. the analog prototype: `N` poles `−e^{iπm/(2N)}`, `m = −N+1, −N+3, …, N−1`, on the left
//!    half of the unit circle, no zeros, gain 1;
//! 2. pre-warping: each cut-off `f` becomes `ω = 4·tan(π·f/f_s)` (the bilinear transform below
//!    uses a sampling rate of 2, as scipy does), so the digital −3 dB point lands exactly on `f`;
//! 3. the frequency transformation — low-pass `s → s/ω`, high-pass `s → ω/s`, band-pass and
//!    band-stop around `ω₀ = √(ω₁ω₂)` with bandwidth `ω₂ − ω₁` (each doubles the order);
//! 4. the bilinear transform `z = (4 + s)/(4 − s)`, zeros at infinity moving to `z = −1`;
//! 5. pairing into sections ([`Zpk::to_sections`]).
//!
//! Second-order sections are the only safe form at high order and low cut-off: the order-10,
//! 5 Hz at 10 kHz low-pass of paper 000 is unstable as one transfer function (a pole of the
//! expanded polynomial lands at radius 1.056) but exact as five sections.
//!
//! Bad parameters are a [`DesignError`] whose message names the field; nothing here panics.
//!
//! ```
//! use cutlab::signal::butterworth::{butter, ButterworthSpec, Cutoff, FilterKind};
//! let spec = ButterworthSpec {
//!     kind: FilterKind::Lowpass,
//!     order: 10,
//!     cutoff_hz: Cutoff::Single(50.0),
//!     sample_rate_hz: 10_000.0,
//! };
//! let sos = butter(&spec).unwrap();
//! assert_eq!(sos.sections().len(), 5);
//! // −3 dB at the cut-off.
//! let h = sos.frequency_response(&[50.0], 10_000.0)[0];
//! assert!((20.0 * h.norm().log10() + 3.0103).abs() < 1e-3);
//! ```

use std::fmt;
use std::str::FromStr;

use rustfft::num_complex::Complex64;

use super::complex;
use super::sos::Sos;
use super::zpk::Zpk;
use crate::math;

/// The highest order [`butter`] accepts. Higher orders are possible with sections, but nothing in
/// milling needs them and the response of a 40-pole band-pass is already numerically delicate.
pub const MAX_ORDER: usize = 20;

/// What a Butterworth filter lets through.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FilterKind {
    /// Passes below the cut-off.
    Lowpass,
    /// Passes above the cut-off.
    Highpass,
    /// Passes between two cut-offs.
    Bandpass,
    /// Stops between two cut-offs.
    Bandstop,
}

impl FilterKind {
    /// Every kind, in the order the UI lists them.
    pub const ALL: [FilterKind; 4] = [
        FilterKind::Lowpass,
        FilterKind::Highpass,
        FilterKind::Bandpass,
        FilterKind::Bandstop,
    ];

    /// A label for people: `"Low-pass"`.
    ///
    /// ```
    /// use cutlab::signal::butterworth::FilterKind;
    /// assert_eq!(FilterKind::Bandpass.label(), "Band-pass");
    /// ```
    pub fn label(self) -> &'static str {
        match self {
            Self::Lowpass => "Low-pass",
            Self::Highpass => "High-pass",
            Self::Bandpass => "Band-pass",
            Self::Bandstop => "Band-stop",
        }
    }

    /// The machine name, as scipy's `btype` and the CLI's `--kind`: `"lowpass"`.
    ///
    /// ```
    /// use cutlab::signal::butterworth::FilterKind;
    /// for kind in FilterKind::ALL {
    ///     assert_eq!(kind.name().parse::<FilterKind>().unwrap(), kind);
    /// }
    /// assert_eq!(FilterKind::ALL.len(), 4);
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            Self::Lowpass => "lowpass",
            Self::Highpass => "highpass",
            Self::Bandpass => "bandpass",
            Self::Bandstop => "bandstop",
        }
    }

    /// Whether the kind takes two cut-offs ([`Cutoff::Band`]).
    ///
    /// ```
    /// use cutlab::signal::butterworth::FilterKind;
    /// assert_eq!(FilterKind::ALL.iter().filter(|k| k.is_band()).count(), 2);
    /// ```
    pub fn is_band(self) -> bool {
        matches!(self, Self::Bandpass | Self::Bandstop)
    }
}

impl fmt::Display for FilterKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A filter kind that is not one of [`FilterKind::ALL`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UnknownFilterKind(pub String);

impl fmt::Display for UnknownFilterKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "unknown filter kind {:?}; kinds: lowpass, highpass, bandpass, bandstop",
            self.0
        )
    }
}

impl std::error::Error for UnknownFilterKind {}

impl FromStr for FilterKind {
    type Err = UnknownFilterKind;

    /// Accepts the [`name`](FilterKind::name), the [`label`](FilterKind::label) and scipy's short
    /// forms (`low`, `lp`, `high`, `hp`, `band`, `bp`, `stop`, `bs`), in any case.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let key = text
            .trim()
            .to_ascii_lowercase()
            .replace(['-', ' ', '_'], "");
        match key.as_str() {
            "lowpass" | "low" | "lp" => Ok(Self::Lowpass),
            "highpass" | "high" | "hp" => Ok(Self::Highpass),
            "bandpass" | "band" | "bp" | "pass" => Ok(Self::Bandpass),
            "bandstop" | "stop" | "bs" | "notch" => Ok(Self::Bandstop),
            _ => Err(UnknownFilterKind(text.to_string())),
        }
    }
}

/// Cut-off frequencies in Hz: one for low/high-pass, two (lower, upper) for band-pass/stop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Cutoff {
    /// The −3 dB frequency of a low-pass or high-pass, Hz.
    Single(f64),
    /// The lower and upper −3 dB frequencies of a band-pass or band-stop, Hz.
    Band(f64, f64),
}

/// Everything that defines a digital Butterworth filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ButterworthSpec {
    /// Low-pass, high-pass, band-pass or band-stop.
    pub kind: FilterKind,
    /// Order of the prototype, 1 to [`MAX_ORDER`]; band filters have twice as many poles.
    pub order: usize,
    /// Cut-off(s), Hz.
    pub cutoff_hz: Cutoff,
    /// Sampling rate, Hz.
    pub sample_rate_hz: f64,
}

impl ButterworthSpec {
    /// Half the sampling rate, Hz.
    ///
    /// ```
    /// use cutlab::signal::butterworth::{ButterworthSpec, Cutoff, FilterKind};
    /// let spec = ButterworthSpec {
    ///     kind: FilterKind::Lowpass,
    ///     order: 2,
    ///     cutoff_hz: Cutoff::Single(260.0),
    ///     sample_rate_hz: 10_000.0,
    /// };
    /// assert_eq!(spec.nyquist_hz(), 5_000.0);
    /// ```
    pub fn nyquist_hz(&self) -> f64 {
        self.sample_rate_hz / 2.0
    }
}

/// Which cut-off an error is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Edge {
    /// The single cut-off of a low-pass or high-pass.
    Single,
    /// The lower edge of a band.
    Lower,
    /// The upper edge of a band.
    Upper,
}

impl Edge {
    fn describe(self) -> &'static str {
        match self {
            Self::Single => "cut-off",
            Self::Lower => "lower cut-off",
            Self::Upper => "upper cut-off",
        }
    }
}

/// Why a Butterworth design was refused. Each message names the field it is about ("order",
/// "sample rate", "cut-off", "lower cut-off", "upper cut-off") so a form can show it beside that
/// field.
#[derive(Debug, Clone, PartialEq)]
pub enum DesignError {
    /// The order is 0 or above [`MAX_ORDER`].
    Order {
        /// The order asked for.
        order: usize,
    },
    /// The sampling rate is not a positive finite number.
    SampleRate {
        /// The rate given, Hz.
        sample_rate_hz: f64,
    },
    /// A band filter was given one cut-off, or a low/high-pass two.
    CutoffCount {
        /// The kind asked for.
        kind: FilterKind,
    },
    /// A cut-off is NaN or infinite.
    CutoffNotFinite {
        /// Which cut-off.
        edge: Edge,
        /// The value given, Hz.
        cutoff_hz: f64,
    },
    /// A cut-off is zero or negative.
    CutoffNotPositive {
        /// Which cut-off.
        edge: Edge,
        /// The value given, Hz.
        cutoff_hz: f64,
    },
    /// A cut-off is at or above half the sampling rate.
    CutoffAboveNyquist {
        /// Which cut-off.
        edge: Edge,
        /// The value given, Hz.
        cutoff_hz: f64,
        /// Half the sampling rate, Hz.
        nyquist_hz: f64,
    },
    /// The band's upper edge is not above its lower edge.
    BandEdges {
        /// Lower cut-off, Hz.
        lower_hz: f64,
        /// Upper cut-off, Hz.
        upper_hz: f64,
    },
    /// The parameters are valid but the design cannot be represented in double precision: a pole
    /// rounds onto the unit circle or the gain under- or overflows (a cut-off extremely close to
    /// 0 Hz or to the Nyquist frequency).
    Numerical {
        /// What went wrong.
        detail: String,
    },
}

impl fmt::Display for DesignError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Order { order } => write!(
                f,
                "order must be a whole number from 1 to {MAX_ORDER}, got {order}"
            ),
            Self::SampleRate { sample_rate_hz } => write!(
                f,
                "sample rate must be a positive, finite number of Hz, got {sample_rate_hz}"
            ),
            Self::CutoffCount { kind } => {
                if kind.is_band() {
                    write!(
                        f,
                        "a {} filter needs a lower and an upper cut-off",
                        kind.label().to_lowercase()
                    )
                } else {
                    write!(
                        f,
                        "a {} filter takes one cut-off, not a band",
                        kind.label().to_lowercase()
                    )
                }
            }
            Self::CutoffNotFinite { edge, cutoff_hz } => write!(
                f,
                "{} must be a finite number of Hz, got {cutoff_hz}",
                edge.describe()
            ),
            Self::CutoffNotPositive { edge, cutoff_hz } => write!(
                f,
                "{} must be above 0 Hz, got {cutoff_hz} Hz",
                edge.describe()
            ),
            Self::CutoffAboveNyquist {
                edge,
                cutoff_hz,
                nyquist_hz,
            } => write!(
                f,
                "{} {cutoff_hz} Hz must be below the Nyquist frequency, {nyquist_hz} Hz",
                edge.describe()
            ),
            Self::BandEdges { lower_hz, upper_hz } => write!(
                f,
                "upper cut-off {upper_hz} Hz must be above the lower cut-off, {lower_hz} Hz"
            ),
            Self::Numerical { detail } => write!(f, "no usable design: {detail}"),
        }
    }
}

impl std::error::Error for DesignError {}

/// Designs a digital Butterworth filter as second-order sections, equal to
/// `scipy.signal.butter(order, cutoff, kind, fs=sample_rate, output='sos')`.
///
/// ```
/// use cutlab::signal::butterworth::{butter, ButterworthSpec, Cutoff, FilterKind};
/// let spec = ButterworthSpec {
///     kind: FilterKind::Bandpass,
///     order: 3,
///     cutoff_hz: Cutoff::Band(50.0, 200.0),
///     sample_rate_hz: 10_000.0,
/// };
/// let sos = butter(&spec).unwrap();
/// // A band-pass of order 3 has 6 poles: three sections, unit gain in the pass band.
/// assert_eq!(sos.sections().len(), 3);
/// let centre_hz = (50.0_f64 * 200.0).sqrt();
/// let h = sos.frequency_response(&[centre_hz], 10_000.0)[0];
/// assert!((h.norm() - 1.0).abs() < 1e-3);
///
/// let too_high = ButterworthSpec { cutoff_hz: Cutoff::Band(50.0, 6000.0), ..spec };
/// assert_eq!(
///     butter(&too_high).unwrap_err().to_string(),
///     "upper cut-off 6000 Hz must be below the Nyquist frequency, 5000 Hz"
/// );
/// ```
pub fn butter(spec: &ButterworthSpec) -> Result<Sos, DesignError> {
    let zpk = butter_zpk(spec)?;
    let rows = zpk.to_sections().map_err(|e| DesignError::Numerical {
        detail: e.to_string(),
    })?;
    Sos::from_rows(&rows).map_err(|e| DesignError::Numerical {
        detail: e.to_string(),
    })
}

/// The same design as [`butter`], as digital zeros, poles and gain (before pairing).
///
/// ```
/// use cutlab::signal::butterworth::{butter_zpk, ButterworthSpec, Cutoff, FilterKind};
/// let zpk = butter_zpk(&ButterworthSpec {
///     kind: FilterKind::Lowpass,
///     order: 4,
///     cutoff_hz: Cutoff::Single(1000.0),
///     sample_rate_hz: 10_000.0,
/// })
/// .unwrap();
/// assert_eq!(zpk.poles.len(), 4);
/// // Every zero of a digital Butterworth low-pass sits at z = −1 (the Nyquist frequency).
/// assert!(zpk.zeros.iter().all(|z| z.re == -1.0 && z.im == 0.0));
/// assert!(zpk.poles.iter().all(|p| p.norm() < 1.0));
/// ```
pub fn butter_zpk(spec: &ButterworthSpec) -> Result<Zpk, DesignError> {
    let warped = validate(spec)?;
    let poles = analog_prototype(spec.order);
    let analog = match (spec.kind, warped) {
        (FilterKind::Lowpass, Warped::Single(w)) => lowpass(&poles, w),
        (FilterKind::Highpass, Warped::Single(w)) => highpass(&poles, w),
        (FilterKind::Bandpass, Warped::Band(w1, w2)) => bandpass(&poles, w1, w2),
        (FilterKind::Bandstop, Warped::Band(w1, w2)) => bandstop(&poles, w1, w2),
        (kind, _) => return Err(DesignError::CutoffCount { kind }),
    };
    let digital = bilinear(&analog);
    check_representable(&digital)?;
    Ok(digital)
}

/// Pre-warped analog cut-off(s), rad/s for a bilinear transform at a sampling rate of 2.
#[derive(Clone, Copy)]
enum Warped {
    Single(f64),
    Band(f64, f64),
}

fn validate(spec: &ButterworthSpec) -> Result<Warped, DesignError> {
    if spec.order == 0 || spec.order > MAX_ORDER {
        return Err(DesignError::Order { order: spec.order });
    }
    let rate = spec.sample_rate_hz;
    if !(rate.is_finite() && rate > 0.0) {
        return Err(DesignError::SampleRate {
            sample_rate_hz: rate,
        });
    }
    let nyquist_hz = rate / 2.0;
    let check = |edge: Edge, cutoff_hz: f64| -> Result<f64, DesignError> {
        if !cutoff_hz.is_finite() {
            return Err(DesignError::CutoffNotFinite { edge, cutoff_hz });
        }
        if cutoff_hz <= 0.0 {
            return Err(DesignError::CutoffNotPositive { edge, cutoff_hz });
        }
        // Normalised to the Nyquist frequency as scipy does (`Wn = Wn / (fs/2)`), then compared
        // with 1, so a cut-off a rounding error below Nyquist is judged like scipy judges it.
        let normalised = cutoff_hz / nyquist_hz;
        if normalised >= 1.0 {
            return Err(DesignError::CutoffAboveNyquist {
                edge,
                cutoff_hz,
                nyquist_hz,
            });
        }
        Ok(4.0 * math::tan(std::f64::consts::PI * normalised / 2.0))
    };
    match (spec.kind.is_band(), spec.cutoff_hz) {
        (false, Cutoff::Single(f)) => Ok(Warped::Single(check(Edge::Single, f)?)),
        (true, Cutoff::Band(lower_hz, upper_hz)) => {
            let w1 = check(Edge::Lower, lower_hz)?;
            let w2 = check(Edge::Upper, upper_hz)?;
            if lower_hz >= upper_hz {
                return Err(DesignError::BandEdges { lower_hz, upper_hz });
            }
            Ok(Warped::Band(w1, w2))
        }
        _ => Err(DesignError::CutoffCount { kind: spec.kind }),
    }
}

/// The analog Butterworth prototype's poles (cut-off 1 rad/s, gain 1, no zeros).
fn analog_prototype(order: usize) -> Vec<Complex64> {
    let n = order as f64;
    // numpy computes 1j·π·m / (2N) as a complex division, which multiplies by 1/(2N).
    let inverse = 1.0 / (2.0 * n);
    (0..order)
        .map(|i| {
            let m = -(n - 1.0) + 2.0 * i as f64;
            -complex::exp_i((std::f64::consts::PI * m) * inverse)
        })
        .collect()
}

/// Low-pass cut-off `w`: `s → s/w`.
fn lowpass(poles: &[Complex64], w: f64) -> Zpk {
    Zpk {
        zeros: Vec::new(),
        poles: poles.iter().map(|p| p * w).collect(),
        gain: math::pow(w, poles.len() as f64),
    }
}

/// High-pass cut-off `w`: `s → w/s`; the prototype's zeros at infinity move to the origin.
fn highpass(poles: &[Complex64], w: f64) -> Zpk {
    let negated: Vec<Complex64> = poles.iter().map(|p| -p).collect();
    Zpk {
        zeros: vec![Complex64::new(0.0, 0.0); poles.len()],
        poles: poles.iter().map(|&p| complex::real_div(w, p)).collect(),
        gain: complex::real_div(1.0, complex::product(&negated)).re,
    }
}

/// Band-pass between `w1` and `w2`: `s → (s² + w0²)/(s·bw)`.
fn bandpass(poles: &[Complex64], w1: f64, w2: f64) -> Zpk {
    let bandwidth = w2 - w1;
    let centre = (w1 * w2).sqrt();
    let scaled: Vec<Complex64> = poles.iter().map(|p| (p * bandwidth) * 0.5).collect();
    Zpk {
        zeros: vec![Complex64::new(0.0, 0.0); poles.len()],
        poles: split_around(&scaled, centre),
        gain: math::pow(bandwidth, poles.len() as f64),
    }
}

/// Band-stop between `w1` and `w2`: `s → s·bw/(s² + w0²)`; zeros at `±i·w0`.
fn bandstop(poles: &[Complex64], w1: f64, w2: f64) -> Zpk {
    let bandwidth = w2 - w1;
    let centre = (w1 * w2).sqrt();
    let inverted: Vec<Complex64> = poles
        .iter()
        .map(|&p| complex::real_div(bandwidth / 2.0, p))
        .collect();
    let negated: Vec<Complex64> = poles.iter().map(|p| -p).collect();
    let mut zeros = vec![Complex64::new(0.0, centre); poles.len()];
    zeros.extend(std::iter::repeat_n(
        Complex64::new(0.0, -centre),
        poles.len(),
    ));
    Zpk {
        zeros,
        poles: split_around(&inverted, centre),
        gain: complex::real_div(1.0, complex::product(&negated)).re,
    }
}

/// Each value `v` becomes `v ± √(v² − w0²)`: all the `+` roots, then all the `−` roots.
fn split_around(values: &[Complex64], centre: f64) -> Vec<Complex64> {
    let roots: Vec<Complex64> = values
        .iter()
        .map(|&v| {
            let square = v * v;
            complex::sqrt(Complex64::new(square.re - centre * centre, square.im))
        })
        .collect();
    let plus = values.iter().zip(&roots).map(|(v, r)| v + r);
    let minus = values.iter().zip(&roots).map(|(v, r)| v - r);
    plus.chain(minus).collect()
}

/// The bilinear transform at a sampling rate of 2 (`z = (4 + s)/(4 − s)`); zeros at infinity
/// move to `z = −1`.
fn bilinear(analog: &Zpk) -> Zpk {
    const FS2: f64 = 4.0;
    let to_z = |s: &Complex64| {
        complex::div(
            Complex64::new(FS2 + s.re, s.im),
            Complex64::new(FS2 - s.re, -s.im),
        )
    };
    let relative_degree = analog.poles.len().saturating_sub(analog.zeros.len());
    let mut zeros: Vec<Complex64> = analog.zeros.iter().map(to_z).collect();
    zeros.extend(std::iter::repeat_n(
        Complex64::new(-1.0, 0.0),
        relative_degree,
    ));
    let from_zeros: Vec<Complex64> = analog
        .zeros
        .iter()
        .map(|z| Complex64::new(FS2 - z.re, -z.im))
        .collect();
    let from_poles: Vec<Complex64> = analog
        .poles
        .iter()
        .map(|p| Complex64::new(FS2 - p.re, -p.im))
        .collect();
    let gain_change = complex::div(complex::product(&from_zeros), complex::product(&from_poles));
    Zpk {
        zeros,
        poles: analog.poles.iter().map(to_z).collect(),
        gain: analog.gain * gain_change.re,
    }
}

/// Refuses designs that double precision cannot hold: a pole on or outside the unit circle, or a
/// gain that under- or overflowed.
fn check_representable(zpk: &Zpk) -> Result<(), DesignError> {
    if !(zpk.gain.is_finite() && zpk.gain != 0.0) {
        return Err(DesignError::Numerical {
            detail: format!(
                "the gain {} is out of double-precision range (cut-off too close to 0 Hz or to \
                 the Nyquist frequency for this order)",
                zpk.gain
            ),
        });
    }
    if let Some(p) = zpk
        .poles
        .iter()
        .find(|p| !(p.re.is_finite() && p.im.is_finite() && p.norm() < 1.0))
    {
        return Err(DesignError::Numerical {
            detail: format!(
                "a pole rounds to radius {} (must be inside the unit circle); the cut-off is too \
                 close to 0 Hz or to the Nyquist frequency for double precision",
                p.norm()
            ),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(kind: FilterKind, order: usize, cutoff_hz: Cutoff) -> ButterworthSpec {
        ButterworthSpec {
            kind,
            order,
            cutoff_hz,
            sample_rate_hz: 10_000.0,
        }
    }

    #[test]
    fn every_kind_has_unit_gain_in_its_pass_band_and_minus_3_db_at_its_edges() {
        for kind in FilterKind::ALL {
            for order in [1, 2, 5, 10, 20] {
                let cutoff = if kind.is_band() {
                    Cutoff::Band(200.0, 2000.0)
                } else {
                    Cutoff::Single(500.0)
                };
                let sos = butter(&spec(kind, order, cutoff)).unwrap();
                let pass_hz = match kind {
                    FilterKind::Lowpass | FilterKind::Bandstop => 0.0,
                    FilterKind::Highpass => 4999.0,
                    FilterKind::Bandpass => (200.0_f64 * 2000.0).sqrt(),
                };
                let edges: Vec<f64> = match cutoff {
                    Cutoff::Single(f) => vec![f],
                    Cutoff::Band(a, b) => vec![a, b],
                };
                let h = sos.frequency_response(&[pass_hz], 10_000.0)[0].norm();
                assert!((h - 1.0).abs() < 1e-3, "{kind} order {order}: |H| = {h}");
                for f in edges {
                    let h = sos.frequency_response(&[f], 10_000.0)[0].norm();
                    let db = 20.0 * h.log10();
                    assert!(
                        (db + 3.0103).abs() < 1e-6,
                        "{kind} {order} at {f} Hz: {db} dB"
                    );
                }
            }
        }
    }

    #[test]
    fn bad_parameters_are_errors_that_name_the_field() {
        let lp = |order, cutoff, rate| ButterworthSpec {
            kind: FilterKind::Lowpass,
            order,
            cutoff_hz: Cutoff::Single(cutoff),
            sample_rate_hz: rate,
        };
        let message = |s: ButterworthSpec| butter(&s).unwrap_err().to_string();
        assert!(message(lp(0, 50.0, 1e4)).starts_with("order must be"));
        assert!(message(lp(21, 50.0, 1e4)).contains("order"));
        assert!(message(lp(2, 50.0, 0.0)).starts_with("sample rate"));
        assert!(message(lp(2, 50.0, f64::NAN)).starts_with("sample rate"));
        assert!(message(lp(2, f64::INFINITY, 1e4)).starts_with("cut-off must be a finite"));
        assert!(message(lp(2, -1.0, 1e4)).starts_with("cut-off must be above 0 Hz"));
        assert_eq!(
            message(lp(2, 5000.0, 1e4)),
            "cut-off 5000 Hz must be below the Nyquist frequency, 5000 Hz"
        );
        let band = |a, b| spec(FilterKind::Bandstop, 2, Cutoff::Band(a, b));
        assert!(message(band(400.0, 40.0)).starts_with("upper cut-off 40 Hz"));
        assert!(message(band(0.0, 40.0)).starts_with("lower cut-off"));
        assert!(message(spec(FilterKind::Bandpass, 2, Cutoff::Single(5.0))).contains("upper"));
        assert!(message(spec(FilterKind::Lowpass, 2, Cutoff::Band(5.0, 6.0))).contains("one"));
    }

    #[test]
    fn cutoffs_beyond_double_precision_are_refused_not_unstable() {
        let e = butter(&spec(FilterKind::Lowpass, 10, Cutoff::Single(1e-12))).unwrap_err();
        assert!(matches!(e, DesignError::Numerical { .. }), "{e}");
        // Very low but representable: fine.
        assert!(butter(&spec(FilterKind::Lowpass, 20, Cutoff::Single(0.5))).is_ok());
    }

    #[test]
    fn kinds_parse_from_names_labels_and_short_forms() {
        assert_eq!("Low-pass".parse::<FilterKind>(), Ok(FilterKind::Lowpass));
        assert_eq!("HP".parse::<FilterKind>(), Ok(FilterKind::Highpass));
        assert_eq!("band stop".parse::<FilterKind>(), Ok(FilterKind::Bandstop));
        assert!("comb".parse::<FilterKind>().is_err());
    }
}
