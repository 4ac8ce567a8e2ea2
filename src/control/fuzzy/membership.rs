//! Membership functions: triangle, trapezoid and ramp (fuzzylite's shoulder), as exact
//! piecewise-linear functions.
//!
//! Conventions follow fuzzylite 6 so that an FLL file means the same here and there: a triangle
//! `a b c` is 0 outside [a, c] and 1 at b; a trapezoid `a b c d` is 1 on [b, c]; a ramp
//! `start end` is 0 at and before `start` and 1 at and after `end` (decreasing when
//! `end < start`). Degenerate edges (a = b) are vertical: the degree jumps to 1 at the vertex.
//! A NaN input has degree 0 (it activates nothing), where fuzzylite would propagate NaN.

use std::fmt;

use super::FuzzyError;

/// The shape of one linguistic term.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// Rises from `a` to 1 at `b`, falls to 0 at `c`.
    Triangle {
        /// Left foot.
        a: f64,
        /// Peak.
        b: f64,
        /// Right foot.
        c: f64,
    },
    /// Rises from `a` to 1 at `b`, stays 1 to `c`, falls to 0 at `d`.
    Trapezoid {
        /// Left foot.
        a: f64,
        /// Left shoulder.
        b: f64,
        /// Right shoulder.
        c: f64,
        /// Right foot.
        d: f64,
    },
    /// A shoulder: 0 at `start`, 1 at `end`, constant beyond.
    Ramp {
        /// Where the degree is 0.
        start: f64,
        /// Where the degree reaches 1.
        end: f64,
    },
}

fn finite(values: &[f64]) -> bool {
    values.iter().all(|v| v.is_finite())
}

impl Shape {
    /// A triangle; `a ≤ b ≤ c`, `a < c`, all finite.
    ///
    /// ```
    /// use cutlab::control::fuzzy::membership::Shape;
    /// let t = Shape::triangle(-2.0, 0.0, 2.0).unwrap();
    /// assert_eq!(t.degree(1.0), 0.5);
    /// assert!(Shape::triangle(1.0, 0.0, 2.0).is_err());
    /// ```
    pub fn triangle(a: f64, b: f64, c: f64) -> Result<Self, FuzzyError> {
        if !(finite(&[a, b, c]) && a <= b && b <= c && a < c) {
            return Err(FuzzyError::new(format!(
                "a triangle needs a ≤ b ≤ c with a < c, got {a} {b} {c}"
            )));
        }
        Ok(Shape::Triangle { a, b, c })
    }

    /// A trapezoid; `a ≤ b ≤ c ≤ d`, `a < d`, all finite.
    pub fn trapezoid(a: f64, b: f64, c: f64, d: f64) -> Result<Self, FuzzyError> {
        if !(finite(&[a, b, c, d]) && a <= b && b <= c && c <= d && a < d) {
            return Err(FuzzyError::new(format!(
                "a trapezoid needs a ≤ b ≤ c ≤ d with a < d, got {a} {b} {c} {d}"
            )));
        }
        Ok(Shape::Trapezoid { a, b, c, d })
    }

    /// A ramp (shoulder); `start ≠ end`, both finite.
    pub fn ramp(start: f64, end: f64) -> Result<Self, FuzzyError> {
        if !(finite(&[start, end]) && start != end) {
            return Err(FuzzyError::new(format!(
                "a ramp needs two different finite ends, got {start} {end}"
            )));
        }
        Ok(Shape::Ramp { start, end })
    }

    /// The degree of membership of `x`, in [0, 1].
    pub fn degree(&self, x: f64) -> f64 {
        if x.is_nan() {
            return 0.0;
        }
        match *self {
            Shape::Triangle { a, b, c } => {
                if x < a || x > c {
                    0.0
                } else if x == b {
                    1.0
                } else if x < b {
                    (x - a) / (b - a)
                } else {
                    (c - x) / (c - b)
                }
            }
            Shape::Trapezoid { a, b, c, d } => {
                if x < a || x > d {
                    0.0
                } else if x < b {
                    (x - a) / (b - a)
                } else if x <= c {
                    1.0
                } else {
                    (d - x) / (d - c)
                }
            }
            Shape::Ramp { start, end } => {
                if start < end {
                    if x <= start {
                        0.0
                    } else if x >= end {
                        1.0
                    } else {
                        (x - start) / (end - start)
                    }
                } else if x >= start {
                    0.0
                } else if x <= end {
                    1.0
                } else {
                    (start - x) / (start - end)
                }
            }
        }
    }

    /// The x values where the slope can change.
    pub fn vertices(&self) -> ([f64; 4], usize) {
        match *self {
            Shape::Triangle { a, b, c } => ([a, b, c, 0.0], 3),
            Shape::Trapezoid { a, b, c, d } => ([a, b, c, d], 4),
            Shape::Ramp { start, end } => ([start, end, 0.0, 0.0], 2),
        }
    }

    /// The value "associated with" the term in a weighted average (paper 002 eq 7): the peak of
    /// a triangle, the middle of a trapezoid's plateau, the full end of a ramp.
    pub fn centre(&self) -> f64 {
        match *self {
            Shape::Triangle { b, .. } => b,
            Shape::Trapezoid { b, c, .. } => (b + c) / 2.0,
            Shape::Ramp { end, .. } => end,
        }
    }

    /// The values just inside the ends of `[x0, x1]`, an interval containing no vertex inside,
    /// so the shape is one straight piece there: (f(x0⁺), f(x1⁻)). One-sided values get vertical
    /// edges right.
    pub fn piece(&self, x0: f64, x1: f64) -> (f64, f64) {
        let third = (x1 - x0) / 3.0;
        let p = self.degree(x0 + third);
        let q = self.degree(x1 - third);
        (2.0 * p - q, 2.0 * q - p)
    }
}

/// The shape as an FLL term writes it: `Triangle -6 -6 -4`, `Trapezoid 0 1 2 4`, `Ramp 2 0`.
impl fmt::Display for Shape {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Shape::Triangle { a, b, c } => write!(f, "Triangle {a} {b} {c}"),
            Shape::Trapezoid { a, b, c, d } => write!(f, "Trapezoid {a} {b} {c} {d}"),
            Shape::Ramp { start, end } => write!(f, "Ramp {start} {end}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn degrees_follow_fuzzylite_conventions() {
        let right_angle = Shape::triangle(-6.0, -6.0, -4.0).unwrap();
        assert_eq!(right_angle.degree(-6.0), 1.0);
        assert_eq!(right_angle.degree(-5.0), 0.5);
        assert_eq!(right_angle.degree(-6.5), 0.0);
        let trap = Shape::trapezoid(0.0, 1.0, 2.0, 4.0).unwrap();
        assert_eq!(trap.degree(1.5), 1.0);
        assert_eq!(trap.degree(3.0), 0.5);
        let down = Shape::ramp(2.0, 0.0).unwrap();
        assert_eq!(down.degree(-1.0), 1.0);
        assert_eq!(down.degree(0.5), 0.75);
        assert_eq!(down.degree(3.0), 0.0);
        assert_eq!(trap.degree(f64::NAN), 0.0);
    }

    #[test]
    fn pieces_are_one_sided_at_vertical_edges() {
        let t = Shape::triangle(0.0, 0.0, 2.0).unwrap();
        let (f0, f1) = t.piece(0.0, 2.0);
        assert!((f0 - 1.0).abs() < 1e-12 && f1.abs() < 1e-12);
    }
}
