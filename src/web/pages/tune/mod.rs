//! Tune: teach-in (the chosen scenarios' simulated teach cuts, or a saved calibration file), a
//! grid sweep or a Nelder–Mead search over a controller's parameters across scenarios, its runs
//! in the computation workers, several at once (`tuning::TuningPlan`); the table, the heat map of
//! a two-parameter sweep and the chart of the Pareto front fill in when it is done. Every field is a row of the tuning's
//! table ([`crate::tuning::settings`]), as `cutlab tune`'s options are.
//!
//! | file | panel |
//! |---|---|
//! | `mod.rs` | the page: the run of a tuning from the form |
//! | `teach_in.rs` | the scenarios and the teach-in |
//! | `params.rs` | the controller and the parameters tuned |
//! | `method.rs` | search or sweep, and the objective's weights |
//! | `results.rs` | the proposals, the best evaluation, the trade-off, the heat map, the evaluations |
//! | [`in_workers`] | the tuning's runs in the computation workers, several at once |
//! | [`params`] | the controller tuned and its parameters with their bounds |
//! | [`method`] | how the parameters are tried: Nelder–Mead or a grid |
//! | [`teach_in`] | the scenarios tuned, and the teach-in |
//! | [`results`] | what a tuning and a teach-in found |

mod in_workers;
mod method;
mod params;
mod results;
mod teach_in;

use leptos::prelude::*;

use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::paper_defaults::preset_controller;
use crate::control::fuzzy::fll;
use crate::control::registry::{ControllerConfig, ControllerKind};
use crate::input::table::{self, Table};
use crate::plant::Preset;
use crate::tuning::nelder_mead::NelderMead;
use crate::tuning::settings::{parse_objective, TuneSetting};
use crate::tuning::{ParamRange, TeachIn, Tuned, TuningMode, TuningPlan, TuningProblem};
use crate::web::components::page::PageShell;
use crate::web::components::run_view::StaleNotice;
use crate::web::components::runner::{RunProgress, Runner};
use crate::web::components::table_form::{FieldErrors, TableForm};
use crate::web::route::{query_params, replace_query, Page};
use in_workers::start_tuning;
use method::{method_errors, MethodPanel};
use params::{ParamRow, ParamsPanel, TUNABLE};
use results::{TeachInTable, TuningResults};
use teach_in::{Scenarios, ScenariosPanel, TeachInPanel};

/// What the last finished tuning was asked: its ranges, a sweep's values per parameter (0 for a
/// search), the first scenario and the controller, for the heat map and the links.
type Asked = (Vec<ParamRange>, usize, Preset, ControllerConfig);

/// The Tune page.
#[component]
pub fn TunePage() -> impl IntoView {
    // What a shared link or a reload says (the page writes it back below).
    let query = query_params(&window().location().hash().unwrap_or_default());
    let typed = |key: &str| query.iter().find(|(k, _)| k == key).map(|(_, v)| v.clone());
    let kind_text = RwSignal::new(
        typed("controller")
            .filter(|k| {
                k.parse::<ControllerKind>()
                    .is_ok_and(|k| TUNABLE.contains(&k))
            })
            .unwrap_or_else(|| ControllerKind::Pi.name().to_string()),
    );
    let kind = Memo::new(move |_| {
        kind_text
            .get()
            .parse::<ControllerKind>()
            .unwrap_or(ControllerKind::Pi)
    });
    let scenarios = Scenarios::new();
    if let Some(names) = typed("scenarios") {
        scenarios.restore(&names);
    }
    // An engine carried from the Fuzzy rules page (`engine=`, as Simulate's URL holds it).
    let engine = RwSignal::new(typed("engine").map(|v| fll::from_url_text(&v)));
    let rows = [ParamRow::new(kind, 0), ParamRow::new(kind, 1)];
    for (i, row) in rows.iter().enumerate() {
        row.restore(kind.get_untracked(), i, &query);
    }
    let second_on = RwSignal::new(typed("second").as_deref() != Some("0"));
    Effect::new(move |previous: Option<ControllerKind>| {
        let k = kind.get();
        if previous.is_some_and(|p| p != k) {
            for (i, row) in rows.iter().enumerate() {
                row.reset(k, i);
            }
        }
        k
    });
    let mode = RwSignal::new(
        typed("method")
            .filter(|m| m == "sweep")
            .unwrap_or_else(|| "search".to_string()),
    );
    let form = TableForm::<TuneSetting>::new(&query);
    // Everything settable in the address bar, so a reload or a shared link restores it.
    Effect::new(move |_| {
        let chosen: Vec<&str> = scenarios.chosen().iter().map(|p| p.name()).collect();
        let mut pairs = vec![
            ("controller".to_string(), kind_text.get()),
            ("scenarios".to_string(), chosen.join(",")),
        ];
        for (i, row) in rows.iter().enumerate() {
            pairs.extend(row.query(i));
        }
        if !second_on.get() {
            pairs.push(("second".to_string(), "0".to_string()));
        }
        pairs.push(("method".to_string(), mode.get()));
        pairs.extend(form.query());
        if let Some(text) = engine.get() {
            pairs.push(("engine".to_string(), fll::to_url_text(&text)));
        }
        replace_query(Page::Tune, &pairs);
    });
    let errors = Memo::new(move |_| method_errors(form));
    let fields_invalid = any_field_invalid(errors, rows, second_on);

    let runner = Runner::<Tuned>::new();
    let teach_runner = Runner::<Vec<TeachIn>>::new();
    let (form_error, set_form_error) = signal(None::<String>);
    let asked = RwSignal::new(None::<Asked>);
    let from_file = RwSignal::new(None::<TeachIn>);

    let runner_for_start = runner.clone();
    let start = move |_| {
        let presets = scenarios.chosen();
        let Some(&first) = presets.first() else {
            set_form_error.set(Some("Choose at least one scenario.".into()));
            return;
        };
        let k = kind.get_untracked();
        let count = if second_on.get_untracked() { 2 } else { 1 };
        // What is wrong, by the label of its field: the message beside the Run button names
        // them, each field's own message stands beside it.
        let mut wrong: Vec<String> = Vec::new();
        let mut params = Vec::new();
        for (i, row) in rows[..count].iter().enumerate() {
            match row.parse() {
                Ok(range) => params.push(range),
                Err(e) => wrong.extend(e.keys().map(|side| format!("Parameter {} {side}", i + 1))),
            }
        }
        let texts = form.texts_untracked();
        let text = |s: TuneSetting| {
            texts
                .iter()
                .find(|(t, _)| *t == s)
                .map_or("", |(_, x)| x.as_str())
        };
        let tuning_mode = if mode.get_untracked() == "sweep" {
            table::count(TuneSetting::Steps, text(TuneSetting::Steps)).map(TuningMode::Sweep)
        } else {
            table::count(TuneSetting::Evaluations, text(TuneSetting::Evaluations)).map(|n| {
                TuningMode::Search(NelderMead {
                    max_evaluations: n,
                    ..NelderMead::default()
                })
            })
        };
        let objective = parse_objective(&texts);
        if let Err(e) = &tuning_mode {
            wrong.push(e.setting.row().label.to_string());
        }
        if let Err(errors) = &objective {
            wrong.extend(errors.iter().map(|e| e.setting.row().label.to_string()));
        }
        let (true, Ok(tuning_mode), Ok(objective)) = (wrong.is_empty(), tuning_mode, objective)
        else {
            set_form_error.set(Some(format!(
                "Fix the fields marked above: {}.",
                wrong.join(", ")
            )));
            return;
        };
        let mut problem = TuningProblem {
            controller: preset_controller(first, k),
            params: params.clone(),
            scenarios: presets.iter().map(|&p| RunSpec::new(p, k)).collect(),
            objective,
        };
        if let Some(text) = engine
            .get_untracked()
            .filter(|_| k == ControllerKind::FuzzyEngine)
        {
            let controllers = std::iter::once(&mut problem.controller)
                .chain(problem.scenarios.iter_mut().map(|s| &mut s.controller));
            for controller in controllers {
                if let Err(e) = controller.set_engine(&text) {
                    set_form_error.set(Some(e.to_string()));
                    return;
                }
            }
        }
        let controller = problem.controller.clone();
        match TuningPlan::new(problem, tuning_mode) {
            Ok(plan) => {
                set_form_error.set(None);
                let steps = match tuning_mode {
                    TuningMode::Sweep(n) => n,
                    TuningMode::Search(_) => 0,
                };
                asked.set(Some((params, steps, first, controller)));
                // Each run of an evaluation in a computation worker of its own, several at once.
                let search = matches!(tuning_mode, TuningMode::Search(_));
                start_tuning(&runner_for_start, plan, search);
            }
            Err(e) => set_form_error.set(Some(e.to_string())),
        }
    };

    let tuned = runner.finished();
    let stale = Signal::derive(move || fields_invalid.get() && tuned.with(Option::is_some));
    view! {
        <PageShell id="tune" title="Tune a controller">
            <p class="lede">
                "Find settings instead of trying them: a teach-in proposes a target and a threshold "
                "gap from one teach cut; a sweep runs a grid of one or two parameters; a search "
                "(Nelder–Mead) minimises the weighted objective across the scenarios. Every "
                "evaluation runs the same closed loop as Simulate."
            </p>
            <div class="layout-two">
                <form class="panel" aria-label="Tuning settings" on:submit=|ev| ev.prevent_default()>
                    <ScenariosPanel scenarios=scenarios />
                    <TeachInPanel scenarios=scenarios runner=teach_runner.clone() from_file=from_file form_error=set_form_error />
                    <ParamsPanel kind_text=kind_text kind=kind rows=rows second_on=second_on engine=engine />
                    <MethodPanel form=form mode=mode errors=errors />
                    <div class="button-row">
                        <button type="button" on:click=start>"Run"</button>
                    </div>
                    {move || form_error.get().map(|e| view! { <p class="run-error" role="alert">{e}</p> })}
                </form>
                <div class="results" class:stale=stale>
                    <RunProgress runner=teach_runner.clone() id="teach-progress" failure="The teach-in could not be made" />
                    <TeachInTable taught=teach_runner.finished() from_file=from_file />
                    <RunProgress runner=runner.clone() id="tune-progress" failure="The tuning could not be made" />
                    <StaleNotice stale=stale />
                    <div class="tuning-results">
                        <TuningResults tuned=tuned asked=asked />
                    </div>
                </div>
            </div>
        </PageShell>
    }
}

/// Whether a field no longer validates: the results shown are then from settings the form does
/// not hold, and are marked stale (as Simulate's and Compare's are) until the next run.
fn any_field_invalid(
    errors: Memo<FieldErrors>,
    rows: [ParamRow; 2],
    second_on: RwSignal<bool>,
) -> Memo<bool> {
    Memo::new(move |_| {
        let count = if second_on.get() { 2 } else { 1 };
        !errors.get().is_empty() || rows[..count].iter().any(|row| row.parse().is_err())
    })
}
