//! How runs of several controller configurations side by side are named (Compare's columns, the
//! CLI's `cutlab compare --config` table): by the law each runs, so that no two columns that run
//! different laws read alike.

use super::fuzzy::fll;
use super::fuzzy::rules::{RuleBase, RuleTable};
use super::registry::{default_engine_fll, ControllerConfig};

/// The names of runs of `configs` side by side (Compare's columns): each its controller's name,
/// and where it runs another law than its kind's own, which one, so that no two columns that run
/// different laws read alike: a built-in rule table other than its kind's ("fuzzy-dynamics
/// (experience table)"), a table that is no built-in one ("fuzzy-dynamics (edited table)",
/// numbered "(edited table 1)", "(edited table 2)" … where several differ), an engine other than
/// `fuzzy-engine`'s default by its name ("fuzzy-engine (linear_tip_calculator)", numbered where
/// different engines share a name). Equal tables or engines share their name. Tunings are not
/// named: the parameters differ in the form beside each column.
///
/// ```
/// use cutlab::control::fuzzy::rules::RuleBase;
/// use cutlab::control::registry::{ControllerConfig, ControllerKind};
/// use cutlab::control::run_names::run_names;
/// let own = ControllerConfig::new(ControllerKind::FuzzyDynamics);
/// let mut experience = own.clone();
/// experience.set_rule_table(RuleBase::Experience.table()).unwrap();
/// let mut edited = own.clone();
/// let mut table = RuleBase::Dynamics.table();
/// table[6][6] = -3;
/// edited.set_rule_table(table).unwrap();
/// assert_eq!(
///     run_names(&[&own, &experience, &edited]),
///     ["fuzzy-dynamics", "fuzzy-dynamics (experience table)", "fuzzy-dynamics (edited table)"]
/// );
/// ```
pub fn run_names(configs: &[&ControllerConfig]) -> Vec<String> {
    /// What a configuration runs beyond its kind's own law.
    #[derive(PartialEq)]
    enum Law<'a> {
        Own,
        BuiltIn(RuleBase),
        Edited(&'a RuleTable),
        /// The engine's name and its FLL.
        Engine(&'a str, &'a str),
    }
    fn law(c: &ControllerConfig) -> Law<'_> {
        if let Some(table) = c.rule_table() {
            match RuleBase::ALL.into_iter().find(|b| b.table() == *table) {
                Some(b) if Some(b) == c.kind().rule_base() => Law::Own,
                Some(b) => Law::BuiltIn(b),
                None => Law::Edited(table),
            }
        } else if let Some(text) = c.engine_fll().filter(|t| *t != default_engine_fll()) {
            Law::Engine(fll::written_name(text).unwrap_or_default(), text)
        } else {
            Law::Own
        }
    }
    let laws: Vec<Law> = configs.iter().map(|c| law(c)).collect();
    // `label`, numbered among the different laws that `alike` says would read as it does.
    let numbered = |kind: &str, this: &Law, label: &str, alike: &dyn Fn(&Law) -> bool| {
        let mut distinct: Vec<&Law> = Vec::new();
        for other in laws.iter().filter(|o| alike(o)) {
            if !distinct.contains(&other) {
                distinct.push(other);
            }
        }
        match distinct.iter().position(|d| *d == this) {
            Some(i) if distinct.len() > 1 => format!("{kind} ({label} {})", i + 1),
            _ => format!("{kind} ({label})"),
        }
    };
    laws.iter()
        .zip(configs)
        .map(|(this, c)| {
            let kind = c.kind().name();
            match this {
                Law::Own => kind.to_string(),
                Law::BuiltIn(b) => format!("{kind} ({} table)", b.name()),
                Law::Edited(_) => {
                    numbered(kind, this, "edited table", &|o| matches!(o, Law::Edited(_)))
                }
                Law::Engine(name, _) => numbered(
                    kind,
                    this,
                    name,
                    &|o| matches!(o, Law::Engine(n, _) if n == name),
                ),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::fuzzy::engine::Defuzzifier;
    use crate::control::fuzzy::rules::paper_002_engine;
    use crate::control::registry::{ControllerKind, PAPER_002_DEFUZZIFIER};

    #[test]
    fn runs_of_different_tables_or_engines_never_share_a_name() {
        let dynamics = ControllerConfig::new(ControllerKind::FuzzyDynamics);
        let with_table = |table: RuleTable| {
            let mut c = dynamics.clone();
            c.set_rule_table(table).unwrap();
            c
        };
        let (mut one, mut two) = (RuleBase::Dynamics.table(), RuleBase::Dynamics.table());
        one[0][0] = 3;
        two[6][6] = -3;
        let (a, b, b_again) = (with_table(one), with_table(two), with_table(two));
        assert_eq!(
            run_names(&[&dynamics, &a, &b, &b_again]),
            [
                "fuzzy-dynamics",
                "fuzzy-dynamics (edited table 1)",
                "fuzzy-dynamics (edited table 2)",
                "fuzzy-dynamics (edited table 2)",
            ]
        );
        // A kind's own table given as rules is its own law; another built-in one is named.
        let own = with_table(RuleBase::Dynamics.table());
        assert_eq!(
            run_names(&[&own, &a]),
            ["fuzzy-dynamics", "fuzzy-dynamics (edited table)"]
        );
        let mut experience = ControllerConfig::new(ControllerKind::FuzzyExperience);
        experience
            .set_rule_table(RuleBase::Dynamics.table())
            .unwrap();
        assert_eq!(
            run_names(&[&experience, &dynamics]),
            ["fuzzy-experience (dynamics table)", "fuzzy-dynamics"]
        );
        // Engines by their name, numbered where different engines share one; the default engine
        // (paper 002's dynamics table as fuzzy-dynamics runs it) is the kind's own.
        let engine = |d: Defuzzifier| {
            let e = paper_002_engine(&RuleBase::Dynamics.table(), d).unwrap();
            let mut c = ControllerConfig::new(ControllerKind::FuzzyEngine);
            c.set_engine(&fll::write(&e)).unwrap();
            c
        };
        let default = ControllerConfig::new(ControllerKind::FuzzyEngine);
        let (centroid, bisector) = (engine(Defuzzifier::Centroid), engine(Defuzzifier::Bisector));
        assert_eq!(
            run_names(&[&default, &engine(PAPER_002_DEFUZZIFIER), &centroid]),
            ["fuzzy-engine", "fuzzy-engine", "fuzzy-engine (paper002)"]
        );
        assert_eq!(
            run_names(&[&centroid, &bisector, &centroid, &dynamics]),
            [
                "fuzzy-engine (paper002 1)",
                "fuzzy-engine (paper002 2)",
                "fuzzy-engine (paper002 1)",
                "fuzzy-dynamics",
            ]
        );
        // Other controllers are named by their kind alone, whatever their tuning.
        let mut pi = ControllerConfig::new(ControllerKind::Pi);
        pi.set("kp", 0.8).unwrap();
        assert_eq!(
            run_names(&[&pi, &ControllerConfig::new(ControllerKind::Pi)]),
            ["pi", "pi"]
        );
    }
}
