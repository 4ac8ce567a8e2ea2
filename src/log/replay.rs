//! A log as a [`Machine`]: replay of controllers on a recorded cut, and calibration from it.
//!
//! ```text
//! Log columns ─(Mapping)─► LogMachine::step, one row per sample at the log's rate
//!   ─► the closed loop of every other mode, unchanged (closed_loop::runner):
//!      SafetyEnvelope::observe ─► signal chain ─► estimator ─► controller ─► envelope
//!   ─► the override each controller *would* have commanded, one TraceRow per control period
//! ```
//!
//! Replay is open-loop by nature: the log was recorded under whatever override the machine had
//! then, and it cannot react to the commands a replayed controller gives. What a replay shows is
//! each controller's decision on the signals the log holds — the override it asks for, what the
//! safety envelope lets through (arming, limits, rate limit, quantisation, sensor faults,
//! overload) and the force estimate — not what would have happened after the first decision that
//! differs from the machine's own. docs/logs.md says more.
//!
//! How the log's columns become a [`crate::machine::SensorSample`] (the [`Channel`]s of a [`Mapping`]):
//!
//! * **three phase currents** of a motor go in as they are; **two** are completed by Kirchhoff's
//!   current law (`i_w = −i_u − i_v`, exact for a motor without neutral); **one** stands for the
//!   three scaled so that the chain's period mean of |i| reads the RMS of a sinusoidal current
//!   (`×√3·π/(2√2)`, exact for a sine, approximate for a distorted current);
//! * an **RMS or "current feedback" value** (a drive's slow log, often 10 Hz) stands for all three
//!   phases, so the three-phase RMS of the chain gives it back (a signed value by its magnitude).
//!   Its low-pass stage is skipped, since it filters phase currents before the RMS and the log has
//!   none; so is any low-pass whose cut-off is at or above the log's Nyquist frequency. Each
//!   skipped stage is said in the replay's notes;
//! * the **spindle speed** is also the programmed speed and the F/V converter's input (through
//!   the calibration's own slope) unless the log has those columns; without a speed column the
//!   speed is a constant (the one given, or the calibration's);
//! * the spindle **runs** while its programmed speed (or else its speed) is above 1 rpm, and a
//!   spindle already running at the log's first row is taken to start there: the envelope arms
//!   its delay after it;
//! * the **applied override** is the log's override column (100 % without one), the programmed
//!   feed the feed over it; a measured **force** and the **depth** are the run's "truth" for the
//!   plots and metrics, and the force is also a dynamometer's reading; never a controller's input.
//!
//! With a calibration the estimator turns current into force as everywhere else; without one the
//! controllers regulate the current itself: the "force" they see is the current in A (flagged as
//! outside any calibrated range), and the target is a current.

use std::sync::Arc;

use serde::Serialize;

use super::mapping::{Channel, Mapping, MappingError, Resolved};
use super::Log;
use crate::closed_loop::chain::{PeriodSummary, SignalChain};
use crate::closed_loop::runner::{
    Calibration, ClosedLoop, Estimator, Feedback, LoopError, LoopSettings, GEAR_CHANGE_RPM,
};
use crate::closed_loop::trace::{csv_field, Trace, TraceRow};
use crate::control::registry::{ControllerConfig, RunContext};
use crate::estimation::current_force::{
    FeedCurrentModel, FitQuality, Range, SpindleCurrentModel, SpindleSpeedRow,
};
use crate::estimation::cut_forces::CutGeometry;
use crate::estimation::speed::{in_high_speed_range, FvSpeedModel};
use crate::machine::{DynamometerReading, Machine, MachineStep, OverrideCommand, PlantTruth};
use crate::safety::{EnvelopeConfig, SafetyEvent};
use crate::work::{Progress, Work};

/// A spindle at or below this speed is stopped.
const SPINDLE_RUNNING_RPM: f64 = 1.0;
/// One phase scaled so that the period mean of its magnitude reads a sine's RMS: the
/// three-phase RMS of `[k·i, 0, 0]` is `k·|i|/√3`, and a sine's mean |i| is `2√2/π` of its RMS.
const SINGLE_PHASE_SCALE: f64 =
    1.732_050_807_568_877_2 * std::f64::consts::PI / 2.828_427_124_746_19;
/// The envelope calls readings stuck after at least this many identical samples: a slow log's
/// RMS value written to two decimals repeats from one sample to the next without a fault.
const STUCK_SAMPLES: f64 = 10.0;

/// Why a replay or a calibration from a log could not be made; the message says what to change.
#[derive(Debug, Clone, PartialEq)]
pub enum ReplayError {
    /// The mapping does not fit the log.
    Mapping(MappingError),
    /// Something the replay needs is missing or out of range.
    Setting(String),
    /// The loop refused its settings.
    Loop(LoopError),
}

impl std::fmt::Display for ReplayError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ReplayError::Mapping(e) => write!(f, "{e}"),
            ReplayError::Setting(e) => f.write_str(e),
            ReplayError::Loop(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for ReplayError {}

impl From<MappingError> for ReplayError {
    fn from(e: MappingError) -> Self {
        ReplayError::Mapping(e)
    }
}

impl From<LoopError> for ReplayError {
    fn from(e: LoopError) -> Self {
        ReplayError::Loop(e)
    }
}

fn setting(message: impl Into<String>) -> ReplayError {
    ReplayError::Setting(message.into())
}

/// How a log's rows become sensor samples, apart from the mapping.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogSource {
    /// The log's sample period (its time column's, or the one given).
    pub sample_period_s: f64,
    /// The spindle speed when the log has no speed column.
    pub spindle_rpm: f64,
    /// The F/V converter's volts per rpm in the low and high gear, and the gear change (NaN when
    /// unknown: the estimator then reads the programmed speed itself).
    pub fv_v_per_rpm: (f64, f64, f64),
}

/// A log that steps like a machine: one row per sample, whatever the command.
pub struct LogMachine {
    log: Arc<Log>,
    columns: Resolved,
    source: LogSource,
    row: usize,
    spindle_started_at_s: Option<f64>,
    last: MachineStep,
    last_force_n: Option<f64>,
}

impl LogMachine {
    /// `log` read through `mapping`.
    pub fn new(log: Arc<Log>, mapping: &Mapping, source: LogSource) -> Result<Self, ReplayError> {
        let columns = mapping.resolve(&log)?;
        if !(source.sample_period_s.is_finite() && source.sample_period_s > 0.0) {
            return Err(setting(
                "the log's sample period is unknown: it has no time column; give the period",
            ));
        }
        Ok(Self {
            log,
            columns,
            source,
            row: 0,
            spindle_started_at_s: None,
            last: MachineStep::default(),
            last_force_n: None,
        })
    }

    /// Rows replayed so far.
    pub fn row(&self) -> usize {
        self.row
    }

    /// Rows in the log.
    pub fn rows(&self) -> usize {
        self.log.rows
    }

    fn value(&self, channel: Channel, row: usize) -> Option<f64> {
        let column = self.columns.column(channel)?;
        self.log.columns.get(column)?.values.get(row).copied()
    }

    /// The phase currents of a motor from its phase columns, else its RMS column, else zeros.
    fn currents(&self, phases: Channel, rms: Channel, row: usize) -> [f64; 3] {
        let value = |c: usize| {
            self.log
                .columns
                .get(c)
                .and_then(|c| c.values.get(row))
                .copied()
                .unwrap_or(f64::NAN)
        };
        match *self.columns.columns(phases) {
            [u, v, w] => [value(u), value(v), value(w)],
            [u, v] => {
                let (u, v) = (value(u), value(v));
                [u, v, -u - v]
            }
            [u] => [SINGLE_PHASE_SCALE * value(u), 0.0, 0.0],
            _ => match self.value(rms, row) {
                Some(i) => [i; 3],
                None => [0.0; 3],
            },
        }
    }

    fn sample(&mut self, row: usize) -> MachineStep {
        let s = &self.source;
        let time_s = match self.value(Channel::Time, row) {
            Some(t) if t.is_finite() => t,
            // A damaged time cell (a gap, NaN, ±∞): a period after the row before, so no event
            // or period of the replay is timed "NaN s".
            Some(_) if row > 0 => self.last.sensors.time_s + s.sample_period_s,
            _ => row as f64 * s.sample_period_s,
        };
        let speed_rpm = self
            .value(Channel::SpindleSpeed, row)
            .unwrap_or(s.spindle_rpm);
        let command_rpm = self
            .value(Channel::SpindleCommand, row)
            .unwrap_or(speed_rpm);
        let (low, high, gear_change_rpm) = s.fv_v_per_rpm;
        let fv_voltage_v = self.value(Channel::FvVoltage, row).unwrap_or_else(|| {
            let slope = if in_high_speed_range(command_rpm, gear_change_rpm) {
                high
            } else {
                low
            };
            speed_rpm.abs() * slope
        });
        let running = command_rpm.abs() > SPINDLE_RUNNING_RPM;
        if running && self.spindle_started_at_s.is_none() {
            self.spindle_started_at_s = Some(time_s);
        } else if !running {
            self.spindle_started_at_s = None;
        }
        let applied_override_pct = self.value(Channel::Override, row).unwrap_or(100.0);
        let feed_mm_min = self.value(Channel::Feed, row).unwrap_or(f64::NAN);
        let programmed_feed_mm_min =
            self.value(Channel::ProgrammedFeed, row).unwrap_or_else(|| {
                if applied_override_pct > 0.0 {
                    feed_mm_min * 100.0 / applied_override_pct
                } else {
                    feed_mm_min
                }
            });
        let force_n = self.value(Channel::Force, row);
        let depth_mm = self.value(Channel::Depth, row);
        self.last_force_n = force_n;
        let truth = (force_n.is_some() || depth_mm.is_some()).then(|| {
            let f = force_n.unwrap_or(f64::NAN);
            PlantTruth {
                force_x_n: f,
                force_y_n: 0.0,
                force_z_n: f64::NAN,
                force_resultant_n: f,
                feed_force_n: f,
                spindle_torque_nm: f64::NAN,
                cutting_power_w: f64::NAN,
                depth_mm: depth_mm.unwrap_or(f64::NAN),
                width_mm: f64::NAN,
                feed_per_tooth_mm: f64::NAN,
                path_position_mm: f64::NAN,
                material_removal_mm3_s: f64::NAN,
                tool_x_mm: f64::NAN,
                tool_y_mm: f64::NAN,
                feed_current_rms_a: f64::NAN,
                spindle_current_rms_a: f64::NAN,
            }
        });
        MachineStep {
            sensors: crate::machine::SensorSample {
                time_s,
                feed_phase_currents_a: self.currents(Channel::FeedPhase, Channel::FeedCurrent, row),
                spindle_phase_currents_a: self.currents(
                    Channel::SpindlePhase,
                    Channel::SpindleCurrent,
                    row,
                ),
                spindle_fv_voltage_v: fv_voltage_v,
                spindle_speed_rpm: speed_rpm,
                spindle_command_rpm: command_rpm,
                programmed_feed_mm_min,
                feed_mm_min,
                applied_override_pct,
                spindle_running: running,
                time_since_spindle_start_s: self.spindle_started_at_s.map_or(0.0, |t| time_s - t),
            },
            truth,
        }
    }
}

impl Machine for LogMachine {
    fn sample_rate_hz(&self) -> f64 {
        1.0 / self.source.sample_period_s
    }

    /// The next row, whatever `command` says: a log cannot react.
    fn step(&mut self, _command: OverrideCommand) -> MachineStep {
        if self.row < self.log.rows {
            self.last = self.sample(self.row);
            self.row += 1;
        }
        self.last
    }

    fn finished(&self) -> bool {
        self.row >= self.log.rows
    }

    fn dynamometer_force_n(&self) -> Option<DynamometerReading> {
        self.last_force_n.map(|f| DynamometerReading {
            force_x_n: f,
            force_y_n: 0.0,
            feed_force_n: f,
        })
    }
}

/// The target a replay holds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Target {
    /// A force, N (needs a calibration).
    ForceN(f64),
    /// A current, A: through the calibration a force, without one the regulated current itself.
    CurrentA(f64),
}

/// What a replay (or a calibration from a log) is made with, besides the log and its mapping.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplaySettings {
    /// Which current measures the force (spindle or feed; dynamometer replays the force column).
    pub feedback: Feedback,
    /// The control period; `None` picks one: a whole number of log samples and, with a spindle
    /// speed, of spindle revolutions, at least 40 ms.
    pub control_period_s: Option<f64>,
    /// The sample period of a log without a time column (overrides the time column's).
    pub sample_period_s: Option<f64>,
    /// Low-pass on spindle phase currents (skipped above the log's Nyquist frequency).
    pub spindle_lowpass_hz: f64,
    /// Low-pass on feed phase currents.
    pub feed_lowpass_hz: f64,
    /// Order of both low-passes.
    pub lowpass_order: usize,
    /// The target; `None` takes 80 % of the calibration's force at full override.
    pub target: Option<Target>,
    /// The safety envelope (its overload limit follows the target: 3 × target).
    pub envelope: EnvelopeConfig,
    /// The spindle speed when the log has no speed column (`None`: the calibration's).
    pub spindle_rpm: Option<f64>,
    /// The current → force model; `None` regulates the current itself.
    pub calibration: Option<Calibration>,
}

impl Default for ReplaySettings {
    fn default() -> Self {
        Self {
            feedback: Feedback::SpindleCurrent,
            control_period_s: None,
            sample_period_s: None,
            spindle_lowpass_hz: 260.0,
            feed_lowpass_hz: 50.0,
            lowpass_order: 4,
            target: None,
            envelope: EnvelopeConfig::for_target(1.0),
            spindle_rpm: None,
            calibration: None,
        }
    }
}

/// The shortest control period a replay picks by itself (a mill's: see the lab's presets).
const MIN_CONTROL_PERIOD_S: f64 = 0.04;
/// Overload at this multiple of the target, as in the lab's runs.
const OVERLOAD_FACTOR: f64 = 3.0;
/// The metrics' force limit, as a multiple of the target.
const FORCE_LIMIT_FACTOR: f64 = 1.2;

/// Everything a replay or a calibration resolved from the log, its mapping and the settings.
struct Prepared {
    machine: LogMachine,
    settings: LoopSettings,
    estimator: Estimator,
    notes: Vec<String>,
    /// The target as given (or chosen), for the report.
    target: Target,
    calibrated: bool,
    spindle_rpm: f64,
}

/// The mean of the finite values of a column (NaN if none).
fn column_mean(log: &Log, column: Option<usize>) -> f64 {
    column
        .and_then(|c| log.columns.get(c))
        .map_or(f64::NAN, |c| c.min_max_mean().2)
}

/// An estimator that reads the current itself as the "force" (1 A ≙ 1 unit), flagged outside any
/// calibrated range: the controllers then regulate the current.
fn current_as_force(feedback: Feedback, spindle_rpm: f64) -> Estimator {
    // No calibrated range: every estimate is outside it (so the loop never takes the current
    // for a cut before arming either).
    let unbounded = Range {
        min: f64::NAN,
        max: f64::NAN,
    };
    let quality = FitQuality {
        r_squared: f64::NAN,
        residual_std_a: f64::NAN,
        residual_std_n: f64::NAN,
        samples: 0,
    };
    match feedback {
        Feedback::FeedCurrent => Estimator::Feed {
            model: FeedCurrentModel {
                idle_current_a: 0.0,
                idle_current_a_per_mm_min: 0.0,
                sensitivity_a_per_n: 1.0,
                current_range_a: unbounded,
                feed_range_mm_min: Range {
                    min: f64::NAN,
                    max: f64::NAN,
                },
                quality,
            },
        },
        _ => Estimator::Spindle {
            model: SpindleCurrentModel {
                // Every speed in one gear.
                gear_change_rpm: f64::INFINITY,
                rows: vec![SpindleSpeedRow {
                    speed_rpm: if spindle_rpm.is_finite() && spindle_rpm > 0.0 {
                        spindle_rpm
                    } else {
                        1.0
                    },
                    idle_current_a: 0.0,
                    sensitivity_a_per_n: 1.0,
                    quality,
                    current_range_a: unbounded,
                }],
            },
            speed: FvSpeedModel {
                gear_change_rpm: f64::INFINITY,
                low_range_v_per_rpm: f64::NAN,
                high_range_v_per_rpm: f64::NAN,
            },
        },
    }
}

/// The low-pass a log can take: the given cut-off, or none (infinite) for an RMS column or a
/// cut-off at or above the Nyquist frequency, with a note saying so.
fn chain_lowpass(
    cutoff_hz: f64,
    motor: &str,
    feedback_motor: bool,
    has_phases: bool,
    has_rms: bool,
    sample_rate_hz: f64,
    notes: &mut Vec<String>,
) -> f64 {
    let readable = crate::input::readable;
    if !has_phases {
        if has_rms && feedback_motor {
            notes.push(format!(
                "the {motor} current is an RMS value in the log: the chain's low-pass and \
                 three-phase RMS stages are skipped (they act on phase currents); the period mean \
                 of the logged value is the current"
            ));
        }
        return f64::INFINITY;
    }
    if cutoff_hz >= 0.5 * sample_rate_hz {
        if feedback_motor {
            notes.push(format!(
            "the log samples at {} Hz: the {motor} low-pass at {} Hz is at or above its Nyquist \
             frequency ({} Hz), so that stage is skipped",
            readable(sample_rate_hz),
            readable(cutoff_hz),
            readable(0.5 * sample_rate_hz)
            ));
        }
        return f64::INFINITY;
    }
    cutoff_hz
}

fn prepare(
    log: &Arc<Log>,
    mapping: &Mapping,
    settings: &ReplaySettings,
    for_calibration: bool,
) -> Result<Prepared, ReplayError> {
    let columns = mapping.resolve(log)?;
    let mut notes = Vec::new();
    let sample_period_s = settings
        .sample_period_s
        .or(log.sample_period_s)
        .filter(|p| p.is_finite() && *p > 0.0)
        .ok_or_else(|| {
            setting(
                "the log's sample period is unknown: it has no time column; give the sample \
                 period (--sample-period-s)",
            )
        })?;
    let rate_hz = 1.0 / sample_period_s;
    let feedback = settings.feedback;
    let (phases, rms) = match feedback {
        Feedback::SpindleCurrent => (Channel::SpindlePhase, Channel::SpindleCurrent),
        Feedback::FeedCurrent => (Channel::FeedPhase, Channel::FeedCurrent),
        Feedback::Dynamometer => (Channel::Force, Channel::Force),
    };
    if columns.columns(phases).is_empty() && columns.column(rms).is_none() {
        return Err(setting(match feedback {
            Feedback::Dynamometer => {
                "dynamometer feedback replays a measured force: map a force column".to_string()
            }
            _ => format!(
                "{} feedback needs the {} current: map its phase currents or its RMS column",
                feedback.name(),
                feedback.name()
            ),
        }));
    }
    if feedback == Feedback::FeedCurrent && columns.column(Channel::Feed).is_none() {
        return Err(setting(
            "feed-current feedback needs the feed (paper 000's model reads the idle current \
             from it): map a feed column",
        ));
    }
    let spindle_phases = !columns.columns(Channel::SpindlePhase).is_empty();
    let feed_phases = !columns.columns(Channel::FeedPhase).is_empty();
    for (has_phases, rms_channel, motor) in [
        (spindle_phases, Channel::SpindleCurrent, "spindle"),
        (feed_phases, Channel::FeedCurrent, "feed-drive"),
    ] {
        if has_phases && columns.column(rms_channel).is_some() {
            notes.push(format!(
                "the {motor} phase currents are used; its RMS column is not"
            ));
        }
        let phase_count = columns
            .columns(if motor == "spindle" {
                Channel::SpindlePhase
            } else {
                Channel::FeedPhase
            })
            .len();
        match phase_count {
            2 => notes.push(format!(
                "two {motor} phases: the third is −(i_u + i_v) (Kirchhoff's current law)"
            )),
            1 => notes.push(format!(
                "one {motor} phase: it stands for the three, scaled to read a sinusoidal \
                 current's RMS"
            )),
            _ => {}
        }
    }
    let spindle_lowpass_hz = chain_lowpass(
        settings.spindle_lowpass_hz,
        "spindle",
        feedback != Feedback::FeedCurrent,
        spindle_phases,
        columns.column(Channel::SpindleCurrent).is_some(),
        rate_hz,
        &mut notes,
    );
    let feed_lowpass_hz = chain_lowpass(
        settings.feed_lowpass_hz,
        "feed-drive",
        feedback == Feedback::FeedCurrent,
        feed_phases,
        columns.column(Channel::FeedCurrent).is_some(),
        rate_hz,
        &mut notes,
    );

    // The speed: the column's mean for the control period, else the one given or calibrated.
    let calibration = settings.calibration.as_ref();
    let calibrated_rpm = match calibration.map(|c| &c.estimator) {
        Some(Estimator::Spindle { model, .. }) => model.rows.first().map(|r| r.speed_rpm),
        _ => None,
    };
    let speed_column = columns.column(Channel::SpindleSpeed);
    if speed_column.is_none() {
        notes.push(match settings.spindle_rpm.or(calibrated_rpm) {
            Some(rpm) => format!(
                "no spindle-speed column: the speed is taken as {} rpm throughout",
                crate::input::readable(rpm)
            ),
            None => "no spindle-speed column and no speed given: the spindle is taken to run \
                     from the first row"
                .to_string(),
        });
    }
    let spindle_rpm = settings.spindle_rpm.or(calibrated_rpm).unwrap_or(1000.0);
    let typical_rpm = match speed_column {
        Some(c) => column_mean(log, Some(c)),
        None => spindle_rpm,
    };
    let control_period_s = match settings.control_period_s {
        Some(p) => p,
        None => {
            let base = if typical_rpm.is_finite() && typical_rpm > SPINDLE_RUNNING_RPM {
                let revolution_s = 60.0 / typical_rpm;
                (MIN_CONTROL_PERIOD_S / revolution_s).ceil() * revolution_s
            } else {
                MIN_CONTROL_PERIOD_S
            };
            // A whole number of log samples, at least one.
            (base / sample_period_s).round().max(1.0) * sample_period_s
        }
    };
    if !(control_period_s.is_finite() && control_period_s > 0.0) {
        return Err(setting(format!(
            "the control period must be a positive time, not {control_period_s} s"
        )));
    }
    if control_period_s < 0.999 * sample_period_s {
        return Err(setting(format!(
            "the control period ({} s) is shorter than the log's sample period ({} s)",
            crate::input::readable(control_period_s),
            crate::input::readable(sample_period_s)
        )));
    }

    // The estimator and the target.
    let (estimator, calibrated) = match calibration {
        Some(c) => {
            if c.estimator.feedback() != feedback {
                return Err(setting(format!(
                    "the calibration is for {} feedback, the replay measures with {}",
                    c.estimator.feedback().name(),
                    feedback.name()
                )));
            }
            (c.estimator.clone(), true)
        }
        None if feedback == Feedback::Dynamometer => (Estimator::Dynamometer, true),
        None => (current_as_force(feedback, spindle_rpm), false),
    };
    let typical_feed = column_mean(log, columns.column(Channel::Feed));
    let (target, target_force_n) =
        match (settings.target, calibrated) {
            (Some(Target::ForceN(f)), true) => (Target::ForceN(f), f),
            (Some(Target::ForceN(_)), false) => return Err(setting(
                "a force target needs a calibration (a saved calibration file, or calibrate from \
                 a log with a force); without one give a current target",
            )),
            (Some(Target::CurrentA(a)), true) => (
                Target::CurrentA(a),
                estimator.force_for_current_n(a, typical_rpm, typical_feed),
            ),
            (Some(Target::CurrentA(a)), false) => (Target::CurrentA(a), a),
            (None, true) => {
                let f = 0.8 * calibration.map_or(f64::NAN, |c| c.median_force_at_full_override_n);
                notes.push(format!(
                "no target given: 80 % of the calibration's median force at full override, {} N",
                crate::input::readable(f)
            ));
                (Target::ForceN(f), f)
            }
            (None, false) if for_calibration => (Target::CurrentA(1.0), 1.0),
            (None, false) => return Err(setting(
                "no calibration, so the controllers regulate the current: give a current target \
                 (--target-a)",
            )),
        };
    if !(target_force_n.is_finite() && target_force_n > 0.0) {
        return Err(setting(format!(
            "the target must be positive; it comes to {} here",
            crate::input::readable(target_force_n)
        )));
    }
    if !calibrated {
        notes.push(
            "no calibration: the controllers regulate the current itself (the force they see is \
             the current in A, and force_est_n is left out)"
                .to_string(),
        );
    }
    let mut envelope = settings.envelope.clone();
    envelope.overload_limit_n = OVERLOAD_FACTOR * target_force_n;
    let stuck_s = STUCK_SAMPLES * sample_period_s;
    if envelope.stuck_after_s < stuck_s {
        envelope.stuck_after_s = stuck_s;
    }
    if let Some(c) = calibration {
        if c.max_phase_current_a.is_finite() && c.max_phase_current_a > 0.0 {
            envelope.max_current_a = 2.0 * c.max_phase_current_a;
        }
    }
    let last_time_s = match columns.column(Channel::Time) {
        Some(t) => log.columns[t]
            .values
            .iter()
            .rev()
            .find(|v| v.is_finite())
            .copied()
            .unwrap_or(0.0),
        None => log.rows as f64 * sample_period_s,
    };
    let loop_settings = LoopSettings {
        feedback,
        control_period_s,
        spindle_lowpass_hz,
        feed_lowpass_hz,
        lowpass_order: settings.lowpass_order,
        target_force_n,
        force_limit_n: FORCE_LIMIT_FACTOR * target_force_n,
        envelope,
        // The log's end, not a time limit, ends a replay.
        max_duration_s: last_time_s.abs() + control_period_s + 1.0,
        cross_check_tolerance: 0.3,
    };
    let fv_v_per_rpm = match calibration.map(|c| &c.estimator) {
        Some(Estimator::Spindle { speed, .. }) => (
            speed.low_range_v_per_rpm,
            speed.high_range_v_per_rpm,
            speed.gear_change_rpm,
        ),
        _ => (f64::NAN, f64::NAN, GEAR_CHANGE_RPM),
    };
    let machine = LogMachine::new(
        log.clone(),
        mapping,
        LogSource {
            sample_period_s,
            spindle_rpm,
            fv_v_per_rpm,
        },
    )?;
    Ok(Prepared {
        machine,
        settings: loop_settings,
        estimator,
        notes,
        target,
        calibrated,
        spindle_rpm: typical_rpm,
    })
}

/// One controller replayed on a log: the lab's closed loop on a [`LogMachine`], done a piece at
/// a time ([`Work`]).
pub struct ReplayRun {
    name: String,
    controller: ControllerConfig,
    /// The loop, until its trace is taken.
    run: Option<ClosedLoop>,
    notes: Vec<String>,
    target: Target,
    calibrated: bool,
    duration_s: f64,
    rows: usize,
    done: Option<ReplayResult>,
}

impl ReplayRun {
    /// Replays `controller` on `log` read through `mapping`.
    pub fn new(
        log: &Arc<Log>,
        mapping: &Mapping,
        settings: &ReplaySettings,
        controller: &ControllerConfig,
    ) -> Result<Self, ReplayError> {
        let p = prepare(log, mapping, settings, false)?;
        let sensitivity = p.estimator.sensitivity_a_per_n(p.spindle_rpm);
        let built = controller
            .build(&RunContext {
                target_force_n: p.settings.target_force_n,
                control_period_s: p.settings.control_period_s,
                amps_per_newton: if sensitivity.is_finite() {
                    sensitivity
                } else {
                    f64::NAN
                },
            })
            .map_err(LoopError::Controller)?;
        let rows = p.machine.rows();
        let duration_s = p.settings.max_duration_s;
        let run = ClosedLoop::new(Box::new(p.machine), built, p.estimator, p.settings)?;
        Ok(Self {
            name: controller.kind().name().to_string(),
            controller: controller.clone(),
            run: Some(run),
            notes: p.notes,
            target: p.target,
            calibrated: p.calibrated,
            duration_s,
            rows,
            done: None,
        })
    }
}

impl Work for ReplayRun {
    type Output = ReplayResult;
    type Error = ReplayError;

    /// Replays at most `budget` control periods.
    fn advance(&mut self, budget: usize) -> Result<bool, ReplayError> {
        let Some(run) = &mut self.run else {
            return Ok(true);
        };
        if run.advance(budget)? {
            let settings = run.settings().clone();
            let trace = self
                .run
                .take()
                .map(ClosedLoop::into_trace)
                .unwrap_or_default();
            let summary = ReplaySummary::of(&trace, &settings, self.calibrated);
            self.done = Some(ReplayResult {
                name: self.name.clone(),
                controller: self.controller.clone(),
                settings,
                target: self.target,
                calibrated: self.calibrated,
                notes: self.notes.clone(),
                rows: self.rows,
                summary,
                trace,
            });
            return Ok(true);
        }
        Ok(false)
    }

    fn progress(&self) -> Progress {
        Progress::new(
            format!("Replaying {}", self.name),
            self.run
                .as_ref()
                .map_or(1.0, |r| r.elapsed_s() / self.duration_s.max(1e-9)),
        )
    }

    fn finish(&mut self) -> Result<ReplayResult, ReplayError> {
        self.done
            .take()
            .ok_or(ReplayError::Loop(LoopError::NotFinished))
    }
}

/// Several controllers replayed on one log, one after another (the Logs page's comparison).
pub struct ReplayRuns {
    log: Arc<Log>,
    mapping: Mapping,
    settings: ReplaySettings,
    controllers: Vec<ControllerConfig>,
    current: Option<ReplayRun>,
    results: Vec<Arc<ReplayResult>>,
}

impl ReplayRuns {
    /// `controllers` replayed in turn on `log`.
    pub fn new(
        log: Arc<Log>,
        mapping: Mapping,
        settings: ReplaySettings,
        controllers: Vec<ControllerConfig>,
    ) -> Self {
        Self {
            log,
            mapping,
            settings,
            controllers,
            current: None,
            results: Vec::new(),
        }
    }
}

impl Work for ReplayRuns {
    type Output = Vec<Arc<ReplayResult>>;
    type Error = ReplayError;

    fn advance(&mut self, budget: usize) -> Result<bool, ReplayError> {
        let Some(controller) = self.controllers.get(self.results.len()) else {
            return Ok(true);
        };
        let run = match &mut self.current {
            Some(run) => run,
            None => self.current.insert(ReplayRun::new(
                &self.log,
                &self.mapping,
                &self.settings,
                controller,
            )?),
        };
        if run.advance(budget)? {
            let result = run.finish()?;
            self.results.push(Arc::new(result));
            self.current = None;
        }
        Ok(self.results.len() >= self.controllers.len())
    }

    fn progress(&self) -> Progress {
        let total = self.controllers.len().max(1);
        let index = self.results.len();
        let part = self.current.as_ref().map_or(0.0, |r| r.progress().fraction);
        Progress::new(
            format!("Replaying controller {} of {total}", (index + 1).min(total)),
            (index as f64 + part) / total as f64,
        )
    }

    fn finish(&mut self) -> Result<Self::Output, ReplayError> {
        if self.results.len() < self.controllers.len() {
            return Err(ReplayError::Loop(LoopError::NotFinished));
        }
        Ok(std::mem::take(&mut self.results))
    }
}

/// What the envelope did in one control period.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum EnvelopeState {
    /// Before arming: the arming override holds.
    Disarmed,
    /// The controller's request went through (quantised).
    Armed,
    /// The request was clamped to the override band or rate-limited.
    Limited,
    /// A sensor fault: the override is held (or falls back).
    SensorFault,
    /// The overload alarm latched feed hold.
    FeedHold,
}

impl EnvelopeState {
    /// The state of `row`, with `step_pct` the machine's override step (a difference below half
    /// a step is quantisation, not a limit).
    pub fn of(row: &TraceRow, step_pct: f64) -> Self {
        if row.feed_hold {
            EnvelopeState::FeedHold
        } else if row.sensor_fault {
            EnvelopeState::SensorFault
        } else if !row.armed {
            EnvelopeState::Disarmed
        } else if (row.requested_override_pct - row.override_pct).abs() > 0.5 * step_pct + 1e-9 {
            EnvelopeState::Limited
        } else {
            EnvelopeState::Armed
        }
    }

    /// The name in the CSV.
    pub fn name(self) -> &'static str {
        match self {
            EnvelopeState::Disarmed => "disarmed",
            EnvelopeState::Armed => "armed",
            EnvelopeState::Limited => "limited",
            EnvelopeState::SensorFault => "sensor-fault",
            EnvelopeState::FeedHold => "feed-hold",
        }
    }
}

/// A replay's numbers in brief.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReplaySummary {
    /// Control periods replayed.
    pub periods: usize,
    /// Time of the last period's end.
    pub end_time_s: f64,
    /// When the envelope armed (`None`: never).
    pub armed_at_s: Option<f64>,
    /// Smallest, mean and largest commanded override over the armed periods.
    pub override_min_pct: Option<f64>,
    /// Mean commanded override over the armed periods.
    pub override_mean_pct: Option<f64>,
    /// Largest commanded override over the armed periods.
    pub override_max_pct: Option<f64>,
    /// Mean override the machine applied (the log's), over the same periods.
    pub logged_override_mean_pct: Option<f64>,
    /// Periods whose request the envelope clamped or rate-limited.
    pub periods_limited: usize,
    /// Time under a sensor fault.
    pub sensor_fault_s: f64,
    /// Sensor faults detected.
    pub sensor_faults: usize,
    /// When the overload alarm latched feed hold (`None`: never).
    pub overload_at_s: Option<f64>,
    /// Mean and largest force estimate over the armed periods (calibrated replays).
    pub force_est_mean_n: Option<f64>,
    /// Largest force estimate over the armed periods.
    pub force_est_max_n: Option<f64>,
    /// Mean of the log's measured force over the armed periods, if it has one.
    pub force_mean_n: Option<f64>,
}

impl ReplaySummary {
    fn of(trace: &Trace, settings: &LoopSettings, calibrated: bool) -> Self {
        let step = settings.envelope.resolution.step_pct();
        let armed: Vec<&TraceRow> = trace.rows.iter().filter(|r| r.armed).collect();
        let stat = |f: fn(&TraceRow) -> f64| {
            let values: Vec<f64> = armed
                .iter()
                .map(|r| f(r))
                .filter(|v| v.is_finite())
                .collect();
            if values.is_empty() {
                return (None, None, None);
            }
            let lo = values.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let mean = values.iter().sum::<f64>() / values.len() as f64;
            (Some(lo), Some(mean), Some(hi))
        };
        let (override_min_pct, override_mean_pct, override_max_pct) = stat(|r| r.override_pct);
        let (_, logged_override_mean_pct, _) = stat(|r| r.applied_override_pct);
        let (_, force_est_mean_n, force_est_max_n) = if calibrated {
            stat(|r| r.force_est_n)
        } else {
            (None, None, None)
        };
        let (_, force_mean_n, _) = stat(|r| r.force_n);
        Self {
            periods: trace.rows.len(),
            end_time_s: trace.rows.last().map_or(0.0, |r| r.time_s),
            armed_at_s: trace.events.iter().find_map(|e| match e {
                SafetyEvent::Armed { time_s } => Some(*time_s),
                _ => None,
            }),
            override_min_pct,
            override_mean_pct,
            override_max_pct,
            logged_override_mean_pct,
            periods_limited: trace
                .rows
                .iter()
                .filter(|r| EnvelopeState::of(r, step) == EnvelopeState::Limited)
                .count(),
            sensor_fault_s: trace.rows.iter().filter(|r| r.sensor_fault).count() as f64
                * settings.control_period_s,
            sensor_faults: trace
                .events
                .iter()
                .filter(|e| matches!(e, SafetyEvent::FaultDetected { .. }))
                .count(),
            overload_at_s: trace.events.iter().find_map(|e| match e {
                SafetyEvent::Overload { time_s, .. } => Some(*time_s),
                _ => None,
            }),
            force_est_mean_n,
            force_est_max_n,
            force_mean_n,
        }
    }
}

/// One controller replayed on a log.
#[derive(Debug, Clone, PartialEq)]
pub struct ReplayResult {
    /// The controller's name.
    pub name: String,
    /// The controller and its parameters.
    pub controller: ControllerConfig,
    /// The loop's settings as replayed (low-passes skipped are infinite).
    pub settings: LoopSettings,
    /// The target as given.
    pub target: Target,
    /// Whether a calibration turned current into force.
    pub calibrated: bool,
    /// What the replay adapted to the log (stages skipped, columns completed), for people.
    pub notes: Vec<String>,
    /// Rows of the log.
    pub rows: usize,
    /// The numbers in brief.
    pub summary: ReplaySummary,
    /// One row per control period, and the envelope's events.
    pub trace: Trace,
}

impl ReplayResult {
    /// The regulated current of a period (the feedback path's), A.
    pub fn current_a(&self, row: &TraceRow) -> f64 {
        match self.settings.feedback {
            Feedback::FeedCurrent => row.feed_current_rms_a,
            _ => row.spindle_current_rms_a,
        }
    }

    /// The envelope's state in each period.
    pub fn envelope_state(&self, row: &TraceRow) -> EnvelopeState {
        EnvelopeState::of(row, self.settings.envelope.resolution.step_pct())
    }
}

/// Writes replays as CSV, one row per control period (and per replay, named in a first `run`
/// column when there are several): `time_s`, `current_a`, `force_est_n` (calibrated replays),
/// `requested_override_pct`, `override_pct`, `envelope_state`, `logged_override_pct`, and
/// `force_n` where the log measured a force.
///
/// ```
/// use cutlab::log::replay::write_replay_csv;
/// let mut out = Vec::new();
/// write_replay_csv(&[], &mut out).unwrap();
/// assert!(String::from_utf8(out).unwrap().starts_with("time_s,current_a,"));
/// ```
pub fn write_replay_csv(
    runs: &[&ReplayResult],
    out: &mut dyn std::io::Write,
) -> std::io::Result<()> {
    let named = runs.len() > 1;
    let calibrated = runs.iter().any(|r| r.calibrated);
    let force = runs
        .iter()
        .any(|r| r.trace.rows.iter().any(|row| row.force_n.is_finite()));
    let mut header = Vec::new();
    if named {
        header.push("run");
    }
    header.extend(["time_s", "current_a"]);
    if calibrated {
        header.push("force_est_n");
    }
    header.extend([
        "requested_override_pct",
        "override_pct",
        "envelope_state",
        "logged_override_pct",
    ]);
    if force {
        header.push("force_n");
    }
    writeln!(out, "{}", header.join(","))?;
    for run in runs {
        let name = csv_field(&run.name);
        for row in &run.trace.rows {
            let mut line = Vec::with_capacity(header.len());
            if named {
                line.push(name.clone());
            }
            line.push(row.time_s.to_string());
            line.push(run.current_a(row).to_string());
            if calibrated {
                line.push(if run.calibrated {
                    row.force_est_n.to_string()
                } else {
                    "NaN".into()
                });
            }
            line.push(row.requested_override_pct.to_string());
            line.push(row.override_pct.to_string());
            line.push(run.envelope_state(row).name().to_string());
            line.push(row.applied_override_pct.to_string());
            if force {
                line.push(row.force_n.to_string());
            }
            writeln!(out, "{}", line.join(","))?;
        }
    }
    Ok(())
}

/// One event of a replay, for the JSON report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EventReport {
    /// When.
    pub time_s: f64,
    /// What, in a word: `armed`, `sensor-fault`, `fault-cleared`, `overload`,
    /// `controller-fault`, `cut-before-arming`.
    pub kind: &'static str,
    /// What, in a sentence.
    pub message: String,
}

/// The events of a replay, for people and the JSON report.
pub fn events(trace: &Trace) -> Vec<EventReport> {
    trace
        .events
        .iter()
        .map(|e| EventReport {
            time_s: e.time_s(),
            kind: match e {
                SafetyEvent::Armed { .. } => "armed",
                SafetyEvent::FaultDetected { .. } => "sensor-fault",
                SafetyEvent::FaultCleared { .. } => "fault-cleared",
                SafetyEvent::Overload { .. } => "overload",
                SafetyEvent::ControllerFault { .. } => "controller-fault",
                SafetyEvent::CutBeforeArming { .. } => "cut-before-arming",
                SafetyEvent::AirCut { .. } => "air-cut",
            },
            message: e.describe(),
        })
        .collect()
}

/// Where a calibration from a log takes its force.
#[derive(Debug, Clone, PartialEq)]
pub enum ForceSource {
    /// The log's measured force (the [`Channel::Force`] column).
    Measured,
    /// The mean force of the cut, modelled from each period's feed and speed (as `cutlab
    /// calibrate --material` does): for a log without a dynamometer.
    CutModel {
        /// Cutter, milling mode and material.
        geometry: CutGeometry,
        /// Axial depth; `None` reads the [`Channel::Depth`] column.
        depth_mm: Option<f64>,
        /// Radial width.
        width_mm: f64,
    },
}

/// One control period a calibration used: its current and force.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FitPoint {
    /// The period's end.
    pub time_s: f64,
    /// Its RMS current after the signal chain.
    pub current_a: f64,
    /// Its force (measured or modelled).
    pub force_n: f64,
    /// Its spindle speed, as the estimator reads it.
    pub speed_rpm: f64,
    /// Its feed.
    pub feed_mm_min: f64,
}

/// A calibration made from a log, with the points it was fitted to.
#[derive(Debug, Clone, PartialEq)]
pub struct LogFit {
    /// The calibration (the same kind a teach cut makes, so a replay, a run or a saved file can
    /// use it).
    pub calibration: Calibration,
    /// The periods used, for plotting the fit.
    pub points: Vec<FitPoint>,
    /// What was left out and why.
    pub notes: Vec<String>,
    /// Where the force came from, for people and the saved file.
    pub force_source: String,
}

impl LogFit {
    /// The model's current for `force_n` at a period's speed and feed (to draw the fitted line).
    pub fn model_current_a(&self, point: &FitPoint, force_n: f64) -> f64 {
        self.calibration
            .estimator
            .current_for_force_a(force_n, point.speed_rpm, point.feed_mm_min)
    }

    /// One line for people: the fit's quality.
    pub fn quality(&self) -> String {
        let readable = crate::input::readable;
        match &self.calibration.estimator {
            Estimator::Spindle { model, .. } => model
                .rows
                .iter()
                .map(|r| {
                    format!(
                        "at {} rpm: I = {} A + {} A/N · F, R² {:.4}, residual {} A (≈ {} N), {} \
                         periods",
                        readable(r.speed_rpm),
                        readable(r.idle_current_a),
                        readable(r.sensitivity_a_per_n),
                        r.quality.r_squared,
                        readable(r.quality.residual_std_a),
                        readable(r.quality.residual_std_n),
                        r.quality.samples
                    )
                })
                .collect::<Vec<_>>()
                .join("; "),
            Estimator::Feed { model } => format!(
                "I = {} A + {} A/(mm/min) · |v| + {} A/N · F, R² {:.4}, residual {} A (≈ {} N), \
                 {} periods",
                readable(model.idle_current_a),
                readable(model.idle_current_a_per_mm_min),
                readable(model.sensitivity_a_per_n),
                model.quality.r_squared,
                readable(model.quality.residual_std_a),
                readable(model.quality.residual_std_n),
                model.quality.samples
            ),
            Estimator::Dynamometer => "a dynamometer needs no fit".to_string(),
        }
    }
}

/// A period whose current is within this fraction of the log's lowest is taken for air by the
/// cut-model force (which gives a force whenever the axes feed).
const AIR_CURRENT_MARGIN: f64 = 0.02;
/// A period whose speed moved more than this fraction since the one before is the spindle
/// accelerating: its current says nothing about the load.
const STEADY_SPEED_FRACTION: f64 = 0.01;

/// Fits the current → force model of `settings.feedback` to a log: the log runs through the
/// replay's own signal chain (the same low-pass, RMS and control period a replay uses), and each
/// period's current is paired with the force from `force`. Periods without a positive force, with
/// an accelerating spindle, or (for the cut model) in air are left out.
pub fn fit_calibration(
    log: &Arc<Log>,
    mapping: &Mapping,
    settings: &ReplaySettings,
    force: &ForceSource,
) -> Result<LogFit, ReplayError> {
    LogFitWork::new(log, mapping, settings, force)?.run_to_end()
}

/// [`fit_calibration`] done a piece at a time: the chain runs a budget of control periods per
/// call, the fit at the end.
pub struct LogFitWork {
    machine: LogMachine,
    chain: SignalChain,
    per_period: usize,
    feedback: Feedback,
    force: ForceSource,
    force_source: String,
    notes: Vec<String>,
    has_fv: bool,
    rms_only: bool,
    periods: Vec<(PeriodSummary, f64)>,
    /// Per period: whether the override changed less than [`SETTLE_AFTER_CHANGE_S`] before its end.
    settling: Vec<bool>,
    last_override_pct: f64,
    last_change_s: f64,
    max_phase_a: f64,
    output: Option<LogFit>,
    done: bool,
}

/// Periods ending this soon after the logged override changed are left out of a fit: the feed and
/// the currents are still moving to the new level (as in the lab's teach cut).
const SETTLE_AFTER_CHANGE_S: f64 = 0.5;

impl LogFitWork {
    /// Sets up the chain; a missing column or setting is an error saying what to give.
    pub fn new(
        log: &Arc<Log>,
        mapping: &Mapping,
        settings: &ReplaySettings,
        force: &ForceSource,
    ) -> Result<Self, ReplayError> {
        if settings.feedback == Feedback::Dynamometer {
            return Err(setting(
                "a dynamometer reads the force itself: there is no current model to fit",
            ));
        }
        let columns = mapping.resolve(log)?;
        let force_source = match force {
            ForceSource::Measured => {
                let Some(c) = columns.column(Channel::Force) else {
                    return Err(setting(
                        "the log has no measured force mapped: map a force column, or model the \
                         force from the cut",
                    ));
                };
                format!("the log's measured force ({})", log.columns[c].name)
            }
            ForceSource::CutModel {
                geometry,
                depth_mm,
                width_mm,
            } => {
                if depth_mm.is_none() && columns.column(Channel::Depth).is_none() {
                    return Err(setting(
                        "the cut model needs the depth: give it, or map a depth column",
                    ));
                }
                if columns.column(Channel::Feed).is_none() {
                    return Err(setting("the cut model needs the feed: map a feed column"));
                }
                format!(
                    "the mechanistic model of the cut (Ø{} mm, {} teeth, {} milling, depth {}, \
                     width {} mm)",
                    crate::input::readable(geometry.cutter.diameter_mm),
                    geometry.cutter.teeth,
                    geometry.mode.name(),
                    depth_mm.map_or("from the log".to_string(), |d| format!(
                        "{} mm",
                        crate::input::readable(d)
                    )),
                    crate::input::readable(*width_mm)
                )
            }
        };
        let mut calibration_settings = settings.clone();
        calibration_settings.calibration = None;
        let p = prepare(log, mapping, &calibration_settings, true)?;
        let mut notes = p.notes;
        notes.retain(|n| !n.starts_with("no calibration"));
        let sample_rate_hz = p.machine.sample_rate_hz();
        let s = &p.settings;
        let lowpass = |cutoff_hz: f64| -> Result<crate::signal::sos::Sos, ReplayError> {
            if cutoff_hz == f64::INFINITY {
                return crate::signal::sos::Sos::from_rows(&[[1.0, 0.0, 0.0, 1.0, 0.0, 0.0]])
                    .map_err(|e| setting(format!("low-pass: {e}")));
            }
            crate::signal::butterworth::butter(&crate::signal::butterworth::ButterworthSpec {
                kind: crate::signal::butterworth::FilterKind::Lowpass,
                order: s.lowpass_order,
                cutoff_hz: crate::signal::butterworth::Cutoff::Single(cutoff_hz),
                sample_rate_hz,
            })
            .map_err(|e| setting(format!("low-pass: {e}")))
        };
        let chain = SignalChain::new(
            &lowpass(s.spindle_lowpass_hz)?,
            &lowpass(s.feed_lowpass_hz)?,
        )
        .map_err(|_| setting("the signal chain has no channels"))?;
        let per_period = (s.control_period_s * sample_rate_hz).round().max(1.0) as usize;
        // An RMS column stands for three phases of its own value; a phase's peak is √2 of it.
        let rms_only = columns
            .columns(match settings.feedback {
                Feedback::FeedCurrent => Channel::FeedPhase,
                _ => Channel::SpindlePhase,
            })
            .is_empty();
        Ok(Self {
            machine: p.machine,
            chain,
            per_period,
            feedback: settings.feedback,
            force: force.clone(),
            force_source,
            notes,
            has_fv: columns.column(Channel::FvVoltage).is_some(),
            rms_only,
            periods: Vec::new(),
            settling: Vec::new(),
            last_override_pct: f64::NAN,
            last_change_s: f64::NEG_INFINITY,
            max_phase_a: 0.0,
            output: None,
            done: false,
        })
    }

    /// Runs the chain over one control period of the log.
    fn period(&mut self) {
        let mut override_sum = 0.0;
        let mut n = 0usize;
        while n < self.per_period && !self.machine.finished() {
            let step = self.machine.step(OverrideCommand::default());
            for i in step
                .sensors
                .spindle_phase_currents_a
                .iter()
                .chain(&step.sensors.feed_phase_currents_a)
            {
                if i.is_finite() {
                    self.max_phase_a = self.max_phase_a.max(i.abs());
                }
            }
            self.chain.push(&step);
            let pct = step.sensors.applied_override_pct;
            if self.last_override_pct.is_finite() && pct != self.last_override_pct {
                self.last_change_s = step.sensors.time_s;
            }
            self.last_override_pct = pct;
            override_sum += pct;
            n += 1;
        }
        if n > 0 {
            let period = self.chain.finish_period();
            self.settling
                .push(period.end_time_s - self.last_change_s < SETTLE_AFTER_CHANGE_S);
            self.periods.push((period, override_sum / n as f64));
        }
    }

    /// Pairs each period's current with its force and fits.
    fn fit(&mut self) -> Result<LogFit, ReplayError> {
        let periods = std::mem::take(&mut self.periods);
        let feedback = self.feedback;
        let force = &self.force;
        let fv_model = if self.has_fv {
            let commands: Vec<f64> = periods.iter().map(|(p, _)| p.spindle_command_rpm).collect();
            let speeds: Vec<f64> = periods.iter().map(|(p, _)| p.spindle_speed_rpm).collect();
            let volts: Vec<f64> = periods
                .iter()
                .map(|(p, _)| p.spindle_fv_voltage_v)
                .collect();
            FvSpeedModel::calibrate(&commands, &speeds, &volts, GEAR_CHANGE_RPM)
        } else {
            FvSpeedModel {
                gear_change_rpm: GEAR_CHANGE_RPM,
                low_range_v_per_rpm: f64::NAN,
                high_range_v_per_rpm: f64::NAN,
            }
        };
        let current_of = |p: &PeriodSummary| match feedback {
            Feedback::FeedCurrent => p.feed_current_rms_a,
            _ => p.spindle_current_rms_a,
        };
        let force_of = |p: &PeriodSummary| match force {
            ForceSource::Measured => p.force_mean_resultant_n,
            ForceSource::CutModel {
                geometry,
                depth_mm,
                width_mm,
            } => geometry
                .mean_forces(
                    p.feed_mm_min,
                    p.spindle_speed_rpm,
                    depth_mm.unwrap_or(p.depth_mm),
                    *width_mm,
                )
                .map_or(f64::NAN, |f| match feedback {
                    Feedback::FeedCurrent => -f.fx_n,
                    _ => f.resultant_n(),
                }),
        };
        let air_a = periods
            .iter()
            .map(|(p, _)| current_of(p))
            .filter(|i| i.is_finite())
            .fold(f64::INFINITY, f64::min);
        let mut points = Vec::new();
        let mut full_override_forces = Vec::new();
        let mut previous_rpm = f64::NAN;
        let (mut accelerating, mut air, mut no_force, mut settling) = (0, 0, 0, 0usize);
        for (k, (p, mean_override)) in periods.iter().enumerate() {
            let current_a = current_of(p);
            let force_n = force_of(p);
            let speed_rpm = fv_model.speed_rpm(p.spindle_fv_voltage_v, p.spindle_command_rpm);
            let steady = !(previous_rpm.is_finite()
                && (p.spindle_speed_rpm - previous_rpm).abs()
                    > STEADY_SPEED_FRACTION * p.spindle_speed_rpm.abs());
            previous_rpm = p.spindle_speed_rpm;
            if !(current_a.is_finite() && force_n.is_finite() && force_n > 0.0) {
                no_force += 1;
                continue;
            }
            if !steady {
                accelerating += 1;
                continue;
            }
            if self.settling.get(k).copied().unwrap_or(false) {
                settling += 1;
                continue;
            }
            if matches!(force, ForceSource::CutModel { .. })
                && current_a <= air_a * (1.0 + AIR_CURRENT_MARGIN)
            {
                air += 1;
                continue;
            }
            if (mean_override - 100.0).abs() < 0.5 {
                full_override_forces.push(force_n);
            }
            points.push(FitPoint {
                time_s: p.end_time_s,
                current_a,
                force_n,
                speed_rpm,
                feed_mm_min: p.feed_mm_min,
            });
        }
        let mut notes = std::mem::take(&mut self.notes);
        notes.push(format!(
            "{} of {} control periods used ({no_force} without a positive force, {accelerating} \
             with the spindle changing speed, {settling} within {} s of an override change{})",
            points.len(),
            periods.len(),
            SETTLE_AFTER_CHANGE_S,
            if matches!(force, ForceSource::CutModel { .. }) {
                format!(", {air} in air")
            } else {
                String::new()
            }
        ));
        let currents: Vec<f64> = points.iter().map(|p| p.current_a).collect();
        let forces: Vec<f64> = points.iter().map(|p| p.force_n).collect();
        let estimator = match feedback {
            Feedback::FeedCurrent => {
                let feeds: Vec<f64> = points.iter().map(|p| p.feed_mm_min).collect();
                Estimator::Feed {
                    model: FeedCurrentModel::calibrate(&currents, &feeds, &forces)
                        .map_err(|e| setting(format!("the fit failed: {e}")))?,
                }
            }
            _ => {
                let speeds: Vec<f64> = points.iter().map(|p| p.speed_rpm).collect();
                Estimator::Spindle {
                    model: SpindleCurrentModel::calibrate(
                        &currents,
                        &speeds,
                        &forces,
                        GEAR_CHANGE_RPM,
                    )
                    .map_err(|e| setting(format!("the fit failed: {e}")))?,
                    speed: fv_model,
                }
            }
        };
        let median = |values: &mut Vec<f64>| {
            values.sort_by(f64::total_cmp);
            values.get(values.len() / 2).copied().unwrap_or(f64::NAN)
        };
        let mut reference = if full_override_forces.is_empty() {
            forces.clone()
        } else {
            full_override_forces
        };
        let median_force_at_full_override_n = median(&mut reference);
        // What the fitted model reads with the tool in air, as a simulated teach cut learns it:
        // the periods whose force said (next to) nothing, or for a modelled force, whose current
        // is the idle one.
        let air_force_estimate_n = periods
            .iter()
            .filter(|(p, _)| match force {
                ForceSource::CutModel { .. } => current_of(p) <= air_a * (1.0 + AIR_CURRENT_MARGIN),
                ForceSource::Measured => {
                    let force_n = force_of(p);
                    force_n.is_finite() && force_n.abs() < 0.02 * median_force_at_full_override_n
                }
            })
            .map(|(p, _)| estimator.estimate(p).force_n)
            .filter(|f| f.is_finite())
            .fold(f64::NAN, f64::max);
        let calibration = Calibration {
            estimator,
            air_force_estimate_n,
            median_force_at_full_override_n,
            regulated_per_resultant: 1.0,
            periods: points.len(),
            max_phase_current_a: if self.rms_only {
                self.max_phase_a * std::f64::consts::SQRT_2
            } else {
                self.max_phase_a
            },
            duration_s: periods.last().map_or(0.0, |(p, _)| p.end_time_s),
        };
        Ok(LogFit {
            calibration,
            points,
            notes,
            force_source: self.force_source.clone(),
        })
    }
}

impl Work for LogFitWork {
    type Output = LogFit;
    type Error = ReplayError;

    /// Runs the chain over at most `budget` control periods; the fit once the log has ended.
    fn advance(&mut self, budget: usize) -> Result<bool, ReplayError> {
        if self.done {
            return Ok(true);
        }
        for _ in 0..budget.max(1) {
            if self.machine.finished() {
                break;
            }
            self.period();
        }
        if self.machine.finished() {
            self.output = Some(self.fit()?);
            self.done = true;
        }
        Ok(self.done)
    }

    fn progress(&self) -> Progress {
        Progress::new(
            "Calibrating",
            self.machine.row() as f64 / self.machine.rows().max(1) as f64,
        )
    }

    fn finish(&mut self) -> Result<LogFit, ReplayError> {
        self.output
            .take()
            .ok_or(ReplayError::Loop(LoopError::NotFinished))
    }
}
