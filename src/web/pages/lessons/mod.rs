//! Lessons: the list of guided experiments with the student's progress (`#/lessons`), and a
//! lesson opened by its link (`#/lessons/ID`), which puts the lesson panel ([`panel`]) beside the
//! real lab page of its step. The lessons are the core's ([`crate::lessons`]), shipped in
//! `www/lessons/`.
//!
//! | file | what |
//! |---|---|
//! | [`panel`] | the lesson beside the lab: the task, hints, the check and its outcome |
//! | [`feed`] | the runs the lab's pages finish, for the panel to check |
//! | [`store`] | the progress, kept in `localStorage` |

pub mod feed;
pub mod panel;
pub mod store;

use leptos::prelude::*;

use crate::lessons::shipped::shipped;
use crate::lessons::Lesson;
use crate::web::components::download::download_text;
use crate::web::components::page::PageShell;
use crate::web::components::runner::next_task;
use crate::web::route::sub_path;

/// Opens step `step` of `lesson` beside the lab: remembers it, then goes to the page it sets up
/// — unless the page shown already holds that setup ([`Setup::held_by`](crate::lessons::setup::Setup::held_by)), so that a step never
/// throws away what the student did there (the log opened on the Logs page).
pub fn open_step(lesson: &Lesson, step: usize) {
    let step = step.min(lesson.steps.len().saturating_sub(1));
    store::update(|p| p.open_step(&lesson.id, step));
    if let Some(s) = lesson.steps.get(step) {
        let location = window().location();
        let current = location.hash().unwrap_or_default();
        if !s.setup.held_by(&current) {
            let _ = location.set_hash(&s.setup.link());
        }
    }
}

/// The Lessons page.
#[component]
pub fn LessonsPage() -> impl IntoView {
    let lessons: Vec<Lesson> = shipped().into_iter().flatten().collect();
    let hash = window().location().hash().unwrap_or_default();
    let asked = sub_path(&hash).map(str::to_string);
    // A lesson's link opens it beside the lab, at the step the student reached.
    let unknown = asked
        .clone()
        .filter(|id| match lessons.iter().find(|l| &l.id == id) {
            Some(lesson) => {
                let lesson = lesson.clone();
                let step = store::progress().with_untracked(|p| p.of(&lesson.id).step);
                next_task(move || open_step(&lesson, step));
                false
            }
            None => true,
        });
    let progress = store::progress();
    let (export_error, set_export_error) = signal(None::<String>);
    let report_lessons = lessons.clone();
    let export = move |_| {
        let text = store::progress().with_untracked(|p| p.to_report_json(&report_lessons));
        set_export_error
            .set(download_text("cutlab-lessons-progress.json", "application/json", &text).err());
    };
    let rows = lessons
        .into_iter()
        .map(|lesson| {
            let progress = progress.clone();
            let steps = lesson.steps.len();
            let id = lesson.id.clone();
            let done = Signal::derive(move || progress.with(|p| p.done_count(&id, steps)));
            let href = format!("#/lessons/{}", lesson.id);
            view! {
                <li class="lesson-card">
                    <h2><a href=href>{lesson.title.clone()}</a></h2>
                    <p class="lesson-meta">"Paper " {lesson.paper.clone()} " · " {steps} " steps"</p>
                    <p>{lesson.teaches.clone()}</p>
                    <p class="lesson-progress">
                        <progress max=steps.to_string() value=move || done.get().to_string() aria-label=format!("Progress in {}", lesson.title)></progress>
                        " " {move || done.get()} " of " {steps} " steps done"
                    </p>
                </li>
            }
        })
        .collect_view();
    view! {
        <PageShell id="lessons" title="Lessons: guided experiments">
            <p class="lede">
                "Each lesson walks one idea of the papers on the real lab: a step opens a page set "
                "up for it, asks a question or sets a task, and checks your run as it finishes, "
                "condition by condition, with the measured value. Your progress stays in this "
                "browser; download it to hand it in or keep it."
            </p>
            {unknown.map(|id| view! {
                <p class="error" role="alert">"There is no lesson named \u{201c}" {id} "\u{201d}: choose one below."</p>
            })}
            <ul class="lesson-list">{rows}</ul>
            <div class="button-row">
                <button type="button" on:click=export>"Download progress (JSON)"</button>
            </div>
            {move || export_error.get().map(|e| view! { <p class="error" role="alert">{e}</p> })}
        </PageShell>
    }
}
