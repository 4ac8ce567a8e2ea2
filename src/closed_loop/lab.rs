//! A closed-loop run on one of the papers' presets: the defaults, the teach cut, the run, its
//! metrics and the reference runs the savings are measured against. The CLI and the browser both
//! call this, so a run is the same wherever it is made.

use serde::{Deserialize, Serialize};

use super::definition::{
    check_spec, default_override_band_pct, machine_max_override_pct, PAPER_002_CONTROL_PERIOD_S,
    PAPER_002_OUTPUT_RANGE_PCT,
};
use super::metrics::{compute, with_savings, Metrics, MetricsConfig};
use super::runner::{
    Calibration, ClosedLoop, Feedback, FeedbackLoop, LoopError, LoopSettings, OnMachine, TeachCut,
    TeachForce,
};
use super::trace::Trace;
use crate::control::registry::{ControllerConfig, ControllerKind, RunContext};
use crate::estimation::cut_forces::CutGeometry;
use crate::machine::Machine;
use crate::plant::cnc::OverrideMode;
use crate::plant::presets::PlantEdits;
use crate::plant::presets::{PlantKind, TEACH_SEED_OFFSET};
use crate::plant::Preset;
use crate::safety::{ArmingTrigger, EnvelopeConfig, OverrideResolution, AIR_CUT_FRACTION};
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
    (envelope.min_override_pct, envelope.max_override_pct) = default_override_band_pct(preset);
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
    match o.arming_override_pct {
        // check_spec refused one outside the band.
        Some(v) => envelope.arming_override_pct = v,
        // The default (100 %) follows a band set below or above it.
        None => {
            envelope.arming_override_pct = envelope
                .arming_override_pct
                .clamp(envelope.min_override_pct, envelope.max_override_pct);
        }
    }
    let max_duration_s = time_limit_s(spec, envelope.min_override_pct);
    let mut settings = LoopSettings {
        feedback,
        control_period_s: period,
        spindle_lowpass_hz: o.spindle_lowpass_hz.unwrap_or(260.0),
        feed_lowpass_hz: o.feed_lowpass_hz.unwrap_or(50.0),
        lowpass_order: o.lowpass_order.unwrap_or(4),
        target_force_n: f64::NAN,
        force_limit_n: f64::NAN,
        envelope,
        max_duration_s,
        cross_check_tolerance: 0.3,
    };
    set_target(&mut settings, target);
    Ok(settings)
}

/// The time a run may take before it is stopped: three times the program's nominal duration,
/// and for a fixed feed below 100 % that much longer again (a reference run at 20 % takes five
/// times the program's time and must still finish to count); and at least half again the time
/// the program takes at the envelope's lowest override, which a controller may hold for long
/// stretches (feed-current feedback on a mill holds 10–20 % through paper 003's deep steps).
fn time_limit_s(spec: &RunSpec, min_override_pct: f64) -> f64 {
    let nominal_s = spec.preset.summary().nominal_duration_s.max(1.0);
    let slowdown = |pct: f64| (100.0 / pct.max(1.0)).max(1.0);
    let fixed = spec.controller.fixed_override_pct().map_or(1.0, slowdown);
    let slowest = 1.5 * slowdown(min_override_pct);
    nominal_s * (3.0 * fixed).max(slowest) + 10.0
}

/// The metrics' force limit, as a multiple of the target.
const FORCE_LIMIT_FACTOR: f64 = 1.2;
/// The overload alarm's hard limit, as a multiple of the target: a tool-breakage limit well above
/// the target, so a fixed-feed baseline through a deep step still completes for the comparison.
const OVERLOAD_FACTOR: f64 = 3.0;

/// Above the air estimate by this factor, an estimated force is a cut.
const AIR_MARGIN: f64 = 1.5;
/// The air-cut threshold never rises above this fraction of the target: a model that reads a
/// large force in air still leaves the controller the light cuts (paper 003's 1 mm entry cuts at
/// 40 % of the target at 100 %).
pub const MAX_AIR_CUT_FRACTION: f64 = 0.35;

/// The estimated force below which the safety envelope takes the tool for in air: a fifth of
/// the target, raised to half again the force the calibrated model read in the teach cut's air
/// (its bias there), but never above [`MAX_AIR_CUT_FRACTION`] of the target.
///
/// ```
/// use cutlab::closed_loop::lab::air_cut_force_n;
/// assert_eq!(air_cut_force_n(320.0, f64::NAN), 64.0);   // no air seen: 20 %
/// assert_eq!(air_cut_force_n(320.0, 68.0), 102.0);      // 1.5 × the air reading
/// assert_eq!(air_cut_force_n(320.0, 300.0), 112.0);     // at most 35 %
/// ```
pub fn air_cut_force_n(target_force_n: f64, air_force_estimate_n: f64) -> f64 {
    let base = AIR_CUT_FRACTION * target_force_n;
    let biased = AIR_MARGIN * air_force_estimate_n;
    let threshold = if biased > base { biased } else { base };
    threshold.min(MAX_AIR_CUT_FRACTION * target_force_n)
}

/// Sets the target and the limits that follow from it (NaN leaves them unset).
fn set_target(settings: &mut LoopSettings, target_force_n: f64) {
    settings.target_force_n = target_force_n;
    settings.force_limit_n = FORCE_LIMIT_FACTOR * target_force_n;
    settings.envelope.overload_limit_n = OVERLOAD_FACTOR * target_force_n;
    settings.envelope.air_cut_force_n = AIR_CUT_FRACTION * target_force_n;
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
        let [teach, run] = spec
            .preset
            .teach_and_run_machines(spec.seed, &spec.plant, with_dynamometer(spec))
            .map_err(LoopError::Machine)?;
        Ok(RunMachines::Separate { teach, run })
    }
}

/// Whether `spec`'s machines carry a dynamometer: when the run feeds back the measured force.
fn with_dynamometer(spec: &RunSpec) -> bool {
    let feedback = spec
        .settings
        .feedback
        .unwrap_or_else(|| default_feedback(spec.preset));
    feedback == Feedback::Dynamometer
}

/// `spec`'s simulated machine seeded with `seed` (one of [`RunMachines::for_preset`]'s).
fn preset_machine(spec: &RunSpec, seed: u64) -> Result<Box<dyn Machine>, LoopError> {
    spec.preset
        .seeded_machine(seed, &spec.plant, with_dynamometer(spec))
        .map_err(LoopError::Machine)
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
        let feedback_loop = feedback_loop(
            &self.spec,
            &self.settings,
            calibration,
            machine.sample_rate_hz(),
        )?;
        Ok(OnMachine::new_with(machine, feedback_loop))
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

    /// The run so far as a result: the trace up to now and its metrics, once the closed loop has
    /// started (`None` during the teach cut).
    pub fn partial_result(&self) -> Option<RunResult> {
        match &self.stage {
            Stage::Running { run, calibration } => {
                let settings = run.settings().clone();
                let trace = run.trace().clone();
                let metrics = compute(&trace, &metrics_config(self.spec.preset, &settings));
                Some(RunResult {
                    spec: self.spec.clone(),
                    settings,
                    calibration: calibration.clone(),
                    trace,
                    metrics,
                })
            }
            Stage::Done(r) => Some((**r).clone()),
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

/// The closed loop of `spec` with `settings` once `calibration` is known, for samples at
/// `sample_rate_hz`, without a machine: the target settled, the sensor-fault current limit taken
/// from the teach cut, the controller built. [`LabRun`] runs it on its machine; a host that gets
/// samples as they arrive (the browser's Hardware page) pushes them into it.
pub fn feedback_loop(
    spec: &RunSpec,
    settings: &LoopSettings,
    calibration: &Calibration,
    sample_rate_hz: f64,
) -> Result<FeedbackLoop, LoopError> {
    let mut settings = settings.clone();
    let summary = spec.preset.summary();
    settle_target(spec, &mut settings, calibration);
    if !(settings.target_force_n.is_finite() && settings.target_force_n > 0.0) {
        return Err(LoopError::NoTarget);
    }
    settings.envelope.air_cut_force_n =
        air_cut_force_n(settings.target_force_n, calibration.air_force_estimate_n);
    // A phase current beyond twice anything the teach cut saw (its overrides reach 140 %) is
    // a sensor fault, whatever the machine's size.
    if calibration.max_phase_current_a > 0.0 {
        settings.envelope.max_current_a = 2.0 * calibration.max_phase_current_a;
    }
    let controller = spec
        .controller
        .build(&RunContext {
            target_force_n: settings.target_force_n,
            control_period_s: settings.control_period_s,
            amps_per_newton: calibration
                .estimator
                .sensitivity_a_per_n(summary.spindle_rpm.unwrap_or(0.0)),
        })
        .map_err(LoopError::Controller)?;
    FeedbackLoop::new(
        sample_rate_hz,
        controller,
        calibration.estimator.clone(),
        settings,
    )
}

/// The teach cut's seed is the run's plus this, so its noise differs from the run's.
/// The metrics settings for a run of `preset` with `settings`.
pub fn metrics_config(preset: Preset, settings: &LoopSettings) -> MetricsConfig {
    MetricsConfig {
        force_limit_n: settings.force_limit_n,
        // Paper 002 judges its load step by how soon the current stays near I_ref (Fig. 7): ±2 %.
        // The mills' depth steps are judged at ±10 %, their force's tooth-passing and noise
        // spread alone being a few percent.
        settling_band_pct: if preset.plant_kind() == PlantKind::BondGraph {
            2.0
        } else {
            10.0
        },
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

/// What a simulated teach cut depends on: two specs with equal keys make the same teach cut, so
/// one calibration serves both ([`LabRun::calibrated`]). A teach cut runs the preset's machine
/// (with its edits, seeded from the run's seed) through the fixed override schedule, summarised
/// by the signal chain at the control period, for the feedback path: the controller, the target
/// and the safety envelope play no part in it.
#[derive(Debug, Clone, PartialEq)]
pub struct TeachKey {
    preset: Preset,
    seed: u64,
    plant: PlantEdits,
    feedback: Feedback,
    control_period_s: f64,
    spindle_lowpass_hz: f64,
    feed_lowpass_hz: f64,
    lowpass_order: usize,
    max_duration_s: f64,
}

impl TeachKey {
    /// The key of `spec`'s teach cut.
    pub fn of(spec: &RunSpec) -> Result<Self, LoopError> {
        let s = default_settings(spec)?;
        Ok(Self {
            preset: spec.preset,
            seed: spec.seed,
            plant: spec.plant,
            feedback: s.feedback,
            control_period_s: s.control_period_s,
            spindle_lowpass_hz: s.spindle_lowpass_hz,
            feed_lowpass_hz: s.feed_lowpass_hz,
            lowpass_order: s.lowpass_order,
            max_duration_s: s.max_duration_s,
        })
    }
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
#[derive(Debug, Clone, Copy, PartialEq, Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct References {
    /// Cycle time at the programmed feed (fixed 100 %).
    #[serde(deserialize_with = "crate::estimation::null_as_nan")]
    pub programmed_cycle_time_s: f64,
    /// The highest fixed override whose peak regulated force stays at or below the target (NaN
    /// when not even the lowest does, and with it the cycle time and that saving): the
    /// feed a machinist would fix for the part's worst spot, judged against the same force the
    /// controllers are asked to hold (not the 1.2 × target limit, which would let the fixed feed
    /// run 20 % harder than any controller aims to).
    #[serde(deserialize_with = "crate::estimation::null_as_nan")]
    pub safe_fixed_override_pct: f64,
    /// Cycle time at that override.
    #[serde(deserialize_with = "crate::estimation::null_as_nan")]
    pub safe_fixed_cycle_time_s: f64,
}

/// Runs the fixed-feed references for `spec`'s preset and settings: 100 %, and a search for the
/// highest fixed override that keeps the peak force at or below the target (to 1 %).
pub fn references(spec: &RunSpec) -> Result<References, LoopError> {
    ReferenceSearch::new(spec)?.run_to_end()
}

/// The search's bracket of fixed overrides, percent: the answer lies in [low, high), and neither
/// end is run unless the search comes down to it.
const REFERENCE_BRACKET_PCT: (f64, f64) = (1.0, 250.0);

/// Probes the force model may place before the search falls back to halving the bracket.
pub const GUIDED_PROBES: usize = 4;

/// A probe that only needs a verdict is looked at after this many control periods.
const VERDICT_CHECK_PERIODS: usize = 20;

/// The reference runs of [`references`], done a piece at a time so a browser can show progress
/// and stay responsive: the programmed feed at 100 %, then probes of fixed overrides.
///
/// The peak force of a fixed-feed run grows with the override, nearly in a straight line (the
/// chip's force with the feed per tooth, plus the edge forces), so the probes are placed where
/// the line through the runs so far meets the target (through the origin while only one run is
/// known), inside the bracket of the highest override that passed and the lowest that failed;
/// after [`GUIDED_PROBES`] such probes, or when the line gives nothing, the bracket is halved.
/// For a peak that rises with the override this finds the same answer as a bisection, in three
/// to five runs instead of nine. Once two whole runs have fixed the line, a probe that breaks the
/// target is stopped there (the rest of its cut cannot lower its peak). The teach cut is made
/// once, by the first run (or given: [`ReferenceSearch::calibrated`]); the others reuse its
/// calibration (they differ from it only in controller and override band, which the teach cut
/// does not depend on).
pub struct ReferenceSearch {
    spec: RunSpec,
    run: LabRun,
    /// The fixed override of `run`, percent, and what it is for.
    running: (f64, RunKind),
    calibration: Option<Calibration>,
    programmed_cycle_time_s: f64,
    /// The force no reference run may exceed: the target the controllers hold.
    reference_force_n: f64,
    /// The highest override known to keep the force (the bracket's floor until one is run).
    low_pct: f64,
    /// The lowest override known to break it (the bracket's top until one is run).
    high_pct: f64,
    best_cycle_time_s: Option<f64>,
    /// (override, peak force) of every whole run so far: the line's points.
    peaks: Vec<(f64, f64)>,
    /// Rows of `run`'s trace already compared with the reference force.
    rows_checked: usize,
    guided_probes: usize,
    runs_done: usize,
    /// The largest fraction shown so far (the number of runs is not known in advance).
    shown_fraction: std::cell::Cell<f64>,
    found: Option<References>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum RunKind {
    Programmed,
    Probe,
    /// No probe stayed under the target: the lowest override, checked like the others.
    Lowest,
}

impl ReferenceSearch {
    /// Starts with the programmed-feed run (and its teach cut).
    pub fn new(spec: &RunSpec) -> Result<Self, LoopError> {
        Self::starting(spec, LabRun::new(&fixed_feed_spec(spec, 100.0)?)?, None)
    }

    /// Starts with the programmed-feed run, calibrated by `calibration` (from a teach cut of a
    /// run on the same scenario: [`TeachKey`]) instead of a teach cut of its own.
    pub fn calibrated(spec: &RunSpec, calibration: Calibration) -> Result<Self, LoopError> {
        let run = LabRun::calibrated(&fixed_feed_spec(spec, 100.0)?, calibration.clone())?;
        Self::starting(spec, run, Some(calibration))
    }

    fn starting(
        spec: &RunSpec,
        run: LabRun,
        calibration: Option<Calibration>,
    ) -> Result<Self, LoopError> {
        let (low_pct, bracket_high_pct) = REFERENCE_BRACKET_PCT;
        // A dial that stops at 150 % cannot run a fixed 250 %.
        let high_pct = bracket_high_pct.min(machine_max_override_pct(spec.preset));
        Ok(Self {
            run,
            running: (100.0, RunKind::Programmed),
            spec: spec.clone(),
            calibration,
            programmed_cycle_time_s: f64::NAN,
            reference_force_n: f64::NAN,
            low_pct,
            high_pct,
            best_cycle_time_s: None,
            peaks: Vec::new(),
            rows_checked: 0,
            guided_probes: 0,
            runs_done: 0,
            shown_fraction: std::cell::Cell::new(0.0),
            found: None,
        })
    }

    /// The references, once found.
    pub fn found(&self) -> Option<References> {
        self.found
    }

    /// The calibration of the scenario's teach cut, once made (or given).
    pub fn calibration(&self) -> Option<&Calibration> {
        self.calibration.as_ref()
    }

    /// Whether the run under way has already broken the reference force, checking the rows added
    /// since the last look.
    fn run_broke_target(&mut self) -> bool {
        let Some(trace) = self.run.trace() else {
            return false;
        };
        let rows = &trace.rows[self.rows_checked.min(trace.rows.len())..];
        self.rows_checked = trace.rows.len();
        rows.iter()
            .any(|r| r.force_n.is_finite() && r.force_n > self.reference_force_n)
    }

    /// Where the straight line through the whole runs so far (the last two; through the origin
    /// while there is one) reaches the reference force, if it rises.
    fn line_reaches_target_pct(&self) -> Option<f64> {
        let target = self.reference_force_n;
        let pct = match self.peaks.as_slice() {
            [] => return None,
            [(p, f)] => p * target / f,
            [.., (p0, f0), (p1, f1)] => {
                let slope = (f1 - f0) / (p1 - p0);
                // A line that does not rise (or a NaN) says nothing: halve the bracket instead.
                if slope.is_nan() || slope <= 0.0 {
                    return None;
                }
                p1 + (target - f1) / slope
            }
        };
        pct.is_finite().then_some(pct)
    }

    /// The next override to run, or `None` when the bracket is down to 1 %.
    fn next_probe_pct(&mut self) -> Option<f64> {
        if self.high_pct - self.low_pct <= 1.0 {
            return None;
        }
        let (inside_low, inside_high) = (self.low_pct + 1.0, self.high_pct - 1.0);
        let guided = (self.guided_probes < GUIDED_PROBES)
            .then(|| self.line_reaches_target_pct())
            .flatten();
        let pct = match guided {
            Some(pct) => {
                self.guided_probes += 1;
                pct.floor()
            }
            None => ((self.low_pct + self.high_pct) / 2.0).round(),
        };
        Some(pct.clamp(inside_low, inside_high))
    }

    /// The run after a `kind` run ended: the next probe, the lowest override's check, or the
    /// answer.
    fn next(&mut self, kind: RunKind) -> Result<bool, LoopError> {
        let next = match self.next_probe_pct() {
            Some(pct) => Some((pct, RunKind::Probe)),
            None if self.best_cycle_time_s.is_none() && kind != RunKind::Lowest => {
                Some((self.low_pct, RunKind::Lowest))
            }
            None => None,
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
                self.rows_checked = 0;
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
        let (pct, kind) = self.running;
        // Once the line is fixed by two whole runs, a probe needs no more than a verdict: it is
        // looked at every few periods and stopped when it breaks the target. (The answer does not
        // depend on where it stops, nor on the budget: such a probe adds no point to the line.)
        let verdict_only = kind == RunKind::Probe && self.peaks.len() >= 2;
        let mut left = periods.max(1);
        let finished = loop {
            let piece = if verdict_only {
                left.min(VERDICT_CHECK_PERIODS)
            } else {
                left
            };
            left -= piece;
            if self.run.advance(piece)? {
                break true;
            }
            if verdict_only && self.run_broke_target() {
                self.runs_done += 1;
                self.high_pct = self.high_pct.min(pct);
                return self.next(kind);
            }
            if left == 0 {
                break false;
            }
        };
        if !finished {
            return Ok(false);
        }
        let result = self.run.finish()?;
        self.runs_done += 1;
        if kind == RunKind::Programmed {
            self.programmed_cycle_time_s = result.metrics.cycle_time_s;
            self.reference_force_n = result.settings.target_force_n;
            self.calibration.get_or_insert(result.calibration);
        }
        let peak_n = result.metrics.peak_force_n;
        let kept = peak_n <= self.reference_force_n && result.trace.completed;
        if result.trace.completed && (kept || !verdict_only) {
            self.peaks.push((pct, peak_n));
        }
        match kind {
            // The programmed feed is a probe at 100 % too.
            RunKind::Programmed | RunKind::Probe => {
                if kept && pct > self.low_pct {
                    self.low_pct = pct;
                    self.best_cycle_time_s = Some(result.metrics.cycle_time_s);
                } else if !kept {
                    self.high_pct = self.high_pct.min(pct);
                }
            }
            RunKind::Lowest => {
                if kept {
                    self.best_cycle_time_s = Some(result.metrics.cycle_time_s);
                }
            }
        }
        self.next(kind)
    }

    /// The fixed override of the current run and the rough fraction done.
    fn progress(&self) -> Progress {
        // The runs still to come: about one per halving of the bracket, at most three once the
        // line guides the probes, and the run under way.
        let width = (self.high_pct - self.low_pct).max(1.0);
        let remaining = if self.found.is_some() {
            0
        } else {
            1 + (width.log2().ceil() as usize).min(3)
        };
        let expected = (self.runs_done + remaining).max(1);
        let label = format!(
            "Savings: reference run {} of about {expected}, fixed feed at {:.0} %",
            self.runs_done + 1,
            self.running.0
        );
        let fraction = ((self.runs_done as f64 + self.run.progress().fraction) / expected as f64)
            .clamp(0.0, 1.0)
            .max(self.shown_fraction.get());
        self.shown_fraction.set(fraction);
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

/// What a scenario's fixed-feed references depend on: the preset, the seed, the machine edits and
/// the settings of its run at the fixed 100 % feed, resolved to values. Two specs that spell the
/// same settings differently (a default left unset, or typed in) have the same key, and their
/// reference searches give the same result; the controller plays no part.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioKey {
    preset: Preset,
    seed: u64,
    plant: PlantEdits,
    settings: LoopSettings,
}

impl ScenarioKey {
    /// The key of `spec`'s scenario.
    pub fn of(spec: &RunSpec) -> Result<Self, LoopError> {
        let fixed = fixed_feed_spec(spec, 100.0)?;
        Ok(Self {
            preset: spec.preset,
            seed: spec.seed,
            plant: spec.plant,
            settings: default_settings(&fixed)?,
        })
    }
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
    /// The teach cuts made so far, when runs on the preset's simulation share them: a run whose
    /// [`TeachKey`] is here starts from its calibration instead of cutting again.
    calibrations: Option<Vec<(TeachKey, Calibration)>>,
    current: Option<LabRun>,
    results: Vec<std::sync::Arc<RunResult>>,
}

impl LabRuns {
    /// The runs of `specs`, in order, on their presets' simulated machines.
    ///
    /// Runs on the same scenario share one teach cut (their results are the same as with a teach
    /// cut each: the simulation repeats it exactly).
    pub fn new(specs: Vec<RunSpec>) -> Self {
        Self {
            calibrations: Some(Vec::new()),
            ..Self::on_machines(
                specs,
                Box::new(RunMachines::for_preset),
                TeachForce::SimulationTruth,
            )
        }
    }

    /// Runs that start from a known calibration when their teach cut would be the one of its
    /// key (the Simulate page keeps the calibrations of its last runs, so an edit that leaves
    /// the teach cut alone re-runs only the loop); [`LabRuns::new`] otherwise.
    pub fn with_calibrations(specs: Vec<RunSpec>, known: Vec<(TeachKey, Calibration)>) -> Self {
        let mut runs = Self::new(specs);
        runs.calibrations = Some(known);
        runs
    }

    /// The runs finished so far and, once the run under way has started its closed loop, that
    /// run up to now (its trace so far, with the metrics of that part): what a page draws while
    /// the work goes on.
    pub fn partial(&self) -> Vec<std::sync::Arc<RunResult>> {
        let mut runs = self.results.clone();
        if let Some(run) = self.current.as_ref().and_then(LabRun::partial_result) {
            runs.push(std::sync::Arc::new(run));
        }
        runs
    }

    /// The teach cuts made or given so far, by key (empty on other machines than the preset's).
    pub fn calibrations(&self) -> &[(TeachKey, Calibration)] {
        self.calibrations.as_deref().unwrap_or(&[])
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
            calibrations: None,
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
                let known = match &self.calibrations {
                    Some(known) => {
                        let key = TeachKey::of(spec)?;
                        known
                            .iter()
                            .find(|(k, _)| *k == key)
                            .map(|(_, c)| c.clone())
                    }
                    None => None,
                };
                let run = match known {
                    Some(calibration) => LabRun::calibrated(spec, calibration)?,
                    None => {
                        let machines = (self.machines)(spec)?;
                        LabRun::on_machines(spec, machines, self.teach_force.clone())?
                    }
                };
                self.current.insert(run)
            }
        };
        if run.advance(budget)? {
            let result = run.finish()?;
            if let Some(known) = &mut self.calibrations {
                let key = TeachKey::of(spec)?;
                if !known.iter().any(|(k, _)| *k == key) {
                    known.push((key, result.calibration.clone()));
                }
            }
            self.results.push(std::sync::Arc::new(result));
            self.current = None;
        }
        Ok(self.results.len() >= self.specs.len())
    }

    fn progress(&self) -> Progress {
        let total = self.specs.len().max(1);
        let index = self.results.len();
        let (stage, part) = match &self.current {
            Some(r) => {
                let p = r.progress();
                (p.stage, p.fraction)
            }
            // Between runs nothing has been done yet for the next one (which may need no teach
            // cut); after the last, the output is being handed over.
            None if index >= self.specs.len() => ("done".to_string(), 0.0),
            None => ("starting".to_string(), 0.0),
        };
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
