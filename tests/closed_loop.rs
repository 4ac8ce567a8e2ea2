//! The closed loop on the papers' presets: every controller runs inside the safety envelope, the
//! metrics agree with a recomputation from the CSV trace, runs are deterministic, and the papers'
//! findings show up where the model can show them.
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use cutlab::closed_loop::definition::RunSpec;
use cutlab::closed_loop::lab::{simulate, LabRun, RunResult};
use cutlab::closed_loop::settings::OperatingPoint;
use cutlab::closed_loop::trace::write_csv;
use cutlab::control::registry::ControllerKind;
use cutlab::plant::Preset;
use cutlab::work::Work;

fn run(preset: Preset, controller: ControllerKind) -> RunResult {
    simulate(&RunSpec::new(preset, controller))
        .unwrap_or_else(|e| panic!("{} with {}: {e}", preset.name(), controller.name()))
}

/// The presets and controllers checked: all of them natively; under wasm (slower, and the same
/// code) one mill, the bond graph and the bench.
fn matrix() -> Vec<(Preset, ControllerKind)> {
    let presets: Vec<Preset> = if cfg!(target_arch = "wasm32") {
        vec![
            Preset::ManeeratDoc2,
            Preset::LiuCurrentStep,
            Preset::WangBrakeBench,
        ]
    } else {
        Preset::ALL.to_vec()
    };
    presets
        .into_iter()
        .flat_map(|p| ControllerKind::ALL.into_iter().map(move |k| (p, k)))
        .collect()
}

/// Inside the envelope: every command finite, in the band, rate-limited; on a mill inside the
/// chip-load window of its cutter and material; and no adaptive controller loads the tool more than
/// the fixed feed does (the entry hold: a controller released while the cutter engages would),
/// but for the settling band a controller may hold above the target when a load step arrives.
#[test]
fn every_controller_runs_on_every_preset_inside_the_envelope() {
    let mut fixed_peak_n = std::collections::HashMap::new();
    for (preset, kind) in matrix() {
        let r = run(preset, kind);
        let who = format!("{} / {}", preset.name(), kind.name());
        // ControllerKind::ALL begins with the fixed feed.
        if kind == ControllerKind::Fixed {
            fixed_peak_n.insert(preset, r.metrics.peak_force_n);
        } else {
            // A load step in mid-cut (paper 002's) meets each controller wherever its band
            // holds the force, up to the settling band above the target the fixed feed sits on:
            // its peak may be that much higher, and no more.
            let band = if preset.load_step_times_s().is_empty() {
                0.0
            } else {
                r.metrics.settling_band_pct / 100.0
            };
            let fixed = fixed_peak_n[&preset];
            assert!(
                r.metrics.peak_force_n <= fixed * (1.0 + band) + 1e-9,
                "{who}: peak force {} N above the fixed feed's {fixed} N (+{} % allowed)",
                r.metrics.peak_force_n,
                100.0 * band
            );
        }
        let spindle_rpm = OperatingPoint::of_preset(&RunSpec::new(preset, kind)).spindle_rpm;
        match r.settings.envelope.chip_load {
            Some(window) => {
                for row in r
                    .trace
                    .rows
                    .iter()
                    .filter(|r| r.programmed_feed_mm_min > 0.0)
                {
                    let per_tooth = window.feed_per_tooth_mm(
                        row.programmed_feed_mm_min,
                        spindle_rpm,
                        row.override_pct,
                    );
                    assert!(
                        per_tooth >= window.min_mm - 1e-9 && per_tooth <= window.max_mm + 1e-9,
                        "{who}: {per_tooth} mm per tooth outside {}–{} mm at {} s",
                        window.min_mm,
                        window.max_mm,
                        row.time_s
                    );
                }
            }
            None => assert!(
                preset.scenario_spec().is_none(),
                "{who}: a mill without a chip-load window"
            ),
        }
        assert!(
            r.trace.completed,
            "{who}: the program did not run to its end"
        );
        assert!(!r.trace.rows.is_empty(), "{who}: empty trace");
        let e = &r.settings.envelope;
        let step = e.resolution.step_pct();
        let dt = r.settings.control_period_s;
        let mut previous: Option<f64> = None;
        for row in &r.trace.rows {
            let u = row.override_pct;
            assert!(
                u.is_finite(),
                "{who}: non-finite override at {} s",
                row.time_s
            );
            assert!(
                u >= e.min_override_pct && u <= e.max_override_pct,
                "{who}: override {u} outside the envelope at {} s",
                row.time_s
            );
            if let Some(p) = previous {
                assert!(
                    (u - p).abs() <= e.max_rate_pct_per_s * dt + step + 1e-9,
                    "{who}: override jumped {p} → {u} at {} s",
                    row.time_s
                );
            }
            previous = Some(u);
        }
        let m = &r.metrics;
        for (name, v) in [
            ("cycle time", m.cycle_time_s),
            ("IAE", m.force_iae_n_s),
            ("peak force", m.peak_force_n),
            ("total variation", m.override_total_variation_pct),
        ] {
            assert!(v.is_finite() && v >= 0.0, "{who}: {name} = {v}");
        }
    }
}

/// Parses one numeric column of the CSV.
fn column(csv: &str, name: &str) -> Vec<f64> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let index = header.iter().position(|h| *h == name).unwrap();
    lines
        .map(|l| l.split(',').nth(index).unwrap().parse::<f64>().unwrap())
        .collect()
}

#[test]
fn metrics_equal_a_recomputation_from_the_csv_trace() {
    let r = run(Preset::KimStepDoc, ControllerKind::Threshold);
    let mut csv = Vec::new();
    write_csv(&r.trace, &mut csv).unwrap();
    let csv = String::from_utf8(csv).unwrap();
    let time = column(&csv, "time_s");
    let force = column(&csv, "force_n");
    let target = column(&csv, "target_force_n");
    let depth = column(&csv, "depth_mm");
    let width = column(&csv, "width_mm");
    let armed = column(&csv, "armed");
    let over = column(&csv, "override_pct");
    let mrr = column(&csv, "material_removal_mm3_s");
    let in_range = column(&csv, "estimate_in_range");
    let disagrees = column(&csv, "sensor_failure_predicted");
    let limit = r.settings.force_limit_n;

    // Each row stands for the interval since the previous one.
    let (mut iae, mut above, mut removed, mut controlled) = (0.0, 0.0, 0.0, 0.0);
    let (mut squared, mut relative, mut outside, mut disagreeing) = (0.0, 0.0, 0.0, 0.0);
    for i in 1..time.len() {
        let dt = time[i] - time[i - 1];
        removed += mrr[i] * dt;
        if force[i] > limit {
            above += dt;
        }
        if armed[i] == 1.0 && depth[i] > 0.0 && width[i] > 0.0 {
            let error = force[i] - target[i];
            iae += error.abs() * dt;
            squared += error * error * dt;
            relative += (error / target[i]).abs() * dt;
            controlled += dt;
            if in_range[i] == 0.0 {
                outside += dt;
            }
            if disagrees[i] == 1.0 {
                disagreeing += dt;
            }
        }
    }
    let changes = over.windows(2).filter(|w| w[1] != w[0]).count();
    let variation: f64 = over.windows(2).map(|w| (w[1] - w[0]).abs()).sum();
    let cycle = time[time.len() - 1] - time[0];
    let peak = force.iter().cloned().fold(0.0, f64::max);
    let m = &r.metrics;
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1.0);
    assert!(close(m.force_iae_n_s, iae), "{} vs {iae}", m.force_iae_n_s);
    assert!(close(m.controlled_cutting_time_s, controlled));
    assert!(close(m.time_above_limit_s, above));
    assert!(close(m.removed_volume_mm3, removed));
    assert!(close(m.peak_force_n, peak));
    assert_eq!(m.override_changes, changes);
    assert!(close(m.cycle_time_s, cycle));
    assert!(close(m.force_rms_error_n, (squared / controlled).sqrt()));
    assert!(close(
        m.force_mean_abs_error_pct,
        100.0 * relative / controlled
    ));
    assert!(close(m.override_total_variation_pct, variation));
    assert!(close(m.mean_material_removal_mm3_s, removed / cycle));
    assert!(close(m.time_outside_calibration_s, outside));
    assert!(close(m.time_sensor_failure_predicted_s, disagreeing));
}

#[test]
fn the_same_seed_gives_the_same_trace_and_another_seed_does_not() {
    let spec = RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Pi);
    let a = simulate(&spec).unwrap();
    let b = simulate(&spec).unwrap();
    assert_eq!(a.trace, b.trace);
    let mut other = spec.clone();
    other.seed = 2;
    let c = simulate(&other).unwrap();
    assert_ne!(a.trace.rows, c.trace.rows);
}

/// Mean |F − target| / target over the armed cut.
fn mean_error_pct(r: &RunResult) -> f64 {
    r.metrics.force_mean_abs_error_pct
}

#[test]
fn feedback_holds_the_force_closer_to_target_than_fixed_feed_across_depth_steps() {
    // Paper 003, Fig. 10: the DOC steps 1 → 5 mm; fixed feed lets the force follow the depth,
    // the threshold controller holds it near the target.
    let fixed = run(Preset::KimStepDoc, ControllerKind::Fixed);
    let threshold = run(Preset::KimStepDoc, ControllerKind::Threshold);
    assert!(
        mean_error_pct(&threshold) < 0.3 * mean_error_pct(&fixed),
        "threshold {:.1} % vs fixed {:.1} %",
        mean_error_pct(&threshold),
        mean_error_pct(&fixed)
    );
    assert!(threshold.metrics.peak_force_n < fixed.metrics.peak_force_n);
    // On paper 003's 0–255 % override the controller crosses the 1 mm entry at up to 255 %, so
    // the step to 5 mm overshoots for longer than it did on a 150 % dial (1.8 s against 0.8 s of
    // the fixed feed's 18 s): still a small fraction of the fixed feed's.
    assert!(threshold.metrics.time_above_limit_s < 0.15 * fixed.metrics.time_above_limit_s);
}

#[test]
fn the_depth_steps_of_the_program_are_the_steps_measured() {
    // Each of kim-step-doc's steps into the cut (0 → 1 → … → 5 mm) once, however the control
    // period splits it; leaving the cut is not a step.
    for controller in [ControllerKind::Fixed, ControllerKind::Threshold] {
        let m = run(Preset::KimStepDoc, controller).metrics;
        let depths: Vec<(f64, f64)> = m
            .steps
            .iter()
            .map(|s| (s.depth_before_mm, s.depth_after_mm))
            .collect();
        assert_eq!(
            depths,
            [(0.0, 1.0), (1.0, 2.0), (2.0, 3.0), (3.0, 4.0), (4.0, 5.0)],
            "{controller:?}"
        );
    }
    // The fixed feed never brings the force into the ±10 % band after any step (the target is
    // the force at 2.5 mm); the threshold law does after every step it can reach: at 1 mm even
    // the envelope's 150 % ceiling leaves the force under the band.
    let fixed = run(Preset::KimStepDoc, ControllerKind::Fixed).metrics;
    assert_eq!(fixed.steps_not_settled, 5);
    assert_eq!(fixed.max_settling_time_s, None);
    let threshold = run(Preset::KimStepDoc, ControllerKind::Threshold).metrics;
    assert_eq!(threshold.steps_not_settled, 1);
    assert!(threshold.steps[0].settling_time_s.is_none());
    assert!(threshold.max_settling_time_s.is_some_and(|t| t < 2.0));
}

#[test]
fn feedback_holds_the_force_across_the_material_change() {
    // Paper 003, Fig. 11: SM45C then aluminium on a taper; controlled feed speeds up in aluminium
    // and finishes sooner than the fixed 160 mm/min.
    let fixed = run(Preset::KimMaterialTaper, ControllerKind::Fixed);
    let threshold = run(Preset::KimMaterialTaper, ControllerKind::Threshold);
    assert!(mean_error_pct(&threshold) < 0.5 * mean_error_pct(&fixed));
    assert!(threshold.metrics.cycle_time_s < fixed.metrics.cycle_time_s);
}

#[test]
fn adaptive_control_converges_to_the_papers_targets() {
    // Paper 001, Fig. 7–9: 150, 200 and 320 N at DOC 1, 2 and 4 mm.
    for (preset, target) in [
        (Preset::ManeeratDoc1, 150.0),
        (Preset::ManeeratDoc2, 200.0),
        (Preset::ManeeratDoc4, 320.0),
    ] {
        let r = run(preset, ControllerKind::Mrac);
        assert_eq!(r.settings.target_force_n, target);
        // The second half of the controlled cut, short of the tool's exit.
        let cutting: Vec<f64> = r
            .trace
            .rows
            .iter()
            .filter(|row| row.armed && row.depth_mm > 0.0)
            .map(|row| row.force_n)
            .collect();
        let tail = &cutting[cutting.len() / 2..cutting.len() * 9 / 10];
        let mean = tail.iter().sum::<f64>() / tail.len() as f64;
        assert!(
            (mean - target).abs() < 0.05 * target,
            "{}: converged to {mean:.1} N, target {target} N",
            preset.name()
        );
    }
}

#[test]
fn a_run_given_the_teach_cuts_calibration_equals_one_that_teaches_itself() {
    let spec = RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Pi);
    let taught = simulate(&spec).unwrap();
    let mut run = LabRun::calibrated(&spec, taught.calibration.clone()).unwrap();
    while !run.advance(1000).unwrap() {}
    let reused = run.into_result().unwrap();
    assert_eq!(reused.trace, taught.trace);
    assert_eq!(reused.metrics, taught.metrics);
}

#[test]
fn a_calibration_taught_at_another_spindle_speed_is_refused_and_says_why() {
    // kim-step-doc teaches its line at 1000 rpm; maneerat-doc-4 cuts at 3000 rpm, where that
    // line reads about −10 N for 630 N: a controller must not act on it.
    let kim = simulate(&RunSpec::new(Preset::KimStepDoc, ControllerKind::Fixed)).unwrap();
    let elsewhere = RunSpec::new(Preset::ManeeratDoc4, ControllerKind::Pi);
    let message = LabRun::calibrated(&elsewhere, kim.calibration.clone())
        .err()
        .expect("refused")
        .to_string();
    assert!(message.contains("saw the spindle at 1000 rpm"), "{message}");
    assert!(message.contains("3000 rpm"), "{message}");
    assert!(message.contains("teach a cut on this program"), "{message}");
    // On its own program the same calibration is taken.
    let own = RunSpec::new(Preset::KimStepDoc, ControllerKind::Pi);
    assert!(LabRun::calibrated(&own, kim.calibration).is_ok());
}

/// Natively only: a bisection is ten runs.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn the_reference_search_finds_the_highest_safe_fixed_override_in_pieces_or_at_once() {
    use cutlab::closed_loop::references::{fixed_feed_spec, references, ReferenceSearch};
    let spec = RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Threshold);
    let whole = references(&spec).unwrap();

    // In small pieces, as the browser runs it: the same answer, progress never going back.
    let mut search = ReferenceSearch::new(&spec).unwrap();
    let mut last = 0.0;
    let pieces = loop {
        let fraction = search.progress().fraction;
        assert!((last..=1.0).contains(&fraction), "{fraction} after {last}");
        last = fraction;
        if search.advance(37).unwrap() {
            break search.finish().unwrap();
        }
    };
    assert_eq!(pieces, whole);

    // The answer: fixed at that override the peak force stays under the limit; 1 % more and it
    // does not; the cycle times are those of the fixed runs.
    let fixed = |pct: f64| simulate(&fixed_feed_spec(&spec, pct).unwrap()).unwrap();
    let safe = fixed(whole.safe_fixed_override_pct);
    // Judged against the target, the force the controllers hold (issue: the reference once ran
    // at up to 1.2 × target while the controllers aimed at 1.0 ×).
    let limit = safe.settings.target_force_n;
    assert!(safe.metrics.peak_force_n <= limit);
    assert_eq!(safe.metrics.cycle_time_s, whole.safe_fixed_cycle_time_s);
    let faster = fixed(whole.safe_fixed_override_pct + 1.0);
    assert!(faster.metrics.peak_force_n > limit || !faster.trace.completed);
    assert_eq!(
        fixed(100.0).metrics.cycle_time_s,
        whole.programmed_cycle_time_s
    );
}

/// The rows of `r` in the program's cut, armed: where the fixed override is the machine's.
fn applied_overrides_pct(r: &RunResult) -> Vec<f64> {
    r.trace
        .rows
        .iter()
        .filter(|row| row.armed && row.programmed_feed_mm_min > 0.0)
        .map(|row| row.applied_override_pct)
        .collect()
}

/// Natively only: three whole runs and a teach cut.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn a_target_far_above_the_cut_leaves_the_controller_in_charge() {
    // 5000 N on kim-step-doc, whose cut gives 300–700 N at 100 %: a fifth of the target (1000 N)
    // lies above every cut, so the envelope once took the whole run for air and held the
    // programmed feed, the controller silently off. It now asks for more feed, up to the ceiling.
    let mut spec = RunSpec::new(Preset::KimStepDoc, ControllerKind::Pi);
    spec.settings.target_force_n = Some(5_000.0);
    let far = simulate(&spec).unwrap();
    assert!(far.metrics.override_changes > 0, "{:?}", far.metrics);
    let programmed = simulate(&RunSpec::new(Preset::KimStepDoc, ControllerKind::Fixed)).unwrap();
    assert!(
        far.metrics.cycle_time_s < programmed.metrics.cycle_time_s - 1.0,
        "{} s against the programmed feed's {} s",
        far.metrics.cycle_time_s,
        programmed.metrics.cycle_time_s
    );
}

#[test]
fn the_safe_fixed_override_reported_is_the_one_the_machine_ran_at() {
    use cutlab::closed_loop::references::{fixed_feed_spec, references};
    // kim-step-doc's 0.1 mm per tooth lies inside SM45C's chip-load window (0.01–0.15 mm) from
    // 10 to 150 %; with a target no fixed feed reaches, the highest safe override is the window's
    // ceiling. (The search once reported a fixed 249 %, which the envelope ran as 150 %.)
    let mut spec = RunSpec::new(Preset::KimStepDoc, ControllerKind::Fixed);
    spec.settings.target_force_n = Some(20_000.0);
    let found = references(&spec).unwrap();
    let safe = simulate(&fixed_feed_spec(&spec, found.safe_fixed_override_pct).unwrap()).unwrap();
    let applied = applied_overrides_pct(&safe);
    assert!(!applied.is_empty());
    assert!(
        applied.iter().all(|&p| p == found.safe_fixed_override_pct),
        "reported {} %, applied {:?} %",
        found.safe_fixed_override_pct,
        applied
            .iter()
            .fold((f64::INFINITY, 0.0_f64), |(lo, hi), &p| (
                lo.min(p),
                hi.max(p)
            ))
    );
    assert_eq!(found.safe_fixed_override_pct, 150.0);
    assert_eq!(safe.metrics.cycle_time_s, found.safe_fixed_cycle_time_s);
}

/// Natively only: four whole runs of a 170 s program, a teach cut and a check run.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn the_reference_search_starts_at_the_chip_load_floor_and_runs_it_once() {
    use cutlab::closed_loop::references::{
        fixed_feed_spec, fixed_override_range_pct, ReferenceSearch,
    };
    let spec = RunSpec::new(Preset::KimCircularTaper, ControllerKind::Threshold);
    // Below 36 % the envelope raises any fixed override to the chip-load window's floor at this
    // program's 170 mm/min (SM45C's 0.01 mm per tooth), so every slower fixed feed is one run.
    let (floor_pct, _) = fixed_override_range_pct(&spec).unwrap();
    assert_eq!(floor_pct, 36.0);
    let at_floor = simulate(&fixed_feed_spec(&spec, floor_pct).unwrap()).unwrap();
    let below = simulate(&fixed_feed_spec(&spec, 14.0).unwrap()).unwrap();
    assert!(applied_overrides_pct(&below)
        .iter()
        .all(|&p| p == floor_pct));
    assert_eq!(below.metrics.peak_force_n, at_floor.metrics.peak_force_n);

    let mut search = ReferenceSearch::new(&spec).unwrap();
    let mut labels = Vec::new();
    let found = loop {
        labels.push(search.progress().stage);
        if search.advance(1000).unwrap() {
            break search.finish().unwrap();
        }
    };
    // The total a person reads stays the first estimate while the search keeps within it (it
    // read 4, 5, 6 run by run before).
    assert!(
        labels.iter().all(|l| l.contains(" of about 4,")),
        "{labels:?}"
    );
    assert!(labels
        .iter()
        .any(|l| l.starts_with("Savings: reference run 3 of about 4,")));
    // 100 and 60 % whole (they fix the line, which places the target below the floor), then the
    // floor, stopped where it breaks: the search once halved its way down to 1 %, ten runs of
    // which the last eight were the floor's, and later probed just above the floor before it.
    assert_eq!(search.runs_done(), 3);
    // Even the floor's peak lies above the target: no fixed feed is safe.
    assert!(at_floor.metrics.peak_force_n > at_floor.settings.target_force_n);
    assert!(found.safe_fixed_override_pct.is_nan(), "{found:?}");
    assert!(found.safe_fixed_cycle_time_s.is_nan());
}

#[test]
fn on_the_brake_bench_restriction_steps_the_dial_down_under_load_and_back_up() {
    // Paper 000's bench has no spindle: the envelope arms from the first feed motion, and the
    // restriction law answers the brake's load steps (which no feed change can lower).
    let r = run(Preset::WangBrakeBench, ControllerKind::Restriction);
    assert!(r
        .trace
        .events
        .iter()
        .any(|e| matches!(e, cutlab::safety::SafetyEvent::Armed { .. })));
    let override_at = |t: f64| {
        r.trace
            .rows
            .iter()
            .find(|row| row.time_s >= t)
            .map(|row| row.override_pct)
            .unwrap()
    };
    assert_eq!(override_at(1.0), 100.0, "held at the arming override");
    let under_load = r
        .trace
        .rows
        .iter()
        .filter(|row| (25.0..45.0).contains(&row.time_s))
        .map(|row| row.override_pct)
        .fold(f64::INFINITY, f64::min);
    assert!(
        under_load <= 20.0,
        "override {under_load} % at the heaviest load"
    );
    assert!(override_at(58.0) >= 100.0, "back up once the load falls");
}

#[test]
fn on_the_brake_bench_threshold_control_starts_once_the_feed_has_run_its_ignore_time() {
    // The bench has no spindle, so "current ignored for 3 s after the spindle starts" (paper 003)
    // runs on the clock the envelope arms by: the first feed motion. On a spindle clock that never
    // starts, the law would ignore the current for the whole run.
    let r = run(Preset::WangBrakeBench, ControllerKind::Threshold);
    assert!(
        r.metrics.override_changes > 5,
        "{}",
        r.metrics.override_changes
    );
    let first_change = r
        .trace
        .rows
        .windows(2)
        .find(|w| w[1].override_pct != w[0].override_pct)
        .map(|w| w[1].time_s)
        .unwrap();
    assert!(
        first_change >= 3.0,
        "changed at {first_change} s, inside the ignore time"
    );
}

#[test]
fn a_run_stopped_by_the_overload_alarm_has_no_cycle_time_to_win_with() {
    use cutlab::closed_loop::summary::METRIC_ROWS;
    // A target far below the force of the cut: fixed feed trips the overload alarm (3 × target).
    let mut spec = RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Fixed);
    spec.settings.target_force_n = Some(40.0);
    let r = simulate(&spec).unwrap();
    assert!(!r.metrics.completed);
    let value = |label: &str| {
        let row = METRIC_ROWS.iter().find(|row| row.label == label).unwrap();
        (row.value)(&r)
    };
    assert_eq!(value("Program finished"), Some(0.0));
    assert_eq!(value("Cycle time"), None);
    assert_eq!(value("Saving vs programmed feed"), None);
}

/// Feed-current feedback on a mill (paper 000's path, on paper 003's machine): the preset's
/// target, a mean resultant force, is converted to feed force by the ratio the teach cut saw; a
/// down-milling cut, whose force pulls the table along, is refused with the reason.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn feed_current_feedback_converts_the_target_and_refuses_down_milling() {
    use cutlab::estimation::estimator::Feedback;
    let mut spec = RunSpec::new(Preset::KimStepDoc, ControllerKind::Threshold);
    spec.settings.feedback = Some(Feedback::FeedCurrent);
    let r = simulate(&spec).unwrap();
    let resultant_target = Preset::KimStepDoc.target_force_n().unwrap();
    let ratio = r.calibration.regulated_per_resultant;
    assert!((0.2..0.9).contains(&ratio), "feed / resultant = {ratio}");
    assert!((r.settings.target_force_n - resultant_target * ratio).abs() < 1e-9);
    assert!(r.metrics.completed);

    let mut down = RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Threshold);
    down.settings.feedback = Some(Feedback::FeedCurrent);
    let e = simulate(&down).unwrap_err().to_string();
    assert!(e.contains("down milling"), "{e}");
}

/// Feed-current feedback on a mill reports the cut's entry once and its exit once: its period is
/// whole spindle revolutions, as the spindle current's is. At 50 ms against kim-step-doc's 60 ms
/// revolution each period's mean caught another share of the teeth's ripple, and the air-cut rule
/// took one period in three of the steady 2 mm cut for air: 99 air/entry events.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn feed_current_feedback_reports_a_cuts_entry_and_exit_once() {
    use cutlab::estimation::estimator::Feedback;
    use cutlab::safety::SafetyEvent;
    let mut spec = RunSpec::new(Preset::KimStepDoc, ControllerKind::Threshold);
    spec.settings.feedback = Some(Feedback::FeedCurrent);
    let r = simulate(&spec).unwrap();
    let rpm = Preset::KimStepDoc.mill_parameters().unwrap().spindle_rpm;
    let revolutions = r.settings.control_period_s * rpm / 60.0;
    assert!(
        (revolutions - revolutions.round()).abs() < 1e-6,
        "{} s is {revolutions} revolutions",
        r.settings.control_period_s
    );
    let count = |f: fn(&SafetyEvent) -> bool| r.trace.events.iter().filter(|e| f(e)).count();
    let events = &r.trace.events;
    // The program enters its cut once and leaves it once: in air before the entry and after it.
    assert_eq!(
        count(|e| matches!(e, SafetyEvent::EntryHold { .. })),
        1,
        "{events:?}"
    );
    assert_eq!(
        count(|e| matches!(e, SafetyEvent::AirCut { .. })),
        2,
        "{events:?}"
    );
    assert!(r.metrics.completed);
}

/// tests/reference/plant/liu_cut.csv (scripts/reference/plant_reference.py): liu-current-step's
/// cut in closed form.
const LIU_CUT: &str = include_str!("reference/plant/liu_cut.csv");

/// Issue 26: every quantity in liu-current-step's trace is a machining centre's, whatever the
/// controller does with the feed. Each period's cutting force is the closed form's at its depth and
/// feed per tooth (the reference's resultant per millimetre of depth and of feed per tooth: the
/// chip's force is proportional to both), its removal rate is depth × width × feed, the x axis
/// draws a servo's few amperes (the 100 A of the bound is never approached) and the
/// spindle stays within its 100 A channel.
#[test]
fn liu_current_steps_traces_are_a_machining_centres_for_every_controller() {
    let header: Vec<&str> = LIU_CUT.lines().next().unwrap().split(',').collect();
    let reference: Vec<f64> = LIU_CUT
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .map(|c| c.parse().unwrap())
        .collect();
    let col = |name: &str| reference[header.iter().position(|h| *h == name).unwrap()];
    let resultant_per_mm_mm =
        col("mean_resultant_n") / (col("depth_mm") * col("feed_per_tooth_mm"));
    let (teeth, width_mm) = (5.0, 40.0);
    for kind in ControllerKind::ALL {
        let r = run(Preset::LiuCurrentStep, kind);
        let who = kind.name();
        for row in r.trace.rows.iter().filter(|row| row.feed_mm_min > 100.0) {
            let at = format!("{who} at {} s", row.time_s);
            let feed_per_tooth = row.feed_mm_min / (teeth * row.spindle_speed_rpm);
            let closed_form = resultant_per_mm_mm * row.depth_mm * feed_per_tooth;
            assert!(
                (row.force_n - closed_form).abs() < 0.02 * closed_form,
                "{at}: {} N against {closed_form} N",
                row.force_n
            );
            let removal = row.depth_mm * width_mm * row.feed_mm_min / 60.0;
            assert!(
                (row.material_removal_mm3_s - removal).abs() < 0.005 * removal,
                "{at}"
            );
            let feed_phase_peak = row.feed_current_u_max_a.max(-row.feed_current_u_min_a);
            assert!(
                row.feed_current_rms_a < 5.0 && feed_phase_peak < 7.0,
                "{at}: x axis {} A RMS, {feed_phase_peak} A peak",
                row.feed_current_rms_a
            );
            assert!(row.spindle_current_rms_a < 100.0, "{at}");
        }
    }
}

/// Paper 002's Fig. 7 under the readings docs/papers.md's grid compares (tests/docs.rs makes it),
/// at the preset's +40 % step. The preset reads the paper as printed where it speaks: k_u's
/// 100 % per period let through by the envelope, EC in A/s (Table 2), Table 2's 50 ms spacing as
/// the period. There both tables limit-cycle, the dynamics table less; at 0.1 s the experience
/// table keeps cycling while the dynamics table settles (the Compare page's comparison). With
/// EC and k_u per period, as eq 6 and eq 1 print them, the tables answer alike at the short
/// periods; and with k_u per second (its gain per second held) they still answer alike at 0.5 s,
/// where per-period k_u made them differ: lengthening the period alone does not.
#[test]
fn paper_002s_claim_holds_where_the_grid_says() {
    let runs = |period: Option<f64>, ec_base_s: f64, ku_base_s: f64| {
        [
            ControllerKind::FuzzyExperience,
            ControllerKind::FuzzyDynamics,
        ]
        .map(|kind| {
            let mut spec = RunSpec::new(Preset::LiuCurrentStep, kind);
            spec.settings.control_period_s = period;
            spec.controller
                .set("change_time_base_s", ec_base_s)
                .unwrap();
            spec.controller
                .set("output_time_base_s", ku_base_s)
                .unwrap();
            simulate(&spec).unwrap()
        })
    };
    let settled = |r: &RunResult| r.metrics.max_settling_time_s.unwrap_or(f64::INFINITY);
    let wobble = |r: &RunResult| r.metrics.late_force_fluctuation_pct;

    // The preset's reading at its 50 ms: both cycle, the dynamics table less.
    let [experience, dynamics] = runs(None, 1.0, 0.0);
    assert_eq!(dynamics.settings.control_period_s, 0.05);
    assert_eq!(dynamics.settings.envelope.max_rate_pct_per_s, 2000.0);
    let c = &dynamics.spec.controller;
    assert_eq!(
        (c.get("output_range_pct"), c.get("change_time_base_s")),
        (Some(100.0), Some(1.0))
    );
    // The load step is measured once, at 15 s, with its depths.
    assert_eq!(dynamics.metrics.steps.len(), 1);
    let step = dynamics.metrics.steps[0];
    assert_eq!(step.time_s, 15.0);
    assert!((step.depth_after_mm / step.depth_before_mm - 1.4).abs() < 1e-9);
    assert!(wobble(&experience) > 1.0 && wobble(&dynamics) > 1.0);
    assert!(wobble(&dynamics) < 0.8 * wobble(&experience));

    // At 0.1 s the experience table cycles (10 % of the target) and the dynamics table settles.
    let [experience, dynamics] = runs(Some(0.1), 1.0, 0.0);
    assert!(experience.metrics.max_settling_time_s.is_none());
    assert!(settled(&dynamics) < 10.0 && wobble(&dynamics) < 0.5);
    assert!(wobble(&experience) > 5.0);

    // Eq 6 and eq 1 as printed, at 50 ms: alike, within a fifth.
    let [experience, dynamics] = runs(None, 0.0, 0.0);
    assert!((settled(&dynamics) - settled(&experience)).abs() <= 0.2 * settled(&experience));

    // At 0.5 s per-period k_u makes them differ; with k_u's gain per second held they do not.
    let [experience, dynamics] = runs(Some(0.5), 0.0, 0.0);
    assert!(settled(&dynamics) * 1.5 < settled(&experience));
    let [experience, dynamics] = runs(Some(0.5), 0.0, 1.0);
    assert!(
        settled(&dynamics) >= 0.8 * settled(&experience),
        "dynamics {} s, experience {} s",
        settled(&dynamics),
        settled(&experience)
    );
}

/// Paper 001 under its own assumptions: its second-order process (eq 2.3) with the force read by
/// a dynamometer. The loop regulates what the sensor reads, and the sensor reads the truth within
/// its noise and lag.
#[test]
fn paper_001_process_with_dynamometer_feedback_holds_the_target() {
    use cutlab::estimation::estimator::{Estimator, Feedback};
    let r = run(Preset::ManeeratSecondOrder, ControllerKind::Mrac);
    assert_eq!(r.settings.feedback, Feedback::Dynamometer);
    assert_eq!(r.calibration.estimator, Estimator::Dynamometer);
    assert!(r.trace.completed);
    let controlled: Vec<_> = r
        .trace
        .rows
        .iter()
        .filter(|row| row.armed && row.depth_mm > 0.0 && row.time_s > 8.0)
        .collect();
    assert!(
        controlled.len() > 50,
        "{} controlled periods",
        controlled.len()
    );
    // Sensor against truth: a period mean of 2 N noise and a 500 Hz lag is within a few newtons.
    let worst = controlled
        .iter()
        .map(|row| (row.force_est_n - row.force_n).abs())
        .fold(0.0, f64::max);
    assert!(worst < 0.03 * 200.0, "sensor and truth differ by {worst} N");
    // Settled on the target once past the entry.
    let mean_error = controlled
        .iter()
        .map(|row| (row.force_n - 200.0).abs() / 200.0)
        .sum::<f64>()
        / controlled.len() as f64;
    assert!(mean_error < 0.05, "mean |error| {mean_error}");
}

/// Paper 004's sensor failure prediction on the circular taper (a program with one depth, which
/// teaches no network: the published power law, calibrated, is its sensorless estimate), where the
/// controller cuts the feed per tooth down far below the cut the power law was calibrated on:
/// with the exponents' uncertainty in its tolerance the prediction no longer flags that known
/// difference of model form (31 % of the cut before), only the instants where the two estimates
/// truly part (the steps, where the power law answers at once and the current through its
/// filters).
#[test]
fn paper_004_sensor_failure_prediction_raises_no_false_alarms_at_low_feed_per_tooth() {
    let r = run(Preset::KimCircularTaper, ControllerKind::Threshold);
    let share = r.metrics.time_sensor_failure_predicted_s / r.metrics.controlled_cutting_time_s;
    assert!(
        share < 0.01,
        "a sensor failure is predicted over {:.1} % of the cut",
        100.0 * share
    );
    let low_feed = r
        .trace
        .rows
        .iter()
        .filter(|row| row.armed && row.depth_mm > 0.0 && row.override_pct < 60.0)
        .count();
    assert!(
        low_feed > 50,
        "the controller never slowed the feed ({low_feed} periods)"
    );
}

/// The papers' comparisons the Compare page offers, with the verdicts docs/papers.md reports:
/// if a model or controller change moves one, this fails and the docs must be rewritten.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn the_papers_comparisons_give_the_verdicts_the_docs_report() {
    use cutlab::closed_loop::paper_comparisons::PAPER_COMPARISONS;
    let expected = [
        (
            "Paper 003: fixed feed vs threshold control over DOC steps",
            Some(true),
        ),
        // Needs the reference runs for its saving: judged without them, it waits.
        ("Paper 003: across the material change", None),
        (
            "Paper 002: experience vs dynamics rules, sampled every 0.1 s",
            Some(true),
        ),
        (
            "Paper 002: experience vs dynamics rules, sampled every 0.2 s",
            Some(true),
        ),
        ("Paper 001: adaptive control at DOC 4 mm", Some(true)),
        ("Paper 001's own model with a dynamometer", Some(true)),
        // No claim to judge: the figures side by side.
        ("Paper 000 vs 003: restriction vs threshold vs PI", None),
    ];
    let mut report = String::new();
    let mut wrong = Vec::new();
    for (comparison, (label, verdict)) in PAPER_COMPARISONS.iter().zip(expected) {
        assert_eq!(comparison.label, label);
        let results: Vec<_> = comparison
            .specs()
            .unwrap()
            .iter()
            .map(|s| simulate(s).unwrap())
            .collect();
        let refs: Vec<_> = results.iter().collect();
        let finding = comparison.finding(&refs).unwrap();
        report += &format!("{label}: {}\n", finding.text());
        if finding.reproduced != verdict {
            wrong.push(label);
        }
    }
    assert!(wrong.is_empty(), "{wrong:?}\n{report}");
}

/// Paper 001's presets approach in air: the controllers, seeing no force there, used to wind the
/// override up to 150 % and enter the cut at it (peaks 422 N and 845 N against the fixed feed's
/// 315 N and 631 N). The envelope's air-cut rule holds the override at the entry override in air,
/// so every controller enters as the programmed feed does and only then takes over.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn controllers_enter_the_cut_at_the_programmed_feed_not_wound_up_in_air() {
    for preset in [Preset::ManeeratDoc2, Preset::ManeeratDoc4] {
        let fixed = simulate(&RunSpec::new(preset, ControllerKind::Fixed)).unwrap();
        for kind in [
            ControllerKind::Mrac,
            ControllerKind::Pi,
            ControllerKind::Threshold,
            ControllerKind::FuzzyDynamics,
        ] {
            let run = simulate(&RunSpec::new(preset, kind)).unwrap();
            let entry = run.trace.rows.iter().find(|r| r.depth_mm > 0.0).unwrap();
            assert!(
                entry.override_pct <= 100.0,
                "{} on {}: entered at {} %",
                kind.name(),
                preset.name(),
                entry.override_pct
            );
            assert!(
                run.metrics.peak_force_n <= 1.1 * fixed.metrics.peak_force_n,
                "{} on {}: peak {} N against the fixed feed's {} N",
                kind.name(),
                preset.name(),
                run.metrics.peak_force_n,
                fixed.metrics.peak_force_n
            );
        }
    }
}

/// Dynamometer feedback is a choice on every preset, not only on paper 001's own process.
#[test]
fn dynamometer_feedback_on_a_mill_holds_the_target() {
    use cutlab::estimation::estimator::Feedback;
    let mut spec = RunSpec::new(Preset::ManeeratDoc2, ControllerKind::Mrac);
    spec.settings.feedback = Some(Feedback::Dynamometer);
    let r = simulate(&spec).unwrap();
    assert!(matches!(
        r.calibration.estimator,
        cutlab::estimation::estimator::Estimator::Dynamometer
    ));
    assert!(r.metrics.completed);
    assert!(
        r.metrics.force_mean_abs_error_pct < 10.0,
        "{}",
        r.metrics.force_mean_abs_error_pct
    );
}
