//! `cutlab calibrate FILE.csv`: fit the current-to-force models from a logged teach cut.
//!
//! Reads a CSV with a header line — the CSV `cutlab sim --csv` writes, or any log with the same
//! column names. The spindle model needs `spindle_current_rms_a` and `spindle_speed_rpm`, the
//! feed model `feed_current_rms_a` and `feed_mm_min`, and both a force:
//!
//! * measured: the `force_n` column (a dynamometer's |F̄|); the feed model uses a
//!   `feed_force_n` column if the log has one, else `force_n`, and says so;
//! * or, without a dynamometer, modelled from the cut: with `--material`, `--diameter-mm`,
//!   `--teeth` and `--mode`, each row's mean force comes from its `feed_mm_min`,
//!   `spindle_speed_rpm`, `depth_mm` and `width_mm` through the mechanistic model
//!   ([`crate::estimation::cut_forces`]), the resultant for the spindle model and the feed force
//!   for the feed model. If the log has `force_n` too, the report says how far the two differ.
//!
//! Rows without force (air cuts, force ≤ 0) are left out, as in the teach cut. Full import of
//! messy machine logs comes later; this reader is strict and says exactly where a file is wrong.

use std::fmt::Write as _;

use serde::Serialize;

use super::{help_text_for, wants_help, write_json, CliError, Io, OptionSpec, Options};
use crate::closed_loop::runner::GEAR_CHANGE_RPM;
use crate::estimation::current_force::{FeedCurrentModel, SpindleCurrentModel};
use crate::estimation::cut_forces::CutGeometry;
use crate::plant::materials::Material;
use crate::plant::mechanics::{Cutter, MillingMode, ToolForces};
use crate::signal::spectrum::{uniform_sample_rate_hz, SpectrumError, TIME_STEP_TOLERANCE};

const OPTIONS: &[OptionSpec] = &[
    OptionSpec::flag("json", "Print the fitted models as JSON"),
    OptionSpec::value(
        "gear-change-rpm",
        "RPM",
        "Spindle speed of the gear change (default 900, paper 003)",
    ),
    OptionSpec::value(
        "material",
        "NAME",
        "Model each row's force from its feed, speed, depth and width instead of force_n \
         (with --diameter-mm, --teeth, --mode; names as in cutlab force --help)",
    ),
    OptionSpec::value("diameter-mm", "D", "Cutter diameter, mm (with --material)"),
    OptionSpec::value("teeth", "Z", "Number of teeth (with --material)"),
    OptionSpec::value("mode", "up|down|slot", "Milling mode (with --material)"),
];

const GEOMETRY_OPTIONS: [&str; 3] = ["diameter-mm", "teeth", "mode"];

/// The cut from `--material` and its companions, if given, with a description for the report.
fn cut_geometry(options: &Options) -> Result<Option<(CutGeometry, String)>, CliError> {
    let Some(name) = options.text("material") else {
        if let Some(stray) = GEOMETRY_OPTIONS.iter().find(|o| options.flag(o)) {
            return Err(CliError::new(format!(
                "--{stray} only applies with --material (modelled forces)"
            )));
        }
        return Ok(None);
    };
    let material = Material::from_name(name).ok_or_else(|| {
        CliError::new(format!(
            "--material: unknown material {name:?}; materials: {}",
            Material::ALL.map(Material::name).join(", ")
        ))
    })?;
    let diameter_mm: f64 = options.require("diameter-mm")?;
    let teeth: u32 = options.require("teeth")?;
    let mode_text: String = options.require("mode")?;
    let mode = MillingMode::from_name(&mode_text).ok_or_else(|| {
        CliError::new(format!(
            "--mode: expected up, down or slot, got {mode_text:?}"
        ))
    })?;
    let cutter = Cutter::new(diameter_mm, teeth, 0.0)
        .map_err(|e| CliError::new(format!("--diameter-mm/--teeth: {e}")))?;
    let description = format!(
        "the mechanistic model (material {}, Ø{diameter_mm} mm, {teeth} teeth, {} milling)",
        material.name(),
        mode.name()
    );
    Ok(Some((
        CutGeometry {
            cutter,
            mode,
            coefficients: material.coefficients(),
        },
        description,
    )))
}

/// The forces the fits use, and where they came from.
struct Forces {
    resultant_n: Vec<f64>,
    feed_n: Vec<f64>,
    source: String,
    feed_source: String,
    /// RMS of (model − force_n) over rows where both cut, % of the mean force_n.
    model_vs_measured_pct: Option<f64>,
}

fn forces(
    table: &Table,
    geometry: Option<&(CutGeometry, String)>,
    file: &str,
) -> Result<Forces, CliError> {
    let measured = table.column("force_n");
    let Some((geometry, source)) = geometry else {
        let measured = measured.ok_or_else(|| {
            CliError::new(format!(
                "{file}: no \"force_n\" column (columns: {}); without a measured force, \
                 model it from the cut with --material, --diameter-mm, --teeth and --mode",
                table.header.join(", ")
            ))
        })?;
        let (feed_n, feed_source) = match table.column("feed_force_n") {
            Some(feed) => (feed.to_vec(), "the feed_force_n column".to_string()),
            None => (
                measured.to_vec(),
                "the force_n column (the log has no feed_force_n)".to_string(),
            ),
        };
        return Ok(Forces {
            resultant_n: measured.to_vec(),
            feed_n,
            source: "the force_n column".into(),
            feed_source,
            model_vs_measured_pct: None,
        });
    };
    let column = |name: &str| {
        table.column(name).ok_or_else(|| {
            CliError::new(format!(
                "{file}: modelled forces need a {name:?} column (columns: {})",
                table.header.join(", ")
            ))
        })
    };
    let (feed, speed, depth, width) = (
        column("feed_mm_min")?,
        column("spindle_speed_rpm")?,
        column("depth_mm")?,
        column("width_mm")?,
    );
    let rows = 0..feed.len();
    let modelled: Vec<Option<ToolForces>> = rows
        .map(|i| geometry.mean_forces(feed[i], speed[i], depth[i], width[i]))
        .collect();
    let resultant_n: Vec<f64> = modelled
        .iter()
        .map(|f| f.map_or(f64::NAN, |f| f.resultant_n()))
        .collect();
    let feed_n = modelled
        .iter()
        .map(|f| f.map_or(f64::NAN, |f| -f.fx_n))
        .collect();
    let model_vs_measured_pct = measured.and_then(|measured| {
        let pairs: Vec<(f64, f64)> = resultant_n
            .iter()
            .zip(measured)
            .filter(|(m, f)| **m > 0.0 && **f > 0.0 && f.is_finite())
            .map(|(m, f)| (*m, *f))
            .collect();
        let n = pairs.len() as f64;
        let mean = pairs.iter().map(|p| p.1).sum::<f64>() / n;
        let rms = (pairs.iter().map(|(m, f)| (m - f).powi(2)).sum::<f64>() / n).sqrt();
        (n > 0.0).then_some(100.0 * rms / mean)
    });
    Ok(Forces {
        resultant_n,
        feed_n,
        feed_source: format!("{source}, feed force −F̄x"),
        source: source.clone(),
        model_vs_measured_pct,
    })
}

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
    /// Where the spindle model's force came from.
    force_source: String,
    /// Where the feed model's force came from.
    feed_force_source: String,
    /// With modelled forces and a force_n column: RMS difference, % of the mean measured force.
    model_vs_measured_pct: Option<f64>,
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
            "cutlab calibrate FILE.csv [--json] [--gear-change-rpm RPM] \
             [--material NAME --diameter-mm D --teeth Z --mode up|down|slot]",
            "Fit paper 003's spindle-current model and paper 000's feed-current model from a\n\
             logged teach cut (e.g. the CSV of cutlab sim --csv) and report R², the residual\n\
             spread and the calibrated range. The force is the log's force_n column, or without\n\
             a dynamometer, modelled from each row's feed, speed, depth and width (--material).",
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
    let geometry = cut_geometry(&options)?;
    let forces = forces(&table, geometry.as_ref(), file)?;
    let force = forces.resultant_n.as_slice();
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
        force_source: forces.source.clone(),
        feed_force_source: forces.feed_source.clone(),
        model_vs_measured_pct: forces.model_vs_measured_pct,
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
            let rows = cutting_rows(&forces.feed_n, &[current, feed]);
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
    let mut out = format!(
        "{file}: {rows_with_force} rows with force, from {}\n",
        report.force_source
    );
    if let Some(pct) = report.model_vs_measured_pct {
        let _ = writeln!(
            out,
            "modelled force vs the log's force_n: RMS difference {pct:.1} % of the measured mean"
        );
    }
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
            "feed current → feed force (paper 000), against {}:\n  I = {:.4} A + {:.3e} A/(mm/min) · |v| + {:.6} A/N · F   \
             R² {:.5}, residual {:.3} A = {:.1} N, {} rows",
            report.feed_force_source,
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
