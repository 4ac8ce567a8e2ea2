//! Current restriction (paper 000, §1 and §5): the classic commercial adaptive feed.
//!
//! The control holds an upper and a lower limit. Above the upper one it steps the feed override
//! down, below the lower one it steps it up, and between them it leaves it alone. Paper 000
//! states the limits on motor current; cutlab states them on the estimated force, which the
//! linear current-to-force model maps one-to-one (`docs/controllers.md`). Each step is one
//! position of the machine's override dial by default (10 %), because a step smaller than the
//! dial's resolution would be quantised away and the loop would never move.

use super::law::{ControlInput, Controller, LawTerm};

/// Parameters of [`CurrentRestriction`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RestrictionParams {
    /// Upper force limit.
    pub upper_limit_n: f64,
    /// Lower force limit; below `upper_limit_n`.
    pub lower_limit_n: f64,
    /// Override change per control period when outside the band.
    pub step_pct: f64,
}

/// The step-up/step-down band controller of paper 000.
///
/// ```
/// use cutlab::control::restriction::{CurrentRestriction, RestrictionParams};
/// use cutlab::control::law::{Controller, ControlInput};
/// let mut c = CurrentRestriction::new(RestrictionParams {
///     upper_limit_n: 330.0, lower_limit_n: 270.0, step_pct: 10.0 });
/// let mut input = ControlInput { time_s: 0.0, dt_s: 0.1, force_n: 400.0, target_force_n: 300.0,
///     programmed_feed_mm_min: 200.0, applied_override_pct: 100.0, time_since_start_s: 5.0 };
/// assert_eq!(c.step(&input), 90.0);
/// input.force_n = 300.0;
/// assert_eq!(c.step(&input), 100.0);
/// ```
#[derive(Debug, Clone)]
pub struct CurrentRestriction {
    params: RestrictionParams,
    terms: [LawTerm; 2],
}

impl CurrentRestriction {
    /// The controller; the caller guarantees `lower_limit_n < upper_limit_n` and `step_pct > 0`
    /// (the registry's constructor checks them).
    pub fn new(params: RestrictionParams) -> Self {
        Self {
            params,
            terms: [LawTerm::new("upper", "N"), LawTerm::new("lower", "N")],
        }
    }
}

impl Controller for CurrentRestriction {
    /// A non-finite force compares false with both limits and so holds the override.
    fn step(&mut self, input: &ControlInput) -> f64 {
        let p = self.params;
        self.terms[0].value = p.upper_limit_n;
        self.terms[1].value = p.lower_limit_n;
        if input.force_n > p.upper_limit_n {
            input.applied_override_pct - p.step_pct
        } else if input.force_n < p.lower_limit_n {
            input.applied_override_pct + p.step_pct
        } else {
            input.applied_override_pct
        }
    }

    fn terms(&self) -> &[LawTerm] {
        &self.terms
    }

    fn reset(&mut self) {}
}

#[cfg(test)]
mod tests {
    use super::*;

    fn input(force_n: f64) -> ControlInput {
        ControlInput {
            time_s: 10.0,
            dt_s: 0.1,
            force_n,
            target_force_n: 300.0,
            programmed_feed_mm_min: 100.0,
            applied_override_pct: 70.0,
            time_since_start_s: 10.0,
        }
    }

    #[test]
    fn steps_from_the_applied_override_and_holds_in_the_band_or_on_nan() {
        let mut c = CurrentRestriction::new(RestrictionParams {
            upper_limit_n: 330.0,
            lower_limit_n: 270.0,
            step_pct: 10.0,
        });
        assert_eq!(c.step(&input(200.0)), 80.0);
        assert_eq!(c.step(&input(400.0)), 60.0);
        assert_eq!(c.step(&input(330.0)), 70.0);
        assert_eq!(c.step(&input(f64::NAN)), 70.0);
        assert_eq!(c.terms()[0].value, 330.0);
    }
}
