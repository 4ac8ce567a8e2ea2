//! The weighted objective a tuning minimises.
//!
//! Four measures of a run, each made dimensionless so that a weight of 1 means "as bad as":
//!
//! ```text
//! J = w_t · T / T₀            cycle time against the program's nominal duration at 100 %
//!   + w_e · ē / 10 %          mean |force error| over the armed cut, per 10 % of target
//!   + w_a · t_above / 1 s     time above the force limit (1.2 × target), per second
//!   + w_u · TV / 100 %        override activity (total variation Σ|Δu|), per 100 % of travel
//! ```
//!
//! A run that did not finish its program costs +∞: it never wins. The weights are rows of the
//! tuning's table ([`super::settings`]), which the Tune page and `cutlab tune --objective` parse
//! alike. The default weights (1, 1, 1, 0.1) trade a 10 % longer cycle for one point of force error or 0.1 s above the limit, and only
//! penalise chatter lightly.

use serde::Serialize;

use crate::closed_loop::metrics::Metrics;

/// The weights of the objective's four terms.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Objective {
    /// Weight of the cycle time (per nominal duration).
    pub cycle_time: f64,
    /// Weight of the mean |force error| (per 10 % of target).
    pub force_error: f64,
    /// Weight of the time above the force limit (per second).
    pub time_above_limit: f64,
    /// Weight of the override's total variation (per 100 %).
    pub override_activity: f64,
}

impl Default for Objective {
    fn default() -> Self {
        Self {
            cycle_time: 1.0,
            force_error: 1.0,
            time_above_limit: 1.0,
            override_activity: 0.1,
        }
    }
}

impl Objective {
    /// The cost of a run whose program lasts `nominal_duration_s` at 100 % override.
    ///
    /// ```
    /// use cutlab::closed_loop::metrics::{compute, MetricsConfig};
    /// use cutlab::closed_loop::trace::{Trace, TraceRow};
    /// use cutlab::tuning::Objective;
    /// let rows = (0..=10).map(|i| TraceRow { time_s: f64::from(i), depth_mm: 1.0, width_mm: 1.0,
    ///     force_n: 110.0, target_force_n: 100.0, armed: true, ..TraceRow::default() }).collect();
    /// let m = compute(&Trace { rows, completed: true, ..Trace::default() },
    ///     &MetricsConfig { force_limit_n: 120.0, settling_band_pct: 5.0, depth_step_mm: 0.2,
    ///                      load_step_times_s: vec![] });
    /// // 10 s of a 5 s program (2), 10 % error (1), nothing above the limit, no override change.
    /// assert!((Objective::default().cost(&m, 5.0) - 3.0).abs() < 1e-9);
    /// ```
    pub fn cost(&self, metrics: &Metrics, nominal_duration_s: f64) -> f64 {
        if !metrics.completed {
            return f64::INFINITY;
        }
        let nominal = if nominal_duration_s > 0.0 {
            nominal_duration_s
        } else {
            1.0
        };
        self.cycle_time * metrics.cycle_time_s / nominal
            + self.force_error * metrics.force_mean_abs_error_pct / 10.0
            + self.time_above_limit * metrics.time_above_limit_s
            + self.override_activity * metrics.override_total_variation_pct / 100.0
    }
}
