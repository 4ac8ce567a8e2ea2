//! Paper 004's sensor failure prediction (issue 32): each control period the current-based force
//! estimate is held against the sensorless one — the network kim-step-doc learned on its own
//! trial cuts from its current-based estimates, fed with what the CNC program knows of the cut —
//! and a period where they part beyond their tolerance predicts a failing current sensor. A
//! healthy run predicts almost none; a spindle Hall sensor whose gain drops mid-cut is predicted
//! within a second; and the learned network raises no more false alarms than paper 004's
//! published weights (calibrated) did as the sensorless estimate.
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

#[path = "common/faults.rs"]
mod faults;

use cutlab::closed_loop::definition::RunSpec;
use cutlab::closed_loop::lab::RunResult;
use cutlab::control::registry::ControllerKind;
use cutlab::machine::Machine;
use cutlab::plant::Preset;
use faults::{
    prediction_delay_s, published_run_machine, run_on, DriftingSpindleSensor, FAULTY_GAIN,
    FAULT_AT_S,
};

/// The controllers a shop would run the check under: fixed feed, paper 003's threshold law and
/// the PI law (the ones that need no rule base or engine).
const CONTROLLERS: [ControllerKind; 3] = [
    ControllerKind::Fixed,
    ControllerKind::Threshold,
    ControllerKind::Pi,
];

/// Controlled cutting time with a sensor failure predicted, and its share of the controlled cut.
fn predicted(result: &RunResult) -> (f64, f64) {
    let m = &result.metrics;
    let share = m.time_sensor_failure_predicted_s / m.controlled_cutting_time_s.max(1e-9);
    (m.time_sensor_failure_predicted_s, share)
}

#[test]
fn kim_step_doc_estimates_sensorless_with_its_learned_network() {
    // The run machine's sensorless force is the shipped network's prediction, not the
    // published law's: the two differ on the first cut.
    let spec = RunSpec::new(Preset::KimStepDoc, ControllerKind::Fixed);
    let learned = run_on(&spec, |m| m);
    let network = cutlab::plant::sensorless::shipped_network(Preset::KimStepDoc).unwrap();
    let cut = learned
        .trace
        .rows
        .iter()
        .find(|r| r.armed && r.depth_mm > 0.0 && r.force_power_law_n > 0.0)
        .unwrap();
    let published = run_on(&spec, |_| published_run_machine(&spec));
    let same = published
        .trace
        .rows
        .iter()
        .find(|r| r.time_s == cut.time_s)
        .unwrap();
    assert_ne!(cut.force_power_law_n, same.force_power_law_n);
    assert!(network.bias_n > 0.0);
}

#[test]
fn a_healthy_run_predicts_almost_no_sensor_failure() {
    for controller in CONTROLLERS {
        let spec = RunSpec::new(Preset::KimStepDoc, controller);
        let result = run_on(&spec, |m| m);
        let (time_s, share) = predicted(&result);
        eprintln!(
            "{}: sensor failure predicted for {time_s:.2} s ({:.2} % of the controlled cut)",
            controller.name(),
            100.0 * share
        );
        assert!(
            share < 0.01,
            "{}: a sensor failure predicted over {:.2} % of a healthy cut",
            controller.name(),
            100.0 * share
        );
    }
}

#[test]
fn a_spindle_sensor_losing_gain_mid_cut_is_predicted_within_a_second() {
    for controller in CONTROLLERS {
        let spec = RunSpec::new(Preset::KimStepDoc, controller);
        let result = run_on(&spec, |machine| {
            Box::new(DriftingSpindleSensor {
                machine,
                from_s: FAULT_AT_S,
                gain: FAULTY_GAIN,
            })
        });
        let rows = &result.trace.rows;
        let before = rows
            .iter()
            .filter(|r| r.time_s < FAULT_AT_S && r.sensor_failure_predicted)
            .count();
        assert_eq!(
            before,
            0,
            "{}: predicted before the fault",
            controller.name()
        );
        let delay_s = prediction_delay_s(&result)
            .unwrap_or_else(|| panic!("{}: the fault was never predicted", controller.name()));
        eprintln!(
            "{}: the sensor's gain drop predicted after {delay_s:.2} s; failure predicted for {:.1} s \
             of the cut after it",
            controller.name(),
            result.metrics.time_sensor_failure_predicted_s
        );
        assert!(
            delay_s < 1.0,
            "{}: predicted {delay_s} s late",
            controller.name()
        );
        // And it stays predicted while the sensor stays wrong: most of the cut after the fault.
        let cut_after: Vec<_> = rows
            .iter()
            .filter(|r| r.time_s >= FAULT_AT_S + 1.0 && r.armed && r.depth_mm > 0.0)
            .collect();
        let flagged = cut_after
            .iter()
            .filter(|r| r.sensor_failure_predicted)
            .count();
        assert!(
            flagged as f64 > 0.8 * cut_after.len() as f64,
            "{}: {flagged} of {} periods after the fault flagged",
            controller.name(),
            cut_after.len()
        );
    }
}

#[test]
fn the_learned_network_raises_no_more_false_alarms_than_the_published_weights() {
    for controller in CONTROLLERS {
        let spec = RunSpec::new(Preset::KimStepDoc, controller);
        let (learned_s, _) = predicted(&run_on(&spec, |m| m));
        let (published_s, _) = predicted(&run_on(&spec, |_| published_run_machine(&spec)));
        eprintln!(
            "{}: false alarms {learned_s:.2} s with the learned network, {published_s:.2} s with \
             the published weights",
            controller.name()
        );
        assert!(
            learned_s <= published_s,
            "{}: {learned_s} s learned vs {published_s} s published",
            controller.name()
        );
    }
}

#[test]
fn the_learned_network_sees_a_small_drift_at_least_as_long_as_the_published_weights() {
    // A 10 % gain drop: the learned network's band (its trial cuts' residuals and its exponents'
    // standard errors) is narrower than the published weights' (±0.25 per exponent), so it
    // predicts the failure over at least as much of the cut after it.
    let gain = 0.9;
    for controller in CONTROLLERS {
        let spec = RunSpec::new(Preset::KimStepDoc, controller);
        let drifting = |machine| -> Box<dyn Machine> {
            Box::new(DriftingSpindleSensor {
                machine,
                from_s: FAULT_AT_S,
                gain,
            })
        };
        let (learned_s, _) = predicted(&run_on(&spec, drifting));
        let (published_s, _) =
            predicted(&run_on(&spec, |_| drifting(published_run_machine(&spec))));
        eprintln!(
            "{}: a 10 % gain drop predicted for {learned_s:.2} s with the learned network, \
             {published_s:.2} s with the published weights",
            controller.name()
        );
        assert!(
            learned_s >= published_s && learned_s > 0.0,
            "{}: {learned_s} s learned vs {published_s} s published",
            controller.name()
        );
    }
}
