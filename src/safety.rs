//! The safety envelope: the last word between any controller and the machine.
//!
//! Every override request passes through [`SafetyEnvelope::command`], in every mode (simulation,
//! log replay, hardware), whatever the controller. The envelope
//!
//! 1. holds a fixed *arming* override until the spindle has run for the arming delay (its
//!    starting current says nothing about the cut, paper 003);
//! 2. holds the entry override while the estimated force says the tool is in air
//!    ([`EnvelopeConfig::air_cut_force_n`]) and, once it enters a cut, until the cutter is
//!    engaged ([`EnvelopeConfig::entry_hold_s`]) or the load reaches the target: no controller
//!    enters a cut wound up, and none raises the feed while the cutter is still engaging (which
//!    loads the tool beyond the fixed feed);
//! 3. keeps the override where the feed per tooth stays inside the chip-load window of the tool in
//!    the work material ([`EnvelopeConfig::chip_load`]), whatever the programmed feed and speed;
//! 4. clamps the request to `[min, max]` and rate-limits it (a continuous internal value moves
//!    by at most `max_rate_pct_per_s · dt` per period);
//! 5. quantises it to what the machine can take (a 16-position dial, 1 % steps, or continuous),
//!    never outside `[min, max]`;
//! 6. watches the sensors ([`SafetyEnvelope::observe`], every sample): non-finite, stuck or
//!    out-of-range currents and missing samples raise a fault, during which the override is held
//!    (or moves to a fallback value) and the controller's request is ignored;
//! 7. raises an overload alarm when the estimated force stays above a hard limit for longer than
//!    a set time, and then latches feed hold.
//!
//! Each of these emits a [`SafetyEvent`] for the event log.
//!
//! Guarantees, checked by property tests with random (also non-finite) inputs: the commanded
//! override is always finite, inside `[min, max]`, one of the machine's positions, and moves per
//! period by at most the rate limit plus one quantisation step — except where the chip-load window
//! moves (a block with another programmed feed or speed): the window wins at once.

use std::fmt;

use crate::machine::{OverrideCommand, SensorSample};

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

/// The chip-load window: the feed per tooth a cutter of `teeth` teeth may take in the work
/// material. Below `min_mm` the edge rubs instead of cutting (its edge radius is of that order);
/// above `max_mm` the chip overloads the edge. The override that keeps a period's feed per tooth
/// inside follows from the programmed feed and spindle speed:
/// `f_z = programmed feed × override / (teeth × rpm)`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ChipLoad {
    /// Teeth of the cutter.
    pub teeth: u32,
    /// Smallest feed per tooth, mm.
    pub min_mm: f64,
    /// Largest feed per tooth, mm.
    pub max_mm: f64,
}

impl ChipLoad {
    /// The overrides, %, that keep the feed per tooth inside the window at `programmed_feed_mm_min`
    /// and `spindle_rpm`; `None` where the two give no feed per tooth (the spindle or the axes
    /// standing still).
    ///
    /// ```
    /// use cutlab::safety::ChipLoad;
    /// let window = ChipLoad { teeth: 2, min_mm: 0.02, max_mm: 0.15 };
    /// // 200 mm/min at 1000 rpm is 0.1 mm per tooth: 20–150 % keeps it inside.
    /// let (lo, hi) = window.override_range_pct(200.0, 1000.0).unwrap();
    /// assert!((lo - 20.0).abs() < 1e-9 && (hi - 150.0).abs() < 1e-9);
    /// assert!(window.override_range_pct(0.0, 1000.0).is_none());
    /// ```
    pub fn override_range_pct(
        &self,
        programmed_feed_mm_min: f64,
        spindle_rpm: f64,
    ) -> Option<(f64, f64)> {
        let per_tooth_at_100 = programmed_feed_mm_min / (f64::from(self.teeth) * spindle_rpm);
        (per_tooth_at_100.is_finite() && per_tooth_at_100 > 0.0).then(|| {
            (
                100.0 * self.min_mm / per_tooth_at_100,
                100.0 * self.max_mm / per_tooth_at_100,
            )
        })
    }

    /// The feed per tooth at `override_pct`, mm (NaN where the spindle stands).
    pub fn feed_per_tooth_mm(
        &self,
        programmed_feed_mm_min: f64,
        spindle_rpm: f64,
        override_pct: f64,
    ) -> f64 {
        programmed_feed_mm_min * override_pct / 100.0 / (f64::from(self.teeth) * spindle_rpm)
    }
}

/// The overrides the envelope commands inside in a period at `programmed_feed_mm_min` and
/// `spindle_rpm`, %: the band `(min, max)` narrowed to those that keep the feed per tooth inside
/// `window`; the whole band without a window, or where the feed and speed give no feed per tooth.
/// A window that lies outside the band gives the band's nearer end (the band is the machine's).
///
/// ```
/// use cutlab::safety::{chip_load_band_pct, ChipLoad};
/// let window = ChipLoad { teeth: 2, min_mm: 0.02, max_mm: 0.15 };
/// // 200 mm/min at 1000 rpm: 20–150 % keeps the feed per tooth inside, within 0–255 %.
/// assert_eq!(chip_load_band_pct(Some(&window), (0.0, 255.0), 200.0, 1000.0), (20.0, 150.0));
/// assert_eq!(chip_load_band_pct(Some(&window), (10.0, 120.0), 200.0, 1000.0), (20.0, 120.0));
/// assert_eq!(chip_load_band_pct(None, (10.0, 120.0), 200.0, 1000.0), (10.0, 120.0));
/// ```
pub fn chip_load_band_pct(
    window: Option<&ChipLoad>,
    (min_pct, max_pct): (f64, f64),
    programmed_feed_mm_min: f64,
    spindle_rpm: f64,
) -> (f64, f64) {
    match window.and_then(|w| w.override_range_pct(programmed_feed_mm_min, spindle_rpm)) {
        Some((lo, hi)) => (lo.clamp(min_pct, max_pct), hi.clamp(min_pct, max_pct)),
        None => (min_pct, max_pct),
    }
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

/// A sensor fault the envelope recognises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum SensorFault {
    /// A phase current is NaN or infinite.
    NonFinite,
    /// A phase current exceeds the plausible range.
    OutOfRange,
    /// Every phase current repeats exactly while the axes move.
    Stuck,
    /// Samples are missing (a time gap).
    MissingSamples,
}

impl SensorFault {
    /// A short description for the event log.
    pub fn describe(self) -> &'static str {
        match self {
            SensorFault::NonFinite => "a current reading is not a number",
            SensorFault::OutOfRange => "a current reading is out of range",
            SensorFault::Stuck => "the current readings are stuck",
            SensorFault::MissingSamples => "samples are missing",
        }
    }
}

/// Something the envelope did or saw, for the event log.
/// Serialised for a trace sent from a worker to the page (a NaN is written as null and read back
/// as NaN).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum SafetyEvent {
    /// The arming delay passed: the controller is now in charge.
    Armed {
        /// When.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        time_s: f64,
    },
    /// A sensor fault began; the override is held or falls back.
    FaultDetected {
        /// When.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        time_s: f64,
        /// Which fault.
        fault: SensorFault,
    },
    /// The sensors have been healthy for the recovery time.
    FaultCleared {
        /// When.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        time_s: f64,
    },
    /// The estimated force stayed above the hard limit: feed hold is latched.
    Overload {
        /// When.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        time_s: f64,
        /// The force that tripped the alarm.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        force_n: f64,
    },
    /// The controller asked for a non-finite override (a law fed garbage, or one that diverged):
    /// the envelope holds the override until the requests are numbers again.
    ControllerFault {
        /// When.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        time_s: f64,
    },
    /// The tool was cutting before the loop armed: the controller enters the cut uncontrolled
    /// (a part program should approach in air until the arming delay has passed).
    CutBeforeArming {
        /// When the cut was first seen.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        time_s: f64,
        /// The estimated force then.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        force_n: f64,
    },
    /// The tool is in air and the controller asked for more than the entry override: the
    /// envelope holds the entry override until the estimate shows a cut again (once per stretch
    /// of air).
    AirCut {
        /// When.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        time_s: f64,
        /// The override held.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        entry_override_pct: f64,
    },
    /// The tool entered a cut: the override stays at the entry override until the cutter is
    /// engaged.
    EntryHold {
        /// When.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        time_s: f64,
        /// The override held at most.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        entry_override_pct: f64,
    },
    /// The cutter is engaged after an entry, or the load reached the target: the controller takes
    /// over.
    EntrySettled {
        /// When.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        time_s: f64,
        /// The estimated force it settled at.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        force_n: f64,
    },
    /// The chip-load window held the override (once per stretch that it holds at that end).
    ChipLoad {
        /// When.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        time_s: f64,
        /// The window's end that held.
        end: ChipLoadEnd,
        /// The feed per tooth there, mm.
        #[serde(deserialize_with = "crate::estimation::null_as_nan")]
        feed_per_tooth_mm: f64,
    },
}

/// Which end of the chip-load window held the override.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum ChipLoadEnd {
    /// The smallest feed per tooth: the edge would rub.
    Lowest,
    /// The largest: the edge would be overloaded.
    Highest,
}

impl SafetyEvent {
    /// When the event happened.
    pub fn time_s(&self) -> f64 {
        match *self {
            SafetyEvent::Armed { time_s }
            | SafetyEvent::FaultDetected { time_s, .. }
            | SafetyEvent::FaultCleared { time_s }
            | SafetyEvent::Overload { time_s, .. }
            | SafetyEvent::CutBeforeArming { time_s, .. }
            | SafetyEvent::AirCut { time_s, .. }
            | SafetyEvent::EntryHold { time_s, .. }
            | SafetyEvent::EntrySettled { time_s, .. }
            | SafetyEvent::ChipLoad { time_s, .. }
            | SafetyEvent::ControllerFault { time_s } => time_s,
        }
    }

    /// A one-line description.
    pub fn describe(&self) -> String {
        match *self {
            SafetyEvent::Armed { .. } => "armed: the controller now sets the override".into(),
            SafetyEvent::FaultDetected { fault, .. } => {
                format!("sensor fault: {}; override held", fault.describe())
            }
            SafetyEvent::FaultCleared { .. } => "sensor fault cleared".into(),
            SafetyEvent::Overload { force_n, .. } => {
                format!("overload: {force_n:.0} N above the hard limit; feed hold")
            }
            SafetyEvent::ControllerFault { .. } => {
                "controller fault: it asked for a non-finite override; override held".into()
            }
            SafetyEvent::CutBeforeArming { force_n, .. } => format!(
                "warning: cutting ({force_n:.0} N) before the loop armed; the controller enters \
                 the cut uncontrolled (approach in air until the arming delay has passed)"
            ),
            SafetyEvent::AirCut {
                entry_override_pct, ..
            } => format!(
                "air cut: override held at {entry_override_pct:.0} % until the tool enters the cut"
            ),
            SafetyEvent::EntryHold {
                entry_override_pct, ..
            } => format!(
                "entry: the tool entered the cut; override held at {entry_override_pct:.0} % \
                 until the cutter is engaged"
            ),
            SafetyEvent::EntrySettled { force_n, .. } => format!(
                "entry: the cutter is in the cut at {force_n:.0} N; the controller takes over"
            ),
            SafetyEvent::ChipLoad {
                end,
                feed_per_tooth_mm,
                ..
            } => match end {
                ChipLoadEnd::Highest => format!(
                    "chip load: override held so the feed per tooth stays at most \
                     {feed_per_tooth_mm:.3} mm"
                ),
                ChipLoadEnd::Lowest => format!(
                    "chip load: override held so the feed per tooth stays at least \
                     {feed_per_tooth_mm:.3} mm (below, the edge rubs)"
                ),
            },
        }
    }
}

/// The envelope's state.
#[derive(Debug, Clone)]
pub struct SafetyEnvelope {
    config: EnvelopeConfig,
    sample_period_s: f64,
    /// The rate-limited continuous override that the quantised output follows.
    continuous_pct: f64,
    output_pct: f64,
    armed: bool,
    feed_hold: bool,
    fault: Option<SensorFault>,
    fault_free_s: f64,
    previous_sample: Option<SensorSample>,
    unchanged_s: f64,
    overload_s: f64,
    /// How long the programmed feed has been non-zero (for [`ArmingTrigger::ProgrammedFeed`]).
    programmed_feed_s: f64,
    /// Whether the controller's last request was not a number (reported once per episode).
    controller_fault: bool,
    /// Whether the air-cut rule is holding the override (for one event per stretch of air).
    holding_in_air: bool,
    /// Whether the envelope held the entry override at the last period (in air, or an entry's
    /// hold): the controller was not in charge.
    holding: bool,
    /// Whether the tool was in air at the last period (so the next cut is an entry).
    was_in_air: bool,
    /// When the entry hold under way began.
    entry_since_s: Option<f64>,
    /// The end of the chip-load window that held the override at the last period.
    chip_limited: Option<ChipLoadEnd>,
    events: Vec<SafetyEvent>,
}

/// Events kept before the caller drains them; more in one period are dropped, which cannot
/// happen with the event kinds above (at most five per period).
const EVENT_CAPACITY: usize = 16;

impl SafetyEnvelope {
    /// An envelope for a machine whose sensors deliver `sample_rate_hz`.
    pub fn new(config: EnvelopeConfig, sample_rate_hz: f64) -> Result<Self, EnvelopeError> {
        let c = &config;
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
        let start = c
            .arming_override_pct
            .clamp(c.min_override_pct, c.max_override_pct);
        let mut envelope = Self {
            continuous_pct: start,
            output_pct: start,
            sample_period_s: 1.0 / sample_rate_hz,
            armed: false,
            feed_hold: false,
            fault: None,
            fault_free_s: 0.0,
            previous_sample: None,
            unchanged_s: 0.0,
            overload_s: 0.0,
            programmed_feed_s: 0.0,
            controller_fault: false,
            holding_in_air: false,
            holding: false,
            was_in_air: false,
            entry_since_s: None,
            chip_limited: None,
            events: Vec::with_capacity(EVENT_CAPACITY),
            config,
        };
        envelope.output_pct = envelope.quantize(start);
        Ok(envelope)
    }

    /// The configuration.
    pub fn config(&self) -> &EnvelopeConfig {
        &self.config
    }

    /// The override commanded now.
    pub fn output_pct(&self) -> f64 {
        self.output_pct
    }

    /// Time since the start the arming waits for: the spindle's, or with
    /// [`ArmingTrigger::ProgrammedFeed`] (a bench without a spindle) the first programmed feed
    /// motion's. Controllers that ignore a starting transient use this clock too.
    pub fn time_since_start_s(&self, sample: &SensorSample) -> f64 {
        match self.config.arming_trigger {
            ArmingTrigger::SpindleStart => sample.time_since_spindle_start_s,
            ArmingTrigger::ProgrammedFeed => self.programmed_feed_s,
        }
    }

    /// Whether the envelope has armed (the arming delay passed).
    pub fn armed(&self) -> bool {
        self.armed
    }

    /// Whether the envelope held the entry override at the last period — the tool in air, or an
    /// entry's hold — so the controller's request was not listened to. The loop does not step its
    /// controller then (an integrating law would wind up on what it cannot change) and hands it
    /// the override when the hold ends ([`crate::control::law::Controller::take_over`]).
    pub fn holding(&self) -> bool {
        self.holding
    }

    /// The sensor fault in force, if any.
    pub fn fault(&self) -> Option<SensorFault> {
        self.fault
    }

    /// Whether feed hold is latched.
    pub fn feed_hold(&self) -> bool {
        self.feed_hold
    }

    fn quantize(&self, pct: f64) -> f64 {
        let c = &self.config;
        c.resolution
            .nearest(pct, c.min_override_pct, c.max_override_pct)
            .unwrap_or(c.min_override_pct)
    }

    fn emit(&mut self, event: SafetyEvent) {
        if self.events.len() < EVENT_CAPACITY {
            self.events.push(event);
        }
    }

    /// Moves the events raised since the last call into `sink`.
    pub fn drain_events(&mut self, sink: &mut Vec<SafetyEvent>) {
        sink.append(&mut self.events);
    }

    /// Whether the arming trigger is on in `sample`.
    fn triggered(&self, sample: &SensorSample) -> bool {
        match self.config.arming_trigger {
            ArmingTrigger::SpindleStart => sample.spindle_running,
            ArmingTrigger::ProgrammedFeed => sample.programmed_feed_mm_min > 0.0,
        }
    }

    /// Watches one sensor sample for faults. Call for every sample, before [`Self::command`].
    #[inline(always)]
    pub fn observe(&mut self, sample: &SensorSample) {
        // Six currents every sample: plain loops (an iterator chain is a call per item in the
        // size-optimised browser build).
        let mut non_finite = !sample.time_s.is_finite();
        let mut out_of_range = false;
        for currents in [
            &sample.feed_phase_currents_a,
            &sample.spindle_phase_currents_a,
        ] {
            for i in currents {
                non_finite |= !i.is_finite();
                out_of_range |= i.abs() > self.config.max_current_a;
            }
        }
        let mut fault = None;
        if non_finite {
            fault = Some(SensorFault::NonFinite);
        } else if out_of_range {
            fault = Some(SensorFault::OutOfRange);
        }
        if let Some(previous) = self.previous_sample {
            let gap_s = sample.time_s - previous.time_s;
            if fault.is_none() && gap_s > self.config.max_gap_periods * self.sample_period_s {
                fault = Some(SensorFault::MissingSamples);
            }
            let unchanged = previous.feed_phase_currents_a == sample.feed_phase_currents_a
                && previous.spindle_phase_currents_a == sample.spindle_phase_currents_a;
            let moving = sample.feed_mm_min.abs() > 0.0 && self.triggered(sample);
            self.unchanged_s = if unchanged && moving {
                self.unchanged_s + self.sample_period_s
            } else {
                0.0
            };
            if fault.is_none()
                && self.unchanged_s >= self.config.stuck_after_s
                && self.unchanged_s > 0.0
            {
                fault = Some(SensorFault::Stuck);
            }
        }
        self.previous_sample = Some(*sample);
        self.programmed_feed_s = if sample.programmed_feed_mm_min > 0.0 {
            self.programmed_feed_s + self.sample_period_s
        } else {
            0.0
        };
        let time_s = sample.time_s;
        match (self.fault, fault) {
            (None, Some(f)) => {
                self.fault = Some(f);
                self.fault_free_s = 0.0;
                self.emit(SafetyEvent::FaultDetected { time_s, fault: f });
            }
            (Some(_), Some(_)) => self.fault_free_s = 0.0,
            (Some(_), None) => {
                self.fault_free_s += self.sample_period_s;
                if self.fault_free_s >= self.config.recover_after_s {
                    self.fault = None;
                    self.emit(SafetyEvent::FaultCleared { time_s });
                }
            }
            (None, None) => {}
        }
    }

    /// Turns a controller's request into the command the machine receives for the next control
    /// period of length `dt_s`. `force_n` is the estimated force (for the overload alarm).
    pub fn command(
        &mut self,
        request_pct: f64,
        force_n: f64,
        time_s: f64,
        dt_s: f64,
        sample: &SensorSample,
    ) -> OverrideCommand {
        let dt_s = if dt_s.is_finite() && dt_s > 0.0 {
            dt_s
        } else {
            0.0
        };

        let triggered = self.triggered(sample);
        let since_trigger_s = self.time_since_start_s(sample);
        let armed_now = triggered && since_trigger_s >= self.config.arming_delay_s;
        if armed_now && !self.armed {
            self.armed = true;
            self.emit(SafetyEvent::Armed { time_s });
        } else if !triggered {
            self.armed = false;
        }

        // Overload alarm: a latched feed hold, independent of the controller. It counts only
        // while armed: before that the estimate is dominated by the spindle's starting current
        // (paper 003), which says nothing about the load on the tool.
        if self.armed && force_n.is_finite() && force_n > self.config.overload_limit_n {
            self.overload_s += dt_s;
        } else {
            self.overload_s = 0.0;
        }
        if !self.feed_hold && self.overload_s > self.config.overload_time_s {
            self.feed_hold = true;
            self.emit(SafetyEvent::Overload { time_s, force_n });
        }

        // A non-finite request (a controller fed garbage, or diverged) holds the override, and
        // says so once per episode.
        if self.armed && self.fault.is_none() {
            let bad_request = !request_pct.is_finite();
            if bad_request && !self.controller_fault {
                self.emit(SafetyEvent::ControllerFault { time_s });
            }
            self.controller_fault = bad_request;
        }
        let c = &self.config;
        let wanted = if !self.armed {
            c.arming_override_pct
        } else {
            match (self.fault, c.fault_action) {
                (Some(_), FaultAction::Hold) => self.continuous_pct,
                (Some(_), FaultAction::Fallback(v)) => v,
                (None, _) if request_pct.is_finite() => request_pct,
                (None, _) => self.continuous_pct,
            }
        };
        // In air a controller sees no force and asks for ever more feed; entering the next cut at
        // that feed would load the tool far beyond the target before any loop could react. The
        // tool enters at the entry override, as commercial adaptive feed controls do (they do not
        // adapt in air), and — with the entry hold — stays at most there until the load has
        // settled: a controller released while the cutter is still engaging sees a force below
        // the target, raises the feed, and the full engagement then loads the tool beyond what the
        // fixed feed would.
        let watching = self.armed && self.fault.is_none() && force_n.is_finite();
        // 0 turns the rule off (a negative estimate in air is no reason to act then).
        let in_air = watching && c.air_cut_force_n > 0.0 && force_n < c.air_cut_force_n;
        let entry_override_pct = c.entry_override_pct;
        if !watching || in_air {
            self.entry_since_s = None;
        } else if self.was_in_air && c.entry_hold_s > 0.0 {
            self.entry_since_s = Some(time_s);
            self.emit(SafetyEvent::EntryHold {
                time_s,
                entry_override_pct,
            });
        } else if let Some(since_s) = self.entry_since_s {
            // The cutter is engaged after its hold; a cut already as heavy as wanted needs the
            // controller at once (it will only reduce the feed from there).
            if time_s - since_s >= c.entry_hold_s || force_n >= c.entry_release_n {
                self.entry_since_s = None;
                self.emit(SafetyEvent::EntrySettled { time_s, force_n });
            }
        }
        if watching {
            self.was_in_air = in_air;
        }
        let c = &self.config;
        // In air and through an entry's hold the override is the entry override, whatever the
        // controller asks: the controller is not in charge ([`Self::holding`]).
        self.holding = in_air || self.entry_since_s.is_some();
        let wanted = if self.holding {
            entry_override_pct
        } else {
            wanted
        };
        // The band, narrowed to the overrides that keep the feed per tooth inside the chip-load
        // window at this period's programmed feed and speed.
        let (lowest, highest) = chip_load_band_pct(
            c.chip_load.as_ref(),
            (c.min_override_pct, c.max_override_pct),
            sample.programmed_feed_mm_min,
            sample.spindle_command_rpm,
        );
        // Which end of the window holds the request, if either (for the event log).
        let window = c.chip_load.and_then(|w| {
            w.override_range_pct(sample.programmed_feed_mm_min, sample.spindle_command_rpm)
                .map(|range| (w, range))
        });
        let chip_end = match window {
            Some((_, (_, hi))) if wanted > hi && hi < c.max_override_pct => {
                Some(ChipLoadEnd::Highest)
            }
            Some((_, (lo, _))) if wanted < lo && lo > c.min_override_pct => {
                Some(ChipLoadEnd::Lowest)
            }
            _ => None,
        };
        let wanted = wanted.clamp(lowest, highest);
        let max_step = c.max_rate_pct_per_s * dt_s;
        // One event per stretch of air.
        if in_air && !self.holding_in_air {
            self.emit(SafetyEvent::AirCut {
                time_s,
                entry_override_pct,
            });
        }
        self.holding_in_air = in_air;
        self.continuous_pct += (wanted - self.continuous_pct).clamp(-max_step, max_step);
        // The window wins over the rate limit: where a block's programmed feed or speed moves
        // it, the override follows at once (the feed per tooth is the limit, not the override).
        self.continuous_pct = self.continuous_pct.clamp(lowest, highest);
        self.output_pct = self
            .config
            .resolution
            .nearest(self.continuous_pct, lowest, highest)
            .unwrap_or_else(|| self.quantize(self.continuous_pct));
        if let (Some(end), Some((w, _))) = (chip_end, window) {
            if self.chip_limited != Some(end) {
                let feed_per_tooth_mm = match end {
                    ChipLoadEnd::Highest => w.max_mm,
                    ChipLoadEnd::Lowest => w.min_mm,
                };
                self.emit(SafetyEvent::ChipLoad {
                    time_s,
                    end,
                    feed_per_tooth_mm,
                });
            }
        }
        self.chip_limited = chip_end;
        OverrideCommand {
            override_pct: self.output_pct,
            feed_hold: self.feed_hold,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn running_sample(time_s: f64) -> SensorSample {
        SensorSample {
            time_s,
            feed_phase_currents_a: [1.0, -0.5, -0.5],
            spindle_phase_currents_a: [5.0, -2.5, -2.5],
            feed_mm_min: 100.0,
            spindle_running: true,
            time_since_spindle_start_s: 10.0 + time_s,
            ..SensorSample::default()
        }
    }

    fn envelope(config: EnvelopeConfig) -> SafetyEnvelope {
        SafetyEnvelope::new(config, 1000.0).unwrap()
    }

    #[test]
    fn in_air_the_override_stays_at_the_entry_override_whatever_the_controller_asks() {
        // Target 300 N: below 60 N the tool is in air.
        let mut env = envelope(EnvelopeConfig::for_target(300.0));
        let mut t = 0.0;
        let mut step = |env: &mut SafetyEnvelope, request: f64, force_n: f64| {
            t += 0.1;
            env.command(request, force_n, t, 0.1, &running_sample(t))
                .override_pct
        };
        // A controller that sees no force asks for the most it may: the envelope holds 100 %,
        // and says so once.
        for _ in 0..30 {
            assert_eq!(step(&mut env, 150.0, 5.0), 100.0);
        }
        let mut seen = Vec::new();
        let mut air_events = |env: &mut SafetyEnvelope| {
            env.drain_events(&mut seen);
            seen.iter()
                .filter(|e| matches!(e, SafetyEvent::AirCut { .. }))
                .count()
        };
        assert_eq!(air_events(&mut env), 1);
        // Asking for less changes nothing either: in air the controller is not in charge.
        assert_eq!(step(&mut env, 50.0, 5.0), 100.0);
        assert!(env.holding());
        // In the cut the controller has the whole band again.
        let mut last = 0.0;
        for _ in 0..20 {
            last = step(&mut env, 150.0, 250.0);
        }
        assert_eq!(last, 150.0);
        // The next stretch of air is a new event.
        step(&mut env, 150.0, 5.0);
        assert_eq!(air_events(&mut env), 2);
        // Off: the air cut rule does nothing.
        let mut config = EnvelopeConfig::for_target(300.0);
        config.air_cut_force_n = 0.0;
        let mut env = envelope(config);
        let mut last = 0.0;
        for _ in 0..20 {
            last = step(&mut env, 150.0, 5.0);
        }
        assert_eq!(last, 150.0);
    }

    #[test]
    fn after_an_entry_the_override_holds_until_the_cutter_is_engaged_or_the_target_reached() {
        // Target 300 N: in air below 60 N; the cutter engages over 0.5 s.
        let mut config = EnvelopeConfig::for_target(300.0);
        config.entry_hold_s = 0.5;
        config.entry_release_n = 300.0;
        let mut env = envelope(config);
        let mut t = 0.0;
        let mut step = |env: &mut SafetyEnvelope, force_n: f64| {
            t += 0.1;
            env.command(150.0, force_n, t, 0.1, &running_sample(t))
                .override_pct
        };
        step(&mut env, 5.0);
        // The cutter engages: the force rises, the controller asks for 150 %, the envelope holds
        // 100 % for the hold's 0.5 s.
        for k in 1..=5 {
            assert_eq!(step(&mut env, 40.0 * f64::from(k) + 30.0), 100.0);
            assert!(env.holding(), "period {k}");
        }
        // Then the cutter is in the cut (within a period of the hold's end: times add up in
        // floating point).
        step(&mut env, 235.0);
        step(&mut env, 236.0);
        assert!(!env.holding());
        let mut events = Vec::new();
        env.drain_events(&mut events);
        let kinds: Vec<&str> = events
            .iter()
            .map(|e| match e {
                SafetyEvent::Armed { .. } => "armed",
                SafetyEvent::AirCut { .. } => "air",
                SafetyEvent::EntryHold { .. } => "hold",
                SafetyEvent::EntrySettled { .. } => "settled",
                _ => "other",
            })
            .collect();
        assert_eq!(kinds, ["armed", "air", "hold", "settled"]);
        // A cut already at the target ends the hold at once: the controller reduces from there.
        step(&mut env, 5.0);
        step(&mut env, 200.0);
        assert!(env.holding());
        step(&mut env, 320.0);
        assert!(!env.holding());
        // Off (0 s): the controller is in charge as soon as the tool is in the cut.
        let mut config = EnvelopeConfig::for_target(300.0);
        config.entry_hold_s = 0.0;
        let mut env = envelope(config);
        step(&mut env, 5.0);
        step(&mut env, 100.0);
        assert!(!env.holding());
    }

    #[test]
    fn the_chip_load_window_keeps_every_command_inside_it_and_says_when_it_holds() {
        // Two teeth at 1000 rpm, 200 mm/min: 0.1 mm per tooth at 100 %; a window of 0.02–0.15 mm
        // allows 20–150 % of the 10–255 % band.
        let mut config = EnvelopeConfig::for_target(300.0);
        config.min_override_pct = 10.0;
        config.max_override_pct = 255.0;
        config.resolution = OverrideResolution::WholePercent;
        config.chip_load = Some(ChipLoad {
            teeth: 2,
            min_mm: 0.02,
            max_mm: 0.15,
        });
        let mut env = envelope(config);
        let sample = |t: f64, feed: f64| SensorSample {
            programmed_feed_mm_min: feed,
            spindle_command_rpm: 1000.0,
            ..running_sample(t)
        };
        let mut rng = Rng::seed_from(11);
        let mut t = 0.0;
        for _ in 0..2000 {
            t += 0.05;
            let feed = if rng.uniform() < 0.5 { 200.0 } else { 400.0 };
            let request = -50.0 + 450.0 * rng.uniform();
            let c = env.command(request, 300.0, t, 0.05, &sample(t, feed));
            let per_tooth = feed * c.override_pct / 100.0 / 2000.0;
            assert!(
                (0.02 - 1e-12..=0.15 + 1e-12).contains(&per_tooth),
                "{per_tooth} mm at {feed} mm/min, {} %",
                c.override_pct
            );
        }
        let mut events = Vec::new();
        env.drain_events(&mut events);
        // Held at each end, once per stretch (the last stretches' events; the queue holds 16).
        assert!(events.iter().any(|e| matches!(
            e,
            SafetyEvent::ChipLoad {
                end: ChipLoadEnd::Highest,
                ..
            }
        )));
        // No feed or no spindle: no window to keep.
        let free = env.command(250.0, 300.0, t + 10.0, 10.0, &sample(t, 0.0));
        assert_eq!(free.override_pct, 250.0);
    }

    #[test]
    fn a_non_finite_request_is_one_controller_fault_event_and_the_override_holds() {
        let mut env = envelope(EnvelopeConfig::for_target(300.0));
        let s = running_sample(0.0);
        let held = env.command(100.0, 300.0, 0.0, 0.1, &s).override_pct;
        assert!(env.armed());
        for (i, bad) in [f64::NAN, f64::NEG_INFINITY, f64::INFINITY]
            .into_iter()
            .enumerate()
        {
            let cmd = env.command(bad, 300.0, 0.1 * (i + 1) as f64, 0.1, &s);
            assert_eq!(cmd.override_pct, held);
        }
        env.command(110.0, 300.0, 0.4, 0.1, &s);
        env.command(f64::NAN, 300.0, 0.5, 0.1, &s);
        let mut events = Vec::new();
        env.drain_events(&mut events);
        let faults: Vec<f64> = events
            .iter()
            .filter_map(|e| match e {
                SafetyEvent::ControllerFault { time_s } => Some(*time_s),
                _ => None,
            })
            .collect();
        // One event per episode: the first bad request, and again after a good one.
        assert_eq!(faults, vec![0.1, 0.5]);
    }

    #[test]
    fn holds_the_arming_override_until_the_delay_has_passed() {
        let mut env = envelope(EnvelopeConfig::for_target(300.0));
        let mut s = running_sample(0.0);
        s.time_since_spindle_start_s = 1.0;
        let cmd = env.command(40.0, 100.0, 0.0, 0.1, &s);
        assert_eq!(cmd.override_pct, 100.0);
        assert!(!env.armed());
        s.time_since_spindle_start_s = 3.0;
        env.command(40.0, 100.0, 0.1, 0.1, &s);
        assert!(env.armed());
        let mut events = Vec::new();
        env.drain_events(&mut events);
        assert_eq!(events, vec![SafetyEvent::Armed { time_s: 0.1 }]);
    }

    #[test]
    fn without_a_spindle_arming_counts_from_the_programmed_feed() {
        let mut config = EnvelopeConfig::for_target(300.0);
        config.arming_trigger = ArmingTrigger::ProgrammedFeed;
        config.arming_delay_s = 0.5;
        let mut env = envelope(config);
        // A bench: no spindle ever; the program feeds from the start; the feed motor's currents
        // turn (constant ones would be a stuck sensor, which the envelope now watches for).
        let bench = |time_s: f64, programmed_feed_mm_min: f64| {
            let angle = 2.0 * std::f64::consts::PI * 50.0 * time_s;
            SensorSample {
                spindle_running: false,
                spindle_phase_currents_a: [0.0; 3],
                feed_phase_currents_a: [0.0, 2.0, 4.0].map(|k| (angle - k).sin()),
                programmed_feed_mm_min,
                ..running_sample(time_s)
            }
        };
        let feed_for = |env: &mut SafetyEnvelope, from_s: f64, to_s: f64, feed: f64| {
            let mut t = from_s;
            while t < to_s - 1e-9 {
                env.observe(&bench(t, feed));
                t += 0.001;
            }
            env.command(40.0, 100.0, to_s, 0.1, &bench(to_s, feed))
        };
        assert_eq!(feed_for(&mut env, 0.0, 0.4, 500.0).override_pct, 100.0);
        assert!(!env.armed());
        feed_for(&mut env, 0.4, 0.6, 500.0);
        assert!(env.armed());
        // The program stops feeding: disarmed, and the delay starts again with the next move.
        feed_for(&mut env, 0.6, 0.7, 0.0);
        assert!(!env.armed());
        feed_for(&mut env, 0.7, 1.0, 500.0);
        assert!(!env.armed());
        let mut events = Vec::new();
        env.drain_events(&mut events);
        assert_eq!(events, vec![SafetyEvent::Armed { time_s: 0.6 }]);
    }

    #[test]
    fn rate_limit_moves_the_dial_one_grade_at_a_time() {
        let mut env = envelope(EnvelopeConfig::for_target(300.0));
        let s = running_sample(0.0);
        // 100 %/s for 0.1 s periods: 10 % per period, one dial grade.
        let outputs: Vec<f64> = (0..5)
            .map(|i| {
                env.command(40.0, 100.0, f64::from(i) * 0.1, 0.1, &s)
                    .override_pct
            })
            .collect();
        assert_eq!(outputs, vec![90.0, 80.0, 70.0, 60.0, 50.0]);
    }

    #[test]
    fn stuck_currents_raise_a_fault_and_hold_then_clear() {
        let mut env = envelope(EnvelopeConfig::for_target(300.0));
        let mut events = Vec::new();
        let mut t = 0.0;
        // A healthy, rotating signal first.
        for i in 0..100 {
            let mut s = running_sample(t);
            s.feed_phase_currents_a[0] = f64::from(i % 7);
            env.observe(&s);
            t += 0.001;
        }
        assert_eq!(env.fault(), None);
        // 60 ms of identical readings (the limit is 50 ms).
        for _ in 0..60 {
            env.observe(&running_sample(t));
            t += 0.001;
        }
        assert_eq!(env.fault(), Some(SensorFault::Stuck));
        let s = running_sample(t);
        let before = env.output_pct();
        assert_eq!(env.command(20.0, 100.0, t, 0.1, &s).override_pct, before);
        for i in 0..150 {
            let mut s = running_sample(t);
            s.feed_phase_currents_a[0] = f64::from(i % 5);
            env.observe(&s);
            t += 0.001;
        }
        assert_eq!(env.fault(), None);
        env.drain_events(&mut events);
        events.retain(|e| !matches!(e, SafetyEvent::Armed { .. }));
        assert!(matches!(
            events[..],
            [
                SafetyEvent::FaultDetected {
                    fault: SensorFault::Stuck,
                    ..
                },
                SafetyEvent::FaultCleared { .. }
            ]
        ));
    }

    #[test]
    fn a_time_gap_is_missing_samples() {
        let mut env = envelope(EnvelopeConfig::for_target(300.0));
        env.observe(&running_sample(0.0));
        env.observe(&running_sample(0.010));
        assert_eq!(env.fault(), Some(SensorFault::MissingSamples));
    }

    #[test]
    fn overload_latches_feed_hold_after_the_set_time() {
        let mut env = envelope(EnvelopeConfig::for_target(300.0));
        let s = running_sample(0.0);
        let mut held_at = None;
        for i in 0..10 {
            let cmd = env.command(100.0, 500.0, f64::from(i) * 0.1, 0.1, &s);
            if cmd.feed_hold && held_at.is_none() {
                held_at = Some(i);
            }
        }
        // 0.2 s must be exceeded: the third period above the limit trips it.
        assert_eq!(held_at, Some(2));
        // Latched: a normal force does not release it.
        assert!(env.command(100.0, 100.0, 1.0, 0.1, &s).feed_hold);
    }

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

    /// A random value that is sometimes wild: huge, negative, NaN or infinite.
    fn wild(rng: &mut Rng, typical: f64) -> f64 {
        match rng.next_u64() % 10 {
            0 => f64::NAN,
            1 => f64::INFINITY,
            2 => f64::NEG_INFINITY,
            3 => -typical * 10.0 * rng.uniform(),
            4 => typical * 1e6 * rng.uniform(),
            _ => typical * 2.0 * rng.uniform(),
        }
    }

    #[test]
    fn property_output_stays_inside_the_envelope_for_random_inputs() {
        let resolutions = [
            OverrideResolution::Continuous,
            OverrideResolution::WholePercent,
            OverrideResolution::Dial((0..16).map(|i| 10.0 * f64::from(i)).collect()),
        ];
        let mut rng = Rng::seed_from(2024);
        for case in 0..300 {
            let mut config = EnvelopeConfig::for_target(300.0);
            config.resolution = resolutions[case % 3].clone();
            config.min_override_pct = 10.0 * (rng.uniform() * 5.0).floor();
            config.max_override_pct =
                config.min_override_pct + 20.0 + 10.0 * (rng.uniform() * 10.0).floor();
            config.max_rate_pct_per_s = 5.0 + 200.0 * rng.uniform();
            config.arming_delay_s = 2.0 * rng.uniform();
            if rng.uniform() < 0.5 {
                config.arming_trigger = ArmingTrigger::ProgrammedFeed;
            }
            if rng.uniform() < 0.5 {
                config.fault_action = FaultAction::Fallback(config.min_override_pct);
            }
            let step = config.resolution.step_pct();
            let (min, max, rate) = (
                config.min_override_pct,
                config.max_override_pct,
                config.max_rate_pct_per_s,
            );
            let mut env = SafetyEnvelope::new(config.clone(), 1000.0).unwrap();
            let mut previous = env.output_pct();
            let mut t = 0.0;
            for _ in 0..200 {
                for _ in 0..10 {
                    let mut s = running_sample(t);
                    s.feed_phase_currents_a[0] = wild(&mut rng, 5.0);
                    s.spindle_running = rng.uniform() < 0.95;
                    s.time_since_spindle_start_s = wild(&mut rng, 3.0);
                    s.programmed_feed_mm_min = if rng.uniform() < 0.9 {
                        100.0
                    } else {
                        wild(&mut rng, 100.0)
                    };
                    env.observe(&s);
                    t += if rng.uniform() < 0.01 { 0.05 } else { 0.001 };
                }
                let dt = 0.01;
                let s = running_sample(t);
                let cmd = env.command(wild(&mut rng, 100.0), wild(&mut rng, 300.0), t, dt, &s);
                let out = cmd.override_pct;
                assert!(out.is_finite(), "case {case}: non-finite output");
                assert!(
                    out >= min && out <= max,
                    "case {case}: {out} outside [{min}, {max}]"
                );
                assert_eq!(
                    config.resolution.nearest(out, min, max),
                    Some(out),
                    "case {case}: {out} is not a machine position"
                );
                assert!(
                    (out - previous).abs() <= rate * dt + step + 1e-9,
                    "case {case}: jump {previous} → {out}"
                );
                previous = out;
            }
        }
    }

    #[test]
    fn property_each_run_of_non_finite_requests_is_one_fault_event_and_the_output_holds() {
        let mut rng = Rng::seed_from(4711);
        let mut episodes = 0;
        for case in 0..200 {
            let mut config = EnvelopeConfig::for_target(300.0);
            if case % 2 == 0 {
                config.resolution = OverrideResolution::Continuous;
            }
            config.min_override_pct = 10.0 * (rng.uniform() * 5.0).floor();
            config.max_override_pct = config.min_override_pct + 20.0 + 100.0 * rng.uniform();
            config.max_rate_pct_per_s = 5.0 + 200.0 * rng.uniform();
            config.arming_delay_s = rng.uniform();
            let step = config.resolution.step_pct();
            let (min, max, rate) = (
                config.min_override_pct,
                config.max_override_pct,
                config.max_rate_pct_per_s,
            );
            let mut env = envelope(config);
            let (mut previous, mut t, mut spindle_start_s) = (env.output_pct(), 0.0, 0.0);
            // Whether the last request the envelope listened to was not a number.
            let mut in_episode = false;
            let mut events = Vec::new();
            for period in 0..400 {
                let dt = 0.01 + 0.05 * rng.uniform();
                t += dt;
                // Now and then the spindle stops and starts again: disarmed, then re-armed.
                let mut s = running_sample(t);
                if rng.uniform() < 0.01 {
                    spindle_start_s = t;
                }
                s.time_since_spindle_start_s = t - spindle_start_s;
                // Runs of non-finite requests among finite ones, some far outside the limits.
                let request = match rng.next_u64() % 8 {
                    0 | 1 if in_episode || rng.uniform() < 0.3 => {
                        [f64::NAN, f64::INFINITY, f64::NEG_INFINITY][period % 3]
                    }
                    2 => -1e6 + 2e6 * rng.uniform(),
                    _ => 200.0 * rng.uniform(),
                };
                let out = env.command(request, 100.0, t, dt, &s).override_pct;
                events.clear();
                env.drain_events(&mut events);
                let faults = events
                    .iter()
                    .filter(
                        |e| matches!(e, SafetyEvent::ControllerFault { time_s } if *time_s == t),
                    )
                    .count();
                let listened = env.armed() && env.fault().is_none();
                let bad = !request.is_finite();
                let opens = listened && bad && !in_episode;
                assert_eq!(
                    faults,
                    usize::from(opens),
                    "case {case}, period {period}: {events:?}"
                );
                episodes += usize::from(opens);
                if listened {
                    in_episode = bad;
                    if bad {
                        assert_eq!(out, previous, "case {case}, period {period}: not held");
                    }
                }
                assert!(
                    out.is_finite() && out >= min && out <= max,
                    "case {case}: {out}"
                );
                assert!(
                    (out - previous).abs() <= rate * dt + step + 1e-9,
                    "case {case}, period {period}: jump {previous} → {out}"
                );
                previous = out;
            }
            let described = SafetyEvent::ControllerFault { time_s: t }.describe();
            assert!(described.contains("non-finite override"), "{described}");
        }
        assert!(episodes > 1000, "only {episodes} episodes");
    }
}
