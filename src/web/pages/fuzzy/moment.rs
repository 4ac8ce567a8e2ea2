//! A moment of a simulated run with the table: the run (computed in a worker of the pool,
//! [`crate::web::components::pool`], so the page stays free while it runs), and a slider whose
//! moment's E and EC the viewer shows.

use std::sync::Arc;

use leptos::prelude::*;

use super::Fuzzy;
use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::lab::RunResult;
use crate::closed_loop::paper_defaults::preset_controller;
use crate::control::registry::ControllerKind;
use crate::plant::Preset;
use crate::web::components::fields::SelectField;
use crate::web::components::runner::{RunProgress, Runner};

/// The run a moment is picked from, shared with the charts.
#[derive(Clone)]
pub struct RunMoment {
    /// Runs it.
    pub runner: Runner<Vec<Arc<RunResult>>>,
    /// Its result, once done.
    pub result: Memo<Option<Arc<RunResult>>>,
    /// The control period picked.
    pub moment: RwSignal<usize>,
}

impl RunMoment {
    /// No run yet; the picked moment's E and EC go to `fuzzy`'s viewer.
    pub fn new(fuzzy: Fuzzy) -> Self {
        let runner = Runner::<Vec<Arc<RunResult>>>::new();
        let done = runner.finished();
        let result = Memo::new(move |_| done.get().and_then(|mut runs| runs.pop()));
        let moment = RwSignal::new(0usize);
        Effect::new(move |_| {
            let index = moment.get();
            result.with(|r| {
                if let Some(r) = r {
                    let width = r.trace.term_names.len();
                    let e = r.trace.terms.get(index * width).copied();
                    let ec = r.trace.terms.get(index * width + 1).copied();
                    // A held period (no force) has no inputs to show: the viewer keeps its point.
                    if let (Some(e), Some(ec)) =
                        (e.filter(|v| v.is_finite()), ec.filter(|v| v.is_finite()))
                    {
                        fuzzy.e_text.set(format!("{e:.3}"));
                        fuzzy.ec_text.set(format!("{ec:.3}"));
                    }
                }
            });
        });
        Self {
            runner,
            result,
            moment,
        }
    }
}

/// The run's fieldset: its preset, the run, the moment's slider.
#[component]
pub fn RunMomentPanel(fuzzy: Fuzzy, run: RunMoment) -> impl IntoView {
    let run_preset = RwSignal::new(Preset::LiuCurrentStep.name().to_string());
    let RunMoment {
        runner,
        result,
        moment,
    } = run;
    let runner_for_button = runner.clone();
    let start_run = move |_| {
        let Some(preset) = Preset::from_name(&run_preset.get_untracked()) else {
            return;
        };
        let mut controller = preset_controller(preset, ControllerKind::FuzzyDynamics);
        if controller
            .set_rule_table(fuzzy.table.get_untracked())
            .is_err()
        {
            return;
        }
        let spec = RunSpec {
            preset,
            controller,
            seed: 1,
            settings: Default::default(),
            plant: Default::default(),
        };
        runner_for_button.start_in_workers(vec![spec], Vec::new());
    };
    view! {
        <fieldset>
            <legend>"A moment of a simulated run"</legend>
            <SelectField
                id="fuzzy-run-preset"
                label="Preset"
                options=Preset::ALL.iter().map(|p| (p.name(), p.label())).collect()
                value=run_preset
            />
            <p class="hint">
                "The run uses the fuzzy controller with this table and paper 002's "
                "weighted-average defuzzification, whatever the viewer's choice."
            </p>
            <div class="button-row">
                <button type="button" on:click=start_run>"Run with this table"</button>
            </div>
            <RunProgress runner=runner />
            {move || {
                result
                    .get()
                    .map(|r| {
                        let last = r.trace.rows.len().saturating_sub(1);
                        view! {
                            <div class="field">
                                <label for="moment">
                                    {move || {
                                        let t = result
                                            .with(|r| r.as_ref().and_then(|r| r.trace.rows.get(moment.get()).map(|row| row.time_s)))
                                            .unwrap_or(0.0);
                                        format!("Moment: {t:.2} s")
                                    }}
                                </label>
                                <input
                                    id="moment"
                                    type="range"
                                    min="0"
                                    max=last.to_string()
                                    prop:value=move || moment.get().to_string()
                                    on:input=move |ev| {
                                        if let Ok(i) = event_target_value(&ev).parse::<usize>() {
                                            moment.set(i.min(last));
                                        }
                                    }
                                />
                            </div>
                        }
                    })
            }}
        </fieldset>
    }
}
