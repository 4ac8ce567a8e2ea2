//! The Logs page's state in its URL: which sample log is open, which column is which channel, the
//! column analysed and its grouping, and the replay's form (controllers, target, machine) — so a
//! reload or a shared link restores the analysis and the replay. The analysis settings' own keys
//! are their table's ([`LogSetting`]); every other key is a row of [`LogsKey`], read and written
//! here only: the page writes its address bar with [`LogsLink::query`] and reads it with
//! [`LogsLink::parse`], and a lesson's `#/logs?…` setup is read by the same parser
//! ([`crate::lessons::setup`]) and replayed natively ([`LogsLink::replay_runs`]).
//!
//! A person's own file cannot travel in a link (it is on their disk): a link that maps columns
//! without naming a sample applies its mapping to the next log opened whose columns have those
//! names ([`LogsLink::mapping_for`]).

use std::sync::Arc;

use super::mapping::{Channel, Mapping};
use super::replay::{ReplayRuns, ReplaySettings};
use super::settings::{sample_period, LogSetting};
use super::Log;
use crate::closed_loop::definition::{max_override_pct_of, RunSetting, SettingsOverrides};
use crate::control::registry::{ControllerConfig, ControllerKind};
use crate::estimation::estimator::{Calibration, Feedback};
use crate::input::table::Table;
use crate::plant::cnc::OverrideMode;

/// The synthetic sample logs in `www/data`: file name and what it is.
pub const SAMPLES: [(&str, &str); 2] = [
    (
        "synthetic-kim-step-doc-export.csv",
        "Synthetic CNC export: 60 ms RMS currents, semicolons, decimal commas",
    ),
    (
        "synthetic-maneerat-doc-2-daq.csv",
        "Synthetic 1 kHz DAQ: spindle phase currents and a dynamometer",
    ),
];

/// The sample log named `file`, as [`SAMPLES`] spells it.
pub fn sample_named(file: &str) -> Option<&'static str> {
    SAMPLES.iter().find(|(f, _)| *f == file).map(|(f, _)| *f)
}

/// A key of the Logs page's URL (besides the analysis settings').
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LogsKey {
    /// The sample log open (a file of [`SAMPLES`]).
    Sample,
    /// `map.CHANNEL=COLUMN`: a column's channel (repeated for the phases). Present, these are the
    /// whole mapping; absent, the log's guessed one.
    Map,
    /// The column the signal chain analyses.
    Column,
    /// The label column its statistics are grouped by (empty: none).
    By,
    /// The controllers replayed, by name, comma-separated.
    Replay,
    /// The override input of the machine the log was recorded on.
    Machine,
    /// The replay's target force, N (the run definition's key).
    TargetForce,
    /// The replay's target current, A (the run definition's key).
    TargetCurrent,
}

impl LogsKey {
    /// Every key, in the order a link writes them.
    pub const ALL: [LogsKey; 8] = [
        LogsKey::Sample,
        LogsKey::Map,
        LogsKey::Column,
        LogsKey::By,
        LogsKey::Replay,
        LogsKey::Machine,
        LogsKey::TargetForce,
        LogsKey::TargetCurrent,
    ];

    /// The key in the query (for [`LogsKey::Map`], the prefix before the channel's name).
    pub fn key(self) -> &'static str {
        match self {
            LogsKey::Sample => "sample",
            LogsKey::Map => "map.",
            LogsKey::Column => "column",
            LogsKey::By => "by",
            LogsKey::Replay => "replay",
            LogsKey::Machine => "machine",
            LogsKey::TargetForce => RunSetting::TargetForce.spec().query_key,
            LogsKey::TargetCurrent => RunSetting::TargetCurrent.spec().query_key,
        }
    }

    /// The key `key` is, if it is one.
    pub fn of(key: &str) -> Option<LogsKey> {
        if key.starts_with(LogsKey::Map.key()) {
            return Some(LogsKey::Map);
        }
        Self::ALL
            .into_iter()
            .find(|k| *k != LogsKey::Map && k.key() == key)
    }
}

/// What a replay's target is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TargetKind {
    /// A current, A (the replay regulates the current without a calibration).
    #[default]
    Current,
    /// A force, N (needs a calibration).
    Force,
}

impl TargetKind {
    /// Both, in the form's order.
    pub const ALL: [TargetKind; 2] = [TargetKind::Current, TargetKind::Force];

    /// The name in the form's drop-down.
    pub fn name(self) -> &'static str {
        match self {
            TargetKind::Current => "current",
            TargetKind::Force => "force",
        }
    }

    /// For people.
    pub fn label(self) -> &'static str {
        match self {
            TargetKind::Current => "Current (A)",
            TargetKind::Force => "Force (N)",
        }
    }

    /// The kind named `name` (anything else: a current).
    pub fn from_name(name: &str) -> TargetKind {
        if name == TargetKind::Force.name() {
            TargetKind::Force
        } else {
            TargetKind::Current
        }
    }

    /// The run definition's row of this target.
    pub fn setting(self) -> RunSetting {
        match self {
            TargetKind::Current => RunSetting::TargetCurrent,
            TargetKind::Force => RunSetting::TargetForce,
        }
    }

    fn key(self) -> LogsKey {
        match self {
            TargetKind::Current => LogsKey::TargetCurrent,
            TargetKind::Force => LogsKey::TargetForce,
        }
    }
}

/// The controllers a replay starts with: the threshold loop and the PI.
pub const DEFAULT_REPLAYED: [ControllerKind; 2] = [ControllerKind::Threshold, ControllerKind::Pi];

/// The Logs page's state as its URL holds it.
#[derive(Debug, Clone, PartialEq)]
pub struct LogsLink {
    /// The sample log open.
    pub sample: Option<&'static str>,
    /// `(column, channel)` pairs: the whole mapping; empty for the log's guess.
    pub mapping: Vec<(String, Channel)>,
    /// The column analysed (`None`: the page's pick).
    pub column: Option<String>,
    /// The label column grouping the statistics (`None`: the page's pick; empty: none).
    pub by: Option<String>,
    /// The controllers replayed.
    pub replayed: Vec<ControllerKind>,
    /// The override input of the log's machine.
    pub machine: OverrideMode,
    /// The target's kind.
    pub target_kind: TargetKind,
    /// The target as typed (empty: the replay's default).
    pub target_text: String,
    /// The analysis settings' texts, by their table's keys.
    pub analysis: Vec<(LogSetting, String)>,
}

impl Default for LogsLink {
    fn default() -> Self {
        Self {
            sample: None,
            mapping: Vec::new(),
            column: None,
            by: None,
            replayed: DEFAULT_REPLAYED.to_vec(),
            machine: OverrideMode::default(),
            target_kind: TargetKind::default(),
            target_text: String::new(),
            analysis: Vec::new(),
        }
    }
}

/// The machines a log can come from: their override inputs.
pub fn machines() -> [OverrideMode; 3] {
    [
        OverrideMode::default(),
        OverrideMode::WholePercent,
        OverrideMode::Continuous,
    ]
}

/// The machine whose override input is named `name` ([`OverrideMode::name`]).
pub fn machine_named(name: &str) -> Option<OverrideMode> {
    machines().into_iter().find(|m| m.name() == name)
}

/// A machine's override input, for people.
pub fn machine_label(mode: &OverrideMode) -> &'static str {
    match mode {
        OverrideMode::Dial(_) => "FANUC's 16-position dial (10–150 %)",
        OverrideMode::WholePercent => "Whole percent, 0–255 % (paper 003's machine)",
        OverrideMode::Continuous => "Any value, 0–255 %",
    }
}

impl LogsLink {
    /// Reads a Logs link's query. Every key is checked; the problems, each naming its key, come
    /// beside what could be read (the page keeps the rest, a lesson refuses the link).
    pub fn parse(query: &[(String, String)]) -> (LogsLink, Vec<String>) {
        let mut link = LogsLink::default();
        let mut problems = Vec::new();
        let mut replay_given = false;
        for (key, value) in query {
            let Some(which) = LogsKey::of(key) else {
                match LogSetting::from_key(key) {
                    Some(setting) => match setting.parse(value) {
                        Ok(_) => link.analysis.push((setting, value.clone())),
                        Err(e) => problems.push(format!("{key}: {}", e.problem)),
                    },
                    None => problems.push(format!("\"{key}\" is not a setting of the logs page")),
                }
                continue;
            };
            match which {
                LogsKey::Sample => match sample_named(value) {
                    Some(file) => link.sample = Some(file),
                    None => problems.push(format!(
                        "{key}: \"{value}\" is not a sample log; samples: {}",
                        SAMPLES.map(|(f, _)| f).join(", ")
                    )),
                },
                LogsKey::Map => {
                    let name = &key[LogsKey::Map.key().len()..];
                    match Channel::from_name(name) {
                        Some(channel) if !value.is_empty() => {
                            link.mapping.push((value.clone(), channel))
                        }
                        Some(_) => problems.push(format!("{key}: name the column")),
                        None => problems.push(format!(
                            "{key}: \"{name}\" is not a channel; channels: {}",
                            Channel::ALL.map(Channel::name).join(", ")
                        )),
                    }
                }
                LogsKey::Column => link.column = Some(value.clone()),
                LogsKey::By => link.by = Some(value.clone()),
                LogsKey::Replay => {
                    replay_given = true;
                    link.replayed.clear();
                    for name in value.split(',').map(str::trim).filter(|n| !n.is_empty()) {
                        match name.parse::<ControllerKind>() {
                            Ok(kind) if !link.replayed.contains(&kind) => link.replayed.push(kind),
                            Ok(_) => {}
                            Err(e) => problems.push(format!("{key}: {e}")),
                        }
                    }
                }
                LogsKey::Machine => match machine_named(value) {
                    Some(machine) => link.machine = machine,
                    None => problems.push(format!(
                        "{key}: \"{value}\" is not a machine's override input; inputs: {}",
                        machines().map(|m| m.name()).join(", ")
                    )),
                },
                LogsKey::TargetForce | LogsKey::TargetCurrent => {
                    let kind = if which == LogsKey::TargetForce {
                        TargetKind::Force
                    } else {
                        TargetKind::Current
                    };
                    link.target_kind = kind;
                    link.target_text = value.clone();
                }
            }
        }
        // The target is checked against the machine's highest override, known only now.
        if let Err(e) = link
            .target_kind
            .setting()
            .parse_on(&link.target_text, max_override_pct_of(&link.machine))
        {
            problems.push(format!("{}: {}", link.target_kind.key().key(), e.problem));
        }
        if replay_given && link.replayed.is_empty() {
            problems.push(format!(
                "{}: name at least one controller",
                LogsKey::Replay.key()
            ));
        }
        (link, problems)
    }

    /// The query that restores this state, keys in [`LogsKey::ALL`]'s order, then the analysis
    /// settings; what is at its default is left out.
    pub fn query(&self) -> Vec<(String, String)> {
        let mut pairs = Vec::new();
        let mut push = |key: LogsKey, value: String| pairs.push((key.key().to_string(), value));
        if let Some(sample) = self.sample {
            push(LogsKey::Sample, sample.to_string());
        }
        for (column, channel) in &self.mapping {
            pairs.push((
                format!("{}{}", LogsKey::Map.key(), channel.name()),
                column.clone(),
            ));
        }
        let mut push = |key: LogsKey, value: String| pairs.push((key.key().to_string(), value));
        if let Some(column) = &self.column {
            push(LogsKey::Column, column.clone());
        }
        if let Some(by) = &self.by {
            push(LogsKey::By, by.clone());
        }
        if self.replayed != DEFAULT_REPLAYED {
            let names: Vec<&str> = self.replayed.iter().map(|k| k.name()).collect();
            push(LogsKey::Replay, names.join(","));
        }
        if self.machine != OverrideMode::default() {
            push(LogsKey::Machine, self.machine.name().to_string());
        }
        if !self.target_text.trim().is_empty() || self.target_kind != TargetKind::default() {
            push(self.target_kind.key(), self.target_text.clone());
        }
        pairs.extend(
            self.analysis
                .iter()
                .map(|(s, text)| (s.row().key.to_string(), text.clone())),
        );
        pairs
    }

    /// The mapping `mapping` as a link writes it: its pairs when it differs from `log`'s guess,
    /// none when it is the guess.
    pub fn mapping_of(log: &Log, mapping: &Mapping) -> Vec<(String, Channel)> {
        let sorted = |m: &Mapping| {
            let mut pairs = m.columns.clone();
            pairs.sort_by(|a, b| a.0.cmp(&b.0));
            pairs
        };
        if sorted(mapping) == sorted(&Mapping::guess(log)) {
            Vec::new()
        } else {
            mapping.columns.clone()
        }
    }

    /// This link's mapping for `log`: `None` when the link names none, or names a column the log
    /// does not have, or maps channels the log cannot be read through.
    pub fn mapping_for(&self, log: &Log) -> Option<Mapping> {
        if self.mapping.is_empty()
            || !self
                .mapping
                .iter()
                .all(|(name, _)| log.columns.iter().any(|c| c.name == *name))
        {
            return None;
        }
        let mapping = Mapping {
            columns: log
                .columns
                .iter()
                .flat_map(|c| {
                    self.mapping
                        .iter()
                        .filter(move |(name, _)| *name == c.name)
                        .map(|(name, channel)| (name.clone(), *channel))
                })
                .collect(),
        };
        mapping.resolve(log).ok().map(|_| mapping)
    }

    /// The mapping `log` is read through under this link: the link's if it fits, else the guess.
    pub fn mapping_or_guess(&self, log: &Log) -> Mapping {
        self.mapping_for(log).unwrap_or_else(|| Mapping::guess(log))
    }

    /// The sample period the analysis settings give (`None`: the log's time column).
    pub fn sample_period_s(&self) -> Option<f64> {
        let text = self
            .analysis
            .iter()
            .find(|(s, _)| *s == LogSetting::SamplePeriod)
            .map(|(_, t)| t.as_str());
        sample_period(text).ok().flatten()
    }

    /// The replay's settings: this link's target and machine, `feedback` measured, `calibration`
    /// (`None`: the current itself is regulated), the sample period of the analysis settings.
    pub fn replay_settings(
        &self,
        feedback: Feedback,
        calibration: Option<Calibration>,
        sample_period_s: Option<f64>,
    ) -> Result<ReplaySettings, String> {
        let mut run = SettingsOverrides {
            feedback: Some(feedback),
            ..SettingsOverrides::default()
        };
        let setting = self.target_kind.setting();
        let value = setting
            .parse_on(&self.target_text, max_override_pct_of(&self.machine))
            .map_err(|e| format!("{}: {}", self.target_kind.key().key(), e.problem))?;
        setting.apply_to_settings(&mut run, value);
        Ok(ReplaySettings {
            override_mode: self.machine,
            run,
            sample_period_s,
            calibration,
            ..ReplaySettings::default()
        })
    }

    /// The controllers replayed, configured as the page configures them.
    pub fn controllers(&self) -> Vec<ControllerConfig> {
        self.replayed
            .iter()
            .map(|k| ControllerConfig::new(*k))
            .collect()
    }

    /// The replays this link's form starts on `log` — the page's [`ReplayRuns`] — measuring the
    /// spindle (the calibration form's default) without a calibration, as a lesson's link sets
    /// them up.
    pub fn replay_runs(&self, log: Arc<Log>) -> Result<ReplayRuns, String> {
        if self.replayed.is_empty() {
            return Err("choose at least one controller".into());
        }
        let settings =
            self.replay_settings(Feedback::SpindleCurrent, None, self.sample_period_s())?;
        let mapping = self.mapping_or_guess(&log);
        Ok(ReplayRuns::new(log, mapping, settings, self.controllers()))
    }
}

/// The bytes of a sample log, for replays without a browser (the browser fetches them: none are
/// built into it).
#[cfg(target_arch = "wasm32")]
pub fn sample_bytes(_file: &str) -> Option<&'static [u8]> {
    None
}

/// The bytes of a sample log, for replays without a browser (the browser fetches them).
#[cfg(not(target_arch = "wasm32"))]
pub fn sample_bytes(file: &str) -> Option<&'static [u8]> {
    match file {
        "synthetic-kim-step-doc-export.csv" => Some(include_bytes!(
            "../../www/data/synthetic-kim-step-doc-export.csv"
        )),
        "synthetic-maneerat-doc-2-daq.csv" => Some(include_bytes!(
            "../../www/data/synthetic-maneerat-doc-2-daq.csv"
        )),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pairs(query: &[(&str, &str)]) -> Vec<(String, String)> {
        query
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    }

    #[test]
    fn a_link_reads_back_as_it_was_written() {
        let link = LogsLink {
            sample: Some(SAMPLES[0].0),
            mapping: vec![
                ("S_Strom [A]".into(), Channel::SpindleCurrent),
                ("Phase".into(), Channel::Label),
            ],
            column: Some("S_Strom [A]".into()),
            by: Some(String::new()),
            replayed: vec![ControllerKind::Pi, ControllerKind::Mrac],
            machine: OverrideMode::WholePercent,
            target_kind: TargetKind::Current,
            target_text: "10.4".into(),
            analysis: vec![(LogSetting::Lowpass, "5".into())],
        };
        let (read, problems) = LogsLink::parse(&link.query());
        assert!(problems.is_empty(), "{problems:?}");
        assert_eq!(read, link);
        assert!(link
            .query()
            .contains(&("map.spindle-current".into(), "S_Strom [A]".into())));
        // The defaults write nothing.
        assert!(LogsLink::default().query().is_empty());
    }

    #[test]
    fn each_bad_key_is_named_and_the_rest_is_kept() {
        let (link, problems) = LogsLink::parse(&pairs(&[
            ("sample", "nope.csv"),
            ("map.torque", "T"),
            ("replay", "pi,pid"),
            ("machine", "lathe"),
            ("target_a", "-3"),
            ("lowpass", "abc"),
            ("colour", "red"),
            ("column", "S_Strom [A]"),
        ]));
        let starts: Vec<&str> = problems
            .iter()
            .map(|p| p.split(':').next().unwrap_or_default())
            .collect();
        assert_eq!(
            starts,
            [
                "sample",
                "map.torque",
                "replay",
                "machine",
                "lowpass",
                "\"colour\" is not a setting of the logs page",
                "target_a"
            ]
        );
        assert_eq!(link.replayed, [ControllerKind::Pi]);
        assert_eq!(link.column.as_deref(), Some("S_Strom [A]"));
    }

    #[test]
    fn a_links_mapping_applies_only_to_a_log_with_those_columns() {
        let log = crate::log::load(sample_bytes(SAMPLES[0].0).unwrap_or_default(), None).unwrap();
        let guess = Mapping::guess(&log);
        assert!(LogsLink::mapping_of(&log, &guess).is_empty());
        let mut changed = guess.clone();
        changed.set("S_Strom [A]", None);
        changed.set("X_Strom [A]", Some(Channel::SpindleCurrent));
        let link = LogsLink {
            mapping: LogsLink::mapping_of(&log, &changed),
            ..LogsLink::default()
        };
        let mut read = link.mapping_for(&log).unwrap().columns;
        let mut wanted = changed.columns;
        read.sort_by(|a, b| a.0.cmp(&b.0));
        wanted.sort_by(|a, b| a.0.cmp(&b.0));
        assert_eq!(read, wanted);
        let elsewhere = LogsLink {
            mapping: vec![("Strom".into(), Channel::SpindleCurrent)],
            ..LogsLink::default()
        };
        assert_eq!(elsewhere.mapping_for(&log), None);
        assert_eq!(elsewhere.mapping_or_guess(&log), guess);
    }
}
