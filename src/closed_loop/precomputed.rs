//! Work computed ahead of time for the lab's default scenario, shipped with the code: its teach
//! cut's calibration, so the browser's first run on it starts with the closed loop instead of a
//! 66 s teach cut (about half of the first result's time), and its fixed-feed references, so its
//! savings appear with the first result instead of after three to five more runs.
//!
//! A simulation repeats itself exactly for the same [`TeachKey`] (and the references for the
//! same scenario), so what is shipped is what the lab would compute, to the bit;
//! `tests/sample_data.rs` holds both files to that (`scripts/sample-data` writes them again when
//! the plant, the chain or the envelope changes). An edit that changes the teach cut or the
//! scenario (another preset, seed, machine, signal-chain or envelope setting, target) has another
//! key and computes as usual.

use super::calibration_file::CalibrationFile;
use super::definition::RunSpec;
use super::lab::TeachKey;
use super::references::{References, ScenarioKey};
use crate::control::registry::ControllerKind;
use crate::estimation::estimator::Calibration;
use crate::plant::Preset;

/// kim-step-doc's teach cut with its default settings, as `cutlab sim --scenario kim-step-doc
/// --controller fixed --save-calibration` writes it.
const KIM_STEP_DOC: &str = include_str!("../../www/data/kim-step-doc-calibration.json");

/// kim-step-doc's fixed-feed references with its default settings, as `cutlab sim --scenario
/// kim-step-doc --controller fixed --json` reports them.
const KIM_STEP_DOC_REFERENCES: &str = include_str!("../../www/data/kim-step-doc-references.json");

/// The shipped calibrations with the key of the teach cut each one is. A file that does not
/// read (it cannot, short of a broken build) is left out: those runs teach as usual.
///
/// ```
/// use cutlab::closed_loop::definition::RunSpec;
/// use cutlab::closed_loop::lab::TeachKey;
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

/// The shipped fixed-feed references with the key of the scenario each one is of.
///
/// ```
/// use cutlab::closed_loop::definition::RunSpec;
/// use cutlab::closed_loop::references::ScenarioKey;
/// use cutlab::closed_loop::precomputed::shipped_references;
/// use cutlab::control::registry::ControllerKind;
/// use cutlab::plant::Preset;
/// let default_run = RunSpec::new(Preset::KimStepDoc, ControllerKind::Threshold);
/// let key = ScenarioKey::of(&default_run).unwrap();
/// assert!(shipped_references().iter().any(|(k, _)| *k == key));
/// ```
pub fn shipped_references() -> Vec<(ScenarioKey, References)> {
    let spec = RunSpec::new(Preset::KimStepDoc, ControllerKind::Fixed);
    let references = serde_json::from_str::<References>(KIM_STEP_DOC_REFERENCES);
    match (ScenarioKey::of(&spec), references) {
        (Ok(key), Ok(references)) => vec![(key, references)],
        _ => Vec::new(),
    }
}
