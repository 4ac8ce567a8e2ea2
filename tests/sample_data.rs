//! The sample files under www/data (served with the lab, named in its README) still load and
//! still mean what the README says; scripts/sample-data regenerates them.
#![cfg(feature = "cli")]
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;
#[path = "common/log_fit.rs"]
mod log_fit;

use cutlab::closed_loop::config::RunConfiguration;
use cutlab::control::fuzzy::fll;
use cutlab::control::fuzzy::rules::{paper_002_engine, RuleBase};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/www/data/");

fn read(name: &str) -> String {
    std::fs::read_to_string(format!("{DATA}{name}")).unwrap()
}

#[test]
fn the_fll_files_are_paper_002s_engines_as_exported_today() {
    for (file, base) in [
        ("paper-002-experience.fll", RuleBase::Experience),
        ("paper-002-dynamics.fll", RuleBase::Dynamics),
    ] {
        let saved = fll::parse(&read(file)).unwrap();
        let engine = paper_002_engine(&base.table(), saved.outputs()[0].defuzzifier).unwrap();
        assert_eq!(fll::write(&saved), fll::write(&engine), "{file} is stale");
    }
}

#[test]
fn the_saved_comparison_and_the_teach_cut_log_load() {
    let config = RunConfiguration::from_json(&read("paper-002-fuzzy-comparison.json")).unwrap();
    let kinds: Vec<&str> = config
        .runs
        .iter()
        .map(|r| r.controller.kind().name())
        .collect();
    assert_eq!(kinds, ["fuzzy-experience", "fuzzy-dynamics"]);

    let path = format!("{DATA}kim-step-doc-teach-cut.csv");
    let (result, out) = common::cutlab_text(&["calibrate", &path, "--json"], "");
    result.unwrap();
    let fitted: serde_json::Value = serde_json::from_str(&out).unwrap();
    let r2 = fitted["spindle"]["rows"][0]["quality"]["r_squared"]
        .as_f64()
        .unwrap();
    assert!(r2 > 0.95, "R² {r2}");
}

/// The saved calibration is kim-step-doc's teach cut as made today, and a teach-in proposes
/// from it what the teach cut itself proposes.
#[test]
fn the_saved_calibration_is_kim_step_docs_teach_cut() {
    use cutlab::closed_loop::calibration_file::CalibrationFile;
    use cutlab::closed_loop::definition::RunSpec;
    use cutlab::closed_loop::lab::teach_cut_only;
    use cutlab::control::registry::ControllerKind;
    use cutlab::plant::Preset;
    let saved = CalibrationFile::from_json(&read("kim-step-doc-calibration.json")).unwrap();
    let spec = RunSpec::new(Preset::KimStepDoc, ControllerKind::Fixed);
    let (_, fresh) = teach_cut_only(&spec).unwrap();
    // Debug text compares every bit, and NaN (written null) equal to NaN.
    assert_eq!(
        format!("{:?}", saved.calibration),
        format!("{fresh:?}"),
        "kim-step-doc-calibration.json is stale"
    );
    let path = format!("{DATA}kim-step-doc-calibration.json");
    let (result, out) = common::cutlab_text(
        &[
            "tune",
            "--teach-in",
            "--calibration",
            &path,
            "--scenarios",
            "kim-step-doc",
        ],
        "",
    );
    result.unwrap();
    assert!(out.contains("proposed target 357 N"), "{out}");
}

/// Calibration without a dynamometer: the forces modelled from the log's feed, speed, depth and
/// width give the line the measured forces give (the simulated mill's mean force is the
/// mechanistic model's, so here the two must agree closely).
#[test]
fn modelled_forces_calibrate_like_measured_ones() {
    let path = format!("{DATA}kim-step-doc-teach-cut.csv");
    let sensitivity = |extra: &[&str]| {
        let mut args = vec!["calibrate", path.as_str(), "--json"];
        args.extend(extra);
        let (result, out) = common::cutlab_text(&args, "");
        result.unwrap();
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        (
            v["spindle"]["rows"][0]["sensitivity_a_per_n"]
                .as_f64()
                .unwrap(),
            v,
        )
    };
    let (measured, _) = sensitivity(&[]);
    let (modelled, report) = sensitivity(&[
        "--material",
        "sm45c",
        "--diameter-mm",
        "20",
        "--teeth",
        "2",
        "--mode",
        "slot",
    ]);
    assert!(
        (modelled / measured - 1.0).abs() < 0.01,
        "{modelled} vs {measured}"
    );
    assert!(report["force_source"]
        .as_str()
        .unwrap()
        .starts_with("the mechanistic model (material sm45c"));
    assert!(
        report["model_vs_measured_pct"].as_f64().unwrap() < 2.0,
        "{report}"
    );

    for (args, expected) in [
        (
            vec!["calibrate", path.as_str(), "--teeth", "2"],
            "--teeth only applies with --material",
        ),
        (
            vec![
                "calibrate",
                path.as_str(),
                "--material",
                "sm45c",
                "--teeth",
                "2",
            ],
            "missing required option --diameter-mm",
        ),
    ] {
        let message = common::cutlab_text(&args, "").0.unwrap_err();
        assert!(message.contains(expected), "{message}");
    }
}

/// `calibrate --material` and `force --material` take the same names: the composite part is two
/// materials, and both refuse it with the same words (calibrate once accepted it).
#[test]
fn calibrate_and_force_refuse_the_same_materials() {
    let path = format!("{DATA}kim-step-doc-teach-cut.csv");
    let calibrate = |material: &str| {
        common::cutlab_text(
            &[
                "calibrate",
                &path,
                "--material",
                material,
                "--diameter-mm",
                "20",
                "--teeth",
                "2",
                "--mode",
                "slot",
            ],
            "",
        )
        .0
    };
    let force = |material: &str| {
        common::cutlab_text(
            &[
                "force",
                "--material",
                material,
                "--diameter-mm",
                "20",
                "--teeth",
                "2",
                "--helix-deg",
                "30",
                "--axial-depth-mm",
                "3",
                "--radial-width-mm",
                "20",
                "--mode",
                "slot",
                "--feed-per-tooth-mm",
                "0.1",
                "--rpm",
                "1000",
            ],
            "",
        )
        .0
    };
    for material in ["composite", "cheese"] {
        let (a, b) = (
            calibrate(material).unwrap_err(),
            force(material).unwrap_err(),
        );
        assert_eq!(a, b);
        assert!(a.starts_with("--material: "), "{a}");
    }
    assert!(calibrate("sm45c").is_ok());
    assert!(force("sm45c").is_ok());
}

/// The sample teach cut rewritten as another machine's export would be — semicolons, decimal
/// commas, a byte-order mark, CRLF, its own column names with units, a phase label — calibrates
/// to the same line once `--map` names the columns.
#[test]
fn a_messy_export_of_the_teach_cut_calibrates_like_the_clean_one() {
    let clean = read("kim-step-doc-teach-cut.csv");
    let mut lines = clean.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let keep = [
        "time_s",
        "force_n",
        "spindle_current_rms_a",
        "spindle_speed_rpm",
    ];
    let names = ["Zeit [s]", "Kraft [N]", "S_Strom [A]", "S_Drehzahl (rpm)"];
    let index: Vec<usize> = keep
        .iter()
        .map(|k| header.iter().position(|h| h == k).unwrap())
        .collect();
    let mut messy = String::from("\u{feff}");
    messy.push_str(&names.join(";"));
    messy.push_str(";Phase\r\n");
    for (row, line) in lines.enumerate() {
        let cells: Vec<&str> = line.split(',').collect();
        let picked: Vec<String> = index.iter().map(|&i| cells[i].replace('.', ",")).collect();
        messy.push_str(&picked.join(";"));
        messy.push_str(if row < 20 {
            ";\"Anfahren\"\r\n"
        } else {
            ";Schnitt\r\n"
        });
    }
    let path = std::env::temp_dir().join("cutlab-messy-teach-cut.csv");
    std::fs::write(&path, messy).unwrap();
    let path = path.to_str().unwrap();
    let fit = |args: &[&str]| -> serde_json::Value {
        let (result, out) = common::cutlab_text(args, "");
        serde_json::from_str(&out).unwrap_or_else(|_| panic!("{result:?}"))
    };
    let reference = fit(&[
        "calibrate",
        &format!("{DATA}kim-step-doc-teach-cut.csv"),
        "--json",
    ]);
    let mapped = fit(&[
        "calibrate",
        path,
        "--json",
        "--map",
        "time_s=Zeit [s]",
        "--map",
        "force_n=Kraft [N]",
        "--map",
        "spindle_current_rms_a=S_Strom [A]",
        "--map",
        "spindle_speed_rpm=S_Drehzahl (rpm)",
    ]);
    let sensitivity = |v: &serde_json::Value| {
        v["spindle"]["rows"][0]["sensitivity_a_per_n"]
            .as_f64()
            .unwrap()
    };
    assert!((sensitivity(&mapped) / sensitivity(&reference) - 1.0).abs() < 1e-9);
    // The one thing the reader notes in either file: the short last period.
    let problems = |v: &serde_json::Value| v["log_problems"].as_array().unwrap().len();
    assert_eq!(problems(&mapped), problems(&reference));
    // A role or column that is not there says which ones are.
    let (result, _) = common::cutlab_text(&["calibrate", path, "--map", "kraft=Kraft [N]"], "");
    assert!(result.unwrap_err().contains("roles: time_s, force_n"));
    let (result, _) = common::cutlab_text(&["calibrate", path, "--map", "force_n=Force"], "");
    assert!(result.unwrap_err().contains("columns: Zeit [s], Kraft [N]"));
}

/// The synthetic machine export in www/data (made by scripts/sample-logs): the reader finds its
/// dialect, time and roles, and the per-phase analysis shows the controller holding the force
/// across the depth steps the fixed feed would follow.
#[test]
fn the_synthetic_machine_export_reads_and_analyses_by_phase() {
    use cutlab::log::analysis::{analyse, AnalysisRequest};
    use cutlab::log::Role;
    let bytes = std::fs::read(format!("{DATA}synthetic-kim-step-doc-export.csv")).unwrap();
    let log = cutlab::log::load(&bytes, None).unwrap();
    assert_eq!(log.dialect.delimiter, b';');
    assert!(log.dialect.decimal_comma);
    assert_eq!(log.sample_period_s, Some(0.06));
    let role = |name: &str| log.columns.iter().find(|c| c.name == name).unwrap().role;
    assert_eq!(role("Zeit [s]"), Some(Role::Time));
    assert_eq!(role("S_Strom [A]"), Some(Role::RmsCurrent));
    assert_eq!(role("S_Drehzahl (rpm)"), Some(Role::SpindleSpeed));
    assert_eq!(role("X_Vorschub [mm/min]"), Some(Role::Feed));
    assert_eq!(role("Kraft [N]"), Some(Role::Force));
    assert_eq!(role("Phase"), Some(Role::Label));
    let a = analyse(
        &log,
        "Kraft [N]",
        &AnalysisRequest {
            by: Some("Phase".into()),
            ..AnalysisRequest::default()
        },
    )
    .unwrap();
    let mean = |label: &str| {
        a.by_label
            .iter()
            .find(|l| l.label == label)
            .and_then(|l| l.stats.mean)
            .unwrap()
    };
    assert_eq!(mean("Luftschnitt"), 0.0);
    // 3, 4 and 5 mm deep, the force stays within 10 % of one level (the target, 372 N).
    for depth in ["Schnitt 3 mm", "Schnitt 4 mm", "Schnitt 5 mm"] {
        assert!(
            (mean(depth) / 372.0 - 1.0).abs() < 0.1,
            "{depth}: {}",
            mean(depth)
        );
    }
}

/// The synthetic 1 kHz DAQ capture in www/data (made by scripts/sample-logs from
/// examples/sample_daq_log.rs): time in ms, three spindle phase currents, a dynamometer; its
/// columns map themselves, and its force calibrates the spindle current it was recorded with.
#[test]
fn the_synthetic_daq_capture_maps_itself_and_calibrates() {
    use cutlab::log::mapping::Channel;
    let bytes = std::fs::read(format!("{DATA}synthetic-maneerat-doc-2-daq.csv")).unwrap();
    let (log, mapping, fit) = log_fit::measured_fit(&bytes);
    assert_eq!(log.rows, 12_000);
    assert_eq!(log.sample_period_s, Some(0.001));
    assert!(log.problems.is_empty(), "{:?}", log.problems);
    assert_eq!(mapping.count(Channel::SpindlePhase), 3);
    for (channel, column) in [
        (Channel::Time, "Time [ms]"),
        (Channel::SpindleSpeed, "S_speed [rpm]"),
        (Channel::Feed, "X_feed [mm/min]"),
        (Channel::Override, "Override [%]"),
        (Channel::Force, "F [N]"),
        (Channel::Label, "Phase"),
    ] {
        assert_eq!(mapping.columns_of(channel), [column], "{channel:?}");
    }
    let cutlab::estimation::estimator::Estimator::Spindle { model, .. } =
        &fit.calibration.estimator
    else {
        panic!("a spindle model");
    };
    assert!(model.rows[0].quality.r_squared > 0.95, "{}", fit.quality());
}

/// The browser's first run on the default scenario starts from the shipped calibration: the run
/// it gives is the run its own teach cut gives, trace and metrics to the bit.
#[test]
fn a_run_from_the_shipped_calibration_is_the_run_with_its_own_teach_cut() {
    use cutlab::closed_loop::definition::RunSpec;
    use cutlab::closed_loop::lab::{simulate, LabRun, TeachKey};
    use cutlab::closed_loop::precomputed::shipped_calibrations;
    use cutlab::control::registry::ControllerKind;
    use cutlab::plant::Preset;
    use cutlab::work::Work;
    let spec = RunSpec::new(Preset::KimStepDoc, ControllerKind::Threshold);
    let key = TeachKey::of(&spec).unwrap();
    let (_, shipped) = shipped_calibrations()
        .into_iter()
        .find(|(k, _)| *k == key)
        .expect("the default scenario's teach cut is shipped");
    let from_shipped = LabRun::calibrated(&spec, shipped)
        .and_then(Work::run_to_end)
        .unwrap();
    let taught = simulate(&spec).unwrap();
    assert_eq!(
        format!("{:?}", from_shipped.trace),
        format!("{:?}", taught.trace)
    );
    assert_eq!(
        format!("{:?}", from_shipped.metrics),
        format!("{:?}", taught.metrics)
    );
}

/// The shipped references are what the reference search finds for the default scenario, and the
/// Simulate page's default run (threshold) has that scenario, however its settings are spelled.
#[test]
fn the_shipped_references_are_kim_step_docs_reference_search() {
    use cutlab::closed_loop::definition::RunSpec;
    use cutlab::closed_loop::precomputed::shipped_references;
    use cutlab::closed_loop::references::{fixed_feed_spec, references, ScenarioKey};
    use cutlab::control::registry::ControllerKind;
    use cutlab::plant::Preset;
    let default_run = RunSpec::new(Preset::KimStepDoc, ControllerKind::Threshold);
    let scenario = fixed_feed_spec(&default_run, 100.0).unwrap();
    let key = ScenarioKey::of(&default_run).unwrap();
    let (_, shipped) = shipped_references()
        .into_iter()
        .find(|(k, _)| *k == key)
        .expect("the default scenario's references are shipped");
    let fresh = references(&scenario).unwrap();
    // Debug text compares every bit (and NaN equal to NaN).
    assert_eq!(
        format!("{shipped:?}"),
        format!("{fresh:?}"),
        "kim-step-doc-references.json is stale: run scripts/sample-data"
    );
    // The browser's form spells every setting out; the key is the same.
    let mut spelled = default_run.clone();
    spelled.settings.control_period_s = Some(
        cutlab::closed_loop::lab::preset_plan(&default_run)
            .unwrap()
            .chain
            .control_period_s,
    );
    assert_eq!(ScenarioKey::of(&spelled).unwrap(), key);
}

/// The shipped table of kim-step-doc's trial cuts is its trial cuts as made today, and it
/// reads back as a table of cuts.
#[test]
fn the_shipped_trial_cuts_are_kim_step_docs() {
    use cutlab::closed_loop::trial_cuts::{learn_on_preset, DEFAULT_TRIAL_FEEDS_PCT};
    use cutlab::log::trial_cuts::{learning_table, read_table, TableTool};
    use cutlab::plant::Preset;
    let shipped = read("kim-step-doc-trial-cuts.csv");
    let learning = learn_on_preset(Preset::KimStepDoc, &DEFAULT_TRIAL_FEEDS_PCT).unwrap();
    assert_eq!(
        shipped,
        learning_table(&learning).unwrap(),
        "kim-step-doc-trial-cuts.csv is stale: run scripts/sample-data"
    );
    let log = cutlab::log::load(shipped.as_bytes(), None).unwrap();
    let table = read_table(&log, None, TableTool::default()).unwrap();
    assert_eq!(table.cuts.len(), learning.cuts.len());
    assert!(table.left_out.is_empty());
}
