//! FLL (fuzzylite) and FIS (MATLAB) export and import: a file or pasted text, told apart by the
//! file's extension or the text's first line; paper 002's engine with any table comes into the
//! editable table, any other engine is studied whole.

use leptos::prelude::*;

use super::Fuzzy;
use crate::control::fuzzy::{fis, fll, Format};
use crate::web::components::download::download_text;
use crate::web::js::read_chosen_file;

/// The FLL fieldset.
#[component]
pub fn FllPanel(fuzzy: Fuzzy) -> impl IntoView {
    // Kept by the page (the text and a refusal outlive this panel's redraw).
    let fll_error = fuzzy.import_error;
    let set_fll_error = fuzzy.import_error;
    let fll_text = fuzzy.engine_text;
    // The chosen file's name, whose extension says its format.
    let file_name = RwSignal::new(String::new());
    let export = move |_| {
        let text = fuzzy
            .engine
            .with(|e| e.as_ref().ok().map(|e| fll::write(e)));
        if let Some(text) = text {
            set_fll_error.set(download_text("cutlab-fuzzy.fll", "text/plain", &text).err());
        }
    };
    let export_fis = move |_| {
        let text = fuzzy
            .engine
            .with(|e| e.as_ref().ok().map(|e| fis::write(e)));
        match text {
            Some(Ok(text)) => {
                set_fll_error.set(download_text("cutlab-fuzzy.fis", "text/plain", &text).err())
            }
            Some(Err(e)) => set_fll_error.set(Some(format!("No FIS for this engine: {e}"))),
            None => {}
        }
    };
    let import = move |_| {
        let text = fll_text.get_untracked();
        let format = Format::of(&file_name.get_untracked(), &text);
        let name = match format {
            Format::Fll => "FLL",
            Format::Fis => "FIS",
        };
        match format.parse(&text) {
            Ok(engine) => {
                set_fll_error.set(None);
                fuzzy.study(engine);
            }
            // The engine studied before stays.
            Err(e) => set_fll_error.set(Some(format!(
                "The {name} could not be read: {e}. The engine studied is unchanged."
            ))),
        }
    };
    let on_file = move |ev: leptos::ev::Event| {
        read_chosen_file(&ev, move |name, text| match text {
            Ok(text) => {
                file_name.set(name);
                fll_text.set(text);
            }
            Err(e) => set_fll_error.set(Some(e)),
        });
    };
    view! {
        <fieldset>
            <legend>"FLL (fuzzylite) and FIS (MATLAB)"</legend>
            <div class="button-row">
                <button type="button" on:click=export>"Export FLL"</button>
                <button type="button" on:click=export_fis>"Export FIS"</button>
            </div>
            <div class="field">
                <label for="fll-file">"FLL or FIS file to import"</label>
                <input id="fll-file" type="file" accept=".fll,.fis,text/plain" on:change=on_file />
            </div>
            <div class="field">
                <label for="fll-text">"Engine text (FLL or FIS)"</label>
                <textarea
                    id="fll-text"
                    class="fll"
                    prop:value=move || fll_text.get()
                    on:input=move |ev| {
                        // Typed text is told apart by its content, not by a file's name.
                        file_name.set(String::new());
                        fll_text.set(event_target_value(&ev))
                    }
                ></textarea>
            </div>
            <div class="button-row">
                <button type="button" on:click=import>"Import FLL or FIS"</button>
            </div>
            {move || fll_error.get().map(|e| view! { <p class="run-error" role="alert">{e}</p> })}
        </fieldset>
    }
}
