//! The operators of fuzzy logic, as fuzzylite 6 computes them: T-norms (`and`, implication),
//! S-norms (`or`, aggregation) and hedges, each a registry under fuzzylite's names. Pure functions
//! of degrees, which the rules' checks, inference and the defuzzifiers all apply.

use crate::control::fuzzy::FUZZYLITE_EPSILON;

/// A T-norm: conjunction (`and`) and implication operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Norm {
    /// min(a, b).
    Minimum,
    /// a · b.
    AlgebraicProduct,
    /// max(0, a + b − 1).
    BoundedDifference,
    /// min(a, b) if max(a, b) = 1, else 0.
    DrasticProduct,
    /// a·b / (2 − (a + b − a·b)).
    EinsteinProduct,
    /// a·b / (a + b − a·b), 0 when a + b = 0.
    HamacherProduct,
    /// min(a, b) if a + b > 1, else 0.
    NilpotentMinimum,
}

/// Whether fuzzylite counts `a` and `b` as equal (within [`FUZZYLITE_EPSILON`]).
pub(super) fn same(a: f64, b: f64) -> bool {
    a == b || (a - b).abs() < FUZZYLITE_EPSILON || (a.is_nan() && b.is_nan())
}

impl Norm {
    /// Every T-norm.
    pub const ALL: [Norm; 7] = [
        Norm::Minimum,
        Norm::AlgebraicProduct,
        Norm::BoundedDifference,
        Norm::DrasticProduct,
        Norm::EinsteinProduct,
        Norm::HamacherProduct,
        Norm::NilpotentMinimum,
    ];

    /// T(a, b), as fuzzylite 6 computes it.
    pub fn apply(self, a: f64, b: f64) -> f64 {
        match self {
            Norm::Minimum => a.min(b),
            Norm::AlgebraicProduct => a * b,
            Norm::BoundedDifference => 0f64.max(a + b - 1.0),
            Norm::DrasticProduct => {
                if same(a.max(b), 1.0) {
                    a.min(b)
                } else {
                    0.0
                }
            }
            Norm::EinsteinProduct => (a * b) / (2.0 - (a + b - a * b)),
            Norm::HamacherProduct => {
                if same(a + b, 0.0) {
                    0.0
                } else {
                    (a * b) / (a + b - a * b)
                }
            }
            Norm::NilpotentMinimum => {
                if a + b > 1.0 && !same(a + b, 1.0) {
                    a.min(b)
                } else {
                    0.0
                }
            }
        }
    }

    /// fuzzylite's name.
    pub fn name(self) -> &'static str {
        match self {
            Norm::Minimum => "Minimum",
            Norm::AlgebraicProduct => "AlgebraicProduct",
            Norm::BoundedDifference => "BoundedDifference",
            Norm::DrasticProduct => "DrasticProduct",
            Norm::EinsteinProduct => "EinsteinProduct",
            Norm::HamacherProduct => "HamacherProduct",
            Norm::NilpotentMinimum => "NilpotentMinimum",
        }
    }

    /// The T-norm fuzzylite names `name`.
    pub fn from_name(name: &str) -> Option<Norm> {
        Self::ALL.into_iter().find(|n| n.name() == name)
    }
}

/// An S-norm: disjunction (`or`) and aggregation operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SNorm {
    /// max(a, b).
    Maximum,
    /// a + b − a·b.
    AlgebraicSum,
    /// min(1, a + b).
    BoundedSum,
    /// max(a, b) if min(a, b) = 0, else 1.
    DrasticSum,
    /// (a + b) / (1 + a·b).
    EinsteinSum,
    /// (a + b − 2ab) / (1 − ab), 1 when ab = 1.
    HamacherSum,
    /// max(a, b) if a + b < 1, else 1.
    NilpotentMaximum,
    /// (a + b) / max(1, a + b).
    NormalizedSum,
    /// a + b.
    UnboundedSum,
}

impl SNorm {
    /// Every S-norm.
    pub const ALL: [SNorm; 9] = [
        SNorm::Maximum,
        SNorm::AlgebraicSum,
        SNorm::BoundedSum,
        SNorm::DrasticSum,
        SNorm::EinsteinSum,
        SNorm::HamacherSum,
        SNorm::NilpotentMaximum,
        SNorm::NormalizedSum,
        SNorm::UnboundedSum,
    ];

    /// S(a, b), as fuzzylite 6 computes it.
    pub fn apply(self, a: f64, b: f64) -> f64 {
        match self {
            SNorm::Maximum => a.max(b),
            SNorm::AlgebraicSum => a + b - a * b,
            SNorm::BoundedSum => 1f64.min(a + b),
            SNorm::DrasticSum => {
                if same(a.min(b), 0.0) {
                    a.max(b)
                } else {
                    1.0
                }
            }
            SNorm::EinsteinSum => (a + b) / (1.0 + a * b),
            SNorm::HamacherSum => {
                if same(a * b, 1.0) {
                    1.0
                } else {
                    (a + b - 2.0 * a * b) / (1.0 - a * b)
                }
            }
            SNorm::NilpotentMaximum => {
                if a + b < 1.0 && !same(a + b, 1.0) {
                    a.max(b)
                } else {
                    1.0
                }
            }
            SNorm::NormalizedSum => (a + b) / 1f64.max(a + b),
            SNorm::UnboundedSum => a + b,
        }
    }

    /// fuzzylite's name.
    pub fn name(self) -> &'static str {
        match self {
            SNorm::Maximum => "Maximum",
            SNorm::AlgebraicSum => "AlgebraicSum",
            SNorm::BoundedSum => "BoundedSum",
            SNorm::DrasticSum => "DrasticSum",
            SNorm::EinsteinSum => "EinsteinSum",
            SNorm::HamacherSum => "HamacherSum",
            SNorm::NilpotentMaximum => "NilpotentMaximum",
            SNorm::NormalizedSum => "NormalizedSum",
            SNorm::UnboundedSum => "UnboundedSum",
        }
    }

    /// The S-norm fuzzylite names `name`.
    pub fn from_name(name: &str) -> Option<SNorm> {
        Self::ALL.into_iter().find(|n| n.name() == name)
    }
}

/// A hedge: a function applied to a degree.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Hedge {
    /// 1 − μ.
    Not,
    /// √(μ/2) up to 0.5, 1 − √((1 − μ)/2) above.
    Seldom,
    /// √μ.
    Somewhat,
    /// μ².
    Very,
    /// 2μ² up to 0.5, 1 − 2(1 − μ)² above.
    Extremely,
    /// 1, whatever the value: the proposition names no term.
    Any,
}

impl Hedge {
    /// Every hedge.
    pub const ALL: [Hedge; 6] = [
        Hedge::Not,
        Hedge::Seldom,
        Hedge::Somewhat,
        Hedge::Very,
        Hedge::Extremely,
        Hedge::Any,
    ];

    /// The word in a rule.
    pub fn name(self) -> &'static str {
        match self {
            Hedge::Not => "not",
            Hedge::Seldom => "seldom",
            Hedge::Somewhat => "somewhat",
            Hedge::Very => "very",
            Hedge::Extremely => "extremely",
            Hedge::Any => "any",
        }
    }

    /// The hedge a rule's word names.
    pub fn from_name(name: &str) -> Option<Hedge> {
        Self::ALL.into_iter().find(|h| h.name() == name)
    }

    /// The hedged degree.
    pub fn apply(self, mu: f64) -> f64 {
        let at_most_half = mu <= 0.5 || same(mu, 0.5);
        match self {
            Hedge::Not => 1.0 - mu,
            Hedge::Seldom if at_most_half => (0.5 * mu).sqrt(),
            Hedge::Seldom => 1.0 - (0.5 * (1.0 - mu)).sqrt(),
            Hedge::Somewhat => mu.sqrt(),
            Hedge::Very => mu * mu,
            Hedge::Extremely if at_most_half => 2.0 * mu * mu,
            Hedge::Extremely => 1.0 - 2.0 * (1.0 - mu) * (1.0 - mu),
            Hedge::Any => 1.0,
        }
    }
}
