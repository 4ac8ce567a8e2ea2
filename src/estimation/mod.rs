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
