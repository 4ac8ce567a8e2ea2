//! Command-line options made from a table of settings ([`crate::input::table`]): one option per
//! row, named by its `cli_option`, its help the row's help with its unit, range and default, its
//! text kept as typed until the table parses it. A row added to a table is an option at once.

use std::fmt::Debug;
use std::marker::PhantomData;

use crate::input::readable;
use crate::input::table::{Kind, Row, Shown, Table};

/// The rows a command takes as options: all of a table's, or some.
pub trait OptionRows: Clone + Debug + Default + Send + Sync + 'static {
    /// The table.
    type Setting: Table + Send + Sync;
    /// The rows, in the order `--help` lists them.
    const ROWS: &'static [Self::Setting];
}

/// The text of each option given, by its row.
#[derive(Debug, Clone)]
pub struct TableArgs<R: OptionRows> {
    texts: Vec<(R::Setting, String)>,
    rows: PhantomData<R>,
}

impl<R: OptionRows> Default for TableArgs<R> {
    fn default() -> Self {
        Self {
            texts: Vec::new(),
            rows: PhantomData,
        }
    }
}

impl<R: OptionRows> TableArgs<R> {
    /// Each option given with its text, in the rows' order.
    pub fn texts(&self) -> Vec<(R::Setting, &str)> {
        self.texts.iter().map(|(s, t)| (*s, t.as_str())).collect()
    }

    /// The text given for `setting`, if any.
    pub fn given(&self, setting: R::Setting) -> Option<&str> {
        self.texts
            .iter()
            .find(|(s, _)| *s == setting)
            .map(|(_, t)| t.as_str())
    }

    /// The options given, as typed (`--order`), for refusing them where they do not apply.
    pub fn given_options(&self) -> Vec<String> {
        self.texts
            .iter()
            .map(|(s, _)| format!("--{}", s.row().cli_option))
            .collect()
    }
}

/// The placeholder of a row's value in `--help` (`--order <N>`).
fn placeholder(row: &Row) -> &'static str {
    match row.kind {
        Kind::Count { .. } | Kind::Seed => "N",
        Kind::Choice => "NAME",
        Kind::Number { .. } => match row.unit {
            "%" => "PCT",
            "s" => "S",
            "Hz" => "HZ",
            "mm" => "MM",
            "A" => "A",
            _ => "X",
        },
    }
}

/// A row's help for `--help`: what it is, its unit and range, and its default.
pub fn option_help(row: &Row) -> String {
    let unit = match row.unit {
        "" => String::new(),
        unit => format!(" {unit}"),
    };
    let range = match row.kind {
        Kind::Number { min, max } => format!("{}–{}{unit}", readable(min), readable(max)),
        Kind::Count { min, max } => format!("{min}–{max}{unit}"),
        Kind::Seed | Kind::Choice => String::new(),
    };
    let default = match row.default {
        Shown::Blank => String::new(),
        _ => format!("default {}", row.default_text()),
    };
    let detail: Vec<String> = [range, default]
        .into_iter()
        .filter(|s| !s.is_empty())
        .collect();
    if detail.is_empty() {
        row.help.to_string()
    } else {
        format!("{} ({})", row.help, detail.join("; "))
    }
}

impl<R: OptionRows> clap::FromArgMatches for TableArgs<R> {
    fn from_arg_matches(matches: &clap::ArgMatches) -> Result<Self, clap::Error> {
        Self::from_arg_matches_mut(&mut matches.clone())
    }

    fn from_arg_matches_mut(matches: &mut clap::ArgMatches) -> Result<Self, clap::Error> {
        Ok(Self {
            texts: R::ROWS
                .iter()
                .filter_map(|s| {
                    matches
                        .remove_one::<String>(s.row().cli_option)
                        .map(|text| (*s, text))
                })
                .collect(),
            rows: PhantomData,
        })
    }

    fn update_from_arg_matches(&mut self, matches: &clap::ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(matches)?;
        Ok(())
    }
}

impl<R: OptionRows> clap::Args for TableArgs<R> {
    fn augment_args(command: clap::Command) -> clap::Command {
        let mut command = command;
        for s in R::ROWS {
            let row = s.row();
            command = command.arg(
                clap::Arg::new(row.cli_option)
                    .long(row.cli_option)
                    .value_name(placeholder(&row))
                    .value_parser(clap::value_parser!(String))
                    .allow_hyphen_values(true)
                    .help(option_help(&row)),
            );
        }
        command
    }

    fn augment_args_for_update(command: clap::Command) -> clap::Command {
        Self::augment_args(command)
    }
}
