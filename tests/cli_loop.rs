//! `cutlab sim`, `cutlab compare` and `cutlab calibrate` end to end, in-process.
#![cfg(feature = "cli")]
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;

fn cutlab(args: &[&str]) -> (Result<(), String>, String) {
    common::cutlab_text(args, "")
}

/// A fresh scratch directory for one test.
fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("cutlab-cli-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn sim_writes_the_trace_csv_and_the_metrics_json_and_calibrate_reads_the_csv_back() {
    let dir = scratch("sim");
    let csv = dir.join("run.csv");
    let json = dir.join("run.json");
    let (result, out) = cutlab(&[
        "sim",
        "--scenario",
        "maneerat-doc-1",
        "--controller",
        "pi",
        "--set",
        "kp=0.4",
        "--seed",
        "3",
        "--no-references",
        "--csv",
        csv.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
    ]);
    result.unwrap();
    assert!(out.contains("Force IAE (N·s)"), "{out}");

    let text = std::fs::read_to_string(&csv).unwrap();
    let header = text.lines().next().unwrap();
    for column in [
        "time_s",
        "depth_mm",
        "feed_mm_min",
        "override_pct",
        "force_n",
        "force_est_n",
        "spindle_current_rms_a",
        "feed_current_rms_a",
    ] {
        assert!(header.split(',').any(|c| c == column), "missing {column}");
    }

    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["scenario"], "maneerat-doc-1");
    assert_eq!(report["controller"]["params"]["kp"], 0.4);
    assert_eq!(report["target_force_n"], 150.0);
    for key in [
        "cycle_time_s",
        "force_iae_n_s",
        "peak_force_n",
        "time_above_limit_s",
    ] {
        assert!(report["metrics"][key].is_number(), "metrics.{key}");
    }

    // A controlled run holds the load nearly constant, which calibrates poorly; a teach cut at
    // fixed feed through the depth steps spans the loads.
    let teach = dir.join("teach.csv");
    let (result, _) = cutlab(&[
        "sim",
        "--scenario",
        "kim-step-doc",
        "--controller",
        "fixed",
        "--no-references",
        "--csv",
        teach.to_str().unwrap(),
    ]);
    result.unwrap();
    let csv = teach;
    let (result, out) = cutlab(&["calibrate", csv.to_str().unwrap()]);
    result.unwrap();
    assert!(out.contains("spindle current → force"), "{out}");
    let (result, out) = cutlab(&["calibrate", csv.to_str().unwrap(), "--json"]);
    result.unwrap();
    let fitted: serde_json::Value = serde_json::from_str(&out).unwrap();
    let row = &fitted["spindle"]["rows"][0];
    assert!(row["quality"]["r_squared"].as_f64().unwrap() > 0.9, "{row}");

    // The log's sampling is reported, and a dropped row is found by its line (kim-step-doc's
    // control period is three revolutions at 1000 rpm, 60 ms).
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    let dropped_time: f64 = lines[41].split(',').next().unwrap().parse().unwrap();
    lines.remove(40); // file line 41
    let gappy = dir.join("gappy.csv");
    std::fs::write(&gappy, lines.join("\n")).unwrap();
    let (result, out) = cutlab(&["calibrate", gappy.to_str().unwrap()]);
    result.unwrap();
    assert!(
        out.contains(&format!(
            "time steps: uneven: the step to line 41 (time_s {dropped_time}) is 0.120000 s, the \
             median step 0.060000 s"
        )),
        "{out}"
    );
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn compare_marks_the_best_value_of_each_row() {
    let (result, out) = cutlab(&[
        "compare",
        "--scenario",
        "maneerat-doc-1",
        "--controllers",
        "fixed,pi:kp=0.5",
        "--no-references",
    ]);
    result.unwrap();
    assert!(out.contains("pi:kp=0.5"), "{out}");
    let iae = out.lines().find(|l| l.starts_with("Force IAE")).unwrap();
    assert_eq!(iae.matches('*').count(), 1, "{iae}");
}

#[test]
fn bad_input_gives_one_line_that_names_it() {
    let cases: [(&[&str], &str); 12] = [
        (
            &[
                "sim",
                "--scenario",
                "kim-step-doc",
                "--controller",
                "pi",
                "--material",
                "unobtainium",
            ],
            "--material: unknown material \"unobtainium\"",
        ),
        (
            &[
                "sim",
                "--scenario",
                "kim-step-doc",
                "--controller",
                "pi",
                "--rpm",
                "-5",
                "--no-references",
            ],
            "--rpm: must be positive, got -5",
        ),
        (
            &["sim", "--scenario", "nowhere", "--controller", "pi"],
            "--scenario: unknown preset",
        ),
        (
            &[
                "sim",
                "--scenario",
                "maneerat-doc-1",
                "--controller",
                "warp",
            ],
            "--controller: unknown controller",
        ),
        (
            &[
                "sim",
                "--scenario",
                "maneerat-doc-1",
                "--controller",
                "pi",
                "--set",
                "kp=-2",
            ],
            "--set: kp = -2",
        ),
        (
            &[
                "compare",
                "--scenario",
                "maneerat-doc-1",
                "--controllers",
                "pi:ki=3",
            ],
            "pi:ki=3: controller \"pi\" has no parameter \"ki\"",
        ),
        (
            &["calibrate", "/nonexistent/log.csv"],
            "/nonexistent/log.csv: cannot read",
        ),
        (
            &["calibrate", "log.csv", "--gear-change-rpm", "-5"],
            "--gear-change-rpm: must be a positive speed",
        ),
        (
            &[
                "sim",
                "--scenario",
                "kim-step-doc",
                "--controller",
                "pi",
                "extra",
            ],
            "unexpected argument \"extra\"",
        ),
        (
            &[
                "compare",
                "--scenario",
                "kim-step-doc",
                "--controllers",
                "pi,,mrac",
            ],
            "--controllers: entry 2 of \"pi,,mrac\" is empty",
        ),
        (
            &[
                "sim",
                "--scenario",
                "kim-step-doc",
                "--controller",
                "pi",
                "--max-override",
                "1e6",
            ],
            "highest override 1000000 % is more than this machine applies (255 %)",
        ),
        (
            &[
                "sim",
                "--scenario",
                "liu-current-step",
                "--controller",
                "pi",
                "--material",
                "aluminium",
            ],
            "plant: machine and cut edits apply to the mill presets",
        ),
    ];
    for (args, expected) in cases {
        let (result, _) = cutlab(args);
        let message = result.unwrap_err();
        assert!(message.starts_with(expected), "{args:?}: {message}");
        assert!(!message.contains('\n'));
    }
}

/// A saved configuration (what the browser's "Configuration (JSON)" export writes) runs the same
/// loops as the options that describe them.
#[test]
fn a_saved_configuration_reproduces_the_runs_it_describes() {
    use cutlab::closed_loop::config::RunConfiguration;
    use cutlab::closed_loop::definition::RunSpec;
    use cutlab::control::registry::{ControllerConfig, ControllerKind};
    use cutlab::plant::Preset;

    let dir = scratch("config");
    let mut tuned = ControllerConfig::new(ControllerKind::Pi);
    tuned.set_text("kp=0.5").unwrap();
    let mut fixed = RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Fixed);
    fixed.seed = 7;
    fixed.plant.spindle_rpm = Some(2800.0);
    let pi = RunSpec {
        controller: tuned,
        ..fixed.clone()
    };
    let write = |name: &str, runs: Vec<RunSpec>| {
        let path = dir.join(name);
        std::fs::write(&path, RunConfiguration::new(runs, None).to_json()).unwrap();
        path.to_string_lossy().into_owned()
    };
    let one = write("one.json", vec![pi.clone()]);
    let both = write("both.json", vec![fixed.clone(), pi.clone()]);
    let common = [
        "--scenario",
        "maneerat-doc-1",
        "--seed",
        "7",
        "--rpm",
        "2800",
        "--no-references",
    ];

    let (result, from_file) = cutlab(&["sim", "--config", &one, "--no-references"]);
    result.unwrap();
    let mut args = vec!["sim", "--controller", "pi", "--set", "kp=0.5"];
    args.extend(common);
    let (result, from_options) = cutlab(&args);
    result.unwrap();
    assert_eq!(from_file, from_options);

    let (result, from_file) = cutlab(&["compare", "--config", &both, "--no-references"]);
    result.unwrap();
    let mut args = vec!["compare", "--controllers", "fixed,pi:kp=0.5"];
    args.extend(common);
    let (result, from_options) = cutlab(&args);
    result.unwrap();
    // Same numbers; only the column headings (the controllers' names) differ.
    let rows = |out: &str| out.lines().skip(2).map(str::to_string).collect::<Vec<_>>();
    assert_eq!(rows(&from_file), rows(&from_options));
    assert!(
        from_file.starts_with("scenario maneerat-doc-1, seed 7"),
        "{from_file}"
    );

    let mut other_seed = pi.clone();
    other_seed.seed = 8;
    let mixed = write("mixed.json", vec![fixed, other_seed]);
    let not_json = dir.join("not.json");
    std::fs::write(&not_json, "preset=kim-step-doc").unwrap();
    let not_json = not_json.to_string_lossy().into_owned();
    let cases: [(&[&str], &str); 4] = [
        (
            &["sim", "--config", &one, "--scenario", "kim-step-doc"],
            "--scenario cannot be given with --config",
        ),
        (&["sim", "--config", &both], "--config holds 2 runs"),
        (&["compare", "--config", &mixed], "run 2 differs from run 1"),
        (
            &["sim", "--config", &not_json],
            "not a cutlab configuration",
        ),
    ];
    for (args, expected) in cases {
        let message = cutlab(args).0.unwrap_err();
        assert!(message.contains(expected), "{args:?}: {message}");
        assert!(!message.contains('\n'), "{message}");
    }
    std::fs::remove_dir_all(dir).ok();
}

/// A saved comparison's columns are named as the Compare page names them, by the law each runs
/// (`control::run_names`); runs of one law, which the page tells apart by the form beside each
/// column, are numbered.
#[test]
fn a_saved_comparison_names_its_columns_as_the_compare_page_does() {
    use cutlab::closed_loop::config::RunConfiguration;
    use cutlab::closed_loop::definition::RunSpec;
    use cutlab::control::fuzzy::rules::RuleBase;
    use cutlab::control::registry::ControllerKind;
    use cutlab::plant::Preset;

    let dir = scratch("config-names");
    let run = |kind| RunSpec::new(Preset::ManeeratDoc1, kind);
    let dynamics = run(ControllerKind::FuzzyDynamics);
    let mut experience_table = dynamics.clone();
    experience_table
        .controller
        .set_rule_table(RuleBase::Experience.table())
        .unwrap();
    let pi = run(ControllerKind::Pi);
    let mut tuned = pi.clone();
    tuned.controller.set_text("kp=0.5").unwrap();
    let path = dir.join("four.json");
    let runs = vec![dynamics, experience_table, pi, tuned];
    std::fs::write(&path, RunConfiguration::new(runs, None).to_json()).unwrap();
    let (result, out) = cutlab(&[
        "compare",
        "--config",
        &path.to_string_lossy(),
        "--no-references",
    ]);
    result.unwrap();
    let headings: Vec<&str> = out
        .lines()
        .nth(1)
        .unwrap()
        .split("  ")
        .map(str::trim)
        .filter(|h| !h.is_empty())
        .collect();
    assert_eq!(
        headings,
        [
            "fuzzy-dynamics",
            "fuzzy-dynamics (experience table)",
            "pi",
            "pi (2)"
        ],
        "{out}"
    );
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn a_saved_calibration_reproduces_the_teach_cut_run_and_is_refused_for_another_feedback() {
    let dir = scratch("calibration");
    let saved = dir.join("kim.json");
    let (json_a, json_b) = (dir.join("a.json"), dir.join("b.json"));
    let run = |extra: &[&str], json: &std::path::Path| {
        let mut args = vec![
            "sim",
            "--scenario",
            "kim-step-doc",
            "--controller",
            "threshold",
            "--no-references",
            "--json",
            json.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        cutlab(&args)
    };
    let (result, _) = run(&["--save-calibration", saved.to_str().unwrap()], &json_a);
    result.unwrap();
    let file = std::fs::read_to_string(&saved).unwrap();
    assert!(
        file.contains("\"format\": \"cutlab-calibration\""),
        "{file}"
    );
    assert!(file.contains("teach cut on kim-step-doc, seed 1"), "{file}");
    let (result, _) = run(&["--calibration", saved.to_str().unwrap()], &json_b);
    result.unwrap();
    // The teach cut depends only on the preset, seed and chain: starting from its saved result
    // gives the same run, metric for metric.
    let report = |path: &std::path::Path| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
    };
    let (a, b) = (report(&json_a), report(&json_b));
    assert_eq!(a["metrics"], b["metrics"]);
    assert_eq!(a["calibration"], b["calibration"]);

    let (result, _) = run(
        &[
            "--calibration",
            saved.to_str().unwrap(),
            "--feedback",
            "feed",
        ],
        &json_b,
    );
    let e = result.unwrap_err();
    assert!(
        e.contains("the calibration is for spindle feedback but the run measures with feed"),
        "{e}"
    );
    std::fs::write(&saved, file.replace("\"periods\"", "\"period\"")).unwrap();
    let (result, _) = run(&["--calibration", saved.to_str().unwrap()], &json_b);
    let e = result.unwrap_err();
    assert!(
        e.contains("--calibration") && e.contains("unknown field `period`"),
        "{e}"
    );
}

/// Issue 26: a program that runs for a time (paper 002's 40 s, the brake bench's schedule)
/// ends at the same moment at any feed, so it shows no saving ("—", null in the JSON), where a
/// path's program shows one.
#[test]
fn savings_are_none_where_the_cycle_time_does_not_follow_the_feed() {
    let dir = scratch("savings");
    let saving = |scenario: &str, controller: &str| {
        let json = dir.join(format!("{scenario}.json"));
        let (result, out) = cutlab(&[
            "sim",
            "--scenario",
            scenario,
            "--controller",
            controller,
            "--json",
            json.to_str().unwrap(),
        ]);
        result.unwrap();
        let line = out
            .lines()
            .find(|l| l.starts_with("Saving vs programmed feed"))
            .unwrap()
            .to_string();
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        (report["metrics"]["saving_vs_programmed_pct"].clone(), line)
    };
    for (scenario, controller) in [
        ("liu-current-step", "fuzzy-dynamics"),
        ("wang-brake-bench", "restriction"),
    ] {
        let (value, line) = saving(scenario, controller);
        assert!(value.is_null(), "{scenario}: {value}");
        assert!(line.trim_end().ends_with('—'), "{scenario}: {line}");
    }
    let (value, _) = saving("maneerat-doc-1", "pi");
    assert!(value.is_number(), "{value}");
}

/// Two columns of one name would be indistinguishable (and equal: one scenario, one seed).
#[test]
fn compare_refuses_an_entry_given_twice_and_names_it() {
    for (list, expected) in [
        (
            "pi,pi",
            "--controllers: \"pi\" is given twice in \"pi,pi\" (entries 1 and 2)",
        ),
        (
            "fixed, pi:kp=0.5 ,mrac,pi:kp=0.5",
            "--controllers: \"pi:kp=0.5\" is given twice in \"fixed, pi:kp=0.5 ,mrac,pi:kp=0.5\" \
             (entries 2 and 4)",
        ),
    ] {
        let (result, _) = cutlab(&[
            "compare",
            "--scenario",
            "maneerat-doc-1",
            "--controllers",
            list,
            "--no-references",
        ]);
        let message = result.unwrap_err();
        assert!(message.starts_with(expected), "{list}: {message}");
        assert!(!message.contains('\n'));
    }
}

/// `pi:kp=0.5:kp=0.9` or `--set kp=0.5 --set kp=0.9` would run one of the two values without a
/// word: every front end that reads assignments refuses the repeat, naming the parameter, as
/// `tune --param` does.
#[test]
fn a_parameter_given_twice_is_refused_naming_it_in_every_front_end() {
    let repeat = "kp is given twice (kp=0.5, then kp=0.9); give each parameter once";
    let cases: [(&[&str], String); 4] = [
        (
            &[
                "compare",
                "--scenario",
                "maneerat-doc-1",
                "--controllers",
                "fixed,pi:kp=0.5:kp=0.9",
            ],
            format!("pi:kp=0.5:kp=0.9: {repeat}"),
        ),
        (
            &[
                "sim",
                "--scenario",
                "maneerat-doc-1",
                "--controller",
                "pi",
                "--set",
                "kp=0.5",
                "--set",
                "kp=0.9",
            ],
            format!("--set: {repeat}"),
        ),
        (
            &[
                "tune",
                "--quiet",
                "--controller",
                "pi:kp=0.5:kp=0.9",
                "--scenarios",
                "maneerat-doc-1",
                "--param",
                "ki_per_s=0:1",
            ],
            format!("--controller: pi:kp=0.5:kp=0.9: {repeat}"),
        ),
        (
            // Spaces around the key still name one parameter.
            &[
                "compare",
                "--scenario",
                "maneerat-doc-1",
                "--controllers",
                "pi:kp=0.5: kp =0.9",
            ],
            "pi:kp=0.5: kp =0.9: kp is given twice (kp=0.5, then kp =0.9)".to_string(),
        ),
    ];
    for (args, expected) in cases {
        let (result, _) = cutlab(args);
        let message = result.unwrap_err();
        assert!(message.starts_with(&expected), "{args:?}: {message}");
    }
    // Different parameters together still set both.
    let spec = cutlab::cli::sim::spec_from_args(
        &[
            "--scenario",
            "maneerat-doc-1",
            "--controller",
            "pi",
            "--set",
            "kp=0.5",
            "--set",
            "ki_per_s=2",
        ]
        .map(String::from),
    )
    .unwrap();
    assert_eq!(spec.controller.get("kp"), Some(0.5));
    assert_eq!(spec.controller.get("ki_per_s"), Some(2.0));
}
