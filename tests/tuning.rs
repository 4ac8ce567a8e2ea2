//! Tuning on the closed loop: a sweep's table is the individual runs' (whatever the threads), the
//! search improves on where it starts within its budget and bounds, each scenario keeps its own
//! paper values, bad ranges are refused with their reason, and a teach-in proposes what values
//! computed outside cutlab say it should (tests/reference/tuning, made by
//! scripts/reference/tuning_reference.py).
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use cutlab::closed_loop::definition::RunSpec;
use cutlab::closed_loop::lab::simulate;
use cutlab::closed_loop::settings::DEFAULT_TARGET_FRACTION;
use cutlab::control::registry::{ControllerConfig, ControllerKind};
use cutlab::plant::Preset;
use cutlab::tuning::nelder_mead::NelderMead;
use cutlab::tuning::teach_in::{teach_in_calibration, teach_in_log, LogTeachIn, TargetBasis};
use cutlab::tuning::{Objective, ParamRange, Report, Tuner, TuningError, TuningProblem};

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
fn the_search_improves_on_where_it_starts_within_its_budget_and_bounds() {
    // Start in a corner of the box, away from the defaults (0.3, 1): the first vertex is the
    // start, so only a real improvement makes the best strictly cheaper than it.
    let mut p = problem(
        ControllerKind::Pi,
        &["kp=0.05:1.5", "ki_per_s=0.1:5"],
        &[Preset::ManeeratDoc1],
    );
    p.controller.set("kp", 1.5).unwrap();
    p.controller.set("ki_per_s", 5.0).unwrap();
    let tuner = Tuner::new(p).unwrap();
    let start = tuner.evaluate(&[1.5, 5.0]).unwrap();
    let mut reported = Vec::new();
    let tuned = tuner
        .tune_reporting(
            &NelderMead {
                max_evaluations: 16,
                ..NelderMead::default()
            },
            &mut |r| {
                if let Report::Evaluated {
                    done,
                    total,
                    at_most,
                    ..
                } = r
                {
                    reported.push((*done, *total, *at_most));
                }
            },
        )
        .unwrap();
    assert_eq!(
        tuned.evaluations[0], start,
        "the search starts at the start"
    );
    assert!(
        tuned.best.cost < start.cost,
        "{} vs {}",
        tuned.best.cost,
        start.cost
    );
    assert_ne!(tuned.best.values, start.values);
    // The budget holds exactly: 16 evaluations unless the tolerances were met first.
    assert!(tuned.evaluations.len() <= 16, "{}", tuned.evaluations.len());
    if !tuned.converged {
        assert_eq!(tuned.evaluations.len(), 16);
    }
    assert_eq!(
        reported,
        (1..=tuned.evaluations.len())
            .map(|done| (done, 16, true))
            .collect::<Vec<_>>()
    );
    for e in &tuned.evaluations {
        assert!((0.05..=1.5).contains(&e.values[0]) && (0.1..=5.0).contains(&e.values[1]));
    }
    // The front holds the best cycle time and the best force error of all evaluations, as the
    // tables print them (evaluations that read alike are judged alike).
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
    let shown = cutlab::input::three_significant;
    assert_eq!(shown(front.first().unwrap().cycle_time_s), shown(fastest));
    assert_eq!(shown(front.last().unwrap().force_error_pct), shown(closest));
}

#[test]
fn a_sweep_on_one_thread_equals_the_sweep_on_several() {
    let make = || {
        problem(
            ControllerKind::Threshold,
            &["kp=0.2:1.0", "gap_pct=5:20"],
            &[Preset::ManeeratDoc1, Preset::ManeeratDoc2],
        )
    };
    let mut order = Vec::new();
    let serial = Tuner::with_threads(make(), 1, &mut |_| {})
        .unwrap()
        .sweep(2)
        .unwrap();
    let parallel = Tuner::with_threads(make(), 3, &mut |_| {})
        .unwrap()
        .sweep_reporting(2, &mut |r| {
            if let Report::Evaluated {
                done,
                total,
                evaluation,
                ..
            } = r
            {
                order.push((*done, *total, evaluation.values.clone()));
            }
        })
        .unwrap();
    // Bit for bit, in grid order (Debug text compares NaN with NaN too).
    assert_eq!(format!("{parallel:?}"), format!("{serial:?}"));
    // Every point is reported once, counted 1…4, whatever order the threads finished in.
    assert_eq!(
        order.iter().map(|o| (o.0, o.1)).collect::<Vec<_>>(),
        vec![(1, 4), (2, 4), (3, 4), (4, 4)]
    );
    let mut points: Vec<_> = order.into_iter().map(|o| o.2).collect();
    points.sort_by(|a, b| a.partial_cmp(b).unwrap());
    assert_eq!(
        points,
        serial.iter().map(|e| e.values.clone()).collect::<Vec<_>>()
    );
}

#[test]
fn a_search_on_one_thread_equals_the_search_on_several_running_ahead() {
    // On several threads the idle ones run ahead of the search (points it may ask next); the
    // search, its evaluations and their reports are those of one thread, bit for bit.
    let make = || {
        problem(
            ControllerKind::Pi,
            &["kp=0.05:1.5", "ki_per_s=0.1:5"],
            &[Preset::ManeeratDoc1, Preset::ManeeratSecondOrder],
        )
    };
    let search = NelderMead {
        max_evaluations: 14,
        ..NelderMead::default()
    };
    let tune = |threads: usize| {
        let mut reports = Vec::new();
        let tuned = Tuner::with_threads(make(), threads, &mut |_| {})
            .unwrap()
            .tune_reporting(&search, &mut |r| {
                if let Report::Evaluated {
                    done, evaluation, ..
                } = r
                {
                    reports.push((*done, evaluation.values.clone()));
                }
            })
            .unwrap();
        (tuned, reports)
    };
    let (serial, serial_reports) = tune(1);
    let (parallel, parallel_reports) = tune(3);
    assert_eq!(format!("{parallel:?}"), format!("{serial:?}"));
    assert_eq!(parallel_reports, serial_reports);
    assert_eq!(serial_reports.len(), serial.evaluations.len());
    assert!(serial_reports.iter().enumerate().all(|(i, r)| r.0 == i + 1));
}

#[test]
fn each_scenario_keeps_its_own_paper_values() {
    // Paper 002's output range (100 %) belongs to its own preset only; maneerat-doc-1 comes
    // first and keeps the registry's 20 %.
    let kind = ControllerKind::FuzzyDynamics;
    let p = TuningProblem {
        controller: RunSpec::new(Preset::ManeeratDoc1, kind).controller,
        params: vec![ParamRange::parse("error_range_pct=80:80").unwrap()],
        scenarios: vec![
            RunSpec::new(Preset::ManeeratDoc1, kind),
            RunSpec::new(Preset::LiuCurrentStep, kind),
        ],
        objective: Objective::default(),
    };
    let table = Tuner::new(p).unwrap().sweep(1).unwrap();
    for (i, preset) in [Preset::ManeeratDoc1, Preset::LiuCurrentStep]
        .into_iter()
        .enumerate()
    {
        let mut spec = RunSpec::new(preset, kind);
        spec.controller.set("error_range_pct", 80.0).unwrap();
        let alone = simulate(&spec).unwrap();
        // Debug text compares every bit, and NaN (a step without depths) equal to NaN.
        assert_eq!(
            format!("{:?}", table[0].metrics[i]),
            format!("{:?}", alone.metrics),
            "{}",
            preset.name()
        );
    }
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
    let e = Tuner::new(problem(
        ControllerKind::Pi,
        &["kp=0:1", "ki_per_s=0:1", "kp=0.2:0.5"],
        &[Preset::ManeeratDoc1],
    ))
    .err()
    .unwrap();
    assert_eq!(
        e.to_string(),
        "kp is given twice (0:1 and 0.2:0.5); give each parameter once"
    );
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

const REFERENCE: &str = include_str!("reference/tuning/teach_in.json");
const TEACH_LOG: &[u8] = include_bytes!("reference/tuning/teach_cut_log.csv");

fn reference() -> serde_json::Value {
    serde_json::from_str(REFERENCE).unwrap()
}

fn close(actual: f64, expected: &serde_json::Value, relative: f64, what: &str) {
    let expected = expected.as_f64().unwrap();
    assert!(
        (actual - expected).abs() <= relative * expected.abs(),
        "{what}: {actual} vs {expected}"
    );
}

#[test]
fn a_simulated_teach_in_proposes_from_the_force_it_measured() {
    // The mean resultant at the programmed feed in closed form (Altintas) is what the teach cut
    // must find at 100 % override; the proposal is 80 % of what it found, not the paper's target.
    let reference = reference();
    for preset in [Preset::ManeeratDoc1, Preset::ManeeratDoc2] {
        let expected = &reference["mills"][preset.name()];
        let t = cutlab::tuning::teach_in(&RunSpec::new(preset, ControllerKind::Threshold)).unwrap();
        let (learned, p) = (&t.learned, &t.proposal);
        close(
            learned.force_at_full_override_n,
            &expected["force_at_full_override_n"],
            0.01,
            preset.name(),
        );
        close(p.target_n, &expected["target_n"], 0.01, preset.name());
        assert_eq!(
            p.target_n,
            DEFAULT_TARGET_FRACTION * learned.force_at_full_override_n
        );
        assert_eq!(p.basis, TargetBasis::Fraction);
        // The paper's own target is shown beside it, and differs from it.
        let paper = t.paper.unwrap();
        assert_eq!(paper.target_n, preset.target_force_n().unwrap());
        assert!(
            (paper.target_n - p.target_n).abs() > 20.0,
            "{paper:?} vs {p:?}"
        );
        let line = learned.line.unwrap();
        assert!(p.calibrated_force_n.min <= p.target_n && p.target_n <= p.calibrated_force_n.max);
        assert_eq!(p.reference_current_a, line.current_a(p.target_n));
    }
    // Paper 002 states its target as I_ref = 25 A: shown as such for comparison.
    let liu = cutlab::tuning::teach_in(&RunSpec::new(
        Preset::LiuCurrentStep,
        ControllerKind::FuzzyDynamics,
    ))
    .unwrap();
    let paper = liu.paper.unwrap();
    assert!(paper.what.contains("I_ref = 25 A"), "{}", paper.what);
    assert!(
        (paper.reference_current_a - 25.0).abs() < 0.025,
        "{paper:?}"
    );
    assert_eq!(
        liu.proposal.target_n,
        DEFAULT_TARGET_FRACTION * liu.learned.force_at_full_override_n
    );
}

#[test]
fn a_logged_teach_cut_proposes_what_pandas_and_numpy_compute() {
    let expected = &reference()["log"];
    let log = cutlab::log::load(TEACH_LOG, None).unwrap();
    let map: Vec<(String, String)> = [
        ("spindle_current_rms_a", "S_Strom [A]"),
        ("spindle_speed_rpm", "S_Drehzahl (rpm)"),
        ("force_n", "Kraft [N]"),
        ("override_pct", "Override [%]"),
    ]
    .iter()
    .map(|(r, c)| (r.to_string(), c.to_string()))
    .collect();
    let logged = teach_in_log(
        &log,
        "teach_cut_log.csv",
        LogTeachIn {
            map: &map,
            geometry: None,
            gear_change_rpm: 900.0,
        },
    )
    .unwrap();
    let t = &logged.teach_in;
    let (learned, p) = (&t.learned, &t.proposal);
    let line = learned.line.unwrap();
    let tight = 1e-9;
    close(
        learned.force_at_full_override_n,
        &expected["force_at_full_override_n"],
        tight,
        "force at 100 %",
    );
    close(
        learned.at.spindle_rpm,
        &expected["spindle_rpm"],
        tight,
        "speed",
    );
    close(
        line.idle_current_a,
        &expected["idle_current_a"],
        tight,
        "idle",
    );
    close(
        line.sensitivity_a_per_n,
        &expected["sensitivity_a_per_n"],
        tight,
        "sensitivity",
    );
    close(
        line.residual_std_n,
        &expected["residual_std_n"],
        1e-6,
        "residual",
    );
    close(
        p.calibrated_force_n.min,
        &expected["calibrated_force_n"][0],
        tight,
        "lowest covered force",
    );
    close(
        p.calibrated_force_n.max,
        &expected["calibrated_force_n"][1],
        tight,
        "highest covered force",
    );
    close(p.target_n, &expected["target_n"], tight, "target");
    close(
        p.reference_current_a,
        &expected["reference_current_a"],
        tight,
        "reference current",
    );
    close(p.gap_pct, &expected["gap_pct"], 1e-6, "gap");
    assert_eq!(
        learned.periods,
        expected["rows_fitted"].as_u64().unwrap() as usize
    );
    assert!(t.paper.is_none() && t.source.contains("teach_cut_log.csv"));

    // Without the override column every cutting row counts, and the note says so.
    let without: Vec<_> = map
        .iter()
        .filter(|(r, _)| r != "override_pct")
        .cloned()
        .collect();
    let all_rows = teach_in_log(
        &log,
        "teach_cut_log.csv",
        LogTeachIn {
            map: &without,
            geometry: None,
            gear_change_rpm: 900.0,
        },
    )
    .unwrap();
    assert!(
        all_rows.notes[0].contains("no override_pct column"),
        "{:?}",
        all_rows.notes
    );
    assert_ne!(
        all_rows.teach_in.learned.force_at_full_override_n,
        learned.force_at_full_override_n
    );
    // A log without a force and without a cut model says what is missing, naming the file.
    let e = teach_in_log(
        &log,
        "teach_cut_log.csv",
        LogTeachIn {
            map: &map[..2],
            geometry: None,
            gear_change_rpm: 900.0,
        },
    )
    .unwrap_err();
    assert!(
        e.to_string()
            .starts_with("teach_cut_log.csv: no \"force_n\" column"),
        "{e}"
    );
    // A file without data rows is refused by the reader, with what it held instead; a log built
    // by hand without rows finds nothing to fit and says so, naming the file (no panic).
    let header_only = cutlab::log::load(b"a,b,c\n", None).unwrap_err();
    assert!(
        header_only.to_string().contains("no data rows"),
        "{header_only}"
    );
    let mut empty = log.clone();
    empty.rows = 0;
    empty.row_lines.clear();
    for column in &mut empty.columns {
        column.values.clear();
        column.labels.clear();
    }
    let how = LogTeachIn {
        map: &map,
        geometry: None,
        gear_change_rpm: 900.0,
    };
    let e = teach_in_log(&empty, "empty.csv", how).unwrap_err();
    assert!(e.to_string().starts_with("empty.csv: "), "{e}");
}

#[test]
fn a_saved_calibration_proposes_what_its_teach_cut_did() {
    // What `cutlab host --save-calibration` writes after a teach cut over the link feeds the
    // same proposal as the teach cut itself.
    use cutlab::closed_loop::calibration_file::CalibrationFile;
    let spec = RunSpec::new(Preset::KimStepDoc, ControllerKind::Threshold);
    let simulated = cutlab::tuning::teach_in(&spec).unwrap();
    let (_, calibration) = cutlab::closed_loop::lab::teach_cut_only(&spec).unwrap();
    let file = CalibrationFile::from_json(
        &CalibrationFile::new(calibration, "teach cut over the link on device-1").to_json(),
    )
    .unwrap();
    let saved = teach_in_calibration(&file, "kim.json", Some(&spec)).unwrap();
    assert_eq!(saved.proposal, simulated.proposal);
    assert_eq!(saved.paper, simulated.paper);
    assert_eq!(
        saved.source,
        "calibration kim.json (teach cut over the link on device-1)"
    );
    // Without the program, a spindle calibration is read at its most-sampled speed: kim's
    // program runs at one speed, so the proposal is the same.
    let alone = teach_in_calibration(&file, "kim.json", None).unwrap();
    assert!(
        (alone.learned.at.spindle_rpm - 1000.0).abs() < 10.0,
        "{:?}",
        alone.learned.at
    );
    assert!((alone.proposal.target_n - saved.proposal.target_n).abs() < 1e-9);
    assert!(alone.paper.is_none());
    // A feed-current calibration needs its program's feed.
    let bench = RunSpec::new(Preset::WangBrakeBench, ControllerKind::Threshold);
    let (_, calibration) = cutlab::closed_loop::lab::teach_cut_only(&bench).unwrap();
    let e = teach_in_calibration(&CalibrationFile::new(calibration, ""), "bench.json", None)
        .unwrap_err();
    assert!(
        e.to_string().contains("depends on the programmed feed"),
        "{e}"
    );
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

/// A plan's runs made by `workers` simulated workers, as the browser's pool makes them: every
/// run takes `duration(scenario)` units of a simulated clock, the first finished is told first,
/// and runs ahead of the search fill idle workers when `ahead`, the first of them failing.
/// Returns the outcome, the clock at the end, the most
/// runs out at once, the plan's runs ahead (made, used) and its count (done, in all).
fn run_plan(
    plan: &mut cutlab::tuning::TuningPlan,
    workers: usize,
    ahead: bool,
    duration: impl Fn(usize) -> u32,
    metrics_of: &mut impl FnMut(&RunSpec) -> cutlab::closed_loop::metrics::Metrics,
) -> (
    cutlab::tuning::Tuned,
    u32,
    usize,
    (usize, usize),
    (usize, usize),
) {
    use cutlab::tuning::PlannedRun;
    let mut clock = 0;
    let mut out: Vec<(u32, PlannedRun)> = Vec::new();
    let mut queue: std::collections::VecDeque<PlannedRun> = Default::default();
    let mut most_out = 0;
    let mut failed_ahead = false;
    loop {
        let idle = if queue.is_empty() {
            workers - out.len()
        } else {
            0
        };
        let runs = plan.next_runs(if ahead { idle } else { 0 }).unwrap();
        queue.extend(runs);
        while out.len() < workers {
            let Some(run) = queue.pop_front() else { break };
            out.push((clock + duration(run.id.scenario), run));
        }
        most_out = most_out.max(out.len());
        // The first to finish (the first sent of those finishing together).
        let Some(first) = (0..out.len()).min_by_key(|&i| out[i].0) else {
            break;
        };
        let (end, run) = out.remove(first);
        clock = end;
        // The first run ahead fails (a worker lost): taken back, as the page does, it is
        // made again if the search asks for its point.
        if run.ahead && !failed_ahead && plan.is_ahead(run.id) {
            failed_ahead = true;
            plan.forget(run.id);
            continue;
        }
        plan.tell(run.id, metrics_of(&run.spec));
    }
    assert!(plan.is_done());
    let (made, count) = (plan.runs_ahead(), plan.count());
    (plan.finish().unwrap(), clock, most_out, made, count)
}

#[test]
fn a_plan_told_runs_made_elsewhere_in_any_order_gives_the_tuning_works_result() {
    use cutlab::closed_loop::lab::{LabRuns, TeachKey};
    use cutlab::estimation::estimator::Calibration;
    use cutlab::tuning::{TuningMode, TuningPlan, TuningWork};
    use cutlab::work::Work;
    use std::collections::HashMap;
    let make = || {
        problem(
            ControllerKind::Pi,
            &["kp=0.05:1.5", "ki_per_s=0.1:5"],
            &[Preset::ManeeratDoc1, Preset::ManeeratDoc2],
        )
    };
    // As the browser's workers make them: the first point's runs with their own teach cuts,
    // every later run from the calibration of its scenario's teach cut. A run made before is
    // not made again (the runs are deterministic; this keeps the test short).
    let mut known: Vec<(TeachKey, Calibration)> = Vec::new();
    let mut made: HashMap<String, cutlab::closed_loop::metrics::Metrics> = HashMap::new();
    let mut metrics_of = |spec: &RunSpec| {
        let key = format!("{spec:?}");
        if let Some(metrics) = made.get(&key) {
            return metrics.clone();
        }
        let result = LabRuns::with_calibrations(vec![spec.clone()], known.clone())
            .run_to_end()
            .unwrap()
            .remove(0);
        let teach_key = TeachKey::of(spec).unwrap();
        if !known.iter().any(|(k, _)| *k == teach_key) {
            known.push((teach_key, result.calibration.clone()));
        }
        made.insert(key, result.metrics.clone());
        result.metrics.clone()
    };
    let search = NelderMead {
        max_evaluations: 16,
        ..NelderMead::default()
    };
    // maneerat-doc-1's runs take five times doc-2's, as kim-step-doc's take maneerat-doc-1's on
    // the Tune page: the worker with the short run waits unless it runs ahead.
    let duration = |scenario: usize| if scenario == 0 { 5 } else { 1 };
    for mode in [TuningMode::Search(search), TuningMode::Sweep(3)] {
        let expected = TuningWork::new(make(), mode).unwrap().run_to_end().unwrap();
        let mut clocks = Vec::new();
        for ahead in [false, true] {
            let mut plan = TuningPlan::new(make(), mode).unwrap();
            let (tuned, clock, most_out, (made_ahead, used), (done, total)) =
                run_plan(&mut plan, 2, ahead, duration, &mut metrics_of);
            assert_eq!(tuned, expected, "{mode:?}, ahead {ahead}");
            assert_eq!(done, expected.evaluations.len());
            assert!(done <= total);
            assert!(most_out <= 2);
            match mode {
                TuningMode::Search(_) if ahead => {
                    assert!(used > 0 && used <= made_ahead, "{used} of {made_ahead}");
                }
                _ => assert_eq!(made_ahead, 0, "{mode:?}, ahead {ahead}"),
            }
            clocks.push(clock);
        }
        // Runs ahead shorten a search (its workers wait less) and change nothing of a sweep.
        match mode {
            TuningMode::Search(_) => assert!(clocks[1] < clocks[0], "{clocks:?}"),
            TuningMode::Sweep(_) => assert_eq!(clocks[1], clocks[0]),
        }
    }
}
