//! A long computation's status, progress and Cancel on the page, the computation itself in the
//! worker pool ([`super::pool`]): [`Runner::start_in_workers`] (closed-loop runs, each a job of
//! its own), [`Runner::start_in_worker`] (any other [`JobRequest`]: references, learning,
//! recordings, teach cuts), [`Runner::start_log_job`] (the Logs page's signal chain and
//! calibration fit) and, for callers that drive the pool themselves (the Logs page's replays,
//! Tune's search), [`Runner::begin_in_workers`]. Starting a new job or cancelling bumps a
//! generation counter and cancels the job's pool jobs (their workers are terminated); an answer
//! of an older generation is dropped, so a stale job never overwrites a fresh result, and a job
//! whose page was left ends quietly. What an answer redraws runs in a task of its own
//! ([`next_task`]), never in the task that received it.

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
use crate::log::transfer::{LogJobRequest, LogNumbers};
use crate::web::components::pool::{self, Answer, JobEvent, JobId};
use crate::work::Progress;

/// How often the output so far of a job is shown while it runs: the traces a worker streams
/// ([`Runner::start_in_workers`]; the first piece is drawn at once, so the start of a long cut
/// shows as soon as it is computed). A preview redraws every chart of the page, tens of
/// milliseconds in all, so a run fills in twice a second.
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

/// Hands jobs to the worker pool and publishes their status.
pub struct Runner<T: Send + Sync + 'static> {
    /// The status, for the page to show.
    pub status: RwSignal<RunStatus<T>>,
    /// The runs so far of [`Runner::start_in_workers`], refreshed every [`PREVIEW_EVERY_MS`]
    /// while they compute and set to the runs when they are done; `None` for other jobs, before
    /// the first preview, and after a failure or cancel.
    pub preview: RwSignal<Option<T>>,
    /// The first run of the latest [`Runner::start_in_workers`] to stream its calibration (its
    /// teach cut made, or one given), with its spec: what the savings' reference search starts
    /// from, beside the runs. `None` until one has; other kinds of job leave it as it is.
    pub taught: RwSignal<Option<(RunSpec, Calibration)>>,
    generation: Arc<AtomicU64>,
    /// The worker-pool jobs of the job under way, cancelled with it.
    pool_jobs: Arc<Mutex<Vec<JobId>>>,
}

impl<T: Send + Sync + 'static> Clone for Runner<T> {
    fn clone(&self) -> Self {
        Self {
            status: self.status,
            preview: self.preview,
            taught: self.taught,
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
            taught: RwSignal::new(None),
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
    /// Does `request` in the worker pool, replacing anything running, behind the runner's
    /// status, progress bar and Cancel; `output` takes the answer (`None`: an answer of
    /// another kind, a bug, fails the job). The output is published in a task of its own.
    pub fn start_in_worker(&self, request: JobRequest, output: fn(Answer) -> Option<T>) {
        self.start_in_pool(|listener| pool::submit(request, listener), output);
    }

    /// Does a job on a log in the worker pool, its `numbers` sent beside it
    /// ([`pool::submit_log_job`]), as [`Runner::start_in_worker`] does a [`JobRequest`].
    pub fn start_log_job(
        &self,
        request: &LogJobRequest,
        numbers: &LogNumbers<'_>,
        output: fn(Answer) -> Option<T>,
    ) {
        self.start_in_pool(
            |listener| pool::submit_log_job(request, numbers, listener),
            output,
        );
    }

    /// Submits one job with `submit`, given its listener, behind this runner's status.
    fn start_in_pool(
        &self,
        submit: impl FnOnce(Box<dyn FnMut(JobEvent)>) -> JobId,
        output: fn(Answer) -> Option<T>,
    ) {
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
        let job = submit(Box::new(move |event| {
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
        }));
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
    /// As many runs as there are workers start at once; each of the others is sent when one
    /// finishes, with the calibrations known by then, so it does not make again a teach cut a
    /// run before it made (Compare's four variants share one). A job another part of the page
    /// sends meanwhile (the savings' reference search) takes the next free worker.
    ///
    /// While they compute, [`Runner::preview`] holds the runs so far as the workers stream them
    /// (in `specs`' order, up to the first that has nothing yet): the first piece at once, then
    /// every [`PREVIEW_EVERY_MS`], each in a task of its own; once all are done, the runs.
    pub fn start_in_workers(&self, specs: Vec<RunSpec>, known: Vec<(TeachKey, Calibration)>) {
        let generation = self.generation.fetch_add(1, Ordering::SeqCst) + 1;
        cancel_pool_jobs(&self.pool_jobs);
        let _ = self.preview.try_set(None);
        let _ = self.taught.try_set(None);
        let count = specs.len();
        if count == 0 {
            let _ = self.status.try_set(RunStatus::Done(Vec::new()));
            return;
        }
        let workers = pool::pool_size().min(count);
        let runs = Rc::new(RunsInWorkers {
            runner: self.clone(),
            generation,
            count,
            workers,
            fractions: RefCell::new(vec![0.0; count]),
            results: RefCell::new(vec![None; count]),
            progress_at_ms: std::cell::Cell::new(f64::NEG_INFINITY),
            streams: RefCell::new(Streams {
                runs: vec![None; count],
                previewed_at_ms: f64::NEG_INFINITY,
                preview_due: false,
            }),
            known: RefCell::new(known),
            waiting: RefCell::new(specs.into_iter().enumerate().collect()),
        });
        let _ = self.status.try_set(runs.stage());
        for _ in 0..workers {
            send_next_run(&runs);
        }
    }
}

/// The runs of one [`Runner::start_in_workers`], shared by their jobs' listeners.
struct RunsInWorkers {
    runner: Runner<Vec<Arc<RunResult>>>,
    /// The runner's generation they belong to (a later start or a cancel ends them).
    generation: u64,
    count: usize,
    /// The workers they run on at once.
    workers: usize,
    /// Each run's progress, 0–1.
    fractions: RefCell<Vec<f64>>,
    results: RefCell<Vec<Option<Arc<RunResult>>>>,
    progress_at_ms: std::cell::Cell<f64>,
    streams: RefCell<Streams>,
    /// The calibrations known so far: given, or of the runs' teach cuts.
    known: RefCell<Vec<(TeachKey, Calibration)>>,
    /// The runs not sent yet, with their index in the specs.
    waiting: RefCell<VecDeque<(usize, RunSpec)>>,
}

impl RunsInWorkers {
    fn current(&self) -> bool {
        self.runner.generation.load(Ordering::SeqCst) == self.generation
    }

    /// The status while they run: their mean progress.
    fn stage(&self) -> RunStatus<Vec<Arc<RunResult>>> {
        let (count, workers) = (self.count, self.workers);
        let label = match (count, workers) {
            (1, _) => "Running in a worker".to_string(),
            (_, 1) => format!("{count} runs in a worker"),
            _ => format!("{count} runs on {workers} workers"),
        };
        RunStatus::Running {
            stage: label,
            fraction: self.fractions.borrow().iter().sum::<f64>() / count as f64,
        }
    }

    /// Adds `calibration`, of `spec`'s teach cut, to those known; the first of the runs to
    /// have one is the runner's [`Runner::taught`].
    fn learn(&self, spec: &RunSpec, calibration: &Calibration) {
        if self.runner.taught.with_untracked(Option::is_none) {
            let _ = self
                .runner
                .taught
                .try_set(Some((spec.clone(), calibration.clone())));
        }
        let Ok(key) = TeachKey::of(spec) else { return };
        let mut known = self.known.borrow_mut();
        if !known.iter().any(|(k, _)| *k == key) {
            known.push((key, calibration.clone()));
        }
    }
}

/// Sends the next waiting run of `runs` to the pool, with the calibrations known now.
fn send_next_run(runs: &Rc<RunsInWorkers>) {
    let Some((index, spec)) = runs.waiting.borrow_mut().pop_front() else {
        return;
    };
    let request = JobRequest::Runs(RunRequest::new(vec![spec.clone()], &runs.known.borrow()));
    let shared = runs.clone();
    let job = pool::submit(request, move |event| {
        let runs = &shared;
        if !runs.current() {
            return;
        }
        let (status, preview) = (runs.runner.status, runs.runner.preview);
        match event {
            JobEvent::Chunk(chunk) => {
                let first = chunk.calibration_json.is_some();
                let outcome = runs.streams.borrow_mut().receive(index, &spec, chunk);
                if first {
                    let streams = runs.streams.borrow();
                    if let Some(Some(streamed)) = streams.runs.get(index) {
                        runs.learn(&spec, streamed.calibration());
                    }
                }
                match outcome {
                    Err(message) => {
                        runs.runner.cancel();
                        let _ = status.try_set(RunStatus::Failed(message));
                    }
                    Ok(true) => {
                        let runs = runs.clone();
                        // The redraw a preview starts runs in a task of its own.
                        next_task(move || {
                            if runs.current() {
                                let so_far =
                                    runs.streams.borrow_mut().so_far(&runs.results.borrow());
                                let _ = preview.try_set(Some(so_far));
                            }
                        });
                    }
                    Ok(false) => {}
                }
            }
            JobEvent::Progress(p) => {
                runs.fractions.borrow_mut()[index] = p.fraction;
                // At most every PROGRESS_EVERY_MS.
                if now_ms() - runs.progress_at_ms.get() >= PROGRESS_EVERY_MS {
                    runs.progress_at_ms.set(now_ms());
                    let _ = status.try_set(runs.stage());
                }
            }
            JobEvent::Done(Answer::Runs(mut finished)) => {
                let run = finished.pop();
                if let Some(run) = &run {
                    runs.learn(&spec, &run.calibration);
                }
                runs.results.borrow_mut()[index] = run;
                runs.fractions.borrow_mut()[index] = 1.0;
                send_next_run(runs);
                let all: Option<Vec<_>> = runs.results.borrow().iter().cloned().collect();
                match all {
                    Some(all) => {
                        let runs = runs.clone();
                        // The redraw the output starts runs in a task of its own.
                        next_task(move || {
                            if runs.current() {
                                // The finished runs replace what was streamed of them.
                                let _ = preview.try_set(Some(all.clone()));
                                // An open lesson checks every finished run.
                                crate::web::pages::lessons::feed::publish(&all);
                                let _ = status.try_set(RunStatus::Done(all));
                            }
                        });
                    }
                    None => {
                        let _ = status.try_set(runs.stage());
                    }
                }
            }
            JobEvent::Done(_) => {
                runs.runner.cancel();
                let _ = status.try_set(RunStatus::Failed(ANOTHER_ANSWER.into()));
            }
            JobEvent::Failed(message) => {
                runs.runner.cancel();
                let _ = status.try_set(RunStatus::Failed(message));
            }
        }
    });
    runs.runner.track(job);
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

fn now_ms() -> f64 {
    window().performance().map_or(0.0, |p| p.now())
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
