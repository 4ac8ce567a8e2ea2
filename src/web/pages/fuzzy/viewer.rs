//! The rule viewer: the output and the rules that fire, with their strengths, for a chosen
//! (E, EC), a point picked on the surface or a moment of a run.

use leptos::prelude::*;

use super::Fuzzy;
use crate::web::components::fields::{parse_number, NumberField};

/// The viewer's fieldset.
#[component]
pub fn RuleViewer(fuzzy: Fuzzy) -> impl IntoView {
    let Fuzzy {
        e_text,
        ec_text,
        engine,
        viewer,
        ..
    } = fuzzy;
    let rule_text = move |index: usize| {
        engine.with(|engine| {
            let Ok(engine) = engine else {
                return String::new();
            };
            engine.rule_text(index)
        })
    };
    view! {
        <fieldset>
            <legend>"Rule viewer"</legend>
            <NumberField
                id="viewer-e"
                label="E (scaled)"
                value=e_text
                error=Signal::derive(move || parse_number(&e_text.get()).err())
            />
            <NumberField
                id="viewer-ec"
                label="EC (scaled)"
                value=ec_text
                error=Signal::derive(move || parse_number(&ec_text.get()).err())
            />
            <p class="hint">"Or click a point of the control surface."</p>
            {move || {
                viewer
                    .get()
                    .map(|(u, firing)| {
                        let mut firing = firing;
                        firing.sort_by(|a, b| b.1.total_cmp(&a.1));
                        view! {
                            <p role="status">
                                <strong>{format!("U = {u:.3}")}</strong>
                                {format!(" — {} rule(s) fire", firing.len())}
                            </p>
                            <ol class="firing-list" aria-label="Firing rules">
                                {firing
                                    .into_iter()
                                    .map(|(r, a)| {
                                        view! {
                                            <li>
                                                <span class="bar" style=format!("width: {:.1}rem", 4.0 * a)></span>
                                                {format!("{:.2}: {}", a, rule_text(r))}
                                            </li>
                                        }
                                    })
                                    .collect_view()}
                            </ol>
                        }
                    })
            }}
        </fieldset>
    }
}
