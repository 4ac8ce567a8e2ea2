//! Tune's evaluations in the computation workers: every run of an evaluation (one per scenario)
//! is a job of its own, so the scenarios of a search's point, or a sweep's points, compute at
//! once on different workers. The first point's runs make their scenarios' teach cuts; every
//! later run starts from those calibrations, as the page's own [`crate::tuning::TuningWork`]
//! did, and the result is the same ([`TuningPlan`]).

use std::cell::RefCell;
use std::rc::Rc;

use leptos::prelude::Set;

use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::lab::TeachKey;
use crate::closed_loop::transfer::{JobRequest, RunRequest};
use crate::estimation::estimator::Calibration;
use crate::tuning::{Tuned, TuningPlan};
use crate::web::components::pool::{self, Answer, JobEvent};
use crate::web::components::runner::{next_task, RunStatus, Runner};

/// Where a tuning in the workers is.
struct Tuning {
    plan: TuningPlan,
    /// The scenarios' teach cuts, by key: those of the first point's runs.
    teach_keys: Vec<TeachKey>,
    known: Vec<(TeachKey, Calibration)>,
    /// Runs sent and not yet answered.
    out: usize,
    /// Whether a search asks at most its budget ("at most") or a grid's points.
    at_most: bool,
}

/// Starts `plan` in the workers on `runner`, replacing anything it runs; `teach_keys` are the
/// scenarios' teach cuts; `at_most` says the plan is a search (which may stop before its
/// budget).
pub fn start_tuning(
    runner: &Runner<Tuned>,
    plan: TuningPlan,
    teach_keys: Vec<TeachKey>,
    at_most: bool,
) {
    let current = runner.begin_in_workers();
    let tuning = Rc::new(RefCell::new(Tuning {
        plan,
        teach_keys,
        known: Vec::new(),
        out: 0,
        at_most,
    }));
    show_progress(runner, &tuning.borrow());
    send_ready(runner, &tuning, &current);
}

/// The status while the evaluations run: how many are done, of how many.
fn show_progress(runner: &Runner<Tuned>, tuning: &Tuning) {
    let (done, total) = tuning.plan.count();
    let stage = format!(
        "Evaluation {} of {}{total} (runs on {} workers)",
        (done + 1).min(total),
        if tuning.at_most { "at most " } else { "" },
        pool::pool_size(),
    );
    let _ = runner.status.try_set(RunStatus::Running {
        stage,
        fraction: done as f64 / total.max(1) as f64,
    });
}

/// Sends the runs of every point the plan can ask now (after the first point, only once its
/// teach cuts are known, so no run makes one again); publishes the outcome once all are done.
fn send_ready(
    runner: &Runner<Tuned>,
    tuning: &Rc<RefCell<Tuning>>,
    current: &(impl Fn() -> bool + Clone + 'static),
) {
    let mut sends: Vec<(usize, usize, RunSpec)> = Vec::new();
    let asked = {
        let mut t = tuning.borrow_mut();
        let mut asked = Ok(());
        loop {
            let taught = t
                .teach_keys
                .iter()
                .all(|key| t.known.iter().any(|(k, _)| k == key));
            let idle = t.out == 0 && sends.is_empty();
            if !idle && !taught {
                break;
            }
            match t.plan.ask() {
                Ok(Some((point, specs))) => {
                    sends.extend(specs.into_iter().enumerate().map(|(i, s)| (point, i, s)));
                }
                Ok(None) => break,
                Err(e) => {
                    asked = Err(e.to_string());
                    break;
                }
            }
        }
        t.out += sends.len();
        asked
    };
    if let Err(message) = asked {
        runner.cancel();
        let _ = runner.status.try_set(RunStatus::Failed(message));
        return;
    }
    for (point, scenario, spec) in sends {
        let known = tuning.borrow().known.clone();
        let request = JobRequest::Runs(RunRequest::new(vec![spec], &known));
        let (runner_in, tuning, current) = (runner.clone(), tuning.clone(), current.clone());
        let job = pool::submit(request, move |event| {
            if !current() {
                return;
            }
            match event {
                JobEvent::Progress(_) | JobEvent::Chunk(_) => {}
                JobEvent::Done(Answer::Runs(mut runs)) if runs.len() == 1 => {
                    let run = runs.remove(0);
                    {
                        let mut t = tuning.borrow_mut();
                        t.out = t.out.saturating_sub(1);
                        if let Ok(key) = TeachKey::of(&run.spec) {
                            if !t.known.iter().any(|(k, _)| *k == key) {
                                t.known.push((key, run.calibration.clone()));
                            }
                        }
                        t.plan.tell(point, scenario, run.metrics.clone());
                    }
                    show_progress(&runner_in, &tuning.borrow());
                    send_ready(&runner_in, &tuning, &current);
                }
                JobEvent::Done(_) => {
                    runner_in.cancel();
                    let _ = runner_in.status.try_set(RunStatus::Failed(
                        "the computation worker answered another job than the one asked".into(),
                    ));
                }
                JobEvent::Failed(message) => {
                    runner_in.cancel();
                    let _ = runner_in.status.try_set(RunStatus::Failed(message));
                }
            }
        });
        runner.track(job);
    }
    let done = {
        let t = tuning.borrow();
        t.out == 0 && t.plan.is_done()
    };
    if done {
        let outcome = tuning.borrow_mut().plan.finish();
        let status = runner.status;
        let current = current.clone();
        // The redraw of the results runs in a task of its own.
        next_task(move || {
            if current() {
                let _ = status.try_set(match outcome {
                    Ok(tuned) => RunStatus::Done(tuned),
                    Err(e) => RunStatus::Failed(e.to_string()),
                });
            }
        });
    }
}
