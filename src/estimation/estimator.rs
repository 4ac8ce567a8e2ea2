//! The calibrated estimator: a period's motor current → the force on the cutter, through the
//! model a teach cut fitted ([`Calibration`]), on the feedback path the run measures with
//! ([`Feedback`]).

use serde::{Deserialize, Serialize};

use super::current_force::{
    FeedCurrentModel, ForceEstimate, SpindleCurrentModel, SpindleSpeedRow, RANGE_SLACK_FRACTION,
};
use super::load_levels::FewLoadLevels;
use super::speed::FvSpeedModel;
use crate::signal::chain::PeriodSummary;

/// Which motor current the force is measured from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Feedback {
    /// Spindle current → mean cutting force (paper 003; independent of the feed direction).
    #[serde(alias = "spindle")]
    SpindleCurrent,
    /// Feed-drive current → feed force (paper 000).
    #[serde(alias = "feed")]
    FeedCurrent,
    /// A dynamometer under the part reads the mean cutting force itself (paper 001's
    /// experiments): no current, no model, but a sensor few machines carry.
    Dynamometer,
}

impl Feedback {
    /// Both feedback paths.
    pub const ALL: [Feedback; 3] = [
        Feedback::SpindleCurrent,
        Feedback::FeedCurrent,
        Feedback::Dynamometer,
    ];

    /// Name for the command line and URLs.
    pub fn name(self) -> &'static str {
        match self {
            Feedback::SpindleCurrent => "spindle",
            Feedback::FeedCurrent => "feed",
            Feedback::Dynamometer => "dynamometer",
        }
    }

    /// Human label.
    pub fn label(self) -> &'static str {
        match self {
            Feedback::SpindleCurrent => "Spindle current (paper 003)",
            Feedback::FeedCurrent => "Feed-drive current (paper 000)",
            Feedback::Dynamometer => "Dynamometer (paper 001)",
        }
    }

    /// The period's current on this path, A: the spindle's RMS for the spindle (and for a
    /// dynamometer, which a teach cut still pairs with the spindle current), the feed drive's for
    /// the feed.
    pub fn current_a(self, period: &PeriodSummary) -> f64 {
        match self {
            Feedback::SpindleCurrent | Feedback::Dynamometer => period.spindle_current_rms_a,
            Feedback::FeedCurrent => period.feed_current_rms_a,
        }
    }

    /// The true value of the regulated force in a period: the mean cutting-force vector's
    /// magnitude for the spindle path, the mean feed force for the feed path.
    pub fn regulated_truth_n(self, period: &PeriodSummary) -> f64 {
        match self {
            Feedback::SpindleCurrent | Feedback::Dynamometer => period.force_mean_resultant_n,
            Feedback::FeedCurrent => period.feed_force_n,
        }
    }
}

/// A calibrated current-to-force estimator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "feedback", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Estimator {
    /// Paper 003's spindle model with F/V speed identification.
    Spindle {
        /// Current → force per speed.
        model: SpindleCurrentModel,
        /// F/V voltage → speed.
        speed: FvSpeedModel,
    },
    /// Paper 000's feed-drive model.
    Feed {
        /// Current and feed speed → feed force.
        model: FeedCurrentModel,
    },
    /// A dynamometer's reading, used as it is (its maker calibrated it).
    Dynamometer,
}

impl Estimator {
    /// The force estimate for a period.
    pub fn estimate(&self, period: &PeriodSummary) -> ForceEstimate {
        match self {
            Estimator::Spindle { model, speed } => {
                let rpm = speed.speed_rpm(period.spindle_fv_voltage_v, period.spindle_command_rpm);
                model.estimate(period.spindle_current_rms_a, rpm)
            }
            Estimator::Feed { model } => {
                model.estimate(period.feed_current_rms_a, period.feed_mm_min)
            }
            Estimator::Dynamometer => ForceEstimate {
                force_n: period.dynamometer_resultant_n,
                in_range: true,
            },
        }
    }

    /// Why this estimator cannot be read at a program's `spindle_rpm` and `feed_mm_min`: the
    /// calibration never saw that speed (spindle model: no row within
    /// [`RANGE_SLACK_FRACTION`] of it, none on each side of it in the same gear) or that feed (feed model: outside its range, loosely); `None` where it did,
    /// where an operating point is not known (not finite), and for a dynamometer. A calibration
    /// taught on another program comes here: at 3,000 rpm a 1,000 rpm line reads −10 N for 630 N.
    ///
    /// ```
    /// use cutlab::estimation::estimator::Estimator;
    /// assert_eq!(Estimator::Dynamometer.not_calibrated_at(3000.0, 500.0), None);
    /// ```
    pub fn not_calibrated_at(&self, spindle_rpm: f64, feed_mm_min: f64) -> Option<String> {
        match self {
            Estimator::Spindle { model, .. } if spindle_rpm.is_finite() => {
                // Loosely: a measured speed sags under load (a log's mean speed sits a few
                // percent under the command a teach cut was read at).
                let slack = 1.0 + RANGE_SLACK_FRACTION;
                let seen = |r: &SpindleSpeedRow| {
                    spindle_rpm >= r.speed_rpm / slack && spindle_rpm <= r.speed_rpm * slack
                };
                let (_, _, between) = model.line_at(spindle_rpm);
                let inside = between || model.rows.iter().any(seen);
                (!inside).then(|| {
                    let seen: Vec<String> = model
                        .rows
                        .iter()
                        .map(|r| format!("{:.0}", r.speed_rpm))
                        .collect();
                    format!(
                        "the calibration saw the spindle at {} rpm, not at this program's \
                         {spindle_rpm:.0} rpm: its force estimate would be an extrapolation",
                        seen.join(", ")
                    )
                })
            }
            Estimator::Feed { model } if feed_mm_min.is_finite() => {
                let seen = model.feed_range_mm_min;
                (!seen.contains_loosely(feed_mm_min.abs())).then(|| {
                    format!(
                        "the calibration saw feeds of {:.0}–{:.0} mm/min, not this program's \
                         {feed_mm_min:.0} mm/min: its force estimate would be an extrapolation",
                        seen.min, seen.max
                    )
                })
            }
            _ => None,
        }
    }

    /// The current sensitivity, A per N, at a spindle speed (the spindle model's line there; the
    /// feed model's one slope).
    pub fn sensitivity_a_per_n(&self, spindle_rpm: f64) -> f64 {
        match self {
            Estimator::Spindle { model, .. } => model.line_at(spindle_rpm).1,
            Estimator::Feed { model } => model.sensitivity_a_per_n,
            // No current is read: a limit in amperes has no meaning here.
            Estimator::Dynamometer => f64::NAN,
        }
    }

    /// The spread (1 σ) of one period's estimate about the calibration line, in newtons: the
    /// fit's residual at the calibration row nearest `spindle_rpm` (0 for a dynamometer, whose
    /// noise the period mean averages away).
    pub fn residual_std_n(&self, spindle_rpm: f64) -> f64 {
        match self {
            Estimator::Spindle { model, .. } => model
                .rows
                .iter()
                .min_by(|a, b| {
                    (a.speed_rpm - spindle_rpm)
                        .abs()
                        .total_cmp(&(b.speed_rpm - spindle_rpm).abs())
                })
                .map_or(f64::NAN, |row| row.quality.residual_std_n),
            Estimator::Feed { model } => model.quality.residual_std_n,
            Estimator::Dynamometer => 0.0,
        }
    }

    /// The current the model expects at `force_n` (the reference current of a force target).
    pub fn current_for_force_a(&self, force_n: f64, spindle_rpm: f64, feed_mm_min: f64) -> f64 {
        match self {
            Estimator::Spindle { model, .. } => {
                let (idle, sensitivity, _) = model.line_at(spindle_rpm);
                idle + sensitivity * force_n
            }
            Estimator::Feed { model } => {
                model.idle_current_a(feed_mm_min) + model.sensitivity_a_per_n * force_n
            }
            Estimator::Dynamometer => f64::NAN,
        }
    }

    /// The force the model reads from `current_a` (to express a current target as a force).
    pub fn force_for_current_n(&self, current_a: f64, spindle_rpm: f64, feed_mm_min: f64) -> f64 {
        match self {
            Estimator::Spindle { model, .. } => {
                let (idle, sensitivity, _) = model.line_at(spindle_rpm);
                (current_a - idle) / sensitivity
            }
            Estimator::Feed { model } => {
                (current_a - model.idle_current_a(feed_mm_min)) / model.sensitivity_a_per_n
            }
            Estimator::Dynamometer => f64::NAN,
        }
    }
}

/// What a teach cut produced. Saved and read back as a calibration file
/// ([`crate::closed_loop::calibration_file`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Calibration {
    /// The fitted estimator.
    pub estimator: Estimator,
    /// The largest force the estimator read while the teach cut's tool was in air (NaN if the
    /// teach cut had no air, or a saved calibration predates this field): the safety envelope
    /// takes the tool for in air below a margin above it.
    #[serde(
        default = "crate::estimation::nan",
        deserialize_with = "crate::estimation::null_as_nan"
    )]
    pub air_force_estimate_n: f64,
    /// Median regulated force over the cutting periods of the teach cut at 100 % override.
    #[serde(deserialize_with = "crate::estimation::null_as_nan")]
    pub median_force_at_full_override_n: f64,
    /// Median of regulated force ÷ mean resultant force over those periods: converts a
    /// resultant-force target into the regulated force (1 for spindle feedback).
    #[serde(deserialize_with = "crate::estimation::null_as_nan")]
    pub regulated_per_resultant: f64,
    /// Periods used for the fit.
    pub periods: usize,
    /// The largest phase current (feed or spindle, raw) seen during the teach cut.
    pub max_phase_current_a: f64,
    /// How long the teach cut ran (machine time).
    pub duration_s: f64,
    /// The fitted lines that rest on too few load levels to be determined (empty when none do,
    /// and for a dynamometer); `None` for a calibration saved before cutlab kept them (a
    /// version 1 calibration file), which cannot say. Shown through
    /// [`load_level_warnings`](super::teach_fit::load_level_warnings).
    #[serde(default)]
    pub few_load_levels: Option<Vec<FewLoadLevels>>,
}

impl Estimator {
    /// The feedback path this estimator reads.
    pub fn feedback(&self) -> Feedback {
        match self {
            Estimator::Spindle { .. } => Feedback::SpindleCurrent,
            Estimator::Feed { .. } => Feedback::FeedCurrent,
            Estimator::Dynamometer => Feedback::Dynamometer,
        }
    }
}
