//! Simulate: one closed loop on a preset, re-run whenever a setting changes.

use std::sync::Arc;
use std::time::Duration;

use leptos::prelude::*;

use crate::closed_loop::lab::LabRuns;
use crate::closed_loop::lab::{RunResult, RunSpec};
use crate::closed_loop::metrics::metrics_csv;
use crate::closed_loop::trace::write_csv;
use crate::control::registry::ControllerKind;
use crate::web::components::download::{download_configuration, download_text, download_written};
use crate::web::components::run_form::{
    ControllerFields, ControllerForm, MachineAndSignalFields, ScenarioFields, ScenarioForm,
};
use crate::web::components::run_view::{metrics_json, EventLog, MetricsTable, NamedRun, RunCharts};
use crate::web::components::runner::{Debounce, RunProgress, Runner};
use crate::web::components::savings::Savings;
use crate::web::route::{query_params, replace_query, Page};

/// Wait after the last edit before re-running, so typing "150" does not start three runs.
const RERUN_DELAY: Duration = Duration::from_millis(350);

/// The Simulate page.
#[component]
pub fn SimulatePage() -> impl IntoView {
    let query = query_params(&window().location().hash().unwrap_or_default());
    let scenario = ScenarioForm::new(&query);
    let controller = ControllerForm::new(
        "sim-",
        ControllerKind::Threshold,
        scenario.chosen_preset_untracked(),
        &query,
        "",
    );
    // Untouched controller parameters follow the preset (a paper's own values on its preset).
    Effect::new(move |_| {
        if let Some(preset) = scenario.chosen_preset() {
            controller.follow_preset(preset);
        }
    });
    let runner = Runner::<Vec<Arc<RunResult>>>::new();
    let savings = Savings::new();

    let spec = Memo::new(move |_| {
        let s = scenario.parse().ok()?;
        let c = controller.parse().ok()?;
        Some(RunSpec {
            preset: s.preset,
            controller: c,
            seed: s.seed,
            settings: s.settings,
            plant: s.plant,
        })
    });

    // Keep the URL in step with the form, and re-run (debounced) when a valid spec changes.
    let debounce = Debounce::new(RERUN_DELAY);
    let savings_for_edits = savings.clone();
    let runner_for_effect = runner.clone();
    Effect::new(move |_| {
        let mut q = scenario.query();
        q.extend(controller.query(""));
        replace_query(Page::Simulate, &q);
        let Some(spec) = spec.get() else {
            return;
        };
        savings_for_edits.keep_only(&spec);
        let runner = runner_for_effect.clone();
        debounce.request(move || runner.start(LabRuns::new(vec![spec])));
    });

    // The last finished run stays on screen while the next one computes; its savings fill in
    // when the reference runs of its scenario are done.
    let done = runner.finished();
    let finished = Memo::new(move |_| done.get().and_then(|mut runs| runs.pop()));
    let savings_for_effect = savings.clone();
    Effect::new(move |_| {
        if let Some(r) = finished.get() {
            savings_for_effect.request(&r.spec);
        }
    });
    let savings_for_result = savings.clone();
    let result = Memo::new(move |_| finished.get().map(|r| savings_for_result.apply(r)));
    let runs = Signal::derive(move || {
        result
            .get()
            .map(|r| vec![(r.spec.controller.kind().label().to_string(), r) as NamedRun])
            .unwrap_or_default()
    });
    let (export_error, set_export_error) = signal(None::<String>);
    let export_csv = move |_| {
        if let Some(r) = result.get_untracked() {
            let outcome = download_written("cutlab-trace.csv", "text/csv", |out| {
                write_csv(&r.trace, out)
            });
            set_export_error.set(outcome.err());
        }
    };
    let export_metrics = move |_| {
        if let Some(r) = result.get_untracked() {
            set_export_error.set(
                download_text(
                    "cutlab-metrics.json",
                    "application/json",
                    &metrics_json(&r.metrics),
                )
                .err(),
            );
        }
    };
    let export_metrics_csv = move |_| {
        if let Some(r) = result.get_untracked() {
            set_export_error.set(
                download_text("cutlab-metrics.csv", "text/csv", &metrics_csv(&r.metrics)).err(),
            );
        }
    };
    let export_config = move |_| {
        set_export_error.set(
            spec.get_untracked()
                .ok_or_else(|| "fix the settings marked above first".to_string())
                .and_then(|s| download_configuration(vec![s]))
                .err(),
        );
    };
    let runner_for_button = runner.clone();
    let run_now = move |_| {
        if let Some(s) = spec.get_untracked() {
            runner_for_button.start(LabRuns::new(vec![s]));
        }
    };

    view! {
        <section class="page" aria-labelledby="simulate-title">
            <h1 id="simulate-title">"Simulate a closed loop"</h1>
            <p class="lede">
                "Pick one of the papers' experiments and a controller. A teach cut first calibrates "
                "the current-to-force model; then the controller holds the force through the "
                "safety envelope while the simulated machine cuts. Every change re-runs."
            </p>
            <div class="layout-two">
                <form class="panel" aria-label="Run settings" on:submit=|ev| ev.prevent_default()>
                    <ScenarioFields form=scenario />
                    <ControllerFields form=controller />
                    <MachineAndSignalFields form=scenario />
                    <div class="button-row">
                        <button type="button" class="primary" on:click=run_now>"Run"</button>
                    </div>
                    <RunProgress runner=runner.clone() />
                    <fieldset>
                        <legend>"Export"</legend>
                        <div class="button-row">
                            <button type="button" on:click=export_csv disabled=move || result.get().is_none()>
                                "Trace (CSV)"
                            </button>
                            <button type="button" on:click=export_metrics_csv disabled=move || result.get().is_none()>
                                "Metrics (CSV)"
                            </button>
                            <button type="button" on:click=export_metrics disabled=move || result.get().is_none()>
                                "Metrics (JSON)"
                            </button>
                            <button type="button" on:click=export_config disabled=move || spec.get().is_none()>
                                "Configuration (JSON)"
                            </button>
                        </div>
                        {move || export_error.get().map(|e| view! { <p class="run-error" role="alert">{e}</p> })}
                    </fieldset>
                </form>
                <div class="results">
                    <RunCharts runs=runs />
                    {savings.progress()}
                    <MetricsTable runs=runs />
                    <EventLog run=Signal::derive(move || result.get()) />
                </div>
            </div>
        </section>
    }
}
