//! Why a run could not be set up or made: one error type for the loop, its settings and its
//! teach cut, whose variants name what is wrong in their own terms so a page can put the message
//! beside the control that caused it.

use std::fmt;

use super::definition::SettingError;
use crate::control::registry::ParamError;
use crate::estimation::estimator::Feedback;
use crate::math::least_squares::FitError;
use crate::plant::PlantError;
use crate::safety::EnvelopeError;
use crate::signal::butterworth::DesignError;

/// Why a loop could not be set up or run. Each variant says what is wrong in its own terms, so the
/// page can put the message beside the control that caused it.
#[derive(Debug, Clone, PartialEq)]
pub enum LoopError {
    /// A run setting is out of range or does not parse; names the setting.
    Setting(SettingError),
    /// A low-pass design failed.
    Filter(DesignError),
    /// The safety settings are inconsistent.
    Envelope(EnvelopeError),
    /// The controller's parameters do not build a controller.
    Controller(ParamError),
    /// The machine (a preset with edits) could not be built.
    Machine(PlantError),
    /// The teach cut did not give a usable model.
    Calibration(FitError),
    /// A given calibration measures force through another path than the run's feedback.
    CalibrationFeedback {
        /// The path the calibration was made for.
        calibration: Feedback,
        /// The path the run measures with.
        run: Feedback,
    },
    /// A given calibration never saw the program's spindle speed (or feed): its estimate there
    /// would be an extrapolation, and the controller would act on it.
    CalibrationElsewhere(String),
    /// A teach cut on a machine that reports no force (no simulation truth, no dynamometer) and
    /// whose cut changes along the path, so the model of the cut cannot stand in.
    NoTeachForce,
    /// Feed-current feedback on a cut that never loads the feed drive.
    NoFeedLoad,
    /// The control period is below one sample or absurdly long at this sample rate.
    ControlPeriod {
        /// The period asked for.
        period_s: f64,
        /// The machine's sample rate.
        sample_rate_hz: f64,
    },
    /// The target came to no positive force.
    NoTarget {
        /// Where it came from, in words.
        from: String,
        /// What it came to, N.
        force_n: f64,
    },
    /// The run's time limit is not a positive duration.
    TimeLimit(f64),
    /// A reference run (fixed feed) ended without a cycle time.
    NoReference,
    /// `finish` was asked for before the work was done, or twice.
    NotFinished,
}

impl fmt::Display for LoopError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LoopError::Setting(e) => write!(f, "{e}"),
            LoopError::Filter(e) => write!(f, "current filter: {e}"),
            LoopError::Envelope(e) => write!(f, "safety envelope: {e}"),
            LoopError::Controller(e) => write!(f, "controller: {e}"),
            LoopError::Machine(e) => write!(f, "{e}"),
            LoopError::Calibration(e) => write!(f, "calibration (teach cut): {e}"),
            LoopError::CalibrationElsewhere(why) => write!(
                f,
                "{why}; teach a cut on this program, or give a calibration made at its speed \
                 and feed"
            ),
            LoopError::CalibrationFeedback { calibration, run } => write!(
                f,
                "the calibration is for {} feedback but the run measures with {}; choose \
                 feedback {} or calibrate for {}",
                calibration.name(),
                run.name(),
                calibration.name(),
                run.name()
            ),
            LoopError::NoTeachForce => f.write_str(
                "the machine reports no force (no simulation truth, no dynamometer) and the \
                 program's cut changes along the path, so a teach cut has no force to learn \
                 from: give a saved calibration (--calibration FILE, from cutlab calibrate or an \
                 earlier run's --save-calibration)",
            ),
            LoopError::NoFeedLoad => f.write_str(
                "feed-current feedback needs a cut that loads the feed drive, and this one never \
                 pushed back against the feed (in down milling the cutting force pulls the table \
                 along); measure the force through the spindle current",
            ),
            LoopError::ControlPeriod {
                period_s,
                sample_rate_hz,
            } => write!(
                f,
                "control period {period_s} s must be at least one sample and at most 10⁷ samples \
                 at {sample_rate_hz} Hz"
            ),
            LoopError::NoTarget { from, force_n } if force_n.is_nan() => write!(
                f,
                "no force target: {from} cannot be turned into a force (this run's calibration \
                 relates no current to the force: its feedback is not a motor current, or its \
                 model is not defined there); give a target force"
            ),
            LoopError::NoTarget { from, force_n } => write!(
                f,
                "no force target: {from} comes to {} N; give a target force",
                crate::input::readable(*force_n)
            ),
            LoopError::TimeLimit(s) => {
                write!(f, "the run's time limit must be positive, not {s} s")
            }
            LoopError::NoReference => f.write_str("the reference runs found no cycle time"),
            LoopError::NotFinished => f.write_str("the run has not ended yet"),
        }
    }
}

impl std::error::Error for LoopError {}
