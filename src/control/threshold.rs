//! Threshold-proportional feedrate control (paper 003, §8 and Fig. 9).
//!
//! The measured value is compared with a maximum and a minimum threshold. Above the maximum the
//! feed drops by an amount proportional (gain K_p) to the excess; below the minimum it rises in
//! proportion to the shortfall; between them it holds. Paper 003 works on spindle RMS current with
//! K_p = 0.5 and a 0.4 A gap, and found that a gap below the current noise or a large K_p makes
//! the loop unstable, while a wide gap or a small K_p leaves the force unregulated. cutlab states
//! the excess relative to the target force, so K_p is dimensionless: K_p = 0.5 and a 10 % excess
//! lower the override by 5 percentage points per control period.
//!
//! For a set time after the spindle starts, the current is ignored (3 s in the paper), because the
//! spindle's starting current says nothing about the cut.

use super::law::{ControlInput, Controller, LawTerm};

/// Parameters of [`ThresholdProportional`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThresholdParams {
    /// Gap between the maximum and minimum thresholds, as a percentage of the target; the band is
    /// centred on the target.
    pub gap_pct: f64,
    /// Proportional gain: override percentage points per percent of relative excess.
    pub kp: f64,
    /// Time after spindle start during which the measurement is ignored.
    pub ignore_after_start_s: f64,
}

/// The controller of paper 003.
///
/// ```
/// use cutlab::control::threshold::{ThresholdProportional, ThresholdParams};
/// use cutlab::control::law::{Controller, ControlInput};
/// let mut c = ThresholdProportional::new(ThresholdParams { gap_pct: 10.0, kp: 0.5, ignore_after_start_s: 3.0 });
/// let input = ControlInput { time_s: 10.0, dt_s: 0.1, force_n: 345.0, target_force_n: 300.0,
///     programmed_feed_mm_min: 200.0, applied_override_pct: 100.0, time_since_start_s: 10.0 };
/// // The maximum threshold is 315 N; 30 N = 10 % of the target over it lowers the override by 5.
/// assert!((c.step(&input) - 95.0).abs() < 1e-12);
/// ```
#[derive(Debug, Clone)]
pub struct ThresholdProportional {
    params: ThresholdParams,
    terms: [LawTerm; 3],
}

impl ThresholdProportional {
    /// The controller; the registry's constructor checks the parameters' ranges.
    pub fn new(params: ThresholdParams) -> Self {
        Self {
            params,
            terms: [
                LawTerm::new("max threshold", "N"),
                LawTerm::new("min threshold", "N"),
                LawTerm::new("Δ override", "%"),
            ],
        }
    }
}

impl Controller for ThresholdProportional {
    /// A non-finite force holds the override.
    fn step(&mut self, input: &ControlInput) -> f64 {
        let p = self.params;
        let half_gap_n = input.target_force_n * p.gap_pct / 200.0;
        let max_n = input.target_force_n + half_gap_n;
        let min_n = input.target_force_n - half_gap_n;
        let percent_of_target = 100.0 / input.target_force_n;
        let change_pct = if input.time_since_start_s < p.ignore_after_start_s {
            0.0
        } else if input.force_n > max_n {
            -p.kp * (input.force_n - max_n) * percent_of_target
        } else if input.force_n < min_n {
            p.kp * (min_n - input.force_n) * percent_of_target
        } else {
            0.0
        };
        self.terms[0].value = max_n;
        self.terms[1].value = min_n;
        self.terms[2].value = change_pct;
        input.applied_override_pct + change_pct
    }

    fn terms(&self) -> &[LawTerm] {
        &self.terms
    }

    fn reset(&mut self) {
        for t in &mut self.terms {
            t.value = 0.0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn input(force_n: f64, since_start_s: f64) -> ControlInput {
        ControlInput {
            time_s: 10.0,
            dt_s: 0.1,
            force_n,
            target_force_n: 200.0,
            programmed_feed_mm_min: 100.0,
            applied_override_pct: 80.0,
            time_since_start_s: since_start_s,
        }
    }

    fn controller() -> ThresholdProportional {
        ThresholdProportional::new(ThresholdParams {
            gap_pct: 10.0,
            kp: 0.5,
            ignore_after_start_s: 3.0,
        })
    }

    #[test]
    fn holds_inside_the_band_and_corrects_in_proportion_outside() {
        let mut c = controller();
        // Band: 190–210 N.
        assert_eq!(c.step(&input(205.0, 10.0)), 80.0);
        // 30 N below 190 N is 15 % of the target: +7.5 points.
        assert!((c.step(&input(160.0, 10.0)) - 87.5).abs() < 1e-12);
        // Twice the excess, twice the correction.
        assert!((c.step(&input(270.0, 10.0)) - (80.0 - 15.0)).abs() < 1e-12);
    }

    #[test]
    fn ignores_the_current_right_after_spindle_start() {
        let mut c = controller();
        assert_eq!(c.step(&input(1000.0, 2.9)), 80.0);
        assert!(c.step(&input(1000.0, 3.0)) < 80.0);
    }

    #[test]
    fn a_non_finite_force_holds() {
        let mut c = controller();
        assert_eq!(c.step(&input(f64::NAN, 10.0)), 80.0);
    }
}
