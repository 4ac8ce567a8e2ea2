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
    let commands = "commands: calibrate, compare, controllers, device, filter, force, fuzzy, host, protocol, scenarios, \
                    sim, spectrum";
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
