//! `cutlab controllers`: the controllers, their parameters, defaults and units.

use serde::Serialize;

use super::{help_text_for, wants_help, write_json, CliError, Io, OptionSpec, Options};
use crate::control::registry::{ControllerKind, ParamSpec};

const OPTIONS: &[OptionSpec] = &[OptionSpec::flag("json", "Print JSON instead of a table")];

#[derive(Serialize)]
struct ControllerListing {
    name: &'static str,
    label: &'static str,
    source: &'static str,
    params: &'static [ParamSpec],
}

/// Runs `cutlab controllers`.
pub fn run(args: &[String], io: &mut Io<'_>) -> Result<(), CliError> {
    if wants_help(args) {
        return help_text_for(
            io,
            "cutlab controllers [--json]",
            "List the feed-override controllers with their parameters (default, range, unit).\n\
             Set a parameter in `cutlab sim` with --set key=value.",
            OPTIONS,
        );
    }
    let options = Options::parse(args, OPTIONS)?;
    options.reject_positionals("")?;
    if options.flag("json") {
        let listing: Vec<ControllerListing> = ControllerKind::ALL
            .iter()
            .map(|k| ControllerListing {
                name: k.name(),
                label: k.label(),
                source: k.source(),
                params: k.params(),
            })
            .collect();
        return write_json(io.stdout, &listing);
    }
    for kind in ControllerKind::ALL {
        writeln!(
            io.stdout,
            "{} — {} ({})",
            kind.name(),
            kind.label(),
            kind.source()
        )?;
        for p in kind.params() {
            let unit = if p.unit.is_empty() {
                String::new()
            } else {
                format!(" {}", p.unit)
            };
            writeln!(
                io.stdout,
                "    {:<26} default {}{unit}, range {}..={}: {}",
                p.key, p.default, p.min, p.max, p.help
            )?;
        }
        writeln!(io.stdout)?;
    }
    Ok(())
}
