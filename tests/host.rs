//! The native host against the device emulator, in-process over pipes (and once as processes):
//! the closed loop over the protocol matches `cutlab sim`, survives a lossy line counting its
//! losses, and both watchdogs do what docs/protocol.md says.
//!
//! The device keeps scaled real time, so these tests take their time (about 7 s each at 20× real
//! time) and run one at a time: two machines in parallel on a small runner could starve a host,
//! and a starved host trips the device's watchdog, which is what one of the tests is about.
#![cfg(not(target_arch = "wasm32"))]
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::sync::Mutex;

use cutlab::closed_loop::calibration_file::CalibrationFile;
use cutlab::closed_loop::lab::{simulate, RunResult, RunSpec};
use cutlab::closed_loop::runner::Calibration;
use cutlab::control::registry::ControllerKind;
use cutlab::plant::Preset;
use cutlab::protocol::device::{DeviceConfig, DeviceEmulator, DeviceStats, FaultInjection};
use cutlab::protocol::link::{run_device, run_on_link, HostLink, HostOptions, LinkRun};

/// One closed loop against the emulator at a time.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

const TIME_SCALE: f64 = 20.0;

/// The device on a thread and the host on this one, joined by two pipes.
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
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
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

/// The emulator of kim-step-doc with a watchdog of `watchdog_s` device seconds. Tests that are
/// not about the watchdog give it 5 s (a quarter second of wall time at 20×), so a busy machine
/// that holds the host up for a moment does not trip it.
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

/// The metrics a run over the link must share with the simulation. The protocol adds a
/// 1 kHz signal chain, 5 mA current counts and a few milliseconds of latency; the removed volume,
/// removal rate and peak force stay within 3 %, the cycle time within 5 % (a test machine busy
/// with other work delays the host, and every delay is latency in the loop), the mean force error
/// within three points. (The force IAE of the threshold controller is not compared: it moves by 9 % between
/// two seeds of the simulation itself, as the controller's limit cycle locks in differently.)
fn assert_like_sim(sim: &RunResult, run: &LinkRun) {
    let link = run.result.as_ref().unwrap();
    let (s, l) = (&sim.metrics, &link.metrics);
    let report = format!("sim {s:#?}\nlink {l:#?}\n{:?}", run.stats);
    assert!(l.completed, "{report}");
    assert!(within(s.cycle_time_s, l.cycle_time_s, 0.05), "{report}");
    assert!(
        within(s.removed_volume_mm3, l.removed_volume_mm3, 0.01),
        "{report}"
    );
    assert!(
        within(
            s.mean_material_removal_mm3_s,
            l.mean_material_removal_mm3_s,
            0.03
        ),
        "{report}"
    );
    assert!(within(s.peak_force_n, l.peak_force_n, 0.03), "{report}");
    assert!(
        (s.force_mean_abs_error_pct - l.force_mean_abs_error_pct).abs() <= 3.0,
        "{report}"
    );
    assert_eq!(sim.settings.target_force_n, link.settings.target_force_n);
}

#[test]
fn the_closed_loop_over_the_protocol_matches_the_simulation() {
    let spec = kim_threshold();
    let sim = simulate(&spec).unwrap();
    let (run, device, diagnostics) =
        host_against_emulator(kim_device(5.0), &spec, HostOptions::default());
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
    assert_eq!(run.device.protocol_version, "1.0");
}

#[test]
fn a_saved_calibration_replaces_the_teach_cut_over_the_link() {
    let spec = kim_threshold();
    let sim = simulate(&spec).unwrap();
    // Through the file, as `cutlab host --calibration` reads it.
    let saved = CalibrationFile::new(sim.calibration.clone(), "sim teach cut").to_json();
    let calibration = CalibrationFile::from_json(&saved).unwrap().calibration;
    let (run, device, diagnostics) = host_against_emulator_calibrated(
        kim_device(5.0),
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
    let mid = &sim.trace.rows[sim.trace.rows.len() / 2];
    let at = |r: &RunResult| {
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
    let mut config = kim_device(5.0);
    config.sim_truth = false;
    let (run, _, _) = host_against_emulator(config, &kim_threshold(), HostOptions::default());
    let e = run.result.unwrap_err().to_string();
    assert!(e.contains("--calibration FILE"), "{e}");
}

#[test]
fn a_lossy_noisy_line_still_completes_and_the_losses_are_counted() {
    let spec = kim_threshold();
    let sim = simulate(&spec).unwrap();
    let mut config = kim_device(5.0);
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
    // The device's watchdog (5 s of device time) fires while the host's (1 s of wall time, 20 s
    // of device time) is still waiting.
    let mut config = kim_device(5.0);
    // In the closed loop (the teach cut's part takes the first 66 s of device time).
    config.faults.unplug_at_s = Some(100.0);
    let options = HostOptions {
        link_timeout_s: 1.0,
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
    // A 4 s stall against a 2 s watchdog: the stall fires it, a hiccup of the test machine
    // (under 0.1 s of wall time) does not.
    let mut config = kim_device(2.0);
    config.faults.stall_at_s = Some(90.0);
    config.faults.stall_s = 4.0;
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

/// The whole thing as a person types it: `cutlab host --device-cmd "cutlab device …"`, two
/// processes, a short closed loop.
#[cfg(feature = "cli")]
#[test]
fn the_binary_runs_the_host_against_the_binary_device() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let exe = env!("CARGO_BIN_EXE_cutlab");
    let dir = std::env::temp_dir().join(format!("cutlab-host-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let json = dir.join("host.json");
    let out = std::process::Command::new(exe)
        .args([
            "host",
            "--device-cmd",
            &format!("{exe} device --stdio --scenario kim-step-doc --time-scale 40 --watchdog-s 2"),
            "--controller",
            "threshold",
            "--duration-s",
            "10",
            "--json",
            json.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert!(stdout.contains("link: protocol 1.0"), "{stdout}");
    assert!(stderr.contains("part 2: cycle start"), "{stderr}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
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
    assert_eq!(report["protocol_version"], "1.0");
    assert_eq!(report["link_losses"], 0);
    // Stopped at 10 s of machine time, not at the program's end.
    assert_eq!(report["metrics"]["completed"], false);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `cutlab device` survives any bytes on stdin: random bytes in, only frames out (heartbeats,
/// nothing armed it), and it ends when stdin closes.
#[cfg(feature = "cli")]
#[test]
fn the_device_binary_survives_garbage_on_stdin_and_writes_only_frames() {
    use std::io::Write;
    use std::process::{Command, Stdio};
    let mut child = Command::new(env!("CARGO_BIN_EXE_cutlab"))
        .args([
            "device",
            "--stdio",
            "--scenario",
            "kim-step-doc",
            "--time-scale",
            "10",
        ])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
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
