//! Complex arithmetic that gives the same bits natively and in wasm.
//!
//! `num_complex`'s `sqrt`, `exp` and `/` go through `std`'s transcendental functions or a
//! textbook formula; the filter design feeds simulations, so it uses these instead: division by
//! Smith's method (the algorithm numpy uses, so a design reproduces scipy's to the last few bits)
//! and the principal square root computed from `hypot` and `sqrt` only.

use rustfft::num_complex::Complex64;

use crate::math;

/// `a / b` by Smith's method: scales by the larger component of `b` so that no intermediate
/// overflows, as numpy does.
pub(crate) fn div(a: Complex64, b: Complex64) -> Complex64 {
    if b.re.abs() >= b.im.abs() {
        if b.re == 0.0 && b.im == 0.0 {
            // Division by zero: a complex ∞ or NaN, as IEEE would give component-wise.
            return Complex64::new(a.re / b.re.abs(), a.im / b.re.abs());
        }
        let ratio = b.im / b.re;
        let scale = 1.0 / (b.re + b.im * ratio);
        Complex64::new((a.re + a.im * ratio) * scale, (a.im - a.re * ratio) * scale)
    } else {
        let ratio = b.re / b.im;
        let scale = 1.0 / (b.im + b.re * ratio);
        Complex64::new((a.re * ratio + a.im) * scale, (a.im * ratio - a.re) * scale)
    }
}

/// The real number `x` divided by `b`.
pub(crate) fn real_div(x: f64, b: Complex64) -> Complex64 {
    div(Complex64::new(x, 0.0), b)
}

/// The principal square root (real part ≥ 0; the sign of the imaginary part follows `z.im`,
/// including the sign of zero, as C's `csqrt`).
pub(crate) fn sqrt(z: Complex64) -> Complex64 {
    if z.re == 0.0 && z.im == 0.0 {
        return Complex64::new(0.0, z.im);
    }
    let t = ((z.re.abs() + math::hypot(z.re, z.im)) / 2.0).sqrt();
    if z.re >= 0.0 {
        Complex64::new(t, z.im / (2.0 * t))
    } else {
        Complex64::new(z.im.abs() / (2.0 * t), t.copysign(z.im))
    }
}

/// `e^{iθ}`.
pub(crate) fn exp_i(theta: f64) -> Complex64 {
    Complex64::new(math::cos(theta), math::sin(theta))
}

/// The product of `values`, multiplied left to right (1 for none).
pub(crate) fn product(values: &[Complex64]) -> Complex64 {
    values
        .iter()
        .fold(Complex64::new(1.0, 0.0), |acc, &v| acc * v)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Complex64, b: Complex64) -> bool {
        (a - b).norm() <= 1e-15 * b.norm().max(1.0)
    }

    #[test]
    fn division_matches_the_definition() {
        let cases = [
            (Complex64::new(1.0, 2.0), Complex64::new(3.0, -4.0)),
            (Complex64::new(-2.5, 0.5), Complex64::new(0.1, 7.0)),
            (Complex64::new(4.0, 0.0), Complex64::new(4.0, 0.0)),
        ];
        for (a, b) in cases {
            let expected = a * b.conj() / b.norm_sqr();
            assert!(close(div(a, b), expected), "{a} / {b}");
        }
        let inf = div(Complex64::new(1.0, 0.0), Complex64::new(0.0, 0.0));
        assert!(inf.re.is_infinite());
    }

    #[test]
    fn square_root_is_principal_and_squares_back() {
        for (re, im) in [
            (4.0, 0.0),
            (-4.0, 0.0),
            (-4.0, -0.0),
            (3.0, 4.0),
            (-3.0, -4.0),
        ] {
            let z = Complex64::new(re, im);
            let r = sqrt(z);
            assert!(r.re >= 0.0);
            assert!(close(r * r, z), "sqrt({z}) = {r}");
        }
        assert_eq!(sqrt(Complex64::new(-4.0, 0.0)), Complex64::new(0.0, 2.0));
        assert_eq!(sqrt(Complex64::new(-4.0, -0.0)), Complex64::new(0.0, -2.0));
    }

    #[test]
    fn product_of_nothing_is_one() {
        assert_eq!(product(&[]), Complex64::new(1.0, 0.0));
        let p = product(&[Complex64::new(0.0, 1.0), Complex64::new(0.0, 1.0)]);
        assert!(close(p, Complex64::new(-1.0, 0.0)));
    }
}
