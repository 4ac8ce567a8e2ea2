//! The calibrations a browser keeps: saved calibration files under one key of its
//! `localStorage`, so the Logs page can save one and Simulate and the Hardware page can list them.
//!
//! The key is [`STORAGE_KEY`]; its value is a JSON array of calibration files
//! ([`super::calibration_file`]), each named by its `source`. This module is the pure half (text
//! in, text out, testable natively); `src/web` reads and writes the storage.

use super::calibration_file::CalibrationFile;

/// The `localStorage` key that holds the saved calibrations.
pub const STORAGE_KEY: &str = "cutlab-calibrations";

/// The calibrations in the stored text, and a message for each entry that could not be read
/// (a file from a newer cutlab, an edited entry), naming its place in the list.
///
/// ```
/// use cutlab::closed_loop::calibration_store::read_store;
/// let (files, problems) = read_store(Some("[{\"format\": \"cutlab-runs\"}]"));
/// assert!(files.is_empty());
/// assert!(problems[0].starts_with("saved calibration 1:"), "{problems:?}");
/// assert_eq!(read_store(None).0.len(), 0);
/// ```
pub fn read_store(text: Option<&str>) -> (Vec<CalibrationFile>, Vec<String>) {
    let Some(text) = text.filter(|t| !t.trim().is_empty()) else {
        return (Vec::new(), Vec::new());
    };
    let entries: Vec<serde_json::Value> = match serde_json::from_str(text) {
        Ok(entries) => entries,
        Err(e) => {
            return (
                Vec::new(),
                vec![format!(
                    "the saved calibrations ({STORAGE_KEY}) are not a JSON list: {e}"
                )],
            )
        }
    };
    let mut files = Vec::new();
    let mut problems = Vec::new();
    for (i, entry) in entries.iter().enumerate() {
        match CalibrationFile::from_json(&entry.to_string()) {
            Ok(file) => files.push(file),
            Err(e) => problems.push(format!("saved calibration {}: {e}", i + 1)),
        }
    }
    (files, problems)
}

/// The stored text with `file` added; an entry of the same `source` is replaced, so saving again
/// updates it. Entries that cannot be read are kept as they were (nothing a user saved is lost).
///
/// ```
/// use cutlab::closed_loop::calibration_store::{read_store, with_saved};
/// use cutlab::closed_loop::calibration_file::CalibrationFile;
/// use cutlab::closed_loop::lab::teach_cut_only;
/// use cutlab::closed_loop::definition::RunSpec;
/// use cutlab::control::registry::ControllerKind;
/// use cutlab::plant::Preset;
/// let (_, c) = teach_cut_only(&RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Fixed)).unwrap();
/// let text = with_saved(None, &CalibrationFile::new(c.clone(), "a"));
/// let text = with_saved(Some(&text), &CalibrationFile::new(c.clone(), "b"));
/// let text = with_saved(Some(&text), &CalibrationFile::new(c, "a"));
/// let names: Vec<String> = read_store(Some(&text)).0.into_iter().map(|f| f.source).collect();
/// assert_eq!(names, ["b", "a"]);
/// ```
pub fn with_saved(text: Option<&str>, file: &CalibrationFile) -> String {
    let mut entries: Vec<serde_json::Value> = text
        .and_then(|t| serde_json::from_str(t).ok())
        .unwrap_or_default();
    entries.retain(|e| e.get("source").and_then(|s| s.as_str()) != Some(file.source.as_str()));
    if let Ok(value) = serde_json::from_str::<serde_json::Value>(&file.to_json()) {
        entries.push(value);
    }
    serde_json::to_string(&entries).unwrap_or_else(|_| "[]".to_string())
}
