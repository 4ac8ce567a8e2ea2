//! An imported fuzzy engine as the loop's controller (`fuzzy-engine`): the same trace as paper
//! 002's built-in controller when the engine is paper 002's own table, saved in the configuration
//! JSON and the URL, refused with the reader's message when it is bad, run from the command line,
//! and held by the safety envelope like every controller.
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use cutlab::closed_loop::config::RunConfiguration;
use cutlab::closed_loop::definition::RunSpec;
use cutlab::closed_loop::lab::{simulate, RunResult};
use cutlab::closed_loop::paper_defaults::preset_controller;
use cutlab::control::fuzzy::rules::{paper_002_engine, RuleBase};
use cutlab::control::fuzzy::{fis, fll};
use cutlab::control::law::ControlInput;
use cutlab::control::registry::{
    ControllerConfig, ControllerKind, RunContext, PAPER_002_DEFUZZIFIER,
};
use cutlab::plant::Preset;

#[cfg(feature = "cli")]
mod common;

/// Paper 002's dynamics table as `cutlab fuzzy export --rules dynamics --defuzzifier
/// weighted-average` writes it: the engine an engineer would export and bring back.
fn exported_dynamics_fll() -> String {
    fll::write(&paper_002_engine(&RuleBase::Dynamics.table(), PAPER_002_DEFUZZIFIER).unwrap())
}

/// `preset`'s run with the `fuzzy-engine` controller on `engine_text`, every parameter at the
/// preset's fuzzy defaults.
fn engine_spec(preset: Preset, engine_text: &str) -> RunSpec {
    let mut spec = RunSpec::new(preset, ControllerKind::FuzzyEngine);
    spec.controller.set_engine(engine_text).unwrap();
    spec
}

/// Every number of two traces, bit for bit (NaN equal to NaN), with the first difference named.
fn assert_same_bits(a: &RunResult, b: &RunResult, what: &str) {
    let bits = |r: &RunResult| -> Vec<u64> {
        let rows = serde_json::to_value(&r.trace.rows).unwrap();
        let mut out: Vec<u64> = r.trace.terms.iter().map(|v| v.to_bits()).collect();
        for row in rows.as_array().unwrap() {
            for value in row.as_object().unwrap().values() {
                out.push(match value {
                    serde_json::Value::Number(n) => n.as_f64().unwrap().to_bits(),
                    serde_json::Value::Bool(b) => u64::from(*b),
                    _ => u64::MAX, // NaN is written as null
                });
            }
        }
        out
    };
    assert_eq!(a.trace.rows.len(), b.trace.rows.len(), "{what}: rows");
    let (x, y) = (bits(a), bits(b));
    if let Some(i) = x.iter().zip(&y).position(|(p, q)| p != q) {
        panic!(
            "{what}: value {i} differs: {} vs {}",
            f64::from_bits(x[i]),
            f64::from_bits(y[i])
        );
    }
    assert_eq!(a.trace.events, b.trace.events, "{what}: events");
}

/// Paper 002's dynamics table, exported as FLL and imported again, runs as the built-in
/// `fuzzy-dynamics` controller: the controller is the same code on both (the built-in's
/// universes are [−6, 6], where the mapping onto an engine's universes is k_e·E computed by the
/// same expressions), and the FLL round trip keeps every term, rule and setting but one.
///
/// That one is fuzzylite's firing threshold: an engine read from a file fires a rule above 1e-6,
/// as fuzzylite does, the built-in above 0. Where no rule's activation falls in (0, 1e-6] the two
/// give the same bits; where one does, the imported engine leaves out rules of total weight at
/// most 4·1e-6 (four rules fire at a point of two overlapping triangle partitions) from a
/// weighted average whose weights add up to at least 0.5 (on such a partition each input's
/// largest degree is at least 0.5) over levels 12 apart: U moves by at most 1e-4, the override by
/// at most 1e-4/6 of the output range. A closed loop amplifies such a step through the
/// envelope's whole-percent quantisation, so the runs are compared in two ways: closed loop, bit
/// for bit, on presets where no rule fires that weakly, and step by step on paper 002's own preset,
/// where one does, by feeding both controllers the built-in run's inputs.
#[test]
fn paper_002s_dynamics_table_imported_runs_as_the_built_in_controller() {
    let text = exported_dynamics_fll();
    for preset in [Preset::KimStepDoc, Preset::ManeeratDoc2] {
        let built_in = simulate(&RunSpec::new(preset, ControllerKind::FuzzyDynamics)).unwrap();
        let imported = simulate(&engine_spec(preset, &text)).unwrap();
        assert!(imported.trace.rows.len() > 50, "{}", preset.name());
        assert_same_bits(&built_in, &imported, preset.name());
        assert_eq!(built_in.metrics, imported.metrics, "{}", preset.name());
    }
    // Step by step on the built-in's run of paper 002's preset.
    let preset = Preset::LiuCurrentStep;
    let built_in_spec = RunSpec::new(preset, ControllerKind::FuzzyDynamics);
    let run = simulate(&built_in_spec).unwrap();
    let context = RunContext {
        target_force_n: run.settings.target_force_n,
        control_period_s: run.settings.control_period_s,
        amps_per_newton: f64::NAN,
    };
    let mut built_in = built_in_spec.controller.build(&context).unwrap();
    let imported_config = engine_spec(preset, &text).controller;
    let mut imported = imported_config.build(&context).unwrap();
    let output_range_pct = imported_config.get("output_range_pct").unwrap();
    let (mut same, mut weak) = (0, 0);
    for row in &run.trace.rows {
        let input = ControlInput {
            time_s: row.time_s,
            dt_s: run.settings.control_period_s,
            force_n: row.force_est_n,
            target_force_n: row.target_force_n,
            programmed_feed_mm_min: row.programmed_feed_mm_min,
            applied_override_pct: row.applied_override_pct,
            time_since_start_s: row.time_s,
        };
        let (a, b) = (built_in.step(&input), imported.step(&input));
        let fires_weakly = built_in
            .rule_activations()
            .is_some_and(|acts| acts.iter().any(|w| *w > 0.0 && *w <= 1e-6));
        if fires_weakly {
            weak += 1;
            assert!(
                (a - b).abs() <= 1e-4 / 6.0 * output_range_pct,
                "{} s: {a} vs {b}",
                row.time_s
            );
        } else {
            assert_eq!(a.to_bits(), b.to_bits(), "{} s: {a} vs {b}", row.time_s);
            same += 1;
        }
    }
    assert!(
        same > 500 && weak > 0,
        "{same} equal, {weak} with a weak rule"
    );
    // The comparison can fail: the experience table, imported the same way, runs another trace.
    let experience = fll::write(
        &paper_002_engine(&RuleBase::Experience.table(), PAPER_002_DEFUZZIFIER).unwrap(),
    );
    let built_in = simulate(&RunSpec::new(
        Preset::KimStepDoc,
        ControllerKind::FuzzyDynamics,
    ))
    .unwrap();
    let other = simulate(&engine_spec(Preset::KimStepDoc, &experience)).unwrap();
    assert_ne!(built_in.trace.terms, other.trace.terms);
}

/// Until an engine is imported, `fuzzy-engine` runs paper 002's dynamics table (so every
/// listing of the controllers can run it).
#[test]
fn the_engine_before_any_import_is_paper_002s_dynamics_table() {
    let c = ControllerConfig::new(ControllerKind::FuzzyEngine);
    assert_eq!(c.engine_fll(), Some(exported_dynamics_fll().as_str()));
    assert_eq!(ControllerConfig::new(ControllerKind::Pi).engine_fll(), None);
    assert_eq!(
        ControllerKind::FuzzyEngine.params(),
        ControllerKind::FuzzyDynamics.params()
    );
}

/// A small engine on universes of its own (not [−6, 6]), a centroid Mamdani: E on [0, 10],
/// EC on [−1, 1], U on [0, 20] (10 is no change).
const SHIFTED: &str = "\
Engine: shifted
InputVariable: load
  enabled: true
  range: 0 10
  lock-range: false
  term: light Ramp 0 10
  term: heavy Ramp 10 0
InputVariable: trend
  enabled: true
  range: -1 1
  lock-range: false
  term: any Rectangle -1 1
OutputVariable: feed
  enabled: true
  range: 0 20
  lock-range: false
  aggregation: Maximum
  defuzzifier: Centroid 200
  default: nan
  lock-previous: false
  term: down Triangle 0 0 20
  term: up Triangle 0 20 20
RuleBlock: main
  enabled: true
  conjunction: Minimum
  disjunction: Maximum
  implication: Minimum
  activation: General
  rule: if load is light and trend is any then feed is up
  rule: if load is heavy then feed is down
";

/// On a run, the override's change is the engine's U mapped from its universe (the mapping of
/// E and EC is checked step by step in `control::fuzzy::controller`'s tests).
#[test]
fn an_engine_on_other_universes_runs_with_its_output_mapped_onto_the_override() {
    let mut spec = engine_spec(Preset::KimStepDoc, SHIFTED);
    spec.controller.set("output_range_pct", 30.0).unwrap();
    let run = simulate(&spec).unwrap();
    let names: Vec<_> = run.trace.term_names.iter().map(|(n, _)| *n).collect();
    assert_eq!(names, ["E (scaled)", "EC (scaled)", "U", "Δ override"]);
    let mut checked = 0;
    for (row, terms) in run
        .trace
        .rows
        .iter()
        .zip(run.trace.terms.chunks(names.len()))
    {
        let [e, ec, u, delta] = [terms[0], terms[1], terms[2], terms[3]];
        // All four 0: the state before the controller's first step.
        if !(row.armed && e.is_finite()) || terms.iter().all(|t| *t == 0.0) {
            continue;
        }
        assert!((0.0..=10.0).contains(&e), "E {e} outside its universe");
        assert!((-1.0..=1.0).contains(&ec), "EC {ec} outside its universe");
        // U on [0, 20]: centre 10, half-width 10, ±30 % at its edges.
        assert!(
            (delta - (u - 10.0) / 10.0 * 30.0).abs() < 1e-9,
            "{} s: Δ {delta} for U {u}",
            row.time_s
        );
        checked += 1;
    }
    assert!(checked > 20, "only {checked} periods checked");
    assert!(run.trace.completed);
}

#[test]
fn a_run_with_an_imported_engine_round_trips_through_the_configuration_json() {
    let mut spec = engine_spec(Preset::ManeeratDoc1, SHIFTED);
    spec.controller.set("error_range_pct", 55.0).unwrap();
    let saved = RunConfiguration::new(vec![spec.clone()], None);
    let json = saved.to_json();
    assert!(json.contains("\"engine\": \"Engine: shifted\\n"), "{json}");
    let back = RunConfiguration::from_json(&json).unwrap();
    assert_eq!(back, saved);
    assert_eq!(
        back.runs[0].controller.engine_fll(),
        spec.controller.engine_fll()
    );
    // Written as FLL whatever it was read from: a FIS engine in the file comes back as FLL.
    let fis_text = fis::write(&fll::parse(SHIFTED).unwrap()).unwrap();
    let from_fis = json.replace(
        &serde_json::to_string(spec.controller.engine_fll().unwrap()).unwrap(),
        &serde_json::to_string(&fis_text).unwrap(),
    );
    assert_ne!(from_fis, json);
    let read = RunConfiguration::from_json(&from_fis).unwrap();
    assert!(read.runs[0]
        .controller
        .engine_fll()
        .unwrap()
        .starts_with("Engine: shifted\n"));
    // And it runs the same loop.
    let a = simulate(&spec).unwrap();
    let b = simulate(&back.runs[0]).unwrap();
    assert_same_bits(&a, &b, "after the JSON round trip");
}

#[test]
fn a_run_with_an_imported_engine_round_trips_through_the_url() {
    let mut spec = engine_spec(Preset::KimStepDoc, SHIFTED);
    spec.controller.set("output_range_pct", 12.5).unwrap();
    let fll_text = spec.controller.engine_fll().unwrap();
    let value = fll::to_url_text(fll_text);
    // Only characters encodeURIComponent leaves as they are: the value costs its own length.
    assert!(
        value
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_.!~*'()".contains(c)),
        "{value}"
    );
    assert!(
        value.len() <= fll_text.len() + fll_text.len() / 20,
        "{}",
        value.len()
    );
    // The page reads the query back into a form: kind, parameters, engine.
    let query = [
        ("controller", spec.controller.kind().name().to_string()),
        ("output_range_pct", "12.5".to_string()),
        ("engine", value),
    ];
    let mut read = preset_controller(Preset::KimStepDoc, query[0].1.parse().unwrap());
    read.set_text(&format!("{}={}", query[1].0, query[1].1))
        .unwrap();
    read.set_engine(&fll::from_url_text(&query[2].1)).unwrap();
    assert_eq!(read, spec.controller);
    // A damaged link is an error, not another engine.
    let damaged = fll::to_url_text(fll_text).replacen("range*_0_10", "range*_10_0", 1);
    let e = read.set_engine(&fll::from_url_text(&damaged)).unwrap_err();
    assert!(e.to_string().starts_with("engine: "), "{e}");
}

#[test]
fn bad_engines_are_errors_with_the_readers_message() {
    let mut c = ControllerConfig::new(ControllerKind::FuzzyEngine);
    let before = c.clone();
    // Unreadable: the reader's line.
    let e = c
        .set_engine("Engine: broken\nInputVariable: a\n  range: 0 one\n")
        .unwrap_err();
    assert!(e.to_string().starts_with("engine: line 3"), "{e}");
    // Readable, but not two inputs and one output.
    let one_input = SHIFTED
        .replace("InputVariable: trend", "OutputVariable: trend")
        .replace("trend is any", "load is light");
    let e = c.set_engine(&one_input).unwrap_err().to_string();
    assert!(
        e.contains("needs 2 inputs (E, then EC) and 1 output"),
        "{e}"
    );
    let e = c.set_engine("").unwrap_err().to_string();
    assert!(e.starts_with("engine: "), "{e}");
    // The configuration keeps its engine after a refusal.
    assert_eq!(c, before);
    // Only fuzzy-engine takes an engine.
    let e = ControllerConfig::new(ControllerKind::FuzzyDynamics)
        .set_engine(SHIFTED)
        .unwrap_err();
    assert!(e.to_string().contains("\"fuzzy-engine\""), "{e}");
    // In a saved configuration the message names the run.
    let json = RunConfiguration::new(
        vec![RunSpec::new(
            Preset::KimStepDoc,
            ControllerKind::FuzzyDynamics,
        )],
        None,
    )
    .to_json()
    .replace(
        "\"kind\": \"fuzzy-dynamics\"",
        "\"kind\": \"fuzzy-engine\", \"engine\": \"Engine: x\"",
    );
    let e = RunConfiguration::from_json(&json).unwrap_err().to_string();
    assert!(
        e.starts_with("controller: engine: the engine has no output variable"),
        "{e}"
    );
    assert!(e.contains(" line "), "{e}");
}

/// The envelope sits after the imported engine as after every controller: an engine that always
/// asks for more feed (every rule concludes "up") never takes the override past the envelope's
/// limits (its maximum, the cutter's chip load) or its rate.
#[test]
fn the_safety_envelope_holds_an_engine_that_always_asks_for_more() {
    let greedy = SHIFTED.replace("then feed is down", "then feed is up");
    let mut spec = engine_spec(Preset::KimStepDoc, &greedy);
    spec.controller.set("output_range_pct", 255.0).unwrap();
    let run = simulate(&spec).unwrap();
    let envelope = run.settings.envelope;
    let period_s = run.settings.control_period_s;
    // The engine asked for far more than it got.
    let held_back = run
        .trace
        .rows
        .iter()
        .filter(|r| r.requested_override_pct > r.override_pct + 50.0)
        .count();
    assert!(held_back > 100, "{held_back}");
    let mut previous: Option<f64> = None;
    for row in &run.trace.rows {
        assert!(
            row.override_pct <= envelope.max_override_pct + 1e-9,
            "{row:?}"
        );
        if let Some(p) = previous {
            let step = row.override_pct - p;
            assert!(
                step <= envelope.max_rate_pct_per_s * period_s + 1.0,
                "{step} at {}",
                row.time_s
            );
        }
        previous = Some(row.override_pct);
    }
    // The chip-load window of the cutter caps it below the envelope's maximum here.
    let highest = run
        .trace
        .rows
        .iter()
        .map(|r| r.override_pct)
        .fold(0.0, f64::max);
    assert!(highest < envelope.max_override_pct, "{highest}");
}

/// `--fuzzy-engine FILE` on the command line: `sim` runs it (the controller is implied), `compare`
/// gives it to its fuzzy-engine entries, a bad file is one line naming it, and an engine no
/// controller runs is a mistake.
#[cfg(feature = "cli")]
#[test]
fn the_command_line_runs_an_engine_file() {
    let dir = std::env::temp_dir().join(format!("cutlab-engine-loop-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let fll_path = dir.join("dynamics.fll");
    std::fs::write(&fll_path, exported_dynamics_fll()).unwrap();
    let fll_path = fll_path.to_str().unwrap();
    let metrics = |args: &[&str]| -> Vec<serde_json::Value> {
        let all = [args, &["--no-references", "--json"]].concat();
        let (result, out) = common::cutlab_text(&all, "");
        result.unwrap_or_else(|e| panic!("{all:?}: {e}"));
        let entries: Vec<serde_json::Value> = serde_json::from_str(&out).unwrap();
        entries.into_iter().map(|e| e["metrics"].clone()).collect()
    };
    let both = metrics(&[
        "compare",
        "--scenario",
        "kim-step-doc",
        "--controllers",
        "fuzzy-dynamics,fuzzy-engine",
        "--fuzzy-engine",
        fll_path,
    ]);
    assert_eq!(both.len(), 2);
    assert_eq!(both[0], both[1]);
    let (result, out) = common::cutlab_text(
        &[
            "sim",
            "--scenario",
            "liu-current-step",
            "--fuzzy-engine",
            fll_path,
            "--no-references",
        ],
        "",
    );
    result.unwrap();
    assert!(
        out.contains("fuzzy-engine") && out.contains("Cycle time (s)"),
        "{out}"
    );
    let bad = dir.join("bad.fll");
    std::fs::write(&bad, "Engine: x\nInputVariable: a\n  range: 0 one\n").unwrap();
    let bad = bad.to_str().unwrap();
    let (result, _) = common::cutlab_text(
        &["sim", "--scenario", "kim-step-doc", "--fuzzy-engine", bad],
        "",
    );
    let e = result.unwrap_err();
    assert!(
        e.starts_with(&format!("--fuzzy-engine {bad}: engine: line 3")),
        "{e}"
    );
    let (result, _) = common::cutlab_text(
        &[
            "compare",
            "--scenario",
            "kim-step-doc",
            "--controllers",
            "pi,fixed",
            "--fuzzy-engine",
            fll_path,
        ],
        "",
    );
    let e = result.unwrap_err();
    assert!(e.contains("no controller runs it"), "{e}");
    let (result, _) = common::cutlab_text(
        &[
            "sim",
            "--scenario",
            "kim-step-doc",
            "--fuzzy-engine",
            "/nonexistent/x.fll",
        ],
        "",
    );
    assert!(result
        .unwrap_err()
        .starts_with("--fuzzy-engine: cannot read"));
}

/// An engine from fuzzylite's corpus (read where Debian's package puts it; the files stay out of
/// this repository) runs as the controller: linear_tip_calculator's tip rises with both its
/// inputs, as the feed should with E (a light cut) and EC (a cut getting lighter).
#[test]
fn an_engine_from_fuzzylites_corpus_runs_as_the_controller() {
    let path = "/usr/share/doc/fuzzylite/examples/takagi-sugeno/octave/linear_tip_calculator.fll";
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| {
        panic!("{path}: {e}; install Debian's fuzzylite package (scripts/setup test does)")
    });
    let run = simulate(&engine_spec(Preset::KimStepDoc, &text)).unwrap();
    assert!(run.trace.completed);
    assert!(run.metrics.peak_force_n.is_finite());
    let fixed = simulate(&RunSpec::new(Preset::KimStepDoc, ControllerKind::Fixed)).unwrap();
    // It acts: the override it commands is not the fixed feed's.
    assert!(run
        .trace
        .rows
        .iter()
        .zip(&fixed.trace.rows)
        .any(|(a, b)| (a.override_pct - b.override_pct).abs() > 1.0));
}

/// The browser runs Simulate's and Compare's loops in computation workers; the engine travels
/// inside the run's definition, so a worker runs the engine the page holds.
#[test]
fn a_run_with_an_imported_engine_reaches_a_computation_worker_whole() {
    use cutlab::closed_loop::transfer::{JobRequest, RunRequest};
    let spec = engine_spec(Preset::KimStepDoc, SHIFTED);
    let request = JobRequest::Runs(RunRequest::new(vec![spec.clone()], &[]));
    let back = JobRequest::from_json(&request.to_json().unwrap()).unwrap();
    let JobRequest::Runs(runs) = &back else {
        panic!("a run request read back as {back:?}");
    };
    assert_eq!(
        runs.specs[0].controller.engine_fll(),
        spec.controller.engine_fll()
    );
    assert_eq!(back, request);
}
