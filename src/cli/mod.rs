//! The `cutlab` command line: the same core as the browser lab, in a terminal.
//!
//! [`run`] takes the arguments and the standard streams, so tests drive the whole command line
//! in-process. Each subcommand lives in its own module with a `run(args, io)` function and lists
//! itself once in [`COMMANDS`], which also produces the top-level help.

pub mod args;
pub mod calibrate;
pub mod controllers;
pub mod filter;
pub mod force;
pub mod fuzzy;
pub mod scenarios;
pub mod sim;
pub mod spectrum;

use std::io::{BufRead, Write};

pub use args::{CliError, OptionSpec, Options};

/// The standard streams a subcommand reads and writes.
pub struct Io<'a> {
    /// Standard input (samples, evaluations).
    pub stdin: &'a mut dyn BufRead,
    /// Standard output (results).
    pub stdout: &'a mut dyn Write,
}

/// One subcommand: its name, a line of help and its entry point.
pub struct Command {
    /// The word typed after `cutlab`.
    pub name: &'static str,
    /// One line for `cutlab --help`.
    pub about: &'static str,
    /// Runs the subcommand on the arguments after its name.
    pub run: fn(&[String], &mut Io<'_>) -> Result<(), CliError>,
}

/// Every subcommand, in the order `cutlab --help` lists them.
pub const COMMANDS: &[Command] = &[
    Command {
        name: "calibrate",
        about: "Fit the current-to-force models from a logged teach cut (CSV)",
        run: calibrate::run,
    },
    Command {
        name: "compare",
        about: "Run several controllers on one preset and print their metrics side by side",
        run: sim::run_compare,
    },
    Command {
        name: "controllers",
        about: "List the controllers with their parameters, defaults and units",
        run: controllers::run,
    },
    Command {
        name: "filter",
        about: "Design a Butterworth filter (second-order sections) or apply one to f64 samples",
        run: filter::run,
    },
    Command {
        name: "force",
        about: "Mean and peak milling forces of one cut (mechanistic model, whole revolutions)",
        run: force::run,
    },
    Command {
        name: "fuzzy",
        about: "Evaluate a fuzzy engine from an FLL file, or export paper 002's engine as FLL",
        run: fuzzy::run,
    },
    Command {
        name: "scenarios",
        about: "List the papers' experiments (presets), or run one open-loop",
        run: scenarios::run,
    },
    Command {
        name: "sim",
        about: "Run one closed loop on a preset: teach cut, controller, safety envelope, metrics",
        run: sim::run_sim,
    },
    Command {
        name: "spectrum",
        about: "Welch power spectral density of f64 samples on stdin (scipy.signal.welch)",
        run: spectrum::run,
    },
];

/// The version line printed by `cutlab --version`.
pub fn version_line() -> String {
    format!("cutlab {}", env!("CARGO_PKG_VERSION"))
}

/// The top-level help.
pub fn help_text() -> String {
    let mut out = String::from(
        "cutlab — adaptive cutting-force control of CNC milling: signal chain, simulated machine,\n\
         estimators, controllers and safety envelope.\n\n\
         Usage: cutlab <COMMAND> [OPTIONS]\n\nCommands:\n",
    );
    let width = COMMANDS.iter().map(|c| c.name.len()).max().unwrap_or(0);
    for c in COMMANDS {
        out.push_str(&format!("  {:width$}  {}\n", c.name, c.about));
    }
    out.push_str(
        "\nOptions:\n  --help     Print this help (also after a command: cutlab <COMMAND> --help)\n  \
         --version  Print the version\n",
    );
    out
}

/// Runs the command line on `args` (without the program name).
pub fn run(args: &[String], io: &mut Io<'_>) -> Result<(), CliError> {
    let Some(first) = args.first() else {
        io.stdout.write_all(help_text().as_bytes())?;
        return Ok(());
    };
    match first.as_str() {
        "--help" | "-h" | "help" => {
            io.stdout.write_all(help_text().as_bytes())?;
            Ok(())
        }
        "--version" | "-V" => {
            if let Some(extra) = args.get(1) {
                return Err(CliError::new(format!(
                    "{first} takes no arguments, got {extra:?}"
                )));
            }
            writeln!(io.stdout, "{}", version_line())?;
            Ok(())
        }
        name => {
            let command = COMMANDS.iter().find(|c| c.name == name).ok_or_else(|| {
                CliError::new(format!(
                    "unknown command {name:?}; commands: {}",
                    COMMANDS
                        .iter()
                        .map(|c| c.name)
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            })?;
            (command.run)(&args[1..], io)
        }
    }
}

/// True when `args` asks for help (`--help` or `-h` anywhere before a `--`).
pub fn wants_help(args: &[String]) -> bool {
    args.iter()
        .take_while(|a| a.as_str() != "--")
        .any(|a| a == "--help" || a == "-h")
}

/// Prints a subcommand's help.
pub fn help_text_for(
    io: &mut Io<'_>,
    usage: &str,
    about: &str,
    options: &[OptionSpec],
) -> Result<(), CliError> {
    io.stdout
        .write_all(args::help_text(usage, about, options).as_bytes())?;
    Ok(())
}

/// Writes `value` as pretty JSON followed by a newline.
pub fn write_json<T: serde::Serialize>(out: &mut dyn Write, value: &T) -> Result<(), CliError> {
    serde_json::to_writer_pretty(&mut *out, value)
        .map_err(|e| CliError::new(format!("cannot write JSON: {e}")))?;
    writeln!(out)?;
    Ok(())
}
