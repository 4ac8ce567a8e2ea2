//! A page mounted in pieces, and its own work done after its mount: the one place this is
//! explained.
//!
//! Everything a page builds as it mounts runs in one task, with the effects that follow it and
//! V8's compilation of each function the first time it is called: for a page with a form, five
//! charts and tables, more than the 50 ms a task should take (docs/benchmarks.md holds the first
//! task to 50 ms). So what a person needs first (the header, the navigation, the form) mounts at
//! once, and what waits for a result anyway (charts, tables, the later parts of a long form)
//! mounts in a following task ([`Later`]); and the page's own work — parsing its form, writing
//! its URL, starting its first run — starts in the task after its mount ([`effect_after_mount`]).
//! Each `<Later>` on a page and each such effect needs no comment of its own.

use leptos::prelude::*;

use crate::web::components::runner::next_task;

/// `false` until the task after the one that calls it, then `true`. An effect that returns early
/// while it reads `false` does its work in that task instead of the one that mounts the page.
fn from_next_task() -> ReadSignal<bool> {
    let (ready, set_ready) = signal(false);
    next_task(move || {
        let _ = set_ready.try_set(true);
    });
    ready
}

/// An effect that first runs `work` in the task after the one that mounts the page, then again
/// whenever what `work` reads changes: the page's own work, kept out of its mount's task.
pub fn effect_after_mount(work: impl Fn() + 'static) {
    let mounted = from_next_task();
    Effect::new(move |_| {
        if mounted.get() {
            work();
        }
    });
}

/// Shows `children` from the task after the one that mounts it: the browser paints what was
/// mounted before and handles input in between. Nothing shows if the page is left meanwhile.
#[component]
pub fn Later(children: ChildrenFn) -> impl IntoView {
    let ready = from_next_task();
    move || ready.get().then(|| children())
}
