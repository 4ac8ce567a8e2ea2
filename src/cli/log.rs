//! `cutlab log`: engineers' own CSV logs, as they are (see [`crate::log`]).

use std::io::Read;
use std::sync::Arc;

use serde::Serialize;

use super::args::required;
use super::table_args::{OptionRows, TableArgs};
use super::{write_json, CliError, Io};
use crate::closed_loop::definition::{max_override_pct_of, parse_settings, RunSetting};
use crate::control::registry::{ControllerConfig, ControllerKind};
use crate::estimation::estimator::Feedback;
use crate::input::table::RowError;
use crate::log::mapping::{Channel, Mapping};
use crate::log::replay::{write_replay_csv, ReplayRun, ReplaySettings, Target};
use crate::log::settings::{parse_analysis, sample_period, LogSetting};
use crate::log::{ColumnKind, LogBuilder, Role};
use crate::plant::cnc::OverrideMode;
use crate::work::Work;

/// The long help of `cutlab log`.
pub const ABOUT: &str = "Read a machine's CSV log as it is: comma, semicolon or tab delimited \
(detected), a decimal comma, quoted fields, a byte-order mark, CRLF or CR line ends, a preamble \
or comment lines before a header with units, or no header, text columns kept as labels. Damaged \
lines are reported by line and column and kept as gaps, and every line and cell not read as data \
is counted; a file in UTF-16 or UTF-32, or with a quote that swallows the lines after it, is \
refused. Inspect it, analyse its columns, or replay a controller on it (docs/logs.md).";

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
    /// Replay a controller on the log: the override it would have commanded, what the safety
    /// envelope would have done, the force estimate (open-loop: the log cannot react)
    #[command(long_about = REPLAY_ABOUT)]
    Replay(Box<ReplayArgs>),
}

/// The long help of `cutlab log replay`.
const REPLAY_ABOUT: &str = "Replay a controller on a machine log. The log becomes one more \
machine: each row is a sensor sample at the log's rate, fed through the lab's own closed loop \
(signal chain, estimator, controller, safety envelope). Replay is open-loop: it shows the \
override the controller would have commanded on the signals the log holds, when the envelope \
would have acted (arming, override limits and rate limit, sensor faults, overload) and the force \
estimate, not what the machine would have done after that. A log of RMS values (e.g. a 10 Hz \
drive export) skips the chain's low-pass and RMS stages; a low-pass above the log's Nyquist \
frequency is skipped too; the notes say which. Without --calibration the controllers regulate \
the current itself (give --target-a). docs/logs.md describes it.";

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
    /// The analysis: the low-pass and the sample period (rows of the log table, as the Logs
    /// page's fields)
    #[command(flatten)]
    settings: TableArgs<AnalyseRows>,
    /// Find the strongest peaks of each column's spectrum (Welch)
    #[arg(long)]
    spectrum: bool,
    /// Print JSON instead of a table
    #[arg(long)]
    json: bool,
}

#[derive(Debug, clap::Args)]
pub struct ReplayArgs {
    /// The CSV file ("-" for standard input)
    #[arg(value_name = "FILE")]
    file: Option<String>,
    /// The current column the force is measured from: an RMS/feedback value, or a phase current
    /// (give two or three phases with --current each)
    #[arg(long = "current", value_name = "NAME")]
    current: Vec<String>,
    /// The spindle-speed column (else guessed from the names; without one the speed is the
    /// calibration's)
    #[arg(long, value_name = "NAME")]
    speed: Option<String>,
    /// The feed column (else guessed from the names)
    #[arg(long, value_name = "NAME")]
    feed: Option<String>,
    /// Any other column's channel, CHANNEL=COLUMN (repeatable; channels: time, spindle-phase,
    /// feed-phase, spindle-current, feed-current, spindle-speed, spindle-command, fv-voltage,
    /// feed, programmed-feed, override, force, depth, label; an empty COLUMN unmaps the channel)
    #[arg(long = "map", value_name = "CHANNEL=COLUMN")]
    map: Vec<String>,
    #[command(flatten)]
    period: TableArgs<PeriodRow>,
    /// Which current measures the force: spindle or feed (default: the calibration's, else the
    /// axis prefix of the current column: X_/Y_/Z_ is the feed drive's)
    #[arg(long, value_name = "spindle|feed")]
    feedback: Option<String>,
    /// The controller to replay (see cutlab controllers)
    #[arg(long, value_name = "NAME")]
    controller: Option<String>,
    /// A controller parameter, key=value (repeatable)
    #[arg(long = "set", value_name = "K=V")]
    set: Vec<String>,
    /// The force to hold, N (needs --calibration)
    #[arg(
        long,
        value_name = "N",
        conflicts_with = "target_a",
        allow_hyphen_values = true
    )]
    target_n: Option<String>,
    /// The current to hold, A (through the calibration a force; without one the current itself)
    #[arg(long, value_name = "A", allow_hyphen_values = true)]
    target_a: Option<String>,
    /// The control period, s (default: whole spindle revolutions, at least 40 ms; rounded to
    /// whole log samples)
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    period_s: Option<String>,
    /// A saved calibration file (cutlab sim/calibrate --save-calibration) turning current into
    /// force
    #[arg(long, value_name = "FILE")]
    calibration: Option<String>,
    /// Write one row per control period: time_s, current_a, force_est_n (calibrated),
    /// requested_override_pct, override_pct, envelope_state, logged_override_pct, force_n
    #[arg(long, value_name = "OUT")]
    csv: Option<String>,
    /// Write the settings, the notes, the envelope's events and a summary as JSON
    #[arg(long, value_name = "OUT")]
    json: Option<String>,
}

#[derive(Debug, clap::Args)]
pub struct InspectArgs {
    /// The CSV file ("-" for standard input)
    #[arg(value_name = "FILE")]
    file: Option<String>,
    #[command(flatten)]
    period: TableArgs<PeriodRow>,
    /// Print one JSON object instead of a table
    #[arg(long)]
    json: bool,
}

/// The log table's rows `cutlab log analyse` takes.
#[derive(Debug, Clone, Default)]
pub struct AnalyseRows;

impl OptionRows for AnalyseRows {
    type Setting = LogSetting;
    const ROWS: &'static [LogSetting] = &[
        LogSetting::Lowpass,
        LogSetting::Order,
        LogSetting::SamplePeriod,
    ];
}

/// The sample period, the one row `cutlab log inspect` and `replay` take of the log table.
#[derive(Debug, Clone, Default)]
pub struct PeriodRow;

impl OptionRows for PeriodRow {
    type Setting = LogSetting;
    const ROWS: &'static [LogSetting] = &[LogSetting::SamplePeriod];
}

/// `--sample-period-s`, through its row.
fn given_period(args: &TableArgs<PeriodRow>) -> Result<Option<f64>, CliError> {
    sample_period(args.given(LogSetting::SamplePeriod)).map_err(|e| CliError::new(e.for_cli()))
}

/// The first of a table's errors, naming its option.
fn first_for_cli<S: crate::input::table::Table>(errors: Vec<RowError<S>>) -> CliError {
    match errors.first() {
        Some(e) => CliError::new(e.for_cli()),
        None => CliError::new("the options were refused"),
    }
}

/// Runs `cutlab log`.
pub fn run(args: LogArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    match args.command {
        Some(LogCommand::Inspect(a)) => inspect(a, io),
        Some(LogCommand::Analyse(a)) => analyse(a, io),
        Some(LogCommand::Replay(a)) => replay(*a, io),
        None => super::print_help(io, &["log"]),
    }
}

#[derive(Serialize)]
struct ColumnReport<'a> {
    name: &'a str,
    kind: ColumnKind,
    unit: Option<&'a str>,
    role: Option<Role>,
    /// What the role guess rests on (or why there is none).
    role_reason: Option<&'a str>,
    numeric_share: f64,
    missing: usize,
    not_finite: usize,
    /// Values the statistics cover (finite ones).
    count: usize,
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
    /// Where every line went and what was not read as data.
    account: crate::log::ReadAccount,
    /// The same, as sentences.
    not_read: Vec<String>,
}

/// Reads `path` (or standard input for "-") in chunks into a log.
fn read_log(
    path: &str,
    sample_period_s: Option<f64>,
    io: &mut Io<'_>,
) -> Result<crate::log::Log, CliError> {
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
        if let Some(e) = builder.refused() {
            return Err(CliError::new(format!("{path}: {e}")));
        }
    }
    builder
        .finish(sample_period_s)
        .map_err(|e| CliError::new(format!("{path}: {e}")))
}

fn inspect(args: InspectArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    let path: String = required("FILE", &args.file)?;
    let log = read_log(&path, given_period(&args.period)?, io)?;
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
                let numeric = matches!(c.kind, ColumnKind::Number | ColumnKind::Time);
                let stats = crate::log::analysis::Stats::of(&c.values, None);
                ColumnReport {
                    name: &c.name,
                    kind: c.kind,
                    unit: c.unit.as_deref(),
                    role: c.role,
                    role_reason: c.role_reason.as_deref(),
                    numeric_share: c.numeric_share,
                    missing: c.missing,
                    not_finite: c.not_finite,
                    count: stats.count,
                    min: stats.min.filter(|_| numeric),
                    max: stats.max.filter(|_| numeric),
                    mean: stats.mean.filter(|_| numeric),
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
        account: log.account,
        not_read: log.account.unread(),
    };
    if args.json {
        return write_json(io.stdout, &report);
    }
    let mut out =
        format!(
            "{path}: {} rows; {}, {}; time {}; sample period {}\n",
            report.rows,
            log.dialect.in_words(),
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
    let a = &report.account;
    out.push_str(&format!(
        "  {} lines: {} rows on {}, a header on {}, {} skipped\n",
        a.lines,
        report.rows,
        a.row_lines,
        a.header_lines,
        a.preamble_lines + a.blank_lines
    ));
    for sentence in &report.not_read {
        out.push_str(&format!("  not read as data: {sentence}\n"));
    }
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
        if c.not_finite > 0 {
            out.push_str(&format!(", not finite {}", c.not_finite));
        }
        if let (Some(lo), Some(hi), Some(mean)) = (c.min, c.max, c.mean) {
            out.push_str(&format!(
                "  {} … {}, mean {}",
                crate::input::readable(lo),
                crate::input::readable(hi),
                crate::input::readable(mean)
            ));
            if c.count < report.rows {
                out.push_str(&format!(" ({} of {} rows)", c.count, report.rows));
            }
        }
        if let Some(why) = c.role_reason {
            out.push_str(&format!("  [{why}]"));
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
    if args.settings.given(LogSetting::Order).is_some()
        && args.settings.given(LogSetting::Lowpass).is_none()
    {
        return Err(CliError::new("--order: give --lowpass-hz too"));
    }
    let analysis = parse_analysis(&args.settings.texts()).map_err(first_for_cli)?;
    let lowpass = analysis.lowpass;
    let log = read_log(&path, analysis.sample_period_s, io)?;
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
                "  {name:<24} n {:>8}  mean {:>10}  rms {:>10}  min {:>10}  max {:>10}  duration {} s{}\n",
                s.count,
                number(s.mean),
                number(s.rms),
                number(s.min),
                number(s.max),
                number(s.duration_s),
                if s.left_out > 0 {
                    format!(" ({} of {} rows left out: gaps or not finite)", s.left_out, s.count + s.left_out)
                } else {
                    String::new()
                }
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

/// The mapping of `cutlab log replay`: guessed, then the options' columns. Returns it and the
/// feedback path.
fn replay_mapping(
    args: &ReplayArgs,
    log: &crate::log::Log,
    calibration_feedback: Option<Feedback>,
) -> Result<(Mapping, Feedback), CliError> {
    let column = |option: &str, name: &str| -> Result<usize, CliError> {
        log.columns
            .iter()
            .position(|c| c.name == name)
            .ok_or_else(|| {
                CliError::new(format!(
                    "--{option}: no column {name:?}; columns: {}",
                    log.columns
                        .iter()
                        .map(|c| c.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            })
    };
    if args.current.is_empty() {
        return Err(CliError::new(
            "--current: name the current column the force is measured from (see cutlab log \
             inspect)",
        ));
    }
    if args.current.len() > 3 {
        return Err(CliError::new(format!(
            "--current: at most three phases, got {}",
            args.current.len()
        )));
    }
    for name in &args.current {
        column("current", name)?;
    }
    let feedback = match args.feedback.as_deref().map(str::trim) {
        Some("spindle") => Feedback::SpindleCurrent,
        Some("feed") => Feedback::FeedCurrent,
        Some(other) => {
            return Err(CliError::new(format!(
                "--feedback: expected spindle or feed, got {other:?}"
            )))
        }
        None => calibration_feedback.unwrap_or_else(|| {
            let first = args.current[0].trim().to_ascii_lowercase();
            if ["x_", "y_", "z_"].iter().any(|p| first.starts_with(p)) {
                Feedback::FeedCurrent
            } else {
                Feedback::SpindleCurrent
            }
        }),
    };
    if feedback == Feedback::Dynamometer {
        return Err(CliError::new(
            "the calibration is a dynamometer's: a replay measures the force from a current",
        ));
    }
    let (phase, rms) = match feedback {
        Feedback::FeedCurrent => (Channel::FeedPhase, Channel::FeedCurrent),
        _ => (Channel::SpindlePhase, Channel::SpindleCurrent),
    };
    let mut mapping = Mapping::guess(log);
    // The named currents replace whatever was guessed for this motor.
    for (name, channel) in mapping.columns.clone() {
        if channel == phase || channel == rms {
            mapping.set(&name, None);
        }
    }
    let phases = args.current.len() > 1
        || log
            .columns
            .iter()
            .find(|c| c.name == args.current[0])
            .is_some_and(|c| c.role == Some(crate::log::Role::PhaseCurrent));
    for name in &args.current {
        mapping.set(name, Some(if phases { phase } else { rms }));
    }
    for (option, channel, name) in [
        ("speed", Channel::SpindleSpeed, &args.speed),
        ("feed", Channel::Feed, &args.feed),
    ] {
        if let Some(name) = name {
            column(option, name)?;
            for other in mapping
                .columns_of(channel)
                .into_iter()
                .map(String::from)
                .collect::<Vec<_>>()
            {
                mapping.set(&other, None);
            }
            mapping.set(name, Some(channel));
        }
    }
    for assignment in &args.map {
        let Some((channel, name)) = assignment.split_once('=') else {
            return Err(CliError::new(format!(
                "--map: {assignment:?} is not of the form CHANNEL=COLUMN"
            )));
        };
        let channel = Channel::from_name(channel).ok_or_else(|| {
            CliError::new(format!(
                "--map: unknown channel {:?}; channels: {}",
                channel.trim(),
                Channel::ALL.map(Channel::name).join(", ")
            ))
        })?;
        let name = name.trim();
        if name.is_empty() {
            for other in mapping
                .columns_of(channel)
                .into_iter()
                .map(String::from)
                .collect::<Vec<_>>()
            {
                mapping.set(&other, None);
            }
        } else {
            column("map", name)?;
            mapping.set(name, Some(channel));
        }
    }
    Ok((mapping, feedback))
}

#[derive(Serialize)]
struct ReplaySettingsReport<'a> {
    file: &'a str,
    rows: usize,
    sample_period_s: Option<f64>,
    mapping: &'a Mapping,
    feedback: &'static str,
    controller: &'a crate::control::registry::ControllerConfig,
    control_period_s: f64,
    spindle_lowpass_hz: Option<f64>,
    feed_lowpass_hz: Option<f64>,
    lowpass_order: usize,
    target: Target,
    target_force_n: f64,
    calibration: Option<&'a str>,
    calibrated: bool,
    min_override_pct: f64,
    max_override_pct: f64,
    max_rate_pct_per_s: f64,
    arming_delay_s: f64,
    overload_limit_n: f64,
}

#[derive(Serialize)]
struct ReplayReport<'a> {
    settings: ReplaySettingsReport<'a>,
    notes: &'a [String],
    events: Vec<crate::log::replay::EventReport>,
    summary: &'a crate::log::replay::ReplaySummary,
    log_problems: &'a [crate::log::LineProblem],
}

fn replay(args: ReplayArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    let path: String = required("FILE", &args.file)?;
    let controller_name: String = required("controller", &args.controller)?;
    let kind: ControllerKind = controller_name
        .parse()
        .map_err(|e| CliError::new(format!("--controller: {e}")))?;
    let mut controller = ControllerConfig::new(kind);
    controller
        .set_texts(args.set.iter().map(String::as_str))
        .map_err(|e| CliError::new(format!("--set: {e}")))?;
    // The run's settings, through the run definition's rows as `cutlab sim`'s.
    let texts: Vec<(RunSetting, &str)> = [
        (RunSetting::TargetForce, &args.target_n),
        (RunSetting::TargetCurrent, &args.target_a),
        (RunSetting::ControlPeriod, &args.period_s),
    ]
    .into_iter()
    .filter_map(|(setting, text)| text.as_deref().map(|t| (setting, t)))
    .collect();
    let mut run_settings = parse_settings(&texts, max_override_pct_of(&OverrideMode::default()))
        .map_err(|errors| CliError::new(errors[0].for_cli()))?;
    let calibration = args
        .calibration
        .as_deref()
        .map(super::read_calibration)
        .transpose()?;
    let sample_period_s = given_period(&args.period)?;
    let log = Arc::new(read_log(&path, sample_period_s, io)?);
    if sample_period_s.is_none() {
        if let Some(why) = log.period_unknown() {
            return Err(CliError::new(format!(
                "{path}: the log's sample period is unknown: {why}; give it with \
                 --sample-period-s"
            )));
        }
    }
    let (mapping, feedback) =
        replay_mapping(&args, &log, calibration.as_ref().map(|c| c.feedback()))?;
    run_settings.feedback = Some(feedback);
    let settings = ReplaySettings {
        run: run_settings,
        sample_period_s,
        calibration: calibration.as_ref().map(|c| c.calibration.clone()),
        ..ReplaySettings::default()
    };
    let result = ReplayRun::new(&log, &mapping, &settings, &controller)
        .and_then(|run| run.run_to_end())
        .map_err(|e| CliError::new(format!("{path}: {}", e.for_cli())))?;
    if let Some(out) = args.csv.as_deref() {
        let mut file = std::fs::File::create(out)
            .map_err(|e| CliError::new(format!("--csv: cannot create {out:?}: {e}")))?;
        write_replay_csv(&[&result], &mut file)
            .map_err(|e| CliError::new(format!("--csv: cannot write {out:?}: {e}")))?;
    }
    let events = crate::log::replay::events(&result.trace);
    let finite = |v: f64| v.is_finite().then_some(v);
    let s = &result.settings;
    if let Some(out) = args.json.as_deref() {
        let report = ReplayReport {
            settings: ReplaySettingsReport {
                file: &path,
                rows: log.rows,
                sample_period_s: log.sample_period_s.or(sample_period_s),
                mapping: &mapping,
                feedback: s.feedback.name(),
                controller: &result.controller,
                control_period_s: s.control_period_s,
                spindle_lowpass_hz: finite(s.spindle_lowpass_hz),
                feed_lowpass_hz: finite(s.feed_lowpass_hz),
                lowpass_order: s.lowpass_order,
                target: result.target,
                target_force_n: s.target_force_n,
                calibration: args.calibration.as_deref(),
                calibrated: result.calibrated,
                min_override_pct: s.envelope.min_override_pct,
                max_override_pct: s.envelope.max_override_pct,
                max_rate_pct_per_s: s.envelope.max_rate_pct_per_s,
                arming_delay_s: s.envelope.arming_delay_s,
                overload_limit_n: s.envelope.overload_limit_n,
            },
            notes: &result.notes,
            events: events.clone(),
            summary: &result.summary,
            log_problems: &log.problems,
        };
        let mut file = std::fs::File::create(out)
            .map_err(|e| CliError::new(format!("--json: cannot create {out:?}: {e}")))?;
        write_json(&mut file, &report)?;
    }
    // The brief for a terminal.
    let readable = crate::input::readable;
    // Percent and newtons to a tenth: what a person compares at a glance.
    let tenth = |v: Option<f64>| v.map_or("—".to_string(), |v| format!("{v:.1}"));
    let sum = &result.summary;
    let mut out = format!(
        "{path}: {} replayed on {} rows, {} control periods of {} s ({} feedback, {})\n",
        result.name,
        log.rows,
        sum.periods,
        readable(s.control_period_s),
        s.feedback.name(),
        match (result.calibrated, result.target) {
            (true, Target::ForceN(f)) => format!("target {} N", readable(f)),
            (true, Target::CurrentA(a)) => format!(
                "target {} A = {} N through the calibration",
                readable(a),
                readable(s.target_force_n)
            ),
            (false, _) => format!("uncalibrated: holding {} A", readable(s.target_force_n)),
        }
    );
    for note in &result.notes {
        out.push_str(&format!("note: {note}\n"));
    }
    for p in log.problems.iter().take(5) {
        out.push_str(&format!(
            "log: line {}{}: {}\n",
            p.line,
            p.column
                .as_deref()
                .map_or(String::new(), |c| format!(", {c}")),
            p.message
        ));
    }
    for e in &events {
        out.push_str(&format!("{:>9} s  {}\n", readable(e.time_s), e.message));
    }
    out.push_str(&format!(
        "override while armed: min {} %, mean {} %, max {} % (the log's own: mean {} %); \
         {} periods limited by the envelope; {} s under a sensor fault",
        tenth(sum.override_min_pct),
        tenth(sum.override_mean_pct),
        tenth(sum.override_max_pct),
        tenth(sum.logged_override_mean_pct),
        sum.periods_limited,
        readable(sum.sensor_fault_s)
    ));
    if result.calibrated {
        out.push_str(&format!(
            "; force estimate mean {} N, max {} N",
            tenth(sum.force_est_mean_n),
            tenth(sum.force_est_max_n)
        ));
    }
    out.push('\n');
    io.stdout.write_all(out.as_bytes())?;
    Ok(())
}
