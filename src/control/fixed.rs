//! Fixed feed: the baseline every comparison is made against.

use super::law::{ControlInput, Controller, LawTerm};

/// Always asks for the same override, whatever the force.
///
/// ```
/// use cutlab::control::fixed::FixedFeed;
/// use cutlab::control::law::{Controller, ControlInput};
/// let mut c = FixedFeed::new(80.0);
/// let input = ControlInput { time_s: 0.0, dt_s: 0.1, force_n: 500.0, target_force_n: 300.0,
///     programmed_feed_mm_min: 200.0, applied_override_pct: 100.0, time_since_start_s: 5.0 };
/// assert_eq!(c.step(&input), 80.0);
/// ```
#[derive(Debug, Clone)]
pub struct FixedFeed {
    override_pct: f64,
    terms: [LawTerm; 0],
}

impl FixedFeed {
    /// A controller that always requests `override_pct`.
    pub fn new(override_pct: f64) -> Self {
        Self {
            override_pct,
            terms: [],
        }
    }
}

impl Controller for FixedFeed {
    fn step(&mut self, _input: &ControlInput) -> f64 {
        self.override_pct
    }

    fn terms(&self) -> &[LawTerm] {
        &self.terms
    }

    fn reset(&mut self) {}
}
