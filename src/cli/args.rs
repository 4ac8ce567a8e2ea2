//! A small, strict command-line option parser.
//!
//! Each subcommand declares its options as a table of [`OptionSpec`]; the same table produces the
//! help text and rejects anything unknown, so a typo never silently falls back to a default.
//! Values are parsed where they are read, and every error names the option it came from.

use std::collections::BTreeMap;
use std::fmt;
use std::str::FromStr;

/// One option a subcommand accepts.
#[derive(Debug, Clone, Copy)]
pub struct OptionSpec {
    /// Long name without the leading dashes, e.g. `"order"`.
    pub name: &'static str,
    /// Placeholder for the value in help text (`"N"`), or `None` for a flag without a value.
    pub value: Option<&'static str>,
    /// One line of help, units included.
    pub help: &'static str,
    /// Whether the option may be given more than once (each value kept, in order). Any other
    /// option given twice is an error: silently keeping one of two values hides a typo.
    pub repeatable: bool,
}

impl OptionSpec {
    /// An option that takes a value.
    pub const fn value(name: &'static str, value: &'static str, help: &'static str) -> Self {
        Self {
            name,
            value: Some(value),
            help,
            repeatable: false,
        }
    }

    /// An option that takes a value and may be given any number of times.
    pub const fn repeatable(name: &'static str, value: &'static str, help: &'static str) -> Self {
        Self {
            name,
            value: Some(value),
            help,
            repeatable: true,
        }
    }

    /// A flag without a value.
    pub const fn flag(name: &'static str, help: &'static str) -> Self {
        Self {
            name,
            value: None,
            help,
            repeatable: false,
        }
    }
}

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

/// Parsed options of one subcommand.
#[derive(Debug, Default)]
pub struct Options {
    values: BTreeMap<&'static str, Vec<String>>,
    positionals: Vec<String>,
}

impl Options {
    /// Parses `args` (everything after the subcommand's name) against `specs`.
    ///
    /// Accepts `--name value`, `--name=value` and bare flags; anything not starting with `--` is a
    /// positional argument; `--` ends option parsing.
    pub fn parse(args: &[String], specs: &[OptionSpec]) -> Result<Self, CliError> {
        let mut options = Options::default();
        let mut iter = args.iter();
        while let Some(arg) = iter.next() {
            if arg == "--" {
                options.positionals.extend(iter.by_ref().cloned());
                break;
            }
            let Some(body) = arg.strip_prefix("--") else {
                if arg.starts_with('-') && arg.len() > 1 && arg.parse::<f64>().is_err() {
                    return Err(CliError::new(format!(
                        "unknown option {arg:?}: options are spelled --name (see --help)"
                    )));
                }
                options.positionals.push(arg.clone());
                continue;
            };
            let (name, inline_value) = match body.split_once('=') {
                Some((n, v)) => (n, Some(v.to_string())),
                None => (body, None),
            };
            let Some(spec) = specs.iter().find(|s| s.name == name) else {
                return Err(CliError::new(format!(
                    "unknown option --{name} (see --help)"
                )));
            };
            let value = match (spec.value, inline_value) {
                (None, None) => String::new(),
                (None, Some(_)) => {
                    return Err(CliError::new(format!("--{name} takes no value")));
                }
                (Some(_), Some(v)) => v,
                (Some(placeholder), None) => iter.next().cloned().ok_or_else(|| {
                    CliError::new(format!("--{name} needs a value ({placeholder})"))
                })?,
            };
            let values = options.values.entry(spec.name).or_default();
            if let Some(first) = values.first().filter(|_| !spec.repeatable) {
                return Err(CliError::new(match spec.value {
                    Some(_) => format!("--{name} is given twice ({first:?}, then {value:?})"),
                    None => format!("--{name} is given twice"),
                }));
            }
            values.push(value);
        }
        Ok(options)
    }

    /// Whether the flag `name` was given.
    pub fn flag(&self, name: &str) -> bool {
        self.values.contains_key(name)
    }

    /// The raw text of the last `--name`, if given.
    pub fn text(&self, name: &str) -> Option<&str> {
        self.values
            .get(name)
            .and_then(|v| v.last())
            .map(String::as_str)
    }

    /// Every value given for a repeatable option, in order.
    pub fn all(&self, name: &str) -> &[String] {
        self.values.get(name).map(Vec::as_slice).unwrap_or(&[])
    }

    /// The positional arguments.
    pub fn positionals(&self) -> &[String] {
        &self.positionals
    }

    /// An error naming the first positional argument, for commands that take none; `hint` (if
    /// not empty) says where such input goes instead.
    pub fn reject_positionals(&self, hint: &str) -> Result<(), CliError> {
        match self.positionals.first() {
            Some(extra) if hint.is_empty() => {
                Err(CliError::new(format!("unexpected argument {extra:?}")))
            }
            Some(extra) => Err(CliError::new(format!(
                "unexpected argument {extra:?} ({hint})"
            ))),
            None => Ok(()),
        }
    }

    /// The value of `--name` parsed as `T`, or `None` if absent.
    pub fn get<T: FromStr>(&self, name: &str) -> Result<Option<T>, CliError> {
        self.text(name)
            .map(|text| parse_value(name, text))
            .transpose()
    }

    /// The value of `--name` parsed as `T`; an error if absent.
    pub fn require<T: FromStr>(&self, name: &str) -> Result<T, CliError> {
        self.get(name)?
            .ok_or_else(|| CliError::new(format!("missing required option --{name}")))
    }

    /// The value of `--name` parsed as `T`, or `default` if absent.
    pub fn get_or<T: FromStr>(&self, name: &str, default: T) -> Result<T, CliError> {
        Ok(self.get(name)?.unwrap_or(default))
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

fn type_description<T>() -> &'static str {
    let name = std::any::type_name::<T>();
    match name {
        "f64" | "f32" => "a number",
        "u64" | "u32" | "usize" | "u16" | "u8" => "a non-negative integer",
        "i64" | "i32" | "isize" => "an integer",
        _ => "a value of the expected form",
    }
}

/// Help text for a subcommand: description, usage line and the option table.
pub fn help_text(usage: &str, about: &str, specs: &[OptionSpec]) -> String {
    let mut rows: Vec<(String, &str)> = specs
        .iter()
        .map(|s| match s.value {
            Some(v) => (format!("--{} {v}", s.name), s.help),
            None => (format!("--{}", s.name), s.help),
        })
        .collect();
    rows.push(("--help".to_string(), "Print this help"));
    let width = rows.iter().map(|(label, _)| label.len()).max().unwrap_or(0);
    let mut out = format!("{about}\n\nUsage: {usage}\n\nOptions:\n");
    for (label, help) in rows {
        out.push_str(&format!("  {label:width$}  {help}\n"));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const SPECS: &[OptionSpec] = &[
        OptionSpec::value("order", "N", "filter order"),
        OptionSpec::repeatable("set", "KEY=VALUE", "repeatable"),
        OptionSpec::flag("json", "print JSON"),
    ];

    fn strings(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn parses_values_flags_repeats_and_positionals() {
        let o = Options::parse(
            &strings(&[
                "--order",
                "4",
                "--json",
                "--set=a=1",
                "--set",
                "b=2",
                "file.csv",
            ]),
            SPECS,
        )
        .unwrap();
        assert_eq!(o.require::<usize>("order").unwrap(), 4);
        assert!(o.flag("json"));
        assert_eq!(o.all("set"), ["a=1", "b=2"]);
        assert_eq!(o.positionals(), ["file.csv"]);
    }

    #[test]
    fn an_option_given_twice_is_an_error_unless_repeatable() {
        let e = Options::parse(&strings(&["--order", "2", "--order=3"]), SPECS).unwrap_err();
        assert_eq!(e.0, r#"--order is given twice ("2", then "3")"#);
        let e = Options::parse(&strings(&["--json", "--json"]), SPECS).unwrap_err();
        assert_eq!(e.0, "--json is given twice");
    }

    #[test]
    fn negative_numbers_are_positionals_not_options() {
        let o = Options::parse(&strings(&["-3.5"]), SPECS).unwrap();
        assert_eq!(o.positionals(), ["-3.5"]);
    }

    #[test]
    fn errors_name_the_option() {
        let e = Options::parse(&strings(&["--ordr", "4"]), SPECS).unwrap_err();
        assert_eq!(e.0, "unknown option --ordr (see --help)");
        let e = Options::parse(&strings(&["--order"]), SPECS).unwrap_err();
        assert_eq!(e.0, "--order needs a value (N)");
        let o = Options::parse(&strings(&["--order", "four"]), SPECS).unwrap();
        let e = o.require::<usize>("order").unwrap_err();
        assert_eq!(
            e.0,
            "--order: cannot parse \"four\" as a non-negative integer"
        );
        let e = Options::parse(&[], SPECS)
            .unwrap()
            .require::<usize>("order")
            .unwrap_err();
        assert_eq!(e.0, "missing required option --order");
    }
}
