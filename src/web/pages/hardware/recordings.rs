//! The recordings in this browser's IndexedDB: listed, exported as CSV, deleted; one a reload or
//! a crash cut short is offered first.

use leptos::prelude::*;

use super::ui::{StationRef, Ui};
use crate::hardware::recording::RecordingMeta;
use crate::web::components::download::download_parts;
use crate::web::components::page::TableScroll;
use crate::web::hardware::station::Station;

/// The recordings: listed, exported as CSV, deleted; an unfinished one (a reload or crash cut it
/// short) is offered first.
#[component]
pub fn Recordings(ui: Ui, station: StationRef) -> impl IntoView {
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
                download_parts(&meta.file_name(), "text/csv", &array)
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
                Ok(chunks) => download_parts(&meta.file_name(), "text/csv", &chunks),
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
                "page and the command line's log inspector."
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
                    <TableScroll label="Stored recordings".to_string()>
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
                    </TableScroll>
                }
                .into_any()
            }}
        </section>
    }
}
