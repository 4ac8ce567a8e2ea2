//! Labelled form fields that keep what the user typed and show why it is not accepted.
//!
//! A field stores its raw text; the page parses it with the core's constructors and hands the
//! error back, which the field shows beside itself (linked with `aria-describedby`, so a screen
//! reader announces it too). Nothing typed is ever discarded because it did not parse.

use leptos::prelude::*;

use crate::web::components::help::HelpToggle;

pub use crate::input::parse_number;

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
    /// What the value is, opened by a "?" beside the label (empty: no "?").
    #[prop(optional)]
    help: &'static str,
    /// What a blank field means, shown in it while it is blank (the value the run uses).
    #[prop(into, optional)]
    placeholder: Signal<Option<String>>,
) -> impl IntoView {
    let error_id = format!("{id}-error");
    let described = error_id.clone();
    let input_id = id.clone();
    view! {
        <div class="field" class:field-invalid=move || error.get().is_some() hidden=move || hidden.get()>
            <div class="field-head">
                <label for=id>
                    {move || label.get()}
                    {move || {
                        label
                            .with(|l| shows_unit(l, unit))
                            .then(|| view! { <span class="unit">" (" {unit} ")"</span> })
                    }}
                </label>
                {(!help.is_empty()).then(|| view! { <HelpToggle subject=label help=help /> })}
            </div>
            <input
                id=input_id
                type="text"
                inputmode="decimal"
                autocomplete="off"
                step=step
                placeholder=move || placeholder.get()
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

/// Whether a field labelled `label` needs its `unit` after the label: not when there is none, nor
/// when the label already names it ("Teeth" counts teeth, "Depth of cut ×" is a factor), so a
/// unit is written once.
fn shows_unit(label: &str, unit: &str) -> bool {
    let unit = unit.trim();
    !unit.is_empty()
        && !label
            .split(|c: char| c.is_whitespace() || c == '(' || c == ')')
            .any(|word| word.eq_ignore_ascii_case(unit))
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
    /// Why the choice is not accepted, for a select whose value is checked.
    #[prop(optional, into)]
    error: Option<Signal<Option<String>>>,
    /// Hides the field without losing its choice.
    #[prop(into, optional)]
    hidden: Signal<bool>,
    /// What the choice is, opened by a "?" beside the label (empty: no "?").
    #[prop(optional)]
    help: &'static str,
) -> impl IntoView {
    let options = Signal::stored(
        options
            .into_iter()
            .map(|(v, text)| (v.to_string(), text.to_string()))
            .collect::<Vec<_>>(),
    );
    view! { <ChoiceField id=id label=label options=options value=value error=error hidden=hidden help=help /> }
}

/// A labelled drop-down over choices that may change (a log's columns), keeping its value, with
/// an error slot where the choice is checked.
#[component]
pub fn ChoiceField(
    /// Element id, also used to link label and error.
    #[prop(into)]
    id: String,
    /// Visible label (the accessible name).
    label: &'static str,
    /// `(value, text)` for each option.
    #[prop(into)]
    options: Signal<Vec<(String, String)>>,
    /// The selected value.
    value: RwSignal<String>,
    /// Why the choice is not accepted, for a select whose value is checked.
    #[prop(default = None)]
    error: Option<Signal<Option<String>>>,
    /// Hides the field without losing its choice.
    #[prop(into, optional)]
    hidden: Signal<bool>,
    /// What the choice is, opened by a "?" beside the label (empty: no "?").
    #[prop(optional)]
    help: &'static str,
) -> impl IntoView {
    let error_id = format!("{id}-error");
    let described = error.map(|_| error_id.clone());
    let invalid = move || error.is_some_and(|e| e.get().is_some());
    view! {
        <div class="field" class:field-invalid=invalid hidden=move || hidden.get()>
            <div class="field-head">
                <label for=id.clone()>{label}</label>
                {(!help.is_empty()).then(|| view! { <HelpToggle subject=label.to_string() help=help /> })}
            </div>
            <select
                id=id
                on:change=move |ev| value.set(event_target_value(&ev))
                prop:value=move || value.get()
                aria-describedby=described
            >
                {move || {
                    options
                        .get()
                        .into_iter()
                        .map(|(v, text)| {
                            let selected = v.clone();
                            view! { <option value=v selected=move || value.get() == selected>{text}</option> }
                        })
                        .collect_view()
                }}
            </select>
            {error.map(|error| view! {
                <p class="field-error" id=error_id aria-live="polite">{move || error.get().unwrap_or_default()}</p>
            })}
        </div>
    }
}

#[cfg(test)]
mod tests {
    use super::shows_unit;

    #[test]
    fn a_unit_the_label_already_names_is_not_repeated() {
        assert!(!shows_unit("Teeth", "teeth"));
        assert!(!shows_unit("Depth of cut ×", "×"));
        assert!(!shows_unit("Seed", ""));
        assert!(shows_unit("Spindle speed", "rpm"));
        assert!(shows_unit("K_p", "% per %"));
        // A word that only contains the unit is not the unit.
        assert!(shows_unit("Smallest feed per tooth", "mm"));
    }
}
