//! What a host keeps sending to hold a device: the command, heartbeats and re-arming after a
//! watchdog fallback, in device time.

use super::frame::Capabilities;
use super::host::HostSession;
use crate::machine::OverrideCommand;

/// What a host keeps sending while it holds the device (docs/protocol.md §4 and §5): the command
/// in force whenever it changes or has gone unacknowledged for two heartbeat intervals, a
/// Heartbeat when nothing else went out for one interval (a fifth of the device's watchdog
/// timeout), and, while the device reports its watchdog fallback, an Arm: one per attempt, the
/// next an interval after the device answered it, or two intervals after it went out unanswered.
///
/// Times are the device's, read from its samples, so a device that runs faster than real time
/// (an emulator's `--time-scale`) is kept up in its own time. The host answers a batch of
/// samples after its newest one, and the device reads the answer no earlier than that: an Arm is
/// awaited from the newest sample's time, so the samples of the batch that raised the fallback
/// (at a high time scale, up to a few hundred) cannot each send one more. The native host
/// ([`super::link::HostLink`]) and the browser's Hardware page both keep up through this.
#[derive(Debug, Clone, PartialEq)]
pub struct KeepUp {
    heartbeat_interval_s: f64,
    /// The command in force, and the sequence number and time it was last sent with.
    command: Option<OverrideCommand>,
    command_seq: u32,
    command_sent_s: f64,
    /// The latest command's round trip is still to be measured.
    latency_pending: bool,
    /// When the host last sent anything.
    last_sent_s: f64,
    /// The latest Arm (the operator's, or a re-arm): its sequence number when this sent it, and
    /// the device time its answer is awaited from.
    arm_seq: Option<u32>,
    arm_sent_s: f64,
}

impl KeepUp {
    /// Keeping up a device with `capabilities`.
    pub fn new(capabilities: &Capabilities) -> Self {
        Self {
            heartbeat_interval_s: (f64::from(capabilities.watchdog_timeout_ms) / 5000.0).max(0.005),
            command: None,
            command_seq: 0,
            command_sent_s: 0.0,
            latency_pending: false,
            last_sent_s: 0.0,
            arm_seq: None,
            arm_sent_s: f64::NEG_INFINITY,
        }
    }

    /// The heartbeat interval: a fifth of the device's watchdog timeout.
    pub fn heartbeat_interval_s(&self) -> f64 {
        self.heartbeat_interval_s
    }

    /// The device was armed at `now_s`: the next command goes out whatever it is, and a fallback
    /// is not re-armed before an interval has passed.
    pub fn armed(&mut self, now_s: f64) {
        self.command = None;
        self.arm_seq = None;
        self.arm_sent_s = now_s;
    }

    /// Bytes went out at `now_s`.
    pub fn sent(&mut self, now_s: f64) {
        self.last_sent_s = now_s;
    }

    /// Appends to `out` what is due at `now_s` while `command` is in force (the caller sends it
    /// and calls [`KeepUp::sent`]).
    pub fn keep_up(
        &mut self,
        session: &mut HostSession,
        command: OverrideCommand,
        now_s: f64,
        out: &mut Vec<u8>,
    ) {
        let interval = self.heartbeat_interval_s;
        if self.latency_pending && session.acknowledged(self.command_seq) {
            self.latency_pending = false;
            session.record_latency(now_s - self.command_sent_s);
        }
        if session.in_fallback() {
            // An Arm the device answered (its Ack, or a later command's: they are read in
            // order) left the fallback in place: try again after an interval; one lost on the
            // line, after two.
            let answered = self.arm_seq.is_none_or(|seq| session.acknowledged(seq));
            let wait_s = if answered { interval } else { 2.0 * interval };
            if now_s - self.arm_sent_s >= wait_s {
                session.event_at(now_s, "re-arming the device after its watchdog fallback");
                self.arm_seq = Some(session.arm(out));
                self.arm_sent_s = session
                    .newest_sample_device_time_s()
                    .map_or(now_s, |newest| newest.max(now_s));
            }
        }
        let changed = self.command != Some(command);
        // A command the device ignored as stale goes again at once, decided on fresher samples.
        let unacknowledged = (!session.acknowledged(self.command_seq)
            && now_s - self.command_sent_s >= 2.0 * interval)
            || session.stale(self.command_seq);
        if changed || unacknowledged {
            self.command = Some(command);
            self.command_seq = session.set_override(command, out);
            self.command_sent_s = now_s;
            self.latency_pending = true;
        } else if now_s - self.last_sent_s >= interval {
            session.heartbeat(out);
        }
    }

    /// Appends a Heartbeat to `out` if nothing went out for an interval before `now_s` (a host
    /// that holds no device keeps the line alive).
    pub fn heartbeat_if_due(&mut self, session: &mut HostSession, now_s: f64, out: &mut Vec<u8>) {
        if now_s - self.last_sent_s >= self.heartbeat_interval_s {
            session.heartbeat(out);
        }
    }
}
