//! `cutlab metrics`: the glossary of the metrics table `cutlab sim` and `cutlab compare` print,
//! the same entries the browser shows behind each row's "?" ([`METRIC_ROWS`]).

use serde::Serialize;

use super::{write_json, CliError, Io};
use crate::closed_loop::summary::METRIC_ROWS;

/// What every row of the metrics table means, and when one run's value is marked better (★).
#[derive(Debug, clap::Args)]
pub struct MetricsArgs {
    /// Print JSON instead of text
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct MetricEntry {
    label: &'static str,
    unit: &'static str,
    help: String,
}

/// Runs `cutlab metrics`.
pub fn run(args: MetricsArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    let entries: Vec<MetricEntry> = METRIC_ROWS
        .iter()
        .map(|row| MetricEntry {
            label: row.label,
            unit: row.unit,
            help: row.help_with_rule(),
        })
        .collect();
    if args.json {
        return write_json(io.stdout, &entries);
    }
    for e in &entries {
        if e.unit.is_empty() {
            writeln!(io.stdout, "{}", e.label)?;
        } else {
            writeln!(io.stdout, "{} ({})", e.label, e.unit)?;
        }
        writeln!(io.stdout, "  {}\n", e.help)?;
    }
    Ok(())
}
