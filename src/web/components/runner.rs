//! Runs long computations in the browser without freezing the page.
//!
//! Any core [`Work`] advances a little at a time; between chunks the browser gets control back (a
//! zero-delay timeout), so input, painting and the Cancel button stay responsive. The chunk size
//! adapts so each chunk takes about [`CHUNK_BUDGET_MS`], well under the 100 ms a person notices.
//! Starting a new job or cancelling bumps a generation counter; a pump that sees a newer
//! generation stops, so a stale job never overwrites a fresh result, and a job whose page was left
//! ends quietly.

use std::cell::RefCell;
use std::rc::Rc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;

use leptos::prelude::*;

use crate::work::{Progress, Work};

/// Target duration of one chunk of work.
pub const CHUNK_BUDGET_MS: f64 = 30.0;

/// What a runner is doing.
#[derive(Debug, Clone, PartialEq)]
pub enum RunStatus<T> {
    /// Nothing started yet.
    Idle,
    /// Working.
    Running {
        /// What it is doing.
        stage: String,
        /// Fraction done, 0–1.
        fraction: f64,
    },
    /// Finished.
    Done(T),
    /// The job could not be done; the message says why.
    Failed(String),
    /// The user cancelled.
    Cancelled,
}

/// Drives jobs and publishes their status.
pub struct Runner<T: Send + Sync + 'static> {
    /// The status, for the page to show.
    pub status: RwSignal<RunStatus<T>>,
    generation: Arc<AtomicU64>,
}

impl<T: Send + Sync + 'static> Clone for Runner<T> {
    fn clone(&self) -> Self {
        Self {
            status: self.status,
            generation: self.generation.clone(),
        }
    }
}

impl<T: Clone + Send + Sync + 'static> Runner<T> {
    /// A runner with nothing started; whatever it runs stops when the page that made it is left.
    pub fn new() -> Self {
        let generation = Arc::new(AtomicU64::new(0));
        let on_leave = generation.clone();
        on_cleanup(move || {
            on_leave.fetch_add(1, Ordering::SeqCst);
        });
        Self {
            status: RwSignal::new(RunStatus::Idle),
            generation,
        }
    }

    /// The output of the last job that finished; it stays while the next one runs.
    ///
    /// A signal set on completion rather than a memo of the status: outputs hold NaN where a
    /// quantity is undefined, so an output compared with itself reads as changed, and a memo
    /// would wake every chart on every progress tick.
    pub fn finished(&self) -> ReadSignal<Option<T>> {
        let (finished, set_finished) = signal(None::<T>);
        let status = self.status;
        Effect::new(move |_| {
            if let RunStatus::Done(output) = status.get() {
                set_finished.set(Some(output));
            }
        });
        finished
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

    /// Starts `job`, replacing anything running.
    pub fn start(&self, job: impl Work<Output = T> + 'static) {
        let generation = self.generation.fetch_add(1, Ordering::SeqCst) + 1;
        let Progress { stage, fraction } = job.progress();
        let _ = self.status.try_set(RunStatus::Running { stage, fraction });
        let state = Rc::new(RefCell::new(Pumped { job, budget: 1 }));
        pump(state, self.status, self.generation.clone(), generation);
    }
}

impl<T: Clone + Send + Sync + 'static> Default for Runner<T> {
    fn default() -> Self {
        Self::new()
    }
}

struct Pumped<J> {
    job: J,
    budget: usize,
}

fn now_ms() -> f64 {
    window().performance().map_or(0.0, |p| p.now())
}

/// Does one chunk of work, publishes progress, and schedules the next chunk.
fn pump<J: Work + 'static>(
    state: Rc<RefCell<Pumped<J>>>,
    status: RwSignal<RunStatus<J::Output>>,
    generation: Arc<AtomicU64>,
    mine: u64,
) where
    J::Output: Send + Sync + 'static,
{
    if generation.load(Ordering::SeqCst) != mine {
        return;
    }
    let next = {
        let mut s = state.borrow_mut();
        let started = now_ms();
        // Work in small steps until the chunk's time is used up: the cost of a step can jump
        // (a run enters the cut and the force model wakes up), and checking the clock between
        // steps keeps the chunk near its budget whatever the step costs.
        let outcome = loop {
            let step_started = now_ms();
            let budget = s.budget;
            match s.job.advance(budget) {
                Err(e) => break Some(Err(e.to_string())),
                Ok(true) => break Some(Ok(())),
                Ok(false) => {}
            }
            // Aim each step at an eighth of the chunk; grow at most 2× at a time.
            let elapsed = (now_ms() - step_started).max(0.05);
            let b = budget as f64;
            s.budget = (b * CHUNK_BUDGET_MS / 8.0 / elapsed)
                .clamp(b / 4.0, b * 2.0)
                .round()
                .clamp(1.0, 1e9) as usize;
            if now_ms() - started >= CHUNK_BUDGET_MS {
                break None;
            }
        };
        match outcome {
            Some(Err(e)) => RunStatus::Failed(e),
            Some(Ok(())) => match s.job.finish() {
                Ok(out) => RunStatus::Done(out),
                Err(e) => RunStatus::Failed(e.to_string()),
            },
            None => {
                let Progress { stage, fraction } = s.job.progress();
                RunStatus::Running { stage, fraction }
            }
        }
    };
    let running = matches!(next, RunStatus::Running { .. });
    // The page may have been left meanwhile: a disposed status ends the job quietly.
    if status.try_set(next).is_none() && running {
        set_timeout(
            move || pump(state, status, generation, mine),
            Duration::ZERO,
        );
    }
}

/// Runs an action a moment after the last request, dropping earlier ones: typing "150" into a
/// field starts one run, not three. Requests still pending when the page is left are dropped.
#[derive(Clone, Copy)]
pub struct Debounce {
    latest: StoredValue<u64>,
    delay: Duration,
}

impl Debounce {
    /// Waits `delay` after the last request.
    pub fn new(delay: Duration) -> Self {
        Self {
            latest: StoredValue::new(0),
            delay,
        }
    }

    /// Requests `action`; it runs unless another request comes within the delay.
    pub fn request(&self, action: impl FnOnce() + 'static) {
        self.latest.update_value(|n| *n += 1);
        let mine = self.latest.get_value();
        let latest = self.latest;
        set_timeout(
            move || {
                if latest.try_get_value() == Some(mine) {
                    action();
                }
            },
            self.delay,
        );
    }
}

/// A progress bar with the stage and a Cancel button, shown while running.
#[component]
pub fn RunProgress<T: Clone + Send + Sync + 'static>(
    runner: Runner<T>,
    /// The progress bar's element id (unique on the page).
    #[prop(default = "run-progress-bar")]
    id: &'static str,
    /// Say nothing after a cancel (for background work the page cancels itself).
    #[prop(optional)]
    quiet_cancel: bool,
    /// What a failure message starts with.
    #[prop(default = "The run could not be made")]
    failure: &'static str,
) -> impl IntoView {
    let status = runner.status;
    move || {
        match status.get() {
        RunStatus::Running { stage, fraction } => {
            let runner = runner.clone();
            view! {
                <div class="run-progress" role="status">
                    <label for=id>{stage}</label>
                    <progress id=id max="1" value=fraction.to_string()></progress>
                    <button type="button" on:click=move |_| runner.cancel()>"Cancel"</button>
                </div>
            }
            .into_any()
        }
        RunStatus::Failed(message) => view! {
            <p class="run-error" role="alert">{format!("{failure}: {message}")}</p>
        }
        .into_any(),
        RunStatus::Cancelled if quiet_cancel => ().into_any(),
        RunStatus::Cancelled => view! {
            <p class="hint" role="status">"Cancelled. Change a setting or press Run to start again."</p>
        }
        .into_any(),
        _ => ().into_any(),
    }
    }
}
