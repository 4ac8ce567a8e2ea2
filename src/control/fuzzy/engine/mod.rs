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
//!
//! | file | holds |
//! |---|---|
//! | `mod.rs` | [`Engine`]: its definition and scratch space, and what it shows of them (variables, rule blocks, rules as text, activations) |
//! | `operators` | the T-norms ([`Norm`]), S-norms ([`SNorm`]) and [`Hedge`]s, as fuzzylite 6 computes them |
//! | `variables` | [`Term`], [`InputVariable`] and [`OutputVariable`] |
//! | `rule` | a rule's parts ([`Proposition`], [`Antecedent`], [`Conclusion`]), [`Rule`], [`RuleBlock`] and its [`Operators`], and the check of a rule's condition |
//! | `build` | [`Engine::new`] and [`Engine::with_blocks`]: every check of a definition, the choice of each output's exact path, the scratch space allocated once |
//! | `inference` | [`Engine::evaluate`]: inputs, rule activations block by block, and an output's value when no rule fired for it |
//! | `defuzzify` | [`Defuzzifier`] and [`WeightedKind`], and each output's number: weighted, sampled, or the exact centroid and mean of maximum |
//!
//! [`Shape::centre`]: super::membership::Shape::centre
//! [`Shape::piece`]: super::membership::Shape::piece

mod build;
mod defuzzify;
mod inference;
mod operators;
mod rule;
mod variables;

use std::ops::Range;

pub use super::FUZZYLITE_EPSILON;
pub use build::CROSSING_RESERVE_TERMS;
pub(crate) use build::NO_RULES_WHY;
pub use defuzzify::{Defuzzifier, WeightedKind};
pub use operators::{Hedge, Norm, SNorm};
pub use rule::{
    Antecedent, Conclusion, Operators, Pair, Proposition, Rule, RuleBlock, VariableRef,
};
pub use variables::{InputVariable, OutputVariable, Term, DEFAULT_RESOLUTION};

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

impl Engine {
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::fuzzy::membership::Shape;

    /// Input x on [0, 1] (ramps low and high), output y on [0, 10] (triangles small and large,
    /// default −1), rules low → small and high → large: the engine the files' tests share.
    pub(super) fn one_output_engine(implication: Norm, defuzzifier: Defuzzifier) -> Engine {
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
}
