//! fuzzylite's FLL format, read and written: fuzzylite 6's whole language.
//!
//! `Engine:`, `InputVariable:` and `OutputVariable:` with `enabled`, `range`, `lock-range` and
//! `term:` lines (every shape of [`Shape`], Function formulas of [`super::function`]), the
//! output's `aggregation:` (any S-norm or `none`), `defuzzifier:` (Centroid, Bisector,
//! SmallestOfMaximum, LargestOfMaximum, MeanOfMaximum with a resolution; WeightedAverage,
//! WeightedSum with a type Automatic, TakagiSugeno or Tsukamoto), `default:` and `lock-previous:`,
//! and any number of `RuleBlock:`s with `conjunction` (any T-norm or `none`), `disjunction` (any
//! S-norm or `none`), `implication` (any T-norm or `none`), `activation: General` and `rule: if
//! … then … [with w]` lines: `and`, `or` (looser than `and`), parentheses, hedges `not seldom
//! somewhat very extremely any`, output variables in conditions (chained engines), several
//! conclusions with hedges. `description:` lines and `#` comments are skipped. Engines read here
//! fire a rule above fuzzylite's activation threshold ([`FUZZYLITE_EPSILON`]).
//!
//! Not supported, each an error naming the line: disabled variables or rule blocks, activation
//! methods other than General, terms of a height other than 1, a missing defuzzifier; and an
//! engine without a single rule (fuzzylite loads one, but it holds its outputs at their defaults
//! whatever the inputs: a controller running it would silently hold the feed). Nothing is
//! silently dropped: an engine that loads here evaluates as written.

use std::collections::{HashMap, HashSet};
use std::fmt::Write as _;

use super::engine::{
    Antecedent, Conclusion, Defuzzifier, Engine, Hedge, InputVariable, Norm, Operators,
    OutputVariable, Proposition, Rule, RuleBlock, SNorm, Term, VariableRef, WeightedKind,
    DEFAULT_RESOLUTION, FUZZYLITE_EPSILON, NO_RULES_WHY,
};
use super::function::{Formula, Var};
use super::membership::Shape;
use super::FuzzyError;

fn error(line: usize, message: impl AsRef<str>) -> FuzzyError {
    FuzzyError::new(format!("line {line}: {}", message.as_ref()))
}

pub(crate) fn number(line: usize, text: &str, what: &str) -> Result<f64, FuzzyError> {
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
    Rules(usize),
}

/// A rule block as read: its operators and its rule lines.
struct BlockText {
    /// The line of its `RuleBlock:`.
    line: usize,
    name: String,
    operators: Operators,
    rules: Vec<(usize, String)>,
}

/// A Function term waiting for every variable to be known: (line, output?, variable, term,
/// formula).
type PendingFormula = (usize, bool, usize, usize, String);

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
/// assert!(parse("Engine: x\nInputVariable: E\n  term: A Gaussian 0 0\n").unwrap_err()
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
    let mut blocks: Vec<BlockText> = Vec::new();
    let mut pending: Vec<PendingFormula> = Vec::new();
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
                    aggregation: Some(SNorm::Maximum),
                    resolution: DEFAULT_RESOLUTION,
                    weighted_kind: WeightedKind::Automatic,
                });
                section = Section::Output(outputs.len() - 1);
                continue;
            }
            "RuleBlock" => {
                blocks.push(BlockText {
                    line: line_no,
                    name: value.to_string(),
                    operators: Operators {
                        conjunction: Some(Norm::Minimum),
                        disjunction: Some(SNorm::Maximum),
                        implication: Some(Norm::Minimum),
                    },
                    rules: Vec::new(),
                });
                section = Section::Rules(blocks.len() - 1);
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
                    "term" => {
                        let at = (false, i, v.terms.len());
                        add_term(line_no, value, &v.name, &mut v.terms, &mut term_names)?;
                        note_formula(line_no, value, at, &mut pending);
                    }
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
                    "aggregation" => v.aggregation = s_norm(line_no, value, key)?,
                    "defuzzifier" => {
                        (v.defuzzifier, v.resolution, v.weighted_kind) =
                            defuzzifier(line_no, value)?;
                    }
                    "default" => v.default_value = number(line_no, value, "default")?,
                    "lock-previous" => v.lock_previous = boolean(line_no, value, key)?,
                    "term" => {
                        let at = (true, o, v.terms.len());
                        add_term(line_no, value, &v.name, &mut v.terms, &mut term_names)?;
                        note_formula(line_no, value, at, &mut pending);
                    }
                    _ => {
                        return Err(error(
                            line_no,
                            format!("unknown output-variable key {key:?}"),
                        ))
                    }
                }
            }
            Section::Rules(b) => {
                let block = &mut blocks[b];
                match key {
                    "enabled" => {
                        if !boolean(line_no, value, key)? {
                            return Err(error(line_no, "a disabled rule block is not supported"));
                        }
                    }
                    "conjunction" => block.operators.conjunction = t_norm(line_no, value, key)?,
                    "disjunction" => block.operators.disjunction = s_norm(line_no, value, key)?,
                    "implication" => block.operators.implication = t_norm(line_no, value, key)?,
                    "activation" => {
                        if value != "General" && !value.is_empty() && value != "none" {
                            return Err(error(
                                line_no,
                                format!("activation {value:?} is not supported (only General)"),
                            ));
                        }
                    }
                    "rule" => block.rules.push((line_no, value.to_string())),
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
    resolve_formulas(&pending, &mut inputs, &mut outputs)?;
    // Checked after the engine builds, so a missing variable is named first.
    let no_rules = refuse_no_rules(&blocks);
    let names = Names::of(&inputs, &outputs);
    let blocks = blocks
        .into_iter()
        .map(|b| {
            let rules = b
                .rules
                .iter()
                .map(|(line_no, text)| rule(*line_no, text, &names))
                .collect::<Result<Vec<_>, _>>()?;
            Ok(RuleBlock {
                name: b.name,
                operators: b.operators,
                rules,
            })
        })
        .collect::<Result<Vec<_>, FuzzyError>>()?;
    let engine = Engine::with_blocks(name, inputs, outputs, blocks, FUZZYLITE_EPSILON)?;
    no_rules.map(|()| engine)
}

/// An engine without a single rule is refused: every output would hold its default whatever the
/// inputs, so a controller running it would output nothing and a feed would stay fixed without a
/// word (fuzzylite loads such a file; nothing useful evaluates it). A rule block left empty
/// beside one with rules adds nothing and is kept, as written.
fn refuse_no_rules(blocks: &[BlockText]) -> Result<(), FuzzyError> {
    let why = format!("{NO_RULES_WHY}; add \"rule: if … then …\" lines");
    if blocks.iter().any(|b| !b.rules.is_empty()) {
        return Ok(());
    }
    Err(match blocks {
        [] => FuzzyError::new(format!("the engine has no RuleBlock: {why}")),
        [block] => error(
            block.line,
            format!("the rule block {:?} is empty: {why}", block.name),
        ),
        [first, ..] => error(
            first.line,
            format!("every rule block is empty ({} blocks): {why}", blocks.len()),
        ),
    })
}

/// Remembers a Function term for [`resolve_formulas`], which parses it once every variable is
/// known (a formula may name a variable declared after it).
fn note_formula(
    line_no: usize,
    value: &str,
    (output, variable, term): (bool, usize, usize),
    pending: &mut Vec<PendingFormula>,
) {
    let mut words = value.split_whitespace();
    let _name = words.next();
    if words.next() == Some("Function") {
        let formula = words.collect::<Vec<_>>().join(" ");
        pending.push((line_no, output, variable, term, formula));
    }
}

/// What a name in a formula means: an input or an output of these variables.
pub(crate) fn formula_names<'a>(
    inputs: &'a [InputVariable],
    outputs: &'a [OutputVariable],
) -> impl Fn(&str) -> Option<Var> + 'a {
    move |name: &str| {
        inputs
            .iter()
            .position(|v| v.name == name)
            .map(Var::Input)
            .or_else(|| outputs.iter().position(|v| v.name == name).map(Var::Output))
    }
}

/// Parses every pending Function formula now that every variable is known.
fn resolve_formulas(
    pending: &[PendingFormula],
    inputs: &mut [InputVariable],
    outputs: &mut [OutputVariable],
) -> Result<(), FuzzyError> {
    for (line_no, output, variable, term, text) in pending {
        let formula = Formula::parse(text, formula_names(inputs, outputs))
            .map_err(|e| error(*line_no, e.to_string()))?;
        let terms = if *output {
            outputs.get_mut(*variable).map(|v| &mut v.terms)
        } else {
            inputs.get_mut(*variable).map(|v| &mut v.terms)
        };
        if let Some(t) = terms.and_then(|terms| terms.get_mut(*term)) {
            t.shape = Shape::Function(formula);
        }
    }
    Ok(())
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
    if name.is_empty() || name.contains(char::is_whitespace) {
        return Err(error(
            line_no,
            format!("a variable's name is one word, got {name:?}"),
        ));
    }
    if !names.insert(name.to_string()) {
        return Err(error(
            line_no,
            format!("a variable named {name} already exists"),
        ));
    }
    Ok(())
}

/// A term; a Function's shape is a placeholder until [`resolve_formulas`].
fn term(line: usize, value: &str) -> Result<Term, FuzzyError> {
    let parts: Vec<&str> = value.split_whitespace().collect();
    let Some((&name, rest)) = parts.split_first() else {
        return Err(error(line, "a term needs a name and a shape"));
    };
    let Some((&kind, params)) = rest.split_first() else {
        return Err(error(line, format!("term {name} has no shape")));
    };
    if kind == "Function" {
        return Ok(Term {
            name: name.to_string(),
            shape: Shape::Constant { value: 0.0 },
        });
    }
    let values = params
        .iter()
        .map(|p| number(line, p, "term parameter"))
        .collect::<Result<Vec<f64>, _>>()?;
    let shape =
        Shape::from_fll(kind, &values).map_err(|e| error(line, format!("term {name}: {e}")))?;
    Ok(Term {
        name: name.to_string(),
        shape,
    })
}

fn t_norm(line: usize, value: &str, key: &str) -> Result<Option<Norm>, FuzzyError> {
    if matches!(value, "none" | "") {
        return Ok(None);
    }
    Norm::from_name(value).map(Some).ok_or_else(|| {
        let names: Vec<&str> = Norm::ALL.iter().map(|n| n.name()).collect();
        error(
            line,
            format!(
                "{key} {value:?} is not a T-norm ({} or none)",
                names.join(", ")
            ),
        )
    })
}

fn s_norm(line: usize, value: &str, key: &str) -> Result<Option<SNorm>, FuzzyError> {
    if matches!(value, "none" | "") {
        return Ok(None);
    }
    SNorm::from_name(value).map(Some).ok_or_else(|| {
        let names: Vec<&str> = SNorm::ALL.iter().map(|n| n.name()).collect();
        error(
            line,
            format!(
                "{key} {value:?} is not an S-norm ({} or none)",
                names.join(", ")
            ),
        )
    })
}

fn defuzzifier(line: usize, value: &str) -> Result<(Defuzzifier, usize, WeightedKind), FuzzyError> {
    let mut words = value.split_whitespace();
    let kind = words.next().unwrap_or_default();
    let defuzzifier = Defuzzifier::from_name(kind).ok_or_else(|| {
        let names: Vec<&str> = Defuzzifier::ALL.iter().map(|d| d.name()).collect();
        error(
            line,
            format!(
                "defuzzifier {kind:?} is not supported ({})",
                names.join(", ")
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
    if !defuzzifier.is_integral() {
        let weighted = match parameter {
            None => WeightedKind::Automatic,
            Some(p) => WeightedKind::ALL
                .into_iter()
                .find(|k| k.name() == p)
                .ok_or_else(|| {
                    error(
                        line,
                        format!("{kind} {p:?}: the type is Automatic, TakagiSugeno or Tsukamoto"),
                    )
                })?,
        };
        return Ok((defuzzifier, DEFAULT_RESOLUTION, weighted));
    }
    let resolution = match parameter {
        None => DEFAULT_RESOLUTION,
        // A value fuzzylite would refuse (0, negative, NaN, not whole) is a mistake to say.
        Some(r) => match r.parse::<usize>() {
            Ok(r) if r >= 1 => r,
            _ => {
                return Err(error(
                    line,
                    format!(
                        "{kind}: the resolution must be a whole number of at least 1 \
                         (fuzzylite's default is 100), got {r:?}"
                    ),
                ))
            }
        },
    };
    Ok((defuzzifier, resolution, WeightedKind::Automatic))
}

/// Each variable's reference and its terms' indices by name, built once so that every
/// proposition of every rule is found in constant time (a list of every variable's terms built
/// per proposition made rules × terms work and allocation).
pub(crate) struct Names<'a>(HashMap<&'a str, (VariableRef, HashMap<&'a str, usize>)>);

impl<'a> Names<'a> {
    pub(crate) fn of(inputs: &'a [InputVariable], outputs: &'a [OutputVariable]) -> Self {
        let terms = |terms: &'a [Term]| {
            terms
                .iter()
                .enumerate()
                .map(|(t, term)| (term.name.as_str(), t))
                .collect::<HashMap<_, _>>()
        };
        let mut map = HashMap::new();
        for (v, var) in inputs.iter().enumerate() {
            map.insert(
                var.name.as_str(),
                (VariableRef::Input(v), terms(&var.terms)),
            );
        }
        for (v, var) in outputs.iter().enumerate() {
            map.insert(
                var.name.as_str(),
                (VariableRef::Output(v), terms(&var.terms)),
            );
        }
        Self(map)
    }
}

/// The most propositions a rule may hold: its condition is a tree that evaluation recurses over.
pub const MAX_PROPOSITIONS: usize = 1000;

/// A recursive-descent reader of a rule's condition: `or` of `and`s of propositions or
/// parenthesised conditions.
struct Condition<'a, 'n> {
    words: &'a [&'a str],
    at: usize,
    names: &'a Names<'n>,
    propositions: usize,
}

impl Condition<'_, '_> {
    fn peek(&self) -> Option<&str> {
        self.words.get(self.at).copied()
    }

    fn or(&mut self, depth: usize) -> Result<Antecedent, String> {
        if depth > super::function::MAX_DEPTH {
            return Err(format!(
                "parentheses nested deeper than {}",
                super::function::MAX_DEPTH
            ));
        }
        let mut left = self.and(depth)?;
        while self.peek() == Some("or") {
            self.at += 1;
            let right = self.and(depth)?;
            left = Antecedent::Or(Box::new(left), Box::new(right));
        }
        Ok(left)
    }

    fn and(&mut self, depth: usize) -> Result<Antecedent, String> {
        let mut left = self.factor(depth)?;
        while self.peek() == Some("and") {
            self.at += 1;
            let right = self.factor(depth)?;
            left = Antecedent::And(Box::new(left), Box::new(right));
        }
        Ok(left)
    }

    fn factor(&mut self, depth: usize) -> Result<Antecedent, String> {
        if self.peek() == Some("(") {
            self.at += 1;
            let inner = self.or(depth + 1)?;
            if self.peek() != Some(")") {
                return Err("a \"(\" is not closed".into());
            }
            self.at += 1;
            return Ok(inner);
        }
        self.propositions += 1;
        if self.propositions > MAX_PROPOSITIONS {
            return Err(format!("more than {MAX_PROPOSITIONS} propositions"));
        }
        let (variable, hedges, term) = proposition(self.words, &mut self.at, self.names, true)?;
        Ok(Antecedent::Is(Proposition {
            variable,
            hedges,
            term,
        }))
    }
}

/// `X is h₁ … T` from `words` at `at`: the variable, the hedges and the term (none after `any`
/// when `any_allowed`).
fn proposition(
    words: &[&str],
    at: &mut usize,
    names: &Names,
    any_allowed: bool,
) -> Result<(VariableRef, Vec<Hedge>, Option<usize>), String> {
    let var = words
        .get(*at)
        .ok_or_else(|| "a proposition is missing".to_string())?;
    let (variable, terms) = names
        .0
        .get(var)
        .ok_or_else(|| format!("unknown variable {var:?}"))?;
    *at += 1;
    if words.get(*at) != Some(&"is") {
        return Err(format!("expected \"is\" after {var}"));
    }
    *at += 1;
    let mut hedges = Vec::new();
    loop {
        let word = words
            .get(*at)
            .ok_or_else(|| format!("{var} is … needs a term"))?;
        *at += 1;
        if let Some(h) = Hedge::from_name(word) {
            hedges.push(h);
            if h == Hedge::Any {
                if any_allowed {
                    return Ok((*variable, hedges, None));
                }
                return Err("\"any\" cannot conclude a rule".into());
            }
            continue;
        }
        let t = terms
            .get(word)
            .ok_or_else(|| format!("unknown term {word:?} of {var}"))?;
        return Ok((*variable, hedges, Some(*t)));
    }
}

/// Parses a rule's text (after `rule:`) against the engine's variables.
pub(crate) fn rule(line: usize, text: &str, names: &Names) -> Result<Rule, FuzzyError> {
    let fail = |m: String| error(line, format!("{m} in rule {text:?}"));
    let spaced = text.replace('(', " ( ").replace(')', " ) ");
    let words: Vec<&str> = spaced.split_whitespace().collect();
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
    let condition_words = &words[1..then];
    if condition_words.is_empty() {
        return Err(fail("the condition is empty".into()));
    }
    let mut condition = Condition {
        words: condition_words,
        at: 0,
        names,
        propositions: 0,
    };
    let antecedent = condition.or(0).map_err(&fail)?;
    if let Some(extra) = condition.peek() {
        return Err(fail(format!("unexpected {extra:?} in the condition")));
    }
    let mut consequents = Vec::new();
    let mut at = 0;
    loop {
        let (variable, hedges, term) =
            proposition(consequent_words, &mut at, names, false).map_err(&fail)?;
        let (VariableRef::Output(output), Some(term)) = (variable, term) else {
            return Err(fail("a conclusion names an output variable".into()));
        };
        consequents.push(Conclusion {
            output,
            hedges,
            term,
        });
        match consequent_words.get(at) {
            None => break,
            Some(&"and") => at += 1,
            Some(other) => return Err(fail(format!("expected \"and\", found {other:?}"))),
        }
        if consequents.len() > MAX_PROPOSITIONS {
            return Err(fail(format!("more than {MAX_PROPOSITIONS} conclusions")));
        }
    }
    Ok(Rule {
        antecedent,
        consequents,
        weight,
    })
}

/// A number as FLL and FIS write it: as Rust prints it (the shortest that reads back), `nan` for
/// NaN.
pub(crate) fn float(v: f64) -> String {
    if v.is_nan() {
        "nan".into()
    } else {
        format!("{v}")
    }
}

/// The engine's name in FLL text that [`write()`] wrote (its first line), read without parsing
/// the rest: what names a kept engine in a list of runs.
///
/// ```
/// use cutlab::control::fuzzy::engine::Defuzzifier;
/// use cutlab::control::fuzzy::fll::{write, written_name};
/// use cutlab::control::fuzzy::rules::{paper_002_engine, RuleBase};
/// let engine = paper_002_engine(&RuleBase::Dynamics.table(), Defuzzifier::Centroid).unwrap();
/// assert_eq!(written_name(&write(&engine)), Some("paper002"));
/// assert_eq!(written_name("InputVariable: E"), None);
/// ```
pub fn written_name(text: &str) -> Option<&str> {
    text.lines().next()?.strip_prefix("Engine:").map(str::trim)
}

/// Writes `engine` as FLL that fuzzylite 6 loads. Integral defuzzifiers are written with their
/// resolution (cutlab's exact paths ignore it; raise it in fuzzylite to approach cutlab's exact
/// values).
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
        let _ = writeln!(
            out,
            "  aggregation: {}",
            v.aggregation.map_or("none", |a| a.name())
        );
        let parameter = if v.defuzzifier.is_integral() {
            v.resolution.to_string()
        } else {
            v.weighted_kind.name().to_string()
        };
        let _ = writeln!(out, "  defuzzifier: {} {parameter}", v.defuzzifier.name());
        let _ = writeln!(out, "  default: {}", float(v.default_value));
        let _ = writeln!(out, "  lock-previous: {}", v.lock_previous);
        for t in &v.terms {
            let _ = writeln!(out, "  term: {} {}", t.name, t.shape);
        }
    }
    let mut index = 0;
    for (name, operators, rules) in engine.rule_blocks() {
        let t = |n: Option<Norm>| n.map_or("none", |n| n.name());
        let _ = writeln!(
            out,
            "RuleBlock: {}",
            if name.is_empty() { "rules" } else { name }
        );
        let _ = writeln!(out, "  enabled: true");
        let _ = writeln!(out, "  conjunction: {}", t(operators.conjunction));
        let _ = writeln!(
            out,
            "  disjunction: {}",
            operators.disjunction.map_or("none", |n| n.name())
        );
        let _ = writeln!(out, "  implication: {}", t(operators.implication));
        let _ = writeln!(out, "  activation: General");
        for _ in rules {
            let _ = writeln!(out, "  rule: {}", engine.rule_text(index));
            index += 1;
        }
    }
    out
}

/// FLL text as a URL query value that percent-encoding leaves nearly as long: a space becomes
/// `_`, a line break `~`, a colon `*`, and `!` escapes those four characters where the text has
/// them (`!_`, `!~`, `!*`, `!!`). `encodeURIComponent` keeps all four as they are, so a written
/// engine (letters, digits, `.-:()`, spaces and line breaks) costs one character a character
/// instead of three for each space, colon and line break. [`from_url_text`] reverses it.
///
/// ```
/// use cutlab::control::fuzzy::fll::{from_url_text, to_url_text};
/// let text = "Engine: a_b\n  range: -6 6\n# ~!*\n";
/// assert_eq!(to_url_text(text), "Engine*_a!_b~__range*_-6_6~#_!~!!!*~");
/// assert_eq!(from_url_text(&to_url_text(text)), text);
/// ```
pub fn to_url_text(fll_text: &str) -> String {
    let mut out = String::with_capacity(fll_text.len());
    for c in fll_text.chars() {
        match c {
            '!' | '_' | '~' | '*' => {
                out.push('!');
                out.push(c);
            }
            ' ' => out.push('_'),
            '\n' => out.push('~'),
            ':' => out.push('*'),
            c => out.push(c),
        }
    }
    out
}

/// The FLL text of [`to_url_text`]'s value (a `!` at the end, escaping nothing, is kept).
pub fn from_url_text(url_text: &str) -> String {
    let mut out = String::with_capacity(url_text.len());
    let mut chars = url_text.chars();
    while let Some(c) = chars.next() {
        match c {
            '!' => out.push(chars.next().unwrap_or('!')),
            '_' => out.push(' '),
            '~' => out.push('\n'),
            '*' => out.push(':'),
            c => out.push(c),
        }
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
                "rule: if (E is NB or EC is NB then U is NB",
                "a \"(\" is not closed",
            ),
            (
                "rule: if E is NB and EC is NB then U is NB",
                "rule: if E is very then U is NB",
                "E is … needs a term",
            ),
            (
                "aggregation: Maximum",
                "aggregation: Sum",
                "aggregation \"Sum\" is not an S-norm",
            ),
            (
                "term: NB Triangle -6 -6 -4",
                "term: NB Blob -6 1 2",
                "shape Blob",
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
                "defuzzifier: WeightedAverage Linear",
                "the type is Automatic, TakagiSugeno or Tsukamoto",
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
