//! The run definition: every setting a person may change about a run, described once.
//!
//! A run is a preset (the experiment), a controller with its parameters, a seed, and the settings
//! below, each of which keeps the preset's value when left out. This table is the only place a
//! setting's names, unit and accepted range are written: the browser's form fields, the command
//! line's options (`cutlab sim --help`) and a saved configuration's JSON all parse and check
//! through it, so a value one of them accepts the others accept too, with the same message.
//!
//! | setting | JSON field | URL key | option | unit | range |
//! |---|---|---|---|---|---|
//! | see [`RunSetting::ALL`] and `docs/run-definition.md` | | | | | |
//!
//! A range may depend on the preset: the highest override cannot exceed what the preset's
//! machine applies (a 16-grade dial stops at 150 %, paper 003's override at 255 %).

use std::fmt;

use serde::{Deserialize, Serialize};

use crate::control::registry::{ControllerConfig, ControllerKind};
use crate::estimation::estimator::Feedback;
use crate::input::{parse_count, parse_number, parse_seed, readable, table};
use crate::plant::cnc::{OverrideMode, MAX_OVERRIDE_PCT};
use crate::plant::deflection::{
    SPINDLE_STIFFNESS_RANGE_N_UM, STICK_OUT_RANGE_MM, YOUNGS_MODULUS_RANGE_GPA,
};
use crate::plant::materials::Material;
use crate::plant::mechanics::{DIAMETER_RANGE_MM, MAX_TEETH};
use crate::plant::presets::PlantEdits;
use crate::plant::Preset;
use crate::safety::EnvelopeConfig;

use super::paper_defaults::preset_controller;

/// Everything that defines a run; the same spec and seed give the same trace. Its JSON form is
/// what a saved configuration holds ([`super::config`]). Read from JSON, a controller's missing
/// parameters take the preset's values ([`preset_controller`], as a run made by a form or the
/// command line does).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RunSpecText")]
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
    /// Target current (through the calibrated model), when no force is given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target_current_a: Option<f64>,
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
    /// The override the tool enters a cut with.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub entry_override_pct: Option<f64>,
    /// How long the entry override is held at most after an entry.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub entry_hold_s: Option<f64>,
    /// Smallest feed per tooth.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_feed_per_tooth_mm: Option<f64>,
    /// Largest feed per tooth.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_feed_per_tooth_mm: Option<f64>,
}

/// A run spec as a saved configuration writes it, before its controller takes the preset's
/// defaults and its settings are checked.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RunSpecText {
    preset: Preset,
    controller: crate::control::registry::ControllerText,
    seed: u64,
    #[serde(default)]
    settings: SettingsOverrides,
    #[serde(default)]
    plant: PlantEdits,
}

impl TryFrom<RunSpecText> for RunSpec {
    type Error = String;

    fn try_from(text: RunSpecText) -> Result<Self, String> {
        let preset = text.preset;
        let controller = text
            .controller
            .resolve(|kind| preset_controller(preset, kind))
            .map_err(|e| format!("controller: {e}"))?;
        // The settings are checked by the reader of the whole configuration
        // ([`super::config::RunConfiguration::from_json`]), which names the run.
        Ok(RunSpec {
            preset,
            controller,
            seed: text.seed,
            settings: text.settings,
            plant: text.plant,
        })
    }
}

impl RunSpec {
    /// A run of `preset` with `controller` at its defaults and seed 1.
    pub fn new(preset: Preset, controller: ControllerKind) -> Self {
        Self {
            preset,
            controller: preset_controller(preset, controller),
            seed: 1,
            settings: SettingsOverrides::default(),
            plant: PlantEdits::default(),
        }
    }
}

/// Which group of the form a setting belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SettingGroup {
    /// Seed, target, feedback and the safety envelope's override band.
    Scenario,
    /// Control period and the current filters.
    SignalChain,
    /// Changes to the preset's machine and cut (mill presets only).
    Machine,
}

/// What kind of value a setting takes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SettingKind {
    /// A decimal number in `min..=max` (in the setting's unit).
    Number {
        /// Smallest accepted value.
        min: f64,
        /// Largest accepted value.
        max: f64,
    },
    /// A whole number in `min..=max`.
    Count {
        /// Smallest accepted value.
        min: usize,
        /// Largest accepted value.
        max: usize,
    },
    /// A simulation seed, any whole number from 0 to 2⁶⁴ − 1.
    Seed,
    /// One of [`Feedback::ALL`] by name.
    Feedback,
    /// One of [`Material::ALL`] by name.
    Material,
}

/// A setting's value, once parsed and checked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SettingValue {
    /// A number in the setting's unit.
    Number(f64),
    /// A whole number.
    Count(usize),
    /// A seed.
    Seed(u64),
    /// A feedback path.
    Feedback(Feedback),
    /// A work material.
    Material(Material),
}

impl SettingValue {
    /// The number, if this is one.
    pub fn number(self) -> Option<f64> {
        match self {
            SettingValue::Number(v) => Some(v),
            _ => None,
        }
    }

    /// The whole number, if this is one.
    pub fn count(self) -> Option<usize> {
        match self {
            SettingValue::Count(n) => Some(n),
            _ => None,
        }
    }

    /// The text [`RunSetting::parse`] reads back as this value, exactly (a form loading a saved
    /// configuration shows it).
    pub fn text(self) -> String {
        match self {
            SettingValue::Number(v) => v.to_string(),
            SettingValue::Count(n) => n.to_string(),
            SettingValue::Seed(seed) => seed.to_string(),
            SettingValue::Feedback(f) => f.name().to_string(),
            SettingValue::Material(m) => m.name().to_string(),
        }
    }
}

/// Every setting of a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RunSetting {
    /// Seed of every noise source.
    Seed,
    /// Which motor current measures the force.
    Feedback,
    /// The force to hold.
    TargetForce,
    /// The force to hold, stated as a current.
    TargetCurrent,
    /// The lowest override the envelope allows.
    MinOverride,
    /// The highest override the envelope allows.
    MaxOverride,
    /// The envelope's override rate limit.
    MaxRate,
    /// The override held until the envelope arms.
    ArmingOverride,
    /// The override a cut is entered with.
    EntryOverride,
    /// How long the entry override is held at most after an entry.
    EntryHoldTime,
    /// Smallest feed per tooth.
    MinFeedPerTooth,
    /// Largest feed per tooth.
    MaxFeedPerTooth,
    /// Size of paper 002's load step (liu-current-step).
    LoadStep,
    /// The controller's period.
    ControlPeriod,
    /// Order of both current low-passes.
    FilterOrder,
    /// Spindle current low-pass cut-off.
    SpindleCutoff,
    /// Feed current low-pass cut-off.
    FeedCutoff,
    /// Work material of the whole part.
    Material,
    /// Spindle speed of every block.
    SpindleSpeed,
    /// Programmed feed of every block.
    ProgrammedFeed,
    /// Factor on the axial depth profile.
    DepthScale,
    /// Cutter diameter.
    ToolDiameter,
    /// Number of teeth.
    Teeth,
    /// The tool's stick-out from its holder.
    ToolStickOut,
    /// The spindle's radial stiffness at its nose.
    SpindleStiffness,
    /// The Young's modulus of the tool's material.
    ToolModulus,
    /// Hall-sensor noise.
    SensorNoise,
}

/// Everything written about one setting.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SettingSpec {
    /// Field name in a saved configuration's JSON (`settings.…` or `plant.…`).
    pub json_field: &'static str,
    /// Key in the page's URL query and the form's field.
    pub query_key: &'static str,
    /// Command-line option, without the leading dashes.
    pub cli_option: &'static str,
    /// Label of the form field.
    pub label: &'static str,
    /// Unit shown beside the value (empty for dimensionless).
    pub unit: &'static str,
    /// What the value is, for `--help` and the form's hint.
    pub help: &'static str,
    /// The value's kind and static range.
    pub kind: SettingKind,
    /// Where the form shows it.
    pub group: SettingGroup,
}

const fn number(min: f64, max: f64) -> SettingKind {
    SettingKind::Number { min, max }
}

impl RunSetting {
    /// Every setting, in the order the form shows them.
    pub const ALL: [RunSetting; 27] = [
        RunSetting::Seed,
        RunSetting::TargetForce,
        RunSetting::TargetCurrent,
        RunSetting::Feedback,
        RunSetting::MaxOverride,
        RunSetting::MinOverride,
        RunSetting::MaxRate,
        RunSetting::ArmingOverride,
        RunSetting::EntryOverride,
        RunSetting::EntryHoldTime,
        RunSetting::MinFeedPerTooth,
        RunSetting::MaxFeedPerTooth,
        RunSetting::LoadStep,
        RunSetting::Material,
        RunSetting::SpindleSpeed,
        RunSetting::ProgrammedFeed,
        RunSetting::DepthScale,
        RunSetting::ToolDiameter,
        RunSetting::Teeth,
        RunSetting::ToolStickOut,
        RunSetting::SpindleStiffness,
        RunSetting::ToolModulus,
        RunSetting::SensorNoise,
        RunSetting::ControlPeriod,
        RunSetting::FilterOrder,
        RunSetting::SpindleCutoff,
        RunSetting::FeedCutoff,
    ];

    /// The setting's names, unit, range and help.
    pub const fn spec(self) -> SettingSpec {
        use SettingGroup::{Machine, Scenario, SignalChain};
        let (json_field, query_key, cli_option, label, unit, kind, group, help) = match self {
            RunSetting::Seed => (
                "seed",
                "seed",
                "seed",
                "Seed",
                "",
                SettingKind::Seed,
                Scenario,
                "seed of every noise source (default 1); the same seed gives the same trace",
            ),
            RunSetting::TargetForce => (
                "target_force_n",
                "target",
                "target-n",
                "Target force (blank: preset's)",
                "N",
                number(1.0, 100_000.0),
                Scenario,
                "the force to hold (default: the preset's)",
            ),
            RunSetting::TargetCurrent => (
                "target_current_a",
                "target_a",
                "target-a",
                "Target current (blank: none)",
                "A",
                number(0.001, 10_000.0),
                Scenario,
                "the force to hold, stated as the current the calibrated model gives at the \
                 program's speed and feed (as papers 000, 002 and 003 state their targets); a \
                 target force, if given, wins",
            ),
            RunSetting::Feedback => (
                "feedback",
                "feedback",
                "feedback",
                "Force measured from",
                "",
                SettingKind::Feedback,
                Scenario,
                "how the force is measured: spindle or feed motor current, or a dynamometer under the \
                 part (default: the preset's)",
            ),
            RunSetting::MaxOverride => (
                "max_override_pct",
                "max_override",
                "max-override",
                "Highest override (blank: preset's)",
                "%",
                number(20.0, MAX_OVERRIDE_PCT),
                Scenario,
                "highest override the safety envelope allows (default 150 %, 255 % on paper \
                 003's machine; at most what the machine applies)",
            ),
            RunSetting::MinOverride => (
                "min_override_pct",
                "min_override",
                "min-override",
                "Lowest override",
                "%",
                number(0.0, MAX_OVERRIDE_PCT),
                Scenario,
                "lowest override the safety envelope allows (default 10)",
            ),
            RunSetting::MaxRate => (
                "max_rate_pct_per_s",
                "max_rate",
                "max-rate-pct-s",
                "Override rate limit (blank: preset's)",
                "%/s",
                number(1.0, 100_000.0),
                Scenario,
                "fastest change of the override the safety envelope allows (default 100 %/s; on \
                 paper 002's preset its fuzzy law's 100 % per control period)",
            ),
            RunSetting::ArmingOverride => (
                "arming_override_pct",
                "arming_override",
                "arming-override",
                "Override before arming",
                "%",
                number(0.0, MAX_OVERRIDE_PCT),
                Scenario,
                "override held until the envelope arms, within the lowest–highest band (default \
                 100, or the nearer end of the band)",
            ),
            RunSetting::EntryOverride => (
                "entry_override_pct",
                "entry_override",
                "entry-override",
                "Entry override",
                "%",
                number(1.0, MAX_OVERRIDE_PCT),
                Scenario,
                "override the tool enters a cut with, held at most until the load settles (default \
                 100: the programmed feed)",
            ),
            RunSetting::EntryHoldTime => (
                "entry_hold_s",
                "entry_hold",
                "entry-hold-s",
                "Entry hold (blank: one cutter radius of feed; 0: none)",
                "s",
                number(0.0, 30.0),
                Scenario,
                "after the tool enters a cut, how long the entry override is held at most before \
                 the controller takes over: until the cutter is engaged, or sooner if the force \
                 reaches the target (default: the time to feed one cutter radius, 0.2–5 s; 0 turns \
                 the hold off; a fixed feed never holds)",
            ),
            RunSetting::MinFeedPerTooth => (
                "min_feed_per_tooth_mm",
                "min_fz",
                "min-fz-mm",
                "Smallest feed per tooth (blank: the material's)",
                "mm",
                number(0.001, 1.0),
                Scenario,
                "smallest feed per tooth the override allows; below it the edge rubs (default: the \
                 handbook window of the part's material for the cutter, mill presets)",
            ),
            RunSetting::MaxFeedPerTooth => (
                "max_feed_per_tooth_mm",
                "max_fz",
                "max-fz-mm",
                "Largest feed per tooth (blank: the material's)",
                "mm",
                number(0.001, 1.0),
                Scenario,
                "largest feed per tooth the override allows; above it the chip overloads the edge \
                 (default: the handbook window of the part's material for the cutter, mill \
                 presets)",
            ),
            RunSetting::LoadStep => (
                "load_step_pct",
                "load_step",
                "load-step-pct",
                "Load step at 15 s (blank: preset's)",
                "%",
                number(PlantEdits::LOAD_STEP_PCT[0], PlantEdits::LOAD_STEP_PCT[1]),
                Scenario,
                "size of paper 002's step in depth of cut, percent of the depth (liu-current-step \
                 only; default +40 %, the lab's choice: the paper's E range of ±25 A implies \
                 full-scale steps, about +100 %)",
            ),
            RunSetting::ControlPeriod => (
                "control_period_s",
                "period",
                "period-s",
                "Control period (blank: whole revolutions ≥ 40 ms)",
                "s",
                number(0.001, 2.0),
                SignalChain,
                "control period (default: whole spindle revolutions, at least 40 ms; 50 ms on paper 002's \
                 preset)",
            ),
            RunSetting::FilterOrder => (
                "lowpass_order",
                "filter_order",
                "filter-order",
                "Current filter order",
                "",
                SettingKind::Count { min: 1, max: 20 },
                SignalChain,
                "order of the Butterworth low-passes on the phase currents (default 4)",
            ),
            RunSetting::SpindleCutoff => (
                "spindle_lowpass_hz",
                "spindle_cutoff",
                "spindle-cutoff-hz",
                "Spindle current cut-off",
                "Hz",
                number(1.0, 4_999.0),
                SignalChain,
                "spindle current low-pass cut-off, below the 5 kHz Nyquist frequency (default 260)",
            ),
            RunSetting::FeedCutoff => (
                "feed_lowpass_hz",
                "feed_cutoff",
                "feed-cutoff-hz",
                "Feed current cut-off",
                "Hz",
                number(1.0, 4_999.0),
                SignalChain,
                "feed current low-pass cut-off, below the 5 kHz Nyquist frequency (default 50)",
            ),
            RunSetting::Material => (
                "material",
                "material",
                "material",
                "Work material",
                "",
                SettingKind::Material,
                Machine,
                "work material of the whole part (mill presets)",
            ),
            RunSetting::SpindleSpeed => (
                "spindle_rpm",
                "rpm",
                "rpm",
                "Spindle speed",
                "rpm",
                number(50.0, 20_000.0),
                Machine,
                "spindle speed of every block (mill presets)",
            ),
            RunSetting::ProgrammedFeed => (
                "programmed_feed_mm_min",
                "feed",
                "feed-mm-min",
                "Programmed feed",
                "mm/min",
                number(1.0, 20_000.0),
                Machine,
                "programmed feed of every block (mill presets)",
            ),
            RunSetting::DepthScale => (
                "depth_scale",
                "depth_scale",
                "depth-scale",
                "Depth of cut ×",
                "×",
                number(0.05, 5.0),
                Machine,
                "factor on the axial depth profile (mill presets)",
            ),
            RunSetting::ToolDiameter => (
                "tool_diameter_mm",
                "diameter",
                "diameter-mm",
                "Tool diameter",
                "mm",
                number(DIAMETER_RANGE_MM.0, DIAMETER_RANGE_MM.1),
                Machine,
                "cutter diameter (mill presets)",
            ),
            RunSetting::Teeth => (
                "teeth",
                "teeth",
                "teeth",
                "Teeth",
                "teeth",
                SettingKind::Count {
                    min: 1,
                    max: MAX_TEETH as usize,
                },
                Machine,
                "number of teeth of the cutter (mill presets)",
            ),
            RunSetting::ToolStickOut => (
                "tool_stick_out_mm",
                "stick_out",
                "stick-out-mm",
                "Tool stick-out",
                "mm",
                number(STICK_OUT_RANGE_MM.0, STICK_OUT_RANGE_MM.1),
                Machine,
                "how far the tool sticks out of its holder, the cantilever the force bends into the \
                 wall's error (mill presets; blank: 3 tool diameters; at least the deepest cut, at \
                 most 10 diameters)",
            ),
            RunSetting::SpindleStiffness => (
                "spindle_stiffness_n_um",
                "spindle_k",
                "spindle-stiffness-n-um",
                "Spindle stiffness",
                "N/µm",
                number(SPINDLE_STIFFNESS_RANGE_N_UM.0, SPINDLE_STIFFNESS_RANGE_N_UM.1),
                Machine,
                "radial stiffness at the spindle nose, in series with the tool's (mill presets; \
                 blank: 50 N/µm, a mid-size BT40 spindle)",
            ),
            RunSetting::ToolModulus => (
                "tool_youngs_modulus_gpa",
                "tool_e",
                "tool-modulus-gpa",
                "Tool Young's modulus",
                "GPa",
                number(YOUNGS_MODULUS_RANGE_GPA.0, YOUNGS_MODULUS_RANGE_GPA.1),
                Machine,
                "Young's modulus of the tool's material, the cantilever's stiffness (mill presets; \
                 blank: 600 GPa, cemented carbide; high-speed steel about 210)",
            ),
            RunSetting::SensorNoise => (
                "sensor_noise_a",
                "noise",
                "noise-a",
                "Sensor noise",
                "A",
                number(0.0, 5.0),
                Machine,
                "Hall-sensor noise, standard deviation (mill presets)",
            ),
        };
        SettingSpec {
            json_field,
            query_key,
            cli_option,
            label,
            unit,
            help,
            kind,
            group,
        }
    }

    /// The setting whose URL key is `key`.
    pub fn from_query_key(key: &str) -> Option<RunSetting> {
        Self::ALL.into_iter().find(|s| s.spec().query_key == key)
    }

    /// The setting whose command-line option is `option` (without dashes).
    pub fn from_cli_option(option: &str) -> Option<RunSetting> {
        Self::ALL
            .into_iter()
            .find(|s| s.spec().cli_option == option)
    }

    /// The accepted numeric range for `preset`: the static range, narrowed where the preset's
    /// machine cannot follow (the highest override a dial or override input applies).
    pub fn range(self, preset: Preset) -> Option<(f64, f64)> {
        self.range_on(machine_max_override_pct(preset))
    }

    /// The accepted numeric range on a machine whose highest override is
    /// `machine_max_override_pct` (a log's, or a preset's: [`RunSetting::range`]).
    pub fn range_on(self, machine_max_override_pct: f64) -> Option<(f64, f64)> {
        match self.spec().kind {
            SettingKind::Number { min, max }
                if matches!(
                    self,
                    RunSetting::MaxOverride
                        | RunSetting::ArmingOverride
                        | RunSetting::EntryOverride
                ) =>
            {
                Some((min, max.min(machine_max_override_pct)))
            }
            SettingKind::Number { min, max } => Some((min, max)),
            SettingKind::Count { min, max } => Some((min as f64, max as f64)),
            SettingKind::Seed | SettingKind::Feedback | SettingKind::Material => None,
        }
    }

    /// The names a setting that takes names accepts, comma separated, for messages.
    pub fn choices(self) -> Option<String> {
        let names: Vec<&str> = match self.spec().kind {
            SettingKind::Feedback => Feedback::ALL.iter().map(|f| f.name()).collect(),
            SettingKind::Material => Material::ALL.iter().map(|m| m.name()).collect(),
            _ => return None,
        };
        Some(names.join(", "))
    }

    /// Parses what a person typed for this setting on `preset`; blank text keeps the preset's
    /// value (`Ok(None)`).
    ///
    /// ```
    /// use cutlab::closed_loop::definition::{RunSetting, SettingValue};
    /// use cutlab::plant::Preset;
    /// let preset = Preset::ALL[0];
    /// let period = RunSetting::ControlPeriod;
    /// assert_eq!(period.parse("0,05", preset), Ok(Some(SettingValue::Number(0.05))));
    /// assert_eq!(period.parse("  ", preset), Ok(None));
    /// let e = period.parse("5", preset).unwrap_err();
    /// assert_eq!(e.problem.to_string(), "5 s is outside 0.001–2 s");
    /// ```
    pub fn parse(self, text: &str, preset: Preset) -> Result<Option<SettingValue>, SettingError> {
        self.parse_on(text, machine_max_override_pct(preset))
    }

    /// [`RunSetting::parse`] on a machine whose highest override is `machine_max_override_pct`.
    pub fn parse_on(
        self,
        text: &str,
        machine_max_override_pct: f64,
    ) -> Result<Option<SettingValue>, SettingError> {
        let text = text.trim();
        if text.is_empty() {
            return Ok(None);
        }
        let problem = |problem: table::Problem| SettingError {
            setting: self,
            problem: problem.into(),
        };
        let unknown = |what| {
            problem(table::Problem::Unknown {
                what,
                text: text.to_string(),
                choices: self.choices().unwrap_or_default(),
            })
        };
        let value = match self.spec().kind {
            SettingKind::Number { .. } => SettingValue::Number(
                parse_number(text).map_err(|m| problem(table::Problem::Parse(m)))?,
            ),
            SettingKind::Count { .. } => SettingValue::Count(
                parse_count(text).map_err(|m| problem(table::Problem::Parse(m)))?,
            ),
            SettingKind::Seed => {
                SettingValue::Seed(parse_seed(text).map_err(|m| problem(table::Problem::Parse(m)))?)
            }
            SettingKind::Feedback => SettingValue::Feedback(
                Feedback::ALL
                    .into_iter()
                    .find(|f| f.name() == text)
                    .ok_or_else(|| unknown("feedback path"))?,
            ),
            SettingKind::Material => SettingValue::Material(
                Material::from_name(text).ok_or_else(|| unknown("material"))?,
            ),
        };
        self.check_on(value, machine_max_override_pct)?;
        Ok(Some(value))
    }

    /// Checks a value against the range for `preset`.
    pub fn check(self, value: SettingValue, preset: Preset) -> Result<(), SettingError> {
        self.check_on(value, machine_max_override_pct(preset))
    }

    /// [`RunSetting::check`] on a machine whose highest override is `machine_max_override_pct`.
    pub fn check_on(
        self,
        value: SettingValue,
        machine_max_override_pct: f64,
    ) -> Result<(), SettingError> {
        let Some((min, max)) = self.range_on(machine_max_override_pct) else {
            return Ok(());
        };
        let v = match value {
            SettingValue::Number(v) => v,
            SettingValue::Count(n) => n as f64,
            _ => return Ok(()),
        };
        if v >= min && v <= max {
            return Ok(());
        }
        let spec = self.spec();
        let problem =
            if matches!(self, RunSetting::MaxOverride | RunSetting::ArmingOverride) && v > max {
                RunProblem::AboveMachine {
                    value: v,
                    max,
                    what: if self == RunSetting::MaxOverride {
                        "highest override"
                    } else {
                        "override before arming"
                    },
                }
            } else {
                // A unitless number is named by what it counts, the label's last word ("order").
                let noun = match spec.unit {
                    "" => spec.label.rsplit(' ').next().unwrap_or(spec.label),
                    _ => "",
                };
                match table::Problem::outside(v, min, max, spec.unit, noun) {
                    Some(problem) => problem.into(),
                    None => return Ok(()),
                }
            };
        Err(SettingError {
            setting: self,
            problem,
        })
    }

    /// The value `spec` holds for this setting, if it changes the preset's.
    pub fn value_in(self, spec: &RunSpec) -> Option<SettingValue> {
        let s = &spec.settings;
        let p = &spec.plant;
        let number = |v: Option<f64>| v.map(SettingValue::Number);
        match self {
            RunSetting::Seed => Some(SettingValue::Seed(spec.seed)),
            RunSetting::Feedback => s.feedback.map(SettingValue::Feedback),
            RunSetting::TargetForce => number(s.target_force_n),
            RunSetting::TargetCurrent => number(s.target_current_a),
            RunSetting::MinOverride => number(s.min_override_pct),
            RunSetting::MaxOverride => number(s.max_override_pct),
            RunSetting::MaxRate => number(s.max_rate_pct_per_s),
            RunSetting::ArmingOverride => number(s.arming_override_pct),
            RunSetting::EntryOverride => number(s.entry_override_pct),
            RunSetting::EntryHoldTime => number(s.entry_hold_s),
            RunSetting::MinFeedPerTooth => number(s.min_feed_per_tooth_mm),
            RunSetting::MaxFeedPerTooth => number(s.max_feed_per_tooth_mm),
            RunSetting::ControlPeriod => number(s.control_period_s),
            RunSetting::FilterOrder => s.lowpass_order.map(SettingValue::Count),
            RunSetting::SpindleCutoff => number(s.spindle_lowpass_hz),
            RunSetting::FeedCutoff => number(s.feed_lowpass_hz),
            RunSetting::Material => p.material.map(SettingValue::Material),
            RunSetting::SpindleSpeed => number(p.spindle_rpm),
            RunSetting::ProgrammedFeed => number(p.programmed_feed_mm_min),
            RunSetting::DepthScale => number(p.depth_scale),
            RunSetting::ToolDiameter => number(p.tool_diameter_mm),
            RunSetting::Teeth => p.teeth.map(|z| SettingValue::Count(z as usize)),
            RunSetting::ToolStickOut => number(p.tool_stick_out_mm),
            RunSetting::SpindleStiffness => number(p.spindle_stiffness_n_um),
            RunSetting::ToolModulus => number(p.tool_youngs_modulus_gpa),
            RunSetting::SensorNoise => number(p.sensor_noise_a),
            RunSetting::LoadStep => number(p.load_step_pct),
        }
    }

    /// Puts a checked value into `spec` (`None` restores the preset's value).
    ///
    /// # Panics
    /// Never for values made by [`RunSetting::parse`] for this setting; a value of another kind
    /// is ignored (a bug, caught by the tests that cover every setting).
    pub fn apply(self, spec: &mut RunSpec, value: Option<SettingValue>) {
        let number = value.and_then(SettingValue::number);
        let count = value.and_then(SettingValue::count);
        if self.apply_to_settings(&mut spec.settings, value) {
            return;
        }
        let p = &mut spec.plant;
        match self {
            RunSetting::Seed => {
                spec.seed = match value {
                    Some(SettingValue::Seed(seed)) => seed,
                    _ => DEFAULT_SEED,
                }
            }
            RunSetting::Material => {
                p.material = match value {
                    Some(SettingValue::Material(m)) => Some(m),
                    _ => None,
                }
            }
            RunSetting::SpindleSpeed => p.spindle_rpm = number,
            RunSetting::ProgrammedFeed => p.programmed_feed_mm_min = number,
            // A factor of 1 is the preset's own profile, not an edit.
            RunSetting::DepthScale => p.depth_scale = number.filter(|k| *k != 1.0),
            RunSetting::ToolDiameter => p.tool_diameter_mm = number,
            RunSetting::Teeth => p.teeth = count.map(|n| n as u32),
            RunSetting::ToolStickOut => p.tool_stick_out_mm = number,
            RunSetting::SpindleStiffness => p.spindle_stiffness_n_um = number,
            RunSetting::ToolModulus => p.tool_youngs_modulus_gpa = number,
            RunSetting::SensorNoise => p.sensor_noise_a = number,
            RunSetting::LoadStep => p.load_step_pct = number,
            // Settings rows: applied above.
            _ => {}
        }
    }

    /// Puts a checked value into `settings` (`None` restores the default) if this is one of the
    /// run's settings rather than the seed or a machine edit; says whether it was.
    pub fn apply_to_settings(
        self,
        settings: &mut SettingsOverrides,
        value: Option<SettingValue>,
    ) -> bool {
        let number = value.and_then(SettingValue::number);
        let count = value.and_then(SettingValue::count);
        let s = settings;
        match self {
            RunSetting::Feedback => {
                s.feedback = match value {
                    Some(SettingValue::Feedback(f)) => Some(f),
                    _ => None,
                }
            }
            RunSetting::TargetForce => s.target_force_n = number,
            RunSetting::TargetCurrent => s.target_current_a = number,
            RunSetting::MinOverride => s.min_override_pct = number,
            RunSetting::MaxOverride => s.max_override_pct = number,
            RunSetting::MaxRate => s.max_rate_pct_per_s = number,
            RunSetting::ArmingOverride => s.arming_override_pct = number,
            RunSetting::EntryOverride => s.entry_override_pct = number,
            RunSetting::EntryHoldTime => s.entry_hold_s = number,
            RunSetting::MinFeedPerTooth => s.min_feed_per_tooth_mm = number,
            RunSetting::MaxFeedPerTooth => s.max_feed_per_tooth_mm = number,
            RunSetting::ControlPeriod => s.control_period_s = number,
            RunSetting::FilterOrder => s.lowpass_order = count,
            RunSetting::SpindleCutoff => s.spindle_lowpass_hz = number,
            RunSetting::FeedCutoff => s.feed_lowpass_hz = number,
            RunSetting::Seed
            | RunSetting::Material
            | RunSetting::SpindleSpeed
            | RunSetting::ProgrammedFeed
            | RunSetting::DepthScale
            | RunSetting::ToolDiameter
            | RunSetting::Teeth
            | RunSetting::ToolStickOut
            | RunSetting::SpindleStiffness
            | RunSetting::ToolModulus
            | RunSetting::SensorNoise
            | RunSetting::LoadStep => return false,
        }
        true
    }
}

/// Parses the typed text of run settings (no seed, no machine edits) for a machine whose highest
/// override is `machine_max_override_pct`: what a replay of a log takes, through the same rows as a
/// lab run. Every setting that does not parse, is out of range or is not a run setting is
/// reported.
///
/// ```
/// use cutlab::closed_loop::definition::{parse_settings, RunSetting};
/// let texts = [(RunSetting::TargetCurrent, "12,5"), (RunSetting::ControlPeriod, "0.1")];
/// let s = parse_settings(&texts, 150.0).unwrap();
/// assert_eq!((s.target_current_a, s.control_period_s), (Some(12.5), Some(0.1)));
/// let e = parse_settings(&[(RunSetting::ControlPeriod, "1000")], 150.0).unwrap_err();
/// assert_eq!(e[0].problem.to_string(), "1000 s is outside 0.001–2 s");
/// ```
pub fn parse_settings<T: AsRef<str>>(
    texts: &[(RunSetting, T)],
    machine_max_override_pct: f64,
) -> Result<SettingsOverrides, Vec<SettingError>> {
    let mut settings = SettingsOverrides::default();
    let mut errors = Vec::new();
    for (setting, text) in texts {
        match setting.parse_on(text.as_ref(), machine_max_override_pct) {
            Ok(value) if setting.apply_to_settings(&mut settings, value) => {}
            Ok(_) => errors.push(SettingError {
                setting: *setting,
                problem: RunProblem::other("not a setting of a replay: it changes the machine"),
            }),
            Err(e) => errors.push(e),
        }
    }
    if errors.is_empty() {
        Ok(settings)
    } else {
        Err(errors)
    }
}

/// Parses the typed text of several settings on `preset` into a run of its controller: what the
/// browser's form and the command line both do with what a person typed. Blank text keeps the
/// preset's value; every setting that does not parse or is out of range is reported.
///
/// ```
/// use cutlab::closed_loop::definition::{parse_texts, RunSetting};
/// use cutlab::control::registry::ControllerConfig;
/// use cutlab::control::registry::ControllerKind;
/// use cutlab::plant::Preset;
/// let texts = [(RunSetting::SpindleSpeed, "1200"), (RunSetting::ControlPeriod, "")];
/// let spec = parse_texts(Preset::KimStepDoc, ControllerConfig::new(ControllerKind::Pi), &texts)
///     .unwrap();
/// assert_eq!(spec.plant.spindle_rpm, Some(1200.0));
/// assert_eq!(spec.settings.control_period_s, None);
/// let bad = [(RunSetting::FilterOrder, "0"), (RunSetting::SpindleSpeed, "10")];
/// let errors = parse_texts(Preset::KimStepDoc, ControllerConfig::new(ControllerKind::Pi), &bad)
///     .unwrap_err();
/// assert_eq!(errors.len(), 2);
/// ```
pub fn parse_texts<T: AsRef<str>>(
    preset: Preset,
    controller: ControllerConfig,
    texts: &[(RunSetting, T)],
) -> Result<RunSpec, Vec<SettingError>> {
    let mut spec = RunSpec::new(preset, controller.kind());
    spec.controller = controller;
    let mut errors = Vec::new();
    for (setting, text) in texts {
        match setting.parse(text.as_ref(), preset) {
            Ok(value) => setting.apply(&mut spec, value),
            Err(e) => errors.push(e),
        }
    }
    if errors.is_empty() {
        check_band(&spec.settings, default_override_band_pct(preset)).map_err(|e| vec![e])?;
        Ok(spec)
    } else {
        Err(errors)
    }
}

/// The seed of a run that names none.
pub const DEFAULT_SEED: u64 = 1;

/// The highest override `preset`'s machine applies: the top of its dial, or the 255 % of an
/// override input.
pub fn machine_max_override_pct(preset: Preset) -> f64 {
    max_override_pct_of(&preset.override_mode())
}

/// The highest override a machine whose override input is `mode` applies.
pub fn max_override_pct_of(mode: &OverrideMode) -> f64 {
    match mode {
        OverrideMode::Dial(table) => table.positions().into_iter().fold(0.0, f64::max),
        OverrideMode::WholePercent | OverrideMode::Continuous => MAX_OVERRIDE_PCT,
    }
}

/// The override band a run of `preset` allows unless its settings move it: 10–150 % (FANUC's
/// dial), and up to 255 % on paper 003's machine, whose override is a byte in percent (its
/// experiments — the 1 mm entry, the aluminium section, the taper's light corner — need the room
/// above 150 %).
pub fn default_override_band_pct(preset: Preset) -> (f64, f64) {
    default_band_pct_of(&preset.override_mode())
}

/// The default override band on a machine whose override input is `mode`
/// ([`default_override_band_pct`]).
pub fn default_band_pct_of(mode: &OverrideMode) -> (f64, f64) {
    let defaults = EnvelopeConfig::default_for_dial();
    let max = match mode {
        OverrideMode::WholePercent => MAX_OVERRIDE_PCT,
        _ => defaults.max_override_pct,
    };
    (defaults.min_override_pct, max)
}

/// Checks every setting `spec` holds against the table, then the settings that constrain each
/// other: a saved configuration is held to the same ranges as the form and the command line.
pub fn check_spec(spec: &RunSpec) -> Result<(), SettingError> {
    for setting in RunSetting::ALL {
        if let Some(value) = setting.value_in(spec) {
            setting.check(value, spec.preset)?;
        }
    }
    check_band(&spec.settings, default_override_band_pct(spec.preset)).map(|_| ())
}

/// The override band `settings` ask for, each end the machine's default (`default_band_pct`)
/// where they leave it out: refused when its lowest end lies above its highest, or when the
/// override held before arming lies outside it (refused, not clamped or swapped: either would
/// run something other than what was asked).
///
/// ```
/// use cutlab::closed_loop::definition::{check_band, SettingsOverrides};
/// let mut s = SettingsOverrides::default();
/// assert_eq!(check_band(&s, (10.0, 150.0)), Ok((10.0, 150.0)));
/// s.min_override_pct = Some(200.0);
/// let e = check_band(&s, (10.0, 150.0)).unwrap_err();
/// assert_eq!(e.to_string(), "min_override_pct: the lowest override 200 % is above the highest, 150 %");
/// ```
pub fn check_band(
    settings: &SettingsOverrides,
    default_band_pct: (f64, f64),
) -> Result<(f64, f64), SettingError> {
    let (default_min, default_max) = default_band_pct;
    let min = settings.min_override_pct.unwrap_or(default_min);
    let max = settings.max_override_pct.unwrap_or(default_max);
    if min > max {
        // Name the setting that was given: the other end is the machine's default.
        let setting = if settings.min_override_pct.is_some() {
            RunSetting::MinOverride
        } else {
            RunSetting::MaxOverride
        };
        return Err(SettingError {
            setting,
            problem: RunProblem::BandInverted { min, max },
        });
    }
    match settings.arming_override_pct {
        Some(value) if !(value >= min && value <= max) => Err(SettingError {
            setting: RunSetting::ArmingOverride,
            problem: RunProblem::OutsideBand { value, min, max },
        }),
        _ => Ok((min, max)),
    }
}

/// What is wrong with a run setting: what any table's value can have wrong (in the words every
/// table uses), or one of the run's own refusals, which depend on the machine or on another
/// setting.
#[derive(Debug, Clone, PartialEq)]
pub enum RunProblem {
    /// Not a value of the setting's kind, not one of its names, outside its range, or refused
    /// for a reason the text gives.
    Value(table::Problem),
    /// Above what the preset's machine applies.
    AboveMachine {
        /// The value given.
        value: f64,
        /// The machine's highest override.
        max: f64,
        /// Which override ("highest override").
        what: &'static str,
    },
    /// The smallest feed per tooth not below the largest.
    WindowInverted {
        /// The smallest, mm.
        min: f64,
        /// The largest, mm.
        max: f64,
    },
    /// The lowest override above the highest.
    BandInverted {
        /// The run's lowest override.
        min: f64,
        /// The run's highest override.
        max: f64,
    },
    /// A control period that is not between one sample and 10⁷ samples of the machine.
    PeriodInSamples {
        /// The period asked for.
        period_s: f64,
        /// The machine's sample period.
        sample_period_s: f64,
    },
    /// An override outside the run's own lowest–highest band.
    OutsideBand {
        /// The value given.
        value: f64,
        /// The run's lowest override.
        min: f64,
        /// The run's highest override.
        max: f64,
    },
}

impl RunProblem {
    /// A refusal whose text says why (a setting given where it cannot be used).
    pub fn other(why: &str) -> Self {
        RunProblem::Value(table::Problem::Other(why.to_string()))
    }
}

impl From<table::Problem> for RunProblem {
    fn from(problem: table::Problem) -> Self {
        RunProblem::Value(problem)
    }
}

impl fmt::Display for RunProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RunProblem::Value(problem) => problem.fmt(f),
            RunProblem::AboveMachine { value, max, what } => write!(
                f,
                "{what} {} % is more than this machine applies ({} %)",
                readable(*value),
                readable(*max)
            ),
            RunProblem::WindowInverted { min, max } => write!(
                f,
                "the smallest feed per tooth {} mm is not below the largest, {} mm",
                readable(*min),
                readable(*max)
            ),
            RunProblem::BandInverted { min, max } => write!(
                f,
                "the lowest override {} % is above the highest, {} %",
                readable(*min),
                readable(*max)
            ),
            RunProblem::PeriodInSamples {
                period_s,
                sample_period_s,
            } => write!(
                f,
                "{} s is shorter than one sample of the machine ({} s) or longer than 10⁷ samples",
                readable(*period_s),
                readable(*sample_period_s)
            ),
            RunProblem::OutsideBand { value, min, max } => write!(
                f,
                "{} % is outside this run's override band {}–{} % (lowest and highest override)",
                readable(*value),
                readable(*min),
                readable(*max)
            ),
        }
    }
}

/// A setting that did not parse or is out of range.
#[derive(Debug, Clone, PartialEq)]
pub struct SettingError {
    /// Which setting.
    pub setting: RunSetting,
    /// What is wrong with it.
    pub problem: RunProblem,
}

impl SettingError {
    /// The message for the command line, naming the option (`--period-s: 5 s is outside …`).
    pub fn for_cli(&self) -> String {
        let option = self.setting.spec().cli_option;
        match self.problem {
            // The message names the quantity already.
            RunProblem::AboveMachine { .. } => format!("{} (--{option})", self.problem),
            _ => format!("--{option}: {}", self.problem),
        }
    }
}

impl fmt::Display for SettingError {
    /// The message for a saved configuration, naming its JSON field.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.problem {
            RunProblem::AboveMachine { .. } => write!(f, "{}", self.problem),
            _ => write!(f, "{}: {}", self.setting.spec().json_field, self.problem),
        }
    }
}

impl std::error::Error for SettingError {}

#[cfg(test)]
mod tests {
    use super::*;

    fn preset(name: &str) -> Preset {
        Preset::from_name(name).unwrap()
    }

    #[test]
    fn names_are_unique_in_each_namespace() {
        for names in [
            RunSetting::ALL.map(|s| s.spec().json_field),
            RunSetting::ALL.map(|s| s.spec().query_key),
            RunSetting::ALL.map(|s| s.spec().cli_option),
        ] {
            let mut sorted = names.to_vec();
            sorted.sort_unstable();
            sorted.dedup();
            assert_eq!(sorted.len(), names.len(), "{names:?}");
        }
        for s in RunSetting::ALL {
            assert_eq!(RunSetting::from_query_key(s.spec().query_key), Some(s));
            assert_eq!(RunSetting::from_cli_option(s.spec().cli_option), Some(s));
        }
    }

    #[test]
    fn every_setting_takes_its_range_ends_and_refuses_beyond() {
        let p = preset("kim-step-doc");
        for s in RunSetting::ALL {
            let Some((min, max)) = s.range(p) else {
                continue;
            };
            for v in [min, max] {
                let parsed = s.parse(&v.to_string(), p).unwrap().unwrap();
                let mut spec = RunSpec::new(p, ControllerKind::Pi);
                // The override before arming must also lie in the run's band, which starts at
                // 10 % unless the lowest override is lowered (tests/run_definition.rs).
                if s == RunSetting::ArmingOverride {
                    spec.settings.min_override_pct = Some(0.0);
                }
                s.apply(&mut spec, Some(parsed));
                assert_eq!(s.value_in(&spec), Some(parsed), "{s:?}");
                // Its text reads back as the same value (a form loading a configuration).
                assert_eq!(s.parse(&parsed.text(), p), Ok(Some(parsed)), "{s:?}");
                assert_eq!(check_spec(&spec), Ok(()));
                s.apply(&mut spec, None);
                assert!(s.value_in(&spec).is_none() || s == RunSetting::Seed);
            }
            let step = if matches!(s.spec().kind, SettingKind::Count { .. }) {
                1.0
            } else {
                (max - min).abs().max(1.0) * 0.01
            };
            for v in [min - step, max + step] {
                if v < 0.0 && matches!(s.spec().kind, SettingKind::Count { .. }) {
                    continue;
                }
                let e = s.parse(&v.to_string(), p).unwrap_err();
                assert_eq!(e.setting, s);
                assert!(e.for_cli().contains(s.spec().cli_option), "{}", e.for_cli());
            }
        }
    }

    #[test]
    fn messages_match_what_people_already_read() {
        let p = preset("kim-step-doc");
        let message = |s: RunSetting, text: &str| s.parse(text, p).unwrap_err().problem.to_string();
        assert_eq!(
            message(RunSetting::FilterOrder, "0"),
            "order 0 is outside 1–20"
        );
        assert_eq!(
            message(RunSetting::SpindleSpeed, "10"),
            "10 rpm is outside 50–20000 rpm"
        );
        assert_eq!(
            RunSetting::SpindleSpeed
                .parse("-5", p)
                .unwrap_err()
                .for_cli(),
            "--rpm: must be positive, got -5"
        );
        assert_eq!(
            RunSetting::MaxOverride
                .parse("1e6", p)
                .unwrap_err()
                .for_cli(),
            "highest override 1000000 % is more than this machine applies (255 %) \
             (--max-override)"
        );
        assert!(message(RunSetting::ProgrammedFeed, "1,500").contains("ambiguous"));
        assert!(message(RunSetting::Feedback, "torque").contains("\"torque\""));
    }

    #[test]
    fn the_highest_override_follows_the_machine() {
        let dial = Preset::ALL
            .into_iter()
            .find(|p| matches!(p.override_mode(), OverrideMode::Dial(_)))
            .unwrap();
        let top = machine_max_override_pct(dial);
        assert!(top < MAX_OVERRIDE_PCT);
        assert!(RunSetting::MaxOverride
            .parse(&top.to_string(), dial)
            .is_ok());
        let e = RunSetting::MaxOverride
            .parse(&(top + 1.0).to_string(), dial)
            .unwrap_err();
        assert!(matches!(e.problem, RunProblem::AboveMachine { .. }), "{e}");
    }

    #[test]
    fn a_saved_spec_out_of_range_is_refused_with_its_field() {
        let mut spec = RunSpec::new(preset("kim-step-doc"), ControllerKind::Pi);
        spec.settings.arming_override_pct = Some(400.0);
        let e = check_spec(&spec).unwrap_err();
        assert_eq!(
            e.to_string(),
            "override before arming 400 % is more than this machine applies (255 %)"
        );
    }
}
