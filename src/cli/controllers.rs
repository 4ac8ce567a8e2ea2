//! `cutlab controllers`: the controllers, their parameters, defaults and units.

use serde::Serialize;

use super::{write_json, CliError, Io};
use crate::control::registry::{ControllerKind, ParamSpec};

/// List the feed-override controllers with their parameters (default, range, unit). Set a
/// parameter in `cutlab sim` with --set key=value.
#[derive(Debug, clap::Args)]
pub struct ControllersArgs {
    /// Print JSON instead of a table
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct ControllerListing {
    name: &'static str,
    label: &'static str,
    source: &'static str,
    params: &'static [ParamSpec],
}

/// Runs `cutlab controllers`.
pub fn run(args: ControllersArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    if args.json {
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
                "    {:<26} default {}{unit}, range {}: {}",
                p.key,
                p.default,
                crate::input::table::range_text(p.min, p.max, p.unit),
                p.help
            )?;
        }
        writeln!(io.stdout)?;
    }
    Ok(())
}
