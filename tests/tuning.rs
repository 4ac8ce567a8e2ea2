//! Tuning on the closed loop: a sweep's table is the individual runs', the search improves on the
//! defaults within the bounds, and bad ranges are refused with their reason.
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use cutlab::closed_loop::lab::{simulate, RunSpec};
use cutlab::control::registry::{ControllerConfig, ControllerKind};
use cutlab::plant::Preset;
use cutlab::tuning::nelder_mead::NelderMead;
use cutlab::tuning::{Objective, ParamRange, Tuner, TuningError, TuningProblem};

fn problem(kind: ControllerKind, ranges: &[&str], presets: &[Preset]) -> TuningProblem {
    TuningProblem {
        controller: ControllerConfig::new(kind),
        params: ranges
            .iter()
            .map(|r| ParamRange::parse(r).unwrap())
            .collect(),
        scenarios: presets.iter().map(|p| RunSpec::new(*p, kind)).collect(),
        objective: Objective::default(),
    }
}

#[test]
fn a_sweeps_table_equals_the_individual_runs() {
    let tuner = Tuner::new(problem(
        ControllerKind::Threshold,
        &["kp=0.2:1.0"],
        &[Preset::ManeeratDoc1],
    ))
    .unwrap();
    let table = tuner.sweep(3).unwrap();
    assert_eq!(
        table.iter().map(|e| e.values[0]).collect::<Vec<_>>(),
        vec![0.2, 0.6, 1.0]
    );
    for row in &table {
        let mut spec = RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Threshold);
        spec.controller.set("kp", row.values[0]).unwrap();
        let alone = simulate(&spec).unwrap();
        assert_eq!(row.metrics[0], alone.metrics, "kp = {}", row.values[0]);
        let nominal = Preset::ManeeratDoc1.summary().nominal_duration_s;
        assert_eq!(row.cost, Objective::default().cost(&alone.metrics, nominal));
    }
}

#[test]
fn the_search_improves_on_the_defaults_inside_the_bounds() {
    let tuner = Tuner::new(problem(
        ControllerKind::Pi,
        &["kp=0.05:1.5", "ki_per_s=0.1:5"],
        &[Preset::ManeeratDoc1],
    ))
    .unwrap();
    let default = tuner.evaluate(&[0.3, 1.0]).unwrap();
    let tuned = tuner
        .tune(&NelderMead {
            max_evaluations: 16,
            ..NelderMead::default()
        })
        .unwrap();
    assert!(
        tuned.best.cost <= default.cost,
        "{} vs {}",
        tuned.best.cost,
        default.cost
    );
    assert!(tuned.evaluations.len() >= 3 && tuned.evaluations.len() <= 16 + 3);
    for e in &tuned.evaluations {
        assert!((0.05..=1.5).contains(&e.values[0]) && (0.1..=5.0).contains(&e.values[1]));
    }
    // The front holds the best cycle time and the best force error of all evaluations.
    let front: Vec<_> = tuned
        .pareto
        .iter()
        .map(|&i| &tuned.evaluations[i])
        .collect();
    let fastest = tuned
        .evaluations
        .iter()
        .map(|e| e.cycle_time_s)
        .fold(f64::INFINITY, f64::min);
    let closest = tuned
        .evaluations
        .iter()
        .map(|e| e.force_error_pct)
        .fold(f64::INFINITY, f64::min);
    assert_eq!(front.first().unwrap().cycle_time_s, fastest);
    assert_eq!(front.last().unwrap().force_error_pct, closest);
}

#[test]
fn ranges_outside_the_controllers_are_refused_with_the_reason() {
    let e = Tuner::new(problem(
        ControllerKind::Pi,
        &["kp=0:50"],
        &[Preset::ManeeratDoc1],
    ))
    .err()
    .unwrap();
    assert!(matches!(e, TuningError::Param(_)));
    assert!(e.to_string().contains("kp = 50 is outside"), "{e}");
    let e = Tuner::new(problem(
        ControllerKind::Pi,
        &["gain=0:1"],
        &[Preset::ManeeratDoc1],
    ))
    .err()
    .unwrap();
    assert!(e.to_string().contains("has no parameter \"gain\""), "{e}");
    let e = Tuner::new(problem(ControllerKind::Pi, &[], &[Preset::ManeeratDoc1]))
        .err()
        .unwrap();
    assert!(e.to_string().contains("at least one parameter"), "{e}");
    let tuner = Tuner::new(problem(
        ControllerKind::Pi,
        &["kp=0.1:1", "ki_per_s=0.1:1"],
        &[Preset::ManeeratDoc1],
    ))
    .unwrap();
    assert!(tuner
        .sweep(21)
        .unwrap_err()
        .to_string()
        .contains("more than 400 points"));
}

#[test]
fn a_teach_in_proposes_the_papers_target_and_its_reference_current() {
    // Paper 002 states its target as 25 A of spindle current: the teach-in gives it back.
    let liu = cutlab::tuning::teach_in(&RunSpec::new(
        Preset::LiuCurrentStep,
        ControllerKind::FuzzyDynamics,
    ))
    .unwrap();
    assert!(
        (liu.reference_current_a - 25.0).abs() < 0.025,
        "{}",
        liu.reference_current_a
    );
    // kim-step-doc's target is the mean force at DOC 2.5 mm; the noise of its estimate sets a
    // gap of the order of paper 003's 0.4 A (about 24 % of that target).
    let kim =
        cutlab::tuning::teach_in(&RunSpec::new(Preset::KimStepDoc, ControllerKind::Threshold))
            .unwrap();
    assert!(
        (kim.proposed_target_n - 372.0).abs() < 1.0,
        "{}",
        kim.proposed_target_n
    );
    assert!(kim.estimate_noise_n > 0.0);
    assert!(
        (10.0..30.0).contains(&kim.proposed_gap_pct),
        "{}",
        kim.proposed_gap_pct
    );
    assert!(kim.force_at_full_override_n > kim.proposed_target_n);
}

#[test]
fn tuning_in_pieces_gives_the_tuners_result() {
    use cutlab::tuning::{TuningMode, TuningWork};
    use cutlab::work::Work;
    let make = || {
        problem(
            ControllerKind::Pi,
            &["kp=0.05:1.5"],
            &[Preset::ManeeratDoc1],
        )
    };
    let search = NelderMead {
        max_evaluations: 6,
        ..NelderMead::default()
    };
    let whole = Tuner::new(make()).unwrap().tune(&search).unwrap();
    let mut pieces = TuningWork::new(make(), TuningMode::Search(search)).unwrap();
    let mut steps = 0;
    while !pieces.advance(7).unwrap() {
        steps += 1;
        let p = pieces.progress();
        assert!((0.0..=1.0).contains(&p.fraction), "{p:?}");
    }
    assert!(steps > 10, "{steps} pieces");
    assert_eq!(pieces.finish().unwrap(), whole);

    let sweep = Tuner::new(make()).unwrap().sweep(3).unwrap();
    let swept = TuningWork::new(make(), TuningMode::Sweep(3))
        .unwrap()
        .run_to_end()
        .unwrap();
    assert_eq!(swept.evaluations, sweep);
}
