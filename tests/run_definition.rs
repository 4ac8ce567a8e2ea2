//! The command line and the browser accept exactly the same settings with the same ranges and
//! messages: both parse what a person typed through the run definition
//! (`closed_loop::definition`). The browser's form gathers its fields' text and calls
//! [`parse_texts`]; the command line maps its options onto the same table. For every setting, at
//! both ends of its range, just beyond them and with junk, the two must give the same run or the
//! same problem.
#![cfg(feature = "cli")]
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;

use cutlab::cli::sim::spec_from_args;
use cutlab::closed_loop::definition::{parse_texts, RunSetting, SettingKind};
use cutlab::control::registry::{ControllerConfig, ControllerKind};
use cutlab::plant::Preset;

/// Texts a person might type for `setting` on `preset`: the range's ends, just beyond them, and
/// junk.
fn probes(setting: RunSetting, preset: Preset) -> Vec<String> {
    let mut texts = vec!["junk".to_string(), "1,500".to_string(), "-1".to_string()];
    match setting.spec().kind {
        SettingKind::Feedback => texts.extend(["spindle", "feed", "torque"].map(String::from)),
        SettingKind::Material => texts.extend(["sm45c", "aluminium", "cheese"].map(String::from)),
        SettingKind::Seed => texts.extend(["0", "18446744073709551615", "2.5"].map(String::from)),
        SettingKind::Count { .. } | SettingKind::Number { .. } => {
            let (min, max) = setting.range(preset).unwrap();
            let step = if matches!(setting.spec().kind, SettingKind::Count { .. }) {
                1.0
            } else {
                (max - min) * 0.001
            };
            for v in [min, max, min - step, max + step, 1e308] {
                texts.push(v.to_string());
            }
        }
    }
    texts
}

#[test]
fn the_command_line_and_the_form_accept_the_same_settings_and_ranges() {
    let mut compared = 0;
    for preset in [Preset::KimStepDoc, Preset::WangBrakeBench] {
        for setting in RunSetting::ALL {
            for text in probes(setting, preset) {
                let option = format!("--{}", setting.spec().cli_option);
                let args: Vec<String> = ["--scenario", preset.name(), option.as_str(), &text]
                    .map(String::from)
                    .to_vec();
                let cli = spec_from_args(&args);
                let form = parse_texts(
                    preset,
                    ControllerConfig::new(ControllerKind::Fixed),
                    &[(setting, text.as_str())],
                );
                match (&cli, &form) {
                    (Ok(a), Ok(b)) => assert_eq!(a, b, "{setting:?} {text:?}"),
                    (Err(a), Err(b)) => {
                        // The same problem, the command line naming its option.
                        let problem = b[0].problem.to_string();
                        assert!(
                            a.0.contains(&problem),
                            "{setting:?} {text:?}: {a} / {problem}"
                        );
                        assert!(a.0.contains(&option), "{a}");
                    }
                    _ => panic!("{setting:?} {text:?}: CLI {cli:?}, form {form:?}"),
                }
                compared += 1;
            }
        }
    }
    // Every setting of the table was tried, on a mill and on the bench.
    assert!(compared > 2 * RunSetting::ALL.len() * 5, "{compared}");
}

#[test]
fn every_setting_has_its_option_in_the_help() {
    let (result, out) = common::cutlab_text(&["sim", "--help"], "");
    result.unwrap();
    for setting in RunSetting::ALL {
        let option = format!("--{}", setting.spec().cli_option);
        assert!(out.contains(&option), "sim --help lacks {option}");
    }
}

#[test]
fn the_override_before_arming_is_refused_outside_the_band_and_the_default_follows_it() {
    use cutlab::closed_loop::config::RunConfiguration;
    use cutlab::closed_loop::lab::preset_plan;
    let texts = |preset: Preset, pairs: &[(RunSetting, &str)]| {
        parse_texts(preset, ControllerConfig::new(ControllerKind::Pi), pairs)
    };
    // Above what the brake bench's 150 % dial applies: was silently run at 150 %.
    let e = texts(
        Preset::WangBrakeBench,
        &[(RunSetting::ArmingOverride, "200")],
    )
    .unwrap_err();
    assert_eq!(
        e[0].problem.to_string(),
        "override before arming 200 % is more than this machine applies (150 %)"
    );
    // Above the run's own highest override: was silently run at 120 %.
    let e = texts(
        Preset::ManeeratDoc1,
        &[
            (RunSetting::ArmingOverride, "130"),
            (RunSetting::MaxOverride, "120"),
        ],
    )
    .unwrap_err();
    assert_eq!(e[0].setting, RunSetting::ArmingOverride);
    assert!(
        e[0].problem
            .to_string()
            .contains("outside this run's override band 10–120 %"),
        "{}",
        e[0].problem
    );
    // The same from the command line, naming the option.
    let args: Vec<String> = [
        "--scenario",
        "maneerat-doc-1",
        "--arming-override",
        "130",
        "--max-override",
        "120",
    ]
    .map(String::from)
    .to_vec();
    let e = spec_from_args(&args).unwrap_err().to_string();
    assert!(e.starts_with("--arming-override: 130 % is outside"), "{e}");
    // And from a saved configuration.
    let mut spec = texts(Preset::ManeeratDoc1, &[(RunSetting::MaxOverride, "120")]).unwrap();
    spec.settings.arming_override_pct = Some(130.0);
    let text = RunConfiguration::new(vec![spec.clone()], None).to_json();
    // Refused as the file is read, before anything runs, naming the run.
    let e = RunConfiguration::from_json(&text).unwrap_err().to_string();
    assert!(
        e.contains("run 1: arming_override_pct: 130 % is outside"),
        "{e}"
    );
    // And when a run is planned from the spec itself.
    let e = preset_plan(&spec).unwrap_err().to_string();
    assert!(e.contains("arming_override_pct: 130 % is outside"), "{e}");
    // Left at its default, the override before arming follows a band below 100 %.
    spec.settings.arming_override_pct = None;
    spec.settings.max_override_pct = Some(80.0);
    let plan = preset_plan(&spec).unwrap();
    assert_eq!(plan.limits.arming_override_pct, 80.0);
}

/// docs/run-definition.md's table names every setting by its JSON field, URL key and option.
#[test]
fn the_documented_table_lists_every_setting_by_its_names() {
    let docs = include_str!("../docs/run-definition.md");
    for setting in RunSetting::ALL {
        let spec = setting.spec();
        let row = format!(
            "| `{}` | `{}` | `--{}` |",
            spec.json_field, spec.query_key, spec.cli_option
        );
        assert!(docs.contains(&row), "docs/run-definition.md lacks {row}");
    }
}
