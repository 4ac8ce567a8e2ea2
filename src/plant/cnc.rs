//! The simulated FANUC-style control: how the override reaches the machine and how the
//! commanded feed follows it.
//!
//! ## Override (papers 000 and 003)
//!
//! The controller's request reaches the CNC one of three ways ([`OverrideMode`]):
//!
//! * **Dial** — paper 000's FANUC 18M reads the feed-rate override as a 4-bit code on the PMC
//!   inputs X20.7, X20.4, X20.3 and X20.2 (the adaptive controller's "feed rate adjustor" drives
//!   them through opto-isolators; 16 grades). The percentage of each code is a machine-builder
//!   table in the ladder program ([`DialTable`], default 0, 10, …, 150 % for codes 0…15 read as a
//!   binary number with X20.7 the most significant bit; a Gray-coded switch is a permutation of
//!   this table).
//! * **Whole percent** — paper 003's DSP board drives the override 0–255 % in 1 % steps.
//! * **Continuous** — any value in 0–255 %.
//!
//! The PMC reads its inputs once per scan (default 8 ms), so a new override or feed hold takes
//! effect at the first interpolation period after the next scan.
//!
//! ## Feed
//!
//! Every interpolation period (default 8 ms) the CNC sets the commanded path feed
//!
//! ```text
//! v_target = programmed feed × override/100     (0 in feed hold, or until the spindle is at speed)
//! v_cmd    ← v_target, changed by at most a·T_ipo per period
//! v_cmd    ≤ √(v_j² + 2·a·d_j)  for every junction j ahead at distance d_j with speed limit v_j
//! ```
//!
//! Junction limits: a direction change θ above `exact_stop_angle_deg` stops the axes and waits
//! until the following error is inside `in_position_mm` (an in-position check: paper 003
//! Fig. 13's spindle-current dip at B); a smaller one limits the speed to
//! Δv/(2·sin(θ/2)) so that no axis jumps by more than Δv; the next block's feed limits it too; the
//! program end is a stop. On an arc of radius r the feed is limited to √(a_n·r).
//!
//! Between periods the commanded position advances linearly (v_cmd held), and the axes follow it
//! through a position loop of gain K_v: ṡ = K_v·(s_cmd − s), so the actual feed lags the command
//! with time constant 1/K_v (default 30 s⁻¹, 33 ms).
//!
//! A NaN override keeps the override applied last; ±∞ clamps to the mode's limits.

use serde::{Deserialize, Serialize};

use super::{in_range, positive, PlantError, S_PER_MIN};
use crate::machine::OverrideCommand;
use crate::math;

/// The four PMC inputs paper 000 wires to the feed-rate adjustor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
pub struct PmcInputs {
    /// X20.7, bit 3 of the code.
    pub x20_7: bool,
    /// X20.4, bit 2.
    pub x20_4: bool,
    /// X20.3, bit 1.
    pub x20_3: bool,
    /// X20.2, bit 0.
    pub x20_2: bool,
}

impl PmcInputs {
    /// The inputs that present dial code `code` (only its low four bits are used).
    ///
    /// ```
    /// use cutlab::plant::cnc::PmcInputs;
    /// let p = PmcInputs::from_code(0b1010);
    /// assert!(p.x20_7 && !p.x20_4 && p.x20_3 && !p.x20_2);
    /// assert_eq!(p.code(), 10);
    /// ```
    pub fn from_code(code: u8) -> Self {
        Self {
            x20_7: code & 0b1000 != 0,
            x20_4: code & 0b0100 != 0,
            x20_3: code & 0b0010 != 0,
            x20_2: code & 0b0001 != 0,
        }
    }

    /// The 4-bit code these inputs present.
    pub fn code(self) -> u8 {
        (u8::from(self.x20_7) << 3)
            | (u8::from(self.x20_4) << 2)
            | (u8::from(self.x20_3) << 1)
            | u8::from(self.x20_2)
    }
}

/// The machine builder's table: override percentage for each of the 16 dial codes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DialTable {
    /// Percentage of code 0…15.
    pub percent_by_code: [f64; 16],
}

impl Default for DialTable {
    /// [`DialTable::FANUC`].
    fn default() -> Self {
        Self::FANUC
    }
}

impl DialTable {
    /// FANUC's usual 16-position feed-rate override: 0, 10, …, 150 %.
    pub const FANUC: DialTable = DialTable {
        percent_by_code: [
            0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 80.0, 90.0, 100.0, 110.0, 120.0, 130.0,
            140.0, 150.0,
        ],
    };

    /// A table of 16 finite percentages in 0–255 (any order: the codes need not be monotonic).
    pub fn new(percent_by_code: [f64; 16]) -> Result<Self, PlantError> {
        for (i, p) in percent_by_code.iter().enumerate() {
            in_range(&format!("percent_by_code[{i}]"), *p, 0.0, 255.0)?;
        }
        Ok(Self { percent_by_code })
    }

    /// The code whose percentage is nearest to `pct` (the lower code on a tie); ±∞ picks the
    /// extreme positions. `None` for NaN.
    ///
    /// ```
    /// use cutlab::plant::cnc::DialTable;
    /// let t = DialTable::default();
    /// assert_eq!(t.code_for(73.0), Some(7));
    /// assert_eq!(t.code_for(f64::INFINITY), Some(15));
    /// assert_eq!(t.percent(t.code_for(36.0).unwrap()), 40.0);
    /// ```
    pub fn code_for(&self, pct: f64) -> Option<u8> {
        if pct.is_nan() {
            return None;
        }
        let (lo, hi) = self
            .percent_by_code
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        let pct = pct.clamp(lo, hi);
        let mut best = 0u8;
        let mut best_distance = f64::INFINITY;
        for (code, p) in self.percent_by_code.iter().enumerate() {
            let d = (p - pct).abs();
            if d < best_distance {
                best_distance = d;
                best = code as u8;
            }
        }
        Some(best)
    }

    /// The percentage of `code` (low four bits).
    pub fn percent(&self, code: u8) -> f64 {
        self.percent_by_code[usize::from(code & 0x0f)]
    }

    /// The positions in ascending order (for the safety envelope's quantiser).
    ///
    /// ```
    /// use cutlab::plant::cnc::DialTable;
    /// let p = DialTable::default().positions();
    /// assert_eq!((p.len(), p[15]), (16, 150.0));
    /// ```
    pub fn positions(&self) -> Vec<f64> {
        let mut p = self.percent_by_code.to_vec();
        p.sort_by(f64::total_cmp);
        p.dedup();
        p
    }
}

/// How the override reaches the CNC.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OverrideMode {
    /// A 16-position dial code on X20.7, X20.4, X20.3, X20.2 (paper 000).
    Dial(DialTable),
    /// 0–255 % in 1 % steps (paper 003).
    WholePercent,
    /// Any value in 0–255 %.
    Continuous,
}

impl Default for OverrideMode {
    fn default() -> Self {
        OverrideMode::Dial(DialTable::default())
    }
}

/// The override the machine applies, and the dial code that carried it.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct AppliedOverride {
    /// The override in percent.
    pub pct: f64,
    /// The dial code on the PMC inputs (dial mode only).
    pub dial_code: Option<u8>,
}

/// The highest override of the whole-percent and continuous modes (paper 003: 255 %).
pub const MAX_OVERRIDE_PCT: f64 = 255.0;

impl OverrideMode {
    /// Short name.
    pub fn name(&self) -> &'static str {
        match self {
            OverrideMode::Dial(_) => "dial",
            OverrideMode::WholePercent => "whole-percent",
            OverrideMode::Continuous => "continuous",
        }
    }

    /// What the machine applies when asked for `pct`, `previous` being what it applied before
    /// (kept for NaN).
    ///
    /// ```
    /// use cutlab::plant::cnc::{AppliedOverride, OverrideMode};
    /// let prev = AppliedOverride { pct: 100.0, dial_code: None };
    /// assert_eq!(OverrideMode::WholePercent.apply(87.6, prev).pct, 88.0);
    /// assert_eq!(OverrideMode::WholePercent.apply(300.0, prev).pct, 255.0);
    /// assert_eq!(OverrideMode::Continuous.apply(f64::NAN, prev).pct, 100.0);
    /// let dial = OverrideMode::default().apply(87.6, prev);
    /// assert_eq!((dial.pct, dial.dial_code), (90.0, Some(9)));
    /// ```
    pub fn apply(&self, pct: f64, previous: AppliedOverride) -> AppliedOverride {
        if pct.is_nan() {
            return previous;
        }
        match self {
            OverrideMode::Dial(table) => match table.code_for(pct) {
                Some(code) => {
                    // The adjustor writes the code; the ladder reads it back from the inputs.
                    let read = PmcInputs::from_code(code).code();
                    AppliedOverride {
                        pct: table.percent(read),
                        dial_code: Some(read),
                    }
                }
                None => previous,
            },
            OverrideMode::WholePercent => AppliedOverride {
                pct: pct.round().clamp(0.0, MAX_OVERRIDE_PCT),
                dial_code: None,
            },
            OverrideMode::Continuous => AppliedOverride {
                pct: pct.clamp(0.0, MAX_OVERRIDE_PCT),
                dial_code: None,
            },
        }
    }

    /// The highest override this mode can apply.
    ///
    /// ```
    /// use cutlab::plant::cnc::OverrideMode;
    /// assert_eq!(OverrideMode::default().max_pct(), 150.0);
    /// assert_eq!(OverrideMode::WholePercent.max_pct(), 255.0);
    /// ```
    pub fn max_pct(&self) -> f64 {
        match self {
            OverrideMode::Dial(t) => t.percent_by_code.iter().copied().fold(0.0, f64::max),
            _ => MAX_OVERRIDE_PCT,
        }
    }
}

/// Settings of the control.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CncConfig {
    /// How the override arrives. Default: the 16-position dial with FANUC's 0–150 % table.
    pub override_mode: OverrideMode,
    /// Interpolation period. Default 8 ms (FANUC Series 16/18 class, chosen).
    pub interpolation_period_s: f64,
    /// PMC ladder scan period. Default 8 ms (chosen).
    pub pmc_scan_s: f64,
    /// Acceleration of the path feed. Default 200 mm/s² (chosen).
    pub cutting_accel_mm_s2: f64,
    /// Centripetal acceleration limit on arcs. Default 200 mm/s² (chosen).
    pub centripetal_accel_mm_s2: f64,
    /// Highest cutting feed. Default 10 000 mm/min (chosen).
    pub max_feed_mm_min: f64,
    /// Speed jump an axis may take at a smooth corner, Δv. Default 100 mm/min (chosen).
    pub corner_speed_difference_mm_min: f64,
    /// Direction changes above this angle stop the axes at the corner and wait in position.
    /// Default 30° (chosen).
    pub exact_stop_angle_deg: f64,
    /// In-position width. Default 0.01 mm (chosen).
    pub in_position_mm: f64,
    /// Position loop gain K_v. Default 30 s⁻¹ (FANUC's usual 3000 × 0.01 s⁻¹).
    pub position_loop_gain_per_s: f64,
    /// Speed-arrival tolerance: motion waits until the spindle is within this fraction of its
    /// command. Default 0.05 (chosen).
    pub spindle_arrival_tolerance: f64,
}

impl Default for CncConfig {
    fn default() -> Self {
        Self {
            override_mode: OverrideMode::default(),
            interpolation_period_s: 0.008,
            pmc_scan_s: 0.008,
            cutting_accel_mm_s2: 200.0,
            centripetal_accel_mm_s2: 200.0,
            max_feed_mm_min: 10_000.0,
            corner_speed_difference_mm_min: 100.0,
            exact_stop_angle_deg: 30.0,
            in_position_mm: 0.01,
            position_loop_gain_per_s: 30.0,
            spindle_arrival_tolerance: 0.05,
        }
    }
}

impl CncConfig {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), PlantError> {
        if let OverrideMode::Dial(t) = &self.override_mode {
            DialTable::new(t.percent_by_code).map_err(|e| e.within("override_mode"))?;
        }
        positive("interpolation_period_s", self.interpolation_period_s)?;
        positive("pmc_scan_s", self.pmc_scan_s)?;
        positive("cutting_accel_mm_s2", self.cutting_accel_mm_s2)?;
        positive("centripetal_accel_mm_s2", self.centripetal_accel_mm_s2)?;
        positive("max_feed_mm_min", self.max_feed_mm_min)?;
        positive(
            "corner_speed_difference_mm_min",
            self.corner_speed_difference_mm_min,
        )?;
        in_range(
            "exact_stop_angle_deg",
            self.exact_stop_angle_deg,
            0.0,
            180.0,
        )?;
        positive("in_position_mm", self.in_position_mm)?;
        positive("position_loop_gain_per_s", self.position_loop_gain_per_s)?;
        in_range(
            "spindle_arrival_tolerance",
            self.spindle_arrival_tolerance,
            0.0,
            1.0,
        )?;
        Ok(())
    }
}

/// The PMC side: latches the override and feed hold once per scan.
///
/// ```
/// use cutlab::machine::OverrideCommand;
/// use cutlab::plant::cnc::{CncConfig, OverrideInput};
/// let mut input = OverrideInput::new(&CncConfig::default(), 1e-3).unwrap();
/// let cmd = OverrideCommand { override_pct: 64.0, feed_hold: false };
/// let (applied, _) = input.step(cmd);
/// assert_eq!(applied.pct, 60.0); // nearest dial position
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OverrideInput {
    mode: OverrideMode,
    scan: Every,
    applied: AppliedOverride,
    feed_hold: bool,
}

impl OverrideInput {
    /// An input reading at 100 % (until the first scan), sampled every `dt_s`.
    pub fn new(config: &CncConfig, dt_s: f64) -> Result<Self, PlantError> {
        config.validate()?;
        positive("dt_s", dt_s)?;
        let initial = config
            .override_mode
            .apply(100.0, AppliedOverride::default());
        Ok(Self {
            mode: config.override_mode,
            scan: Every::new(samples_per(config.pmc_scan_s, dt_s)),
            applied: initial,
            feed_hold: false,
        })
    }

    /// Advances one sample; at a scan, reads `command`. Returns the override in force and whether
    /// feed hold is set.
    #[inline(always)]
    pub fn step(&mut self, command: OverrideCommand) -> (AppliedOverride, bool) {
        if self.scan.tick() {
            self.applied = self.mode.apply(command.override_pct, self.applied);
            self.feed_hold = command.feed_hold;
        }
        (self.applied, self.feed_hold)
    }

    /// The override in force.
    pub fn applied(&self) -> AppliedOverride {
        self.applied
    }

    /// Back to the start.
    pub fn reset(&mut self) {
        self.scan.reset();
        self.applied = self.mode.apply(100.0, AppliedOverride::default());
        self.feed_hold = false;
    }
}

/// A clock that ticks on the first sample and every `period` samples after: the same as testing
/// a sample counter for a multiple of the period, without a division per sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Every {
    period: u64,
    left: u64,
}

impl Every {
    /// A clock of `period` samples (at least one), about to tick.
    pub(crate) fn new(period: u64) -> Self {
        Self {
            period: period.max(1),
            left: 0,
        }
    }

    /// Advances one sample; true on the samples where the period starts.
    #[inline(always)]
    pub(crate) fn tick(&mut self) -> bool {
        let now = self.left == 0;
        self.left = if now { self.period - 1 } else { self.left - 1 };
        now
    }

    /// Back to about to tick.
    pub(crate) fn reset(&mut self) {
        self.left = 0;
    }
}

/// Whole samples in `period_s` (at least one).
pub(crate) fn samples_per(period_s: f64, dt_s: f64) -> u64 {
    let n = (period_s / dt_s).round();
    if n >= 1.0 && n.is_finite() {
        n as u64
    } else {
        1
    }
}

/// One block of the path as the planner sees it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PlanBlock {
    /// Path length of the block.
    pub length_mm: f64,
    /// Programmed feed F.
    pub feed_mm_min: f64,
    /// Radius of an arc (∞ for a line), for the centripetal limit.
    pub radius_mm: f64,
    /// Direction of motion at the block's start (radians, counter-clockwise from +x).
    pub start_direction_rad: f64,
    /// Direction at its end.
    pub end_direction_rad: f64,
}

impl PlanBlock {
    /// A straight block along +x: the one block of the plants without a tool path.
    pub fn straight(length_mm: f64, feed_mm_min: f64) -> Self {
        Self {
            length_mm,
            feed_mm_min,
            radius_mm: f64::INFINITY,
            start_direction_rad: 0.0,
            end_direction_rad: 0.0,
        }
    }
}

/// The control as every plant drives it, one sample at a time: the PMC reads the override and
/// feed hold (at its scan), then the planner moves the axes along the blocks.
///
/// ```
/// use cutlab::machine::OverrideCommand;
/// use cutlab::plant::cnc::{CncConfig, Control, OverrideMode, PlanBlock};
/// let config = CncConfig { override_mode: OverrideMode::Continuous, ..CncConfig::default() };
/// let mut control = Control::new(&config, vec![PlanBlock::straight(100.0, 600.0)], 1e-3).unwrap();
/// let half = OverrideCommand { override_pct: 50.0, feed_hold: false };
/// let mut s = control.step(half, true);
/// for _ in 0..1000 { s = control.step(half, true); } // 1 s at 5 mm/s: 5 mm along
/// assert_eq!(s.applied.pct, 50.0);
/// assert!((s.cnc.feed_mm_min - 300.0).abs() < 1.0);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Control {
    input: OverrideInput,
    planner: FeedPlanner,
}

/// One sample of the [`Control`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControlStep {
    /// What the controller asked for.
    pub command: OverrideCommand,
    /// The override in force.
    pub applied: AppliedOverride,
    /// Feed hold in force.
    pub feed_hold: bool,
    /// What the CNC commanded and where the axes are.
    pub cnc: CncState,
}

impl Control {
    /// The control of `config` along `blocks`, sampled every `dt_s`.
    pub fn new(config: &CncConfig, blocks: Vec<PlanBlock>, dt_s: f64) -> Result<Self, PlantError> {
        Ok(Self {
            input: OverrideInput::new(config, dt_s)?,
            planner: FeedPlanner::new(blocks, *config, dt_s)?,
        })
    }

    /// Advances one sample under `command`; the axes move only once `spindle_ready`.
    #[inline(always)]
    pub fn step(&mut self, command: OverrideCommand, spindle_ready: bool) -> ControlStep {
        let (applied, feed_hold) = self.input.step(command);
        let cnc = self.planner.step(applied.pct, feed_hold, spindle_ready);
        ControlStep {
            command,
            applied,
            feed_hold,
            cnc,
        }
    }

    /// The override in force.
    pub fn applied(&self) -> AppliedOverride {
        self.input.applied()
    }

    /// Back to the start of the program at 100 %.
    pub fn reset(&mut self) {
        self.input.reset();
        self.planner.reset();
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Junction {
    /// Path position of the block's end.
    end_mm: f64,
    /// Speed limit at the end from the corner's geometry (0 = stop); ∞ if none.
    corner_limit_mm_min: f64,
    /// Whether the axes stop and wait in position here.
    exact_stop: bool,
}

/// What the CNC does in one sample.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct CncState {
    /// Programmed feed of the block being commanded.
    pub programmed_feed_mm_min: f64,
    /// Override in force.
    pub applied_override_pct: f64,
    /// Dial code on the PMC inputs, if the override comes through the dial.
    pub dial_code: Option<u8>,
    /// Feed hold in force.
    pub feed_hold: bool,
    /// Commanded path feed.
    pub commanded_feed_mm_min: f64,
    /// Commanded path position.
    pub commanded_position_mm: f64,
    /// Actual path position (after the position loop).
    pub position_mm: f64,
    /// Actual path feed.
    pub feed_mm_min: f64,
    /// Index of the block being commanded.
    pub block: usize,
    /// Waiting in position at a corner or the program end.
    pub in_position_wait: bool,
    /// The program has ended and the axes are in position.
    pub finished: bool,
}

/// The feed planner and position loop along a path of blocks.
///
/// ```
/// use cutlab::plant::cnc::{CncConfig, FeedPlanner, PlanBlock};
/// let block = PlanBlock { length_mm: 10.0, feed_mm_min: 600.0, radius_mm: f64::INFINITY,
///                         start_direction_rad: 0.0, end_direction_rad: 0.0 };
/// let mut p = FeedPlanner::new(vec![block], CncConfig::default(), 1e-3).unwrap();
/// let mut s = p.step(100.0, false, true);
/// for _ in 0..3000 { s = p.step(100.0, false, true); } // 10 mm at 10 mm/s ≈ 1 s
/// assert!(s.finished && (s.position_mm - 10.0).abs() < 0.01);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct FeedPlanner {
    config: CncConfig,
    blocks: Vec<PlanBlock>,
    junctions: Vec<Junction>,
    dt_s: f64,
    ipo: Every,
    loop_alpha: f64,
    block: usize,
    commanded_mm: f64,
    commanded_mm_min: f64,
    position_mm: f64,
    waiting: bool,
    done: bool,
}

impl FeedPlanner {
    /// A planner at the start of `blocks`, sampled every `dt_s`.
    pub fn new(blocks: Vec<PlanBlock>, config: CncConfig, dt_s: f64) -> Result<Self, PlantError> {
        config.validate()?;
        positive("dt_s", dt_s)?;
        if blocks.is_empty() {
            return Err(PlantError::new("blocks", "the program has no moves"));
        }
        for (i, b) in blocks.iter().enumerate() {
            positive(&format!("blocks[{i}].length_mm"), b.length_mm)?;
            positive(&format!("blocks[{i}].feed_mm_min"), b.feed_mm_min)?;
            if b.radius_mm.is_nan() || b.radius_mm <= 0.0 {
                return Err(PlantError::new(
                    format!("blocks[{i}].radius_mm"),
                    format!("must be > 0 (∞ for a line), got {}", b.radius_mm),
                ));
            }
        }
        let mut junctions = Vec::with_capacity(blocks.len());
        let mut end = 0.0;
        for (i, b) in blocks.iter().enumerate() {
            end += b.length_mm;
            let (limit, stop) = match blocks.get(i + 1) {
                None => (0.0, true),
                Some(next) => {
                    let turn = angle_between(b.end_direction_rad, next.start_direction_rad);
                    if turn > config.exact_stop_angle_deg.to_radians() {
                        (0.0, true)
                    } else if turn > 1e-9 {
                        (
                            config.corner_speed_difference_mm_min / (2.0 * math::sin(turn / 2.0)),
                            false,
                        )
                    } else {
                        (f64::INFINITY, false)
                    }
                }
            };
            junctions.push(Junction {
                end_mm: end,
                corner_limit_mm_min: limit,
                exact_stop: stop,
            });
        }
        Ok(Self {
            loop_alpha: 1.0 - math::exp(-config.position_loop_gain_per_s * dt_s),
            ipo: Every::new(samples_per(config.interpolation_period_s, dt_s)),
            config,
            blocks,
            junctions,
            dt_s,
            block: 0,
            commanded_mm: 0.0,
            commanded_mm_min: 0.0,
            position_mm: 0.0,
            waiting: false,
            done: false,
        })
    }

    /// Total path length.
    pub fn length_mm(&self) -> f64 {
        self.junctions.last().map_or(0.0, |j| j.end_mm)
    }

    /// Back to the start of the path.
    pub fn reset(&mut self) {
        self.ipo.reset();
        self.block = 0;
        self.commanded_mm = 0.0;
        self.commanded_mm_min = 0.0;
        self.position_mm = 0.0;
        self.waiting = false;
        self.done = false;
    }

    /// The speed limit inside block `i` at override `ov`: programmed feed × override, the
    /// machine's maximum and the arc's centripetal limit.
    fn block_limit(&self, i: usize, override_pct: f64) -> f64 {
        let b = &self.blocks[i];
        let centripetal = (self.config.centripetal_accel_mm_s2 * b.radius_mm).sqrt() * S_PER_MIN;
        (b.feed_mm_min * override_pct / 100.0)
            .min(self.config.max_feed_mm_min)
            .min(centripetal)
    }

    /// The braking limit from the junctions ahead of the commanded position.
    fn braking_limit(&self, override_pct: f64) -> f64 {
        let a = self.config.cutting_accel_mm_s2;
        let horizon_mm = {
            let v = self.config.max_feed_mm_min / S_PER_MIN;
            v * v / (2.0 * a) + 1.0
        };
        let mut limit = f64::INFINITY;
        for j in self.block..self.junctions.len() {
            let junction = &self.junctions[j];
            let d = (junction.end_mm - self.commanded_mm).max(0.0);
            let next_limit = match self.blocks.get(j + 1) {
                Some(_) if !junction.exact_stop => self.block_limit(j + 1, override_pct),
                _ => 0.0,
            };
            let v_end = junction.corner_limit_mm_min.min(next_limit) / S_PER_MIN;
            limit = limit.min((v_end * v_end + 2.0 * a * d).sqrt() * S_PER_MIN);
            if junction.exact_stop || d > horizon_mm {
                break;
            }
        }
        limit
    }

    /// Advances one sample with the override in force, feed hold, and whether the spindle is
    /// ready (at speed) for motion.
    #[inline(always)]
    pub fn step(&mut self, override_pct: f64, feed_hold: bool, spindle_ready: bool) -> CncState {
        if self.ipo.tick() {
            self.interpolation_tick(override_pct, feed_hold, spindle_ready);
        }
        // Commanded position advances linearly within the period, never past the next stop.
        if !self.waiting && !self.done {
            let stop_at = self.next_stop_mm();
            self.commanded_mm += self.commanded_mm_min / S_PER_MIN * self.dt_s;
            while self.block + 1 < self.junctions.len()
                && !self.junctions[self.block].exact_stop
                && self.commanded_mm >= self.junctions[self.block].end_mm
            {
                self.block += 1;
            }
            if self.commanded_mm >= stop_at {
                self.commanded_mm = stop_at;
                self.commanded_mm_min = 0.0;
                self.waiting = true;
            }
        }
        let before = self.position_mm;
        self.position_mm += self.loop_alpha * (self.commanded_mm - self.position_mm);
        let feed_mm_min = (self.position_mm - before) / self.dt_s * S_PER_MIN;
        let in_position =
            (self.commanded_mm - self.position_mm).abs() <= self.config.in_position_mm;
        let finished = self.done && in_position;
        CncState {
            programmed_feed_mm_min: self.blocks[self.block].feed_mm_min,
            applied_override_pct: override_pct,
            dial_code: None,
            feed_hold,
            commanded_feed_mm_min: self.commanded_mm_min,
            commanded_position_mm: self.commanded_mm,
            position_mm: self.position_mm,
            feed_mm_min,
            block: self.block,
            in_position_wait: self.waiting,
            finished,
        }
    }

    fn next_stop_mm(&self) -> f64 {
        self.junctions[self.block..]
            .iter()
            .find(|j| j.exact_stop)
            .map_or(self.length_mm(), |j| j.end_mm)
    }

    fn interpolation_tick(&mut self, override_pct: f64, feed_hold: bool, spindle_ready: bool) {
        if self.done {
            self.commanded_mm_min = 0.0;
            return;
        }
        if self.waiting {
            let in_position =
                (self.commanded_mm - self.position_mm).abs() <= self.config.in_position_mm;
            if !in_position {
                return;
            }
            if self.block + 1 >= self.blocks.len() {
                self.done = true;
                return;
            }
            self.waiting = false;
            self.block += 1;
        }
        let a_per_tick_mm_min =
            self.config.cutting_accel_mm_s2 * self.config.interpolation_period_s * S_PER_MIN;
        let target = if feed_hold || !spindle_ready {
            0.0
        } else {
            self.block_limit(self.block, override_pct)
        };
        let v = self.commanded_mm_min;
        let ramped = if target > v {
            (v + a_per_tick_mm_min).min(target)
        } else {
            (v - a_per_tick_mm_min).max(target)
        };
        self.commanded_mm_min = ramped.min(self.braking_limit(override_pct)).max(0.0);
    }
}

/// The unsigned angle between two directions, in [0, π].
fn angle_between(a: f64, b: f64) -> f64 {
    let d = (b - a).rem_euclid(std::f64::consts::TAU);
    if d > std::f64::consts::PI {
        std::f64::consts::TAU - d
    } else {
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(length_mm: f64, feed: f64, direction: f64) -> PlanBlock {
        PlanBlock {
            length_mm,
            feed_mm_min: feed,
            radius_mm: f64::INFINITY,
            start_direction_rad: direction,
            end_direction_rad: direction,
        }
    }

    #[test]
    fn dial_codes_round_trip_through_the_pmc_inputs() {
        for code in 0..16u8 {
            assert_eq!(PmcInputs::from_code(code).code(), code);
        }
        let t = DialTable::default();
        for code in 0..16u8 {
            assert_eq!(t.code_for(t.percent(code)), Some(code));
        }
    }

    #[test]
    fn a_permuted_dial_table_still_reads_the_nearest_position() {
        let mut p = DialTable::default().percent_by_code;
        p.swap(3, 12);
        let t = DialTable::new(p).unwrap();
        assert_eq!(t.code_for(118.0), Some(3));
        assert_eq!(t.percent(3), 120.0);
        assert!(DialTable::new([300.0; 16]).is_err());
    }

    #[test]
    fn acceleration_is_limited() {
        let cfg = CncConfig::default();
        let mut p = FeedPlanner::new(vec![line(1000.0, 3000.0, 0.0)], cfg, 1e-3).unwrap();
        let mut last = 0.0;
        let mut max_step = 0.0f64;
        for _ in 0..400 {
            let s = p.step(100.0, false, true);
            max_step = max_step.max(s.commanded_feed_mm_min - last);
            last = s.commanded_feed_mm_min;
        }
        let per_tick = cfg.cutting_accel_mm_s2 * cfg.interpolation_period_s * 60.0;
        assert!(max_step <= per_tick + 1e-9, "{max_step} > {per_tick}");
        assert!((last - 3000.0).abs() < 1e-9);
    }

    #[test]
    fn feed_hold_stops_and_resuming_continues() {
        let mut p =
            FeedPlanner::new(vec![line(100.0, 600.0, 0.0)], CncConfig::default(), 1e-3).unwrap();
        for _ in 0..500 {
            p.step(100.0, false, true);
        }
        let mut s = p.step(100.0, true, true);
        for _ in 0..500 {
            s = p.step(100.0, true, true);
        }
        assert!(s.feed_mm_min.abs() < 1e-3, "{s:?}");
        let held_at = s.position_mm;
        for _ in 0..500 {
            s = p.step(100.0, false, true);
        }
        assert!(s.position_mm > held_at + 1.0);
    }

    #[test]
    fn a_right_angle_stops_and_waits_in_position() {
        let blocks = vec![
            line(10.0, 600.0, 0.0),
            line(10.0, 600.0, std::f64::consts::FRAC_PI_2),
        ];
        let mut p = FeedPlanner::new(blocks, CncConfig::default(), 1e-3).unwrap();
        let mut min_feed_near_corner = f64::INFINITY;
        let mut waited = false;
        for _ in 0..4000 {
            let s = p.step(100.0, false, true);
            if (s.position_mm - 10.0).abs() < 0.05 {
                min_feed_near_corner = min_feed_near_corner.min(s.feed_mm_min);
            }
            waited |= s.in_position_wait && s.block == 0;
        }
        assert!(waited);
        // Stopped until the following error is inside 0.01 mm: K_v·0.01 mm = 18 mm/min.
        assert!(
            min_feed_near_corner < 0.05 * 600.0,
            "{min_feed_near_corner}"
        );
    }

    #[test]
    fn a_shallow_corner_limits_the_speed_without_stopping() {
        let turn = 10f64.to_radians();
        let blocks = vec![line(50.0, 3000.0, 0.0), line(50.0, 3000.0, turn)];
        let cfg = CncConfig::default();
        let mut p = FeedPlanner::new(blocks, cfg, 1e-3).unwrap();
        let limit = cfg.corner_speed_difference_mm_min / (2.0 * (turn / 2.0).sin());
        let mut at_corner = f64::NAN;
        for _ in 0..3000 {
            let s = p.step(100.0, false, true);
            assert!(!s.in_position_wait || s.block == 1);
            if s.block == 1 && at_corner.is_nan() {
                at_corner = s.commanded_feed_mm_min;
            }
        }
        assert!(
            at_corner <= limit + 200.0 && at_corner > 0.0,
            "{at_corner} vs {limit}"
        );
    }

    #[test]
    fn motion_waits_for_the_spindle() {
        let mut p =
            FeedPlanner::new(vec![line(10.0, 600.0, 0.0)], CncConfig::default(), 1e-3).unwrap();
        for _ in 0..100 {
            assert_eq!(p.step(100.0, false, false).position_mm, 0.0);
        }
    }

    #[test]
    fn empty_programs_and_bad_blocks_are_refused() {
        assert!(FeedPlanner::new(vec![], CncConfig::default(), 1e-3).is_err());
        let e =
            FeedPlanner::new(vec![line(0.0, 100.0, 0.0)], CncConfig::default(), 1e-3).unwrap_err();
        assert_eq!(e.field, "blocks[0].length_mm");
    }
}
