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

/// The controller that runs `table`, as a link's `controller` and `rules`: a built-in rule
/// base is its own controller (`fuzzy-experience`, `fuzzy-dynamics`), so Simulate and Compare
/// name the table run; an edited table runs on `fuzzy-dynamics` with its `rules`.
fn controller_of(table: &RuleTable) -> (ControllerKind, Option<String>) {
    if *table == RuleBase::Experience.table() {
        (ControllerKind::FuzzyExperience, None)
    } else if *table == RuleBase::Dynamics.table() {
        (ControllerKind::FuzzyDynamics, None)
    } else {
        (
            ControllerKind::FuzzyDynamics,
            Some(encode_rule_table(table)),
        )
    }
}

/// The query pairs of the controller that runs `table` ([`controller_of`]), each key after
/// `prefix` (Compare's `b.`).
fn controller_query(table: &RuleTable, prefix: &str) -> Vec<(String, String)> {
    let (kind, rules) = controller_of(table);
    let mut q = vec![(format!("{prefix}controller"), kind.name().to_string())];
    q.extend(rules.map(|r| (format!("{prefix}rules"), r)));
    q
}

/// Simulate with `table` on paper 002's preset.
fn simulate_href(table: &RuleTable) -> String {
    let mut q = vec![(
        "preset".to_string(),
        Preset::LiuCurrentStep.name().to_string(),
    )];
    q.extend(controller_query(table, ""));
    hash_with_query(Page::Simulate, &q)
}

/// Compare with `table` as variant B beside paper 002's own dynamics table (variant A), on
/// paper 002's preset, in the URL form Compare's controller forms read.
fn compare_href(table: &RuleTable) -> String {
    let mut q = vec![
        (
            "preset".to_string(),
            Preset::LiuCurrentStep.name().to_string(),
        ),
        ("variants".to_string(), "2".to_string()),
        (
            "a.controller".to_string(),
            ControllerKind::FuzzyDynamics.name().to_string(),
        ),
    ];
    q.extend(controller_query(table, "b."));
    hash_with_query(Page::Compare, &q)
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
                        // Pressed while the table studied is this base's, unedited.
                        let pressed = move || {
                            matches!(source.get(), Source::Table) && table.with(|t| *t == b.table())
                        };
                        view! {
                            <button
                                type="button"
                                class="toggle"
                                aria-pressed=move || if pressed() { "true" } else { "false" }
                                on:click=move |_| {
                                    table.set(b.table());
                                    source.set(Source::Table);
                                }
                            >
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
            // An imported engine has its own links (the Engine panel's); these run the table.
            <p class="hint" hidden=move || !matches!(source.get(), Source::Table)>
                <a href=move || simulate_href(&table.get())>"Simulate with this table"</a>
                " · "
                <a href=move || compare_href(&table.get())>"Open in Compare"</a>
                " (beside paper 002's own table)"
            </p>
        </fieldset>
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_built_in_table_runs_as_its_own_controller_and_an_edited_one_with_its_rules() {
        let experience = RuleBase::Experience.table();
        assert_eq!(
            controller_of(&experience),
            (ControllerKind::FuzzyExperience, None)
        );
        assert_eq!(
            controller_of(&RuleBase::Dynamics.table()),
            (ControllerKind::FuzzyDynamics, None)
        );
        let mut edited = experience;
        edited[0][0] = 3;
        assert_eq!(
            controller_of(&edited),
            (
                ControllerKind::FuzzyDynamics,
                Some(encode_rule_table(&edited))
            )
        );
        // Compare's variant B is named by its controller: the experience table's, not A's.
        assert_eq!(
            controller_query(&experience, "b."),
            vec![("b.controller".to_string(), "fuzzy-experience".to_string())]
        );
        assert_eq!(
            controller_query(&edited, "b."),
            vec![
                ("b.controller".to_string(), "fuzzy-dynamics".to_string()),
                ("b.rules".to_string(), encode_rule_table(&edited)),
            ]
        );
    }
}
