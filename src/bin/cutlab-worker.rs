//! The browser lab's computation worker, built by Trunk (`data-type="worker"` in index.html) from
//! the core alone: no Leptos, no pages. The page's worker pool (`cutlab::web::components::pool`)
//! starts one per core; each runs one request at a time and answers with messages:
//!
//! | message | fields |
//! |---|---|
//! | `ready` | — (the module is loaded: requests posted before this would be lost) |
//! | `progress` | `job`, `stage`, `fraction` (about ten times a second) |
//! | `chunk` | `job`, `run`, `rows`, `terms`, and with a run's first chunk `calibration`: the trace rows added since the last chunk ([`TraceChunk`](cutlab::closed_loop::transfer::TraceChunk)), about every `CHUNK_EVERY_MS` (100 ms) once the closed loop runs |
//! | `done` | `job`, and for runs `runs`: one `{ header, rows, terms }` per spec ([`RunParts`](cutlab::closed_loop::transfer::RunParts); `rows` and `terms` are `Float64Array`s, transferred); for references `references`, as JSON; for a bench or open-loop recording, teach cuts, a log's signal chain or a calibration fitted to a log `json` and `arrays`, a list of `Float64Array`s, transferred (`cutlab::closed_loop::recording_jobs::Packed`); for replays `replays`: one `{ header, rows, terms }` per controller ([`ReplayParts`](cutlab::log::transfer::ReplayParts), the same way) |
//! | `failed` | `job`, `message` (shown to a person as is) |
//!
//! A request is `{ job, request }`, `request` being a [`JobRequest`](cutlab::closed_loop::transfer::JobRequest) as JSON: closed-loop runs, a
//! scenario's fixed-feed references, paper 004's learning, paper 000's bench recording (Signal
//! chain), a preset's open-loop recording (Machine) or a teach-in's teach cuts (Tune); or
//! `{ job, log_job, numbers }`, `log_job` being a [`LogJobRequest`](cutlab::log::transfer::LogJobRequest) as JSON (the Logs page's
//! replays, signal chain or calibration fit, a layer above the loop's protocol) and `numbers`
//! one `Float64Array` per column of the log it sends. The job is done in one go: the page
//! cancels it by terminating the worker.
//!
//! A worker the Hardware page starts for its virtual device (outside the pool) gets instead
//! `{ device_start }`, a `DeviceStart` as JSON, then `{ device_bytes }`, each a `Uint8Array` of
//! what the host wrote; it runs the device on its own timer (`cutlab::protocol::device_worker`'s
//! `ClockedDevice`, every `VIRTUAL_TICK_MS`) and answers `{ kind: "device_bytes", bytes }` (transferred) with what the
//! device sent, or `{ kind: "device_failed", message }` if it cannot start. The page switches the
//! device off by terminating the worker.

#[cfg(target_arch = "wasm32")]
fn main() {
    worker::start();
}

#[cfg(not(target_arch = "wasm32"))]
fn main() {
    eprintln!("cutlab-worker runs only in a browser's Web Worker (trunk builds it for wasm32)");
}

#[cfg(target_arch = "wasm32")]
mod worker {
    use cutlab::closed_loop::recording_jobs::{
        pack_calibrations, pack_open_loop_recording, pack_phase_recording, Packed,
    };
    use cutlab::closed_loop::transfer::{
        learning_to_json, references_to_json, JobRequest, LearningRequest, ReferenceRequest,
        RunParts, RunRequest, TraceChunk, TraceStream,
    };
    use cutlab::log::transfer::{
        pack_chain_output, pack_log_fit, LogJobRequest, ReplayParts, ReplayRequest,
    };
    use cutlab::work::Work;
    use js_sys::{Array, Float64Array, Object, Reflect};
    use wasm_bindgen::prelude::{Closure, JsCast, JsValue};
    use web_sys::{DedicatedWorkerGlobalScope, MessageEvent};

    /// How often progress is posted: a page shows it, and more would only cost messages.
    const PROGRESS_EVERY_MS: f64 = 100.0;

    /// How often the trace so far is posted after its first chunk (sent as soon as the closed
    /// loop has traced anything, so a long run shows at once). The page redraws a run under way
    /// every half second (`PREVIEW_EVERY_MS` in `web::components::runner`) from what has arrived
    /// and the finished run comes whole, so chunks in between only cost the page's thread work
    /// beside the runs.
    pub const CHUNK_EVERY_MS: f64 = 100.0;

    /// Control periods advanced between looks at the clock: about a simulated second, a few ms
    /// in the worker, so a run's first piece leaves a few ms after its closed loop starts and
    /// later pieces keep to [`CHUNK_EVERY_MS`]. (200 periods, 8–12 simulated s, held the first
    /// piece of an edited run back 30–50 ms.) A budget only says where work may pause: the
    /// results are the same whatever it is ([`Work`]).
    const BUDGET: usize = 20;

    pub fn start() {
        let scope: DedicatedWorkerGlobalScope = js_sys::global().unchecked_into();
        let replies = scope.clone();
        let on_message = Closure::<dyn FnMut(MessageEvent)>::new(move |event: MessageEvent| {
            let data = event.data();
            if device::handled(&replies, &data) {
                return;
            }
            let job = Reflect::get(&data, &"job".into())
                .ok()
                .and_then(|j| j.as_f64())
                .unwrap_or(-1.0);
            let log_job = Reflect::get(&data, &"log_job".into())
                .ok()
                .and_then(|r| r.as_string());
            let outcome = match log_job {
                Some(json) => LogJobRequest::from_json(&json)
                    .and_then(|request| work_on_log(&replies, job, request, &data)),
                None => Reflect::get(&data, &"request".into())
                    .ok()
                    .and_then(|r| r.as_string())
                    .ok_or_else(|| "the worker received a request without a run".to_string())
                    .and_then(|json| run(&replies, job, &json)),
            };
            if let Err(message) = outcome {
                // A failure that cannot be posted either leaves the page to its onerror.
                let _ = post(
                    &replies,
                    &[
                        ("kind", "failed".into()),
                        ("job", job.into()),
                        ("message", message.into()),
                    ],
                    None,
                );
            }
        });
        scope.set_onmessage(Some(on_message.as_ref().unchecked_ref()));
        // The handler lives as long as the worker.
        on_message.forget();
        let _ = post(&scope, &[("kind", "ready".into())], None);
    }

    /// Does `json`'s job, posting progress and, at the end, its answer.
    fn run(scope: &DedicatedWorkerGlobalScope, job: f64, json: &str) -> Result<(), String> {
        match JobRequest::from_json(json)? {
            JobRequest::Runs(request) => run_loops(scope, job, request),
            JobRequest::References(request) => find_references(scope, job, *request),
            JobRequest::Learning(request) => learn_network(scope, job, &request),
            JobRequest::Bench(request) => {
                let work = request.into_work()?;
                answer_packed(scope, job, work, |r| pack_phase_recording(&r))
            }
            JobRequest::OpenLoop(request) => {
                let work = request.into_work()?;
                answer_packed(scope, job, work, |r| pack_open_loop_recording(&r))
            }
            JobRequest::TeachCuts(request) => {
                answer_packed(scope, job, request.into_work(), |c| pack_calibrations(&c))
            }
        }
    }

    /// Does a job on the log whose numbers came with the request (`data`, the whole message)
    /// and posts its answer.
    fn work_on_log(
        scope: &DedicatedWorkerGlobalScope,
        job: f64,
        request: LogJobRequest,
        data: &JsValue,
    ) -> Result<(), String> {
        let numbers = Reflect::get(data, &"numbers".into())
            .ok()
            .filter(Array::is_array)
            .map(|a| Array::from(&a))
            .ok_or("the worker received a job on a log without the log's numbers")?
            .iter()
            .map(|column| {
                column
                    .dyn_into::<Float64Array>()
                    .map(|a| a.to_vec())
                    .map_err(|_| "a column of the log's numbers is not an array of numbers")
            })
            .collect::<Result<Vec<_>, _>>()?;
        match request {
            LogJobRequest::Replay(request) => replay_on_log(scope, job, request, numbers),
            LogJobRequest::Chain(request) => {
                answer_packed(scope, job, request.into_work(numbers)?, pack_chain_output)
            }
            LogJobRequest::Fit(request) => {
                answer_packed(scope, job, request.into_work(numbers)?, pack_log_fit)
            }
        }
    }

    /// Replays controllers on the log rebuilt from `numbers`, and posts their traces.
    fn replay_on_log(
        scope: &DedicatedWorkerGlobalScope,
        job: f64,
        request: ReplayRequest,
        numbers: Vec<Vec<f64>>,
    ) -> Result<(), String> {
        let mut work = request.into_work(numbers)?;
        let replays = advance_to_end(scope, job, &mut work, |_, _| Ok(()))?;
        let sent = Array::new();
        let transfer = Array::new();
        for replay in &replays {
            let parts = ReplayParts::of(replay)?;
            sent.push(&trace_parts(
                parts.header_json,
                &parts.rows,
                &parts.terms,
                &transfer,
            ));
        }
        let fields = [
            ("kind", "done".into()),
            ("job", job.into()),
            ("replays", sent.into()),
        ];
        if post(scope, &fields, Some(&transfer)) {
            Ok(())
        } else {
            Err("the worker could not send the replays".into())
        }
    }

    /// Learns paper 004's network on a preset's trial cuts and posts it (a few closed-loop
    /// runs, so no progress between them).
    fn learn_network(
        scope: &DedicatedWorkerGlobalScope,
        job: f64,
        request: &LearningRequest,
    ) -> Result<(), String> {
        let learning = learning_to_json(&request.learn()?)?;
        let fields = [
            ("kind", "done".into()),
            ("job", job.into()),
            ("learning", learning.into()),
        ];
        if post(scope, &fields, None) {
            Ok(())
        } else {
            Err("the worker could not send the learning".into())
        }
    }

    /// Advances `work` to its end, posting its progress about every [`PROGRESS_EVERY_MS`] and
    /// calling `between` after each piece (with the time).
    fn advance_to_end<W: Work>(
        scope: &DedicatedWorkerGlobalScope,
        job: f64,
        work: &mut W,
        mut between: impl FnMut(&W, f64) -> Result<(), String>,
    ) -> Result<W::Output, String> {
        let mut posted_at_ms = f64::NEG_INFINITY;
        while !work.advance(BUDGET).map_err(|e| e.to_string())? {
            let now_ms = js_sys::Date::now();
            between(work, now_ms)?;
            if now_ms - posted_at_ms >= PROGRESS_EVERY_MS {
                posted_at_ms = now_ms;
                let progress = work.progress();
                let _ = post(
                    scope,
                    &[
                        ("kind", "progress".into()),
                        ("job", job.into()),
                        ("stage", progress.stage.into()),
                        ("fraction", progress.fraction.into()),
                    ],
                    None,
                );
            }
        }
        work.finish().map_err(|e| e.to_string())
    }

    /// Does `work` (a recording, or teach cuts) posting its progress, and posts its output
    /// `pack`ed: the lists of numbers transferred, not copied.
    fn answer_packed<W: Work>(
        scope: &DedicatedWorkerGlobalScope,
        job: f64,
        mut work: W,
        pack: impl FnOnce(W::Output) -> Result<Packed, String>,
    ) -> Result<(), String> {
        let packed = pack(advance_to_end(scope, job, &mut work, |_, _| Ok(()))?)?;
        let arrays = Array::new();
        let transfer = Array::new();
        for numbers in &packed.arrays {
            let array = Float64Array::from(numbers.as_slice());
            transfer.push(&array.buffer());
            arrays.push(&array);
        }
        let fields = [
            ("kind", "done".into()),
            ("job", job.into()),
            ("json", packed.json.into()),
            ("arrays", arrays.into()),
        ];
        if post(scope, &fields, Some(&transfer)) {
            Ok(())
        } else {
            Err("the worker could not send its answer".into())
        }
    }

    /// Finds a scenario's references and posts them.
    fn find_references(
        scope: &DedicatedWorkerGlobalScope,
        job: f64,
        request: ReferenceRequest,
    ) -> Result<(), String> {
        let mut work = request.into_work()?;
        let found = advance_to_end(scope, job, &mut work, |_, _| Ok(()))?;
        let fields = [
            ("kind", "done".into()),
            ("job", job.into()),
            ("references", references_to_json(&found)?.into()),
        ];
        if post(scope, &fields, None) {
            Ok(())
        } else {
            Err("the worker could not send the references".into())
        }
    }

    /// Runs closed loops, streaming each one's trace as it goes, and posts the finished runs.
    fn run_loops(
        scope: &DedicatedWorkerGlobalScope,
        job: f64,
        request: RunRequest,
    ) -> Result<(), String> {
        let mut work = request.into_work();
        let mut stream = TraceStream::default();
        let mut streamed_at_ms = f64::NEG_INFINITY;
        let runs = advance_to_end(scope, job, &mut work, |work, now_ms| {
            if now_ms - streamed_at_ms >= CHUNK_EVERY_MS {
                if let Some(chunk) = stream.next_chunk(work)? {
                    streamed_at_ms = now_ms;
                    post_chunk(scope, job, chunk);
                }
            }
            Ok(())
        })?;
        let sent = Array::new();
        let transfer = Array::new();
        for run in &runs {
            let parts = RunParts::of(run)?;
            sent.push(&trace_parts(
                parts.header_json,
                &parts.rows,
                &parts.terms,
                &transfer,
            ));
        }
        if post(
            scope,
            &[
                ("kind", "done".into()),
                ("job", job.into()),
                ("runs", sent.into()),
            ],
            Some(&transfer),
        ) {
            Ok(())
        } else {
            Err("the worker could not send the finished run".into())
        }
    }

    /// Posts a piece of the trace, its numbers transferred rather than copied.
    fn post_chunk(scope: &DedicatedWorkerGlobalScope, job: f64, chunk: TraceChunk) {
        let rows = Float64Array::from(chunk.rows.as_slice());
        let terms = Float64Array::from(chunk.terms.as_slice());
        let transfer = Array::of2(&rows.buffer(), &terms.buffer());
        let mut fields = vec![
            ("kind", "chunk".into()),
            ("job", job.into()),
            ("run", (chunk.run as f64).into()),
            ("rows", rows.into()),
            ("terms", terms.into()),
        ];
        if let Some(calibration) = chunk.calibration_json {
            fields.push(("calibration", calibration.into()));
        }
        // A chunk that cannot be sent only leaves the page to wait for the finished run.
        let _ = post(scope, &fields, Some(&transfer));
    }

    /// A finished trace as sent, `{ header, rows, terms }`, its numbers' buffers added to
    /// `transfer` (moved to the page rather than copied).
    fn trace_parts(header_json: String, rows: &[f64], terms: &[f64], transfer: &Array) -> JsValue {
        let rows = Float64Array::from(rows);
        let terms = Float64Array::from(terms);
        transfer.push(&rows.buffer());
        transfer.push(&terms.buffer());
        object(&[
            ("header", header_json.into()),
            ("rows", rows.into()),
            ("terms", terms.into()),
        ])
    }

    fn object(fields: &[(&str, JsValue)]) -> JsValue {
        let object = Object::new();
        for (name, value) in fields {
            let _ = Reflect::set(&object, &(*name).into(), value);
        }
        object.into()
    }

    /// The Hardware page's virtual device, ticked on this worker's timer.
    mod device {
        use std::cell::RefCell;
        use std::rc::Rc;

        use cutlab::protocol::device_worker::{ClockedDevice, DeviceStart, VIRTUAL_TICK_MS};
        use js_sys::{Array, Reflect, Uint8Array};
        use wasm_bindgen::prelude::{Closure, JsCast, JsValue};
        use web_sys::DedicatedWorkerGlobalScope;

        use super::post;

        thread_local! {
            /// The device this worker runs, once started.
            static DEVICE: RefCell<Option<Rc<RefCell<ClockedDevice>>>> = const { RefCell::new(None) };
        }

        /// Whether `data` was a message for the virtual device (and is now handled).
        pub fn handled(scope: &DedicatedWorkerGlobalScope, data: &JsValue) -> bool {
            let field = |name: &str| Reflect::get(data, &name.into()).unwrap_or(JsValue::UNDEFINED);
            if let Some(json) = field("device_start").as_string() {
                if let Err(message) = start(scope, &json) {
                    let _ = post(
                        scope,
                        &[
                            ("kind", "device_failed".into()),
                            ("message", message.into()),
                        ],
                        None,
                    );
                }
                return true;
            }
            if let Ok(bytes) = field("device_bytes").dyn_into::<Uint8Array>() {
                DEVICE.with(|d| {
                    if let Some(device) = d.borrow().as_ref() {
                        device.borrow_mut().receive(&bytes.to_vec());
                    }
                });
                return true;
            }
            false
        }

        /// Wall time, seconds (this worker's clock).
        fn now_s(scope: &DedicatedWorkerGlobalScope) -> f64 {
            scope.performance().map_or(0.0, |p| p.now()) / 1000.0
        }

        /// Powers the device on and ticks it until the page terminates this worker.
        fn start(scope: &DedicatedWorkerGlobalScope, json: &str) -> Result<(), String> {
            if DEVICE.with(|d| d.borrow().is_some()) {
                return Err("its worker already runs a device".into());
            }
            let request = DeviceStart::from_json(json)?;
            let device = Rc::new(RefCell::new(ClockedDevice::start(&request, now_s(scope))?));
            let tick = {
                let (scope, device) = (scope.clone(), Rc::clone(&device));
                Closure::<dyn FnMut()>::new(move || {
                    let bytes = device.borrow_mut().tick(now_s(&scope));
                    if bytes.is_empty() {
                        return;
                    }
                    let bytes = Uint8Array::from(bytes.as_slice());
                    let transfer = Array::of1(&bytes.buffer());
                    // Bytes that cannot be posted are lost as on a noisy line; the host counts them.
                    let _ = post(
                        &scope,
                        &[("kind", "device_bytes".into()), ("bytes", bytes.into())],
                        Some(&transfer),
                    );
                })
            };
            scope
                .set_interval_with_callback_and_timeout_and_arguments_0(
                    tick.as_ref().unchecked_ref(),
                    VIRTUAL_TICK_MS as i32,
                )
                .map_err(|e| format!("its timer did not start ({e:?})"))?;
            // The timer runs as long as the worker.
            tick.forget();
            DEVICE.with(|d| *d.borrow_mut() = Some(device));
            Ok(())
        }
    }

    /// Posts a message to the page; false if it could not be sent.
    fn post(
        scope: &DedicatedWorkerGlobalScope,
        fields: &[(&str, JsValue)],
        transfer: Option<&Array>,
    ) -> bool {
        let message = object(fields);
        match transfer {
            Some(list) => scope.post_message_with_transfer(&message, list),
            None => scope.post_message(&message),
        }
        .is_ok()
    }
}
