//! A step's conditions and their evaluation on what the student did: the finished runs of a
//! Simulate or Compare page (their metrics by the stable names of the metrics CSV, and their run
//! definition), a Signal chain page's filter (its settings and its gain at a frequency), or the
//! Logs page's finished replays (each controller's summary by the stable names of
//! [`replay_values`]).
//!
//! A condition's evaluation says whether it is met and what was measured, with the unit, so the
//! lesson panel and `cutlab lesson check` show "Mean |error| 3.2 % (needs below 5 %)".

use serde::Deserialize;

use super::setup::{LabPage, VARIANT_NAMES};
use crate::closed_loop::definition::{RunSetting, SettingValue};
use crate::closed_loop::lab::RunResult;
use crate::closed_loop::metrics::{compute, metric_values, Metrics, MetricsConfig};
use crate::closed_loop::summary::{MetricRow, METRIC_ROWS};
use crate::closed_loop::trace::Trace;
use crate::control::registry::ControllerKind;
use crate::input::table::Table;
use crate::log::replay::{replay_value_names, replay_values, ReplayResult};
use crate::signal::butterworth::{ButterworthSpec, Cutoff};
use crate::signal::design_settings::FilterSetting;
use crate::signal::sos::Sos;

/// How a measured value is compared.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Op {
    /// Strictly less.
    Below,
    /// Strictly more.
    Above,
    /// Less or equal.
    AtMost,
    /// More or equal.
    AtLeast,
    /// Equal (to a part in 10⁹).
    Equals,
}

impl Op {
    /// Whether `measured` relates to `wanted` this way.
    pub fn holds(self, measured: f64, wanted: f64) -> bool {
        match self {
            Op::Below => measured < wanted,
            Op::Above => measured > wanted,
            Op::AtMost => measured <= wanted,
            Op::AtLeast => measured >= wanted,
            Op::Equals => (measured - wanted).abs() <= 1e-9 * wanted.abs().max(1.0),
        }
    }

    /// The words for a student: "below".
    pub fn words(self) -> &'static str {
        match self {
            Op::Below => "below",
            Op::Above => "above",
            Op::AtMost => "at most",
            Op::AtLeast => "at least",
            Op::Equals => "equal to",
        }
    }
}

/// What a condition measures.
#[derive(Debug, Clone, PartialEq)]
pub enum Subject {
    /// A metric of a run, by its stable name (`force_mean_abs_error_pct`).
    Metric(String),
    /// A setting of a run's definition, by its URL key (`target`, `period`).
    Setting(RunSetting),
    /// A parameter of a run's controller (`kp`).
    Parameter(&'static str),
    /// Which controller a run uses.
    Controller(ControllerKind),
    /// A setting of the Signal chain page's filter (`order`, `cutoff`).
    Design(FilterSetting),
    /// The filter's gain at a frequency, in dB: what the Signal chain page's magnitude chart
    /// shows there ([`Sos::frequency_response`]).
    GainDb {
        /// The frequency, Hz.
        at_hz: f64,
    },
    /// A value of a Logs page replay's summary, by its stable name ([`replay_values`]), on the
    /// replay of controller `of`.
    Replay {
        /// The value's name (`override_changes`).
        name: &'static str,
        /// The controller whose replay it is measured on.
        of: ControllerKind,
    },
}

/// The name of [`Subject::GainDb`] in a lesson file.
pub const GAIN_DB: &str = "gain_db";

/// A filter's gain at `at_hz`, in dB (−300 dB at an exact zero).
///
/// ```
/// use cutlab::lessons::check::gain_db;
/// use cutlab::signal::butterworth::{butter, ButterworthSpec, Cutoff, FilterKind};
/// let spec = ButterworthSpec { kind: FilterKind::Lowpass, order: 2,
///     cutoff_hz: Cutoff::Single(50.0), sample_rate_hz: 10_000.0 };
/// let sos = butter(&spec).unwrap();
/// assert!((gain_db(&sos, &spec, 50.0) + 3.0103).abs() < 1e-3);
/// ```
pub fn gain_db(sos: &Sos, spec: &ButterworthSpec, at_hz: f64) -> f64 {
    let h = sos.frequency_response(&[at_hz], spec.sample_rate_hz);
    20.0 * h.first().map_or(0.0, |h| h.norm()).max(1e-15).log10()
}

/// What a condition compares the measured value with.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Wanted {
    /// A number, in the subject's unit.
    Value(Op, f64),
    /// The same subject of another Compare variant (index from 0 for A).
    Variant(Op, usize),
    /// Only that the subject holds (a controller).
    Holds,
    /// The same value of another controller's replay.
    Replay(Op, ControllerKind),
}

/// One condition of a step.
#[derive(Debug, Clone, PartialEq)]
pub struct StepCondition {
    /// What is measured.
    pub subject: Subject,
    /// On which run (0 for A, or the Simulate page's only run).
    pub variant: usize,
    /// What it must be.
    pub wanted: Wanted,
}

/// What a step's check was evaluated on.
#[derive(Debug, Clone, Copy)]
pub enum Evidence<'a> {
    /// The finished runs of a Simulate (one) or Compare (A first) page.
    Runs(&'a [&'a RunResult]),
    /// The Signal chain page's filter.
    Design {
        /// What was designed.
        spec: &'a ButterworthSpec,
        /// The design's sections.
        sos: &'a Sos,
    },
    /// The Logs page's finished replays, one per controller.
    Replays(&'a [&'a ReplayResult]),
}

/// A condition evaluated.
#[derive(Debug, Clone, PartialEq)]
pub struct ConditionOutcome {
    /// The condition, in words: "Mean |error| of A below 5 %".
    pub wants: String,
    /// Whether it is met.
    pub met: bool,
    /// What was measured, in words with its unit ("3.21 %"); "not measured" where the run has
    /// no such value (no depth step settled, another page's work).
    pub measured: String,
    /// The measured number, where there is one.
    pub value: Option<f64>,
    /// Its unit (empty for counts).
    pub unit: &'static str,
}

/// The stable names of the metrics a condition can name: the metrics CSV's names
/// ([`metric_values`]), units in the names.
pub fn metric_names() -> Vec<String> {
    named_metrics(&compute(&Trace::default(), &MetricsConfig::default()))
        .into_iter()
        .map(|(name, _)| name)
        .collect()
}

/// Every metric of `metrics` by its stable name ([`metric_values`], the list the metrics CSV
/// writes).
fn named_metrics(metrics: &Metrics) -> Vec<(String, Option<f64>)> {
    metric_values(metrics)
        .into_iter()
        .map(|(name, value)| (name.to_string(), value))
        .collect()
}

/// A metric's unit, from the suffix its stable name carries.
pub fn metric_unit(name: &str) -> &'static str {
    const SUFFIXES: [(&str, &str); 7] = [
        ("_mm3_s", "mm³/s"),
        ("_mm3", "mm³"),
        ("_n_s", "N·s"),
        ("_pct", "%"),
        ("_um", "µm"),
        ("_n", "N"),
        ("_s", "s"),
    ];
    SUFFIXES
        .iter()
        .find(|(suffix, _)| name.ends_with(suffix))
        .map_or("", |(_, unit)| unit)
}

/// A metric's name in words: `force_mean_abs_error_pct` → "force mean abs error".
fn metric_words(name: &str) -> String {
    let unit_suffix = ["_mm3_s", "_mm3", "_n_s", "_pct", "_um", "_n", "_s"]
        .iter()
        .find(|s| name.ends_with(*s))
        .map_or(0, |s| s.len());
    name[..name.len() - unit_suffix].replace('_', " ")
}

/// A number as a student reads it: four significant figures, no trailing zeros
/// ([`crate::input::significant`]); but a value from 0.00005 to 0.001, where that would write an
/// exponent, to four decimals as [`crate::input::readable`] writes a message's numbers: a gain of
/// −1.778e-4 dB reads "-0.0002 dB", as near 0 dB as it is.
pub fn shown(value: f64) -> String {
    if (5e-5..1e-3).contains(&value.abs()) {
        let text = format!("{value:.4}");
        text.trim_end_matches('0').to_string()
    } else {
        crate::input::significant(value, 4)
    }
}

fn with_unit(value: f64, unit: &str) -> String {
    if unit.is_empty() {
        shown(value)
    } else {
        format!("{} {unit}", shown(value))
    }
}

impl StepCondition {
    /// Whether this condition can be evaluated on `page`'s work; a message saying why not.
    pub fn fits(&self, page: LabPage) -> Result<(), FieldProblem> {
        let on_runs = matches!(
            self.subject,
            Subject::Metric(_)
                | Subject::Setting(_)
                | Subject::Parameter(_)
                | Subject::Controller(_)
        );
        let runs = match page {
            LabPage::Simulate => 1,
            LabPage::Compare => VARIANT_NAMES.len(),
            _ => 0,
        };
        let fits = match self.subject {
            Subject::Replay { .. } => page == LabPage::Logs,
            _ if on_runs => page.runs(),
            _ => page == LabPage::SignalChain,
        };
        if !fits {
            return Err((
                "",
                format!(
                    "this condition cannot be checked on the {} page",
                    page.slug()
                ),
            ));
        }
        let other = match self.wanted {
            Wanted::Variant(_, other) => Some(other),
            _ => None,
        };
        if on_runs && other.is_some() && page != LabPage::Compare {
            return Err((
                "than",
                format!(
                    "than compares one Compare variant with another; the {} page has one run, \
                     so give a value instead",
                    page.slug()
                ),
            ));
        }
        if other == Some(self.variant) {
            let name = VARIANT_NAMES.get(self.variant).unwrap_or(&"?");
            return Err((
                "than",
                format!(
                    "than names the variant measured ({name}): a value is never below or above \
                     itself"
                ),
            ));
        }
        if on_runs && (self.variant >= runs || other.is_some_and(|o| o >= runs)) {
            return Err(("", format!("the {} page has no such variant", page.slug())));
        }
        Ok(())
    }

    /// The name of what is measured, in words, with the run it is measured on.
    fn subject_words(&self, variants: bool) -> String {
        let on = if variants {
            format!(" of {}", VARIANT_NAMES.get(self.variant).unwrap_or(&"?"))
        } else {
            String::new()
        };
        match &self.subject {
            Subject::Metric(name) => format!("{}{on}", metric_words(name)),
            Subject::Setting(s) => format!("{}{on}", s.spec().label),
            Subject::Parameter(key) => format!("{key}{on}"),
            Subject::Controller(kind) => format!("controller{on} is {}", kind.label()),
            Subject::Design(s) => s.row().label.to_string(),
            Subject::GainDb { at_hz } => format!("gain at {} Hz", shown(*at_hz)),
            Subject::Replay { name, of } => {
                format!("{} of the {} replay", metric_words(name), of.label())
            }
        }
    }

    /// The unit of what is measured.
    fn unit(&self) -> &'static str {
        match &self.subject {
            Subject::Metric(name) => metric_unit(name),
            Subject::Replay { name, .. } => metric_unit(name),
            Subject::Setting(s) => s.spec().unit,
            Subject::Design(s) => s.row().unit,
            Subject::GainDb { .. } => "dB",
            Subject::Parameter(_) | Subject::Controller(_) => "",
        }
    }

    /// The measured value of this condition's subject on run `run`.
    fn measure_run(&self, run: &RunResult) -> Option<f64> {
        match &self.subject {
            Subject::Metric(name) => named_metrics(&run.metrics)
                .into_iter()
                .find(|(n, _)| n == name)
                .and_then(|(_, v)| v),
            Subject::Setting(setting) => setting.value_in(&run.spec).and_then(|v| match v {
                SettingValue::Number(x) => Some(x),
                SettingValue::Count(n) => Some(n as f64),
                SettingValue::Seed(s) => Some(s as f64),
                SettingValue::Feedback(_) | SettingValue::Material(_) => None,
            }),
            Subject::Parameter(key) => run.spec.controller.get(key),
            Subject::Controller(kind) => {
                Some(f64::from(u8::from(run.spec.controller.kind() == *kind)))
            }
            Subject::Design(_) | Subject::GainDb { .. } | Subject::Replay { .. } => None,
        }
    }

    /// The measured value on the replay of `of`, among `replays`.
    fn measure_replay(&self, replays: &[&ReplayResult], of: ControllerKind) -> Option<f64> {
        let Subject::Replay { name, .. } = &self.subject else {
            return None;
        };
        let replay = replays.iter().find(|r| r.controller.kind() == of)?;
        replay_values(&replay.summary)
            .into_iter()
            .find(|(n, _)| n == name)
            .and_then(|(_, v)| v)
    }

    /// The measured value on a design.
    fn measure_design(&self, spec: &ButterworthSpec, sos: &Sos) -> Option<f64> {
        match &self.subject {
            Subject::Design(FilterSetting::Order) => Some(spec.order as f64),
            Subject::Design(FilterSetting::Cutoff) => Some(match spec.cutoff_hz {
                Cutoff::Single(f) | Cutoff::Band(f, _) => f,
            }),
            Subject::Design(FilterSetting::Upper) => match spec.cutoff_hz {
                Cutoff::Band(_, f) => Some(f),
                Cutoff::Single(_) => None,
            },
            Subject::Design(FilterSetting::SampleRate) => Some(spec.sample_rate_hz),
            Subject::GainDb { at_hz } => Some(gain_db(sos, spec, *at_hz)),
            _ => None,
        }
    }

    /// Why this condition's subject has no value on `work`'s run `variant` (or replay of `of`),
    /// in words: "not measured: the force never settled after a depth step" — the reason the
    /// results table gives beside its "—" ([`MetricRow::why_missing`]).
    fn not_measured(
        &self,
        work: Evidence<'_>,
        variant: usize,
        of: Option<ControllerKind>,
    ) -> String {
        let why = match (work, &self.subject) {
            (Evidence::Runs(runs), Subject::Metric(name)) => runs.get(variant).map(|run| {
                let words = metric_words(name);
                let label = |row: &&MetricRow| row.label.to_lowercase();
                METRIC_ROWS
                    .iter()
                    .find(|row| label(row) == words)
                    .or_else(|| {
                        METRIC_ROWS
                            .iter()
                            .find(|row| label(row).starts_with(&words))
                    })
                    .map_or("the run has no such value", |row| row.why_missing(run))
                    .to_string()
            }),
            (Evidence::Runs(_), _) => None,
            (Evidence::Replays(replays), Subject::Replay { .. }) => of.map(|of| {
                if replays.iter().any(|r| r.controller.kind() == of) {
                    format!("the {} replay has no such value", of.label())
                } else {
                    format!("no {} replay was done (tick it and replay)", of.label())
                }
            }),
            _ => None,
        };
        match why {
            Some(why) if variant > 0 || matches!(self.wanted, Wanted::Variant(..)) => {
                let name = VARIANT_NAMES.get(variant).unwrap_or(&"?");
                format!("not measured for {name}: {why}")
            }
            Some(why) => format!("not measured: {why}"),
            None => "not measured".to_string(),
        }
    }

    /// Evaluates the condition on `work`.
    pub fn evaluate(&self, work: Evidence<'_>) -> ConditionOutcome {
        let variants = matches!(work, Evidence::Runs(runs) if runs.len() > 1)
            || matches!(self.wanted, Wanted::Variant(..))
            || self.variant > 0;
        let unit = self.unit();
        let measure = |variant: usize| -> Option<f64> {
            match work {
                Evidence::Runs(runs) => runs.get(variant).and_then(|r| self.measure_run(r)),
                Evidence::Design { spec, sos } => self.measure_design(spec, sos),
                Evidence::Replays(replays) => match self.subject {
                    Subject::Replay { of, .. } => self.measure_replay(replays, of),
                    _ => None,
                },
            }
        };
        let measure_replay = |of: ControllerKind| -> Option<f64> {
            match work {
                Evidence::Replays(replays) => self.measure_replay(replays, of),
                _ => None,
            }
        };
        let value = measure(self.variant).filter(|v| v.is_finite());
        let subject = self.subject_words(variants);
        let replay_of = match self.subject {
            Subject::Replay { of, .. } => Some(of),
            _ => None,
        };
        let (wants, met, measured) = match self.wanted {
            Wanted::Holds => {
                let met = value == Some(1.0);
                let measured = match value {
                    Some(_) if met => "yes".to_string(),
                    Some(_) => "no".to_string(),
                    None => self.not_measured(work, self.variant, None),
                };
                (subject, met, measured)
            }
            Wanted::Value(op, wanted) => (
                format!("{subject} {} {}", op.words(), with_unit(wanted, unit)),
                value.is_some_and(|v| op.holds(v, wanted)),
                value.map_or_else(
                    || self.not_measured(work, self.variant, replay_of),
                    |v| with_unit(v, unit),
                ),
            ),
            Wanted::Replay(op, other) => {
                let other_value = measure_replay(other).filter(|v| v.is_finite());
                let measured = match (value, other_value) {
                    (Some(v), Some(o)) => format!(
                        "{} vs {} for the {} replay",
                        with_unit(v, unit),
                        with_unit(o, unit),
                        other.label()
                    ),
                    (None, _) => self.not_measured(work, 0, replay_of),
                    (Some(_), None) => self.not_measured(work, 0, Some(other)),
                };
                (
                    format!(
                        "{subject} {} that of the {} replay",
                        op.words(),
                        other.label()
                    ),
                    matches!((value, other_value), (Some(v), Some(o)) if op.holds(v, o)),
                    measured,
                )
            }
            Wanted::Variant(op, other) => {
                let other_value = measure(other).filter(|v| v.is_finite());
                let other_name = VARIANT_NAMES.get(other).unwrap_or(&"?");
                let measured = match (value, other_value) {
                    (Some(v), Some(o)) => {
                        format!(
                            "{} vs {} for {other_name}",
                            with_unit(v, unit),
                            with_unit(o, unit)
                        )
                    }
                    (None, _) => self.not_measured(work, self.variant, None),
                    (Some(_), None) => self.not_measured(work, other, None),
                };
                (
                    format!("{subject} {} that of {other_name}", op.words()),
                    matches!((value, other_value), (Some(v), Some(o)) if op.holds(v, o)),
                    measured,
                )
            }
        };
        ConditionOutcome {
            wants,
            met,
            measured,
            value,
            unit,
        }
    }
}

/// A condition as a lesson file writes it: one subject (`metric`, `setting`, `controller`,
/// `signal` or `replay`), the variant it is on (a replay: `of`, its controller), and what it
/// must be (`is` with a `value`, or `is` with `than`, another variant or replayed controller).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StepConditionText {
    #[serde(default)]
    metric: Option<String>,
    #[serde(default)]
    setting: Option<String>,
    #[serde(default)]
    controller: Option<String>,
    #[serde(default)]
    signal: Option<String>,
    #[serde(default)]
    replay: Option<String>,
    #[serde(default)]
    of: Option<String>,
    #[serde(default)]
    at_hz: Option<f64>,
    #[serde(default)]
    variant: Option<String>,
    #[serde(default)]
    is: Option<Op>,
    #[serde(default)]
    value: Option<f64>,
    #[serde(default)]
    than: Option<String>,
}

/// A condition's problem and the field of the condition it is in.
pub type FieldProblem = (&'static str, String);

fn variant_index(name: &str) -> Option<usize> {
    VARIANT_NAMES
        .iter()
        .position(|v| v.eq_ignore_ascii_case(name))
}

impl StepConditionText {
    /// The condition this text states, checked against the metrics, settings and controllers
    /// that exist; the field at fault otherwise.
    pub fn resolve(&self) -> Result<StepCondition, FieldProblem> {
        let subjects = [
            self.metric.is_some(),
            self.setting.is_some(),
            self.controller.is_some(),
            self.signal.is_some(),
            self.replay.is_some(),
        ];
        if subjects.iter().filter(|s| **s).count() != 1 {
            return Err((
                "metric",
                "a condition names exactly one of metric, setting, controller, signal or replay"
                    .into(),
            ));
        }
        if let Some(name) = &self.replay {
            return self.resolve_replay(name);
        }
        if self.of.is_some() {
            return Err(("of", "of belongs to a replay condition".into()));
        }
        let variant = match &self.variant {
            None => 0,
            Some(name) => variant_index(name).ok_or((
                "variant",
                format!("\"{name}\" is not a variant; variants: A, B, C, D"),
            ))?,
        };
        let subject = if let Some(name) = &self.metric {
            if !metric_names().contains(name) {
                return Err((
                    "metric",
                    format!(
                        "\"{name}\" is not a metric; metrics: {}",
                        metric_names().join(", ")
                    ),
                ));
            }
            Subject::Metric(name.clone())
        } else if let Some(key) = &self.setting {
            if let Some(setting) = RunSetting::from_query_key(key) {
                Subject::Setting(setting)
            } else if let Some(param) = ControllerKind::ALL
                .iter()
                .flat_map(|k| k.params())
                .find(|p| p.key == key)
            {
                Subject::Parameter(param.key)
            } else if let Some(setting) =
                FilterSetting::from_key(key).filter(|s| *s != FilterSetting::Kind)
            {
                Subject::Design(setting)
            } else {
                return Err((
                    "setting",
                    format!(
                        "\"{key}\" is not a setting: use a run setting's or controller \
                         parameter's key as the lab's links write it (target, period, kp, …), or \
                         a filter's (order, cutoff)"
                    ),
                ));
            }
        } else if let Some(name) = &self.controller {
            let kind = name
                .parse::<ControllerKind>()
                .map_err(|e| ("controller", e.to_string()))?;
            if self.is.is_some() || self.value.is_some() || self.than.is_some() {
                return Err((
                    "is",
                    "a controller condition takes no is, value or than".into(),
                ));
            }
            return Ok(StepCondition {
                subject: Subject::Controller(kind),
                variant,
                wanted: Wanted::Holds,
            });
        } else {
            let name = self.signal.as_deref().unwrap_or_default();
            if name != GAIN_DB {
                return Err((
                    "signal",
                    format!("\"{name}\" is not a measure of a filter; measures: {GAIN_DB}"),
                ));
            }
            let at_hz = self.at_hz.filter(|f| f.is_finite() && *f >= 0.0).ok_or((
                "at_hz",
                "the gain is measured at a frequency: give at_hz, in Hz, 0 or more".into(),
            ))?;
            Subject::GainDb { at_hz }
        };
        if self.at_hz.is_some() && self.signal.is_none() {
            return Err(("at_hz", "at_hz belongs to a signal condition".into()));
        }
        let wanted = self.wanted("another variant", |op, other| {
            variant_index(other).map(|v| Wanted::Variant(op, v)).ok_or((
                "than",
                format!("\"{other}\" is not a variant; variants: A, B, C, D"),
            ))
        })?;
        Ok(StepCondition {
            subject,
            variant,
            wanted,
        })
    }

    /// What the condition must be: `is` with a `value`, or `is` with `than` (`others`, as
    /// `other` reads it).
    fn wanted(
        &self,
        others: &str,
        other: impl FnOnce(Op, &str) -> Result<Wanted, FieldProblem>,
    ) -> Result<Wanted, FieldProblem> {
        let op = self.is.ok_or((
            "is",
            "say how it compares: below, above, at_most, at_least or equals".into(),
        ))?;
        match (self.value, &self.than) {
            (Some(value), None) if value.is_finite() => Ok(Wanted::Value(op, value)),
            (None, Some(name)) => other(op, name),
            _ => Err((
                "value",
                format!("give a value to compare with, or than: {others} (not both)"),
            )),
        }
    }

    /// A condition on a replay's value `name`.
    fn resolve_replay(&self, name: &str) -> Result<StepCondition, FieldProblem> {
        let names = replay_value_names();
        let name = names.iter().copied().find(|n| *n == name).ok_or_else(|| {
            (
                "replay",
                format!(
                    "\"{name}\" is not a value of a replay; values: {}",
                    names.join(", ")
                ),
            )
        })?;
        let controller = |field: &'static str, text: &str| {
            text.parse::<ControllerKind>()
                .map_err(|e| (field, e.to_string()))
        };
        let of = controller(
            "of",
            self.of.as_deref().ok_or((
                "of",
                "a replay condition names the controller replayed: of (threshold, pi, …)".into(),
            ))?,
        )?;
        if self.variant.is_some() {
            return Err((
                "variant",
                "a replay is picked by its controller (of), not by a variant".into(),
            ));
        }
        if self.at_hz.is_some() {
            return Err(("at_hz", "at_hz belongs to a signal condition".into()));
        }
        let wanted = self.wanted("another controller's replay", |op, other| {
            Ok(Wanted::Replay(op, controller("than", other)?))
        })?;
        Ok(StepCondition {
            subject: Subject::Replay { name, of },
            variant: 0,
            wanted,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn condition(json: &str) -> Result<StepCondition, FieldProblem> {
        serde_json::from_str::<StepConditionText>(json)
            .map_err(|e| ("json", e.to_string()))?
            .resolve()
    }

    #[test]
    fn every_metric_name_has_a_value_and_a_known_unit_where_it_has_one() {
        let names = metric_names();
        assert!(names.contains(&"force_mean_abs_error_pct".to_string()));
        assert!(names.contains(&"time_above_limit_s".to_string()));
        assert_eq!(metric_unit("force_iae_n_s"), "N·s");
        assert_eq!(metric_unit("peak_force_n"), "N");
        assert_eq!(metric_unit("override_changes"), "");
    }

    #[test]
    fn conditions_resolve_to_their_subject_or_name_the_field_at_fault() {
        let c = condition(r#"{"metric": "force_mean_abs_error_pct", "is": "below", "value": 5}"#)
            .unwrap();
        assert_eq!(c.wanted, Wanted::Value(Op::Below, 5.0));
        let c = condition(r#"{"setting": "kp", "is": "at_most", "value": 1}"#).unwrap();
        assert_eq!(c.subject, Subject::Parameter("kp"));
        let c =
            condition(r#"{"metric": "cycle_time_s", "variant": "B", "is": "below", "than": "A"}"#)
                .unwrap();
        assert_eq!((c.variant, c.wanted), (1, Wanted::Variant(Op::Below, 0)));
        assert_eq!(
            condition(r#"{"metric": "nope", "is": "below", "value": 1}"#)
                .unwrap_err()
                .0,
            "metric"
        );
        assert_eq!(
            condition(r#"{"setting": "nope", "is": "below", "value": 1}"#)
                .unwrap_err()
                .0,
            "setting"
        );
        assert_eq!(
            condition(r#"{"metric": "cycle_time_s", "value": 1}"#)
                .unwrap_err()
                .0,
            "is"
        );
        assert_eq!(
            condition(r#"{"metric": "cycle_time_s", "is": "below"}"#)
                .unwrap_err()
                .0,
            "value"
        );
        assert_eq!(
            condition(r#"{"controller": "pid"}"#).unwrap_err().0,
            "controller"
        );
        assert_eq!(
            condition(r#"{"metric": "cycle_time_s", "variant": "E", "is": "below", "value": 1}"#)
                .unwrap_err()
                .0,
            "variant"
        );
    }

    #[test]
    fn a_filter_condition_reports_the_measured_value_with_its_unit() {
        let spec = ButterworthSpec {
            kind: crate::signal::butterworth::FilterKind::Lowpass,
            order: 6,
            cutoff_hz: Cutoff::Single(50.0),
            sample_rate_hz: 10_000.0,
        };
        let sos = crate::signal::butterworth::butter(&spec).unwrap();
        let order = condition(r#"{"setting": "order", "is": "at_most", "value": 4}"#).unwrap();
        let out = order.evaluate(Evidence::Design {
            spec: &spec,
            sos: &sos,
        });
        assert!(!out.met);
        assert_eq!((out.value, out.measured.as_str()), (Some(6.0), "6"));
        // Six orders above 50 Hz: −120 dB a decade up, to within the bilinear warp.
        let gain =
            condition(r#"{"signal": "gain_db", "at_hz": 500, "is": "below", "value": -100}"#)
                .unwrap();
        let out = gain.evaluate(Evidence::Design {
            spec: &spec,
            sos: &sos,
        });
        assert!(out.met, "{out:?}");
        assert_eq!(out.unit, "dB");
        assert_eq!(
            condition(r#"{"signal": "gain_db", "is": "below", "value": 1}"#)
                .unwrap_err()
                .0,
            "at_hz"
        );
    }

    #[test]
    fn numbers_are_shown_to_four_figures() {
        assert_eq!(shown(3.214_59), "3.215");
        assert_eq!(shown(1234.6), "1235");
        assert_eq!(shown(0.05), "0.05");
        assert_eq!(shown(0.0), "0");
        // A gain a hair below 0 dB, as the reviewer saw "-1.778e-4 dB".
        assert_eq!(shown(-1.778e-4), "-0.0002");
        assert_eq!(shown(9.9e-4), "0.001");
        assert_eq!(shown(2.5e-5), "2.5e-5");
    }
}
