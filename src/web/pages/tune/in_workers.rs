//! Tune's evaluations in the computation workers: every run of an evaluation (one per scenario)
//! is a job of its own, so the scenarios of a search's point, or a sweep's points, compute at
//! once on different workers, and a worker a search leaves idle runs ahead of it
//! ([`crate::tuning::plan`]). The first point's runs make their scenarios' teach cuts; every
//! later run starts from those calibrations, as the page's own [`crate::tuning::TuningWork`]
//! did, and the result is the same ([`TuningPlan`]).

use std::cell::RefCell;
use std::rc::Rc;

use leptos::prelude::Set;

use crate::closed_loop::lab::TeachKey;
use crate::closed_loop::transfer::{JobRequest, RunRequest};
use crate::estimation::estimator::Calibration;
use crate::tuning::{PlannedRun, RunId, Tuned, TuningPlan};
use crate::web::components::pool::{self, Answer, JobEvent, JobId};
use crate::web::components::runner::{next_task, RunStatus, Runner, ANOTHER_ANSWER};

/// Where a tuning in the workers is.
struct Tuning {
    plan: TuningPlan,
    /// The scenarios' teach cuts, by key: those of the first point's runs.
    known: Vec<(TeachKey, Calibration)>,
    /// The runs sent and not yet answered, with their jobs.
    out: Vec<(RunId, JobId)>,
    /// The outcome has been published: answers still coming (runs ahead) change nothing.
    published: bool,
    /// Whether a search asks at most its budget ("at most") or a grid's points.
    at_most: bool,
}

/// Starts `plan` in the workers on `runner`, replacing anything it runs; `at_most` says the plan
/// is a search (which may stop before its budget).
pub fn start_tuning(runner: &Runner<Tuned>, plan: TuningPlan, at_most: bool) {
    let current = runner.begin_in_workers();
    let tuning = Rc::new(RefCell::new(Tuning {
        plan,
        known: Vec::new(),
        out: Vec::new(),
        published: false,
        at_most,
    }));
    show_progress(runner, &tuning.borrow());
    send_ready(runner, &tuning, &current);
}

/// The status while the evaluations run: how many are done, of how many, and how many of the
/// runs made ahead of a search it used.
fn show_progress(runner: &Runner<Tuned>, tuning: &Tuning) {
    let (done, total) = tuning.plan.count();
    let (made_ahead, used) = tuning.plan.runs_ahead();
    let ahead = if made_ahead > 0 {
        format!("; {used} of {made_ahead} runs made ahead of the search used")
    } else {
        String::new()
    };
    let stage = format!(
        "Evaluation {} of {}{total} (runs on {} workers{ahead})",
        (done + 1).min(total),
        if tuning.at_most { "at most " } else { "" },
        pool::pool_size(),
    );
    let _ = runner.status.try_set(RunStatus::Running {
        stage,
        fraction: done as f64 / total.max(1) as f64,
    });
}

/// Sends the runs the plan asks for now: every asked point's, then runs ahead of a search in
/// the workers left idle. A run ahead that the search no longer needs is left to finish (it may
/// be asked later): cancelling it would restart its worker, which costs more than the short
/// wait of the runs queued behind it. Publishes the outcome once every point asked is
/// evaluated.
fn send_ready(
    runner: &Runner<Tuned>,
    tuning: &Rc<RefCell<Tuning>>,
    current: &(impl Fn() -> bool + Clone + 'static),
) {
    let asked = {
        let mut t = tuning.borrow_mut();
        let idle = pool::pool_size().saturating_sub(t.out.len());
        t.plan.next_runs(idle)
    };
    let runs = match asked {
        Ok(runs) => runs,
        Err(e) => {
            runner.cancel();
            let _ = runner.status.try_set(RunStatus::Failed(e.to_string()));
            return;
        }
    };
    for run in runs {
        send(runner, tuning, current, run);
    }
    // Done once every point the search asked is evaluated: runs still out were run ahead of it
    // for points it did not ask, and are cancelled to free their workers.
    let done = {
        let t = tuning.borrow();
        !t.published && t.plan.is_done()
    };
    if done {
        let (outcome, unused) = {
            let mut t = tuning.borrow_mut();
            t.published = true;
            (t.plan.finish(), std::mem::take(&mut t.out))
        };
        for (_, job) in unused {
            pool::cancel(job);
        }
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

/// Sends one run to the pool; its answer is told to the plan, which may ask for more.
fn send(
    runner: &Runner<Tuned>,
    tuning: &Rc<RefCell<Tuning>>,
    current: &(impl Fn() -> bool + Clone + 'static),
    run: PlannedRun,
) {
    let id = run.id;
    let request = JobRequest::Runs(RunRequest::new(vec![run.spec], &tuning.borrow().known));
    let (runner_in, tuning_in, current_in) = (runner.clone(), tuning.clone(), current.clone());
    let job = pool::submit(request, move |event| {
        if !current_in() || tuning_in.borrow().published {
            return;
        }
        let fail = |message: String| {
            runner_in.cancel();
            let _ = runner_in.status.try_set(RunStatus::Failed(message));
        };
        match event {
            JobEvent::Progress(_) | JobEvent::Chunk(_) => {}
            JobEvent::Done(Answer::Runs(mut runs)) if runs.len() == 1 => {
                let result = runs.remove(0);
                {
                    let mut t = tuning_in.borrow_mut();
                    t.out.retain(|(run, _)| *run != id);
                    if let Ok(key) = TeachKey::of(&result.spec) {
                        if !t.known.iter().any(|(k, _)| *k == key) {
                            t.known.push((key, result.calibration.clone()));
                        }
                    }
                    t.plan.tell(id, result.metrics.clone());
                }
                show_progress(&runner_in, &tuning_in.borrow());
                send_ready(&runner_in, &tuning_in, &current_in);
            }
            JobEvent::Done(_) => fail(ANOTHER_ANSWER.into()),
            JobEvent::Failed(message) => {
                let ahead = {
                    let mut t = tuning_in.borrow_mut();
                    t.out.retain(|(run, _)| *run != id);
                    let ahead = t.plan.is_ahead(id);
                    if ahead {
                        // Not the tuning's failure: the search has not asked for this point,
                        // and if it does, the run is sent again and fails then.
                        t.plan.forget(id);
                    }
                    ahead
                };
                if ahead {
                    send_ready(&runner_in, &tuning_in, &current_in);
                } else {
                    fail(message);
                }
            }
        }
    });
    tuning.borrow_mut().out.push((id, job));
    runner.track(job);
}
