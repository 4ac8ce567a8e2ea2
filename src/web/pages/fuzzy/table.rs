//! The 7×7 rule table, cell by cell (keyboard too), with the rule bases one click away and the
//! defuzzifier; an imported engine that is no such table is shown by name.

use leptos::prelude::*;

use super::{Fuzzy, Source};
use crate::control::fuzzy::engine::Defuzzifier;
use crate::control::fuzzy::rules::{RuleBase, RuleTable, LEVEL_NAMES};
use crate::control::registry::ControllerKind;
use crate::plant::Preset;
use crate::web::components::fields::SelectField;
use crate::web::components::later::Later;
use crate::web::components::run_form::encode_rule_table;
use crate::web::route::{hash_with_query, Page};

/// One cell of the table: a select of the seven levels, marked while its rule fires.
fn cell(fuzzy: Fuzzy, e: usize, ec: usize) -> impl IntoView {
    let table = fuzzy.table;
    let label = format!(
        "Output when E is {} and EC is {}",
        LEVEL_NAMES[e], LEVEL_NAMES[ec]
    );
    let value = Signal::derive(move || {
        let level = table.with(|t| t[e][ec]);
        LEVEL_NAMES[(level + 3).clamp(0, 6) as usize].to_string()
    });
    let class = move || {
        let level = table.with(|t| t[e][ec]);
        let mut c = match level {
            -3 => "level-n3",
            -2 => "level-n2",
            -1 => "level-n1",
            0 => "level-0",
            1 => "level-1",
            2 => "level-2",
            _ => "level-3",
        }
        .to_string();
        if fuzzy.is_firing(e, ec) {
            c.push_str(" firing");
        }
        c
    };
    // The options are marked once, as the cell mounts (`prop:value` cannot choose an option
    // before the options exist); later changes of the table go through `prop:value` alone,
    // which saves a reactive `selected` per option: 343 of them in the table.
    let chosen_at_mount = value.get_untracked();
    view! {
        <td class=class>
            <select
                aria-label=label
                on:change=move |ev| {
                    let chosen = event_target_value(&ev);
                    if let Some(level) = LEVEL_NAMES.iter().position(|n| *n == chosen) {
                        table.update(|t| t[e][ec] = level as i8 - 3);
                    }
                }
                prop:value=move || value.get()
            >
                {LEVEL_NAMES
                    .iter()
                    .map(|n| view! { <option value=*n selected=*n == chosen_at_mount>{*n}</option> })
                    .collect_view()}
            </select>
        </td>
    }
}

/// Compare with `table` as variant B beside paper 002's own dynamics table (variant A), on
/// paper 002's preset, in the URL form Compare's controller forms read.
fn compare_href(table: &RuleTable) -> String {
    let fuzzy_dynamics = ControllerKind::FuzzyDynamics.name().to_string();
    hash_with_query(
        Page::Compare,
        &[
            ("preset".into(), Preset::LiuCurrentStep.name().into()),
            ("variants".into(), "2".into()),
            ("a.controller".into(), fuzzy_dynamics.clone()),
            ("b.controller".into(), fuzzy_dynamics),
            ("b.rules".into(), encode_rule_table(table)),
        ],
    )
}

/// The rule table's fieldset.
#[component]
pub fn RuleTablePanel(fuzzy: Fuzzy) -> impl IntoView {
    let Fuzzy {
        table,
        source,
        defuzzifier,
        ..
    } = fuzzy;
    view! {
        <fieldset>
            <legend>"Rule table"</legend>
            <div class="button-row">
                {RuleBase::ALL
                    .iter()
                    .map(|b| {
                        let b = *b;
                        view! {
                            <button type="button" on:click=move |_| {
                                table.set(b.table());
                                source.set(Source::Table);
                            }>
                                {b.label()}
                            </button>
                        }
                    })
                    .collect_view()}
            </div>
            <Later>
            {move || match source.get() {
                Source::Imported(e, why) => view! {
                    <p class="hint">
                        {format!("Showing the imported engine \"{}\"; it is not a 7×7 table ({why}). ", e.name)}
                        <button type="button" on:click=move |_| source.set(Source::Table)>"Back to the table"</button>
                    </p>
                }
                .into_any(),
                Source::Table => view! {
                    <p class="hint">{format!("Levels: {}.", crate::control::fuzzy::rules::level_legend())}</p>
                    <div class="rule-table-wrap">
                    <table class="rule-table" aria-label="Rule table: output U for each E (rows) and EC (columns)">
                        <thead>
                            <tr>
                                <th scope="col">"E \\ EC"</th>
                                {LEVEL_NAMES.iter().map(|n| view! { <th scope="col">{*n}</th> }).collect_view()}
                            </tr>
                        </thead>
                        <tbody>
                            {(0..7)
                                .map(|e| {
                                    view! {
                                        <tr>
                                            <th scope="row">{LEVEL_NAMES[e]}</th>
                                            {(0..7).map(|ec| cell(fuzzy, e, ec)).collect_view()}
                                        </tr>
                                    }
                                })
                                .collect_view()}
                        </tbody>
                    </table>
                    </div>
                }
                .into_any(),
            }}
            </Later>
            <SelectField
                id="defuzzifier"
                label="Defuzzifier"
                options=Defuzzifier::ALL.iter().map(|d| (d.name(), d.label())).collect()
                value=defuzzifier
            />
            <p class="hint">
                <a href=move || format!(
                    "#/simulate?preset=liu-current-step&controller=fuzzy-dynamics&rules={}",
                    encode_rule_table(&table.get())
                )>"Simulate with this table"</a>
                " · "
                <a href=move || compare_href(&table.get())>"Open in Compare"</a>
                " (beside paper 002's own table)"
            </p>
        </fieldset>
    }
}
