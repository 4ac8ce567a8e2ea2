//! Zeros, poles and gain of a digital filter, and their pairing into second-order sections.
//!
//! [`Zpk::to_sections`] follows the rules of `scipy.signal.zpk2sos` with its default
//! `pairing='nearest'` for digital filters, so that a design reproduces scipy's sections one by
//! one, in the same order and with the gain in the same place:
//!
//! 1. Pad with poles/zeros at the origin until both lists have the same, even length.
//! 2. Keep one member of each complex-conjugate pair (the one with positive imaginary part,
//!    averaged with its partner) followed by the real values, as scipy's `_cplxreal` orders them.
//! 3. Fill the sections from the *last* to the first: take the pole closest to the unit circle
//!    (it has the highest Q; placing it last keeps intermediate signals small), pair it with its
//!    conjugate or with the next real pole closest to the circle, and give it the zeros nearest to
//!    it.
//! 4. Multiply the first section's numerator by the overall gain.
//!
//! Written from scipy's documented algorithm; no code is shared with it.

use std::fmt;

use rustfft::num_complex::Complex64;

use crate::math;

/// The zero-pole-gain form of a digital transfer function
/// `H(z) = gain · Π(1 − zᵢ z⁻¹) / Π(1 − pᵢ z⁻¹)`.
///
/// ```
/// use cutlab::signal::zpk::Zpk;
/// use rustfft::num_complex::Complex64;
/// // One real pole at 0.5 and a zero at −1: a first-order low-pass with DC gain 1 needs gain 0.25.
/// let zpk = Zpk {
///     zeros: vec![Complex64::new(-1.0, 0.0)],
///     poles: vec![Complex64::new(0.5, 0.0)],
///     gain: 0.25,
/// };
/// let rows = zpk.to_sections().unwrap();
/// assert_eq!(rows.len(), 1);
/// let [b0, b1, b2, a0, a1, a2] = rows[0];
/// assert_eq!([b0, b1, b2, a0, a1, a2], [0.25, 0.25, 0.0, 1.0, -0.5, 0.0]);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Zpk {
    /// Zeros in the z-plane; complex ones in conjugate pairs.
    pub zeros: Vec<Complex64>,
    /// Poles in the z-plane; complex ones in conjugate pairs.
    pub poles: Vec<Complex64>,
    /// Overall gain.
    pub gain: f64,
}

/// Why zeros and poles could not be paired into real second-order sections.
#[derive(Debug, Clone, PartialEq)]
pub enum PairingError {
    /// A complex zero or pole has no conjugate partner, so no real section can hold it.
    UnpairedComplex {
        /// `"zero"` or `"pole"`.
        what: &'static str,
    },
    /// The gain is complex or not finite.
    Gain,
}

impl fmt::Display for PairingError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::UnpairedComplex { what } => write!(
                f,
                "a complex {what} has no conjugate partner, so it cannot go into a real section"
            ),
            Self::Gain => f.write_str("the gain is not a finite real number"),
        }
    }
}

impl std::error::Error for PairingError {}

/// Relative tolerance for deciding that a value is real or that two values are conjugates: 100
/// machine epsilons, as scipy's `_cplxreal`.
const CONJUGATE_TOLERANCE: f64 = 100.0 * f64::EPSILON;

fn is_real(z: Complex64) -> bool {
    z.im == 0.0
}

fn abs(z: Complex64) -> f64 {
    math::hypot(z.re, z.im)
}

impl Zpk {
    /// Pairs the zeros and poles into second-order sections, each row
    /// `[b0, b1, b2, a0, a1, a2]` (scipy's layout, `a0 = 1`), in scipy's order: the section with
    /// the poles closest to the unit circle comes last and the gain sits in the first.
    pub fn to_sections(&self) -> Result<Vec<[f64; 6]>, PairingError> {
        if !self.gain.is_finite() {
            return Err(PairingError::Gain);
        }
        let mut zeros = self.zeros.clone();
        let mut poles = self.poles.clone();
        if zeros.is_empty() && poles.is_empty() {
            return Ok(vec![[self.gain, 0.0, 0.0, 1.0, 0.0, 0.0]]);
        }
        // Same number of poles and zeros, then an even number of each: the padding sits at the
        // origin, where it changes nothing but the sections' shape.
        let origin = Complex64::new(0.0, 0.0);
        let count = zeros.len().max(poles.len());
        zeros.resize(count, origin);
        poles.resize(count, origin);
        let sections = count.div_ceil(2);
        if count % 2 == 1 {
            zeros.push(origin);
            poles.push(origin);
        }

        let mut zeros = conjugates_then_reals(&zeros, "zero")?;
        let mut poles = conjugates_then_reals(&poles, "pole")?;

        let mut rows = vec![[0.0; 6]; sections];
        for row in rows.iter_mut().rev() {
            let Some(p1_index) = index_closest_to_unit_circle(&poles) else {
                break;
            };
            let p1 = poles.remove(p1_index);
            let reals_left = poles.iter().filter(|p| is_real(**p)).count();
            let real_zeros_left = zeros.iter().filter(|z| is_real(**z)).count();

            *row = if is_real(p1) && reals_left == 0 {
                // The last real pole: it goes with the nearest real zero and one at the origin.
                let z1 = take_nearest(&mut zeros, p1, Which::Real).unwrap_or(origin);
                section(&[z1, origin], &[p1, origin])
            } else if poles.len() + 1 == zeros.len()
                && !is_real(p1)
                && reals_left == 1
                && real_zeros_left == 1
            {
                // One real pole and one real zero are left for a later section, so this complex
                // pole must take a complex zero pair.
                match take_nearest(&mut zeros, p1, Which::Complex) {
                    Some(z1) => section(&[z1, z1.conj()], &[p1, p1.conj()]),
                    None => section(&[], &[p1, p1.conj()]),
                }
            } else {
                let p2 = if is_real(p1) {
                    let real_indices: Vec<usize> =
                        (0..poles.len()).filter(|&i| is_real(poles[i])).collect();
                    let reals: Vec<Complex64> = real_indices.iter().map(|&i| poles[i]).collect();
                    match index_closest_to_unit_circle(&reals) {
                        Some(j) => poles.remove(real_indices[j]),
                        None => origin,
                    }
                } else {
                    p1.conj()
                };
                match take_nearest(&mut zeros, p1, Which::Any) {
                    Some(z1) if !is_real(z1) => section(&[z1, z1.conj()], &[p1, p2]),
                    Some(z1) => match take_nearest(&mut zeros, p1, Which::Real) {
                        Some(z2) => section(&[z1, z2], &[p1, p2]),
                        None => section(&[z1], &[p1, p2]),
                    },
                    None => section(&[], &[p1, p2]),
                }
            };
        }
        if let Some(first) = rows.first_mut() {
            for b in &mut first[..3] {
                *b *= self.gain;
            }
        }
        Ok(rows)
    }
}

/// One member of each conjugate pair (positive imaginary part, averaged with its partner) sorted
/// by real part and then by imaginary part, followed by the real values sorted.
fn conjugates_then_reals(
    values: &[Complex64],
    what: &'static str,
) -> Result<Vec<Complex64>, PairingError> {
    let mut sorted = values.to_vec();
    // A stable sort by real part, then by the magnitude of the imaginary part.
    sorted.sort_by(|a, b| {
        a.re.total_cmp(&b.re)
            .then(a.im.abs().total_cmp(&b.im.abs()))
    });
    let (reals, complex): (Vec<Complex64>, Vec<Complex64>) = sorted
        .into_iter()
        .partition(|z| z.im.abs() <= CONJUGATE_TOLERANCE * abs(*z));
    let mut upper: Vec<Complex64> = complex.iter().copied().filter(|z| z.im > 0.0).collect();
    let mut lower: Vec<Complex64> = complex.iter().copied().filter(|z| z.im < 0.0).collect();
    if upper.len() != lower.len() {
        return Err(PairingError::UnpairedComplex { what });
    }
    // Within a run of (nearly) equal real parts, order by imaginary part so partners line up.
    let mut start = 0;
    while start < upper.len() {
        let mut end = start + 1;
        while end < upper.len()
            && upper[end].re - upper[end - 1].re <= CONJUGATE_TOLERANCE * abs(upper[end - 1])
        {
            end += 1;
        }
        if end - start > 1 {
            upper[start..end].sort_by(|a, b| a.im.abs().total_cmp(&b.im.abs()));
            lower[start..end].sort_by(|a, b| a.im.abs().total_cmp(&b.im.abs()));
        }
        start = end;
    }
    let mut out = Vec::with_capacity(upper.len() + reals.len());
    for (u, l) in upper.iter().zip(&lower) {
        if abs(*u - l.conj()) > CONJUGATE_TOLERANCE * abs(*l) {
            return Err(PairingError::UnpairedComplex { what });
        }
        out.push((*u + l.conj()) * 0.5);
    }
    out.extend(reals.iter().map(|z| Complex64::new(z.re, 0.0)));
    Ok(out)
}

/// Distances to the unit circle this close (relative) count as equal.
///
/// Mirror-image poles (a band-pass or band-stop whose edges add up to half the sampling rate, so
/// its band is centred on `f_s/4` in the warped sense) are equally close to the circle in exact
/// arithmetic; which one rounding makes closer decides the section order. scipy takes the first
/// of exactly equal distances, in the order of step 2. Treating near-equal distances as equal
/// makes this pick what scipy picks whenever scipy's rounding produced an exact tie; when its
/// rounding split the tie by an ulp, the order of the sections (not the filter) may differ.
const TIE_TOLERANCE: f64 = 1e-12;

/// The index of the value whose magnitude is closest to 1 (the first of equals).
fn index_closest_to_unit_circle(values: &[Complex64]) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, v) in values.iter().enumerate() {
        let distance = (1.0 - abs(*v)).abs();
        if best.is_none_or(|(_, d)| distance < d - TIE_TOLERANCE * d) {
            best = Some((i, distance));
        }
    }
    best.map(|(i, _)| i)
}

#[derive(Clone, Copy, PartialEq)]
enum Which {
    Real,
    Complex,
    Any,
}

/// Removes and returns the value of the requested kind nearest to `target`.
fn take_nearest(values: &mut Vec<Complex64>, target: Complex64, which: Which) -> Option<Complex64> {
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&a, &b| abs(values[a] - target).total_cmp(&abs(values[b] - target)));
    let index = order.into_iter().find(|&i| match which {
        Which::Any => true,
        Which::Real => is_real(values[i]),
        Which::Complex => !is_real(values[i]),
    })?;
    Some(values.remove(index))
}

/// The real coefficients of `Π(x − rᵢ)` for up to two roots, highest power first.
fn polynomial(roots: &[Complex64]) -> Vec<f64> {
    let mut coefficients = vec![Complex64::new(1.0, 0.0)];
    for &root in roots {
        let mut next = vec![Complex64::new(0.0, 0.0); coefficients.len() + 1];
        for (i, &c) in coefficients.iter().enumerate() {
            next[i] += c;
            next[i + 1] += c * -root;
        }
        coefficients = next;
    }
    coefficients.iter().map(|c| c.re).collect()
}

/// One section from up to two zeros and two poles, each polynomial right-aligned in its half of
/// the row as scipy's `_single_zpksos` places it.
fn section(zeros: &[Complex64], poles: &[Complex64]) -> [f64; 6] {
    let mut row = [0.0; 6];
    let b = polynomial(zeros);
    let a = polynomial(poles);
    row[3 - b.len()..3].copy_from_slice(&b);
    row[6 - a.len()..6].copy_from_slice(&a);
    row
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(re: f64, im: f64) -> Complex64 {
        Complex64::new(re, im)
    }

    #[test]
    fn scipy_docstring_example_pairs_nearest() {
        // zpk2sos([-1, -0.5-0.5j, -0.5+0.5j], [0.75, 0.8+0.1j, 0.8-0.1j], 1)
        let zpk = Zpk {
            zeros: vec![c(-1.0, 0.0), c(-0.5, -0.5), c(-0.5, 0.5)],
            poles: vec![c(0.75, 0.0), c(0.8, 0.1), c(0.8, -0.1)],
            gain: 1.0,
        };
        let rows = zpk.to_sections().unwrap();
        let expected = [
            [1.0, 1.0, 0.5, 1.0, -0.75, 0.0],
            [1.0, 1.0, 0.0, 1.0, -1.6, 0.65],
        ];
        for (row, want) in rows.iter().zip(&expected) {
            for (x, y) in row.iter().zip(want) {
                assert!((x - y).abs() < 1e-15, "{row:?} vs {want:?}");
            }
        }
    }

    #[test]
    fn unpaired_complex_pole_is_an_error_not_a_panic() {
        let zpk = Zpk {
            zeros: vec![],
            poles: vec![c(0.5, 0.5)],
            gain: 1.0,
        };
        assert_eq!(
            zpk.to_sections(),
            Err(PairingError::UnpairedComplex { what: "pole" })
        );
    }

    #[test]
    fn gain_only_is_one_pass_through_section() {
        let zpk = Zpk {
            zeros: vec![],
            poles: vec![],
            gain: 2.0,
        };
        assert_eq!(
            zpk.to_sections().unwrap(),
            vec![[2.0, 0.0, 0.0, 1.0, 0.0, 0.0]]
        );
    }
}
