//! `cutlab protocol encode` under random and hostile JSON lines: it never panics, and a line is
//! either refused with one short line naming it or encoded into exactly the frame it describes.
#![cfg(feature = "cli")]
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;

use cutlab::protocol::codec::Decoder;
use cutlab::protocol::frame::{Frame, FrameType};
use cutlab::protocol::json::{frame_from_json, frame_to_json, parse_line};
use cutlab::rng::Rng;
use serde_json::{json, Value};

fn pick(rng: &mut Rng, n: usize) -> usize {
    (rng.next_u64() % n as u64) as usize
}

/// A value to put where a field was: out of range, of the wrong kind, or hostile.
fn hostile(rng: &mut Rng) -> Value {
    match pick(rng, 14) {
        0 => json!(1e39),
        1 => json!(-1e300),
        2 => json!(3.0e38),
        3 => Value::Null,
        4 => json!(-1),
        5 => json!(1u64 << 40),
        6 => json!("a\u{0}b"),
        7 => json!("x".repeat(1 + pick(rng, 5000))),
        8 => json!([1, 2]),
        9 => json!({"nested": true}),
        10 => json!(true),
        11 => json!(0.5),
        12 => json!("dial16"),
        _ => json!(rng.next_u64() % 70_000),
    }
}

/// One line: a random frame's JSON, often mutated; or not an object, or not JSON at all.
fn random_line(rng: &mut Rng) -> Vec<u8> {
    let t = FrameType::ALL[pick(rng, FrameType::ALL.len())];
    let mut payload = [0u8; 250];
    for b in payload.iter_mut() {
        *b = rng.next_u64() as u8;
    }
    payload[0] = t as u8;
    let Ok(frame) = Frame::read_payload(&payload) else {
        return b"{}".to_vec();
    };
    let mut value = frame_to_json(&frame);
    let keys: Vec<String> = value.as_object().unwrap().keys().cloned().collect();
    let mut duplicate = None;
    for _ in 0..pick(rng, 4) {
        let key = keys[pick(rng, keys.len())].clone();
        match pick(rng, 6) {
            0 => {
                value.as_object_mut().unwrap().remove(&key);
            }
            1 => value["unknown_field"] = hostile(rng),
            2 => duplicate = Some(key),
            3 => value["type"] = hostile(rng),
            _ => value[&key] = hostile(rng),
        }
    }
    let mut text = value.to_string();
    if let Some(key) = duplicate {
        // A key given twice, which a Value cannot hold: written into the text.
        text.insert_str(1, &format!("{}:0,", json!(key)));
    }
    let mut bytes = text.into_bytes();
    match pick(rng, 20) {
        0 => bytes.truncate(pick(rng, bytes.len().max(1))),
        1 => bytes.insert(pick(rng, bytes.len().max(1)), 0xFF),
        2 => bytes = b"[1, 2, 3]".to_vec(),
        _ => {}
    }
    bytes
}

/// Whether a value written in a line is the one decoded from its frame: integers and text
/// exactly, a number in a 32-bit field to f32's rounding, null as null. A code written as a
/// number comes back as its name, and text written as bytes as text: those are not compared.
fn arrives(sent: &Value, got: &Value) -> bool {
    match (sent, got) {
        (Value::Number(a), Value::Number(b)) => match (a.as_i64(), b.as_i64()) {
            (Some(a), Some(b)) => a == b,
            _ => a.as_f64().map(|x| x as f32) == b.as_f64().map(|x| x as f32),
        },
        (Value::Number(_) | Value::Array(_), Value::String(_)) => true,
        (a, b) => a == b,
    }
}

#[test]
fn random_lines_encode_to_the_frame_they_describe_or_are_refused_in_one_short_line() {
    let mut rng = Rng::seed_from(2717);
    let (mut encoded, mut refused) = (0, 0);
    for round in 0..3000 {
        let mut line = random_line(&mut rng);
        line.push(b'\n');
        let (result, out) = common::cutlab_bytes(&["protocol", "encode"], &line);
        let text = String::from_utf8_lossy(&line);
        match result {
            // A blank line (a line truncated to nothing) is skipped, as in a file of frames.
            Ok(()) if text.trim().is_empty() => assert!(out.is_empty(), "round {round}"),
            Ok(()) => {
                encoded += 1;
                let mut decoder = Decoder::new();
                let frames: Vec<Frame> = decoder.frames(&out).map(|f| f.unwrap()).collect();
                assert_eq!(frames.len(), 1, "round {round}: {text}");
                // Exactly what the line says (Debug text compares NaN as equal) ...
                let sent = parse_line(text.trim()).unwrap();
                let described = frame_from_json(&sent).unwrap();
                assert_eq!(
                    format!("{:?}", frames[0]),
                    format!("{described:?}"),
                    "round {round}"
                );
                // ... and every value of the line arrives as it was written.
                let got = frame_to_json(&frames[0]);
                for (key, value) in sent.as_object().unwrap() {
                    assert!(
                        arrives(value, &got[key]),
                        "round {round}: {key}: {value} became {}",
                        got[key]
                    );
                }
                // And the frame's own JSON encodes to the same bytes.
                let again = format!("{}\n", frame_to_json(&frames[0]));
                let (result, bytes) =
                    common::cutlab_bytes(&["protocol", "encode"], again.as_bytes());
                result.unwrap();
                assert_eq!(bytes, out, "round {round}");
            }
            Err(e) => {
                refused += 1;
                assert!(e.starts_with("line 1: "), "round {round}: {e}");
                assert!(!e.contains('\n') && e.len() < 500, "round {round}: {e}");
                assert!(out.is_empty(), "round {round}");
            }
        }
    }
    // Both outcomes are exercised, often.
    assert!(
        encoded > 300 && refused > 300,
        "{encoded} encoded, {refused} refused"
    );
}

#[test]
fn a_line_that_is_not_utf8_is_named_by_its_number() {
    let (result, _) = common::cutlab_bytes(
        &["protocol", "encode"],
        b"{\"type\": \"arm\", \"seq\": 1}\n{\"type\": \"arm\", \"seq\": \xff}\n",
    );
    assert_eq!(
        result.unwrap_err(),
        "line 2: not UTF-8 text (byte 24 is not)"
    );
}
