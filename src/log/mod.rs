//! Engineers' logs as they are: a messy CSV file in, columns out.
//!
//! ```text
//! bytes (chunks) ─► csv::CsvReader (dialect, quotes, BOM, CRLF) ─► records
//!   ─► LogBuilder (header, numbers or labels per column, problems by line and column)
//!   ─► Log (columns, units, time column and sample period, role guesses)
//! ```
//!
//! Numbers are stored as one `Vec<f64>` per column and text as interned labels; nothing of the
//! text is kept after a record is read, so memory follows the numbers, not the file. A damaged
//! line (too few or too many fields, text in a numeric column) is reported by line and column
//! and kept as a gap (NaN); the rest of the file loads. docs/logs.md describes the rules.

pub mod analysis;
pub mod calibration;
pub mod csv;
pub mod machine;
pub mod mapping;
pub mod period_log;
pub mod replay;

use serde::Serialize;

use csv::{parse_number, Cell, CsvReader, Dialect, RecordView};

/// A column with at least this share of numbers (among its non-empty cells) is numeric; its
/// other cells are gaps, each reported. Below it the column is text (labels).
pub const NUMERIC_SHARE: f64 = 0.75;
/// At most this many problems are listed one by one; the rest are counted.
pub const MAX_LISTED_PROBLEMS: usize = 200;

/// What a column holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ColumnKind {
    /// Numbers.
    Number,
    /// Labels (a machining phase, a pass/fail flag).
    Text,
    /// The time axis.
    Time,
    /// Nothing in any row.
    Empty,
}

/// What a column measures, guessed from its name and unit (a person confirms or changes it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Role {
    /// Time.
    Time,
    /// A phase current of a motor.
    PhaseCurrent,
    /// An RMS or "current feedback" value.
    RmsCurrent,
    /// Spindle speed.
    SpindleSpeed,
    /// Feed rate.
    Feed,
    /// A measured force.
    Force,
    /// Depth of cut.
    Depth,
    /// A label column.
    Label,
}

/// One problem, by line and (where it is one cell's) column.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Problem {
    /// The line in the file (1-based).
    pub line: usize,
    /// The column's name, when the problem is one cell's.
    pub column: Option<String>,
    /// What is wrong, and what was done about it.
    pub message: String,
}

/// One column of a log.
#[derive(Debug, Clone, PartialEq)]
pub struct Column {
    /// Its name as written (or `column N` without a header).
    pub name: String,
    /// The unit read from the name (`Current [A]`, `speed(rpm)`), if any.
    pub unit: Option<String>,
    /// What it holds.
    pub kind: ColumnKind,
    /// What it measures, guessed.
    pub role: Option<Role>,
    /// One value per row (NaN for a gap); empty for a text column.
    pub values: Vec<f64>,
    /// One label id per row for a text column (`u32::MAX` for an empty cell).
    pub labels: Vec<u32>,
    /// The distinct labels, by id.
    pub label_names: Vec<String>,
    /// Numbers among the non-empty cells, 0–1.
    pub numeric_share: f64,
    /// Empty or unreadable cells.
    pub missing: usize,
}

impl Column {
    /// Smallest, largest and mean of the finite values (NaN when there are none).
    pub fn min_max_mean(&self) -> (f64, f64, f64) {
        // Four independent lanes: the additions of one do not wait for another's.
        let (mut lo, mut hi) = ([f64::INFINITY; 4], [f64::NEG_INFINITY; 4]);
        let (mut sum, mut n) = ([0.0; 4], [0usize; 4]);
        let mut lanes = self.values.chunks_exact(4);
        for four in &mut lanes {
            for k in 0..4 {
                let v = four[k];
                if v.is_finite() {
                    lo[k] = if v < lo[k] { v } else { lo[k] };
                    hi[k] = if v > hi[k] { v } else { hi[k] };
                    sum[k] += v;
                    n[k] += 1;
                }
            }
        }
        for &v in lanes.remainder() {
            if v.is_finite() {
                lo[0] = lo[0].min(v);
                hi[0] = hi[0].max(v);
                sum[0] += v;
                n[0] += 1;
            }
        }
        let count: usize = n.iter().sum();
        if count == 0 {
            (f64::NAN, f64::NAN, f64::NAN)
        } else {
            let lo = lo.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = hi.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            (lo, hi, (sum[0] + sum[1] + (sum[2] + sum[3])) / count as f64)
        }
    }
}

/// A loaded log.
#[derive(Debug, Clone, PartialEq)]
pub struct Log {
    /// How it was written.
    pub dialect: Dialect,
    /// Whether its first record named the columns.
    pub header: bool,
    /// Its columns, in file order.
    pub columns: Vec<Column>,
    /// Rows (records after the header).
    pub rows: usize,
    /// The time column's index, if one was found.
    pub time_column: Option<usize>,
    /// The sample period: the median time step (in seconds), or the one given; `None` if
    /// neither.
    pub sample_period_s: Option<f64>,
    /// What was wrong, by line and column.
    pub problems: Vec<Problem>,
    /// Problems beyond [`MAX_LISTED_PROBLEMS`], counted only.
    pub problems_not_listed: usize,
    /// The file line (from 1) each row starts on.
    pub row_lines: Vec<u32>,
}

/// Per column while reading: numbers as they come, text cells interned.
#[derive(Debug, Default)]
struct ColumnBuilder {
    values: Vec<f64>,
    /// (row, label id) of every non-numeric, non-empty cell.
    text: Vec<(u32, u32)>,
    numbers: usize,
    empty: usize,
}

/// Reads a log from chunks of bytes.
///
/// ```
/// use cutlab::log::LogBuilder;
/// let mut builder = LogBuilder::new();
/// builder.push(b"time [s];I [A]\n0;1,5\n0,0");
/// builder.push(b"1;2,5\n");
/// let log = builder.finish(None);
/// assert_eq!(log.columns[1].values, [1.5, 2.5]);
/// assert_eq!(log.sample_period_s, Some(0.01));
/// ```
#[derive(Debug, Default)]
pub struct LogBuilder {
    reader: CsvReader,
    sink: Sink,
}

/// Everything but the reader, so the reader's callback can borrow it.
#[derive(Debug, Default)]
struct Sink {
    /// The first record, waiting for the second to say whether it is a header.
    first: Option<(usize, Vec<Vec<u8>>)>,
    names: Vec<String>,
    header: Option<bool>,
    columns: Vec<ColumnBuilder>,
    interned: std::collections::HashMap<String, u32>,
    label_names: Vec<String>,
    rows: usize,
    /// The line of each row, to report time problems by line.
    row_lines: Vec<u32>,
    problems: Vec<Problem>,
    problems_not_listed: usize,
    reported_utf8: bool,
    /// The file's size, when the caller knows it: the columns reserve their room once.
    expected_bytes: Option<u64>,
    reserved: bool,
}

/// Rows read before the columns reserve room for the whole file (when its size is known).
const ROWS_BEFORE_RESERVING: usize = 1000;

impl LogBuilder {
    /// A builder for a new file.
    pub fn new() -> Self {
        Self {
            reader: CsvReader::new(),
            sink: Sink::default(),
        }
    }

    /// A builder for a file of `bytes` bytes: once the first rows show how long a row is, the
    /// columns reserve room for all of them, so memory grows once instead of doubling.
    pub fn with_expected_bytes(bytes: u64) -> Self {
        let mut builder = Self::new();
        builder.sink.expected_bytes = Some(bytes);
        builder
    }

    /// Bytes taken so far.
    pub fn bytes_read(&self) -> u64 {
        self.reader.bytes_read()
    }

    /// Rows read so far.
    pub fn rows(&self) -> usize {
        self.sink.rows
    }

    /// Takes the next chunk of the file.
    pub fn push(&mut self, chunk: &[u8]) {
        let sink = &mut self.sink;
        self.reader.push(chunk, &mut |r| sink.record(&r));
        if !sink.reserved && sink.rows >= ROWS_BEFORE_RESERVING {
            sink.reserve(self.reader.bytes_read());
        }
    }

    /// Ends the file. `sample_period_s`, when given, is the period of a log without a time
    /// column (and overrides the time column's).
    pub fn finish(mut self, sample_period_s: Option<f64>) -> Log {
        let sink = &mut self.sink;
        self.reader.finish(&mut |r| sink.record(&r));
        let dialect = self.reader.dialect().unwrap_or(Dialect {
            delimiter: b',',
            decimal_comma: false,
        });
        // A file of one record: it is data if it is all numbers, else a header alone.
        if let Some((line, first)) = sink.first.take() {
            let numeric = first.iter().all(|f| {
                parse_number(f, dialect.decimal_comma).is_some() || f.trim_ascii().is_empty()
            });
            sink.start_columns(line, &first, !numeric);
            if numeric {
                sink.data(line, first.len(), dialect.decimal_comma, |i| {
                    Cell::Bytes(first.get(i).map_or(&[][..], Vec::as_slice))
                });
            }
        }
        for p in self.reader.take_problems() {
            sink.problem(p.line, None, p.message);
        }
        sink.finish(dialect, sample_period_s)
    }
}

impl Sink {
    fn problem(&mut self, line: usize, column: Option<String>, message: String) {
        if self.problems.len() < MAX_LISTED_PROBLEMS {
            self.problems.push(Problem {
                line,
                column,
                message,
            });
        } else {
            self.problems_not_listed += 1;
        }
    }

    /// Reserves room for the rows a file of the expected size holds, at the rate seen so far
    /// (and a little more).
    fn reserve(&mut self, bytes_read: u64) {
        self.reserved = true;
        let Some(total) = self.expected_bytes else {
            return;
        };
        if bytes_read == 0 {
            return;
        }
        let estimate = (self.rows as f64 * total as f64 / bytes_read as f64 * 1.02) as usize + 16;
        // A wild estimate (a file with a huge first line) must not reserve absurd amounts.
        let extra = estimate.saturating_sub(self.rows).min(1 << 28);
        self.row_lines.reserve_exact(extra);
        for c in &mut self.columns {
            c.values.reserve_exact(extra);
        }
    }

    /// Text from the file's bytes; bytes that are not UTF-8 are replaced, and the first time
    /// that happens it is reported.
    fn text(&mut self, bytes: &[u8], line: usize) -> String {
        match std::str::from_utf8(bytes) {
            Ok(t) => t.to_string(),
            Err(_) => {
                if !self.reported_utf8 {
                    self.reported_utf8 = true;
                    self.problem(
                        line,
                        None,
                        "bytes that are not UTF-8 were replaced (is the file Latin-1?)".into(),
                    );
                }
                String::from_utf8_lossy(bytes).into_owned()
            }
        }
    }

    fn record(&mut self, record: &RecordView<'_>) {
        let decimal_comma = record.dialect().decimal_comma;
        if self.header.is_none() {
            // The first record waits for the second: together they say whether it is a header.
            let Some((line, first)) = self.first.take() else {
                self.first = Some((record.line, record.fields().map(<[u8]>::to_vec).collect()));
                return;
            };
            let second: Vec<&[u8]> = record.fields().collect();
            let header = is_header(&first, &second, decimal_comma);
            self.start_columns(line, &first, header);
            if !header {
                self.data(line, first.len(), decimal_comma, |i| {
                    Cell::Bytes(first.get(i).map_or(&[][..], Vec::as_slice))
                });
            }
        }
        self.data(record.line, record.len(), decimal_comma, |i| record.cell(i));
    }

    /// Names the columns from the first record (a header) or by number.
    fn start_columns(&mut self, line: usize, first: &[Vec<u8>], header: bool) {
        self.header = Some(header);
        self.names = first
            .iter()
            .enumerate()
            .map(|(i, n)| {
                let name = self.text(n.trim_ascii(), line);
                if header && !name.is_empty() {
                    name
                } else {
                    format!("column {}", i + 1)
                }
            })
            .collect();
        self.columns = (0..self.names.len())
            .map(|_| ColumnBuilder::default())
            .collect();
    }

    /// One data row of `fields` fields, field `i` given by `cell(i)`.
    fn data<'a>(
        &mut self,
        line: usize,
        fields: usize,
        decimal_comma: bool,
        cell: impl Fn(usize) -> Cell<'a>,
    ) {
        let width = self.columns.len();
        if fields != width {
            self.problem(
                line,
                None,
                format!(
                    "{fields} fields where the header has {width}; {}",
                    if fields < width {
                        "the missing cells are gaps"
                    } else {
                        "the extra fields are ignored"
                    }
                ),
            );
        }
        let row = self.rows as u32;
        for c in 0..width {
            let cell = match if c < fields {
                cell(c)
            } else {
                Cell::Bytes(&[])
            } {
                Cell::Number(v) => {
                    let builder = &mut self.columns[c];
                    builder.values.push(v);
                    builder.numbers += 1;
                    continue;
                }
                Cell::Bytes(bytes) => bytes,
            };
            if let Some(v) = parse_number(cell, decimal_comma) {
                let builder = &mut self.columns[c];
                builder.values.push(v);
                builder.numbers += 1;
                continue;
            }
            let cell = cell.trim_ascii();
            if cell.is_empty() {
                let builder = &mut self.columns[c];
                builder.values.push(f64::NAN);
                builder.empty += 1;
                continue;
            }
            // Text: interned, so a label repeated a million times is stored once.
            let id = match std::str::from_utf8(cell)
                .ok()
                .and_then(|t| self.interned.get(t))
            {
                Some(&id) => id,
                None => {
                    let text = self.text(cell, line);
                    let next = self.label_names.len() as u32;
                    let id = *self.interned.entry(text.clone()).or_insert(next);
                    if id == next {
                        self.label_names.push(text);
                    }
                    id
                }
            };
            let builder = &mut self.columns[c];
            builder.values.push(f64::NAN);
            builder.text.push((row, id));
        }
        self.rows += 1;
        self.row_lines.push(line.min(u32::MAX as usize) as u32);
    }

    fn finish(&mut self, dialect: Dialect, sample_period_s: Option<f64>) -> Log {
        let builders = std::mem::take(&mut self.columns);
        let names = std::mem::take(&mut self.names);
        let mut columns = Vec::with_capacity(builders.len());
        for (name, b) in names.into_iter().zip(builders) {
            columns.push(self.column(name, b));
        }
        let time_column = columns.iter().position(|c| c.role == Some(Role::Time));
        let mut log = Log {
            dialect,
            header: self.header.unwrap_or(false),
            rows: self.rows,
            time_column,
            sample_period_s: None,
            columns,
            problems: Vec::new(),
            problems_not_listed: 0,
            row_lines: Vec::new(),
        };
        let period = time_column.and_then(|t| self.time_steps(&mut log.columns[t]));
        log.sample_period_s = sample_period_s
            .filter(|p| p.is_finite() && *p > 0.0)
            .or(period);
        log.problems = std::mem::take(&mut self.problems);
        log.problems_not_listed = self.problems_not_listed;
        log.row_lines = std::mem::take(&mut self.row_lines);
        log
    }

    /// A column from what was read: numeric if [`NUMERIC_SHARE`] of its non-empty cells are
    /// numbers (each other cell a reported gap), else text.
    fn column(&mut self, name: String, b: ColumnBuilder) -> Column {
        let filled = b.numbers + b.text.len();
        let numeric_share = if filled > 0 {
            b.numbers as f64 / filled as f64
        } else {
            0.0
        };
        let unit = unit_of(&name);
        let (kind, values, labels, label_names, missing) = if filled == 0 {
            (ColumnKind::Empty, b.values, Vec::new(), Vec::new(), b.empty)
        } else if numeric_share >= NUMERIC_SHARE {
            for &(row, id) in &b.text {
                let line = self.row_lines.get(row as usize).copied().unwrap_or(0) as usize;
                let text = self
                    .label_names
                    .get(id as usize)
                    .cloned()
                    .unwrap_or_default();
                self.problem(
                    line,
                    Some(name.clone()),
                    format!("{text:?} is not a number; kept as a gap"),
                );
            }
            (
                ColumnKind::Number,
                b.values,
                Vec::new(),
                Vec::new(),
                b.empty + b.text.len(),
            )
        } else {
            // Labels: numbers in a text column are labels too (a flag written 0/1 beside "ok").
            let mut local: Vec<String> = Vec::new();
            let mut map = std::collections::HashMap::new();
            let mut labels = vec![u32::MAX; b.values.len()];
            let mut text = b.text.iter().peekable();
            for (row, value) in b.values.iter().enumerate() {
                let label = match text.peek() {
                    Some(&&(r, id)) if r as usize == row => {
                        text.next();
                        self.label_names.get(id as usize).cloned()
                    }
                    _ if value.is_nan() => None,
                    _ => Some(crate::input::readable(*value)),
                };
                if let Some(label) = label {
                    let next = local.len() as u32;
                    let id = *map.entry(label.clone()).or_insert(next);
                    if id == next {
                        local.push(label);
                    }
                    labels[row] = id;
                }
            }
            (ColumnKind::Text, Vec::new(), labels, local, b.empty)
        };
        let role = guess_role(&name, unit.as_deref(), kind);
        Column {
            kind: if role == Some(Role::Time) && kind == ColumnKind::Number {
                ColumnKind::Time
            } else {
                kind
            },
            name,
            unit,
            role,
            values,
            labels,
            label_names,
            numeric_share,
            missing,
        }
    }

    /// Converts a time column to seconds (a unit or name in ms says milliseconds), and returns
    /// the median step; uneven steps and gaps are reported by line.
    fn time_steps(&mut self, column: &mut Column) -> Option<f64> {
        let unit = column.unit.as_deref().map(str::to_ascii_lowercase);
        let name = column.name.to_ascii_lowercase();
        let scale = match unit.as_deref() {
            Some("ms") => 1e-3,
            Some("us" | "µs" | "μs") => 1e-6,
            Some(_) => 1.0,
            None if name.contains("ms") => 1e-3,
            None if name.contains("us") && !name.contains("s_") => 1e-6,
            None => 1.0,
        };
        if scale != 1.0 {
            for v in &mut column.values {
                *v *= scale;
            }
            column.unit = Some(if scale == 1e-3 { "ms" } else { "µs" }.into());
        }
        // The median step (in linear time: a million-row log would spend a tenth of its load
        // sorting otherwise).
        let median = crate::signal::stats::median(column.values.windows(2).map(|w| w[1] - w[0]));
        if median.is_nan() {
            return None;
        }
        // Nothing says the unit and the usual step is a second or more: no machine log samples
        // that slowly (the slowest ones log at 10 Hz), but a DAQ's counter of milliseconds does.
        let mut median = median;
        if scale == 1.0 && unit.is_none() && median >= 1.0 && !name.contains("sec") {
            for v in &mut column.values {
                *v *= 1e-3;
            }
            median *= 1e-3;
            column.unit = Some("ms".into());
            self.problem(
                1,
                Some(column.name.clone()),
                format!(
                    "the time column gives no unit and steps by {}: read as milliseconds \
                     (write \"[s]\" in its name if they are seconds)",
                    crate::input::readable(median * 1e3)
                ),
            );
        }
        if median <= 0.0 {
            self.problem(
                0,
                Some(column.name.clone()),
                "the time column does not increase; no sample period from it".into(),
            );
            return None;
        }
        let mut uneven = 0;
        let steps = column
            .values
            .windows(2)
            .enumerate()
            .map(|(i, w)| (i + 1, w[1] - w[0]));
        for (row, d) in steps {
            if !d.is_finite() {
                continue;
            }
            let line = self.row_lines.get(row).copied().unwrap_or(0) as usize;
            if d > 1.5 * median {
                self.problem(
                    line,
                    Some(column.name.clone()),
                    format!(
                        "a gap of {} s in time (the usual step is {} s)",
                        crate::input::readable(d),
                        crate::input::readable(median)
                    ),
                );
            } else if (d - median).abs() > 0.1 * median {
                uneven += 1;
                if uneven <= 10 {
                    self.problem(
                        line,
                        Some(column.name.clone()),
                        format!(
                            "an uneven time step of {} s (the usual step is {} s)",
                            crate::input::readable(d),
                            crate::input::readable(median)
                        ),
                    );
                }
            }
        }
        // Time stamps are written to a few digits: 0.0009999999999998899 is the log's 1 ms.
        Some(format!("{median:.11e}").parse().unwrap_or(median))
    }
}

/// Whether `first` names the columns: it has a non-empty cell that is not a number where the
/// second record has a number, or every cell is text while the second record has a number.
fn is_header(first: &[Vec<u8>], second: &[&[u8]], decimal_comma: bool) -> bool {
    let number = |f: &[u8]| parse_number(f, decimal_comma).is_some();
    let text = |f: &[u8]| !f.trim_ascii().is_empty() && !number(f);
    first.iter().zip(second).any(|(a, b)| text(a) && number(b))
        || (first.iter().all(|f| text(f)) && second.iter().any(|f| number(f)))
}

/// The unit in a column name: `Current [A]`, `speed(rpm)`, `F / N`.
///
/// ```
/// use cutlab::log::unit_of;
/// assert_eq!(unit_of("Current [A]").as_deref(), Some("A"));
/// assert_eq!(unit_of("speed(rpm)").as_deref(), Some("rpm"));
/// assert_eq!(unit_of("I_A"), None);
/// ```
pub fn unit_of(name: &str) -> Option<String> {
    let name = name.trim();
    for (open, close) in [('[', ']'), ('(', ')'), ('{', '}')] {
        if let (Some(a), Some(b)) = (name.rfind(open), name.rfind(close)) {
            if a < b && b == name.len() - 1 {
                let unit = name[a + 1..b].trim();
                if !unit.is_empty() {
                    return Some(unit.to_string());
                }
            }
        }
    }
    name.rsplit_once(" / ")
        .map(|(_, u)| u.trim().to_string())
        .filter(|u| !u.is_empty() && !u.contains(' '))
}

/// A role from a column's name and unit (docs/logs.md lists the rules).
///
/// ```
/// use cutlab::log::{guess_role, ColumnKind, Role};
/// assert_eq!(guess_role("Time [s]", Some("s"), ColumnKind::Number), Some(Role::Time));
/// assert_eq!(guess_role("S_speed(rpm)", Some("rpm"), ColumnKind::Number), Some(Role::SpindleSpeed));
/// assert_eq!(guess_role("X_I_U", None, ColumnKind::Number), Some(Role::PhaseCurrent));
/// assert_eq!(guess_role("Z_Current [A]", Some("A"), ColumnKind::Number), Some(Role::RmsCurrent));
/// assert_eq!(guess_role("Fx [N]", Some("N"), ColumnKind::Number), Some(Role::Force));
/// assert_eq!(guess_role("Phase", None, ColumnKind::Text), Some(Role::Label));
/// ```
pub fn guess_role(name: &str, unit: Option<&str>, kind: ColumnKind) -> Option<Role> {
    if kind == ColumnKind::Text {
        return Some(Role::Label);
    }
    if kind == ColumnKind::Empty {
        return None;
    }
    let base = name
        .split(['[', '(', '{'])
        .next()
        .unwrap_or_default()
        .trim()
        .to_ascii_lowercase();
    // Axis prefixes: X_, Y_, Z_, S_ (spindle).
    let (axis, stem) = match base.split_once('_') {
        Some((a, rest)) if matches!(a, "x" | "y" | "z" | "s" | "sp") => {
            (Some(a.to_string()), rest.to_string())
        }
        _ => (None, base.clone()),
    };
    let unit = unit.map(str::to_ascii_lowercase);
    let words = |list: &[&str]| {
        list.iter().any(|w| {
            stem == *w || stem.starts_with(&format!("{w}_")) || stem.starts_with(&format!("{w} "))
        })
    };
    if words(&["time", "t", "timestamp", "zeit", "time_s", "time_ms"])
        || matches!(unit.as_deref(), Some("s" | "ms" | "sec"))
            && (stem.contains("time") || stem == "t")
    {
        return Some(Role::Time);
    }
    let phase = [
        "i_u", "i_v", "i_w", "iu", "iv", "iw", "i_a", "i_b", "i_c", "ia", "ib", "ic",
    ];
    if phase.contains(&stem.as_str()) || stem.starts_with("phase") {
        return Some(Role::PhaseCurrent);
    }
    if stem.contains("speed")
        || stem.contains("rpm")
        || unit.as_deref() == Some("rpm")
        || (axis.as_deref() == Some("s") && stem.starts_with('n'))
    {
        return Some(if axis.as_deref().is_some_and(|a| a != "s" && a != "sp") {
            Role::Feed
        } else {
            Role::SpindleSpeed
        });
    }
    if stem.contains("feed") || matches!(unit.as_deref(), Some("mm/min" | "m/min" | "mm/s")) {
        return Some(Role::Feed);
    }
    if stem.contains("current")
        || stem.contains("curr")
        || stem == "i"
        || stem.starts_with("i_rms")
        || stem.contains("load")
        || unit.as_deref() == Some("a")
    {
        return Some(Role::RmsCurrent);
    }
    if stem.contains("force")
        || stem.starts_with('f') && unit.as_deref() == Some("n")
        || unit.as_deref() == Some("n")
    {
        return Some(Role::Force);
    }
    if stem.contains("depth") || stem == "doc" || stem == "ap" {
        return Some(Role::Depth);
    }
    None
}

/// Loads a whole file in memory at once (the command line; the browser pushes chunks).
pub fn load(bytes: &[u8], sample_period_s: Option<f64>) -> Log {
    let mut builder = LogBuilder::new();
    for chunk in bytes.chunks(1 << 16) {
        builder.push(chunk);
    }
    builder.finish(sample_period_s)
}
