//! A step's work done without a browser: the runs its setup defines, simulated to the end
//! ([`simulate`]), the filter it designs, or the replays its Logs link starts on a sample log. What
//! `cutlab lesson check` and the tests use to show that a step's reference solution meets its
//! check and its starting point does not.

use super::check::{ConditionOutcome, Evidence};
use super::setup::{Defined, Setup};
use super::{Lesson, StepCheck};
use crate::closed_loop::lab::{simulate, RunResult};
use crate::log::link::LogsLink;
use crate::log::replay::ReplayResult;
use crate::work::Work;

use std::sync::Arc;

/// The replays a Logs link's form starts on its sample log, read from `www/data` (built in),
/// through the page's own [`crate::log::replay::ReplayRuns`].
fn replay(link: &LogsLink) -> Result<Vec<Arc<ReplayResult>>, String> {
    let file = link
        .sample
        .ok_or("a replay is checked on a sample log: give the link a sample")?;
    let bytes = crate::log::link::sample_bytes(file)
        .ok_or_else(|| format!("{file}: not built into this program"))?;
    let log =
        crate::log::load(bytes, link.sample_period_s()).map_err(|e| format!("{file}: {e}"))?;
    link.replay_runs(Arc::new(log))?
        .run_to_end()
        .map_err(|e| format!("{file}: {e}"))
}

/// Checks steps on the simulated lab.
#[derive(Default)]
pub struct Checker;

/// A step's check done on one setup: each condition's outcome.
#[derive(Debug, Clone, PartialEq)]
pub struct StepOutcome {
    /// The step, from 0.
    pub step: usize,
    /// Each condition's outcome, in order.
    pub outcomes: Vec<ConditionOutcome>,
}

impl StepOutcome {
    /// Whether every condition is met.
    pub fn met(&self) -> bool {
        self.outcomes.iter().all(|o| o.met)
    }
}

impl Checker {
    /// A checker.
    pub fn new() -> Self {
        Self
    }

    /// The outcomes of step `step` of `lesson` on `setup`'s work (the step's starting point,
    /// its solution, or what a student did); `None` for a multiple-choice step.
    pub fn check_step(
        &self,
        lesson: &Lesson,
        step: usize,
        setup: &Setup,
    ) -> Result<Option<StepOutcome>, String> {
        let Some(StepCheck::Conditions { conditions, .. }) =
            lesson.steps.get(step).map(|s| &s.check)
        else {
            return Ok(None);
        };
        let outcomes = match setup.define()? {
            Defined::Runs(specs) => {
                let runs = specs
                    .iter()
                    .map(|spec| simulate(spec).map_err(|e| e.to_string()))
                    .collect::<Result<Vec<RunResult>, String>>()?;
                let runs: Vec<&RunResult> = runs.iter().collect();
                conditions
                    .iter()
                    .map(|c| c.evaluate(Evidence::Runs(&runs)))
                    .collect()
            }
            Defined::Design(spec, sos) => conditions
                .iter()
                .map(|c| {
                    c.evaluate(Evidence::Design {
                        spec: &spec,
                        sos: &sos,
                    })
                })
                .collect(),
            Defined::Logs(link) => {
                let replays = replay(&link)?;
                let replays: Vec<&ReplayResult> = replays.iter().map(Arc::as_ref).collect();
                conditions
                    .iter()
                    .map(|c| c.evaluate(Evidence::Replays(&replays)))
                    .collect()
            }
            Defined::Nothing => {
                return Err(format!(
                    "the {} page has no work a condition can check",
                    setup.page.slug()
                ))
            }
        };
        Ok(Some(StepOutcome { step, outcomes }))
    }
}
