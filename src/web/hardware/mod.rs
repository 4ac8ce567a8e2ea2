//! The Hardware page's plumbing: the ports that move bytes (WebSerial, or the device emulator in
//! a worker of its own), the recordings store in IndexedDB, and the station that joins them to the core's
//! [`crate::hardware::session::HardwareSession`].
//!
//! ```text
//! Port (serial reader / virtual device's worker) ─► Station::on_bytes ─► HardwareSession
//!   ─► bytes back to the Port; rows ─► live window (charts) and Recorder ─► Store (IndexedDB)
//! page timer ─► Station::tick (watchdogs, heartbeats, flush); page ◄─ Station::snapshot
//! ```
//!
//! | file | what |
//! |---|---|
//! | [`port`] | the byte ports: WebSerial, or the device emulator in its worker |
//! | [`station`] | the page's state outside the reactive system: the session, the port, the recorder |
//! | [`store`] | the recordings in IndexedDB |

pub mod port;
pub mod station;
pub mod store;
