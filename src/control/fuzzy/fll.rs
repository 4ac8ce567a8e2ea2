//! fuzzylite's FLL format for Mamdani engines, read and written.
//!
//! The subset is what fuzzylite 6 writes for a Mamdani engine: `Engine:`, `InputVariable:` and
//! `OutputVariable:` with `enabled`, `range`, `lock-range` and `term:` lines (`Triangle`,
//! `Trapezoid`, `Ramp`), the output's `aggregation: Maximum`, `defuzzifier:` (`Centroid`,
//! `WeightedAverage [Automatic]`, `MeanOfMaximum`; a resolution, a whole number ≥ 1, is accepted
//! and ignored, since cutlab defuzzifies exactly), `default:` and `lock-previous:`, and one `RuleBlock:` with `conjunction`
//! (`Minimum` or `AlgebraicProduct`), `disjunction`, `implication`, `activation: General` and
//! `rule: if … and … then … [with w]` lines. `description:` lines and `#` comments are skipped.
//!
//! Anything else — other term shapes, `or`, hedges such as `very`, disabled variables, a second
//! rule block, another aggregation — is an error naming the line, never silently dropped: an engine
//! that loads here evaluates exactly as written.

use std::collections::{HashMap, HashSet};
use std::fmt::Write as _;

use super::engine::{Defuzzifier, Engine, InputVariable, Norm, OutputVariable, Rule, Term};
use super::membership::Shape;
use super::FuzzyError;

fn error(line: usize, message: impl AsRef<str>) -> FuzzyError {
    FuzzyError::new(format!("line {line}: {}", message.as_ref()))
}

fn number(line: usize, text: &str, what: &str) -> Result<f64, FuzzyError> {
    match text.trim() {
        "nan" | "NaN" => Ok(f64::NAN),
        t => t
            .parse::<f64>()
            .map_err(|_| error(line, format!("cannot parse {t:?} as a number ({what})"))),
    }
}

fn boolean(line: usize, text: &str, key: &str) -> Result<bool, FuzzyError> {
    match text.trim() {
        "true" => Ok(true),
        "false" => Ok(false),
        t => Err(error(
            line,
            format!("{key}: expected true or false, got {t:?}"),
        )),
    }
}

enum Section {
    None,
    Engine,
    Input(usize),
    Output(usize),
    Rules,
}

/// Parses an FLL document.
///
/// ```
/// use cutlab::control::fuzzy::fll::{parse, write};
/// use cutlab::control::fuzzy::rules::{paper_002_engine, RuleBase};
/// use cutlab::control::fuzzy::engine::Defuzzifier;
/// let engine = paper_002_engine(&RuleBase::Dynamics.table(), Defuzzifier::Centroid).unwrap();
/// let mut again = parse(&write(&engine)).unwrap();
/// let mut out = [0.0];
/// again.evaluate(&[2.0, -1.0], &mut out);
/// assert!(out[0].is_finite());
/// assert!(parse("Engine: x\nInputVariable: E\n  term: A Gaussian 0 1\n").unwrap_err()
///     .to_string().starts_with("line 3:"));
/// ```
pub fn parse(text: &str) -> Result<Engine, FuzzyError> {
    let mut name = String::from("engine");
    let mut inputs: Vec<InputVariable> = Vec::new();
    // Names seen so far, in sets: a scan per name made 80 000 terms take seconds.
    let mut variable_names: HashSet<String> = HashSet::new();
    // The term names of the variable being read.
    let mut term_names: HashSet<String> = HashSet::new();
    let mut outputs: Vec<OutputVariable> = Vec::new();
    let mut rule_lines: Vec<(usize, String)> = Vec::new();
    let mut conjunction = Norm::Minimum;
    let mut implication = Norm::Minimum;
    let mut rule_blocks = 0;
    let mut section = Section::None;

    for (index, raw) in text.lines().enumerate() {
        let line_no = index + 1;
        let line = raw.split('#').next().unwrap_or_default().trim();
        if line.is_empty() {
            continue;
        }
        let Some((key, value)) = line.split_once(':') else {
            return Err(error(
                line_no,
                format!("expected \"key: value\", got {line:?}"),
            ));
        };
        let (key, value) = (key.trim(), value.trim());
        match key {
            "Engine" => {
                name = value.to_string();
                section = Section::Engine;
                continue;
            }
            "InputVariable" => {
                unique_variable(line_no, value, &mut variable_names)?;
                term_names.clear();
                inputs.push(InputVariable {
                    name: value.to_string(),
                    min: f64::NAN,
                    max: f64::NAN,
                    lock_range: false,
                    terms: Vec::new(),
                });
                section = Section::Input(inputs.len() - 1);
                continue;
            }
            "OutputVariable" => {
                unique_variable(line_no, value, &mut variable_names)?;
                term_names.clear();
                outputs.push(OutputVariable {
                    name: value.to_string(),
                    min: f64::NAN,
                    max: f64::NAN,
                    lock_range: false,
                    terms: Vec::new(),
                    defuzzifier: Defuzzifier::Centroid,
                    default_value: f64::NAN,
                    lock_previous: false,
                });
                section = Section::Output(outputs.len() - 1);
                continue;
            }
            "RuleBlock" => {
                rule_blocks += 1;
                if rule_blocks > 1 {
                    return Err(error(line_no, "only one rule block is supported"));
                }
                section = Section::Rules;
                continue;
            }
            "description" => continue,
            _ => {}
        }
        match section {
            Section::None => {
                return Err(error(
                    line_no,
                    format!("{key:?} before any Engine or variable"),
                ));
            }
            Section::Engine => {
                return Err(error(line_no, format!("unknown engine key {key:?}")));
            }
            Section::Input(i) => {
                let v = &mut inputs[i];
                match key {
                    "enabled" => {
                        if !boolean(line_no, value, key)? {
                            return Err(error(line_no, "disabled variables are not supported"));
                        }
                    }
                    "range" => (v.min, v.max) = range(line_no, value)?,
                    "lock-range" => v.lock_range = boolean(line_no, value, key)?,
                    "term" => add_term(line_no, value, &v.name, &mut v.terms, &mut term_names)?,
                    _ => {
                        return Err(error(
                            line_no,
                            format!("unknown input-variable key {key:?}"),
                        ))
                    }
                }
            }
            Section::Output(o) => {
                let v = &mut outputs[o];
                match key {
                    "enabled" => {
                        if !boolean(line_no, value, key)? {
                            return Err(error(line_no, "disabled variables are not supported"));
                        }
                    }
                    "range" => (v.min, v.max) = range(line_no, value)?,
                    "lock-range" => v.lock_range = boolean(line_no, value, key)?,
                    "aggregation" => {
                        if value != "Maximum" {
                            return Err(error(
                                line_no,
                                format!("aggregation {value:?} is not supported (only Maximum)"),
                            ));
                        }
                    }
                    "defuzzifier" => v.defuzzifier = defuzzifier(line_no, value)?,
                    "default" => v.default_value = number(line_no, value, "default")?,
                    "lock-previous" => v.lock_previous = boolean(line_no, value, key)?,
                    "term" => add_term(line_no, value, &v.name, &mut v.terms, &mut term_names)?,
                    _ => {
                        return Err(error(
                            line_no,
                            format!("unknown output-variable key {key:?}"),
                        ))
                    }
                }
            }
            Section::Rules => {
                match key {
                    "enabled" => {
                        if !boolean(line_no, value, key)? {
                            return Err(error(line_no, "a disabled rule block is not supported"));
                        }
                    }
                    "conjunction" => conjunction = norm(line_no, value, key)?,
                    "implication" => implication = norm(line_no, value, key)?,
                    "disjunction" => {
                        if !matches!(value, "Maximum" | "none" | "") {
                            return Err(error(
                            line_no,
                            format!("disjunction {value:?} is not supported (rules use only \"and\")"),
                        ));
                        }
                    }
                    "activation" => {
                        if value != "General" && !value.is_empty() {
                            return Err(error(
                                line_no,
                                format!("activation {value:?} is not supported (only General)"),
                            ));
                        }
                    }
                    "rule" => rule_lines.push((line_no, value.to_string())),
                    _ => return Err(error(line_no, format!("unknown rule-block key {key:?}"))),
                }
            }
        }
    }
    for v in &inputs {
        if !(v.min.is_finite() && v.max.is_finite()) {
            return Err(FuzzyError::new(format!(
                "input variable {} has no range",
                v.name
            )));
        }
    }
    for v in &outputs {
        if !(v.min.is_finite() && v.max.is_finite()) {
            return Err(FuzzyError::new(format!(
                "output variable {} has no range",
                v.name
            )));
        }
    }
    let input_names = VariableNames::of(inputs.iter().map(|v| (v.name.as_str(), &v.terms[..])));
    let output_names = VariableNames::of(outputs.iter().map(|v| (v.name.as_str(), &v.terms[..])));
    let rules = rule_lines
        .iter()
        .map(|(line_no, text)| rule(*line_no, text, &input_names, &output_names))
        .collect::<Result<Vec<_>, _>>()?;
    Engine::new(name, inputs, outputs, rules, conjunction, implication)
}

fn range(line: usize, value: &str) -> Result<(f64, f64), FuzzyError> {
    let parts: Vec<&str> = value.split_whitespace().collect();
    let [lo, hi] = parts[..] else {
        return Err(error(
            line,
            format!("range needs two numbers, got {value:?}"),
        ));
    };
    Ok((number(line, lo, "range")?, number(line, hi, "range")?))
}

/// Parses a `term:` line of variable `variable` and adds it to `terms`; a second term of the same
/// name is an error, since rules refer to terms by name. `names` holds the variable's term names
/// so far: a set, so 80 000 terms parse in linear time (a scan per term took 37 s).
fn add_term(
    line_no: usize,
    value: &str,
    variable: &str,
    terms: &mut Vec<Term>,
    names: &mut HashSet<String>,
) -> Result<(), FuzzyError> {
    let t = term(line_no, value)?;
    if !names.insert(t.name.clone()) {
        return Err(error(
            line_no,
            format!("{variable} already has a term named {}", t.name),
        ));
    }
    terms.push(t);
    Ok(())
}

/// An error if a variable is already named `name` (`names` holds every variable's name so far):
/// rules refer to variables by name.
fn unique_variable(
    line_no: usize,
    name: &str,
    names: &mut HashSet<String>,
) -> Result<(), FuzzyError> {
    if !names.insert(name.to_string()) {
        return Err(error(
            line_no,
            format!("a variable named {name} already exists"),
        ));
    }
    Ok(())
}

fn term(line: usize, value: &str) -> Result<Term, FuzzyError> {
    let parts: Vec<&str> = value.split_whitespace().collect();
    let Some((&name, rest)) = parts.split_first() else {
        return Err(error(line, "a term needs a name and a shape"));
    };
    let Some((&kind, params)) = rest.split_first() else {
        return Err(error(line, format!("term {name} has no shape")));
    };
    let values = params
        .iter()
        .map(|p| number(line, p, "term parameter"))
        .collect::<Result<Vec<f64>, _>>()?;
    // fuzzylite appends an optional height; only the full height 1 is supported.
    let take = |n: usize| -> Result<&[f64], FuzzyError> {
        match values.len() {
            l if l == n => Ok(&values[..n]),
            l if l == n + 1 && values[n] == 1.0 => Ok(&values[..n]),
            _ => Err(error(
                line,
                format!("{kind} {name} needs {n} numbers, got {}", values.len()),
            )),
        }
    };
    let shape = match kind {
        "Triangle" => {
            let v = take(3)?;
            Shape::triangle(v[0], v[1], v[2])
        }
        "Trapezoid" => {
            let v = take(4)?;
            Shape::trapezoid(v[0], v[1], v[2], v[3])
        }
        "Ramp" => {
            let v = take(2)?;
            Shape::ramp(v[0], v[1])
        }
        other => {
            return Err(error(
                line,
                format!("term {name}: shape {other} is not supported (Triangle, Trapezoid, Ramp)"),
            ))
        }
    }
    .map_err(|e| error(line, format!("term {name}: {e}")))?;
    Ok(Term {
        name: name.to_string(),
        shape,
    })
}

fn norm(line: usize, value: &str, key: &str) -> Result<Norm, FuzzyError> {
    match value {
        "Minimum" => Ok(Norm::Minimum),
        "AlgebraicProduct" => Ok(Norm::AlgebraicProduct),
        other => Err(error(
            line,
            format!("{key} {other:?} is not supported (Minimum or AlgebraicProduct)"),
        )),
    }
}

fn defuzzifier(line: usize, value: &str) -> Result<Defuzzifier, FuzzyError> {
    let mut words = value.split_whitespace();
    let kind = words.next().unwrap_or_default();
    let defuzzifier = Defuzzifier::from_name(kind).ok_or_else(|| {
        error(
            line,
            format!(
                "defuzzifier {kind:?} is not supported (Centroid, WeightedAverage, MeanOfMaximum)"
            ),
        )
    })?;
    let parameter = words.next();
    if let Some(extra) = words.next() {
        return Err(error(
            line,
            format!("defuzzifier {kind}: unexpected {extra:?} after {parameter:?}"),
        ));
    }
    match (defuzzifier, parameter) {
        (_, None) | (Defuzzifier::WeightedAverage, Some("Automatic")) => Ok(defuzzifier),
        (Defuzzifier::WeightedAverage, Some(other)) => Err(error(
            line,
            format!(
                "WeightedAverage {other:?}: only the Automatic type of a Mamdani engine is \
                 supported"
            ),
        )),
        // A resolution: cutlab integrates exactly and ignores it, but a value fuzzylite would
        // refuse (0, negative, NaN, not whole) is a mistake to say.
        (_, Some(resolution)) => match resolution.parse::<u64>() {
            Ok(r) if r >= 1 => Ok(defuzzifier),
            _ => Err(error(
                line,
                format!(
                    "{kind}: the resolution must be a whole number of at least 1 (fuzzylite's \
                     default is 100), got {resolution:?}"
                ),
            )),
        },
    }
}

/// Each variable's index and its terms' indices by name, built once so that every proposition
/// of every rule is found in constant time (a list of every variable's terms built per
/// proposition made rules × terms work and allocation).
struct VariableNames<'a>(HashMap<&'a str, (usize, HashMap<&'a str, usize>)>);

impl<'a> VariableNames<'a> {
    fn of(variables: impl Iterator<Item = (&'a str, &'a [Term])>) -> Self {
        Self(
            variables
                .enumerate()
                .map(|(v, (name, terms))| {
                    let terms = terms.iter().enumerate();
                    (
                        name,
                        (v, terms.map(|(t, term)| (term.name.as_str(), t)).collect()),
                    )
                })
                .collect(),
        )
    }
}

fn rule(
    line: usize,
    text: &str,
    inputs: &VariableNames,
    outputs: &VariableNames,
) -> Result<Rule, FuzzyError> {
    let fail = |m: String| error(line, format!("{m} in rule {text:?}"));
    let words: Vec<&str> = text.split_whitespace().collect();
    if words.first() != Some(&"if") {
        return Err(fail("a rule starts with \"if\"".into()));
    }
    let then = words
        .iter()
        .position(|w| *w == "then")
        .ok_or_else(|| fail("no \"then\"".into()))?;
    let (consequent_words, weight) = match words.iter().position(|w| *w == "with") {
        // The weight closes the rule: a "with" before "then" would leave the consequent inside
        // out (and slicing it panicked).
        Some(w) if w < then => {
            return Err(fail(
                "\"with\" and its weight come after the consequent".into(),
            ))
        }
        Some(w) => {
            let value = words
                .get(w + 1)
                .ok_or_else(|| fail("\"with\" needs a weight".into()))?;
            if words.len() > w + 2 {
                return Err(fail("nothing may follow the weight".into()));
            }
            let consequent = words.get(then + 1..w).unwrap_or_default();
            (consequent, number(line, value, "rule weight")?)
        }
        None => (words.get(then + 1..).unwrap_or_default(), 1.0),
    };
    let propositions = |part: &[&str], names: &VariableNames| {
        part.split(|w| *w == "and")
            .map(|p| match p {
                [var, "is", term] => {
                    let (v, terms) = names
                        .0
                        .get(var)
                        .ok_or_else(|| fail(format!("unknown variable {var:?}")))?;
                    let t = terms
                        .get(term)
                        .ok_or_else(|| fail(format!("unknown term {term:?} of {var}")))?;
                    Ok((*v, *t))
                }
                _ if p.contains(&"or") => Err(fail("\"or\" is not supported".into())),
                [_, "is", ..] => Err(fail(format!(
                    "hedges such as {:?} are not supported",
                    p.get(2).copied().unwrap_or_default()
                ))),
                _ => Err(fail(format!("cannot read {:?}", p.join(" ")))),
            })
            .collect::<Result<Vec<(usize, usize)>, FuzzyError>>()
    };
    Ok(Rule {
        antecedents: propositions(&words[1..then], inputs)?,
        consequents: propositions(consequent_words, outputs)?,
        weight,
    })
}

fn float(v: f64) -> String {
    if v.is_nan() {
        "nan".into()
    } else {
        format!("{v}")
    }
}

/// Writes `engine` as FLL that fuzzylite 6 loads. Centroid and mean of maximum are written with a
/// resolution of 100 (fuzzylite's default; cutlab ignores it); raise it in fuzzylite to approach
/// cutlab's exact values.
pub fn write(engine: &Engine) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "Engine: {}", engine.name);
    for v in engine.inputs() {
        let _ = writeln!(out, "InputVariable: {}", v.name);
        let _ = writeln!(out, "  enabled: true");
        let _ = writeln!(out, "  range: {} {}", float(v.min), float(v.max));
        let _ = writeln!(out, "  lock-range: {}", v.lock_range);
        for t in &v.terms {
            let _ = writeln!(out, "  term: {} {}", t.name, t.shape);
        }
    }
    for v in engine.outputs() {
        let _ = writeln!(out, "OutputVariable: {}", v.name);
        let _ = writeln!(out, "  enabled: true");
        let _ = writeln!(out, "  range: {} {}", float(v.min), float(v.max));
        let _ = writeln!(out, "  lock-range: {}", v.lock_range);
        let _ = writeln!(out, "  aggregation: Maximum");
        let defuzzifier = match v.defuzzifier {
            Defuzzifier::Centroid => "Centroid 100",
            Defuzzifier::WeightedAverage => "WeightedAverage Automatic",
            Defuzzifier::MeanOfMaximum => "MeanOfMaximum 100",
        };
        let _ = writeln!(out, "  defuzzifier: {defuzzifier}");
        let _ = writeln!(out, "  default: {}", float(v.default_value));
        let _ = writeln!(out, "  lock-previous: {}", v.lock_previous);
        for t in &v.terms {
            let _ = writeln!(out, "  term: {} {}", t.name, t.shape);
        }
    }
    let _ = writeln!(out, "RuleBlock: rules");
    let _ = writeln!(out, "  enabled: true");
    let _ = writeln!(out, "  conjunction: {}", engine.conjunction().name());
    let _ = writeln!(out, "  disjunction: Maximum");
    let _ = writeln!(out, "  implication: {}", engine.implication().name());
    let _ = writeln!(out, "  activation: General");
    for r in engine.rules() {
        let part = |pairs: &[(usize, usize)], output: bool| -> String {
            pairs
                .iter()
                .map(|&(v, t)| {
                    let (name, term) = if output {
                        let var = &engine.outputs()[v];
                        (&var.name, &var.terms[t].name)
                    } else {
                        let var = &engine.inputs()[v];
                        (&var.name, &var.terms[t].name)
                    };
                    format!("{name} is {term}")
                })
                .collect::<Vec<_>>()
                .join(" and ")
        };
        let weight = if r.weight == 1.0 {
            String::new()
        } else {
            format!(" with {}", r.weight)
        };
        let _ = writeln!(
            out,
            "  rule: if {} then {}{weight}",
            part(&r.antecedents, false),
            part(&r.consequents, true)
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_with_keywords_in_any_order_are_errors_that_name_the_line_never_panics() {
        let head = "Engine: e\nInputVariable: E\n  range: -1 1\n  term: A Triangle -1 0 1\n\
                    OutputVariable: U\n  range: -1 1\n  term: B Triangle -1 0 1\n\
                    RuleBlock: r\n";
        let words = [
            "if", "is", "and", "or", "then", "with", "very", "not", "E", "A", "U", "B", "0.5",
        ];
        let mut rng = crate::rng::Rng::seed_from(11);
        for n in 0..3000 {
            let len = 1 + (rng.next_u64() % 12) as usize;
            let rule: Vec<&str> = (0..len)
                .map(|_| words[(rng.next_u64() % words.len() as u64) as usize])
                .collect();
            let text = format!("{head}  rule: {}\n", rule.join(" "));
            if let Err(e) = parse(&text) {
                assert!(e.to_string().starts_with("line 9:"), "{n}: {e}");
            }
        }
        // The case that panicked, and a weight with something after it.
        for rule in [
            "if E is A with 0.5 then U is B",
            "if E is A then U is B with 0.5 U",
        ] {
            let e = parse(&format!("{head}  rule: {rule}\n")).unwrap_err();
            assert!(e.to_string().starts_with("line 9:"), "{e}");
        }
        assert!(parse(&format!("{head}  rule: if E is A then U is B with 0.5\n")).is_ok());
    }
    use crate::control::fuzzy::rules::{paper_002_engine, RuleBase};

    #[test]
    fn written_engines_read_back_identically() {
        for base in RuleBase::ALL {
            for d in Defuzzifier::ALL {
                let e = paper_002_engine(&base.table(), d).unwrap();
                let back = parse(&write(&e)).unwrap();
                assert_eq!(back.inputs(), e.inputs());
                assert_eq!(back.outputs()[0].terms, e.outputs()[0].terms);
                assert_eq!(back.outputs()[0].defuzzifier, d);
                assert_eq!(back.rules(), e.rules());
            }
        }
    }

    #[test]
    fn errors_name_the_line_and_the_problem() {
        let base =
            write(&paper_002_engine(&RuleBase::Experience.table(), Defuzzifier::Centroid).unwrap());
        let cases = [
            (
                "rule: if E is NB and EC is NB then U is NB",
                "rule: if E is PX and EC is NB then U is NB",
                "unknown term \"PX\" of E",
            ),
            (
                "rule: if E is NB and EC is NB then U is NB",
                "rule: if E is NB or EC is NB then U is NB",
                "\"or\" is not supported",
            ),
            (
                "rule: if E is NB and EC is NB then U is NB",
                "rule: if E is very NB then U is NB",
                "hedges",
            ),
            (
                "aggregation: Maximum",
                "aggregation: AlgebraicSum",
                "aggregation \"AlgebraicSum\"",
            ),
            (
                "term: NB Triangle -6 -6 -4",
                "term: NB Bell -6 1 2",
                "shape Bell",
            ),
            (
                "defuzzifier: Centroid 100",
                "defuzzifier: Centroid 0",
                "the resolution must be a whole number of at least 1",
            ),
            (
                "defuzzifier: Centroid 100",
                "defuzzifier: Centroid -5",
                "got \"-5\"",
            ),
            (
                "defuzzifier: Centroid 100",
                "defuzzifier: Centroid NaN",
                "got \"NaN\"",
            ),
            (
                "defuzzifier: Centroid 100",
                "defuzzifier: Centroid 100 200",
                "unexpected \"200\"",
            ),
            (
                "defuzzifier: Centroid 100",
                "defuzzifier: WeightedAverage TakagiSugeno",
                "only the Automatic type",
            ),
        ];
        for (from, to, expected) in cases {
            let text = base.replacen(from, to, 1);
            let line = text.lines().position(|l| l.trim() == to).unwrap() + 1;
            let e = parse(&text).unwrap_err().to_string();
            assert!(e.starts_with(&format!("line {line}:")), "{e}");
            assert!(e.contains(expected), "{e}");
        }
    }

    #[test]
    fn empty_engines_and_repeated_names_are_errors() {
        assert!(parse("")
            .unwrap_err()
            .to_string()
            .contains("no output variable"));
        let base =
            write(&paper_002_engine(&RuleBase::Experience.table(), Defuzzifier::Centroid).unwrap());
        let twice = base.replacen("term: NM ", "term: NB ", 1);
        let e = parse(&twice).unwrap_err().to_string();
        assert!(
            e.starts_with("line ") && e.contains("E already has a term named NB"),
            "{e}"
        );
        let same_name = base.replacen("InputVariable: EC", "InputVariable: E", 1);
        let e = parse(&same_name).unwrap_err().to_string();
        assert!(e.contains("a variable named E already exists"), "{e}");
    }
}
