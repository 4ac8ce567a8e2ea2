//! The native host against the device emulator, in-process over pipes or a line without latency,
//! and as processes: the closed loop over the protocol keeps `cutlab sim`'s metrics (what it
//! costs: docs/protocol.md §8), survives a lossy line counting its losses and a flood on the
//! device's input, both watchdogs and the device's faults do what docs/protocol.md §5 says, and
//! the command line reports whatever happened.
//!
//! The device keeps scaled real time, so these tests take their time (about 7 s each at 20× real
//! time) and run one at a time: two machines in parallel on a small runner could starve a host,
//! and a starved host trips the device's watchdog, which is what one of the tests is about. The
//! tests over a [`LockstepLine`] (no latency, no clock) are deterministic; they take the same
//! turn so as not to starve the others.
#![cfg(not(target_arch = "wasm32"))]
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::cell::RefCell;
use std::rc::Rc;
use std::sync::mpsc::RecvTimeoutError;
use std::sync::Mutex;

use cutlab::closed_loop::calibration_file::CalibrationFile;
use cutlab::closed_loop::definition::RunSpec;
use cutlab::closed_loop::lab::{simulate, RunResult};
use cutlab::control::registry::ControllerKind;
use cutlab::estimation::estimator::Calibration;
use cutlab::hardware::link_run::{run_on_link, LinkRun};
use cutlab::plant::Preset;
use cutlab::protocol::codec::{encode_frame, MAX_FRAME_LEN};
use cutlab::protocol::device::{
    DeviceConfig, DeviceEmulator, DeviceStats, FaultInjection, HoldCause,
};
use cutlab::protocol::frame::{Capabilities, FaultKind, Frame};
use cutlab::protocol::link::{
    run_device, DeviceExit, HostLink, HostOptions, Line, LockstepLine, DEVICE_QUEUE_CHUNKS,
    READ_CHUNK,
};

/// One closed loop against the emulator at a time, and nothing else heavy beside it: a test that
/// runs the link in real time holds this for its whole body (its own simulation included), so
/// another test's simulation cannot take the cores the host and the device need and add latency
/// the metrics then show (a clean CI-like run once saw 76 s instead of 72 s of cycle time).
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

const TIME_SCALE: f64 = 20.0;

/// The device's watchdog in the real-time tests that are not about it: 20 s of device time, a
/// second of wall time at 20×, so a loaded machine (another build beside the tests, load average
/// 8) that holds the host thread up for a few tenths of a second does not trip it. The watchdog
/// tests themselves give it 10 or 15 s (0.5 or 0.75 s of wall time) and a fault longer still.
const CALM_WATCHDOG_S: f64 = 20.0;

/// The device on a thread and the host on this one, joined by two pipes (the caller holds
/// [`ONE_AT_A_TIME`]).
fn host_against_emulator(
    config: DeviceConfig,
    spec: &RunSpec,
    options: HostOptions,
) -> (LinkRun, DeviceStats, String) {
    host_against_emulator_calibrated(config, spec, options, None)
}

/// As [`host_against_emulator`], starting from `calibration` (no teach cut) when given.
fn host_against_emulator_calibrated(
    config: DeviceConfig,
    spec: &RunSpec,
    options: HostOptions,
    calibration: Option<Calibration>,
) -> (LinkRun, DeviceStats, String) {
    let (host_to_device_r, host_to_device_w) = std::io::pipe().unwrap();
    let (device_to_host_r, mut device_to_host_w) = std::io::pipe().unwrap();
    let device = std::thread::spawn(move || {
        let mut d = DeviceEmulator::new(config).unwrap();
        let mut diagnostics = Vec::new();
        run_device(
            &mut d,
            host_to_device_r,
            &mut device_to_host_w,
            &mut diagnostics,
            None,
            TIME_SCALE,
        );
        (
            d.stats(),
            String::from_utf8_lossy(&diagnostics).into_owned(),
        )
    });
    let link = HostLink::connect(device_to_host_r, Box::new(host_to_device_w), options).unwrap();
    let run = run_on_link(link, spec, None, calibration);
    let (stats, diagnostics) = device.join().unwrap();
    (run, stats, diagnostics)
}

/// The emulator of kim-step-doc with a watchdog of `watchdog_s` device seconds. Tests in real
/// time that are not about the watchdog give it [`CALM_WATCHDOG_S`]; the lockstep tests, which
/// have no wall clock, 5 s.
fn kim_device(watchdog_s: f64) -> DeviceConfig {
    let mut config = DeviceConfig::new(Preset::KimStepDoc);
    config.watchdog_timeout_s = watchdog_s;
    config
}

fn kim_threshold() -> RunSpec {
    RunSpec::new(Preset::KimStepDoc, ControllerKind::Threshold)
}

fn within(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs())
}

/// What a run over the link in real time is sure to share with the simulation, busy machine or
/// not (docs/protocol.md §8, "What the protocol costs"): the program's metrics — removed volume
/// within 0.5 %, and peak force (the depth step's, met at the override before it), cycle time and
/// mean removal rate within 5 % (a busy test machine delays the host, and every delay is latency
/// in the loop: a load average of 11 moved the peak by 3 %) — and a force held near its target:
/// mean |error| within 1.3 × the simulation's. The force error is not compared closely: the
/// threshold controller's limit cycle locks in differently after any small perturbation (the
/// 1 kHz chain alone, or another seed of the simulation), which moves its force IAE by up to
/// ±28 % (the lockstep tests below hold the rest to 1–2 %).
fn assert_like_sim(sim: &RunResult, run: &LinkRun) {
    let link = run.result.as_ref().unwrap();
    let (s, l) = (&sim.metrics, &link.metrics);
    let report = format!("sim {s:#?}\nlink {l:#?}\n{:?}", run.stats);
    assert!(l.completed, "{report}");
    assert!(within(s.cycle_time_s, l.cycle_time_s, 0.05), "{report}");
    assert!(
        within(s.removed_volume_mm3, l.removed_volume_mm3, 0.005),
        "{report}"
    );
    assert!(
        within(
            s.mean_material_removal_mm3_s,
            l.mean_material_removal_mm3_s,
            0.05
        ),
        "{report}"
    );
    assert!(within(s.peak_force_n, l.peak_force_n, 0.05), "{report}");
    assert!(
        l.force_mean_abs_error_pct < 1.3 * s.force_mean_abs_error_pct,
        "{report}"
    );
    assert_eq!(sim.settings.target_force_n, link.settings.target_force_n);
}

/// `spec` run over a [`LockstepLine`] to the emulator: the protocol's bytes, 1 kHz block means
/// and 5 mA counts with no latency and no clock — deterministic and quick.
fn lockstep(config: DeviceConfig, spec: &RunSpec, calibration: Option<Calibration>) -> LinkRun {
    lockstep_for(config, spec, None, calibration).0
}

/// As [`lockstep`], with a duration limit, and the device afterwards.
fn lockstep_for(
    config: DeviceConfig,
    spec: &RunSpec,
    duration_s: Option<f64>,
    calibration: Option<Calibration>,
) -> (LinkRun, DeviceEmulator) {
    let device = Rc::new(RefCell::new(DeviceEmulator::new(config).unwrap()));
    let line = Box::new(LockstepLine::new(Rc::clone(&device)));
    let link = HostLink::connect_line(line, HostOptions::default()).unwrap();
    let run = run_on_link(link, spec, duration_s, calibration);
    let device = Rc::try_unwrap(device).ok().unwrap().into_inner();
    (run, device)
}

fn kim_seed_1(controller: ControllerKind) -> RunSpec {
    RunSpec::new(Preset::KimStepDoc, controller)
}

/// Without a line's latency, the protocol costs a continuous controller nothing measurable:
/// every metric, the force error's too, within 1 % of `cutlab sim`'s (0.9 % at most over seeds
/// 1–4). What the protocol changes is the chain: 1 kHz block means of the 10 kHz currents in
/// 5 mA counts, which the teach cut over the same link calibrates.
#[test]
fn without_latency_the_protocol_costs_a_pi_loop_under_one_percent_on_every_metric() {
    // Not timed, but heavy: the tests in real time must not be starved by it.
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let spec = kim_seed_1(ControllerKind::Pi);
    let sim = simulate(&spec).unwrap();
    let run = lockstep(kim_device(5.0), &spec, None);
    let (s, l) = (&sim.metrics, &run.result.as_ref().unwrap().metrics);
    let report = format!("sim {s:#?}\nlockstep {l:#?}");
    assert!(l.completed && run.stats.frames_lost == 0, "{report}");
    for (what, a, b) in [
        ("cycle time", s.cycle_time_s, l.cycle_time_s),
        ("volume", s.removed_volume_mm3, l.removed_volume_mm3),
        (
            "removal rate",
            s.mean_material_removal_mm3_s,
            l.mean_material_removal_mm3_s,
        ),
        ("peak force", s.peak_force_n, l.peak_force_n),
        ("force IAE", s.force_iae_n_s, l.force_iae_n_s),
        ("force RMS error", s.force_rms_error_n, l.force_rms_error_n),
        (
            "mean |error|",
            s.force_mean_abs_error_pct,
            l.force_mean_abs_error_pct,
        ),
    ] {
        assert!(within(a, b, 0.01), "{what}: {a} vs {b}\n{report}");
    }
}

/// The threshold controller over the protocol without latency: the program's metrics within
/// 2 % of `cutlab sim`'s (1.3 % at most over seeds 1–4); its force error is left out — it moved
/// by up to 13 % over those seeds with the chain alone, as it does between two seeds of the
/// simulation.
#[test]
fn without_latency_a_threshold_loop_keeps_the_programs_metrics_within_two_percent() {
    // Not timed, but heavy: the tests in real time must not be starved by it.
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let spec = kim_seed_1(ControllerKind::Threshold);
    let sim = simulate(&spec).unwrap();
    let run = lockstep(kim_device(5.0), &spec, None);
    let (s, l) = (&sim.metrics, &run.result.as_ref().unwrap().metrics);
    let report = format!("sim {s:#?}\nlockstep {l:#?}");
    assert!(l.completed, "{report}");
    for (what, a, b) in [
        ("cycle time", s.cycle_time_s, l.cycle_time_s),
        ("volume", s.removed_volume_mm3, l.removed_volume_mm3),
        (
            "removal rate",
            s.mean_material_removal_mm3_s,
            l.mean_material_removal_mm3_s,
        ),
        ("peak force", s.peak_force_n, l.peak_force_n),
    ] {
        assert!(within(a, b, 0.02), "{what}: {a} vs {b}\n{report}");
    }
}

/// Issue 27 item 21: liu-current-step runs over the protocol. Its machining centre draws 25 A on
/// the spindle and about 1 A on the x axis, far under the emulator's 150 A over-current (on
/// eq 5's Table 1 the x axis drew 4 kA, and every run tripped it about 3 s in). Both fuzzy rule
/// tables run the program to its end, and the program's metrics are the simulation's.
#[test]
fn liu_current_step_runs_over_the_protocol_without_an_over_current() {
    // Not timed, but heavy: the tests in real time must not be starved by it.
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    for kind in [
        ControllerKind::FuzzyExperience,
        ControllerKind::FuzzyDynamics,
    ] {
        let spec = RunSpec::new(Preset::LiuCurrentStep, kind);
        let sim = simulate(&spec).unwrap();
        let config = DeviceConfig::new(Preset::LiuCurrentStep);
        let over_current_a = config.over_current_a;
        let run = lockstep(config, &spec, None);
        assert!(run.alarm.is_none(), "{kind}: {:?}", run.alarm);
        assert!(!run.link_lost, "{kind}: {:?}", texts(&run));
        let link = run.result.as_ref().unwrap();
        let (s, l) = (&sim.metrics, &link.metrics);
        let report = format!("{kind}: sim {s:#?}\nlockstep {l:#?}");
        assert!(l.completed, "{report}");
        // The largest RMS current either channel read is a fraction of the trip's peak.
        let peak_a = link
            .trace
            .rows
            .iter()
            .map(|r| r.spindle_current_rms_a.max(r.feed_current_rms_a))
            .fold(0.0, f64::max);
        assert!(
            peak_a * std::f64::consts::SQRT_2 < 0.4 * over_current_a,
            "{kind}: {peak_a} A"
        );
        for (what, a, b, rel) in [
            ("cycle time", s.cycle_time_s, l.cycle_time_s, 0.001),
            ("volume", s.removed_volume_mm3, l.removed_volume_mm3, 0.01),
            ("peak force", s.peak_force_n, l.peak_force_n, 0.02),
        ] {
            assert!(within(a, b, rel), "{what}: {a} vs {b}\n{report}");
        }
    }
}

#[test]
fn the_closed_loop_over_the_protocol_matches_the_simulation() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let spec = kim_threshold();
    let sim = simulate(&spec).unwrap();
    let (run, device, diagnostics) =
        host_against_emulator(kim_device(CALM_WATCHDOG_S), &spec, HostOptions::default());
    assert_like_sim(&sim, &run);
    let s = run.stats;
    assert!(!run.link_lost, "{:?}", run.events);
    assert_eq!(
        (s.frames_lost, s.bytes_dropped, s.frames_rejected),
        (0, 0, 0)
    );
    assert_eq!(device.watchdog_fallbacks, 0, "{diagnostics}");
    assert_eq!(device.parts, 2);
    // Every command but the last Disarm (sent as the host left) was acknowledged.
    assert!(s.commands_acknowledged + 1 >= s.commands_sent, "{s:?}");
    assert!(s.command_latency_mean_s < 0.06, "{s:?}");
    assert_eq!(run.device.protocol_version, "2.0");
}

#[test]
fn a_saved_calibration_replaces_the_teach_cut_over_the_link() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let spec = kim_threshold();
    let sim = simulate(&spec).unwrap();
    // Through the file, as `cutlab host --calibration` reads it.
    let saved = CalibrationFile::new(sim.calibration.clone(), "sim teach cut").to_json();
    let calibration = CalibrationFile::from_json(&saved).unwrap().calibration;
    let (run, device, diagnostics) = host_against_emulator_calibrated(
        kim_device(CALM_WATCHDOG_S),
        &spec,
        HostOptions::default(),
        Some(calibration),
    );
    // No teach part: the device's first part was the run, which finished with the target the
    // calibration gives. (How closely a run over the link follows the simulation is the test
    // above's; this one is about where the calibration came from.)
    assert_eq!(device.parts, 1, "{diagnostics}");
    let link = run.result.as_ref().unwrap();
    assert!(link.metrics.completed, "{diagnostics}");
    assert!(within(
        sim.metrics.removed_volume_mm3,
        link.metrics.removed_volume_mm3,
        0.01
    ));
    assert_eq!(sim.settings.target_force_n, link.settings.target_force_n);
    assert_eq!(
        format!("{:?}", link.calibration),
        format!("{:?}", sim.calibration)
    );
}

#[test]
fn a_bridge_without_truth_is_taught_by_the_cut_model_or_needs_a_calibration() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    // maneerat-doc-1 cuts one depth in one material: the model of the cut gives the teach force.
    let spec = RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Pi);
    let sim = simulate(&spec).unwrap();
    let mut config = DeviceConfig::new(Preset::ManeeratDoc1);
    config.watchdog_timeout_s = 5.0;
    config.sim_truth = false;
    let (run, device, diagnostics) =
        host_against_emulator(config.clone(), &spec, HostOptions::default());
    assert!(!run.device.sim_truth);
    let link = run.result.as_ref().unwrap();
    assert!(link.metrics.completed, "{diagnostics}");
    assert_eq!(device.parts, 2);
    // No truth crossed the line: the trace has estimates, not forces.
    assert!(link.trace.rows.iter().all(|r| r.force_n.is_nan()));
    // Each calibration read at its own run's current in the middle of the cut: the device's
    // sampling (1 kHz, interpolated) reads the RMS current a few percent apart from the
    // simulation's 10 kHz chain, and each model is fitted to its own.
    let at = |r: &RunResult| {
        let mid = &r.trace.rows[r.trace.rows.len() / 2];
        r.calibration.estimator.force_for_current_n(
            mid.spindle_current_rms_a,
            mid.spindle_speed_rpm,
            mid.feed_mm_min,
        )
    };
    assert!(
        within(at(link), at(&sim), 0.1),
        "cut model {} N vs truth {} N",
        at(link),
        at(&sim)
    );

    // kim-step-doc's depth steps along the part: without truth the host refuses to guess.
    let mut config = kim_device(CALM_WATCHDOG_S);
    config.sim_truth = false;
    let (run, _, _) = host_against_emulator(config, &kim_threshold(), HostOptions::default());
    let e = run.result.unwrap_err().to_string();
    assert!(e.contains("--calibration FILE"), "{e}");
}

#[test]
fn a_lossy_noisy_line_still_completes_and_the_losses_are_counted() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let spec = kim_threshold();
    let sim = simulate(&spec).unwrap();
    let mut config = kim_device(CALM_WATCHDOG_S);
    config.faults = FaultInjection {
        drop_rate: 0.01,
        noise_rate: 0.01,
        ..FaultInjection::default()
    };
    let (run, device, diagnostics) = host_against_emulator(config, &spec, HostOptions::default());
    assert_like_sim(&sim, &run);
    let s = run.stats;
    // About 2 % of 135 000 samples lost: 1 % dropped and 1 % corrupted (and rejected).
    assert!(s.frames_lost > 2000 && s.frames_lost < 3500, "{s:?}");
    assert!(s.frames_rejected > 1000, "{s:?}");
    assert!(s.bytes_dropped > 20_000, "{s:?}");
    assert!(s.commands_acknowledged < s.commands_sent, "{s:?}");
    assert!(
        device.frames_dropped > 0 && device.frames_corrupted > 0,
        "{diagnostics}"
    );
    assert_eq!(s.link_losses, 0);
}

#[test]
fn an_unplugged_cable_alarms_the_host_and_the_device_falls_back() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    // The device's watchdog (15 s of device time, 0.75 s of wall time) fires while the host's
    // (2 s of wall time, 40 s of device time) is still waiting; each is long enough that a loaded
    // machine holding a thread up for a few tenths of a second trips neither before the cable
    // comes out.
    let mut config = kim_device(15.0);
    // In the closed loop (the teach cut's part takes the first 66 s of device time).
    config.faults.unplug_at_s = Some(100.0);
    let options = HostOptions {
        link_timeout_s: 2.0,
        ..HostOptions::default()
    };
    let (run, device, diagnostics) = host_against_emulator(config, &kim_threshold(), options);
    assert!(run.link_lost);
    assert_eq!(run.stats.link_losses, 1);
    assert!(
        run.events.iter().any(|e| e.text.contains("host watchdog")),
        "{:?}",
        run.events
    );
    let result = run.result.unwrap();
    assert!(!result.metrics.completed);
    let end_s = result.trace.rows.last().unwrap().time_s;
    assert!(end_s > 25.0 && end_s < 40.0, "{end_s}");
    assert_eq!(device.watchdog_fallbacks, 1, "{diagnostics}");
    assert!(
        diagnostics.contains("fallback override 50 %"),
        "{diagnostics}"
    );
}

#[test]
fn a_stalled_receiver_fires_the_device_watchdog_and_both_sides_report_it() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    // A 12 s stall against a 10 s watchdog: the stall fires it, a hiccup of the test machine
    // (under half a second of wall time at 20×) does not. The stall outlasts the watchdog by
    // less than the device's 5 s limit on a fallback, beyond which it would latch a feed hold.
    let mut config = kim_device(10.0);
    config.faults.stall_at_s = Some(90.0);
    config.faults.stall_s = 12.0;
    let (run, device, diagnostics) =
        host_against_emulator(config, &kim_threshold(), HostOptions::default());
    assert_eq!(device.watchdog_fallbacks, 1, "{diagnostics}");
    assert!(diagnostics.contains("watchdog"), "{diagnostics}");
    assert_eq!(run.stats.watchdog_fallbacks, 1, "{:?}", run.events);
    let texts: Vec<&str> = run.events.iter().map(|e| e.text.as_str()).collect();
    assert!(
        texts.iter().any(|t| t.contains("fault watchdog raised")),
        "{texts:?}"
    );
    assert!(texts.iter().any(|t| t.contains("re-arming")), "{texts:?}");
    assert!(
        texts.iter().any(|t| t.contains("fault watchdog cleared")),
        "{texts:?}"
    );
    // Re-armed, the loop takes over again and the program completes.
    let result = run.result.unwrap();
    assert!(result.metrics.completed);
    assert!(!run.link_lost);
    // While the device held its fallback, the machine ran at 50 %.
    assert!(result
        .trace
        .rows
        .iter()
        .any(|r| (r.applied_override_pct - 50.0).abs() < 1e-9));
}

#[test]
fn a_watchdog_fallback_in_the_teach_cut_abandons_it_and_arms_no_run() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    // The same stall as above, inside the teach cut's part (its first 66 s of device time): the
    // machine runs at the fallback's 50 % while the teach schedule would label those periods
    // with its own overrides, so no calibration may be made of it, and no run follows.
    let mut config = kim_device(10.0);
    config.faults.stall_at_s = Some(20.0);
    config.faults.stall_s = 12.0;
    let (run, device, diagnostics) =
        host_against_emulator(config, &kim_threshold(), HostOptions::default());
    assert_eq!(device.watchdog_fallbacks, 1, "{diagnostics}");
    let error = run
        .result
        .expect_err("no run after an abandoned teach cut")
        .0;
    assert!(
        error.contains("the teach cut (part 1) was abandoned")
            && error.contains("watchdog fell back"),
        "{error}"
    );
    assert!(
        run.events
            .iter()
            .any(|e| e.text.starts_with("teach cut abandoned")),
        "{:?}",
        run.events
    );
    assert_eq!(device.parts, 1, "a run's part was armed: {diagnostics}");
}

/// maneerat-doc-1's PI run (an 11 s program) from the simulation's calibration, so the device's
/// first part is the run; the emulator with a watchdog that only the tests about it trip.
fn maneerat_calibrated() -> (RunSpec, RunResult, DeviceConfig) {
    let spec = RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Pi);
    let sim = simulate(&spec).unwrap();
    let mut config = DeviceConfig::new(Preset::ManeeratDoc1);
    config.watchdog_timeout_s = 5.0;
    (spec, sim, config)
}

/// [`maneerat_calibrated`]'s run over a [`LockstepLine`] with the faults `inject` sets; the run
/// and the device afterwards.
fn maneerat_faulted(inject: impl FnOnce(&mut FaultInjection)) -> (LinkRun, DeviceEmulator) {
    let (spec, sim, mut config) = maneerat_calibrated();
    inject(&mut config.faults);
    lockstep_for(config, &spec, None, Some(sim.calibration))
}

fn texts(run: &LinkRun) -> Vec<&str> {
    run.events.iter().map(|e| e.text.as_str()).collect()
}

/// docs/protocol.md §5: an over-current the device reports while the host holds it stops the
/// loop there, and the device latches the feed hold (a crash, a broken tool) until the
/// operator's reset: the host has nothing to hold and disarms at once; the hold stays.
#[test]
fn an_over_current_stops_the_loop_and_the_device_holds_the_feed_until_reset() {
    // Not timed, but heavy: the tests in real time must not be starved by it.
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (run, mut device) = maneerat_faulted(|f| {
        f.over_current_at_s = Some(6.0);
        f.over_current_s = 0.2;
    });
    let alarm = run.alarm.clone().unwrap();
    assert_eq!((alarm.kind, alarm.part), (Some(FaultKind::OverCurrent), 1));
    let result = run.result.as_ref().unwrap();
    assert!(!result.metrics.completed);
    let end_s = result.trace.rows.last().unwrap().time_s;
    assert!((5.9..6.1).contains(&end_s), "the loop ran to {end_s} s");
    let texts = texts(&run);
    assert!(
        texts
            .iter()
            .any(|t| t.contains("holds the feed, latched: the host disarms")),
        "{texts:?}"
    );
    // The device, disarmed, keeps the feed held, whatever time passes.
    let mut out = Vec::new();
    for _ in 0..3000 {
        device.step_frame(&mut out);
    }
    assert!(device.in_cycle() && !device.armed());
    assert_eq!(device.hold_latched(), Some(HoldCause::OverCurrent));
    assert!(device.feed_hold());
}

/// docs/protocol.md §5: under an E-stop the device refuses commands and the machine's axes stop,
/// so there is nothing to hold: the host stops the loop and disarms at once.
#[test]
fn an_e_stop_stops_the_loop_and_the_host_disarms_at_once() {
    // Not timed, but heavy: the tests in real time must not be starved by it.
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (run, device) = maneerat_faulted(|f| f.estop_at_s = Some(6.0));
    let alarm = run.alarm.clone().unwrap();
    assert_eq!(alarm.kind, Some(FaultKind::EStop));
    assert!(alarm.text.contains("disarms"), "{}", alarm.text);
    let result = run.result.as_ref().unwrap();
    assert!(!result.metrics.completed);
    let end_s = result.trace.rows.last().unwrap().time_s;
    assert!((5.9..6.1).contains(&end_s), "the loop ran to {end_s} s");
    assert!(
        texts(&run).iter().all(|t| !t.contains("holding")),
        "{:?}",
        texts(&run)
    );
    // Disarmed with its part stopped by the E-stop: the operator takes over at the machine.
    assert!(device.in_cycle() && !device.armed());
}

/// A loop stopped by its time limit hands the device back at once (the machine's own dial runs
/// the rest), as the teach cut's part is handed back after its schedule.
#[test]
fn a_duration_limit_hands_the_device_back_at_once() {
    // Not timed, but heavy: the tests in real time must not be starved by it.
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (spec, sim, config) = maneerat_calibrated();
    let (run, device) = lockstep_for(config, &spec, Some(5.0), Some(sim.calibration.clone()));
    let result = run.result.as_ref().unwrap();
    assert!(!result.metrics.completed && run.alarm.is_none() && !run.link_lost);
    assert!((4.9..5.1).contains(&result.trace.rows.last().unwrap().time_s));
    assert!(texts(&run).iter().all(|t| !t.contains("holding")));
    assert!(device.in_cycle() && !device.armed());
}

/// A line that plays back canned bytes from a device and swallows what the host sends.
struct Canned(Vec<u8>);

impl Line for Canned {
    fn send(&mut self, _: &[u8]) -> std::io::Result<()> {
        Ok(())
    }

    fn receive(&mut self, _: std::time::Duration) -> Result<Vec<u8>, RecvTimeoutError> {
        if self.0.is_empty() {
            Err(RecvTimeoutError::Timeout)
        } else {
            Ok(std::mem::take(&mut self.0))
        }
    }
}

fn capabilities_bytes(version_major: u8, version_minor: u8) -> Vec<u8> {
    let device = DeviceEmulator::new(DeviceConfig::new(Preset::KimStepDoc)).unwrap();
    let caps = Capabilities {
        version_major,
        version_minor,
        ..*device.capabilities()
    };
    let mut out = [0u8; MAX_FRAME_LEN];
    let n = encode_frame(&Frame::Capabilities(caps), &mut out).unwrap();
    out[..n].to_vec()
}

/// docs/protocol.md §6: a host refuses a device of another major version before arming it, and
/// says which versions met; a newer minor version of its own major is accepted.
#[test]
fn a_device_of_another_major_version_is_refused_naming_both_versions() {
    let options = HostOptions {
        handshake_timeout_s: 1.0,
        ..HostOptions::default()
    };
    let e = HostLink::connect_line(Box::new(Canned(capabilities_bytes(1, 3))), options)
        .err()
        .unwrap();
    assert!(
        e.0.contains("the device speaks protocol 1.3; this host speaks 2.0"),
        "{e}"
    );
    let link = HostLink::connect_line(Box::new(Canned(capabilities_bytes(2, 7))), options).unwrap();
    assert_eq!(link.capabilities().version_minor, 7);
}

/// `cat /dev/urandom | cutlab device --stdio` once grew to 1.2 GB in 5 s and starved the
/// device's clock: its reader queued every chunk it could read, and the device took every queued
/// chunk before it stepped the machine. Now the reader waits when 16 chunks are queued (the pipe
/// and the writer wait with it) and the device takes at most two chunks between two runs of the
/// frames that are due. A flood of random bytes for one second of wall time, in-process.
#[test]
fn a_flood_on_the_device_input_is_held_back_and_the_device_keeps_its_clock() {
    use std::io::Write;
    use std::time::Instant;
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    const FLOOD_S: f64 = 1.0;
    let (reader, mut writer) = std::io::pipe().unwrap();
    let flooder = std::thread::spawn(move || {
        let mut rng = cutlab::rng::Rng::seed_from(9);
        let junk: Vec<u8> = (0..65_536).map(|_| rng.next_u64() as u8).collect();
        let start = Instant::now();
        let mut written = 0u64;
        while start.elapsed().as_secs_f64() < FLOOD_S {
            match writer.write(&junk) {
                Ok(n) => written += n as u64,
                Err(_) => break,
            }
        }
        // The writer is dropped here: the device's input ends.
        written
    });
    let mut device = DeviceEmulator::new(kim_device(5.0)).unwrap();
    let (mut out, mut diagnostics) = (Vec::new(), Vec::new());
    let start = Instant::now();
    let run = run_device(
        &mut device,
        reader,
        &mut out,
        &mut diagnostics,
        None,
        TIME_SCALE,
    );
    let wall_s = start.elapsed().as_secs_f64();
    let written = flooder.join().unwrap();
    let diagnostics = String::from_utf8_lossy(&diagnostics);
    assert_eq!(run.exit, DeviceExit::InputClosed);
    // Memory: never more than the queue and the chunk the reader holds.
    assert!(
        run.peak_queued_bytes <= (DEVICE_QUEUE_CHUNKS + 1) * READ_CHUNK,
        "{run:?}"
    );
    // A flood it was, and every byte of it went through the device's decoder.
    assert!(written > 1_000_000, "{written} bytes");
    assert_eq!(device.decoder_stats().bytes_received, written);
    assert!(
        diagnostics.contains("bytes of input queued"),
        "{diagnostics}"
    );
    // The clock kept pace with the wall clock, and the heartbeats with it: one per 0.1 s of
    // device time. (Starved, it made 15 % of them; half leaves room for a busy machine.)
    let expected = wall_s * TIME_SCALE / 0.1;
    let heartbeats = cutlab::protocol::codec::Decoder::new()
        .frames(&out)
        .filter(|f| matches!(f, Ok(cutlab::protocol::frame::Frame::Heartbeat(_))))
        .count() as f64;
    println!(
        "flood: {written} bytes in {wall_s:.2} s, {heartbeats} heartbeats of {expected:.0}, \
         {:.1} s of device time, at most {} bytes queued",
        device.time_s(),
        run.peak_queued_bytes
    );
    assert!(
        heartbeats >= 0.5 * expected && device.time_s() >= 0.5 * wall_s * TIME_SCALE,
        "{heartbeats} heartbeats and {} s of device time in {wall_s} s at {TIME_SCALE}x",
        device.time_s()
    );
}

/// A scratch directory for one test's files.
#[cfg(feature = "cli")]
fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("cutlab-host-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `cutlab host ARGS… --json DIR/host.json` as a process: its output and the report, if any.
#[cfg(feature = "cli")]
fn cutlab_host(
    dir: &std::path::Path,
    args: &[&str],
) -> (std::process::Output, Option<serde_json::Value>) {
    let json = dir.join("host.json");
    let _ = std::fs::remove_file(&json);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_cutlab"))
        .arg("host")
        .args(args)
        .args(["--json", json.to_str().unwrap()])
        .output()
        .unwrap();
    let report = std::fs::read_to_string(&json)
        .ok()
        .map(|text| serde_json::from_str(&text).unwrap());
    (out, report)
}

/// The whole thing as a person types it: `cutlab host --device-cmd "cutlab device …"`, two
/// processes, a teach cut and a closed loop to the program's end, and the savings against the
/// simulated preset's fixed-feed references.
#[cfg(feature = "cli")]
#[test]
fn the_binary_runs_the_host_against_the_binary_device() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let exe = env!("CARGO_BIN_EXE_cutlab");
    let dir = scratch("binary");
    let device =
        format!("{exe} device --stdio --scenario maneerat-doc-1 --time-scale 20 --watchdog-s 20");
    let (out, report) = cutlab_host(&dir, &["--device-cmd", &device, "--controller", "pi"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert!(stdout.contains("link: protocol 2.0"), "{stdout}");
    assert!(stdout.contains("references: simulated"), "{stdout}");
    // The device's diagnostics, and the host's events as they happened.
    assert!(stderr.contains("part 2: cycle start"), "{stderr}");
    assert!(stderr.contains("host: part 2"), "{stderr}");
    let report = report.unwrap();
    for key in [
        "protocol_version",
        "frames_received",
        "frames_lost",
        "bytes_dropped",
        "commands_sent",
        "commands_acknowledged",
        "watchdog_fallbacks",
        "link_losses",
        "events",
        "metrics",
        "calibration",
    ] {
        assert!(report.get(key).is_some(), "{key} missing from {report}");
    }
    assert_eq!(report["protocol_version"], "2.0");
    assert_eq!(report["link_losses"], 0);
    assert_eq!(report["error"], serde_json::Value::Null);
    assert_eq!(report["metrics"]["completed"], true);
    // Savings against the simulated preset's references, and the report says they are simulated.
    assert!(
        report["references"]["programmed_cycle_time_s"]
            .as_f64()
            .unwrap()
            > 0.0
    );
    assert!(
        report["metrics"]["saving_vs_programmed_pct"].is_f64(),
        "{report}"
    );
    assert!(report["references_source"]
        .as_str()
        .unwrap()
        .starts_with("simulated"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// An engine file runs on the machine as in `cutlab sim`: `--fuzzy-engine` gives the
/// fuzzy-engine controller its engine over the link, and is refused where no controller runs it.
#[cfg(feature = "cli")]
#[test]
fn the_host_runs_an_imported_fuzzy_engine() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let exe = env!("CARGO_BIN_EXE_cutlab");
    let dir = scratch("engine");
    let engine_path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/www/data/paper-002-experience.fll"
    );
    let engine_text = std::fs::read_to_string(engine_path).unwrap();
    let device =
        format!("{exe} device --stdio --scenario maneerat-doc-1 --time-scale 20 --watchdog-s 20");
    let (out, report) = cutlab_host(
        &dir,
        &[
            "--device-cmd",
            &device,
            "--controller",
            "fuzzy-engine",
            "--fuzzy-engine",
            engine_path,
            "--no-references",
        ],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let report = report.unwrap();
    assert_eq!(report["metrics"]["completed"], true, "{report}");
    assert_eq!(report["controller"]["kind"], "fuzzy-engine", "{report}");
    assert_eq!(
        report["controller"]["engine"].as_str(),
        Some(engine_text.as_str()),
        "the report names the engine that ran"
    );
    // Given to a controller that does not run it, it is refused before anything connects.
    let (out, _) = cutlab_host(
        &dir,
        &[
            "--device-cmd",
            &device,
            "--controller",
            "pi",
            "--fuzzy-engine",
            engine_path,
        ],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(stderr.contains("no controller runs it"), "{stderr}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A device command that answers Hello with `caps` (from a file, through `cutlab protocol
/// encode`) and then says nothing more for a second.
#[cfg(feature = "cli")]
fn canned_device(dir: &std::path::Path, caps: &Capabilities) -> String {
    let path = dir.join("caps.jsonl");
    let line = cutlab::protocol::json::frame_to_json(&Frame::Capabilities(*caps));
    std::fs::write(&path, format!("{line}\n")).unwrap();
    format!(
        "{} protocol encode < {}; sleep 1",
        env!("CARGO_BIN_EXE_cutlab"),
        path.display()
    )
}

/// A link lost before the run (a device that shakes hands and then sends no sample) fails the
/// command, and `--json` still gets the report: the link's counts, its events and the error. A
/// device of protocol 2.x is refused, naming both versions, and gets a report too.
#[cfg(feature = "cli")]
#[test]
fn the_report_is_written_when_the_link_is_lost_in_the_teach_cut_or_the_device_is_refused() {
    let dir = scratch("no-run");
    let emulator = DeviceEmulator::new(DeviceConfig::new(Preset::KimStepDoc)).unwrap();
    let caps = *emulator.capabilities();
    let device = canned_device(&dir, &caps);
    let args = [
        "--device-cmd",
        &device,
        "--controller",
        "threshold",
        "--link-timeout-s",
        "0.3",
    ];
    let (out, report) = cutlab_host(&dir, &args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("the teach cut (part 1) was abandoned"),
        "{stderr}"
    );
    let report = report.unwrap();
    assert_eq!(report["protocol_version"], "2.0");
    assert_eq!(report["frames_received"], 1);
    assert_eq!(report["link_losses"], 1);
    assert_eq!(report["link_lost"], true);
    assert_eq!(report["metrics"], serde_json::Value::Null);
    assert!(
        report["error"].as_str().unwrap().contains("host watchdog"),
        "{report}"
    );
    let events = report["events"].as_array().unwrap();
    // The teach cut's part was armed; the run's, on a link already lost, is not.
    let arms = events
        .iter()
        .filter(|e| e["event"].as_str().unwrap().contains("arm (cycle start)"))
        .count();
    assert_eq!(arms, 1, "{report}");
    assert!(!stderr.contains("part 2, 0.000 s: arm"), "{stderr}");

    let newer = Capabilities {
        version_major: 3,
        version_minor: 0,
        ..caps
    };
    let device = canned_device(&dir, &newer);
    let (out, report) = cutlab_host(&dir, &["--device-cmd", &device, "--controller", "pi"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("the device speaks protocol 3.0; this host speaks 2.0"),
        "{stderr}"
    );
    let report = report.unwrap();
    assert_eq!(report["device"], serde_json::Value::Null);
    assert_eq!(report["frames_received"], serde_json::Value::Null);
    assert!(report["error"].as_str().unwrap().contains("protocol 3.0"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `cutlab host` running PI against maneerat-doc-1's emulated device (20× its time, a 20 s
/// watchdog: a second of wall time) whose cable is pulled at `unplug_at_s` of device time; the
/// host waits 1 s (both long enough that a loaded machine holding a process up for a few tenths
/// of a second trips neither before the cable comes out).
#[cfg(feature = "cli")]
fn pi_host_unplugged_at(
    dir: &std::path::Path,
    unplug_at_s: f64,
) -> (std::process::Output, Option<serde_json::Value>) {
    let exe = env!("CARGO_BIN_EXE_cutlab");
    let device = format!(
        "{exe} device --stdio --scenario maneerat-doc-1 --time-scale 20 --watchdog-s 20 \
         --unplug-at-s {unplug_at_s}"
    );
    cutlab_host(
        dir,
        &[
            "--device-cmd",
            &device,
            "--controller",
            "pi",
            "--link-timeout-s",
            "1",
        ],
    )
}

/// A link lost in the middle of the teach cut: the command fails saying the teach cut was
/// abandoned, and no second part is armed on the dead link (no "arm (cycle start)" line for it).
#[cfg(feature = "cli")]
#[test]
fn a_link_lost_in_the_teach_cut_arms_no_further_part() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let dir = scratch("lost-teach");
    // The teach cut's part takes about 15 s of device time: the cable goes 8 s into it.
    let (out, report) = pi_host_unplugged_at(&dir, 8.0);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(
        stderr.contains("the teach cut (part 1) was abandoned"),
        "{stderr}"
    );
    assert!(!stderr.contains("part 2, 0.000 s: arm"), "{stderr}");
    let report = report.unwrap();
    let arms = report["events"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["event"].as_str().unwrap().contains("arm (cycle start)"))
        .count();
    assert_eq!(arms, 1, "{report}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A link lost in the closed loop: the results up to there are printed and written, and the
/// command fails, as `cutlab sim` fails on a controller fault.
#[cfg(feature = "cli")]
#[test]
fn a_link_lost_in_the_closed_loop_fails_the_command_with_the_results_written() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let dir = scratch("lost");
    // The teach cut's part takes about 15 s of device time: the cable goes 7 s into the run.
    let (out, report) = pi_host_unplugged_at(&dir, 22.0);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stdout}\n{stderr}");
    assert!(stdout.contains("Cycle time"), "{stdout}");
    assert!(
        stdout.contains("references: none: the run did not complete"),
        "{stdout}"
    );
    assert!(
        stderr.contains("the program did not finish under control"),
        "{stderr}"
    );
    let report = report.unwrap();
    assert_eq!(report["link_lost"], true);
    assert_eq!(report["metrics"]["completed"], false);
    let cycle_time_s = report["metrics"]["cycle_time_s"].as_f64().unwrap();
    assert!((5.0..8.0).contains(&cycle_time_s), "{report}");
    assert!(
        report["metrics"]["controlled_cutting_time_s"]
            .as_f64()
            .unwrap()
            > 1.0
    );
    assert_eq!(report["error"], serde_json::Value::Null);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `cutlab device --stdio --scenario kim-step-doc --time-scale 10 EXTRA…` as a process, its stdin
/// piped.
#[cfg(feature = "cli")]
fn kim_device_process(
    extra: &[&str],
    stdout: std::process::Stdio,
    stderr: std::process::Stdio,
) -> std::process::Child {
    std::process::Command::new(env!("CARGO_BIN_EXE_cutlab"))
        .args([
            "device",
            "--stdio",
            "--scenario",
            "kim-step-doc",
            "--time-scale",
            "10",
        ])
        .args(extra)
        .stdin(std::process::Stdio::piped())
        .stdout(stdout)
        .stderr(stderr)
        .spawn()
        .unwrap()
}

/// `cutlab device` survives any bytes on stdin: random bytes in, only frames out (heartbeats,
/// nothing armed it), and it ends when stdin closes.
#[cfg(feature = "cli")]
#[test]
fn the_device_binary_survives_garbage_on_stdin_and_writes_only_frames() {
    use std::io::Write;
    use std::process::Stdio;
    let mut child = kim_device_process(&[], Stdio::piped(), Stdio::piped());
    let mut stdin = child.stdin.take().unwrap();
    let mut rng = cutlab::rng::Rng::seed_from(8);
    for _ in 0..20 {
        let junk: Vec<u8> = (0..512).map(|_| rng.next_u64() as u8).collect();
        stdin.write_all(&junk).unwrap();
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    drop(stdin);
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    let mut decoder = cutlab::protocol::codec::Decoder::new();
    let frames: Vec<_> = decoder.frames(&out.stdout).collect();
    assert!(frames.len() > 10);
    assert!(frames
        .iter()
        .all(|f| matches!(f, Ok(cutlab::protocol::frame::Frame::Heartbeat(_)))));
    assert_eq!(decoder.stats().bytes_dropped, 0);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("bytes dropped by the decoder"), "{stderr}");
}

#[cfg(feature = "cli")]
mod common;

#[cfg(feature = "cli")]
#[test]
fn host_and_device_options_are_checked_with_messages_that_name_them() {
    let error = |args: &[&str]| common::cutlab_text(args, "").0.unwrap_err();
    assert!(error(&["device", "--scenario", "kim-step-doc"]).contains("--stdio is required"));
    assert!(error(&["device", "--stdio", "--scenario", "nope"]).contains("unknown preset"));
    assert!(error(&[
        "device",
        "--stdio",
        "--scenario",
        "kim-step-doc",
        "--stall-at-s",
        "3"
    ])
    .contains("--stall-s"));
    assert!(error(&[
        "device",
        "--stdio",
        "--scenario",
        "kim-step-doc",
        "--drop-rate",
        "2"
    ])
    .contains("drop rate"));
    assert!(error(&["host", "--controller", "threshold"]).contains("--device-cmd"));
    assert!(error(&["host", "--device-cmd", "true"]).contains("--controller"));
    assert!(error(&[
        "host",
        "--port",
        "/nonexistent/tty",
        "--controller",
        "threshold"
    ])
    .contains("cannot open"));
    // A parameter given twice is refused before any link is opened, as `cutlab sim` refuses it.
    let twice = error(&[
        "host",
        "--device-cmd",
        "true",
        "--controller",
        "pi",
        "--set",
        "kp=0.5",
        "--set",
        "kp=0.9",
    ]);
    assert!(
        twice.contains("--set: kp is given twice (kp=0.5, then kp=0.9)"),
        "{twice}"
    );
    // A device that says nothing: the handshake gives up and says so.
    let e = error(&[
        "host",
        "--device-cmd",
        "cat > /dev/null",
        "--controller",
        "threshold",
        "--link-timeout-s",
        "0.3",
    ]);
    assert!(e.contains("no answer to Hello"), "{e}");
}

/// A device that sends nothing but garbage: the handshake gives up, and every byte that was part
/// of no frame is counted dropped — a line of zeros (all frame delimiters) included, which the
/// decoder used to take for silence ("0 of them dropped").
#[cfg(feature = "cli")]
#[test]
fn a_device_that_sends_only_garbage_is_reported_with_its_bytes_dropped() {
    let error = |args: &[&str]| common::cutlab_text(args, "").0.unwrap_err();
    // (device, bytes received less bytes dropped): of a line of zeros, the first could stand
    // between two frames.
    for (device, kept) in [("cat /dev/zero", 1), ("yes", 0)] {
        let e = error(&[
            "host",
            "--device-cmd",
            device,
            "--controller",
            "threshold",
            "--link-timeout-s",
            "0.1",
        ]);
        let count = |after: &str| -> u64 {
            let (head, _) = e.split_once(after).unwrap_or_else(|| panic!("{e}"));
            let word = head.rsplit([' ', '(']).next().unwrap_or_default();
            word.parse().unwrap_or_else(|_| panic!("{word:?} in {e}"))
        };
        let received = count(" bytes received");
        let dropped = count(" of them dropped (part of no frame)");
        assert!(e.contains("no answer to Hello"), "{e}");
        assert!(received > 1000, "{device}: {e}");
        assert_eq!(dropped + kept, received, "{device}: {e}");
    }
}

/// Each part is a `Machine`: its first step arms the device and a fresh part starts at time
/// zero; a part left before its program's end is disarmed and run out before the next starts.
#[test]
fn parts_are_machines_and_a_part_left_early_is_run_out_before_the_next() {
    use cutlab::machine::{Machine, OverrideCommand};
    use cutlab::protocol::link::LinkPart;
    use std::cell::RefCell;
    use std::rc::Rc;
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (host_to_device_r, host_to_device_w) = std::io::pipe().unwrap();
    let (device_to_host_r, mut device_to_host_w) = std::io::pipe().unwrap();
    let device = std::thread::spawn(move || {
        let mut d = DeviceEmulator::new(kim_device(5.0)).unwrap();
        let mut sink = Vec::new();
        run_device(
            &mut d,
            host_to_device_r,
            &mut device_to_host_w,
            &mut sink,
            None,
            TIME_SCALE,
        );
        d.stats()
    });
    let link = HostLink::connect(
        device_to_host_r,
        Box::new(host_to_device_w),
        HostOptions::default(),
    )
    .unwrap();
    let link = Rc::new(RefCell::new(link));
    let mut first = LinkPart::new(Rc::clone(&link));
    assert_eq!(first.sample_rate_hz(), 1000.0);
    let command = OverrideCommand {
        override_pct: 87.6,
        feed_hold: false,
    };
    let mut last = first.step(command);
    for _ in 0..2000 {
        last = first.step(command);
    }
    assert!(
        (last.sensors.time_s - 2.001).abs() < 1e-6,
        "{}",
        last.sensors.time_s
    );
    // kim-step-doc's override is whole percent: 87.6 % applies as 88 %.
    assert_eq!(last.sensors.applied_override_pct, 88.0);
    assert!(last.truth.is_some() && !first.finished());
    let mut second = LinkPart::new(Rc::clone(&link));
    let s = second.step(OverrideCommand::default());
    assert!(
        (s.sensors.time_s - 0.001).abs() < 1e-6,
        "{}",
        s.sensors.time_s
    );
    let events = link.borrow().session().events().to_vec();
    assert!(
        events.iter().any(|e| e.text.contains("still running")),
        "{events:?}"
    );
    assert!(
        events.iter().any(|e| e.part == 2 && e.text.contains("arm")),
        "{events:?}"
    );
    drop(first);
    drop(second);
    drop(link);
    let stats = device.join().unwrap();
    assert_eq!((stats.parts, stats.watchdog_fallbacks), (2, 0));
}

// ── Issue 31: every fault path of the fail-safe design, one test each ──────────────────────────

/// The frame bytes of `frame`.
fn wire(frame: Frame) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = encode_frame(&frame, &mut buf).unwrap();
    buf[..n].to_vec()
}

/// The Acks among the bytes a device sent.
fn acks(bytes: &[u8]) -> Vec<cutlab::protocol::frame::Ack> {
    cutlab::protocol::codec::Decoder::new()
        .frames(bytes)
        .filter_map(|f| match f {
            Ok(Frame::Ack(a)) => Some(a),
            _ => None,
        })
        .collect()
}

fn set_override(seq: u32, pct: u16, sample_time_us: u32) -> Frame {
    Frame::SetOverride(cutlab::protocol::frame::SetOverride {
        seq,
        override_cpct: pct * 100,
        flags: 0,
        sample_time_us,
    })
}

/// A link lost after the loop cut the feed to 30 % keeps at most 30 %: the fallback is the lower
/// of the applied and the configured 50 % (before, the fixed 50 % raised the feed by 67 % into
/// the section that had needed 30 %); and the fallback's time limit ends in a latched feed hold.
#[test]
fn a_link_loss_after_the_loop_cut_to_30_percent_keeps_30_and_its_time_limit_ends_in_a_hold() {
    use cutlab::protocol::frame::{fault_flag, Arm};
    let mut config = DeviceConfig::new(Preset::KimStepDoc);
    config.fallback_limit_s = 2.0;
    config.trace = true;
    let mut d = DeviceEmulator::new(config).unwrap();
    let mut out = Vec::new();
    d.receive(&wire(Frame::Arm(Arm { seq: 1 })), &mut out);
    d.receive(&wire(set_override(2, 30, 0)), &mut out);
    assert_eq!(d.applied_override_pct(), 30.0);
    // The host goes quiet: 0.5 s of watchdog, then 2 s of fallback, then the hold.
    for _ in 0..3000 {
        d.step_frame(&mut out);
    }
    let trace = d.take_trace();
    let fallback: Vec<_> = trace.iter().filter(|r| r.fallback).collect();
    assert!(!fallback.is_empty());
    assert!(
        fallback.iter().all(|r| r.bridge_override_pct <= 30.0),
        "the fallback raised the feed: {:?}",
        fallback[0]
    );
    let first_fallback_s = fallback[0].time_s;
    assert!(
        (0.5..0.52).contains(&first_fallback_s),
        "{first_fallback_s}"
    );
    let held = trace.iter().find(|r| r.hold_latched.is_some()).unwrap();
    assert!(
        (held.time_s - first_fallback_s - 2.0).abs() < 0.01,
        "held at {} s",
        held.time_s
    );
    assert_eq!(held.hold_latched, Some(HoldCause::FallbackLimit));
    assert_ne!(held.faults & fault_flag::FALLBACK_LIMIT, 0);
    let last = trace.last().unwrap();
    assert!(last.feed_hold && last.feed_mm_min.abs() < 0.01, "{last:?}");
}

/// The same from outside, as a person checks it: `cutlab device --trace` writes what the bridge
/// applied at each sample while a host that set 30 % went quiet.
#[cfg(feature = "cli")]
#[test]
fn the_device_trace_shows_the_fallback_at_30_percent_and_then_the_hold() {
    use std::io::Write;
    use std::process::Stdio;
    let dir = scratch("trace");
    let trace = dir.join("trace.csv");
    let mut child = kim_device_process(
        &[
            "--fallback-limit-s",
            "2",
            "--trace",
            trace.to_str().unwrap(),
        ],
        Stdio::null(),
        Stdio::null(),
    );
    let mut stdin = child.stdin.take().unwrap();
    stdin
        .write_all(&wire(Frame::Arm(cutlab::protocol::frame::Arm { seq: 1 })))
        .unwrap();
    stdin.write_all(&wire(set_override(2, 30, 0))).unwrap();
    stdin.flush().unwrap();
    // 4 device seconds: 0.5 s of watchdog, 2 s of fallback, then the hold.
    std::thread::sleep(std::time::Duration::from_millis(400));
    drop(stdin);
    assert!(child.wait().unwrap().success());
    let text = std::fs::read_to_string(&trace).unwrap();
    let mut lines = text.lines();
    assert!(lines
        .next()
        .unwrap()
        .starts_with("time_s,part,seq,armed,fallback,feed_hold"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let fallback: Vec<_> = rows.iter().filter(|r| r[4] == "1").collect();
    assert!(!fallback.is_empty(), "{text}");
    assert!(fallback
        .iter()
        .all(|r| r[7].parse::<f64>().unwrap() <= 30.0));
    assert!(
        rows.iter()
            .any(|r| r[6] == "fallback time limit" && r[5] == "1"),
        "no latched hold in the trace"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A replayed command (its sequence number not newer) and one decided on a sample older than the
/// device's watchdog timeout are ignored, acknowledged as stale; a Hello starts a new session.
#[test]
fn a_stale_or_replayed_command_is_ignored() {
    use cutlab::protocol::frame::{AckResult, Arm, Hello};
    let mut d = DeviceEmulator::new(DeviceConfig::new(Preset::KimStepDoc)).unwrap();
    let mut out = Vec::new();
    d.receive(&wire(Frame::Arm(Arm { seq: 1 })), &mut out);
    for i in 0..1000 {
        if i % 100 == 0 {
            d.receive(&wire(Frame::Heartbeat(Default::default())), &mut out);
        }
        d.step_frame(&mut out);
    }
    let now_us = (d.time_s() * 1e6) as u32;
    out.clear();
    d.receive(&wire(set_override(5, 80, now_us)), &mut out);
    d.receive(&wire(set_override(5, 120, now_us)), &mut out); // replayed seq
    d.receive(&wire(set_override(4, 120, now_us)), &mut out); // older seq
    d.receive(&wire(set_override(6, 120, now_us - 600_000)), &mut out); // a stale sample
    let results: Vec<_> = acks(&out).iter().map(|a| a.result).collect();
    assert_eq!(
        results,
        [
            AckResult::Applied,
            AckResult::Stale,
            AckResult::Stale,
            AckResult::Stale
        ]
    );
    assert_eq!(d.applied_override_pct(), 80.0);
    out.clear();
    d.receive(
        &wire(Frame::Hello(Hello {
            version_major: 2,
            version_minor: 0,
        })),
        &mut out,
    );
    d.receive(&wire(set_override(1, 90, now_us)), &mut out);
    assert_eq!(acks(&out)[0].result, AckResult::Applied);
    assert_eq!(d.applied_override_pct(), 90.0);
}

/// A device whose stream does not fit its line with the headroom is refused at the handshake,
/// by the native host and by the Hardware page's session alike.
#[test]
fn a_handshake_whose_line_budget_does_not_fit_is_refused() {
    use cutlab::hardware::session::{HardwareSession, LinkState, SessionOptions};
    let device = |baud: u32, truth: bool| {
        let mut config = DeviceConfig::new(Preset::KimStepDoc);
        config.line_baud = baud;
        config.sim_truth = truth;
        Rc::new(RefCell::new(DeviceEmulator::new(config).unwrap()))
    };
    for (baud, truth, fits) in [
        (921_600, false, true),
        (921_600, true, false),
        (115_200, false, false),
        (0, true, true),
    ] {
        let line = Box::new(LockstepLine::new(device(baud, truth)));
        let got = HostLink::connect_line(line, HostOptions::default());
        assert_eq!(got.is_ok(), fits, "{baud} baud, truth {truth}");
        if let Err(e) = got {
            assert!(e.0.contains("cannot carry its stream"), "{e}");
        }
        let d = device(baud, truth);
        let mut session = HardwareSession::new(SessionOptions::default(), 0.0);
        let mut answer = Vec::new();
        d.borrow_mut().receive(&session.take_output(), &mut answer);
        session.receive(&answer, 0.01);
        let state = session.state();
        assert_eq!(state == LinkState::Streaming, fits, "{}", session.reason());
    }
}

/// A control period set shorter than the handshake allowed for asks the line for an Ack a
/// period: both hosts refuse to arm a run whose commands do not fit, and say what to change.
#[test]
fn a_control_period_too_short_for_the_line_is_refused_before_arming() {
    use cutlab::hardware::session::{check_line, HardwareSession, LinkState, SessionOptions};
    let mut config = DeviceConfig::new(Preset::ManeeratDoc1);
    config.line_baud = 921_600;
    config.sim_truth = false;
    let caps = *DeviceEmulator::new(config.clone()).unwrap().capabilities();
    let mut spec = RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Threshold);
    assert_eq!(check_line(&caps, &spec), Ok(()));
    spec.settings.control_period_s = Some(0.001);
    let why = check_line(&caps, &spec).unwrap_err();
    assert!(why.contains("lengthen the control period"), "{why}");

    // The native host: refused before the teach cut's first command.
    let run = lockstep(config.clone(), &spec, None);
    let e = run.result.unwrap_err();
    assert!(e.0.contains("lengthen the control period"), "{e}");

    // The Hardware page's session: streaming, yet the teach cut is not armed.
    let device = Rc::new(RefCell::new(DeviceEmulator::new(config).unwrap()));
    let mut session = HardwareSession::new(SessionOptions::default(), 0.0);
    let mut answer = Vec::new();
    device
        .borrow_mut()
        .receive(&session.take_output(), &mut answer);
    session.receive(&answer, 0.01);
    assert_eq!(
        session.state(),
        LinkState::Streaming,
        "{}",
        session.reason()
    );
    let refused = session.start_teach_cut(&spec, 0.02).unwrap_err();
    assert!(refused.contains("lengthen the control period"), "{refused}");
    assert_eq!(session.state(), LinkState::Streaming);
}

/// An open transducer (it reads 0 A) breaks its drive's three-phase sum: the device raises a
/// sensor fault naming the channel and the host's alarm stops the loop within a second.
#[test]
fn an_open_sensor_raises_its_alarm_within_a_second() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (run, _) = maneerat_faulted(|f| f.sensor_open_at_s = Some(6.0));
    let alarm = run.alarm.clone().unwrap();
    assert_eq!(alarm.kind, Some(FaultKind::Sensor), "{}", alarm.text);
    let result = run.result.as_ref().unwrap();
    let end_s = result.trace.rows.last().unwrap().time_s;
    assert!((6.0..7.0).contains(&end_s), "the loop ran to {end_s} s");
    assert!(
        texts(&run)
            .iter()
            .any(|t| t.contains("device fault sensor raised, channel 0")),
        "{:?}",
        texts(&run)
    );
}

/// A CNC that ignores the bridge's outputs (the selector on the dial, a dead output, a ladder
/// that does not take the code) moves at another feed than the override the bridge applies:
/// the host alarms within a second of the first step the CNC did not follow. Here the teach
/// cut's 30 % step, 1.5 s in, which the machine, stuck at 100 %, never takes.
#[test]
fn a_stuck_override_raises_its_alarm_within_a_second() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let spec = RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Pi);
    let mut config = DeviceConfig::new(Preset::ManeeratDoc1);
    config.watchdog_timeout_s = 5.0;
    config.faults.stuck_override_at_s = Some(0.0);
    let run = lockstep(config, &spec, None);
    let error = run.result.as_ref().err().unwrap().0.clone();
    assert!(error.contains("stuck override"), "{error}");
    let alarm = run.alarm.clone().unwrap();
    assert_eq!(alarm.kind, None);
    let at = run
        .events
        .iter()
        .find(|e| e.text.starts_with("stuck override"))
        .unwrap();
    assert!((1.5..2.5).contains(&at.time_s), "alarm at {} s", at.time_s);
}

/// A line that loses every Sample frame carrying "program end".
struct LosesProgramEnd {
    inner: LockstepLine,
    decoder: cutlab::protocol::codec::Decoder,
    lost: usize,
}

impl Line for LosesProgramEnd {
    fn send(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.inner.send(bytes)
    }

    fn receive(&mut self, timeout: std::time::Duration) -> Result<Vec<u8>, RecvTimeoutError> {
        use cutlab::protocol::frame::sample_flag;
        let bytes = self.inner.receive(timeout)?;
        let mut kept = Vec::new();
        for b in bytes {
            match self.decoder.push(b) {
                Some(Ok(Frame::Sample(s))) if s.flags & sample_flag::PROGRAM_END != 0 => {
                    self.lost += 1
                }
                Some(Ok(f)) => kept.extend(wire(f)),
                _ => {}
            }
        }
        Ok(kept)
    }
}

/// Issue 27 item 20: one lost "program end" frame made the host declare the link lost and
/// abandon the run while the device ended the part and kept sending heartbeats. The heartbeat
/// says no program runs any more: the host takes that as the end.
#[test]
fn a_lost_program_end_sample_is_taken_from_the_devices_heartbeat() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (spec, sim, config) = maneerat_calibrated();
    let config_again = config.clone();
    let device = Rc::new(RefCell::new(DeviceEmulator::new(config).unwrap()));
    let line = Box::new(LosesProgramEnd {
        inner: LockstepLine::new(Rc::clone(&device)),
        decoder: cutlab::protocol::codec::Decoder::new(),
        lost: 0,
    });
    let link = HostLink::connect_line(line, HostOptions::default()).unwrap();
    let run = run_on_link(link, &spec, None, Some(sim.calibration.clone()));
    assert!(!run.link_lost, "{:?}", texts(&run));
    let result = run.result.as_ref().unwrap();
    assert!(result.metrics.completed, "{:?}", texts(&run));
    // The same run on a line that loses nothing ends one sample later, at most.
    let whole = lockstep(config_again, &spec, Some(sim.calibration.clone()));
    let whole_s = whole.result.unwrap().metrics.cycle_time_s;
    assert!(
        (result.metrics.cycle_time_s - whole_s).abs() <= 0.0011,
        "{} s with the end sample lost, {whole_s} s without",
        result.metrics.cycle_time_s
    );
    assert!(texts(&run)
        .iter()
        .any(|t| t.contains("the device's heartbeat says the part ended")));
}

/// Issue 27 items 2 and 3: numbers of seconds far out of range are refused with a message, not
/// a panic converting them to a wait; and `--json` is written for an option error too.
#[cfg(feature = "cli")]
#[test]
fn seconds_out_of_range_are_refused_and_the_report_is_written_for_option_errors() {
    let error = |args: &[&str]| common::cutlab_text(args, "").0.unwrap_err();
    let e = error(&[
        "host",
        "--device-cmd",
        "true",
        "--controller",
        "pi",
        "--link-timeout-s",
        "1e300",
    ]);
    assert!(
        // The Hardware page's words for its Host watchdog field, with the option.
        e.contains("--link-timeout-s: 1e300 s is outside 0.1–60 s"),
        "{e}"
    );
    let e = error(&[
        "device",
        "--stdio",
        "--scenario",
        "kim-step-doc",
        "--time-scale",
        "1e-300",
    ]);
    // The words the Hardware page's virtual device shows beside its Time scale field, with the
    // option named (one row of the device table).
    assert!(
        e.contains("--time-scale: time scale 1e-300 is outside 0.01–1000"),
        "{e}"
    );
    let dir = scratch("option-error");
    let (out, report) = cutlab_host(
        &dir,
        &[
            "--device-cmd",
            "true",
            "--controller",
            "pi",
            "--link-timeout-s",
            "-1",
        ],
    );
    assert!(!out.status.success());
    let report = report.expect("the report, written whatever happens");
    assert!(
        report["error"]
            .as_str()
            .unwrap()
            .contains("--link-timeout-s"),
        "{report}"
    );
    assert_eq!(report["metrics"], serde_json::Value::Null);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 27 item 19: `cutlab host` left its `--device-cmd` child running when it gave up (the
/// shell killed, what it started reparented to PID 1). Now the child's whole process group ends
/// with the host, on every way out.
#[cfg(feature = "cli")]
#[test]
fn the_device_command_and_what_it_started_end_with_the_host() {
    let dir = scratch("child");
    let pid_file = dir.join("pid");
    let device = format!("sleep 30 & echo $! > {}; wait", pid_file.display());
    let (out, _) = cutlab_host(
        &dir,
        &[
            "--device-cmd",
            &device,
            "--controller",
            "pi",
            "--link-timeout-s",
            "0.2",
        ],
    );
    assert!(!out.status.success());
    let pid = std::fs::read_to_string(&pid_file).unwrap();
    let stat = format!("/proc/{}/stat", pid.trim());
    // Reparented and reaped by init, or never: give it a moment to go.
    let gone = (0..100).any(|_| {
        let alive = std::fs::read_to_string(&stat)
            .is_ok_and(|s| !s.split(") ").nth(1).is_some_and(|t| t.starts_with('Z')));
        if alive {
            std::thread::sleep(std::time::Duration::from_millis(30));
        }
        !alive
    });
    assert!(
        gone,
        "the device's sleep (pid {}) outlived the host",
        pid.trim()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The operator's reset (`cutlab host --reset-hold`, `HostLink::reset_hold`): refused while the
/// hold's cause lasts, granted once it is gone; the device then moves again.
#[test]
fn the_operators_reset_releases_a_latched_hold_once_its_cause_is_gone() {
    use cutlab::protocol::frame::Arm;
    let mut config = DeviceConfig::new(Preset::KimStepDoc);
    config.watchdog_timeout_s = 30.0;
    config.faults.over_current_at_s = Some(0.5);
    config.faults.over_current_s = 1.0;
    let device = Rc::new(RefCell::new(DeviceEmulator::new(config).unwrap()));
    let mut out = Vec::new();
    {
        let mut d = device.borrow_mut();
        d.receive(&wire(Frame::Arm(Arm { seq: 1 })), &mut out);
        while d.hold_latched().is_none() {
            d.step_frame(&mut out);
        }
    }
    let line = Box::new(LockstepLine::new(Rc::clone(&device)));
    let mut link = HostLink::connect_line(line, HostOptions::default()).unwrap();
    let answer = link.reset_hold().unwrap();
    assert!(answer.contains("keeps the feed hold"), "{answer}");
    assert_eq!(device.borrow().hold_latched(), Some(HoldCause::OverCurrent));
    {
        let mut d = device.borrow_mut();
        for _ in 0..1500 {
            d.step_frame(&mut out);
        }
    }
    let answer = link.reset_hold().unwrap();
    assert!(answer.contains("released"), "{answer}");
    assert_eq!(device.borrow().hold_latched(), None);
    assert!(!device.borrow().feed_hold());
}

/// `cutlab host --reset-hold` against a device with nothing latched: it says so and succeeds.
#[cfg(feature = "cli")]
#[test]
fn the_reset_hold_option_sends_the_reset_and_says_what_the_device_answered() {
    let exe = env!("CARGO_BIN_EXE_cutlab");
    let device = format!("{exe} device --stdio --scenario kim-step-doc --time-scale 10");
    let (result, out) = common::cutlab_text(&["host", "--device-cmd", &device, "--reset-hold"], "");
    result.unwrap();
    assert!(out.starts_with("reset: the feed hold is released"), "{out}");
}

/// The stuck-override and phase-sum checks raise nothing on a healthy machine: every preset's
/// first part, through the teach cut's steps (100, 30, 140, 60 %, 1.5 s each), with every
/// command applied (docs/protocol.md §4 and §5 quote what this finds).
#[test]
fn no_preset_raises_a_stuck_override_or_a_sensor_fault_when_healthy() {
    use cutlab::protocol::frame::{fault_flag, Arm, Hello, SetOverride};
    use cutlab::protocol::host::HostSession;
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    for preset in Preset::ALL {
        let mut d = DeviceEmulator::new(DeviceConfig::new(preset)).unwrap();
        let mut host = HostSession::new();
        let mut out = Vec::new();
        d.receive(
            &wire(Frame::Hello(Hello {
                version_major: 2,
                version_minor: 0,
            })),
            &mut out,
        );
        d.receive(&wire(Frame::Arm(Arm { seq: 1 })), &mut out);
        host.start_part();
        host.receive(&out);
        let mut seq = 1;
        let mut faults = 0u8;
        let mut frame = 0u64;
        while d.in_cycle() && frame < 200_000 {
            if frame.is_multiple_of(1500) {
                seq += 1;
                let pct = [100, 30, 140, 60][(frame / 1500 % 4) as usize];
                let mut command = Vec::new();
                host.set_override(
                    cutlab::machine::OverrideCommand {
                        override_pct: f64::from(pct),
                        feed_hold: false,
                    },
                    &mut command,
                );
                let Ok(Frame::SetOverride(c)) = cutlab::protocol::codec::Decoder::new()
                    .frames(&command)
                    .next()
                    .unwrap()
                else {
                    panic!("not a set-override")
                };
                d.receive(
                    &wire(Frame::SetOverride(SetOverride { seq, ..c })),
                    &mut out,
                );
            }
            if frame.is_multiple_of(100) {
                d.receive(&wire(Frame::Heartbeat(Default::default())), &mut out);
            }
            out.clear();
            d.step_frame(&mut out);
            host.receive(&out);
            while host.next_sample().is_some() {}
            faults |= d.fault_flags();
            frame += 1;
        }
        assert!(!d.in_cycle(), "{} did not end", preset.name());
        assert_eq!(faults & fault_flag::SENSOR, 0, "{}", preset.name());
        assert_eq!(host.take_stuck_override(), None, "{}", preset.name());
    }
}

/// `cutlab host` refuses, before it arms anything, a bridge that does not measure what the run
/// needs (docs/protocol.md §4), as the Hardware page does.
#[test]
fn the_host_refuses_a_bridge_that_lacks_a_measurement_before_arming_it() {
    use cutlab::protocol::frame::measured;
    let mut config = kim_device(5.0);
    config.measured = measured::ALL & !measured::ACTUAL_FEED;
    let (run, device) = lockstep_for(config, &kim_threshold(), None, None);
    let error = run.result.err().unwrap().0;
    assert!(
        error.contains("does not measure the actual feed"),
        "{error}"
    );
    assert_eq!(device.stats().parts, 0);
}
