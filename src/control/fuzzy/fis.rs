//! MATLAB's FIS format (what the Fuzzy Logic Designer saves), read and written, with fuzzylite 6's
//! meaning.
//!
//! A FIS file has a `[System]` section (`Name`, `Type`, `AndMethod`, `OrMethod`, `ImpMethod`,
//! `AggMethod`, `DefuzzMethod`, and counts that are redundant), `[InputN]` and `[OutputN]`
//! sections (`Name`, `Range=[min max]`, `MFk='name':'type',[parameters]`; outputs may add
//! fuzzylite's `Default`, `LockPrevious` and `LockRange`) and `[Rules]`, one rule per line:
//! `i₁ i₂ …, o₁ o₂ … (weight) : connective`, where a code is a term's 1-based index, 0 for "not
//! named", negative for `not`, with fuzzylite's hedge decimals (.01 seldom, .05 somewhat, .2 very,
//! .3 extremely, .4 very very, .99 any) and the connective 1 for `and`, 2 for `or`. Membership
//! functions: MATLAB's `trimf trapmf gaussmf gauss2mf gbellmf sigmf dsigmf psigmf zmf smf pimf
//! constant linear` and fuzzylite's `rampmf rectmf concavemf cosinemf spikemf discretemf
//! function`. Methods: `min prod` and fuzzylite's T-norm names (`bounded_difference`, …); `max
//! probor sum` and its S-norm names; `centroid bisector mom som lom wtaver wtsum`; `''` is none.
//!
//! The engine reads as fuzzylite 6's `FisImporter` reads it: every output gets the system's
//! aggregation and defuzzifier (an integral one at fuzzylite's resolution of 100), the default
//! NaN unless the file says otherwise, and rules fire above fuzzylite's threshold. (MATLAB
//! instead returns the middle of the range when no rule fires.) Every malformed line is an error
//! naming it; nothing is dropped.
//!
//! [`write()`] exports any engine FIS can say: one rule block whose rules name input variables
//! only, each at most once, joined all by `and` or all by `or`, hedges that have a code, one
//! conclusion per output, one defuzzifier and aggregation for all outputs, no input locking its
//! range. Anything else is an error saying what FIS cannot express.

use std::fmt::Write as _;

use super::engine::{
    Antecedent, Conclusion, Defuzzifier, Engine, Hedge, InputVariable, Norm, Operators,
    OutputVariable, Proposition, Rule, RuleBlock, SNorm, Term, VariableRef, WeightedKind,
    DEFAULT_RESOLUTION, FUZZYLITE_EPSILON, NO_RULES_WHY,
};
use super::fll::{float, formula_names, number};
use super::function::Formula;
use super::membership::Shape;
use super::FuzzyError;

fn error(line: usize, message: impl AsRef<str>) -> FuzzyError {
    FuzzyError::new(format!("line {line}: {}", message.as_ref()))
}

/// fuzzylite's T-norms by their FIS names.
const T_NORMS: [(&str, Norm); 7] = [
    ("min", Norm::Minimum),
    ("prod", Norm::AlgebraicProduct),
    ("bounded_difference", Norm::BoundedDifference),
    ("drastic_product", Norm::DrasticProduct),
    ("einstein_product", Norm::EinsteinProduct),
    ("hamacher_product", Norm::HamacherProduct),
    ("nilpotent_minimum", Norm::NilpotentMinimum),
];

/// fuzzylite's S-norms by their FIS names.
const S_NORMS: [(&str, SNorm); 9] = [
    ("max", SNorm::Maximum),
    ("probor", SNorm::AlgebraicSum),
    ("bounded_sum", SNorm::BoundedSum),
    ("normalized_sum", SNorm::NormalizedSum),
    ("drastic_sum", SNorm::DrasticSum),
    ("einstein_sum", SNorm::EinsteinSum),
    ("hamacher_sum", SNorm::HamacherSum),
    ("nilpotent_maximum", SNorm::NilpotentMaximum),
    ("sum", SNorm::UnboundedSum),
];

/// The defuzzifiers by their FIS names.
const DEFUZZIFIERS: [(&str, Defuzzifier); 7] = [
    ("centroid", Defuzzifier::Centroid),
    ("bisector", Defuzzifier::Bisector),
    ("mom", Defuzzifier::MeanOfMaximum),
    ("som", Defuzzifier::SmallestOfMaximum),
    ("lom", Defuzzifier::LargestOfMaximum),
    ("wtaver", Defuzzifier::WeightedAverage),
    ("wtsum", Defuzzifier::WeightedSum),
];

/// Hedge decimals of a rule code, as fuzzylite's FIS importer and exporter use them.
const HEDGE_CODES: [(f64, &[Hedge]); 6] = [
    (0.01, &[Hedge::Seldom]),
    (0.05, &[Hedge::Somewhat]),
    (0.2, &[Hedge::Very]),
    (0.3, &[Hedge::Extremely]),
    (0.4, &[Hedge::Very, Hedge::Very]),
    (0.99, &[Hedge::Any]),
];

/// fuzzylite's valid name: letters, digits, `_` and `.` kept, anything else dropped.
fn valid_name(name: &str) -> String {
    name.chars()
        .filter(|c| c.is_alphanumeric() || *c == '_' || *c == '.')
        .collect()
}

/// A variable section as read: its lines, for terms parsed once every variable is known.
struct VariableText {
    output: bool,
    name: String,
    name_line: usize,
    range: Option<(f64, f64)>,
    mfs: Vec<(usize, String)>,
    default: f64,
    lock_previous: bool,
    lock_range: bool,
}

enum FisSection {
    System,
    Variable(usize),
    Rules,
}

/// Parses a FIS document.
///
/// ```
/// use cutlab::control::fuzzy::fis::{parse, write};
/// let text = "[System]\nName='dimmer'\nType='mamdani'\nAndMethod='min'\nOrMethod='max'\n\
///     ImpMethod='min'\nAggMethod='max'\nDefuzzMethod='centroid'\n\n[Input1]\nName='Ambient'\n\
///     Range=[0 1]\nNumMFs=2\nMF1='DARK':'trimf',[0 0.25 0.5]\nMF2='BRIGHT':'trimf',[0.5 0.75 1]\n\n\
///     [Output1]\nName='Power'\nRange=[0 1]\nMF1='LOW':'trimf',[0 0.25 0.5]\n\
///     MF2='HIGH':'trimf',[0.5 0.75 1]\n\n[Rules]\n1, 2 (1) : 1\n2, 1 (1) : 1\n";
/// let mut engine = parse(text).unwrap();
/// let mut out = [0.0];
/// engine.evaluate(&[0.25], &mut out);
/// assert!((out[0] - 0.75).abs() < 1e-12);
/// assert_eq!(parse(&write(&engine).unwrap()).unwrap().rules(), engine.rules());
/// assert!(parse(&text.replace("2, 1 (1)", "2, 3 (1)")).unwrap_err().to_string()
///     .starts_with("line 25:"));
/// ```
pub fn parse(text: &str) -> Result<Engine, FuzzyError> {
    let mut name = String::from("engine");
    let mut methods: [Option<(usize, String)>; 5] = Default::default();
    let mut variables: Vec<VariableText> = Vec::new();
    let mut rule_lines: Vec<(usize, String)> = Vec::new();
    let mut rules_section_line: Option<usize> = None;
    let mut section: Option<FisSection> = None;
    for (index, raw) in text.lines().enumerate() {
        let line_no = index + 1;
        let line = raw.split("//").next().unwrap_or_default();
        let line = line.split('#').next().unwrap_or_default().trim();
        if line.is_empty() || line.starts_with('%') {
            continue;
        }
        if line.starts_with('[') {
            section = Some(match line {
                "[System]" => FisSection::System,
                "[Rules]" => {
                    rules_section_line = Some(line_no);
                    FisSection::Rules
                }
                _ if line.starts_with("[Input") || line.starts_with("[Output") => {
                    let output = line.starts_with("[Output");
                    variables.push(VariableText {
                        output,
                        name: String::new(),
                        name_line: line_no,
                        range: None,
                        mfs: Vec::new(),
                        default: f64::NAN,
                        lock_previous: false,
                        lock_range: false,
                    });
                    FisSection::Variable(variables.len() - 1)
                }
                other => return Err(error(line_no, format!("unknown section {other:?}"))),
            });
            continue;
        }
        let Some(current) = &section else {
            return Err(error(
                line_no,
                format!("{line:?} is outside any section ([System], [Input1], …)"),
            ));
        };
        if let FisSection::Rules = current {
            rule_lines.push((line_no, line.to_string()));
            continue;
        }
        let Some((key, value)) = line.split_once('=') else {
            return Err(error(
                line_no,
                format!("expected \"key=value\", got {line:?}"),
            ));
        };
        let key = key.trim();
        let value = value.trim().replace('\'', "");
        match current {
            FisSection::System => {
                let slot = match key {
                    "Name" => {
                        name = value.trim().to_string();
                        continue;
                    }
                    "Type" | "Version" | "NumInputs" | "NumOutputs" | "NumRules" => continue,
                    "AndMethod" => 0,
                    "OrMethod" => 1,
                    "ImpMethod" => 2,
                    "AggMethod" => 3,
                    "DefuzzMethod" => 4,
                    other => return Err(error(line_no, format!("unknown [System] key {other:?}"))),
                };
                methods[slot] = Some((line_no, value.trim().to_string()));
            }
            FisSection::Variable(v) => {
                let var = &mut variables[*v];
                let flag = |value: &str| -> Result<bool, FuzzyError> {
                    Ok(number(line_no, value, key)? == 1.0)
                };
                match key {
                    "Name" => {
                        var.name = valid_name(value.trim());
                        var.name_line = line_no;
                    }
                    "Range" => var.range = Some(range(line_no, &value)?),
                    "NumMFs" => {}
                    "Enabled" => {
                        if !flag(&value)? {
                            return Err(error(line_no, "disabled variables are not supported"));
                        }
                    }
                    "Default" if var.output => var.default = number(line_no, &value, key)?,
                    "LockPrevious" if var.output => var.lock_previous = flag(&value)?,
                    "LockRange" if var.output => var.lock_range = flag(&value)?,
                    _ if key.starts_with("MF") => var.mfs.push((line_no, value.to_string())),
                    other => return Err(error(line_no, format!("unknown variable key {other:?}"))),
                }
            }
            FisSection::Rules => {}
        }
    }
    let method = |slot: usize| methods[slot].clone().unwrap_or((0, String::new()));
    let (and_line, and) = method(0);
    let (or_line, or) = method(1);
    let (imp_line, imp) = method(2);
    let (agg_line, agg) = method(3);
    let (defuzz_line, defuzz) = method(4);
    let t_norm = |line: usize, name: &str| -> Result<Option<Norm>, FuzzyError> {
        if name.is_empty() {
            return Ok(None);
        }
        T_NORMS
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, norm)| Some(*norm))
            .or_else(|| Norm::from_name(name).map(Some))
            .ok_or_else(|| error(line, format!("{name:?} is not a T-norm (min, prod, …)")))
    };
    let s_norm = |line: usize, name: &str| -> Result<Option<SNorm>, FuzzyError> {
        if name.is_empty() {
            return Ok(None);
        }
        S_NORMS
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, norm)| Some(*norm))
            .or_else(|| SNorm::from_name(name).map(Some))
            .ok_or_else(|| {
                error(
                    line,
                    format!("{name:?} is not an S-norm (max, probor, sum, …)"),
                )
            })
    };
    let operators = Operators {
        conjunction: t_norm(and_line, &and)?,
        disjunction: s_norm(or_line, &or)?,
        implication: t_norm(imp_line, &imp)?,
    };
    let aggregation = s_norm(agg_line, &agg)?;
    if methods[4].is_none() {
        return Err(FuzzyError::new(
            "the [System] section has no DefuzzMethod (centroid, wtaver, …)",
        ));
    }
    let defuzzifier = DEFUZZIFIERS
        .iter()
        .find(|(n, _)| *n == defuzz)
        .map(|(_, d)| *d)
        .or_else(|| Defuzzifier::from_name(&defuzz))
        .ok_or_else(|| {
            error(
                defuzz_line,
                format!(
                    "DefuzzMethod {defuzz:?} is not centroid, bisector, mom, som, lom, wtaver or \
                     wtsum"
                ),
            )
        })?;

    let mut inputs = Vec::new();
    let mut outputs = Vec::new();
    for v in &variables {
        let Some((min, max)) = v.range else {
            return Err(error(
                v.name_line,
                format!("variable {:?} has no Range", v.name),
            ));
        };
        if v.name.is_empty() {
            return Err(error(v.name_line, "a variable needs a Name"));
        }
        if v.output {
            outputs.push(OutputVariable {
                name: v.name.clone(),
                min,
                max,
                lock_range: v.lock_range,
                terms: Vec::new(),
                defuzzifier,
                default_value: v.default,
                lock_previous: v.lock_previous,
                aggregation,
                resolution: DEFAULT_RESOLUTION,
                weighted_kind: WeightedKind::Automatic,
            });
        } else {
            inputs.push(InputVariable {
                name: v.name.clone(),
                min,
                max,
                lock_range: false,
                terms: Vec::new(),
            });
        }
    }
    // Terms once every variable is known: a function may name any of them.
    let (mut i, mut o) = (0, 0);
    let mut all_terms: Vec<Vec<Term>> = Vec::new();
    for v in &variables {
        let mut terms = Vec::new();
        for (line_no, text) in &v.mfs {
            let t = membership(*line_no, text, &inputs, &outputs)?;
            if terms.iter().any(|x: &Term| x.name == t.name) {
                return Err(error(
                    *line_no,
                    format!("{} already has a term named {}", v.name, t.name),
                ));
            }
            terms.push(t);
        }
        all_terms.push(terms);
    }
    for (v, terms) in variables.iter().zip(all_terms) {
        if v.output {
            outputs[o].terms = terms;
            o += 1;
        } else {
            inputs[i].terms = terms;
            i += 1;
        }
    }
    let rules = rule_lines
        .iter()
        .map(|(line_no, text)| rule(*line_no, text, &inputs, &outputs))
        .collect::<Result<Vec<_>, _>>()?;
    let no_rules = rules.is_empty();
    let block = RuleBlock {
        name: String::new(),
        operators,
        rules,
    };
    // Checked after the engine builds, so a missing variable is named first (as FLL does).
    let engine = Engine::with_blocks(name, inputs, outputs, vec![block], FUZZYLITE_EPSILON)?;
    if no_rules {
        let why = NO_RULES_WHY;
        let why = format!("{why}; add a line per rule under [Rules] (\"1 2, 1 (1) : 1\")");
        return Err(match rules_section_line {
            Some(line) => error(line, format!("the [Rules] section is empty: {why}")),
            None => FuzzyError::new(format!("the file has no [Rules] section: {why}")),
        });
    }
    Ok(engine)
}

fn range(line: usize, value: &str) -> Result<(f64, f64), FuzzyError> {
    let inner = value.trim();
    let inner = inner
        .strip_prefix('[')
        .and_then(|v| v.strip_suffix(']'))
        .ok_or_else(|| error(line, format!("a range is [min max], got {inner:?}")))?;
    let parts: Vec<&str> = inner.split_whitespace().collect();
    let [lo, hi] = parts[..] else {
        return Err(error(line, format!("a range is [min max], got {value:?}")));
    };
    Ok((number(line, lo, "range")?, number(line, hi, "range")?))
}

/// One `MFk='name':'type',[parameters]` value (quotes already removed).
fn membership(
    line: usize,
    text: &str,
    inputs: &[InputVariable],
    outputs: &[OutputVariable],
) -> Result<Term, FuzzyError> {
    let fail = || {
        error(
            line,
            format!("expected 'name':'type',[parameters], got {text:?}"),
        )
    };
    let (name, rest) = text.split_once(':').ok_or_else(fail)?;
    let (kind, params) = rest.split_once(',').ok_or_else(fail)?;
    let name = valid_name(name.trim());
    let kind = kind.trim();
    let params = params.trim();
    let params = params
        .strip_prefix('[')
        .and_then(|p| p.strip_suffix(']'))
        .ok_or_else(fail)?;
    if name.is_empty() {
        return Err(error(line, "a membership function needs a name"));
    }
    if kind == "function" {
        let formula = Formula::parse(params, formula_names(inputs, outputs))
            .map_err(|e| error(line, format!("term {name}: {e}")))?;
        return Ok(Term {
            name,
            shape: Shape::Function(formula),
        });
    }
    let p = params
        .split_whitespace()
        .map(|w| number(line, w, "parameter"))
        .collect::<Result<Vec<f64>, _>>()?;
    let need = |n: usize| -> Result<(), FuzzyError> {
        if p.len() == n {
            Ok(())
        } else {
            Err(error(
                line,
                format!("term {name}: {kind} needs {n} parameters, got {}", p.len()),
            ))
        }
    };
    // MATLAB's parameter orders, turned into fuzzylite's.
    let (fll_kind, fll_params): (&str, Vec<f64>) = match kind {
        "trimf" => ("Triangle", p.clone()),
        "trapmf" => ("Trapezoid", p.clone()),
        "gaussmf" => {
            need(2)?;
            ("Gaussian", vec![p[1], p[0]])
        }
        "gauss2mf" => {
            need(4)?;
            ("GaussianProduct", vec![p[1], p[0], p[3], p[2]])
        }
        "gbellmf" => {
            need(3)?;
            ("Bell", vec![p[2], p[0], p[1]])
        }
        "sigmf" => {
            need(2)?;
            ("Sigmoid", vec![p[1], p[0]])
        }
        "dsigmf" => {
            need(4)?;
            ("SigmoidDifference", vec![p[1], p[0], p[2], p[3]])
        }
        "psigmf" => {
            need(4)?;
            ("SigmoidProduct", vec![p[1], p[0], p[2], p[3]])
        }
        "zmf" => ("ZShape", p.clone()),
        "smf" => ("SShape", p.clone()),
        "pimf" => ("PiShape", p.clone()),
        "constant" => ("Constant", p.clone()),
        "linear" => ("Linear", p.clone()),
        "rampmf" => ("Ramp", p.clone()),
        "rectmf" => ("Rectangle", p.clone()),
        "concavemf" => ("Concave", p.clone()),
        "cosinemf" => ("Cosine", p.clone()),
        "spikemf" => ("Spike", p.clone()),
        "discretemf" => ("Discrete", p.clone()),
        other => {
            return Err(error(
                line,
                format!("term {name}: membership function {other:?} is not supported"),
            ))
        }
    };
    let shape = Shape::from_fll(fll_kind, &fll_params)
        .map_err(|e| error(line, format!("term {name}: {e}")))?;
    Ok(Term { name, shape })
}

/// A rule code's hedges and term index (0-based, `None` for `any`).
type Coded = (Vec<Hedge>, Option<usize>);

/// The hedges and the term of a rule code; `None` for 0 (the variable is not named).
fn code(line: usize, text: &str, terms: usize) -> Result<Option<Coded>, FuzzyError> {
    let value = number(line, text, "rule code")?;
    if !value.is_finite() {
        return Err(error(
            line,
            format!("a rule code is a number, got {text:?}"),
        ));
    }
    if value.abs() < FUZZYLITE_EPSILON {
        return Ok(None);
    }
    let whole = value.abs().floor();
    let fraction = value.abs() - whole;
    let mut hedges = Vec::new();
    if value < 0.0 {
        hedges.push(Hedge::Not);
    }
    if fraction.abs() >= FUZZYLITE_EPSILON {
        let (_, named) = HEDGE_CODES
            .iter()
            .find(|(f, _)| (fraction - f).abs() < FUZZYLITE_EPSILON)
            .ok_or_else(|| error(line, format!("no hedge has the code {text:?}")))?;
        hedges.extend_from_slice(named);
    }
    if hedges.last() == Some(&Hedge::Any) {
        return Ok(Some((hedges, None)));
    }
    if whole < 1.0 || whole > terms as f64 {
        return Err(error(
            line,
            format!("code {text} names term {whole}, but the variable has {terms} terms"),
        ));
    }
    Ok(Some((hedges, Some(whole as usize - 1))))
}

/// One `[Rules]` line.
fn rule(
    line: usize,
    text: &str,
    inputs: &[InputVariable],
    outputs: &[OutputVariable],
) -> Result<Rule, FuzzyError> {
    let fail = |m: String| error(line, format!("{m} in rule {text:?}"));
    let shape = || fail("a rule is \"i₁ i₂ …, o₁ o₂ … (weight) : 1 or 2\"".into());
    let (left, rest) = text.split_once(',').ok_or_else(shape)?;
    let (middle, connective) = rest.split_once(':').ok_or_else(shape)?;
    let (outputs_text, weight_text) = middle.split_once('(').ok_or_else(shape)?;
    let weight_text = weight_text.trim().strip_suffix(')').ok_or_else(shape)?;
    let weight = number(line, weight_text, "rule weight")?;
    let in_codes: Vec<&str> = left.split_whitespace().collect();
    let out_codes: Vec<&str> = outputs_text.split_whitespace().collect();
    if in_codes.len() != inputs.len() || out_codes.len() != outputs.len() {
        return Err(fail(format!(
            "{} input and {} output codes, the engine has {} inputs and {} outputs",
            in_codes.len(),
            out_codes.len(),
            inputs.len(),
            outputs.len()
        )));
    }
    let mut propositions = Vec::new();
    for (v, (c, var)) in in_codes.iter().zip(inputs).enumerate() {
        if let Some((hedges, term)) = code(line, c, var.terms.len())? {
            propositions.push(Antecedent::Is(Proposition {
                variable: VariableRef::Input(v),
                hedges,
                term,
            }));
        }
    }
    let join: fn(Box<Antecedent>, Box<Antecedent>) -> Antecedent = match connective.trim() {
        "1" => Antecedent::And,
        "2" => Antecedent::Or,
        other => {
            return Err(fail(format!(
                "the connective is 1 (and) or 2 (or), got {other:?}"
            )))
        }
    };
    let mut parts = propositions.into_iter();
    let first = parts
        .next()
        .ok_or_else(|| fail("no input is named (every code is 0)".into()))?;
    let antecedent = parts.fold(first, |l, r| join(Box::new(l), Box::new(r)));
    let mut consequents = Vec::new();
    for (o, (c, var)) in out_codes.iter().zip(outputs).enumerate() {
        if let Some((hedges, term)) = code(line, c, var.terms.len())? {
            let term = term.ok_or_else(|| fail("\"any\" cannot conclude a rule".into()))?;
            consequents.push(Conclusion {
                output: o,
                hedges,
                term,
            });
        }
    }
    if consequents.is_empty() {
        return Err(fail("no output is named (every code is 0)".into()));
    }
    Ok(Rule {
        antecedent,
        consequents,
        weight,
    })
}

/// The FIS code of a term with hedges, or why there is none.
fn encode(hedges: &[Hedge], term: Option<usize>) -> Result<String, String> {
    let (negated, rest) = match hedges.split_first() {
        Some((Hedge::Not, rest)) => (true, rest),
        _ => (false, hedges),
    };
    let fraction = if rest.is_empty() {
        0.0
    } else {
        HEDGE_CODES
            .iter()
            .find(|(_, named)| *named == rest)
            .map(|(f, _)| *f)
            .ok_or_else(|| {
                let words: Vec<&str> = hedges.iter().map(|h| h.name()).collect();
                format!("FIS has no code for the hedges \"{}\"", words.join(" "))
            })?
    };
    let whole = term.map_or(0.0, |t| (t + 1) as f64);
    let value = whole + fraction;
    Ok(float(if negated { -value } else { value }))
}

/// The FIS membership function of a term: its type and parameters in MATLAB's order.
fn mf(shape: &Shape) -> (String, String) {
    let p = shape.parameters();
    let join = |v: &[f64]| v.iter().map(|x| float(*x)).collect::<Vec<_>>().join(" ");
    let (kind, params) = match shape {
        Shape::Triangle { .. } => ("trimf", join(&p)),
        Shape::Trapezoid { .. } => ("trapmf", join(&p)),
        Shape::Gaussian { .. } => ("gaussmf", join(&[p[1], p[0]])),
        Shape::GaussianProduct { .. } => ("gauss2mf", join(&[p[1], p[0], p[3], p[2]])),
        Shape::Bell { .. } => ("gbellmf", join(&[p[1], p[2], p[0]])),
        Shape::Sigmoid { .. } => ("sigmf", join(&[p[1], p[0]])),
        Shape::SigmoidDifference { .. } => ("dsigmf", join(&[p[1], p[0], p[2], p[3]])),
        Shape::SigmoidProduct { .. } => ("psigmf", join(&[p[1], p[0], p[2], p[3]])),
        Shape::ZShape { .. } => ("zmf", join(&p)),
        Shape::SShape { .. } => ("smf", join(&p)),
        Shape::PiShape { .. } => ("pimf", join(&p)),
        Shape::Constant { .. } => ("constant", join(&p)),
        Shape::Linear { .. } => ("linear", join(&p)),
        Shape::Ramp { .. } => ("rampmf", join(&p)),
        Shape::Rectangle { .. } => ("rectmf", join(&p)),
        Shape::Concave { .. } => ("concavemf", join(&p)),
        Shape::Cosine { .. } => ("cosinemf", join(&p)),
        Shape::Spike { .. } => ("spikemf", join(&p)),
        Shape::Discrete { .. } => ("discretemf", join(&p)),
        Shape::Function(f) => ("function", f.text().to_string()),
    };
    (kind.to_string(), params)
}

/// Writes `engine` as a FIS file, or says what FIS cannot express (see the module's
/// documentation). MATLAB reads the standard parts; fuzzylite reads all of it.
pub fn write(engine: &Engine) -> Result<String, FuzzyError> {
    let cannot = |m: String| FuzzyError::new(format!("FIS cannot express this engine: {m}"));
    let blocks: Vec<(&str, Operators, &[Rule])> = engine.rule_blocks().collect();
    let [(_, operators, rules)] = blocks[..] else {
        return Err(cannot(format!(
            "it has {} rule blocks, FIS has one",
            blocks.len()
        )));
    };
    let first = &engine.outputs()[0];
    for v in engine.outputs() {
        if (v.defuzzifier, v.aggregation) != (first.defuzzifier, first.aggregation) {
            return Err(cannot(format!(
                "outputs {} and {} differ in defuzzifier or aggregation, FIS has one for all",
                first.name, v.name
            )));
        }
        // FIS has no type: it reads back as Automatic, which means the same when the terms
        // leave Automatic no other choice.
        let same_as_automatic = match v.weighted_kind {
            WeightedKind::Automatic => true,
            WeightedKind::TakagiSugeno => v.terms.iter().all(|t| t.shape.is_takagi_sugeno()),
            WeightedKind::Tsukamoto => v.terms.iter().all(|t| t.shape.is_monotonic()),
        };
        if !v.defuzzifier.is_integral() && !same_as_automatic {
            return Err(cannot(format!(
                "output {}: FIS has no {} type for a weighted defuzzifier",
                v.name,
                v.weighted_kind.name()
            )));
        }
    }
    if let Some(v) = engine.inputs().iter().find(|v| v.lock_range) {
        return Err(cannot(format!(
            "input {} locks its range (a value outside it is taken at its nearest end), which \
             FIS cannot say; write it as FLL",
            v.name
        )));
    }
    let t = |n: Option<Norm>| {
        n.map_or(String::new(), |n| {
            T_NORMS
                .iter()
                .find(|(_, x)| *x == n)
                .map_or(String::new(), |(name, _)| (*name).to_string())
        })
    };
    let s = |n: Option<SNorm>| {
        n.map_or(String::new(), |n| {
            S_NORMS
                .iter()
                .find(|(_, x)| *x == n)
                .map_or(String::new(), |(name, _)| (*name).to_string())
        })
    };
    let defuzz = DEFUZZIFIERS
        .iter()
        .find(|(_, d)| *d == first.defuzzifier)
        .map_or("centroid", |(n, _)| n);
    let sugeno = engine
        .outputs()
        .iter()
        .all(|v| v.terms.iter().all(|t| t.shape.is_takagi_sugeno()));
    let mut out = String::new();
    let _ = writeln!(out, "[System]");
    let _ = writeln!(out, "Name='{}'", engine.name);
    let _ = writeln!(out, "Type='{}'", if sugeno { "sugeno" } else { "mamdani" });
    let _ = writeln!(out, "Version=2.0");
    let _ = writeln!(out, "NumInputs={}", engine.inputs().len());
    let _ = writeln!(out, "NumOutputs={}", engine.outputs().len());
    let _ = writeln!(out, "NumRules={}", rules.len());
    let _ = writeln!(out, "AndMethod='{}'", t(operators.conjunction));
    let _ = writeln!(out, "OrMethod='{}'", s(operators.disjunction));
    let _ = writeln!(out, "ImpMethod='{}'", t(operators.implication));
    let _ = writeln!(out, "AggMethod='{}'", s(first.aggregation));
    let _ = writeln!(out, "DefuzzMethod='{defuzz}'");
    let terms = |out: &mut String, terms: &[Term]| {
        let _ = writeln!(out, "NumMFs={}", terms.len());
        for (k, term) in terms.iter().enumerate() {
            let (kind, params) = mf(&term.shape);
            let _ = writeln!(out, "MF{}='{}':'{kind}',[{params}]", k + 1, term.name);
        }
    };
    for (i, v) in engine.inputs().iter().enumerate() {
        let _ = writeln!(out, "\n[Input{}]", i + 1);
        let _ = writeln!(out, "Name='{}'", v.name);
        let _ = writeln!(out, "Range=[{} {}]", float(v.min), float(v.max));
        terms(&mut out, &v.terms);
    }
    for (o, v) in engine.outputs().iter().enumerate() {
        let _ = writeln!(out, "\n[Output{}]", o + 1);
        let _ = writeln!(out, "Name='{}'", v.name);
        let _ = writeln!(out, "Range=[{} {}]", float(v.min), float(v.max));
        let _ = writeln!(out, "Default={}", float(v.default_value));
        let _ = writeln!(out, "LockPrevious={}", u8::from(v.lock_previous));
        let _ = writeln!(out, "LockRange={}", u8::from(v.lock_range));
        terms(&mut out, &v.terms);
    }
    let _ = writeln!(out, "\n[Rules]");
    for (index, r) in rules.iter().enumerate() {
        let number = index + 1;
        let mut codes = vec![String::from("0"); engine.inputs().len()];
        let mut connective = None;
        let mut stack = vec![&r.antecedent];
        while let Some(a) = stack.pop() {
            let (joined, l, rr) = match a {
                Antecedent::Is(p) => {
                    let VariableRef::Input(v) = p.variable else {
                        return Err(cannot(format!(
                            "rule {number} names an output in its condition"
                        )));
                    };
                    if codes[v] != "0" {
                        return Err(cannot(format!("rule {number} names an input twice")));
                    }
                    codes[v] = encode(&p.hedges, p.term)
                        .map_err(|m| cannot(format!("rule {number}: {m}")))?;
                    continue;
                }
                Antecedent::And(l, r) => (1, l, r),
                Antecedent::Or(l, r) => (2, l, r),
            };
            if connective.is_some_and(|c| c != joined) {
                return Err(cannot(format!("rule {number} mixes \"and\" and \"or\"")));
            }
            connective = Some(joined);
            stack.push(rr);
            stack.push(l);
        }
        let mut out_codes = vec![String::from("0"); engine.outputs().len()];
        for c in &r.consequents {
            if out_codes[c.output] != "0" {
                return Err(cannot(format!(
                    "rule {number} concludes on an output twice"
                )));
            }
            out_codes[c.output] = encode(&c.hedges, Some(c.term))
                .map_err(|m| cannot(format!("rule {number}: {m}")))?;
        }
        let _ = writeln!(
            out,
            "{}, {} ({}) : {}",
            codes.join(" "),
            out_codes.join(" "),
            float(r.weight),
            connective.unwrap_or(1)
        );
    }
    Ok(out)
}
