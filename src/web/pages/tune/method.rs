//! How the parameters are tried — a Nelder–Mead search of at most so many evaluations, or a grid
//! of so many values per parameter — and the objective's weights: rows of the tuning's table,
//! checked as typed.

use leptos::prelude::*;

use crate::input::table::{self, form_errors};
use crate::tuning::settings::{parse_objective, TuneSetting, WEIGHTS};
use crate::web::components::fields::SelectField;
use crate::web::components::table_form::{FieldErrors, SettingField, TableForm};

/// The method's and the objective's messages, by field (tracked).
pub fn method_errors(form: TableForm<TuneSetting>) -> FieldErrors {
    let texts = form.texts();
    let text = |s: TuneSetting| {
        texts
            .iter()
            .find(|(t, _)| *t == s)
            .map_or("", |(_, text)| text.as_str())
    };
    let mut errors: Vec<_> = [TuneSetting::Evaluations, TuneSetting::Steps]
        .into_iter()
        .filter_map(|s| table::count(s, text(s)).err())
        .collect();
    errors.extend(parse_objective(&texts).err().unwrap_or_default());
    form_errors(&errors)
}

/// The method and objective fieldsets.
#[component]
pub fn MethodPanel(
    form: TableForm<TuneSetting>,
    /// "search" or "sweep".
    mode: RwSignal<String>,
    errors: Memo<FieldErrors>,
) -> impl IntoView {
    let field = move |setting: TuneSetting, hidden: Signal<bool>| {
        view! { <SettingField form=form setting=setting errors=errors id_prefix="tune-" hidden=hidden /> }
    };
    view! {
        <fieldset>
            <legend>"Method"</legend>
            <SelectField
                id="tune-mode"
                label="Method"
                options=vec![("search", "Search (Nelder–Mead)"), ("sweep", "Sweep a grid")]
                value=mode
            />
            {field(TuneSetting::Evaluations, Signal::derive(move || mode.get() == "sweep"))}
            {field(TuneSetting::Steps, Signal::derive(move || mode.get() != "sweep"))}
        </fieldset>
        <fieldset>
            <legend>"Objective"</legend>
            {WEIGHTS
                .into_iter()
                .map(|s| field(s, Signal::stored(false)))
                .collect_view()}
        </fieldset>
    }
}
