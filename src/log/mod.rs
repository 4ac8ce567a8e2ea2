//! Engineers' logs as they are: a messy CSV file in, columns out.
//!
//! ```text
//! bytes (chunks) ─► csv::CsvReader (encoding, dialect, quotes, BOM, CRLF or CR) ─► records
//!   ─► LogBuilder (preamble and header, numbers or labels per column, problems by line and column)
//!   ─► Log (columns, units, time column in seconds and sample period, role guesses and why,
//!           an account of every line and cell not read as data)
//! ```
//!
//! Numbers are stored as one `Vec<f64>` per column and text as interned labels; nothing of the
//! text is kept after a record is read, so memory follows the numbers, not the file. A damaged
//! line (too few or too many fields, text in a numeric column, a line of delimiters only) is
//! reported by line and column and kept as gaps (NaN); the rest of the file loads. Nothing is
//! dropped without a count: [`ReadAccount`] says where every line of the file went (rows, the
//! header, a preamble, blank lines) and how many cells were not read as numbers. What cannot be
//! read without guessing — UTF-16 or UTF-32 text, a quote that swallows the lines after it — is
//! refused with a [`ReadError`]. docs/logs.md describes the rules.
//!
//! NaN and ±∞ in a numeric column (written as such, or a number beyond a double's range) are
//! kept as values, counted per column ([`Column::not_finite`]) and left out of statistics, which
//! say how many values they left out.
//!
//! | file | what |
//! |---|---|
//! | this file | [`Log`]: the builder that reads a file's records into columns, and what it could not read |
//! | [`csv`] | the incremental reader of messy CSV: encodings, dialects, quotes, line ends |
//! | [`analysis`] | the signal chain on a log's columns: statistics whole and per label, filtering, spectra |
//! | [`names`] | what a column's name and unit say: its words, unit, time unit and likely role |
//! | [`mapping`] | which column is which signal of the machine, guessed and edited |
//! | [`machine`] | a log as a machine, and what the run's settings need to know about it |
//! | [`replay`] | controllers replayed on a log through the lab's closed loop |
//! | [`calibration`] | calibration from a recorded log: the teach cut over the log |
//! | [`period_log`] | calibration from a log whose rows are control periods (`cutlab calibrate`, logged teach-in) |
//! | [`settings`] | the settings of a log's analysis as one table (Logs page fields, CLI options) |
//! | [`link`] | the Logs page's state in its URL (sample, mapping, analysed column, replay form), read by the page and by lessons |
//! | [`transfer`] | the Logs page's replays sent to a computation worker and back |
//! | [`trial_cuts`] | a shop's own trial cuts as a table (conditions and a monitor's force), what paper 004's network learns from |

pub mod analysis;
pub mod calibration;
pub mod csv;
pub mod link;
pub mod machine;
pub mod mapping;
pub mod names;
pub mod period_log;
pub mod replay;
pub mod settings;
pub mod transfer;
pub mod trial_cuts;

use serde::{Deserialize, Serialize};

use crate::input::{excerpt, readable};
use csv::{parse_number, Cell, CsvReader, Dialect, RecordView};
pub use names::{
    clearly_negative, guess_role, guess_role_from, name_words, time_scale, unit_of, Role,
};

/// A column with at least this share of numbers (among its non-empty cells) is numeric; its
/// other cells are gaps, each reported. Below it the column is text (labels).
pub const NUMERIC_SHARE: f64 = 0.75;
/// At most this many problems are listed one by one; the rest are counted.
pub const MAX_LISTED_PROBLEMS: usize = 200;
/// How many records are read before deciding which of them is the header (a preamble, comment
/// lines or a damaged line must not turn the header into data).
const HEADER_LOOKAHEAD: usize = 20;

/// What a column holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
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

/// One problem, by line and (where it is one cell's) column.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LineProblem {
    /// The line in the file (1-based).
    pub line: usize,
    /// The column's name, when the problem is one cell's.
    pub column: Option<String>,
    /// What is wrong, and what was done about it.
    pub message: String,
}

/// Why a file is not read at all: bytes that are no text this reader decodes (UTF-16, UTF-32,
/// zero bytes) or a quote that swallows the lines after it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReadError {
    /// The line where it shows (1-based; 0 for a file with no line at all).
    pub line: usize,
    /// What is wrong, and what to do.
    pub message: String,
}

impl std::fmt::Display for ReadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.line == 0 {
            // No line to point at (an empty file).
            return write!(f, "{}", self.message);
        }
        write!(f, "line {}: {}", self.line, self.message)
    }
}

impl std::error::Error for ReadError {}

/// Where every line of a file went, and what was not read as data, counted. The lines add up:
/// `lines == header_lines + preamble_lines + blank_lines + row_lines`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct ReadAccount {
    /// Bytes in the file.
    pub bytes: u64,
    /// Lines in the file.
    pub lines: usize,
    /// Lines of the header (more than one when a quoted name holds a line break; 0 without one).
    pub header_lines: usize,
    /// Lines before the header skipped as a preamble or comments (`# …`, `Machine: DMU 50`).
    pub preamble_lines: usize,
    /// The first of them (0 if none).
    pub first_preamble_line: usize,
    /// Blank lines, skipped.
    pub blank_lines: usize,
    /// The first of them (0 if none).
    pub first_blank_line: usize,
    /// Lines of the rows (more than the rows when a quoted cell holds a line break).
    pub row_lines: usize,
    /// Cells of the rows: rows × columns.
    pub cells: usize,
    /// Empty cells (gaps), the ones short rows lack included.
    pub empty_cells: usize,
    /// Cells short rows lack (gaps, among the empty ones).
    pub short_cells: usize,
    /// Fields beyond the header's width, not read.
    pub extra_cells: usize,
    /// Text in a numeric column (gaps).
    pub text_cells: usize,
    /// Numbers that are not finite: NaN, ±∞, beyond a double's range (kept, left out of
    /// statistics).
    pub not_finite_cells: usize,
    /// Rows of only delimiters (every cell a gap).
    pub empty_rows: usize,
    /// Bytes of names and labels that are not UTF-8, replaced.
    pub bytes_not_utf8: usize,
    /// Whether the lines end with a lone CR (read as line feeds).
    pub cr_line_ends: bool,
}

impl ReadAccount {
    /// What was not read as data, as sentences for people (none when everything was).
    ///
    /// ```
    /// let text = b"# exported\nt [s],I [A]\n0,1\n\n0.1,x\n0.2,3,4\n0.3,4\n0.4,5\n";
    /// let log = cutlab::log::load(text, None).unwrap();
    /// assert_eq!(log.account.unread(), [
    ///     "1 line before the header skipped as a preamble or comments (from line 1)",
    ///     "1 blank line skipped (first: line 4)",
    ///     "1 cell of text in a numeric column, kept as gaps",
    ///     "1 field beyond the header's columns, not read",
    /// ]);
    /// ```
    pub fn unread(&self) -> Vec<String> {
        let gaps = self.empty_cells - self.short_cells.min(self.empty_cells);
        let preamble = format!(
            "before the header skipped as a preamble or comments (from line {})",
            self.first_preamble_line
        );
        let blank = format!("skipped (first: line {})", self.first_blank_line);
        // (count, the thing and its plural, what became of them)
        let counts: [(usize, &str, &str, &str); 9] = [
            (self.preamble_lines, "line", "lines", &preamble),
            (self.blank_lines, "blank line", "blank lines", &blank),
            (
                self.empty_rows,
                "row",
                "rows",
                "of only delimiters, kept as gaps",
            ),
            (gaps, "empty cell", "empty cells", "(gaps)"),
            (
                self.short_cells,
                "cell",
                "cells",
                "missing from short rows (gaps)",
            ),
            (
                self.text_cells,
                "cell",
                "cells",
                "of text in a numeric column, kept as gaps",
            ),
            (
                self.not_finite_cells,
                "number",
                "numbers",
                "not finite (NaN, ±inf or beyond ±1.8e308), left out of statistics",
            ),
            (
                self.extra_cells,
                "field",
                "fields",
                "beyond the header's columns, not read",
            ),
            (
                self.bytes_not_utf8,
                "byte",
                "bytes",
                "of names or labels not UTF-8, replaced",
            ),
        ];
        counts
            .iter()
            .filter(|(n, ..)| *n > 0)
            .map(|&(n, one, many, what)| format!("{n} {} {what}", if n == 1 { one } else { many }))
            .collect()
    }
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
    /// What the guess rests on (`the unit "A"`, `the word "current"`), or why there is none
    /// where a guess was refused.
    pub role_reason: Option<String>,
    /// One value per row (NaN for a gap); empty for a text column. A time column is in seconds.
    pub values: Vec<f64>,
    /// One label id per row for a text column (`u32::MAX` for an empty cell).
    pub labels: Vec<u32>,
    /// The distinct labels, by id.
    pub label_names: Vec<String>,
    /// Numbers among the non-empty cells, 0–1.
    pub numeric_share: f64,
    /// Empty or unreadable cells.
    pub missing: usize,
    /// Numbers that are not finite (NaN, ±∞, beyond a double's range): kept as values, left out
    /// of statistics.
    pub not_finite: usize,
}

impl Column {
    /// Smallest, largest and mean of the finite values (NaN when there are none). The mean
    /// cannot overflow: a column of 1e308 has the mean 1e308.
    ///
    /// ```
    /// let log = cutlab::log::load(b"a\n1e308\n1e308\nNaN\n", None).unwrap();
    /// assert_eq!(log.columns[0].min_max_mean(), (1e308, 1e308, 1e308));
    /// ```
    pub fn min_max_mean(&self) -> (f64, f64, f64) {
        let s = analysis::Stats::of(&self.values, None);
        (
            s.min.unwrap_or(f64::NAN),
            s.max.unwrap_or(f64::NAN),
            s.mean.unwrap_or(f64::NAN),
        )
    }
}

/// A loaded log.
#[derive(Debug, Clone, PartialEq)]
pub struct Log {
    /// How it was written.
    pub dialect: Dialect,
    /// Whether a record named the columns.
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
    pub problems: Vec<LineProblem>,
    /// Problems beyond [`MAX_LISTED_PROBLEMS`], counted only.
    pub problems_not_listed: usize,
    /// The file line (from 1) each row starts on.
    pub row_lines: Vec<u32>,
    /// Where every line went, and what was not read as data.
    pub account: ReadAccount,
}

impl Log {
    /// Why the log has no sample period, for a message that asks for one ("it has no time
    /// column", "its time column \"t\" does not increase"); `None` when it has one.
    ///
    /// ```
    /// let log = cutlab::log::load(b"t [s],I\n1,5\n1,6\n", None).unwrap();
    /// assert_eq!(log.period_unknown().as_deref(), Some("its time column \"t [s]\" does not increase"));
    /// ```
    pub fn period_unknown(&self) -> Option<String> {
        if self.sample_period_s.is_some() {
            return None;
        }
        Some(match self.time_column.and_then(|t| self.columns.get(t)) {
            None => "it has no time column".to_string(),
            Some(t) if t.values.iter().filter(|v| v.is_finite()).count() < 2 => {
                format!("its time column {:?} has fewer than two times", t.name)
            }
            Some(t) => format!("its time column {:?} does not increase", t.name),
        })
    }
}

/// Per column while reading: numbers as they come, text cells interned.
#[derive(Debug, Default)]
struct ColumnBuilder {
    values: Vec<f64>,
    /// (row, label id) of every non-numeric, non-empty cell.
    text: Vec<(u32, u32)>,
    numbers: usize,
    empty: usize,
    /// Numbers that are not finite, and the row of the first.
    not_finite: usize,
    first_not_finite_row: u32,
}

/// Reads a log from chunks of bytes.
///
/// ```
/// use cutlab::log::LogBuilder;
/// let mut builder = LogBuilder::new();
/// builder.push(b"time [s];I [A]\n0;1,5\n0,0");
/// builder.push(b"1;2,5\n");
/// let log = builder.finish(None).unwrap();
/// assert_eq!(log.columns[1].values, [1.5, 2.5]);
/// assert_eq!(log.sample_period_s, Some(0.01));
/// ```
#[derive(Debug, Default)]
pub struct LogBuilder {
    reader: CsvReader,
    sink: RecordSink,
}

/// One of the first records, held until the header is found.
#[derive(Debug)]
struct Held {
    line: usize,
    lines: usize,
    fields: Vec<Vec<u8>>,
}

impl Held {
    fn of(record: &RecordView<'_>) -> Self {
        Self {
            line: record.line,
            lines: record.lines,
            fields: record.fields().map(<[u8]>::to_vec).collect(),
        }
    }

    /// A comment line: its first field starts with `#` or `//`.
    fn comment(&self) -> bool {
        self.fields.first().is_some_and(|f| {
            let t = f.trim_ascii();
            t.starts_with(b"#") || t.starts_with(b"//")
        })
    }
}

/// Everything but the reader, so the reader's callback can borrow it.
#[derive(Debug, Default)]
struct RecordSink {
    /// The first records, held until [`HEADER_LOOKAHEAD`] of them say which is the header.
    held: Vec<Held>,
    names: Vec<String>,
    header: Option<bool>,
    /// The header's line (the first row's when there is none).
    header_line: usize,
    columns: Vec<ColumnBuilder>,
    interned: std::collections::HashMap<String, u32>,
    label_names: Vec<String>,
    rows: usize,
    /// The line of each row, to report time problems by line.
    row_lines: Vec<u32>,
    problems: Vec<LineProblem>,
    problems_not_listed: usize,
    account: ReadAccount,
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
            sink: RecordSink::default(),
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

    /// Why the file will not be read, once that is known (its first bytes, a runaway quote): a
    /// caller streaming a big file can stop there.
    pub fn refused(&self) -> Option<ReadError> {
        self.reader.refused().map(|p| ReadError {
            line: p.line,
            message: p.message.clone(),
        })
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
    /// column (and overrides the time column's). A file this reader cannot read without
    /// guessing is an error that says where and why.
    pub fn finish(mut self, sample_period_s: Option<f64>) -> Result<Log, ReadError> {
        {
            let sink = &mut self.sink;
            self.reader.finish(&mut |r| sink.record(&r));
        }
        if let Some(refused) = self.refused() {
            return Err(refused);
        }
        let sink = &mut self.sink;
        let dialect = self.reader.dialect().unwrap_or(Dialect {
            delimiter: b',',
            decimal_comma: false,
        });
        if sink.header.is_none() {
            sink.start(dialect);
        }
        for p in self.reader.take_problems() {
            sink.problem(p.line, None, p.message);
        }
        let (blank, first_blank) = self.reader.blank_lines();
        sink.account.blank_lines = blank;
        sink.account.first_blank_line = first_blank;
        sink.account.lines = self.reader.lines_read();
        sink.account.bytes = self.reader.bytes_read();
        sink.account.cr_line_ends = self.reader.cr_line_ends();
        let log = sink.finish(dialect, sample_period_s);
        if log.rows == 0 {
            return Err(no_data_rows(&log));
        }
        Ok(log)
    }
}

impl RecordSink {
    fn problem(&mut self, line: usize, column: Option<String>, message: String) {
        if self.problems.len() < MAX_LISTED_PROBLEMS {
            self.problems.push(LineProblem {
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

    /// Text from the file's bytes; bytes that are not UTF-8 are replaced and counted, and the
    /// first time that happens it is reported.
    fn text(&mut self, bytes: &[u8], line: usize) -> String {
        match std::str::from_utf8(bytes) {
            Ok(t) => t.to_string(),
            Err(_) => {
                let bad: usize = bytes.utf8_chunks().map(|c| c.invalid().len()).sum();
                if self.account.bytes_not_utf8 == 0 {
                    self.problem(
                        line,
                        None,
                        "bytes that are not UTF-8 were replaced (is the file Latin-1?)".into(),
                    );
                }
                self.account.bytes_not_utf8 += bad;
                String::from_utf8_lossy(bytes).into_owned()
            }
        }
    }

    fn record(&mut self, record: &RecordView<'_>) {
        if self.header.is_none() {
            // The first records wait: together they say which of them is the header.
            self.held.push(Held::of(record));
            if self.held.len() >= HEADER_LOOKAHEAD {
                self.start(record.dialect());
            }
            return;
        }
        let decimal_comma = record.dialect().decimal_comma;
        self.data(
            record.line,
            record.lines,
            record.len(),
            decimal_comma,
            |i| record.cell(i),
        );
    }

    /// Finds the header among the held records, names the columns and reads the held rows.
    ///
    /// Comment lines (`#`, `//`) at the start are skipped. The columns are as many as most
    /// records have fields; the first record of that width is the header when it has text
    /// where most records after it have numbers (or is all text above records with numbers).
    /// With a header, every record before it is a preamble, skipped and counted; a record just
    /// before the data that is all text when split at another delimiter is a header written
    /// with that delimiter. Without a header, the records are all rows.
    fn start(&mut self, dialect: Dialect) {
        let held = std::mem::take(&mut self.held);
        let decimal_comma = dialect.decimal_comma;
        let leading_comments = held.iter().take_while(|h| h.comment()).count();
        let rest = &held[leading_comments..];
        // The usual width: the most common field count (the larger on a tie).
        let mut counts: Vec<(usize, usize)> = Vec::new();
        for h in rest {
            match counts.iter_mut().find(|(n, _)| *n == h.fields.len()) {
                Some((_, k)) => *k += 1,
                None => counts.push((h.fields.len(), 1)),
            }
        }
        let width = counts
            .iter()
            .max_by_key(|(n, k)| (*k, *n))
            .map_or(0, |(n, _)| *n);
        let first = rest.iter().position(|h| h.fields.len() == width);
        let (header_at, names) = match first {
            Some(c) => {
                let following: Vec<&[Vec<u8>]> = rest[c + 1..]
                    .iter()
                    .filter(|h| h.fields.len() == width)
                    .map(|h| h.fields.as_slice())
                    .collect();
                if is_header(&rest[c].fields, &following, decimal_comma) {
                    (Some(c), Some(rest[c].fields.clone()))
                } else {
                    match c.checked_sub(1).and_then(|b| {
                        other_delimiter_header(&rest[b].fields, dialect.delimiter, width)
                            .map(|(names, d)| (b, names, d))
                    }) {
                        Some((b, names, delimiter)) => {
                            self.problem(
                                rest[b].line,
                                None,
                                format!(
                                    "the header is delimited by {} where the data uses {}: its \
                                     names are split at {}",
                                    delimiter_name(delimiter),
                                    dialect.delimiter_name(),
                                    delimiter_name(delimiter)
                                ),
                            );
                            (Some(b), Some(names))
                        }
                        None => (None, None),
                    }
                }
            }
            None => (None, None),
        };
        // Skipped: the leading comments always, and with a header everything before it.
        let skipped = leading_comments + header_at.unwrap_or(0);
        for h in &held[..skipped] {
            self.account.preamble_lines += h.lines;
        }
        if let Some(first) = held.first().filter(|_| skipped > 0) {
            self.account.first_preamble_line = first.line;
        }
        let data_from = match header_at {
            Some(c) => leading_comments + c + 1,
            None => leading_comments,
        };
        let header_record = header_at.map(|c| &held[leading_comments + c]);
        self.header = Some(header_record.is_some());
        self.header_line = header_record
            .map(|h| h.line)
            .or(held.get(data_from).map(|h| h.line))
            .unwrap_or(1);
        if let Some(h) = header_record {
            self.account.header_lines = h.lines;
        }
        let names = names.unwrap_or_default();
        let line = self.header_line;
        self.names = (0..width)
            .map(|i| {
                let name = names
                    .get(i)
                    .map(|n| self.text(n.trim_ascii(), line))
                    .unwrap_or_default();
                if name.is_empty() {
                    format!("column {}", i + 1)
                } else {
                    name
                }
            })
            .collect();
        self.columns = (0..width).map(|_| ColumnBuilder::default()).collect();
        for h in &held[data_from..] {
            self.data(h.line, h.lines, h.fields.len(), decimal_comma, |i| {
                Cell::Bytes(h.fields.get(i).map_or(&[][..], Vec::as_slice))
            });
        }
    }

    /// One data row of `fields` fields, field `i` given by `cell(i)`, starting on `line` and
    /// spanning `lines`.
    fn data<'a>(
        &mut self,
        line: usize,
        lines: usize,
        fields: usize,
        decimal_comma: bool,
        cell: impl Fn(usize) -> Cell<'a>,
    ) {
        let width = self.columns.len();
        self.account.row_lines += lines;
        if fields != width {
            if fields < width {
                self.account.short_cells += width - fields;
            } else {
                self.account.extra_cells += fields - width;
            }
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
        let mut empty = 0;
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
                if !v.is_finite() {
                    if builder.not_finite == 0 {
                        builder.first_not_finite_row = row;
                    }
                    builder.not_finite += 1;
                }
                builder.values.push(v);
                builder.numbers += 1;
                continue;
            }
            let cell = cell.trim_ascii();
            if cell.is_empty() {
                let builder = &mut self.columns[c];
                builder.values.push(f64::NAN);
                builder.empty += 1;
                empty += 1;
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
        if width > 0 && empty == width {
            self.account.empty_rows += 1;
            self.problem(
                line,
                None,
                "every cell is empty (a line of delimiters only); kept as a row of gaps".into(),
            );
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
        self.account.cells = self.rows * columns.len();
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
            account: ReadAccount::default(),
        };
        let period = time_column.and_then(|t| self.time_steps(&mut log.columns[t]));
        log.sample_period_s = sample_period_s
            .filter(|p| p.is_finite() && *p > 0.0)
            .or(period);
        log.problems = std::mem::take(&mut self.problems);
        log.problems_not_listed = self.problems_not_listed;
        log.row_lines = std::mem::take(&mut self.row_lines);
        log.account = self.account;
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
        self.account.empty_cells += b.empty;
        let mut not_finite = 0;
        let (kind, values, labels, label_names, missing) = if filled == 0 {
            (ColumnKind::Empty, b.values, Vec::new(), Vec::new(), b.empty)
        } else if numeric_share >= NUMERIC_SHARE {
            self.account.text_cells += b.text.len();
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
                    format!("{} is not a number; kept as a gap", excerpt(&text)),
                );
            }
            if b.not_finite > 0 {
                not_finite = b.not_finite;
                self.account.not_finite_cells += b.not_finite;
                let line = self
                    .row_lines
                    .get(b.first_not_finite_row as usize)
                    .copied()
                    .unwrap_or(0) as usize;
                self.problem(
                    line,
                    Some(name.clone()),
                    format!(
                        "{} not finite (NaN, ±inf or beyond ±1.8e308), the first here: kept, \
                         and left out of statistics",
                        if b.not_finite == 1 {
                            "1 number is".to_string()
                        } else {
                            format!("{} numbers are", b.not_finite)
                        }
                    ),
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
                    // Every digit: two numbers must never become one label.
                    _ => Some(number_label(*value)),
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
        let mut guess = guess_role_from(&name, unit.as_deref(), kind)
            .map(|(role, why)| (Some(role), Some(why)));
        if let Some((Some(Role::Time), _)) = guess {
            if let Err(other) = time_scale(unit.as_deref(), &name) {
                let why = format!(
                    "a time name, but {other:?} is no time unit this reader converts (s, ms, \
                     µs, ns, min, h): not used as the time axis"
                );
                self.problem(self.header_line, Some(name.clone()), why.clone());
                guess = Some((None, Some(why)));
            }
        }
        if let Some((Some(Role::RmsCurrent), Some(why))) = &guess {
            if let Some(lowest) = clearly_negative(&values) {
                guess = Some((
                    Some(Role::PhaseCurrent),
                    Some(format!(
                        "{why}, but it swings down to {}: an RMS is never negative, so a phase \
                         current",
                        readable(lowest)
                    )),
                ));
            }
        }
        let (role, role_reason) = guess.unwrap_or((None, None));
        Column {
            kind: if role == Some(Role::Time) && kind == ColumnKind::Number {
                ColumnKind::Time
            } else {
                kind
            },
            name,
            unit,
            role,
            role_reason,
            values,
            labels,
            label_names,
            numeric_share,
            missing,
            not_finite,
        }
    }

    /// Converts a time column to seconds (its unit, or a unit word ending its name, says which:
    /// s, ms, µs, ns, min, h), and returns the median step; uneven steps and gaps are reported
    /// by line.
    fn time_steps(&mut self, column: &mut Column) -> Option<f64> {
        let scale = time_scale(column.unit.as_deref(), &column.name)
            .ok()
            .flatten();
        if let Some((seconds, symbol)) = scale {
            if seconds != 1.0 {
                for v in &mut column.values {
                    *v *= seconds;
                }
                column.unit = Some(symbol.into());
            }
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
        if scale.is_none() && median >= 1.0 {
            for v in &mut column.values {
                *v *= 1e-3;
            }
            median *= 1e-3;
            column.unit = Some("ms".into());
            self.problem(
                self.header_line,
                Some(column.name.clone()),
                format!(
                    "the time column gives no unit and steps by {}: read as milliseconds \
                     (write \"[s]\" in its name if they are seconds)",
                    readable(median * 1e3)
                ),
            );
        }
        if median <= 0.0 {
            // Said at the first step that does not go forward.
            let row = column
                .values
                .windows(2)
                .position(|w| w[1] - w[0] <= 0.0)
                .map_or(0, |i| i + 1);
            let line = self
                .row_lines
                .get(row)
                .map_or(self.header_line, |&l| l as usize);
            self.problem(
                line,
                Some(column.name.clone()),
                "the time column does not increase (its usual step is not positive); no \
                 sample period from it"
                    .into(),
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
                        readable(d),
                        readable(median)
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
                            readable(d),
                            readable(median)
                        ),
                    );
                }
            }
        }
        // Time stamps are written to a few digits: 0.0009999999999998899 is the log's 1 ms.
        Some(format!("{median:.11e}").parse().unwrap_or(median))
    }
}

/// A number in a text column as its label: every digit (the shortest text that reads back as
/// the same number), with an exponent where plain digits would run long.
fn number_label(v: f64) -> String {
    let plain = format!("{v}");
    if plain.len() <= 24 {
        plain
    } else {
        format!("{v:e}")
    }
}

fn delimiter_name(delimiter: u8) -> &'static str {
    Dialect {
        delimiter,
        decimal_comma: false,
    }
    .delimiter_name()
}

/// The names of a record when it is split at another delimiter than the file's (a header written
/// with `;` above data written with `,`): `Some` when that gives `width` fields of text, none a
/// number.
fn other_delimiter_header(
    fields: &[Vec<u8>],
    delimiter: u8,
    width: usize,
) -> Option<(Vec<Vec<u8>>, u8)> {
    if width < 2 || fields.len() == width {
        return None;
    }
    let joined = fields.join(&delimiter);
    let text = String::from_utf8_lossy(&joined);
    [b',', b';', b'\t']
        .into_iter()
        .filter(|&d| d != delimiter)
        .find_map(|d| {
            let names = csv::split_fields(&text, d);
            let all_text = names
                .iter()
                .all(|n| !n.trim().is_empty() && parse_number(n.as_bytes(), false).is_none());
            (names.len() == width && all_text)
                .then(|| (names.into_iter().map(String::into_bytes).collect(), d))
        })
}

/// Whether `first` names the columns, given the records of its width that follow: it has text
/// (a non-empty cell that is not a number) in a column where most of them have numbers, or it is
/// all text while one of them has a number. A file of one record: it names the columns when none
/// of its cells is a number.
fn is_header(first: &[Vec<u8>], following: &[&[Vec<u8>]], decimal_comma: bool) -> bool {
    let number = |f: &[u8]| parse_number(f, decimal_comma).is_some();
    let text = |f: &[u8]| !f.trim_ascii().is_empty() && !number(f);
    let all_text = first.iter().any(|f| text(f)) && !first.iter().any(|f| number(f));
    if following.is_empty() {
        return all_text;
    }
    let numbers_below = |c: usize| {
        following
            .iter()
            .filter(|r| r.get(c).is_some_and(|f| number(f)))
            .count()
    };
    first
        .iter()
        .enumerate()
        .any(|(c, a)| text(a) && 2 * numbers_below(c) > following.len())
        || (all_text && following.iter().any(|r| r.iter().any(|f| number(f))))
}

/// Why a log without data rows is refused: there is nothing to map, analyse, calibrate or
/// replay. Says what the file held instead.
fn no_data_rows(log: &Log) -> ReadError {
    let lines = log.account.lines;
    let message = if log.account.bytes == 0 {
        "the file is empty: a log needs a line of values (after an optional header)".to_string()
    } else if log.header {
        let names: Vec<String> = log.columns.iter().map(|c| c.name.clone()).collect();
        format!(
            "no data rows: a header of {} column{} ({}) but no line of values after it",
            names.len(),
            if names.len() == 1 { "" } else { "s" },
            excerpt(&period_log::some_names(&names))
        )
    } else {
        format!(
            "no data rows: none of its {lines} line{} holds values",
            if lines == 1 { "" } else { "s" }
        )
    };
    ReadError {
        line: if log.account.bytes == 0 {
            0
        } else {
            lines.max(1)
        },
        message,
    }
}

/// Loads a whole file in memory at once (the command line; the browser pushes chunks).
pub fn load(bytes: &[u8], sample_period_s: Option<f64>) -> Result<Log, ReadError> {
    let mut builder = LogBuilder::new();
    for chunk in bytes.chunks(1 << 16) {
        builder.push(chunk);
    }
    builder.finish(sample_period_s)
}
