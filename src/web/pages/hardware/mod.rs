//! Hardware: a real machine through its bridge over WebSerial, or the virtual device (the device
//! emulator running in a worker of this page behind the same protocol bytes), driven by the same closed loop
//! as Simulate and `cutlab host`.
//!
//! The page is a thin shell over [`crate::web::hardware::station::Station`], which holds the
//! core's [`crate::hardware::session::HardwareSession`], the port and the recording. Port events
//! and a 100 ms timer call into the station; the page shows a snapshot of it at most four times a
//! second (at once when the link state changes). Arming and the teach cut go through a
//! confirmation that lists the limits in force; Disarm, Escape and any alarm command the safe
//! override at once. Recordings go to IndexedDB every half second while they stream. Every field
//! is a row of a core table: the serial line's, the virtual device's (as `cutlab device`'s
//! options), the run definition's and the host's (as `cutlab host`'s).
//!
//! | file | panel |
//! |---|---|
//! | `mod.rs` | the page, and what its panels share: the station, the run's forms, the link's state |
//! | `ui.rs` | the station's snapshot as signals, and its effects carried out |
//! | `connection.rs` | the serial port and the virtual device |
//! | `control.rs`, `calibration.rs` | the run's settings and its calibration |
//! | `actions.rs` | teach cut, arm (through the confirmation), disarm, acknowledge, reset the hold |
//! | `link.rs` | the link's state, counters and events |
//! | `recordings.rs` | the recordings, exported and deleted |
//! | [`connection`] | connecting: a serial port through WebSerial, or the virtual device |
//! | [`link`] | the link: its state, the overrides commanded and applied, the feed hold |
//! | [`calibration`] | the run's calibration: a teach cut over the link, or a saved one |
//! | [`control`] | the run on the machine and the preset whose settings it takes |
//! | [`actions`] | what the operator does to the machine, each through a confirmation |
//! | [`recordings`] | the recordings in this browser's IndexedDB: listed, exported, deleted |
//! | [`ui`] | what the page shows of the station, and how the station's effects reach the page |

mod actions;
mod calibration;
mod connection;
mod control;
mod link;
mod recordings;
mod ui;

use std::time::Duration;

use leptos::prelude::*;

use crate::closed_loop::definition::{RunSetting, RunSpec};
use crate::control::registry::ControllerKind;
use crate::hardware::commissioning::REDUCE_ONLY_MAX_OVERRIDE_PCT;
use crate::hardware::host_settings::{parse_host, HostSetting};
use crate::hardware::session::{LinkState, SessionOptions, Stage};
use crate::input::parse_number;
use crate::input::table::form_errors;
use crate::plant::presets::PlantEdits;
use crate::plant::Preset;
use crate::web::components::chart::ChartCanvas;
use crate::web::components::later::Later;
use crate::web::components::page::PageShell;
use crate::web::components::run_form::{ControllerForm, ScenarioForm};
use crate::web::components::run_view::{MetricsTable, NamedRun};
use crate::web::components::table_form::{FieldErrors, TableForm};
use crate::web::hardware::port::web_serial_unavailable;
use crate::web::hardware::station::Station;
use crate::web::hardware::store::Store;
use crate::web::route::{query_params, replace_query, Page};
use actions::ControlActions;
use connection::ConnectionPanel;
use control::ControlPanel;
use link::{EventList, LinkPanel};
use recordings::Recordings;
use ui::{StationRef, Ui};

/// How often the station's clock ticks (watchdogs, heartbeats, the store's flush).
const TICK: Duration = Duration::from_millis(100);

/// What the panels share: the station and its signals, the run's forms, the link's state.
#[derive(Clone, Copy)]
struct HardwareState {
    station: StationRef,
    ui: Ui,
    scenario: ScenarioForm,
    controller: ControllerForm,
    /// The run the forms define, if they parse (no machine edits: the machine is the device's).
    spec: Memo<Option<RunSpec>>,
    host: TableForm<HostSetting>,
    host_errors: Signal<FieldErrors>,
    /// The session's refusal of the host's settings (a change refused while armed).
    options_error: RwSignal<Option<String>>,
    state: Memo<Option<LinkState>>,
    stage: Memo<Option<Stage>>,
    connected: Memo<bool>,
    is_virtual: Memo<bool>,
}

impl HardwareState {
    fn new() -> Self {
        let query = query_params(&window().location().hash().unwrap_or_default());
        let scenario = ScenarioForm::new(&query);
        let controller = ControllerForm::new(
            "hw-",
            ControllerKind::Threshold,
            scenario.chosen_preset_untracked(),
            &query,
            "",
        );
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
        let ui = Ui::new();
        let host = TableForm::<HostSetting>::new(&query);
        let parsed = Memo::new(move |_| parse_host(&host.texts()));
        Self {
            station: StoredValue::new_local(Station::default()),
            ui,
            scenario,
            controller,
            spec,
            host,
            host_errors: Signal::derive(move || {
                parsed
                    .get()
                    .err()
                    .map(|e| form_errors(&e))
                    .unwrap_or_default()
            }),
            options_error: RwSignal::new(None),
            state: Memo::new(move |_| ui.snapshot.with(|s| s.state)),
            stage: Memo::new(move |_| ui.snapshot.with(|s| s.stage)),
            connected: Memo::new(move |_| ui.snapshot.with(|s| s.port.is_some())),
            is_virtual: Memo::new(move |_| {
                ui.snapshot.with(|s| s.port == Some("the virtual device"))
            }),
        }
        .following(parsed)
    }

    /// The effects that keep the page and the station in step: the controller's untouched
    /// parameters follow the preset, the URL the forms, the session the host's settings (also
    /// when the link state changes: a change refused while armed applies after), and the preset
    /// the program the device names, as in `cutlab host`.
    fn following(
        self,
        host: Memo<Result<SessionOptions, Vec<crate::input::table::RowError<HostSetting>>>>,
    ) -> Self {
        let Self {
            scenario,
            controller,
            station,
            ui,
            state,
            options_error,
            host: host_form,
            ..
        } = self;
        Effect::new(move |_| {
            if let Some(preset) = scenario.chosen_preset() {
                controller.follow_preset(preset);
            }
        });
        Effect::new(move |_| {
            // The settings, never the port: a link names no one's serial device.
            let mut q = scenario.query();
            q.extend(controller.query(""));
            q.extend(host_form.query());
            replace_query(Page::Hardware, &q);
        });
        Effect::new(move |_| {
            state.track();
            let Ok(options) = host.get() else {
                return;
            };
            let result = station
                .try_update_value(|s| s.set_options(options))
                .unwrap_or(Ok(()));
            options_error.set(result.err());
        });
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
        self
    }
}

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
             {REDUCE_ONLY_MAX_OVERRIDE_PCT} % (raise it only after the commissioning checks in \
             the hardware guide, §10)."
        )));
    }
}

/// The station's clock, its store, Escape, and leaving the page.
fn keep_station(station: StationRef, ui: Ui) {
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
}

/// The Hardware page.
#[component]
pub fn HardwarePage() -> impl IntoView {
    let shared = HardwareState::new();
    let HardwareState { station, ui, .. } = shared;
    keep_station(station, ui);
    let no_serial = web_serial_unavailable();
    let x_view = RwSignal::new(None::<std::ops::Range<f64>>);
    let chart = move |i: usize| Signal::derive(move || ui.charts[i].get());
    view! {
        <PageShell id="hardware" title="Hardware: a machine over the serial line" class="hardware">
            <p class="lede">
                "Connect the bridge on a real machine (Hall sensors in, feed override out; the "
                "project's hardware guide says how to build and wire one) over WebSerial, or start "
                "the virtual device: the simulated machine running in this browser behind the same "
                "protocol bytes, with the same fault switches as the command line's device "
                "emulator. The teach cut and the closed loop are the ones Simulate runs; everything "
                "received is recorded as it streams."
            </p>
            {no_serial.map(|why| view! { <NoSerial why=why /> })}
            <div class="layout-two">
                <div class="panel-stack">
                    <ConnectionPanel shared=shared no_serial=no_serial />
                    <Later>
                        <ControlPanel shared=shared />
                    </Later>
                </div>
                <div class="results">
                    <LinkPanel ui=ui>
                        <ControlActions shared=shared />
                    </LinkPanel>
                    <section aria-labelledby="live-title">
                        <h2 id="live-title">"Live view"</h2>
                        <p class="hint">
                            "The last 30 s of device time at the device's rate. Zooming holds the "
                            "view still; Reset zoom (or 0) follows the stream again."
                        </p>
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
        </PageShell>
    }
}

/// Why WebSerial is not available here, and what works instead.
#[component]
fn NoSerial(why: &'static str) -> impl IntoView {
    view! {
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
    }
}
