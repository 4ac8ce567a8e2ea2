//! Calibration from a log whose rows are control periods: the CSV `cutlab sim --csv` writes (a
//! teach cut's or a run's trace), or any log with the same column names (or mapped to them) →
//! paper 003's spindle-current model and paper 000's feed-current model, each through the one
//! teach-cut fit ([`crate::estimation::teach_fit`]), with the quality of each.
//!
//! The spindle model needs `spindle_current_rms_a` and `spindle_speed_rpm`, the feed model
//! `feed_current_rms_a` and `feed_mm_min`, and both a force:
//!
//! * measured: the `force_n` column (a dynamometer's |F̄|); the feed model uses a `feed_force_n`
//!   column if the log has one, else `force_n`, and says so;
//! * or, without a dynamometer, modelled from the cut ([`CutGeometry`]): each row's mean force
//!   from its `feed_mm_min`, `spindle_speed_rpm`, `depth_mm` and `width_mm`, the resultant for
//!   the spindle model and the feed force for the feed model. If the log has `force_n` too, the
//!   report says how far the two differ.
//!
//! The rows are selected as a teach cut's periods are: the spindle's speed steady, half a second
//! past an override change (from `override_pct` and `time_s`, where the log has them), the axes
//! feeding, a positive force, and with a modelled force not in air. Messy machine logs are read by
//! the log reader ([`crate::log`]) first; nothing here panics on any input.

use std::fmt;

use serde::Serialize;

use crate::estimation::current_force::{FeedCurrentModel, SpindleCurrentModel};
use crate::estimation::cut_forces::CutGeometry;
use crate::estimation::estimator::Feedback;
use crate::estimation::teach_fit::{fit, ForceOrigin, TeachFit, TeachPeriod};
use crate::plant::mechanics::ToolForces;
use crate::signal::chain::PeriodSummary;
use crate::signal::spectrum::{uniform_sample_rate_hz, SpectrumError, TIME_STEP_TOLERANCE};
use crate::signal::stats::median;

/// Magnitudes beyond this in a column the fit uses are no physical current, speed or force; a
/// least-squares fit over them would overflow (1e200 squared) and report nonsense.
pub const MAX_FIT_MAGNITUDE: f64 = 1e12;

/// Why a log could not be read or fitted; the message says where.
#[derive(Debug, Clone, PartialEq)]
pub enum LogError {
    /// A value the fit would use is beyond any physical magnitude.
    Absurd {
        /// File line, from 1.
        line: usize,
        /// Its column.
        column: String,
        /// The value.
        value: f64,
    },
    /// A column the calibration needs is missing.
    MissingColumn {
        /// The column.
        name: &'static str,
        /// Why it is needed.
        purpose: &'static str,
        /// The columns the log has.
        columns: Vec<String>,
    },
    /// No row has a positive force: nothing to pair a current with.
    NoPositiveForce {
        /// Where the force came from (the report's `force_source`).
        source: String,
        /// The rows.
        rows: usize,
        /// The rows whose force is negative.
        negative: NegativeForces,
    },
    /// Neither model could be fitted.
    NoModel {
        /// Why the spindle model failed.
        spindle: String,
        /// Why the feed model failed.
        feed: String,
    },
}

impl fmt::Display for LogError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LogError::Absurd {
                line,
                column,
                value,
            } => write!(
                f,
                "line {line}, column {column:?}: {value:e} is beyond any physical value \
                 (|value| ≤ {MAX_FIT_MAGNITUDE:e})"
            ),
            LogError::MissingColumn {
                name,
                purpose,
                columns,
            } => write!(
                f,
                "no {name:?} column (the file's columns: {}); {purpose}",
                some_names(columns)
            ),
            LogError::NoPositiveForce {
                source,
                rows,
                negative,
            } => {
                write!(f, "no row has a positive force ({source}): ")?;
                if negative.rows == 0 {
                    write!(f, "each of its {rows} rows is zero or missing")?;
                } else {
                    write!(
                        f,
                        "{} of its {rows} rows are negative (from line {}, down to {} N)",
                        negative.rows,
                        negative.first_line,
                        crate::input::readable(negative.lowest_n)
                    )?;
                }
                write!(
                    f,
                    "; the fit pairs each current with the force's magnitude, so it needs rows \
                     cut with a positive force{}",
                    if negative.rows * 2 > *rows {
                        " (a force mostly negative is a dynamometer's sign flipped: negate the \
                         column)"
                    } else {
                        ""
                    }
                )
            }
            LogError::NoModel { spindle, feed } => write!(
                f,
                "no model could be fitted: spindle: {spindle}; feed: {feed}"
            ),
        }
    }
}

impl std::error::Error for LogError {}

/// The first few of `names` for a message, and how many there are in all: a file with ten
/// thousand columns must not make a ten-thousand-name error.
pub(crate) fn some_names(names: &[String]) -> String {
    const SHOWN: usize = 12;
    match names.len() {
        0 => "none".to_string(),
        n if n <= SHOWN => names.join(", "),
        n => format!("{}, … ({n} in all)", names[..SHOWN].join(", ")),
    }
}

/// The columns calibration reads, by their names in cutlab's own logs (`override_pct` only by
/// a teach-in, to find the rows cut at 100 %).
pub const CALIBRATION_COLUMNS: [&str; 10] = [
    "time_s",
    "force_n",
    "feed_force_n",
    "spindle_current_rms_a",
    "spindle_speed_rpm",
    "feed_current_rms_a",
    "feed_mm_min",
    "depth_mm",
    "width_mm",
    "override_pct",
];

/// The numeric columns of a CSV log, by name.
#[derive(Debug, Clone, PartialEq)]
pub struct LogTable {
    /// Every column of the file, by name (for messages).
    file_columns: Vec<String>,
    header: Vec<String>,
    columns: Vec<Vec<f64>>,
    /// The file line (from 1) of each data row: blank lines are skipped.
    row_lines: Vec<usize>,
}

impl LogTable {
    /// The columns calibration reads from `log` (a messy file read by [`crate::log`]): each
    /// of [`CALIBRATION_COLUMNS`] from the column `map` names for it (`ROLE=COLUMN`, as typed
    /// after `--map`), else from a column of that very name. Only numeric columns can be
    /// mapped.
    ///
    /// ```
    /// use cutlab::log::period_log::LogTable;
    /// let log = cutlab::log::load(b"t;F [N];I [A]\n0;1,5;2\n0,1;2,5;3\n", None).unwrap();
    /// let map = [("force_n".to_string(), "F [N]".to_string())];
    /// let t = LogTable::from_log(&log, &map).unwrap();
    /// assert_eq!(t.column("force_n"), Some(&[1.5, 2.5][..]));
    /// assert!(LogTable::from_log(&log, &[("torque".into(), "F [N]".into())]).unwrap_err()
    ///     .contains("force_n"));
    /// ```
    pub fn from_log(log: &super::Log, map: &[(String, String)]) -> Result<Self, String> {
        for (role, column) in map {
            if !CALIBRATION_COLUMNS.contains(&role.as_str()) {
                return Err(format!(
                    "--map: unknown role {role:?}; roles: {}",
                    CALIBRATION_COLUMNS.join(", ")
                ));
            }
            if !log.columns.iter().any(|c| &c.name == column) {
                let names: Vec<String> = log.columns.iter().map(|c| c.name.clone()).collect();
                return Err(format!(
                    "--map {role}={column}: no such column; columns: {}",
                    some_names(&names)
                ));
            }
        }
        let mut header = Vec::new();
        let mut columns = Vec::new();
        let mut read: Vec<(&str, &str)> = Vec::new();
        for role in CALIBRATION_COLUMNS {
            let source = map
                .iter()
                .find(|(r, _)| r == role)
                .map_or(role, |(_, c)| c.as_str());
            // One column read as two quantities fits a line of itself (I = 0 + 1·F, R² 1).
            if let Some((other, _)) = read.iter().find(|(_, c)| *c == source) {
                return Err(format!(
                    "{other} and {role} would both be read from column {source:?}; a column can \
                     be only one of them: map the other to a column of its own"
                ));
            }
            let same_name = log.columns.iter().filter(|c| c.name == source).count();
            if same_name > 1 {
                return Err(format!(
                    "{same_name} columns are named {source:?}: which one is {role} is ambiguous; \
                     rename one in the file"
                ));
            }
            let column = log.columns.iter().find(|c| c.name == source).or_else(|| {
                // The time axis is the reader's time column (in seconds) unless one is mapped.
                (role == "time_s" && source == role)
                    .then(|| log.time_column.and_then(|t| log.columns.get(t)))
                    .flatten()
            });
            if let Some(column) = column {
                if column.values.len() != log.rows {
                    return Err(format!(
                        "column {source:?} holds no numbers, so it cannot be {role}"
                    ));
                }
                header.push(role.to_string());
                columns.push(column.values.clone());
                read.push((role, source));
            }
        }
        Ok(Self {
            file_columns: log.columns.iter().map(|c| c.name.clone()).collect(),
            header,
            columns,
            row_lines: log.row_lines.iter().map(|&l| l as usize).collect(),
        })
    }

    /// The column names, in file order.
    pub fn header(&self) -> &[String] {
        &self.header
    }

    /// The file line of data row `row` (from 0).
    pub fn line_of_row(&self, row: usize) -> usize {
        self.row_lines.get(row).copied().unwrap_or(0)
    }

    /// The values of column `name`.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.header
            .iter()
            .position(|h| h == name)
            .and_then(|i| self.columns.get(i))
            .map(Vec::as_slice)
    }

    /// Column `name` with every value checked against [`MAX_FIT_MAGNITUDE`].
    fn fit_column(&self, name: &str) -> Result<Option<&[f64]>, LogError> {
        let Some(values) = self.column(name) else {
            return Ok(None);
        };
        if let Some(row) = values.iter().position(|v| v.abs() > MAX_FIT_MAGNITUDE) {
            return Err(LogError::Absurd {
                line: self.line_of_row(row),
                column: name.to_string(),
                value: values[row],
            });
        }
        Ok(Some(values))
    }

    fn required(&self, name: &'static str, purpose: &'static str) -> Result<&[f64], LogError> {
        self.fit_column(name)?
            .ok_or_else(|| LogError::MissingColumn {
                name,
                purpose,
                columns: self.file_columns.clone(),
            })
    }
}

struct Forces {
    resultant_n: Vec<f64>,
    feed_n: Vec<f64>,
    source: String,
    feed_source: String,
    model_vs_measured_pct: Option<f64>,
}

/// The forces of each row: measured, or modelled from the cut by `geometry` (described by
/// `geometry_source` in the report).
fn forces(table: &LogTable, geometry: Option<(&CutGeometry, &str)>) -> Result<Forces, LogError> {
    let measured = table.fit_column("force_n")?;
    let Some((geometry, source)) = geometry else {
        let measured = measured.ok_or_else(|| LogError::MissingColumn {
            name: "force_n",
            purpose: "without a measured force, model it from the cut (--material, \
                      --diameter-mm, --teeth and --mode)",
            columns: table.file_columns.clone(),
        })?;
        let (feed_n, feed_source) = match table.fit_column("feed_force_n")? {
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
    const PURPOSE: &str = "modelled forces need the cut's feed, speed, depth and width";
    let (feed, speed, depth, width) = (
        table.required("feed_mm_min", PURPOSE)?,
        table.required("spindle_speed_rpm", PURPOSE)?,
        table.required("depth_mm", PURPOSE)?,
        table.required("width_mm", PURPOSE)?,
    );
    let modelled: Vec<Option<ToolForces>> = (0..feed.len())
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
        source: source.to_string(),
        model_vs_measured_pct,
    })
}

/// The rows of `table` as the control periods of a teach cut, each with its force from `force`
/// (the resultant for the spindle model, the feed force for the feed model).
fn periods(table: &LogTable, force: &[f64], forces: &Forces) -> Result<Vec<TeachPeriod>, LogError> {
    let column = |name: &str| table.fit_column(name);
    let (time, override_pct) = (column("time_s")?, column("override_pct")?);
    let (speed, feed) = (column("spindle_speed_rpm")?, column("feed_mm_min")?);
    let spindle_current = column("spindle_current_rms_a")?;
    let feed_current = column("feed_current_rms_a")?;
    let (depth, width) = (column("depth_mm")?, column("width_mm")?);
    let at = |c: Option<&[f64]>, i: usize| c.and_then(|c| c.get(i).copied()).unwrap_or(f64::NAN);
    let mut periods = Vec::with_capacity(force.len());
    let mut changed_s = f64::NEG_INFINITY;
    let mut previous_pct = f64::NAN;
    for (i, &force_n) in force.iter().enumerate() {
        let time_s = time.map_or(i as f64, |t| t.get(i).copied().unwrap_or(f64::NAN));
        // A log without an override column ran the program as written.
        let pct = override_pct.map_or(100.0, |o| o.get(i).copied().unwrap_or(f64::NAN));
        if previous_pct.is_finite() && pct != previous_pct {
            changed_s = time_s;
        }
        previous_pct = pct;
        let rpm = at(speed, i);
        periods.push(TeachPeriod {
            summary: PeriodSummary {
                samples: 1,
                end_time_s: time_s,
                spindle_current_rms_a: at(spindle_current, i),
                feed_current_rms_a: at(feed_current, i),
                // No F/V converter in a log of a speed column: the estimator reads the speed.
                spindle_fv_voltage_v: f64::NAN,
                spindle_speed_rpm: rpm,
                spindle_command_rpm: rpm,
                feed_mm_min: at(feed, i),
                force_mean_resultant_n: forces.resultant_n.get(i).copied().unwrap_or(f64::NAN),
                feed_force_n: forces.feed_n.get(i).copied().unwrap_or(f64::NAN),
                depth_mm: at(depth, i),
                width_mm: at(width, i),
                ..PeriodSummary::default()
            },
            force_n,
            override_pct: pct,
            since_override_change_s: time_s - changed_s,
            // Nothing says when the spindle started: a period log starts in the cut.
            since_spindle_start_s: f64::INFINITY,
        });
    }
    Ok(periods)
}

/// How the log was sampled, from its `time_s` column, naming the file line where steps are
/// uneven.
fn describe_time_steps(table: &LogTable) -> Option<String> {
    let times = table.column("time_s")?;
    Some(match uniform_sample_rate_hz(times, TIME_STEP_TOLERANCE) {
        Ok(rate_hz) => format!("even, {:.6} s ({rate_hz:.4} Hz)", 1.0 / rate_hz),
        // The error counts time stamps from 0; say where in the file.
        Err(SpectrumError::UnevenTimeSteps {
            index,
            step_s,
            median_step_s,
            ..
        }) => format!(
            "uneven: the step to line {} (time_s {}) is {step_s:.6} s, the median step \
             {median_step_s:.6} s (a short last row is a period the program ended in)",
            table.line_of_row(index),
            times.get(index).copied().unwrap_or(f64::NAN)
        ),
        Err(e) => format!("not usable: {e}"),
    })
}

/// The rows whose force is negative, which the fit leaves out: a force the fit reads is a
/// magnitude, so a negative one is a sign flipped or a damaged value.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct NegativeForces {
    /// How many.
    pub rows: usize,
    /// The file line of the first (0 without any).
    pub first_line: usize,
    /// The lowest, N (NaN without any).
    pub lowest_n: f64,
}

impl NegativeForces {
    fn of(table: &LogTable, force_n: &[f64]) -> Self {
        let mut negative = Self {
            rows: 0,
            first_line: 0,
            lowest_n: f64::NAN,
        };
        for (row, &f) in force_n.iter().enumerate() {
            if f.is_finite() && f < 0.0 {
                if negative.rows == 0 {
                    negative.first_line = table.line_of_row(row);
                }
                negative.rows += 1;
                negative.lowest_n = negative.lowest_n.min(f);
            }
        }
        negative
    }
}

/// What a calibration from a log of control periods found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LogCalibration {
    /// Rows with a positive force.
    pub rows_with_force: usize,
    /// Rows with a negative force, left out of the fit.
    pub negative_force: NegativeForces,
    /// Median of the forces the spindle model was fitted to (NaN without any).
    pub median_force_n: f64,
    /// Median of the feed forces the feed model was fitted to (NaN without any).
    pub median_feed_force_n: f64,
    /// Where the spindle model's force came from.
    pub force_source: String,
    /// Where the feed model's force came from.
    pub feed_force_source: String,
    /// With modelled forces and a `force_n` column: RMS difference, % of the mean measured force.
    pub model_vs_measured_pct: Option<f64>,
    /// The log's sampling, from its `time_s` column: even steps and their rate, or where the
    /// steps are uneven (the fit itself does not need even steps, but a reader of the log does).
    pub time_steps: Option<String>,
    /// Paper 003's spindle model, if it could be fitted.
    pub spindle: Option<SpindleCurrentModel>,
    /// Why not.
    pub spindle_error: Option<String>,
    /// Paper 000's feed model, if it could be fitted.
    pub feed: Option<FeedCurrentModel>,
    /// Why not.
    pub feed_error: Option<String>,
    /// The fits' warnings: a line resting on too few load levels
    /// ([`TeachFit::warnings`]).
    pub warnings: Vec<String>,
    /// The spindle model's fit, with its calibration and the rows it used.
    #[serde(skip)]
    pub spindle_fit: Option<TeachFit>,
    /// The feed model's fit.
    #[serde(skip)]
    pub feed_fit: Option<TeachFit>,
}

impl LogCalibration {
    /// The fit of `feedback`'s model, or why there is none.
    pub fn fit_of(&self, feedback: Feedback) -> Result<&TeachFit, String> {
        let (fit, error, name) = match feedback {
            Feedback::FeedCurrent => (&self.feed_fit, &self.feed_error, "feed"),
            _ => (&self.spindle_fit, &self.spindle_error, "spindle"),
        };
        fit.as_ref().ok_or_else(|| {
            format!(
                "no {name} model was fitted ({})",
                error.as_deref().unwrap_or("no reason given")
            )
        })
    }
}

/// Fits both current-to-force models from a log of control periods. `geometry` models the force
/// from the cut instead of the `force_n` column (with a description of the cut for the report);
/// `gear_change_rpm` splits the spindle's speeds into gear ranges.
///
/// ```
/// use cutlab::log::period_log::{calibrate_log, LogTable};
/// let mut csv = String::from("spindle_current_rms_a,spindle_speed_rpm,force_n\n");
/// for i in 1..=20 {
///     let force = 10.0 * f64::from(i);
///     csv += &format!("{},1000,{force}\n", 5.0 + 0.01 * force);
/// }
/// let table = LogTable::from_log(&cutlab::log::load(csv.as_bytes(), None).unwrap(), &[]).unwrap();
/// let fitted = calibrate_log(&table, None, 900.0).unwrap();
/// let row = fitted.spindle.unwrap().rows[0];
/// assert!((row.sensitivity_a_per_n - 0.01).abs() < 1e-9);
/// assert!(fitted.feed.is_none());
/// ```
pub fn calibrate_log(
    table: &LogTable,
    geometry: Option<(&CutGeometry, &str)>,
    gear_change_rpm: f64,
) -> Result<LogCalibration, LogError> {
    let forces = forces(table, geometry)?;
    let origin = if geometry.is_some() {
        ForceOrigin::Modelled
    } else {
        ForceOrigin::Measured
    };
    // An RMS value stands for three phases of its own value; a phase's peak is √2 of it.
    let largest_phase = |name: &str| -> Result<f64, LogError> {
        Ok(std::f64::consts::SQRT_2
            * table.fit_column(name)?.map_or(0.0, |values| {
                values
                    .iter()
                    .copied()
                    .filter(|v| v.is_finite())
                    .fold(0.0, f64::max)
            }))
    };
    let positive = |force_n: &[f64]| force_n.iter().any(|f| f.is_finite() && *f > 0.0);
    if !positive(&forces.resultant_n) && !positive(&forces.feed_n) {
        return Err(LogError::NoPositiveForce {
            source: forces.source.clone(),
            rows: forces.resultant_n.len(),
            negative: NegativeForces::of(table, &forces.resultant_n),
        });
    }
    let mut report = LogCalibration {
        rows_with_force: forces
            .resultant_n
            .iter()
            .filter(|f| f.is_finite() && **f > 0.0)
            .count(),
        negative_force: NegativeForces::of(table, &forces.resultant_n),
        median_force_n: f64::NAN,
        median_feed_force_n: f64::NAN,
        force_source: forces.source.clone(),
        feed_force_source: forces.feed_source.clone(),
        model_vs_measured_pct: forces.model_vs_measured_pct,
        time_steps: describe_time_steps(table),
        spindle: None,
        spindle_error: None,
        feed: None,
        feed_error: None,
        warnings: Vec::new(),
        spindle_fit: None,
        feed_fit: None,
    };
    let fitted = |feedback: Feedback, force: &[f64], largest_a: f64| {
        let periods = periods(table, force, &forces)?;
        Ok::<_, LogError>(
            fit(&periods, feedback, origin, largest_a, gear_change_rpm).map_err(|e| e.to_string()),
        )
    };
    if table.column("spindle_current_rms_a").is_some()
        && table.column("spindle_speed_rpm").is_some()
    {
        let largest_a = largest_phase("spindle_current_rms_a")?;
        match fitted(Feedback::SpindleCurrent, &forces.resultant_n, largest_a)? {
            Ok(f) => {
                report.median_force_n = median(f.points.iter().map(|p| p.force_n));
                if let crate::estimation::estimator::Estimator::Spindle { model, .. } =
                    &f.calibration.estimator
                {
                    report.spindle = Some(model.clone());
                }
                report.spindle_fit = Some(f);
            }
            Err(e) => report.spindle_error = Some(e),
        }
    } else {
        report.spindle_error =
            Some("needs columns spindle_current_rms_a and spindle_speed_rpm".into());
    }
    if table.column("feed_current_rms_a").is_some() && table.column("feed_mm_min").is_some() {
        let largest_a = largest_phase("feed_current_rms_a")?;
        match fitted(Feedback::FeedCurrent, &forces.feed_n, largest_a)? {
            Ok(f) => {
                report.median_feed_force_n = median(f.points.iter().map(|p| p.force_n));
                if let crate::estimation::estimator::Estimator::Feed { model } =
                    &f.calibration.estimator
                {
                    report.feed = Some(*model);
                }
                report.feed_fit = Some(f);
            }
            Err(e) => report.feed_error = Some(e),
        }
    } else {
        report.feed_error = Some("needs columns feed_current_rms_a and feed_mm_min".into());
    }
    report.warnings = [&report.spindle_fit, &report.feed_fit]
        .into_iter()
        .flatten()
        .flat_map(TeachFit::warnings)
        .collect();
    if report.spindle.is_none() && report.feed.is_none() {
        return Err(LogError::NoModel {
            spindle: report.spindle_error.clone().unwrap_or_default(),
            feed: report.feed_error.clone().unwrap_or_default(),
        });
    }
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spindle_log(extra_row: &str) -> String {
        let mut csv = String::from("spindle_current_rms_a,spindle_speed_rpm,force_n\n");
        for i in 1..=20 {
            let force = 10.0 * f64::from(i);
            csv += &format!("{},1000,{force}\n", 5.0 + 0.01 * force);
        }
        csv + extra_row
    }

    /// The calibration's columns of a CSV text, read as `cutlab calibrate` reads a file.
    fn table(csv: &str) -> LogTable {
        LogTable::from_log(&crate::log::load(csv.as_bytes(), None).unwrap(), &[]).unwrap()
    }

    #[test]
    fn a_byte_order_mark_keeps_the_first_column() {
        let t = table(&format!("\u{feff}{}", spindle_log("")));
        assert_eq!(
            t.column("spindle_current_rms_a").map(<[f64]>::len),
            Some(20)
        );
        assert!(calibrate_log(&t, None, 900.0).unwrap().spindle.is_some());
    }

    #[test]
    fn a_log_on_two_load_levels_is_fitted_with_a_warning() {
        // `spindle_log`'s ramp over 20 loads: no warning.
        let ramp = calibrate_log(&table(&spindle_log("")), None, 900.0).unwrap();
        assert!(ramp.warnings.is_empty(), "{:?}", ramp.warnings);
        let mut csv = String::from("spindle_current_rms_a,spindle_speed_rpm,force_n\n");
        for i in 0..20 {
            let force = if i < 10 { 100.0 } else { 200.0 };
            csv += &format!("{},1000,{force}\n", 5.0 + 0.01 * force);
        }
        let two = calibrate_log(&table(&csv), None, 900.0).unwrap();
        assert_eq!(two.warnings.len(), 1, "{:?}", two.warnings);
        assert!(
            two.warnings[0].contains("rests on 2 load levels (100, 200 N)"),
            "{:?}",
            two.warnings
        );
    }

    #[test]
    fn an_absurd_value_is_refused_where_it_is_instead_of_a_nan_fit() {
        for value in ["1e308", "1e200"] {
            let t = table(&spindle_log(&format!("6,1000,{value}\n")));
            let e = calibrate_log(&t, None, 900.0).unwrap_err();
            assert!(
                matches!(&e, LogError::Absurd { line: 22, column, .. } if column == "force_n"),
                "{e}"
            );
            assert!(
                e.to_string().starts_with("line 22, column \"force_n\""),
                "{e}"
            );
        }
    }

    #[test]
    fn one_column_read_as_two_quantities_is_refused() {
        let csv =
            "time_s,force_n,spindle_current_rms_a,spindle_speed_rpm\n0,1,2,900\n0.1,2,3,900\n";
        let log = crate::log::load(csv.as_bytes(), None).unwrap();
        let map = [("force_n".to_string(), "spindle_current_rms_a".to_string())];
        let e = LogTable::from_log(&log, &map).unwrap_err();
        assert!(
            e.contains("force_n and spindle_current_rms_a would both be read from column \"spindle_current_rms_a\""),
            "{e}"
        );
    }

    #[test]
    fn a_column_named_twice_is_refused_as_ambiguous() {
        let csv = "spindle_current_rms_a,force_n,force_n\n1,2,3\n";
        let log = crate::log::load(csv.as_bytes(), None).unwrap();
        let e = LogTable::from_log(&log, &[]).unwrap_err();
        assert_eq!(
            e,
            "2 columns are named \"force_n\": which one is force_n is ambiguous; rename one in \
             the file"
        );
        // A name no role reads may repeat.
        let log = crate::log::load(b"note,note,force_n\na,b,3\n", None).unwrap();
        assert_eq!(
            LogTable::from_log(&log, &[]).unwrap().column("force_n"),
            Some(&[3.0][..])
        );
    }

    #[test]
    fn without_force_or_cut_the_error_names_the_missing_column() {
        let t = table("spindle_current_rms_a,spindle_speed_rpm\n1,1000\n");
        let e = calibrate_log(&t, None, 900.0).unwrap_err();
        assert!(e.to_string().starts_with("no \"force_n\" column"), "{e}");
    }
}
