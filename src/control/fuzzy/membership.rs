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

/// An error if `right − left` overflows: the slopes of a shape that wide are not f64 numbers.
/// A shape's numbers for a message, compact (1e-320, not 320 zeros).
fn shown(values: &[f64]) -> String {
    values
        .iter()
        .map(|v| crate::input::readable(*v))
        .collect::<Vec<_>>()
        .join(" ")
}

fn span_fits(left: f64, right: f64) -> Result<(), FuzzyError> {
    if (right - left).is_finite() {
        Ok(())
    } else {
        Err(FuzzyError::new(format!(
            "a shape from {left:?} to {right:?} is wider than an f64 can hold"
        )))
    }
}

impl Shape {
    /// A triangle; `a ≤ b ≤ c`, `a < c`, all finite, and `c − a` finite (a wider triangle's
    /// degrees cannot be computed in f64).
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
                "a triangle needs a ≤ b ≤ c with a < c, got {}",
                shown(&[a, b, c])
            )));
        }
        span_fits(a, c)?;
        Ok(Shape::Triangle { a, b, c })
    }

    /// A trapezoid; `a ≤ b ≤ c ≤ d`, `a < d`, all finite, and `d − a` finite.
    pub fn trapezoid(a: f64, b: f64, c: f64, d: f64) -> Result<Self, FuzzyError> {
        if !(finite(&[a, b, c, d]) && a <= b && b <= c && c <= d && a < d) {
            return Err(FuzzyError::new(format!(
                "a trapezoid needs a ≤ b ≤ c ≤ d with a < d, got {}",
                shown(&[a, b, c, d])
            )));
        }
        span_fits(a, d)?;
        Ok(Shape::Trapezoid { a, b, c, d })
    }

    /// A ramp (shoulder); `start ≠ end`, both finite, and `end − start` finite.
    pub fn ramp(start: f64, end: f64) -> Result<Self, FuzzyError> {
        if !(finite(&[start, end]) && start != end) {
            return Err(FuzzyError::new(format!(
                "a ramp needs two different finite ends, got {}",
                shown(&[start, end])
            )));
        }
        span_fits(start.min(end), start.max(end))?;
        Ok(Shape::Ramp { start, end })
    }

    /// The same shape if its fields pass its constructor's checks, else that constructor's error:
    /// the variants' fields are public, so a shape built without a constructor is checked here.
    ///
    /// ```
    /// use cutlab::control::fuzzy::membership::Shape;
    /// assert!(Shape::Triangle { a: 0.0, b: 1.0, c: 2.0 }.checked().is_ok());
    /// assert!(Shape::Triangle { a: 2.0, b: 1.0, c: 0.0 }.checked().is_err());
    /// assert!(Shape::Ramp { start: -1e308, end: 1e308 }.checked().is_err());
    /// ```
    pub fn checked(self) -> Result<Self, FuzzyError> {
        match self {
            Shape::Triangle { a, b, c } => Shape::triangle(a, b, c),
            Shape::Trapezoid { a, b, c, d } => Shape::trapezoid(a, b, c, d),
            Shape::Ramp { start, end } => Shape::ramp(start, end),
        }
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
            // The midpoint without overflow: c − b is finite for a checked shape.
            Shape::Trapezoid { b, c, .. } => b + (c - b) / 2.0,
            Shape::Ramp { end, .. } => end,
        }
    }

    /// Where the degree can be above 0: the open interval (left, right), infinite on a ramp's
    /// full side.
    pub fn support(&self) -> (f64, f64) {
        match *self {
            Shape::Triangle { a, c, .. } => (a, c),
            Shape::Trapezoid { a, d, .. } => (a, d),
            Shape::Ramp { start, end } if start < end => (start, f64::INFINITY),
            Shape::Ramp { start, .. } => (f64::NEG_INFINITY, start),
        }
    }

    /// The values just inside the ends of `[x0, x1]`, an interval containing no vertex inside,
    /// so the shape is one straight piece there: (f(x0⁺), f(x1⁻)). One-sided values get vertical
    /// edges right.
    ///
    /// The piece is picked from where the interval lies against the vertices and evaluated by its
    /// own formula at both ends, so the values are as exact as f64 allows at any magnitude and
    /// for an interval of any width (sampling inside the interval lost them to rounding when the
    /// interval was a few ulps wide).
    ///
    /// ```
    /// use cutlab::control::fuzzy::membership::Shape;
    /// let narrow = Shape::triangle(1.0, 1.0 + 0.5e-12, 1.0 + 1e-12).unwrap();
    /// assert_eq!(narrow.piece(1.0, 1.0 + 0.5e-12), (0.0, 1.0));
    /// ```
    pub fn piece(&self, x0: f64, x1: f64) -> (f64, f64) {
        // The straight line through (from, 0) and (to, 1), at x.
        let line = |from: f64, to: f64, x: f64| ((x - from) / (to - from)).clamp(0.0, 1.0);
        let both = |f: &dyn Fn(f64) -> f64| (f(x0), f(x1));
        match *self {
            Shape::Triangle { a, b, c } => {
                if x1 <= a || x0 >= c {
                    (0.0, 0.0)
                } else if x1 <= b {
                    both(&|x| line(a, b, x))
                } else {
                    both(&|x| line(c, b, x))
                }
            }
            Shape::Trapezoid { a, b, c, d } => {
                if x1 <= a || x0 >= d {
                    (0.0, 0.0)
                } else if x1 <= b {
                    both(&|x| line(a, b, x))
                } else if x1 <= c {
                    (1.0, 1.0)
                } else {
                    both(&|x| line(d, c, x))
                }
            }
            Shape::Ramp { start, end } => {
                let (zero_side, full_side) = if start < end {
                    (x1 <= start, x0 >= end)
                } else {
                    (x0 >= start, x1 <= end)
                };
                if zero_side {
                    (0.0, 0.0)
                } else if full_side {
                    (1.0, 1.0)
                } else {
                    both(&|x| line(start, end, x))
                }
            }
        }
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

    #[test]
    fn every_piece_is_the_straight_line_through_the_degrees_between_vertices() {
        let mut rng = crate::rng::Rng::seed_from(3);
        for _ in 0..2000 {
            let mut v: Vec<f64> = (0..4).map(|_| -5.0 + 10.0 * rng.uniform()).collect();
            v.sort_by(f64::total_cmp);
            // Sometimes a vertical edge.
            if rng.uniform() < 0.2 {
                v[1] = v[0];
            }
            let shapes = [
                Shape::triangle(v[0], v[1], v[3]),
                Shape::trapezoid(v[0], v[1], v[2], v[3]),
                Shape::ramp(v[0], v[3]),
                Shape::ramp(v[3], v[0]),
            ];
            for shape in shapes.into_iter().flatten() {
                let (vertices, n) = shape.vertices();
                let mut points = vec![-6.0, 6.0];
                points.extend(&vertices[..n]);
                points.sort_by(f64::total_cmp);
                points.dedup();
                for w in points.windows(2) {
                    let (x0, x1) = (w[0], w[1]);
                    let (f0, f1) = shape.piece(x0, x1);
                    for t in [0.25, 0.5, 0.75] {
                        let x = x0 + t * (x1 - x0);
                        let line = f0 + t * (f1 - f0);
                        assert!(
                            (line - shape.degree(x)).abs() < 1e-9,
                            "{shape} on [{x0}, {x1}] at {x}: {line} vs {}",
                            shape.degree(x)
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn shapes_wider_than_an_f64_are_refused() {
        assert!(Shape::triangle(-1e308, 0.0, 1e308).is_err());
        assert!(Shape::trapezoid(-1e308, 0.0, 0.0, 1e308).is_err());
        let e = Shape::ramp(1e308, -1e308).unwrap_err().to_string();
        assert_eq!(
            e,
            "a shape from -1e308 to 1e308 is wider than an f64 can hold"
        );
        assert!(Shape::ramp(1e308, 0.0).is_ok());
    }
}
