//! The fixed-feed reference runs the savings are measured against: the programmed feed at 100 %,
//! and the highest fixed override that keeps the peak force at the target — the feed a machinist
//! would fix for the part's worst spot.

use serde::Serialize;

use super::definition::{machine_max_override_pct, RunSpec};
use super::error::LoopError;
use super::lab::{preset_plan, LabRun, RunResult};
use super::metrics::with_savings;
use super::settings::Plan;
use crate::control::registry::{ControllerConfig, ControllerKind};
use crate::estimation::estimator::Calibration;
use crate::plant::presets::PlantEdits;
use crate::plant::Preset;
use crate::safety::chip_load_band_pct;
use crate::work::{Progress, Work};

/// The reference runs of the savings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct References {
    /// Cycle time at the programmed feed (fixed 100 %).
    #[serde(deserialize_with = "crate::estimation::null_as_nan")]
    pub programmed_cycle_time_s: f64,
    /// The highest fixed override whose peak regulated force stays at or below the target (NaN
    /// when not even the lowest the envelope applies does, and with it the cycle time and that
    /// saving): the feed a machinist would fix for the part's worst spot, judged against the same
    /// force the controllers are asked to hold (not the 1.2 × target limit, which would let the
    /// fixed feed run 20 % harder than any controller aims to). Always an override the safety
    /// envelope applies as set in every block of the program ([`fixed_override_range_pct`]): the
    /// override the machine ran at, not one the chip-load window raised or lowered.
    #[serde(deserialize_with = "crate::estimation::null_as_nan")]
    pub safe_fixed_override_pct: f64,
    /// Cycle time at that override.
    #[serde(deserialize_with = "crate::estimation::null_as_nan")]
    pub safe_fixed_cycle_time_s: f64,
}

/// Runs the fixed-feed references for `spec`'s preset and settings: 100 %, and a search for the
/// highest fixed override that keeps the peak force at or below the target (to
/// [`REFERENCE_RESOLUTION_PCT`]), among those the envelope applies ([`fixed_override_range_pct`]).
pub fn references(spec: &RunSpec) -> Result<References, LoopError> {
    ReferenceSearch::new(spec)?.run_to_end()
}

/// The slowest fixed feed the search considers where nothing else bounds it (a machine without a
/// chip-load window), percent: a fixed 0 % never finishes the program.
const SLOWEST_FIXED_PCT: f64 = 1.0;

/// The fixed overrides the safety envelope applies as set in every block of `spec`'s program, %:
/// from the highest of the blocks' lowest overrides to the lowest of their highest. In each block
/// the envelope narrows any override to the chip-load window at that block's programmed feed and
/// spindle speed, within a fixed-feed run's band (up to the machine's highest override), and the
/// machine takes the nearest of its override positions; a fixed override is one number for the
/// whole program, so the one it runs at everywhere lies in this range. Below it, the block with
/// the highest floor runs at its floor whatever is set (a fixed 14 % on kim-circular-taper's
/// 170 mm/min runs as 36 %); above it, the block with the lowest ceiling runs at its ceiling.
/// Where the blocks' windows share no override, the range is the highest floor alone (which the
/// envelope then lowers in the blocks whose ceiling lies below it). At least
/// 1 % (the slowest fixed feed considered) where the machine has no window.
///
/// ```
/// use cutlab::closed_loop::definition::RunSpec;
/// use cutlab::closed_loop::references::fixed_override_range_pct;
/// use cutlab::control::registry::ControllerKind;
/// use cutlab::plant::Preset;
/// // 200 mm/min at 1000 rpm on two teeth is 0.1 mm per tooth; SM45C's window for a Ø20 mm
/// // cutter, 0.01–0.15 mm, is 10–150 %.
/// let spec = RunSpec::new(Preset::KimStepDoc, ControllerKind::Fixed);
/// assert_eq!(fixed_override_range_pct(&spec).unwrap(), (10.0, 150.0));
/// ```
pub fn fixed_override_range_pct(spec: &RunSpec) -> Result<(f64, f64), LoopError> {
    let plan = preset_plan(&fixed_feed_spec(spec, 100.0)?)?;
    let limits = &plan.limits;
    let band = (
        limits.min_override_pct.max(SLOWEST_FIXED_PCT),
        limits.max_override_pct,
    );
    // What the machine runs at in a block whose band is [lo, hi], set to `pct` inside it.
    let applied =
        |pct: f64, (lo, hi): (f64, f64)| limits.resolution.nearest(pct, lo, hi).unwrap_or(pct);
    let blocks: Vec<(f64, f64)> = spec
        .preset
        .edited_scenario_spec(&spec.plant)
        .map(|program| {
            program
                .moves
                .iter()
                .map(|m| {
                    chip_load_band_pct(plan.chip_load.as_ref(), band, m.feed_mm_min, m.spindle_rpm)
                })
                .collect()
        })
        .unwrap_or_default();
    let blocks = if blocks.is_empty() {
        vec![band]
    } else {
        blocks
    };
    let floor_pct = blocks
        .iter()
        .map(|&b| applied(b.0, b))
        .fold(f64::NEG_INFINITY, f64::max);
    let ceiling_pct = blocks
        .iter()
        .map(|&b| applied(b.1, b))
        .fold(f64::INFINITY, f64::min);
    Ok((floor_pct, ceiling_pct.max(floor_pct)))
}

/// The search stops once the bracket is this narrow, percent of override.
pub const REFERENCE_RESOLUTION_PCT: f64 = 1.0;

/// Probes the force model may place before the search falls back to halving the bracket.
pub const GUIDED_PROBES: usize = 4;

/// A probe that only needs a verdict is looked at after this many control periods.
const VERDICT_CHECK_PERIODS: usize = 20;

/// The reference runs of [`references`], done a piece at a time so a browser can show progress
/// and stay responsive: the programmed feed at 100 %, then probes of fixed overrides.
///
/// The probes lie in the range the envelope applies ([`fixed_override_range_pct`]): below its
/// floor every fixed override is the same run as the floor (the envelope raises it to the
/// chip-load window), so a probe there would only repeat one, and report an override the machine
/// never ran at. The floor is run once: last, when nothing above it kept the force, or next, as
/// soon as the line through the runs so far places the target at or just above it; if it breaks
/// the target too (the run is stopped there), no fixed feed is safe (NaN).
///
/// The peak force of a fixed-feed run grows with the override, nearly in a straight line (the
/// chip's force with the feed per tooth, plus the edge forces), so the probes are placed where
/// the line through the runs so far meets the target (through the origin while only one run is
/// known), inside the bracket of the highest override that passed and the lowest that failed;
/// after [`GUIDED_PROBES`] such probes, or when the line gives nothing, the bracket is halved.
/// For a peak that rises with the override this finds the same answer as a bisection, in three
/// to five runs instead of nine. Once two whole runs have fixed the line, a probe that breaks the
/// target is stopped there (the rest of its cut cannot lower its peak). The teach cut is made
/// once, by the first run (or given: [`ReferenceSearch::calibrated`]); the others reuse its
/// calibration (they differ from it only in controller and override band, which the teach cut
/// does not depend on).
pub struct ReferenceSearch {
    spec: RunSpec,
    run: LabRun,
    /// The fixed override of `run`, percent, and what it is for.
    running: (f64, RunKind),
    calibration: Option<Calibration>,
    programmed_cycle_time_s: f64,
    /// The force no reference run may exceed: the target the controllers hold.
    reference_force_n: f64,
    /// The lowest fixed override the envelope applies as set: the bracket's floor.
    floor_pct: f64,
    /// Whether a run at the floor has broken the target (no fixed feed is safe).
    floor_broke: bool,
    /// The highest override known to keep the force (the floor until one is run).
    low_pct: f64,
    /// The lowest override known to break it (just above the highest the envelope applies until
    /// one is run: the answer lies in [low, high)).
    high_pct: f64,
    best_cycle_time_s: Option<f64>,
    /// (override, peak force) of every whole run so far: the line's points.
    peaks: Vec<(f64, f64)>,
    /// Rows of `run`'s trace already compared with the reference force.
    rows_checked: usize,
    guided_probes: usize,
    runs_done: usize,
    /// The largest fraction shown so far (the number of runs is not known in advance).
    shown_fraction: std::cell::Cell<f64>,
    /// The runs the search is expected to take, as first estimated: the total a person reads
    /// rises only once the search has run that many.
    expected_runs: usize,
    found: Option<References>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum RunKind {
    Programmed,
    Probe,
    /// No probe stayed under the target: the floor, checked like the others.
    Lowest,
}

impl ReferenceSearch {
    /// Starts with the programmed-feed run (and its teach cut).
    pub fn new(spec: &RunSpec) -> Result<Self, LoopError> {
        let run = LabRun::new(&fixed_feed_spec(spec, 100.0)?)?;
        Self::starting(spec, run, None)
    }

    /// Starts with the programmed-feed run, calibrated by `calibration` (from a teach cut of a
    /// run on the same scenario: [`super::lab::TeachKey`]) instead of a teach cut of its own.
    pub fn calibrated(spec: &RunSpec, calibration: Calibration) -> Result<Self, LoopError> {
        let run = LabRun::calibrated(&fixed_feed_spec(spec, 100.0)?, calibration.clone())?;
        Self::starting(spec, run, Some(calibration))
    }

    fn starting(
        spec: &RunSpec,
        run: LabRun,
        calibration: Option<Calibration>,
    ) -> Result<Self, LoopError> {
        let (floor_pct, ceiling_pct) = fixed_override_range_pct(spec)?;
        // The programmed feed is a probe at the override the machine runs it at.
        let programmed_pct = 100.0_f64.clamp(floor_pct, ceiling_pct);
        Ok(Self {
            run,
            running: (programmed_pct, RunKind::Programmed),
            spec: spec.clone(),
            calibration,
            programmed_cycle_time_s: f64::NAN,
            reference_force_n: f64::NAN,
            floor_pct,
            floor_broke: false,
            low_pct: floor_pct,
            high_pct: ceiling_pct + REFERENCE_RESOLUTION_PCT,
            best_cycle_time_s: None,
            peaks: Vec::new(),
            rows_checked: 0,
            guided_probes: 0,
            runs_done: 0,
            shown_fraction: std::cell::Cell::new(0.0),
            expected_runs: 1 + Self::probes_expected(
                ceiling_pct + REFERENCE_RESOLUTION_PCT - floor_pct,
            ),
            found: None,
        })
    }

    /// The references, once found.
    pub fn found(&self) -> Option<References> {
        self.found
    }

    /// The calibration of the scenario's teach cut, once made (or given).
    pub fn calibration(&self) -> Option<&Calibration> {
        self.calibration.as_ref()
    }

    /// The reference runs ended so far, the programmed feed's included (a probe stopped once it
    /// broke the target counts as one).
    pub fn runs_done(&self) -> usize {
        self.runs_done
    }

    /// The probes expected after the programmed run in a bracket `width_pct` wide: about one per
    /// halving of it, at most three, since the line guides them.
    fn probes_expected(width_pct: f64) -> usize {
        (width_pct.max(1.0).log2().ceil() as usize).min(3)
    }

    /// Narrows the bracket after a run at `pct` that broke the target (or did not finish).
    fn broke_at(&mut self, pct: f64) {
        self.high_pct = self.high_pct.min(pct);
        self.floor_broke |= pct <= self.floor_pct;
    }

    /// Whether the run under way has already broken the reference force, checking the rows added
    /// since the last look.
    fn run_broke_target(&mut self) -> bool {
        let Some(trace) = self.run.trace() else {
            return false;
        };
        let rows = &trace.rows[self.rows_checked.min(trace.rows.len())..];
        self.rows_checked = trace.rows.len();
        rows.iter()
            .any(|r| r.force_n.is_finite() && r.force_n > self.reference_force_n)
    }

    /// Where the straight line through the whole runs so far (the last two; through the origin
    /// while there is one) reaches the reference force, if it rises.
    fn line_reaches_target_pct(&self) -> Option<f64> {
        let target = self.reference_force_n;
        let pct = match self.peaks.as_slice() {
            [] => return None,
            [(p, f)] => p * target / f,
            [.., (p0, f0), (p1, f1)] => {
                let slope = (f1 - f0) / (p1 - p0);
                // A line that does not rise (or a NaN) says nothing: halve the bracket instead.
                if slope.is_nan() || slope <= 0.0 {
                    return None;
                }
                p1 + (target - f1) / slope
            }
        };
        pct.is_finite().then_some(pct)
    }

    /// The next override to run, or `None` when the bracket is down to
    /// [`REFERENCE_RESOLUTION_PCT`].
    fn next_probe_pct(&mut self) -> Option<f64> {
        if self.high_pct - self.low_pct <= REFERENCE_RESOLUTION_PCT {
            return None;
        }
        let (inside_low, inside_high) = (
            self.low_pct + REFERENCE_RESOLUTION_PCT,
            self.high_pct - REFERENCE_RESOLUTION_PCT,
        );
        let guided = (self.guided_probes < GUIDED_PROBES)
            .then(|| self.line_reaches_target_pct())
            .flatten();
        let pct = match guided {
            Some(pct) => {
                self.guided_probes += 1;
                pct.floor()
            }
            None => ((self.low_pct + self.high_pct) / 2.0).round(),
        };
        Some(pct.clamp(inside_low, inside_high))
    }

    /// Whether the floor is still to be checked and the line already places the target at or
    /// just above it: no probe between could keep the force where the floor does not, so the
    /// floor decides next (a verdict, stopped where it breaks), instead of last.
    fn floor_decides(&self) -> bool {
        self.best_cycle_time_s.is_none()
            && !self.floor_broke
            && self
                .line_reaches_target_pct()
                .is_some_and(|pct| pct <= self.floor_pct + REFERENCE_RESOLUTION_PCT)
    }

    /// The run after one ended: the next probe, the floor's check, or the answer.
    fn next(&mut self) -> Result<bool, LoopError> {
        let probe = if self.floor_decides() {
            None
        } else {
            self.next_probe_pct()
        };
        let next = match probe {
            Some(pct) => Some((pct, RunKind::Probe)),
            None if self.best_cycle_time_s.is_none() && !self.floor_broke => {
                Some((self.floor_pct, RunKind::Lowest))
            }
            None => None,
        };
        match (
            next,
            self.best_cycle_time_s.or_else(|| self.no_safe_fixed_feed()),
        ) {
            (Some((pct, kind)), _) => {
                let spec = fixed_feed_spec(&self.spec, pct)?;
                self.run = match &self.calibration {
                    Some(c) => LabRun::calibrated(&spec, c.clone())?,
                    None => LabRun::new(&spec)?,
                };
                self.running = (pct, kind);
                self.rows_checked = 0;
                Ok(false)
            }
            (None, Some(best)) => {
                self.found = Some(References {
                    programmed_cycle_time_s: self.programmed_cycle_time_s,
                    safe_fixed_override_pct: self.low_pct,
                    safe_fixed_cycle_time_s: best,
                });
                Ok(true)
            }
            (None, None) => Err(LoopError::NoReference),
        }
    }

    /// After the floor also broke the target, the answer is that no fixed feed keeps the force
    /// at the target (the chip-load window allows none slower, or the cut's own floor, its edge
    /// forces at the deepest point, lies above it): NaN, which leaves the saving against a safe
    /// fixed feed undefined rather than measured against a crawl that is not safe either.
    fn no_safe_fixed_feed(&mut self) -> Option<f64> {
        self.floor_broke.then(|| {
            self.low_pct = f64::NAN;
            f64::NAN
        })
    }
}

impl Work for ReferenceSearch {
    type Output = References;
    type Error = LoopError;

    /// Does at most `periods` control periods of work.
    fn advance(&mut self, periods: usize) -> Result<bool, LoopError> {
        if self.found.is_some() {
            return Ok(true);
        }
        let (pct, kind) = self.running;
        // Once the line is fixed by two whole runs, a probe needs no more than a verdict: it is
        // looked at every few periods and stopped when it breaks the target. (The answer does not
        // depend on where it stops, nor on the budget: such a probe adds no point to the line.)
        // The floor's check is a verdict too: if it breaks, no fixed feed is safe.
        let verdict_only =
            (kind == RunKind::Probe && self.peaks.len() >= 2) || kind == RunKind::Lowest;
        let mut left = periods.max(1);
        let finished = loop {
            let piece = if verdict_only {
                left.min(VERDICT_CHECK_PERIODS)
            } else {
                left
            };
            left -= piece;
            if self.run.advance(piece)? {
                break true;
            }
            if verdict_only && self.run_broke_target() {
                self.runs_done += 1;
                self.broke_at(pct);
                return self.next();
            }
            if left == 0 {
                break false;
            }
        };
        if !finished {
            return Ok(false);
        }
        let result = self.run.finish()?;
        self.runs_done += 1;
        if kind == RunKind::Programmed {
            self.programmed_cycle_time_s = result.metrics.cycle_time_s;
            self.reference_force_n = result.settings.target_force_n;
            self.calibration.get_or_insert(result.calibration);
        }
        let peak_n = result.metrics.peak_force_n;
        let kept = peak_n <= self.reference_force_n && result.trace.completed;
        if result.trace.completed && (kept || !verdict_only) {
            self.peaks.push((pct, peak_n));
        }
        // The programmed feed and the floor's check are probes too.
        if !kept {
            self.broke_at(pct);
        } else if pct >= self.low_pct {
            self.low_pct = pct;
            self.best_cycle_time_s = Some(result.metrics.cycle_time_s);
        }
        self.next()
    }

    /// The fixed override of the current run and the rough fraction done.
    fn progress(&self) -> Progress {
        // The first estimate stands while the search keeps within it (a total that grew with
        // every run, 4, 5, 6, read as a goal moving away); past it, the run under way is the last
        // one counted.
        let expected = if self.found.is_some() {
            self.runs_done.max(1)
        } else {
            self.expected_runs.max(self.runs_done + 1)
        };
        let label = format!(
            "Savings: reference run {} of about {expected}, fixed feed at {:.0} %",
            self.runs_done + 1,
            self.running.0
        );
        let fraction = ((self.runs_done as f64 + self.run.progress().fraction) / expected as f64)
            .clamp(0.0, 1.0)
            .max(self.shown_fraction.get());
        self.shown_fraction.set(fraction);
        Progress::new(label, fraction)
    }

    fn finish(&mut self) -> Result<References, LoopError> {
        self.found.ok_or(LoopError::NotFinished)
    }
}

/// `spec` at a fixed override from start to end, not bounded by the envelope's override band:
/// the program as a machinist would run it without adaptive control.
pub fn fixed_feed_spec(spec: &RunSpec, override_pct: f64) -> Result<RunSpec, LoopError> {
    let mut s = spec.clone();
    s.controller = ControllerConfig::new(ControllerKind::Fixed);
    s.controller
        .set("override_pct", override_pct)
        .map_err(LoopError::Controller)?;
    s.settings.min_override_pct = Some(0.0);
    s.settings.max_override_pct = Some(machine_max_override_pct(spec.preset));
    s.settings.arming_override_pct = Some(override_pct);
    Ok(s)
}

/// What a scenario's fixed-feed references depend on: the preset, the seed, the machine edits and
/// the settings of its run at the fixed 100 % feed, resolved to values. Two specs that spell the
/// same settings differently (a default left unset, or typed in) have the same key, and their
/// reference searches give the same result; the controller plays no part.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioKey {
    preset: Preset,
    seed: u64,
    plant: PlantEdits,
    plan: Plan,
}

impl ScenarioKey {
    /// The key of `spec`'s scenario.
    pub fn of(spec: &RunSpec) -> Result<Self, LoopError> {
        let fixed = fixed_feed_spec(spec, 100.0)?;
        Ok(Self {
            preset: spec.preset,
            seed: spec.seed,
            plant: spec.plant,
            plan: preset_plan(&fixed)?,
        })
    }
}

/// Fills a result's savings from the references (none for a program that runs for a time:
/// [`with_savings`]).
pub fn apply_references(result: &mut RunResult, references: &References) {
    result.metrics = with_savings(
        result.metrics.clone(),
        result.spec.preset.program_length(),
        Some(references.programmed_cycle_time_s),
        Some(references.safe_fixed_cycle_time_s),
    );
}
