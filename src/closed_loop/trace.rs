//! What a closed-loop run records: one row per control period, plus the events.
//!
//! Rows carry every signal a user may want to plot, with units in the field names. Signals that
//! change within a control period (the raw phase current, the instantaneous force) are kept as
//! their minimum and maximum over the period, so a chart of the rows shows every peak without
//! storing every sample.

use serde::Serialize;

use crate::safety::SafetyEvent;

/// One control period of a run.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct TraceRow {
    /// Time at the end of the period.
    pub time_s: f64,
    /// Axial depth of cut at the tool (simulation only; NaN for a real machine).
    pub depth_mm: f64,
    /// Radial width of cut.
    pub width_mm: f64,
    /// Distance along the programmed path.
    pub path_position_mm: f64,
    /// Programmed feed of the current block.
    pub programmed_feed_mm_min: f64,
    /// Actual path feed.
    pub feed_mm_min: f64,
    /// Override the controller asked for.
    pub requested_override_pct: f64,
    /// Override the envelope commanded.
    pub override_pct: f64,
    /// Override the machine applied.
    pub applied_override_pct: f64,
    /// The regulated force quantity, true value (simulation only).
    pub force_n: f64,
    /// The regulated force quantity as estimated from current.
    pub force_est_n: f64,
    /// Paper 004's sensorless estimate: the network learned on the preset's trial cuts (or,
    /// without one, the published power law), from what the CNC knows of the cut.
    pub force_power_law_n: f64,
    /// Target force.
    pub target_force_n: f64,
    /// Minimum of the true instantaneous resultant force over the period.
    pub force_min_n: f64,
    /// Maximum of the true instantaneous resultant force over the period.
    pub force_max_n: f64,
    /// Spindle RMS current after the signal chain.
    pub spindle_current_rms_a: f64,
    /// Feed-drive RMS current after the signal chain.
    pub feed_current_rms_a: f64,
    /// Minimum of the raw feed phase current i_u over the period.
    pub feed_current_u_min_a: f64,
    /// Maximum of the raw feed phase current i_u over the period.
    pub feed_current_u_max_a: f64,
    /// Spindle speed.
    pub spindle_speed_rpm: f64,
    /// Material removal rate.
    pub material_removal_mm3_s: f64,
    /// Whether the controller was in charge.
    pub armed: bool,
    /// Whether a sensor fault was in force.
    pub sensor_fault: bool,
    /// Whether feed hold was latched.
    pub feed_hold: bool,
    /// The wall's error from the tool and spindle deflecting under the period's mean normal
    /// force, µm ([`crate::plant::deflection`]; NaN where the tool's stiffness or the force is
    /// not known, 0 in air).
    pub surface_error_um: f64,
    /// What is left of the surface error once paper 004's compensator offsets the tool path by
    /// the error the power law predicts from what the CNC knows of the cut (sensorless), µm.
    pub compensated_error_power_law_um: f64,
    /// What is left of it once the offset is predicted from the current-based estimate of the
    /// period before, µm (NaN where the feedback path does not estimate the in-plane resultant).
    pub compensated_error_current_um: f64,
    /// Whether the estimator's inputs lay inside its calibrated range.
    pub estimate_in_range: bool,
    /// Whether paper 004's sensor failure prediction flags the period: the current-based and
    /// the sensorless estimates disagree beyond their tolerance.
    pub sensor_failure_predicted: bool,
}

/// A whole run.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Trace {
    /// One row per control period.
    pub rows: Vec<TraceRow>,
    /// Safety events in time order.
    pub events: Vec<SafetyEvent>,
    /// Names and units of the controller's internal terms, in column order.
    pub term_names: Vec<(&'static str, &'static str)>,
    /// The controller's terms, `term_names.len()` values per row.
    pub terms: Vec<f64>,
    /// True if the program ran to its end (not stopped by feed hold or the time limit).
    pub completed: bool,
}

impl Trace {
    /// The values of term `index` over the run.
    pub fn term_series(&self, index: usize) -> impl Iterator<Item = f64> + '_ {
        let width = self.term_names.len().max(1);
        self.terms.iter().skip(index).step_by(width).copied()
    }
}

/// A numeric column of the trace CSV: its name (unit in the name) and the value it takes from a
/// row, side by side so the two cannot drift apart.
#[derive(Clone, Copy)]
pub struct CsvColumn<T> {
    /// Header name.
    pub name: &'static str,
    /// The row's value.
    pub value: fn(&TraceRow) -> T,
}

macro_rules! csv_columns {
    ($ty:ty; $($field:ident),+ $(,)?) => {
        [$(CsvColumn::<$ty> { name: stringify!($field), value: |r| r.$field }),+]
    };
}

/// The numeric columns [`write_csv`] writes, in order.
pub const CSV_COLUMNS: [CsvColumn<f64>; 20] = csv_columns![f64;
    time_s,
    depth_mm,
    width_mm,
    path_position_mm,
    programmed_feed_mm_min,
    feed_mm_min,
    requested_override_pct,
    override_pct,
    applied_override_pct,
    force_n,
    force_est_n,
    force_power_law_n,
    target_force_n,
    spindle_current_rms_a,
    feed_current_rms_a,
    spindle_speed_rpm,
    material_removal_mm3_s,
    surface_error_um,
    compensated_error_power_law_um,
    compensated_error_current_um,
];

/// The state flags [`write_csv`] writes after the values and terms, as 0/1.
pub const CSV_FLAG_COLUMNS: [CsvColumn<bool>; 5] = csv_columns![bool;
    armed,
    sensor_fault,
    feed_hold,
    estimate_in_range,
    sensor_failure_predicted,
];

fn csv_values(r: &TraceRow) -> impl Iterator<Item = String> + '_ {
    CSV_COLUMNS.iter().map(move |c| (c.value)(r).to_string())
}

fn csv_flags(r: &TraceRow) -> impl Iterator<Item = String> + '_ {
    CSV_FLAG_COLUMNS
        .iter()
        .map(move |c| u8::from((c.value)(r)).to_string())
}

/// Writes the trace as CSV with a header: the [`CSV_COLUMNS`], the controller's terms, and the
/// [`CSV_FLAG_COLUMNS`]. Numbers are written at full precision (shortest round-trip form).
pub fn write_csv(trace: &Trace, out: &mut dyn std::io::Write) -> std::io::Result<()> {
    let mut header: Vec<String> = CSV_COLUMNS.iter().map(|c| c.name.to_string()).collect();
    for (name, unit) in &trace.term_names {
        header.push(csv_term_header(name, unit));
    }
    header.extend(CSV_FLAG_COLUMNS.iter().map(|c| c.name.to_string()));
    writeln!(out, "{}", header.join(","))?;
    let width = trace.term_names.len();
    for (i, r) in trace.rows.iter().enumerate() {
        let mut line: Vec<String> = csv_values(r).collect();
        line.extend(
            trace
                .terms
                .iter()
                .skip(i * width)
                .take(width)
                .map(|v| v.to_string()),
        );
        line.extend(csv_flags(r));
        writeln!(out, "{}", line.join(","))?;
    }
    Ok(())
}

/// Writes several runs' traces as one CSV, a first `run` column naming each row's run: the
/// [`CSV_COLUMNS`] and [`CSV_FLAG_COLUMNS`] of every run, one after the other. The controllers'
/// terms are left out, since each controller has its own (one run's [`write_csv`] has them).
///
/// ```
/// use cutlab::closed_loop::trace::{write_csv_runs, Trace};
/// let mut out = Vec::new();
/// write_csv_runs(&[("A: fixed", &Trace::default())], &mut out).unwrap();
/// assert!(String::from_utf8(out).unwrap().starts_with("run,time_s,depth_mm,"));
/// ```
pub fn write_csv_runs(
    runs: &[(&str, &Trace)],
    out: &mut dyn std::io::Write,
) -> std::io::Result<()> {
    let mut header = vec!["run"];
    header.extend(CSV_COLUMNS.iter().map(|c| c.name));
    header.extend(CSV_FLAG_COLUMNS.iter().map(|c| c.name));
    writeln!(out, "{}", header.join(","))?;
    for (name, trace) in runs {
        let name = csv_field(name);
        for r in &trace.rows {
            let mut line = vec![name.clone()];
            line.extend(csv_values(r));
            line.extend(csv_flags(r));
            writeln!(out, "{}", line.join(","))?;
        }
    }
    Ok(())
}

/// A text field quoted as RFC 4180 wants when it holds a comma, a quote or a line break.
pub fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// A CSV-safe column name for a controller term: ASCII, lower case, with the unit.
fn csv_term_header(name: &str, unit: &str) -> String {
    let ascii: String = name
        .chars()
        .map(|c| match c {
            'β' => "beta".to_string(),
            'α' => "alpha".to_string(),
            'Δ' => "delta".to_string(),
            '−' => "minus".to_string(),
            '·' | ' ' | '_' => "_".to_string(),
            c if c.is_ascii_alphanumeric() => c.to_ascii_lowercase().to_string(),
            _ => String::new(),
        })
        .collect();
    let unit = match unit {
        "%" => "pct".to_string(),
        "" => String::new(),
        u => u
            .chars()
            .filter(|c| c.is_ascii_alphanumeric())
            .collect::<String>()
            .to_lowercase(),
    };
    let mut name = format!("term_{ascii}");
    if !unit.is_empty() {
        name.push('_');
        name.push_str(&unit);
    }
    name.replace("__", "_")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_has_a_header_the_required_columns_and_one_line_per_row() {
        let mut trace = Trace {
            rows: vec![TraceRow::default(); 3],
            term_names: vec![("β̂", "%"), ("E", "1/s")],
            terms: vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0],
            ..Trace::default()
        };
        trace.rows[1].time_s = 0.1;
        let mut out = Vec::new();
        write_csv(&trace, &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines.len(), 4);
        for required in [
            "time_s",
            "depth_mm",
            "feed_mm_min",
            "override_pct",
            "force_n",
            "force_est_n",
            "spindle_current_rms_a",
            "feed_current_rms_a",
        ] {
            assert!(lines[0].split(',').any(|c| c == required), "{required}");
        }
        assert!(lines[0].contains("term_beta_pct,term_e_1s"), "{}", lines[0]);
        assert!(lines[2].starts_with("0.1,"));
        assert_eq!(lines[2].split(',').count(), lines[0].split(',').count());
        let third: Vec<&str> = lines[3].split(',').collect();
        assert_eq!(third[CSV_COLUMNS.len()], "5");
    }

    #[test]
    fn term_series_reads_one_column() {
        let trace = Trace {
            term_names: vec![("a", ""), ("b", "")],
            terms: vec![1.0, 2.0, 3.0, 4.0],
            ..Trace::default()
        };
        assert_eq!(trace.term_series(1).collect::<Vec<_>>(), vec![2.0, 4.0]);
    }
}
