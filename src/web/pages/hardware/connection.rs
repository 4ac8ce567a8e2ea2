//! Connecting: a serial port through WebSerial (its line settings, the serial table's rows), or
//! the virtual device — the emulator in a worker of its own behind the same protocol bytes, its
//! settings the device table's rows, as `cutlab device`'s options — and disconnecting.

use leptos::prelude::*;

use super::ui::sink;
use super::{reduce_only, HardwareState};
use crate::hardware::serial_settings::{parse_serial, SerialSetting};
use crate::input::table::{form_errors, Table};
use crate::protocol::device_settings::{parse_device, DeviceSetting};
use crate::protocol::device_worker::{refusal, DeviceStart};
use crate::web::components::later::Later;
use crate::web::components::table_form::{SettingField, TableForm};
use crate::web::hardware::port::{Port, SerialLink, VirtualLink};
use crate::web::hardware::station::Station;

/// The device's settings the page shows (the rest keep `cutlab device`'s defaults).
const VIRTUAL_SETTINGS: [DeviceSetting; 10] = [
    DeviceSetting::Program,
    DeviceSetting::Seed,
    DeviceSetting::TimeScale,
    DeviceSetting::DropRate,
    DeviceSetting::NoiseRate,
    DeviceSetting::StallAt,
    DeviceSetting::StallFor,
    DeviceSetting::UnplugAt,
    DeviceSetting::Watchdog,
    DeviceSetting::Fallback,
];

/// The Connection panel.
#[component]
pub fn ConnectionPanel(shared: HardwareState, no_serial: Option<&'static str>) -> impl IntoView {
    let HardwareState {
        station,
        ui,
        scenario,
        ..
    } = shared;
    let serial = TableForm::<SerialSetting>::new(&[]);
    let serial_parsed =
        Memo::new(move |_| parse_serial(&serial.texts()).map_err(|e| form_errors(&e)));
    let serial_errors = Signal::derive(move || serial_parsed.get().err().unwrap_or_default());
    let connect_serial = move |_| {
        ui.message.set(None);
        let Ok(settings) = serial_parsed.get_untracked() else {
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
    let disconnect = move |_| {
        ui.message.set(None);
        if let Some(e) = station.try_update_value(Station::disconnect) {
            ui.apply(station, e);
        }
    };
    let connected = shared.connected;
    let serial_field = move |setting: SerialSetting| {
        view! { <SettingField form=serial setting=setting errors=serial_errors id_prefix="hw-" /> }
    };
    view! {
        <form class="panel" aria-label="Connection" on:submit=|ev| ev.prevent_default()>
            <fieldset>
                <legend>"Serial port"</legend>
                {SerialSetting::ROWS.iter().map(|s| serial_field(*s)).collect_view()}
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
                <VirtualDeviceFields shared=shared />
            </Later>
            <div class="button-row">
                <button type="button" on:click=disconnect disabled=move || !connected.get()>
                    "Disconnect"
                </button>
            </div>
        </form>
    }
}

/// The virtual device's fieldset: its settings, its truth switch, start and unplug.
#[component]
fn VirtualDeviceFields(shared: HardwareState) -> impl IntoView {
    let HardwareState {
        station,
        ui,
        scenario,
        ..
    } = shared;
    let device = TableForm::<DeviceSetting>::new(&[(
        DeviceSetting::Program.row().key.to_string(),
        scenario.preset.get_untracked(),
    )]);
    let parsed = Memo::new(move |_| parse_device(&device.texts()));
    let errors = Signal::derive(move || {
        parsed
            .get()
            .err()
            .map(|e| form_errors(&e))
            .unwrap_or_default()
    });
    // Send the simulation's truth (off: a real bridge's twin, `cutlab device --no-truth`).
    let truth = RwSignal::new(true);
    let start_virtual = move |_| {
        ui.message.set(None);
        // The form's errors at once (the worker parses the same texts the same way).
        if let Err(errors) = parsed.get_untracked() {
            ui.message.set(Some(format!(
                "The virtual device cannot start: {}.",
                refusal(&errors)
            )));
            return;
        }
        let request = DeviceStart::new(&device.texts_untracked(), truth.get_untracked());
        let Some(generation) = station.try_update_value(Station::next_generation) else {
            return;
        };
        match VirtualLink::start(request, sink(station, ui, generation)) {
            Ok(link) => {
                station.try_update_value(|s| s.connect(Port::Virtual(link), generation));
                ui.publish(station, true);
            }
            Err(e) => ui
                .message
                .set(Some(format!("The virtual device cannot start: {e}."))),
        }
    };
    let unplug = move |_| {
        station.try_with_value(Station::unplug_virtual);
    };
    let (connected, is_virtual) = (shared.connected, shared.is_virtual);
    view! {
        <fieldset>
            <legend>"Virtual device"</legend>
            {VIRTUAL_SETTINGS
                .into_iter()
                .map(|s| view! { <SettingField form=device setting=s errors=errors id_prefix="hw-" /> })
                .collect_view()}
            <label class="check">
                <input
                    type="checkbox"
                    prop:checked=move || truth.get()
                    on:change=move |ev| truth.set(event_target_checked(&ev))
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
    }
}
