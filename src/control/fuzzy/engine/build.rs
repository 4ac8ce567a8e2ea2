//! Building an engine: every check of a definition (names, universes, shapes, indices, weights,
//! the operators each rule needs), the outputs that take the exact path, and the scratch space,
//! allocated here once so that inference allocates nothing.

use std::collections::HashSet;
use std::hash::Hash;

use super::defuzzify::Defuzzifier;
use super::operators::{Norm, SNorm};
use super::rule::{check_antecedent, Operators, Rule, RuleBlock};
use super::variables::{InputVariable, OutputVariable};
use super::Engine;
use crate::control::fuzzy::FuzzyError;

/// Outputs with up to this many terms have every pairwise crossing reserved (inference then
/// never allocates); paper 002's engine has 7.
pub const CROSSING_RESERVE_TERMS: usize = 64;

/// Why an engine file without a single rule is refused, by the FLL and the FIS reader alike (each
/// says where, in its own terms): fuzzylite loads one, but a controller running it would hold a
/// fixed feed without a word. (An engine built in code may have no rules: a test's, or one being
/// assembled.)
pub(crate) const NO_RULES_WHY: &str =
    "a fuzzy engine without rules holds every output at its default whatever its inputs";

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
    ///
    /// [`FUZZYLITE_EPSILON`]: crate::control::fuzzy::FUZZYLITE_EPSILON
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
}

/// The first item equal to an earlier one, found through a hash set: linear in the number of
/// items, where a scan of the earlier items per item made 80 000 term names cost 3·10⁹
/// comparisons (7 s).
fn first_repeated<T: Eq + Hash + Copy>(items: impl IntoIterator<Item = T>) -> Option<T> {
    let mut seen = HashSet::new();
    items.into_iter().find(|item| !seen.insert(*item))
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
