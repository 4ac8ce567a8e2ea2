//! The controller tuned and its one or two parameters, each a key and the bounds tried: rows of
//! the tuning's table, checked as typed against what the controller's parameter takes.

use leptos::prelude::*;

use crate::control::registry::{ControllerConfig, ControllerKind};
use crate::input::readable;
use crate::input::table::form_errors;
use crate::tuning::settings::{parse_range, TuneSetting};
use crate::tuning::ParamRange;
use crate::web::components::fields::SelectField;
use crate::web::components::run_form::EngineFile;
use crate::web::components::table_form::{FieldErrors, SettingField, TableForm};

/// The controllers worth tuning (a fixed feed has one value, found by the reference search).
pub const TUNABLE: [ControllerKind; 7] = [
    ControllerKind::Restriction,
    ControllerKind::Threshold,
    ControllerKind::FuzzyExperience,
    ControllerKind::FuzzyDynamics,
    ControllerKind::FuzzyEngine,
    ControllerKind::Pi,
    ControllerKind::Mrac,
];

/// The ids' prefixes of the two parameters' bounds.
const BOUND_IDS: [&str; 2] = ["tune-param-1-", "tune-param-2-"];

/// A sensible range around a parameter's default: a quarter to twice it, inside its limits.
fn default_range(kind: ControllerKind, key: &str) -> (f64, f64) {
    kind.params()
        .iter()
        .find(|p| p.key == key)
        .map_or((0.0, 1.0), |p| {
            let d = p.default;
            if d > 0.0 {
                ((0.25 * d).max(p.min), (2.0 * d).min(p.max))
            } else {
                (p.min, p.max.min(p.min + 1.0))
            }
        })
}

/// One parameter of the form: its key and the text of its bounds.
#[derive(Clone, Copy)]
pub struct ParamRow {
    key: RwSignal<String>,
    bounds: TableForm<TuneSetting>,
    /// The range, or the message of each bound (tracked).
    parsed: Memo<Result<ParamRange, FieldErrors>>,
}

impl ParamRow {
    /// The `index`-th parameter of `kind`, around its default.
    pub fn new(kind: Memo<ControllerKind>, index: usize) -> Self {
        let key = RwSignal::new(String::new());
        let bounds = TableForm::new(&[]);
        let parsed = Memo::new(move |_| {
            let controller = ControllerConfig::new(kind.get());
            let text = |s| bounds.text(s).get();
            parse_range(
                &key.get(),
                &text(TuneSetting::From),
                &text(TuneSetting::To),
                Some(&controller),
            )
            .map_err(|e| form_errors(&e))
        });
        let row = Self {
            key,
            bounds,
            parsed,
        };
        row.reset(kind.get_untracked(), index);
        row
    }

    /// The `index`-th parameter of `kind` at its default range.
    pub fn reset(&self, kind: ControllerKind, index: usize) {
        let key = kind
            .params()
            .get(index)
            .map_or(String::new(), |p| p.key.to_string());
        self.choose(kind, key);
    }

    /// Parameter `key` of `kind`, at its default range.
    fn choose(&self, kind: ControllerKind, key: String) {
        let (lo, hi) = default_range(kind, &key);
        self.key.set(key);
        self.bounds.text(TuneSetting::From).set(readable(lo));
        self.bounds.text(TuneSetting::To).set(readable(hi));
    }

    /// The range asked for, or the message of each bound (tracked).
    /// Takes the row's key and bounds from a shared link's `p1`, `p1.from`, `p1.to` (row `index`
    /// 0), where the key is one of `kind`'s parameters.
    pub fn restore(&self, kind: ControllerKind, index: usize, query: &[(String, String)]) {
        let name = format!("p{}", index + 1);
        let typed = |key: &str| query.iter().find(|(k, _)| k == key).map(|(_, v)| v.clone());
        let Some(key) = typed(&name).filter(|k| kind.params().iter().any(|p| p.key == k)) else {
            return;
        };
        self.choose(kind, key);
        for (setting, side) in [(TuneSetting::From, "from"), (TuneSetting::To, "to")] {
            if let Some(text) = typed(&format!("{name}.{side}")) {
                self.bounds.text(setting).set(text);
            }
        }
    }

    /// The row as a link's query pairs (see [`ParamRow::restore`]); tracked.
    pub fn query(&self, index: usize) -> Vec<(String, String)> {
        let name = format!("p{}", index + 1);
        vec![
            (name.clone(), self.key.get()),
            (
                format!("{name}.from"),
                self.bounds.text(TuneSetting::From).get(),
            ),
            (
                format!("{name}.to"),
                self.bounds.text(TuneSetting::To).get(),
            ),
        ]
    }

    pub fn parse(&self) -> Result<ParamRange, FieldErrors> {
        self.parsed.get()
    }
}

/// The controller and parameters fieldset.
#[component]
pub fn ParamsPanel(
    /// The controller's name, as chosen.
    kind_text: RwSignal<String>,
    kind: Memo<ControllerKind>,
    rows: [ParamRow; 2],
    /// Whether the second parameter is tuned.
    second_on: RwSignal<bool>,
    /// The engine of a `fuzzy-engine` controller (`None`: paper 002's dynamics table).
    engine: RwSignal<Option<String>>,
) -> impl IntoView {
    let engine_fields = move || {
        (kind.get() == ControllerKind::FuzzyEngine).then(|| {
            let mapping = move || {
                let mut c = ControllerConfig::new(ControllerKind::FuzzyEngine);
                match engine.get() {
                    Some(text) => c.set_engine(&text).ok().and_then(|_| c.engine_mapping()),
                    None => c.engine_mapping(),
                }
            };
            view! {
                <p class="hint engine-mapping">{mapping}</p>
                <EngineFile engine=engine id="tune-engine-file".to_string() />
            }
        })
    };
    let param_options = Memo::new(move |_| {
        kind.get()
            .params()
            .iter()
            .map(|p| (p.key, p.label))
            .collect::<Vec<_>>()
    });
    view! {
        <fieldset>
            <legend>"Controller and parameters"</legend>
            <SelectField
                id="tune-controller"
                label="Controller"
                options=TUNABLE.iter().map(|k| (k.name(), k.label())).collect()
                value=kind_text
            />
            {engine_fields}
            {rows
                .iter()
                .enumerate()
                .map(|(i, row)| {
                    let row = *row;
                    let n = i + 1;
                    let hidden = Signal::derive(move || i == 1 && !second_on.get());
                    let errors = Signal::derive(move || row.parse().err().unwrap_or_default());
                    let bound = move |setting: TuneSetting, side: &'static str| {
                        view! {
                            <SettingField
                                form=row.bounds
                                setting=setting
                                errors=errors
                                id_prefix=BOUND_IDS[i]
                                label=Signal::stored(format!("Parameter {n} {side}"))
                                hidden=hidden
                            />
                        }
                    };
                    view! {
                        <div class="field" hidden=move || hidden.get()>
                            <label for=format!("tune-param-{n}")>{format!("Parameter {n}")}</label>
                            <select
                                id=format!("tune-param-{n}")
                                on:change=move |ev| row.choose(kind.get_untracked(), event_target_value(&ev))
                                prop:value=move || row.key.get()
                            >
                                {move || {
                                    param_options
                                        .get()
                                        .into_iter()
                                        .map(|(key, label)| view! { <option value=key>{format!("{label} ({key})")}</option> })
                                        .collect_view()
                                }}
                            </select>
                        </div>
                        {bound(TuneSetting::From, "from")}
                        {bound(TuneSetting::To, "to")}
                    }
                })
                .collect_view()}
            <div class="check">
                <input
                    type="checkbox"
                    id="tune-second"
                    prop:checked=move || second_on.get()
                    on:change=move |ev| second_on.set(event_target_checked(&ev))
                />
                <label for="tune-second">"Tune a second parameter"</label>
            </div>
        </fieldset>
    }
}
