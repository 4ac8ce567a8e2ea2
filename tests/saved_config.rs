//! A saved configuration is the run it describes: the runs the browser's Compare page exports
//! (`Configuration (JSON)`), run again by `cutlab compare --config`, give the metrics the same
//! comparison gives from the command line's flags, for every preset and every controller; and the
//! shipped paper-002 comparison is the preset's own runs.
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
// Runs the command line and writes files: native only.
#![cfg(all(feature = "cli", not(target_arch = "wasm32")))]

mod common;

use cutlab::closed_loop::config::RunConfiguration;
use cutlab::closed_loop::definition::{parse_texts, RunSetting};
use cutlab::closed_loop::paper_comparisons::PAPER_COMPARISONS;
use cutlab::closed_loop::paper_defaults::preset_controller;
use cutlab::control::registry::ControllerKind;
use cutlab::plant::Preset;

fn scratch(name: &str) -> String {
    let dir = std::env::temp_dir().join(format!("cutlab-saved-config-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name).to_string_lossy().into_owned()
}

/// `cutlab compare … --no-references --json`'s metrics, one JSON value per run.
fn compare(args: &[&str]) -> Vec<serde_json::Value> {
    let all = [args, &["--no-references", "--json"]].concat();
    let (result, out) = common::cutlab_text(&all, "");
    result.unwrap_or_else(|e| panic!("{all:?}: {e}"));
    let entries: Vec<serde_json::Value> = serde_json::from_str(&out).unwrap();
    entries.into_iter().map(|e| e["metrics"].clone()).collect()
}

#[test]
fn every_exported_comparison_runs_as_the_flags_run_it() {
    let kinds = ControllerKind::ALL;
    let names: Vec<&str> = kinds.iter().map(|k| k.name()).collect();
    for preset in Preset::ALL {
        // What the Compare page exports: one run per variant, each parsed from the form through the
        // run definition with the preset's controller defaults, written with every parameter.
        let no_edits: [(RunSetting, &str); 0] = [];
        let runs = kinds
            .iter()
            .map(|&kind| parse_texts(preset, preset_controller(preset, kind), &no_edits).unwrap())
            .collect();
        let path = scratch(&format!("{}.json", preset.name()));
        std::fs::write(&path, RunConfiguration::new(runs, None).to_json()).unwrap();
        let from_file = compare(&["compare", "--config", &path]);
        let from_flags = compare(&[
            "compare",
            "--scenario",
            preset.name(),
            "--controllers",
            &names.join(","),
        ]);
        assert_eq!(from_file.len(), kinds.len());
        // Serialised metrics compare every number (NaN written as null on both sides).
        assert_eq!(from_file, from_flags, "{}", preset.name());
    }
}

/// The paper-002 comparison shipped in www/data is the Compare page's "sampled every 0.1 s" one —
/// paper 002's k_u (the preset's fuzzy output range, 100 % per period) at a period where Fig. 7's
/// claim holds — and `cutlab compare --config` runs it as the flags do and finds it reproduced.
#[test]
fn the_shipped_paper_002_comparison_is_the_one_the_compare_page_offers() {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/www/data/paper-002-fuzzy-comparison.json"
    );
    let config = RunConfiguration::from_json(&std::fs::read_to_string(path).unwrap()).unwrap();
    let offered = PAPER_COMPARISONS
        .iter()
        .find(|c| c.label.starts_with("Paper 002") && c.label.ends_with("0.1 s"))
        .unwrap();
    assert_eq!(config.runs, offered.specs().unwrap());
    for run in &config.runs {
        assert_eq!(run.controller.get("output_range_pct"), Some(100.0));
    }
    let from_file = compare(&["compare", "--config", path]);
    let from_flags = compare(&[
        "compare",
        "--scenario",
        "liu-current-step",
        "--controllers",
        "fuzzy-experience,fuzzy-dynamics",
        "--period-s",
        "0.1",
    ]);
    assert_eq!(from_file, from_flags);
    let (result, printed) =
        common::cutlab_text(&["compare", "--config", path, "--no-references"], "");
    result.unwrap();
    assert!(printed.contains("Reproduced."), "{printed}");
}
