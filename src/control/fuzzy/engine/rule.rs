//! A rule's parts, with indices into the engine's variables and terms: propositions, conditions,
//! conclusions, rules (and the `and`-only form of paper 002's tables), rule blocks with their
//! operators, and the check of a condition against the variables and the block's operators.

use super::operators::{Hedge, Norm, SNorm};
use super::variables::{InputVariable, OutputVariable};

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

/// Checks a rule's condition against the variables and the block's operators: every index
/// exists, a term is named exactly when the last hedge is not `any`, and `and` / `or` have their
/// operator.
pub(super) fn check_antecedent(
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
