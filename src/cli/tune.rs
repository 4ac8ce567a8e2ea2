//! `cutlab tune`: a controller's parameters swept over a grid or searched by Nelder–Mead across
//! scenarios, or a teach-in's proposal from a simulated, logged or saved teach cut (see
//! [`crate::tuning`]). Results go to stdout; progress goes to stderr, one line per teach cut and
//! per evaluation, so `--json` output stays clean.

use std::fmt::Write as _;
use std::io::Write as _;

use serde::Serialize;

use super::args::required;
use super::calibrate::{problem_notes, read_log, LogCalibrationArgs};
use super::sim::{check_engine_used, controller_with_settings, EngineFile, FUZZY_ENGINE_HELP};
use super::table_args::{OptionRows, TableArgs};
use super::{write_json, CliError, Io};
use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::definition::DEFAULT_SEED;
use crate::control::registry::ControllerKind;
use crate::estimation::estimator::Feedback;
use crate::input::table::{self, RowError};
use crate::plant::Preset;
use crate::tuning::nelder_mead::NelderMead;
use crate::tuning::settings::{objective_from_terms, TuneSetting};
use crate::tuning::teach_in::{
    teach_in_calibration, teach_in_log, teach_in_scenarios, LogTeachIn, TeachIn,
};
use crate::tuning::{
    default_threads, Evaluation, Objective, ParamRange, Report, Tuner, TuningProblem,
};

/// The long help of `cutlab tune`.
pub const ABOUT: &str = "Tune a controller's parameters over one or more scenarios, or propose \
settings from a teach cut.

With --sweep N every combination of N values per parameter runs on every scenario (a grid of at \
most 400 points); without it, Nelder-Mead searches the parameters' box for the lowest objective \
(at most --max-evals evaluations). The objective per scenario is

  J = cycle·T/T0 + error·(mean |force error| / 10 %) + above·(seconds above the force limit)
      + activity·(override total variation / 100 %)

averaged over the scenarios; T0 is the program's duration at 100 % override. Each scenario's \
teach cut runs once and keeps its preset's own controller values for the parameters not tuned; \
natively every run of a sweep, and the scenarios of each search evaluation, share all cores; a \
core a search leaves idle runs ahead (points it may ask next), which changes none of its results.

--teach-in proposes a force target (80 % of the force the teach cut measured at 100 % override, \
kept inside the calibrated currents), its reference current and a threshold gap (±3 σ of the \
estimate's noise, at least 5 %), beside the preset's own target. The teach cut is each \
scenario's on the simulated machine, a logged one (--log FILE, read as cutlab calibrate reads \
it, with --map and --material), or a saved calibration (--calibration FILE, as cutlab host \
--save-calibration writes it after a teach cut on the machine; --scenarios names its program).

Progress goes to stderr (--quiet silences it); results to stdout.

Examples:
  cutlab tune --controller pi --scenarios maneerat-doc-1,maneerat-doc-2 \\
    --param kp=0.05:1.5 --param ki_per_s=0.1:5
  cutlab tune --teach-in --scenarios kim-step-doc,maneerat-doc-2
  cutlab tune --teach-in --log export.csv --map spindle_current_rms_a='S_Strom [A]' ...
  cutlab tune --teach-in --calibration machine.json --scenarios kim-step-doc";

/// Tune a controller's parameters (grid sweep or Nelder–Mead) across scenarios
#[derive(Debug, clap::Args)]
pub struct TuneArgs {
    /// The controller to tune, with fixed parameters as NAME:key=value:…
    #[arg(long, value_name = "NAME")]
    controller: Option<String>,
    #[arg(long = "fuzzy-engine", value_name = "FILE", help = FUZZY_ENGINE_HELP)]
    fuzzy_engine: Option<String>,
    /// The presets to tune on (or to teach in), comma separated
    #[arg(long, value_name = "A,B,...")]
    scenarios: Option<String>,
    /// A parameter to tune and its bounds (repeat for more; each parameter once)
    #[arg(long = "param", value_name = "KEY=LO:HI")]
    params: Vec<String>,
    /// Weights of the objective's terms: cycle, error, above, activity (default 1,1,1,0.1)
    #[arg(long, value_name = "TERM=W,...")]
    objective: Option<String>,
    /// --sweep and --max-evals: rows of the tuning's table, as the Tune page's fields
    #[command(flatten)]
    method: TableArgs<MethodRows>,
    /// Seed of every run (default 1)
    #[arg(long, value_name = "N")]
    seed: Option<u64>,
    /// Propose a target, reference current and threshold gap from a teach cut instead of tuning
    #[arg(long)]
    teach_in: bool,
    /// With --teach-in: the CSV log of a teach cut (any delimiter, decimal comma, …)
    #[arg(long, value_name = "FILE", conflicts_with = "calibration")]
    log: Option<String>,
    /// With --teach-in: a saved calibration (cutlab host/sim --save-calibration)
    #[arg(long, value_name = "FILE")]
    calibration: Option<String>,
    /// Print no progress on stderr
    #[arg(long)]
    quiet: bool,
    /// Print JSON instead of a table
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    log_options: LogCalibrationArgs,
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

/// The rows of the tuning's table that are options of their own: `--sweep` and `--max-evals`.
#[derive(Debug, Clone, Default)]
pub struct MethodRows;

impl OptionRows for MethodRows {
    type Setting = TuneSetting;
    const ROWS: &'static [TuneSetting] = &[TuneSetting::Steps, TuneSetting::Evaluations];
}

/// Progress lines on stderr (nothing with --quiet).
struct ProgressLines {
    quiet: bool,
    params: Vec<String>,
}

impl ProgressLines {
    fn line(&self, text: &str) {
        if !self.quiet {
            // Progress is a courtesy: a closed stderr must not stop the work.
            let _ = writeln!(std::io::stderr(), "tune: {text}");
        }
    }

    fn report(&self, report: &Report<'_>) {
        if self.quiet {
            return;
        }
        match report {
            Report::Taught {
                preset,
                done,
                total,
            } => self.line(&format!("teach cut {done} of {total} done ({preset})")),
            Report::Evaluated {
                done,
                total,
                at_most,
                evaluation,
            } => {
                let mut values = String::new();
                for (key, value) in self.params.iter().zip(&evaluation.values) {
                    let _ = write!(values, " {key}={}", crate::input::readable(*value));
                }
                let what = if *at_most {
                    format!("evaluation {done} of at most {total}")
                } else {
                    format!(
                        "point {done} of {total} ({:.0} %)",
                        100.0 * *done as f64 / (*total).max(1) as f64
                    )
                };
                self.line(&format!(
                    "{what}:{values} → objective {:.3}",
                    evaluation.cost
                ));
            }
        }
    }
}

/// The presets of `--scenarios`, if given.
fn presets(args: &TuneArgs) -> Result<Option<Vec<Preset>>, CliError> {
    let Some(text) = &args.scenarios else {
        return Ok(None);
    };
    let presets = text
        .split(',')
        .map(|name| {
            Preset::named(name.trim()).map_err(|e| CliError::new(format!("--scenarios: {e}")))
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Some(presets))
}

/// Runs `cutlab tune`.
pub fn run(args: TuneArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    let presets = presets(&args)?;
    let seed = args.seed.unwrap_or(DEFAULT_SEED);
    if args.teach_in {
        return run_teach_in(&args, presets, seed, io);
    }
    let only_teach_in = [
        ("--log", args.log.is_some()),
        ("--calibration", args.calibration.is_some()),
    ]
    .into_iter()
    .filter_map(|(name, given)| given.then_some(name))
    .chain(args.log_options.given());
    if let Some(name) = only_teach_in.into_iter().next() {
        return Err(CliError::new(format!(
            "{name} only applies with --teach-in (a teach-in from a log or a saved calibration)"
        )));
    }
    let Some(presets) = presets else {
        return Err(CliError::new("missing required option --scenarios"));
    };
    let controller_text: String = required("controller", &args.controller)?;
    let engine = EngineFile::read(args.fuzzy_engine.as_deref())?;
    // Each scenario runs its own preset's paper values with the caller's settings on top.
    let controllers = presets
        .iter()
        .map(|&p| {
            controller_with_settings(&controller_text, p, engine.as_ref())
                .map_err(|e| CliError::new(format!("--controller: {e}")))
        })
        .collect::<Result<Vec<_>, _>>()?;
    check_engine_used(&engine, controllers.iter())?;
    let controller = controllers[0].clone();
    let params = args
        .params
        .iter()
        .map(|p| ParamRange::parse(p).map_err(|e| CliError::new(format!("--param: {e}"))))
        .collect::<Result<Vec<_>, _>>()?;
    for (i, range) in params.iter().enumerate() {
        if let Some(earlier) = params[..i].iter().find(|r| r.key == range.key) {
            return Err(CliError::new(format!(
                "--param: {} is given twice ({}:{} and {}:{}); give each parameter once",
                range.key, earlier.lo, earlier.hi, range.lo, range.hi
            )));
        }
    }
    let objective = match &args.objective {
        Some(text) => {
            objective_from_terms(text).map_err(|e| CliError::new(format!("--objective: {e}")))?
        }
        None => Objective::default(),
    };
    let sweep_text = args.method.given(TuneSetting::Steps);
    let evals_text = args.method.given(TuneSetting::Evaluations);
    if sweep_text.is_some() && evals_text.is_some() {
        return Err(CliError::new(
            "--max-evals applies to the search; a sweep (--sweep) runs every grid point",
        ));
    }
    let for_cli = |e: RowError<TuneSetting>| CliError::new(e.for_cli());
    let sweep = sweep_text
        .map(|text| table::count(TuneSetting::Steps, text))
        .transpose()
        .map_err(for_cli)?;
    let search = NelderMead {
        max_evaluations: table::count(TuneSetting::Evaluations, evals_text.unwrap_or_default())
            .map_err(for_cli)?,
        ..NelderMead::default()
    };
    let scenarios: Vec<RunSpec> = presets
        .iter()
        .zip(controllers)
        .map(|(&p, controller)| {
            let mut spec = RunSpec::new(p, controller.kind());
            spec.controller = controller;
            spec.seed = seed;
            spec
        })
        .collect();
    let names: Vec<&'static str> = presets.iter().map(|p| p.name()).collect();
    let progress = ProgressLines {
        quiet: args.quiet,
        params: params.iter().map(|p| p.key.clone()).collect(),
    };
    let tuner = Tuner::with_threads(
        TuningProblem {
            controller: controller.clone(),
            params: params.clone(),
            scenarios,
            objective,
        },
        default_threads(),
        &mut |r| progress.report(r),
    )
    .map_err(|e| CliError::new(e.to_string()))?;
    let kind = controller.kind().name();

    if let Some(steps) = sweep {
        let points = tuner
            .sweep_reporting(steps, &mut |r| progress.report(r))
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

    let tuned = tuner
        .tune_reporting(&search, &mut |r| progress.report(r))
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

/// `cutlab tune --teach-in`: a proposal from each scenario's simulated teach cut, a logged teach
/// cut or a saved calibration.
fn run_teach_in(
    args: &TuneArgs,
    presets: Option<Vec<Preset>>,
    seed: u64,
    io: &mut Io<'_>,
) -> Result<(), CliError> {
    let tuning_options = [
        ("--controller", args.controller.is_some()),
        ("--param", !args.params.is_empty()),
        ("--sweep", args.method.given(TuneSetting::Steps).is_some()),
        ("--objective", args.objective.is_some()),
        (
            "--max-evals",
            args.method.given(TuneSetting::Evaluations).is_some(),
        ),
    ];
    if let Some((name, _)) = tuning_options.iter().find(|(_, given)| *given) {
        return Err(CliError::new(format!(
            "{name} does not apply to --teach-in, which tunes nothing: it proposes a target, \
             reference current and threshold gap from a teach cut"
        )));
    }
    if args.log.is_none() {
        if let Some(name) = args.log_options.given().first() {
            return Err(CliError::new(format!(
                "{name} only applies to a teach-in from a log (--log FILE)"
            )));
        }
    }
    let spec_of = |preset: Preset| {
        let mut spec = RunSpec::new(preset, ControllerKind::Threshold);
        spec.seed = seed;
        spec
    };
    let progress = ProgressLines {
        quiet: args.quiet,
        params: Vec::new(),
    };
    if let Some(file) = &args.log {
        if presets.is_some() {
            return Err(CliError::new(
                "--scenarios does not apply to a teach-in from a log: the log is the program",
            ));
        }
        let log = read_log(file)?;
        let map = args.log_options.map()?;
        let geometry = args.log_options.geometry()?;
        let logged = teach_in_log(
            &log,
            file,
            LogTeachIn {
                map: &map,
                geometry: geometry.as_ref().map(|(g, d)| (g, d.as_str())),
                gear_change_rpm: args.log_options.gear_change_rpm()?,
            },
        )
        .map_err(|e| CliError::new(e.to_string()))?;
        if args.json {
            #[derive(Serialize)]
            struct LogReport<'a> {
                #[serde(flatten)]
                logged: &'a crate::tuning::teach_in::LoggedTeachIn,
                log_problems: &'a [crate::log::LineProblem],
            }
            return write_json(
                io.stdout,
                &LogReport {
                    logged: &logged,
                    log_problems: &log.problems,
                },
            );
        }
        let mut out = problem_notes(&log);
        for note in &logged.notes {
            let _ = writeln!(out, "note: {note}");
        }
        out.push_str(&describe(&logged.teach_in));
        io.stdout.write_all(out.as_bytes())?;
        return Ok(());
    }
    let taught: Vec<TeachIn> = if let Some(file) = &args.calibration {
        let program = match presets.as_deref() {
            None => None,
            Some([one]) => Some(spec_of(*one)),
            Some(_) => {
                return Err(CliError::new(
                    "--scenarios: a calibration was taught on one program; name one preset",
                ))
            }
        };
        let saved = super::read_calibration(file)?;
        vec![teach_in_calibration(&saved, file, program.as_ref())
            .map_err(|e| CliError::new(e.to_string()))?]
    } else {
        let presets = presets.ok_or_else(|| {
            CliError::new(
                "--teach-in needs a teach cut: --scenarios A,B (simulated), --log FILE or \
                 --calibration FILE",
            )
        })?;
        let specs: Vec<RunSpec> = presets.into_iter().map(spec_of).collect();
        teach_in_scenarios(&specs, default_threads(), &mut |r| progress.report(r))
            .map_err(|e| CliError::new(e.to_string()))?
    };
    if args.json {
        return write_json(io.stdout, &taught);
    }
    let out: String = taught.iter().map(describe).collect();
    io.stdout.write_all(out.as_bytes())?;
    Ok(())
}

/// A teach-in for people: what was learned, what is proposed, the preset's own target.
fn describe(t: &TeachIn) -> String {
    let l = &t.learned;
    let p = &t.proposal;
    let mut out = String::new();
    let at = match l.feedback {
        Feedback::SpindleCurrent => format!("spindle current at {:.0} rpm", l.at.spindle_rpm),
        Feedback::FeedCurrent => format!("feed current at {:.0} mm/min", l.at.feed_mm_min),
        Feedback::Dynamometer => "a dynamometer's force".to_string(),
    };
    let _ = writeln!(out, "{}: {at}, fitted on {} samples", t.source, l.periods);
    let calibrated = if p.calibrated_force_n.min.is_finite() {
        format!(
            "; the calibrated currents cover {:.0} to {:.0} N",
            p.calibrated_force_n.min, p.calibrated_force_n.max
        )
    } else {
        String::new()
    };
    let _ = writeln!(
        out,
        "  force at 100 % override {:.0} N{calibrated}",
        l.force_at_full_override_n
    );
    let current = |a: f64| {
        if a.is_finite() {
            format!("reference current {a:.3} A")
        } else {
            "read by the dynamometer: no current".to_string()
        }
    };
    let _ = writeln!(
        out,
        "  proposed target {:.0} N ({}), {}",
        p.target_n,
        p.basis.describe(),
        current(p.reference_current_a)
    );
    let _ = writeln!(
        out,
        "  estimate noise {:.1} N (1 σ); threshold gap {:.1} % (threshold:gap_pct={:.1})",
        p.estimate_noise_n, p.gap_pct, p.gap_pct
    );
    if let Some(paper) = &t.paper {
        let _ = writeln!(
            out,
            "  for comparison, {}: {:.0} N, {}",
            paper.what,
            paper.target_n,
            current(paper.reference_current_a)
        );
    }
    // What the calibration rests on, in the fit's words (as `cutlab calibrate` says it).
    for warning in &t.warnings {
        let _ = writeln!(out, "  warning: {warning}");
    }
    out
}

/// One row per evaluation: its parameters, then the objective and the means over the
/// scenarios of cycle time, force error, time above the limit and override activity; `best`
/// is marked with `*`.
fn evaluation_table<'a>(
    params: &[ParamRange],
    rows: impl Iterator<Item = (usize, &'a Evaluation)>,
    best: Option<usize>,
) -> String {
    let mut out = String::new();
    let widths: Vec<usize> = params.iter().map(|p| p.key.len().max(12) + 2).collect();
    let keys: usize = widths.iter().sum();
    let header = format!(
        "{:keys$}{:11}{:^49}",
        "", "", "── means over the scenarios ──"
    );
    let _ = writeln!(out, "{}", header.trim_end());
    for (p, width) in params.iter().zip(&widths) {
        let _ = write!(out, "{:>width$}", p.key);
    }
    let _ = writeln!(
        out,
        "{:>11}{:>11}{:>12}{:>12}{:>14}",
        "objective", "cycle (s)", "error (%)", "above (s)", "activity (%)"
    );
    for (i, e) in rows {
        for (v, width) in e.values.iter().zip(&widths) {
            let _ = write!(out, "{:>width$}", crate::input::readable(*v));
        }
        let mark = if best == Some(i) { "*" } else { " " };
        let _ = writeln!(
            out,
            "{:>10.3}{mark}{:>11.1}{:>12.1}{:>12.2}{:>14.0}",
            e.cost,
            e.cycle_time_s,
            e.force_error_pct,
            e.time_above_limit_s,
            e.override_activity_pct
        );
    }
    out
}
