//! The calibrations saved in this browser's `localStorage`
//! ([`crate::closed_loop::calibration_store`]): the Logs page saves them, the Hardware page
//! starts a run from one.

use leptos::prelude::window;

use crate::closed_loop::calibration_file::CalibrationFile;
use crate::closed_loop::calibration_store::{read_store, with_saved, STORAGE_KEY};

/// The saved calibrations, and what could not be read (each named by its place in the list).
pub fn stored_calibrations() -> (Vec<CalibrationFile>, Vec<String>) {
    let text = window()
        .local_storage()
        .ok()
        .flatten()
        .and_then(|s| s.get_item(STORAGE_KEY).ok().flatten());
    read_store(text.as_deref())
}

/// Saves `file` (replacing a saved one of the same source).
pub fn save_calibration(file: &CalibrationFile) -> Result<(), String> {
    let storage = window()
        .local_storage()
        .ok()
        .flatten()
        .ok_or("this browser keeps no local storage")?;
    let text = storage.get_item(STORAGE_KEY).ok().flatten();
    storage
        .set_item(STORAGE_KEY, &with_saved(text.as_deref(), file))
        .map_err(|_| "the browser refused to store the calibration (storage full?)".to_string())
}
