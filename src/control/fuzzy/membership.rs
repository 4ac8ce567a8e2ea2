//! Membership functions: every term of fuzzylite 6's language.
//!
//! Triangle, trapezoid and ramp (fuzzylite's shoulder) are exact piecewise-linear functions, and
//! the engine integrates aggregates of them in closed form. The other shapes follow fuzzylite 6's
//! formulas: Rectangle, Discrete (straight lines between points), Bell, Gaussian,
//! GaussianProduct, Cosine, Sigmoid, SigmoidDifference (|difference|), SigmoidProduct, Spike,
//! Concave, SShape, ZShape, PiShape. Constant, Linear and Function are Takagi–Sugeno terms: their
//! value does not depend on x but on the engine's inputs (Linear: c₀·x₀ + … + cₙ₋₁·xₙ₋₁ [+ cₙ];
//! Function: a formula of the inputs, the outputs and x, see [`super::function`]).
//!
//! Conventions follow fuzzylite 6 so that an FLL file means the same here and there: a triangle
//! `a b c` is 0 outside [a, c] and 1 at b; a trapezoid `a b c d` is 1 on [b, c]; a ramp
//! `start end` is 0 at and before `start` and 1 at and after `end` (decreasing when
//! `end < start`). Degenerate edges (a = b) are vertical: the degree jumps to 1 at the vertex.
//! A NaN input has degree 0 (it activates nothing), where fuzzylite would propagate NaN.

use std::fmt;

use super::function::Formula;
pub use super::function::Values;
use super::{FuzzyError, FUZZYLITE_EPSILON};

/// The shape of one linguistic term.
#[derive(Debug, Clone, PartialEq)]
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
    /// 1 on [start, end], 0 elsewhere.
    Rectangle {
        /// Left edge.
        start: f64,
        /// Right edge.
        end: f64,
    },
    /// Straight lines between (x, y) points sorted by x, constant beyond the ends.
    Discrete {
        /// The points, x non-decreasing, y in [0, 1].
        points: Vec<(f64, f64)>,
    },
    /// 1 / (1 + |(x − center) / width|^(2·slope)).
    Bell {
        /// Centre.
        center: f64,
        /// Half width at degree 0.5.
        width: f64,
        /// Steepness.
        slope: f64,
    },
    /// exp(−(x − mean)² / (2·sd²)).
    Gaussian {
        /// Mean.
        mean: f64,
        /// Standard deviation.
        sd: f64,
    },
    /// A Gaussian rising to 1 at `mean_a`, 1 up to `mean_b`, a Gaussian falling after it.
    GaussianProduct {
        /// Where the left Gaussian reaches 1.
        mean_a: f64,
        /// Its standard deviation.
        sd_a: f64,
        /// Where the right Gaussian starts falling.
        mean_b: f64,
        /// Its standard deviation.
        sd_b: f64,
    },
    /// ½(1 + cos(2π(x − center)/width)) within width/2 of the centre, 0 outside.
    Cosine {
        /// Centre.
        center: f64,
        /// Width of the support.
        width: f64,
    },
    /// 1 / (1 + exp(−slope·(x − inflection))).
    Sigmoid {
        /// Where the degree is 0.5.
        inflection: f64,
        /// Steepness (negative: decreasing).
        slope: f64,
    },
    /// |sigmoid(rising, left) − sigmoid(falling, right)|.
    SigmoidDifference {
        /// Inflection of the first sigmoid.
        left: f64,
        /// Slope of the first sigmoid.
        rising: f64,
        /// Slope of the second sigmoid.
        falling: f64,
        /// Inflection of the second sigmoid.
        right: f64,
    },
    /// sigmoid(rising, left) · sigmoid(falling, right).
    SigmoidProduct {
        /// Inflection of the first sigmoid.
        left: f64,
        /// Slope of the first sigmoid.
        rising: f64,
        /// Slope of the second sigmoid.
        falling: f64,
        /// Inflection of the second sigmoid.
        right: f64,
    },
    /// exp(−|10·(x − center)/width|).
    Spike {
        /// Centre.
        center: f64,
        /// Width.
        width: f64,
    },
    /// (end − inflection) / (2·end − inflection − x) below `end` (increasing when
    /// inflection ≤ end), mirrored when decreasing, 1 beyond.
    Concave {
        /// Where the degree is 0.5.
        inflection: f64,
        /// Where the degree reaches 1.
        end: f64,
    },
    /// A smooth S from 0 at `start` to 1 at `end` (two parabolas).
    SShape {
        /// Where the degree leaves 0.
        start: f64,
        /// Where it reaches 1.
        end: f64,
    },
    /// A smooth Z from 1 at `start` to 0 at `end`.
    ZShape {
        /// Where the degree leaves 1.
        start: f64,
        /// Where it reaches 0.
        end: f64,
    },
    /// SShape(bottom_left, top_left) · ZShape(top_right, bottom_right).
    PiShape {
        /// Where the degree leaves 0.
        bottom_left: f64,
        /// Where it reaches 1.
        top_left: f64,
        /// Where it leaves 1.
        top_right: f64,
        /// Where it reaches 0.
        bottom_right: f64,
    },
    /// A Takagi–Sugeno constant.
    Constant {
        /// The value.
        value: f64,
    },
    /// A Takagi–Sugeno linear function of the inputs: Σ cᵢ·xᵢ, plus a constant when there is one
    /// coefficient more than inputs.
    Linear {
        /// The coefficients, in the order of the engine's inputs.
        coefficients: Vec<f64>,
    },
    /// A Takagi–Sugeno formula of the inputs, the outputs and x.
    Function(Formula),
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
        let params = self.parameters();
        if !finite(&params) {
            return Err(FuzzyError::new(format!(
                "{}: every parameter must be a finite number, got {}",
                self.fll_name(),
                shown(&params)
            )));
        }
        let nonzero = |what: &str, v: f64| {
            if v == 0.0 {
                Err(FuzzyError::new(format!(
                    "{}: the {what} must not be 0",
                    self.fll_name()
                )))
            } else {
                Ok(())
            }
        };
        let distinct = |start: f64, end: f64| {
            if start == end {
                Err(FuzzyError::new(format!(
                    "{} needs two different ends, got {}",
                    self.fll_name(),
                    shown(&[start, end])
                )))
            } else {
                span_fits(start.min(end), start.max(end))
            }
        };
        match &self {
            Shape::Triangle { a, b, c } => Shape::triangle(*a, *b, *c),
            Shape::Trapezoid { a, b, c, d } => Shape::trapezoid(*a, *b, *c, *d),
            Shape::Ramp { start, end } => Shape::ramp(*start, *end),
            Shape::Rectangle { start, end } => {
                if start > end {
                    return Err(FuzzyError::new(format!(
                        "a rectangle needs start ≤ end, got {}",
                        shown(&[*start, *end])
                    )));
                }
                span_fits(*start, *end).map(|()| self)
            }
            Shape::Discrete { points } => {
                if points.is_empty() {
                    return Err(FuzzyError::new(
                        "a discrete term needs at least one x y pair",
                    ));
                }
                if points.windows(2).any(|w| w[1].0 < w[0].0) {
                    return Err(FuzzyError::new(
                        "a discrete term's x values must not decrease",
                    ));
                }
                Ok(self)
            }
            Shape::Bell { width, .. } => nonzero("width", *width).map(|()| self),
            Shape::Gaussian { sd, .. } => nonzero("standard deviation", *sd).map(|()| self),
            Shape::GaussianProduct { sd_a, sd_b, .. } => {
                nonzero("standard deviation", *sd_a)?;
                nonzero("standard deviation", *sd_b).map(|()| self)
            }
            Shape::Cosine { width, .. } | Shape::Spike { width, .. } => {
                nonzero("width", *width).map(|()| self)
            }
            Shape::Concave { inflection, end } => distinct(*inflection, *end).map(|()| self),
            Shape::SShape { start, end } | Shape::ZShape { start, end } => {
                distinct(*start, *end).map(|()| self)
            }
            Shape::PiShape {
                bottom_left,
                top_left,
                top_right,
                bottom_right,
            } => {
                distinct(*bottom_left, *top_left)?;
                distinct(*top_right, *bottom_right).map(|()| self)
            }
            Shape::Sigmoid { .. }
            | Shape::SigmoidDifference { .. }
            | Shape::SigmoidProduct { .. }
            | Shape::Constant { .. }
            | Shape::Linear { .. }
            | Shape::Function(_) => Ok(self),
        }
    }

    /// The degree of membership of `x`, in [0, 1] (a Takagi–Sugeno term's value without the
    /// engine's inputs: a Linear or Function term is NaN here, see [`Shape::degree_in`]).
    pub fn degree(&self, x: f64) -> f64 {
        self.degree_in(x, Values::default())
    }

    /// The degree of membership of `x` (the value, for a Takagi–Sugeno term) with the engine's
    /// current `values`. A NaN `x` has degree 0: it activates nothing.
    pub fn degree_in(&self, x: f64, values: Values<'_>) -> f64 {
        if x.is_nan() {
            return 0.0;
        }
        // fuzzylite's comparisons, which count values within 1e-6 as equal: a Concave's degree
        // at 1 − 9e-7 is its full 1 there, and the engines' outputs depend on it.
        let eq = |a: f64, b: f64| a == b || (a - b).abs() < FUZZYLITE_EPSILON;
        let lt = |a: f64, b: f64| !eq(a, b) && a < b;
        let le = |a: f64, b: f64| eq(a, b) || a < b;
        let sigmoid = |slope: f64, inflection: f64| 1.0 / (1.0 + (-slope * (x - inflection)).exp());
        let s_shape = |start: f64, end: f64| {
            if le(x, start) {
                0.0
            } else if le(x, 0.5 * (start + end)) {
                2.0 * ((x - start) / (end - start)).powi(2)
            } else if lt(x, end) {
                1.0 - 2.0 * ((x - end) / (end - start)).powi(2)
            } else {
                1.0
            }
        };
        let z_shape = |start: f64, end: f64| {
            if le(x, start) {
                1.0
            } else if le(x, 0.5 * (start + end)) {
                1.0 - 2.0 * ((x - start) / (end - start)).powi(2)
            } else if lt(x, end) {
                2.0 * ((x - end) / (end - start)).powi(2)
            } else {
                0.0
            }
        };
        match self {
            Shape::Triangle { .. } | Shape::Trapezoid { .. } | Shape::Ramp { .. } => {
                self.piecewise_linear_degree(x)
            }
            Shape::Rectangle { start, end } => f64::from(u8::from(le(*start, x) && le(x, *end))),
            Shape::Discrete { points } => discrete_degree(points, x, eq),
            Shape::Bell {
                center,
                width,
                slope,
            } => 1.0 / (1.0 + ((x - center) / width).abs().powf(2.0 * slope)),
            Shape::Gaussian { mean, sd } => (-(x - mean) * (x - mean) / (2.0 * sd * sd)).exp(),
            Shape::GaussianProduct {
                mean_a,
                sd_a,
                mean_b,
                sd_b,
            } => {
                let a = if lt(x, *mean_a) {
                    (-(x - mean_a) * (x - mean_a) / (2.0 * sd_a * sd_a)).exp()
                } else {
                    1.0
                };
                let b = if lt(*mean_b, x) {
                    (-(x - mean_b) * (x - mean_b) / (2.0 * sd_b * sd_b)).exp()
                } else {
                    1.0
                };
                a * b
            }
            Shape::Cosine { center, width } => {
                if lt(x, center - 0.5 * width) || lt(center + 0.5 * width, x) {
                    0.0
                } else {
                    0.5 * (1.0 + (2.0 / width * std::f64::consts::PI * (x - center)).cos())
                }
            }
            Shape::Sigmoid { inflection, slope } => sigmoid(*slope, *inflection),
            Shape::SigmoidDifference {
                left,
                rising,
                falling,
                right,
            } => (sigmoid(*rising, *left) - sigmoid(*falling, *right)).abs(),
            Shape::SigmoidProduct {
                left,
                rising,
                falling,
                right,
            } => sigmoid(*rising, *left) * sigmoid(*falling, *right),
            Shape::Spike { center, width } => (-(10.0 / width * (x - center)).abs()).exp(),
            Shape::Concave { inflection, end } => {
                if le(*inflection, *end) {
                    if lt(x, *end) {
                        (end - inflection) / (2.0 * end - inflection - x)
                    } else {
                        1.0
                    }
                } else if lt(*end, x) {
                    (inflection - end) / (inflection - 2.0 * end + x)
                } else {
                    1.0
                }
            }
            Shape::SShape { start, end } => s_shape(*start, *end),
            Shape::ZShape { start, end } => z_shape(*start, *end),
            Shape::PiShape {
                bottom_left,
                top_left,
                top_right,
                bottom_right,
            } => s_shape(*bottom_left, *top_left) * z_shape(*top_right, *bottom_right),
            Shape::Constant { value } => *value,
            Shape::Linear { coefficients } => {
                if values.inputs.is_empty() && !coefficients.is_empty() {
                    return f64::NAN;
                }
                let mut sum = 0.0;
                for (c, v) in coefficients.iter().zip(values.inputs) {
                    sum += c * v;
                }
                if coefficients.len() > values.inputs.len() {
                    sum += coefficients.last().copied().unwrap_or(0.0);
                }
                sum
            }
            Shape::Function(formula) => formula.evaluate(x, values),
        }
    }

    /// Whether the aggregate of this shape can be integrated in closed form (straight pieces
    /// with a bounded number of vertices): triangle, trapezoid, ramp.
    pub fn is_piecewise_linear(&self) -> bool {
        matches!(
            self,
            Shape::Triangle { .. } | Shape::Trapezoid { .. } | Shape::Ramp { .. }
        )
    }

    /// Whether this is a Takagi–Sugeno term (Constant, Linear, Function): its value, not a
    /// degree, is the output.
    pub fn is_takagi_sugeno(&self) -> bool {
        matches!(
            self,
            Shape::Constant { .. } | Shape::Linear { .. } | Shape::Function(_)
        )
    }

    /// Whether fuzzylite treats the shape as monotonic (Tsukamoto): Ramp, Sigmoid, SShape,
    /// ZShape, Concave.
    pub fn is_monotonic(&self) -> bool {
        matches!(
            self,
            Shape::Ramp { .. }
                | Shape::Sigmoid { .. }
                | Shape::SShape { .. }
                | Shape::ZShape { .. }
                | Shape::Concave { .. }
        )
    }

    /// The x at which a monotonic term has degree `w` (Tsukamoto's inverse), as fuzzylite 6
    /// computes it, within the output universe [`min`, `max`] where the term never reaches
    /// 0 or 1 (Sigmoid). For any other shape, its centre ([`Shape::centre`], paper 002 eq 7).
    pub fn tsukamoto(&self, w: f64, min: f64, max: f64, values: Values<'_>) -> f64 {
        const EPS: f64 = 1e-6;
        match *self {
            Shape::Ramp { start, end } => start + w * (end - start),
            Shape::Sigmoid { inflection, slope } => {
                if (w - 1.0).abs() < EPS {
                    if slope >= 0.0 {
                        max
                    } else {
                        min
                    }
                } else if w.abs() < EPS {
                    if slope >= 0.0 {
                        min
                    } else {
                        max
                    }
                } else {
                    inflection + (1.0 / w - 1.0).ln() / -slope
                }
            }
            Shape::SShape { start, end } => {
                // fuzzylite 6's two candidates, the closer one kept (its second candidate lies
                // beyond `end`; kept as fuzzylite has it so that the results agree).
                let d = end - start;
                let a = start + (0.5 * w * d * d).sqrt();
                let b = end + (-0.5 * (w - 1.0) * d * d).sqrt();
                closer(w, a, b, |x| self.degree(x))
            }
            Shape::ZShape { start, end } => {
                let d = end - start;
                let a = start + (-0.5 * (w - 1.0) * d * d).sqrt();
                let b = end + (0.5 * w * d * d).sqrt();
                closer(w, a, b, |x| self.degree(x))
            }
            Shape::Concave { inflection, end } => {
                (inflection - end) / self.degree(w) + 2.0 * end - inflection
            }
            _ if self.is_takagi_sugeno() => self.degree_in(w, values),
            _ => self.centre(),
        }
    }

    /// fuzzylite's name of the shape.
    pub fn fll_name(&self) -> &'static str {
        match self {
            Shape::Triangle { .. } => "Triangle",
            Shape::Trapezoid { .. } => "Trapezoid",
            Shape::Ramp { .. } => "Ramp",
            Shape::Rectangle { .. } => "Rectangle",
            Shape::Discrete { .. } => "Discrete",
            Shape::Bell { .. } => "Bell",
            Shape::Gaussian { .. } => "Gaussian",
            Shape::GaussianProduct { .. } => "GaussianProduct",
            Shape::Cosine { .. } => "Cosine",
            Shape::Sigmoid { .. } => "Sigmoid",
            Shape::SigmoidDifference { .. } => "SigmoidDifference",
            Shape::SigmoidProduct { .. } => "SigmoidProduct",
            Shape::Spike { .. } => "Spike",
            Shape::Concave { .. } => "Concave",
            Shape::SShape { .. } => "SShape",
            Shape::ZShape { .. } => "ZShape",
            Shape::PiShape { .. } => "PiShape",
            Shape::Constant { .. } => "Constant",
            Shape::Linear { .. } => "Linear",
            Shape::Function(_) => "Function",
        }
    }

    /// The numeric parameters in fuzzylite's order (a Function has none: its formula is text).
    pub fn parameters(&self) -> Vec<f64> {
        match self {
            Shape::Triangle { a, b, c } => vec![*a, *b, *c],
            Shape::Trapezoid { a, b, c, d } => vec![*a, *b, *c, *d],
            Shape::Ramp { start, end }
            | Shape::Rectangle { start, end }
            | Shape::SShape { start, end }
            | Shape::ZShape { start, end } => vec![*start, *end],
            Shape::Discrete { points } => points.iter().flat_map(|(x, y)| [*x, *y]).collect(),
            Shape::Bell {
                center,
                width,
                slope,
            } => vec![*center, *width, *slope],
            Shape::Gaussian { mean, sd } => vec![*mean, *sd],
            Shape::GaussianProduct {
                mean_a,
                sd_a,
                mean_b,
                sd_b,
            } => vec![*mean_a, *sd_a, *mean_b, *sd_b],
            Shape::Cosine { center, width } | Shape::Spike { center, width } => {
                vec![*center, *width]
            }
            Shape::Sigmoid { inflection, slope } => vec![*inflection, *slope],
            Shape::SigmoidDifference {
                left,
                rising,
                falling,
                right,
            }
            | Shape::SigmoidProduct {
                left,
                rising,
                falling,
                right,
            } => vec![*left, *rising, *falling, *right],
            Shape::Concave { inflection, end } => vec![*inflection, *end],
            Shape::PiShape {
                bottom_left,
                top_left,
                top_right,
                bottom_right,
            } => vec![*bottom_left, *top_left, *top_right, *bottom_right],
            Shape::Constant { value } => vec![*value],
            Shape::Linear { coefficients } => coefficients.clone(),
            Shape::Function(_) => Vec::new(),
        }
    }

    /// The shape fuzzylite names `kind` with `params` in fuzzylite's order (a Function is built
    /// by [`super::function::Formula::parse`], not here), checked. A trailing height is accepted
    /// only when it is 1.
    pub fn from_fll(kind: &str, params: &[f64]) -> Result<Shape, FuzzyError> {
        let needed = match kind {
            "Triangle" | "Bell" => 3,
            "Trapezoid" | "GaussianProduct" | "SigmoidDifference" | "SigmoidProduct"
            | "PiShape" => 4,
            "Ramp" | "Rectangle" | "Gaussian" | "Cosine" | "Sigmoid" | "Spike" | "Concave"
            | "SShape" | "ZShape" => 2,
            "Constant" => 1,
            "Discrete" => {
                let height_given = params.len() % 2 == 1;
                if height_given && params.last() != Some(&1.0) {
                    return Err(FuzzyError::new(format!(
                        "Discrete: only the full height 1 is supported, got {}",
                        shown(&params[params.len() - 1..])
                    )));
                }
                let pairs = &params[..params.len() - usize::from(height_given)];
                let points = pairs.chunks_exact(2).map(|p| (p[0], p[1])).collect();
                return Shape::Discrete { points }.checked();
            }
            "Linear" => {
                return Shape::Linear {
                    coefficients: params.to_vec(),
                }
                .checked()
            }
            other => {
                return Err(FuzzyError::new(format!(
                    "shape {other} is not one of fuzzylite's terms (Triangle, Trapezoid, Ramp, \
                     Rectangle, Discrete, Bell, Gaussian, GaussianProduct, Cosine, Sigmoid, \
                     SigmoidDifference, SigmoidProduct, Spike, Concave, SShape, ZShape, PiShape, \
                     Constant, Linear, Function)"
                )))
            }
        };
        let v = match params.len() {
            l if l == needed => params,
            l if l == needed + 1 && kind != "Constant" => {
                if params[needed] != 1.0 {
                    return Err(FuzzyError::new(format!(
                        "{kind}: only the full height 1 is supported, got {}",
                        shown(&params[needed..])
                    )));
                }
                &params[..needed]
            }
            l => {
                return Err(FuzzyError::new(format!(
                    "{kind} needs {needed} numbers, got {l}"
                )))
            }
        };
        match kind {
            "Triangle" => Shape::triangle(v[0], v[1], v[2]),
            "Trapezoid" => Shape::trapezoid(v[0], v[1], v[2], v[3]),
            "Ramp" => Shape::ramp(v[0], v[1]),
            "Rectangle" => Shape::Rectangle {
                start: v[0],
                end: v[1],
            }
            .checked(),
            "Bell" => Shape::Bell {
                center: v[0],
                width: v[1],
                slope: v[2],
            }
            .checked(),
            "Gaussian" => Shape::Gaussian {
                mean: v[0],
                sd: v[1],
            }
            .checked(),
            "GaussianProduct" => Shape::GaussianProduct {
                mean_a: v[0],
                sd_a: v[1],
                mean_b: v[2],
                sd_b: v[3],
            }
            .checked(),
            "Cosine" => Shape::Cosine {
                center: v[0],
                width: v[1],
            }
            .checked(),
            "Sigmoid" => Shape::Sigmoid {
                inflection: v[0],
                slope: v[1],
            }
            .checked(),
            "SigmoidDifference" => Shape::SigmoidDifference {
                left: v[0],
                rising: v[1],
                falling: v[2],
                right: v[3],
            }
            .checked(),
            "SigmoidProduct" => Shape::SigmoidProduct {
                left: v[0],
                rising: v[1],
                falling: v[2],
                right: v[3],
            }
            .checked(),
            "Spike" => Shape::Spike {
                center: v[0],
                width: v[1],
            }
            .checked(),
            "Concave" => Shape::Concave {
                inflection: v[0],
                end: v[1],
            }
            .checked(),
            "SShape" => Shape::SShape {
                start: v[0],
                end: v[1],
            }
            .checked(),
            "ZShape" => Shape::ZShape {
                start: v[0],
                end: v[1],
            }
            .checked(),
            "PiShape" => Shape::PiShape {
                bottom_left: v[0],
                top_left: v[1],
                top_right: v[2],
                bottom_right: v[3],
            }
            .checked(),
            _ => Shape::Constant { value: v[0] }.checked(),
        }
    }

    /// A triangle, trapezoid or ramp's degree, exact.
    fn piecewise_linear_degree(&self, x: f64) -> f64 {
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
            _ => 0.0,
        }
    }

    /// The x values where the slope of a piecewise-linear shape can change (none for the
    /// others, which the engine integrates numerically).
    pub fn vertices(&self) -> ([f64; 4], usize) {
        match *self {
            Shape::Triangle { a, b, c } => ([a, b, c, 0.0], 3),
            Shape::Trapezoid { a, b, c, d } => ([a, b, c, d], 4),
            Shape::Ramp { start, end } => ([start, end, 0.0, 0.0], 2),
            _ => ([0.0; 4], 0),
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
            Shape::Rectangle { start, end } => start + (end - start) / 2.0,
            Shape::Discrete { ref points } => {
                // The middle of the points at the highest degree.
                let top = points.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
                let mut at_top = points.iter().filter(|p| p.1 == top).map(|p| p.0);
                let first = at_top.next().unwrap_or(0.0);
                let last = at_top.next_back().unwrap_or(first);
                first + (last - first) / 2.0
            }
            Shape::Bell { center, .. }
            | Shape::Cosine { center, .. }
            | Shape::Spike { center, .. } => center,
            Shape::Gaussian { mean, .. } => mean,
            Shape::GaussianProduct { mean_a, mean_b, .. } => mean_a + (mean_b - mean_a) / 2.0,
            Shape::Sigmoid { inflection, .. } | Shape::Concave { inflection, .. } => inflection,
            Shape::SigmoidDifference { left, right, .. }
            | Shape::SigmoidProduct { left, right, .. } => left + (right - left) / 2.0,
            Shape::SShape { end, .. } => end,
            Shape::ZShape { start, .. } => start,
            Shape::PiShape {
                top_left,
                top_right,
                ..
            } => top_left + (top_right - top_left) / 2.0,
            Shape::Constant { value } => value,
            Shape::Linear { .. } | Shape::Function(_) => f64::NAN,
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
            _ => (f64::NEG_INFINITY, f64::INFINITY),
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
            _ => (self.degree(x0), self.degree(x1)),
        }
    }
}

/// The closer of fuzzylite's two Tsukamoto candidates `a` and `b`: the one whose degree is
/// nearer `w`.
fn closer(w: f64, a: f64, b: f64, degree: impl Fn(f64) -> f64) -> f64 {
    if (w - degree(a)).abs() < (w - degree(b)).abs() {
        a
    } else {
        b
    }
}

/// Straight lines between sorted points, constant beyond the ends.
/// `eq` is fuzzylite's tolerant equality.
fn discrete_degree(points: &[(f64, f64)], x: f64, eq: impl Fn(f64, f64) -> bool) -> f64 {
    let (Some(first), Some(last)) = (points.first(), points.last()) else {
        return 0.0;
    };
    if x <= first.0 || eq(x, first.0) {
        return first.1;
    }
    if x >= last.0 || eq(x, last.0) {
        return last.1;
    }
    // The first point at or right of x; x lies strictly inside, so there is one before it.
    let right = points.partition_point(|p| p.0 < x);
    let (Some(r), Some(l)) = (points.get(right), points.get(right.wrapping_sub(1))) else {
        return 0.0;
    };
    if eq(r.0, x) {
        return r.1;
    }
    l.1 + (x - l.0) / (r.0 - l.0) * (r.1 - l.1)
}

/// The shape as an FLL term writes it: `Triangle -6 -6 -4`, `Trapezoid 0 1 2 4`, `Ramp 2 0`,
/// `Function sin(x)/x`.
impl fmt::Display for Shape {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.fll_name())?;
        if let Shape::Function(formula) = self {
            return write!(f, " {}", formula.text());
        }
        for p in self.parameters() {
            write!(f, " {p}")?;
        }
        Ok(())
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
