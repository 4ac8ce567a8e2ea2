//! Tuning: a controller's parameters chosen by sweeping a grid or by minimising an objective over
//! several scenarios.
//!
//! ```text
//! TuningProblem (controller, 1–n parameter ranges, scenarios, objective)
//!   ├─ sweep(steps)   every grid point on every scenario          → Vec<Evaluation>
//!   └─ tune(search)   Nelder–Mead in the parameters' box          → Tuned { best, evaluations, pareto }
//! Evaluation = the parameters, each scenario's metrics, their objective, the mean cycle time and
//!              force error (the two axes of the Pareto front)
//! ```
//!
//! Every evaluation runs the same closed loop as Simulate ([`crate::closed_loop::lab`]); each
//! scenario's teach cut runs once and its calibration is reused for every parameter set, since it
//! does not depend on the controller. Natively the scenarios of one evaluation, and the points of
//! a sweep, run on all cores; the results do not depend on how many.

pub mod nelder_mead;
pub mod objective;

use serde::Serialize;

use crate::closed_loop::lab::{LabRun, RunSpec};
use crate::closed_loop::metrics::Metrics;
use crate::closed_loop::runner::{Calibration, LoopError};
use crate::control::registry::{ControllerConfig, ParamError};
use crate::work::Work;
use nelder_mead::NelderMead;
pub use objective::Objective;

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
    /// Parses `key=lo:hi`, as typed on the command line.
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
        let number =
            |s: &str| crate::input::parse_number(s).map_err(|e| format!("{}: {e}", key.trim()));
        let (lo, hi) = (number(lo)?, number(hi)?);
        if lo > hi {
            return Err(format!(
                "{}: the lower bound {lo} is above the upper {hi}",
                key.trim()
            ));
        }
        Ok(Self {
            key: key.trim().to_string(),
            lo,
            hi,
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
}

impl std::fmt::Display for TuningError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TuningError::Param(e) => write!(f, "{e}"),
            TuningError::Setup(message) => f.write_str(message),
            TuningError::Run { preset, error } => write!(f, "{preset}: {error}"),
        }
    }
}

impl std::error::Error for TuningError {}

/// The largest grid a sweep runs (points × scenarios are full closed-loop runs).
pub const MAX_SWEEP_POINTS: usize = 400;

/// What to tune, where, and by what measure.
#[derive(Debug, Clone)]
pub struct TuningProblem {
    /// The controller with every parameter not tuned at its chosen value.
    pub controller: ControllerConfig,
    /// The parameters tuned, each within its range.
    pub params: Vec<ParamRange>,
    /// The scenarios, each a run definition (its own controller is replaced).
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

/// Runs evaluations of a problem, reusing each scenario's teach cut.
pub struct Tuner {
    problem: TuningProblem,
    calibrations: Vec<Calibration>,
}

impl Tuner {
    /// Checks the problem and runs each scenario's teach cut once.
    pub fn new(problem: TuningProblem) -> Result<Self, TuningError> {
        check(&problem)?;
        let calibrations = parallel_map(&problem.scenarios, |spec| {
            let mut spec = spec.clone();
            spec.controller = problem.controller.clone();
            calibrate(&spec)
        })
        .into_iter()
        .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            problem,
            calibrations,
        })
    }

    /// The problem.
    pub fn problem(&self) -> &TuningProblem {
        &self.problem
    }

    /// Runs `values` (one per tuned parameter) on every scenario.
    pub fn evaluate(&self, values: &[f64]) -> Result<Evaluation, TuningError> {
        let mut controller = self.problem.controller.clone();
        for (range, &v) in self.problem.params.iter().zip(values) {
            controller.set(&range.key, v).map_err(TuningError::Param)?;
        }
        let jobs: Vec<(&RunSpec, &Calibration)> = self
            .problem
            .scenarios
            .iter()
            .zip(&self.calibrations)
            .collect();
        let metrics = parallel_map(&jobs, |(spec, calibration)| {
            let mut spec = (*spec).clone();
            spec.controller = controller.clone();
            run_calibrated(&spec, (*calibration).clone())
        })
        .into_iter()
        .collect::<Result<Vec<Metrics>, _>>()?;
        Ok(summarise(&self.problem, values.to_vec(), metrics))
    }

    /// Every point of the grid with `steps` values per parameter (lo … hi evenly, both ends
    /// included; one step takes the middle), the first parameter varying slowest.
    ///
    /// The grid's points run in parallel natively; the result is in grid order either way.
    pub fn sweep(&self, steps: usize) -> Result<Vec<Evaluation>, TuningError> {
        // The scenarios of each point already run in parallel: points go one at a time.
        grid_points(&self.problem.params, steps)?
            .iter()
            .map(|p| self.evaluate(p))
            .collect()
    }

    /// Minimises the objective with `search` from the controller's current values.
    pub fn tune(&self, search: &NelderMead) -> Result<Tuned, TuningError> {
        let bounds: Vec<(f64, f64)> = self.problem.params.iter().map(|r| (r.lo, r.hi)).collect();
        let start: Vec<f64> = self
            .problem
            .params
            .iter()
            .map(|r| self.problem.controller.get(&r.key).unwrap_or(r.lo))
            .collect();
        let mut evaluations = Vec::new();
        let mut failure = None;
        let minimum = search.minimize(
            |values| match self.evaluate(values) {
                Ok(e) => {
                    let cost = e.cost;
                    evaluations.push(e);
                    cost
                }
                Err(e) => {
                    failure.get_or_insert(e);
                    f64::INFINITY
                }
            },
            &bounds,
            &start,
        );
        if let Some(e) = failure.filter(|_| evaluations.is_empty()) {
            return Err(e);
        }
        let best = evaluations
            .iter()
            .min_by(|a, b| a.cost.total_cmp(&b.cost))
            .cloned()
            .ok_or_else(|| TuningError::Setup("no evaluation succeeded".into()))?;
        let pareto = pareto_front(
            &evaluations
                .iter()
                .map(|e| (e.cycle_time_s, e.force_error_pct))
                .collect::<Vec<_>>(),
        );
        Ok(Tuned {
            best,
            evaluations,
            pareto,
            converged: minimum.converged,
        })
    }
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
/// axis; ties keep the first. NaN points are never on the front.
///
/// ```
/// use cutlab::tuning::pareto_front;
/// let points = [(10.0, 5.0), (12.0, 3.0), (11.0, 6.0), (15.0, 1.0), (9.0, f64::NAN)];
/// assert_eq!(pareto_front(&points), vec![0, 1, 3]);
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
    let mut front = Vec::new();
    let mut best_second = f64::INFINITY;
    for i in order {
        if points[i].1 < best_second {
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
        cycle_time_s: metrics.iter().map(|m| m.cycle_time_s).sum::<f64>() / n,
        force_error_pct: metrics
            .iter()
            .map(|m| m.force_mean_abs_error_pct)
            .sum::<f64>()
            / n,
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

/// `f` over `items` on every core natively, in order in wasm ([`crate::work::parallel_map`]).
fn parallel_map<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    crate::work::parallel_map(items, f)
}

/// What a teach-in learns from one teach cut, and the settings it proposes (as commercial
/// adaptive feed controls do: cut once at known overrides, then start from what was measured).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TeachIn {
    /// The preset taught.
    pub preset: &'static str,
    /// The calibrated estimator and what the teach cut saw.
    pub calibration: Calibration,
    /// The median force of the teach cut at 100 % override.
    pub force_at_full_override_n: f64,
    /// The force to hold: the paper's target where the preset has one, else 80 % of the force
    /// at 100 % override.
    pub proposed_target_n: f64,
    /// The current the calibrated model expects at that force and the program's speed: the
    /// reference current to hold, as papers 000, 002 and 003 state their targets (NaN with a
    /// dynamometer).
    pub reference_current_a: f64,
    /// The spread of one period's force estimate about the calibration line (1 σ).
    pub estimate_noise_n: f64,
    /// A threshold gap (% of target) wide enough that estimate noise alone does not cross it:
    /// ±3 σ, at least [`MIN_PROPOSED_GAP_PCT`].
    pub proposed_gap_pct: f64,
}

/// The narrowest threshold gap a teach-in proposes, % of target.
pub const MIN_PROPOSED_GAP_PCT: f64 = 5.0;

/// Runs `spec`'s teach cut and proposes a target, its reference current and a threshold gap.
///
/// ```
/// use cutlab::closed_loop::lab::RunSpec;
/// use cutlab::control::registry::ControllerKind;
/// use cutlab::plant::Preset;
/// let t = cutlab::tuning::teach_in(&RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Threshold))
///     .unwrap();
/// assert_eq!(t.proposed_target_n, 150.0); // paper 001's own target
/// assert!(t.reference_current_a > 0.0 && t.proposed_gap_pct >= 5.0);
/// ```
pub fn teach_in(spec: &RunSpec) -> Result<TeachIn, TuningError> {
    let (_, calibration) =
        crate::closed_loop::lab::teach_cut_only(spec).map_err(|error| TuningError::Run {
            preset: spec.preset.name(),
            error,
        })?;
    propose(spec, calibration)
}

/// What a teach-in proposes from `spec`'s teach-cut `calibration`.
fn propose(spec: &RunSpec, calibration: Calibration) -> Result<TeachIn, TuningError> {
    let settings =
        crate::closed_loop::lab::settled_settings(spec, &calibration).map_err(|error| {
            TuningError::Run {
                preset: spec.preset.name(),
                error,
            }
        })?;
    let summary = spec.preset.summary();
    let rpm = summary.spindle_rpm.unwrap_or(0.0);
    let feed = summary.programmed_feed_mm_min.unwrap_or(0.0);
    let target = settings.target_force_n;
    let estimate_noise_n = calibration.estimator.residual_std_n(rpm);
    let reference_current_a = calibration.estimator.current_for_force_a(target, rpm, feed);
    let gap = if target > 0.0 && estimate_noise_n.is_finite() {
        (600.0 * estimate_noise_n / target).max(MIN_PROPOSED_GAP_PCT)
    } else {
        MIN_PROPOSED_GAP_PCT
    };
    Ok(TeachIn {
        preset: spec.preset.name(),
        force_at_full_override_n: calibration.median_force_at_full_override_n,
        calibration,
        proposed_target_n: target,
        reference_current_a,
        estimate_noise_n,
        proposed_gap_pct: gap,
    })
}

/// A teach-in of several scenarios done a piece at a time (for the browser).
pub struct TeachInWork {
    specs: Vec<RunSpec>,
    current:
        Option<Box<crate::closed_loop::runner::OnMachine<crate::closed_loop::runner::TeachCut>>>,
    taught: Vec<TeachIn>,
}

impl TeachInWork {
    /// The teach-ins of `specs`, in order.
    pub fn new(specs: Vec<RunSpec>) -> Self {
        Self {
            specs,
            current: None,
            taught: Vec::new(),
        }
    }
}

impl Work for TeachInWork {
    type Output = Vec<TeachIn>;
    type Error = TuningError;

    fn advance(&mut self, periods: usize) -> Result<bool, TuningError> {
        let Some(spec) = self.specs.get(self.taught.len()) else {
            return Ok(true);
        };
        let failed = |error| TuningError::Run {
            preset: spec.preset.name(),
            error,
        };
        let teach = match &mut self.current {
            Some(teach) => teach,
            None => self.current.insert(Box::new(
                crate::closed_loop::lab::teach_cut_work(spec).map_err(failed)?,
            )),
        };
        if teach.advance(periods).map_err(failed)? {
            let calibration = teach.finish().map_err(failed)?;
            self.current = None;
            self.taught.push(propose(spec, calibration)?);
        }
        Ok(self.taught.len() >= self.specs.len())
    }

    fn progress(&self) -> crate::work::Progress {
        let total = self.specs.len().max(1);
        let part = self.current.as_ref().map_or(0.0, |t| t.progress().fraction);
        crate::work::Progress::new(
            format!(
                "Teach cut {} of {total}",
                (self.taught.len() + 1).min(total)
            ),
            (self.taught.len() as f64 + part) / total as f64,
        )
    }

    fn finish(&mut self) -> Result<Vec<TeachIn>, TuningError> {
        if self.taught.len() < self.specs.len() {
            return Err(TuningError::Setup("the teach-in has not finished".into()));
        }
        Ok(std::mem::take(&mut self.taught))
    }
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
    Search(nelder_mead::Search),
}

enum WorkStage {
    Teaching(Box<crate::closed_loop::runner::OnMachine<crate::closed_loop::runner::TeachCut>>),
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
        let points = match mode {
            TuningMode::Sweep(steps) => Points::Grid {
                points: grid_points(&problem.params, steps)?,
                next: 0,
            },
            TuningMode::Search(search) => {
                let bounds: Vec<(f64, f64)> = problem.params.iter().map(|r| (r.lo, r.hi)).collect();
                let start: Vec<f64> = problem
                    .params
                    .iter()
                    .map(|r| problem.controller.get(&r.key).unwrap_or(r.lo))
                    .collect();
                Points::Search(search.search(&bounds, &start))
            }
        };
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
        match &mut self.points {
            Points::Grid { points, next } => {
                let point = points.get(*next).cloned();
                *next += 1;
                point
            }
            Points::Search(search) => {
                if let Some(last) = self.evaluations.last() {
                    search.tell(last.cost);
                }
                let point = search.ask();
                if point.is_none() {
                    self.converged = search.minimum().converged;
                }
                point
            }
        }
    }

    /// The run of `values` on scenario `index`, with its teach cut's calibration.
    fn start_run(&self, values: &[f64], index: usize) -> Result<Box<LabRun>, TuningError> {
        let mut spec = self.problem.scenarios[index].clone();
        spec.controller = self.problem.controller.clone();
        for (range, &v) in self.problem.params.iter().zip(values) {
            spec.controller
                .set(&range.key, v)
                .map_err(TuningError::Param)?;
        }
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
    for range in &problem.params {
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
    Box<crate::closed_loop::runner::OnMachine<crate::closed_loop::runner::TeachCut>>,
    TuningError,
> {
    let mut spec = problem.scenarios[index].clone();
    spec.controller = problem.controller.clone();
    crate::closed_loop::lab::teach_cut_work(&spec)
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
        let best = self
            .evaluations
            .iter()
            .min_by(|a, b| a.cost.total_cmp(&b.cost))
            .cloned()
            .ok_or_else(|| TuningError::Setup("no evaluation succeeded".into()))?;
        let pareto = pareto_front(
            &self
                .evaluations
                .iter()
                .map(|e| (e.cycle_time_s, e.force_error_pct))
                .collect::<Vec<_>>(),
        );
        Ok(Tuned {
            best,
            evaluations: std::mem::take(&mut self.evaluations),
            pareto,
            converged: self.converged,
        })
    }
}

impl TuningWork {
    fn problem_search_budget(&self) -> Option<usize> {
        match &self.points {
            Points::Search(search) => Some(search.max_evaluations()),
            Points::Grid { .. } => None,
        }
    }
}
