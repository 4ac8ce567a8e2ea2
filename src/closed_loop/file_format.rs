//! What every JSON file cutlab saves opens with — `"format"` and `"version"` — and how reading
//! checks them before anything else, so that a file of another kind, or one a newer cutlab wrote,
//! gets a message about that rather than about its first unexpected field.

use std::fmt;
use std::ops::RangeInclusive;

use serde::Deserialize;

/// Why a file is not one this build reads.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FormatError(pub String);

impl fmt::Display for FormatError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

/// Checks that `text` is JSON whose `"format"` is `format` and whose `"version"` is `version`;
/// `what` names the kind of file in messages ("configuration", "calibration").
///
/// ```
/// use cutlab::closed_loop::file_format::check_format;
/// assert!(check_format(r#"{"format": "x", "version": 1}"#, "x", 1, "thing").is_ok());
/// let e = check_format(r#"{"format": "x", "version": 3}"#, "x", 1, "thing").unwrap_err();
/// assert!(e.to_string().contains("version 3, written by a newer cutlab"));
/// ```
pub fn check_format(text: &str, format: &str, version: u32, what: &str) -> Result<(), FormatError> {
    check_format_versions(text, format, version..=version, what)
}

/// [`check_format`] for a kind of file this build reads in several versions (`versions`, the
/// newest last): an older one is read as it was written, a newer one is refused as such.
///
/// ```
/// use cutlab::closed_loop::file_format::check_format_versions;
/// let file = |v: u32| format!(r#"{{"format": "x", "version": {v}}}"#);
/// assert!(check_format_versions(&file(1), "x", 1..=2, "thing").is_ok());
/// assert!(check_format_versions(&file(2), "x", 1..=2, "thing").is_ok());
/// let e = check_format_versions(&file(3), "x", 1..=2, "thing").unwrap_err();
/// assert!(e.to_string().contains("this one reads versions 1 to 2"), "{e}");
/// let e = check_format_versions(&file(0), "x", 1..=2, "thing").unwrap_err();
/// assert!(e.to_string().starts_with("\"version\" must be 1 to 2, found"), "{e}");
/// ```
pub fn check_format_versions(
    text: &str,
    format: &str,
    versions: RangeInclusive<u32>,
    what: &str,
) -> Result<(), FormatError> {
    #[derive(Deserialize)]
    struct Opening {
        format: Option<String>,
        version: Option<serde_json::Value>,
    }
    let opening: Opening = serde_json::from_str(text).map_err(|e| {
        FormatError(crate::input::one_short_line(&format!(
            "not a cutlab {what}: {e}"
        )))
    })?;
    if opening.format.as_deref() != Some(format) {
        return Err(FormatError(format!(
            "not a cutlab {what}: \"format\" must be \"{format}\", found {}",
            opening
                .format
                .map_or("nothing".to_string(), |f| crate::input::excerpt(&f))
        )));
    }
    let (oldest, newest) = (*versions.start(), *versions.end());
    let readable = if oldest == newest {
        newest.to_string()
    } else {
        format!("{oldest} to {newest}")
    };
    match opening.version.as_ref().and_then(serde_json::Value::as_u64) {
        Some(v) if (u64::from(oldest)..=u64::from(newest)).contains(&v) => Ok(()),
        Some(v) if v > u64::from(newest) => Err(FormatError(format!(
            "this {what} is version {v}, written by a newer cutlab; this one reads version{} \
             {readable}",
            if oldest == newest { "" } else { "s" }
        ))),
        _ => Err(FormatError(format!(
            "\"version\" must be {readable}, found {}",
            opening
                .version
                .map_or("nothing".to_string(), |v| crate::input::excerpt(
                    &v.to_string()
                ))
        ))),
    }
}
