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

use super::engine::{Defuzzifier, Engine, InputVariable, Norm, OutputVariable, Rule, Term};
use super::membership::Shape;
use super::FuzzyError;

/// The seven linguistic levels, NB = −3 … PB = +3.
pub const LEVEL_NAMES: [&str; 7] = ["NB", "NM", "NS", "ZO", "PS", "PM", "PB"];

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
    };
    let rules = (0..7)
        .flat_map(|e| {
            (0..7).map(move |ec| Rule {
                antecedents: vec![(0, e), (1, ec)],
                consequents: vec![(0, (table[e][ec] + 3).clamp(0, 6) as usize)],
                weight: 1.0,
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

/// The rule table of an engine that has paper 002's shape — inputs E and EC and output U, each
/// with the seven standard triangles, and rules of one E term and one EC term to one U term —
/// whatever order its rules come in; `None` for any other engine (a table would misstate it).
/// This is how an imported FLL engine comes back to the 7×7 table the lab edits.
///
/// ```
/// use cutlab::control::fuzzy::engine::Defuzzifier;
/// use cutlab::control::fuzzy::rules::{paper_002_engine, rule_table_of, RuleBase};
/// let table = RuleBase::Dynamics.table();
/// let engine = paper_002_engine(&table, Defuzzifier::WeightedAverage).unwrap();
/// assert_eq!(rule_table_of(&engine), Some(table));
/// ```
pub fn rule_table_of(engine: &Engine) -> Option<RuleTable> {
    let standard = seven_terms();
    let [e, ec] = engine.inputs() else {
        return None;
    };
    let [u] = engine.outputs() else {
        return None;
    };
    if e.terms != standard || ec.terms != standard || u.terms != standard {
        return None;
    }
    // 9 marks a cell no rule filled: a table with a hole is no table.
    let mut table = [[9i8; 7]; 7];
    for rule in engine.rules() {
        let (&[(0, i), (1, j)] | &[(1, j), (0, i)]) = rule.antecedents.as_slice() else {
            return None;
        };
        let &[(0, t)] = rule.consequents.as_slice() else {
            return None;
        };
        let cell = table.get_mut(i).and_then(|row| row.get_mut(j))?;
        *cell = i8::try_from(t).ok()? - 3;
    }
    table
        .iter()
        .flatten()
        .all(|l| (-3..=3).contains(l))
        .then_some(table)
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
}
