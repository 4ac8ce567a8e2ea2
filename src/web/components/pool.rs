//! The computation workers: the lab's long computations off the page's thread — closed-loop
//! runs, the savings' reference runs, Tune's evaluations and teach cuts, paper 004's learning,
//! the Signal chain page's bench recording, the Machine page's open-loop recording, and the Logs
//! page's replays, signal chain and calibration fit — one Web Worker per core the browser
//! reports.
//!
//! Each worker instantiates the core-only module (`src/bin/cutlab-worker.rs`, no Leptos, no
//! pages) and does one [`JobRequest`] at a time. The first is started by index.html as the page
//! is read: it fetches and compiles the module for all of them while the page's own module
//! loads, so the first job finds it ready. Jobs wait in one queue and each goes to the next
//! free worker, so independent runs (a comparison's variants) compute at once on different
//! cores. A job's progress, the pieces of its trace as they are computed ([`JobEvent::Chunk`])
//! and its result reach the caller through its listener. The result is rebuilt on the page from
//! what the worker sends ([`RunParts`]; a recording's long lists of numbers as [`Packed`]
//! `Float64Array`s, transferred), equal bit for bit to a computation made here. Cancelling a
//! running job terminates its worker at once and starts a fresh one; a worker that throws fails
//! its job with the browser's message and is replaced, so a caller never waits for an answer
//! that will not come.
//!
//! The page's `<html>` element carries `data-busy-workers` (the workers computing now) and
//! `data-workers` (the pool's size), for a person's devtools and the browser tests.

use std::borrow::Cow;
use std::cell::RefCell;
use std::collections::{HashMap, VecDeque};
use std::sync::Arc;
use std::time::Duration;

use js_sys::{Array, Float64Array, Reflect};
use leptos::prelude::{set_timeout, window};
use wasm_bindgen::prelude::{Closure, JsCast, JsValue};
use web_sys::{ErrorEvent, MessageEvent, Worker};

use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::lab::RunResult;
use crate::closed_loop::recording_jobs::{
    unpack_calibrations, unpack_open_loop_recording, unpack_phase_recording, Packed,
};
use crate::closed_loop::references::References;
use crate::closed_loop::transfer::{
    learning_from_json, references_from_json, JobRequest, RunParts, TraceChunk,
};
use crate::closed_loop::trial_cuts::PresetLearning;
use crate::log::analysis::ChainOutput;
use crate::log::calibration::LogFit;
use crate::log::transfer::{unpack_chain_output, unpack_log_fit, LogJobRequest, ReplayParts};
use crate::plant::recording::{OpenLoopRecording, PhaseRecording};
use crate::tuning::{simulated_teach_in, TeachIn};
use crate::work::Progress;

/// The most workers the pool starts, whatever the browser reports: each holds a module and its
/// runs' memory, and a comparison has at most four variants.
pub const MAX_WORKERS: usize = 8;

/// Every worker's loader (`www/worker-loader.js`, copied by Trunk): it instantiates the module
/// its first message gives ([`hand_module`]) with the worker's script, `cutlab-worker.js`.
const WORKER_LOADER: &str = "worker-loader.js";
/// The worker's module as Trunk writes it (`data-type="worker"` keeps its name).
const WORKER_MODULE: &str = "cutlab-worker_bg.wasm";
/// Where index.html leaves the first worker, started from [`WORKER_LOADER`] as the page is read,
/// for the pool to take as its first; with `cutlabReady` set once it has posted `ready`, and
/// `cutlabFailed` if it threw before the pool took it. (index.html names both files again:
/// change them together.)
const FIRST_WORKER: &str = "cutlabFirstWorker";
/// Where index.html leaves the promise of the workers' module, compiled by the first worker.
const COMPILED_MODULE: &str = "cutlabWorkerModule";

/// What a job tells its caller.
pub enum JobEvent {
    /// How far it has got.
    Progress(Progress),
    /// The next piece of the trace of a run under way (the worker streams it as the run goes).
    Chunk(TraceChunk),
    /// Its answer.
    Done(Answer),
    /// Why it could not be done (a worker that threw included).
    Failed(String),
}

/// What a finished job gives, by the kind of its [`JobRequest`].
pub enum Answer {
    /// The runs, in the order asked for.
    Runs(Vec<Arc<RunResult>>),
    /// A scenario's references.
    References(References),
    /// Paper 004's network learned on a preset's trial cuts.
    Learning(Box<PresetLearning>),
    /// Paper 000's bench recording.
    BenchRecording(Arc<PhaseRecording>),
    /// An open-loop recording of a preset's machine.
    OpenLoopRecording(Arc<OpenLoopRecording>),
    /// A teach-in's proposals, one per scenario, derived here from the worker's teach cuts.
    TeachIns(Vec<TeachIn>),
    /// Replays' traces, in the order of the request's controllers (the page rebuilds each with
    /// the replay it prepares, [`ReplayParts::into_result`]).
    Replays(Vec<ReplayParts>),
    /// The Logs page's signal chain on a column.
    Chain(Arc<ChainOutput>),
    /// A calibration fitted to a log.
    LogFit(Arc<LogFit>),
}

/// What a job's answer is rebuilt from: for runs, their specs.
#[derive(Clone)]
enum Expecting {
    Runs(Vec<RunSpec>),
    References,
    Learning,
    Replays,
    /// A packed answer ([`Packed`]) of one of these kinds.
    Packed(PackedKind),
}

/// What a packed answer is rebuilt into.
#[derive(Clone)]
enum PackedKind {
    BenchRecording,
    OpenLoopRecording,
    /// The teach-ins of these scenarios.
    TeachIns(Vec<RunSpec>),
    Chain,
    LogFit,
}

impl PackedKind {
    /// The answer `packed` holds.
    fn answer(self, packed: Packed) -> Result<Answer, String> {
        Ok(match self {
            Self::BenchRecording => {
                Answer::BenchRecording(Arc::new(unpack_phase_recording(packed)?))
            }
            Self::OpenLoopRecording => {
                Answer::OpenLoopRecording(Arc::new(unpack_open_loop_recording(packed)?))
            }
            Self::TeachIns(specs) => {
                let calibrations = unpack_calibrations(packed, specs.len())?;
                let teach_ins = specs
                    .iter()
                    .zip(&calibrations)
                    .map(|(spec, c)| simulated_teach_in(spec, c).map_err(|e| e.to_string()))
                    .collect::<Result<_, _>>()?;
                Answer::TeachIns(teach_ins)
            }
            Self::Chain => Answer::Chain(Arc::new(unpack_chain_output(packed)?)),
            Self::LogFit => Answer::LogFit(Arc::new(unpack_log_fit(packed)?)),
        })
    }
}

/// A job given to the pool.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct JobId(u64);

type Listener = Box<dyn FnMut(JobEvent)>;

/// A job waiting for a worker.
struct Queued {
    id: u64,
    expecting: Expecting,
    request_json: String,
    /// The message's field the JSON goes in: `request` for a [`JobRequest`], `log_job` for a
    /// [`LogJobRequest`].
    field: &'static str,
    /// Numbers sent beside the JSON (`Float64Array`s, moved to the worker with the request).
    numbers: Array,
}

/// One worker and what it is doing.
struct Slot {
    worker: Worker,
    /// Which worker of this slot it is (a replaced worker's late events are ignored).
    serial: u64,
    /// The module has loaded: requests posted before this would be lost.
    ready: bool,
    /// The job it computes, and what its answer is rebuilt from.
    running: Option<(u64, Expecting)>,
    _on_message: Closure<dyn FnMut(MessageEvent)>,
    _on_error: Closure<dyn FnMut(ErrorEvent)>,
}

#[derive(Default)]
struct Pool {
    slots: Vec<Option<Slot>>,
    queue: VecDeque<Queued>,
    listeners: HashMap<u64, Listener>,
    next_id: u64,
    next_serial: u64,
}

thread_local! {
    static POOL: RefCell<Pool> = RefCell::default();
}

/// The workers the pool runs: one per core the browser reports, at least one, at most
/// [`MAX_WORKERS`].
pub fn pool_size() -> usize {
    let cores = window().navigator().hardware_concurrency();
    if cores.is_finite() {
        (cores as usize).clamp(1, MAX_WORKERS)
    } else {
        1
    }
}

/// Queues `request` as one job; `listener` hears its progress (and a run's trace as it comes),
/// then its answer or why it failed, never in the task that submits it.
pub fn submit(request: JobRequest, listener: impl FnMut(JobEvent) + 'static) -> JobId {
    let expecting = match &request {
        JobRequest::Runs(runs) => Expecting::Runs(runs.specs.clone()),
        JobRequest::References(_) => Expecting::References,
        JobRequest::Learning(_) => Expecting::Learning,
        JobRequest::Bench(_) => Expecting::Packed(PackedKind::BenchRecording),
        JobRequest::OpenLoop(_) => Expecting::Packed(PackedKind::OpenLoopRecording),
        JobRequest::TeachCuts(request) => {
            Expecting::Packed(PackedKind::TeachIns(request.specs.clone()))
        }
    };
    enqueue("request", request.to_json(), expecting, &[], listener)
}

/// Queues a job on a log as one job, as [`submit`] does, with `numbers` (the log's columns,
/// [`crate::log::transfer::LogNumbers`]) sent beside its JSON: each copied once, into an array
/// moved to the worker with the request. A replay is answered by [`Answer::Replays`], the signal
/// chain by [`Answer::Chain`], a fit by [`Answer::LogFit`].
pub fn submit_log_job(
    request: &LogJobRequest,
    numbers: &[Cow<[f64]>],
    listener: impl FnMut(JobEvent) + 'static,
) -> JobId {
    let expecting = match request {
        LogJobRequest::Replay(_) => Expecting::Replays,
        LogJobRequest::Chain(_) => Expecting::Packed(PackedKind::Chain),
        LogJobRequest::Fit(_) => Expecting::Packed(PackedKind::LogFit),
    };
    enqueue("log_job", request.to_json(), expecting, numbers, listener)
}

/// Queues a job whose JSON goes in the message's `field`.
fn enqueue(
    field: &'static str,
    json: Result<String, String>,
    expecting: Expecting,
    numbers: &[Cow<[f64]>],
    mut listener: impl FnMut(JobEvent) + 'static,
) -> JobId {
    let id = POOL.with(|pool| {
        let mut pool = pool.borrow_mut();
        pool.next_id += 1;
        pool.next_id
    });
    match json {
        Ok(request_json) => {
            let sent = Array::new();
            for column in numbers {
                sent.push(&Float64Array::from(&**column));
            }
            POOL.with(|pool| {
                let mut pool = pool.borrow_mut();
                pool.listeners.insert(id, Box::new(listener));
                pool.queue.push_back(Queued {
                    id,
                    expecting,
                    request_json,
                    field,
                    numbers: sent,
                });
            });
            start_workers();
            dispatch();
        }
        Err(message) => set_timeout(move || listener(JobEvent::Failed(message)), Duration::ZERO),
    }
    JobId(id)
}

/// Drops job `id`: out of the queue if it waits, its worker terminated (and a fresh one
/// started) if it runs. Its listener hears nothing more.
pub fn cancel(JobId(id): JobId) {
    let running_in = POOL.with(|pool| {
        let mut pool = pool.borrow_mut();
        pool.listeners.remove(&id);
        pool.queue.retain(|q| q.id != id);
        pool.slots.iter().position(|slot| {
            slot.as_ref()
                .and_then(|s| s.running.as_ref())
                .is_some_and(|(job, _)| *job == id)
        })
    });
    if let Some(index) = running_in {
        replace_worker(index);
    }
    show_busy();
}

/// Starts the pool's workers that are not running yet. The page calls it as it loads (nearly
/// every page computes), so that the first job finds them ready; a job submitted calls it again
/// for any worker that could not start.
pub fn start_workers() {
    let size = pool_size();
    let missing: Vec<usize> = POOL.with(|pool| {
        let mut pool = pool.borrow_mut();
        if pool.slots.len() < size {
            pool.slots.resize_with(size, || None);
        }
        (0..pool.slots.len())
            .filter(|&i| pool.slots[i].is_none())
            .collect()
    });
    for index in missing {
        replace_worker(index);
    }
    set_root_attribute("data-workers", &size.to_string());
}

/// Terminates slot `index`'s worker, if any, and starts a fresh one there; a worker that cannot
/// be started fails the jobs waiting (none would ever run).
fn replace_worker(index: usize) {
    let old = POOL.with(|pool| {
        let mut pool = pool.borrow_mut();
        pool.slots.get_mut(index).and_then(Option::take)
    });
    if let Some(old) = old {
        old.worker.terminate();
    }
    match spawn(index) {
        Ok(slot) => POOL.with(|pool| {
            if let Some(place) = pool.borrow_mut().slots.get_mut(index) {
                *place = Some(slot);
            }
        }),
        Err(message) => fail_waiting(&format!("a computation worker could not start: {message}")),
    }
}

/// A new worker for slot `index`: index.html's first worker, the first time it is asked for,
/// unless that one failed already.
fn spawn(index: usize) -> Result<Slot, String> {
    let (worker, ready) = match first_worker() {
        Some(first) => first,
        None => (module_worker()?, false),
    };
    let serial = POOL.with(|pool| {
        let mut pool = pool.borrow_mut();
        pool.next_serial += 1;
        pool.next_serial
    });
    let on_message = Closure::<dyn FnMut(MessageEvent)>::new(move |event: MessageEvent| {
        on_message(index, serial, &event.data());
    });
    let on_error = Closure::<dyn FnMut(ErrorEvent)>::new(move |event: ErrorEvent| {
        // Reported here, in the page, as the job's failure.
        event.prevent_default();
        on_error(index, serial, &event.message());
    });
    worker.set_onmessage(Some(on_message.as_ref().unchecked_ref()));
    worker.set_onerror(Some(on_error.as_ref().unchecked_ref()));
    Ok(Slot {
        worker,
        serial,
        ready,
        running: None,
        _on_message: on_message,
        _on_error: on_error,
    })
}

/// A new worker of the computation module (its first message is `ready`, its requests those of
/// `src/bin/cutlab-worker.rs`). The pool's own, and one a caller keeps outside the pool for a
/// computation that lasts as long as a page wants it; terminating that one is the caller's.
pub fn module_worker() -> Result<Worker, String> {
    let worker =
        Worker::new(&absolute(WORKER_LOADER)?).map_err(|e| crate::web::js::describe(&e))?;
    hand_module(&worker)?;
    Ok(worker)
}

/// index.html's first worker, taken once, with whether it is ready; `None` once taken, where the
/// page has none, or where it threw before the pool took it (terminated here: it has no module).
fn first_worker() -> Option<(Worker, bool)> {
    let window = window();
    let worker = Reflect::get(&window, &FIRST_WORKER.into())
        .ok()?
        .dyn_into::<Worker>()
        .ok()?;
    let _ = Reflect::delete_property(&window, &FIRST_WORKER.into());
    let flag = |name: &str| {
        Reflect::get(&worker, &name.into())
            .map(|v| v.is_truthy())
            .unwrap_or(false)
    };
    if flag("cutlabFailed") {
        worker.terminate();
        return None;
    }
    let ready = flag("cutlabReady");
    Some((worker, ready))
}

/// Gives a new worker its module: the one the first worker compiled (once, for every worker
/// the page starts, a replaced one included), or, where that is missing or failed, the module's
/// address, which the worker then fetches and compiles itself.
fn hand_module(worker: &Worker) -> Result<(), String> {
    let address = JsValue::from_str(&absolute(WORKER_MODULE)?);
    let compiled = Reflect::get(&window(), &COMPILED_MODULE.into())
        .ok()
        .and_then(|promise| promise.dyn_into::<js_sys::Promise>().ok());
    let Some(compiled) = compiled else {
        return worker
            .post_message(&address)
            .map_err(|e| crate::web::js::describe(&e));
    };
    let worker = worker.clone();
    wasm_bindgen_futures::spawn_local(async move {
        let module = wasm_bindgen_futures::JsFuture::from(compiled)
            .await
            .unwrap_or(address);
        // A worker terminated meanwhile (its job cancelled) ignores it.
        let _ = worker.post_message(&module);
    });
    Ok(())
}

/// `name` as an address on the page's server.
fn absolute(name: &str) -> Result<String, String> {
    let page = window()
        .location()
        .href()
        .map_err(|e| crate::web::js::describe(&e))?;
    web_sys::Url::new_with_base(name, &page)
        .map(|u| u.href())
        .map_err(|e| crate::web::js::describe(&e))
}

/// Gives waiting jobs to the ready workers that are free.
fn dispatch() {
    loop {
        let posted = POOL.with(|pool| {
            let mut pool = pool.borrow_mut();
            let free = pool
                .slots
                .iter()
                .position(|s| s.as_ref().is_some_and(|s| s.ready && s.running.is_none()))?;
            let job = pool.queue.pop_front()?;
            let slot = pool.slots.get_mut(free)?.as_mut()?;
            let message = js_sys::Object::new();
            let _ = Reflect::set(&message, &"job".into(), &(job.id as f64).into());
            let _ = Reflect::set(&message, &job.field.into(), &job.request_json.into());
            let sent = if job.numbers.length() == 0 {
                slot.worker.post_message(&message)
            } else {
                let moved = Array::new();
                for numbers in job.numbers.iter() {
                    moved.push(&numbers.unchecked_into::<Float64Array>().buffer());
                }
                let _ = Reflect::set(&message, &"numbers".into(), &job.numbers);
                slot.worker.post_message_with_transfer(&message, &moved)
            };
            slot.running = Some((job.id, job.expecting));
            Some(sent.map_err(|e| (free, job.id, crate::web::js::describe(&e))))
        });
        match posted {
            None => break,
            Some(Ok(())) => {}
            Some(Err((slot, job, message))) => {
                finish(
                    slot,
                    job,
                    Err(format!("the run could not be sent to a worker: {message}")),
                );
            }
        }
    }
    show_busy();
}

/// What worker `serial` of slot `index` posted.
fn on_message(index: usize, serial: u64, data: &JsValue) {
    let field = |name: &str| Reflect::get(data, &name.into()).unwrap_or(JsValue::UNDEFINED);
    let job = field("job").as_f64().map(|j| j as u64);
    let kind = field("kind").as_string().unwrap_or_default();
    // The job this worker computes, if the message is from the slot's current worker.
    let running = POOL.with(|pool| {
        let mut pool = pool.borrow_mut();
        let slot = pool.slots.get_mut(index)?.as_mut()?;
        if slot.serial != serial {
            return None;
        }
        if kind == "ready" {
            slot.ready = true;
        }
        slot.running
            .as_ref()
            .map(|(id, expecting)| (*id, expecting.clone()))
    });
    match (kind.as_str(), running) {
        ("ready", _) => dispatch(),
        ("progress", Some((id, _))) if job == Some(id) => {
            let stage = field("stage").as_string().unwrap_or_default();
            let fraction = field("fraction").as_f64().unwrap_or(0.0);
            tell(id, JobEvent::Progress(Progress::new(stage, fraction)));
        }
        ("chunk", Some((id, _))) if job == Some(id) => match received_chunk(&field) {
            Ok(chunk) => tell(id, JobEvent::Chunk(chunk)),
            Err(message) => finish(index, id, Err(message)),
        },
        ("done", Some((id, expecting))) if job == Some(id) => {
            let answer = match expecting {
                Expecting::Runs(specs) => {
                    received_runs(&Array::from(&field("runs")), specs).map(Answer::Runs)
                }
                Expecting::References => {
                    references_from_json(&field("references").as_string().unwrap_or_default())
                        .map(Answer::References)
                }
                Expecting::Learning => {
                    learning_from_json(&field("learning").as_string().unwrap_or_default())
                        .map(|l| Answer::Learning(Box::new(l)))
                }
                Expecting::Packed(kind) => {
                    received_packed(&field).and_then(|packed| kind.answer(packed))
                }
                Expecting::Replays => {
                    received_replays(&Array::from(&field("replays"))).map(Answer::Replays)
                }
            };
            finish(index, id, answer);
        }
        ("failed", Some((id, _))) if job == Some(id) => {
            let message = field("message").as_string().unwrap_or_default();
            finish(index, id, Err(message));
        }
        _ => {}
    }
}

/// The piece of a trace a worker sent, `field` reading the message's fields.
fn received_chunk(field: &dyn Fn(&str) -> JsValue) -> Result<TraceChunk, String> {
    let numbers = |name: &str| numbers_in(field(name), "a piece of the worker's trace", name);
    Ok(TraceChunk {
        run: field("run").as_f64().unwrap_or(0.0) as usize,
        calibration_json: field("calibration").as_string(),
        rows: numbers("rows")?,
        terms: numbers("terms")?,
    })
}

/// A packed answer a worker sent, `field` reading the message's fields: `json`, and `arrays`
/// of `Float64Array`s.
fn received_packed(field: &dyn Fn(&str) -> JsValue) -> Result<Packed, String> {
    let arrays = field("arrays")
        .dyn_into::<Array>()
        .map_err(|_| "the worker's answer lacks its numbers".to_string())?
        .iter()
        .map(|a| {
            a.dyn_into::<Float64Array>()
                .map(|a| a.to_vec())
                .map_err(|_| "the worker's answer holds a list that is not numbers".to_string())
        })
        .collect::<Result<_, _>>()?;
    Ok(Packed {
        json: field("json").as_string().unwrap_or_default(),
        arrays,
    })
}

/// The runs a worker sent, rebuilt for `specs`.
fn received_runs(runs: &Array, specs: Vec<RunSpec>) -> Result<Vec<Arc<RunResult>>, String> {
    if runs.length() as usize != specs.len() {
        return Err(format!(
            "the worker sent {} runs for {} asked for",
            runs.length(),
            specs.len()
        ));
    }
    runs.iter()
        .zip(specs)
        .map(|(run, spec)| {
            let field = |name: &str| Reflect::get(&run, &name.into()).unwrap_or(JsValue::UNDEFINED);
            let numbers = |name: &str| numbers_in(field(name), "the worker's run", name);
            RunParts {
                header_json: field("header").as_string().unwrap_or_default(),
                rows: numbers("rows")?,
                terms: numbers("terms")?,
            }
            .into_result(spec)
            .map(Arc::new)
        })
        .collect()
}

/// The numbers of `value` (a `Float64Array`), or why not: `whose` lacks its `name`.
fn numbers_in(value: JsValue, whose: &str, name: &str) -> Result<Vec<f64>, String> {
    value
        .dyn_into::<Float64Array>()
        .map(|a| a.to_vec())
        .map_err(|_| format!("{whose} lacks its {name}"))
}

/// The replays' traces a worker sent.
fn received_replays(replays: &Array) -> Result<Vec<ReplayParts>, String> {
    replays
        .iter()
        .map(|replay| {
            let field =
                |name: &str| Reflect::get(&replay, &name.into()).unwrap_or(JsValue::UNDEFINED);
            let numbers = |name: &str| numbers_in(field(name), "the worker's replay", name);
            Ok(ReplayParts {
                header_json: field("header").as_string().unwrap_or_default(),
                rows: numbers("rows")?,
                terms: numbers("terms")?,
            })
        })
        .collect()
}

/// Worker `serial` of slot `index` threw (a bug or out of memory): its job fails with the
/// browser's message and a fresh worker takes its place. A worker that threw before it was ready
/// could not load its module; the jobs waiting fail with it rather than wait for a worker that
/// will not come.
fn on_error(index: usize, serial: u64, message: &str) {
    // The job is taken off the slot before its listener hears, so a listener that cancels it
    // does not replace the worker a second time.
    let state = POOL.with(|pool| {
        let mut pool = pool.borrow_mut();
        let slot = pool.slots.get_mut(index)?.as_mut()?;
        (slot.serial == serial).then(|| (slot.ready, slot.running.take().map(|(id, _)| id)))
    });
    let Some((ready, running)) = state else {
        return;
    };
    let why = format!("the computation worker stopped: {message}");
    if let Some(id) = running {
        tell(id, JobEvent::Failed(why.clone()));
    }
    if ready {
        replace_worker(index);
        dispatch();
    } else {
        let old = POOL.with(|pool| {
            pool.borrow_mut()
                .slots
                .get_mut(index)
                .and_then(Option::take)
        });
        if let Some(old) = old {
            old.worker.terminate();
        }
        fail_waiting(&why);
    }
    show_busy();
}

/// Job `id` on slot `index` is over: its listener hears the outcome and the slot takes the next.
fn finish(index: usize, id: u64, outcome: Result<Answer, String>) {
    POOL.with(|pool| {
        if let Some(Some(slot)) = pool.borrow_mut().slots.get_mut(index) {
            if slot.running.as_ref().is_some_and(|(job, _)| *job == id) {
                slot.running = None;
            }
        }
    });
    tell(
        id,
        match outcome {
            Ok(runs) => JobEvent::Done(runs),
            Err(message) => JobEvent::Failed(message),
        },
    );
    dispatch();
}

/// Fails every job waiting for a worker.
fn fail_waiting(message: &str) {
    let waiting: Vec<u64> =
        POOL.with(|pool| pool.borrow_mut().queue.drain(..).map(|q| q.id).collect());
    for id in waiting {
        tell(id, JobEvent::Failed(message.to_string()));
    }
}

/// Tells job `id`'s listener, outside the pool's borrow (a listener may submit or cancel); a
/// final event drops the listener.
fn tell(id: u64, event: JobEvent) {
    let last = !matches!(event, JobEvent::Progress(_) | JobEvent::Chunk(_));
    let Some(mut listener) = POOL.with(|pool| pool.borrow_mut().listeners.remove(&id)) else {
        return;
    };
    listener(event);
    if !last {
        // Kept unless the listener cancelled its job meanwhile.
        POOL.with(|pool| {
            let mut pool = pool.borrow_mut();
            let alive = pool.queue.iter().any(|q| q.id == id)
                || pool
                    .slots
                    .iter()
                    .flatten()
                    .any(|s| s.running.as_ref().is_some_and(|(job, _)| *job == id));
            if alive {
                pool.listeners.entry(id).or_insert(listener);
            }
        });
    }
}

/// Publishes how many workers compute now.
fn show_busy() {
    let busy = POOL.with(|pool| {
        pool.borrow()
            .slots
            .iter()
            .flatten()
            .filter(|s| s.running.is_some())
            .count()
    });
    set_root_attribute("data-busy-workers", &busy.to_string());
}

fn set_root_attribute(name: &str, value: &str) {
    if let Some(root) = window().document().and_then(|d| d.document_element()) {
        let _ = root.set_attribute(name, value);
    }
}
