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
use super::definition::SettingError;
use super::trace::{Trace, TraceRow};
use crate::control::law::{ControlInput, Controller};
use crate::control::registry::ParamError;
use crate::estimation::current_force::{FeedCurrentModel, ForceEstimate, SpindleCurrentModel};
use crate::estimation::cut_forces::CutGeometry;
use crate::estimation::least_squares::FitError;
use crate::estimation::speed::FvSpeedModel;
use crate::machine::{
    BlockStep, DynamometerReading, Machine, MachineStep, OverrideCommand, SensorSample,
    SensorlessEstimate,
};
use crate::plant::PlantError;
use crate::safety::{EnvelopeConfig, EnvelopeError, SafetyEnvelope, SafetyEvent};
use crate::signal::butterworth::{butter, ButterworthSpec, Cutoff, DesignError, FilterKind};
use crate::work::{Progress, Work};

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
    /// A dynamometer under the part reads the mean cutting force itself (paper 001's
    /// experiments): no current, no model, but a sensor few machines carry.
    Dynamometer,
}

impl Feedback {
    /// Both feedback paths.
    pub const ALL: [Feedback; 3] = [
        Feedback::SpindleCurrent,
        Feedback::FeedCurrent,
        Feedback::Dynamometer,
    ];

    /// Name for the command line and URLs.
    pub fn name(self) -> &'static str {
        match self {
            Feedback::SpindleCurrent => "spindle",
            Feedback::FeedCurrent => "feed",
            Feedback::Dynamometer => "dynamometer",
        }
    }

    /// Human label.
    pub fn label(self) -> &'static str {
        match self {
            Feedback::SpindleCurrent => "Spindle current (paper 003)",
            Feedback::FeedCurrent => "Feed-drive current (paper 000)",
            Feedback::Dynamometer => "Dynamometer (paper 001)",
        }
    }

    /// The true value of the regulated force in a period: the mean cutting-force vector's
    /// magnitude for the spindle path, the mean feed force for the feed path.
    pub fn regulated_truth_n(self, period: &PeriodSummary) -> f64 {
        match self {
            Feedback::SpindleCurrent | Feedback::Dynamometer => period.force_mean_resultant_n,
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
    /// Low-pass on the spindle phase currents (paper 003's analog filter: 260 Hz). Infinite:
    /// no low-pass (a replayed log whose current is already an RMS value, or one sampled too
    /// slowly for the cut-off: [`crate::log::replay`]).
    pub spindle_lowpass_hz: f64,
    /// Low-pass on the feed phase currents (paper 003: 50 Hz); infinite: none.
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

/// Why a loop could not be set up or run. Each variant says what is wrong in its own terms, so the
/// page can put the message beside the control that caused it.
#[derive(Debug, Clone, PartialEq)]
pub enum LoopError {
    /// A run setting is out of range or does not parse; names the setting.
    Setting(SettingError),
    /// A low-pass design failed.
    Filter(DesignError),
    /// The safety settings are inconsistent.
    Envelope(EnvelopeError),
    /// The controller's parameters do not build a controller.
    Controller(ParamError),
    /// The machine (a preset with edits) could not be built.
    Machine(PlantError),
    /// The teach cut did not give a usable model.
    Calibration(FitError),
    /// A given calibration measures force through another path than the run's feedback.
    CalibrationFeedback {
        /// The path the calibration was made for.
        calibration: Feedback,
        /// The path the run measures with.
        run: Feedback,
    },
    /// A teach cut on a machine that reports no force (no simulation truth, no dynamometer) and
    /// whose cut changes along the path, so the model of the cut cannot stand in.
    NoTeachForce,
    /// Feed-current feedback on a cut that never loads the feed drive.
    NoFeedLoad,
    /// The control period is below one sample or absurdly long at this sample rate.
    ControlPeriod {
        /// The period asked for.
        period_s: f64,
        /// The machine's sample rate.
        sample_rate_hz: f64,
    },
    /// No force target: the preset has none and the teach cut found no cutting.
    NoTarget,
    /// The run's time limit is not a positive duration.
    TimeLimit(f64),
    /// A reference run (fixed feed) ended without a cycle time.
    NoReference,
    /// `finish` was asked for before the work was done, or twice.
    NotFinished,
}

impl fmt::Display for LoopError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LoopError::Setting(e) => write!(f, "{e}"),
            LoopError::Filter(e) => write!(f, "current filter: {e}"),
            LoopError::Envelope(e) => write!(f, "safety envelope: {e}"),
            LoopError::Controller(e) => write!(f, "controller: {e}"),
            LoopError::Machine(e) => write!(f, "{e}"),
            LoopError::Calibration(e) => write!(f, "calibration (teach cut): {e}"),
            LoopError::CalibrationFeedback { calibration, run } => write!(
                f,
                "the calibration is for {} feedback but the run measures with {}; choose \
                 feedback {} or calibrate for {}",
                calibration.name(),
                run.name(),
                calibration.name(),
                run.name()
            ),
            LoopError::NoTeachForce => f.write_str(
                "the machine reports no force (no simulation truth, no dynamometer) and the \
                 program's cut changes along the path, so a teach cut has no force to learn \
                 from: give a saved calibration (--calibration FILE, from cutlab calibrate or an \
                 earlier run's --save-calibration)",
            ),
            LoopError::NoFeedLoad => f.write_str(
                "feed-current feedback needs a cut that loads the feed drive, and this one never \
                 pushed back against the feed (in down milling the cutting force pulls the table \
                 along); measure the force through the spindle current",
            ),
            LoopError::ControlPeriod {
                period_s,
                sample_rate_hz,
            } => write!(
                f,
                "control period {period_s} s must be at least one sample and at most 10⁷ samples \
                 at {sample_rate_hz} Hz"
            ),
            LoopError::NoTarget => f.write_str(
                "no force target: the preset has none and the teach cut found no cutting",
            ),
            LoopError::TimeLimit(s) => {
                write!(f, "the run's time limit must be positive, not {s} s")
            }
            LoopError::NoReference => f.write_str("the reference runs found no cycle time"),
            LoopError::NotFinished => f.write_str("the run has not ended yet"),
        }
    }
}

impl std::error::Error for LoopError {}

/// A calibrated current-to-force estimator.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "feedback", rename_all = "kebab-case", deny_unknown_fields)]
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
    /// A dynamometer's reading, used as it is (its maker calibrated it).
    Dynamometer,
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
            Estimator::Dynamometer => ForceEstimate {
                force_n: period.dynamometer_resultant_n,
                in_range: true,
            },
        }
    }

    /// The current sensitivity, A per N, at a spindle speed (the spindle model's line there; the
    /// feed model's one slope).
    pub fn sensitivity_a_per_n(&self, spindle_rpm: f64) -> f64 {
        match self {
            Estimator::Spindle { model, .. } => model.line_at(spindle_rpm).1,
            Estimator::Feed { model } => model.sensitivity_a_per_n,
            // No current is read: a limit in amperes has no meaning here.
            Estimator::Dynamometer => f64::NAN,
        }
    }

    /// The spread (1 σ) of one period's estimate about the calibration line, in newtons: the
    /// fit's residual at the calibration row nearest `spindle_rpm` (0 for a dynamometer, whose
    /// noise the period mean averages away).
    pub fn residual_std_n(&self, spindle_rpm: f64) -> f64 {
        match self {
            Estimator::Spindle { model, .. } => model
                .rows
                .iter()
                .min_by(|a, b| {
                    (a.speed_rpm - spindle_rpm)
                        .abs()
                        .total_cmp(&(b.speed_rpm - spindle_rpm).abs())
                })
                .map_or(f64::NAN, |row| row.quality.residual_std_n),
            Estimator::Feed { model } => model.quality.residual_std_n,
            Estimator::Dynamometer => 0.0,
        }
    }

    /// The current the model expects at `force_n` (the reference current of a force target).
    pub fn current_for_force_a(&self, force_n: f64, spindle_rpm: f64, feed_mm_min: f64) -> f64 {
        match self {
            Estimator::Spindle { model, .. } => {
                let (idle, sensitivity, _) = model.line_at(spindle_rpm);
                idle + sensitivity * force_n
            }
            Estimator::Feed { model } => {
                model.idle_current_a(feed_mm_min) + model.sensitivity_a_per_n * force_n
            }
            Estimator::Dynamometer => f64::NAN,
        }
    }

    /// The force the model reads from `current_a` (to express a current target as a force).
    pub fn force_for_current_n(&self, current_a: f64, spindle_rpm: f64, feed_mm_min: f64) -> f64 {
        match self {
            Estimator::Spindle { model, .. } => {
                let (idle, sensitivity, _) = model.line_at(spindle_rpm);
                (current_a - idle) / sensitivity
            }
            Estimator::Feed { model } => {
                (current_a - model.idle_current_a(feed_mm_min)) / model.sensitivity_a_per_n
            }
            Estimator::Dynamometer => f64::NAN,
        }
    }
}

/// What a teach cut produced. Saved and read back as a calibration file
/// ([`super::calibration_file`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Calibration {
    /// The fitted estimator.
    pub estimator: Estimator,
    /// The largest force the estimator read while the teach cut's tool was in air (NaN if the
    /// teach cut had no air, or a saved calibration predates this field): the safety envelope
    /// takes the tool for in air below a margin above it.
    #[serde(
        default = "crate::estimation::nan",
        deserialize_with = "crate::estimation::null_as_nan"
    )]
    pub air_force_estimate_n: f64,
    /// Median regulated force over the cutting periods of the teach cut at 100 % override.
    #[serde(deserialize_with = "crate::estimation::null_as_nan")]
    pub median_force_at_full_override_n: f64,
    /// Median of regulated force ÷ mean resultant force over those periods: converts a
    /// resultant-force target into the regulated force (1 for spindle feedback).
    #[serde(deserialize_with = "crate::estimation::null_as_nan")]
    pub regulated_per_resultant: f64,
    /// Periods used for the fit.
    pub periods: usize,
    /// The largest phase current (feed or spindle, raw) seen during the teach cut.
    pub max_phase_current_a: f64,
    /// How long the teach cut ran (machine time).
    pub duration_s: f64,
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
/// Teach-cut periods whose mean spindle speed moved more than this fraction since the period
/// before are skipped: a spindle still accelerating draws a current that says nothing about the
/// load (40 A where the cut takes 6), and only the force source that knows the tool is in air
/// (the simulation's truth) would otherwise reject it.
const TEACH_STEADY_SPEED_FRACTION: f64 = 0.01;

fn lowpass(
    cutoff_hz: f64,
    order: usize,
    sample_rate_hz: f64,
) -> Result<crate::signal::sos::Sos, LoopError> {
    if cutoff_hz == f64::INFINITY {
        // No low-pass: one section that passes every sample through unchanged.
        return crate::signal::sos::Sos::from_rows(&[[1.0, 0.0, 0.0, 1.0, 0.0, 0.0]])
            .map_err(|_| LoopError::Filter(DesignError::Order { order: 0 }));
    }
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
    // Three phases per drive: the bank always has channels.
    SignalChain::new(&spindle, &feed)
        .map_err(|_| LoopError::Filter(DesignError::Order { order: 0 }))
}

fn samples_per_period(settings: &LoopSettings, sample_rate_hz: f64) -> Result<usize, LoopError> {
    let n = (settings.control_period_s * sample_rate_hz).round();
    if !(1.0..=1e7).contains(&n) {
        return Err(LoopError::ControlPeriod {
            period_s: settings.control_period_s,
            sample_rate_hz,
        });
    }
    Ok(n as usize)
}

/// Where a teach cut takes the force that the current is fitted against.
///
/// A simulation knows the true force; a shop has either a dynamometer under the part or the
/// mechanistic model of the cut it programmed (the same model `cutlab calibrate --material` uses),
/// so a real teach cut calibrates without any simulation truth.
#[derive(Debug, Clone, PartialEq)]
pub enum TeachForce {
    /// The plant's truth (simulation only): each sample's [`crate::machine::PlantTruth`].
    SimulationTruth,
    /// A force sensor: each sample's [`Machine::dynamometer_force_n`].
    Dynamometer,
    /// The mean force of the programmed cut, modelled from the period's feed and spindle speed.
    CutModel {
        /// Cutter, milling mode and the material's coefficients.
        geometry: CutGeometry,
        /// Axial depth of the teach cut.
        depth_mm: f64,
        /// Radial width of the teach cut.
        width_mm: f64,
    },
}

impl TeachForce {
    /// Name for the command line and URLs.
    pub fn name(&self) -> &'static str {
        match self {
            TeachForce::SimulationTruth => "truth",
            TeachForce::Dynamometer => "dynamometer",
            TeachForce::CutModel { .. } => "cut-model",
        }
    }
}

/// One sensor sample as a loop takes it: the machine's step and what the machine adds beside it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopSample<'a> {
    /// What the sensors read (and the truth, if simulated).
    pub step: &'a MachineStep,
    /// The power-law estimate of [`Machine::sensorless_force`], when the machine offers one.
    /// Only a period's last sample needs it ([`SampleLoop::next_sample_ends_period`]).
    pub sensorless: Option<SensorlessEstimate>,
    /// A dynamometer's reading, when the machine has one.
    pub dynamometer: Option<DynamometerReading>,
}

/// A loop that takes sensor samples as they come and answers with an override command at the end
/// of each control period.
///
/// This is the shape a real machine needs: WebSerial delivers samples when they arrive and a log
/// is read in chunks, so the loop is pushed, never pulls. [`OnMachine`] is the thin adapter that
/// pulls samples from a [`Machine`] (the simulation) and pushes them here; replay and hardware
/// push theirs directly. The teach cut and the closed loop are both sample loops.
pub trait SampleLoop {
    /// What the finished loop gives.
    type Output;

    /// Takes one sample. At the end of a control period it returns the command for the samples
    /// that follow; in between, `None` (the command in force is [`SampleLoop::command`]).
    fn push(&mut self, sample: &LoopSample<'_>) -> Option<OverrideCommand>;

    /// The override command in force.
    fn command(&self) -> OverrideCommand;

    /// Whether the next pushed sample is the last of its control period.
    fn next_sample_ends_period(&self) -> bool;

    /// How many more samples the control period under way takes (at least one): a machine can
    /// step that many under the same command at once.
    fn samples_left_in_period(&self) -> usize;

    /// The machine says its program (or log) has ended with the last sample pushed: a period
    /// under way ends with the samples it has (the machine has nothing more to say, and repeating
    /// its last reading would look like a stuck sensor), and the loop ends.
    fn end_of_program(&mut self);

    /// Whether the loop has ended (program over, time limit, or its own reason).
    fn finished(&self) -> bool;

    /// Machine time of the latest period's end.
    fn elapsed_s(&self) -> f64;

    /// What a person reads on a progress bar.
    fn stage(&self) -> &'static str;

    /// The output, once finished (or early, for what is there so far when the run is stopped).
    fn finish(&mut self) -> Result<Self::Output, LoopError>;
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
    /// The regulated force of the periods at 100 % override, the index of each among the
    /// samples, and its ratio to the true mean resultant (NaN without truth).
    full_override_forces_n: Vec<f64>,
    full_override_at: Vec<usize>,
    full_override_ratios: Vec<f64>,
    max_phase_current_a: f64,
    /// Every settled period, whatever its force, with its force: the air periods among them tell
    /// what the fitted model reads with the tool in air ([`Calibration::air_force_estimate_n`]).
    settled: Vec<(PeriodSummary, f64)>,
}

/// A period whose current is within this fraction of the teach cut's lowest is taken for air by
/// the cut-model force source.
const AIR_CURRENT_MARGIN: f64 = 0.02;

impl TeachSamples {
    /// The samples without the air cut. The model of the cut gives a force whenever the axes
    /// feed, in air too, so it cannot say where the tool enters; the current can: the teach
    /// program approaches in air (as a part program does), and its lowest current is the idle
    /// one. Periods within [`AIR_CURRENT_MARGIN`] of it are air.
    fn without_air(&self) -> TeachSamples {
        let air_a = self.current_a.iter().copied().fold(f64::INFINITY, f64::min);
        let keep: Vec<usize> = (0..self.current_a.len())
            .filter(|&i| self.current_a[i] > air_a * (1.0 + AIR_CURRENT_MARGIN))
            .collect();
        let pick = |v: &[f64]| keep.iter().filter_map(|&i| v.get(i).copied()).collect();
        let full: Vec<usize> = (0..self.full_override_at.len())
            .filter(|&k| keep.contains(&self.full_override_at[k]))
            .collect();
        let pick_full = |v: &[f64]| full.iter().filter_map(|&k| v.get(k).copied()).collect();
        TeachSamples {
            current_a: pick(&self.current_a),
            force_n: pick(&self.force_n),
            speed_rpm: pick(&self.speed_rpm),
            command_rpm: pick(&self.command_rpm),
            fv_voltage_v: pick(&self.fv_voltage_v),
            feed_mm_min: pick(&self.feed_mm_min),
            full_override_forces_n: pick_full(&self.full_override_forces_n),
            full_override_at: full.iter().map(|&k| self.full_override_at[k]).collect(),
            full_override_ratios: pick_full(&self.full_override_ratios),
            max_phase_current_a: self.max_phase_current_a,
            settled: Vec::new(),
        }
    }
}

/// A teach cut: the machine open-loop through the teach-cut override schedule
/// ([`TEACH_OVERRIDES_PCT`]), each control period summarised by the loop's own signal chain and
/// paired with the force from a [`TeachForce`] source; [`SampleLoop::finish`] fits the estimator.
pub struct TeachCut {
    feedback: Feedback,
    force_source: TeachForce,
    max_duration_s: f64,
    chain: SignalChain,
    samples_per_period: usize,
    samples_in_period: usize,
    last: SensorSample,
    samples: TeachSamples,
    time_s: f64,
    /// The mean spindle speed of the period before, to tell acceleration from a steady cut.
    previous_speed_rpm: f64,
    command: OverrideCommand,
    done: bool,
}

impl TeachCut {
    /// A teach cut at `sample_rate_hz` with the signal chain and feedback path of `settings`,
    /// taking its force from `force_source`.
    pub fn new(
        sample_rate_hz: f64,
        settings: &LoopSettings,
        force_source: TeachForce,
    ) -> Result<Self, LoopError> {
        Ok(Self {
            chain: chain_for(settings, sample_rate_hz)?,
            samples_per_period: samples_per_period(settings, sample_rate_hz)?,
            samples_in_period: 0,
            feedback: settings.feedback,
            force_source,
            max_duration_s: settings.max_duration_s,
            last: SensorSample::default(),
            samples: TeachSamples::default(),
            time_s: 0.0,
            previous_speed_rpm: f64::NAN,
            command: Self::command_at(0.0),
            done: false,
        })
    }

    /// The override the schedule holds at machine time `time_s`.
    fn command_at(time_s: f64) -> OverrideCommand {
        let step_index = (time_s / TEACH_STEP_S) as usize % TEACH_OVERRIDES_PCT.len();
        OverrideCommand {
            override_pct: TEACH_OVERRIDES_PCT[step_index],
            feed_hold: false,
        }
    }

    /// The period's force from the chosen source (NaN when the source has nothing to say).
    fn period_force_n(&self, period: &PeriodSummary) -> f64 {
        match &self.force_source {
            TeachForce::SimulationTruth => self.feedback.regulated_truth_n(period),
            TeachForce::Dynamometer => match self.feedback {
                Feedback::FeedCurrent => period.dynamometer_feed_force_n,
                Feedback::SpindleCurrent | Feedback::Dynamometer => period.dynamometer_resultant_n,
            },
            TeachForce::CutModel {
                geometry,
                depth_mm,
                width_mm,
                ..
            } => geometry
                .mean_forces(
                    period.feed_mm_min,
                    period.spindle_speed_rpm,
                    *depth_mm,
                    *width_mm,
                )
                .map_or(f64::NAN, |f| match self.feedback {
                    Feedback::SpindleCurrent | Feedback::Dynamometer => f.resultant_n(),
                    Feedback::FeedCurrent => -f.fx_n,
                }),
        }
    }

    /// Files one ended period's (current, force) pair, if the period is usable.
    fn end_period(&mut self, command_pct: f64) {
        let period = self.chain.finish_period();
        self.samples_in_period = 0;
        self.time_s = period.end_time_s;
        let force_n = self.period_force_n(&period);
        let last = self.last;
        let spindle_settled =
            last.time_since_spindle_start_s >= TEACH_SETTLE_S || !last.spindle_running;
        // The drives need a moment after each override change (the spindle's bandwidth is below
        // 5 Hz), and air cuts are left out: the line is fitted where it is used, in the cut.
        let since_change_s = self.time_s % TEACH_STEP_S;
        let speed_change_rpm = (period.spindle_speed_rpm - self.previous_speed_rpm).abs();
        let accelerating =
            speed_change_rpm > TEACH_STEADY_SPEED_FRACTION * period.spindle_speed_rpm.abs();
        self.previous_speed_rpm = period.spindle_speed_rpm;
        let samples = &mut self.samples;
        let settled = spindle_settled
            && !accelerating
            && since_change_s >= TEACH_SETTLE_AFTER_CHANGE_S
            && period.feed_mm_min.abs() >= 1e-6;
        if settled {
            samples.settled.push((period, force_n));
        }
        let skipped = !(settled && force_n.is_finite() && force_n > 0.0);
        if !skipped {
            if command_pct == 100.0 {
                samples.full_override_at.push(samples.current_a.len());
                samples.full_override_forces_n.push(force_n);
                // NaN without truth: dropped when the ratio is taken.
                samples
                    .full_override_ratios
                    .push(force_n / period.force_mean_resultant_n);
            }
            samples.current_a.push(match self.feedback {
                Feedback::SpindleCurrent | Feedback::Dynamometer => period.spindle_current_rms_a,
                Feedback::FeedCurrent => period.feed_current_rms_a,
            });
            samples.force_n.push(force_n);
            samples.speed_rpm.push(period.spindle_speed_rpm);
            samples.command_rpm.push(period.spindle_command_rpm);
            samples.fv_voltage_v.push(period.spindle_fv_voltage_v);
            samples.feed_mm_min.push(period.feed_mm_min);
        }
        if self.time_s >= self.max_duration_s {
            self.done = true;
        }
        self.command = Self::command_at(self.time_s);
    }

    /// Fits the estimator to what was collected.
    pub fn calibration(&self) -> Result<Calibration, LoopError> {
        let in_cut;
        let s = match self.force_source {
            TeachForce::CutModel { .. } => {
                in_cut = self.samples.without_air();
                &in_cut
            }
            _ => &self.samples,
        };
        let estimator = match self.feedback {
            // The sensor reads the force itself: nothing to fit.
            Feedback::Dynamometer => Estimator::Dynamometer,
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
            Feedback::FeedCurrent if s.force_n.is_empty() => {
                return Err(LoopError::NoFeedLoad);
            }
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
        let median_force_at_full_override_n = median(&s.full_override_forces_n);
        let air_force_estimate_n =
            self.air_force_estimate_n(&estimator, median_force_at_full_override_n);
        Ok(Calibration {
            estimator,
            air_force_estimate_n,
            median_force_at_full_override_n,
            regulated_per_resultant: median(
                &s.full_override_ratios
                    .iter()
                    .copied()
                    .filter(|r| r.is_finite())
                    .collect::<Vec<_>>(),
            ),
            periods: s.force_n.len(),
            max_phase_current_a: s.max_phase_current_a,
            duration_s: self.time_s,
        })
    }
}

impl TeachCut {
    /// The largest force `estimator` reads over the teach cut's air periods (NaN if it saw none):
    /// a spindle current's line fitted in the cut seldom passes through the idle current (an
    /// induction motor's magnetising current makes the current convex in the load), so "no
    /// force" reads as tens of newtons. The periods in air are those whose force source said
    /// (next to) nothing — below 2 % of the force at 100 % override — or, for the model of the cut,
    /// which gives a force wherever the axes feed, those whose current is the idle one.
    fn air_force_estimate_n(&self, estimator: &Estimator, full_override_force_n: f64) -> f64 {
        let settled = &self.samples.settled;
        let current = |p: &PeriodSummary| match self.feedback {
            Feedback::FeedCurrent => p.feed_current_rms_a,
            Feedback::SpindleCurrent | Feedback::Dynamometer => p.spindle_current_rms_a,
        };
        let idle_a = settled
            .iter()
            .map(|(p, _)| current(p))
            .fold(f64::INFINITY, f64::min);
        let in_air = |p: &PeriodSummary, force_n: f64| match self.force_source {
            TeachForce::CutModel { .. } => current(p) <= idle_a * (1.0 + AIR_CURRENT_MARGIN),
            _ => force_n.is_finite() && force_n.abs() < 0.02 * full_override_force_n,
        };
        settled
            .iter()
            .filter(|(p, f)| in_air(p, *f))
            .map(|(p, _)| estimator.estimate(p).force_n)
            .filter(|f| f.is_finite())
            .fold(f64::NAN, f64::max)
    }
}

impl SampleLoop for TeachCut {
    type Output = Calibration;

    #[inline(always)]
    fn push(&mut self, sample: &LoopSample<'_>) -> Option<OverrideCommand> {
        if self.done {
            return None;
        }
        let sensors = &sample.step.sensors;
        self.chain.push(sample.step);
        for i in sensors
            .feed_phase_currents_a
            .iter()
            .chain(&sensors.spindle_phase_currents_a)
        {
            if i.is_finite() {
                self.samples.max_phase_current_a =
                    crate::math::max(self.samples.max_phase_current_a, i.abs());
            }
        }
        if let Some(d) = &sample.dynamometer {
            self.chain.push_dynamometer(d);
        }
        self.last = *sensors;
        self.samples_in_period += 1;
        if self.samples_in_period < self.samples_per_period {
            return None;
        }
        self.end_period(self.command.override_pct);
        Some(self.command)
    }

    fn command(&self) -> OverrideCommand {
        self.command
    }

    fn next_sample_ends_period(&self) -> bool {
        self.samples_in_period + 1 >= self.samples_per_period
    }

    fn samples_left_in_period(&self) -> usize {
        self.samples_per_period
            .saturating_sub(self.samples_in_period)
            .max(1)
    }

    fn end_of_program(&mut self) {
        if self.samples_in_period > 0 && !self.done {
            self.end_period(self.command.override_pct);
        }
        self.done = true;
    }

    fn finished(&self) -> bool {
        self.done
    }

    fn elapsed_s(&self) -> f64 {
        self.time_s
    }

    fn stage(&self) -> &'static str {
        "teach cut"
    }

    fn finish(&mut self) -> Result<Calibration, LoopError> {
        self.calibration()
    }
}

/// Runs a whole teach cut of `machine` with the simulation's truth as the force and fits the
/// estimator for `settings.feedback`.
pub fn teach_cut(
    machine: Box<dyn Machine>,
    settings: &LoopSettings,
) -> Result<Calibration, LoopError> {
    OnMachine::teach_cut(machine, settings, TeachForce::SimulationTruth)?.run_to_end()
}

/// The spindle gear change of paper 003's machining centre.
pub const GEAR_CHANGE_RPM: f64 = 900.0;

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
    samples_per_period: usize,
    samples_in_period: usize,
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
    done: bool,
}

/// A force estimate above this fraction of the target, with the spindle at speed, before the
/// loop has armed, is a cut the controller cannot shape.
const CUT_BEFORE_ARMING_FRACTION: f64 = 0.5;
/// The spindle is at speed within this fraction of its command (its run-up current would read as
/// a force).
const AT_SPEED_FRACTION: f64 = 0.02;

impl FeedbackLoop {
    /// Wires `controller` and `estimator` with `settings` for samples at `sample_rate_hz`.
    pub fn new(
        sample_rate_hz: f64,
        controller: Box<dyn Controller>,
        estimator: Estimator,
        settings: LoopSettings,
    ) -> Result<Self, LoopError> {
        if !(settings.target_force_n.is_finite() && settings.target_force_n > 0.0) {
            return Err(LoopError::NoTarget);
        }
        if !(settings.max_duration_s.is_finite() && settings.max_duration_s > 0.0) {
            return Err(LoopError::TimeLimit(settings.max_duration_s));
        }
        let chain = chain_for(&settings, sample_rate_hz)?;
        let samples_per_period = samples_per_period(&settings, sample_rate_hz)?;
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
            samples_per_period,
            samples_in_period: 0,
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

    /// Warns once when the estimate shows a cut before the loop has armed.
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
            && force_n > CUT_BEFORE_ARMING_FRACTION * self.settings.target_force_n
        {
            self.warned_cut_before_arming = true;
            self.trace.events.push(SafetyEvent::CutBeforeArming {
                time_s: period.end_time_s,
                force_n,
            });
        }
    }

    /// Ends a control period: estimate, control, limit, record.
    fn end_period(&mut self, sensorless: SensorlessEstimate) {
        let sensorless_n = sensorless.force_n;
        let last = self.last;
        let period = self.chain.finish_period();
        self.samples_in_period = 0;
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
                self.settings.cross_check_tolerance + sensorless.relative_uncertainty,
                self.settings.target_force_n,
            ),
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
        self.samples_in_period += 1;
        if self.samples_in_period < self.samples_per_period {
            return None;
        }
        self.end_period(self.last_sensorless);
        Some(self.command)
    }

    fn command(&self) -> OverrideCommand {
        self.command
    }

    fn next_sample_ends_period(&self) -> bool {
        self.samples_in_period + 1 >= self.samples_per_period
    }

    fn samples_left_in_period(&self) -> usize {
        self.samples_per_period
            .saturating_sub(self.samples_in_period)
            .max(1)
    }

    fn end_of_program(&mut self) {
        if self.samples_in_period > 0 && !self.done {
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

/// A [`SampleLoop`] pulling its samples from a [`Machine`]: each sample period it steps the
/// machine with the loop's command and pushes what the machine read. This is how a simulation
/// (and a replayed log) drives the same loop a real machine pushes samples into.
pub struct OnMachine<L> {
    machine: Box<dyn Machine>,
    sample_loop: L,
    /// The samples of the block being pushed ([`Machine::step_block`]).
    block: Vec<BlockStep>,
}

/// Samples a machine steps at once, at most (a block stays in the first-level cache).
const MACHINE_BLOCK: usize = 64;

/// The closed loop on a machine.
pub type ClosedLoop = OnMachine<FeedbackLoop>;

impl<L: SampleLoop> OnMachine<L> {
    /// `sample_loop` driven by `machine`.
    pub fn new_with(machine: Box<dyn Machine>, sample_loop: L) -> Self {
        Self {
            machine,
            sample_loop,
            block: vec![BlockStep::default(); MACHINE_BLOCK],
        }
    }

    /// The loop.
    pub fn sample_loop(&self) -> &L {
        &self.sample_loop
    }

    /// Machine time of the latest period's end.
    pub fn elapsed_s(&self) -> f64 {
        self.sample_loop.elapsed_s()
    }

    /// Whether the loop has ended.
    pub fn finished(&self) -> bool {
        self.sample_loop.finished()
    }

    /// The machine back (a real machine does the teach cut and then the run), and the loop.
    pub fn into_parts(self) -> (Box<dyn Machine>, L) {
        (self.machine, self.sample_loop)
    }

    /// Runs one control period: the machine steps the period's samples in blocks under the
    /// period's command, and each sample is pushed into the loop in turn.
    fn period(&mut self) {
        let command = self.sample_loop.command();
        loop {
            let wanted = self.sample_loop.samples_left_in_period().min(MACHINE_BLOCK);
            let stepped = self.machine.step_block(command, &mut self.block[..wanted]);
            let program_over = self.machine.finished();
            for (i, b) in self.block[..stepped].iter().enumerate() {
                let last = i + 1 == stepped;
                // A period ends at the block's last sample (the block never crosses one), or
                // where the program does.
                let ends = (last && program_over) || self.sample_loop.next_sample_ends_period();
                let sample = LoopSample {
                    step: &b.step,
                    // The power law is evaluated once per period, where the loop reads it: at
                    // the machine's latest sample, which is this one.
                    sensorless: if ends && last {
                        self.machine.sensorless_force()
                    } else {
                        None
                    },
                    dynamometer: b.dynamometer,
                };
                let period_ended = self.sample_loop.push(&sample).is_some();
                if last && program_over {
                    self.sample_loop.end_of_program();
                    return;
                }
                if period_ended || self.sample_loop.finished() {
                    return;
                }
            }
            if stepped == 0 {
                // Not reached (a block holds at least one sample); never spin.
                return;
            }
        }
    }
}

impl OnMachine<TeachCut> {
    /// A teach cut of `machine` with the signal chain and feedback path of `settings`.
    pub fn teach_cut(
        machine: Box<dyn Machine>,
        settings: &LoopSettings,
        force_source: TeachForce,
    ) -> Result<Self, LoopError> {
        let teach = TeachCut::new(machine.sample_rate_hz(), settings, force_source)?;
        Ok(Self::new_with(machine, teach))
    }

    /// Fits the estimator to what was collected so far.
    pub fn calibration(&self) -> Result<Calibration, LoopError> {
        self.sample_loop.calibration()
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

impl<L: SampleLoop> Work for OnMachine<L> {
    type Output = L::Output;
    type Error = LoopError;

    /// Runs at most `periods` control periods.
    fn advance(&mut self, periods: usize) -> Result<bool, LoopError> {
        for _ in 0..periods {
            if self.sample_loop.finished() {
                break;
            }
            self.period();
        }
        Ok(self.sample_loop.finished())
    }

    fn progress(&self) -> Progress {
        // The machine's own duration is unknown here; LabRun scales by the program's.
        Progress::new(self.sample_loop.stage(), 0.0)
    }

    fn finish(&mut self) -> Result<L::Output, LoopError> {
        self.sample_loop.finish()
    }
}

/// Whether two estimates differ by more than `tolerance` of the larger of them and the target
/// (so two near-zero estimates in air never disagree).
/// What a period without a sensorless estimate records.
const NO_SENSORLESS_ESTIMATE: SensorlessEstimate = SensorlessEstimate {
    force_n: f64::NAN,
    relative_uncertainty: 0.0,
};

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cross_check_widens_with_the_power_laws_uncertainty_but_still_sees_a_real_gap() {
        // ±30 % at the calibration cut.
        assert!(!disagrees(100.0, 130.0, 0.3, 100.0));
        assert!(disagrees(100.0, 150.0, 0.3, 100.0));
        // Half the calibrated feed per tooth adds 0.25·ln 2 ≈ 0.17: 50 % apart is then within it.
        let tolerance = 0.3 + 0.25 * 2f64.ln();
        assert!(!disagrees(100.0, 150.0, tolerance, 100.0));
        // A force two and a half times the estimate is still a disagreement.
        assert!(disagrees(100.0, 250.0, tolerance, 100.0));
        // No power-law estimate, no verdict.
        assert!(!disagrees(100.0, f64::NAN, tolerance, 100.0));
    }
}
