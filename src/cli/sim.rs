//! `cutlab sim` and `cutlab compare`: closed-loop runs on the papers' presets.

use std::fmt::Write as _;

use serde::Serialize;

use super::args::required;
use super::{write_json, CliError, Io};
use crate::closed_loop::config::RunConfiguration;
use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::definition::{parse_texts, RunSetting, SettingError, SettingKind};
use crate::closed_loop::lab::{teach_cut_only, LabRun, RunResult, TeachKey};
use crate::closed_loop::metrics::Metrics;
use crate::closed_loop::paper_comparisons::PAPER_COMPARISONS;
use crate::closed_loop::paper_defaults::preset_controller;
use crate::closed_loop::references::{apply_references, ReferenceSearch, References};
use crate::closed_loop::summary::{
    best_marks, missing_notes, negative_saving_notes, not_best_note, METRIC_ROWS,
};
use crate::closed_loop::trace::write_csv;
use crate::control::registry::{ControllerConfig, ControllerKind};
use crate::control::run_names::run_names;
use crate::estimation::estimator::{Calibration, Feedback};
use crate::plant::Preset;
use crate::safety::SafetyEvent;
use crate::work::Work;

/// Options shared by `sim` and `compare`: the preset, every setting of the run definition
/// ([`RunSetting::ALL`], the same table the browser's form is made from), and `--no-references`.
/// Declared from that table at run time, so a setting added to it is an option here at once.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    scenario: Option<String>,
    /// The settings given, with their text, in table order.
    texts: Vec<(RunSetting, String)>,
    no_references: bool,
}

impl RunOptions {
    /// The first option given that defines the run (for the clash with `--config`).
    fn first_defining(&self) -> Option<&'static str> {
        self.scenario
            .as_ref()
            .map(|_| "scenario")
            .or_else(|| self.texts.first().map(|(s, _)| s.spec().cli_option))
    }
}

impl clap::FromArgMatches for RunOptions {
    fn from_arg_matches(matches: &clap::ArgMatches) -> Result<Self, clap::Error> {
        Self::from_arg_matches_mut(&mut matches.clone())
    }

    fn from_arg_matches_mut(matches: &mut clap::ArgMatches) -> Result<Self, clap::Error> {
        Ok(Self {
            scenario: matches.remove_one::<String>("scenario"),
            texts: RunSetting::ALL
                .into_iter()
                .filter_map(|s| {
                    matches
                        .remove_one::<String>(s.spec().cli_option)
                        .map(|text| (s, text))
                })
                .collect(),
            no_references: matches.get_flag("no-references"),
        })
    }

    fn update_from_arg_matches(&mut self, matches: &clap::ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(matches)?;
        Ok(())
    }
}

impl clap::Args for RunOptions {
    fn augment_args(command: clap::Command) -> clap::Command {
        use clap::{Arg, ArgAction};
        let mut command = command.arg(
            Arg::new("scenario")
                .long("scenario")
                .value_name("NAME")
                .value_parser(clap::value_parser!(String))
                .help("Preset to run (see cutlab scenarios)"),
        );
        for setting in RunSetting::ALL {
            let spec = setting.spec();
            let placeholder = match spec.kind {
                SettingKind::Feedback => "spindle|feed|dynamometer",
                SettingKind::Material => "NAME",
                SettingKind::Count { .. } | SettingKind::Seed => "N",
                SettingKind::Number { .. } if spec.unit.is_empty() => "X",
                SettingKind::Number { .. } => spec.unit,
            };
            command = command.arg(
                Arg::new(spec.cli_option)
                    .long(spec.cli_option)
                    .value_name(placeholder)
                    .value_parser(clap::value_parser!(String))
                    .allow_hyphen_values(true)
                    .help(spec.help),
            );
        }
        command.arg(
            Arg::new("no-references")
                .long("no-references")
                .action(ArgAction::SetTrue)
                .help("Skip the fixed-feed reference runs (no savings; faster)"),
        )
    }

    fn augment_args_for_update(command: clap::Command) -> clap::Command {
        Self::augment_args(command)
    }
}

pub(crate) const FUZZY_ENGINE_HELP: &str =
    "The engine the fuzzy-engine controller runs: an FLL or \
     FIS file with two inputs (the first is E, the second EC) and one output (the override's \
     change)";

/// An engine file given with `--fuzzy-engine`: its path (for messages) and text.
#[derive(Debug, Clone)]
pub struct EngineFile {
    path: String,
    text: String,
}

impl EngineFile {
    /// Reads `--fuzzy-engine FILE`, if given.
    pub fn read(path: Option<&str>) -> Result<Option<Self>, CliError> {
        path.map(|path| {
            std::fs::read_to_string(path)
                .map(|text| EngineFile {
                    path: path.to_string(),
                    text,
                })
                .map_err(|e| CliError::new(format!("--fuzzy-engine: cannot read {path:?}: {e}")))
        })
        .transpose()
    }

    /// Gives the engine to `config` if it is a `fuzzy-engine` controller; other controllers
    /// run their own laws.
    pub(crate) fn give_to(&self, config: &mut ControllerConfig) -> Result<(), CliError> {
        if config.kind() != ControllerKind::FuzzyEngine {
            return Ok(());
        }
        config
            .set_engine(&self.text)
            .map_err(|e| CliError::new(format!("--fuzzy-engine {}: {e}", self.path)))
    }
}

/// `--fuzzy-engine` given where no controller runs it is a mistake worth a message.
pub(crate) fn check_engine_used<'a>(
    engine: &Option<EngineFile>,
    mut kinds: impl Iterator<Item = &'a ControllerConfig>,
) -> Result<(), CliError> {
    match engine {
        Some(file) if !kinds.any(|c| c.kind() == ControllerKind::FuzzyEngine) => {
            Err(CliError::new(format!(
                "--fuzzy-engine {}: no controller runs it; it is the engine of the {} controller",
                file.path,
                ControllerKind::FuzzyEngine
            )))
        }
        _ => Ok(()),
    }
}

const CONFIG_HELP: &str = "Run what a saved configuration (the browser's Configuration JSON \
     export) holds, instead of --scenario, --controller and the other run options";

/// Run one closed loop on a preset: a teach cut calibrates the current-to-force model, then the
/// controller holds the force through the safety envelope. Prints the metrics; --csv and --json
/// write the trace and the full report.
#[derive(Debug, clap::Args)]
pub struct SimArgs {
    #[command(flatten)]
    run: RunOptions,
    /// Controller (see cutlab controllers)
    #[arg(long, value_name = "NAME")]
    controller: Option<String>,
    /// Set a controller parameter (repeatable)
    #[arg(long, value_name = "KEY=VALUE", allow_hyphen_values = true)]
    set: Vec<String>,
    #[arg(long = "fuzzy-engine", value_name = "FILE", help = FUZZY_ENGINE_HELP)]
    fuzzy_engine: Option<String>,
    /// Write the trace as CSV (one row per control period)
    #[arg(long, value_name = "FILE")]
    csv: Option<String>,
    /// Write metrics, settings, calibration and events as JSON
    #[arg(long, value_name = "FILE")]
    json: Option<String>,
    #[arg(long, value_name = "FILE", help = CONFIG_HELP)]
    config: Option<String>,
    /// Start from a saved calibration (cutlab-calibration JSON) instead of a teach cut
    #[arg(long, value_name = "FILE")]
    calibration: Option<String>,
    /// Write the run's calibration (the teach cut's, or the one given) as a calibration file
    #[arg(long = "save-calibration", value_name = "FILE")]
    save_calibration: Option<String>,
}

/// Run several controllers (or tunings: pi:kp=0.5) on one preset with the same seed and print
/// their metrics side by side; * marks the best value of each row.
#[derive(Debug, clap::Args)]
pub struct CompareArgs {
    #[command(flatten)]
    run: RunOptions,
    /// Controllers to compare; each NAME or NAME:key=value:key=value
    #[arg(long, value_name = "A,B,...")]
    controllers: Option<String>,
    #[arg(long = "fuzzy-engine", value_name = "FILE", help = FUZZY_ENGINE_HELP)]
    fuzzy_engine: Option<String>,
    /// Print the metrics as JSON instead of a table
    #[arg(long)]
    json: bool,
    #[arg(long, value_name = "FILE", help = CONFIG_HELP)]
    config: Option<String>,
}

/// The runs of `--config FILE`, if given; `defining` is the first option given that it replaces,
/// which may not be given with it (two sources for one setting would leave a person guessing
/// which won).
fn runs_from_config(
    config: &Option<String>,
    defining: Option<&str>,
) -> Result<Option<Vec<RunSpec>>, CliError> {
    let Some(path) = config else {
        return Ok(None);
    };
    if let Some(clash) = defining {
        return Err(CliError::new(format!(
            "--{clash} cannot be given with --config: the file defines the runs"
        )));
    }
    let text = std::fs::read_to_string(path)
        .map_err(|e| CliError::new(format!("--config: cannot read {path:?}: {e}")))?;
    let config = RunConfiguration::from_json(&text)
        .map_err(|e| CliError::new(format!("--config {path}: {e}")))?;
    Ok(Some(config.runs))
}

fn preset_option(run: &RunOptions) -> Result<Preset, CliError> {
    let name: String = required("scenario", &run.scenario)?;
    Preset::named(&name).map_err(|e| CliError::new(format!("--scenario: {e}")))
}

/// The run spec from the shared options, for a given controller: every setting parsed and
/// checked by the run definition, as the browser's form does ([`parse_texts`]).
fn spec(run: &RunOptions, controller: ControllerConfig) -> Result<RunSpec, CliError> {
    parse_texts(preset_option(run)?, controller, &run.texts).map_err(|errors| {
        // The first problem, in the order the options are listed, as one line.
        let message = errors
            .first()
            .map_or_else(String::new, SettingError::for_cli);
        CliError::new(message)
    })
}

/// Every run spec the `sim` options describe, for tests that hold the command line and the
/// browser's form to one run definition.
pub fn spec_from_args(args: &[String]) -> Result<RunSpec, CliError> {
    #[derive(clap::Parser)]
    struct Sim {
        #[command(flatten)]
        args: SimArgs,
    }
    let parsed = <Sim as clap::Parser>::try_parse_from(
        std::iter::once("sim").chain(args.iter().map(String::as_str)),
    )
    .map_err(|e| super::args::one_line(&e, args, &<Sim as clap::CommandFactory>::command()))?;
    let engine = EngineFile::read(parsed.args.fuzzy_engine.as_deref())?;
    // Settings alone (what these tests vary) run the fixed feed; `cutlab sim` asks for a
    // controller.
    let only_settings =
        parsed.args.controller.is_none() && parsed.args.set.is_empty() && engine.is_none();
    let controller = if only_settings {
        ControllerConfig::new(ControllerKind::Fixed)
    } else {
        sim_controller(&parsed.args, &engine)?
    };
    spec(&parsed.args.run, controller)
}

/// The controller `sim`'s options describe: `--controller NAME` (an engine alone implies
/// `fuzzy-engine`) with the preset's defaults, the engine, then the `--set` assignments through
/// [`ControllerConfig::set_texts`] (a parameter given twice is refused).
fn sim_controller(
    args: &SimArgs,
    engine: &Option<EngineFile>,
) -> Result<ControllerConfig, CliError> {
    let kind: ControllerKind = match (&args.controller, engine) {
        (None, Some(_)) => ControllerKind::FuzzyEngine,
        _ => required::<String>("controller", &args.controller)?
            .parse()
            .map_err(|e| CliError::new(format!("--controller: {e}")))?,
    };
    let mut controller = preset_controller(preset_option(&args.run)?, kind);
    if let Some(file) = engine {
        file.give_to(&mut controller)?;
    }
    check_engine_used(engine, std::iter::once(&controller))?;
    controller
        .set_texts(args.set.iter().map(String::as_str))
        .map_err(|e| CliError::new(format!("--set: {e}")))?;
    Ok(controller)
}

/// Parses `NAME` or `NAME:key=value:key=value`, starting from `preset`'s defaults (the paper's own
/// parameters where it states them); a `fuzzy-engine` controller runs `engine` if given. The
/// assignments go through [`ControllerConfig::set_texts`], which refuses a parameter given twice.
pub fn controller_with_settings(
    text: &str,
    preset: Preset,
    engine: Option<&EngineFile>,
) -> Result<ControllerConfig, CliError> {
    let mut parts = text.split(':');
    let name = parts.next().unwrap_or_default();
    let kind: ControllerKind = name.parse().map_err(|e| CliError::new(format!("{e}")))?;
    let mut config = preset_controller(preset, kind);
    if let Some(file) = engine {
        file.give_to(&mut config)?;
    }
    config
        .set_texts(parts)
        .map_err(|e| CliError::new(format!("{text}: {e}")))?;
    Ok(config)
}

fn run_one(
    spec: &RunSpec,
    calibration: Option<Calibration>,
    with_references: bool,
) -> Result<(RunResult, Option<References>), CliError> {
    let (mut results, refs) = run_many(
        spec,
        &[(String::new(), spec.clone())],
        calibration,
        with_references,
    )?;
    let result = results
        .pop()
        .ok_or_else(|| CliError::new("the run gave no result"))?;
    Ok((result, refs))
}

/// A job of [`run_many`].
enum Job<'a> {
    References,
    Run(&'a str, &'a RunSpec),
}

/// What a job gave, its error already in words.
enum JobOutcome {
    References(Result<References, String>),
    Run(Box<Result<RunResult, String>>),
}

/// The runs of `named` (on `base`'s scenario) and, `with_references`, that scenario's fixed-feed
/// references, their savings filled in. The teach cut is made once for every run whose teach cut
/// it is ([`TeachKey`]: the simulation would repeat it exactly), then the runs and the reference
/// search go side by side on every core ([`crate::work::parallel_map`]); the results are the
/// same as one after another. A `given` calibration (a saved one) replaces the runs' teach cut;
/// the references still learn theirs, as they would on the machine.
fn run_many(
    base: &RunSpec,
    named: &[(String, RunSpec)],
    given: Option<Calibration>,
    with_references: bool,
) -> Result<(Vec<RunResult>, Option<References>), CliError> {
    let key = TeachKey::of(base).map_err(|e| CliError::new(e.to_string()))?;
    let taught = if given.is_none() || with_references {
        Some(
            teach_cut_only(base)
                .map_err(|e| CliError::new(e.to_string()))?
                .1,
        )
    } else {
        None
    };
    let mut jobs = Vec::with_capacity(named.len() + 1);
    // The reference search first: its runs are the longest, so it starts at once.
    if with_references {
        jobs.push(Job::References);
    }
    jobs.extend(named.iter().map(|(name, spec)| Job::Run(name, spec)));
    let outcomes = crate::work::parallel_map(&jobs, |job| match job {
        Job::References => JobOutcome::References(match &taught {
            Some(calibration) => ReferenceSearch::calibrated(base, calibration.clone())
                .and_then(|search| search.run_to_end())
                .map_err(|e| e.to_string()),
            None => Err("the references need a teach cut".into()),
        }),
        Job::Run(name, spec) => {
            let run = match (&given, &taught, TeachKey::of(spec)) {
                (Some(given), _, _) => LabRun::calibrated(spec, given.clone()),
                (None, Some(taught), Ok(k)) if k == key => LabRun::calibrated(spec, taught.clone()),
                (_, _, Ok(_)) => LabRun::new(spec),
                (_, _, Err(e)) => Err(e),
            };
            JobOutcome::Run(Box::new(run.and_then(|run| run.run_to_end()).map_err(
                |e| {
                    if name.is_empty() {
                        e.to_string()
                    } else {
                        format!("{name}: {e}")
                    }
                },
            )))
        }
    });
    let mut refs = None;
    let mut results = Vec::with_capacity(named.len());
    for outcome in outcomes {
        match outcome {
            JobOutcome::References(r) => refs = Some(r.map_err(CliError::new)?),
            JobOutcome::Run(r) => results.push((*r).map_err(CliError::new)?),
        }
    }
    if let Some(r) = &refs {
        for result in &mut results {
            apply_references(result, r);
        }
    }
    Ok((results, refs))
}

/// The JSON report of one run (`cutlab sim --json`; `cutlab host --json` adds the link's).
#[derive(Serialize)]
pub(crate) struct SimReport<'a> {
    scenario: &'static str,
    controller: &'a ControllerConfig,
    seed: u64,
    target_force_n: f64,
    force_limit_n: f64,
    control_period_s: f64,
    feedback: Feedback,
    metrics: &'a Metrics,
    references: Option<References>,
    calibration: &'a Calibration,
    pub(crate) events: Vec<EventLine>,
}

/// One event of a report.
#[derive(Serialize)]
pub(crate) struct EventLine {
    pub(crate) time_s: f64,
    pub(crate) event: String,
}

impl<'a> SimReport<'a> {
    /// The report of `result`, a run of `spec`.
    pub(crate) fn new(
        spec: &RunSpec,
        result: &'a RunResult,
        references: Option<References>,
    ) -> Self {
        SimReport {
            scenario: spec.preset.name(),
            controller: &result.spec.controller,
            seed: spec.seed,
            target_force_n: result.settings.target_force_n,
            force_limit_n: result.settings.force_limit_n,
            control_period_s: result.settings.control_period_s,
            feedback: result.settings.feedback,
            metrics: &result.metrics,
            references,
            calibration: &result.calibration,
            events: result
                .trace
                .events
                .iter()
                .map(|e| EventLine {
                    time_s: e.time_s(),
                    event: e.describe(),
                })
                .collect(),
        }
    }
}

/// Runs `cutlab sim`.
pub fn run_sim(args: SimArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    let defining = args.run.first_defining().or_else(|| {
        (args.controller.is_some())
            .then_some("controller")
            .or((!args.set.is_empty()).then_some("set"))
            .or(args.fuzzy_engine.is_some().then_some("fuzzy-engine"))
    });
    let spec = match runs_from_config(&args.config, defining)? {
        Some(mut runs) if runs.len() == 1 => runs.remove(0),
        Some(runs) => {
            return Err(CliError::new(format!(
                "--config holds {} runs; cutlab sim runs one (use cutlab compare --config)",
                runs.len()
            )))
        }
        None => {
            let engine = EngineFile::read(args.fuzzy_engine.as_deref())?;
            spec(&args.run, sim_controller(&args, &engine)?)?
        }
    };
    let calibration = args
        .calibration
        .as_deref()
        .map(super::read_calibration)
        .transpose()?;
    let (result, refs) = run_one(
        &spec,
        calibration.map(|c| c.calibration),
        !args.run.no_references,
    )?;
    if let Some(path) = args.save_calibration.as_deref() {
        let source = match args.calibration.as_deref() {
            Some(from) => format!("{from}, used by cutlab sim on {}", spec.preset.name()),
            None => format!(
                "teach cut on {}, seed {}, {} feedback",
                spec.preset.name(),
                spec.seed,
                result.settings.feedback.name()
            ),
        };
        super::save_calibration(path, &result.calibration, source)?;
    }
    if let Some(path) = args.csv.as_deref() {
        let mut file = std::fs::File::create(path)
            .map_err(|e| CliError::new(format!("--csv: cannot create {path:?}: {e}")))?;
        write_csv(&result.trace, &mut file)
            .map_err(|e| CliError::new(format!("--csv: cannot write {path:?}: {e}")))?;
    }
    if let Some(path) = args.json.as_deref() {
        let report = SimReport::new(&spec, &result, refs);
        let mut file = std::fs::File::create(path)
            .map_err(|e| CliError::new(format!("--json: cannot create {path:?}: {e}")))?;
        write_json(&mut file, &report)?;
    }
    let table = metrics_table(&[(spec.controller.kind().name().to_string(), &result)]);
    io.stdout.write_all(table.as_bytes())?;
    super::print_calibration_warnings(io.stdout, &result.calibration)?;
    fail_on_controller_faults([(spec.controller.kind().name(), &result)])
}

/// A run whose controller asked for a non-finite override completed only because the envelope
/// held the override: its results are printed, and the command still fails so a script notices.
pub(crate) fn fail_on_controller_faults<'a>(
    runs: impl IntoIterator<Item = (&'a str, &'a RunResult)>,
) -> Result<(), CliError> {
    let faulted: Vec<String> = runs
        .into_iter()
        .filter_map(|(name, result)| {
            result.trace.events.iter().find_map(|e| match e {
                SafetyEvent::ControllerFault { time_s } => Some(format!("{name} at {time_s:.2} s")),
                _ => None,
            })
        })
        .collect();
    if faulted.is_empty() {
        Ok(())
    } else {
        Err(CliError::new(format!(
            "the controller asked for a non-finite override ({}); the safety envelope held the \
             override, so the results above are not the controller's",
            faulted.join(", ")
        )))
    }
}

#[derive(Serialize)]
struct CompareEntry<'a> {
    controller: &'a ControllerConfig,
    metrics: &'a Metrics,
}

/// Runs `cutlab compare`.
pub fn run_compare(args: CompareArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    let defining = args
        .run
        .first_defining()
        .or_else(|| args.controllers.is_some().then_some("controllers"))
        .or_else(|| args.fuzzy_engine.is_some().then_some("fuzzy-engine"));
    let (base, named) = match runs_from_config(&args.config, defining)? {
        Some(runs) => one_scenario(runs)?,
        None => {
            let engine = EngineFile::read(args.fuzzy_engine.as_deref())?;
            let list: String = required("controllers", &args.controllers)?;
            let named = list
                .split(',')
                .enumerate()
                .map(|(i, s)| match s.trim() {
                    "" => Err(CliError::new(format!(
                        "--controllers: entry {} of {list:?} is empty",
                        i + 1
                    ))),
                    s => Ok((
                        s.to_string(),
                        controller_with_settings(s, preset_option(&args.run)?, engine.as_ref())?,
                    )),
                })
                .collect::<Result<Vec<_>, CliError>>()?;
            refuse_repeated_entries(&list, &named)?;
            check_engine_used(&engine, named.iter().map(|(_, c)| c))?;
            (
                spec(&args.run, ControllerConfig::new(ControllerKind::Fixed))?,
                named,
            )
        }
    };
    let specs: Vec<(String, RunSpec)> = named
        .iter()
        .map(|(name, config)| {
            let mut s = base.clone();
            s.controller = config.clone();
            (name.clone(), s)
        })
        .collect();
    let (runs, refs) = run_many(&base, &specs, None, !args.run.no_references)?;
    let results: Vec<(String, ControllerConfig, RunResult)> = named
        .into_iter()
        .zip(runs)
        .map(|((name, config), result)| (name, config, result))
        .collect();
    if args.json {
        let entries: Vec<CompareEntry> = results
            .iter()
            .map(|(_, config, r)| CompareEntry {
                controller: config,
                metrics: &r.metrics,
            })
            .collect();
        write_json(io.stdout, &entries)?;
        return fail_on_controller_faults(results.iter().map(|(n, _, r)| (n.as_str(), r)));
    }
    let refs_line = refs.map(|r| {
        let safe = if r.safe_fixed_override_pct.is_finite() {
            format!(
                "safest fixed override {:.0} % → {:.1} s",
                r.safe_fixed_override_pct, r.safe_fixed_cycle_time_s
            )
        } else {
            "no fixed override keeps the peak force at the target".to_string()
        };
        format!(
            "references: programmed feed {:.1} s; {safe}\n",
            r.programmed_cycle_time_s
        )
    });
    let borrowed: Vec<(String, &RunResult)> =
        results.iter().map(|(n, _, r)| (n.clone(), r)).collect();
    io.stdout
        .write_all(format!("scenario {}, seed {}\n", base.preset.name(), base.seed).as_bytes())?;
    if let Some(line) = refs_line {
        io.stdout.write_all(line.as_bytes())?;
    }
    io.stdout.write_all(metrics_table(&borrowed).as_bytes())?;
    // Runs of one of the papers' comparisons (its preset and controllers, whatever the settings)
    // are judged as the Compare page judges them.
    let shown: Vec<&RunResult> = results.iter().map(|(_, _, r)| r).collect();
    let judged = PAPER_COMPARISONS
        .iter()
        .find_map(|c| c.finding(&shown).map(|f| (c.claim, f)));
    if let Some((claim, finding)) = judged {
        io.stdout
            .write_all(format!("{claim}\n{}\n", finding.text()).as_bytes())?;
    }
    fail_on_controller_faults(results.iter().map(|(n, _, r)| (n.as_str(), r)))
}

/// A `--controllers` entry given twice would make two columns of one name and the same numbers
/// (one scenario, one seed): refused, naming it. Entries that differ in their text (`pi` and
/// `pi:kp=0.45`) are columns of their own, named as typed, even where they set the same values.
fn refuse_repeated_entries(
    list: &str,
    named: &[(String, ControllerConfig)],
) -> Result<(), CliError> {
    for (i, (name, _)) in named.iter().enumerate() {
        if let Some(earlier) = named[..i].iter().position(|(n, _)| n == name) {
            return Err(CliError::new(format!(
                "--controllers: {name:?} is given twice in {list:?} (entries {} and {}); each \
                 column is one controller: give each once, or tell them apart by a parameter \
                 ({name}:key=value)",
                earlier + 1,
                i + 1
            )));
        }
    }
    Ok(())
}

/// Splits a saved comparison into its scenario (with the fixed-feed controller, for the
/// references) and its named controllers. Every run must share the scenario: one set of reference
/// runs measures every variant's saving.
fn one_scenario(
    runs: Vec<RunSpec>,
) -> Result<(RunSpec, Vec<(String, ControllerConfig)>), CliError> {
    let Some(mut base) = runs.first().cloned() else {
        return Err(CliError::new("--config: the file holds no runs"));
    };
    base.controller = ControllerConfig::new(ControllerKind::Fixed);
    let mut named: Vec<(String, ControllerConfig)> = Vec::new();
    for (i, run) in runs.into_iter().enumerate() {
        let mut scenario = run.clone();
        scenario.controller = base.controller.clone();
        if scenario != base {
            return Err(CliError::new(format!(
                "--config: run {} differs from run 1 in its preset, seed, settings or machine; a \
                 comparison runs one scenario (run the others with cutlab sim --config)",
                i + 1
            )));
        }
        named.push((String::new(), run.controller));
    }
    // Named as the Compare page names its columns, by the law each runs; the page tells runs of
    // one law apart by the form beside each column, a table by a number.
    let configs: Vec<&ControllerConfig> = named.iter().map(|(_, c)| c).collect();
    let names = run_names(&configs);
    for (i, name) in names.iter().enumerate() {
        let same = names[..i].iter().filter(|n| *n == name).count();
        named[i].0 = match same {
            0 => name.clone(),
            _ => format!("{name} ({})", same + 1),
        };
    }
    Ok((base, named))
}

/// A table of metrics, one column per run; `*` marks the best value of each row (never a run
/// above the force limit for a share of its cycle, which a last line names).
pub(crate) fn metrics_table(runs: &[(String, &RunResult)]) -> String {
    let shown = |v: f64| {
        if v.fract() == 0.0 {
            format!("{v:.0}")
        } else {
            format!("{v:.1}")
        }
    };
    let label_width = METRIC_ROWS
        .iter()
        .map(|row| row.heading().chars().count())
        .max()
        .unwrap_or(0);
    let col_width = runs
        .iter()
        .map(|(n, _)| n.chars().count())
        .max()
        .unwrap_or(0)
        .max(10);
    let mut out = String::new();
    let _ = write!(out, "{:label_width$}", "");
    for (name, _) in runs {
        let _ = write!(out, "  {name:>col_width$}");
    }
    out.push('\n');
    let results: Vec<&RunResult> = runs.iter().map(|(_, r)| *r).collect();
    for row in &METRIC_ROWS {
        let values: Vec<Option<f64>> = runs.iter().map(|(_, r)| (row.value)(r)).collect();
        let marks = best_marks(row, &results, shown);
        let _ = write!(out, "{:label_width$}", row.heading());
        for (v, is_best) in values.into_iter().zip(marks) {
            let cell = format!("{}{}", row.show(v, shown), if is_best { "*" } else { " " });
            let _ = write!(out, "  {cell:>col_width$}");
        }
        out.push('\n');
    }
    let named: Vec<(&str, &RunResult)> = runs.iter().map(|(n, r)| (n.as_str(), *r)).collect();
    for note in missing_notes(&named) {
        let _ = writeln!(out, "— {note}");
    }
    for note in negative_saving_notes(&named) {
        let _ = writeln!(out, "{note}");
    }
    if let Some(note) = not_best_note(&named) {
        out.push_str(&note);
        out.push('\n');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::closed_loop::lab::simulate;

    #[test]
    fn every_dash_of_the_table_says_why() {
        let spec = RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Fixed);
        let run = simulate(&spec).unwrap();
        let mut none_safe = run.clone();
        apply_references(
            &mut none_safe,
            &References {
                programmed_cycle_time_s: 2.0 * run.metrics.cycle_time_s,
                safe_fixed_override_pct: f64::NAN,
                safe_fixed_cycle_time_s: f64::NAN,
            },
        );
        // No references yet: both savings say so, for every run alike.
        let table = metrics_table(&[("a".into(), &run), ("b".into(), &run)]);
        assert!(
            table.contains("— Saving vs safe fixed feed (%): no reference runs"),
            "{table}"
        );
        // References without a safe fixed feed: that run's reason is its own, and named.
        let table = metrics_table(&[("a".into(), &run), ("b".into(), &none_safe)]);
        assert!(
            table.contains("— Saving vs safe fixed feed (%), b: no safe fixed feed"),
            "{table}"
        );
        assert!(
            table.contains("— Saving vs programmed feed (%), a: no reference runs"),
            "{table}"
        );
        assert!(!table.contains("programmed feed (%), b"), "{table}");
    }

    #[test]
    fn a_controller_fault_fails_the_command_and_names_the_run() {
        let spec = RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Fixed);
        let mut result = simulate(&spec).unwrap();
        assert!(fail_on_controller_faults([("fixed", &result)]).is_ok());
        result
            .trace
            .events
            .push(SafetyEvent::ControllerFault { time_s: 4.5 });
        let e = fail_on_controller_faults([("fixed", &result)]).unwrap_err();
        assert!(e.0.contains("fixed at 4.50 s"), "{e}");
        assert!(e.0.contains("held the override"), "{e}");
    }
}
