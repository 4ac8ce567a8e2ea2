//! The envelope's tests: each rule through [`SafetyEnvelope::command`] and
//! [`SafetyEnvelope::observe`], and properties that hold for random (also non-finite) inputs.

use super::*;
use crate::machine::SensorSample;
use crate::rng::Rng;

fn running_sample(time_s: f64) -> SensorSample {
    SensorSample {
        time_s,
        feed_phase_currents_a: [1.0, -0.5, -0.5],
        spindle_phase_currents_a: [5.0, -2.5, -2.5],
        feed_mm_min: 100.0,
        spindle_running: true,
        time_since_spindle_start_s: 10.0 + time_s,
        ..SensorSample::default()
    }
}

fn envelope(config: EnvelopeConfig) -> SafetyEnvelope {
    SafetyEnvelope::new(config, 1000.0).unwrap()
}

#[test]
fn in_air_the_override_stays_at_the_entry_override_whatever_the_controller_asks() {
    // Target 300 N: below 60 N the tool is in air.
    let mut env = envelope(EnvelopeConfig::for_target(300.0));
    let mut t = 0.0;
    let mut step = |env: &mut SafetyEnvelope, request: f64, force_n: f64| {
        t += 0.1;
        env.command(request, force_n, t, 0.1, &running_sample(t))
            .override_pct
    };
    // A controller that sees no force asks for the most it may: the envelope holds 100 %,
    // and says so once.
    for _ in 0..30 {
        assert_eq!(step(&mut env, 150.0, 5.0), 100.0);
    }
    let mut seen = Vec::new();
    let mut air_events = |env: &mut SafetyEnvelope| {
        env.drain_events(&mut seen);
        seen.iter()
            .filter(|e| matches!(e, SafetyEvent::AirCut { .. }))
            .count()
    };
    assert_eq!(air_events(&mut env), 1);
    // Asking for less changes nothing either: in air the controller is not in charge.
    assert_eq!(step(&mut env, 50.0, 5.0), 100.0);
    assert!(env.holding());
    // In the cut the controller has the whole band again.
    let mut last = 0.0;
    for _ in 0..20 {
        last = step(&mut env, 150.0, 250.0);
    }
    assert_eq!(last, 150.0);
    // The next stretch of air is a new event.
    step(&mut env, 150.0, 5.0);
    assert_eq!(air_events(&mut env), 2);
    // Off: the air cut rule does nothing.
    let mut config = EnvelopeConfig::for_target(300.0);
    config.air_cut_force_n = 0.0;
    let mut env = envelope(config);
    let mut last = 0.0;
    for _ in 0..20 {
        last = step(&mut env, 150.0, 5.0);
    }
    assert_eq!(last, 150.0);
}

#[test]
fn after_an_entry_the_override_holds_until_the_cutter_is_engaged_or_the_target_reached() {
    // Target 300 N: in air below 60 N; the cutter engages over 0.5 s.
    let mut config = EnvelopeConfig::for_target(300.0);
    config.entry_hold_s = 0.5;
    config.entry_release_n = 300.0;
    let mut env = envelope(config);
    let mut t = 0.0;
    let mut step = |env: &mut SafetyEnvelope, force_n: f64| {
        t += 0.1;
        env.command(150.0, force_n, t, 0.1, &running_sample(t))
            .override_pct
    };
    step(&mut env, 5.0);
    // The cutter engages: the force rises, the controller asks for 150 %, the envelope holds
    // 100 % for the hold's 0.5 s.
    for k in 1..=5 {
        assert_eq!(step(&mut env, 40.0 * f64::from(k) + 30.0), 100.0);
        assert!(env.holding(), "period {k}");
    }
    // Then the cutter is in the cut (within a period of the hold's end: times add up in
    // floating point).
    step(&mut env, 235.0);
    step(&mut env, 236.0);
    assert!(!env.holding());
    let mut events = Vec::new();
    env.drain_events(&mut events);
    let kinds: Vec<&str> = events
        .iter()
        .map(|e| match e {
            SafetyEvent::Armed { .. } => "armed",
            SafetyEvent::AirCut { .. } => "air",
            SafetyEvent::EntryHold { .. } => "hold",
            SafetyEvent::EntrySettled { .. } => "settled",
            _ => "other",
        })
        .collect();
    assert_eq!(kinds, ["armed", "air", "hold", "settled"]);
    // A cut already at the target ends the hold at once: the controller reduces from there.
    step(&mut env, 5.0);
    step(&mut env, 200.0);
    assert!(env.holding());
    step(&mut env, 320.0);
    assert!(!env.holding());
    // Off (0 s): the controller is in charge as soon as the tool is in the cut.
    let mut config = EnvelopeConfig::for_target(300.0);
    config.entry_hold_s = 0.0;
    let mut env = envelope(config);
    step(&mut env, 5.0);
    step(&mut env, 100.0);
    assert!(!env.holding());
}

#[test]
fn the_chip_load_window_keeps_every_command_inside_it_and_says_when_it_holds() {
    // Two teeth at 1000 rpm, 200 mm/min: 0.1 mm per tooth at 100 %; a window of 0.02–0.15 mm
    // allows 20–150 % of the 10–255 % band.
    let mut config = EnvelopeConfig::for_target(300.0);
    config.min_override_pct = 10.0;
    config.max_override_pct = 255.0;
    config.resolution = OverrideResolution::WholePercent;
    config.chip_load = Some(ChipLoad {
        teeth: 2,
        min_mm: 0.02,
        max_mm: 0.15,
    });
    let mut env = envelope(config);
    let sample = |t: f64, feed: f64| SensorSample {
        programmed_feed_mm_min: feed,
        spindle_command_rpm: 1000.0,
        ..running_sample(t)
    };
    let mut rng = Rng::seed_from(11);
    let mut t = 0.0;
    for _ in 0..2000 {
        t += 0.05;
        let feed = if rng.uniform() < 0.5 { 200.0 } else { 400.0 };
        let request = -50.0 + 450.0 * rng.uniform();
        let c = env.command(request, 300.0, t, 0.05, &sample(t, feed));
        let per_tooth = feed * c.override_pct / 100.0 / 2000.0;
        assert!(
            (0.02 - 1e-12..=0.15 + 1e-12).contains(&per_tooth),
            "{per_tooth} mm at {feed} mm/min, {} %",
            c.override_pct
        );
    }
    let mut events = Vec::new();
    env.drain_events(&mut events);
    // Held at each end, once per stretch (the last stretches' events; the queue holds 16).
    assert!(events.iter().any(|e| matches!(
        e,
        SafetyEvent::ChipLoad {
            end: ChipLoadEnd::Highest,
            ..
        }
    )));
    // No feed or no spindle: no window to keep.
    let free = env.command(250.0, 300.0, t + 10.0, 10.0, &sample(t, 0.0));
    assert_eq!(free.override_pct, 250.0);
}

#[test]
fn a_chip_load_window_beyond_the_band_is_said_to_be_out_of_reach() {
    // 20,000 mm/min at 1000 rpm with two teeth: 10 mm per tooth at 100 %, 1 mm at the band's
    // lowest 10 %, nearly seven times the 0.15 mm the edge takes. The envelope runs at 10 %
    // (the band is the machine's) and the event must not claim the window holds.
    let mut config = EnvelopeConfig::for_target(300.0);
    config.min_override_pct = 10.0;
    config.max_override_pct = 150.0;
    config.chip_load = Some(ChipLoad {
        teeth: 2,
        min_mm: 0.02,
        max_mm: 0.15,
    });
    let mut env = envelope(config);
    let fast = |t: f64| SensorSample {
        programmed_feed_mm_min: 20_000.0,
        spindle_command_rpm: 1000.0,
        ..running_sample(t)
    };
    let mut t = 0.0;
    let mut last = 0.0;
    for _ in 0..100 {
        t += 0.05;
        last = env.command(100.0, 300.0, t, 0.05, &fast(t)).override_pct;
    }
    assert_eq!(last, 10.0);
    let mut events = Vec::new();
    env.drain_events(&mut events);
    let said: Vec<String> = events
        .iter()
        .filter(|e| matches!(e, SafetyEvent::ChipLoad { .. }))
        .map(SafetyEvent::describe)
        .collect();
    assert_eq!(said.len(), 1, "{said:?}");
    assert!(
        said[0].contains("runs 1.000 mm per tooth, above the 0.150 mm"),
        "{}",
        said[0]
    );
    assert!(said[0].contains("too high for this cutter"), "{}", said[0]);
}

#[test]
fn a_non_finite_request_is_one_controller_fault_event_and_the_override_holds() {
    let mut env = envelope(EnvelopeConfig::for_target(300.0));
    let s = running_sample(0.0);
    let held = env.command(100.0, 300.0, 0.0, 0.1, &s).override_pct;
    assert!(env.armed());
    for (i, bad) in [f64::NAN, f64::NEG_INFINITY, f64::INFINITY]
        .into_iter()
        .enumerate()
    {
        let cmd = env.command(bad, 300.0, 0.1 * (i + 1) as f64, 0.1, &s);
        assert_eq!(cmd.override_pct, held);
    }
    env.command(110.0, 300.0, 0.4, 0.1, &s);
    env.command(f64::NAN, 300.0, 0.5, 0.1, &s);
    let mut events = Vec::new();
    env.drain_events(&mut events);
    let faults: Vec<f64> = events
        .iter()
        .filter_map(|e| match e {
            SafetyEvent::ControllerFault { time_s } => Some(*time_s),
            _ => None,
        })
        .collect();
    // One event per episode: the first bad request, and again after a good one.
    assert_eq!(faults, vec![0.1, 0.5]);
}

#[test]
fn holds_the_arming_override_until_the_delay_has_passed() {
    let mut env = envelope(EnvelopeConfig::for_target(300.0));
    let mut s = running_sample(0.0);
    s.time_since_spindle_start_s = 1.0;
    let cmd = env.command(40.0, 100.0, 0.0, 0.1, &s);
    assert_eq!(cmd.override_pct, 100.0);
    assert!(!env.armed());
    s.time_since_spindle_start_s = 3.0;
    env.command(40.0, 100.0, 0.1, 0.1, &s);
    assert!(env.armed());
    let mut events = Vec::new();
    env.drain_events(&mut events);
    assert_eq!(events, vec![SafetyEvent::Armed { time_s: 0.1 }]);
}

#[test]
fn without_a_spindle_arming_counts_from_the_programmed_feed() {
    let mut config = EnvelopeConfig::for_target(300.0);
    config.arming_trigger = ArmingTrigger::ProgrammedFeed;
    config.arming_delay_s = 0.5;
    let mut env = envelope(config);
    // A bench: no spindle ever; the program feeds from the start; the feed motor's currents
    // turn (constant ones would be a stuck sensor, which the envelope now watches for).
    let bench = |time_s: f64, programmed_feed_mm_min: f64| {
        let angle = 2.0 * std::f64::consts::PI * 50.0 * time_s;
        SensorSample {
            spindle_running: false,
            spindle_phase_currents_a: [0.0; 3],
            feed_phase_currents_a: [0.0, 2.0, 4.0].map(|k| (angle - k).sin()),
            programmed_feed_mm_min,
            ..running_sample(time_s)
        }
    };
    let feed_for = |env: &mut SafetyEnvelope, from_s: f64, to_s: f64, feed: f64| {
        let mut t = from_s;
        while t < to_s - 1e-9 {
            env.observe(&bench(t, feed));
            t += 0.001;
        }
        env.command(40.0, 100.0, to_s, 0.1, &bench(to_s, feed))
    };
    assert_eq!(feed_for(&mut env, 0.0, 0.4, 500.0).override_pct, 100.0);
    assert!(!env.armed());
    feed_for(&mut env, 0.4, 0.6, 500.0);
    assert!(env.armed());
    // The program stops feeding: disarmed, and the delay starts again with the next move.
    feed_for(&mut env, 0.6, 0.7, 0.0);
    assert!(!env.armed());
    feed_for(&mut env, 0.7, 1.0, 500.0);
    assert!(!env.armed());
    let mut events = Vec::new();
    env.drain_events(&mut events);
    assert_eq!(events, vec![SafetyEvent::Armed { time_s: 0.6 }]);
}

#[test]
fn rate_limit_moves_the_dial_one_grade_at_a_time() {
    let mut env = envelope(EnvelopeConfig::for_target(300.0));
    let s = running_sample(0.0);
    // 100 %/s for 0.1 s periods: 10 % per period, one dial grade.
    let outputs: Vec<f64> = (0..5)
        .map(|i| {
            env.command(40.0, 100.0, f64::from(i) * 0.1, 0.1, &s)
                .override_pct
        })
        .collect();
    assert_eq!(outputs, vec![90.0, 80.0, 70.0, 60.0, 50.0]);
}

#[test]
fn stuck_currents_raise_a_fault_and_hold_then_clear() {
    let mut env = envelope(EnvelopeConfig::for_target(300.0));
    let mut events = Vec::new();
    let mut t = 0.0;
    // A healthy, rotating signal first.
    for i in 0..100 {
        let mut s = running_sample(t);
        s.feed_phase_currents_a[0] = f64::from(i % 7);
        env.observe(&s);
        t += 0.001;
    }
    assert_eq!(env.fault(), None);
    // 60 ms of identical readings (the limit is 50 ms).
    for _ in 0..60 {
        env.observe(&running_sample(t));
        t += 0.001;
    }
    assert_eq!(env.fault(), Some(SensorFault::Stuck));
    let s = running_sample(t);
    let before = env.output_pct();
    assert_eq!(env.command(20.0, 100.0, t, 0.1, &s).override_pct, before);
    for i in 0..150 {
        let mut s = running_sample(t);
        s.feed_phase_currents_a[0] = f64::from(i % 5);
        env.observe(&s);
        t += 0.001;
    }
    assert_eq!(env.fault(), None);
    env.drain_events(&mut events);
    events.retain(|e| !matches!(e, SafetyEvent::Armed { .. }));
    assert!(matches!(
        events[..],
        [
            SafetyEvent::FaultDetected {
                fault: SensorFault::Stuck,
                ..
            },
            SafetyEvent::FaultCleared { .. }
        ]
    ));
}

#[test]
fn a_time_gap_is_missing_samples() {
    let mut env = envelope(EnvelopeConfig::for_target(300.0));
    env.observe(&running_sample(0.0));
    env.observe(&running_sample(0.010));
    assert_eq!(env.fault(), Some(SensorFault::MissingSamples));
}

#[test]
fn overload_latches_feed_hold_after_the_set_time() {
    let mut env = envelope(EnvelopeConfig::for_target(300.0));
    let s = running_sample(0.0);
    let mut held_at = None;
    for i in 0..10 {
        let cmd = env.command(100.0, 500.0, f64::from(i) * 0.1, 0.1, &s);
        if cmd.feed_hold && held_at.is_none() {
            held_at = Some(i);
        }
    }
    // 0.2 s must be exceeded: the third period above the limit trips it.
    assert_eq!(held_at, Some(2));
    // Latched: a normal force does not release it.
    assert!(env.command(100.0, 100.0, 1.0, 0.1, &s).feed_hold);
}

/// A random value that is sometimes wild: huge, negative, NaN or infinite.
fn wild(rng: &mut Rng, typical: f64) -> f64 {
    match rng.next_u64() % 10 {
        0 => f64::NAN,
        1 => f64::INFINITY,
        2 => f64::NEG_INFINITY,
        3 => -typical * 10.0 * rng.uniform(),
        4 => typical * 1e6 * rng.uniform(),
        _ => typical * 2.0 * rng.uniform(),
    }
}

#[test]
fn property_output_stays_inside_the_envelope_for_random_inputs() {
    let resolutions = [
        OverrideResolution::Continuous,
        OverrideResolution::WholePercent,
        OverrideResolution::Dial((0..16).map(|i| 10.0 * f64::from(i)).collect()),
    ];
    let mut rng = Rng::seed_from(2024);
    for case in 0..300 {
        let mut config = EnvelopeConfig::for_target(300.0);
        config.resolution = resolutions[case % 3].clone();
        config.min_override_pct = 10.0 * (rng.uniform() * 5.0).floor();
        config.max_override_pct =
            config.min_override_pct + 20.0 + 10.0 * (rng.uniform() * 10.0).floor();
        config.max_rate_pct_per_s = 5.0 + 200.0 * rng.uniform();
        config.arming_delay_s = 2.0 * rng.uniform();
        if rng.uniform() < 0.5 {
            config.arming_trigger = ArmingTrigger::ProgrammedFeed;
        }
        if rng.uniform() < 0.5 {
            config.fault_action = FaultAction::Fallback(config.min_override_pct);
        }
        let step = config.resolution.step_pct();
        let (min, max, rate) = (
            config.min_override_pct,
            config.max_override_pct,
            config.max_rate_pct_per_s,
        );
        let mut env = SafetyEnvelope::new(config.clone(), 1000.0).unwrap();
        let mut previous = env.output_pct();
        let mut t = 0.0;
        for _ in 0..200 {
            for _ in 0..10 {
                let mut s = running_sample(t);
                s.feed_phase_currents_a[0] = wild(&mut rng, 5.0);
                s.spindle_running = rng.uniform() < 0.95;
                s.time_since_spindle_start_s = wild(&mut rng, 3.0);
                s.programmed_feed_mm_min = if rng.uniform() < 0.9 {
                    100.0
                } else {
                    wild(&mut rng, 100.0)
                };
                env.observe(&s);
                t += if rng.uniform() < 0.01 { 0.05 } else { 0.001 };
            }
            let dt = 0.01;
            let s = running_sample(t);
            let cmd = env.command(wild(&mut rng, 100.0), wild(&mut rng, 300.0), t, dt, &s);
            let out = cmd.override_pct;
            assert!(out.is_finite(), "case {case}: non-finite output");
            assert!(
                out >= min && out <= max,
                "case {case}: {out} outside [{min}, {max}]"
            );
            assert_eq!(
                config.resolution.nearest(out, min, max),
                Some(out),
                "case {case}: {out} is not a machine position"
            );
            assert!(
                (out - previous).abs() <= rate * dt + step + 1e-9,
                "case {case}: jump {previous} → {out}"
            );
            previous = out;
        }
    }
}

#[test]
fn property_each_run_of_non_finite_requests_is_one_fault_event_and_the_output_holds() {
    let mut rng = Rng::seed_from(4711);
    let mut episodes = 0;
    for case in 0..200 {
        let mut config = EnvelopeConfig::for_target(300.0);
        if case % 2 == 0 {
            config.resolution = OverrideResolution::Continuous;
        }
        config.min_override_pct = 10.0 * (rng.uniform() * 5.0).floor();
        config.max_override_pct = config.min_override_pct + 20.0 + 100.0 * rng.uniform();
        config.max_rate_pct_per_s = 5.0 + 200.0 * rng.uniform();
        config.arming_delay_s = rng.uniform();
        let step = config.resolution.step_pct();
        let (min, max, rate) = (
            config.min_override_pct,
            config.max_override_pct,
            config.max_rate_pct_per_s,
        );
        let mut env = envelope(config);
        let (mut previous, mut t, mut spindle_start_s) = (env.output_pct(), 0.0, 0.0);
        // Whether the last request the envelope listened to was not a number.
        let mut in_episode = false;
        let mut events = Vec::new();
        for period in 0..400 {
            let dt = 0.01 + 0.05 * rng.uniform();
            t += dt;
            // Now and then the spindle stops and starts again: disarmed, then re-armed.
            let mut s = running_sample(t);
            if rng.uniform() < 0.01 {
                spindle_start_s = t;
            }
            s.time_since_spindle_start_s = t - spindle_start_s;
            // Runs of non-finite requests among finite ones, some far outside the limits.
            let request = match rng.next_u64() % 8 {
                0 | 1 if in_episode || rng.uniform() < 0.3 => {
                    [f64::NAN, f64::INFINITY, f64::NEG_INFINITY][period % 3]
                }
                2 => -1e6 + 2e6 * rng.uniform(),
                _ => 200.0 * rng.uniform(),
            };
            let out = env.command(request, 100.0, t, dt, &s).override_pct;
            events.clear();
            env.drain_events(&mut events);
            let faults = events
                .iter()
                .filter(|e| matches!(e, SafetyEvent::ControllerFault { time_s } if *time_s == t))
                .count();
            let listened = env.armed() && env.fault().is_none();
            let bad = !request.is_finite();
            let opens = listened && bad && !in_episode;
            assert_eq!(
                faults,
                usize::from(opens),
                "case {case}, period {period}: {events:?}"
            );
            episodes += usize::from(opens);
            if listened {
                in_episode = bad;
                if bad {
                    assert_eq!(out, previous, "case {case}, period {period}: not held");
                }
            }
            assert!(
                out.is_finite() && out >= min && out <= max,
                "case {case}: {out}"
            );
            assert!(
                (out - previous).abs() <= rate * dt + step + 1e-9,
                "case {case}, period {period}: jump {previous} → {out}"
            );
            previous = out;
        }
        let described = SafetyEvent::ControllerFault { time_s: t }.describe();
        assert!(described.contains("non-finite override"), "{described}");
    }
    assert!(episodes > 1000, "only {episodes} episodes");
}
