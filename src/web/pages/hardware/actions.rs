//! What the operator does to the machine: the teach cut and arming, each through a confirmation
//! naming the limits in force (and, before a new device's first Arm on a real port, every
//! commissioning check), Disarm (or Escape), acknowledging an alarm and resetting the device's
//! latched feed hold.

use leptos::prelude::*;

use super::HardwareState;
use crate::closed_loop::definition::RunSpec;
use crate::hardware::commissioning::{
    commissioned, with_commissioned, CHECKS, COMMISSIONED_DEVICES_KEY,
};
use crate::hardware::session::{LinkState, Stage};
use crate::web::hardware::station::Station;

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

/// The action buttons, the last action's message, and the confirmation dialog.
#[component]
pub fn ControlActions(shared: HardwareState) -> impl IntoView {
    let HardwareState {
        station,
        ui,
        spec,
        state,
        stage,
        ..
    } = shared;
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

    view! {
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
                            <legend>{format!("First arming of {id}: the commissioning checks (the hardware guide, §10)")}</legend>
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
    }
}
