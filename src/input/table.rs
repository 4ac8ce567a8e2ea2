//! Tables of settings: each setting a page or the command line accepts is a row of a table —
//! its key, its names, unit, range and default written once — and is parsed through that row, so
//! a form's field and a command-line option take the same values and refuse the rest with the
//! same words.
//!
//! A table is an enum implementing [`Table`]: [`Table::ROWS`] lists its settings in the order a
//! form shows them, [`Table::row`] describes each. The browser's form renders any table's rows
//! (labels, units, choices and the text a fresh form shows); the table's own parse turns the
//! typed text into the core's value and reports each [`RowError`] with the setting it belongs
//! to, so a page puts the message beside that setting's field and the command line names its
//! option ([`RowError::for_cli`]). A message itself never names an option: it is read in the
//! browser too.
//!
//! The tables: the run ([`crate::closed_loop::definition::RunSetting`], whose preset-dependent
//! ranges have their own parse), the Butterworth design ([`crate::signal::design_settings`]), the
//! cut of a calibration without a dynamometer ([`crate::estimation::cut_settings::CutSetting`]),
//! the virtual device ([`crate::protocol::device_settings`]), the analysis of a log
//! ([`crate::log::settings`]), tuning ([`crate::tuning::settings`]) and the open-loop machine
//! ([`crate::plant::recording::OpenLoopSetting`]).

use std::fmt;

use super::{parse_count, parse_number, parse_seed, readable};

/// What kind of value a row takes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind {
    /// A decimal number in `min..=max` (in the row's unit).
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
    /// A seed: any whole number from 0 to 2⁶⁴ − 1.
    Seed,
    /// One of the names [`Table::choices`] lists.
    Choice,
}

/// The value a fresh form shows and an option left out takes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shown {
    /// Nothing: the setting is optional, and blank means what its label says.
    Blank,
    /// This number.
    Number(f64),
    /// This whole number.
    Count(usize),
    /// This seed.
    Seed(u64),
    /// This choice, by name.
    Choice(&'static str),
}

/// Everything written about one setting.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row {
    /// Key in a page's URL query, its form field's id and its errors.
    pub key: &'static str,
    /// Command-line option, without the leading dashes (empty: the command line has none).
    pub cli_option: &'static str,
    /// Label of the form field (its accessible name).
    pub label: &'static str,
    /// Unit shown beside the value (empty for none).
    pub unit: &'static str,
    /// What the value is, for `--help` and the form's hint.
    pub help: &'static str,
    /// The value's kind and range.
    pub kind: Kind,
    /// What a fresh form shows and an option left out takes.
    pub default: Shown,
    /// What the value is, for messages: a range message names it instead of repeating the unit
    /// ("time scale 5000 is outside 0.01–1000"); empty: the unit says it ("5 s is outside …").
    pub noun: &'static str,
}

impl Row {
    /// A row of a number with no range yet (see [`Row::takes`]), its default blank, its help
    /// empty; `cli_option` empty where the command line has no option for it.
    ///
    /// ```
    /// use cutlab::input::table::{Kind, Row, Shown};
    /// let row = Row::new("order", "order", "Order", "")
    ///     .takes(Kind::Count { min: 1, max: 20 }, Shown::Count(4))
    ///     .noun("order")
    ///     .help("filter order");
    /// assert_eq!((row.default_text(), row.range()), ("4".to_string(), Some((1.0, 20.0))));
    /// ```
    pub const fn new(
        key: &'static str,
        cli_option: &'static str,
        label: &'static str,
        unit: &'static str,
    ) -> Row {
        Row {
            key,
            cli_option,
            label,
            unit,
            help: "",
            kind: Kind::Number {
                min: f64::NEG_INFINITY,
                max: f64::INFINITY,
            },
            default: Shown::Blank,
            noun: "",
        }
    }

    /// This row taking `kind` of value, `default` where left out.
    pub const fn takes(self, kind: Kind, default: Shown) -> Row {
        Row {
            kind,
            default,
            ..self
        }
    }

    /// This row naming its value `noun` in messages.
    pub const fn noun(self, noun: &'static str) -> Row {
        Row { noun, ..self }
    }

    /// This row with its help.
    pub const fn help(self, help: &'static str) -> Row {
        Row { help, ..self }
    }

    /// The text a fresh form shows.
    ///
    /// ```
    /// use cutlab::input::table::{Kind, Row, Shown};
    /// let row = Row {
    ///     key: "order", cli_option: "order", label: "Order", unit: "", help: "",
    ///     kind: Kind::Count { min: 1, max: 20 }, default: Shown::Count(4), noun: "order",
    /// };
    /// assert_eq!(row.default_text(), "4");
    /// ```
    pub fn default_text(&self) -> String {
        match self.default {
            Shown::Blank => String::new(),
            Shown::Number(v) => readable(v),
            Shown::Count(n) => n.to_string(),
            Shown::Seed(seed) => seed.to_string(),
            Shown::Choice(name) => name.to_string(),
        }
    }

    /// The default as a value (`None` for a blank one).
    pub fn default_value(&self) -> Option<Value> {
        match self.default {
            Shown::Blank => None,
            Shown::Number(v) => Some(Value::Number(v)),
            Shown::Count(n) => Some(Value::Count(n)),
            Shown::Seed(seed) => Some(Value::Seed(seed)),
            Shown::Choice(name) => Some(Value::Choice(name)),
        }
    }

    /// The accepted numeric range, if the row takes a number.
    pub fn range(&self) -> Option<(f64, f64)> {
        match self.kind {
            Kind::Number { min, max } => Some((min, max)),
            Kind::Count { min, max } => Some((min as f64, max as f64)),
            Kind::Seed | Kind::Choice => None,
        }
    }
}

/// A setting's value, once parsed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    /// A number in the row's unit.
    Number(f64),
    /// A whole number.
    Count(usize),
    /// A seed.
    Seed(u64),
    /// A choice, by its name.
    Choice(&'static str),
}

impl Value {
    /// The number, if this is one (a whole number too).
    pub fn number(self) -> Option<f64> {
        match self {
            Value::Number(v) => Some(v),
            Value::Count(n) => Some(n as f64),
            _ => None,
        }
    }

    /// The whole number, if this is one.
    pub fn count(self) -> Option<usize> {
        match self {
            Value::Count(n) => Some(n),
            _ => None,
        }
    }

    /// The seed, if this is one.
    pub fn seed(self) -> Option<u64> {
        match self {
            Value::Seed(s) => Some(s),
            _ => None,
        }
    }

    /// The choice's name, if this is one.
    pub fn choice(self) -> Option<&'static str> {
        match self {
            Value::Choice(name) => Some(name),
            _ => None,
        }
    }
}

/// What is wrong with a setting's text or value. The words are the same wherever it is shown.
#[derive(Debug, Clone, PartialEq)]
pub enum Problem {
    /// The text is not a value of the row's kind; the message says why.
    Parse(String),
    /// Not one of the names the row takes.
    Unknown {
        /// What the row names ("material").
        what: &'static str,
        /// What was given.
        text: String,
        /// The names it takes, comma separated.
        choices: String,
    },
    /// Zero or negative where only a positive value makes sense.
    NotPositive(f64),
    /// Negative where zero is the least.
    Negative(f64),
    /// Outside the accepted range.
    OutOfRange {
        /// The value given.
        value: f64,
        /// Smallest accepted.
        min: f64,
        /// Largest accepted.
        max: f64,
        /// Unit of all three.
        unit: &'static str,
        /// What the number counts, for unitless settings ("order 0 is outside 1–20").
        noun: &'static str,
    },
    /// Refused for a reason of its own (two settings that go together, a design the values
    /// do not make); the text says why.
    Other(String),
}

impl Problem {
    /// The problem of `value` outside `min..=max`, in the words every table uses: "must be
    /// positive" for a number at or below zero whose least is above zero (a length, a rate), "must
    /// be zero or positive" below a least of zero, else the range. `None` inside the range.
    ///
    /// ```
    /// use cutlab::input::table::Problem;
    /// assert_eq!(Problem::outside(5.0, 0.001, 2.0, "s", "").unwrap().to_string(), "5 s is outside 0.001–2 s");
    /// assert_eq!(Problem::outside(-1.0, 0.5, 100.0, "mm", "").unwrap().to_string(), "must be positive, got -1");
    /// assert_eq!(Problem::outside(0.0, 1.0, 20.0, "", "order").unwrap().to_string(), "order 0 is outside 1–20");
    /// assert_eq!(Problem::outside(1.0, 0.0, 2.0, "", "x"), None);
    /// ```
    pub fn outside(
        value: f64,
        min: f64,
        max: f64,
        unit: &'static str,
        noun: &'static str,
    ) -> Option<Problem> {
        if value >= min && value <= max {
            None
        } else if value <= 0.0 && min > 0.0 && !unit.is_empty() {
            Some(Problem::NotPositive(value))
        } else if value < 0.0 && min == 0.0 {
            Some(Problem::Negative(value))
        } else {
            Some(Problem::OutOfRange {
                value,
                min,
                max,
                unit,
                noun,
            })
        }
    }
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Problem::Parse(message) | Problem::Other(message) => f.write_str(message),
            Problem::Unknown {
                what,
                text,
                choices,
            } => write!(
                f,
                "unknown {what} {}; choices: {choices}",
                super::excerpt(text)
            ),
            Problem::NotPositive(v) => write_not_positive(f, *v),
            Problem::Negative(v) => write_negative(f, *v),
            Problem::OutOfRange {
                value,
                min,
                max,
                unit,
                noun,
            } => write_out_of_range(f, *value, *min, *max, unit, noun),
        }
    }
}

/// "must be positive, got -1": the words of [`Problem::NotPositive`], for every error type.
pub fn write_not_positive(f: &mut fmt::Formatter<'_>, value: f64) -> fmt::Result {
    write!(f, "must be positive, got {}", readable(value))
}

/// "must be zero or positive, got -1": the words of [`Problem::Negative`].
pub fn write_negative(f: &mut fmt::Formatter<'_>, value: f64) -> fmt::Result {
    write!(f, "must be zero or positive, got {}", readable(value))
}

/// A range as a person reads it, in the form, the command line's help and every message:
/// "0.001–2 s", "1–20" (no unit), never Rust's `0.001..=2`.
///
/// ```
/// use cutlab::input::table::range_text;
/// assert_eq!(range_text(0.001, 2.0, "s"), "0.001–2 s");
/// assert_eq!(range_text(0.0, 10.0, "% per %"), "0–10 % per %");
/// assert_eq!(range_text(1.0, 20.0, ""), "1–20");
/// ```
pub fn range_text(min: f64, max: f64, unit: &str) -> String {
    let (min, max) = (readable(min), readable(max));
    if unit.is_empty() {
        format!("{min}–{max}")
    } else {
        format!("{min}–{max} {unit}")
    }
}

/// "5 s is outside 0.001–2 s", or, for a value named by what it counts, "order 0 is outside
/// 1–20" (its unit, if any, is the form's label's): the words of [`Problem::OutOfRange`].
pub fn write_out_of_range(
    f: &mut fmt::Formatter<'_>,
    value: f64,
    min: f64,
    max: f64,
    unit: &str,
    noun: &str,
) -> fmt::Result {
    let value = readable(value);
    match (noun, unit) {
        ("", "") => write!(f, "value {value} is outside {}", range_text(min, max, "")),
        ("", unit) => write!(
            f,
            "{value} {unit} is outside {}",
            range_text(min, max, unit)
        ),
        (noun, _) => write!(f, "{noun} {value} is outside {}", range_text(min, max, "")),
    }
}

/// A setting of table `S` that did not parse, is out of range or was refused: the setting as
/// data, so a page shows the message beside its field and the command line names its option.
#[derive(Debug, Clone, PartialEq)]
pub struct RowError<S> {
    /// Which setting.
    pub setting: S,
    /// What is wrong with it.
    pub problem: Problem,
}

impl<S: Table> RowError<S> {
    /// An error of `setting`.
    pub fn new(setting: S, problem: Problem) -> Self {
        Self { setting, problem }
    }

    /// A refusal of `setting` for a reason of its own.
    pub fn other(setting: S, why: impl Into<String>) -> Self {
        Self::new(setting, Problem::Other(why.into()))
    }

    /// The message for the command line, naming the option (`--time-scale: time scale 5000 is
    /// outside 0.01–1000`).
    pub fn for_cli(&self) -> String {
        match self.setting.row().cli_option {
            "" => self.to_string(),
            option => format!("--{option}: {}", self.problem),
        }
    }

    /// The message for a form, keyed by the setting's row key.
    pub fn for_form(&self) -> (&'static str, String) {
        (self.setting.row().key, self.problem.to_string())
    }
}

impl<S: Table> fmt::Display for RowError<S> {
    /// The message naming the setting by its label (`Time scale: …`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.setting.row().label, self.problem)
    }
}

impl<S: Table> std::error::Error for RowError<S> {}

/// A table of settings: an enum whose variants are its rows.
pub trait Table: Copy + Eq + fmt::Debug + 'static {
    /// Every row, in the order a form shows them.
    const ROWS: &'static [Self];

    /// Everything written about this setting.
    fn row(self) -> Row;

    /// The `(name, label)` of each choice of a [`Kind::Choice`] row, a blank name first where
    /// blank is accepted.
    fn choices(self) -> Vec<(&'static str, &'static str)> {
        Vec::new()
    }

    /// The setting whose key is `key`.
    fn from_key(key: &str) -> Option<Self> {
        Self::ROWS.iter().copied().find(|s| s.row().key == key)
    }

    /// The setting whose command-line option is `option` (without dashes).
    fn from_cli_option(option: &str) -> Option<Self> {
        Self::ROWS
            .iter()
            .copied()
            .find(|s| !option.is_empty() && s.row().cli_option == option)
    }

    /// Reads what a person typed as this row's kind of value, without its range: blank text is
    /// `Ok(None)` (the default, or nothing where the default is blank). A table whose choices
    /// have other spellings reads them here ([`read_text`] is the plain reading).
    fn read(self, text: &str) -> Result<Option<Value>, RowError<Self>> {
        read_text(self, text)
    }

    /// Checks a value against the row's range.
    fn check(self, value: Value) -> Result<(), RowError<Self>> {
        let row = self.row();
        match (row.range(), value.number()) {
            (Some((min, max)), Some(v)) => {
                match Problem::outside(v, min, max, row.unit, row.noun) {
                    Some(problem) => Err(RowError::new(self, problem)),
                    None => Ok(()),
                }
            }
            _ => Ok(()),
        }
    }

    /// Parses and checks what a person typed; blank text takes the row's default (`Ok(None)`
    /// where that is blank).
    fn parse(self, text: &str) -> Result<Option<Value>, RowError<Self>> {
        match self.read(text)? {
            Some(value) => {
                self.check(value)?;
                Ok(Some(value))
            }
            None => Ok(self.row().default_value()),
        }
    }

    /// [`Table::parse`] of a command-line option's text, or the row's default where the option
    /// was left out.
    fn parse_given(self, text: Option<&str>) -> Result<Option<Value>, RowError<Self>> {
        match text {
            Some(text) => self.parse(text),
            None => Ok(self.row().default_value()),
        }
    }
}

/// Reads `text` as `setting`'s kind of value, without its range: a number, a whole number, a
/// seed, or one of its choices by name (any case). Blank text is `Ok(None)`.
pub fn read_text<S: Table>(setting: S, text: &str) -> Result<Option<Value>, RowError<S>> {
    let text = text.trim();
    if text.is_empty() {
        return Ok(None);
    }
    let parse = |r: Result<Value, String>| r.map_err(|m| RowError::new(setting, Problem::Parse(m)));
    let value = match setting.row().kind {
        Kind::Number { .. } => parse(parse_number(text).map(Value::Number))?,
        Kind::Count { .. } => parse(parse_count(text).map(Value::Count))?,
        Kind::Seed => parse(parse_seed(text).map(Value::Seed))?,
        Kind::Choice => {
            let found = setting
                .choices()
                .into_iter()
                .find(|(name, _)| !name.is_empty() && name.eq_ignore_ascii_case(text));
            match found {
                Some((name, _)) => Value::Choice(name),
                None => return Err(unknown_choice(setting, text)),
            }
        }
    };
    Ok(Some(value))
}

/// The refusal of `text`, which names none of `setting`'s choices; the message lists them.
pub fn unknown_choice<S: Table>(setting: S, text: &str) -> RowError<S> {
    let choices: Vec<&str> = setting
        .choices()
        .into_iter()
        .map(|(name, _)| name)
        .filter(|name| !name.is_empty())
        .collect();
    RowError::new(
        setting,
        Problem::Unknown {
            what: setting.row().noun,
            text: text.trim().to_string(),
            choices: choices.join(", "),
        },
    )
}

/// Reads the rows of a table from typed text, each once, those not given (or blank) taking their
/// defaults, and keeps every refusal: what each table's parse does before it builds its value.
///
/// ```
/// use cutlab::input::table::Reader;
/// use cutlab::protocol::device_settings::DeviceSetting;
/// let texts = [(DeviceSetting::TimeScale, "4"), (DeviceSetting::DropRate, "2")];
/// let mut reader = Reader::new(&texts);
/// assert_eq!(reader.number(DeviceSetting::TimeScale), Some(4.0));
/// assert_eq!(reader.number(DeviceSetting::Watchdog), Some(0.5));
/// assert_eq!(reader.number(DeviceSetting::DropRate), None);
/// assert_eq!(reader.errors().len(), 1);
/// ```
pub struct Reader<'a, S, T> {
    texts: &'a [(S, T)],
    errors: Vec<RowError<S>>,
}

impl<'a, S: Table, T: AsRef<str>> Reader<'a, S, T> {
    /// A reader of `texts` (the last text given for a setting counts).
    pub fn new(texts: &'a [(S, T)]) -> Self {
        Self {
            texts,
            errors: Vec::new(),
        }
    }

    /// The text given for `setting`, if any.
    pub fn text(&self, setting: S) -> Option<&'a str> {
        self.texts
            .iter()
            .rev()
            .find(|(given, _)| *given == setting)
            .map(|(_, t)| t.as_ref())
    }

    /// `setting`'s value ([`Table::parse_given`]); `None` where blank without a default or
    /// refused (the refusal kept).
    pub fn value(&mut self, setting: S) -> Option<Value> {
        match setting.parse_given(self.text(setting)) {
            Ok(value) => value,
            Err(e) => {
                self.errors.push(e);
                None
            }
        }
    }

    /// `setting`'s value as read, without its range ([`Table::read`]), or its default.
    pub fn read(&mut self, setting: S) -> Option<Value> {
        match setting.read(self.text(setting).unwrap_or_default()) {
            Ok(value) => value.or_else(|| setting.row().default_value()),
            Err(e) => {
                self.errors.push(e);
                None
            }
        }
    }

    /// `setting`'s number.
    pub fn number(&mut self, setting: S) -> Option<f64> {
        self.value(setting).and_then(Value::number)
    }

    /// `setting`'s whole number.
    pub fn count(&mut self, setting: S) -> Option<usize> {
        self.value(setting).and_then(Value::count)
    }

    /// `setting`'s choice, by name.
    pub fn choice(&mut self, setting: S) -> Option<&'static str> {
        self.value(setting).and_then(Value::choice)
    }

    /// A refusal of the table's own (two settings that go together).
    pub fn refuse(&mut self, error: RowError<S>) {
        self.errors.push(error);
    }

    /// Whether `setting` was refused.
    pub fn refused(&self, setting: S) -> bool {
        self.errors.iter().any(|e| e.setting == setting)
    }

    /// The refusals so far.
    pub fn errors(&self) -> &[RowError<S>] {
        &self.errors
    }

    /// `value` if nothing was refused, else every refusal.
    pub fn finish<V>(self, value: Option<V>) -> Result<V, Vec<RowError<S>>> {
        match value {
            Some(value) if self.errors.is_empty() => Ok(value),
            _ => Err(self.errors),
        }
    }
}

/// The value of a number row (its default where blank); an error where it has none.
pub fn number<S: Table>(setting: S, text: &str) -> Result<f64, RowError<S>> {
    required(setting, setting.parse(text)?)?
        .number()
        .ok_or_else(|| RowError::new(setting, Problem::Parse("enter a number".to_string())))
}

/// The value of an optional number row: `None` where blank.
pub fn optional_number<S: Table>(setting: S, text: &str) -> Result<Option<f64>, RowError<S>> {
    Ok(setting.parse(text)?.and_then(Value::number))
}

/// The value of a whole-number row (its default where blank).
pub fn count<S: Table>(setting: S, text: &str) -> Result<usize, RowError<S>> {
    required(setting, setting.parse(text)?)?
        .count()
        .ok_or_else(|| RowError::new(setting, Problem::Parse("enter a whole number".to_string())))
}

fn required<S: Table>(setting: S, value: Option<Value>) -> Result<Value, RowError<S>> {
    value.ok_or_else(|| {
        let what = match setting.row().kind {
            Kind::Count { .. } | Kind::Seed => "enter a whole number",
            Kind::Choice => "choose one",
            Kind::Number { .. } => "enter a number",
        };
        RowError::new(setting, Problem::Parse(what.to_string()))
    })
}

/// The errors of a table's form as its field keys and messages, for a page.
pub fn form_errors<S: Table>(
    errors: &[RowError<S>],
) -> std::collections::BTreeMap<&'static str, String> {
    let mut keyed = std::collections::BTreeMap::new();
    for e in errors {
        // The first error of a field is the one to fix first.
        let (key, message) = e.for_form();
        keyed.entry(key).or_insert(message);
    }
    keyed
}

/// Checks a table: its keys and options are unique, its defaults lie inside its ranges and read
/// back to themselves, each range's ends are accepted and what lies beyond is refused with the
/// setting named and no option in the words, and each choice reads back. Every table's tests
/// call it; the first broken rule is the error.
pub fn check_table<S: Table>() -> Result<(), String> {
    let rows: Vec<Row> = S::ROWS.iter().map(|s| s.row()).collect();
    for names in [
        rows.iter().map(|r| r.key).collect::<Vec<_>>(),
        rows.iter().map(|r| r.cli_option).collect(),
    ] {
        let mut sorted: Vec<&str> = names.into_iter().filter(|n| !n.is_empty()).collect();
        let count = sorted.len();
        sorted.sort_unstable();
        sorted.dedup();
        if sorted.len() != count {
            return Err(format!("names repeat in {:?}", S::ROWS));
        }
    }
    for s in S::ROWS {
        let row = s.row();
        // The help is the form's too: no option of the command line in it.
        if row.help.contains("--") {
            return Err(format!("{s:?}: its help names a command-line option"));
        }
        if S::from_key(row.key) != Some(*s) {
            return Err(format!("{s:?}: its key finds another row"));
        }
        if let Some(v) = row.default_value() {
            s.check(v)
                .map_err(|e| format!("{s:?}: its default is refused: {e}"))?;
            if s.parse(&row.default_text()).ok().flatten() != Some(v) {
                return Err(format!("{s:?}: its default text does not read back"));
            }
        }
        if let Some((min, max)) = row.range() {
            for v in [min, max] {
                // Every digit, so the ends read back exactly (1.7976931348623157e308).
                let text = match row.kind {
                    Kind::Count { .. } => format!("{v}"),
                    _ => format!("{v:e}"),
                };
                s.parse(&text)
                    .map_err(|e| format!("{s:?}: the end {v} of its range is refused: {e}"))?;
            }
            let step = if matches!(row.kind, Kind::Count { .. }) {
                1.0
            } else {
                (max - min).abs().max(1.0) * 0.01
            };
            for v in [min - step, max + step] {
                if v < 0.0 && matches!(row.kind, Kind::Count { .. }) || !v.is_finite() {
                    continue;
                }
                match s.parse(&format!("{v}")) {
                    Err(e) if e.setting == *s && !e.problem.to_string().contains("--") => {}
                    other => return Err(format!("{s:?}: {v} beyond its range gives {other:?}")),
                }
            }
        }
        if row.kind == Kind::Choice {
            let choices = s.choices();
            if choices.iter().all(|(name, _)| name.is_empty()) {
                return Err(format!("{s:?}: a choice without choices"));
            }
            for (name, _) in choices.iter().filter(|(n, _)| !n.is_empty()) {
                if s.parse(name).ok().flatten() != Some(Value::Choice(name)) {
                    return Err(format!("{s:?}: its choice {name:?} does not read back"));
                }
            }
            if s.parse("no such choice").is_ok() {
                return Err(format!("{s:?}: takes any name"));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    enum Demo {
        Period,
        Order,
        Colour,
        Offset,
    }

    impl Table for Demo {
        const ROWS: &'static [Self] = &[Demo::Period, Demo::Order, Demo::Colour, Demo::Offset];

        fn row(self) -> Row {
            let row = |key, label, unit, kind, default, noun| Row {
                key,
                cli_option: key,
                label,
                unit,
                help: "",
                kind,
                default,
                noun,
            };
            match self {
                Demo::Period => row(
                    "period",
                    "Period",
                    "s",
                    Kind::Number {
                        min: 0.001,
                        max: 2.0,
                    },
                    Shown::Blank,
                    "",
                ),
                Demo::Order => row(
                    "order",
                    "Order",
                    "",
                    Kind::Count { min: 1, max: 20 },
                    Shown::Count(4),
                    "order",
                ),
                Demo::Colour => row(
                    "colour",
                    "Colour",
                    "",
                    Kind::Choice,
                    Shown::Choice("red"),
                    "colour",
                ),
                Demo::Offset => row(
                    "offset",
                    "Offset",
                    "mm",
                    Kind::Number { min: 0.0, max: 5.0 },
                    Shown::Number(0.0),
                    "",
                ),
            }
        }

        fn choices(self) -> Vec<(&'static str, &'static str)> {
            vec![("red", "Red"), ("blue", "Blue")]
        }
    }

    #[test]
    fn rows_parse_check_and_say_what_is_wrong_without_naming_an_option() {
        assert_eq!(check_table::<Demo>(), Ok(()));
        assert_eq!(Demo::Period.parse(" 0,05 "), Ok(Some(Value::Number(0.05))));
        assert_eq!(Demo::Period.parse(""), Ok(None));
        assert_eq!(Demo::Order.parse(""), Ok(Some(Value::Count(4))));
        assert_eq!(Demo::Colour.parse("BLUE"), Ok(Some(Value::Choice("blue"))));
        let e = Demo::Period.parse("5").unwrap_err();
        assert_eq!(e.problem.to_string(), "5 s is outside 0.001–2 s");
        assert_eq!(e.for_cli(), "--period: 5 s is outside 0.001–2 s");
        assert_eq!(e.to_string(), "Period: 5 s is outside 0.001–2 s");
        assert_eq!(
            e.for_form(),
            ("period", "5 s is outside 0.001–2 s".to_string())
        );
        assert_eq!(
            Demo::Order.parse("0").unwrap_err().problem.to_string(),
            "order 0 is outside 1–20"
        );
        assert_eq!(
            Demo::Offset.parse("-1").unwrap_err().problem.to_string(),
            "must be zero or positive, got -1"
        );
        assert_eq!(
            Demo::Colour.parse("green").unwrap_err().problem.to_string(),
            "unknown colour \"green\"; choices: red, blue"
        );
        assert!(Demo::Order.read("2.5").is_err());
        assert_eq!(Demo::Order.read("50"), Ok(Some(Value::Count(50))));
        assert_eq!(Demo::Order.parse_given(None), Ok(Some(Value::Count(4))));
        assert_eq!(number(Demo::Offset, ""), Ok(0.0));
        assert!(number(Demo::Period, "").is_err());
        assert_eq!(optional_number(Demo::Period, ""), Ok(None));
        assert_eq!(count(Demo::Order, "7"), Ok(7));
        assert_eq!(Demo::from_cli_option("colour"), Some(Demo::Colour));
        assert_eq!(Demo::from_key("nothing"), None);
        let errors = [
            Demo::Period.parse("x").unwrap_err(),
            Demo::Period.parse("9").unwrap_err(),
        ];
        assert_eq!(form_errors(&errors)["period"], "\"x\" is not a number");
    }
}
