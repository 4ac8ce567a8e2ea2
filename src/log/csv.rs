//! An incremental reader of messy CSV logs: bytes in chunks, records out, the dialect inferred
//! from the first lines.
//!
//! What it takes: comma, semicolon or tab delimiters (detected), a decimal comma beside semicolons
//! or tabs, quoted fields (doubled quotes inside, delimiters and line breaks inside quotes), a
//! UTF-8 byte-order mark, LF or CRLF, a last line with or without its newline. Bytes that are not
//! UTF-8 are replaced (and reported once). It never panics on any input and keeps no copy of the
//! text: only the unfinished last record of a chunk waits for the next one.

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
}

/// How much of the start is read to infer the dialect.
const SNIFF_BYTES: usize = 64 * 1024;
/// How many records the dialect is inferred from.
const SNIFF_RECORDS: usize = 50;
/// A record longer than this is cut (a file with no line breaks must not grow one record
/// without bound); the cut is reported.
pub const MAX_RECORD_BYTES: usize = 1 << 20;

/// One record: its first line number (1-based) and its fields.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// The line the record starts on.
    pub line: usize,
    /// The fields, unquoted.
    pub fields: Vec<String>,
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
    /// Bytes not yet split into records.
    pending: Vec<u8>,
    /// Line number of the first byte of `pending`.
    pending_line: usize,
    /// Records read before the dialect was known are re-split once it is.
    started: bool,
    bom_checked: bool,
    bytes_read: u64,
    reported_utf8: bool,
    problems: Vec<ReadProblem>,
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

    /// Takes `chunk` and hands every record it completes to `out`.
    pub fn push(&mut self, chunk: &[u8], out: &mut impl FnMut(Record)) {
        self.bytes_read += chunk.len() as u64;
        let mut chunk = chunk;
        if !self.bom_checked {
            // The mark may arrive split over chunks: wait for three bytes.
            let mut head = std::mem::take(&mut self.pending);
            head.extend_from_slice(chunk);
            if head.len() < 3 && head.starts_with(&[0xEF, 0xBB, 0xBF][..head.len()]) {
                self.pending = head;
                return;
            }
            self.bom_checked = true;
            let start = if head.starts_with(&[0xEF, 0xBB, 0xBF]) {
                3
            } else {
                0
            };
            self.pending = head.split_off(start.min(head.len()));
            chunk = &[];
        }
        self.pending.extend_from_slice(chunk);
        if self.dialect.is_none() {
            if self.pending.len() < SNIFF_BYTES {
                return;
            }
            self.dialect = Some(sniff(&self.pending));
        }
        self.drain(false, out);
    }

    /// Ends the input: hands over the last record (with or without its newline).
    pub fn finish(&mut self, out: &mut impl FnMut(Record)) {
        if !self.bom_checked {
            self.bom_checked = true;
            if self.pending.starts_with(&[0xEF, 0xBB, 0xBF]) {
                self.pending.drain(..3);
            }
        }
        if self.dialect.is_none() {
            self.dialect = Some(sniff(&self.pending));
        }
        self.drain(true, out);
    }

    /// Splits every complete record out of `pending` (all of it at the end).
    fn drain(&mut self, at_end: bool, out: &mut impl FnMut(Record)) {
        let Some(dialect) = self.dialect else { return };
        self.started = true;
        let bytes = std::mem::take(&mut self.pending);
        let mut start = 0;
        let mut line = self.pending_line;
        loop {
            match record_end(&bytes[start..]) {
                Some((len, next)) => {
                    let record_line = line;
                    let raw = &bytes[start..start + len];
                    line += raw.iter().filter(|&&b| b == b'\n').count() + 1;
                    self.emit(raw, record_line, dialect, out);
                    start += next;
                }
                None => {
                    let rest = &bytes[start..];
                    if at_end {
                        if !rest.is_empty() {
                            self.emit(rest, line, dialect, out);
                        }
                        start = bytes.len();
                    } else if rest.len() > MAX_RECORD_BYTES {
                        self.problems.push(ReadProblem {
                            line,
                            message: format!(
                                "a record longer than {} MiB without a line break (an unclosed \
                                 quote?); cut there",
                                MAX_RECORD_BYTES >> 20
                            ),
                        });
                        self.emit(&rest[..MAX_RECORD_BYTES], line, dialect, out);
                        start += MAX_RECORD_BYTES;
                        continue;
                    }
                    break;
                }
            }
        }
        self.pending = bytes[start.min(bytes.len())..].to_vec();
        self.pending_line = line;
    }

    fn emit(&mut self, raw: &[u8], line: usize, dialect: Dialect, out: &mut impl FnMut(Record)) {
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        if raw.iter().all(|b| b.is_ascii_whitespace()) {
            return;
        }
        let text = match std::str::from_utf8(raw) {
            Ok(t) => std::borrow::Cow::Borrowed(t),
            Err(_) => {
                if !self.reported_utf8 {
                    self.reported_utf8 = true;
                    self.problems.push(ReadProblem {
                        line,
                        message: "bytes that are not UTF-8 were replaced (is the file Latin-1?)"
                            .into(),
                    });
                }
                String::from_utf8_lossy(raw)
            }
        };
        out(Record {
            line,
            fields: split_fields(&text, dialect.delimiter),
        });
    }
}

/// Where the first record in `bytes` ends: (its length without the newline, the offset of the
/// next record), or `None` if it does not end in `bytes`. A newline inside quotes is part of the
/// field.
fn record_end(bytes: &[u8]) -> Option<(usize, usize)> {
    let mut quoted = false;
    for (i, &b) in bytes.iter().enumerate() {
        match b {
            b'"' => quoted = !quoted,
            b'\n' if !quoted => return Some((i, i + 1)),
            _ => {}
        }
    }
    None
}

/// The fields of one record, quotes removed (`""` inside quotes is one quote).
pub fn split_fields(text: &str, delimiter: u8) -> Vec<String> {
    let delimiter = char::from(delimiter);
    let mut fields = Vec::new();
    let mut field = String::new();
    let mut quoted = false;
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '"' if quoted => {
                if chars.peek() == Some(&'"') {
                    field.push('"');
                    chars.next();
                } else {
                    quoted = false;
                }
            }
            '"' if field.trim().is_empty() => {
                field.clear();
                quoted = true;
            }
            c if c == delimiter && !quoted => fields.push(std::mem::take(&mut field)),
            c => field.push(c),
        }
    }
    fields.push(field);
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
    let text = String::from_utf8_lossy(&start[..start.len().min(SNIFF_BYTES)]);
    let records: Vec<&str> = text
        .lines()
        .filter(|l| !l.trim().is_empty())
        .take(SNIFF_RECORDS)
        .collect();
    let mut best = (b',', 0usize, 0usize); // delimiter, lines agreeing, fields
    for delimiter in [b',', b';', b'\t'] {
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
    Dialect {
        delimiter,
        decimal_comma,
    }
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
    let t = cell.trim();
    if t.is_empty() {
        return None;
    }
    if decimal_comma && t.contains(',') {
        if t.contains('.') {
            return None;
        }
        return t.replace(',', ".").parse().ok();
    }
    match t.to_ascii_lowercase().as_str() {
        "nan" | "-nan" => return Some(f64::NAN),
        "inf" | "+inf" | "infinity" => return Some(f64::INFINITY),
        "-inf" | "-infinity" => return Some(f64::NEG_INFINITY),
        _ => {}
    }
    // Rust accepts "infinity"/"nan" spellings handled above; refuse anything but digits, signs,
    // points and exponents, so "1_000" or "0x10" stay text.
    if t.bytes()
        .all(|b| b.is_ascii_digit() || matches!(b, b'.' | b'-' | b'+' | b'e' | b'E'))
    {
        t.parse().ok()
    } else {
        None
    }
}
