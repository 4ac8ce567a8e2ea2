//! Option values and errors of the command line.
//!
//! clap (derive) declares every command's options and parses the arguments; values stay text
//! until the command reads them with [`value`], [`required`] or [`value_or`], so an error names
//! the option and says why (`--order: cannot parse "x" as a non-negative integer`), and ranges
//! are checked where the value is used. [`one_line`] turns clap's own errors (unknown option,
//! missing value, an option given twice) into the one line the command line prints.

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

/// The option's name as typed on the command line (`--order`), from clap's `--order <N>`.
fn option_name(arg: &str) -> &str {
    arg.split([' ', '=']).next().unwrap_or(arg)
}

/// clap's error as the one line the command line prints; a misspelt option or command gets
/// clap's suggestion.
pub fn one_line(e: &clap::Error) -> CliError {
    let suggestion = context(e, ContextKind::SuggestedArg)
        .or_else(|| context(e, ContextKind::SuggestedSubcommand))
        .map(|s| format!(" (did you mean {s}?)"))
        .unwrap_or_default();
    let message = match e.kind() {
        ErrorKind::UnknownArgument => match context(e, ContextKind::InvalidArg) {
            Some(arg) if arg.starts_with('-') && arg.len() > 1 => {
                format!(
                    "unknown option {}{suggestion} (see --help)",
                    option_name(&arg)
                )
            }
            Some(arg) => format!("unexpected argument {arg:?}"),
            None => first_line(e),
        },
        ErrorKind::InvalidSubcommand => match (
            context(e, ContextKind::InvalidSubcommand),
            parent_command(e),
        ) {
            (Some(name), Some(parent)) => format!(
                "unknown {parent} subcommand {name:?}{suggestion} (see cutlab {parent} --help)"
            ),
            (Some(name), None) => format!("unknown command {name:?}{suggestion} (see --help)"),
            (None, _) => first_line(e),
        },
        ErrorKind::ArgumentConflict => match context(e, ContextKind::InvalidArg) {
            Some(arg) => format!("{} is given twice", option_name(&arg)),
            None => first_line(e),
        },
        ErrorKind::InvalidValue | ErrorKind::NoEquals => {
            match context(e, ContextKind::InvalidArg) {
                Some(arg) => format!("{} needs a value", option_name(&arg)),
                None => first_line(e),
            }
        }
        ErrorKind::MissingRequiredArgument => match context(e, ContextKind::InvalidArg) {
            Some(arg) => format!("missing required option {}", option_name(&arg)),
            None => first_line(e),
        },
        _ => first_line(e),
    };
    CliError::new(message)
}

/// The command whose subcommand was misspelt (`filter` in `cutlab filter frobnicate`), read from
/// the usage line clap attaches; `None` at the top level.
fn parent_command(e: &clap::Error) -> Option<String> {
    let usage = match e.get(ContextKind::Usage)? {
        ContextValue::StyledStr(s) => s.to_string(),
        _ => return None,
    };
    let after = usage.split("cutlab").nth(1)?;
    let words: Vec<&str> = after
        .split_whitespace()
        .take_while(|w| !w.starts_with(['<', '[', '-']))
        .collect();
    (!words.is_empty()).then(|| words.join(" "))
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
}
