//! FLL (fuzzylite) export and import: a file or pasted text; paper 002's engine with any table
//! comes into the editable table, any other engine is studied whole.

use std::sync::Arc;

use leptos::prelude::*;

use super::{Fuzzy, Source};
use crate::control::fuzzy::fll;
use crate::control::fuzzy::rules::paper_002_table;
use crate::web::components::download::download_text;
use crate::web::js::read_chosen_file;

/// The FLL fieldset.
#[component]
pub fn FllPanel(fuzzy: Fuzzy) -> impl IntoView {
    let (fll_error, set_fll_error) = signal(None::<String>);
    let fll_text = RwSignal::new(String::new());
    let export = move |_| {
        let text = fuzzy
            .engine
            .with(|e| e.as_ref().ok().map(|e| fll::write(e)));
        if let Some(text) = text {
            set_fll_error.set(download_text("cutlab-fuzzy.fll", "text/plain", &text).err());
        }
    };
    let import = move |_| match fll::parse(&fll_text.get_untracked()) {
        Ok(engine) => {
            set_fll_error.set(None);
            // The page shows the file's own defuzzifier; changing it afterwards is a choice.
            if let Some(output) = engine.outputs().first() {
                fuzzy.defuzzifier.set(output.defuzzifier.name().to_string());
            }
            // Into the editable table only if the file is paper 002's engine with some table:
            // anything else is kept whole.
            match paper_002_table(&engine) {
                Ok(t) => {
                    fuzzy.table.set(t);
                    fuzzy.source.set(Source::Table);
                }
                Err(why) => fuzzy
                    .source
                    .set(Source::Imported(Arc::new(engine), why.to_string())),
            }
        }
        Err(e) => set_fll_error.set(Some(format!("The FLL could not be read: {e}"))),
    };
    let on_file = move |ev: leptos::ev::Event| {
        read_chosen_file(&ev, move |_, text| match text {
            Ok(text) => fll_text.set(text),
            Err(e) => set_fll_error.set(Some(e)),
        });
    };
    view! {
        <fieldset>
            <legend>"FLL (fuzzylite)"</legend>
            <div class="button-row">
                <button type="button" on:click=export>"Export FLL"</button>
            </div>
            <div class="field">
                <label for="fll-file">"FLL file to import"</label>
                <input id="fll-file" type="file" accept=".fll,text/plain" on:change=on_file />
            </div>
            <div class="field">
                <label for="fll-text">"FLL text"</label>
                <textarea
                    id="fll-text"
                    class="fll"
                    prop:value=move || fll_text.get()
                    on:input=move |ev| fll_text.set(event_target_value(&ev))
                ></textarea>
            </div>
            <div class="button-row">
                <button type="button" on:click=import>"Import FLL"</button>
            </div>
            {move || fll_error.get().map(|e| view! { <p class="run-error" role="alert">{e}</p> })}
        </fieldset>
    }
}
