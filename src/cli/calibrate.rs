//! `cutlab calibrate FILE.csv`: fit the current-to-force models from a logged teach cut.
//!
//! Reads a CSV with a header line and at least a force column and one current column — the CSV
//! `cutlab sim --csv` writes, or any log with the same column names. The spindle model needs
//! `spindle_current_rms_a`, `spindle_speed_rpm` and `force_n`; the feed model
//! `feed_current_rms_a`, `feed_mm_min` and `force_n`. Rows without force (air cuts, `force_n`
//! ≤ 0) are left out, as in the teach cut. Full import of messy machine logs comes later; this
//! reader is strict and says exactly where a file is wrong.

use std::fmt::Write as _;

use serde::Serialize;

use super::{help_text_for, wants_help, write_json, CliError, Io, OptionSpec, Options};
use crate::closed_loop::runner::GEAR_CHANGE_RPM;
use crate::estimation::current_force::{FeedCurrentModel, SpindleCurrentModel};
use crate::signal::spectrum::{uniform_sample_rate_hz, SpectrumError, TIME_STEP_TOLERANCE};

const OPTIONS: &[OptionSpec] = &[
    OptionSpec::flag("json", "Print the fitted models as JSON"),
    OptionSpec::value(
        "gear-change-rpm",
        "RPM",
        "Spindle speed of the gear change (default 900, paper 003)",
    ),
];

/// The numeric columns of a CSV, by name.
struct Table {
    header: Vec<String>,
    columns: Vec<Vec<f64>>,
    /// The file line (from 1) of each data row: blank lines are skipped.
    row_lines: Vec<usize>,
}

impl Table {
    fn parse(text: &str, file: &str) -> Result<Self, CliError> {
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty());
        let Some((header_index, header_line)) = lines.next() else {
            return Err(CliError::new(format!("{file}: the file is empty")));
        };
        let header: Vec<String> = header_line
            .split(',')
            .map(|h| h.trim().trim_matches('"').to_string())
            .collect();
        for (i, name) in header.iter().enumerate() {
            if header[..i].contains(name) {
                return Err(CliError::new(format!(
                    "{file}: line {}: column {name:?} appears twice; which one to fit is ambiguous",
                    header_index + 1
                )));
            }
        }
        let mut columns = vec![Vec::new(); header.len()];
        let mut row_lines = Vec::new();
        for (index, line) in lines {
            row_lines.push(index + 1);
            let cells: Vec<&str> = line.split(',').collect();
            if cells.len() != header.len() {
                return Err(CliError::new(format!(
                    "{file}: line {}: {} fields, the header has {}",
                    index + 1,
                    cells.len(),
                    header.len()
                )));
            }
            for ((cell, column), name) in cells.iter().zip(&mut columns).zip(&header) {
                let value = cell.trim().parse::<f64>().map_err(|_| {
                    CliError::new(format!(
                        "{file}: line {}, column {name:?}: cannot parse {:?} as a number",
                        index + 1,
                        cell.trim()
                    ))
                })?;
                column.push(value);
            }
        }
        Ok(Self {
            header,
            columns,
            row_lines,
        })
    }

    /// The file line of data row `row` (from 0).
    fn line_of_row(&self, row: usize) -> usize {
        self.row_lines.get(row).copied().unwrap_or(0)
    }

    fn column(&self, name: &str) -> Option<&[f64]> {
        self.header
            .iter()
            .position(|h| h == name)
            .map(|i| self.columns[i].as_slice())
    }
}

#[derive(Serialize)]
struct Report {
    file: String,
    rows_with_force: usize,
    /// The log's sampling, from its `time_s` column: even steps and their rate, or where the
    /// steps are uneven (the fit itself does not need even steps, but a reader of the log does).
    time_steps: Option<String>,
    spindle: Option<SpindleCurrentModel>,
    spindle_error: Option<String>,
    feed: Option<FeedCurrentModel>,
    feed_error: Option<String>,
}

/// Keeps the rows of `columns` where `force` is finite and positive.
fn cutting_rows(force: &[f64], columns: &[&[f64]]) -> Vec<Vec<f64>> {
    let keep: Vec<usize> = (0..force.len())
        .filter(|&i| force[i].is_finite() && force[i] > 0.0)
        .collect();
    std::iter::once(force)
        .chain(columns.iter().copied())
        .map(|c| keep.iter().map(|&i| c[i]).collect())
        .collect()
}

/// Runs `cutlab calibrate`.
pub fn run(args: &[String], io: &mut Io<'_>) -> Result<(), CliError> {
    if wants_help(args) {
        return help_text_for(
            io,
            "cutlab calibrate FILE.csv [--json] [--gear-change-rpm RPM]",
            "Fit paper 003's spindle-current model and paper 000's feed-current model from a\n\
             logged teach cut (e.g. the CSV of cutlab sim --csv) and report R², the residual\n\
             spread and the calibrated range.",
            OPTIONS,
        );
    }
    let options = Options::parse(args, OPTIONS)?;
    let [file] = options.positionals() else {
        return Err(CliError::new("name exactly one CSV file to calibrate from"));
    };
    let gear_change_rpm: f64 = options.get_or("gear-change-rpm", GEAR_CHANGE_RPM)?;
    if !(gear_change_rpm.is_finite() && gear_change_rpm > 0.0) {
        return Err(CliError::new(format!(
            "--gear-change-rpm: must be a positive speed, got {gear_change_rpm}"
        )));
    }
    let text = std::fs::read_to_string(file)
        .map_err(|e| CliError::new(format!("{file}: cannot read: {e}")))?;
    let table = Table::parse(&text, file)?;
    let force = table.column("force_n").ok_or_else(|| {
        CliError::new(format!(
            "{file}: no \"force_n\" column (columns: {})",
            table.header.join(", ")
        ))
    })?;
    let rows_with_force = force.iter().filter(|f| f.is_finite() && **f > 0.0).count();

    let time_steps = table.column("time_s").map(|times| {
        match uniform_sample_rate_hz(times, TIME_STEP_TOLERANCE) {
            Ok(rate_hz) => format!("even, {:.6} s ({rate_hz:.4} Hz)", 1.0 / rate_hz),
            // The error counts time stamps from 0; say where in the file (data from line 2).
            Err(SpectrumError::UnevenTimeSteps {
                index,
                step_s,
                median_step_s,
                ..
            }) => format!(
                "uneven: the step to line {} (time_s {}) is {step_s:.6} s, the median step \
                 {median_step_s:.6} s (a short last row is a period the program ended in)",
                table.line_of_row(index),
                times[index]
            ),
            Err(e) => format!("not usable: {e}"),
        }
    });
    let mut report = Report {
        file: file.clone(),
        rows_with_force,
        time_steps,
        spindle: None,
        spindle_error: None,
        feed: None,
        feed_error: None,
    };
    match (
        table.column("spindle_current_rms_a"),
        table.column("spindle_speed_rpm"),
    ) {
        (Some(current), Some(speed)) => {
            let rows = cutting_rows(force, &[current, speed]);
            match SpindleCurrentModel::calibrate(&rows[1], &rows[2], &rows[0], gear_change_rpm) {
                Ok(m) => report.spindle = Some(m),
                Err(e) => report.spindle_error = Some(e.to_string()),
            }
        }
        _ => {
            report.spindle_error =
                Some("needs columns spindle_current_rms_a and spindle_speed_rpm".into())
        }
    }
    match (
        table.column("feed_current_rms_a"),
        table.column("feed_mm_min"),
    ) {
        (Some(current), Some(feed)) => {
            let rows = cutting_rows(force, &[current, feed]);
            match FeedCurrentModel::calibrate(&rows[1], &rows[2], &rows[0]) {
                Ok(m) => report.feed = Some(m),
                Err(e) => report.feed_error = Some(e.to_string()),
            }
        }
        _ => report.feed_error = Some("needs columns feed_current_rms_a and feed_mm_min".into()),
    }
    if report.spindle.is_none() && report.feed.is_none() {
        return Err(CliError::new(format!(
            "{file}: no model could be fitted: spindle: {}; feed: {}",
            report.spindle_error.as_deref().unwrap_or("-"),
            report.feed_error.as_deref().unwrap_or("-")
        )));
    }
    if options.flag("json") {
        return write_json(io.stdout, &report);
    }
    let mut out = format!("{file}: {rows_with_force} rows with force\n");
    if let Some(steps) = &report.time_steps {
        let _ = writeln!(out, "time steps: {steps}");
    }
    if let Some(m) = &report.spindle {
        out.push_str("spindle current → force (paper 003), per speed:\n");
        for r in &m.rows {
            let _ = writeln!(
                out,
                "  {:7.1} rpm: I = {:.4} A + {:.6} A/N · F   R² {:.5}, residual {:.3} A = {:.1} N, \
                 {} rows, current {:.3}–{:.3} A",
                r.speed_rpm,
                r.idle_current_a,
                r.sensitivity_a_per_n,
                r.quality.r_squared,
                r.quality.residual_std_a,
                r.quality.residual_std_n,
                r.quality.samples,
                r.current_range_a.min,
                r.current_range_a.max
            );
        }
    } else if let Some(e) = &report.spindle_error {
        let _ = writeln!(out, "spindle model: not fitted: {e}");
    }
    if let Some(m) = &report.feed {
        let _ = writeln!(
            out,
            "feed current → feed force (paper 000):\n  I = {:.4} A + {:.3e} A/(mm/min) · |v| + {:.6} A/N · F   \
             R² {:.5}, residual {:.3} A = {:.1} N, {} rows",
            m.idle_current_a,
            m.idle_current_a_per_mm_min,
            m.sensitivity_a_per_n,
            m.quality.r_squared,
            m.quality.residual_std_a,
            m.quality.residual_std_n,
            m.quality.samples
        );
    } else if let Some(e) = &report.feed_error {
        let _ = writeln!(out, "feed model: not fitted: {e}");
    }
    io.stdout.write_all(out.as_bytes())?;
    Ok(())
}
