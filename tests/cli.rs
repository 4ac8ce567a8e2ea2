//! The command line as a whole: help, version, errors, and `cutlab controllers`.
#![cfg(feature = "cli")]
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;

fn cutlab(args: &[&str], stdin: &str) -> (Result<(), String>, String) {
    common::cutlab_text(args, stdin)
}

#[test]
fn help_lists_every_command() {
    let (result, out) = cutlab(&["--help"], "");
    assert!(result.is_ok());
    assert!(out.starts_with("cutlab"));
    for command in cutlab::cli::COMMANDS {
        assert!(out.contains(command.name), "help lacks {}", command.name);
        let (result, sub_help) = cutlab(&[command.name, "--help"], "");
        assert!(result.is_ok(), "{} --help failed", command.name);
        assert!(
            sub_help.contains("Usage: cutlab"),
            "{}: {sub_help}",
            command.name
        );
    }
}

#[test]
fn version_names_the_package_version() {
    let (result, out) = cutlab(&["--version"], "");
    assert!(result.is_ok());
    assert_eq!(out.trim(), format!("cutlab {}", env!("CARGO_PKG_VERSION")));
}

#[test]
fn errors_are_one_line_and_name_what_is_wrong() {
    let (result, _) = cutlab(&["frobnicate"], "");
    let message = result.unwrap_err();
    assert!(
        message.starts_with("unknown command \"frobnicate\""),
        "{message}"
    );
    assert!(!message.contains('\n'));
    let (result, _) = cutlab(&["controllers", "--jsn"], "");
    // clap suggests the option meant.
    assert_eq!(
        result.unwrap_err(),
        "unknown option --jsn (did you mean --json?) (see --help)"
    );
}

#[test]
fn controllers_json_lists_every_controller_with_parameter_units() {
    let (result, out) = cutlab(&["controllers", "--json"], "");
    assert!(result.is_ok());
    let listing: serde_json::Value = serde_json::from_str(&out).unwrap();
    let listing = listing.as_array().unwrap();
    assert_eq!(
        listing.len(),
        cutlab::control::registry::ControllerKind::ALL.len()
    );
    for controller in listing {
        for p in controller["params"].as_array().unwrap() {
            assert!(p["unit"].is_string() && p["default"].is_number(), "{p}");
        }
    }
    let (result, table) = cutlab(&["controllers"], "");
    assert!(result.is_ok());
    assert!(table.contains("ki_per_s"));
}

/// `cutlab metrics` is the browser's glossary: every row of the metrics table, in its order, with
/// its unit and its help (and the ★ rule where the row ranks runs).
#[test]
fn metrics_lists_every_rows_glossary_entry() {
    use cutlab::closed_loop::summary::METRIC_ROWS;
    let (result, out) = cutlab(&["metrics", "--json"], "");
    result.unwrap();
    let listing: serde_json::Value = serde_json::from_str(&out).unwrap();
    let listing = listing.as_array().unwrap();
    assert_eq!(listing.len(), METRIC_ROWS.len());
    for (entry, row) in listing.iter().zip(METRIC_ROWS.iter()) {
        assert_eq!(entry["label"], row.label);
        assert_eq!(entry["help"], row.help_with_rule());
        assert!(entry["help"].as_str().unwrap().len() > 20, "{entry}");
    }
    let (result, text) = cutlab(&["metrics"], "");
    result.unwrap();
    let first = &METRIC_ROWS[0];
    assert!(text.contains(first.help), "{text}");
    assert!(text.contains("A ★ only where"), "{text}");
}

/// The real process: a bad argument or a bad value ends in one stderr line and a failure exit,
/// never a panic (exit 101) or an abort.
#[cfg(unix)]
#[test]
fn the_binary_turns_hostile_arguments_into_one_line_errors() {
    use std::ffi::OsStr;
    use std::os::unix::ffi::OsStrExt;
    use std::process::Command;

    let run = |args: &[&OsStr]| {
        let out = Command::new(env!("CARGO_BIN_EXE_cutlab"))
            .args(args)
            .output()
            .unwrap();
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let not_utf8 = OsStr::from_bytes(b"\xff");
    let cases: [&[&OsStr]; 3] = [
        &[
            "filter".as_ref(),
            "design".as_ref(),
            "--order".as_ref(),
            "2".as_ref(),
            "--cutoff".as_ref(),
            not_utf8,
            "--fs".as_ref(),
            "1000".as_ref(),
        ],
        &[
            "filter".as_ref(),
            "apply".as_ref(),
            "--order".as_ref(),
            "2".as_ref(),
            "--cutoff".as_ref(),
            "10".as_ref(),
            "--fs".as_ref(),
            "1000".as_ref(),
            "--channels".as_ref(),
            "4611686018427387904".as_ref(),
        ],
        &["--version".as_ref(), "extra".as_ref()],
    ];
    for args in cases {
        let (code, stderr) = run(args);
        assert_eq!(code, Some(1), "{args:?}: {stderr}");
        assert!(stderr.starts_with("cutlab: error: "), "{stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
    }
}

/// clap's errors, in the command line's words: one line, a suggestion for a misspelling, the
/// names that exist for an unknown command, both values of an option given twice.
#[test]
fn parser_errors_are_one_line_with_suggestions_and_the_names_that_exist() {
    let error = |args: &[&str]| {
        let (result, _) = cutlab(args, "");
        let message = result.unwrap_err();
        assert!(!message.contains('\n'), "{args:?}: {message}");
        message
    };
    assert_eq!(
        error(&["filter", "design", "--ordr", "4"]),
        "unknown option --ordr (did you mean --order?) (see --help)"
    );
    // Every command the parser has, in its order (tested against the parser in cli/mod.rs).
    let names: Vec<&str> = cutlab::cli::COMMANDS.iter().map(|c| c.name).collect();
    assert!([
        "calibrate",
        "compare",
        "device",
        "host",
        "log",
        "sim",
        "tune"
    ]
    .iter()
    .all(|n| names.contains(n)));
    let commands = format!("commands: {}", names.join(", "));
    let commands = commands.as_str();
    assert_eq!(
        error(&["simm"]),
        format!("unknown command \"simm\" (did you mean sim?); {commands}")
    );
    assert!(error(&["frobnicate"]).ends_with(commands));
    assert!(error(&["help", "frobnicate"]).starts_with("unknown command \"frobnicate\""));
    assert_eq!(
        error(&["filter", "desing"]),
        "unknown filter subcommand \"desing\" (did you mean design?); subcommands: design, apply"
    );
    assert_eq!(
        error(&["fuzzy", "evl"]),
        "unknown fuzzy subcommand \"evl\" (did you mean eval?); subcommands: eval, export"
    );
    let design = ["filter", "design", "--order", "4", "--fs", "100"];
    assert_eq!(
        error(&[&design[..], &["--cutoff", "5", "--cutoff=6"]].concat()),
        "--cutoff is given twice (\"5\", then \"6\")"
    );
    assert_eq!(
        error(&["controllers", "--json", "--json"]),
        "--json is given twice"
    );
    assert_eq!(
        error(&["controllers", "--json=yes"]),
        "--json takes no value"
    );
    assert_eq!(error(&["spectrum", "--fs"]), "--fs needs a value (HZ)");
    assert_eq!(
        error(&["sim", "--scenario", "--controller", "pi"]),
        "--scenario needs a value (NAME)"
    );
}

/// `cutlab help`, `cutlab help COMMAND`, `-h` and `--help` after a command print help on
/// standard output and succeed.
#[test]
fn help_in_every_spelling_goes_to_stdout() {
    let (result, top) = cutlab(&["--help"], "");
    assert!(result.is_ok());
    for args in [&["help"][..], &["-h"]] {
        let (result, out) = cutlab(args, "");
        assert!(result.is_ok(), "{args:?}");
        assert!(out.starts_with("cutlab"), "{args:?}: {out}");
        assert!(out.contains("Usage: cutlab"), "{args:?}: {out}");
    }
    assert!(top.contains("--version"));
    let (result, sim) = cutlab(&["help", "sim"], "");
    assert!(result.is_ok());
    assert!(
        sim.contains("Usage: cutlab sim") && sim.contains("--rpm"),
        "{sim}"
    );
    let (result, design) = cutlab(&["filter", "design", "--order", "4", "-h"], "");
    assert!(result.is_ok());
    assert!(design.contains("Usage: cutlab filter design"), "{design}");
}

#[test]
fn huge_and_tiny_numbers_in_messages_read_as_a_person_writes_them() {
    let (result, _) = cutlab(
        &[
            "sim",
            "--scenario",
            "kim-step-doc",
            "--controller",
            "pi",
            "--feed-mm-min",
            "1e308",
        ],
        "",
    );
    assert_eq!(
        result.unwrap_err(),
        "--feed-mm-min: 1e308 mm/min is outside 1–20000 mm/min"
    );
    let (result, _) = cutlab(
        &[
            "sim",
            "--scenario",
            "kim-step-doc",
            "--controller",
            "pi",
            "--set",
            "kp=1e300",
        ],
        "",
    );
    assert!(result.unwrap_err().contains("kp = 1e300 is outside"));
    let (result, _) = cutlab(
        &[
            "force",
            "--diameter-mm",
            "1e300",
            "--teeth",
            "2",
            "--axial-depth-mm",
            "1",
            "--mode",
            "slot",
            "--feed-per-tooth-mm",
            "0.1",
            "--rpm",
            "1000",
            "--material",
            "sm45c",
        ],
        "",
    );
    assert!(result
        .unwrap_err()
        .contains("1e300 mm is larger than any end mill"));
}

#[test]
fn tune_sweeps_and_searches_and_says_what_is_wrong() {
    let (result, out) = cutlab(
        &[
            "tune",
            "--quiet",
            "--controller",
            "threshold",
            "--scenarios",
            "maneerat-doc-1",
            "--param",
            "kp=0.2:1",
            "--sweep",
            "3",
            "--json",
        ],
        "",
    );
    result.unwrap();
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    let points = report["points"].as_array().unwrap();
    assert_eq!(points.len(), 3);
    assert_eq!(points[2]["values"][0], 1.0);
    assert!(points.iter().all(|p| p["cost"].as_f64().unwrap() > 0.0));

    let (result, out) = cutlab(
        &[
            "tune",
            "--quiet",
            "--controller",
            "pi",
            "--scenarios",
            "maneerat-doc-1",
            "--param",
            "kp=0.05:1.5",
            "--max-evals",
            "6",
        ],
        "",
    );
    result.unwrap();
    assert!(out.contains("best: kp="), "{out}");
    assert!(out.contains("Pareto front"), "{out}");

    for (args, message) in [
        (
            &[
                "tune",
                "--quiet",
                "--controller",
                "pi",
                "--scenarios",
                "nope",
                "--param",
                "kp=0:1",
            ][..],
            "--scenarios: unknown preset \"nope\"",
        ),
        (
            &[
                "tune",
                "--quiet",
                "--controller",
                "pi",
                "--scenarios",
                "maneerat-doc-1",
                "--param",
                "kp=0:99",
            ][..],
            "kp = 99 is outside",
        ),
        (
            &[
                "tune",
                "--quiet",
                "--controller",
                "pi",
                "--scenarios",
                "maneerat-doc-1",
                "--param",
                "kp",
            ][..],
            "--param: \"kp\" is not of the form key=lo:hi",
        ),
        (
            &[
                "tune",
                "--quiet",
                "--controller",
                "pi",
                "--scenarios",
                "maneerat-doc-1",
                "--param",
                "kp=0:1",
                "--objective",
                "speed=2",
            ][..],
            "--objective: unknown objective term \"speed\"",
        ),
        (
            &["tune", "--scenarios", "maneerat-doc-1", "--param", "kp=0:1"][..],
            "--controller",
        ),
        (
            &[
                "tune",
                "--quiet",
                "--controller",
                "pi",
                "--scenarios",
                "maneerat-doc-1",
                "--param",
                "kp=0:1",
                "--param",
                "kp=0.2:0.5",
            ][..],
            "--param: kp is given twice (0:1 and 0.2:0.5)",
        ),
        (
            &[
                "tune",
                "--quiet",
                "--teach-in",
                "--scenarios",
                "maneerat-doc-1",
                "--param",
                "kp=0:1",
            ][..],
            "--param does not apply to --teach-in",
        ),
        (
            &[
                "tune",
                "--quiet",
                "--teach-in",
                "--scenarios",
                "maneerat-doc-1",
                "--controller",
                "pi",
            ][..],
            "--controller does not apply to --teach-in",
        ),
        (
            &[
                "tune",
                "--quiet",
                "--teach-in",
                "--scenarios",
                "maneerat-doc-1",
                "--objective",
                "error=2",
            ][..],
            "--objective does not apply to --teach-in",
        ),
        (
            &[
                "tune",
                "--quiet",
                "--teach-in",
                "--scenarios",
                "maneerat-doc-1",
                "--sweep",
                "3",
            ][..],
            "--sweep does not apply to --teach-in",
        ),
        (
            &["tune", "--teach-in"][..],
            "--teach-in needs a teach cut: --scenarios A,B (simulated), --log FILE or \
             --calibration FILE",
        ),
        (
            &[
                "tune",
                "--quiet",
                "--teach-in",
                "--scenarios",
                "maneerat-doc-1",
                "--map",
                "force_n=F",
            ][..],
            "--map only applies to a teach-in from a log (--log FILE)",
        ),
        (
            &[
                "tune",
                "--quiet",
                "--controller",
                "pi",
                "--scenarios",
                "maneerat-doc-1",
                "--param",
                "kp=0:1",
                "--log",
                "x.csv",
            ][..],
            "--log only applies with --teach-in",
        ),
        (
            &[
                "tune",
                "--quiet",
                "--teach-in",
                "--log",
                "tests/reference/tuning/teach_cut_log.csv",
                "--scenarios",
                "maneerat-doc-1",
            ][..],
            "--scenarios does not apply to a teach-in from a log",
        ),
        (
            &[
                "tune",
                "--quiet",
                "--teach-in",
                "--calibration",
                "x.json",
                "--scenarios",
                "maneerat-doc-1,maneerat-doc-2",
            ][..],
            "--scenarios: a calibration was taught on one program; name one preset",
        ),
        (
            &[
                "tune",
                "--quiet",
                "--controller",
                "pi",
                "--scenarios",
                "maneerat-doc-1",
                "--param",
                "kp=0:1",
                "--sweep",
                "2",
                "--max-evals",
                "4",
            ][..],
            "--max-evals applies to the search",
        ),
    ] {
        let (result, _) = cutlab(args, "");
        let e = result.unwrap_err();
        assert!(e.contains(message), "{args:?}: {e}");
        assert!(!e.contains('\n'));
    }
}

/// Progress is on stderr, one line per teach cut and per evaluation; stdout holds only the
/// result (JSON that parses), and --quiet silences the progress.
#[test]
fn tune_prints_progress_on_stderr_and_keeps_stdout_clean() {
    use std::process::Command;
    let run = |extra: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_cutlab"))
            .args([
                "tune",
                "--controller",
                "threshold",
                "--scenarios",
                "maneerat-doc-1",
                "--param",
                "kp=0.2:1",
            ])
            .args(extra)
            .output()
            .unwrap();
        assert!(out.status.success(), "{out:?}");
        (
            String::from_utf8(out.stdout).unwrap(),
            String::from_utf8(out.stderr).unwrap(),
        )
    };
    let (stdout, stderr) = run(&["--sweep", "2", "--json"]);
    let report: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(report["points"].as_array().unwrap().len(), 2);
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 3, "{stderr}");
    assert_eq!(lines[0], "tune: teach cut 1 of 1 done (maneerat-doc-1)");
    assert!(
        lines[1].starts_with("tune: point 1 of 2 (50 %): kp="),
        "{stderr}"
    );
    assert!(
        lines[2].starts_with("tune: point 2 of 2 (100 %): kp="),
        "{stderr}"
    );
    assert!(lines[2].contains("→ objective "), "{stderr}");

    let (stdout, stderr) = run(&["--max-evals", "3"]);
    assert!(stdout.contains("best: kp="), "{stdout}");
    assert!(!stdout.contains("tune:"), "{stdout}");
    for n in 1..=3 {
        assert!(
            stderr.contains(&format!("tune: evaluation {n} of at most 3: kp=")),
            "{stderr}"
        );
    }
    assert!(!stderr.contains("evaluation 4"), "{stderr}");

    let (_, stderr) = run(&["--max-evals", "2", "--quiet"]);
    assert_eq!(stderr, "");
}

const TEACH_LOG: &str = "tests/reference/tuning/teach_cut_log.csv";

#[test]
fn tune_teach_in_reads_a_logged_teach_cut_as_calibrate_does() {
    let expected: serde_json::Value =
        serde_json::from_str(include_str!("reference/tuning/teach_in.json")).unwrap();
    let expected = &expected["log"];
    let args = [
        "tune",
        "--teach-in",
        "--log",
        TEACH_LOG,
        "--map",
        "spindle_current_rms_a=S_Strom [A]",
        "--map",
        "spindle_speed_rpm=S_Drehzahl (rpm)",
        "--map",
        "force_n=Kraft [N]",
        "--map",
        "override_pct=Override [%]",
    ];
    let (result, out) = cutlab(&[&args[..], &["--json"]].concat(), "");
    result.unwrap();
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    let target = report["proposal"]["target_n"].as_f64().unwrap();
    let expected_target = expected["target_n"].as_f64().unwrap();
    assert!(
        (target - expected_target).abs() < 1e-9 * expected_target,
        "{out}"
    );
    assert_eq!(report["learned"]["feedback"], "spindle-current");
    assert!(
        report["log_problems"].as_array().unwrap().is_empty(),
        "{out}"
    );
    let (result, out) = cutlab(&args, "");
    result.unwrap();
    assert!(out.starts_with("note: feed model not fitted"), "{out}");
    assert!(
        out.contains(&format!(
            "proposed target {expected_target:.0} N (80 % of the force at 100 % override)"
        )),
        "{out}"
    );
    let gap_pct = expected["gap_pct"].as_f64().unwrap();
    assert!(
        out.contains(&format!("threshold:gap_pct={gap_pct:.1}")),
        "{out}"
    );
    // A column that is not there is named with the ones that are.
    let (result, _) = cutlab(
        &[
            "tune",
            "--teach-in",
            "--log",
            TEACH_LOG,
            "--map",
            "force_n=Force",
        ],
        "",
    );
    let e = result.unwrap_err();
    assert!(e.contains("--map force_n=Force: no such column"), "{e}");
    assert!(e.starts_with(TEACH_LOG), "{e}");
}

/// What a version 1 calibration file cannot tell, as every command that loads one says it.
const CANNOT_TELL_LOAD_LEVELS: &str = "the calibration does not say how many load levels its \
                                       lines rest on (saved by an older cutlab)";

/// The shipped kim-step-doc calibration written into `dir` as today's file and as its version 1
/// twin (saved before files kept their load levels): `(today, older)`.
fn today_and_older_calibrations(dir: &std::path::Path) -> (std::path::PathBuf, std::path::PathBuf) {
    std::fs::create_dir_all(dir).unwrap();
    let shipped = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/www/data/kim-step-doc-calibration.json"
    ))
    .unwrap();
    let today = dir.join("today.json");
    std::fs::write(&today, &shipped).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&shipped).unwrap();
    json["version"] = 1.into();
    json["calibration"]
        .as_object_mut()
        .unwrap()
        .remove("few_load_levels");
    let older = dir.join("older.json");
    std::fs::write(&older, json.to_string()).unwrap();
    (today, older)
}

/// `cutlab host --calibration FILE` says what the calibration rests on, in the words of the fit's
/// other front ends: a version 1 file (saved before files kept their load levels) cannot tell.
#[cfg(unix)]
#[test]
fn the_host_warns_that_an_older_calibration_file_cannot_tell_its_load_levels() {
    use std::process::Command;
    let exe = env!("CARGO_BIN_EXE_cutlab");
    let dir = std::env::temp_dir().join(format!("cutlab-host-v1-{}", std::process::id()));
    let (today, older) = today_and_older_calibrations(&dir);
    let run = |file: &std::path::Path| {
        let out = Command::new(exe)
            .args([
                "host",
                "--device-cmd",
                &format!(
                    "{exe} device --stdio --scenario kim-step-doc --time-scale 40 --watchdog-s 20"
                ),
                "--controller",
                "threshold",
                "--duration-s",
                "1",
                "--no-references",
                "--calibration",
                file.to_str().unwrap(),
            ])
            .output()
            .unwrap();
        assert!(out.status.success(), "{out:?}");
        String::from_utf8(out.stdout).unwrap()
    };
    // Today's file: the teach cut's lines rest on enough loads, no warning.
    let out = run(&today);
    assert!(!out.contains("warning:"), "{out}");
    let out = run(&older);
    assert!(
        out.contains(&format!("warning: {CANNOT_TELL_LOAD_LEVELS}")),
        "{out}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every other command that loads a saved calibration says what `cutlab host` says of it, in the
/// same words: `cutlab sim`, `cutlab log replay` and `cutlab tune --teach-in` warn that a version
/// 1 file cannot tell what its lines rest on, and say nothing of today's file.
#[test]
fn every_command_that_loads_a_calibration_warns_that_an_older_file_cannot_tell() {
    let dir = std::env::temp_dir().join(format!("cutlab-v1-everywhere-{}", std::process::id()));
    let (today, older) = today_and_older_calibrations(&dir);
    let export = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/www/data/synthetic-kim-step-doc-export.csv"
    );
    let commands: [(&str, Vec<&str>); 3] = [
        (
            "sim",
            vec![
                "sim",
                "--scenario",
                "kim-step-doc",
                "--controller",
                "threshold",
                "--no-references",
            ],
        ),
        (
            "log replay",
            vec![
                "log",
                "replay",
                export,
                "--current",
                "S_Strom [A]",
                "--controller",
                "pi",
                "--target-n",
                "372",
            ],
        ),
        (
            "tune --teach-in",
            vec!["tune", "--teach-in", "--scenarios", "kim-step-doc"],
        ),
    ];
    for (what, args) in &commands {
        for (file, warns) in [(&today, false), (&older, true)] {
            let mut args = args.clone();
            args.extend(["--calibration", file.to_str().unwrap()]);
            let (result, out) = common::cutlab_text(&args, "");
            assert!(result.is_ok(), "{what}: {result:?}\n{out}");
            assert_eq!(
                out.contains(CANNOT_TELL_LOAD_LEVELS),
                warns,
                "{what} with {}:\n{out}",
                file.display()
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The hardware path as a person types it: a teach cut over the link (`cutlab host` against the
/// device with no simulation truth, the force modelled from the cut) saved with
/// --save-calibration, then proposed from by `cutlab tune --teach-in --calibration`.
#[cfg(unix)]
#[test]
fn tune_teach_in_proposes_from_a_calibration_saved_by_the_host() {
    use std::process::Command;
    let exe = env!("CARGO_BIN_EXE_cutlab");
    let dir = std::env::temp_dir().join(format!("cutlab-tune-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let saved = dir.join("machine.json");
    let out = Command::new(exe)
        .args([
            "host",
            "--device-cmd",
            &format!(
                "{exe} device --stdio --scenario maneerat-doc-1 --time-scale 40 --no-truth \
                 --watchdog-s 2"
            ),
            "--controller",
            "threshold",
            "--duration-s",
            "1",
            "--save-calibration",
            saved.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    let (result, text) = cutlab(
        &[
            "tune",
            "--teach-in",
            "--calibration",
            saved.to_str().unwrap(),
            "--scenarios",
            "maneerat-doc-1",
            "--json",
        ],
        "",
    );
    result.unwrap();
    let report: serde_json::Value = serde_json::from_str(&text).unwrap();
    let t = &report[0];
    assert!(
        t["source"]
            .as_str()
            .unwrap()
            .contains("teach cut over the link"),
        "{text}"
    );
    // The force the link's teach cut learned at 100 % is the cut's mean resultant (Altintas,
    // tests/reference/tuning); the proposal is 80 % of it, the paper's 150 N beside it.
    let expected: serde_json::Value =
        serde_json::from_str(include_str!("reference/tuning/teach_in.json")).unwrap();
    let expected = expected["mills"]["maneerat-doc-1"]["force_at_full_override_n"]
        .as_f64()
        .unwrap();
    let learned = t["learned"]["force_at_full_override_n"].as_f64().unwrap();
    assert!((learned - expected).abs() < 0.02 * expected, "{text}");
    assert_eq!(t["proposal"]["target_n"].as_f64().unwrap(), 0.8 * learned);
    assert_eq!(t["paper"]["target_n"], 150.0);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn log_inspect_reports_the_dialect_columns_and_problems_as_json() {
    let (result, out) = cutlab(
        &[
            "log",
            "inspect",
            "tests/data/logs/semicolon_decimal_comma.csv",
            "--json",
        ],
        "",
    );
    result.unwrap();
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(report["rows"], 12);
    assert_eq!(report["delimiter"], ";");
    assert_eq!(report["decimal"], ",");
    assert_eq!(report["header"], true);
    assert_eq!(report["time_column"], "Time [s]");
    assert_eq!(report["sample_period_s"], 0.01);
    let current = &report["columns"][1];
    for (key, value) in [
        ("name", serde_json::json!("X_Current [A]")),
        ("kind", serde_json::json!("number")),
        ("unit", serde_json::json!("A")),
        ("role", serde_json::json!("rms-current")),
        ("numeric_share", serde_json::json!(1.0)),
        ("missing", serde_json::json!(0)),
        ("min", serde_json::json!(1.5)),
    ] {
        assert_eq!(current[key], value, "{key}");
    }
    assert_eq!(report["columns"][4]["kind"], "text");
    assert_eq!(report["columns"][4]["min"], serde_json::Value::Null);

    let (result, out) = cutlab(
        &[
            "log",
            "inspect",
            "tests/data/logs/messy_no_header.csv",
            "--json",
        ],
        "",
    );
    result.unwrap();
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(report["sample_period_s"], serde_json::Value::Null);
    let problems = report["problems"].as_array().unwrap();
    assert!(problems
        .iter()
        .any(|p| p["line"] == 7 && p["column"] == "column 2"));

    let (result, _) = cutlab(&["log", "inspect", "no/such/file.csv"], "");
    assert!(result
        .unwrap_err()
        .starts_with("no/such/file.csv: cannot open"));
    let (result, _) = cutlab(
        &[
            "log",
            "inspect",
            "tests/data/logs/comma.csv",
            "--sample-period-s",
            "0",
        ],
        "",
    );
    assert!(result.unwrap_err().contains("--sample-period-s"));
}

#[test]
fn log_analyse_groups_by_label_and_says_when_a_stage_is_skipped() {
    let (result, out) = cutlab(
        &[
            "log",
            "analyse",
            "tests/data/logs/comma.csv",
            "--column",
            "X_Current [A]",
            "--by",
            "Phase",
            "--lowpass-hz",
            "80",
            "--json",
        ],
        "",
    );
    result.unwrap();
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    let column = &report["columns"][0];
    assert_eq!(column["whole"]["count"], 12);
    assert_eq!(column["by_label"][0]["label"], "Prep");
    assert_eq!(column["by_label"][0]["stats"]["count"], 3);
    assert!(column["notes"][0].as_str().unwrap().contains("Nyquist"));
    for (args, message) in [
        (
            &["log", "analyse", "tests/data/logs/comma.csv"][..],
            "--column",
        ),
        (
            &[
                "log",
                "analyse",
                "tests/data/logs/comma.csv",
                "--column",
                "nope",
            ][..],
            "no column \"nope\"",
        ),
        (
            &[
                "log",
                "analyse",
                "tests/data/logs/comma.csv",
                "--column",
                "Fx [N]",
                "--order",
                "4",
            ][..],
            "--lowpass-hz",
        ),
        (
            &[
                "log",
                "analyse",
                "tests/data/logs/comma.csv",
                "--column",
                "Fx [N]",
                "--lowpass-hz",
                "1",
                "--order",
                "99",
            ][..],
            "--order",
        ),
    ] {
        let (result, _) = cutlab(args, "");
        let e = result.unwrap_err();
        assert!(e.contains(message), "{args:?}: {e}");
    }
}

/// `cutlab calibrate` reads a hostile log (a BOM, CRLF, numbers at the edge of f64) as the log
/// reader does: no panic, one error naming the file, line and column.
#[test]
fn calibrate_names_the_line_and_column_of_an_impossible_value() {
    let dir = std::env::temp_dir().join(format!("cutlab-calibrate-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("hostile.csv");
    let mut text =
        String::from("\u{feff}time_s,spindle_current_rms_a,spindle_speed_rpm,force_n\r\n");
    for i in 0..40 {
        text.push_str(&format!(
            "{},{},1000,{}\r\n",
            f64::from(i) * 0.1,
            5 + i % 7,
            200 + 3 * i
        ));
    }
    text.push_str("4,1e308,1000,1e200\r\n");
    std::fs::write(&path, &text).unwrap();
    let file = path.to_str().unwrap();
    let (result, out) = cutlab(&["calibrate", file], "");
    let e = result.unwrap_err();
    assert!(out.is_empty(), "{out}");
    assert!(
        e.starts_with(&format!(
            "{file}: line 42, column \"force_n\": 1e200 is beyond"
        )),
        "{e}"
    );
    assert!(!e.contains('\n'), "{e}");
    // Without the impossible row the same file (BOM and CRLF kept) calibrates.
    let good: String = text.lines().take(41).map(|l| format!("{l}\r\n")).collect();
    std::fs::write(&path, good).unwrap();
    let (result, out) = cutlab(&["calibrate", file, "--json"], "");
    result.unwrap();
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(report["rows_with_force"], 40, "{out}");
    std::fs::remove_dir_all(&dir).ok();
}

/// A header of twenty thousand columns (a few MB) is read at once, and the error for a missing
/// force column names a few of the file's columns and how many there are, not all of them.
#[test]
fn calibrate_on_a_very_wide_file_says_what_is_missing_in_one_short_line() {
    let dir = std::env::temp_dir().join(format!("cutlab-wide-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("wide.csv");
    let names: Vec<String> = (0..20_000).map(|i| format!("c{i}")).collect();
    let values = vec!["1"; names.len()].join(",");
    std::fs::write(&path, format!("{}\n{values}\n{values}\n", names.join(","))).unwrap();
    let file = path.to_str().unwrap();
    let (result, _) = cutlab(&["calibrate", file], "");
    let e = result.unwrap_err();
    assert!(
        e.contains("no \"force_n\" column (the file's columns: c0, c1,")
            && e.contains("c11, … (20000 in all)"),
        "{e}"
    );
    assert!(e.len() < 400, "{e}");
    let (result, _) = cutlab(&["calibrate", file, "--map", "force_n=F"], "");
    let e = result.unwrap_err();
    assert!(
        e.contains("--map force_n=F: no such column; columns: c0,"),
        "{e}"
    );
    assert!(e.len() < 400, "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Only a closed standard output is quiet: an error that merely says "Broken pipe" (a file of
/// that name, a device that went away) is printed and fails.
#[cfg(unix)]
#[test]
fn an_error_is_never_taken_for_a_closed_pipe_by_its_words() {
    use std::process::{Command, Stdio};
    let exe = env!("CARGO_BIN_EXE_cutlab");
    let out = Command::new(exe)
        .args(["log", "inspect", "Broken pipe.csv"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1), "{out:?}");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.starts_with("cutlab: error: Broken pipe.csv: cannot open"),
        "{stderr}"
    );
    // The reader of stdout gone before the output: quiet, and a success.
    let mut child = Command::new(exe)
        .args(["fuzzy", "export", "--rules", "dynamics"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "{out:?}");
    assert!(out.stderr.is_empty(), "{out:?}");
}

#[test]
fn negative_values_get_the_options_own_message() {
    for (args, expected) in [
        (
            &[
                "log",
                "replay",
                "x.csv",
                "--current",
                "I",
                "--controller",
                "pi",
                "--target-a",
                "-1",
            ][..],
            "--target-a: must be positive, got -1",
        ),
        (
            &[
                "tune",
                "--controller",
                "pi",
                "--scenarios",
                "maneerat-doc-1",
                "--sweep",
                "-1",
            ][..],
            // The Tune page's words for its "Values per parameter" field, with the option.
            "--sweep: \"-1\" is not a whole number",
        ),
        (
            &[
                "tune",
                "--controller",
                "pi",
                "--scenarios",
                "maneerat-doc-1",
                "--max-evals",
                "-5",
            ][..],
            "--max-evals: \"-5\" is not a whole number",
        ),
        (
            &[
                "host",
                "--port",
                "/dev/null",
                "--baud",
                "-1",
                "--controller",
                "pi",
            ][..],
            // The Hardware page's words for its Baud rate field, with the option.
            "--baud: \"-1\" is not a whole number",
        ),
    ] {
        let (result, _) = cutlab(args, "");
        assert_eq!(result.unwrap_err(), expected, "{args:?}");
    }
}

#[test]
fn a_range_error_in_a_config_file_names_the_file_the_run_and_the_field() {
    let path =
        std::env::temp_dir().join(format!("cutlab-config-range-{}.json", std::process::id()));
    std::fs::write(
        &path,
        r#"{"format": "cutlab-runs", "version": 1, "runs": [{"preset": "maneerat-doc-1",
            "controller": {"kind": "pi"}, "seed": 1, "settings": {"max_override_pct": 1e300}}]}"#,
    )
    .unwrap();
    let path = path.to_string_lossy().into_owned();
    for command in ["sim", "compare"] {
        let (result, _) = cutlab(&[command, "--config", &path, "--no-references"], "");
        assert_eq!(
            result.unwrap_err(),
            format!(
                "--config {path}: run 1: highest override 1e300 % is more than this machine \
                 applies (255 %)"
            )
        );
    }
}

#[test]
fn an_objective_of_all_zero_weights_is_refused_before_any_run() {
    let (result, out) = cutlab(
        &[
            "tune",
            "--controller",
            "pi",
            "--scenarios",
            "maneerat-doc-1",
            "--param",
            "kp=0.1:1",
            "--objective",
            "cycle=0,error=0,above=0,activity=0",
        ],
        "",
    );
    let e = result.unwrap_err();
    assert!(e.starts_with("--objective: every weight is 0"), "{e}");
    assert!(out.is_empty(), "{out}");
}

#[test]
fn log_inspect_gives_the_mean_of_huge_values_and_counts_what_statistics_leave_out() {
    let path = std::env::temp_dir().join(format!("cutlab-huge-{}.csv", std::process::id()));
    let mut text = String::from("t [s],F [N],I [A]\n");
    for i in 0..50 {
        // 30 of 50 currents are NaN, inf or beyond a double's range.
        let current = match i % 5 {
            0 => "NaN",
            1 => "inf",
            2 => "1e309",
            _ => "2",
        };
        text.push_str(&format!("{i},1e308,{current}\n"));
    }
    std::fs::write(&path, text).unwrap();
    let path = path.to_string_lossy().into_owned();
    let (result, out) = cutlab(&["log", "inspect", &path], "");
    result.unwrap();
    let force = out
        .lines()
        .find(|l| l.trim_start().starts_with("F [N]"))
        .unwrap();
    assert!(force.contains("1e308 … 1e308, mean 1e308"), "{force}");
    let current = out
        .lines()
        .find(|l| l.trim_start().starts_with("I [A]"))
        .unwrap();
    assert!(
        current.contains("not finite 30") && current.contains("(20 of 50 rows)"),
        "{current}"
    );
    let (result, json) = cutlab(&["log", "inspect", &path, "--json"], "");
    result.unwrap();
    let report: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(report["columns"][1]["mean"], 1e308);
    assert_eq!(report["columns"][2]["not_finite"], 30);
    assert_eq!(report["columns"][2]["count"], 20);
    assert_eq!(report["account"]["not_finite_cells"], 30);
    let (result, out) = cutlab(&["log", "analyse", &path, "--column", "I [A]"], "");
    result.unwrap();
    assert!(
        out.contains("(30 of 50 rows left out: gaps or not finite)"),
        "{out}"
    );
}
