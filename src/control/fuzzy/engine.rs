//! A Mamdani fuzzy inference engine with exact defuzzification.
//!
//! For each rule `if X₁ is A₁ and X₂ is A₂ … then Y is B (with w)` the activation is
//! `w · AND(μ_A₁(x₁), μ_A₂(x₂), …)` with AND = minimum or algebraic product. Each output term is
//! implied (clipped by minimum, or scaled by product) by the largest activation among the rules
//! that name it, and the implied terms are aggregated by maximum. Defuzzification:
//!
//! * **Centroid**, exact: the aggregate of clipped or scaled piecewise-linear terms is itself
//!   piecewise linear, so the engine collects every breakpoint (term vertices, clip corners, and
//!   crossings of the implied pieces) and integrates ∫x·μ and ∫μ over each straight piece in closed
//!   form. No sampling: fuzzylite and scikit-fuzzy approach this value as their resolution grows.
//! * **Weighted average**, paper 002 eq 7: U = Σᵢ Δa_fi·Hᵢ / Σᵢ Hᵢ over the rules, with Hᵢ the
//!   activation of rule i and Δa_fi the centre of its output term ([`Shape::centre`]).
//! * **Mean of maximum**, as fuzzylite defines it: the midpoint of the first (leftmost) interval
//!   on which the aggregate reaches its maximum. Where the maximum is reached on two separate
//!   intervals this is not scikit-fuzzy's `mom` (the mean of every maximising x), which can fall
//!   where the aggregate is 0.
//!
//! When no rule fires (every activation 0, e.g. for NaN inputs) the output is the previous output
//! if `lock_previous` is set and there is one, else the variable's `default_value` (0 unless an
//! FLL file says otherwise; NaN is allowed, as in fuzzylite).
//!
//! **Magnitudes.** Every universe whose width `max − min` is an f64 works, at any position:
//! terms near 1e155 or 1e-300, or 1e-12 wide at 1.0. The centroid is integrated in coordinates
//! relative to the aggregate's support (so its moments cannot overflow), breakpoints are merged
//! only when equal (so a narrow term keeps its vertices), straight pieces are evaluated by their
//! own formula at their ends ([`Shape::piece`]), and the weighted average is a convex combination
//! of the centres. The results agree with the closed forms and with the references moved to those
//! magnitudes to within the rounding of the terms' own vertices (`tests/fuzzy.rs`). A universe or
//! term wider than an f64 holds (−1e308 to 1e308) is refused when the engine is built.
//!
//! The engine allocates its scratch space when built; [`Engine::evaluate`] allocates nothing.

use std::collections::HashSet;
use std::hash::Hash;

use super::membership::Shape;
use super::FuzzyError;

/// A linguistic term: a name and a shape.
#[derive(Debug, Clone, PartialEq)]
pub struct Term {
    /// The term's name, e.g. `NB`.
    pub name: String,
    /// Its membership function.
    pub shape: Shape,
}

/// An input variable.
#[derive(Debug, Clone, PartialEq)]
pub struct InputVariable {
    /// Name.
    pub name: String,
    /// Universe minimum.
    pub min: f64,
    /// Universe maximum.
    pub max: f64,
    /// Clamp inputs into the universe before fuzzification.
    pub lock_range: bool,
    /// Terms.
    pub terms: Vec<Term>,
}

/// How an output is turned into a number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Defuzzifier {
    /// Exact centroid of the aggregate.
    Centroid,
    /// Paper 002 eq 7.
    WeightedAverage,
    /// Midpoint of the smallest and largest maximiser.
    MeanOfMaximum,
}

impl Defuzzifier {
    /// Every defuzzifier.
    pub const ALL: [Defuzzifier; 3] = [
        Defuzzifier::Centroid,
        Defuzzifier::WeightedAverage,
        Defuzzifier::MeanOfMaximum,
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
        }
    }

    /// A human label.
    pub fn label(self) -> &'static str {
        match self {
            Defuzzifier::Centroid => "Centroid (exact)",
            Defuzzifier::WeightedAverage => "Weighted average (paper 002 eq 7)",
            Defuzzifier::MeanOfMaximum => "Mean of maximum",
        }
    }
}

/// An output variable.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputVariable {
    /// Name.
    pub name: String,
    /// Universe minimum.
    pub min: f64,
    /// Universe maximum.
    pub max: f64,
    /// Clamp the defuzzified value into the universe.
    pub lock_range: bool,
    /// Terms.
    pub terms: Vec<Term>,
    /// Defuzzifier.
    pub defuzzifier: Defuzzifier,
    /// Output when no rule fires.
    pub default_value: f64,
    /// Keep the previous output when no rule fires.
    pub lock_previous: bool,
}

/// Outputs with up to this many terms have every pairwise crossing reserved (inference then
/// never allocates); paper 002's engine has 7.
pub const CROSSING_RESERVE_TERMS: usize = 64;

/// AND and implication operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Norm {
    /// min(a, b).
    Minimum,
    /// a · b.
    AlgebraicProduct,
}

impl Norm {
    fn apply(self, a: f64, b: f64) -> f64 {
        match self {
            Norm::Minimum => a.min(b),
            Norm::AlgebraicProduct => a * b,
        }
    }

    /// fuzzylite's name.
    pub fn name(self) -> &'static str {
        match self {
            Norm::Minimum => "Minimum",
            Norm::AlgebraicProduct => "AlgebraicProduct",
        }
    }
}

/// `if … and … then …` with indices into the engine's variables and terms.
#[derive(Debug, Clone, PartialEq)]
pub struct Rule {
    /// (input variable, term) pairs, all joined by AND.
    pub antecedents: Vec<(usize, usize)>,
    /// (output variable, term) pairs.
    pub consequents: Vec<(usize, usize)>,
    /// Weight in [0, 1].
    pub weight: f64,
}

/// A validated engine with its scratch space.
#[derive(Debug, Clone)]
pub struct Engine {
    /// Engine name.
    pub name: String,
    inputs: Vec<InputVariable>,
    outputs: Vec<OutputVariable>,
    rules: Vec<Rule>,
    conjunction: Norm,
    implication: Norm,
    activations: Vec<f64>,
    previous: Vec<f64>,
    term_degrees: Vec<f64>,
    breakpoints: Vec<f64>,
    pieces: Vec<(f64, f64)>,
}

/// Two engines are equal when they define the same inference; scratch space and remembered
/// outputs do not count.
impl PartialEq for Engine {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
            && self.inputs == other.inputs
            && self.outputs == other.outputs
            && self.rules == other.rules
            && self.conjunction == other.conjunction
            && self.implication == other.implication
    }
}

impl Engine {
    /// Builds an engine, checking every index, range and weight.
    pub fn new(
        name: impl Into<String>,
        inputs: Vec<InputVariable>,
        outputs: Vec<OutputVariable>,
        rules: Vec<Rule>,
        conjunction: Norm,
        implication: Norm,
    ) -> Result<Self, FuzzyError> {
        // The width must be an f64 too: degrees and centroids are computed relative to it.
        let range_ok = |min: f64, max: f64| {
            min.is_finite() && max.is_finite() && min < max && (max - min).is_finite()
        };
        if outputs.is_empty() {
            return Err(FuzzyError::new(
                "the engine has no output variable: there is nothing to infer",
            ));
        }
        // A rule names variables and terms; two of the same name would make it ambiguous.
        let variable_names = inputs.iter().map(|v| v.name.as_str());
        let variable_names = variable_names.chain(outputs.iter().map(|v| v.name.as_str()));
        if let Some(name) = first_repeated(variable_names) {
            return Err(FuzzyError::new(format!(
                "two variables are named {name}: names must be unique"
            )));
        }
        let term_lists = inputs.iter().map(|v| (&v.name, &v.terms));
        for (variable, terms) in term_lists.chain(outputs.iter().map(|v| (&v.name, &v.terms))) {
            if let Some(term) = first_repeated(terms.iter().map(|t| t.name.as_str())) {
                return Err(FuzzyError::new(format!(
                    "variable {variable} has two terms named {term}: names must be unique"
                )));
            }
        }
        for v in &inputs {
            if !range_ok(v.min, v.max) {
                return Err(FuzzyError::new(format!(
                    "input {}: range {:?} {:?} must be finite with min < max and a width \
                     max − min that an f64 can hold",
                    v.name, v.min, v.max
                )));
            }
        }
        for v in &outputs {
            if !range_ok(v.min, v.max) {
                return Err(FuzzyError::new(format!(
                    "output {}: range {:?} {:?} must be finite with min < max and a width \
                     max − min that an f64 can hold",
                    v.name, v.min, v.max
                )));
            }
            if v.terms.is_empty() {
                return Err(FuzzyError::new(format!("output {} has no terms", v.name)));
            }
        }
        // The shapes' fields are public: a shape built without its constructor is checked here.
        let shapes = inputs.iter().map(|v| ("input", &v.name, &v.terms));
        let shapes = shapes.chain(outputs.iter().map(|v| ("output", &v.name, &v.terms)));
        for (kind, variable, terms) in shapes {
            for t in terms {
                t.shape.checked().map_err(|e| {
                    FuzzyError::new(format!("{kind} {variable}, term {}: {e}", t.name))
                })?;
            }
        }
        for (i, r) in rules.iter().enumerate() {
            let ok_in = r
                .antecedents
                .iter()
                .all(|&(v, t)| inputs.get(v).is_some_and(|v| t < v.terms.len()));
            let ok_out = r
                .consequents
                .iter()
                .all(|&(v, t)| outputs.get(v).is_some_and(|v| t < v.terms.len()));
            if !ok_in || !ok_out || r.antecedents.is_empty() || r.consequents.is_empty() {
                return Err(FuzzyError::new(format!(
                    "rule {}: refers to a variable or term that does not exist",
                    i + 1
                )));
            }
            if !(0.0..=1.0).contains(&r.weight) {
                return Err(FuzzyError::new(format!(
                    "rule {}: weight {} must lie in [0, 1]",
                    i + 1,
                    crate::input::readable(r.weight)
                )));
            }
        }
        let max_terms = outputs.iter().map(|o| o.terms.len()).max().unwrap_or(0);
        // Vertices, clip corners and pairwise crossings per interval, allocated once so that
        // inference allocates nothing. Crossings grow with the square of the terms, so they are
        // reserved only up to CROSSING_RESERVE_TERMS terms: a 10 000-term output once reserved
        // 25 GB here. Beyond that the buffer grows on the rare evaluation that needs more.
        let crossing_terms = max_terms.min(CROSSING_RESERVE_TERMS);
        let capacity = 8 + max_terms * 8 + crossing_terms * crossing_terms * 8;
        Ok(Self {
            name: name.into(),
            activations: vec![0.0; rules.len()],
            previous: vec![f64::NAN; outputs.len()],
            term_degrees: vec![0.0; max_terms],
            breakpoints: Vec::with_capacity(capacity * 4),
            pieces: Vec::with_capacity(max_terms),
            inputs,
            outputs,
            rules,
            conjunction,
            implication,
        })
    }

    /// The input variables.
    pub fn inputs(&self) -> &[InputVariable] {
        &self.inputs
    }

    /// The output variables.
    pub fn outputs(&self) -> &[OutputVariable] {
        &self.outputs
    }

    /// The rules.
    pub fn rules(&self) -> &[Rule] {
        &self.rules
    }

    /// AND operator.
    pub fn conjunction(&self) -> Norm {
        self.conjunction
    }

    /// Implication operator.
    pub fn implication(&self) -> Norm {
        self.implication
    }

    /// Each rule's activation after the latest evaluation.
    pub fn activations(&self) -> &[f64] {
        &self.activations
    }

    /// Sets the defuzzifier of every output.
    pub fn set_defuzzifier(&mut self, defuzzifier: Defuzzifier) {
        for o in &mut self.outputs {
            o.defuzzifier = defuzzifier;
        }
    }

    /// Forgets the previous outputs (for `lock_previous`).
    pub fn reset(&mut self) {
        self.previous.fill(f64::NAN);
        self.activations.fill(0.0);
    }

    /// Evaluates the engine: `inputs` in the order of [`Engine::inputs`], results written to
    /// `outputs` in the order of [`Engine::outputs`] (extra values are ignored, missing inputs
    /// count as NaN).
    ///
    /// ```
    /// use cutlab::control::fuzzy::rules::{paper_002_engine, RuleBase};
    /// use cutlab::control::fuzzy::engine::Defuzzifier;
    /// let mut e = paper_002_engine(&RuleBase::Dynamics.table(), Defuzzifier::WeightedAverage).unwrap();
    /// let mut out = [0.0];
    /// e.evaluate(&[0.0, 0.0], &mut out);
    /// assert_eq!(out[0], 0.0);
    /// ```
    pub fn evaluate(&mut self, inputs: &[f64], outputs: &mut [f64]) {
        for (r, rule) in self.rules.iter().enumerate() {
            let mut degree = f64::NAN;
            for &(v, t) in &rule.antecedents {
                let var = &self.inputs[v];
                let mut x = inputs.get(v).copied().unwrap_or(f64::NAN);
                if var.lock_range {
                    x = x.clamp(var.min, var.max);
                }
                let mu = var.terms[t].shape.degree(x);
                degree = if degree.is_nan() {
                    mu
                } else {
                    self.conjunction.apply(degree, mu)
                };
            }
            self.activations[r] = if degree.is_finite() {
                rule.weight * degree
            } else {
                0.0
            };
        }
        for o in 0..self.outputs.len() {
            let value = self.defuzzify(o);
            let var = &self.outputs[o];
            let value = if value.is_nan() {
                if var.lock_previous && !self.previous[o].is_nan() {
                    self.previous[o]
                } else {
                    var.default_value
                }
            } else if var.lock_range {
                value.clamp(var.min, var.max)
            } else {
                value
            };
            if !value.is_nan() {
                self.previous[o] = value;
            }
            if let Some(slot) = outputs.get_mut(o) {
                *slot = value;
            }
        }
    }

    /// The defuzzified output `o`, NaN if no rule fires.
    fn defuzzify(&mut self, o: usize) -> f64 {
        let var = &self.outputs[o];
        let terms = var.terms.len();
        let degrees = &mut self.term_degrees[..terms];
        degrees.fill(0.0);
        let mut weight_total = 0.0;
        for (rule, &a) in self.rules.iter().zip(&self.activations) {
            for &(v, t) in &rule.consequents {
                if v == o && a > 0.0 {
                    degrees[t] = degrees[t].max(a);
                    weight_total += a;
                }
            }
        }
        if weight_total <= 0.0 {
            return f64::NAN;
        }
        match var.defuzzifier {
            Defuzzifier::WeightedAverage => {
                // Σ (aᵢ/Σa)·cᵢ, a convex combination of the centres: it stays finite where
                // Σ aᵢ·cᵢ overflows (centres near 1e308).
                let mut average = 0.0;
                for (rule, &a) in self.rules.iter().zip(&self.activations) {
                    for &(v, t) in &rule.consequents {
                        if v == o && a > 0.0 {
                            average += a / weight_total * var.terms[t].shape.centre();
                        }
                    }
                }
                average
            }
            Defuzzifier::Centroid | Defuzzifier::MeanOfMaximum => self.integrate(o),
        }
    }

    /// Exact centroid or mean of maximum of output `o`'s aggregate (term degrees already set).
    ///
    /// Only the support of the aggregate counts (the universe cut to where an active term is
    /// above 0), and the centroid is integrated in coordinates relative to it, u = (x − left) /
    /// width ∈ [0, 1]: moments of x itself overflowed for terms near 1e155, and breakpoints merged
    /// within 1e-12·(1 + |x|) erased a term narrower than that, so both came out as the default.
    fn integrate(&mut self, o: usize) -> f64 {
        let var = &self.outputs[o];
        let implication = self.implication;
        let degrees = &self.term_degrees[..var.terms.len()];
        let active = || {
            var.terms
                .iter()
                .zip(degrees)
                .filter(|(_, d)| **d > 0.0)
                .map(|(t, &d)| (t.shape, d))
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
                    Norm::AlgebraicProduct => self.pieces.push((d * f0, d * f1)),
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
                        Norm::AlgebraicProduct => {
                            [(a, b), ((0.0, 0.0), (0.0, 0.0)), ((0.0, 0.0), (0.0, 0.0))]
                        }
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

/// The first item equal to an earlier one, found through a hash set: linear in the number of
/// items, where a scan of the earlier items per item made 80 000 term names cost 3·10⁹
/// comparisons (7 s).
fn first_repeated<T: Eq + Hash + Copy>(items: impl IntoIterator<Item = T>) -> Option<T> {
    let mut seen = HashSet::new();
    items.into_iter().find(|item| !seen.insert(*item))
}

/// Sorts breakpoints and drops exact repeats. Near repeats stay: a piece a few ulps wide is
/// evaluated exactly ([`Shape::piece`]) and adds next to nothing, where merging points within a
/// fixed tolerance erased every vertex of a term narrower than it.
fn sort_dedup(v: &mut Vec<f64>) {
    v.sort_by(f64::total_cmp);
    v.dedup();
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one_output_engine(implication: Norm, defuzzifier: Defuzzifier) -> Engine {
        let t = |name: &str, s: Shape| Term {
            name: name.into(),
            shape: s,
        };
        let input = InputVariable {
            name: "x".into(),
            min: 0.0,
            max: 1.0,
            lock_range: false,
            terms: vec![
                t("low", Shape::ramp(1.0, 0.0).unwrap()),
                t("high", Shape::ramp(0.0, 1.0).unwrap()),
            ],
        };
        let output = OutputVariable {
            name: "y".into(),
            min: 0.0,
            max: 10.0,
            lock_range: false,
            terms: vec![
                t("small", Shape::triangle(0.0, 2.0, 6.0).unwrap()),
                t("large", Shape::triangle(4.0, 8.0, 10.0).unwrap()),
            ],
            defuzzifier,
            default_value: -1.0,
            lock_previous: false,
        };
        let rules = vec![
            Rule {
                antecedents: vec![(0, 0)],
                consequents: vec![(0, 0)],
                weight: 1.0,
            },
            Rule {
                antecedents: vec![(0, 1)],
                consequents: vec![(0, 1)],
                weight: 1.0,
            },
        ];
        Engine::new(
            "t",
            vec![input],
            vec![output],
            rules,
            Norm::Minimum,
            implication,
        )
        .unwrap()
    }

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
            let mu = probe
                .rules
                .iter()
                .zip(&probe.activations)
                .map(|(r, &a)| {
                    probe
                        .implication
                        .apply(a, var.terms[r.consequents[0].1].shape.degree(y))
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

    #[test]
    fn repeated_names_are_found_with_comparisons_linear_in_their_number() {
        use std::cell::Cell;
        /// A key that counts how often it is compared for equality.
        struct Counted<'a>(u64, &'a Cell<u64>);
        impl PartialEq for Counted<'_> {
            fn eq(&self, other: &Self) -> bool {
                self.1.set(self.1.get() + 1);
                self.0 == other.0
            }
        }
        impl Eq for Counted<'_> {}
        impl Hash for Counted<'_> {
            fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
                self.0.hash(state);
            }
        }
        let comparisons = Cell::new(0);
        let n = 100_000;
        let keys: Vec<Counted> = (0..n).map(|i| Counted(i, &comparisons)).collect();
        assert!(first_repeated(&keys).is_none());
        // A scan per key would compare n²/2 = 5·10⁹ times.
        assert!(
            comparisons.get() <= 2 * n,
            "{} comparisons",
            comparisons.get()
        );
        let again = [
            Counted(3, &comparisons),
            Counted(4, &comparisons),
            Counted(3, &comparisons),
        ];
        assert_eq!(first_repeated(&again).map(|k| k.0), Some(3));
    }

    #[test]
    fn nothing_fires_gives_the_default_or_the_previous_value() {
        let mut e = one_output_engine(Norm::Minimum, Defuzzifier::Centroid);
        let mut out = [0.0];
        e.evaluate(&[f64::NAN], &mut out);
        assert_eq!(out[0], -1.0);
        e.outputs[0].lock_previous = true;
        e.evaluate(&[0.5], &mut out);
        let previous = out[0];
        e.evaluate(&[f64::NAN], &mut out);
        assert_eq!(out[0], previous);
    }
}
