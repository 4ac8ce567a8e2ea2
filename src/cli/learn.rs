//! `cutlab learn`: paper 004's network learned from trial cuts made on a preset's simulated
//! machine — its exponents with their uncertainty beside the published ones and the mechanistic
//! model's, and each cut's residual — from the force on the tool and from the lab's
//! current-based estimate ([`crate::closed_loop::trial_cuts`],
//! [`crate::estimation::power_law_fit`]).

use std::fmt::Write as _;

use serde::Serialize;

use super::args::{reject_extra, required, value};
use super::calibrate::{problem_note, problem_notes, read_log};
use super::{write_json, CliError, Io};
use crate::closed_loop::trial_cuts::{
    learn_on_preset, preset_networks, LearningError, PresetLearning, DEFAULT_TRIAL_FEEDS_PCT,
};
use crate::estimation::power_law_fit::{LearnError, LearnedPowerLaw};
use crate::input::{parse_number, readable};
use crate::log::trial_cuts::{
    learn_from_table, learning_table, TableLearning, TableTool, TrialCutTable,
};
use crate::plant::materials::Material;
use crate::plant::Preset;

pub(crate) const ABOUT: &str =
    "Paper 004's network learned from trial cuts on a preset's simulated machine: its\n\
program cut at a fixed feed, once per feed, each section of constant depth a trial cut.\n\
The log-space weights are fitted by least squares (what a linear network trained to\n\
convergence reaches), each ± two standard errors, once on the force on the tool and once\n\
on the lab's current-based estimate, beside paper 004's published weights and the\n\
mechanistic model's local exponents over the same cuts; then each cut's residual.\n\n\
With --cuts FILE the network is learned from your own machine's trial cuts: a CSV table,\n\
one row per cut, with columns a_e [mm], f_z [mm], a_p [mm], force [N] (the force your\n\
current-based monitor gave for the cut) and the tool's d [mm] and z (or --diameter-mm and\n\
--teeth). --write-cuts FILE writes a preset's trial cuts as such a table.";

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
        long = "cuts",
        help = "learn from your own trial cuts: a CSV table, one row per cut (a_e [mm], f_z [mm], \
                a_p [mm], force [N], and d [mm], z or --diameter-mm, --teeth)",
        value_name = "FILE"
    )]
    cuts: Option<String>,
    #[arg(
        long = "force-column",
        help = "with --cuts: the column of the force to learn from (default: the one named force)",
        value_name = "NAME"
    )]
    force_column: Option<String>,
    #[arg(
        long = "diameter-mm",
        help = "with --cuts: the tool's diameter, mm, for a table without a d column",
        value_name = "MM"
    )]
    diameter_mm: Option<String>,
    #[arg(
        long = "teeth",
        help = "with --cuts: the cutter's teeth, for a table without a z column",
        value_name = "Z"
    )]
    teeth: Option<String>,
    #[arg(
        long = "material",
        help = "with --cuts: the workpiece material whose published weights the learned ones are \
                compared with (see cutlab scenarios; default sm45c, carbon steel)",
        value_name = "NAME"
    )]
    material: Option<String>,
    #[arg(
        long = "write-cuts",
        help = "with --scenario: also write its trial cuts as a table --cuts reads (force: the \
                lab's current-based estimate; dynamometer force: the force on the tool)",
        value_name = "FILE"
    )]
    write_cuts: Option<String>,
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
    if let Some(file) = &args.cuts {
        if args.scenario.is_some() || args.feeds_pct.is_some() || args.write_cuts.is_some() {
            return Err(CliError::new(
                "--cuts learns from a table of your own cuts: leave out --scenario, --feeds-pct \
                 and --write-cuts",
            ));
        }
        return run_on_table(file, &args, io);
    }
    for (given, name) in [
        (args.force_column.is_some(), "--force-column"),
        (args.diameter_mm.is_some(), "--diameter-mm"),
        (args.teeth.is_some(), "--teeth"),
        (args.material.is_some(), "--material"),
    ] {
        if given {
            return Err(CliError::new(format!(
                "{name} goes with --cuts (a preset's own cuts know their tool and material)"
            )));
        }
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
    if let Some(path) = &args.write_cuts {
        let table = learning_table(&learning).ok_or_else(|| {
            CliError::new(format!("--write-cuts: {} has no cutter", preset.name()))
        })?;
        std::fs::write(path, table)
            .map_err(|e| CliError::new(format!("--write-cuts: cannot write {path:?}: {e}")))?;
    }
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

/// What `--cuts --json` prints.
#[derive(Serialize)]
struct TableReport<'a> {
    file: &'a str,
    /// The quantities and the columns they were read from (null: given for the whole table).
    columns: Vec<(&'static str, Option<&'a str>)>,
    /// Each cut's line in the file, in the order of the residuals.
    lines: &'a [u32],
    left_out: &'a [crate::log::LineProblem],
    material: &'static str,
    learned: &'a LearnedPowerLaw,
}

/// `cutlab learn --cuts FILE`: the network learned from a table of the user's own cuts.
fn run_on_table(file: &str, args: &LearnArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    let tool = TableTool {
        diameter_mm: value::<f64>("diameter-mm", &args.diameter_mm)?,
        teeth: value::<u32>("teeth", &args.teeth)?,
    };
    let material = match &args.material {
        Some(name) => Material::from_name(name).ok_or_else(|| {
            CliError::new(format!(
                "--material: no material {name:?}; choose one of {}",
                Material::ALL.map(|m| m.name()).join(", ")
            ))
        })?,
        None => Material::Sm45c,
    };
    let log = read_log(file)?;
    let learning = learn_from_table(&log, args.force_column.as_deref(), tool, material)
        .map_err(|e| CliError::new(format!("{file}: {e}")))?;
    let TableLearning {
        table:
            TrialCutTable {
                cuts,
                lines,
                columns,
                left_out,
            },
        material: weights,
        learned,
    } = &learning;
    if args.json {
        return write_json(
            io.stdout,
            &TableReport {
                file,
                columns: columns
                    .iter()
                    .map(|(q, c)| (q.header(), c.as_deref()))
                    .collect(),
                lines,
                left_out,
                material: weights.name(),
                learned,
            },
        );
    }
    let mut out = problem_notes(&log);
    for p in left_out {
        out.push_str(&problem_note(p));
    }
    let force = learning.force_column();
    let _ = writeln!(
        out,
        "Paper 004's network learned from {file}: {} trial cuts{}, the force from {force:?}, \
         published weights: {}",
        cuts.len(),
        if left_out.is_empty() {
            String::new()
        } else {
            format!(" ({} rows left out, above)", left_out.len())
        },
        weights.label()
    );
    let _ = writeln!(
        out,
        "\n{:<6} {:>16} {:>10}",
        "input", "learned", "published"
    );
    for e in &learned.learned {
        let _ = writeln!(
            out,
            "{:<6} {:>16} {:>10.2}",
            e.input.symbol(),
            e.with_uncertainty(),
            e.published
        );
    }
    for (input, exponent) in &learned.held {
        let _ = writeln!(
            out,
            "{:<6} held at the published {exponent:.2} (it does not vary over the cuts)",
            input.symbol()
        );
    }
    let _ = writeln!(out, "bias   {:.1} N", learned.bias_n);
    let _ = writeln!(
        out,
        "\n{:>6} {:>8} {:>9} {:>8} {:>10} {:>11}",
        "line", "a_e mm", "f mm", "a_p mm", "force N", "residual %"
    );
    for ((cut, line), residual) in cuts.iter().zip(lines.iter()).zip(&learned.residuals_pct) {
        let _ = writeln!(
            out,
            "{:>6} {:>8.2} {:>9.4} {:>8.2} {:>10.1} {:>11.2}",
            line,
            cut.inputs.radial_width_mm,
            cut.inputs.feed_per_tooth_mm,
            cut.inputs.axial_depth_mm,
            cut.force_n,
            residual
        );
    }
    let _ = writeln!(
        out,
        "residual RMS (log scale): {:.2} %",
        100.0 * learned.residual_rms_log
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
