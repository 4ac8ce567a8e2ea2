//! The host's end of a link to a machine, driven by the caller's clock: what the Hardware page
//! runs between its serial port (or virtual device) and its controls.
//!
//! A [`HardwareSession`] takes the bytes that arrived ([`HardwareSession::receive`]) and the time
//! now ([`HardwareSession::tick`], a few times a second), and leaves the bytes to send in
//! [`HardwareSession::take_output`]. It owns the protocol session ([`HostSession`]), the run
//! under way, and the link state with the reason of its last change.
//!
//! ## What the host does with the device ([`Stage`])
//!
//! * **Teach cut** ([`HardwareSession::start_teach_cut`]): arms the device (the emulator loads a
//!   part and starts it) and pushes each sample into a [`TeachCut`] — the schedule of overrides
//!   and the fit `cutlab sim` and `cutlab host` make. At the program's end the calibration is
//!   kept and the device disarmed.
//! * **Closed loop** ([`HardwareSession::arm`]): arms the device and pushes each sample into the
//!   [`FeedbackLoop`] [`closed_loop_of`] builds — estimator, controller and safety envelope, the
//!   loop [`crate::closed_loop::lab::LabRun`] runs on a simulated machine. Each period's command
//!   goes out at once; at the program's end the run's metrics are computed as `cutlab sim`
//!   computes them and the device is disarmed.
//! * **Held at the safe override**: Disarm, Escape, an alarm, or a loop that stopped before the
//!   program's end (its time limit, the overload's feed hold) command the configured safe
//!   override at once — keeping a feed hold in force — and hold it until the part ends, when the
//!   device is disarmed (handed back to the machine's own dial). The operator can re-arm.
//!
//! ## Watchdogs and faults
//!
//! * The **host's watchdog** (wall time, [`SessionOptions::link_timeout_s`]): no sample while a
//!   part runs under the host, or no frame at all while connected → alarm (a link loss).
//! * The **device's watchdog** fallback (its Fault, or the fallback flag) is answered by re-arming
//!   it, as docs/protocol.md §5 says, and counted.
//! * A **device fault** raised (sensor, over-current) → alarm; an **E-stop** (its fault, or the
//!   E-stop flag in a sample) → alarm, and the device handed back at once: it refuses commands
//!   and its axes stopped.
//! * The **port closing** (unplugged, read error: [`HardwareSession::link_lost`]) → alarm; nothing
//!   can be sent, and the device falls back on its own watchdog.
//!
//! An alarm ends a teach cut (no calibration) or a run (its trace marked incomplete) and holds
//! the safe override while the device still listens; it stays until the operator acknowledges it.
//!
//! Times: `now_s` is the caller's wall clock (seconds, any origin); a row's time is the device's
//! clock since the session's first sample, so a device that runs faster than real time records
//! in its own time.
//!
//! In the order the bytes flow (the session's state first, then what moves it):
//!
//! | file | what it holds |
//! |---|---|
//! | [`state`] | what the page shows: the link state ([`LinkState`]), the stage ([`Stage`]), the events ([`SessionEvent`]) |
//! | [`options`] | the host's settings ([`SessionOptions`]) |
//! | [`calibration`] | a calibration the closed loop can use, with what it was made with ([`TaughtCalibration`]) |
//! | [`hardware_session`] | the session itself ([`HardwareSession`]): its fields, the constructor, what the page reads, the bookkeeping of state changes, events and the device's clock |
//! | [`link`] | bytes in, time passing, the port closing: the handshake, the host's watchdog, device faults, what is due to be sent; [`describe_ack`] |
//! | [`work`] | each sample pushed into the teach cut or the run, a row per sample, and how the work ends (held at the safe override, handed back, an alarm) |
//! | [`arming`] | before arming: the device ready, what it measures ([`check_measured`]), whether its line carries the run ([`check_line`]), the limits the operator confirms ([`ArmLimits`]) |
//! | [`operator`] | the operator's commands: teach cut, arm, disarm, reset the feed hold, acknowledge an alarm, disconnect |
//!
//! [`TeachCut`]: crate::closed_loop::teach_cut::TeachCut
//! [`FeedbackLoop`]: crate::closed_loop::feedback_loop::FeedbackLoop
//! [`closed_loop_of`]: crate::closed_loop::lab::closed_loop_of
//! [`HostSession`]: crate::protocol::host::HostSession

pub mod arming;
pub mod calibration;
pub mod hardware_session;
pub mod link;
pub mod operator;
pub mod options;
pub mod state;
pub mod work;

pub use arming::{check_line, check_measured, ArmLimits};
pub use calibration::TaughtCalibration;
pub use hardware_session::HardwareSession;
pub use link::describe_ack;
pub use options::SessionOptions;
pub use state::{LinkState, SessionEvent, Stage};
