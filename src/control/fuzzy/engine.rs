//! A fuzzy inference engine for fuzzylite 6's language: Mamdani, Takagi–Sugeno and Tsukamoto
//! engines, any number of rule blocks, chained outputs, exact defuzzification where the aggregate
//! is piecewise linear.
//!
//! **Inference**, as fuzzylite 6 does it. Rule blocks run in order, and each block's rules in
//! order. A rule `if A then Y is B and Z is C (with w)` has activation `w · μ_A`, where `μ_A`
//! combines its propositions with the block's conjunction (T-norm, `and`) and disjunction
//! (S-norm, `or`), `and` binding tighter than `or`. A proposition `X is h₁ h₂ … T` is the term's
//! degree at the input's value with the hedges applied right to left; when X is an output
//! variable (a chained engine), the degree is the aggregation of the activations T received so far
//! (their sum when the output has no aggregation). `any` is 1 whatever the value. A rule fires
//! when its activation exceeds the engine's firing threshold (fuzzylite's 1e-6 for engines read
//! from files, 0 for engines built here); it adds, for each conclusion, its term activated at the
//! activation with the block's implication to that output's fuzzy output (a conclusion's hedges
//! apply to the activation and, as in fuzzylite 6, carry on to the conclusions after it).
//!
//! **Defuzzification**, per output in order (a Function term reads the outputs already computed):
//!
//! * **Centroid** and **mean of maximum**, exact where the aggregate is piecewise linear (every
//!   term of the output a Triangle, Trapezoid or Ramp, implication Minimum or AlgebraicProduct,
//!   aggregation Maximum): the engine collects every breakpoint (term vertices, clip corners, and
//!   crossings of the implied pieces) and integrates ∫x·μ and ∫μ over each straight piece in
//!   closed form. fuzzylite approaches this value as its resolution grows.
//! * Every other integral case (Bisector, SmallestOfMaximum, LargestOfMaximum, smooth terms,
//!   other norms) samples the aggregate at the midpoints of `resolution` cells of the universe,
//!   as fuzzylite does, with its tolerance of 1e-6 when comparing degrees.
//! * **Weighted average** Σ wᵢ·zᵢ / Σ wᵢ and **weighted sum** Σ wᵢ·zᵢ over the activated terms: zᵢ
//!   is a Takagi–Sugeno term's value (Constant, Linear, Function at wᵢ); on an output whose
//!   terms are all monotonic (Ramp, Sigmoid, SShape, ZShape, Concave: a Tsukamoto engine) the
//!   term's inverse at wᵢ; on any other (Mamdani) output the term's centre ([`Shape::centre`],
//!   paper 002 eq 7). fuzzylite 6 differs on a Mamdani output: it inverts the monotonic terms
//!   among others and takes a non-monotonic term's degree at wᵢ, which is not a point of the
//!   output axis.
//!
//! When an output's fuzzy output is empty (no rule fired for it) its value is the previous value
//! if `lock_previous` is set and there is a finite one, else the variable's `default_value` (NaN
//! allowed, as in fuzzylite). `lock_range` clamps an input before fuzzification and an output
//! after defuzzification.
//!
//! **Magnitudes.** Every universe whose width `max − min` is an f64 works, at any position:
//! terms near 1e155 or 1e-300, or 1e-12 wide at 1.0. The exact centroid is integrated in
//! coordinates relative to the aggregate's support (so its moments cannot overflow), breakpoints
//! are merged only when equal (so a narrow term keeps its vertices), straight pieces are
//! evaluated by their own formula at their ends ([`Shape::piece`]), and the weighted average is a
//! convex combination of the terms' values. The results agree with the closed forms and with the
//! references moved to those magnitudes to within the rounding of the terms' own vertices
//! (`tests/fuzzy.rs`). A universe or term wider than an f64 holds (−1e308 to 1e308) is refused
//! when the engine is built.
//!
//! The engine allocates its scratch space when built; [`Engine::evaluate`] allocates nothing.

use std::collections::HashSet;
use std::hash::Hash;
use std::ops::Range;

use super::membership::{Shape, Values};
use super::FuzzyError;
pub use super::FUZZYLITE_EPSILON;

/// The resolution fuzzylite gives an integral defuzzifier that names none.
pub const DEFAULT_RESOLUTION: usize = 100;

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
    /// How activated terms combine (fuzzylite's `aggregation`; `None` is its `none`, which only
    /// a weighted defuzzifier accepts).
    pub aggregation: Option<SNorm>,
    /// Cells of a sampled integral defuzzifier (fuzzylite's resolution); the exact paths ignore
    /// it.
    pub resolution: usize,
    /// The type of a weighted defuzzifier.
    pub weighted_kind: WeightedKind,
}

/// Outputs with up to this many terms have every pairwise crossing reserved (inference then
/// never allocates); paper 002's engine has 7.
pub const CROSSING_RESERVE_TERMS: usize = 64;

/// A T-norm: conjunction (`and`) and implication operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Norm {
    /// min(a, b).
    Minimum,
    /// a · b.
    AlgebraicProduct,
    /// max(0, a + b − 1).
    BoundedDifference,
    /// min(a, b) if max(a, b) = 1, else 0.
    DrasticProduct,
    /// a·b / (2 − (a + b − a·b)).
    EinsteinProduct,
    /// a·b / (a + b − a·b), 0 when a + b = 0.
    HamacherProduct,
    /// min(a, b) if a + b > 1, else 0.
    NilpotentMinimum,
}

/// Whether fuzzylite counts `a` and `b` as equal (within [`FUZZYLITE_EPSILON`]).
fn same(a: f64, b: f64) -> bool {
    a == b || (a - b).abs() < FUZZYLITE_EPSILON || (a.is_nan() && b.is_nan())
}

impl Norm {
    /// Every T-norm.
    pub const ALL: [Norm; 7] = [
        Norm::Minimum,
        Norm::AlgebraicProduct,
        Norm::BoundedDifference,
        Norm::DrasticProduct,
        Norm::EinsteinProduct,
        Norm::HamacherProduct,
        Norm::NilpotentMinimum,
    ];

    /// T(a, b), as fuzzylite 6 computes it.
    pub fn apply(self, a: f64, b: f64) -> f64 {
        match self {
            Norm::Minimum => a.min(b),
            Norm::AlgebraicProduct => a * b,
            Norm::BoundedDifference => 0f64.max(a + b - 1.0),
            Norm::DrasticProduct => {
                if same(a.max(b), 1.0) {
                    a.min(b)
                } else {
                    0.0
                }
            }
            Norm::EinsteinProduct => (a * b) / (2.0 - (a + b - a * b)),
            Norm::HamacherProduct => {
                if same(a + b, 0.0) {
                    0.0
                } else {
                    (a * b) / (a + b - a * b)
                }
            }
            Norm::NilpotentMinimum => {
                if a + b > 1.0 && !same(a + b, 1.0) {
                    a.min(b)
                } else {
                    0.0
                }
            }
        }
    }

    /// fuzzylite's name.
    pub fn name(self) -> &'static str {
        match self {
            Norm::Minimum => "Minimum",
            Norm::AlgebraicProduct => "AlgebraicProduct",
            Norm::BoundedDifference => "BoundedDifference",
            Norm::DrasticProduct => "DrasticProduct",
            Norm::EinsteinProduct => "EinsteinProduct",
            Norm::HamacherProduct => "HamacherProduct",
            Norm::NilpotentMinimum => "NilpotentMinimum",
        }
    }

    /// The T-norm fuzzylite names `name`.
    pub fn from_name(name: &str) -> Option<Norm> {
        Self::ALL.into_iter().find(|n| n.name() == name)
    }
}

/// An S-norm: disjunction (`or`) and aggregation operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SNorm {
    /// max(a, b).
    Maximum,
    /// a + b − a·b.
    AlgebraicSum,
    /// min(1, a + b).
    BoundedSum,
    /// max(a, b) if min(a, b) = 0, else 1.
    DrasticSum,
    /// (a + b) / (1 + a·b).
    EinsteinSum,
    /// (a + b − 2ab) / (1 − ab), 1 when ab = 1.
    HamacherSum,
    /// max(a, b) if a + b < 1, else 1.
    NilpotentMaximum,
    /// (a + b) / max(1, a + b).
    NormalizedSum,
    /// a + b.
    UnboundedSum,
}

impl SNorm {
    /// Every S-norm.
    pub const ALL: [SNorm; 9] = [
        SNorm::Maximum,
        SNorm::AlgebraicSum,
        SNorm::BoundedSum,
        SNorm::DrasticSum,
        SNorm::EinsteinSum,
        SNorm::HamacherSum,
        SNorm::NilpotentMaximum,
        SNorm::NormalizedSum,
        SNorm::UnboundedSum,
    ];

    /// S(a, b), as fuzzylite 6 computes it.
    pub fn apply(self, a: f64, b: f64) -> f64 {
        match self {
            SNorm::Maximum => a.max(b),
            SNorm::AlgebraicSum => a + b - a * b,
            SNorm::BoundedSum => 1f64.min(a + b),
            SNorm::DrasticSum => {
                if same(a.min(b), 0.0) {
                    a.max(b)
                } else {
                    1.0
                }
            }
            SNorm::EinsteinSum => (a + b) / (1.0 + a * b),
            SNorm::HamacherSum => {
                if same(a * b, 1.0) {
                    1.0
                } else {
                    (a + b - 2.0 * a * b) / (1.0 - a * b)
                }
            }
            SNorm::NilpotentMaximum => {
                if a + b < 1.0 && !same(a + b, 1.0) {
                    a.max(b)
                } else {
                    1.0
                }
            }
            SNorm::NormalizedSum => (a + b) / 1f64.max(a + b),
            SNorm::UnboundedSum => a + b,
        }
    }

    /// fuzzylite's name.
    pub fn name(self) -> &'static str {
        match self {
            SNorm::Maximum => "Maximum",
            SNorm::AlgebraicSum => "AlgebraicSum",
            SNorm::BoundedSum => "BoundedSum",
            SNorm::DrasticSum => "DrasticSum",
            SNorm::EinsteinSum => "EinsteinSum",
            SNorm::HamacherSum => "HamacherSum",
            SNorm::NilpotentMaximum => "NilpotentMaximum",
            SNorm::NormalizedSum => "NormalizedSum",
            SNorm::UnboundedSum => "UnboundedSum",
        }
    }

    /// The S-norm fuzzylite names `name`.
    pub fn from_name(name: &str) -> Option<SNorm> {
        Self::ALL.into_iter().find(|n| n.name() == name)
    }
}

/// A hedge: a function applied to a degree.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Hedge {
    /// 1 − μ.
    Not,
    /// √(μ/2) up to 0.5, 1 − √((1 − μ)/2) above.
    Seldom,
    /// √μ.
    Somewhat,
    /// μ².
    Very,
    /// 2μ² up to 0.5, 1 − 2(1 − μ)² above.
    Extremely,
    /// 1, whatever the value: the proposition names no term.
    Any,
}

impl Hedge {
    /// Every hedge.
    pub const ALL: [Hedge; 6] = [
        Hedge::Not,
        Hedge::Seldom,
        Hedge::Somewhat,
        Hedge::Very,
        Hedge::Extremely,
        Hedge::Any,
    ];

    /// The word in a rule.
    pub fn name(self) -> &'static str {
        match self {
            Hedge::Not => "not",
            Hedge::Seldom => "seldom",
            Hedge::Somewhat => "somewhat",
            Hedge::Very => "very",
            Hedge::Extremely => "extremely",
            Hedge::Any => "any",
        }
    }

    /// The hedge a rule's word names.
    pub fn from_name(name: &str) -> Option<Hedge> {
        Self::ALL.into_iter().find(|h| h.name() == name)
    }

    /// The hedged degree.
    pub fn apply(self, mu: f64) -> f64 {
        let at_most_half = mu <= 0.5 || same(mu, 0.5);
        match self {
            Hedge::Not => 1.0 - mu,
            Hedge::Seldom if at_most_half => (0.5 * mu).sqrt(),
            Hedge::Seldom => 1.0 - (0.5 * (1.0 - mu)).sqrt(),
            Hedge::Somewhat => mu.sqrt(),
            Hedge::Very => mu * mu,
            Hedge::Extremely if at_most_half => 2.0 * mu * mu,
            Hedge::Extremely => 1.0 - 2.0 * (1.0 - mu) * (1.0 - mu),
            Hedge::Any => 1.0,
        }
    }
}

/// The variable a proposition is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VariableRef {
    /// An input, by index.
    Input(usize),
    /// An output, by index (a chained engine: the activations its term received so far).
    Output(usize),
}

/// `X is h₁ … T`: a variable, hedges (applied right to left), and a term (none after `any`).
#[derive(Debug, Clone, PartialEq)]
pub struct Proposition {
    /// The variable.
    pub variable: VariableRef,
    /// Hedges, in the order written.
    pub hedges: Vec<Hedge>,
    /// The term's index, `None` exactly when the last hedge is `any`.
    pub term: Option<usize>,
}

/// A rule's condition.
#[derive(Debug, Clone, PartialEq)]
pub enum Antecedent {
    /// One proposition.
    Is(Proposition),
    /// Both, by the block's conjunction.
    And(Box<Antecedent>, Box<Antecedent>),
    /// Either, by the block's disjunction.
    Or(Box<Antecedent>, Box<Antecedent>),
}

/// `Y is h₁ … T` in a rule's consequent.
#[derive(Debug, Clone, PartialEq)]
pub struct Conclusion {
    /// The output's index.
    pub output: usize,
    /// Hedges, in the order written.
    pub hedges: Vec<Hedge>,
    /// The term's index.
    pub term: usize,
}

/// A (variable, term) pair of indices.
pub type Pair = (usize, usize);

/// `if … then … (with w)`, with indices into the engine's variables and terms.
#[derive(Debug, Clone, PartialEq)]
pub struct Rule {
    /// The condition.
    pub antecedent: Antecedent,
    /// The conclusions, in order.
    pub consequents: Vec<Conclusion>,
    /// Weight in [0, 1].
    pub weight: f64,
}

impl Rule {
    /// `if X₁ is A₁ and X₂ is A₂ … then Y₁ is B₁ and …` with (input, term) and (output, term)
    /// pairs and no hedges. `None` when either list is empty.
    ///
    /// ```
    /// use cutlab::control::fuzzy::engine::Rule;
    /// let rule = Rule::all_of(&[(0, 2), (1, 3)], &[(0, 1)], 1.0).unwrap();
    /// assert_eq!(rule.as_all_of(), Some((vec![(0, 2), (1, 3)], vec![(0, 1)])));
    /// ```
    pub fn all_of(
        antecedents: &[(usize, usize)],
        consequents: &[(usize, usize)],
        weight: f64,
    ) -> Option<Rule> {
        let is = |&(v, t): &(usize, usize)| {
            Antecedent::Is(Proposition {
                variable: VariableRef::Input(v),
                hedges: Vec::new(),
                term: Some(t),
            })
        };
        let mut parts = antecedents.iter().map(is);
        let first = parts.next()?;
        let antecedent = parts.fold(first, |l, r| Antecedent::And(Box::new(l), Box::new(r)));
        if consequents.is_empty() {
            return None;
        }
        Some(Rule {
            antecedent,
            consequents: consequents
                .iter()
                .map(|&(output, term)| Conclusion {
                    output,
                    hedges: Vec::new(),
                    term,
                })
                .collect(),
            weight,
        })
    }

    /// The (input, term) and (output, term) pairs of a rule [`Rule::all_of`] could build: inputs
    /// joined by `and` only, no hedges. `None` for any other rule.
    pub fn as_all_of(&self) -> Option<(Vec<Pair>, Vec<Pair>)> {
        fn walk(a: &Antecedent, out: &mut Vec<(usize, usize)>) -> bool {
            match a {
                Antecedent::Is(Proposition {
                    variable: VariableRef::Input(v),
                    hedges,
                    term: Some(t),
                }) if hedges.is_empty() => {
                    out.push((*v, *t));
                    true
                }
                Antecedent::And(l, r) => walk(l, out) && walk(r, out),
                _ => false,
            }
        }
        let mut antecedents = Vec::new();
        if !walk(&self.antecedent, &mut antecedents) {
            return None;
        }
        let consequents = self
            .consequents
            .iter()
            .map(|c| c.hedges.is_empty().then_some((c.output, c.term)))
            .collect::<Option<Vec<_>>>()?;
        Some((antecedents, consequents))
    }
}

/// A rule block's operators; `None` is fuzzylite's `none` (the block's rules must not need it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Operators {
    /// `and`.
    pub conjunction: Option<Norm>,
    /// `or`.
    pub disjunction: Option<SNorm>,
    /// How a fired rule activates its terms (needed by integral defuzzifiers).
    pub implication: Option<Norm>,
}

/// Rules evaluated together with one set of operators.
#[derive(Debug, Clone, PartialEq)]
pub struct RuleBlock {
    /// Name (may be empty).
    pub name: String,
    /// Operators.
    pub operators: Operators,
    /// Rules, in order.
    pub rules: Vec<Rule>,
}

/// A term activated by a fired rule: the term, the activation, the implication.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Activated {
    term: usize,
    degree: f64,
    implication: Option<Norm>,
}

/// A validated engine with its scratch space.
#[derive(Debug, Clone)]
pub struct Engine {
    /// Engine name.
    pub name: String,
    inputs: Vec<InputVariable>,
    outputs: Vec<OutputVariable>,
    rules: Vec<Rule>,
    /// Each block's name, operators and its rules' range in `rules`.
    blocks: Vec<(String, Operators, Range<usize>)>,
    firing_threshold: f64,
    /// Per output, the implication of its exact path ([`Engine::exact_implication`]).
    exact: Vec<Option<Norm>>,
    activations: Vec<f64>,
    previous: Vec<f64>,
    input_values: Vec<f64>,
    output_values: Vec<f64>,
    fired: Vec<Vec<Activated>>,
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
            && self.blocks == other.blocks
            && self.firing_threshold == other.firing_threshold
    }
}

/// The name of what a rule refers to, for messages.
fn rule_error(number: usize, message: impl std::fmt::Display) -> FuzzyError {
    FuzzyError::new(format!("rule {number}: {message}"))
}

impl Engine {
    /// A one-block Mamdani engine: the rules' `and` by `conjunction`, `or` by maximum, terms
    /// activated by `implication`; a rule fires at any activation above 0. Checks every index,
    /// range and weight.
    pub fn new(
        name: impl Into<String>,
        inputs: Vec<InputVariable>,
        outputs: Vec<OutputVariable>,
        rules: Vec<Rule>,
        conjunction: Norm,
        implication: Norm,
    ) -> Result<Self, FuzzyError> {
        let block = RuleBlock {
            name: String::new(),
            operators: Operators {
                conjunction: Some(conjunction),
                disjunction: Some(SNorm::Maximum),
                implication: Some(implication),
            },
            rules,
        };
        Self::with_blocks(name, inputs, outputs, vec![block], 0.0)
    }

    /// An engine of any number of rule blocks; a rule fires when its activation exceeds
    /// `firing_threshold` (fuzzylite's is [`FUZZYLITE_EPSILON`]). Checks every name, range,
    /// shape, index and weight, and that every rule has the operators it needs.
    pub fn with_blocks(
        name: impl Into<String>,
        inputs: Vec<InputVariable>,
        outputs: Vec<OutputVariable>,
        blocks: Vec<RuleBlock>,
        firing_threshold: f64,
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
            if v.resolution == 0 {
                return Err(FuzzyError::new(format!(
                    "output {}: the resolution must be at least 1",
                    v.name
                )));
            }
            if v.defuzzifier.is_integral() && v.aggregation.is_none() {
                return Err(FuzzyError::new(format!(
                    "output {}: {} needs an aggregation; \"none\" is only for a weighted \
                     defuzzifier",
                    v.name,
                    v.defuzzifier.name()
                )));
            }
        }
        // The shapes' fields are public: a shape built without its constructor is checked here.
        let shapes = inputs.iter().map(|v| ("input", &v.name, &v.terms));
        let shapes = shapes.chain(outputs.iter().map(|v| ("output", &v.name, &v.terms)));
        for (kind, variable, terms) in shapes {
            for t in terms {
                t.shape.clone().checked().map_err(|e| {
                    FuzzyError::new(format!("{kind} {variable}, term {}: {e}", t.name))
                })?;
            }
        }
        if !(firing_threshold.is_finite() && (0.0..1.0).contains(&firing_threshold)) {
            return Err(FuzzyError::new(format!(
                "the firing threshold {firing_threshold} must lie in [0, 1)"
            )));
        }
        let mut rules = Vec::new();
        let mut ranges = Vec::new();
        let mut conclusions_per_output = vec![0usize; outputs.len()];
        for block in blocks {
            let start = rules.len();
            for rule in block.rules {
                let number = rules.len() + 1;
                check_antecedent(&rule.antecedent, &inputs, &outputs, block.operators)
                    .map_err(|m| rule_error(number, m))?;
                if rule.consequents.is_empty() {
                    return Err(rule_error(number, "has no conclusion"));
                }
                for c in &rule.consequents {
                    let output = outputs
                        .get(c.output)
                        .filter(|v| c.term < v.terms.len())
                        .ok_or_else(|| {
                            rule_error(number, "refers to a variable or term that does not exist")
                        })?;
                    if output.defuzzifier.is_integral() && block.operators.implication.is_none() {
                        return Err(rule_error(
                            number,
                            format!(
                                "output {} is defuzzified by {}, which needs an implication; \
                                 the rule block has none",
                                output.name,
                                output.defuzzifier.name()
                            ),
                        ));
                    }
                    conclusions_per_output[c.output] += 1;
                }
                if !(0.0..=1.0).contains(&rule.weight) {
                    return Err(rule_error(
                        number,
                        format!(
                            "weight {} must lie in [0, 1]",
                            crate::input::readable(rule.weight)
                        ),
                    ));
                }
                rules.push(rule);
            }
            ranges.push((block.name, block.operators, start..rules.len()));
        }
        // The implications each output's conclusions use.
        let mut implications: Vec<Vec<Option<Norm>>> = vec![Vec::new(); outputs.len()];
        for (_, operators, range) in &ranges {
            for rule in &rules[range.clone()] {
                for c in &rule.consequents {
                    if !implications[c.output].contains(&operators.implication) {
                        implications[c.output].push(operators.implication);
                    }
                }
            }
        }
        let exact = outputs
            .iter()
            .zip(&implications)
            .map(|(var, used)| {
                let one = match used.as_slice() {
                    [Some(n @ (Norm::Minimum | Norm::AlgebraicProduct))] => Some(*n),
                    _ => None,
                };
                let closed_form = matches!(
                    var.defuzzifier,
                    Defuzzifier::Centroid | Defuzzifier::MeanOfMaximum
                ) && var.aggregation == Some(SNorm::Maximum)
                    && var.terms.iter().all(|t| t.shape.is_piecewise_linear());
                one.filter(|_| closed_form)
            })
            .collect();
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
            input_values: vec![f64::NAN; inputs.len()],
            output_values: vec![f64::NAN; outputs.len()],
            fired: conclusions_per_output
                .iter()
                .map(|n| Vec::with_capacity(*n))
                .collect(),
            term_degrees: vec![0.0; max_terms],
            breakpoints: Vec::with_capacity(capacity * 4),
            pieces: Vec::with_capacity(max_terms),
            inputs,
            outputs,
            rules,
            blocks: ranges,
            firing_threshold,
            exact,
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

    /// Every rule, block after block.
    pub fn rules(&self) -> &[Rule] {
        &self.rules
    }

    /// The rule blocks: name, operators and rules.
    pub fn rule_blocks(&self) -> impl Iterator<Item = (&str, Operators, &[Rule])> + '_ {
        self.blocks
            .iter()
            .map(|(name, ops, range)| (name.as_str(), *ops, &self.rules[range.clone()]))
    }

    /// The implication with which output `o` is defuzzified in closed form, or `None` when it is
    /// sampled or weighted. The closed form applies to Centroid and MeanOfMaximum when every term
    /// of the output is piecewise linear (Triangle, Trapezoid, Ramp), its aggregation is Maximum,
    /// and every rule concluding on it implies by the same Minimum or AlgebraicProduct.
    pub fn exact_implication(&self, o: usize) -> Option<Norm> {
        self.exact.get(o).copied().flatten()
    }

    /// The activation above which a rule fires.
    pub fn firing_threshold(&self) -> f64 {
        self.firing_threshold
    }

    /// The first block's `and` operator.
    pub fn conjunction(&self) -> Option<Norm> {
        self.blocks.first().and_then(|b| b.1.conjunction)
    }

    /// The first block's implication operator.
    pub fn implication(&self) -> Option<Norm> {
        self.blocks.first().and_then(|b| b.1.implication)
    }

    /// Each rule's activation after the latest evaluation.
    pub fn activations(&self) -> &[f64] {
        &self.activations
    }

    /// The text of rule `index` as FLL writes it (`if E is NB and EC is not PS then U is NB
    /// with 0.5`); empty for an index past the last rule.
    ///
    /// ```
    /// use cutlab::control::fuzzy::engine::Defuzzifier;
    /// use cutlab::control::fuzzy::rules::{paper_002_engine, RuleBase};
    /// let e = paper_002_engine(&RuleBase::Dynamics.table(), Defuzzifier::Centroid).unwrap();
    /// assert_eq!(e.rule_text(0), "if E is NB and EC is NB then U is NB");
    /// ```
    pub fn rule_text(&self, index: usize) -> String {
        let Some(rule) = self.rules.get(index) else {
            return String::new();
        };
        let hedged = |hedges: &[Hedge], term: Option<&str>| {
            let mut words: Vec<&str> = hedges.iter().map(|h| h.name()).collect();
            words.extend(term);
            words.join(" ")
        };
        fn condition(engine: &Engine, a: &Antecedent, parent_and: bool, out: &mut String) {
            match a {
                Antecedent::Is(p) => {
                    let (name, terms) = match p.variable {
                        VariableRef::Input(v) => {
                            let var = &engine.inputs[v];
                            (&var.name, &var.terms)
                        }
                        VariableRef::Output(v) => {
                            let var = &engine.outputs[v];
                            (&var.name, &var.terms)
                        }
                    };
                    let mut words: Vec<&str> = p.hedges.iter().map(|h| h.name()).collect();
                    words.extend(p.term.and_then(|t| terms.get(t)).map(|t| t.name.as_str()));
                    out.push_str(&format!("{name} is {}", words.join(" ")));
                }
                Antecedent::And(l, r) => {
                    condition(engine, l, true, out);
                    out.push_str(" and ");
                    condition(engine, r, true, out);
                }
                Antecedent::Or(l, r) => {
                    // `and` binds tighter: an `or` inside an `and` needs parentheses.
                    if parent_and {
                        out.push('(');
                    }
                    condition(engine, l, false, out);
                    out.push_str(" or ");
                    condition(engine, r, false, out);
                    if parent_and {
                        out.push(')');
                    }
                }
            }
        }
        let mut text = String::from("if ");
        condition(self, &rule.antecedent, false, &mut text);
        text.push_str(" then ");
        let conclusions: Vec<String> = rule
            .consequents
            .iter()
            .map(|c| {
                let var = &self.outputs[c.output];
                let term = var.terms.get(c.term).map(|t| t.name.as_str());
                format!("{} is {}", var.name, hedged(&c.hedges, term))
            })
            .collect();
        text.push_str(&conclusions.join(" and "));
        if rule.weight != 1.0 {
            text.push_str(&format!(" with {}", rule.weight));
        }
        text
    }

    /// Sets the defuzzifier of every output (an integral one gets maximum aggregation if the
    /// output had none).
    pub fn set_defuzzifier(&mut self, defuzzifier: Defuzzifier) {
        for o in &mut self.outputs {
            o.defuzzifier = defuzzifier;
            if defuzzifier.is_integral() && o.aggregation.is_none() {
                o.aggregation = Some(SNorm::Maximum);
            }
        }
    }

    /// Forgets the previous outputs (for `lock_previous`).
    pub fn reset(&mut self) {
        self.previous.fill(f64::NAN);
        self.output_values.fill(f64::NAN);
        self.activations.fill(0.0);
    }

    /// Evaluates an engine of two inputs and one output, such as a loop controller's: (e, ec)
    /// → the output. `None` for an engine of another shape.
    ///
    /// ```
    /// use cutlab::control::fuzzy::engine::Defuzzifier;
    /// use cutlab::control::fuzzy::rules::{paper_002_engine, RuleBase};
    /// let mut e = paper_002_engine(&RuleBase::Dynamics.table(), Defuzzifier::WeightedAverage).unwrap();
    /// assert_eq!(e.evaluate_pair(0.0, 0.0), Some(0.0));
    /// ```
    pub fn evaluate_pair(&mut self, e: f64, ec: f64) -> Option<f64> {
        if self.inputs.len() != 2 || self.outputs.len() != 1 {
            return None;
        }
        let mut out = [f64::NAN];
        self.evaluate(&[e, ec], &mut out);
        Some(out[0])
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
        for (i, var) in self.inputs.iter().enumerate() {
            let x = inputs.get(i).copied().unwrap_or(f64::NAN);
            self.input_values[i] = if var.lock_range {
                x.clamp(var.min, var.max)
            } else {
                x
            };
        }
        for fired in &mut self.fired {
            fired.clear();
        }
        for (_, operators, range) in &self.blocks {
            for r in range.clone() {
                let rule = &self.rules[r];
                let values = Values {
                    inputs: &self.input_values,
                    outputs: &self.output_values,
                };
                let degree = antecedent_degree(
                    &rule.antecedent,
                    *operators,
                    &self.inputs,
                    &self.outputs,
                    &self.fired,
                    values,
                );
                let activation = if degree.is_finite() {
                    rule.weight * degree
                } else {
                    0.0
                };
                self.activations[r] = activation;
                if activation > self.firing_threshold {
                    // fuzzylite 6 hedges the activation itself, so a conclusion's hedges carry on
                    // to the conclusions after it.
                    let mut degree = activation;
                    for c in &rule.consequents {
                        for h in c.hedges.iter().rev() {
                            degree = h.apply(degree);
                        }
                        self.fired[c.output].push(Activated {
                            term: c.term,
                            degree,
                            implication: operators.implication,
                        });
                    }
                }
            }
        }
        for o in 0..self.outputs.len() {
            let value = if self.fired[o].is_empty() {
                let var = &self.outputs[o];
                if var.lock_previous && self.previous[o].is_finite() {
                    self.previous[o]
                } else {
                    var.default_value
                }
            } else {
                self.defuzzify(o)
            };
            let var = &self.outputs[o];
            let value = if var.lock_range && !value.is_nan() {
                value.clamp(var.min, var.max)
            } else {
                value
            };
            if value.is_finite() {
                self.previous[o] = value;
            }
            self.output_values[o] = value;
            if let Some(slot) = outputs.get_mut(o) {
                *slot = value;
            }
        }
    }

    /// The defuzzified output `o` from its (non-empty) fuzzy output.
    fn defuzzify(&mut self, o: usize) -> f64 {
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

/// Checks a rule's condition against the variables and the block's operators: every index
/// exists, a term is named exactly when the last hedge is not `any`, and `and` / `or` have their
/// operator.
fn check_antecedent(
    a: &Antecedent,
    inputs: &[InputVariable],
    outputs: &[OutputVariable],
    operators: Operators,
) -> Result<(), String> {
    match a {
        Antecedent::Is(p) => {
            let terms = match p.variable {
                VariableRef::Input(v) => inputs.get(v).map(|v| v.terms.len()),
                VariableRef::Output(v) => outputs.get(v).map(|v| v.terms.len()),
            };
            let any_last = p.hedges.last() == Some(&Hedge::Any);
            match (terms, p.term) {
                (Some(_), None) if any_last => Ok(()),
                (Some(n), Some(t)) if t < n && !any_last => Ok(()),
                _ => Err("refers to a variable or term that does not exist".into()),
            }
        }
        Antecedent::And(l, r) => {
            if operators.conjunction.is_none() {
                return Err("uses \"and\" but the rule block's conjunction is none".into());
            }
            check_antecedent(l, inputs, outputs, operators)?;
            check_antecedent(r, inputs, outputs, operators)
        }
        Antecedent::Or(l, r) => {
            if operators.disjunction.is_none() {
                return Err("uses \"or\" but the rule block's disjunction is none".into());
            }
            check_antecedent(l, inputs, outputs, operators)?;
            check_antecedent(r, inputs, outputs, operators)
        }
    }
}

/// The degree of a rule's condition (the engine checked its operators and indices).
fn antecedent_degree(
    a: &Antecedent,
    operators: Operators,
    inputs: &[InputVariable],
    outputs: &[OutputVariable],
    fired: &[Vec<Activated>],
    values: Values<'_>,
) -> f64 {
    let degree = |a: &Antecedent| antecedent_degree(a, operators, inputs, outputs, fired, values);
    match a {
        Antecedent::Is(p) => {
            let mut hedges = p.hedges.iter().rev().copied();
            let mu = match (p.term, p.variable) {
                // `any` is 1 whatever the value; the hedges before it apply to that.
                (None, _) => hedges.next().map_or(1.0, |h| h.apply(f64::NAN)),
                (Some(t), VariableRef::Input(v)) => inputs[v].terms[t]
                    .shape
                    .degree_in(values.inputs.get(v).copied().unwrap_or(f64::NAN), values),
                (Some(t), VariableRef::Output(v)) => {
                    // The activations term t received so far, aggregated (summed without an
                    // aggregation), as fuzzylite's chained engines read an output.
                    let aggregation = outputs[v].aggregation;
                    fired[v]
                        .iter()
                        .filter(|x| x.term == t)
                        .fold(0.0, |acc, x| match aggregation {
                            Some(s) => s.apply(acc, x.degree),
                            None => acc + x.degree,
                        })
                }
            };
            hedges.fold(mu, |mu, h| h.apply(mu))
        }
        Antecedent::And(l, r) => operators
            .conjunction
            .map_or(f64::NAN, |n| n.apply(degree(l), degree(r))),
        Antecedent::Or(l, r) => operators
            .disjunction
            .map_or(f64::NAN, |n| n.apply(degree(l), degree(r))),
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
            aggregation: Some(SNorm::Maximum),
            resolution: DEFAULT_RESOLUTION,
            weighted_kind: WeightedKind::Automatic,
        };
        let rules = vec![
            Rule::all_of(&[(0, 0)], &[(0, 0)], 1.0).unwrap(),
            Rule::all_of(&[(0, 1)], &[(0, 1)], 1.0).unwrap(),
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
