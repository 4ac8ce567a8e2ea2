//! Defuzzification: the defuzzifiers and weighted kinds fuzzylite names, and how an output's fuzzy
//! output becomes a number: a weighted average or sum of the activated terms, fuzzylite's sampling
//! of the aggregate, or the exact centroid and mean of maximum of a piecewise-linear aggregate.

use super::operators::{same, Norm, SNorm};
use super::{Activated, Engine};
use crate::control::fuzzy::membership::Values;

/// How an output is turned into a number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Defuzzifier {
    /// Centroid of the aggregate (exact when it is piecewise linear).
    Centroid,
    /// Weighted average of the activated terms (paper 002 eq 7 for Mamdani terms).
    WeightedAverage,
    /// Midpoint of the first plateau at the maximum.
    MeanOfMaximum,
    /// The x that splits the aggregate's area in two halves (sampled).
    Bisector,
    /// The smallest x at the maximum (sampled).
    SmallestOfMaximum,
    /// The largest x at the maximum (sampled).
    LargestOfMaximum,
    /// Weighted sum of the activated terms.
    WeightedSum,
}

impl Defuzzifier {
    /// Every defuzzifier.
    pub const ALL: [Defuzzifier; 7] = [
        Defuzzifier::Centroid,
        Defuzzifier::WeightedAverage,
        Defuzzifier::MeanOfMaximum,
        Defuzzifier::Bisector,
        Defuzzifier::SmallestOfMaximum,
        Defuzzifier::LargestOfMaximum,
        Defuzzifier::WeightedSum,
    ];

    /// The defuzzifier of fuzzylite's `name` (`"Centroid"`, `"WeightedAverage"`, …).
    pub fn from_name(name: &str) -> Option<Defuzzifier> {
        Self::ALL.into_iter().find(|d| d.name() == name)
    }

    /// fuzzylite's name.
    pub fn name(self) -> &'static str {
        match self {
            Defuzzifier::Centroid => "Centroid",
            Defuzzifier::WeightedAverage => "WeightedAverage",
            Defuzzifier::MeanOfMaximum => "MeanOfMaximum",
            Defuzzifier::Bisector => "Bisector",
            Defuzzifier::SmallestOfMaximum => "SmallestOfMaximum",
            Defuzzifier::LargestOfMaximum => "LargestOfMaximum",
            Defuzzifier::WeightedSum => "WeightedSum",
        }
    }

    /// A human label.
    pub fn label(self) -> &'static str {
        match self {
            Defuzzifier::Centroid => "Centroid (exact)",
            Defuzzifier::WeightedAverage => "Weighted average (paper 002 eq 7)",
            Defuzzifier::MeanOfMaximum => "Mean of maximum",
            Defuzzifier::Bisector => "Bisector",
            Defuzzifier::SmallestOfMaximum => "Smallest of maximum",
            Defuzzifier::LargestOfMaximum => "Largest of maximum",
            Defuzzifier::WeightedSum => "Weighted sum",
        }
    }

    /// Whether it integrates the aggregate over the universe (fuzzylite's integral
    /// defuzzifiers, which need an implication and an aggregation) rather than weighting the
    /// activated terms.
    pub fn is_integral(self) -> bool {
        !matches!(
            self,
            Defuzzifier::WeightedAverage | Defuzzifier::WeightedSum
        )
    }
}

/// What a weighted defuzzifier takes as each activated term's value (fuzzylite's type).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum WeightedKind {
    /// Takagi–Sugeno if the first activated term is Constant, Linear or Function, else Tsukamoto.
    Automatic,
    /// The term's value at the activation.
    TakagiSugeno,
    /// The inverse of a monotonic term at the activation.
    Tsukamoto,
}

impl WeightedKind {
    /// Every kind.
    pub const ALL: [WeightedKind; 3] = [
        WeightedKind::Automatic,
        WeightedKind::TakagiSugeno,
        WeightedKind::Tsukamoto,
    ];

    /// fuzzylite's name.
    pub fn name(self) -> &'static str {
        match self {
            WeightedKind::Automatic => "Automatic",
            WeightedKind::TakagiSugeno => "TakagiSugeno",
            WeightedKind::Tsukamoto => "Tsukamoto",
        }
    }
}

impl Engine {
    /// The defuzzified output `o` from its (non-empty) fuzzy output.
    pub(super) fn defuzzify(&mut self, o: usize) -> f64 {
        let var = &self.outputs[o];
        let fired = &self.fired[o];
        let values = Values {
            inputs: &self.input_values,
            outputs: &self.output_values,
        };
        if !var.defuzzifier.is_integral() {
            // Automatic: Takagi–Sugeno when the first activated term is such a term (as
            // fuzzylite infers it), Tsukamoto when every term of the output is monotonic (a
            // Tsukamoto engine), else a Mamdani output whose terms weigh in at their centres
            // (paper 002 eq 7) — where fuzzylite would invert the monotonic terms among them.
            let (takagi_sugeno, centres) = match var.weighted_kind {
                WeightedKind::Automatic => match fired.first() {
                    Some(a) if var.terms[a.term].shape.is_takagi_sugeno() => (true, false),
                    _ => (false, !var.terms.iter().all(|t| t.shape.is_monotonic())),
                },
                WeightedKind::TakagiSugeno => (true, false),
                WeightedKind::Tsukamoto => (false, false),
            };
            let z = |a: &Activated| {
                let shape = &var.terms[a.term].shape;
                if takagi_sugeno {
                    shape.degree_in(a.degree, values)
                } else if centres {
                    shape.centre()
                } else {
                    shape.tsukamoto(a.degree, var.min, var.max, values)
                }
            };
            if var.defuzzifier == Defuzzifier::WeightedSum {
                return fired.iter().map(|a| a.degree * z(a)).sum();
            }
            // Σ (wᵢ/Σw)·zᵢ, a convex combination: it stays finite where Σ wᵢ·zᵢ overflows
            // (values near 1e308).
            let weight_total: f64 = fired.iter().map(|a| a.degree).sum();
            let mut average = 0.0;
            for a in fired {
                average += a.degree / weight_total * z(a);
            }
            return average;
        }
        match self.exact[o] {
            Some(implication) => {
                let degrees = &mut self.term_degrees[..var.terms.len()];
                degrees.fill(0.0);
                for a in fired {
                    degrees[a.term] = degrees[a.term].max(a.degree);
                }
                self.integrate(o, implication)
            }
            _ => self.sampled(o),
        }
    }

    /// The aggregate of output `o` at `x`: fuzzylite's fold of the aggregation over the activated
    /// terms, from 0.
    fn aggregate_at(&self, o: usize, x: f64) -> f64 {
        let var = &self.outputs[o];
        let values = Values {
            inputs: &self.input_values,
            outputs: &self.output_values,
        };
        let aggregation = var.aggregation.unwrap_or(SNorm::Maximum);
        self.fired[o].iter().fold(0.0, |mu, a| {
            let degree = var.terms[a.term].shape.degree_in(x, values);
            let implied = a
                .implication
                .map_or(degree, |imp| imp.apply(degree, a.degree));
            aggregation.apply(mu, implied)
        })
    }

    /// An integral defuzzifier of output `o` by sampling the aggregate at the midpoints of
    /// `resolution` cells, as fuzzylite 6 does (with its tolerance when comparing degrees).
    fn sampled(&self, o: usize) -> f64 {
        let var = &self.outputs[o];
        let (min, max) = (var.min, var.max);
        let n = var.resolution;
        let dx = (max - min) / n as f64;
        let at = |i: usize| min + (i as f64 + 0.5) * dx;
        let greater = |a: f64, b: f64| !same(a, b) && a > b;
        match var.defuzzifier {
            Defuzzifier::Bisector => {
                let (mut left, mut right) = (0usize, 0usize);
                let (mut left_area, mut right_area) = (0.0, 0.0);
                let (mut x_left, mut x_right) = (min, max);
                for _ in 0..n {
                    if !greater(left_area, right_area) {
                        x_left = at(left);
                        left_area += self.aggregate_at(o, x_left);
                        left += 1;
                    } else {
                        x_right = max - (right as f64 + 0.5) * dx;
                        right_area += self.aggregate_at(o, x_right);
                        right += 1;
                    }
                }
                (left_area * x_right + right_area * x_left) / (left_area + right_area)
            }
            Defuzzifier::SmallestOfMaximum => {
                let (mut best, mut x_best) = (-1.0, min);
                for i in 0..n {
                    let y = self.aggregate_at(o, at(i));
                    if greater(y, best) {
                        best = y;
                        x_best = at(i);
                    }
                }
                x_best
            }
            Defuzzifier::LargestOfMaximum => {
                let (mut best, mut x_best) = (-1.0, max);
                for i in 0..n {
                    let y = self.aggregate_at(o, at(i));
                    if same(y, best) || y > best {
                        best = y;
                        x_best = at(i);
                    }
                }
                x_best
            }
            Defuzzifier::MeanOfMaximum => {
                let (mut best, mut smallest, mut largest) = (-1.0, min, max);
                let mut on_plateau = false;
                for i in 0..n {
                    let (x, y) = (at(i), self.aggregate_at(o, at(i)));
                    if greater(y, best) {
                        best = y;
                        smallest = x;
                        largest = x;
                        on_plateau = true;
                    } else if on_plateau && same(y, best) {
                        largest = x;
                    } else if !same(y, best) && y < best {
                        on_plateau = false;
                    }
                }
                0.5 * (largest + smallest)
            }
            _ => {
                let (mut area, mut moment) = (0.0, 0.0);
                for i in 0..n {
                    let (x, y) = (at(i), self.aggregate_at(o, at(i)));
                    moment += y * x;
                    area += y;
                }
                moment / area
            }
        }
    }

    /// Exact centroid or mean of maximum of output `o`'s aggregate (term degrees already set).
    ///
    /// Only the support of the aggregate counts (the universe cut to where an active term is
    /// above 0), and the centroid is integrated in coordinates relative to it, u = (x − left) /
    /// width ∈ [0, 1]: moments of x itself overflowed for terms near 1e155, and breakpoints merged
    /// within 1e-12·(1 + |x|) erased a term narrower than that, so both came out as the default.
    fn integrate(&mut self, o: usize, implication: Norm) -> f64 {
        let var = &self.outputs[o];
        let degrees = &self.term_degrees[..var.terms.len()];
        let active = || {
            var.terms
                .iter()
                .zip(degrees)
                .filter(|(_, d)| **d > 0.0)
                .map(|(t, &d)| (&t.shape, d))
        };
        let (left, right) = active().fold((var.max, var.min), |(l, r), (shape, _)| {
            let (from, to) = shape.support();
            (l.min(from), r.max(to))
        });
        let (lo, hi) = (left.max(var.min), right.min(var.max));
        // lo and hi lie in the universe, so the width is a number: the engine refuses universes
        // whose width overflows. None left means the active terms lie outside the universe.
        let width = hi - lo;
        if width <= 0.0 {
            return f64::NAN;
        }
        let bp = &mut self.breakpoints;
        bp.clear();
        bp.push(lo);
        bp.push(hi);
        for (shape, _) in active() {
            let (v, n) = shape.vertices();
            bp.extend(v[..n].iter().copied().filter(|x| *x > lo && *x < hi));
        }
        sort_dedup(bp);
        // Refine: within each interval every term is one straight piece; add the points where a
        // clipped piece meets its clip level and where two implied pieces cross.
        let coarse = bp.len();
        for i in 0..coarse - 1 {
            let (x0, x1) = (bp[i], bp[i + 1]);
            // Where a straight piece from g0 at x0 to g1 at x1 passes through 0, if it does.
            let zero_between = |g0: f64, g1: f64| {
                (g0 * g1 < 0.0).then(|| (x0 + g0 / (g0 - g1) * (x1 - x0)).clamp(x0, x1))
            };
            self.pieces.clear();
            for (shape, d) in active() {
                let (f0, f1) = shape.piece(x0, x1);
                match implication {
                    Norm::Minimum => {
                        bp.extend(zero_between(f0 - d, f1 - d));
                        self.pieces.push((f0, f1));
                    }
                    // Only minimum and product reach the exact path.
                    _ => self.pieces.push((d * f0, d * f1)),
                }
            }
            // The envelope of the implied functions can also turn where two of them cross:
            // piece against piece and, for Minimum, piece against the other's clip level.
            let clip_levels = degrees.iter().copied().filter(|d| *d > 0.0);
            for (k, da) in clip_levels.clone().enumerate() {
                for (m, db) in clip_levels.clone().enumerate().skip(k + 1) {
                    let (a, b) = (self.pieces[k], self.pieces[m]);
                    let pairs = match implication {
                        Norm::Minimum => [(a, b), (a, (db, db)), ((da, da), b)],
                        _ => [(a, b), ((0.0, 0.0), (0.0, 0.0)), ((0.0, 0.0), (0.0, 0.0))],
                    };
                    for ((p0, p1), (q0, q1)) in pairs {
                        bp.extend(zero_between(p0 - q0, p1 - q1));
                    }
                }
            }
        }
        sort_dedup(bp);
        // The aggregate at both ends of the straight piece between breakpoints x0 < x1.
        let aggregate = |x0: f64, x1: f64| -> (f64, f64) {
            // A clip corner is a breakpoint rounded to the nearest f64, which can leave the
            // piece short of its clip level by its slope times that rounding: far more than
            // mean of maximum's 1e-12 for terms narrow against their position (1e-12 wide at
            // 1.0), enough to cut a plateau in two. Values that close to the level are the level.
            let resolution = 2.0 * f64::EPSILON * x0.abs().max(x1.abs()).max(f64::MIN_POSITIVE);
            active().fold((0.0, 0.0), |(m0, m1), (shape, d)| {
                let (f0, f1) = shape.piece(x0, x1);
                let slack = (f1 - f0).abs() / (x1 - x0) * resolution;
                let implied = |f: f64| match implication {
                    Norm::Minimum if f < d && d - f <= slack => d,
                    _ => implication.apply(d, f),
                };
                (m0.max(implied(f0)), m1.max(implied(f1)))
            })
        };
        match var.defuzzifier {
            Defuzzifier::MeanOfMaximum => {
                // Left to right, as fuzzylite scans: a higher value starts a new plateau, an
                // equal one extends the current plateau, and once the aggregate dips below the
                // maximum a later equal plateau no longer counts — the first one wins.
                let mut best = 0.0;
                let (mut smallest, mut largest) = (f64::NAN, f64::NAN);
                let mut on_plateau = false;
                for w in bp.windows(2) {
                    let (x0, x1) = (w[0], w[1]);
                    let (m0, m1) = aggregate(x0, x1);
                    for (x, mu) in [(x0, m0), (x1, m1)] {
                        if mu > best + 1e-12 {
                            best = mu;
                            smallest = x;
                            largest = x;
                            on_plateau = true;
                        } else if (mu - best).abs() <= 1e-12 && mu > 0.0 {
                            if on_plateau {
                                largest = largest.max(x);
                            }
                        } else {
                            on_plateau = false;
                        }
                    }
                }
                // The midpoint without overflow: largest − smallest ≤ width.
                smallest + (largest - smallest) / 2.0
            }
            _ => {
                // ∫μ du and ∫u·μ du over each straight piece, exactly (trapezoid rule and its
                // first moment), in u = (x − lo) / width.
                let (mut area, mut moment) = (0.0, 0.0);
                for w in bp.windows(2) {
                    let (x0, x1) = (w[0], w[1]);
                    let (m0, m1) = aggregate(x0, x1);
                    let (u0, u1) = ((x0 - lo) / width, (x1 - lo) / width);
                    let du = u1 - u0;
                    area += 0.5 * (m0 + m1) * du;
                    moment += du / 6.0 * (u0 * (2.0 * m0 + m1) + u1 * (m0 + 2.0 * m1));
                }
                if area > 0.0 {
                    lo + width * (moment / area)
                } else {
                    f64::NAN
                }
            }
        }
    }
}

/// Sorts breakpoints and drops exact repeats. Near repeats stay: a piece a few ulps wide is
/// evaluated exactly ([`Shape::piece`]) and adds next to nothing, where merging points within a
/// fixed tolerance erased every vertex of a term narrower than it.
///
/// [`Shape::piece`]: crate::control::fuzzy::membership::Shape::piece
fn sort_dedup(v: &mut Vec<f64>) {
    v.sort_by(f64::total_cmp);
    v.dedup();
}

#[cfg(test)]
mod tests {
    use super::super::tests::one_output_engine;
    use super::*;

    /// The centroid by brute-force midpoint integration on a very fine grid.
    fn sampled_centroid(e: &Engine, x: f64) -> f64 {
        let mut probe = e.clone();
        let mut out = [0.0];
        probe.evaluate(&[x], &mut out);
        let var = &probe.outputs[0];
        let (mut area, mut moment) = (0.0, 0.0);
        let n = 400_000;
        for i in 0..n {
            let y = var.min + (f64::from(i) + 0.5) * (var.max - var.min) / f64::from(n);
            let implication = probe.implication().unwrap();
            let mu = probe
                .rules
                .iter()
                .zip(&probe.activations)
                .map(|(r, &a)| {
                    implication.apply(a, var.terms[r.consequents[0].term].shape.degree(y))
                })
                .fold(0.0, f64::max);
            area += mu;
            moment += mu * y;
        }
        moment / area
    }

    #[test]
    fn exact_centroid_matches_fine_sampling() {
        for implication in [Norm::Minimum, Norm::AlgebraicProduct] {
            let mut e = one_output_engine(implication, Defuzzifier::Centroid);
            for x in [0.0, 0.1, 0.3, 0.5, 0.77, 1.0] {
                let mut out = [0.0];
                e.evaluate(&[x], &mut out);
                let sampled = sampled_centroid(&e, x);
                assert!(
                    (out[0] - sampled).abs() < 1e-6,
                    "{implication:?} x={x}: {} vs {sampled}",
                    out[0]
                );
            }
        }
    }

    #[test]
    fn weighted_average_and_mean_of_maximum() {
        let mut e = one_output_engine(Norm::Minimum, Defuzzifier::WeightedAverage);
        let mut out = [0.0];
        e.evaluate(&[0.25], &mut out);
        // Activations 0.75 (small, centre 2) and 0.25 (large, centre 8).
        assert!((out[0] - (0.75 * 2.0 + 0.25 * 8.0)).abs() < 1e-12);
        let mut e = one_output_engine(Norm::Minimum, Defuzzifier::MeanOfMaximum);
        e.evaluate(&[0.25], &mut out);
        // "small" clipped at 0.75: plateau from 1.5 to 3.0.
        assert!((out[0] - 2.25).abs() < 1e-9, "{}", out[0]);
        // Both rules at 0.5: two separate plateaus at the same height. fuzzylite 6 takes the
        // first (small's, 1 to 4), not the midpoint of both (1 to 9), which would be 5.
        e.evaluate(&[0.5], &mut out);
        assert!((out[0] - 2.5).abs() < 1e-9, "{}", out[0]);
    }
}
