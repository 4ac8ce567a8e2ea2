//! The Hardware page's core (`cutlab::hardware`) against the device emulator, byte for byte, on a
//! clock the test keeps: handshake, teach cut and closed loop over the link, Disarm's safe
//! override, both watchdogs, a lost port, and recordings the log reader reads back.
//!
//! Nothing here waits for real time: the "wall clock" advances in 5 ms steps and the device runs
//! `SCALE` device seconds per wall second, so each test takes a fraction of a second of compute.
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
// The page runs this core in wasm: the same tests run there too.
#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use cutlab::closed_loop::calibration_file::CalibrationFile;
use cutlab::closed_loop::definition::RunSpec;
use cutlab::closed_loop::lab::simulate;
use cutlab::control::registry::ControllerKind;
use cutlab::estimation::estimator::Feedback;
use cutlab::estimation::load_levels::{FewLoadLevels, LineModel};
use cutlab::hardware::recording::{LiveRow, Recorder, RecordingMeta};
use cutlab::hardware::session::{
    HardwareSession, LinkState, SessionOptions, Stage, TaughtCalibration,
};
use cutlab::log::{load, ColumnKind, Role};
use cutlab::plant::Preset;
use cutlab::protocol::codec::{encode_frame, Decoder, MAX_FRAME_LEN};
use cutlab::protocol::device::{DeviceConfig, DeviceEmulator, FaultInjection, HoldCause};
use cutlab::protocol::frame::{padded, Capabilities, Frame, OverrideModeCode};
use cutlab::protocol::keep_up::KeepUp;

/// Device seconds per wall second.
const SCALE: f64 = 4.0;
/// Wall seconds per step of the test's clock.
const STEP_S: f64 = 0.005;

/// A device and the session joined by the test: bytes cross at every step of the clock.
struct Bench {
    device: DeviceEmulator,
    session: HardwareSession,
    now_s: f64,
    to_host: Vec<u8>,
    rows: Vec<LiveRow>,
    /// The link is cut both ways (the test's unplug).
    cut: bool,
}

impl Bench {
    fn new(config: DeviceConfig, options: SessionOptions) -> Self {
        let mut b = Self {
            device: DeviceEmulator::new(config).unwrap(),
            session: HardwareSession::new(options, 0.0),
            now_s: 0.0,
            to_host: Vec::new(),
            rows: Vec::new(),
            cut: false,
        };
        b.run_until(|b| b.session.state() != LinkState::Handshaking, 5.0);
        assert_eq!(
            b.session.state(),
            LinkState::Streaming,
            "{}",
            b.session.reason()
        );
        b
    }

    /// One step of the clock: host → device, the device's due frames, device → host, tick.
    fn step(&mut self) {
        self.now_s += STEP_S;
        let to_device = self.session.take_output();
        if !self.cut {
            self.device.receive(&to_device, &mut self.to_host);
        }
        while self.device.time_s() + self.device.frame_period_s() <= self.now_s * SCALE {
            self.device.step_frame(&mut self.to_host);
        }
        let bytes = std::mem::take(&mut self.to_host);
        if !self.cut {
            self.session.receive(&bytes, self.now_s);
        }
        self.session.tick(self.now_s);
        self.rows.extend(self.session.take_rows());
    }

    /// Steps until `done` or `limit_s` of wall time more.
    fn run_until(&mut self, done: impl Fn(&Self) -> bool, limit_s: f64) {
        let until = self.now_s + limit_s;
        while !done(self) && self.now_s < until {
            self.step();
        }
    }

    fn events(&self) -> String {
        self.session
            .events()
            .iter()
            .map(|e| format!("{:8.3} {}\n", e.time_s, e.text))
            .collect()
    }

    /// Teach, then arm the closed loop of `spec`.
    fn teach_and_arm(&mut self, spec: &RunSpec) {
        self.session.teach_limits(spec).unwrap();
        self.session.start_teach_cut(spec, self.now_s).unwrap();
        assert_eq!(self.session.state(), LinkState::Armed);
        self.run_until(|b| b.session.stage() == Stage::Idle, 60.0);
        assert!(self.session.calibration().is_some(), "{}", self.events());
        assert_eq!(self.session.state(), LinkState::Streaming);
        assert!(
            !self.session.holding(),
            "handed back at the teach cut's end"
        );
        let limits = self.session.arm_limits(spec).unwrap();
        assert!(
            limits.lines.iter().any(|l| l.contains("Overload")),
            "{limits:?}"
        );
        self.session.arm(spec, self.now_s).unwrap();
        assert_eq!(self.session.state(), LinkState::Armed);
    }
}

fn maneerat(watchdog_s: f64) -> DeviceConfig {
    let mut c = DeviceConfig::new(Preset::ManeeratDoc1);
    c.watchdog_timeout_s = watchdog_s;
    c
}

fn spec() -> RunSpec {
    RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Threshold)
}

fn within(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs())
}

#[test]
fn a_teach_cut_and_a_closed_loop_over_the_link_run_like_the_simulation() {
    let mut b = Bench::new(maneerat(0.5), SessionOptions::default());
    let device = b.session.device().unwrap();
    assert_eq!(
        (device.device_id.as_str(), device.program.as_str()),
        ("cutlab-emulator", "maneerat-doc-1")
    );
    b.teach_and_arm(&spec());
    b.run_until(|b| b.session.stage() == Stage::Idle, 60.0);
    let events = b.events();
    let run = b.session.result().expect("a result").clone();
    let sim = simulate(&spec()).unwrap();
    let (s, l) = (&sim.metrics, &run.metrics);
    assert!(l.completed, "{events}");
    assert!(within(s.cycle_time_s, l.cycle_time_s, 0.05), "{s:?}\n{l:?}");
    assert!(
        within(s.removed_volume_mm3, l.removed_volume_mm3, 0.01),
        "{s:?}\n{l:?}"
    );
    assert!(within(s.peak_force_n, l.peak_force_n, 0.1), "{s:?}\n{l:?}");
    assert_eq!(sim.settings.target_force_n, run.settings.target_force_n);
    // At the program's end the device was handed back, and said so.
    assert_eq!(b.session.state(), LinkState::Streaming, "{events}");
    assert!(!b.session.holding());
    assert!(events.contains("run complete"), "{events}");
    let st = b.session.stats();
    assert_eq!(
        (st.frames_lost, st.bytes_dropped, st.link_losses),
        (0, 0, 0)
    );
    assert!(st.commands_sent > 10, "{st:?}");
    // Every command (Arms, SetOverrides, Disarms) was acknowledged.
    b.run_until(|_| false, 0.05);
    assert_eq!(
        b.session.stats().commands_acknowledged,
        b.session.stats().commands_sent
    );
    assert_eq!(b.device.stats().watchdog_fallbacks, 0);
    // One row per sample, in device time, with the loop's commands and estimates on them.
    let samples = b.device.stats().frames_sent;
    assert!(b.rows.len() > 20_000 && (b.rows.len() as u64) < samples);
    assert!(b.rows.windows(2).all(|w| w[1].time_s > w[0].time_s));
    let looped: Vec<&LiveRow> = b.rows.iter().filter(|r| r.phase == "closed loop").collect();
    assert!(looped.iter().all(|r| r.commanded_override_pct.is_finite()));
    assert!(looped.iter().any(|r| r.force_est_n > 0.5 * l.peak_force_n));
}

#[test]
fn disarm_commands_the_safe_override_at_once_and_hands_back_when_the_part_ends() {
    let options = SessionOptions::new(2.0, Some(35.0)).unwrap();
    let mut b = Bench::new(maneerat(0.5), options);
    b.teach_and_arm(&spec());
    // Into the cut, under control.
    b.run_until(
        |b| b.rows.last().is_some_and(|r| r.force_est_n > 50.0),
        10.0,
    );
    let acked = b.session.stats().commands_acknowledged;
    b.session.disarm("Escape", b.now_s);
    assert_eq!(b.session.state(), LinkState::Streaming);
    assert_eq!(b.session.stage(), Stage::HoldingSafe);
    assert!(
        b.session.reason().contains("35 %"),
        "{}",
        b.session.reason()
    );
    // The SetOverride went out with the disarm itself.
    let out = b.session.take_output();
    let sent: Vec<Frame> = Decoder::new().frames(&out).filter_map(Result::ok).collect();
    assert!(
        sent.iter()
            .any(|f| matches!(f, Frame::SetOverride(c) if c.override_cpct == 3500)),
        "{sent:?}"
    );
    b.device.receive(&out, &mut b.to_host);
    b.run_until(|b| b.session.stats().commands_acknowledged > acked, 1.0);
    let ack = b.session.last_ack().unwrap();
    assert_eq!(ack.applied_override_cpct, 3500);
    // The run ended there, incomplete; the machine runs on at 35 % to the program's end, then
    // the device is handed back.
    assert!(!b.session.result().unwrap().trace.completed);
    b.run_until(|b| b.session.stage() == Stage::Idle, 60.0);
    assert!(!b.session.holding(), "{}", b.events());
    let last_held = b
        .rows
        .iter()
        .rev()
        .find(|r| r.phase == "held at the safe override")
        .unwrap();
    assert_eq!(last_held.applied_override_pct, 35.0);
}

#[test]
fn the_host_watchdog_alarms_when_samples_stop_and_the_device_falls_back() {
    let mut config = maneerat(0.5);
    // The cable is pulled 2 s (device time) into the closed loop's part, which starts at about
    // 12 s: the teach cut's part is about 12 s long.
    config.faults = FaultInjection {
        unplug_at_s: Some(16.0),
        ..FaultInjection::default()
    };
    let mut b = Bench::new(config, SessionOptions::new(0.5, None).unwrap());
    b.teach_and_arm(&spec());
    b.run_until(|b| b.session.state() == LinkState::Alarm, 30.0);
    let events = b.events();
    assert_eq!(b.session.state(), LinkState::Alarm, "{events}");
    assert!(
        b.session
            .reason()
            .starts_with("host watchdog: no sample for 0.5 s"),
        "{}",
        b.session.reason()
    );
    assert!(b.session.reason().contains("safe override (50 %)"));
    assert_eq!(b.session.stats().link_losses, 1);
    assert!(!b.session.result().unwrap().trace.completed);
    // The device, hearing nothing, fell back on its own.
    b.run_until(|b| b.device.stats().watchdog_fallbacks > 0, 2.0);
    assert_eq!(b.device.stats().watchdog_fallbacks, 1);
    // The alarm stays until acknowledged, and cannot be while the device is silent.
    assert!(b.session.acknowledge_alarm(b.now_s).is_err());
    assert_eq!(b.session.state(), LinkState::Alarm);
}

#[test]
fn a_device_watchdog_fallback_is_counted_and_answered_by_re_arming() {
    let mut config = maneerat(0.5);
    // The device's receiver stalls for 1 s of device time inside the closed loop's part.
    config.faults = FaultInjection {
        stall_at_s: Some(18.0),
        stall_s: 1.0,
        ..FaultInjection::default()
    };
    let mut b = Bench::new(config, SessionOptions::default());
    b.teach_and_arm(&spec());
    b.run_until(|b| b.session.stage() == Stage::Idle, 60.0);
    let events = b.events();
    let st = b.session.stats();
    assert_eq!(st.watchdog_fallbacks, 1, "{events}");
    assert_eq!(b.device.stats().watchdog_fallbacks, 1);
    assert!(events.contains("re-arming the device"), "{events}");
    assert!(
        events.contains("device back under the host's control"),
        "{events}"
    );
    assert!(b.rows.iter().any(|r| r.phase == "device watchdog fallback"));
    // The host stayed in control and the run completed.
    assert!(b.session.result().unwrap().metrics.completed, "{events}");
    assert_eq!(st.link_losses, 0);
}

#[test]
fn a_lost_port_alarms_and_nothing_more_is_sent() {
    let mut b = Bench::new(maneerat(0.5), SessionOptions::default());
    b.teach_and_arm(&spec());
    b.run_until(|b| b.rows.len() > 15_000, 10.0);
    b.cut = true;
    b.session.link_lost("the device was unplugged", b.now_s);
    assert_eq!(b.session.state(), LinkState::Alarm);
    let reason = b.session.reason().to_string();
    assert!(
        reason.starts_with("link lost: the device was unplugged")
            && reason.contains("fallback override (at most 50 %, never above the applied)"),
        "{reason}"
    );
    assert!(!b.session.holding());
    for _ in 0..100 {
        b.step();
        assert!(b.session.take_output().is_empty());
    }
    assert_eq!(b.session.stats().link_losses, 1);
}

#[test]
fn a_silent_port_ends_the_handshake_with_the_reason() {
    let mut s = HardwareSession::new(SessionOptions::new(1.0, None).unwrap(), 100.0);
    let mut hellos = 0;
    let mut t = 100.0;
    while s.state() == LinkState::Handshaking && t < 120.0 {
        t += 0.05;
        s.tick(t);
        hellos += Decoder::new()
            .frames(&s.take_output())
            .filter(|f| matches!(f, Ok(Frame::Hello(_))))
            .count();
    }
    assert_eq!(s.state(), LinkState::Closed);
    assert!(s.reason().starts_with("no answer to Hello within 5 s"));
    assert!((15..=25).contains(&hellos), "{hellos}");
}

#[test]
fn a_device_of_another_major_version_is_refused_and_arming_needs_a_calibration() {
    let caps = |major| Capabilities {
        version_major: major,
        version_minor: 3,
        device_id: padded("bridge"),
        program: padded("maneerat-doc-1"),
        channel_mask: 0x7F,
        spindle_current_a_per_count: 0.01,
        feed_current_a_per_count: 0.01,
        fv_v_per_count: 0.001,
        sample_rate_hz: 1000.0,
        override_mode: OverrideModeCode::WholePercent,
        min_override_cpct: 0,
        max_override_cpct: 25500,
        dial_cpct: [0; 16],
        watchdog_timeout_ms: 500,
        fallback_override_cpct: 5000,
        over_current_a: 150.0,
        features: 0,
        measured: cutlab::protocol::frame::measured::ALL,
        fallback_limit_ms: 5000,
        line_baud: 0,
    };
    let bytes = |c| {
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = encode_frame(&Frame::Capabilities(c), &mut buf).unwrap();
        buf[..n].to_vec()
    };
    let mut s = HardwareSession::new(SessionOptions::default(), 0.0);
    s.receive(&bytes(caps(3)), 0.1);
    assert_eq!(s.state(), LinkState::Closed);
    assert_eq!(
        s.reason(),
        "the device speaks protocol 3.3; this host speaks 2.x"
    );
    let mut s = HardwareSession::new(SessionOptions::default(), 0.0);
    s.receive(&bytes(caps(2)), 0.1);
    assert_eq!(s.state(), LinkState::Streaming);
    assert!(s
        .arm(&spec(), 0.2)
        .unwrap_err()
        .starts_with("no calibration yet"));
    // A real bridge sends no truth: the teach cut takes the model of a cut of one depth, and
    // says why it cannot run on a program whose depth steps.
    let limits = s.teach_limits(&spec()).unwrap();
    assert!(
        limits
            .lines
            .iter()
            .any(|l| l.contains("the model of the preset's cut (1 mm deep")),
        "{limits:?}"
    );
    let steps = RunSpec::new(Preset::KimStepDoc, ControllerKind::Threshold);
    assert!(s
        .teach_limits(&steps)
        .unwrap_err()
        .contains("load a saved calibration instead"));
    // A safe override the device cannot apply is refused before anything is armed.
    let mut dial = caps(2);
    dial.max_override_cpct = 15000;
    dial.features = 1;
    let mut s = HardwareSession::new(SessionOptions::new(2.0, Some(200.0)).unwrap(), 0.0);
    s.receive(&bytes(dial), 0.1);
    let why = s.start_teach_cut(&spec(), 0.2).unwrap_err();
    assert_eq!(
        why,
        "the safe override 200 % is outside what the device applies (0–150 %)"
    );
    assert!(s.take_output().iter().all(|_| false) || s.state() == LinkState::Streaming);
    assert!(SessionOptions::new(2.0, Some(300.0)).is_err());
    assert!(SessionOptions::new(0.0, None).is_err());
}

#[test]
fn a_recording_reads_back_through_the_log_reader_with_each_roles_guess() {
    let mut b = Bench::new(maneerat(0.5), SessionOptions::default());
    b.teach_and_arm(&spec());
    b.rows.clear();
    // Past the arming delay and into the cut.
    b.run_until(|b| b.rows.len() >= 6000, 10.0);
    let device = b.session.device().unwrap();
    let mut recorder = Recorder::new(RecordingMeta {
        id: 1,
        name: "closed loop".into(),
        started_ms: 0.0,
        device: device.device_id.clone(),
        sample_rate_hz: device.sample_rate_hz,
        sim_truth: device.sim_truth,
        rows: 0,
        chunks: 0,
        duration_s: 0.0,
        finished: false,
        end: String::new(),
        summary: String::new(),
    });
    let mut csv = String::new();
    for row in &b.rows {
        recorder.push(row);
        if recorder.pending_bytes() > 50_000 {
            csv.push_str(&recorder.take_chunk().unwrap().1);
        }
    }
    csv.push_str(&recorder.take_chunk().unwrap().1);
    let log = load(csv.as_bytes(), None).unwrap();
    assert!(
        log.problems.is_empty(),
        "{:?}",
        &log.problems[..3.min(log.problems.len())]
    );
    assert_eq!(log.rows, b.rows.len());
    let role = |name: &str| {
        log.columns
            .iter()
            .find(|c| c.name == name)
            .unwrap_or_else(|| panic!("no column {name}"))
            .role
    };
    assert_eq!(role("time [s]"), Some(Role::Time));
    assert_eq!(role("S_I_U [A]"), Some(Role::PhaseCurrent));
    assert_eq!(role("X_I_W [A]"), Some(Role::PhaseCurrent));
    assert_eq!(role("S_speed [rpm]"), Some(Role::SpindleSpeed));
    assert_eq!(role("feed [mm/min]"), Some(Role::Feed));
    assert_eq!(role("S_current_rms [A]"), Some(Role::RmsCurrent));
    assert_eq!(role("force estimate [N]"), Some(Role::Force));
    assert_eq!(role("depth (simulated) [mm]"), Some(Role::Depth));
    assert_eq!(role("phase"), Some(Role::Label));
    let time = &log.columns[log.time_column.unwrap()];
    assert_eq!(time.kind, ColumnKind::Time);
    // 1 kHz, in device time.
    assert!((log.sample_period_s.unwrap() - 0.001).abs() < 1e-9);
}

#[test]
fn a_device_without_truth_is_taught_from_the_cut_model_and_a_saved_calibration_needs_no_teach_cut()
{
    let mut config = maneerat(0.5);
    config.sim_truth = false;
    let mut b = Bench::new(config, SessionOptions::default());
    assert!(!b.session.device().unwrap().sim_truth);
    b.teach_and_arm(&spec());
    b.run_until(|b| b.session.stage() == Stage::Idle, 60.0);
    let taught = b.session.calibration().unwrap().clone();
    let run = b.session.result().unwrap();
    assert!(run.metrics.completed, "{}", b.events());
    // No truth on the rows either.
    assert!(b.rows.iter().all(|r| r.force_n.is_nan()));

    // The teach cut over the link knows what its lines rest on, and warns of it as the fit's
    // other front ends do (one event per warning, the fit's own words).
    assert!(taught.calibration.few_load_levels.is_some());
    let warned: Vec<String> = b
        .session
        .events()
        .iter()
        .filter_map(|e| e.text.strip_prefix("calibration warning: "))
        .map(str::to_string)
        .collect();
    assert_eq!(warned, taught.warnings());

    // The calibration saved as a file and loaded into a fresh session arms at once.
    let file = CalibrationFile::new(taught.calibration.clone(), "teach cut over the link");
    let read = CalibrationFile::from_json(&file.to_json()).unwrap();
    assert_eq!(
        read.calibration.few_load_levels,
        taught.calibration.few_load_levels
    );
    let mut b = Bench::new(maneerat(0.5), SessionOptions::default());
    b.session.set_calibration(TaughtCalibration {
        calibration: read.calibration.clone(),
        settings: None,
        source: "a file".into(),
    });
    b.session.arm(&spec(), b.now_s).unwrap();
    b.run_until(|b| b.session.stage() == Stage::Idle, 60.0);
    assert!(b.session.result().unwrap().metrics.completed);
    assert_eq!(b.device.stats().parts, 1, "no teach cut");
    // A calibration of another feedback path is refused, saying so.
    let mut feed = spec();
    feed.settings.feedback = Some(Feedback::FeedCurrent);
    let why = b.session.arm(&feed, b.now_s).unwrap_err();
    assert!(
        why.starts_with("the calibration is for spindle feedback but the run measures with feed"),
        "{why}"
    );

    // A saved calibration whose line rests on two load levels warns when it is loaded, and one
    // saved before cutlab kept them says it cannot tell.
    let mut two = read.calibration.clone();
    two.few_load_levels = Some(vec![FewLoadLevels {
        model: LineModel::Spindle,
        speed_rpm: 3000.0,
        levels_n: vec![150.0, 300.0],
        r_squared: 0.9995,
    }]);
    let mut unknown = read.calibration;
    unknown.few_load_levels = None;
    for (calibration, expected) in [
        (
            two,
            "calibration warning: the spindle line at 3000 rpm rests on 2 load levels (150, 300 N)",
        ),
        (
            unknown,
            "calibration warning: the calibration does not say how many load levels",
        ),
    ] {
        b.session.set_calibration(TaughtCalibration {
            calibration,
            settings: None,
            source: "another file".into(),
        });
        let last = &b.session.events().last().unwrap().text;
        assert!(last.starts_with(expected), "{}", b.events());
    }
}

/// The envelope's overload holds the feed, and the device latches the hold: it stays through
/// a link loss, the device's fallback and its time limit, and a host's restart, and only the
/// operator's reset releases it (issue 31: "a hold survives a link loss and a host restart until
/// reset"; before, the fallback resumed the feed at 50 %).
#[test]
fn an_overload_feed_hold_is_latched_through_a_link_loss_and_a_host_restart_until_reset() {
    let mut config = maneerat(0.5);
    config.fallback_limit_s = 1.0;
    let mut b = Bench::new(config, SessionOptions::default());
    // A target far below the cut's force: the envelope's overload limit (3 × target) is crossed
    // as soon as the tool enters, and it holds the feed.
    let mut low = spec();
    low.settings.target_force_n = Some(10.0);
    b.teach_and_arm(&low);
    b.run_until(|b| b.session.state() == LinkState::Alarm, 30.0);
    let events = b.events();
    assert_eq!(b.session.state(), LinkState::Alarm, "{events}");
    assert!(
        b.session
            .reason()
            .starts_with("overload: the envelope held the feed")
            || b.session
                .reason()
                .starts_with("the device holds the feed, latched"),
        "{}",
        b.session.reason()
    );
    assert!(b.session.hold_state().is_some(), "{events}");
    assert_eq!(b.device.hold_latched(), Some(HoldCause::Host));
    // The feed drive's deceleration first.
    let settled = b.now_s + 0.5;
    b.run_until(|b| b.now_s > settled, 1.0);
    b.rows.clear();
    b.run_until(|b| b.rows.len() > 500, 5.0);
    assert!(
        b.rows.iter().all(|r| r.feed_mm_min.abs() < 1e-6),
        "{events}"
    );
    assert_eq!(
        b.session.last_ack().unwrap().flags & 3,
        3,
        "hold in force, latched"
    );

    // The cable goes: the host alarms, the device falls back — and keeps the feed held, past
    // its fallback's time limit.
    b.cut = true;
    let until = b.now_s + 3.0;
    b.run_until(|b| b.now_s > until, 4.0);
    assert!(b.device.in_fallback());
    assert!(b.device.feed_hold() && b.device.hold_latched().is_some());
    // A new host (a restart, a reload): it sees the latched hold and will not arm over it.
    b.cut = false;
    b.session = HardwareSession::new(SessionOptions::default(), b.now_s);
    b.run_until(|b| b.session.state() == LinkState::Streaming, 5.0);
    b.run_until(|b| b.session.hold_state().is_some(), 1.0);
    assert!(b.session.hold_state().is_some(), "{}", b.events());
    assert!(b
        .session
        .start_teach_cut(&low, b.now_s)
        .unwrap_err()
        .contains("latched"));
    b.rows.clear();
    b.run_until(|b| b.rows.len() > 200, 2.0);
    assert!(b.rows.iter().all(|r| r.feed_mm_min.abs() < 1e-6));
    // The operator's reset: the feed moves again (at the device's fallback, as the link left
    // it), and the new host may arm.
    b.session.reset_hold().unwrap();
    b.rows.clear();
    b.run_until(|b| b.rows.iter().any(|r| r.feed_mm_min > 1.0), 2.0);
    assert!(b.rows.iter().any(|r| r.feed_mm_min > 1.0), "{}", b.events());
    assert_eq!(b.device.hold_latched(), None);
    assert!(b.session.hold_state().is_none());
}

/// docs/protocol.md §5, as the page does it: an over-current the device reports stops the run and
/// the device latches the feed hold (a crash, a broken tool) until the operator's reset, after
/// which the safe override is held until the part ends; an E-stop stops the run and hands the
/// device back at once (it refuses commands and its axes stopped).
#[test]
fn a_device_fault_alarms_an_over_current_holds_the_feed_until_reset_an_e_stop_hands_back() {
    // The teach cut's part ends about 15 s into device time: the faults come 5 s into the run.
    let mut config = maneerat(5.0);
    config.faults.over_current_at_s = Some(20.0);
    config.faults.over_current_s = 0.2;
    let mut b = Bench::new(config, SessionOptions::default());
    b.teach_and_arm(&spec());
    b.run_until(|b| b.session.state() == LinkState::Alarm, 30.0);
    let events = b.events();
    assert_eq!(b.session.state(), LinkState::Alarm, "{events}");
    assert!(
        b.session
            .reason()
            .contains("device fault over-current raised"),
        "{}",
        b.session.reason()
    );
    assert_eq!(b.session.stage(), Stage::HoldingSafe);
    assert!(!b.session.result().unwrap().metrics.completed);
    assert_eq!(b.device.hold_latched(), Some(HoldCause::OverCurrent));
    // The feed drive's deceleration first.
    let settled = b.now_s + 0.5;
    b.run_until(|b| b.now_s > settled, 1.0);
    b.rows.clear();
    b.run_until(|b| b.rows.len() > 400, 5.0);
    assert!(
        b.rows.iter().all(|r| r.feed_mm_min.abs() < 1e-6),
        "{}",
        b.events()
    );
    assert!(b.session.hold_state().unwrap().contains("latched"));
    // The over-current is gone (it lasted 0.2 s): the operator resets, the safe override runs
    // the part to its end, and the device is handed back.
    b.session.reset_hold().unwrap();
    b.rows.clear();
    b.run_until(|b| !b.session.holding(), 30.0);
    assert!(b.rows.iter().any(|r| r.program_end), "{}", b.events());
    assert!(b
        .rows
        .iter()
        .all(|r| r.commanded_override_pct == 50.0 || r.commanded_override_pct.is_nan()));

    let mut config = maneerat(5.0);
    config.faults.estop_at_s = Some(20.0);
    let mut b = Bench::new(config, SessionOptions::default());
    b.teach_and_arm(&spec());
    b.run_until(|b| b.session.state() == LinkState::Alarm, 30.0);
    let events = b.events();
    assert_eq!(b.session.state(), LinkState::Alarm, "{events}");
    assert!(
        b.session.reason().contains("device fault e-stop raised"),
        "{}",
        b.session.reason()
    );
    assert!(!b.session.holding(), "{events}");
    assert!(!b.session.result().unwrap().metrics.completed);
    assert!(events.contains("disarm: E-stop"), "{events}");
}

/// The event log stamps a device's fault with the device time of the sample it came with — as
/// `cutlab host` does — not with the latest sample of the batch before (the page used to stamp
/// the protocol session's events before applying the batch's samples), and the row of that
/// sample carries it.
#[test]
fn a_device_fault_is_logged_at_the_sample_it_came_with() {
    let mut config = maneerat(5.0);
    config.faults.estop_at_s = Some(20.0);
    let mut b = Bench::new(config, SessionOptions::default());
    b.teach_and_arm(&spec());
    b.run_until(|b| b.session.state() == LinkState::Alarm, 30.0);
    let fault = "device fault e-stop raised";
    let events = b.events();
    let event = b
        .session
        .events()
        .iter()
        .find(|e| e.text.contains(fault))
        .unwrap_or_else(|| panic!("{events}"));
    let rows: Vec<&LiveRow> = b.rows.iter().filter(|r| r.event.contains(fault)).collect();
    assert_eq!(rows.len(), 1, "{events}");
    assert!(
        (rows[0].time_s - event.time_s).abs() < 1e-9,
        "the event at {} s, its row at {} s\n{events}",
        event.time_s,
        rows[0].time_s
    );
}

/// docs/hardware.md is the reference design an engineer builds from (issue 31): every section of
/// it must be there, each with what it must say, and the commissioning procedure must be the
/// checks the page names before a new device's first Arm. Removing a section fails here.
#[test]
fn the_hardware_document_has_every_section_of_the_fail_safe_design() {
    let doc = include_str!("../docs/hardware.md");
    let sections: [(&str, &[&str]); 14] = [
        (
            "## 1. The reference design",
            &[
                "ladder route with an enable line",
                "second feedrate override",
                "force-guided changeover relays",
                "retriggerable monostable",
                "independent watchdog",
                "pull-down",
                "normally-closed contact in the machine's feed-hold chain",
                "open-sensor detection in hardware",
                "sum to about zero",
                "PELV",
                "USB isolator",
                "Reduce-only first cuts",
            ],
        ),
        (
            "## 2. Wiring",
            &["not FANUC's", "its own pin", "latency timer"],
        ),
        (
            "## 3. Bill of materials",
            &["| qty | part | example | requirement |"],
        ),
        (
            "## 4. Schematic",
            &["bridge-schematic.svg", "bridge-schematic.py"],
        ),
        (
            "## 5. Working in the cabinet",
            &["Lock out and tag out", "DC link", "qualified electrician"],
        ),
        ("## 6. Connecting", &["if the link"]),
        (
            "## 7. Calibration, arming, running",
            &["Reduce-only limits", "current"],
        ),
        ("## 8. Recordings", &["IndexedDB"]),
        (
            "## 9. What the page does on every fault",
            &["stuck override", "latched"],
        ),
        (
            "## 10. Commissioning procedure",
            &["PMC diagnosis screen", "air cut"],
        ),
        ("## 11. Bench calibration", &["N times", "known"]),
        (
            "## 12. Risk assessment",
            &["IEC 60204-1", "ISO 13849", "not a safety function"],
        ),
        (
            "## 13. Alternatives",
            &[
                "*AFV0",
                "DB21.DBB4",
                "$AC_OVR",
                "AFC",
                "Setting 84",
                "feed-scale",
                "FOCAS",
            ],
        ),
        ("## 14. How it is tested", &["tests/host.rs"]),
    ];
    for (i, (heading, musts)) in sections.iter().enumerate() {
        let start = doc
            .find(&format!("\n{heading}\n"))
            .unwrap_or_else(|| panic!("docs/hardware.md lacks the section {heading:?}"));
        let end = sections
            .get(i + 1)
            .and_then(|(next, _)| doc.find(&format!("\n{next}\n")))
            .unwrap_or(doc.len());
        let body = &doc[start..end];
        for must in *musts {
            assert!(body.contains(must), "{heading} does not say {must:?}");
        }
    }
    let svg = include_str!("../docs/bridge-schematic.svg");
    assert!(svg.starts_with("<svg") && svg.contains("feed-hold"));
    let procedure = &doc[doc.find("## 10. Commissioning procedure").unwrap()..];
    for (n, check) in cutlab::hardware::commissioning::CHECKS.iter().enumerate() {
        let line = format!(
            "{}. {}",
            n + 1,
            check.text.split_whitespace().collect::<Vec<_>>().join(" ")
        );
        assert!(
            procedure.contains(&line),
            "§10 lacks check {}: {line}",
            n + 1
        );
    }
}

/// A bridge that does not measure what a run needs is refused before it is armed, naming the
/// field: the programmed feed (without it a stuck override cannot be seen) for the closed loop;
/// the program end for any run (the teach cut and the hand-back wait for it).
#[test]
fn a_device_that_lacks_a_measurement_the_run_needs_is_not_armed() {
    use cutlab::protocol::frame::measured;
    let mut config = maneerat(5.0);
    config.measured = measured::ALL & !measured::PROGRAMMED_FEED;
    let mut b = Bench::new(config, SessionOptions::default());
    b.session.teach_limits(&spec()).unwrap();
    b.session.start_teach_cut(&spec(), b.now_s).unwrap();
    b.run_until(|b| b.session.stage() == Stage::Idle, 60.0);
    assert!(b.session.calibration().is_some(), "{}", b.events());
    let why = b.session.arm(&spec(), b.now_s).unwrap_err();
    assert!(
        why.contains("does not measure the programmed feed a closed loop needs"),
        "{why}"
    );
    assert_eq!(b.session.state(), LinkState::Streaming);

    let mut config = maneerat(5.0);
    config.measured = measured::ALL & !measured::PROGRAM_END;
    let mut b = Bench::new(config, SessionOptions::default());
    let why = b.session.start_teach_cut(&spec(), b.now_s).unwrap_err();
    assert!(why.contains("program end"), "{why}");
}

/// The Hardware page's virtual device as the browser runs it: the emulator in its worker, on
/// a wall clock at `time_scale` ([`ClockedDevice`]), ticked every [`VIRTUAL_TICK_MS`] (at most
/// [`MAX_VIRTUAL_FRAMES_PER_TICK`] frames a tick, reading what the host wrote only at a tick's
/// start); the host's answer to a tick's bytes reaches the worker `reply_ms` of wall time later
/// (the two messages between the worker and the page, and the page's own work); the page's
/// timer ticks the session every 100 ms.
struct VirtualBench {
    device: cutlab::protocol::device_worker::ClockedDevice,
    session: HardwareSession,
    now_ms: u64,
    reply_ms: u64,
    /// Bytes on their way to the worker: when they arrive (wall ms) and what.
    to_device: std::collections::VecDeque<(u64, Vec<u8>)>,
}

impl VirtualBench {
    fn new(time_scale: &str, reply_ms: u64) -> Self {
        use cutlab::protocol::device_settings::DeviceSetting;
        use cutlab::protocol::device_worker::{ClockedDevice, DeviceStart};
        let start = DeviceStart::new(
            &[
                (DeviceSetting::Program, "maneerat-doc-1".to_string()),
                (DeviceSetting::TimeScale, time_scale.to_string()),
            ],
            true,
        );
        let mut b = Self {
            device: ClockedDevice::start(&start, 0.0).unwrap(),
            session: HardwareSession::new(SessionOptions::default(), 0.0),
            now_ms: 0,
            reply_ms,
            to_device: std::collections::VecDeque::new(),
        };
        b.run_until(|b| b.session.state() != LinkState::Handshaking, 5.0);
        assert_eq!(
            b.session.state(),
            LinkState::Streaming,
            "{}",
            b.session.reason()
        );
        b
    }

    fn now_s(&self) -> f64 {
        self.now_ms as f64 / 1000.0
    }

    /// One wall millisecond.
    fn step(&mut self) {
        use cutlab::protocol::device_worker::VIRTUAL_TICK_MS;
        self.now_ms += 1;
        let now_s = self.now_s();
        let out = self.session.take_output();
        if !out.is_empty() {
            self.to_device.push_back((self.now_ms + self.reply_ms, out));
        }
        if self.now_ms.is_multiple_of(u64::from(VIRTUAL_TICK_MS)) {
            while self
                .to_device
                .front()
                .is_some_and(|(at, _)| *at <= self.now_ms)
            {
                let (_, bytes) = self.to_device.pop_front().unwrap();
                self.device.receive(&bytes);
            }
            let bytes = self.device.tick(now_s);
            self.session.receive(&bytes, now_s);
        }
        if self.now_ms.is_multiple_of(100) {
            self.session.tick(now_s);
        }
        let _ = self.session.take_rows();
    }

    fn run_until(&mut self, done: impl Fn(&Self) -> bool, limit_s: f64) {
        let until = self.now_ms + (limit_s * 1000.0) as u64;
        while !done(self) && self.now_ms < until {
            self.step();
        }
    }

    fn events(&self) -> String {
        self.session
            .events()
            .iter()
            .map(|e| format!("{:8.3} {}\n", e.time_s, e.text))
            .collect()
    }

    /// Runs a teach cut to its end (or `limit_s` of wall time).
    fn teach(&mut self, limit_s: f64) {
        self.session.teach_limits(&spec()).unwrap();
        self.session.start_teach_cut(&spec(), self.now_s()).unwrap();
        self.run_until(|b| b.session.stage() == Stage::Idle, limit_s);
    }
}

/// The host's heartbeat interval for the virtual device's default watchdog, device seconds: what
/// the host's own pacing ([`KeepUp`]) works out, not a copy of it.
fn host_heartbeat_interval_s() -> f64 {
    let device = DeviceEmulator::new(DeviceConfig::new(Preset::ManeeratDoc1)).unwrap();
    KeepUp::new(device.capabilities()).heartbeat_interval_s()
}

/// The re-arm lines' times in `events`.
fn rearm_times(session: &HardwareSession) -> Vec<f64> {
    session
        .events()
        .iter()
        .filter(|e| e.text.contains("re-arming the device"))
        .map(|e| e.time_s)
        .collect()
}

#[test]
fn the_hosts_pacing_keeps_a_virtual_device_fed_at_every_time_scale_when_the_page_keeps_up() {
    // The page answers each tick's bytes before the worker's next tick: from the slowest time
    // scale the form allows to the fastest (which the worker's frame cap makes 40x), the
    // host's heartbeats and commands, paced in device time, never let the device's watchdog
    // fall back.
    for (scale, wall_s) in [("0.01", 120.0), ("1", 60.0), ("8", 20.0), ("1000", 10.0)] {
        let mut b = VirtualBench::new(scale, 5);
        b.session.teach_limits(&spec()).unwrap();
        b.session.start_teach_cut(&spec(), b.now_s()).unwrap();
        b.run_until(|b| b.session.stage() == Stage::Idle, wall_s);
        let events = b.events();
        assert_eq!(
            b.session.stats().watchdog_fallbacks,
            0,
            "x{scale}: {events}"
        );
        assert!(b.session.stats().heartbeats_sent > 0, "x{scale}: {events}");
        if scale != "0.01" {
            assert!(b.session.calibration().is_some(), "x{scale}: {events}");
        }
    }
}

#[test]
fn a_virtual_device_answered_later_than_its_watchdog_falls_back_and_is_re_armed_once_per_attempt() {
    // At 1000x the worker runs 400 frames (0.4 s of device time) a tick and reads the host's
    // bytes only at a tick's start; a page that answers 15 ms late misses a tick, and the
    // device hears nothing for 0.8 s: its watchdog falls back, whatever the host's pacing. The
    // host then sees a batch of 400 samples at once: it re-arms once for the batch (not once
    // an interval of its samples' time), logs it at the sample that sent it, and waits for
    // the device's answer before the next attempt.
    let mut b = VirtualBench::new("1000", 15);
    b.teach(20.0);
    let events = b.events();
    assert!(b.session.stats().watchdog_fallbacks >= 1, "{events}");
    let times = rearm_times(&b.session);
    assert!(!times.is_empty(), "{events}");
    let interval_s = host_heartbeat_interval_s();
    assert!(interval_s > 0.0);
    for pair in times.windows(2) {
        assert!(
            pair[1] - pair[0] >= interval_s - 1e-9,
            "re-arms closer than an interval: {times:?}\n{events}"
        );
    }
    assert!(
        events.contains("device back under the host's control"),
        "{events}"
    );
    // The teach cut saw the fallback: no calibration from it.
    assert!(b.session.calibration().is_none(), "{events}");
}

#[test]
fn a_teach_cut_that_sees_a_device_watchdog_fallback_is_abandoned_and_says_so() {
    let mut config = maneerat(0.5);
    // The device's receiver stalls for 1 s of device time 3 s into the teach cut's part.
    config.faults = FaultInjection {
        stall_at_s: Some(3.0),
        stall_s: 1.0,
        ..FaultInjection::default()
    };
    let mut b = Bench::new(config, SessionOptions::default());
    b.session.teach_limits(&spec()).unwrap();
    b.session.start_teach_cut(&spec(), b.now_s).unwrap();
    b.run_until(|b| b.session.stage() != Stage::TeachCut, 60.0);
    let events = b.events();
    assert_eq!(b.session.stats().watchdog_fallbacks, 1, "{events}");
    assert!(b.session.calibration().is_none(), "{events}");
    assert_eq!(b.session.stage(), Stage::HoldingSafe, "{events}");
    assert!(
        events.contains("teach cut abandoned (the device's watchdog fell back"),
        "{events}"
    );
    assert!(
        b.session.reason().contains("run the teach cut again"),
        "{}",
        b.session.reason()
    );
    // The safe override is held (the device re-armed) until the part ends, then handed back.
    b.run_until(|b| !b.session.holding(), 60.0);
    let events = b.events();
    assert!(!b.session.holding(), "{events}");
    assert!(events.contains("re-arming the device"), "{events}");
    assert!(b.session.calibration().is_none(), "{events}");
    assert!(
        b.rows
            .iter()
            .any(|r| r.phase == "held at the safe override"),
        "{:?}",
        b.rows
            .iter()
            .map(|r| r.phase)
            .collect::<std::collections::BTreeSet<_>>()
    );
}
