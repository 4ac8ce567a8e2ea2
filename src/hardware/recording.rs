//! What the Hardware page records: one row per device sample, written as CSV a chunk at a time.
//!
//! A [`Recorder`] turns [`LiveRow`]s into CSV text and hands it out in chunks
//! ([`Recorder::take_chunk`]) that the page stores as they come (IndexedDB in the browser), so a
//! reload or a crash loses at most the chunk not yet taken. The first chunk starts with the
//! header; the chunks joined in order are the whole file. [`RecordingMeta`] describes a recording
//! in the list (JSON beside the chunks).
//!
//! The columns are named so that the log reader ([`crate::log`], `cutlab log inspect`) guesses
//! each one's role: `time [s]` the time axis, `S_I_U [A]`… and `X_I_U [A]`… phase currents of the
//! spindle and the feed drive, `S_speed [rpm]` the spindle speed, `feed [mm/min]` the feed,
//! `S_current_rms [A]` an RMS current, `force estimate [N]` a force, `phase` and `event` labels.
//! Values a row does not have (the period's estimate before the loop runs, the simulation's
//! truth from a real machine) are empty cells, which the reader takes as gaps.

use std::fmt::Write as _;

use serde::{Deserialize, Serialize};

/// One device sample as the host saw it, with what the host did at the time.
#[derive(Debug, Clone, PartialEq)]
pub struct LiveRow {
    /// Device time since the session's first sample.
    pub time_s: f64,
    /// The part (1 = the first the host armed; 0 before any).
    pub part: u32,
    /// Spindle phase currents u, v, w.
    pub spindle_currents_a: [f64; 3],
    /// Feed-drive phase currents u, v, w.
    pub feed_currents_a: [f64; 3],
    /// The spindle's F/V converter output.
    pub spindle_fv_v: f64,
    /// Spindle speed.
    pub spindle_speed_rpm: f64,
    /// Programmed spindle speed.
    pub spindle_command_rpm: f64,
    /// The block's programmed feed.
    pub programmed_feed_mm_min: f64,
    /// Actual path feed.
    pub feed_mm_min: f64,
    /// The override the machine applies.
    pub applied_override_pct: f64,
    /// The override the host commands (NaN when it does not hold the device).
    pub commanded_override_pct: f64,
    /// The latest control period's force estimate (closed loop only).
    pub force_est_n: f64,
    /// The safety envelope had armed at that period's end: before, the estimate reads the
    /// spindle's starting current, thousands of newtons of nothing (the chart leaves it out; the
    /// recording keeps it).
    pub envelope_armed: bool,
    /// The latest period's spindle RMS current (closed loop only).
    pub spindle_current_rms_a: f64,
    /// The latest period's feed RMS current (closed loop only).
    pub feed_current_rms_a: f64,
    /// The force the loop holds (closed loop only).
    pub target_force_n: f64,
    /// The resultant cutting force (a simulated device's truth; NaN otherwise).
    pub force_n: f64,
    /// The axial depth of cut (a simulated device's truth; NaN otherwise).
    pub depth_mm: f64,
    /// What the host was doing.
    pub phase: &'static str,
    /// The program ended with this sample.
    pub program_end: bool,
    /// Events since the previous row, `; `-separated (usually empty).
    pub event: String,
}

/// The columns, in file order; the last two are only in recordings of a simulated device.
pub const COLUMNS: [&str; 22] = [
    "time [s]",
    "part",
    "phase",
    "S_I_U [A]",
    "S_I_V [A]",
    "S_I_W [A]",
    "X_I_U [A]",
    "X_I_V [A]",
    "X_I_W [A]",
    "S_FV [V]",
    "S_speed [rpm]",
    "S_speed command [rpm]",
    "programmed feed [mm/min]",
    "feed [mm/min]",
    "override applied [%]",
    "override commanded [%]",
    "S_current_rms [A]",
    "X_current_rms [A]",
    "force estimate [N]",
    "event",
    "force (simulated) [N]",
    "depth (simulated) [mm]",
];

/// Columns present in every recording (the rest need a simulated device).
const COMMON_COLUMNS: usize = 20;

/// The header line of a recording.
///
/// ```
/// use cutlab::hardware::recording::csv_header;
/// assert_eq!(csv_header(false).split(',').count(), 20);
/// assert!(csv_header(true).starts_with("time [s],part,phase,S_I_U [A]"));
/// ```
pub fn csv_header(sim_truth: bool) -> String {
    let n = if sim_truth {
        COLUMNS.len()
    } else {
        COMMON_COLUMNS
    };
    let mut line = COLUMNS[..n].join(",");
    line.push('\n');
    line
}

/// Writes `value` with `decimals` digits, nothing for NaN or ±∞ (a gap to the reader).
fn number(out: &mut String, value: f64, decimals: usize) {
    if value.is_finite() {
        let _ = write!(out, "{value:.decimals$}");
    }
}

/// Writes `text` as a CSV field, quoted when it holds a comma, quote or line break.
fn text_field(out: &mut String, text: &str) {
    if text.contains([',', '"', '\n', '\r']) {
        out.push('"');
        out.push_str(&text.replace('"', "\"\""));
        out.push('"');
    } else {
        out.push_str(text);
    }
}

/// Appends `row` as one CSV line, its time measured from `start_s`.
pub fn write_row(out: &mut String, row: &LiveRow, start_s: f64, sim_truth: bool) {
    number(out, row.time_s - start_s, 6);
    let _ = write!(out, ",{},", row.part);
    text_field(out, row.phase);
    for i in row.spindle_currents_a.iter().chain(&row.feed_currents_a) {
        out.push(',');
        number(out, *i, 3);
    }
    for (value, decimals) in [
        (row.spindle_fv_v, 4),
        (row.spindle_speed_rpm, 2),
        (row.spindle_command_rpm, 2),
        (row.programmed_feed_mm_min, 2),
        (row.feed_mm_min, 2),
        (row.applied_override_pct, 2),
        (row.commanded_override_pct, 2),
        (row.spindle_current_rms_a, 4),
        (row.feed_current_rms_a, 4),
        (row.force_est_n, 2),
    ] {
        out.push(',');
        number(out, value, decimals);
    }
    out.push(',');
    text_field(out, &row.event);
    if sim_truth {
        out.push(',');
        number(out, row.force_n, 2);
        out.push(',');
        number(out, row.depth_mm, 4);
    }
    out.push('\n');
}

/// What the list of recordings shows, stored beside the chunks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecordingMeta {
    /// Unique key (milliseconds since 1970 at the start).
    pub id: u64,
    /// A name a person recognises.
    pub name: String,
    /// When it started, milliseconds since 1970.
    pub started_ms: f64,
    /// The device's identity and program.
    pub device: String,
    /// Samples per second.
    pub sample_rate_hz: f64,
    /// Whether it has the simulation's truth columns.
    pub sim_truth: bool,
    /// Rows stored so far.
    pub rows: u64,
    /// Chunks stored so far.
    pub chunks: u32,
    /// Device time it covers.
    pub duration_s: f64,
    /// Closed cleanly (the part ended, the link was lost or closed); false while it records, or
    /// after a reload or crash cut it short.
    pub finished: bool,
    /// How it ended.
    #[serde(default)]
    pub end: String,
    /// The run's metrics in a line, when a closed loop ended within it.
    #[serde(default)]
    pub summary: String,
}

impl RecordingMeta {
    /// Its JSON form (what the page stores).
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }

    /// Reads the JSON form back.
    pub fn from_json(text: &str) -> Result<Self, String> {
        serde_json::from_str(text).map_err(|e| format!("a recording's description: {e}"))
    }

    /// The file name an export gets.
    pub fn file_name(&self) -> String {
        let slug = crate::input::file_slug(&self.name);
        format!("cutlab-recording-{slug}.csv")
    }
}

/// Builds a recording's CSV text a row at a time and hands it out in chunks.
#[derive(Debug, Clone)]
pub struct Recorder {
    meta: RecordingMeta,
    start_s: Option<f64>,
    text: String,
    rows_in_text: u64,
}

impl Recorder {
    /// A recording described by `meta` (its counts start at zero); the first chunk will start
    /// with the header.
    pub fn new(mut meta: RecordingMeta) -> Self {
        meta.rows = 0;
        meta.chunks = 0;
        meta.duration_s = 0.0;
        meta.finished = false;
        Self {
            text: csv_header(meta.sim_truth),
            meta,
            start_s: None,
            rows_in_text: 0,
        }
    }

    /// What it is so far (counting the rows not yet taken).
    pub fn meta(&self) -> &RecordingMeta {
        &self.meta
    }

    /// Adds one row.
    pub fn push(&mut self, row: &LiveRow) {
        let start_s = *self.start_s.get_or_insert(row.time_s);
        write_row(&mut self.text, row, start_s, self.meta.sim_truth);
        self.rows_in_text += 1;
        self.meta.rows += 1;
        self.meta.duration_s = row.time_s - start_s;
    }

    /// Text waiting to be taken, bytes.
    pub fn pending_bytes(&self) -> usize {
        self.text.len()
    }

    /// The next chunk — its index and text — if there is anything to take.
    pub fn take_chunk(&mut self) -> Option<(u32, String)> {
        if self.text.is_empty() {
            return None;
        }
        let index = self.meta.chunks;
        self.meta.chunks += 1;
        self.rows_in_text = 0;
        Some((index, std::mem::take(&mut self.text)))
    }

    /// Sets the run's summary (a closed loop ended within it).
    pub fn set_summary(&mut self, summary: &str) {
        self.meta.summary = summary.to_string();
    }

    /// Marks it closed with `end` (its last chunk is still to be taken) and the run's summary.
    pub fn finish(&mut self, end: &str, summary: Option<String>) {
        self.meta.finished = true;
        self.meta.end = end.to_string();
        if let Some(s) = summary {
            self.meta.summary = s;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(time_s: f64) -> LiveRow {
        LiveRow {
            time_s,
            part: 1,
            spindle_currents_a: [1.0, -0.5, -0.5],
            feed_currents_a: [0.1, 0.2, -0.3],
            spindle_fv_v: 5.0,
            spindle_speed_rpm: 3000.0,
            spindle_command_rpm: 3000.0,
            programmed_feed_mm_min: 900.0,
            feed_mm_min: 850.0,
            applied_override_pct: 95.0,
            commanded_override_pct: f64::NAN,
            force_est_n: f64::NAN,
            envelope_armed: false,
            spindle_current_rms_a: f64::NAN,
            feed_current_rms_a: f64::NAN,
            target_force_n: f64::NAN,
            force_n: 120.0,
            depth_mm: 1.0,
            phase: "closed loop",
            program_end: false,
            event: String::new(),
        }
    }

    #[test]
    fn a_row_has_a_field_per_column_and_gaps_for_what_it_lacks() {
        let mut line = String::new();
        write_row(&mut line, &row(10.5), 10.0, true);
        let fields: Vec<&str> = line.trim_end().split(',').collect();
        assert_eq!(fields.len(), COLUMNS.len());
        assert_eq!(fields[0], "0.500000");
        assert_eq!(fields[15], "", "no command: a gap");
        line.clear();
        write_row(&mut line, &row(1.0), 0.0, false);
        assert_eq!(line.trim_end().split(',').count(), COMMON_COLUMNS);
    }

    #[test]
    fn an_event_with_a_comma_or_quote_is_quoted() {
        let mut r = row(0.0);
        r.event = "alarm: \"no sample\", disarm".to_string();
        let mut line = String::new();
        write_row(&mut line, &r, 0.0, false);
        assert!(
            line.ends_with(",\"alarm: \"\"no sample\"\", disarm\"\n"),
            "{line}"
        );
    }

    #[test]
    fn chunks_joined_are_the_header_and_every_row_in_order() {
        let meta = RecordingMeta {
            id: 1,
            name: "test".into(),
            started_ms: 0.0,
            device: "d".into(),
            sample_rate_hz: 1000.0,
            sim_truth: false,
            rows: 0,
            chunks: 0,
            duration_s: 0.0,
            finished: false,
            end: String::new(),
            summary: String::new(),
        };
        let mut recorder = Recorder::new(meta);
        let mut joined = String::new();
        for k in 0..25 {
            recorder.push(&row(f64::from(k) * 0.001));
            if k % 10 == 9 {
                let (index, text) = recorder.take_chunk().unwrap();
                assert_eq!(index, k / 10);
                joined.push_str(&text);
            }
        }
        recorder.finish("the part ended", None);
        joined.push_str(&recorder.take_chunk().unwrap().1);
        assert!(recorder.take_chunk().is_none());
        let lines: Vec<&str> = joined.lines().collect();
        assert_eq!(lines.len(), 26);
        assert_eq!(lines[0], csv_header(false).trim_end());
        assert!(lines[25].starts_with("0.024000,"));
        let m = recorder.meta();
        assert_eq!((m.rows, m.chunks, m.finished), (25, 3, true));
        assert!((m.duration_s - 0.024).abs() < 1e-12);
        assert_eq!(RecordingMeta::from_json(&m.to_json()).unwrap(), *m);
    }
}
