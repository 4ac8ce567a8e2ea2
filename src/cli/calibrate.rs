//! `cutlab calibrate FILE.csv`: fit the current-to-force models from a logged teach cut.
//!
//! Reads the file, hands the text to [`crate::log::period_log`] (which says what the log
//! must hold and fits both models), and prints the report or its JSON.

use std::fmt::Write as _;

use serde::Serialize;

use super::args::{required, value_or};
use super::{write_json, CliError, Io};
use crate::estimation::cut_forces::CutGeometry;
use crate::estimation::cut_settings::{parse_cut, CutSetting};
use crate::estimation::estimator::{Calibration, Feedback};
use crate::estimation::speed::GEAR_CHANGE_RPM;
use crate::log::period_log::{calibrate_log, LogCalibration, LogError, LogTable};

pub(crate) const ABOUT: &str =
    "Fit paper 003's spindle-current model and paper 000's feed-current model from a\n\
logged teach cut (e.g. the CSV of cutlab sim --csv) and report R², the residual\n\
spread and the calibrated range. The force is the log's force_n column, or without\n\
a dynamometer, modelled from each row's feed, speed, depth and width (--material).";

#[derive(Debug, clap::Args)]
pub struct CalibrateArgs {
    /// The CSV log of a teach cut
    #[arg(value_name = "FILE.csv")]
    files: Vec<String>,
    #[arg(long = "json", help = "Print the fitted models as JSON")]
    json: bool,
    #[command(flatten)]
    log: LogCalibrationArgs,
    #[arg(
        long = "save-calibration",
        help = "Write the fitted model as a calibration file that cutlab sim/host --calibration, \
         cutlab log replay --calibration and the browser read (the spindle model, or the feed \
         model with --feedback feed)",
        value_name = "FILE"
    )]
    save_calibration: Option<String>,
    #[arg(
        long = "feedback",
        help = "Which model --save-calibration writes: spindle (default when fitted) or feed",
        value_name = "spindle|feed"
    )]
    feedback: Option<String>,
}

/// How a logged teach cut is read: the options `cutlab calibrate` and `cutlab tune --teach-in
/// --log` share.
#[derive(Debug, clap::Args)]
#[command(next_help_heading = "Reading a logged teach cut")]
pub struct LogCalibrationArgs {
    #[arg(
        long = "gear-change-rpm",
        help = "Spindle speed of the gear change (default 900, paper 003)",
        value_name = "RPM",
        allow_hyphen_values = true
    )]
    gear_change_rpm: Option<String>,
    #[arg(
        long = "material",
        help = "Model each row's force from its feed, speed, depth and width instead of force_n \
         (with --diameter-mm, --teeth, --mode; names as in cutlab force --help)",
        value_name = "NAME",
        allow_hyphen_values = true
    )]
    material: Option<String>,
    #[arg(
        long = "diameter-mm",
        help = "Cutter diameter, mm (with --material)",
        value_name = "D",
        allow_hyphen_values = true
    )]
    diameter_mm: Option<String>,
    #[arg(
        long = "teeth",
        help = "Number of teeth (with --material)",
        value_name = "Z",
        allow_hyphen_values = true
    )]
    teeth: Option<String>,
    #[arg(
        long = "mode",
        help = "Milling mode (with --material)",
        value_name = "up|down|slot",
        allow_hyphen_values = true
    )]
    mode: Option<String>,
    #[arg(
        long = "map",
        help = "Read a calibration column from another column of the file (ROLE=COLUMN, repeatable; \
         roles: time_s, force_n, feed_force_n, spindle_current_rms_a, spindle_speed_rpm, \
         feed_current_rms_a, feed_mm_min, depth_mm, width_mm, and override_pct for a teach-in)",
        value_name = "ROLE=COLUMN"
    )]
    map: Vec<String>,
}

const GEOMETRY_OPTIONS: [&str; 3] = ["diameter-mm", "teeth", "mode"];

impl LogCalibrationArgs {
    /// The options given, as typed (`--map`, …), for refusing them where they do not apply.
    pub fn given(&self) -> Vec<&'static str> {
        [
            ("--gear-change-rpm", self.gear_change_rpm.is_some()),
            ("--material", self.material.is_some()),
            ("--diameter-mm", self.diameter_mm.is_some()),
            ("--teeth", self.teeth.is_some()),
            ("--mode", self.mode.is_some()),
            ("--map", !self.map.is_empty()),
        ]
        .into_iter()
        .filter_map(|(name, given)| given.then_some(name))
        .collect()
    }

    /// `--gear-change-rpm`, checked.
    pub fn gear_change_rpm(&self) -> Result<f64, CliError> {
        let rpm: f64 = value_or("gear-change-rpm", &self.gear_change_rpm, GEAR_CHANGE_RPM)?;
        if !(rpm.is_finite() && rpm > 0.0) {
            return Err(CliError::new(format!(
                "--gear-change-rpm: must be a positive speed, got {}",
                crate::input::readable(rpm)
            )));
        }
        Ok(rpm)
    }

    /// The `--map ROLE=COLUMN` pairs.
    pub fn map(&self) -> Result<Vec<(String, String)>, CliError> {
        self.map
            .iter()
            .map(|m| {
                m.split_once('=')
                    .map(|(role, column)| (role.trim().to_string(), column.trim().to_string()))
                    .ok_or_else(|| {
                        CliError::new(format!("--map: {m:?} is not of the form ROLE=COLUMN"))
                    })
            })
            .collect()
    }

    /// The cut from `--material` and its companions, if given, with a description for the
    /// report: through the cut table's rows, as the Logs page's modelled force.
    pub fn geometry(&self) -> Result<Option<(CutGeometry, String)>, CliError> {
        let Some(material) = self.material.as_deref() else {
            let given = [&self.diameter_mm, &self.teeth, &self.mode].map(Option::is_some);
            if let Some((stray, _)) = GEOMETRY_OPTIONS.iter().zip(given).find(|(_, g)| *g) {
                return Err(CliError::new(format!(
                    "--{stray} only applies with --material (modelled forces)"
                )));
            }
            return Ok(None);
        };
        // Each needed with --material: the page's defaults are no guess to make for a log.
        let diameter: String = required("diameter-mm", &self.diameter_mm)?;
        let teeth: String = required("teeth", &self.teeth)?;
        let mode: String = required("mode", &self.mode)?;
        let texts = [
            (CutSetting::Material, material),
            (CutSetting::Diameter, diameter.as_str()),
            (CutSetting::Teeth, teeth.as_str()),
            (CutSetting::Mode, mode.as_str()),
        ];
        let cut = parse_cut(&texts).map_err(|errors| match errors.first() {
            Some(e) => CliError::new(e.for_cli()),
            None => CliError::new("--material: the cut was refused"),
        })?;
        let description = format!("the mechanistic model ({})", cut.describe());
        Ok(Some((cut.geometry, description)))
    }
}

/// Reads `file` with the messy-log reader (any delimiter, decimal comma, quotes, damaged lines
/// kept as gaps); a file without data rows is refused ([`crate::log::load`] says so).
pub fn read_log(file: &str) -> Result<crate::log::Log, CliError> {
    let bytes =
        std::fs::read(file).map_err(|e| CliError::new(format!("{file}: cannot read: {e}")))?;
    crate::log::load(&bytes, None).map_err(|e| CliError::new(format!("{file}: {e}")))
}

/// One problem of a file as a note line: `note: line 12, Force [N]: …`.
pub fn problem_note(p: &crate::log::LineProblem) -> String {
    format!(
        "note: line {}{}: {}\n",
        p.line,
        p.column
            .as_deref()
            .map_or(String::new(), |c| format!(", {c}")),
        p.message
    )
}

/// Notes on the log reader's problems (damaged lines kept as gaps), at most five lines.
pub fn problem_notes(log: &crate::log::Log) -> String {
    let mut out = String::new();
    for p in log.problems.iter().take(5) {
        out.push_str(&problem_note(p));
    }
    if log.problems.len() > 5 {
        out.push_str(&format!(
            "note: … and {} more problems (see --json)\n",
            log.problems.len() - 5 + log.problems_not_listed
        ));
    }
    out
}

/// The forces the fits use, and where they came from.
/// The JSON report: the file and what the calibration found.
#[derive(Serialize)]
struct JsonReport<'a> {
    file: &'a str,
    #[serde(flatten)]
    report: &'a LogCalibration,
    /// What the log reader found wrong (damaged lines kept as gaps), by line and column.
    log_problems: &'a [crate::log::LineProblem],
}

/// Runs `cutlab calibrate`.
pub fn run(args: CalibrateArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    let [file] = args.files.as_slice() else {
        return Err(CliError::new("name exactly one CSV file to calibrate from"));
    };
    let gear_change_rpm = args.log.gear_change_rpm()?;
    let map = args.log.map()?;
    let log = read_log(file)?;
    let in_file = |e: LogError| CliError::new(format!("{file}: {e}"));
    let table =
        LogTable::from_log(&log, &map).map_err(|e| CliError::new(format!("{file}: {e}")))?;
    let geometry = args.log.geometry()?;
    let report = calibrate_log(
        &table,
        geometry.as_ref().map(|(g, source)| (g, source.as_str())),
        gear_change_rpm,
    )
    .map_err(in_file)?;
    let rows_with_force = report.rows_with_force;
    if let Some(path) = args.save_calibration.as_deref() {
        let (calibration, which) = saved_calibration(&report, args.feedback.as_deref())?;
        super::save_calibration(
            path,
            &calibration,
            format!(
                "cutlab calibrate {file}, {which} model, force from {}",
                report.force_source
            ),
        )?;
    } else if args.feedback.is_some() {
        return Err(CliError::new(
            "--feedback only applies with --save-calibration",
        ));
    }
    if args.json {
        return write_json(
            io.stdout,
            &JsonReport {
                file,
                report: &report,
                log_problems: &log.problems,
            },
        );
    }
    let mut out = format!(
        "{file}: {rows_with_force} rows with force, from {}\n",
        report.force_source
    );
    let negative = report.negative_force;
    if negative.rows > 0 {
        let _ = writeln!(
            out,
            "note: {} rows with a negative force left out (the first on line {}, down to {} N): \
             the fit reads a force's magnitude, so a negative one is a flipped sign or a damaged \
             value",
            negative.rows,
            negative.first_line,
            crate::input::readable(negative.lowest_n)
        );
    }
    out.push_str(&problem_notes(&log));
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
    for warning in &report.warnings {
        let _ = writeln!(out, "warning: {warning}");
    }
    io.stdout.write_all(out.as_bytes())?;
    Ok(())
}

/// The calibration a fitted log makes: the spindle model's unless `feedback` says feed (or only
/// the feed model was fitted), as the teach-cut fit made it (a log of a speed column has no
/// converter voltage: the estimator reads the speed itself).
fn saved_calibration(
    report: &LogCalibration,
    feedback: Option<&str>,
) -> Result<(Calibration, &'static str), CliError> {
    let feedback = match feedback.map(str::trim) {
        None if report.spindle.is_none() => Feedback::FeedCurrent,
        None | Some("spindle") => Feedback::SpindleCurrent,
        Some("feed") => Feedback::FeedCurrent,
        Some(other) => {
            return Err(CliError::new(format!(
                "--feedback: expected spindle or feed, got {other:?}"
            )))
        }
    };
    let fit = report
        .fit_of(feedback)
        .map_err(|e| CliError::new(format!("--save-calibration: {e}")))?;
    Ok((fit.calibration.clone(), feedback.name()))
}
