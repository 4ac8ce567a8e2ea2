//! Simulate: one closed loop on a preset, re-run whenever a setting changes.

use std::sync::Arc;
use std::time::Duration;

use leptos::prelude::*;

use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::lab::RunResult;
use crate::closed_loop::metrics::metrics_csv;
use crate::closed_loop::trace::write_csv;
use crate::control::registry::ControllerKind;
use crate::web::components::download::{download_configuration, download_text, download_written};
use crate::web::components::later::{effect_after_mount, now_and_after_mount, Later};
use crate::web::components::page::PageShell;
use crate::web::components::run_form::{
    ConfigurationFile, ControllerFields, ControllerForm, MachineAndSignalFields, ScenarioFields,
    ScenarioForm,
};
use crate::web::components::run_view::{
    metrics_json, EventLog, MetricsTable, NamedRun, RunCharts, StaleNotice,
};
use crate::web::components::runner::{Debounce, RunProgress, Runner};
use crate::web::components::savings::Savings;
use crate::web::components::teach_cuts::KeptCalibrations;
use crate::web::route::{hash_with_query, query_params, replace_query, Page};

/// Wait after an edit before re-running: none beyond the task that made it, so the events of one
/// edit start one run. A new run cancels the one before and its first chunk waits for a task of
/// its own, so typing "150" costs only the last run, and the page answers within a frame.
const RERUN_DELAY: Duration = Duration::ZERO;

/// Teach cuts whose calibrations the page keeps: an edit that leaves the teach cut as it was (a
/// controller parameter, the target, the envelope) re-runs only the loop.
const KEPT_CALIBRATIONS: usize = 4;

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

    let calibrations = KeptCalibrations::new(KEPT_CALIBRATIONS);
    let start_run = {
        let runner = runner.clone();
        move |spec: RunSpec| {
            let known = calibrations.known();
            // In a computation worker: the page's thread stays free while the run computes.
            runner.start_in_workers(vec![spec], known);
        }
    };

    // Keep the URL in step with the form, and re-run when a valid spec changes: the first run at
    // once, edits in the next task.
    let debounce = Debounce::first_at_once(RERUN_DELAY);
    let savings_for_edits = savings.clone();
    let start_for_effect = start_run.clone();
    effect_after_mount(move || {
        let mut q = scenario.query();
        q.extend(controller.query(""));
        replace_query(Page::Simulate, &q);
    });
    // Re-run when the valid spec changes, and only then: `spec` is a memo, so the form's signals
    // settling after the page mounts, or a field set to what it held, start nothing. The first
    // run is asked for as the page mounts.
    now_and_after_mount(spec, move |spec| {
        savings_for_edits.keep_only(&spec);
        let start = start_for_effect.clone();
        debounce.request(move || start(spec));
    });

    // The last finished run stays on screen while the next one computes (its charts fill in as
    // it advances); its savings fill in when the reference runs of its scenario are done.
    let done = runner.finished();
    let finished = Memo::new(move |_| done.get().and_then(|mut runs| runs.pop()));
    savings.request_while_running(&runner);
    let savings_for_effect = savings.clone();
    Effect::new(move |_| {
        if let Some(r) = finished.get() {
            calibrations.remember(&r.spec, &r.calibration);
            savings_for_effect.request(&r.spec, Some(&r.calibration));
        }
    });
    let savings_for_result = savings.clone();
    let result = Memo::new(move |_| finished.get().map(|r| savings_for_result.apply(r)));
    let name_of = |r: Arc<RunResult>| (r.spec.controller.kind().label().to_string(), r) as NamedRun;
    let runs = Signal::derive(move || result.get().map(name_of).into_iter().collect::<Vec<_>>());
    // The charts draw the run under way as it advances, then the finished run with its savings.
    let preview = runner.preview;
    let drawn = Signal::derive(move || {
        let running = preview.get().and_then(|mut runs| runs.pop());
        match (running, result.get()) {
            // The run that just finished: shown with its savings.
            (Some(r), Some(done)) if r.spec == done.spec && r.trace == done.trace => {
                vec![name_of(done)]
            }
            (Some(r), _) => vec![name_of(r)],
            (None, done) => done.map(name_of).into_iter().collect(),
        }
    });
    let (before, drawn_before) = run_before(result, preview, scenario);
    // Results from settings the form no longer holds (a field that does not validate).
    let stale = Signal::derive(move || spec.with(Option::is_none) && result.with(Option::is_some));
    let compare_href = move || compare_href(scenario, controller);
    // A saved configuration's first run into the forms (Compare shows every run of a file).
    let load_configuration = Callback::new(
        move |config: crate::closed_loop::config::RunConfiguration| {
            let Some(first) = config.runs.first() else {
                return Err("the file holds no run".to_string());
            };
            scenario.load(first);
            controller.load(&first.controller, first.preset);
            Ok(())
        },
    );
    let run_now = move |_| {
        if let Some(s) = spec.get_untracked() {
            start_run(s);
        }
    };

    view! {
        <PageShell id="simulate" title="Simulate a closed loop">
            <p class="lede">
                "Pick one of the papers' experiments and a controller. A teach cut first calibrates "
                "the current-to-force model; then the controller holds the force through the "
                "safety envelope while the simulated machine cuts. Every change re-runs."
            </p>
            <div class="layout-two">
                <form class="panel" aria-label="Run settings" on:submit=|ev| ev.prevent_default()>
                    <Later>
                    <ScenarioFields form=scenario />
                    <ControllerFields form=controller />
                    </Later>
                    <Later>
                    <MachineAndSignalFields form=scenario />
                    <div class="button-row">
                        <button type="button" class="primary" on:click=run_now.clone()>"Run"</button>
                        <a class="button-link" href=compare_href>"Open in Compare"</a>
                    </div>
                    <ConfigurationFile id="sim-config-file" load=load_configuration />
                    <RunProgress runner=runner.clone() />
                    <SimulateExport result=result spec=spec />
                    </Later>
                </form>
                <div class="results" class:stale=stale>
                    <StaleNotice stale=stale />
                    <Later>
                    <RunCharts runs=drawn before=drawn_before />
                    {savings.progress()}
                    <MetricsTable runs=runs before=before />
                    <EventLog run=Signal::derive(move || result.get()) />
                    </Later>
                </div>
            </div>
        </PageShell>
    }
}

/// The export buttons: the trace and metrics of the run shown, the configuration of the form.
#[component]
fn SimulateExport(
    /// The finished run shown, with its savings.
    result: Memo<Option<Arc<RunResult>>>,
    /// The run the form defines, if it parses.
    spec: Memo<Option<RunSpec>>,
) -> impl IntoView {
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
    view! {
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
    }
}

/// A run shown on the page, if any.
type ShownRun = Option<Arc<RunResult>>;

/// The run before the one shown, for the "Before" column, and the run to draw faint (the one
/// shown while the next streams in): the last run shown whose settings differ from the current
/// one's (the same run arriving again with its savings, or re-run as it was, keeps it). Only
/// within one preset: another scenario has another program, target and length, so its trace
/// beside this one would compare two experiments, not show what an edit did.
fn run_before(
    result: Memo<ShownRun>,
    preview: RwSignal<Option<Vec<Arc<RunResult>>>>,
    scenario: ScenarioForm,
) -> (RwSignal<ShownRun>, Signal<ShownRun>) {
    let shown_run = StoredValue::new(None::<Arc<RunResult>>);
    let before = RwSignal::new(None::<Arc<RunResult>>);
    Effect::new(move |_| {
        let Some(now) = result.get() else {
            return;
        };
        match shown_run.get_value() {
            Some(last) if last.spec == now.spec => {}
            Some(last) if last.spec.preset == now.spec.preset => before.set(Some(last)),
            _ => before.set(None),
        }
        shown_run.set_value(Some(now));
    });
    Effect::new(move |_| {
        let preset = scenario.chosen_preset();
        if before.with_untracked(|b| b.as_ref().is_some_and(|b| Some(b.spec.preset) != preset)) {
            before.set(None);
        }
    });
    // While a new run streams in, the run it replaces is the faint one.
    let drawn = Signal::derive(move || {
        let running = preview.with(|p| {
            p.as_ref()
                .and_then(|runs| runs.last().map(|r| r.spec.clone()))
        });
        match (running, result.get()) {
            (Some(spec), Some(done)) if spec != done.spec => {
                (spec.preset == done.spec.preset).then_some(done)
            }
            _ => before.get(),
        }
    });
    (before, drawn)
}

/// The same run definition in Compare, through the forms' own URL form: variant B as edited
/// here, beside variant A, the same controller at its defaults (built-in rule table), or the
/// fixed feed when nothing was edited.
fn compare_href(scenario: ScenarioForm, controller: ControllerForm) -> String {
    let mut q = scenario.query();
    let edited = controller.query("b.");
    let baseline = if edited.len() > 1 {
        controller.kind.get()
    } else {
        ControllerKind::Fixed.name().to_string()
    };
    q.push(("variants".into(), "2".into()));
    q.push(("a.controller".into(), baseline));
    q.extend(edited);
    hash_with_query(Page::Compare, &q)
}
