//! `cutlab fuzzy export` and `cutlab fuzzy eval`, in-process.
#![cfg(feature = "cli")]
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;

fn cutlab(args: &[&str], stdin: &str) -> (Result<(), String>, String) {
    common::cutlab_text(args, stdin)
}

#[test]
fn exported_engine_evaluates_line_by_line_at_full_precision() {
    let dir = std::env::temp_dir().join(format!("cutlab-fuzzy-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("dynamics.fll");
    let (result, fll) = cutlab(&["fuzzy", "export", "--rules", "dynamics"], "");
    result.unwrap();
    assert!(fll.contains("rule: if E is NB and EC is NB then U is NB"));
    std::fs::write(&path, &fll).unwrap();
    let (result, out) = cutlab(
        &["fuzzy", "eval", "--fll", path.to_str().unwrap()],
        "# E EC\n0 0\n6 6\n\n2.5 -1.3\n",
    );
    result.unwrap();
    let values: Vec<f64> = out.lines().map(|l| l.parse().unwrap()).collect();
    assert_eq!(values.len(), 3);
    assert!(values[0].abs() < 1e-12);
    // Fully PB: the centroid of the right-angled PB triangle (4, 6, 6) is 16/3.
    assert!((values[1] - 16.0 / 3.0).abs() < 1e-12);
    // Debian's fuzzylite 6 at resolution 10⁶ gives 0.755600815 for (2.5, -1.3).
    assert!((values[2] - 0.755_600_815).abs() < 1e-8);

    let (result, _) = cutlab(
        &["fuzzy", "eval", "--fll", path.to_str().unwrap()],
        "1 2\n1 two\n",
    );
    assert_eq!(
        result.unwrap_err(),
        "stdin line 2: cannot parse \"two\" as a number"
    );
    let (result, _) = cutlab(&["fuzzy", "eval", "--fll", path.to_str().unwrap()], "1\n");
    assert!(result
        .unwrap_err()
        .starts_with("stdin line 1: 1 values, the engine has 2 inputs"));

    let broken = dir.join("broken.fll");
    std::fs::write(
        &broken,
        fll.replace("term: PB Triangle 4 6 6", "term: PB Blob 6 1"),
    )
    .unwrap();
    let (result, _) = cutlab(&["fuzzy", "eval", "--fll", broken.to_str().unwrap()], "");
    let message = result.unwrap_err();
    assert!(message.contains(": line "), "{message}");
    assert!(
        message.contains("shape Blob is not one of fuzzylite's terms"),
        "{message}"
    );
    std::fs::remove_dir_all(dir).ok();
}

/// Stray words after `fuzzy eval` and `fuzzy export` were silently ignored; they are errors.
#[test]
fn stray_arguments_after_fuzzy_subcommands_are_refused() {
    let fll = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/www/data/paper-002-dynamics.fll"
    );
    let (result, _) = cutlab(&["fuzzy", "eval", "--fll", fll, "0.5"], "0 0\n");
    let e = result.unwrap_err();
    assert!(e.starts_with("unexpected argument \"0.5\""), "{e}");
    let (result, _) = cutlab(&["fuzzy", "export", "--rules", "dynamics", "extra"], "");
    assert_eq!(result.unwrap_err(), "unexpected argument \"extra\"");
    assert!(cutlab(&["fuzzy", "eval", "--fll", fll], "0 0\n").0.is_ok());
}

#[test]
fn an_input_that_is_not_finite_is_refused_not_answered_with_the_default() {
    let dir = std::env::temp_dir().join(format!("cutlab-fuzzy-nan-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("experience.fll");
    let (result, fll) = cutlab(&["fuzzy", "export", "--rules", "experience"], "");
    result.unwrap();
    std::fs::write(&path, &fll).unwrap();
    for (input, word) in [
        ("NaN 0\n", "NaN"),
        ("0 inf\n", "inf"),
        ("-infinity 1\n", "-infinity"),
    ] {
        let (result, out) = cutlab(&["fuzzy", "eval", "--fll", path.to_str().unwrap()], input);
        assert_eq!(
            result.unwrap_err(),
            format!("stdin line 1: \"{word}\" is not a finite input"),
            "{out}"
        );
    }
    // A 10 000-character word is cut in the message.
    let long = "x".repeat(10_000);
    let (result, _) = cutlab(
        &["fuzzy", "eval", "--fll", path.to_str().unwrap()],
        &format!("{long} 0\n"),
    );
    let e = result.unwrap_err();
    assert!(e.len() < 120 && e.contains("(10000 characters)"), "{e}");
}

/// paper 002's engine with its rules taken out: it loaded, and a controller running it held the
/// feed fixed without a word. Every reader of a file refuses it at load, naming the empty block.
#[test]
fn an_engine_without_rules_is_refused_at_load_naming_the_empty_rule_block() {
    let dir = std::env::temp_dir().join(format!("cutlab-fuzzy-norules-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("norules.fll");
    let (result, fll) = cutlab(&["fuzzy", "export", "--rules", "experience"], "");
    result.unwrap();
    let rule_less: String = fll
        .lines()
        .filter(|l| !l.trim_start().starts_with("rule:"))
        .map(|l| format!("{l}\n"))
        .collect();
    assert!(rule_less.len() < fll.len());
    let block_line = 1 + rule_less
        .lines()
        .position(|l| l.starts_with("RuleBlock:"))
        .unwrap();
    std::fs::write(&path, &rule_less).unwrap();
    let file = path.to_str().unwrap();
    let why = format!(
        "line {block_line}: the rule block \"rules\" is empty: a fuzzy engine without rules \
         holds every output at its default whatever its inputs"
    );
    let (result, out) = cutlab(&["fuzzy", "eval", "--fll", file], "0 0\n");
    let e = result.unwrap_err();
    assert!(e.starts_with(&format!("{file}: {why}")), "{e}");
    assert!(out.is_empty(), "{out}");
    let (result, _) = cutlab(
        &[
            "sim",
            "--scenario",
            "maneerat-doc-1",
            "--fuzzy-engine",
            file,
            "--no-references",
        ],
        "",
    );
    let e = result.unwrap_err();
    assert!(
        e.starts_with(&format!("--fuzzy-engine {file}: engine: {why}")),
        "{e}"
    );
    std::fs::remove_dir_all(dir).ok();
}
