//! The controller registry: every controller the lab offers, its parameters with units, defaults
//! and ranges, and one constructor. The CLI (`cutlab controllers`, `--set key=value`), the browser
//! forms and the tests all read this one table, so a new parameter appears everywhere at once.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use super::fixed::FixedFeed;
use super::fuzzy::controller::{FuzzyController, FuzzyParams};
use super::fuzzy::engine::Defuzzifier;
use super::fuzzy::rules::{paper_002_engine, RuleBase, RuleTable};
use super::fuzzy::{fll, Format};
use super::law::Controller;
use super::mrac::{ModelReferenceAdaptive, MracParams};
use super::pi::{PiController, PiParams};
use super::restriction::{CurrentRestriction, RestrictionParams};
use super::threshold::{ThresholdParams, ThresholdProportional};

/// One tunable parameter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ParamSpec {
    /// Key for `--set key=value`, URLs and JSON.
    pub key: &'static str,
    /// Label for forms.
    pub label: &'static str,
    /// Unit, shown beside the value (empty for dimensionless).
    pub unit: &'static str,
    /// Default value.
    pub default: f64,
    /// Smallest accepted value.
    pub min: f64,
    /// Largest accepted value.
    pub max: f64,
    /// One sentence on what it does.
    pub help: &'static str,
}

const fn param(
    key: &'static str,
    label: &'static str,
    unit: &'static str,
    default: f64,
    min: f64,
    max: f64,
    help: &'static str,
) -> ParamSpec {
    ParamSpec {
        key,
        label,
        unit,
        default,
        min,
        max,
        help,
    }
}

/// Declares a controller's tuning: a struct with one `f64` field per parameter and its table
/// (`PARAMS`: key = field name, label, unit, default, range, help), in one place, so the table
/// and the fields cannot drift apart and a misspelt parameter is a compile error, not a NaN.
macro_rules! tuning {
    (
        $(#[$meta:meta])*
        pub struct $name:ident {
            $($field:ident: ($label:expr, $unit:expr, $default:expr, $min:expr, $max:expr, $help:expr),)+
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq)]
        pub struct $name {
            $(
                #[doc = $help]
                pub $field: f64,
            )+
        }

        impl $name {
            /// The parameters, in form order.
            pub const PARAMS: &'static [ParamSpec] = &[
                $(param(stringify!($field), $label, $unit, $default, $min, $max, $help),)+
            ];

            /// The tuning from values in the order of [`Self::PARAMS`] (missing ones take their
            /// defaults).
            fn from_values(values: &[f64]) -> Self {
                let mut index = 0;
                $(
                    let $field = values
                        .get(index)
                        .copied()
                        .unwrap_or(Self::PARAMS[index].default);
                    index += 1;
                )+
                let _ = index;
                Self { $($field,)+ }
            }
        }
    };
}

tuning! {
    /// The fixed-feed baseline.
    pub struct FixedTuning {
        override_pct: ("Override", "%", 100.0, 0.0, 255.0, "the override held for the whole run"),
    }
}

tuning! {
    /// Paper 000's current restriction.
    pub struct RestrictionTuning {
        band_pct: ("Band width", "% of target", 10.0, 0.5, 100.0, "distance between the upper and lower limit, centred on the target"),
        step_pct: ("Step", "%", 10.0, 0.1, 50.0, "override change per control period outside the band (one dial grade)"),
    }
}

tuning! {
    /// Paper 003's threshold-proportional law.
    pub struct ThresholdTuning {
        gap_pct: ("Threshold gap", "% of target", 10.0, 0.0, 100.0, "distance between the maximum and minimum thresholds, centred on the target"),
        kp: ("K_p", "% per %", 0.5, 0.0, 10.0, "override change per percent of force beyond a threshold (paper 003: 0.5)"),
        ignore_after_start_s: ("Ignore after spindle start", "s", 3.0, 0.0, 60.0, "time after spindle start during which the current is ignored (paper 003: 3 s)"),
        gap_a: ("Threshold gap as current", "A", 0.0, 0.0, 20.0, "the gap as paper 003 states it, in amperes of spindle current (paper 003: 0.4 A), converted to force by the teach cut's sensitivity; 0 uses the gap in % of target"),
    }
}

tuning! {
    /// PI with anti-windup.
    pub struct PiTuning {
        kp: ("K_p", "% per %", 0.3, 0.0, 10.0, "proportional gain on the relative force error"),
        ki_per_s: ("K_i", "% per %·s", 1.0, 0.0, 100.0, "integral gain on the relative force error"),
        tracking_time_s: ("Anti-windup time", "s", 0.5, 0.001, 100.0, "back-calculation time constant: how fast the integrator follows a clamp"),
        initial_override_pct: ("Initial override", "%", 100.0, 0.0, 255.0, "override the integrator starts from"),
    }
}

tuning! {
    /// Paper 001's Lyapunov MRAC.
    pub struct MracTuning {
        lambda_per_s: ("λ", "1/s", 2.0, 0.01, 100.0, "slope of the sliding variable E = dF̃/dt + λF̃"),
        kd_pct_s: ("K_d", "%·s", 8.0, 0.0, 1000.0, "gain on the sliding variable"),
        gamma_beta_pct_per_s: ("γ₃", "%/s", 50.0, 0.0, 10_000.0, "adaptation gain of β̂"),
        gamma_dynamics_pct_per_s: ("γ₁ = γ₂", "%/s", 0.0, 0.0, 10_000.0, "adaptation gains of m̂ and α̂ (act only while the target changes)"),
        initial_beta_pct: ("Initial β̂", "%", 100.0, 1.0, 255.0, "the override first assumed to give the target force"),
        min_beta_pct: ("β̂ lower bound", "%", 5.0, 0.0, 255.0, "projection bound of β̂"),
        max_beta_pct: ("β̂ upper bound", "%", 255.0, 1.0, 1000.0, "projection bound of β̂"),
        derivative_time_s: ("Derivative filter", "s", 0.2, 0.001, 10.0, "time constant of the filtered differentiator of the force"),
    }
}

tuning! {
    /// Paper 002's fuzzy controller (both rule bases).
    pub struct FuzzyTuning {
        error_range_pct: ("Error range", "% of target", 100.0, 1.0, 1000.0, "|E| that saturates the error input (paper 002: 25 A of 25 A, k_e = 6/25)"),
        change_range_pct: ("Error-change range", "% of target", 200.0, 1.0, 2000.0, "|EC| that saturates the change input, per control period or per the EC time base (paper 002: k_ec = 3/25, 50 A of 25 A)"),
        output_range_pct: ("Output range", "%", 20.0, 0.1, 255.0, "override change at |U| = 6 per control period, or per the k_u time base (paper 002's k_u = 250 of 1500 mm/min is 100 %, \
         the default on its own preset; 20 % on the mills, whose 40–60 ms periods run under a 100 %/s rate limit)"),
        change_time_base_s: ("EC time base", "s", 0.0, 0.0, 10.0, "0 reads EC per control period (eq 6: E(i) − E(i−1)); t > 0 reads it as the change over t, \
         (E(i) − E(i−1))·t/T: 1 s is paper 002's Table 2 (EC in A/s), and makes the error-change range per second"),
        output_time_base_s: ("k_u time base", "s", 0.0, 0.0, 10.0, "0 applies k_u per control period (eq 1: a_f(i+1) = a_f(i) + k_u·U); t > 0 applies it per t, \
         k_u·U·T/t each period: 1 s makes the output range the override's change per second, whatever the period"),
    }
}

/// Every controller of the lab.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ControllerKind {
    /// Fixed feed override, the baseline.
    Fixed,
    /// Paper 000's upper/lower limit stepping.
    Restriction,
    /// Paper 003's thresholds with proportional correction.
    Threshold,
    /// PI with anti-windup.
    Pi,
    /// Paper 001's Lyapunov model-reference adaptive control.
    Mrac,
    /// Paper 002's fuzzy controller with the experience-based (MacVicar-Whelan) rules.
    FuzzyExperience,
    /// Paper 002's fuzzy controller with the dynamics-based rules of Table 4.
    FuzzyDynamics,
    /// Paper 002's fuzzy law on an engine the engineer brings (FLL or FIS, two inputs and one
    /// output); paper 002's dynamics table until one is imported.
    FuzzyEngine,
}

impl ControllerKind {
    /// Every controller, in the order the lab lists them.
    pub const ALL: [ControllerKind; 8] = [
        ControllerKind::Fixed,
        ControllerKind::Restriction,
        ControllerKind::Threshold,
        ControllerKind::FuzzyExperience,
        ControllerKind::FuzzyDynamics,
        ControllerKind::FuzzyEngine,
        ControllerKind::Pi,
        ControllerKind::Mrac,
    ];

    /// The name used on the command line and in URLs.
    pub fn name(self) -> &'static str {
        match self {
            ControllerKind::Fixed => "fixed",
            ControllerKind::Restriction => "restriction",
            ControllerKind::Threshold => "threshold",
            ControllerKind::Pi => "pi",
            ControllerKind::Mrac => "mrac",
            ControllerKind::FuzzyExperience => "fuzzy-experience",
            ControllerKind::FuzzyDynamics => "fuzzy-dynamics",
            ControllerKind::FuzzyEngine => "fuzzy-engine",
        }
    }

    /// A human label.
    pub fn label(self) -> &'static str {
        match self {
            ControllerKind::Fixed => "Fixed feed",
            ControllerKind::Restriction => "Current restriction",
            ControllerKind::Threshold => "Threshold-proportional",
            ControllerKind::Pi => "PI with anti-windup",
            ControllerKind::Mrac => "Lyapunov adaptive (MRAC)",
            ControllerKind::FuzzyExperience => "Fuzzy, experience rules",
            ControllerKind::FuzzyDynamics => "Fuzzy, dynamics rules",
            ControllerKind::FuzzyEngine => "Fuzzy, imported engine",
        }
    }

    /// Where the law comes from.
    pub fn source(self) -> &'static str {
        match self {
            ControllerKind::Fixed => "baseline: the programmed feed at a fixed override",
            ControllerKind::Restriction => "Wang, Ai, Ze, He (paper 000), §1 and §5",
            ControllerKind::Threshold => "Kim, Kwon, Chu (paper 003), §8, Fig. 9",
            ControllerKind::Pi => "textbook; back-calculation anti-windup per Åström & Hägglund",
            ControllerKind::Mrac => "Maneerat, Khaengsarigid, Pasaya (paper 001), §3, eq 5–10",
            ControllerKind::FuzzyExperience => {
                "Liu, Wang, Wang (paper 002), §4; MacVicar-Whelan rule table"
            }
            ControllerKind::FuzzyDynamics => "Liu, Wang, Wang (paper 002), §4, Table 4, repaired where the printed table is damaged",
            ControllerKind::FuzzyEngine => {
                "your FLL or FIS engine (first input E, second EC, one output U) under paper \
                 002's law, §4; paper 002's dynamics table until you import one"
            }
        }
    }

    /// The parameters, in form order.
    pub fn params(self) -> &'static [ParamSpec] {
        match self {
            ControllerKind::Fixed => FixedTuning::PARAMS,
            ControllerKind::Restriction => RestrictionTuning::PARAMS,
            ControllerKind::Threshold => ThresholdTuning::PARAMS,
            ControllerKind::Pi => PiTuning::PARAMS,
            ControllerKind::Mrac => MracTuning::PARAMS,
            ControllerKind::FuzzyExperience
            | ControllerKind::FuzzyDynamics
            | ControllerKind::FuzzyEngine => FuzzyTuning::PARAMS,
        }
    }

    /// The built-in rule table this controller runs unless given another (`None` for a
    /// controller without one).
    pub fn rule_base(self) -> Option<RuleBase> {
        match self {
            ControllerKind::FuzzyExperience => Some(RuleBase::Experience),
            ControllerKind::FuzzyDynamics => Some(RuleBase::Dynamics),
            _ => None,
        }
    }

    /// Whether this is one of the fuzzy controllers (paper 002's law, [`FuzzyTuning`]).
    pub fn is_fuzzy(self) -> bool {
        matches!(
            self,
            ControllerKind::FuzzyExperience
                | ControllerKind::FuzzyDynamics
                | ControllerKind::FuzzyEngine
        )
    }
}

impl fmt::Display for ControllerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for ControllerKind {
    type Err = ParamError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        ControllerKind::ALL
            .into_iter()
            .find(|k| k.name() == s.trim())
            .ok_or_else(|| {
                ParamError(format!(
                    "unknown controller \"{}\"; controllers: {}",
                    s.trim(),
                    ControllerKind::ALL
                        .iter()
                        .map(|k| k.name())
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            })
    }
}

/// A bad controller parameter; the message names it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParamError(pub String);

impl fmt::Display for ParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ParamError {}

/// `key=value` split into the trimmed key and the number.
fn assignment_parts(assignment: &str) -> Result<(&str, f64), ParamError> {
    let Some((key, value)) = assignment.split_once('=') else {
        return Err(ParamError(format!(
            "\"{assignment}\" is not of the form key=value"
        )));
    };
    let key = key.trim();
    let value: f64 = value.trim().parse().map_err(|_| {
        ParamError(format!(
            "{key}: cannot parse \"{}\" as a number",
            value.trim()
        ))
    })?;
    Ok((key, value))
}

/// A controller choice with its parameter values, each inside its range.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "ControllerText", into = "ControllerText")]
pub struct ControllerConfig {
    kind: ControllerKind,
    values: Vec<f64>,
    /// A user's rule table for the fuzzy controllers (the kind's built-in table when `None`).
    rule_table: Option<RuleTable>,
    /// The engine of [`ControllerKind::FuzzyEngine`] as FLL, written by [`fll::write`] from an
    /// engine of two inputs and one output that builds (`None` for every other kind).
    engine_fll: Option<String>,
}

/// The serialised form: `{"kind": "pi", "params": {"kp": 0.3, ...}}`; missing parameters take
/// their defaults, unknown or out-of-range ones are errors, and so is a field other than these
/// four (a misspelt `"parms"` would otherwise run on the defaults). Whose defaults depends on
/// the reader: a controller on its own takes its kind's ([`ControllerConfig::new`]), a run in a
/// saved configuration its preset's (`closed_loop::paper_defaults::preset_controller`), through
/// [`ControllerText::resolve`].
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerText {
    /// The controller.
    pub kind: ControllerKind,
    /// Parameters by key.
    #[serde(default)]
    pub params: std::collections::BTreeMap<String, f64>,
    /// A user's rule table (fuzzy controllers).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rule_table: Option<RuleTable>,
    /// The engine of `fuzzy-engine`, as FLL or FIS text (written as FLL).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub engine: Option<String>,
}

impl ControllerText {
    /// The controller this text describes: `defaults` for its kind, with the parameters and the
    /// rule table it gives.
    pub fn resolve(
        self,
        defaults: impl FnOnce(ControllerKind) -> ControllerConfig,
    ) -> Result<ControllerConfig, ParamError> {
        let mut config = defaults(self.kind);
        for (key, value) in self.params {
            config.set(&key, value)?;
        }
        if let Some(table) = self.rule_table {
            config.set_rule_table(table)?;
        }
        if let Some(engine) = self.engine {
            config.set_engine(&engine)?;
        }
        Ok(config)
    }
}

impl TryFrom<ControllerText> for ControllerConfig {
    type Error = ParamError;

    fn try_from(text: ControllerText) -> Result<Self, ParamError> {
        text.resolve(ControllerConfig::new)
    }
}

impl From<ControllerConfig> for ControllerText {
    fn from(config: ControllerConfig) -> Self {
        ControllerText {
            kind: config.kind,
            params: config
                .kind
                .params()
                .iter()
                .zip(&config.values)
                .map(|(p, v)| (p.key.to_string(), *v))
                .collect(),
            rule_table: config.rule_table,
            engine: config.engine_fll,
        }
    }
}

/// How the lab's paper 002 controllers defuzzify U: eq 7's weighted average.
pub const PAPER_002_DEFUZZIFIER: Defuzzifier = Defuzzifier::WeightedAverage;

/// The fuzzy law's scalings from a fuzzy controller's values.
fn fuzzy_params(values: &[f64]) -> FuzzyParams {
    let t = FuzzyTuning::from_values(values);
    FuzzyParams {
        error_range_pct: t.error_range_pct,
        change_range_pct: t.change_range_pct,
        output_range_pct: t.output_range_pct,
        change_time_base_s: t.change_time_base_s,
        output_time_base_s: t.output_time_base_s,
    }
}

/// The engine `fuzzy-engine` runs until one is imported: paper 002's dynamics table as the
/// `fuzzy-dynamics` controller runs it, written as FLL (so it runs the same).
pub fn default_engine_fll() -> &'static str {
    static TEXT: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    TEXT.get_or_init(|| {
        paper_002_engine(&RuleBase::Dynamics.table(), PAPER_002_DEFUZZIFIER)
            .map(|engine| fll::write(&engine))
            .unwrap_or_default()
    })
}

/// What a controller needs to know about the run it is built for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunContext {
    /// The force to hold.
    pub target_force_n: f64,
    /// The control period.
    pub control_period_s: f64,
    /// The calibrated current sensitivity at the run's operating point, A per N (NaN when not
    /// known): turns a limit stated in amperes, as the papers state theirs, into a force.
    pub amps_per_newton: f64,
}

impl ControllerConfig {
    /// The controller with every parameter at its default.
    pub fn new(kind: ControllerKind) -> Self {
        Self {
            kind,
            values: kind.params().iter().map(|p| p.default).collect(),
            rule_table: None,
            engine_fll: (kind == ControllerKind::FuzzyEngine)
                .then(|| default_engine_fll().to_string()),
        }
    }

    /// Uses an engine (FLL or FIS text, told apart by content) as the `fuzzy-engine`
    /// controller's: its first input is E, its second EC, its one output the override's change.
    /// An engine that does not read, or is not of two inputs and one output, is an error with the
    /// reader's message (its line).
    ///
    /// ```
    /// use cutlab::control::registry::{ControllerConfig, ControllerKind};
    /// let mut c = ControllerConfig::new(ControllerKind::FuzzyEngine);
    /// let e = c.set_engine("Engine: x\nInputVariable: a\n  range: 0 1 2").unwrap_err();
    /// assert!(e.to_string().starts_with("engine: line 3"), "{e}");
    /// ```
    pub fn set_engine(&mut self, text: &str) -> Result<(), ParamError> {
        if self.kind != ControllerKind::FuzzyEngine {
            return Err(ParamError(format!(
                "controller \"{}\" runs its own rules; an imported engine runs as \"{}\"",
                self.kind,
                ControllerKind::FuzzyEngine
            )));
        }
        let engine = Format::of("", text)
            .parse(text)
            .map_err(|e| ParamError(format!("engine: {e}")))?;
        let fll_text = fll::write(&engine);
        // What is kept is the FLL, so it is the FLL that must read back and build: then every
        // later build of this configuration succeeds. The shape is the controller's to check.
        let written = fll::parse(&fll_text).map_err(|e| {
            ParamError(format!(
                "engine: written as FLL, it does not read back: {e}"
            ))
        })?;
        FuzzyController::from_engine(written, fuzzy_params(&self.values))
            .map_err(|e| ParamError(format!("engine: {e}")))?;
        self.engine_fll = Some(fll_text);
        Ok(())
    }

    /// The engine of a `fuzzy-engine` controller, as FLL (`None` for every other kind).
    pub fn engine_fll(&self) -> Option<&str> {
        self.engine_fll.as_deref()
    }

    /// How a `fuzzy-engine` controller maps E, EC and the override's change onto its engine, in
    /// words with this configuration's ranges (the form shows it; `None` for every other kind).
    /// The mapping itself is [`FuzzyController`]'s.
    ///
    /// ```
    /// use cutlab::control::registry::{ControllerConfig, ControllerKind};
    /// let c = ControllerConfig::new(ControllerKind::FuzzyEngine);
    /// assert_eq!(c.engine_mapping().unwrap(), "Engine \"paper002\": E = (F_target − F)/F_target \
    ///     → first input \"E\" on [-6, 6], ±100 % at its edges; EC, the change of E per control \
    ///     period → second input \"EC\" on [-6, 6], ±200 % at its edges; output \"U\" on [-6, 6] \
    ///     → override change, ±20 % per control period at its edges, none at its centre 0.");
    /// ```
    pub fn engine_mapping(&self) -> Option<String> {
        let engine = fll::parse(self.engine_fll.as_deref()?).ok()?;
        let ([e, ec], [u]) = (engine.inputs(), engine.outputs()) else {
            return None;
        };
        let t = FuzzyTuning::from_values(&self.values);
        let n = crate::input::readable;
        let per = |base_s: f64| {
            if base_s > 0.0 {
                format!("per {} s", n(base_s))
            } else {
                "per control period".to_string()
            }
        };
        Some(format!(
            "Engine \"{}\": E = (F_target − F)/F_target → first input \"{}\" on [{}, {}], ±{} % at \
             its edges; EC, the change of E {} → second input \"{}\" on [{}, {}], ±{} % at its \
             edges; output \"{}\" on [{}, {}] → override change, ±{} % {} at its edges, none at \
             its centre {}.",
            engine.name,
            e.name,
            n(e.min),
            n(e.max),
            n(t.error_range_pct),
            per(t.change_time_base_s),
            ec.name,
            n(ec.min),
            n(ec.max),
            n(t.change_range_pct),
            u.name,
            n(u.min),
            n(u.max),
            n(t.output_range_pct),
            per(t.output_time_base_s),
            n(u.min + (u.max - u.min) / 2.0),
        ))
    }

    /// Uses a user's 7×7 rule table (levels −3…3) for a fuzzy controller.
    pub fn set_rule_table(&mut self, table: RuleTable) -> Result<(), ParamError> {
        if !matches!(
            self.kind,
            ControllerKind::FuzzyExperience | ControllerKind::FuzzyDynamics
        ) {
            return Err(ParamError(format!(
                "controller \"{}\" has no rule table",
                self.kind
            )));
        }
        if table.iter().flatten().any(|l| !(-3..=3).contains(l)) {
            return Err(ParamError(
                "rule table entries must be levels from -3 (NB) to 3 (PB)".to_string(),
            ));
        }
        self.rule_table = Some(table);
        Ok(())
    }

    /// The user's rule table, if one is set.
    pub fn rule_table(&self) -> Option<&RuleTable> {
        self.rule_table.as_ref()
    }

    /// Which controller.
    pub fn kind(&self) -> ControllerKind {
        self.kind
    }

    /// The override a fixed-feed controller holds (`None` for every other controller).
    pub fn fixed_override_pct(&self) -> Option<f64> {
        (self.kind == ControllerKind::Fixed)
            .then(|| FixedTuning::from_values(&self.values).override_pct)
    }

    /// The value of parameter `key`.
    pub fn get(&self, key: &str) -> Option<f64> {
        self.kind
            .params()
            .iter()
            .position(|p| p.key == key)
            .map(|i| self.values[i])
    }

    /// `(spec, value)` for every parameter.
    pub fn values(&self) -> impl Iterator<Item = (&'static ParamSpec, f64)> + '_ {
        self.kind.params().iter().zip(self.values.iter().copied())
    }

    /// Sets parameter `key`, checking its range.
    pub fn set(&mut self, key: &str, value: f64) -> Result<(), ParamError> {
        let params = self.kind.params();
        let Some(index) = params.iter().position(|p| p.key == key) else {
            return Err(ParamError(format!(
                "controller \"{}\" has no parameter \"{key}\"; its parameters: {}",
                self.kind,
                params.iter().map(|p| p.key).collect::<Vec<_>>().join(", ")
            )));
        };
        let spec = params[index];
        if !(value.is_finite() && value >= spec.min && value <= spec.max) {
            return Err(ParamError(format!(
                "{key} = {} is outside {}",
                crate::input::readable(value),
                crate::input::table::range_text(spec.min, spec.max, spec.unit)
            )));
        }
        self.values[index] = value;
        Ok(())
    }

    /// Sets a parameter from `key=value` text, as typed on the command line.
    ///
    /// ```
    /// use cutlab::control::registry::{ControllerConfig, ControllerKind};
    /// let mut c = ControllerConfig::new(ControllerKind::Pi);
    /// c.set_text("kp=0.8").unwrap();
    /// assert_eq!(c.get("kp"), Some(0.8));
    /// assert!(c.set_text("kp=fast").unwrap_err().to_string().contains("kp"));
    /// ```
    pub fn set_text(&mut self, assignment: &str) -> Result<(), ParamError> {
        let (key, value) = assignment_parts(assignment)?;
        self.set(key, value)
    }

    /// Sets parameters from `key=value` texts in order: the parts of a spec `pi:kp=0.5:ki=2` or
    /// repeated `--set` options. Every front end that takes several assignments goes through
    /// here, so a parameter given twice is refused everywhere, naming it (otherwise the last
    /// would silently win). Nothing is set unless every assignment is good.
    ///
    /// ```
    /// use cutlab::control::registry::{ControllerConfig, ControllerKind};
    /// let mut c = ControllerConfig::new(ControllerKind::Pi);
    /// c.set_texts(["kp=0.8", "ki_per_s=2"]).unwrap();
    /// assert_eq!(c.get("kp"), Some(0.8));
    /// let e = c.set_texts(["kp=0.5", "kp=0.9"]).unwrap_err();
    /// assert_eq!(e.to_string(), "kp is given twice (kp=0.5, then kp=0.9); give each parameter once");
    /// assert_eq!(c.get("kp"), Some(0.8));
    /// ```
    pub fn set_texts<'a>(
        &mut self,
        assignments: impl IntoIterator<Item = &'a str>,
    ) -> Result<(), ParamError> {
        let mut updated = self.clone();
        let mut given: Vec<(&str, &str)> = Vec::new();
        for assignment in assignments {
            let (key, value) = assignment_parts(assignment)?;
            if let Some((_, earlier)) = given.iter().find(|(k, _)| *k == key) {
                return Err(ParamError(format!(
                    "{key} is given twice ({}, then {}); give each parameter once",
                    earlier.trim(),
                    assignment.trim()
                )));
            }
            updated.set(key, value)?;
            given.push((key, assignment));
        }
        *self = updated;
        Ok(())
    }

    /// Builds the controller for a run. Cross-parameter checks happen here.
    pub fn build(&self, context: &RunContext) -> Result<Box<dyn Controller>, ParamError> {
        if !(context.target_force_n.is_finite() && context.target_force_n > 0.0) {
            return Err(ParamError(format!(
                "the target force must be positive, not {} N",
                context.target_force_n
            )));
        }
        let target = context.target_force_n;
        let values = &self.values;
        Ok(match self.kind {
            ControllerKind::Fixed => Box::new(FixedFeed::new(
                FixedTuning::from_values(values).override_pct,
            )),
            ControllerKind::Restriction => {
                let t = RestrictionTuning::from_values(values);
                let half_band = target * t.band_pct / 200.0;
                Box::new(CurrentRestriction::new(RestrictionParams {
                    upper_limit_n: target + half_band,
                    lower_limit_n: target - half_band,
                    step_pct: t.step_pct,
                }))
            }
            ControllerKind::Threshold => {
                let t = ThresholdTuning::from_values(values);
                let gap_pct = if t.gap_a > 0.0 {
                    let per_n = context.amps_per_newton;
                    if !(per_n.is_finite() && per_n > 0.0) {
                        return Err(ParamError(
                            "gap_a needs the teach cut's current sensitivity, which this run \
                             does not have; give the gap in % of target (gap_pct)"
                                .to_string(),
                        ));
                    }
                    100.0 * t.gap_a / (per_n * target)
                } else {
                    t.gap_pct
                };
                Box::new(ThresholdProportional::new(ThresholdParams {
                    gap_pct,
                    kp: t.kp,
                    ignore_after_start_s: t.ignore_after_start_s,
                }))
            }
            ControllerKind::Pi => {
                let t = PiTuning::from_values(values);
                Box::new(PiController::new(PiParams {
                    kp: t.kp,
                    ki_per_s: t.ki_per_s,
                    tracking_time_s: t.tracking_time_s,
                    initial_override_pct: t.initial_override_pct,
                }))
            }
            ControllerKind::FuzzyExperience | ControllerKind::FuzzyDynamics => {
                let base = if self.kind == ControllerKind::FuzzyExperience {
                    RuleBase::Experience
                } else {
                    RuleBase::Dynamics
                };
                let table = self.rule_table.unwrap_or_else(|| base.table());
                Box::new(
                    FuzzyController::new(&table, PAPER_002_DEFUZZIFIER, fuzzy_params(values))
                        .map_err(|e| ParamError(e.to_string()))?,
                )
            }
            ControllerKind::FuzzyEngine => {
                let text = self.engine_fll().unwrap_or_else(|| default_engine_fll());
                let engine = fll::parse(text).map_err(|e| ParamError(format!("engine: {e}")))?;
                Box::new(
                    FuzzyController::from_engine(engine, fuzzy_params(values))
                        .map_err(|e| ParamError(format!("engine: {e}")))?,
                )
            }
            ControllerKind::Mrac => {
                let t = MracTuning::from_values(values);
                if t.min_beta_pct >= t.max_beta_pct {
                    return Err(ParamError(
                        "min_beta_pct must be below max_beta_pct".to_string(),
                    ));
                }
                Box::new(ModelReferenceAdaptive::new(MracParams {
                    lambda_per_s: t.lambda_per_s,
                    kd_pct_s: t.kd_pct_s,
                    gamma_beta_pct_per_s: t.gamma_beta_pct_per_s,
                    gamma_dynamics_pct_per_s: t.gamma_dynamics_pct_per_s,
                    initial_beta_pct: t.initial_beta_pct.clamp(t.min_beta_pct, t.max_beta_pct),
                    min_beta_pct: t.min_beta_pct,
                    max_beta_pct: t.max_beta_pct,
                    derivative_time_s: t.derivative_time_s,
                }))
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::law::ControlInput;

    #[test]
    fn every_default_lies_in_its_range_and_every_controller_builds() {
        let context = RunContext {
            target_force_n: 300.0,
            control_period_s: 0.1,
            amps_per_newton: f64::NAN,
        };
        for kind in ControllerKind::ALL {
            assert_eq!(kind.name().parse::<ControllerKind>(), Ok(kind));
            for p in kind.params() {
                assert!(p.min <= p.default && p.default <= p.max, "{kind}.{}", p.key);
            }
            let mut controller = ControllerConfig::new(kind).build(&context).unwrap();
            let out = controller.step(&ControlInput {
                time_s: 10.0,
                dt_s: 0.1,
                force_n: 300.0,
                target_force_n: 300.0,
                programmed_feed_mm_min: 200.0,
                applied_override_pct: 100.0,
                time_since_start_s: 10.0,
            });
            // On target at 100 % every controller's request is 100 %.
            assert!((out - 100.0).abs() < 1e-9, "{kind}: {out}");
        }
    }

    #[test]
    fn the_threshold_gap_in_amperes_is_the_papers_and_needs_a_sensitivity() {
        let mut c = ControllerConfig::new(ControllerKind::Threshold);
        c.set("gap_a", 0.4).unwrap();
        let context = |amps_per_newton| RunContext {
            target_force_n: 400.0,
            control_period_s: 0.1,
            amps_per_newton,
        };
        assert!(c.build(&context(f64::NAN)).is_err());
        // 0.4 A at 0.005 A/N is 80 N, a 20 % gap on a 400 N target (±10 %): 9 % above target is
        // inside it (no change), and outside the default 10 % gap (±5 %).
        let mut controller = c.build(&context(0.005)).unwrap();
        let input = ControlInput {
            time_s: 10.0,
            dt_s: 0.1,
            force_n: 436.0,
            target_force_n: 400.0,
            programmed_feed_mm_min: 200.0,
            applied_override_pct: 100.0,
            time_since_start_s: 10.0,
        };
        assert_eq!(controller.step(&input), 100.0);
        let mut default_gap = ControllerConfig::new(ControllerKind::Threshold)
            .build(&context(0.005))
            .unwrap();
        assert!(default_gap.step(&input) < 100.0);
    }

    #[test]
    fn a_tuning_reads_each_value_into_the_field_of_its_key() {
        let t = PiTuning::from_values(&[0.7, 2.0, 0.25, 90.0]);
        assert_eq!(
            (t.kp, t.ki_per_s, t.tracking_time_s, t.initial_override_pct),
            (0.7, 2.0, 0.25, 90.0)
        );
        let keys: Vec<_> = PiTuning::PARAMS.iter().map(|p| p.key).collect();
        assert_eq!(
            keys,
            ["kp", "ki_per_s", "tracking_time_s", "initial_override_pct"]
        );
        // Missing values take their defaults, never NaN.
        let m = MracTuning::from_values(&[]);
        assert_eq!(m.derivative_time_s, 0.2);
        assert!(MracTuning::PARAMS.iter().all(|p| !p.default.is_nan()));
    }

    #[test]
    fn parameters_are_checked_and_errors_name_them() {
        let mut c = ControllerConfig::new(ControllerKind::Threshold);
        assert!(c.set("kp", 0.8).is_ok());
        let e = c.set("kp", -1.0).unwrap_err();
        assert!(e.0.starts_with("kp = -1"), "{e}");
        let e = c.set("ki", 1.0).unwrap_err();
        assert!(e.0.contains("no parameter \"ki\""), "{e}");
        assert!(c.set("kp", f64::NAN).is_err());
        assert!("warp".parse::<ControllerKind>().is_err());
    }

    #[test]
    fn json_round_trip_keeps_values_and_rejects_bad_ones() {
        let mut c = ControllerConfig::new(ControllerKind::Mrac);
        c.set("kd_pct_s", 35.0).unwrap();
        let text = serde_json::to_string(&c).unwrap();
        let back: ControllerConfig = serde_json::from_str(&text).unwrap();
        assert_eq!(back, c);
        let partial: ControllerConfig =
            serde_json::from_str(r#"{"kind":"pi","params":{"kp":0.7}}"#).unwrap();
        assert_eq!(partial.get("kp"), Some(0.7));
        assert_eq!(partial.get("ki_per_s"), Some(1.0));
        assert!(
            serde_json::from_str::<ControllerConfig>(r#"{"kind":"pi","params":{"kp":-3}}"#)
                .is_err()
        );
        // A misspelt field is an error, not a run on the defaults.
        let e = serde_json::from_str::<ControllerConfig>(r#"{"kind":"pi","parms":{"kp":5}}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("unknown field `parms`"), "{e}");
    }
}
