//! `cutlab scenarios`: the papers' experiments, listed or run open-loop.
//!
//! Without `--run` it lists every preset with its source and key parameters. With
//! `--run NAME` it runs that preset's machine at a fixed override and prints its signals as CSV
//! (one row every `--every` samples), or with `--summary` one JSON object of peaks and means.

use serde::Serialize;

use super::args::value_or;
use super::{write_json, CliError, Io};
use crate::closed_loop::definition::DEFAULT_SEED;
use crate::input::{readable, table};
use crate::machine::{Machine, OverrideCommand};
use crate::plant::recording::OpenLoopSetting;
use crate::plant::signals::{csv_header, csv_row};
use crate::plant::{Plant, Preset};

/// List the papers' experiments (presets) with their sources, key parameters and every value
/// cutlab chose where the paper is silent; or run one open-loop.
#[derive(Debug, clap::Args)]
pub struct ScenariosArgs {
    #[arg(long = "json", help = "Print the list as JSON")]
    json: bool,
    #[arg(
        long = "run",
        help = "Run this preset open-loop and print its signals as CSV",
        value_name = "NAME",
        allow_hyphen_values = true
    )]
    run: Option<String>,
    #[arg(
        long = "seed",
        help = format!("Seed of the sensor noise (default {DEFAULT_SEED}, as every run's)"),
        value_name = "N",
        allow_hyphen_values = true
    )]
    seed: Option<String>,
    #[arg(
        long = "override",
        help = "Override held for the whole run, % (default 100)",
        value_name = "PCT",
        allow_hyphen_values = true
    )]
    r#override: Option<String>,
    #[arg(
        long = "every",
        help = "Print every N-th sample (default 100: 10 ms at 10 kHz)",
        value_name = "N",
        allow_hyphen_values = true
    )]
    every: Option<String>,
    #[arg(
        long = "max-s",
        help = "Stop after S seconds of machine time (default: the end)",
        value_name = "S",
        allow_hyphen_values = true
    )]
    max_s: Option<String>,
    #[arg(
        long = "summary",
        help = "With --run: print peaks and means as JSON instead of CSV"
    )]
    summary: bool,
}

#[derive(Serialize)]
struct RunSummary {
    preset: &'static str,
    seed: u64,
    override_pct: f64,
    samples: u64,
    duration_s: f64,
    finished: bool,
    final_path_position_mm: f64,
    peak_force_resultant_n: f64,
    mean_force_resultant_n: f64,
    peak_spindle_current_rms_a: f64,
    peak_spindle_current_rms_after_3_s_a: f64,
    peak_feed_current_rms_a: f64,
    mean_feed_mm_min: f64,
}

fn preset_named(name: &str) -> Result<Preset, CliError> {
    Preset::named(name).map_err(|e| CliError::new(format!("--run: {e}")))
}

/// Runs `cutlab scenarios`.
pub fn run(args: ScenariosArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    match args.run.as_deref() {
        Some(_) if args.json => Err(CliError::new(
            "--json lists the presets; with --run the samples are CSV (use --summary for totals)",
        )),
        Some(name) => run_preset(preset_named(name)?, &args, io),
        None => {
            let given = [
                args.seed.is_some(),
                args.r#override.is_some(),
                args.every.is_some(),
                args.max_s.is_some(),
                args.summary,
            ];
            let names = ["seed", "override", "every", "max-s", "summary"];
            if let Some((only_with_run, _)) = names.iter().zip(given).find(|(_, g)| *g) {
                return Err(CliError::new(format!(
                    "--{only_with_run} only applies with --run NAME"
                )));
            }
            list(&args, io)
        }
    }
}

fn list(args: &ScenariosArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    let summaries: Vec<_> = Preset::ALL.iter().map(|p| p.summary()).collect();
    if args.json {
        return write_json(io.stdout, &summaries);
    }
    for s in &summaries {
        writeln!(io.stdout, "{} — {} ({})", s.name, s.label, s.source)?;
        let mut facts = vec![format!("plant {}", s.plant)];
        if let Some(t) = &s.tool {
            facts.push(t.clone());
        }
        if let Some(m) = &s.material {
            facts.push(m.clone());
        }
        if let Some(mode) = s.mode {
            facts.push(mode.to_string());
        }
        if let Some(n) = s.spindle_rpm {
            facts.push(format!("{n:.0} rpm"));
        }
        if let Some(f) = s.programmed_feed_mm_min {
            facts.push(format!("{f:.0} mm/min"));
        }
        if let Some([lo, hi]) = s.depth_mm {
            let (lo, hi) = (readable(lo), readable(hi));
            facts.push(if lo == hi {
                format!("DOC {lo} mm")
            } else {
                format!("DOC {lo}-{hi} mm")
            });
        }
        facts.push(format!("≈{:.0} s", s.nominal_duration_s));
        facts.push(format!("override {}", s.override_mode));
        if let Some(f) = s.target_force_n {
            facts.push(format!("target {f:.0} N"));
        }
        if let Some(i) = s.target_spindle_current_a {
            facts.push(format!("target {i:.0} A"));
        }
        writeln!(io.stdout, "    {}", facts.join(", "))?;
        writeln!(io.stdout, "    chosen: {}", s.choices.join("; "))?;
        writeln!(io.stdout)?;
    }
    Ok(())
}

fn run_preset(preset: Preset, args: &ScenariosArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    let seed: u64 = value_or("seed", &args.seed, DEFAULT_SEED)?;
    // The Machine page's field, with the option named.
    let override_pct = table::number(
        OpenLoopSetting::Override,
        args.r#override.as_deref().unwrap_or_default(),
    )
    .map_err(|e| CliError::new(e.for_cli()))?;
    let every: u64 = value_or("every", &args.every, 100)?;
    if every == 0 {
        return Err(CliError::new("--every: must be at least 1"));
    }
    let max_s: f64 = value_or("max-s", &args.max_s, f64::INFINITY)?;
    if max_s.is_nan() || max_s <= 0.0 {
        return Err(CliError::new(format!("--max-s: must be > 0, got {max_s}")));
    }
    let summary = args.summary;
    let mut machine = preset
        .machine(seed)
        .map_err(|e| CliError::new(format!("--run {}: {e}", preset.name())))?;
    let max_samples = (max_s * machine.sample_rate_hz()).min(1e12) as u64;
    let command = OverrideCommand {
        override_pct,
        feed_hold: false,
    };
    if !summary {
        writeln!(io.stdout, "{}", csv_header())?;
    }
    let mut n = 0u64;
    let mut stats = RunSummary {
        preset: preset.name(),
        seed,
        override_pct,
        samples: 0,
        duration_s: 0.0,
        finished: false,
        final_path_position_mm: 0.0,
        peak_force_resultant_n: 0.0,
        mean_force_resultant_n: 0.0,
        peak_spindle_current_rms_a: 0.0,
        peak_spindle_current_rms_after_3_s_a: 0.0,
        peak_feed_current_rms_a: 0.0,
        mean_feed_mm_min: 0.0,
    };
    let (mut force_sum, mut feed_sum) = (0.0, 0.0);
    while n < max_samples && !machine.finished() {
        machine.step(command);
        n += 1;
        let s = machine.signals();
        if summary {
            stats.peak_force_resultant_n =
                stats.peak_force_resultant_n.max(s.truth.force_resultant_n);
            stats.peak_spindle_current_rms_a = stats
                .peak_spindle_current_rms_a
                .max(s.truth.spindle_current_rms_a);
            if s.time_s > 3.0 {
                stats.peak_spindle_current_rms_after_3_s_a = stats
                    .peak_spindle_current_rms_after_3_s_a
                    .max(s.truth.spindle_current_rms_a);
            }
            stats.peak_feed_current_rms_a = stats
                .peak_feed_current_rms_a
                .max(s.truth.feed_current_rms_a);
            force_sum += s.truth.force_resultant_n;
            feed_sum += s.feed_mm_min;
        } else if n.is_multiple_of(every) {
            writeln!(io.stdout, "{}", csv_row(s))?;
        }
    }
    if summary {
        let s = machine.signals();
        stats.samples = n;
        stats.duration_s = s.time_s;
        stats.finished = machine.finished();
        stats.final_path_position_mm = s.truth.path_position_mm;
        stats.mean_force_resultant_n = force_sum / n.max(1) as f64;
        stats.mean_feed_mm_min = feed_sum / n.max(1) as f64;
        return write_json(io.stdout, &stats);
    }
    if !n.is_multiple_of(every) {
        writeln!(io.stdout, "{}", csv_row(machine.signals()))?;
    }
    Ok(())
}
