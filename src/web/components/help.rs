//! A "?" beside a term that opens its explanation in place: the glossary entry of a metric, the
//! help of a setting. A real button (keyboard, screen reader: "What Cycle time means",
//! expanded or not), the text in the page rather than in a tooltip a phone cannot show.

use leptos::prelude::*;

/// The toggle and, when open, the text.
#[component]
pub fn HelpToggle(
    /// What is explained, for the button's accessible name ("Cycle time").
    #[prop(into)]
    subject: Signal<String>,
    /// The explanation.
    #[prop(into)]
    help: String,
    /// Whether it is open, where the owner keeps that across a redraw of the toggle (a table
    /// drawn again when a late result arrives); by default the toggle's own.
    #[prop(optional)]
    open: Option<RwSignal<bool>>,
) -> impl IntoView {
    let open = open.unwrap_or_else(|| RwSignal::new(false));
    view! {
        // Named by its content, not an aria-label: a label naming the subject would make the
        // button one more element "labelled" by the field's label.
        <button
            type="button"
            class="help-toggle"
            aria-expanded=move || if open.get() { "true" } else { "false" }
            on:click=move |_| open.update(|o| *o = !*o)
        >
            <span aria-hidden="true">"?"</span>
            <span class="visually-hidden">{move || format!("What {} means", subject.get())}</span>
        </button>
        // In the page only while open: closed, it is nobody's text to find.
        {move || open.get().then(|| view! { <p class="help-text">{help.clone()}</p> })}
    }
}
