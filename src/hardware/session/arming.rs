//! Before arming: whether the device is ready and measures what the work needs, and the limits
//! the operator confirms ([`ArmLimits`]).

use super::{HardwareSession, LinkState};
use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::feedback_loop::FeedbackLoop;
use crate::closed_loop::lab::{closed_loop_of, cut_model_teach_force, plan_on};
use crate::closed_loop::teach_cut::{TeachForce, TEACH_OVERRIDES_PCT, TEACH_STEP_S};
use crate::estimation::estimator::{Calibration, Feedback};
use crate::protocol::frame::{measured, Capabilities};
use crate::protocol::host::DeviceSummary;
use crate::protocol::line_budget::LineBudget;
use crate::safety::OverrideResolution;

/// The limits a run will be held to, for the confirmation the operator reads before arming.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmLimits {
    /// Sentences, one per limit.
    pub lines: Vec<String>,
}

impl HardwareSession {
    pub(super) fn ready_to_arm(&self) -> Result<Capabilities, String> {
        let Some(caps) = self.capabilities else {
            return Err("no device: connect first".into());
        };
        if self.host.hold_latched() {
            return Err(
                "the device holds the feed, latched: clear the cause, then reset the \
                        feed hold"
                    .into(),
            );
        }
        match self.state {
            LinkState::Streaming => Ok(caps),
            LinkState::Armed => Err("already armed: disarm first".into()),
            LinkState::Alarm => Err("acknowledge the alarm first".into()),
            LinkState::Closed | LinkState::Handshaking => Err("no device: connect first".into()),
        }
    }

    /// The limits a teach cut will be run with, for the confirmation.
    pub fn teach_limits(&self, spec: &RunSpec) -> Result<ArmLimits, String> {
        let caps = self.ready_to_arm()?;
        let force = teach_force(&caps, spec)?;
        let plan = plan_on(spec, f64::from(caps.sample_rate_hz)).map_err(|e| e.to_string())?;
        let settings = plan.chain;
        // The teach cut never exceeds the run's highest override (reduce-only limits: 100 %).
        let schedule = TEACH_OVERRIDES_PCT
            .iter()
            .map(|p| format!("{:.0} %", p.min(plan.limits.max_override_pct)))
            .collect::<Vec<_>>()
            .join(", ");
        let mut lines = vec![
            format!(
                "The next part runs open loop through the teach-cut overrides {schedule}, each \
                 held {TEACH_STEP_S} s, again and again until the program ends: no controller, \
                 no envelope."
            ),
            match force {
                TeachForce::SimulationTruth => {
                    "The force the current is fitted against: the simulation's truth, which \
                     this device sends."
                        .to_string()
                }
                TeachForce::CutModel {
                    depth_mm, width_mm, ..
                } => format!(
                    "The force the current is fitted against: the model of the preset's cut \
                     ({} deep, {width_mm} mm wide, from each period's feed and speed): the \
                     machine must cut exactly that.",
                    depth_mm.map_or("the machine's depth".to_string(), |d| format!("{d} mm"))
                ),
                TeachForce::Dynamometer => {
                    "The force the current is fitted against: the dynamometer's.".to_string()
                }
            },
            format!(
                "Current measured: {}; control period {} s; low-passes {} Hz (spindle) and {} Hz \
                 (feed), order {}.",
                feedback_name(settings.feedback),
                settings.control_period_s,
                settings.spindle_lowpass_hz,
                settings.feed_lowpass_hz,
                settings.lowpass_order
            ),
        ];
        lines.extend(self.common_limits(&caps));
        Ok(ArmLimits { lines })
    }

    /// The limits the closed loop of `spec` will be held to, for the confirmation.
    pub fn arm_limits(&self, spec: &RunSpec) -> Result<ArmLimits, String> {
        let caps = self.ready_to_arm()?;
        let (run, _) = self.prepare_loop(spec, &caps)?;
        let s = run.settings();
        let e = &s.envelope;
        let resolution = match &e.resolution {
            OverrideResolution::Dial(p) => format!("the {} positions of the dial", p.len()),
            OverrideResolution::WholePercent => "whole percent".to_string(),
            OverrideResolution::Continuous => "continuous".to_string(),
        };
        let mut lines = vec![
            format!(
                "Controller: {}, holding {:.0} N ({}).",
                spec.controller.kind().label(),
                s.target_force_n,
                feedback_name(s.feedback)
            ),
            format!(
                "Override {}–{} % in {resolution}, changing by at most {} %/s; {} % until the \
                 envelope arms, {} s after the spindle starts.",
                e.min_override_pct,
                e.max_override_pct,
                e.max_rate_pct_per_s,
                e.arming_override_pct,
                e.arming_delay_s
            ),
            format!(
                "Overload: feed hold when the force stays above {:.0} N for {} s.",
                e.overload_limit_n, e.overload_time_s
            ),
            format!(
                "A phase current beyond {:.1} A is a sensor fault.",
                e.max_current_a
            ),
        ];
        lines.extend(self.common_limits(&caps));
        Ok(ArmLimits { lines })
    }

    fn common_limits(&self, caps: &Capabilities) -> Vec<String> {
        vec![
            format!(
                "The device applies {}–{} %; its watchdog falls back to {} % after {} s without \
                 the host.",
                f64::from(caps.min_override_cpct) / 100.0,
                f64::from(caps.max_override_cpct) / 100.0,
                f64::from(caps.fallback_override_cpct) / 100.0,
                f64::from(caps.watchdog_timeout_ms) / 1000.0
            ),
            format!(
                "Disarm, Escape and any alarm command {} % (the safe override) at once; the host \
                 alarms after {} s without samples.",
                self.safe_override_pct(),
                self.options.link_timeout_s
            ),
        ]
    }

    pub(super) fn check_safe_override(&self, caps: &Capabilities) -> Result<(), String> {
        let safe = self.safe_override_pct();
        let (lo, hi) = (
            f64::from(caps.min_override_cpct) / 100.0,
            f64::from(caps.max_override_cpct) / 100.0,
        );
        if !(safe >= lo && safe <= hi) {
            return Err(format!(
                "the safe override {safe} % is outside what the device applies ({lo}–{hi} %)"
            ));
        }
        Ok(())
    }

    /// The closed loop of `spec` on this device with the calibration at hand.
    pub(super) fn prepare_loop(
        &self,
        spec: &RunSpec,
        caps: &Capabilities,
    ) -> Result<(FeedbackLoop, Calibration), String> {
        let Some(taught) = &self.calibration else {
            return Err("no calibration yet: make a teach cut, or load a saved calibration".into());
        };
        let sample_rate_hz = f64::from(caps.sample_rate_hz);
        let plan = plan_on(spec, sample_rate_hz).map_err(|e| e.to_string())?;
        if let Some(why) = taught.mismatch(&plan.chain) {
            return Err(why);
        }
        check_measured(caps, false)?;
        check_line(caps, spec)?;
        self.check_safe_override(caps)?;
        let run = closed_loop_of(spec, &plan, &taught.calibration, sample_rate_hz)
            .map_err(|e| e.to_string())?;
        Ok((run, taught.calibration.clone()))
    }
}

/// Whether the device's line carries `spec`'s loop: the handshake allowed for a command a
/// [`COMMANDS_PER_S`](crate::protocol::line_budget::COMMANDS_PER_S) period, and a control period
/// set shorter by hand asks for more ([`LineBudget::for_period`]). A spec that does not resolve
/// on the device says why, as the run would.
pub fn check_line(caps: &Capabilities, spec: &RunSpec) -> Result<(), String> {
    let plan = plan_on(spec, f64::from(caps.sample_rate_hz)).map_err(|e| e.to_string())?;
    LineBudget::for_period(caps, plan.chain.control_period_s)
        .refusal()
        .map_or(Ok(()), Err)
}

/// Whether the device measures what a teach cut (`teach`) or a closed loop needs
/// (docs/protocol.md §3, `measured`): program end to end a part, the spindle's speed and command
/// to judge it at speed, the actual feed for the teach cut's periods and the feed-drive model,
/// and for the closed loop the programmed feed too, so that a stuck override is seen.
pub fn check_measured(caps: &Capabilities, teach: bool) -> Result<(), String> {
    let mut needed = measured::PROGRAM_END
        | measured::SPINDLE_SPEED
        | measured::SPINDLE_COMMAND
        | measured::ACTUAL_FEED;
    if !teach {
        needed |= measured::PROGRAMMED_FEED;
    }
    let missing: Vec<&str> = measured::NAMES
        .iter()
        .filter(|(bit, _)| needed & bit != 0 && caps.measured & bit == 0)
        .map(|(_, name)| *name)
        .collect();
    if missing.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "the device does not measure the {} a {} needs: wire {} to the bridge (docs/hardware.md §1)",
            missing.join(", "),
            if teach { "teach cut" } else { "closed loop" },
            if missing.len() == 1 { "it" } else { "them" }
        ))
    }
}

/// Where a teach cut on this device takes its force: the simulation's truth when the device
/// sends it, else the model of the preset's cut when the program cuts one depth, width and
/// material (as `cutlab host` decides).
pub(super) fn teach_force(caps: &Capabilities, spec: &RunSpec) -> Result<TeachForce, String> {
    if DeviceSummary::of(caps).sim_truth {
        return Ok(TeachForce::SimulationTruth);
    }
    cut_model_teach_force(spec.preset).ok_or_else(|| {
        "this device sends no force and the preset's cut changes along the path, so a teach cut \
         has nothing to fit the current against: load a saved calibration instead"
            .to_string()
    })
}

fn feedback_name(feedback: Feedback) -> &'static str {
    match feedback {
        Feedback::SpindleCurrent => "force from the spindle current",
        Feedback::FeedCurrent => "force from the feed-drive current",
        Feedback::Dynamometer => "force from a dynamometer",
    }
}
