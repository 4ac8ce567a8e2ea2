//! A log is one more machine: replaying a recorded run through the loop gives the loop's own
//! decisions, slow RMS logs adapt the chain (and say so), gaps and damaged lines reach the safety
//! envelope, and a log with a measured force calibrates the current → force model.
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
// A whole recorded run at 10 kHz: native only (the wasm suite has the reader's tests).
#![cfg(not(target_arch = "wasm32"))]

#[path = "common/log_fit.rs"]
mod log_fit;

use std::cell::RefCell;
use std::fmt::Write as _;
use std::rc::Rc;
use std::sync::Arc;

use cutlab::closed_loop::definition::RunSpec;
use cutlab::closed_loop::definition::SettingsOverrides;
use cutlab::closed_loop::feedback_loop::ClosedLoop;
use cutlab::closed_loop::lab::{settled_settings, teach_cut_only};
use cutlab::closed_loop::trace::Trace;
use cutlab::control::registry::{ControllerConfig, ControllerKind, RunContext};
use cutlab::estimation::estimator::Feedback;
use cutlab::log::load;
use cutlab::log::mapping::{Channel, Mapping};
use cutlab::log::replay::{write_replay_csv, EnvelopeState, ReplayRun, ReplaySettings};
use cutlab::machine::{Machine, MachineStep, OverrideCommand, SensorSample};
use cutlab::plant::Preset;
use cutlab::safety::{SafetyEvent, SensorFault};
use cutlab::work::Work;
use log_fit::measured_fit;

/// Settings with the time limit left out: a replay ends where its log does.
fn without_time_limit(
    settings: &cutlab::closed_loop::settings::LoopSettings,
) -> cutlab::closed_loop::settings::LoopSettings {
    cutlab::closed_loop::settings::LoopSettings {
        max_duration_s: 0.0,
        ..settings.clone()
    }
}

/// A machine that records every sample it returns.
struct Recorder {
    inner: Box<dyn Machine>,
    samples: Rc<RefCell<Vec<SensorSample>>>,
}

impl Machine for Recorder {
    fn sample_rate_hz(&self) -> f64 {
        self.inner.sample_rate_hz()
    }
    fn step(&mut self, command: OverrideCommand) -> MachineStep {
        let step = self.inner.step(command);
        self.samples.borrow_mut().push(step.sensors);
        step
    }
    fn finished(&self) -> bool {
        self.inner.finished()
    }
}

/// The samples as a machine's monitoring export would write them (full precision).
fn export(samples: &[SensorSample]) -> String {
    let mut csv = String::from(
        "time [s],S_I_U [A],S_I_V [A],S_I_W [A],S_speed [rpm],S_command [rpm],S_FV [V],\
         X_feed [mm/min],X_programmed feed [mm/min],Override [%]\n",
    );
    for s in samples {
        let [u, v, w] = s.spindle_phase_currents_a;
        writeln!(
            csv,
            "{},{u},{v},{w},{},{},{},{},{},{}",
            s.time_s,
            s.spindle_speed_rpm,
            s.spindle_command_rpm,
            s.spindle_fv_voltage_v,
            s.feed_mm_min,
            s.programmed_feed_mm_min,
            s.applied_override_pct
        )
        .unwrap();
    }
    csv
}

fn replay(
    log: &Arc<cutlab::log::Log>,
    mapping: &Mapping,
    settings: &ReplaySettings,
    controller: &ControllerConfig,
) -> cutlab::log::replay::ReplayResult {
    ReplayRun::new(log, mapping, settings, controller)
        .unwrap()
        .run_to_end()
        .unwrap()
}

#[test]
fn replaying_a_recorded_run_through_its_controller_gives_the_loops_decisions() {
    // Paper 001's DOC 2 mm cut with the PI law, recorded for 7 s: the approach in air, arming at
    // 3 s, the entry into the cut and the regulation.
    let spec = RunSpec::new(Preset::ManeeratDoc2, ControllerKind::Pi);
    let (_, calibration) = teach_cut_only(&spec).unwrap();
    let mut settings = settled_settings(&spec, &calibration).unwrap();
    settings.max_duration_s = 7.0;
    settings.envelope.max_current_a = 2.0 * calibration.max_phase_current_a;
    let controller = spec
        .controller
        .build(&RunContext {
            target_force_n: settings.target_force_n,
            control_period_s: settings.control_period_s,
            amps_per_newton: calibration.estimator.sensitivity_a_per_n(3000.0),
        })
        .unwrap();
    let samples = Rc::new(RefCell::new(Vec::new()));
    let machine = Recorder {
        inner: Box::new(spec.preset.machine_with(spec.seed, &spec.plant).unwrap()),
        samples: samples.clone(),
    };
    let live: Trace = ClosedLoop::new(
        Box::new(machine),
        controller,
        calibration.estimator.clone(),
        settings.clone(),
    )
    .unwrap()
    .run();
    let text = export(&samples.borrow());
    let log = Arc::new(load(text.as_bytes(), None).unwrap());
    assert_eq!(log.rows, samples.borrow().len());
    assert!(log.problems.is_empty(), "{:?}", log.problems);

    let mut mapping = Mapping::guess(&log);
    for (column, channel) in [
        ("S_command [rpm]", Channel::SpindleCommand),
        ("S_FV [V]", Channel::FvVoltage),
        ("X_programmed feed [mm/min]", Channel::ProgrammedFeed),
    ] {
        mapping.set(column, Some(channel));
    }
    assert_eq!(mapping.count(Channel::SpindlePhase), 3);
    assert_eq!(mapping.columns_of(Channel::Override), ["Override [%]"]);
    // The replay is asked what the run was asked: its target, its control period, its entry
    // hold, the machine's override input, the tool's chip-load window and stiffness (a log knows
    // neither cutter nor material); the rest it derives as the lab did.
    let replay_settings = ReplaySettings {
        override_mode: spec.preset.override_mode(),
        run: SettingsOverrides {
            feedback: Some(Feedback::SpindleCurrent),
            target_force_n: Some(settings.target_force_n),
            control_period_s: Some(settings.control_period_s),
            entry_hold_s: Some(settings.envelope.entry_hold_s),
            ..SettingsOverrides::default()
        },
        calibration: Some(calibration.clone()),
        chip_load: settings.envelope.chip_load,
        error_model: settings.error_model,
        ..ReplaySettings::default()
    };
    let replayed = replay(&log, &mapping, &replay_settings, &spec.controller);
    // The same settings resolved from the same target, calibration and sample period: the
    // air-cut force, the limits, the control period; only the time limit is the log's end.
    assert_eq!(
        without_time_limit(&replayed.settings),
        without_time_limit(&settings)
    );

    // The same samples through the same loop: every decision, bit for bit.
    assert_eq!(replayed.trace.rows.len(), live.rows.len());
    for (r, l) in replayed.trace.rows.iter().zip(&live.rows) {
        assert_eq!(r.time_s.to_bits(), l.time_s.to_bits());
        assert_eq!(
            r.force_est_n.to_bits(),
            l.force_est_n.to_bits(),
            "at {} s",
            l.time_s
        );
        assert_eq!(
            r.requested_override_pct.to_bits(),
            l.requested_override_pct.to_bits()
        );
        assert_eq!(
            r.override_pct.to_bits(),
            l.override_pct.to_bits(),
            "at {} s",
            l.time_s
        );
        assert_eq!(
            (r.armed, r.sensor_fault, r.feed_hold),
            (l.armed, l.sensor_fault, l.feed_hold)
        );
    }
    assert_eq!(replayed.trace.events, live.events);
    // Decisions that could have gone otherwise: the law moved the override many times, and
    // armed at 3 s.
    let changes = live
        .rows
        .windows(2)
        .filter(|w| w[0].override_pct != w[1].override_pct)
        .count();
    assert!(changes > 20, "only {changes} override changes");
    let armed_at = replayed.summary.armed_at_s.unwrap();
    assert!((3.0..3.1).contains(&armed_at), "{armed_at}");
    // Another controller on the same log decides otherwise.
    let fixed = replay(
        &log,
        &mapping,
        &replay_settings,
        &ControllerConfig::new(ControllerKind::Fixed),
    );
    let differing = fixed
        .trace
        .rows
        .iter()
        .zip(&live.rows)
        .filter(|(f, l)| f.override_pct != l.override_pct)
        .count();
    assert!(differing > live.rows.len() / 3, "{differing}");

    // Without the columns only a CNC export has (programmed speed, F/V voltage, programmed
    // feed), the replay stands in for them and still decides as the loop did nearly everywhere.
    let mut plain = Mapping::guess(&log);
    for column in ["S_command [rpm]", "S_FV [V]", "X_programmed feed [mm/min]"] {
        plain.set(column, None);
    }
    let approximate = replay(&log, &plain, &replay_settings, &spec.controller);
    let close = approximate
        .trace
        .rows
        .iter()
        .zip(&live.rows)
        .filter(|(a, l)| (a.override_pct - l.override_pct).abs() <= 2.0)
        .count();
    assert!(
        close * 10 >= live.rows.len() * 9,
        "{close} of {}",
        live.rows.len()
    );

    // The CSV has one row per control period with the issue's columns.
    let mut out = Vec::new();
    write_replay_csv(&[&replayed], &mut out).unwrap();
    let csv = String::from_utf8(out).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "time_s,current_a,force_est_n,requested_override_pct,override_pct,envelope_state,logged_override_pct"
    );
    assert_eq!(lines.count(), live.rows.len());
    assert!(csv.contains(",disarmed,") && csv.contains(",armed,"));
}

/// A drive's 10 Hz "current feedback" export: RMS values to two decimals, a gap in time, a
/// damaged line.
fn slow_log() -> String {
    let mut csv = String::from("Zeit [s];S_Strom [A];S_Drehzahl [rpm]\r\n");
    for i in 0..600 {
        let t = f64::from(i) * 0.1;
        if (300..310).contains(&i) {
            continue; // a second of missing samples
        }
        if i == 400 {
            csv.push_str("40,0;###;1000\r\n");
            continue;
        }
        // 8 A idle, 12 A in the cut from 20 s: repeated values, as a two-decimal export has.
        let current = if t < 20.0 { 8.0 } else { 12.0 };
        let rpm = if t < 1.0 { 1000.0 * t } else { 1000.0 };
        writeln!(
            csv,
            "{};{};{}\r",
            format!("{t:.1}").replace('.', ","),
            format!("{current:.2}").replace('.', ","),
            rpm
        )
        .unwrap();
    }
    csv
}

#[test]
fn a_slow_rms_log_skips_the_phase_stages_and_the_envelope_sees_its_gaps() {
    let log = Arc::new(load(slow_log().as_bytes(), None).unwrap());
    assert_eq!(log.sample_period_s, Some(0.1));
    let mapping = Mapping::guess(&log);
    assert_eq!(mapping.columns_of(Channel::SpindleCurrent), ["S_Strom [A]"]);
    let settings = ReplaySettings {
        run: SettingsOverrides {
            target_current_a: Some(10.0),
            ..SettingsOverrides::default()
        },
        ..ReplaySettings::default()
    };
    let result = replay(
        &log,
        &mapping,
        &settings,
        &ControllerConfig::new(ControllerKind::Threshold),
    );
    assert!(!result.calibrated);
    assert!(
        result
            .notes
            .iter()
            .any(|n| n.contains("RMS value") && n.contains("skipped")),
        "{:?}",
        result.notes
    );
    // One sample per control period at 10 Hz; the low-passes are off.
    assert!((result.settings.control_period_s - 0.1).abs() < 1e-12);
    assert_eq!(result.settings.spindle_lowpass_hz, f64::INFINITY);
    // The missing second is a sensor fault where it starts; the damaged line (a gap in the
    // current) is one too; repeated values are not "stuck".
    let faults: Vec<(f64, SensorFault)> = result
        .trace
        .events
        .iter()
        .filter_map(|e| match e {
            SafetyEvent::FaultDetected { time_s, fault } => Some((*time_s, *fault)),
            _ => None,
        })
        .collect();
    assert_eq!(
        faults,
        [
            (31.0, SensorFault::MissingSamples),
            (40.0, SensorFault::NonFinite)
        ],
        "{:?}",
        result.trace.events
    );
    // Uncalibrated, the current is what is regulated: at 12 A against 10 A the threshold law
    // cuts the override, and the envelope's states say when it acted.
    let in_cut = result.trace.rows.iter().find(|r| r.time_s > 25.0).unwrap();
    assert!((in_cut.force_est_n - 12.0).abs() < 1e-9);
    assert!(in_cut.override_pct < 100.0, "{in_cut:?}");
    let states: Vec<EnvelopeState> = result
        .trace
        .rows
        .iter()
        .map(|r| result.envelope_state(r))
        .collect();
    for state in [
        EnvelopeState::Disarmed,
        EnvelopeState::Armed,
        EnvelopeState::SensorFault,
    ] {
        assert!(states.contains(&state), "{state:?}");
    }
    // The CSV leaves out force_est_n when nothing was calibrated.
    let mut out = Vec::new();
    write_replay_csv(&[&result], &mut out).unwrap();
    assert!(String::from_utf8(out).unwrap().starts_with(
        "time_s,current_a,requested_override_pct,override_pct,envelope_state,logged_override_pct\n"
    ));
}

#[test]
fn an_uncalibrated_replay_asks_for_a_current_target_and_names_a_missing_current() {
    let log = Arc::new(load(slow_log().as_bytes(), None).unwrap());
    let mapping = Mapping::guess(&log);
    let pi = ControllerConfig::new(ControllerKind::Pi);
    let error = |settings: &ReplaySettings, mapping: &Mapping| {
        ReplayRun::new(&log, mapping, settings, &pi)
            .err()
            .unwrap()
            .to_string()
    };
    let e = error(&ReplaySettings::default(), &mapping);
    assert!(e.contains("give a current target"), "{e}");
    let force_target = ReplaySettings {
        run: SettingsOverrides {
            target_force_n: Some(300.0),
            ..SettingsOverrides::default()
        },
        ..ReplaySettings::default()
    };
    assert!(error(&force_target, &mapping).contains("needs a calibration"));
    let feed = ReplaySettings {
        run: SettingsOverrides {
            feedback: Some(Feedback::FeedCurrent),
            target_current_a: Some(1.0),
            ..SettingsOverrides::default()
        },
        ..ReplaySettings::default()
    };
    let e = error(&feed, &mapping);
    assert!(e.contains("feed feedback needs the feed current"), "{e}");
}

/// One motor's currents at 5 kHz: a 50 Hz three-phase set of amplitude `amplitude(t)`, a force
/// the current follows, and a label.
fn phase_log(columns: usize) -> String {
    let names = ["S_I_U [A]", "S_I_V [A]", "S_I_W [A]"];
    let mut csv = format!(
        "t [s],{},S_speed [rpm],Fx [N]\n",
        names[..columns].join(",")
    );
    for i in 0..20_000 {
        let t = f64::from(i) / 5000.0;
        // Force steps every second: 0, 100, …, 300 N; current 4 A + 0.02 A/N (RMS).
        let force = 100.0 * (t.floor() % 4.0);
        let amplitude = (4.0 + 0.02 * force) * 2f64.sqrt();
        let theta = std::f64::consts::TAU * 50.0 * t;
        let phases: Vec<String> = (0..columns)
            .map(|k| {
                let shift = std::f64::consts::TAU / 3.0 * k as f64;
                format!("{:.6}", amplitude * (theta - shift).cos())
            })
            .collect();
        writeln!(csv, "{t},{},1000,{force}", phases.join(",")).unwrap();
    }
    csv
}

#[test]
fn a_log_with_a_force_calibrates_the_line_its_currents_follow_from_one_two_or_three_phases() {
    for columns in [3, 2, 1] {
        let (log, mapping, fit) = measured_fit(phase_log(columns).as_bytes());
        assert_eq!(mapping.count(Channel::SpindlePhase), columns);
        assert_eq!(mapping.columns_of(Channel::Force), ["Fx [N]"]);
        let cutlab::estimation::estimator::Estimator::Spindle { model, .. } =
            &fit.calibration.estimator
        else {
            panic!("a spindle model");
        };
        let row = &model.rows[0];
        // I_rms = 4 A + 0.02 A/N · F, exactly for three phases; two are completed exactly; one
        // phase is its rectified mean scaled to a sine's RMS, exact for this sine.
        assert!(
            (row.sensitivity_a_per_n - 0.02).abs() < 2e-4,
            "{columns}: {row:?}"
        );
        assert!(
            (row.idle_current_a - 4.0).abs() < 0.04,
            "{columns}: {row:?}"
        );
        assert!(row.quality.r_squared > 0.999, "{columns}: {row:?}");
        // Periods straddling a force step are in, the zero-force second is out.
        assert!(fit.points.len() > 50 && fit.points.iter().all(|p| p.force_n > 0.0));
        assert!(fit.quality().contains("R² 0.99"), "{}", fit.quality());

        // The calibration replays: the estimate reads the log's force back.
        let settings = ReplaySettings {
            calibration: Some(fit.calibration.clone()),
            run: SettingsOverrides {
                target_force_n: Some(200.0),
                ..SettingsOverrides::default()
            },
            ..ReplaySettings::default()
        };
        let result = replay(
            &log,
            &mapping,
            &settings,
            &ControllerConfig::new(ControllerKind::Fixed),
        );
        let steady = result
            .trace
            .rows
            .iter()
            .find(|r| (3.5..3.6).contains(&r.time_s))
            .unwrap();
        assert!(
            (steady.force_est_n - 300.0).abs() < 5.0,
            "{columns}: {steady:?}"
        );
        assert!((steady.force_n - 300.0).abs() < 1e-9);
    }
}

#[test]
fn a_signed_current_calibrates_as_a_phase_and_the_assumed_speed_and_start_are_said() {
    // As a reviewer's DAQ log: 1 kHz, a 50 Hz current of ±5 A then ±10 A named like an RMS,
    // the force 150 then 300 N, no speed column.
    let mut csv = String::from("time_s,spindle_current_a,force_n\n");
    for k in 0..3000 {
        let t = k as f64 * 1e-3;
        let (amplitude_a, force_n) = if k < 1500 {
            (5.0, 150.0)
        } else {
            (10.0, 300.0)
        };
        let i = amplitude_a * (2.0 * std::f64::consts::PI * 50.0 * t).sin();
        csv += &format!("{t:.3},{i:.4},{force_n}\n");
    }
    let (_, mapping, fit) = measured_fit(csv.as_bytes());
    assert_eq!(
        mapping.columns_of(Channel::SpindlePhase),
        ["spindle_current_a"]
    );
    assert_eq!(mapping.count(Channel::SpindleCurrent), 0);
    let notes = fit.notes.join("\n");
    assert!(!notes.contains("is an RMS value"), "{notes}");
    assert!(notes.contains("one spindle phase"), "{notes}");
    assert!(
        notes.contains("the speed is assumed to be 1000 rpm (the log does not say it"),
        "{notes}"
    );
    assert!(
        notes.contains("its start is assumed to be there (the log does not show it)"),
        "{notes}"
    );
    assert!(notes.contains("leaves out the first 1 s"), "{notes}");
}
