//! Labelled form fields that keep what the user typed and show why it is not accepted.
//!
//! A field stores its raw text; the page parses it with the core's constructors and hands the
//! error back, which the field shows beside itself (linked with `aria-describedby`, so a screen
//! reader announces it too). Nothing typed is ever discarded because it did not parse.

use leptos::prelude::*;

pub use crate::input::{parse_count, parse_number};

/// A labelled numeric input with its unit and an error slot.
#[component]
pub fn NumberField(
    /// Element id, also used to link label and error.
    #[prop(into)]
    id: String,
    /// Visible label (the accessible name).
    #[prop(into)]
    label: Signal<String>,
    /// Unit shown after the label, e.g. "Hz"; empty for none.
    #[prop(optional)]
    unit: &'static str,
    /// The text in the field.
    value: RwSignal<String>,
    /// Why the current text is not accepted, if it is not.
    #[prop(into)]
    error: Signal<Option<String>>,
    /// Step for the spinner arrows.
    #[prop(default = "any")]
    step: &'static str,
    /// Hides the field (for options that do not apply) without losing its text.
    #[prop(into, optional)]
    hidden: Signal<bool>,
) -> impl IntoView {
    let error_id = format!("{id}-error");
    let described = error_id.clone();
    let input_id = id.clone();
    view! {
        <div class="field" class:field-invalid=move || error.get().is_some() hidden=move || hidden.get()>
            <label for=id>
                {move || label.get()}
                {(!unit.is_empty()).then(|| view! { <span class="unit">" (" {unit} ")"</span> })}
            </label>
            <input
                id=input_id
                type="text"
                inputmode="decimal"
                autocomplete="off"
                step=step
                prop:value=move || value.get()
                on:input=move |ev| value.set(event_target_value(&ev))
                aria-invalid=move || if error.get().is_some() { "true" } else { "false" }
                aria-describedby=described
            />
            <p class="field-error" id=error_id aria-live="polite">
                {move || error.get().unwrap_or_default()}
            </p>
        </div>
    }
}

/// A labelled drop-down over a registry of choices.
#[component]
pub fn SelectField(
    /// Element id.
    #[prop(into)]
    id: String,
    /// Visible label (the accessible name).
    label: &'static str,
    /// `(value, text)` for each option.
    options: Vec<(&'static str, &'static str)>,
    /// The selected value.
    value: RwSignal<String>,
) -> impl IntoView {
    view! {
        <div class="field">
            <label for=id.clone()>{label}</label>
            <select
                id=id
                on:change=move |ev| value.set(event_target_value(&ev))
                prop:value=move || value.get()
            >
                {options
                    .into_iter()
                    .map(|(v, text)| {
                        view! {
                            <option value=v selected=move || value.get() == v>
                                {text}
                            </option>
                        }
                    })
                    .collect_view()}
            </select>
        </div>
    }
}
