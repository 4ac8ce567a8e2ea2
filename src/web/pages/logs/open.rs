//! Opening logs — a file picker, a drop zone, the sample logs one click away, the loader's
//! progress — and the open logs: which one is analysed, and removing one.

use leptos::prelude::*;
use wasm_bindgen::JsCast;

use super::loader::{fetch_blob, files_of, LoadStatus, Logs};

use crate::log::link::SAMPLES;

/// Opens the sample log `file` (one of [`SAMPLES`]) from the server.
pub fn load_sample(logs: Logs, file: &'static str) {
    let url = format!("data/{file}");
    leptos::task::spawn_local(async move {
        match fetch_blob(&url).await {
            Ok(blob) => logs.load(vec![(file.to_string(), blob)]),
            Err(e) => {
                let _ = logs.status.try_set(LoadStatus::Failed(e));
            }
        }
    });
}

/// The Open a log panel.
#[component]
pub fn OpenPanel(logs: Logs) -> impl IntoView {
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
    let load_sample = move |file: &'static str| load_sample(logs, file);
    let status = logs.status;
    view! {
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
    }
}

/// The Open logs panel: which log is analysed, and removing one.
#[component]
pub fn OpenLogsPanel(logs: Logs) -> impl IntoView {
    view! {
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
    }
}
