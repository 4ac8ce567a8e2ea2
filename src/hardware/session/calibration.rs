//! A calibration the closed loop can use, with what it was made with ([`TaughtCalibration`]),
//! and why a run cannot use it.

use crate::closed_loop::error::LoopError;
use crate::closed_loop::settings::ChainSettings;
use crate::estimation::estimator::Calibration;
use crate::estimation::teach_fit::load_level_warnings;

/// A calibration the closed loop can use, with what it was made with.
#[derive(Debug, Clone, PartialEq)]
pub struct TaughtCalibration {
    /// The fitted model.
    pub calibration: Calibration,
    /// The settings of the teach cut when it was made over this link: a run must measure the
    /// force the same way. `None` for a saved calibration, whose file keeps only the model.
    pub settings: Option<ChainSettings>,
    /// Where it came from.
    pub source: String,
}

impl TaughtCalibration {
    /// What to warn the operator of before using it, one sentence each: a fitted line that rests
    /// on too few load levels, or a saved calibration that cannot say
    /// ([`load_level_warnings`], the words every front end uses).
    pub fn warnings(&self) -> Vec<String> {
        load_level_warnings(&self.calibration)
    }

    /// Why a run with the signal chain `settings` cannot use this calibration, if it cannot: the
    /// feedback path must be the calibration's, and after a teach cut over this link the signal
    /// chain too (the fitted line holds for those only).
    pub fn mismatch(&self, settings: &ChainSettings) -> Option<String> {
        let feedback = self.calibration.estimator.feedback();
        if feedback != settings.feedback {
            return Some(
                LoopError::CalibrationFeedback {
                    calibration: feedback,
                    run: settings.feedback,
                }
                .to_string(),
            );
        }
        let t = self.settings.as_ref()?;
        let differs = |a: f64, b: f64| (a - b).abs() > 1e-9 * a.abs().max(b.abs()).max(1.0);
        let field = if t.feedback != settings.feedback {
            Some(format!(
                "the feedback ({} in the teach cut, {} now)",
                t.feedback.name(),
                settings.feedback.name()
            ))
        } else if differs(t.control_period_s, settings.control_period_s) {
            Some(format!(
                "the control period ({} s in the teach cut, {} s now)",
                t.control_period_s, settings.control_period_s
            ))
        } else if t.lowpass_order != settings.lowpass_order {
            Some(format!(
                "the filter order ({} in the teach cut, {} now)",
                t.lowpass_order, settings.lowpass_order
            ))
        } else if differs(t.spindle_lowpass_hz, settings.spindle_lowpass_hz) {
            Some(format!(
                "the spindle current cut-off ({} Hz in the teach cut, {} Hz now)",
                t.spindle_lowpass_hz, settings.spindle_lowpass_hz
            ))
        } else if differs(t.feed_lowpass_hz, settings.feed_lowpass_hz) {
            Some(format!(
                "the feed current cut-off ({} Hz in the teach cut, {} Hz now)",
                t.feed_lowpass_hz, settings.feed_lowpass_hz
            ))
        } else {
            None
        };
        field.map(|f| {
            format!(
                "the calibration was made with other settings: {f}; teach again or change it back"
            )
        })
    }
}
