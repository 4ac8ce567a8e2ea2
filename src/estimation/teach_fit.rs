//! The teach-cut fit: control periods of a cut at known loads → a [`Calibration`].
//!
//! Every calibration cutlab makes goes through [`fit`]: the simulated teach cut, the teach cut on a
//! machine over the serial line (both [`crate::closed_loop::teach_cut`]), a recorded log run through
//! the same signal chain, and a log whose rows are already control periods (`cutlab calibrate`,
//! a logged teach-in). Each caller gives the periods as [`TeachPeriod`]s — the signal chain's
//! summary, the force from its source and what it knows about the override and the spindle — and
//! gets the same selection, the same least-squares models and the same statistics back.
//!
//! ```text
//! periods ─► selection ─────────────────────────────► used periods ─► least squares ─► estimator
//!            spindle past its start (1 s)                            (spindle: F/V speed model,
//!            speed steady (±1 % from the period before, 0.5 s on)               then paper 003's lines;
//!            0.5 s past an override change                            feed: paper 000's model)
//!            axes feeding, force finite and positive
//!            modelled force: not in air (current above the idle one)
//!                                    used periods at 100 % ─► median force, median speed and feed
//!            settled periods in air ─► the estimator's reading there (its bias in air)
//!            used periods per fitted line ─► load levels: under 3, a warning (R² proves nothing)
//! ```
//!
//! Why each rule: a spindle starting or changing speed draws a current that says nothing about the
//! load (40 A where the cut takes 6), the feed and the currents need a moment after each override
//! change (the spindle's bandwidth is below 5 Hz), and the line is fitted where it is used, in the
//! cut. A measured force (simulation truth, a dynamometer, a logged force) says itself where the
//! tool is in air; the model of the cut gives a force wherever the axes feed, so with a modelled
//! force the air is told by the current: a teach program approaches in air, and its lowest current
//! is the idle one.
//!
//! NaN: a period whose force or current is not finite is not used. Unknown feed (NaN) does not
//! exclude a period; a known zero feed does.

use std::fmt;

use serde::Serialize;

use super::current_force::{FeedCurrentModel, SpindleCurrentModel};
use super::estimator::{Calibration, Estimator, Feedback};
use super::load_levels::{load_levels_n, FewLoadLevels, LineModel, MIN_LOAD_LEVELS};
use super::speed::FvSpeedModel;
#[cfg(test)]
use super::speed::GEAR_CHANGE_RPM;
use crate::math::least_squares::FitError;
use crate::signal::chain::PeriodSummary;
use crate::signal::stats::median;

/// Periods ending this soon after a spindle start are left out: the starting current says
/// nothing about the load.
pub const SETTLE_AFTER_SPINDLE_START_S: f64 = 1.0;
/// Periods ending this soon after an override change are left out: the feed and the currents are
/// still moving to the new level.
pub const SETTLE_AFTER_CHANGE_S: f64 = 0.5;
/// Periods whose mean spindle speed moved more than this fraction since the period before, and
/// those less than [`SETTLE_AFTER_CHANGE_S`] after one, are left out: a spindle still
/// accelerating draws a current that says nothing about the load.
pub const STEADY_SPEED_FRACTION: f64 = 0.01;
/// With a modelled force, a period whose current is within this fraction of the lowest current of
/// the usable periods is the tool in air.
pub const AIR_CURRENT_MARGIN: f64 = 0.02;
/// With a measured force, a settled period whose force is below this fraction of the median force
/// at 100 % override is the tool in air (for the estimator's bias there).
pub const AIR_FORCE_FRACTION: f64 = 0.02;
/// A period ran at 100 % override when its override is within this of 100 %.
pub const FULL_OVERRIDE_TOLERANCE_PCT: f64 = 0.5;
/// A feed below this (mm/min) is the axes standing still.
const STANDING_FEED_MM_MIN: f64 = 1e-6;
/// One control period of a teach cut, as the fit takes it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TeachPeriod {
    /// The signal chain's summary of the period: currents, speeds, feed, and the truth beside them
    /// where a simulation has it.
    pub summary: PeriodSummary,
    /// The force the current is fitted against, N, on the feedback path's own terms (the mean
    /// resultant for the spindle, the feed force for the feed drive); NaN where the source has
    /// nothing to say.
    pub force_n: f64,
    /// The override the period ran at, %.
    pub override_pct: f64,
    /// Time from the latest override change to the period's end, s (∞ if it never changed).
    pub since_override_change_s: f64,
    /// Time from the spindle's start to the period's end, s (∞ where the spindle was not
    /// running, or already ran when the record began and nothing says when it started).
    pub since_spindle_start_s: f64,
}

/// How the periods' forces were obtained, which decides how air is told apart from cutting.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ForceOrigin {
    /// Measured (simulation truth, a dynamometer, a logged force): near-zero force is air.
    Measured,
    /// Modelled from the programmed cut: the current tells the air.
    Modelled,
}

/// Why periods were left out of a fit, counted by the first rule each failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct Exclusions {
    /// Within [`SETTLE_AFTER_SPINDLE_START_S`] of the spindle's start.
    pub spindle_starting: usize,
    /// The spindle changing speed.
    pub accelerating: usize,
    /// Within [`SETTLE_AFTER_CHANGE_S`] of an override change.
    pub override_settling: usize,
    /// The axes standing still.
    pub not_feeding: usize,
    /// No finite positive force (or no finite current).
    pub no_force: usize,
    /// The tool in air (modelled forces only).
    pub air: usize,
}

impl Exclusions {
    /// Every period left out.
    pub fn total(&self) -> usize {
        self.spindle_starting
            + self.accelerating
            + self.override_settling
            + self.not_feeding
            + self.no_force
            + self.air
    }
}

/// One period the fit used: its current and force, for plotting the fit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FitPoint {
    /// The period's end.
    pub time_s: f64,
    /// Its RMS current after the signal chain.
    pub current_a: f64,
    /// Its force (measured or modelled).
    pub force_n: f64,
    /// Its spindle speed, as the estimator reads it (from the F/V voltage where there is one).
    pub speed_rpm: f64,
    /// Its feed.
    pub feed_mm_min: f64,
}

/// Where the program ran at 100 % override: medians over the used periods there.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FullOverride {
    /// Used periods at 100 % override.
    pub periods: usize,
    /// Median measured spindle speed, rpm (NaN without one).
    pub spindle_rpm: f64,
    /// Median feed, mm/min (NaN without one).
    pub feed_mm_min: f64,
}

/// The warnings a calibration carries, for every front end to show beside it — after a fit, and
/// when a saved calibration is loaded: one per fitted line on too few load levels
/// ([`FewLoadLevels::describe`]), or one saying it cannot tell for a calibration saved before
/// cutlab kept its load levels (a version 1 calibration file). A dynamometer fits nothing and
/// warns of nothing.
///
/// ```
/// use cutlab::estimation::estimator::{Calibration, Estimator};
/// use cutlab::estimation::load_levels::{FewLoadLevels, LineModel};
/// use cutlab::estimation::teach_fit::load_level_warnings;
/// let mut c = Calibration {
///     estimator: Estimator::Dynamometer,
///     air_force_estimate_n: f64::NAN,
///     median_force_at_full_override_n: 300.0,
///     regulated_per_resultant: 1.0,
///     periods: 100,
///     max_phase_current_a: 0.0,
///     duration_s: 10.0,
///     few_load_levels: None,
/// };
/// assert!(load_level_warnings(&c).is_empty());
/// c.few_load_levels = Some(vec![FewLoadLevels {
///     model: LineModel::Feed,
///     speed_rpm: f64::NAN,
///     levels_n: vec![200.4],
///     r_squared: 0.5,
/// }]);
/// let w = load_level_warnings(&c);
/// assert!(w[0].starts_with("the feed model rests on 1 load level (200 N)"), "{w:?}");
/// ```
pub fn load_level_warnings(calibration: &Calibration) -> Vec<String> {
    match &calibration.few_load_levels {
        Some(lines) => lines.iter().map(FewLoadLevels::describe).collect(),
        None if matches!(calibration.estimator, Estimator::Dynamometer) => Vec::new(),
        None => vec![format!(
            "the calibration does not say how many load levels its lines rest on (saved by an \
             older cutlab): a line on fewer than {MIN_LOAD_LEVELS} is not determined by them, \
             whatever its R²; teach again to know"
        )],
    }
}

/// What a fit made, and what it rests on.
#[derive(Debug, Clone, PartialEq)]
pub struct TeachFit {
    /// The calibration.
    pub calibration: Calibration,
    /// The periods used, in order.
    pub points: Vec<FitPoint>,
    /// The periods left out, by reason.
    pub excluded: Exclusions,
    /// The operating point at 100 % override.
    pub full_override: FullOverride,
}

impl TeachFit {
    /// The fit's warnings for people (a line on too few load levels), for every front end to
    /// show beside its R²: the calibration's own ([`load_level_warnings`]).
    pub fn warnings(&self) -> Vec<String> {
        load_level_warnings(&self.calibration)
    }

    /// One line for people: how many periods were used and why the others were not.
    pub fn selection_note(&self) -> String {
        let e = &self.excluded;
        let mut reasons = vec![
            format!("{} without a positive force", e.no_force),
            format!("{} with the spindle changing speed", e.accelerating),
            format!(
                "{} within {SETTLE_AFTER_CHANGE_S} s of an override change",
                e.override_settling
            ),
        ];
        for (count, why) in [
            (
                e.spindle_starting,
                format!("within {SETTLE_AFTER_SPINDLE_START_S} s of the spindle's start"),
            ),
            (e.not_feeding, "with the axes standing".to_string()),
            (e.air, "in air".to_string()),
        ] {
            if count > 0 {
                reasons.push(format!("{count} {why}"));
            }
        }
        format!(
            "{} of {} control periods used ({})",
            self.points.len(),
            self.points.len() + e.total(),
            reasons.join(", ")
        )
    }
}

/// Why no calibration could be fitted.
#[derive(Debug, Clone, PartialEq)]
pub enum TeachFitError {
    /// The least-squares fit failed (too few periods, one load only).
    Fit(FitError),
    /// Feed-current feedback on a cut that never loaded the feed drive.
    NoFeedLoad,
}

impl fmt::Display for TeachFitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TeachFitError::Fit(e) => write!(f, "{e}"),
            TeachFitError::NoFeedLoad => f.write_str(
                "feed-current feedback needs a cut that loads the feed drive, and this one never \
                 pushed back against the feed (in down milling the cutting force pulls the table \
                 along); measure the force through the spindle current",
            ),
        }
    }
}

impl std::error::Error for TeachFitError {}

/// Fits `feedback`'s estimator to `periods` (in time order) whose forces have `origin`.
/// `max_phase_current_a` is the largest raw phase current the cut saw, for the safety envelope's
/// sensor-fault limit; `gear_change_rpm` splits the spindle's speeds into its gear ranges
/// ([`GEAR_CHANGE_RPM`](super::speed::GEAR_CHANGE_RPM) on paper 003's machine).
///
/// ```
/// use cutlab::estimation::estimator::Feedback;
/// use cutlab::estimation::teach_fit::{fit, ForceOrigin, TeachPeriod};
/// use cutlab::signal::chain::PeriodSummary;
/// // Four loads at 1000 rpm on the line I = 5 A + 0.01 A/N · F.
/// let periods: Vec<TeachPeriod> = (0..40)
///     .map(|k| {
///         let force_n = [100.0, 300.0, 200.0, 400.0][k / 10];
///         TeachPeriod {
///             summary: PeriodSummary {
///                 end_time_s: 0.1 * k as f64,
///                 spindle_current_rms_a: 5.0 + 0.01 * force_n,
///                 spindle_speed_rpm: 1000.0,
///                 spindle_command_rpm: 1000.0,
///                 spindle_fv_voltage_v: f64::NAN,
///                 feed_mm_min: 200.0,
///                 force_mean_resultant_n: force_n,
///                 ..PeriodSummary::default()
///             },
///             force_n,
///             override_pct: if k < 10 { 100.0 } else { 50.0 },
///             since_override_change_s: f64::INFINITY,
///             since_spindle_start_s: f64::INFINITY,
///         }
///     })
///     .collect();
/// let taught = fit(&periods, Feedback::SpindleCurrent, ForceOrigin::Measured, 20.0, 900.0).unwrap();
/// let c = &taught.calibration;
/// assert!((c.estimator.sensitivity_a_per_n(1000.0) - 0.01).abs() < 1e-12);
/// assert_eq!((c.periods, c.median_force_at_full_override_n), (40, 100.0));
/// assert_eq!(taught.full_override.periods, 10);
/// ```
pub fn fit(
    periods: &[TeachPeriod],
    feedback: Feedback,
    origin: ForceOrigin,
    max_phase_current_a: f64,
    gear_change_rpm: f64,
) -> Result<TeachFit, TeachFitError> {
    let (settled, usable, mut excluded) = select(periods, feedback);
    let used = without_air(periods, &usable, feedback, origin, &mut excluded);

    let current = |i: &usize| feedback.current_a(&periods[*i].summary);
    let currents: Vec<f64> = used.iter().map(current).collect();
    let forces: Vec<f64> = used.iter().map(|&i| periods[i].force_n).collect();
    let column = |f: fn(&PeriodSummary) -> f64| -> Vec<f64> {
        used.iter().map(|&i| f(&periods[i].summary)).collect()
    };
    let speed_model = FvSpeedModel::calibrate(
        &column(|s| s.spindle_command_rpm),
        &column(|s| s.spindle_speed_rpm),
        &column(|s| s.spindle_fv_voltage_v),
        gear_change_rpm,
    );
    let identified_rpm: Vec<f64> = used
        .iter()
        .map(|&i| {
            let s = &periods[i].summary;
            speed_model.speed_rpm(s.spindle_fv_voltage_v, s.spindle_command_rpm)
        })
        .collect();
    let estimator = match feedback {
        // The sensor reads the force itself: nothing to fit.
        Feedback::Dynamometer => Estimator::Dynamometer,
        Feedback::SpindleCurrent => Estimator::Spindle {
            model: SpindleCurrentModel::calibrate(
                &currents,
                &identified_rpm,
                &forces,
                gear_change_rpm,
            )
            .map_err(TeachFitError::Fit)?,
            speed: speed_model,
        },
        Feedback::FeedCurrent if forces.is_empty() => return Err(TeachFitError::NoFeedLoad),
        Feedback::FeedCurrent => Estimator::Feed {
            model: FeedCurrentModel::calibrate(&currents, &column(|s| s.feed_mm_min), &forces)
                .map_err(TeachFitError::Fit)?,
        },
    };

    let at_full: Vec<usize> = used
        .iter()
        .copied()
        .filter(|&i| (periods[i].override_pct - 100.0).abs() <= FULL_OVERRIDE_TOLERANCE_PCT)
        .collect();
    let over_full =
        |f: &dyn Fn(&TeachPeriod) -> f64| median(at_full.iter().map(|&i| f(&periods[i])));
    let median_force_at_full_override_n = over_full(&|p| p.force_n);
    let air_force_estimate_n = air_force_estimate_n(
        periods,
        &settled,
        feedback,
        origin,
        &estimator,
        median_force_at_full_override_n,
    );
    let points: Vec<FitPoint> = used
        .iter()
        .zip(currents.iter().zip(&forces).zip(&identified_rpm))
        .map(|(&i, ((&current_a, &force_n), &speed_rpm))| FitPoint {
            time_s: periods[i].summary.end_time_s,
            current_a,
            force_n,
            speed_rpm,
            feed_mm_min: periods[i].summary.feed_mm_min,
        })
        .collect();
    let few_load_levels = Some(few_load_levels(&estimator, &points));
    let calibration = Calibration {
        estimator,
        air_force_estimate_n,
        median_force_at_full_override_n,
        // NaN without truth: left out of the median.
        regulated_per_resultant: over_full(&|p| p.force_n / p.summary.force_mean_resultant_n),
        periods: used.len(),
        max_phase_current_a,
        duration_s: periods.last().map_or(0.0, |p| p.summary.end_time_s),
        few_load_levels,
    };
    let full_override = FullOverride {
        periods: at_full.len(),
        spindle_rpm: over_full(&|p| p.summary.spindle_speed_rpm),
        feed_mm_min: over_full(&|p| p.summary.feed_mm_min),
    };
    Ok(TeachFit {
        calibration,
        points,
        excluded,
        full_override,
    })
}

/// The lines of `estimator` whose `points` (those the fit used) rest on too few load levels: each
/// calibrated speed of the spindle model over the points nearest its speed, the feed model over
/// all of them.
fn few_load_levels(estimator: &Estimator, points: &[FitPoint]) -> Vec<FewLoadLevels> {
    let few = |model, speed_rpm, forces: Vec<f64>, r_squared| {
        let levels_n = load_levels_n(&forces);
        (levels_n.len() < MIN_LOAD_LEVELS).then_some(FewLoadLevels {
            model,
            speed_rpm,
            levels_n,
            r_squared,
        })
    };
    match estimator {
        Estimator::Spindle { model, .. } => {
            let nearest_row = |speed_rpm: f64| {
                (0..model.rows.len()).min_by(|&a, &b| {
                    let off = |i: usize| (model.rows[i].speed_rpm - speed_rpm).abs();
                    off(a).total_cmp(&off(b))
                })
            };
            model
                .rows
                .iter()
                .enumerate()
                .filter_map(|(i, row)| {
                    let forces = points
                        .iter()
                        .filter(|p| nearest_row(p.speed_rpm) == Some(i))
                        .map(|p| p.force_n)
                        .collect();
                    few(
                        LineModel::Spindle,
                        row.speed_rpm,
                        forces,
                        row.quality.r_squared,
                    )
                })
                .collect()
        }
        Estimator::Feed { model } => {
            let forces = points.iter().map(|p| p.force_n).collect();
            few(LineModel::Feed, f64::NAN, forces, model.quality.r_squared)
                .into_iter()
                .collect()
        }
        Estimator::Dynamometer => Vec::new(),
    }
}

/// The settled periods (spindle past its start, speed steady, override settled, axes feeding)
/// and, among them, the usable ones (finite current, finite positive force), by index.
fn select(periods: &[TeachPeriod], feedback: Feedback) -> (Vec<usize>, Vec<usize>, Exclusions) {
    let mut excluded = Exclusions::default();
    let (mut settled, mut usable) = (Vec::new(), Vec::new());
    let mut previous_rpm = f64::NAN;
    let mut last_accelerating_s = f64::NEG_INFINITY;
    for (i, p) in periods.iter().enumerate() {
        let s = &p.summary;
        // NaN before the first period: not accelerating. The current needs as long as after an
        // override change to settle once the speed has: a run-up's last period reads as steady
        // while the motor still draws its accelerating current (1.8 kN "in air" on a 3000 rpm
        // spindle).
        if (s.spindle_speed_rpm - previous_rpm).abs()
            > STEADY_SPEED_FRACTION * s.spindle_speed_rpm.abs()
        {
            last_accelerating_s = s.end_time_s;
        }
        let accelerating = s.end_time_s - last_accelerating_s < SETTLE_AFTER_CHANGE_S;
        previous_rpm = s.spindle_speed_rpm;
        let reason = if p.since_spindle_start_s < SETTLE_AFTER_SPINDLE_START_S {
            &mut excluded.spindle_starting
        } else if accelerating {
            &mut excluded.accelerating
        } else if p.since_override_change_s < SETTLE_AFTER_CHANGE_S {
            &mut excluded.override_settling
        } else if s.feed_mm_min.abs() < STANDING_FEED_MM_MIN {
            &mut excluded.not_feeding
        } else {
            settled.push(i);
            if p.force_n.is_finite() && p.force_n > 0.0 && feedback.current_a(s).is_finite() {
                usable.push(i);
                continue;
            }
            &mut excluded.no_force
        };
        *reason += 1;
    }
    (settled, usable, excluded)
}

/// The usable periods without those in air, for a modelled force: the lowest current among them
/// is the idle one, and a current within [`AIR_CURRENT_MARGIN`] of it is air.
fn without_air(
    periods: &[TeachPeriod],
    usable: &[usize],
    feedback: Feedback,
    origin: ForceOrigin,
    excluded: &mut Exclusions,
) -> Vec<usize> {
    if origin == ForceOrigin::Measured {
        return usable.to_vec();
    }
    let current = |i: usize| feedback.current_a(&periods[i].summary);
    let idle_a = usable
        .iter()
        .map(|&i| current(i))
        .fold(f64::INFINITY, f64::min);
    let kept: Vec<usize> = usable
        .iter()
        .copied()
        .filter(|&i| current(i) > idle_a * (1.0 + AIR_CURRENT_MARGIN))
        .collect();
    excluded.air += usable.len() - kept.len();
    kept
}

/// The largest force `estimator` reads over the settled periods in air (NaN if there were none):
/// a spindle current's line fitted in the cut seldom passes through the idle current (an induction
/// motor's magnetising current makes the current convex in the load), so "no force" reads as tens
/// of newtons. In air are the periods whose measured force is (next to) nothing — below
/// [`AIR_FORCE_FRACTION`] of the force at 100 % override — or, for a modelled force, whose current
/// is the idle one.
fn air_force_estimate_n(
    periods: &[TeachPeriod],
    settled: &[usize],
    feedback: Feedback,
    origin: ForceOrigin,
    estimator: &Estimator,
    full_override_force_n: f64,
) -> f64 {
    let current = |i: usize| feedback.current_a(&periods[i].summary);
    let idle_a = settled
        .iter()
        .map(|&i| current(i))
        .fold(f64::INFINITY, f64::min);
    settled
        .iter()
        .copied()
        .filter(|&i| match origin {
            ForceOrigin::Modelled => current(i) <= idle_a * (1.0 + AIR_CURRENT_MARGIN),
            ForceOrigin::Measured => {
                let force_n = periods[i].force_n;
                force_n.is_finite() && force_n.abs() < AIR_FORCE_FRACTION * full_override_force_n
            }
        })
        .map(|i| estimator.estimate(&periods[i].summary).force_n)
        .filter(|f| f.is_finite())
        .fold(f64::NAN, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn period(k: usize, force_n: f64, current_a: f64) -> TeachPeriod {
        TeachPeriod {
            summary: PeriodSummary {
                end_time_s: 0.1 * k as f64,
                spindle_current_rms_a: current_a,
                spindle_speed_rpm: 1000.0,
                spindle_command_rpm: 1000.0,
                spindle_fv_voltage_v: f64::NAN,
                feed_mm_min: 100.0,
                force_mean_resultant_n: f64::NAN,
                ..PeriodSummary::default()
            },
            force_n,
            override_pct: 100.0,
            since_override_change_s: f64::INFINITY,
            since_spindle_start_s: f64::INFINITY,
        }
    }

    fn spindle_fit(
        periods: &[TeachPeriod],
        origin: ForceOrigin,
    ) -> Result<TeachFit, TeachFitError> {
        fit(
            periods,
            Feedback::SpindleCurrent,
            origin,
            1.0,
            GEAR_CHANGE_RPM,
        )
    }

    fn line(force_n: f64) -> f64 {
        5.0 + 0.01 * force_n
    }

    #[test]
    fn each_rule_leaves_out_its_periods_and_counts_them() {
        let mut periods: Vec<TeachPeriod> = (0..20)
            .map(|k| {
                let f = 100.0 + 10.0 * k as f64;
                period(k, f, line(f))
            })
            .collect();
        periods[2].since_spindle_start_s = 0.5;
        periods[4].since_override_change_s = 0.2;
        periods[6].summary.feed_mm_min = 0.0;
        periods[8].force_n = -1.0;
        // A speed change at period 10 and back at 11: both, and the 0.5 s after (12–15), out.
        periods[10].summary.spindle_speed_rpm = 1100.0;
        let taught = spindle_fit(&periods, ForceOrigin::Measured).unwrap();
        let e = taught.excluded;
        assert_eq!(
            (
                e.spindle_starting,
                e.override_settling,
                e.not_feeding,
                e.no_force,
                e.accelerating
            ),
            (1, 1, 1, 1, 6)
        );
        assert_eq!(taught.points.len(), 10);
        assert!(taught
            .selection_note()
            .starts_with("10 of 20 control periods used"));
    }

    #[test]
    fn a_line_on_two_load_levels_is_warned_about_and_one_on_many_is_not() {
        // Two depths, ten periods each, a little current noise: R² near 1, and it proves nothing.
        let two: Vec<TeachPeriod> = (0..20)
            .map(|k| {
                let f = if k < 10 { 150.0 } else { 300.0 };
                period(k, f, line(f) + 0.002 * (k % 3) as f64)
            })
            .collect();
        let taught = spindle_fit(&two, ForceOrigin::Measured).unwrap();
        let r_squared = match &taught.calibration.estimator {
            Estimator::Spindle { model, .. } => model.rows[0].quality.r_squared,
            other => panic!("{other:?}"),
        };
        assert!(r_squared > 0.999, "{r_squared}");
        let few = taught.calibration.few_load_levels.as_deref().unwrap();
        assert_eq!(few.len(), 1);
        assert_eq!(few[0].levels_n, vec![150.0, 300.0]);
        let warnings = taught.warnings();
        assert!(!warnings[0].contains("  "), "{warnings:?}");
        assert!(
            warnings[0]
                .starts_with("the spindle line at 1000 rpm rests on 2 load levels (150, 300 N)")
                && warnings[0].contains("R² 1.0000 proves nothing")
                && warnings[0].contains("a teach cut over more depths or feeds"),
            "{warnings:?}"
        );
        // A third level can disagree with the line: no warning.
        let mut three = two.clone();
        three.extend((20..30).map(|k| period(k, 220.0, line(220.0))));
        let taught = spindle_fit(&three, ForceOrigin::Measured).unwrap();
        assert!(taught.warnings().is_empty(), "{:?}", taught.warnings());
        // The feed model too: one level (a single cut at one feed), three coefficients.
        let one_feed: Vec<TeachPeriod> = (0..30)
            .map(|k| {
                let f = 200.0 + (k % 3) as f64;
                let mut p = period(k, f, f64::NAN);
                p.summary.feed_current_rms_a = 1.0 + 0.001 * f + 0.01 * ((k * 7) % 5) as f64;
                p.summary.feed_mm_min = 100.0 + 50.0 * (k % 2) as f64;
                p
            })
            .collect();
        let fed = fit(
            &one_feed,
            Feedback::FeedCurrent,
            ForceOrigin::Measured,
            1.0,
            GEAR_CHANGE_RPM,
        )
        .unwrap();
        let w = fed.warnings();
        assert!(
            w.len() == 1 && w[0].starts_with("the feed model rests on 1 load level (201 N)"),
            "{w:?}"
        );
    }

    #[test]
    fn a_modelled_force_leaves_out_the_idle_current_as_air() {
        // An approach in air at the idle current, with the model still giving a force.
        let mut periods: Vec<TeachPeriod> = (0..5).map(|k| period(k, 50.0, 5.0)).collect();
        periods.extend((5..25).map(|k| {
            let f = 100.0 + 10.0 * k as f64;
            period(k, f, line(f))
        }));
        let modelled = spindle_fit(&periods, ForceOrigin::Modelled).unwrap();
        assert_eq!((modelled.excluded.air, modelled.points.len()), (5, 20));
        let line_at = modelled.calibration.estimator.sensitivity_a_per_n(1000.0);
        assert!((line_at - 0.01).abs() < 1e-12, "{line_at}");
        // Measured, the same periods are cutting at 50 N and bend the line.
        let measured = spindle_fit(&periods, ForceOrigin::Measured).unwrap();
        assert_eq!(measured.points.len(), 25);
    }

    #[test]
    fn the_air_bias_is_what_the_line_reads_in_air() {
        // Air at 5.3 A (the line reads 30 N there), then the cut.
        let mut periods: Vec<TeachPeriod> = (0..5).map(|k| period(k, 0.0, 5.3)).collect();
        periods.extend((5..25).map(|k| {
            let f = 100.0 + 10.0 * k as f64;
            period(k, f, line(f))
        }));
        let taught = spindle_fit(&periods, ForceOrigin::Measured).unwrap();
        let bias = taught.calibration.air_force_estimate_n;
        assert!((bias - 30.0).abs() < 1e-9, "{bias}");
        assert_eq!(taught.excluded.no_force, 5);
    }

    #[test]
    fn the_full_override_statistics_are_medians_over_the_periods_at_100_percent() {
        let periods: Vec<TeachPeriod> = (0..20)
            .map(|k| {
                let f = 100.0 + 10.0 * k as f64;
                TeachPeriod {
                    override_pct: if k % 2 == 0 { 100.0 } else { 60.0 },
                    ..period(k, f, line(f))
                }
            })
            .collect();
        let taught = spindle_fit(&periods, ForceOrigin::Measured).unwrap();
        // Forces 100, 120, …, 280 at 100 %: the median of ten is the mean of 180 and 200.
        assert_eq!(taught.calibration.median_force_at_full_override_n, 190.0);
        assert_eq!(taught.full_override.periods, 10);
        assert_eq!(taught.full_override.spindle_rpm, 1000.0);
    }

    #[test]
    fn a_feed_fit_without_load_says_so() {
        let periods: Vec<TeachPeriod> = (0..5).map(|k| period(k, f64::NAN, 5.0)).collect();
        assert_eq!(
            fit(
                &periods,
                Feedback::FeedCurrent,
                ForceOrigin::Measured,
                1.0,
                GEAR_CHANGE_RPM
            )
            .unwrap_err(),
            TeachFitError::NoFeedLoad
        );
    }
}
