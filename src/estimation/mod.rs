//! Estimation: motor current → cutting force.
//!
//! | module | what it holds |
//! |---|---|
//! | [`current_force`] | paper 000's feed-current model and paper 003's spindle-current model, their calibration from a teach cut, and range checks |
//! | [`cut_forces`] | a logged cut's force from its feed, speed, depth and width (mechanistic model), for calibration without a dynamometer |
//! | [`teach_log`] | calibration from a logged teach cut (CSV text → both models and their fit quality), shared by `cutlab calibrate` and the browser |
//! | [`speed`] | spindle speed from the F/V converter voltage, per gear range |
//! | [`least_squares`] | the QR least-squares fit behind every calibration |

pub mod current_force;
pub mod cut_forces;
pub mod least_squares;
pub mod speed;
pub mod teach_log;

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
