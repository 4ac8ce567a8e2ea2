//! A log as a [`Machine`]: one row per sample, whatever the command, and what the run's settings
//! need to know about it ([`LogSetup`]: its sampling, speed, feed and currents as a
//! [`MachineContext`]).
//!
//! How the log's columns become a [`crate::machine::SensorSample`] (the [`Channel`]s of a
//! [`Mapping`]):
//!
//! * **three phase currents** of a motor go in as they are; **two** are completed by Kirchhoff's
//!   current law (`i_w = −i_u − i_v`, exact for a motor without neutral); **one** stands for the
//!   three scaled so that the chain's period mean of |i| reads the RMS of a sinusoidal current
//!   (`×√3·π/(2√2)`, exact for a sine, approximate for a distorted current);
//! * an **RMS or "current feedback" value** (a drive's slow log, often 10 Hz) stands for all three
//!   phases, so the three-phase RMS of the chain gives it back (a signed value by its magnitude).
//!   Its low-pass stage is skipped, since it filters phase currents before the RMS and the log has
//!   none; so is any low-pass whose cut-off is at or above the log's Nyquist frequency
//!   ([`crate::closed_loop::settings`] decides both and says so in its notes);
//! * the **spindle speed** is also the programmed speed and the F/V converter's input (through
//!   the calibration's own slope) unless the log has those columns; without a speed column the
//!   speed is a constant (the one given, or the calibration's);
//! * the spindle **runs** while its programmed speed (or else its speed) is above 1 rpm, and a
//!   spindle already running at the log's first row is taken to start there: the envelope arms
//!   its delay after it;
//! * the **applied override** is the log's override column (100 % without one), the programmed
//!   feed the feed over it; a measured **force** and the **depth** are the run's "truth" for the
//!   plots and metrics, and the force is also a dynamometer's reading; never a controller's input.

use std::sync::Arc;

use super::mapping::{Channel, Mapping, MappingError, Resolved};
use super::Log;
use crate::closed_loop::definition::{default_band_pct_of, max_override_pct_of};
use crate::closed_loop::error::LoopError;
use crate::closed_loop::settings::{
    envelope_resolution, CurrentSignal, MachineContext, OperatingPoint, PeriodRule, RateRule,
    TimeLimit, DEFAULT_ENTRY_HOLD_S,
};
use crate::estimation::current_force::{
    FeedCurrentModel, FitQuality, Range, SpindleCurrentModel, SpindleSpeedRow,
};
use crate::estimation::estimator::{Calibration, Estimator, Feedback};
use crate::estimation::speed::{in_high_speed_range, FvSpeedModel, GEAR_CHANGE_RPM};
use crate::machine::{DynamometerReading, Machine, MachineStep, OverrideCommand, PlantTruth};
use crate::plant::cnc::OverrideMode;
use crate::plant::deflection::ErrorModel;
use crate::safety::{ArmingTrigger, ChipLoad, EnvelopeConfig};

/// A spindle at or below this speed is stopped.
const SPINDLE_RUNNING_RPM: f64 = 1.0;
/// One phase scaled so that the period mean of its magnitude reads a sine's RMS: the
/// three-phase RMS of `[k·i, 0, 0]` is `k·|i|/√3`, and a sine's mean |i| is `2√2/π` of its RMS.
const SINGLE_PHASE_SCALE: f64 =
    1.732_050_807_568_877_2 * std::f64::consts::PI / 2.828_427_124_746_19;

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

/// The mean of the finite values of a column (NaN if none).
fn column_mean(log: &Log, column: Option<usize>) -> f64 {
    column
        .and_then(|c| log.columns.get(c))
        .map_or(f64::NAN, |c| c.min_max_mean().2)
}

/// An estimator that reads the current itself as the "force" (1 A ≙ 1 unit), flagged outside any
/// calibrated range: the controllers then regulate the current.
pub fn current_as_force(feedback: Feedback, spindle_rpm: f64) -> Estimator {
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

/// Why a log could not be set up, replayed or calibrated from; the message says what to change.
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

impl ReplayError {
    /// The message for the command line: a run setting's problem names its option
    /// (`--target-a: …`), as `cutlab sim`'s do.
    pub fn for_cli(&self) -> String {
        match self {
            ReplayError::Loop(LoopError::Setting(e)) => e.for_cli(),
            other => other.to_string(),
        }
    }
}

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

/// The spindle speed taken for a log with neither a speed column nor a speed given nor a
/// calibrated one, rpm.
const FALLBACK_SPINDLE_RPM: f64 = 1000.0;

/// A log ready to run: the machine, what the run's settings need to know about it, and what was
/// taken or completed, for people.
pub struct LogSetup {
    /// The log as a machine.
    pub machine: LogMachine,
    /// Its sampling, operating point, currents and defaults.
    pub context: MachineContext,
    /// What the setup completed or assumed (a phase from Kirchhoff's law, a constant speed).
    pub notes: Vec<String>,
    /// Whether the feedback path's current is an RMS value rather than phase currents.
    pub rms_only: bool,
}

/// What is needed to set a log up beside its mapping.
#[derive(Debug, Clone, Copy)]
pub struct LogOptions<'a> {
    /// The path whose current measures the force.
    pub feedback: Feedback,
    /// The sample period of a log without a time column (overrides the time column's).
    pub sample_period_s: Option<f64>,
    /// The spindle speed when the log has no speed column (`None`: the calibration's).
    pub spindle_rpm: Option<f64>,
    /// The calibration the run will estimate with, if any (its speed and F/V slopes).
    pub calibration: Option<&'a Calibration>,
    /// The machine's override input (a log does not say: FANUC's dial unless told).
    pub override_mode: OverrideMode,
    /// The chip-load window of the tool, when known.
    pub chip_load: Option<ChipLoad>,
    /// The tool and spindle as springs, when known.
    pub error_model: Option<ErrorModel>,
}

pub(super) fn setting(message: impl Into<String>) -> ReplayError {
    ReplayError::Setting(message.into())
}

/// Sets `log` up as a machine through `mapping`: refused with a message saying what to map or
/// give when the feedback path's current (or the feed paper 000's model needs) is missing, or the
/// sample period is unknown.
pub fn log_setup(
    log: &Arc<Log>,
    mapping: &Mapping,
    options: LogOptions<'_>,
) -> Result<LogSetup, ReplayError> {
    let columns = mapping.resolve(log)?;
    let mut notes = Vec::new();
    let sample_period_s = options
        .sample_period_s
        .or(log.sample_period_s)
        .filter(|p| p.is_finite() && *p > 0.0)
        .ok_or_else(|| {
            let why = log
                .period_unknown()
                .unwrap_or_else(|| "its time steps are not positive".to_string());
            setting(format!(
                "the log's sample period is unknown: {why}; give the sample period"
            ))
        })?;
    let feedback = options.feedback;
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
    let mut signal_of = |phase_channel: Channel, rms_channel: Channel, motor: &str| {
        let phase_count = columns.columns(phase_channel).len();
        let has_rms = columns.column(rms_channel).is_some();
        if phase_count > 0 && has_rms {
            notes.push(format!(
                "the {motor} phase currents are used; its RMS column is not"
            ));
        }
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
        if phase_count == 0 && has_rms {
            CurrentSignal::Rms
        } else {
            CurrentSignal::Phases
        }
    };
    let spindle_current = signal_of(Channel::SpindlePhase, Channel::SpindleCurrent, "spindle");
    let feed_current = signal_of(Channel::FeedPhase, Channel::FeedCurrent, "feed-drive");
    let rms_only = match feedback {
        Feedback::FeedCurrent => feed_current == CurrentSignal::Rms,
        _ => spindle_current == CurrentSignal::Rms,
    };

    // The speed: the column's mean for the control period, else the one given or calibrated.
    let calibrated_rpm = match options.calibration.map(|c| &c.estimator) {
        Some(Estimator::Spindle { model, .. }) => model.rows.first().map(|r| r.speed_rpm),
        _ => None,
    };
    let speed_column = columns.column(Channel::SpindleSpeed);
    if speed_column.is_none() {
        notes.push(match options.spindle_rpm.or(calibrated_rpm) {
            Some(rpm) => format!(
                "no spindle-speed column: the speed is taken as {} rpm throughout",
                crate::input::readable(rpm)
            ),
            None => format!(
                "no spindle-speed column and no speed given: the speed is assumed to be {} rpm \
                 (the log does not say it; a fit's model is labelled with it and the control \
                 period follows it): map a spindle-speed column to use the real one",
                crate::input::readable(FALLBACK_SPINDLE_RPM)
            ),
        });
    }
    // A spindle that runs at the first row started before the log or at it: which, the log
    // cannot tell; the machine takes it to start there (see the module's documentation).
    let first_speed_rpm = columns
        .column(Channel::SpindleCommand)
        .or(speed_column)
        .map(|c| {
            log.columns[c]
                .values
                .iter()
                .copied()
                .find(|v| v.is_finite())
        });
    let runs_at_first_row = match first_speed_rpm {
        None => true,
        Some(first) => first.is_some_and(|rpm| rpm.abs() > SPINDLE_RUNNING_RPM),
    };
    if runs_at_first_row {
        notes.push(format!(
            "the spindle runs from the log's first row, so its start is assumed to be there \
             (the log does not show it): the envelope's arming delay counts from it, and a fit \
             leaves out the first {} s as the spindle's starting transient",
            crate::input::readable(crate::estimation::teach_fit::SETTLE_AFTER_SPINDLE_START_S)
        ));
    }
    let spindle_rpm = options
        .spindle_rpm
        .or(calibrated_rpm)
        .unwrap_or(FALLBACK_SPINDLE_RPM);
    let typical_rpm = match speed_column {
        Some(c) => column_mean(log, Some(c)),
        None => spindle_rpm,
    };
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
    let fv_v_per_rpm = match options.calibration.map(|c| &c.estimator) {
        Some(Estimator::Spindle { speed, .. }) => (
            speed.low_range_v_per_rpm,
            speed.high_range_v_per_rpm,
            speed.gear_change_rpm,
        ),
        _ => (f64::NAN, f64::NAN, GEAR_CHANGE_RPM),
    };
    let mode = options.override_mode;
    let context = MachineContext {
        sample_rate_hz: 1.0 / sample_period_s,
        operating_point: OperatingPoint {
            spindle_rpm: typical_rpm,
            feed_mm_min: column_mean(log, columns.column(Channel::Feed)),
        },
        default_feedback: Feedback::SpindleCurrent,
        period_rule: PeriodRule::WholeRevolutions,
        max_override_pct: max_override_pct_of(&mode),
        resolution: envelope_resolution(&mode),
        default_band_pct: default_band_pct_of(&mode),
        default_rate: RateRule::PerSecond(EnvelopeConfig::default_for_dial().max_rate_pct_per_s),
        arming_trigger: ArmingTrigger::SpindleStart,
        target_force_n: None,
        target_current_a: None,
        time_limit: TimeLimit::Record {
            duration_s: last_time_s,
        },
        spindle_current,
        feed_current,
        // A log says nothing of the cutter: the entry hold takes its default time, and the
        // chip-load window is the one given.
        entry_hold_s: DEFAULT_ENTRY_HOLD_S,
        chip_load: options.chip_load,
        error_model: options.error_model,
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
    Ok(LogSetup {
        machine,
        context,
        notes,
        rms_only,
    })
}
