//! Fuzzy control (paper 002): a general Mamdani engine, the paper's rule tables, FLL import and
//! export, and the incremental feed controller.
//!
//! | module | what it holds |
//! |---|---|
//! | [`membership`] | triangle, trapezoid and ramp terms as exact piecewise-linear functions |
//! | [`engine`] | rules, inference (AND = min or product, max aggregation), exact centroid, weighted average (eq 7), mean of maximum |
//! | [`rules`] | the experience-based (MacVicar-Whelan) and dynamics-based (Table 4, repaired) tables, paper 002's engine, and the table of an engine ([`rules::paper_002_table`]) |
//! | [`fll`] | fuzzylite's FLL format, read and written, for cross-checking in fuzzylite/QtFuzzyLite |
//! | [`controller`] | a_f(i+1) = a_f(i) + k_u·U(k_e·E, k_ec·EC) as a [`crate::control::law::Controller`] |

pub mod controller;
pub mod engine;
pub mod fis;
pub mod fll;
pub mod function;
pub mod membership;
pub mod rules;

use std::fmt;

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
