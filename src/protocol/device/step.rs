//! One frame period ([`DeviceEmulator::step_frame`]): the injected E-stop, the device-side
//! watchdog and its fallback, the fallback's time limit, a block of the part (or the idle clock),
//! and the heartbeat.

use super::faults::NO_CHANNEL;
use super::{DeviceEmulator, HoldCause};
use crate::protocol::frame::{FaultKind, Frame, Heartbeat};

/// How often the device sends a heartbeat, device time.
pub const HEARTBEAT_INTERVAL_S: f64 = 0.1;

impl DeviceEmulator {
    /// Runs one sample period: the machine (if a part is in), the watchdog, heartbeats; the
    /// frames to send go into `out`.
    pub fn step_frame(&mut self, out: &mut Vec<u8>) {
        self.update_link_faults();
        let start_s = self.time_s();
        if !self.estop
            && self
                .config
                .faults
                .estop_at_s
                .is_some_and(|at| start_s >= at)
        {
            self.estop = true;
            self.apply_override();
            self.log(
                "E-stop input active (injected): the feed stops; commands refused".to_string(),
            );
            self.report_fault(FaultKind::EStop, true, NO_CHANNEL, out);
        }
        if self.armed
            && !self.fallback
            && start_s - self.last_host_frame_s > self.config.watchdog_timeout_s
        {
            // Never faster than the loop left it: the fallback is the lower of the override
            // applied now and the configured one.
            self.fallback_pct = self.applied.pct.min(self.config.fallback_override_pct);
            self.fallback = true;
            self.fallback_since_s = start_s;
            self.stats.watchdog_fallbacks += 1;
            self.apply_override();
            self.log(format!(
                "watchdog: nothing from the host for {} s; fallback override {} % (the lower of \
                 the applied and the configured {} %) until the host re-arms, for at most {} s",
                self.config.watchdog_timeout_s,
                self.applied.pct,
                self.config.fallback_override_pct,
                self.config.fallback_limit_s
            ));
            self.report_fault(FaultKind::Watchdog, true, NO_CHANNEL, out);
        }
        if self.fallback
            && self.hold_latched.is_none()
            && start_s - self.fallback_since_s >= self.config.fallback_limit_s
        {
            self.latch_hold(HoldCause::FallbackLimit);
            self.report_fault(FaultKind::FallbackLimit, true, NO_CHANNEL, out);
        }
        if self.in_cycle() {
            self.run_block(out);
        } else {
            self.ticks += self.config.decimation as u64;
        }
        if self.time_s() >= self.next_heartbeat_s {
            self.next_heartbeat_s = self.time_s() + HEARTBEAT_INTERVAL_S;
            self.heartbeat_seq = self.heartbeat_seq.wrapping_add(1);
            let hb = Heartbeat {
                seq: self.heartbeat_seq,
                time_us: self.time_us(),
                flags: self.state_flags(),
                faults: self.fault_flags(),
                last_sample_seq: self.sample_seq,
            };
            self.send(&Frame::Heartbeat(hb), out);
        }
    }
}
