//! The work under way: each sample pushed into the teach cut or the run and recorded as a row,
//! and how the work ends (finished, stopped, held at the safe override, the device handed back,
//! an alarm).

use std::fmt::Write as _;

use super::hardware_session::{Activity, PeriodValues, NO_PERIOD};
use super::{HardwareSession, LinkState, TaughtCalibration};
use crate::closed_loop::lab::{metrics_config, RunResult};
use crate::closed_loop::metrics::compute;
use crate::closed_loop::sample_loop::{LoopSample, SampleLoop};
use crate::hardware::recording::LiveRow;
use crate::machine::OverrideCommand;
use crate::protocol::frame::sample_flag;
use crate::protocol::host::LinkSample;

impl HardwareSession {
    pub(super) fn sample(&mut self, s: &LinkSample, now_s: f64) {
        self.device_time_s = s.device_time_s;
        self.wall_at_device_time_s = now_s;
        self.last_sample_s = now_s;
        let first = *self.first_device_time_s.get_or_insert(s.device_time_s);
        let loop_sample = LoopSample {
            step: &s.step,
            sensorless: None,
            dynamometer: None,
        };
        if s.flags & sample_flag::FALLBACK != 0 && matches!(self.activity, Activity::Teach(_)) {
            self.teach_cut_fell_back(now_s);
        }
        let idle_before = matches!(self.activity, Activity::Hold | Activity::Idle);
        let (mut teach_done, mut run_done) = (false, false);
        match &mut self.activity {
            Activity::Teach(t) => {
                t.teach.push(&loop_sample);
                if s.program_end {
                    t.teach.end_of_program();
                }
                teach_done = t.teach.finished();
            }
            Activity::Loop(r) => {
                if r.run.push(&loop_sample).is_some() && r.run.trace().rows.len() > r.rows_seen {
                    r.rows_seen = r.run.trace().rows.len();
                    if let Some(row) = r.run.trace().rows.last() {
                        self.period = PeriodValues {
                            force_est_n: row.force_est_n,
                            armed: row.armed,
                            spindle_current_rms_a: row.spindle_current_rms_a,
                            feed_current_rms_a: row.feed_current_rms_a,
                            target_force_n: row.target_force_n,
                        };
                    }
                }
                if s.program_end {
                    r.run.end_of_program();
                }
                run_done = r.run.finished();
            }
            Activity::Hold | Activity::Idle => {}
        }
        self.copy_loop_events();
        if teach_done {
            self.finish_teach(s.program_end, now_s);
        }
        if run_done {
            self.finish_run(s.program_end, now_s);
        }
        if idle_before && s.program_end && self.holding {
            self.release("the part ended");
            self.set_state(
                if self.state == LinkState::Alarm {
                    LinkState::Alarm
                } else {
                    LinkState::Streaming
                },
                "the part ended: the device handed back to the machine's own dial".to_string(),
            );
        }
        self.keep_up(s.device_time_s);
        // A re-arm this sample sent is logged at its time, not at the newest sample's; the
        // batch's later events wait for their own samples.
        self.copy_host_events_until(Some(s.device_time_s));
        let sensors = &s.step.sensors;
        let truth = s.step.truth;
        let stage = self.stage();
        let row = LiveRow {
            time_s: s.device_time_s - first,
            part: self.host.part(),
            spindle_currents_a: sensors.spindle_phase_currents_a,
            feed_currents_a: sensors.feed_phase_currents_a,
            spindle_fv_v: sensors.spindle_fv_voltage_v,
            spindle_speed_rpm: sensors.spindle_speed_rpm,
            spindle_command_rpm: sensors.spindle_command_rpm,
            programmed_feed_mm_min: sensors.programmed_feed_mm_min,
            feed_mm_min: sensors.feed_mm_min,
            applied_override_pct: sensors.applied_override_pct,
            commanded_override_pct: self.command().map_or(f64::NAN, |c| c.override_pct),
            force_est_n: self.period.force_est_n,
            envelope_armed: self.period.armed,
            spindle_current_rms_a: self.period.spindle_current_rms_a,
            feed_current_rms_a: self.period.feed_current_rms_a,
            target_force_n: self.period.target_force_n,
            force_n: truth.map_or(f64::NAN, |t| t.force_resultant_n),
            depth_mm: truth.map_or(f64::NAN, |t| t.depth_mm),
            phase: if s.flags & sample_flag::FALLBACK != 0 {
                "device watchdog fallback"
            } else {
                stage.label()
            },
            program_end: s.program_end,
            event: std::mem::take(&mut self.pending_row_event),
        };
        self.rows.push(row);
    }

    fn copy_loop_events(&mut self) {
        let Activity::Loop(r) = &mut self.activity else {
            return;
        };
        let events = &r.run.trace().events;
        let new: Vec<String> = events
            .iter()
            .skip(r.events_copied)
            .map(|e| format!("safety envelope: {}", e.describe()))
            .collect();
        r.events_copied = events.len();
        for text in new {
            self.event(text);
        }
    }

    fn finish_teach(&mut self, program_end: bool, now_s: f64) {
        let Activity::Teach(t) = std::mem::replace(&mut self.activity, Activity::Idle) else {
            return;
        };
        self.finished_work = true;
        match t.teach.calibration() {
            Ok(calibration) => {
                let text = format!(
                    "teach cut complete: {} periods fitted over {:.1} s",
                    calibration.periods, calibration.duration_s
                );
                let source = format!("teach cut over the link (part {})", self.host.part());
                self.use_calibration(TaughtCalibration {
                    calibration,
                    settings: Some(t.settings),
                    source,
                });
                self.end_part(program_end, text, now_s);
            }
            Err(e) => self.end_part(program_end, format!("teach cut failed: {e}"), now_s),
        }
    }

    /// The device's watchdog fell back during the teach cut: from this sample on the machine runs
    /// at the fallback override, while the fit would take each period for the override the
    /// teach schedule commanded — a calibration made of both would be wrong without a word.
    /// The teach cut is abandoned (no calibration) and the safe override held until the part
    /// ends; the operator runs it again.
    fn teach_cut_fell_back(&mut self, now_s: f64) {
        let fallback_pct = self
            .capabilities
            .map_or(f64::NAN, |c| f64::from(c.fallback_override_cpct) / 100.0);
        let why = format!(
            "the device's watchdog fell back (override at most {fallback_pct} %), so the cut no \
             longer follows the teach cut's overrides"
        );
        self.stop_work(&why, false);
        self.hold_safe(now_s);
        let safe = self.safe_override_pct();
        self.set_state(
            LinkState::Streaming,
            format!(
                "teach cut abandoned: {why}; no calibration made, run the teach cut again (the \
                 override held at {safe} % until the part ends)"
            ),
        );
    }

    fn finish_run(&mut self, program_end: bool, now_s: f64) {
        self.stop_work("", program_end);
        let text = match (&self.result, program_end) {
            (Some(r), true) => format!(
                "run complete: cycle time {:.1} s, mean |error| {:.1} %",
                r.metrics.cycle_time_s, r.metrics.force_mean_abs_error_pct
            ),
            _ if self.held.feed_hold => "overload: the envelope held the feed".to_string(),
            _ => "the run reached its time limit before the program's end".to_string(),
        };
        if self.held.feed_hold && !program_end {
            self.alarm(text, now_s);
        } else {
            self.end_part(program_end, text, now_s);
        }
    }

    /// After a teach cut or a run: at the program's end the device is handed back; before it,
    /// the safe override is held until the part ends.
    fn end_part(&mut self, program_end: bool, text: String, now_s: f64) {
        if program_end {
            self.release(&text);
            self.set_state(LinkState::Streaming, text);
        } else {
            self.hold_safe(now_s);
            let safe = self.safe_override_pct();
            self.set_state(
                LinkState::Streaming,
                format!("{text}; the override held at {safe} % until the part ends"),
            );
        }
    }

    /// Ends the teach cut or run under way: a run's trace becomes the result (marked incomplete
    /// unless the program ended), a teach cut is dropped.
    pub(super) fn stop_work(&mut self, why: &str, completed: bool) {
        match std::mem::replace(&mut self.activity, Activity::Idle) {
            Activity::Teach(_) => {
                self.finished_work = true;
                if !why.is_empty() {
                    self.event(format!("teach cut abandoned ({why}): no calibration made"));
                }
            }
            Activity::Loop(mut r) => {
                self.finished_work = true;
                // A feed hold the envelope ordered stays in force whatever comes next.
                self.held.feed_hold |= r.run.command().feed_hold;
                let settings = r.run.settings().clone();
                let mut trace = r.run.finish().unwrap_or_default();
                trace.completed = completed;
                let metrics = compute(&trace, &metrics_config(r.spec.preset, &settings));
                self.result = Some(Box::new(RunResult {
                    spec: r.spec,
                    settings,
                    calibration: r.calibration,
                    trace,
                    metrics,
                }));
                if !why.is_empty() {
                    self.event(format!("run stopped ({why}): its trace ends here"));
                }
            }
            other => self.activity = other,
        }
        self.period = NO_PERIOD;
    }

    /// Commands the safe override at once (keeping a feed hold in force) and holds it.
    pub(super) fn hold_safe(&mut self, now_s: f64) {
        if !self.holding {
            self.activity = Activity::Idle;
            return;
        }
        self.held.override_pct = self.safe_override_pct();
        self.activity = Activity::Hold;
        let clock_s = self.clock_s(now_s);
        self.keep_up(clock_s);
    }

    /// Hands the device back to the machine's own dial (Disarm).
    pub(super) fn release(&mut self, why: &str) {
        if self.holding {
            self.host.disarm(&mut self.out);
            let clock_s = self.device_time_s;
            self.sent(clock_s);
            self.holding = false;
            self.held = OverrideCommand::default();
            self.event(format!("disarm: {why}; the machine's own dial applies"));
        }
        self.activity = Activity::Idle;
    }

    pub(super) fn alarm(&mut self, reason: String, now_s: f64) {
        self.stop_work(&reason, false);
        self.hold_safe(now_s);
        let mut text = reason;
        if self.holding {
            let _ = write!(
                text,
                "; the host commands the safe override ({} %)",
                self.safe_override_pct()
            );
        }
        self.set_state(LinkState::Alarm, text);
    }
}
