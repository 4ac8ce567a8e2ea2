//! Logs: engineers' own machine logs, loaded as they are, analysed, calibrated from and replayed.
//!
//! ```text
//! File / drop / sample ─► streamed in chunks (Blob.slice + arrayBuffer) ─► LogBuilder::push
//!   ─► Log + guessed Mapping (editable, kept per file name)
//!   ─► signal chain on a column (ChainWork): zero-phase low-pass, moving RMS, spectrum, statistics
//!   ─► calibration (LogFitWork) ─► saved in localStorage (calibration_store::STORAGE_KEY)
//!   ─► replay of controllers (ReplayRuns) ─► charts on linked time axes, CSV export
//! ```
//!
//! Every long job runs in pieces (the file a chunk per task, the chain a stage per task, fits and
//! replays a budget of periods per task), so the page never freezes.

use std::collections::HashMap;
use std::ops::Range;
use std::sync::Arc;
use std::time::Duration;

use leptos::prelude::*;
use wasm_bindgen::JsCast;

use crate::charts::{Axis, LineChart, Series, Stroke, PALETTE};
use crate::closed_loop::calibration_file::CalibrationFile;
use crate::closed_loop::definition::{max_override_pct_of, RunSetting, SettingsOverrides};
use crate::closed_loop::error::LoopError;
use crate::control::registry::{ControllerConfig, ControllerKind};
use crate::estimation::cut_forces::CutGeometry;
use crate::estimation::estimator::{Calibration, Feedback};
use crate::input::readable;
use crate::log::analysis::{row_times, write_channels_csv, ChainOutput, ChainRequest, ChainWork};
use crate::log::calibration::{ForceSource, LogFit, LogFitWork};
use crate::log::machine::ReplayError;
use crate::log::mapping::{Channel, Mapping};
use crate::log::replay::{events, write_replay_csv, ReplayResult, ReplayRuns, ReplaySettings};
use crate::log::{ColumnKind, Log, LogBuilder};
use crate::plant::materials::Material;
use crate::plant::mechanics::{Cutter, MillingMode};
use crate::signal::decimate::min_max_indices;
use crate::web::components::chart::ChartCanvas;
use crate::web::components::download::{download_text, download_written};
use crate::web::components::fields::{parse_count, parse_number, NumberField, SelectField};
use crate::web::components::later::Later;
use crate::web::components::runner::{Debounce, RunProgress, Runner};
use crate::web::components::saved_calibrations::{save_calibration, stored_calibrations};
use crate::web::components::work_job::Shared;

/// At most this many logs are open (and overlaid) at once.
const MAX_LOGS: usize = 4;
/// The file is read this many bytes at a time: one chunk is one task of a few tens of ms.
const CHUNK_BYTES: f64 = 1024.0 * 1024.0;
/// Points per series a chart is given (the chart decimates further to its width).
const CHART_POINTS: usize = 4000;

/// The synthetic sample logs in www/data, one click away.
const SAMPLES: [(&str, &str); 2] = [
    (
        "synthetic-kim-step-doc-export.csv",
        "Synthetic CNC export: 60 ms RMS currents, semicolons, decimal commas",
    ),
    (
        "synthetic-maneerat-doc-2-daq.csv",
        "Synthetic 1 kHz DAQ: spindle phase currents and a dynamometer",
    ),
];

/// A loaded log with its mapping.
#[derive(Clone)]
struct LoadedLog {
    id: u32,
    name: String,
    bytes: u64,
    load_s: f64,
    log: Arc<Log>,
    mapping: Mapping,
}

impl PartialEq for LoadedLog {
    fn eq(&self, other: &Self) -> bool {
        self.id == other.id && self.mapping == other.mapping && Arc::ptr_eq(&self.log, &other.log)
    }
}

/// What the loader is doing.
#[derive(Debug, Clone, PartialEq)]
enum LoadStatus {
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
async fn fetch_blob(url: &str) -> Result<web_sys::Blob, String> {
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
struct Logs {
    logs: RwSignal<Vec<LoadedLog>>,
    active: RwSignal<Option<u32>>,
    status: RwSignal<LoadStatus>,
    generation: StoredValue<u64>,
    next_id: StoredValue<u32>,
    /// Mappings by file name: a file loaded again keeps the one the person made.
    remembered: StoredValue<HashMap<String, Mapping>>,
}

impl Logs {
    fn new() -> Self {
        Self {
            logs: RwSignal::new(Vec::new()),
            active: RwSignal::new(None),
            status: RwSignal::new(LoadStatus::Idle),
            generation: StoredValue::new(0),
            next_id: StoredValue::new(1),
            remembered: StoredValue::new(HashMap::new()),
        }
    }

    /// Loads blobs one after another (the page's cap of open logs applies).
    fn load(self, blobs: Vec<(String, web_sys::Blob)>) {
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
        let mapping = self
            .remembered
            .try_with_value(|m| m.get(&name).cloned())
            .flatten()
            .filter(|m| m.resolve(&log).is_ok())
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

    fn cancel(self) {
        self.generation.update_value(|g| *g += 1);
    }

    fn set_channel(self, column: &str, channel: Option<Channel>) {
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

/// `values` against `times` as chart points within `view`, min/max-decimated.
fn points(times: &[f64], values: &[f64], view: Option<&Range<f64>>) -> Vec<(f64, f64)> {
    let n = times.len().min(values.len());
    let (start, end) = match view {
        Some(r) => (
            times[..n]
                .partition_point(|t| *t < r.start)
                .saturating_sub(1),
            (times[..n].partition_point(|t| *t <= r.end) + 1).min(n),
        ),
        None => (0, n),
    };
    if start >= end {
        return Vec::new();
    }
    min_max_indices(&values[start..end], CHART_POINTS / 2)
        .into_iter()
        .map(|i| (times[start + i], values[start + i]))
        .collect()
}

/// The column of a log carrying the first of `channels` in its mapping.
fn channel_column<'a>(l: &'a LoadedLog, channels: &[Channel]) -> Option<&'a crate::log::Column> {
    channels.iter().find_map(|c| {
        let name = l.mapping.columns_of(*c).first().map(|s| s.to_string())?;
        l.log.columns.iter().find(|col| col.name == name)
    })
}

const CURRENTS: [Channel; 4] = [
    Channel::SpindlePhase,
    Channel::SpindleCurrent,
    Channel::FeedPhase,
    Channel::FeedCurrent,
];

/// One chart of every open log's column for a channel, on the shared time axis.
fn overlay_chart(
    logs: &[LoadedLog],
    channels: &[Channel],
    y_label: &str,
    view: Option<&Range<f64>>,
) -> LineChart {
    let mut chart = LineChart::new(Axis::linear("time (s)"), Axis::linear(y_label));
    for (k, l) in logs.iter().enumerate() {
        if let Some(column) = channel_column(l, channels) {
            let generated;
            let times: &[f64] = match l.log.time_column.and_then(|t| l.log.columns.get(t)) {
                Some(t) => &t.values,
                None => {
                    generated = row_times(&l.log, None);
                    &generated
                }
            };
            chart.series.push(Series::new(
                format!("{}: {}", l.name, column.name),
                PALETTE[k % PALETTE.len()],
                points(times, &column.values, view),
            ));
        }
    }
    chart.fit();
    chart
}

fn spectrum_chart(output: &ChainOutput, speed_rpm: Option<f64>, teeth: Option<usize>) -> LineChart {
    let (freq, psd) = &output.spectrum;
    let shown: Vec<(f64, f64)> = freq
        .iter()
        .zip(psd)
        .filter(|(f, p)| **f > 0.0 && **p > 0.0)
        .map(|(f, p)| (*f, *p))
        .collect();
    let mut chart = LineChart::new(Axis::log("frequency (Hz)"), Axis::log("PSD (unit²/Hz)"));
    chart
        .series
        .push(Series::new("Welch PSD", PALETTE[0], shown.clone()));
    let (lo, hi) = shown
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.1), hi.max(p.1))
        });
    let top = freq.last().copied().unwrap_or(0.0);
    if let Some(rpm) = speed_rpm.filter(|r| r.is_finite() && *r > 0.0) {
        let spindle_hz = rpm / 60.0;
        let mut markers = vec![(
            format!("spindle {} Hz", readable(spindle_hz)),
            spindle_hz,
            PALETTE[5],
        )];
        if let Some(z) = teeth.filter(|z| *z > 0) {
            let tooth_hz = spindle_hz * z as f64;
            markers.push((
                format!("tooth passing {} Hz", readable(tooth_hz)),
                tooth_hz,
                PALETTE[2],
            ));
        }
        for (label, f, color) in markers {
            if f < top && lo.is_finite() {
                chart
                    .series
                    .push(Series::new(label, color, vec![(f, lo), (f, hi)]).dashed());
            }
        }
    }
    chart.fit();
    chart
}

fn fit_chart(fit: &LogFit) -> LineChart {
    let mut chart = LineChart::new(Axis::linear("force (N)"), Axis::linear("RMS current (A)"));
    let mut dots: Vec<(f64, f64)> = fit
        .points
        .iter()
        .map(|p| (p.force_n, p.current_a))
        .collect();
    dots.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart
        .series
        .push(Series::new("control periods", PALETTE[0], dots.clone()).with_stroke(Stroke::Points));
    let (lo, hi) = dots
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.0), hi.max(p.0))
        });
    if let (Some(point), true) = (fit.points.first(), lo.is_finite()) {
        chart.series.push(Series::new(
            "fitted line",
            PALETTE[5],
            vec![
                (lo, fit.model_current_a(point, lo)),
                (hi, fit.model_current_a(point, hi)),
            ],
        ));
    }
    chart.fit();
    chart
}

/// A value of a replay's trace row.
type RowValue = fn(&crate::closed_loop::trace::TraceRow) -> f64;

fn replay_chart(
    results: &[Arc<ReplayResult>],
    value: RowValue,
    logged: Option<(&str, RowValue)>,
    y_label: &str,
    view: Option<&Range<f64>>,
) -> LineChart {
    let mut chart = LineChart::new(Axis::linear("time (s)"), Axis::linear(y_label));
    for (k, r) in results.iter().enumerate() {
        let times: Vec<f64> = r.trace.rows.iter().map(|row| row.time_s).collect();
        let values: Vec<f64> = r.trace.rows.iter().map(value).collect();
        chart.series.push(Series::new(
            r.controller.kind().label(),
            PALETTE[k % PALETTE.len()],
            points(&times, &values, view),
        ));
    }
    if let (Some((label, f)), Some(first)) = (logged, results.first()) {
        let times: Vec<f64> = first.trace.rows.iter().map(|row| row.time_s).collect();
        let values: Vec<f64> = first.trace.rows.iter().map(f).collect();
        if values.iter().any(|v| v.is_finite()) {
            chart
                .series
                .push(Series::new(label, PALETTE[7], points(&times, &values, view)).dashed());
        }
    }
    chart.fit();
    chart
}

/// A labelled select over dynamic options, keeping its value.
#[component]
fn ChoiceField(
    #[prop(into)] id: String,
    label: &'static str,
    #[prop(into)] options: Signal<Vec<(String, String)>>,
    value: RwSignal<String>,
    #[prop(into, optional)] error: Signal<Option<String>>,
) -> impl IntoView {
    let error_id = format!("{id}-error");
    let described = error_id.clone();
    view! {
        <div class="field" class:field-invalid=move || error.get().is_some()>
            <label for=id.clone()>{label}</label>
            <select
                id=id
                on:change=move |ev| value.set(event_target_value(&ev))
                prop:value=move || value.get()
                aria-describedby=described
            >
                {move || {
                    options
                        .get()
                        .into_iter()
                        .map(|(v, text)| {
                            let selected = v.clone();
                            view! { <option value=v selected=move || value.get() == selected>{text}</option> }
                        })
                        .collect_view()
                }}
            </select>
            <p class="field-error" id=error_id aria-live="polite">{move || error.get().unwrap_or_default()}</p>
        </div>
    }
}

/// The Logs page.
#[component]
pub fn LogsPage() -> impl IntoView {
    let logs = Logs::new();
    let time_view = RwSignal::new(None::<Range<f64>>);
    let active_log = Memo::new(move |_| {
        let id = logs.active.get();
        logs.logs
            .with(|l| l.iter().find(|x| Some(x.id) == id).cloned())
    });

    // --- Opening files.
    let on_files = move |ev: leptos::ev::Event| {
        let Some(input) = ev
            .target()
            .and_then(|t| t.dyn_into::<web_sys::HtmlInputElement>().ok())
        else {
            return;
        };
        let blobs = files_of(input.files());
        input.set_value("");
        logs.load(blobs);
    };
    let on_drop = move |ev: leptos::ev::DragEvent| {
        ev.prevent_default();
        let files = ev.data_transfer().and_then(|d| d.files());
        logs.load(files_of(files));
    };
    let load_sample = move |file: &'static str| {
        let url = format!("data/{file}");
        leptos::task::spawn_local(async move {
            match fetch_blob(&url).await {
                Ok(blob) => logs.load(vec![(file.to_string(), blob)]),
                Err(e) => {
                    let _ = logs.status.try_set(LoadStatus::Failed(e));
                }
            }
        });
    };

    // --- Sample period of a log without a time column.
    let period_text = RwSignal::new(String::new());
    let period = Memo::new(move |_| -> Result<Option<f64>, String> {
        let text = period_text.get();
        if text.trim().is_empty() {
            return Ok(None);
        }
        parse_number(&text).and_then(|p| {
            if p > 0.0 {
                Ok(Some(p))
            } else {
                Err("the sample period must be positive".to_string())
            }
        })
    });
    let period_value = Signal::derive(move || period.get().ok().flatten());
    let mapping_error = Memo::new(move |_| {
        active_log.with(|l| {
            l.as_ref()
                .and_then(|l| l.mapping.resolve(&l.log).err().map(|e| e.0))
        })
    });

    // --- The signal chain on one column.
    let chain_column = RwSignal::new(String::new());
    let lowpass_text = RwSignal::new(String::new());
    let order_text = RwSignal::new("4".to_string());
    let rms_text = RwSignal::new("0.1".to_string());
    let teeth_text = RwSignal::new("2".to_string());
    let by_label = RwSignal::new(String::new());
    // A new log: analyse its current (or first numeric) column, grouped by its label.
    Effect::new(move |_| {
        active_log.with(|l| {
            let Some(l) = l else { return };
            let present = |name: &str| l.log.columns.iter().any(|c| c.name == name);
            if !present(&chain_column.get_untracked()) {
                let pick = channel_column(l, &CURRENTS)
                    .or_else(|| l.log.columns.iter().find(|c| c.kind == ColumnKind::Number))
                    .map(|c| c.name.clone())
                    .unwrap_or_default();
                chain_column.set(pick);
            }
            if !present(&by_label.get_untracked()) {
                by_label.set(
                    l.mapping
                        .columns_of(Channel::Label)
                        .first()
                        .map_or(String::new(), |s| s.to_string()),
                );
            }
        })
    });
    let lowpass = Memo::new(move |_| -> Result<Option<f64>, String> {
        let text = lowpass_text.get();
        if text.trim().is_empty() {
            return Ok(None);
        }
        let cutoff = parse_number(&text).and_then(|f| {
            if f > 0.0 {
                Ok(f)
            } else {
                Err("the cut-off must be a positive frequency".to_string())
            }
        })?;
        Ok(Some(cutoff))
    });
    let order = Memo::new(move |_| {
        parse_count(&order_text.get()).and_then(|n| {
            if (1..=crate::signal::butterworth::MAX_ORDER).contains(&n) {
                Ok(n)
            } else {
                Err(format!(
                    "the order must be 1 to {}",
                    crate::signal::butterworth::MAX_ORDER
                ))
            }
        })
    });
    let rms_window = Memo::new(move |_| {
        parse_number(&rms_text.get()).and_then(|w| {
            if w > 0.0 {
                Ok(w)
            } else {
                Err("the window must be a positive time".to_string())
            }
        })
    });
    let teeth = Memo::new(move |_| parse_count(&teeth_text.get()));
    let chain_runner = Runner::<Arc<ChainOutput>>::new();
    let chain_error = RwSignal::new(None::<String>);
    let chain_debounce = Debounce::new(Duration::from_millis(250));
    let chain_for_effect = chain_runner.clone();
    Effect::new(move |_| {
        let Some(l) = active_log.get() else { return };
        let column = chain_column.get();
        let (Ok(lowpass), Ok(order), Ok(window)) = (lowpass.get(), order.get(), rms_window.get())
        else {
            return;
        };
        let request = ChainRequest {
            column,
            lowpass: lowpass.map(|f| (f, order)),
            rms_window_s: window,
            by: Some(by_label.get()).filter(|b| !b.is_empty()),
            sample_period_s: period_value.get(),
        };
        let runner = chain_for_effect.clone();
        chain_debounce.request(move || match ChainWork::new(l.log.clone(), request) {
            Ok(work) => {
                chain_error.set(None);
                runner.start(Shared(work));
            }
            Err(e) => chain_error.set(Some(e)),
        });
    });
    let chain_done = chain_runner.finished();

    // --- Calibration.
    let feedback_text = RwSignal::new("spindle".to_string());
    let feedback = Memo::new(move |_| {
        if feedback_text.get() == "feed" {
            Feedback::FeedCurrent
        } else {
            Feedback::SpindleCurrent
        }
    });
    let force_from = RwSignal::new("measured".to_string());
    let material = RwSignal::new(Material::Sm45c.name().to_string());
    let diameter_text = RwSignal::new("10".to_string());
    let cutter_teeth_text = RwSignal::new("4".to_string());
    let mode = RwSignal::new(MillingMode::Down.name().to_string());
    let depth_text = RwSignal::new(String::new());
    let width_text = RwSignal::new("3".to_string());
    let fit_runner = Runner::<Arc<LogFit>>::new();
    let fit_error = RwSignal::new(None::<String>);
    let fit_done = fit_runner.finished();
    let fit_runner_for_click = fit_runner.clone();
    let calibrate = move |_| {
        fit_error.set(None);
        let Some(l) = active_log.get_untracked() else {
            fit_error.set(Some("open a log first".into()));
            return;
        };
        let force = if force_from.get_untracked() == "measured" {
            ForceSource::Measured
        } else {
            let geometry = (|| -> Result<ForceSource, String> {
                let diameter = parse_number(&diameter_text.get_untracked())
                    .map_err(|e| format!("cutter diameter: {e}"))?;
                let z = parse_count(&cutter_teeth_text.get_untracked())
                    .map_err(|e| format!("cutter teeth: {e}"))?;
                let cutter = Cutter::new(diameter, z as u32, 0.0).map_err(|e| e.to_string())?;
                let material =
                    Material::from_name(&material.get_untracked()).ok_or("choose a material")?;
                let mode = MillingMode::from_name(&mode.get_untracked()).ok_or("choose a mode")?;
                let depth = depth_text.get_untracked();
                let depth_mm = if depth.trim().is_empty() {
                    None
                } else {
                    Some(parse_number(&depth).map_err(|e| format!("depth: {e}"))?)
                };
                let width_mm =
                    parse_number(&width_text.get_untracked()).map_err(|e| format!("width: {e}"))?;
                Ok(ForceSource::CutModel {
                    geometry: CutGeometry {
                        cutter,
                        mode,
                        coefficients: material.coefficients(),
                    },
                    depth_mm,
                    width_mm,
                })
            })();
            match geometry {
                Ok(g) => g,
                Err(e) => {
                    fit_error.set(Some(e));
                    return;
                }
            }
        };
        let settings = ReplaySettings {
            run: SettingsOverrides {
                feedback: Some(feedback.get_untracked()),
                ..SettingsOverrides::default()
            },
            sample_period_s: period_value.get_untracked(),
            ..ReplaySettings::default()
        };
        match LogFitWork::new(&l.log, &l.mapping, &settings, &force) {
            Ok(work) => fit_runner_for_click.start(Shared(work)),
            Err(e) => fit_error.set(Some(e.to_string())),
        }
    };
    let saved_message = RwSignal::new(None::<Result<String, String>>);
    let stored = RwSignal::new(stored_calibrations());
    let fit_file = move || {
        let fit = fit_done.get()?;
        let name = active_log.with_untracked(|l| l.as_ref().map(|l| l.name.clone()))?;
        Some(CalibrationFile::new(
            fit.calibration.clone(),
            format!(
                "log {name}, {} feedback, force from {}",
                feedback.get_untracked().name(),
                fit.force_source
            ),
        ))
    };
    let save_in_browser = move |_| {
        let Some(file) = fit_file() else {
            saved_message.set(Some(Err("calibrate first".into())));
            return;
        };
        saved_message
            .set(Some(save_calibration(&file).map(|()| {
                format!("Saved in this browser as “{}”.", file.source)
            })));
        stored.set(stored_calibrations());
    };
    let download_calibration = move |_| {
        let Some(file) = fit_file() else {
            saved_message.set(Some(Err("calibrate first".into())));
            return;
        };
        if let Err(e) = download_text(
            "cutlab-calibration.json",
            "application/json",
            &file.to_json(),
        ) {
            saved_message.set(Some(Err(e)));
        }
    };

    // --- Replay.
    let chosen: [RwSignal<bool>; 7] = std::array::from_fn(|i| {
        RwSignal::new(matches!(
            ControllerKind::ALL[i],
            ControllerKind::Threshold | ControllerKind::Pi
        ))
    });
    let target_kind = RwSignal::new("current".to_string());
    let target_text = RwSignal::new(String::new());
    let use_calibration = RwSignal::new("none".to_string());
    let calibration_options = Signal::derive(move || {
        let mut options = vec![("none".to_string(), "None: regulate the current".to_string())];
        if fit_done.with(Option::is_some) {
            options.push(("fit".to_string(), "The fit made above".to_string()));
        }
        for (i, f) in stored.with(|s| s.0.clone()).iter().enumerate() {
            options.push((format!("stored-{i}"), format!("Saved: {}", f.source)));
        }
        options
    });
    let chosen_calibration = move || -> Option<Calibration> {
        let choice = use_calibration.get_untracked();
        if choice == "fit" {
            return fit_done.get_untracked().map(|f| f.calibration.clone());
        }
        let index: usize = choice.strip_prefix("stored-")?.parse().ok()?;
        stored.with_untracked(|s| s.0.get(index).map(|f| f.calibration.clone()))
    };
    let target_error = RwSignal::new(None::<String>);
    let replay_error = RwSignal::new(None::<String>);
    let replay_runner = Runner::<Vec<Arc<ReplayResult>>>::new();
    let replay_done = replay_runner.finished();
    let replay_runner_for_click = replay_runner.clone();
    let replay = move |_| {
        replay_error.set(None);
        target_error.set(None);
        let Some(l) = active_log.get_untracked() else {
            replay_error.set(Some("open a log first".into()));
            return;
        };
        let controllers: Vec<ControllerConfig> = ControllerKind::ALL
            .iter()
            .zip(chosen)
            .filter(|(_, on)| on.get_untracked())
            .map(|(k, _)| ControllerConfig::new(*k))
            .collect();
        if controllers.is_empty() {
            replay_error.set(Some("choose at least one controller".into()));
            return;
        }
        // The target through the run definition's row, as `cutlab log replay --target-n/-a`.
        let target_setting = if target_kind.get_untracked() == "force" {
            RunSetting::TargetForce
        } else {
            RunSetting::TargetCurrent
        };
        let mut run = SettingsOverrides {
            feedback: Some(feedback.get_untracked()),
            ..SettingsOverrides::default()
        };
        let text = target_text.get_untracked();
        let max_override_pct = max_override_pct_of(&ReplaySettings::default().override_mode);
        match target_setting.parse_on(&text, max_override_pct) {
            Ok(value) => {
                target_setting.apply_to_settings(&mut run, value);
            }
            Err(e) => {
                target_error.set(Some(e.problem.to_string()));
                return;
            }
        }
        let settings = ReplaySettings {
            run,
            sample_period_s: period_value.get_untracked(),
            calibration: chosen_calibration(),
            ..ReplaySettings::default()
        };
        // Check what the first replay needs before starting, so the message lands beside the
        // control it is about.
        if let Err(e) =
            crate::log::replay::ReplayRun::new(&l.log, &l.mapping, &settings, &controllers[0])
        {
            match e {
                ReplayError::Loop(LoopError::Setting(e))
                    if matches!(
                        e.setting,
                        RunSetting::TargetForce | RunSetting::TargetCurrent
                    ) =>
                {
                    target_error.set(Some(e.problem.to_string()))
                }
                e => replay_error.set(Some(e.to_string())),
            }
            return;
        }
        replay_runner_for_click.start(ReplayRuns::new(
            l.log.clone(),
            l.mapping.clone(),
            settings,
            controllers,
        ));
    };

    // --- Export.
    let export_error = RwSignal::new(None::<String>);
    let export_channels = move |_| {
        let Some(l) = active_log.get_untracked() else {
            export_error.set(Some("open a log first".into()));
            return;
        };
        let chain = chain_done.get_untracked();
        let column = chain_column.get_untracked();
        let result = download_written("cutlab-log-channels.csv", "text/csv", |out| {
            write_channels_csv(
                &l.log,
                &l.mapping,
                chain.as_deref().map(|c| (column.as_str(), c)),
                period_value.get_untracked(),
                out,
            )
        });
        export_error.set(result.err());
    };
    let export_replays = move |_| {
        let Some(results) = replay_done.get_untracked() else {
            export_error.set(Some("replay first".into()));
            return;
        };
        let runs: Vec<&ReplayResult> = results.iter().map(|r| r.as_ref()).collect();
        let result = download_written("cutlab-log-replay.csv", "text/csv", |out| {
            write_replay_csv(&runs, out)
        });
        export_error.set(result.err());
    };

    // --- Charts.
    let overlay_current = Signal::derive(move || {
        logs.logs
            .with(|l| overlay_chart(l, &CURRENTS, "current (A)", time_view.get().as_ref()))
    });
    let overlay_force = Signal::derive(move || {
        logs.logs
            .with(|l| overlay_chart(l, &[Channel::Force], "force (N)", time_view.get().as_ref()))
    });
    let chain_chart = Signal::derive(move || {
        let view = time_view.get();
        let mut chart = LineChart::new(Axis::linear("time (s)"), Axis::linear(chain_column.get()));
        let (Some(l), Some(out)) = (active_log.get(), chain_done.get()) else {
            return chart;
        };
        let Some(column) = l
            .log
            .columns
            .iter()
            .find(|c| c.name == chain_column.get_untracked())
        else {
            return chart;
        };
        if out.filtered.len() != column.values.len() {
            return chart;
        }
        let times = row_times(&l.log, period_value.get());
        chart.series.push(Series::new(
            "as logged",
            PALETTE[4],
            points(&times, &column.values, view.as_ref()),
        ));
        if out.lowpass_applied {
            chart.series.push(Series::new(
                "zero-phase low-pass",
                PALETTE[0],
                points(&times, &out.filtered, view.as_ref()),
            ));
        }
        chart.series.push(Series::new(
            format!("moving RMS ({} samples)", out.rms_window_samples),
            PALETTE[5],
            points(&times, &out.rms, view.as_ref()),
        ));
        chart.fit();
        chart
    });
    let spectrum = Signal::derive(move || {
        let Some(out) = chain_done.get() else {
            return LineChart::new(Axis::log("frequency (Hz)"), Axis::log("PSD"));
        };
        let speed = active_log.with(|l| {
            l.as_ref()
                .and_then(|l| channel_column(l, &[Channel::SpindleSpeed, Channel::SpindleCommand]))
                .map(|c| crate::signal::stats::median(c.values.iter().copied()))
        });
        spectrum_chart(&out, speed, teeth.get().ok())
    });
    let calibration_chart = Signal::derive(move || {
        fit_done.get().map(|f| fit_chart(&f)).unwrap_or_else(|| {
            LineChart::new(Axis::linear("force (N)"), Axis::linear("RMS current (A)"))
        })
    });
    let replay_override = Signal::derive(move || {
        let results = replay_done.get().unwrap_or_default();
        replay_chart(
            &results,
            |r| r.override_pct,
            Some(("logged override", |r| r.applied_override_pct)),
            "override (%)",
            time_view.get().as_ref(),
        )
    });
    let replay_force = Signal::derive(move || {
        let results = replay_done.get().unwrap_or_default();
        replay_chart(
            &results,
            |r| r.force_est_n,
            Some(("measured force", |r| r.force_n)),
            "force estimate (N, or A uncalibrated)",
            time_view.get().as_ref(),
        )
    });

    let column_options = Signal::derive(move || {
        active_log.with(|l| {
            l.as_ref()
                .map(|l| {
                    l.log
                        .columns
                        .iter()
                        .filter(|c| matches!(c.kind, ColumnKind::Number))
                        .map(|c| (c.name.clone(), c.name.clone()))
                        .collect()
                })
                .unwrap_or_default()
        })
    });
    let label_options = Signal::derive(move || {
        let mut options = vec![(String::new(), "No grouping".to_string())];
        active_log.with(|l| {
            if let Some(l) = l {
                options.extend(
                    l.log
                        .columns
                        .iter()
                        .filter(|c| c.kind == ColumnKind::Text)
                        .map(|c| (c.name.clone(), c.name.clone())),
                );
            }
        });
        options
    });

    let status = logs.status;
    view! {
        <section class="page" aria-labelledby="logs-title">
            <h1 id="logs-title">"Machine logs"</h1>
            <p class="lede">
                "Bring a log from your own machine — a CNC's spindle or servo monitor export, a DAQ, a "
                "logging script — as it is: comma, semicolon or tab, decimal commas, quotes, a header "
                "with units or none. Map its columns, run the signal chain on a current, calibrate the "
                "current-to-force model from it, and replay controllers on it: the override each would "
                "have commanded and when the safety envelope would have acted. Replay is open-loop: the "
                "log cannot react to a command."
            </p>
            <div class="layout-two">
                <form class="panel" aria-label="Logs" on:submit=|ev| ev.prevent_default()>
                    <fieldset>
                        <legend>"Open a log"</legend>
                        <div class="field">
                            <label for="log-files">"Open log files"</label>
                            <input id="log-files" type="file" multiple accept=".csv,.txt,.tsv,.dat,text/csv,text/plain" on:change=on_files />
                        </div>
                        <div
                            class="drop-zone"
                            role="region"
                            aria-label="Drop log files here"
                            on:dragover=|ev: leptos::ev::DragEvent| ev.prevent_default()
                            on:drop=on_drop
                        >
                            "Drop log files here"
                        </div>
                        <p class="hint">"Sample logs (made by the simulator, not a machine):"</p>
                        <div class="preset-row">
                            {SAMPLES
                                .iter()
                                .map(|(file, label)| {
                                    let file: &'static str = file;
                                    view! {
                                        <button type="button" class="preset" on:click=move |_| load_sample(file)>
                                            {*label}
                                        </button>
                                    }
                                })
                                .collect_view()}
                        </div>
                        {move || match status.get() {
                            LoadStatus::Loading { name, fraction } => view! {
                                <div class="run-progress" role="status">
                                    <label for="log-load-progress">{format!("Loading {name}")}</label>
                                    <progress id="log-load-progress" max="1" value=fraction.to_string()></progress>
                                    <button type="button" on:click=move |_| logs.cancel()>"Cancel loading"</button>
                                </div>
                            }.into_any(),
                            LoadStatus::Done(m) => view! { <p class="hint" role="status">{m}</p> }.into_any(),
                            LoadStatus::Cancelled(m) => view! { <p class="hint" role="status">{m}</p> }.into_any(),
                            LoadStatus::Failed(e) => view! { <p class="run-error" role="alert">{e}</p> }.into_any(),
                            LoadStatus::Idle => ().into_any(),
                        }}
                    </fieldset>
                    <fieldset>
                        <legend>"Open logs"</legend>
                        {move || {
                            let list = logs.logs.get();
                            if list.is_empty() {
                                return view! { <p class="hint">"None yet."</p> }.into_any();
                            }
                            view! {
                                <ul class="log-list">
                                    {list
                                        .into_iter()
                                        .map(|l| {
                                            let id = l.id;
                                            let input_id = format!("log-active-{id}");
                                            view! {
                                                <li class="check">
                                                    <input
                                                        type="radio"
                                                        name="log-active"
                                                        id=input_id.clone()
                                                        prop:checked=move || logs.active.get() == Some(id)
                                                        on:change=move |_| logs.active.set(Some(id))
                                                    />
                                                    <label for=input_id>{format!("Analyse {}", l.name)}</label>
                                                    <button
                                                        type="button"
                                                        aria-label=format!("Remove {}", l.name)
                                                        on:click=move |_| {
                                                            logs.logs.update(|v| v.retain(|x| x.id != id));
                                                            if logs.active.get_untracked() == Some(id) {
                                                                logs.active.set(logs.logs.with_untracked(|v| v.first().map(|x| x.id)));
                                                            }
                                                        }
                                                    >
                                                        "Remove"
                                                    </button>
                                                </li>
                                            }
                                        })
                                        .collect_view()}
                                </ul>
                            }
                            .into_any()
                        }}
                    </fieldset>
                    // Each part of the form past the first mounts in a task of its own (`Later`): the
                    // first compile of all they call made the page's first task long.
                    <Later>
                        <fieldset>
                            <legend>"Signal chain"</legend>
                            <ChoiceField id="chain-column" label="Column" options=column_options value=chain_column error=Signal::derive(move || chain_error.get()) />
                            <NumberField id="chain-lowpass" label="Zero-phase low-pass cut-off (empty: none)" unit="Hz" value=lowpass_text
                                error=Signal::derive(move || lowpass.get().err()) />
                            <NumberField id="chain-order" label="Low-pass order" value=order_text step="1"
                                error=Signal::derive(move || order.get().err()) />
                            <NumberField id="chain-rms" label="RMS window" unit="s" value=rms_text
                                error=Signal::derive(move || rms_window.get().err()) />
                            <NumberField id="chain-teeth" label="Cutter teeth (tooth-passing marker)" value=teeth_text step="1"
                                error=Signal::derive(move || teeth.get().err()) />
                            <ChoiceField id="chain-by" label="Statistics per label of" options=label_options value=by_label />
                            <RunProgress runner=chain_runner.clone() id="chain-progress" failure="The signal chain failed" />
                        </fieldset>
                    </Later>
                    <Later>
                        <fieldset>
                            <legend>"Calibration"</legend>
                            <SelectField id="log-feedback" label="Force measured from the current of the"
                                options=vec![("spindle", "Spindle"), ("feed", "Feed drive")] value=feedback_text />
                            <SelectField id="fit-force" label="Force for the fit"
                                options=vec![("measured", "The log's measured force"), ("model", "Modelled from the cut")] value=force_from />
                            <div hidden=move || force_from.get() != "model">
                                <SelectField id="fit-material" label="Material"
                                    options=Material::ALL.iter().map(|m| (m.name(), m.label())).collect() value=material />
                                <NumberField id="fit-diameter" label="Cutter diameter" unit="mm" value=diameter_text error=Signal::derive(|| None::<String>) />
                                <NumberField id="fit-teeth" label="Cutter teeth" value=cutter_teeth_text step="1" error=Signal::derive(|| None::<String>) />
                                <SelectField id="fit-mode" label="Milling mode"
                                    options=MillingMode::ALL.iter().map(|m| (m.name(), m.label())).collect() value=mode />
                                <NumberField id="fit-depth" label="Depth of cut (empty: the depth column)" unit="mm" value=depth_text error=Signal::derive(|| None::<String>) />
                                <NumberField id="fit-width" label="Width of cut" unit="mm" value=width_text error=Signal::derive(|| None::<String>) />
                            </div>
                            <div class="button-row">
                                <button type="button" on:click=calibrate.clone()>"Calibrate"</button>
                                <button type="button" on:click=save_in_browser disabled=move || fit_done.with(Option::is_none)>"Save calibration in this browser"</button>
                                <button type="button" on:click=download_calibration disabled=move || fit_done.with(Option::is_none)>"Calibration (JSON)"</button>
                            </div>
                            {move || fit_error.get().map(|e| view! { <p class="run-error" role="alert">{e}</p> })}
                            {move || saved_message.get().map(|m| match m {
                                Ok(m) => view! { <p class="hint" role="status">{m}</p> }.into_any(),
                                Err(e) => view! { <p class="run-error" role="alert">{e}</p> }.into_any(),
                            })}
                            <RunProgress runner=fit_runner.clone() id="fit-progress" failure="The calibration failed" />
                        </fieldset>
                    </Later>
                    <Later>
                        <fieldset>
                            <legend>"Replay controllers"</legend>
                            {ControllerKind::ALL
                                .iter()
                                .zip(chosen)
                                .map(|(kind, on)| {
                                    let id = format!("replay-{}", kind.name());
                                    view! {
                                        <div class="check">
                                            <input type="checkbox" id=id.clone() prop:checked=move || on.get()
                                                on:change=move |ev| on.set(event_target_checked(&ev)) />
                                            <label for=id>{format!("Replay {}", kind.label())}</label>
                                        </div>
                                    }
                                })
                                .collect_view()}
                            <SelectField id="replay-target-kind" label="Target is a"
                                options=vec![("current", "Current (A)"), ("force", "Force (N)")] value=target_kind />
                            <NumberField id="replay-target" label="Target value (empty: 80 % of the calibrated force at full override)" value=target_text
                                error=Signal::derive(move || target_error.get()) />
                            <ChoiceField id="replay-calibration" label="Calibration for the replay" options=calibration_options value=use_calibration />
                            {move || stored.with(|s| s.1.clone()).into_iter().map(|p| view! { <p class="field-error">{p}</p> }).collect_view()}
                            <div class="button-row">
                                <button type="button" on:click=replay.clone()>"Replay"</button>
                            </div>
                            {move || replay_error.get().map(|e| view! { <p class="run-error" role="alert">{e}</p> })}
                            <RunProgress runner=replay_runner.clone() id="replay-progress" failure="The replay failed" />
                        </fieldset>
                    </Later>
                    <Later>
                        <fieldset>
                            <legend>"Export"</legend>
                            <div class="button-row">
                                <button type="button" on:click=export_channels disabled=move || active_log.with(Option::is_none)>"Analysed channels (CSV)"</button>
                                <button type="button" on:click=export_replays disabled=move || replay_done.with(Option::is_none)>"Replayed overrides (CSV)"</button>
                            </div>
                            {move || export_error.get().map(|e| view! { <p class="run-error" role="alert">{e}</p> })}
                        </fieldset>
                    </Later>
                </form>
                <div class="results">
                    // The results and their charts a task after the form: together with the form they
                    // took the page's first task past 50 ms.
                    <Later>
                        {move || active_log.get().map(|l| view! { <LogSummary l=l period_text=period_text period_error=Signal::derive(move || period.get().err()) mapping_error=Signal::derive(move || mapping_error.get()) logs=logs /> })}
                        <div class="charts">
                            <ChartCanvas label="Current of each open log" chart=overlay_current x_view=time_view />
                            <ChartCanvas label="Measured force of each open log" chart=overlay_force x_view=time_view height_px=200 />
                            <ChartCanvas label="Signal chain on the chosen column" chart=chain_chart x_view=time_view />
                            <ChartCanvas label="Spectrum of the chosen column" chart=spectrum />
                        </div>
                        {move || chain_done.get().map(|out| view! { <ChainReport out=out column=chain_column.get_untracked() /> })}
                        <h2>"Calibration"</h2>
                        {move || fit_done.get().map(|f| view! {
                            <p role="status" class="finding">{format!("Fit: {}", f.quality())}</p>
                            <ul class="hint">{f.notes.iter().map(|n| view! { <li>{n.clone()}</li> }).collect_view()}</ul>
                        })}
                        <ChartCanvas label="Calibration fit: current against force" chart=calibration_chart />
                        <h2>"Replay"</h2>
                        <div class="charts">
                            <ChartCanvas label="Replayed override" chart=replay_override x_view=time_view />
                            <ChartCanvas label="Replayed force estimate" chart=replay_force x_view=time_view />
                        </div>
                        {move || replay_done.get().map(|results| view! { <ReplayReport results=results /> })}
                    </Later>
                </div>
            </div>
        </section>
    }
}

/// The blobs of a file list, with their names.
fn files_of(files: Option<web_sys::FileList>) -> Vec<(String, web_sys::Blob)> {
    let Some(files) = files else {
        return Vec::new();
    };
    (0..files.length())
        .filter_map(|i| files.get(i))
        .map(|f| (f.name(), f.into()))
        .collect()
}

/// What the reader found in the active log, and its column mapping.
#[component]
fn LogSummary(
    l: LoadedLog,
    period_text: RwSignal<String>,
    #[prop(into)] period_error: Signal<Option<String>>,
    #[prop(into)] mapping_error: Signal<Option<String>>,
    logs: Logs,
) -> impl IntoView {
    let log = l.log.clone();
    let dialect = format!(
        "{}: {} rows, {} columns; delimiter {}, decimal {}, {}; time {}; sample period {}; {} MB read in {:.2} s.",
        l.name,
        log.rows,
        log.columns.len(),
        log.dialect.delimiter_name(),
        if log.dialect.decimal_comma { "comma" } else { "point" },
        if log.header { "a header" } else { "no header" },
        log.time_column
            .and_then(|t| log.columns.get(t))
            .map_or("none".to_string(), |c| c.name.clone()),
        log.sample_period_s
            .map_or("unknown".to_string(), |p| format!("{} s", readable(p))),
        readable(l.bytes as f64 / 1e6),
        l.load_s
    );
    let problems: Vec<String> = log
        .problems
        .iter()
        .take(10)
        .map(|p| {
            format!(
                "line {}{}: {}",
                p.line,
                p.column
                    .as_deref()
                    .map_or(String::new(), |c| format!(", {c}")),
                p.message
            )
        })
        .collect();
    let more = log.problems.len().saturating_sub(10) + log.problems_not_listed;
    let not_read = log.account.unread();
    let needs_period = log.time_column.is_none();
    let options: Vec<(String, String)> = std::iter::once((String::new(), "—".to_string()))
        .chain(
            Channel::ALL
                .iter()
                .map(|c| (c.name().to_string(), c.label().to_string())),
        )
        .collect();
    view! {
        <section aria-labelledby="log-summary-title">
            <h2 id="log-summary-title">"The log"</h2>
            <p role="status">{dialect}</p>
            {(!not_read.is_empty()).then(|| view! {
                <p class="hint">{format!("Not read as data: {}.", not_read.join("; "))}</p>
            })}
            {(!problems.is_empty()).then(|| view! {
                <details>
                    <summary>{format!("{} problems, by line and column", problems.len() + more)}</summary>
                    <ul>{problems.into_iter().map(|p| view! { <li>{p}</li> }).collect_view()}</ul>
                    {(more > 0).then(|| view! { <p class="hint">{format!("… and {more} more")}</p> })}
                </details>
            })}
            {needs_period.then(|| view! {
                <NumberField id="log-period" label="Sample period (the log has no time column)" unit="s" value=period_text error=period_error />
            })}
            <table class="metrics">
                <caption>"Columns and what they carry (the mapping replay and calibration read)"</caption>
                <thead>
                    <tr>
                        <th scope="col">"Column"</th>
                        <th scope="col">"Kind"</th>
                        <th scope="col">"Unit"</th>
                        <th scope="col">"Missing"</th>
                        <th scope="col">"Not finite"</th>
                        <th scope="col">"Guessed from"</th>
                        <th scope="col">"Channel"</th>
                    </tr>
                </thead>
                <tbody>
                    {log.columns
                        .iter()
                        .enumerate()
                        .map(|(i, c)| {
                            let id = format!("map-{}-{i}", l.id);
                            let name = c.name.clone();
                            let current = l.mapping.channel_of(&c.name).map_or(String::new(), |ch| ch.name().to_string());
                            let options = options.clone();
                            view! {
                                <tr>
                                    <th scope="row"><label for=id.clone()>{c.name.clone()}</label></th>
                                    <td>{format!("{:?}", c.kind).to_lowercase()}</td>
                                    <td>{c.unit.clone().unwrap_or_else(|| "—".into())}</td>
                                    <td>{c.missing}</td>
                                    <td>{c.not_finite}</td>
                                    <td>{c.role_reason.clone().unwrap_or_else(|| "—".into())}</td>
                                    <td>
                                        <select
                                            id=id
                                            on:change=move |ev| logs.set_channel(&name, Channel::from_name(&event_target_value(&ev)))
                                        >
                                            {options
                                                .into_iter()
                                                .map(|(v, text)| {
                                                    let selected = v == current;
                                                    view! { <option value=v selected=selected>{text}</option> }
                                                })
                                                .collect_view()}
                                        </select>
                                    </td>
                                </tr>
                            }
                        })
                        .collect_view()}
                </tbody>
            </table>
            {move || mapping_error.get().map(|e| view! { <p class="run-error" role="alert">{e}</p> })}
        </section>
    }
}

/// Statistics per label and the chain's notes and peaks.
#[component]
fn ChainReport(out: Arc<ChainOutput>, column: String) -> impl IntoView {
    let a = &out.analysis;
    let number = |v: Option<f64>| v.map_or("—".to_string(), readable);
    let mut rows = vec![("All rows".to_string(), a.whole)];
    rows.extend(a.by_label.iter().map(|l| (l.label.clone(), l.stats)));
    view! {
        <section aria-labelledby="chain-report-title">
            <h2 id="chain-report-title">{format!("Statistics of {column}")}</h2>
            <ul class="hint">{a.notes.iter().map(|n| view! { <li>{n.clone()}</li> }).collect_view()}</ul>
            <table class="metrics">
                <caption>"Per label segment (after the low-pass, if any)"</caption>
                <thead>
                    <tr>
                        <th scope="col">"Segment"</th>
                        <th scope="col">"Rows"</th>
                        <th scope="col">"Duration (s)"</th>
                        <th scope="col">"Mean"</th>
                        <th scope="col">"RMS"</th>
                        <th scope="col">"Min"</th>
                        <th scope="col">"Max"</th>
                    </tr>
                </thead>
                <tbody>
                    {rows
                        .into_iter()
                        .map(|(label, s)| view! {
                            <tr>
                                <th scope="row">{label}</th>
                                <td>{s.count}</td>
                                <td>{number(s.duration_s)}</td>
                                <td>{number(s.mean)}</td>
                                <td>{number(s.rms)}</td>
                                <td>{number(s.min)}</td>
                                <td>{number(s.max)}</td>
                            </tr>
                        })
                        .collect_view()}
                </tbody>
            </table>
            <p class="hint" role="status">
                {if a.peaks.is_empty() {
                    "No spectral peaks.".to_string()
                } else {
                    format!(
                        "Spectral peaks: {}.",
                        a.peaks.iter().map(|p| format!("{} Hz", readable(p.freq_hz))).collect::<Vec<_>>().join(", ")
                    )
                }}
            </p>
        </section>
    }
}

/// Each replay's numbers and events.
#[component]
fn ReplayReport(results: Vec<Arc<ReplayResult>>) -> impl IntoView {
    let number = |v: Option<f64>| v.map_or("—".to_string(), readable);
    let metric_rows: Vec<(&'static str, Vec<String>)> = vec![
        (
            "Armed at (s)",
            results
                .iter()
                .map(|r| number(r.summary.armed_at_s))
                .collect(),
        ),
        (
            "Override min (%)",
            results
                .iter()
                .map(|r| number(r.summary.override_min_pct))
                .collect(),
        ),
        (
            "Override mean (%)",
            results
                .iter()
                .map(|r| number(r.summary.override_mean_pct))
                .collect(),
        ),
        (
            "Override max (%)",
            results
                .iter()
                .map(|r| number(r.summary.override_max_pct))
                .collect(),
        ),
        (
            "Logged override mean (%)",
            results
                .iter()
                .map(|r| number(r.summary.logged_override_mean_pct))
                .collect(),
        ),
        (
            "Periods limited by the envelope",
            results
                .iter()
                .map(|r| r.summary.periods_limited.to_string())
                .collect(),
        ),
        (
            "Sensor faults",
            results
                .iter()
                .map(|r| r.summary.sensor_faults.to_string())
                .collect(),
        ),
        (
            "Overload (feed hold) at (s)",
            results
                .iter()
                .map(|r| number(r.summary.overload_at_s))
                .collect(),
        ),
        (
            "Force estimate mean (N)",
            results
                .iter()
                .map(|r| number(r.summary.force_est_mean_n))
                .collect(),
        ),
    ];
    let notes = results.first().map(|r| r.notes.clone()).unwrap_or_default();
    view! {
        <section aria-labelledby="replay-report-title">
            <h2 id="replay-report-title">"Replayed controllers"</h2>
            <ul class="hint">{notes.into_iter().map(|n| view! { <li>{n}</li> }).collect_view()}</ul>
            <table class="metrics">
                <caption>"What each controller would have done on this log"</caption>
                <thead>
                    <tr>
                        <th scope="col">"Measure"</th>
                        {results.iter().map(|r| view! { <th scope="col">{r.controller.kind().label()}</th> }).collect_view()}
                    </tr>
                </thead>
                <tbody>
                    {metric_rows
                        .into_iter()
                        .map(|(name, values)| view! {
                            <tr>
                                <th scope="row">{name}</th>
                                {values.into_iter().map(|v| view! { <td>{v}</td> }).collect_view()}
                            </tr>
                        })
                        .collect_view()}
                </tbody>
            </table>
            {results
                .iter()
                .map(|r| {
                    let list = events(&r.trace);
                    view! {
                        <section class="event-log" aria-label=format!("Envelope events of {}", r.controller.kind().label())>
                            <h3>{format!("Envelope events: {}", r.controller.kind().label())}</h3>
                            {if list.is_empty() {
                                view! { <p class="hint">"No events."</p> }.into_any()
                            } else {
                                view! {
                                    <ol>
                                        {list.into_iter().take(50).map(|e| view! {
                                            <li><span class="event-time">{format!("{:.2} s", e.time_s)}</span>" "{e.message}</li>
                                        }).collect_view()}
                                    </ol>
                                }.into_any()
                            }}
                        </section>
                    }
                })
                .collect_view()}
        </section>
    }
}
