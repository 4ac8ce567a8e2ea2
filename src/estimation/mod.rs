//! Estimation: motor current → cutting force.
//!
//! | module | what it holds |
//! |---|---|
//! | [`current_force`] | paper 000's feed-current model and paper 003's spindle-current model, their calibration from a teach cut, and range checks |
//! | [`load_levels`] | how many distinct loads a fitted current line rests on, and the warning for a line on too few ([`FewLoadLevels`](load_levels::FewLoadLevels)) |
//! | [`estimator`] | [`Feedback`](estimator::Feedback) (which current measures the force), the calibrated [`Estimator`](estimator::Estimator) a loop calls every period, and the [`Calibration`](estimator::Calibration) a teach cut makes |
//! | [`cut_forces`] | a logged cut's force from its feed, speed, depth and width (mechanistic model), for calibration without a dynamometer |
//! | [`cut_settings`] | such a cut's settings as one table (material, cutter, mode, depth, width) that the Logs page and `cutlab calibrate` parse alike |
//! | [`teach_fit`] | the one teach-cut fit: control periods at known loads → a calibration, with the periods it used and why it left the others out |
//! | [`speed`] | spindle speed from the F/V converter voltage, per gear range |
//! | [`power_law_fit`] | paper 004's network learned from trial cuts: the power law's exponents and bias for this machine, with their uncertainty |

pub mod current_force;
pub mod cut_forces;
pub mod cut_settings;
pub mod estimator;
pub mod load_levels;
pub mod power_law_fit;
pub mod speed;
pub mod teach_fit;

/// Reads a number that JSON wrote as `null` because it was not finite (serde_json writes NaN and
/// ±∞ as null) back as NaN, so a saved model round-trips; the reader of a saved calibration then
/// decides which of its numbers must be finite.
pub(crate) fn null_as_nan<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    use serde::Deserialize;
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// NaN, the default of a number a saved file may leave out.
pub(crate) fn nan() -> f64 {
    f64::NAN
}
