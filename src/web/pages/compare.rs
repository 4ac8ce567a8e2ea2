//! Compare: one scenario, two to four controller variants, overlaid and side by side.

use std::sync::Arc;
use std::time::Duration;

use leptos::prelude::*;

use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::lab::{LabRuns, RunResult};
use crate::closed_loop::metrics::metrics_csv_columns;
use crate::closed_loop::paper_comparisons::PAPER_COMPARISONS;
use crate::closed_loop::trace::write_csv_runs;
use crate::control::registry::ControllerKind;
use crate::web::components::download::{download_configuration, download_text, download_written};
use crate::web::components::later::{from_next_task, Later};
use crate::web::components::run_form::{
    ControllerFields, ControllerForm, MachineAndSignalFields, ScenarioFields, ScenarioForm,
};
use crate::web::components::run_view::{MetricsTable, NamedRun, RunCharts};
use crate::web::components::runner::{Debounce, RunProgress, RunStatus, Runner};
use crate::web::components::savings::Savings;
use crate::web::components::teach_cuts::KeptCalibrations;
use crate::web::route::{query_params, replace_query, Page};

/// Wait after an edit before re-running: none beyond the task that made it, so the events of one
/// edit start one run. A new run cancels the one before and its first chunk waits for a task of
/// its own, so typing "150" costs only the last run, and the page answers within a frame.
const RERUN_DELAY: Duration = Duration::ZERO;

/// Teach cuts whose calibrations the page keeps, so an edit of a controller re-runs only loops.
const KEPT_CALIBRATIONS: usize = 4;

/// The runs so far while a comparison advances (the one under way up to now).
fn runs_so_far(runs: &LabRuns) -> Option<Vec<Arc<RunResult>>> {
    Some(runs.partial()).filter(|r| !r.is_empty())
}
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
    // The paper comparison last chosen: its claim, and what its runs measure once they are done.
    let chosen_comparison = RwSignal::new(None::<usize>);
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
    // Both effects wait for the task after the page's: parsing the forms and writing the URL are
    // the page's own work, not its mount's.
    let mounted = from_next_task();
    let savings_for_edits = savings.clone();
    let runner_for_effect = runner.clone();
    // Keep the URL in step with the forms.
    Effect::new(move |_| {
        if !mounted.get() {
            return;
        }
        let mut q = scenario.query();
        q.push(("variants".into(), count.get().to_string()));
        for (form, prefix) in forms.iter().zip(VARIANT_PREFIXES).take(count.get()) {
            q.extend(form.query(prefix));
        }
        replace_query(Page::Compare, &q);
    });
    // Re-run when the valid specs change, and only then: `specs` is a memo, so the forms' signals
    // settling after the page mounts, or a field set to what it held, start nothing.
    Effect::new(move |_| {
        if !mounted.get() {
            return;
        }
        let Some(specs) = specs.get() else {
            return;
        };
        if let Some(first) = specs.first() {
            savings_for_edits.keep_only(first);
        }
        let runner = runner_for_effect.clone();
        let start = move || {
            let runs = LabRuns::with_calibrations(specs, calibrations.known());
            runner.start_previewing(runs, runs_so_far);
        };
        debounce.request(start);
    });

    let named = |runs: Vec<Arc<RunResult>>| {
        runs.into_iter()
            .zip(VARIANT_NAMES)
            .map(|(r, variant)| (format!("{variant}: {}", r.spec.controller.kind().name()), r))
            .collect::<Vec<NamedRun>>()
    };
    let done = runner.finished();
    let results = Memo::new(move |_| named(done.get().unwrap_or_default()));
    // Every variant shares the scenario, so one set of reference runs serves them all, on the
    // variants' teach cut.
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

    // The claim at once; the measured finding when the runs shown are the comparison's (an edit
    // that changes the controllers or the preset leaves the claim alone).
    let finding = move || {
        let comparison = &PAPER_COMPARISONS[chosen_comparison.get()?];
        let measured = runs.with(|shown| {
            let results: Vec<&RunResult> = shown.iter().map(|(_, r)| r.as_ref()).collect();
            comparison.finding(&results)
        });
        Some(match measured {
            Some(f) => format!("{} {}", comparison.claim, f.text()),
            None => format!(
                "{} (what the lab measures appears when this comparison's runs are shown)",
                comparison.claim
            ),
        })
    };

    let (export_error, set_export_error) = signal(None::<String>);
    let export_traces = move |_| {
        let shown = runs.get_untracked();
        let named: Vec<(&str, &crate::closed_loop::trace::Trace)> =
            shown.iter().map(|(n, r)| (n.as_str(), &r.trace)).collect();
        let outcome = download_written("cutlab-compare-traces.csv", "text/csv", |out| {
            write_csv_runs(&named, out)
        });
        set_export_error.set(outcome.err());
    };
    let export_metrics = move |_| {
        let shown = runs.get_untracked();
        let named: Vec<(&str, &crate::closed_loop::metrics::Metrics)> = shown
            .iter()
            .map(|(n, r)| (n.as_str(), &r.metrics))
            .collect();
        set_export_error.set(
            download_text(
                "cutlab-compare-metrics.csv",
                "text/csv",
                &metrics_csv_columns(&named),
            )
            .err(),
        );
    };
    let export_config = move |_| {
        set_export_error.set(
            specs
                .get_untracked()
                .ok_or_else(|| "fix the settings marked above first".to_string())
                .and_then(download_configuration)
                .err(),
        );
    };

    view! {
        <section class="page" aria-labelledby="compare-title">
            <h1 id="compare-title">"Compare controllers"</h1>
            <p class="lede">
                "One scenario and seed, two to four controllers or tunings. The traces are overlaid "
                "on linked time axes and the metrics table marks the best value of each row."
            </p>
            <div class="layout-two">
                <form class="panel" aria-label="Comparison settings" on:submit=|ev| ev.prevent_default()>
                    // The page mounts in pieces, a task each (the page itself with its state, the
                    // papers' comparisons and the scenario, the variants, the rest of the form, the
                    // results), so that no task of a first load takes more than 50 ms.
                    <Later>
                    <fieldset>
                        <legend>"The papers' comparisons"</legend>
                        <div class="preset-row">
                            {PAPER_COMPARISONS
                                .iter()
                                .enumerate()
                                .map(|(index, c)| {
                                    view! {
                                        <button
                                            type="button"
                                            class="preset"
                                            on:click=move |_| {
                                                scenario.reset_to(c.preset);
                                                for (setting, text) in c.settings {
                                                    scenario.text(*setting).set(text.to_string());
                                                }
                                                count.set(c.controllers.len().clamp(2, 4));
                                                for (form, kind) in forms.iter().zip(c.controllers) {
                                                    form.follow_preset(c.preset);
                                                    form.reset_to(*kind);
                                                }
                                                chosen_comparison.set(Some(index));
                                            }
                                        >
                                            {c.label}
                                        </button>
                                    }
                                })
                                .collect_view()}
                        </div>
                        <p class="finding" role="status">{finding}</p>
                    </fieldset>
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
                    <fieldset>
                        <legend>"Export"</legend>
                        <div class="button-row">
                            <button type="button" on:click=export_traces disabled=move || runs.with(Vec::is_empty)>
                                "Traces (CSV)"
                            </button>
                            <button type="button" on:click=export_metrics disabled=move || runs.with(Vec::is_empty)>
                                "Metrics (CSV)"
                            </button>
                            <button type="button" on:click=export_config disabled=move || specs.get().is_none()>
                                "Configuration (JSON)"
                            </button>
                        </div>
                        {move || export_error.get().map(|e| view! { <p class="run-error" role="alert">{e}</p> })}
                    </fieldset>
                    </Later>
                </form>
                <div class="results">
                    <Later>
                    <RunCharts runs=drawn />
                    {savings.progress()}
                    <MetricsTable runs=runs />
                    </Later>
                </div>
            </div>
        </section>
    }
}
