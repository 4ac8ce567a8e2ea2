//! The protocol codec: every frame type round-trips, the decoder recovers every valid frame after
//! garbage, truncated and oversized frames, and no byte stream makes it panic (a bounded,
//! time-limited fuzz run).
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use cutlab::protocol::codec::{encode_frame, DecodeError, Decoder, MAX_BLOCK_LEN, MAX_FRAME_LEN};
use cutlab::protocol::frame::{
    padded, Ack, AckResult, Arm, Capabilities, Disarm, Fault, FaultKind, Frame, FrameType,
    Heartbeat, Hello, OverrideModeCode, Reset, Sample, SetOverride, SimTruth,
};
use cutlab::rng::Rng;

fn u8r(r: &mut Rng) -> u8 {
    r.next_u64() as u8
}
fn u16r(r: &mut Rng) -> u16 {
    r.next_u64() as u16
}
fn u32r(r: &mut Rng) -> u32 {
    r.next_u64() as u32
}
fn i16r(r: &mut Rng) -> i16 {
    r.next_u64() as i16
}
/// Any f32 bit pattern but NaN (NaN != NaN would fail the equality; NaN is checked by bytes).
fn f32r(r: &mut Rng) -> f32 {
    let v = f32::from_bits(u32r(r));
    if v.is_nan() {
        1.5
    } else {
        v
    }
}

/// A random frame of type `t`, every field drawn from its whole range.
fn random_frame(t: FrameType, r: &mut Rng) -> Frame {
    match t {
        FrameType::Hello => Frame::Hello(Hello {
            version_major: u8r(r),
            version_minor: u8r(r),
        }),
        FrameType::Capabilities => Frame::Capabilities(Capabilities {
            version_major: u8r(r),
            version_minor: u8r(r),
            device_id: core::array::from_fn(|_| u8r(r)),
            program: padded("kim-step-doc"),
            channel_mask: u8r(r),
            spindle_current_a_per_count: f32r(r),
            feed_current_a_per_count: f32r(r),
            fv_v_per_count: f32r(r),
            sample_rate_hz: f32r(r),
            override_mode: OverrideModeCode::from_code(u8r(r)),
            min_override_cpct: u16r(r),
            max_override_cpct: u16r(r),
            dial_cpct: core::array::from_fn(|_| u16r(r)),
            watchdog_timeout_ms: u16r(r),
            fallback_override_cpct: u16r(r),
            over_current_a: f32r(r),
            features: u8r(r),
            measured: u16r(r),
            fallback_limit_ms: u16r(r),
            line_baud: u32r(r),
        }),
        FrameType::Sample => Frame::Sample(Sample {
            seq: u32r(r),
            time_us: u32r(r),
            flags: u8r(r),
            spindle_current_counts: [i16r(r), i16r(r), i16r(r)],
            feed_current_counts: [i16r(r), i16r(r), i16r(r)],
            fv_counts: i16r(r),
            spindle_speed_rpm: f32r(r),
            spindle_command_rpm: f32r(r),
            programmed_feed_mm_min: f32r(r),
            feed_mm_min: f32r(r),
            applied_override_cpct: u16r(r),
            dial_code: u8r(r),
            faults: u8r(r),
        }),
        FrameType::SimTruth => {
            let seq = u32r(r);
            Frame::SimTruth(SimTruth::from_values(
                seq,
                core::array::from_fn(|_| f32r(r)),
            ))
        }
        FrameType::SetOverride => Frame::SetOverride(SetOverride {
            seq: u32r(r),
            override_cpct: u16r(r),
            flags: u8r(r),
            sample_time_us: u32r(r),
        }),
        FrameType::Arm => Frame::Arm(Arm { seq: u32r(r) }),
        FrameType::Disarm => Frame::Disarm(Disarm { seq: u32r(r) }),
        FrameType::Reset => Frame::Reset(Reset { seq: u32r(r) }),
        FrameType::Ack => Frame::Ack(Ack {
            seq: u32r(r),
            command: u8r(r),
            result: AckResult::from_code(u8r(r)),
            applied_override_cpct: u16r(r),
            flags: u8r(r),
        }),
        FrameType::Fault => Frame::Fault(Fault {
            seq: u32r(r),
            time_us: u32r(r),
            kind: FaultKind::from_code(u8r(r)),
            active: u8r(r),
            channel: u8r(r),
            applied_override_cpct: u16r(r),
        }),
        FrameType::Heartbeat => Frame::Heartbeat(Heartbeat {
            seq: u32r(r),
            time_us: u32r(r),
            flags: u8r(r),
            faults: u8r(r),
            last_sample_seq: u32r(r),
        }),
    }
}

fn any_frame(r: &mut Rng) -> Frame {
    let t = FrameType::ALL[(r.next_u64() % FrameType::ALL.len() as u64) as usize];
    random_frame(t, r)
}

fn encoded(frame: &Frame) -> Vec<u8> {
    let mut out = [0u8; MAX_FRAME_LEN];
    let n = encode_frame(frame, &mut out).unwrap();
    out[..n].to_vec()
}

fn decode_all(bytes: &[u8]) -> (Vec<Result<Frame, DecodeError>>, Decoder) {
    let mut d = Decoder::new();
    let got = d.frames(bytes).collect();
    (got, d)
}

#[test]
fn every_frame_type_round_trips_with_any_field_values() {
    let mut r = Rng::seed_from(16);
    for t in FrameType::ALL {
        for _ in 0..300 {
            let f = random_frame(t, &mut r);
            let bytes = encoded(&f);
            assert_eq!(bytes.first(), Some(&0));
            assert_eq!(bytes.last(), Some(&0));
            assert!(!bytes[1..bytes.len() - 1].contains(&0));
            let (got, d) = decode_all(&bytes);
            assert_eq!(got, vec![Ok(f)], "{}", t.name());
            assert_eq!(d.stats().bytes_dropped, 0);
            assert_eq!(d.stats().bytes_received, bytes.len() as u64);
            let mut payload = [0u8; 256];
            let n = f.write_payload(&mut payload).unwrap();
            assert_eq!(n, t.payload_len(), "{}", t.name());
        }
    }
}

#[test]
fn nan_fields_round_trip_bit_for_bit() {
    let f = Frame::SimTruth(SimTruth::from_values(3, [f32::NAN; 16]));
    let bytes = encoded(&f);
    let (got, _) = decode_all(&bytes);
    let Some(Ok(back)) = got.first() else {
        panic!("{got:?}")
    };
    assert_eq!(encoded(back), bytes);
}

#[test]
fn garbage_spliced_between_frames_is_skipped_and_every_later_frame_recovered() {
    let mut r = Rng::seed_from(7);
    for round in 0..200 {
        let frames: Vec<Frame> = (0..20).map(|_| any_frame(&mut r)).collect();
        let mut stream = Vec::new();
        let mut garbage_bytes = 0u64;
        for f in &frames {
            if r.uniform() < 0.4 {
                let len = (r.next_u64() % 400) as usize;
                let mut g: Vec<u8> = (0..len).map(|_| u8r(&mut r)).collect();
                // Some garbage is a frame cut short by a reset: its first half.
                if r.uniform() < 0.3 {
                    let cut = encoded(&any_frame(&mut r));
                    g.extend_from_slice(&cut[..cut.len() / 2]);
                }
                garbage_bytes += g.len() as u64;
                stream.extend_from_slice(&g);
            }
            stream.extend_from_slice(&encoded(f));
        }
        let (got, d) = decode_all(&stream);
        let ok: Vec<Frame> = got.iter().filter_map(|g| g.ok()).collect();
        assert_eq!(ok, frames, "round {round}");
        let s = d.stats();
        assert_eq!(s.frames_decoded, frames.len() as u64);
        // At most the garbage is counted dropped: its bytes, and its zeros beyond the two that
        // may stand between frames (less what random garbage may, very rarely, form into
        // unknown frames, and the delimiters of the blocks it makes).
        assert!(s.bytes_dropped <= garbage_bytes, "round {round}");
        assert_eq!(s.bytes_received, stream.len() as u64);
    }
}

#[test]
fn truncated_and_oversized_frames_cost_only_themselves() {
    let mut r = Rng::seed_from(3);
    let a = any_frame(&mut r);
    let b = any_frame(&mut r);
    let ea = encoded(&a);
    let eb = encoded(&b);
    let mut stream = ea[..ea.len() - 3].to_vec();
    stream.extend(std::iter::repeat_n(0x42u8, MAX_BLOCK_LEN * 3));
    stream.extend_from_slice(&eb);
    stream.extend_from_slice(&ea);
    let (got, d) = decode_all(&stream);
    let ok: Vec<Frame> = got.iter().filter_map(|g| g.ok()).collect();
    assert_eq!(ok, vec![b, a]);
    assert_eq!(d.stats().oversized, 1);
    assert_eq!(
        d.stats().bytes_dropped,
        (ea.len() - 4 + MAX_BLOCK_LEN * 3) as u64
    );
}

#[test]
fn a_longer_payload_from_a_newer_minor_version_decodes_and_an_unknown_type_is_skipped() {
    use cutlab::protocol::crc::crc32;
    let frame_of = |payload: &[u8]| {
        let mut body = payload.to_vec();
        body.extend_from_slice(&crc32(payload).to_le_bytes());
        let mut out = vec![0u8; 300];
        let n = cutlab::protocol::cobs::encode(&body, &mut out).unwrap();
        let mut v = vec![0];
        v.extend_from_slice(&out[..n]);
        v.push(0);
        v
    };
    let mut stream = frame_of(&[0x40, 1, 0, 0, 0, 2, 0, 0, 0, 0, 0, 3, 0, 0, 0, 0xEE, 0xEE]);
    stream.extend(frame_of(&[0x7A, 1, 2, 3]));
    stream.extend(frame_of(&[0x40, 1, 0]));
    let (got, d) = decode_all(&stream);
    assert_eq!(
        got[0],
        Ok(Frame::Heartbeat(Heartbeat {
            seq: 1,
            time_us: 2,
            flags: 0,
            faults: 0,
            last_sample_seq: 3,
        }))
    );
    assert!(matches!(got[1], Err(DecodeError::Frame(_))));
    assert!(matches!(got[2], Err(DecodeError::Frame(_))));
    assert_eq!(d.stats().unknown_frames, 1);
    assert_eq!(d.stats().frames_rejected, 1);
}

/// Framing vectors from implementations cutlab did not write: zlib's CRC-32 and the PyPI
/// package `cobs` (scripts/reference/protocol_reference.py; tests/reference/protocol/README.md).
const FRAMING: &str = include_str!("reference/protocol/framing.json");

fn unhex(text: &str) -> Vec<u8> {
    (0..text.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&text[i..i + 2], 16).unwrap())
        .collect()
}

#[test]
fn crc32_agrees_with_zlib() {
    use cutlab::protocol::crc::crc32;
    let v: serde_json::Value = serde_json::from_str(FRAMING).unwrap();
    let cases = v["crc32"].as_array().unwrap();
    assert!(cases.len() > 100);
    for case in cases {
        let data = unhex(case["data"].as_str().unwrap());
        assert_eq!(
            u64::from(crc32(&data)),
            case["crc32"].as_u64().unwrap(),
            "{case}"
        );
    }
    // The catalogue's check value is the first case.
    assert_eq!(cases[0]["crc32"], 0xCBF4_3926u32);
}

#[test]
fn cobs_agrees_with_an_independent_encoder_and_decodes_its_output() {
    use cutlab::protocol::cobs::{decode, encode, max_encoded_len};
    let v: serde_json::Value = serde_json::from_str(FRAMING).unwrap();
    let cases = v["cobs"].as_array().unwrap();
    assert!(cases.len() > 80);
    for case in cases {
        let data = unhex(case["data"].as_str().unwrap());
        let expected = unhex(case["encoded"].as_str().unwrap());
        let mut out = vec![0u8; max_encoded_len(data.len())];
        let n = encode(&data, &mut out).unwrap();
        assert_eq!(out[..n], expected[..], "{case}");
        let mut back = vec![0u8; data.len() + 1];
        let m = decode(&expected, &mut back).unwrap();
        assert_eq!(back[..m], data[..], "{case}");
    }
}

#[test]
fn every_frame_type_goes_on_the_wire_as_zlib_and_cobs_compose_it() {
    let v: serde_json::Value = serde_json::from_str(FRAMING).unwrap();
    let cases = v["frames"].as_array().unwrap();
    let mut types = std::collections::BTreeSet::new();
    for case in cases {
        let payload = unhex(case["payload"].as_str().unwrap());
        let wire = unhex(case["wire"].as_str().unwrap());
        let frame = Frame::read_payload(&payload).unwrap();
        assert_eq!(frame.frame_type().name(), case["type"], "{case}");
        types.insert(frame.frame_type().name());
        assert_eq!(encoded(&frame), wire, "{case}");
        let (got, _) = decode_all(&wire);
        assert_eq!(got.len(), 1);
        // Compared by bytes: a random f32 field may be a NaN.
        assert_eq!(encoded(got[0].as_ref().unwrap()), wire, "{case}");
    }
    assert_eq!(types.len(), FrameType::ALL.len());
}

/// Mutates a valid stream the ways a serial line does: flipped bits, lost, repeated and inserted
/// bytes, and cuts.
fn mutate(stream: &mut Vec<u8>, r: &mut Rng) {
    let edits = 1 + r.next_u64() % 8;
    for _ in 0..edits {
        if stream.is_empty() {
            stream.push(u8r(r));
        }
        let i = (r.next_u64() % stream.len() as u64) as usize;
        match r.next_u64() % 5 {
            0 => stream[i] ^= 1 << (r.next_u64() % 8),
            1 => {
                stream.remove(i);
            }
            2 => stream.insert(i, u8r(r)),
            3 => {
                let b = stream[i];
                stream.insert(i, b);
            }
            _ => stream.truncate(i),
        }
    }
}

fn check_stream(bytes: &[u8]) {
    let mut d = Decoder::new();
    let mut results = 0u64;
    for res in d.frames(bytes) {
        results += 1;
        if let Ok(f) = res {
            // Whatever decodes is a frame that encodes again.
            let mut out = [0u8; MAX_FRAME_LEN];
            assert!(encode_frame(&f, &mut out).is_ok());
        }
    }
    let s = d.stats();
    assert_eq!(s.bytes_received, bytes.len() as u64);
    assert_eq!(
        s.frames_decoded + s.frames_rejected + s.unknown_frames,
        results
    );
    assert!(s.bytes_dropped <= bytes.len() as u64);
    assert!(d.pending_len() <= MAX_BLOCK_LEN);
}

#[test]
fn random_and_mutated_streams_never_panic_and_the_counts_add_up() {
    let mut r = Rng::seed_from(99);
    for _ in 0..300 {
        let len = (r.next_u64() % 2000) as usize;
        let random: Vec<u8> = (0..len).map(|_| u8r(&mut r)).collect();
        check_stream(&random);
        let mut stream: Vec<u8> = (0..10).flat_map(|_| encoded(&any_frame(&mut r))).collect();
        mutate(&mut stream, &mut r);
        check_stream(&stream);
    }
}

/// The bounded fuzz run: random and mutated streams for a few seconds (native only: wasm32 has
/// no clock), each checked like the test above. FUZZ_SECONDS sets the budget (default 3). The
/// seed comes from the clock, so every run explores new streams; a failure names the seed, the
/// stream's number and its bytes, and `CUTLAB_FUZZ_SEED=…` replays that seed's streams.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn fuzz_the_decoder_for_a_few_seconds() {
    let budget_s: f64 = std::env::var("FUZZ_SECONDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3.0);
    let seed: u64 = match std::env::var("CUTLAB_FUZZ_SEED") {
        Ok(text) => text
            .parse()
            .unwrap_or_else(|e| panic!("CUTLAB_FUZZ_SEED={text:?}: {e}")),
        Err(_) => std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(1, |d| d.as_nanos() as u64),
    };
    // Shown by cargo test only when the test fails.
    println!("fuzz seed {seed} (replay with CUTLAB_FUZZ_SEED={seed})");
    let start = std::time::Instant::now();
    let mut r = Rng::seed_from(seed);
    let mut streams = 0u64;
    while start.elapsed().as_secs_f64() < budget_s {
        let stream = fuzz_stream(&mut r);
        let checked = std::panic::catch_unwind(|| check_stream(&stream));
        if let Err(cause) = checked {
            let why = cause
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| cause.downcast_ref::<&str>().map(|s| (*s).to_string()))
                .unwrap_or_default();
            panic!(
                "fuzz stream {streams} of seed {seed} failed (replay with \
                 CUTLAB_FUZZ_SEED={seed}): {why}\nthe stream ({} bytes): {}",
                stream.len(),
                hex(&stream)
            );
        }
        streams += 1;
    }
    assert!(streams > 100, "only {streams} streams in {budget_s} s");
}

/// The fuzz run's next stream: valid frames, mutated, or (one time in five) random bytes,
/// mutated.
#[cfg(not(target_arch = "wasm32"))]
fn fuzz_stream(r: &mut Rng) -> Vec<u8> {
    let mut stream: Vec<u8> = (0..1 + r.next_u64() % 30)
        .flat_map(|_| encoded(&any_frame(r)))
        .collect();
    if r.uniform() < 0.2 {
        let len = (r.next_u64() % 600) as usize;
        stream = (0..len).map(|_| u8r(r)).collect();
    }
    mutate(&mut stream, r);
    stream
}

/// The same seed gives the same streams, so a failure's seed replays it.
#[cfg(not(target_arch = "wasm32"))]
#[test]
fn a_fuzz_seed_replays_the_same_streams() {
    let streams = |seed| {
        let mut r = Rng::seed_from(seed);
        (0..20).map(|_| fuzz_stream(&mut r)).collect::<Vec<_>>()
    };
    assert_eq!(streams(42), streams(42));
    assert_ne!(streams(42), streams(43));
}

#[test]
fn every_frame_type_round_trips_through_json() {
    use cutlab::protocol::json::{frame_from_json, frame_to_json};
    let mut r = Rng::seed_from(11);
    for t in FrameType::ALL {
        for _ in 0..50 {
            let mut f = random_frame(t, &mut r);
            // Text fields travel as text: keep them ASCII, as the specification asks.
            if let Frame::Capabilities(c) = &mut f {
                c.device_id = padded("bridge-7");
            }
            let v = frame_to_json(&f);
            assert_eq!(v["type"], t.name());
            // Through text, as the command line carries it.
            let back = serde_json::from_str(&v.to_string()).unwrap();
            assert_eq!(frame_from_json(&back), Ok(f), "{v}");
        }
    }
    let bad = serde_json::json!({"type": "sample", "seq": -1});
    assert!(frame_from_json(&bad).unwrap_err().contains("seq"));
    let bad = serde_json::json!({"type": "warp"});
    assert!(frame_from_json(&bad).unwrap_err().contains("unknown type"));
}

#[cfg(feature = "cli")]
mod common;

/// `cutlab protocol encode | cutlab protocol decode` gives back the JSON lines, and decode
/// counts the garbage it skipped.
#[cfg(feature = "cli")]
#[test]
fn the_command_line_encodes_and_decodes_json_lines() {
    use cutlab::protocol::json::frame_to_json;
    let mut r = Rng::seed_from(12);
    let frames: Vec<Frame> = FrameType::ALL
        .iter()
        .map(|t| match random_frame(*t, &mut r) {
            Frame::Capabilities(mut c) => {
                c.device_id = padded("bridge");
                Frame::Capabilities(c)
            }
            f => f,
        })
        .collect();
    let lines: String = frames
        .iter()
        .map(|f| format!("{}\n", frame_to_json(f)))
        .collect();
    let (result, bytes) = common::cutlab_bytes(&["protocol", "encode"], lines.as_bytes());
    result.unwrap();
    let mut noisy = b"\x13\x37garbage".to_vec();
    noisy.extend_from_slice(&bytes);
    let (result, out) = common::cutlab_bytes(&["protocol", "decode"], &noisy);
    result.unwrap();
    let text = String::from_utf8(out).unwrap();
    let mut decoded: Vec<&str> = text.lines().collect();
    let summary: serde_json::Value = serde_json::from_str(decoded.pop().unwrap()).unwrap();
    assert_eq!(decoded, lines.lines().collect::<Vec<_>>());
    assert_eq!(summary["summary"]["bytes_dropped"], 9);
    assert_eq!(summary["summary"]["frames_decoded"], frames.len());
    let (result, _) = common::cutlab_bytes(
        &["protocol", "encode"],
        b"{\"type\": \"arm\", \"seq\": 1}\nnope\n",
    );
    assert_eq!(
        result.unwrap_err(),
        "line 2: not JSON: expected ident at line 1 column 2"
    );
}

/// `cutlab protocol encode` refuses what it would once have zero-filled: a misspelt field (an
/// 80 % override that became a feed stop) and a frame with fields left out; only a `flags` byte
/// (or `faults`) byte may be left out. The message names the line, the frame type and the field.
#[cfg(feature = "cli")]
#[test]
fn encode_refuses_unknown_and_missing_fields_naming_line_type_and_field() {
    let encode = |text: &str| common::cutlab_bytes(&["protocol", "encode"], text.as_bytes());
    let (result, out) = encode("{\"type\":\"set-override\",\"seq\":1,\"override_pct\":80}\n");
    assert_eq!(
        result.unwrap_err(),
        "line 1: set-override: unknown field \"override_pct\"; a set-override frame has seq, \
         override_cpct, flags, sample_time_us"
    );
    assert!(out.is_empty());
    let (result, _) = encode("{\"type\":\"arm\",\"seq\":1}\n\n{\"type\":\"capabilities\"}\n");
    assert_eq!(
        result.unwrap_err(),
        "line 3: capabilities: missing field \"version_major\""
    );
    // flags left out: no bit set.
    let (result, out) = encode(
        "{\"type\":\"set-override\",\"seq\":42,\"override_cpct\":8760,\"sample_time_us\":1233000}\n",
    );
    result.unwrap();
    let example = Frame::SetOverride(SetOverride {
        seq: 42,
        override_cpct: 8760,
        flags: 0,
        sample_time_us: 1_233_000,
    });
    assert_eq!(out, encoded(&example));
}

/// The worked examples of docs/protocol.md, one per frame type.
fn doc_examples() -> Vec<Frame> {
    use cutlab::protocol::frame::{feature, measured, sample_flag};
    vec![
        Frame::Hello(Hello {
            version_major: 2,
            version_minor: 0,
        }),
        Frame::Capabilities(Capabilities {
            version_major: 2,
            version_minor: 0,
            device_id: padded("cutlab-emulator"),
            program: padded("wang-brake-bench"),
            channel_mask: 0x7F,
            spindle_current_a_per_count: 0.005,
            feed_current_a_per_count: 0.005,
            fv_v_per_count: 0.0005,
            sample_rate_hz: 1000.0,
            override_mode: OverrideModeCode::Dial16,
            min_override_cpct: 0,
            max_override_cpct: 15000,
            dial_cpct: core::array::from_fn(|i| 1000 * i as u16),
            watchdog_timeout_ms: 500,
            fallback_override_cpct: 5000,
            over_current_a: 150.0,
            features: feature::SIM_TRUTH,
            measured: measured::ALL,
            fallback_limit_ms: 5000,
            line_baud: 0,
        }),
        Frame::Sample(Sample {
            seq: 1234,
            time_us: 1_234_000,
            flags: sample_flag::SPINDLE_RUNNING | sample_flag::IN_CYCLE | sample_flag::ARMED,
            spindle_current_counts: [1200, -400, -800],
            feed_current_counts: [100, -50, -50],
            fv_counts: 2777,
            spindle_speed_rpm: 1000.0,
            spindle_command_rpm: 1000.0,
            programmed_feed_mm_min: 200.0,
            feed_mm_min: 180.0,
            applied_override_cpct: 9000,
            dial_code: 9,
            faults: 0,
        }),
        Frame::SimTruth(SimTruth::from_values(
            1234,
            [
                -250.0, 300.0, 40.0, 390.5, 250.0, 3.9, 408.0, 2.0, 20.0, 0.09, 40.0, 120.0, 25.0,
                0.0, 1.5, 9.2,
            ],
        )),
        Frame::SetOverride(SetOverride {
            seq: 42,
            override_cpct: 8760,
            flags: 0,
            sample_time_us: 1_233_000,
        }),
        Frame::Arm(Arm { seq: 1 }),
        Frame::Disarm(Disarm { seq: 43 }),
        Frame::Reset(Reset { seq: 44 }),
        Frame::Ack(Ack {
            seq: 42,
            command: FrameType::SetOverride as u8,
            result: AckResult::Applied,
            applied_override_cpct: 9000,
            flags: 0,
        }),
        Frame::Fault(Fault {
            seq: 1,
            time_us: 90_500_000,
            kind: FaultKind::Watchdog,
            active: 1,
            channel: 0xFF,
            applied_override_cpct: 5000,
        }),
        Frame::Heartbeat(Heartbeat {
            seq: 7,
            time_us: 700_000,
            flags: sample_flag::ARMED,
            faults: 0,
            last_sample_seq: 0,
        }),
    ]
}

fn hex(bytes: &[u8]) -> String {
    bytes
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The example block of `frame` as docs/protocol.md prints it.
fn doc_block(frame: &Frame) -> String {
    use cutlab::protocol::crc::crc32;
    let mut payload = [0u8; 256];
    let n = frame.write_payload(&mut payload).unwrap();
    let wire = encoded(frame);
    format!(
        "payload ({n} bytes): {}\ncrc32:   {}\nwire:    {}\n",
        hex(&payload[..n]),
        hex(&crc32(&payload[..n]).to_le_bytes()),
        hex(&wire)
    )
}

/// docs/protocol.md's byte-level examples are this code's output. `PRINT_DOC_EXAMPLES=1`
/// prints them (to paste after a change of layout).
#[test]
fn the_specifications_worked_examples_are_what_the_codec_writes() {
    let doc = include_str!("../docs/protocol.md");
    let print = std::env::var("PRINT_DOC_EXAMPLES").is_ok();
    for f in doc_examples() {
        let block = doc_block(&f);
        if print {
            println!(
                "### {}\n{}\n{block}",
                f.frame_type().name(),
                frame_to_json_line(&f)
            );
            continue;
        }
        assert!(
            doc.contains(&block),
            "docs/protocol.md lacks the {} example:\n{block}",
            f.frame_type().name()
        );
    }
}

fn frame_to_json_line(f: &Frame) -> String {
    cutlab::protocol::json::frame_to_json(f).to_string()
}

/// docs/protocol.md §1's table of what a stream asks of its line is `LineBudget`'s arithmetic.
#[test]
fn the_line_budget_table_in_the_specification_is_what_the_host_computes() {
    use cutlab::protocol::frame::{feature, measured};
    use cutlab::protocol::line_budget::LineBudget;
    let doc = include_str!("../docs/protocol.md");
    let caps = |rate: f32, truth: bool, baud: u32| Capabilities {
        version_major: 2,
        version_minor: 0,
        device_id: padded("bridge"),
        program: padded("p"),
        channel_mask: 0x7F,
        spindle_current_a_per_count: 0.005,
        feed_current_a_per_count: 0.005,
        fv_v_per_count: 0.0005,
        sample_rate_hz: rate,
        override_mode: OverrideModeCode::WholePercent,
        min_override_cpct: 0,
        max_override_cpct: 10000,
        dial_cpct: [0; 16],
        watchdog_timeout_ms: 500,
        fallback_override_cpct: 5000,
        over_current_a: 150.0,
        features: if truth { feature::SIM_TRUTH } else { 0 },
        measured: measured::ALL,
        fallback_limit_ms: 5000,
        line_baud: baud,
    };
    let spaced = |n: f64| {
        let digits = format!("{n:.0}");
        let mut out = String::new();
        for (i, c) in digits.chars().enumerate() {
            if i > 0 && (digits.len() - i) % 3 == 0 {
                out.push(' ');
            }
            out.push(c);
        }
        out
    };
    for (rate, truth) in [
        (100.0, false),
        (200.0, false),
        (1000.0, false),
        (1000.0, true),
    ] {
        let slow = LineBudget::of(&caps(rate, truth, 115_200));
        let fast = LineBudget::of(&caps(rate, truth, 921_600));
        let pct = |b: &LineBudget| format!("{:.0} %", 100.0 * b.bits_per_s / f64::from(b.baud));
        let row_start = format!(
            "| {rate:.0} | {} | {} |",
            if truth { "yes" } else { "no" },
            spaced(slow.bits_per_s)
        );
        let row = doc
            .lines()
            .find(|l| l.starts_with(&row_start))
            .unwrap_or_else(|| panic!("docs/protocol.md §1 lacks the row {row_start}"));
        for b in [&slow, &fast] {
            let verdict = if b.fits() { "fits" } else { "refused" };
            assert!(
                row.contains(&format!("{} — {verdict}", pct(b)))
                    || (!b.fits() && row.contains("| refused |")),
                "{row}: {} baud should read {} — {verdict}",
                b.baud,
                pct(b)
            );
        }
    }
    // The most samples 115 200 baud carries, as §1 says.
    let most = (1..2000)
        .rev()
        .find(|r| LineBudget::of(&caps(*r as f32, false, 115_200)).fits())
        .unwrap();
    assert!(
        doc.contains(&format!("at 115 200 baud, at most {most} samples/s")),
        "{most}"
    );
}
