//! Fuzzy control (paper 002): a general Mamdani engine, the paper's rule tables, FLL import and
//! export, and the incremental feed controller.
//!
//! | module | what it holds |
//! |---|---|
//! | [`membership`] | every term of fuzzylite 6; triangle, trapezoid and ramp as exact piecewise-linear functions |
//! | [`function`] | the formulas of fuzzylite's Function terms |
//! | [`engine`] | rule blocks, T-norms, S-norms, hedges, chained outputs; exact centroid and mean of maximum of piecewise-linear aggregates, fuzzylite's sampling otherwise; weighted average (eq 7, Takagi–Sugeno, Tsukamoto) and sum |
//! | [`rules`] | the experience-based (MacVicar-Whelan) and dynamics-based (Table 4, repaired) tables, paper 002's engine, and the table of an engine ([`rules::paper_002_table`]) |
//! | [`fll`] | fuzzylite's FLL format, read and written, for cross-checking in fuzzylite/QtFuzzyLite |
//! | [`fis`] | MATLAB's FIS format (Fuzzy Logic Designer), read and written |
//! | [`controller`] | a_f(i+1) = a_f(i) + k_u·U(k_e·E, k_ec·EC) as a [`crate::control::law::Controller`] |

pub mod controller;
pub mod engine;
pub mod fis;
pub mod fll;
pub mod function;
pub mod membership;
pub mod rules;

use std::fmt;

/// fuzzylite's tolerance when it compares degrees (its `macheps`): a rule fires when its
/// activation exceeds it, and sampled defuzzifiers and fuzzylite's shapes count values this
/// close as equal.
pub const FUZZYLITE_EPSILON: f64 = 1e-6;

/// A fuzzy definition that cannot be used; the message says what and where.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FuzzyError(pub String);

impl FuzzyError {
    /// An error with this message, kept to one short line (an FLL line it quotes may be long).
    pub fn new(message: impl Into<String>) -> Self {
        Self(crate::input::one_short_line(&message.into()))
    }
}

impl fmt::Display for FuzzyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for FuzzyError {}

/// The formats an engine file can be in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// fuzzylite's FLL ([`fll`]).
    Fll,
    /// MATLAB's FIS ([`fis`]).
    Fis,
}

impl Format {
    /// The format of a file: by its name's extension (`.fll`, `.fis`), else by its content (a FIS
    /// file's first line that is not a comment opens a `[section]`).
    ///
    /// ```
    /// use cutlab::control::fuzzy::Format;
    /// assert_eq!(Format::of("tipper.FIS", ""), Format::Fis);
    /// assert_eq!(Format::of("engine.txt", "% MATLAB\n[System]\nName='x'"), Format::Fis);
    /// assert_eq!(Format::of("engine.txt", "Engine: x"), Format::Fll);
    /// ```
    pub fn of(file_name: &str, text: &str) -> Format {
        let lower = file_name.to_ascii_lowercase();
        if lower.ends_with(".fis") {
            return Format::Fis;
        }
        if lower.ends_with(".fll") {
            return Format::Fll;
        }
        let first = text
            .lines()
            .map(str::trim)
            .find(|l| !(l.is_empty() || l.starts_with('#') || l.starts_with('%')));
        if first.is_some_and(|l| l.starts_with('[')) {
            Format::Fis
        } else {
            Format::Fll
        }
    }

    /// Reads an engine in this format.
    pub fn parse(self, text: &str) -> Result<engine::Engine, FuzzyError> {
        match self {
            Format::Fll => fll::parse(text),
            Format::Fis => fis::parse(text),
        }
    }
}
