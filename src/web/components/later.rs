//! A page mounted in pieces. Everything a page builds as it mounts runs in one task, with the
//! effects that follow it and V8's compilation of each function the first time it is called: for
//! a page with a form, five charts and tables, more than the 50 ms a task should take. What a
//! person needs first (the header, the navigation, the form) mounts at once; what waits for a
//! result anyway (charts, tables) mounts in the next task, before the first chunk of the run.

use leptos::prelude::*;

use crate::web::components::runner::next_task;

/// `false` until the task after the one that calls it, then `true`. An effect that returns early
/// while it reads `false` does its work in that task instead of the one that mounts the page.
pub fn from_next_task() -> ReadSignal<bool> {
    let (ready, set_ready) = signal(false);
    next_task(move || {
        let _ = set_ready.try_set(true);
    });
    ready
}

/// Shows `children` from the task after the one that mounts it: the browser paints what was
/// mounted before and handles input in between. Nothing shows if the page is left meanwhile.
#[component]
pub fn Later(children: ChildrenFn) -> impl IntoView {
    let ready = from_next_task();
    move || ready.get().then(|| children())
}
