//! The interface every feed-override controller implements.
//!
//! A controller sees one [`ControlInput`] per control period and asks for a feed override. It
//! never commands the machine directly: the safety envelope ([`crate::safety`]) limits,
//! rate-limits and quantises every request, and the controller learns what was really applied
//! from [`ControlInput::applied_override_pct`] on the next period. Incremental laws integrate from
//! that applied value, which is what keeps them from winding up against the envelope's limits.
//!
//! Every controller regulates the *estimated cutting force* in newtons. The papers' current-based
//! laws (paper 000's current limits, paper 003's current thresholds, paper 002's current error)
//! are expressed in force through the calibrated linear current-to-force model, which maps a
//! current band to a force band exactly; `docs/controllers.md` gives each conversion.

/// What a controller sees once per control period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlInput {
    /// Time since the start of the run.
    pub time_s: f64,
    /// The control period.
    pub dt_s: f64,
    /// The estimated cutting force, the regulated variable. May be non-finite if the estimator
    /// had no valid input; the safety envelope holds the override in that case, and controllers
    /// must not let it poison their state (each documents what it does).
    pub force_n: f64,
    /// The force to hold.
    pub target_force_n: f64,
    /// The programmed feed of the current block.
    pub programmed_feed_mm_min: f64,
    /// The override the machine applies now, after the envelope and the machine's quantisation.
    pub applied_override_pct: f64,
    /// Time since the drive last started: the spindle on a mill (paper 003's "current ignored
    /// for 3 s after the spindle starts"), the feed on a bench without a spindle. The same clock
    /// the safety envelope's arming delay runs on ([`crate::safety::SafetyEnvelope::time_since_start_s`]).
    pub time_since_start_s: f64,
}

/// One internal value of a controller, for plotting beside the force and override.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LawTerm {
    /// Short name, e.g. `"P"`, `"I"`, `"β̂"`.
    pub name: &'static str,
    /// Unit of `value`, e.g. `"%"`, `"N"`, `""`.
    pub unit: &'static str,
    /// The value after the latest step.
    pub value: f64,
}

impl LawTerm {
    /// A term with value 0, for pre-allocating a controller's term list.
    pub const fn new(name: &'static str, unit: &'static str) -> Self {
        Self {
            name,
            unit,
            value: 0.0,
        }
    }
}

/// A feed-override controller.
///
/// Object-safe, so the lab can switch controllers at run time. `step` must not allocate.
pub trait Controller {
    /// Computes the override request for the next control period, in percent.
    fn step(&mut self, input: &ControlInput) -> f64;

    /// The internal values after the latest `step` (P/I terms, adaptive estimates, …), in a fixed
    /// order and with fixed names for the whole run.
    fn terms(&self) -> &[LawTerm];

    /// Per-rule firing strengths after the latest `step`, for rule-based controllers.
    fn rule_activations(&self) -> Option<&[f64]> {
        None
    }

    /// Returns to the state at construction.
    fn reset(&mut self);

    /// Takes charge of a machine running at `applied_override_pct` after a stretch in which the
    /// safety envelope held the override and this controller was not stepped (the tool in air, an
    /// entry's hold): its next request starts from there rather than from whatever it held
    /// before. The default starts afresh ([`Controller::reset`]); laws with an integrating state
    /// set it so that they continue from the applied override.
    fn take_over(&mut self, applied_override_pct: f64) {
        let _ = applied_override_pct;
        self.reset();
    }
}

/// The relative force error `(target − force) / target`: positive when the cut is lighter than
/// wanted. Normalising by the target makes gains portable between a 150 N finishing cut and a
/// 2 kN roughing cut.
pub fn relative_force_error(input: &ControlInput) -> f64 {
    (input.target_force_n - input.force_n) / input.target_force_n
}
