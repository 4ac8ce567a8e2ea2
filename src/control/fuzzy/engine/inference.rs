//! Evaluating an engine: inputs (clamped where locked), each rule's activation block by block
//! (its condition through the block's operators), the fired terms handed to their outputs, and an
//! output's value when no rule fired for it (the previous or the default value).

use super::rule::{Antecedent, Operators, VariableRef};
use super::variables::{InputVariable, OutputVariable};
use super::{Activated, Engine};
use crate::control::fuzzy::membership::Values;

impl Engine {
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

#[cfg(test)]
mod tests {
    use super::super::tests::one_output_engine;
    use super::super::{Defuzzifier, Norm};

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
