//! Compare: one scenario, two to four controller variants, overlaid and side by side.
//!
//! | file | panel |
//! |---|---|
//! | `mod.rs` | the page: the scenario, the variants, the runs and their charts and metrics |
//! | `papers.rs` | the papers' comparisons, one click away, with what the lab measures of each claim |
//! | `export.rs` | traces, metrics and the configuration as files |
//! | [`export`] | the comparison as files: traces and metrics as CSV, the configuration as JSON |
//! | [`papers`] | the papers' comparisons, one click away, each with its claim and measured finding |

mod export;
mod papers;

use std::sync::Arc;
use std::time::Duration;

use leptos::prelude::*;

use crate::closed_loop::config::RunConfiguration;
use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::lab::RunResult;
use crate::control::registry::ControllerKind;
use crate::control::run_names::run_names;
use crate::web::components::later::{effect_after_mount, now_and_after_mount, Later};
use crate::web::components::page::PageShell;
use crate::web::components::run_form::{
    ConfigurationFile, ControllerFields, ControllerForm, MachineAndSignalFields, ScenarioFields,
    ScenarioForm,
};
use crate::web::components::run_view::{MetricsTable, NamedRun, RunCharts, StaleNotice};
use crate::web::components::runner::{Debounce, RunProgress, RunStatus, Runner};
use crate::web::components::savings::Savings;
use crate::web::components::teach_cuts::KeptCalibrations;
use crate::web::route::{query_params, replace_query, Page};
use export::ExportPanel;
use papers::PaperComparisons;

/// Wait after an edit before re-running: none beyond the task that made it, so the events of one
/// edit start one run. A new run cancels the one before and its first chunk waits for a task of
/// its own, so typing "150" costs only the last run, and the page answers within a frame.
const RERUN_DELAY: Duration = Duration::ZERO;

/// Teach cuts whose calibrations the page keeps, so an edit of a controller re-runs only loops.
const KEPT_CALIBRATIONS: usize = 4;

const VARIANT_PREFIXES: [&str; 4] = ["a.", "b.", "c.", "d."];
const VARIANT_NAMES: [&str; 4] = ["A", "B", "C", "D"];

/// The Compare page.
#[component]
pub fn ComparePage() -> impl IntoView {
    let query = query_params(&window().location().hash().unwrap_or_default());
    let scenario = ScenarioForm::new(&query);
    let defaults = [
        ControllerKind::Fixed,
        ControllerKind::Threshold,
        ControllerKind::Pi,
        ControllerKind::Mrac,
    ];
    let forms: [ControllerForm; 4] = std::array::from_fn(|i| {
        ControllerForm::new(
            ["cmp-a-", "cmp-b-", "cmp-c-", "cmp-d-"][i],
            defaults[i],
            scenario.chosen_preset_untracked(),
            &query,
            VARIANT_PREFIXES[i],
        )
    });
    // Untouched controller parameters follow the preset (a paper's own values on its preset).
    Effect::new(move |_| {
        if let Some(preset) = scenario.chosen_preset() {
            for form in &forms {
                form.follow_preset(preset);
            }
        }
    });
    let initial_count = query
        .iter()
        .find(|(k, _)| k == "variants")
        .and_then(|(_, v)| v.parse::<usize>().ok())
        .unwrap_or(2)
        .clamp(2, 4);
    let count = RwSignal::new(initial_count);
    let runner = Runner::<Vec<Arc<RunResult>>>::new();
    let savings = Savings::new();

    let specs = Memo::new(move |_| {
        let s = scenario.parse().ok()?;
        forms[..count.get()]
            .iter()
            .map(|f| {
                f.parse().ok().map(|c| RunSpec {
                    preset: s.preset,
                    controller: c,
                    seed: s.seed,
                    settings: s.settings,
                    plant: s.plant,
                })
            })
            .collect::<Option<Vec<_>>>()
    });

    let calibrations = KeptCalibrations::new(KEPT_CALIBRATIONS);
    let debounce = Debounce::first_at_once(RERUN_DELAY);
    let savings_for_edits = savings.clone();
    let runner_for_effect = runner.clone();
    // Keep the URL in step with the forms.
    effect_after_mount(move || {
        let mut q = scenario.query();
        q.push(("variants".into(), count.get().to_string()));
        for (form, prefix) in forms.iter().zip(VARIANT_PREFIXES).take(count.get()) {
            q.extend(form.query(prefix));
        }
        replace_query(Page::Compare, &q);
    });
    // Re-run when the valid specs change, and only then: `specs` is a memo, so the forms' signals
    // settling after the page mounts, or a field set to what it held, start nothing. The first
    // runs are asked for as the page mounts.
    now_and_after_mount(specs, move |specs| {
        if let Some(first) = specs.first() {
            savings_for_edits.keep_only(first);
        }
        let runner = runner_for_effect.clone();
        // Each variant in a computation worker of its own, all at once.
        let start = move || runner.start_in_workers(specs, calibrations.known());
        debounce.request(start);
    });

    // Each column by its variant and its controller, with the table or engine it runs where that
    // is not its kind's own, so two columns of different laws never read alike.
    let named = |runs: Vec<Arc<RunResult>>| {
        let controllers: Vec<_> = runs.iter().map(|r| &r.spec.controller).collect();
        let names = run_names(&controllers);
        runs.into_iter()
            .zip(VARIANT_NAMES)
            .zip(names)
            .map(|((r, variant), name)| (format!("{variant}: {name}"), r))
            .collect::<Vec<NamedRun>>()
    };
    let done = runner.finished();
    let results = Memo::new(move |_| named(done.get().unwrap_or_default()));
    // Every variant shares the scenario, so one set of reference runs serves them all, on the
    // variants' teach cut.
    savings.request_while_running(&runner);
    let savings_for_effect = savings.clone();
    Effect::new(move |_| {
        results.with(|runs| {
            if let Some((_, first)) = runs.first() {
                calibrations.remember(&first.spec, &first.calibration);
                savings_for_effect.request(&first.spec, Some(&first.calibration));
            }
        });
    });
    let savings_for_runs = savings.clone();
    let runs = Signal::derive(move || savings_for_runs.apply_all(results.get()));
    // The charts draw the runs as they advance, then the finished comparison with its savings.
    let preview = runner.preview;
    let status = runner.status;
    // Only the start and end of a run matter here, not every progress tick.
    let running = Memo::new(move |_| matches!(status.get(), RunStatus::Running { .. }));
    let drawn = Signal::derive(move || match preview.get() {
        Some(so_far) if running.get() => named(so_far),
        _ => runs.get(),
    });

    // Results from settings the forms no longer hold (a field that does not validate).
    let stale = Signal::derive(move || specs.with(Option::is_none) && !results.with(Vec::is_empty));
    // A saved configuration into the forms: its runs are the variants, on its first run's
    // scenario; checked whole before any field changes.
    let load_configuration = Callback::new(move |config: RunConfiguration| {
        let runs = &config.runs;
        let Some(first) = runs.first() else {
            return Err("the file holds no run".to_string());
        };
        if runs.len() > forms.len() {
            return Err(format!(
                "it holds {} runs; Compare shows at most {}",
                runs.len(),
                forms.len()
            ));
        }
        let same_scenario = |r: &RunSpec| {
            (r.preset, r.seed, r.settings, r.plant)
                == (first.preset, first.seed, first.settings, first.plant)
        };
        if let Some(i) = runs.iter().position(|r| !same_scenario(r)) {
            return Err(format!(
                "run {} has another scenario than run 1; Compare runs every variant on one",
                i + 1
            ));
        }
        scenario.load(first);
        for (form, run) in forms.iter().zip(runs) {
            form.load(&run.controller, first.preset);
        }
        count.set(runs.len().clamp(2, forms.len()));
        Ok(())
    });

    view! {
        <PageShell id="compare" title="Compare controllers">
            <p class="lede">
                "One scenario and seed, two to four controllers or tunings. The traces are overlaid "
                "on linked time axes and the metrics table marks the best value of each row."
            </p>
            <div class="layout-two">
                <form class="panel" aria-label="Comparison settings" on:submit=|ev| ev.prevent_default()>
                    <Later>
                    <PaperComparisons scenario=scenario forms=forms count=count runs=runs />
                    <ScenarioFields form=scenario />
                    </Later>
                    <Later>
                    {move || {
                        (0..count.get())
                            .map(|i| {
                                let legend = ["Variant A", "Variant B", "Variant C", "Variant D"][i];
                                view! { <ControllerFields form=forms[i] legend=legend /> }
                            })
                            .collect_view()
                    }}
                    </Later>
                    <Later>
                    <MachineAndSignalFields form=scenario />
                    <div class="button-row">
                        <button type="button" on:click=move |_| count.update(|c| *c = (*c + 1).min(4)) disabled=move || { count.get() >= 4 }>
                            "Add a variant"
                        </button>
                        <button type="button" on:click=move |_| count.update(|c| *c = (*c - 1).max(2)) disabled=move || { count.get() <= 2 }>
                            "Remove the last variant"
                        </button>
                    </div>
                    <RunProgress runner=runner.clone() />
                    <ExportPanel runs=runs specs=specs />
                    <ConfigurationFile id="cmp-config-file" load=load_configuration />
                    </Later>
                </form>
                <div class="results" class:stale=stale>
                    <StaleNotice stale=stale />
                    <Later>
                    <RunCharts runs=drawn />
                    {savings.progress()}
                    <MetricsTable runs=runs />
                    </Later>
                </div>
            </div>
        </PageShell>
    }
}
