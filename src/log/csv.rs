//! An incremental reader of messy CSV logs: bytes in chunks, records out, the dialect inferred
//! from the first lines.
//!
//! What it takes: comma, semicolon or tab delimiters (detected), a decimal comma beside semicolons
//! or tabs, quoted fields (doubled quotes inside, delimiters and line breaks inside quotes), a
//! UTF-8 byte-order mark, LF, CRLF or CR-only line ends, a last line with or without its newline.
//! It never panics on any input and keeps no copy of the text: only the unfinished last record of
//! a chunk waits for the next one.
//!
//! What it refuses rather than guesses at ([`CsvReader::refused`]): text in UTF-16 or UTF-32
//! (with or without a byte-order mark) and other bytes with zeros among them, and a quote that
//! swallows the lines after it — one never closed, or one whose field holds lines that look like
//! whole records. Blank lines are skipped and counted ([`CsvReader::blank_lines`]).
//!
//! It is built for speed as much as for mess (a 100 MB log loads in well under a second, see
//! docs/benchmarks.md): one pass over the bytes splits a record into fields that are slices of
//! the input (a quoted field is unescaped into one reused buffer), nothing is allocated per field
//! or per record, and numbers are parsed straight from the bytes ([`parse_number`]). Text stays
//! bytes until a caller keeps it (a new label); bytes that are not UTF-8 are then replaced.

/// How the file is written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Dialect {
    /// The field delimiter: `,`, `;` or tab.
    pub delimiter: u8,
    /// True when numbers use a decimal comma (`1,5`), which only a `;` or tab file can.
    pub decimal_comma: bool,
}

impl Dialect {
    /// The delimiter as text for people (`","`, `";"`, `"tab"`).
    pub fn delimiter_name(&self) -> &'static str {
        match self.delimiter {
            b';' => ";",
            b'\t' => "tab",
            _ => ",",
        }
    }

    /// The dialect in words for a sentence (`delimiter semicolon, decimal comma`): a bare `,` or
    /// `;` there reads as punctuation (`delimiter ,, decimal .`).
    ///
    /// ```
    /// use cutlab::log::csv::Dialect;
    /// let d = Dialect { delimiter: b';', decimal_comma: true };
    /// assert_eq!(d.in_words(), "delimiter semicolon, decimal comma");
    /// ```
    pub fn in_words(&self) -> String {
        let delimiter = match self.delimiter {
            b';' => "semicolon",
            b'\t' => "tab",
            _ => "comma",
        };
        let decimal = if self.decimal_comma { "comma" } else { "point" };
        format!("delimiter {delimiter}, decimal {decimal}")
    }
}

/// How much of the start is read to infer the dialect.
const SNIFF_BYTES: usize = 64 * 1024;
/// How many records the dialect is inferred from.
const SNIFF_RECORDS: usize = 50;
/// How much of the start is looked at for zero bytes (UTF-16, UTF-32, binary files).
const ENCODING_BYTES: usize = 4096;
/// A record longer than this is cut (a file with no line breaks must not grow one record
/// without bound); the cut is reported.
pub const MAX_RECORD_BYTES: usize = 1 << 20;

/// Where one field's bytes are: in the input, or (unescaped, for a quoted field) in the reader's
/// scratch buffer.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Span {
    Input(usize, usize),
    Scratch(usize, usize),
    /// An unquoted field read as a number while splitting (its bytes, and the value).
    Number(usize, usize, f64),
}

/// One cell: a number read while splitting, or bytes to read.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Cell<'a> {
    /// A number (exactly what [`parse_number`] reads from the field).
    Number(f64),
    /// The field's bytes, quotes removed.
    Bytes(&'a [u8]),
}

/// One record, borrowed from the reader until the callback returns.
#[derive(Debug, Clone, Copy)]
pub struct RecordView<'a> {
    /// The line the record starts on (1-based).
    pub line: usize,
    /// The lines it spans (more than one when a quoted field holds a line break).
    pub lines: usize,
    dialect: Dialect,
    input: &'a [u8],
    scratch: &'a [u8],
    spans: &'a [Span],
}

impl<'a> RecordView<'a> {
    /// The file's dialect.
    pub fn dialect(&self) -> Dialect {
        self.dialect
    }

    /// How many fields the record has.
    pub fn len(&self) -> usize {
        self.spans.len()
    }

    /// True for a record without fields (never handed out: blank lines are skipped).
    pub fn is_empty(&self) -> bool {
        self.spans.is_empty()
    }

    /// Whether every field is empty or blank (a line of only delimiters).
    pub fn all_empty(&self) -> bool {
        self.fields().all(|f| f.trim_ascii().is_empty())
    }

    /// Field `i`'s bytes, quotes removed (empty past the last field).
    pub fn field(&self, i: usize) -> &'a [u8] {
        let bytes = match self.spans.get(i) {
            Some(&Span::Input(a, b) | &Span::Number(a, b, _)) => self.input.get(a..b),
            Some(&Span::Scratch(a, b)) => self.scratch.get(a..b),
            None => None,
        };
        bytes.unwrap_or_default()
    }

    /// Field `i` as a number, if the reader already read it as one, else its bytes.
    pub fn cell(&self, i: usize) -> Cell<'a> {
        match self.spans.get(i) {
            Some(&Span::Number(_, _, v)) => Cell::Number(v),
            _ => Cell::Bytes(self.field(i)),
        }
    }

    /// Every field, in order.
    pub fn fields(&self) -> impl Iterator<Item = &'a [u8]> + '_ {
        (0..self.spans.len()).map(|i| self.field(i))
    }

    /// The fields as owned text (bytes that are not UTF-8 replaced).
    pub fn to_strings(&self) -> Vec<String> {
        self.fields()
            .map(|f| String::from_utf8_lossy(f).into_owned())
            .collect()
    }
}

/// Something about the bytes themselves (not their meaning) worth telling.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadProblem {
    /// The line.
    pub line: usize,
    /// What.
    pub message: String,
}

/// The reader.
#[derive(Debug, Default)]
pub struct CsvReader {
    dialect: Option<Dialect>,
    /// The most common number of fields in the first records (from the sniff).
    usual_fields: usize,
    /// Bytes not yet split into records.
    pending: Vec<u8>,
    /// Line number of the first byte of `pending`.
    pending_line: usize,
    bom_checked: bool,
    bytes_read: u64,
    /// Unescaped quoted fields of the record being split.
    scratch: Vec<u8>,
    /// The fields of the record being split.
    spans: Vec<Span>,
    problems: Vec<ReadProblem>,
    /// Why the file is not read, once it is known; nothing more is read after it.
    refused: Option<ReadProblem>,
    /// The file ends its lines with a lone CR (old Mac exports): each CR is read as a line feed.
    cr_line_ends: bool,
    /// Blank lines skipped, and the first of them.
    blank_lines: usize,
    first_blank_line: usize,
    /// The line within the record being split where its last quoted field opened.
    quote_opened: usize,
}

/// How a scan of one record ended.
enum Scan {
    /// A complete record: the offset after its line break, and the lines it spans.
    Complete { next: usize, lines: usize },
    /// The bytes ran out inside the record (`in_quote`: inside a quoted field).
    Incomplete { in_quote: bool },
    /// The input ended inside a quoted field: the quote is never closed.
    Unclosed,
}

impl CsvReader {
    /// A reader that infers the dialect from the first lines.
    pub fn new() -> Self {
        Self {
            pending_line: 1,
            ..Self::default()
        }
    }

    /// The dialect, once inferred.
    pub fn dialect(&self) -> Option<Dialect> {
        self.dialect
    }

    /// Bytes taken so far, for a progress bar.
    pub fn bytes_read(&self) -> u64 {
        self.bytes_read
    }

    /// Problems with the bytes so far.
    pub fn take_problems(&mut self) -> Vec<ReadProblem> {
        std::mem::take(&mut self.problems)
    }

    /// Why the file is not read (UTF-16 or UTF-32, zero bytes, a quote swallowing lines), once
    /// that is known; the reader hands out no records after it.
    pub fn refused(&self) -> Option<&ReadProblem> {
        self.refused.as_ref()
    }

    /// Lines split so far (every line once the input is finished).
    pub fn lines_read(&self) -> usize {
        self.pending_line.saturating_sub(1)
    }

    /// Blank lines skipped so far, and the first of them (0 if none).
    pub fn blank_lines(&self) -> (usize, usize) {
        (self.blank_lines, self.first_blank_line)
    }

    /// Whether the file ends its lines with a lone CR (read as line feeds).
    pub fn cr_line_ends(&self) -> bool {
        self.cr_line_ends
    }

    /// Takes `chunk` and hands every record it completes to `out`.
    pub fn push(&mut self, chunk: &[u8], out: &mut impl FnMut(RecordView<'_>)) {
        if self.refused.is_some() {
            return;
        }
        self.bytes_read += chunk.len() as u64;
        let from = self.pending.len();
        self.pending.extend_from_slice(chunk);
        if self.cr_line_ends {
            cr_to_lf(&mut self.pending[from..]);
        }
        if !self.bom_checked {
            // The mark may arrive split over chunks: wait for three bytes.
            let head = &self.pending[..self.pending.len().min(3)];
            if self.pending.len() < 3 && BOM.starts_with(head) {
                return;
            }
            self.bom_checked = true;
            if self.pending.starts_with(BOM) {
                self.pending.drain(..3);
            }
        }
        if self.dialect.is_none() {
            if self.pending.len() < SNIFF_BYTES {
                return;
            }
            self.decide();
        }
        self.drain(false, out);
    }

    /// Ends the input: hands over the last record (with or without its newline).
    pub fn finish(&mut self, out: &mut impl FnMut(RecordView<'_>)) {
        if self.refused.is_some() {
            return;
        }
        if !self.bom_checked {
            self.bom_checked = true;
            if self.pending.starts_with(BOM) {
                self.pending.drain(..3);
            }
        }
        if self.dialect.is_none() {
            self.decide();
        }
        self.drain(true, out);
    }

    /// From the start of the file: whether it is text at all, its line ends and its dialect.
    fn decide(&mut self) {
        if let Some(message) = encoding_problem(&self.pending) {
            self.refuse(1, message);
            return;
        }
        // No line feed anywhere in the start, but carriage returns: the lines end with a lone CR.
        let start = &self.pending[..self.pending.len().min(SNIFF_BYTES)];
        if !start.contains(&b'\n') && start.contains(&b'\r') {
            self.cr_line_ends = true;
            cr_to_lf(&mut self.pending);
        }
        let (dialect, fields) = sniff_fields(&self.pending);
        self.dialect = Some(dialect);
        self.usual_fields = fields;
    }

    /// Stops reading: the file is not read, for `message` at `line`.
    fn refuse(&mut self, line: usize, message: String) {
        self.refused = Some(ReadProblem { line, message });
        self.pending = Vec::new();
    }

    /// Splits every complete record out of `pending` (all of it at the end).
    fn drain(&mut self, at_end: bool, out: &mut impl FnMut(RecordView<'_>)) {
        let Some(dialect) = self.dialect else { return };
        let pending = std::mem::take(&mut self.pending);
        let mut start = 0;
        let mut line = self.pending_line;
        while start < pending.len() {
            let rest = &pending[start..];
            let (scan, cut) = match self.split(rest, dialect, at_end) {
                Scan::Incomplete { in_quote: true } if rest.len() > MAX_RECORD_BYTES => {
                    let lines = rest.iter().filter(|&&b| b == b'\n').count();
                    self.refuse(
                        line + self.quote_opened - 1,
                        format!(
                            "a quote opens a field here and runs on for more than {} MiB ({lines} \
                             lines) without closing: an unclosed quote would swallow the lines \
                             after it; the file is not read (close or remove the quote)",
                            MAX_RECORD_BYTES >> 20
                        ),
                    );
                    return;
                }
                Scan::Incomplete { .. } if rest.len() > MAX_RECORD_BYTES => {
                    // No line break at all: cut the record, say so (the rest is read on).
                    self.problems.push(ReadProblem {
                        line,
                        message: format!(
                            "a record longer than {} MiB without a line break; cut there",
                            MAX_RECORD_BYTES >> 20
                        ),
                    });
                    let cut = &rest[..MAX_RECORD_BYTES];
                    let scan = self.split(cut, dialect, true);
                    (scan, true)
                }
                scan => (scan, false),
            };
            let (next, lines) = match scan {
                Scan::Complete { next, lines } => (next, lines),
                Scan::Incomplete { .. } => break,
                Scan::Unclosed => {
                    let opened = line + self.quote_opened - 1;
                    // Line breaks after the quote, but a last one that ends the file.
                    let breaks = rest.iter().filter(|&&b| b == b'\n').count();
                    let after = breaks
                        .saturating_sub(self.quote_opened - 1)
                        .saturating_sub(usize::from(rest.ends_with(b"\n")));
                    self.refuse(
                        opened,
                        format!(
                            "a quote opens a field here and is never closed: it would swallow \
                             the {after} lines after it into one field; the file is not read \
                             (close or remove the quote)"
                        ),
                    );
                    return;
                }
            };
            let record_input = if cut { &rest[..MAX_RECORD_BYTES] } else { rest };
            if lines > 1 {
                let swallowed = self.swallowed_records(dialect.delimiter);
                if swallowed > 0 {
                    self.refuse(
                        line,
                        format!(
                            "a quoted field here runs over {lines} lines, {swallowed} of them \
                             with the delimiters of a whole record: an unclosed quote? The file \
                             is not read (close or remove the quote)"
                        ),
                    );
                    return;
                }
            }
            if self.blank(record_input) {
                self.blank_lines += lines;
                if self.first_blank_line == 0 {
                    self.first_blank_line = line;
                }
            } else {
                out(RecordView {
                    line,
                    lines,
                    dialect,
                    input: record_input,
                    scratch: &self.scratch,
                    spans: &self.spans,
                });
            }
            line += lines;
            start += next;
        }
        let mut pending = pending;
        pending.drain(..start.min(pending.len()));
        self.pending = pending;
        self.pending_line = line;
    }

    /// The lines inside the quoted fields of the record just split (after a line break in one)
    /// that hold as many delimiters as a whole record of the file's usual width: lines a quote
    /// swallowed. A line break inside a quoted label ("two\nlines") is no record.
    fn swallowed_records(&self, delimiter: u8) -> usize {
        let needed = self.usual_fields.saturating_sub(1).max(1);
        self.spans
            .iter()
            .filter_map(|s| match *s {
                Span::Scratch(a, b) => self.scratch.get(a..b),
                _ => None,
            })
            .flat_map(|field| field.split(|&b| b == b'\n').skip(1))
            .filter(|l| l.iter().filter(|&&b| b == delimiter).count() >= needed)
            .count()
    }

    /// Whether the record just split is blank (one field of white space): such lines are
    /// skipped and counted. A line of delimiters only is a record of empty cells, not blank.
    fn blank(&self, input: &[u8]) -> bool {
        match self.spans.as_slice() {
            [Span::Input(a, b)] => input
                .get(*a..*b)
                .is_none_or(|f| f.iter().all(u8::is_ascii_whitespace)),
            // A quoted field is a value, even if empty (""), and so is a number.
            _ => false,
        }
    }

    /// Splits the first record of `bytes` into `self.spans` in one pass. A quote opens a quoted
    /// field only at the field's start (after blanks); inside, `""` is a quote and a line break
    /// or delimiter is part of the field; after the closing quote, further bytes join the field.
    /// A CR before the line break is dropped. At the end of the input (`at_end`) the last record
    /// needs no line break.
    fn split(&mut self, bytes: &[u8], dialect: Dialect, at_end: bool) -> Scan {
        self.spans.clear();
        self.scratch.clear();
        let mut lines = 1;
        let mut i = 0;
        loop {
            match self.field(bytes, i, dialect, at_end, &mut lines) {
                FieldEnd::Delimiter(next) => i = next,
                FieldEnd::Record(next) => return Scan::Complete { next, lines },
                FieldEnd::Incomplete { in_quote } => return Scan::Incomplete { in_quote },
                FieldEnd::Unclosed => return Scan::Unclosed,
            }
        }
    }

    /// Reads the field starting at `start` into `self.spans`; says how it ended.
    fn field(
        &mut self,
        bytes: &[u8],
        start: usize,
        dialect: Dialect,
        at_end: bool,
        lines: &mut usize,
    ) -> FieldEnd {
        let delimiter = dialect.delimiter;
        let n = bytes.len();
        // Nearly every field of a log is a plain number: read it as the field is found, so its
        // bytes are looked at once.
        if let Some((value, end)) = number_at(bytes, start, dialect.decimal_comma) {
            match bytes.get(end) {
                Some(&b) if b == delimiter => {
                    self.spans.push(Span::Number(start, end, value));
                    return FieldEnd::Delimiter(end + 1);
                }
                Some(b'\n') => {
                    self.spans.push(Span::Number(start, end, value));
                    return FieldEnd::Record(end + 1);
                }
                Some(b'\r') if bytes.get(end + 1) == Some(&b'\n') => {
                    self.spans.push(Span::Number(start, end, value));
                    return FieldEnd::Record(end + 2);
                }
                None if at_end => {
                    self.spans.push(Span::Number(start, end, value));
                    return FieldEnd::Record(n);
                }
                None => return FieldEnd::Incomplete { in_quote: false },
                // Something else follows (a unit, a space): read the field the long way.
                Some(_) => {}
            }
        }
        let mut i = start;
        loop {
            // An unquoted field: jump to the next delimiter, line break or quote.
            i = find_special(bytes, i, delimiter);
            let Some(&b) = bytes.get(i) else {
                if !at_end {
                    return FieldEnd::Incomplete { in_quote: false };
                }
                // The last record without its line break.
                let end = if n > start && bytes[n - 1] == b'\r' {
                    n - 1
                } else {
                    n
                };
                self.spans.push(Span::Input(start, end));
                return FieldEnd::Record(n);
            };
            if b == delimiter {
                self.spans.push(Span::Input(start, i));
                return FieldEnd::Delimiter(i + 1);
            }
            if b == b'\n' {
                let end = if i > start && bytes[i - 1] == b'\r' {
                    i - 1
                } else {
                    i
                };
                self.spans.push(Span::Input(start, end));
                return FieldEnd::Record(i + 1);
            }
            // A quote: it opens a quoted field only at the field's start (after blanks); in the
            // middle of a field ("5\"") it is a character.
            if bytes[start..i].iter().all(u8::is_ascii_whitespace) {
                return self.quoted(bytes, i + 1, delimiter, at_end, lines);
            }
            i += 1;
        }
    }

    /// A quoted field whose content starts at `start` (after the opening quote), unescaped into
    /// the scratch buffer.
    fn quoted(
        &mut self,
        bytes: &[u8],
        start: usize,
        delimiter: u8,
        at_end: bool,
        lines: &mut usize,
    ) -> FieldEnd {
        let n = bytes.len();
        let from = self.scratch.len();
        self.quote_opened = *lines;
        let mut i = start;
        let mut closed = false;
        while let Some(&b) = bytes.get(i) {
            if b == b'"' {
                match bytes.get(i + 1) {
                    Some(b'"') => {
                        self.scratch.push(b'"');
                        i += 2;
                        continue;
                    }
                    // The next chunk may start with the second quote of a pair.
                    None if !at_end => return FieldEnd::Incomplete { in_quote: true },
                    _ => {
                        closed = true;
                        i += 1;
                        break;
                    }
                }
            }
            if b == b'\n' {
                *lines += 1;
            }
            self.scratch.push(b);
            i += 1;
        }
        if !closed {
            if !at_end {
                return FieldEnd::Incomplete { in_quote: true };
            }
            // A quote open at the end of the input swallowed everything after it.
            return FieldEnd::Unclosed;
        }
        // After the closing quote, up to the delimiter or line break.
        while let Some(&b) = bytes.get(i) {
            if b == delimiter || b == b'\n' {
                break;
            }
            self.scratch.push(b);
            i += 1;
        }
        let at = bytes.get(i).copied();
        if at != Some(delimiter) && self.scratch.len() > from && self.scratch.last() == Some(&b'\r')
        {
            self.scratch.pop();
        }
        self.spans.push(Span::Scratch(from, self.scratch.len()));
        match at {
            Some(b) if b == delimiter => FieldEnd::Delimiter(i + 1),
            Some(_) => FieldEnd::Record(i + 1),
            None if at_end => FieldEnd::Record(n),
            None => FieldEnd::Incomplete { in_quote: false },
        }
    }
}

/// How a field ended.
enum FieldEnd {
    /// At a delimiter; the next field starts here.
    Delimiter(usize),
    /// At the record's end; the next record starts here.
    Record(usize),
    /// The bytes ran out (inside a quoted field, or not).
    Incomplete { in_quote: bool },
    /// The input ended inside a quoted field.
    Unclosed,
}

/// Reads every carriage return as a line feed (a file whose lines end with a lone CR).
fn cr_to_lf(bytes: &mut [u8]) {
    for b in bytes.iter_mut().filter(|b| **b == b'\r') {
        *b = b'\n';
    }
}

/// Why the start of a file is no text this reader reads, or `None` for UTF-8, ASCII or
/// Latin-1 text: UTF-32 or UTF-16 by its byte-order mark, or without one by the zero bytes
/// beside each ASCII character (three in UTF-32, one in UTF-16), or zero bytes in any other
/// pattern (a spreadsheet, an archive). Reading such bytes as text would give garbage columns.
///
/// ```
/// use cutlab::log::csv::encoding_problem;
/// assert!(encoding_problem(b"t,I\n0,1\n").is_none());
/// assert!(encoding_problem(b"\xFF\xFEt\0,\0").unwrap().contains("UTF-16"));
/// assert!(encoding_problem(b"t\0\0\0,\0\0\0I\0\0\0").unwrap().contains("UTF-32"));
/// ```
pub fn encoding_problem(start: &[u8]) -> Option<String> {
    let marks: [(&[u8], &str); 4] = [
        (&[0xFF, 0xFE, 0, 0], "UTF-32 (little-endian)"),
        (&[0, 0, 0xFE, 0xFF], "UTF-32 (big-endian)"),
        (&[0xFF, 0xFE], "UTF-16 (little-endian)"),
        (&[0xFE, 0xFF], "UTF-16 (big-endian)"),
    ];
    let save_as = "save it as UTF-8 (or plain ASCII) and open it again";
    for (mark, name) in marks {
        if start.starts_with(mark) {
            return Some(format!(
                "the file is {name} text (its byte-order mark says so), which this reader does \
                 not decode; {save_as}"
            ));
        }
    }
    let head = &start[..start.len().min(ENCODING_BYTES)];
    let zeros = head.iter().filter(|&&b| b == 0).count();
    // A stray zero byte in text is damage, read as text; many of them are an encoding.
    if zeros == 0 || zeros * 8 < head.len() {
        return None;
    }
    // The share of zero bytes at each position modulo 4.
    let share = |k: usize| {
        let at: Vec<u8> = head.iter().skip(k).step_by(4).copied().collect();
        at.iter().filter(|&&b| b == 0).count() as f64 / at.len().max(1) as f64
    };
    let z = [share(0), share(1), share(2), share(3)];
    let (high, low) = (|v: f64| v > 0.8, |v: f64| v < 0.5);
    let name = if low(z[0]) && high(z[1]) && high(z[2]) && high(z[3]) {
        Some("UTF-32 (little-endian)")
    } else if high(z[0]) && high(z[1]) && high(z[2]) && low(z[3]) {
        Some("UTF-32 (big-endian)")
    } else if low(z[0]) && high(z[1]) && low(z[2]) && high(z[3]) {
        Some("UTF-16 (little-endian)")
    } else if high(z[0]) && low(z[1]) && high(z[2]) && low(z[3]) {
        Some("UTF-16 (big-endian)")
    } else {
        None
    };
    Some(match name {
        Some(name) => format!(
            "the file looks like {name} text without a byte-order mark ({zeros} zero bytes in \
             its first {} bytes), which this reader does not decode; {save_as}",
            head.len()
        ),
        None => format!(
            "the file is not text: {zeros} of its first {} bytes are zero (a spreadsheet or a \
             compressed file?); export it as CSV",
            head.len()
        ),
    })
}

const BOM: &[u8] = &[0xEF, 0xBB, 0xBF];

/// The index of the first delimiter, line feed or quote in `bytes` from `from` (`bytes.len()` if
/// none): eight bytes at a time, the classic "has a zero byte" test on each byte XOR the
/// wanted one (exact for the lowest match, which is the one taken).
fn find_special(bytes: &[u8], from: usize, delimiter: u8) -> usize {
    const ONES: u64 = 0x0101_0101_0101_0101;
    const HIGHS: u64 = 0x8080_8080_8080_8080;
    let zero_bytes = |v: u64| v.wrapping_sub(ONES) & !v & HIGHS;
    let (d, lf, quote) = (
        ONES * u64::from(delimiter),
        ONES * u64::from(b'\n'),
        ONES * u64::from(b'"'),
    );
    let mut i = from;
    while let Some(word) = bytes.get(i..i + 8) {
        let mut eight = [0u8; 8];
        eight.copy_from_slice(word);
        let x = u64::from_le_bytes(eight);
        let found = zero_bytes(x ^ d) | zero_bytes(x ^ lf) | zero_bytes(x ^ quote);
        if found != 0 {
            return i + (found.trailing_zeros() / 8) as usize;
        }
        i += 8;
    }
    while let Some(&b) = bytes.get(i) {
        if b == delimiter || b == b'\n' || b == b'"' {
            return i;
        }
        i += 1;
    }
    bytes.len()
}

/// The fields of one record, quotes removed (`""` inside quotes is one quote), by the reader's
/// own rules (the record is read as the last of a file).
///
/// ```
/// use cutlab::log::csv::split_fields;
/// assert_eq!(split_fields("a,\"b,\"\"c\"\"\",", b','), ["a", "b,\"c\"", ""]);
/// ```
pub fn split_fields(text: &str, delimiter: u8) -> Vec<String> {
    let mut reader = CsvReader::new();
    let mut fields = Vec::new();
    let dialect = Dialect {
        delimiter,
        decimal_comma: false,
    };
    if let Scan::Complete { .. } = reader.split(text.as_bytes(), dialect, true) {
        let view = RecordView {
            line: 1,
            lines: 1,
            dialect,
            input: text.as_bytes(),
            scratch: &reader.scratch,
            spans: &reader.spans,
        };
        fields = view.to_strings();
    }
    fields
}

/// Infers the dialect from the start of a file: the delimiter that splits the first records
/// into the same number of fields (more than one) most often, then whether numbers use a decimal
/// comma.
///
/// ```
/// use cutlab::log::csv::sniff;
/// assert_eq!(sniff(b"t;I [A]\n0;1,5\n0,1;1,7\n").delimiter, b';');
/// assert!(sniff(b"t;I [A]\n0;1,5\n0,1;1,7\n").decimal_comma);
/// assert_eq!(sniff(b"a,b\n1,2\n").delimiter, b',');
/// assert_eq!(sniff(b"a\tb\n1.5\t2\n").delimiter, b'\t');
/// ```
pub fn sniff(start: &[u8]) -> Dialect {
    sniff_fields(start).0
}

/// [`sniff`], and the number of fields most of the first records have (0 when none has more
/// than one).
fn sniff_fields(start: &[u8]) -> (Dialect, usize) {
    let text = String::from_utf8_lossy(&start[..start.len().min(SNIFF_BYTES)]);
    // Comment lines (`# exported by …`) say nothing of the dialect.
    let records: Vec<&str> = text
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
        .take(SNIFF_RECORDS)
        .collect();
    let mut best = (b',', 0usize, 0usize); // delimiter, lines agreeing, fields
                                           // On a tie a semicolon or tab wins: a comma that splits as well is a decimal comma.
    for delimiter in [b';', b'\t', b','] {
        let counts: Vec<usize> = records
            .iter()
            .map(|l| split_fields(l, delimiter).len())
            .collect();
        // The most common field count above one, and how many lines have it.
        let mut tally: Vec<(usize, usize)> = Vec::new();
        for &c in counts.iter().filter(|&&c| c > 1) {
            match tally.iter_mut().find(|(n, _)| *n == c) {
                Some((_, k)) => *k += 1,
                None => tally.push((c, 1)),
            }
        }
        if let Some(&(fields, agreeing)) = tally.iter().max_by_key(|(n, k)| (*k, *n)) {
            if (agreeing, fields) > (best.1, best.2) {
                best = (delimiter, agreeing, fields);
            }
        }
    }
    let delimiter = best.0;
    let decimal_comma = delimiter != b',' && {
        let fields = records
            .iter()
            .skip(1)
            .flat_map(|l| split_fields(l, delimiter))
            .collect::<Vec<_>>();
        let comma = fields.iter().filter(|f| looks_decimal(f, ',')).count();
        let dot = fields.iter().filter(|f| looks_decimal(f, '.')).count();
        comma > dot
    };
    (
        Dialect {
            delimiter,
            decimal_comma,
        },
        best.2,
    )
}

/// `1,5` / `-0.25e3`: digits, one `sep`, digits.
fn looks_decimal(field: &str, sep: char) -> bool {
    let f = field.trim().trim_start_matches(['-', '+']);
    let Some((whole, fraction)) = f.split_once(sep) else {
        return false;
    };
    let fraction = fraction.split(['e', 'E']).next().unwrap_or_default();
    !whole.is_empty()
        && whole.bytes().all(|b| b.is_ascii_digit())
        && !fraction.is_empty()
        && fraction.bytes().all(|b| b.is_ascii_digit())
}

/// A cell as a number, if it is one: decimal point or (with `decimal_comma`) comma, exponents,
/// `NaN`, `inf`; surrounding spaces ignored. An empty cell is `None`.
///
/// ```
/// use cutlab::log::csv::parse_cell;
/// assert_eq!(parse_cell("-1.42E-06", false), Some(-1.42e-6));
/// assert_eq!(parse_cell(" 1,5 ", true), Some(1.5));
/// assert!(parse_cell("NaN", false).unwrap().is_nan());
/// assert_eq!(parse_cell("inf", false), Some(f64::INFINITY));
/// assert_eq!(parse_cell("Layer 1", false), None);
/// assert_eq!(parse_cell("1,5", false), None);
/// ```
pub fn parse_cell(cell: &str, decimal_comma: bool) -> Option<f64> {
    parse_number(cell.as_bytes(), decimal_comma)
}

/// [`parse_cell`] on bytes, without allocating: the reader's hot path. The result is exactly
/// what Rust's `str::parse::<f64>` gives for the same text (correctly rounded); the common
/// short decimals take an exact fast path, anything longer goes to `str::parse`.
///
/// ```
/// use cutlab::log::csv::parse_number;
/// assert_eq!(parse_number(b" 0.1 ", false), Some(0.1));
/// assert_eq!(parse_number(b"-2,5e3", true), Some(-2500.0));
/// assert_eq!(parse_number(b"1_000", false), None);
/// ```
pub fn parse_number(cell: &[u8], decimal_comma: bool) -> Option<f64> {
    let t = cell.trim_ascii();
    if t.is_empty() {
        return None;
    }
    // Nearly every cell of a log is a short decimal: one pass, no checks beforehand.
    if let Some(v) = fast_decimal(t, decimal_comma) {
        return Some(v);
    }
    let mut buffer = [0u8; 64];
    let t = if decimal_comma && t.contains(&b',') {
        if t.contains(&b'.') || t.len() > buffer.len() {
            // 64 bytes is no number a log writes with a decimal comma: text.
            return None;
        }
        let copy = &mut buffer[..t.len()];
        copy.copy_from_slice(t);
        for b in copy.iter_mut() {
            if *b == b',' {
                *b = b'.';
            }
        }
        // Only digits, signs, points and exponents are numbers (as without the comma).
        if !copy.iter().all(|&b| is_number_byte(b)) {
            return None;
        }
        return parse_decimal(copy);
    } else {
        t
    };
    if !t.iter().all(|&b| is_number_byte(b)) {
        // NaN and infinities in any case; anything else with other bytes ("1_000", "0x10",
        // "Layer 1") is text.
        return if t.eq_ignore_ascii_case(b"nan") || t.eq_ignore_ascii_case(b"-nan") {
            Some(f64::NAN)
        } else if t.eq_ignore_ascii_case(b"inf")
            || t.eq_ignore_ascii_case(b"+inf")
            || t.eq_ignore_ascii_case(b"infinity")
            || t.eq_ignore_ascii_case(b"+infinity")
        {
            Some(f64::INFINITY)
        } else if t.eq_ignore_ascii_case(b"-inf") || t.eq_ignore_ascii_case(b"-infinity") {
            Some(f64::NEG_INFINITY)
        } else {
            None
        };
    }
    parse_decimal(t)
}

fn is_number_byte(b: u8) -> bool {
    b.is_ascii_digit() || matches!(b, b'.' | b'-' | b'+' | b'e' | b'E')
}

/// Exact powers of ten a double holds (10²² is the largest).
const POWERS_OF_TEN: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Text of digits, signs, points and exponents as a number, as `str::parse` reads it: the fast
/// path, else `str::parse` itself.
fn parse_decimal(t: &[u8]) -> Option<f64> {
    fast_decimal(t, false).or_else(|| std::str::from_utf8(t).ok()?.parse::<f64>().ok())
}

/// The fast path (Clinger's): a decimal `[±]digits[.digits][e[±]digits]` (the point may be a
/// comma when `decimal_comma`) whose digits fit a mantissa below 2⁵³ and whose power of ten is
/// at most 22 is one exact integer times (or over) one exact power of ten, so the single
/// rounding of that multiplication or division is the correctly rounded result — the bits
/// `str::parse` gives. `None` for anything else (longer numbers, text, NaN), which the caller
/// reads the slow way.
fn fast_decimal(t: &[u8], decimal_comma: bool) -> Option<f64> {
    number_at(t, 0, decimal_comma)
        .filter(|&(_, end)| end == t.len())
        .map(|(v, _)| v)
}

/// The fast path's number starting at `bytes[start]`, and the index just after it: it stops
/// at the first byte that cannot continue the number. `None` where the fast path does not apply:
/// more than 15 digits (then the mantissa might not be exact), a power of ten beyond 22, no
/// digit at all.
#[inline]
fn number_at(bytes: &[u8], start: usize, decimal_comma: bool) -> Option<(f64, usize)> {
    let mut i = start;
    let negative = match bytes.get(i) {
        Some(b'-') => {
            i += 1;
            true
        }
        Some(b'+') => {
            i += 1;
            false
        }
        _ => false,
    };
    let mut mantissa: u64 = 0;
    let mut digits = 0usize;
    let integer_start = i;
    i = digits_at(bytes, i, &mut mantissa, &mut digits);
    let mut any_digit = i > integer_start;
    let mut exponent: i64 = 0;
    if matches!(bytes.get(i), Some(b'.')) || (decimal_comma && bytes.get(i) == Some(&b',')) {
        i += 1;
        let fraction_start = i;
        i = digits_at(bytes, i, &mut mantissa, &mut digits);
        exponent -= (i - fraction_start) as i64;
        any_digit |= i > fraction_start;
    }
    if !any_digit || digits > 15 {
        return None;
    }
    if matches!(bytes.get(i), Some(b'e' | b'E')) {
        i += 1;
        let negative_exponent = match bytes.get(i) {
            Some(b'-') => {
                i += 1;
                true
            }
            Some(b'+') => {
                i += 1;
                false
            }
            _ => false,
        };
        let exponent_start = i;
        let mut e: i64 = 0;
        while let Some(&b) = bytes.get(i) {
            let d = b.wrapping_sub(b'0');
            if d > 9 || e > 100_000 {
                break;
            }
            e = e * 10 + i64::from(d);
            i += 1;
        }
        if i == exponent_start {
            return None;
        }
        exponent += if negative_exponent { -e } else { e };
    }
    // At most 15 digits: the mantissa is below 10¹⁵ < 2⁵³, exact in a double.
    let value = mantissa as f64;
    let value = if mantissa == 0 {
        0.0
    } else if (0..=22).contains(&exponent) {
        value * POWERS_OF_TEN[exponent as usize]
    } else if (-22..0).contains(&exponent) {
        value / POWERS_OF_TEN[(-exponent) as usize]
    } else {
        return None;
    };
    Some((if negative { -value } else { value }, i))
}

/// Powers of ten as integers, for appending up to eight digits to a mantissa.
const POWERS_OF_TEN_U64: [u64; 9] = [
    1,
    10,
    100,
    1_000,
    10_000,
    100_000,
    1_000_000,
    10_000_000,
    100_000_000,
];

/// Reads the decimal digits at `bytes[i..]` into `mantissa` (counting them in `digits`), eight
/// bytes at a time; returns the index after the last digit. Stops adding once more than 15
/// digits were seen (the caller then takes the slow path), so nothing overflows.
#[inline]
fn digits_at(bytes: &[u8], mut i: usize, mantissa: &mut u64, digits: &mut usize) -> usize {
    while let Some(word) = bytes.get(i..i + 8) {
        let mut eight = [0u8; 8];
        eight.copy_from_slice(word);
        let word = u64::from_le_bytes(eight);
        let k = leading_digits(word);
        if k > 0 {
            // The k digits moved to the top bytes: the number "0…0d₁…d_k".
            let shifted = word.wrapping_sub(0x3030_3030_3030_3030) << (8 * (8 - k));
            *mantissa = mantissa
                .wrapping_mul(POWERS_OF_TEN_U64[k])
                .wrapping_add(eight_digits(shifted));
            *digits += k;
            i += k;
        }
        if k < 8 || *digits > 15 {
            return i;
        }
    }
    while let Some(&b) = bytes.get(i) {
        let d = b.wrapping_sub(b'0');
        if d > 9 || *digits > 15 {
            break;
        }
        *mantissa = mantissa.wrapping_mul(10).wrapping_add(u64::from(d));
        *digits += 1;
        i += 1;
    }
    i
}

/// How many of the eight bytes of `word` (first byte lowest) are ASCII digits before the first
/// that is not.
#[inline]
fn leading_digits(word: u64) -> usize {
    // A digit byte 0x3d becomes 0x33: its high nibble is 3, and adding 6 keeps it 3. A carry
    // out of a non-digit byte only disturbs the bytes after it.
    let nibbles = (word & 0xF0F0_F0F0_F0F0_F0F0)
        | ((word.wrapping_add(0x0606_0606_0606_0606) & 0xF0F0_F0F0_F0F0_F0F0) >> 4);
    let other = nibbles ^ 0x3333_3333_3333_3333;
    // The high bit of every byte that is not zero (exact: no carry crosses a byte).
    let flags =
        (other | ((other & 0x7F7F_7F7F_7F7F_7F7F) + 0x7F7F_7F7F_7F7F_7F7F)) & 0x8080_8080_8080_8080;
    (flags.trailing_zeros() / 8) as usize
}

/// Eight digit values (0–9, first digit in the lowest byte) as one number (simdjson's
/// "eight digits" reduction: pairs, then quadruples, then the whole).
#[inline]
fn eight_digits(values: u64) -> u64 {
    const MASK: u64 = 0x0000_00FF_0000_00FF;
    const MUL1: u64 = 100 + (1_000_000 << 32);
    const MUL2: u64 = 1 + (10_000 << 32);
    let v = values.wrapping_mul(10).wrapping_add(values >> 8);
    ((v & MASK)
        .wrapping_mul(MUL1)
        .wrapping_add(((v >> 16) & MASK).wrapping_mul(MUL2)))
        >> 32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn eight_bytes_at_a_time_read_digits_as_one_at_a_time_does() {
        for text in [
            "12345678", "1234567x", "0", "x", "12.5", "99999999", "00000001", "7;8",
        ] {
            let mut padded = text.as_bytes().to_vec();
            padded.resize(8, b';');
            let mut eight = [0u8; 8];
            eight.copy_from_slice(&padded);
            let word = u64::from_le_bytes(eight);
            let k = text.bytes().take_while(u8::is_ascii_digit).count().min(8);
            assert_eq!(leading_digits(word), k, "{text}");
            if k > 0 {
                let value = eight_digits(word.wrapping_sub(0x3030_3030_3030_3030) << (8 * (8 - k)));
                assert_eq!(value, text[..k].parse::<u64>().unwrap(), "{text}");
            }
        }
    }

    #[test]
    fn the_fast_number_parser_gives_the_standard_parsers_bits() {
        let mut rng = Rng::seed_from(11);
        let alphabet = b"0123456789.-+eE";
        for _ in 0..200_000 {
            let len = 1 + (rng.next_u64() % 24) as usize;
            let text: Vec<u8> = (0..len)
                .map(|_| {
                    let r = rng.next_u64() as usize;
                    // Mostly digits, so most strings are numbers.
                    if r.is_multiple_of(4) {
                        alphabet[(r >> 8) % alphabet.len()]
                    } else {
                        b'0' + ((r >> 8) % 10) as u8
                    }
                })
                .collect();
            let expected = std::str::from_utf8(&text)
                .unwrap()
                .parse::<f64>()
                .ok()
                .map(f64::to_bits);
            assert_eq!(
                parse_decimal(&text).map(f64::to_bits),
                expected,
                "{:?}",
                String::from_utf8_lossy(&text)
            );
        }
        for text in [
            "0.1",
            "-0.0",
            "1e22",
            "1e23",
            "9007199254740993",
            "123456789012345.6",
            "5e-324",
            "1.7976931348623157e308",
            "1e400",
            ".5",
            "5.",
            "-.5e1",
            "0000000000000000000001.5",
        ] {
            assert_eq!(
                parse_decimal(text.as_bytes()).map(f64::to_bits),
                text.parse::<f64>().ok().map(f64::to_bits),
                "{text}"
            );
        }
    }

    /// The straightforward reading of a cell the fast one must match: allocate, lower-case,
    /// replace the decimal comma, `str::parse`.
    fn reference_parse(cell: &str, decimal_comma: bool) -> Option<f64> {
        let t = cell.trim();
        if t.is_empty() {
            return None;
        }
        if decimal_comma && t.contains(',') {
            if t.contains('.') {
                return None;
            }
            let t = t.replace(',', ".");
            return if t.bytes().all(is_number_byte) {
                t.parse().ok()
            } else {
                None
            };
        }
        match t.to_ascii_lowercase().as_str() {
            "nan" | "-nan" => return Some(f64::NAN),
            "inf" | "+inf" | "infinity" | "+infinity" => return Some(f64::INFINITY),
            "-inf" | "-infinity" => return Some(f64::NEG_INFINITY),
            _ => {}
        }
        if t.bytes().all(is_number_byte) {
            t.parse().ok()
        } else {
            None
        }
    }

    #[test]
    fn cells_read_as_the_straightforward_reading_reads_them() {
        let mut rng = Rng::seed_from(12);
        let alphabet = b"0123456789.,-+eE nNaAiIfFx";
        for _ in 0..200_000 {
            let len = 1 + (rng.next_u64() % 12) as usize;
            let text: String = (0..len)
                .map(|_| {
                    let r = rng.next_u64() as usize;
                    if r.is_multiple_of(3) {
                        char::from(alphabet[(r >> 8) % alphabet.len()])
                    } else {
                        char::from(b'0' + ((r >> 8) % 10) as u8)
                    }
                })
                .collect();
            for comma in [false, true] {
                assert_eq!(
                    parse_number(text.as_bytes(), comma).map(f64::to_bits),
                    reference_parse(&text, comma).map(f64::to_bits),
                    "{text:?} decimal comma {comma}"
                );
            }
        }
        for text in ["NaN", "-INF", "Infinity", "+inf", " 1,5 ", "1.5,2", "inf,0"] {
            for comma in [false, true] {
                assert_eq!(
                    parse_number(text.as_bytes(), comma).map(f64::to_bits),
                    reference_parse(text, comma).map(f64::to_bits),
                    "{text:?} decimal comma {comma}"
                );
            }
        }
    }

    fn records(bytes: &[u8], chunk: usize) -> Vec<(usize, Vec<String>)> {
        let mut reader = CsvReader::new();
        let mut out = Vec::new();
        for piece in bytes.chunks(chunk.max(1)) {
            reader.push(piece, &mut |r| out.push((r.line, r.to_strings())));
        }
        reader.finish(&mut |r| out.push((r.line, r.to_strings())));
        out
    }

    #[test]
    fn quotes_line_breaks_and_crlf_split_the_same_in_any_chunking() {
        let text = b"a,b\r\n\"x\"\"y\",\"two\r\nlines\"\r\n\r\n 3 ,\"\"\r\n5\"inch,6";
        let expected = vec![
            (1, vec!["a".to_string(), "b".into()]),
            (2, vec!["x\"y".into(), "two\r\nlines".into()]),
            (5, vec![" 3 ".into(), String::new()]),
            (6, vec!["5\"inch".into(), "6".into()]),
        ];
        for chunk in [1, 2, 3, 7, 100] {
            assert_eq!(records(text, chunk), expected, "chunk {chunk}");
        }
    }
}
