//! Paper 004's network learned on the preset's machine: its program cut at fixed feeds in a
//! worker, each section of constant depth a trial cut; the learned exponents beside the
//! published and mechanistic ones, and each cut's residual — what `cutlab learn` prints.

use std::sync::Arc;

use leptos::prelude::*;

use crate::closed_loop::transfer::{JobRequest, LearningRequest};
use crate::closed_loop::trial_cuts::{PresetLearning, DEFAULT_TRIAL_FEEDS_PCT};
use crate::plant::presets::PlantKind;
use crate::plant::Preset;
use crate::web::components::paper_link::WithPaperLinks;
use crate::web::components::pool::Answer;
use crate::web::components::runner::{RunProgress, Runner};

use super::learned_tables::{
    CutRow, ForceFit, LearnedExponentsTable, LearnedFrom, TrialCutResiduals,
};

/// Both tables of a preset's learning: the force on the tool and the lab's estimate of it, each
/// learned on, with the mechanistic model's exponents beside them.
fn learning_tables(learning: &PresetLearning) -> impl IntoView {
    let fits = vec![
        ForceFit {
            from: LearnedFrom::Force,
            forces_n: learning.cuts.iter().map(|c| c.force_n).collect(),
            learned: learning.from_force.clone(),
        },
        ForceFit {
            from: LearnedFrom::Estimate,
            forces_n: learning.cuts.iter().map(|c| c.estimate_n).collect(),
            learned: learning.from_estimate.clone(),
        },
    ];
    let mechanistic = learning
        .from_force
        .learned
        .iter()
        .filter_map(|e| Some((e.input, learning.mechanistic_text(e.input)?)))
        .collect::<Vec<_>>();
    let cuts = learning
        .cuts
        .iter()
        .enumerate()
        .map(|(k, cut)| CutRow {
            label: k + 1,
            radial_width_mm: cut.radial_width_mm,
            feed_per_tooth_mm: cut.feed_per_tooth_mm,
            axial_depth_mm: cut.axial_depth_mm,
        })
        .collect();
    view! {
        <LearnedExponentsTable caption="Learned exponents" fits=fits.clone() mechanistic />
        <TrialCutResiduals caption="Trial cuts and residuals" row_heading="Cut" cuts fits />
    }
}

/// The panel: a button that learns on the chosen preset, its progress, and the result.
#[component]
pub fn LearningPanel(
    /// The preset chosen on the page, by name.
    preset: RwSignal<String>,
) -> impl IntoView {
    let runner = Runner::<Arc<PresetLearning>>::new();
    let learned = runner.finished();
    let mill =
        move || Preset::from_name(&preset.get()).filter(|p| p.plant_kind() == PlantKind::Mill);
    let feeds = DEFAULT_TRIAL_FEEDS_PCT
        .iter()
        .map(|f| format!("{f:.0}"))
        .collect::<Vec<_>>()
        .join(", ");
    let runner_for_click = runner.clone();
    let learn = move |_| {
        if let Some(p) = mill() {
            runner_for_click.start_in_worker(
                JobRequest::Learning(LearningRequest {
                    preset: p,
                    feeds_pct: DEFAULT_TRIAL_FEEDS_PCT.to_vec(),
                }),
                |answer| match answer {
                    Answer::Learning(learning) => Some(Arc::new(*learning)),
                    _ => None,
                },
            );
        }
    };
    view! {
        <section class="panel" aria-labelledby="learning-title">
            <h2 id="learning-title">"Paper 004's network, learned on this machine"</h2>
            <p class="hint">
                <WithPaperLinks text=format!(
                    "The preset's program is cut at {feeds} % of its programmed feed; each section of \
                     constant depth is a trial cut. The power law's log-space weights are fitted by least \
                     squares (what paper 004's linear network reaches when trained to convergence), once on \
                     the force on the tool and once on the lab's estimate from the motor current."
                ) />
            </p>
            <button type="button" on:click=learn disabled=move || mill().is_none()>
                "Learn from trial cuts"
            </button>
            <p class="hint" hidden=move || mill().is_some()>
                "Trial cuts need a cutter: choose a mill preset."
            </p>
            <RunProgress runner=runner.clone() />
            {move || {
                // The last learning, while its preset is the one chosen.
                learned.get().filter(|l| l.preset.name() == preset.get()).map(|learning| {
                    learning_tables(&learning)
                })
            }}
        </section>
    }
}
