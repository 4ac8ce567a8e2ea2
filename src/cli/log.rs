//! `cutlab log`: engineers' own CSV logs, as they are (see [`crate::log`]).

use std::io::Read;

use serde::Serialize;

use super::args::required;
use super::{write_json, CliError, Io};
use crate::log::{ColumnKind, LogBuilder, Role};

/// The long help of `cutlab log`.
pub const ABOUT: &str = "Read a machine's CSV log as it is: comma, semicolon or tab delimited \
(detected), a decimal comma, quoted fields, a byte-order mark, CRLF, a header with units or none, \
text columns kept as labels. Damaged lines are reported by line and column and kept as gaps.";

/// The options of `cutlab log`: a subcommand.
#[derive(Debug, clap::Args)]
pub struct LogArgs {
    #[command(subcommand)]
    command: Option<LogCommand>,
}

#[derive(Debug, clap::Subcommand)]
enum LogCommand {
    /// Describe a log: its dialect, columns (kind, unit, role guess, statistics) and problems
    Inspect(InspectArgs),
    /// Statistics of columns (whole and per label), an optional zero-phase low-pass, spectrum peaks
    Analyse(AnalyseArgs),
}

#[derive(Debug, clap::Args)]
pub struct AnalyseArgs {
    /// The CSV file ("-" for standard input)
    #[arg(value_name = "FILE")]
    file: Option<String>,
    /// A column to analyse (repeat for more)
    #[arg(long = "column", value_name = "NAME")]
    columns: Vec<String>,
    /// A label column to group the statistics by
    #[arg(long, value_name = "LABEL_COLUMN")]
    by: Option<String>,
    /// Zero-phase Butterworth low-pass cut-off (skipped, and said, above the log's Nyquist frequency)
    #[arg(long, value_name = "HZ")]
    lowpass_hz: Option<f64>,
    /// Order of the low-pass (default 4)
    #[arg(long, value_name = "N")]
    order: Option<usize>,
    /// Find the strongest peaks of each column's spectrum (Welch)
    #[arg(long)]
    spectrum: bool,
    /// The sample period of a log without a time column, in seconds
    #[arg(long, value_name = "S")]
    sample_period_s: Option<f64>,
    /// Print JSON instead of a table
    #[arg(long)]
    json: bool,
}

#[derive(Debug, clap::Args)]
pub struct InspectArgs {
    /// The CSV file ("-" for standard input)
    #[arg(value_name = "FILE")]
    file: Option<String>,
    /// The sample period of a log without a time column, in seconds
    #[arg(long, value_name = "S")]
    sample_period_s: Option<f64>,
    /// Print one JSON object instead of a table
    #[arg(long)]
    json: bool,
}

/// Runs `cutlab log`.
pub fn run(args: LogArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    match args.command {
        Some(LogCommand::Inspect(a)) => inspect(a, io),
        Some(LogCommand::Analyse(a)) => analyse(a, io),
        None => super::print_help(io, &["log"]),
    }
}

#[derive(Serialize)]
struct ColumnReport<'a> {
    name: &'a str,
    kind: ColumnKind,
    unit: Option<&'a str>,
    role: Option<Role>,
    numeric_share: f64,
    missing: usize,
    min: Option<f64>,
    max: Option<f64>,
    mean: Option<f64>,
}

#[derive(Serialize)]
struct ProblemReport<'a> {
    line: usize,
    column: Option<&'a str>,
    message: &'a str,
}

#[derive(Serialize)]
struct InspectReport<'a> {
    rows: usize,
    delimiter: &'static str,
    decimal: &'static str,
    header: bool,
    time_column: Option<&'a str>,
    sample_period_s: Option<f64>,
    columns: Vec<ColumnReport<'a>>,
    problems: Vec<ProblemReport<'a>>,
    problems_not_listed: usize,
}

/// Reads `path` (or standard input for "-") in chunks into a log.
fn read_log(
    path: &str,
    sample_period_s: Option<f64>,
    io: &mut Io<'_>,
) -> Result<crate::log::Log, CliError> {
    if let Some(p) = sample_period_s {
        if !(p.is_finite() && p > 0.0) {
            return Err(CliError::new(format!(
                "--sample-period-s: must be a positive number of seconds, got {p}"
            )));
        }
    }
    let mut builder = LogBuilder::new();
    // A megabyte at a time: few system calls, and little beside the columns in memory.
    let mut buffer = vec![0u8; 1 << 20];
    let mut file;
    let reader: &mut dyn Read = if path == "-" {
        &mut io.stdin
    } else {
        file = std::fs::File::open(path)
            .map_err(|e| CliError::new(format!("{path}: cannot open: {e}")))?;
        if let Ok(meta) = file.metadata() {
            builder = LogBuilder::with_expected_bytes(meta.len());
        }
        &mut file
    };
    loop {
        let n = reader
            .read(&mut buffer)
            .map_err(|e| CliError::new(format!("{path}: cannot read: {e}")))?;
        if n == 0 {
            break;
        }
        builder.push(&buffer[..n]);
    }
    Ok(builder.finish(sample_period_s))
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

fn inspect(args: InspectArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    let path: String = required("FILE", &args.file)?;
    let log = read_log(&path, args.sample_period_s, io)?;
    let report = InspectReport {
        rows: log.rows,
        delimiter: log.dialect.delimiter_name(),
        decimal: if log.dialect.decimal_comma { "," } else { "." },
        header: log.header,
        time_column: log.time_column.map(|i| log.columns[i].name.as_str()),
        sample_period_s: log.sample_period_s,
        columns: log
            .columns
            .iter()
            .map(|c| {
                let (min, max, mean) = c.min_max_mean();
                let numeric = matches!(c.kind, ColumnKind::Number | ColumnKind::Time);
                ColumnReport {
                    name: &c.name,
                    kind: c.kind,
                    unit: c.unit.as_deref(),
                    role: c.role,
                    numeric_share: c.numeric_share,
                    missing: c.missing,
                    min: finite(min).filter(|_| numeric),
                    max: finite(max).filter(|_| numeric),
                    mean: finite(mean).filter(|_| numeric),
                }
            })
            .collect(),
        problems: log
            .problems
            .iter()
            .map(|p| ProblemReport {
                line: p.line,
                column: p.column.as_deref(),
                message: &p.message,
            })
            .collect(),
        problems_not_listed: log.problems_not_listed,
    };
    if args.json {
        return write_json(io.stdout, &report);
    }
    let mut out =
        format!(
            "{path}: {} rows; delimiter {}, decimal {}, {}; time {}; sample period {}\n",
            report.rows,
            report.delimiter,
            report.decimal,
            if report.header {
                "a header"
            } else {
                "no header"
            },
            report.time_column.unwrap_or("none"),
            report.sample_period_s.map_or(
                "unknown (give --sample-period-s)".to_string(),
                |p| format!("{} s", crate::input::readable(p))
            )
        );
    for c in &report.columns {
        out.push_str(&format!(
            "  {:<28} {:<7} {:<8} {:<14} missing {:>6}",
            c.name,
            serde_json::to_value(c.kind)
                .ok()
                .and_then(|v| v.as_str().map(str::to_string))
                .unwrap_or_default(),
            c.unit.unwrap_or("—"),
            c.role
                .and_then(|r| serde_json::to_value(r).ok())
                .and_then(|v| v.as_str().map(str::to_string))
                .unwrap_or_else(|| "—".into()),
            c.missing
        ));
        if let (Some(lo), Some(hi), Some(mean)) = (c.min, c.max, c.mean) {
            out.push_str(&format!(
                "  {} … {}, mean {}",
                crate::input::readable(lo),
                crate::input::readable(hi),
                crate::input::readable(mean)
            ));
        }
        out.push('\n');
    }
    for p in &report.problems {
        out.push_str(&format!(
            "  line {}{}: {}\n",
            p.line,
            p.column.map_or(String::new(), |c| format!(", {c}")),
            p.message
        ));
    }
    if report.problems_not_listed > 0 {
        out.push_str(&format!(
            "  … and {} more problems\n",
            report.problems_not_listed
        ));
    }
    io.stdout.write_all(out.as_bytes())?;
    Ok(())
}

#[derive(Serialize)]
struct AnalyseReport {
    rows: usize,
    sample_period_s: Option<f64>,
    columns: Vec<crate::log::analysis::ColumnAnalysis>,
}

fn analyse(args: AnalyseArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    let path: String = required("FILE", &args.file)?;
    if args.columns.is_empty() {
        return Err(CliError::new(
            "--column: name at least one column to analyse",
        ));
    }
    if args.order.is_some() && args.lowpass_hz.is_none() {
        return Err(CliError::new("--order: give --lowpass-hz too"));
    }
    let lowpass = match args.lowpass_hz {
        Some(f) if !(f.is_finite() && f > 0.0) => {
            return Err(CliError::new(format!(
                "--lowpass-hz: must be a positive frequency, got {f}"
            )))
        }
        Some(f) => {
            let order = args.order.unwrap_or(4);
            if !(1..=crate::signal::butterworth::MAX_ORDER).contains(&order) {
                return Err(CliError::new(format!(
                    "--order: must be 1 to {}, got {order}",
                    crate::signal::butterworth::MAX_ORDER
                )));
            }
            Some((f, order))
        }
        None => None,
    };
    let log = read_log(&path, args.sample_period_s, io)?;
    let request = crate::log::analysis::AnalysisRequest {
        by: args.by.clone(),
        lowpass,
        spectrum: args.spectrum,
    };
    let columns = args
        .columns
        .iter()
        .map(|c| crate::log::analysis::analyse(&log, c, &request).map_err(CliError::new))
        .collect::<Result<Vec<_>, _>>()?;
    let report = AnalyseReport {
        rows: log.rows,
        sample_period_s: log.sample_period_s,
        columns,
    };
    if args.json {
        return write_json(io.stdout, &report);
    }
    let number = |v: Option<f64>| v.map_or("—".to_string(), crate::input::readable);
    let mut out = String::new();
    for c in &report.columns {
        let unit = c
            .unit
            .as_deref()
            .filter(|u| !c.column.contains(u))
            .map_or(String::new(), |u| format!(" [{u}]"));
        out.push_str(&format!("{}{unit}", c.column));
        if let Some((f, n)) = c.lowpass {
            out.push_str(&format!(
                ", low-pass {} Hz order {n} (zero-phase)",
                crate::input::readable(f)
            ));
        }
        out.push('\n');
        for note in &c.notes {
            out.push_str(&format!("  note: {note}\n"));
        }
        let line = |name: &str, s: &crate::log::analysis::Stats| {
            format!(
                "  {name:<24} n {:>8}  mean {:>10}  rms {:>10}  min {:>10}  max {:>10}  duration {} s\n",
                s.count,
                number(s.mean),
                number(s.rms),
                number(s.min),
                number(s.max),
                number(s.duration_s)
            )
        };
        out.push_str(&line("all rows", &c.whole));
        for l in &c.by_label {
            out.push_str(&line(&l.label, &l.stats));
        }
        for p in &c.peaks {
            out.push_str(&format!(
                "  peak at {} Hz (PSD {})\n",
                crate::input::readable(p.freq_hz),
                crate::input::readable(p.psd)
            ));
        }
    }
    io.stdout.write_all(out.as_bytes())?;
    Ok(())
}
