//! The host's side of the protocol as a state machine without I/O: bytes from the device in,
//! machine samples and events out, frames to send encoded on request.
//!
//! [`super::link::HostLink`] drives it over a native byte link and presents each part the
//! device runs as a [`crate::machine::Machine`]; a browser can drive it from WebSerial the same
//! way.
//!
//! ## From samples to machine steps
//!
//! Each [`Sample`] becomes a [`MachineStep`]: counts times the device's scales, overrides in
//! percent, the time since the part's cycle start (its first sample's device time less one
//! sample period), the time since the spindle started (from the spindle-running flag), and the
//! [`SimTruth`] of the same sequence number when the device sends one (the previous one when it
//! was lost). Sequence numbers tell losses: a gap of up to [`MAX_FILLED_GAP`] samples is filled by
//! linear interpolation so the loop's control periods keep their length in device time; a longer
//! gap is passed on as it is, and the safety envelope sees the missing samples. A sample older
//! than the last (reordered or duplicated) is dropped.

use std::collections::VecDeque;

use serde::Serialize;

use super::codec::{encode_frame, Decoder, MAX_FRAME_LEN};
use super::device::cpct;
use super::frame::{
    command_flag, fault_flag, feature, measured, sample_flag, text_field, Ack, AckResult, Arm,
    Capabilities, Disarm, FaultKind, Frame, FrameType, Heartbeat, Hello, OverrideModeCode, Reset,
    Sample, SetOverride, SimTruth, VERSION_MAJOR, VERSION_MINOR,
};
use crate::machine::{MachineStep, OverrideCommand, PlantTruth, SensorSample};
use crate::truth_fields::TRUTH_VALUES;

/// The longest run of lost samples the host fills by interpolation.
pub const MAX_FILLED_GAP: u32 = 8;

/// The host repeats its Hello this often until the device answers (a device may be booting).
pub const HELLO_INTERVAL_S: f64 = 0.25;

/// The host's watchdog may be set from 0.1 s (a device that streams at all sends a sample far
/// more often) to 60 s: the one range `cutlab host --link-timeout-s` and the Hardware page
/// accept.
pub const LINK_TIMEOUT_RANGE_S: (f64, f64) = (0.1, 60.0);
/// The host's watchdog unless told, s.
pub const DEFAULT_LINK_TIMEOUT_S: f64 = 2.0;

/// `link_timeout_s` if it is in [`LINK_TIMEOUT_RANGE_S`], or why not.
///
/// ```
/// use cutlab::protocol::host::check_link_timeout_s;
/// assert_eq!(check_link_timeout_s(2.0), Ok(2.0));
/// assert!(check_link_timeout_s(1e300).unwrap_err().contains("0.1 to 60 s"));
/// assert!(check_link_timeout_s(f64::NAN).is_err());
/// ```
pub fn check_link_timeout_s(link_timeout_s: f64) -> Result<f64, String> {
    let (lo, hi) = LINK_TIMEOUT_RANGE_S;
    if link_timeout_s >= lo && link_timeout_s <= hi {
        Ok(link_timeout_s)
    } else {
        Err(format!(
            "the host watchdog must be {lo} to {hi} s, not {}",
            crate::input::readable(link_timeout_s)
        ))
    }
}

/// How long the actual feed may disagree with the override the bridge applies before the host
/// calls the override stuck (device time): longer than the feed drive takes to follow a change.
pub const OVERRIDE_MISMATCH_S: f64 = 0.5;

/// The disagreement that counts: the actual feed's share of the programmed feed off the applied
/// override by more than this many percentage points (or [`OVERRIDE_MISMATCH_FRACTION`] of it).
pub const OVERRIDE_MISMATCH_PCT: f64 = 10.0;

/// See [`OVERRIDE_MISMATCH_PCT`].
pub const OVERRIDE_MISMATCH_FRACTION: f64 = 0.15;

/// Below this programmed feed the ratio says nothing (a dwell, a stop).
pub const OVERRIDE_CHECK_MIN_FEED_MM_MIN: f64 = 1.0;

/// The feed is judged only while it moves (above this share of the programmed feed: a standing
/// axis is a dwell, a wait for the spindle, or a stop — none of them faster than asked) ...
pub const OVERRIDE_CHECK_MOVING_FRACTION: f64 = 0.05;

/// ... and is steady: within this share of the programmed feed of its own mean over the last
/// [`OVERRIDE_CHECK_STEADY_S`] (a drive still following a change, a corner's slowdown, are
/// not a stuck override). No preset's plant raises the alarm through the teach cut's steps
/// (tests/host.rs).
pub const OVERRIDE_CHECK_STEADY_FRACTION: f64 = 0.02;

/// See [`OVERRIDE_CHECK_STEADY_FRACTION`].
pub const OVERRIDE_CHECK_STEADY_S: f64 = 0.1;

/// Counts of what crossed the link, for the host's report.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct LinkStats {
    /// Bytes received.
    pub bytes_received: u64,
    /// Valid frames received.
    pub frames_received: u64,
    /// Samples missing from the sequence (gaps).
    pub frames_lost: u64,
    /// Samples that arrived out of order or twice, dropped.
    pub frames_reordered: u64,
    /// Blocks the decoder rejected (CRC, COBS, oversized).
    pub frames_rejected: u64,
    /// Bytes the decoder dropped, part of no frame: garbage, rejected blocks, zeros beyond the
    /// two that may stand between frames ([`super::codec::DecoderStats::bytes_dropped`]).
    pub bytes_dropped: u64,
    /// Frames of a type this host does not know, skipped.
    pub frames_unknown: u64,
    /// Commands (SetOverride, Arm, Disarm) sent.
    pub commands_sent: u64,
    /// Acks received.
    pub commands_acknowledged: u64,
    /// Heartbeats sent.
    pub heartbeats_sent: u64,
    /// Times the device's watchdog fell back.
    pub watchdog_fallbacks: u64,
    /// Times the host's watchdog found the link dead.
    pub link_losses: u64,
    /// Fault reports from the device (raised), watchdog included.
    pub device_faults: u64,
    /// Mean device time from sending a SetOverride to reading its Ack (at the resolution of
    /// one sample): the latency the link adds to the loop.
    pub command_latency_mean_s: f64,
    /// The longest such time.
    pub command_latency_max_s: f64,
}

impl LinkStats {
    /// What came in, in words, for a link that did not come up: the bytes, how many of them
    /// were part of no frame, and the blocks rejected.
    ///
    /// ```
    /// use cutlab::protocol::host::LinkStats;
    /// let s = LinkStats { bytes_received: 1000, bytes_dropped: 999, ..LinkStats::default() };
    /// assert_eq!(s.received(), "1000 bytes received, 999 of them dropped (part of no frame), \
    ///     0 frames rejected");
    /// ```
    pub fn received(&self) -> String {
        format!(
            "{} bytes received, {} of them dropped (part of no frame), {} frames rejected",
            self.bytes_received, self.bytes_dropped, self.frames_rejected
        )
    }
}

/// Something that happened on the link.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinkEvent {
    /// The part (1 = the first armed).
    pub part: u32,
    /// Machine time within the part (of the latest sample).
    pub time_s: f64,
    /// The device's clock (unwrapped) at the sample the event belongs to: the latest one decoded
    /// when it happened, or the time it was recorded at ([`HostSession::event_at`]); `None`
    /// before any sample.
    #[serde(skip)]
    pub device_time_s: Option<f64>,
    /// What.
    pub text: String,
}

/// A sample ready for the loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkSample {
    /// What the machine read.
    pub step: MachineStep,
    /// The device's clock at the sample, seconds (unwrapped).
    pub device_time_s: f64,
    /// The program ended with this sample.
    pub program_end: bool,
    /// The sample's flags ([`sample_flag`]).
    pub flags: u8,
}

/// The host's side of the protocol.
pub struct HostSession {
    decoder: Decoder,
    capabilities: Option<Capabilities>,
    queue: VecDeque<LinkSample>,
    pending_truth: Option<SimTruth>,
    last_truth: Option<PlantTruth>,
    expected_seq: Option<u32>,
    last: Option<LinkSample>,
    /// Device time of the part's cycle start, µs (wrapping arithmetic).
    cycle_start_us: Option<u32>,
    /// Unwrapped device time: the latest raw value and the wraps seen.
    last_time_us: Option<u32>,
    time_wraps: u64,
    spindle_started_s: Option<f64>,
    part: u32,
    command_seq: u32,
    heartbeat_seq: u32,
    last_ack_seq: Option<u32>,
    last_ack: Option<Ack>,
    device_armed: bool,
    fallback: bool,
    /// Faults raised that call for the host's alarm (all but the watchdog's), not yet taken.
    alarm_faults: Vec<FaultKind>,
    /// The faults known active ([`fault_flag`] bits), from Fault reports and the level flags
    /// of every Sample and device Heartbeat.
    active_faults: u8,
    /// The device's latest word on its latched feed hold.
    hold_latched: bool,
    /// The device clock of the latest Sample or device Heartbeat: what a command echoes.
    latest_device_time_us: Option<u32>,
    /// The device time of the newest Sample received (unwrapped), s.
    newest_sample_device_time_s: Option<f64>,
    /// The part's program ended (its end sample, or a heartbeat that says so).
    part_ended: bool,
    /// The override the bridge says it applies while armed (its latest Ack), if it does.
    bridge_override_pct: Option<f64>,
    /// The override the host commanded last, within the device's range, while it holds the
    /// device.
    commanded_pct: Option<f64>,
    /// Device time the actual feed has disagreed with the bridge's override for.
    mismatch_s: f64,
    /// The actual feed's mean over the last [`OVERRIDE_CHECK_STEADY_S`] (exponential).
    feed_mean_mm_min: f64,
    /// A stuck override found, not yet taken; and whether one was found in this part (it is
    /// reported once a part).
    stuck_override: Option<String>,
    stuck_reported: bool,
    stats: LinkStats,
    latencies: u64,
    events: Vec<LinkEvent>,
}

impl Default for HostSession {
    fn default() -> Self {
        Self::new()
    }
}

impl HostSession {
    /// A session before the handshake.
    pub fn new() -> Self {
        Self {
            decoder: Decoder::new(),
            capabilities: None,
            queue: VecDeque::with_capacity(1024),
            pending_truth: None,
            last_truth: None,
            expected_seq: None,
            last: None,
            cycle_start_us: None,
            last_time_us: None,
            time_wraps: 0,
            spindle_started_s: None,
            part: 0,
            command_seq: 0,
            heartbeat_seq: 0,
            last_ack_seq: None,
            last_ack: None,
            device_armed: false,
            fallback: false,
            alarm_faults: Vec::new(),
            active_faults: 0,
            hold_latched: false,
            latest_device_time_us: None,
            newest_sample_device_time_s: None,
            part_ended: false,
            bridge_override_pct: None,
            commanded_pct: None,
            mismatch_s: 0.0,
            feed_mean_mm_min: 0.0,
            stuck_override: None,
            stuck_reported: false,
            stats: LinkStats::default(),
            latencies: 0,
            events: Vec::new(),
        }
    }

    /// The device's capabilities, once it has answered the Hello.
    pub fn capabilities(&self) -> Option<&Capabilities> {
        self.capabilities.as_ref()
    }

    /// The counts so far.
    pub fn stats(&self) -> LinkStats {
        let d = self.decoder.stats();
        LinkStats {
            bytes_received: d.bytes_received,
            frames_rejected: d.frames_rejected,
            bytes_dropped: d.bytes_dropped,
            frames_unknown: d.unknown_frames,
            ..self.stats
        }
    }

    /// The events so far.
    pub fn events(&self) -> &[LinkEvent] {
        &self.events
    }

    /// Records an event at the latest sample's time.
    pub fn event(&mut self, text: impl Into<String>) {
        let time_s = self.last.map_or(0.0, |l| l.step.sensors.time_s);
        let device_time_s = self
            .last
            .map(|l| l.device_time_s)
            .or(self.newest_sample_device_time_s);
        self.events.push(LinkEvent {
            part: self.part,
            time_s,
            device_time_s,
            text: text.into(),
        });
    }

    /// Records an event at device time `device_time_s` (that of a sample in the batch the host
    /// is working through, not the newest one received).
    pub fn event_at(&mut self, device_time_s: f64, text: impl Into<String>) {
        let time_s = self.last.map_or(0.0, |l| {
            l.step.sensors.time_s - (l.device_time_s - device_time_s)
        });
        self.events.push(LinkEvent {
            part: self.part,
            time_s,
            device_time_s: Some(device_time_s),
            text: text.into(),
        });
    }

    /// The device time of the newest Sample received, s: the device reads what the host sends
    /// now no earlier than this (a batch of samples is answered after its newest one).
    pub fn newest_sample_device_time_s(&self) -> Option<f64> {
        self.newest_sample_device_time_s
    }

    /// Counts a loss of the link (the host's watchdog).
    pub fn link_lost(&mut self, text: impl Into<String>) {
        self.stats.link_losses += 1;
        self.event(text);
    }

    /// Whether the device reports its watchdog fallback (until the host re-arms it).
    pub fn in_fallback(&self) -> bool {
        self.fallback
    }

    /// The faults raised since the last call that call for an alarm (docs/protocol.md §5): a
    /// sensor, over-current or E-stop fault, or one of a kind this version does not know —
    /// everything but the watchdog's, which the host answers by re-arming. A sample that shows
    /// the E-stop input active counts as an E-stop fault raised, in case its Fault frame was
    /// lost on the line.
    pub fn take_alarm_faults(&mut self) -> Vec<FaultKind> {
        std::mem::take(&mut self.alarm_faults)
    }

    /// Whether the device's latest sample said the host is in control.
    pub fn device_armed(&self) -> bool {
        self.device_armed
    }

    /// Whether the device holds the feed latched (until the operator's reset), by its latest
    /// Sample, Heartbeat or Ack.
    pub fn hold_latched(&self) -> bool {
        self.hold_latched
    }

    /// The faults the device reports active ([`fault_flag`] bits).
    pub fn active_faults(&self) -> u8 {
        self.active_faults
    }

    /// A stuck override found since the last call (docs/protocol.md §5): the actual feed has
    /// not followed the override the bridge applies for [`OVERRIDE_MISMATCH_S`].
    pub fn take_stuck_override(&mut self) -> Option<String> {
        self.stuck_override.take()
    }

    /// Records one command's round trip, device time.
    pub fn record_latency(&mut self, latency_s: f64) {
        let n = self.latencies as f64;
        let s = &mut self.stats;
        s.command_latency_mean_s = (s.command_latency_mean_s * n + latency_s) / (n + 1.0);
        s.command_latency_max_s = s.command_latency_max_s.max(latency_s);
        self.latencies += 1;
    }

    /// Whether command `seq` (or a later one) has been acknowledged.
    pub fn acknowledged(&self, seq: u32) -> bool {
        self.last_ack_seq
            .is_some_and(|a| a.wrapping_sub(seq) < 1 << 31)
    }

    /// The latest acknowledgement: which command, its result and the override the device applied.
    pub fn last_ack(&self) -> Option<Ack> {
        self.last_ack
    }

    /// The next sample for the loop, if one is ready.
    pub fn next_sample(&mut self) -> Option<LinkSample> {
        self.queue.pop_front()
    }

    /// Starts a new part: the next sample is its first.
    pub fn start_part(&mut self) {
        self.part += 1;
        self.cycle_start_us = None;
        self.spindle_started_s = None;
        self.last = None;
        self.last_truth = None;
        self.part_ended = false;
        self.mismatch_s = 0.0;
        self.stuck_reported = false;
    }

    /// The part under way (1 = the first).
    pub fn part(&self) -> u32 {
        self.part
    }

    fn push_frame(frame: &Frame, out: &mut Vec<u8>) {
        let mut buf = [0u8; MAX_FRAME_LEN];
        if let Ok(n) = encode_frame(frame, &mut buf) {
            out.extend_from_slice(buf.get(..n).unwrap_or_default());
        }
    }

    fn next_command_seq(&mut self) -> u32 {
        self.command_seq = self.command_seq.wrapping_add(1);
        self.stats.commands_sent += 1;
        self.command_seq
    }

    /// Encodes a Hello into `out`.
    pub fn hello(&mut self, out: &mut Vec<u8>) {
        Self::push_frame(
            &Frame::Hello(Hello {
                version_major: VERSION_MAJOR,
                version_minor: VERSION_MINOR,
            }),
            out,
        );
    }

    /// Encodes an Arm into `out`; returns its sequence number.
    pub fn arm(&mut self, out: &mut Vec<u8>) -> u32 {
        let seq = self.next_command_seq();
        Self::push_frame(&Frame::Arm(Arm { seq }), out);
        seq
    }

    /// Encodes a Disarm into `out`; returns its sequence number.
    pub fn disarm(&mut self, out: &mut Vec<u8>) -> u32 {
        self.commanded_pct = None;
        let seq = self.next_command_seq();
        Self::push_frame(&Frame::Disarm(Disarm { seq }), out);
        seq
    }

    /// Encodes a Reset of the device's latched feed hold into `out` (only on the operator's
    /// explicit action); returns its sequence number.
    pub fn reset(&mut self, out: &mut Vec<u8>) -> u32 {
        let seq = self.next_command_seq();
        Self::push_frame(&Frame::Reset(Reset { seq }), out);
        seq
    }

    /// Whether the device ignored command `seq` as stale (its latest Ack says so).
    pub fn stale(&self, seq: u32) -> bool {
        self.last_ack
            .is_some_and(|a| a.seq == seq && a.result == AckResult::Stale)
    }

    /// Encodes a SetOverride for `command` into `out`; returns its sequence number.
    pub fn set_override(&mut self, command: OverrideCommand, out: &mut Vec<u8>) -> u32 {
        self.commanded_pct = self.capabilities.map(|c| {
            command.override_pct.clamp(
                f64::from(c.min_override_cpct) / 100.0,
                f64::from(c.max_override_cpct) / 100.0,
            )
        });
        let seq = self.next_command_seq();
        let frame = Frame::SetOverride(SetOverride {
            seq,
            override_cpct: cpct(command.override_pct),
            flags: if command.feed_hold {
                command_flag::FEED_HOLD
            } else {
                0
            },
            sample_time_us: self.latest_device_time_us.unwrap_or(0),
        });
        Self::push_frame(&frame, out);
        seq
    }

    /// Encodes a Heartbeat carrying the device time of the latest sample into `out`.
    pub fn heartbeat(&mut self, out: &mut Vec<u8>) {
        self.heartbeat_seq = self.heartbeat_seq.wrapping_add(1);
        self.stats.heartbeats_sent += 1;
        let time_us = self.latest_device_time_us.unwrap_or(0);
        Self::push_frame(
            &Frame::Heartbeat(Heartbeat {
                seq: self.heartbeat_seq,
                time_us,
                flags: 0,
                faults: 0,
                last_sample_seq: self.expected_seq.map_or(0, |s| s.wrapping_sub(1)),
            }),
            out,
        );
    }

    /// Takes bytes from the device.
    pub fn receive(&mut self, bytes: &[u8]) {
        for &b in bytes {
            if let Some(Ok(frame)) = self.decoder.push(b) {
                self.stats.frames_received += 1;
                self.handle(frame);
            }
        }
    }

    fn handle(&mut self, frame: Frame) {
        match frame {
            Frame::Capabilities(c) => {
                if self.capabilities.is_none() {
                    self.capabilities = Some(c);
                }
            }
            Frame::SimTruth(t) => self.pending_truth = Some(t),
            Frame::Sample(s) => self.sample(&s),
            Frame::Ack(a) => {
                self.stats.commands_acknowledged += 1;
                self.last_ack_seq = Some(a.seq);
                self.last_ack = Some(a);
                self.hold_latched = a.flags & command_flag::HOLD_LATCHED != 0;
                let applied = matches!(a.result, AckResult::Applied | AckResult::Limited);
                if a.command == FrameType::Disarm as u8 && applied {
                    self.bridge_override_pct = None;
                } else if (a.command == FrameType::SetOverride as u8
                    || a.command == FrameType::Arm as u8)
                    && applied
                {
                    self.bridge_override_pct = Some(f64::from(a.applied_override_cpct) / 100.0);
                }
            }
            Frame::Fault(f) => {
                let raised = f.active != 0;
                if raised {
                    self.stats.device_faults += 1;
                }
                if f.kind == FaultKind::Watchdog && raised {
                    self.stats.watchdog_fallbacks += 1;
                    self.fallback = true;
                } else if raised && self.active_faults & f.kind.flag() == 0 {
                    self.alarm_faults.push(f.kind);
                }
                if raised {
                    self.active_faults |= f.kind.flag();
                } else {
                    self.active_faults &= !f.kind.flag();
                }
                let channel = if f.channel == 0xFF {
                    String::new()
                } else {
                    format!(", channel {}", f.channel)
                };
                self.event(format!(
                    "device fault {} {}{channel} (override now {} %)",
                    f.kind.name(),
                    if raised { "raised" } else { "cleared" },
                    f64::from(f.applied_override_cpct) / 100.0
                ));
            }
            Frame::Heartbeat(h) => self.device_heartbeat(&h),
            // A host ignores frames a host sends.
            Frame::Hello(_)
            | Frame::SetOverride(_)
            | Frame::Arm(_)
            | Frame::Disarm(_)
            | Frame::Reset(_) => {}
        }
    }

    /// The level flags of a Sample or a device Heartbeat: a fault active there whose report was
    /// lost is raised now (once), and one no longer there is cleared.
    fn level_faults(&mut self, faults: u8) {
        let raised = faults & !self.active_faults;
        for kind in FaultKind::KNOWN {
            if raised & kind.flag() == 0 {
                continue;
            }
            if kind == FaultKind::Watchdog {
                // Answered by re-arming (the flag bit 5 of a Sample says the same).
                continue;
            }
            self.event(format!(
                "the device's {} fault is active (its report was lost on the line)",
                kind.name()
            ));
            self.alarm_faults.push(kind);
        }
        self.active_faults = faults;
    }

    /// A device's heartbeat: its clock, its faults, its latched hold, and — when a part's
    /// samples were streaming and it says no program runs any more — the part's end, in case
    /// the program-end sample was lost.
    fn device_heartbeat(&mut self, h: &Heartbeat) {
        self.latest_device_time_us = Some(h.time_us);
        self.level_faults(h.faults);
        self.hold_latched = h.flags & sample_flag::HOLD_LATCHED != 0;
        let Some(last) = self.last else {
            return;
        };
        let after_last_sample = self
            .last_time_us
            .is_some_and(|t| h.time_us.wrapping_sub(t) < 1 << 31 && h.time_us != t);
        if !self.part_ended && h.flags & sample_flag::IN_CYCLE == 0 && after_last_sample {
            self.part_ended = true;
            let lost = h
                .last_sample_seq
                .wrapping_sub(self.expected_seq.map_or(0, |e| e.wrapping_sub(1)));
            self.event(format!(
                "program end: the device's heartbeat says the part ended ({lost} last samples, \
                 the program-end one among them, lost on the line)"
            ));
            self.stats.frames_lost += u64::from(lost);
            self.queue.push_back(LinkSample {
                program_end: true,
                ..last
            });
        }
    }

    /// Compares the actual feed's share of the programmed feed with the override the bridge
    /// says it applies; a disagreement that lasts [`OVERRIDE_MISMATCH_S`] is a stuck override
    /// (the selector on the dial, a dead output, a ladder that ignores the code).
    fn watch_override(&mut self, s: &Sample, period_s: f64) {
        let feed = f64::from(s.feed_mm_min);
        if feed.is_finite() {
            let k = (period_s / OVERRIDE_CHECK_STEADY_S).min(1.0);
            self.feed_mean_mm_min += (feed - self.feed_mean_mm_min) * k;
        }
        let held = s.flags & (sample_flag::FEED_HOLD | sample_flag::ESTOP) != 0;
        let controlled = s.flags & sample_flag::ARMED != 0;
        let programmed = f64::from(s.programmed_feed_mm_min);
        // What the machine should do: the override the host commanded, or the one the bridge
        // last acknowledged (a command still on its way, or an Ack lost on the line, leaves one
        // of them behind; a stuck override disagrees with both).
        let expected: Vec<f64> = [self.commanded_pct, self.bridge_override_pct]
            .into_iter()
            .flatten()
            .collect();
        let (Some(&bridge_pct), true, false) = (expected.last(), controlled, held) else {
            self.mismatch_s = 0.0;
            return;
        };
        let moving = feed > OVERRIDE_CHECK_MOVING_FRACTION * programmed;
        let steady =
            (feed - self.feed_mean_mm_min).abs() <= OVERRIDE_CHECK_STEADY_FRACTION * programmed;
        if programmed.is_nan()
            || programmed < OVERRIDE_CHECK_MIN_FEED_MM_MIN
            || s.flags & sample_flag::SPINDLE_RUNNING == 0
            || !moving
            || !steady
        {
            self.mismatch_s = 0.0;
            return;
        }
        let moving_pct = 100.0 * feed / programmed;
        let agrees = |pct: &f64| {
            (moving_pct - pct).abs() <= OVERRIDE_MISMATCH_PCT.max(OVERRIDE_MISMATCH_FRACTION * pct)
        };
        if expected.iter().any(agrees) || !moving_pct.is_finite() {
            self.mismatch_s = 0.0;
            return;
        }
        self.mismatch_s += period_s;
        if self.mismatch_s >= OVERRIDE_MISMATCH_S && !self.stuck_reported {
            let text = format!(
                "stuck override: for {OVERRIDE_MISMATCH_S} s the machine has moved at {moving_pct:.0} % \
                 of the programmed feed while the bridge applies {bridge_pct:.0} % (the selector on \
                 the dial, a dead output, or a ladder that ignores the code)"
            );
            self.event(text.clone());
            self.stuck_override = Some(text);
            self.stuck_reported = true;
        }
    }

    /// The device time of a raw timestamp, unwrapped across the 32-bit wrap.
    fn unwrap_time_s(&mut self, time_us: u32) -> f64 {
        if let Some(last) = self.last_time_us {
            if time_us < last && last - time_us > 1 << 31 {
                self.time_wraps += 1;
            }
        }
        self.last_time_us = Some(time_us);
        (self.time_wraps as f64 * 4_294_967_296.0 + f64::from(time_us)) * 1e-6
    }

    fn sample(&mut self, s: &Sample) {
        let Some(caps) = self.capabilities else {
            return;
        };
        let mut missing = 0u32;
        if let Some(expected) = self.expected_seq {
            let ahead = s.seq.wrapping_sub(expected);
            if ahead >= 1 << 31 {
                self.stats.frames_reordered += 1;
                return;
            }
            self.stats.frames_lost += u64::from(ahead);
            missing = ahead;
        }
        self.expected_seq = Some(s.seq.wrapping_add(1));
        let period_s = 1.0 / f64::from(caps.sample_rate_hz).max(1e-9);
        let cycle_start_us = *self.cycle_start_us.get_or_insert_with(|| {
            s.time_us
                .wrapping_sub((period_s * 1e6).round() as u64 as u32)
        });
        let device_time_s = self.unwrap_time_s(s.time_us);
        let time_s = f64::from(s.time_us.wrapping_sub(cycle_start_us)) * 1e-6;
        let spindle_running = s.flags & sample_flag::SPINDLE_RUNNING != 0;
        if spindle_running {
            // The spindle started somewhere in this sample's block; its end errs late, so the
            // arming delay is never cut short.
            self.spindle_started_s.get_or_insert(time_s);
        } else {
            self.spindle_started_s = None;
        }
        let scale_spindle = f64::from(caps.spindle_current_a_per_count);
        let scale_feed = f64::from(caps.feed_current_a_per_count);
        let sensors = SensorSample {
            time_s,
            feed_phase_currents_a: s.feed_current_counts.map(|c| f64::from(c) * scale_feed),
            spindle_phase_currents_a: s
                .spindle_current_counts
                .map(|c| f64::from(c) * scale_spindle),
            spindle_fv_voltage_v: f64::from(s.fv_counts) * f64::from(caps.fv_v_per_count),
            spindle_speed_rpm: f64::from(s.spindle_speed_rpm),
            spindle_command_rpm: f64::from(s.spindle_command_rpm),
            programmed_feed_mm_min: f64::from(s.programmed_feed_mm_min),
            feed_mm_min: f64::from(s.feed_mm_min),
            applied_override_pct: f64::from(s.applied_override_cpct) / 100.0,
            spindle_running,
            time_since_spindle_start_s: self.spindle_started_s.map_or(0.0, |t| time_s - t),
        };
        let truth = match self.pending_truth.take() {
            Some(t) if t.seq == s.seq => {
                let v = t.values().map(f64::from);
                let truth = PlantTruth::from_wire_values(v);
                self.last_truth = Some(truth);
                Some(truth)
            }
            // Lost: the one before stands in (a simulation's truth moves slowly between samples).
            _ if caps.features & feature::SIM_TRUTH != 0 => self.last_truth,
            _ => None,
        };
        let sample = LinkSample {
            step: MachineStep { sensors, truth },
            device_time_s,
            program_end: s.flags & sample_flag::PROGRAM_END != 0,
            flags: s.flags,
        };
        // Fill a short gap within the part by interpolation.
        if let Some(prev) = self.last {
            if (1..=MAX_FILLED_GAP).contains(&missing) {
                for k in 1..=missing {
                    let f = f64::from(k) / f64::from(missing + 1);
                    self.queue.push_back(interpolate(&prev, &sample, f));
                }
            }
        }
        self.last = Some(sample);
        self.latest_device_time_us = Some(s.time_us);
        self.newest_sample_device_time_s = Some(device_time_s);
        self.device_armed = s.flags & sample_flag::ARMED != 0;
        self.hold_latched = s.flags & sample_flag::HOLD_LATCHED != 0;
        // The E-stop flag (bit 6) says what the faults' E-stop bit says.
        let estop = if s.flags & sample_flag::ESTOP != 0 {
            fault_flag::ESTOP
        } else {
            0
        };
        self.level_faults(s.faults | estop);
        self.watch_override(s, period_s);
        if sample.program_end {
            self.part_ended = true;
        }
        let fallback = s.flags & sample_flag::FALLBACK != 0;
        if self.fallback && !fallback {
            self.event("device back under the host's control");
        }
        self.fallback = fallback;
        self.queue.push_back(sample);
    }
}

fn lerp(a: f64, b: f64, f: f64) -> f64 {
    a + (b - a) * f
}

fn lerp3(a: [f64; 3], b: [f64; 3], f: f64) -> [f64; 3] {
    [
        lerp(a[0], b[0], f),
        lerp(a[1], b[1], f),
        lerp(a[2], b[2], f),
    ]
}

/// A sample a fraction `f` of the way from `a` to `b` (flags and booleans from `a`).
fn interpolate(a: &LinkSample, b: &LinkSample, f: f64) -> LinkSample {
    let (sa, sb) = (&a.step.sensors, &b.step.sensors);
    let sensors = SensorSample {
        time_s: lerp(sa.time_s, sb.time_s, f),
        feed_phase_currents_a: lerp3(sa.feed_phase_currents_a, sb.feed_phase_currents_a, f),
        spindle_phase_currents_a: lerp3(
            sa.spindle_phase_currents_a,
            sb.spindle_phase_currents_a,
            f,
        ),
        spindle_fv_voltage_v: lerp(sa.spindle_fv_voltage_v, sb.spindle_fv_voltage_v, f),
        spindle_speed_rpm: lerp(sa.spindle_speed_rpm, sb.spindle_speed_rpm, f),
        feed_mm_min: lerp(sa.feed_mm_min, sb.feed_mm_min, f),
        time_since_spindle_start_s: lerp(
            sa.time_since_spindle_start_s,
            sb.time_since_spindle_start_s,
            f,
        ),
        ..*sa
    };
    let truth = match (a.step.truth, b.step.truth) {
        (Some(ta), Some(tb)) => {
            let (va, vb) = (ta.wire_values(), tb.wire_values());
            let v: [f64; TRUTH_VALUES] = std::array::from_fn(|i| lerp(va[i], vb[i], f));
            Some(PlantTruth::from_wire_values(v))
        }
        (t, _) => t,
    };
    LinkSample {
        step: MachineStep { sensors, truth },
        device_time_s: lerp(a.device_time_s, b.device_time_s, f),
        program_end: false,
        flags: a.flags,
    }
}

/// A short description of a device's capabilities, for the report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DeviceSummary {
    /// Protocol version, "major.minor".
    pub protocol_version: String,
    /// Identity.
    pub device_id: String,
    /// Program or setup.
    pub program: String,
    /// Samples per second.
    pub sample_rate_hz: f64,
    /// "dial16", "whole-percent", "continuous" or "other".
    pub override_mode: &'static str,
    /// Override range, percent.
    pub override_range_pct: (f64, f64),
    /// Watchdog timeout.
    pub watchdog_timeout_s: f64,
    /// Watchdog fallback override.
    pub fallback_override_pct: f64,
    /// Whether it sends simulation truth.
    pub sim_truth: bool,
    /// How long its fallback lasts before it holds the feed.
    pub fallback_limit_s: f64,
    /// The Sample fields it really measures.
    pub measured: Vec<&'static str>,
    /// The missing ones.
    pub not_measured: Vec<&'static str>,
    /// Its line's baud rate (0: none declared).
    pub line_baud: u32,
}

impl DeviceSummary {
    /// The summary of `c`.
    pub fn of(c: &Capabilities) -> Self {
        Self {
            protocol_version: format!("{}.{}", c.version_major, c.version_minor),
            device_id: text_field(&c.device_id).unwrap_or("?").to_string(),
            program: text_field(&c.program).unwrap_or("?").to_string(),
            sample_rate_hz: f64::from(c.sample_rate_hz),
            override_mode: match c.override_mode {
                OverrideModeCode::Dial16 => "dial16",
                OverrideModeCode::WholePercent => "whole-percent",
                OverrideModeCode::Continuous => "continuous",
                OverrideModeCode::Other(_) => "other",
            },
            override_range_pct: (
                f64::from(c.min_override_cpct) / 100.0,
                f64::from(c.max_override_cpct) / 100.0,
            ),
            watchdog_timeout_s: f64::from(c.watchdog_timeout_ms) / 1000.0,
            fallback_override_pct: f64::from(c.fallback_override_cpct) / 100.0,
            sim_truth: c.features & feature::SIM_TRUTH != 0,
            fallback_limit_s: f64::from(c.fallback_limit_ms) / 1000.0,
            measured: measured::NAMES
                .iter()
                .filter(|(bit, _)| c.measured & bit != 0)
                .map(|(_, name)| *name)
                .collect(),
            not_measured: measured::NAMES
                .iter()
                .filter(|(bit, _)| c.measured & bit == 0)
                .map(|(_, name)| *name)
                .collect(),
            line_baud: c.line_baud,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::frame::{padded, Frame};
    use crate::protocol::keep_up::KeepUp;

    fn caps() -> Capabilities {
        Capabilities {
            version_major: 1,
            version_minor: 0,
            device_id: padded("test"),
            program: padded("kim-step-doc"),
            channel_mask: 0x7F,
            spindle_current_a_per_count: 0.01,
            feed_current_a_per_count: 0.01,
            fv_v_per_count: 0.001,
            sample_rate_hz: 1000.0,
            override_mode: OverrideModeCode::WholePercent,
            min_override_cpct: 0,
            max_override_cpct: 25500,
            dial_cpct: [0; 16],
            watchdog_timeout_ms: 500,
            fallback_override_cpct: 5000,
            over_current_a: 150.0,
            features: 0,
            measured: measured::ALL,
            fallback_limit_ms: 5000,
            line_baud: 0,
        }
    }

    fn sample(seq: u32, time_us: u32, spindle_counts: i16) -> Sample {
        Sample {
            seq,
            time_us,
            flags: sample_flag::IN_CYCLE | sample_flag::SPINDLE_RUNNING,
            spindle_current_counts: [spindle_counts, 0, 0],
            feed_current_counts: [0; 3],
            fv_counts: 0,
            spindle_speed_rpm: 1000.0,
            spindle_command_rpm: 1000.0,
            programmed_feed_mm_min: 200.0,
            feed_mm_min: 200.0,
            applied_override_cpct: 10000,
            dial_code: 0xFF,
            faults: 0,
        }
    }

    fn session_with(frames: &[Frame]) -> HostSession {
        let mut s = HostSession::new();
        let mut bytes = Vec::new();
        HostSession::push_frame(&Frame::Capabilities(caps()), &mut bytes);
        for f in frames {
            HostSession::push_frame(f, &mut bytes);
        }
        s.start_part();
        s.receive(&bytes);
        s
    }

    fn drain(s: &mut HostSession) -> Vec<LinkSample> {
        std::iter::from_fn(|| s.next_sample()).collect()
    }

    #[test]
    fn samples_scale_counts_and_time_from_the_cycle_start() {
        let mut s = session_with(&[
            Frame::Sample(sample(10, 5_001_000, 100)),
            Frame::Sample(sample(11, 5_002_000, 200)),
        ]);
        let got = drain(&mut s);
        assert_eq!(got.len(), 2);
        let a = got[0].step.sensors;
        assert!((a.time_s - 0.001).abs() < 1e-12);
        // The scale travels as an f32: 0.01 is 0.0099999998.
        assert!((a.spindle_phase_currents_a[0] - 1.0).abs() < 1e-6);
        assert_eq!(a.applied_override_pct, 100.0);
        assert!((got[1].step.sensors.time_since_spindle_start_s - 0.001).abs() < 1e-12);
        assert_eq!(s.stats().frames_lost, 0);
    }

    #[test]
    fn a_short_gap_is_counted_and_filled_by_interpolation_a_long_one_only_counted() {
        let mut s = session_with(&[
            Frame::Sample(sample(1, 1000, 100)),
            Frame::Sample(sample(4, 4000, 400)),
            Frame::Sample(sample(20, 20_000, 400)),
        ]);
        let got = drain(&mut s);
        let currents: Vec<f64> = got
            .iter()
            .map(|g| g.step.sensors.spindle_phase_currents_a[0])
            .collect();
        let times: Vec<f64> = got.iter().map(|g| g.step.sensors.time_s).collect();
        assert_eq!(got.len(), 5, "{currents:?}");
        for (c, want) in currents.iter().zip([1.0, 2.0, 3.0, 4.0, 4.0]) {
            assert!((c - want).abs() < 1e-6, "{currents:?}");
        }
        assert!((times[2] - 0.003).abs() < 1e-9 && (times[4] - 0.020).abs() < 1e-9);
        assert_eq!(s.stats().frames_lost, 2 + 15);
    }

    #[test]
    fn a_reordered_or_repeated_sample_is_dropped() {
        let mut s = session_with(&[
            Frame::Sample(sample(5, 5000, 1)),
            Frame::Sample(sample(6, 6000, 1)),
            Frame::Sample(sample(5, 5000, 1)),
            Frame::Sample(sample(7, 7000, 1)),
        ]);
        assert_eq!(drain(&mut s).len(), 3);
        assert_eq!(s.stats().frames_reordered, 1);
        assert_eq!(s.stats().frames_lost, 0);
    }

    #[test]
    fn faults_other_than_the_watchdog_call_for_an_alarm_once_and_an_e_stop_flag_counts_too() {
        use crate::protocol::frame::Fault;
        let fault = |seq, kind, active| {
            Frame::Fault(Fault {
                seq,
                time_us: 0,
                kind,
                active,
                channel: 0xFF,
                applied_override_cpct: 5000,
            })
        };
        let mut s = session_with(&[
            fault(1, FaultKind::Watchdog, 1),
            fault(2, FaultKind::OverCurrent, 1),
            fault(3, FaultKind::OverCurrent, 0),
            fault(4, FaultKind::EStop, 1),
            // Its samples show the E-stop the fault reported: nothing new.
            Frame::Sample(Sample {
                flags: sample_flag::ESTOP,
                ..sample(1, 1000, 0)
            }),
        ]);
        assert_eq!(
            s.take_alarm_faults(),
            [FaultKind::OverCurrent, FaultKind::EStop]
        );
        assert!(s.take_alarm_faults().is_empty());
        assert_eq!(s.stats().watchdog_fallbacks, 1);
        // An E-stop whose fault report was lost: the samples' flag raises it.
        let mut s = session_with(&[
            Frame::Sample(sample(1, 1000, 0)),
            Frame::Sample(Sample {
                flags: sample_flag::ESTOP,
                ..sample(2, 2000, 0)
            }),
            Frame::Sample(Sample {
                flags: sample_flag::ESTOP,
                ..sample(3, 3000, 0)
            }),
        ]);
        assert_eq!(s.take_alarm_faults(), [FaultKind::EStop]);
    }

    #[test]
    fn a_batch_of_fallback_samples_is_re_armed_once_logged_at_its_sample() {
        // 400 samples (0.4 s) in fallback arrive at once, as from a device running 40x real
        // time: the device reads nothing the host sends before the batch's last sample.
        let batch: Vec<Frame> = (1..=400)
            .map(|seq| {
                Frame::Sample(Sample {
                    flags: sample_flag::IN_CYCLE | sample_flag::ARMED | sample_flag::FALLBACK,
                    ..sample(seq, seq * 1000, 0)
                })
            })
            .collect();
        let mut s = session_with(&batch);
        let mut keep = KeepUp::new(&caps());
        keep.armed(0.0);
        let command = OverrideCommand::default();
        let mut out = Vec::new();
        for l in drain(&mut s) {
            keep.keep_up(&mut s, command, l.device_time_s, &mut out);
            keep.sent(l.device_time_s);
        }
        let rearms: Vec<&LinkEvent> = s
            .events()
            .iter()
            .filter(|e| e.text.starts_with("re-arming"))
            .collect();
        assert_eq!(rearms.len(), 1, "{rearms:?}");
        // Sent at the first sample an interval after the arming (at 0.1 s or the one after, by
        // rounding), and logged there.
        assert!((rearms[0].time_s - 0.1).abs() <= 0.0011, "{rearms:?}");
        // Unanswered two intervals after the batch's last sample: the next attempt.
        keep.keep_up(&mut s, command, 0.4 + 0.15, &mut out);
        let n = |s: &HostSession| {
            s.events()
                .iter()
                .filter(|e| e.text.starts_with("re-arming"))
                .count()
        };
        assert_eq!(n(&s), 1);
        keep.keep_up(&mut s, command, 0.4 + 0.2, &mut out);
        assert_eq!(n(&s), 2);
    }

    #[test]
    fn the_device_clock_unwraps_across_its_32_bit_wrap() {
        let mut s = session_with(&[
            Frame::Sample(sample(1, u32::MAX - 499, 1)),
            Frame::Sample(sample(2, 500, 1)),
        ]);
        let got = drain(&mut s);
        let step_s = got[1].device_time_s - got[0].device_time_s;
        assert!((step_s - 0.001).abs() < 1e-9, "{step_s}");
        assert!((got[1].step.sensors.time_s - 0.002).abs() < 1e-9);
    }
}
