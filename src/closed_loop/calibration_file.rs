//! A saved calibration: the current-to-force model a teach cut (or a logged cut) produced, as JSON
//! a person can read, keep with the machine and load again — so a run on the simulated machine,
//! a replayed log or the real machine can start from it instead of cutting a teach part.
//!
//! ```json
//! {
//!   "format": "cutlab-calibration",
//!   "version": 2,
//!   "source": "teach cut on kim-step-doc, seed 1",
//!   "calibration": {
//!     "estimator": { "feedback": "spindle", "model": { "gear_change_rpm": 900.0, "rows": [ … ] },
//!                    "speed": { … } },
//!     "median_force_at_full_override_n": 812.4,
//!     "regulated_per_resultant": 1.0,
//!     "periods": 512,
//!     "max_phase_current_a": 18.2,
//!     "duration_s": 65.9,
//!     "few_load_levels": []
//!   }
//! }
//! ```
//!
//! Version 2 added `few_load_levels`: the fitted lines that rest on too few load levels to be
//! determined ([`crate::estimation::load_levels::FewLoadLevels`]), so that a saved calibration
//! warns when it is loaded as its teach cut did when it was made
//! ([`crate::estimation::teach_fit::load_level_warnings`]). A version 1 file is still read; its
//! lines' load levels are unknown (`None`), and the warnings say so.
//!
//! Reading checks more than the JSON's shape: every number the estimator divides by or compares
//! with must be finite and of the right sign, spindle rows must ascend in speed, and a model that
//! cannot estimate anything is refused — each with the path of the field at fault
//! (`calibration.estimator.model.rows[1].sensitivity_a_per_n: …`). A number that was not finite
//! when saved is written as `null` (as serde_json writes NaN) and read back as NaN where that is
//! allowed (an F/V gear range never calibrated, the ratio a dynamometer teach cut has none of).

use std::fmt;

use serde::{Deserialize, Serialize};

use super::file_format::{check_format_versions, FormatError};
use crate::estimation::current_force::{FitQuality, Range};
use crate::estimation::estimator::{Calibration, Estimator, Feedback};

/// The largest current sensitivity a calibration may have, A per N. A newton of cutting force
/// moving a drive's current by more than this is no milling drive (fitted spindle and feed
/// sensitivities are thousandths of an ampere per newton); a larger one makes every estimate
/// read near 0 N, and a controller would then feed as fast as it may.
pub const MAX_SENSITIVITY_A_PER_N: f64 = 10.0;

/// The `format` every calibration file carries.
pub const FORMAT: &str = "cutlab-calibration";
/// The version this build writes (and the newest it reads).
pub const VERSION: u32 = 2;
/// The oldest version this build reads: version 1 files lack `few_load_levels`.
pub const OLDEST_VERSION: u32 = 1;

/// A calibration with what made it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationFile {
    /// Always [`FORMAT`].
    pub format: String,
    /// [`VERSION`] for files this build writes; from [`OLDEST_VERSION`] for those it reads.
    pub version: u32,
    /// Where the calibration came from, for people ("teach cut on kim-step-doc, seed 1",
    /// "log spindle-2026-11-20.csv, column S_current").
    #[serde(default)]
    pub source: String,
    /// The model and what the teach cut saw.
    pub calibration: Calibration,
}

/// Why a calibration file could not be read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CalibrationFileError(pub String);

impl fmt::Display for CalibrationFileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for CalibrationFileError {}

impl From<FormatError> for CalibrationFileError {
    fn from(e: FormatError) -> Self {
        Self(e.0)
    }
}

impl CalibrationFile {
    /// A file of `calibration`, made by `source`.
    pub fn new(calibration: Calibration, source: impl Into<String>) -> Self {
        Self {
            format: FORMAT.to_string(),
            version: VERSION,
            source: source.into(),
            calibration,
        }
    }

    /// The feedback path the calibration measures force with.
    pub fn feedback(&self) -> Feedback {
        self.calibration.estimator.feedback()
    }

    /// Pretty-printed JSON.
    pub fn to_json(&self) -> String {
        // Plain structs of numbers and strings cannot fail to serialise; a non-finite number
        // becomes null, which reading maps back to NaN where NaN is allowed.
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// Reads a calibration file, naming the line and column, or the field, of anything wrong.
    ///
    /// ```
    /// use cutlab::closed_loop::calibration_file::CalibrationFile;
    /// use cutlab::closed_loop::lab::teach_cut_only;
    /// use cutlab::closed_loop::definition::RunSpec;
    /// use cutlab::control::registry::ControllerKind;
    /// use cutlab::plant::Preset;
    /// let spec = RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Fixed);
    /// let (_, calibration) = teach_cut_only(&spec).unwrap();
    /// let file = CalibrationFile::new(calibration, "teach cut on maneerat-doc1");
    /// let read = CalibrationFile::from_json(&file.to_json()).unwrap();
    /// assert_eq!(read.calibration.duration_s, file.calibration.duration_s);
    /// let e = CalibrationFile::from_json(r#"{"format": "cutlab-runs", "version": 1}"#).unwrap_err();
    /// assert!(e.to_string().contains("\"format\" must be \"cutlab-calibration\""), "{e}");
    /// ```
    pub fn from_json(text: &str) -> Result<Self, CalibrationFileError> {
        check_format_versions(text, FORMAT, OLDEST_VERSION..=VERSION, "calibration")?;
        let file: Self = serde_json::from_str(text)
            .map_err(|e| CalibrationFileError(crate::input::one_short_line(&e.to_string())))?;
        check_calibration(&file.calibration).map_err(CalibrationFileError)?;
        Ok(file)
    }
}

/// Checks that a calibration read from outside can estimate: the message names the field.
fn check_calibration(c: &Calibration) -> Result<(), String> {
    let at = "calibration";
    match &c.estimator {
        Estimator::Spindle { model, speed } => {
            let at = format!("{at}.estimator.model");
            positive(&format!("{at}.gear_change_rpm"), model.gear_change_rpm)?;
            if model.rows.is_empty() {
                return Err(format!(
                    "{at}.rows: empty; a spindle model needs at least one calibrated speed"
                ));
            }
            let mut previous_rpm = f64::NEG_INFINITY;
            for (i, row) in model.rows.iter().enumerate() {
                let at = format!("{at}.rows[{i}]");
                positive(&format!("{at}.speed_rpm"), row.speed_rpm)?;
                if row.speed_rpm <= previous_rpm {
                    return Err(format!(
                        "{at}.speed_rpm: rows must ascend in speed, and {} follows {}",
                        row.speed_rpm, previous_rpm
                    ));
                }
                previous_rpm = row.speed_rpm;
                finite(&format!("{at}.idle_current_a"), row.idle_current_a)?;
                sensitivity(
                    &format!("{at}.sensitivity_a_per_n"),
                    row.sensitivity_a_per_n,
                )?;
                check_range(&format!("{at}.current_range_a"), &row.current_range_a)?;
                check_quality(&format!("{at}.quality"), &row.quality)?;
            }
            let at = "calibration.estimator.speed";
            positive(&format!("{at}.gear_change_rpm"), speed.gear_change_rpm)?;
            let slopes = [
                ("low_range_v_per_rpm", speed.low_range_v_per_rpm),
                ("high_range_v_per_rpm", speed.high_range_v_per_rpm),
            ];
            for (name, slope) in slopes {
                // NaN is a gear range the teach cut never ran in (or, for both, a calibration
                // from a log without an F/V converter's voltage): the estimator then takes the
                // programmed speed. Anything else must be a real slope.
                if !slope.is_nan() {
                    positive(&format!("{at}.{name}"), slope)?;
                }
            }
        }
        Estimator::Feed { model } => {
            let at = format!("{at}.estimator.model");
            finite(&format!("{at}.idle_current_a"), model.idle_current_a)?;
            finite(
                &format!("{at}.idle_current_a_per_mm_min"),
                model.idle_current_a_per_mm_min,
            )?;
            sensitivity(
                &format!("{at}.sensitivity_a_per_n"),
                model.sensitivity_a_per_n,
            )?;
            check_range(&format!("{at}.current_range_a"), &model.current_range_a)?;
            check_range(&format!("{at}.feed_range_mm_min"), &model.feed_range_mm_min)?;
            check_quality(&format!("{at}.quality"), &model.quality)?;
        }
        Estimator::Dynamometer => {}
    }
    // NaN means the teach cut never cut at 100 %: the run then needs an explicit target.
    if !c.median_force_at_full_override_n.is_nan() {
        positive(
            "calibration.median_force_at_full_override_n",
            c.median_force_at_full_override_n,
        )?;
    }
    if !c.regulated_per_resultant.is_nan() {
        positive(
            "calibration.regulated_per_resultant",
            c.regulated_per_resultant,
        )?;
    }
    if !(c.max_phase_current_a.is_finite() && c.max_phase_current_a >= 0.0) {
        return Err(format!(
            "calibration.max_phase_current_a: must be a finite current ≥ 0 A, not {}",
            shown(c.max_phase_current_a)
        ));
    }
    if !(c.duration_s.is_finite() && c.duration_s >= 0.0) {
        return Err(format!(
            "calibration.duration_s: must be a finite time ≥ 0 s, not {}",
            shown(c.duration_s)
        ));
    }
    Ok(())
}

fn finite(at: &str, v: f64) -> Result<(), String> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(format!("{at}: must be a finite number, not {}", shown(v)))
    }
}

fn positive(at: &str, v: f64) -> Result<(), String> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(format!(
            "{at}: must be a positive finite number, not {}",
            shown(v)
        ))
    }
}

fn sensitivity(at: &str, v: f64) -> Result<(), String> {
    positive(at, v)?;
    if v > MAX_SENSITIVITY_A_PER_N {
        return Err(format!(
            "{at}: {} A/N is beyond any drive's sensitivity (at most {} A/N): every force \
             estimate would read near 0 N",
            crate::input::readable(v),
            crate::input::readable(MAX_SENSITIVITY_A_PER_N)
        ));
    }
    Ok(())
}

fn check_range(at: &str, r: &Range) -> Result<(), String> {
    finite(&format!("{at}.min"), r.min)?;
    finite(&format!("{at}.max"), r.max)?;
    if r.min > r.max {
        return Err(format!(
            "{at}: min {} is above max {}",
            shown(r.min),
            shown(r.max)
        ));
    }
    Ok(())
}

fn check_quality(at: &str, q: &FitQuality) -> Result<(), String> {
    // Quality is reported, never computed with: NaN (a fit of exactly as many samples as
    // unknowns) is allowed; a negative spread is not.
    for (name, v) in [
        ("residual_std_a", q.residual_std_a),
        ("residual_std_n", q.residual_std_n),
    ] {
        if v < 0.0 || v.is_infinite() {
            return Err(format!(
                "{at}.{name}: must be a spread ≥ 0, not {}",
                shown(v)
            ));
        }
    }
    Ok(())
}

/// A number as the file wrote it (NaN was `null`), compact (1e300, not 301 digits).
fn shown(v: f64) -> String {
    if v.is_nan() {
        "null".to_string()
    } else {
        crate::input::readable(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::closed_loop::definition::RunSpec;
    use crate::closed_loop::lab::teach_cut_only;
    use crate::control::registry::ControllerKind;
    use crate::plant::Preset;

    fn saved(preset: Preset) -> CalibrationFile {
        let spec = RunSpec::new(preset, ControllerKind::Fixed);
        let (_, calibration) = teach_cut_only(&spec).unwrap();
        CalibrationFile::new(calibration, format!("teach cut on {}", preset.name()))
    }

    #[test]
    fn spindle_feed_and_dynamometer_calibrations_round_trip_bit_for_bit() {
        for (preset, feedback) in [
            (Preset::KimStepDoc, Feedback::SpindleCurrent),
            (Preset::WangBrakeBench, Feedback::FeedCurrent),
            (Preset::ManeeratSecondOrder, Feedback::Dynamometer),
        ] {
            let file = saved(preset);
            assert_eq!(file.feedback(), feedback);
            let read = CalibrationFile::from_json(&file.to_json()).unwrap();
            // Debug text compares every bit, and NaN (written null) equal to NaN.
            assert_eq!(
                format!("{read:?}"),
                format!("{file:?}"),
                "{}",
                preset.name()
            );
        }
    }

    #[test]
    fn a_calibration_that_cannot_estimate_is_refused_with_the_field_path() {
        let text = saved(Preset::KimStepDoc).to_json();
        let json: serde_json::Value = serde_json::from_str(&text).unwrap();
        let edit = |path: &[&str], value: serde_json::Value| {
            let mut j = json.clone();
            let mut at = &mut j;
            for key in path {
                at = match key.parse::<usize>() {
                    Ok(i) => &mut at[i],
                    Err(_) => &mut at[*key],
                };
            }
            *at = value;
            CalibrationFile::from_json(&serde_json::to_string_pretty(&j).unwrap())
                .unwrap_err()
                .to_string()
        };
        let rows = ["calibration", "estimator", "model", "rows"];
        let e = edit(
            &[&rows[..], &["0", "sensitivity_a_per_n"]].concat(),
            (-0.01).into(),
        );
        assert!(
            e.contains("calibration.estimator.model.rows[0].sensitivity_a_per_n")
                && e.contains("-0.01"),
            "{e}"
        );
        // An absurd sensitivity would read every current as 0 N.
        let e = edit(
            &[&rows[..], &["0", "sensitivity_a_per_n"]].concat(),
            1e308.into(),
        );
        assert!(
            e.contains("rows[0].sensitivity_a_per_n: 1e308 A/N is beyond any drive's sensitivity"),
            "{e}"
        );
        let e = edit(&rows, serde_json::json!([]));
        assert!(e.contains("rows: empty"), "{e}");
        // kim-step-doc runs above the gear change only: the low range's slope is null (never
        // calibrated), which is allowed.
        assert!(text.contains("\"low_range_v_per_rpm\": null"), "{text}");
        // Without either slope (a calibration from a log without the F/V voltage) the estimator
        // reads the programmed speed: allowed.
        let mut no_fv = json.clone();
        no_fv["calibration"]["estimator"]["speed"]["high_range_v_per_rpm"] =
            serde_json::Value::Null;
        let read = CalibrationFile::from_json(&no_fv.to_string()).unwrap();
        let Estimator::Spindle { speed, .. } = &read.calibration.estimator else {
            panic!("a spindle model");
        };
        assert_eq!(speed.speed_rpm(4.2, 1000.0), 1000.0);
        let e = edit(
            &["calibration", "estimator", "speed", "high_range_v_per_rpm"],
            0.into(),
        );
        assert!(
            e.contains("calibration.estimator.speed.high_range_v_per_rpm: must be a positive"),
            "{e}"
        );
        let e = edit(
            &["calibration", "max_phase_current_a"],
            serde_json::Value::Null,
        );
        // A number the shape requires is a JSON error with its place in the file.
        assert!(e.contains("expected f64 at line"), "{e}");
        let e = edit(
            &["calibration", "estimator", "feedback"],
            "magnetometer".into(),
        );
        assert!(e.contains("unknown variant `magnetometer`"), "{e}");
        let e = edit(&["calibration", "tolerance"], 1.into());
        assert!(e.contains("unknown field `tolerance`"), "{e}");
    }

    #[test]
    fn a_saved_calibration_keeps_its_few_load_levels_warning() {
        use crate::estimation::load_levels::{FewLoadLevels, LineModel};
        use crate::estimation::teach_fit::load_level_warnings;
        let mut file = saved(Preset::KimStepDoc);
        // kim-step-doc's teach cut runs over many loads: nothing to warn of, and the file says so.
        assert_eq!(file.calibration.few_load_levels, Some(Vec::new()));
        assert!(file.to_json().contains("\"few_load_levels\": []"));
        assert!(load_level_warnings(&file.calibration).is_empty());
        let two = FewLoadLevels {
            model: LineModel::Spindle,
            speed_rpm: 1000.0,
            levels_n: vec![150.0, 300.0],
            r_squared: 0.9995,
        };
        file.calibration.few_load_levels = Some(vec![two.clone()]);
        let read = CalibrationFile::from_json(&file.to_json()).unwrap();
        assert_eq!(read.calibration.few_load_levels, Some(vec![two.clone()]));
        // The same sentence as the fit gave.
        assert_eq!(load_level_warnings(&read.calibration), vec![two.describe()]);
        assert!(load_level_warnings(&read.calibration)[0]
            .starts_with("the spindle line at 1000 rpm rests on 2 load levels (150, 300 N)"));
    }

    #[test]
    fn a_version_1_file_is_read_and_says_its_load_levels_are_unknown() {
        let mut json: serde_json::Value =
            serde_json::from_str(&saved(Preset::KimStepDoc).to_json()).unwrap();
        json["version"] = 1.into();
        json["calibration"]
            .as_object_mut()
            .unwrap()
            .remove("few_load_levels");
        let read = CalibrationFile::from_json(&json.to_string()).unwrap();
        assert_eq!(read.calibration.few_load_levels, None);
        let warnings = crate::estimation::teach_fit::load_level_warnings(&read.calibration);
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(
            warnings[0].starts_with(
                "the calibration does not say how many load levels its lines rest on (saved by \
                 an older cutlab)"
            ),
            "{warnings:?}"
        );
        // Saved again, it still cannot say (null, not an empty list).
        let again = CalibrationFile::from_json(&read.to_json()).unwrap();
        assert_eq!(again.calibration.few_load_levels, None);
        // A dynamometer fits nothing: nothing to be unknown.
        let mut dyn_json: serde_json::Value =
            serde_json::from_str(&saved(Preset::ManeeratSecondOrder).to_json()).unwrap();
        dyn_json["calibration"]
            .as_object_mut()
            .unwrap()
            .remove("few_load_levels");
        let read = CalibrationFile::from_json(&dyn_json.to_string()).unwrap();
        assert!(crate::estimation::teach_fit::load_level_warnings(&read.calibration).is_empty());
    }

    #[test]
    fn other_files_and_versions_are_named_as_such() {
        for (text, expected) in [
            ("not json", "not a cutlab calibration"),
            (
                r#"{"format": "cutlab-runs", "version": 1, "runs": []}"#,
                "\"format\" must be \"cutlab-calibration\"",
            ),
            (
                r#"{"format": "cutlab-calibration", "version": 3}"#,
                "version 3, written by a newer cutlab; this one reads versions 1 to 2",
            ),
            (
                r#"{"format": "cutlab-calibration", "version": 1}"#,
                "missing field `calibration`",
            ),
        ] {
            let e = CalibrationFile::from_json(text).unwrap_err().to_string();
            assert!(e.contains(expected), "{text} → {e}");
        }
    }
}
