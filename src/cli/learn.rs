//! `cutlab learn`: paper 004's network learned from trial cuts made on a preset's simulated
//! machine — its exponents with their uncertainty beside the published ones and the mechanistic
//! model's, and each cut's residual — from the force on the tool and from the lab's
//! current-based estimate ([`crate::closed_loop::trial_cuts`],
//! [`crate::estimation::power_law_fit`]).

use std::fmt::Write as _;

use serde::Serialize;

use super::args::{reject_extra, required};
use super::{write_json, CliError, Io};
use crate::closed_loop::trial_cuts::{
    learn_on_preset, preset_networks, LearningError, PresetLearning, DEFAULT_TRIAL_FEEDS_PCT,
};
use crate::estimation::power_law_fit::LearnError;
use crate::input::{parse_number, readable};
use crate::plant::Preset;

pub(crate) const ABOUT: &str =
    "Paper 004's network learned from trial cuts on a preset's simulated machine: its\n\
program cut at a fixed feed, once per feed, each section of constant depth a trial cut.\n\
The log-space weights are fitted by least squares (what a linear network trained to\n\
convergence reaches), each ± two standard errors, once on the force on the tool and once\n\
on the lab's current-based estimate, beside paper 004's published weights and the\n\
mechanistic model's local exponents over the same cuts; then each cut's residual.";

#[derive(Debug, clap::Args)]
pub struct LearnArgs {
    #[arg(
        long = "scenario",
        help = "mill preset whose program makes the trial cuts (see cutlab scenarios)",
        value_name = "NAME"
    )]
    scenario: Option<String>,
    #[arg(
        long = "feeds-pct",
        help = "fixed feeds to cut the program at, percent of its programmed feed, comma \
                separated (default 60,80,100)",
        value_name = "P,P,…",
        allow_hyphen_values = true
    )]
    feeds_pct: Option<String>,
    #[arg(long = "json", help = "print the cuts and both fits as JSON")]
    json: bool,
    #[arg(
        long = "shipped-networks",
        help = "learn every mill preset's network from its default trial cuts and print the \
                networks the lab ships for its sensorless estimate (www/data/sensorless-networks.json)"
    )]
    shipped_networks: bool,
    /// Stray words: refused.
    #[arg(hide = true)]
    extra: Vec<String>,
}

/// Feeds a learning can ask for, percent of the programmed feed: below a tenth the chip is
/// rubbing, above the machine's override range nothing is cut.
const FEED_RANGE_PCT: (f64, f64) = (10.0, 255.0);

/// What `--json` prints.
#[derive(Serialize)]
struct LearnReport<'a> {
    feeds_pct: &'a [f64],
    #[serde(flatten)]
    learning: &'a PresetLearning,
}

/// Runs `cutlab learn`.
pub fn run(args: LearnArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    reject_extra(&args.extra, "")?;
    if args.shipped_networks {
        if args.scenario.is_some() || args.feeds_pct.is_some() {
            return Err(CliError::new(
                "--shipped-networks learns every mill preset at the default feeds: leave out \
                 --scenario and --feeds-pct",
            ));
        }
        let networks = preset_networks().map_err(|e| CliError::new(e.to_string()))?;
        return write_json(io.stdout, &networks);
    }
    let name: String = required("scenario", &args.scenario)?;
    let preset = Preset::named(&name).map_err(|e| CliError::new(format!("--scenario: {e}")))?;
    let feeds_pct = match &args.feeds_pct {
        Some(text) => feeds(text)?,
        None => DEFAULT_TRIAL_FEEDS_PCT.to_vec(),
    };
    let learning = learn_on_preset(preset, &feeds_pct).map_err(|e| match e {
        LearningError::Learn {
            error: LearnError::TooFewCuts { .. },
            ..
        } => CliError::new(format!(
            "{e} (each feed of --feeds-pct cuts every depth of the program once: give more feeds)"
        )),
        _ => CliError::new(e.to_string()),
    })?;
    let PresetLearning {
        preset: _,
        cuts,
        material,
        from_force,
        from_estimate,
        mechanistic: _,
    } = &learning;
    let material = *material;
    if args.json {
        return write_json(
            io.stdout,
            &LearnReport {
                feeds_pct: &feeds_pct,
                learning: &learning,
            },
        );
    }
    let mut out = String::new();
    let _ = writeln!(
        out,
        "Paper 004's network learned on {}: {} trial cuts (each section of constant depth, at {} % \
         of the programmed feed), published weights: {}",
        preset.name(),
        cuts.len(),
        feeds_pct
            .iter()
            .map(|p| readable(*p))
            .collect::<Vec<_>>()
            .join(", "),
        material.label()
    );
    let _ = writeln!(
        out,
        "\n{:<6} {:>16} {:>18} {:>10} {:>14}",
        "input", "from the force", "from the estimate", "published", "mechanistic"
    );
    for (learned_force, learned_estimate) in from_force.learned.iter().zip(&from_estimate.learned) {
        let input = learned_force.input;
        let local = learning.mechanistic_text(input);
        let _ = writeln!(
            out,
            "{:<6} {:>16} {:>18} {:>10.2} {:>14}",
            input.symbol(),
            learned_force.with_uncertainty(),
            learned_estimate.with_uncertainty(),
            learned_force.published,
            local.unwrap_or_default()
        );
    }
    for (input, exponent) in &from_force.held {
        let _ = writeln!(
            out,
            "{:<6} held at the published {exponent:.2} (it does not vary over the cuts)",
            input.symbol()
        );
    }
    let _ = writeln!(
        out,
        "bias   {:.1} N from the force, {:.1} N from the estimate ({:+.1} %)",
        from_force.bias_n,
        from_estimate.bias_n,
        100.0 * (from_estimate.bias_n / from_force.bias_n - 1.0)
    );
    let _ = writeln!(
        out,
        "\n{:>4} {:>8} {:>9} {:>8} {:>10} {:>10} {:>11} {:>11}",
        "cut", "a_e mm", "f mm", "a_p mm", "force N", "estimate N", "residual %", "est. res. %"
    );
    for (k, cut) in cuts.iter().enumerate() {
        let _ = writeln!(
            out,
            "{:>4} {:>8.2} {:>9.4} {:>8.2} {:>10.1} {:>10.1} {:>11.2} {:>11.2}",
            k + 1,
            cut.radial_width_mm,
            cut.feed_per_tooth_mm,
            cut.axial_depth_mm,
            cut.force_n,
            cut.estimate_n,
            from_force.residuals_pct.get(k).copied().unwrap_or(f64::NAN),
            from_estimate
                .residuals_pct
                .get(k)
                .copied()
                .unwrap_or(f64::NAN),
        );
    }
    let _ = writeln!(
        out,
        "residual RMS (log scale): {:.2} % from the force, {:.2} % from the estimate",
        100.0 * from_force.residual_rms_log,
        100.0 * from_estimate.residual_rms_log
    );
    io.stdout.write_all(out.as_bytes())?;
    Ok(())
}

/// The feeds of `--feeds-pct`: numbers, comma separated, each inside [`FEED_RANGE_PCT`].
fn feeds(text: &str) -> Result<Vec<f64>, CliError> {
    let (lo, hi) = FEED_RANGE_PCT;
    let feeds = text
        .split(',')
        .map(|part| {
            let v = parse_number(part.trim())
                .map_err(|e| CliError::new(format!("--feeds-pct: {e}")))?;
            if (lo..=hi).contains(&v) {
                Ok(v)
            } else {
                Err(CliError::new(format!(
                    "--feeds-pct: {} % is outside {}",
                    readable(v),
                    crate::input::table::range_text(lo, hi, "%")
                )))
            }
        })
        .collect::<Result<Vec<f64>, CliError>>()?;
    if feeds.is_empty() {
        return Err(CliError::new("--feeds-pct: give at least one feed"));
    }
    Ok(feeds)
}
