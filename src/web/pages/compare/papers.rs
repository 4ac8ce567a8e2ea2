//! The papers' comparisons, one click away: each sets the scenario and the variants, and states
//! the paper's claim beside what the lab measures once its runs are shown.

use leptos::prelude::*;

use crate::closed_loop::lab::RunResult;
use crate::closed_loop::paper_comparisons::PAPER_COMPARISONS;
use crate::web::components::run_form::{ControllerForm, ScenarioForm};
use crate::web::components::run_view::NamedRun;

/// The comparisons' buttons and the chosen one's finding.
#[component]
pub fn PaperComparisons(
    scenario: ScenarioForm,
    forms: [ControllerForm; 4],
    /// How many variants the page shows.
    count: RwSignal<usize>,
    /// The runs shown.
    #[prop(into)]
    runs: Signal<Vec<NamedRun>>,
) -> impl IntoView {
    // The paper comparison last chosen: its claim, and what its runs measure once they are done.
    let chosen = RwSignal::new(None::<usize>);
    // The claim at once; the measured finding when the runs shown are the comparison's (an edit
    // that changes the controllers or the preset leaves the claim alone).
    let finding = move || {
        let comparison = &PAPER_COMPARISONS[chosen.get()?];
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
    view! {
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
                                    chosen.set(Some(index));
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
    }
}
