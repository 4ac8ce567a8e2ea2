//! `cutlab log` and `cutlab calibrate` on logs a reviewer found wanting: a file without data
//! rows, forces that are negative.
#![cfg(feature = "cli")]
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;

fn scratch(name: &str, text: &str) -> String {
    let dir = std::env::temp_dir().join(format!("cutlab-cli-log-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path.to_string_lossy().into_owned()
}

#[test]
fn every_log_command_refuses_a_file_without_data_rows_with_one_message() {
    for (name, text, says) in [
        ("empty.csv", "", "the file is empty"),
        (
            "headeronly.csv",
            "a,b,c\n",
            "line 1: no data rows: a header of 3 columns (\"a, b, c\")",
        ),
    ] {
        let path = scratch(name, text);
        for command in [
            &["log", "inspect", path.as_str()][..],
            &["log", "analyse", path.as_str(), "--column", "a"],
            &[
                "log",
                "replay",
                path.as_str(),
                "--controller",
                "pi",
                "--current",
                "a",
            ],
            &["calibrate", path.as_str()],
        ] {
            let (result, _) = common::cutlab_text(command, "");
            let error = result.unwrap_err();
            assert!(
                error.contains(&format!("{path}: {says}")),
                "{command:?}: {error}"
            );
        }
    }
}

/// A period log: current 5 A + 0.01 A/N · F at 1000 rpm, forces 10…400 N.
fn period_log(force: impl Fn(usize, f64) -> f64) -> String {
    let mut csv = String::from("time_s,spindle_current_rms_a,spindle_speed_rpm,force_n\n");
    for i in 0..40 {
        let f = 10.0 * (i + 1) as f64;
        csv += &format!(
            "{},{},1000,{}\n",
            0.06 * i as f64,
            5.0 + 0.01 * f,
            force(i, f)
        );
    }
    csv
}

#[test]
fn calibrate_says_which_rows_it_left_out_for_a_negative_force() {
    let path = scratch(
        "five_negative.csv",
        &period_log(|i, f| if (10..15).contains(&i) { -1e9 } else { f }),
    );
    let (result, out) = common::cutlab_text(&["calibrate", &path], "");
    result.unwrap();
    assert!(out.contains("35 rows with force"), "{out}");
    // The header is line 1: row 10 is line 12.
    assert!(
        out.contains(
            "note: 5 rows with a negative force left out (the first on line 12, down to -1e9 N)"
        ),
        "{out}"
    );
}

#[test]
fn calibrate_says_why_a_force_column_all_negative_fits_nothing() {
    let path = scratch("flipped.csv", &period_log(|_, f| -f));
    let (result, _) = common::cutlab_text(&["calibrate", &path], "");
    let error = result.unwrap_err();
    assert!(
        error.contains("no row has a positive force (the force_n column): 40 of its 40 rows are negative (from line 2, down to -400 N)"),
        "{error}"
    );
    assert!(
        error.contains("a dynamometer's sign flipped: negate the column"),
        "{error}"
    );
    assert!(!error.contains("usable samples"), "{error}");
}
