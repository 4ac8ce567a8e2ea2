//! Tuning whose runs are made elsewhere — the browser's computation workers, several at once —
//! and runs made ahead of a search to keep those workers busy.
//!
//! A [`TuningPlan`] asks for runs (one per point and scenario, each calibrated by its scenario's
//! teach cut) and is told their metrics, in any order; its result is [`super::TuningWork`]'s for
//! the same runs. A sweep's points can all be asked at once. A search asks its next point only
//! once the last one's cost is known, which leaves workers idle: a point's scenarios differ in
//! length (kim-step-doc's 75 s cut beside maneerat-doc-1's 13 s), so the worker with the short
//! run waits for the long one. An idle worker therefore runs ahead: a run of a point the search
//! may ask next ([`super::nelder_mead::Search::candidates`], the likeliest first, its longest
//! scenario first). The search itself is told only the costs of the points it asked, so what it
//! asks and finds is the same as without the runs ahead; a point it asks that was run ahead is
//! not run again (the runs are deterministic, so the metrics are those it would have got).
//!
//! ```text
//! next_runs(idle workers) ─► the asked points' runs not yet sent, then runs ahead in idle workers
//! tell(run, metrics)      ─► a point whose runs are all told is evaluated; the search asks on
//! ```

use super::nelder_mead::same_point;
use super::{check, nominal_duration_s, spec_with, summarise, tuned, Points, TuningMode};
use super::{Evaluation, Tuned, TuningError, TuningProblem};
use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::metrics::Metrics;

/// Which run of a plan: a point's number in the plan and a scenario's in the problem.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct RunId {
    /// The point's number in the plan (not the order of the search's evaluations).
    pub point: usize,
    /// The scenario's number in the problem.
    pub scenario: usize,
}

/// A run a [`TuningPlan`] asks for.
#[derive(Debug, Clone)]
pub struct PlannedRun {
    /// What to tell its metrics as.
    pub id: RunId,
    /// Its definition, with the point's values set.
    pub spec: RunSpec,
    /// Run ahead of the search, which may never ask for its point.
    pub ahead: bool,
}

/// Where a run is.
#[derive(Debug, Clone)]
enum RunState {
    /// Not sent.
    Unsent,
    /// Sent ahead of the search and failed: sent again only if the search asks for its point.
    FailedAhead,
    /// Sent, not told; `ahead` if sent ahead of the search.
    Out { ahead: bool },
    /// Told.
    Told { metrics: Box<Metrics>, ahead: bool },
}

/// A point whose runs were asked for: the search's (or the grid's), or one ahead of it.
#[derive(Debug, Clone)]
struct PlannedPoint {
    values: Vec<f64>,
    /// One per scenario, in the problem's order.
    specs: Vec<RunSpec>,
    runs: Vec<RunState>,
}

/// Tuning whose runs are made elsewhere (see the module's documentation).
pub struct TuningPlan {
    problem: TuningProblem,
    points: Points,
    /// Every point whose runs were asked for, the search's and those ahead of it.
    planned: Vec<PlannedPoint>,
    /// The points the search (or the grid) asked, in its order: each one's number in `planned`
    /// and its evaluation once all its runs are told.
    asked: Vec<(usize, Option<Evaluation>)>,
    /// The scenarios' numbers, longest program first: the order a point's runs are sent in
    /// (the one the others wait for first).
    longest_first: Vec<usize>,
    /// No point is left to ask.
    exhausted: bool,
    converged: bool,
}

impl TuningPlan {
    /// Checks the problem; nothing is asked yet.
    pub fn new(problem: TuningProblem, mode: TuningMode) -> Result<Self, TuningError> {
        check(&problem)?;
        let points = Points::of(&problem, mode)?;
        let durations: Vec<f64> = problem.scenarios.iter().map(nominal_duration_s).collect();
        let mut longest_first: Vec<usize> = (0..durations.len()).collect();
        longest_first.sort_by(|&a, &b| durations[b].total_cmp(&durations[a]));
        Ok(Self {
            problem,
            points,
            planned: Vec::new(),
            asked: Vec::new(),
            longest_first,
            exhausted: false,
            converged: false,
        })
    }

    /// The runs to send now, each marked sent: first every asked point's runs not yet sent
    /// (however many workers are idle), then, for a search, runs ahead of it to fill the rest of
    /// `idle_workers`.
    ///
    /// The first point's runs make the scenarios' teach cuts: until each scenario has a run told,
    /// nothing more is asked, so no other run makes a teach cut again.
    pub fn next_runs(&mut self, idle_workers: usize) -> Result<Vec<PlannedRun>, TuningError> {
        self.ask_points()?;
        let mut runs = Vec::new();
        for &(index, _) in &self.asked {
            send_unsent(
                &mut self.planned[index],
                index,
                &self.longest_first,
                false,
                usize::MAX,
                &mut runs,
            );
        }
        let mut spare = idle_workers.saturating_sub(runs.len());
        if spare == 0 || !self.taught() {
            return Ok(runs);
        }
        let Points::Search(search) = &self.points else {
            return Ok(runs);
        };
        for values in search.candidates() {
            if spare == 0 {
                break;
            }
            // A point the problem cannot set (a value its controller refuses) is not run ahead:
            // if the search asks for it, its error comes then.
            let Some(index) = self.plan_point(values).ok() else {
                continue;
            };
            spare -= send_unsent(
                &mut self.planned[index],
                index,
                &self.longest_first,
                true,
                spare,
                &mut runs,
            );
        }
        Ok(runs)
    }

    /// The metrics of run `run` (a run not sent, or told before, changes nothing).
    pub fn tell(&mut self, run: RunId, metrics: Metrics) {
        let Some(state) = self
            .planned
            .get_mut(run.point)
            .and_then(|p| p.runs.get_mut(run.scenario))
        else {
            return;
        };
        if let RunState::Out { ahead } = *state {
            *state = RunState::Told {
                metrics: Box::new(metrics),
                ahead,
            };
        }
        self.evaluate_told();
    }

    /// Takes back run `run`, sent and not told, which failed ahead of the search: it is not
    /// run ahead again, and is sent again if the search asks for its point.
    pub fn forget(&mut self, run: RunId) {
        if let Some(state) = self
            .planned
            .get_mut(run.point)
            .and_then(|p| p.runs.get_mut(run.scenario))
        {
            if matches!(state, RunState::Out { .. }) {
                *state = RunState::FailedAhead;
            }
        }
    }

    /// Whether `run`'s point has not been asked by the search (so far): it was sent ahead, and
    /// its failure is not the tuning's.
    pub fn is_ahead(&self, run: RunId) -> bool {
        !self.asked.iter().any(|(i, _)| *i == run.point)
    }

    /// Runs told that were sent ahead of the search: how many, and how many of them the search
    /// used (their point asked afterwards).
    pub fn runs_ahead(&self) -> (usize, usize) {
        let mut made = 0;
        let mut used = 0;
        for (index, point) in self.planned.iter().enumerate() {
            let told_ahead = point
                .runs
                .iter()
                .filter(|s| matches!(s, RunState::Told { ahead: true, .. }))
                .count();
            made += told_ahead;
            if self.asked.iter().any(|(i, _)| *i == index) {
                used += told_ahead;
            }
        }
        (made, used)
    }

    /// The `index`-th evaluation of the search (or grid), in its order, once all its runs are
    /// told.
    pub fn evaluation(&self, index: usize) -> Option<&Evaluation> {
        self.asked.get(index).and_then(|(_, e)| e.as_ref())
    }

    /// Evaluations done and evaluations in all (the grid's points, or the search's budget).
    pub fn count(&self) -> (usize, usize) {
        let done = self.asked.iter().filter(|(_, e)| e.is_some()).count();
        (done, self.points.total())
    }

    /// Whether every point has been asked and told.
    pub fn is_done(&self) -> bool {
        self.exhausted && self.asked.iter().all(|(_, e)| e.is_some())
    }

    /// The outcome, once [`TuningPlan::is_done`].
    pub fn finish(&mut self) -> Result<Tuned, TuningError> {
        if !self.is_done() {
            return Err(TuningError::Setup("the tuning has not finished".into()));
        }
        let evaluations = std::mem::take(&mut self.asked)
            .into_iter()
            .filter_map(|(_, e)| e);
        tuned(evaluations.collect(), self.converged)
    }

    /// Whether every scenario has a run told, so its teach cut's calibration is known.
    fn taught(&self) -> bool {
        (0..self.problem.scenarios.len()).all(|scenario| {
            self.planned
                .iter()
                .any(|p| matches!(p.runs[scenario], RunState::Told { .. }))
        })
    }

    /// Asks the points the search or grid can give now: a search's next once the last one is
    /// evaluated (and the next after it, if its runs were all told ahead), every grid point; only
    /// the first point until the teach cuts are known.
    fn ask_points(&mut self) -> Result<(), TuningError> {
        while !self.exhausted {
            let waiting = self.asked.iter().any(|(_, e)| e.is_none());
            let one_at_a_time = matches!(self.points, Points::Search(_)) || !self.taught();
            if (waiting && one_at_a_time) || (!self.asked.is_empty() && !self.taught()) {
                return Ok(());
            }
            let last = self.asked.last().and_then(|(_, e)| e.as_ref());
            let Some(values) = self.points.next(last, &mut self.converged) else {
                self.exhausted = true;
                return Ok(());
            };
            let index = self.plan_point(values)?;
            self.asked.push((index, None));
            self.evaluate_told();
        }
        Ok(())
    }

    /// The number of the planned point at `values` (bit for bit), planned now if it is new.
    fn plan_point(&mut self, values: Vec<f64>) -> Result<usize, TuningError> {
        if let Some(index) = self
            .planned
            .iter()
            .position(|p| same_point(&p.values, &values))
        {
            return Ok(index);
        }
        let specs = (0..self.problem.scenarios.len())
            .map(|i| spec_with(&self.problem, i, &values))
            .collect::<Result<Vec<_>, _>>()?;
        self.planned.push(PlannedPoint {
            runs: vec![RunState::Unsent; specs.len()],
            values,
            specs,
        });
        Ok(self.planned.len() - 1)
    }

    /// Evaluates every asked point whose runs are all told.
    fn evaluate_told(&mut self) {
        for (index, evaluation) in &mut self.asked {
            if evaluation.is_some() {
                continue;
            }
            let point = &self.planned[*index];
            let metrics: Option<Vec<Metrics>> = point
                .runs
                .iter()
                .map(|state| match state {
                    RunState::Told { metrics, .. } => Some(metrics.as_ref().clone()),
                    _ => None,
                })
                .collect();
            if let Some(metrics) = metrics {
                *evaluation = Some(summarise(&self.problem, point.values.clone(), metrics));
            }
        }
    }
}

/// Marks at most `limit` of `point`'s unsent runs sent, in the scenario order `order`, and adds
/// them to `runs`; returns how many.
fn send_unsent(
    point: &mut PlannedPoint,
    index: usize,
    order: &[usize],
    ahead: bool,
    limit: usize,
    runs: &mut Vec<PlannedRun>,
) -> usize {
    let mut sent = 0;
    for &scenario in order {
        if sent == limit {
            break;
        }
        let sendable = match point.runs[scenario] {
            RunState::Unsent => true,
            RunState::FailedAhead => !ahead,
            RunState::Out { .. } | RunState::Told { .. } => false,
        };
        if sendable {
            point.runs[scenario] = RunState::Out { ahead };
            runs.push(PlannedRun {
                id: RunId {
                    point: index,
                    scenario,
                },
                spec: point.specs[scenario].clone(),
                ahead,
            });
            sent += 1;
        }
    }
    sent
}
