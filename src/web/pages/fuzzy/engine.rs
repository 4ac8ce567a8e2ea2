//! The engine studied, whole: its variables with their ranges and terms, its rules as a list
//! (the 7×7 table shows paper 002's engine; any other engine is listed rule by rule), and, for an
//! engine of two inputs and one output, the links that run it as the `fuzzy-engine` controller in
//! Simulate and beside paper 002's dynamics table in Compare.

use leptos::prelude::*;

use super::{Fuzzy, Source};
use crate::control::fuzzy::engine::Engine;
use crate::control::fuzzy::fll;
use crate::control::registry::ControllerKind;
use crate::web::route::{hash_with_query, Page};

/// The preset the links open on: paper 002's own.
const LINK_PRESET: &str = "liu-current-step";

/// One variable: its name, range and terms, as FLL states them.
fn variable(
    kind: &'static str,
    name: &str,
    range: (f64, f64),
    terms: Vec<String>,
) -> impl IntoView {
    view! {
        <li>
            {format!("{kind} {name} on [{}, {}]: ", range.0, range.1)}
            {terms.join("; ")}
        </li>
    }
}

/// The engine's variables, each with its terms.
fn variables(engine: &Engine) -> impl IntoView {
    let terms = |terms: &[crate::control::fuzzy::engine::Term]| {
        terms
            .iter()
            .map(|t| format!("{} {}", t.name, t.shape))
            .collect::<Vec<_>>()
    };
    let inputs = engine
        .inputs()
        .iter()
        .map(|v| variable("input", &v.name, (v.min, v.max), terms(&v.terms)))
        .collect_view();
    let outputs = engine
        .outputs()
        .iter()
        .map(|v| {
            let kind = "output";
            let text = format!("{} ({})", v.name, v.defuzzifier.name());
            variable(kind, &text, (v.min, v.max), terms(&v.terms))
        })
        .collect_view();
    view! {
        <ul class="engine-variables" aria-label="Variables and terms">
            {inputs}
            {outputs}
        </ul>
    }
}

/// The links that run `engine` as the `fuzzy-engine` controller: in Simulate, and in Compare
/// beside paper 002's dynamics table (variant A) on paper 002's preset.
fn links(engine: &Engine) -> Option<impl IntoView> {
    if !(engine.inputs().len() == 2 && engine.outputs().len() == 1) {
        return None;
    }
    let text = fll::to_url_text(&fll::write(engine));
    let kind = ControllerKind::FuzzyEngine.name().to_string();
    let simulate = hash_with_query(
        Page::Simulate,
        &[
            ("preset".into(), LINK_PRESET.into()),
            ("controller".into(), kind.clone()),
            ("engine".into(), text.clone()),
        ],
    );
    let compare = hash_with_query(
        Page::Compare,
        &[
            ("preset".into(), LINK_PRESET.into()),
            ("variants".into(), "2".into()),
            (
                "a.controller".into(),
                ControllerKind::FuzzyDynamics.name().into(),
            ),
            ("b.controller".into(), kind.clone()),
            ("b.engine".into(), text.clone()),
        ],
    );
    let tune = hash_with_query(Page::Tune, &[("engine".into(), text)]);
    Some(view! {
        <p class="hint">
            "As the loop's controller (first input E, second EC, the output the override's change): "
            <a href=simulate>"Use in Simulate"</a>
            " · "
            <a href=compare>"Use in Compare"</a>
            " (beside paper 002's dynamics table) · "
            <a href=tune>"Tune it"</a>
        </p>
    })
}

/// The engine fieldset.
#[component]
pub fn EnginePanel(fuzzy: Fuzzy) -> impl IntoView {
    let Fuzzy {
        studied, source, ..
    } = fuzzy;
    let body = move || {
        studied.with(|e| {
            let Ok(e) = e else {
                return ().into_any();
            };
            let rule_list = matches!(source.get(), Source::Imported(..)).then(|| {
                let rules = (0..e.rules().len())
                    .map(|r| view! { <li>{e.rule_text(r)}</li> })
                    .collect_view();
                view! { <ol class="firing-list" aria-label="Rules">{rules}</ol> }
            });
            view! {
                <p>{format!("Engine \"{}\": {} rules.", e.name, e.rules().len())}</p>
                {variables(e)}
                {rule_list}
                {links(e)}
            }
            .into_any()
        })
    };
    view! {
        <fieldset>
            <legend>"Engine"</legend>
            {body}
        </fieldset>
    }
}
