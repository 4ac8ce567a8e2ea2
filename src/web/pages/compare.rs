//! Compare: one scenario, two to four controller variants, overlaid and side by side.

use std::sync::Arc;
use std::time::Duration;

use leptos::prelude::*;

use crate::closed_loop::definition::RunSetting;
use crate::closed_loop::lab::{LabRuns, RunResult, RunSpec, TeachKey};
use crate::closed_loop::metrics::metrics_csv_columns;
use crate::closed_loop::runner::Calibration;
use crate::closed_loop::trace::write_csv_runs;
use crate::control::registry::ControllerKind;
use crate::plant::Preset;
use crate::web::components::download::{download_configuration, download_text, download_written};
use crate::web::components::run_form::{
    ControllerFields, ControllerForm, MachineAndSignalFields, ScenarioFields, ScenarioForm,
};
use crate::web::components::run_view::{MetricsTable, NamedRun, RunCharts};
use crate::web::components::runner::{Debounce, RunProgress, Runner};
use crate::web::components::savings::Savings;
use crate::web::route::{query_params, replace_query, Page};

/// Wait after the last edit before re-running (a new run cancels the one under way).
const RERUN_DELAY: Duration = Duration::from_millis(40);

/// Teach cuts whose calibrations the page keeps, so an edit of a controller re-runs only loops.
const KEPT_CALIBRATIONS: usize = 4;

/// The runs so far while a comparison advances (the one under way up to now).
fn runs_so_far(runs: &LabRuns) -> Option<Vec<Arc<RunResult>>> {
    Some(runs.partial()).filter(|r| !r.is_empty())
}
const VARIANT_PREFIXES: [&str; 4] = ["a.", "b.", "c.", "d."];
const VARIANT_NAMES: [&str; 4] = ["A", "B", "C", "D"];

/// A comparison the papers make, one click away, with what the paper claims and what the lab
/// shows (docs/papers.md has the figures).
struct PaperComparison {
    label: &'static str,
    preset: Preset,
    controllers: &'static [ControllerKind],
    /// Settings other than the preset's, as typed in the form.
    settings: &'static [(RunSetting, &'static str)],
    finding: &'static str,
}

const PAPER_COMPARISONS: [PaperComparison; 7] = [
    PaperComparison {
        label: "Paper 003: fixed feed vs threshold control over DOC steps",
        preset: Preset::KimStepDoc,
        controllers: &[ControllerKind::Fixed, ControllerKind::Threshold],
        settings: &[],
        finding: "Paper 003 (Fig. 10): the threshold law holds the force through the depth steps \
                  that a fixed feed follows. Here too: about 6 % mean force error against 52 %.",
    },
    PaperComparison {
        label: "Paper 003: across the material change",
        preset: Preset::KimMaterialTaper,
        controllers: &[ControllerKind::Fixed, ControllerKind::Threshold],
        settings: &[],
        finding:
            "Paper 003 (Fig. 11): the controller speeds up in aluminium. Here it finishes \
                  about 48 % sooner than the fastest fixed feed that keeps the steel at the target.",
    },
    PaperComparison {
        label: "Paper 002: experience-based vs dynamics-based fuzzy rules",
        preset: Preset::LiuCurrentStep,
        controllers: &[
            ControllerKind::FuzzyExperience,
            ControllerKind::FuzzyDynamics,
        ],
        settings: &[],
        finding: "Paper 002 (Fig. 7) says the dynamics-based rules settle sooner after the load \
                  step and fluctuate less. At the paper's own 50 ms sampling and k_u the two \
                  tables settle alike here (about 1.1 s to ±2 %): the claim is not reproduced. \
                  The next comparison samples ten times more slowly, where it is.",
    },
    PaperComparison {
        label: "Paper 002 at 0.5 s sampling",
        preset: Preset::LiuCurrentStep,
        controllers: &[
            ControllerKind::FuzzyExperience,
            ControllerKind::FuzzyDynamics,
        ],
        settings: &[(RunSetting::ControlPeriod, "0.5")],
        finding: "Sampled every 0.5 s, each correction is a full step and the rules away from the \
                  diagonal decide: the experience table overshoots and keeps oscillating, the \
                  dynamics table settles in about 4.5 s against 16 s — Fig. 7's difference.",
    },
    PaperComparison {
        label: "Paper 001: adaptive control at DOC 4 mm",
        preset: Preset::ManeeratDoc4,
        controllers: &[
            ControllerKind::Fixed,
            ControllerKind::Mrac,
            ControllerKind::Pi,
        ],
        settings: &[],
        finding: "Paper 001 (Fig. 9): the adaptive law converges to 320 N. Here it does within \
                  5 %, after entering the cut fast from the air (about 1 s above the limit).",
    },
    PaperComparison {
        label: "Paper 001's own model with a dynamometer",
        preset: Preset::ManeeratSecondOrder,
        controllers: &[
            ControllerKind::Fixed,
            ControllerKind::Mrac,
            ControllerKind::Pi,
        ],
        settings: &[],
        finding: "Paper 001's second-order process (eq 2.3) with the force read by a dynamometer, \
                  as in its experiments: the adaptive law holds 200 N with about 6 % mean error.",
    },
    PaperComparison {
        label: "Paper 000 vs 003: restriction vs threshold vs PI",
        preset: Preset::KimCircularTaper,
        controllers: &[
            ControllerKind::Restriction,
            ControllerKind::Threshold,
            ControllerKind::Pi,
        ],
        settings: &[],
        finding: "Paper 000's restriction steps the override one grade at a time and chatters; \
                  paper 003 made the step proportional to the excess. Compare the override \
                  changes row.",
    },
];

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
    // What the last chosen paper comparison claims and what the lab shows.
    let finding = RwSignal::new(None::<&'static str>);
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

    let calibrations = StoredValue::new(Vec::<(TeachKey, Calibration)>::new());
    let debounce = Debounce::new(RERUN_DELAY);
    let first_run = StoredValue::new(true);
    let savings_for_edits = savings.clone();
    let runner_for_effect = runner.clone();
    Effect::new(move |_| {
        let mut q = scenario.query();
        q.push(("variants".into(), count.get().to_string()));
        for (form, prefix) in forms.iter().zip(VARIANT_PREFIXES).take(count.get()) {
            q.extend(form.query(prefix));
        }
        replace_query(Page::Compare, &q);
        let Some(specs) = specs.get() else {
            return;
        };
        if let Some(first) = specs.first() {
            savings_for_edits.keep_only(first);
        }
        let runner = runner_for_effect.clone();
        let start = move || {
            let runs = LabRuns::with_calibrations(specs, calibrations.get_value());
            runner.start_previewing(runs, runs_so_far);
        };
        if first_run.get_value() {
            first_run.set_value(false);
            start();
        } else {
            debounce.request(start);
        }
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
                if let Ok(key) = TeachKey::of(&first.spec) {
                    calibrations.update_value(|known| {
                        known.retain(|(k, _)| *k != key);
                        known.push((key, first.calibration.clone()));
                        let excess = known.len().saturating_sub(KEPT_CALIBRATIONS);
                        known.drain(..excess);
                    });
                }
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
    let running = Memo::new(move |_| {
        matches!(
            status.get(),
            crate::web::components::runner::RunStatus::Running { .. }
        )
    });
    let drawn = Signal::derive(move || match preview.get() {
        Some(so_far) if running.get() => named(so_far),
        _ => runs.get(),
    });

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
                    <fieldset>
                        <legend>"The papers' comparisons"</legend>
                        <div class="preset-row">
                            {PAPER_COMPARISONS
                                .iter()
                                .map(|c| {
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
                                                finding.set(Some(c.finding));
                                            }
                                        >
                                            {c.label}
                                        </button>
                                    }
                                })
                                .collect_view()}
                        </div>
                        <p class="finding" role="status">{move || finding.get()}</p>
                    </fieldset>
                    <ScenarioFields form=scenario />
                    {move || {
                        (0..count.get())
                            .map(|i| {
                                let legend = ["Variant A", "Variant B", "Variant C", "Variant D"][i];
                                view! { <ControllerFields form=forms[i] legend=legend /> }
                            })
                            .collect_view()
                    }}
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
                </form>
                <div class="results">
                    <RunCharts runs=drawn />
                    {savings.progress()}
                    <MetricsTable runs=runs />
                </div>
            </div>
        </section>
    }
}
