//! Which column of a log is which signal of the machine: the mapping replay and calibration
//! read a log through.
//!
//! A [`Channel`] is a field of the closed loop's [`crate::machine::SensorSample`] (or of what a
//! log adds beside it: a measured force, the depth, a label). [`Mapping::guess`] proposes one from
//! the column roles the reader guessed ([`super::guess_role`]) and the axis prefix of each name
//! (`S_…` and unprefixed currents are the spindle's, `X_`/`Y_`/`Z_` the feed drive's); a person
//! confirms or changes it. The mapping names columns, not positions, so it survives reading the
//! file again and can be saved with an analysis.

use serde::{Deserialize, Serialize};

use super::{ColumnKind, Log, Role};

/// A signal of the machine a log column can carry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Channel {
    /// Time.
    Time,
    /// One phase current of the spindle motor (up to three columns).
    SpindlePhase,
    /// One phase current of the feed drive (up to three columns).
    FeedPhase,
    /// The spindle's RMS or "current feedback" value.
    SpindleCurrent,
    /// The feed drive's RMS or "current feedback" value.
    FeedCurrent,
    /// Spindle speed.
    SpindleSpeed,
    /// Programmed spindle speed (the S word).
    SpindleCommand,
    /// The spindle's frequency-to-voltage converter output (paper 003).
    FvVoltage,
    /// Actual path feed.
    Feed,
    /// Programmed feed, before override.
    ProgrammedFeed,
    /// The feed override the machine applied.
    Override,
    /// A measured force (a dynamometer).
    Force,
    /// Axial depth of cut.
    Depth,
    /// A label (a machining phase).
    Label,
}

impl Channel {
    /// Every channel, in the order the lab lists them.
    pub const ALL: [Channel; 14] = [
        Channel::Time,
        Channel::SpindlePhase,
        Channel::FeedPhase,
        Channel::SpindleCurrent,
        Channel::FeedCurrent,
        Channel::SpindleSpeed,
        Channel::SpindleCommand,
        Channel::FvVoltage,
        Channel::Feed,
        Channel::ProgrammedFeed,
        Channel::Override,
        Channel::Force,
        Channel::Depth,
        Channel::Label,
    ];

    /// The name on the command line (`--map spindle-current=S_I`) and in saved mappings.
    pub fn name(self) -> &'static str {
        match self {
            Channel::Time => "time",
            Channel::SpindlePhase => "spindle-phase",
            Channel::FeedPhase => "feed-phase",
            Channel::SpindleCurrent => "spindle-current",
            Channel::FeedCurrent => "feed-current",
            Channel::SpindleSpeed => "spindle-speed",
            Channel::SpindleCommand => "spindle-command",
            Channel::FvVoltage => "fv-voltage",
            Channel::Feed => "feed",
            Channel::ProgrammedFeed => "programmed-feed",
            Channel::Override => "override",
            Channel::Force => "force",
            Channel::Depth => "depth",
            Channel::Label => "label",
        }
    }

    /// For people.
    pub fn label(self) -> &'static str {
        match self {
            Channel::Time => "Time (s)",
            Channel::SpindlePhase => "Spindle phase current (A)",
            Channel::FeedPhase => "Feed-drive phase current (A)",
            Channel::SpindleCurrent => "Spindle RMS / feedback current (A)",
            Channel::FeedCurrent => "Feed-drive RMS / feedback current (A)",
            Channel::SpindleSpeed => "Spindle speed (rpm)",
            Channel::SpindleCommand => "Programmed spindle speed (rpm)",
            Channel::FvVoltage => "F/V converter voltage (V)",
            Channel::Feed => "Feed (mm/min)",
            Channel::ProgrammedFeed => "Programmed feed (mm/min)",
            Channel::Override => "Feed override (%)",
            Channel::Force => "Measured force (N)",
            Channel::Depth => "Depth of cut (mm)",
            Channel::Label => "Label (machining phase)",
        }
    }

    /// The channel of a name, if one has it.
    pub fn from_name(name: &str) -> Option<Channel> {
        let name = name.trim();
        Channel::ALL.into_iter().find(|c| c.name() == name)
    }

    /// How many columns may carry it: three phases, one of anything else.
    pub fn max_columns(self) -> usize {
        match self {
            Channel::SpindlePhase | Channel::FeedPhase => 3,
            _ => 1,
        }
    }

    /// Whether it holds numbers (every channel but the label).
    pub fn numeric(self) -> bool {
        self != Channel::Label
    }
}

/// Which column is which channel, by column name. Saved as
/// `[{"column": "S_I_U [A]", "channel": "spindle-phase"}, …]`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(into = "Vec<MappedColumn>", from = "Vec<MappedColumn>")]
pub struct Mapping {
    /// `(column name, channel)`, in the log's column order.
    pub columns: Vec<(String, Channel)>,
}

/// One column of a saved mapping.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MappedColumn {
    /// The column's name.
    pub column: String,
    /// Its channel.
    pub channel: Channel,
}

impl From<Mapping> for Vec<MappedColumn> {
    fn from(m: Mapping) -> Self {
        m.columns
            .into_iter()
            .map(|(column, channel)| MappedColumn { column, channel })
            .collect()
    }
}

impl From<Vec<MappedColumn>> for Mapping {
    fn from(columns: Vec<MappedColumn>) -> Self {
        Mapping {
            columns: columns.into_iter().map(|c| (c.column, c.channel)).collect(),
        }
    }
}

/// A mapping that does not fit its log; the message names the column.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MappingError(pub String);

impl std::fmt::Display for MappingError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for MappingError {}

/// A label in running text: "Measured force (N)" → "measured force (N)".
fn lower_first(label: &str) -> String {
    let mut chars = label.chars();
    chars
        .next()
        .map_or(String::new(), |c| c.to_lowercase().chain(chars).collect())
}

/// Whether a column name is a feed drive's: it starts with a feed axis (`X_`, `Y_`, `Z_`, also
/// `X.`, `X-`, `X `) or has the word "feed" (`feed_current_rms_a`).
fn feed_drive(name: &str) -> bool {
    let words = super::name_words(name);
    matches!(words.first().map(String::as_str), Some("x" | "y" | "z")) && words.len() > 1
        || words.iter().any(|w| w == "feed" || w == "vorschub")
}

/// Whether a name says it is a set value (a command, programmed): one of its words says so
/// (`offset` and `reset` are no set values).
fn commanded(name: &str) -> bool {
    super::name_words(name).iter().any(|w| {
        [
            "command",
            "commanded",
            "cmd",
            "prog",
            "programmed",
            "soll",
            "sollwert",
            "set",
            "setpoint",
            "target",
        ]
        .contains(&w.as_str())
    })
}

impl Mapping {
    /// The mapping the column roles suggest (docs/logs.md lists the rules): each channel takes
    /// the first columns that fit it, up to [`Channel::max_columns`].
    ///
    /// ```
    /// use cutlab::log::{load, mapping::{Channel, Mapping}};
    /// let log = load(b"t [s];S_I_U;S_I_V;S_speed (rpm);X_Strom [A];Override [%]\n0;1;2;3;4;100\n0,1;1;2;3;4;100\n", None).unwrap();
    /// let m = Mapping::guess(&log);
    /// assert_eq!(m.channel_of("S_I_V"), Some(Channel::SpindlePhase));
    /// assert_eq!(m.channel_of("X_Strom [A]"), Some(Channel::FeedCurrent));
    /// assert_eq!(m.channel_of("Override [%]"), Some(Channel::Override));
    /// ```
    pub fn guess(log: &Log) -> Mapping {
        let mut mapping = Mapping::default();
        for (i, column) in log.columns.iter().enumerate() {
            let name = column.name.as_str();
            let lower = name.to_ascii_lowercase();
            let channel = if log.time_column == Some(i) {
                Some(Channel::Time)
            } else if column.kind == ColumnKind::Number
                && (lower.contains("override") || lower.starts_with("ovr"))
            {
                Some(Channel::Override)
            } else if column.kind == ColumnKind::Number
                && (lower.contains("f/v") || lower.starts_with("fv") || lower.contains("_fv"))
            {
                Some(Channel::FvVoltage)
            } else {
                match column.role {
                    Some(Role::PhaseCurrent) if feed_drive(name) => Some(Channel::FeedPhase),
                    Some(Role::PhaseCurrent) => Some(Channel::SpindlePhase),
                    Some(Role::RmsCurrent) if feed_drive(name) => Some(Channel::FeedCurrent),
                    Some(Role::RmsCurrent) => Some(Channel::SpindleCurrent),
                    Some(Role::SpindleSpeed) if commanded(name) => Some(Channel::SpindleCommand),
                    Some(Role::SpindleSpeed) => Some(Channel::SpindleSpeed),
                    Some(Role::Feed) if commanded(name) => Some(Channel::ProgrammedFeed),
                    Some(Role::Feed) => Some(Channel::Feed),
                    Some(Role::Force) => Some(Channel::Force),
                    Some(Role::Depth) => Some(Channel::Depth),
                    Some(Role::Label) => Some(Channel::Label),
                    Some(Role::Time) | None => None,
                }
            };
            if let Some(channel) = channel {
                if mapping.count(channel) < channel.max_columns() {
                    mapping.columns.push((column.name.clone(), channel));
                }
            }
        }
        mapping
    }

    /// How many columns carry `channel`.
    pub fn count(&self, channel: Channel) -> usize {
        self.columns.iter().filter(|(_, c)| *c == channel).count()
    }

    /// The channel column `name` carries, if any.
    pub fn channel_of(&self, name: &str) -> Option<Channel> {
        self.columns
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, c)| *c)
    }

    /// The columns that carry `channel`, by name, in order.
    pub fn columns_of(&self, channel: Channel) -> Vec<&str> {
        self.columns
            .iter()
            .filter(|(_, c)| *c == channel)
            .map(|(n, _)| n.as_str())
            .collect()
    }

    /// Makes column `name` carry `channel` (or nothing). A channel that holds one column gives
    /// up its previous one; a phase channel already full gives up its first.
    pub fn set(&mut self, name: &str, channel: Option<Channel>) {
        self.columns.retain(|(n, _)| n != name);
        let Some(channel) = channel else {
            return;
        };
        if self.count(channel) >= channel.max_columns() {
            if let Some(first) = self.columns.iter().position(|(_, c)| *c == channel) {
                self.columns.remove(first);
            }
        }
        self.columns.push((name.to_string(), channel));
    }

    /// The column indexes of every channel in `log`, checked: each named column exists, holds
    /// numbers where the channel needs them, and no channel has too many columns.
    pub fn resolve(&self, log: &Log) -> Result<Resolved, MappingError> {
        let mut resolved = Resolved::default();
        for (name, channel) in &self.columns {
            let Some(index) = log.columns.iter().position(|c| &c.name == name) else {
                return Err(MappingError(format!(
                    "{}: no column {name:?} in the log; columns: {}",
                    channel.name(),
                    log.columns
                        .iter()
                        .map(|c| c.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            };
            let column = &log.columns[index];
            let numeric = matches!(column.kind, ColumnKind::Number | ColumnKind::Time);
            if channel.numeric() && !numeric {
                return Err(MappingError(format!(
                    "column {name:?} holds no numbers, so it cannot be the {}",
                    lower_first(channel.label())
                )));
            }
            if !channel.numeric() && column.kind != ColumnKind::Text {
                return Err(MappingError(format!(
                    "column {name:?} holds no labels, so it cannot be the label"
                )));
            }
            let slot = resolved.slot_mut(*channel);
            if slot.len() >= channel.max_columns() {
                return Err(MappingError(format!(
                    "{} columns are the {}: {}; choose {}",
                    slot.len() + 1,
                    lower_first(channel.label()),
                    self.columns_of(*channel).join(", "),
                    if channel.max_columns() == 1 {
                        "one".to_string()
                    } else {
                        format!("at most {}", channel.max_columns())
                    }
                )));
            }
            slot.push(index);
        }
        Ok(resolved)
    }
}

/// A mapping resolved against one log: column indexes per channel.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Resolved {
    /// Column indexes, per channel in [`Channel::ALL`] order.
    slots: [Vec<usize>; 14],
}

impl Resolved {
    fn slot_mut(&mut self, channel: Channel) -> &mut Vec<usize> {
        let at = Channel::ALL
            .iter()
            .position(|c| *c == channel)
            .unwrap_or_default();
        &mut self.slots[at]
    }

    /// The columns of `channel`, in order.
    pub fn columns(&self, channel: Channel) -> &[usize] {
        let at = Channel::ALL
            .iter()
            .position(|c| *c == channel)
            .unwrap_or_default();
        &self.slots[at]
    }

    /// The one column of `channel`, if mapped.
    pub fn column(&self, channel: Channel) -> Option<usize> {
        self.columns(channel).first().copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::log::load;

    #[test]
    fn a_channel_of_one_column_moves_and_a_fourth_phase_replaces_the_first() {
        let mut m = Mapping::default();
        m.set("a", Some(Channel::SpindleSpeed));
        m.set("b", Some(Channel::SpindleSpeed));
        assert_eq!(m.columns_of(Channel::SpindleSpeed), ["b"]);
        for name in ["u", "v", "w", "x"] {
            m.set(name, Some(Channel::SpindlePhase));
        }
        assert_eq!(m.columns_of(Channel::SpindlePhase), ["v", "w", "x"]);
        m.set("v", None);
        assert_eq!(m.columns_of(Channel::SpindlePhase), ["w", "x"]);
    }

    #[test]
    fn resolving_names_the_column_at_fault() {
        let log = load(b"t,I [A],Phase\n0,1,Prep\n0.1,2,Cut\n", None).unwrap();
        let mut m = Mapping::guess(&log);
        assert_eq!(m.channel_of("I [A]"), Some(Channel::SpindleCurrent));
        assert_eq!(m.channel_of("Phase"), Some(Channel::Label));
        let r = m.resolve(&log).unwrap();
        assert_eq!(r.column(Channel::SpindleCurrent), Some(1));
        assert_eq!(r.column(Channel::Time), Some(0));
        m.set("Phase", Some(Channel::Force));
        let e = m.resolve(&log).unwrap_err().to_string();
        assert!(
            e.ends_with("\"Phase\" holds no numbers, so it cannot be the measured force (N)"),
            "{e}"
        );
        m.set("Phase", Some(Channel::Label));
        m.columns.push(("Torque".into(), Channel::Force));
        let e = m.resolve(&log).unwrap_err().to_string();
        assert!(e.contains("no column \"Torque\""), "{e}");
    }
}
