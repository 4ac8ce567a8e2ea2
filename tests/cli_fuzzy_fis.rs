//! `cutlab fuzzy eval --fis` and `cutlab fuzzy export --fis / --engine`, in-process.
#![cfg(feature = "cli")]
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;

fn cutlab(args: &[&str], stdin: &str) -> (Result<(), String>, String) {
    common::cutlab_text(args, stdin)
}

#[test]
fn an_fll_engine_exported_as_fis_evaluates_the_same_through_either_file() {
    let dir = std::env::temp_dir().join(format!("cutlab-fuzzy-fis-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // Paper 002's engine with its inputs free (FIS has no lock-range for inputs).
    let (result, fll) = cutlab(&["fuzzy", "export", "--rules", "experience"], "");
    result.unwrap();
    let fll_path = dir.join("experience.fll");
    std::fs::write(
        &fll_path,
        fll.replace("lock-range: true", "lock-range: false"),
    )
    .unwrap();
    let (result, fis) = cutlab(
        &[
            "fuzzy",
            "export",
            "--engine",
            fll_path.to_str().unwrap(),
            "--fis",
        ],
        "",
    );
    result.unwrap();
    assert!(fis.starts_with("[System]\nName='paper002'"), "{fis}");
    assert!(fis.contains("MF1='NB':'trimf',[-6 -6 -4]"), "{fis}");
    let fis_path = dir.join("experience.fis");
    std::fs::write(&fis_path, &fis).unwrap();
    let points = "0 0\n2.5 -1.3\n-6 6\n";
    let (a, via_fll) = cutlab(
        &["fuzzy", "eval", "--fll", fll_path.to_str().unwrap()],
        points,
    );
    let (b, via_fis) = cutlab(
        &["fuzzy", "eval", "--fis", fis_path.to_str().unwrap()],
        points,
    );
    a.unwrap();
    b.unwrap();
    assert_eq!(via_fll, via_fis);
    assert_eq!(via_fll.lines().count(), 3);
    // And back to FLL from the FIS file, found by its extension.
    let (result, again) = cutlab(
        &["fuzzy", "export", "--engine", fis_path.to_str().unwrap()],
        "",
    );
    result.unwrap();
    assert!(
        again.contains("rule: if E is NB and EC is NB then U is NB"),
        "{again}"
    );

    // Paper 002's own engine locks its inputs' range: refused, saying so.
    let (result, _) = cutlab(&["fuzzy", "export", "--rules", "dynamics", "--fis"], "");
    assert_eq!(
        result.unwrap_err(),
        "FIS cannot express this engine: input E locks its range (a value outside it is taken at its nearest end), which FIS cannot say; write it as FLL"
    );
    // A broken FIS names its line.
    let broken = dir.join("broken.fis");
    std::fs::write(&broken, fis.replace("(1) : 1", "(1) : 7")).unwrap();
    let (result, _) = cutlab(&["fuzzy", "eval", "--fis", broken.to_str().unwrap()], "");
    let e = result.unwrap_err();
    assert!(
        e.contains(": line ") && e.contains("the connective is 1 (and) or 2 (or)"),
        "{e}"
    );
    let (result, _) = cutlab(&["fuzzy", "eval"], "");
    assert_eq!(
        result.unwrap_err(),
        "missing required option --fll or --fis"
    );
    std::fs::remove_dir_all(dir).ok();
}
