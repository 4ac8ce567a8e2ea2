//! The host's frames in ([`DeviceEmulator::receive`]): Hello, Heartbeat, Arm, Disarm, Reset and
//! SetOverride, each checked for freshness, applied as the device's state allows, and acknowledged
//! with the override applied; an Arm outside a program loads the next part.

use super::faults::NO_CHANNEL;
use super::{cpct, DeviceEmulator, HoldCause, Part, DISARMED_OVERRIDE_PCT};
use crate::machine::OverrideCommand;
use crate::protocol::frame::{
    command_flag, Ack, AckResult, FaultKind, Frame, FrameType, VERSION_MAJOR, VERSION_MINOR,
};

impl DeviceEmulator {
    /// Takes the bytes that arrived from the host; answers go into `out`.
    pub fn receive(&mut self, bytes: &[u8], out: &mut Vec<u8>) {
        self.update_link_faults();
        if self.stalled || self.unplugged {
            self.stats.bytes_discarded += bytes.len() as u64;
            return;
        }
        for &b in bytes {
            let Some(result) = self.decoder.push(b) else {
                continue;
            };
            let Ok(frame) = result else {
                continue;
            };
            if self.injected_loss() {
                continue;
            }
            self.stats.frames_received += 1;
            self.handle(frame, out);
        }
    }

    fn handle(&mut self, frame: Frame, out: &mut Vec<u8>) {
        let now = self.time_s();
        match frame {
            Frame::Hello(h) => {
                self.last_host_frame_s = now;
                // A new session (a host started, or restarted): its commands count from its own
                // first. A latched hold stays.
                self.last_command_seq = None;
                if h.version_major != VERSION_MAJOR {
                    self.log(format!(
                        "host speaks version {}.{}; answering with {VERSION_MAJOR}.{VERSION_MINOR}",
                        h.version_major, h.version_minor
                    ));
                }
                let caps = self.capabilities;
                self.send(&Frame::Capabilities(caps), out);
            }
            Frame::Heartbeat(_) => self.last_host_frame_s = now,
            Frame::Arm(a) => {
                let result = if !self.fresh_command(a.seq) {
                    AckResult::Stale
                } else if self.estop {
                    self.last_host_frame_s = now;
                    AckResult::Refused
                } else {
                    self.last_host_frame_s = now;
                    if self.fallback {
                        self.fallback = false;
                        self.log("re-armed by the host: watchdog fallback cleared".to_string());
                        self.report_fault(FaultKind::Watchdog, false, NO_CHANNEL, out);
                    }
                    self.armed = true;
                    if !self.in_cycle() {
                        self.start_part();
                    }
                    AckResult::Applied
                };
                self.ack(a.seq, FrameType::Arm, result, out);
            }
            Frame::Disarm(d) => {
                let result = if self.fresh_command(d.seq) {
                    self.last_host_frame_s = now;
                    self.armed = false;
                    self.requested = OverrideCommand::default();
                    self.apply_override();
                    AckResult::Applied
                } else {
                    AckResult::Stale
                };
                self.ack(d.seq, FrameType::Disarm, result, out);
            }
            Frame::Reset(r) => {
                let result = if !self.fresh_command(r.seq) {
                    AckResult::Stale
                } else if self.hold_latched.is_some() && (self.over_current || self.estop) {
                    self.last_host_frame_s = now;
                    AckResult::CauseActive
                } else {
                    self.last_host_frame_s = now;
                    if let Some(cause) = self.hold_latched.take() {
                        self.requested.feed_hold = false;
                        // Still without a host, the fallback runs for its time limit again.
                        self.fallback_since_s = now;
                        self.log(format!(
                            "the operator reset the latched feed hold ({})",
                            cause.name()
                        ));
                        if cause == HoldCause::FallbackLimit {
                            self.report_fault(FaultKind::FallbackLimit, false, NO_CHANNEL, out);
                        }
                    }
                    AckResult::Applied
                };
                self.ack(r.seq, FrameType::Reset, result, out);
            }
            Frame::SetOverride(c) => {
                let age_us = self.time_us().wrapping_sub(c.sample_time_us);
                let max_age_us = u32::from(self.capabilities.watchdog_timeout_ms) * 1000;
                let result = if !self.fresh_command(c.seq) || age_us > max_age_us {
                    // A replayed or reordered frame, or a decision on a sample too old to
                    // stand for the machine now: neither applied nor feeding the watchdog.
                    AckResult::Stale
                } else if self.estop {
                    self.last_host_frame_s = now;
                    AckResult::Refused
                } else if !self.armed || self.fallback {
                    self.last_host_frame_s = now;
                    AckResult::NotArmed
                } else {
                    self.last_host_frame_s = now;
                    let pct = f64::from(c.override_cpct) / 100.0;
                    let limited = pct.clamp(self.min_pct, self.max_pct);
                    let feed_hold = c.flags & command_flag::FEED_HOLD != 0;
                    self.requested = OverrideCommand {
                        override_pct: limited,
                        feed_hold,
                    };
                    if feed_hold {
                        self.latch_hold(HoldCause::Host);
                    }
                    self.apply_override();
                    if limited != pct {
                        AckResult::Limited
                    } else {
                        AckResult::Applied
                    }
                };
                self.ack(c.seq, FrameType::SetOverride, result, out);
            }
            // Frames a device sends: a host has no business sending them.
            other => self.log(format!(
                "ignored a {} frame from the host",
                other.frame_type().name()
            )),
        }
    }

    /// Whether command `seq` is newer than the last one accepted since the Hello; it is then
    /// the last one.
    fn fresh_command(&mut self, seq: u32) -> bool {
        if let Some(last) = self.last_command_seq {
            let ahead = seq.wrapping_sub(last);
            if ahead == 0 || ahead >= 1 << 31 {
                return false;
            }
        }
        self.last_command_seq = Some(seq);
        true
    }

    /// The override the machine gets now: the host's while armed, the fallback after the
    /// watchdog, the machine's own dial otherwise.
    pub(super) fn apply_override(&mut self) {
        let pct = if self.fallback {
            self.fallback_pct
        } else if self.armed {
            self.requested.override_pct
        } else {
            DISARMED_OVERRIDE_PCT
        };
        self.applied = self.mode.apply(pct, self.applied);
    }

    fn start_part(&mut self) {
        if self.next_parts.is_empty() {
            match Self::machines(&self.config, self.stats.parts) {
                Ok(mut m) => self.next_parts.append(&mut m),
                Err(e) => {
                    self.log(format!("cannot load the next part: {e}"));
                    return;
                }
            }
        }
        let Some(machine) = self.next_parts.pop() else {
            return;
        };
        self.stats.parts += 1;
        let n = self.stats.parts;
        self.log(format!("part {n}: cycle start"));
        self.part = Some(Part {
            machine,
            ended: false,
        });
    }

    fn ack(&mut self, seq: u32, command: FrameType, result: AckResult, out: &mut Vec<u8>) {
        let ack = Ack {
            seq,
            command: command as u8,
            result,
            applied_override_cpct: cpct(self.applied.pct),
            flags: if self.feed_hold() {
                command_flag::FEED_HOLD
            } else {
                0
            } | if self.hold_latched.is_some() {
                command_flag::HOLD_LATCHED
            } else {
                0
            },
        };
        self.send(&Frame::Ack(ack), out);
    }
}
