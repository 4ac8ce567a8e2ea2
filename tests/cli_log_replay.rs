//! `cutlab log replay` and `cutlab calibrate --save-calibration` on the synthetic machine export
//! in www/data: a calibration saved from a log, used to replay a controller on it, with the CSV
//! and JSON the issue names.
#![cfg(feature = "cli")]
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;

use cutlab::closed_loop::calibration_file::CalibrationFile;
use cutlab::estimation::estimator::Feedback;

const EXPORT: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/www/data/synthetic-kim-step-doc-export.csv"
);

fn scratch(name: &str) -> String {
    let dir = std::env::temp_dir().join(format!("cutlab-cli-log-replay-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name).to_string_lossy().into_owned()
}

#[test]
fn a_calibration_saved_from_a_log_replays_a_controller_on_it() {
    let saved = scratch("export-calibration.json");
    let (result, out) = common::cutlab_text(
        &[
            "calibrate",
            EXPORT,
            "--map",
            "time_s=Zeit [s]",
            "--map",
            "force_n=Kraft [N]",
            "--map",
            "spindle_current_rms_a=S_Strom [A]",
            "--map",
            "spindle_speed_rpm=S_Drehzahl (rpm)",
            "--save-calibration",
            &saved,
        ],
        "",
    );
    result.unwrap();
    assert!(out.contains("0.004493 A/N"), "{out}");
    let file = CalibrationFile::from_json(&std::fs::read_to_string(&saved).unwrap()).unwrap();
    assert_eq!(file.feedback(), Feedback::SpindleCurrent);
    assert!(file.source.contains("spindle model"), "{}", file.source);
    // The median logged force in the cut, and a phase's peak from the largest RMS current.
    let c = &file.calibration;
    assert!(
        (300.0..420.0).contains(&c.median_force_at_full_override_n),
        "{c:?}"
    );
    assert!(
        (c.max_phase_current_a / 48.9991 - 2f64.sqrt()).abs() < 1e-3,
        "{c:?}"
    );

    let (csv, json) = (scratch("replay.csv"), scratch("replay.json"));
    let (result, out) = common::cutlab_text(
        &[
            "log",
            "replay",
            EXPORT,
            "--current",
            "S_Strom [A]",
            "--controller",
            "pi",
            "--set",
            "kp=0.4",
            "--calibration",
            &saved,
            "--target-n",
            "372",
            "--csv",
            &csv,
            "--json",
            &json,
        ],
        "",
    );
    result.unwrap();
    assert!(out.contains("pi replayed on 1149 rows"), "{out}");
    assert!(out.contains("current is an RMS value"), "{out}");
    // The summary's percents and forces to a tenth, as a person reads them.
    let summary = out
        .lines()
        .find(|l| l.starts_with("override while armed: "))
        .unwrap();
    for number in summary
        .split([' ', '(', ')', ';', ','])
        .filter(|w| w.contains('.'))
    {
        let decimals = number.split('.').nth(1).unwrap();
        assert_eq!(decimals.len(), 1, "{number} in {summary}");
    }
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(
        lines.next().unwrap(),
        "time_s,current_a,force_est_n,requested_override_pct,override_pct,envelope_state,\
         logged_override_pct,force_n"
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(
        rows.len() as u64,
        report["summary"]["periods"].as_u64().unwrap()
    );
    assert_eq!(report["settings"]["controller"]["params"]["kp"], 0.4);
    assert_eq!(report["settings"]["target_force_n"], 372.0);
    assert_eq!(
        report["settings"]["spindle_lowpass_hz"],
        serde_json::Value::Null
    );
    assert_eq!(report["events"][0]["kind"], "armed");
    let armed_at = report["summary"]["armed_at_s"].as_f64().unwrap();
    assert!((3.0..3.2).contains(&armed_at), "{armed_at}");
    // In the 4 mm step the estimate reads the log's force: the calibration was fitted to it.
    let (mut estimate, mut measured, mut n) = (0.0, 0.0, 0.0);
    for row in &rows {
        let t: f64 = row[0].parse().unwrap();
        if (40.0..50.0).contains(&t) {
            estimate += row[2].parse::<f64>().unwrap();
            measured += row[7].parse::<f64>().unwrap();
            n += 1.0;
        }
    }
    assert!(n > 100.0);
    assert!(
        (estimate / measured - 1.0).abs() < 0.05,
        "{} vs {}",
        estimate / n,
        measured / n
    );
    // The envelope's states in the CSV: disarmed first, armed later.
    assert_eq!(rows[0][5], "disarmed");
    assert!(rows.iter().any(|r| r[5] == "armed" || r[5] == "limited"));
}

#[test]
fn replay_refuses_what_it_cannot_do_and_says_what_to_give() {
    for (args, message) in [
        (
            &["log", "replay", EXPORT, "--controller", "pi"][..],
            "--current",
        ),
        (
            &[
                "log",
                "replay",
                EXPORT,
                "--current",
                "Strom",
                "--controller",
                "pi",
            ][..],
            "--current: no column \"Strom\"; columns: Zeit [s]",
        ),
        (
            &["log", "replay", EXPORT, "--current", "S_Strom [A]"][..],
            "--controller",
        ),
        (
            &[
                "log",
                "replay",
                EXPORT,
                "--current",
                "S_Strom [A]",
                "--controller",
                "pi",
                "--target-n",
                "300",
            ][..],
            "a force target needs a calibration",
        ),
        (
            &[
                "log",
                "replay",
                EXPORT,
                "--current",
                "S_Strom [A]",
                "--controller",
                "pi",
            ][..],
            "--target-a: no calibration, so the controllers regulate the current: give a current target",
        ),
        (
            &[
                "log",
                "replay",
                EXPORT,
                "--current",
                "S_Strom [A]",
                "--controller",
                "pi",
                "--target-a",
                "10",
                "--set",
                "kq=1",
            ][..],
            "--set: controller \"pi\" has no parameter \"kq\"",
        ),
        (
            &[
                "log",
                "replay",
                EXPORT,
                "--current",
                "S_Strom [A]",
                "--controller",
                "pi",
                "--target-a",
                "10",
                "--set",
                "kp=0.5",
                "--set",
                "kp=0.9",
            ][..],
            "--set: kp is given twice (kp=0.5, then kp=0.9); give each parameter once",
        ),
        (
            &[
                "log",
                "replay",
                EXPORT,
                "--current",
                "S_Strom [A]",
                "--controller",
                "pi",
                "--target-a",
                "10",
                "--map",
                "torque=S_Strom [A]",
            ][..],
            "--map: unknown channel \"torque\"",
        ),
        (
            &[
                "log",
                "replay",
                EXPORT,
                "--current",
                "X_Strom [A]",
                "--controller",
                "pi",
                "--target-a",
                "1",
                "--map",
                "feed=",
            ][..],
            "feed-current feedback needs the feed",
        ),
    ] {
        let (result, _) = common::cutlab_text(args, "");
        let e = result.unwrap_err();
        assert!(e.contains(message), "{args:?}: {e}");
        assert!(!e.contains('\n'), "{e}");
    }
    let (result, help) = common::cutlab_text(&["log", "replay", "--help"], "");
    result.unwrap();
    for option in [
        "--current",
        "--target-n",
        "--calibration",
        "--csv",
        "--json",
        "open-loop",
    ] {
        assert!(help.contains(option), "{option}");
    }
}

/// The export with `damage` applied to the time cell (the first field) of each of `lines`.
fn damaged_export(name: &str, lines: &[usize], damage: &str) -> String {
    let text = std::fs::read_to_string(EXPORT).unwrap();
    let damaged: Vec<String> = text
        .split('\n')
        .enumerate()
        .map(
            |(i, line)| match (lines.contains(&(i + 1)), line.split_once(';')) {
                (true, Some((_, rest))) => format!("{damage};{rest}"),
                _ => line.to_string(),
            },
        )
        .collect();
    let path = scratch(name);
    std::fs::write(&path, damaged.join("\n")).unwrap();
    path
}

#[test]
fn replayed_events_are_timed_even_where_a_time_cell_is_damaged() {
    // The arming (3.06 s) and the air cut after it are events: damage the times around them.
    for damage in ["NaN", "inf", "kaputt", ""] {
        let path = damaged_export(
            &format!("damaged-time-{damage}.csv"),
            &[50, 51, 52, 53, 54, 1100],
            damage,
        );
        let json = scratch(&format!("damaged-time-{damage}.json"));
        let (result, out) = common::cutlab_text(
            &[
                "log",
                "replay",
                &path,
                "--current",
                "S_Strom [A]",
                "--controller",
                "pi",
                "--target-a",
                "10.3",
                "--json",
                &json,
            ],
            "",
        );
        result.unwrap();
        assert!(
            !out.contains("NaN s") && !out.contains("inf s"),
            "{damage:?}: {out}"
        );
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        let events = report["events"].as_array().unwrap();
        assert!(!events.is_empty());
        for e in events {
            assert!(
                e["time_s"].as_f64().is_some_and(f64::is_finite),
                "{damage:?}: {e}"
            );
        }
    }
}

#[test]
fn a_time_column_that_does_not_increase_is_named_as_such() {
    let path = scratch("standing-time.csv");
    std::fs::write(&path, "time_s,I [A]\n0,10\n0,11\n0,12\n0,11\n").unwrap();
    let (result, _) = common::cutlab_text(
        &[
            "log",
            "replay",
            &path,
            "--current",
            "I [A]",
            "--controller",
            "pi",
            "--target-a",
            "10",
        ],
        "",
    );
    let e = result.unwrap_err();
    assert!(
        e.contains("its time column \"time_s\" does not increase; give it with --sample-period-s"),
        "{e}"
    );
    let (result, out) = common::cutlab_text(&["log", "inspect", &path], "");
    result.unwrap();
    assert!(
        out.contains("line 3, time_s: the time column does not increase"),
        "{out}"
    );
    assert!(!out.contains("line 0"), "{out}");
}

/// A control period that is not a whole number of the log's samples is rounded, and the replay
/// says so; one shorter than a sample, or outside the run definition's range, is refused in the
/// run definition's words.
#[test]
fn a_period_is_rounded_to_whole_log_samples_or_refused_as_the_run_definition_says() {
    let replay = |period: &str| {
        common::cutlab_text(
            &[
                "log",
                "replay",
                EXPORT,
                "--current",
                "S_Strom [A]",
                "--controller",
                "pi",
                "--target-a",
                "10",
                "--period-s",
                period,
            ],
            "",
        )
    };
    // The export samples every 0.06 s: 0.1 s is 1.67 samples, run as 2.
    let (result, out) = replay("0.1");
    result.unwrap();
    assert!(out.contains("control periods of 0.12 s"), "{out}");
    assert!(
        out.contains("the control period 0.1 s is rounded to 0.12 s, 2 samples of 0.06 s"),
        "{out}"
    );
    let (result, _) = replay("0.02");
    let e = result.unwrap_err();
    assert!(
        e.contains("--period-s: 0.02 s is shorter than one sample of the machine (0.06 s)"),
        "{e}"
    );
    // Beyond the run definition's range, as `cutlab sim --period-s` says it: a 69 s log was
    // replayed in one period before.
    let (result, _) = replay("1000");
    assert_eq!(
        result.unwrap_err(),
        "--period-s: 1000 s is outside 0.001–2 s"
    );
}
