//! Tuning: a controller's parameters chosen by sweeping a grid or by minimising an objective over
//! several scenarios, and the settings a teach-in proposes.
//!
//! ```text
//! TuningProblem (controller, 1–n parameter ranges, scenarios, objective)
//!   ├─ sweep(steps)   every grid point on every scenario          → Vec<Evaluation>
//!   └─ tune(search)   Nelder–Mead in the parameters' box          → Tuned { best, evaluations, pareto }
//! Evaluation = the parameters, each scenario's metrics, their objective, the mean cycle time and
//!              force error (the two axes of the Pareto front)
//! teach_in          a teach cut (simulated, logged or saved) → a target, reference current, gap
//! ```
//!
//! Every evaluation runs the same closed loop as Simulate ([`crate::closed_loop::lab`]); each
//! scenario's teach cut runs once and its calibration is reused for every parameter set, since it
//! does not depend on the controller. Each scenario runs its own controller settings (its preset's
//! paper values and the caller's) with the tuned parameters set. Natively every (point, scenario)
//! run of a sweep, and the runs of each search evaluation (with runs ahead of the search in idle
//! threads, [`plan`]), share the machine's cores through one queue; the results are in the same
//! order, bit for bit, however many threads ran them.
//!
//! | file | what |
//! |---|---|
//! | this file | the problem (controller, ranges, scenarios, objective), sweeps, searches, the Pareto front |
//! | [`objective`] | the weighted objective a tuning minimises |
//! | [`nelder_mead`] | Nelder–Mead inside a box, deterministic |
//! | [`plan`] | tuning whose runs are made elsewhere (the browser's workers), with runs ahead of a search |
//! | [`teach_in`](mod@teach_in) | what a teach cut learned and the target, reference current and gap proposed from it |
//! | [`settings`] | a tuning's settings as one table (Tune page fields, `cutlab tune` options) |

pub mod nelder_mead;
pub mod objective;
pub mod plan;
pub mod settings;
pub mod teach_in;

use serde::Serialize;

use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::error::LoopError;
use crate::closed_loop::lab::LabRun;
use crate::closed_loop::metrics::Metrics;
use crate::control::registry::{ControllerConfig, ParamError};
use crate::estimation::estimator::Calibration;
use crate::input::three_significant;
use crate::work::{parallel_map_reporting as parallel_map, Work};
use nelder_mead::NelderMead;
pub use objective::Objective;
pub use plan::{PlannedRun, RunId, TuningPlan};
pub use teach_in::{simulated_teach_in, teach_in, TeachIn};

/// One parameter to tune and its bounds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParamRange {
    /// The controller's parameter key (`kp`, `output_range_pct`, …).
    pub key: String,
    /// Lowest value tried.
    pub lo: f64,
    /// Highest value tried.
    pub hi: f64,
}

impl ParamRange {
    /// Parses `key=lo:hi`, as typed on the command line: each bound through its row of the
    /// tuning's table ([`settings::parse_range`]), as the Tune page's fields.
    ///
    /// ```
    /// use cutlab::tuning::ParamRange;
    /// let r = ParamRange::parse("kp=0.1:2").unwrap();
    /// assert_eq!((r.key.as_str(), r.lo, r.hi), ("kp", 0.1, 2.0));
    /// assert!(ParamRange::parse("kp=2:0.1").unwrap_err().contains("lower"));
    /// assert!(ParamRange::parse("kp").is_err());
    /// ```
    pub fn parse(text: &str) -> Result<Self, String> {
        let (key, range) = text
            .split_once('=')
            .ok_or_else(|| format!("{text:?} is not of the form key=lo:hi"))?;
        let (lo, hi) = range
            .split_once(':')
            .ok_or_else(|| format!("{text:?}: the range must be lo:hi"))?;
        settings::parse_range(key, lo, hi, None).map_err(|errors| {
            let problem = errors.first().map(|e| e.problem.to_string());
            format!("{}: {}", key.trim(), problem.unwrap_or_default())
        })
    }
}

/// Why tuning could not run.
#[derive(Debug, Clone, PartialEq)]
pub enum TuningError {
    /// A parameter range is not the controller's, or leaves its accepted range.
    Param(ParamError),
    /// No scenario or no parameter given, or a grid too large.
    Setup(String),
    /// A scenario's run failed; names the preset.
    Run {
        /// The preset.
        preset: &'static str,
        /// Why.
        error: LoopError,
    },
    /// A teach-in could not propose anything; the message names the source.
    TeachIn(String),
}

impl TuningError {
    /// The error with `source` (a log, a calibration file) named in front of a teach-in's
    /// message.
    pub fn within(self, source: &str) -> Self {
        match self {
            TuningError::TeachIn(message) => TuningError::TeachIn(format!("{source}: {message}")),
            other => other,
        }
    }
}

impl std::fmt::Display for TuningError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TuningError::Param(e) => write!(f, "{e}"),
            TuningError::Setup(message) => f.write_str(message),
            TuningError::Run { preset, error } => write!(f, "{preset}: {error}"),
            TuningError::TeachIn(message) => f.write_str(message),
        }
    }
}

impl std::error::Error for TuningError {}

/// The largest grid a sweep runs (points × scenarios are full closed-loop runs).
pub const MAX_SWEEP_POINTS: usize = 400;

/// What to tune, where, and by what measure.
#[derive(Debug, Clone)]
pub struct TuningProblem {
    /// The controller tuned: its kind, and the values the search starts from.
    pub controller: ControllerConfig,
    /// The parameters tuned, each within its range.
    pub params: Vec<ParamRange>,
    /// The scenarios, each a run definition. Its controller (the same kind as `controller`)
    /// runs with the tuned parameters set and every other parameter as it is there, so each
    /// preset keeps its own paper values (paper 002's output range on its own preset only).
    pub scenarios: Vec<RunSpec>,
    /// What "better" means.
    pub objective: Objective,
}

/// One parameter set on every scenario.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Evaluation {
    /// The tuned parameters' values, in the problem's order.
    pub values: Vec<f64>,
    /// The objective, averaged over the scenarios.
    pub cost: f64,
    /// Mean cycle time over the scenarios.
    pub cycle_time_s: f64,
    /// Mean |force error| over the scenarios, percent of target.
    pub force_error_pct: f64,
    /// Mean time above the force limit over the scenarios.
    pub time_above_limit_s: f64,
    /// Mean override activity (total variation Σ|Δu|) over the scenarios, percent.
    pub override_activity_pct: f64,
    /// Each scenario's metrics, in the problem's order.
    pub metrics: Vec<Metrics>,
}

/// The outcome of [`Tuner::tune`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Tuned {
    /// The evaluation of lowest cost.
    pub best: Evaluation,
    /// Every evaluation, in the order made.
    pub evaluations: Vec<Evaluation>,
    /// Indices into `evaluations` of the Pareto front of (cycle time, force error), by cycle time.
    pub pareto: Vec<usize>,
    /// Whether the search met its tolerances before its budget ran out.
    pub converged: bool,
}

/// What a tuning reports while it runs (the command line prints it on stderr).
#[derive(Debug, Clone, Copy)]
pub enum Report<'a> {
    /// A scenario's teach cut finished.
    Taught {
        /// The scenario.
        preset: &'static str,
        /// Teach cuts done so far.
        done: usize,
        /// Teach cuts in all.
        total: usize,
    },
    /// A parameter set has run on every scenario.
    Evaluated {
        /// Evaluations done so far (a sweep's finish out of grid order).
        done: usize,
        /// Evaluations in all: the grid's points, or the search's budget.
        total: usize,
        /// True for a search, which may stop before its budget.
        at_most: bool,
        /// The evaluation.
        evaluation: &'a Evaluation,
    },
}

/// The threads tuning uses natively: one per core.
pub fn default_threads() -> usize {
    crate::work::available_threads()
}

/// Runs evaluations of a problem, reusing each scenario's teach cut.
pub struct Tuner {
    problem: TuningProblem,
    calibrations: Vec<Calibration>,
    threads: usize,
}

impl Tuner {
    /// Checks the problem and runs each scenario's teach cut once, on all cores.
    pub fn new(problem: TuningProblem) -> Result<Self, TuningError> {
        Self::with_threads(problem, default_threads(), &mut |_| {})
    }

    /// [`Tuner::new`] on at most `threads` threads (natively; wasm has one), telling `report`
    /// as each teach cut finishes. The results do not depend on `threads`.
    pub fn with_threads(
        problem: TuningProblem,
        threads: usize,
        report: &mut dyn FnMut(&Report<'_>),
    ) -> Result<Self, TuningError> {
        check(&problem)?;
        let total = problem.scenarios.len();
        let mut done = 0;
        let calibrations = parallel_map(&problem.scenarios, threads, calibrate, |i, _| {
            done += 1;
            report(&Report::Taught {
                preset: problem.scenarios[i].preset.name(),
                done,
                total,
            });
        })
        .into_iter()
        .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            problem,
            calibrations,
            threads: threads.max(1),
        })
    }

    /// The problem.
    pub fn problem(&self) -> &TuningProblem {
        &self.problem
    }

    /// Scenario `index`'s run definition with `values` set on its controller.
    fn spec_at(&self, index: usize, values: &[f64]) -> Result<RunSpec, TuningError> {
        spec_with(&self.problem, index, values)
    }

    /// Runs `values` (one per tuned parameter) on every scenario, in parallel.
    pub fn evaluate(&self, values: &[f64]) -> Result<Evaluation, TuningError> {
        let specs = (0..self.problem.scenarios.len())
            .map(|i| self.spec_at(i, values))
            .collect::<Result<Vec<_>, _>>()?;
        let jobs: Vec<(RunSpec, &Calibration)> =
            specs.into_iter().zip(&self.calibrations).collect();
        let metrics = parallel_map(
            &jobs,
            self.threads,
            |(spec, calibration)| run_calibrated(spec, (*calibration).clone()),
            |_, _| {},
        )
        .into_iter()
        .collect::<Result<Vec<Metrics>, _>>()?;
        Ok(summarise(&self.problem, values.to_vec(), metrics))
    }

    /// Every point of the grid with `steps` values per parameter (lo … hi evenly, both ends
    /// included; one step takes the middle), the first parameter varying slowest.
    ///
    /// Natively every (point, scenario) run goes into one queue the threads take from, so all
    /// cores stay busy until the grid is done; the result is in grid order either way.
    pub fn sweep(&self, steps: usize) -> Result<Vec<Evaluation>, TuningError> {
        self.sweep_reporting(steps, &mut |_| {})
    }

    /// [`Tuner::sweep`], telling `report` as each point's last run finishes (in the order they
    /// finish, on the calling thread).
    pub fn sweep_reporting(
        &self,
        steps: usize,
        report: &mut dyn FnMut(&Report<'_>),
    ) -> Result<Vec<Evaluation>, TuningError> {
        let points = grid_points(&self.problem.params, steps)?;
        let scenarios = self.problem.scenarios.len();
        let mut jobs = Vec::with_capacity(points.len() * scenarios);
        for point in &points {
            for (index, calibration) in self.calibrations.iter().enumerate() {
                jobs.push((self.spec_at(index, point)?, calibration));
            }
        }
        // Each point's metrics as its runs come in; a point is reported once all are there.
        let mut pending: Vec<Vec<Option<Metrics>>> = vec![vec![None; scenarios]; points.len()];
        let mut done = 0;
        let results = parallel_map(
            &jobs,
            self.threads,
            |(spec, calibration)| run_calibrated(spec, (*calibration).clone()),
            |job, result| {
                let (point, scenario) = (job / scenarios, job % scenarios);
                let Ok(metrics) = result else { return };
                pending[point][scenario] = Some(metrics.clone());
                if pending[point].iter().all(Option::is_some) {
                    let metrics = pending[point].iter_mut().filter_map(Option::take).collect();
                    let evaluation = summarise(&self.problem, points[point].clone(), metrics);
                    done += 1;
                    report(&Report::Evaluated {
                        done,
                        total: points.len(),
                        at_most: false,
                        evaluation: &evaluation,
                    });
                }
            },
        );
        let mut results = results.into_iter();
        points
            .into_iter()
            .map(|point| {
                let metrics = results
                    .by_ref()
                    .take(scenarios)
                    .collect::<Result<Vec<Metrics>, _>>()?;
                Ok(summarise(&self.problem, point, metrics))
            })
            .collect()
    }

    /// Minimises the objective with `search` from the controller's current values.
    pub fn tune(&self, search: &NelderMead) -> Result<Tuned, TuningError> {
        self.tune_reporting(search, &mut |_| {})
    }

    /// [`Tuner::tune`], telling `report` after each evaluation.
    ///
    /// The runs go through a [`TuningPlan`] on the tuner's threads: each point's runs at once,
    /// and runs ahead of the search in threads it leaves idle, as the browser's workers make
    /// them; the result does not depend on the threads. A run that fails fails the tuning, with
    /// its scenario named (a run ahead of the search that fails is only made again if the
    /// search asks for its point).
    pub fn tune_reporting(
        &self,
        search: &NelderMead,
        report: &mut dyn FnMut(&Report<'_>),
    ) -> Result<Tuned, TuningError> {
        let mut plan = TuningPlan::new(self.problem.clone(), TuningMode::Search(*search))?;
        let mut failure = None;
        let mut reported = 0;
        crate::work::job_queue(
            self.threads,
            |run: &PlannedRun| {
                run_calibrated(&run.spec, self.calibrations[run.id.scenario].clone())
            },
            |finished, idle| {
                if let Some((run, result)) = finished {
                    match result {
                        Ok(metrics) => plan.tell(run.id, metrics),
                        Err(_) if plan.is_ahead(run.id) => plan.forget(run.id),
                        Err(e) => {
                            failure.get_or_insert(e);
                        }
                    }
                }
                let runs = if failure.is_some() {
                    Vec::new()
                } else {
                    plan.next_runs(idle).unwrap_or_else(|e| {
                        failure = Some(e);
                        Vec::new()
                    })
                };
                // After asking: a point asked now whose runs were all made ahead is evaluated at
                // once, and may be the last.
                while let Some(evaluation) = plan.evaluation(reported) {
                    reported += 1;
                    report(&Report::Evaluated {
                        done: reported,
                        total: search.max_evaluations,
                        at_most: true,
                        evaluation,
                    });
                }
                runs
            },
        );
        match failure {
            Some(e) => Err(e),
            None => plan.finish(),
        }
    }
}

/// Where a search starts: the problem's controller's values of the tuned parameters.
fn start_point(problem: &TuningProblem) -> Vec<f64> {
    problem
        .params
        .iter()
        .map(|r| problem.controller.get(&r.key).unwrap_or(r.lo))
        .collect()
}

/// Scenario `index`'s run definition with `values` set on its own controller.
fn spec_with(
    problem: &TuningProblem,
    index: usize,
    values: &[f64],
) -> Result<RunSpec, TuningError> {
    let mut spec = problem.scenarios[index].clone();
    for (range, &v) in problem.params.iter().zip(values) {
        spec.controller
            .set(&range.key, v)
            .map_err(TuningError::Param)?;
    }
    Ok(spec)
}

/// Every point of the grid with `steps` values per parameter, the first varying slowest.
fn grid_points(params: &[ParamRange], steps: usize) -> Result<Vec<Vec<f64>>, TuningError> {
    let axes: Vec<Vec<f64>> = params
        .iter()
        .map(|r| grid_axis(r.lo, r.hi, steps))
        .collect();
    let total = axes.iter().map(Vec::len).try_fold(1usize, |acc, len| {
        acc.checked_mul(len).filter(|t| *t <= MAX_SWEEP_POINTS)
    });
    let Some(total) = total.filter(|t| *t > 0) else {
        return Err(TuningError::Setup(format!(
            "a sweep of {steps} steps on {} parameters is more than {MAX_SWEEP_POINTS} points",
            axes.len()
        )));
    };
    Ok((0..total)
        .map(|mut index| {
            let mut point = vec![0.0; axes.len()];
            for (slot, axis) in point.iter_mut().zip(&axes).rev() {
                *slot = axis[index % axis.len()];
                index /= axis.len();
            }
            point
        })
        .collect())
}

/// `steps` evenly spaced values from `lo` to `hi` (the middle for one step).
fn grid_axis(lo: f64, hi: f64, steps: usize) -> Vec<f64> {
    match steps {
        0 => Vec::new(),
        1 => vec![0.5 * (lo + hi)],
        // Weighted ends, so both ends and a symmetric middle come out exact.
        _ => (0..steps)
            .map(|i| {
                let t = i as f64 / (steps - 1) as f64;
                lo * (1.0 - t) + hi * t
            })
            .collect(),
    }
}

/// The points no other point beats on both axes (smaller is better on each), by the first
/// axis; points equal on both axes are on the front together (neither beats the other). NaN
/// points are never on the front.
///
/// ```
/// use cutlab::tuning::pareto_front;
/// let points = [(10.0, 5.0), (12.0, 3.0), (11.0, 6.0), (15.0, 1.0), (9.0, f64::NAN), (12.0, 3.0)];
/// assert_eq!(pareto_front(&points), vec![0, 1, 5, 3]);
/// ```
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].0.is_finite() && points[i].1.is_finite())
        .collect();
    order.sort_by(|&a, &b| {
        points[a]
            .0
            .total_cmp(&points[b].0)
            .then(points[a].1.total_cmp(&points[b].1))
    });
    let mut front: Vec<usize> = Vec::new();
    let mut best_second = f64::INFINITY;
    for i in order {
        let tied = front.last().is_some_and(|&last| points[last] == points[i]);
        if points[i].1 < best_second || tied {
            best_second = points[i].1;
            front.push(i);
        }
    }
    front
}

fn calibrate(spec: &RunSpec) -> Result<Calibration, TuningError> {
    crate::closed_loop::lab::teach_cut_only(spec)
        .map(|(_, calibration)| calibration)
        .map_err(|error| TuningError::Run {
            preset: spec.preset.name(),
            error,
        })
}

/// An evaluation's summary: the objective and the means over the scenarios.
fn summarise(problem: &TuningProblem, values: Vec<f64>, metrics: Vec<Metrics>) -> Evaluation {
    let n = metrics.len().max(1) as f64;
    let mean = |f: fn(&Metrics) -> f64| metrics.iter().map(f).sum::<f64>() / n;
    let cost = problem
        .scenarios
        .iter()
        .zip(&metrics)
        .map(|(spec, m)| problem.objective.cost(m, nominal_duration_s(spec)))
        .sum::<f64>()
        / n;
    Evaluation {
        values,
        cost,
        cycle_time_s: mean(|m| m.cycle_time_s),
        force_error_pct: mean(|m| m.force_mean_abs_error_pct),
        time_above_limit_s: mean(|m| m.time_above_limit_s),
        override_activity_pct: mean(|m| m.override_total_variation_pct),
        metrics,
    }
}

fn run_calibrated(spec: &RunSpec, calibration: Calibration) -> Result<Metrics, TuningError> {
    let failed = |error| TuningError::Run {
        preset: spec.preset.name(),
        error,
    };
    let result = LabRun::calibrated(spec, calibration)
        .map_err(failed)?
        .run_to_end()
        .map_err(failed)?;
    Ok(result.metrics)
}

fn nominal_duration_s(spec: &RunSpec) -> f64 {
    spec.preset.summary().nominal_duration_s
}

/// How a [`TuningWork`] chooses its points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TuningMode {
    /// Every point of a grid with this many values per parameter.
    Sweep(usize),
    /// Nelder–Mead from the controller's current values.
    Search(NelderMead),
}

/// Tuning done a piece at a time (for the browser): the teach cuts, then each evaluation's runs,
/// each advanced a budget of control periods at a time. The result is the [`Tuner`]'s.
pub struct TuningWork {
    problem: TuningProblem,
    points: Points,
    calibrations: Vec<Calibration>,
    stage: WorkStage,
    evaluations: Vec<Evaluation>,
    converged: bool,
}

enum Points {
    Grid { points: Vec<Vec<f64>>, next: usize },
    Search(Box<nelder_mead::Search>),
}

impl Points {
    /// The points of `mode` for `problem`.
    fn of(problem: &TuningProblem, mode: TuningMode) -> Result<Self, TuningError> {
        Ok(match mode {
            TuningMode::Sweep(steps) => Points::Grid {
                points: grid_points(&problem.params, steps)?,
                next: 0,
            },
            TuningMode::Search(search) => {
                let bounds: Vec<(f64, f64)> = problem.params.iter().map(|r| (r.lo, r.hi)).collect();
                Points::Search(Box::new(search.search(&bounds, &start_point(problem))))
            }
        })
    }

    /// The next point to evaluate, telling a search the `last` evaluation's cost first; when a
    /// search has none left, whether it converged goes to `converged`.
    fn next(&mut self, last: Option<&Evaluation>, converged: &mut bool) -> Option<Vec<f64>> {
        match self {
            Points::Grid { points, next } => {
                let point = points.get(*next).cloned();
                *next += 1;
                point
            }
            Points::Search(search) => {
                if let Some(last) = last {
                    search.tell(last.cost);
                }
                let point = search.ask();
                if point.is_none() {
                    *converged = search.minimum().converged;
                }
                point
            }
        }
    }

    /// Evaluations in all: the grid's points, or the search's budget.
    fn total(&self) -> usize {
        match self {
            Points::Grid { points, .. } => points.len(),
            Points::Search(search) => search.max_evaluations(),
        }
    }
}

enum WorkStage {
    Teaching(
        Box<crate::closed_loop::sample_loop::OnMachine<crate::closed_loop::teach_cut::TeachCut>>,
    ),
    Evaluating {
        values: Vec<f64>,
        run: Box<LabRun>,
        metrics: Vec<Metrics>,
    },
    Done,
}

impl TuningWork {
    /// Checks the problem and starts the first teach cut.
    pub fn new(problem: TuningProblem, mode: TuningMode) -> Result<Self, TuningError> {
        check(&problem)?;
        let points = Points::of(&problem, mode)?;
        let first = start_teach_cut(&problem, 0)?;
        Ok(Self {
            problem,
            points,
            calibrations: Vec::new(),
            stage: WorkStage::Teaching(first),
            evaluations: Vec::new(),
            converged: false,
        })
    }

    /// The evaluations made so far, for a table that fills in while the work runs.
    pub fn evaluations(&self) -> &[Evaluation] {
        &self.evaluations
    }

    /// The next point to evaluate, telling the search the last evaluation's cost first.
    fn next_point(&mut self) -> Option<Vec<f64>> {
        self.points
            .next(self.evaluations.last(), &mut self.converged)
    }

    /// The run of `values` on scenario `index`, with its teach cut's calibration.
    fn start_run(&self, values: &[f64], index: usize) -> Result<Box<LabRun>, TuningError> {
        let spec = spec_with(&self.problem, index, values)?;
        LabRun::calibrated(&spec, self.calibrations[index].clone())
            .map(Box::new)
            .map_err(|error| TuningError::Run {
                preset: spec.preset.name(),
                error,
            })
    }

    /// Moves on to the next point, or to done.
    fn start_next_point(&mut self) -> Result<(), TuningError> {
        self.stage = match self.next_point() {
            Some(values) => WorkStage::Evaluating {
                run: self.start_run(&values, 0)?,
                values,
                metrics: Vec::new(),
            },
            None => WorkStage::Done,
        };
        Ok(())
    }
}

/// The checks [`Tuner::new`] makes before any run.
fn check(problem: &TuningProblem) -> Result<(), TuningError> {
    if problem.scenarios.is_empty() {
        return Err(TuningError::Setup("name at least one scenario".into()));
    }
    if problem.params.is_empty() {
        return Err(TuningError::Setup(
            "name at least one parameter to tune (key=lo:hi)".into(),
        ));
    }
    let kind = problem.controller.kind();
    if let Some(spec) = problem
        .scenarios
        .iter()
        .find(|s| s.controller.kind() != kind)
    {
        return Err(TuningError::Setup(format!(
            "{} runs {}, not the {} tuned",
            spec.preset.name(),
            spec.controller.kind().name(),
            kind.name()
        )));
    }
    for (i, range) in problem.params.iter().enumerate() {
        if let Some(earlier) = problem.params[..i].iter().find(|r| r.key == range.key) {
            return Err(TuningError::Setup(format!(
                "{} is given twice ({}:{} and {}:{}); give each parameter once",
                range.key, earlier.lo, earlier.hi, range.lo, range.hi
            )));
        }
        // Both ends must be values the controller accepts.
        let mut probe = problem.controller.clone();
        probe
            .set(&range.key, range.lo)
            .map_err(TuningError::Param)?;
        probe
            .set(&range.key, range.hi)
            .map_err(TuningError::Param)?;
    }
    Ok(())
}

fn start_teach_cut(
    problem: &TuningProblem,
    index: usize,
) -> Result<
    Box<crate::closed_loop::sample_loop::OnMachine<crate::closed_loop::teach_cut::TeachCut>>,
    TuningError,
> {
    let spec = &problem.scenarios[index];
    crate::closed_loop::lab::teach_cut_work(spec)
        .map(Box::new)
        .map_err(|error| TuningError::Run {
            preset: spec.preset.name(),
            error,
        })
}

impl Work for TuningWork {
    type Output = Tuned;
    type Error = TuningError;

    /// Advances the current teach cut or run by at most `periods` control periods.
    fn advance(&mut self, periods: usize) -> Result<bool, TuningError> {
        let scenarios = self.problem.scenarios.len();
        match std::mem::replace(&mut self.stage, WorkStage::Done) {
            WorkStage::Done => {}
            WorkStage::Teaching(mut teach) => {
                let preset = self.problem.scenarios[self.calibrations.len()]
                    .preset
                    .name();
                let failed = |error| TuningError::Run { preset, error };
                if !teach.advance(periods).map_err(failed)? {
                    self.stage = WorkStage::Teaching(teach);
                } else {
                    self.calibrations.push(teach.finish().map_err(failed)?);
                    if self.calibrations.len() < scenarios {
                        let next = start_teach_cut(&self.problem, self.calibrations.len())?;
                        self.stage = WorkStage::Teaching(next);
                    } else {
                        self.start_next_point()?;
                    }
                }
            }
            WorkStage::Evaluating {
                values,
                mut run,
                mut metrics,
            } => {
                let preset = self.problem.scenarios[metrics.len()].preset.name();
                let failed = |error| TuningError::Run { preset, error };
                if !run.advance(periods).map_err(failed)? {
                    self.stage = WorkStage::Evaluating {
                        values,
                        run,
                        metrics,
                    };
                } else {
                    metrics.push(run.finish().map_err(failed)?.metrics);
                    if metrics.len() < scenarios {
                        self.stage = WorkStage::Evaluating {
                            run: self.start_run(&values, metrics.len())?,
                            values,
                            metrics,
                        };
                    } else {
                        self.evaluations
                            .push(summarise(&self.problem, values, metrics));
                        self.start_next_point()?;
                    }
                }
            }
        }
        Ok(matches!(self.stage, WorkStage::Done))
    }

    fn progress(&self) -> crate::work::Progress {
        let scenarios = self.problem.scenarios.len().max(1);
        let total = match &self.points {
            Points::Grid { points, .. } => points.len(),
            Points::Search(_) => match self.problem_search_budget() {
                Some(n) => n,
                None => self.evaluations.len() + 1,
            },
        }
        .max(1);
        let (stage, done) = match &self.stage {
            WorkStage::Teaching(_) => (
                format!("Teach cut {} of {scenarios}", self.calibrations.len() + 1),
                0.0,
            ),
            WorkStage::Evaluating { metrics, .. } => (
                format!(
                    "Evaluation {} of {}{total} (scenario {} of {scenarios})",
                    self.evaluations.len() + 1,
                    if matches!(self.points, Points::Search(_)) {
                        "at most "
                    } else {
                        ""
                    },
                    metrics.len() + 1
                ),
                (self.evaluations.len() as f64 + metrics.len() as f64 / scenarios as f64)
                    / total as f64,
            ),
            WorkStage::Done => ("Done".to_string(), 1.0),
        };
        crate::work::Progress::new(stage, done)
    }

    fn finish(&mut self) -> Result<Tuned, TuningError> {
        if !matches!(self.stage, WorkStage::Done) {
            return Err(TuningError::Setup("the tuning has not finished".into()));
        }
        tuned(std::mem::take(&mut self.evaluations), self.converged)
    }
}

/// The outcome of `evaluations` (in the order made): the best, the Pareto front.
fn tuned(evaluations: Vec<Evaluation>, converged: bool) -> Result<Tuned, TuningError> {
    let best = evaluations
        .iter()
        .min_by(|a, b| a.cost.total_cmp(&b.cost))
        .cloned()
        .ok_or_else(|| TuningError::Setup("no evaluation succeeded".into()))?;
    // Judged as the tables print them: two evaluations that read alike are marked alike, not
    // one of them beaten by a thousandth of a second nobody sees.
    let shown = |v: f64| three_significant(v).parse::<f64>().unwrap_or(f64::NAN);
    let pareto = pareto_front(
        &evaluations
            .iter()
            .map(|e| (shown(e.cycle_time_s), shown(e.force_error_pct)))
            .collect::<Vec<_>>(),
    );
    Ok(Tuned {
        best,
        evaluations,
        pareto,
        converged,
    })
}

impl TuningWork {
    fn problem_search_budget(&self) -> Option<usize> {
        match &self.points {
            Points::Search(search) => Some(search.max_evaluations()),
            Points::Grid { .. } => None,
        }
    }
}
