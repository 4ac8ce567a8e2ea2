//! The feed-override protocol between the lab and a bridge device on the machine
//! (docs/protocol.md is the specification).
//!
//! ```text
//! host (cutlab host, the lab)                       device (bridge firmware, or cutlab device)
//!   Hello ───────────────────────────────────────►
//!         ◄─────────────────────────────────────── Capabilities
//!   Arm ─────────────────────────────────────────►
//!         ◄────────────────────────── Ack, then Sample, Sample, … (SimTruth before each, if simulated)
//!   SetOverride / Heartbeat ─────────────────────►  (feeds the device's watchdog)
//!         ◄─────────────────────────────────────── Ack, Fault, Heartbeat
//!   Disarm ──────────────────────────────────────►
//! ```
//!
//! The codec — [`crc`], [`cobs`], [`frame`] and [`codec`] — uses `core` alone, allocates nothing
//! and never panics, so a bridge's firmware can compile those four files as they are
//! (`tests/no_std/lib.rs` proves it for `wasm32-unknown-unknown` without `std`).

pub mod cobs;
pub mod codec;
pub mod crc;
pub mod device;
pub mod frame;
pub mod host;
pub mod json;
#[cfg(not(target_arch = "wasm32"))]
pub mod link;
