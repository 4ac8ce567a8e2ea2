//! The envelope itself: [`SafetyEnvelope`] watches every sensor sample
//! ([`SafetyEnvelope::observe`]) and turns each controller request into the override the machine
//! receives ([`SafetyEnvelope::command`]), by the rules the module doc of [`crate::safety`] lists.

use crate::machine::{OverrideCommand, SensorSample};

use super::chip_load::{chip_load_band_pct, ChipLoadEnd};
use super::config::{ArmingTrigger, EnvelopeConfig, EnvelopeError, FaultAction};
use super::events::{SafetyEvent, SensorFault};

/// The envelope's state.
#[derive(Debug, Clone)]
pub struct SafetyEnvelope {
    config: EnvelopeConfig,
    sample_period_s: f64,
    /// The rate-limited continuous override that the quantised output follows.
    continuous_pct: f64,
    output_pct: f64,
    armed: bool,
    feed_hold: bool,
    fault: Option<SensorFault>,
    fault_free_s: f64,
    previous_sample: Option<SensorSample>,
    unchanged_s: f64,
    overload_s: f64,
    /// How long the programmed feed has been non-zero (for [`ArmingTrigger::ProgrammedFeed`]).
    programmed_feed_s: f64,
    /// Whether the controller's last request was not a number (reported once per episode).
    controller_fault: bool,
    /// Whether the air-cut rule is holding the override (for one event per stretch of air).
    holding_in_air: bool,
    /// Whether the envelope held the entry override at the last period (in air, or an entry's
    /// hold): the controller was not in charge.
    holding: bool,
    /// Whether the tool was in air at the last period (so the next cut is an entry).
    was_in_air: bool,
    /// When the entry hold under way began.
    entry_since_s: Option<f64>,
    /// The end of the chip-load window that held the override at the last period.
    chip_limited: Option<ChipLoadEnd>,
    events: Vec<SafetyEvent>,
}

/// Events kept before the caller drains them; more in one period are dropped, which cannot
/// happen with the event kinds of [`SafetyEvent`] (at most five per period).
const EVENT_CAPACITY: usize = 16;

impl SafetyEnvelope {
    /// An envelope for a machine whose sensors deliver `sample_rate_hz`.
    pub fn new(config: EnvelopeConfig, sample_rate_hz: f64) -> Result<Self, EnvelopeError> {
        config.check(sample_rate_hz)?;
        let c = &config;
        let start = c
            .arming_override_pct
            .clamp(c.min_override_pct, c.max_override_pct);
        let mut envelope = Self {
            continuous_pct: start,
            output_pct: start,
            sample_period_s: 1.0 / sample_rate_hz,
            armed: false,
            feed_hold: false,
            fault: None,
            fault_free_s: 0.0,
            previous_sample: None,
            unchanged_s: 0.0,
            overload_s: 0.0,
            programmed_feed_s: 0.0,
            controller_fault: false,
            holding_in_air: false,
            holding: false,
            was_in_air: false,
            entry_since_s: None,
            chip_limited: None,
            events: Vec::with_capacity(EVENT_CAPACITY),
            config,
        };
        envelope.output_pct = envelope.quantize(start);
        Ok(envelope)
    }

    /// The configuration.
    pub fn config(&self) -> &EnvelopeConfig {
        &self.config
    }

    /// The override commanded now.
    pub fn output_pct(&self) -> f64 {
        self.output_pct
    }

    /// Time since the start the arming waits for: the spindle's, or with
    /// [`ArmingTrigger::ProgrammedFeed`] (a bench without a spindle) the first programmed feed
    /// motion's. Controllers that ignore a starting transient use this clock too.
    pub fn time_since_start_s(&self, sample: &SensorSample) -> f64 {
        match self.config.arming_trigger {
            ArmingTrigger::SpindleStart => sample.time_since_spindle_start_s,
            ArmingTrigger::ProgrammedFeed => self.programmed_feed_s,
        }
    }

    /// Whether the envelope has armed (the arming delay passed).
    pub fn armed(&self) -> bool {
        self.armed
    }

    /// Whether the envelope held the entry override at the last period — the tool in air, or an
    /// entry's hold — so the controller's request was not listened to. The loop does not step its
    /// controller then (an integrating law would wind up on what it cannot change) and hands it
    /// the override when the hold ends ([`crate::control::law::Controller::take_over`]).
    pub fn holding(&self) -> bool {
        self.holding
    }

    /// The sensor fault in force, if any.
    pub fn fault(&self) -> Option<SensorFault> {
        self.fault
    }

    /// Whether feed hold is latched.
    pub fn feed_hold(&self) -> bool {
        self.feed_hold
    }

    fn quantize(&self, pct: f64) -> f64 {
        let c = &self.config;
        c.resolution
            .nearest(pct, c.min_override_pct, c.max_override_pct)
            .unwrap_or(c.min_override_pct)
    }

    fn emit(&mut self, event: SafetyEvent) {
        if self.events.len() < EVENT_CAPACITY {
            self.events.push(event);
        }
    }

    /// Moves the events raised since the last call into `sink`.
    pub fn drain_events(&mut self, sink: &mut Vec<SafetyEvent>) {
        sink.append(&mut self.events);
    }

    /// Whether the arming trigger is on in `sample`.
    fn triggered(&self, sample: &SensorSample) -> bool {
        match self.config.arming_trigger {
            ArmingTrigger::SpindleStart => sample.spindle_running,
            ArmingTrigger::ProgrammedFeed => sample.programmed_feed_mm_min > 0.0,
        }
    }

    /// Watches one sensor sample for faults. Call for every sample, before [`Self::command`].
    #[inline(always)]
    pub fn observe(&mut self, sample: &SensorSample) {
        // Six currents every sample: plain loops (an iterator chain is a call per item in the
        // size-optimised browser build).
        let mut non_finite = !sample.time_s.is_finite();
        let mut out_of_range = false;
        for currents in [
            &sample.feed_phase_currents_a,
            &sample.spindle_phase_currents_a,
        ] {
            for i in currents {
                non_finite |= !i.is_finite();
                out_of_range |= i.abs() > self.config.max_current_a;
            }
        }
        let mut fault = None;
        if non_finite {
            fault = Some(SensorFault::NonFinite);
        } else if out_of_range {
            fault = Some(SensorFault::OutOfRange);
        }
        if let Some(previous) = self.previous_sample {
            let gap_s = sample.time_s - previous.time_s;
            if fault.is_none() && gap_s > self.config.max_gap_periods * self.sample_period_s {
                fault = Some(SensorFault::MissingSamples);
            }
            let unchanged = previous.feed_phase_currents_a == sample.feed_phase_currents_a
                && previous.spindle_phase_currents_a == sample.spindle_phase_currents_a;
            let moving = sample.feed_mm_min.abs() > 0.0 && self.triggered(sample);
            self.unchanged_s = if unchanged && moving {
                self.unchanged_s + self.sample_period_s
            } else {
                0.0
            };
            if fault.is_none()
                && self.unchanged_s >= self.config.stuck_after_s
                && self.unchanged_s > 0.0
            {
                fault = Some(SensorFault::Stuck);
            }
        }
        self.previous_sample = Some(*sample);
        self.programmed_feed_s = if sample.programmed_feed_mm_min > 0.0 {
            self.programmed_feed_s + self.sample_period_s
        } else {
            0.0
        };
        let time_s = sample.time_s;
        match (self.fault, fault) {
            (None, Some(f)) => {
                self.fault = Some(f);
                self.fault_free_s = 0.0;
                self.emit(SafetyEvent::FaultDetected { time_s, fault: f });
            }
            (Some(_), Some(_)) => self.fault_free_s = 0.0,
            (Some(_), None) => {
                self.fault_free_s += self.sample_period_s;
                if self.fault_free_s >= self.config.recover_after_s {
                    self.fault = None;
                    self.emit(SafetyEvent::FaultCleared { time_s });
                }
            }
            (None, None) => {}
        }
    }

    /// Turns a controller's request into the command the machine receives for the next control
    /// period of length `dt_s`. `force_n` is the estimated force (for the overload alarm).
    pub fn command(
        &mut self,
        request_pct: f64,
        force_n: f64,
        time_s: f64,
        dt_s: f64,
        sample: &SensorSample,
    ) -> OverrideCommand {
        let dt_s = if dt_s.is_finite() && dt_s > 0.0 {
            dt_s
        } else {
            0.0
        };

        let triggered = self.triggered(sample);
        let since_trigger_s = self.time_since_start_s(sample);
        let armed_now = triggered && since_trigger_s >= self.config.arming_delay_s;
        if armed_now && !self.armed {
            self.armed = true;
            self.emit(SafetyEvent::Armed { time_s });
        } else if !triggered {
            self.armed = false;
        }

        // Overload alarm: a latched feed hold, independent of the controller. It counts only
        // while armed: before that the estimate is dominated by the spindle's starting current
        // (paper 003), which says nothing about the load on the tool.
        if self.armed && force_n.is_finite() && force_n > self.config.overload_limit_n {
            self.overload_s += dt_s;
        } else {
            self.overload_s = 0.0;
        }
        if !self.feed_hold && self.overload_s > self.config.overload_time_s {
            self.feed_hold = true;
            self.emit(SafetyEvent::Overload { time_s, force_n });
        }

        // A non-finite request (a controller fed garbage, or diverged) holds the override, and
        // says so once per episode.
        if self.armed && self.fault.is_none() {
            let bad_request = !request_pct.is_finite();
            if bad_request && !self.controller_fault {
                self.emit(SafetyEvent::ControllerFault { time_s });
            }
            self.controller_fault = bad_request;
        }
        let c = &self.config;
        let wanted = if !self.armed {
            c.arming_override_pct
        } else {
            match (self.fault, c.fault_action) {
                (Some(_), FaultAction::Hold) => self.continuous_pct,
                (Some(_), FaultAction::Fallback(v)) => v,
                (None, _) if request_pct.is_finite() => request_pct,
                (None, _) => self.continuous_pct,
            }
        };
        // In air a controller sees no force and asks for ever more feed; entering the next cut at
        // that feed would load the tool far beyond the target before any loop could react. The
        // tool enters at the entry override, as commercial adaptive feed controls do (they do not
        // adapt in air), and — with the entry hold — stays at most there until the load has
        // settled: a controller released while the cutter is still engaging sees a force below
        // the target, raises the feed, and the full engagement then loads the tool beyond what the
        // fixed feed would.
        let watching = self.armed && self.fault.is_none() && force_n.is_finite();
        // 0 turns the rule off (a negative estimate in air is no reason to act then).
        let in_air = watching && c.air_cut_force_n > 0.0 && force_n < c.air_cut_force_n;
        let entry_override_pct = c.entry_override_pct;
        if !watching || in_air {
            self.entry_since_s = None;
        } else if self.was_in_air && c.entry_hold_s > 0.0 {
            self.entry_since_s = Some(time_s);
            self.emit(SafetyEvent::EntryHold {
                time_s,
                entry_override_pct,
            });
        } else if let Some(since_s) = self.entry_since_s {
            // The cutter is engaged after its hold; a cut already as heavy as wanted needs the
            // controller at once (it will only reduce the feed from there).
            if time_s - since_s >= c.entry_hold_s || force_n >= c.entry_release_n {
                self.entry_since_s = None;
                self.emit(SafetyEvent::EntrySettled { time_s, force_n });
            }
        }
        if watching {
            self.was_in_air = in_air;
        }
        let c = &self.config;
        // In air and through an entry's hold the override is the entry override, whatever the
        // controller asks: the controller is not in charge ([`Self::holding`]).
        self.holding = in_air || self.entry_since_s.is_some();
        let wanted = if self.holding {
            entry_override_pct
        } else {
            wanted
        };
        // The band, narrowed to the overrides that keep the feed per tooth inside the chip-load
        // window at this period's programmed feed and speed.
        let (lowest, highest) = chip_load_band_pct(
            c.chip_load.as_ref(),
            (c.min_override_pct, c.max_override_pct),
            sample.programmed_feed_mm_min,
            sample.spindle_command_rpm,
        );
        // Which end of the window holds the request, if either (for the event log).
        let window = c.chip_load.and_then(|w| {
            w.override_range_pct(sample.programmed_feed_mm_min, sample.spindle_command_rpm)
                .map(|range| (w, range))
        });
        let chip_end = match window {
            Some((_, (_, hi))) if wanted > hi && hi < c.max_override_pct => {
                Some(ChipLoadEnd::Highest)
            }
            Some((_, (lo, _))) if wanted < lo && lo > c.min_override_pct => {
                Some(ChipLoadEnd::Lowest)
            }
            _ => None,
        };
        let wanted = wanted.clamp(lowest, highest);
        let max_step = c.max_rate_pct_per_s * dt_s;
        // One event per stretch of air.
        if in_air && !self.holding_in_air {
            self.emit(SafetyEvent::AirCut {
                time_s,
                entry_override_pct,
            });
        }
        self.holding_in_air = in_air;
        self.continuous_pct += (wanted - self.continuous_pct).clamp(-max_step, max_step);
        // The window wins over the rate limit: where a block's programmed feed or speed moves
        // it, the override follows at once (the feed per tooth is the limit, not the override).
        self.continuous_pct = self.continuous_pct.clamp(lowest, highest);
        self.output_pct = self
            .config
            .resolution
            .nearest(self.continuous_pct, lowest, highest)
            .unwrap_or_else(|| self.quantize(self.continuous_pct));
        if let (Some(end), Some((w, _))) = (chip_end, window) {
            if self.chip_limited != Some(end) {
                let feed_per_tooth_mm = match end {
                    ChipLoadEnd::Highest => w.max_mm,
                    ChipLoadEnd::Lowest => w.min_mm,
                };
                let running_mm = w.feed_per_tooth_mm(
                    sample.programmed_feed_mm_min,
                    sample.spindle_command_rpm,
                    self.output_pct,
                );
                self.emit(SafetyEvent::ChipLoad {
                    time_s,
                    end,
                    feed_per_tooth_mm,
                    running_mm,
                });
            }
        }
        self.chip_limited = chip_end;
        OverrideCommand {
            override_pct: self.output_pct,
            feed_hold: self.feed_hold,
        }
    }
}
