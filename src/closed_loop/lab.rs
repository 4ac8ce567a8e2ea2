//! A closed-loop run on one of the papers' presets: the defaults, the teach cut, the run, its
//! metrics and the reference runs the savings are measured against. The CLI and the browser both
//! call this, so a run is the same wherever it is made.

use serde::{Deserialize, Serialize};

use super::definition::{
    check_spec, machine_max_override_pct, PAPER_002_CONTROL_PERIOD_S, PAPER_002_OUTPUT_RANGE_PCT,
};
use super::metrics::{compute, with_savings, Metrics, MetricsConfig};
use super::runner::{
    Calibration, ClosedLoop, Feedback, LoopError, LoopSettings, OnMachine, TeachCut, TeachForce,
};
use super::trace::Trace;
use crate::control::registry::{ControllerConfig, ControllerKind, RunContext};
use crate::estimation::cut_forces::CutGeometry;
use crate::machine::Machine;
use crate::plant::cnc::{OverrideMode, MAX_OVERRIDE_PCT};
use crate::plant::dynamometer::{DynamometerConfig, WithDynamometer};
use crate::plant::presets::PlantEdits;
use crate::plant::presets::PlantKind;
use crate::plant::Preset;
use crate::safety::{ArmingTrigger, EnvelopeConfig, OverrideResolution};
use crate::work::{Progress, Work};

/// Everything that defines a run; the same spec and seed give the same trace. Its JSON form is
/// what a saved configuration holds ([`super::config`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunSpec {
    /// The experiment.
    pub preset: Preset,
    /// The controller and its parameters.
    pub controller: ControllerConfig,
    /// Seed of every noise source.
    pub seed: u64,
    /// Overrides of the preset's default settings.
    #[serde(default)]
    pub settings: SettingsOverrides,
    /// Changes to the preset's machine and cut (mill presets).
    #[serde(default)]
    pub plant: PlantEdits,
}

/// Settings a user may change; `None` keeps the preset's default (and is left out of the
/// serialised form).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SettingsOverrides {
    /// Which current measures the force.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub feedback: Option<Feedback>,
    /// Target force.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target_force_n: Option<f64>,
    /// Control period.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub control_period_s: Option<f64>,
    /// Spindle current low-pass cut-off.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spindle_lowpass_hz: Option<f64>,
    /// Feed current low-pass cut-off.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub feed_lowpass_hz: Option<f64>,
    /// Order of the low-passes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lowpass_order: Option<usize>,
    /// Lowest override.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_override_pct: Option<f64>,
    /// Highest override.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_override_pct: Option<f64>,
    /// Override rate limit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_rate_pct_per_s: Option<f64>,
    /// Override held until the envelope arms.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub arming_override_pct: Option<f64>,
}

impl RunSpec {
    /// A run of `preset` with `controller` at its defaults and seed 1.
    pub fn new(preset: Preset, controller: ControllerKind) -> Self {
        Self {
            preset,
            controller: super::definition::preset_controller(preset, controller),
            seed: 1,
            settings: SettingsOverrides::default(),
            plant: PlantEdits::default(),
        }
    }
}

/// A finished run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunResult {
    /// What was run.
    pub spec: RunSpec,
    /// The settings the run used.
    pub settings: LoopSettings,
    /// The teach cut's calibration.
    pub calibration: Calibration,
    /// The trace.
    pub trace: Trace,
    /// The metrics (savings filled when reference runs were made).
    pub metrics: Metrics,
}

/// The shortest control period; a mill's period is a whole number of spindle revolutions at
/// least this long, so the period mean removes the tooth-passing ripple.
const MIN_CONTROL_PERIOD_S: f64 = 0.04;
/// A loop without a spindle to synchronise with uses this period.
const DEFAULT_CONTROL_PERIOD_S: f64 = 0.05;

/// The feedback path a preset measures force with by default: the brake bench has only a feed
/// drive; everything else uses the spindle, as paper 003 and paper 002 do.
pub fn default_feedback(preset: Preset) -> Feedback {
    match preset.plant_kind() {
        PlantKind::BrakeBench => Feedback::FeedCurrent,
        PlantKind::SecondOrder => Feedback::Dynamometer,
        _ => Feedback::SpindleCurrent,
    }
}

fn envelope_resolution(mode: &OverrideMode) -> OverrideResolution {
    match mode {
        OverrideMode::Dial(table) => {
            let mut positions = table.positions();
            positions.sort_by(f64::total_cmp);
            positions.dedup();
            OverrideResolution::Dial(positions)
        }
        OverrideMode::WholePercent => OverrideResolution::WholePercent,
        OverrideMode::Continuous => OverrideResolution::Continuous,
    }
}

/// The preset's default settings with the spec's changes (the target is filled after the teach
/// cut when the preset has none of its own). Every setting the spec holds is checked against the
/// run definition ([`super::definition`]) first.
pub fn default_settings(spec: &RunSpec) -> Result<LoopSettings, LoopError> {
    check_spec(spec).map_err(LoopError::Setting)?;
    let preset = spec.preset;
    let o = &spec.settings;
    let summary = preset.summary();
    let feedback = o.feedback.unwrap_or_else(|| default_feedback(preset));
    let period = o
        .control_period_s
        .unwrap_or_else(|| match summary.spindle_rpm {
            _ if preset.plant_kind() == PlantKind::BondGraph => PAPER_002_CONTROL_PERIOD_S,
            Some(rpm) if rpm > 0.0 && feedback != Feedback::FeedCurrent => {
                let revolution_s = 60.0 / rpm;
                (MIN_CONTROL_PERIOD_S / revolution_s).ceil() * revolution_s
            }
            _ => DEFAULT_CONTROL_PERIOD_S,
        });
    // A preset's target is a force of its own feedback path (a mill's mean resultant, the
    // bench's feed force); for the other path it is converted after the teach cut.
    let target = o
        .target_force_n
        .or(preset
            .target_force_n()
            .filter(|_| feedback == default_feedback(preset)))
        .unwrap_or(f64::NAN);
    let mut envelope = EnvelopeConfig::for_target(1.0);
    envelope.resolution = envelope_resolution(&preset.override_mode());
    // The bench has no spindle: its "start" is the feed drive's.
    if preset.plant_kind() == PlantKind::BrakeBench {
        envelope.arming_trigger = ArmingTrigger::ProgrammedFeed;
    }
    // Paper 003's override is a byte in percent, 0–255 %: its experiments (the 1 mm entry, the
    // aluminium section, the taper's light corner) need the room above FANUC's 150 % dial.
    if matches!(preset.override_mode(), OverrideMode::WholePercent) {
        envelope.max_override_pct = MAX_OVERRIDE_PCT;
    }
    // Paper 002's fuzzy law moves the feed by up to k_u·6 = 100 % in one sampling period; the
    // envelope on its preset lets that action through (the mills keep 100 %/s).
    if preset.plant_kind() == PlantKind::BondGraph {
        envelope.max_rate_pct_per_s = PAPER_002_OUTPUT_RANGE_PCT / period;
    }
    if let Some(v) = o.min_override_pct {
        envelope.min_override_pct = v;
    }
    if let Some(v) = o.max_override_pct {
        envelope.max_override_pct = v;
    }
    if let Some(v) = o.max_rate_pct_per_s {
        envelope.max_rate_pct_per_s = v;
    }
    if let Some(v) = o.arming_override_pct {
        envelope.arming_override_pct = v;
    }
    let mut settings = LoopSettings {
        feedback,
        control_period_s: period,
        spindle_lowpass_hz: o.spindle_lowpass_hz.unwrap_or(260.0),
        feed_lowpass_hz: o.feed_lowpass_hz.unwrap_or(50.0),
        lowpass_order: o.lowpass_order.unwrap_or(4),
        target_force_n: f64::NAN,
        force_limit_n: f64::NAN,
        envelope,
        max_duration_s: time_limit_s(spec),
        cross_check_tolerance: 0.3,
    };
    set_target(&mut settings, target);
    Ok(settings)
}

/// The time a run may take before it is stopped: three times the program's nominal duration, and
/// for a fixed feed below 100 % that much longer again (a reference run at 20 % takes five times
/// the program's time and must still finish to count).
fn time_limit_s(spec: &RunSpec) -> f64 {
    let nominal_s = spec.preset.summary().nominal_duration_s.max(1.0);
    let slowdown = spec
        .controller
        .fixed_override_pct()
        .map_or(1.0, |pct| (100.0 / pct.max(1.0)).max(1.0));
    3.0 * nominal_s * slowdown + 10.0
}

/// The metrics' force limit, as a multiple of the target.
const FORCE_LIMIT_FACTOR: f64 = 1.2;
/// The overload alarm's hard limit, as a multiple of the target: a tool-breakage limit well above
/// the target, so a fixed-feed baseline through a deep step still completes for the comparison.
const OVERLOAD_FACTOR: f64 = 3.0;

/// Sets the target and the limits that follow from it (NaN leaves them unset).
fn set_target(settings: &mut LoopSettings, target_force_n: f64) {
    settings.target_force_n = target_force_n;
    settings.force_limit_n = FORCE_LIMIT_FACTOR * target_force_n;
    settings.envelope.overload_limit_n = OVERLOAD_FACTOR * target_force_n;
}

/// Sets the target (and what derives from it) once the teach cut is known: the preset's own
/// force target (a mill's resultant converted to feed force by the ratio the teach cut saw, when
/// the feed current measures it), else its current target through the calibrated model (paper
/// 002's 25 A), else 80 % of the force the program gives at 100 % override.
fn settle_target(spec: &RunSpec, settings: &mut LoopSettings, calibration: &Calibration) {
    if settings.target_force_n.is_finite() {
        return;
    }
    let summary = spec.preset.summary();
    let converted = spec
        .preset
        .target_force_n()
        .filter(|_| settings.feedback != default_feedback(spec.preset))
        .map(|resultant_n| resultant_n * calibration.regulated_per_resultant);
    let from_current = spec
        .preset
        .target_spindle_current_a()
        .filter(|_| settings.feedback == Feedback::SpindleCurrent)
        .map(|current_a| {
            calibration.estimator.force_for_current_n(
                current_a,
                summary.spindle_rpm.unwrap_or(0.0),
                summary.programmed_feed_mm_min.unwrap_or(0.0),
            )
        });
    let target = converted
        .or(from_current)
        .filter(|f| f.is_finite() && *f > 0.0)
        .unwrap_or(0.8 * calibration.median_force_at_full_override_n);
    set_target(settings, target);
}

/// The teach force a machine without simulation truth or dynamometer can use: the model of the
/// preset's cut, when the whole program cuts one depth, one width and one material (the model
/// takes each period's feed and speed from the machine, but not where on the part the tool is).
/// `None` for a program whose cut changes along the path: such a machine needs a saved
/// calibration ([`super::calibration_file`]).
pub fn cut_model_teach_force(preset: Preset) -> Option<TeachForce> {
    let scenario = preset.scenario_spec()?;
    let single = |points: &[(f64, f64)]| -> Option<f64> {
        let first = points.first()?.1;
        points.iter().all(|p| p.1 == first).then_some(first)
    };
    let [material] = scenario.materials.as_slice() else {
        return None;
    };
    Some(TeachForce::CutModel {
        geometry: CutGeometry {
            cutter: scenario.cutter,
            mode: scenario.mode,
            coefficients: material.material.coefficients(),
        },
        depth_mm: single(&scenario.depth_mm)?,
        width_mm: single(&scenario.width_mm)?,
    })
}

/// The machines a run uses: a simulation makes a fresh pass for the teach cut and another for the
/// run (differently seeded, like two parts); a real machine or a replayed log does both in turn.
pub enum RunMachines {
    /// One machine for the teach cut, another for the closed loop.
    Separate {
        /// Runs the teach cut.
        teach: Box<dyn Machine>,
        /// Runs the closed loop.
        run: Box<dyn Machine>,
    },
    /// One machine that does the teach cut and then the closed loop.
    Shared(Box<dyn Machine>),
}

impl RunMachines {
    /// The preset's machines for `spec`: the teach cut seeded apart from the run.
    pub fn for_preset(spec: &RunSpec) -> Result<Self, LoopError> {
        Ok(RunMachines::Separate {
            teach: preset_machine(spec, spec.seed.wrapping_add(TEACH_SEED_OFFSET))?,
            run: preset_machine(spec, spec.seed)?,
        })
    }
}

/// `spec`'s simulated machine seeded with `seed`, with a dynamometer under the part when the run
/// feeds back the measured force.
fn preset_machine(spec: &RunSpec, seed: u64) -> Result<Box<dyn Machine>, LoopError> {
    let machine = Box::new(
        spec.preset
            .machine_with(seed, &spec.plant)
            .map_err(LoopError::Machine)?,
    );
    let feedback = spec
        .settings
        .feedback
        .unwrap_or_else(|| default_feedback(spec.preset));
    Ok(if feedback == Feedback::Dynamometer {
        Box::new(
            WithDynamometer::new(machine, DynamometerConfig::default(), seed)
                .map_err(LoopError::Machine)?,
        )
    } else {
        machine
    })
}

/// A run in progress: first the teach cut, then the closed loop. Advancing in chunks lets a
/// browser show progress and cancel between frames; [`simulate`] runs it to the end at once.
pub struct LabRun {
    spec: RunSpec,
    settings: LoopSettings,
    nominal_duration_s: f64,
    /// True when the run was given a calibration and has no teach cut of its own.
    calibrated: bool,
    stage: Stage,
}

enum Stage {
    Teaching {
        teach: Box<OnMachine<TeachCut>>,
        /// The closed loop's machine, when it is not the teach cut's.
        run_machine: Option<Box<dyn Machine>>,
    },
    Running {
        run: Box<ClosedLoop>,
        calibration: Calibration,
    },
    Done(Box<RunResult>),
    /// Between stages, or after the result was taken.
    Empty,
}

impl LabRun {
    /// Starts a run of `spec` on its preset's simulated machine, calibrated by a teach cut that
    /// takes its force from the simulation's truth.
    pub fn new(spec: &RunSpec) -> Result<Self, LoopError> {
        let machines = RunMachines::for_preset(spec)?;
        Self::on_machines(spec, machines, TeachForce::SimulationTruth)
    }

    /// Starts a run of `spec`'s controller and settings on any machine: the teach cut runs on
    /// `machines` with its force from `teach_force`, then the closed loop. The preset gives the
    /// defaults of every setting the spec leaves out.
    pub fn on_machines(
        spec: &RunSpec,
        machines: RunMachines,
        teach_force: TeachForce,
    ) -> Result<Self, LoopError> {
        let settings = default_settings(spec)?;
        let (teach_machine, run_machine) = match machines {
            RunMachines::Separate { teach, run } => (teach, Some(run)),
            RunMachines::Shared(machine) => (machine, None),
        };
        Ok(Self {
            nominal_duration_s: spec.preset.summary().nominal_duration_s.max(1.0),
            calibrated: false,
            stage: Stage::Teaching {
                teach: Box::new(OnMachine::teach_cut(teach_machine, &settings, teach_force)?),
                run_machine,
            },
            settings,
            spec: spec.clone(),
        })
    }

    /// Starts a run that skips the teach cut and uses `calibration`, made by an earlier run of a
    /// spec with the same preset, seed, machine and signal chain (the teach cut depends on those
    /// alone, so the result is the same as [`LabRun::new`]'s, for less work).
    pub fn calibrated(spec: &RunSpec, calibration: Calibration) -> Result<Self, LoopError> {
        Self::calibrated_on(spec, preset_machine(spec, spec.seed)?, calibration)
    }

    /// Starts the closed loop on any machine from a calibration made elsewhere (a saved
    /// calibration file, a logged cut): no teach cut. Refused when the calibration reads another
    /// feedback path than the run's settings.
    pub fn calibrated_on(
        spec: &RunSpec,
        machine: Box<dyn Machine>,
        calibration: Calibration,
    ) -> Result<Self, LoopError> {
        let settings = default_settings(spec)?;
        let calibration_feedback = calibration.estimator.feedback();
        if calibration_feedback != settings.feedback {
            return Err(LoopError::CalibrationFeedback {
                calibration: calibration_feedback,
                run: settings.feedback,
            });
        }
        let mut run = Self {
            nominal_duration_s: spec.preset.summary().nominal_duration_s.max(1.0),
            calibrated: true,
            stage: Stage::Empty,
            settings,
            spec: spec.clone(),
        };
        let closed_loop = run.start_loop(machine, &calibration)?;
        run.stage = Stage::Running {
            run: Box::new(closed_loop),
            calibration,
        };
        Ok(run)
    }

    fn start_loop(
        &mut self,
        machine: Box<dyn Machine>,
        calibration: &Calibration,
    ) -> Result<ClosedLoop, LoopError> {
        let mut settings = self.settings.clone();
        let summary = self.spec.preset.summary();
        settle_target(&self.spec, &mut settings, calibration);
        if !(settings.target_force_n.is_finite() && settings.target_force_n > 0.0) {
            return Err(LoopError::NoTarget);
        }
        // A phase current beyond twice anything the teach cut saw (its overrides reach 140 %) is
        // a sensor fault, whatever the machine's size.
        if calibration.max_phase_current_a > 0.0 {
            settings.envelope.max_current_a = 2.0 * calibration.max_phase_current_a;
        }
        let controller = self
            .spec
            .controller
            .build(&RunContext {
                target_force_n: settings.target_force_n,
                control_period_s: settings.control_period_s,
                amps_per_newton: calibration
                    .estimator
                    .sensitivity_a_per_n(summary.spindle_rpm.unwrap_or(0.0)),
            })
            .map_err(LoopError::Controller)?;
        ClosedLoop::new(machine, controller, calibration.estimator.clone(), settings)
    }

    /// Stops the closed loop after `duration_s` of machine time if that comes before the
    /// preset's own limit (a host's `--duration-s`); the teach cut is not affected.
    pub fn limit_duration_s(&mut self, duration_s: f64) {
        if duration_s < self.settings.max_duration_s || duration_s.is_nan() {
            self.settings.max_duration_s = duration_s;
        }
    }

    /// The trace so far, once the closed loop has started.
    pub fn trace(&self) -> Option<&Trace> {
        match &self.stage {
            Stage::Running { run, .. } => Some(run.trace()),
            Stage::Done(r) => Some(&r.trace),
            _ => None,
        }
    }

    /// The result, once complete.
    pub fn into_result(self) -> Option<RunResult> {
        match self.stage {
            Stage::Done(r) => Some(*r),
            _ => None,
        }
    }
}

impl Work for LabRun {
    type Output = RunResult;
    type Error = LoopError;

    /// Runs at most `periods` control periods of whichever stage is under way.
    fn advance(&mut self, periods: usize) -> Result<bool, LoopError> {
        match std::mem::replace(&mut self.stage, Stage::Empty) {
            Stage::Teaching {
                mut teach,
                run_machine,
            } => {
                if teach.advance(periods)? {
                    let calibration = teach.calibration()?;
                    let (teach_machine, _) = teach.into_parts();
                    let machine = run_machine.unwrap_or(teach_machine);
                    let run = self.start_loop(machine, &calibration)?;
                    self.stage = Stage::Running {
                        run: Box::new(run),
                        calibration,
                    };
                } else {
                    self.stage = Stage::Teaching { teach, run_machine };
                }
                Ok(false)
            }
            Stage::Running {
                mut run,
                calibration,
            } => {
                if run.advance(periods)? {
                    let settings = run.settings().clone();
                    let trace = run.into_trace();
                    let metrics = compute(&trace, &metrics_config(self.spec.preset, &settings));
                    self.stage = Stage::Done(Box::new(RunResult {
                        spec: self.spec.clone(),
                        settings,
                        calibration,
                        trace,
                        metrics,
                    }));
                    Ok(true)
                } else {
                    self.stage = Stage::Running { run, calibration };
                    Ok(false)
                }
            }
            done @ Stage::Done(_) => {
                self.stage = done;
                Ok(true)
            }
            Stage::Empty => Ok(true),
        }
    }

    /// "teach cut", "closed loop" or "done", with the teach cut counted as the first half.
    fn progress(&self) -> Progress {
        let fraction = |elapsed_s: f64| (elapsed_s / self.nominal_duration_s).clamp(0.0, 1.0);
        match &self.stage {
            Stage::Teaching { teach, .. } => {
                Progress::new("teach cut", 0.5 * fraction(teach.elapsed_s()))
            }
            Stage::Running { run, .. } if self.calibrated => {
                Progress::new("closed loop", fraction(run.elapsed_s()))
            }
            Stage::Running { run, .. } => {
                Progress::new("closed loop", 0.5 + 0.5 * fraction(run.elapsed_s()))
            }
            Stage::Done(_) | Stage::Empty => Progress::new("done", 1.0),
        }
    }

    fn finish(&mut self) -> Result<RunResult, LoopError> {
        match std::mem::replace(&mut self.stage, Stage::Empty) {
            Stage::Done(result) => Ok(*result),
            other => {
                self.stage = other;
                Err(LoopError::NotFinished)
            }
        }
    }
}

/// The teach cut's seed is the run's plus this, so its noise differs from the run's.
const TEACH_SEED_OFFSET: u64 = 0x7EAC;

/// The metrics settings for a run of `preset` with `settings`.
pub fn metrics_config(preset: Preset, settings: &LoopSettings) -> MetricsConfig {
    MetricsConfig {
        force_limit_n: settings.force_limit_n,
        settling_band_pct: 10.0,
        depth_step_mm: 0.2,
        load_step_times_s: preset.load_step_times_s(),
    }
}

/// `spec`'s teach cut (on the machine a run would teach on) as work done in pieces; its
/// calibration is the one [`LabRun::new`] would use.
pub fn teach_cut_work(spec: &RunSpec) -> Result<OnMachine<TeachCut>, LoopError> {
    let settings = default_settings(spec)?;
    let teach = preset_machine(spec, spec.seed.wrapping_add(TEACH_SEED_OFFSET))?;
    OnMachine::teach_cut(teach, &settings, TeachForce::SimulationTruth)
}

/// The settings a run of `spec` uses once its teach cut gave `calibration` (the target settled).
pub fn settled_settings(
    spec: &RunSpec,
    calibration: &Calibration,
) -> Result<LoopSettings, LoopError> {
    let mut settings = default_settings(spec)?;
    settle_target(spec, &mut settings, calibration);
    Ok(settings)
}

/// Runs only `spec`'s teach cut (on the machine a run would teach on) and returns the run's
/// settings with the target it settles to, and the calibration: what a teach-in learns.
pub fn teach_cut_only(spec: &RunSpec) -> Result<(LoopSettings, Calibration), LoopError> {
    let mut settings = default_settings(spec)?;
    let teach = preset_machine(spec, spec.seed.wrapping_add(TEACH_SEED_OFFSET))?;
    let calibration =
        OnMachine::teach_cut(teach, &settings, TeachForce::SimulationTruth)?.run_to_end()?;
    settle_target(spec, &mut settings, &calibration);
    Ok((settings, calibration))
}

/// Runs `spec` to the end, without reference runs.
pub fn simulate(spec: &RunSpec) -> Result<RunResult, LoopError> {
    LabRun::new(spec)?.run_to_end()
}

/// The reference runs of the savings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct References {
    /// Cycle time at the programmed feed (fixed 100 %).
    pub programmed_cycle_time_s: f64,
    /// The highest fixed override whose peak regulated force stays at or below the target (NaN
    /// when not even the lowest does, and with it the cycle time and that saving): the
    /// feed a machinist would fix for the part's worst spot, judged against the same force the
    /// controllers are asked to hold (not the 1.2 × target limit, which would let the fixed feed
    /// run 20 % harder than any controller aims to).
    pub safe_fixed_override_pct: f64,
    /// Cycle time at that override.
    pub safe_fixed_cycle_time_s: f64,
}

/// Runs the fixed-feed references for `spec`'s preset and settings: 100 %, and a bisection for
/// the highest fixed override that keeps the peak force at or below the target (to 1 %).
pub fn references(spec: &RunSpec) -> Result<References, LoopError> {
    ReferenceSearch::new(spec)?.run_to_end()
}

/// The bisection's bracket of fixed overrides, percent.
const REFERENCE_BRACKET_PCT: (f64, f64) = (1.0, 250.0);

/// The reference runs of [`references`], done a piece at a time so a browser can show progress
/// and stay responsive: the programmed feed at 100 %, then a bisection over fixed overrides.
/// The teach cut is made once, by the first run; the others reuse its calibration (they differ
/// from it only in controller and override band, which the teach cut does not depend on).
pub struct ReferenceSearch {
    spec: RunSpec,
    run: LabRun,
    /// The fixed override of `run`, percent, and whether it is a bisection step.
    running: (f64, RunKind),
    calibration: Option<Calibration>,
    programmed_cycle_time_s: f64,
    /// The force no reference run may exceed: the target the controllers hold.
    reference_force_n: f64,
    low_pct: f64,
    high_pct: f64,
    best_cycle_time_s: Option<f64>,
    runs_done: usize,
    found: Option<References>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum RunKind {
    Programmed,
    Bisection,
    /// No bisection step stayed under the target: the lowest override, checked like the others.
    Lowest,
}

impl ReferenceSearch {
    /// Runs a bisection needs from the bracket down to 1 %, plus the programmed-feed run.
    const EXPECTED_RUNS: usize = 9;

    /// Starts with the programmed-feed run.
    pub fn new(spec: &RunSpec) -> Result<Self, LoopError> {
        let (low_pct, bracket_high_pct) = REFERENCE_BRACKET_PCT;
        // A dial that stops at 150 % cannot run a fixed 250 %.
        let high_pct = bracket_high_pct.min(machine_max_override_pct(spec.preset));
        Ok(Self {
            run: LabRun::new(&fixed_feed_spec(spec, 100.0)?)?,
            running: (100.0, RunKind::Programmed),
            spec: spec.clone(),
            calibration: None,
            programmed_cycle_time_s: f64::NAN,
            reference_force_n: f64::NAN,
            low_pct,
            high_pct,
            best_cycle_time_s: None,
            runs_done: 0,
            found: None,
        })
    }

    /// The references, once found.
    pub fn found(&self) -> Option<References> {
        self.found
    }

    /// After the lowest override also broke the target, the answer is that no fixed feed keeps
    /// the force at the target (the cut's floor, its edge forces at the deepest point, lies
    /// above it): NaN, which leaves the saving against a safe fixed feed undefined rather than
    /// measured against a 1 % crawl that is not safe either.
    fn no_safe_fixed_feed(&mut self, kind: RunKind) -> Option<f64> {
        (kind == RunKind::Lowest).then(|| {
            self.low_pct = f64::NAN;
            f64::NAN
        })
    }
}

impl Work for ReferenceSearch {
    type Output = References;
    type Error = LoopError;

    /// Does at most `periods` control periods of work.
    fn advance(&mut self, periods: usize) -> Result<bool, LoopError> {
        if self.found.is_some() {
            return Ok(true);
        }
        if !self.run.advance(periods)? {
            return Ok(false);
        }
        let result = self.run.finish()?;
        self.runs_done += 1;
        let (pct, kind) = self.running;
        match kind {
            RunKind::Programmed => {
                self.programmed_cycle_time_s = result.metrics.cycle_time_s;
                self.reference_force_n = result.settings.target_force_n;
                self.calibration = Some(result.calibration);
            }
            RunKind::Bisection => {
                if result.metrics.peak_force_n <= self.reference_force_n && result.trace.completed {
                    self.low_pct = pct;
                    self.best_cycle_time_s = Some(result.metrics.cycle_time_s);
                } else {
                    self.high_pct = pct;
                }
            }
            RunKind::Lowest => {
                if result.metrics.peak_force_n <= self.reference_force_n && result.trace.completed {
                    self.best_cycle_time_s = Some(result.metrics.cycle_time_s);
                }
            }
        }
        let next = if self.high_pct - self.low_pct > 1.0 {
            Some((
                ((self.low_pct + self.high_pct) / 2.0).round(),
                RunKind::Bisection,
            ))
        } else if self.best_cycle_time_s.is_none() && kind != RunKind::Lowest {
            Some((self.low_pct, RunKind::Lowest))
        } else {
            None
        };
        match (
            next,
            self.best_cycle_time_s
                .or_else(|| self.no_safe_fixed_feed(kind)),
        ) {
            (Some((pct, kind)), _) => {
                let spec = fixed_feed_spec(&self.spec, pct)?;
                self.run = match &self.calibration {
                    Some(c) => LabRun::calibrated(&spec, c.clone())?,
                    None => LabRun::new(&spec)?,
                };
                self.running = (pct, kind);
                Ok(false)
            }
            (None, Some(best)) => {
                self.found = Some(References {
                    programmed_cycle_time_s: self.programmed_cycle_time_s,
                    safe_fixed_override_pct: self.low_pct,
                    safe_fixed_cycle_time_s: best,
                });
                Ok(true)
            }
            (None, None) => Err(LoopError::NoReference),
        }
    }

    /// The fixed override of the current run and the rough fraction done.
    fn progress(&self) -> Progress {
        let expected = Self::EXPECTED_RUNS.max(self.runs_done + 1);
        let label = format!(
            "Savings: reference run {} of about {expected}, fixed feed at {:.0} %",
            self.runs_done + 1,
            self.running.0
        );
        let fraction = (self.runs_done as f64 + self.run.progress().fraction) / expected as f64;
        Progress::new(label, fraction)
    }

    fn finish(&mut self) -> Result<References, LoopError> {
        self.found.ok_or(LoopError::NotFinished)
    }
}

/// `spec` at a fixed override from start to end, not bounded by the envelope's override band:
/// the program as a machinist would run it without adaptive control.
pub fn fixed_feed_spec(spec: &RunSpec, override_pct: f64) -> Result<RunSpec, LoopError> {
    let mut s = spec.clone();
    s.controller = ControllerConfig::new(ControllerKind::Fixed);
    s.controller
        .set("override_pct", override_pct)
        .map_err(LoopError::Controller)?;
    s.settings.min_override_pct = Some(0.0);
    s.settings.max_override_pct = Some(machine_max_override_pct(spec.preset));
    s.settings.arming_override_pct = Some(override_pct);
    Ok(s)
}

/// Fills a result's savings from the references.
pub fn apply_references(result: &mut RunResult, references: &References) {
    result.metrics = with_savings(
        result.metrics.clone(),
        Some(references.programmed_cycle_time_s),
        Some(references.safe_fixed_cycle_time_s),
    );
}

/// Makes the machines of each run of a batch.
pub type MachineFactory = Box<dyn Fn(&RunSpec) -> Result<RunMachines, LoopError>>;

/// Closed-loop runs one after another: the Simulate page's run, the Compare page's variants.
/// Each run gets its machines from a factory (the preset's simulation unless told otherwise), so
/// a comparison can run on any machine that can be made more than once, such as a replayed log.
pub struct LabRuns {
    specs: Vec<RunSpec>,
    machines: MachineFactory,
    teach_force: TeachForce,
    current: Option<LabRun>,
    results: Vec<std::sync::Arc<RunResult>>,
}

impl LabRuns {
    /// The runs of `specs`, in order, on their presets' simulated machines.
    pub fn new(specs: Vec<RunSpec>) -> Self {
        Self::on_machines(
            specs,
            Box::new(RunMachines::for_preset),
            TeachForce::SimulationTruth,
        )
    }

    /// The runs of `specs`, in order, each on machines made by `machines` and calibrated with
    /// the teach-cut force from `teach_force`.
    pub fn on_machines(
        specs: Vec<RunSpec>,
        machines: MachineFactory,
        teach_force: TeachForce,
    ) -> Self {
        Self {
            results: Vec::with_capacity(specs.len()),
            specs,
            machines,
            teach_force,
            current: None,
        }
    }
}

impl Work for LabRuns {
    type Output = Vec<std::sync::Arc<RunResult>>;
    type Error = LoopError;

    fn advance(&mut self, budget: usize) -> Result<bool, LoopError> {
        let Some(spec) = self.specs.get(self.results.len()) else {
            return Ok(true);
        };
        let run = match &mut self.current {
            Some(run) => run,
            None => {
                let machines = (self.machines)(spec)?;
                self.current.insert(LabRun::on_machines(
                    spec,
                    machines,
                    self.teach_force.clone(),
                )?)
            }
        };
        if run.advance(budget)? {
            let result = run.finish()?;
            self.results.push(std::sync::Arc::new(result));
            self.current = None;
        }
        Ok(self.results.len() >= self.specs.len())
    }

    fn progress(&self) -> Progress {
        let total = self.specs.len().max(1);
        let index = self.results.len();
        let (stage, part) = self
            .current
            .as_ref()
            .map_or(("teach cut".to_string(), 0.0), |r| {
                let p = r.progress();
                (p.stage, p.fraction)
            });
        let label = if total > 1 {
            format!("Run {} of {total}: {stage}", (index + 1).min(total))
        } else {
            format!("Running: {stage}")
        };
        Progress::new(label, (index as f64 + part) / total as f64)
    }

    fn finish(&mut self) -> Result<Self::Output, LoopError> {
        if self.results.len() < self.specs.len() {
            return Err(LoopError::NotFinished);
        }
        Ok(std::mem::take(&mut self.results))
    }
}
