//! The 7×7 rule table, cell by cell (keyboard too), with the rule bases one click away and the
//! defuzzifier; an imported engine that is no such table is shown by name.

use leptos::prelude::*;

use super::{Fuzzy, Source};
use crate::control::fuzzy::engine::{Defuzzifier, Engine};
use crate::control::fuzzy::fll;
use crate::control::fuzzy::rules::{paper_002_engine, RuleBase, RuleTable, LEVEL_NAMES};
use crate::control::registry::{ControllerKind, PAPER_002_DEFUZZIFIER};
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

/// Paper 002's engine of `table` defuzzified by `defuzzifier`, named after both so the run's
/// form shows what it runs: `paper002_dynamics_Centroid`, `paper002_edited_Bisector`.
fn table_engine(table: &RuleTable, defuzzifier: Defuzzifier) -> Option<Engine> {
    let which = RuleBase::ALL
        .into_iter()
        .find(|b| b.table() == *table)
        .map_or("edited", RuleBase::name);
    let mut engine = paper_002_engine(table, defuzzifier).ok()?;
    engine.name = format!("paper002_{which}_{}", defuzzifier.name());
    Some(engine)
}

/// The query pairs of the controller that runs `table` defuzzified by `defuzzifier`, each key
/// after `prefix` (Compare's `b.`). With paper 002's defuzzifier, the table's controller
/// ([`controller_of`]). With another, the table and the defuzzifier as one engine
/// ([`table_engine`]) on `fuzzy-engine` (`engine=`): the table controllers defuzzify as paper
/// 002 does (eq 7, [`PAPER_002_DEFUZZIFIER`]), and an engine is how a run already carries a
/// table with any other defuzzifier, in its link, its saved configuration and the CLI's
/// `--fuzzy-engine`, so the run is the engine the page shows.
fn controller_query(
    table: &RuleTable,
    defuzzifier: Defuzzifier,
    prefix: &str,
) -> Vec<(String, String)> {
    if defuzzifier != PAPER_002_DEFUZZIFIER {
        if let Some(engine) = table_engine(table, defuzzifier) {
            return vec![
                (
                    format!("{prefix}controller"),
                    ControllerKind::FuzzyEngine.name().to_string(),
                ),
                (
                    format!("{prefix}engine"),
                    fll::to_url_text(&fll::write(&engine)),
                ),
            ];
        }
    }
    let (kind, rules) = controller_of(table);
    let mut q = vec![(format!("{prefix}controller"), kind.name().to_string())];
    q.extend(rules.map(|r| (format!("{prefix}rules"), r)));
    q
}

/// Simulate with `table` and `defuzzifier` on paper 002's preset.
fn simulate_href(table: &RuleTable, defuzzifier: Defuzzifier) -> String {
    let mut q = vec![(
        "preset".to_string(),
        Preset::LiuCurrentStep.name().to_string(),
    )];
    q.extend(controller_query(table, defuzzifier, ""));
    hash_with_query(Page::Simulate, &q)
}

/// Compare with `table` and `defuzzifier` as variant B beside paper 002's own dynamics table
/// (variant A), on paper 002's preset, in the URL form Compare's controller forms read.
fn compare_href(table: &RuleTable, defuzzifier: Defuzzifier) -> String {
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
    q.extend(controller_query(table, defuzzifier, "b."));
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
                <a href=move || simulate_href(&table.get(), fuzzy.chosen_defuzzifier())>"Simulate with this table"</a>
                " · "
                <a href=move || compare_href(&table.get(), fuzzy.chosen_defuzzifier())>"Open in Compare"</a>
                " (beside paper 002's own table)"
                {move || {
                    let d = fuzzy.chosen_defuzzifier();
                    (d != PAPER_002_DEFUZZIFIER)
                        .then(|| table_engine(&table.get(), d))
                        .flatten()
                        .map(|e| format!(
                            ". Paper 002's controllers defuzzify by the weighted average (eq 7), so \
                             with {} the table runs as the engine \"{}\" (fuzzy-engine).",
                            d.label(),
                            e.name
                        ))
                }}
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
        let d = PAPER_002_DEFUZZIFIER;
        assert_eq!(
            controller_query(&experience, d, "b."),
            vec![("b.controller".to_string(), "fuzzy-experience".to_string())]
        );
        assert_eq!(
            controller_query(&edited, d, "b."),
            vec![
                ("b.controller".to_string(), "fuzzy-dynamics".to_string()),
                ("b.rules".to_string(), encode_rule_table(&edited)),
            ]
        );
    }

    #[test]
    fn a_table_with_another_defuzzifier_runs_as_its_engine_named_after_both() {
        use crate::control::fuzzy::rules::paper_002_table;
        use crate::control::law::ControlInput;
        use crate::control::registry::{ControllerConfig, RunContext};
        use crate::web::components::run_form::decode_rule_table;
        let context = RunContext {
            target_force_n: 300.0,
            control_period_s: 0.1,
            amps_per_newton: f64::NAN,
        };
        // A light cut, 20 % below the target: the two defuzzifiers answer differently.
        let light = ControlInput {
            time_s: 10.0,
            dt_s: 0.1,
            force_n: 240.0,
            target_force_n: 300.0,
            programmed_feed_mm_min: 200.0,
            applied_override_pct: 100.0,
            time_since_start_s: 10.0,
        };
        let mut edited = RuleBase::Dynamics.table();
        edited[6][6] = -3;
        for (table, name) in [
            (RuleBase::Dynamics.table(), "paper002_dynamics_Centroid"),
            (RuleBase::Experience.table(), "paper002_experience_Centroid"),
            (edited, "paper002_edited_Centroid"),
        ] {
            let q = controller_query(&table, Defuzzifier::Centroid, "b.");
            assert_eq!(q.len(), 2, "{q:?}");
            assert_eq!(
                q[0],
                ("b.controller".to_string(), "fuzzy-engine".to_string())
            );
            assert_eq!(q[1].0, "b.engine");
            // What Simulate's and Compare's forms make of the link: the engine, named, with the
            // table and the defuzzifier chosen.
            let mut config = ControllerConfig::new(ControllerKind::FuzzyEngine);
            config.set_engine(&fll::from_url_text(&q[1].1)).unwrap();
            let engine = fll::parse(config.engine_fll().unwrap()).unwrap();
            assert_eq!(engine.name, name);
            assert_eq!(engine.outputs()[0].defuzzifier, Defuzzifier::Centroid);
            assert_eq!(paper_002_table(&engine).ok(), Some(table));
            let mapping = config.engine_mapping().unwrap();
            assert!(
                mapping.starts_with(&format!("Engine \"{name}\"")),
                "{mapping}"
            );
            // And it runs otherwise than the table under paper 002's weighted average.
            let (kind, rules) = controller_of(&table);
            let mut paper = ControllerConfig::new(kind);
            if let Some(rules) = rules {
                paper
                    .set_rule_table(decode_rule_table(&rules).unwrap())
                    .unwrap();
            }
            let centroid = config.build(&context).unwrap().step(&light);
            let weighted = paper.build(&context).unwrap().step(&light);
            assert!(
                (centroid - weighted).abs() > 1e-6,
                "{name}: {centroid} against {weighted}"
            );
        }
        // With paper 002's defuzzifier the table runs on its own controller, as before.
        assert_eq!(
            controller_query(&edited, PAPER_002_DEFUZZIFIER, ""),
            vec![
                ("controller".to_string(), "fuzzy-dynamics".to_string()),
                ("rules".to_string(), encode_rule_table(&edited)),
            ]
        );
    }
}
