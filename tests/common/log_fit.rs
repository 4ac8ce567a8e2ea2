//! A log read as the Logs page and `cutlab calibrate` read it — loaded, its columns mapped by
//! their guessed roles — and calibrated with its own measured force, the replay's default
//! settings: tests/log_replay.rs's synthetic phase logs and tests/sample_data.rs's DAQ capture.
// Each test binary uses a different subset of these helpers.
#![allow(dead_code)]

use std::sync::Arc;

use cutlab::log::calibration::{fit_calibration, ForceSource, LogFit};
use cutlab::log::mapping::Mapping;
use cutlab::log::replay::ReplaySettings;
use cutlab::log::{load, Log};

/// `bytes` (a CSV log) loaded, mapped by its guessed roles and fitted against its measured force.
///
/// # Panics
/// If the log does not load or does not calibrate: the tests that call this expect both.
pub fn measured_fit(bytes: &[u8]) -> (Arc<Log>, Mapping, LogFit) {
    let log = Arc::new(load(bytes, None).unwrap());
    let mapping = Mapping::guess(&log);
    let fit = fit_calibration(
        &log,
        &mapping,
        &ReplaySettings::default(),
        &ForceSource::Measured,
    )
    .unwrap_or_else(|e| panic!("{e} (mapping {mapping:?})"));
    (log, mapping, fit)
}
