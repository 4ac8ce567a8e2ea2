//! Runs closed-loop simulations in the browser without freezing the page.
//!
//! A [`LabRun`] advances a few control periods at a time; between chunks the browser gets control
//! back (a zero-delay timeout), so input, painting and the Cancel button stay responsive. The
//! chunk size adapts so each chunk takes about [`CHUNK_BUDGET_MS`], well under the 100 ms a
//! person notices. Starting a new run or cancelling bumps a generation counter; a pump that sees
//! a newer generation stops, so a stale run never overwrites a fresh result.

use std::cell::RefCell;
use std::rc::Rc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;

use leptos::prelude::*;

use crate::closed_loop::lab::{LabRun, RunResult, RunSpec};

/// Target duration of one chunk of work.
pub const CHUNK_BUDGET_MS: f64 = 30.0;

/// What the runner is doing.
#[derive(Debug, Clone, PartialEq)]
pub enum RunStatus {
    /// Nothing started yet.
    Idle,
    /// Working on run `index` of `total`.
    Running {
        /// Which run (0-based).
        index: usize,
        /// How many runs.
        total: usize,
        /// "teach cut" or "closed loop".
        stage: &'static str,
        /// Overall fraction done, 0–1.
        fraction: f64,
    },
    /// Every run finished.
    Done(Vec<Arc<RunResult>>),
    /// A run could not be set up or failed; the message says why.
    Failed(String),
    /// The user cancelled.
    Cancelled,
}

/// Drives runs and publishes their status.
#[derive(Clone)]
pub struct Runner {
    /// The status, for the page to show.
    pub status: RwSignal<RunStatus>,
    generation: Arc<AtomicU64>,
}

impl Runner {
    /// A runner with nothing started.
    pub fn new() -> Self {
        Self {
            status: RwSignal::new(RunStatus::Idle),
            generation: Arc::new(AtomicU64::new(0)),
        }
    }

    /// Cancels whatever is running.
    pub fn cancel(&self) {
        self.generation.fetch_add(1, Ordering::SeqCst);
        if matches!(
            self.status.try_get_untracked(),
            Some(RunStatus::Running { .. })
        ) {
            let _ = self.status.try_set(RunStatus::Cancelled);
        }
    }

    /// Starts `specs` one after the other, replacing anything running.
    pub fn start(&self, specs: Vec<RunSpec>) {
        let generation = self.generation.fetch_add(1, Ordering::SeqCst) + 1;
        let total = specs.len();
        let job = Rc::new(RefCell::new(Job {
            specs,
            current: None,
            results: Vec::with_capacity(total),
            periods_per_chunk: 4,
        }));
        let _ = self.status.try_set(RunStatus::Running {
            index: 0,
            total,
            stage: "teach cut",
            fraction: 0.0,
        });
        pump(job, self.status, self.generation.clone(), generation);
    }
}

impl Default for Runner {
    fn default() -> Self {
        Self::new()
    }
}

struct Job {
    specs: Vec<RunSpec>,
    current: Option<LabRun>,
    results: Vec<Arc<RunResult>>,
    periods_per_chunk: usize,
}

fn now_ms() -> f64 {
    window().performance().map_or(0.0, |p| p.now())
}

/// Does one chunk of work, publishes progress, and schedules the next chunk.
fn pump(job: Rc<RefCell<Job>>, status: RwSignal<RunStatus>, generation: Arc<AtomicU64>, mine: u64) {
    if generation.load(Ordering::SeqCst) != mine {
        return;
    }
    let outcome = {
        let mut job = job.borrow_mut();
        step(&mut job)
    };
    match outcome {
        // The page may have been left meanwhile: a disposed status ends the job quietly.
        Step::Progress(next) => {
            if status.try_set(next).is_none() {
                let (job, generation) = (job.clone(), generation.clone());
                set_timeout(move || pump(job, status, generation, mine), Duration::ZERO);
            }
        }
        Step::Finished(results) => {
            let _ = status.try_set(RunStatus::Done(results));
        }
        Step::Failed(message) => {
            let _ = status.try_set(RunStatus::Failed(message));
        }
    }
}

enum Step {
    Progress(RunStatus),
    Finished(Vec<Arc<RunResult>>),
    Failed(String),
}

fn step(job: &mut Job) -> Step {
    let total = job.specs.len();
    let index = job.results.len();
    if index >= total {
        return Step::Finished(std::mem::take(&mut job.results));
    }
    if job.current.is_none() {
        match LabRun::new(&job.specs[index]) {
            Ok(run) => job.current = Some(run),
            Err(e) => return Step::Failed(e.to_string()),
        }
    }
    let Some(run) = job.current.as_mut() else {
        return Step::Failed("internal: no run".into());
    };
    let started = now_ms();
    let done = match run.advance(job.periods_per_chunk) {
        Ok(done) => done,
        Err(e) => return Step::Failed(e.to_string()),
    };
    // Aim each chunk at the budget; never less than one period, never a jump of more than 4×.
    let elapsed = (now_ms() - started).max(0.1);
    let scaled = (job.periods_per_chunk as f64 * CHUNK_BUDGET_MS / elapsed).clamp(
        job.periods_per_chunk as f64 / 4.0,
        job.periods_per_chunk as f64 * 4.0,
    );
    job.periods_per_chunk = scaled.round().clamp(1.0, 100_000.0) as usize;
    let progress = run.progress();
    if done {
        if let Some(result) = job.current.take().and_then(LabRun::into_result) {
            job.results.push(Arc::new(result));
        }
        if job.results.len() >= total {
            return Step::Finished(std::mem::take(&mut job.results));
        }
    }
    Step::Progress(RunStatus::Running {
        index,
        total,
        stage: progress.stage,
        fraction: (index as f64 + progress.fraction) / total as f64,
    })
}

/// A progress bar with the stage and a Cancel button, shown while running.
#[component]
pub fn RunProgress(runner: Runner) -> impl IntoView {
    let status = runner.status;
    move || {
        match status.get() {
        RunStatus::Running {
            index,
            total,
            stage,
            fraction,
        } => {
            let runner = runner.clone();
            let label = if total > 1 {
                format!("Run {} of {total}: {stage}", index + 1)
            } else {
                format!("Running: {stage}")
            };
            view! {
                <div class="run-progress" role="status">
                    <label for="run-progress-bar">{label}</label>
                    <progress id="run-progress-bar" max="1" value=fraction.to_string()></progress>
                    <button type="button" on:click=move |_| runner.cancel()>"Cancel"</button>
                </div>
            }
            .into_any()
        }
        RunStatus::Failed(message) => view! {
            <p class="run-error" role="alert">{format!("The run could not be made: {message}")}</p>
        }
        .into_any(),
        RunStatus::Cancelled => view! {
            <p class="hint" role="status">"Cancelled. Change a setting or press Run to start again."</p>
        }
        .into_any(),
        _ => ().into_any(),
    }
    }
}
