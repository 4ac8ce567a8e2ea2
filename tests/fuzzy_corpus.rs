//! fuzzylite's own example corpus, read where Debian's `fuzzylite` package puts it: every engine
//! that ships a `.fld` file of fuzzylite's outputs is evaluated by cutlab on the same inputs, in
//! the same order (lock-previous carries across rows), and compared output by output; every
//! `.fis` file is imported and evaluated like fuzzylite evaluates it.
//!
//! The files are LGPL-3+ (parts GPL-3): they stay out of this repository, and `scripts/setup
//! test` installs the package (`apt-get install -y fuzzylite`). Without it these tests fail
//! saying so.
//!
//! **Tolerance.** Where cutlab defuzzifies in closed form (Centroid, MeanOfMaximum of a
//! piecewise-linear aggregate: [`Engine::exact_implication`]) and fuzzylite samples the universe
//! at `resolution` cell midpoints, the two differ by sampling error: at most one cell, h = (max −
//! min) / resolution, for the mean of maximum (each end of the plateau is found within h/2) and,
//! for the centroid, far less (a cell holding a kink is off by a fraction of h² in area), so h
//! bounds both. Everywhere else cutlab computes what fuzzylite computes (the same samples, the
//! same weighted sums), and the outputs differ only by the 9 decimals the `.fld` prints and the
//! rounding of the sums: 1e-8·max(1, |value|). NaN must match NaN.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};

use cutlab::control::fuzzy::engine::Engine;
use cutlab::control::fuzzy::{fis, fll};

const CORPUS: &str = "/usr/share/doc/fuzzylite/examples";

/// The corpus directory, or a failure that says how to install it.
fn corpus() -> PathBuf {
    let dir = PathBuf::from(CORPUS);
    assert!(
        dir.is_dir(),
        "fuzzylite's example corpus is not at {CORPUS}: install Debian's fuzzylite package \
         (scripts/setup test does it; by hand: apt-get install -y fuzzylite, as root)"
    );
    dir
}

/// Every file under `dir` whose name ends with `extension`, sorted.
fn files(dir: &Path, extension: &str) -> Vec<PathBuf> {
    let mut found = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == extension) {
                found.push(path);
            }
        }
    }
    found.sort();
    found
}

/// A `.fld` file: its header's names and its rows of numbers.
fn read_fld(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines().filter(|l| !l.trim().is_empty());
    let header = lines.next().unwrap();
    let names = header
        .trim_start_matches('#')
        .split_whitespace()
        .map(String::from)
        .collect();
    let rows = lines
        .map(|l| {
            l.split_whitespace()
                .map(|w| match w {
                    "nan" | "-nan" => f64::NAN,
                    "inf" => f64::INFINITY,
                    "-inf" => f64::NEG_INFINITY,
                    w => w.parse().unwrap(),
                })
                .collect()
        })
        .collect();
    (names, rows)
}

/// How far cutlab's output `k` may lie from fuzzylite's (see the module's documentation).
fn tolerance(engine: &Engine, k: usize, expected: f64) -> f64 {
    let var = &engine.outputs()[k];
    if engine.exact_implication(k).is_some() {
        (var.max - var.min) / var.resolution as f64
    } else {
        1e-8 * expected.abs().max(1.0)
    }
}

/// Evaluates `engine` on `rows` (inputs first, then fuzzylite's outputs) in order and returns the
/// mismatches, described.
fn mismatches(name: &str, engine: &mut Engine, rows: &[Vec<f64>]) -> Vec<String> {
    let n_in = engine.inputs().len();
    let n_out = engine.outputs().len();
    let mut out = vec![0.0; n_out];
    let mut bad = Vec::new();
    for (r, row) in rows.iter().enumerate() {
        assert_eq!(
            row.len(),
            n_in + n_out,
            "{name}: row {r} has {} values",
            row.len()
        );
        engine.evaluate(&row[..n_in], &mut out);
        for k in 0..n_out {
            let (got, expected) = (out[k], row[n_in + k]);
            let ok = if expected.is_nan() {
                got.is_nan()
            } else {
                (got - expected).abs() <= tolerance(engine, k, expected)
            };
            if !ok {
                bad.push(format!(
                    "{name} row {} ({:?}): {} = {got}, fuzzylite {expected} (tolerance {:e})",
                    r + 1,
                    &row[..n_in],
                    engine.outputs()[k].name,
                    tolerance(engine, k, expected)
                ));
            }
        }
    }
    bad
}

/// The number of engines in the corpus that ship an `.fld`: docs/fuzzy.md states it.
const ENGINES_WITH_FLD: usize = 18;

#[test]
fn every_engine_of_fuzzylites_corpus_matches_its_fld_outputs() {
    let dir = corpus();
    let flds = files(&dir, "fld");
    assert_eq!(flds.len(), ENGINES_WITH_FLD, "{flds:?}");
    let mut failures = Vec::new();
    let mut compared = 0;
    for fld in &flds {
        let fll_path = fld.with_extension("fll");
        let name = fll_path.strip_prefix(&dir).unwrap().display().to_string();
        let text = std::fs::read_to_string(&fll_path).unwrap();
        let mut engine = match fll::parse(&text) {
            Ok(e) => e,
            Err(e) => {
                failures.push(format!("{name}: {e}"));
                continue;
            }
        };
        let (names, rows) = read_fld(fld);
        let declared: Vec<&str> = engine
            .inputs()
            .iter()
            .map(|v| v.name.as_str())
            .chain(engine.outputs().iter().map(|v| v.name.as_str()))
            .collect();
        assert_eq!(names, declared, "{name}: the .fld's columns");
        // docs/fuzzy.md: "the .fld's 1,024 inputs".
        assert_eq!(rows.len(), 1024, "{name}");
        compared += rows.len() * engine.outputs().len();
        let bad = mismatches(&name, &mut engine, &rows);
        failures.extend(bad.into_iter().take(3));
    }
    assert!(
        failures.is_empty(),
        "{} problems:\n{}",
        failures.len(),
        failures.join("\n")
    );
    assert!(
        compared >= ENGINES_WITH_FLD * 1024,
        "{compared} values compared"
    );
}

/// Runs Debian's `fuzzylite` CLI on `engine_path` (format `format`) at the inputs of `rows` and
/// returns its outputs, one row per input row.
fn fuzzylite_outputs(engine_path: &Path, format: &str, inputs: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let dir = std::env::temp_dir().join(format!("cutlab-corpus-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let stem = engine_path
        .file_stem()
        .unwrap()
        .to_string_lossy()
        .to_string();
    let points = dir.join(format!("{stem}-{format}-inputs.fld"));
    let text: Vec<String> = inputs
        .iter()
        .map(|r| {
            r.iter()
                .map(|v| format!("{v:.12}"))
                .collect::<Vec<_>>()
                .join(" ")
        })
        .collect();
    std::fs::write(&points, text.join("\n") + "\n").unwrap();
    let out = std::process::Command::new("fuzzylite")
        .args(["-i"])
        .arg(engine_path)
        .args([
            "-if",
            format,
            "-of",
            "fld",
            "-decimals",
            "12",
            "-dheader",
            "false",
        ])
        .args(["-dinputs", "false", "-d"])
        .arg(&points)
        .output()
        .expect("fuzzylite's CLI (apt-get install -y fuzzylite)");
    assert!(
        out.status.success(),
        "fuzzylite failed on {}: {}",
        engine_path.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            l.split_whitespace()
                .map(|w| {
                    if w.contains("nan") {
                        f64::NAN
                    } else {
                        w.parse().unwrap()
                    }
                })
                .collect()
        })
        .collect()
}

/// The number of `.fis` files in the corpus: docs/fuzzy.md states it.
const FIS_FILES: usize = 29;

/// The `.fis` files fuzzylite exported from chained engines: FIS cannot name an output in a
/// condition, so fuzzylite wrote those rules with every input code 0 (its own importer then loads
/// them as rules that never fire). cutlab refuses such a rule, naming its line, rather than drop
/// it: these are the files, and the line each is refused at.
const LOSSY_FIS: [(&str, &str); 3] = [
    ("mamdani/Laundry.fis", "line 50: no input is named"),
    (
        "mamdani/SimpleDimmerChained.fis",
        "line 44: no input is named",
    ),
    (
        "mamdani/SimpleDimmerInverse.fis",
        "line 44: no input is named",
    ),
];

#[test]
fn every_fis_file_of_the_corpus_imports_and_evaluates_as_fuzzylite_evaluates_it() {
    let dir = corpus();
    let fis_files = files(&dir, "fis");
    assert_eq!(fis_files.len(), FIS_FILES, "{fis_files:?}");
    let mut failures = Vec::new();
    let mut evaluated = 0;
    for path in &fis_files {
        let name = path.strip_prefix(&dir).unwrap().display().to_string();
        let text = std::fs::read_to_string(path).unwrap();
        let lossy = LOSSY_FIS.iter().find(|(file, _)| *file == name);
        let mut engine = match (fis::parse(&text), lossy) {
            (Ok(e), None) => e,
            (Err(e), Some((_, expected))) if e.to_string().starts_with(expected) => continue,
            (Ok(_), Some(_)) => {
                failures.push(format!("{name}: loads, but its chained rules are lost"));
                continue;
            }
            (Err(e), _) => {
                failures.push(format!("{name}: {e}"));
                continue;
            }
        };
        // The inputs: the twin's .fld rows where there is one, else a grid over the ranges.
        let fld = path.with_extension("fld");
        let n_in = engine.inputs().len();
        let inputs: Vec<Vec<f64>> = if fld.exists() {
            read_fld(&fld)
                .1
                .into_iter()
                .map(|r| r[..n_in].to_vec())
                .collect()
        } else {
            (0..=200)
                .map(|k| {
                    engine
                        .inputs()
                        .iter()
                        .enumerate()
                        .map(|(i, v)| {
                            let t = ((k * (7 + 3 * i)) % 201) as f64 / 200.0;
                            v.min + t * (v.max - v.min)
                        })
                        .collect()
                })
                .collect()
        };
        let expected = fuzzylite_outputs(path, "fis", &inputs);
        let rows: Vec<Vec<f64>> = inputs
            .iter()
            .zip(&expected)
            .map(|(i, o)| i.iter().chain(o).copied().collect())
            .collect();
        failures.extend(mismatches(&name, &mut engine, &rows).into_iter().take(3));
        evaluated += 1;
    }
    assert!(
        failures.is_empty(),
        "{} problems:\n{}",
        failures.len(),
        failures.join("\n")
    );
    // docs/fuzzy.md: "26 import and evaluate as fuzzylite evaluates them".
    assert_eq!(evaluated, 26);
}

/// The corpus's FLL engines that cutlab's FIS exporter refuses, with the reason's start: FIS has
/// no way to say these (docs/fuzzy.md lists them).
const NOT_FIS: [(&str, &str); 7] = [
    (
        "hybrid/ObstacleAvoidance.fll",
        "FIS cannot express this engine: it has 2 rule blocks",
    ),
    (
        "hybrid/tipper.fll",
        "FIS cannot express this engine: it has 2 rule blocks",
    ),
    (
        "mamdani/Laundry.fll",
        "FIS cannot express this engine: rule 5 names an output",
    ),
    (
        "mamdani/SimpleDimmerChained.fll",
        "FIS cannot express this engine: rule 4 names an output",
    ),
    (
        "original/mamdani/Laundry.fll",
        "FIS cannot express this engine: rule 5 names an output",
    ),
    (
        "mamdani/SimpleDimmerInverse.fll",
        "FIS cannot express this engine: rule 4 names an output",
    ),
    (
        "original/mamdani/SimpleDimmerInverse.fll",
        "FIS cannot express this engine: rule 4 names an output",
    ),
];

/// Every FLL engine of the corpus written as FIS by cutlab and read back is the same engine,
/// but for what FIS cannot carry and which means the same or is not used here: the integral
/// defuzzifiers' resolution (it reads back as fuzzylite's default of 100) and a weighted
/// defuzzifier's type that the terms decide anyway (it reads back as Automatic). The engines
/// FIS cannot express are refused saying why.
#[test]
fn every_fll_engine_of_the_corpus_survives_cutlabs_fis_export_or_is_refused_saying_why() {
    let dir = corpus();
    let mut failures = Vec::new();
    let mut round_trips = 0;
    for path in files(&dir, "fll") {
        let name = path.strip_prefix(&dir).unwrap().display().to_string();
        let engine = fll::parse(&std::fs::read_to_string(&path).unwrap()).unwrap();
        let refused = NOT_FIS.iter().find(|(file, _)| *file == name);
        let text = match (fis::write(&engine), refused) {
            (Ok(text), None) => text,
            (Err(e), Some((_, why))) if e.to_string().starts_with(why) => continue,
            (result, _) => {
                failures.push(format!("{name}: {:?}", result.map(|_| "exported")));
                continue;
            }
        };
        let back = match fis::parse(&text) {
            Ok(back) => back,
            Err(e) => {
                failures.push(format!("{name}: the exported FIS does not read back: {e}"));
                continue;
            }
        };
        let mut outputs = back.outputs().to_vec();
        for (mine, theirs) in outputs.iter_mut().zip(engine.outputs()) {
            mine.resolution = theirs.resolution;
            // An explicit type that its terms leave no choice about reads back as Automatic.
            mine.weighted_kind = theirs.weighted_kind;
        }
        // Compared as printed: a NaN default is the same default, where == says it is not.
        let same = |a: String, b: String| a == b;
        if !same(
            format!("{:?}", back.inputs()),
            format!("{:?}", engine.inputs()),
        ) || !same(format!("{outputs:?}"), format!("{:?}", engine.outputs()))
            || !same(
                format!("{:?}", back.rules()),
                format!("{:?}", engine.rules()),
            )
        {
            failures.push(format!("{name}: reads back as another engine"));
        }
        round_trips += 1;
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    // docs/fuzzy.md: "All 31 .fll engines … 24 read back as the same engine".
    assert_eq!((round_trips, NOT_FIS.len()), (24, 7));
}
