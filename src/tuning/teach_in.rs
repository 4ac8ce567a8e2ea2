//! Teach-in: what one teach cut learned, and the settings proposed from it — as commercial
//! adaptive feed controls do: cut the part once, learn the load the program gives and how the
//! current shows it, then start from what was measured.
//!
//! ```text
//! a simulated teach cut (a preset)  ── teach_in ─────────────┐
//! a saved calibration (cutlab host)  ── teach_in_calibration ─┼─► Learned ─► propose ─► Proposal
//! a logged teach cut (any CSV)      ── teach_in_log ──────────┘
//! ```
//!
//! Each source gives a [`Learned`]: the force the program produced at 100 % override, the
//! calibrated current line where the program runs (idle current, sensitivity, the current range
//! the fit saw, the spread of one estimate) and that operating point. [`propose`] is the one
//! function that turns it into a target, its reference current and a threshold gap:
//!
//! * **target** = [`DEFAULT_TARGET_FRACTION`] (80 %) of the force at 100 % override. The metrics and
//!   the threshold controller put the force limit 20 % above the target, so this target puts
//!   that limit (96 %) just under the load the programmer accepted at 100 %; where the cut is
//!   lighter the control raises the feed, where it is heavier it slows below the program.
//! * bounded by the calibration: a target whose current lies outside the currents the fit saw
//!   would be held on an extrapolated line, so it is moved to the nearest force the calibrated
//!   current range covers ([`TargetBasis`] says so);
//! * **reference current** = the calibrated line at the target (how papers 000, 002 and 003
//!   state their targets);
//! * **threshold gap** = ±[`NOISE_SIGMAS`] σ of one period's estimate (the fit's residual), at
//!   least [`MIN_PROPOSED_GAP_PCT`] of the target: noise alone does not cross it.
//!
//! The preset's own (paper's) target, where it has one, is reported beside the proposal for
//! comparison ([`PaperTarget`]); it never feeds the proposal.

use serde::Serialize;

use super::TuningError;
use crate::closed_loop::calibration_file::CalibrationFile;
use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::lab::settled_settings;
use crate::closed_loop::settings::{OperatingPoint, DEFAULT_TARGET_FRACTION};
use crate::estimation::current_force::{FeedCurrentModel, Range, SpindleCurrentModel};
use crate::estimation::cut_forces::CutGeometry;
use crate::estimation::estimator::{Calibration, Estimator, Feedback};
use crate::estimation::teach_fit::load_level_warnings;
use crate::log::period_log::{calibrate_log, LogTable};

/// The narrowest threshold gap a teach-in proposes, % of target.
pub const MIN_PROPOSED_GAP_PCT: f64 = 5.0;
/// The proposed gap spans ± this many standard deviations of one period's estimate.
pub const NOISE_SIGMAS: f64 = 3.0;

/// The calibrated current-to-force line at the operating point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CalibratedLine {
    /// Current with no cutting force, A.
    pub idle_current_a: f64,
    /// Current per newton, A/N.
    pub sensitivity_a_per_n: f64,
    /// The currents the fit saw (at the calibrated speed nearest the operating point).
    pub current_range_a: Range,
    /// Spread of one period's estimate about the line, N (1 σ).
    pub residual_std_n: f64,
}

impl CalibratedLine {
    /// The current the line gives at `force_n`.
    pub fn current_a(&self, force_n: f64) -> f64 {
        self.idle_current_a + self.sensitivity_a_per_n * force_n
    }

    /// The force the line reads from `current_a`.
    pub fn force_n(&self, current_a: f64) -> f64 {
        (current_a - self.idle_current_a) / self.sensitivity_a_per_n
    }

    /// Paper 003's spindle model at `spindle_rpm` (the line interpolated between calibrated
    /// speeds; range and spread of the nearest one).
    pub fn of_spindle(model: &SpindleCurrentModel, spindle_rpm: f64) -> Option<Self> {
        let (idle, sensitivity, _) = model.line_at(spindle_rpm);
        let nearest = model.rows.iter().min_by(|a, b| {
            (a.speed_rpm - spindle_rpm)
                .abs()
                .total_cmp(&(b.speed_rpm - spindle_rpm).abs())
        })?;
        Some(Self {
            idle_current_a: idle,
            sensitivity_a_per_n: sensitivity,
            current_range_a: nearest.current_range_a,
            residual_std_n: nearest.quality.residual_std_n,
        })
    }

    /// Paper 000's feed model at `feed_mm_min` (its idle current grows with the feed).
    pub fn of_feed(model: &FeedCurrentModel, feed_mm_min: f64) -> Self {
        Self {
            idle_current_a: model.idle_current_a(feed_mm_min),
            sensitivity_a_per_n: model.sensitivity_a_per_n,
            current_range_a: model.current_range_a,
            residual_std_n: model.quality.residual_std_n,
        }
    }
}

/// What a teach cut learned, from whichever source: all [`propose`] needs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Learned {
    /// The path the force is measured on.
    pub feedback: Feedback,
    /// Where the program runs.
    pub at: OperatingPoint,
    /// Median regulated force of the cutting periods at 100 % override, N.
    pub force_at_full_override_n: f64,
    /// The current line at `at`; `None` with a dynamometer (the force is read directly).
    pub line: Option<CalibratedLine>,
    /// Periods (or log rows) the calibration used.
    pub periods: usize,
}

/// Why the proposed target is what it is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum TargetBasis {
    /// [`DEFAULT_TARGET_FRACTION`] of the force at 100 % override.
    Fraction,
    /// That fraction lay below the currents the fit saw: raised to the lowest force they cover.
    RaisedToCalibratedRange,
    /// That fraction lay above the currents the fit saw: lowered to the highest force they cover.
    LoweredToCalibratedRange,
}

impl TargetBasis {
    /// For people.
    pub fn describe(self) -> &'static str {
        match self {
            TargetBasis::Fraction => "80 % of the force at 100 % override",
            TargetBasis::RaisedToCalibratedRange => {
                "80 % of the force at 100 % override lies below the calibrated currents: raised \
                 to the lowest force they cover"
            }
            TargetBasis::LoweredToCalibratedRange => {
                "80 % of the force at 100 % override lies above the calibrated currents: lowered \
                 to the highest force they cover"
            }
        }
    }
}

/// The settings a teach-in proposes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Proposal {
    /// The force to hold, N.
    pub target_n: f64,
    /// How it was chosen.
    pub basis: TargetBasis,
    /// The forces the calibrated current range covers at the operating point (−∞…∞ with a
    /// dynamometer).
    pub calibrated_force_n: Range,
    /// The current the calibrated line gives at the target (NaN with a dynamometer).
    pub reference_current_a: f64,
    /// Spread of one period's force estimate, N (1 σ; 0 with a dynamometer).
    pub estimate_noise_n: f64,
    /// Threshold gap, % of target (`threshold:gap_pct=…`).
    pub gap_pct: f64,
}

/// Proposes a target, its reference current and a threshold gap from what a teach cut learned
/// (see the module's documentation for the reasoning).
///
/// ```
/// use cutlab::estimation::estimator::Feedback;
/// use cutlab::estimation::current_force::Range;
/// use cutlab::closed_loop::settings::OperatingPoint;
/// use cutlab::tuning::teach_in::{propose, CalibratedLine, Learned, TargetBasis};
/// // 5 A idle, 0.01 A/N, currents 6–9 A seen (100–400 N), estimates ±4 N (1 σ).
/// let line = CalibratedLine { idle_current_a: 5.0, sensitivity_a_per_n: 0.01,
///     current_range_a: Range { min: 6.0, max: 9.0 }, residual_std_n: 4.0 };
/// let learned = Learned { feedback: Feedback::SpindleCurrent, periods: 40, line: Some(line),
///     at: OperatingPoint { spindle_rpm: 1000.0, feed_mm_min: f64::NAN },
///     force_at_full_override_n: 300.0 };
/// let p = propose(&learned).unwrap();
/// assert_eq!((p.target_n, p.basis), (240.0, TargetBasis::Fraction));
/// assert!((p.reference_current_a - 7.4).abs() < 1e-12);
/// assert!((p.gap_pct - 10.0).abs() < 1e-12); // 6 σ = 24 N of 240 N
/// ```
pub fn propose(learned: &Learned) -> Result<Proposal, TuningError> {
    let full = learned.force_at_full_override_n;
    if !(full.is_finite() && full > 0.0) {
        return Err(TuningError::TeachIn(
            "the teach cut has no cutting period at 100 % override, so there is no load to \
             propose a target from"
                .into(),
        ));
    }
    let wanted = DEFAULT_TARGET_FRACTION * full;
    let (calibrated, noise) = match &learned.line {
        Some(line) => (
            Range {
                min: line.force_n(line.current_range_a.min),
                max: line.force_n(line.current_range_a.max),
            },
            line.residual_std_n,
        ),
        None => (
            Range {
                min: f64::NEG_INFINITY,
                max: f64::INFINITY,
            },
            0.0,
        ),
    };
    let (target_n, basis) = if wanted < calibrated.min {
        (calibrated.min, TargetBasis::RaisedToCalibratedRange)
    } else if wanted > calibrated.max {
        (calibrated.max, TargetBasis::LoweredToCalibratedRange)
    } else {
        (wanted, TargetBasis::Fraction)
    };
    let gap_pct = if noise.is_finite() && target_n > 0.0 {
        (200.0 * NOISE_SIGMAS * noise / target_n).max(MIN_PROPOSED_GAP_PCT)
    } else {
        MIN_PROPOSED_GAP_PCT
    };
    Ok(Proposal {
        target_n,
        basis,
        calibrated_force_n: calibrated,
        reference_current_a: learned
            .line
            .map_or(f64::NAN, |line| line.current_a(target_n)),
        estimate_noise_n: noise,
        gap_pct,
    })
}

/// The preset's own target, shown beside the proposal for comparison.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PaperTarget {
    /// Whose target and how it is stated.
    pub what: String,
    /// As a force on the calibrated path, N.
    pub target_n: f64,
    /// Its current on the calibrated line (NaN with a dynamometer).
    pub reference_current_a: f64,
}

/// A teach-in's result: where it came from, what it learned, what it proposes.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TeachIn {
    /// Where the calibration came from, for people.
    pub source: String,
    /// The preset whose program it describes, if any.
    pub preset: Option<&'static str>,
    /// What was learned.
    pub learned: Learned,
    /// What it proposes.
    pub proposal: Proposal,
    /// The preset's own target, if it has one.
    pub paper: Option<PaperTarget>,
    /// What the calibration rests on, in the fit's words ([`load_level_warnings`]): a line on
    /// too few load levels, or a file saved before calibrations kept them. Empty when sound.
    pub warnings: Vec<String>,
}

/// The operating point of `spec`'s program (its plant edits included).
pub fn operating_point(spec: &RunSpec) -> OperatingPoint {
    OperatingPoint::of_preset(spec)
}

/// What `calibration` learned, at `at`.
pub fn learned_from_calibration(calibration: &Calibration, at: OperatingPoint) -> Learned {
    let line = match &calibration.estimator {
        Estimator::Spindle { model, .. } => CalibratedLine::of_spindle(model, at.spindle_rpm),
        Estimator::Feed { model } => Some(CalibratedLine::of_feed(model, at.feed_mm_min)),
        Estimator::Dynamometer => None,
    };
    Learned {
        feedback: calibration.estimator.feedback(),
        at,
        force_at_full_override_n: calibration.median_force_at_full_override_n,
        line,
        periods: calibration.periods,
    }
}

/// The preset's own target as a force on `calibration`'s path, when the preset has one.
fn paper_target(
    spec: &RunSpec,
    learned: &Learned,
    calibration: &Calibration,
) -> Option<PaperTarget> {
    let what = match (
        spec.preset.target_force_n(),
        spec.preset.target_spindle_current_a(),
    ) {
        (Some(_), _) => format!("{}'s target force", spec.preset.name()),
        (None, Some(current_a)) => format!(
            "{}'s target current I_ref = {current_a} A",
            spec.preset.name()
        ),
        (None, None) => return None,
    };
    let mut spec = spec.clone();
    spec.settings.feedback = Some(learned.feedback);
    let target_n = settled_settings(&spec, calibration).ok()?.target_force_n;
    target_n.is_finite().then(|| PaperTarget {
        what,
        target_n,
        reference_current_a: learned
            .line
            .map_or(f64::NAN, |line| line.current_a(target_n)),
    })
}

fn teach_in_of(
    source: String,
    spec: Option<&RunSpec>,
    calibration: &Calibration,
    at: OperatingPoint,
) -> Result<TeachIn, TuningError> {
    let learned = learned_from_calibration(calibration, at);
    let proposal = propose(&learned).map_err(|e| e.within(&source))?;
    Ok(TeachIn {
        paper: spec.and_then(|spec| paper_target(spec, &learned, calibration)),
        preset: spec.map(|s| s.preset.name()),
        source,
        learned,
        proposal,
        warnings: load_level_warnings(calibration),
    })
}

/// Runs `spec`'s teach cut on the simulated machine and proposes from it.
///
/// ```
/// use cutlab::closed_loop::definition::RunSpec;
/// use cutlab::control::registry::ControllerKind;
/// use cutlab::plant::Preset;
/// let t = cutlab::tuning::teach_in(&RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Threshold))
///     .unwrap();
/// let p = t.proposal;
/// assert_eq!(p.target_n, 0.8 * t.learned.force_at_full_override_n);
/// assert!(p.reference_current_a > 0.0 && p.gap_pct >= 5.0);
/// assert_eq!(t.paper.unwrap().target_n, 150.0); // paper 001's own target, for comparison
/// ```
pub fn teach_in(spec: &RunSpec) -> Result<TeachIn, TuningError> {
    let (_, calibration) =
        crate::closed_loop::lab::teach_cut_only(spec).map_err(|error| TuningError::Run {
            preset: spec.preset.name(),
            error,
        })?;
    simulated_teach_in(spec, &calibration)
}

/// The teach-in of `spec` whose simulated teach cut gave `calibration`: what [`teach_in`]
/// proposes, for a teach cut made elsewhere (the browser's computation workers make them,
/// `closed_loop::recording_jobs::TeachCuts`).
pub fn simulated_teach_in(
    spec: &RunSpec,
    calibration: &Calibration,
) -> Result<TeachIn, TuningError> {
    teach_in_of(
        simulated_source(spec),
        Some(spec),
        calibration,
        operating_point(spec),
    )
}

fn simulated_source(spec: &RunSpec) -> String {
    format!(
        "{} (simulated teach cut, seed {})",
        spec.preset.name(),
        spec.seed
    )
}

/// Proposes from a saved calibration (what `cutlab host --save-calibration` or `cutlab sim
/// --save-calibration` wrote; `name` is the file's). `program` is the preset the calibration
/// was taught on: its speed and feed are the operating point, and its own target is shown for
/// comparison. Without one, a spindle calibration is read at its most-sampled calibrated
/// speed; a feed calibration needs the program's feed and is refused.
pub fn teach_in_calibration(
    file: &CalibrationFile,
    name: &str,
    program: Option<&RunSpec>,
) -> Result<TeachIn, TuningError> {
    let source = if file.source.is_empty() {
        format!("calibration {name}")
    } else {
        format!("calibration {name} ({})", file.source)
    };
    let at = match (program, &file.calibration.estimator) {
        (Some(spec), _) => operating_point(spec),
        (None, Estimator::Spindle { model, .. }) => OperatingPoint {
            spindle_rpm: model
                .rows
                .iter()
                .max_by_key(|row| row.quality.samples)
                .map_or(f64::NAN, |row| row.speed_rpm),
            feed_mm_min: f64::NAN,
        },
        (None, Estimator::Feed { .. }) => {
            return Err(TuningError::TeachIn(format!(
                "{source}: a feed-current calibration's reference current depends on the \
                 programmed feed; name the program it was taught on (a scenario)"
            )))
        }
        (None, Estimator::Dynamometer) => OperatingPoint {
            spindle_rpm: f64::NAN,
            feed_mm_min: f64::NAN,
        },
    };
    teach_in_of(source, program, &file.calibration, at)
}

/// The simulated teach-ins of `specs`, on up to `threads` threads natively, in `specs`' order;
/// `report` hears of each as it finishes (on the calling thread).
pub fn teach_in_scenarios(
    specs: &[RunSpec],
    threads: usize,
    report: &mut dyn FnMut(&super::Report<'_>),
) -> Result<Vec<TeachIn>, TuningError> {
    let mut done = 0;
    crate::work::parallel_map_reporting(specs, threads, teach_in, |i, _| {
        done += 1;
        report(&super::Report::Taught {
            preset: specs[i].preset.name(),
            done,
            total: specs.len(),
        });
    })
    .into_iter()
    .collect()
}

/// How to read a logged teach cut.
#[derive(Debug, Clone, Copy)]
pub struct LogTeachIn<'a> {
    /// Calibration columns taken from other columns of the log (`ROLE=COLUMN`).
    pub map: &'a [(String, String)],
    /// Model the force from the cut instead of the log's `force_n` (with its description).
    pub geometry: Option<(&'a CutGeometry, &'a str)>,
    /// The spindle's gear change (paper 003: 900 rpm).
    pub gear_change_rpm: f64,
}

/// What a logged teach cut gave: the teach-in, and what to tell a person about the log.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LoggedTeachIn {
    /// The teach-in.
    #[serde(flatten)]
    pub teach_in: TeachIn,
    /// What the proposal rests on, for people (the override column or its absence, the force's
    /// source, the model not fitted).
    pub notes: Vec<String>,
}

/// Proposes from a logged teach cut read by the messy-log reader ([`crate::log`]): the
/// calibration `cutlab calibrate` fits ([`calibrate_log`]: the spindle model where the log
/// has the spindle's columns, else the feed model), the force at 100 % override as the fit's
/// median over the rows it used whose `override_pct` is 100 % (every row when the log has no
/// override column: a teach cut runs the program as written), and the operating point as the
/// median speed and feed of those rows. `name` names the log in messages.
pub fn teach_in_log(
    log: &crate::log::Log,
    name: &str,
    how: LogTeachIn<'_>,
) -> Result<LoggedTeachIn, TuningError> {
    // A log without data rows never gets here from a file: the reader refuses it, saying what the
    // file held instead. One built by hand finds no cutting rows to fit below.
    let in_log = |e: String| TuningError::TeachIn(format!("{name}: {e}"));
    let table = LogTable::from_log(log, how.map).map_err(in_log)?;
    let fitted = calibrate_log(&table, how.geometry, how.gear_change_rpm)
        .map_err(|e| in_log(e.to_string()))?;
    let mut notes = Vec::new();
    if table.column("override_pct").is_none() {
        notes.push(
            "the log has no override_pct column (map one with --map override_pct=COLUMN): every \
             cutting row is taken as cut at 100 % override"
                .to_string(),
        );
    }
    let fit = match (&fitted.spindle_fit, &fitted.feed_fit) {
        (Some(fit), _) => {
            if let Some(e) = &fitted.feed_error {
                notes.push(format!("feed model not fitted: {e}"));
            }
            notes.push(format!("force from {}", fitted.force_source));
            fit
        }
        (None, Some(fit)) => {
            if let Some(e) = &fitted.spindle_error {
                notes.push(format!("spindle model not fitted: {e}"));
            }
            notes.push(format!("feed force from {}", fitted.feed_force_source));
            fit
        }
        // calibrate_log refuses a log where neither model could be fitted.
        (None, None) => return Err(in_log("no current model could be fitted".into())),
    };
    notes.push(fit.selection_note());
    let at = OperatingPoint {
        spindle_rpm: fit.full_override.spindle_rpm,
        feed_mm_min: fit.full_override.feed_mm_min,
    };
    let learned = learned_from_calibration(&fit.calibration, at);
    let source = format!("log {name}");
    let proposal = propose(&learned).map_err(|e| e.within(&source))?;
    Ok(LoggedTeachIn {
        teach_in: TeachIn {
            source,
            preset: None,
            learned,
            proposal,
            paper: None,
            warnings: fit.warnings(),
        },
        notes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn learned(force_at_full_override_n: f64) -> Learned {
        Learned {
            feedback: Feedback::SpindleCurrent,
            at: OperatingPoint {
                spindle_rpm: 1000.0,
                feed_mm_min: f64::NAN,
            },
            force_at_full_override_n,
            // 2 A idle, 0.02 A/N, currents 4–8 A seen: 100–300 N.
            line: Some(CalibratedLine {
                idle_current_a: 2.0,
                sensitivity_a_per_n: 0.02,
                current_range_a: Range { min: 4.0, max: 8.0 },
                residual_std_n: 1.0,
            }),
            periods: 30,
        }
    }

    #[test]
    fn a_target_outside_the_calibrated_currents_is_moved_to_their_edge() {
        // 80 % of 110 N = 88 N lies below the 100 N the lowest current covers.
        let p = propose(&learned(110.0)).unwrap();
        assert_eq!(p.basis, TargetBasis::RaisedToCalibratedRange);
        assert!((p.target_n - 100.0).abs() < 1e-9 && (p.reference_current_a - 4.0).abs() < 1e-12);
        // 80 % of 400 N = 320 N lies above the 300 N the highest covers.
        let p = propose(&learned(400.0)).unwrap();
        assert_eq!(p.basis, TargetBasis::LoweredToCalibratedRange);
        assert!((p.target_n - 300.0).abs() < 1e-9 && (p.reference_current_a - 8.0).abs() < 1e-12);
        // Inside: 80 % of 250 N, with the 5 % floor on the gap (6 σ = 6 N is 3 % of 200 N).
        let p = propose(&learned(250.0)).unwrap();
        assert_eq!((p.target_n, p.basis), (200.0, TargetBasis::Fraction));
        assert_eq!(p.gap_pct, MIN_PROPOSED_GAP_PCT);
    }

    #[test]
    fn a_teach_cut_without_a_period_at_full_override_proposes_nothing() {
        for force in [f64::NAN, 0.0, -5.0] {
            let e = propose(&learned(force)).unwrap_err();
            assert!(e.to_string().contains("no cutting period at 100 %"), "{e}");
            assert!(e
                .within("log a.csv")
                .to_string()
                .starts_with("log a.csv: the teach cut"));
        }
    }

    #[test]
    fn a_dynamometer_needs_no_current_and_no_bounds() {
        let l = Learned {
            feedback: Feedback::Dynamometer,
            line: None,
            ..learned(500.0)
        };
        let p = propose(&l).unwrap();
        assert_eq!((p.target_n, p.basis), (400.0, TargetBasis::Fraction));
        assert!(p.reference_current_a.is_nan() && p.estimate_noise_n == 0.0);
        assert_eq!(p.gap_pct, MIN_PROPOSED_GAP_PCT);
    }
}
