//! The `cutlab` command line: the same core as the browser lab, in a terminal.
//!
//! [`run`] takes the arguments and the standard streams, so tests drive the whole command line
//! in-process. clap (derive) parses them: each subcommand lives in its own module with an
//! `…Args` struct (its options, their help and value names) and a `run(args, io)` function.
//!
//! | file | what |
//! |---|---|
//! | [`args`] | option values and the errors of the command line |
//! | [`sim`] | `cutlab sim` and `cutlab compare`: closed-loop runs on the presets, or a saved configuration |
//! | [`tune`] | `cutlab tune`: sweeps, Nelder–Mead and teach-in |
//! | [`controllers`], [`scenarios`], [`metrics`] | `cutlab controllers`, `cutlab scenarios` and `cutlab metrics`: what the lab offers and what its metrics mean |
//! | [`calibrate`] | `cutlab calibrate`: the current-to-force models from a log of control periods |
//! | [`log`] | `cutlab log inspect`, `analyse`, `replay`: engineers' own logs |
//! | [`learn`] | `cutlab learn`: paper 004's power-law network learned from trial cuts on a preset or from a table of your own |
//! | [`lesson`] | `cutlab lesson check`: lesson files' schema, references, reference solutions and starting points |
//! | [`force`], [`filter`], [`spectrum`] | one cut's forces; Butterworth design and filtering; Welch spectra |
//! | [`fuzzy`] | `cutlab fuzzy eval` and `export`: the fuzzy engine on FLL and FIS files |
//! | [`device`], [`host`], [`protocol`] | the device emulator on stdin/stdout, the closed loop over the protocol, frames as JSON |
//! | [`table_args`] | command-line options made from a table of settings, one option per row |

pub mod args;
pub mod calibrate;
pub mod controllers;
pub mod device;
pub mod filter;
pub mod force;
pub mod fuzzy;
pub mod host;
pub mod learn;
pub mod lesson;
pub mod log;
pub mod metrics;
pub mod protocol;
pub mod scenarios;
pub mod sim;
pub mod spectrum;
pub mod table_args;
pub mod tune;

use std::io::{BufRead, Write};

use clap::{CommandFactory, Parser, Subcommand};

use crate::closed_loop::calibration_file::CalibrationFile;
use crate::estimation::estimator::Calibration;

pub use args::CliError;

/// The standard streams a command reads and writes.
pub struct Io<'a> {
    /// Standard input (samples, evaluations).
    pub stdin: &'a mut dyn BufRead,
    /// Standard output (results).
    pub stdout: &'a mut dyn Write,
}

/// cutlab — adaptive cutting-force control of CNC milling: signal chain, simulated machine,
/// estimators, controllers and safety envelope.
#[derive(Debug, Parser)]
#[command(
    name = "cutlab",
    version,
    about = "cutlab — adaptive cutting-force control of CNC milling: signal chain, simulated \
             machine, estimators, controllers and safety envelope.",
    arg_required_else_help = false
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

/// Every subcommand; [`COMMANDS`] lists their names. One is parsed per process, so the size of
/// the largest variant costs nothing worth boxing.
#[derive(Debug, Subcommand)]
#[allow(clippy::large_enum_variant)]
enum Command {
    /// Fit the current-to-force models from a logged teach cut (CSV)
    #[command(long_about = calibrate::ABOUT)]
    Calibrate(calibrate::CalibrateArgs),
    /// Run several controllers on one preset and print their metrics side by side
    Compare(sim::CompareArgs),
    /// List the controllers with their parameters, defaults and units
    Controllers(controllers::ControllersArgs),
    /// Run a preset's simulated machine behind the feed-override protocol on stdin/stdout
    #[command(long_about = device::ABOUT)]
    Device(device::DeviceArgs),
    /// Design a Butterworth filter (second-order sections) or apply one to f64 samples
    #[command(long_about = filter::ABOUT)]
    Filter(filter::FilterArgs),
    /// Mean and peak milling forces of one cut (mechanistic model, whole revolutions)
    #[command(long_about = force::ABOUT)]
    Force(force::ForceArgs),
    /// Evaluate a fuzzy engine from an FLL or FIS file, or export an engine as FLL or FIS
    #[command(long_about = fuzzy::ABOUT)]
    Fuzzy(fuzzy::FuzzyArgs),
    /// Run the closed loop against a device over the feed-override protocol
    #[command(long_about = host::ABOUT)]
    Host(host::HostArgs),
    /// Learn paper 004's power-law network from trial cuts on a preset's machine or your own table
    #[command(long_about = learn::ABOUT)]
    Learn(learn::LearnArgs),
    /// Check lesson files: schema, references, reference solutions (pass), starting points (fail)
    #[command(long_about = lesson::ABOUT)]
    Lesson(lesson::LessonArgs),
    /// Read a machine's CSV log as it is: its dialect, columns and problems
    #[command(long_about = log::ABOUT)]
    Log(log::LogArgs),
    /// What each row of the metrics table means, and when a run's value is marked better
    Metrics(metrics::MetricsArgs),
    /// Decode the feed-override protocol's bytes to JSON lines, or encode JSON lines to bytes
    #[command(long_about = protocol::ABOUT)]
    Protocol(protocol::ProtocolArgs),
    /// List the papers' experiments (presets), or run one open-loop
    Scenarios(scenarios::ScenariosArgs),
    /// Run one closed loop on a preset: teach cut, controller, safety envelope, metrics
    Sim(sim::SimArgs),
    /// Welch power spectral density of f64 samples on stdin (scipy.signal.welch)
    #[command(long_about = spectrum::ABOUT)]
    Spectrum(spectrum::SpectrumArgs),
    /// Tune a controller's parameters (grid sweep or Nelder–Mead) across scenarios
    #[command(long_about = tune::ABOUT)]
    Tune(tune::TuneArgs),
}

/// A subcommand's name and its line in `cutlab --help`.
pub struct CommandInfo {
    /// The word typed after `cutlab`.
    pub name: &'static str,
}

/// Every subcommand's name, in `--help` order.
pub const COMMANDS: &[CommandInfo] = &[
    CommandInfo { name: "calibrate" },
    CommandInfo { name: "compare" },
    CommandInfo {
        name: "controllers",
    },
    CommandInfo { name: "device" },
    CommandInfo { name: "filter" },
    CommandInfo { name: "force" },
    CommandInfo { name: "fuzzy" },
    CommandInfo { name: "host" },
    CommandInfo { name: "learn" },
    CommandInfo { name: "lesson" },
    CommandInfo { name: "log" },
    CommandInfo { name: "metrics" },
    CommandInfo { name: "protocol" },
    CommandInfo { name: "scenarios" },
    CommandInfo { name: "sim" },
    CommandInfo { name: "spectrum" },
    CommandInfo { name: "tune" },
];

/// Prints the help of the command at `path` (`["filter"]` for `cutlab filter`): what a command
/// made of subcommands shows when none is named.
pub fn print_help(io: &mut Io<'_>, path: &[&str]) -> Result<(), CliError> {
    let mut command = Cli::command();
    for name in path {
        let Some(sub) = command.find_subcommand(name).cloned() else {
            break;
        };
        command = sub.bin_name(format!("cutlab {}", path.join(" ")));
    }
    write!(io.stdout, "{}", command.render_long_help())?;
    Ok(())
}

/// The version line `--version` prints.
pub fn version_line() -> String {
    format!("cutlab {}", env!("CARGO_PKG_VERSION"))
}

/// The parser: every option that takes a value takes a negative one too (`--target-a -1` is a
/// value the command refuses with its range, not an unknown option `-1`).
fn command() -> clap::Command {
    fn negative_values(command: clap::Command) -> clap::Command {
        command
            .mut_args(|arg| {
                if arg.get_action().takes_values() {
                    arg.allow_negative_numbers(true)
                } else {
                    arg
                }
            })
            .mut_subcommands(negative_values)
    }
    negative_values(Cli::command())
}

/// Runs the command line on `args` (without the program name).
pub fn run(args: &[String], io: &mut Io<'_>) -> Result<(), CliError> {
    // clap prints the version at --version whatever follows; a stray word is a mistake to say.
    if let [first, extra, ..] = args {
        if first == "--version" || first == "-V" {
            return Err(CliError::new(format!(
                "{first} takes no arguments, got {extra:?}"
            )));
        }
    }
    let parsed = match command()
        .try_get_matches_from(std::iter::once("cutlab").chain(args.iter().map(String::as_str)))
        .and_then(|matches| <Cli as clap::FromArgMatches>::from_arg_matches(&matches))
    {
        Ok(parsed) => parsed,
        Err(e) => {
            use clap::error::ErrorKind;
            return match e.kind() {
                ErrorKind::DisplayHelp | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
                    write!(io.stdout, "{}", e.render())?;
                    Ok(())
                }
                ErrorKind::DisplayVersion => {
                    writeln!(io.stdout, "{}", version_line())?;
                    Ok(())
                }
                _ => Err(args::one_line(&e, args, &command())),
            };
        }
    };
    match parsed.command {
        None => {
            write!(io.stdout, "{}", Cli::command().render_help())?;
            Ok(())
        }
        Some(Command::Calibrate(a)) => calibrate::run(a, io),
        Some(Command::Compare(a)) => sim::run_compare(a, io),
        Some(Command::Controllers(a)) => controllers::run(a, io),
        Some(Command::Device(a)) => device::run(a, io),
        Some(Command::Filter(a)) => filter::run(a, io),
        Some(Command::Force(a)) => force::run(a, io),
        Some(Command::Fuzzy(a)) => fuzzy::run(a, io),
        Some(Command::Host(a)) => host::run(a, io),
        Some(Command::Learn(a)) => learn::run(a, io),
        Some(Command::Lesson(a)) => lesson::run(a, io),
        Some(Command::Log(a)) => log::run(a, io),
        Some(Command::Metrics(a)) => metrics::run(a, io),
        Some(Command::Protocol(a)) => protocol::run(a, io),
        Some(Command::Scenarios(a)) => scenarios::run(a, io),
        Some(Command::Sim(a)) => sim::run_sim(a, io),
        Some(Command::Spectrum(a)) => spectrum::run(a, io),
        Some(Command::Tune(a)) => tune::run(a, io),
    }
}

/// Writes `value` as pretty JSON followed by a newline.
pub fn write_json<T: serde::Serialize>(out: &mut dyn Write, value: &T) -> Result<(), CliError> {
    serde_json::to_writer_pretty(&mut *out, value)
        .map_err(|e| CliError::new(format!("cannot write JSON: {e}")))?;
    writeln!(out)?;
    Ok(())
}

/// Reads the calibration file `--calibration PATH` names.
pub fn read_calibration(path: &str) -> Result<CalibrationFile, CliError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| CliError::new(format!("--calibration: cannot read {path:?}: {e}")))?;
    CalibrationFile::from_json(&text)
        .map_err(|e| CliError::new(format!("--calibration {path}: {e}")))
}

/// Prints what `calibration` rests on (the teach cut's or a file's), in the fit's words, one
/// `warning:` line each, as `cutlab calibrate` and the Hardware page say it.
pub fn print_calibration_warnings(
    out: &mut dyn Write,
    calibration: &Calibration,
) -> Result<(), CliError> {
    for warning in crate::estimation::teach_fit::load_level_warnings(calibration) {
        writeln!(out, "warning: {warning}")?;
    }
    Ok(())
}

/// Writes `calibration`, made by `source`, to the file `--save-calibration PATH` names.
pub fn save_calibration(
    path: &str,
    calibration: &Calibration,
    source: String,
) -> Result<(), CliError> {
    let text = CalibrationFile::new(calibration.clone(), source).to_json();
    std::fs::write(path, text + "\n")
        .map_err(|e| CliError::new(format!("--save-calibration: cannot write {path:?}: {e}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_command_list_is_the_parsers() {
        let parsed: Vec<String> = Cli::command()
            .get_subcommands()
            .map(|c| c.get_name().to_string())
            .collect();
        let listed: Vec<&str> = COMMANDS.iter().map(|c| c.name).collect();
        assert_eq!(parsed, listed);
        Cli::command().debug_assert();
    }
}
