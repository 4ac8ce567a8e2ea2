//! Transcendental functions with the same bits on every target.
//!
//! `f64::sin` and friends call the platform's C library natively (glibc on Linux) but a Rust port
//! of musl's libm in wasm; the two can differ in the last bit, and a closed loop that quantises its
//! output can turn one bit into a different trace. Core code that feeds a simulation uses these
//! wrappers instead, so a seed gives the same trace natively and in the browser. Arithmetic and
//! `sqrt` are exactly rounded by IEEE 754 everywhere and need no wrapper.

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

#[cfg(test)]
mod tests {
    use super::*;

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
