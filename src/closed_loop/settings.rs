//! Settings resolved once: what a person asked for and what the machine is, in; one complete,
//! valid set of loop settings out.
//!
//! ```text
//! SettingsOverrides (a form, command-line flags, a saved configuration, a replay's options,
//!   the Hardware page's run) + the controller
//!   + MachineContext (a preset's simulated machine, a device on the serial line, a log)
//!   ──► plan ──► Plan: the signal chain (feedback, control period in whole samples, low-passes),
//!                      the override limits, the time limit and how the target will be set
//!   teach cut ──► Calibration
//!   Plan::settle ──► LoopSettings: the target and everything derived from it (force limit,
//!                      overload limit, air-cut force, the sensor-fault current limit)
//! ```
//!
//! Every front end calls [`plan`] and [`Plan::settle`]: the lab's runs ([`super::lab`]), the
//! reference runs, the tuner, the Hardware page's session and the replay of a log. A setting's
//! default, a derived value and a cross-check (the lowest override not above the highest, the
//! override before arming inside the band) are written here once, so a saved comparison, a replay
//! and a run on a machine resolve the same request to the same numbers. A value that exists is
//! complete: nothing here stands for "not known yet".

use super::definition::{
    check_band, machine_max_override_pct, RunProblem, RunSetting, RunSpec, SettingError,
    SettingsOverrides,
};
use super::error::LoopError;
use super::paper_defaults::{PAPER_002_CONTROL_PERIOD_S, PAPER_002_OUTPUT_RANGE_PCT};
use super::thresholds::{air_cut_force_n, cut_before_arming_force_n};
use crate::control::registry::ControllerConfig;
use crate::estimation::estimator::{Calibration, Feedback};
use crate::plant::cnc::OverrideMode;
use crate::plant::deflection::ErrorModel;
use crate::plant::presets::PlantKind;
use crate::plant::Preset;
use crate::safety::{ArmingTrigger, ChipLoad, EnvelopeConfig, OverrideResolution};

/// Paper 003's analog low-pass on the spindle phase currents, Hz.
pub const DEFAULT_SPINDLE_LOWPASS_HZ: f64 = 260.0;
/// Paper 003's low-pass on the feed phase currents, Hz.
pub const DEFAULT_FEED_LOWPASS_HZ: f64 = 50.0;
/// The order of both low-passes.
pub const DEFAULT_LOWPASS_ORDER: usize = 4;
/// The shortest control period picked by default: a mill's period is a whole number of spindle
/// revolutions at least this long, so the period mean removes the tooth-passing ripple.
pub const MIN_CONTROL_PERIOD_S: f64 = 0.04;
/// The control period of a loop without a spindle to synchronise with.
pub const DEFAULT_CONTROL_PERIOD_S: f64 = 0.05;
/// The metrics' force limit, as a multiple of the target.
pub const FORCE_LIMIT_FACTOR: f64 = 1.2;
/// The overload alarm's hard limit, as a multiple of the target: a tool-breakage limit well above
/// the target, so a fixed-feed baseline through a deep step still completes for the comparison.
pub const OVERLOAD_FACTOR: f64 = 3.0;
/// A target nobody gave is this fraction of the median force the teach cut measured at 100 %
/// override: the force limit 20 % above it then lies just under the load the programmer
/// accepted (teach-in proposes the same).
pub const DEFAULT_TARGET_FRACTION: f64 = 0.8;
/// Relative disagreement between the current-based and the sensorless estimate, beyond the
/// sensorless network's own uncertainty, above which a period predicts a sensor failure (paper
/// 004): a current-based estimate is within 5–15 % of the force where it was calibrated, so 30 %
/// is a sensor that no longer reads as it did.
pub const SENSOR_FAILURE_TOLERANCE: f64 = 0.3;
/// The envelope calls readings stuck only after at least this many identical samples: a slow
/// log's RMS value written to two decimals repeats from one sample to the next without a fault.
const STUCK_SAMPLES: f64 = 10.0;
/// A phase current beyond this multiple of the largest the teach cut saw (its overrides reach
/// 140 %) is a sensor fault, whatever the machine's size.
const FAULT_CURRENT_FACTOR: f64 = 2.0;
/// The entry hold's longest time where the machine gives no cutter to time it by, s.
pub const DEFAULT_ENTRY_HOLD_S: f64 = 1.0;
/// The bounds of an entry hold's settle time derived from the cutter, s.
const ENTRY_HOLD_BOUNDS_S: (f64, f64) = (0.2, 5.0);
/// The most samples a control period may hold.
const MAX_SAMPLES_PER_PERIOD: f64 = 1e7;

/// What the signal chain and the teach cut need: the feedback path, the control period and the
/// current low-passes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChainSettings {
    /// Which current measures the force.
    pub feedback: Feedback,
    /// The control period, a whole number of the machine's samples.
    pub control_period_s: f64,
    /// Low-pass on the spindle phase currents, Hz; infinite: none (an RMS value in a log, or a
    /// cut-off at or above the machine's Nyquist frequency).
    pub spindle_lowpass_hz: f64,
    /// Low-pass on the feed phase currents, Hz; infinite: none.
    pub feed_lowpass_hz: f64,
    /// Order of both Butterworth low-passes.
    pub lowpass_order: usize,
}

/// Settings of a closed-loop run, complete: made by [`Plan::settle`].
#[derive(Debug, Clone, PartialEq)]
pub struct LoopSettings {
    /// Which current the force is measured from.
    pub feedback: Feedback,
    /// The controller's period, a whole number of the machine's samples.
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
    /// The estimated force above which a period before arming is a cut the controller cannot
    /// shape, warned about once ([`cut_before_arming_force_n`]).
    pub cut_before_arming_force_n: f64,
    /// The safety envelope.
    pub envelope: EnvelopeConfig,
    /// The run stops here if the program has not ended.
    pub max_duration_s: f64,
    /// Relative disagreement between the current-based and the sensorless estimate above which a
    /// period predicts a sensor failure ([`SENSOR_FAILURE_TOLERANCE`]).
    pub sensor_failure_tolerance: f64,
    /// The tool and spindle as springs and the force's normal share, if the tool is known: the
    /// trace's surface error and what remains of it after compensation.
    pub error_model: Option<ErrorModel>,
}

impl LoopSettings {
    /// The signal chain's part.
    pub fn chain(&self) -> ChainSettings {
        ChainSettings {
            feedback: self.feedback,
            control_period_s: self.control_period_s,
            spindle_lowpass_hz: self.spindle_lowpass_hz,
            feed_lowpass_hz: self.feed_lowpass_hz,
            lowpass_order: self.lowpass_order,
        }
    }
}

/// Where a program runs: its spindle speed and feed at 100 % override (NaN where unknown).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct OperatingPoint {
    /// Spindle speed, rpm.
    pub spindle_rpm: f64,
    /// Programmed feed, mm/min.
    pub feed_mm_min: f64,
}

impl OperatingPoint {
    /// Where `spec`'s program runs: its preset's speed and feed, or the plant edits'.
    pub fn of_preset(spec: &RunSpec) -> Self {
        let summary = spec.preset.summary();
        Self {
            spindle_rpm: spec
                .plant
                .spindle_rpm
                .or(summary.spindle_rpm)
                .unwrap_or(f64::NAN),
            feed_mm_min: spec
                .plant
                .programmed_feed_mm_min
                .or(summary.programmed_feed_mm_min)
                .unwrap_or(f64::NAN),
        }
    }
}

/// How the control period is chosen when nobody gave one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PeriodRule {
    /// Whole spindle revolutions, at least [`MIN_CONTROL_PERIOD_S`], with a spindle running
    /// (whatever the feedback path); else [`DEFAULT_CONTROL_PERIOD_S`].
    WholeRevolutions,
    /// This period, s.
    Fixed(f64),
}

/// How fast the envelope lets the override change when nobody said.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RateRule {
    /// This many % per second.
    PerSecond(f64),
    /// This many % per control period.
    PerPeriod(f64),
}

/// When a run is stopped if its program has not ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimeLimit {
    /// A program that takes this long at 100 % override: three times that, more for slow fixed
    /// feeds and low override floors ([`program_time_limit_s`]).
    Program {
        /// Its duration at 100 %, s.
        nominal_duration_s: f64,
    },
    /// A record of this length (a log): its end ends the run.
    Record {
        /// The record's length, s.
        duration_s: f64,
    },
}

/// What a motor's current is, as the machine delivers it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CurrentSignal {
    /// Phase currents: the low-pass acts on them before the RMS.
    Phases,
    /// An RMS value standing for the three phases (a drive's slow log): no low-pass.
    Rms,
}

/// What the machine is, as far as the settings need to know: its sampling, its program, its
/// override input and the defaults that follow from them.
#[derive(Debug, Clone, PartialEq)]
pub struct MachineContext {
    /// Samples per second the machine delivers.
    pub sample_rate_hz: f64,
    /// Where its program runs.
    pub operating_point: OperatingPoint,
    /// The feedback path used when nobody chose one.
    pub default_feedback: Feedback,
    /// How the default control period is chosen.
    pub period_rule: PeriodRule,
    /// The override positions the machine applies.
    pub resolution: OverrideResolution,
    /// The highest override the machine applies, %.
    pub max_override_pct: f64,
    /// The lowest and highest override allowed when nobody said, %.
    pub default_band_pct: (f64, f64),
    /// The rate limit when nobody said.
    pub default_rate: RateRule,
    /// What starts the envelope's arming delay.
    pub arming_trigger: ArmingTrigger,
    /// The program's own force target on the default feedback path, N (a mill's mean resultant).
    pub target_force_n: Option<f64>,
    /// The program's own target as a spindle current, A (paper 002's I_ref).
    pub target_current_a: Option<f64>,
    /// When the run is stopped.
    pub time_limit: TimeLimit,
    /// The spindle current as delivered.
    pub spindle_current: CurrentSignal,
    /// The feed-drive current as delivered.
    pub feed_current: CurrentSignal,
    /// How long the entry override is held at most after the tool enters a cut, when nobody
    /// said, s.
    pub entry_hold_s: f64,
    /// The cutter's chip-load window in the work material, if the machine's tool and material
    /// are known.
    pub chip_load: Option<ChipLoad>,
    /// The force-induced error's model, if the machine's tool is known.
    pub error_model: Option<ErrorModel>,
}

/// The feedback path a preset measures force with by default: the brake bench has only a feed
/// drive; paper 001's second-order plant is judged by its dynamometer; everything else uses the
/// spindle, as paper 003 and paper 002 do.
pub fn default_feedback(preset: Preset) -> Feedback {
    match preset.plant_kind() {
        PlantKind::BrakeBench => Feedback::FeedCurrent,
        PlantKind::SecondOrder => Feedback::Dynamometer,
        _ => Feedback::SpindleCurrent,
    }
}

/// The override positions the envelope commands on a machine with `mode`.
pub fn envelope_resolution(mode: &OverrideMode) -> OverrideResolution {
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

impl MachineContext {
    /// The machine of `spec`'s preset (its plant edits included), sampling at `sample_rate_hz`
    /// (the simulation's rate, or the rate a device on the serial line reports).
    pub fn of_preset(spec: &RunSpec, sample_rate_hz: f64) -> Self {
        let preset = spec.preset;
        let summary = preset.summary();
        let bond_graph = preset.plant_kind() == PlantKind::BondGraph;
        Self {
            sample_rate_hz,
            operating_point: OperatingPoint::of_preset(spec),
            default_feedback: default_feedback(preset),
            period_rule: if bond_graph {
                PeriodRule::Fixed(PAPER_002_CONTROL_PERIOD_S)
            } else {
                PeriodRule::WholeRevolutions
            },
            resolution: envelope_resolution(&preset.override_mode()),
            max_override_pct: machine_max_override_pct(preset),
            default_band_pct: super::definition::default_override_band_pct(preset),
            // Paper 002's fuzzy law moves the feed by up to k_u·6 = 100 % in one sampling period;
            // the envelope on its preset lets that action through (the mills keep 100 %/s).
            default_rate: if bond_graph {
                RateRule::PerPeriod(PAPER_002_OUTPUT_RANGE_PCT)
            } else {
                RateRule::PerSecond(EnvelopeConfig::default_for_dial().max_rate_pct_per_s)
            },
            // The bench has no spindle: its "start" is the feed drive's.
            arming_trigger: if preset.plant_kind() == PlantKind::BrakeBench {
                ArmingTrigger::ProgrammedFeed
            } else {
                ArmingTrigger::SpindleStart
            },
            target_force_n: preset.target_force_n(),
            target_current_a: preset.target_spindle_current_a(),
            time_limit: TimeLimit::Program {
                nominal_duration_s: summary.nominal_duration_s,
            },
            spindle_current: CurrentSignal::Phases,
            feed_current: CurrentSignal::Phases,
            entry_hold_s: preset_entry_hold_s(spec),
            chip_load: preset_chip_load(spec),
            error_model: preset_error_model(spec),
        }
    }
}

/// The time `spec`'s program takes to feed its cutter one radius at the programmed feed (the
/// cutter is fully engaged by then, in a slot or a side cut), bounded to [`ENTRY_HOLD_BOUNDS_S`];
/// the default without a cutter.
fn preset_entry_hold_s(spec: &RunSpec) -> f64 {
    let Some(scenario) = spec.preset.scenario_spec() else {
        return DEFAULT_ENTRY_HOLD_S;
    };
    let diameter_mm = spec
        .plant
        .tool_diameter_mm
        .unwrap_or(scenario.cutter.diameter_mm);
    let feed_mm_s = OperatingPoint::of_preset(spec).feed_mm_min / 60.0;
    let (lo, hi) = ENTRY_HOLD_BOUNDS_S;
    let settle_s = 0.5 * diameter_mm / feed_mm_s;
    if settle_s.is_finite() {
        settle_s.clamp(lo, hi)
    } else {
        DEFAULT_ENTRY_HOLD_S
    }
}

/// The force-induced error's model of `spec`'s program (its edits included), on a mill; `None` on
/// the plants without a tool (the bench, paper 001's process, paper 002's bond graph).
fn preset_error_model(spec: &RunSpec) -> Option<ErrorModel> {
    if spec.preset.plant_kind() != PlantKind::Mill {
        return None;
    }
    ErrorModel::of_program(
        &spec.preset.edited_scenario_spec(&spec.plant)?,
        spec.plant.tool_mount(),
    )
}

/// The chip-load window of `spec`'s cutter (its edits included) in the materials of its part: on
/// a part of several, the window spans them all ([`crate::plant::materials::Material::Composite`]
/// says why).
fn preset_chip_load(spec: &RunSpec) -> Option<ChipLoad> {
    let scenario = spec.preset.scenario_spec()?;
    let diameter_mm = spec
        .plant
        .tool_diameter_mm
        .unwrap_or(scenario.cutter.diameter_mm);
    let teeth = spec.plant.teeth.unwrap_or(scenario.cutter.teeth);
    let materials: Vec<_> = match spec.plant.material {
        Some(m) => vec![m],
        None => scenario.materials.iter().map(|r| r.material).collect(),
    };
    let (min_mm, max_mm) = materials.iter().fold((f64::INFINITY, 0.0), |(lo, hi), m| {
        let (a, b) = m.feed_per_tooth_window_mm(diameter_mm);
        (f64::min(lo, a), f64::max(hi, b))
    });
    (min_mm > 0.0 && min_mm < max_mm).then_some(ChipLoad {
        teeth,
        min_mm,
        max_mm,
    })
}

/// How the target will be set once the teach cut is known.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TargetRule {
    /// This force, N, on the run's feedback path.
    Force(f64),
    /// A mean resultant force, N, turned into the run's (feed) force by the ratio the teach cut
    /// saw ([`Calibration::regulated_per_resultant`]).
    Resultant(f64),
    /// A current, A, turned into a force through the calibrated model at the operating point.
    Current(f64),
    /// [`DEFAULT_TARGET_FRACTION`] of the teach cut's median force at 100 % override.
    FromTeachCut,
}

impl TargetRule {
    /// Where the target comes from, in words.
    pub fn describe(&self) -> String {
        let readable = crate::input::readable;
        match self {
            TargetRule::Force(f) => format!("the target force {} N", readable(*f)),
            TargetRule::Resultant(f) => format!(
                "the program's {} N mean resultant on this feedback path",
                readable(*f)
            ),
            TargetRule::Current(a) => format!(
                "the target current {} A through the calibrated model",
                readable(*a)
            ),
            TargetRule::FromTeachCut => format!(
                "{} % of the teach cut's median force at 100 % override",
                DEFAULT_TARGET_FRACTION * 100.0
            ),
        }
    }
}

/// The override limits of a run: the band, the rate limit and the override before arming.
#[derive(Debug, Clone, PartialEq)]
pub struct OverrideLimits {
    /// Lowest override, %.
    pub min_override_pct: f64,
    /// Highest override, %.
    pub max_override_pct: f64,
    /// Fastest change, %/s.
    pub max_rate_pct_per_s: f64,
    /// Held until the envelope arms, %.
    pub arming_override_pct: f64,
    /// The machine's override positions.
    pub resolution: OverrideResolution,
    /// What starts the arming delay.
    pub arming_trigger: ArmingTrigger,
}

/// A run's settings before its calibration is known: all a teach cut needs, and how the rest
/// follows once it has been made. Two requests that spell the same settings differently (a
/// default left out or typed in) have equal plans.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// The signal chain.
    pub chain: ChainSettings,
    /// The override limits.
    pub limits: OverrideLimits,
    /// How the target will be set.
    pub target: TargetRule,
    /// Where the program runs (a current target's force is read there).
    pub operating_point: OperatingPoint,
    /// When the run (and its teach cut) is stopped.
    pub max_duration_s: f64,
    /// The shortest time readings must repeat to be a stuck sensor.
    pub stuck_after_s: f64,
    /// The override the tool enters a cut with, held at most until the load settles, %.
    pub entry_override_pct: f64,
    /// How long the entry override is held at most after an entry, s (0: no entry hold).
    pub entry_hold_s: f64,
    /// Whether the envelope holds the entry override while the tool is in air (not for a fixed
    /// feed).
    pub holds_in_air: bool,
    /// The feed-per-tooth window the override keeps inside.
    pub chip_load: Option<ChipLoad>,
    /// The force-induced error's model, for the surface error and its compensation.
    pub error_model: Option<ErrorModel>,
    /// What the resolution adapted to the machine (a low-pass skipped, the period rounded), for
    /// people.
    pub notes: Vec<String>,
}

fn refuse(setting: RunSetting, problem: RunProblem) -> LoopError {
    LoopError::Setting(SettingError { setting, problem })
}

/// Resolves what `settings` asks of a run of `controller` on the machine `context` describes:
/// defaults filled, the period rounded to whole samples, the override limits checked against
/// each other (a band refused, never swapped or clamped).
///
/// ```
/// use cutlab::closed_loop::definition::RunSpec;
/// use cutlab::closed_loop::settings::{plan, MachineContext};
/// use cutlab::control::registry::ControllerKind;
/// use cutlab::plant::Preset;
/// let mut spec = RunSpec::new(Preset::KimStepDoc, ControllerKind::Pi);
/// spec.settings.control_period_s = Some(0.04138);
/// let context = MachineContext::of_preset(&spec, 10_000.0);
/// let p = plan(&spec.settings, &spec.controller, &context).unwrap();
/// assert_eq!(p.chain.control_period_s, 414.0 / 10_000.0); // whole samples
/// spec.settings.min_override_pct = Some(120.0);
/// spec.settings.max_override_pct = Some(80.0);
/// let e = plan(&spec.settings, &spec.controller, &context).unwrap_err();
/// assert!(e.to_string().contains("above the highest"), "{e}");
/// ```
pub fn plan(
    settings: &SettingsOverrides,
    controller: &ControllerConfig,
    context: &MachineContext,
) -> Result<Plan, LoopError> {
    let mut notes = Vec::new();
    let feedback = settings.feedback.unwrap_or(context.default_feedback);
    let control_period_s = control_period_s(settings, context, &mut notes)?;
    let nyquist_hz = 0.5 * context.sample_rate_hz;
    let spindle_lowpass_hz = lowpass_hz(
        settings
            .spindle_lowpass_hz
            .unwrap_or(DEFAULT_SPINDLE_LOWPASS_HZ),
        "spindle",
        context.spindle_current,
        feedback != Feedback::FeedCurrent,
        nyquist_hz,
        &mut notes,
    );
    let feed_lowpass_hz = lowpass_hz(
        settings.feed_lowpass_hz.unwrap_or(DEFAULT_FEED_LOWPASS_HZ),
        "feed-drive",
        context.feed_current,
        feedback == Feedback::FeedCurrent,
        nyquist_hz,
        &mut notes,
    );
    let chain = ChainSettings {
        feedback,
        control_period_s,
        spindle_lowpass_hz,
        feed_lowpass_hz,
        lowpass_order: settings.lowpass_order.unwrap_or(DEFAULT_LOWPASS_ORDER),
    };
    let limits = override_limits(settings, context, control_period_s)?;
    let target = match (settings.target_force_n, settings.target_current_a) {
        (Some(force_n), _) => TargetRule::Force(force_n),
        (None, Some(current_a)) => TargetRule::Current(current_a),
        // The program's target is a force on its own feedback path (a mill's mean resultant, the
        // bench's feed force); on the other path it is converted by what the teach cut saw.
        (None, None) => match (context.target_force_n, context.target_current_a) {
            (Some(f), _) if feedback == context.default_feedback => TargetRule::Force(f),
            (Some(f), _) => TargetRule::Resultant(f),
            (None, Some(a)) if feedback == Feedback::SpindleCurrent => TargetRule::Current(a),
            _ => TargetRule::FromTeachCut,
        },
    };
    let max_duration_s = match context.time_limit {
        TimeLimit::Program { nominal_duration_s } => {
            program_time_limit_s(nominal_duration_s, controller, limits.min_override_pct)
        }
        // The record's end, not a time limit, ends the run.
        TimeLimit::Record { duration_s } => duration_s.abs() + control_period_s + 1.0,
    };
    let stuck_after_s = EnvelopeConfig::default_for_dial()
        .stuck_after_s
        .max(STUCK_SAMPLES / context.sample_rate_hz);
    // A fixed feed is the baseline the others are judged against, the program as a machinist
    // runs it: neither the air rule nor an entry hold shapes it.
    let adaptive = controller.fixed_override_pct().is_none();
    let entry_hold_s = if adaptive {
        settings.entry_hold_s.unwrap_or(context.entry_hold_s)
    } else {
        0.0
    };
    let entry_override_pct = settings
        .entry_override_pct
        .unwrap_or(EnvelopeConfig::default_for_dial().entry_override_pct)
        .clamp(limits.min_override_pct, limits.max_override_pct);
    let chip_load = chip_window(settings, context)?;
    Ok(Plan {
        chain,
        limits,
        target,
        operating_point: context.operating_point,
        max_duration_s,
        stuck_after_s,
        entry_override_pct,
        entry_hold_s,
        holds_in_air: adaptive,
        chip_load,
        error_model: context.error_model,
        notes,
    })
}

/// The machine's chip-load window with the ends the settings give in its place; refused when its
/// smallest feed per tooth is not below its largest.
fn chip_window(
    settings: &SettingsOverrides,
    context: &MachineContext,
) -> Result<Option<ChipLoad>, LoopError> {
    let Some(machine) = context.chip_load else {
        return Ok(None);
    };
    let window = ChipLoad {
        min_mm: settings.min_feed_per_tooth_mm.unwrap_or(machine.min_mm),
        max_mm: settings.max_feed_per_tooth_mm.unwrap_or(machine.max_mm),
        ..machine
    };
    if window.min_mm >= window.max_mm {
        let setting = if settings.min_feed_per_tooth_mm.is_some() {
            RunSetting::MinFeedPerTooth
        } else {
            RunSetting::MaxFeedPerTooth
        };
        let problem = RunProblem::WindowInverted {
            min: window.min_mm,
            max: window.max_mm,
        };
        return Err(refuse(setting, problem));
    }
    Ok(Some(window))
}

/// The control period: the one asked for, else the context's rule; in whole samples.
///
/// Whole revolutions whatever the feedback path: the feed force ripples with the teeth as the
/// spindle's torque does, and a period of a fraction of a revolution more or less aliases that
/// ripple into its mean (kim-step-doc with feed-current feedback at 50 ms against a 60 ms
/// revolution: a period mean swinging 91–173 N over three periods in a steady 2 mm cut, a
/// teach-cut fit of R² 0.54, and the air-cut rule taking every third period for air).
fn control_period_s(
    settings: &SettingsOverrides,
    context: &MachineContext,
    notes: &mut Vec<String>,
) -> Result<f64, LoopError> {
    let rate_hz = context.sample_rate_hz;
    let asked = settings.control_period_s;
    let period_s = asked.unwrap_or_else(|| match context.period_rule {
        PeriodRule::Fixed(p) => p,
        PeriodRule::WholeRevolutions => {
            let rpm = context.operating_point.spindle_rpm;
            if rpm > 0.0 {
                let revolution_s = 60.0 / rpm;
                (MIN_CONTROL_PERIOD_S / revolution_s).ceil() * revolution_s
            } else {
                DEFAULT_CONTROL_PERIOD_S
            }
        }
    });
    let samples = (period_s * rate_hz).round();
    if !(1.0..=MAX_SAMPLES_PER_PERIOD).contains(&samples) {
        let problem = RunProblem::PeriodInSamples {
            period_s,
            sample_period_s: 1.0 / rate_hz,
        };
        return Err(refuse(RunSetting::ControlPeriod, problem));
    }
    let whole_s = samples / rate_hz;
    if let Some(asked_s) = asked {
        if (whole_s - asked_s).abs() > 1e-9 * asked_s {
            let readable = crate::input::readable;
            notes.push(format!(
                "the control period {} s is rounded to {} s, {} samples of {} s",
                readable(asked_s),
                readable(whole_s),
                samples,
                readable(1.0 / rate_hz)
            ));
        }
    }
    Ok(whole_s)
}

/// The low-pass a motor's current can take: the given cut-off, or none (infinite) for an RMS
/// value or a cut-off at or above the Nyquist frequency, with a note saying so where that motor
/// measures the force.
fn lowpass_hz(
    cutoff_hz: f64,
    motor: &str,
    signal: CurrentSignal,
    measures_force: bool,
    nyquist_hz: f64,
    notes: &mut Vec<String>,
) -> f64 {
    let readable = crate::input::readable;
    if signal == CurrentSignal::Rms {
        if measures_force {
            notes.push(format!(
                "the {motor} current is an RMS value: the chain's low-pass and three-phase RMS \
                 stages are skipped (they act on phase currents); the period mean of the value \
                 is the current"
            ));
        }
        return f64::INFINITY;
    }
    if cutoff_hz >= nyquist_hz {
        if measures_force {
            notes.push(format!(
                "the machine samples at {} Hz: the {motor} low-pass at {} Hz is at or above its \
                 Nyquist frequency ({} Hz), so that stage is skipped",
                readable(2.0 * nyquist_hz),
                readable(cutoff_hz),
                readable(nyquist_hz)
            ));
        }
        return f64::INFINITY;
    }
    cutoff_hz
}

/// The band, rate limit and arming override: asked for, else the machine's defaults; the band
/// must hold the override before arming, and its lowest end must not lie above its highest.
fn override_limits(
    settings: &SettingsOverrides,
    context: &MachineContext,
    control_period_s: f64,
) -> Result<OverrideLimits, LoopError> {
    let (min, max) = check_band(settings, context.default_band_pct).map_err(LoopError::Setting)?;
    let arming = settings.arming_override_pct.unwrap_or_else(|| {
        // The default (100 %) follows a band set below or above it.
        EnvelopeConfig::default_for_dial()
            .arming_override_pct
            .clamp(min, max)
    });
    let rate = settings
        .max_rate_pct_per_s
        .unwrap_or(match context.default_rate {
            RateRule::PerSecond(r) => r,
            RateRule::PerPeriod(pct) => pct / control_period_s,
        });
    Ok(OverrideLimits {
        min_override_pct: min,
        max_override_pct: max,
        max_rate_pct_per_s: rate,
        arming_override_pct: arming,
        resolution: context.resolution.clone(),
        arming_trigger: context.arming_trigger,
    })
}

/// The time a run may take before it is stopped: three times the program's nominal duration,
/// and for a fixed feed below 100 % that much longer again (a reference run at 20 % takes five
/// times the program's time and must still finish to count); and at least half again the time
/// the program takes at the envelope's lowest override, which a controller may hold for long
/// stretches (feed-current feedback on a mill holds 10–20 % through paper 003's deep steps).
pub fn program_time_limit_s(
    nominal_duration_s: f64,
    controller: &ControllerConfig,
    min_override_pct: f64,
) -> f64 {
    let nominal_s = nominal_duration_s.max(1.0);
    let slowdown = |pct: f64| (100.0 / pct.max(1.0)).max(1.0);
    let fixed = controller.fixed_override_pct().map_or(1.0, slowdown);
    let slowest = 1.5 * slowdown(min_override_pct);
    nominal_s * (3.0 * fixed).max(slowest) + 10.0
}

impl Plan {
    /// What a run resolves for `setting` where its field is left blank, as a person would type
    /// it — the form's placeholder: the plan's value (the preset's, adapted to the machine), or for
    /// a machine edit the preset's cut. `None` where the run decides later (a target taken from
    /// the teach cut), the setting has no value on this preset, or a blank means nothing.
    ///
    /// ```
    /// use cutlab::closed_loop::definition::{RunSetting, RunSpec};
    /// use cutlab::closed_loop::lab::preset_plan;
    /// use cutlab::control::registry::ControllerKind;
    /// use cutlab::plant::Preset;
    /// let spec = RunSpec::new(Preset::KimStepDoc, ControllerKind::Threshold);
    /// let plan = preset_plan(&spec).unwrap();
    /// assert_eq!(plan.planned_text(RunSetting::MaxOverride, &spec).as_deref(), Some("255"));
    /// assert_eq!(plan.planned_text(RunSetting::Teeth, &spec).as_deref(), Some("2"));
    /// assert_eq!(plan.planned_text(RunSetting::Seed, &spec), None);
    /// ```
    pub fn planned_text(&self, setting: RunSetting, spec: &RunSpec) -> Option<String> {
        let plan = self;
        let cut = || spec.preset.edited_scenario_spec(&spec.plant);
        let number = match setting {
            RunSetting::Seed
            | RunSetting::LoadStep
            | RunSetting::DepthScale
            | RunSetting::SensorNoise => None,
            RunSetting::TargetCurrent => match plan.target {
                TargetRule::Current(a) => Some(a),
                _ => None,
            },
            RunSetting::TargetForce => match plan.target {
                TargetRule::Force(n) | TargetRule::Resultant(n) => Some(n),
                TargetRule::Current(_) | TargetRule::FromTeachCut => None,
            },
            RunSetting::Feedback => return Some(plan.chain.feedback.name().to_string()),
            RunSetting::Material => {
                let cut = cut()?;
                let [region] = cut.materials.as_slice() else {
                    return None;
                };
                return Some(region.material.name().to_string());
            }
            RunSetting::Teeth => return cut().map(|c| c.cutter.teeth.to_string()),
            RunSetting::FilterOrder => return Some(plan.chain.lowpass_order.to_string()),
            RunSetting::MaxOverride => Some(plan.limits.max_override_pct),
            RunSetting::MinOverride => Some(plan.limits.min_override_pct),
            RunSetting::MaxRate => Some(plan.limits.max_rate_pct_per_s),
            RunSetting::ArmingOverride => Some(plan.limits.arming_override_pct),
            RunSetting::EntryOverride => Some(plan.entry_override_pct),
            RunSetting::EntryHoldTime => Some(plan.entry_hold_s),
            RunSetting::MinFeedPerTooth => plan.chip_load.map(|c| c.min_mm),
            RunSetting::MaxFeedPerTooth => plan.chip_load.map(|c| c.max_mm),
            RunSetting::ControlPeriod => Some(plan.chain.control_period_s),
            RunSetting::SpindleCutoff => Some(plan.chain.spindle_lowpass_hz),
            RunSetting::FeedCutoff => Some(plan.chain.feed_lowpass_hz),
            RunSetting::SpindleSpeed => Some(plan.operating_point.spindle_rpm),
            RunSetting::ProgrammedFeed => Some(plan.operating_point.feed_mm_min),
            RunSetting::ToolDiameter => cut().map(|c| c.cutter.diameter_mm),
            RunSetting::ToolStickOut => cut().map(|c| {
                spec.plant
                    .tool_mount()
                    .stick_out_or_default_mm(c.cutter.diameter_mm)
            }),
            RunSetting::ToolModulus => {
                cut().map(|_| spec.plant.tool_mount().youngs_modulus_or_default_gpa())
            }
            RunSetting::SpindleStiffness => {
                cut().map(|_| spec.plant.tool_mount().spindle_stiffness_or_default_n_um())
            }
        };
        number.filter(|v| v.is_finite()).map(crate::input::readable)
    }

    /// The target, N, once `calibration` is known.
    pub fn target_force_n(&self, calibration: &Calibration) -> Result<f64, LoopError> {
        let at = self.operating_point;
        let target = match self.target {
            TargetRule::Force(f) => f,
            TargetRule::Resultant(f) => f * calibration.regulated_per_resultant,
            TargetRule::Current(a) => {
                calibration
                    .estimator
                    .force_for_current_n(a, at.spindle_rpm, at.feed_mm_min)
            }
            TargetRule::FromTeachCut => {
                DEFAULT_TARGET_FRACTION * calibration.median_force_at_full_override_n
            }
        };
        if target.is_finite() && target > 0.0 {
            Ok(target)
        } else {
            Err(LoopError::NoTarget {
                from: self.target.describe(),
                force_n: target,
            })
        }
    }

    /// The complete settings once `calibration` is known (refused when it reads another
    /// feedback path than the run's): the target and every limit derived from it, the air-cut force from the calibration's reading in air, the sensor-fault current
    /// limit from the largest current the teach cut saw.
    pub fn settle(&self, calibration: &Calibration) -> Result<LoopSettings, LoopError> {
        let calibration_feedback = calibration.estimator.feedback();
        if calibration_feedback != self.chain.feedback {
            return Err(LoopError::CalibrationFeedback {
                calibration: calibration_feedback,
                run: self.chain.feedback,
            });
        }
        let at = self.operating_point;
        if let Some(why) = calibration
            .estimator
            .not_calibrated_at(at.spindle_rpm, at.feed_mm_min)
        {
            return Err(LoopError::CalibrationElsewhere(why));
        }
        let target_force_n = self.target_force_n(calibration)?;
        let l = &self.limits;
        let mut envelope = EnvelopeConfig {
            min_override_pct: l.min_override_pct,
            max_override_pct: l.max_override_pct,
            max_rate_pct_per_s: l.max_rate_pct_per_s,
            arming_override_pct: l.arming_override_pct,
            resolution: l.resolution.clone(),
            arming_trigger: l.arming_trigger,
            stuck_after_s: self.stuck_after_s,
            air_cut_force_n: if self.holds_in_air {
                air_cut_force_n(
                    target_force_n,
                    calibration.air_force_estimate_n,
                    calibration.median_force_at_full_override_n,
                )
            } else {
                0.0
            },
            entry_override_pct: self.entry_override_pct,
            entry_hold_s: self.entry_hold_s,
            entry_release_n: target_force_n,
            chip_load: self.chip_load,
            overload_limit_n: OVERLOAD_FACTOR * target_force_n,
            ..EnvelopeConfig::default_for_dial()
        };
        if calibration.max_phase_current_a.is_finite() && calibration.max_phase_current_a > 0.0 {
            envelope.max_current_a = FAULT_CURRENT_FACTOR * calibration.max_phase_current_a;
        }
        let c = &self.chain;
        Ok(LoopSettings {
            feedback: c.feedback,
            control_period_s: c.control_period_s,
            spindle_lowpass_hz: c.spindle_lowpass_hz,
            feed_lowpass_hz: c.feed_lowpass_hz,
            lowpass_order: c.lowpass_order,
            target_force_n,
            force_limit_n: FORCE_LIMIT_FACTOR * target_force_n,
            cut_before_arming_force_n: cut_before_arming_force_n(
                target_force_n,
                calibration.air_force_estimate_n,
                calibration.estimator.residual_std_n(at.spindle_rpm),
            ),
            envelope,
            max_duration_s: self.max_duration_s,
            sensor_failure_tolerance: SENSOR_FAILURE_TOLERANCE,
            error_model: self.error_model,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::registry::ControllerKind;

    #[test]
    fn a_blank_field_on_a_mill_preset_shows_what_the_run_uses() {
        let spec = RunSpec::new(Preset::KimStepDoc, ControllerKind::Threshold);
        let plan = crate::closed_loop::lab::preset_plan(&spec).unwrap();
        let decided_elsewhere = [
            RunSetting::Seed,
            RunSetting::LoadStep,
            RunSetting::DepthScale,
            RunSetting::SensorNoise,
            RunSetting::TargetCurrent,
        ];
        for setting in RunSetting::ALL {
            let text = plan.planned_text(setting, &spec);
            assert_eq!(
                text.is_none(),
                decided_elsewhere.contains(&setting),
                "{setting:?}: {text:?}"
            );
            if let Some(text) = text {
                assert!(
                    setting.parse(&text, spec.preset).is_ok(),
                    "{setting:?}: {text} is refused"
                );
            }
        }
        assert_eq!(
            plan.planned_text(RunSetting::SpindleSpeed, &spec)
                .as_deref(),
            Some("1000")
        );
    }

    fn context_and_spec(preset: Preset) -> (MachineContext, RunSpec) {
        let spec = RunSpec::new(preset, ControllerKind::Pi);
        (MachineContext::of_preset(&spec, 10_000.0), spec)
    }

    #[test]
    fn an_inverted_band_is_refused_naming_the_setting_given() {
        let (context, mut spec) = context_and_spec(Preset::ManeeratDoc1);
        spec.settings.min_override_pct = Some(200.0);
        let e = plan(&spec.settings, &spec.controller, &context).unwrap_err();
        let LoopError::Setting(e) = e else {
            panic!("{e}")
        };
        assert_eq!(e.setting, RunSetting::MinOverride);
        assert_eq!(
            e.problem.to_string(),
            "the lowest override 200 % is above the highest, 150 %"
        );
    }

    #[test]
    fn the_period_is_whole_samples_and_a_period_below_one_sample_is_refused() {
        let (mut context, spec) = context_and_spec(Preset::ManeeratDoc1);
        context.sample_rate_hz = 10.0;
        let mut settings = spec.settings;
        settings.control_period_s = Some(0.25);
        let p = plan(&settings, &spec.controller, &context).unwrap();
        // 2.5 samples round half away from zero, to 3.
        assert_eq!(p.chain.control_period_s, 0.3);
        assert!(p.notes[0].contains("rounded to 0.3 s"), "{:?}", p.notes);
        settings.control_period_s = Some(0.04);
        let e = plan(&settings, &spec.controller, &context).unwrap_err();
        assert!(e.to_string().contains("one sample"), "{e}");
    }

    #[test]
    fn a_cutoff_above_nyquist_or_on_an_rms_value_is_skipped_with_a_note() {
        let (mut context, spec) = context_and_spec(Preset::ManeeratDoc1);
        context.sample_rate_hz = 400.0;
        let p = plan(&spec.settings, &spec.controller, &context).unwrap();
        assert_eq!(p.chain.spindle_lowpass_hz, f64::INFINITY);
        assert_eq!(p.chain.feed_lowpass_hz, 50.0);
        assert!(
            p.notes.iter().any(|n| n.contains("Nyquist")),
            "{:?}",
            p.notes
        );
        context.sample_rate_hz = 10_000.0;
        context.feed_current = CurrentSignal::Rms;
        let p = plan(&spec.settings, &spec.controller, &context).unwrap();
        assert_eq!(p.chain.feed_lowpass_hz, f64::INFINITY);
        // Not the feedback path: skipped without a word.
        assert!(p.notes.is_empty(), "{:?}", p.notes);
    }
}
