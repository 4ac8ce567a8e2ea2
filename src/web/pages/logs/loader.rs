//! Opening logs: a file, a drop or a sample streamed in chunks (`Blob.slice` + `arrayBuffer`)
//! into the core's `LogBuilder`, a task per chunk so the page never freezes; the open logs with
//! their mappings (kept per file name).

use std::collections::HashMap;
use std::sync::Arc;

use leptos::prelude::*;
use wasm_bindgen::JsCast;

use crate::log::link::LogsLink;
use crate::log::mapping::{Channel, Mapping};
use crate::log::{Log, LogBuilder};

/// At most this many logs are open (and overlaid) at once.
const MAX_LOGS: usize = 4;
/// The file is read this many bytes at a time, one chunk a task. A mebibyte's parse measured
/// 60–130 ms in Chromium on the 2-core reference machine (the browser tests' long-task check
/// caught it above 100 ms); a quarter of it keeps each task well inside the 50 ms a page task may
/// take.
const CHUNK_BYTES: f64 = 256.0 * 1024.0;

/// A loaded log with its mapping.
#[derive(Clone)]
pub struct LoadedLog {
    pub id: u32,
    pub name: String,
    pub bytes: u64,
    pub load_s: f64,
    pub log: Arc<Log>,
    pub mapping: Mapping,
}

impl PartialEq for LoadedLog {
    fn eq(&self, other: &Self) -> bool {
        self.id == other.id && self.mapping == other.mapping && Arc::ptr_eq(&self.log, &other.log)
    }
}

/// What the loader is doing.
#[derive(Debug, Clone, PartialEq)]
pub enum LoadStatus {
    Idle,
    Loading { name: String, fraction: f64 },
    Done(String),
    Failed(String),
    Cancelled(String),
}

fn now_ms() -> f64 {
    window().performance().map_or(0.0, |p| p.now())
}

/// Reads `blob` in chunks into a log. `Ok(None)` when cancelled (`generation` moved on).
async fn read_blob(
    blob: web_sys::Blob,
    name: String,
    status: RwSignal<LoadStatus>,
    generation: StoredValue<u64>,
    mine: u64,
) -> Result<Option<Log>, String> {
    let size = blob.size();
    let mut builder = LogBuilder::with_expected_bytes(size as u64);
    let mut offset = 0.0;
    let mut buffer: Vec<u8> = Vec::new();
    while offset < size {
        if generation.try_get_value() != Some(mine) {
            return Ok(None);
        }
        let end = (offset + CHUNK_BYTES).min(size);
        let slice = blob
            .slice_with_f64_and_f64(offset, end)
            .map_err(|_| format!("{name}: the browser could not cut the file into pieces"))?;
        let data = wasm_bindgen_futures::JsFuture::from(slice.array_buffer())
            .await
            .map_err(|_| format!("{name}: the browser could not read the file"))?;
        let array = js_sys::Uint8Array::new(&data);
        buffer.resize(array.length() as usize, 0);
        array.copy_to(&mut buffer);
        builder.push(&buffer);
        if let Some(e) = builder.refused() {
            return Err(format!("{name}: {e}"));
        }
        offset = end;
        let _ = status.try_set(LoadStatus::Loading {
            name: name.clone(),
            fraction: if size > 0.0 { offset / size } else { 1.0 },
        });
    }
    if generation.try_get_value() != Some(mine) {
        return Ok(None);
    }
    // The last chunk's task has ended; finishing (the time column's steps over every row) gets
    // a task of its own, and so does what the page makes of the log.
    next_task().await;
    let log = builder.finish(None).map_err(|e| format!("{name}: {e}"))?;
    next_task().await;
    Ok(Some(log))
}

/// Lets the browser run its other tasks (input, painting) before going on.
async fn next_task() {
    let promise = js_sys::Promise::new(&mut |resolve, _| {
        let _ = window().set_timeout_with_callback(&resolve);
    });
    let _ = wasm_bindgen_futures::JsFuture::from(promise).await;
}

/// Fetches a sample log from the server as a blob.
pub async fn fetch_blob(url: &str) -> Result<web_sys::Blob, String> {
    let response = wasm_bindgen_futures::JsFuture::from(window().fetch_with_str(url))
        .await
        .map_err(|_| format!("{url}: could not be fetched"))?;
    let response: web_sys::Response = response
        .dyn_into()
        .map_err(|_| format!("{url}: no response"))?;
    if !response.ok() {
        return Err(format!("{url}: the server answered {}", response.status()));
    }
    let blob = response.blob().map_err(|_| format!("{url}: no body"))?;
    wasm_bindgen_futures::JsFuture::from(blob)
        .await
        .map_err(|_| format!("{url}: the body could not be read"))?
        .dyn_into()
        .map_err(|_| format!("{url}: the body is not a file"))
}

/// The page's loaded logs and the loader.
#[derive(Clone, Copy)]
pub struct Logs {
    pub logs: RwSignal<Vec<LoadedLog>>,
    pub active: RwSignal<Option<u32>>,
    pub status: RwSignal<LoadStatus>,
    generation: StoredValue<u64>,
    next_id: StoredValue<u32>,
    /// Mappings by file name: a file loaded again keeps the one the person made.
    remembered: StoredValue<HashMap<String, Mapping>>,
    /// The shared link the page opened with, until the next log is opened: its sample and its
    /// mapping (applied to that log if it has the columns the link names).
    pub from_link: RwSignal<Option<LogsLink>>,
}

impl Logs {
    pub fn new() -> Self {
        Self {
            logs: RwSignal::new(Vec::new()),
            active: RwSignal::new(None),
            status: RwSignal::new(LoadStatus::Idle),
            generation: StoredValue::new(0),
            next_id: StoredValue::new(1),
            remembered: StoredValue::new(HashMap::new()),
            from_link: RwSignal::new(None),
        }
    }

    /// Loads blobs one after another (the page's cap of open logs applies).
    pub fn load(self, blobs: Vec<(String, web_sys::Blob)>) {
        self.generation.update_value(|g| *g += 1);
        let mine = self.generation.get_value();
        leptos::task::spawn_local(async move {
            for (name, blob) in blobs {
                if self.logs.with_untracked(Vec::len) >= MAX_LOGS {
                    let _ = self.status.try_set(LoadStatus::Failed(format!(
                        "{name}: at most {MAX_LOGS} logs are open at once; remove one first"
                    )));
                    return;
                }
                let started = now_ms();
                let bytes = blob.size() as u64;
                let _ = self.status.try_set(LoadStatus::Loading {
                    name: name.clone(),
                    fraction: 0.0,
                });
                match read_blob(blob, name.clone(), self.status, self.generation, mine).await {
                    Ok(Some(log)) => {
                        let seconds = (now_ms() - started) / 1000.0;
                        self.add(name, bytes, seconds, log);
                    }
                    Ok(None) => {
                        let _ = self.status.try_set(LoadStatus::Cancelled(format!(
                            "Cancelled: {name} was not loaded."
                        )));
                        return;
                    }
                    Err(e) => {
                        let _ = self.status.try_set(LoadStatus::Failed(e));
                        return;
                    }
                }
            }
        });
    }

    fn add(self, name: String, bytes: u64, load_s: f64, log: Log) {
        let from_link = self
            .from_link
            .try_get_untracked()
            .flatten()
            .and_then(|link| link.mapping_for(&log));
        let _ = self.from_link.try_set(None);
        let mapping = from_link
            .or_else(|| {
                self.remembered
                    .try_with_value(|m| m.get(&name).cloned())
                    .flatten()
                    .filter(|m| m.resolve(&log).is_ok())
            })
            .unwrap_or_else(|| Mapping::guess(&log));
        let id = self.next_id.get_value();
        self.next_id.set_value(id + 1);
        let message = format!(
            "Loaded {name}: {} rows × {} columns in {:.2} s.",
            log.rows,
            log.columns.len(),
            load_s
        );
        let entry = LoadedLog {
            id,
            name,
            bytes,
            load_s,
            log: Arc::new(log),
            mapping,
        };
        let _ = self.logs.try_update(|l| l.push(entry));
        let _ = self.active.try_set(Some(id));
        let _ = self.status.try_set(LoadStatus::Done(message));
    }

    pub fn cancel(self) {
        self.generation.update_value(|g| *g += 1);
    }

    pub fn set_channel(self, column: &str, channel: Option<Channel>) {
        let Some(id) = self.active.get_untracked() else {
            return;
        };
        self.logs.update(|logs| {
            if let Some(l) = logs.iter_mut().find(|l| l.id == id) {
                l.mapping.set(column, channel);
                let (name, mapping) = (l.name.clone(), l.mapping.clone());
                self.remembered.update_value(|m| {
                    m.insert(name, mapping);
                });
            }
        });
    }
}

/// The blobs of a file list, with their names.
pub fn files_of(files: Option<web_sys::FileList>) -> Vec<(String, web_sys::Blob)> {
    let Some(files) = files else {
        return Vec::new();
    };
    (0..files.length())
        .filter_map(|i| files.get(i))
        .map(|f| (f.name(), f.into()))
        .collect()
}
