//! Teach cuts computed ahead of time: the calibration of the lab's default scenario, shipped with
//! the code, so the browser's first run on it starts with the closed loop instead of a 66 s teach
//! cut (about half of the first result's time).
//!
//! A simulation repeats itself exactly for the same [`TeachKey`], so a shipped calibration is the
//! one the teach cut would learn, to the bit; `tests/sample_data.rs` holds the file to that
//! (`scripts/sample-data` writes it again when the plant or the chain changes). An edit that
//! changes the teach cut (another preset, seed, machine or signal-chain setting) has another key
//! and teaches as usual.

use super::calibration_file::CalibrationFile;
use super::lab::{RunSpec, TeachKey};
use super::runner::Calibration;
use crate::control::registry::ControllerKind;
use crate::plant::Preset;

/// kim-step-doc's teach cut with its default settings, as `cutlab sim --scenario kim-step-doc
/// --controller fixed --save-calibration` writes it.
const KIM_STEP_DOC: &str = include_str!("../../www/data/kim-step-doc-calibration.json");

/// The shipped calibrations with the key of the teach cut each one is. A file that does not
/// read (it cannot, short of a broken build) is left out: those runs teach as usual.
///
/// ```
/// use cutlab::closed_loop::lab::{RunSpec, TeachKey};
/// use cutlab::closed_loop::precomputed::shipped_calibrations;
/// use cutlab::control::registry::ControllerKind;
/// use cutlab::plant::Preset;
/// let shipped = shipped_calibrations();
/// let default_run = RunSpec::new(Preset::KimStepDoc, ControllerKind::Threshold);
/// assert!(shipped.iter().any(|(key, _)| Ok(key) == TeachKey::of(&default_run).as_ref()));
/// ```
pub fn shipped_calibrations() -> Vec<(TeachKey, Calibration)> {
    let spec = RunSpec::new(Preset::KimStepDoc, ControllerKind::Fixed);
    match (
        TeachKey::of(&spec),
        CalibrationFile::from_json(KIM_STEP_DOC),
    ) {
        (Ok(key), Ok(file)) => vec![(key, file.calibration)],
        _ => Vec::new(),
    }
}
