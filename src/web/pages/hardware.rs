//! Hardware: a real machine through its bridge over WebSerial, or the virtual device (the device
//! emulator running in this page behind the same protocol bytes), driven by the same closed loop
//! as Simulate and `cutlab host`.
//!
//! The page is a thin shell over [`crate::web::hardware::station::Station`], which holds the
//! core's [`crate::hardware::session::HardwareSession`], the port and the recording. Port events
//! and a 100 ms timer call into the station; the page shows a snapshot of it at most four times a
//! second (at once when the link state changes). Arming and the teach cut go through a
//! confirmation that lists the limits in force; Disarm, Escape and any alarm command the safe
//! override at once. Recordings go to IndexedDB every half second while they stream.

use std::rc::Rc;
use std::sync::Arc;
use std::time::Duration;

use leptos::prelude::*;
use wasm_bindgen::JsCast;

use crate::charts::{Axis, LineChart};
use crate::closed_loop::calibration_file::CalibrationFile;
use crate::closed_loop::definition::RunSetting;
use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::lab::RunResult;
use crate::control::registry::ControllerKind;
use crate::hardware::commissioning::{
    commissioned, with_commissioned, CHECKS, COMMISSIONED_DEVICES_KEY, REDUCE_ONLY_MAX_OVERRIDE_PCT,
};
use crate::hardware::recording::RecordingMeta;
use crate::hardware::session::{LinkState, SessionOptions, Stage, TaughtCalibration};
use crate::input::{parse_count, parse_number, parse_seed};
use crate::plant::presets::PlantEdits;
use crate::plant::Preset;
use crate::protocol::device::{DeviceConfig, DeviceEmulator, FaultInjection};
use crate::web::components::chart::ChartCanvas;
use crate::web::components::download::download_text;
use crate::web::components::fields::{NumberField, SelectField};
use crate::web::components::later::Later;
use crate::web::components::run_form::{
    ControllerFields, ControllerForm, ScenarioForm, SettingFields,
};
use crate::web::components::run_view::{MetricsTable, NamedRun};
use crate::web::components::saved_calibrations::stored_calibrations;
use crate::web::hardware::port::{
    now_s, web_serial_unavailable, Port, PortEvent, SerialLink, SerialSettings, Sink, VirtualLink,
};
use crate::web::hardware::station::{Effects, Snapshot, Station};
use crate::web::hardware::store::Store;
use crate::web::js::{describe, read_chosen_file};
use crate::web::route::{query_params, replace_query, Page};

/// How often the station's clock ticks (watchdogs, heartbeats, the store's flush).
const TICK: Duration = Duration::from_millis(100);
/// The fastest virtual device: at 20× real time it simulates 200 000 plant samples a second in
/// the page, beside the host's loop and the charts.
const MAX_TIME_SCALE: f64 = 20.0;
/// The page redraws the live view at most this often.
const PUBLISH_INTERVAL_S: f64 = 0.25;

/// Everything the page shows, as signals.
#[derive(Clone, Copy)]
struct Ui {
    snapshot: RwSignal<Snapshot>,
    charts: [RwSignal<LineChart>; 4],
    result: RwSignal<Option<Arc<RunResult>>>,
    recordings: RwSignal<Vec<RecordingMeta>>,
    active_recording: RwSignal<Option<u64>>,
    /// The outcome of the last action (connect, arm, …), shown beside the buttons.
    message: RwSignal<Option<String>>,
    /// What went wrong with the recordings store.
    store_error: RwSignal<Option<String>>,
    last_publish_s: StoredValue<f64>,
}

type StationRef = StoredValue<Station, LocalStorage>;

impl Ui {
    fn new() -> Self {
        let empty = || RwSignal::new(LineChart::new(Axis::linear("time (s)"), Axis::linear("")));
        Self {
            snapshot: RwSignal::new(Snapshot::default()),
            charts: [empty(), empty(), empty(), empty()],
            result: RwSignal::new(None),
            recordings: RwSignal::new(Vec::new()),
            active_recording: RwSignal::new(None),
            message: RwSignal::new(None),
            store_error: RwSignal::new(None),
            last_publish_s: StoredValue::new(f64::NEG_INFINITY),
        }
    }

    /// Copies the station into the signals (at most every [`PUBLISH_INTERVAL_S`] unless `now`).
    fn publish(self, station: StationRef, now: bool) {
        let t = now_s();
        if !now && t - self.last_publish_s.get_value() < PUBLISH_INTERVAL_S {
            return;
        }
        self.last_publish_s.set_value(t);
        let Some((snapshot, charts, result, active)) = station.try_update_value(|s| {
            (
                s.snapshot(),
                s.live_charts(),
                s.take_result(),
                s.recording().cloned(),
            )
        }) else {
            return;
        };
        self.snapshot.set(snapshot);
        for (signal, chart) in self.charts.iter().zip(charts) {
            signal.set(chart);
        }
        if let Some(r) = result {
            self.result.set(Some(r));
        }
        self.active_recording.set(active.as_ref().map(|m| m.id));
        if let Some(meta) = active {
            self.recordings
                .update(|list| match list.iter_mut().find(|m| m.id == meta.id) {
                    Some(m) => *m = meta,
                    None => list.push(meta),
                });
        }
    }

    /// Carries out what the station asked for: store writes, a list refresh, a redraw.
    fn apply(self, station: StationRef, effects: Effects) {
        let store = station.try_with_value(|s| s.store.clone()).flatten();
        for (meta, chunk) in effects.writes {
            match &store {
                Some(store) => {
                    let store = store.clone();
                    let error = self.store_error;
                    leptos::task::spawn_local(async move {
                        if let Err(e) = store.put(&meta, chunk).await {
                            error.set(Some(format!(
                                "The recording “{}” could not be saved in this browser: {e}. \
                                 Export it before leaving the page.",
                                meta.name
                            )));
                        }
                    });
                }
                None => {
                    station.try_update_value(|s| s.keep_in_memory(meta, chunk));
                }
            }
        }
        if effects.recording_closed {
            self.refresh_recordings(station);
        }
        self.publish(station, effects.state_changed);
    }

    /// Reads the list of recordings from the store again.
    fn refresh_recordings(self, station: StationRef) {
        let Some(store) = station.try_with_value(|s| s.store.clone()).flatten() else {
            if let Some(list) = station.try_with_value(Station::memory_list) {
                self.recordings.set(list);
            }
            return;
        };
        let ui = self;
        leptos::task::spawn_local(async move {
            match store.list().await {
                Ok((list, unreadable)) => {
                    ui.recordings.set(list);
                    if unreadable > 0 {
                        ui.store_error.set(Some(format!(
                            "{unreadable} stored recording description(s) could not be read and \
                             are not listed."
                        )));
                    }
                    ui.publish(station, true);
                }
                Err(e) => ui
                    .store_error
                    .set(Some(format!("The recordings could not be listed: {e}"))),
            }
        });
    }
}

/// A port's events, into the station (ignored once connection `generation` is over).
fn sink(station: StationRef, ui: Ui, generation: u64) -> Sink {
    Rc::new(move |event: PortEvent| {
        let effects = station.try_update_value(|s| match &event {
            PortEvent::Bytes(bytes) => s.on_bytes(generation, bytes),
            PortEvent::Closed(why) => s.on_closed(generation, why),
        });
        if let Some(e) = effects {
            ui.apply(station, e);
        }
    })
}

/// The serial settings as typed.
#[derive(Clone, Copy)]
struct SerialForm {
    baud: RwSignal<String>,
    data_bits: RwSignal<String>,
    stop_bits: RwSignal<String>,
    parity: RwSignal<String>,
    flow: RwSignal<String>,
    buffer: RwSignal<String>,
}

impl SerialForm {
    fn new() -> Self {
        Self {
            baud: RwSignal::new("921600".into()),
            data_bits: RwSignal::new("8".into()),
            stop_bits: RwSignal::new("1".into()),
            parity: RwSignal::new("none".into()),
            flow: RwSignal::new("none".into()),
            buffer: RwSignal::new("4096".into()),
        }
    }

    fn baud_error(&self) -> Option<String> {
        match parse_count(&self.baud.get()) {
            Ok(b) if (300..=16_000_000).contains(&b) => None,
            Ok(b) => Some(format!("{b} baud is outside 300–16000000")),
            Err(e) => Some(e),
        }
    }

    fn buffer_error(&self) -> Option<String> {
        match parse_count(&self.buffer.get()) {
            Ok(b) if (255..=16_777_216).contains(&b) => None,
            Ok(b) => Some(format!("{b} bytes is outside 255–16777216")),
            Err(e) => Some(e),
        }
    }

    fn parse(&self) -> Option<SerialSettings> {
        if self.baud_error().is_some() || self.buffer_error().is_some() {
            return None;
        }
        Some(SerialSettings {
            baud_rate: parse_count(&self.baud.get()).ok()? as u32,
            data_bits: if self.data_bits.get() == "7" { 7 } else { 8 },
            stop_bits: if self.stop_bits.get() == "2" { 2 } else { 1 },
            parity: match self.parity.get().as_str() {
                "even" => "even",
                "odd" => "odd",
                _ => "none",
            },
            flow_control: if self.flow.get() == "hardware" {
                "hardware"
            } else {
                "none"
            },
            buffer_size: parse_count(&self.buffer.get()).ok()? as u32,
        })
    }
}

/// The virtual device's switches as typed: the same as `cutlab device`'s.
#[derive(Clone, Copy)]
struct VirtualForm {
    preset: RwSignal<String>,
    seed: RwSignal<String>,
    time_scale: RwSignal<String>,
    drop_rate: RwSignal<String>,
    noise_rate: RwSignal<String>,
    stall_at: RwSignal<String>,
    stall_for: RwSignal<String>,
    unplug_at: RwSignal<String>,
    watchdog: RwSignal<String>,
    fallback: RwSignal<String>,
    /// Send the simulation's truth (off: a real bridge's twin, `cutlab device --no-truth`).
    truth: RwSignal<bool>,
}

/// A field's number, `None` when blank.
fn optional(text: &str) -> Result<Option<f64>, String> {
    if text.trim().is_empty() {
        Ok(None)
    } else {
        parse_number(text).map(Some)
    }
}

impl VirtualForm {
    fn new(preset: &str) -> Self {
        Self {
            preset: RwSignal::new(preset.to_string()),
            seed: RwSignal::new("1".into()),
            time_scale: RwSignal::new("1".into()),
            drop_rate: RwSignal::new("0".into()),
            noise_rate: RwSignal::new("0".into()),
            stall_at: RwSignal::new(String::new()),
            stall_for: RwSignal::new(String::new()),
            unplug_at: RwSignal::new(String::new()),
            watchdog: RwSignal::new("0.5".into()),
            fallback: RwSignal::new("50".into()),
            truth: RwSignal::new(true),
        }
    }

    /// Each field's error, by field.
    fn error(&self, field: &str) -> Option<String> {
        let number = |s: RwSignal<String>| parse_number(&s.get()).err();
        match field {
            "seed" => parse_seed(&self.seed.get()).err(),
            "time_scale" => match parse_number(&self.time_scale.get()) {
                Ok(k) if (0.1..=MAX_TIME_SCALE).contains(&k) => None,
                Ok(k) => Some(format!("{k} is outside 0.1–{MAX_TIME_SCALE}")),
                Err(e) => Some(e),
            },
            "drop_rate" => number(self.drop_rate),
            "noise_rate" => number(self.noise_rate),
            "watchdog" => number(self.watchdog),
            "fallback" => number(self.fallback),
            "stall_at" => optional(&self.stall_at.get()).err(),
            "stall_for" => optional(&self.stall_for.get()).err(),
            "unplug_at" => optional(&self.unplug_at.get()).err(),
            _ => None,
        }
    }

    /// The emulator and its time scale, or why not.
    fn parse(&self) -> Result<(DeviceEmulator, f64), String> {
        let preset = Preset::from_name(&self.preset.get())
            .ok_or_else(|| "choose the virtual device's program".to_string())?;
        let field = |name: &str, text: &str| parse_number(text).map_err(|e| format!("{name}: {e}"));
        let opt = |name: &str, text: &str| optional(text).map_err(|e| format!("{name}: {e}"));
        let mut config = DeviceConfig::new(preset);
        config.sim_truth = self.truth.get();
        config.seed = parse_seed(&self.seed.get()).map_err(|e| format!("seed: {e}"))?;
        config.watchdog_timeout_s = field("device watchdog", &self.watchdog.get())?;
        config.fallback_override_pct = field("fallback override", &self.fallback.get())?;
        let stall_at_s = opt("stall at", &self.stall_at.get())?;
        let stall_s = opt("stall for", &self.stall_for.get())?;
        if stall_at_s.is_some() != stall_s.is_some() {
            return Err(
                "a stall needs both when it starts and how long it lasts (or neither)".into(),
            );
        }
        config.faults = FaultInjection {
            drop_rate: field("drop rate", &self.drop_rate.get())?,
            noise_rate: field("noise rate", &self.noise_rate.get())?,
            stall_at_s,
            stall_s: stall_s.unwrap_or(0.0),
            unplug_at_s: opt("unplug at", &self.unplug_at.get())?,
            ..FaultInjection::default()
        };
        let scale = parse_number(&self.time_scale.get()).map_err(|e| format!("time scale: {e}"))?;
        if !(0.1..=MAX_TIME_SCALE).contains(&scale) {
            return Err(format!(
                "time scale: {scale} is outside 0.1–{MAX_TIME_SCALE}"
            ));
        }
        let device = DeviceEmulator::new(config).map_err(|e| e.to_string())?;
        Ok((device, scale))
    }
}

/// A pending confirmation: a teach cut or arming, with the limits it will run under.
#[derive(Clone, PartialEq)]
struct Confirm {
    teach: bool,
    lines: Vec<String>,
    spec: RunSpec,
    /// The device's identity, when this is the first Arm on a real device not yet commissioned
    /// in this browser: the confirmation then names every commissioning check.
    uncommissioned: Option<String>,
}

/// The devices commissioned in this browser (their identities, one a line).
fn commissioned_devices() -> Option<String> {
    window()
        .local_storage()
        .ok()
        .flatten()
        .and_then(|s| s.get_item(COMMISSIONED_DEVICES_KEY).ok().flatten())
}

/// Remembers that the engineer confirmed every commissioning check for `device_id`.
fn remember_commissioned(device_id: &str) {
    if let Some(storage) = window().local_storage().ok().flatten() {
        let text = with_commissioned(commissioned_devices().as_deref(), device_id);
        let _ = storage.set_item(COMMISSIONED_DEVICES_KEY, &text);
    }
}

/// The settings of the run shown in the Control panel, in order.
const RUN_SETTINGS: [RunSetting; 6] = [
    RunSetting::TargetForce,
    RunSetting::Feedback,
    RunSetting::MinOverride,
    RunSetting::MaxOverride,
    RunSetting::MaxRate,
    RunSetting::ArmingOverride,
];
const SIGNAL_SETTINGS: [RunSetting; 4] = [
    RunSetting::ControlPeriod,
    RunSetting::FilterOrder,
    RunSetting::SpindleCutoff,
    RunSetting::FeedCutoff,
];

/// On a real port the run starts from reduce-only limits: the highest override at most
/// [`REDUCE_ONLY_MAX_OVERRIDE_PCT`] (docs/hardware.md §7), whatever the form held.
fn reduce_only(scenario: ScenarioForm, ui: Ui) {
    let max = scenario.text(RunSetting::MaxOverride);
    let above =
        parse_number(&max.get_untracked()).map_or(true, |v| v > REDUCE_ONLY_MAX_OVERRIDE_PCT);
    if above {
        max.set(format!("{REDUCE_ONLY_MAX_OVERRIDE_PCT}"));
        ui.message.set(Some(format!(
            "A real port: reduce-only limits, the highest override set to \
             {REDUCE_ONLY_MAX_OVERRIDE_PCT} % (raise it only after the commissioning checks, \
             docs/hardware.md §10)."
        )));
    }
}

fn pct(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.1} %")
    } else {
        "—".into()
    }
}

/// The Hardware page.
#[component]
pub fn HardwarePage() -> impl IntoView {
    let query = query_params(&window().location().hash().unwrap_or_default());
    let scenario = ScenarioForm::new(&query);
    let controller = ControllerForm::new(
        "hw-",
        ControllerKind::Threshold,
        scenario.chosen_preset_untracked(),
        &query,
        "",
    );
    Effect::new(move |_| {
        if let Some(preset) = scenario.chosen_preset() {
            controller.follow_preset(preset);
        }
    });
    let station: StationRef = StoredValue::new_local(Station::default());
    let ui = Ui::new();
    let serial_form = SerialForm::new();
    let virtual_form = VirtualForm::new(&scenario.preset.get_untracked());
    let no_serial = web_serial_unavailable();

    // The run: the form's preset, controller and settings (no machine edits: the machine is
    // the device's).
    let spec = Memo::new(move |_| {
        let s = scenario.parse().ok()?;
        let c = controller.parse().ok()?;
        Some(RunSpec {
            preset: s.preset,
            controller: c,
            seed: s.seed,
            settings: s.settings,
            plant: PlantEdits::default(),
        })
    });
    Effect::new(move |_| {
        let mut q = scenario.query();
        q.extend(controller.query(""));
        replace_query(Page::Hardware, &q);
    });

    let state = Memo::new(move |_| ui.snapshot.with(|s| s.state));

    // The host's own safety settings.
    let safe_text = RwSignal::new(String::new());
    let watchdog_text = RwSignal::new("2".to_string());
    let safe_error = Signal::derive(move || optional(&safe_text.get()).err());
    let watchdog_error = Signal::derive(move || parse_number(&watchdog_text.get()).err());
    let options_error = RwSignal::new(None::<String>);
    Effect::new(move |_| {
        // Also when the link state changes: a change refused while armed applies after.
        state.track();
        let (Ok(safe), Ok(timeout)) = (
            optional(&safe_text.get()),
            parse_number(&watchdog_text.get()),
        ) else {
            return;
        };
        let result = SessionOptions::new(timeout, safe).and_then(|o| {
            station
                .try_update_value(|s| s.set_options(o))
                .unwrap_or(Ok(()))
        });
        options_error.set(result.err());
    });

    // The device's program names the preset whose settings the run takes, as in cutlab host.
    Effect::new(move |previous: Option<Option<String>>| {
        let program = ui
            .snapshot
            .with(|s| s.device.as_ref().map(|d| d.program.clone()));
        if program != previous.clone().flatten() {
            if let Some(p) = program.as_deref().and_then(Preset::from_name) {
                scenario.preset.set(p.name().to_string());
            }
        }
        program
    });

    // The clock, the store, Escape, and leaving the page.
    if let Ok(handle) = set_interval_with_handle(
        move || {
            if let Some(e) = station.try_update_value(Station::tick) {
                ui.apply(station, e);
            }
            ui.publish(station, false);
        },
        TICK,
    ) {
        on_cleanup(move || handle.clear());
    }
    leptos::task::spawn_local(async move {
        match Store::open().await {
            Ok(store) => {
                station.try_update_value(|s| s.store = Some(store));
                ui.refresh_recordings(station);
            }
            Err(e) => ui.store_error.set(Some(format!(
                "Recordings cannot be stored in this browser ({e}): they are kept in this page's \
                 memory only; export each before leaving the page."
            ))),
        }
    });
    let escape = window_event_listener(leptos::ev::keydown, move |ev| {
        if ev.key() == "Escape" && station.try_with_value(Station::running) == Some(true) {
            if let Some(e) = station.try_update_value(|s| s.disarm("Escape pressed")) {
                ui.apply(station, e);
            }
        }
    });
    on_cleanup(move || escape.remove());
    on_cleanup(move || {
        // Leaving the page hands a held device back, as Disconnect does.
        if let Some(e) = station.try_update_value(Station::disconnect) {
            for (meta, chunk) in e.writes {
                if let Some(store) = station.try_with_value(|s| s.store.clone()).flatten() {
                    leptos::task::spawn_local(async move {
                        let _ = store.put(&meta, chunk).await;
                    });
                }
            }
        }
    });

    // Connecting.
    let connect_serial = move |_| {
        ui.message.set(None);
        let Some(settings) = serial_form.parse() else {
            ui.message
                .set(Some("Fix the serial settings marked above first.".into()));
            return;
        };
        let Some(generation) = station.try_update_value(Station::next_generation) else {
            return;
        };
        let port_sink = sink(station, ui, generation);
        leptos::task::spawn_local(async move {
            match SerialLink::open(settings, port_sink).await {
                Ok(link) => {
                    let mut port = Some(Port::Serial(link));
                    station.try_update_value(|s| {
                        if s.generation() == generation && !s.connected() {
                            if let Some(p) = port.take() {
                                s.connect(p, generation);
                            }
                        }
                    });
                    if let Some(mut stale) = port {
                        stale.close();
                    } else {
                        reduce_only(scenario, ui);
                    }
                    ui.publish(station, true);
                }
                Err(e) => ui.message.set(Some(format!("Not connected: {e}."))),
            }
        });
    };
    let start_virtual = move |_| {
        ui.message.set(None);
        let (device, scale) = match virtual_form.parse() {
            Ok(v) => v,
            Err(e) => {
                ui.message
                    .set(Some(format!("The virtual device cannot start: {e}.")));
                return;
            }
        };
        let Some(generation) = station.try_update_value(Station::next_generation) else {
            return;
        };
        match VirtualLink::start(device, scale, sink(station, ui, generation)) {
            Ok(link) => {
                station.try_update_value(|s| s.connect(Port::Virtual(link), generation));
                ui.publish(station, true);
            }
            Err(e) => ui.message.set(Some(e)),
        }
    };
    let disconnect = move |_| {
        ui.message.set(None);
        if let Some(e) = station.try_update_value(Station::disconnect) {
            ui.apply(station, e);
        }
    };
    let unplug = move |_| {
        station.try_with_value(Station::unplug_virtual);
    };

    // Calibrations: loaded from a file (cutlab sim/host --save-calibration, cutlab calibrate),
    // saved after a teach cut over the link.
    let calibration_error = RwSignal::new(None::<String>);
    let use_calibration = move |file: CalibrationFile, source: String| {
        station.try_update_value(|s| {
            s.set_calibration(TaughtCalibration {
                calibration: file.calibration,
                settings: None,
                source,
            })
        });
        calibration_error.set(None);
        ui.publish(station, true);
    };
    let load_calibration = move |ev: leptos::ev::Event| {
        read_chosen_file(&ev, move |name, text| {
            match text
                .and_then(|t| CalibrationFile::from_json(&t).map_err(|e| format!("{name}: {e}")))
            {
                Ok(file) => {
                    let source = if file.source.is_empty() {
                        format!("file {name}")
                    } else {
                        format!("file {name} ({})", file.source)
                    };
                    use_calibration(file, source);
                }
                Err(e) => calibration_error.set(Some(e)),
            }
        });
    };
    // The calibrations saved in this browser (the Logs page saves them), read again whenever
    // the list is opened so one saved in another tab shows up.
    let saved = RwSignal::new(stored_calibrations());
    let refresh_saved = move |_| saved.set(stored_calibrations());
    let use_saved = move |ev: leptos::ev::Event| {
        let chosen = event_target_value(&ev);
        let Ok(index) = chosen.parse::<usize>() else {
            return;
        };
        match saved.with_untracked(|(files, _)| files.get(index).cloned()) {
            Some(file) => {
                let source = format!("saved in this browser: {}", file.source);
                use_calibration(file, source);
            }
            None => calibration_error.set(Some(
                "that saved calibration is gone (deleted in another tab?)".into(),
            )),
        }
    };
    let save_calibration = move |_| {
        let Some(file) = station.try_with_value(Station::calibration_file).flatten() else {
            return;
        };
        calibration_error.set(
            download_text(
                "cutlab-calibration.json",
                "application/json",
                &file.to_json(),
            )
            .err(),
        );
    };

    // Teach cut and arming, through the confirmation.
    let dialog_ref = NodeRef::<leptos::html::Dialog>::new();
    let pending = RwSignal::new(None::<Confirm>);
    let ticked = RwSignal::new(vec![false; CHECKS.len()]);
    let ask = move |teach: bool| {
        ui.message.set(None);
        ticked.set(vec![false; CHECKS.len()]);
        let Some(spec) = spec.get_untracked() else {
            ui.message.set(Some(
                "Fix the settings marked in the Control panel first.".into(),
            ));
            return;
        };
        match station.try_with_value(|s| s.limits(teach, &spec)) {
            Some(Ok(limits)) => {
                let device_id = ui
                    .snapshot
                    .with_untracked(|s| s.device.as_ref().map(|d| d.device_id.clone()));
                let on_serial = station.try_with_value(Station::on_serial_port) == Some(true);
                let uncommissioned = device_id
                    .filter(|id| on_serial && !commissioned(commissioned_devices().as_deref(), id));
                pending.set(Some(Confirm {
                    teach,
                    lines: limits.lines,
                    spec,
                    uncommissioned,
                }));
                if let Some(d) = dialog_ref.get_untracked() {
                    let _ = d.show_modal();
                }
            }
            Some(Err(e)) => ui.message.set(Some(format!("Cannot start: {e}."))),
            None => {}
        }
    };
    let confirm = move |_| {
        if let Some(d) = dialog_ref.get_untracked() {
            d.close();
        }
        let Some(c) = pending.get_untracked() else {
            return;
        };
        if let Some(id) = &c.uncommissioned {
            if !ticked.with_untracked(|t| t.iter().all(|&x| x)) {
                return;
            }
            remember_commissioned(id);
        }
        pending.set(None);
        match station.try_update_value(|s| s.start(c.teach, &c.spec)) {
            Some(Ok(e)) => ui.apply(station, e),
            Some(Err(e)) => ui.message.set(Some(format!("Cannot start: {e}."))),
            None => {}
        }
    };
    let cancel = move |_| {
        if let Some(d) = dialog_ref.get_untracked() {
            d.close();
        }
        pending.set(None);
    };
    let disarm = move |_| {
        if let Some(e) = station.try_update_value(|s| s.disarm("disarmed by the operator")) {
            ui.apply(station, e);
        }
    };
    let reset_hold = move |_| match station.try_update_value(Station::reset_hold) {
        Some(Ok(e)) => {
            ui.message.set(None);
            ui.apply(station, e);
        }
        Some(Err(e)) => ui.message.set(Some(format!("Not reset: {e}."))),
        None => {}
    };
    let acknowledge = move |_| match station.try_update_value(Station::acknowledge) {
        Some(Ok(e)) => {
            ui.message.set(None);
            ui.apply(station, e);
        }
        Some(Err(e)) => ui.message.set(Some(format!("The alarm stays: {e}."))),
        None => {}
    };

    let stage = Memo::new(move |_| ui.snapshot.with(|s| s.stage));
    let connected = Memo::new(move |_| ui.snapshot.with(|s| s.port.is_some()));
    let is_virtual = Memo::new(move |_| ui.snapshot.with(|s| s.port == Some("the virtual device")));
    let x_view = RwSignal::new(None::<std::ops::Range<f64>>);
    let chart = move |i: usize| Signal::derive(move || ui.charts[i].get());

    view! {
        <section class="page hardware" aria-labelledby="hardware-title">
            <h1 id="hardware-title">"Hardware: a machine over the serial line"</h1>
            <p class="lede">
                "Connect the bridge on a real machine (Hall sensors in, feed override out; "
                <code>"docs/hardware.md"</code>
                " says how to build and wire one) over WebSerial, or start the virtual device: the "
                "simulated machine running in "
                "this page behind the same protocol bytes, with the same fault switches as "
                <code>"cutlab device"</code>
                ". The teach cut and the closed loop are the ones Simulate runs; everything "
                "received is recorded as it streams."
            </p>
            {no_serial.map(|why| view! {
                <section class="panel notice" role="note" aria-labelledby="no-serial-title">
                    <h2 id="no-serial-title">"WebSerial is not available here"</h2>
                    <p>{format!("The Connect button cannot reach a serial port: {why}.")}</p>
                    <p>
                        "What works instead: the virtual device below, in any browser — the "
                        "whole hardware run with its link faults and watchdogs, without a "
                        "machine; Chrome or Edge on a desktop, with the lab served over https "
                        "or on localhost ("
                        <code>"scripts/serve"</code>
                        "); or the command line, which opens the port itself: "
                        <code>"cutlab host --port /dev/ttyUSB0 --baud 921600 --controller threshold"</code>
                        "."
                    </p>
                </section>
            })}
            <div class="layout-two">
                <div class="panel-stack">
                    <form class="panel" aria-label="Connection" on:submit=|ev| ev.prevent_default()>
                        <fieldset>
                            <legend>"Serial port"</legend>
                            <NumberField
                                id="hw-baud"
                                label="Baud rate".to_string()
                                unit="bit/s"
                                value=serial_form.baud
                                error=Signal::derive(move || serial_form.baud_error())
                                step="1"
                            />
                            <SelectField id="hw-data-bits" label="Data bits" options=vec![("8", "8"), ("7", "7")] value=serial_form.data_bits />
                            <SelectField id="hw-parity" label="Parity" options=vec![("none", "none"), ("even", "even"), ("odd", "odd")] value=serial_form.parity />
                            <SelectField id="hw-stop-bits" label="Stop bits" options=vec![("1", "1"), ("2", "2")] value=serial_form.stop_bits />
                            <SelectField id="hw-flow" label="Flow control" options=vec![("none", "none"), ("hardware", "hardware (RTS/CTS)")] value=serial_form.flow />
                            <NumberField
                                id="hw-buffer"
                                label="Read buffer".to_string()
                                unit="bytes"
                                value=serial_form.buffer
                                error=Signal::derive(move || serial_form.buffer_error())
                                step="1"
                            />
                            <div class="button-row">
                                <button
                                    type="button"
                                    class="primary"
                                    on:click=connect_serial
                                    disabled=move || no_serial.is_some() || connected.get()
                                >
                                    "Connect to a serial port…"
                                </button>
                            </div>
                        </fieldset>
                        <Later>
                            <fieldset>
                                <legend>"Virtual device"</legend>
                                <SelectField
                                    id="hw-virtual-preset"
                                    label="Program (preset)"
                                    options=Preset::ALL.iter().map(|p| (p.name(), p.label())).collect()
                                    value=virtual_form.preset
                                />
                                {[
                                    ("seed", "hw-virtual-seed", "Seed", "", virtual_form.seed),
                                    ("time_scale", "hw-time-scale", "Time scale", "× real time", virtual_form.time_scale),
                                    ("drop_rate", "hw-drop-rate", "Drop rate", "0–1 per frame", virtual_form.drop_rate),
                                    ("noise_rate", "hw-noise-rate", "Noise rate", "0–1 per frame", virtual_form.noise_rate),
                                    ("stall_at", "hw-stall-at", "Receiver stall at", "s, blank: none", virtual_form.stall_at),
                                    ("stall_for", "hw-stall-for", "Receiver stall for", "s", virtual_form.stall_for),
                                    ("unplug_at", "hw-unplug-at", "Cable pulled at", "s, blank: never", virtual_form.unplug_at),
                                    ("watchdog", "hw-device-watchdog", "Device watchdog", "s", virtual_form.watchdog),
                                    ("fallback", "hw-fallback", "Device fallback override", "%", virtual_form.fallback),
                                ]
                                    .into_iter()
                                    .map(|(key, id, label, unit, value)| {
                                        view! {
                                            <NumberField
                                                id=id
                                                label=label.to_string()
                                                unit=unit
                                                value=value
                                                error=Signal::derive(move || virtual_form.error(key))
                                            />
                                        }
                                    })
                                    .collect_view()}
                                <label class="check">
                                    <input
                                        type="checkbox"
                                        prop:checked=move || virtual_form.truth.get()
                                        on:change=move |ev| virtual_form.truth.set(event_target_checked(&ev))
                                    />
                                    "Send the simulation's truth (off: a real bridge's twin)"
                                </label>
                                <div class="button-row">
                                    <button type="button" on:click=start_virtual disabled=move || connected.get()>
                                        "Start the virtual device"
                                    </button>
                                    <button type="button" on:click=unplug hidden=move || !is_virtual.get()>
                                        "Pull the virtual cable"
                                    </button>
                                </div>
                                <p class="hint">
                                    "Times are device seconds from power-on. Each frame either way is lost "
                                    "(drop) or corrupted (noise) with its rate; a stall makes the device deaf."
                                </p>
                            </fieldset>
                        </Later>
                        <div class="button-row">
                            <button type="button" on:click=disconnect disabled=move || !connected.get()>
                                "Disconnect"
                            </button>
                        </div>
                    </form>
                    // The run's form, and the virtual device's fields above, each mount in a task of
                    // their own: with the serial port's they took the page's first task past 50 ms.
                    <Later>
                        <form class="panel" aria-label="Control" on:submit=|ev| ev.prevent_default()>
                            <fieldset>
                                <legend>"Run settings"</legend>
                                <SelectField
                                    id="preset"
                                    label="Preset (the run's settings)"
                                    options=Preset::ALL.iter().map(|p| (p.name(), p.label())).collect()
                                    value=scenario.preset
                                />
                                <p class="hint">"Follows the program the device names, as cutlab host does."</p>
                            </fieldset>
                            <ControllerFields form=controller />
                            <SettingFields form=scenario legend="Target and safety envelope" settings=RUN_SETTINGS.to_vec() />
                            <fieldset>
                                <legend>"Host safety"</legend>
                                <NumberField
                                    id="hw-safe-override"
                                    label="Safe override (blank: the device's fallback)".to_string()
                                    unit="%"
                                    value=safe_text
                                    error=safe_error
                                />
                                <NumberField
                                    id="hw-host-watchdog"
                                    label="Host watchdog".to_string()
                                    unit="s"
                                    value=watchdog_text
                                    error=watchdog_error
                                />
                                {move || options_error.get().map(|e| view! { <p class="field-error" role="alert">{e}</p> })}
                            </fieldset>
                            <SettingFields form=scenario legend="Signal chain" settings=SIGNAL_SETTINGS.to_vec() />
                            <fieldset>
                                <legend>"Calibration"</legend>
                                <p class="calibration">
                                    {move || ui.snapshot.with(|s| s.calibration.clone()).map_or_else(
                                        || "None yet: make a teach cut over the link, or load a saved calibration.".to_string(),
                                        |c| format!("In use: {c}"),
                                    )}
                                </p>
                                <div class="field">
                                    <label for="hw-calibration-file">"Load a calibration file (cutlab-calibration JSON)"</label>
                                    <input
                                        id="hw-calibration-file"
                                        type="file"
                                        accept=".json,application/json"
                                        on:change=load_calibration
                                        aria-describedby="hw-calibration-error"
                                    />
                                </div>
                                <div class="field">
                                    <label for="hw-saved-calibration">"Or one saved in this browser (Logs page)"</label>
                                    <select
                                        id="hw-saved-calibration"
                                        on:focus=refresh_saved
                                        on:change=use_saved
                                        aria-describedby="hw-calibration-error hw-saved-problems"
                                    >
                                        <option value="" selected=true>
                                            {move || if saved.with(|(files, _)| files.is_empty()) {
                                                "None saved yet"
                                            } else {
                                                "Choose a saved calibration…"
                                            }}
                                        </option>
                                        {move || saved.with(|(files, _)| files.iter().enumerate().map(|(i, f)| {
                                            view! { <option value=i.to_string()>{f.source.clone()}</option> }
                                        }).collect_view())}
                                    </select>
                                    <p class="hint" id="hw-saved-problems">
                                        {move || saved.with(|(_, problems)| problems.join("; "))}
                                    </p>
                                    <p class="field-error" id="hw-calibration-error" aria-live="polite">
                                        {move || calibration_error.get().unwrap_or_default()}
                                    </p>
                                </div>
                                <div class="button-row">
                                    <button
                                        type="button"
                                        on:click=save_calibration
                                        disabled=move || ui.snapshot.with(|s| s.calibration.is_none())
                                    >
                                        "Save the calibration (JSON)"
                                    </button>
                                </div>
                            </fieldset>
                        </form>
                    </Later>
                </div>
                <div class="results">
                    <LinkPanel ui=ui>
                        <div class="button-row actions" role="group" aria-label="Control actions">
                            <button type="button" on:click=move |_| ask(true) disabled=move || state.get() != Some(LinkState::Streaming)>
                                "Teach cut…"
                            </button>
                            <button type="button" class="primary" on:click=move |_| ask(false) disabled=move || state.get() != Some(LinkState::Streaming)>
                                "Arm…"
                            </button>
                            <button
                                type="button"
                                class="danger"
                                on:click=disarm
                                disabled=move || !matches!(stage.get(), Some(Stage::TeachCut | Stage::ClosedLoop))
                            >
                                "Disarm (Esc)"
                            </button>
                            <button type="button" on:click=acknowledge hidden=move || state.get() != Some(LinkState::Alarm)>
                                "Acknowledge the alarm"
                            </button>
                            <button
                                type="button"
                                class="danger"
                                on:click=reset_hold
                                hidden=move || ui.snapshot.with(|s| s.hold.is_none())
                            >
                                "Reset the feed hold"
                            </button>
                        </div>
                        {move || ui.message.get().map(|m| view! { <p class="run-error" role="alert">{m}</p> })}
                    </LinkPanel>
                    <section aria-labelledby="live-title">
                        <h2 id="live-title">"Live view"</h2>
                        <p class="hint">
                            "The last 30 s of device time at the device's rate. Zooming holds the "
                            "view still; Reset zoom (or 0) follows the stream again."
                        </p>
                        // The charts, results and recordings in the task after the forms':
                        // together they took the page's first task past 50 ms.
                        <Later>
                            <div class="charts">
                                <ChartCanvas label="Live motor current" chart=chart(0) height_px=190 x_view=x_view />
                                <ChartCanvas label="Live cutting force" chart=chart(1) height_px=190 x_view=x_view />
                                <ChartCanvas label="Live feed override" chart=chart(2) height_px=160 x_view=x_view />
                                <ChartCanvas label="Live feed rate" chart=chart(3) height_px=150 x_view=x_view />
                            </div>
                        </Later>
                    </section>
                    <Later>
                        <MetricsTable runs=Signal::derive(move || {
                            ui.result
                                .get()
                                .map(|r| vec![(format!("{} over the link", r.spec.controller.kind().label()), r) as NamedRun])
                                .unwrap_or_default()
                        }) />
                        <EventList ui=ui />
                        <Recordings ui=ui station=station />
                    </Later>
                </div>
            </div>
            <dialog node_ref=dialog_ref class="confirm" aria-labelledby="confirm-title" on:cancel=move |_: web_sys::Event| pending.set(None)>
                {move || pending.get().map(|c| {
                    let title = if c.teach { "Start the teach cut?" } else { "Arm the controller?" };
                    view! {
                        <h2 id="confirm-title">{title}</h2>
                        <p>"The limits in force:"</p>
                        <ul>{c.lines.iter().map(|l| view! { <li>{l.clone()}</li> }).collect_view()}</ul>
                        <p class="hint">"Disarm or Escape returns the override to the safe value at once."</p>
                        {c.uncommissioned.clone().map(|id| view! {
                            <fieldset class="commissioning">
                                <legend>{format!("First arming of {id}: the commissioning checks (docs/hardware.md §10)")}</legend>
                                {CHECKS.iter().enumerate().map(|(i, check)| view! {
                                    <label class="check">
                                        <input
                                            type="checkbox"
                                            prop:checked=move || ticked.with(|t| t.get(i).copied().unwrap_or(false))
                                            on:change=move |ev| {
                                                let on = event_target_checked(&ev);
                                                ticked.update(|t| if let Some(x) = t.get_mut(i) { *x = on });
                                            }
                                        />
                                        {check.text}
                                    </label>
                                }).collect_view()}
                            </fieldset>
                        })}
                    }
                })}
                <div class="button-row">
                    <button
                        type="button"
                        class="primary"
                        on:click=confirm
                        disabled=move || pending.with(|p| p.as_ref().is_some_and(|c| c.uncommissioned.is_some()))
                            && !ticked.with(|t| t.iter().all(|&x| x))
                    >
                        {move || if pending.with(|p| p.as_ref().is_some_and(|c| c.teach)) { "Start the teach cut" } else { "Arm now" }}
                    </button>
                    <button type="button" on:click=cancel>"Cancel"</button>
                </div>
            </dialog>
        </section>
    }
}

/// The link: its state and why, the device, the counters.
#[component]
fn LinkPanel(ui: Ui, children: Children) -> impl IntoView {
    let s = ui.snapshot;
    let state_name = move || s.with(|s| s.state.map_or("closed", LinkState::name));
    let counters = move || {
        s.with(|s| {
            let st = &s.stats;
            vec![
                ("Frames received", st.frames_received.to_string()),
                ("Samples lost (sequence gaps)", st.frames_lost.to_string()),
                ("Samples out of order", st.frames_reordered.to_string()),
                (
                    "Frames rejected (CRC, COBS, size)",
                    st.frames_rejected.to_string(),
                ),
                (
                    "Bytes dropped while resynchronising",
                    st.bytes_dropped.to_string(),
                ),
                ("Frames of unknown type", st.frames_unknown.to_string()),
                ("Commands sent", st.commands_sent.to_string()),
                (
                    "Commands acknowledged",
                    st.commands_acknowledged.to_string(),
                ),
                ("Heartbeats sent", st.heartbeats_sent.to_string()),
                (
                    "Device watchdog fallbacks",
                    st.watchdog_fallbacks.to_string(),
                ),
                (
                    "Link losses (host watchdog, port lost)",
                    st.link_losses.to_string(),
                ),
                ("Device faults", st.device_faults.to_string()),
                (
                    "Command round trip, mean / max (ms)",
                    format!(
                        "{:.1} / {:.1}",
                        1000.0 * st.command_latency_mean_s,
                        1000.0 * st.command_latency_max_s
                    ),
                ),
            ]
        })
    };
    view! {
        <section class="panel link-panel" aria-labelledby="link-title">
            <h2 id="link-title">"Link"</h2>
            <p class="link-state" role="status">
                "Link state: "
                <strong class=move || format!("state state-{}", state_name())>{state_name}</strong>
                {move || s.with(|s| s.port.map(|p| format!(" — {p}")))}
            </p>
            {move || {
                let (state, reason) = s.with(|s| (s.state, s.reason.clone()));
                if state == Some(LinkState::Alarm) {
                    view! { <p role="alert" class="link-reason run-error">"Alarm: " {reason}</p> }.into_any()
                } else if reason.is_empty() {
                    view! { <p class="link-reason">"Not connected."</p> }.into_any()
                } else {
                    view! { <p class="link-reason">"Why: " {reason}</p> }.into_any()
                }
            }}
            {children()}
            <p class="overrides">
                {move || s.with(|s| format!(
                    "Override commanded {}, applied {}{}",
                    pct(s.commanded_pct),
                    pct(s.applied_pct),
                    if s.fallback { " — the device is in its watchdog fallback" } else { "" },
                ))}
            </p>
            <p class="hold" role="status" aria-label="Feed hold at the machine">
                {move || s.with(|s| s.hold.clone().map_or_else(
                    || "Feed hold: none latched at the device.".to_string(),
                    |h| format!("Feed hold: {h}."),
                ))}
            </p>
            <p class="hint if-link-lost">
                {move || s.with(|s| s.if_link_lost.clone())}
            </p>
            <p class="hint">
                {move || s.with(|s| s.last_ack.clone().map_or_else(
                    || "No acknowledgement yet.".to_string(),
                    |a| format!("Last acknowledgement: {a}"),
                ))}
            </p>
            <p class="hint">{move || s.with(|s| s.recording.clone().unwrap_or_default())}</p>
            <div class="link-details">
                {move || s.with(|s| s.device.clone()).map(|d| view! {
                    <dl class="device" aria-label="Device">
                        <dt>"Device"</dt><dd>{d.device_id.clone()}</dd>
                        <dt>"Program"</dt><dd>{d.program.clone()}</dd>
                        <dt>"Protocol version"</dt><dd>{d.protocol_version.clone()}</dd>
                        <dt>"Sample rate"</dt><dd>{format!("{} Hz", d.sample_rate_hz)}</dd>
                        {s.with(|s| s.device_details.clone())
                            .into_iter()
                            .map(|(k, v)| view! { <dt>{k}</dt><dd>{v}</dd> })
                            .collect_view()}
                    </dl>
                })}
                <table class="metrics counters">
                    <caption>"Link counters"</caption>
                    <tbody>
                        {move || counters()
                            .into_iter()
                            .map(|(name, value)| view! { <tr><th scope="row">{name}</th><td>{value}</td></tr> })
                            .collect_view()}
                    </tbody>
                </table>
            </div>
        </section>
    }
}

/// The session's events, latest last.
#[component]
fn EventList(ui: Ui) -> impl IntoView {
    view! {
        <section class="event-log" aria-labelledby="hw-events-title">
            <h2 id="hw-events-title">"Events"</h2>
            {move || {
                let events = ui.snapshot.with(|s| s.events.clone());
                if events.is_empty() {
                    view! { <p class="hint">"No events yet."</p> }.into_any()
                } else {
                    view! {
                        <ol>
                            {events
                                .into_iter()
                                .map(|(t, text)| view! { <li><span class="event-time">{format!("{t:.2} s")}</span>" "{text}</li> })
                                .collect_view()}
                        </ol>
                    }
                    .into_any()
                }
            }}
        </section>
    }
}

/// Offers the chunks of a recording, joined, as a CSV download.
fn download_chunks(file_name: &str, chunks: &js_sys::Array) -> Result<(), String> {
    let fail = |what: &str| format!("could not save {file_name}: {what}");
    let options = web_sys::BlobPropertyBag::new();
    options.set_type("text/csv");
    let blob = web_sys::Blob::new_with_str_sequence_and_options(chunks, &options)
        .map_err(|e| fail(&describe(&e)))?;
    let url =
        web_sys::Url::create_object_url_with_blob(&blob).map_err(|_| fail("no object URL"))?;
    let anchor: web_sys::HtmlAnchorElement = document()
        .create_element("a")
        .map_err(|_| fail("no anchor"))?
        .dyn_into()
        .map_err(|_| fail("not an anchor"))?;
    anchor.set_href(&url);
    anchor.set_download(file_name);
    anchor.click();
    let _ = web_sys::Url::revoke_object_url(&url);
    Ok(())
}

/// The recordings: listed, exported as CSV, deleted; an unfinished one (a reload or crash cut it
/// short) is offered first.
#[component]
fn Recordings(ui: Ui, station: StationRef) -> impl IntoView {
    let export = move |meta: RecordingMeta| {
        if ui.active_recording.get_untracked() == Some(meta.id) {
            if let Some(e) = station.try_update_value(Station::flush_now) {
                ui.apply(station, e);
            }
        }
        let Some(store) = station.try_with_value(|s| s.store.clone()).flatten() else {
            // No IndexedDB: the recording is in memory.
            let chunks = station
                .try_with_value(|s| s.memory_chunks(meta.id))
                .flatten()
                .unwrap_or_default();
            let array: js_sys::Array = chunks
                .iter()
                .map(|c| wasm_bindgen::JsValue::from_str(c))
                .collect();
            let result = if chunks.is_empty() {
                Err("nothing of it was kept yet".to_string())
            } else {
                download_chunks(&meta.file_name(), &array)
            };
            ui.store_error.set(
                result
                    .err()
                    .map(|e| format!("“{}” could not be exported: {e}", meta.name)),
            );
            return;
        };
        leptos::task::spawn_local(async move {
            let result = match store.chunks(meta.id).await {
                Ok(chunks) if chunks.length() == 0 => {
                    Err("nothing of it was stored yet".to_string())
                }
                Ok(chunks) => download_chunks(&meta.file_name(), &chunks),
                Err(e) => Err(e),
            };
            ui.store_error.set(
                result
                    .err()
                    .map(|e| format!("“{}” could not be exported: {e}", meta.name)),
            );
        });
    };
    let delete = move |meta: RecordingMeta| {
        if ui.active_recording.get_untracked() == Some(meta.id) {
            ui.store_error.set(Some(format!(
                "“{}” is still recording: it ends with the part, or at Disconnect.",
                meta.name
            )));
            return;
        }
        let Some(store) = station.try_with_value(|s| s.store.clone()).flatten() else {
            station.try_update_value(|s| s.memory_delete(meta.id));
            ui.refresh_recordings(station);
            return;
        };
        leptos::task::spawn_local(async move {
            match store.delete(meta.id).await {
                Ok(()) => {
                    ui.store_error.set(None);
                    ui.refresh_recordings(station);
                }
                Err(e) => ui
                    .store_error
                    .set(Some(format!("“{}” could not be deleted: {e}", meta.name))),
            }
        });
    };
    let keep = move |mut meta: RecordingMeta| {
        meta.finished = true;
        meta.end = "cut short: the page closed while it recorded (kept up to its last stored \
                    half second)"
            .to_string();
        let Some(store) = station.try_with_value(|s| s.store.clone()).flatten() else {
            return;
        };
        leptos::task::spawn_local(async move {
            match store.put(&meta, None).await {
                Ok(()) => ui.refresh_recordings(station),
                Err(e) => ui.store_error.set(Some(format!("“{}”: {e}", meta.name))),
            }
        });
    };
    let unfinished = Memo::new(move |_| {
        let active = ui.active_recording.get();
        ui.recordings.with(|list| {
            list.iter()
                .filter(|m| !m.finished && Some(m.id) != active)
                .cloned()
                .collect::<Vec<_>>()
        })
    });
    view! {
        <section class="recordings" aria-labelledby="recordings-title">
            <h2 id="recordings-title">"Recordings"</h2>
            <p class="hint">
                "Every sample received, written to this browser's storage (IndexedDB) every half "
                "second while it streams: a reload or a crash loses at most that. CSV for the Logs "
                "page and " <code>"cutlab log inspect"</code> "."
            </p>
            {move || ui.store_error.get().map(|e| view! { <p class="run-error" role="alert">{e}</p> })}
            {move || {
                let list = unfinished.get();
                (!list.is_empty()).then(|| view! {
                    <div class="panel notice" role="region" aria-label="Unfinished recordings">
                        <p>
                            "Found after a reload: recording(s) the page did not get to close. "
                            "Each is intact up to its last stored half second."
                        </p>
                        <ul>
                            {list.into_iter().map(|m| {
                                let name = m.name.clone();
                                let for_keep = m.clone();
                                view! {
                                    <li>
                                        {format!("{} — {} rows, {:.1} s ", m.name, m.rows, m.duration_s)}
                                        <button type="button" aria-label=format!("Keep {name}") on:click=move |_| keep(for_keep.clone())>"Keep"</button>
                                    </li>
                                }
                            }).collect_view()}
                        </ul>
                    </div>
                })
            }}
            {move || {
                let list = ui.recordings.get();
                if list.is_empty() {
                    return view! { <p class="hint">"No recordings yet."</p> }.into_any();
                }
                let active = ui.active_recording.get();
                view! {
                    <table class="metrics recordings-table">
                        <caption>"Stored recordings"</caption>
                        <thead>
                            <tr>
                                <th scope="col">"Recording"</th>
                                <th scope="col">"Rows"</th>
                                <th scope="col">"Duration (s)"</th>
                                <th scope="col">"Status"</th>
                                <th scope="col">"Actions"</th>
                            </tr>
                        </thead>
                        <tbody>
                            {list.into_iter().rev().map(|m| {
                                let status = if Some(m.id) == active {
                                    "recording".to_string()
                                } else if m.finished {
                                    m.end.clone()
                                } else {
                                    "unfinished".to_string()
                                };
                                let status = if m.summary.is_empty() { status } else { format!("{status}; {}", m.summary) };
                                let for_export = m.clone();
                                let for_delete = m.clone();
                                view! {
                                    <tr>
                                        <th scope="row">{m.name.clone()}</th>
                                        <td>{m.rows.to_string()}</td>
                                        <td>{format!("{:.1}", m.duration_s)}</td>
                                        <td>{status}</td>
                                        <td class="actions">
                                            <button type="button" aria-label=format!("Export {} as CSV", m.name) on:click=move |_| export(for_export.clone())>"Export CSV"</button>
                                            " "
                                            <button type="button" aria-label=format!("Delete {}", m.name) on:click=move |_| delete(for_delete.clone())>"Delete"</button>
                                        </td>
                                    </tr>
                                }
                            }).collect_view()}
                        </tbody>
                    </table>
                }
                .into_any()
            }}
        </section>
    }
}
