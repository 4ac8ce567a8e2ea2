//! The lesson beside the lab: the open step's task, its hints one at a time, and its check —
//! a multiple-choice answer checked here, the runs the lab's page finishes or the Logs page's
//! replays (each condition met or not, with the measured value), or the Signal chain page's
//! filter, checked on request.
//! A step whose check is met is saved as done; the panel says "Step done" only while the work
//! shown meets the check ([`StepStatus`]).

use std::sync::Arc;

use leptos::prelude::*;

use super::{feed, open_step, store};
use crate::closed_loop::lab::RunResult;
use crate::lessons::check::{ConditionOutcome, Evidence};
use crate::lessons::progress::StepStatus;
use crate::lessons::setup::{Defined, LabPage, Setup};
use crate::lessons::shipped::shipped_lesson;
use crate::lessons::{Lesson, StepCheck};
use crate::log::replay::ReplayResult;

/// The open lesson's panel, or nothing when no lesson is open.
#[component]
pub fn LessonPanel() -> impl IntoView {
    let progress = store::progress();
    let open = Memo::new(move |_| progress.with(|p| p.open.clone()));
    move || {
        open.get()
            .and_then(|id| shipped_lesson(&id))
            .map(|lesson| view! { <LessonView lesson=Arc::new(lesson) /> })
    }
}

#[component]
fn LessonView(lesson: Arc<Lesson>) -> impl IntoView {
    let progress = store::progress();
    let id = lesson.id.clone();
    let step = Memo::new(move |_| progress.with(|p| p.of(&id).step));
    let close = move |_| store::update(|p| p.open = None);
    let title = lesson.title.clone();
    let paper = lesson.paper.clone();
    // Below 1100 px the panel is a bar at the bottom of the window (www/lessons.css), which the
    // student can shrink to the step, its task and its check while editing the page above.
    let minimised = RwSignal::new(false);
    view! {
        <aside class="lesson-panel" class:minimised=move || minimised.get()
            aria-labelledby="lesson-panel-title">
            <div class="lesson-bar">
                <p class="lesson-kicker">"Lesson · paper " {paper}</p>
                <button type="button" class="lesson-toggle"
                    aria-expanded=move || (!minimised.get()).to_string()
                    on:click=move |_| minimised.update(|m| *m = !*m)>
                    {move || if minimised.get() { "Show the whole lesson" } else { "Shrink the lesson" }}
                </button>
            </div>
            <h2 id="lesson-panel-title">{title}</h2>
            {move || {
                let index = step.get();
                view! { <StepView lesson=lesson.clone() index=index /> }
            }}
            <div class="button-row lesson-detail">
                <a href="#/lessons">"All lessons"</a>
                <button type="button" on:click=close>"Close the lesson"</button>
            </div>
        </aside>
    }
}

/// The outcome of a check shown in the panel.
#[derive(Debug, Clone, PartialEq)]
enum Checked {
    /// Nothing checked yet.
    Waiting,
    /// The conditions evaluated.
    Conditions(Vec<ConditionOutcome>),
    /// The multiple-choice answer given, and whether it is right.
    Answer(bool),
    /// The work could not be checked; why.
    Problem(String),
}

#[component]
fn StepView(lesson: Arc<Lesson>, index: usize) -> impl IntoView {
    let Some(step) = lesson.steps.get(index).cloned() else {
        return view! { <p>"This lesson has no such step."</p> }.into_any();
    };
    let count = lesson.steps.len();
    let progress = store::progress();
    let id = lesson.id.clone();
    let done = Memo::new(move |_| progress.with(|p| p.of(&id).done.contains(&index)));
    let checked = RwSignal::new(Checked::Waiting);
    let mark_done = {
        let id = lesson.id.clone();
        move || store::update(|p| p.mark_done(&id, index))
    };

    // Runs (or the Logs page's replays) the page finishes after the step opened are checked as
    // they arrive.
    if let StepCheck::Conditions { conditions, .. } = &step.check {
        if step.setup.page.runs() || step.setup.page == LabPage::Logs {
            let opened_after = feed::last_serial();
            let finished = feed::finished();
            let conditions = conditions.clone();
            let slug = step.setup.page.slug();
            let mark_done = mark_done.clone();
            Effect::new(move |_| {
                let Some(runs) = finished.get() else { return };
                if runs.serial <= opened_after || runs.page != slug {
                    return;
                }
                let refs: Vec<&RunResult> = runs.runs.iter().map(Arc::as_ref).collect();
                let replays: Vec<&ReplayResult> = runs.replays.iter().map(Arc::as_ref).collect();
                let evidence = if slug == LabPage::Logs.slug() {
                    Evidence::Replays(&replays)
                } else {
                    Evidence::Runs(&refs)
                };
                let outcomes: Vec<ConditionOutcome> =
                    conditions.iter().map(|c| c.evaluate(evidence)).collect();
                if outcomes.iter().all(|o| o.met) {
                    mark_done();
                }
                checked.set(Checked::Conditions(outcomes));
            });
        }
    }

    let hints = step.hints.clone();
    let hint_count = hints.len();
    let hints_shown = RwSignal::new(0usize);
    let setup_link = step.setup.link();
    let set_up = move |_| {
        let _ = window().location().set_hash(&setup_link);
    };
    let (previous, next) = (lesson.clone(), lesson.clone());
    let check_view = match step.check.clone() {
        StepCheck::Choice { choices, answer } => {
            let chosen = RwSignal::new(None::<usize>);
            let mark_done = mark_done.clone();
            let name = format!("lesson-{}-step-{index}", lesson.id);
            let options = choices
                .into_iter()
                .enumerate()
                .map(|(i, text)| {
                    let input_id = format!("{name}-{i}");
                    view! {
                        <div class="lesson-choice">
                            <input type="radio" id=input_id.clone() name=name.clone()
                                on:change=move |_| chosen.set(Some(i)) />
                            <label for=input_id>{text}</label>
                        </div>
                    }
                })
                .collect_view();
            let check = move |_| match chosen.get_untracked() {
                Some(i) => {
                    if i == answer {
                        mark_done();
                    }
                    checked.set(Checked::Answer(i == answer));
                }
                None => checked.set(Checked::Problem("choose an answer first".into())),
            };
            view! {
                <fieldset class="lesson-choices">
                    <legend>"Your answer"</legend>
                    {options}
                </fieldset>
                <button type="button" on:click=check>"Check my answer"</button>
            }
            .into_any()
        }
        StepCheck::Conditions { conditions, .. } if step.setup.page == LabPage::SignalChain => {
            let mark_done = mark_done.clone();
            let check = move |_| {
                let hash = window().location().hash().unwrap_or_default();
                let outcome = Setup::from_link(&hash).and_then(|setup| {
                    if setup.page != LabPage::SignalChain {
                        return Err("open the Signal chain page (\u{201c}Set up this step\u{201d}) and design the filter there".to_string());
                    }
                    match setup.define()? {
                        Defined::Design(spec, sos) => Ok(conditions
                            .iter()
                            .map(|c| c.evaluate(Evidence::Design { spec: &spec, sos: &sos }))
                            .collect::<Vec<_>>()),
                        _ => Err("the Signal chain page holds no filter".to_string()),
                    }
                });
                match outcome {
                    Ok(outcomes) => {
                        if outcomes.iter().all(|o| o.met) {
                            mark_done();
                        }
                        checked.set(Checked::Conditions(outcomes));
                    }
                    Err(e) => checked.set(Checked::Problem(e)),
                }
            };
            view! { <button type="button" on:click=check>"Check my filter"</button> }.into_any()
        }
        StepCheck::Conditions { .. } => view! {
            <p class="hint">
                {if step.setup.page == LabPage::Logs { "Each replay" } else { "Each run" }}
                " you finish on the " {page_name(step.setup.page)} " page is checked here."
            </p>
        }
        .into_any(),
    };
    let explain = step.explain.clone();
    let work = match (&step.check, step.setup.page) {
        (StepCheck::Choice { .. }, _) => "answer",
        (_, LabPage::SignalChain) => "filter",
        (_, LabPage::Logs) => "replay",
        _ => "run",
    };
    view! {
        <h3>"Step " {index + 1} " of " {count} ": " {step.title.clone()}</h3>
        <p class="lesson-task">{step.task.clone()}</p>
        <div class="lesson-detail">
        {(hint_count > 0).then(|| view! {
            <ol class="lesson-hints">
                {move || hints.iter().take(hints_shown.get()).map(|h| view! { <li>{h.clone()}</li> }).collect_view()}
            </ol>
            <button type="button" disabled={move || hints_shown.get() >= hint_count}
                on:click=move |_| hints_shown.update(|n| *n = (*n + 1).min(hint_count))>
                {move || format!("Show a hint ({} of {hint_count} shown)", hints_shown.get())}
            </button>
        })}
        {check_view}
        </div>
        <div class="lesson-check" aria-live="polite">
            {move || match checked.get() {
                Checked::Waiting => None,
                Checked::Answer(true) => Some(view! { <p class="met">"Right."</p> }.into_any()),
                Checked::Answer(false) => Some(view! { <p class="unmet">"Not this one: read the hints and try again."</p> }.into_any()),
                Checked::Problem(e) => Some(view! { <p class="unmet">{e}</p> }.into_any()),
                Checked::Conditions(outcomes) => Some(view! {
                    <ul class="lesson-outcomes" aria-label="Check of your run">
                        {outcomes.into_iter().map(|o| {
                            let (class, word) = if o.met { ("met", "Met") } else { ("unmet", "Not met") };
                            view! {
                                <li class=class>
                                    <strong>{word}": "</strong>{o.wants}" — measured "{o.measured}
                                </li>
                            }
                        }).collect_view()}
                    </ul>
                }.into_any()),
            }}
            {move || {
                let met_now = match &*checked.read() {
                    Checked::Waiting | Checked::Problem(_) => None,
                    Checked::Answer(right) => Some(*right),
                    Checked::Conditions(outcomes) => Some(outcomes.iter().all(|o| o.met)),
                };
                let status = StepStatus::of(done.get(), met_now);
                status.words(work).map(|words| {
                    let class = if status.explains() { "lesson-done" } else { "lesson-done unmet" };
                    let explain = status.explains().then(|| format!(" {explain}"));
                    view! { <p class=class role="status">{words} {explain}</p> }
                })
            }}
        </div>
        <div class="button-row lesson-detail">
            <button type="button" on:click=set_up>"Set up this step"</button>
            <button type="button" disabled={index == 0}
                on:click=move |_| open_step(&previous, index.saturating_sub(1))>"Previous step"</button>
            <button type="button" disabled={index + 1 >= count}
                on:click=move |_| open_step(&next, index + 1)>"Next step"</button>
        </div>
    }
    .into_any()
}

/// The navigation label of a lab page.
fn page_name(page: LabPage) -> &'static str {
    crate::web::route::Page::from_hash(page.slug()).map_or("lab", |p| p.label())
}
