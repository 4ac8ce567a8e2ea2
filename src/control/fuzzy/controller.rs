//! Paper 002's incremental fuzzy feed controller.
//!
//! Each control period (paper 002 eq 6 and §2):
//!
//! ```text
//! E(i)  = F_target − F(i)              (paper: I_ref − I)
//! EC(i) = E(i) − E(i−1)
//! U     = fuzzy(k_e·E, k_ec·EC)        (inputs saturated to the universe [−6, 6])
//! a_f(i+1) = a_f(i) + k_u·U
//! ```
//!
//! Paper 002 regulates the spindle current with k_e = 6/25 A⁻¹ and k_ec = 3/25 A⁻¹ for
//! I_ref = 25 A, and k_u = 250 mm/min for a 1500 mm/min feed: an error of the whole reference
//! saturates E, a change of twice the reference saturates EC, and a saturated output changes the
//! feed by the whole programmed feed. cutlab states the same scalings relative to the target force
//! and the programmed feed, so the paper's numbers are the defaults (100 %, 200 %, 100 %) on every
//! preset. The feed a_f(i) the law increments is the one the machine applied, so the envelope's
//! limits cannot wind it up.

use super::engine::{Defuzzifier, Engine};
use super::rules::{paper_002_engine, RuleTable};
use super::FuzzyError;
use crate::control::law::{ControlInput, Controller, Term};

/// Scalings of [`FuzzyController`], relative to the target and the programmed feed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FuzzyParams {
    /// |E| that saturates the input, in percent of the target (paper: 25 A of 25 A = 100 %).
    pub error_range_pct: f64,
    /// |EC| that saturates the input, in percent of the target (paper: 50 A of 25 A = 200 %).
    pub change_range_pct: f64,
    /// Override change at |U| = 6, percentage points (paper: 6 · 250 mm/min of 1500 = 100 %).
    pub output_range_pct: f64,
    /// How U is defuzzified.
    pub defuzzifier: Defuzzifier,
}

/// The incremental fuzzy controller of paper 002.
///
/// ```
/// use cutlab::control::fuzzy::controller::{FuzzyController, FuzzyParams};
/// use cutlab::control::fuzzy::engine::Defuzzifier;
/// use cutlab::control::fuzzy::rules::RuleBase;
/// use cutlab::control::law::{Controller, ControlInput};
/// let mut c = FuzzyController::new(&RuleBase::Dynamics.table(), FuzzyParams {
///     error_range_pct: 100.0, change_range_pct: 200.0, output_range_pct: 100.0,
///     defuzzifier: Defuzzifier::WeightedAverage }).unwrap();
/// let input = ControlInput { time_s: 10.0, dt_s: 0.05, force_n: 300.0, target_force_n: 300.0,
///     programmed_feed_mm_min: 1500.0, applied_override_pct: 100.0, time_since_start_s: 10.0 };
/// assert_eq!(c.step(&input), 100.0); // on target: ZO, ZO → ZO
/// ```
#[derive(Debug, Clone)]
pub struct FuzzyController {
    engine: Engine,
    params: FuzzyParams,
    previous_error_n: Option<f64>,
    output: [f64; 1],
    terms: [Term; 4],
}

impl FuzzyController {
    /// The controller for a rule table.
    pub fn new(table: &RuleTable, params: FuzzyParams) -> Result<Self, FuzzyError> {
        Ok(Self {
            engine: paper_002_engine(table, params.defuzzifier)?,
            params,
            previous_error_n: None,
            output: [0.0],
            terms: [
                Term::new("E (scaled)", ""),
                Term::new("EC (scaled)", ""),
                Term::new("U", ""),
                Term::new("Δ override", "%"),
            ],
        })
    }

    /// The engine, for drawing its surface and rules.
    pub fn engine(&self) -> &Engine {
        &self.engine
    }
}

impl Controller for FuzzyController {
    /// A non-finite force holds the override and leaves the error history as it was.
    fn step(&mut self, input: &ControlInput) -> f64 {
        let error_n = input.target_force_n - input.force_n;
        if !error_n.is_finite() {
            return input.applied_override_pct;
        }
        let change_n = error_n - self.previous_error_n.unwrap_or(error_n);
        self.previous_error_n = Some(error_n);
        let p = self.params;
        let ke = 6.0 / (input.target_force_n * p.error_range_pct / 100.0);
        let kec = 6.0 / (input.target_force_n * p.change_range_pct / 100.0);
        let e = (ke * error_n).clamp(-6.0, 6.0);
        let ec = (kec * change_n).clamp(-6.0, 6.0);
        self.engine.evaluate(&[e, ec], &mut self.output);
        let u = self.output[0];
        let change_pct = u / 6.0 * p.output_range_pct;
        self.terms[0].value = e;
        self.terms[1].value = ec;
        self.terms[2].value = u;
        self.terms[3].value = change_pct;
        input.applied_override_pct + change_pct
    }

    fn terms(&self) -> &[Term] {
        &self.terms
    }

    fn rule_activations(&self) -> Option<&[f64]> {
        Some(self.engine.activations())
    }

    fn reset(&mut self) {
        self.previous_error_n = None;
        self.engine.reset();
        for t in &mut self.terms {
            t.value = 0.0;
        }
    }
}
