//! `cutlab tune`: a controller's parameters swept over a grid or searched by Nelder–Mead across
//! scenarios (see [`crate::tuning`]).

use std::fmt::Write as _;

use serde::Serialize;

use super::args::required;
use super::sim::controller_with_settings;
use super::{write_json, CliError, Io};
use crate::closed_loop::definition::DEFAULT_SEED;
use crate::closed_loop::lab::RunSpec;
use crate::control::registry::ControllerKind;
use crate::plant::Preset;
use crate::tuning::nelder_mead::NelderMead;
use crate::tuning::{teach_in, Evaluation, Objective, ParamRange, TeachIn, Tuner, TuningProblem};

/// The long help of `cutlab tune`.
pub const ABOUT: &str = "Tune a controller's parameters over one or more scenarios.

With --sweep N every combination of N values per parameter runs on every scenario (a grid of at \
most 400 points); without it, Nelder-Mead searches the parameters' box for the lowest objective \
(at most --max-evals evaluations). The objective per scenario is

  J = cycle·T/T0 + error·(mean |force error| / 10 %) + above·(seconds above the force limit)
      + activity·(override total variation / 100 %)

averaged over the scenarios; T0 is the program's duration at 100 % override. Each scenario's \
teach cut runs once; natively the scenarios run on all cores.

Example: cutlab tune --controller pi --scenarios maneerat-doc-1,maneerat-doc-2 \
--param kp=0.05:1.5 --param ki_per_s=0.1:5";

/// Tune a controller's parameters (grid sweep or Nelder–Mead) across scenarios
#[derive(Debug, clap::Args)]
pub struct TuneArgs {
    /// The controller to tune, with fixed parameters as NAME:key=value:…
    #[arg(long, value_name = "NAME")]
    controller: Option<String>,
    /// The presets to tune on, comma separated
    #[arg(long, value_name = "A,B,...")]
    scenarios: Option<String>,
    /// A parameter to tune and its bounds (repeat for more)
    #[arg(long = "param", value_name = "KEY=LO:HI")]
    params: Vec<String>,
    /// Weights of the objective's terms: cycle, error, above, activity (default 1,1,1,0.1)
    #[arg(long, value_name = "TERM=W,...")]
    objective: Option<String>,
    /// Run a grid of N values per parameter instead of searching
    #[arg(long, value_name = "N")]
    sweep: Option<usize>,
    /// Largest number of evaluations of the search (default 60)
    #[arg(long, value_name = "N")]
    max_evals: Option<usize>,
    /// Seed of every run (default 1)
    #[arg(long, value_name = "N")]
    seed: Option<u64>,
    /// Only run each scenario's teach cut and propose a target, reference current and threshold gap
    #[arg(long)]
    teach_in: bool,
    /// Print JSON instead of a table
    #[arg(long)]
    json: bool,
}

#[derive(Serialize)]
struct SweepReport<'a> {
    controller: &'a str,
    params: &'a [ParamRange],
    scenarios: Vec<&'static str>,
    objective: Objective,
    points: &'a [Evaluation],
}

#[derive(Serialize)]
struct TuneReport<'a> {
    controller: &'a str,
    params: &'a [ParamRange],
    scenarios: Vec<&'static str>,
    objective: Objective,
    converged: bool,
    best: &'a Evaluation,
    pareto: Vec<&'a Evaluation>,
    evaluations: usize,
}

/// Runs `cutlab tune`.
pub fn run(args: TuneArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    let scenario_text: String = required("scenarios", &args.scenarios)?;
    let presets = scenario_text
        .split(',')
        .map(|name| {
            Preset::from_name(name).ok_or_else(|| {
                CliError::new(format!(
                    "--scenarios: unknown preset {:?}; presets: {}",
                    name.trim(),
                    Preset::names()
                ))
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let first = presets
        .first()
        .copied()
        .ok_or_else(|| CliError::new("--scenarios: name at least one preset"))?;
    let seed = args.seed.unwrap_or(DEFAULT_SEED);
    if args.teach_in {
        return run_teach_in(&presets, seed, args.json, io);
    }
    let controller_text: String = required("controller", &args.controller)?;
    let controller = controller_with_settings(&controller_text, first)
        .map_err(|e| CliError::new(format!("--controller: {e}")))?;
    let params = args
        .params
        .iter()
        .map(|p| ParamRange::parse(p).map_err(|e| CliError::new(format!("--param: {e}"))))
        .collect::<Result<Vec<_>, _>>()?;
    let objective = match &args.objective {
        Some(text) => {
            Objective::parse(text).map_err(|e| CliError::new(format!("--objective: {e}")))?
        }
        None => Objective::default(),
    };
    let scenarios: Vec<RunSpec> = presets
        .iter()
        .map(|&p| {
            let mut spec = RunSpec::new(p, controller.kind());
            spec.seed = seed;
            spec
        })
        .collect();
    let names: Vec<&'static str> = presets.iter().map(|p| p.name()).collect();
    let tuner = Tuner::new(TuningProblem {
        controller: controller.clone(),
        params: params.clone(),
        scenarios,
        objective,
    })
    .map_err(|e| CliError::new(e.to_string()))?;
    let kind = controller.kind().name();

    if let Some(steps) = args.sweep {
        if steps == 0 {
            return Err(CliError::new(
                "--sweep: give at least 1 value per parameter",
            ));
        }
        let points = tuner
            .sweep(steps)
            .map_err(|e| CliError::new(e.to_string()))?;
        if args.json {
            return write_json(
                io.stdout,
                &SweepReport {
                    controller: kind,
                    params: &params,
                    scenarios: names,
                    objective,
                    points: &points,
                },
            );
        }
        let best = points
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.cost.total_cmp(&b.1.cost))
            .map(|(i, _)| i);
        io.stdout.write_all(
            format!(
                "{kind} on {}, seed {seed}: {} points\n",
                names.join(", "),
                points.len()
            )
            .as_bytes(),
        )?;
        io.stdout
            .write_all(evaluation_table(&params, points.iter().enumerate(), best).as_bytes())?;
        return Ok(());
    }

    let search = NelderMead {
        max_evaluations: args
            .max_evals
            .unwrap_or(NelderMead::default().max_evaluations),
        ..NelderMead::default()
    };
    if search.max_evaluations == 0 {
        return Err(CliError::new("--max-evals: give at least 1"));
    }
    let tuned = tuner
        .tune(&search)
        .map_err(|e| CliError::new(e.to_string()))?;
    if args.json {
        return write_json(
            io.stdout,
            &TuneReport {
                controller: kind,
                params: &params,
                scenarios: names,
                objective,
                converged: tuned.converged,
                best: &tuned.best,
                pareto: tuned
                    .pareto
                    .iter()
                    .map(|&i| &tuned.evaluations[i])
                    .collect(),
                evaluations: tuned.evaluations.len(),
            },
        );
    }
    let mut out = format!(
        "{kind} on {}, seed {seed}: {} evaluations, {}\nbest:",
        names.join(", "),
        tuned.evaluations.len(),
        if tuned.converged {
            "converged"
        } else {
            "stopped at the evaluation budget"
        }
    );
    for (range, value) in params.iter().zip(&tuned.best.values) {
        let _ = write!(out, " {}={}", range.key, crate::input::readable(*value));
    }
    let _ = writeln!(
        out,
        " (objective {:.3}, cycle {:.1} s, force error {:.1} %)",
        tuned.best.cost, tuned.best.cycle_time_s, tuned.best.force_error_pct
    );
    out.push_str("Pareto front of cycle time against force error:\n");
    out.push_str(&evaluation_table(
        &params,
        tuned.pareto.iter().map(|&i| (i, &tuned.evaluations[i])),
        None,
    ));
    io.stdout.write_all(out.as_bytes())?;
    Ok(())
}

/// `cutlab tune --teach-in`: each scenario's teach cut and what it proposes.
fn run_teach_in(
    presets: &[Preset],
    seed: u64,
    json: bool,
    io: &mut Io<'_>,
) -> Result<(), CliError> {
    let taught = presets
        .iter()
        .map(|&p| {
            let mut spec = RunSpec::new(p, ControllerKind::Threshold);
            spec.seed = seed;
            teach_in(&spec).map_err(|e| CliError::new(e.to_string()))
        })
        .collect::<Result<Vec<TeachIn>, _>>()?;
    if json {
        return write_json(io.stdout, &taught);
    }
    let mut out = String::new();
    for t in &taught {
        let reference = if t.reference_current_a.is_finite() {
            format!("reference current {:.3} A", t.reference_current_a)
        } else {
            "a dynamometer measures it: no current".to_string()
        };
        let _ = writeln!(
            out,
            "{}: {} periods taught; force at 100 % override {:.0} N; target {:.0} N \
             ({reference}); estimate noise {:.1} N (1 σ); threshold gap {:.1} % \
             (threshold:gap_pct={:.1})",
            t.preset,
            t.calibration.periods,
            t.force_at_full_override_n,
            t.proposed_target_n,
            t.estimate_noise_n,
            t.proposed_gap_pct,
            t.proposed_gap_pct
        );
    }
    io.stdout.write_all(out.as_bytes())?;
    Ok(())
}

/// One row per evaluation: its parameters, objective, cycle time, force error and time above the
/// limit (summed over the scenarios); `best` is marked with `*`.
fn evaluation_table<'a>(
    params: &[ParamRange],
    rows: impl Iterator<Item = (usize, &'a Evaluation)>,
    best: Option<usize>,
) -> String {
    let mut out = String::new();
    let widths: Vec<usize> = params.iter().map(|p| p.key.len().max(12) + 2).collect();
    for (p, width) in params.iter().zip(&widths) {
        let _ = write!(out, "{:>width$}", p.key);
    }
    let _ = writeln!(
        out,
        "{:>11}{:>11}{:>12}{:>12}",
        "objective", "cycle (s)", "error (%)", "above (s)"
    );
    for (i, e) in rows {
        for (v, width) in e.values.iter().zip(&widths) {
            let _ = write!(out, "{:>width$}", crate::input::readable(*v));
        }
        let above: f64 = e.metrics.iter().map(|m| m.time_above_limit_s).sum();
        let mark = if best == Some(i) { "*" } else { " " };
        let _ = writeln!(
            out,
            "{:>10.3}{mark}{:>11.1}{:>12.1}{:>12.1}",
            e.cost, e.cycle_time_s, e.force_error_pct, above
        );
    }
    out
}
