//! Option values and errors of the command line.
//!
//! clap (derive) declares every command's options and parses the arguments; values stay text
//! until the command reads them with [`value`], [`required`] or [`value_or`], so an error names
//! the option and says why (`--order: cannot parse "x" as a non-negative integer`), and ranges
//! are checked where the value is used. [`one_line`] turns clap's own errors (unknown option,
//! missing value, an option given twice, an unknown command) into the one line the command line
//! prints.

use std::fmt;
use std::str::FromStr;

use clap::error::{ContextKind, ContextValue, ErrorKind};

/// A command-line error: one line for stderr.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CliError(pub String);

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for CliError {}

impl CliError {
    /// An error with the given message.
    pub fn new(message: impl Into<String>) -> Self {
        Self(message.into())
    }
}

impl From<std::io::Error> for CliError {
    fn from(e: std::io::Error) -> Self {
        Self(format!("I/O error: {e}"))
    }
}

/// Parses `text` as the value of option `name`, naming both in the error.
pub fn parse_value<T: FromStr>(name: &str, text: &str) -> Result<T, CliError> {
    text.trim().parse::<T>().map_err(|_| {
        CliError::new(format!(
            "--{name}: cannot parse {text:?} as {}",
            type_description::<T>()
        ))
    })
}

/// The value of `--name` parsed as `T`, or `None` if it was not given.
pub fn value<T: FromStr>(name: &str, text: &Option<String>) -> Result<Option<T>, CliError> {
    text.as_deref()
        .map(|text| parse_value(name, text))
        .transpose()
}

/// The value of `--name` parsed as `T`; an error if it was not given.
pub fn required<T: FromStr>(name: &str, text: &Option<String>) -> Result<T, CliError> {
    value(name, text)?.ok_or_else(|| CliError::new(format!("missing required option --{name}")))
}

/// The value of `--name` parsed as `T`, or `default` if it was not given.
pub fn value_or<T: FromStr>(name: &str, text: &Option<String>, default: T) -> Result<T, CliError> {
    Ok(value(name, text)?.unwrap_or(default))
}

/// An error naming the first stray argument of a command that takes none; `hint` (if not empty)
/// says where such input goes instead.
pub fn reject_extra(extra: &[String], hint: &str) -> Result<(), CliError> {
    match extra.first() {
        Some(extra) if hint.is_empty() => {
            Err(CliError::new(format!("unexpected argument {extra:?}")))
        }
        Some(extra) => Err(CliError::new(format!(
            "unexpected argument {extra:?} ({hint})"
        ))),
        None => Ok(()),
    }
}

fn type_description<T>() -> &'static str {
    let name = std::any::type_name::<T>();
    match name {
        "f64" | "f32" => "a number",
        "u64" | "u32" | "usize" | "u16" | "u8" => "a non-negative integer",
        "i64" | "i32" | "isize" => "an integer",
        _ => "a value of the expected form",
    }
}

fn context(e: &clap::Error, kind: ContextKind) -> Option<String> {
    match e.get(kind)? {
        ContextValue::String(s) => Some(s.clone()),
        ContextValue::Strings(v) => v.first().cloned(),
        _ => None,
    }
}

/// clap's most likely subcommand for a misspelt one (it lists them most similar last).
fn best_suggestion(e: &clap::Error) -> Option<String> {
    match e.get(ContextKind::SuggestedSubcommand)? {
        ContextValue::String(s) => Some(s.clone()),
        ContextValue::Strings(v) => v.last().cloned(),
        _ => None,
    }
}

/// The option's name as typed on the command line (`--order`), from clap's `--order <N>`.
fn option_name(arg: &str) -> &str {
    arg.split([' ', '=']).next().unwrap_or(arg)
}

/// The placeholder of an option's value (`N` from clap's `--order <N>`), if it takes one.
fn placeholder(arg: &str) -> Option<&str> {
    let (_, rest) = arg.split_once(' ')?;
    let rest = rest.trim_end_matches("...");
    Some(rest.trim_start_matches('<').trim_end_matches('>'))
}

/// The values `args` gives option `name` (`--cutoff 5`, `--cutoff=6`), in order, up to `--`.
fn given_values(args: &[String], name: &str) -> Vec<String> {
    let mut values = Vec::new();
    let mut iter = args.iter().take_while(|a| *a != "--");
    while let Some(arg) = iter.next() {
        if arg == name {
            values.extend(iter.next().cloned());
        } else if let Some(value) = arg
            .strip_prefix(name)
            .and_then(|rest| rest.strip_prefix('='))
        {
            values.push(value.to_string());
        }
    }
    values
}

/// clap's error on `args` (without the program name) as the one line the command line prints;
/// `root` is the command that parsed them, whose subcommands an unknown one is told. A misspelt
/// option or command gets clap's suggestion.
pub fn one_line(e: &clap::Error, args: &[String], root: &clap::Command) -> CliError {
    let suggestion = context(e, ContextKind::SuggestedArg)
        .or_else(|| best_suggestion(e))
        .map(|s| format!(" (did you mean {s}?)"))
        .unwrap_or_default();
    let invalid_arg = context(e, ContextKind::InvalidArg);
    let message = match (e.kind(), invalid_arg) {
        (ErrorKind::UnknownArgument, Some(arg)) if arg.starts_with('-') && arg.len() > 1 => {
            format!(
                "unknown option {}{suggestion} (see --help)",
                option_name(&arg)
            )
        }
        (ErrorKind::UnknownArgument, Some(arg)) => format!("unexpected argument {arg:?}"),
        (ErrorKind::InvalidSubcommand, _) => match context(e, ContextKind::InvalidSubcommand) {
            Some(name) => unknown_subcommand(&name, &suggestion, e, root),
            None => first_line(e),
        },
        (ErrorKind::ArgumentConflict, Some(arg)) => {
            let name = option_name(&arg);
            let prior = context(e, ContextKind::PriorArg);
            match prior.as_deref().map(option_name) {
                Some(other) if other != name => format!("{name} cannot be given with {other}"),
                _ => match (placeholder(&arg), given_values(args, name).as_slice()) {
                    (Some(_), [first, second, ..]) => {
                        format!("{name} is given twice ({first:?}, then {second:?})")
                    }
                    _ => format!("{name} is given twice"),
                },
            }
        }
        (ErrorKind::InvalidValue | ErrorKind::NoEquals, Some(arg)) => match placeholder(&arg) {
            Some(value) => format!("{} needs a value ({value})", option_name(&arg)),
            None => format!("{} needs a value", option_name(&arg)),
        },
        (ErrorKind::ValueValidation, Some(arg)) => {
            let value = context(e, ContextKind::InvalidValue).unwrap_or_default();
            match value.trim().parse::<f64>() {
                Ok(v) if v < 0.0 => format!(
                    "{}: cannot be negative, got {}",
                    option_name(&arg),
                    crate::input::readable(v)
                ),
                _ => match std::error::Error::source(e) {
                    Some(why) => format!("{}: cannot read {value:?}: {why}", option_name(&arg)),
                    None => format!("{}: cannot read {value:?}", option_name(&arg)),
                },
            }
        }
        (ErrorKind::TooManyValues, Some(arg)) if placeholder(&arg).is_none() => {
            format!("{} takes no value", option_name(&arg))
        }
        (ErrorKind::MissingRequiredArgument, Some(arg)) => {
            format!("missing required option {}", option_name(&arg))
        }
        _ => first_line(e),
    };
    CliError::new(message)
}

/// `unknown command "x"` (or `unknown filter subcommand "x"`) with clap's suggestion and the
/// names that exist.
fn unknown_subcommand(
    name: &str,
    suggestion: &str,
    e: &clap::Error,
    root: &clap::Command,
) -> String {
    let path = parent_command(e);
    let mut command = root;
    for word in &path {
        match command.find_subcommand(word) {
            Some(sub) => command = sub,
            None => break,
        }
    }
    let names: Vec<&str> = command
        .get_subcommands()
        .filter(|c| !c.is_hide_set() && c.get_name() != "help")
        .map(|c| c.get_name())
        .collect();
    let (what, plural) = match path.as_slice() {
        [] => (String::from("command"), "commands"),
        path => (format!("{} subcommand", path.join(" ")), "subcommands"),
    };
    if names.is_empty() {
        format!("unknown {what} {name:?}{suggestion}")
    } else {
        format!(
            "unknown {what} {name:?}{suggestion}; {plural}: {}",
            names.join(", ")
        )
    }
}

/// The command whose subcommand was misspelt (`["filter"]` in `cutlab filter frobnicate`), read
/// from the usage line clap attaches; empty at the top level (and for `cutlab help frobnicate`).
fn parent_command(e: &clap::Error) -> Vec<String> {
    let usage = match e.get(ContextKind::Usage) {
        Some(ContextValue::StyledStr(s)) => s.to_string(),
        _ => return Vec::new(),
    };
    let usage = usage.trim_start();
    usage
        .strip_prefix("Usage:")
        .unwrap_or(usage)
        .split_whitespace()
        .skip(1)
        .take_while(|w| !w.starts_with(['<', '[', '-']))
        .filter(|w| *w != "help")
        .map(str::to_string)
        .collect()
}

fn first_line(e: &clap::Error) -> String {
    let text = e.to_string();
    let line = text.lines().next().unwrap_or_default();
    line.strip_prefix("error: ").unwrap_or(line).to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_parsed_where_read_and_errors_name_the_option() {
        assert_eq!(value::<f64>("fs", &Some(" 10 ".into())), Ok(Some(10.0)));
        assert_eq!(value::<f64>("fs", &None), Ok(None));
        assert_eq!(value_or::<u32>("order", &None, 4), Ok(4));
        let e = required::<usize>("order", &Some("-1".into())).unwrap_err();
        assert_eq!(
            e.0,
            "--order: cannot parse \"-1\" as a non-negative integer"
        );
        let e = required::<f64>("cutoff", &None).unwrap_err();
        assert_eq!(e.0, "missing required option --cutoff");
        assert_eq!(
            reject_extra(&["x".into()], "samples come on stdin")
                .unwrap_err()
                .0,
            "unexpected argument \"x\" (samples come on stdin)"
        );
    }

    #[test]
    fn option_names_placeholders_and_given_values_come_from_clap_and_the_args() {
        assert_eq!(option_name("--order <N>"), "--order");
        assert_eq!(placeholder("--set <KEY=VALUE>..."), Some("KEY=VALUE"));
        assert_eq!(placeholder("--json"), None);
        let args: Vec<String> = ["--fs", "1", "--fs=2", "--fsx", "3", "--", "--fs", "4"]
            .map(String::from)
            .to_vec();
        assert_eq!(given_values(&args, "--fs"), ["1", "2"]);
    }
}
