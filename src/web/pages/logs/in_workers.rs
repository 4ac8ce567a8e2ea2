//! The Logs page's replays in the computation workers: each controller's replay is a job of its
//! own, so with two or more workers the controllers replay at once on different cores. Each job
//! carries the log's mapped columns as raw numbers beside its JSON
//! ([`ReplayRequest`]: copied once into an array moved to the worker, never written out as
//! text), and answers its trace ([`ReplayParts`]); the page rebuilds each result with the replay
//! it prepares itself, equal bit for bit to a replay made here. The log stays on the page,
//! whatever happens to a worker.
//!
//! One job per controller rather than one job for all: a job replays its controllers in turn,
//! so one job for two would take their sum, where two jobs on two workers overlap. Measured on
//! the reference machine (2 cores, Chromium, release build, a 1.8-million-row 10 kHz log of
//! 37.6 MB, six rounds while other builds held the load average at 12–14): Threshold alone
//! 0.44–1.94 s in its worker, PI alone 0.44–1.80 s; both as two jobs 8.1 s over the six rounds
//! against 11.1 s for the sums of the two alone (what one job takes), faster in four rounds of
//! six. The price is a copy of the log's mapped columns per job, on the page: with the check
//! before the start, a task of 50–190 ms at the click for this log (the log's three columns,
//! 14 MB each).

use std::cell::RefCell;
use std::rc::Rc;
use std::sync::Arc;

use leptos::prelude::Set;

use crate::control::registry::ControllerConfig;
use crate::log::mapping::Mapping;
use crate::log::replay::{ReplayResult, ReplayRun, ReplaySettings};
use crate::log::transfer::{ReplayParts, ReplayRequest};
use crate::log::Log;
use crate::web::components::pool::{self, Answer, JobEvent};
use crate::web::components::runner::{
    next_task, RunStatus, Runner, ANOTHER_ANSWER, PROGRESS_EVERY_MS,
};

/// The replays' runner.
pub type ReplayRunner = Runner<Vec<Arc<ReplayResult>>>;

/// What the jobs of one replay have answered.
struct Replays {
    log: Arc<Log>,
    mapping: Mapping,
    settings: ReplaySettings,
    controllers: Vec<ControllerConfig>,
    fractions: Vec<f64>,
    answered: Vec<Option<ReplayParts>>,
    progress_at_ms: f64,
}

impl Replays {
    /// The status while the jobs run: their mean progress.
    fn running(&self) -> RunStatus<Vec<Arc<ReplayResult>>> {
        let count = self.controllers.len();
        let workers = pool::pool_size().min(count);
        let stage = match (count, workers) {
            (1, _) => "Replaying in a worker".to_string(),
            (_, 1) => format!("Replaying {count} controllers in a worker"),
            _ => format!("Replaying {count} controllers on {workers} workers"),
        };
        RunStatus::Running {
            stage,
            fraction: self.fractions.iter().sum::<f64>() / count.max(1) as f64,
        }
    }

    /// Every replay rebuilt on the page from its worker's trace, once all have answered.
    fn results(&mut self) -> Option<Result<Vec<Arc<ReplayResult>>, String>> {
        if self.answered.iter().any(Option::is_none) {
            return None;
        }
        let log = self.log.clone();
        Some(
            self.answered
                .iter_mut()
                .zip(&self.controllers)
                .map(|(parts, controller)| {
                    let prepared = ReplayRun::new(&log, &self.mapping, &self.settings, controller)
                        .map_err(|e| e.to_string())?;
                    parts
                        .take()
                        .ok_or("a replay's answer was read twice")?
                        .into_result(prepared)
                        .map(Arc::new)
                })
                .collect(),
        )
    }
}

/// Replays `controllers` on `log` in the workers on `runner`, replacing anything it runs. This is
/// the one place a replay's results arrive: `runner`'s status turns `Done` with them.
pub fn start_replays(
    runner: &ReplayRunner,
    log: Arc<Log>,
    mapping: Mapping,
    settings: ReplaySettings,
    controllers: Vec<ControllerConfig>,
) {
    let current = runner.begin_in_workers();
    let count = controllers.len();
    let replays = Rc::new(RefCell::new(Replays {
        log: log.clone(),
        mapping: mapping.clone(),
        settings: settings.clone(),
        controllers: controllers.clone(),
        fractions: vec![0.0; count],
        answered: vec![None; count],
        progress_at_ms: f64::NEG_INFINITY,
    }));
    let _ = runner.status.try_set(replays.borrow().running());
    for (index, controller) in controllers.into_iter().enumerate() {
        let (request, numbers) =
            ReplayRequest::job(&log, mapping.clone(), settings.clone(), vec![controller]);
        let (runner_in, replays, current) = (runner.clone(), replays.clone(), current.clone());
        let job = pool::submit_log_job(&request, &numbers, move |event| {
            if !current() {
                return;
            }
            let status = runner_in.status;
            match event {
                JobEvent::Progress(p) => {
                    let mut r = replays.borrow_mut();
                    r.fractions[index] = p.fraction;
                    let now_ms = js_sys::Date::now();
                    if now_ms - r.progress_at_ms >= PROGRESS_EVERY_MS {
                        r.progress_at_ms = now_ms;
                        let _ = status.try_set(r.running());
                    }
                }
                JobEvent::Chunk(_) => {}
                JobEvent::Done(Answer::Replays(mut parts)) if parts.len() == 1 => {
                    {
                        let mut r = replays.borrow_mut();
                        r.answered[index] = parts.pop();
                        r.fractions[index] = 1.0;
                    }
                    let all_in = replays.borrow().answered.iter().all(Option::is_some);
                    if !all_in {
                        let _ = status.try_set(replays.borrow().running());
                        return;
                    }
                    let (replays, current) = (replays.clone(), current.clone());
                    // The rebuild and the redraw it starts run in a task of their own.
                    next_task(move || {
                        if !current() {
                            return;
                        }
                        let outcome = replays.borrow_mut().results();
                        match outcome {
                            Some(Ok(results)) => {
                                let _ = status.try_set(RunStatus::Done(results));
                            }
                            Some(Err(message)) => {
                                let _ = status.try_set(RunStatus::Failed(message));
                            }
                            None => {}
                        }
                    });
                }
                JobEvent::Done(_) => {
                    runner_in.cancel();
                    let _ = status.try_set(RunStatus::Failed(ANOTHER_ANSWER.into()));
                }
                JobEvent::Failed(message) => {
                    runner_in.cancel();
                    let _ = status.try_set(RunStatus::Failed(message));
                }
            }
        });
        runner.track(job);
    }
}
