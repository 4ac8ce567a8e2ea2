//! The operator's commands: teach cut, arm, disarm, reset the feed hold, acknowledge an alarm,
//! disconnect; and what the machine gets if the link is lost now.

use super::arming::{check_line, check_measured, teach_force};
use super::hardware_session::{Activity, PeriodValues, Running, Teaching, NO_PERIOD};
use super::{HardwareSession, LinkState};
use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::lab::plan_on;
use crate::closed_loop::teach_cut::{TeachCut, TeachSchedule};
use crate::machine::OverrideCommand;
use crate::protocol::frame::fault_flag;

impl HardwareSession {
    /// Arms the device for a teach cut of `spec`'s settings (after the page's confirmation).
    pub fn start_teach_cut(&mut self, spec: &RunSpec, now_s: f64) -> Result<(), String> {
        self.teach_limits(spec)?;
        let caps = self.ready_to_arm()?;
        self.check_safe_override(&caps)?;
        let plan = plan_on(spec, f64::from(caps.sample_rate_hz)).map_err(|e| e.to_string())?;
        check_measured(&caps, true)?;
        check_line(&caps, spec)?;
        let teach = TeachCut::new(
            f64::from(caps.sample_rate_hz),
            &plan,
            teach_force(&caps, spec)?,
            TeachSchedule::Overrides,
        )
        .map_err(|e| e.to_string())?;
        let settings = plan.chain;
        self.activity = Activity::Teach(Box::new(Teaching { teach, settings }));
        self.arm_device(
            "teach cut armed: the host runs the teach-cut overrides",
            now_s,
        );
        Ok(())
    }

    /// Arms the device for the closed loop of `spec` (after the page's confirmation).
    pub fn arm(&mut self, spec: &RunSpec, now_s: f64) -> Result<(), String> {
        let caps = self.ready_to_arm()?;
        let (run, calibration) = self.prepare_loop(spec, &caps)?;
        self.period = PeriodValues {
            target_force_n: run.settings().target_force_n,
            ..NO_PERIOD
        };
        self.activity = Activity::Loop(Box::new(Running {
            run,
            spec: spec.clone(),
            calibration,
            events_copied: 0,
            rows_seen: 0,
        }));
        self.arm_device(
            &format!(
                "armed by the operator: {} in control",
                spec.controller.kind().label()
            ),
            now_s,
        );
        Ok(())
    }

    fn arm_device(&mut self, reason: &str, now_s: f64) {
        self.host.start_part();
        self.host.event("arm (cycle start)");
        let clock_s = self.clock_s(now_s);
        if let Some(k) = &mut self.keep_up {
            k.armed(clock_s);
        }
        self.host.arm(&mut self.out);
        self.sent(clock_s);
        self.holding = true;
        self.held = OverrideCommand::default();
        self.last_sample_s = now_s;
        self.set_state(LinkState::Armed, reason.to_string());
    }

    /// The operator resets the device's latched feed hold (after clearing its cause): a Reset
    /// goes out; the device releases the hold unless the cause is still there.
    pub fn reset_hold(&mut self) -> Result<(), String> {
        if self.capabilities.is_none() || self.port_gone || self.state == LinkState::Closed {
            return Err("no device: connect first".into());
        }
        self.host.reset(&mut self.out);
        // The host's own feed hold goes too, or its next command would latch the hold again.
        self.held.feed_hold = false;
        let clock_s = self.device_time_s;
        self.sent(clock_s);
        self.event("the operator resets the device's latched feed hold".to_string());
        Ok(())
    }

    /// The feed hold as the machine sees it: latched at the device (with its cause), or `None`.
    pub fn hold_state(&self) -> Option<String> {
        if !self.host.hold_latched() {
            return None;
        }
        let faults = self.host.active_faults();
        let cause = if faults & fault_flag::OVER_CURRENT != 0 {
            "an over-current, still there: reset once it is cleared"
        } else if faults & fault_flag::FALLBACK_LIMIT != 0 {
            "the fallback lasted its time limit"
        } else {
            "the host's feed hold (the envelope's overload) or an over-current since cleared"
        };
        Some(format!(
            "the device holds the feed, latched ({cause}): it stays through any link state \
             until the operator resets it"
        ))
    }

    /// What the machine gets if the link is lost now (docs/protocol.md §5): the device's
    /// fallback — the lower of the override applied and its configured fallback — for its time
    /// limit, then a latched feed hold; `None` when the host does not hold the device.
    pub fn if_link_lost(&self) -> Option<String> {
        let caps = self.capabilities?;
        if !self.holding {
            return None;
        }
        let applied = self
            .host
            .last_ack()
            .map_or(f64::NAN, |a| f64::from(a.applied_override_cpct) / 100.0);
        let configured = f64::from(caps.fallback_override_cpct) / 100.0;
        let fallback = if applied.is_finite() {
            applied.min(configured)
        } else {
            configured
        };
        Some(format!(
            "If the link is lost now: after {} s the device applies {fallback} % (the lower of \
             {applied} % applied and its {configured} % fallback) for at most {} s, then holds \
             the feed until the operator resets it.",
            f64::from(caps.watchdog_timeout_ms) / 1000.0,
            f64::from(caps.fallback_limit_ms) / 1000.0
        ))
    }

    /// The operator takes the host out of control (Disarm, or Escape): the run ends there and
    /// the safe override is commanded at once and held until the part ends.
    pub fn disarm(&mut self, why: &str, now_s: f64) {
        if !matches!(self.activity, Activity::Teach(_) | Activity::Loop(_)) {
            return;
        }
        self.stop_work(why, false);
        self.hold_safe(now_s);
        let safe = self.safe_override_pct();
        self.set_state(
            LinkState::Streaming,
            format!("{why}: the override held at {safe} % (the safe value) until the part ends"),
        );
    }

    /// The operator acknowledges an alarm; the link must be alive again (a frame within the
    /// host's watchdog) to leave it.
    pub fn acknowledge_alarm(&mut self, now_s: f64) -> Result<(), String> {
        if self.state != LinkState::Alarm {
            return Ok(());
        }
        if self.capabilities.is_none() || now_s - self.last_frame_s > self.options.link_timeout_s {
            return Err(
                "the device is still silent: reconnect it (Disconnect, then Connect)".into(),
            );
        }
        self.set_state(
            LinkState::Streaming,
            "alarm acknowledged by the operator".to_string(),
        );
        Ok(())
    }

    /// Ends the session: a held device is disarmed (handed back to the machine's own dial).
    pub fn disconnect(&mut self, now_s: f64) {
        if self.state == LinkState::Closed {
            return;
        }
        self.stop_work("disconnected", false);
        if self.holding {
            self.host.disarm(&mut self.out);
            let clock_s = self.clock_s(now_s);
            self.sent(clock_s);
            self.holding = false;
        }
        self.activity = Activity::Idle;
        self.close("disconnected by the operator".to_string());
    }
}
