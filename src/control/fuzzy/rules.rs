//! The 7×7 rule tables of paper 002 and the engine they define.
//!
//! Seven triangular sets NB, NM, NS, ZO, PS, PM, PB on the universe [−6, 6], peaks 2 apart, for the
//! error E, its change EC and the output U (paper 002 §4.2). The outer sets are right-angled at the
//! universe's ends (NB = Triangle −6 −6 −4), so a saturated input belongs fully to them.
//!
//! **Experience-based table.** Paper 002 does not print it. cutlab uses the classic diagonal
//! MacVicar-Whelan table: U = sat(E + EC) in levels −3 … 3 (NB … PB), with paper 002's sign
//! convention (E = I_ref − I > 0 means the cut is light, so U > 0 raises the feed). Table 5's
//! first lines, which the paper reports for its experience rules, are flatter near the corners;
//! `docs/fuzzy.md` lists where they differ.
//!
//! **Dynamics-based table (paper 002, Table 4, repaired).** Each printed row has eight entries
//! under seven column labels. Dropping the seventh printed entry of every row (the same spurious
//! column that appears as the stray "21" column of Table 5) is the only single-column repair that
//! makes all seven rows agree with the output levels of Table 5's second lines; `tests/fuzzy.rs`
//! checks the repaired table against Table 5.

use super::engine::{
    Defuzzifier, Engine, InputVariable, Norm, OutputVariable, Rule, SNorm, Term, WeightedKind,
    DEFAULT_RESOLUTION,
};
use super::membership::Shape;
use super::FuzzyError;

/// The seven linguistic levels, NB = −3 … PB = +3.
pub const LEVEL_NAMES: [&str; 7] = ["NB", "NM", "NS", "ZO", "PS", "PM", "PB"];

/// What each of [`LEVEL_NAMES`] stands for, in words.
pub const LEVEL_MEANINGS: [&str; 7] = [
    "negative big",
    "negative medium",
    "negative small",
    "zero",
    "positive small",
    "positive medium",
    "positive big",
];

/// The levels written out, for a reader who has not met the abbreviations:
/// "NB negative big, NM negative medium, …, PB positive big".
///
/// ```
/// let legend = cutlab::control::fuzzy::rules::level_legend();
/// assert!(legend.starts_with("NB negative big, NM negative medium"));
/// assert!(legend.ends_with("PB positive big"));
/// ```
pub fn level_legend() -> String {
    LEVEL_NAMES
        .iter()
        .zip(LEVEL_MEANINGS)
        .map(|(name, meaning)| format!("{name} {meaning}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A 7×7 table: `table[e][ec]` is the output level (−3…3) for E level `e − 3` and EC level
/// `ec − 3`.
pub type RuleTable = [[i8; 7]; 7];

/// The built-in rule bases.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RuleBase {
    /// MacVicar-Whelan diagonal table.
    Experience,
    /// Paper 002's Table 4, repaired.
    Dynamics,
}

/// Paper 002's Table 4 as printed: eight entries per row under seven column labels.
pub const TABLE_4_AS_PRINTED: [[i8; 8]; 7] = [
    [-3, -3, -3, -2, -2, -1, -1, -1],
    [-3, -3, -2, -2, -1, 0, 1, 1],
    [-3, -2, -2, -1, 0, 1, 1, 2],
    [-2, -2, -1, 0, 1, 1, 1, 2],
    [-2, -1, 0, 1, 1, 2, 2, 2],
    [-1, 0, 1, 1, 1, 2, 2, 2],
    [0, 1, 1, 1, 1, 2, 2, 3],
];

/// The printed entry dropped from every row of Table 4 (0-based): the seventh.
pub const TABLE_4_SPURIOUS_COLUMN: usize = 6;

impl RuleBase {
    /// Both built-in tables.
    pub const ALL: [RuleBase; 2] = [RuleBase::Experience, RuleBase::Dynamics];

    /// Name for the command line.
    pub fn name(self) -> &'static str {
        match self {
            RuleBase::Experience => "experience",
            RuleBase::Dynamics => "dynamics",
        }
    }

    /// Human label.
    pub fn label(self) -> &'static str {
        match self {
            RuleBase::Experience => "Experience-based (MacVicar-Whelan)",
            RuleBase::Dynamics => "Dynamics-based (paper 002, Table 4)",
        }
    }

    /// The table.
    ///
    /// ```
    /// use cutlab::control::fuzzy::rules::RuleBase;
    /// let t = RuleBase::Experience.table();
    /// assert_eq!(t[3][3], 0);      // ZO, ZO → ZO
    /// assert_eq!(t[6][6], 3);      // PB, PB → PB
    /// assert_eq!(t[0][6], 0);      // NB, PB → ZO: the diagonal
    /// ```
    pub fn table(self) -> RuleTable {
        let mut t = [[0i8; 7]; 7];
        for (e, row) in t.iter_mut().enumerate() {
            for (ec, cell) in row.iter_mut().enumerate() {
                *cell = match self {
                    RuleBase::Experience => (e as i8 - 3 + ec as i8 - 3).clamp(-3, 3),
                    RuleBase::Dynamics => {
                        let printed = &TABLE_4_AS_PRINTED[e];
                        if ec < TABLE_4_SPURIOUS_COLUMN {
                            printed[ec]
                        } else {
                            printed[ec + 1]
                        }
                    }
                };
            }
        }
        t
    }
}

/// The seven triangular terms on [−6, 6].
pub fn seven_terms() -> Vec<Term> {
    (0..7)
        .map(|i| {
            let peak = 2.0 * (i as f64 - 3.0);
            let shape = Shape::Triangle {
                a: (peak - 2.0).max(-6.0),
                b: peak,
                c: (peak + 2.0).min(6.0),
            };
            Term {
                name: LEVEL_NAMES[i].to_string(),
                shape,
            }
        })
        .collect()
}

/// Paper 002's engine (inputs E and EC, output U, all on [−6, 6]) for a rule table: AND =
/// minimum, implication = minimum, aggregation = maximum. Inputs are clamped to the universe
/// (the controller saturates them anyway); no rule firing gives U = 0.
pub fn paper_002_engine(table: &RuleTable, defuzzifier: Defuzzifier) -> Result<Engine, FuzzyError> {
    let input = |name: &str| InputVariable {
        name: name.into(),
        min: -6.0,
        max: 6.0,
        lock_range: true,
        terms: seven_terms(),
    };
    let output = OutputVariable {
        name: "U".into(),
        min: -6.0,
        max: 6.0,
        lock_range: false,
        terms: seven_terms(),
        defuzzifier,
        default_value: 0.0,
        lock_previous: false,
        aggregation: Some(SNorm::Maximum),
        resolution: DEFAULT_RESOLUTION,
        weighted_kind: WeightedKind::Automatic,
    };
    let rules = (0..7)
        .flat_map(|e| {
            (0..7).filter_map(move |ec| {
                Rule::all_of(
                    &[(0, e), (1, ec)],
                    &[(0, (table[e][ec] + 3).clamp(0, 6) as usize)],
                    1.0,
                )
            })
        })
        .collect();
    Engine::new(
        "paper002",
        vec![input("E"), input("EC")],
        vec![output],
        rules,
        Norm::Minimum,
        Norm::Minimum,
    )
}

/// The rule table of an engine that has paper 002's shape, whatever order its rules come in;
/// `None` for any other engine (a table would misstate it). [`paper_002_table`] says why not.
///
/// ```
/// use cutlab::control::fuzzy::engine::Defuzzifier;
/// use cutlab::control::fuzzy::rules::{paper_002_engine, rule_table_of, RuleBase};
/// let table = RuleBase::Dynamics.table();
/// let engine = paper_002_engine(&table, Defuzzifier::WeightedAverage).unwrap();
/// assert_eq!(rule_table_of(&engine), Some(table));
/// ```
pub fn rule_table_of(engine: &Engine) -> Option<RuleTable> {
    paper_002_table(engine).ok()
}

/// The rule table of `engine` if it is paper 002's engine ([`paper_002_engine`]) with some table,
/// else an error that says what differs. This is how an imported FLL engine comes back to the
/// 7×7 table the lab edits.
///
/// Paper 002's engine has inputs E and EC and one output U, each with [`seven_terms`] on
/// [−6, 6], inputs clamped to their range, output default 0, AND and implication = minimum, and
/// exactly one rule of weight 1 for every (E, EC) pair, naming one U term. The order of the
/// rules, the engine's name and the defuzzifier are not part of a table: an engine that differs
/// only in them evaluates the same under paper 002's engine with the returned table.
///
/// ```
/// use cutlab::control::fuzzy::engine::Defuzzifier;
/// use cutlab::control::fuzzy::fll;
/// use cutlab::control::fuzzy::rules::{paper_002_engine, paper_002_table, RuleBase};
/// let table = RuleBase::Dynamics.table();
/// let text = fll::write(&paper_002_engine(&table, Defuzzifier::Centroid).unwrap());
/// assert_eq!(paper_002_table(&fll::parse(&text).unwrap()), Ok(table));
/// assert_eq!(table[0][6], -1); // E is NB, EC is PB → U is NS
/// let lopsided = text.replacen("range: -6 6", "range: -6 7", 1);
/// let why = paper_002_table(&fll::parse(&lopsided).unwrap()).unwrap_err();
/// assert_eq!(why.to_string(), "input E: range -6 7, paper 002's is -6 6");
/// ```
pub fn paper_002_table(engine: &Engine) -> Result<RuleTable, FuzzyError> {
    let (e, ec, u) = match (engine.inputs(), engine.outputs()) {
        ([e, ec], [u]) if e.name == "E" && ec.name == "EC" && u.name == "U" => (e, ec, u),
        (inputs, outputs) => {
            let names = |names: Vec<&str>| names.join(", ");
            return Err(FuzzyError::new(format!(
                "a 7×7 table needs inputs E and EC and one output U; this engine has inputs [{}] \
                 and outputs [{}]",
                names(inputs.iter().map(|v| v.name.as_str()).collect()),
                names(outputs.iter().map(|v| v.name.as_str()).collect()),
            )));
        }
    };
    // Paper 002's engine itself is the reference for every setting, so the two cannot drift.
    let paper = paper_002_engine(&RuleBase::Experience.table(), u.defuzzifier)?;
    let (paper_e, paper_u) = (&paper.inputs()[0], &paper.outputs()[0]);
    for v in [e, ec] {
        let what = format!("input {}", v.name);
        same_universe(
            &what,
            &v.terms,
            (v.min, v.max),
            &paper_e.terms,
            (paper_e.min, paper_e.max),
        )?;
        if v.lock_range != paper_e.lock_range {
            return Err(FuzzyError::new(format!(
                "{what}: lock-range {}, paper 002's is {}",
                v.lock_range, paper_e.lock_range
            )));
        }
    }
    same_universe(
        "output U",
        &u.terms,
        (u.min, u.max),
        &paper_u.terms,
        (paper_u.min, paper_u.max),
    )?;
    let flags = [
        ("lock-range", u.lock_range, paper_u.lock_range),
        ("lock-previous", u.lock_previous, paper_u.lock_previous),
    ];
    for (key, mine, theirs) in flags {
        if mine != theirs {
            return Err(FuzzyError::new(format!(
                "output U: {key} {mine}, paper 002's is {theirs}"
            )));
        }
    }
    if u.default_value != paper_u.default_value {
        return Err(FuzzyError::new(format!(
            "output U: default {}, paper 002's is {}",
            u.default_value, paper_u.default_value
        )));
    }
    if engine.rule_blocks().count() != 1 {
        return Err(FuzzyError::new(format!(
            "{} rule blocks; paper 002's engine has one",
            engine.rule_blocks().count()
        )));
    }
    if u.aggregation != paper_u.aggregation {
        return Err(FuzzyError::new(format!(
            "output U: aggregation {}, paper 002's is Maximum",
            u.aggregation.map_or("none", |a| a.name())
        )));
    }
    let operators = [
        ("conjunction", engine.conjunction(), paper.conjunction()),
        ("implication", engine.implication(), paper.implication()),
    ];
    for (key, mine, theirs) in operators {
        if mine != theirs {
            let name = |n: Option<Norm>| n.map_or("none", |n| n.name());
            return Err(FuzzyError::new(format!(
                "{key} {}, paper 002's is {}",
                name(mine),
                name(theirs)
            )));
        }
    }
    // Which rule (1-based) filled each cell: a cell filled twice or not at all is no table.
    let mut filled_by = [[0usize; 7]; 7];
    let mut table = [[0i8; 7]; 7];
    for (index, rule) in engine.rules().iter().enumerate() {
        let number = index + 1;
        let Some((antecedents, consequents)) = rule.as_all_of() else {
            return Err(FuzzyError::new(format!(
                "rule {number}: a table cell is \"if E is … and EC is … then U is …\", without \
                 hedges or \"or\""
            )));
        };
        let (&[(0, i), (1, j)] | &[(1, j), (0, i)]) = antecedents.as_slice() else {
            return Err(FuzzyError::new(format!(
                "rule {number}: a table cell needs one E term and one EC term joined by \"and\""
            )));
        };
        let &[(0, t)] = consequents.as_slice() else {
            return Err(FuzzyError::new(format!(
                "rule {number}: a table cell names one U term"
            )));
        };
        if rule.weight != 1.0 {
            return Err(FuzzyError::new(format!(
                "rule {number}: weight {}; a table's rules have weight 1",
                rule.weight
            )));
        }
        // The terms are paper 002's seven (checked above), so every index is a level; the
        // engine checked them against its terms when it was built.
        let level = i8::try_from(t).ok().filter(|t| *t < 7).map(|t| t - 3);
        let cell = filled_by.get_mut(i).and_then(|row| row.get_mut(j));
        let (Some(first), Some(level)) = (cell, level) else {
            return Err(FuzzyError::new(format!(
                "rule {number}: refers to a term that does not exist"
            )));
        };
        if *first != 0 {
            return Err(FuzzyError::new(format!(
                "rules {} and {number} both cover {}",
                *first,
                cell_name(i, j)
            )));
        }
        *first = number;
        table[i][j] = level;
    }
    for (i, row) in filled_by.iter().enumerate() {
        for (j, rule) in row.iter().enumerate() {
            if *rule == 0 {
                return Err(FuzzyError::new(format!(
                    "no rule covers {}",
                    cell_name(i, j)
                )));
            }
        }
    }
    Ok(table)
}
/// "E is NB and EC is PS" for the cell of E level `e` and EC level `ec` (0-based).
fn cell_name(e: usize, ec: usize) -> String {
    let name = |i: usize| LEVEL_NAMES.get(i).copied().unwrap_or("?");
    format!("E is {} and EC is {}", name(e), name(ec))
}

/// An error naming the first way a variable's terms or range differ from paper 002's.
fn same_universe(
    what: &str,
    terms: &[Term],
    range: (f64, f64),
    paper_terms: &[Term],
    paper_range: (f64, f64),
) -> Result<(), FuzzyError> {
    if terms.len() != paper_terms.len() {
        return Err(FuzzyError::new(format!(
            "{what} has {} terms; a 7×7 table needs paper 002's seven ({})",
            terms.len(),
            LEVEL_NAMES.join(" ")
        )));
    }
    if let Some((mine, theirs)) = terms.iter().zip(paper_terms).find(|(a, b)| a != b) {
        return Err(FuzzyError::new(format!(
            "{what}: term {} {}, paper 002's is {} {}",
            mine.name, mine.shape, theirs.name, theirs.shape
        )));
    }
    if range != paper_range {
        return Err(FuzzyError::new(format!(
            "{what}: range {} {}, paper 002's is {} {}",
            range.0, range.1, paper_range.0, paper_range.1
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::fuzzy::fll;

    #[test]
    fn an_exported_engine_comes_back_to_its_table() {
        for base in [RuleBase::Experience, RuleBase::Dynamics] {
            let table = base.table();
            let engine = paper_002_engine(&table, Defuzzifier::Centroid).unwrap();
            let text = fll::write(&engine);
            let imported = fll::parse(&text).unwrap();
            assert_eq!(rule_table_of(&imported), Some(table), "{base:?}");
        }
    }

    #[test]
    fn an_engine_of_another_shape_has_no_table() {
        let table = RuleBase::Dynamics.table();
        let engine = paper_002_engine(&table, Defuzzifier::Centroid).unwrap();
        // A rule missing leaves a hole.
        let mut rules = engine.rules().to_vec();
        rules.pop();
        let holed = Engine::new(
            "holed",
            engine.inputs().to_vec(),
            engine.outputs().to_vec(),
            rules,
            Norm::Minimum,
            Norm::Minimum,
        )
        .unwrap();
        assert_eq!(rule_table_of(&holed), None);
        // Other terms on an input.
        let mut inputs = engine.inputs().to_vec();
        inputs[0].terms.pop();
        let fewer = Engine::new(
            "fewer",
            inputs,
            engine.outputs().to_vec(),
            engine.rules()[..42].to_vec(),
            Norm::Minimum,
            Norm::Minimum,
        );
        if let Ok(fewer) = fewer {
            assert_eq!(rule_table_of(&fewer), None);
        }
    }

    /// The exported FLL of the experience table, for editing into engines that are no table.
    fn exported() -> String {
        let engine = paper_002_engine(&RuleBase::Experience.table(), Defuzzifier::Centroid);
        fll::write(&engine.unwrap())
    }

    #[test]
    fn every_exported_engine_comes_back_to_its_table_whatever_its_rule_order() {
        for base in RuleBase::ALL {
            for d in Defuzzifier::ALL {
                let text = fll::write(&paper_002_engine(&base.table(), d).unwrap());
                assert_eq!(
                    paper_002_table(&fll::parse(&text).unwrap()),
                    Ok(base.table())
                );
                // Rules last to first, and the engine renamed: still the same table.
                let (head, rules) = text.split_at(text.find("  rule:").unwrap());
                let mut reversed: Vec<&str> = rules.lines().collect();
                reversed.reverse();
                let text = format!("{}{}\n", head, reversed.join("\n")).replacen(
                    "Engine: paper002",
                    "Engine: mine",
                    1,
                );
                let engine = fll::parse(&text).unwrap();
                assert_eq!(engine.rules().len(), 49);
                assert_eq!(paper_002_table(&engine), Ok(base.table()), "{base:?} {d:?}");
            }
        }
    }

    #[test]
    fn a_cell_covered_by_two_rules_is_no_table() {
        // Rule 2 (E is NB, EC is NM) moved onto rule 1's cell: the old look-up kept the later
        // rule and returned a table that misstated the engine.
        let text = exported().replacen(
            "rule: if E is NB and EC is NM then",
            "rule: if E is NB and EC is NB then",
            1,
        );
        let engine = fll::parse(&text).unwrap();
        assert_eq!(rule_table_of(&engine), None);
        assert_eq!(
            paper_002_table(&engine).unwrap_err().to_string(),
            "rules 1 and 2 both cover E is NB and EC is NB"
        );
    }

    #[test]
    fn an_engine_that_is_no_table_says_why() {
        let last_rule = exported()
            .lines()
            .rfind(|l| l.contains("rule:"))
            .unwrap()
            .to_string();
        let cases: [(&str, &str, &str); 9] = [
            (
                "term: NB Triangle -6 -6 -4",
                "term: NB Triangle -6 -6 -3",
                "input E: term NB Triangle -6 -6 -3, paper 002's is NB Triangle -6 -6 -4",
            ),
            (
                "term: PB Triangle 4 6 6\nOutputVariable",
                "term: PB Ramp 4 6\nOutputVariable",
                "input EC: term PB Ramp 4 6, paper 002's is PB Triangle 4 6 6",
            ),
            (
                "lock-range: true",
                "lock-range: false",
                "input E: lock-range false, paper 002's is true",
            ),
            (
                "lock-range: false",
                "lock-range: true",
                "output U: lock-range true, paper 002's is false",
            ),
            (
                "default: 0",
                "default: nan",
                "output U: default NaN, paper 002's is 0",
            ),
            (
                "conjunction: Minimum",
                "conjunction: AlgebraicProduct",
                "conjunction AlgebraicProduct, paper 002's is Minimum",
            ),
            (
                "then U is NB\n",
                "then U is NB with 0.5\n",
                "rule 1: weight 0.5; a table's rules have weight 1",
            ),
            (
                "rule: if E is NB and EC is NB then",
                "rule: if E is NB then",
                "rule 1: a table cell needs one E term and one EC term",
            ),
            (
                &format!("{last_rule}\n"),
                "",
                "no rule covers E is PB and EC is PB",
            ),
        ];
        for (from, to, expected) in cases {
            let text = exported().replacen(from, to, 1);
            let engine = fll::parse(&text).unwrap_or_else(|e| panic!("{to}: {e}"));
            let why = paper_002_table(&engine).unwrap_err().to_string();
            assert!(why.starts_with(expected), "{to}: {why}");
            assert_eq!(rule_table_of(&engine), None, "{to}");
        }
        // Another name for an input, and a second output.
        let text = exported()
            .replacen("InputVariable: EC", "InputVariable: X", 1)
            .replace("EC is", "X is");
        let why = paper_002_table(&fll::parse(&text).unwrap()).unwrap_err();
        assert_eq!(
            why.to_string(),
            "a 7×7 table needs inputs E and EC and one output U; this engine has inputs [E, X] and \
             outputs [U]"
        );
        let text = exported().replacen(
            "RuleBlock:",
            "OutputVariable: V\n  range: 0 1\n  term: A Triangle 0 0.5 1\nRuleBlock:",
            1,
        );
        let why = paper_002_table(&fll::parse(&text).unwrap()).unwrap_err();
        assert!(why.to_string().ends_with("outputs [U, V]"), "{why}");
    }
}
