//! Runs long computations in the browser without freezing the page.
//!
//! Any core [`Work`] advances a little at a time; between chunks the browser gets control back (a
//! message the page posts to itself, which starts a new task without the ≥ 4 ms a nested
//! zero-delay timeout waits), so input, painting and the Cancel button stay responsive. The chunk size
//! adapts so each chunk takes about [`CHUNK_BUDGET_MS`], well under the 100 ms a person notices.
//! Starting a new job or cancelling bumps a generation counter; a pump that sees a newer
//! generation stops, so a stale job never overwrites a fresh result, and a job whose page was left
//! ends quietly.
//!
//! Most jobs do not share the page's thread at all: [`Runner::start_in_workers`] (closed-loop
//! runs) and [`Runner::start_in_worker`] (any other [`JobRequest`]: references, learning,
//! recordings, teach cuts) hand them to the worker pool ([`super::pool`]) behind the same
//! status, progress bar and Cancel. Only the Logs page's computations are still sliced here.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::rc::Rc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use leptos::prelude::*;
use wasm_bindgen::prelude::{Closure, JsCast, JsValue};

use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::lab::{RunResult, TeachKey};
use crate::closed_loop::transfer::{JobRequest, RunRequest, StreamedRun, TraceChunk};
use crate::estimation::estimator::Calibration;
use crate::web::components::pool::{self, Answer, JobEvent, JobId};
use crate::work::{Progress, Work};

/// Longest duration of one chunk of work: a chunk ends before a step that would take it past
/// this, so with the page's own work around it a chunk stays under the 50 ms a task should take;
/// between chunks the browser draws a frame (a few ms), so shorter chunks would cost the run time.
pub const CHUNK_BUDGET_MS: f64 = 35.0;

/// How often the output so far of a job is shown while it runs: the traces a worker streams
/// ([`Runner::start_in_workers`]; the first piece is drawn at once, so the start of a long cut
/// shows as soon as it is computed), or a sliced job's preview. A preview redraws every chart of
/// the page, tens of milliseconds in all, so a run fills in twice a second.
pub const PREVIEW_EVERY_MS: f64 = 500.0;

/// How often a running job's progress (stage and fraction) is published. Each change of the
/// status has the browser draw a frame after the chunk (a few ms of layout and paint), so a
/// progress bar updated after every chunk would slow the run it shows; ten times a second is
/// smooth to read.
pub const PROGRESS_EVERY_MS: f64 = 100.0;

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

/// Drives jobs — sliced on the page's thread, or closed-loop runs in the worker pool
/// ([`Runner::start_in_workers`]) — and publishes their status.
pub struct Runner<T: Send + Sync + 'static> {
    /// The status, for the page to show.
    pub status: RwSignal<RunStatus<T>>,
    /// The output so far of a previewing job, refreshed every
    /// [`PREVIEW_EVERY_MS`] while it runs and set to its output when it is done; `None` for
    /// other jobs, before the first preview, and after a failure or cancel.
    pub preview: RwSignal<Option<T>>,
    generation: Arc<AtomicU64>,
    /// The worker-pool jobs of the job under way, cancelled with it.
    pool_jobs: Arc<Mutex<Vec<JobId>>>,
}

impl<T: Send + Sync + 'static> Clone for Runner<T> {
    fn clone(&self) -> Self {
        Self {
            status: self.status,
            preview: self.preview,
            generation: self.generation.clone(),
            pool_jobs: self.pool_jobs.clone(),
        }
    }
}

/// Cancels the pool jobs in `jobs`.
fn cancel_pool_jobs(jobs: &Mutex<Vec<JobId>>) {
    let taken = jobs
        .lock()
        .map(|mut j| std::mem::take(&mut *j))
        .unwrap_or_default();
    for job in taken {
        pool::cancel(job);
    }
}

impl<T: Clone + Send + Sync + 'static> Runner<T> {
    /// A runner with nothing started; whatever it runs stops when the page that made it is left.
    pub fn new() -> Self {
        let generation = Arc::new(AtomicU64::new(0));
        let pool_jobs = Arc::new(Mutex::new(Vec::new()));
        let (on_leave, jobs_on_leave) = (generation.clone(), pool_jobs.clone());
        on_cleanup(move || {
            on_leave.fetch_add(1, Ordering::SeqCst);
            cancel_pool_jobs(&jobs_on_leave);
        });
        Self {
            status: RwSignal::new(RunStatus::Idle),
            preview: RwSignal::new(None),
            generation,
            pool_jobs,
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
        cancel_pool_jobs(&self.pool_jobs);
        let _ = self.preview.try_set(None);
        if matches!(
            self.status.try_get_untracked(),
            Some(RunStatus::Running { .. })
        ) {
            let _ = self.status.try_set(RunStatus::Cancelled);
        }
    }

    /// Starts `job`, replacing anything running.
    pub fn start<J: Work<Output = T> + 'static>(&self, job: J) {
        self.start_with(job, None);
    }

    fn start_with<J: Work<Output = T> + 'static>(
        &self,
        job: J,
        preview: Option<fn(&J) -> Option<T>>,
    ) {
        let generation = self.generation.fetch_add(1, Ordering::SeqCst) + 1;
        cancel_pool_jobs(&self.pool_jobs);
        let Progress { stage, fraction } = job.progress();
        let _ = self.status.try_set(RunStatus::Running { stage, fraction });
        let _ = self.preview.try_set(None);
        let state = Rc::new(RefCell::new(Pumped {
            job,
            budget: 1,
            preview,
            previewed_at_ms: now_ms(),
            progress_at_ms: now_ms(),
            phase: Phase::Working,
        }));
        let signals = Published {
            status: self.status,
            preview: self.preview,
        };
        // The first chunk in a task of its own: a page that starts a run as it mounts paints first.
        let generations = self.generation.clone();
        next_task(move || pump(state, signals, generations, generation));
    }
}

impl<T: Clone + Send + Sync + 'static> Default for Runner<T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<T: Send + Sync + 'static> Runner<T> {
    /// Starts a job the caller drives through the worker pool itself, replacing anything
    /// running; the returned check says whether it is still this runner's job (a later start, a
    /// cancel or leaving the page ends it). Its pool jobs, given to [`Runner::track`], are
    /// cancelled with it.
    pub fn begin_in_workers(&self) -> impl Fn() -> bool + Clone + 'static {
        let generation = self.generation.fetch_add(1, Ordering::SeqCst) + 1;
        cancel_pool_jobs(&self.pool_jobs);
        let _ = self.preview.try_set(None);
        let generations = self.generation.clone();
        move || generations.load(Ordering::SeqCst) == generation
    }

    /// Cancels pool job `job` with the job under way.
    pub fn track(&self, job: JobId) {
        if let Ok(mut jobs) = self.pool_jobs.lock() {
            jobs.push(job);
        }
    }
}

/// What a job answered with another kind of answer than its request's (a bug) fails with.
pub const ANOTHER_ANSWER: &str = "the computation worker answered another job than the one asked";

impl<T: Clone + Send + Sync + 'static> Runner<T> {
    /// Does `request` in the worker pool, replacing anything running, behind the same status,
    /// progress bar and Cancel as a sliced job; `output` takes the answer (`None`: an answer of
    /// another kind, a bug, fails the job). The output is published in a task of its own.
    pub fn start_in_worker(&self, request: JobRequest, output: fn(Answer) -> Option<T>) {
        let generation = self.generation.fetch_add(1, Ordering::SeqCst) + 1;
        cancel_pool_jobs(&self.pool_jobs);
        let _ = self.preview.try_set(None);
        let status = self.status;
        let _ = status.try_set(RunStatus::Running {
            stage: "Waiting for a worker".into(),
            fraction: 0.0,
        });
        let generations = self.generation.clone();
        let current = move || generations.load(Ordering::SeqCst) == generation;
        let mut progress_at_ms = f64::NEG_INFINITY;
        let job = pool::submit(request, move |event| {
            if !current() {
                return;
            }
            match event {
                JobEvent::Progress(Progress { stage, fraction }) => {
                    if now_ms() - progress_at_ms >= PROGRESS_EVERY_MS {
                        progress_at_ms = now_ms();
                        let _ = status.try_set(RunStatus::Running { stage, fraction });
                    }
                }
                JobEvent::Chunk(_) => {}
                JobEvent::Done(answer) => {
                    let next = output(answer)
                        .map_or_else(|| RunStatus::Failed(ANOTHER_ANSWER.into()), RunStatus::Done);
                    let current = current.clone();
                    // The redraw the output starts runs in a task of its own.
                    next_task(move || {
                        if current() {
                            let _ = status.try_set(next);
                        }
                    });
                }
                JobEvent::Failed(message) => {
                    let _ = status.try_set(RunStatus::Failed(message));
                }
            }
        });
        if let Ok(mut pool_jobs) = self.pool_jobs.lock() {
            *pool_jobs = vec![job];
        }
    }
}

impl Runner<Vec<Arc<RunResult>>> {
    /// Runs `specs` in the worker pool, replacing anything running: each spec a job of its own,
    /// so independent runs compute at once on different workers, each starting from the `known`
    /// calibration of its teach cut if there is one. The status shows their mean progress; the
    /// output is the runs in `specs`' order, published in a task of its own once all are done
    /// (the first failure fails the whole and cancels the rest).
    ///
    /// While they compute, [`Runner::preview`] holds the runs so far as the workers stream them
    /// (in `specs`' order, up to the first that has nothing yet): the first piece at once, then
    /// every [`PREVIEW_EVERY_MS`], each in a task of its own; once all are done, the runs.
    pub fn start_in_workers(&self, specs: Vec<RunSpec>, known: Vec<(TeachKey, Calibration)>) {
        let generation = self.generation.fetch_add(1, Ordering::SeqCst) + 1;
        cancel_pool_jobs(&self.pool_jobs);
        let _ = self.preview.try_set(None);
        let count = specs.len();
        if count == 0 {
            let _ = self.status.try_set(RunStatus::Done(Vec::new()));
            return;
        }
        let workers = pool::pool_size().min(count);
        let stage = move |fractions: &[f64]| {
            let label = match (count, workers) {
                (1, _) => "Running in a worker".to_string(),
                (_, 1) => format!("{count} runs in a worker"),
                _ => format!("{count} runs on {workers} workers"),
            };
            RunStatus::Running {
                stage: label,
                fraction: fractions.iter().sum::<f64>() / count as f64,
            }
        };
        let _ = self.status.try_set(stage(&vec![0.0; count]));
        // What the jobs have reported, shared by their listeners.
        let fractions = std::rc::Rc::new(RefCell::new(vec![0.0; count]));
        let results = std::rc::Rc::new(RefCell::new(vec![None::<Arc<RunResult>>; count]));
        let progress_at_ms = std::rc::Rc::new(RefCell::new(f64::NEG_INFINITY));
        let streams = Rc::new(RefCell::new(Streams {
            runs: vec![None; count],
            previewed_at_ms: f64::NEG_INFINITY,
            preview_due: false,
        }));
        let mut jobs = Vec::with_capacity(count);
        for (index, spec) in specs.into_iter().enumerate() {
            let (status, runner) = (self.status, self.clone());
            let (fractions, results) = (fractions.clone(), results.clone());
            let progress_at_ms = progress_at_ms.clone();
            let generations = self.generation.clone();
            let current = move || generations.load(Ordering::SeqCst) == generation;
            let (streams, preview) = (streams.clone(), self.preview);
            let spec_streamed = spec.clone();
            let request = JobRequest::Runs(RunRequest::new(vec![spec], &known));
            let job = pool::submit(request, move |event| {
                if !current() {
                    return;
                }
                match event {
                    JobEvent::Chunk(chunk) => {
                        let outcome = streams.borrow_mut().receive(index, &spec_streamed, chunk);
                        match outcome {
                            Err(message) => {
                                runner.cancel();
                                let _ = status.try_set(RunStatus::Failed(message));
                            }
                            Ok(true) => {
                                let (streams, results) = (streams.clone(), results.clone());
                                let current = current.clone();
                                // The redraw a preview starts runs in a task of its own.
                                next_task(move || {
                                    if current() {
                                        let so_far = streams.borrow_mut().so_far(&results.borrow());
                                        let _ = preview.try_set(Some(so_far));
                                    }
                                });
                            }
                            Ok(false) => {}
                        }
                    }
                    JobEvent::Progress(p) => {
                        fractions.borrow_mut()[index] = p.fraction;
                        // At most every PROGRESS_EVERY_MS, as for a sliced job.
                        let due = now_ms() - *progress_at_ms.borrow() >= PROGRESS_EVERY_MS;
                        if due {
                            *progress_at_ms.borrow_mut() = now_ms();
                            let _ = status.try_set(stage(&fractions.borrow()));
                        }
                    }
                    JobEvent::Done(Answer::Runs(mut runs)) => {
                        results.borrow_mut()[index] = runs.pop();
                        fractions.borrow_mut()[index] = 1.0;
                        let all: Option<Vec<_>> = results.borrow().iter().cloned().collect();
                        match all {
                            Some(all) => {
                                let current = current.clone();
                                // The redraw the output starts runs in a task of its own.
                                next_task(move || {
                                    if current() {
                                        // The finished runs replace what was streamed of them.
                                        let _ = preview.try_set(Some(all.clone()));
                                        // An open lesson checks every finished run.
                                        crate::web::pages::lessons::feed::publish(&all);
                                        let _ = status.try_set(RunStatus::Done(all));
                                    }
                                });
                            }
                            None => {
                                let _ = status.try_set(stage(&fractions.borrow()));
                            }
                        }
                    }
                    JobEvent::Done(_) => {
                        runner.cancel();
                        let _ = status.try_set(RunStatus::Failed(ANOTHER_ANSWER.into()));
                    }
                    JobEvent::Failed(message) => {
                        runner.cancel();
                        let _ = status.try_set(RunStatus::Failed(message));
                    }
                }
            });
            jobs.push(job);
        }
        if let Ok(mut pool_jobs) = self.pool_jobs.lock() {
            *pool_jobs = jobs;
        }
    }
}

/// What the workers of [`Runner::start_in_workers`] have streamed of their runs.
struct Streams {
    /// Each run's pieces so far, in the specs' order.
    runs: Vec<Option<StreamedRun>>,
    previewed_at_ms: f64,
    /// A preview has been asked for and not yet made.
    preview_due: bool,
}

impl Streams {
    /// Adds `chunk` to run `index` (of `spec`); true if a preview is due now and none is
    /// pending (the first piece at once, then every [`PREVIEW_EVERY_MS`]).
    fn receive(&mut self, index: usize, spec: &RunSpec, chunk: TraceChunk) -> Result<bool, String> {
        let Some(slot) = self.runs.get_mut(index) else {
            return Ok(false);
        };
        match slot {
            Some(run) => run.append(chunk)?,
            None => *slot = Some(StreamedRun::start(spec.clone(), chunk)?),
        }
        let due = !self.preview_due && now_ms() - self.previewed_at_ms >= PREVIEW_EVERY_MS;
        if due {
            self.preview_due = true;
        }
        Ok(due)
    }

    /// The runs so far, in order up to the first with nothing yet: each finished one as
    /// `finished` holds it, else what has been streamed of it.
    fn so_far(&mut self, finished: &[Option<Arc<RunResult>>]) -> Vec<Arc<RunResult>> {
        self.preview_due = false;
        self.previewed_at_ms = now_ms();
        self.runs
            .iter()
            .zip(finished)
            .map_while(|(streamed, done)| {
                done.clone()
                    .or_else(|| streamed.as_ref().map(|s| Arc::new(s.so_far())))
            })
            .collect()
    }
}

/// How a job shows its output so far.
type PreviewOf<J> = fn(&J) -> Option<<J as Work>::Output>;

struct Pumped<J: Work> {
    job: J,
    budget: usize,
    preview: Option<PreviewOf<J>>,
    previewed_at_ms: f64,
    /// When the progress was last published.
    progress_at_ms: f64,
    phase: Phase,
}

/// Where a pumped job is.
#[derive(Clone, Copy, PartialEq)]
enum Phase {
    /// More work to do.
    Working,
    /// The work is done; its output is published next.
    Finished,
}

/// Where a pump publishes.
struct Published<T: Send + Sync + 'static> {
    status: RwSignal<RunStatus<T>>,
    preview: RwSignal<Option<T>>,
}

impl<T: Send + Sync + 'static> Clone for Published<T> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<T: Send + Sync + 'static> Copy for Published<T> {}

fn now_ms() -> f64 {
    window().performance().map_or(0.0, |p| p.now())
}

/// Does one chunk of work, publishes progress, and schedules the next chunk.
fn pump<J: Work + 'static>(
    state: Rc<RefCell<Pumped<J>>>,
    published: Published<J::Output>,
    generation: Arc<AtomicU64>,
    mine: u64,
) where
    J::Output: Clone + Send + Sync + 'static,
{
    let status = published.status;
    if generation.load(Ordering::SeqCst) != mine {
        return;
    }
    // What the page redraws — a preview of the work so far, or the finished output — is
    // published in a task of its own, not after a chunk of work: the redraw runs in the task that
    // sets the signals, and a chunk plus a redraw could exceed the 50 ms a task should take.
    let phase = state.borrow().phase;
    let next = match phase {
        Phase::Finished => {
            let finished = state.borrow_mut().job.finish();
            match finished {
                Ok(out) => RunStatus::Done(out),
                Err(e) => RunStatus::Failed(e.to_string()),
            }
        }
        Phase::Working => {
            let preview = {
                let mut s = state.borrow_mut();
                match s.preview {
                    Some(show) if now_ms() - s.previewed_at_ms >= PREVIEW_EVERY_MS => {
                        s.previewed_at_ms = now_ms();
                        Some(show(&s.job))
                    }
                    _ => None,
                }
            };
            match preview {
                Some(so_far) => {
                    if so_far.is_some() {
                        let _ = published.preview.try_set(so_far);
                    }
                    let Progress { stage, fraction } = state.borrow().job.progress();
                    RunStatus::Running { stage, fraction }
                }
                None => work_chunk(&mut state.borrow_mut()),
            }
        }
    };
    let running = matches!(next, RunStatus::Running { .. });
    match &next {
        // A previewed job's final output is its last preview, so the page shows it at once.
        RunStatus::Done(output) if state.borrow().preview.is_some() => {
            let _ = published.preview.try_set(Some(output.clone()));
        }
        RunStatus::Running { .. } => {}
        _ => {
            let _ = published.preview.try_set(None);
        }
    }
    // Progress at most every PROGRESS_EVERY_MS; an end (done, failed) at once.
    let publish = !running || {
        let mut s = state.borrow_mut();
        let due = now_ms() - s.progress_at_ms >= PROGRESS_EVERY_MS;
        if due {
            s.progress_at_ms = now_ms();
        }
        due
    };
    // The page may have been left meanwhile: a disposed status ends the job quietly.
    let alive = if publish {
        status.try_set(next).is_none()
    } else {
        status.try_with_untracked(|_| ()).is_some()
    };
    if alive && running {
        next_task(move || pump(state, published, generation, mine));
    }
}

/// One chunk of work of about [`CHUNK_BUDGET_MS`]; the status to show after it (still running
/// when the work is done: the output is published by the next task).
fn work_chunk<J: Work>(s: &mut Pumped<J>) -> RunStatus<J::Output> {
    let started = now_ms();
    let stage_at_start = s.job.progress().stage;
    // Work in small steps until the chunk's time is used up: the cost of a step can jump (a run
    // enters the cut and the force model wakes up), and checking the clock between steps keeps
    // the chunk near its budget whatever the step costs.
    loop {
        let step_started = now_ms();
        let budget = s.budget;
        match s.job.advance(budget) {
            Err(e) => return RunStatus::Failed(e.to_string()),
            Ok(true) => {
                s.phase = Phase::Finished;
                break;
            }
            Ok(false) => {}
        }
        // Aim each step at an eighth of the chunk; grow at most 2× at a time.
        let elapsed = (now_ms() - step_started).max(0.05);
        let b = budget as f64;
        s.budget = (b * CHUNK_BUDGET_MS / 8.0 / elapsed)
            .clamp(b / 4.0, b * 2.0)
            .round()
            .clamp(1.0, 1e9) as usize;
        // End the chunk before a step that would take it past its budget, at the last step's
        // pace: a job's first step, which sets it up (and has V8 compile its code), can take
        // most of a chunk by itself.
        let next_step_ms = elapsed * s.budget as f64 / b;
        if now_ms() - started + next_step_ms >= CHUNK_BUDGET_MS {
            break;
        }
        // A new stage (the spectrum after the samples, the closed loop after the teach cut, the
        // next reference run) costs what the last step cannot tell: it starts a chunk of its
        // own rather than finishing this one past its budget.
        let progress = s.job.progress();
        if progress.stage != stage_at_start {
            return RunStatus::Running {
                stage: progress.stage,
                fraction: progress.fraction,
            };
        }
    }
    let Progress { stage, fraction } = s.job.progress();
    RunStatus::Running { stage, fraction }
}

/// Callbacks waiting for their task, first in first out.
type Pending = Rc<RefCell<VecDeque<Box<dyn FnOnce()>>>>;

/// Callbacks waiting for their task, and the channel whose messages start them.
struct TaskQueue {
    pending: Pending,
    sender: web_sys::MessagePort,
    /// Kept alive as long as the queue: the receiving port's handler.
    _on_message: Closure<dyn FnMut(web_sys::MessageEvent)>,
}

thread_local! {
    static TASKS: Option<TaskQueue> = {
        web_sys::MessageChannel::new().ok().map(|channel| {
            let pending: Pending = Rc::default();
            let queue = pending.clone();
            let on_message = Closure::<dyn FnMut(web_sys::MessageEvent)>::new(
                move |_: web_sys::MessageEvent| {
                    let next = queue.borrow_mut().pop_front();
                    if let Some(task) = next {
                        task();
                    }
                },
            );
            channel
                .port1()
                .set_onmessage(Some(on_message.as_ref().unchecked_ref()));
            TaskQueue {
                pending,
                sender: channel.port2(),
                _on_message: on_message,
            }
        })
    };
}

/// Runs `task` as a task of its own once the browser has handled input and painting: a message
/// the page posts to itself, which (unlike a zero-delay timeout, held back ≥ 4 ms once timeouts
/// nest) starts as soon as the browser is free. Falls back to a timeout without a channel.
pub fn next_task(task: impl FnOnce() + 'static) {
    let posted = TASKS.with(|queue| match queue {
        Some(q) => {
            q.pending.borrow_mut().push_back(Box::new(task));
            if q.sender.post_message(&JsValue::NULL).is_ok() {
                None
            } else {
                q.pending.borrow_mut().pop_back()
            }
        }
        None => Some(Box::new(task) as Box<dyn FnOnce()>),
    });
    if let Some(task) = posted {
        set_timeout(task, Duration::ZERO);
    }
}

/// Runs an action a moment after the last request, dropping earlier ones: typing "150" into a
/// field starts one run, not three. Requests still pending when the page is left are dropped.
#[derive(Clone, Copy)]
pub struct Debounce {
    latest: StoredValue<u64>,
    delay: Duration,
    /// The next request runs at once (a page's first run, which nothing can supersede yet).
    next_at_once: StoredValue<bool>,
}

impl Debounce {
    /// Waits `delay` after the last request.
    pub fn new(delay: Duration) -> Self {
        Self {
            latest: StoredValue::new(0),
            delay,
            next_at_once: StoredValue::new(false),
        }
    }

    /// The same, except that the first request runs at once: a page's first run should not
    /// wait for edits that have not happened.
    pub fn first_at_once(delay: Duration) -> Self {
        Self {
            next_at_once: StoredValue::new(true),
            ..Self::new(delay)
        }
    }

    /// No wait beyond the next task: of the requests made before it, only the last runs (a
    /// chart redrawn twice in one task draws once), and it runs in a task of its own.
    pub fn to_next_task() -> Self {
        Self::new(Duration::ZERO)
    }

    /// Requests `action`; it runs unless another request comes within the delay (before the
    /// next task, for a delay of zero).
    pub fn request(&self, action: impl FnOnce() + 'static) {
        if self.next_at_once.get_value() {
            self.next_at_once.set_value(false);
            action();
            return;
        }
        self.latest.update_value(|n| *n += 1);
        let mine = self.latest.get_value();
        let latest = self.latest;
        let if_latest = move || {
            if latest.try_get_value() == Some(mine) {
                action();
            }
        };
        // A zero timeout waits at least 4 ms once timeouts nest; a posted message does not.
        if self.delay.is_zero() {
            next_task(if_latest);
        } else {
            set_timeout(if_latest, self.delay);
        }
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
    // What is shown changes only when a run starts or ends; while it runs, each chunk's progress
    // updates the label and the bar in place instead of building them again (and having the
    // browser lay out the form again) after every chunk.
    let shown = Memo::new(move |_| {
        status.with(|s| match s {
            RunStatus::Running { .. } => ProgressStage::Running,
            RunStatus::Failed(message) => ProgressStage::Failed(message.clone()),
            RunStatus::Cancelled if !quiet_cancel => ProgressStage::Cancelled,
            _ => ProgressStage::Nothing,
        })
    });
    let stage = Memo::new(move |_| {
        status.with(|s| match s {
            RunStatus::Running { stage, .. } => stage.clone(),
            _ => String::new(),
        })
    });
    let fraction = move || {
        status.with(|s| match s {
            RunStatus::Running { fraction, .. } => fraction.to_string(),
            _ => "0".to_string(),
        })
    };
    move || {
        match shown.get() {
        ProgressStage::Running => {
            let runner = runner.clone();
            view! {
                <div class="run-progress" role="status">
                    <label for=id>{move || stage.get()}</label>
                    <progress id=id max="1" value=fraction></progress>
                    <button type="button" on:click=move |_| runner.cancel()>"Cancel"</button>
                </div>
            }
            .into_any()
        }
        ProgressStage::Failed(message) => view! {
            <p class="run-error" role="alert">{format!("{failure}: {message}")}</p>
        }
        .into_any(),
        ProgressStage::Cancelled => view! {
            <p class="hint" role="status">"Cancelled. Change a setting or press Run to start again."</p>
        }
        .into_any(),
        ProgressStage::Nothing => ().into_any(),
    }
    }
}

/// Which of its forms a [`RunProgress`] shows.
#[derive(Clone, PartialEq)]
enum ProgressStage {
    Running,
    Failed(String),
    Cancelled,
    Nothing,
}
