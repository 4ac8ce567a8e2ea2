//! The protocol codec built without `std` (and without `alloc`): the five files a bridge's
//! firmware compiles as they are. `scripts/test` builds this for wasm32-unknown-unknown:
//!
//! ```text
//! rustc --edition 2021 --crate-type rlib --target wasm32-unknown-unknown -o /tmp/x.rlib tests/no_std/lib.rs
//! ```
//!
//! Not a cargo test target (cargo only collects `tests/*.rs` and `tests/*/main.rs`).
#![no_std]
#![forbid(unsafe_code)]
#![deny(warnings)]

#[path = "../../src/protocol/cobs.rs"]
pub mod cobs;
#[path = "../../src/protocol/codec.rs"]
pub mod codec;
#[path = "../../src/protocol/crc.rs"]
pub mod crc;
#[path = "../../src/protocol/frame.rs"]
pub mod frame;
#[path = "../../src/truth_fields.rs"]
mod truth_fields;

/// One frame encoded and decoded, so the build exercises the whole path.
pub fn round_trip_heartbeat(seq: u32) -> bool {
    let frame = frame::Frame::Heartbeat(frame::Heartbeat {
        seq,
        ..frame::Heartbeat::default()
    });
    let mut out = [0u8; codec::MAX_FRAME_LEN];
    let Ok(n) = codec::encode_frame(&frame, &mut out) else {
        return false;
    };
    let mut decoder = codec::Decoder::new();
    let mut ok = false;
    for &b in out.get(..n).unwrap_or_default() {
        if let Some(Ok(f)) = decoder.push(b) {
            ok = f == frame;
        }
    }
    ok
}
