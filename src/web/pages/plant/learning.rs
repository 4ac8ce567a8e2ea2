//! Paper 004's network learned on the preset's machine: its program cut at fixed feeds in a
//! worker, each section of constant depth a trial cut; the learned exponents beside the
//! published and mechanistic ones, and each cut's residual — what `cutlab learn` prints.

use std::sync::Arc;

use leptos::prelude::*;

use crate::closed_loop::transfer::{JobRequest, LearningRequest};
use crate::closed_loop::trial_cuts::{PresetLearning, DEFAULT_TRIAL_FEEDS_PCT};
use crate::plant::presets::PlantKind;
use crate::plant::Preset;
use crate::web::components::page::TableScroll;
use crate::web::components::paper_link::WithPaperLinks;
use crate::web::components::pool::Answer;
use crate::web::components::runner::{RunProgress, Runner};

/// An exponent with its uncertainty, as the tables show it.
fn exponent(value: f64, uncertainty: f64) -> String {
    format!("{value:.2} ± {uncertainty:.2}")
}

/// The learned exponents beside the published and the mechanistic model's.
fn exponents_table(learning: &PresetLearning) -> impl IntoView {
    let rows = learning
        .from_force
        .learned
        .iter()
        .zip(&learning.from_estimate.learned)
        .map(|(force, estimate)| {
            let mechanistic = learning
                .mechanistic
                .iter()
                .find(|(input, _, _)| *input == force.input)
                .map_or("—".to_string(), |&(_, lo, hi)| {
                    if (hi - lo).abs() < 0.005 {
                        format!("{lo:.2}")
                    } else {
                        format!("{lo:.2}–{hi:.2}")
                    }
                });
            view! {
                <tr>
                    <th scope="row">{force.input.symbol()}</th>
                    <td>{exponent(force.exponent, force.uncertainty)}</td>
                    <td>{exponent(estimate.exponent, estimate.uncertainty)}</td>
                    <td>{format!("{:.2}", force.published)}</td>
                    <td>{mechanistic}</td>
                </tr>
            }
        })
        .collect_view();
    let held = learning
        .from_force
        .held
        .iter()
        .map(|(input, w)| format!("{} {w:.2}", input.symbol()))
        .collect::<Vec<_>>()
        .join(", ");
    view! {
        <table class="metrics">
            <caption>"Learned exponents (± two standard errors)"</caption>
            <thead>
                <tr>
                    <th scope="col">"Input"</th>
                    <th scope="col">"From the force"</th>
                    <th scope="col">"From the estimate"</th>
                    <th scope="col">"Published"</th>
                    <th scope="col">"Mechanistic"</th>
                </tr>
            </thead>
            <tbody>{rows}</tbody>
        </table>
        <p class="hint">
            {format!(
                "Held at the published exponents (they do not vary over the cuts): {held}. Bias {:.1} N \
                 from the force, {:.1} N from the estimate; residual RMS {:.2} % and {:.2} %.",
                learning.from_force.bias_n,
                learning.from_estimate.bias_n,
                100.0 * learning.from_force.residual_rms_log,
                100.0 * learning.from_estimate.residual_rms_log,
            )}
        </p>
    }
}

/// Each trial cut with both forces and both fits' residuals.
fn residuals_table(learning: &PresetLearning) -> impl IntoView {
    let residual =
        |fit: &[f64], k: usize| fit.get(k).map_or("—".to_string(), |r| format!("{r:+.2}"));
    let rows = learning
        .cuts
        .iter()
        .enumerate()
        .map(|(k, cut)| {
            view! {
                <tr>
                    <th scope="row">{k + 1}</th>
                    <td>{format!("{:.2}", cut.radial_width_mm)}</td>
                    <td>{format!("{:.4}", cut.feed_per_tooth_mm)}</td>
                    <td>{format!("{:.2}", cut.axial_depth_mm)}</td>
                    <td>{format!("{:.1}", cut.force_n)}</td>
                    <td>{format!("{:.1}", cut.estimate_n)}</td>
                    <td>{residual(&learning.from_force.residuals_pct, k)}</td>
                    <td>{residual(&learning.from_estimate.residuals_pct, k)}</td>
                </tr>
            }
        })
        .collect_view();
    view! {
        <TableScroll label="Trial cuts and residuals".to_string()>
            <table class="metrics">
                <caption>"Trial cuts and residuals"</caption>
                <thead>
                    <tr>
                        <th scope="col">"Cut"</th>
                        <th scope="col">"a_e (mm)"</th>
                        <th scope="col">"f (mm)"</th>
                        <th scope="col">"a_p (mm)"</th>
                        <th scope="col">"Force (N)"</th>
                        <th scope="col">"Estimate (N)"</th>
                        <th scope="col">"Residual, force fit (%)"</th>
                        <th scope="col">"Residual, estimate fit (%)"</th>
                    </tr>
                </thead>
                <tbody>{rows}</tbody>
            </table>
        </TableScroll>
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
                    view! {
                        {exponents_table(&learning)}
                        {residuals_table(&learning)}
                    }
                })
            }}
        </section>
    }
}
