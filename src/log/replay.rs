//! Replay of controllers on a recorded cut: a log as a machine ([`super::machine`]) through the
//! closed loop of every other mode.
//!
//! ```text
//! Log columns ─(Mapping)─► LogMachine::step, one row per sample at the log's rate
//!   ─► the closed loop of every other mode, unchanged (closed_loop::feedback_loop):
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
//! How the log's columns become sensor samples: [`super::machine`].
//!
//! With a calibration the estimator turns current into force as everywhere else; without one the
//! controllers regulate the current itself: the "force" they see is the current in A (flagged as
//! outside any calibrated range), and the target is a current.

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::machine::{current_as_force, log_setup, LogOptions, ReplayError};
use super::mapping::Mapping;
use super::Log;
use crate::closed_loop::definition::{RunProblem, RunSetting, SettingError, SettingsOverrides};
use crate::closed_loop::error::LoopError;
use crate::closed_loop::feedback_loop::{ClosedLoop, FeedbackLoop};
use crate::closed_loop::metrics::override_moves;
use crate::closed_loop::sample_loop::OnMachine;
use crate::closed_loop::settings::{plan, LoopSettings, TargetRule};
use crate::closed_loop::trace::{csv_field, Trace, TraceRow};
use crate::control::registry::ControllerConfig;
use crate::estimation::estimator::{Calibration, Estimator, Feedback};
use crate::estimation::teach_fit::load_level_warnings;
use crate::plant::cnc::OverrideMode;
use crate::plant::deflection::ErrorModel;
use crate::safety::{ChipLoad, SafetyEvent};
use crate::work::{Progress, Work};

/// The target a replay holds, as given (or chosen), for the report.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Target {
    /// A force, N (needs a calibration).
    ForceN(f64),
    /// A current, A: through the calibration a force, without one the regulated current itself.
    CurrentA(f64),
}

/// What a replay (or a calibration from a log) is made with, besides the log and its mapping.
/// As JSON it is what the Logs page sends a worker with a replay
/// ([`crate::log::transfer::ReplayRequest`]).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ReplaySettings {
    /// The override input of the machine the log was recorded on (a log does not say: FANUC's
    /// dial by default), which decides the positions the envelope commands and its highest.
    pub override_mode: OverrideMode,
    /// The run's settings, rows of the run definition as a lab run's are
    /// ([`crate::closed_loop::definition::RunSetting`]): the feedback path (without one, the
    /// calibration's, else the spindle), the target force or current (without one, 80 % of the
    /// calibration's force at full override), the control period, the low-passes and the
    /// override band. They resolve as a lab run's do ([`crate::closed_loop::settings`]).
    pub run: SettingsOverrides,
    /// The sample period of a log without a time column (overrides the time column's).
    pub sample_period_s: Option<f64>,
    /// The spindle speed when the log has no speed column (`None`: the calibration's).
    pub spindle_rpm: Option<f64>,
    /// The current → force model; `None` regulates the current itself.
    pub calibration: Option<Calibration>,
    /// The chip-load window of the tool in the work material, when known (a log does not say
    /// which cutter cut it).
    pub chip_load: Option<ChipLoad>,
    /// The tool and spindle as springs, when known: the replay's surface error (a log does not
    /// say which tool cut it).
    pub error_model: Option<ErrorModel>,
}

impl ReplaySettings {
    /// How a log is set up for these settings, measuring with `feedback` and estimating with
    /// `calibration`.
    pub fn log_options<'a>(
        &self,
        feedback: Feedback,
        calibration: Option<&'a Calibration>,
    ) -> LogOptions<'a> {
        LogOptions {
            feedback,
            sample_period_s: self.sample_period_s,
            spindle_rpm: self.spindle_rpm,
            calibration,
            override_mode: self.override_mode,
            chip_load: self.chip_load,
            error_model: self.error_model,
        }
    }

    /// The feedback path: the one asked for, else the calibration's, else the spindle's.
    pub fn feedback(&self) -> Feedback {
        self.run.feedback.unwrap_or_else(|| {
            self.calibration
                .as_ref()
                .map_or(Feedback::SpindleCurrent, |c| c.estimator.feedback())
        })
    }
}

/// A calibration that reads the current itself as the force (no calibration given): the
/// controllers then regulate the current.
fn uncalibrated(feedback: Feedback, spindle_rpm: f64) -> Calibration {
    Calibration {
        estimator: current_as_force(feedback, spindle_rpm),
        air_force_estimate_n: f64::NAN,
        median_force_at_full_override_n: f64::NAN,
        regulated_per_resultant: f64::NAN,
        periods: 0,
        // Unknown: the envelope keeps its default sensor-fault limit.
        max_phase_current_a: 0.0,
        duration_s: 0.0,
        // Nothing fitted: no line to rest on too few loads.
        few_load_levels: Some(Vec::new()),
    }
}

/// The loop of `controller` on `log` with `settings`, resolved as a lab run's.
struct Prepared {
    run: ClosedLoop,
    notes: Vec<String>,
    target: Target,
    calibrated: bool,
}

fn refuse(setting: RunSetting, why: &'static str) -> ReplayError {
    ReplayError::Loop(LoopError::Setting(SettingError {
        setting,
        problem: RunProblem::other(why),
    }))
}

fn prepare(
    log: &Arc<Log>,
    mapping: &Mapping,
    settings: &ReplaySettings,
    controller: &ControllerConfig,
) -> Result<Prepared, ReplayError> {
    let feedback = settings.feedback();
    let setup = log_setup(
        log,
        mapping,
        settings.log_options(feedback, settings.calibration.as_ref()),
    )?;
    let (calibration, calibrated) = match &settings.calibration {
        Some(c) => (c.clone(), true),
        None if feedback == Feedback::Dynamometer => (
            Calibration {
                estimator: Estimator::Dynamometer,
                ..uncalibrated(feedback, f64::NAN)
            },
            true,
        ),
        None => (
            uncalibrated(feedback, setup.context.operating_point.spindle_rpm),
            false,
        ),
    };
    let run = &settings.run;
    if !calibrated && run.target_force_n.is_some() {
        return Err(refuse(
            RunSetting::TargetForce,
            "a force target needs a calibration (a saved calibration file, or calibrate from a \
             log with a force); without one give a current target",
        ));
    }
    if !calibrated && run.target_force_n.is_none() && run.target_current_a.is_none() {
        return Err(refuse(
            RunSetting::TargetCurrent,
            "no calibration, so the controllers regulate the current: give a current target",
        ));
    }
    let plan = plan(run, controller, &setup.context)?;
    let mut notes = setup.notes;
    notes.extend(plan.notes.iter().cloned());
    let loop_settings = plan.settle(&calibration)?;
    let target = match plan.target {
        TargetRule::Current(a) => Target::CurrentA(a),
        TargetRule::FromTeachCut => {
            notes.push(format!(
                "no target given: 80 % of the calibration's median force at full override, {} N",
                crate::input::readable(loop_settings.target_force_n)
            ));
            Target::ForceN(loop_settings.target_force_n)
        }
        TargetRule::Force(_) | TargetRule::Resultant(_) => {
            Target::ForceN(loop_settings.target_force_n)
        }
    };
    if !calibrated {
        notes.push(
            "no calibration: the controllers regulate the current itself (the force they see is \
             the current in A, and force_est_n is left out)"
                .to_string(),
        );
    }
    // What a given calibration rests on, in the fit's words, as every other front end that
    // loads one says it (a line on too few load levels, or a file too old to tell).
    if settings.calibration.is_some() {
        notes.extend(load_level_warnings(&calibration));
    }
    let sample_rate_hz = setup.context.sample_rate_hz;
    let feedback_loop = FeedbackLoop::wire(
        controller,
        loop_settings,
        &calibration,
        plan.operating_point,
        sample_rate_hz,
    )?;
    Ok(Prepared {
        run: OnMachine::new_with(Box::new(setup.machine), feedback_loop),
        notes,
        target,
        calibrated,
    })
}

/// One controller replayed on a log: the lab's closed loop on a [`super::machine::LogMachine`],
/// done a piece at a time ([`Work`]).
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
        let p = prepare(log, mapping, settings, controller)?;
        Ok(Self {
            name: controller.kind().name().to_string(),
            controller: controller.clone(),
            duration_s: p.run.settings().max_duration_s,
            run: Some(p.run),
            notes: p.notes,
            target: p.target,
            calibrated: p.calibrated,
            rows: log.rows,
            done: None,
        })
    }
}

impl ReplayRun {
    /// The names and units of the replayed controller's terms, as in [`Trace::term_names`]
    /// (empty once the replay is finished).
    pub fn term_names(&self) -> Vec<(&'static str, &'static str)> {
        self.run
            .as_ref()
            .map(|r| r.trace().term_names.clone())
            .unwrap_or_default()
    }

    /// The result of this replay, not run here, had its loop traced `trace`: a worker's replay
    /// of the same controller on the same log and settings (the Logs page's,
    /// [`crate::log::transfer::ReplayParts`]).
    ///
    /// # Errors
    /// A replay already run here has no loop left to read its settings from.
    pub fn with_trace(self, trace: Trace) -> Result<ReplayResult, ReplayError> {
        let settings = self
            .run
            .as_ref()
            .map(|r| r.settings().clone())
            .ok_or(ReplayError::Loop(LoopError::NotFinished))?;
        Ok(self.result_with(settings, trace))
    }

    fn result_with(&self, settings: LoopSettings, trace: Trace) -> ReplayResult {
        let summary = ReplaySummary::of(&trace, &settings, self.calibrated);
        ReplayResult {
            name: self.name.clone(),
            controller: self.controller.clone(),
            settings,
            target: self.target,
            calibrated: self.calibrated,
            notes: self.notes.clone(),
            rows: self.rows,
            summary,
            trace,
        }
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
            self.done = Some(self.result_with(settings, trace));
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
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
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
    /// Control periods the commanded override changed in (as a run's `override_changes`).
    pub override_changes: usize,
    /// The commanded override's total variation, % (as a run's).
    pub override_total_variation_pct: f64,
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
        let (override_total_variation_pct, override_changes) = override_moves(&trace.rows);
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
            override_changes,
            override_total_variation_pct,
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

/// A replay's summary by stable names, units in the names — what a lesson's condition on a
/// replay names (`{"replay": "override_changes", …}`); `None` where the replay has no such value
/// (never armed, no calibration, no measured force).
pub fn replay_values(summary: &ReplaySummary) -> [(&'static str, Option<f64>); 16] {
    [
        ("periods", Some(summary.periods as f64)),
        ("end_time_s", Some(summary.end_time_s)),
        ("armed_at_s", summary.armed_at_s),
        ("override_min_pct", summary.override_min_pct),
        ("override_mean_pct", summary.override_mean_pct),
        ("override_max_pct", summary.override_max_pct),
        ("logged_override_mean_pct", summary.logged_override_mean_pct),
        ("override_changes", Some(summary.override_changes as f64)),
        (
            "override_total_variation_pct",
            Some(summary.override_total_variation_pct),
        ),
        ("periods_limited", Some(summary.periods_limited as f64)),
        ("sensor_fault_s", Some(summary.sensor_fault_s)),
        ("sensor_faults", Some(summary.sensor_faults as f64)),
        ("overload_at_s", summary.overload_at_s),
        ("force_est_mean_n", summary.force_est_mean_n),
        ("force_est_max_n", summary.force_est_max_n),
        ("force_mean_n", summary.force_mean_n),
    ]
}

/// The stable names of [`replay_values`].
pub fn replay_value_names() -> Vec<&'static str> {
    replay_values(&ReplaySummary::default())
        .map(|(name, _)| name)
        .to_vec()
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
    /// `controller-fault`, `cut-before-arming`, `air-cut`, `entry-hold`, `entry-settled`,
    /// `chip-load`.
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
                SafetyEvent::EntryHold { .. } => "entry-hold",
                SafetyEvent::EntrySettled { .. } => "entry-settled",
                SafetyEvent::ChipLoad { .. } => "chip-load",
            },
            message: e.describe(),
        })
        .collect()
}
