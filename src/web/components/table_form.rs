//! One form for any table of the core's settings ([`crate::input::table`]): the text of each
//! row kept as typed ([`TableForm`]), and one field per row ([`SettingField`]) with the row's
//! label, unit and choices, showing the message the core's parse gave for that row's key. The
//! page never writes a setting's label, range, default or message itself.

use std::collections::BTreeMap;

use leptos::prelude::*;

use crate::input::table::{Kind, Table};
use crate::web::components::fields::{ChoiceField, NumberField};

/// The messages of a form's fields, by row key.
pub type FieldErrors = BTreeMap<&'static str, String>;

/// What each blank field of a form resolves to, as text, by row key (its placeholder).
pub type Placeholders = BTreeMap<&'static str, String>;

/// The typed text of a table's rows, one signal per row; a fresh form shows each row's default.
pub struct TableForm<S: 'static> {
    texts: StoredValue<Vec<(S, RwSignal<String>)>>,
}

impl<S> Clone for TableForm<S> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<S> Copy for TableForm<S> {}

impl<S: Table + Send + Sync> TableForm<S> {
    /// Every row at its default, then whatever `query` says (by row key).
    pub fn new(query: &[(String, String)]) -> Self {
        let texts = S::ROWS
            .iter()
            .map(|&s| {
                let row = s.row();
                let typed = query
                    .iter()
                    .find(|(k, _)| k == row.key)
                    .map(|(_, v)| v.clone());
                (
                    s,
                    RwSignal::new(typed.unwrap_or_else(|| row.default_text())),
                )
            })
            .collect();
        Self {
            texts: StoredValue::new(texts),
        }
    }

    /// The text signal of `setting`.
    pub fn text(&self, setting: S) -> RwSignal<String> {
        self.texts
            .with_value(|t| t.iter().find(|(s, _)| *s == setting).map(|(_, t)| *t))
            .unwrap_or_else(|| RwSignal::new(String::new()))
    }

    /// Every row's text (tracked), for the table's parse.
    pub fn texts(&self) -> Vec<(S, String)> {
        self.texts
            .with_value(|t| t.iter().map(|(s, text)| (*s, text.get())).collect())
    }

    /// Every row's text, untracked (for an action, not a derivation).
    pub fn texts_untracked(&self) -> Vec<(S, String)> {
        self.texts.with_value(|t| {
            t.iter()
                .map(|(s, text)| (*s, text.get_untracked()))
                .collect()
        })
    }

    /// The query pairs of the rows whose text differs from the default (tracked).
    pub fn query(&self) -> Vec<(String, String)> {
        self.texts()
            .into_iter()
            .filter_map(|(s, text)| {
                let row = s.row();
                (text.trim() != row.default_text()).then(|| (row.key.to_string(), text))
            })
            .collect()
    }

    /// Every row back to its default.
    pub fn reset(&self) {
        self.texts.with_value(|t| {
            for (s, text) in t {
                text.set(s.row().default_text());
            }
        });
    }
}

/// The id of `setting`'s field on a page: `prefix` and its key.
pub fn field_id<S: Table>(prefix: &str, setting: S) -> String {
    format!("{prefix}{}", setting.row().key.replace('_', "-"))
}

/// One row's field: a select for a choice, a text field otherwise, with the message `errors`
/// holds for its key beside it.
#[component]
pub fn SettingField<S: Table + Send + Sync>(
    /// The form.
    form: TableForm<S>,
    /// The row.
    setting: S,
    /// Messages by row key.
    #[prop(into)]
    errors: Signal<FieldErrors>,
    /// Prefix of the field's id, so several forms share a page.
    #[prop(default = "")]
    id_prefix: &'static str,
    /// A label other than the row's (a band's "Lower cut-off").
    #[prop(into, optional)]
    label: Option<Signal<String>>,
    /// Hides the field (its text is kept).
    #[prop(into, optional)]
    hidden: Signal<bool>,
    /// What blank fields resolve to, by row key (none: no placeholder).
    #[prop(into, optional)]
    placeholders: Signal<Placeholders>,
) -> impl IntoView {
    let row = setting.row();
    let placeholder = Signal::derive(move || placeholders.with(|p| p.get(row.key).cloned()));
    let id = field_id(id_prefix, setting);
    let value = form.text(setting);
    let error = Signal::derive(move || errors.with(|e| e.get(row.key).cloned()));
    match row.kind {
        Kind::Choice => {
            // The blank option ("The preset's") names the choice it stands for, as a text
            // field's placeholder shows the value a blank field runs with.
            let choices = setting.choices();
            let options = Signal::derive(move || {
                let in_use = placeholder.get().and_then(|value| {
                    choices
                        .iter()
                        .find(|(v, _)| !v.is_empty() && *v == value)
                        .map(|(_, text)| *text)
                });
                choices
                    .iter()
                    .map(|&(v, text)| match in_use {
                        Some(used) if v.is_empty() => (String::new(), format!("{text}: {used}")),
                        _ => (v.to_string(), text.to_string()),
                    })
                    .collect::<Vec<_>>()
            });
            view! {
                <ChoiceField id=id label=row.label options=options value=value error=Some(error) hidden=hidden help=row.help />
            }
            .into_any()
        }
        Kind::Number { .. } | Kind::Count { .. } | Kind::Seed => {
            let step = if matches!(row.kind, Kind::Number { .. }) {
                "any"
            } else {
                "1"
            };
            let label = label.unwrap_or_else(|| Signal::stored(row.label.to_string()));
            view! {
                <NumberField id=id label=label unit=row.unit value=value error=error step=step hidden=hidden help=row.help placeholder=placeholder />
            }
            .into_any()
        }
    }
}

/// Several rows' fields, in the order given.
#[component]
pub fn SettingFields<S: Table + Send + Sync>(
    /// The form.
    form: TableForm<S>,
    /// The rows shown.
    settings: Vec<S>,
    /// Messages by row key.
    #[prop(into)]
    errors: Signal<FieldErrors>,
    /// Prefix of the fields' ids.
    #[prop(default = "")]
    id_prefix: &'static str,
    /// What blank fields resolve to, by row key.
    #[prop(into, optional)]
    placeholders: Signal<Placeholders>,
) -> impl IntoView {
    settings
        .into_iter()
        .map(|setting| {
            view! { <SettingField form=form setting=setting errors=errors id_prefix=id_prefix placeholders=placeholders /> }
        })
        .collect_view()
}
