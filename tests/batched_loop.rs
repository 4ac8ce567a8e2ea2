//! Runs of one plant stepped together (`closed_loop::batch`) equal each run alone bit for bit,
//! natively and under wasm: different controllers, a fixed override, another seed, and a run
//! that cannot start, in one batch.
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use cutlab::closed_loop::batch::{run_batch, LabBatch};
use cutlab::closed_loop::definition::RunSpec;
use cutlab::closed_loop::lab::{simulate, RunResult};
use cutlab::control::registry::ControllerKind;
use cutlab::plant::Preset;
use cutlab::work::Work;

/// Every number of a result, trace rows included, as text that tells any two bit patterns apart
/// (Rust's `Debug` of an `f64` is its shortest round-trip form; NaN compares equal here, unlike
/// `==`).
fn exact(result: &RunResult) -> String {
    format!("{result:?}")
}

/// A batch of `preset`'s runs: two adaptive controllers, a fixed 70 % override and the first
/// controller at another seed (its own teach cut).
fn batch_of(preset: Preset) -> Vec<RunSpec> {
    let mut fixed = RunSpec::new(preset, ControllerKind::Fixed);
    fixed.controller.set("override_pct", 70.0).unwrap();
    let mut reseeded = RunSpec::new(preset, ControllerKind::FuzzyDynamics);
    reseeded.seed = 7;
    vec![
        RunSpec::new(preset, ControllerKind::FuzzyDynamics),
        RunSpec::new(preset, ControllerKind::Pi),
        fixed,
        reseeded,
    ]
}

fn assert_batch_equals_runs_alone(specs: &[RunSpec]) {
    let together = run_batch(specs);
    assert_eq!(together.len(), specs.len());
    for (spec, outcome) in specs.iter().zip(&together) {
        let alone = simulate(spec).unwrap();
        let batched = outcome.as_ref().unwrap();
        assert!(!alone.trace.rows.is_empty());
        assert_eq!(
            exact(batched),
            exact(&alone),
            "{} with {} (seed {})",
            spec.preset.name(),
            spec.controller.kind().name(),
            spec.seed
        );
    }
}

#[test]
fn a_batch_on_kim_step_doc_equals_each_run_alone() {
    assert_batch_equals_runs_alone(&batch_of(Preset::KimStepDoc));
}

#[test]
fn a_batch_on_maneerat_doc_2_equals_each_run_alone() {
    assert_batch_equals_runs_alone(&batch_of(Preset::ManeeratDoc2));
}

#[test]
fn a_run_that_cannot_start_fails_alone_and_the_others_finish() {
    let mut bad = RunSpec::new(Preset::WangBrakeBench, ControllerKind::Pi);
    bad.settings.control_period_s = Some(1e-9);
    let specs = vec![
        RunSpec::new(Preset::WangBrakeBench, ControllerKind::Fixed),
        bad.clone(),
        RunSpec::new(Preset::WangBrakeBench, ControllerKind::Pi),
    ];
    let together = run_batch(&specs);
    assert_eq!(
        together[1].as_ref().unwrap_err().to_string(),
        simulate(&bad).unwrap_err().to_string()
    );
    assert_eq!(
        exact(together[2].as_ref().unwrap()),
        exact(&simulate(&specs[2]).unwrap())
    );
}

#[test]
fn a_batch_advanced_in_small_pieces_gives_the_same_results() {
    let specs = batch_of(Preset::WangBrakeBench);
    let mut batch = LabBatch::new(specs.clone());
    assert!(batch.finish().is_err(), "finished before it ran");
    let mut rounds = 0;
    while !batch.advance(3).unwrap() {
        let progress = batch.progress().fraction;
        assert!((0.0..=1.0).contains(&progress), "{progress}");
        rounds += 1;
    }
    assert!(rounds > 10, "{rounds} rounds: not advanced in pieces");
    let pieces = batch.finish().unwrap();
    for (piece, whole) in pieces.iter().zip(run_batch(&specs)) {
        assert_eq!(exact(piece.as_ref().unwrap()), exact(&whole.unwrap()));
    }
}
