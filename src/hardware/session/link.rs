//! The link: the bytes that arrived, time passing and the port closing; the handshake, the host's
//! watchdog, the device's faults and what is due to be sent.

use super::hardware_session::Activity;
use super::{HardwareSession, LinkState};
use crate::closed_loop::sample_loop::SampleLoop;
use crate::machine::OverrideCommand;
use crate::protocol::frame::{Ack, Capabilities, FaultKind, FrameType, VERSION_MAJOR};
use crate::protocol::host::{DeviceSummary, LinkEvent, HELLO_INTERVAL_S};
use crate::protocol::keep_up::KeepUp;
use crate::protocol::line_budget::LineBudget;

impl HardwareSession {
    /// Takes the bytes that arrived at `now_s`.
    pub fn receive(&mut self, bytes: &[u8], now_s: f64) {
        if self.state == LinkState::Closed || self.port_gone {
            return;
        }
        let frames_before = self.host.stats().frames_received;
        self.host.receive(bytes);
        if self.host.stats().frames_received > frames_before {
            self.last_frame_s = now_s;
        }
        if self.capabilities.is_none() {
            if let Some(c) = self.host.capabilities().copied() {
                self.handshake_done(c, now_s);
            }
        }
        // Each event of the batch goes in at the sample it came with (the protocol session
        // stamped it so), before that sample's row is made, so its row carries it.
        while let Some(sample) = self.host.next_sample() {
            self.copy_host_events_until(Some(sample.device_time_s));
            self.sample(&sample, now_s);
        }
        self.copy_host_events();
        self.watch_device_faults(now_s);
    }

    /// Time passes: the handshake's Hello, heartbeats, the host's watchdog.
    pub fn tick(&mut self, now_s: f64) {
        match self.state {
            LinkState::Closed => return,
            LinkState::Handshaking => {
                if now_s - self.connected_s > self.options.handshake_timeout_s {
                    self.close(format!(
                        "no answer to Hello within {} s ({}): is the device on, at this baud \
                         rate?",
                        self.options.handshake_timeout_s,
                        self.host.stats().received()
                    ));
                } else if now_s - self.last_hello_s >= HELLO_INTERVAL_S {
                    self.last_hello_s = now_s;
                    self.host.hello(&mut self.out);
                }
                return;
            }
            LinkState::Streaming | LinkState::Armed | LinkState::Alarm => {}
        }
        let timeout = self.options.link_timeout_s;
        let running = matches!(self.activity, Activity::Teach(_) | Activity::Loop(_));
        if running && now_s - self.last_sample_s > timeout {
            self.host.link_lost(format!(
                "host watchdog: no sample for {timeout} s while the part runs"
            ));
            self.alarm(
                format!("host watchdog: no sample for {timeout} s while the part ran"),
                now_s,
            );
        } else if self.state != LinkState::Alarm && now_s - self.last_frame_s > timeout {
            self.host
                .link_lost(format!("host watchdog: the device silent for {timeout} s"));
            self.alarm(
                format!("host watchdog: the device has been silent for {timeout} s"),
                now_s,
            );
        }
        if !self.port_gone {
            let clock_s = self.clock_s(now_s);
            self.keep_up(clock_s);
        }
        self.copy_host_events();
    }

    /// The port closed under the session (unplugged, a read or write error): nothing more can
    /// be sent or received.
    pub fn link_lost(&mut self, why: &str, now_s: f64) {
        if self.state == LinkState::Closed {
            return;
        }
        let was_holding = self.holding;
        self.holding = false;
        self.port_gone = true;
        self.out.clear();
        self.host.link_lost(format!("link lost: {why}"));
        let fallback = match self.capabilities {
            Some(c) if was_holding => format!(
                "; the device applies its fallback override (at most {} %, never above the \
                 applied) on its own after its watchdog ({} s), then holds the feed",
                f64::from(c.fallback_override_cpct) / 100.0,
                f64::from(c.watchdog_timeout_ms) / 1000.0
            ),
            _ => String::new(),
        };
        self.alarm(format!("link lost: {why}{fallback}"), now_s);
        self.activity = Activity::Idle;
        self.copy_host_events();
    }

    /// The protocol session's new events, each at the device time of the sample it belongs to.
    pub(super) fn copy_host_events(&mut self) {
        self.copy_host_events_until(None);
    }

    /// The protocol session's new events up to the first that belongs to a sample after
    /// `until_device_time_s` (`None`: all), each at the device time of the sample it belongs to
    /// (the latest sample's, for one recorded before any).
    pub(super) fn copy_host_events_until(&mut self, until_device_time_s: Option<f64>) {
        let due = |e: &LinkEvent| match (e.device_time_s, until_device_time_s) {
            (Some(t), Some(until)) => t <= until,
            _ => true,
        };
        let new: Vec<(Option<f64>, String)> = self
            .host
            .events()
            .iter()
            .skip(self.host_events_copied)
            .take_while(|e| due(e))
            .map(|e| {
                (
                    e.device_time_s,
                    format!("link, part {}: {}", e.part, e.text),
                )
            })
            .collect();
        self.host_events_copied += new.len();
        for (device_time_s, text) in new {
            self.event_at(device_time_s, text);
        }
    }

    fn handshake_done(&mut self, caps: Capabilities, now_s: f64) {
        let summary = DeviceSummary::of(&caps);
        if caps.version_major != VERSION_MAJOR {
            self.close(format!(
                "the device speaks protocol {}; this host speaks {VERSION_MAJOR}.x",
                summary.protocol_version
            ));
            return;
        }
        if !(summary.sample_rate_hz.is_finite() && summary.sample_rate_hz > 0.0) {
            self.close(format!(
                "the device declares a sample rate of {} Hz",
                summary.sample_rate_hz
            ));
            return;
        }
        if let Some(why) = LineBudget::of(&caps).refusal() {
            self.close(why);
            return;
        }
        self.capabilities = Some(caps);
        self.keep_up = Some(KeepUp::new(&caps));
        self.last_frame_s = now_s;
        self.set_state(
            LinkState::Streaming,
            format!(
                "handshake complete: {} ({}), protocol {}",
                summary.device_id, summary.program, summary.protocol_version
            ),
        );
    }

    /// A device fault (not the watchdog's, which the host answers by re-arming) raises an alarm
    /// (docs/protocol.md §5): after an over-current or a sensor fault the safe override is held
    /// until the part ends; after an E-stop — commands refused, the axes stopped — the device is
    /// handed back at once, so that after the reset the machine's own dial applies.
    fn watch_device_faults(&mut self, now_s: f64) {
        let running = matches!(self.activity, Activity::Teach(_) | Activity::Loop(_));
        if let Some(stuck) = self.host.take_stuck_override() {
            if self.state != LinkState::Alarm {
                self.alarm(stuck, now_s);
            }
        }
        if running && self.host.hold_latched() {
            self.alarm(
                "the device holds the feed, latched: the operator resets it once the cause is \
                 cleared"
                    .to_string(),
                now_s,
            );
        }
        let Some(kind) = self.host.take_alarm_faults().first().copied() else {
            return;
        };
        let text = self
            .host
            .events()
            .iter()
            .rev()
            .find(|e| e.text.starts_with("device fault") || e.text.contains("fault is active"))
            .map_or_else(
                || format!("device fault {}", kind.name()),
                |e| e.text.clone(),
            );
        if kind == FaultKind::EStop {
            self.stop_work(&text, false);
            self.release("E-stop: commands are refused and the axes stopped");
            self.set_state(
                LinkState::Alarm,
                format!("{text}; the device handed back to the machine's own dial"),
            );
        } else {
            self.alarm(text, now_s);
        }
    }

    /// The command in force while the host holds the device.
    pub(super) fn command(&self) -> Option<OverrideCommand> {
        if !self.holding {
            return None;
        }
        Some(match &self.activity {
            Activity::Teach(t) => t.teach.command(),
            Activity::Loop(r) => r.run.command(),
            Activity::Hold | Activity::Idle => self.held,
        })
    }

    /// What is due at device time `clock_s`: the command, heartbeats, re-arming.
    pub(super) fn keep_up(&mut self, clock_s: f64) {
        let command = self.command();
        let Some(k) = &mut self.keep_up else {
            return;
        };
        let before = self.out.len();
        match command {
            Some(c) => k.keep_up(&mut self.host, c, clock_s, &mut self.out),
            None => k.heartbeat_if_due(&mut self.host, clock_s, &mut self.out),
        }
        if self.out.len() > before {
            k.sent(clock_s);
        }
    }
}

/// A short description of an acknowledgement, for the page.
pub fn describe_ack(ack: &Ack) -> String {
    let command = FrameType::from_code(ack.command).map_or("?", FrameType::name);
    let result = match ack.result.code() {
        0 => "applied",
        1 => "applied, limited to the device's range",
        2 => "ignored: not armed",
        3 => "refused: E-stop",
        _ => "unknown result",
    };
    format!(
        "{command} #{}: {result}; override now {} %",
        ack.seq,
        f64::from(ack.applied_override_cpct) / 100.0
    )
}
