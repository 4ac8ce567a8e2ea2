//! The envelope's settings and their checks: [`EnvelopeConfig`] with its defaults, the machine's
//! override positions ([`OverrideResolution`]), what starts the arming delay ([`ArmingTrigger`]),
//! what a sensor fault does ([`FaultAction`]), and [`EnvelopeError`], why the envelope cannot honour
//! a configuration (checked once, as [`SafetyEnvelope::new`](super::SafetyEnvelope::new) makes the
//! envelope).

use std::fmt;

use super::chip_load::ChipLoad;

/// The override positions a machine can take.
#[derive(Debug, Clone, PartialEq)]
pub enum OverrideResolution {
    /// Any value.
    Continuous,
    /// Whole percent (paper 003's DSP board drives 0–255 % in 1 % steps).
    WholePercent,
    /// A dial with a machine-builder table of positions in percent, ascending (paper 000's FANUC
    /// 18M reads 16 positions from four PMC inputs).
    Dial(Vec<f64>),
}

impl OverrideResolution {
    /// The position nearest to `pct` among those inside `[min_pct, max_pct]`; `None` if no
    /// position lies inside (the envelope's constructor rules that out).
    ///
    /// ```
    /// use cutlab::safety::OverrideResolution;
    /// let dial = OverrideResolution::Dial((0..16).map(|i| 10.0 * f64::from(i)).collect());
    /// assert_eq!(dial.nearest(73.0, 0.0, 150.0), Some(70.0));
    /// assert_eq!(dial.nearest(73.0, 75.0, 150.0), Some(80.0));
    /// assert_eq!(OverrideResolution::WholePercent.nearest(99.6, 0.0, 255.0), Some(100.0));
    /// ```
    pub fn nearest(&self, pct: f64, min_pct: f64, max_pct: f64) -> Option<f64> {
        let inside = |v: f64| v >= min_pct && v <= max_pct;
        match self {
            OverrideResolution::Continuous => Some(pct.clamp(min_pct, max_pct)),
            OverrideResolution::WholePercent => {
                let v = pct.round().clamp(min_pct.ceil(), max_pct.floor());
                inside(v).then_some(v)
            }
            OverrideResolution::Dial(positions) => positions
                .iter()
                .copied()
                .filter(|v| inside(*v))
                .min_by(|a, b| (a - pct).abs().total_cmp(&(b - pct).abs())),
        }
    }

    /// The largest gap between neighbouring positions (0 for continuous).
    pub fn step_pct(&self) -> f64 {
        match self {
            OverrideResolution::Continuous => 0.0,
            OverrideResolution::WholePercent => 1.0,
            OverrideResolution::Dial(p) => p.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max),
        }
    }
}

/// What to do while a sensor fault lasts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FaultAction {
    /// Keep the override where it was when the fault began.
    Hold,
    /// Move (rate-limited) to this override.
    Fallback(f64),
}

/// Settings of the envelope.
#[derive(Debug, Clone, PartialEq)]
pub struct EnvelopeConfig {
    /// Lowest override the envelope commands.
    pub min_override_pct: f64,
    /// Highest override the envelope commands.
    pub max_override_pct: f64,
    /// Fastest change of the (continuous) override.
    pub max_rate_pct_per_s: f64,
    /// The machine's override positions.
    pub resolution: OverrideResolution,
    /// What starts the arming delay.
    pub arming_trigger: ArmingTrigger,
    /// Time after the trigger before the controller is listened to.
    pub arming_delay_s: f64,
    /// Override commanded until armed.
    pub arming_override_pct: f64,
    /// A phase current beyond ± this is out of range.
    pub max_current_a: f64,
    /// Identical readings of every phase current for this long, while the axes move, are a stuck
    /// sensor (a rotating motor's currents always change).
    pub stuck_after_s: f64,
    /// A gap between samples longer than this many nominal periods is missing data.
    pub max_gap_periods: f64,
    /// Fault-free time needed before a fault counts as cleared.
    pub recover_after_s: f64,
    /// What to do during a fault.
    pub fault_action: FaultAction,
    /// An estimated force below this is the tool in air (before it enters the part, between
    /// cuts): the override is then held at most at [`EnvelopeConfig::entry_override_pct`]. 0 turns
    /// the rule off.
    pub air_cut_force_n: f64,
    /// The highest override while the tool is in air: the one it enters the next cut with.
    pub entry_override_pct: f64,
    /// The entry hold: once the estimate shows the tool has entered a cut, the override stays at
    /// the entry override for this long (the cutter engaging), or until the estimate reaches
    /// [`Self::entry_release_n`], then the controller takes over. 0 turns the hold off (the
    /// controller takes over as soon as the tool is in the cut).
    pub entry_hold_s: f64,
    /// An estimate at or above this ends the entry hold at once, N (the target: a cut already as
    /// heavy as wanted needs the controller, which will only reduce the feed from there).
    pub entry_release_n: f64,
    /// The feed per tooth the override keeps inside, if the tool and material give a window.
    pub chip_load: Option<ChipLoad>,
    /// The hard force limit of the overload alarm.
    pub overload_limit_n: f64,
    /// How long the force may exceed the hard limit before feed hold.
    pub overload_time_s: f64,
}

/// What the arming delay counts from. While the trigger is off, the envelope is disarmed and
/// commands the arming override.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ArmingTrigger {
    /// The spindle starting (paper 003 ignores the current for 3 s after it: the starting
    /// current of the spindle motor would read as a huge force).
    #[default]
    SpindleStart,
    /// The program commanding feed motion, for a machine without a spindle (paper 000's brake
    /// bench, where the feed drive is the motor under test).
    ProgrammedFeed,
}

/// Below this fraction of the target, an estimated force is the tool in air: the idle current's
/// residual scatter (a few percent of a cut's current) stays well under it, and a tool entering a
/// cut passes it within a fraction of the tool radius.
pub const AIR_CUT_FRACTION: f64 = 0.2;

impl EnvelopeConfig {
    /// The defaults on FANUC's 16-position dial (0, 10, …, 150 %): override 10–150 % at up to
    /// 100 %/s, arming 3 s after spindle start (paper 003), overload held 0.2 s before feed hold;
    /// the force limits, which follow a target, off (0) until one is set
    /// ([`EnvelopeConfig::for_target`], or a run's resolved settings).
    pub fn default_for_dial() -> Self {
        Self {
            min_override_pct: 10.0,
            max_override_pct: 150.0,
            max_rate_pct_per_s: 100.0,
            resolution: OverrideResolution::Dial((0..16).map(|i| 10.0 * f64::from(i)).collect()),
            arming_trigger: ArmingTrigger::SpindleStart,
            arming_delay_s: 3.0,
            arming_override_pct: 100.0,
            max_current_a: 100.0,
            stuck_after_s: 0.05,
            max_gap_periods: 3.0,
            recover_after_s: 0.1,
            fault_action: FaultAction::Hold,
            air_cut_force_n: 0.0,
            entry_override_pct: 100.0,
            entry_hold_s: 0.0,
            entry_release_n: f64::INFINITY,
            chip_load: None,
            overload_limit_n: 0.0,
            overload_time_s: 0.2,
        }
    }

    /// [`EnvelopeConfig::default_for_dial`] for a force target: the tool taken for in air below
    /// [`AIR_CUT_FRACTION`] of it, overload at 1.5 × target.
    pub fn for_target(target_force_n: f64) -> Self {
        Self {
            air_cut_force_n: AIR_CUT_FRACTION * target_force_n,
            overload_limit_n: 1.5 * target_force_n,
            ..Self::default_for_dial()
        }
    }

    /// Why the envelope cannot honour this configuration at `sample_rate_hz`, if it cannot: the
    /// error [`SafetyEnvelope::new`](super::SafetyEnvelope::new) returns.
    pub(super) fn check(&self, sample_rate_hz: f64) -> Result<(), EnvelopeError> {
        let c = self;
        let err = |m: String| Err(EnvelopeError(m));
        let all_finite = [
            c.min_override_pct,
            c.max_override_pct,
            c.max_rate_pct_per_s,
            c.arming_delay_s,
            c.arming_override_pct,
            c.max_current_a,
            c.stuck_after_s,
            c.max_gap_periods,
            c.recover_after_s,
            c.overload_limit_n,
            c.overload_time_s,
            c.air_cut_force_n,
            c.entry_override_pct,
            c.entry_hold_s,
            sample_rate_hz,
        ]
        .iter()
        .all(|v| v.is_finite());
        if !all_finite {
            return err("every safety setting must be a finite number".into());
        }
        if !(c.min_override_pct >= 0.0 && c.min_override_pct < c.max_override_pct) {
            return err(format!(
                "minimum override {} % must be at least 0 and below the maximum {} %",
                c.min_override_pct, c.max_override_pct
            ));
        }
        if c.max_rate_pct_per_s <= 0.0 {
            return err("the override rate limit must be positive".into());
        }
        if sample_rate_hz <= 0.0 {
            return err("the sample rate must be positive".into());
        }
        if c.air_cut_force_n < 0.0 {
            return err("the air-cut force must not be negative (0 turns the rule off)".into());
        }
        if c.entry_hold_s < 0.0 || c.entry_release_n.is_nan() {
            return err("the entry hold's time must not be negative (0 s: no hold)".into());
        }
        if let Some(w) = c.chip_load {
            let valid = w.teeth > 0
                && w.min_mm.is_finite()
                && w.max_mm.is_finite()
                && 0.0 < w.min_mm
                && w.min_mm < w.max_mm;
            if !valid {
                return err(format!(
                    "the chip-load window {}–{} mm per tooth must be positive and ascending, for \
                     a cutter with teeth",
                    w.min_mm, w.max_mm
                ));
            }
        }
        if c.max_current_a <= 0.0 || c.overload_limit_n <= 0.0 {
            return err("the current range and the overload limit must be positive".into());
        }
        if c.stuck_after_s < 0.0
            || c.recover_after_s < 0.0
            || c.arming_delay_s < 0.0
            || c.overload_time_s < 0.0
            || c.max_gap_periods < 1.0
        {
            return err("safety times must be non-negative and the gap at least one period".into());
        }
        if let OverrideResolution::Dial(p) = &c.resolution {
            if p.is_empty()
                || p.windows(2).any(|w| w[1] <= w[0])
                || p.iter().any(|v| !v.is_finite())
            {
                return err("the dial table must list finite positions in ascending order".into());
            }
        }
        if c.resolution
            .nearest(c.min_override_pct, c.min_override_pct, c.max_override_pct)
            .is_none()
        {
            return err(format!(
                "no override position of the machine lies between {} % and {} %",
                c.min_override_pct, c.max_override_pct
            ));
        }
        if let FaultAction::Fallback(v) = c.fault_action {
            if !(v.is_finite() && v >= c.min_override_pct && v <= c.max_override_pct) {
                return err(format!(
                    "the fault fallback override {v} % must lie within the override limits"
                ));
            }
        }
        Ok(())
    }
}

/// A configuration the envelope cannot honour.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EnvelopeError(pub String);

impl fmt::Display for EnvelopeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for EnvelopeError {}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::safety::SafetyEnvelope;

    #[test]
    fn rejects_configurations_it_cannot_honour() {
        let mut c = EnvelopeConfig::for_target(300.0);
        c.min_override_pct = 151.0;
        assert!(SafetyEnvelope::new(c, 1000.0).is_err());
        let mut c = EnvelopeConfig::for_target(300.0);
        c.min_override_pct = 11.0;
        c.max_override_pct = 19.0;
        let e = SafetyEnvelope::new(c, 1000.0).unwrap_err();
        assert!(e.0.contains("no override position"), "{e}");
        let mut c = EnvelopeConfig::for_target(300.0);
        c.max_rate_pct_per_s = f64::NAN;
        assert!(SafetyEnvelope::new(c, 1000.0).is_err());
    }
}
