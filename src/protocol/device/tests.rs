//! The emulator's tests, driven through its frames as a host would: capabilities, a part's
//! samples, the watchdog, an over-current, and junk bytes.

use super::*;
use crate::plant::Preset;
use crate::protocol::codec::{encode_frame, MAX_FRAME_LEN};
use crate::protocol::frame::{AckResult, FaultKind, Frame, OverrideModeCode};
use crate::protocol::frame::{Arm, Hello, SetOverride};

fn frames(bytes: &[u8]) -> Vec<Frame> {
    Decoder::new()
        .frames(bytes)
        .filter_map(Result::ok)
        .collect()
}

fn bytes_of(frame: Frame) -> Vec<u8> {
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = encode_frame(&frame, &mut buf).unwrap();
    buf[..n].to_vec()
}

#[test]
fn hello_gets_capabilities_and_arm_starts_a_part_that_streams_samples() {
    let mut d = DeviceEmulator::new(DeviceConfig::new(Preset::KimStepDoc)).unwrap();
    let mut out = Vec::new();
    d.receive(
        &bytes_of(Frame::Hello(Hello {
            version_major: 1,
            version_minor: 0,
        })),
        &mut out,
    );
    let Some(Frame::Capabilities(c)) = frames(&out).first().copied() else {
        panic!("no capabilities")
    };
    assert_eq!(c.sample_rate_hz, 1000.0);
    assert_eq!(c.override_mode, OverrideModeCode::WholePercent);
    out.clear();
    d.receive(&bytes_of(Frame::Arm(Arm { seq: 1 })), &mut out);
    assert!(d.in_cycle());
    d.receive(
        &bytes_of(Frame::SetOverride(SetOverride {
            seq: 2,
            override_cpct: 8760,
            flags: 0,
            sample_time_us: 0,
        })),
        &mut out,
    );
    let acks: Vec<_> = frames(&out)
        .into_iter()
        .filter_map(|f| match f {
            Frame::Ack(a) => Some(a),
            _ => None,
        })
        .collect();
    // Whole percent: 87.6 % applies as 88 %.
    assert_eq!(acks[1].applied_override_cpct, 8800);
    out.clear();
    for _ in 0..10 {
        d.step_frame(&mut out);
    }
    let samples: Vec<_> = frames(&out)
        .into_iter()
        .filter_map(|f| match f {
            Frame::Sample(s) => Some(s),
            _ => None,
        })
        .collect();
    assert_eq!(samples.len(), 10);
    assert_eq!(samples[9].seq, 10);
    assert_eq!(samples[9].time_us, 10_000);
}

#[test]
fn the_watchdog_falls_back_without_the_host_and_only_an_arm_clears_it() {
    let mut d = DeviceEmulator::new(DeviceConfig::new(Preset::KimStepDoc)).unwrap();
    let mut out = Vec::new();
    d.receive(&bytes_of(Frame::Arm(Arm { seq: 1 })), &mut out);
    for _ in 0..600 {
        d.step_frame(&mut out);
    }
    assert_eq!(d.stats().watchdog_fallbacks, 1);
    let faults: Vec<_> = frames(&out)
        .into_iter()
        .filter_map(|f| match f {
            Frame::Fault(f) => Some(f),
            _ => None,
        })
        .collect();
    assert_eq!(faults[0].kind, FaultKind::Watchdog);
    assert_eq!(faults[0].applied_override_cpct, 5000);
    out.clear();
    d.receive(
        &bytes_of(Frame::SetOverride(SetOverride {
            seq: 2,
            override_cpct: 12000,
            flags: 0,
            sample_time_us: (d.time_s() * 1e6) as u32,
        })),
        &mut out,
    );
    let Some(Frame::Ack(a)) = frames(&out).first().copied() else {
        panic!()
    };
    assert_eq!(
        (a.result, a.applied_override_cpct),
        (AckResult::NotArmed, 5000)
    );
    out.clear();
    d.receive(&bytes_of(Frame::Arm(Arm { seq: 3 })), &mut out);
    let got = frames(&out);
    assert!(got
        .iter()
        .any(|f| matches!(f, Frame::Fault(x) if x.active == 0)));
}

#[test]
fn an_over_current_is_reported_raised_and_cleared() {
    let mut config = DeviceConfig::new(Preset::KimStepDoc);
    // The spindle's starting current peaks near 70 A; running idle, about 12 A.
    config.over_current_a = 30.0;
    let mut d = DeviceEmulator::new(config).unwrap();
    let mut out = Vec::new();
    d.receive(&bytes_of(Frame::Arm(Arm { seq: 1 })), &mut out);
    let mut faults = Vec::new();
    for _ in 0..3000 {
        // Keep the watchdog fed.
        d.receive(
            &bytes_of(Frame::Heartbeat(
                crate::protocol::frame::Heartbeat::default(),
            )),
            &mut out,
        );
        d.step_frame(&mut out);
        faults.extend(frames(&out).into_iter().filter_map(|f| match f {
            Frame::Fault(f) => Some((f.kind, f.active)),
            _ => None,
        }));
        out.clear();
    }
    assert_eq!(
        faults.first().copied(),
        Some((FaultKind::OverCurrent, 1)),
        "{faults:?}"
    );
    assert!(faults.contains(&(FaultKind::OverCurrent, 0)), "{faults:?}");
    assert_eq!(d.stats().watchdog_fallbacks, 0);
}

#[test]
fn any_bytes_from_the_host_are_survived() {
    let mut d = DeviceEmulator::new(DeviceConfig::new(Preset::KimStepDoc)).unwrap();
    let mut rng = Rng::seed_from(5);
    let mut out = Vec::new();
    for _ in 0..200 {
        let junk: Vec<u8> = (0..300).map(|_| rng.next_u64() as u8).collect();
        d.receive(&junk, &mut out);
        d.step_frame(&mut out);
    }
    assert!(d.decoder_stats().bytes_dropped > 0);
}
