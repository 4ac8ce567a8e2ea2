//! A real machine (or the device emulator) driven from the lab as it runs: the browser's Hardware
//! page's core, plain Rust without I/O or clock of its own.
//!
//! ```text
//! port bytes ─► HardwareSession::receive ─► HostSession (protocol, samples, counts)
//!   ─► each LinkSample pushed into the run's SampleLoop (TeachCut, then FeedbackLoop with its
//!      safety envelope: the loop LabRun and `cutlab host` run)
//!   ─► override command ─► KeepUp (SetOverride, Heartbeat, re-Arm) ─► bytes for the port
//!   ─► one LiveRow per sample ─► the live charts and a Recorder (CSV chunks the page stores)
//! HardwareSession::tick (the caller's clock): handshake, both ways of the host's watchdog
//! the operator: teach cut, arm (after the page's confirmation), disarm / Escape, disconnect
//! ```
//!
//! | file | what |
//! |---|---|
//! | [`commissioning`] | the checks of the commissioning procedure the page names before a new device's first Arm |
//! | [`host_settings`] | the host's own safety settings (its watchdog, the safe override) as one table, which the Hardware page and `cutlab host` parse alike |
//! | [`session`] | the link state and what the host does with the device, on the caller's clock (the Hardware page) |
//! | [`serial_settings`] | a serial line's settings as one table (the page's Serial port fields, `cutlab host --baud`) |
//! | [`recording`] | the rows as CSV chunks for IndexedDB, read back by the log reader |
//! | `link_run` | the closed loop over a native byte link: `cutlab host`'s run (native only) |
//!
//! [`session`] holds the link state (closed, handshaking, streaming, armed, alarm) with the reason
//! of its last change, and what the host does with the device; [`recording`] turns its rows into
//! the CSV text the page writes to IndexedDB a chunk at a time, which the log reader
//! ([`crate::log`]) reads back with each column's role guessed.

pub mod commissioning;
pub mod host_settings;
#[cfg(not(target_arch = "wasm32"))]
pub mod link_run;
pub mod recording;
pub mod serial_settings;
pub mod session;
