//! The feed-override protocol between the lab and a bridge device on the machine
//! (docs/protocol.md is the specification).
//!
//! ```text
//! host (cutlab host, the lab)                       device (bridge firmware, or cutlab device)
//!   Hello ───────────────────────────────────────►
//!         ◄─────────────────────────────────────── Capabilities
//!   Arm ─────────────────────────────────────────►
//!         ◄────────────────────────── Ack, then Sample, Sample, … (SimTruth before each, if simulated)
//!   SetOverride / Heartbeat ─────────────────────►  (feeds the device's watchdog; stale ones ignored)
//!         ◄─────────────────────────────────────── Ack, Fault, Heartbeat (faults as levels)
//!   Disarm ──────────────────────────────────────►
//!   Reset ───────────────────────────────────────►  (the operator's, of a latched feed hold)
//! ```
//!
//! | file | what |
//! |---|---|
//! | [`crc`], [`cobs`], [`frame`], [`codec`] | the `no_std` codec: CRC-32, COBS, the frames and their layouts, framing |
//! | [`json`] | frames as JSON lines (`cutlab protocol encode`/`decode`) |
//! | [`line_budget`] | what a device's stream asks of its line against its baud rate, which both hosts check before arming |
//! | [`host`] | the host's side without I/O: samples, faults, the stuck-override watch |
//! | [`keep_up`] | keeping a device up: the command, heartbeats, re-arming after a watchdog fallback |
//! | [`device`] | the device emulator without I/O: the simulated machine, its watchdog, fallback, latched hold and injected faults |
//! | [`device_settings`] | the emulator's settings as one table, which `cutlab device` and the Hardware page's virtual device parse alike |
//! | [`device_worker`] | the Hardware page's virtual device as its worker runs it: the start request, the emulator on a wall clock ticked by a timer |
//! | `link` | byte links in real time (native): the emulator on a clock, the host's end of a line, each part as a machine |
//!
//! This is a transport: it knows frames, parts and watchdogs, not runs. The closed loop over a
//! link is the application's (`crate::hardware::link_run`).
//!
//! The codec — [`crc`], [`cobs`], [`frame`] and [`codec`] — uses `core` alone, allocates nothing
//! and never panics, so a bridge's firmware can compile those four files as they are, with
//! [`crate::truth_fields`] beside them (`tests/no_std/lib.rs` proves it for
//! `wasm32-unknown-unknown` without `std`).

pub mod cobs;
pub mod codec;
pub mod crc;
pub mod device;
pub mod device_settings;
pub mod device_worker;
pub mod frame;
pub mod host;
pub mod json;
pub mod keep_up;
pub mod line_budget;
#[cfg(not(target_arch = "wasm32"))]
pub mod link;
