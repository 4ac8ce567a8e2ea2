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
//! the serial line run through exactly this code. It advances in chunks ([`ClosedLoop::advance`])
//! so a browser can run it across animation frames with a progress bar and a cancel button.
//!
//! Before a loop can estimate force it needs a calibrated current-to-force model. [`teach_cut`]
//! makes one the way a shop would: it runs the machine open-loop through a schedule of fixed
//! overrides (so the load varies), summarises each control period with the same signal chain the
//! loop uses, and fits [`crate::estimation::current_force`]'s model to (current, force) pairs.
//! In simulation the force comes from the plant's truth, standing in for the dynamometer of a
//! real teach cut.

use std::fmt;

use serde::{Deserialize, Serialize};

use super::chain::{PeriodSummary, SignalChain};
use super::trace::{Trace, TraceRow};
use crate::control::law::{ControlInput, Controller};
use crate::estimation::current_force::{FeedCurrentModel, ForceEstimate, SpindleCurrentModel};
use crate::estimation::least_squares::FitError;
use crate::estimation::speed::FvSpeedModel;
use crate::machine::{Machine, OverrideCommand, SensorSample};
use crate::safety::{EnvelopeConfig, EnvelopeError, SafetyEnvelope};
use crate::signal::butterworth::{butter, ButterworthSpec, Cutoff, DesignError, FilterKind};

/// Which motor current the force is measured from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Feedback {
    /// Spindle current → mean cutting force (paper 003; independent of the feed direction).
    #[serde(alias = "spindle")]
    SpindleCurrent,
    /// Feed-drive current → feed force (paper 000).
    #[serde(alias = "feed")]
    FeedCurrent,
}

impl Feedback {
    /// Both feedback paths.
    pub const ALL: [Feedback; 2] = [Feedback::SpindleCurrent, Feedback::FeedCurrent];

    /// Name for the command line and URLs.
    pub fn name(self) -> &'static str {
        match self {
            Feedback::SpindleCurrent => "spindle",
            Feedback::FeedCurrent => "feed",
        }
    }

    /// Human label.
    pub fn label(self) -> &'static str {
        match self {
            Feedback::SpindleCurrent => "Spindle current (paper 003)",
            Feedback::FeedCurrent => "Feed-drive current (paper 000)",
        }
    }

    /// The true value of the regulated force in a period: the mean cutting-force vector's
    /// magnitude for the spindle path, the mean feed force for the feed path.
    pub fn regulated_truth_n(self, period: &PeriodSummary) -> f64 {
        match self {
            Feedback::SpindleCurrent => period.force_mean_resultant_n,
            Feedback::FeedCurrent => period.feed_force_n,
        }
    }
}

/// Settings of a closed-loop run.
#[derive(Debug, Clone, PartialEq)]
pub struct LoopSettings {
    /// Which current the force is measured from.
    pub feedback: Feedback,
    /// The controller's period.
    pub control_period_s: f64,
    /// Low-pass on the spindle phase currents (paper 003's analog filter: 260 Hz).
    pub spindle_lowpass_hz: f64,
    /// Low-pass on the feed phase currents (paper 003: 50 Hz).
    pub feed_lowpass_hz: f64,
    /// Order of both Butterworth low-passes.
    pub lowpass_order: usize,
    /// The force to hold.
    pub target_force_n: f64,
    /// The force limit for the metrics' "time above the limit".
    pub force_limit_n: f64,
    /// The safety envelope.
    pub envelope: EnvelopeConfig,
    /// The run stops here if the program has not ended.
    pub max_duration_s: f64,
    /// Relative disagreement between the current-based and the power-law estimate above which a
    /// period is flagged.
    pub cross_check_tolerance: f64,
}

/// Why a loop could not be set up.
#[derive(Debug, Clone, PartialEq)]
pub enum LoopError {
    /// A low-pass design failed.
    Filter(DesignError),
    /// The safety settings are inconsistent.
    Envelope(EnvelopeError),
    /// The teach cut did not give a usable model.
    Calibration(FitError),
    /// A setting is out of range; the text names it.
    Setting(String),
}

impl fmt::Display for LoopError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LoopError::Filter(e) => write!(f, "current filter: {e}"),
            LoopError::Envelope(e) => write!(f, "safety envelope: {e}"),
            LoopError::Calibration(e) => write!(f, "calibration (teach cut): {e}"),
            LoopError::Setting(e) => f.write_str(e),
        }
    }
}

impl std::error::Error for LoopError {}

/// A calibrated current-to-force estimator.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "feedback", rename_all = "kebab-case")]
pub enum Estimator {
    /// Paper 003's spindle model with F/V speed identification.
    Spindle {
        /// Current → force per speed.
        model: SpindleCurrentModel,
        /// F/V voltage → speed.
        speed: FvSpeedModel,
    },
    /// Paper 000's feed-drive model.
    Feed {
        /// Current and feed speed → feed force.
        model: FeedCurrentModel,
    },
}

impl Estimator {
    /// The force estimate for a period.
    pub fn estimate(&self, period: &PeriodSummary) -> ForceEstimate {
        match self {
            Estimator::Spindle { model, speed } => {
                let rpm = speed.speed_rpm(period.spindle_fv_voltage_v, period.spindle_command_rpm);
                model.estimate(period.spindle_current_rms_a, rpm)
            }
            Estimator::Feed { model } => {
                model.estimate(period.feed_current_rms_a, period.feed_mm_min)
            }
        }
    }

    /// The current the model expects for `force_n` (to express a current target as a force).
    pub fn force_for_current_n(&self, current_a: f64, spindle_rpm: f64, feed_mm_min: f64) -> f64 {
        match self {
            Estimator::Spindle { model, .. } => {
                let (idle, sensitivity, _) = model.line_at(spindle_rpm);
                (current_a - idle) / sensitivity
            }
            Estimator::Feed { model } => {
                (current_a - model.idle_current_a(feed_mm_min)) / model.sensitivity_a_per_n
            }
        }
    }
}

/// What a teach cut produced.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Calibration {
    /// The fitted estimator.
    pub estimator: Estimator,
    /// Median regulated force over the cutting periods of the teach cut at 100 % override.
    pub median_force_at_full_override_n: f64,
    /// Median of regulated force ÷ mean resultant force over those periods: converts a
    /// resultant-force target into the regulated force (1 for spindle feedback).
    pub regulated_per_resultant: f64,
    /// Periods used for the fit.
    pub periods: usize,
    /// The largest phase current (feed or spindle, raw) seen during the teach cut.
    pub max_phase_current_a: f64,
}

/// The overrides a teach cut cycles through, each held for [`TEACH_STEP_S`]: a spread of loads
/// from one pass over the part.
pub const TEACH_OVERRIDES_PCT: [f64; 4] = [100.0, 30.0, 140.0, 60.0];
/// How long each teach-cut override is held.
pub const TEACH_STEP_S: f64 = 1.5;
/// Teach-cut samples this soon after a spindle start are skipped: the starting current says
/// nothing about the load.
const TEACH_SETTLE_S: f64 = 1.0;
/// Teach-cut periods this soon after an override change are skipped: the feed and the currents
/// are still moving to the new level.
const TEACH_SETTLE_AFTER_CHANGE_S: f64 = 0.5;

fn lowpass(
    cutoff_hz: f64,
    order: usize,
    sample_rate_hz: f64,
) -> Result<crate::signal::sos::Sos, LoopError> {
    butter(&ButterworthSpec {
        kind: FilterKind::Lowpass,
        order,
        cutoff_hz: Cutoff::Single(cutoff_hz),
        sample_rate_hz,
    })
    .map_err(LoopError::Filter)
}

fn chain_for(settings: &LoopSettings, sample_rate_hz: f64) -> Result<SignalChain, LoopError> {
    let spindle = lowpass(
        settings.spindle_lowpass_hz,
        settings.lowpass_order,
        sample_rate_hz,
    )?;
    let feed = lowpass(
        settings.feed_lowpass_hz,
        settings.lowpass_order,
        sample_rate_hz,
    )?;
    SignalChain::new(&spindle, &feed).map_err(|e| LoopError::Setting(e.to_string()))
}

fn samples_per_period(settings: &LoopSettings, sample_rate_hz: f64) -> Result<usize, LoopError> {
    let n = (settings.control_period_s * sample_rate_hz).round();
    if !(1.0..=1e7).contains(&n) {
        return Err(LoopError::Setting(format!(
            "control period {} s must be at least one sample and at most 10⁷ samples",
            settings.control_period_s
        )));
    }
    Ok(n as usize)
}

/// The (current, force, …) pairs a teach cut collects, one per usable control period.
#[derive(Debug, Clone, Default)]
struct TeachSamples {
    current_a: Vec<f64>,
    force_n: Vec<f64>,
    speed_rpm: Vec<f64>,
    command_rpm: Vec<f64>,
    fv_voltage_v: Vec<f64>,
    feed_mm_min: Vec<f64>,
    full_override_forces_n: Vec<f64>,
    full_override_ratios: Vec<f64>,
    max_phase_current_a: f64,
}

/// A teach cut in progress: the machine open-loop through the teach-cut override schedule, one
/// control period per step, so a browser can run it across frames.
pub struct TeachCut {
    machine: Box<dyn Machine>,
    feedback: Feedback,
    max_duration_s: f64,
    chain: SignalChain,
    samples_per_period: usize,
    samples: TeachSamples,
    time_s: f64,
}

impl TeachCut {
    /// A teach cut of `machine` with the signal chain and feedback path of `settings`.
    pub fn new(machine: Box<dyn Machine>, settings: &LoopSettings) -> Result<Self, LoopError> {
        let rate = machine.sample_rate_hz();
        Ok(Self {
            chain: chain_for(settings, rate)?,
            samples_per_period: samples_per_period(settings, rate)?,
            feedback: settings.feedback,
            max_duration_s: settings.max_duration_s,
            machine,
            samples: TeachSamples::default(),
            time_s: 0.0,
        })
    }

    /// Machine time so far.
    pub fn elapsed_s(&self) -> f64 {
        self.time_s
    }

    /// Whether the program (or the time limit) has ended.
    pub fn finished(&self) -> bool {
        self.machine.finished() || self.time_s >= self.max_duration_s
    }

    /// Runs at most `periods` control periods; returns true once the teach cut has ended.
    pub fn advance(&mut self, periods: usize) -> bool {
        for _ in 0..periods {
            if self.finished() {
                break;
            }
            self.period();
        }
        self.finished()
    }

    fn period(&mut self) {
        let step_index = (self.time_s / TEACH_STEP_S) as usize % TEACH_OVERRIDES_PCT.len();
        let command_pct = TEACH_OVERRIDES_PCT[step_index];
        let samples = &mut self.samples;
        let mut last = SensorSample::default();
        for _ in 0..self.samples_per_period {
            let step = self.machine.step(OverrideCommand {
                override_pct: command_pct,
                feed_hold: false,
            });
            self.chain.push(&step);
            last = step.sensors;
            for i in last
                .feed_phase_currents_a
                .iter()
                .chain(&last.spindle_phase_currents_a)
            {
                if i.is_finite() {
                    samples.max_phase_current_a = samples.max_phase_current_a.max(i.abs());
                }
            }
        }
        let period = self.chain.finish_period();
        // A machine that produced no sample (already finished) ends the teach cut.
        self.time_s = if period.samples == 0 {
            self.max_duration_s
        } else {
            period.end_time_s
        };
        let spindle_settled =
            last.time_since_spindle_start_s >= TEACH_SETTLE_S || !last.spindle_running;
        // The drives need a moment after each override change (the spindle's bandwidth is below
        // 5 Hz), and air cuts are left out: the line is fitted where it is used, in the cut.
        let since_change_s = self.time_s % TEACH_STEP_S;
        let truth = self.feedback.regulated_truth_n(&period);
        if !spindle_settled
            || since_change_s < TEACH_SETTLE_AFTER_CHANGE_S
            || !(truth.is_finite() && truth > 0.0)
            || period.feed_mm_min.abs() < 1e-6
        {
            return;
        }
        if command_pct == 100.0 {
            samples.full_override_forces_n.push(truth);
            let ratio = truth / period.force_mean_resultant_n;
            if ratio.is_finite() {
                samples.full_override_ratios.push(ratio);
            }
        }
        samples.current_a.push(match self.feedback {
            Feedback::SpindleCurrent => period.spindle_current_rms_a,
            Feedback::FeedCurrent => period.feed_current_rms_a,
        });
        samples.force_n.push(truth);
        samples.speed_rpm.push(period.spindle_speed_rpm);
        samples.command_rpm.push(period.spindle_command_rpm);
        samples.fv_voltage_v.push(period.spindle_fv_voltage_v);
        samples.feed_mm_min.push(period.feed_mm_min);
    }

    /// Fits the estimator to what was collected.
    pub fn calibration(&self) -> Result<Calibration, LoopError> {
        let s = &self.samples;
        let estimator =
            match self.feedback {
                Feedback::SpindleCurrent => {
                    let speed_model = FvSpeedModel::calibrate(
                        &s.command_rpm,
                        &s.speed_rpm,
                        &s.fv_voltage_v,
                        GEAR_CHANGE_RPM,
                    );
                    let identified: Vec<f64> = s
                        .fv_voltage_v
                        .iter()
                        .zip(&s.command_rpm)
                        .map(|(v, c)| speed_model.speed_rpm(*v, *c))
                        .collect();
                    Estimator::Spindle {
                        model: SpindleCurrentModel::calibrate(
                            &s.current_a,
                            &identified,
                            &s.force_n,
                            GEAR_CHANGE_RPM,
                        )
                        .map_err(LoopError::Calibration)?,
                        speed: speed_model,
                    }
                }
                Feedback::FeedCurrent if s.force_n.is_empty() => return Err(LoopError::Setting(
                    "feed-current feedback needs a cut that loads the feed drive, and this one \
                     never pushed back against the feed (in down milling the cutting force pulls \
                     the table along); measure the force through the spindle current"
                        .into(),
                )),
                Feedback::FeedCurrent => Estimator::Feed {
                    model: FeedCurrentModel::calibrate(&s.current_a, &s.feed_mm_min, &s.force_n)
                        .map_err(LoopError::Calibration)?,
                },
            };
        let median = |values: &[f64]| {
            let mut sorted = values.to_vec();
            sorted.sort_by(f64::total_cmp);
            sorted.get(sorted.len() / 2).copied().unwrap_or(f64::NAN)
        };
        Ok(Calibration {
            estimator,
            median_force_at_full_override_n: median(&s.full_override_forces_n),
            regulated_per_resultant: median(&s.full_override_ratios),
            periods: s.force_n.len(),
            max_phase_current_a: s.max_phase_current_a,
        })
    }
}

/// Runs a whole teach cut of `machine` and fits the estimator for `settings.feedback`.
pub fn teach_cut(
    machine: Box<dyn Machine>,
    settings: &LoopSettings,
) -> Result<Calibration, LoopError> {
    let mut teach = TeachCut::new(machine, settings)?;
    while !teach.advance(1000) {}
    teach.calibration()
}

/// The spindle gear change of paper 003's machining centre.
pub const GEAR_CHANGE_RPM: f64 = 900.0;

/// A running closed loop.
pub struct ClosedLoop {
    machine: Box<dyn Machine>,
    controller: Box<dyn Controller>,
    estimator: Estimator,
    settings: LoopSettings,
    chain: SignalChain,
    envelope: SafetyEnvelope,
    samples_per_period: usize,
    command: OverrideCommand,
    last_request_pct: f64,
    trace: Trace,
    done: bool,
}

impl ClosedLoop {
    /// Wires `machine`, `controller` and `estimator` with `settings`.
    pub fn new(
        machine: Box<dyn Machine>,
        controller: Box<dyn Controller>,
        estimator: Estimator,
        settings: LoopSettings,
    ) -> Result<Self, LoopError> {
        if !(settings.target_force_n.is_finite() && settings.target_force_n > 0.0) {
            return Err(LoopError::Setting(format!(
                "target force must be positive, not {} N",
                settings.target_force_n
            )));
        }
        if !(settings.max_duration_s.is_finite() && settings.max_duration_s > 0.0) {
            return Err(LoopError::Setting(
                "the run's time limit must be positive".into(),
            ));
        }
        let rate = machine.sample_rate_hz();
        let chain = chain_for(&settings, rate)?;
        let samples_per_period = samples_per_period(&settings, rate)?;
        let envelope =
            SafetyEnvelope::new(settings.envelope.clone(), rate).map_err(LoopError::Envelope)?;
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
            machine,
            controller,
            estimator,
            chain,
            envelope,
            samples_per_period,
            command,
            last_request_pct: command.override_pct,
            trace: Trace {
                rows: Vec::with_capacity(capacity),
                term_names,
                ..Trace::default()
            },
            settings,
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

    /// The trace, ending the loop.
    pub fn into_trace(self) -> Trace {
        self.trace
    }

    /// Whether the run has ended (program finished, time limit, or feed hold with the axes at
    /// rest).
    pub fn finished(&self) -> bool {
        self.done
    }

    /// Progress as a fraction of the time limit (the program usually ends before it).
    pub fn elapsed_s(&self) -> f64 {
        self.trace.rows.last().map_or(0.0, |r| r.time_s)
    }

    /// Runs at most `periods` control periods; returns true once the run has ended.
    pub fn advance(&mut self, periods: usize) -> bool {
        for _ in 0..periods {
            if self.done {
                break;
            }
            self.period();
        }
        self.done
    }

    /// Runs to the end.
    pub fn run(mut self) -> Trace {
        while !self.advance(1000) {}
        self.trace
    }

    fn period(&mut self) {
        let mut last = SensorSample::default();
        let mut sensorless_n = f64::NAN;
        for _ in 0..self.samples_per_period {
            let step = self.machine.step(self.command);
            self.envelope.observe(&step.sensors);
            self.chain.push(&step);
            last = step.sensors;
        }
        if let Some(f) = self.machine.sensorless_force_n() {
            sensorless_n = f;
        }
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
        // The controller runs only while armed: before that its output would be ignored, and an
        // integrating law must not accumulate the spindle's starting transient.
        if armed {
            self.last_request_pct = self.controller.step(&input);
        }
        self.command = self.envelope.command(
            self.last_request_pct,
            estimate.force_n,
            period.end_time_s,
            dt_s,
            &last,
        );
        if !self.envelope.armed() {
            self.last_request_pct = self.command.override_pct;
        }
        self.envelope.drain_events(&mut self.trace.events);
        for t in self.controller.terms() {
            self.trace.terms.push(t.value);
        }
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
            armed,
            sensor_fault: self.envelope.fault().is_some(),
            feed_hold: self.command.feed_hold,
            estimate_in_range: estimate.in_range,
            cross_check_disagrees: disagrees(
                estimate.force_n,
                sensorless_n,
                self.settings.cross_check_tolerance,
                self.settings.target_force_n,
            ),
        });
        let held_at_rest = self.command.feed_hold && period.feed_mm_min.abs() < 1e-9;
        if self.machine.finished() || held_at_rest {
            self.trace.completed = self.machine.finished();
            self.done = true;
        } else if period.end_time_s >= self.settings.max_duration_s || period.samples == 0 {
            self.done = true;
        }
    }
}

/// Whether two estimates differ by more than `tolerance` of the larger of them and the target
/// (so two near-zero estimates in air never disagree).
fn disagrees(current_based_n: f64, sensorless_n: f64, tolerance: f64, target_n: f64) -> bool {
    if !(current_based_n.is_finite() && sensorless_n.is_finite()) {
        return false;
    }
    let scale = current_based_n
        .abs()
        .max(sensorless_n.abs())
        .max(target_n * 0.25);
    (current_based_n - sensorless_n).abs() > tolerance * scale
}
