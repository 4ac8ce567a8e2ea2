//! Numerics: transcendental functions with the same bits on every target, and the least-squares
//! fit behind every calibration ([`least_squares`]).
//!
//! ## Transcendental functions
//!
//! `f64::sin` and friends call the platform's C library natively (glibc on Linux) but a Rust port
//! of musl's libm in wasm; the two can differ in the last bit, and a closed loop that quantises its
//! output can turn one bit into a different trace. Core code that feeds a simulation uses these
//! wrappers instead, so a seed gives the same trace natively and in the browser. Arithmetic and
//! `sqrt` are exactly rounded by IEEE 754 everywhere and need no wrapper.
//!
//! The simulation's inner loop (10 kHz, several angles per sample) avoids the library calls
//! altogether where it can, with arithmetic that is exactly rounded on every target and so gives
//! the same bits too: [`Phasor`] keeps an advancing angle's cosine and sine by rotation,
//! [`wrap_turn`] replaces `rem_euclid(2π)` for an angle that moved by less than a turn, and
//! [`round_ties_even`] rounds without a call.
//!
//! | file | what |
//! |---|---|
//! | this file | sine, cosine, exponential and friends through libm, `Phasor`, `wrap_turn`, `round_ties_even` |
//! | [`least_squares`] | ordinary least squares by Householder QR, for every calibration |

pub mod least_squares;

use std::f64::consts::TAU;

/// Sine of `x` radians.
#[inline]
pub fn sin(x: f64) -> f64 {
    libm::sin(x)
}

/// Cosine of `x` radians.
#[inline]
pub fn cos(x: f64) -> f64 {
    libm::cos(x)
}

/// Tangent of `x` radians.
#[inline]
pub fn tan(x: f64) -> f64 {
    libm::tan(x)
}

/// Four-quadrant arc tangent of `y / x`, in radians.
#[inline]
pub fn atan2(y: f64, x: f64) -> f64 {
    libm::atan2(y, x)
}

/// Arc cosine, in radians.
#[inline]
pub fn acos(x: f64) -> f64 {
    libm::acos(x)
}

/// Arc sine, in radians.
#[inline]
pub fn asin(x: f64) -> f64 {
    libm::asin(x)
}

/// `e^x`.
#[inline]
pub fn exp(x: f64) -> f64 {
    libm::exp(x)
}

/// Natural logarithm.
#[inline]
pub fn ln(x: f64) -> f64 {
    libm::log(x)
}

/// `x^y`.
#[inline]
pub fn pow(x: f64, y: f64) -> f64 {
    libm::pow(x, y)
}

/// `sqrt(x² + y²)` without undue overflow.
#[inline]
pub fn hypot(x: f64, y: f64) -> f64 {
    libm::hypot(x, y)
}

/// `x` rounded to the nearest integer, ties to even, by two additions (exactly rounded on every
/// target, and no library call: the ADC quantises every sample with it). Valid for
/// |x| < 2⁵¹; NaN stays NaN.
///
/// ```
/// use cutlab::math::round_ties_even;
/// assert_eq!(round_ties_even(2.4), 2.0);
/// assert_eq!(round_ties_even(-2.6), -3.0);
/// assert_eq!(round_ties_even(2.5), 2.0);
/// assert_eq!(round_ties_even(3.5), 4.0);
/// ```
#[inline(always)]
pub fn round_ties_even(x: f64) -> f64 {
    // 1.5·2⁵²: the sum lies in [2⁵², 2⁵³), where the spacing of doubles is 1, so the addition
    // rounds x to an integer (ties to even, as IEEE 754 rounds) and the subtraction is exact.
    const SHIFT: f64 = 6_755_399_441_055_744.0;
    (x + SHIFT) - SHIFT
}

/// The larger of `a` and `b`, a NaN giving way to the other (as `f64::max`), by one comparison:
/// wasm has no instruction with `f64::max`'s NaN rule, so the standard method is a library call
/// there, and the simulation takes a few maxima every sample.
#[inline(always)]
pub fn max(a: f64, b: f64) -> f64 {
    if a > b || b.is_nan() {
        a
    } else {
        b
    }
}

/// The smaller of `a` and `b`, a NaN giving way to the other (as `f64::min`); see [`max`].
#[inline(always)]
pub fn min(a: f64, b: f64) -> f64 {
    if a < b || b.is_nan() {
        a
    } else {
        b
    }
}

/// `x` clamped to [`lo`, `hi`] (`lo` ≤ `hi`), NaN staying NaN (as `f64::clamp`); see [`max`].
///
/// ```
/// use cutlab::math::{clamp, max, min};
/// assert_eq!((clamp(5.0, 0.0, 1.0), clamp(-5.0, 0.0, 1.0), clamp(0.5, 0.0, 1.0)), (1.0, 0.0, 0.5));
/// assert!(clamp(f64::NAN, 0.0, 1.0).is_nan());
/// assert_eq!((max(f64::NAN, 2.0), max(2.0, f64::NAN), min(f64::NAN, 2.0)), (2.0, 2.0, 2.0));
/// ```
#[inline(always)]
pub fn clamp(x: f64, lo: f64, hi: f64) -> f64 {
    if x < lo {
        lo
    } else if x > hi {
        hi
    } else {
        x
    }
}

/// `angle_rad` brought into [0, 2π), the same bits as `angle_rad.rem_euclid(2π)`: an angle that
/// moved by less than a turn out of [0, 2π) comes back by one addition of ±2π (the one
/// `rem_euclid` makes after its remainder, which is exact there: a − 2π is exact for a in
/// [π, 4π] by Sterbenz's lemma) instead of a floating-point remainder.
///
/// ```
/// use cutlab::math::wrap_turn;
/// use std::f64::consts::TAU;
/// for a in [0.0, 1.0, TAU + 0.5, -0.25, 3.0 * TAU + 1.0, -2.5 * TAU] {
///     assert_eq!(wrap_turn(a), a.rem_euclid(TAU));
/// }
/// ```
#[inline(always)]
pub fn wrap_turn(angle_rad: f64) -> f64 {
    if (0.0..TAU).contains(&angle_rad) {
        angle_rad
    } else if (TAU..2.0 * TAU).contains(&angle_rad) {
        angle_rad - TAU
    } else if (-TAU..0.0).contains(&angle_rad) {
        angle_rad + TAU
    } else {
        angle_rad.rem_euclid(TAU)
    }
}

/// Steps up to this size (radians) rotate a [`Phasor`] by a short series; larger ones recompute
/// its cosine and sine.
const PHASOR_SMALL_STEP_RAD: f64 = 0.25;

/// A [`Phasor`] recomputes its cosine and sine from its angle after this many rotations, so
/// rounding cannot accumulate (the drift in between is ~10⁻¹³ rad).
pub const PHASOR_RESYNC_STEPS: u32 = 1024;

/// Below this step (radians) the short form of [`small_cos_sin`] is already exact.
const PHASOR_TINY_STEP_RAD: f64 = 1.0 / 32.0;

/// cos δ and sin δ for |δ| ≤ [`PHASOR_SMALL_STEP_RAD`] by their Taylor series, the first term
/// left out below 10⁻¹⁷ (under half an ulp): up to δ¹³ in general, up to δ⁸ for the steps of
/// ordinary speeds (|δ| ≤ 1/32, where δ⁹/9! < 10⁻¹⁹).
#[inline(always)]
fn small_cos_sin(d: f64) -> (f64, f64) {
    // Horner in d² with the reciprocal factorials folded into constants (no division).
    const S: [f64; 6] = [
        -1.0 / 6.0,
        1.0 / 120.0,
        -1.0 / 5_040.0,
        1.0 / 362_880.0,
        -1.0 / 39_916_800.0,
        1.0 / 6_227_020_800.0,
    ];
    const C: [f64; 6] = [
        -1.0 / 2.0,
        1.0 / 24.0,
        -1.0 / 720.0,
        1.0 / 40_320.0,
        -1.0 / 3_628_800.0,
        1.0 / 479_001_600.0,
    ];
    let d2 = d * d;
    let (s, c) = if d.abs() <= PHASOR_TINY_STEP_RAD {
        (
            S[0] + d2 * (S[1] + d2 * S[2]),
            C[0] + d2 * (C[1] + d2 * (C[2] + d2 * C[3])),
        )
    } else {
        (
            S[0] + d2 * (S[1] + d2 * (S[2] + d2 * (S[3] + d2 * (S[4] + d2 * S[5])))),
            C[0] + d2 * (C[1] + d2 * (C[2] + d2 * (C[3] + d2 * (C[4] + d2 * C[5])))),
        )
    };
    (1.0 + d2 * c, d + d * d2 * s)
}

/// An angle that advances by small steps, with its cosine and sine.
///
/// A motor's electrical angle or a spindle's tool angle moves by a fraction of a radian per
/// sample. Instead of calling `sin` and `cos` every sample (with their argument reduction), the
/// phasor (cos θ, sin θ) is rotated by the step δ — cos δ and sin δ from a short series — and
/// recomputed exactly from θ every [`PHASOR_RESYNC_STEPS`] steps, which keeps its length and
/// phase within ~10⁻¹³ of the exact values. The angle itself is kept in [0, 2π) by
/// [`wrap_turn`]. Everything is exactly rounded arithmetic or [`crate::math`]'s functions, so a
/// run gives the same bits natively and in wasm.
///
/// A NaN step makes the angle and both values NaN (as `sin(NaN)` would).
///
/// ```
/// use cutlab::math::Phasor;
/// let mut p = Phasor::new(0.0);
/// for _ in 0..10_000 {
///     p.advance(0.01);
/// }
/// // The angle is the sum of its steps (to their rounding, ~10⁻¹² after 10 000), and the
/// // cosine and sine are those of the angle.
/// let exact = 100.0f64.rem_euclid(std::f64::consts::TAU);
/// assert!((p.angle_rad() - exact).abs() < 1e-10);
/// let a = p.angle_rad();
/// assert!((p.cos() - a.cos()).abs() < 1e-12 && (p.sin() - a.sin()).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Phasor {
    angle_rad: f64,
    cos: f64,
    sin: f64,
    steps_since_exact: u32,
}

impl Phasor {
    /// A phasor at `angle_rad` (brought into [0, 2π)).
    pub fn new(angle_rad: f64) -> Self {
        let angle_rad = wrap_turn(angle_rad);
        Self {
            angle_rad,
            cos: cos(angle_rad),
            sin: sin(angle_rad),
            steps_since_exact: 0,
        }
    }

    /// The angle, in [0, 2π).
    #[inline]
    pub fn angle_rad(&self) -> f64 {
        self.angle_rad
    }

    /// cos θ.
    #[inline]
    pub fn cos(&self) -> f64 {
        self.cos
    }

    /// sin θ.
    #[inline]
    pub fn sin(&self) -> f64 {
        self.sin
    }

    /// Advances the angle by `step_rad`.
    #[inline(always)]
    pub fn advance(&mut self, step_rad: f64) {
        if step_rad == 0.0 {
            // At rest (an axis that does not move): nothing turns, nothing accumulates.
            return;
        }
        self.angle_rad = wrap_turn(self.angle_rad + step_rad);
        self.steps_since_exact += 1;
        // A NaN step fails the comparison and takes the exact path, which makes both NaN.
        let small = step_rad.abs() <= PHASOR_SMALL_STEP_RAD;
        if small && self.steps_since_exact < PHASOR_RESYNC_STEPS {
            let (c, s) = small_cos_sin(step_rad);
            let (c0, s0) = (self.cos, self.sin);
            self.cos = c0 * c - s0 * s;
            self.sin = s0 * c + c0 * s;
        } else {
            self.resync();
        }
    }

    /// Recomputes cos θ and sin θ from θ (once in [`PHASOR_RESYNC_STEPS`] steps: kept out of
    /// line so the rotation inlines).
    #[cold]
    #[inline(never)]
    fn resync(&mut self) {
        self.cos = cos(self.angle_rad);
        self.sin = sin(self.angle_rad);
        self.steps_since_exact = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_short_series_is_exact_to_an_ulp_over_its_range() {
        for i in -1000..=1000 {
            let d = PHASOR_SMALL_STEP_RAD * f64::from(i) / 1000.0;
            let (c, s) = small_cos_sin(d);
            assert!((c - cos(d)).abs() <= f64::EPSILON, "cos {d}");
            assert!(
                (s - sin(d)).abs() <= f64::EPSILON * d.abs().max(1e-300),
                "sin {d}"
            );
        }
    }

    #[test]
    fn a_phasor_follows_its_angle_over_a_long_run_at_varying_steps() {
        let mut p = Phasor::new(1.0);
        let mut angle = 1.0f64;
        for k in 0..200_000 {
            // Steps of a drive whose speed wanders, with an occasional large one.
            let step = if k % 50_000 == 7 {
                2.0
            } else {
                0.02 + 0.015 * sin(f64::from(k) * 1e-3)
            };
            p.advance(step);
            angle = (angle + step).rem_euclid(TAU);
            assert!((p.angle_rad() - angle).abs() < 1e-9);
            assert!((p.cos() - cos(p.angle_rad())).abs() < 1e-12, "step {k}");
            assert!((p.sin() - sin(p.angle_rad())).abs() < 1e-12, "step {k}");
        }
        // Backwards too, and NaN propagates.
        p.advance(-0.1);
        assert!(p.angle_rad() >= 0.0 && p.angle_rad() < TAU);
        p.advance(f64::NAN);
        assert!(p.angle_rad().is_nan() && p.cos().is_nan() && p.sin().is_nan());
    }

    #[test]
    fn wrapping_a_turn_gives_the_bits_of_rem_euclid() {
        for i in -4000..4000 {
            let a = f64::from(i) * 0.00731 + 1e-9 * f64::from(i % 7);
            assert_eq!(wrap_turn(a).to_bits(), a.rem_euclid(TAU).to_bits(), "{a}");
        }
        assert!(wrap_turn(f64::NAN).is_nan());
    }

    #[test]
    fn rounding_by_addition_matches_round_ties_even() {
        for i in -100_000..100_000 {
            let x = f64::from(i) * 0.0137 - 0.5;
            assert_eq!(round_ties_even(x), x.round_ties_even(), "{x}");
        }
        for x in [0.5, 1.5, -0.5, -1.5, 2.5, 1e15 + 0.5] {
            assert_eq!(round_ties_even(x), x.round_ties_even(), "{x}");
        }
        assert!(round_ties_even(f64::NAN).is_nan());
    }

    #[test]
    fn wrappers_agree_with_std_to_an_ulp() {
        for i in 0..1000 {
            let x = -20.0 + 0.04 * f64::from(i);
            assert!((sin(x) - x.sin()).abs() <= 2.0 * f64::EPSILON);
            assert!((cos(x) - x.cos()).abs() <= 2.0 * f64::EPSILON);
            let e = exp(x / 4.0);
            assert!((e - (x / 4.0).exp()).abs() <= 2.0 * f64::EPSILON * e);
        }
        assert_eq!(ln(1.0), 0.0);
        assert_eq!(pow(2.0, 10.0), 1024.0);
    }
}
