//! The engine's variables: linguistic terms, and input and output variables with their universe,
//! their terms and (for an output) how it is aggregated and defuzzified. Plain data: building the
//! engine checks it.

use super::defuzzify::{Defuzzifier, WeightedKind};
use super::operators::SNorm;
use crate::control::fuzzy::membership::Shape;

/// The resolution fuzzylite gives an integral defuzzifier that names none.
pub const DEFAULT_RESOLUTION: usize = 100;

/// A linguistic term: a name and a shape.
#[derive(Debug, Clone, PartialEq)]
pub struct Term {
    /// The term's name, e.g. `NB`.
    pub name: String,
    /// Its membership function.
    pub shape: Shape,
}

/// An input variable.
#[derive(Debug, Clone, PartialEq)]
pub struct InputVariable {
    /// Name.
    pub name: String,
    /// Universe minimum.
    pub min: f64,
    /// Universe maximum.
    pub max: f64,
    /// Clamp inputs into the universe before fuzzification.
    pub lock_range: bool,
    /// Terms.
    pub terms: Vec<Term>,
}

/// An output variable.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputVariable {
    /// Name.
    pub name: String,
    /// Universe minimum.
    pub min: f64,
    /// Universe maximum.
    pub max: f64,
    /// Clamp the defuzzified value into the universe.
    pub lock_range: bool,
    /// Terms.
    pub terms: Vec<Term>,
    /// Defuzzifier.
    pub defuzzifier: Defuzzifier,
    /// Output when no rule fires.
    pub default_value: f64,
    /// Keep the previous output when no rule fires.
    pub lock_previous: bool,
    /// How activated terms combine (fuzzylite's `aggregation`; `None` is its `none`, which only
    /// a weighted defuzzifier accepts).
    pub aggregation: Option<SNorm>,
    /// Cells of a sampled integral defuzzifier (fuzzylite's resolution); the exact paths ignore
    /// it.
    pub resolution: usize,
    /// The type of a weighted defuzzifier.
    pub weighted_kind: WeightedKind,
}
