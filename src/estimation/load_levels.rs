//! Load levels: how many distinct loads a fitted current line rests on. Through two levels any
//! line fits (R² near 1 whatever the current does between them) and one level leaves the slope to
//! the noise, so a line on fewer than [`MIN_LOAD_LEVELS`] is not determined by them. The teach-cut
//! fit ([`super::teach_fit`]) counts the levels of each line it fits ([`load_levels_n`]) and keeps
//! those on too few ([`FewLoadLevels`]) in the calibration, whose words for people are
//! [`FewLoadLevels::describe`].

use serde::{Deserialize, Serialize};

use crate::signal::stats::median;

/// Forces within this fraction of the largest force a line was fitted to are one load level.
pub const LOAD_LEVEL_FRACTION: f64 = 0.05;
/// A line fitted on fewer load levels than this is not determined by them: through two levels any
/// line fits (R² near 1 whatever the current does between them), and one level leaves the slope
/// to the noise. A third level is the first that can disagree with the line.
pub const MIN_LOAD_LEVELS: usize = 3;

/// The model a fitted line belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LineModel {
    /// The spindle's current model: one line per calibrated speed.
    Spindle,
    /// The feed drive's current model.
    Feed,
}

impl LineModel {
    /// Its name for people and files: "spindle", "feed".
    pub fn name(self) -> &'static str {
        match self {
            LineModel::Spindle => "spindle",
            LineModel::Feed => "feed",
        }
    }
}

/// A fitted line whose periods rest on fewer than [`MIN_LOAD_LEVELS`] load levels
/// ([`load_levels_n`]): its coefficients are not determined and its R² proves nothing. The
/// calibration keeps these ([`Calibration::few_load_levels`](super::estimator::Calibration::few_load_levels)),
/// so a saved one warns when it is loaded.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FewLoadLevels {
    /// The model the line belongs to.
    pub model: LineModel,
    /// The calibrated speed of the spindle's line, rpm (NaN, written null, for the feed model).
    #[serde(deserialize_with = "super::null_as_nan")]
    pub speed_rpm: f64,
    /// Each load level's median force, N, ascending.
    pub levels_n: Vec<f64>,
    /// The line's R² (NaN, written null, for a fit of as many periods as coefficients).
    #[serde(deserialize_with = "super::null_as_nan")]
    pub r_squared: f64,
}

impl FewLoadLevels {
    /// The warning, for people: how many levels, why it matters, what to do.
    pub fn describe(&self) -> String {
        let readable = crate::input::readable;
        let model = self.model.name();
        let line = if self.speed_rpm.is_finite() {
            format!("the {model} line at {} rpm", readable(self.speed_rpm))
        } else {
            format!("the {model} model")
        };
        let levels: Vec<String> = self.levels_n.iter().map(|f| readable(f.round())).collect();
        let n = self.levels_n.len();
        format!(
            "{line} rests on {n} load level{} ({} N), too few to determine it (at least \
             {MIN_LOAD_LEVELS} are needed): its R² {:.4} proves nothing; teach over more loads: \
             a teach cut over more depths or feeds, or at more fixed overrides",
            if n == 1 { "" } else { "s" },
            levels.join(", "),
            self.r_squared
        )
    }
}

/// The load levels among `forces_n` (non-finite ones left out): from the lowest force up, each
/// level takes the forces within [`LOAD_LEVEL_FRACTION`] of the largest force above its first.
/// Each level's median, N.
///
/// ```
/// use cutlab::estimation::load_levels::load_levels_n;
/// // A cut at two depths, with a little noise: two levels, whatever R² the line through them has.
/// let two: Vec<f64> = (0..20).map(|k| if k < 10 { 150.0 } else { 300.0 } + (k % 3) as f64).collect();
/// assert_eq!(load_levels_n(&two), vec![151.0, 301.0]);
/// // A ramp from 100 to 400 N: many.
/// let ramp: Vec<f64> = (0..60).map(|k| 100.0 + 5.0 * k as f64).collect();
/// assert!(load_levels_n(&ramp).len() > 10);
/// ```
pub fn load_levels_n(forces_n: &[f64]) -> Vec<f64> {
    let mut sorted: Vec<f64> = forces_n.iter().copied().filter(|f| f.is_finite()).collect();
    sorted.sort_by(f64::total_cmp);
    let width_n = LOAD_LEVEL_FRACTION * sorted.iter().fold(0.0, |m: f64, f| m.max(f.abs()));
    let mut levels = Vec::new();
    let mut start = 0;
    while start < sorted.len() {
        let end = start
            + sorted[start..]
                .iter()
                .take_while(|&&f| f <= sorted[start] + width_n)
                .count();
        levels.push(median(sorted[start..end].iter().copied()));
        start = end;
    }
    levels
}
