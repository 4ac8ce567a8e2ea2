//! The closed loop: one code path for every machine.
//!
//! ```text
//! Machine::step ─► SafetyEnvelope::observe ─► SignalChain::push        (every sensor sample)
//!   every control period:
//!   SignalChain::finish_period ─► Estimator ─► Controller::step ─► SafetyEnvelope::command
//!   ─► OverrideCommand for the next period, and one TraceRow
//! ```
//!
//! [`ClosedLoop`] owns a `Box<dyn Machine>`, so the simulated mill, a replayed log and a machine on
//! the serial line run through exactly this code. It advances in chunks
//! ([`crate::work::Work::advance`]) so a browser can run it across animation frames with a
//! progress bar and a cancel button. Its settings come resolved ([`super::settings`]); its
//! estimator from a teach cut ([`super::teach_cut`]) or a saved calibration.

use super::error::LoopError;
use super::sample_loop::{signal_chain, LoopSample, OnMachine, PeriodClock, SampleLoop};
use super::settings::{LoopSettings, OperatingPoint};
use super::trace::{Trace, TraceRow};
use crate::control::law::{ControlInput, Controller};
use crate::control::registry::{ControllerConfig, RunContext};
use crate::estimation::current_force::ForceEstimate;
use crate::estimation::estimator::{Calibration, Estimator, Feedback};
use crate::machine::{Machine, OverrideCommand, SensorSample, SensorlessEstimate};
use crate::plant::deflection::normal_force_n;
use crate::safety::{SafetyEnvelope, SafetyEvent};
use crate::signal::chain::{PeriodSummary, SignalChain};
use crate::work::Work;

/// The closed loop on a machine.
pub type ClosedLoop = OnMachine<FeedbackLoop>;

/// The closed loop without a machine: sensor samples in, override commands out.
///
/// Every sample passes the safety envelope's observation (stuck or implausible currents, the
/// arming clock) and the signal chain; at each control period's end the estimator turns the
/// period's current into a force, the controller asks for an override, the envelope limits it,
/// and one [`TraceRow`] is recorded. Nothing allocates per sample beyond the trace's reserve.
pub struct FeedbackLoop {
    controller: Box<dyn Controller>,
    estimator: Estimator,
    settings: LoopSettings,
    chain: SignalChain,
    envelope: SafetyEnvelope,
    clock: PeriodClock,
    last: SensorSample,
    /// The power-law estimate at the latest sample that carried one.
    last_sensorless: SensorlessEstimate,
    command: OverrideCommand,
    last_request_pct: f64,
    trace: Trace,
    /// Whether the cut-before-arming warning was given (once a run).
    warned_cut_before_arming: bool,
    /// The force estimate of the period before.
    previous_estimate_n: f64,
    /// Whether the controller was stepped at the last period.
    controller_in_charge: bool,
    /// How long the estimates have disagreed: paper 004's sensor failure prediction.
    failure_watch: FailureWatch,
    /// The tool-path offset the current-based compensation commands for this period, from the
    /// last period's estimate, µm (NaN where the feedback path does not estimate the resultant).
    current_compensation_um: f64,
    done: bool,
}

/// A period's force-induced wall error, µm, and what paper 004's compensator leaves of it when it
/// offsets the tool path by the error it predicts. The offsets are not fed back into the cut:
/// they are micrometres against millimetres of width of cut, a few percent of the engagement at
/// most, so the loop's force is the uncompensated run's.
struct SurfaceErrors {
    /// The error without compensation (0 in air).
    surface_um: f64,
    /// After an offset predicted from the power law of what the CNC knows of this period's cut
    /// (paper 004's sensorless compensation; fed forward, as the program is known ahead).
    after_power_law_um: f64,
    /// After an offset predicted from the last period's current-based estimate (one control
    /// period late, as a measurement is).
    after_current_um: f64,
}

impl SurfaceErrors {
    const UNKNOWN: SurfaceErrors = SurfaceErrors {
        surface_um: f64::NAN,
        after_power_law_um: f64::NAN,
        after_current_um: f64::NAN,
    };
}

/// How long the current-based and the sensorless estimates must disagree before a sensor failure
/// is predicted, s. At a step of the cut the sensorless estimate, which reads the program,
/// changes at once, while the current-based one follows the spindle's current through its lag
/// (< 5 Hz) and the signal chain's filters: a period or two apart at each depth step of
/// kim-step-doc (tests/sensor_failure.rs). A sensor that has failed stays apart.
pub const SENSOR_FAILURE_PERSISTENCE_S: f64 = 0.25;

/// Paper 004's sensor failure prediction over time: a failure is predicted once the estimates
/// have disagreed ([`estimates_disagree`]) for [`SENSOR_FAILURE_PERSISTENCE_S`], and for as
/// long as they go on disagreeing.
#[derive(Debug, Clone, Copy, Default)]
struct FailureWatch {
    /// When the current disagreement began (the start of its first period).
    since_s: Option<f64>,
}

impl FailureWatch {
    /// Whether the period of `dt_s` ending at `end_s`, whose estimates `disagree` or not,
    /// predicts a sensor failure.
    fn predicts(&mut self, disagree: bool, end_s: f64, dt_s: f64) -> bool {
        if !disagree {
            self.since_s = None;
            return false;
        }
        let since_s = *self.since_s.get_or_insert(end_s - dt_s);
        // A hair under the persistence: sums of periods are not exact.
        end_s - since_s >= SENSOR_FAILURE_PERSISTENCE_S - 1e-9
    }
}

/// The spindle is at speed within this fraction of its command (its run-up current would read as
/// a force).
const AT_SPEED_FRACTION: f64 = 0.02;

impl FeedbackLoop {
    /// The closed loop of `controller` with `settings` and `calibration`'s estimator, for samples
    /// at `sample_rate_hz`: the controller built for the target and the period, with the current
    /// sensitivity of the calibrated line where the program runs (`at`).
    pub fn wire(
        controller: &ControllerConfig,
        settings: LoopSettings,
        calibration: &Calibration,
        at: OperatingPoint,
        sample_rate_hz: f64,
    ) -> Result<Self, LoopError> {
        let built = controller_for(controller, &settings, calibration, at)?;
        Self::new(
            sample_rate_hz,
            built,
            calibration.estimator.clone(),
            settings,
        )
    }

    /// Wires `controller` and `estimator` with `settings` for samples at `sample_rate_hz`.
    pub fn new(
        sample_rate_hz: f64,
        controller: Box<dyn Controller>,
        estimator: Estimator,
        settings: LoopSettings,
    ) -> Result<Self, LoopError> {
        if !(settings.max_duration_s.is_finite() && settings.max_duration_s > 0.0) {
            return Err(LoopError::TimeLimit(settings.max_duration_s));
        }
        let chain = signal_chain(&settings.chain(), sample_rate_hz)?;
        let clock = PeriodClock::new(&settings.chain(), sample_rate_hz)?;
        let envelope = SafetyEnvelope::new(settings.envelope.clone(), sample_rate_hz)
            .map_err(LoopError::Envelope)?;
        let command = OverrideCommand {
            override_pct: envelope.output_pct(),
            feed_hold: false,
        };
        let capacity = (settings.max_duration_s / settings.control_period_s).min(1e6) as usize + 1;
        let term_names = controller
            .terms()
            .iter()
            .map(|t| (t.name, t.unit))
            .collect();
        Ok(Self {
            controller,
            estimator,
            chain,
            envelope,
            clock,
            last: SensorSample::default(),
            last_sensorless: NO_SENSORLESS_ESTIMATE,
            command,
            last_request_pct: command.override_pct,
            trace: Trace {
                rows: Vec::with_capacity(capacity),
                term_names,
                ..Trace::default()
            },
            settings,
            warned_cut_before_arming: false,
            previous_estimate_n: f64::NAN,
            current_compensation_um: 0.0,
            controller_in_charge: false,
            failure_watch: FailureWatch::default(),
            done: false,
        })
    }

    /// The settings.
    pub fn settings(&self) -> &LoopSettings {
        &self.settings
    }

    /// The trace so far.
    pub fn trace(&self) -> &Trace {
        &self.trace
    }

    /// Warns once when the estimate shows a cut before the loop has armed: above
    /// [`LoopSettings::cut_before_arming_force_n`], which the estimate's noise in air stays below.
    fn watch_cut_before_arming(
        &mut self,
        period: &PeriodSummary,
        estimate: &ForceEstimate,
        armed: bool,
    ) {
        let force_n = estimate.force_n;
        let at_speed = period.spindle_command_rpm > 0.0
            && (period.spindle_speed_rpm - period.spindle_command_rpm).abs()
                <= AT_SPEED_FRACTION * period.spindle_command_rpm;
        // After its run-up the spindle's current decays for a few periods and reads as a falling
        // force; a cut's force rises or holds. (A run-up also reads far outside the calibrated
        // range, which `in_range` rejects.)
        let falling = force_n < 0.9 * self.previous_estimate_n;
        self.previous_estimate_n = force_n;
        if !armed
            && !self.warned_cut_before_arming
            && at_speed
            && !falling
            && estimate.in_range
            && force_n > self.settings.cut_before_arming_force_n
        {
            self.warned_cut_before_arming = true;
            self.trace.events.push(SafetyEvent::CutBeforeArming {
                time_s: period.end_time_s,
                force_n,
            });
        }
    }

    /// The period's force-induced wall error and what paper 004's compensator leaves of it
    /// ([`SurfaceErrors`]); sets the offset the current-based compensation commands for the next
    /// period.
    fn surface_errors(
        &mut self,
        period: &PeriodSummary,
        sensorless_n: f64,
        estimate_n: f64,
        armed: bool,
    ) -> SurfaceErrors {
        let Some(model) = self.settings.error_model else {
            return SurfaceErrors::UNKNOWN;
        };
        let surface_um = if period.depth_mm > 0.0 {
            model.stiffness.surface_error_um(normal_force_n(
                period.force_mean_resultant_n,
                period.feed_force_n,
            ))
        } else {
            0.0
        };
        let current_offset_um = self.current_compensation_um;
        // The next period's offset, from this one's estimate: only an estimate of the in-plane
        // resultant says how hard the tool is pushed off the wall (the feed path estimates the
        // feed force), and only once armed (before, the spindle's run-up current reads as force).
        let resultant_estimated = matches!(
            self.settings.feedback,
            Feedback::SpindleCurrent | Feedback::Dynamometer
        );
        self.current_compensation_um = if !resultant_estimated {
            f64::NAN
        } else if armed && estimate_n.is_finite() {
            model.predicted_error_um(estimate_n.max(0.0))
        } else {
            0.0
        };
        SurfaceErrors {
            surface_um,
            after_power_law_um: surface_um - model.predicted_error_um(sensorless_n),
            after_current_um: surface_um - current_offset_um,
        }
    }

    /// Ends a control period: estimate, control, limit, record.
    fn end_period(&mut self, sensorless: SensorlessEstimate) {
        let sensorless_n = sensorless.force_n;
        let last = self.last;
        let period = self.chain.finish_period();
        let estimate = self.estimator.estimate(&period);
        let dt_s = self.settings.control_period_s;
        let input = ControlInput {
            time_s: period.end_time_s,
            dt_s,
            force_n: estimate.force_n,
            target_force_n: self.settings.target_force_n,
            programmed_feed_mm_min: last.programmed_feed_mm_min,
            applied_override_pct: last.applied_override_pct,
            time_since_start_s: self.envelope.time_since_start_s(&last),
        };
        let armed = self.envelope.armed();
        self.watch_cut_before_arming(&period, &estimate, armed);
        // The controller runs only while it is in charge: armed, and the envelope not holding the
        // entry override (the tool in air, an entry's hold). Otherwise its output would be
        // ignored, and an integrating law must not accumulate what it cannot change (the
        // spindle's starting transient, the missing force in air). When it takes charge it starts
        // from the override the machine runs at.
        let in_charge = armed && !self.envelope.holding();
        if in_charge {
            if !self.controller_in_charge {
                self.controller.take_over(last.applied_override_pct);
            }
            self.last_request_pct = self.controller.step(&input);
        }
        self.controller_in_charge = in_charge;
        self.command = self.envelope.command(
            self.last_request_pct,
            estimate.force_n,
            period.end_time_s,
            dt_s,
            &last,
        );
        if !self.envelope.armed() || self.envelope.holding() {
            self.last_request_pct = self.command.override_pct;
        }
        self.envelope.drain_events(&mut self.trace.events);
        for t in self.controller.terms() {
            self.trace.terms.push(t.value);
        }
        let errors = self.surface_errors(&period, sensorless_n, estimate.force_n, armed);
        // Only once armed: before, the spindle's run-up current reads as a force.
        let disagree = armed
            && estimates_disagree(
                estimate.force_n,
                sensorless_n,
                self.settings.sensor_failure_tolerance + sensorless.relative_uncertainty,
                self.settings.target_force_n,
            );
        let sensor_failure_predicted =
            self.failure_watch
                .predicts(disagree, period.end_time_s, dt_s);
        self.trace.rows.push(TraceRow {
            time_s: period.end_time_s,
            depth_mm: period.depth_mm,
            width_mm: period.width_mm,
            path_position_mm: period.path_position_mm,
            programmed_feed_mm_min: last.programmed_feed_mm_min,
            feed_mm_min: period.feed_mm_min,
            requested_override_pct: self.last_request_pct,
            override_pct: self.command.override_pct,
            applied_override_pct: last.applied_override_pct,
            force_n: self.settings.feedback.regulated_truth_n(&period),
            force_est_n: estimate.force_n,
            force_power_law_n: sensorless_n,
            target_force_n: self.settings.target_force_n,
            force_min_n: period.force_min_max_n.0,
            force_max_n: period.force_min_max_n.1,
            spindle_current_rms_a: period.spindle_current_rms_a,
            feed_current_rms_a: period.feed_current_rms_a,
            feed_current_u_min_a: period.feed_current_u_min_max_a.0,
            feed_current_u_max_a: period.feed_current_u_min_max_a.1,
            spindle_speed_rpm: period.spindle_speed_rpm,
            material_removal_mm3_s: period.material_removal_mm3_s,
            surface_error_um: errors.surface_um,
            compensated_error_power_law_um: errors.after_power_law_um,
            compensated_error_current_um: errors.after_current_um,
            armed,
            sensor_fault: self.envelope.fault().is_some(),
            feed_hold: self.command.feed_hold,
            estimate_in_range: estimate.in_range,
            sensor_failure_predicted,
        });
        let held_at_rest = self.command.feed_hold && period.feed_mm_min.abs() < 1e-9;
        if held_at_rest || period.end_time_s >= self.settings.max_duration_s {
            self.done = true;
        }
    }
}

impl SampleLoop for FeedbackLoop {
    type Output = Trace;

    #[inline(always)]
    fn push(&mut self, sample: &LoopSample<'_>) -> Option<OverrideCommand> {
        if self.done {
            return None;
        }
        self.envelope.observe(&sample.step.sensors);
        self.chain.push(sample.step);
        if let Some(d) = &sample.dynamometer {
            self.chain.push_dynamometer(d);
        }
        self.last = sample.step.sensors;
        self.last_sensorless = sample.sensorless.unwrap_or(NO_SENSORLESS_ESTIMATE);
        if !self.clock.tick() {
            return None;
        }
        self.end_period(self.last_sensorless);
        Some(self.command)
    }

    fn command(&self) -> OverrideCommand {
        self.command
    }

    fn clock(&self) -> &PeriodClock {
        &self.clock
    }

    fn end_of_program(&mut self) {
        if self.clock.cut_short() > 0 && !self.done {
            self.end_period(self.last_sensorless);
        }
        self.trace.completed = true;
        self.done = true;
    }

    fn finished(&self) -> bool {
        self.done
    }

    fn elapsed_s(&self) -> f64 {
        self.trace.rows.last().map_or(0.0, |r| r.time_s)
    }

    fn stage(&self) -> &'static str {
        "closed loop"
    }

    fn finish(&mut self) -> Result<Trace, LoopError> {
        Ok(std::mem::take(&mut self.trace))
    }
}

impl OnMachine<FeedbackLoop> {
    /// Wires `machine`, `controller` and `estimator` with `settings`.
    pub fn new(
        machine: Box<dyn Machine>,
        controller: Box<dyn Controller>,
        estimator: Estimator,
        settings: LoopSettings,
    ) -> Result<Self, LoopError> {
        let feedback_loop =
            FeedbackLoop::new(machine.sample_rate_hz(), controller, estimator, settings)?;
        Ok(Self::new_with(machine, feedback_loop))
    }

    /// The settings.
    pub fn settings(&self) -> &LoopSettings {
        self.sample_loop.settings()
    }

    /// The trace so far.
    pub fn trace(&self) -> &Trace {
        self.sample_loop.trace()
    }

    /// The trace, ending the loop.
    pub fn into_trace(mut self) -> Trace {
        std::mem::take(&mut self.sample_loop.trace)
    }

    /// Runs to the end.
    pub fn run(self) -> Trace {
        self.run_to_end().unwrap_or_default()
    }
}

/// What a period without a sensorless estimate records.
const NO_SENSORLESS_ESTIMATE: SensorlessEstimate = SensorlessEstimate {
    force_n: f64::NAN,
    relative_uncertainty: 0.0,
};

/// Paper 004's sensor failure prediction for a period: whether the current-based estimate and
/// the sensorless one (the network learned on the machine's trial cuts, from what the CNC knows
/// of the cut: [`crate::plant::sensorless`]) differ by more than `tolerance` of the larger of
/// them and a quarter of the target (so two near-zero estimates in air never disagree); no
/// verdict (false) without two finite estimates. The loop's tolerance is
/// [`super::settings::SENSOR_FAILURE_TOLERANCE`] widened by the network's uncertainty at the cut.
///
/// ```
/// use cutlab::closed_loop::feedback_loop::estimates_disagree;
/// assert!(!estimates_disagree(100.0, 130.0, 0.3, 100.0));
/// assert!(estimates_disagree(100.0, 150.0, 0.3, 100.0));
/// ```
pub fn estimates_disagree(
    current_based_n: f64,
    sensorless_n: f64,
    tolerance: f64,
    target_n: f64,
) -> bool {
    if !(current_based_n.is_finite() && sensorless_n.is_finite()) {
        return false;
    }
    let scale = current_based_n
        .abs()
        .max(sensorless_n.abs())
        .max(target_n * 0.25);
    (current_based_n - sensorless_n).abs() > tolerance * scale
}

/// `controller` built for a loop with `settings` and `calibration` at `at`: what
/// [`FeedbackLoop::wire`] runs, and what tells a trace received from elsewhere (a worker) its
/// controller's term names.
pub fn controller_for(
    controller: &ControllerConfig,
    settings: &LoopSettings,
    calibration: &Calibration,
    at: OperatingPoint,
) -> Result<Box<dyn Controller>, LoopError> {
    // A program without a spindle speed reads the line at rest.
    let rpm = if at.spindle_rpm.is_finite() {
        at.spindle_rpm
    } else {
        0.0
    };
    controller
        .build(&RunContext {
            target_force_n: settings.target_force_n,
            control_period_s: settings.control_period_s,
            amps_per_newton: calibration.estimator.sensitivity_a_per_n(rpm),
        })
        .map_err(LoopError::Controller)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_prediction_widens_with_the_networks_uncertainty_but_still_sees_a_real_gap() {
        // ±30 % at the calibration cut.
        assert!(!estimates_disagree(100.0, 130.0, 0.3, 100.0));
        assert!(estimates_disagree(100.0, 150.0, 0.3, 100.0));
        // Half the calibrated feed per tooth adds 0.25·ln 2 ≈ 0.17: 50 % apart is then within it.
        let tolerance = 0.3 + 0.25 * 2f64.ln();
        assert!(!estimates_disagree(100.0, 150.0, tolerance, 100.0));
        // A force two and a half times the estimate is still a disagreement.
        assert!(estimates_disagree(100.0, 250.0, tolerance, 100.0));
        // No sensorless estimate, no verdict.
        assert!(!estimates_disagree(100.0, f64::NAN, tolerance, 100.0));
    }

    #[test]
    fn a_failure_is_predicted_only_once_the_estimates_have_disagreed_for_the_persistence() {
        let dt_s = 0.06;
        let mut watch = FailureWatch::default();
        // A depth step: two periods apart, then together again.
        let step = [true, true, false];
        let mut t = 0.0;
        for disagree in step {
            t += dt_s;
            assert!(!watch.predicts(disagree, t, dt_s));
        }
        // A failed sensor: apart from now on, predicted from the period that completes 0.25 s.
        let mut predicted_at = None;
        for _ in 0..10 {
            t += dt_s;
            if watch.predicts(true, t, dt_s) && predicted_at.is_none() {
                predicted_at = Some(t);
            }
        }
        let apart_from = 3.0 * dt_s;
        let delay = predicted_at.unwrap() - apart_from;
        assert!(
            (SENSOR_FAILURE_PERSISTENCE_S..SENSOR_FAILURE_PERSISTENCE_S + dt_s).contains(&delay)
        );
        // Together again: no longer predicted.
        assert!(!watch.predicts(false, t + dt_s, dt_s));
    }
}
