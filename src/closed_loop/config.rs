//! A saved configuration: the runs a page made, as JSON a person can read, keep beside a report
//! and run again — in the browser (its link) or in a terminal (`cutlab sim --config FILE`,
//! `cutlab compare --config FILE`).
//!
//! ```json
//! {
//!   "format": "cutlab-runs",
//!   "version": 1,
//!   "link": "http://127.0.0.1:8080/#/simulate?preset=kim-step-doc&…",
//!   "runs": [
//!     { "preset": "kim-step-doc", "controller": { "kind": "threshold", "params": { … } },
//!       "seed": 1, "settings": { "target_force_n": 600.0 }, "plant": { "spindle_rpm": 1200.0 } }
//!   ]
//! }
//! ```
//!
//! Each run is a [`RunSpec`]: settings and machine edits left out keep the preset's values, and
//! every controller parameter is written out, so a later change of a default does not change what
//! a saved file means. Unknown fields are errors, not silently ignored: a misspelt
//! `"target_force"` would otherwise run at the preset's target, a misspelt `"parms"` in a
//! controller object at the controller's defaults. Every setting is checked against its range
//! when the file is read, so an error names the run and the field before anything runs.

use std::fmt;

use serde::{Deserialize, Serialize};

use super::definition::{check_spec, RunSpec};
use super::file_format::check_format;

/// The `format` every saved configuration carries.
pub const FORMAT: &str = "cutlab-runs";
/// The version this build writes and reads.
pub const VERSION: u32 = 1;

/// Runs saved together.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunConfiguration {
    /// Always [`FORMAT`]: tells a cutlab configuration from any other JSON.
    pub format: String,
    /// Always [`VERSION`] for files this build writes.
    pub version: u32,
    /// The page link that reproduces the runs in the browser, when saved from one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub link: Option<String>,
    /// The runs, in the order the page showed them.
    pub runs: Vec<RunSpec>,
}

/// Why a saved configuration could not be read.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConfigError(pub String);

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ConfigError {}

impl RunConfiguration {
    /// A configuration of `runs`, saved from `link` if any.
    pub fn new(runs: Vec<RunSpec>, link: Option<String>) -> Self {
        Self {
            format: FORMAT.to_string(),
            version: VERSION,
            link,
            runs,
        }
    }

    /// Pretty-printed JSON.
    pub fn to_json(&self) -> String {
        // Serialising plain structs of numbers and strings cannot fail; a non-finite number
        // becomes null, which reading then refuses with its place.
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// Reads a configuration, naming the line and column of anything wrong.
    ///
    /// ```
    /// use cutlab::closed_loop::config::RunConfiguration;
    /// use cutlab::closed_loop::definition::RunSpec;
    /// use cutlab::control::registry::ControllerKind;
    /// use cutlab::plant::Preset;
    /// let saved = RunConfiguration::new(vec![RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Pi)], None);
    /// assert_eq!(RunConfiguration::from_json(&saved.to_json()), Ok(saved));
    /// let e = RunConfiguration::from_json(r#"{"format": "cutlab-runs", "version": 1, "runs": [
    ///     {"preset": "kim-step-dock", "controller": {"kind": "pi"}, "seed": 1}]}"#).unwrap_err();
    /// assert!(e.to_string().contains("unknown preset \"kim-step-dock\""), "{e}");
    /// assert!(e.to_string().contains("line 2"), "{e}");
    /// ```
    pub fn from_json(text: &str) -> Result<Self, ConfigError> {
        check_format(text, FORMAT, VERSION, "configuration").map_err(|e| ConfigError(e.0))?;
        let config: Self = serde_json::from_str(text)
            .map_err(|e| ConfigError(crate::input::one_short_line(&e.to_string())))?;
        if config.runs.is_empty() {
            return Err(ConfigError("\"runs\" is empty: nothing to run".into()));
        }
        // Every setting in range before anything runs, each error naming its run and field.
        for (i, run) in config.runs.iter().enumerate() {
            check_spec(run).map_err(|e| ConfigError(format!("run {}: {e}", i + 1)))?;
        }
        Ok(config)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::registry::{ControllerConfig, ControllerKind};
    use crate::plant::materials::Material;
    use crate::plant::Preset;

    fn edited_spec() -> RunSpec {
        let mut controller = ControllerConfig::new(ControllerKind::Pi);
        controller.set_text("kp=0.25").unwrap();
        let mut spec = RunSpec::new(Preset::KimMaterialTaper, ControllerKind::Pi);
        spec.controller = controller;
        spec.seed = u64::MAX;
        spec.settings.target_force_n = Some(612.5);
        spec.settings.lowpass_order = Some(6);
        spec.plant.material = Some(Material::Gc30);
        spec.plant.teeth = Some(4);
        spec
    }

    #[test]
    fn every_field_survives_the_round_trip() {
        let saved = RunConfiguration::new(
            vec![
                edited_spec(),
                RunSpec::new(Preset::WangBrakeBench, ControllerKind::Fixed),
            ],
            Some("http://127.0.0.1:8080/#/compare?preset=kim-material-taper".into()),
        );
        let text = saved.to_json();
        assert_eq!(RunConfiguration::from_json(&text), Ok(saved));
        // Names a person reads, not Rust's variant names.
        assert!(
            text.contains("\"preset\": \"kim-material-taper\""),
            "{text}"
        );
        assert!(text.contains("\"material\": \"gc30\""), "{text}");
        // Settings left at the preset's default are left out.
        assert!(!text.contains("control_period_s"), "{text}");
    }

    /// A value to put in place of one in a saved configuration: out of range, of the wrong kind,
    /// or hostile.
    fn hostile(rng: &mut crate::rng::Rng) -> serde_json::Value {
        use serde_json::json;
        match rng.next_u64() % 14 {
            0 => json!(1e300),
            1 => json!(-1e-300),
            2 => json!(-1),
            3 => serde_json::Value::Null,
            4 => json!("x".repeat(1 + (rng.next_u64() % 100_000) as usize)),
            5 => json!([1, 2]),
            6 => json!({"nested": {"deeper": 1}}),
            7 => json!(true),
            8 => json!(u64::MAX),
            9 => json!(0),
            10 => json!(0.5),
            11 => json!("kim-step-doc"),
            12 => json!(250.0),
            _ => json!((rng.next_u64() % 100_000) as f64 / 7.0),
        }
    }

    /// Every place in a JSON value (a path of keys and indices), for mutating one.
    fn places(value: &serde_json::Value, at: Vec<String>, out: &mut Vec<Vec<String>>) {
        match value {
            serde_json::Value::Object(m) => {
                for (k, v) in m {
                    let mut next = at.clone();
                    next.push(k.clone());
                    out.push(next.clone());
                    places(v, next, out);
                }
            }
            serde_json::Value::Array(a) => {
                for (i, v) in a.iter().enumerate() {
                    let mut next = at.clone();
                    next.push(i.to_string());
                    out.push(next.clone());
                    places(v, next, out);
                }
            }
            _ => {}
        }
    }

    #[test]
    fn random_and_hostile_configurations_load_whole_or_are_refused_in_one_short_line() {
        use crate::rng::Rng;
        let mut rng = Rng::seed_from(2727);
        let saved = RunConfiguration::new(
            vec![
                edited_spec(),
                RunSpec::new(Preset::ManeeratDoc1, ControllerKind::FuzzyDynamics),
                RunSpec::new(Preset::WangBrakeBench, ControllerKind::Fixed),
            ],
            Some("http://127.0.0.1:8080/#/compare".into()),
        );
        let original: serde_json::Value = serde_json::from_str(&saved.to_json()).unwrap();
        let (mut loaded, mut refused) = (0, 0);
        for round in 0..1500 {
            let mut value = original.clone();
            for _ in 0..1 + rng.next_u64() % 3 {
                let mut all = Vec::new();
                places(&value, Vec::new(), &mut all);
                let path = &all[(rng.next_u64() % all.len() as u64) as usize];
                let (last, parents) = path.split_last().unwrap();
                let mut at = &mut value;
                for key in parents {
                    at = match key.parse::<usize>() {
                        Ok(i) if at.is_array() => &mut at[i],
                        _ => &mut at[key.as_str()],
                    };
                }
                match (rng.next_u64() % 4, at) {
                    (0, serde_json::Value::Object(m)) => {
                        m.remove(last);
                    }
                    (1, serde_json::Value::Object(m)) => {
                        m.insert(format!("{last}_typo"), hostile(&mut rng));
                    }
                    (_, serde_json::Value::Object(m)) => {
                        m.insert(last.clone(), hostile(&mut rng));
                    }
                    (_, serde_json::Value::Array(a)) => {
                        if let Ok(i) = last.parse::<usize>() {
                            a[i] = hostile(&mut rng);
                        }
                    }
                    _ => {}
                }
            }
            let mut text = serde_json::to_string_pretty(&value).unwrap();
            if rng.next_u64().is_multiple_of(20) {
                text.truncate((rng.next_u64() % text.len() as u64) as usize);
            }
            match RunConfiguration::from_json(&text) {
                Ok(config) => {
                    loaded += 1;
                    // Every run of the file is there, each in range, and it saves as it reads.
                    let runs = value["runs"].as_array().map_or(0, Vec::len);
                    assert_eq!(config.runs.len(), runs, "round {round}");
                    for run in &config.runs {
                        check_spec(run).unwrap();
                    }
                    assert_eq!(RunConfiguration::from_json(&config.to_json()), Ok(config));
                }
                Err(e) => {
                    refused += 1;
                    let e = e.to_string();
                    assert!(!e.contains('\n') && e.len() < 400, "round {round}: {e}");
                }
            }
        }
        // Both outcomes are exercised often (most damage lands in a controller's parameters and
        // is refused).
        assert!(
            loaded > 60 && refused > 300,
            "{loaded} loaded, {refused} refused"
        );
    }

    #[test]
    fn mistakes_are_errors_that_say_what_and_where() {
        let cases = [
            ("[]", "not a cutlab configuration"),
            (
                r#"{"format": "fll", "version": 1, "runs": []}"#,
                "\"format\" must be",
            ),
            (
                r#"{"format": "cutlab-runs", "version": 9, "runs": []}"#,
                "newer cutlab",
            ),
            (
                r#"{"format": "cutlab-runs", "runs": []}"#,
                "\"version\" must be 1",
            ),
            (
                r#"{"format": "cutlab-runs", "version": 1, "runs": []}"#,
                "nothing to run",
            ),
            (
                r#"{"format": "cutlab-runs", "version": 1, "runs": [{"preset": "kim-step-doc",
                 "controller": {"kind": "pi"}, "seed": 1, "settings": {"target_force": 5}}]}"#,
                "unknown field `target_force`",
            ),
            (
                r#"{"format": "cutlab-runs", "version": 1, "runs": [{"preset": "kim-step-doc",
                 "controller": {"kind": "pi", "params": {"kp": -4}}, "seed": 1}]}"#,
                "kp",
            ),
            (
                r#"{"format": "cutlab-runs", "version": 1, "runs": [{"preset": "kim-step-doc",
                 "controller": {"kind": "pi"}, "seed": -1}]}"#,
                "line 2",
            ),
            (
                r#"{"format": "cutlab-runs", "version": 1, "runs": [{"preset": "kim-step-doc",
                 "controller": {"kind": "pi", "parms": {"kp": 5}}, "seed": 1}]}"#,
                "unknown field `parms`",
            ),
            (
                r#"{"format": "cutlab-runs", "version": 1, "runs": [{"preset": "kim-step-doc",
                 "controller": {"kind": "pi"}, "seed": 1}, {"preset": "kim-step-doc",
                 "controller": {"kind": "pi"}, "seed": 1, "settings": {"max_override_pct": 1e300}}]}"#,
                "run 2: highest override 1e300 % is more than this machine applies",
            ),
            (
                r#"{"format": "cutlab-runs", "version": 1, "runs": [{"preset": "kim-step-doc",
                 "controller": {"kind": "pi"}, "seed": 1, "settings": {"control_period_s": 1e-300}}]}"#,
                "run 1: control_period_s: 1e-300 s is outside",
            ),
        ];
        for (text, expected) in cases {
            let e = RunConfiguration::from_json(text).unwrap_err().to_string();
            assert!(e.contains(expected), "{text}\n→ {e}");
        }
    }
}
