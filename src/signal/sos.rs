//! Second-order sections: the coefficients of a biquad cascade, without any filter state.
//!
//! A [`Sos`] is what a design produces and what a filter ([`super::filter::SosFilter`]) runs. It
//! is valid by construction: at least one section, every coefficient finite, each section
//! normalised so that `a0 = 1`. Rows use scipy's layout `[b0, b1, b2, a0, a1, a2]`, for
//!
//! ```text
//!            b0 + b1·z⁻¹ + b2·z⁻²
//! H_k(z) = ────────────────────────        H(z) = Π H_k(z)
//!            1  + a1·z⁻¹ + a2·z⁻²
//! ```

use std::fmt;

use rustfft::num_complex::Complex64;

use super::complex;
use crate::math;

/// One second-order section, normalised so that `a0 = 1`.
///
/// ```
/// use cutlab::signal::sos::Biquad;
/// let section = Biquad::new([0.5, 0.5, 0.0], [2.0, -1.0, 0.0]).unwrap();
/// // Stored divided by a0 = 2.
/// assert_eq!(section.coefficients(), [0.25, 0.25, 0.0, 1.0, -0.5, 0.0]);
/// assert_eq!(section.dc_gain(), 1.0);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Biquad {
    pub(crate) b0: f64,
    pub(crate) b1: f64,
    pub(crate) b2: f64,
    pub(crate) a1: f64,
    pub(crate) a2: f64,
}

/// Why coefficients do not form a usable cascade.
#[derive(Debug, Clone, PartialEq)]
pub enum SosError {
    /// No sections at all.
    Empty,
    /// A coefficient is NaN or infinite.
    NotFinite {
        /// Section index, from 0.
        section: usize,
        /// Column in scipy's layout: 0–2 are b0–b2, 3–5 are a0–a2.
        column: usize,
        /// The value found.
        value: f64,
    },
    /// `a0` is zero, so the section cannot be normalised.
    ZeroLeadingDenominator {
        /// Section index, from 0.
        section: usize,
    },
}

impl fmt::Display for SosError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const NAMES: [&str; 6] = ["b0", "b1", "b2", "a0", "a1", "a2"];
        match self {
            Self::Empty => f.write_str("a cascade needs at least one section"),
            Self::NotFinite {
                section,
                column,
                value,
            } => write!(
                f,
                "section {section}, coefficient {}: {value} is not a finite number",
                NAMES.get(*column).copied().unwrap_or("?")
            ),
            Self::ZeroLeadingDenominator { section } => {
                write!(f, "section {section}, coefficient a0: must not be zero")
            }
        }
    }
}

impl std::error::Error for SosError {}

impl Biquad {
    /// A section from numerator `b` and denominator `a` (highest power of `z⁻¹` last), divided
    /// by `a[0]`.
    pub fn new(b: [f64; 3], a: [f64; 3]) -> Result<Self, SosError> {
        Self::from_row(0, [b[0], b[1], b[2], a[0], a[1], a[2]])
    }

    fn from_row(section: usize, row: [f64; 6]) -> Result<Self, SosError> {
        if let Some((column, &value)) = row.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(SosError::NotFinite {
                section,
                column,
                value,
            });
        }
        let a0 = row[3];
        if a0 == 0.0 {
            return Err(SosError::ZeroLeadingDenominator { section });
        }
        let [b0, b1, b2, _, a1, a2] = if a0 == 1.0 { row } else { row.map(|c| c / a0) };
        let section_value = Self { b0, b1, b2, a1, a2 };
        if [b0, b1, b2, a1, a2].iter().any(|c| !c.is_finite()) {
            // Dividing by a tiny a0 overflowed.
            return Err(SosError::NotFinite {
                section,
                column: 3,
                value: a0,
            });
        }
        Ok(section_value)
    }

    /// `[b0, b1, b2, 1, a1, a2]`, scipy's row layout.
    pub fn coefficients(&self) -> [f64; 6] {
        [self.b0, self.b1, self.b2, 1.0, self.a1, self.a2]
    }

    /// Numerator `[b0, b1, b2]`.
    pub fn b(&self) -> [f64; 3] {
        [self.b0, self.b1, self.b2]
    }

    /// Denominator `[1, a1, a2]`.
    pub fn a(&self) -> [f64; 3] {
        [1.0, self.a1, self.a2]
    }

    /// `H(1)`, the gain for a constant input: `Σb / Σa`.
    pub fn dc_gain(&self) -> f64 {
        (self.b0 + self.b1 + self.b2) / (1.0 + self.a1 + self.a2)
    }

    /// `H(e^{iω})` at `ω` radians per sample.
    pub fn response(&self, omega_rad: f64) -> Complex64 {
        // z⁻¹ = e^{−iω}; both polynomials by Horner in z⁻¹, as scipy's freqz evaluates them.
        let z_inv = Complex64::new(math::cos(omega_rad), -math::sin(omega_rad));
        let numerator = (z_inv * self.b2 + self.b1) * z_inv + self.b0;
        let denominator = (z_inv * self.a2 + self.a1) * z_inv + 1.0;
        complex::div(numerator, denominator)
    }

    /// The transposed-direct-form-II state `[s0, s1]` this section holds after a unit step has
    /// settled (scipy's `lfilter_zi` for one section). Infinite when the section has a pole at
    /// `z = 1`.
    pub fn steady_state(&self) -> [f64; 2] {
        // Solve s = A·s + B for the companion matrix A: two equations, closed form.
        let b_0 = self.b1 - self.a1 * self.b0;
        let b_1 = self.b2 - self.a2 * self.b0;
        let s0 = (b_0 + b_1) / (1.0 + self.a1 + self.a2);
        [s0, b_1 - self.a2 * s0]
    }
}

/// A cascade of second-order sections: coefficients only, no state.
///
/// ```
/// use cutlab::signal::sos::Sos;
/// let sos = Sos::from_rows(&[[0.25, 0.5, 0.25, 1.0, -0.2, 0.1]]).unwrap();
/// assert_eq!(sos.sections().len(), 1);
/// assert_eq!(sos.rows(), vec![[0.25, 0.5, 0.25, 1.0, -0.2, 0.1]]);
/// // Unit gain at DC: Σb / Σa = 1 / 0.9.
/// assert!((sos.dc_gain() - 1.0 / 0.9).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Sos {
    sections: Vec<Biquad>,
}

impl Sos {
    /// A cascade from rows in scipy's layout `[b0, b1, b2, a0, a1, a2]`; each row is divided by
    /// its `a0`.
    pub fn from_rows(rows: &[[f64; 6]]) -> Result<Self, SosError> {
        if rows.is_empty() {
            return Err(SosError::Empty);
        }
        let sections = rows
            .iter()
            .enumerate()
            .map(|(i, row)| Biquad::from_row(i, *row))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self { sections })
    }

    /// A cascade of the given sections.
    pub fn from_sections(sections: Vec<Biquad>) -> Result<Self, SosError> {
        if sections.is_empty() {
            return Err(SosError::Empty);
        }
        Ok(Self { sections })
    }

    /// The sections, first to last.
    pub fn sections(&self) -> &[Biquad] {
        &self.sections
    }

    /// Rows in scipy's layout `[b0, b1, b2, 1, a1, a2]`.
    pub fn rows(&self) -> Vec<[f64; 6]> {
        self.sections.iter().map(Biquad::coefficients).collect()
    }

    /// `H(1)`, the cascade's gain for a constant input.
    pub fn dc_gain(&self) -> f64 {
        self.sections.iter().map(Biquad::dc_gain).product()
    }

    /// The complex frequency response at each of `freqs_hz` for a sampling rate of
    /// `sample_rate_hz` (scipy's `sosfreqz(sos, worN=freqs_hz, fs=sample_rate_hz)`).
    ///
    /// ```
    /// use cutlab::signal::butterworth::{butter, ButterworthSpec, Cutoff, FilterKind};
    /// let sos = butter(&ButterworthSpec {
    ///     kind: FilterKind::Lowpass,
    ///     order: 2,
    ///     cutoff_hz: Cutoff::Single(50.0),
    ///     sample_rate_hz: 10_000.0,
    /// })
    /// .unwrap();
    /// let h = sos.frequency_response(&[0.0, 50.0, 5_000.0], 10_000.0);
    /// assert!((h[0].norm() - 1.0).abs() < 1e-12);
    /// assert!((h[1].norm() - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-9);
    /// assert!(h[2].norm() < 1e-12); // the zeros sit at Nyquist
    /// ```
    pub fn frequency_response(&self, freqs_hz: &[f64], sample_rate_hz: f64) -> Vec<Complex64> {
        freqs_hz
            .iter()
            .map(|&f| {
                let omega = 2.0 * std::f64::consts::PI * f / sample_rate_hz;
                self.sections
                    .iter()
                    .fold(Complex64::new(1.0, 0.0), |h, s| h * s.response(omega))
            })
            .collect()
    }

    /// The filter state, per section, that makes a constant input `x0` come out as the constant
    /// `dc_gain() · x0` from the first sample on, for `x0 = 1` (scipy's `sosfilt_zi`). Scale it by
    /// the first sample to start a filter "already settled".
    ///
    /// ```
    /// use cutlab::signal::sos::Sos;
    /// let sos = Sos::from_rows(&[[0.25, 0.5, 0.25, 1.0, -0.2, 0.1]]).unwrap();
    /// let zi = sos.steady_state();
    /// // For a constant input of 1 the first output b0 + s0 is already the DC gain.
    /// assert!((0.25 + zi[0][0] - sos.dc_gain()).abs() < 1e-15);
    /// ```
    pub fn steady_state(&self) -> Vec<[f64; 2]> {
        let mut scale = 1.0;
        self.sections
            .iter()
            .map(|s| {
                let [s0, s1] = s.steady_state();
                let state = [scale * s0, scale * s1];
                // The next section sees this one's settled output.
                scale *= (s.b0 + s.b1 + s.b2) / (1.0 + s.a1 + s.a2);
                state
            })
            .collect()
    }

    /// The number of samples scipy's `sosfiltfilt` pads each end with by default:
    /// `3 · (2·sections + 1 − min(#sections with b2 = 0, #sections with a2 = 0))`.
    ///
    /// ```
    /// use cutlab::signal::butterworth::{butter, ButterworthSpec, Cutoff, FilterKind};
    /// let spec = |order| ButterworthSpec {
    ///     kind: FilterKind::Lowpass,
    ///     order,
    ///     cutoff_hz: Cutoff::Single(50.0),
    ///     sample_rate_hz: 10_000.0,
    /// };
    /// assert_eq!(butter(&spec(10)).unwrap().filtfilt_padlen(), 33);
    /// // Odd order: one section is first-order (b2 = a2 = 0), one tap fewer.
    /// assert_eq!(butter(&spec(3)).unwrap().filtfilt_padlen(), 12);
    /// ```
    pub fn filtfilt_padlen(&self) -> usize {
        let zero_b2 = self.sections.iter().filter(|s| s.b2 == 0.0).count();
        let zero_a2 = self.sections.iter().filter(|s| s.a2 == 0.0).count();
        let taps = 2 * self.sections.len() + 1 - zero_b2.min(zero_a2);
        3 * taps
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_are_validated_and_normalised() {
        assert_eq!(Sos::from_rows(&[]), Err(SosError::Empty));
        let e = Sos::from_rows(&[
            [1.0, 0.0, 0.0, 1.0, 0.0, 0.0],
            [1.0, f64::NAN, 0.0, 1.0, 0.0, 0.0],
        ])
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "section 1, coefficient b1: NaN is not a finite number"
        );
        let e = Sos::from_rows(&[[1.0, 0.0, 0.0, 0.0, 0.0, 0.0]]).unwrap_err();
        assert_eq!(e.to_string(), "section 0, coefficient a0: must not be zero");
        let sos = Sos::from_rows(&[[2.0, 4.0, 2.0, 2.0, 1.0, 0.5]]).unwrap();
        assert_eq!(sos.rows(), vec![[1.0, 2.0, 1.0, 1.0, 0.5, 0.25]]);
    }

    #[test]
    fn steady_state_holds_a_constant_input() {
        let sos = Sos::from_rows(&[
            [0.1, 0.2, 0.1, 1.0, -1.2, 0.5],
            [1.0, -0.3, 0.0, 1.0, -0.4, 0.0],
        ])
        .unwrap();
        let zi = sos.steady_state();
        // Run the cascade by hand from the settled state on a constant 3.
        let mut state: Vec<[f64; 2]> = zi.iter().map(|s| [3.0 * s[0], 3.0 * s[1]]).collect();
        for _ in 0..5 {
            let mut x = 3.0;
            for (s, z) in sos.sections().iter().zip(&mut state) {
                let y = s.b0 * x + z[0];
                z[0] = (s.b1 * x + z[1]) - s.a1 * y;
                z[1] = s.b2 * x - s.a2 * y;
                x = y;
            }
            assert!((x - 3.0 * sos.dc_gain()).abs() < 1e-12, "{x}");
        }
    }

    #[test]
    fn response_at_dc_is_the_dc_gain() {
        let sos = Sos::from_rows(&[[0.1, 0.2, 0.1, 1.0, -1.2, 0.5]]).unwrap();
        let h = sos.frequency_response(&[0.0], 1000.0)[0];
        assert!((h.re - sos.dc_gain()).abs() < 1e-12 && h.im.abs() < 1e-15);
    }
}
